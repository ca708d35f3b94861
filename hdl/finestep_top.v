`timescale 1ns / 1ps
`default_nettype none
// finestep top: the motion core behind its host interface. Two host links (SPI with
// CRC-checked frames, and the 8080/FSMC parallel bus) share one register bus into the
// register file; period records reach the core through the position FIFO, gated by the
// motion control (start threshold, underrun); the safety monitor (watchdog, E-stop)
// halts the core, drops the enables and stops the run.
//
// Every output is a flip-flop. rst must be held for at least 2 cycles.
module finestep_top #(
    parameter N_AXES          = 4,
    parameter P_WIDTH         = 20,
    parameter TIMING_W        = 12,
    parameter FIFO_DEPTH_LOG2 = 8,
    parameter WD_W            = 24,
    parameter CLOCK_HZ        = 50000000,
    parameter HAS_SPI         = 1,
    parameter HAS_PARALLEL    = 1
) (
    // clock, reset
    input  wire              clk,
    input  wire              rst,
    // SPI (asynchronous)
    input  wire              spi_cs_n,
    input  wire              spi_sck,
    input  wire              spi_mosi,
    output wire              spi_miso,
    output wire              spi_miso_oe,
    // 8080/FSMC parallel bus (asynchronous)
    input  wire              bus_cs_n,
    input  wire              bus_adv_n,
    input  wire              bus_rd_n,
    input  wire              bus_wr_n,
    input  wire [15:0]       bus_ad_in,
    output wire [15:0]       bus_ad_out,
    output wire              bus_ad_oe,
    // machine
    input  wire              estop_pin,
    output wire              irq,
    output wire [N_AXES-1:0] pin_a,
    output wire [N_AXES-1:0] pin_b,
    output wire [N_AXES-1:0] pin_en
);

    localparam REC_W   = 32 * N_AXES + 8;
    localparam LEVEL_W = FIFO_DEPTH_LOG2 + 1;
    localparam [LEVEL_W-1:0] FIFO_DEPTH = 1 << FIFO_DEPTH_LOG2;

    // Register bus
    wire        spi_req, spi_we, spi_grant;
    wire [6:0]  spi_addr;
    wire [31:0] spi_wdata;
    wire        par_req, par_we, par_grant;
    wire [6:0]  par_addr;
    wire [31:0] par_wdata;
    wire [31:0] rdata;
    // Configuration and commands
    wire                       run_request, watchdog_enable, estop_active_high;
    wire [P_WIDTH-1:0]         period_clocks;
    wire [WD_W-1:0]            watchdog_timeout;
    wire [7:0]                 estop_filter;
    wire [15:0]                start_level;
    wire [N_AXES-1:0]          axis_enable;
    wire [TIMING_W*N_AXES-1:0] step_len, step_space, dir_setup, dir_hold;
    wire [2*N_AXES-1:0]        out_mode;
    wire [3*N_AXES-1:0]        invert;
    wire                       clear_errors, clear_faults, flush_cmd, kick;
    // Safety
    wire estop_active, fault_estop, fault_watchdog, halt;
    reg  halt_prev_reg;
    // FIFO
    wire               spi_wr_en, spi_wr_commit, spi_wr_abort, spi_fifo_busy;
    wire [REC_W-1:0]   spi_wr_data;
    wire               push_write;
    wire [REC_W-1:0]   push_data;
    wire               fifo_valid, fifo_pop, fifo_full, fifo_overflow_unused;
    wire [REC_W-1:0]   fifo_head;
    wire [LEVEL_W-1:0] fifo_level, fifo_staged;
    wire [LEVEL_W-1:0] fifo_free = FIFO_DEPTH - fifo_level - fifo_staged;
    // SPI frame layer events
    wire       latch_hold, spi_crc_error, spi_frame_error, spi_refused;
    wire [7:0] spi_refused_count;
    wire [7:0] status_byte;
    wire       par_error;
    // Motion
    wire core_run = run_request && !halt;
    wire rec_ready, rec_valid, gate, underrun, underrun_event;
    wire boundary = core_run && rec_ready;
    wire [32*N_AXES-1:0] position;
    wire [N_AXES-1:0]    rate_error, step_lost;
    wire record_error, block_end;

    // The halt's rising edge empties the FIFO: its records belong to the motion that
    // was stopped.
    wire flush = flush_cmd || (halt && !halt_prev_reg);
    always @(posedge clk) halt_prev_reg <= rst ? 1'b1 : halt;

    generate
        if (HAS_SPI != 0) begin : spi
            wire       frame_start, frame_end, frame_whole, rx_valid;
            wire [7:0] rx_byte, tx_byte;
            spi_slave_phy phy (
                .clk(clk), .rst(rst),
                .spi_cs_n(spi_cs_n), .spi_sck(spi_sck), .spi_mosi(spi_mosi),
                .spi_miso(spi_miso), .spi_miso_oe(spi_miso_oe),
                .frame_start(frame_start), .frame_end(frame_end), .frame_whole(frame_whole),
                .rx_valid(rx_valid), .rx_byte(rx_byte), .tx_byte(tx_byte)
            );
            spi_frame #(
                .N_AXES(N_AXES),
                .LEVEL_W(LEVEL_W)
            ) frame (
                .clk(clk), .rst(rst),
                .frame_start(frame_start), .frame_end(frame_end), .frame_whole(frame_whole),
                .rx_valid(rx_valid), .rx_byte(rx_byte), .tx_byte(tx_byte),
                .status_byte(status_byte),
                .fifo_free(fifo_free),
                .fifo_flush(flush),
                .bus_req(spi_req), .bus_we(spi_we), .bus_addr(spi_addr), .bus_wdata(spi_wdata),
                .bus_grant(spi_grant), .bus_rdata(rdata),
                .fifo_wr_en(spi_wr_en), .fifo_wr_data(spi_wr_data),
                .fifo_wr_commit(spi_wr_commit), .fifo_wr_abort(spi_wr_abort),
                .fifo_busy(spi_fifo_busy),
                .latch_hold(latch_hold), .crc_error(spi_crc_error), .frame_error(spi_frame_error),
                .refused(spi_refused), .refused_count(spi_refused_count)
            );
        end else begin : no_spi
            wire unused_spi = &{1'b0, spi_cs_n, spi_sck, spi_mosi, spi_grant, status_byte};
            assign spi_miso = 1'b0;
            assign spi_miso_oe = 1'b0;
            assign spi_req = 1'b0;
            assign spi_we = 1'b0;
            assign spi_addr = 7'd0;
            assign spi_wdata = 32'd0;
            assign spi_wr_en = 1'b0;
            assign spi_wr_data = {REC_W{1'b0}};
            assign spi_wr_commit = 1'b0;
            assign spi_wr_abort = 1'b0;
            assign spi_fifo_busy = 1'b0;
            assign latch_hold = 1'b0;
            assign spi_crc_error = 1'b0;
            assign spi_frame_error = 1'b0;
            assign spi_refused = 1'b0;
            assign spi_refused_count = 8'd0;
        end

        if (HAS_PARALLEL != 0) begin : parallel
            parallel_bus_slave slave (
                .clk(clk), .rst(rst),
                .bus_cs_n(bus_cs_n), .bus_adv_n(bus_adv_n), .bus_rd_n(bus_rd_n), .bus_wr_n(bus_wr_n),
                .bus_ad_in(bus_ad_in), .bus_ad_out(bus_ad_out), .bus_ad_oe(bus_ad_oe),
                .bus_req(par_req), .bus_we(par_we), .bus_addr(par_addr), .bus_wdata(par_wdata),
                .bus_grant(par_grant), .bus_rdata(rdata),
                .error(par_error)
            );
        end else begin : no_parallel
            wire unused_parallel = &{1'b0, bus_cs_n, bus_adv_n, bus_rd_n, bus_wr_n, bus_ad_in, par_grant};
            assign bus_ad_out = 16'd0;
            assign bus_ad_oe = 1'b0;
            assign par_req = 1'b0;
            assign par_we = 1'b0;
            assign par_addr = 7'd0;
            assign par_wdata = 32'd0;
            assign par_error = 1'b0;
        end
    endgenerate

    register_file #(
        .N_AXES(N_AXES), .P_WIDTH(P_WIDTH), .TIMING_W(TIMING_W), .FIFO_DEPTH_LOG2(FIFO_DEPTH_LOG2),
        .WD_W(WD_W), .CLOCK_HZ(CLOCK_HZ), .HAS_SPI(HAS_SPI), .HAS_PARALLEL(HAS_PARALLEL)
    ) registers (
        .clk(clk), .rst(rst),
        .spi_req(spi_req), .spi_we(spi_we), .spi_addr(spi_addr), .spi_wdata(spi_wdata), .spi_grant(spi_grant),
        .par_req(par_req), .par_we(par_we), .par_addr(par_addr), .par_wdata(par_wdata), .par_grant(par_grant),
        .rdata(rdata),
        .run(run_request), .watchdog_enable(watchdog_enable), .estop_active_high(estop_active_high),
        .period_clocks(period_clocks), .watchdog_timeout(watchdog_timeout), .estop_filter(estop_filter),
        .start_level(start_level), .axis_enable(axis_enable),
        .step_len(step_len), .step_space(step_space), .dir_setup(dir_setup), .dir_hold(dir_hold),
        .out_mode(out_mode), .invert(invert),
        .clear_errors(clear_errors), .clear_faults(clear_faults), .flush_cmd(flush_cmd), .kick(kick),
        .core_run(core_run), .gate(gate), .halt(halt), .fault_estop(fault_estop),
        .fault_watchdog(fault_watchdog), .estop_active(estop_active),
        .underrun(underrun), .underrun_event(underrun_event), .record_error(record_error),
        .rate_error(rate_error), .step_lost(step_lost), .boundary(boundary), .block_end(block_end),
        .position(position), .fifo_level(fifo_level), .fifo_staged(fifo_staged), .fifo_full(fifo_full),
        .latch_hold(latch_hold), .spi_crc_error(spi_crc_error), .spi_frame_error(spi_frame_error),
        .spi_refused(spi_refused), .spi_refused_count(spi_refused_count),
        .spi_fifo_in_use(spi_fifo_busy || spi_wr_en || spi_wr_commit || spi_wr_abort),
        .spi_fifo_commit(spi_wr_commit), .par_error(par_error),
        .push_write(push_write), .push_data(push_data),
        .status_byte(status_byte), .irq(irq)
    );

    safety_monitor #(
        .WD_W(WD_W),
        .FILTER_W(8)
    ) safety (
        .clk(clk), .rst(rst),
        .watchdog_enable(watchdog_enable), .watchdog_timeout(watchdog_timeout),
        .estop_active_high(estop_active_high), .estop_filter(estop_filter),
        .kick(kick), .clear_faults(clear_faults), .estop_pin(estop_pin),
        .estop_active(estop_active), .fault_estop(fault_estop), .fault_watchdog(fault_watchdog),
        .halt(halt)
    );

    // The SPI frame layer owns the write port while it uses it; RECORD_PUSH is refused
    // then (register_file), so the two never meet.
    position_fifo #(
        .WIDTH(REC_W),
        .DEPTH_LOG2(FIFO_DEPTH_LOG2)
    ) fifo (
        .clk(clk), .rst(rst), .flush(flush), .clear_errors(clear_errors),
        .wr_en(spi_wr_en || push_write),
        .wr_data(spi_wr_en ? spi_wr_data : push_data),
        .wr_commit(spi_wr_commit || push_write),
        .wr_abort(spi_wr_abort),
        .rd_valid(fifo_valid), .rd_pop(fifo_pop), .rd_data(fifo_head),
        .level(fifo_level), .staged(fifo_staged), .full(fifo_full), .overflow(fifo_overflow_unused)
    );

    motion_control #(
        .LEVEL_W(LEVEL_W)
    ) motion (
        .clk(clk), .rst(rst),
        .core_run(core_run), .start_level(start_level), .clear_errors(clear_errors),
        .fifo_level(fifo_level), .fifo_valid(fifo_valid), .head_block_end(fifo_head[32*N_AXES]),
        .fifo_pop(fifo_pop),
        .rec_ready(rec_ready), .rec_valid(rec_valid),
        .gate(gate), .underrun(underrun), .underrun_event(underrun_event)
    );

    finestep_core #(
        .N_AXES(N_AXES),
        .P_WIDTH(P_WIDTH),
        .TIMING_W(TIMING_W)
    ) core (
        .clk(clk), .rst(rst),
        .run(core_run), .period_clocks(period_clocks), .clear_errors(clear_errors), .halt(halt),
        .axis_enable(axis_enable),
        .step_len(step_len), .step_space(step_space), .dir_setup(dir_setup), .dir_hold(dir_hold),
        .out_mode(out_mode), .invert(invert),
        .rec_valid(rec_valid), .rec_ready(rec_ready),
        .rec_inc(fifo_head[32*N_AXES-1:0]), .rec_flags(fifo_head[32*N_AXES +: 8]),
        .pin_a(pin_a), .pin_b(pin_b), .pin_en(pin_en),
        .position(position), .rate_error(rate_error), .step_lost(step_lost),
        .record_error(record_error), .block_end(block_end)
    );

    wire unused_top = &{1'b0, fifo_overflow_unused};

endmodule

`default_nettype wire

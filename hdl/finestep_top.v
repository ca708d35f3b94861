`timescale 1ns / 1ps
`default_nettype none
// Specification: docs/spec/finestep_top.md
// finestep top: the motion core behind its host interface. Two host links (SPI with
// CRC-checked frames, and the 8080/FSMC parallel bus) share one register bus into the
// register file; period records reach the core through the position FIFO, gated by the
// motion control (start threshold, underrun); the safety monitor (watchdog, E-stop)
// halts the core, drops the enables and stops the run. The feedback blocks count encoders
// and gratings, latch them on the probe, and decode the hand wheel, whose jog generator
// drives the core in place of the FIFO while RUN is 0. The spindle (PWM or SPI DAC) and
// the logic outputs (coolant, light, general outputs, the interlock input) hang on the
// same register bus [HAS_SPINDLE, HAS_OUTPUTS]; a halt (a safety fault or the gantry's
// alarm) turns them off or safe. The
// gantry card's panel (a 4x4 keypad and a 7-segment LED menu choosing the gantry's mode)
// [HAS_PANEL] and the gantry pair's registers and channel decoders [HAS_GANTRY, with a
// DDA and a shaper per axis] hang there too.
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
    parameter HAS_PARALLEL    = 1,
    parameter N_ENC           = 4,
    parameter HAS_MPG         = 1,
    parameter RAM_BLOCK       = 0,
    parameter STEP_SHARED     = 1,
    parameter STEP_DIGIT      = 0,   // with STEP_SHARED: 0 step_engine; 1, 2, 4, 8 step_serial
    parameter READ_STORE      = 1,
    parameter FIFO_HEAD_REG   = 1,
    parameter NO_RAM          = 0,   // 1: no RAM on the part (stores in flip-flops)
    parameter ONE_SNAPSHOT    = 0,   // 1: the probe's snapshot is the position latch (POSITION, LATCH_TIME)
    parameter INC_WRITE_ONLY  = 0,   // 1: RECORD_INC reads 0 (needs READ_STORE 0)
    parameter AXIS_WRITE_ONLY = 0,   // 1: AXIS_TIMING_A/B, AXIS_MODE read 0 (needs READ_STORE 0)
    parameter INC_DIRECT      = 0,   // 1: RECORD_INC writes go straight into the FIFO's record (needs INC_WRITE_ONLY 1)
    parameter ENC_COUNT_W     = 32,  // 16: the encoders' counts and edge times 16 bits, read extended (VERSION.ENC_COUNT_16)
    parameter HAS_SPINDLE     = 1,
    parameter HAS_OUTPUTS     = 1,
    parameter N_GPIO          = 4,
    parameter HAS_PANEL       = 0,
    parameter HAS_GANTRY      = 0,
    parameter HAS_PBP         = 1,   // 1: the core's point-by-point interpolator (VERSION.HAS_PBP); every board top sets 0
    parameter FEEDBACK_REG    = 1    // 1: the feedback read words in a register of their own; 0: in register_file's read register
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
    // feedback (asynchronous)
    input  wire [N_ENC-1:0]  enc_a,
    input  wire [N_ENC-1:0]  enc_b,
    input  wire [N_ENC-1:0]  enc_z,
    input  wire              probe_pin,
    input  wire              mpg_a,
    input  wire              mpg_b,
    output wire              irq,
    output wire [N_AXES-1:0] pin_a,
    output wire [N_AXES-1:0] pin_b,
    output wire [N_AXES-1:0] pin_en,
    // spindle: PWM, or a 12-bit SPI DAC (MCP4921 frame)
    output wire              spindle_pwm,
    output wire              spindle_dir,
    output wire              spindle_en,
    output wire              dac_cs_n,
    output wire              dac_sck,
    output wire              dac_sdi,
    // logic outputs and the interlock (asynchronous)
    input  wire              interlock_pin,
    output wire              coolant_mist,
    output wire              coolant_flood,
    output wire              light,
    output wire [((N_GPIO > 0) ? N_GPIO : 1)-1:0] gpio,
    // the panel: keypad matrix (rows pulled up, asynchronous; a column driven low where
    // panel_col is 1: the board makes it open drain) and 8 multiplexed 7-segment digits
    input  wire [3:0]        panel_row_n,
    output wire [3:0]        panel_col,
    output wire [7:0]        panel_seg,
    output wire [7:0]        panel_dig
);

`include "finestep_regs.vh"
`include "finestep_interface.vh"
`include "finestep_top_checks.vh"

    // log2 of the round R, the clocks between two visits of an axis, reported in
    // CAPS.STEP_ROUND_LOG2 (0: a DDA and a shaper per axis): the step engine's slots S,
    // times 32 / STEP_DIGIT with the digit-serial engine (derived in hdl/interface.toml,
    // as finestep_core derives it).
    localparam STEP_ROUND_LOG2 = FS_CHECK_STEP_ROUND_LOG2;
    // Write-only timings with the digit-serial engine: the register file holds each as
    // the engine reads it, its bits from log2 R up and whether X mod R != 0.
    localparam TIMING_ROUND_L = (AXIS_WRITE_ONLY != 0 && STEP_SHARED != 0 && STEP_DIGIT != 0) ? STEP_ROUND_LOG2 : 0;

    // A FIFO record: the increments, then the flags (FS_REC_*).
    localparam INC_W   = FS_REC_INC_WIDTH * N_AXES;
    localparam REC_W   = INC_W + FS_REC_FLAGS_WIDTH;
    localparam LEVEL_W = FIFO_DEPTH_LOG2 + 1;

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
    wire [FS_OUT_MODE_WIDTH*N_AXES-1:0] out_mode;
    wire [FS_INVERT_WIDTH*N_AXES-1:0]   invert;
    wire                       clear_errors, clear_faults, flush_cmd, kick;
    // Safety
    wire estop_active, fault_estop, fault_watchdog, safety_halt, halt;
    reg  halt_prev_reg;
    // FIFO
    wire               spi_wr_en, spi_wr_commit, spi_wr_abort, spi_fifo_busy;
    wire [REC_W-1:0]   spi_wr_data;
    wire [N_AXES:0]    spi_wr_lane;      // the FIFO lanes (axes, then flags) the SPI frame layer writes
    wire [N_AXES:0]    push_lane;        // the FIFO lanes a RECORD_PUSH writes (one a cycle)
    wire [31:0]        push_word;
    wire [7:0]         push_flags;
    wire               push_wr_en, push_commit, push_in_flight;
    wire               fifo_valid, fifo_pop, fifo_full, fifo_overflow_unused;
    wire [REC_W-1:0]   fifo_head;
    wire [LEVEL_W-1:0] fifo_level, fifo_staged;
    wire [LEVEL_W-1:0] fifo_free;
    // SPI frame layer events
    wire       latch_hold, spi_crc_error, spi_frame_error, spi_refused;
    wire [7:0] spi_refused_count;
    wire [7:0] status_byte;
    wire       par_error;
    // Feedback register bus and state
    wire        bus_write;
    wire [6:0]  bus_address;
    wire [31:0] bus_write_data, feedback_rdata, timestamp;
    wire        latch_now;
    wire        jog_engaged, jog_stopping, jog_refused;
    wire [15:0] jog_dropped;
    wire [31:0] jog_remaining, jog_velocity;
    wire [N_AXES-1:0]    jog_lane;     // the jog's record: jog_word on its axis's lane
    wire [31:0]          jog_word;
    // Motion: the FIFO runs on RUN, the core also while the jog is engaged.
    wire fifo_run = run_request && !halt;
    wire core_run = (run_request || jog_engaged) && !halt;
    wire rec_ready, period_boundary, fifo_rec_valid, gate, underrun, underrun_event;
    // A period boundary of the core's timer: PERIOD_COUNT, the period IRQ and the position
    // latch count the idle periods a pbp record runs too (rec_ready is low through it).
    wire boundary = core_run && period_boundary;
    wire rec_valid = jog_engaged ? 1'b1 : fifo_rec_valid;
    // The jog's record goes to the core's alternate record port: the core checks it apart
    // and chooses after the checks (period_timer), so jog_engaged is not in front of them.
    wire [INC_W-1:0]              rec_inc   = fifo_head[INC_W-1:0];
    wire [FS_REC_FLAGS_WIDTH-1:0] rec_flags = jog_engaged ? {FS_REC_FLAGS_WIDTH{1'b0}} : fifo_head[INC_W +: FS_REC_FLAGS_WIDTH];
    wire [32*N_AXES-1:0] position;
    wire [N_AXES-1:0]    rate_error, step_lost;
    wire record_error, block_end;

    // Feedback configuration and state
    wire [15:0]           enc_prescale, mpg_prescale;
    wire [2*N_ENC-1:0]    enc_mode;
    wire [N_ENC-1:0]      enc_z_active_high, enc_arm_index_latch, enc_arm_index_clear;
    wire [4*N_ENC-1:0]    enc_filter;
    wire [2*N_ENC-1:0]    enc_mode_next;
    wire [N_ENC-1:0]      enc_z_active_high_next;
    wire [4*N_ENC-1:0]    enc_filter_next;
    wire                  probe_active_high, probe_arm;
    wire [3:0]            probe_filter, mpg_filter;
    wire                  jog_enable, jog_follow;
    wire [2:0]            jog_axis;
    wire [1:0]            jog_multiplier;
    wire [31:0]           jog_scale;
    wire [30:0]           jog_vmax, jog_accel;
    wire [15:0]           jog_window;
    wire                  bus_read;
    wire [31:0]           enc_copy_rdata;
    wire [16*N_ENC-1:0]   enc_illegal_count;
    wire [N_ENC-1:0]      enc_illegal, enc_index_seen, enc_latch_armed, enc_clear_armed;
    wire [N_ENC-1:0]      enc_a_level, enc_b_level, enc_z_level;
    wire                  probe_armed, probe_seen, probe_active, probe_event;
    wire [31:0]           probe_time;
    wire [32*N_AXES-1:0]  probe_position;
    wire [31:0]           mpg_count, mpg_detents;
    wire                  mpg_illegal, mpg_a_level, mpg_b_level;
    wire [15:0]           mpg_illegal_count;
    wire                  feedback_error = (|enc_illegal) || mpg_illegal;
    wire                  run_write_one, clear_counters;

    wire                  fifo_pop_request;
    // Spindle and logic outputs
    localparam GPIO_W = (N_GPIO > 0) ? N_GPIO : 1;
    wire [31:0]           spindle_rdata, outputs_rdata, panel_rdata, gantry_rdata;
    // VERSION.HAS_PBP: the core's point-by-point interpolator (records with the flag PBP).
    wire [31:0]           pbp_rdata = (HAS_PBP != 0 && bus_address == FS_VERSION_ADDR) ?
                                      (32'd1 << FS_VERSION_HAS_PBP_LSB) : 32'd0;
    wire                  interlock_inhibit, start_blocked;
    // The feedback blocks' read words (feedback_registers, the spindle, the logic outputs,
    // the panel, the gantry pair, VERSION.HAS_PBP), each from the bus stage's address and
    // the state of a served read's cycle, taken at the edge ending it and held to the
    // next served read: register_file ORs it after its read register (late_rdata, beside
    // the encoder bank's copies), so a read returns the same word in the same cycle as
    // when that register took them, and their multiplexers end here, not in front of it
    // (the ECP5 board build's critical path at 100 MHz, seed 2: the feedback multiplexer
    // into register_file's read register). With FEEDBACK_REG 0 (the CPLDs, 32 flip-flops
    // fewer) the word goes into register_file's read register instead (early_rdata), taken
    // at the same edge: the same word in the same cycle.
    wire [31:0]           feedback_word = feedback_rdata | spindle_rdata | outputs_rdata | panel_rdata |
                                          gantry_rdata | pbp_rdata;
    reg  [31:0]           feedback_word_reg;

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
                .fifo_free(push_in_flight ? {LEVEL_W{1'b0}} : fifo_free),   // no room while a RECORD_PUSH writes
                .fifo_flush(flush),
                .bus_req(spi_req), .bus_we(spi_we), .bus_addr(spi_addr), .bus_wdata(spi_wdata),
                .bus_grant(spi_grant), .bus_rdata(rdata),
                .fifo_wr_lane(spi_wr_lane), .fifo_wr_data(spi_wr_data), .fifo_wr_en(spi_wr_en),
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
            assign spi_wr_lane = {(N_AXES+1){1'b0}};
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
            // Without SPI the slave is the register bus's only master: the read word stays
            // on rdata until its next read, and its request is served from its registers.
            parallel_bus_slave #(.SOLE_MASTER(HAS_SPI == 0 ? 1 : 0)) slave (
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
        .WD_W(WD_W), .CLOCK_HZ(CLOCK_HZ), .HAS_SPI(HAS_SPI), .HAS_PARALLEL(HAS_PARALLEL),
        .N_ENC(N_ENC), .HAS_MPG(HAS_MPG), .READ_STORE(READ_STORE), .RAM_BLOCK(RAM_BLOCK),
        .STEP_ROUND_LOG2(STEP_ROUND_LOG2), .ONE_SNAPSHOT(ONE_SNAPSHOT), .INC_WRITE_ONLY(INC_WRITE_ONLY),
        .AXIS_WRITE_ONLY(AXIS_WRITE_ONLY), .INC_DIRECT(INC_DIRECT), .ENC_COUNT_W(ENC_COUNT_W),
        .TIMING_ROUND_L(TIMING_ROUND_L)
    ) registers (
        .clk(clk), .rst(rst),
        .spi_req(spi_req), .spi_we(spi_we), .spi_addr(spi_addr), .spi_wdata(spi_wdata), .spi_grant(spi_grant),
        .par_req(par_req), .par_we(par_we), .par_addr(par_addr), .par_wdata(par_wdata), .par_grant(par_grant),
        .rdata(rdata),
        .bus_write(bus_write), .bus_address(bus_address), .bus_write_data(bus_write_data),
        .bus_read(bus_read), .late_rdata(enc_copy_rdata | feedback_word_reg),
        .early_rdata((FEEDBACK_REG != 0) ? 32'd0 : feedback_word),
        .run(run_request), .watchdog_enable(watchdog_enable), .estop_active_high(estop_active_high),
        .period_clocks(period_clocks), .watchdog_timeout(watchdog_timeout), .estop_filter(estop_filter),
        .start_level(start_level), .axis_enable(axis_enable),
        .step_len(step_len), .step_space(step_space), .dir_setup(dir_setup), .dir_hold(dir_hold),
        .out_mode(out_mode), .invert(invert),
        .clear_errors(clear_errors), .clear_faults(clear_faults), .clear_counters(clear_counters),
        .run_write_one(run_write_one), .flush_cmd(flush_cmd), .kick(kick),
        .core_run(core_run), .gate(gate), .halt(halt), .fault_estop(fault_estop),
        .fault_watchdog(fault_watchdog), .estop_active(estop_active),
        .underrun(underrun), .underrun_event(underrun_event), .record_error(record_error),
        .rate_error(rate_error), .step_lost(step_lost), .boundary(boundary), .block_end(block_end),
        .position(position), .fifo_level(fifo_level), .fifo_staged(fifo_staged), .fifo_full(fifo_full),
        .latch_hold(latch_hold), .probe_event(probe_event), .probe_seen(probe_seen),
        .spi_crc_error(spi_crc_error), .spi_frame_error(spi_frame_error),
        .spi_refused(spi_refused), .spi_refused_count(spi_refused_count),
        .spi_fifo_in_use(spi_fifo_busy || (|spi_wr_lane) || spi_wr_commit || spi_wr_abort),
        .spi_fifo_commit(spi_wr_commit), .par_error(par_error),
        .feedback_error(feedback_error), .jog_engaged(jog_engaged), .jog_refused(jog_refused),
        .timestamp(timestamp), .latch_now(latch_now),
        .fifo_flush(flush), .push_lane(push_lane), .push_word(push_word), .push_flags(push_flags),
        .push_wr_en(push_wr_en), .push_commit(push_commit), .push_in_flight(push_in_flight),
        .status_byte(status_byte), .irq(irq)
    );

    safety_monitor #(
        .WD_W(WD_W),
        .FILTER_W(FS_ESTOP_FILTER_SAMPLES_WIDTH)
    ) safety (
        .clk(clk), .rst(rst),
        .watchdog_enable(watchdog_enable), .watchdog_timeout(watchdog_timeout),
        .estop_active_high(estop_active_high), .estop_filter(estop_filter),
        .kick(kick), .clear_faults(clear_faults), .estop_pin(estop_pin),
        .estop_active(estop_active), .fault_estop(fault_estop), .fault_watchdog(fault_watchdog),
        .halt(safety_halt)
    );

    // The SPI frame layer owns the write port while it uses it, and RECORD_PUSH is
    // refused then (register_file); while a push writes its record the frame layer sees
    // no room (a FIFO frame's header is refused). So the two never meet.
    position_fifo #(
        .WIDTH(REC_W),
        .DEPTH_LOG2(FIFO_DEPTH_LOG2),
        .LANE_W(FS_REC_INC_WIDTH),
        .HEAD_REG(FIFO_HEAD_REG)
    ) fifo (
        .clk(clk), .rst(rst), .flush(flush), .clear_errors(clear_errors),
        .wr_lane(push_lane | spi_wr_lane),
        // (INC_DIRECT: a RECORD_INC lane write is a push lane outside push_in_flight)
        .wr_data((push_in_flight || (INC_DIRECT != 0 && |push_lane)) ? {push_flags[FS_REC_FLAGS_WIDTH-1:0], {N_AXES{push_word}}} : spi_wr_data),
        .wr_en(spi_wr_en || push_wr_en),
        .wr_commit(spi_wr_commit || push_commit),
        .wr_abort(spi_wr_abort),
        .rd_valid(fifo_valid), .rd_pop(fifo_pop), .rd_data(fifo_head),
        .level(fifo_level), .staged(fifo_staged), .free(fifo_free), .full(fifo_full),
        .overflow(fifo_overflow_unused)
    );

    motion_control #(
        .LEVEL_W(LEVEL_W)
    ) motion (
        .clk(clk), .rst(rst),
        .core_run(fifo_run), .start_level(start_level), .clear_errors(clear_errors),
        .inhibit(interlock_inhibit),
        .fifo_level(fifo_level), .fifo_valid(fifo_valid), .head_block_end(fifo_head[INC_W + FS_REC_FLAG_BLOCK_END_BIT]),
        .fifo_pop(fifo_pop_request),
        .rec_ready(rec_ready), .rec_valid(fifo_rec_valid),
        .gate(gate), .underrun(underrun), .underrun_event(underrun_event),
        .start_blocked(start_blocked)
    );

    // The gantry pair: built with HAS_GANTRY where the core has a DDA and a shaper per
    // axis (gantry_sync is not in the step engine).
    localparam GANTRY_BUILT = (HAS_GANTRY != 0) && (STEP_SHARED == 0);
    wire        gantry_enable, gantry_sync_mode, panel_sync;
    wire [2:0]  gantry_master, gantry_slave;
    wire [23:0] gantry_tick;
    wire [15:0] gantry_deadband, gantry_limit, gantry_error16;
    wire [31:0] gantry_enc_master, gantry_enc_slave;
    wire        gantry_engaged, gantry_alarm, gantry_refused;
    // The machine halts on a safety fault and on the gantry's alarm (sticky in
    // gantry_sync, 0 without the gantry): the same stop as an E-stop (no pulse after the
    // alarm's clock, enables dropped, RUN cleared, the FIFO emptied, spindle and outputs
    // safe). Both are flip-flops: one gate between them and the axes.
    assign halt = safety_halt || gantry_alarm;
    wire [31:0] gantry_error;
    wire [15:0] gantry_corrections;

    finestep_core #(
        .N_AXES(N_AXES),
        .P_WIDTH(P_WIDTH),
        .TIMING_W(TIMING_W),
        .HAS_GANTRY(GANTRY_BUILT ? 1 : 0),
        .STEP_SHARED(STEP_SHARED),
        .RAM_BLOCK(RAM_BLOCK),
        .STEP_DIGIT(STEP_DIGIT),
        // The jog's record only with the hand wheel; said to the core only in the
        // digit-serial (CPLD) builds, whose estimate is hierarchical: a flattened build
        // sees the tie-off anyway, and on the HX8K (no wheel) ABC mapped it 3 cells larger.
        .HAS_ALT((HAS_MPG != 0 || STEP_DIGIT == 0) ? 1 : 0),
        .HAS_PBP(HAS_PBP)
    ) core (
        .clk(clk), .rst(rst),
        .run(core_run), .period_clocks(period_clocks), .clear_errors(clear_errors), .halt(halt),
        .axis_enable(axis_enable),
        .step_len(step_len), .step_space(step_space), .dir_setup(dir_setup), .dir_hold(dir_hold),
        .out_mode(out_mode), .invert(invert),
        .gantry_enable(gantry_enable), .gantry_sync_mode(gantry_sync_mode),
        .gantry_master(gantry_master), .gantry_slave(gantry_slave),
        .gantry_tick(gantry_tick), .gantry_deadband(gantry_deadband), .gantry_limit(gantry_limit),
        .enc_master(gantry_enc_master), .enc_slave(gantry_enc_slave), .clear_counters(clear_counters),
        .rec_valid(rec_valid), .rec_ready(rec_ready), .period_boundary(period_boundary),
        .rec_inc(rec_inc), .rec_flags(rec_flags),
        .rec_alt(jog_engaged), .rec_alt_lane(jog_lane), .rec_alt_inc(jog_word),
        .pin_a(pin_a), .pin_b(pin_b), .pin_en(pin_en),
        .position(position), .rate_error(rate_error), .step_lost(step_lost),
        .record_error(record_error), .block_end(block_end),
        .gantry_engaged(gantry_engaged), .gantry_alarm(gantry_alarm),
        .gantry_refused(gantry_refused), .gantry_error(gantry_error),
        .gantry_corrections(gantry_corrections)
    );

    // While the jog is engaged the FIFO is not popped (RUN is 0 then, so its gate is shut).
    assign fifo_pop = fifo_pop_request && !jog_engaged;

    feedback_registers #(
        .N_ENC(N_ENC), .N_AXES(N_AXES), .HAS_MPG(HAS_MPG), .ONE_SNAPSHOT(ONE_SNAPSHOT)
    ) feedback_regs (
        .clk(clk), .rst(rst),
        .write(bus_write), .addr(bus_address), .wdata(bus_write_data), .rdata(feedback_rdata),
        .halt(halt),
        .enc_prescale(enc_prescale), .enc_mode(enc_mode), .enc_z_active_high(enc_z_active_high),
        .enc_filter(enc_filter), .enc_mode_next(enc_mode_next),
        .enc_z_active_high_next(enc_z_active_high_next), .enc_filter_next(enc_filter_next),
        .enc_arm_index_latch(enc_arm_index_latch),
        .enc_arm_index_clear(enc_arm_index_clear),
        .probe_active_high(probe_active_high), .probe_filter(probe_filter), .probe_arm(probe_arm),
        .mpg_prescale(mpg_prescale), .mpg_filter(mpg_filter),
        .jog_enable(jog_enable), .jog_axis(jog_axis), .jog_multiplier(jog_multiplier),
        .jog_follow(jog_follow), .jog_scale(jog_scale), .jog_vmax(jog_vmax), .jog_accel(jog_accel),
        .jog_window(jog_window),
        .enc_illegal_count(enc_illegal_count),
        .enc_illegal(enc_illegal), .enc_index_seen(enc_index_seen), .enc_latch_armed(enc_latch_armed),
        .enc_clear_armed(enc_clear_armed), .enc_a(enc_a_level), .enc_b(enc_b_level), .enc_z(enc_z_level),
        .probe_armed(probe_armed), .probe_seen(probe_seen), .probe_active(probe_active),
        .probe_time(probe_time), .probe_position(probe_position),
        .mpg_count(mpg_count), .mpg_detents(mpg_detents), .mpg_illegal(mpg_illegal),
        .mpg_illegal_count(mpg_illegal_count), .mpg_a(mpg_a_level), .mpg_b(mpg_b_level),
        .jog_engaged(jog_engaged), .jog_stopping(jog_stopping), .jog_refused(jog_refused),
        .jog_dropped(jog_dropped), .jog_remaining(jog_remaining), .jog_velocity(jog_velocity)
    );

    encoder_bank #(
        .N_ENC(N_ENC), .N_AXES(N_AXES), .FILTER_W(FS_ENC_CONTROL_FILTER_WIDTH), .RAM_BLOCK(RAM_BLOCK),
        .COPY_FF(NO_RAM), .PROBE_COPY(ONE_SNAPSHOT == 0 ? 1 : 0), .COUNT_W(ENC_COUNT_W)
    ) encoders (
        .clk(clk), .rst(rst),
        .enc_a(enc_a), .enc_b(enc_b), .enc_z(enc_z), .probe_pin(probe_pin),
        .prescale(enc_prescale), .mode(enc_mode), .z_active_high(enc_z_active_high),
        .filter_len(enc_filter), .mode_next(enc_mode_next), .z_active_high_next(enc_z_active_high_next),
        .filter_len_next(enc_filter_next),
        .probe_active_high(probe_active_high), .probe_filter_len(probe_filter),
        .arm_index_latch(enc_arm_index_latch), .arm_index_clear(enc_arm_index_clear),
        .probe_arm(probe_arm), .clear_errors(clear_errors), .clear_counters(clear_counters),
        .read_served(bus_read), .read_addr(bus_address), .copy_rdata(enc_copy_rdata),
        .timestamp(timestamp), .position(position), .latch_now(latch_now),
        .illegal_count(enc_illegal_count), .illegal(enc_illegal), .index_seen(enc_index_seen),
        .index_latch_armed(enc_latch_armed), .index_clear_armed(enc_clear_armed),
        .a_level(enc_a_level), .b_level(enc_b_level), .z_level(enc_z_level),
        .probe_armed(probe_armed), .probe_seen(probe_seen), .probe_active(probe_active),
        .probe_event_now(probe_event), .probe_time(probe_time), .probe_position(probe_position)
    );

    generate
        if (HAS_MPG != 0) begin : mpg
            wire mpg_detent_up, mpg_detent_down;   // the detent count's step, hand wheel to jog
            hand_wheel #(.FILTER_W(FS_MPG_CONTROL_FILTER_WIDTH)) wheel (
                .clk(clk), .rst(rst), .mpg_a(mpg_a), .mpg_b(mpg_b),
                .prescale(mpg_prescale), .filter_len(mpg_filter),
                .clear_errors(clear_errors), .clear_counters(clear_counters),
                .count(mpg_count), .detents(mpg_detents),
                .detent_up(mpg_detent_up), .detent_down(mpg_detent_down), .illegal(mpg_illegal),
                .illegal_count(mpg_illegal_count), .a_level(mpg_a_level), .b_level(mpg_b_level)
            );
            jog_generator #(.N_AXES(N_AXES), .P_WIDTH(P_WIDTH)) jog (
                .clk(clk), .rst(rst),
                .enable(jog_enable), .axis_select(jog_axis), .multiplier(jog_multiplier),
                .follow(jog_follow), .scale(jog_scale), .vmax(jog_vmax), .accel(jog_accel),
                .window(jog_window), .period_clocks(period_clocks),
                .run(run_request), .run_write_one(run_write_one), .halt(halt), .rec_ready(rec_ready),
                .clear_errors(clear_errors), .clear_counters(clear_counters),
                .detent_up(mpg_detent_up), .detent_down(mpg_detent_down),
                .rec_lane(jog_lane), .rec_word(jog_word), .engaged(jog_engaged), .stopping(jog_stopping), .refused(jog_refused),
                .dropped(jog_dropped), .remaining(jog_remaining), .velocity(jog_velocity)
            );
        end else begin : no_mpg
            wire unused_mpg = &{1'b0, mpg_a, mpg_b, mpg_prescale, mpg_filter, jog_enable, jog_axis,
                                jog_multiplier, jog_follow, jog_scale, jog_vmax, jog_accel, jog_window,
                                run_write_one};
            assign mpg_count = 32'd0;
            assign mpg_detents = 32'd0;
            assign mpg_illegal = 1'b0;
            assign mpg_illegal_count = 16'd0;
            assign mpg_a_level = 1'b0;
            assign mpg_b_level = 1'b0;
            assign jog_lane = {N_AXES{1'b0}};
            assign jog_word = 32'd0;
            assign jog_engaged = 1'b0;
            assign jog_stopping = 1'b0;
            assign jog_refused = 1'b0;
            assign jog_dropped = 16'd0;
            assign jog_remaining = 32'd0;
            assign jog_velocity = 32'd0;
        end
    endgenerate

    generate
        if (HAS_SPINDLE != 0) begin : spindle_block
            spindle #(.LEVEL_W(FS_SPINDLE_LEVEL_LEVEL_WIDTH)) spindle_out (
                .clk(clk), .rst(rst),
                .write(bus_write), .addr(bus_address), .wdata(bus_write_data), .rdata(spindle_rdata),
                .halt(halt),
                .spindle_pwm(spindle_pwm), .spindle_dir(spindle_dir), .spindle_en(spindle_en),
                .dac_cs_n(dac_cs_n), .dac_sck(dac_sck), .dac_sdi(dac_sdi)
            );
        end else begin : no_spindle
            assign spindle_rdata = 32'd0;
            assign spindle_pwm   = 1'b0;
            assign spindle_dir   = 1'b0;
            assign spindle_en    = 1'b0;
            assign dac_cs_n      = 1'b1;
            assign dac_sck       = 1'b0;
            assign dac_sdi       = 1'b0;
        end

        if (HAS_OUTPUTS != 0) begin : outputs_block
            logic_outputs #(.N_GPIO(N_GPIO)) outputs (
                .clk(clk), .rst(rst),
                .write(bus_write), .addr(bus_address), .wdata(bus_write_data), .rdata(outputs_rdata),
                .halt(halt), .clear_errors(clear_errors), .start_blocked(start_blocked),
                .inhibit(interlock_inhibit),
                .interlock_pin(interlock_pin),
                .coolant_mist(coolant_mist), .coolant_flood(coolant_flood), .light(light), .gpio(gpio)
            );
        end else begin : no_outputs
            wire unused_outputs = &{1'b0, interlock_pin, start_blocked};
            assign outputs_rdata     = 32'd0;
            assign interlock_inhibit = 1'b0;
            assign coolant_mist      = 1'b0;
            assign coolant_flood     = 1'b0;
            assign light             = 1'b0;
            assign gpio              = {GPIO_W{1'b0}};
        end
    endgenerate

    generate
        if (GANTRY_BUILT) begin : gantry_block
            gantry_link #(.N_ENC(N_ENC), .HAS_PANEL(HAS_PANEL), .FILTER_W(FS_ENC_CONTROL_FILTER_WIDTH)) gantry (
                .clk(clk), .rst(rst),
                .write(bus_write), .addr(bus_address), .wdata(bus_write_data), .rdata(gantry_rdata),
                .enc_a(enc_a), .enc_b(enc_b), .enc_prescale(enc_prescale), .enc_filter(enc_filter),
                .clear_errors(clear_errors), .clear_counters(clear_counters),
                .panel_sync(panel_sync),
                .enable(gantry_enable), .sync(gantry_sync_mode), .master(gantry_master), .slave(gantry_slave),
                .tick(gantry_tick), .deadband(gantry_deadband), .limit(gantry_limit),
                .enc_master(gantry_enc_master), .enc_slave(gantry_enc_slave),
                .engaged(gantry_engaged), .alarm(gantry_alarm), .refused(gantry_refused),
                .error(gantry_error), .corrections(gantry_corrections),
                .error16(gantry_error16)
            );
        end else begin : no_gantry
            wire unused_gantry = &{1'b0, panel_sync, gantry_engaged, gantry_error, gantry_corrections};
            assign gantry_rdata      = 32'd0;
            assign gantry_enable     = 1'b0;
            assign gantry_sync_mode  = 1'b0;
            assign gantry_master     = 3'd0;
            assign gantry_slave      = 3'd0;
            assign gantry_tick       = 24'd0;
            assign gantry_deadband   = 16'd0;
            assign gantry_limit      = 16'd0;
            assign gantry_enc_master = 32'd0;
            assign gantry_enc_slave  = 32'd0;
            assign gantry_error16    = 16'd0;
        end

        if (HAS_PANEL != 0) begin : panel_block
            // alarm_in: {watchdog expired, E-stop, gantry refused, gantry alarm}
            panel #(.N_DIG(8)) card (
                .clk(clk), .rst(rst),
                .write(bus_write), .addr(bus_address), .wdata(bus_write_data), .rdata(panel_rdata),
                .sync_err(gantry_error16),
                .alarm_in({fault_watchdog, fault_estop, gantry_refused, gantry_alarm}),
                .sync_mode(panel_sync),
                .row_n(panel_row_n), .col_drive(panel_col), .seg(panel_seg), .dig(panel_dig)
            );
        end else begin : no_panel
            wire unused_panel = &{1'b0, panel_row_n, gantry_error16, gantry_refused, gantry_alarm};
            assign panel_rdata = 32'd0;
            assign panel_sync  = 1'b0;
            assign panel_col   = 4'd0;
            assign panel_seg   = 8'd0;
            assign panel_dig   = 8'd0;
        end
    endgenerate

    always @(posedge clk) begin
        if (rst || FEEDBACK_REG == 0) feedback_word_reg <= 32'd0;
        else if (bus_read) feedback_word_reg <= feedback_word;
    end

    wire unused_top = &{1'b0, fifo_overflow_unused};

endmodule

`default_nettype wire

`timescale 1ns / 1ps
`default_nettype none
// Specification: docs/spec/finestep_top.md#panel-and-gantry
// The gantry pair (seed 001) on the chip's register bus: GANTRY_CONTROL and
// GANTRY_LIMITS configure finestep_core's gantry_sync, GANTRY_STATUS reads it. The two
// channels it compares are decoded here, x4, by two hand_wheel decoders of its own on
// the pins of the encoder channels ENC_MASTER and ENC_SLAVE (sampled on ENC_PRESCALE,
// filtered by the channel's ENC_CONTROL.FILTER), so the encoder bank is not touched.
// The mode is the panel's (with HAS_PANEL) or GANTRY_CONTROL.SYNC.
//
// Latency: a register write reaches gantry_sync the clock after; a channel's pin edge
// reaches its count as in hand_wheel (2 clocks plus the filter's samples).
module gantry_link #(
    parameter N_ENC     = 4,
    parameter HAS_PANEL = 0,
    parameter FILTER_W  = 4
) (
    // clock, reset
    input  wire                      clk,
    input  wire                      rst,
    // register bus
    input  wire                      write,
    input  wire [6:0]                addr,
    input  wire [31:0]               wdata,
    output reg  [31:0]               rdata,          // the read value of addr, this cycle
    // the encoder pins and settings
    input  wire [N_ENC-1:0]          enc_a,
    input  wire [N_ENC-1:0]          enc_b,
    input  wire [15:0]               enc_prescale,
    input  wire [FILTER_W*N_ENC-1:0] enc_filter,
    input  wire                      clear_errors,
    input  wire                      clear_counters,
    // the panel's mode (with HAS_PANEL)
    input  wire                      panel_sync,
    // to gantry_sync
    output wire                      enable,
    output wire                      sync,
    output wire [2:0]                master,
    output wire [2:0]                slave,
    output wire [23:0]               tick,
    output wire [15:0]               deadband,
    output wire [15:0]               limit,
    output wire [31:0]               enc_master,
    output wire [31:0]               enc_slave,
    // from gantry_sync
    input  wire                      engaged,
    input  wire                      alarm,
    input  wire                      refused,
    input  wire [31:0]               error,
    input  wire [15:0]               corrections,
    // the error saturated to 16 bits (GANTRY_STATUS.ERROR, the panel's number)
    output wire [15:0]               error16
);

`include "finestep_regs.vh"

    reg        enable_reg;
    reg        sync_reg;
    reg [2:0]  master_reg;
    reg [2:0]  slave_reg;
    reg [1:0]  enc_m_reg;
    reg [1:0]  enc_s_reg;
    reg [15:0] tick_reg;
    reg [15:0] deadband_reg;
    reg [15:0] limit_reg;

    wire control_write = write && (addr == FS_GANTRY_CONTROL_ADDR);
    wire limits_write  = write && (addr == FS_GANTRY_LIMITS_ADDR);

    always @(posedge clk) begin
        if (rst) begin
            enable_reg   <= FS_GANTRY_CONTROL_ENABLE_RESET;
            sync_reg     <= FS_GANTRY_CONTROL_SYNC_RESET;
            master_reg   <= FS_GANTRY_CONTROL_MASTER_RESET;
            slave_reg    <= FS_GANTRY_CONTROL_SLAVE_RESET;
            enc_m_reg    <= FS_GANTRY_CONTROL_ENC_MASTER_RESET;
            enc_s_reg    <= FS_GANTRY_CONTROL_ENC_SLAVE_RESET;
            tick_reg     <= FS_GANTRY_CONTROL_TICK_RESET;
            deadband_reg <= FS_GANTRY_LIMITS_DEADBAND_RESET;
            limit_reg    <= FS_GANTRY_LIMITS_LIMIT_RESET;
        end else begin
            if (control_write) begin
                enable_reg <= wdata[FS_GANTRY_CONTROL_ENABLE_LSB];
                sync_reg   <= wdata[FS_GANTRY_CONTROL_SYNC_LSB];
                master_reg <= wdata[FS_GANTRY_CONTROL_MASTER_LSB +: FS_GANTRY_CONTROL_MASTER_WIDTH];
                slave_reg  <= wdata[FS_GANTRY_CONTROL_SLAVE_LSB +: FS_GANTRY_CONTROL_SLAVE_WIDTH];
                enc_m_reg  <= wdata[FS_GANTRY_CONTROL_ENC_MASTER_LSB +: FS_GANTRY_CONTROL_ENC_MASTER_WIDTH];
                enc_s_reg  <= wdata[FS_GANTRY_CONTROL_ENC_SLAVE_LSB +: FS_GANTRY_CONTROL_ENC_SLAVE_WIDTH];
                tick_reg   <= wdata[FS_GANTRY_CONTROL_TICK_LSB +: FS_GANTRY_CONTROL_TICK_WIDTH];
            end
            if (limits_write) begin
                deadband_reg <= wdata[FS_GANTRY_LIMITS_DEADBAND_LSB +: FS_GANTRY_LIMITS_DEADBAND_WIDTH];
                limit_reg    <= wdata[FS_GANTRY_LIMITS_LIMIT_LSB +: FS_GANTRY_LIMITS_LIMIT_WIDTH];
            end
        end
    end

    // The two channels' pins (a channel not built reads low) and decoders.
    wire [3:0]            a4, b4;
    wire [FILTER_W*4-1:0] f4;
    genvar c;
    generate
        for (c = 0; c < 4; c = c + 1) begin : channel
            if (c < N_ENC) begin : built
                assign a4[c] = enc_a[c];
                assign b4[c] = enc_b[c];
                assign f4[FILTER_W*c +: FILTER_W] = enc_filter[FILTER_W*c +: FILTER_W];
            end else begin : absent
                assign a4[c] = 1'b0;
                assign b4[c] = 1'b0;
                assign f4[FILTER_W*c +: FILTER_W] = {FILTER_W{1'b0}};
            end
        end
    endgenerate
    wire [31:0] det_m_unused, det_s_unused;
    wire [15:0] ill_m_unused, ill_s_unused;
    wire [3:0]  lvl_unused;
    wire [3:0]  step_unused;   // the detent flags (the jog's), unused here
    hand_wheel #(.FILTER_W(FILTER_W)) dec_master (
        .clk(clk), .rst(rst), .mpg_a(a4[enc_m_reg]), .mpg_b(b4[enc_m_reg]),
        .prescale(enc_prescale), .filter_len(f4[FILTER_W*enc_m_reg +: FILTER_W]),
        .clear_errors(clear_errors), .clear_counters(clear_counters),
        .count(enc_master), .detents(det_m_unused), .illegal(lvl_unused[0]),
        .illegal_count(ill_m_unused), .a_level(lvl_unused[1]), .b_level(lvl_unused[2]),
        .detent_up(step_unused[0]), .detent_down(step_unused[1])
    );
    wire ill_s_flag_unused, a_s_unused, b_s_unused;
    hand_wheel #(.FILTER_W(FILTER_W)) dec_slave (
        .clk(clk), .rst(rst), .mpg_a(a4[enc_s_reg]), .mpg_b(b4[enc_s_reg]),
        .prescale(enc_prescale), .filter_len(f4[FILTER_W*enc_s_reg +: FILTER_W]),
        .clear_errors(clear_errors), .clear_counters(clear_counters),
        .count(enc_slave), .detents(det_s_unused), .illegal(ill_s_flag_unused),
        .illegal_count(ill_s_unused), .a_level(a_s_unused), .b_level(b_s_unused),
        .detent_up(step_unused[2]), .detent_down(step_unused[3])
    );
    assign lvl_unused[3] = 1'b0;
    wire unused_dec = &{1'b0, det_m_unused, det_s_unused, ill_m_unused, ill_s_unused, lvl_unused,
                        ill_s_flag_unused, a_s_unused, b_s_unused, step_unused,
                        corrections[15:FS_GANTRY_STATUS_CORRECTIONS_WIDTH]};

    assign enable   = enable_reg;
    assign sync     = (HAS_PANEL != 0) ? panel_sync : sync_reg;
    assign master   = master_reg;
    assign slave    = slave_reg;
    assign tick     = {4'd0, tick_reg, 4'hF};
    assign deadband = deadband_reg;
    assign limit    = limit_reg;

    // error saturated to the signed 16-bit range
    wire over  = !error[31] && (error[30:15] != 16'h0000);
    wire under = error[31] && (error[30:15] != 16'hFFFF);
    assign error16 = over ? 16'h7FFF : (under ? 16'h8000 : error[15:0]);

    always @* begin
        rdata = 32'd0;
        case (addr)
            FS_CAPS_ADDR: rdata[FS_CAPS_HAS_GANTRY_LSB] = 1'b1;
            FS_GANTRY_CONTROL_ADDR: begin
                rdata[FS_GANTRY_CONTROL_ENABLE_LSB] = enable_reg;
                rdata[FS_GANTRY_CONTROL_SYNC_LSB]   = sync_reg;
                rdata[FS_GANTRY_CONTROL_MASTER_LSB +: FS_GANTRY_CONTROL_MASTER_WIDTH]         = master_reg;
                rdata[FS_GANTRY_CONTROL_SLAVE_LSB +: FS_GANTRY_CONTROL_SLAVE_WIDTH]           = slave_reg;
                rdata[FS_GANTRY_CONTROL_ENC_MASTER_LSB +: FS_GANTRY_CONTROL_ENC_MASTER_WIDTH] = enc_m_reg;
                rdata[FS_GANTRY_CONTROL_ENC_SLAVE_LSB +: FS_GANTRY_CONTROL_ENC_SLAVE_WIDTH]   = enc_s_reg;
                rdata[FS_GANTRY_CONTROL_TICK_LSB +: FS_GANTRY_CONTROL_TICK_WIDTH]             = tick_reg;
            end
            FS_GANTRY_LIMITS_ADDR: begin
                rdata[FS_GANTRY_LIMITS_DEADBAND_LSB +: FS_GANTRY_LIMITS_DEADBAND_WIDTH] = deadband_reg;
                rdata[FS_GANTRY_LIMITS_LIMIT_LSB +: FS_GANTRY_LIMITS_LIMIT_WIDTH]       = limit_reg;
            end
            FS_GANTRY_STATUS_ADDR: begin
                rdata[FS_GANTRY_STATUS_ERROR_LSB +: FS_GANTRY_STATUS_ERROR_WIDTH] = error16;
                rdata[FS_GANTRY_STATUS_CORRECTIONS_LSB +: FS_GANTRY_STATUS_CORRECTIONS_WIDTH] =
                    corrections[FS_GANTRY_STATUS_CORRECTIONS_WIDTH-1:0];
                rdata[FS_GANTRY_STATUS_ENGAGED_LSB] = engaged;
                rdata[FS_GANTRY_STATUS_ALARM_LSB]   = alarm;
                rdata[FS_GANTRY_STATUS_REFUSED_LSB] = refused;
                rdata[FS_GANTRY_STATUS_SYNC_LSB]    = sync;
            end
            default: ;
        endcase
    end

`ifdef FORMAL
    // The registers hold the last word written to them; gantry_sync sees them (the mode
    // the panel's with HAS_PANEL); the tick is a whole number of 16 clocks (TICK * 16 +
    // 15, never 0); GANTRY_STATUS.ERROR is the error saturated: equal inside the signed
    // 16-bit range, the range's end of the same sign outside it, so the panel and the
    // host never see an error of the wrong sign or one smaller than the limit it passed.
    reg f_past_valid;
    initial f_past_valid = 1'b0;
    initial assume (rst);
    always @(posedge clk) f_past_valid <= 1'b1;

    wire signed [31:0] f_err = error;
    always @(*) begin
        if (f_err > 32'sd32767) assert (error16 == 16'h7FFF);
        else if (f_err < -32'sd32768) assert (error16 == 16'h8000);
        else assert (error16 == error[15:0]);
        assert (error16[15] == error[31]);
        assert (tick[3:0] == 4'hF && tick[23:20] == 4'd0 && tick != 24'd0);
        assert (sync == ((HAS_PANEL != 0) ? panel_sync : sync_reg));
        assert (enable == enable_reg && limit == limit_reg && deadband == deadband_reg
                && master == master_reg && slave == slave_reg);
        if (addr == FS_GANTRY_STATUS_ADDR)
            assert (rdata[FS_GANTRY_STATUS_ALARM_LSB] == alarm
                    && rdata[FS_GANTRY_STATUS_ERROR_LSB +: FS_GANTRY_STATUS_ERROR_WIDTH] == error16);
    end

    always @(posedge clk) if (f_past_valid && !$past(rst) && !rst) begin
        if ($past(control_write)) begin
            assert (enable_reg == $past(wdata[FS_GANTRY_CONTROL_ENABLE_LSB]));
            assert (sync_reg == $past(wdata[FS_GANTRY_CONTROL_SYNC_LSB]));
            assert (tick_reg == $past(wdata[FS_GANTRY_CONTROL_TICK_LSB +: FS_GANTRY_CONTROL_TICK_WIDTH]));
            assert (slave_reg == $past(wdata[FS_GANTRY_CONTROL_SLAVE_LSB +: FS_GANTRY_CONTROL_SLAVE_WIDTH]));
        end else begin
            assert ($stable(enable_reg) && $stable(sync_reg) && $stable(tick_reg) && $stable(master_reg)
                    && $stable(slave_reg) && $stable(enc_m_reg) && $stable(enc_s_reg));
        end
        if ($past(limits_write))
            assert (limit_reg == $past(wdata[FS_GANTRY_LIMITS_LIMIT_LSB +: FS_GANTRY_LIMITS_LIMIT_WIDTH])
                    && deadband_reg == $past(wdata[FS_GANTRY_LIMITS_DEADBAND_LSB +: FS_GANTRY_LIMITS_DEADBAND_WIDTH]));
        else
            assert ($stable(limit_reg) && $stable(deadband_reg));
        cover (error16 == 16'h8000 && error != 32'hFFFF8000);
        cover (enable && sync && limit == 16'd5 && $past(control_write));
    end
`endif

endmodule

`default_nettype wire

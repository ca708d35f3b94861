`timescale 1ns / 1ps
`default_nettype none
// Specification: docs/spec/feedback_registers.md
// Host registers of the feedback blocks (encoders, probe, hand wheel, jog): their
// configuration fields, their one-shot arms, and their read values. It sits beside
// register_file on the same arbitrated register bus, served from its bus stage: writes
// take effect at the edge ending the serving cycle, pulses are high in the cycle after,
// and finestep_top takes `rdata` into its feedback word at the edge ending a served
// read's cycle, which register_file ORs after its read register (unmapped addresses read
// 0 here).
module feedback_registers #(
    parameter N_ENC   = 4,
    parameter N_AXES  = 4,
    parameter HAS_MPG = 1,
    parameter ONE_SNAPSHOT = 0   // 1: PROBE_TIME and PROBE_POSITION are answered by register_file
) (
    // clock, reset
    input  wire                  clk,
    input  wire                  rst,
    // arbitrated register bus
    input  wire                  write,
    input  wire [6:0]            addr,
    input  wire [31:0]           wdata,
    output reg  [31:0]           rdata,      // the read value of addr, this cycle
    input  wire                  halt,
    // encoder and probe configuration and arms
    output wire [15:0]           enc_prescale,
    output wire [2*N_ENC-1:0]    enc_mode,
    output wire [N_ENC-1:0]      enc_z_active_high,
    output wire [4*N_ENC-1:0]    enc_filter,
    // The three above as they will be after this clock's edge (this cycle's write and
    // reset applied): the encoder bank chooses a visit's configuration a clock ahead.
    output wire [2*N_ENC-1:0]    enc_mode_next,
    output wire [N_ENC-1:0]      enc_z_active_high_next,
    output wire [4*N_ENC-1:0]    enc_filter_next,
    output wire [N_ENC-1:0]      enc_arm_index_latch,
    output wire [N_ENC-1:0]      enc_arm_index_clear,
    output wire                  probe_active_high,
    output wire [3:0]            probe_filter,
    output wire                  probe_arm,
    // hand wheel and jog configuration
    output wire [15:0]           mpg_prescale,
    output wire [3:0]            mpg_filter,
    output wire                  jog_enable,
    output wire [2:0]            jog_axis,
    output wire [1:0]            jog_multiplier,
    output wire                  jog_follow,
    output wire [31:0]           jog_scale,
    output wire [30:0]           jog_vmax,
    output wire [30:0]           jog_accel,
    output wire [15:0]           jog_window,
    // encoder and probe state
    input  wire [16*N_ENC-1:0]   enc_illegal_count,
    input  wire [N_ENC-1:0]      enc_illegal,
    input  wire [N_ENC-1:0]      enc_index_seen,
    input  wire [N_ENC-1:0]      enc_latch_armed,
    input  wire [N_ENC-1:0]      enc_clear_armed,
    input  wire [N_ENC-1:0]      enc_a,
    input  wire [N_ENC-1:0]      enc_b,
    input  wire [N_ENC-1:0]      enc_z,
    input  wire                  probe_armed,
    input  wire                  probe_seen,
    input  wire                  probe_active,
    input  wire [31:0]           probe_time,
    input  wire [32*N_AXES-1:0]  probe_position,
    // hand wheel and jog state
    input  wire [31:0]           mpg_count,
    input  wire [31:0]           mpg_detents,
    input  wire                  mpg_illegal,
    input  wire [15:0]           mpg_illegal_count,
    input  wire                  mpg_a,
    input  wire                  mpg_b,
    input  wire                  jog_engaged,
    input  wire                  jog_stopping,
    input  wire                  jog_refused,
    input  wire [15:0]           jog_dropped,
    input  wire [31:0]           jog_remaining,
    input  wire [31:0]           jog_velocity
);

`include "finestep_regs.vh"

    reg [15:0]        enc_prescale_reg;
    reg [2*N_ENC-1:0] enc_mode_reg;
    reg [N_ENC-1:0]   enc_z_active_high_reg;
    reg [4*N_ENC-1:0] enc_filter_reg;
    reg [N_ENC-1:0]   enc_arm_latch_reg;
    reg [N_ENC-1:0]   enc_arm_clear_reg;
    reg               probe_active_high_reg;
    reg [3:0]         probe_filter_reg;
    reg               probe_arm_reg;
    reg [15:0]        mpg_prescale_reg;
    reg [3:0]         mpg_filter_reg;
    reg               jog_enable_reg;
    reg [2:0]         jog_axis_reg;
    reg [1:0]         jog_multiplier_reg;
    reg               jog_follow_reg;
    reg [31:0]        jog_scale_reg;
    reg [30:0]        jog_vmax_reg;
    reg [30:0]        jog_accel_reg;
    reg [15:0]        jog_window_reg;

    localparam MPG = (HAS_MPG != 0);

    integer w, r;   // loop indices, one per process
    reg [31:0] enc_control_word, enc_status_word;   // one channel's ENC_CONTROL and ENC_STATUS

    // The channels' configuration after this edge: the registers load exactly these.
    reg [2*N_ENC-1:0] enc_mode_nx;
    reg [N_ENC-1:0]   enc_z_active_high_nx;
    reg [4*N_ENC-1:0] enc_filter_nx;
    integer x;
    always @* begin
        enc_mode_nx          = enc_mode_reg;
        enc_z_active_high_nx = enc_z_active_high_reg;
        enc_filter_nx        = enc_filter_reg;
        for (x = 0; x < N_ENC; x = x + 1) begin
            if (write && {25'd0, addr} == {25'd0, FS_ENC_CONTROL_ADDR} + x * FS_ENC_CONTROL_STRIDE) begin
                enc_mode_nx[2*x +: 2]   = wdata[FS_ENC_CONTROL_MODE_LSB +: 2];
                enc_z_active_high_nx[x] = wdata[FS_ENC_CONTROL_Z_ACTIVE_HIGH_LSB];
                enc_filter_nx[4*x +: 4] = wdata[FS_ENC_CONTROL_FILTER_LSB +: 4];
            end
        end
        if (rst) begin
            enc_mode_nx          = {N_ENC{FS_ENC_CONTROL_MODE_RESET}};
            enc_z_active_high_nx = {N_ENC{FS_ENC_CONTROL_Z_ACTIVE_HIGH_RESET}};
            enc_filter_nx        = {N_ENC{FS_ENC_CONTROL_FILTER_RESET}};
        end
    end

    always @(posedge clk) begin
        enc_mode_reg          <= enc_mode_nx;
        enc_z_active_high_reg <= enc_z_active_high_nx;
        enc_filter_reg        <= enc_filter_nx;
        enc_arm_latch_reg <= {N_ENC{1'b0}};
        enc_arm_clear_reg <= {N_ENC{1'b0}};
        probe_arm_reg     <= 1'b0;
        if (write) begin
            case (addr)
                FS_ENC_PRESCALE_ADDR: enc_prescale_reg <= wdata[FS_ENC_PRESCALE_PRESCALE_LSB +: 16];
                FS_PROBE_CONTROL_ADDR: begin
                    probe_active_high_reg <= wdata[FS_PROBE_CONTROL_ACTIVE_HIGH_LSB];
                    probe_filter_reg      <= wdata[FS_PROBE_CONTROL_FILTER_LSB +: 4];
                    probe_arm_reg         <= wdata[FS_PROBE_CONTROL_ARM_LSB];
                end
                FS_MPG_CONTROL_ADDR: begin
                    mpg_prescale_reg <= wdata[FS_MPG_CONTROL_PRESCALE_LSB +: 16];
                    mpg_filter_reg   <= wdata[FS_MPG_CONTROL_FILTER_LSB +: 4];
                end
                FS_JOG_CONTROL_ADDR: begin
                    jog_enable_reg     <= wdata[FS_JOG_CONTROL_ENABLE_LSB];
                    jog_axis_reg       <= wdata[FS_JOG_CONTROL_AXIS_LSB +: 3];
                    jog_multiplier_reg <= wdata[FS_JOG_CONTROL_MULTIPLIER_LSB +: 2];
                    jog_follow_reg     <= wdata[FS_JOG_CONTROL_FOLLOW_LSB];
                end
                FS_JOG_SCALE_ADDR:  jog_scale_reg  <= wdata[FS_JOG_SCALE_STEPS_LSB +: 32];
                FS_JOG_VMAX_ADDR:   jog_vmax_reg   <= wdata[FS_JOG_VMAX_STEPS_LSB +: 31];
                FS_JOG_ACCEL_ADDR:  jog_accel_reg  <= wdata[FS_JOG_ACCEL_STEPS_LSB +: 31];
                FS_JOG_WINDOW_ADDR: jog_window_reg <= wdata[FS_JOG_WINDOW_STEPS_LSB +: 16];
                default: ;
            endcase
            for (w = 0; w < N_ENC; w = w + 1) begin
                if ({25'd0, addr} == {25'd0, FS_ENC_CONTROL_ADDR} + w * FS_ENC_CONTROL_STRIDE) begin
                    enc_arm_latch_reg[w]         <= wdata[FS_ENC_CONTROL_ARM_INDEX_LATCH_LSB];
                    enc_arm_clear_reg[w]         <= wdata[FS_ENC_CONTROL_ARM_INDEX_CLEAR_LSB];
                end
            end
        end
        // A halt stops the jog as it stops a run: the host re-enables it after the fault.
        if (halt) jog_enable_reg <= 1'b0;
        if (rst) begin
            enc_prescale_reg      <= FS_ENC_PRESCALE_PRESCALE_RESET;
            enc_arm_latch_reg     <= {N_ENC{1'b0}};
            enc_arm_clear_reg     <= {N_ENC{1'b0}};
            probe_active_high_reg <= FS_PROBE_CONTROL_ACTIVE_HIGH_RESET;
            probe_filter_reg      <= FS_PROBE_CONTROL_FILTER_RESET;
            probe_arm_reg         <= 1'b0;
            mpg_prescale_reg      <= FS_MPG_CONTROL_PRESCALE_RESET;
            mpg_filter_reg        <= FS_MPG_CONTROL_FILTER_RESET;
            jog_enable_reg        <= FS_JOG_CONTROL_ENABLE_RESET;
            jog_axis_reg          <= FS_JOG_CONTROL_AXIS_RESET;
            jog_multiplier_reg    <= FS_JOG_CONTROL_MULTIPLIER_RESET;
            jog_follow_reg        <= FS_JOG_CONTROL_FOLLOW_RESET;
            jog_scale_reg         <= FS_JOG_SCALE_STEPS_RESET;
            jog_vmax_reg          <= FS_JOG_VMAX_STEPS_RESET;
            jog_accel_reg         <= FS_JOG_ACCEL_STEPS_RESET;
            jog_window_reg        <= FS_JOG_WINDOW_STEPS_RESET;
        end
    end

    // Read values; the hand wheel's and the jog's registers read 0 without them.
    always @* begin
        rdata = 32'd0;
        case (addr)
            FS_ENC_PRESCALE_ADDR: rdata[FS_ENC_PRESCALE_PRESCALE_LSB +: 16] = enc_prescale_reg;
            FS_PROBE_CONTROL_ADDR: begin
                rdata[FS_PROBE_CONTROL_ACTIVE_HIGH_LSB] = probe_active_high_reg;
                rdata[FS_PROBE_CONTROL_FILTER_LSB +: 4] = probe_filter_reg;
            end
            FS_PROBE_STATUS_ADDR: begin
                rdata[FS_PROBE_STATUS_ARMED_LSB]  = probe_armed;
                rdata[FS_PROBE_STATUS_SEEN_LSB]   = probe_seen;
                rdata[FS_PROBE_STATUS_ACTIVE_LSB] = probe_active;
            end
            FS_PROBE_TIME_ADDR: rdata = ONE_SNAPSHOT != 0 ? 32'd0 : probe_time;
            default: ;
        endcase
        if (MPG) begin
            case (addr)
                FS_MPG_STATUS_ADDR: begin
                    rdata[FS_MPG_STATUS_ILLEGAL_COUNT_LSB +: 16] = mpg_illegal_count;
                    rdata[FS_MPG_STATUS_ILLEGAL_LSB]             = mpg_illegal;
                    rdata[FS_MPG_STATUS_A_LSB]                   = mpg_a;
                    rdata[FS_MPG_STATUS_B_LSB]                   = mpg_b;
                end
                FS_MPG_COUNT_ADDR:   rdata = mpg_count;
                FS_MPG_DETENTS_ADDR: rdata = mpg_detents;
                FS_MPG_CONTROL_ADDR: begin
                    rdata[FS_MPG_CONTROL_PRESCALE_LSB +: 16] = mpg_prescale_reg;
                    rdata[FS_MPG_CONTROL_FILTER_LSB +: 4]    = mpg_filter_reg;
                end
                FS_JOG_CONTROL_ADDR: begin
                    rdata[FS_JOG_CONTROL_ENABLE_LSB]          = jog_enable_reg;
                    rdata[FS_JOG_CONTROL_AXIS_LSB +: 3]       = jog_axis_reg;
                    rdata[FS_JOG_CONTROL_MULTIPLIER_LSB +: 2] = jog_multiplier_reg;
                    rdata[FS_JOG_CONTROL_FOLLOW_LSB]          = jog_follow_reg;
                end
                FS_JOG_SCALE_ADDR:  rdata = jog_scale_reg;
                FS_JOG_VMAX_ADDR:   rdata[30:0] = jog_vmax_reg;
                FS_JOG_ACCEL_ADDR:  rdata[30:0] = jog_accel_reg;
                FS_JOG_WINDOW_ADDR: rdata[15:0] = jog_window_reg;
                FS_JOG_STATUS_ADDR: begin
                    rdata[FS_JOG_STATUS_ENGAGED_LSB]       = jog_engaged;
                    rdata[FS_JOG_STATUS_STOPPING_LSB]      = jog_stopping;
                    rdata[FS_JOG_STATUS_REFUSED_LSB]       = jog_refused;
                    rdata[FS_JOG_STATUS_DROPPED_LSB +: 16] = jog_dropped;
                end
                FS_JOG_REMAINING_ADDR: rdata = jog_remaining;
                FS_JOG_VELOCITY_ADDR:  rdata = jog_velocity;
                default: ;
            endcase
        end
        // The per-channel arrays and the probe positions: an OR of masked words (the map
        // keeps addresses distinct), a shallow tree where a chain of overriding ifs would
        // be one 2:1 multiplexer per register in series.
        for (r = 0; r < N_ENC; r = r + 1) begin
            enc_control_word = 32'd0;
            enc_control_word[FS_ENC_CONTROL_MODE_LSB +: 2]     = enc_mode_reg[2*r +: 2];
            enc_control_word[FS_ENC_CONTROL_Z_ACTIVE_HIGH_LSB] = enc_z_active_high_reg[r];
            enc_control_word[FS_ENC_CONTROL_FILTER_LSB +: 4]   = enc_filter_reg[4*r +: 4];
            enc_status_word = 32'd0;
            enc_status_word[FS_ENC_STATUS_ILLEGAL_COUNT_LSB +: 16] = enc_illegal_count[16*r +: 16];
            enc_status_word[FS_ENC_STATUS_ILLEGAL_LSB]             = enc_illegal[r];
            enc_status_word[FS_ENC_STATUS_INDEX_SEEN_LSB]          = enc_index_seen[r];
            enc_status_word[FS_ENC_STATUS_LATCH_ARMED_LSB]         = enc_latch_armed[r];
            enc_status_word[FS_ENC_STATUS_CLEAR_ARMED_LSB]         = enc_clear_armed[r];
            enc_status_word[FS_ENC_STATUS_A_LSB]                   = enc_a[r];
            enc_status_word[FS_ENC_STATUS_B_LSB]                   = enc_b[r];
            enc_status_word[FS_ENC_STATUS_Z_LSB]                   = enc_z[r];
            rdata = rdata
                | ({32{{25'd0, addr} == {25'd0, FS_ENC_CONTROL_ADDR} + r * FS_ENC_CONTROL_STRIDE}} & enc_control_word)
                | ({32{{25'd0, addr} == {25'd0, FS_ENC_STATUS_ADDR} + r * FS_ENC_STATUS_STRIDE}} & enc_status_word);
        end
        // ENC_COUNT, ENC_INDEX_LATCH, ENC_PROBE_LATCH, ENC_EDGE_TIME: the encoder bank's
        // store answers them, after the register file's read register (late_rdata).
        for (r = 0; r < N_AXES; r = r + 1) begin
            if (ONE_SNAPSHOT == 0) rdata = rdata
                | ({32{{25'd0, addr} == {25'd0, FS_PROBE_POSITION_ADDR} + r * FS_PROBE_POSITION_STRIDE}} &
                   probe_position[32*r +: 32]);
        end
    end

    assign enc_prescale        = enc_prescale_reg;
    assign enc_mode            = enc_mode_reg;
    assign enc_z_active_high   = enc_z_active_high_reg;
    assign enc_filter          = enc_filter_reg;
    assign enc_mode_next          = enc_mode_nx;
    assign enc_z_active_high_next = enc_z_active_high_nx;
    assign enc_filter_next        = enc_filter_nx;
    assign enc_arm_index_latch = enc_arm_latch_reg;
    assign enc_arm_index_clear = enc_arm_clear_reg;
    assign probe_active_high   = probe_active_high_reg;
    assign probe_filter        = probe_filter_reg;
    assign probe_arm           = probe_arm_reg;
    // Without the hand wheel and the jog (HAS_MPG = 0) their configuration goes nowhere
    // and reads 0: the outputs are the reset values, so no logic reads the registers and
    // synthesis keeps no flip-flops for them (a hierarchical build keeps a register that
    // drives a port).
    assign mpg_prescale        = MPG ? mpg_prescale_reg : FS_MPG_CONTROL_PRESCALE_RESET;
    assign mpg_filter          = MPG ? mpg_filter_reg : FS_MPG_CONTROL_FILTER_RESET;
    assign jog_enable          = MPG && jog_enable_reg;
    assign jog_axis            = MPG ? jog_axis_reg : FS_JOG_CONTROL_AXIS_RESET;
    assign jog_multiplier      = MPG ? jog_multiplier_reg : FS_JOG_CONTROL_MULTIPLIER_RESET;
    assign jog_follow          = MPG ? jog_follow_reg : FS_JOG_CONTROL_FOLLOW_RESET;
    assign jog_scale           = MPG ? jog_scale_reg : FS_JOG_SCALE_STEPS_RESET;
    assign jog_vmax            = MPG ? jog_vmax_reg : FS_JOG_VMAX_STEPS_RESET;
    assign jog_accel           = MPG ? jog_accel_reg : FS_JOG_ACCEL_STEPS_RESET;
    assign jog_window          = MPG ? jog_window_reg : FS_JOG_WINDOW_STEPS_RESET;

endmodule

`default_nettype wire

`timescale 1ns / 1ps
`default_nettype none
// Simulation only (Verilator co-simulation, never synthesised): finestep_core behind
// registers that hold its inputs. The shim (sim/finestep_sim.cpp) sets the inputs and
// pulses `load` once before the clock edges that use them, so the core sees exactly the
// inputs it would see on its own ports, and no logic in the Verilated model depends
// combinationally on a top-level input. Verilator then evaluates the core's logic once
// per clock (after the edge) instead of also in its input region on both evaluations of
// each clock, which halved the simulation time. The ports are those of finestep_core
// plus `load`.
module finestep_core_sim #(
    parameter N_AXES     = 4,
    parameter P_WIDTH    = 20,
    parameter TIMING_W   = 12,
    parameter HAS_GANTRY = 1,
    parameter STEP_SHARED = 0,
    parameter STEP_DIGIT = 0,
    parameter HAS_PBP    = 0
) (
    input  wire                       load,
    input  wire                       clk,
    input  wire                       rst,
    input  wire                       run,
    input  wire [P_WIDTH-1:0]         period_clocks,
    input  wire                       clear_errors,
    input  wire                       halt,
    input  wire [N_AXES-1:0]          axis_enable,
    input  wire [TIMING_W*N_AXES-1:0] step_len,
    input  wire [TIMING_W*N_AXES-1:0] step_space,
    input  wire [TIMING_W*N_AXES-1:0] dir_setup,
    input  wire [TIMING_W*N_AXES-1:0] dir_hold,
    input  wire [2*N_AXES-1:0]        out_mode,
    input  wire [3*N_AXES-1:0]        invert,
    input  wire                       gantry_enable,
    input  wire                       gantry_sync_mode,
    input  wire [2:0]                 gantry_master,
    input  wire [2:0]                 gantry_slave,
    input  wire [23:0]                gantry_tick,
    input  wire [15:0]                gantry_deadband,
    input  wire [15:0]                gantry_limit,
    input  wire [31:0]                enc_master,
    input  wire [31:0]                enc_slave,
    input  wire                       clear_counters,
    input  wire                       rec_valid,
    output wire                       rec_ready,
    output wire                       period_boundary,
    input  wire [32*N_AXES-1:0]       rec_inc,
    input  wire [7:0]                 rec_flags,
    output wire [N_AXES-1:0]          pin_a,
    output wire [N_AXES-1:0]          pin_b,
    output wire [N_AXES-1:0]          pin_en,
    output wire [32*N_AXES-1:0]       position,
    output wire [N_AXES-1:0]          rate_error,
    output wire [N_AXES-1:0]          step_lost,
    output wire                       record_error,
    output wire                       block_end,
    output wire                       gantry_engaged,
    output wire                       gantry_alarm,
    output wire                       gantry_refused,
    output wire [31:0]                gantry_error,
    output wire [15:0]                gantry_corrections
);

    reg                       rst_q;
    reg                       run_q;
    reg [P_WIDTH-1:0]         period_clocks_q;
    reg                       clear_errors_q;
    reg                       halt_q;
    reg [N_AXES-1:0]          axis_enable_q;
    reg [TIMING_W*N_AXES-1:0] step_len_q;
    reg [TIMING_W*N_AXES-1:0] step_space_q;
    reg [TIMING_W*N_AXES-1:0] dir_setup_q;
    reg [TIMING_W*N_AXES-1:0] dir_hold_q;
    reg [2*N_AXES-1:0]        out_mode_q;
    reg [3*N_AXES-1:0]        invert_q;
    reg                       gantry_enable_q;
    reg                       gantry_sync_mode_q;
    reg [2:0]                 gantry_master_q;
    reg [2:0]                 gantry_slave_q;
    reg [23:0]                gantry_tick_q;
    reg [15:0]                gantry_deadband_q;
    reg [15:0]                gantry_limit_q;
    reg [31:0]                enc_master_q;
    reg [31:0]                enc_slave_q;
    reg                       clear_counters_q;
    reg                       rec_valid_q;
    reg [32*N_AXES-1:0]       rec_inc_q;
    reg [7:0]                 rec_flags_q;

    always @(posedge load) begin
        rst_q              <= rst;
        run_q              <= run;
        period_clocks_q    <= period_clocks;
        clear_errors_q     <= clear_errors;
        halt_q             <= halt;
        axis_enable_q      <= axis_enable;
        step_len_q         <= step_len;
        step_space_q       <= step_space;
        dir_setup_q        <= dir_setup;
        dir_hold_q         <= dir_hold;
        out_mode_q         <= out_mode;
        invert_q           <= invert;
        gantry_enable_q    <= gantry_enable;
        gantry_sync_mode_q <= gantry_sync_mode;
        gantry_master_q    <= gantry_master;
        gantry_slave_q     <= gantry_slave;
        gantry_tick_q      <= gantry_tick;
        gantry_deadband_q  <= gantry_deadband;
        gantry_limit_q     <= gantry_limit;
        enc_master_q       <= enc_master;
        enc_slave_q        <= enc_slave;
        clear_counters_q   <= clear_counters;
        rec_valid_q        <= rec_valid;
        rec_inc_q          <= rec_inc;
        rec_flags_q        <= rec_flags;
    end

    finestep_core #(
        .N_AXES(N_AXES),
        .P_WIDTH(P_WIDTH),
        .TIMING_W(TIMING_W),
        .HAS_GANTRY(HAS_GANTRY),
        .STEP_SHARED(STEP_SHARED),
        .STEP_DIGIT(STEP_DIGIT),
        .HAS_PBP(HAS_PBP)
    ) core (
        .clk(clk),
        .rst(rst_q),
        .run(run_q),
        .period_clocks(period_clocks_q),
        .clear_errors(clear_errors_q),
        .halt(halt_q),
        .axis_enable(axis_enable_q),
        .step_len(step_len_q),
        .step_space(step_space_q),
        .dir_setup(dir_setup_q),
        .dir_hold(dir_hold_q),
        .out_mode(out_mode_q),
        .invert(invert_q),
        .gantry_enable(gantry_enable_q),
        .gantry_sync_mode(gantry_sync_mode_q),
        .gantry_master(gantry_master_q),
        .gantry_slave(gantry_slave_q),
        .gantry_tick(gantry_tick_q),
        .gantry_deadband(gantry_deadband_q),
        .gantry_limit(gantry_limit_q),
        .enc_master(enc_master_q),
        .enc_slave(enc_slave_q),
        .clear_counters(clear_counters_q),
        .rec_valid(rec_valid_q),
        .rec_ready(rec_ready),
        .period_boundary(period_boundary),
        .rec_inc(rec_inc_q),
        .rec_flags(rec_flags_q),
        .rec_alt(1'b0),                         // the core's record port only (the jog's is the chip's)
        .rec_alt_lane({N_AXES{1'b0}}),
        .rec_alt_inc(32'd0),
        .pin_a(pin_a),
        .pin_b(pin_b),
        .pin_en(pin_en),
        .position(position),
        .rate_error(rate_error),
        .step_lost(step_lost),
        .record_error(record_error),
        .block_end(block_end),
        .gantry_engaged(gantry_engaged),
        .gantry_alarm(gantry_alarm),
        .gantry_refused(gantry_refused),
        .gantry_error(gantry_error),
        .gantry_corrections(gantry_corrections)
    );

endmodule

`default_nettype wire

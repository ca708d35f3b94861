`timescale 1ns / 1ps
`default_nettype none
// Specification: docs/spec/jog_generator.md
// Jog generator: moves one axis after the hand wheel, through the core. While engaged it
// is the core's record source: one record a period carrying `next_vel` on the jogged
// axis, so the DDA, the step timing, the rate checks and the step position serve the jog
// as they serve streamed motion. Detents move a target (x1/x10/x100 of JOG_SCALE);
// jog_velocity chases it within JOG_VMAX and JOG_ACCEL and lands on it exactly. In drop
// mode a detent that would put the target more than JOG_WINDOW from the commanded
// position is dropped and counted; in follow mode every detent is followed, later.
// The jog engages only while RUN is 0: the jog and the FIFO never drive the core at once.
module jog_generator #(
    parameter N_AXES  = 4,
    parameter P_WIDTH = 20
) (
    // clock, reset
    input  wire                 clk,
    input  wire                 rst,
    // configuration
    input  wire                 enable,
    input  wire [2:0]           axis_select,
    input  wire [1:0]           multiplier,
    input  wire                 follow,
    input  wire [31:0]          scale,
    input  wire [30:0]          vmax,
    input  wire [30:0]          accel,
    input  wire [15:0]          window,
    input  wire [P_WIDTH-1:0]   period_clocks,
    // machine state and commands
    input  wire                 run,              // CONTROL.RUN
    input  wire                 run_write_one,    // a write of CONTROL with RUN = 1 is served
    input  wire                 halt,
    input  wire                 rec_ready,        // the core's period boundary
    input  wire                 clear_errors,
    input  wire                 clear_counters,
    input  wire [31:0]          detents,
    // record to the core and state
    output wire [32*N_AXES-1:0] rec_inc,
    output wire                 engaged,
    output wire                 stopping,
    output wire                 refused,
    output wire [15:0]          dropped,
    output wire [31:0]          remaining,
    output wire [31:0]          velocity
);

    localparam MIN_PERIOD = 128;
`include "finestep_interface.vh"

    reg         engaged_reg;
    reg  [2:0]  axis_reg;
    reg  [47:0] rem_reg;            // target - cmd: the spec's two positions held as their difference
    reg  [31:0] vel_reg;
    reg  [31:0] next_vel_reg;
    reg  [1:0]  last_det_reg;
    reg  [15:0] dropped_reg;
    reg         refused_reg;
    // The detent configuration through two registers, so that no detent decision adds
    // the shift-adds of the travel and the window to its own carry chains.
    reg  [47:0] travel_cfg_reg;     // m * JOG_SCALE of the cycle before
    reg  [47:0] window_cfg_reg;     // JOG_WINDOW * 65536 of the cycle before
    reg  [47:0] travel_reg;         // the travel a detent uses (two cycles behind)
    reg  [47:0] travel_neg_reg;     // its negative
    // |rem + s| <= W for s = +travel and s = -travel, as two signs each (49 bits: exact):
    // rem + s - W - 1 < 0 and rem + s + W >= 0.
    reg  [48:0] up_over_reg, up_under_reg, down_over_reg, down_under_reg;

    // `detents` moves by at most one a cycle (hand_wheel): its low two bits tell the way.
    wire [1:0]  delta_low  = detents[1:0] - last_det_reg[1:0];
    wire        det_up     = (delta_low == 2'd1);
    wire        det_down   = (delta_low == 2'd3);
    wire        period_ok  = ({{(32-P_WIDTH){1'b0}}, period_clocks} >= MIN_PERIOD);
    wire        axis_ok    = ({29'd0, axis_select} < N_AXES);
    wire        engage     = !engaged_reg && enable && !run && !halt && period_ok && axis_ok;
    wire        boundary   = engaged_reg && rec_ready;
    wire        disengage  = boundary && !enable && (vel_reg == 32'd0) && (next_vel_reg == 32'd0);

    // Travel of one detent: scale times 1, 10 or 100 (shift-adds), sign-extended.
    wire [47:0] scale_x1   = {{16{scale[31]}}, scale};
    wire [47:0] scale_x10  = (scale_x1 << 3) + (scale_x1 << 1);
    wire [47:0] scale_x100 = (scale_x1 << 6) + (scale_x1 << 5) + (scale_x1 << 2);
    wire [47:0] detent_travel = (multiplier == FS_JOG_MULTIPLIER_X1) ? scale_x1 :
                                (multiplier == FS_JOG_MULTIPLIER_X10) ? scale_x10 : scale_x100;
    wire [48:0] travel_cfg_49 = {travel_cfg_reg[47], travel_cfg_reg};
    wire [48:0] window_cfg_49 = {1'b0, window_cfg_reg};

    wire [48:0] rem_49     = {rem_reg[47], rem_reg};
    wire [48:0] up_over    = rem_49 + up_over_reg;
    wire [48:0] up_under   = rem_49 + up_under_reg;
    wire [48:0] down_over  = rem_49 + down_over_reg;
    wire [48:0] down_under = rem_49 + down_under_reg;
    wire        in_window  = det_up ? (up_over[48] && !up_under[48]) : (down_over[48] && !down_under[48]);
    wire unused_sums = &{1'b0, up_over[47:0], up_under[47:0], down_over[47:0], down_under[47:0]};
    wire        detent_now = engaged_reg && enable && !halt && (det_up || det_down);   // a halt wins
    wire        follows    = detent_now && (follow || in_window);

    // rem after this cycle: minus the record taken at a boundary, plus a followed detent.
    // The four outcomes are summed side by side from registers (the three-input one is a
    // carry-save layer and one chain) and chosen by the boundary and the window check.
    wire [47:0] vel_wide    = {{16{next_vel_reg[31]}}, next_vel_reg};
    wire [47:0] travel_sel  = det_up ? travel_reg : travel_neg_reg;
    wire [47:0] rem_taken   = rem_reg - vel_wide;
    wire [47:0] rem_stepped = rem_reg + travel_sel;
    wire [47:0] rem_both    = rem_reg - vel_wide + travel_sel;
    wire [47:0] rem_kept    = boundary ? rem_taken : rem_reg;
    wire [47:0] rem_moved   = boundary ? rem_both : rem_stepped;

    wire        result_valid;
    wire [31:0] result;
    jog_velocity velocity_calc (
        .clk(clk), .rst(rst),
        .restart(boundary && !disengage), .drop(halt || disengage),
        .distance(rem_reg), .vel(vel_reg), .enable(enable),
        .vmax(vmax), .accel(accel),
        .result_valid(result_valid), .result(result)
    );

    always @(posedge clk) begin
        last_det_reg   <= detents[1:0];
        travel_cfg_reg <= detent_travel;
        window_cfg_reg <= {16'd0, window, 16'd0};
        travel_reg     <= travel_cfg_reg;
        travel_neg_reg <= -travel_cfg_reg;
        up_over_reg    <= travel_cfg_49 - window_cfg_49 - 49'd1;
        up_under_reg   <= travel_cfg_49 + window_cfg_49;
        down_over_reg  <= -travel_cfg_49 - window_cfg_49 - 49'd1;
        down_under_reg <= window_cfg_49 - travel_cfg_49;

        rem_reg <= follows ? rem_moved : rem_kept;
        if (detent_now && !follows) dropped_reg <= dropped_reg + 16'd1;
        if (clear_counters) dropped_reg <= 16'd0;

        if (result_valid) next_vel_reg <= result;
        if (boundary) vel_reg <= next_vel_reg;
        if (disengage) engaged_reg <= 1'b0;

        if (engage) begin
            engaged_reg <= 1'b1;
            axis_reg    <= axis_select;
        end

        if ((enable && run) || (enable && !engaged_reg && (!period_ok || !axis_ok)) ||
            (run_write_one && engaged_reg))
            refused_reg <= 1'b1;
        else if (clear_errors)
            refused_reg <= 1'b0;

        if (halt) engaged_reg <= 1'b0;
        // Engaging starts from rest at position 0; a halt leaves the jog there.
        if (engage || halt) begin
            rem_reg      <= 48'd0;
            vel_reg      <= 32'd0;
            next_vel_reg <= 32'd0;
        end
        if (rst) begin
            engaged_reg    <= 1'b0;
            axis_reg       <= 3'd0;
            rem_reg        <= 48'd0;
            vel_reg        <= 32'd0;
            next_vel_reg   <= 32'd0;
            last_det_reg   <= 2'd0;
            dropped_reg    <= 16'd0;
            refused_reg    <= 1'b0;
            travel_cfg_reg <= 48'd0;
            window_cfg_reg <= 48'd0;
            travel_reg     <= 48'd0;
            travel_neg_reg <= 48'd0;
            up_over_reg    <= -49'd1;
            up_under_reg   <= 49'd0;
            down_over_reg  <= -49'd1;
            down_under_reg <= 49'd0;
        end
    end

    genvar i;
    generate
        for (i = 0; i < N_AXES; i = i + 1) begin : record
            assign rec_inc[32*i +: 32] = (axis_reg == i) ? next_vel_reg : 32'd0;
        end
    endgenerate

    assign engaged   = engaged_reg;
    assign stopping  = engaged_reg && !enable;
    assign refused   = refused_reg;
    assign dropped   = dropped_reg;
    assign remaining = rem_reg[47:16];
    wire unused_jog = &{1'b0, detents[31:2]};

`ifdef FORMAL
    // Arbitration and bookkeeping: the jog engages only when asked, with RUN low, not
    // halted and a usable period and axis; a halt leaves it disengaged at rest; the
    // distance to go moves by exactly one detent's travel on a followed detent and by
    // the record taken at a boundary, and by nothing else; the window check is the
    // spec's |cand - cmd| <= JOG_WINDOW * 65536 on 48-bit positions; a dropped detent is
    // counted; a disengaged jog offers zero increments.
    reg f_past_valid;
    initial f_past_valid = 1'b0;
    initial assume (rst);
    always @(posedge clk) f_past_valid <= 1'b1;
    // hand_wheel's detent count moves by at most one a cycle, from 0 at reset.
    reg  [31:0] f_prev_det;
    always @(posedge clk) f_prev_det <= rst ? 32'd0 : detents;
    wire [31:0] f_det_step = detents - f_prev_det;
    always @(*) if (f_past_valid) assume (f_det_step == 32'd0 || f_det_step == 32'd1 || f_det_step == 32'hFFFF_FFFF);
    // The configuration the detents use: two cycles behind, consistent.
    reg  [47:0] f_travel_1, f_travel_2, f_window_1, f_window_2;
    always @(posedge clk) begin
        f_travel_1 <= rst ? 48'd0 : detent_travel;
        f_travel_2 <= rst ? 48'd0 : f_travel_1;
        f_window_1 <= rst ? 48'd0 : {16'd0, window, 16'd0};
        f_window_2 <= rst ? 48'd0 : f_window_1;
    end
    wire [47:0] f_cand_gap  = rem_reg + (det_up ? travel_reg : -travel_reg);
    wire [47:0] f_gap_abs   = f_cand_gap[47] ? -f_cand_gap : f_cand_gap;
    wire [47:0] f_taken     = vel_wide;
    always @(posedge clk) if (f_past_valid && !$past(rst) && !rst) begin
        begin
            assert (travel_reg == f_travel_2);
            assert (travel_neg_reg == -f_travel_2);
            assert (up_over_reg == {f_travel_2[47], f_travel_2} - {1'b0, f_window_2} - 49'd1);
            assert (up_under_reg == {f_travel_2[47], f_travel_2} + {1'b0, f_window_2});
            assert (down_over_reg == -{f_travel_2[47], f_travel_2} - {1'b0, f_window_2} - 49'd1);
            assert (down_under_reg == {1'b0, f_window_2} - {f_travel_2[47], f_travel_2});
            if (det_up || det_down) assert (in_window == (f_gap_abs <= f_window_2));
        end
        if (engaged_reg && !$past(engaged_reg))
            assert ($past(enable) && !$past(run) && !$past(halt) && $past(period_ok) && $past(axis_ok));
        if ($past(halt)) assert (!engaged_reg && vel_reg == 32'd0 && next_vel_reg == 32'd0 && rem_reg == 48'd0);
        if ($past(halt) && !$past(clear_counters)) assert (dropped_reg == $past(dropped_reg));
        if ($past(enable && run)) assert (refused_reg);
        if (!$past(engage) && !$past(halt))
            assert (rem_reg == $past(rem_reg) - ($past(boundary) ? $past(f_taken) : 48'd0) +
                    (!$past(follows) ? 48'd0 : $past(det_up) ? $past(travel_reg) : -$past(travel_reg)));
        if ($past(follows)) assert ($past(detent_now) && ($past(follow) || $past(f_gap_abs) <= $past(f_window_2)));
        if (!$past(engage) && !$past(halt) && !$past(clear_counters) && $past(detent_now) && !$past(follow) &&
            !($past(f_gap_abs) <= $past(f_window_2)))
            assert (dropped_reg == $past(dropped_reg) + 16'd1);
        if ($past(boundary) && !$past(engage) && !$past(halt)) assert (vel_reg == $past(next_vel_reg));
        if (!$past(boundary) && !$past(engage) && !$past(halt)) assert (vel_reg == $past(vel_reg));
        cover (engaged_reg && rem_reg != 48'd0);
        cover ($past(engaged_reg) && !engaged_reg && !$past(halt));
        cover ($past(detent_now) && !$past(follows) && $past(travel_reg) != 48'd0);
    end
    // The travel is sign-extended from at most 39 bits (|100 * JOG_SCALE| < 2^38), which
    // keeps the 49-bit window sums exact.
    always @(*) if (f_past_valid && !rst) begin
        assert (travel_cfg_reg[47:38] == {10{travel_cfg_reg[47]}});
        assert (travel_reg[47:38] == {10{travel_reg[47]}});
        assert (window_cfg_reg[15:0] == 16'd0 && window_cfg_reg[47:32] == 16'd0);
        assert (last_det_reg == f_prev_det[1:0]);
    end
    always @(*) if (f_past_valid && !rst && !engaged_reg) assert (rec_inc == {32*N_AXES{1'b0}} || next_vel_reg != 32'd0);
`endif
    assign velocity  = vel_reg;


endmodule

`default_nettype wire

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
//
// Area (the same function and schedule as the spec's registers, fewer and narrower ones):
// - The spec's target and cmd are held as one 48-bit difference rem = target - cmd.
// - |m * JOG_SCALE| <= 100 * 2^31 < 2^38: the travel is 39 bits signed; x10 = 2 * 5s and
//   x100 = 4 * 25s come from two shift-adds in series (5s, then 5 * 5s). The window is
//   held as its 16 bits (W = JOG_WINDOW * 65536).
// - The detent check stays one carry chain from registers per bound (a detent can follow
//   a detent on the next clock: hand_wheel sampled every clock moves `detents` back and
//   forth on consecutive clocks when its contacts bounce): the bounds travel + W and
//   travel - W - 1 are held, and the check for -travel runs the same two chains on ~rem.
//   40 bits suffice: for |rem| >= 2^38 every detent is out of the window.
// - -travel is never held: the step is travel ^ {down} with the 1 as a carry in.
// - vel == 0 and next_vel == 0 are flags kept beside the registers, so the disengage
//   decision (which restarts or drops the velocity computation) carries no 32-bit compare.
// - The axis is held one-hot (a flip-flop a record lane): the record's select is no
//   compare of a 3-bit register.
// - jog_velocity keeps no copy of vel: vel holds while a computation runs (proven here).
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
    input  wire                 detent_up,        // hand_wheel: the detent count moves +1,
    input  wire                 detent_down,      // -1 in this cycle (flip-flops, never both)
    // record to the core and state
    output wire [N_AXES-1:0]    rec_lane,         // the record: rec_word on the lanes marked
    output wire [31:0]          rec_word,         // here (the axis, one-hot), zero on the others
    output wire                 engaged,
    output wire                 stopping,
    output wire                 refused,
    output wire [15:0]          dropped,
    output wire [31:0]          remaining,
    output wire [31:0]          velocity
);

    localparam MIN_PERIOD = 128;
    localparam [N_AXES-1:0] AXIS0_HOT = 1;   // axis 0, one-hot (the reset axis)
`include "finestep_interface.vh"

    reg         engaged_reg;
    reg  [N_AXES-1:0] axis_hot_reg;  // the spec's axis, one-hot: the record's select is one flip-flop a lane
    reg  [47:0] rem_reg;            // target - cmd: the spec's two positions held as their difference
    reg  [31:0] vel_reg;
    reg  [31:0] next_vel_reg;
    reg         vel_zero_reg;       // vel == 0 and next_vel == 0, kept beside them so that the
    reg         next_vel_zero_reg;  // disengage decision carries no 32-bit compare
    reg  [15:0] dropped_reg;
    reg         refused_reg;
    // The detent configuration through two registers (the spec's travel_cfg/window_cfg, then
    // travel/window): the travel of a detent, m * JOG_SCALE (|.| < 2^38: 39 bits signed),
    // and the window in units of 65536 (16 bits); then the travel and the two window
    // bounds the detent check adds to the distance, travel + W and travel - W - 1 (40 bits
    // signed; travel + W has the travel's low 16 bits, so only its high 24 are held).
    reg  [38:0] travel_cfg_reg;
    reg  [15:0] window_cfg_reg;
    reg  [38:0] travel_reg;
    reg  [39:16] bound_hi_reg;      // travel + W, bits 39..16
    reg  [39:0] bound_lo_reg;       // travel - W - 1
    // The spec's delta = detents - last_det (+1, -1 or 0) comes from hand_wheel as two
    // flip-flops, decoded there a clock ahead: no decode in front of the window chains.
    wire        det_up     = detent_up;
    wire        det_down   = detent_down;
    wire        det_way    = detent_down;
    wire        period_ok  = ({{(32-P_WIDTH){1'b0}}, period_clocks} >= MIN_PERIOD);
    wire        axis_ok    = ({29'd0, axis_select} < N_AXES);
    wire        engage     = !engaged_reg && enable && !run && !halt && period_ok && axis_ok;
    wire        boundary   = engaged_reg && rec_ready;
    wire [N_AXES-1:0] axis_hot;     // axis_select, one-hot (below)
    wire        disengage  = boundary && !enable && vel_zero_reg && next_vel_zero_reg;

    // Travel of one detent: 5s, 25s = 5 * 5s (two shift-adds in series), then s, 10s = 2 * 5s
    // or 100s = 4 * 25s.
    wire [38:0] scale_x1   = {{7{scale[31]}}, scale};
    wire [38:0] scale_x5   = (scale_x1 << 2) + scale_x1;
    wire [38:0] scale_x25  = (scale_x5 << 2) + scale_x5;
    wire [38:0] detent_travel = (multiplier == FS_JOG_MULTIPLIER_X1) ? scale_x1 :
                                (multiplier == FS_JOG_MULTIPLIER_X10) ? (scale_x5 << 1) : (scale_x25 << 2);
    wire [39:0] travel_cfg_40 = {travel_cfg_reg[38], travel_cfg_reg};
    wire [39:0] window_cfg_40 = {8'd0, window_cfg_reg, 16'd0};

    // |rem + s| <= W for s = +travel and s = -travel, as the signs of two carry chains
    // from registers, with H = travel + W and L = travel - W - 1: up, rem + L < 0 and
    // rem + H >= 0; down (rem - travel <= W is rem <= H, rem - travel >= -W is rem > L),
    // L - rem < 0 and H - rem >= 0. Both ways are x + L + c < 0 and x + H + c >= 0 with
    // x = rem, c = 0 up and x = ~rem, c = 1 down (-rem = ~rem + 1): two chains for both
    // directions. |travel| <= 100 (2^31) and W < 2^32 make |travel| + W + 1 < 2^38: in 40
    // bits the sums are exact for |rem| < 2^38, and a larger |rem| leaves
    // |rem + s| > 2^38 - 100 (2^31) > W: out of the window.
    wire        rem_small  = (rem_reg[47:38] == {10{rem_reg[38]}});
    wire [39:0] rem_dir    = {rem_reg[38], rem_reg[38:0]} ^ {40{det_way}};
    wire [39:0] bound_hi   = {bound_hi_reg, travel_reg[15:0]};
    wire [40:0] over       = {rem_dir, det_way} + {bound_lo_reg, det_way};   // the carry in: a low
    wire [40:0] under      = {rem_dir, det_way} + {bound_hi, det_way};       // bit 1 on both sides
    wire        in_window  = rem_small && over[40] && !under[40];
    wire unused_sums = &{1'b0, over[39:0], under[39:0]};
    // The signed step of this cycle's detent, +travel or -travel (= ~travel + 1: the 1 is
    // the carry into the sum below, made by a low bit that is 1 on both sides).
    wire [47:0] step_inv   = {{9{travel_reg[38]}}, travel_reg} ^ {48{det_down}};
    wire        detent_now = engaged_reg && enable && !halt && (det_up || det_down);   // a halt wins
    wire        follows    = detent_now && (follow || in_window);

    // rem after this cycle: minus the record taken at a boundary, plus a followed detent.
    wire [47:0] vel_wide    = {{16{next_vel_reg[31]}}, next_vel_reg};
    wire [47:0] rem_taken   = rem_reg - vel_wide;
    wire [47:0] rem_kept    = boundary ? rem_taken : rem_reg;
    wire [48:0] moved_sum   = {rem_kept, 1'b1} + {step_inv, det_down};
    wire [47:0] rem_moved   = moved_sum[48:1];
    wire unused_moved = &{1'b0, moved_sum[0]};

    wire        result_valid;
    wire [31:0] result;
    wire        calc_busy;
    jog_velocity velocity_calc (
        .clk(clk), .rst(rst),
        .restart(boundary && !disengage), .drop(halt || disengage),
        .distance(rem_reg), .vel(vel_reg), .enable(enable),
        .vmax(vmax), .accel(accel), .busy(calc_busy),
        .result_valid(result_valid), .result(result)
    );

    always @(posedge clk) begin
        travel_cfg_reg <= detent_travel;
        window_cfg_reg <= window;
        travel_reg     <= travel_cfg_reg;
        bound_hi_reg   <= travel_cfg_40[39:16] + window_cfg_40[39:16];
        bound_lo_reg   <= travel_cfg_40 + ~window_cfg_40;

        rem_reg <= follows ? rem_moved : rem_kept;
        if (detent_now && !follows) dropped_reg <= dropped_reg + 16'd1;
        if (clear_counters) dropped_reg <= 16'd0;

        if (result_valid) begin
            next_vel_reg      <= result;
            next_vel_zero_reg <= (result == 32'd0);
        end
        if (boundary) begin
            vel_reg      <= next_vel_reg;
            vel_zero_reg <= next_vel_zero_reg;
        end
        if (disengage) engaged_reg <= 1'b0;

        if (engage) begin
            engaged_reg <= 1'b1;
            axis_hot_reg <= axis_hot;
        end

        if ((enable && run) || (enable && !engaged_reg && (!period_ok || !axis_ok)) ||
            (run_write_one && engaged_reg))
            refused_reg <= 1'b1;
        else if (clear_errors)
            refused_reg <= 1'b0;

        if (halt) engaged_reg <= 1'b0;
        // Engaging starts from rest at position 0; a halt leaves the jog there.
        if (engage || halt || rst) begin
            rem_reg           <= 48'd0;
            vel_reg           <= 32'd0;
            next_vel_reg      <= 32'd0;
            vel_zero_reg      <= 1'b1;
            next_vel_zero_reg <= 1'b1;
        end
        if (rst) begin
            engaged_reg    <= 1'b0;
            axis_hot_reg   <= AXIS0_HOT;
            dropped_reg    <= 16'd0;
            refused_reg    <= 1'b0;
            travel_cfg_reg <= 39'd0;
            window_cfg_reg <= 16'd0;
            travel_reg     <= 39'd0;
            bound_hi_reg   <= 24'd0;
            bound_lo_reg   <= -40'd1;
        end
    end

    genvar i;
    generate
        for (i = 0; i < N_AXES; i = i + 1) begin : record
            assign axis_hot[i] = ({29'd0, axis_select} == i);
        end
    endgenerate

    assign rec_lane  = axis_hot_reg;
    assign rec_word  = next_vel_reg;
    assign engaged   = engaged_reg;
    assign stopping  = engaged_reg && !enable;
    assign refused   = refused_reg;
    assign dropped   = dropped_reg;
    assign remaining = rem_reg[47:16];
    wire unused_jog = &{1'b0, calc_busy};

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
    // The spec's 3-bit axis, taken at engagement; the record's lanes select it one-hot.
    reg  [2:0]  f_axis;
    always @(posedge clk) if (rst) f_axis <= 3'd0; else if (engage) f_axis <= axis_select;
    always @(*) if (f_past_valid && !rst) begin
        assert (axis_hot_reg == (AXIS0_HOT << f_axis));
        assert ({29'd0, f_axis} < N_AXES);
    end
    // hand_wheel's detent count moves by at most one a cycle: up or down, never both.
    always @(*) assume (!(detent_up && detent_down));
    // The configuration the detents use: two cycles behind, consistent. The travel is the
    // spec's m * JOG_SCALE as a product (not the RTL's shift-adds).
    wire [47:0] f_scale_48  = {{16{scale[31]}}, scale};
    wire [47:0] f_travel_0  = (multiplier == FS_JOG_MULTIPLIER_X1) ? f_scale_48 :
                              (multiplier == FS_JOG_MULTIPLIER_X10) ? f_scale_48 * 48'd10 : f_scale_48 * 48'd100;
    reg  [47:0] f_travel_1, f_travel_2, f_window_1, f_window_2;
    always @(posedge clk) begin
        f_travel_1 <= rst ? 48'd0 : f_travel_0;
        f_travel_2 <= rst ? 48'd0 : f_travel_1;
        f_window_1 <= rst ? 48'd0 : {16'd0, window, 16'd0};
        f_window_2 <= rst ? 48'd0 : f_window_1;
    end
    wire [47:0] f_cand_gap  = rem_reg + (det_up ? f_travel_2 : -f_travel_2);
    wire [47:0] f_gap_abs   = f_cand_gap[47] ? -f_cand_gap : f_cand_gap;
    wire [47:0] f_taken     = vel_wide;
    wire [47:0] f_travel_cfg_48 = {{9{travel_cfg_reg[38]}}, travel_cfg_reg};
    wire [47:0] f_travel_48     = {{9{travel_reg[38]}}, travel_reg};
    // |m * JOG_SCALE| <= 100 * 2^31: the bound the 39-bit travel and the 40-bit window sums use.
    wire [47:0] f_travel_max    = 48'd100 << 31;
    always @(posedge clk) if (f_past_valid && !$past(rst) && !rst) begin
        begin
            assert (f_travel_48 == f_travel_2);
            assert ({{8{bound_hi[39]}}, bound_hi} == f_travel_2 + f_window_2);
            assert ({{8{bound_lo_reg[39]}}, bound_lo_reg} == f_travel_2 - f_window_2 - 48'd1);
            if (det_up || det_down) assert (in_window == (f_gap_abs <= f_window_2));
        end
        if (engaged_reg && !$past(engaged_reg))
            assert ($past(enable) && !$past(run) && !$past(halt) && $past(period_ok) && $past(axis_ok));
        if ($past(halt)) assert (!engaged_reg && vel_reg == 32'd0 && next_vel_reg == 32'd0 && rem_reg == 48'd0);
        if ($past(halt) && !$past(clear_counters)) assert (dropped_reg == $past(dropped_reg));
        if ($past(enable && run)) assert (refused_reg);
        if (!$past(engage) && !$past(halt))
            assert (rem_reg == $past(rem_reg) - ($past(boundary) ? $past(f_taken) : 48'd0) +
                    (!$past(follows) ? 48'd0 : $past(det_up) ? $past(f_travel_2) : -$past(f_travel_2)));
        if ($past(follows)) assert ($past(detent_now) && ($past(follow) || $past(f_gap_abs) <= $past(f_window_2)));
        if (!$past(engage) && !$past(halt) && !$past(clear_counters) && $past(detent_now) && !$past(follow) &&
            !($past(f_gap_abs) <= $past(f_window_2)))
            assert (dropped_reg == $past(dropped_reg) + 16'd1);
        if (!$past(engage) && !$past(halt) && !$past(clear_counters) && !($past(detent_now) && !$past(follows)))
            assert (dropped_reg == $past(dropped_reg));
        if ($past(boundary) && !$past(engage) && !$past(halt)) assert (vel_reg == $past(next_vel_reg));
        if (!$past(boundary) && !$past(engage) && !$past(halt)) assert (vel_reg == $past(vel_reg));
        // The disengage decision: the spec's vel == 0 and next_vel == 0, from the flags.
        if ($past(boundary) && !$past(enable) && $past(vel_reg) == 32'd0 && $past(next_vel_reg) == 32'd0 && !$past(engage))
            assert (!engaged_reg);
        if ($past(engaged_reg) && !$past(halt) && !($past(boundary) && !$past(enable) &&
            $past(vel_reg) == 32'd0 && $past(next_vel_reg) == 32'd0))
            assert (engaged_reg);
        cover (engaged_reg && rem_reg != 48'd0);
        cover ($past(engaged_reg) && !engaged_reg && !$past(halt));
        cover ($past(detent_now) && !$past(follows) && $past(travel_reg) != 39'd0);
    end
    always @(*) if (f_past_valid && !rst) begin
        assert (f_travel_cfg_48 == f_travel_1);
        assert ({16'd0, window_cfg_reg, 16'd0} == f_window_1);
        assert (f_travel_1[47] ? (-f_travel_1 <= f_travel_max) : (f_travel_1 <= f_travel_max));
        assert (vel_zero_reg == (vel_reg == 32'd0));
        assert (next_vel_zero_reg == (next_vel_reg == 32'd0));
    end
    // No computation runs while disengaged (a halt or the disengage drops it), so vel,
    // which changes only at a boundary, a halt or an engagement, holds while one runs
    // after its sample: jog_velocity's assumption, an assertion here (chformal in the .sby).
    always @(*) if (f_past_valid && !rst && !engaged_reg) assert (!calc_busy);
    always @(*) if (f_past_valid && !rst) assert (rec_lane == (AXIS0_HOT << f_axis));
`endif
    assign velocity  = vel_reg;


endmodule

`default_nettype wire

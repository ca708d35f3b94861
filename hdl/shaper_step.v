`timescale 1ns / 1ps
`default_nettype none
// Specification: docs/spec/step_shaper.md (the rules of one edge), docs/spec/step_engine.md
// One step-shaper decision, combinational: from the pending count, the level, the
// direction, this edge's DDA request and the counter compares (made by the caller:
// cnt >= X for step_shaper, cnt * S >= X for step_engine), whether the level falls,
// rises or the direction turns, the next pending count (clamped at +-127) and the
// sticky flags' causes. Used by step_shaper (every clock) and step_engine (every visit),
// so the rule is written once.
//
// The spec's arithmetic is e = pending + request (pending in [-127, 127], request in
// {-1, 0, +1}), then pending <- e - issued, saturated at +-127. Here the decisions are
// decoded from a few constant compares of pending (no carry chain before them), and the
// new pending is pending + (request - issued), summed for both outcomes of the decision
// and chosen by it (the callers' formal sections check both against the spec's sums).
module shaper_step (
    input  wire [7:0] pending,          // signed, in [-127, 127]
    input  wire       level,
    input  wire       dir,              // 1 = positive
    input  wire       req_valid,
    input  wire       req_negative,
    input  wire       halt,
    input  wire       len_reached,      // the level has lasted step_len
    input  wire       space_reached,    // ... step_space (low)
    input  wire       setup_reached,    // dir has lasted dir_setup
    input  wire       hold_reached,     // the level has lasted dir_hold (low)
    output wire       rise,
    output wire       fall,
    output wire       dir_change,
    output wire [7:0] pending_next,
    output wire       clamp_high,       // 127 + 1: a step lost
    output wire       clamp_low,        // -127 - 1: a step lost
    output wire       behind            // |e| >= 2: the pulses fell behind the DDA
);

    localparam [7:0] PEND_MAX = 8'sd127;

    wire req_up   = req_valid && !req_negative;
    wire req_down = req_valid && req_negative;
    wire p_neg    = pending[7];
    wire p_is_m2  = (pending == -8'sd2);
    wire p_is_m1  = (pending == -8'sd1);
    wire p_is_0   = (pending == 8'sd0);
    wire p_is_1   = (pending == 8'sd1);
    wire p_is_2   = (pending == 8'sd2);
    wire p_is_max = (pending == PEND_MAX);
    wire p_is_min = (pending == -PEND_MAX);
    // e != 0; e >= 0; |e| >= 2.
    wire want_step    = req_up ? !p_is_m1 : (req_down ? !p_is_1 : !p_is_0);
    wire want_forward = req_up ? (!p_neg || p_is_m1) : (req_down ? (!p_neg && !p_is_0) : !p_neg);
    wire far          = req_up ? !(p_is_m2 || p_is_m1 || p_is_0) :
                        (req_down ? !(p_is_0 || p_is_1 || p_is_2) : !(p_is_m1 || p_is_0 || p_is_1));
    wire dir_matches  = (want_forward == dir);

    assign fall       = level && len_reached;
    assign rise       = !halt && !level && want_step && dir_matches && space_reached && setup_reached;
    assign dir_change = !halt && !level && want_step && !dir_matches && hold_reached;

    // The new pending count is pending + (request - issued), saturated at +-127. Both
    // outcomes, with and without a rise, are summed and clamped beside the decision (their
    // terms are the request and dir, known at the visit's start), and the rise only
    // chooses one: no adder after the timing compares. r = request (+1, -1, 0); a rise
    // issues +1 when dir is 1, else -1.
    wire [7:0] request     = req_up ? 8'sd1 : (req_down ? -8'sd1 : 8'sd0);
    wire [7:0] request_rise = req_up ? (dir ? 8'sd0 : 8'sd2) :
                              req_down ? (dir ? -8'sd2 : 8'sd0) :
                              (dir ? -8'sd1 : 8'sd1);        // r - issued
    wire [7:0] sum_stay    = pending + request;
    wire [7:0] sum_rise    = pending + request_rise;
    // +1 (no +2 can reach past 127: it needs e < 0) from 127, or -1 from -127.
    wire clamp_high_stay = p_is_max && req_up;
    wire clamp_low_stay  = p_is_min && req_down;
    wire clamp_high_rise = p_is_max && !req_valid && !dir;
    wire clamp_low_rise  = p_is_min && !req_valid && dir;
    wire [7:0] next_stay = clamp_high_stay ? PEND_MAX : (clamp_low_stay ? -PEND_MAX : sum_stay);
    wire [7:0] next_rise = clamp_high_rise ? PEND_MAX : (clamp_low_rise ? -PEND_MAX : sum_rise);
    assign clamp_high = !halt && (rise ? clamp_high_rise : clamp_high_stay);
    assign clamp_low  = !halt && (rise ? clamp_low_rise : clamp_low_stay);
    assign behind     = !halt && far;
    assign pending_next = halt ? 8'd0 : (rise ? next_rise : next_stay);

`ifdef FORMAL
    // The step shaper's rules in the spec's arithmetic (step_shaper.md), pending in
    // [-127, 127]: r = the request (+1, -1, 0), e = pending + r; a rise when level is low and
    // e's sign matches dir (timing permitting), a direction change when it does not;
    // pending <- e - the issued step, clamped to [-127, 127] (the clamp flagged); behind
    // is |e| >= 2; a halt issues nothing and drops pending.
    wire signed [9:0] f_e    = $signed({{2{pending[7]}}, pending}) +
                               (req_up ? 10'sd1 : (req_down ? -10'sd1 : 10'sd0));
    wire              f_move = !halt && !level && f_e != 10'sd0;
    wire              f_fwd  = f_e > 10'sd0;
    wire signed [9:0] f_next = f_e - (rise ? (dir ? 10'sd1 : -10'sd1) : 10'sd0);
    always @(*) if (pending != 8'h80) begin
        assert (behind == (!halt && (f_e >= 10'sd2 || f_e <= -10'sd2)));
        assert (fall == (level && len_reached));
        assert (rise == (f_move && f_fwd == dir && space_reached && setup_reached));
        assert (dir_change == (f_move && f_fwd != dir && hold_reached));
        assert (clamp_high == (!halt && f_next > 10'sd127));
        assert (clamp_low == (!halt && f_next < -10'sd127));
        if (halt) assert (pending_next == 8'd0);
        else if (f_next > 10'sd127) assert (pending_next == 8'sd127);
        else if (f_next < -10'sd127) assert (pending_next == -8'sd127);
        else assert (pending_next == f_next[7:0]);
    end
`endif

endmodule

`default_nettype wire

`timescale 1ns / 1ps
`default_nettype none
// Specification: docs/spec/dda_axis.md (the rule of one update), docs/spec/step_engine.md
// One DDA update, combinational: s = acc + d against the modulus M = m * 2^16; s >= M
// wraps down by M with a +1 request, s < 0 up by M with a -1 request. Used by dda_axis
// (once per clock, m = P) and by step_engine (once per visit, m = P / S), so the rule is
// written once. The caller keeps |d| < M and 0 <= acc < M, so at most one wrap happens
// and the result stays in [0, M).
//
// acc + d, acc + d - M and acc + d + M are formed side by side, then a choice: with
// AHEAD = 0 (dda_axis) from acc, d and m (each a three-input sum); with AHEAD = 1
// (step_engine, which forms acc - M and acc + M a clock ahead, in registers) as
// acc + d, (acc - M) + d and (acc + M) + d, three two-input sums, one carry chain each.
module dda_step #(
    parameter M_W   = 20,               // bits of m (the modulus's integer part)
    parameter AHEAD = 0                 // 1: acc - M and acc + M come in; 0: from m
) (
    input  wire [M_W+15:0] acc,         // the accumulator, in [0, M)
    input  wire [M_W+17:0] acc_minus_m, // AHEAD = 1: acc - M (two's complement)
    input  wire [M_W+17:0] acc_plus_m,  // AHEAD = 1: acc + M
    input  wire [M_W-1:0]  m,           // AHEAD = 0: M = m * 2^16
    input  wire [31:0]     inc,         // d, Q16.16 two's complement
    output wire [M_W+15:0] acc_next,    // s wrapped into [0, M)
    output wire            wrap_up,     // s >= M: a +1 request
    output wire            wrap_down,   // s < 0: a -1 request
    output wire [M_W+17:0] sum          // s itself (sign and carry bits included)
);

    localparam FRAC_BITS = 16;
    localparam ACC_W     = M_W + FRAC_BITS;
    localparam SUM_W     = ACC_W + 2;   // sign + one carry bit

    // The increment sign-extended (or, for the narrow proofs, truncated: |d| < M always
    // fits) to the sum's width.
    wire [SUM_W-1:0] inc_resized;
    generate
        if (SUM_W > 32) begin : widen
            assign inc_resized = {{(SUM_W-32){inc[31]}}, inc};
        end else if (SUM_W == 32) begin : same
            assign inc_resized = inc;
        end else begin : narrow
            assign inc_resized = inc[SUM_W-1:0];
            wire [31:0] unused_inc_top = {{SUM_W{1'b0}}, inc[31:SUM_W]};
        end
    endgenerate
    wire signed [SUM_W-1:0] acc_wide  = $signed({2'b00, acc});
    wire signed [SUM_W-1:0] sum_kept  = acc_wide + $signed(inc_resized);
    wire signed [SUM_W-1:0] sum_minus;
    wire signed [SUM_W-1:0] sum_plus;
    generate
        if (AHEAD != 0) begin : ahead
            assign sum_minus = $signed(acc_minus_m) + $signed(inc_resized);
            assign sum_plus  = $signed(acc_plus_m) + $signed(inc_resized);
            wire [M_W-1:0] unused_m = m;
        end else begin : here
            wire signed [SUM_W-1:0] modulus = {2'b00, m, {FRAC_BITS{1'b0}}};
            assign sum_minus = acc_wide + $signed(inc_resized) - modulus;
            assign sum_plus  = acc_wide + $signed(inc_resized) + modulus;
            wire [2*SUM_W-1:0] unused_ahead = {acc_minus_m, acc_plus_m};
        end
    endgenerate
    assign wrap_up   = !sum_minus[SUM_W-1];
    assign wrap_down = sum_kept[SUM_W-1];
    wire signed [SUM_W-1:0] sum_wrapped = wrap_up ? sum_minus : (wrap_down ? sum_plus : sum_kept);
    // The wrapped sum is in [0, M): its sign and carry bits are always zero.
    wire [1:0] unused_wrapped_top = sum_wrapped[SUM_W-1:ACC_W];
    assign acc_next = sum_wrapped[ACC_W-1:0];
    assign sum      = sum_kept;

endmodule

`default_nettype wire

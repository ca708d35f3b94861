`timescale 1ns / 1ps
`default_nettype none
// Specification: docs/spec/jog_generator.md ("Computation")
// The jog's velocity for the next period, computed sequentially in the 80 cycles after a
// period boundary (a period is thousands of clocks, so a serial multiplier, a
// digit-by-digit square root and one shared adder cost a few hundred cells instead of
// wide multipliers and parallel carry chains):
//   e = target - cmd
//   stopping:                        v' = clamp(0, vel - A, vel + A)
//   |e| <= min(VM, A), |e - vel| <= A: v' = e               (the last step, brakeable)
//   else u = max(isqrt(2 A min(|e|, 2^40 - 1)) - A, min(|e|, A))
//        v' = clamp(sign(e) min(VM, u), vel - A, vel + A)   (fastest speed that can stop)
// Inputs are sampled in the cycle after `restart`; `result_valid` is high in cycle 80
// after it, with `result`. A new `restart` or `drop` drops the computation in flight.
// `vel` is not copied: the caller holds it from the sample to the result (jog_generator's
// vel changes only at a boundary, a halt or an engagement, and each of them restarts or
// drops the computation, or finds none running); `busy` tells the caller's proof when.
//
// How it is computed (the same function, fewer carry chains). With m = min(|e|, 2^40 - 1)
// and s = sign(e):
// - isqrt(2 A m) < A + m (AM-GM), so u = m when m <= A, else u = max(root - A, A). In
//   particular |e| <= min(VM, A) gives sign(e) min(VM, u) = e, and then the clamp leaves
//   e exactly when |e - vel| <= A: the arrive branch is the general rule's special case.
// - The root only matters below VM + A < 2^32: a product 2 A m >= 2^64 saturates the
//   root at 2^32 - 1 (u > VM either way), so the root has 32 digits.
// - In the direction of e (w = s ? -vel : vel, speed = EN ? min(VM, u) : 0):
//   v' = vel + (s ? -c : c) with c = clamp(speed - w, -A, A).
// Datapath: P holds e's low 40 bits, then the product A m (radix-4 multiply, least
// significant digit first, digits -1..2 with a carry; |e|'s bits are formed serially as
// they are consumed, so no 48-bit negation); the square root reads P's bit pairs in
// place into a 33-bit remainder; one 34-bit adder (`acc`) forms m, compares it with A,
// shifts the root digits in, and runs the end in nine single-chain steps. Schedule
// (cycles after the restart): 1 sample; 2 m = |e| (32 bits) into acc; 3 m <= A;
// 2-22 multiply; 32-63 root digits; 64-72 the end; 80 result (acc).
module jog_velocity (
    // clock, reset
    input  wire        clk,
    input  wire        rst,
    // control
    input  wire        restart,
    input  wire        drop,
    // operands, sampled in the cycle after restart
    input  wire [47:0] distance,    // e = target - cmd
    input  wire [31:0] vel,
    input  wire        enable,
    input  wire [30:0] vmax,
    input  wire [30:0] accel,
    // state
    output wire        busy,        // a computation runs (vel must hold after its sample)
    // result
    output wire        result_valid,
    output wire [31:0] result
);

    localparam [6:0] SAMPLE_AT  = 7'd1;
    localparam [6:0] ABS_AT     = 7'd2;    // acc = |e| (low 32 bits)
    localparam [6:0] SMALL_AT   = 7'd3;    // small = m <= A
    localparam [6:0] CLEAR_AT   = 7'd4;    // acc = 0 unless small (the root's start)
    localparam [6:0] MUL_FIRST  = 7'd2;    // 21 radix-4 multiply steps: 2..22
    localparam [6:0] MUL_LAST   = 7'd22;
    localparam [6:0] PAIR_FIRST = 7'd32;   // the radicand's bit pairs, index ~step: 32..63
    localparam [6:0] PAIR_LAST  = 7'd63;
    localparam [6:0] SQRT_FIRST = 7'd33;   // 32 root digits: 33..64, folded into acc one step later
    localparam [6:0] SQRT_LAST  = 7'd64;
    localparam [6:0] FOLD_AT    = 7'd65;   // acc = 2 acc + the last digit     (root)
    localparam [6:0] U1_AT      = 7'd66;   // acc = root - 2A
    localparam [6:0] U2_AT      = 7'd67;   // acc = max(acc, 0) + A            (u)
    localparam [6:0] S1_AT      = 7'd68;   // acc = u - VM
    localparam [6:0] S2_AT      = 7'd69;   // acc = min(acc, 0) + VM, 0 if !EN (speed)
    localparam [6:0] D_AT       = 7'd70;   // acc = speed - w                  (d)
    localparam [6:0] C1_AT      = 7'd71;   // acc = d - A
    localparam [6:0] C2_AT      = 7'd72;   // acc = min(acc, 0) + 2A
    localparam [6:0] C3_AT      = 7'd73;   // acc = max(acc, 0) - A            (c)
    localparam [6:0] V_AT       = 7'd74;   // acc = vel + (s ? -c : c)         (v')
    localparam [6:0] RESULT_AT  = 7'd80;

    // The shared adder's operations (decoded one cycle ahead into ctl_reg).
    localparam [2:0] R_ZERO = 3'd0, R_A = 3'd1, R_2A = 3'd2, R_VM = 3'd3, R_VEL = 3'd4, R_E = 3'd5, R_ACC = 3'd6;
    localparam [1:0] L_ACC = 2'd0, L_ZERO = 2'd1, L_ZERO_IF_NEG = 2'd2, L_ZERO_IF_POS = 2'd3;   // POS: >= 0

    reg        busy_reg;
    reg [6:0]  step_reg;        // cycles since the restart
    // sampled operands (vel is held by the caller)
    reg        enable_reg;
    reg [30:0] vmax_reg;
    reg [30:0] accel_reg;
    reg        sign_reg;        // s = e < 0
    reg        sat_reg;         // |e| >= 2^40: m = 2^40 - 1
    reg        big_reg;         // |e| >= 2^31: m > A
    // the multiplier: serial |e|, the next digit and its carry, precomputed a step ahead
    reg        seen_reg;        // a one among e's bits consumed so far (two's complement negation)
    reg        dcarry_reg;      // the radix-4 recoding's carry into the next digit
    reg [1:0]  dsel_reg;        // this step's digit: 0, A, 2A or -A
    reg        small_reg;       // m <= A: u = m, kept in acc, no root
    // P: e's low 40 bits (and two zeros), then the product A m = {P_hi, P_lo}
    reg signed [32:0] p_hi_reg;
    reg [41:0]        p_lo_reg;
    // the root: remainder, the next bit pair, the last digit (root = {acc, digit})
    reg [32:0]        rem_reg;
    reg [1:0]         pair_reg;
    reg               digit_reg;
    // the shared adder's register (m, the root, the end, v') and its decoded operation
    reg signed [33:0] acc_reg;
    reg [1:0]         ctl_left_reg;
    reg               ctl_linv_reg;
    reg [2:0]         ctl_right_reg;
    reg               ctl_rinv_reg;
    reg [1:0]         ctl_cin_reg;     // 0, 1, the root digit
    reg               ctl_write_reg;
    reg               ctl_large_reg;   // write only unless small

    wire busy_at_mul  = busy_reg && step_reg >= MUL_FIRST && step_reg <= MUL_LAST;
    wire busy_at_pair = busy_reg && step_reg >= PAIR_FIRST && step_reg <= PAIR_LAST;
    wire busy_at_sqrt = busy_reg && step_reg >= SQRT_FIRST && step_reg <= SQRT_LAST;

    // |e| >= 2^40 and |e| >= 2^31 from the raw distance (two's complement: -2^n has |e| = 2^n).
    wire        d_neg     = distance[47];
    wire        d_sat     = d_neg ? !(&distance[46:40] && |distance[39:0]) : |distance[46:40];
    wire        d_big     = d_neg ? !(&distance[46:31] && |distance[30:0]) : |distance[46:31];

    // The multiplier's digit for a pair of e's raw bits: two bits of m (|e| formed
    // serially, all ones when saturated, zero past bit 39) plus the carry, recoded to a
    // digit -1, 0, 1 or 2 (3 = 4 - 1 and 4 carry one).
    function [3:0] recode;   // {seen after, carry out, digit select}
        input [1:0] raw;
        input       seen, neg, sat, tail, carry;
        reg         n0, n1;
        reg [2:0]   value;
        begin
            n0    = !tail && (sat || (raw[0] ^ (neg && seen)));
            n1    = !tail && (sat || (raw[1] ^ (neg && (seen || raw[0]))));
            value = {1'b0, n1, n0} + {2'b00, carry};
            recode[3] = seen || raw[0] || raw[1];
            recode[2] = value[2] || (value == 3'd3);
            recode[1:0] = (value == 3'd1) ? 2'd1 : (value == 3'd2) ? 2'd2 : (value == 3'd3) ? 2'd3 : 2'd0;
        end
    endfunction
    wire [3:0]  first_digit = recode(distance[1:0], 1'b0, d_neg, d_sat, 1'b0, 1'b0);
    wire [3:0]  next_digit  = recode(p_lo_reg[3:2], seen_reg, sign_reg, sat_reg, step_reg == MUL_LAST - 7'd1,
                                     dcarry_reg);
    wire [33:0] a34         = {3'd0, accel_reg};
    wire [33:0] a2_34       = {a34[32:0], 1'b0};
    wire [33:0] mul_addend  = (dsel_reg == 2'd1) ? a34 : (dsel_reg == 2'd2) ? a2_34 : (dsel_reg == 2'd3) ? ~a34 : 34'd0;
    wire [33:0] mul_sum     = {p_hi_reg[32], p_hi_reg} + mul_addend + {33'd0, dsel_reg == 2'd3};

    // One root digit from the bit pair (registered a step ahead) of the radicand
    // 2 A m = {P[62:0], 0}; a product 2 A m >= 2^64 saturates the root at 2^32 - 1.
    wire [63:0] radicand    = {p_hi_reg[20:0], p_lo_reg, 1'b0};
    wire [4:0]  pair_index  = ~step_reg[4:0];
    wire [1:0]  pair        = radicand[{pair_index, 1'b1} -: 2];
    wire        root_sat    = |p_hi_reg[32:21];
    wire [34:0] rem_shifted = {rem_reg, pair_reg};
    wire [34:0] trial       = {1'b0, acc_reg[30:0], digit_reg, 2'b01};
    wire [35:0] rem_diff    = {1'b0, rem_shifted} - {1'b0, trial};
    wire        root_fits   = !rem_diff[35];

    // The shared adder: acc <= left + right + carry, one chain per step.
    function [10:0] decode;  // {left, linv, right, rinv, cin, write, large}
        input [6:0] step;
        input       neg, en;
        begin
            case (step)
                ABS_AT:   decode = {L_ZERO,        1'b0, R_E,    neg,  1'b0, neg,  1'b1, 1'b0};
                SMALL_AT: decode = {L_ACC,         1'b0, R_A,    1'b1, 2'd0,       1'b0, 1'b0};
                CLEAR_AT: decode = {L_ZERO,        1'b0, R_ZERO, 1'b0, 2'd0,       1'b1, 1'b1};
                FOLD_AT:  decode = {L_ACC,         1'b0, R_ACC,  1'b0, 2'd2,       1'b1, 1'b1};
                U1_AT:    decode = {L_ACC,         1'b0, R_2A,   1'b1, 2'd1,       1'b1, 1'b1};
                U2_AT:    decode = {L_ZERO_IF_NEG, 1'b0, R_A,    1'b0, 2'd0,       1'b1, 1'b1};
                S1_AT:    decode = {L_ACC,         1'b0, R_VM,   1'b1, 2'd1,       1'b1, 1'b0};
                S2_AT:    decode = {en ? L_ZERO_IF_POS : L_ZERO, 1'b0, en ? R_VM : R_ZERO, 1'b0, 2'd0, 1'b1, 1'b0};
                D_AT:     decode = {L_ACC,         1'b0, R_VEL,  !neg, 1'b0, !neg, 1'b1, 1'b0};
                C1_AT:    decode = {L_ACC,         1'b0, R_A,    1'b1, 2'd1,       1'b1, 1'b0};
                C2_AT:    decode = {L_ZERO_IF_POS, 1'b0, R_2A,   1'b0, 2'd0,       1'b1, 1'b0};
                C3_AT:    decode = {L_ZERO_IF_NEG, 1'b0, R_A,    1'b1, 2'd1,       1'b1, 1'b0};
                V_AT:     decode = {L_ACC,         neg,  R_VEL,  1'b0, 1'b0, neg,  1'b1, 1'b0};
                default:  decode = {L_ACC,         1'b0, R_ACC,  1'b0, 2'd2, step >= SQRT_FIRST && step <= SQRT_LAST, 1'b1};
            endcase
        end
    endfunction
    // The operation of the next step: a restart's is SAMPLE_AT's, a constant, chosen after
    // the decode of step + 1, so the restart (the period boundary through the jog's
    // disengage decision, late in the clock) reaches the control registers through one
    // multiplexer, not through the decoder (the ECP5 board build's critical path, seed 2).
    localparam [10:0] CTL_SAMPLE = decode(SAMPLE_AT, 1'b0, 1'b0);
    wire        sign_now  = (step_reg == SAMPLE_AT) ? d_neg : sign_reg;   // the sign is sampled as ABS_AT is decoded
    wire [10:0] ctl_next  = restart ? CTL_SAMPLE : decode(step_reg + 7'd1, sign_now, enable_reg);

    wire        acc_neg   = acc_reg[33];
    wire        left_zero = (ctl_left_reg == L_ZERO) || (ctl_left_reg == L_ZERO_IF_NEG && acc_neg) ||
                            (ctl_left_reg == L_ZERO_IF_POS && !acc_neg);
    wire [33:0] alu_left  = left_zero ? 34'd0 : ctl_linv_reg ? ~acc_reg : acc_reg;
    reg  [33:0] right_src;
    always @(*) begin
        case (ctl_right_reg)
            R_A:     right_src = a34;
            R_2A:    right_src = a2_34;
            R_VM:    right_src = {3'd0, vmax_reg};
            R_VEL:   right_src = {{2{vel[31]}}, vel};
            R_E:     right_src = {{2{sign_reg}}, p_lo_reg[31:0]};
            R_ACC:   right_src = acc_reg;
            default: right_src = 34'd0;
        endcase
    end
    wire [33:0] alu_right = ctl_rinv_reg ? ~right_src : right_src;
    wire        alu_cin   = ctl_cin_reg[1] ? digit_reg : ctl_cin_reg[0];
    wire [33:0] alu_sum   = alu_left + alu_right + {33'd0, alu_cin};
    wire        acc_write = busy_reg && ctl_write_reg && !(ctl_large_reg && small_reg);

    always @(posedge clk) begin
        if (busy_reg) step_reg <= step_reg + 7'd1;
        {ctl_left_reg, ctl_linv_reg, ctl_right_reg, ctl_rinv_reg, ctl_cin_reg, ctl_write_reg, ctl_large_reg} <= ctl_next;
        if (busy_reg && step_reg == SAMPLE_AT) begin
            enable_reg <= enable;
            vmax_reg   <= vmax;
            accel_reg  <= accel;
            sign_reg   <= d_neg;
            sat_reg    <= d_sat;
            big_reg    <= d_big;
            seen_reg   <= first_digit[3];
            dcarry_reg <= first_digit[2];
            dsel_reg   <= first_digit[1:0];
            p_hi_reg   <= 33'sd0;
            p_lo_reg   <= {2'b00, distance[39:0]};
            rem_reg    <= 33'd0;
            digit_reg  <= 1'b0;
        end
        if (busy_at_mul) begin
            seen_reg   <= next_digit[3];
            dcarry_reg <= next_digit[2];
            dsel_reg   <= next_digit[1:0];
            p_hi_reg   <= {mul_sum[33], mul_sum[33:2]};
            p_lo_reg   <= {mul_sum[1:0], p_lo_reg[41:2]};
        end
        if (busy_reg && step_reg == SMALL_AT) small_reg <= !big_reg && !acc_neg && alu_sum[33];
        if (busy_at_pair) pair_reg <= pair;
        if (busy_at_sqrt) begin
            rem_reg   <= root_fits ? rem_diff[32:0] : rem_shifted[32:0];
            digit_reg <= root_sat || root_fits;
        end
        if (acc_write) acc_reg <= alu_sum;
        if (busy_reg && step_reg == RESULT_AT) busy_reg <= 1'b0;
        if (restart) begin
            busy_reg <= 1'b1;
            step_reg <= SAMPLE_AT;
        end
        if (drop) busy_reg <= 1'b0;
        if (rst) begin
            busy_reg   <= 1'b0;
            step_reg   <= 7'd0;
            enable_reg <= 1'b0;
            vmax_reg   <= 31'd0;
            accel_reg  <= 31'd0;
            sign_reg   <= 1'b0;
            sat_reg    <= 1'b0;
            big_reg    <= 1'b0;
            seen_reg   <= 1'b0;
            dcarry_reg <= 1'b0;
            dsel_reg   <= 2'd0;
            small_reg  <= 1'b0;
            p_hi_reg   <= 33'sd0;
            p_lo_reg   <= 42'd0;
            rem_reg    <= 33'd0;
            pair_reg   <= 2'd0;
            digit_reg  <= 1'b0;
            acc_reg    <= 34'sd0;
            {ctl_left_reg, ctl_linv_reg, ctl_right_reg, ctl_rinv_reg, ctl_cin_reg, ctl_write_reg, ctl_large_reg} <= 11'd0;
        end
    end

    assign result_valid = busy_reg && (step_reg == RESULT_AT) && !restart && !drop;
    assign result       = acc_reg[31:0];
    assign busy         = busy_reg;
    wire unused = &{1'b0, rem_diff[34:33], acc_reg[33:32], p_lo_reg[1:0], mul_sum[33]};

`ifdef FORMAL
    // Whatever the root digits and the product are, the result changes the velocity by
    // at most A and is no faster than max(VM, |vel|) (all as sampled): the jog's limits
    // hold by the end's clamp, not by the square root being right (the co-simulation
    // checks that against the model's exact integer square root). Each step of the end
    // is proven to keep acc within the bounds its stage computes from the sampled
    // operands, which stay put while the computation runs; the decoded operation is the
    // one of the current step. A result comes only in cycle 80. (No cover: reaching a
    // result takes 80 cycles of BMC; the co-simulation runs thousands.)
    reg f_past_valid;
    initial f_past_valid = 1'b0;
    initial assume (rst);
    always @(posedge clk) f_past_valid <= 1'b1;
    wire signed [35:0] f_acc   = {{2{acc_reg[33]}}, acc_reg};
    wire signed [35:0] f_a     = {5'd0, accel_reg};
    wire signed [35:0] f_vm    = {5'd0, vmax_reg};
    wire signed [35:0] f_vel   = {{4{vel[31]}}, vel};
    wire signed [35:0] f_w     = sign_reg ? -f_vel : f_vel;           // vel in the direction of e
    wire signed [35:0] f_absw  = f_w[35] ? -f_w : f_w;
    wire signed [35:0] f_t     = f_acc - f_a;
    wire signed [35:0] f_cw    = f_acc + f_w;
    wire signed [35:0] f_abscw = f_cw[35] ? -f_cw : f_cw;
    wire signed [35:0] f_step  = f_acc - f_vel;
    wire signed [35:0] f_absv  = f_acc[35] ? -f_acc : f_acc;
    always @(*) if (f_past_valid && !rst && busy_reg) begin
        assert (step_reg >= SAMPLE_AT && step_reg <= RESULT_AT);
        assert ({ctl_left_reg, ctl_linv_reg, ctl_right_reg, ctl_rinv_reg, ctl_cin_reg, ctl_write_reg, ctl_large_reg} ==
                decode(step_reg, sign_reg, enable_reg));
        if (step_reg > SAMPLE_AT && step_reg <= SQRT_FIRST) assert (!digit_reg);
        if (step_reg > SMALL_AT && step_reg <= S1_AT && small_reg) assert (f_acc >= 0 && f_acc <= f_a);
        if (step_reg > CLEAR_AT && step_reg <= SQRT_FIRST + 7'd1 && !small_reg) assert (acc_reg == 34'sd0);
        if (step_reg > SQRT_FIRST + 7'd1 && step_reg <= U1_AT && !small_reg)
            assert ((acc_reg >> (step_reg - SQRT_FIRST - 7'd1)) == 34'sd0);
        if (step_reg == U2_AT && !small_reg) assert (f_acc < 36'sh1_0000_0000 && f_acc >= -36'sh1_0000_0000);
        if (step_reg == S1_AT) assert (f_acc >= 0 && f_acc < 36'sh2_0000_0000);
        if (step_reg == S2_AT) assert (f_acc >= -f_vm && f_acc < 36'sh2_0000_0000);
        if (step_reg == D_AT) assert (f_acc >= 0 && f_acc <= f_vm && (enable_reg || f_acc == 0));
        if (step_reg == C1_AT) assert (f_cw >= 0 && f_cw <= f_vm);
        if (step_reg == C2_AT) assert (f_cw + f_a >= 0 && f_cw + f_a <= f_vm);
        if (step_reg == C3_AT) assert (f_t <= f_a && f_t + f_w <= f_vm && (f_t == f_a || f_t + f_w >= 0));
        if (step_reg == V_AT) assert (f_acc >= -f_a && f_acc <= f_a && (f_abscw <= f_vm || f_abscw <= f_absw));
        if (step_reg > V_AT) begin
            assert (f_step <= f_a && f_step >= -f_a);
            assert (f_absv <= f_vm || f_absv <= f_absw);
            assert (acc_reg == {{2{acc_reg[31]}}, acc_reg[31:0]});
        end
    end
    always @(*) if (f_past_valid && !rst && result_valid) assert (busy_reg && step_reg == RESULT_AT);
    // The caller holds vel from the sample (step SAMPLE_AT) to the result
    // (jog_generator's proof asserts it).
    always @(posedge clk) if (f_past_valid && !$past(rst) && !rst && busy_reg && step_reg > SAMPLE_AT)
        assume ($stable(vel));
    always @(posedge clk) if (f_past_valid && !$past(rst) && !rst) begin
        if ($past(restart) && !$past(drop)) assert (busy_reg && step_reg == SAMPLE_AT);
        if (busy_reg && step_reg > SAMPLE_AT + 7'd1) begin
            assert ($stable(accel_reg) && $stable(vmax_reg) && $stable(enable_reg) &&
                    $stable(sign_reg) && $stable(sat_reg) && $stable(big_reg));
            if (step_reg > SMALL_AT + 7'd1) assert ($stable(small_reg));
        end
    end
`endif

endmodule

`default_nettype wire

`timescale 1ns / 1ps
`default_nettype none
// Specification: docs/spec/step_serial.md
// Digit-serial step engine: one DDA and one step shaper visiting the axes in turn, as
// step_engine, but every per-axis word (the DDA accumulator, the position, the shaper's
// two counters) is a circulating shift register of flip-flops (no RAM: the MAX II has
// none) that passes a DIGIT-bit adder, DIGIT bits a clock. A visit takes a word's length,
// Q = 32 / DIGIT clocks; S = 2^SL slots (one per axis, as step_engine) make a round of
// R = S * Q clocks, and each axis has a DDA visit (slot a) and a shaper visit (slot
// a + 1 mod S) per round. The rules are dda_axis's and step_shaper's once per visit:
// the DDA's modulus is V = P / R visits, the counters count visits (cnt * R >= timing).
//
// The per-digit datapath: the accumulator ring holds s (the sum before its wrap, mod
// 2^32) and a 2-bit wrap per axis; the next visit takes acc = s - wrap * M first (one
// adder), adds d (a second) and compares the sum against M (a borrow chain); the wrap
// and the request are known at the visit's last digit, so the shaper of the axis
// decides at the first clock of its visit in the next slot. The shaper's compares of a
// counter against a timing are made while the counter's next value streams past and
// kept as flags for the next visit, so every decision is taken at a visit's first clock
// from flip-flops. Per-axis flags ride in S-entry rings that advance once a slot; the
// pins, the sticky flags and the enables are flip-flops per axis. The position leaves
// as a digit stream (pos_digit), not as a parallel word.
//
// Latency: a DDA visit in slot n gives the shaper's decision at the first clock of slot
// n + 1 and the pin edge at the end of that clock.
module step_serial #(
    parameter N_AXES   = 4,
    parameter P_WIDTH  = 20,
    parameter TIMING_W = 12,
    parameter DIGIT    = 4
) (
    // clock, reset
    input  wire                       clk,
    input  wire                       rst,
    // from the period timer
    input  wire                       run,             // the period timer runs (run && active)
    input  wire [P_WIDTH-1:0]         p_active,        // period of the running move, a multiple of R
    input  wire [32*N_AXES-1:0]       inc,             // Q16.16 steps per period, per axis
    output wire                       start_ok,        // phase == R - 2: a run may start now
    // per-axis configuration
    input  wire [N_AXES-1:0]          axis_enable,
    input  wire [TIMING_W*N_AXES-1:0] step_len,
    input  wire [TIMING_W*N_AXES-1:0] step_space,
    input  wire [TIMING_W*N_AXES-1:0] dir_setup,
    input  wire [TIMING_W*N_AXES-1:0] dir_hold,
    input  wire [2*N_AXES-1:0]        out_mode,
    input  wire [3*N_AXES-1:0]        invert,
    input  wire                       clear_errors,
    input  wire                       halt,
    // pins and status
    output wire [N_AXES-1:0]          pin_a,
    output wire [N_AXES-1:0]          pin_b,
    output wire [N_AXES-1:0]          pin_en,
    output wire [N_AXES-1:0]          rate_error,
    output wire [N_AXES-1:0]          step_lost,
    // the positions, a digit a clock: digit pos_index of axis pos_axis's position
    output wire [DIGIT-1:0]           pos_digit,
    output wire [7:0]                 pos_index,
    output wire [2:0]                 pos_axis
);

`include "finestep_interface.vh"

    localparam SL      = (N_AXES <= 2) ? 1 : ((N_AXES <= 4) ? 2 : 3);
    localparam S       = 1 << SL;
    localparam D       = DIGIT;
    localparam DL      = (DIGIT == 1) ? 0 : ((DIGIT == 2) ? 1 : ((DIGIT == 4) ? 2 : 3));
    localparam QL      = 5 - DL;                 // log2 of the clocks of a visit
    localparam Q       = 1 << QL;
    localparam LR      = SL + QL;                // log2 of the round R
    localparam HQ      = Q / 2;                  // clocks of a counter (half a word)
    localparam V_W     = P_WIDTH - LR;           // bits of the visits per period
    localparam PEND_W  = 8;
    // Per-axis shaper flags: init, pending, level, dir, quad, and the compares and
    // saturations of the counters' values the last visit left.
    localparam E_INIT  = 0;
    localparam E_PEND  = 1;
    localparam E_LEVEL = E_PEND + PEND_W;
    localparam E_DIR   = E_LEVEL + 1;
    localparam E_QUAD  = E_DIR + 1;
    localparam E_LEN   = E_QUAD + 2;             // cnt * R >= step_len
    localparam E_SPACE = E_LEN + 1;              // cnt * R >= step_space
    localparam E_HOLD  = E_SPACE + 1;            // cnt * R >= dir_hold
    localparam E_SETUP = E_HOLD + 1;             // dcnt * R >= dir_setup
    localparam E_CFULL = E_SETUP + 1;            // cnt saturated
    localparam E_DFULL = E_CFULL + 1;            // dcnt saturated
    localparam E_W     = E_DFULL + 1;
    localparam [LR-1:0] PHASE_ONE = {{(LR-1){1'b0}}, 1'b1};
    localparam [D-1:0]  DIGIT_ONE = {{(D-1){1'b0}}, 1'b1};

    // Elaboration checks: the digit divides 32 into a power of two; a counter fits half
    // a word; V < 2^15 so that M = V * 2^16 < 2^31.
    generate
        if (!(DIGIT == 1 || DIGIT == 2 || DIGIT == 4 || DIGIT == 8)) begin : bad_digit
            step_serial_digit_must_be_1_2_4_or_8 error();
        end
        if (TIMING_W > 16 || TIMING_W <= LR) begin : bad_timing
            step_serial_timing_w_must_be_above_lr_and_at_most_16 error();
        end
        if (V_W > 15 || V_W < 1) begin : bad_period
            step_serial_p_width_minus_lr_must_be_1_to_15 error();
        end
    endgenerate

    // ---- Schedule --------------------------------------------------------------------
    reg  [LR-1:0] phase_reg;                        // {slot, digit}
    wire [QL-1:0] j       = phase_reg[QL-1:0];
    wire [SL-1:0] slot    = phase_reg[LR-1:QL];
    wire          first   = (j == {QL{1'b0}});
    wire          last    = (j == {QL{1'b1}});
    wire          c_end   = (j == HQ - 1);         // the last digit of the counter cnt
    wire          c_half  = j[QL-1];               // 0: cnt's digits, 1: dcnt's
    wire [QL-2:0] k       = j[QL-2:0];             // the digit within the counter
    wire          k_first = (k == {(QL-1){1'b0}});
    wire [SL-1:0] sh_axis = slot - {{(SL-1){1'b0}}, 1'b1};
    wire dda_visit = ({{(32-SL){1'b0}}, slot} < N_AXES);
    wire sh_visit  = ({{(32-SL){1'b0}}, sh_axis} < N_AXES);
    assign start_ok = (phase_reg == {LR{1'b1}} - PHASE_ONE);   // R - 2

    always @(posedge clk) begin
        phase_reg <= rst ? {LR{1'b0}} : phase_reg + PHASE_ONE;
    end

    // Inputs padded to S axes, so an idle slot selects zeros.
    wire [32*S-1:0]       inc_all   = {{(32*(S-N_AXES)){1'b0}}, inc};
    wire [TIMING_W*S-1:0] len_all   = {{(TIMING_W*(S-N_AXES)){1'b0}}, step_len};
    wire [TIMING_W*S-1:0] space_all = {{(TIMING_W*(S-N_AXES)){1'b0}}, step_space};
    wire [TIMING_W*S-1:0] setup_all = {{(TIMING_W*(S-N_AXES)){1'b0}}, dir_setup};
    wire [TIMING_W*S-1:0] hold_all  = {{(TIMING_W*(S-N_AXES)){1'b0}}, dir_hold};
    wire [2*S-1:0]        mode_all  = {{(2*(S-N_AXES)){1'b0}}, out_mode};
    wire [3*S-1:0]        inv_all   = {{(3*(S-N_AXES)){1'b0}}, invert};

    // ---- DDA visit (slot a): s = (acc_ring - wrap * M) + d, compared with M -------------
    wire [LR-1:0] unused_p_low = p_active[LR-1:0];
    wire [31:0] m_word    = {{(16-V_W){1'b0}}, p_active[P_WIDTH-1:LR], 16'd0};
    wire [31:0] half_word = {1'b0, m_word[31:1]};
    wire [D-1:0] m_dig    = m_word[D*j +: D];
    wire [D-1:0] half_dig = half_word[D*j +: D];
    wire [D-1:0] d_dig    = inc_all[D*phase_reg +: D];   // 32 * slot + D * j

    reg  [32*S-1:0] acc_ring;          // s of each axis, digit 0 of the visited one at [D-1:0]
    reg  [S-1:0]    live_ring;         // per axis: its last DDA visit ran (entry 0: this slot's)
    reg  [S-1:0]    wrap_up_ring;      // per axis: its last s >= M
    reg  [S-1:0]    wrap_down_ring;    // per axis: its last s < 0
    reg             run_v_reg;         // run at this visit's first clock
    reg             live_v_reg;        // the visit continues its axis's accumulator
    reg             live_w_reg;        // run has stayed 1 since the first clock
    reg             cy1_reg, cy2_reg, cy3_reg;
    wire run_v  = first ? run : run_v_reg;
    wire live_v = first ? (run && live_ring[0]) : live_v_reg;
    wire up_v   = live_v && wrap_up_ring[0];
    wire down_v = live_v && wrap_down_ring[0];
    // acc = s - wrap * M (mod 2^32), or M/2 at the first running visit.
    wire [D-1:0] op1 = live_v ? acc_ring[D-1:0] : half_dig;
    wire [D-1:0] op2 = up_v ? ~m_dig : (down_v ? m_dig : {D{1'b0}});
    wire [D:0]   sum1 = {1'b0, op1} + {1'b0, op2} + {{D{1'b0}}, first ? up_v : cy1_reg};
    // s = acc + d; the 33rd bit of s at the last digit is carry ^ sign of d.
    wire [D:0]   sum2 = {1'b0, sum1[D-1:0]} + {1'b0, d_dig} + {{D{1'b0}}, first ? 1'b0 : cy2_reg};
    // s - M, as s + ~M + 1: its carry out of bit 31.
    wire [D:0]   sum3 = {1'b0, sum2[D-1:0]} + {1'b0, ~m_dig} + {{D{1'b0}}, first ? 1'b1 : cy3_reg};
    wire s_neg  = sum2[D] ^ d_dig[D-1];                  // at the last digit: s < 0
    wire s_ge_m = s_neg ^ sum3[D];                       // at the last digit: s >= M
    wire live_new = (first ? run : live_w_reg) && run;

    always @(posedge clk) begin
        acc_ring <= {sum2[D-1:0], acc_ring[32*S-1:D]};
        cy1_reg  <= sum1[D];
        cy2_reg  <= sum2[D];
        cy3_reg  <= sum3[D];
        if (first) begin
            run_v_reg  <= run;
            live_v_reg <= run && live_ring[0];
        end
        live_w_reg <= live_new;
        if (last) begin
            live_ring      <= {live_new, live_ring[S-1:1]};
            wrap_up_ring   <= {s_ge_m, wrap_up_ring[S-1:1]};
            wrap_down_ring <= {s_neg, wrap_down_ring[S-1:1]};
        end
        if (!run) live_ring <= {S{1'b0}};
        if (rst) begin
            live_ring      <= {S{1'b0}};
            wrap_up_ring   <= {S{1'b0}};
            wrap_down_ring <= {S{1'b0}};
        end
    end

    // The visit's request, for the shaper visit of the same axis in the next slot.
    reg req_valid_reg;
    reg req_negative_reg;
    always @(posedge clk) begin
        if (last) begin
            req_valid_reg    <= dda_visit && run_v && (s_ge_m || s_neg);
            req_negative_reg <= s_neg;
        end
        if (rst) begin
            req_valid_reg    <= 1'b0;
            req_negative_reg <= 1'b0;
        end
    end

    // ---- Shaper visit (slot a + 1) ---------------------------------------------------
    reg  [E_W*S-1:0] sh_ring;      // per axis, entry 0: this slot's shaper axis
    wire [E_W-1:0]   sh_reset = {6'b111111, 2'b00, 1'b1, 1'b0, {PEND_W{1'b0}}, 1'b0};
    wire [E_W-1:0]   sh_cur   = sh_ring[E_INIT] ? sh_ring[E_W-1:0] : sh_reset;
    wire [PEND_W-1:0] pending = sh_cur[E_PEND +: PEND_W];
    wire              level   = sh_cur[E_LEVEL];
    wire              dir     = sh_cur[E_DIR];
    wire [1:0]        quad    = sh_cur[E_QUAD +: 2];

    wire rise, fall, dir_change, clamp_high, clamp_low, behind;
    wire [PEND_W-1:0] pending_next;
    shaper_step decide (
        .pending(pending), .level(level), .dir(dir),
        .req_valid(req_valid_reg), .req_negative(req_negative_reg), .halt(halt),
        .len_reached(sh_cur[E_LEN]), .space_reached(sh_cur[E_SPACE]),
        .setup_reached(sh_cur[E_SETUP]), .hold_reached(sh_cur[E_HOLD]),
        .rise(rise), .fall(fall), .dir_change(dir_change), .pending_next(pending_next),
        .clamp_high(clamp_high), .clamp_low(clamp_low), .behind(behind)
    );
    wire       level_next = rise ? 1'b1 : (fall ? 1'b0 : level);
    wire       dir_next   = dir_change ? !dir : dir;
    wire [1:0] quad_next  = rise ? quad + {!dir, 1'b1} : quad;

    // The decisions, held for the visit's later digits.
    reg rise_reg, dir_old_reg, cnt_one_reg, dcnt_one_reg, cfull_reg, dfull_reg, init_reg;
    wire rise_v     = first ? rise : rise_reg;
    wire dir_old_v  = first ? dir : dir_old_reg;
    wire cnt_one_v  = first ? (rise || fall) : cnt_one_reg;
    wire dcnt_one_v = first ? dir_change : dcnt_one_reg;
    wire cfull_v    = first ? sh_cur[E_CFULL] : cfull_reg;
    wire dfull_v    = first ? sh_cur[E_DFULL] : dfull_reg;
    wire init_v     = first ? sh_ring[E_INIT] : init_reg;

    // Position: + (rise ? (dir ? 1 : -1) : 0), a digit a clock.
    reg  [32*S-1:0] pos_ring;
    reg             cyp_reg;
    wire [D-1:0] pos_old = init_v ? pos_ring[D-1:0] : {D{1'b0}};
    wire [D-1:0] pos_add = !rise_v ? {D{1'b0}} : (dir_old_v ? (first ? DIGIT_ONE : {D{1'b0}}) : {D{1'b1}});
    wire [D:0]   pos_sum = {1'b0, pos_old} + {1'b0, pos_add} + {{D{1'b0}}, first ? 1'b0 : cyp_reg};

    // Counters: cnt in bits [0, 16) of the word, dcnt in [16, 32), each TIMING_W bits.
    reg  [32*S-1:0] cnt_ring;
    reg             cyc_reg;
    wire [15:0]  count_max = {{(16-TIMING_W){1'b0}}, {TIMING_W{1'b1}}};
    wire [D-1:0] max_dig   = count_max[D*k +: D];
    wire [D-1:0] cnt_old   = init_v ? cnt_ring[D-1:0] : max_dig;
    wire         to_one    = c_half ? dcnt_one_v : cnt_one_v;
    wire         hold_max  = c_half ? dfull_v : cfull_v;
    wire [D:0]   cnt_inc   = {1'b0, cnt_old} + {{D{1'b0}}, k_first ? 1'b1 : cyc_reg};
    wire [D-1:0] cnt_new   = to_one ? (k_first ? DIGIT_ONE : {D{1'b0}}) :
                             (hold_max ? cnt_old : cnt_inc[D-1:0]);
    // Saturation: every counter bit of the new value is 1.
    wire         cnt_ones  = &(cnt_new | ~max_dig);
    reg          ones_reg;
    wire         ones_all  = cnt_ones && (k_first || ones_reg);

    // Compares cnt * R >= X, i.e. cnt >= (X >> LR) + (X mod R != 0): a borrow chain each.
    wire [TIMING_W-1:0] len_x   = len_all[TIMING_W*sh_axis +: TIMING_W];
    wire [TIMING_W-1:0] space_x = space_all[TIMING_W*sh_axis +: TIMING_W];
    wire [TIMING_W-1:0] setup_x = setup_all[TIMING_W*sh_axis +: TIMING_W];
    wire [TIMING_W-1:0] hold_x  = hold_all[TIMING_W*sh_axis +: TIMING_W];
    wire [TIMING_W-1:0] cmp_a_x = c_half ? setup_x : len_x;     // dcnt against dir_setup
    wire [15:0] ya = {{(16-TIMING_W+LR){1'b0}}, cmp_a_x[TIMING_W-1:LR]};
    wire [15:0] yb = {{(16-TIMING_W+LR){1'b0}}, space_x[TIMING_W-1:LR]};
    wire [15:0] yc = {{(16-TIMING_W+LR){1'b0}}, hold_x[TIMING_W-1:LR]};
    reg          cya_reg, cyb_reg, cyc2_reg;
    wire [D:0]   cmp_a = {1'b0, cnt_new} + {1'b0, ~ya[D*k +: D]} +
                         {{D{1'b0}}, k_first ? (cmp_a_x[LR-1:0] == {LR{1'b0}}) : cya_reg};
    wire [D:0]   cmp_b = {1'b0, cnt_new} + {1'b0, ~yb[D*k +: D]} +
                         {{D{1'b0}}, k_first ? (space_x[LR-1:0] == {LR{1'b0}}) : cyb_reg};
    wire [D:0]   cmp_c = {1'b0, cnt_new} + {1'b0, ~yc[D*k +: D]} +
                         {{D{1'b0}}, k_first ? (hold_x[LR-1:0] == {LR{1'b0}}) : cyc2_reg};
    reg          len_new_reg, space_new_reg, hold_new_reg, cfull_new_reg;

    // Pin functions of the state the visit leaves.
    wire [1:0] mode_cur = mode_all[2*sh_axis +: 2];
    wire [2:0] inv_cur  = inv_all[3*sh_axis +: 3];
    reg a_next, b_next;
    always @* begin
        case (mode_cur)
            FS_OUT_MODE_UP_DOWN: begin
                a_next = level_next && dir_next;
                b_next = level_next && !dir_next;
            end
            FS_OUT_MODE_QUADRATURE: begin
                a_next = quad_next[0] ^ quad_next[1];
                b_next = quad_next[1];
            end
            default: begin
                a_next = level_next;
                b_next = dir_next;
            end
        endcase
    end

    wire [E_W-1:0] head_first = {sh_cur[E_DFULL], sh_cur[E_CFULL], sh_cur[E_SETUP], sh_cur[E_HOLD],
                                 sh_cur[E_SPACE], sh_cur[E_LEN], quad_next, dir_next, level_next,
                                 pending_next, 1'b1};
    wire [E_W-1:0] head_last  = {ones_all, cfull_new_reg, cmp_a[D], hold_new_reg, space_new_reg,
                                 len_new_reg, sh_ring[E_QUAD +: 2], sh_ring[E_DIR], sh_ring[E_LEVEL],
                                 sh_ring[E_PEND +: PEND_W], sh_ring[E_INIT]};

    reg [D-1:0] pos_digit_reg;
    reg [7:0]   pos_index_reg;
    reg [2:0]   pos_axis_reg;
    always @(posedge clk) begin
        pos_ring <= {pos_sum[D-1:0], pos_ring[32*S-1:D]};
        cnt_ring <= {cnt_new, cnt_ring[32*S-1:D]};
        cyp_reg  <= pos_sum[D];
        cyc_reg  <= cnt_inc[D];
        ones_reg <= ones_all;
        cya_reg  <= cmp_a[D];
        cyb_reg  <= cmp_b[D];
        cyc2_reg <= cmp_c[D];
        if (c_end) begin
            len_new_reg   <= cmp_a[D];
            space_new_reg <= cmp_b[D];
            hold_new_reg  <= cmp_c[D];
            cfull_new_reg <= ones_all;
        end
        if (first) begin
            rise_reg     <= rise;
            dir_old_reg  <= dir;
            cnt_one_reg  <= rise || fall;
            dcnt_one_reg <= dir_change;
            cfull_reg    <= sh_cur[E_CFULL];
            dfull_reg    <= sh_cur[E_DFULL];
            init_reg     <= sh_ring[E_INIT];
            if (sh_visit) sh_ring[E_W-1:0] <= head_first;
        end
        if (last) sh_ring <= {head_last, sh_ring[E_W*S-1:E_W]};
        pos_digit_reg <= sh_visit ? pos_sum[D-1:0] : {D{1'b0}};
        pos_index_reg <= {{(8-QL){1'b0}}, j};
        pos_axis_reg  <= {{(3-SL){1'b0}}, sh_axis};
        if (rst) begin
            sh_ring       <= {E_W*S{1'b0}};
            pos_digit_reg <= {D{1'b0}};
            pos_index_reg <= 8'd0;
            pos_axis_reg  <= 3'd0;
        end
    end

    // ---- Per-axis flip-flops: flags and pins -----------------------------------------
    reg [N_AXES-1:0] rate_error_reg;
    reg [N_AXES-1:0] step_lost_reg;
    reg [N_AXES-1:0] pin_a_reg;
    reg [N_AXES-1:0] pin_b_reg;
    reg [N_AXES-1:0] pin_en_reg;
    wire [N_AXES-1:0] sh_hot;      // the shaper's axis one-hot (none in an idle slot)
    genvar h;
    generate
        for (h = 0; h < N_AXES; h = h + 1) begin : hot
            assign sh_hot[h] = ({{(32-SL){1'b0}}, sh_axis} == h);
        end
    endgenerate
    integer a;
    always @(posedge clk) begin
        for (a = 0; a < N_AXES; a = a + 1) begin
            pin_en_reg[a] <= (axis_enable[a] && !halt) ^ invert[FS_INVERT_WIDTH*a + FS_INVERT_PIN_EN_BIT];
            if (first && sh_hot[a] && behind) rate_error_reg[a] <= 1'b1;
            else if (clear_errors) rate_error_reg[a] <= 1'b0;
            if (first && sh_hot[a] && (clamp_high || clamp_low)) step_lost_reg[a] <= 1'b1;
            else if (clear_errors) step_lost_reg[a] <= 1'b0;
            if (first && sh_hot[a]) begin
                pin_a_reg[a] <= a_next ^ inv_cur[FS_INVERT_PIN_A_BIT];
                pin_b_reg[a] <= b_next ^ inv_cur[FS_INVERT_PIN_B_BIT];
            end
        end
        if (rst) begin
            rate_error_reg <= {N_AXES{1'b0}};
            step_lost_reg  <= {N_AXES{1'b0}};
            pin_a_reg      <= {N_AXES{1'b0}};
            pin_b_reg      <= {N_AXES{1'b0}};
            pin_en_reg     <= {N_AXES{1'b0}};
        end
    end

    assign pin_a      = pin_a_reg;
    assign pin_b      = pin_b_reg;
    assign pin_en     = pin_en_reg;
    assign rate_error = rate_error_reg;
    assign step_lost  = step_lost_reg;
    assign pos_digit  = pos_digit_reg;
    assign pos_index  = pos_index_reg;
    assign pos_axis   = pos_axis_reg;

endmodule

`default_nettype wire

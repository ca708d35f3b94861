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
    reg             live_v_reg;        // the visit continues its axis's accumulator
    reg             live_w_reg;        // run has stayed 1 since the first clock
    reg             cy1_reg, cy2_reg, cy3_reg;
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
            req_valid_reg    <= dda_visit && live_new && (s_ge_m || s_neg);
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
    // The visit's timings are the ones its first clock sees: held for its later digits,
    // so a timing written in the middle of a visit applies from the axis's next visit.
    // Each held as the compares read it: X >> LR above a bit for X mod R == 0.
    localparam XW = TIMING_W - LR + 1;
    function [XW-1:0] rounds;
        input [TIMING_W-1:0] x;
        begin
            rounds = {x[TIMING_W-1:LR], x[LR-1:0] == {LR{1'b0}}};
        end
    endfunction
    reg  [XW-1:0] len_reg, space_reg, setup_reg, hold_reg;
    wire [XW-1:0] len_x   = first ? rounds(len_all[TIMING_W*sh_axis +: TIMING_W]) : len_reg;
    wire [XW-1:0] space_x = first ? rounds(space_all[TIMING_W*sh_axis +: TIMING_W]) : space_reg;
    wire [XW-1:0] setup_x = first ? rounds(setup_all[TIMING_W*sh_axis +: TIMING_W]) : setup_reg;
    wire [XW-1:0] hold_x  = first ? rounds(hold_all[TIMING_W*sh_axis +: TIMING_W]) : hold_reg;
    wire [XW-1:0] cmp_a_x = c_half ? setup_x : len_x;     // dcnt against dir_setup
    wire [15:0] ya = {{(16-XW+1){1'b0}}, cmp_a_x[XW-1:1]};
    wire [15:0] yb = {{(16-XW+1){1'b0}}, space_x[XW-1:1]};
    wire [15:0] yc = {{(16-XW+1){1'b0}}, hold_x[XW-1:1]};
    reg          cya_reg, cyb_reg, cyc2_reg;
    wire [D:0]   cmp_a = {1'b0, cnt_new} + {1'b0, ~ya[D*k +: D]} +
                         {{D{1'b0}}, k_first ? cmp_a_x[0] : cya_reg};
    wire [D:0]   cmp_b = {1'b0, cnt_new} + {1'b0, ~yb[D*k +: D]} +
                         {{D{1'b0}}, k_first ? space_x[0] : cyb_reg};
    wire [D:0]   cmp_c = {1'b0, cnt_new} + {1'b0, ~yc[D*k +: D]} +
                         {{D{1'b0}}, k_first ? hold_x[0] : cyc2_reg};
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
            len_reg      <= len_x;
            space_reg    <= space_x;
            setup_reg    <= setup_x;
            hold_reg     <= hold_x;
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

`ifdef FORMAL
    // The engine against the spec's per-axis arithmetic (docs/spec/step_serial.md), in
    // its own words: a shadow state per axis (acc, live, the request, pending, level,
    // dir, quad, the two counters, the compares the last visit left, the position, the
    // pins and the sticky flags) is updated once per visit, at the visit's first clock,
    // by the spec's rules; at the first clock of every slot every ring word and ring flag
    // must be what the shadow says (a ring neither loses nor mixes an axis's words), and
    // in every clock the pins, flags, enables and the position stream must be the
    // shadow's. On the shadow: no step is lost or made up (per axis, position + pending
    // equals the net requests the shaper took, until a clamp; a halt drops the pending
    // ones), and every DDA request reaches the shaper before the axis's next DDA visit.
    reg f_past_valid;
    initial f_past_valid = 1'b0;
    initial assume (rst);
    always @(posedge clk) f_past_valid <= 1'b1;

    // Environment: while run = 1, inc changes only at a round's first clock and p_active
    // not at all; while run = 0 both may change in any clock (the period timer zeroes inc
    // and samples P); a run rises only at a round's first clock; p_active is a whole
    // number (>= 1) of rounds. The timings may change in any clock (the engine takes a
    // visit's timings at its first clock, as the shadow does).
    wire [V_W-1:0] f_v = p_active[P_WIDTH-1:LR];
    always @(*) assume (p_active[LR-1:0] == {LR{1'b0}} && f_v != {V_W{1'b0}});
    always @(posedge clk) if (f_past_valid && !rst) begin
        if (run && phase_reg != {LR{1'b0}}) assume ($stable(inc) && $stable(p_active));
        if (run && $past(run)) assume ($stable(p_active));
        if (run && !$past(run)) assume (phase_reg == {LR{1'b0}});
    end
    wire signed [35:0] f_m = $signed({{(20-V_W){1'b0}}, f_v, 16'd0});
    wire [TIMING_W-1:0] f_max = {TIMING_W{1'b1}};
    wire f_chk = f_past_valid && !rst;

    wire [32*S-1:0] f_pos_new_all;
    generate
        if (S > N_AXES) begin : f_pad
            assign f_pos_new_all[32*S-1:32*N_AXES] = {(32*(S-N_AXES)){1'b0}};
        end
    endgenerate
    genvar fa;
    generate
        for (fa = 0; fa < N_AXES; fa = fa + 1) begin : f_axis
            // ---- The shadow, in the spec's words ----
            reg [31:0]         acc;        // in [0, M) while live
            reg [31:0]         m_used;     // M of the last visit that ran
            reg                live, running;
            reg                req_on, req_neg;   // the last DDA visit's request
            reg                unconsumed;        // a request the shaper has not taken
            reg                init;
            reg [7:0]          pend;
            reg                lvl, dr;
            reg [1:0]          qd;
            reg [TIMING_W-1:0] cnt, dcnt;
            reg                len_ok, space_ok, hold_ok, setup_ok;
            reg [31:0]         pos, net;
            reg                clamped;
            reg                pa, pb, rate, lost;

            wire dda_now = (slot == fa) && first;
            wire sh_now  = sh_visit && (sh_axis == fa) && first;
            wire [TIMING_W-1:0] len_a   = step_len[TIMING_W*fa +: TIMING_W];
            wire [TIMING_W-1:0] space_a = step_space[TIMING_W*fa +: TIMING_W];
            wire [TIMING_W-1:0] setup_a = dir_setup[TIMING_W*fa +: TIMING_W];
            wire [TIMING_W-1:0] hold_a  = dir_hold[TIMING_W*fa +: TIMING_W];

            // DDA visit: s = (live ? acc : M/2) + d, wrapped into [0, M) with a request.
            wire signed [35:0] d  = $signed({{4{inc[32*fa+31]}}, inc[32*fa +: 32]});
            wire signed [35:0] b  = live ? $signed({4'b0000, acc}) : (f_m >>> 1);
            wire signed [35:0] sm = b + d;
            wire               up   = sm >= f_m;
            wire               down = sm < 0;
            wire signed [35:0] acc_new = up ? sm - f_m : (down ? sm + f_m : sm);
            always @(*) if (f_chk && dda_now && run) assume (acc_new < f_m && acc_new >= 0);

            // Shaper visit: step_shaper's rule with the counters counting visits.
            wire signed [9:0] e     = $signed({{2{pend[7]}}, pend}) +
                                      (req_on ? (req_neg ? -10'sd1 : 10'sd1) : 10'sd0);
            wire              move  = !lvl && e != 10'sd0 && !halt;
            wire              rise_s = move && ((e > 10'sd0) == dr) && space_ok && setup_ok;
            wire              fall_s = lvl && len_ok;
            wire              turn_s = move && ((e > 10'sd0) != dr) && hold_ok;
            wire signed [9:0] iss   = rise_s ? (dr ? 10'sd1 : -10'sd1) : 10'sd0;
            wire signed [9:0] left  = e - iss;
            wire [7:0]        pend_new = halt ? 8'd0 : (left > 10'sd127 ? 8'sd127 :
                                         (left < -10'sd127 ? -8'sd127 : left[7:0]));
            wire [31:0]       pos_new  = pos + {{22{iss[9]}}, iss};
            wire              lvl_new  = rise_s ? 1'b1 : (fall_s ? 1'b0 : lvl);
            wire              dr_new   = turn_s ? !dr : dr;
            wire [1:0]        qd_new   = qd + iss[1:0];
            wire [TIMING_W-1:0] cnt_new  = (rise_s || fall_s) ? {{(TIMING_W-1){1'b0}}, 1'b1} :
                                           (cnt == f_max ? cnt : cnt + 1'b1);
            wire [TIMING_W-1:0] dcnt_new = turn_s ? {{(TIMING_W-1){1'b0}}, 1'b1} :
                                           (dcnt == f_max ? dcnt : dcnt + 1'b1);
            wire [31:0] cnt_clk  = {{(32-TIMING_W){1'b0}}, cnt_new} << LR;    // cnt * R
            wire [31:0] dcnt_clk = {{(32-TIMING_W){1'b0}}, dcnt_new} << LR;
            wire [1:0]  mode_a   = out_mode[2*fa +: 2];
            wire [2:0]  inv_a    = invert[3*fa +: 3];
            wire pa_new = (mode_a == FS_OUT_MODE_UP_DOWN) ? (lvl_new && dr_new) :
                          (mode_a == FS_OUT_MODE_QUADRATURE) ? (qd_new[0] ^ qd_new[1]) : lvl_new;
            wire pb_new = (mode_a == FS_OUT_MODE_UP_DOWN) ? (lvl_new && !dr_new) :
                          (mode_a == FS_OUT_MODE_QUADRATURE) ? qd_new[1] : dr_new;
            wire rate_set = sh_now && !halt && (e >= 10'sd2 || e <= -10'sd2);
            wire lost_set = sh_now && !halt && (left > 10'sd127 || left < -10'sd127);
            assign f_pos_new_all[32*fa +: 32] = pos_new;

            always @(posedge clk) begin
                // DDA
                if (slot == fa && dda_visit) begin
                    if (first) running <= run;
                    else running <= running && run;
                    if (last) live <= (first ? run : running) && run;
                    // A visit during which the run falls makes no request.
                    if (last && !((first ? run : running) && run)) begin
                        req_on     <= 1'b0;
                        req_neg    <= 1'b0;
                        unconsumed <= 1'b0;
                    end
                end
                if (dda_now) begin
                    req_on     <= run && (up || down);
                    req_neg    <= run && down;
                    unconsumed <= run && (up || down);
                    if (run) begin
                        acc    <= acc_new[31:0];
                        m_used <= f_m[31:0];
                    end
                end
                if (!run) live <= 1'b0;
                // Shaper
                if (sh_now) begin
                    unconsumed <= 1'b0;
                    init     <= 1'b1;
                    pend     <= pend_new;
                    lvl      <= lvl_new;
                    dr       <= dr_new;
                    qd       <= qd_new;
                    cnt      <= cnt_new;
                    dcnt     <= dcnt_new;
                    len_ok   <= cnt_clk >= {{(32-TIMING_W){1'b0}}, len_a};
                    space_ok <= cnt_clk >= {{(32-TIMING_W){1'b0}}, space_a};
                    hold_ok  <= cnt_clk >= {{(32-TIMING_W){1'b0}}, hold_a};
                    setup_ok <= dcnt_clk >= {{(32-TIMING_W){1'b0}}, setup_a};
                    pos      <= pos_new;
                    net      <= halt ? pos : net + (req_on ? (req_neg ? 32'hffffffff : 32'd1) : 32'd0);
                    if (lost_set) clamped <= 1'b1;
                    pa       <= pa_new ^ inv_a[FS_INVERT_PIN_A_BIT];
                    pb       <= pb_new ^ inv_a[FS_INVERT_PIN_B_BIT];
                end
                if (rate_set) rate <= 1'b1;
                else if (clear_errors) rate <= 1'b0;
                if (lost_set) lost <= 1'b1;
                else if (clear_errors) lost <= 1'b0;
                if (rst) begin
                    live <= 1'b0; running <= 1'b0;
                    req_on <= 1'b0; req_neg <= 1'b0; unconsumed <= 1'b0;
                    init <= 1'b0; pend <= 8'd0; lvl <= 1'b0; dr <= 1'b1; qd <= 2'd0;
                    cnt <= f_max; dcnt <= f_max;
                    len_ok <= 1'b1; space_ok <= 1'b1; hold_ok <= 1'b1; setup_ok <= 1'b1;
                    pos <= 32'd0; net <= 32'd0; clamped <= 1'b0;
                    pa <= 1'b0; pb <= 1'b0; rate <= 1'b0; lost <= 1'b0;
                end
            end

            // ---- The rings against the shadow, at every slot's first clock ----
            wire [SL-1:0] i_dda = fa - slot;        // its entry in the DDA rings
            wire [SL-1:0] i_sh  = fa - sh_axis;     // ... in the shaper rings
            wire [31:0] acc_w = acc_ring >> (32 * i_dda);
            wire [31:0] pos_w = pos_ring >> (32 * i_sh);
            wire [31:0] cnt_w = cnt_ring >> (32 * i_sh);
            wire [E_W-1:0] sh_e = sh_ring >> (E_W * i_sh);
            wire wu = wrap_up_ring[i_dda];
            wire wd = wrap_down_ring[i_dda];
            always @(*) if (f_chk) begin
                // The shadow's own invariants.
                assert (pend != 8'h80);
                if (live) assert (acc < m_used && m_used != 32'd0 && m_used[31] == 1'b0);
                if (!clamped) assert (pos + {{24{pend[7]}}, pend} == net);
                if (!init) assert (pend == 8'd0 && !lvl && dr && qd == 2'd0 && cnt == f_max &&
                                   dcnt == f_max && pos == 32'd0 && len_ok && space_ok &&
                                   hold_ok && setup_ok && !pa && !pb);
                // No request is overwritten before the shaper takes it: one waits only from
                // its DDA visit to the first clock of the axis's shaper visit, the next slot.
                if (unconsumed) assert ((slot == fa && !first) || (sh_axis == fa && first));
                if (!req_on) assert (!unconsumed && !req_neg);
                assert (rate_error[fa] == rate && step_lost[fa] == lost);
                assert (pin_a[fa] == pa && pin_b[fa] == pb);
                if (first) begin
                    assert (live_ring[i_dda] == live);
                    if (live && run) begin
                        assert (!(wu && wd));
                        assert (m_used == f_m[31:0]);
                        assert (acc_w - (wu ? m_used : (wd ? -m_used : 32'd0)) == acc);
                    end
                    assert (sh_e[E_INIT] == init);
                    if (init) begin
                        assert (sh_e[E_PEND +: PEND_W] == pend && sh_e[E_LEVEL] == lvl &&
                                sh_e[E_DIR] == dr && sh_e[E_QUAD +: 2] == qd);
                        assert (sh_e[E_LEN] == len_ok && sh_e[E_SPACE] == space_ok &&
                                sh_e[E_HOLD] == hold_ok && sh_e[E_SETUP] == setup_ok);
                        assert (sh_e[E_CFULL] == (cnt == f_max) && sh_e[E_DFULL] == (dcnt == f_max));
                        assert (cnt_w == {{(16-TIMING_W){1'b0}}, dcnt, {(16-TIMING_W){1'b0}}, cnt});
                        assert (pos_w == pos);
                    end
                end
                // The shaper visit takes this axis's request.
                if (sh_now) assert (req_valid_reg == req_on && (!req_on || req_negative_reg == req_neg));
            end
            always @(posedge clk) if (f_chk && !$past(rst)) begin
                assert (pin_en[fa] == $past((axis_enable[fa] && !halt) ^ invert[3*fa + FS_INVERT_PIN_EN_BIT]));
                cover (init && rate && lvl && !dr);
                // A halt dropping a pending step; a run falling in a DDA visit.
                cover (sh_now && halt && pend != 8'd0);
                cover (slot == fa && !first && running && !run && live);
            end
        end
    endgenerate

    // The position stream: in clock n + 1, digit j (of clock n) of the position the
    // shaper visit left; 0 in an idle slot.
    reg [31:0] f_stream;
    always @(posedge clk) if (sh_visit && first) f_stream <= f_pos_new_all[32*sh_axis +: 32];
    always @(posedge clk) if (f_chk && !$past(rst)) begin
        assert (pos_index == {{(8-QL){1'b0}}, $past(j)} && pos_axis == {{(3-SL){1'b0}}, $past(sh_axis)});
        if ($past(sh_visit)) assert (pos_digit == f_stream[D*$past(j) +: D]);
        else assert (pos_digit == {D{1'b0}});
        assert (phase_reg == $past(phase_reg) + PHASE_ONE);
    end
    always @(*) if (f_chk) assert (start_ok == (phase_reg == {LR{1'b1}} - PHASE_ONE));
`endif

endmodule

`default_nettype wire

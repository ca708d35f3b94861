`timescale 1ns / 1ps
`default_nettype none
// Specification: docs/spec/step_engine.md
// Step engine: one DDA and one step shaper visiting the axes in turn (finestep_core with
// STEP_SHARED = 1), instead of a dda_axis and a step_shaper per axis. S = 2^SL slots; a
// free-running slot counter gives each axis a DDA visit every S cycles (slot == a) and a
// shaper visit the cycle after (slot == a + 1 mod S). The rules are dda_axis's and
// step_shaper's applied once per visit: the DDA's modulus is V = P / S visits, the
// shaper's counters count visits and compare cnt * S against the timings in clocks.
//
// Each axis's DDA accumulator and shaper state live in a store (store_ram: block RAM on
// the iCE40 with RAM_BLOCK = 1, distributed RAM or flip-flops elsewhere), read two
// cycles before the visit and written at the visit (with S = 2, where that read would
// meet the write of the axis's previous visit, a register of that visit's result stands
// in for the store); a store never reads and writes one word on one clock (the formal
// section proves it). Positions, sticky flags and pins stay in flip-flops per axis: the
// registers and the probe read every axis's position in any cycle.
//
// Timing (no visible effect): what a visit starts from is prepared a cycle ahead in
// registers: the DDA's start b, with SUM_AHEAD (the default without block RAM) b - M and
// b + M beside it (three two-input sums at the visit, beside each other, no carry chain
// behind another; without it, on the iCE40's RAM_BLOCK builds, b + d - M and b + d + M
// are formed at the visit from b + d), the shaper's state. The increments and the
// shaper's timings are this cycle's (a timing may change in any cycle): with CMP_EACH
// (the default without block RAM) the counters are compared with every axis's timings
// side by side and the visited axis's four results chosen after the compares; without it
// (the iCE40's RAM_BLOCK builds) the visited axis's timings are chosen, then compared.
//
// Latency: a DDA visit in cycle n gives the shaper's decision in n+1 and the pin edge and
// position in n+2.
//
// With EXT_REQ (finestep_core's pbp block, docs/spec/step_engine.md#requests-from-outside):
// a request on ext_req_* in cycle m is held for its axis and taken by the axis's first
// shaper visit after m (m+1 .. m+S) as that visit's request, the DDA's in its place;
// ext_pending says one is on the port or held. A second one on an axis must wait S
// clocks (the sender's rule, as the period timer's for the DDA).
module step_engine #(
    parameter N_AXES    = 4,
    parameter P_WIDTH   = 20,
    parameter TIMING_W  = 12,
    parameter RAM_BLOCK = 0,
    // 1: the shaper's counters compared with every axis's timings side by side, the
    // visited axis's results chosen after the compares (fast: the ECP5); 0: the visited
    // axis's timings chosen, then one compare each (N_AXES - 1 fewer compares of
    // CMP_W bits: on the iCE40, where a compare's carry chain takes logic cells of its
    // own, the full core did not fit at speed with them). Same results either way.
    parameter CMP_EACH  = (RAM_BLOCK == 0) ? 1 : 0,
    // 1: the DDA's b - M and b + M formed a cycle ahead, in registers (two more carry
    // chains and their flip-flops, fast: the ECP5); 0: formed at the visit (dda_step
    // AHEAD 0: fewer logic cells, the iCE40). Same results either way.
    parameter SUM_AHEAD = (RAM_BLOCK == 0) ? 1 : 0,
    // 1: requests from outside the DDA on ext_req_* (finestep_core with HAS_PBP); 0: the
    // ports are not read and ext_pending is 0.
    parameter EXT_REQ   = 0
) (
    // clock, reset
    input  wire                       clk,
    input  wire                       rst,
    // from the period timer
    input  wire                       run,             // the period timer runs (run && active)
    input  wire [P_WIDTH-1:0]         p_active,        // period of the running move, a multiple of S
    input  wire [32*N_AXES-1:0]       inc,             // Q16.16 steps per period, per axis
    output wire                       start_ok,        // slot == S - 2: a run may start now
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
    // requests from outside the DDA (EXT_REQ), one clock each
    input  wire [N_AXES-1:0]          ext_req_valid,
    input  wire [N_AXES-1:0]          ext_req_negative,
    output wire                       ext_pending,     // a request on the port or held
    // pins and status
    output wire [N_AXES-1:0]          pin_a,
    output wire [N_AXES-1:0]          pin_b,
    output wire [N_AXES-1:0]          pin_en,
    output wire [32*N_AXES-1:0]       position,
    output wire [N_AXES-1:0]          rate_error,
    output wire [N_AXES-1:0]          step_lost
);

`include "finestep_interface.vh"

    localparam SL        = (N_AXES <= 2) ? 1 : ((N_AXES <= 4) ? 2 : 3);
    localparam S         = 1 << SL;
    localparam V_W       = P_WIDTH - SL;          // bits of the visits per period
    localparam FRAC_BITS = 16;
    localparam ACC_W     = V_W + FRAC_BITS;
    localparam SUM_W     = ACC_W + 2;             // sign + one carry bit
    localparam PEND_W    = 8;
    localparam CMP_W     = TIMING_W + SL;         // cnt * S against a timing
    localparam [TIMING_W-1:0] COUNT_MAX = {TIMING_W{1'b1}};
    localparam [TIMING_W-1:0] COUNT_ONE = {{(TIMING_W-1){1'b0}}, 1'b1};
    localparam SH_W      = PEND_W + 2 + 2 * TIMING_W + 2;   // pending, level, dir, cnt, dcnt, quad
    localparam [SL-1:0] SLOT_ONE = {{(SL-1){1'b0}}, 1'b1};

    // ---- Schedule --------------------------------------------------------------------
    reg  [SL-1:0] slot_reg;
    reg  [SL-1:0] sh_axis_reg;                       // slot_reg - 1, as a flip-flop
    wire [SL-1:0] slot_next = slot_reg + SLOT_ONE;
    wire [SL-1:0] dda_axis  = slot_reg;               // DDA visit of this axis
    wire [SL-1:0] sh_axis   = sh_axis_reg;            // shaper visit of this axis
    wire dda_visit = ({{(32-SL){1'b0}}, dda_axis} < N_AXES);
    wire sh_visit  = ({{(32-SL){1'b0}}, sh_axis} < N_AXES);
    // The axis whose configuration and flip-flops a visit reads: 0 in an idle slot (whose
    // results are never used), so no select runs past the per-axis vectors.
    wire [SL-1:0] dda_ix = dda_visit ? dda_axis : {SL{1'b0}};
    wire [SL-1:0] sh_ix  = sh_visit ? sh_axis : {SL{1'b0}};
    // The visited axes one-hot (none in an idle slot).
    wire [N_AXES-1:0] dda_hot;
    wire [N_AXES-1:0] sh_hot;
    genvar h;
    generate
        for (h = 0; h < N_AXES; h = h + 1) begin : hot
            assign dda_hot[h] = ({{(32-SL){1'b0}}, dda_axis} == h);
            assign sh_hot[h]  = ({{(32-SL){1'b0}}, sh_axis} == h);
        end
    endgenerate
    assign start_ok = (slot_reg == {SL{1'b1}} - SLOT_ONE);    // S - 2 (mod S)

    always @(posedge clk) begin
        slot_reg    <= rst ? {SL{1'b0}} : slot_next;
        sh_axis_reg <= rst ? {SL{1'b1}} : slot_reg;
    end

    // Per-axis flags: the DDA store holds the axis's accumulator of this run (its last
    // visit ran); the shaper store holds the axis's state (written at a visit since
    // reset). Otherwise a visit starts from M/2, or from the shaper's reset values.
    reg [N_AXES-1:0] dda_live_reg;
    reg [N_AXES-1:0] sh_init_reg;
    // The next cycle's visits (the axes are known from the slot) and their flags as this
    // cycle leaves them: a visit's start is chosen a cycle ahead, so no select by the slot
    // sits in front of its arithmetic.
    wire [SL-1:0] dda_axis_after = slot_next;
    wire [SL-1:0] sh_axis_after  = slot_reg;
    wire [SL-1:0] dda_ix_after = ({{(32-SL){1'b0}}, dda_axis_after} < N_AXES) ? dda_axis_after : {SL{1'b0}};
    wire [SL-1:0] sh_ix_after  = ({{(32-SL){1'b0}}, sh_axis_after} < N_AXES) ? sh_axis_after : {SL{1'b0}};
    wire dda_live_after = run && dda_live_reg[dda_ix_after];
    wire sh_init_after  = sh_init_reg[sh_ix_after];

    // ---- Stores, read two cycles ahead -------------------------------------------------
    // A store is read in the cycle two before the visit (address: the axis visited two
    // cycles later), and the word, with the visit's start (M/2, the reset values) chosen
    // in, is loaded into the visit's registers in the cycle before. With S = 2 the word is
    // the one the axis's previous visit leaves at that same edge: it is taken from that
    // visit's result, registered, and no store is built.
    wire [ACC_W-1:0] acc_next;   // the DDA visit's result (used after a running visit)
    wire [SH_W-1:0]  sh_next;    // the shaper visit's result
    wire [ACC_W-1:0] acc_src;    // the word of the next cycle's DDA visit
    wire [SH_W-1:0]  sh_src;     // ... and of its shaper visit
    generate
        if (S == 2) begin : last_visit
            reg [ACC_W-1:0] acc_last_reg;
            reg [SH_W-1:0]  sh_last_reg;
            always @(posedge clk) begin
                acc_last_reg <= acc_next;
                sh_last_reg  <= sh_next;
            end
            assign acc_src = acc_last_reg;
            assign sh_src  = sh_last_reg;
        end else begin : stores
            store_ram #(.WIDTH(ACC_W), .DEPTH(S), .ADDR_W(SL), .BLOCK(RAM_BLOCK)) dda_store (
                .clk(clk), .wr_en(dda_visit), .wr_addr(dda_axis), .wr_data(acc_next),
                .rd_en(1'b1), .rd_addr(slot_next + SLOT_ONE), .rd_data(acc_src)
            );
            store_ram #(.WIDTH(SH_W), .DEPTH(S), .ADDR_W(SL), .BLOCK(RAM_BLOCK)) shaper_store (
                .clk(clk), .wr_en(sh_visit), .wr_addr(sh_axis), .wr_data(sh_next),
                .rd_en(1'b1), .rd_addr(slot_next), .rd_data(sh_src)
            );
        end
    endgenerate

    // ---- DDA visit -------------------------------------------------------------------
    // M = V * 2^16 with V = p_active / S, and M/2, where the first running visit starts.
    wire [SL-1:0] unused_p_low = p_active[SL-1:0];
    wire [SUM_W-1:0] modulus      = {2'b00, p_active[P_WIDTH-1:SL], {FRAC_BITS{1'b0}}};
    wire [ACC_W-1:0] half_modulus = {1'b0, p_active[P_WIDTH-1:SL], {(FRAC_BITS-1){1'b0}}};
    // The next visit's start b (acc[a] if live[a], else M/2) and b - M, b + M, loaded a
    // cycle ahead, so the visit's sums are two-input ones (dda_step). M is the next
    // cycle's: p_active changes only while the DDAs stop, so it is when the DDAs ran in
    // this cycle, which every live start needs. A visit in the first running cycle (run
    // rose: the period timer's first cycle, a boundary, whose increments are all zero)
    // has s = M/2 + 0 = M/2 of its own M, no request: it makes none here and leaves
    // live[a] clear, so the axis's next visit starts from M/2 again, as the spec's would.
    wire [ACC_W-1:0] acc_start = dda_live_after ? acc_src : half_modulus;
    reg  [ACC_W-1:0] acc_cur_reg;
    reg              ran_reg;                        // run in the previous cycle
    always @(posedge clk) begin
        acc_cur_reg   <= acc_start;
        ran_reg       <= !rst && run;
    end
    wire [ACC_W-1:0] acc_cur = acc_cur_reg;
    wire [31:0]      inc_cur = inc[32*dda_ix +: 32];
    // One update (dda_step): acc + d against M = V * 2^16.
    wire             wrap_up, wrap_down;
    wire [SUM_W-1:0] unused_sum;
    wire [SUM_W-1:0] acc_minus_m;                    // b - M and b + M (SUM_AHEAD), else 0
    wire [SUM_W-1:0] acc_plus_m;
    generate
        if (SUM_AHEAD != 0) begin : sums_ahead
            reg [SUM_W-1:0] acc_minus_reg;
            reg [SUM_W-1:0] acc_plus_reg;
            always @(posedge clk) begin
                acc_minus_reg <= {2'b00, acc_start} - modulus;
                acc_plus_reg  <= {2'b00, acc_start} + modulus;
            end
            assign acc_minus_m = acc_minus_reg;
            assign acc_plus_m  = acc_plus_reg;
        end else begin : sums_here
            assign acc_minus_m = {SUM_W{1'b0}};
            assign acc_plus_m  = {SUM_W{1'b0}};
            wire unused_modulus = &{1'b0, modulus};   // dda_step forms M from m
        end
    endgenerate
    dda_step #(.M_W(V_W), .AHEAD(SUM_AHEAD != 0 ? 1 : 0)) update (
        .acc(acc_cur), .acc_minus_m(acc_minus_m), .acc_plus_m(acc_plus_m), .m(p_active[P_WIDTH-1:SL]),
        .inc(inc_cur),
        .acc_next(acc_next), .wrap_up(wrap_up), .wrap_down(wrap_down), .sum(unused_sum)
    );

    // The visit's request, taken by the shaper visit of the same axis in the next cycle.
    reg req_valid_reg;
    reg req_negative_reg;
    always @(posedge clk) begin
        req_valid_reg    <= !rst && dda_visit && run && ran_reg && (wrap_up || wrap_down);
        req_negative_reg <= !rst && wrap_down;
    end

    // ---- Requests from outside (EXT_REQ) ----------------------------------------------
    // Held per axis from the clock after they come until the axis's shaper visit takes
    // them (one that comes in a visit of its axis waits for the next); the visited axis's
    // is chosen a cycle ahead, as its state is, so no select by the slot sits in front of
    // the shaper's arithmetic. A held request is the visit's, else the DDA's.
    wire visit_req_valid;
    wire visit_req_negative;
    generate
        if (EXT_REQ != 0) begin : ext
            reg [N_AXES-1:0] held_reg;
            reg [N_AXES-1:0] held_negative_reg;
            reg              visit_held_reg;
            reg              visit_negative_reg;
            wire [N_AXES-1:0] held_next = ext_req_valid | (held_reg & ~sh_hot);
            wire [N_AXES-1:0] negative_next = (ext_req_valid & ext_req_negative) |
                                              (~ext_req_valid & held_negative_reg);
            always @(posedge clk) begin
                held_reg           <= rst ? {N_AXES{1'b0}} : held_next;
                held_negative_reg  <= negative_next;
                // The next cycle's shaper visit is of axis slot_reg (not visited now).
                visit_held_reg     <= !rst && held_next[sh_ix_after] && ({{(32-SL){1'b0}}, sh_axis_after} < N_AXES);
                visit_negative_reg <= negative_next[sh_ix_after];
            end
            assign visit_req_valid    = req_valid_reg || visit_held_reg;
            assign visit_req_negative = visit_held_reg ? visit_negative_reg : req_negative_reg;
            assign ext_pending        = (|ext_req_valid) || (|held_reg);
        end else begin : no_ext
            assign visit_req_valid    = req_valid_reg;
            assign visit_req_negative = req_negative_reg;
            assign ext_pending        = 1'b0;
            wire unused_ext = &{1'b0, ext_req_valid, ext_req_negative};
        end
    endgenerate

    // ---- Shaper visit ----------------------------------------------------------------
    // The visited axis's state, loaded a cycle ahead (the reset values until its first
    // visit).
    wire [SH_W-1:0] sh_reset = {2'd0, COUNT_MAX, COUNT_MAX, 1'b1, 1'b0, {PEND_W{1'b0}}};
    reg  [SH_W-1:0] sh_cur_reg;
    always @(posedge clk) sh_cur_reg <= (sh_init_after && !rst) ? sh_src : sh_reset;
    wire [SH_W-1:0] sh_cur = sh_cur_reg;
    wire signed [PEND_W-1:0] pending = sh_cur[PEND_W-1:0];
    wire                     level   = sh_cur[PEND_W];
    wire                     dir     = sh_cur[PEND_W+1];
    wire [TIMING_W-1:0]      cnt     = sh_cur[PEND_W+2 +: TIMING_W];
    wire [TIMING_W-1:0]      dcnt    = sh_cur[PEND_W+2+TIMING_W +: TIMING_W];
    wire [1:0]               quad    = sh_cur[PEND_W+2+2*TIMING_W +: 2];

    wire [1:0]          mode_cur  = out_mode[FS_OUT_MODE_WIDTH*sh_ix +: FS_OUT_MODE_WIDTH];
    wire [2:0]          inv_cur   = invert[FS_INVERT_WIDTH*sh_ix +: FS_INVERT_WIDTH];

    // Elapsed clocks of the counted visits: cnt * S, dcnt * S (exact).
    wire [CMP_W-1:0] cnt_clocks  = {cnt, {SL{1'b0}}};
    wire [CMP_W-1:0] dcnt_clocks = {dcnt, {SL{1'b0}}};
    // The counters against the visited axis's timings of this cycle (a timing may change
    // in any cycle), with CMP_EACH: every axis's compared side by side, then the visited
    // axis's results chosen: the compares start at flip-flops (the counters, the timings),
    // and the slot selects four bits after them, not 4 * TIMING_W before.
    wire len_reached, space_reached, setup_reached, hold_reached;
    genvar c;
    generate
        if (CMP_EACH != 0) begin : compare_each
            wire [N_AXES-1:0] len_ok, space_ok, setup_ok, hold_ok;
            for (c = 0; c < N_AXES; c = c + 1) begin : compares
                assign len_ok[c]   = cnt_clocks >= {{SL{1'b0}}, step_len[TIMING_W*c +: TIMING_W]};
                assign space_ok[c] = cnt_clocks >= {{SL{1'b0}}, step_space[TIMING_W*c +: TIMING_W]};
                assign setup_ok[c] = dcnt_clocks >= {{SL{1'b0}}, dir_setup[TIMING_W*c +: TIMING_W]};
                assign hold_ok[c]  = cnt_clocks >= {{SL{1'b0}}, dir_hold[TIMING_W*c +: TIMING_W]};
            end
            assign len_reached   = len_ok[sh_ix];
            assign space_reached = space_ok[sh_ix];
            assign setup_reached = setup_ok[sh_ix];
            assign hold_reached  = hold_ok[sh_ix];
        end else begin : compare_one
            assign len_reached   = cnt_clocks >= {{SL{1'b0}}, step_len[TIMING_W*sh_ix +: TIMING_W]};
            assign space_reached = cnt_clocks >= {{SL{1'b0}}, step_space[TIMING_W*sh_ix +: TIMING_W]};
            assign setup_reached = dcnt_clocks >= {{SL{1'b0}}, dir_setup[TIMING_W*sh_ix +: TIMING_W]};
            assign hold_reached  = cnt_clocks >= {{SL{1'b0}}, dir_hold[TIMING_W*sh_ix +: TIMING_W]};
        end
    endgenerate

    // The visit's decisions and next pending count (shaper_step).
    wire rise, fall, dir_change, clamp_high, clamp_low, behind;
    wire signed [PEND_W-1:0] pending_next;
    shaper_step decide (
        .pending(pending), .level(level), .dir(dir),
        .req_valid(visit_req_valid), .req_negative(visit_req_negative), .halt(halt),
        .len_reached(len_reached), .space_reached(space_reached),
        .setup_reached(setup_reached), .hold_reached(hold_reached),
        .rise(rise), .fall(fall), .dir_change(dir_change), .pending_next(pending_next),
        .clamp_high(clamp_high), .clamp_low(clamp_low), .behind(behind)
    );

    wire                level_next = rise ? 1'b1 : (fall ? 1'b0 : level);
    wire                dir_next   = dir_change ? !dir : dir;
    wire [TIMING_W-1:0] cnt_next   = (rise || fall) ? COUNT_ONE :
                                     ((cnt != COUNT_MAX) ? cnt + COUNT_ONE : cnt);
    wire [TIMING_W-1:0] dcnt_next  = dir_change ? COUNT_ONE :
                                     ((dcnt != COUNT_MAX) ? dcnt + COUNT_ONE : dcnt);
    wire [1:0]          quad_next  = rise ? quad + {!dir, 1'b1} : quad;
    assign              sh_next    = {quad_next, dcnt_next, cnt_next, dir_next, level_next, pending_next};

    // Pin functions of the state the visit leaves.
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

    // ---- Per-axis flip-flops: positions, flags, pins -------------------------------
    reg [32*N_AXES-1:0] position_reg;
    reg [N_AXES-1:0]    rate_error_reg;
    reg [N_AXES-1:0]    step_lost_reg;
    reg [N_AXES-1:0]    pin_a_reg;
    reg [N_AXES-1:0]    pin_b_reg;
    reg [N_AXES-1:0]    pin_en_reg;
    // Each axis's position is its own up/down counter enabled at its shaper visit (no
    // shared adder behind a select: fewer cells, and the slot does not steer a 32-bit
    // multiplexer into the carry chain).

    integer a;
    always @(posedge clk) begin
        for (a = 0; a < N_AXES; a = a + 1) begin
            pin_en_reg[a] <= (axis_enable[a] && !halt) ^ invert[FS_INVERT_WIDTH*a + FS_INVERT_PIN_EN_BIT];
            if (sh_hot[a] && behind) rate_error_reg[a] <= 1'b1;
            else if (clear_errors) rate_error_reg[a] <= 1'b0;
            if (sh_hot[a] && (clamp_high || clamp_low)) step_lost_reg[a] <= 1'b1;
            else if (clear_errors) step_lost_reg[a] <= 1'b0;
            if (sh_hot[a]) begin
                pin_a_reg[a] <= a_next ^ inv_cur[FS_INVERT_PIN_A_BIT];
                pin_b_reg[a] <= b_next ^ inv_cur[FS_INVERT_PIN_B_BIT];
                sh_init_reg[a] <= 1'b1;
                if (rise) position_reg[32*a +: 32] <= position_reg[32*a +: 32] + {{31{!dir}}, 1'b1};
            end
            if (!run) dda_live_reg[a] <= 1'b0;
            else if (dda_hot[a] && ran_reg) dda_live_reg[a] <= 1'b1;
        end
        if (rst) begin
            position_reg   <= {32*N_AXES{1'b0}};
            rate_error_reg <= {N_AXES{1'b0}};
            step_lost_reg  <= {N_AXES{1'b0}};
            pin_a_reg      <= {N_AXES{1'b0}};
            pin_b_reg      <= {N_AXES{1'b0}};
            pin_en_reg     <= {N_AXES{1'b0}};
            dda_live_reg   <= {N_AXES{1'b0}};
            sh_init_reg    <= {N_AXES{1'b0}};
        end
    end

    assign pin_a      = pin_a_reg;
    assign pin_b      = pin_b_reg;
    assign pin_en     = pin_en_reg;
    assign position   = position_reg;
    assign rate_error = rate_error_reg;
    assign step_lost  = step_lost_reg;

`ifdef FORMAL
    // The engine against one state per axis: shadow copies of every axis's DDA and shaper
    // state, updated at that axis's visits, must be what the stores hand its next visit
    // (the stores neither lose nor mix an axis's state); the stores never read and write
    // one word on one clock (what store_ram's no_rw_check relies on); the visit's
    // arithmetic is the spec's (e = pending + request, cnt * S >= timing, the DDA's wrap
    // against M = P / S * 2^16); no step is lost or made up: per axis, position + pending
    // equals the net requests of its DDA visits (until a clamp; a halt drops the pending
    // ones); pins move only at their axis's shaper visits.
    reg f_past_valid;
    initial f_past_valid = 1'b0;
    initial assume (rst);
    always @(posedge clk) f_past_valid <= 1'b1;
    wire [31:0] position_cur = position_reg[32*sh_ix +: 32];
    wire [TIMING_W-1:0] len_cur   = step_len[TIMING_W*sh_ix +: TIMING_W];
    wire [TIMING_W-1:0] space_cur = step_space[TIMING_W*sh_ix +: TIMING_W];
    wire [TIMING_W-1:0] setup_cur = dir_setup[TIMING_W*sh_ix +: TIMING_W];
    wire [TIMING_W-1:0] hold_cur  = dir_hold[TIMING_W*sh_ix +: TIMING_W];
    // Configuration is constant during the proof; the period timer's environment: p_active
    // is a whole number of visits while running and every increment is below one step per
    // visit (the record check).
    always @(posedge clk) if (f_past_valid) begin
        assume ($stable(step_len) && $stable(step_space) && $stable(dir_setup) && $stable(dir_hold));
        if (run && $past(run)) assume ($stable(p_active));
        // The first running cycle (after a stop or a reset) is the period timer's first, a
        // boundary: every increment is zero in it.
        if (run && !ran_reg) assume (inc == {32*N_AXES{1'b0}});
    end
    wire [V_W-1:0] f_visits = p_active[P_WIDTH-1:SL];
    always @(*) begin
        assume (p_active[SL-1:0] == {SL{1'b0}} && f_visits != {V_W{1'b0}});
    end

    reg [ACC_W-1:0]  f_acc  [0:N_AXES-1];
    reg [SH_W-1:0]   f_sh   [0:N_AXES-1];
    reg [31:0]       f_net  [0:N_AXES-1];   // net requests taken by the shaper, per axis
    reg [N_AXES-1:0] f_clamped;
    reg [N_AXES-1:0] f_live;                // the axis's last DDA visit ran
    integer f;
    localparam [PEND_W-1:0] PEND_MAX = 8'sd127;
    wire signed [PEND_W:0] f_request = visit_req_valid ? (visit_req_negative ? -9'sd1 : 9'sd1) : 9'sd0;
    always @(posedge clk) begin
        for (f = 0; f < N_AXES; f = f + 1) begin
            // The spec's accumulator: M/2 + 0 after the first running cycle's visit.
            if (dda_hot[f]) f_acc[f] <= (run && !ran_reg) ? half_modulus : acc_next;
            if (!run) f_live[f] <= 1'b0;
            else if (dda_hot[f]) f_live[f] <= 1'b1;
            if (sh_hot[f]) begin
                f_sh[f]  <= sh_next;
                f_net[f] <= halt ? position_cur : f_net[f] + {{23{f_request[PEND_W]}}, f_request};
                if (clamp_high || clamp_low) f_clamped[f] <= 1'b1;
            end
            if (rst) begin
                f_acc[f]     <= {ACC_W{1'b0}};
                f_live[f]    <= 1'b0;
                f_sh[f]      <= sh_reset;
                f_net[f]     <= 32'd0;
                f_clamped[f] <= 1'b0;
            end
        end
    end

    // The spec's arithmetic of a shaper visit, in its own words.
    wire signed [PEND_W:0] f_e      = {pending[PEND_W-1], pending} + f_request;
    wire signed [PEND_W:0] f_issued = rise ? (dir ? 9'sd1 : -9'sd1) : 9'sd0;
    wire signed [PEND_W:0] f_left   = f_e - f_issued;
    wire [31:0] f_cnt_clk  = {{(32-TIMING_W){1'b0}}, cnt} * S;
    wire [31:0] f_dcnt_clk = {{(32-TIMING_W){1'b0}}, dcnt} * S;
    wire f_rise = !halt && !level && f_e != 9'sd0 && (!f_e[PEND_W] == dir) &&
                  f_cnt_clk >= {{(32-TIMING_W){1'b0}}, space_cur} && f_dcnt_clk >= {{(32-TIMING_W){1'b0}}, setup_cur};
    wire f_fall = level && f_cnt_clk >= {{(32-TIMING_W){1'b0}}, len_cur};
    wire f_dir_change = !halt && !level && f_e != 9'sd0 && (!f_e[PEND_W] != dir) &&
                        f_cnt_clk >= {{(32-TIMING_W){1'b0}}, hold_cur};
    wire [PEND_W-1:0] f_pending_next = halt ? {PEND_W{1'b0}} : (f_left > 9'sd127) ? PEND_MAX :
                                       (f_left < -9'sd127) ? -PEND_MAX : f_left[PEND_W-1:0];
    // The DDA's: s = acc + d against M.
    wire [SUM_W+1:0] f_inc_ext;
    generate
        // d as the DDA sees it (its low SUM_W bits: |d| < M always fits), sign-extended.
        if (SUM_W >= 32) begin : f_widen
            assign f_inc_ext = {{(SUM_W+2-32){inc_cur[31]}}, inc_cur};
        end else begin : f_narrow
            assign f_inc_ext = {{2{inc_cur[SUM_W-1]}}, inc_cur[SUM_W-1:0]};
        end
    endgenerate
    wire signed [SUM_W+1:0] f_s = $signed({4'b0000, acc_cur}) + $signed(f_inc_ext);
    wire signed [SUM_W+1:0] f_m = $signed({4'b0000, p_active[P_WIDTH-1:SL], {FRAC_BITS{1'b0}}});

    always @(*) if (f_past_valid && !rst) begin
        // No read-during-write on either store.
        // No read-during-write on either store (read two cycles ahead; with S = 2 there
        // are no stores).
        if (S > 2 && dda_visit) assert (slot_next + SLOT_ONE != dda_axis);
        if (S > 2 && sh_visit) assert (slot_next != sh_axis);
        assert (start_ok == (slot_reg == S - 2));
        assert (sh_axis_reg == slot_reg - SLOT_ONE);
        // Each visit starts from what the axis's last visit left (the visit in the first
        // running cycle aside: its increment is zero and it only keeps live[a] clear, so
        // the axis's next visit starts from M/2 as the spec's would, from s = M/2 + 0),
        // with b - M and b + M beside it.
        if (dda_visit && run && ran_reg) begin
            assert (acc_cur == (f_live[dda_ix] ? f_acc[dda_ix] : half_modulus));
            if (SUM_AHEAD != 0) assert (acc_minus_m == {2'b00, acc_cur} - modulus && acc_plus_m == {2'b00, acc_cur} + modulus);
        end
        if (dda_visit && run && !ran_reg) assert (!dda_live_reg[dda_ix] && inc_cur == 32'd0);
        assert ((dda_live_reg & ~f_live) == {N_AXES{1'b0}});
        if (sh_visit) assert (sh_cur == f_sh[sh_ix]);
        if (sh_visit) begin
            assert (rise == f_rise && fall == f_fall && dir_change == f_dir_change);
            assert (pending_next == f_pending_next);
            // dcnt counts the visits since the axis's last DIR change (COUNT_MAX at reset:
            // none yet, the setup met): it only grows, to COUNT_MAX and no further, until
            // the next change (mutant 201 of the list at dd15ecb: its bound's bit 1 flipped
            // wraps the reset's COUNT_MAX to 0, holding the first step back by DIR_SETUP).
            if (!dir_change) assert (dcnt_next == ((dcnt == COUNT_MAX) ? COUNT_MAX : dcnt + COUNT_ONE));
            assert (behind == (!halt && (f_e > 9'sd1 || f_e < -9'sd1)));
            assert ((clamp_high || clamp_low) == (!halt && (f_left > 9'sd127 || f_left < -9'sd127)));
            assert (pending <= 8'sd127 && pending >= -8'sd127);
            // Steps are conserved: what was issued plus what waits is what was asked.
            if (!f_clamped[sh_ix]) assert (position_cur + {{24{pending[PEND_W-1]}}, pending} == f_net[sh_ix]);
        end
        if (dda_visit && run && ran_reg) begin
            assert ({2'b00, acc_cur} < {2'b00, f_visits, {FRAC_BITS{1'b0}}});
            assume (f_s - $signed({4'b0000, acc_cur}) < f_m && $signed({4'b0000, acc_cur}) - f_s < f_m);
            assert (wrap_up == (f_s >= f_m) && wrap_down == (f_s < 0));
        end
    end
    // The visited axis's step pins with its INVERT bits undone.
    reg [SL-1:0] f_ix_prev;
    reg          f_inv_a_prev, f_inv_b_prev;
    always @(posedge clk) begin
        f_ix_prev    <= sh_ix;
        f_inv_a_prev <= invert[FS_INVERT_WIDTH*sh_ix + FS_INVERT_PIN_A_BIT];
        f_inv_b_prev <= invert[FS_INVERT_WIDTH*sh_ix + FS_INVERT_PIN_B_BIT];
    end
    wire f_pin_a = pin_a[f_ix_prev] ^ f_inv_a_prev;
    wire f_pin_b = pin_b[f_ix_prev] ^ f_inv_b_prev;
    always @(posedge clk) if (f_past_valid && !$past(rst) && !rst) begin
        assert (slot_reg == $past(slot_reg) + SLOT_ONE);
        assert (ran_reg == $past(run));
        // Pins move only at the edge ending their axis's shaper visit; enables every cycle.
        for (f = 0; f < N_AXES; f = f + 1) begin
            if (!$past(sh_hot[f])) assert (pin_a[f] == $past(pin_a[f]) && pin_b[f] == $past(pin_b[f]) &&
                                           position_reg[32*f +: 32] == $past(position_reg[32*f +: 32]));
            assert (pin_en[f] == $past((axis_enable[f] && !halt) ^ invert[FS_INVERT_WIDTH*f + FS_INVERT_PIN_EN_BIT]));
            // ... and the step pins take their own axis's INVERT bits.
            if ($past(sh_hot[f])) assert (pin_a[f] == ($past(a_next) ^ $past(invert[FS_INVERT_WIDTH*f + FS_INVERT_PIN_A_BIT])) &&
                                          pin_b[f] == ($past(b_next) ^ $past(invert[FS_INVERT_WIDTH*f + FS_INVERT_PIN_B_BIT])));
        end
        // ... and carry the spec's function of the state the visit left (step_shaper's
        // table): step/dir A = level, B = dir; up/down the level on A moving up, on B
        // moving down; quadrature the count's Gray code, A = {0,1,1,0}, B = {0,0,1,1}.
        if ($past(sh_visit)) begin
            case ($past(mode_cur))
                FS_OUT_MODE_UP_DOWN: assert (f_pin_a == ($past(level_next) && $past(dir_next)) &&
                                             f_pin_b == ($past(level_next) && !$past(dir_next)));
                FS_OUT_MODE_QUADRATURE: assert (f_pin_a == ($past(quad_next) == 2'd1 || $past(quad_next) == 2'd2) &&
                                                f_pin_b == ($past(quad_next) >= 2'd2));
                default: assert (f_pin_a == $past(level_next) && f_pin_b == $past(dir_next));
            endcase
        end
        // A request comes only from a running DDA visit that wrapped.
        assert (req_valid_reg == ($past(dda_visit) && $past(run) && $past(ran_reg) && ($past(wrap_up) || $past(wrap_down))));
        cover (req_valid_reg && !req_negative_reg);
        cover ($past(rise) && $past(sh_axis) == N_AXES - 1);
        cover ($past(dir_change));
        cover (|rate_error_reg);
    end

    // With EXT_REQ (docs/spec/step_engine.md#requests-from-outside), stated on the ports:
    // under the sender's rules (two requests on one axis at least S clocks apart; every
    // increment zero while a request is on the port or not yet taken and in the clock
    // after, as the core keeps its DDAs idle then), every request on ext_req_* is taken
    // exactly once, by its axis's first shaper visit after it (within S clocks), with its
    // sign, never at a visit that also has a DDA request; none is made up; ext_pending is
    // "a request on the port or not yet taken". With the conservation above (position +
    // pending = the visits' requests) no request of the port is lost on its way to the pins.
    generate
        if (EXT_REQ != 0) begin : f_ext
            reg  [1:0]    f_cnt [0:N_AXES-1];   // requests of the port not yet taken, per axis
            reg  [N_AXES-1:0] f_neg;            // the last one's sign
            reg  [SL+1:0] f_age [0:N_AXES-1];   // clocks since the last request (saturating)
            reg           f_pending_prev;
            localparam [SL+1:0] F_AGE_MAX = {(SL+2){1'b1}};
            wire visit_held_reg_f = ext.visit_held_reg;
            wire [N_AXES-1:0] f_taken = sh_hot & {N_AXES{visit_held_reg_f}};
            reg  [SL-1:0] f_to_visit;           // clocks to the axis's next shaper visit
            reg  [N_AXES-1:0] f_out;
            integer g;
            always @(*) for (g = 0; g < N_AXES; g = g + 1) f_out[g] = (f_cnt[g] != 2'd0);
            always @(posedge clk) begin
                f_pending_prev <= !rst && ext_pending;
                for (g = 0; g < N_AXES; g = g + 1) begin
                    f_cnt[g] <= f_cnt[g] - {1'b0, f_taken[g]} + {1'b0, ext_req_valid[g]};
                    if (ext_req_valid[g]) f_neg[g] <= ext_req_negative[g];
                    f_age[g] <= ext_req_valid[g] ? {{(SL+1){1'b0}}, 1'b1} :
                                (f_age[g] == F_AGE_MAX) ? F_AGE_MAX : f_age[g] + 1'b1;
                    if (rst) begin
                        f_cnt[g] <= 2'd0;
                        f_age[g] <= F_AGE_MAX;
                    end
                end
            end
            always @(*) begin
                // The sender's rules, and no request in a reset clock.
                if (rst) assume (ext_req_valid == {N_AXES{1'b0}});
                for (g = 0; g < N_AXES; g = g + 1)
                    if (ext_req_valid[g]) assume (f_age[g] >= S);
                if (ext_pending || f_pending_prev) assume (inc == {32*N_AXES{1'b0}});
            end
            always @(*) if (f_past_valid && !rst) begin
                assert (ext_pending == ((|ext_req_valid) || (|f_out)));
                // Never two outstanding on an axis (none overwritten), none made up, and
                // a visit never takes a held request and a DDA request together.
                if (sh_visit && visit_held_reg_f) assert (f_out[sh_ix] && visit_req_negative == f_neg[sh_ix]);
                if (sh_visit) assert (!(req_valid_reg && visit_held_reg_f));
                if (!sh_visit) assert (!visit_held_reg_f);
                for (g = 0; g < N_AXES; g = g + 1) begin
                    assert (f_cnt[g] <= 2'd1);
                    assert (ext.held_reg[g] == f_out[g]);
                    if (f_out[g]) assert (ext.held_negative_reg[g] == f_neg[g]);
                    // The first visit of the axis takes it: the clocks it has waited and
                    // the clocks to the axis's next visit are at most S together.
                    f_to_visit = g[SL-1:0] - sh_axis;
                    if (f_out[g]) assert (f_age[g] >= 1 &&
                                          {{(32-SL){1'b0}}, f_to_visit} + {{(30-SL){1'b0}}, f_age[g]} <= S);
                    if (f_out[g] && sh_hot[g]) assert (f_taken[g]);
                end
            end
            always @(posedge clk) if (f_past_valid && !$past(rst) && !rst) begin
                cover (visit_held_reg_f && $past(ext_pending) && |ext_req_valid);
            end
        end
    endgenerate
`endif

endmodule

`default_nettype wire

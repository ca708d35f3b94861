`timescale 1ns / 1ps
`default_nettype none
// Specification: docs/spec/period_timer.md
// Period timer: cuts time into interpolation periods of P clocks and loads one period
// record (all axes' increments + flags) at each period boundary, so every axis changes
// increment on the same clock.
//
// A record taken at boundary cycle b is applied in cycles b+1 .. b+P; the next boundary
// is b+P. While run is low the timer is stopped, every increment is zero and P is
// sampled from period_clocks (0 acts as 1). A boundary with no valid record, or with an
// unacceptable one (some |D| >= P: more than one step per clock), runs an idle period
// (all increments zero); the latter sets the sticky record_error.
//
// P is sampled in every cycle before a run starts.
//
// With the shared step engine (SL > 0, S = 2^SL slots, `start_ok` = the engine's slot is
// S - 2): P is rounded down to a multiple of S (at least S), a run starts only when
// start_ok so that every boundary falls on slot S - 1, and a record is acceptable when
// every |D| < P / S (one step per visit). SL = 0 is the per-axis engine (start_ok tied 1).
// Invariants: remaining < p_act; every loaded increment satisfies |inc| < p_act * 2^16.
//
// AREA chooses the shape, not the behaviour (the same outputs on every clock): 0 for
// Fmax (a record check per main lane and one for the alternate lane, each three carry
// chains against registered bounds; the taken record masked on its way out by one
// flip-flop); 1 for area, the CPLD's (one check per lane of the offered record, whose
// lanes outside rec_alt_lane are zero and always pass, each one carry chain against the
// bound its sign and low half choose; the record zeroed at its load when not taken, by
// the flip-flops' synchronous reset, so no gate on the way out; one bound register,
// W = min(V - 1, 2^16), for every lane: floor(|d| / 2^16) >= V as one carry chain of
// d's high half, inverted for a negative d, and a carry in for a negative d with a zero
// low half, against W; the period counted from P down to 1, so no P - 1 register).
module period_timer #(
    parameter N_AXES  = 4,
    parameter P_WIDTH = 20,
    parameter SL      = 0,       // log2 of the step engine's slots; 0: per-axis engine
    parameter AREA    = 0,       // 1: shaped for area (see above); 0: for Fmax
    parameter HAS_ALT = 1        // 0: no alternate record (a build without the jog): rec_alt is 0
) (
    // clock, reset
    input  wire                 clk,
    input  wire                 rst,
    // control
    input  wire                 run,
    input  wire                 start_ok,      // a run may start in this cycle
    input  wire [P_WIDTH-1:0]   period_clocks,
    input  wire                 clear_errors,
    // record port (valid/ready)
    input  wire                 rec_valid,
    output wire                 rec_ready,
    input  wire [32*N_AXES-1:0] rec_inc,
    input  wire [7:0]           rec_flags,
    // The alternate record (the jog's): when rec_alt, the record offered is rec_alt_inc on
    // the lanes rec_alt_lane marks and zero on the others, in place of rec_inc. It is
    // checked by a carry chain of its own and chosen after the checks, so the select
    // (the jog's engagement) sits behind the record check, not in front of it.
    input  wire                 rec_alt,
    input  wire [N_AXES-1:0]    rec_alt_lane,
    input  wire [31:0]          rec_alt_inc,
    // to the DDAs
    output wire                 active,        // periods are running
    output wire [P_WIDTH-1:0]   p_active,
    output wire [32*N_AXES-1:0] inc,
    // status
    output wire                 block_end,
    output wire                 record_error
);

    // The record layout (FS_REC_*): I16F16 increments, the BLOCK_END flag.
`include "finestep_interface.vh"

    reg                 active_reg;
    reg [P_WIDTH-1:0]   remaining_reg;
    reg [P_WIDTH-1:0]   p_act_reg;
    reg [P_WIDTH-1:0]   p_act_minus_one_reg;
    // The record check's three bounds, from V = p_act / 2^SL (see below), loaded with p_act.
    reg [16:0]          bound_pos_reg;          // min(V, 2^16)
    reg [16:0]          bound_neg_reg;          // 2^16 - min(V, 2^16)
    reg [16:0]          bound_neg_zero_reg;     // 2^16 - min(V - 1, 2^16)
    reg [16:0]          bound_w_reg;            // min(V - 1, 2^16) (AREA 1's one bound)
    // The record taken at the last boundary (or zeros) and whether it was acceptable: the
    // check's result ends at one flip-flop, which masks the increments and the flag on
    // their way out (inc = the record if acceptable, else zeros), instead of steering the
    // load of every increment bit.
    reg [32*N_AXES-1:0] inc_reg;
    reg                 cur_end_reg;
    reg                 taken_ok_reg;
    wire                cur_end = cur_end_reg && taken_ok_reg;
    reg                 block_end_reg;
    reg                 record_error_reg;
    // active && remaining == 0, kept as a register: the boundary fans out across the
    // chip (FIFO pop, jog, latches), so it starts at a flip-flop, not a 20-bit compare.
    reg                 boundary_reg;

    wire boundary = boundary_reg;
    // AREA counts a period from P down to 1 (reloaded with p_act, stopped at 1), AREA 0
    // from P - 1 down to 0 (reloaded with p_act_minus_one): remaining - R_ONE is the
    // spec's remaining either way.
    localparam [P_WIDTH-1:0] R_ONE = (AREA != 0) ? {{(P_WIDTH-1){1'b0}}, 1'b1} : {P_WIDTH{1'b0}};
    wire [P_WIDTH-1:0] reload = (AREA != 0) ? p_act_reg : p_act_minus_one_reg;
    // max(P with its low SL bits cleared, 2^SL); with SL = 0, max(P, 1).
    localparam [P_WIDTH-1:0] P_MIN = {{(P_WIDTH-1){1'b0}}, 1'b1} << SL;
    wire [P_WIDTH-1:0] period_rounded = (period_clocks >> SL) << SL;
    wire [P_WIDTH-1:0] period_sampled =
        (period_rounded == {P_WIDTH{1'b0}}) ? P_MIN : period_rounded;
    // V = p_act / 2^SL visits per period; sat17(x) = min(x, 2^16).
    localparam [16:0] TWO_16 = 17'h1_0000;
    wire [P_WIDTH-1:0] visits_sampled = period_sampled >> SL;
    wire [P_WIDTH-1:0] visits_sampled_minus_one = visits_sampled - {{(P_WIDTH-1){1'b0}}, 1'b1};
    function [16:0] sat17;
        input [P_WIDTH-1:0] x;
        reg   [31:0]        wide;
        begin
            wide  = {{(32-P_WIDTH){1'b0}}, x};
            sat17 = (wide >= {15'd0, TWO_16}) ? TWO_16 : wide[16:0];
        end
    endfunction

    // A record is acceptable when every |D| < V, i.e. floor(|d| / 2^16) < V. With h =
    // d[31:16] (unsigned) and no negation or operand select on the way from the record:
    //   d >= 0:              floor(|d| / 2^16) = h,            fails when h >= V;
    //   d < 0, d[15:0] != 0: floor(|d| / 2^16) = 2^16 - 1 - h, fails when h < 2^16 - V;
    //   d < 0, d[15:0] == 0: floor(|d| / 2^16) = 2^16 - h,     fails when h < 2^16 - (V - 1).
    // As h < 2^16, V may be replaced by min(V, 2^16) in each test (and V - 1 by
    // min(V - 1, 2^16)) without changing its result; the three bounds are then 17-bit
    // registers and each test is one carry chain of h against a register. The sign and the
    // low-half zero test only choose between the three results.
    function lane_fails;          // the check of one increment d against the bounds
        input [31:0] d;
        input [16:0] b_pos, b_neg, b_neg_zero;
        reg   [15:0] whole_high;      // h = d[31:16]
        reg          low_zero;        // d[15:0] == 0
        begin
            whole_high = d[FS_REC_INC_FRAC_BITS +: 16];
            low_zero   = (d[FS_REC_INC_FRAC_BITS-1:0] == {FS_REC_INC_FRAC_BITS{1'b0}});
            lane_fails = d[31] ? (low_zero ? ({1'b0, whole_high} < b_neg_zero) : ({1'b0, whole_high} < b_neg))
                               : ({1'b0, whole_high} >= b_pos);
        end
    endfunction
    // The alternate record's select: a constant 0 without it (HAS_ALT 0: in a hierarchical
    // build the parent's tie-off would not reach in here, leaving the select's logic).
    wire alt = (HAS_ALT != 0) && rec_alt;
    // The record offered (loaded at a boundary: flip-flop to flip-flop through the select).
    reg [32*N_AXES-1:0] rec_offer;
    integer lane;
    always @* begin
        for (lane = 0; lane < N_AXES; lane = lane + 1)
            rec_offer[32*lane +: 32] = alt ? (rec_alt_lane[lane] ? rec_alt_inc : 32'd0) : rec_inc[32*lane +: 32];
    end
    // AREA's check, with W = min(V - 1, 2^16): floor(|d| / 2^16) is x = h (d >= 0), or
    // ~h + z for d < 0 (16 bits, z = 1 when the low half is zero: 2^16 - h; else
    // 2^16 - 1 - h), and fails when x + z >= V, i.e. x + z > W (x + z <= 2^16, so
    // replacing V - 1 by W changes no result): the carry out of x + ~W + z, one chain.
    wire [N_AXES-1:0] lane_fails_w;
    genvar w_lane;
    generate
        for (w_lane = 0; w_lane < N_AXES; w_lane = w_lane + 1) begin : w_check
            wire [31:0] d = rec_offer[32*w_lane +: 32];
            wire [17:0] sum = {2'b00, d[FS_REC_INC_FRAC_BITS +: 16] ^ {16{d[31]}}} + {1'b0, ~bound_w_reg} +
                              {17'd0, d[31] && (d[FS_REC_INC_FRAC_BITS-1:0] == {FS_REC_INC_FRAC_BITS{1'b0}})};
            assign lane_fails_w[w_lane] = sum[17];
            wire unused_sum = &{1'b0, sum[16:0]};
        end
    endgenerate
    // AREA 0: the main record's lanes, each against the three bounds.
    reg main_ok;
    // AREA 1: the offered record's lanes, each against its one bound.
    reg offer_ok;
    integer axis;
    always @* begin
        main_ok = 1'b1;
        offer_ok = 1'b1;
        for (axis = 0; axis < N_AXES; axis = axis + 1) begin
            if (AREA == 0 && lane_fails(rec_inc[32*axis +: 32], bound_pos_reg, bound_neg_reg, bound_neg_zero_reg))
                main_ok = 1'b0;
            if (AREA != 0 && lane_fails_w[axis])
                offer_ok = 1'b0;
        end
    end
    // The alternate record: its lanes are rec_alt_inc or zero, and a zero lane always
    // passes (h = 0 < min(V, 2^16), V >= 1).
    wire alt_ok = (AREA != 0) || !(|rec_alt_lane) ||
                  !lane_fails(rec_alt_inc, bound_pos_reg, bound_neg_reg, bound_neg_zero_reg);
    wire record_ok = (AREA != 0) ? offer_ok : (alt ? alt_ok : main_ok);

    wire take_record = boundary && rec_valid;

    always @(posedge clk) begin
        block_end_reg <= run && boundary && cur_end;
        // A record consumed while stopping is discarded unchecked (the abort case).
        if (take_record && run && !record_ok)
            record_error_reg <= 1'b1;
        else if (clear_errors)
            record_error_reg <= 1'b0;

        if (!run) begin
            active_reg    <= 1'b0;
            boundary_reg  <= 1'b0;
            remaining_reg <= R_ONE;
            inc_reg       <= {32*N_AXES{1'b0}};
            cur_end_reg   <= 1'b0;
            taken_ok_reg  <= 1'b0;
            p_act_reg     <= period_sampled;
            p_act_minus_one_reg <= period_sampled - {{(P_WIDTH-1){1'b0}}, 1'b1};
            bound_pos_reg       <= sat17(visits_sampled);
            bound_neg_reg       <= TWO_16 - sat17(visits_sampled);
            bound_neg_zero_reg  <= TWO_16 - sat17(visits_sampled_minus_one);
            bound_w_reg         <= sat17(visits_sampled_minus_one);
        end else if (!active_reg) begin
            active_reg   <= start_ok;
            boundary_reg <= start_ok;       // remaining is 0 while stopped
            p_act_reg    <= period_sampled;
            p_act_minus_one_reg <= period_sampled - {{(P_WIDTH-1){1'b0}}, 1'b1};
            bound_pos_reg       <= sat17(visits_sampled);
            bound_neg_reg       <= TWO_16 - sat17(visits_sampled);
            bound_neg_zero_reg  <= TWO_16 - sat17(visits_sampled_minus_one);
            bound_w_reg         <= sat17(visits_sampled_minus_one);
        end else if (!boundary) begin
            remaining_reg <= remaining_reg - {{(P_WIDTH-1){1'b0}}, 1'b1};
            boundary_reg  <= (remaining_reg == R_ONE + {{(P_WIDTH-1){1'b0}}, 1'b1});
        end else begin
            remaining_reg <= reload;
            boundary_reg  <= (reload == R_ONE);
            taken_ok_reg <= record_ok;
            if (take_record && (AREA == 0 || record_ok)) begin
                inc_reg     <= rec_offer;
                cur_end_reg <= rec_flags[FS_REC_FLAG_BLOCK_END_BIT];
            end else begin
                inc_reg     <= {32*N_AXES{1'b0}};
                cur_end_reg <= 1'b0;
            end
        end

        if (rst) begin
            active_reg       <= 1'b0;
            boundary_reg     <= 1'b0;
            remaining_reg    <= R_ONE;
            p_act_reg        <= P_MIN;
            p_act_minus_one_reg <= P_MIN - {{(P_WIDTH-1){1'b0}}, 1'b1};
            bound_pos_reg        <= 17'd1;                  // V = 1
            bound_neg_reg        <= TWO_16 - 17'd1;
            bound_neg_zero_reg   <= TWO_16;
            bound_w_reg          <= 17'd0;
            inc_reg          <= {32*N_AXES{1'b0}};
            cur_end_reg      <= 1'b0;
            taken_ok_reg     <= 1'b0;
            block_end_reg    <= 1'b0;
            record_error_reg <= 1'b0;
        end
    end

    assign rec_ready    = boundary;
    assign active       = active_reg;
    assign p_active     = p_act_reg;
    assign inc          = (AREA != 0 || taken_ok_reg) ? inc_reg : {32*N_AXES{1'b0}};
    assign block_end    = block_end_reg;
    assign record_error = record_error_reg;

`ifdef FORMAL
    // Every period lasts exactly P cycles, P only changes while stopped, and every
    // loaded increment is below one step per clock.
    reg f_past_valid;
    reg [P_WIDTH:0] f_since_boundary;
    reg             f_in_period;      // a boundary has passed since run rose
    initial f_past_valid = 1'b0;
    initial assume (rst);
    always @(posedge clk) f_past_valid <= 1'b1;
    always @(posedge clk) begin
        f_since_boundary <= (rst || !run || boundary) ? {{P_WIDTH{1'b0}}, 1'b1} : f_since_boundary + 1'b1;
        f_in_period <= !rst && run && (boundary || f_in_period);
    end

    // The spec's remaining (see R_ONE).
    wire [P_WIDTH-1:0] f_remaining = remaining_reg - R_ONE;
    integer f_axis;
    reg [31:0] f_magnitude, f_rec_magnitude;
    reg        f_record_ok;       // the definition: every floor(|d| / 2^16) < P
    integer f_rec_axis;
    always @(*) begin
        f_record_ok = 1'b1;
        for (f_rec_axis = 0; f_rec_axis < N_AXES; f_rec_axis = f_rec_axis + 1) begin
            f_rec_magnitude = rec_offer[32*f_rec_axis+31] ? (~rec_offer[32*f_rec_axis +: 32] + 32'd1) : rec_offer[32*f_rec_axis +: 32];
            if ({{P_WIDTH{1'b0}}, f_rec_magnitude[31:FS_REC_INC_FRAC_BITS]} >= {16'd0, p_act_reg >> SL}) f_record_ok = 1'b0;
        end
    end
    always @(*) if (f_past_valid && !rst) begin
        assert (p_act_minus_one_reg == p_act_reg - {{(P_WIDTH-1){1'b0}}, 1'b1});
        assert (bound_pos_reg == sat17(p_act_reg >> SL));
        assert (bound_neg_reg == TWO_16 - sat17(p_act_reg >> SL));
        assert (bound_neg_zero_reg == TWO_16 - sat17((p_act_reg >> SL) - {{(P_WIDTH-1){1'b0}}, 1'b1}));
        assert (bound_w_reg == sat17((p_act_reg >> SL) - {{(P_WIDTH-1){1'b0}}, 1'b1}));
        // With the shared engine a running period is a whole number of visits.
        if (active_reg && SL > 0) assert (((p_act_reg >> SL) << SL) == p_act_reg && (p_act_reg >> SL) != {P_WIDTH{1'b0}});
        assert (boundary_reg == (active_reg && f_remaining == {P_WIDTH{1'b0}}));
        assert (remaining_reg >= R_ONE);
        assert (record_ok == f_record_ok);
        assert (p_act_reg != {P_WIDTH{1'b0}});
        assert (f_remaining < p_act_reg);
        if (active_reg && !boundary) assert (f_in_period);
        if (f_in_period) assert (active_reg && f_since_boundary + {1'b0, f_remaining} == {1'b0, p_act_reg});
        if (!active_reg) assert (f_remaining == {P_WIDTH{1'b0}} && inc_reg == {32*N_AXES{1'b0}});
        for (f_axis = 0; f_axis < N_AXES; f_axis = f_axis + 1) begin
            f_magnitude = inc[32*f_axis+31] ? (~inc[32*f_axis +: 32] + 32'd1) : inc[32*f_axis +: 32];
            if (active_reg) assert ({{P_WIDTH{1'b0}}, f_magnitude[31:FS_REC_INC_FRAC_BITS]} < {16'd0, p_act_reg >> SL});
        end
    end
    always @(posedge clk) if (f_past_valid && !$past(rst) && !rst) begin
        if ($past(run) && $past(active_reg)) assert (p_act_reg == $past(p_act_reg));
        if (!$past(active_reg)) assert (p_act_reg == $past(period_sampled));
        // A run starts only when start_ok.
        if (!$past(active_reg) && active_reg) assert ($past(start_ok));
        // A boundary after a running period comes exactly P cycles after the last one.
        if (boundary && $past(active_reg) && $past(run) && !$past(boundary))
            assert (f_since_boundary == {1'b0, p_act_reg});
        // What the DDAs see after a boundary: the record if it was taken and acceptable,
        // else zeros (the last-period flag likewise); between boundaries it holds.
        if ($past(run) && $past(active_reg) && $past(boundary)) begin
            assert (inc == (($past(take_record) && $past(record_ok)) ? $past(rec_offer) : {32*N_AXES{1'b0}}));
            assert (cur_end == ($past(take_record) && $past(record_ok) && $past(rec_flags[FS_REC_FLAG_BLOCK_END_BIT])));
        end
        if ($past(run) && !$past(boundary)) assert (inc == $past(inc) && cur_end == $past(cur_end));
        if (!$past(run)) assert (inc == {32*N_AXES{1'b0}} && !cur_end);
        // The DDAs' first running cycle (run && active rose) has zero increments (the step
        // engine prepares its visits a cycle ahead and relies on it).
        if (!$past(run && active_reg) && run && active_reg) assert (inc == {32*N_AXES{1'b0}});
        if ($past(take_record && run) && !$past(record_ok)) assert (record_error_reg);
        if (!$past(record_error_reg) && !($past(take_record && run) && !$past(record_ok))) assert (!record_error_reg);
        if ($past(record_error_reg) && !$past(clear_errors)) assert (record_error_reg);
        cover (boundary && f_in_period && p_act_reg == 3 && $past(take_record, 3) && $past(record_ok, 3));
        cover (record_error_reg);
        // The alternate record refused where the main one would pass (the select counts).
        cover ($past(take_record && run && rec_alt && !alt_ok && main_ok) && record_error_reg);
        cover (block_end_reg);
    end
`endif

endmodule

`default_nettype wire

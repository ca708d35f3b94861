`timescale 1ns / 1ps
`default_nettype none
// Specification: docs/spec/pbp_interp.md
// Point-by-point comparison interpolator (the F-function method) for one axis pair:
// a line (end point relative to the start) or a circular arc (start relative to the
// centre, CW or CCW, in all four quadrants, crossing them), one decision every
// tick_div + 1 clocks, each a step request on exactly one axis, as dda_axis hands its
// requests to the step shaper. Line: a = |Xe|, b = |Ye|, F = a*j - b*i after i steps
// on X and j on Y; F >= 0 and a != 0 steps X (F -= b), else Y (F += a). Arc:
// F = x^2 + y^2 - R^2; F >= 0 steps the inward axis of the quadrant, else the other;
// a step s = +-1 on coordinate c makes F += 2*s*c + 1. A record ends after its decision
// count (line |Xe| + |Ye|, arc the record's count) with a done pulse.
//
// Latency: a record taken at the edge ending cycle n gives its first request in cycle
// n + tick_div + 2; then one every tick_div + 1 clocks; done with the last request.
// Invariants (proven, sim/formal/pbp_interp.sby): at most one axis per decision;
// decisions == count at done, never more; a line's F == a*j - b*i with i <= a, j <= b
// (so it ends at (Xe, Ye)); an arc's F == x^2 + y^2 - R^2 with |F| <= 2R + 1 (no
// overflow of F_W); no request while idle or in the clock after a halt.
module pbp_interp #(
    parameter COORD_W = 24,   // record coordinates, signed
    parameter DIV_W   = 16    // tick divider
) (
    // clock, reset
    input  wire                      clk,
    input  wire                      rst,
    // control
    input  wire                      halt,        // abort the record; no request
    input  wire [DIV_W-1:0]          tick_div,    // a decision every tick_div + 1 clocks
    // record (taken when rec_valid && rec_ready)
    input  wire                      rec_valid,
    output wire                      rec_ready,
    input  wire                      rec_arc,     // 1: arc, 0: line
    input  wire                      rec_cw,      // arc: clockwise
    input  wire [COORD_W-1:0]        rec_x,       // line: Xe; arc: start x - centre x
    input  wire [COORD_W-1:0]        rec_y,       // line: Ye; arc: start y - centre y
    input  wire [COORD_W+2:0]        rec_steps,   // arc: decisions (the host's arc_steps)
    // step requests to the shapers (axis 0 = X, 1 = Y), status
    output wire [1:0]                req_valid,
    output wire [1:0]                req_negative,
    output wire                      busy,
    output wire                      done,        // pulse with the last request
    // the motion of each axis (0 = X, 1 = Y) while busy, for the gantry: the direction
    // its next step would take, +1 (up) or -1 (down); neither on a line's axis of zero
    // coordinate (never stepped), and neither while not busy
    output wire [1:0]                move_up,
    output wire [1:0]                move_down
);

    // Widths: an arc's position reaches R + 1 < 2^COORD_W in magnitude (R <= sqrt(2) *
    // 2^(COORD_W-1)); |F| <= 2R + 1 < 2^(COORD_W+1) + 1 and F + 2|c| + 1 on the way fit
    // F_W signed bits; an arc takes at most 8R + 8 < 2^(COORD_W+3) decisions.
    localparam POS_W   = COORD_W + 1;
    localparam F_W     = COORD_W + 3;
    localparam COUNT_W = COORD_W + 3;
    localparam [COUNT_W-1:0] COUNT_ONE = {{(COUNT_W-1){1'b0}}, 1'b1};
    localparam [DIV_W-1:0]   DIV_ONE   = {{(DIV_W-1){1'b0}}, 1'b1};

    reg                      busy_reg;
    reg                      arc_reg;
    reg                      cw_reg;
    reg signed [POS_W-1:0]   x_reg;          // arc: position; line: |Xe|
    reg signed [POS_W-1:0]   y_reg;          // arc: position; line: |Ye|
    reg                      x_neg_reg;      // line: Xe < 0
    reg                      y_neg_reg;      // line: Ye < 0
    reg signed [F_W-1:0]     f_reg;
    reg [COUNT_W-1:0]        count_reg;      // decisions left
    reg [DIV_W-1:0]          div_reg;
    reg                      done_reg;
    reg [1:0]                req_valid_reg;
    reg [1:0]                req_negative_reg;

    // The record: a line's magnitudes and count.
    wire signed [POS_W-1:0] rec_x_ext = {rec_x[COORD_W-1], rec_x};
    wire signed [POS_W-1:0] rec_y_ext = {rec_y[COORD_W-1], rec_y};
    wire signed [POS_W-1:0] rec_x_abs = rec_x[COORD_W-1] ? -rec_x_ext : rec_x_ext;
    wire signed [POS_W-1:0] rec_y_abs = rec_y[COORD_W-1] ? -rec_y_ext : rec_y_ext;
    wire [COUNT_W-1:0] line_steps = {{(COUNT_W-POS_W){1'b0}}, rec_x_abs}
                                  + {{(COUNT_W-POS_W){1'b0}}, rec_y_abs};
    wire [COUNT_W-1:0] rec_count  = rec_arc ? rec_steps : line_steps;
    // rec_count == 0 from the fields themselves (|x| + |y| is 0 only with both 0: it
    // cannot wrap, COUNT_W >= POS_W), so that busy and done do not wait for the adder
    // (the record comes straight from the FIFO's head: this was the lathe build's path).
    wire rec_zero = rec_arc ? (rec_steps == {COUNT_W{1'b0}})
                            : (rec_x == {COORD_W{1'b0}} && rec_y == {COORD_W{1'b0}});

    // The quadrant: the signs of the steps along the arc (CCW along (-y, x), CW along
    // (y, -x)); on an axis the quadrant the motion enters decides.
    wire x_zero = (x_reg == {POS_W{1'b0}});
    wire y_zero = (y_reg == {POS_W{1'b0}});
    wire x_neg  = x_reg[POS_W-1];
    wire y_neg  = y_reg[POS_W-1];
    wire x_pos  = !x_neg && !x_zero;
    wire y_pos  = !y_neg && !y_zero;
    wire arc_x_negative = cw_reg ? !(y_pos || (y_zero && x_neg)) : (y_pos || (y_zero && x_pos));
    wire arc_y_negative = cw_reg ? (x_pos || (x_zero && y_pos)) : !(x_pos || (x_zero && y_neg));
    wire inward_x       = (x_pos && arc_x_negative) || (x_neg && !arc_x_negative);

    // The decision.
    wire f_nonneg = !f_reg[F_W-1];
    wire step_x   = arc_reg ? (f_nonneg ? inward_x : !inward_x) : (f_nonneg && !x_zero);
    wire step_neg = arc_reg ? (step_x ? arc_x_negative : arc_y_negative)
                            : (step_x ? x_neg_reg : y_neg_reg);

    // F's update. Arc: F + 2*s*c + 1 for the coordinate c stepped by s. Line: F - b on
    // X, F + a on Y (x_reg, y_reg hold a, b).
    wire signed [POS_W-1:0] coord     = step_x ? x_reg : y_reg;
    wire signed [F_W-1:0]   twice     = {{(F_W-POS_W-1){coord[POS_W-1]}}, coord, 1'b0};
    wire signed [F_W-1:0]   x_ext     = {{(F_W-POS_W){x_reg[POS_W-1]}}, x_reg};
    wire signed [F_W-1:0]   y_ext     = {{(F_W-POS_W){y_reg[POS_W-1]}}, y_reg};
    wire signed [F_W-1:0]   f_delta   = arc_reg ? ((step_neg ? -twice : twice) + {{(F_W-1){1'b0}}, 1'b1})
                                                : (step_x ? -y_ext : x_ext);
    wire signed [F_W-1:0]   f_next    = f_reg + f_delta;
    wire signed [POS_W-1:0] unit      = step_neg ? {POS_W{1'b1}} : {{(POS_W-1){1'b0}}, 1'b1};

    wire tick = (div_reg >= tick_div);

    always @(posedge clk) begin
        done_reg         <= 1'b0;
        req_valid_reg    <= 2'b00;
        req_negative_reg <= 2'b00;
        if (!busy_reg) begin
            if (rec_valid) begin
                arc_reg   <= rec_arc;
                cw_reg    <= rec_cw;
                x_reg     <= rec_arc ? rec_x_ext : rec_x_abs;
                y_reg     <= rec_arc ? rec_y_ext : rec_y_abs;
                x_neg_reg <= rec_x[COORD_W-1];
                y_neg_reg <= rec_y[COORD_W-1];
                f_reg     <= {F_W{1'b0}};
                count_reg <= rec_count;
                div_reg   <= {DIV_W{1'b0}};
                busy_reg  <= !rec_zero;
                done_reg  <= rec_zero;
            end
        end else if (tick) begin
            div_reg          <= {DIV_W{1'b0}};
            f_reg            <= f_next;
            count_reg        <= count_reg - COUNT_ONE;
            req_valid_reg    <= step_x ? 2'b01 : 2'b10;
            req_negative_reg <= step_x ? {1'b0, step_neg} : {step_neg, 1'b0};
            if (arc_reg && step_x) x_reg <= x_reg + unit;
            if (arc_reg && !step_x) y_reg <= y_reg + unit;
            if (count_reg == COUNT_ONE) begin
                busy_reg <= 1'b0;
                done_reg <= 1'b1;
            end
        end else begin
            div_reg <= div_reg + DIV_ONE;
        end

        if (halt) begin
            busy_reg         <= 1'b0;
            done_reg         <= 1'b0;
            req_valid_reg    <= 2'b00;
            req_negative_reg <= 2'b00;
        end
        if (rst) begin
            busy_reg         <= 1'b0;
            done_reg         <= 1'b0;
            req_valid_reg    <= 2'b00;
            req_negative_reg <= 2'b00;
            div_reg          <= {DIV_W{1'b0}};
        end
    end

    assign rec_ready    = !busy_reg;
    assign busy         = busy_reg;
    assign done         = done_reg;
    assign req_valid    = req_valid_reg;
    assign req_negative = req_negative_reg;
    // Registered state through gates: a line's signs and |Xe|, |Ye| != 0; an arc's
    // quadrant directions (both axes: an arc may step either).
    wire x_dir_neg = arc_reg ? arc_x_negative : x_neg_reg;
    wire y_dir_neg = arc_reg ? arc_y_negative : y_neg_reg;
    wire x_moves   = busy_reg && (arc_reg || !x_zero);
    wire y_moves   = busy_reg && (arc_reg || !y_zero);
    assign move_up   = {y_moves && !y_dir_neg, x_moves && !x_dir_neg};
    assign move_down = {y_moves && y_dir_neg, x_moves && x_dir_neg};


`ifdef FORMAL
    // Ghosts: the record's count, the decisions since it was taken; a line's steps i, j
    // on each axis; an arc's R^2. Products in FW bits (no overflow at the proof widths).
    localparam FW = 2 * POS_W + 4;
    reg                   f_past_valid;
    reg [COUNT_W:0]       f_total;
    reg [COUNT_W:0]       f_issued;
    reg [COUNT_W-1:0]     f_i;
    reg [COUNT_W-1:0]     f_j;
    reg signed [FW-1:0]   f_r2;
    reg                   f_crossed;      // an arc changed quadrant
    initial f_past_valid = 1'b0;
    initial assume (rst);
    always @(posedge clk) f_past_valid <= 1'b1;

    wire signed [FW-1:0] f_x   = {{(FW-POS_W){x_reg[POS_W-1]}}, x_reg};
    wire signed [FW-1:0] f_y   = {{(FW-POS_W){y_reg[POS_W-1]}}, y_reg};
    wire signed [FW-1:0] f_f   = {{(FW-F_W){f_reg[F_W-1]}}, f_reg};
    wire signed [FW-1:0] f_ii  = {{(FW-COUNT_W){1'b0}}, f_i};
    wire signed [FW-1:0] f_jj  = {{(FW-COUNT_W){1'b0}}, f_j};
    wire signed [FW-1:0] f_rx  = {{(FW-COORD_W){rec_x[COORD_W-1]}}, rec_x};
    wire signed [FW-1:0] f_ry  = {{(FW-COORD_W){rec_y[COORD_W-1]}}, rec_y};
    wire signed [FW-1:0] f_one = {{(FW-1){1'b0}}, 1'b1};
    wire                 f_take = !busy_reg && rec_valid;
    // R^2 of a start with coordinates in [-2^(COORD_W-1), 2^(COORD_W-1)).
    wire signed [FW-1:0] F_R2_MAX = {{(FW-2*COORD_W+1){1'b0}}, 1'b1, {(2*COORD_W-1){1'b0}}};

    // The host's domain: an arc's R^2 >= 2 (arc_steps refuses smaller).
    always @(*) if (f_take && rec_arc) assume (f_rx * f_rx + f_ry * f_ry >= 2 * f_one);

    always @(posedge clk) begin
        if (f_take) begin
            f_total  <= {1'b0, rec_count};
            f_issued <= {(COUNT_W+1){1'b0}};
            f_i      <= {COUNT_W{1'b0}};
            f_j      <= {COUNT_W{1'b0}};
            f_r2     <= f_rx * f_rx + f_ry * f_ry;
            f_crossed <= 1'b0;
        end else if (busy_reg && tick) begin
            f_issued <= f_issued + 1'b1;
            if (step_x) f_i <= f_i + 1'b1;
            else f_j <= f_j + 1'b1;
            if ((step_x && (x_zero || x_reg == -unit)) || (!step_x && (y_zero || y_reg == -unit)))
                f_crossed <= 1'b1;
        end
    end

    always @(*) if (f_past_valid && busy_reg) begin
        // Decisions: never more than the record's count.
        assert (count_reg != {COUNT_W{1'b0}});
        assert (f_issued + {1'b0, count_reg} == f_total);
        if (arc_reg) begin
            // F is x^2 + y^2 - R^2, and |F| <= 2R + 1: (|F| - 1)^2 <= 4 R^2.
            assert (f_f == f_x * f_x + f_y * f_y - f_r2);
            assert (f_f <= f_one || (f_f - f_one) * (f_f - f_one) <= 4 * f_r2);
            assert (-f_f <= f_one || (-f_f - f_one) * (-f_f - f_one) <= 4 * f_r2);
            assert (f_r2 >= 2 * f_one && f_r2 <= F_R2_MAX);
        end else begin
            // F is a*j - b*i, i <= a, j <= b, and the count is what is left of a + b.
            assert (!x_neg && !y_neg);
            assert (f_f == f_x * f_jj - f_y * f_ii);
            assert (f_ii <= f_x && f_jj <= f_y);
            assert (f_ii + f_jj + {{(FW-COUNT_W){1'b0}}, count_reg} == f_x + f_y);
            assert (f_total[COUNT_W-1:0] == x_reg + y_reg);
        end
    end

    always @(*) if (f_past_valid) begin
        assert (req_valid != 2'b11);               // one axis per decision
        // The motion shown: one direction at most per axis, none while not busy.
        assert ((move_up & move_down) == 2'b00);
        if (!busy_reg) assert (move_up == 2'b00 && move_down == 2'b00);
        // While busy the motion shown on the axis of the decision the state makes is its
        // direction (the request's, a clock later, as asserted below), so an axis showing
        // none (a line's of zero coordinate) is never stepped.
        if (busy_reg && step_x) assert (move_up[0] == !step_neg && move_down[0] == step_neg);
        if (busy_reg && !step_x) assert (move_up[1] == !step_neg && move_down[1] == step_neg);
        assert ((req_negative & ~req_valid) == 2'b00);
        assert (!(done && busy));
    end

    always @(posedge clk) if (f_past_valid && !$past(rst)) begin
        // A request only from a decision: busy, at the tick, not halted.
        if (req_valid != 2'b00) begin
            assert ($past(busy_reg) && $past(tick) && !$past(halt));
            assert (req_valid[0] == $past(step_x));
            assert (req_negative == (($past(step_x) ? 2'b01 : 2'b10) & {2{$past(step_neg)}}));
            // The F update is the formula's.
            if ($past(arc_reg))
                assert (f_reg == $past(f_reg) + ($past(step_neg) ? -$past(twice) : $past(twice)) + 1'b1);
            else
                assert (f_reg == ($past(step_x) ? $past(f_reg) - $past(y_reg) : $past(f_reg) + $past(x_reg)));
        end
        if (!$past(busy_reg) && !$past(rec_valid)) assert (req_valid == 2'b00 && !busy_reg);
        if ($past(halt)) assert (req_valid == 2'b00 && !busy_reg && !done);
        // done exactly when the count is reached: after the count's decisions, or at once
        // for a record of none.
        if (done) begin
            assert (!busy_reg);
            assert (($past(busy_reg) && $past(count_reg) == COUNT_ONE && req_valid != 2'b00)
                    || (!$past(busy_reg) && $past(rec_valid) && $past(rec_count) == {COUNT_W{1'b0}}));
        end
        if ($past(busy_reg) && !busy_reg && !$past(halt)) assert (done);
        // A line ends at its end point: i == a, j == b.
        if (done && $past(busy_reg) && !arc_reg) assert (f_i == {{(COUNT_W-POS_W){1'b0}}, x_reg} && f_j == {{(COUNT_W-POS_W){1'b0}}, y_reg});
        if (done && $past(busy_reg)) assert (f_issued == f_total);
        cover (done && !arc_reg && x_reg != 0 && y_reg != 0 && x_neg_reg && !y_neg_reg);
        cover (done && arc_reg && f_crossed && cw_reg);
        cover (done && arc_reg && f_crossed && !cw_reg);
        cover ($past(busy_reg) && $past(halt));
    end
`endif

endmodule

`default_nettype wire

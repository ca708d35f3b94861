`timescale 1ns / 1ps
`default_nettype none
// Specification: docs/spec/dda_axis.md
// DDA fine interpolator for one axis: spreads the period's signed Q16.16 increment d
// evenly over the P clocks of the period, one step request at a time.
//
// The accumulator counts position in units of 1/(P * 2^16) step, modulo M = P * 2^16:
// each clock acc + d wraps at most once (the period timer guarantees |d| < M), and a
// wrap upward or downward is a +1 or -1 step request. No division: P only sets the
// modulus. Until the period timer runs, acc sits at M/2, so the requests of a run sum to
// floor(T / M + 1/2): the commanded position rounded half up, with no drift.
//
// Latency: an update in cycle n gives req in cycle n+1.
// Invariant: 0 <= acc < M.
module dda_axis #(
    parameter P_WIDTH = 20
) (
    // clock, reset
    input  wire               clk,
    input  wire               rst,
    // control
    input  wire               run,             // the period timer is running
    input  wire [P_WIDTH-1:0] period_clocks,   // sampled while stopped
    input  wire [P_WIDTH-1:0] p_active,        // period of the running move
    input  wire [31:0]        inc,             // Q16.16 steps per period
    // step requests to the shaper
    output wire               req_valid,       // a step is requested this cycle
    output wire               req_negative     // its direction is negative
);

    localparam FRAC_BITS = 16;
    localparam ACC_W     = P_WIDTH + FRAC_BITS;
    localparam SUM_W     = ACC_W + 2;          // sign + one carry bit

    reg [ACC_W-1:0] acc_reg;
    reg             req_valid_reg;
    reg             req_negative_reg;

    wire [P_WIDTH-1:0] period_sampled =
        (period_clocks == {P_WIDTH{1'b0}}) ? {{(P_WIDTH-1){1'b0}}, 1'b1} : period_clocks;
    wire [ACC_W-1:0] half_modulus = {1'b0, period_sampled, {(FRAC_BITS-1){1'b0}}};

    // One update (dda_step): acc + d against M = P * 2^16.
    wire [ACC_W-1:0] acc_wrapped;
    wire             wrap_up, wrap_down;
    wire [SUM_W-1:0] sum;               // acc + d, for the formal section
    wire             unused_sum = &{1'b0, sum};
    dda_step #(.M_W(P_WIDTH)) update (
        .acc(acc_reg), .acc_minus_m({SUM_W{1'b0}}), .acc_plus_m({SUM_W{1'b0}}), .m(p_active), .inc(inc),
        .acc_next(acc_wrapped), .wrap_up(wrap_up), .wrap_down(wrap_down), .sum(sum)
    );

    always @(posedge clk) begin
        if (!run) begin
            acc_reg          <= half_modulus;
            req_valid_reg    <= 1'b0;
            req_negative_reg <= 1'b0;
        end else begin
            acc_reg          <= acc_wrapped;
            req_valid_reg    <= wrap_up || wrap_down;
            req_negative_reg <= wrap_down;
        end

        if (rst) begin
            acc_reg          <= {{(ACC_W-FRAC_BITS){1'b0}}, 1'b1, {(FRAC_BITS-1){1'b0}}};
            req_valid_reg    <= 1'b0;
            req_negative_reg <= 1'b0;
        end
    end

    assign req_valid    = req_valid_reg;
    assign req_negative = req_negative_reg;


`ifdef FORMAL
    // Proof of property (a): over a run, acc + M * (net requests) == M/2 + (sum of the
    // increments applied), with 0 <= acc < M; hence the net requests are exactly
    // floor(sum / M + 1/2), the commanded position rounded half up.
    localparam F_W = ACC_W + 24;
    reg f_past_valid;
    reg signed [F_W-1:0] f_applied;   // sum of increments applied since run rose
    reg signed [F_W-1:0] f_requested; // M * (net requests) since run rose
    initial f_past_valid = 1'b0;
    initial assume (rst);
    always @(posedge clk) f_past_valid <= 1'b1;

    wire signed [F_W-1:0] f_modulus = {{(F_W-ACC_W){1'b0}}, p_active, {FRAC_BITS{1'b0}}};
    wire signed [F_W-1:0] f_inc     = {{(F_W-SUM_W){sum[SUM_W-1]}}, sum} - {{(F_W-ACC_W){1'b0}}, acc_reg};

    // The environment of the period timer: P is latched while stopped and at reset,
    // constant while running, and every applied increment is below one step per clock.
    always @(*) begin
        assume (p_active != {P_WIDTH{1'b0}});
        if (run) assume (f_inc < f_modulus && -f_inc < f_modulus);
    end
    always @(posedge clk) if (f_past_valid) begin
        if ($past(rst)) begin
            assume (p_active == {{(P_WIDTH-1){1'b0}}, 1'b1});
        end else if (!$past(run)) begin
            assume (p_active == $past(period_sampled));
        end else begin
            assume (p_active == $past(p_active));
        end
    end

    always @(posedge clk) begin
        if (rst || !run) begin
            f_applied   <= {F_W{1'b0}};
            f_requested <= {F_W{1'b0}};
        end else begin
            f_applied   <= f_applied + f_inc;
            f_requested <= f_requested + (wrap_up ? f_modulus : {F_W{1'b0}})
                                       - (wrap_down ? f_modulus : {F_W{1'b0}});
        end
    end

    wire signed [F_W-1:0] f_half = {{(F_W-ACC_W+1){1'b0}}, p_active, {(FRAC_BITS-1){1'b0}}};
    always @(*) if (f_past_valid) begin
        assert ({2'b00, acc_reg} < {2'b00, p_active, {FRAC_BITS{1'b0}}});
        assert ({{(F_W-ACC_W){1'b0}}, acc_reg} + f_requested == f_half + f_applied);
    end
    always @(posedge clk) if (f_past_valid && !$past(rst)) begin
        // A request is the result of a wrap, and only while running.
        assert (req_valid == ($past(run) && ($past(wrap_up) || $past(wrap_down))));
        if (req_valid) assert (req_negative == $past(wrap_down));
        cover (req_valid && !req_negative);
        cover (req_valid && req_negative);
    end
`endif

endmodule

`default_nettype wire

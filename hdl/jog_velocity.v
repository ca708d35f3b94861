`timescale 1ns / 1ps
`default_nettype none
// The jog's velocity for the next period, computed sequentially in the 80 cycles after a
// period boundary (a period is thousands of clocks, so a shift-add multiplier and a
// digit-by-digit square root cost a few hundred flip-flops instead of a wide multiplier):
//   e = target - cmd
//   stopping:                        v' = clamp(0, vel - A, vel + A)
//   |e| <= min(VM, A), |e - vel| <= A: v' = e               (the last step, brakeable)
//   else u = max(isqrt(2 A min(|e|, 2^40 - 1)) - A, min(|e|, A))
//        v' = clamp(sign(e) min(VM, u), vel - A, vel + A)   (fastest speed that can stop)
// Inputs are sampled in the cycle after `restart`; `result_valid` is high in cycle 80
// after it, with `result`. A new `restart` or `drop` drops the computation in flight.
module jog_velocity (
    // clock, reset
    input  wire        clk,
    input  wire        rst,
    // control
    input  wire        restart,
    input  wire        drop,
    // operands, sampled in the cycle after restart
    input  wire [47:0] target,
    input  wire [47:0] cmd,
    input  wire [31:0] vel,
    input  wire        enable,
    input  wire [30:0] vmax,
    input  wire [30:0] accel,
    // result
    output wire        result_valid,
    output wire [31:0] result
);

    localparam [6:0] SAMPLE_AT   = 7'd1;
    localparam [6:0] MUL_LAST    = 7'd41;   // 40 multiply steps: cycles 2..41
    localparam [6:0] SQRT_LAST   = 7'd77;   // 36 root digits: cycles 42..77
    localparam [6:0] RESULT_AT   = 7'd80;
    localparam [39:0] E_SAT      = 40'hFF_FFFF_FFFF;

    reg        busy_reg;
    reg [6:0]  step_reg;        // cycles since the restart
    reg [47:0] e_reg;
    reg [31:0] vel_reg;
    reg        enable_reg;
    reg [30:0] vmax_reg;
    reg [30:0] accel_reg;
    reg [39:0] m_reg;           // multiplier bits, MSB first
    reg [71:0] prod_reg;        // 2 A m, then shifted out two bits per root digit
    reg [37:0] rem_reg;
    reg [35:0] root_reg;

    // Sampling: |e| saturated to 40 bits.
    wire [47:0] e_now     = target - cmd;
    wire [47:0] e_abs_now = e_now[47] ? -e_now : e_now;
    wire [39:0] m_now     = (e_abs_now > {8'd0, E_SAT}) ? E_SAT : e_abs_now[39:0];

    // One root digit.
    wire [39:0] rem_shifted = {rem_reg[37:0], prod_reg[71:70]};
    wire [39:0] trial       = {2'b00, root_reg, 2'b01};
    wire        digit       = (rem_shifted >= trial);
    // The remainder stays below 2 root + 1 < 2^37.
    wire [39:0] rem_difference = rem_shifted - trial;

    // The result, from the root and the sampled operands (35-bit signed arithmetic).
    wire signed [34:0] vel_s   = {{3{vel_reg[31]}}, vel_reg};
    wire signed [34:0] accel_s = {4'd0, accel_reg};
    wire signed [36:0] u_full  = $signed({1'b0, root_reg}) - $signed({6'd0, accel_reg});
    wire        [47:0] e_abs   = e_reg[47] ? -e_reg : e_reg;
    wire        [30:0] e_or_a  = (e_abs < {17'd0, accel_reg}) ? e_abs[30:0] : accel_reg;   // min(|e|, A)
    wire        [35:0] u       = (u_full < $signed({6'd0, e_or_a})) ? {5'd0, e_or_a} : u_full[35:0];
    wire        [30:0] speed   = (u > {5'd0, vmax_reg}) ? vmax_reg : u[30:0];
    wire        e_neg   = e_reg[47];
    wire        e_zero  = (e_reg == 48'd0);
    wire signed [34:0] desired = !enable_reg ? 35'sd0 :
                                 e_zero ? 35'sd0 :
                                 e_neg ? -$signed({4'd0, speed}) : $signed({4'd0, speed});
    wire signed [34:0] lo      = vel_s - accel_s;
    wire signed [34:0] hi      = vel_s + accel_s;
    wire signed [34:0] clamped = (desired < lo) ? lo : (desired > hi) ? hi : desired;
    wire        e_small = (e_abs <= {17'd0, vmax_reg}) && (e_abs <= {17'd0, accel_reg});
    // With |e| <= min(VM, A) < 2^31 the low 35 bits of e are e itself.
    wire signed [34:0] e_s       = e_reg[34:0];
    wire signed [34:0] e_minus_v = e_s - vel_s;
    wire        arrive  = enable_reg && e_small &&
                          (e_minus_v <= accel_s) && (e_minus_v >= -accel_s);
    wire signed [34:0] chosen  = arrive ? e_s : clamped;

    always @(posedge clk) begin
        if (busy_reg) step_reg <= step_reg + 7'd1;
        if (busy_reg && step_reg == SAMPLE_AT) begin
            e_reg      <= e_now;
            vel_reg    <= vel;
            enable_reg <= enable;
            vmax_reg   <= vmax;
            accel_reg  <= accel;
            m_reg      <= m_now;
            prod_reg   <= 72'd0;
            rem_reg    <= 38'd0;
            root_reg   <= 36'd0;
        end
        if (busy_reg && step_reg > SAMPLE_AT && step_reg <= MUL_LAST) begin
            prod_reg <= {prod_reg[70:0], 1'b0} + (m_reg[39] ? {40'd0, accel_reg, 1'b0} : 72'd0);
            m_reg    <= {m_reg[38:0], 1'b0};
        end
        if (busy_reg && step_reg > MUL_LAST && step_reg <= SQRT_LAST) begin
            rem_reg  <= digit ? rem_difference[37:0] : rem_shifted[37:0];
            root_reg <= {root_reg[34:0], digit};
            prod_reg <= {prod_reg[69:0], 2'b00};
        end
        if (busy_reg && step_reg == RESULT_AT) busy_reg <= 1'b0;
        if (restart) begin
            busy_reg <= 1'b1;
            step_reg <= SAMPLE_AT;
        end
        if (drop) busy_reg <= 1'b0;
        if (rst) begin
            busy_reg   <= 1'b0;
            step_reg   <= 7'd0;
            e_reg      <= 48'd0;
            vel_reg    <= 32'd0;
            enable_reg <= 1'b0;
            vmax_reg   <= 31'd0;
            accel_reg  <= 31'd0;
            m_reg      <= 40'd0;
            prod_reg   <= 72'd0;
            rem_reg    <= 38'd0;
            root_reg   <= 36'd0;
        end
    end

    assign result_valid = busy_reg && (step_reg == RESULT_AT) && !restart && !drop;
    assign result       = chosen[31:0];
    wire unused_velocity = &{1'b0, chosen[34:32], rem_difference[39:38], rem_shifted[39:38]};

`ifdef FORMAL
    // Whatever the root digits are, the result changes the velocity by at most A and is
    // no faster than max(VM, |vel|) (all as sampled): the jog's limits hold by
    // construction of the clamp, not by the square root being right (the co-simulation
    // checks that against the model's exact integer square root). A result comes only
    // in cycle 80 after a restart. (No cover here: reaching a result takes 80 cycles of
    // BMC; the co-simulation runs thousands.)
    reg f_past_valid;
    initial f_past_valid = 1'b0;
    initial assume (rst);
    always @(posedge clk) f_past_valid <= 1'b1;
    wire signed [34:0] vmax_s     = {4'd0, vmax_reg};
    wire signed [34:0] f_step     = chosen - vel_s;
    wire signed [34:0] f_abs_res  = chosen[34] ? -chosen : chosen;
    wire signed [34:0] f_abs_vel  = vel_s[34] ? -vel_s : vel_s;
    always @(*) if (f_past_valid && !rst) begin
        assert (f_step <= accel_s && f_step >= -accel_s);
        assert (f_abs_res <= vmax_s || f_abs_res <= f_abs_vel);
        assert (chosen == {{3{chosen[31]}}, chosen[31:0]});
        if (busy_reg) assert (step_reg >= SAMPLE_AT && step_reg <= RESULT_AT);
    end
    always @(posedge clk) if (f_past_valid && !$past(rst) && !rst) begin
        if ($past(restart) && !$past(drop)) assert (busy_reg && step_reg == SAMPLE_AT);
    end
`endif

endmodule

`default_nettype wire

`timescale 1ns / 1ps
`default_nettype none
// Specification: docs/spec/jog_generator.md ("Computation")
// The jog's velocity for the next period, computed sequentially in the 80 cycles after a
// period boundary (a period is thousands of clocks, so a radix-4 shift-add multiplier, a
// digit-by-digit square root and a pipelined clamp cost a few hundred flip-flops instead
// of wide multipliers and long carry chains):
//   e = target - cmd
//   stopping:                        v' = clamp(0, vel - A, vel + A)
//   |e| <= min(VM, A), |e - vel| <= A: v' = e               (the last step, brakeable)
//   else u = max(isqrt(2 A min(|e|, 2^40 - 1)) - A, min(|e|, A))
//        v' = clamp(sign(e) min(VM, u), vel - A, vel + A)   (fastest speed that can stop)
// Inputs are sampled in the cycle after `restart`; `result_valid` is high in cycle 80
// after it, with `result`. A new `restart` or `drop` drops the computation in flight.
// Schedule (cycles after the restart): 1 sample; 2-3 operands; 4-23 multiply; 24-59
// square root; 60-63 one carry chain per cycle to the result; 80 result.
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
    // result
    output wire        result_valid,
    output wire [31:0] result
);

    localparam [6:0] SAMPLE_AT  = 7'd1;
    localparam [6:0] PREPARE_AT = 7'd2;
    localparam [6:0] OPERAND_AT = 7'd3;
    localparam [6:0] MUL_LAST   = 7'd23;   // 20 radix-4 multiply steps: 4..23
    localparam [6:0] SQRT_LAST  = 7'd59;   // 36 root digits: 24..59
    localparam [6:0] U_AT       = 7'd60;
    localparam [6:0] SPEED_AT   = 7'd61;
    localparam [6:0] DESIRED_AT = 7'd62;
    localparam [6:0] CHOSEN_AT  = 7'd63;
    localparam [6:0] RESULT_AT  = 7'd80;
    localparam [39:0] E_SAT     = 40'hFF_FFFF_FFFF;

    reg        busy_reg;
    reg [6:0]  step_reg;        // cycles since the restart
    // sampled operands
    reg [47:0] e_reg;
    reg [31:0] vel_reg;
    reg        enable_reg;
    reg [30:0] vmax_reg;
    reg [30:0] accel_reg;
    // derived operands
    reg [47:0]        e_abs_reg;
    reg signed [34:0] lo_reg, hi_reg;        // vel -+ A
    reg signed [34:0] e_minus_v_reg;         // e - vel (low 35 bits of e)
    reg [33:0]        six_a_reg;             // 6 A, the radix-4 digit 3 times 2 A
    reg [39:0]        m_reg;                 // min(|e|, 2^40 - 1), MSB first
    reg [30:0]        e_or_a_reg;            // min(|e|, A)
    reg               arrive_reg;
    // multiplier and root
    reg [71:0] prod_reg;        // 2 A m, then shifted out two bits per root digit
    reg [37:0] rem_reg;
    reg [35:0] root_reg;
    // the pipelined end
    reg [35:0]        u_reg;
    reg [30:0]        speed_reg;
    reg signed [34:0] desired_reg;
    reg signed [34:0] chosen_reg;

    wire signed [34:0] vel_s   = {{3{vel_reg[31]}}, vel_reg};
    wire signed [34:0] accel_s = {4'd0, accel_reg};
    wire signed [34:0] e_s     = e_reg[34:0];

    // One radix-4 multiply step: the top two bits of m select 0, 2A, 4A or 6A.
    wire [33:0] two_a  = {2'b00, accel_reg, 1'b0};
    wire [33:0] four_a = {1'b0, accel_reg, 2'b00};
    wire [33:0] digit_product = (m_reg[39:38] == 2'd0) ? 34'd0 :
                                (m_reg[39:38] == 2'd1) ? two_a :
                                (m_reg[39:38] == 2'd2) ? four_a : six_a_reg;

    // One root digit. The remainder stays below 2 root + 1 < 2^37.
    wire [39:0] rem_shifted    = {rem_reg, prod_reg[71:70]};
    wire [39:0] trial          = {2'b00, root_reg, 2'b01};
    wire        digit          = (rem_shifted >= trial);
    wire [39:0] rem_difference = rem_shifted - trial;

    // The end, one carry chain per stage.
    wire signed [36:0] u_full  = $signed({1'b0, root_reg}) - $signed({6'd0, accel_reg});
    wire        [35:0] u_now   = (u_full < $signed({6'd0, e_or_a_reg})) ? {5'd0, e_or_a_reg} : u_full[35:0];
    wire        [30:0] speed   = (u_reg > {5'd0, vmax_reg}) ? vmax_reg : u_reg[30:0];
    wire signed [34:0] desired = (!enable_reg || e_abs_reg == 48'd0) ? 35'sd0 :
                                 e_reg[47] ? -$signed({4'd0, speed_reg}) : $signed({4'd0, speed_reg});
    wire signed [34:0] clamped = (desired_reg < lo_reg) ? lo_reg : (desired_reg > hi_reg) ? hi_reg : desired_reg;

    always @(posedge clk) begin
        if (busy_reg) step_reg <= step_reg + 7'd1;
        if (busy_reg && step_reg == SAMPLE_AT) begin
            e_reg      <= distance;
            vel_reg    <= vel;
            enable_reg <= enable;
            vmax_reg   <= vmax;
            accel_reg  <= accel;
        end
        if (busy_reg && step_reg == PREPARE_AT) begin
            e_abs_reg     <= e_reg[47] ? -e_reg : e_reg;
            lo_reg        <= vel_s - accel_s;
            hi_reg        <= vel_s + accel_s;
            e_minus_v_reg <= e_s - vel_s;
            six_a_reg     <= four_a + two_a;
        end
        if (busy_reg && step_reg == OPERAND_AT) begin
            m_reg      <= (e_abs_reg > {8'd0, E_SAT}) ? E_SAT : e_abs_reg[39:0];
            e_or_a_reg <= (e_abs_reg < {17'd0, accel_reg}) ? e_abs_reg[30:0] : accel_reg;
            arrive_reg <= enable_reg && (e_abs_reg <= {17'd0, vmax_reg}) && (e_abs_reg <= {17'd0, accel_reg}) &&
                          (e_minus_v_reg <= accel_s) && (e_minus_v_reg >= -accel_s);
            prod_reg   <= 72'd0;
            rem_reg    <= 38'd0;
            root_reg   <= 36'd0;
        end
        if (busy_reg && step_reg > OPERAND_AT && step_reg <= MUL_LAST) begin
            prod_reg <= {prod_reg[69:0], 2'b00} + {38'd0, digit_product};
            m_reg    <= {m_reg[37:0], 2'b00};
        end
        if (busy_reg && step_reg > MUL_LAST && step_reg <= SQRT_LAST) begin
            rem_reg  <= digit ? rem_difference[37:0] : rem_shifted[37:0];
            root_reg <= {root_reg[34:0], digit};
            prod_reg <= {prod_reg[69:0], 2'b00};
        end
        if (busy_reg && step_reg == U_AT) u_reg <= u_now;
        if (busy_reg && step_reg == SPEED_AT) speed_reg <= speed;
        if (busy_reg && step_reg == DESIRED_AT) desired_reg <= desired;
        if (busy_reg && step_reg == CHOSEN_AT) chosen_reg <= arrive_reg ? e_s : clamped;
        if (busy_reg && step_reg == RESULT_AT) busy_reg <= 1'b0;
        if (restart) begin
            busy_reg <= 1'b1;
            step_reg <= SAMPLE_AT;
        end
        if (drop) busy_reg <= 1'b0;
        if (rst) begin
            busy_reg      <= 1'b0;
            step_reg      <= 7'd0;
            e_reg         <= 48'd0;
            vel_reg       <= 32'd0;
            enable_reg    <= 1'b0;
            vmax_reg      <= 31'd0;
            accel_reg     <= 31'd0;
            e_abs_reg     <= 48'd0;
            lo_reg        <= 35'sd0;
            hi_reg        <= 35'sd0;
            e_minus_v_reg <= 35'sd0;
            six_a_reg     <= 34'd0;
            m_reg         <= 40'd0;
            e_or_a_reg    <= 31'd0;
            arrive_reg    <= 1'b0;
            prod_reg      <= 72'd0;
            rem_reg       <= 38'd0;
            root_reg      <= 36'd0;
            u_reg         <= 36'd0;
            speed_reg     <= 31'd0;
            desired_reg   <= 35'sd0;
            chosen_reg    <= 35'sd0;
        end
    end

    assign result_valid = busy_reg && (step_reg == RESULT_AT) && !restart && !drop;
    assign result       = chosen_reg[31:0];
    wire unused_velocity = &{1'b0, chosen_reg[34:32], rem_difference[39:38], rem_shifted[39:38], u_full[36]};

`ifdef FORMAL
    // Whatever the root digits are, the result changes the velocity by at most A and is
    // no faster than max(VM, |vel|) (all as sampled): the jog's limits hold by the
    // clamp and the arrive test, not by the square root being right (the co-simulation
    // checks that against the model's exact integer square root). The pipeline's
    // registers are proven to hold what their stage computed from the sampled operands,
    // which stay put while the computation runs. A result comes only in cycle 80.
    // (No cover: reaching a result takes 80 cycles of BMC; the co-simulation runs
    // thousands.)
    reg f_past_valid;
    initial f_past_valid = 1'b0;
    initial assume (rst);
    always @(posedge clk) f_past_valid <= 1'b1;
    wire signed [34:0] vmax_s       = {4'd0, vmax_reg};
    wire signed [34:0] f_abs_vel    = vel_s[34] ? -vel_s : vel_s;
    wire signed [34:0] f_step       = chosen_reg - vel_s;
    wire signed [34:0] f_abs_chosen = chosen_reg[34] ? -chosen_reg : chosen_reg;
    wire signed [34:0] f_abs_desired = desired_reg[34] ? -desired_reg : desired_reg;
    always @(*) if (f_past_valid && !rst && busy_reg) begin
        assert (step_reg >= SAMPLE_AT && step_reg <= RESULT_AT);
        if (step_reg > PREPARE_AT) begin
            assert (e_abs_reg == (e_reg[47] ? -e_reg : e_reg));
            assert (lo_reg == vel_s - accel_s && hi_reg == vel_s + accel_s);
            assert (e_minus_v_reg == e_s - vel_s);
        end
        if (step_reg > OPERAND_AT && arrive_reg)
            assert (e_abs_reg <= {17'd0, vmax_reg} && e_abs_reg <= {17'd0, accel_reg} &&
                    e_minus_v_reg <= accel_s && e_minus_v_reg >= -accel_s);
        if (step_reg > SPEED_AT) assert (speed_reg <= vmax_reg);
        if (step_reg > DESIRED_AT) assert (f_abs_desired <= vmax_s);
        if (step_reg > CHOSEN_AT) begin
            assert (f_step <= accel_s && f_step >= -accel_s);
            assert (f_abs_chosen <= vmax_s || f_abs_chosen <= f_abs_vel);
            assert (chosen_reg == {{3{chosen_reg[31]}}, chosen_reg[31:0]});
        end
    end
    always @(posedge clk) if (f_past_valid && !$past(rst) && !rst) begin
        if ($past(restart) && !$past(drop)) assert (busy_reg && step_reg == SAMPLE_AT);
        if (busy_reg && step_reg > PREPARE_AT) assert ($stable(e_reg) && $stable(vel_reg) && $stable(accel_reg) &&
                                                      $stable(vmax_reg) && $stable(enable_reg));
    end
`endif

endmodule

`default_nettype wire

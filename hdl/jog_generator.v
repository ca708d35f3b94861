`timescale 1ns / 1ps
`default_nettype none
// Jog generator: moves one axis after the hand wheel, through the core. While engaged it
// is the core's record source: one record a period carrying `next_vel` on the jogged
// axis, so the DDA, the step timing, the rate checks and the step position serve the jog
// as they serve streamed motion. Detents move a target (x1/x10/x100 of JOG_SCALE);
// jog_velocity chases it within JOG_VMAX and JOG_ACCEL and lands on it exactly. In drop
// mode a detent that would put the target more than JOG_WINDOW from the commanded
// position is dropped and counted; in follow mode every detent is followed, later.
// The jog engages only while RUN is 0: the jog and the FIFO never drive the core at once.
module jog_generator #(
    parameter N_AXES  = 4,
    parameter P_WIDTH = 20
) (
    // clock, reset
    input  wire                 clk,
    input  wire                 rst,
    // configuration
    input  wire                 enable,
    input  wire [2:0]           axis_select,
    input  wire [1:0]           multiplier,
    input  wire                 follow,
    input  wire [31:0]          scale,
    input  wire [30:0]          vmax,
    input  wire [30:0]          accel,
    input  wire [15:0]          window,
    input  wire [P_WIDTH-1:0]   period_clocks,
    // machine state and commands
    input  wire                 run,              // CONTROL.RUN
    input  wire                 run_write_one,    // a write of CONTROL with RUN = 1 is served
    input  wire                 halt,
    input  wire                 rec_ready,        // the core's period boundary
    input  wire                 clear_errors,
    input  wire                 clear_counters,
    input  wire [31:0]          detents,
    // record to the core and state
    output wire [32*N_AXES-1:0] rec_inc,
    output wire                 engaged,
    output wire                 stopping,
    output wire                 refused,
    output wire [15:0]          dropped,
    output wire [31:0]          remaining,
    output wire [31:0]          velocity
);

    localparam MIN_PERIOD = 128;

    reg         engaged_reg;
    reg  [2:0]  axis_reg;
    reg  [47:0] target_reg;
    reg  [47:0] cmd_reg;
    reg  [31:0] vel_reg;
    reg  [31:0] next_vel_reg;
    reg  [31:0] last_det_reg;
    reg  [15:0] dropped_reg;
    reg         refused_reg;

    wire [31:0] delta      = detents - last_det_reg;
    wire        det_up     = (delta == 32'd1);
    wire        det_down   = (delta == 32'hFFFF_FFFF);
    wire        period_ok  = ({{(32-P_WIDTH){1'b0}}, period_clocks} >= MIN_PERIOD);
    wire        axis_ok    = ({29'd0, axis_select} < N_AXES);
    wire        engage     = !engaged_reg && enable && !run && !halt && period_ok && axis_ok;
    wire        boundary   = engaged_reg && rec_ready;
    wire        disengage  = boundary && !enable && (vel_reg == 32'd0) && (next_vel_reg == 32'd0);

    // Travel of one detent: scale times 1, 10 or 100 (shift-adds), sign-extended.
    wire [47:0] scale_x1   = {{16{scale[31]}}, scale};
    wire [47:0] scale_x10  = (scale_x1 << 3) + (scale_x1 << 1);
    wire [47:0] scale_x100 = (scale_x1 << 6) + (scale_x1 << 5) + (scale_x1 << 2);
    wire [47:0] detent_travel = (multiplier == 2'd0) ? scale_x1 :
                                (multiplier == 2'd1) ? scale_x10 : scale_x100;
    wire [47:0] candidate  = det_up ? target_reg + detent_travel : target_reg - detent_travel;
    wire [47:0] gap        = candidate - cmd_reg;
    wire [47:0] gap_abs    = gap[47] ? -gap : gap;
    wire        in_window  = (gap_abs <= {16'd0, window, 16'd0});
    wire        detent_now = engaged_reg && enable && (det_up || det_down);

    wire        result_valid;
    wire [31:0] result;
    jog_velocity velocity_calc (
        .clk(clk), .rst(rst),
        .restart(boundary && !disengage), .drop(halt || disengage),
        .target(target_reg), .cmd(cmd_reg), .vel(vel_reg), .enable(enable),
        .vmax(vmax), .accel(accel),
        .result_valid(result_valid), .result(result)
    );

    always @(posedge clk) begin
        last_det_reg <= detents;

        if (detent_now) begin
            if (follow || in_window) target_reg <= candidate;
            else dropped_reg <= dropped_reg + 16'd1;
        end
        if (clear_counters) dropped_reg <= 16'd0;

        if (result_valid) next_vel_reg <= result;
        if (boundary) begin
            cmd_reg <= cmd_reg + {{16{next_vel_reg[31]}}, next_vel_reg};
            vel_reg <= next_vel_reg;
        end
        if (disengage) engaged_reg <= 1'b0;

        if (engage) begin
            engaged_reg <= 1'b1;
            axis_reg    <= axis_select;
        end

        if ((enable && run) || (enable && !engaged_reg && (!period_ok || !axis_ok)) ||
            (run_write_one && engaged_reg))
            refused_reg <= 1'b1;
        else if (clear_errors)
            refused_reg <= 1'b0;

        if (halt) engaged_reg <= 1'b0;
        // Engaging starts from rest at position 0; a halt leaves the jog there.
        if (engage || halt) begin
            target_reg   <= 48'd0;
            cmd_reg      <= 48'd0;
            vel_reg      <= 32'd0;
            next_vel_reg <= 32'd0;
        end
        if (rst) begin
            engaged_reg  <= 1'b0;
            axis_reg     <= 3'd0;
            target_reg   <= 48'd0;
            cmd_reg      <= 48'd0;
            vel_reg      <= 32'd0;
            next_vel_reg <= 32'd0;
            last_det_reg <= 32'd0;
            dropped_reg  <= 16'd0;
            refused_reg  <= 1'b0;
        end
    end

    genvar i;
    generate
        for (i = 0; i < N_AXES; i = i + 1) begin : record
            assign rec_inc[32*i +: 32] = (axis_reg == i) ? next_vel_reg : 32'd0;
        end
    endgenerate

    wire [47:0] remaining_full = target_reg - cmd_reg;
    assign engaged   = engaged_reg;
    assign stopping  = engaged_reg && !enable;
    assign refused   = refused_reg;
    assign dropped   = dropped_reg;
    assign remaining = remaining_full[47:16];
    wire unused_jog = &{1'b0, remaining_full[15:0]};

`ifdef FORMAL
    // Arbitration and bookkeeping: the jog engages only when asked, with RUN low, not
    // halted and a usable period and axis; a halt leaves it disengaged at rest; the
    // target moves by exactly one detent's travel and only on a followed detent; a
    // dropped detent is counted; a disengaged jog offers zero increments.
    reg f_past_valid;
    initial f_past_valid = 1'b0;
    initial assume (rst);
    always @(posedge clk) f_past_valid <= 1'b1;
    reg  [47:0] f_prev_target;
    always @(posedge clk) f_prev_target <= target_reg;
    wire [47:0] f_move = target_reg - f_prev_target;
    always @(posedge clk) if (f_past_valid && !$past(rst) && !rst) begin
        if (engaged_reg && !$past(engaged_reg))
            assert ($past(enable) && !$past(run) && !$past(halt) && $past(period_ok) && $past(axis_ok));
        if ($past(halt)) assert (!engaged_reg && vel_reg == 32'd0 && next_vel_reg == 32'd0 && cmd_reg == 48'd0);
        if ($past(enable && run)) assert (refused_reg);
        if (!$past(engage) && !$past(halt) && target_reg != $past(target_reg))
            assert ($past(detent_now) && (f_move == $past(detent_travel) || f_move == -$past(detent_travel)));
        if (!$past(engage) && !$past(halt) && !$past(clear_counters) && $past(detent_now) && !$past(follow) &&
            !$past(in_window))
            assert (dropped_reg == $past(dropped_reg) + 16'd1 && target_reg == $past(target_reg));
        if (!$past(boundary) && !$past(engage) && !$past(halt)) assert (cmd_reg == $past(cmd_reg) && vel_reg == $past(vel_reg));
        if ($past(boundary) && !$past(engage) && !$past(halt)) assert (vel_reg == $past(next_vel_reg));
        cover (engaged_reg && target_reg != 48'd0);
        cover ($past(engaged_reg) && !engaged_reg && !$past(halt));
    end
    always @(*) if (f_past_valid && !rst && !engaged_reg) assert (rec_inc == {32*N_AXES{1'b0}} || next_vel_reg != 32'd0);
`endif
    assign velocity  = vel_reg;


endmodule

`default_nettype wire

`timescale 1ns / 1ps
`default_nettype none
// Specification: docs/spec/step_shaper.md
// Step shaper for one axis: turns the DDA's step requests into step/dir (or up/down, or
// quadrature) pulses that honour the drive's timing, as hostmot2's stepgen does: step
// high exactly L clocks, low at least S clocks, dir stable H clocks after a falling
// edge and U clocks before a rising edge. A step is delayed when the timing demands it,
// never dropped or shortened: requests wait in a signed pending count, where requests
// of opposite sign cancel. Falling behind by two steps sets the sticky rate_error;
// a pending count beyond +-127 is clamped and sets the sticky step_lost.
//
// halt (a safety fault): no new rise or direction change, pending steps are dropped,
// a pulse already high still lasts its full L (a runt pulse is ambiguous to a drive),
// and the enable pin goes inactive.
//
// Latency: a request in cycle n rises the step level in n+1 at the earliest; the pins
// are flip-flops one cycle behind the level.
// Invariants: the timing rules above hold on the pins for any input sequence.
module step_shaper #(
    parameter TIMING_W = 12
) (
    // clock, reset
    input  wire                clk,
    input  wire                rst,
    // configuration
    input  wire [TIMING_W-1:0] step_len,
    input  wire [TIMING_W-1:0] step_space,
    input  wire [TIMING_W-1:0] dir_setup,
    input  wire [TIMING_W-1:0] dir_hold,
    input  wire [1:0]          out_mode,
    input  wire [2:0]          invert,
    input  wire                axis_enable,
    input  wire                clear_errors,
    input  wire                halt,
    // step requests from the DDA
    input  wire                req_valid,
    input  wire                req_negative,
    // pins and status
    output wire                pin_a,
    output wire                pin_b,
    output wire                pin_en,
    output wire [31:0]         position,
    output wire                rate_error,
    output wire                step_lost
);

    localparam PEND_W = 8;
    // The output modes (out_mode) and inversion bits (invert): FS_OUT_MODE_*, FS_INVERT_*.
`include "finestep_interface.vh"
    localparam [TIMING_W-1:0] COUNT_MAX = {TIMING_W{1'b1}};
    localparam [TIMING_W-1:0] COUNT_ONE = {{(TIMING_W-1){1'b0}}, 1'b1};

    reg signed [PEND_W-1:0] pending_reg;
    reg                     level_reg;
    reg                     dir_reg;        // 1 = positive
    reg [TIMING_W-1:0]      cnt_reg;   // cycles at the current level
    reg [TIMING_W-1:0]      dcnt_reg;  // cycles since dir changed
    reg [1:0]               quad_reg;
    reg [31:0]              position_reg;
    reg                     rate_error_reg;
    reg                     step_lost_reg;
    reg                     pin_a_reg;
    reg                     pin_b_reg;
    reg                     pin_en_reg;

    // One edge's decisions and next pending count (shaper_step).
    wire rise, fall, dir_change, clamp_high, clamp_low, behind;
    wire signed [PEND_W-1:0] pending_next;
    shaper_step decide (
        .pending(pending_reg), .level(level_reg), .dir(dir_reg),
        .req_valid(req_valid), .req_negative(req_negative), .halt(halt),
        .len_reached(cnt_reg >= step_len), .space_reached(cnt_reg >= step_space),
        .setup_reached(dcnt_reg >= dir_setup), .hold_reached(cnt_reg >= dir_hold),
        .rise(rise), .fall(fall), .dir_change(dir_change), .pending_next(pending_next),
        .clamp_high(clamp_high), .clamp_low(clamp_low), .behind(behind)
    );

    // Pin functions of the current state, registered into the pins.
    reg a_now, b_now;
    always @* begin
        case (out_mode)
            FS_OUT_MODE_UP_DOWN: begin
                a_now = level_reg && dir_reg;
                b_now = level_reg && !dir_reg;
            end
            FS_OUT_MODE_QUADRATURE: begin
                a_now = quad_reg[0] ^ quad_reg[1];
                b_now = quad_reg[1];
            end
            default: begin
                a_now = level_reg;
                b_now = dir_reg;
            end
        endcase
    end

    always @(posedge clk) begin
        pin_a_reg  <= a_now ^ invert[FS_INVERT_PIN_A_BIT];
        pin_b_reg  <= b_now ^ invert[FS_INVERT_PIN_B_BIT];
        pin_en_reg <= (axis_enable && !halt) ^ invert[FS_INVERT_PIN_EN_BIT];

        if (rise) level_reg <= 1'b1;
        else if (fall) level_reg <= 1'b0;

        if (rise || fall) cnt_reg <= COUNT_ONE;
        else if (cnt_reg != COUNT_MAX) cnt_reg <= cnt_reg + COUNT_ONE;

        if (dir_change) begin
            dir_reg  <= !dir_reg;
            dcnt_reg <= COUNT_ONE;
        end else if (dcnt_reg != COUNT_MAX) begin
            dcnt_reg <= dcnt_reg + COUNT_ONE;
        end

        pending_reg <= pending_next;

        if (rise) begin
            position_reg <= position_reg + {{31{!dir_reg}}, 1'b1};
            quad_reg     <= dir_reg ? quad_reg + 2'd1 : quad_reg - 2'd1;
        end

        if (behind) rate_error_reg <= 1'b1;
        else if (clear_errors) rate_error_reg <= 1'b0;
        if (clamp_high || clamp_low) step_lost_reg <= 1'b1;
        else if (clear_errors) step_lost_reg <= 1'b0;

        if (rst) begin
            pending_reg    <= {PEND_W{1'b0}};
            level_reg      <= 1'b0;
            dir_reg        <= 1'b1;
            cnt_reg        <= COUNT_MAX;
            dcnt_reg       <= COUNT_MAX;
            quad_reg       <= 2'd0;
            position_reg   <= 32'd0;
            rate_error_reg <= 1'b0;
            step_lost_reg  <= 1'b0;
            pin_a_reg      <= 1'b0;
            pin_b_reg      <= 1'b0;
            pin_en_reg     <= 1'b0;
        end
    end

    assign pin_a      = pin_a_reg;
    assign pin_b      = pin_b_reg;
    assign pin_en     = pin_en_reg;
    assign position   = position_reg;
    assign rate_error = rate_error_reg;
    assign step_lost  = step_lost_reg;

`ifdef FORMAL
    // Drive timing, from counters kept independently of the shaper's own: the step is
    // high exactly max(L,1) cycles, low at least S between pulses, dir changes only while
    // low and at least H cycles after a fall, and a rise comes at least U cycles after a
    // dir change. No step is lost: position + pending == net requests unless step_lost.
    localparam [PEND_W-1:0] PEND_MAX = 8'sd127;
    localparam F_TW = TIMING_W + 2;
    localparam [F_TW-1:0] F_MAX = {F_TW{1'b1}};
    reg f_past_valid;
    reg [F_TW-1:0] f_high;      // cycles high so far
    reg [F_TW-1:0] f_low;       // cycles since the last fall (F_MAX: none yet)
    reg [F_TW-1:0] f_dir_age;   // cycles since dir changed (F_MAX: never)
    reg [31:0]     f_net;       // net step requests
    reg            f_clamped;   // a clamp ever happened (step_lost can be cleared)
    initial f_past_valid = 1'b0;
    initial assume (rst);
    always @(posedge clk) f_past_valid <= 1'b1;

    // The decoded arithmetic against the spec's: e = pending + request, pending <- e -
    // issued saturated at +-127, behind when |e| > 1.
    wire signed [PEND_W:0] f_request = req_valid ? (req_negative ? -9'sd1 : 9'sd1) : 9'sd0;
    wire signed [PEND_W:0] f_wanted  = {pending_reg[PEND_W-1], pending_reg} + f_request;
    wire signed [PEND_W:0] f_issued  = rise ? (dir_reg ? 9'sd1 : -9'sd1) : 9'sd0;
    wire signed [PEND_W:0] f_left    = f_wanted - f_issued;
    wire f_rise = !halt && !level_reg && (f_wanted != 9'sd0) && (!f_wanted[PEND_W] == dir_reg) &&
                  (cnt_reg >= step_space) && (dcnt_reg >= dir_setup);
    wire f_dir_change = !halt && !level_reg && (f_wanted != 9'sd0) && (!f_wanted[PEND_W] != dir_reg) &&
                        (cnt_reg >= dir_hold);
    wire [PEND_W-1:0] f_pending_next = halt ? {PEND_W{1'b0}} : (f_left > 9'sd127) ? PEND_MAX :
                                       (f_left < -9'sd127) ? -PEND_MAX : f_left[PEND_W-1:0];
    always @(*) if (f_past_valid && !rst) begin
        assert (pending_reg != 8'h80);
        assert (rise == f_rise && dir_change == f_dir_change);
        assert (clamp_high == (!halt && f_left > 9'sd127) && clamp_low == (!halt && f_left < -9'sd127));
        assert (behind == (!halt && (f_wanted > 9'sd1 || f_wanted < -9'sd1)));
        assert (pending_next == f_pending_next);
    end

    // Timing settings are configuration: constant during the proof.
    always @(posedge clk) if (f_past_valid) begin
        assume ($stable(step_len) && $stable(step_space) && $stable(dir_setup) && $stable(dir_hold));
    end

    always @(posedge clk) begin
        f_high    <= level_reg ? ((f_high == F_MAX) ? F_MAX : f_high + 1'b1) : {{(F_TW-1){1'b0}}, 1'b1};
        f_low     <= (level_reg && fall) ? {{(F_TW-1){1'b0}}, 1'b1}
                   : ((f_low == F_MAX || level_reg) ? f_low : f_low + 1'b1);
        f_dir_age <= dir_change ? {{(F_TW-1){1'b0}}, 1'b1} : ((f_dir_age == F_MAX) ? F_MAX : f_dir_age + 1'b1);
        // A halt drops the pending steps: what was requested becomes what was issued.
        f_net     <= halt ? position_reg
                          : f_net + {{31{f_request[PEND_W]}}, f_request[0]};
        f_clamped <= f_clamped || clamp_high || clamp_low;
        if (rst) begin
            f_high    <= {{(F_TW-1){1'b0}}, 1'b1};
            f_low     <= F_MAX;
            f_dir_age <= F_MAX;
            f_net     <= 32'd0;
            f_clamped <= 1'b0;
        end
    end

    wire [F_TW-1:0] f_len   = (step_len == {TIMING_W{1'b0}}) ? {{(F_TW-1){1'b0}}, 1'b1} : {2'b00, step_len};
    wire [F_TW-1:0] f_cnt   = (cnt_reg == COUNT_MAX) ? F_MAX : {2'b00, cnt_reg};
    wire [F_TW-1:0] f_dcnt  = (dcnt_reg == COUNT_MAX) ? F_MAX : {2'b00, dcnt_reg};
    wire [F_TW-1:0] f_sat_high = (f_high >= {2'b00, COUNT_MAX}) ? F_MAX : f_high;
    wire [F_TW-1:0] f_sat_low = (f_low >= {2'b00, COUNT_MAX}) ? F_MAX : f_low;
    wire [F_TW-1:0] f_sat_dir = (f_dir_age >= {2'b00, COUNT_MAX}) ? F_MAX : f_dir_age;

    always @(*) if (f_past_valid && !rst) begin
        // The shaper's counters agree with the independent ones.
        if (level_reg) begin
            assert (f_cnt == f_sat_high && f_high <= f_len);
        end else begin
            assert (f_cnt == f_sat_low);
        end
        assert (f_dcnt == f_sat_dir);
        assert (pending_reg <= 8'sd127 && pending_reg >= -8'sd127);
        if (!f_clamped) assert (position_reg + {{24{pending_reg[PEND_W-1]}}, pending_reg} == f_net);
    end

    always @(posedge clk) if (f_past_valid && !$past(rst) && !rst) begin
        if ($past(clamp_high || clamp_low)) assert (step_lost_reg);
        if ($past(behind)) assert (rate_error_reg);
        if ($fell(level_reg)) assert ($past(f_high) == $past(f_len));
        if ($rose(level_reg)) assert ($past(f_low) >= {2'b00, step_space} && $past(f_dir_age) >= {2'b00, dir_setup});
        if ($past(dir_reg) != dir_reg) assert (!$past(level_reg) && !level_reg && $past(f_low) >= {2'b00, dir_hold});
        // The pins in every mode and polarity, one cycle behind the state.
        case ($past(out_mode))
            FS_OUT_MODE_UP_DOWN:
                assert ((pin_a ^ $past(invert[FS_INVERT_PIN_A_BIT])) == $past(level_reg && dir_reg)
                        && (pin_b ^ $past(invert[FS_INVERT_PIN_B_BIT])) == $past(level_reg && !dir_reg));
            FS_OUT_MODE_QUADRATURE:
                assert ((pin_a ^ $past(invert[FS_INVERT_PIN_A_BIT])) == $past(quad_reg[0] ^ quad_reg[1])
                        && (pin_b ^ $past(invert[FS_INVERT_PIN_B_BIT])) == $past(quad_reg[1]));
            default:
                assert ((pin_a ^ $past(invert[FS_INVERT_PIN_A_BIT])) == $past(level_reg)
                        && (pin_b ^ $past(invert[FS_INVERT_PIN_B_BIT])) == $past(dir_reg));
        endcase
        assert ((pin_en ^ $past(invert[FS_INVERT_PIN_EN_BIT])) == $past(axis_enable && !halt));
        if ($past(halt)) assert (!$rose(level_reg) && $past(dir_reg) == dir_reg && pending_reg == 8'sd0);
        // Quadrature: one step is one Gray-code move, +1 forward and -1 backward.
        if ($past(rise)) assert (quad_reg == ($past(dir_reg) ? $past(quad_reg) + 2'd1 : $past(quad_reg) - 2'd1));
        else assert (quad_reg == $past(quad_reg));
        // Sticky flags: set by their cause, held until clear_errors, cleared by it.
        if ($past(rate_error_reg) && !$past(clear_errors)) assert (rate_error_reg);
        if (!$past(behind) && ($past(clear_errors) || !$past(rate_error_reg))) assert (!rate_error_reg);
        if ($past(step_lost_reg) && !$past(clear_errors)) assert (step_lost_reg);
        if (!$past(clamp_high || clamp_low) && ($past(clear_errors) || !$past(step_lost_reg))) assert (!step_lost_reg);
        cover ($fell(level_reg) && !dir_reg);
        cover ($past(dir_reg) != dir_reg && dir_reg);
        cover (rate_error_reg);
        cover ($past(halt) && $fell(level_reg));
    end
`endif

endmodule

`default_nettype wire

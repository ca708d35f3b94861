`timescale 1ns / 1ps
`default_nettype none
// Specification: docs/spec/quadrature_channel.md
// One quadrature encoder (or linear grating) channel: A, B and index Z through input
// filters, decoded x4, x2, x1 or as step/dir into a 32-bit count; an A/B change in the
// same cycle is an illegal transition (flagged and counted, never counted as motion);
// one-shot latch-on-index and clear-on-index; the count snapshotted by the shared probe;
// the timestamp of the last counted edge for velocity estimation. Nothing is decoded
// until the filters have adopted the pins' levels at their first sample (`live`).
//
// Latency: a pin change is counted 2 clocks plus the filter length in samples later.
module quadrature_channel #(
    parameter FILTER_W = 4
) (
    // clock, reset
    input  wire                clk,
    input  wire                rst,
    // pins (asynchronous)
    input  wire                enc_a,
    input  wire                enc_b,
    input  wire                enc_z,
    // configuration
    input  wire [1:0]          mode,            // 0 x4, 1 x2, 2 x1, 3 step/dir
    input  wire                z_active_high,
    input  wire [FILTER_W-1:0] filter_len,
    input  wire                sample,          // shared prescaler strobe
    // host commands (one-cycle pulses)
    input  wire                arm_index_latch,
    input  wire                arm_index_clear,
    input  wire                clear_errors,
    input  wire                clear_counters,
    // shared
    input  wire                probe_event,     // snapshot the count now
    input  wire [31:0]         timestamp,
    // state
    output wire [31:0]         count,
    output wire [31:0]         index_latch,
    output wire                index_seen,
    output wire                index_latch_armed,
    output wire                index_clear_armed,
    output wire [31:0]         probe_latch,
    output wire [31:0]         edge_time,
    output wire                illegal,
    output wire [15:0]         illegal_count,
    output wire                a_level,
    output wire                b_level,
    output wire                z_level_active   // the index after polarity
);

    // The count modes (ENC_CONTROL.MODE) are FS_COUNT_MODE_* of the interface.
`include "finestep_interface.vh"

    // The three filters share the sample strobe, so they are primed on the same clock.
    wire a, b, z_level, primed, primed_b_unused, primed_z_unused;
    input_filter #(.FILTER_W(FILTER_W)) filter_a (
        .clk(clk), .rst(rst), .filter_len(filter_len), .sample(sample), .pin(enc_a), .level(a),
        .primed(primed)
    );
    input_filter #(.FILTER_W(FILTER_W)) filter_b (
        .clk(clk), .rst(rst), .filter_len(filter_len), .sample(sample), .pin(enc_b), .level(b),
        .primed(primed_b_unused)
    );
    input_filter #(.FILTER_W(FILTER_W)) filter_z (
        .clk(clk), .rst(rst), .filter_len(filter_len), .sample(sample), .pin(enc_z), .level(z_level),
        .primed(primed_z_unused)
    );
    wire unused_primed = &{1'b0, primed_b_unused, primed_z_unused};

    reg        live_reg;
    reg        a_prev_reg, b_prev_reg, z_prev_reg;
    reg [31:0] count_reg;
    reg [31:0] index_latch_reg;
    reg        index_seen_reg;
    reg        latch_armed_reg;
    reg        clear_armed_reg;
    reg [31:0] probe_latch_reg;
    reg [31:0] edge_time_reg;
    reg        illegal_reg;
    reg [15:0] illegal_count_reg;

    wire z       = z_level ^ !z_active_high;
    wire da      = (a != a_prev_reg);
    wire db      = (b != b_prev_reg);
    wire forward = (da && (a != b)) || (db && (a == b));
    wire step_dir = (mode == FS_COUNT_MODE_STEP_DIR);
    wire both    = live_reg && da && db && !step_dir;

    // The count change this cycle: +1, -1 or none.
    reg step, step_up;
    always @* begin
        step    = 1'b0;
        step_up = forward;
        case (mode)
            FS_COUNT_MODE_X4: step = (da != db);
            FS_COUNT_MODE_X2: step = da && !db;
            FS_COUNT_MODE_X1: begin
                step    = da && !db && !b;
                step_up = a;
            end
            default: begin   // step/dir: count on A rising, B is the direction
                step    = da && a;
                step_up = b;
            end
        endcase
        step = step && live_reg;
    end

    wire index_event = live_reg && z && !z_prev_reg;
    wire [31:0] counted = step ? (step_up ? count_reg + 32'd1 : count_reg - 32'd1) : count_reg;

    always @(posedge clk) begin
        live_reg   <= primed;
        a_prev_reg <= a;
        b_prev_reg <= b;
        z_prev_reg <= z;

        count_reg <= (index_event && clear_armed_reg) ? 32'd0 : counted;
        if (step) edge_time_reg <= timestamp;

        if (index_event && latch_armed_reg) index_latch_reg <= count_reg;
        if (arm_index_latch) index_seen_reg <= 1'b0;
        else if (index_event && latch_armed_reg) index_seen_reg <= 1'b1;
        if (arm_index_latch) latch_armed_reg <= 1'b1;
        else if (index_event) latch_armed_reg <= 1'b0;
        if (arm_index_clear) clear_armed_reg <= 1'b1;
        else if (index_event) clear_armed_reg <= 1'b0;

        if (probe_event) probe_latch_reg <= count_reg;

        if (both) illegal_reg <= 1'b1;
        else if (clear_errors) illegal_reg <= 1'b0;
        if (clear_counters) illegal_count_reg <= 16'd0;
        else if (both && illegal_count_reg != 16'hFFFF) illegal_count_reg <= illegal_count_reg + 16'd1;

        if (rst) begin
            live_reg          <= 1'b0;
            a_prev_reg        <= 1'b0;
            b_prev_reg        <= 1'b0;
            z_prev_reg        <= 1'b0;
            count_reg         <= 32'd0;
            index_latch_reg   <= 32'd0;
            index_seen_reg    <= 1'b0;
            latch_armed_reg   <= 1'b0;
            clear_armed_reg   <= 1'b0;
            probe_latch_reg   <= 32'd0;
            edge_time_reg     <= 32'd0;
            illegal_reg       <= 1'b0;
            illegal_count_reg <= 16'd0;
        end
    end

    assign count             = count_reg;
    assign index_latch       = index_latch_reg;
    assign index_seen        = index_seen_reg;
    assign index_latch_armed = latch_armed_reg;
    assign index_clear_armed = clear_armed_reg;
    assign probe_latch       = probe_latch_reg;
    assign edge_time         = edge_time_reg;
    assign illegal           = illegal_reg;
    assign illegal_count     = illegal_count_reg;
    assign a_level           = a;
    assign b_level           = b;
    assign z_level_active    = z;

`ifdef FORMAL
    // The count moves by at most one per clock, never on an illegal transition, and in
    // x4 it follows the Gray code exactly: count mod 4 tracks the (A,B) phase.
    reg f_past_valid;
    initial f_past_valid = 1'b0;
    initial assume (rst);
    always @(posedge clk) f_past_valid <= 1'b1;
    always @(posedge clk) if (f_past_valid) assume ($stable(mode) && $stable(z_active_high));
    always @(*) assume (!arm_index_clear);   // the Gray-code invariant needs no clearing
    // (A,B) phase in the step shaper's order: 00 -> 10 -> 11 -> 01 is 0, 1, 2, 3.
    wire [1:0] f_phase = {b_prev_reg, a_prev_reg ^ b_prev_reg};
    always @(posedge clk) if (f_past_valid && !$past(rst) && !rst) begin
        assert (count_reg == $past(count_reg) || count_reg == $past(count_reg) + 32'd1 ||
                count_reg == $past(count_reg) - 32'd1);
        if ($past(both)) assert (count_reg == $past(count_reg) && illegal_reg);
        if ($past(!step)) assert (count_reg == $past(count_reg));
        cover ($past(step) && $past(step, 2) && $past(step, 3) && $past(step, 4) && count_reg == 32'd4);
        cover (illegal_reg);
    end
    // In x4, without illegal transitions, count mod 4 follows the phase from the phase
    // the pins had when decoding went live (the count was 0 then).
    reg f_clean;
    reg [1:0] f_phase0;
    always @(posedge clk) begin
        f_clean <= rst ? 1'b1 : (f_clean && !both);
        if (rst) f_phase0 <= 2'd0;
        else if (!live_reg) f_phase0 <= {b, a ^ b};
    end
    always @(*) if (f_past_valid && !rst) begin
        assert (!clear_armed_reg);
        if (!live_reg) assert (count_reg == 32'd0 && !illegal_reg);
        if (mode == FS_COUNT_MODE_X4 && f_clean && live_reg) assert (count_reg[1:0] == f_phase - f_phase0);
    end
    // The index latch moves only on a rising edge of the index after polarity, stated
    // on the z_level_active port's own history rather than through index_event.
    reg f_z_before;
    always @(posedge clk) f_z_before <= z_level_active;
    always @(posedge clk) if (f_past_valid && !$past(rst) && !rst)
        if (index_latch_reg != $past(index_latch_reg)) assert ($past(z_level_active) && !$past(f_z_before));
`endif

endmodule

`default_nettype wire

`timescale 1ns / 1ps
`default_nettype none
// Specification: docs/spec/quadrature_channel.md
// One visit of a quadrature encoder (or linear grating) channel, as logic: from the
// synchronised pins and the channel's state before the visit, its state after it. A
// sampling visit runs the three input filters (A, B, index Z), then decodes the change
// of the filtered levels x4, x2, x1 or as step/dir into the COUNT_W-bit count (32, or 16 in
// the encoder bank's narrow build); A and B
// changing at one sample is an illegal transition (flagged, never counted as motion);
// a rising index clears the count when armed. Nothing is decoded at the sample that
// first adopts the pins' levels (`primed` before the visit is the channel's `live`).
// The encoder bank visits its channels in turn with one instance (their state in its
// store); the hand wheel visits its channel in every cycle.
//
// Latency: none (combinational); the owner registers the state at the visit's edge.
module quadrature_channel #(
    parameter FILTER_W = 4,
    parameter COUNT_W  = 32     // bits of the count and of the edge time (TIMESTAMP's low bits)
) (
    // configuration
    input  wire [1:0]          mode,            // 0 x4, 1 x2, 2 x1, 3 step/dir
    input  wire                z_active_high,
    input  wire [FILTER_W-1:0] filter_last,     // max(filter_len, 1) - 1 (filter_step's `last`)
    // the visit
    input  wire                sampling,        // this visit samples the pins
    input  wire                raw_a,           // synchronised pins
    input  wire                raw_b,
    input  wire                raw_z,
    input  wire [31:0]         timestamp,
    // state before the visit
    input  wire                primed,
    input  wire                a,
    input  wire                b,
    input  wire                z_level,
    input  wire [FILTER_W-1:0] cnt_a,
    input  wire [FILTER_W-1:0] cnt_b,
    input  wire [FILTER_W-1:0] cnt_z,
    input  wire [COUNT_W-1:0]  count,
    input  wire [COUNT_W-1:0]  edge_time,
    input  wire                clear_armed,
    // state after the visit
    output wire                primed_next,
    output wire                a_next,
    output wire                b_next,
    output wire                z_level_next,
    output wire [FILTER_W-1:0] cnt_a_next,
    output wire [FILTER_W-1:0] cnt_b_next,
    output wire [FILTER_W-1:0] cnt_z_next,
    output wire [COUNT_W-1:0]  count_next,
    output wire [COUNT_W-1:0]  edge_time_next,
    // events of the visit
    output wire                illegal_event,   // A and B changed at one sample
    output wire                index_event      // rising index (after polarity)
);

    // The count modes (ENC_CONTROL.MODE) are FS_COUNT_MODE_* of the interface.
`include "finestep_interface.vh"

    filter_step #(.FILTER_W(FILTER_W)) filter_a (
        .last(filter_last), .sample(sampling), .raw(raw_a), .primed(primed),
        .level(a), .count(cnt_a), .level_next(a_next), .count_next(cnt_a_next)
    );
    filter_step #(.FILTER_W(FILTER_W)) filter_b (
        .last(filter_last), .sample(sampling), .raw(raw_b), .primed(primed),
        .level(b), .count(cnt_b), .level_next(b_next), .count_next(cnt_b_next)
    );
    filter_step #(.FILTER_W(FILTER_W)) filter_z (
        .last(filter_last), .sample(sampling), .raw(raw_z), .primed(primed),
        .level(z_level), .count(cnt_z), .level_next(z_level_next), .count_next(cnt_z_next)
    );
    assign primed_next = primed || sampling;

    // Without a sample the levels stay, so nothing below fires.
    wire live     = primed;
    wire da       = (a_next != a);
    wire db       = (b_next != b);
    wire forward  = (da && (a_next != b_next)) || (db && (a_next == b_next));
    wire step_dir = (mode == FS_COUNT_MODE_STEP_DIR);

    // The count change of this visit: +1, -1 or none.
    reg step, step_up;
    always @* begin
        step    = 1'b0;
        step_up = forward;
        case (mode)
            FS_COUNT_MODE_X4: step = (da != db);
            FS_COUNT_MODE_X2: step = da && !db;
            FS_COUNT_MODE_X1: begin
                step    = da && !db && !b_next;
                step_up = a_next;
            end
            default: begin   // step/dir: count on A rising, B is the direction
                step    = da && a_next;
                step_up = b_next;
            end
        endcase
        step = step && live;
    end

    wire z_before = z_level ^ !z_active_high;
    wire z_after  = z_level_next ^ !z_active_high;
    assign index_event   = live && z_after && !z_before;
    assign illegal_event = live && da && db && !step_dir;

    // Two chains, count + 1 and count - 1, both starting at the store's output and the
    // decode choosing after them: one chain (count + {31{down}, step}, 29 LUT4 fewer in the
    // encoder bank) puts the filters and the decode in front of the carry chain, the
    // ECP5 board build's critical path (seed 3: 80.0 -> 69.7 MHz).
    // (COUNT_W < 32: the count wraps at 2^COUNT_W and the edge time is TIMESTAMP's low
    // COUNT_W bits; the encoder bank's narrow words, docs/spec/encoder_bank.md.)
    localparam [COUNT_W-1:0] ONE = {{(COUNT_W-1){1'b0}}, 1'b1};
    wire [COUNT_W-1:0] counted = step ? (step_up ? count + ONE : count - ONE) : count;
    assign count_next     = (index_event && clear_armed) ? {COUNT_W{1'b0}} : counted;
    assign edge_time_next = step ? timestamp[COUNT_W-1:0] : edge_time;
    generate
        if (COUNT_W < 32) begin : timestamp_high
            wire unused_timestamp_high = &{1'b0, timestamp[31:COUNT_W]};
        end
    endgenerate

`ifdef FORMAL
    // The count moves by at most one per visit and never on an illegal transition; a
    // visit that does not sample changes nothing; the first sample decodes nothing.
    always @(*) begin
        if (!(index_event && clear_armed))
            assert (count_next == count || count_next == count + ONE || count_next == count - ONE);
        if (illegal_event) assert (count_next == count || (index_event && clear_armed));
        if (!sampling) assert (count_next == count && edge_time_next == edge_time && a_next == a &&
                               b_next == b && z_level_next == z_level && cnt_a_next == cnt_a &&
                               !illegal_event && !index_event && primed_next == primed);
        if (!primed) assert (count_next == count && !illegal_event && !index_event);
        if (edge_time_next != edge_time) assert (count_next != count || (index_event && clear_armed));
        // The index event is the rising edge of Z after polarity (Z at the active level
        // now, not before), stated on the ports.
        if (index_event) assert (primed && sampling && z_level_next == z_active_high && z_level != z_active_high);
        if (primed && sampling && z_level_next == z_active_high && z_level != z_active_high) assert (index_event);
    end
`endif

endmodule

`default_nettype wire

`timescale 1ns / 1ps
`default_nettype none
// Specification: docs/spec/input_filter.md (the filter rule)
// One sample of the glitch filter, as logic: from a pin's synchronised value `raw` and
// the filter's state (`level`, `count`, `primed`), the state after a sample. The first
// sample adopts the pin's level; later, `level` follows `raw` once it has shown the
// other level in max(filter_len, 1) samples in a row. Without `sample` the state stays.
// Used by input_filter (a pin with its own registers) and by the quadrature decoder
// (whose filter state lives in the encoder bank's store between visits).
//
// The owner gives the filter length as `last` = max(filter_len, 1) - 1, the count at
// which a differing sample adopts the pin (the encoder bank registers it a clock ahead of
// a visit, so no subtraction stands in front of the compare and the decode after it).
//
// Latency: none (combinational). Invariant: count_next < last + 1 = max(filter_len, 1).
module filter_step #(
    parameter FILTER_W = 4
) (
    input  wire [FILTER_W-1:0] last,          // max(filter_len, 1) - 1
    input  wire                sample,
    input  wire                raw,
    input  wire                primed,
    input  wire                level,
    input  wire [FILTER_W-1:0] count,
    output wire                level_next,
    output wire [FILTER_W-1:0] count_next
);

    localparam [FILTER_W-1:0] ONE  = {{(FILTER_W-1){1'b0}}, 1'b1};
    localparam [FILTER_W-1:0] ZERO = {FILTER_W{1'b0}};

    wire                differs = (raw != level);
    // count + 1 >= needed = last + 1, without overflowing the counter (count < needed always).
    wire                enough  = (count >= last);
    wire                adopt   = !primed || (differs && enough);

    assign level_next = (sample && adopt) ? raw : level;
    assign count_next = !sample ? count : (adopt || !differs) ? ZERO : count + ONE;

`ifdef FORMAL
    // From a state the rule keeps (count < needed), the next state keeps it; the level
    // moves only at a sample, to the pin's value, and only when the pin has differed for
    // `needed` samples (this one included) or at the first sample.
    wire [FILTER_W:0] f_needed = {1'b0, last} + 1'b1;
    always @(*) begin
        if ({1'b0, count} < f_needed) assert ({1'b0, count_next} < f_needed);
        if (!primed && sample) assert (count_next == ZERO && level_next == raw);
        if (level_next != level && {1'b0, count} < f_needed) assert (sample && level_next == raw &&
                                         (!primed || {1'b0, count} + 1'b1 == f_needed));
        if (!sample) assert (count_next == count && level_next == level);
    end
`endif

endmodule

`default_nettype wire

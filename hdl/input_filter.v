`timescale 1ns / 1ps
`default_nettype none
// Specification: docs/spec/input_filter.md
// Input filter for one asynchronous pin: a two-flop synchroniser, then a glitch filter
// whose output changes only after the synchronised pin has shown the other level in
// max(filter_len, 1) consecutive sample cycles. Sample cycles come from a shared
// prescaler, so slow inputs (a hand wheel, a probe) can filter over long times with a
// small counter. The first sample adopts the pin's level (`primed`), so an input that
// rests high at power-on is not seen as an edge.
//
// Latency: a clean change reaches `level` 2 clocks plus max(filter_len, 1) samples after
// the pin changed.
module input_filter #(
    parameter FILTER_W = 4
) (
    // clock, reset
    input  wire                clk,
    input  wire                rst,
    // configuration and timing
    input  wire [FILTER_W-1:0] filter_len,
    input  wire                sample,
    // pin (asynchronous)
    input  wire                pin,
    // filtered level; primed: the first sample has set it
    output wire                level,
    output wire                primed
);

    reg [1:0]          sync_reg;
    reg                level_reg;
    reg                primed_reg;
    reg [FILTER_W-1:0] count_reg;

    wire                raw = sync_reg[1];
    wire                level_next;
    wire [FILTER_W-1:0] count_next;
    wire [FILTER_W-1:0] last = (filter_len == {FILTER_W{1'b0}}) ? {FILTER_W{1'b0}} : filter_len - 1'b1;
    filter_step #(.FILTER_W(FILTER_W)) rule (
        .last(last), .sample(sample), .raw(raw), .primed(primed_reg),
        .level(level_reg), .count(count_reg), .level_next(level_next), .count_next(count_next)
    );

    always @(posedge clk) begin
        sync_reg   <= {sync_reg[0], pin};
        level_reg  <= level_next;
        count_reg  <= count_next;
        if (sample) primed_reg <= 1'b1;
        if (rst) begin
            sync_reg   <= 2'b00;
            level_reg  <= 1'b0;
            primed_reg <= 1'b0;
            count_reg  <= {FILTER_W{1'b0}};
        end
    end

    assign level  = level_reg;
    assign primed = primed_reg;

`ifdef FORMAL
    // The level changes only at a sample, after `needed` samples of the other level in a
    // row; the counter never reaches `needed`. Stated here without filter_step's wires.
    // The filter length is configuration.
    localparam [FILTER_W-1:0] F_ONE = {{(FILTER_W-1){1'b0}}, 1'b1};
    reg f_past_valid;
    reg [FILTER_W:0] f_run;    // samples in a row showing the other level
    wire [FILTER_W-1:0] f_needed  = (filter_len == {FILTER_W{1'b0}}) ? F_ONE : filter_len;
    wire                f_differs = (raw != level_reg);
    initial f_past_valid = 1'b0;
    initial assume (rst);
    always @(posedge clk) f_past_valid <= 1'b1;
    always @(posedge clk) if (f_past_valid) assume ($stable(filter_len));
    always @(posedge clk) begin
        if (rst) f_run <= 0;
        else if (sample) f_run <= (primed_reg && f_differs && f_run + 1'b1 < {1'b0, f_needed}) ? f_run + 1'b1 : 0;
    end
    always @(*) if (f_past_valid && !rst) begin
        assert (count_reg < f_needed);
        assert ({1'b0, count_reg} == f_run);
    end
    always @(posedge clk) if (f_past_valid && !$past(rst) && !rst) begin
        if ($changed(level_reg)) assert ($past(sample) && $past(f_differs) &&
                                         (!$past(primed_reg) || $past(count_reg) + F_ONE == $past(f_needed)));
        // ... and it does change then (found by make mutants-rtl: a level stuck at its
        // reset value kept every property above), and the first sample adopts the pin.
        if ($past(sample) && $past(primed_reg) && $past(f_differs) && $past(count_reg) + F_ONE == $past(f_needed))
            assert ($changed(level_reg));
        if ($past(sample) && !$past(primed_reg)) assert (level_reg == $past(raw) && primed_reg);
        if ($past(primed_reg)) assert (primed_reg);
        // ... and it is primed by a sample, not by time: unprimed until the first sample.
        if (!$past(sample) && !$past(primed_reg)) assert (!primed_reg);
        if (!$past(sample)) assert ($stable(level_reg) && $stable(count_reg));
        cover ($changed(level_reg) && f_needed == 3);
    end
    // Reset leaves the filter unprimed, so the first sample after it adopts the pin; the
    // filter sees the pin through exactly two flip-flops.
    always @(posedge clk) if (f_past_valid && $past(rst)) assert (!primed_reg && !level_reg && count_reg == 0 && sync_reg == 2'b00);
    always @(posedge clk) if (f_past_valid && !$past(rst)) assert (sync_reg == {$past(sync_reg[0]), $past(pin)});
`endif

endmodule

`default_nettype wire

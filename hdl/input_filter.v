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

    localparam [FILTER_W-1:0] ONE = {{(FILTER_W-1){1'b0}}, 1'b1};

    reg [1:0]          sync_reg;
    reg                level_reg;
    reg                primed_reg;
    reg [FILTER_W-1:0] count_reg;

    wire                raw        = sync_reg[1];
    wire [FILTER_W-1:0] needed     = (filter_len == {FILTER_W{1'b0}}) ? ONE : filter_len;
    wire                differs    = (raw != level_reg);
    // count + 1 >= needed, without overflowing the counter (count < needed always).
    wire                enough     = (count_reg >= needed - ONE);

    always @(posedge clk) begin
        sync_reg <= {sync_reg[0], pin};
        if (sample) begin
            primed_reg <= 1'b1;
            if (!primed_reg) begin
                level_reg <= raw;
                count_reg <= {FILTER_W{1'b0}};
            end else if (!differs) begin
                count_reg <= {FILTER_W{1'b0}};
            end else if (enough) begin
                level_reg <= raw;
                count_reg <= {FILTER_W{1'b0}};
            end else begin
                count_reg <= count_reg + ONE;
            end
        end
        if (rst) begin
            sync_reg  <= 2'b00;
            level_reg  <= 1'b0;
            primed_reg <= 1'b0;
            count_reg  <= {FILTER_W{1'b0}};
        end
    end

    assign level  = level_reg;
    assign primed = primed_reg;

`ifdef FORMAL
    // The level changes only at a sample, after `needed` samples of the other level in a
    // row; the counter never reaches `needed`. The filter length is configuration.
    reg f_past_valid;
    reg [FILTER_W:0] f_run;    // samples in a row showing the other level
    initial f_past_valid = 1'b0;
    initial assume (rst);
    always @(posedge clk) f_past_valid <= 1'b1;
    always @(posedge clk) if (f_past_valid) assume ($stable(filter_len));
    always @(posedge clk) begin
        if (rst) f_run <= 0;
        else if (sample) f_run <= (primed_reg && differs && !enough) ? f_run + 1'b1 : 0;
    end
    always @(*) if (f_past_valid && !rst) begin
        assert (count_reg < needed);
        assert ({1'b0, count_reg} == f_run);
    end
    always @(posedge clk) if (f_past_valid && !$past(rst) && !rst) begin
        if ($changed(level_reg)) assert ($past(sample) && $past(differs) &&
                                         (!$past(primed_reg) || $past(count_reg) + ONE == $past(needed)));
        if ($past(primed_reg)) assert (primed_reg);
        if (!$past(sample)) assert ($stable(level_reg) && $stable(count_reg));
        cover ($changed(level_reg) && needed == 3);
    end
`endif

endmodule

`default_nettype wire

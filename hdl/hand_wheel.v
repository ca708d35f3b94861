`timescale 1ns / 1ps
`default_nettype none
// Specification: docs/spec/hand_wheel.md
// Hand wheel (MPG): a quadrature channel counting x4 on its own sampling prescaler, slow
// enough to filter contact bounce, and the wheel's position in detents of 4 edges.
// detents = floor((count + 2) / 4): a wheel resting where it was at reset sits in the
// middle of detent 0, two edges from either boundary, so bounce at rest never moves it.
module hand_wheel #(
    parameter FILTER_W = 4
) (
    // clock, reset
    input  wire                clk,
    input  wire                rst,
    // pins (asynchronous)
    input  wire                mpg_a,
    input  wire                mpg_b,
    // configuration and commands
    input  wire [15:0]         prescale,
    input  wire [FILTER_W-1:0] filter_len,
    input  wire                clear_errors,
    input  wire                clear_counters,
    // state
    output wire [31:0]         count,
    output wire [31:0]         detents,
    output wire                illegal,
    output wire [15:0]         illegal_count,
    output wire                a_level,
    output wire                b_level
);

    reg  [15:0] presc_reg;
    wire        sample = (presc_reg == 16'd0);

    always @(posedge clk) begin
        presc_reg <= sample ? prescale : presc_reg - 16'd1;
        if (rst) presc_reg <= 16'd2;
    end

    wire [31:0] index_latch_unused, probe_latch_unused, edge_time_unused;
    wire        index_seen_unused, latch_armed_unused, clear_armed_unused, z_unused;
    quadrature_channel #(.FILTER_W(FILTER_W)) decoder (
        .clk(clk), .rst(rst),
        .enc_a(mpg_a), .enc_b(mpg_b), .enc_z(1'b0),
        .mode(2'd0), .z_active_high(1'b1), .filter_len(filter_len), .sample(sample),
        .arm_index_latch(1'b0), .arm_index_clear(1'b0),
        .clear_errors(clear_errors), .clear_counters(clear_counters),
        .probe_event(1'b0), .timestamp(32'd0),
        .count(count), .index_latch(index_latch_unused), .index_seen(index_seen_unused),
        .index_latch_armed(latch_armed_unused), .index_clear_armed(clear_armed_unused),
        .probe_latch(probe_latch_unused), .edge_time(edge_time_unused),
        .illegal(illegal), .illegal_count(illegal_count),
        .a_level(a_level), .b_level(b_level), .z_level_active(z_unused)
    );
    wire unused_hand_wheel = &{1'b0, index_latch_unused, probe_latch_unused, edge_time_unused,
                               index_seen_unused, latch_armed_unused, clear_armed_unused, z_unused};

    // count moves by at most one a clock, so its low bits going 1 -> 2 or 2 -> 1 is
    // crossing a detent boundary; a counter of those wraps with the count, where
    // floor((count + 2) / 4) of the 32-bit count would jump at the wrap.
    reg  [1:0]  count_low_prev_reg;
    reg  [31:0] detents_prev_reg;
    wire        detent_up   = (count_low_prev_reg == 2'd1) && (count[1:0] == 2'd2);
    wire        detent_down = (count_low_prev_reg == 2'd2) && (count[1:0] == 2'd1);
    assign detents = detent_up ? detents_prev_reg + 32'd1 :
                     detent_down ? detents_prev_reg - 32'd1 : detents_prev_reg;
    always @(posedge clk) begin
        count_low_prev_reg <= count[1:0];
        detents_prev_reg   <= detents;
        if (rst) begin
            count_low_prev_reg <= 2'd0;
            detents_prev_reg   <= 32'd0;
        end
    end

`ifdef FORMAL
    // The detent count moves by at most one per clock (the jog follows it detent by
    // detent) and is floor((count + 2) / 4) of the count (the quotient's low 30 bits:
    // both wrap).
    reg f_past_valid;
    reg [31:0] f_prev_count;
    initial f_past_valid = 1'b0;
    initial assume (rst);
    always @(posedge clk) begin
        f_past_valid <= 1'b1;
        f_prev_count <= rst ? 32'd0 : count;
    end
    wire [31:0] f_prev_plus2 = f_prev_count + 32'd2;
    wire [31:0] f_plus2      = count + 32'd2;
    always @(*) if (f_past_valid && !rst) begin
        assert (count_low_prev_reg == f_prev_count[1:0]);
        assert (detents_prev_reg[29:0] == f_prev_plus2[31:2]);
        assert (detents[29:0] == f_plus2[31:2]);
    end
    always @(posedge clk) if (f_past_valid && !$past(rst) && !rst) begin
        assert (detents == $past(detents) || detents == $past(detents) + 32'd1 || detents == $past(detents) - 32'd1);
        cover (detents == 32'd1);
        cover (detents == 32'hFFFF_FFFF);
    end
`endif

endmodule

`default_nettype wire

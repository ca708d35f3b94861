`timescale 1ns / 1ps
`default_nettype none
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

    wire [31:0] shifted = count + 32'd2;
    wire        unused_fraction = &{1'b0, shifted[1:0]};
    assign detents = {{2{shifted[31]}}, shifted[31:2]};

endmodule

`default_nettype wire

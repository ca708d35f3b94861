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
    output wire                detent_up,      // detents = detents_prev + 1 in this cycle
    output wire                detent_down,    // detents = detents_prev - 1 in this cycle
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

    // The channel's state in flip-flops of its own; it is visited in every cycle and
    // samples when the prescaler says so (no index: Z rests low).
    reg  [1:0]          sync_a_reg, sync_b_reg;
    reg                 primed_reg, a_reg, b_reg;
    reg  [FILTER_W-1:0] cnt_a_reg, cnt_b_reg;
    reg  [31:0]         count_reg;
    reg                 illegal_reg;
    reg  [15:0]         illegal_count_reg;
    wire                primed_next, a_next, b_next, z_unused, illegal_event, index_unused;
    wire [FILTER_W-1:0] cnt_a_next, cnt_b_next, cnt_z_unused;
    wire [31:0]         count_next, edge_time_unused;
    wire [FILTER_W-1:0] filter_last = (filter_len == {FILTER_W{1'b0}}) ? {FILTER_W{1'b0}} : filter_len - 1'b1;
    quadrature_channel #(.FILTER_W(FILTER_W)) decoder (
        .mode(2'd0), .z_active_high(1'b1), .filter_last(filter_last),
        .sampling(sample), .raw_a(sync_a_reg[1]), .raw_b(sync_b_reg[1]), .raw_z(1'b0),
        .timestamp(32'd0),
        .primed(primed_reg), .a(a_reg), .b(b_reg), .z_level(1'b0),
        .cnt_a(cnt_a_reg), .cnt_b(cnt_b_reg), .cnt_z({FILTER_W{1'b0}}),
        .count(count_reg), .edge_time(32'd0), .clear_armed(1'b0),
        .primed_next(primed_next), .a_next(a_next), .b_next(b_next), .z_level_next(z_unused),
        .cnt_a_next(cnt_a_next), .cnt_b_next(cnt_b_next), .cnt_z_next(cnt_z_unused),
        .count_next(count_next), .edge_time_next(edge_time_unused),
        .illegal_event(illegal_event), .index_event(index_unused)
    );
    wire unused_hand_wheel = &{1'b0, z_unused, cnt_z_unused, edge_time_unused, index_unused};

    always @(posedge clk) begin
        sync_a_reg <= {sync_a_reg[0], mpg_a};
        sync_b_reg <= {sync_b_reg[0], mpg_b};
        primed_reg <= primed_next;
        a_reg      <= a_next;
        b_reg      <= b_next;
        cnt_a_reg  <= cnt_a_next;
        cnt_b_reg  <= cnt_b_next;
        count_reg  <= count_next;
        if (illegal_event) illegal_reg <= 1'b1;
        else if (clear_errors) illegal_reg <= 1'b0;
        if (clear_counters) illegal_count_reg <= 16'd0;
        else if (illegal_event && illegal_count_reg != 16'hFFFF) illegal_count_reg <= illegal_count_reg + 16'd1;
        if (rst) begin
            sync_a_reg        <= 2'b00;
            sync_b_reg        <= 2'b00;
            primed_reg        <= 1'b0;
            a_reg             <= 1'b0;
            b_reg             <= 1'b0;
            cnt_a_reg         <= {FILTER_W{1'b0}};
            cnt_b_reg         <= {FILTER_W{1'b0}};
            count_reg         <= 32'd0;
            illegal_reg       <= 1'b0;
            illegal_count_reg <= 16'd0;
        end
    end
    assign count         = count_reg;
    assign illegal       = illegal_reg;
    assign illegal_count = illegal_count_reg;
    assign a_level       = a_reg;
    assign b_level       = b_reg;

    // count moves by at most one a clock, so its low bits going 1 -> 2 or 2 -> 1 is
    // crossing a detent boundary; a counter of those wraps with the count, where
    // floor((count + 2) / 4) of the 32-bit count would jump at the wrap.
    // The crossing is decoded a clock ahead, from the count and its next value (the
    // count's low two bits, 1 -> 2 up and 2 -> 1 down), into two flip-flops: the jog
    // takes them as they are, with no decode or carry chain in front of its detent logic
    // (the ECP5 board build's critical path ran from the count through the detents'
    // chains into the jog's window check).
    reg         detent_up_reg, detent_down_reg;
    reg  [31:0] detents_prev_reg;
    // Two chains from the flip-flops, the decode choosing after them: with one chain
    // (detents_prev + {31{down}, moved}) the decode sat in front of the carry chain and
    // the jog's detent logic after it, the ECP5 board build's critical path (lowest of
    // three seeds 80.0 -> 74.5 MHz).
    assign detents = detent_up_reg ? detents_prev_reg + 32'd1 :
                     detent_down_reg ? detents_prev_reg - 32'd1 : detents_prev_reg;
    assign detent_up   = detent_up_reg;
    assign detent_down = detent_down_reg;
    always @(posedge clk) begin
        detent_up_reg    <= (count[1:0] == 2'd1) && (count_next[1:0] == 2'd2);
        detent_down_reg  <= (count[1:0] == 2'd2) && (count_next[1:0] == 2'd1);
        detents_prev_reg <= detents;
        if (rst) begin
            detent_up_reg    <= 1'b0;
            detent_down_reg  <= 1'b0;
            detents_prev_reg <= 32'd0;
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
        assert (detent_up_reg == (f_prev_count[1:0] == 2'd1 && count[1:0] == 2'd2));
        assert (detent_down_reg == (f_prev_count[1:0] == 2'd2 && count[1:0] == 2'd1));
        assert (detents_prev_reg[29:0] == f_prev_plus2[31:2]);
        assert (detents[29:0] == f_plus2[31:2]);
    end
    // x4 decoding follows the Gray code: without illegal transitions, count mod 4 is the
    // (A,B) phase (00 -> 10 -> 11 -> 01 is 0, 1, 2, 3) less the phase the first sample
    // adopted (the count is 0 until then).
    reg       f_clean;
    reg [1:0] f_phase0;
    wire [1:0] f_phase = {b_reg, a_reg ^ b_reg};
    always @(posedge clk) begin
        f_clean <= rst ? 1'b1 : (f_clean && !illegal_event);
        if (rst) f_phase0 <= 2'd0;
        else if (!primed_reg) f_phase0 <= {b_next, a_next ^ b_next};
    end
    always @(*) if (f_past_valid && !rst) begin
        if (!primed_reg) assert (count == 32'd0 && !illegal && illegal_count == 16'd0 && f_clean);
        if (f_clean && primed_reg) assert (count_reg[1:0] == f_phase - f_phase0);
    end
    always @(posedge clk) if (f_past_valid && !$past(rst) && !rst) begin
        // Samples every PRESCALE + 1 clocks: a sample reloads PRESCALE, others count down.
        if ($past(sample)) assert (presc_reg == $past(prescale));
        else assert (presc_reg == $past(presc_reg) - 16'd1);
        assert (detents == $past(detents) || detents == $past(detents) + 32'd1 || detents == $past(detents) - 32'd1);
        // The illegal-transition counter: one more per illegal transition up to 0xFFFF,
        // then held; CLEAR_COUNTERS zeroes it (and wins).
        if ($past(clear_counters)) assert (illegal_count == 16'd0);
        else if ($past(illegal_event) && ($past(illegal_count) < 16'hFFFF))
            assert ({16'd0, illegal_count} == {16'd0, $past(illegal_count)} + 32'd1);
        else assert (illegal_count == $past(illegal_count));
        cover (detents == 32'd1);
        cover (detents == 32'hFFFF_FFFF);
    end
`endif

endmodule

`default_nettype wire

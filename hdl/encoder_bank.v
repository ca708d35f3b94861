`timescale 1ns / 1ps
`default_nettype none
// Specification: docs/spec/encoder_bank.md
// Encoder bank: N_ENC quadrature channels (gratings, motor encoders) on one sampling
// prescaler, and the probe input that snapshots every channel's count, every axis's
// step position and the timestamp on one clock. The counts and edge times the host
// reads are copies taken together with the step positions (`latch_now`), so one set of
// register reads describes one instant.
module encoder_bank #(
    parameter N_ENC    = 4,
    parameter N_AXES   = 4,
    parameter FILTER_W = 4
) (
    // clock, reset
    input  wire                         clk,
    input  wire                         rst,
    // pins (asynchronous)
    input  wire [N_ENC-1:0]             enc_a,
    input  wire [N_ENC-1:0]             enc_b,
    input  wire [N_ENC-1:0]             enc_z,
    input  wire                         probe_pin,
    // configuration
    input  wire [15:0]                  prescale,
    input  wire [2*N_ENC-1:0]           mode,
    input  wire [N_ENC-1:0]             z_active_high,
    input  wire [FILTER_W*N_ENC-1:0]    filter_len,
    input  wire                         probe_active_high,
    input  wire [FILTER_W-1:0]          probe_filter_len,
    // host commands (one-cycle pulses)
    input  wire [N_ENC-1:0]             arm_index_latch,
    input  wire [N_ENC-1:0]             arm_index_clear,
    input  wire                         probe_arm,
    input  wire                         clear_errors,
    input  wire                         clear_counters,
    // shared state
    input  wire [31:0]                  timestamp,
    input  wire [32*N_AXES-1:0]         position,
    input  wire                         latch_now,
    // channel state
    output wire [32*N_ENC-1:0]          count_latched,
    output wire [32*N_ENC-1:0]          edge_time_latched,
    output wire [32*N_ENC-1:0]          index_latch,
    output wire [32*N_ENC-1:0]          probe_latch,
    output wire [16*N_ENC-1:0]          illegal_count,
    output wire [N_ENC-1:0]             illegal,
    output wire [N_ENC-1:0]             index_seen,
    output wire [N_ENC-1:0]             index_latch_armed,
    output wire [N_ENC-1:0]             index_clear_armed,
    output wire [N_ENC-1:0]             a_level,
    output wire [N_ENC-1:0]             b_level,
    output wire [N_ENC-1:0]             z_level,
    // probe state
    output wire                         probe_armed,
    output wire                         probe_seen,
    output wire                         probe_active,
    output wire [31:0]                  probe_time,
    output wire [32*N_AXES-1:0]         probe_position
);

    reg  [15:0] presc_reg;
    wire        sample = (presc_reg == 16'd0);

    always @(posedge clk) begin
        presc_reg <= sample ? prescale : presc_reg - 16'd1;
        // The first sample comes in the third cycle, when the synchronisers hold pins.
        if (rst) presc_reg <= 16'd2;
    end

    // Probe: filtered, polarity, rising edge while armed.
    wire probe_level, probe_primed;
    input_filter #(.FILTER_W(FILTER_W)) probe_filter (
        .clk(clk), .rst(rst), .filter_len(probe_filter_len), .sample(sample), .pin(probe_pin),
        .level(probe_level), .primed(probe_primed)
    );

    reg                  probe_live_reg;
    reg                  probe_active_prev_reg;
    reg                  probe_armed_reg;
    reg                  probe_seen_reg;
    reg [31:0]           probe_time_reg;
    reg [32*N_AXES-1:0]  probe_position_reg;

    wire active      = probe_active_high ? probe_level : !probe_level;
    wire probe_event = probe_live_reg && active && !probe_active_prev_reg && probe_armed_reg;

    always @(posedge clk) begin
        probe_live_reg        <= probe_primed;
        probe_active_prev_reg <= active;
        if (probe_event) begin
            probe_time_reg     <= timestamp;
            probe_position_reg <= position;
        end
        // An arm written in the cycle of an event wins.
        if (probe_arm) begin
            probe_armed_reg <= 1'b1;
            probe_seen_reg  <= 1'b0;
        end else if (probe_event) begin
            probe_armed_reg <= 1'b0;
            probe_seen_reg  <= 1'b1;
        end
        if (rst) begin
            probe_live_reg        <= 1'b0;
            probe_active_prev_reg <= 1'b0;
            probe_armed_reg       <= 1'b0;
            probe_seen_reg        <= 1'b0;
            probe_time_reg        <= 32'd0;
            probe_position_reg    <= {32*N_AXES{1'b0}};
        end
    end

    genvar c;
    generate
        for (c = 0; c < N_ENC; c = c + 1) begin : channel
            wire [31:0] count, edge_time;
            reg  [31:0] count_latched_reg, edge_time_latched_reg;
            quadrature_channel #(.FILTER_W(FILTER_W)) decoder (
                .clk(clk), .rst(rst),
                .enc_a(enc_a[c]), .enc_b(enc_b[c]), .enc_z(enc_z[c]),
                .mode(mode[2*c +: 2]), .z_active_high(z_active_high[c]),
                .filter_len(filter_len[FILTER_W*c +: FILTER_W]), .sample(sample),
                .arm_index_latch(arm_index_latch[c]), .arm_index_clear(arm_index_clear[c]),
                .clear_errors(clear_errors), .clear_counters(clear_counters),
                .probe_event(probe_event), .timestamp(timestamp),
                .count(count), .index_latch(index_latch[32*c +: 32]), .index_seen(index_seen[c]),
                .index_latch_armed(index_latch_armed[c]), .index_clear_armed(index_clear_armed[c]),
                .probe_latch(probe_latch[32*c +: 32]), .edge_time(edge_time),
                .illegal(illegal[c]), .illegal_count(illegal_count[16*c +: 16]),
                .a_level(a_level[c]), .b_level(b_level[c]), .z_level_active(z_level[c])
            );
            always @(posedge clk) begin
                if (latch_now) begin
                    count_latched_reg     <= count;
                    edge_time_latched_reg <= edge_time;
                end
                if (rst) begin
                    count_latched_reg     <= 32'd0;
                    edge_time_latched_reg <= 32'd0;
                end
            end
            assign count_latched[32*c +: 32]     = count_latched_reg;
            assign edge_time_latched[32*c +: 32] = edge_time_latched_reg;
        end
    endgenerate

    assign probe_armed    = probe_armed_reg;
    assign probe_seen     = probe_seen_reg;
    assign probe_active   = active;
    assign probe_time     = probe_time_reg;
    assign probe_position = probe_position_reg;

`ifdef FORMAL
    // Samples come every prescale + 1 clocks; the probe fires only while armed, once per
    // arming, and then latches every channel on that clock.
    reg f_past_valid;
    initial f_past_valid = 1'b0;
    initial assume (rst);
    always @(posedge clk) f_past_valid <= 1'b1;
    always @(posedge clk) if (f_past_valid && !$past(rst) && !rst) begin
        if ($past(sample)) assert (presc_reg == $past(prescale));
        else assert (presc_reg == $past(presc_reg) - 16'd1);
        if ($past(probe_event)) assert (probe_seen_reg || $past(probe_arm));
        if ($past(probe_event) && !$past(probe_arm)) assert (!probe_armed_reg && probe_time_reg == $past(timestamp));
        if (!$past(probe_armed_reg)) assert (!$past(probe_event));
        cover ($past(probe_event));
    end
`endif

endmodule

`default_nettype wire

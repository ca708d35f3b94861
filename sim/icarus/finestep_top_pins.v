`timescale 1ns / 1ps
`default_nettype none
// finestep_top with its pins packed into two 64-bit words exactly as the Verilator shim
// packs them (sim/finestep_top_sim.h, finestep_model::top_pins): the second simulator's
// top (Icarus Verilog under cocotb, scripts/icarus_replay.py). The cocotb testbench
// (scripts/icarus_replay_tb.py) drives `clk`, sets `in_word` whenever the recorded inputs
// change and `expect_word` whenever the outputs Verilator drove change; the comparator
// here checks every output pin on every clock (with !==, so an X or Z differs) at the
// falling edge, where the shim reads its outputs, and keeps the first difference.
// The parameters are the Verilated top's: finestep_top's defaults, or the motion chip
// (HAS_SPINDLE = HAS_OUTPUTS = N_GPIO = HAS_PBP = 0), with or without the hand wheel
// (HAS_MPG).
module finestep_top_pins #(
    parameter HAS_MPG     = 1,
    parameter HAS_SPINDLE = 1,
    parameter HAS_OUTPUTS = 1,
    parameter N_GPIO      = 4,
    parameter HAS_PBP     = 1
) (
    input  wire        clk,
    input  wire [63:0] in_word,
    output wire [63:0] out_word,
    // the comparator
    input  wire [63:0] expect_word,
    output reg  [63:0] compared,
    output reg         mismatch,
    output reg  [63:0] mismatch_cycle,
    output reg  [63:0] mismatch_expected,
    output reg  [63:0] mismatch_actual
);
    localparam N_AXES = 4;
    localparam N_ENC  = 4;
    localparam GPIO_W = (N_GPIO > 0) ? N_GPIO : 1;

    wire [N_AXES-1:0] pin_a;
    wire [N_AXES-1:0] pin_b;
    wire [N_AXES-1:0] pin_en;
    wire [15:0]       bus_ad_out;
    wire [GPIO_W-1:0] gpio;
    wire spi_miso, spi_miso_oe, irq, bus_ad_oe, coolant_mist, coolant_flood, light;
    wire spindle_pwm, spindle_dir, spindle_en, dac_cs_n, dac_sck, dac_sdi;

    finestep_top #(
        .N_AXES     (N_AXES),
        .N_ENC      (N_ENC),
        .HAS_MPG    (HAS_MPG),
        .HAS_SPINDLE(HAS_SPINDLE),
        .HAS_OUTPUTS(HAS_OUTPUTS),
        .N_GPIO     (N_GPIO),
        .HAS_PBP    (HAS_PBP)
    ) u_top (
        .clk          (clk),
        .rst          (in_word[0]),
        .spi_cs_n     (in_word[1]),
        .spi_sck      (in_word[2]),
        .spi_mosi     (in_word[3]),
        .spi_miso     (spi_miso),
        .spi_miso_oe  (spi_miso_oe),
        .bus_cs_n     (in_word[4]),
        .bus_adv_n    (in_word[5]),
        .bus_rd_n     (in_word[6]),
        .bus_wr_n     (in_word[7]),
        .bus_ad_in    (in_word[31:16]),
        .bus_ad_out   (bus_ad_out),
        .bus_ad_oe    (bus_ad_oe),
        .estop_pin    (in_word[8]),
        .enc_a        (in_word[32 +: N_ENC]),
        .enc_b        (in_word[40 +: N_ENC]),
        .enc_z        (in_word[48 +: N_ENC]),
        .probe_pin    (in_word[56]),
        .mpg_a        (in_word[57]),
        .mpg_b        (in_word[58]),
        .irq          (irq),
        .pin_a        (pin_a),
        .pin_b        (pin_b),
        .pin_en       (pin_en),
        .spindle_pwm  (spindle_pwm),
        .spindle_dir  (spindle_dir),
        .spindle_en   (spindle_en),
        .dac_cs_n     (dac_cs_n),
        .dac_sck      (dac_sck),
        .dac_sdi      (dac_sdi),
        .interlock_pin(in_word[9]),
        .coolant_mist (coolant_mist),
        .coolant_flood(coolant_flood),
        .light        (light),
        .gpio         (gpio),
        .panel_row_n  (4'hF)  // the keypad's rows idle (active low; HAS_PANEL is 0 here)
    );

    // As the shim: gpio as the top drives it (one bit, unused, when N_GPIO = 0).
    wire [7:0] gpio_packed = {{(8 - GPIO_W){1'b0}}, gpio};

    assign out_word = {gpio_packed, 2'b00, dac_sdi, dac_sck, dac_cs_n, spindle_en, spindle_dir, spindle_pwm,
                       bus_ad_out, 1'b0, light, coolant_flood, coolant_mist, bus_ad_oe, irq, spi_miso_oe,
                       spi_miso, {(8 - N_AXES){1'b0}}, pin_en, {(8 - N_AXES){1'b0}}, pin_b,
                       {(8 - N_AXES){1'b0}}, pin_a};

    // Clock n's outputs (after its rising edge) against Verilator's, at its falling edge;
    // only falling edges after a rising one (the testbench's first 0 on clk is from X).
    reg rose;
    initial rose = 1'b0;
    always @(posedge clk) rose <= 1'b1;
    initial begin
        compared = 64'd0;
        mismatch = 1'b0;
        mismatch_cycle = 64'd0;
        mismatch_expected = 64'd0;
        mismatch_actual = 64'd0;
    end
    always @(negedge clk) if (rose) begin
        compared <= compared + 64'd1;
        if (!mismatch && out_word !== expect_word) begin
            mismatch          <= 1'b1;
            mismatch_cycle    <= compared + 64'd1;
            mismatch_expected <= expect_word;
            mismatch_actual   <= out_word;
        end
    end
endmodule
`default_nettype wire

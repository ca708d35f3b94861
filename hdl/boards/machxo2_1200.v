`timescale 1ns / 1ps
`default_nettype none
// Board top for a Lattice MachXO2-1200 (LCMXO2-1200HC-4TG100C) in the reduced CPLD
// configuration: 4 axes, 2 encoder channels, the probe, the hand wheel and jog, the
// 8080/FSMC bus to the host (no SPI) and a 4-record FIFO. The clock is the internal
// oscillator (OSCH, 26.60 MHz), so the part needs no crystal; reset is power-on plus an
// optional button. Pins: constraints/machxo2_1200.lpf.
//
// This configuration does not fit the 1280 LUT4s yet (docs/resources.md gives the
// figure): `make bitstream-machxo2` reports the overflow until the core is reduced.
module machxo2_1200 #(
    parameter N_AXES          = 4,
    parameter N_ENC           = 2,
    parameter HAS_MPG         = 1,
    parameter FIFO_DEPTH_LOG2 = 2,
    // The core's digit-serial step engine (step_serial), STEP_DIGIT bits a clock: the
    // round R = 4 slots * 32 / STEP_DIGIT clocks (docs/spec/step_serial.md)
    parameter STEP_DIGIT      = 4,
    // 16: narrow encoder words, counts and edge times of 16 bits read extended
    // (VERSION.ENC_COUNT_16, docs/spec/encoder_bank.md#narrow-words)
    parameter ENC_COUNT_W     = 16
) (
    // reset
    input  wire              button_n,   // pulled up: low resets
    // 8080/FSMC bus to the host
    input  wire              bus_cs_n,
    input  wire              bus_adv_n,
    input  wire              bus_rd_n,
    input  wire              bus_wr_n,
    inout  wire [15:0]       bus_ad,
    output wire              irq,
    // machine
    input  wire              estop_pin,
    input  wire              probe_pin,
    input  wire              mpg_a,
    input  wire              mpg_b,
    input  wire [N_ENC-1:0]  enc_a,
    input  wire [N_ENC-1:0]  enc_b,
    input  wire [N_ENC-1:0]  enc_z,
    output wire [N_AXES-1:0] pin_a,
    output wire [N_AXES-1:0] pin_b,
    output wire [N_AXES-1:0] pin_en
);

    localparam CLOCK_HZ = 26600000;

    wire clk, rst;
    wire [15:0] bus_ad_out;
    wire bus_ad_oe;
    wire spi_miso_unused, spi_miso_oe_unused;

    OSCH #(.NOM_FREQ("26.60")) osc (.STDBY(1'b0), .OSC(clk), .SEDSTDBY());

    board_reset reset (
        .clk(clk), .button_n(button_n), .locked(1'b1), .rst(rst)
    );

    wire [8:0] io_unused;
    wire [3:0] gpio_unused;
    wire unused_io = &{1'b0, io_unused, gpio_unused};

    finestep_top #(
        .N_AXES(N_AXES), .FIFO_DEPTH_LOG2(FIFO_DEPTH_LOG2), .CLOCK_HZ(CLOCK_HZ),
        .HAS_SPI(0), .HAS_PARALLEL(1), .N_ENC(N_ENC), .HAS_MPG(HAS_MPG), .HAS_SPINDLE(0), .HAS_OUTPUTS(0),
        .STEP_DIGIT(STEP_DIGIT), .ENC_COUNT_W(ENC_COUNT_W),
        .HAS_PBP(0),        // no pbp block (the digit-serial engine takes none)
        .FIFO_HEAD_REG(0),  // the FIFO in distributed RAM: one register holds its head
        .FEEDBACK_REG(0)    // the feedback read words into the read register: 32 flip-flops fewer
    ) chip (
        .clk(clk), .rst(rst),
        .spi_cs_n(1'b1), .spi_sck(1'b0), .spi_mosi(1'b0),
        .spi_miso(spi_miso_unused), .spi_miso_oe(spi_miso_oe_unused),
        .bus_cs_n(bus_cs_n), .bus_adv_n(bus_adv_n), .bus_rd_n(bus_rd_n), .bus_wr_n(bus_wr_n),
        .bus_ad_in(bus_ad), .bus_ad_out(bus_ad_out), .bus_ad_oe(bus_ad_oe),
        .estop_pin(estop_pin),
        .enc_a(enc_a), .enc_b(enc_b), .enc_z(enc_z), .probe_pin(probe_pin),
        .mpg_a(mpg_a), .mpg_b(mpg_b),
        .irq(irq), .pin_a(pin_a), .pin_b(pin_b), .pin_en(pin_en),
        // the spindle and the logic outputs are not built in this board (HAS_SPINDLE,
        // HAS_OUTPUTS 0): their pins are constants
        .spindle_pwm(io_unused[0]), .spindle_dir(io_unused[1]), .spindle_en(io_unused[2]),
        .dac_cs_n(io_unused[3]), .dac_sck(io_unused[4]), .dac_sdi(io_unused[5]),
        .interlock_pin(1'b0), .coolant_mist(io_unused[6]), .coolant_flood(io_unused[7]),
        .light(io_unused[8]), .gpio(gpio_unused),
        // no panel in this build (HAS_PANEL 0)
        .panel_row_n(4'hF), .panel_col(), .panel_seg(), .panel_dig()
    );

    assign bus_ad = bus_ad_oe ? bus_ad_out : 16'bz;

endmodule

`default_nettype wire

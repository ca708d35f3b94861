`timescale 1ns / 1ps
`default_nettype none
// Board top for the 1BitSquared iCEBreaker (iCE40UP5K-SG48): the 12 MHz oscillator on
// pin 35 through the iCE40 PLL to 20.25 MHz, the user button and the PLL lock through
// board_reset, and finestep_top with its SPI link, 2 axes, 1 encoder channel and the
// probe on the three PMODs. Pins: constraints/icebreaker.pcf.
//
// A reduced configuration: the UP5K has 5280 logic cells. The full core needs about
// 7600 SB_LUT4s (docs/resources.md); 4 axes with 1 encoder and no hand wheel still take
// 5812 logic cells and 3 axes (4913) do not place, so N_AXES = 2, N_ENC = 1, HAS_MPG = 0
// (3990 cells). The pins of axes 2 and 3 and of the hand wheel stay on the board, unused.
module icebreaker #(
    parameter N_AXES          = 2,
    parameter N_ENC           = 1,
    parameter HAS_MPG         = 0,
    parameter FIFO_DEPTH_LOG2 = 8
) (
    // clock, reset
    input  wire              clk12,      // 12 MHz oscillator, a PLL pad
    input  wire              button_n,   // user button BTN_N, active low
    output wire              led_n,      // green LED, lit while out of reset
    // SPI to the host
    input  wire              spi_cs_n,
    input  wire              spi_sck,
    input  wire              spi_mosi,
    output wire              spi_miso,
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

    // 12 MHz * (DIVF + 1) / 2**DIVQ = 20.25 MHz (icepll -i 12 -o 20.25); VCO 648 MHz.
    // The UP5K is the slow iCE40: 24 MHz left the placer no margin.
    localparam CLOCK_HZ = 20250000;

    wire clk, pll_locked, rst;

    SB_PLL40_PAD #(
        .FEEDBACK_PATH("SIMPLE"),
        .DIVR(4'd0),
        .DIVF(7'd53),
        .DIVQ(3'd5),
        .FILTER_RANGE(3'd1)
    ) pll (
        .PACKAGEPIN(clk12), .PLLOUTGLOBAL(clk), .LOCK(pll_locked),
        .RESETB(1'b1), .BYPASS(1'b0)
    );

    spi_board_chip #(
        .N_AXES(N_AXES), .N_ENC(N_ENC), .HAS_MPG(HAS_MPG), .FIFO_DEPTH_LOG2(FIFO_DEPTH_LOG2),
        .CLOCK_HZ(CLOCK_HZ), .RAM_BLOCK(1), .FIFO_HEAD_REG(0)   // the iCE40 has no distributed RAM
    ) board (
        .clk(clk), .locked(pll_locked), .button_n(button_n), .rst(rst),
        .spi_cs_n(spi_cs_n), .spi_sck(spi_sck), .spi_mosi(spi_mosi), .spi_miso(spi_miso), .irq(irq),
        .estop_pin(estop_pin), .probe_pin(probe_pin), .mpg_a(mpg_a), .mpg_b(mpg_b),
        .enc_a(enc_a), .enc_b(enc_b), .enc_z(enc_z),
        .pin_a(pin_a), .pin_b(pin_b), .pin_en(pin_en),
        // no panel in this build (HAS_PANEL 0)
        .panel_row_n(4'hF), .panel_col(), .panel_seg(), .panel_dig()
    );
    assign led_n = rst;

endmodule

`default_nettype wire

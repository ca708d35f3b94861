`timescale 1ns / 1ps
`default_nettype none
// Board top for the Lattice iCE40-HX8K breakout board (iCE40HX8K-CT256): the 12 MHz
// oscillator through the iCE40 PLL to 51 MHz, power-on and external reset and the
// PLL lock through board_reset, and finestep_top with its SPI link, 4 axes, 4 encoder
// channels and the probe. Pins: constraints/ice40_hx8k_breakout.pcf.
//
// HAS_MPG is 0 here: the full core (with the hand wheel and jog) packs into about 7 830
// logic cells and does not fit the 7680 (docs/resources.md); the hand wheel's pins stay
// constrained, unused. The encoder bank's stores are in block RAM (RAM_BLOCK), and the
// FIFO's head record is the RAM's read register (FIFO_HEAD_REG 0).
module ice40_hx8k_breakout #(
    parameter N_AXES          = 4,
    parameter N_ENC           = 4,
    parameter HAS_MPG         = 0,
    parameter FIFO_DEPTH_LOG2 = 8,
    parameter STEP_SHARED     = 1,
    parameter HAS_PBP         = 0,    // 1: the point-by-point interpolator (docs/spec/pbp_interp.md#cost)
    parameter ENC_COUNT_W     = 32    // 16: narrow encoder words (docs/spec/encoder_bank.md#narrow-words)
) (
    // clock, reset
    input  wire              clk12,      // 12 MHz oscillator
    input  wire              reset_n,    // header pin, pulled up: low resets
    output wire              led,        // LED0, lit while out of reset
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

    // 12 MHz * (DIVF + 1) / 2**DIVQ = 51 MHz; VCO 816 MHz. Not icepll's nearest to 50 MHz
    // (50.25): with the step engine's 4 slots a period must be a multiple of 4 clocks,
    // and 1 ms is 51 000 clocks here (50 250 at 50.25 MHz is not).
    localparam CLOCK_HZ = 51000000;

    wire clk, pll_locked, rst;

    SB_PLL40_CORE #(
        .FEEDBACK_PATH("SIMPLE"),
        .DIVR(4'd0),
        .DIVF(7'd67),
        .DIVQ(3'd4),
        .FILTER_RANGE(3'd1)
    ) pll (
        .REFERENCECLK(clk12), .PLLOUTGLOBAL(clk), .LOCK(pll_locked),
        .RESETB(1'b1), .BYPASS(1'b0)
    );

    spi_board_chip #(
        .N_AXES(N_AXES), .N_ENC(N_ENC), .HAS_MPG(HAS_MPG), .FIFO_DEPTH_LOG2(FIFO_DEPTH_LOG2),
        .CLOCK_HZ(CLOCK_HZ), .RAM_BLOCK(1), .FIFO_HEAD_REG(0),  // the iCE40 has no distributed RAM
        .STEP_SHARED(STEP_SHARED), .HAS_PBP(HAS_PBP), .ENC_COUNT_W(ENC_COUNT_W)
    ) board (
        .clk(clk), .locked(pll_locked), .button_n(reset_n), .rst(rst),
        .spi_cs_n(spi_cs_n), .spi_sck(spi_sck), .spi_mosi(spi_mosi), .spi_miso(spi_miso), .irq(irq),
        .estop_pin(estop_pin), .probe_pin(probe_pin), .mpg_a(mpg_a), .mpg_b(mpg_b),
        .enc_a(enc_a), .enc_b(enc_b), .enc_z(enc_z),
        .pin_a(pin_a), .pin_b(pin_b), .pin_en(pin_en),
        // no panel in this build (HAS_PANEL 0)
        .panel_row_n(4'hF), .panel_col(), .panel_seg(), .panel_dig()
    );
    assign led = !rst;

endmodule

`default_nettype wire

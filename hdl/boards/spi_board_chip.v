`timescale 1ns / 1ps
`default_nettype none
// What every SPI board top shares: board_reset (button and PLL lock) and finestep_top
// with its SPI link and no 8080 bus, MISO driven only while the chip asks. A board top
// adds its clock (oscillator, PLL) and its LED.
module spi_board_chip #(
    parameter N_AXES          = 4,
    parameter N_ENC           = 4,
    parameter HAS_MPG         = 1,
    parameter FIFO_DEPTH_LOG2 = 8,
    parameter CLOCK_HZ        = 50000000,
    parameter RAM_BLOCK       = 0,
    parameter STEP_SHARED     = 1,
    parameter FIFO_HEAD_REG   = 1,
    parameter HAS_PANEL       = 0,
    parameter HAS_GANTRY      = 0,
    parameter HAS_PBP         = 0,   // the core's point-by-point interpolator (VERSION.HAS_PBP)
    parameter ENC_COUNT_W     = 32   // 16: narrow encoder words (VERSION.ENC_COUNT_16)
) (
    // clock, reset
    input  wire              clk,
    input  wire              locked,     // the PLL's lock (1 without a PLL)
    input  wire              button_n,   // reset button, active low
    output wire              rst,
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
    output wire [N_AXES-1:0] pin_en,
    // the panel (HAS_PANEL; a board without one ties panel_row_n high, leaves the rest)
    input  wire [3:0]        panel_row_n,
    output wire [3:0]        panel_col,
    output wire [7:0]        panel_seg,
    output wire [7:0]        panel_dig
);

    wire miso, miso_oe;
    wire [15:0] bus_ad_out_unused;
    wire bus_ad_oe_unused;

    board_reset reset (
        .clk(clk), .button_n(button_n), .locked(locked), .rst(rst)
    );

    wire [8:0] io_unused;
    wire [3:0] gpio_unused;
    wire unused_io = &{1'b0, io_unused, gpio_unused};

    finestep_top #(
        .N_AXES(N_AXES), .FIFO_DEPTH_LOG2(FIFO_DEPTH_LOG2), .CLOCK_HZ(CLOCK_HZ),
        .HAS_SPI(1), .HAS_PARALLEL(0), .N_ENC(N_ENC), .HAS_MPG(HAS_MPG), .HAS_SPINDLE(0), .HAS_OUTPUTS(0),
        .RAM_BLOCK(RAM_BLOCK), .STEP_SHARED(STEP_SHARED), .FIFO_HEAD_REG(FIFO_HEAD_REG),
        .HAS_PANEL(HAS_PANEL), .HAS_GANTRY(HAS_GANTRY), .HAS_PBP(HAS_PBP), .ENC_COUNT_W(ENC_COUNT_W)
    ) chip (
        .clk(clk), .rst(rst),
        .spi_cs_n(spi_cs_n), .spi_sck(spi_sck), .spi_mosi(spi_mosi),
        .spi_miso(miso), .spi_miso_oe(miso_oe),
        .bus_cs_n(1'b1), .bus_adv_n(1'b1), .bus_rd_n(1'b1), .bus_wr_n(1'b1),
        .bus_ad_in(16'd0), .bus_ad_out(bus_ad_out_unused), .bus_ad_oe(bus_ad_oe_unused),
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
        .panel_row_n(panel_row_n), .panel_col(panel_col), .panel_seg(panel_seg), .panel_dig(panel_dig)
    );

    assign spi_miso = miso_oe ? miso : 1'bz;

endmodule

`default_nettype wire

`timescale 1ns / 1ps
`default_nettype none
// What every SPI board top shares: board_reset (button and PLL lock) and finestep_top
// with its SPI link and no 8080 bus, MISO driven only while the chip asks. A board top
// adds its clock (oscillator, PLL) and its LED.
//
// With MACHINE_IO (not with HAS_PANEL) the panel's pins carry the spindle and the logic
// outputs instead (HAS_SPINDLE, HAS_OUTPUTS, 4 general outputs): panel_seg[7:0] =
// {coolant_flood, coolant_mist, dac_sdi, dac_sck, dac_cs_n, spindle_en, spindle_dir,
// spindle_pwm}, panel_dig[4:0] = {gpio[3:0], light} (panel_dig[7:5] low), panel_col low,
// and panel_row_n[0] is the interlock input (its polarity is INTERLOCK.ACTIVE_HIGH's).
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
    parameter ENC_COUNT_W     = 32,  // 16: narrow encoder words (VERSION.ENC_COUNT_16)
    parameter MACHINE_IO      = 0    // 1: the spindle and the logic outputs on the panel's pins (above)
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

    wire spindle_pwm, spindle_dir, spindle_en, dac_cs_n, dac_sck, dac_sdi;
    wire coolant_mist, coolant_flood, light;
    wire [3:0] gpio;
    wire [3:0] chip_col;
    wire [7:0] chip_seg, chip_dig;

    finestep_top #(
        .N_AXES(N_AXES), .FIFO_DEPTH_LOG2(FIFO_DEPTH_LOG2), .CLOCK_HZ(CLOCK_HZ),
        .HAS_SPI(1), .HAS_PARALLEL(0), .N_ENC(N_ENC), .HAS_MPG(HAS_MPG), .HAS_SPINDLE(MACHINE_IO), .HAS_OUTPUTS(MACHINE_IO),
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
        // the spindle and the logic outputs: built with MACHINE_IO only (constants else)
        .spindle_pwm(spindle_pwm), .spindle_dir(spindle_dir), .spindle_en(spindle_en),
        .dac_cs_n(dac_cs_n), .dac_sck(dac_sck), .dac_sdi(dac_sdi),
        .interlock_pin(MACHINE_IO != 0 && panel_row_n[0]), .coolant_mist(coolant_mist),
        .coolant_flood(coolant_flood), .light(light), .gpio(gpio),
        .panel_row_n(panel_row_n), .panel_col(chip_col), .panel_seg(chip_seg), .panel_dig(chip_dig)
    );

    generate
        if (MACHINE_IO != 0) begin : machine_io
            if (HAS_PANEL != 0) begin : check
                spi_board_chip_MACHINE_IO_needs_HAS_PANEL_0 MACHINE_IO_needs_HAS_PANEL_0 ();
            end
            assign panel_seg = {coolant_flood, coolant_mist, dac_sdi, dac_sck, dac_cs_n,
                                spindle_en, spindle_dir, spindle_pwm};
            assign panel_dig = {3'b000, gpio, light};
            assign panel_col = 4'b0000;
            wire unused_chip = &{1'b0, chip_col, chip_seg, chip_dig};
        end else begin : panel_pins
            assign panel_seg = chip_seg;
            assign panel_dig = chip_dig;
            assign panel_col = chip_col;
            wire unused_io = &{1'b0, spindle_pwm, spindle_dir, spindle_en, dac_cs_n, dac_sck,
                               dac_sdi, coolant_mist, coolant_flood, light, gpio};
        end
    endgenerate

    assign spi_miso = miso_oe ? miso : 1'bz;

endmodule

`default_nettype wire

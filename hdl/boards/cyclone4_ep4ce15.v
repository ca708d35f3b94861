`timescale 1ns / 1ps
`default_nettype none
// Board top for an Altera Cyclone IV E EP4CE15F23C8 (the QMTech Cyclone IV core board):
// the 50 MHz oscillator through the Cyclone IV PLL (altpll) to 100 MHz, the reset key
// and the PLL lock through board_reset, and finestep_top with its SPI link, 4 axes, 4
// encoder channels, the probe and the hand wheel. Pins and timing:
// constraints/cyclone4_ep4ce15.qsf and .sdc (Quartus project constraints/cyclone4_ep4ce15.qpf).
module cyclone4_ep4ce15 #(
    parameter N_AXES          = 4,
    parameter N_ENC           = 4,
    parameter HAS_MPG         = 1,
    parameter FIFO_DEPTH_LOG2 = 8
) (
    // clock, reset
    input  wire              clk50,      // 50 MHz oscillator
    input  wire              reset_n,    // reset key, active low
    output wire              led_n,      // core board LED, lit while out of reset
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

    // 50 MHz * CLK0_MULTIPLY / CLK0_DIVIDE.
    localparam CLOCK_HZ     = 100000000;
    localparam CLK0_MULTIPLY = 2;
    localparam CLK0_DIVIDE   = 1;
    localparam INCLK0_PS     = 20000;

    wire [4:0] pll_clk;
    wire clk = pll_clk[0];
    wire pll_locked, rst;

    altpll #(
        .intended_device_family("Cyclone IV E"),
        .lpm_type("altpll"),
        .operation_mode("NORMAL"),
        .pll_type("AUTO"),
        .compensate_clock("CLK0"),
        .inclk0_input_frequency(INCLK0_PS),
        .clk0_multiply_by(CLK0_MULTIPLY),
        .clk0_divide_by(CLK0_DIVIDE),
        .clk0_duty_cycle(50),
        .clk0_phase_shift("0"),
        .width_clock(5),
        .port_inclk0("PORT_USED"),
        .port_clk0("PORT_USED"),
        .port_locked("PORT_USED"),
        .port_areset("PORT_UNUSED"),
        .port_clk1("PORT_UNUSED"), .port_clk2("PORT_UNUSED"),
        .port_clk3("PORT_UNUSED"), .port_clk4("PORT_UNUSED")
    ) pll (
        .inclk({1'b0, clk50}), .clk(pll_clk), .locked(pll_locked), .areset(1'b0)
    );

    spi_board_chip #(
        .N_AXES(N_AXES), .N_ENC(N_ENC), .HAS_MPG(HAS_MPG), .FIFO_DEPTH_LOG2(FIFO_DEPTH_LOG2),
        .CLOCK_HZ(CLOCK_HZ)
    ) board (
        .clk(clk), .locked(pll_locked), .button_n(reset_n), .rst(rst),
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

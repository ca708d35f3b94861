`timescale 1ns / 1ps
`default_nettype none
// Board top for a Lattice MachXO3LF-6900 (LCMXO3LF-6900C-5BG256C, the part of Lattice's
// MachXO3LF starter kit), the largest part of the MachXO2 architecture that
// nextpnr-machxo2 places (its MachXO2 list stops at the -1200): the open MachXO2 flow
// end to end with a configuration that fits today, 4 axes, 2 encoder channels, the probe,
// SPI and a 16-record FIFO, no hand wheel. The clock is the internal oscillator (OSCH,
// 26.60 MHz); reset is power-on plus an optional button. Pins: constraints/machxo3_6900.lpf.
module machxo3_6900 #(
    parameter N_AXES          = 4,
    parameter N_ENC           = 2,
    parameter HAS_MPG         = 0,
    parameter FIFO_DEPTH_LOG2 = 4
) (
    // reset
    input  wire              button_n,   // pulled up: low resets
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

    localparam CLOCK_HZ = 26600000;

    wire clk, rst;

    OSCH #(.NOM_FREQ("26.60")) osc (.STDBY(1'b0), .OSC(clk), .SEDSTDBY());

    spi_board_chip #(
        .N_AXES(N_AXES), .N_ENC(N_ENC), .HAS_MPG(HAS_MPG), .FIFO_DEPTH_LOG2(FIFO_DEPTH_LOG2),
        .CLOCK_HZ(CLOCK_HZ), .FIFO_HEAD_REG(0)   // the FIFO in distributed RAM: one register holds its head
    ) board (
        .clk(clk), .locked(1'b1), .button_n(button_n), .rst(rst),
        .spi_cs_n(spi_cs_n), .spi_sck(spi_sck), .spi_mosi(spi_mosi), .spi_miso(spi_miso), .irq(irq),
        .estop_pin(estop_pin), .probe_pin(probe_pin), .mpg_a(mpg_a), .mpg_b(mpg_b),
        .enc_a(enc_a), .enc_b(enc_b), .enc_z(enc_z),
        .pin_a(pin_a), .pin_b(pin_b), .pin_en(pin_en),
        // no panel in this build (HAS_PANEL 0)
        .panel_row_n(4'hF), .panel_col(), .panel_seg(), .panel_dig()
    );

endmodule

`default_nettype wire

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
    wire miso, miso_oe;
    wire [15:0] bus_ad_out_unused;
    wire bus_ad_oe_unused;

    OSCH #(.NOM_FREQ("26.60")) osc (.STDBY(1'b0), .OSC(clk), .SEDSTDBY());

    board_reset reset (
        .clk(clk), .button_n(button_n), .locked(1'b1), .rst(rst)
    );

    finestep_top #(
        .N_AXES(N_AXES), .FIFO_DEPTH_LOG2(FIFO_DEPTH_LOG2), .CLOCK_HZ(CLOCK_HZ),
        .HAS_SPI(1), .HAS_PARALLEL(0), .N_ENC(N_ENC), .HAS_MPG(HAS_MPG)
    ) chip (
        .clk(clk), .rst(rst),
        .spi_cs_n(spi_cs_n), .spi_sck(spi_sck), .spi_mosi(spi_mosi),
        .spi_miso(miso), .spi_miso_oe(miso_oe),
        .bus_cs_n(1'b1), .bus_adv_n(1'b1), .bus_rd_n(1'b1), .bus_wr_n(1'b1),
        .bus_ad_in(16'd0), .bus_ad_out(bus_ad_out_unused), .bus_ad_oe(bus_ad_oe_unused),
        .estop_pin(estop_pin),
        .enc_a(enc_a), .enc_b(enc_b), .enc_z(enc_z), .probe_pin(probe_pin),
        .mpg_a(mpg_a), .mpg_b(mpg_b),
        .irq(irq), .pin_a(pin_a), .pin_b(pin_b), .pin_en(pin_en)
    );

    assign spi_miso = miso_oe ? miso : 1'bz;

endmodule

`default_nettype wire

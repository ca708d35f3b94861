`timescale 1ns / 1ps
`default_nettype none
// Board top for a Lattice XP2 LFXP2-5E-6TN144C (the part of Lattice's XP2 Brevia2 kit),
// built with Lattice Diamond only (no open flow places XP2): finestep_top with its SPI
// link, 3 axes, 1 encoder channel and the probe, straight from the board's 50 MHz
// oscillator (the core's rated clock, so the XP2's PLL is not needed); reset is power-on
// plus the reset button through board_reset. Pins: constraints/xp2_brevia2.lpf; project:
// constraints/xp2_brevia2_diamond.tcl (`make diamond`).
//
// A reduced configuration, estimated with Yosys synth_ecp5 as a stand-in (XP2 has the
// same LUT4 slices): 4 axes with 1 encoder take about 4530 LUT4s of the 5000 (91 %),
// 3 axes about 3780, so N_AXES = 3, N_ENC = 1, HAS_MPG = 0 until a Diamond run says more.
module xp2_brevia2 #(
    parameter N_AXES          = 3,
    parameter N_ENC           = 1,
    parameter HAS_MPG         = 0,
    parameter FIFO_DEPTH_LOG2 = 8
) (
    // clock, reset
    input  wire              clk50,      // 50 MHz oscillator
    input  wire              button_n,   // reset button, active low
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

    localparam CLOCK_HZ = 50000000;

    wire rst;

    spi_board_chip #(
        .N_AXES(N_AXES), .N_ENC(N_ENC), .HAS_MPG(HAS_MPG), .FIFO_DEPTH_LOG2(FIFO_DEPTH_LOG2),
        .CLOCK_HZ(CLOCK_HZ)
    ) board (
        .clk(clk50), .locked(1'b1), .button_n(button_n), .rst(rst),
        .spi_cs_n(spi_cs_n), .spi_sck(spi_sck), .spi_mosi(spi_mosi), .spi_miso(spi_miso), .irq(irq),
        .estop_pin(estop_pin), .probe_pin(probe_pin), .mpg_a(mpg_a), .mpg_b(mpg_b),
        .enc_a(enc_a), .enc_b(enc_b), .enc_z(enc_z),
        .pin_a(pin_a), .pin_b(pin_b), .pin_en(pin_en),
        // no panel in this build (HAS_PANEL 0)
        .panel_row_n(4'hF), .panel_col(), .panel_seg(), .panel_dig()
    );

endmodule

`default_nettype wire

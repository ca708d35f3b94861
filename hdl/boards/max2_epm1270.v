`timescale 1ns / 1ps
`default_nettype none
// Board top for an Altera MAX II EPM1270T144C5 CPLD with seed 002's feature set: the
// DDA fine interpolation of 4 axes (the digit-serial step engine) from an interpolation
// buffer of 2 records (a FIFO in flip-flops: MAX II has no RAM), the period interrupt,
// 2 encoder channels and the probe, the 8080/FSMC bus to the host (no SPI); no hand
// wheel and no jog (HAS_MPG 0, reported in CAPS.HAS_MPG), at the board's 50 MHz
// oscillator (MAX II has no PLL). The MachXO2-1200 top keeps the hand wheel and jog.
// Reset: power-on and the reset key through board_reset. Pins and timing:
// constraints/max2_epm1270.qsf and .sdc (Quartus project constraints/max2_epm1270.qpf).
//
// This configuration does not fit the 1270 logic elements yet (docs/bitstreams.md gives
// the figures); the project is written so that it builds as soon as the core does.
module max2_epm1270 #(
    parameter N_AXES          = 4,
    parameter N_ENC           = 2,
    parameter FIFO_DEPTH_LOG2 = 1,
    // The core's digit-serial step engine (step_serial), STEP_DIGIT bits a clock: the
    // round R = 4 slots * 32 / STEP_DIGIT clocks (docs/spec/step_serial.md)
    parameter STEP_DIGIT      = 4,
    // 16: narrow encoder words, counts and edge times of 16 bits read extended
    // (VERSION.ENC_COUNT_16, docs/spec/encoder_bank.md#narrow-words)
    parameter ENC_COUNT_W     = 16
) (
    // clock, reset
    input  wire              clk50,      // 50 MHz oscillator
    input  wire              reset_n,    // reset key, active low
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
    input  wire [N_ENC-1:0]  enc_a,
    input  wire [N_ENC-1:0]  enc_b,
    input  wire [N_ENC-1:0]  enc_z,
    output wire [N_AXES-1:0] pin_a,
    output wire [N_AXES-1:0] pin_b,
    output wire [N_AXES-1:0] pin_en
);

    localparam CLOCK_HZ = 50000000;

    wire rst;
    wire [15:0] bus_ad_out;
    wire bus_ad_oe;
    wire spi_miso_unused, spi_miso_oe_unused;

    board_reset reset (
        .clk(clk50), .button_n(reset_n), .locked(1'b1), .rst(rst)
    );

    wire [8:0] io_unused;
    wire [3:0] gpio_unused;
    wire unused_io = &{1'b0, io_unused, gpio_unused};

    finestep_top #(
        .N_AXES(N_AXES), .FIFO_DEPTH_LOG2(FIFO_DEPTH_LOG2), .CLOCK_HZ(CLOCK_HZ),
        .HAS_SPI(0), .HAS_PARALLEL(1), .N_ENC(N_ENC), .HAS_MPG(0), .HAS_SPINDLE(0), .HAS_OUTPUTS(0),
        .STEP_DIGIT(STEP_DIGIT),
        .HAS_PBP(0),     // no pbp block (the digit-serial engine takes none)
        .READ_STORE(0),  // no RAM: the read multiplexer costs less than a store in flip-flops
        .FIFO_HEAD_REG(2),  // the FIFO in flip-flops: its head read from its slot, no head register
        .NO_RAM(1),         // the encoder bank's copies in flip-flops behind one read register
        .ONE_SNAPSHOT(1),   // one position snapshot for the period latch and the probe (PROBE_POSITION
                            // and PROBE_TIME read POSITION and LATCH_TIME: docs/spec/register_file.md)
        .INC_WRITE_ONLY(1), // RECORD_INC reads 0: 4 x 32 bits fewer into the read multiplexer
        .AXIS_WRITE_ONLY(1), // AXIS_TIMING_A/B and AXIS_MODE read 0: 4 x 3 words fewer into it
        .INC_DIRECT(1),     // RECORD_INC written straight into the FIFO's record: no 4 x 32-bit copy
                            // and no push sequence (docs/spec/register_file.md)
        .ENC_COUNT_W(ENC_COUNT_W),
        .FEEDBACK_REG(0)    // the feedback read words into the read register: 32 flip-flops fewer
    ) chip (
        .clk(clk50), .rst(rst),
        .spi_cs_n(1'b1), .spi_sck(1'b0), .spi_mosi(1'b0),
        .spi_miso(spi_miso_unused), .spi_miso_oe(spi_miso_oe_unused),
        .bus_cs_n(bus_cs_n), .bus_adv_n(bus_adv_n), .bus_rd_n(bus_rd_n), .bus_wr_n(bus_wr_n),
        .bus_ad_in(bus_ad), .bus_ad_out(bus_ad_out), .bus_ad_oe(bus_ad_oe),
        .estop_pin(estop_pin),
        .enc_a(enc_a), .enc_b(enc_b), .enc_z(enc_z), .probe_pin(probe_pin),
        .mpg_a(1'b0), .mpg_b(1'b0),  // no hand wheel (HAS_MPG 0)
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

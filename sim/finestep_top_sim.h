/* C ABI around the Verilated finestep_top (the core behind its host interface), for
 * bindgen. One ft_sim is one instance with its own clock, driven and observed at its
 * pins: the inputs and outputs are packed into 64-bit words (finestep_model::top_pins
 * mirrors the layout bit for bit). Power-on state is all zero; the caller drives rst. */
#ifndef FINESTEP_TOP_SIM_H
#define FINESTEP_TOP_SIM_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Packed inputs: bit 0 rst, 1 spi_cs_n, 2 spi_sck, 3 spi_mosi, 4 bus_cs_n, 5 bus_adv_n,
 * 6 bus_rd_n, 7 bus_wr_n, 8 estop_pin, 9 interlock_pin, bits 16..31 bus_ad_in, 32..39 enc_a[c],
 * 40..47 enc_b[c], 48..55 enc_z[c], 56 probe_pin, 57 mpg_a, 58 mpg_b. */
#define FT_IN_RST 0
#define FT_IN_SPI_CS_N 1
#define FT_IN_SPI_SCK 2
#define FT_IN_SPI_MOSI 3
#define FT_IN_BUS_CS_N 4
#define FT_IN_BUS_ADV_N 5
#define FT_IN_BUS_RD_N 6
#define FT_IN_BUS_WR_N 7
#define FT_IN_ESTOP 8
#define FT_IN_INTERLOCK 9
#define FT_IN_BUS_AD0 16
#define FT_IN_ENC_A0 32
#define FT_IN_ENC_B0 40
#define FT_IN_ENC_Z0 48
#define FT_IN_PROBE 56
#define FT_IN_MPG_A 57
#define FT_IN_MPG_B 58
/* Packed outputs: bits 0..7 pin_a[i], 8..15 pin_b[i], 16..23 pin_en[i], 24 spi_miso,
 * 25 spi_miso_oe, 26 irq, 27 bus_ad_oe, 28 coolant_mist, 29 coolant_flood, 30 light,
 * bits 32..47 bus_ad_out, 48 spindle_pwm, 49 spindle_dir, 50 spindle_en, 51 dac_cs_n,
 * 52 dac_sck, 53 dac_sdi, bits 56..63 gpio[i]. */
#define FT_OUT_PIN_A0 0
#define FT_OUT_PIN_B0 8
#define FT_OUT_PIN_EN0 16
#define FT_OUT_SPI_MISO 24
#define FT_OUT_SPI_MISO_OE 25
#define FT_OUT_IRQ 26
#define FT_OUT_BUS_AD_OE 27
#define FT_OUT_COOLANT_MIST 28
#define FT_OUT_COOLANT_FLOOD 29
#define FT_OUT_LIGHT 30
#define FT_OUT_BUS_AD0 32
#define FT_OUT_SPINDLE_PWM 48
#define FT_OUT_SPINDLE_DIR 49
#define FT_OUT_SPINDLE_EN 50
#define FT_OUT_DAC_CS_N 51
#define FT_OUT_DAC_SCK 52
#define FT_OUT_DAC_SDI 53
#define FT_OUT_GPIO0 56

/* The outputs after the edge that ended cycle `cycle - 1`, recorded when they changed. */
typedef struct ft_event {
    uint64_t cycle;
    uint64_t outputs;
} ft_event;

typedef struct ft_sim ft_sim;

/* Which Verilation of the top: finestep_top's defaults (the spindle and the logic
 * outputs built), the motion chip every board top builds (without them), or the motion
 * chip without the hand wheel and the jog too (HAS_MPG = 0, as the HX8K and MachXO3
 * boards build it): what the motion tests that turn no wheel and the bench run; or the
 * motion chip with the core's digit-serial step engine (STEP_DIGIT = FT_SERIAL_DIGIT, as
 * the CPLD boards build it). A netlist build (FT_NETLIST) has one top, the default's
 * netlist, for all four. */
#define FT_VARIANT_FULL 0
#define FT_VARIANT_MOTION 1
#define FT_VARIANT_MOTION_NO_MPG 2
#define FT_VARIANT_MOTION_SERIAL 3

/* Build-time parameters of the Verilated top (the same in every variant). */
uint32_t ft_n_axes(void);
uint32_t ft_p_width(void);
uint32_t ft_timing_width(void);
uint32_t ft_fifo_depth_log2(void);
uint32_t ft_n_enc(void);
uint32_t ft_step_shared(void);
/* ... and those of the variant. */
uint32_t ft_has_mpg(uint32_t variant);
uint32_t ft_has_spindle(uint32_t variant);
uint32_t ft_has_outputs(uint32_t variant);
uint32_t ft_n_gpio(uint32_t variant);
uint32_t ft_has_pbp(uint32_t variant);
uint32_t ft_step_digit(uint32_t variant);
uint32_t ft_one_snapshot(uint32_t variant);
uint32_t ft_inc_write_only(uint32_t variant);
uint32_t ft_axis_write_only(uint32_t variant);
uint32_t ft_inc_direct(uint32_t variant);
uint32_t ft_enc_count_w(uint32_t variant);

/* A top of `variant` built without waveform support (the fast one). */
ft_sim *ft_new(uint32_t variant);
/* A top of `variant` that can write waveforms (ft_trace_open); slower. The motion
 * variants and a netlist build have no traced Verilation: this is their fast top. */
ft_sim *ft_new_traced(uint32_t variant);
void ft_free(ft_sim *sim);

/* Cycles run so far (edges since construction). */
uint64_t ft_cycle(const ft_sim *sim);
/* The packed outputs in the current cycle. */
uint64_t ft_outputs(const ft_sim *sim);
/* Runs up to `cycles` edges with the packed `inputs` held. After each edge whose
 * outputs differ from the cycle before, an event is stored; stops early when
 * `capacity` events are stored. Returns the edges run; *n_events the events stored. */
uint64_t ft_run(ft_sim *sim, uint64_t inputs, uint64_t cycles, ft_event *events, size_t capacity,
                size_t *n_events);

/* Waveform tracing on a top from ft_new_traced: open a file (VCD, or FST when the
 * crate was built with FST), dump every cycle until closed. Returns 0 on success, -1
 * when the file cannot be opened or the top was made by ft_new. `levels`: 0 = ports
 * only, 99 = everything. */
int ft_trace_open(ft_sim *sim, const char *path, uint32_t levels);
void ft_trace_close(ft_sim *sim);

#ifdef __cplusplus
}
#endif

#endif

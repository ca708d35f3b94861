/* C ABI around the Verilated step_serial (the digit-serial step engine), alone, for its
 * lockstep test against finestep_model::step_serial. Built in SS_VARIANTS variants
 * (axes, digit) with waveform support (the block is small). */
#ifndef STEP_SERIAL_SIM_H
#define STEP_SERIAL_SIM_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct ss_inputs {
    uint8_t run;
    uint32_t p_active;
    int32_t inc[8];
    uint8_t axis_enable;
    uint16_t step_len[8];
    uint16_t step_space[8];
    uint16_t dir_setup[8];
    uint16_t dir_hold[8];
    uint8_t out_mode[8];
    uint8_t invert[8];
    uint8_t clear_errors;
    uint8_t halt;
} ss_inputs;

typedef struct ss_outputs {
    uint8_t start_ok;
    uint8_t pin_a;
    uint8_t pin_b;
    uint8_t pin_en;
    uint8_t rate_error;
    uint8_t step_lost;
    uint8_t pos_digit;
    uint8_t pos_index;
    uint8_t pos_axis;
} ss_outputs;

typedef struct ss_params {
    uint32_t n_axes;
    uint32_t p_width;
    uint32_t timing_w;
    uint32_t digit;
} ss_params;

typedef struct ss_sim ss_sim;

uint32_t ss_variants(void);
void ss_variant_params(uint32_t variant, ss_params *out);

/* A fresh block of this variant out of reset (one clock with rst), or NULL. */
ss_sim *ss_new(uint32_t variant);
void ss_free(ss_sim *sim);
/* One clock with rst high and the other inputs zero; the cycle count restarts at 0. */
void ss_reset(ss_sim *sim);
/* One rising edge with these inputs. */
void ss_step(ss_sim *sim, const ss_inputs *in);
void ss_read_outputs(const ss_sim *sim, ss_outputs *out);
uint64_t ss_cycle(const ss_sim *sim);
/* A VCD (or FST) of every signal from now until closed; 0 on success, -1 if not opened. */
int ss_trace_open(ss_sim *sim, const char *path);
void ss_trace_close(ss_sim *sim);

#ifdef __cplusplus
}
#endif

#endif

/* C ABI around the Verilated pbp_interp (the point-by-point comparison interpolator),
 * alone, for its lockstep test against finestep_model::pbp_interp. Built with the
 * module's default parameters and waveform support (the block is small). */
#ifndef PBP_INTERP_SIM_H
#define PBP_INTERP_SIM_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct pi_inputs {
    uint8_t halt;
    uint8_t rec_valid;
    uint8_t rec_arc;
    uint8_t rec_cw;
    uint32_t tick_div;
    int32_t rec_x;
    int32_t rec_y;
    uint32_t rec_steps;
} pi_inputs;

/* req_valid, req_negative, move_up, move_down: bit 0 axis X, bit 1 axis Y. */
typedef struct pi_outputs {
    uint8_t rec_ready;
    uint8_t busy;
    uint8_t done;
    uint8_t req_valid;
    uint8_t req_negative;
    uint8_t move_up;
    uint8_t move_down;
} pi_outputs;

typedef struct pi_sim pi_sim;

/* The Verilated parameters. */
uint32_t pi_coord_width(void);
uint32_t pi_div_width(void);

pi_sim *pi_new(void);
void pi_free(pi_sim *sim);
/* One clock with rst high and the other inputs zero; the cycle count restarts at 0. */
void pi_reset(pi_sim *sim);
/* One rising edge with these inputs. */
void pi_step(pi_sim *sim, const pi_inputs *in);
void pi_read_outputs(const pi_sim *sim, pi_outputs *out);
uint64_t pi_cycle(const pi_sim *sim);
/* A VCD (or FST) of every signal from now until closed; 0 on success, -1 if not opened. */
int pi_trace_open(pi_sim *sim, const char *path);
void pi_trace_close(pi_sim *sim);

#ifdef __cplusplus
}
#endif

#endif

/* C ABI around the Verilated keypad_scan (the 4x4 keypad scan with debounce), alone,
 * for its lockstep test against finestep_model::keypad_scan. Built with the module's
 * default parameters (PRE_W 16, DEB_W 4) and waveform support (the block is small). */
#ifndef KEYPAD_SCAN_SIM_H
#define KEYPAD_SCAN_SIM_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct kp_inputs {
    uint32_t scan_div;
    uint32_t deb_scans;
    uint8_t row_n;
} kp_inputs;

typedef struct kp_outputs {
    uint8_t col_drive;
    uint8_t key_valid;
    uint8_t key_code;
    uint16_t key_down;
} kp_outputs;

typedef struct kp_sim kp_sim;

/* The Verilated parameters. */
uint32_t kp_pre_width(void);
uint32_t kp_deb_width(void);

kp_sim *kp_new(void);
void kp_free(kp_sim *sim);
/* One clock with rst high and the other inputs zero (rows released); the cycle count
 * restarts at 0. */
void kp_reset(kp_sim *sim);
/* One rising edge with these inputs. */
void kp_step(kp_sim *sim, const kp_inputs *in);
void kp_read_outputs(const kp_sim *sim, kp_outputs *out);
uint64_t kp_cycle(const kp_sim *sim);
/* A VCD (or FST) of every signal from now until closed; 0 on success, -1 if not opened. */
int kp_trace_open(kp_sim *sim, const char *path);
void kp_trace_close(kp_sim *sim);

#ifdef __cplusplus
}
#endif

#endif

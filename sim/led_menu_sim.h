/* C ABI around the Verilated led_menu (the gantry card's multiplexed 7-segment display
 * and menu), alone, for its lockstep test against finestep_model::led_menu. Two builds:
 * variant 0 with the module's defaults (8 digits, PRE_W 16, active-high levels) and
 * variant 1 with 5 digits and active-low segments and digits; both with waveform support. */
#ifndef LED_MENU_SIM_H
#define LED_MENU_SIM_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct lm_inputs {
    uint32_t refresh_div;
    uint8_t key_valid;
    uint8_t key_code;
    int16_t sync_err;
    uint8_t alarm_in;
    uint8_t host_wr;
    uint8_t host_addr;
    uint16_t host_wdata;
} lm_inputs;

typedef struct lm_outputs {
    uint16_t host_rdata;
    uint8_t seg;
    uint8_t dig;
    uint8_t sync_mode;
    uint8_t alarm_pending;
    uint8_t page;
} lm_outputs;

/* A build's parameters. */
typedef struct lm_params {
    uint32_t n_dig;
    uint32_t pre_w;
    uint8_t seg_active_low;
    uint8_t dig_active_low;
} lm_params;

typedef struct lm_sim lm_sim;

/* The number of variants and one's parameters. */
uint32_t lm_variants(void);
void lm_variant_params(uint32_t variant, lm_params *out);

/* A block of this variant fresh out of reset; null for an unknown variant. */
lm_sim *lm_new(uint32_t variant);
void lm_free(lm_sim *sim);
/* One clock with rst high and the other inputs zero; the cycle count restarts at 0. */
void lm_reset(lm_sim *sim);
/* One rising edge with these inputs. */
void lm_step(lm_sim *sim, const lm_inputs *in);
void lm_read_outputs(const lm_sim *sim, lm_outputs *out);
uint64_t lm_cycle(const lm_sim *sim);
/* A VCD (or FST) of every signal from now until closed; 0 on success, -1 if not opened. */
int lm_trace_open(lm_sim *sim, const char *path);
void lm_trace_close(lm_sim *sim);

#ifdef __cplusplus
}
#endif

#endif

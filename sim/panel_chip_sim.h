/* C ABI around the Verilated finestep_top built as the gantry card's chip: the panel
 * (keypad_scan, led_menu) and the gantry pair (HAS_PANEL = HAS_GANTRY = 1, STEP_SHARED =
 * 0: a DDA and a shaper per axis), its other parameters the default top's (FT_*). Driven
 * one clock at a time at its pins: the inputs in finestep_top_sim.h's packed word plus
 * panel_row_n in bits 59..62 (finestep_model::top_pins::input::PANEL_ROW_N); the outputs
 * in that header's packed word, and the panel's pins in a word of their own. With
 * waveform support. */
#ifndef PANEL_CHIP_SIM_H
#define PANEL_CHIP_SIM_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define PC_IN_PANEL_ROW_N0 59
/* The panel's pins: bits 0..3 panel_col, 8..15 panel_seg, 16..23 panel_dig. */
#define PC_PANEL_COL0 0
#define PC_PANEL_SEG0 8
#define PC_PANEL_DIG0 16

typedef struct pc_sim pc_sim;

/* A chip at power-on (every register 0); the caller drives rst. */
pc_sim *pc_new(void);
void pc_free(pc_sim *sim);
/* One rising edge with these packed inputs. */
void pc_step(pc_sim *sim, uint64_t inputs);
/* The packed outputs and the panel's pins in the current cycle. */
uint64_t pc_outputs(const pc_sim *sim);
uint32_t pc_panel(const pc_sim *sim);
uint64_t pc_cycle(const pc_sim *sim);
/* A VCD (or FST) of every signal from now until closed; 0 on success, -1 if not opened. */
int pc_trace_open(pc_sim *sim, const char *path);
void pc_trace_close(pc_sim *sim);

#ifdef __cplusplus
}
#endif

#endif

// The shims of the models a minimal build (FS_MINIMAL: rust/finestep-rtl-sys's feature
// `minimal`, and every netlist build) does not Verilate: pbp_interp, keypad_scan,
// led_menu, step_serial and the panel chip. Each constructor returns null (the Rust
// wrappers panic naming the feature), each list of variants is empty, and the functions
// that take an object abort: no object of them can exist. The signatures are the
// headers' (a mismatch does not compile), so the full build's shims and these link the
// same Rust API.
#include <cstdlib>

#include "keypad_scan_sim.h"
#include "led_menu_sim.h"
#include "panel_chip_sim.h"
#include "pbp_interp_sim.h"
#include "step_serial_sim.h"

#ifndef FS_MINIMAL
#error "absent_models.cpp is compiled only in a minimal build"
#endif

extern "C" {

uint32_t pi_coord_width(void) { return PI_COORD_W; }
uint32_t pi_div_width(void) { return PI_DIV_W; }
pi_sim *pi_new(void) { return nullptr; }
void pi_free(pi_sim *) { std::abort(); }
void pi_reset(pi_sim *) { std::abort(); }
void pi_step(pi_sim *, const pi_inputs *) { std::abort(); }
void pi_read_outputs(const pi_sim *, pi_outputs *) { std::abort(); }
uint64_t pi_cycle(const pi_sim *) { std::abort(); }
int pi_trace_open(pi_sim *, const char *) { std::abort(); }
void pi_trace_close(pi_sim *) { std::abort(); }

uint32_t kp_pre_width(void) { return KP_PRE_W; }
uint32_t kp_deb_width(void) { return KP_DEB_W; }
kp_sim *kp_new(void) { return nullptr; }
void kp_free(kp_sim *) { std::abort(); }
void kp_reset(kp_sim *) { std::abort(); }
void kp_step(kp_sim *, const kp_inputs *) { std::abort(); }
void kp_read_outputs(const kp_sim *, kp_outputs *) { std::abort(); }
uint64_t kp_cycle(const kp_sim *) { std::abort(); }
int kp_trace_open(kp_sim *, const char *) { std::abort(); }
void kp_trace_close(kp_sim *) { std::abort(); }

uint32_t lm_variants(void) { return 0; }
void lm_variant_params(uint32_t, lm_params *) { std::abort(); }
lm_sim *lm_new(uint32_t) { return nullptr; }
void lm_free(lm_sim *) { std::abort(); }
void lm_reset(lm_sim *) { std::abort(); }
void lm_step(lm_sim *, const lm_inputs *) { std::abort(); }
void lm_read_outputs(const lm_sim *, lm_outputs *) { std::abort(); }
uint64_t lm_cycle(const lm_sim *) { std::abort(); }
int lm_trace_open(lm_sim *, const char *) { std::abort(); }
void lm_trace_close(lm_sim *) { std::abort(); }

uint32_t ss_variants(void) { return 0; }
void ss_variant_params(uint32_t, ss_params *) { std::abort(); }
ss_sim *ss_new(uint32_t) { return nullptr; }
void ss_free(ss_sim *) { std::abort(); }
void ss_reset(ss_sim *) { std::abort(); }
void ss_step(ss_sim *, const ss_inputs *) { std::abort(); }
void ss_read_outputs(const ss_sim *, ss_outputs *) { std::abort(); }
uint64_t ss_cycle(const ss_sim *) { std::abort(); }
int ss_trace_open(ss_sim *, const char *) { std::abort(); }
void ss_trace_close(ss_sim *) { std::abort(); }

pc_sim *pc_new(void) { return nullptr; }
void pc_free(pc_sim *) { std::abort(); }
void pc_step(pc_sim *, uint64_t) { std::abort(); }
uint64_t pc_outputs(const pc_sim *) { std::abort(); }
uint32_t pc_panel(const pc_sim *) { std::abort(); }
uint64_t pc_cycle(const pc_sim *) { std::abort(); }
int pc_trace_open(pc_sim *, const char *) { std::abort(); }
void pc_trace_close(pc_sim *) { std::abort(); }

}  // extern "C"

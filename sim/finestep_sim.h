/* C ABI around the Verilated finestep_core, for bindgen.
 *
 * One fs_sim is one core instance with its own clock. Inputs are given as a whole
 * fs_inputs struct and are held for the cycles they are used for; outputs are read
 * back in the packed layout below, which finestep_model::pins mirrors bit for bit. */
#ifndef FINESTEP_SIM_H
#define FINESTEP_SIM_H

#include <stddef.h>
#include <stdint.h>

/* FS_MAX_AXES, fs_drive_timing: generated from hdl/interface.toml. */
#include "finestep_interface.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Packed pins word: bit 3i pin_a[i], 3i+1 pin_b[i], 3i+2 pin_en[i] (i < 8),
 * 24+i rate_error[i], 32+i step_lost[i], 40 rec_ready, 41 record_error, 42 block_end,
 * 43 period_boundary. */
#define FS_BIT_RATE_ERROR0 24
#define FS_BIT_STEP_LOST0 32
#define FS_BIT_REC_READY 40
#define FS_BIT_RECORD_ERROR 41
#define FS_BIT_BLOCK_END 42
#define FS_BIT_PERIOD_BOUNDARY 43

typedef struct fs_axis_config {
    fs_drive_timing timing;
    uint8_t mode;
    uint8_t invert;
    uint8_t enable;
} fs_axis_config;

/* Gantry synchronisation (finestep_core's gantry_* ports, see gantry_sync). */
typedef struct fs_gantry {
    uint8_t enable;
    uint8_t sync;
    uint8_t master;
    uint8_t slave;
    uint32_t tick;
    uint16_t deadband;
    uint16_t limit;
    uint32_t enc_master;
    uint32_t enc_slave;
    uint8_t clear_counters;
} fs_gantry;

typedef struct fs_inputs {
    uint8_t run;
    uint8_t clear_errors;
    uint8_t halt;
    uint8_t rec_valid;
    uint8_t rec_flags;
    uint32_t period_clocks;
    int32_t rec_inc[FS_MAX_AXES];
    fs_axis_config axes[FS_MAX_AXES];
    fs_gantry gantry;
} fs_inputs;

/* gantry_flags: bit 0 engaged, 1 alarm, 2 refused. */
typedef struct fs_outputs {
    uint64_t pins;
    uint32_t positions[FS_MAX_AXES];
    uint32_t gantry_error;
    uint16_t gantry_corrections;
    uint8_t gantry_flags;
} fs_outputs;

/* The outputs after the edge that ended cycle `cycle - 1`, recorded when they changed. */
typedef struct fs_event {
    uint64_t cycle;
    fs_outputs outputs;
} fs_event;

typedef struct fs_chunk_end {
    uint64_t cycles;  /* cycles run by this call */
    uint8_t consumed; /* the call stopped because a record was consumed */
} fs_chunk_end;

typedef struct fs_sim fs_sim;

/* Build-time parameters of the Verilated core. */
uint32_t fs_n_axes(void);
uint32_t fs_p_width(void);
uint32_t fs_timing_width(void);
/* 1 when waveforms are written as FST, 0 for VCD. */
int fs_trace_is_fst(void);

/* STEP_DIGIT of the core with the digit-serial step engine (variant 2). */
uint32_t fs_serial_digit(void);
/* Variants 3 and 4: the core with the point-by-point interpolator (HAS_PBP) with a DDA
 * and a shaper per axis and the gantry block (3) and with the step engine (4), traced.
 * A core built without waveform support (the fast one): variant 1 with the gantry block
 * and a DDA and a shaper per axis, 2 with the digit-serial step engine (STEP_DIGIT =
 * fs_serial_digit()), else (0) with the step engine. */
fs_sim *fs_new(int variant);
/* A core that can write waveforms (fs_trace_open); slower. */
fs_sim *fs_new_traced(int variant);
void fs_free(fs_sim *sim);

/* One clock with rst high and all other inputs zero; the cycle count restarts at 0 and
 * an open waveform is closed. */
void fs_reset(fs_sim *sim);
uint64_t fs_cycle(const fs_sim *sim);
void fs_read_outputs(const fs_sim *sim, fs_outputs *out);
/* One rising edge with these inputs. */
void fs_step(fs_sim *sim, const fs_inputs *in);
/* Up to max_cycles edges with these inputs. After each edge whose outputs differ from
 * the previous cycle's, an event is stored. Stops early after the edge that consumed a
 * record (rec_ready and rec_valid before it), or when `capacity` events are stored. */
fs_chunk_end fs_run_chunk(fs_sim *sim, const fs_inputs *in, uint64_t max_cycles,
                          fs_event *events, size_t capacity, size_t *n_events);

/* Waveform tracing on a core from fs_new_traced: open a file (VCD, or FST when
 * fs_trace_is_fst()), dump every cycle until closed. Returns 0 on success, -1 when the
 * file cannot be opened or the core was made by fs_new. `levels` is the depth of the
 * hierarchy traced: 0 for the ports only, 99 for everything. */
int fs_trace_open(fs_sim *sim, const char *path, uint32_t levels);
void fs_trace_close(fs_sim *sim);

#ifdef __cplusplus
}
#endif

#endif

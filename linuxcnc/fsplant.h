/* The C ABI of rust/finestep-hal-plant (src/ffi.rs, where each function is documented):
 * the closed-loop machine of finestep-plant behind the fsplant HAL component. */
#ifndef FSPLANT_H
#define FSPLANT_H

#include <stdint.h>

struct fs_plant;

struct fs_plant *fs_plant_new(uint32_t axes, uint64_t tau_clocks, uint32_t counts_per_step, uint64_t slot_clocks,
                              uint64_t slots_per_period);
void fs_plant_free(struct fs_plant *p);
int fs_plant_gate(const struct fs_plant *p);
void fs_plant_sample(const struct fs_plant *p, uint32_t levels);
int fs_plant_read(const struct fs_plant *p, int64_t *counts, uint32_t n);
void fs_plant_write(const struct fs_plant *p);
uint32_t fs_plant_sync_errors(const struct fs_plant *p);

#endif

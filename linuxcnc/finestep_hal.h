/* The C ABI of rust/finestep-hal (src/ffi.rs, where each function is documented; a test
 * there checks these prototypes against the Rust ones):
 * the driver behind the finestep HAL component. Scalars and out-pointers only; every
 * int-returning call gives 0 on success and -1 on failure, the message then in
 * fs_hal_last_error. */
#ifndef FINESTEP_HAL_H
#define FINESTEP_HAL_H

#include <stddef.h>
#include <stdint.h>

struct fs_hal;

struct fs_hal *fs_hal_open(const char *bus, char *err, size_t err_len);
void fs_hal_close(struct fs_hal *h);
int fs_hal_caps(const struct fs_hal *h, uint32_t *n_axes, uint32_t *n_enc, uint32_t *clock_hz, int *paced);
int fs_hal_set_stepgen(struct fs_hal *h, uint32_t axis, double position_cmd, double position_scale, double maxvel,
                       double maxaccel, int enable, uint32_t steplen_ns, uint32_t stepspace_ns, uint32_t dirsetup_ns,
                       uint32_t dirhold_ns, uint32_t step_type);
int fs_hal_set_encoder(struct fs_hal *h, uint32_t channel, double scale, int reset, int counter_mode, int filter,
                       int index_enable);
int fs_hal_read(struct fs_hal *h, int64_t period_ns);
int fs_hal_write(struct fs_hal *h, int64_t period_ns, int enable, uint32_t watchdog_timeout_ns);
int fs_hal_stepgen(struct fs_hal *h, uint32_t axis, int32_t *counts, double *position_fb, double *velocity_fb,
                   uint32_t *limited);
int fs_hal_encoder(struct fs_hal *h, uint32_t channel, int32_t *count, double *position, double *velocity,
                   int *index_enable);
int fs_hal_mpg(struct fs_hal *h, int32_t *count, int32_t *detents);
int fs_hal_turn_wheel(struct fs_hal *h, int64_t edges);
int fs_hal_status(struct fs_hal *h, int clear_watchdog, int *estop_ok, int *watchdog_bit, int *running);
uint32_t fs_hal_last_error(const struct fs_hal *h, char *buf, size_t len);

#endif

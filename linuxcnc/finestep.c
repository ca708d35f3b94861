/* finestep: the realtime HAL component that makes a finestep chip LinuxCNC's motion
 * hardware, named as hostmot2 names its pins, parameters and functions so that an hm2
 * configuration ports by renaming. The HAL side lives here; the driver (record
 * encoding, the SPI frames, the transport) is rust/finestep-hal, linked in as a static
 * library and called through linuxcnc/finestep_hal.h.
 *
 *   loadrt finestep bus=sim:/tmp/finestep.sock     (or bus=spidev:/dev/spidev0.0@4000000)
 *   addf finestep.0.read  servo-thread            (first: one coherent latched read)
 *   addf finestep.0.write servo-thread            (last: one period record)
 *
 * Pins and parameters (NN per CAPS.N_AXES / CAPS.N_ENC, as the chip reports them):
 *   finestep.0.stepgen.NN.{position-cmd (in), position-fb, velocity-fb, counts, limited (out), enable (in)}
 *     params position-scale, maxvel, maxaccel, step_type, steplen, stepspace, dirsetup, dirhold
 *   finestep.0.encoder.NN.{count, position, velocity (out), reset (in), index-enable (io)};
 *     params scale, counter-mode, filter
 *   finestep.0.enable (in: iocontrol.0.user-enable-out), finestep.0.estop-ok (out: iocontrol.0.emc-enable-in:
 *   enable, with the chip's E-stop input released and the watchdog bit clear),
 *   finestep.0.running, finestep.0.error (out), finestep.0.watchdog.has_bit (io), param
 *   finestep.0.watchdog.timeout_ns.
 *   finestep.0.mpg.{count, detents} (out): the hand wheel in quadrature edges and in detents (4 edges),
 *   for axis.L.jog-counts; finestep.0.sim.wheel-edges (in, a simulated chip only): where a test wants
 *   the simulated wheel, in edges (each change turns it by the difference while the chip's time passes).
 */

#include "rtapi.h"
#include "rtapi_app.h"
#include "rtapi_string.h"
#include "hal.h"

#include "finestep_hal.h"

MODULE_AUTHOR("finestep");
MODULE_DESCRIPTION("finestep motion core: step generators, encoders and watchdog over SPI");
MODULE_LICENSE("Dual MIT/GPL");

static char *bus = "";
RTAPI_MP_STRING(bus, "the chip: spidev:/dev/spidevB.C[@SCK_HZ] or sim:SOCKET");

#define NAME "finestep.0"

struct stepgen {
    hal_float_t *position_cmd, *position_fb, *velocity_fb;
    hal_s32_t *counts;
    hal_u32_t *limited;
    hal_bit_t *enable;
    hal_float_t position_scale, maxvel, maxaccel;
    hal_u32_t step_type, steplen, stepspace, dirsetup, dirhold;
};

struct encoder {
    hal_s32_t *count;
    hal_float_t *position, *velocity;
    hal_bit_t *reset, *index_enable;
    hal_float_t scale;
    hal_bit_t counter_mode, filter;
};

struct finestep {
    struct fs_hal *driver;
    uint32_t n_axes, n_enc;
    struct stepgen *stepgens;
    struct encoder *encoders;
    hal_bit_t *enable, *estop_ok, *running, *error, *has_bit;
    hal_s32_t *mpg_count, *mpg_detents, *wheel_edges;
    int32_t wheel_turned;
    int paced;
    hal_u32_t timeout_ns;
    int reported_bit;
    uint32_t errors_seen;
    char message[256];
};

static int comp_id;
static struct finestep *fs;

/* Prints the driver's error once per new message and raises the error pin. */
static void report(struct finestep *f, int rc)
{
    char message[sizeof f->message];
    *f->error = rc != 0;
    if (rc == 0)
        return;
    f->errors_seen = fs_hal_last_error(f->driver, message, sizeof message);
    if (strcmp(message, f->message) != 0) {
        rtapi_print_msg(RTAPI_MSG_ERR, NAME ": %s\n", message);
        rtapi_strxcpy(f->message, message);
    }
}

static void read_fn(void *arg, long period)
{
    struct finestep *f = arg;
    uint32_t i;
    int estop_ok = 0, bit = 0, running = 0;
    int rc = 0;

    for (i = 0; i < f->n_enc; i++) {
        struct encoder *e = &f->encoders[i];
        rc |= fs_hal_set_encoder(f->driver, i, e->scale, *e->reset, e->counter_mode, e->filter, *e->index_enable);
    }
    rc |= fs_hal_read(f->driver, period);
    for (i = 0; i < f->n_axes; i++) {
        struct stepgen *s = &f->stepgens[i];
        int32_t counts;
        uint32_t limited;
        double pos, vel;
        if (fs_hal_stepgen(f->driver, i, &counts, &pos, &vel, &limited) == 0) {
            *s->counts = counts;
            *s->position_fb = pos;
            *s->velocity_fb = vel;
            *s->limited = limited;
        }
    }
    for (i = 0; i < f->n_enc; i++) {
        struct encoder *e = &f->encoders[i];
        int32_t count;
        double pos, vel;
        int index_enable;
        if (fs_hal_encoder(f->driver, i, &count, &pos, &vel, &index_enable) == 0) {
            *e->count = count;
            *e->position = pos;
            *e->velocity = vel;
            /* hostmot2's handshake: LinuxCNC sets it to home to the index, the driver
               clears it in the read that finds the index (count 0 there). */
            *e->index_enable = index_enable;
        }
    }
    {
        int32_t count = 0, detents = 0;
        if (fs_hal_mpg(f->driver, &count, &detents) == 0) {
            *f->mpg_count = count;
            *f->mpg_detents = detents;
        }
    }
    /* hostmot2's has_bit: set when the watchdog bites, re-armed by writing false. */
    rc |= fs_hal_status(f->driver, f->reported_bit && !*f->has_bit, &estop_ok, &bit, &running);
    *f->has_bit = bit;
    f->reported_bit = bit;
    /* The E-stop loop iocontrol expects (user-enable-out back into emc-enable-in), broken
     * by the chip's E-stop input or the watchdog bit. */
    *f->estop_ok = estop_ok && !bit && *f->enable;
    *f->running = running;
    report(f, rc);
}

static void write_fn(void *arg, long period)
{
    struct finestep *f = arg;
    uint32_t i;
    int rc = 0;

    for (i = 0; i < f->n_axes; i++) {
        struct stepgen *s = &f->stepgens[i];
        rc |= fs_hal_set_stepgen(f->driver, i, *s->position_cmd, s->position_scale, s->maxvel, s->maxaccel, *s->enable,
                                 s->steplen, s->stepspace, s->dirsetup, s->dirhold, s->step_type);
    }
    if (f->paced && *f->wheel_edges != f->wheel_turned) {
        rc |= fs_hal_turn_wheel(f->driver, (int64_t)*f->wheel_edges - f->wheel_turned);
        f->wheel_turned = *f->wheel_edges;
    }
    rc |= fs_hal_write(f->driver, period, *f->enable, f->timeout_ns);
    report(f, rc);
}

static int export_stepgen(struct stepgen *s, int i)
{
    int r = 0;
    r |= hal_pin_float_newf(HAL_IN, &s->position_cmd, comp_id, NAME ".stepgen.%02d.position-cmd", i);
    r |= hal_pin_float_newf(HAL_OUT, &s->position_fb, comp_id, NAME ".stepgen.%02d.position-fb", i);
    r |= hal_pin_float_newf(HAL_OUT, &s->velocity_fb, comp_id, NAME ".stepgen.%02d.velocity-fb", i);
    r |= hal_pin_s32_newf(HAL_OUT, &s->counts, comp_id, NAME ".stepgen.%02d.counts", i);
    r |= hal_pin_u32_newf(HAL_OUT, &s->limited, comp_id, NAME ".stepgen.%02d.limited", i);
    r |= hal_pin_bit_newf(HAL_IN, &s->enable, comp_id, NAME ".stepgen.%02d.enable", i);
    r |= hal_param_float_newf(HAL_RW, &s->position_scale, comp_id, NAME ".stepgen.%02d.position-scale", i);
    r |= hal_param_float_newf(HAL_RW, &s->maxvel, comp_id, NAME ".stepgen.%02d.maxvel", i);
    r |= hal_param_float_newf(HAL_RW, &s->maxaccel, comp_id, NAME ".stepgen.%02d.maxaccel", i);
    r |= hal_param_u32_newf(HAL_RW, &s->step_type, comp_id, NAME ".stepgen.%02d.step_type", i);
    r |= hal_param_u32_newf(HAL_RW, &s->steplen, comp_id, NAME ".stepgen.%02d.steplen", i);
    r |= hal_param_u32_newf(HAL_RW, &s->stepspace, comp_id, NAME ".stepgen.%02d.stepspace", i);
    r |= hal_param_u32_newf(HAL_RW, &s->dirsetup, comp_id, NAME ".stepgen.%02d.dirsetup", i);
    r |= hal_param_u32_newf(HAL_RW, &s->dirhold, comp_id, NAME ".stepgen.%02d.dirhold", i);
    s->position_scale = 1.0;
    s->maxvel = 0.0;
    s->maxaccel = 0.0;
    s->step_type = 0;
    s->steplen = 2000;
    s->stepspace = 2000;
    s->dirsetup = 5000;
    s->dirhold = 5000;
    return r;
}

static int export_encoder(struct encoder *e, int i)
{
    int r = 0;
    r |= hal_pin_s32_newf(HAL_OUT, &e->count, comp_id, NAME ".encoder.%02d.count", i);
    r |= hal_pin_float_newf(HAL_OUT, &e->position, comp_id, NAME ".encoder.%02d.position", i);
    r |= hal_pin_float_newf(HAL_OUT, &e->velocity, comp_id, NAME ".encoder.%02d.velocity", i);
    r |= hal_pin_bit_newf(HAL_IN, &e->reset, comp_id, NAME ".encoder.%02d.reset", i);
    r |= hal_pin_bit_newf(HAL_IO, &e->index_enable, comp_id, NAME ".encoder.%02d.index-enable", i);
    r |= hal_param_float_newf(HAL_RW, &e->scale, comp_id, NAME ".encoder.%02d.scale", i);
    r |= hal_param_bit_newf(HAL_RW, &e->counter_mode, comp_id, NAME ".encoder.%02d.counter-mode", i);
    r |= hal_param_bit_newf(HAL_RW, &e->filter, comp_id, NAME ".encoder.%02d.filter", i);
    e->scale = 1.0;
    e->counter_mode = 0;
    e->filter = 1;
    return r;
}

int rtapi_app_main(void)
{
    char err[256];
    uint32_t clock_hz = 0, i;
    int paced = 0, r = 0;

    comp_id = hal_init("finestep");
    if (comp_id < 0)
        return comp_id;
    fs = hal_malloc(sizeof *fs);
    if (!fs) {
        hal_exit(comp_id);
        return -ENOMEM;
    }
    memset(fs, 0, sizeof *fs);
    fs->driver = fs_hal_open(bus, err, sizeof err);
    if (!fs->driver) {
        rtapi_print_msg(RTAPI_MSG_ERR, NAME ": %s\n", err);
        hal_exit(comp_id);
        return -ENODEV;
    }
    fs_hal_caps(fs->driver, &fs->n_axes, &fs->n_enc, &clock_hz, &paced);
    fs->paced = paced;
    fs->stepgens = hal_malloc(fs->n_axes * sizeof *fs->stepgens + 1);
    fs->encoders = hal_malloc(fs->n_enc * sizeof *fs->encoders + 1);
    if (!fs->stepgens || !fs->encoders)
        r = -ENOMEM;
    for (i = 0; r == 0 && i < fs->n_axes; i++)
        r = export_stepgen(&fs->stepgens[i], i);
    for (i = 0; r == 0 && i < fs->n_enc; i++)
        r = export_encoder(&fs->encoders[i], i);
    if (r == 0) {
        r |= hal_pin_bit_newf(HAL_IN, &fs->enable, comp_id, NAME ".enable");
        r |= hal_pin_bit_newf(HAL_OUT, &fs->estop_ok, comp_id, NAME ".estop-ok");
        r |= hal_pin_bit_newf(HAL_OUT, &fs->running, comp_id, NAME ".running");
        r |= hal_pin_bit_newf(HAL_OUT, &fs->error, comp_id, NAME ".error");
        r |= hal_pin_bit_newf(HAL_IO, &fs->has_bit, comp_id, NAME ".watchdog.has_bit");
        r |= hal_param_u32_newf(HAL_RW, &fs->timeout_ns, comp_id, NAME ".watchdog.timeout_ns");
        r |= hal_pin_s32_newf(HAL_OUT, &fs->mpg_count, comp_id, NAME ".mpg.count");
        r |= hal_pin_s32_newf(HAL_OUT, &fs->mpg_detents, comp_id, NAME ".mpg.detents");
        if (paced)
            r |= hal_pin_s32_newf(HAL_IN, &fs->wheel_edges, comp_id, NAME ".sim.wheel-edges");
        fs->timeout_ns = 5000000;
    }
    if (r == 0)
        r = hal_export_funct(NAME ".read", read_fn, fs, 1, 0, comp_id);
    if (r == 0)
        r = hal_export_funct(NAME ".write", write_fn, fs, 1, 0, comp_id);
    if (r != 0) {
        rtapi_print_msg(RTAPI_MSG_ERR, NAME ": exporting pins and functions failed (%d)\n", r);
        fs_hal_close(fs->driver);
        hal_exit(comp_id);
        return r;
    }
    rtapi_print_msg(RTAPI_MSG_INFO, NAME ": %s: %u stepgens, %u encoders, %u Hz%s\n", bus, fs->n_axes, fs->n_enc,
                    clock_hz, paced ? ", simulated chip paced by the servo thread" : "");
    hal_ready(comp_id);
    return 0;
}

void rtapi_app_exit(void)
{
    if (fs && fs->driver)
        fs_hal_close(fs->driver);
    hal_exit(comp_id);
}

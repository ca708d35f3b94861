/* fsplant: the closed-loop machine of rust/finestep-plant (drives lagging their step pins,
 * a linear grating on each: PlantConfig::lagging, the plant `finestep sim-chip --lag-clocks`
 * puts on the simulated chip's pins) as a HAL component, for LinuxCNC's own software
 * stepgen: the same plant under the other step generator (docs/linuxcnc.md#closed-loop).
 * The plant and the lockstep of the two threads are rust/finestep-hal-plant, linked in
 * as a static library and called through linuxcnc/fsplant.h.
 *
 *   loadrt stepgen step_type=0,0,0
 *   loadrt fsplant axes=3 lag_clocks=50000 counts_per_step=1 clock_hz=50000000 base_ns=5000 servo_ns=1000000
 *   addf fsplant.0.read servo-thread    (first: the gratings' counts at the period boundary)
 *   addf fsplant.0.run  servo-thread    (last, after stepgen.update-freq: the period's base periods)
 *
 * No base thread: LinuxCNC's uspace build without a real-time kernel serialises its
 * threads under one lock, so a base thread cannot wait for the servo thread (and a free
 * base thread runs a varying number of times per servo period on a loaded host). Instead
 * fsplant.0.run calls stepgen's own make-pulses function (found by name in HAL) servo_ns /
 * base_ns times per servo period, each call one base period of base_ns, and samples the
 * step pins after each: the pulses of a perfectly periodic base thread, deterministic.
 *
 * Pins: fsplant.0.axis.N.{step, dir} (in: stepgen's; dir high = negative steps, as stepgen
 * drives it), fsplant.0.encoder.NN.{count, position} (out) with param scale (counts per unit),
 * fsplant.0.sync-errors (out: waits that timed out; 0 in an exact run).
 */

#include "rtapi.h"
#include "rtapi_app.h"
#include "rtapi_string.h"
#include "hal.h"

#include "fsplant.h"

MODULE_AUTHOR("finestep");
MODULE_DESCRIPTION("finestep's simulated closed-loop machine for LinuxCNC's software stepgen");
MODULE_LICENSE("Dual MIT/GPL");

static int axes = 3;
RTAPI_MP_INT(axes, "axes (1 to 16)");
static int lag_clocks = 50000;
RTAPI_MP_INT(lag_clocks, "the drives' lag time constant, core clocks");
static int counts_per_step = 1;
RTAPI_MP_INT(counts_per_step, "the gratings' counts per step");
static int clock_hz = 50000000;
RTAPI_MP_INT(clock_hz, "the core clock the plant counts");
static int base_ns = 10000;
RTAPI_MP_INT(base_ns, "the base thread's period, ns");
static int servo_ns = 1000000;
RTAPI_MP_INT(servo_ns, "the servo thread's period, ns (a multiple of base_ns)");

static char *pulses = "stepgen.make-pulses";
RTAPI_MP_STRING(pulses, "the HAL function making the step pulses, run base_ns by base_ns");

/* hal_lib's lookup (exported by hal_lib.so; its header hal_priv.h is not installed). */
struct hal_funct_view;
extern struct hal_funct_view *halpr_find_funct_by_name(const char *name);
/* The head of hal_priv.h's hal_funct_t up to the two fields used here, as LinuxCNC 2.9 on
 * a 64-bit host lays it out (read from memory: next_ptr and owner_ptr are 8-byte SHMFIELDs):
 * next_ptr, uses_fp, owner_ptr, reentrant and users fill 32 bytes, then arg and funct. */
struct hal_funct_view {
    char head[32];
    void *arg;
    void (*funct)(void *, long);
};

#define NAME "fsplant.0"
#define MAX_AXES 16

struct axis {
    hal_bit_t *step, *dir;
    hal_s32_t *count;
    hal_float_t *position;
    hal_float_t scale;
};

struct fsplant {
    struct fs_plant *plant;
    void *pulses_arg;
    void (*pulses)(void *, long);
    int primed;
    struct axis axis[MAX_AXES];
    hal_u32_t *sync_errors;
};

static int comp_id;
static struct fsplant *fp;

static void run_fn(void *arg, long period)
{
    struct fsplant *f = arg;
    long slot, slots = servo_ns / base_ns;
    int i;
    (void)period;
    fs_plant_write(f->plant);
    for (slot = 0; slot < slots; slot++) {
        uint32_t levels = 0;
        fs_plant_gate(f->plant);
        f->pulses(f->pulses_arg, base_ns);
        for (i = 0; i < axes; i++) {
            levels |= (uint32_t)(*f->axis[i].step != 0) << (2 * i);
            levels |= (uint32_t)(*f->axis[i].dir == 0) << (2 * i + 1);
        }
        fs_plant_sample(f->plant, levels);
    }
}

static void read_fn(void *arg, long period)
{
    struct fsplant *f = arg;
    int64_t counts[MAX_AXES];
    int i;
    (void)period;
    if (!f->primed) {
        /* stepgen's update-freq takes the base period from make-pulses' last call: one
         * call before the first (the machine still off, the step generators idle). */
        f->pulses(f->pulses_arg, base_ns);
        f->primed = 1;
    }
    fs_plant_read(f->plant, counts, (uint32_t)axes);
    for (i = 0; i < axes; i++) {
        struct axis *a = &f->axis[i];
        *a->count = (hal_s32_t)counts[i];
        *a->position = a->scale != 0.0 ? (double)counts[i] / a->scale : 0.0;
    }
    *f->sync_errors = fs_plant_sync_errors(f->plant);
}

int rtapi_app_main(void)
{
    uint64_t slot_clocks;
    int i, r = 0;

    if (axes < 1 || axes > MAX_AXES || base_ns <= 0 || servo_ns <= 0 || servo_ns % base_ns != 0 || lag_clocks < 1 ||
        counts_per_step < 1 || clock_hz <= 0) {
        rtapi_print_msg(RTAPI_MSG_ERR, NAME ": bad parameters (axes 1..16; servo_ns a multiple of base_ns)\n");
        return -EINVAL;
    }
    slot_clocks = (uint64_t)base_ns * (uint64_t)clock_hz / 1000000000u;
    if (slot_clocks * 1000000000u != (uint64_t)base_ns * (uint64_t)clock_hz) {
        rtapi_print_msg(RTAPI_MSG_ERR, NAME ": base_ns %d is not a whole number of clocks at %d Hz\n", base_ns,
                        clock_hz);
        return -EINVAL;
    }
    comp_id = hal_init("fsplant");
    if (comp_id < 0)
        return comp_id;
    fp = hal_malloc(sizeof *fp);
    if (!fp) {
        hal_exit(comp_id);
        return -ENOMEM;
    }
    memset(fp, 0, sizeof *fp);
    {
        struct hal_funct_view *f = halpr_find_funct_by_name(pulses);
        if (!f || !f->funct) {
            rtapi_print_msg(RTAPI_MSG_ERR, NAME ": no HAL function %s (load stepgen first)\n", pulses);
            hal_exit(comp_id);
            return -ENOENT;
        }
        fp->pulses = f->funct;
        fp->pulses_arg = f->arg;
    }
    fp->plant = fs_plant_new((uint32_t)axes, (uint64_t)lag_clocks, (uint32_t)counts_per_step, slot_clocks,
                             (uint64_t)(servo_ns / base_ns));
    if (!fp->plant) {
        hal_exit(comp_id);
        return -EINVAL;
    }
    for (i = 0; r == 0 && i < axes; i++) {
        struct axis *a = &fp->axis[i];
        r |= hal_pin_bit_newf(HAL_IN, &a->step, comp_id, NAME ".axis.%d.step", i);
        r |= hal_pin_bit_newf(HAL_IN, &a->dir, comp_id, NAME ".axis.%d.dir", i);
        r |= hal_pin_s32_newf(HAL_OUT, &a->count, comp_id, NAME ".encoder.%02d.count", i);
        r |= hal_pin_float_newf(HAL_OUT, &a->position, comp_id, NAME ".encoder.%02d.position", i);
        r |= hal_param_float_newf(HAL_RW, &a->scale, comp_id, NAME ".encoder.%02d.scale", i);
        a->scale = 1.0;
    }
    if (r == 0)
        r = hal_pin_u32_newf(HAL_OUT, &fp->sync_errors, comp_id, NAME ".sync-errors");
    if (r == 0)
        r = hal_export_funct(NAME ".read", read_fn, fp, 1, 0, comp_id);
    if (r == 0)
        r = hal_export_funct(NAME ".run", run_fn, fp, 1, 0, comp_id);
    if (r == 0) {
        /* The layout above is an assumption about this LinuxCNC: checked on our own function
         * (its argument and code are known), refused with a clear message if it differs. */
        struct hal_funct_view *own = halpr_find_funct_by_name(NAME ".run");
        if (own == 0 || own->arg != (void *)fp || own->funct != run_fn) {
            rtapi_print_msg(RTAPI_MSG_ERR,
                            NAME ": hal_lib's hal_funct_t is not laid out as this component assumes "
                            "(LinuxCNC 2.9, 64-bit); cannot drive %s\n",
                            pulses);
            r = -EINVAL;
        }
    }
    if (r != 0) {
        rtapi_print_msg(RTAPI_MSG_ERR, NAME ": exporting pins and functions failed (%d)\n", r);
        fs_plant_free(fp->plant);
        hal_exit(comp_id);
        return r;
    }
    rtapi_print_msg(RTAPI_MSG_INFO, NAME ": %d axes, lag %d clocks, %d counts a step, %llu clocks a base period\n",
                    axes, lag_clocks, counts_per_step, (unsigned long long)slot_clocks);
    hal_ready(comp_id);
    return 0;
}

void rtapi_app_exit(void)
{
    if (fp && fp->plant)
        fs_plant_free(fp->plant);
    hal_exit(comp_id);
}

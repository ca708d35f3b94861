// C ABI shim around the Verilated finestep_top (see finestep_top_sim.h). As for the
// core, each variant is linked twice: Vfinestep_top (fast) and Vfinestep_top_traced with
// finestep_top's defaults; Vfinestep_top_motion, untraced only, without the spindle and
// the logic outputs (HAS_SPINDLE = HAS_OUTPUTS = N_GPIO = 0, as every board top), and
// Vfinestep_top_motion_nompg, untraced only, without the hand wheel and the jog too
// (HAS_MPG = 0), and Vfinestep_top_motion_serial, untraced only, the motion chip with
// the core's digit-serial step engine (STEP_DIGIT = FT_SERIAL_DIGIT, as the CPLD boards):
// ft_new_traced makes them untraced, and ft_trace_open fails on them. A
// synthesised netlist (FT_NETLIST, rust/finestep-rtl-sys's netlist features) is Verilated
// once, without tracing: ft_new and ft_new_traced make that top for either variant, and
// ft_trace_open fails on it. A minimal RTL build (FS_MINIMAL, the feature `minimal`) has
// the default top, untraced and traced, and the motion chip: the other variants are null.
#include "finestep_top_sim.h"

#include <memory>

#include "Vfinestep_top.h"
#ifndef FT_NETLIST
#include "Vfinestep_top_motion.h"
#include "Vfinestep_top_traced.h"
#ifndef FS_MINIMAL
#include "Vfinestep_top_motion_nompg.h"
#include "Vfinestep_top_motion_serial.h"
#endif
#endif
#ifdef FS_CLK_PREV
#include "Vfinestep_top___024root.h"
#include "Vfinestep_top_motion___024root.h"
#ifndef FS_MINIMAL
#include "Vfinestep_top_motion_nompg___024root.h"
#include "Vfinestep_top_motion_serial___024root.h"
#endif
#endif
#include "finestep_top_pins.h"
#include "verilated_trace.h"

#ifndef FT_N_AXES
#error "FT_N_AXES, FT_P_WIDTH, FT_TIMING_W, FT_FIFO_DEPTH_LOG2, FT_N_ENC, FT_HAS_MPG, FT_STEP_SHARED, FT_HAS_SPINDLE, FT_HAS_OUTPUTS, FT_N_GPIO and FT_HAS_PBP must match the Verilated parameters"
#endif

struct ft_sim {
    uint64_t cycle = 0;
    uint64_t outputs = 0;

    virtual ~ft_sim() = default;
    virtual uint64_t run(uint64_t inputs, uint64_t cycles, ft_event *events, size_t capacity,
                         size_t *n_events) = 0;
    virtual int trace_open(const char *path, uint32_t levels) = 0;
    virtual void trace_close() = 0;
};

namespace {

template <typename Model, bool TRACED>
struct TopSim final : ft_sim {
    std::unique_ptr<VerilatedContext> context;
    std::unique_ptr<Model> top;
    std::unique_ptr<TraceFile> trace;

    TopSim() : context(new VerilatedContext) {
        if (TRACED) context->traceEverOn(true);
        top.reset(new Model(context.get()));
        top->clk = 0;
        finestep::apply_top_inputs(*top, idle_inputs());
        top->eval();
        outputs = read_outputs();
    }

    ~TopSim() override {
        trace_close();
        top->final();
    }

    static uint64_t idle_inputs() {
        return (1ULL << FT_IN_SPI_CS_N) | (1ULL << FT_IN_BUS_CS_N) | (1ULL << FT_IN_BUS_ADV_N) |
               (1ULL << FT_IN_BUS_RD_N) | (1ULL << FT_IN_BUS_WR_N);
    }

    // The new inputs, settled with the clock low (the outputs are read only after edges:
    // where the next edge's eval() settles them first, it alone does).
    void apply(uint64_t in) {
        finestep::apply_top_inputs(*top, in);
        if (!finestep::edge_settles_inputs<TRACED>()) top->eval();
    }

    uint64_t read_outputs() const { return finestep::read_top_outputs(*top); }

    // Cycle c is drawn from time 2c (its rising edge) to 2c+2, its inputs at 2c+1.
    void edge() {
        if (TRACED && trace) trace->dump(2 * cycle + 1);
        top->clk = 1;
        top->eval();
        ++cycle;
        if (TRACED && trace) trace->dump(2 * cycle);
        finestep::clock_fall<TRACED>(*top);
    }

    uint64_t run(uint64_t inputs, uint64_t cycles, ft_event *events, size_t capacity,
                 size_t *n_events) override {
        apply(inputs);
        uint64_t ran = 0;
        size_t stored = 0;
        while (ran < cycles && stored < capacity) {
            edge();
            ++ran;
            const uint64_t now = read_outputs();
            if (now != outputs) {
                outputs = now;
                events[stored].cycle = cycle;
                events[stored].outputs = now;
                ++stored;
            }
        }
        *n_events = stored;
        return ran;
    }

    int trace_open(const char *path, uint32_t levels) override {
        return finestep::open_trace<TRACED>(trace, *top, path, levels);
    }

    void trace_close() override { finestep::close_trace(trace); }
};

// Only a traced model has trace(); give the untraced ones a stub so one template fits.
template <typename Base>
struct Untraced : Base {
    using Base::Base;
    void trace(TraceFile *, int) {}
};

#ifndef FT_NETLIST
bool is_motion(uint32_t variant) {
    return variant == FT_VARIANT_MOTION || variant == FT_VARIANT_MOTION_NO_MPG || variant == FT_VARIANT_MOTION_SERIAL;
}
bool is_no_mpg(uint32_t variant) { return variant == FT_VARIANT_MOTION_NO_MPG; }
bool is_serial(uint32_t variant) { return variant == FT_VARIANT_MOTION_SERIAL; }
#else
bool is_motion(uint32_t) { return false; }
bool is_no_mpg(uint32_t) { return false; }
bool is_serial(uint32_t) { return false; }
#endif

}  // namespace

extern "C" {

uint32_t ft_n_axes(void) { return FT_N_AXES; }
uint32_t ft_p_width(void) { return FT_P_WIDTH; }
uint32_t ft_timing_width(void) { return FT_TIMING_W; }
uint32_t ft_fifo_depth_log2(void) { return FT_FIFO_DEPTH_LOG2; }
uint32_t ft_n_enc(void) { return FT_N_ENC; }
uint32_t ft_step_shared(void) { return FT_STEP_SHARED; }
uint32_t ft_has_mpg(uint32_t variant) { return is_no_mpg(variant) ? 0 : FT_HAS_MPG; }
uint32_t ft_has_spindle(uint32_t variant) { return is_motion(variant) ? 0 : FT_HAS_SPINDLE; }
uint32_t ft_has_outputs(uint32_t variant) { return is_motion(variant) ? 0 : FT_HAS_OUTPUTS; }
uint32_t ft_n_gpio(uint32_t variant) { return is_motion(variant) ? 0 : FT_N_GPIO; }
// The motion variants are built as the board tops, without the pbp block (HAS_PBP = 0).
uint32_t ft_has_pbp(uint32_t variant) { return is_motion(variant) ? 0 : FT_HAS_PBP; }
uint32_t ft_step_digit(uint32_t variant) { return is_serial(variant) ? FT_SERIAL_DIGIT : 0; }
// The serial variant is Verilated with the MAX II's ONE_SNAPSHOT = 1, INC_WRITE_ONLY = 1 and
// AXIS_WRITE_ONLY = 1 (build.rs).
uint32_t ft_one_snapshot(uint32_t variant) { return is_serial(variant) ? 1 : 0; }
uint32_t ft_inc_write_only(uint32_t variant) { return is_serial(variant) ? 1 : 0; }
uint32_t ft_axis_write_only(uint32_t variant) { return is_serial(variant) ? 1 : 0; }
// ... and INC_DIRECT = 1 (RECORD_INC straight into the FIFO's record).
uint32_t ft_inc_direct(uint32_t variant) { return is_serial(variant) ? 1 : 0; }
// ... and the CPLDs' narrow encoder words (ENC_COUNT_W = 16).
uint32_t ft_enc_count_w(uint32_t variant) { return is_serial(variant) ? 16 : 32; }

#if defined(FS_MINIMAL) && !defined(FT_NETLIST)
// A minimal RTL build (the feature `minimal`) has the default top and the motion chip:
// the motion chip without the hand wheel and the serial one are null.
ft_sim *ft_new(uint32_t variant) {
    if (is_serial(variant) || is_no_mpg(variant)) return nullptr;
    if (is_motion(variant)) return new TopSim<Untraced<Vfinestep_top_motion>, false>;
    return new TopSim<Untraced<Vfinestep_top>, false>;
}
ft_sim *ft_new_traced(uint32_t variant) {
    if (is_serial(variant) || is_no_mpg(variant)) return nullptr;
    if (is_motion(variant)) return new TopSim<Untraced<Vfinestep_top_motion>, false>;
    return new TopSim<Vfinestep_top_traced, true>;
}
#elif !defined(FT_NETLIST)
ft_sim *ft_new(uint32_t variant) {
    if (is_serial(variant)) return new TopSim<Untraced<Vfinestep_top_motion_serial>, false>;
    if (is_no_mpg(variant)) return new TopSim<Untraced<Vfinestep_top_motion_nompg>, false>;
    if (is_motion(variant)) return new TopSim<Untraced<Vfinestep_top_motion>, false>;
    return new TopSim<Untraced<Vfinestep_top>, false>;
}
ft_sim *ft_new_traced(uint32_t variant) {
    if (is_serial(variant)) return new TopSim<Untraced<Vfinestep_top_motion_serial>, false>;
    if (is_no_mpg(variant)) return new TopSim<Untraced<Vfinestep_top_motion_nompg>, false>;
    if (is_motion(variant)) return new TopSim<Untraced<Vfinestep_top_motion>, false>;
    return new TopSim<Vfinestep_top_traced, true>;
}
#else
ft_sim *ft_new(uint32_t) { return new TopSim<Untraced<Vfinestep_top>, false>; }
ft_sim *ft_new_traced(uint32_t) { return new TopSim<Untraced<Vfinestep_top>, false>; }
#endif
void ft_free(ft_sim *sim) { delete sim; }
uint64_t ft_cycle(const ft_sim *sim) { return sim->cycle; }
uint64_t ft_outputs(const ft_sim *sim) { return sim->outputs; }

uint64_t ft_run(ft_sim *sim, uint64_t inputs, uint64_t cycles, ft_event *events, size_t capacity,
                size_t *n_events) {
    return sim->run(inputs, cycles, events, capacity, n_events);
}

int ft_trace_open(ft_sim *sim, const char *path, uint32_t levels) {
    return sim->trace_open(path, levels);
}
void ft_trace_close(ft_sim *sim) { sim->trace_close(); }

}  // extern "C"

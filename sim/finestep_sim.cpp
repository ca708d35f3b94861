// C ABI shim around the Verilated finestep_core (see finestep_sim.h).
//
// Eight Verilations of the same RTL are linked (the seventh and eighth,
// Vfinestep_core_pbp and Vfinestep_core_pbp_shared, the core with the point-by-point
// interpolator with a DDA and a shaper per axis and with the step engine, traced only):
// the core without the gantry block
// (HAS_GANTRY = 0, what every test that does not exercise the gantry runs), with it, and
// with the digit-serial step engine (STEP_DIGIT 4, the CPLD's), each without tracing (fast) and with it (Vfinestep_core*_traced); tracing support costs
// about a third of the speed even when no waveform is open. Each is Verilated from
// sim/finestep_core_sim.v: the core behind registers that hold its inputs, loaded by a
// pulse of `load` whenever the inputs are set, so no logic depends combinationally on
// a top-level input and Verilator evaluates the core once per clock.
#include "finestep_sim.h"

#include <cstring>
#include <memory>

#include "Vfinestep_core_gantry.h"
#include "Vfinestep_core_gantry_traced.h"
#ifndef FS_MINIMAL
#include "Vfinestep_core.h"
#include "Vfinestep_core_pbp.h"
#include "Vfinestep_core_pbp_shared.h"
#include "Vfinestep_core_serial.h"
#include "Vfinestep_core_serial_traced.h"
#include "Vfinestep_core_traced.h"
#endif
#ifdef FS_CLK_PREV
#include "Vfinestep_core_gantry___024root.h"
#ifndef FS_MINIMAL
#include "Vfinestep_core___024root.h"
#include "Vfinestep_core_serial___024root.h"
#endif
#endif
#include "verilated_trace.h"

#ifndef FS_N_AXES
#error "FS_N_AXES, FS_P_WIDTH and FS_TIMING_W must match the Verilated parameters"
#endif

namespace {

// Writes `width` bits of `value` at bit `lsb` of a port of any Verilator width.
template <typename T>
void put_bits(T &port, unsigned lsb, unsigned width, uint64_t value) {
    const uint64_t mask = (width >= 64 ? ~0ULL : ((1ULL << width) - 1)) << lsb;
    port = static_cast<T>((static_cast<uint64_t>(port) & ~mask) | ((value << lsb) & mask));
}

template <std::size_t W>
void put_bits(VlWide<W> &port, unsigned lsb, unsigned width, uint64_t value) {
    if (lsb % 32 == 0 && width == 32) {
        port[lsb / 32] = static_cast<uint32_t>(value);
        return;
    }
    for (unsigned bit = 0; bit < width; ++bit) {
        const unsigned index = lsb + bit;
        const uint32_t word_mask = 1u << (index % 32);
        if ((value >> bit) & 1) port[index / 32] |= word_mask;
        else port[index / 32] &= ~word_mask;
    }
}

template <typename T>
uint64_t get_bits(const T &port, unsigned lsb, unsigned width) {
    const uint64_t mask = width >= 64 ? ~0ULL : ((1ULL << width) - 1);
    return (static_cast<uint64_t>(port) >> lsb) & mask;
}

template <std::size_t W>
uint64_t get_bits(const VlWide<W> &port, unsigned lsb, unsigned width) {
    if (lsb % 32 == 0 && width == 32) return port[lsb / 32];
    uint64_t value = 0;
    for (unsigned bit = 0; bit < width; ++bit) {
        const unsigned index = lsb + bit;
        value |= static_cast<uint64_t>((port[index / 32] >> (index % 32)) & 1) << bit;
    }
    return value;
}

// The output ports as Verilator holds them: compared every cycle, packed only on change.
struct RawOutputs {
    uint32_t positions[FS_N_AXES];
    uint32_t gantry_error;
    uint16_t gantry_corrections;
    uint8_t gantry_flags;
    uint8_t pin_a, pin_b, pin_en, rate_error, step_lost, flags;
    uint8_t padding[3];  // explicit, so memcmp sees no indeterminate bytes

    bool operator!=(const RawOutputs &other) const {
        return std::memcmp(this, &other, sizeof *this) != 0;
    }
};

static_assert(sizeof(RawOutputs) == 4 * FS_N_AXES + 16, "RawOutputs must have no implicit padding");

}  // namespace

// The interface the C functions call; one virtual call per chunk, not per cycle.
struct fs_sim {
    uint64_t cycle = 0;
    fs_outputs last{};

    virtual ~fs_sim() = default;
    virtual void reset() = 0;
    virtual void step(const fs_inputs &in) = 0;
    virtual fs_chunk_end run_chunk(const fs_inputs &in, uint64_t max_cycles, fs_event *events,
                                   size_t capacity, size_t *n_events) = 0;
    virtual int trace_open(const char *path, uint32_t levels) = 0;
    virtual void trace_close() = 0;
};

namespace {

template <typename Model, bool TRACED>
struct Sim final : fs_sim {
    std::unique_ptr<VerilatedContext> context;
    std::unique_ptr<Model> top;
    std::unique_ptr<TraceFile> trace;
    RawOutputs raw{};

    Sim() : context(new VerilatedContext) {
        if (TRACED) context->traceEverOn(true);
        top.reset(new Model(context.get()));
        top->clk = 0;
        top->load = 0;
        top->eval();
        reset();
    }

    ~Sim() override {
        trace_close();
        top->final();
    }

    void apply(const fs_inputs &in) {
        top->run = in.run & 1;
        top->clear_errors = in.clear_errors & 1;
        top->halt = in.halt & 1;
        top->rec_valid = in.rec_valid & 1;
        top->rec_flags = in.rec_flags;
        put_bits(top->period_clocks, 0, FS_P_WIDTH, in.period_clocks);
        top->gantry_enable = in.gantry.enable & 1;
        top->gantry_sync_mode = in.gantry.sync & 1;
        top->gantry_master = in.gantry.master & 7;
        top->gantry_slave = in.gantry.slave & 7;
        top->gantry_tick = in.gantry.tick & 0xFFFFFF;
        top->gantry_deadband = in.gantry.deadband;
        top->gantry_limit = in.gantry.limit;
        top->enc_master = in.gantry.enc_master;
        top->enc_slave = in.gantry.enc_slave;
        top->clear_counters = in.gantry.clear_counters & 1;
        for (unsigned i = 0; i < FS_N_AXES; ++i) {
            const fs_axis_config &axis = in.axes[i];
            put_bits(top->rec_inc, 32 * i, 32, static_cast<uint32_t>(in.rec_inc[i]));
            put_bits(top->step_len, FS_TIMING_W * i, FS_TIMING_W, axis.timing.step_len);
            put_bits(top->step_space, FS_TIMING_W * i, FS_TIMING_W, axis.timing.step_space);
            put_bits(top->dir_setup, FS_TIMING_W * i, FS_TIMING_W, axis.timing.dir_setup);
            put_bits(top->dir_hold, FS_TIMING_W * i, FS_TIMING_W, axis.timing.dir_hold);
            put_bits(top->out_mode, FS_OUT_MODE_WIDTH * i, FS_OUT_MODE_WIDTH, axis.mode);
            put_bits(top->invert, FS_INVERT_WIDTH * i, FS_INVERT_WIDTH, axis.invert);
            put_bits(top->axis_enable, i, 1, axis.enable);
        }
        load();
    }

    // The input registers take the inputs set since the last load (clock low). `load`
    // falls in an evaluation of its own (or, untraced, as load_fall sets it), so that the
    // next load is a rising edge again (Verilator compares with the value at the previous
    // evaluation).
    void load() {
        top->load = 1;
        top->eval();
        finestep::load_fall<TRACED>(*top);
    }

    // Cycle c is drawn from time 2c (its rising edge) to 2c+2; its inputs, settled with
    // the clock low, at 2c+1, so a waveform shows each input before the edge sampling it.
    void edge() {
        if (TRACED && trace) trace->dump(2 * cycle + 1);
        top->clk = 1;
        top->eval();
        ++cycle;
        if (TRACED && trace) trace->dump(2 * cycle);
        finestep::clock_fall<TRACED>(*top);
    }

    RawOutputs read_raw() const {
        RawOutputs now{};
        now.padding[0] = now.padding[1] = now.padding[2] = 0;
        now.gantry_error = top->gantry_error;
        now.gantry_corrections = top->gantry_corrections;
        now.gantry_flags = (top->gantry_engaged & 1) | ((top->gantry_alarm & 1) << 1) |
                           ((top->gantry_refused & 1) << 2);
        for (unsigned i = 0; i < FS_N_AXES; ++i)
            now.positions[i] = static_cast<uint32_t>(get_bits(top->position, 32 * i, 32));
        now.pin_a = top->pin_a;
        now.pin_b = top->pin_b;
        now.pin_en = top->pin_en;
        now.rate_error = top->rate_error;
        now.step_lost = top->step_lost;
        now.flags = (top->rec_ready & 1) | ((top->record_error & 1) << 1) | ((top->block_end & 1) << 2) |
                    ((top->period_boundary & 1) << 3);
        return now;
    }

    static fs_outputs pack(const RawOutputs &raw) {
        fs_outputs out{};
        uint64_t pins = 0;
        for (unsigned i = 0; i < FS_N_AXES; ++i) {
            pins |= static_cast<uint64_t>((raw.pin_a >> i) & 1) << (3 * i);
            pins |= static_cast<uint64_t>((raw.pin_b >> i) & 1) << (3 * i + 1);
            pins |= static_cast<uint64_t>((raw.pin_en >> i) & 1) << (3 * i + 2);
            pins |= static_cast<uint64_t>((raw.rate_error >> i) & 1) << (FS_BIT_RATE_ERROR0 + i);
            pins |= static_cast<uint64_t>((raw.step_lost >> i) & 1) << (FS_BIT_STEP_LOST0 + i);
            out.positions[i] = raw.positions[i];
        }
        pins |= static_cast<uint64_t>(raw.flags & 1) << FS_BIT_REC_READY;
        pins |= static_cast<uint64_t>((raw.flags >> 1) & 1) << FS_BIT_RECORD_ERROR;
        pins |= static_cast<uint64_t>((raw.flags >> 2) & 1) << FS_BIT_BLOCK_END;
        pins |= static_cast<uint64_t>((raw.flags >> 3) & 1) << FS_BIT_PERIOD_BOUNDARY;
        out.pins = pins;
        out.gantry_error = raw.gantry_error;
        out.gantry_corrections = raw.gantry_corrections;
        out.gantry_flags = raw.gantry_flags;
        return out;
    }

    void reset() override {
        trace_close();  // the cycle count restarts: a waveform cannot go on across it
        fs_inputs idle;
        std::memset(&idle, 0, sizeof idle);
        top->rst = 1;
        apply(idle);
        edge();
        top->rst = 0;
        load();
        cycle = 0;
        raw = read_raw();
        last = pack(raw);
    }

    void step(const fs_inputs &in) override {
        apply(in);
        edge();
        raw = read_raw();
        last = pack(raw);
    }

    fs_chunk_end run_chunk(const fs_inputs &in, uint64_t max_cycles, fs_event *events,
                           size_t capacity, size_t *n_events) override {
        apply(in);
        fs_chunk_end end{0, 0};
        size_t stored = 0;
        const bool valid = in.rec_valid & 1;
        while (end.cycles < max_cycles && stored < capacity) {
            const bool consumed = valid && (raw.flags & 1);
            edge();
            ++end.cycles;
            const RawOutputs now = read_raw();
            if (now != raw) {
                raw = now;
                last = pack(now);
                events[stored].cycle = cycle;
                events[stored].outputs = last;
                ++stored;
            }
            if (consumed) {
                end.consumed = 1;
                break;
            }
        }
        *n_events = stored;
        return end;
    }

    int trace_open(const char *path, uint32_t levels) override {
        return finestep::open_trace<TRACED>(trace, *top, path, levels);
    }

    void trace_close() override { finestep::close_trace(trace); }
};

// Only the traced models have trace(); give the untraced ones a stub so one template fits.
template <typename Base>
struct Untraced : Base {
    using Base::Base;
    void trace(TraceFile *, int) {}
};

}  // namespace

extern "C" {

uint32_t fs_n_axes(void) { return FS_N_AXES; }
uint32_t fs_p_width(void) { return FS_P_WIDTH; }
uint32_t fs_timing_width(void) { return FS_TIMING_W; }
int fs_trace_is_fst(void) { return VM_TRACE_FST ? 1 : 0; }

uint32_t fs_serial_digit(void) { return FS_SERIAL_DIGIT; }

// A minimal build (FS_MINIMAL: rust/finestep-rtl-sys's feature `minimal`, and every
// netlist build) has only the core with the gantry block (the smoke test's): the other
// variants are null.
fs_sim *fs_new(int variant) {
#ifdef FS_MINIMAL
    if (variant != 1) return nullptr;
    return new Sim<Untraced<Vfinestep_core_gantry>, false>;
#else
    // The core with the point-by-point interpolator is Verilated traced only.
    if (variant == 3) return new Sim<Vfinestep_core_pbp, true>;
    if (variant == 4) return new Sim<Vfinestep_core_pbp_shared, true>;
    if (variant == 1) return new Sim<Untraced<Vfinestep_core_gantry>, false>;
    if (variant == 2) return new Sim<Untraced<Vfinestep_core_serial>, false>;
    return new Sim<Untraced<Vfinestep_core>, false>;
#endif
}
fs_sim *fs_new_traced(int variant) {
#ifdef FS_MINIMAL
    if (variant != 1) return nullptr;
    return new Sim<Vfinestep_core_gantry_traced, true>;
#else
    if (variant == 3) return new Sim<Vfinestep_core_pbp, true>;
    if (variant == 4) return new Sim<Vfinestep_core_pbp_shared, true>;
    if (variant == 1) return new Sim<Vfinestep_core_gantry_traced, true>;
    if (variant == 2) return new Sim<Vfinestep_core_serial_traced, true>;
    return new Sim<Vfinestep_core_traced, true>;
#endif
}
void fs_free(fs_sim *sim) { delete sim; }
void fs_reset(fs_sim *sim) { sim->reset(); }
uint64_t fs_cycle(const fs_sim *sim) { return sim->cycle; }
void fs_read_outputs(const fs_sim *sim, fs_outputs *out) { *out = sim->last; }
void fs_step(fs_sim *sim, const fs_inputs *in) { sim->step(*in); }

fs_chunk_end fs_run_chunk(fs_sim *sim, const fs_inputs *in, uint64_t max_cycles,
                          fs_event *events, size_t capacity, size_t *n_events) {
    return sim->run_chunk(*in, max_cycles, events, capacity, n_events);
}

int fs_trace_open(fs_sim *sim, const char *path, uint32_t levels) {
    return sim->trace_open(path, levels);
}
void fs_trace_close(fs_sim *sim) { sim->trace_close(); }

}  // extern "C"

// C ABI shim around the Verilated finestep_core (see finestep_sim.h).
#include "finestep_sim.h"

#include <cstring>
#include <memory>

#include "Vfinestep_core.h"
#include "verilated.h"
#if VM_TRACE_FST
#include "verilated_fst_c.h"
typedef VerilatedFstC TraceFile;
#elif VM_TRACE
#include "verilated_vcd_c.h"
typedef VerilatedVcdC TraceFile;
#endif

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

}  // namespace

struct fs_sim {
    std::unique_ptr<VerilatedContext> context;
    std::unique_ptr<Vfinestep_core> top;
#if VM_TRACE
    std::unique_ptr<TraceFile> trace;
#endif
    uint64_t cycle = 0;
    fs_outputs last{};

    fs_sim() : context(new VerilatedContext), top(new Vfinestep_core(context.get())) {
#if VM_TRACE
        context->traceEverOn(true);
#endif
        top->clk = 0;
        top->eval();
    }

    void apply(const fs_inputs &in) {
        top->run = in.run & 1;
        top->clear_errors = in.clear_errors & 1;
        top->rec_valid = in.rec_valid & 1;
        top->rec_flags = in.rec_flags;
        put_bits(top->period_clocks, 0, FS_P_WIDTH, in.period_clocks);
        for (unsigned i = 0; i < FS_N_AXES; ++i) {
            const fs_axis_config &axis = in.axes[i];
            put_bits(top->rec_inc, 32 * i, 32, static_cast<uint32_t>(in.rec_inc[i]));
            put_bits(top->step_len, FS_TIMING_W * i, FS_TIMING_W, axis.step_len);
            put_bits(top->step_space, FS_TIMING_W * i, FS_TIMING_W, axis.step_space);
            put_bits(top->dir_setup, FS_TIMING_W * i, FS_TIMING_W, axis.dir_setup);
            put_bits(top->dir_hold, FS_TIMING_W * i, FS_TIMING_W, axis.dir_hold);
            put_bits(top->out_mode, 2 * i, 2, axis.mode);
            put_bits(top->invert, 3 * i, 3, axis.invert);
            put_bits(top->axis_enable, i, 1, axis.enable);
        }
    }

    void edge() {
        top->clk = 1;
        top->eval();
        ++cycle;
#if VM_TRACE
        if (trace) trace->dump(2 * cycle);
#endif
        top->clk = 0;
        top->eval();
#if VM_TRACE
        if (trace) trace->dump(2 * cycle + 1);
#endif
    }

    void read(fs_outputs &out) const {
        uint64_t pins = 0;
        for (unsigned i = 0; i < FS_N_AXES; ++i) {
            pins |= get_bits(top->pin_a, i, 1) << (3 * i);
            pins |= get_bits(top->pin_b, i, 1) << (3 * i + 1);
            pins |= get_bits(top->pin_en, i, 1) << (3 * i + 2);
            pins |= get_bits(top->rate_error, i, 1) << (FS_BIT_RATE_ERROR0 + i);
            pins |= get_bits(top->step_lost, i, 1) << (FS_BIT_STEP_LOST0 + i);
            out.positions[i] = static_cast<uint32_t>(get_bits(top->position, 32 * i, 32));
        }
        for (unsigned i = FS_N_AXES; i < FS_MAX_AXES; ++i) out.positions[i] = 0;
        pins |= static_cast<uint64_t>(top->rec_ready & 1) << FS_BIT_REC_READY;
        pins |= static_cast<uint64_t>(top->record_error & 1) << FS_BIT_RECORD_ERROR;
        pins |= static_cast<uint64_t>(top->block_end & 1) << FS_BIT_BLOCK_END;
        out.pins = pins;
    }
};

extern "C" {

uint32_t fs_n_axes(void) { return FS_N_AXES; }
uint32_t fs_p_width(void) { return FS_P_WIDTH; }
uint32_t fs_timing_width(void) { return FS_TIMING_W; }
int fs_trace_is_fst(void) { return VM_TRACE_FST ? 1 : 0; }

fs_sim *fs_new(void) {
    fs_sim *sim = new fs_sim;
    fs_reset(sim);
    return sim;
}

void fs_free(fs_sim *sim) {
    if (!sim) return;
    fs_trace_close(sim);
    sim->top->final();
    delete sim;
}

void fs_reset(fs_sim *sim) {
    fs_inputs idle;
    std::memset(&idle, 0, sizeof idle);
    sim->apply(idle);
    sim->top->rst = 1;
    sim->edge();
    sim->top->rst = 0;
    sim->top->eval();
    sim->cycle = 0;
    sim->read(sim->last);
}

uint64_t fs_cycle(const fs_sim *sim) { return sim->cycle; }

void fs_read_outputs(const fs_sim *sim, fs_outputs *out) { *out = sim->last; }

void fs_step(fs_sim *sim, const fs_inputs *in) {
    sim->apply(*in);
    sim->edge();
    sim->read(sim->last);
}

fs_chunk_end fs_run_chunk(fs_sim *sim, const fs_inputs *in, uint64_t max_cycles,
                          fs_event *events, size_t capacity, size_t *n_events) {
    sim->apply(*in);
    fs_chunk_end end{0, 0};
    size_t stored = 0;
    const bool valid = in->rec_valid & 1;
    while (end.cycles < max_cycles && stored < capacity) {
        const bool consumed = valid && ((sim->last.pins >> FS_BIT_REC_READY) & 1);
        sim->edge();
        ++end.cycles;
        fs_outputs now;
        sim->read(now);
        if (now.pins != sim->last.pins ||
            std::memcmp(now.positions, sim->last.positions, sizeof now.positions) != 0) {
            events[stored].cycle = sim->cycle;
            events[stored].outputs = now;
            ++stored;
            sim->last = now;
        }
        if (consumed) {
            end.consumed = 1;
            break;
        }
    }
    *n_events = stored;
    return end;
}

int fs_trace_open(fs_sim *sim, const char *path) {
#if VM_TRACE
    fs_trace_close(sim);
    sim->trace.reset(new TraceFile);
    sim->top->trace(sim->trace.get(), 99);
    sim->trace->open(path);
    if (!sim->trace->isOpen()) {
        sim->trace.reset();
        return -1;
    }
    sim->trace->dump(2 * sim->cycle + 1);
    return 0;
#else
    (void)sim;
    (void)path;
    return -1;
#endif
}

void fs_trace_close(fs_sim *sim) {
#if VM_TRACE
    if (sim->trace) {
        sim->trace->close();
        sim->trace.reset();
    }
#else
    (void)sim;
#endif
}

}  // extern "C"

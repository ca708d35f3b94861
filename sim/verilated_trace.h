// Waveform support shared by the C shims: the trace file type the build chose (FST or
// VCD) and opening/closing a trace on a Verilated model.
#ifndef FINESTEP_VERILATED_TRACE_H
#define FINESTEP_VERILATED_TRACE_H

#include <cstdint>
#include <memory>

#include "verilated.h"
#if VM_TRACE_FST
#include "verilated_fst_c.h"
typedef VerilatedFstC TraceFile;
#else
#include "verilated_vcd_c.h"
typedef VerilatedVcdC TraceFile;
#endif

namespace finestep {

inline void close_trace(std::unique_ptr<TraceFile> &trace) {
    if (trace) {
        trace->close();
        trace.reset();
    }
}

// Opens `path` on `model`, `levels` below the ports (0: ports only). Returns 0, or -1
// when the model was built without tracing (TRACED false) or the file cannot be opened.
template <bool TRACED, typename Model>
int open_trace(std::unique_ptr<TraceFile> &trace, Model &model, const char *path, uint32_t levels) {
    if (!TRACED) return -1;
    close_trace(trace);
    trace.reset(new TraceFile);
    // Verilator names top-level ports "TOP <port>": one level below TOP is the ports.
    trace->dumpvars(static_cast<int>(levels) + 1, "TOP");
    model.trace(trace.get(), 99);
    trace->open(path);
    if (!trace->isOpen()) {
        trace.reset();
        return -1;
    }
    return 0;
}

// Clock cycle `cycle` of a model whose inputs are set: the trace (if open) dumps the
// settled inputs at time 2c+1, then the rising edge at 2c+2, and clk returns low.
template <typename Model>
void clock_cycle(Model &model, std::unique_ptr<TraceFile> &trace, uint64_t &cycle) {
    if (trace) trace->dump(2 * cycle + 1);
    model.clk = 1;
    model.eval();
    ++cycle;
    if (trace) trace->dump(2 * cycle);
    model.clk = 0;
    model.eval();
}

// The clock's fall on an untraced model whose logic all runs on the rising edge of `clk`
// (and of the core shim's `load`): nothing is evaluated on a fall, so instead of a second
// eval() per clock (Verilator's per-call work, about a fifth of the core's simulation
// time) only the value Verilator compares `clk` with at the next eval() is set low, as an
// eval() with `clk` low would leave it. FS_CLK_PREV names that member of the model's root
// (`__Vtrigrprev__TOP__clk` in Verilator 5.006); rust/finestep-rtl-sys's build defines it
// only when every such model declares it and its generated code shows that an eval()
// lowering `clk` evaluates nothing (every trigger a rising edge of `clk` or `load`, read
// nowhere else; an input-dependent `ico` region computes again what it computed at the
// last eval()), and never for a netlist; otherwise, and on a traced model (its trace
// records the fall), the fall is an eval().
template <bool TRACED, typename Model>
inline void clock_fall(Model &model) {
    model.clk = 0;
#ifdef FS_CLK_PREV
    if constexpr (!TRACED) {
        model.rootp->FS_CLK_PREV = 0;
        return;
    }
#endif
    model.eval();
}

// The fall of the core shim's `load`, as clock_fall's of `clk` (FS_LOAD_PREV: the member
// of every untraced core's root that holds `load` at the last eval(), defined by the
// build under clock_fall's conditions).
template <bool TRACED, typename Model>
inline void load_fall(Model &model) {
    model.load = 0;
#ifdef FS_LOAD_PREV
    if constexpr (!TRACED) {
        model.rootp->FS_LOAD_PREV = 0;
        return;
    }
#endif
    model.eval();
}

// Whether an untraced model's rising-edge eval() settles inputs set since the last
// eval() before it evaluates the edge (its input-dependent region runs first), so that
// the shims need not evaluate new inputs with the clock low: under FS_CLK_PREV's
// conditions (the inputs are read by no trigger but `clk`'s and `load`'s rising edges). A
// traced model evaluates them (its waveform shows them settled before the edge).
template <bool TRACED>
constexpr bool edge_settles_inputs() {
#ifdef FS_CLK_PREV
    return !TRACED;
#else
    return false;
#endif
}

}  // namespace finestep

#endif

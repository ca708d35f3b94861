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

}  // namespace finestep

#endif

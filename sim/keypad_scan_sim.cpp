// C ABI shim around the Verilated keypad_scan (see keypad_scan_sim.h). Every output of the
// block is a register, so its inputs are applied directly before each rising edge.
#include "keypad_scan_sim.h"

#include <memory>

#include "Vkeypad_scan.h"
#include "verilated_trace.h"

#ifndef KP_PRE_W
#error "KP_PRE_W and KP_DEB_W must match the Verilated parameters"
#endif

struct kp_sim {
    std::unique_ptr<VerilatedContext> context;
    std::unique_ptr<Vkeypad_scan> top;
    std::unique_ptr<TraceFile> trace;
    uint64_t cycle = 0;

    kp_sim() : context(new VerilatedContext) {
        context->traceEverOn(true);
        top.reset(new Vkeypad_scan(context.get()));
        top->clk = 0;
        top->eval();
    }

    ~kp_sim() {
        finestep::close_trace(trace);
        top->final();
    }

    void apply(const kp_inputs &in) {
        top->scan_div = in.scan_div & ((1ull << KP_PRE_W) - 1);
        top->deb_scans = in.deb_scans & ((1u << KP_DEB_W) - 1);
        top->row_n = in.row_n & 0xf;
        top->eval();
    }

    // Cycle c: inputs settled at time 2c+1, its rising edge at 2c+2.
    void edge() {
        finestep::clock_cycle(*top, trace, cycle);
    }
};

extern "C" {

uint32_t kp_pre_width(void) { return KP_PRE_W; }
uint32_t kp_deb_width(void) { return KP_DEB_W; }

kp_sim *kp_new(void) {
    kp_sim *sim = new kp_sim;
    kp_reset(sim);
    return sim;
}

void kp_free(kp_sim *sim) { delete sim; }

void kp_reset(kp_sim *sim) {
    finestep::close_trace(sim->trace);
    kp_inputs idle{};
    idle.row_n = 0xf;
    sim->top->rst = 1;
    sim->apply(idle);
    sim->edge();
    sim->top->rst = 0;
    sim->top->eval();
    sim->cycle = 0;
}

void kp_step(kp_sim *sim, const kp_inputs *in) {
    sim->apply(*in);
    sim->edge();
}

void kp_read_outputs(const kp_sim *sim, kp_outputs *out) {
    out->col_drive = sim->top->col_drive;
    out->key_valid = sim->top->key_valid;
    out->key_code = sim->top->key_code;
    out->key_down = sim->top->key_down;
}

uint64_t kp_cycle(const kp_sim *sim) { return sim->cycle; }

int kp_trace_open(kp_sim *sim, const char *path) {
    return finestep::open_trace<true>(sim->trace, *sim->top, path, 99);
}

void kp_trace_close(kp_sim *sim) { finestep::close_trace(sim->trace); }

}  // extern "C"

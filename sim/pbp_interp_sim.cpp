// C ABI shim around the Verilated pbp_interp (see pbp_interp_sim.h). Every output of the
// block is a register, so its inputs are applied directly before each rising edge.
#include "pbp_interp_sim.h"

#include <memory>

#include "Vpbp_interp.h"
#include "verilated_trace.h"

#ifndef PI_COORD_W
#error "PI_COORD_W and PI_DIV_W must match the Verilated parameters"
#endif

struct pi_sim {
    std::unique_ptr<VerilatedContext> context;
    std::unique_ptr<Vpbp_interp> top;
    std::unique_ptr<TraceFile> trace;
    uint64_t cycle = 0;

    pi_sim() : context(new VerilatedContext) {
        context->traceEverOn(true);
        top.reset(new Vpbp_interp(context.get()));
        top->clk = 0;
        top->eval();
    }

    ~pi_sim() {
        finestep::close_trace(trace);
        top->final();
    }

    void apply(const pi_inputs &in) {
        const uint32_t coord_mask = (1u << PI_COORD_W) - 1;
        top->halt = in.halt & 1;
        top->rec_valid = in.rec_valid & 1;
        top->rec_arc = in.rec_arc & 1;
        top->rec_cw = in.rec_cw & 1;
        top->tick_div = in.tick_div & ((1u << PI_DIV_W) - 1);
        top->rec_x = static_cast<uint32_t>(in.rec_x) & coord_mask;
        top->rec_y = static_cast<uint32_t>(in.rec_y) & coord_mask;
        top->rec_steps = in.rec_steps & ((1u << (PI_COORD_W + 3)) - 1);
        top->eval();
    }

    // Cycle c: inputs settled at time 2c+1, its rising edge at 2c+2.
    void edge() {
        finestep::clock_cycle(*top, trace, cycle);
    }
};

extern "C" {

uint32_t pi_coord_width(void) { return PI_COORD_W; }
uint32_t pi_div_width(void) { return PI_DIV_W; }

pi_sim *pi_new(void) {
    pi_sim *sim = new pi_sim;
    pi_reset(sim);
    return sim;
}

void pi_free(pi_sim *sim) { delete sim; }

void pi_reset(pi_sim *sim) {
    finestep::close_trace(sim->trace);
    const pi_inputs idle{};
    sim->top->rst = 1;
    sim->apply(idle);
    sim->edge();
    sim->top->rst = 0;
    sim->top->eval();
    sim->cycle = 0;
}

void pi_step(pi_sim *sim, const pi_inputs *in) {
    sim->apply(*in);
    sim->edge();
}

void pi_read_outputs(const pi_sim *sim, pi_outputs *out) {
    out->rec_ready = sim->top->rec_ready;
    out->busy = sim->top->busy;
    out->done = sim->top->done;
    out->req_valid = sim->top->req_valid;
    out->req_negative = sim->top->req_negative;
    out->move_up = sim->top->move_up;
    out->move_down = sim->top->move_down;
}

uint64_t pi_cycle(const pi_sim *sim) { return sim->cycle; }

int pi_trace_open(pi_sim *sim, const char *path) {
    return finestep::open_trace<true>(sim->trace, *sim->top, path, 99);
}

void pi_trace_close(pi_sim *sim) { finestep::close_trace(sim->trace); }

}  // extern "C"

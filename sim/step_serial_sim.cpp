// C ABI shim around the Verilated step_serial (see step_serial_sim.h): one template over
// the Verilated variants. Every output of the block is a register or a function of one,
// so its inputs are applied directly before each rising edge.
#include "step_serial_sim.h"

#include <memory>
#include <type_traits>

#include "Vstep_serial_a4d4.h"
#include "Vstep_serial_a3d1.h"
#include "Vstep_serial_a2d2.h"
#include "verilated_trace.h"

#ifndef SS_P_WIDTH
#error "SS_P_WIDTH and SS_TIMING_W must match the Verilated parameters"
#endif

namespace {

const ss_params kParams[3] = {
    {4, SS_P_WIDTH, SS_TIMING_W, 4},
    {3, SS_P_WIDTH, SS_TIMING_W, 1},
    {2, SS_P_WIDTH, SS_TIMING_W, 2},
};

struct ss_base {
    virtual ~ss_base() {}
    virtual void set_rst(uint8_t rst) = 0;
    virtual void apply(const ss_inputs &in) = 0;
    virtual void edge() = 0;
    virtual void read(ss_outputs *out) const = 0;
    virtual int trace_open(const char *path) = 0;
    virtual void trace_close() = 0;
    uint64_t cycle = 0;
};

template <typename Model>
struct ss_model : ss_base {
    std::unique_ptr<VerilatedContext> context;
    std::unique_ptr<Model> top;
    std::unique_ptr<TraceFile> trace;
    uint32_t n;

    explicit ss_model(uint32_t n_axes) : context(new VerilatedContext), n(n_axes) {
        context->traceEverOn(true);
        top.reset(new Model(context.get()));
        top->clk = 0;
        top->eval();
    }

    ~ss_model() override {
        finestep::close_trace(trace);
        top->final();
    }

    void set_rst(uint8_t rst) override {
        top->rst = rst;
        top->eval();
    }

    // A per-axis field of `width` bits, packed axis 0 lowest.
    template <typename T>
    static uint64_t pack(const T *v, uint32_t n, uint32_t width) {
        uint64_t word = 0;
        for (uint32_t a = 0; a < n; ++a) word |= (uint64_t(v[a]) & ((1ull << width) - 1)) << (width * a);
        return word;
    }

    void apply(const ss_inputs &in) override {
        const uint32_t tw = SS_TIMING_W;
        top->run = in.run & 1;
        top->p_active = in.p_active & ((1u << SS_P_WIDTH) - 1);
        if constexpr (std::is_integral_v<std::decay_t<decltype(top->inc)>>) {
            // Two axes: one 64-bit port.
            top->inc = uint64_t(static_cast<uint32_t>(in.inc[0])) | (uint64_t(static_cast<uint32_t>(in.inc[1])) << 32);
        } else {
            for (uint32_t a = 0; a < n; ++a) top->inc[a] = static_cast<uint32_t>(in.inc[a]);
        }
        top->axis_enable = in.axis_enable & ((1u << n) - 1);
        top->step_len = pack(in.step_len, n, tw);
        top->step_space = pack(in.step_space, n, tw);
        top->dir_setup = pack(in.dir_setup, n, tw);
        top->dir_hold = pack(in.dir_hold, n, tw);
        top->out_mode = pack(in.out_mode, n, 2);
        top->invert = pack(in.invert, n, 3);
        top->clear_errors = in.clear_errors & 1;
        top->halt = in.halt & 1;
        top->eval();
    }

    // Cycle c: inputs settled at time 2c+1, its rising edge at 2c+2.
    void edge() override {
        finestep::clock_cycle(*top, trace, cycle);
    }

    void read(ss_outputs *out) const override {
        out->start_ok = top->start_ok;
        out->pin_a = top->pin_a;
        out->pin_b = top->pin_b;
        out->pin_en = top->pin_en;
        out->rate_error = top->rate_error;
        out->step_lost = top->step_lost;
        out->pos_digit = top->pos_digit;
        out->pos_index = top->pos_index;
        out->pos_axis = top->pos_axis;
    }

    int trace_open(const char *path) override { return finestep::open_trace<true>(trace, *top, path, 99); }
    void trace_close() override { finestep::close_trace(trace); }
};

}  // namespace

struct ss_sim {
    std::unique_ptr<ss_base> model;
};

extern "C" {

uint32_t ss_variants(void) { return 3; }

void ss_variant_params(uint32_t variant, ss_params *out) { *out = kParams[variant < 3 ? variant : 0]; }

ss_sim *ss_new(uint32_t variant) {
    if (variant > 2) return nullptr;
    ss_sim *sim = new ss_sim;
    if (variant == 0)
        sim->model.reset(new ss_model<Vstep_serial_a4d4>(4));
    else if (variant == 1)
        sim->model.reset(new ss_model<Vstep_serial_a3d1>(3));
    else
        sim->model.reset(new ss_model<Vstep_serial_a2d2>(2));
    ss_reset(sim);
    return sim;
}

void ss_free(ss_sim *sim) { delete sim; }

void ss_reset(ss_sim *sim) {
    sim->model->trace_close();
    const ss_inputs idle{};
    sim->model->set_rst(1);
    sim->model->apply(idle);
    sim->model->edge();
    sim->model->set_rst(0);
    sim->model->cycle = 0;
}

void ss_step(ss_sim *sim, const ss_inputs *in) {
    sim->model->apply(*in);
    sim->model->edge();
}

void ss_read_outputs(const ss_sim *sim, ss_outputs *out) { sim->model->read(out); }

uint64_t ss_cycle(const ss_sim *sim) { return sim->model->cycle; }

int ss_trace_open(ss_sim *sim, const char *path) { return sim->model->trace_open(path); }

void ss_trace_close(ss_sim *sim) { sim->model->trace_close(); }

}  // extern "C"

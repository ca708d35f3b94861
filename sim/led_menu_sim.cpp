// C ABI shim around the Verilated led_menu (see led_menu_sim.h): one template over the
// two Verilated variants. Every output of the block is a register, so its inputs are
// applied directly before each rising edge.
#include "led_menu_sim.h"

#include <memory>

#include "Vled_menu.h"
#include "Vled_menu_low.h"
#include "verilated_trace.h"

#ifndef LM_PRE_W
#error "LM_PRE_W, LM_LOW_N_DIG must match the Verilated parameters"
#endif

namespace {

const lm_params kParams[2] = {
    {8, LM_PRE_W, 0, 0},
    {LM_LOW_N_DIG, LM_PRE_W, 1, 1},
};

struct lm_base {
    virtual ~lm_base() {}
    virtual void set_rst(uint8_t rst) = 0;
    virtual void apply(const lm_inputs &in) = 0;
    virtual void edge() = 0;
    virtual void read(lm_outputs *out) const = 0;
    virtual int trace_open(const char *path) = 0;
    virtual void trace_close() = 0;
    uint64_t cycle = 0;
};

template <typename Model>
struct lm_model : lm_base {
    std::unique_ptr<VerilatedContext> context;
    std::unique_ptr<Model> top;
    std::unique_ptr<TraceFile> trace;

    lm_model() : context(new VerilatedContext) {
        context->traceEverOn(true);
        top.reset(new Model(context.get()));
        top->clk = 0;
        top->eval();
    }

    ~lm_model() override {
        finestep::close_trace(trace);
        top->final();
    }

    void set_rst(uint8_t rst) override {
        top->rst = rst;
        top->eval();
    }

    void apply(const lm_inputs &in) override {
        top->refresh_div = in.refresh_div & ((1ull << LM_PRE_W) - 1);
        top->key_valid = in.key_valid & 1;
        top->key_code = in.key_code & 0xf;
        top->sync_err = static_cast<uint16_t>(in.sync_err);
        top->alarm_in = in.alarm_in & 0xf;
        top->host_wr = in.host_wr & 1;
        top->host_addr = in.host_addr & 3;
        top->host_wdata = in.host_wdata;
        top->eval();
    }

    // Cycle c: inputs settled at time 2c+1, its rising edge at 2c+2.
    void edge() override {
        finestep::clock_cycle(*top, trace, cycle);
    }

    void read(lm_outputs *out) const override {
        out->host_rdata = top->host_rdata;
        out->seg = top->seg;
        out->dig = top->dig;
        out->sync_mode = top->sync_mode;
        out->alarm_pending = top->alarm_pending;
        out->page = top->page;
    }

    int trace_open(const char *path) override { return finestep::open_trace<true>(trace, *top, path, 99); }
    void trace_close() override { finestep::close_trace(trace); }
};

}  // namespace

struct lm_sim {
    std::unique_ptr<lm_base> model;
};

extern "C" {

uint32_t lm_variants(void) { return 2; }

void lm_variant_params(uint32_t variant, lm_params *out) { *out = kParams[variant < 2 ? variant : 0]; }

lm_sim *lm_new(uint32_t variant) {
    if (variant > 1) return nullptr;
    lm_sim *sim = new lm_sim;
    if (variant == 0)
        sim->model.reset(new lm_model<Vled_menu>);
    else
        sim->model.reset(new lm_model<Vled_menu_low>);
    lm_reset(sim);
    return sim;
}

void lm_free(lm_sim *sim) { delete sim; }

void lm_reset(lm_sim *sim) {
    sim->model->trace_close();
    const lm_inputs idle{};
    sim->model->set_rst(1);
    sim->model->apply(idle);
    sim->model->edge();
    sim->model->set_rst(0);
    sim->model->cycle = 0;
}

void lm_step(lm_sim *sim, const lm_inputs *in) {
    sim->model->apply(*in);
    sim->model->edge();
}

void lm_read_outputs(const lm_sim *sim, lm_outputs *out) { sim->model->read(out); }

uint64_t lm_cycle(const lm_sim *sim) { return sim->model->cycle; }

int lm_trace_open(lm_sim *sim, const char *path) { return sim->model->trace_open(path); }

void lm_trace_close(lm_sim *sim) { sim->model->trace_close(); }

}  // extern "C"

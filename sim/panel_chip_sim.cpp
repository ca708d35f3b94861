// C ABI shim around the Verilated finestep_top built as the gantry card's chip (see
// panel_chip_sim.h): Vfinestep_top_panel, traced, one clock at a time. The packed words
// are finestep_top_sim.h's.
#include "panel_chip_sim.h"

#include <memory>

#include "Vfinestep_top_panel.h"
#include "finestep_top_pins.h"
#include "verilated_trace.h"

struct pc_sim {
    std::unique_ptr<VerilatedContext> context;
    std::unique_ptr<Vfinestep_top_panel> top;
    std::unique_ptr<TraceFile> trace;
    uint64_t cycle = 0;

    pc_sim() : context(new VerilatedContext) {
        context->traceEverOn(true);
        top.reset(new Vfinestep_top_panel(context.get()));
        top->clk = 0;
        top->eval();
    }

    ~pc_sim() {
        finestep::close_trace(trace);
        top->final();
    }

    void apply(uint64_t in) {
        finestep::apply_top_inputs(*top, in);
        top->panel_row_n = static_cast<uint8_t>(in >> PC_IN_PANEL_ROW_N0) & 0xF;
        top->eval();
    }

    uint64_t outputs() const { return finestep::read_top_outputs(*top); }

    uint32_t panel() const {
        return static_cast<uint32_t>(top->panel_col & 0xF) << PC_PANEL_COL0 |
               static_cast<uint32_t>(top->panel_seg & 0xFF) << PC_PANEL_SEG0 |
               static_cast<uint32_t>(top->panel_dig & 0xFF) << PC_PANEL_DIG0;
    }
};

extern "C" {

pc_sim *pc_new(void) { return new pc_sim; }
void pc_free(pc_sim *sim) { delete sim; }

void pc_step(pc_sim *sim, uint64_t inputs) {
    sim->apply(inputs);
    finestep::clock_cycle(*sim->top, sim->trace, sim->cycle);
}

uint64_t pc_outputs(const pc_sim *sim) { return sim->outputs(); }
uint32_t pc_panel(const pc_sim *sim) { return sim->panel(); }
uint64_t pc_cycle(const pc_sim *sim) { return sim->cycle; }

int pc_trace_open(pc_sim *sim, const char *path) { return finestep::open_trace<true>(sim->trace, *sim->top, path, 99); }
void pc_trace_close(pc_sim *sim) { finestep::close_trace(sim->trace); }

}  // extern "C"

// C ABI shim around the Verilated finestep_top built as the gantry card's chip (see
// panel_chip_sim.h): Vfinestep_top_panel, traced, one clock at a time. The packed words
// are finestep_top_sim.h's.
#include "panel_chip_sim.h"

#include <memory>

#include "Vfinestep_top_panel.h"
#include "finestep_top_sim.h"
#include "verilated_trace.h"

#ifndef FT_N_ENC
#error "FT_N_ENC must match the Verilated parameters"
#endif

namespace {

inline uint64_t bit(uint64_t word, unsigned index) { return (word >> index) & 1; }

constexpr uint8_t enc_mask = static_cast<uint8_t>((1u << FT_N_ENC) - 1);

}  // namespace

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
        top->rst = bit(in, FT_IN_RST);
        top->spi_cs_n = bit(in, FT_IN_SPI_CS_N);
        top->spi_sck = bit(in, FT_IN_SPI_SCK);
        top->spi_mosi = bit(in, FT_IN_SPI_MOSI);
        top->bus_cs_n = bit(in, FT_IN_BUS_CS_N);
        top->bus_adv_n = bit(in, FT_IN_BUS_ADV_N);
        top->bus_rd_n = bit(in, FT_IN_BUS_RD_N);
        top->bus_wr_n = bit(in, FT_IN_BUS_WR_N);
        top->estop_pin = bit(in, FT_IN_ESTOP);
        top->bus_ad_in = static_cast<uint16_t>(in >> FT_IN_BUS_AD0);
        top->enc_a = static_cast<uint8_t>(in >> FT_IN_ENC_A0) & enc_mask;
        top->enc_b = static_cast<uint8_t>(in >> FT_IN_ENC_B0) & enc_mask;
        top->enc_z = static_cast<uint8_t>(in >> FT_IN_ENC_Z0) & enc_mask;
        top->probe_pin = bit(in, FT_IN_PROBE);
        top->mpg_a = bit(in, FT_IN_MPG_A);
        top->mpg_b = bit(in, FT_IN_MPG_B);
        top->interlock_pin = bit(in, FT_IN_INTERLOCK);
        top->panel_row_n = static_cast<uint8_t>(in >> PC_IN_PANEL_ROW_N0) & 0xF;
        top->eval();
    }

    uint64_t outputs() const {
        uint64_t out = 0;
        out |= static_cast<uint64_t>(top->pin_a & 0xFF) << FT_OUT_PIN_A0;
        out |= static_cast<uint64_t>(top->pin_b & 0xFF) << FT_OUT_PIN_B0;
        out |= static_cast<uint64_t>(top->pin_en & 0xFF) << FT_OUT_PIN_EN0;
        out |= static_cast<uint64_t>(top->spi_miso & 1) << FT_OUT_SPI_MISO;
        out |= static_cast<uint64_t>(top->spi_miso_oe & 1) << FT_OUT_SPI_MISO_OE;
        out |= static_cast<uint64_t>(top->irq & 1) << FT_OUT_IRQ;
        out |= static_cast<uint64_t>(top->bus_ad_oe & 1) << FT_OUT_BUS_AD_OE;
        out |= static_cast<uint64_t>(top->bus_ad_out & 0xFFFF) << FT_OUT_BUS_AD0;
        out |= static_cast<uint64_t>(top->coolant_mist & 1) << FT_OUT_COOLANT_MIST;
        out |= static_cast<uint64_t>(top->coolant_flood & 1) << FT_OUT_COOLANT_FLOOD;
        out |= static_cast<uint64_t>(top->light & 1) << FT_OUT_LIGHT;
        out |= static_cast<uint64_t>(top->spindle_pwm & 1) << FT_OUT_SPINDLE_PWM;
        out |= static_cast<uint64_t>(top->spindle_dir & 1) << FT_OUT_SPINDLE_DIR;
        out |= static_cast<uint64_t>(top->spindle_en & 1) << FT_OUT_SPINDLE_EN;
        out |= static_cast<uint64_t>(top->dac_cs_n & 1) << FT_OUT_DAC_CS_N;
        out |= static_cast<uint64_t>(top->dac_sck & 1) << FT_OUT_DAC_SCK;
        out |= static_cast<uint64_t>(top->dac_sdi & 1) << FT_OUT_DAC_SDI;
        out |= static_cast<uint64_t>(top->gpio & 0xFF) << FT_OUT_GPIO0;
        return out;
    }

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

// finestep_top's pins packed into the shims' words (finestep_top_sim.h's FT_IN_* and
// FT_OUT_* bit positions), shared by every shim around a Verilated finestep_top
// (finestep_top_sim.cpp's variants, panel_chip_sim.cpp's gantry card).
#ifndef FINESTEP_TOP_PINS_H
#define FINESTEP_TOP_PINS_H

#include <cstdint>

#include "finestep_top_sim.h"

#ifndef FT_N_ENC
#error "FT_N_ENC must match the Verilated parameters"
#endif

namespace finestep {

inline uint64_t bit(uint64_t word, unsigned index) { return (word >> index) & 1; }

constexpr uint8_t enc_mask = static_cast<uint8_t>((1u << FT_N_ENC) - 1);

// Drives the packed inputs onto the model's input ports (no eval).
template <typename Model>
void apply_top_inputs(Model &top, uint64_t in) {
    top.rst = bit(in, FT_IN_RST);
    top.spi_cs_n = bit(in, FT_IN_SPI_CS_N);
    top.spi_sck = bit(in, FT_IN_SPI_SCK);
    top.spi_mosi = bit(in, FT_IN_SPI_MOSI);
    top.bus_cs_n = bit(in, FT_IN_BUS_CS_N);
    top.bus_adv_n = bit(in, FT_IN_BUS_ADV_N);
    top.bus_rd_n = bit(in, FT_IN_BUS_RD_N);
    top.bus_wr_n = bit(in, FT_IN_BUS_WR_N);
    top.estop_pin = bit(in, FT_IN_ESTOP);
    top.bus_ad_in = static_cast<uint16_t>(in >> FT_IN_BUS_AD0);
    top.enc_a = static_cast<uint8_t>(in >> FT_IN_ENC_A0) & enc_mask;
    top.enc_b = static_cast<uint8_t>(in >> FT_IN_ENC_B0) & enc_mask;
    top.enc_z = static_cast<uint8_t>(in >> FT_IN_ENC_Z0) & enc_mask;
    top.probe_pin = bit(in, FT_IN_PROBE);
    top.mpg_a = bit(in, FT_IN_MPG_A);
    top.mpg_b = bit(in, FT_IN_MPG_B);
    top.interlock_pin = bit(in, FT_IN_INTERLOCK);
}

// The model's output ports packed into one word.
template <typename Model>
uint64_t read_top_outputs(const Model &top) {
    uint64_t out = 0;
    out |= static_cast<uint64_t>(top.pin_a & 0xFF) << FT_OUT_PIN_A0;
    out |= static_cast<uint64_t>(top.pin_b & 0xFF) << FT_OUT_PIN_B0;
    out |= static_cast<uint64_t>(top.pin_en & 0xFF) << FT_OUT_PIN_EN0;
    out |= static_cast<uint64_t>(top.spi_miso & 1) << FT_OUT_SPI_MISO;
    out |= static_cast<uint64_t>(top.spi_miso_oe & 1) << FT_OUT_SPI_MISO_OE;
    out |= static_cast<uint64_t>(top.irq & 1) << FT_OUT_IRQ;
    out |= static_cast<uint64_t>(top.bus_ad_oe & 1) << FT_OUT_BUS_AD_OE;
    out |= static_cast<uint64_t>(top.bus_ad_out & 0xFFFF) << FT_OUT_BUS_AD0;
    out |= static_cast<uint64_t>(top.coolant_mist & 1) << FT_OUT_COOLANT_MIST;
    out |= static_cast<uint64_t>(top.coolant_flood & 1) << FT_OUT_COOLANT_FLOOD;
    out |= static_cast<uint64_t>(top.light & 1) << FT_OUT_LIGHT;
    out |= static_cast<uint64_t>(top.spindle_pwm & 1) << FT_OUT_SPINDLE_PWM;
    out |= static_cast<uint64_t>(top.spindle_dir & 1) << FT_OUT_SPINDLE_DIR;
    out |= static_cast<uint64_t>(top.spindle_en & 1) << FT_OUT_SPINDLE_EN;
    out |= static_cast<uint64_t>(top.dac_cs_n & 1) << FT_OUT_DAC_CS_N;
    out |= static_cast<uint64_t>(top.dac_sck & 1) << FT_OUT_DAC_SCK;
    out |= static_cast<uint64_t>(top.dac_sdi & 1) << FT_OUT_DAC_SDI;
    out |= static_cast<uint64_t>(top.gpio & 0xFF) << FT_OUT_GPIO0;
    return out;
}

}  // namespace finestep

#endif

//! `finestep_top`: the host-interface top. Two host links (SPI and 8080/FSMC) on one
//! register bus, the register file, the position FIFO, motion control, the safety
//! monitor, [`Core`], and the feedback blocks (the [`EncoderBank`] with the probe, the
//! [`HandWheel`] and the [`JogGenerator`]), composed cycle by cycle.
//!
//! Specification: docs/spec/finestep_top.md
//!
//! The core runs while `(CONTROL.RUN || jog engaged) && !halt`; motion control sees
//! `CONTROL.RUN && !halt` only. While the jog is engaged the core takes the jog's
//! records and the FIFO is not popped.
//!
//! [`Top::step`] is one clock edge with the pins of [`TopInputs`]; [`Top::outputs`] are
//! the pins of the current cycle, a function of the state only. Every block computes its
//! next state from the state of the current cycle, so the order the blocks are stepped
//! in does not matter; the composition takes all cross-block signals first.
//!
//! ```
//! use finestep_model::top::{Top, TopInputs, TopParams};
//! use finestep_interface::regs;
//!
//! let mut top = Top::new(TopParams::default());
//! let idle = TopInputs::default();
//! top.step(&TopInputs { rst: true, ..idle });
//! top.step(&TopInputs { rst: true, ..idle });
//! assert_eq!(top.register(regs::id::ADDR), regs::id::MAGIC_VALUE);
//! // Out of reset the machine is halted by the E-stop fault.
//! assert_eq!(regs::status::HALT.get(top.register(regs::status::ADDR)), 1);
//! ```

use finestep_interface::regs;

use crate::core::Core;
use crate::encoder_bank::{EncoderBank, EncoderBankInputs, EncoderBankStatus};
use crate::gantry_link::{saturate, GantryLink, GantryLinkInputs};
use crate::hand_wheel::{HandWheel, HandWheelInputs};
use crate::jog_generator::JogGenerator;
use crate::logic_outputs::Interlock;
use crate::motion_control::{MotionControl, MotionInputs};
use crate::panel::{Panel, PanelInputs, PanelPins};
use crate::parallel_bus_slave::{ParallelBusSlave, ParallelPins};
use crate::position_fifo::PositionFifo;
use crate::register_file::{
    arbitrate, position_latch, BusRequest, FeedbackStatus, Grant, HardwareStatus, IoStatus, RegisterFile,
    RegisterFileInputs, ADDRESSES,
};
use crate::safety_monitor::{SafetyInputs, SafetyMonitor};
use crate::spi_frame::{SpiFrame, SpiFrameInputs};
use crate::spi_slave_phy::{SpiPins, SpiSlavePhy};
use crate::spindle::{Spindle, SpindlePins};
use crate::{CoreInputs, CoreOutputs, ParamError, MAX_AXES};
pub use finestep_interface::TopParams;

/// `FILTER_W` of the safety monitor's E-stop filter (the width of `ESTOP_FILTER`).
pub const ESTOP_FILTER_WIDTH: u32 = regs::estop_filter::SAMPLES.width;

/// Bit positions of the packed pins (the layout of the Verilator shim).
pub mod top_pins {
    /// Bits of [`TopInputs::pack`](super::TopInputs::pack).
    pub mod input {
        /// `rst`.
        pub const RST: u32 = 0;
        /// `spi_cs_n`.
        pub const SPI_CS_N: u32 = 1;
        /// `spi_sck`.
        pub const SPI_SCK: u32 = 2;
        /// `spi_mosi`.
        pub const SPI_MOSI: u32 = 3;
        /// `bus_cs_n`.
        pub const BUS_CS_N: u32 = 4;
        /// `bus_adv_n`.
        pub const BUS_ADV_N: u32 = 5;
        /// `bus_rd_n`.
        pub const BUS_RD_N: u32 = 6;
        /// `bus_wr_n`.
        pub const BUS_WR_N: u32 = 7;
        /// `estop_pin`.
        pub const ESTOP_PIN: u32 = 8;
        /// `interlock_pin`.
        pub const INTERLOCK_PIN: u32 = 9;
        /// Lowest bit of `bus_ad_in[15:0]` (bits 16..=31).
        pub const BUS_AD_IN: u32 = 16;
        /// Lowest bit of `enc_a[c]` (bits 32..=39, bit `32 + c` for channel `c`).
        pub const ENC_A: u32 = 32;
        /// Lowest bit of `enc_b[c]` (bits 40..=47).
        pub const ENC_B: u32 = 40;
        /// Lowest bit of `enc_z[c]` (bits 48..=55).
        pub const ENC_Z: u32 = 48;
        /// `probe_pin`.
        pub const PROBE_PIN: u32 = 56;
        /// `mpg_a`.
        pub const MPG_A: u32 = 57;
        /// `mpg_b`.
        pub const MPG_B: u32 = 58;
        /// Lowest bit of `panel_row_n[3:0]` (bits 59..=62).
        pub const PANEL_ROW_N: u32 = 59;
    }

    /// Bits of [`TopOutputs::pack`](super::TopOutputs::pack).
    pub mod output {
        /// `pin_a[axis]`.
        pub const fn pin_a(axis: usize) -> u32 {
            axis as u32
        }
        /// `pin_b[axis]`.
        pub const fn pin_b(axis: usize) -> u32 {
            8 + axis as u32
        }
        /// `pin_en[axis]`.
        pub const fn pin_en(axis: usize) -> u32 {
            16 + axis as u32
        }
        /// `spi_miso`.
        pub const SPI_MISO: u32 = 24;
        /// `spi_miso_oe`.
        pub const SPI_MISO_OE: u32 = 25;
        /// `irq`.
        pub const IRQ: u32 = 26;
        /// `bus_ad_oe`.
        pub const BUS_AD_OE: u32 = 27;
        /// `coolant_mist`.
        pub const COOLANT_MIST: u32 = 28;
        /// `coolant_flood`.
        pub const COOLANT_FLOOD: u32 = 29;
        /// `light`.
        pub const LIGHT: u32 = 30;
        /// Lowest bit of `bus_ad_out[15:0]` (bits 32..=47).
        pub const BUS_AD_OUT: u32 = 32;
        /// `spindle_pwm`.
        pub const SPINDLE_PWM: u32 = 48;
        /// `spindle_dir`.
        pub const SPINDLE_DIR: u32 = 49;
        /// `spindle_en`.
        pub const SPINDLE_EN: u32 = 50;
        /// `dac_cs_n`.
        pub const DAC_CS_N: u32 = 51;
        /// `dac_sck`.
        pub const DAC_SCK: u32 = 52;
        /// `dac_sdi`.
        pub const DAC_SDI: u32 = 53;
        /// Lowest bit of `gpio[i]` (bits 56..=63, bit `56 + i` for output `i`).
        pub const GPIO: u32 = 56;
    }
}

/// Every input pin of the top in one cycle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TopInputs {
    /// Synchronous reset, active high; hold at least 2 cycles.
    pub rst: bool,
    /// SPI chip select, active low.
    pub spi_cs_n: bool,
    /// SPI clock.
    pub spi_sck: bool,
    /// SPI MOSI.
    pub spi_mosi: bool,
    /// 8080 chip select, active low.
    pub bus_cs_n: bool,
    /// 8080 address valid, active low.
    pub bus_adv_n: bool,
    /// 8080 read strobe, active low.
    pub bus_rd_n: bool,
    /// 8080 write strobe, active low.
    pub bus_wr_n: bool,
    /// 8080 multiplexed address/data from the host.
    pub bus_ad_in: u16,
    /// The E-stop input; its active level is `CONTROL.ESTOP_ACTIVE_HIGH`.
    pub estop_pin: bool,
    /// Encoder A pins, bit `c` for channel `c` (bits at and above `N_ENC` ignored).
    pub enc_a: u8,
    /// Encoder B pins.
    pub enc_b: u8,
    /// Encoder index pins.
    pub enc_z: u8,
    /// The probe input; its active level is `PROBE_CONTROL.ACTIVE_HIGH`.
    pub probe_pin: bool,
    /// Hand wheel A.
    pub mpg_a: bool,
    /// Hand wheel B.
    pub mpg_b: bool,
    /// The interlock input; its active level is `INTERLOCK.ACTIVE_HIGH`.
    pub interlock_pin: bool,
    /// The panel's keypad rows (4 bits, pulled up: low where a closed key joins the
    /// row to the driven column).
    pub panel_row_n: u8,
}

impl Default for TopInputs {
    /// Idle pins: not in reset, chip selects and strobes high, SCK and MOSI low,
    /// `bus_ad_in` 0, and `estop_pin` 0, which is *released* for the reset polarity
    /// (`CONTROL.ESTOP_ACTIVE_HIGH = 1`); the feedback pins 0 (index and probe inactive
    /// for their reset polarities).
    fn default() -> Self {
        TopInputs {
            rst: false,
            spi_cs_n: true,
            spi_sck: false,
            spi_mosi: false,
            bus_cs_n: true,
            bus_adv_n: true,
            bus_rd_n: true,
            bus_wr_n: true,
            bus_ad_in: 0,
            estop_pin: false,
            enc_a: 0,
            enc_b: 0,
            enc_z: 0,
            probe_pin: false,
            mpg_a: false,
            mpg_b: false,
            interlock_pin: false,
            panel_row_n: 0xf,
        }
    }
}

impl TopInputs {
    /// The pins in one word, see [`top_pins::input`].
    pub fn pack(&self) -> u64 {
        use top_pins::input as i;
        u64::from(self.rst) << i::RST
            | u64::from(self.spi_cs_n) << i::SPI_CS_N
            | u64::from(self.spi_sck) << i::SPI_SCK
            | u64::from(self.spi_mosi) << i::SPI_MOSI
            | u64::from(self.bus_cs_n) << i::BUS_CS_N
            | u64::from(self.bus_adv_n) << i::BUS_ADV_N
            | u64::from(self.bus_rd_n) << i::BUS_RD_N
            | u64::from(self.bus_wr_n) << i::BUS_WR_N
            | u64::from(self.estop_pin) << i::ESTOP_PIN
            | u64::from(self.bus_ad_in) << i::BUS_AD_IN
            | u64::from(self.enc_a) << i::ENC_A
            | u64::from(self.enc_b) << i::ENC_B
            | u64::from(self.enc_z) << i::ENC_Z
            | u64::from(self.probe_pin) << i::PROBE_PIN
            | u64::from(self.mpg_a) << i::MPG_A
            | u64::from(self.mpg_b) << i::MPG_B
            | u64::from(self.interlock_pin) << i::INTERLOCK_PIN
            | u64::from(self.panel_row_n & 0xf) << i::PANEL_ROW_N
    }

    /// The pins from one word (bits not in [`top_pins::input`] are ignored).
    pub fn unpack(word: u64) -> Self {
        use top_pins::input as i;
        let bit = |index: u32| word >> index & 1 != 0;
        TopInputs {
            rst: bit(i::RST),
            spi_cs_n: bit(i::SPI_CS_N),
            spi_sck: bit(i::SPI_SCK),
            spi_mosi: bit(i::SPI_MOSI),
            bus_cs_n: bit(i::BUS_CS_N),
            bus_adv_n: bit(i::BUS_ADV_N),
            bus_rd_n: bit(i::BUS_RD_N),
            bus_wr_n: bit(i::BUS_WR_N),
            bus_ad_in: (word >> i::BUS_AD_IN) as u16,
            estop_pin: bit(i::ESTOP_PIN),
            enc_a: (word >> i::ENC_A) as u8,
            enc_b: (word >> i::ENC_B) as u8,
            enc_z: (word >> i::ENC_Z) as u8,
            probe_pin: bit(i::PROBE_PIN),
            mpg_a: bit(i::MPG_A),
            mpg_b: bit(i::MPG_B),
            interlock_pin: bit(i::INTERLOCK_PIN),
            panel_row_n: (word >> i::PANEL_ROW_N) as u8 & 0xf,
        }
    }
}

/// Every output pin of the top in one cycle (all flip-flops).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TopOutputs {
    /// `pin_a`, bit `i` for axis `i` (0 at and above `N_AXES`).
    pub pin_a: u8,
    /// `pin_b`, bit `i` for axis `i`.
    pub pin_b: u8,
    /// `pin_en`, bit `i` for axis `i`.
    pub pin_en: u8,
    /// `spi_miso` (meaningful while `spi_miso_oe`).
    pub spi_miso: bool,
    /// `spi_miso_oe`: the SPI link is selected.
    pub spi_miso_oe: bool,
    /// `irq`, active high.
    pub irq: bool,
    /// `bus_ad_oe`: the parallel slave drives `bus_ad`.
    pub bus_ad_oe: bool,
    /// `bus_ad_out`.
    pub bus_ad_out: u16,
    /// The spindle's pins (PWM, direction, enable, the DAC's CS_n, SCK, SDI).
    pub spindle: SpindlePins,
    /// `coolant_mist`.
    pub coolant_mist: bool,
    /// `coolant_flood`.
    pub coolant_flood: bool,
    /// `light`.
    pub light: bool,
    /// `gpio`, bit `i` for output `i` (0 at and above `N_GPIO`).
    pub gpio: u8,
    /// The panel's pins (columns, segments, digits; 0 without `HAS_PANEL`); not in
    /// [`TopOutputs::pack`]'s word.
    pub panel: PanelPins,
}

impl Default for TopOutputs {
    /// Every pin low but the DAC's chip select (inactive high): the pins after reset.
    fn default() -> Self {
        TopOutputs {
            pin_a: 0,
            pin_b: 0,
            pin_en: 0,
            spi_miso: false,
            spi_miso_oe: false,
            irq: false,
            bus_ad_oe: false,
            bus_ad_out: 0,
            spindle: SpindlePins { cs_n: true, ..SpindlePins::default() },
            coolant_mist: false,
            coolant_flood: false,
            light: false,
            gpio: 0,
            panel: PanelPins::default(),
        }
    }
}

impl TopOutputs {
    /// The pins in one word, see [`top_pins::output`].
    pub fn pack(&self) -> u64 {
        use top_pins::output as o;
        u64::from(self.pin_a) << o::pin_a(0)
            | u64::from(self.pin_b) << o::pin_b(0)
            | u64::from(self.pin_en) << o::pin_en(0)
            | u64::from(self.spi_miso) << o::SPI_MISO
            | u64::from(self.spi_miso_oe) << o::SPI_MISO_OE
            | u64::from(self.irq) << o::IRQ
            | u64::from(self.bus_ad_oe) << o::BUS_AD_OE
            | u64::from(self.bus_ad_out) << o::BUS_AD_OUT
            | u64::from(self.spindle.pwm) << o::SPINDLE_PWM
            | u64::from(self.spindle.dir) << o::SPINDLE_DIR
            | u64::from(self.spindle.en) << o::SPINDLE_EN
            | u64::from(self.spindle.cs_n) << o::DAC_CS_N
            | u64::from(self.spindle.sck) << o::DAC_SCK
            | u64::from(self.spindle.sdi) << o::DAC_SDI
            | u64::from(self.coolant_mist) << o::COOLANT_MIST
            | u64::from(self.coolant_flood) << o::COOLANT_FLOOD
            | u64::from(self.light) << o::LIGHT
            | u64::from(self.gpio) << o::GPIO
    }

    /// The pins from one word (bits not in [`top_pins::output`] are ignored).
    pub fn unpack(word: u64) -> Self {
        use top_pins::output as o;
        let bit = |index: u32| word >> index & 1 != 0;
        TopOutputs {
            pin_a: (word >> o::pin_a(0)) as u8,
            pin_b: (word >> o::pin_b(0)) as u8,
            pin_en: (word >> o::pin_en(0)) as u8,
            spi_miso: bit(o::SPI_MISO),
            spi_miso_oe: bit(o::SPI_MISO_OE),
            irq: bit(o::IRQ),
            bus_ad_oe: bit(o::BUS_AD_OE),
            bus_ad_out: (word >> o::BUS_AD_OUT) as u16,
            spindle: SpindlePins {
                pwm: bit(o::SPINDLE_PWM),
                dir: bit(o::SPINDLE_DIR),
                en: bit(o::SPINDLE_EN),
                cs_n: bit(o::DAC_CS_N),
                sck: bit(o::DAC_SCK),
                sdi: bit(o::DAC_SDI),
            },
            coolant_mist: bit(o::COOLANT_MIST),
            coolant_flood: bit(o::COOLANT_FLOOD),
            light: bit(o::LIGHT),
            gpio: (word >> o::GPIO) as u8,
            panel: PanelPins::default(),
        }
    }

    /// Pin A of `axis`.
    pub fn pin_a(&self, axis: usize) -> bool {
        axis < MAX_AXES && self.pin_a >> axis & 1 != 0
    }

    /// Pin B of `axis`.
    pub fn pin_b(&self, axis: usize) -> bool {
        axis < MAX_AXES && self.pin_b >> axis & 1 != 0
    }

    /// The enable pin of `axis`.
    pub fn pin_en(&self, axis: usize) -> bool {
        axis < MAX_AXES && self.pin_en >> axis & 1 != 0
    }
}

/// The cycle-accurate model of `finestep_top`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Top {
    params: TopParams,
    spi_phy: SpiSlavePhy,
    spi_frame: SpiFrame,
    parallel: ParallelBusSlave,
    registers: RegisterFile,
    motion: MotionControl,
    fifo: PositionFifo,
    safety: SafetyMonitor,
    core: Core,
    encoders: EncoderBank,
    hand_wheel: HandWheel,
    jog: JogGenerator,
    spindle: Spindle,
    interlock: Interlock,
    panel: Panel,
    gantry_link: GantryLink,
    cycle: u64,
    /// The SPI frame layer committed a FIFO frame last cycle: the kick's flip-flop
    /// (`kick <- served write || wr_commit`) for the commit half.
    committed_last_cycle: bool,
    /// The register file's bus stage: the request granted last cycle, served in this one
    /// (docs/spec/register_file.md).
    bus_stage: Option<BusRequest>,
}

impl Top {
    /// A top in its reset state (the state after `rst`; power-on state is the same).
    ///
    /// # Panics
    /// If `params` is outside the supported ranges (see [`TopParams::validate`]);
    /// [`Top::try_new`] returns the error instead.
    pub fn new(params: TopParams) -> Top {
        match Top::try_new(params) {
            Ok(top) => top,
            Err(e) => panic!("invalid top parameters: {e}"),
        }
    }

    /// A top in its reset state, or why `params` are not supported.
    pub fn try_new(params: TopParams) -> Result<Top, ParamError> {
        params.validate()?;
        let registers = RegisterFile::new(&params);
        let safety = SafetyMonitor::new(params.wd_w, ESTOP_FILTER_WIDTH, &safety_config(&registers));
        Ok(Top {
            params,
            spi_phy: SpiSlavePhy::default(),
            spi_frame: SpiFrame::new(params.n_axes),
            parallel: ParallelBusSlave::default(),
            registers,
            motion: MotionControl::default(),
            fifo: PositionFifo::new(params.fifo_depth_log2),
            safety,
            core: Core::new(params.core_params()),
            encoders: EncoderBank::with_count_width(params.n_enc, params.enc_count_w),
            hand_wheel: HandWheel::default(),
            jog: JogGenerator::default(),
            spindle: Spindle::default(),
            interlock: Interlock::default(),
            panel: Panel::default(),
            gantry_link: GantryLink::default(),
            cycle: 0,
            committed_last_cycle: false,
            bus_stage: None,
        })
    }

    /// The design parameters.
    pub fn params(&self) -> TopParams {
        self.params
    }

    /// Clock edges since this model was made (resets do not restart it; `TIMESTAMP`
    /// does).
    pub fn cycle(&self) -> u64 {
        self.cycle
    }

    /// The core.
    pub fn core(&self) -> &Core {
        &self.core
    }

    /// The position FIFO.
    pub fn fifo(&self) -> &PositionFifo {
        &self.fifo
    }

    /// The FIFO's committed records (`FIFO_LEVEL.LEVEL`).
    pub fn fifo_level(&self) -> usize {
        self.fifo.level()
    }

    /// The safety monitor.
    pub fn safety(&self) -> &SafetyMonitor {
        &self.safety
    }

    /// Motion control.
    pub fn motion(&self) -> &MotionControl {
        &self.motion
    }

    /// The register file.
    pub fn registers(&self) -> &RegisterFile {
        &self.registers
    }

    /// The SPI byte-level slave.
    pub fn spi_phy(&self) -> &SpiSlavePhy {
        &self.spi_phy
    }

    /// The SPI frame layer.
    pub fn spi_frame(&self) -> &SpiFrame {
        &self.spi_frame
    }

    /// The parallel slave.
    pub fn parallel(&self) -> &ParallelBusSlave {
        &self.parallel
    }

    /// The encoder channels and the probe.
    pub fn encoders(&self) -> &EncoderBank {
        &self.encoders
    }

    /// The hand wheel (stays in reset without `HAS_MPG`).
    pub fn hand_wheel(&self) -> &HandWheel {
        &self.hand_wheel
    }

    /// The jog generator (stays in reset without `HAS_MPG`).
    pub fn jog(&self) -> &JogGenerator {
        &self.jog
    }

    /// The spindle block (its state; meaningful with `HAS_SPINDLE`).
    pub fn spindle(&self) -> &Spindle {
        &self.spindle
    }

    /// The panel (its state; meaningful with `HAS_PANEL`).
    pub fn panel(&self) -> &Panel {
        &self.panel
    }

    /// The gantry link's decoders (meaningful with `HAS_GANTRY`).
    pub fn gantry_link(&self) -> &GantryLink {
        &self.gantry_link
    }

    /// The gantry's mode in this cycle: the panel's with `HAS_PANEL`, else
    /// `GANTRY_CONTROL.SYNC` (true synchronised).
    pub fn gantry_sync_mode(&self) -> bool {
        if self.params.has_panel {
            self.panel.sync_mode()
        } else {
            let control = self.registers.word(regs::gantry_control::ADDR);
            regs::gantry_control::SYNC.get(control) != 0
        }
    }

    /// The interlock (meaningful with `HAS_OUTPUTS`).
    pub fn interlock(&self) -> &Interlock {
        &self.interlock
    }

    /// `halt`: the machine stops on a safety fault (E-stop, watchdog) and on the
    /// gantry's alarm (sticky until `clear_errors` with the error back within the limit
    /// or the gantry disengaged): a gantry whose two sides disagree past the limit must
    /// not go on moving, as a machine whose E-stop is pressed.
    pub fn halt(&self) -> bool {
        self.safety.halt() || (self.params.gantry_built() && self.core.gantry().alarm())
    }

    /// The core's run, `(CONTROL.RUN || jog engaged) && !halt` (`STATUS.RUNNING`).
    pub fn core_run(&self) -> bool {
        (self.registers.run() || self.jog.engaged()) && !self.halt()
    }

    /// Motion control's run, `CONTROL.RUN && !halt`: the FIFO streams only then.
    pub fn motion_run(&self) -> bool {
        self.registers.run() && !self.halt()
    }

    /// The value a register-bus read of `addr` would latch now.
    pub fn register(&self, addr: u8) -> u32 {
        self.registers.read(addr, &self.hardware_status(&self.core.outputs(), true))
    }

    /// The outputs in the current cycle (a function of the state only).
    pub fn outputs(&self) -> TopOutputs {
        let mut out = TopOutputs::default();
        for axis in 0..self.params.n_axes {
            let (a, b, en) = self.core.drive_pins(axis);
            out.pin_a |= u8::from(a) << axis;
            out.pin_b |= u8::from(b) << axis;
            out.pin_en |= u8::from(en) << axis;
        }
        if self.params.has_spi {
            out.spi_miso = self.spi_phy.miso();
            out.spi_miso_oe = self.spi_phy.miso_oe();
        }
        out.irq = self.registers.irq();
        if self.params.has_parallel {
            out.bus_ad_oe = self.parallel.ad_oe();
            out.bus_ad_out = self.parallel.ad_out();
        }
        if self.params.has_spindle {
            out.spindle = self.spindle.pins(&self.registers.spindle_config());
        }
        if self.params.has_outputs {
            use regs::outputs as o;
            let word = self.registers.outputs();
            out.coolant_mist = o::MIST.get(word) != 0;
            out.coolant_flood = o::FLOOD.get(word) != 0;
            out.light = o::LIGHT.get(word) != 0;
            out.gpio = o::GPIO.get(word) as u8;
        }
        if self.params.has_panel {
            out.panel = self.panel.pins();
        }
        out
    }

    /// The hardware values register reads show in this cycle, with `core_out` the
    /// core's outputs in this cycle. `read_served`: a read is served in this cycle (the
    /// encoders' and the spindle's and interlock's register views are built only then;
    /// nothing else reads them).
    fn hardware_status(&self, core_out: &CoreOutputs, read_served: bool) -> HardwareStatus {
        let mut rate_error = 0;
        let mut step_lost = 0;
        for axis in 0..self.params.n_axes {
            rate_error |= u8::from(core_out.rate_error(axis)) << axis;
            step_lost |= u8::from(core_out.step_lost(axis)) << axis;
        }
        let config = safety_config(&self.registers);
        HardwareStatus {
            core_run: self.core_run(),
            gate: self.motion.gate(),
            halt: self.halt(),
            fault_estop: self.safety.fault_estop(),
            fault_watchdog: self.safety.fault_watchdog(),
            estop_active: self.safety.estop_active(&config),
            underrun: self.motion.underrun(),
            record_error: core_out.record_error(),
            rate_error,
            step_lost,
            fifo_level: self.fifo.level(),
            fifo_free: self.fifo.depth() - self.fifo.level() - self.fifo.staged(),
            feedback: self.feedback_status(read_served),
            io: if read_served { self.io_status() } else { IoStatus::default() },
        }
    }

    fn io_status(&self) -> IoStatus {
        let mut io = IoStatus::default();
        if self.params.has_spindle {
            let config = self.registers.spindle_config();
            io.spindle_level = self.spindle.level();
            io.spindle_at_speed = self.spindle.level() == config.target();
            io.spindle_enabled = self.spindle.pins(&config).en;
        }
        if self.params.has_outputs {
            io.interlock_active = self.interlock.active(&self.registers.interlock_config());
            io.interlock_blocked = self.interlock.blocked();
        }
        if self.params.has_panel {
            io.panel_keys = self.panel.keys_word();
            io.panel_menu = self.panel.menu_word();
        }
        if self.params.gantry_built() {
            io.gantry_status = GantryLink::status_word(self.core.gantry(), self.gantry_sync_mode());
        }
        io
    }

    /// The feedback blocks' register view in this cycle.
    fn feedback_status(&self, read_served: bool) -> FeedbackStatus {
        let encoders = if read_served {
            self.encoders.status(&self.registers.encoder_configs(), &self.registers.probe_config())
        } else {
            EncoderBankStatus::default()
        };
        let encoder_illegal = self.encoders.any_illegal();
        if !self.params.has_mpg {
            return FeedbackStatus { encoders, encoder_illegal, ..FeedbackStatus::default() };
        }
        FeedbackStatus {
            encoders,
            encoder_illegal,
            hand_wheel: self.hand_wheel.status(),
            jog: self.jog.status(self.registers.jog_enable()),
        }
    }

    /// Synchronous reset. The safety monitor takes its configuration from the register
    /// file as it is in this cycle (why `rst` must last 2 cycles).
    fn reset(&mut self) {
        let config = safety_config(&self.registers);
        let cycle = self.cycle;
        *self = Top::new(self.params);
        self.safety = SafetyMonitor::new(self.params.wd_w, ESTOP_FILTER_WIDTH, &config);
        self.cycle = cycle;
    }

    /// One rising clock edge with the pins of this cycle.
    pub fn step(&mut self, inputs: &TopInputs) {
        self.cycle = self.cycle.wrapping_add(1);
        if inputs.rst {
            self.reset();
            return;
        }
        let p = self.params;
        let served = self.bus_stage;
        let core_out = self.core.outputs();
        let hw = self.hardware_status(&core_out, served.is_some_and(|request| !request.write));
        let halt = hw.halt;

        // The register bus: SPI has priority.
        let spi_request = if p.has_spi { self.spi_frame.request() } else { None };
        let parallel_request = if p.has_parallel { self.parallel.request() } else { None };
        // The grant goes into the bus stage; what is served now was granted last cycle. A
        // push reading RECORD_INC from the register file's store holds the requests that
        // touch it.
        let grant = arbitrate(spi_request, parallel_request, self.registers.bus_hold(served));
        self.bus_stage = grant.map(|(_, request)| request);
        let rdata = self.registers.rdata();

        // The FIFO's write port and read side.
        let spi_port = self.spi_frame.fifo_port();
        let head = self.fifo.head().copied();
        let engaged = self.jog.engaged();
        let motion_inputs = MotionInputs {
            core_run: self.motion_run(),
            rec_ready: core_out.rec_ready(),
            head: head.as_ref(),
            level: self.fifo.level(),
            start_level: self.registers.start_level(),
            clear_errors: self.registers.clear_errors(),
            inhibit: p.has_outputs && self.interlock.inhibit(&self.registers.interlock_config()),
        };
        let start_blocked = self.motion.start_blocked(&motion_inputs);
        // While the jog drives the core the FIFO waits.
        let pop = !engaged && self.motion.pop(&motion_inputs);
        let (fifo_inputs, push_refused, push_in_flight) =
            self.registers.fifo_port(&spi_port, self.fifo.full(), halt, pop);

        let mut core_inputs = CoreInputs {
            run: hw.core_run,
            period_clocks: self.registers.period_clocks(),
            clear_errors: self.registers.clear_errors(),
            rec_valid: if engaged { self.jog.rec_valid() } else { self.motion.rec_valid(&motion_inputs) },
            record: if engaged { self.jog.record() } else { head.unwrap_or_default() },
            halt,
            ..CoreInputs::default()
        };
        for (axis, config) in core_inputs.axes.iter_mut().enumerate().take(p.n_axes) {
            *config = self.registers.axis_config(axis);
        }
        self.step_panel_gantry(inputs, served, &hw, &mut core_inputs);
        let mut safety_inputs = safety_config(&self.registers);
        safety_inputs.kick = self.registers.kick() || self.committed_last_cycle;
        self.committed_last_cycle = spi_port.commit;
        safety_inputs.clear_faults = self.registers.clear_faults();
        safety_inputs.estop_pin = inputs.estop_pin;

        // The host links.
        let mut spi_events = Default::default();
        let latch_hold = p.has_spi && self.spi_frame.latch_hold();
        if p.has_spi {
            let phy = &self.spi_phy;
            let frame_inputs = SpiFrameInputs {
                frame_start: phy.frame_start(),
                frame_end: phy.frame_end(),
                frame_whole: phy.frame_whole(),
                rx_valid: phy.rx_valid(),
                rx_byte: phy.rx_byte(),
                // While a RECORD_PUSH writes the FIFO, no room for a FIFO frame.
                fifo_free: if push_in_flight { 0 } else { hw.fifo_free },
                fifo_flush: fifo_inputs.flush,
                granted: matches!(grant, Some((Grant::Spi, _))),
                rdata,
            };
            let tx_byte = if phy.takes_tx_byte() {
                let status = self.registers.read(regs::status::ADDR, &hw);
                self.spi_frame.tx_byte(status as u8)
            } else {
                0
            };
            let pins = SpiPins { cs_n: inputs.spi_cs_n, sck: inputs.spi_sck, mosi: inputs.spi_mosi };
            self.spi_phy.step(&pins, tx_byte);
            spi_events = self.spi_frame.step(&frame_inputs);
        }
        let mut parallel_error = false;
        if p.has_parallel {
            let pins = ParallelPins {
                cs_n: inputs.bus_cs_n,
                adv_n: inputs.bus_adv_n,
                rd_n: inputs.bus_rd_n,
                wr_n: inputs.bus_wr_n,
                ad: inputs.bus_ad_in,
            };
            let granted = matches!(grant, Some((Grant::Parallel, _)));
            parallel_error = self.parallel.step(&pins, granted, rdata);
        }

        // The feedback blocks.
        let timestamp = self.registers.timestamp();
        let probe_config = self.registers.probe_config();
        let (probe_event, probe_seen) = (self.encoders.probe_event(&probe_config), self.encoders.probe_seen());
        let clear_errors = self.registers.clear_errors();
        let clear_counters = self.registers.clear_counters();
        self.encoders.step(&EncoderBankInputs {
            enc_a: inputs.enc_a,
            enc_b: inputs.enc_b,
            enc_z: inputs.enc_z,
            probe_pin: inputs.probe_pin,
            prescale: self.registers.enc_prescale(),
            channels: self.registers.encoder_configs(),
            probe: probe_config,
            clear_errors,
            clear_counters,
            timestamp,
            positions: core_out.positions,
            latch: position_latch(hw.core_run, core_out.period_boundary(), latch_hold),
            // The bus stage's read (served in this cycle, granted in the last): a read of
            // the visited channel's store stalls the visit, so the store's read at this
            // cycle's edge sees no write.
            served_read: served.filter(|request| !request.write).map(|request| request.addr),
        });
        if p.has_mpg {
            let (prescale, filter) = self.registers.mpg_control();
            let detents = self.hand_wheel.detents();
            self.hand_wheel.step(&HandWheelInputs {
                mpg_a: inputs.mpg_a,
                mpg_b: inputs.mpg_b,
                prescale,
                filter,
                clear_errors,
                clear_counters,
            });
            let run_written = matches!(served, Some(r) if r.write
                && r.addr & (ADDRESSES - 1) as u8 == regs::control::ADDR
                && regs::control::RUN.get(r.wdata) != 0);
            let mut jog_inputs = self.registers.jog_inputs();
            jog_inputs.halt = halt;
            jog_inputs.detents = detents;
            jog_inputs.rec_ready = core_out.rec_ready();
            jog_inputs.run_written = run_written;
            self.jog.step(&jog_inputs);
        }

        if p.has_spindle {
            self.spindle.step(&self.registers.spindle_config(), halt);
        }
        if p.has_outputs {
            let config = self.registers.interlock_config();
            self.interlock.step(inputs.interlock_pin, &config, start_blocked, clear_errors);
        }
        let underrun = self.motion.step(&motion_inputs);
        self.registers.step(&RegisterFileInputs {
            served,
            hw,
            period_boundary: core_out.period_boundary(),
            block_end: core_out.block_end(),
            positions: core_out.positions,
            latch_hold,
            probe_event,
            probe_seen,
            spi: spi_events,
            parallel_error,
            underrun,
            push_refused,
            fifo_flush: fifo_inputs.flush,
            fifo_full: self.fifo.full(),
            spi_fifo_in_use: spi_port.owns_port(),
        });
        self.fifo.step(&fifo_inputs);
        self.safety.step(&safety_inputs);
        self.core.step(&core_inputs);
    }
}

impl Top {
    /// The panel's and the gantry link's edge (their inputs from this cycle's state,
    /// before anything else steps), and the core's gantry inputs of this cycle.
    fn step_panel_gantry(
        &mut self,
        inputs: &TopInputs,
        served: Option<BusRequest>,
        hw: &HardwareStatus,
        core_inputs: &mut CoreInputs,
    ) {
        let p = self.params;
        if !p.has_panel && !p.gantry_built() {
            return;
        }
        let clear_counters = self.registers.clear_counters();
        let gantry = p.gantry_built().then(|| *self.core.gantry());
        if p.gantry_built() {
            let control = self.registers.word(regs::gantry_control::ADDR);
            let limits = self.registers.word(regs::gantry_limits::ADDR);
            core_inputs.gantry =
                self.gantry_link.gantry_inputs(control, limits, self.gantry_sync_mode(), clear_counters);
            let channels = self.registers.encoder_configs();
            let enc_mask = ((1u16 << p.n_enc.min(8)) - 1) as u8;
            self.gantry_link.step(&GantryLinkInputs {
                control,
                enc_a: inputs.enc_a & enc_mask,
                enc_b: inputs.enc_b & enc_mask,
                prescale: self.registers.enc_prescale(),
                filters: std::array::from_fn(|c| channels[c].filter),
                clear_errors: self.registers.clear_errors(),
                clear_counters,
            });
        }
        if p.has_panel {
            let menu_write =
                served.filter(|r| r.write && r.addr & (ADDRESSES - 1) as u8 == regs::panel_menu::ADDR).map(|r| r.wdata);
            let (sync_err, gantry_flags) = match &gantry {
                Some(g) => (saturate(g.error()), u8::from(g.refused()) << 1 | u8::from(g.alarm())),
                None => (0, 0),
            };
            self.panel.step(&PanelInputs {
                scan: self.registers.word(regs::panel_scan::ADDR),
                menu_write,
                row_n: inputs.panel_row_n,
                sync_err,
                alarm_in: u8::from(hw.fault_watchdog) << 3 | u8::from(hw.fault_estop) << 2 | gantry_flags,
            });
        }
    }
}

/// The safety monitor's configuration from the register file (kick, clear and pin
/// left inactive).
fn safety_config(registers: &RegisterFile) -> SafetyInputs {
    SafetyInputs {
        watchdog_enable: registers.watchdog_enable(),
        watchdog_timeout: registers.watchdog_timeout(),
        estop_active_high: registers.estop_active_high(),
        estop_filter: registers.estop_filter(),
        ..SafetyInputs::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pins_pack_and_unpack() {
        let inputs =
            TopInputs { rst: true, spi_mosi: true, bus_ad_in: 0xBEEF, estop_pin: true, ..TopInputs::default() };
        let word = inputs.pack();
        assert_eq!(word, 1 | 0b10 | 0b1000 | 0b1111_0000 | 1 << 8 | 0xBEEF << 16 | 0xF << 59);
        assert_eq!(TopInputs::unpack(word), inputs);
        let feedback =
            TopInputs { enc_a: 0x81, enc_b: 0x02, enc_z: 0x40, probe_pin: true, mpg_b: true, ..TopInputs::default() };
        let word = feedback.pack() & !TopInputs::default().pack();
        assert_eq!(word, 0x81 << 32 | 0x02 << 40 | 0x40 << 48 | 1 << 56 | 1 << 58);
        assert_eq!(TopInputs::unpack(feedback.pack()), feedback);
        let outputs = TopOutputs { pin_a: 0x81, pin_en: 0x0F, irq: true, bus_ad_out: 0x1234, ..TopOutputs::default() };
        assert_eq!(outputs.pack(), 0x81 | 0x0F << 16 | 1 << 26 | 0x1234 << 32 | 1 << 51);
        assert_eq!(TopOutputs::unpack(outputs.pack()), outputs);
        let io = TopOutputs {
            spindle: SpindlePins { pwm: true, sdi: true, ..SpindlePins::default() },
            light: true,
            gpio: 0x81,
            ..TopOutputs::default()
        };
        assert_eq!(io.pack(), 1 << 48 | 1 << 53 | 1 << 30 | 0x81 << 56);
        assert_eq!(TopOutputs::unpack(io.pack()), io);
        let interlock = TopInputs { interlock_pin: true, ..TopInputs::default() };
        assert_eq!(interlock.pack() & !TopInputs::default().pack(), 1 << 9);
        assert_eq!(TopOutputs::unpack(outputs.pack()), outputs);
    }

    #[test]
    fn bad_params_are_refused() {
        let bad = |p: TopParams| Top::try_new(p).unwrap_err().name;
        let d = TopParams::default();
        assert_eq!(bad(TopParams { n_axes: 0, ..d }), "N_AXES");
        assert_eq!(bad(TopParams { p_width: 25, ..d }), "P_WIDTH");
        assert_eq!(bad(TopParams { timing_w: 17, ..d }), "TIMING_W");
        assert_eq!(bad(TopParams { fifo_depth_log2: 16, ..d }), "FIFO_DEPTH_LOG2");
        assert_eq!(bad(TopParams { wd_w: 0, ..d }), "WD_W");
        assert_eq!(bad(TopParams { n_enc: 5, ..d }), "N_ENC");
        assert_eq!(bad(TopParams { n_enc: 0, ..d }), "N_ENC", "the RTL's per-channel vectors need a channel");
        assert!(Top::try_new(TopParams { n_enc: 1, has_mpg: false, ..d }).is_ok());
        assert!(std::panic::catch_unwind(|| Top::new(TopParams { n_axes: 9, ..d })).is_err());
    }

    #[test]
    fn power_on_equals_reset_and_reads_the_map() {
        let mut top = Top::new(TopParams::default());
        let fresh = top.clone();
        for _ in 0..10 {
            top.step(&TopInputs::default());
        }
        top.step(&TopInputs { rst: true, ..TopInputs::default() });
        top.step(&TopInputs { rst: true, ..TopInputs::default() });
        assert_eq!(Top { cycle: 0, ..top.clone() }, fresh);
        assert_eq!(top.register(regs::id::ADDR), regs::id::MAGIC_VALUE);
        let caps = top.register(regs::caps::ADDR);
        assert_eq!(regs::caps::N_AXES.get(caps), 4);
        assert_eq!(regs::caps::P_WIDTH.get(caps), 20);
        assert_eq!((regs::caps::N_ENC.get(caps), regs::caps::HAS_MPG.get(caps)), (4, 1));
        assert_eq!(top.outputs(), TopOutputs::default());
    }
}

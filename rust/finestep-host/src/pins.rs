//! Driving a simulated core at its pins: [`PinTarget`] is a clocked model of
//! `finestep_top` (packed pin words), and [`PinHost`] plays an SPI master and an 8080
//! master on it with the host timing of docs/spec/spi_frame.md and
//! docs/spec/parallel_bus_slave.md, cycle by cycle.

use finestep_interface::pin_timing::PinTimingReport;

use crate::spi::SpiTransfer;
use crate::BusError;

/// Bit positions of the packed pin words (the layout of `sim/finestep_top_sim.h`).
pub mod layout {
    /// Input: synchronous reset.
    pub const IN_RST: u32 = 0;
    /// Input: SPI chip select, active low.
    pub const IN_SPI_CS_N: u32 = 1;
    /// Input: SPI clock.
    pub const IN_SPI_SCK: u32 = 2;
    /// Input: SPI MOSI.
    pub const IN_SPI_MOSI: u32 = 3;
    /// Input: 8080 chip select, active low.
    pub const IN_BUS_CS_N: u32 = 4;
    /// Input: 8080 address latch (NADV), active low.
    pub const IN_BUS_ADV_N: u32 = 5;
    /// Input: 8080 read strobe, active low.
    pub const IN_BUS_RD_N: u32 = 6;
    /// Input: 8080 write strobe, active low.
    pub const IN_BUS_WR_N: u32 = 7;
    /// Input: E-stop.
    pub const IN_ESTOP: u32 = 8;
    /// Input: the interlock (e.g. a door).
    pub const IN_INTERLOCK: u32 = 9;
    /// Input: lowest bit of the 16-bit multiplexed address/data bus.
    pub const IN_BUS_AD0: u32 = 16;
    /// Input: encoder A of channel `c` is bit `IN_ENC_A0 + c`.
    pub const IN_ENC_A0: u32 = 32;
    /// Input: encoder B of channel `c`.
    pub const IN_ENC_B0: u32 = 40;
    /// Input: encoder index Z of channel `c`.
    pub const IN_ENC_Z0: u32 = 48;
    /// Input: the probe.
    pub const IN_PROBE: u32 = 56;
    /// Input: hand wheel A.
    pub const IN_MPG_A: u32 = 57;
    /// Input: hand wheel B.
    pub const IN_MPG_B: u32 = 58;
    /// Output: pin A of axis `i` is bit `OUT_PIN_A0 + i`.
    pub const OUT_PIN_A0: u32 = 0;
    /// Output: pin B of axis `i`.
    pub const OUT_PIN_B0: u32 = 8;
    /// Output: enable of axis `i`.
    pub const OUT_PIN_EN0: u32 = 16;
    /// Output: SPI MISO.
    pub const OUT_SPI_MISO: u32 = 24;
    /// Output: MISO output enable.
    pub const OUT_SPI_MISO_OE: u32 = 25;
    /// Output: interrupt request.
    pub const OUT_IRQ: u32 = 26;
    /// Output: 8080 bus output enable.
    pub const OUT_BUS_AD_OE: u32 = 27;
    /// Output: lowest bit of the 16-bit read data.
    pub const OUT_BUS_AD0: u32 = 32;
    /// Output: mist coolant.
    pub const OUT_COOLANT_MIST: u32 = 28;
    /// Output: flood coolant.
    pub const OUT_COOLANT_FLOOD: u32 = 29;
    /// Output: the work light.
    pub const OUT_LIGHT: u32 = 30;
    /// Output: the spindle's PWM.
    pub const OUT_SPINDLE_PWM: u32 = 48;
    /// Output: the spindle's direction.
    pub const OUT_SPINDLE_DIR: u32 = 49;
    /// Output: the spindle's enable.
    pub const OUT_SPINDLE_EN: u32 = 50;
    /// Output: the spindle DAC's chip select, active low.
    pub const OUT_DAC_CS_N: u32 = 51;
    /// Output: the spindle DAC's clock.
    pub const OUT_DAC_SCK: u32 = 52;
    /// Output: the spindle DAC's data.
    pub const OUT_DAC_SDI: u32 = 53;
    /// Output: general output `i` is bit `OUT_GPIO0 + i`.
    pub const OUT_GPIO0: u32 = 56;

    /// The inputs of an idle host: chip selects and strobes high, reset low, E-stop
    /// pin low (released for the default active-high polarity).
    pub const IDLE_INPUTS: u64 =
        1 << IN_SPI_CS_N | 1 << IN_BUS_CS_N | 1 << IN_BUS_ADV_N | 1 << IN_BUS_RD_N | 1 << IN_BUS_WR_N;
}

use layout::*;

/// A clocked `finestep_top` seen at its pins.
pub trait PinTarget {
    /// Runs `cycles` clock edges with the packed `inputs` held.
    fn drive(&mut self, inputs: u64, cycles: u64) -> Result<(), BusError>;
    /// The packed outputs in the current cycle.
    fn outputs(&self) -> u64;
    /// What the target measured at its step pins, when it measures them.
    fn pin_timing(&self) -> Option<PinTimingReport> {
        None
    }
    /// Runs up to `cycles` clock edges with `inputs` held, stopping right after the first
    /// edge that changes the outputs; returns the edges run. A closed loop (a drive and
    /// its encoder) uses it to see every output change on its cycle.
    fn drive_to_change(&mut self, inputs: u64, cycles: u64) -> Result<u64, BusError> {
        let before = self.outputs();
        for ran in 1..=cycles {
            self.drive(inputs, 1)?;
            if self.outputs() != before {
                return Ok(ran);
            }
        }
        Ok(cycles)
    }
}

/// Host-side timing in core clocks (defaults: the fastest the spec allows).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PinTiming {
    /// SCK half period (>= 4: SCK at most clk/8).
    pub sck_half: u64,
    /// CS_n low before the first SCK phase (>= 4).
    pub cs_lead: u64,
    /// CS_n high between frames (>= 4).
    pub cs_gap: u64,
    /// 8080: address phase (NADV low) length (>= 3, address valid throughout).
    pub adv_low: u64,
    /// 8080: WR_n low length, data valid throughout (>= 3).
    pub write_low: u64,
    /// 8080: RD_n low length; data sampled in its last cycle (>= 9).
    pub read_low: u64,
    /// 8080: all strobes high after an access (>= 4 after a read).
    pub recovery: u64,
}

impl Default for PinTiming {
    fn default() -> Self {
        PinTiming { sck_half: 4, cs_lead: 4, cs_gap: 4, adv_low: 4, write_low: 5, read_low: 10, recovery: 4 }
    }
}

/// An SPI and 8080 master on a [`PinTarget`], owning the target's input pins.
pub struct PinHost<T> {
    target: T,
    inputs: u64,
    timing: PinTiming,
    wheel: WheelTurn,
}

/// Clocks between two quadrature edges of the hand wheel turned by
/// [`PinHost::turn_wheel`]: well over the chip's default hand-wheel filter (FILTER = 4
/// samples every PRESCALE + 1 = 500 clocks, docs/registers.md#mpg_control).
pub const WHEEL_EDGE_CLOCKS: u64 = 10_000;

/// A hand wheel on the MPG pins turning while clocks pass: edges still to make (the
/// sign is the direction) and the quadrature phase (0..4: A, B = 00, 10, 11, 01, so A
/// leads B turning up).
#[derive(Clone, Copy, Debug, Default)]
struct WheelTurn {
    pending: i64,
    phase: u8,
    until_edge: u64,
}

fn with_bit(word: u64, bit: u32, level: bool) -> u64 {
    if level {
        word | 1 << bit
    } else {
        word & !(1 << bit)
    }
}

impl<T: PinTarget> PinHost<T> {
    /// A host on `target` with idle pins.
    pub fn new(target: T, timing: PinTiming) -> PinHost<T> {
        PinHost { target, inputs: IDLE_INPUTS, timing, wheel: WheelTurn::default() }
    }

    /// The target.
    pub fn target(&self) -> &T {
        &self.target
    }

    /// The target, mutably.
    pub fn target_mut(&mut self) -> &mut T {
        &mut self.target
    }

    /// The target, giving up the host.
    pub fn into_target(self) -> T {
        self.target
    }

    /// The packed inputs being driven.
    pub fn inputs(&self) -> u64 {
        self.inputs
    }

    fn hold(&mut self, mut cycles: u64) -> Result<(), BusError> {
        while self.wheel.pending != 0 && cycles > 0 {
            let run = cycles.min(self.wheel.until_edge);
            self.target.drive(self.inputs, run)?;
            cycles -= run;
            self.wheel.until_edge -= run;
            if self.wheel.until_edge == 0 {
                let up = self.wheel.pending > 0;
                self.wheel.phase = if up { (self.wheel.phase + 1) % 4 } else { (self.wheel.phase + 3) % 4 };
                self.wheel.pending -= if up { 1 } else { -1 };
                self.wheel.until_edge = WHEEL_EDGE_CLOCKS;
                let (a, b) =
                    [(false, false), (true, false), (true, true), (false, true)][usize::from(self.wheel.phase)];
                self.set(IN_MPG_A, a);
                self.set(IN_MPG_B, b);
            }
        }
        self.target.drive(self.inputs, cycles)
    }

    /// Turns the hand wheel on the MPG pins by `edges` quadrature edges (4 a detent;
    /// negative: down) while clocks pass, one edge every [`WHEEL_EDGE_CLOCKS`], after any
    /// turn not yet made.
    pub fn start_wheel_turn(&mut self, edges: i64) {
        if self.wheel.pending == 0 {
            self.wheel.until_edge = WHEEL_EDGE_CLOCKS;
        }
        self.wheel.pending += edges;
    }

    fn set(&mut self, bit: u32, level: bool) {
        self.inputs = with_bit(self.inputs, bit, level);
    }

    /// Holds reset for `cycles` (at least 2 are needed), then releases it.
    pub fn reset(&mut self, cycles: u64) -> Result<(), BusError> {
        self.set(IN_RST, true);
        self.hold(cycles.max(2))?;
        self.set(IN_RST, false);
        Ok(())
    }

    /// Sets the E-stop pin level (held until changed).
    pub fn set_estop_pin(&mut self, level: bool) {
        self.set(IN_ESTOP, level);
    }

    /// Sets the interlock pin (held until changed).
    pub fn set_interlock_pin(&mut self, level: bool) {
        self.set(IN_INTERLOCK, level);
    }

    /// Runs `cycles` clocks with the pins as they are.
    pub fn idle(&mut self, cycles: u64) -> Result<(), BusError> {
        self.hold(cycles)
    }

    fn set_ad(&mut self, value: u16) {
        self.inputs = (self.inputs & !(0xFFFF << IN_BUS_AD0)) | (u64::from(value) << IN_BUS_AD0);
    }

    fn address_phase(&mut self, halfword: u8) -> Result<(), BusError> {
        self.set(IN_BUS_CS_N, false);
        self.set(IN_BUS_ADV_N, false);
        self.set_ad(u16::from(halfword));
        self.hold(self.timing.adv_low)?;
        self.set(IN_BUS_ADV_N, true);
        self.set_ad(0);
        self.hold(1)
    }

    fn end_access(&mut self) -> Result<(), BusError> {
        self.set(IN_BUS_RD_N, true);
        self.set(IN_BUS_WR_N, true);
        self.set(IN_BUS_CS_N, true);
        self.set_ad(0);
        self.hold(self.timing.recovery)
    }

    /// One 8080 write of `data` to halfword address `halfword`.
    pub fn parallel_write16(&mut self, halfword: u8, data: u16) -> Result<(), BusError> {
        self.address_phase(halfword)?;
        self.set_ad(data);
        self.set(IN_BUS_WR_N, false);
        self.hold(self.timing.write_low)?;
        self.end_access()
    }

    /// One 8080 read of halfword address `halfword`; the data is sampled in the last
    /// cycle of the strobe and must be driven then.
    pub fn parallel_read16(&mut self, halfword: u8) -> Result<u16, BusError> {
        self.address_phase(halfword)?;
        self.set(IN_BUS_RD_N, false);
        self.hold(self.timing.read_low)?;
        let outputs = self.target.outputs();
        self.end_access()?;
        if outputs >> OUT_BUS_AD_OE & 1 == 0 {
            return Err(BusError::NotDriven { halfword });
        }
        Ok((outputs >> OUT_BUS_AD0) as u16)
    }

    /// One SPI byte, MSB first, mode 0; returns the byte sampled on MISO at the rising
    /// edges.
    fn spi_byte(&mut self, out: u8) -> Result<u8, BusError> {
        let mut received = 0u8;
        for bit in (0..8).rev() {
            self.set(IN_SPI_MOSI, out >> bit & 1 != 0);
            self.set(IN_SPI_SCK, false);
            self.hold(self.timing.sck_half)?;
            let miso = self.target.outputs() >> OUT_SPI_MISO & 1;
            received = received << 1 | miso as u8;
            self.set(IN_SPI_SCK, true);
            self.hold(self.timing.sck_half)?;
        }
        Ok(received)
    }

    /// Starts an SPI frame (CS_n low) without sending anything; for tests that cut
    /// frames short, with [`PinHost::spi_send_bits`] and [`PinHost::spi_end`].
    pub fn spi_begin(&mut self) -> Result<(), BusError> {
        self.set(IN_SPI_SCK, false);
        self.set(IN_SPI_CS_N, false);
        self.hold(self.timing.cs_lead)
    }

    /// Sends the first `bits` bits of `bytes` (MSB first) in an open frame.
    pub fn spi_send_bits(&mut self, bytes: &[u8], bits: usize) -> Result<(), BusError> {
        for index in 0..bits.min(8 * bytes.len()) {
            let level = bytes[index / 8] >> (7 - index % 8) & 1 != 0;
            self.set(IN_SPI_MOSI, level);
            self.set(IN_SPI_SCK, false);
            self.hold(self.timing.sck_half)?;
            self.set(IN_SPI_SCK, true);
            self.hold(self.timing.sck_half)?;
        }
        Ok(())
    }

    /// Ends an SPI frame: SCK low for half a period, then CS_n high for the gap.
    pub fn spi_end(&mut self) -> Result<(), BusError> {
        self.set(IN_SPI_SCK, false);
        self.hold(self.timing.sck_half)?;
        self.set(IN_SPI_CS_N, true);
        self.set(IN_SPI_MOSI, false);
        self.hold(self.timing.cs_gap)
    }
}

impl<T: PinTarget> SpiTransfer for PinHost<T> {
    fn transfer(&mut self, tx: &[u8]) -> Result<Vec<u8>, BusError> {
        self.spi_begin()?;
        let mut rx = Vec::with_capacity(tx.len());
        for &byte in tx {
            rx.push(self.spi_byte(byte)?);
        }
        self.spi_end()?;
        Ok(rx)
    }

    fn wait(&mut self, clocks: u64) -> Result<(), BusError> {
        self.hold(clocks)
    }

    fn drive_estop(&mut self, level: bool) -> Result<bool, BusError> {
        self.set_estop_pin(level);
        Ok(true)
    }

    fn turn_wheel(&mut self, edges: i64) -> Result<bool, BusError> {
        self.start_wheel_turn(edges);
        Ok(true)
    }

    fn pin_timing(&mut self) -> Result<Option<PinTimingReport>, BusError> {
        Ok(self.target.pin_timing())
    }
}

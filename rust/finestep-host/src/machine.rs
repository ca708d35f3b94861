//! [`Machine`]: one finestep core behind a [`Bus`], at the level a machine builder
//! thinks in: identity, axis setup, faults, run, positions.

use crate::machine_io::SpindleSetup;
use crate::regs::{
    axis_enable, axis_mode, caps, clock_hz, command, control, fifo_level, id, latch_time, period_clocks, position,
    start_level, status, version,
};
use crate::{Bus, BusError};
use finestep_interface::{invert, DriveTiming, OutMode};

/// What the core was built with (`CAPS`, `CLOCK_HZ`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Caps {
    /// Step/dir axes.
    pub n_axes: usize,
    /// The position FIFO holds this many records.
    pub fifo_depth: usize,
    /// Bits of the period register.
    pub p_width: u32,
    /// Bits of each step timing.
    pub timing_w: u32,
    /// The core clock in Hz.
    pub clock_hz: u32,
    /// Encoder channels.
    pub n_enc: usize,
    /// The hand wheel and the jog generator are built.
    pub has_mpg: bool,
    /// `R`: the clocks between two visits of an axis by the step engine
    /// (`2^CAPS.STEP_ROUND_LOG2`: its slots `S` with the step engine, `S * 32 / STEP_DIGIT`
    /// with the digit-serial one; 1 with a DDA and a shaper per axis). Step edges and
    /// drive timings fall on multiples of `R` clocks, and the period must be a multiple of
    /// `R` (docs/spec/step_engine.md, docs/spec/step_serial.md).
    pub step_slots: u32,
    /// The spindle block is built (`CAPS.HAS_SPINDLE`).
    pub has_spindle: bool,
    /// The logic outputs and the interlock are built (`CAPS.HAS_OUTPUTS`).
    pub has_outputs: bool,
    /// The card's panel (keypad, LED menu) is built (`CAPS.HAS_PANEL`).
    pub has_panel: bool,
    /// The gantry pair is built (`CAPS.HAS_GANTRY`).
    pub has_gantry: bool,
}

impl Caps {
    /// The longest period the core's period counter holds, clocks (`2^P_WIDTH - 1`,
    /// within the `PERIOD_CLOCKS.CLOCKS` field).
    pub fn period_max(&self) -> u32 {
        (((1u64 << self.p_width.min(32)) - 1) as u32).min(period_clocks::CLOCKS.max())
    }

    /// The largest drive timing the core's counters hold, clocks (`2^TIMING_W - 1`).
    pub fn timing_max(&self) -> u32 {
        ((1u64 << self.timing_w.min(32)) - 1) as u32
    }
}

/// The `STEP_DIGIT` of a build with `n_axes` axes and `CAPS.STEP_ROUND_LOG2 =
/// round_log2`: 0 where the round is 0 (a DDA and a shaper per axis) or the step engine's
/// slot bits `SL`, the digit of the digit-serial engine where it is `SL + log2(32 /
/// STEP_DIGIT)`, `None` where it is neither (no build the RTL makes).
fn serial_digit(n_axes: usize, round_log2: u32) -> Option<u32> {
    let core = finestep_interface::CoreParams { n_axes, ..finestep_interface::CoreParams::default() };
    if round_log2 == 0 {
        return Some(0);
    }
    match round_log2.checked_sub(core.step_slot_bits()) {
        Some(0) => Some(0),
        Some(visit @ 2..=5) => Some(32 >> visit),
        _ => None,
    }
}

/// Step timing and output mode of one axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct AxisSetup {
    /// The drive timing L, S, U, H in core clocks.
    pub timing: DriveTiming,
    /// How the pins are driven.
    pub out_mode: OutMode,
    /// Pin inversions: the bits of [`finestep_interface::invert`].
    pub invert: u8,
}

/// Every axis's position latched on one clock, with that clock's timestamp.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Positions {
    /// Steps per axis.
    pub steps: Vec<i32>,
    /// `TIMESTAMP` at the latch.
    pub latch_time: u32,
}

/// A finestep core behind a bus.
pub struct Machine<B> {
    pub(crate) bus: B,
    pub(crate) caps: Caps,
    /// The step timing last written per axis (reset values until then), for the jog's
    /// rated-rate check.
    pub(crate) timings: Vec<DriveTiming>,
    /// The period last written (the reset value until then).
    pub(crate) period_clocks: u32,
    /// The spindle's output configuration last written (the reset values until then).
    pub(crate) spindle: SpindleSetup,
}

impl<B: Bus> Machine<B> {
    /// Checks the identity and version, and reads the capabilities (refused when they
    /// are outside every build the RTL accepts).
    pub fn connect(mut bus: B) -> Result<Machine<B>, BusError> {
        let mut words = [0u32; 4];
        bus.read(id::ADDR, &mut words)?;
        let [magic, version_word, caps_word, clock] = words;
        if magic != id::MAGIC_VALUE {
            return Err(BusError::NotFinestep { found: magic, expected: id::MAGIC_VALUE });
        }
        let major = version::MAJOR.get(version_word);
        if major != crate::regs::MAP_VERSION_MAJOR {
            return Err(BusError::MapVersion { found: major, driver: crate::regs::MAP_VERSION_MAJOR });
        }
        debug_assert_eq!(clock_hz::ADDR, id::ADDR + 3);
        let caps = Caps {
            n_axes: caps::N_AXES.get(caps_word) as usize,
            fifo_depth: 1 << caps::FIFO_DEPTH_LOG2.get(caps_word),
            p_width: caps::P_WIDTH.get(caps_word),
            timing_w: caps::TIMING_W.get(caps_word),
            clock_hz: clock,
            n_enc: caps::N_ENC.get(caps_word) as usize,
            has_mpg: caps::HAS_MPG.get(caps_word) != 0,
            step_slots: 1 << caps::STEP_ROUND_LOG2.get(caps_word),
            has_spindle: caps::HAS_SPINDLE.get(caps_word) != 0,
            has_outputs: caps::HAS_OUTPUTS.get(caps_word) != 0,
            has_panel: caps::HAS_PANEL.get(caps_word) != 0,
            has_gantry: caps::HAS_GANTRY.get(caps_word) != 0,
        };
        let Some(step_digit) = serial_digit(caps.n_axes, caps::STEP_ROUND_LOG2.get(caps_word)) else {
            let engine =
                finestep_interface::CoreParams { n_axes: caps.n_axes, step_shared: true, ..Default::default() };
            return Err(BusError::StepSlots { word: caps_word, found: caps.step_slots, built: engine.step_slots() });
        };
        let build = finestep_interface::TopParams {
            n_axes: caps.n_axes,
            p_width: caps.p_width,
            timing_w: caps.timing_w,
            fifo_depth_log2: caps::FIFO_DEPTH_LOG2.get(caps_word),
            clock_hz: clock,
            n_enc: caps.n_enc,
            has_mpg: caps.has_mpg,
            step_shared: caps.step_slots > 1,
            step_digit,
            has_spindle: caps.has_spindle,
            has_outputs: caps.has_outputs,
            has_panel: caps.has_panel,
            has_gantry: caps.has_gantry,
            ..finestep_interface::TopParams::default()
        };
        build.validate().map_err(|error| BusError::Caps { word: caps_word, clock_hz: clock, error })?;
        // The round follows from N_AXES and the digit: any other value is no build the RTL
        // makes.
        let built_slots = build.core_params().step_slots();
        if built_slots != caps.step_slots {
            return Err(BusError::StepSlots { word: caps_word, found: caps.step_slots, built: built_slots });
        }
        let timings = vec![DriveTiming::RESET; caps.n_axes];
        Ok(Machine { bus, caps, timings, period_clocks: period_clocks::CLOCKS_RESET, spindle: SpindleSetup::default() })
    }

    /// The capabilities read at connection.
    pub fn caps(&self) -> Caps {
        self.caps
    }

    /// The period last written, clocks (the reset value until then).
    pub fn period_clocks(&self) -> u32 {
        self.period_clocks
    }

    /// The bus.
    pub fn bus(&mut self) -> &mut B {
        &mut self.bus
    }

    /// The bus, to look at (e.g. a simulated target's state).
    pub fn bus_ref(&self) -> &B {
        &self.bus
    }

    /// The bus, giving up the machine.
    pub fn into_bus(self) -> B {
        self.bus
    }

    /// Sets the step timing and output mode of `axis`; a timing wider than the core's
    /// counters (`CAPS.TIMING_W`) or an axis it lacks is refused before anything is written.
    pub fn configure_axis(&mut self, axis: usize, setup: &AxisSetup) -> Result<(), BusError> {
        if axis >= self.caps.n_axes {
            return Err(BusError::NoSuchAxis { axis, n_axes: self.caps.n_axes });
        }
        let max = self.caps.timing_max();
        if let Some((field, value)) = setup.timing.first_above(max) {
            return Err(BusError::TimingRange { axis, field, value, max });
        }
        let mode = [
            (axis_mode::INVERT_A, invert::PIN_A),
            (axis_mode::INVERT_B, invert::PIN_B),
            (axis_mode::INVERT_EN, invert::PIN_EN),
        ]
        .into_iter()
        .fold(axis_mode::OUT_MODE.set(0, setup.out_mode.bits().into()), |word, (field, bit)| {
            field.set(word, u32::from(setup.invert & bit != 0))
        });
        for (addr, word) in setup.timing.register_words(axis) {
            self.bus.write(addr, word)?;
        }
        self.bus.write(axis_mode::addr(axis), mode)?;
        self.timings[axis] = setup.timing;
        Ok(())
    }

    /// Drive enables, bit `i` for axis `i`.
    pub fn enable_axes(&mut self, mask: u32) -> Result<(), BusError> {
        self.bus.write(axis_enable::ADDR, axis_enable::ENABLE.set(0, mask & 0xFF))
    }

    /// The interpolation period in clocks (taken when a run starts); a period outside
    /// `1..=` [`Caps::period_max`], or not a multiple of the step engine's slots
    /// ([`Caps::step_slots`]: the core would run it rounded down), is refused before
    /// anything is written.
    pub fn set_period(&mut self, clocks: u32) -> Result<(), BusError> {
        let max = self.caps.period_max();
        if !(1..=max).contains(&clocks) {
            return Err(BusError::PeriodRange { clocks, max });
        }
        let slots = self.caps.step_slots;
        if !clocks.is_multiple_of(slots) {
            return Err(BusError::PeriodSlots { clocks, slots });
        }
        self.bus.write(period_clocks::ADDR, period_clocks::CLOCKS.set(0, clocks))?;
        self.period_clocks = clocks;
        Ok(())
    }

    /// The FIFO level at which streaming starts.
    pub fn set_start_level(&mut self, records: u16) -> Result<(), BusError> {
        self.bus.write(start_level::ADDR, start_level::LEVEL.set(0, u32::from(records)))
    }

    /// Writes CONTROL: run request, watchdog, E-stop polarity.
    pub fn set_control(&mut self, run: bool, watchdog: bool, estop_active_high: bool) -> Result<(), BusError> {
        let word = control::ESTOP_ACTIVE_HIGH.set(
            control::WATCHDOG_ENABLE.set(control::RUN.set(0, run.into()), watchdog.into()),
            estop_active_high.into(),
        );
        self.bus.write(control::ADDR, word)
    }

    /// Issues COMMAND bits (see `regs::command`).
    pub fn command(&mut self, word: u32) -> Result<(), BusError> {
        self.bus.write(command::ADDR, word)
    }

    /// Clears the E-stop and watchdog faults (only those whose cause is gone) and every
    /// sticky error flag.
    pub fn clear_faults_and_errors(&mut self) -> Result<(), BusError> {
        self.command(command::CLEAR_FAULTS.set(command::CLEAR_ERRORS.set(0, 1), 1))
    }

    /// The STATUS word.
    pub fn status(&mut self) -> Result<u32, BusError> {
        self.bus.read_one(status::ADDR)
    }

    /// Committed records in the FIFO and the room left.
    pub fn fifo(&mut self) -> Result<(u32, u32), BusError> {
        let word = self.bus.read_one(fifo_level::ADDR)?;
        Ok((fifo_level::LEVEL.get(word), fifo_level::FREE.get(word)))
    }

    /// Every axis's position, all latched on the same clock. While running, the latch
    /// moves only at period boundaries: LATCH_TIME is read before and after the
    /// positions, and the read is retried if a boundary came in between (over SPI one read
    /// frame already holds the latch; over the 8080 bus the reads are separate). While
    /// not running, the latch follows the pulse train every clock: the positions are
    /// returned once two reads agree and the core is still stopped, with the later
    /// LATCH_TIME.
    pub fn positions(&mut self) -> Result<Positions, BusError> {
        let n = self.caps.n_axes;
        let (steps, latch_time) = self.read_latched(8, "positions", |bus| {
            let mut words = vec![0u32; n];
            bus.read(position::addr(0), &mut words)?;
            Ok(words.into_iter().map(|w| w as i32).collect::<Vec<i32>>())
        })?;
        Ok(Positions { steps, latch_time })
    }

    /// Reads registers that the position latch takes on one clock (`read`), coherently,
    /// with the LATCH_TIME they belong to: LATCH_TIME is read before and after, and the
    /// read is retried if the latch moved in between. A stopped core latches every clock:
    /// then two equal reads with the core still stopped describe its state, with the
    /// later LATCH_TIME. Stopped, something outside the core can keep the registers
    /// changing between any two reads (an encoder turned by hand, a hand-wheel jog): on
    /// the last attempt the later read is taken as it is, each frame's registers from
    /// the clock that frame latched (over SPI one frame holds the latch; nothing is lost:
    /// counts and positions are totals). Running, gives up after `attempts`, naming `what`.
    pub(crate) fn read_latched<T: PartialEq>(
        &mut self,
        attempts: usize,
        what: &'static str,
        read: impl Fn(&mut B) -> Result<T, BusError>,
    ) -> Result<(T, u32), BusError> {
        let running =
            |bus: &mut B| -> Result<bool, BusError> { Ok(status::RUNNING.get(bus.read_one(status::ADDR)?) != 0) };
        for attempt in 1..=attempts {
            let before = self.bus.read_one(latch_time::ADDR)?;
            let first = read(&mut self.bus)?;
            let after = self.bus.read_one(latch_time::ADDR)?;
            if before == after {
                return Ok((first, after));
            }
            if !running(&mut self.bus)? {
                let again = read(&mut self.bus)?;
                let latest = self.bus.read_one(latch_time::ADDR)?;
                if (again == first || attempt == attempts) && !running(&mut self.bus)? {
                    return Ok((again, latest));
                }
            }
        }
        Err(BusError::LatchMoving { attempts, what })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::PeriodRecord;

    /// A register file that answers the identity of a core with 3 axes, P_WIDTH 16 and
    /// TIMING_W 8, and records every write.
    struct Registers {
        writes: Vec<(u8, u32)>,
        fifo_depth_log2: u32,
    }

    impl Bus for Registers {
        fn read(&mut self, addr: u8, out: &mut [u32]) -> Result<(), BusError> {
            for (i, word) in out.iter_mut().enumerate() {
                let caps_word = caps::TIMING_W.set(caps::P_WIDTH.set(caps::N_AXES.set(0, 3), 16), 8);
                let caps_word = caps::N_ENC.set(caps::FIFO_DEPTH_LOG2.set(caps_word, self.fifo_depth_log2), 1);
                *word = match addr + i as u8 {
                    id::ADDR => id::MAGIC_VALUE,
                    version::ADDR => version::MAJOR.set(0, crate::regs::MAP_VERSION_MAJOR),
                    caps::ADDR => caps_word,
                    clock_hz::ADDR => 50_000_000,
                    _ => 0,
                };
            }
            Ok(())
        }
        fn write(&mut self, addr: u8, value: u32) -> Result<(), BusError> {
            self.writes.push((addr, value));
            Ok(())
        }
        fn push_records(&mut self, _: &[PeriodRecord]) -> Result<(), BusError> {
            Ok(())
        }
        fn wait(&mut self, _: u64) -> Result<(), BusError> {
            Ok(())
        }
    }

    #[test]
    fn requests_beyond_the_caps_are_refused_before_any_write() {
        let mut machine = Machine::connect(Registers { writes: Vec::new(), fifo_depth_log2: 8 }).unwrap();
        assert_eq!((machine.caps().period_max(), machine.caps().timing_max()), (65_535, 255));
        let err = machine.set_period(65_536).unwrap_err();
        assert!(matches!(err, BusError::PeriodRange { clocks: 65_536, max: 65_535 }), "{err}");
        assert!(matches!(machine.set_period(0), Err(BusError::PeriodRange { .. })));
        let slow =
            AxisSetup { timing: DriveTiming { dir_setup: 256, ..DriveTiming::default() }, ..AxisSetup::default() };
        let err = machine.configure_axis(0, &slow).unwrap_err();
        assert_eq!(err.to_string(), "axis 0: dir_setup = 256 clocks exceeds the core's 255 (CAPS.TIMING_W)");
        let err = machine.configure_axis(3, &AxisSetup::default()).unwrap_err();
        assert!(matches!(err, BusError::NoSuchAxis { axis: 3, n_axes: 3 }), "{err}");
        assert!(machine.bus_ref().writes.is_empty());
        machine.set_period(65_535).unwrap();
        assert_eq!(machine.bus_ref().writes, [(period_clocks::ADDR, 65_535)]);
    }

    #[test]
    fn caps_of_no_buildable_core_are_refused_naming_what_was_read() {
        let err = Machine::connect(Registers { writes: Vec::new(), fifo_depth_log2: 0 }).err().unwrap().to_string();
        assert_eq!(
            err,
            "CAPS reads 0x00110013 and CLOCK_HZ 50000000: finestep_top: FIFO_DEPTH_LOG2 = 0 is outside 1..=15"
        );
    }
}

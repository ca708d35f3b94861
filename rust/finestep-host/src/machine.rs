//! [`Machine`]: one finestep core behind a [`Bus`], at the level a machine builder
//! thinks in: identity, axis setup, faults, run, positions.

use crate::feedback::{CountExtender, EdgeTimeExtender};
use crate::machine_io::SpindleSetup;
use crate::regs::{
    axis_enable, axis_mode, caps, clock_hz, command, control, fifo_level, id, latch_time, period_clocks, position,
    probe_control, probe_status, probe_time, start_level, status, version,
};
use crate::{Bus, BusError};
use finestep_interface::pbp::PbpLanes;
use finestep_interface::{invert, DriveTiming, OutMode, PeriodRecord};

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
    /// One position snapshot for the period latch and the probe (`VERSION.ONE_SNAPSHOT`,
    /// docs/spec/register_file.md#one-snapshot): while `PROBE_STATUS.SEEN`, `POSITION`
    /// and `LATCH_TIME` hold the probe's snapshot, not the period's. [`Machine::positions`]
    /// and [`Machine::feedback`] then say so ([`Machine::probe_holds_positions`]).
    pub one_snapshot: bool,
    /// `RECORD_INC` is write-only, reads 0 (`VERSION.INC_WRITE_ONLY`). This driver never
    /// reads it back in any build: it writes the increments and pushes.
    pub inc_write_only: bool,
    /// `AXIS_TIMING_A/B` and `AXIS_MODE` are write-only, read 0
    /// (`VERSION.AXIS_WRITE_ONLY`). This driver never reads them back in any build: it
    /// keeps the timings it wrote.
    pub axis_write_only: bool,
    /// A `RECORD_INC` write goes straight into the FIFO's record and `RECORD_PUSH` queues
    /// it only when every axis's was written since the last push (`VERSION.INC_DIRECT`,
    /// docs/spec/register_file.md#record_inc-straight-into-the-fifo). The bus's
    /// `push_records` writes every axis's increment before each push in any build.
    pub inc_direct: bool,
    /// The point-by-point comparison interpolator is in the core (`VERSION.HAS_PBP`,
    /// docs/spec/pbp_interp.md#in-the-core): a record with the flag PBP
    /// ([`finestep_interface::PeriodRecord::pbp`], checked by [`Machine::pbp_record`]) runs
    /// a line or an arc on an axis pair. A core without it runs such a record's lanes as
    /// increments: the host sends them only to a core that reports it.
    pub has_pbp: bool,
    /// Bits of each encoder channel's count and edge time: 16 on a core with
    /// `VERSION.ENC_COUNT_16` (the CPLDs; docs/spec/encoder_bank.md#narrow-words), else 32.
    /// [`Machine::feedback`] extends the counts to 64-bit positions and the edge times to
    /// 32-bit `TIMESTAMP`s in either build.
    pub enc_count_w: u32,
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
    /// On a [`Caps::one_snapshot`] core, the `LATCH_TIME` of a probe snapshot released by
    /// [`Machine::release_probe_snapshot`] that the period latch may not have replaced yet
    /// (running, it takes `POSITION` back at the next boundary, with `SEEN` already 0).
    pub(crate) released_probe_time: Option<u32>,
    /// Per encoder channel, the extension of its count and edge-time reads
    /// ([`Caps::enc_count_w`] bits) to a 64-bit position and a 32-bit `TIMESTAMP`.
    pub(crate) encoder_tracks: Vec<(CountExtender, EdgeTimeExtender)>,
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
            // The capabilities CAPS has no room for (0 on a core of map 1.0: the defaults).
            one_snapshot: version::ONE_SNAPSHOT.get(version_word) != 0,
            inc_write_only: version::INC_WRITE_ONLY.get(version_word) != 0,
            axis_write_only: version::AXIS_WRITE_ONLY.get(version_word) != 0,
            inc_direct: version::INC_DIRECT.get(version_word) != 0,
            has_pbp: version::HAS_PBP.get(version_word) != 0,
            enc_count_w: if version::ENC_COUNT_16.get(version_word) != 0 { 16 } else { 32 },
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
            one_snapshot: caps.one_snapshot,
            inc_write_only: caps.inc_write_only,
            axis_write_only: caps.axis_write_only,
            inc_direct: caps.inc_direct,
            has_pbp: caps.has_pbp,
            enc_count_w: caps.enc_count_w,
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
        Ok(Machine {
            bus,
            caps,
            timings,
            period_clocks: period_clocks::CLOCKS_RESET,
            spindle: SpindleSetup::default(),
            released_probe_time: None,
            encoder_tracks: vec![
                (CountExtender::new(caps.enc_count_w), EdgeTimeExtender::new(caps.enc_count_w));
                caps.n_enc
            ],
        })
    }

    /// The capabilities read at connection.
    pub fn caps(&self) -> Caps {
        self.caps
    }

    /// The FIFO record for the point-by-point record `lanes` with `flags` besides PBP
    /// ([`finestep_interface::PeriodRecord::pbp`]), refused before anything is sent when
    /// the core cannot run it as meant: no interpolator ([`Caps::has_pbp`]), a pair beyond
    /// the core's axes (the core would run an idle period and set `RECORD_ERROR`), values
    /// outside the record's fields, or decisions closer than the step engine's visit
    /// (`tick_div + 1 < ` [`Caps::step_slots`]: refused by the core the same way).
    pub fn pbp_record(&self, lanes: &PbpLanes, flags: u8) -> Result<PeriodRecord, BusError> {
        let refuse = |why: String| Err(BusError::PbpRecord { why });
        if !self.caps.has_pbp {
            return refuse("the core has no point-by-point interpolator (VERSION.HAS_PBP 0)".into());
        }
        if 2 * usize::from(lanes.pair) + 1 >= self.caps.n_axes {
            return refuse(format!(
                "pair {} needs axes {}, {}: the core has {} axes",
                lanes.pair,
                2 * lanes.pair,
                2 * lanes.pair + 1,
                self.caps.n_axes
            ));
        }
        if !lanes.fits() {
            return refuse(format!("{lanes:?} does not fit the record's fields"));
        }
        if lanes.tick_div + 1 < self.caps.step_slots {
            return refuse(format!(
                "a decision every {} clocks is closer than the step engine's visit of {} clocks",
                lanes.tick_div + 1,
                self.caps.step_slots
            ));
        }
        Ok(PeriodRecord::pbp(lanes, flags))
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
    ///
    /// On a core with [`Caps::one_snapshot`] whose probe has latched (`PROBE_STATUS.SEEN`)
    /// the positions are the probe event's, not live: refused with
    /// [`BusError::ProbeHoldsPositions`] ([`Machine::release_probe_snapshot`] resumes the
    /// period latch), and so are they after a release until the latch has taken them
    /// (while running, at the next period boundary: the `LATCH_TIME` read with them is
    /// still the probe's).
    pub fn positions(&mut self) -> Result<Positions, BusError> {
        let n = self.caps.n_axes;
        let (steps, latch_time) = self.read_latched(8, "positions", |bus| {
            let mut words = vec![0u32; n];
            bus.read(position::addr(0), &mut words)?;
            Ok(words.into_iter().map(|w| w as i32).collect::<Vec<i32>>())
        })?;
        if self.snapshot_is_the_probes(latch_time)? {
            return Err(BusError::ProbeHoldsPositions);
        }
        Ok(Positions { steps, latch_time })
    }

    /// Whether `POSITION` and `LATCH_TIME` hold the probe event's snapshot instead of the
    /// period latch's: a [`Caps::one_snapshot`] core with `PROBE_STATUS.SEEN`
    /// (docs/spec/register_file.md#one-snapshot). Always `false` on other cores (no
    /// read). `SEEN` stays set until the host arms the probe, so a `false` read after the
    /// positions were read says they were the period latch's.
    pub fn probe_holds_positions(&mut self) -> Result<bool, BusError> {
        if !self.caps.one_snapshot {
            return Ok(false);
        }
        Ok(probe_status::SEEN.get(self.bus.read_one(probe_status::ADDR)?) != 0)
    }

    /// Whether positions read with `latch_time` on this core are a probe event's
    /// snapshot: `SEEN` set ([`Machine::probe_holds_positions`]), or a snapshot released
    /// with that `LATCH_TIME` that the period latch has not replaced yet. Read after the
    /// positions (`SEEN` stays set until the host arms the probe).
    pub(crate) fn snapshot_is_the_probes(&mut self, latch_time: u32) -> Result<bool, BusError> {
        if self.probe_holds_positions()? {
            return Ok(true);
        }
        if self.released_probe_time == Some(latch_time) {
            return Ok(true);
        }
        // A later latch: the release is complete.
        self.released_probe_time = None;
        Ok(false)
    }

    /// On a [`Caps::one_snapshot`] core, hands `POSITION` and `LATCH_TIME` back to the
    /// period latch after a probe event (the probe's snapshot read or not wanted): writes
    /// `PROBE_CONTROL.ARM` with the polarity and filter as they are, which clears `SEEN`;
    /// the latch takes the positions again from the clock after (at the next period
    /// boundary while running: until then [`Machine::positions`] still refuses them, told
    /// by the snapshot's `LATCH_TIME`, kept here). The probe stays armed: its next event
    /// holds the positions again. Nothing on other cores.
    pub fn release_probe_snapshot(&mut self) -> Result<(), BusError> {
        if !self.caps.one_snapshot {
            return Ok(());
        }
        if self.probe_holds_positions()? {
            // PROBE_TIME reads LATCH_TIME on such a core: the snapshot's time.
            self.released_probe_time = Some(self.bus.read_one(probe_time::ADDR)?);
        }
        let word = self.bus.read_one(probe_control::ADDR)?;
        let keep = probe_control::ACTIVE_HIGH.set(0, probe_control::ACTIVE_HIGH.get(word));
        let keep = probe_control::FILTER.set(keep, probe_control::FILTER.get(word));
        self.bus.write(probe_control::ADDR, probe_control::ARM.set(keep, 1))
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

    /// A core of map 1.1 whose VERSION reports `version_bits` (ONE_SNAPSHOT,
    /// INC_WRITE_ONLY), its probe's SEEN as `seen` (cleared by a write of ARM, as the
    /// register file does), POSITION[i] = 100 + i, LATCH_TIME (and PROBE_TIME)
    /// `latch_time`, which a write of ARM advances unless `boundary_pending` (a running
    /// core: the period latch takes the positions back at the next boundary, `boundary()`);
    /// it records every read address and every write.
    struct Snapshot {
        version_bits: u32,
        n_axes: u32,
        seen: bool,
        latch_time: u32,
        boundary_pending: bool,
        probe_control: u32,
        reads: Vec<u8>,
        writes: Vec<(u8, u32)>,
    }

    impl Bus for Snapshot {
        fn read(&mut self, addr: u8, out: &mut [u32]) -> Result<(), BusError> {
            for (i, word) in out.iter_mut().enumerate() {
                let at = addr + i as u8;
                self.reads.push(at);
                let caps_word = caps::TIMING_W.set(caps::P_WIDTH.set(caps::N_AXES.set(0, self.n_axes), 16), 8);
                let caps_word = caps::N_ENC.set(caps::FIFO_DEPTH_LOG2.set(caps_word, 1), 1);
                let version_word = version::MINOR.set(version::MAJOR.set(0, crate::regs::MAP_VERSION_MAJOR), 1);
                *word = match at {
                    id::ADDR => id::MAGIC_VALUE,
                    version::ADDR => version_word | self.version_bits,
                    caps::ADDR => caps_word,
                    clock_hz::ADDR => 50_000_000,
                    probe_status::ADDR => probe_status::SEEN.set(0, u32::from(self.seen)),
                    probe_control::ADDR => self.probe_control,
                    latch_time::ADDR | probe_time::ADDR => self.latch_time,
                    a if (position::addr(0)..position::addr(2)).contains(&a) => 100 + u32::from(a - position::addr(0)),
                    _ => 0,
                };
            }
            Ok(())
        }
        fn write(&mut self, addr: u8, value: u32) -> Result<(), BusError> {
            if addr == probe_control::ADDR && probe_control::ARM.get(value) != 0 {
                self.seen = false;
                if !self.boundary_pending {
                    self.latch_time += 1;
                }
            }
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

    fn snapshot_core(version_bits: u32, seen: bool) -> Machine<Snapshot> {
        Machine::connect(snapshot_bus(version_bits, seen, 2)).unwrap()
    }

    fn snapshot_bus(version_bits: u32, seen: bool, n_axes: u32) -> Snapshot {
        let probe_control = probe_control::FILTER.set(probe_control::ACTIVE_HIGH.set(0, 0), 5);
        Snapshot {
            version_bits,
            n_axes,
            seen,
            latch_time: 7,
            boundary_pending: false,
            probe_control,
            reads: Vec::new(),
            writes: Vec::new(),
        }
    }

    /// HAS_PBP from VERSION: a 4-axis core with it takes point-by-point records on its
    /// pairs 0 and 1; one without it, a pair it lacks, lanes outside the fields are refused
    /// before anything is sent; a 2-axis core reporting it is no build the RTL makes.
    #[test]
    fn pbp_records_only_for_a_core_with_the_interpolator() {
        let lanes = PbpLanes { arc: false, x: 10, y: -3, tick_div: 99, ..PbpLanes::default() };
        let m = Machine::connect(snapshot_bus(version::HAS_PBP.set(0, 1), false, 4)).unwrap();
        assert!(m.caps().has_pbp);
        let record = m.pbp_record(&PbpLanes { pair: 1, ..lanes }, finestep_interface::flags::BLOCK_END).unwrap();
        assert_eq!(record.pbp_lanes(), Some(PbpLanes { pair: 1, ..lanes }));
        let refused = |m: &Machine<Snapshot>, l: PbpLanes| match m.pbp_record(&l, 0) {
            Err(BusError::PbpRecord { why }) => why,
            other => panic!("{other:?}"),
        };
        assert!(refused(&m, PbpLanes { pair: 2, ..lanes }).contains("the core has 4 axes"));
        assert!(refused(&m, PbpLanes { x: 1 << 23, ..lanes }).contains("does not fit"));
        assert!(refused(&m, PbpLanes { tick_div: 1 << PbpLanes::DIV_W, ..lanes }).contains("does not fit"));
        assert!(m.pbp_record(&PbpLanes { tick_div: (1 << PbpLanes::DIV_W) - 1, ..lanes }, 0).is_ok());
        let plain = Machine::connect(snapshot_bus(0, false, 4)).unwrap();
        assert!(!plain.caps().has_pbp);
        assert!(refused(&plain, lanes).contains("VERSION.HAS_PBP 0"));
        assert!(matches!(
            Machine::connect(snapshot_bus(version::HAS_PBP.set(0, 1), false, 2)),
            Err(BusError::Caps { .. })
        ));
    }

    /// Released while running, the probe's snapshot stays in POSITION until the next
    /// boundary with SEEN already 0: the positions are still refused and the feedback
    /// still marked as the probe's (its LATCH_TIME is the snapshot's), until the latch
    /// has moved; a second release in that window keeps the snapshot's time.
    #[test]
    fn one_snapshot_release_holds_until_the_latch_moves() {
        let mut m = snapshot_core(version::ONE_SNAPSHOT.set(0, 1), true);
        m.bus().boundary_pending = true;
        m.release_probe_snapshot().unwrap();
        assert!(!m.probe_holds_positions().unwrap(), "SEEN cleared by the arm");
        assert!(matches!(m.positions(), Err(BusError::ProbeHoldsPositions)));
        assert!(m.feedback().unwrap().probe_held);
        m.release_probe_snapshot().unwrap();
        assert!(matches!(m.positions(), Err(BusError::ProbeHoldsPositions)));
        // The boundary: the period latch takes POSITION and LATCH_TIME.
        m.bus().latch_time += 1;
        assert_eq!(m.positions().unwrap().latch_time, 8);
        assert!(!m.feedback().unwrap().probe_held);
    }

    /// ONE_SNAPSHOT from VERSION: while the probe's SEEN is set the positions are refused
    /// and the feedback marked as the probe's; a release arms the probe with its polarity
    /// and filter kept, and the positions are the latch's again.
    #[test]
    fn one_snapshot_positions_are_not_live_while_the_probe_holds_them() {
        let mut m = snapshot_core(version::ONE_SNAPSHOT.set(0, 1), true);
        assert!(m.caps().one_snapshot && !m.caps().inc_write_only, "{:?}", m.caps());
        assert!(matches!(m.positions(), Err(BusError::ProbeHoldsPositions)));
        let held = m.feedback().unwrap();
        assert!(held.probe_held && held.steps == [100, 101], "{held:?}");
        m.release_probe_snapshot().unwrap();
        let arm = probe_control::ARM.set(probe_control::FILTER.set(0, 5), 1);
        assert_eq!(m.bus_ref().writes, [(probe_control::ADDR, arm)], "ARM, polarity (low) and filter (5) kept");
        assert_eq!(m.positions().unwrap().steps, [100, 101]);
        assert!(!m.feedback().unwrap().probe_held);
    }

    /// Without ONE_SNAPSHOT (a map 1.0 core reads 0 there) SEEN says nothing about
    /// POSITION: never read for it, and a release writes nothing.
    #[test]
    fn without_one_snapshot_the_probe_never_holds_the_positions() {
        let mut m = snapshot_core(0, true);
        assert!(!m.caps().one_snapshot && !m.caps().inc_write_only);
        assert_eq!(m.positions().unwrap().steps, [100, 101]);
        assert!(!m.feedback().unwrap().probe_held);
        m.release_probe_snapshot().unwrap();
        assert!(m.bus_ref().writes.is_empty());
        assert!(!m.bus_ref().reads.contains(&probe_status::ADDR), "{:?}", m.bus_ref().reads);
    }

    /// INC_WRITE_ONLY and AXIS_WRITE_ONLY from VERSION (a build without the readback
    /// store): accepted, and the driver's calls never read RECORD_INC, AXIS_TIMING_A/B or
    /// AXIS_MODE back.
    #[test]
    fn write_only_registers_are_never_read_back() {
        let all = version::INC_WRITE_ONLY.set(version::ONE_SNAPSHOT.set(0, 1), 1);
        let mut m = snapshot_core(version::INC_DIRECT.set(version::AXIS_WRITE_ONLY.set(all, 1), 1), false);
        assert!(m.caps().inc_write_only && m.caps().one_snapshot && m.caps().axis_write_only && m.caps().inc_direct);
        m.configure_axis(1, &AxisSetup::default()).unwrap();
        m.set_period(1000).unwrap();
        m.positions().unwrap();
        m.feedback().unwrap();
        m.set_control(true, false, true).unwrap();
        let inc = crate::regs::record_inc::ADDR..crate::regs::record_inc::addr(2);
        // The axis block: AXIS_TIMING_A/B and AXIS_MODE of every axis (stride 4).
        let block = crate::regs::axis_timing_a::ADDR..crate::regs::axis_timing_a::ADDR + 32;
        let axis = |a: &u8| block.contains(a) && (a - block.start) % 4 < 3;
        assert!(!m.bus_ref().reads.iter().any(|a| inc.contains(a) || axis(a)), "{:?}", m.bus_ref().reads);
        assert!(m.bus_ref().writes.iter().any(|(a, _)| axis(a)), "the axis was configured");
    }

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

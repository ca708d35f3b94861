//! finestep as LinuxCNC's motion hardware: the driver behind the `finestep` HAL
//! component (`linuxcnc/finestep.c`, a realtime module that calls [`ffi`]).
//!
//! LinuxCNC's trajectory planner computes every joint's position once per servo period.
//! Each [`Driver::write`] turns those positions into one period record for the chip's
//! position FIFO, through the host driver's own record encoder and bus
//! ([`finestep_host::SpiBus`]: no second copy of the record layout): the increment of
//! axis `i` is `C_i(k) - C_i(k-1)` with `C_i(k) = round(65536 * position-cmd *
//! position-scale)` in I16F16 steps, so the chip's DDA lands every period's commanded
//! position exactly (its step count after the record is `C_i(k)` rounded half up to a
//! whole step, [`quantised_steps`]). An increment over the axis's rated step rate
//! ([`finestep_interface::rate`]) or over `maxvel` is clamped to it and the rest carried
//! into the next periods (counted in `limited`). Each [`Driver::read`] takes one
//! coherent latched read of every step position and encoder count.
//!
//! Transports ([`Transport`]): a board on Linux spidev, or a simulated chip served by
//! `finestep sim-chip SOCKET`. On the simulated chip the driver is the chip's clock:
//! each write advances simulated time to just past the next period boundary, so each
//! servo period runs exactly one core period whatever the machine's timing jitter.
//!
//! ```no_run
//! use finestep_hal::{Driver, StepgenCommand};
//! let mut driver = Driver::open("sim:/tmp/chip.sock")?;
//! let mut cmd = vec![StepgenCommand::default(); driver.n_axes()];
//! cmd[0] = StepgenCommand { position_cmd: 1.0, position_scale: 800.0, enable: true, ..cmd[0] };
//! driver.read(1_000_000)?;
//! driver.write(1_000_000, true, 0, &cmd)?;
//! # Ok::<(), finestep_hal::HalError>(())
//! ```

#![warn(missing_docs)]

pub mod ffi;

use std::path::PathBuf;
use std::str::FromStr;

use finestep_host::regs::{command, latch_time, status, timestamp, watchdog_timeout};
use finestep_host::{AxisSetup, Bus, BusError, CountMode, EncoderSetup, Machine, SpiBus, SpiTransfer};
use finestep_interface::rate::RateChecker;
use finestep_interface::{DriveTiming, Increment, OutMode, PeriodRecord, TopParams};

/// SCK on spidev when the bus does not give one.
pub const DEFAULT_SCK_HZ: u32 = 1_000_000;

/// Clocks past a period boundary at which a paced write lets the simulated chip stop,
/// so that the next read finds that boundary's latch.
pub const PACE_MARGIN_CLOCKS: u32 = 64;

/// Servo periods between a write and the read that sees its record's end position: the
/// record runs in the core period after the one it was queued in, and the read of the
/// next servo period comes before that period's end. The open-loop check compares at
/// this lag.
pub const FEEDBACK_LAG_PERIODS: usize = 2;

/// Clocks from a DDA update to the step being counted in POSITION
/// (docs/spec/finestep_core.md#latency: an update in cycle n is counted in n + 2): a step
/// requested in a period's last two clocks is not yet in the boundary's latch.
pub const LATCH_LAG_CLOCKS: u64 = 2;

/// The longest a step requested by the DDA may take to be counted in POSITION: the
/// [`LATCH_LAG_CLOCKS`], the longest the step shaper holds a request for the drive
/// timing (a reversal's direction hold and set-up, docs/spec/rated_rate.md:
/// `S * (L_v + max(S_v, H_v + U_v) - 1)` clocks in the step engine's visits) and up to
/// `S - 1` clocks until the axis's visit (docs/spec/step_engine.md). A step requested
/// later than this before a period boundary may be missing from that boundary's latch.
pub fn count_latency_clocks(timing: &DriveTiming, slots: u32) -> u64 {
    LATCH_LAG_CLOCKS + finestep_interface::rate::reversal_wait_in(timing, slots) + u64::from(slots.max(1) - 1)
}

/// The increment that lands on the same whole step as `d` from `sent` (both I16F16
/// steps) but requests its last step at least `latency` clocks (plus a margin of
/// `slots + 2` clocks for the DDA's visits and rounding) before the end of a period of
/// `period_clocks`, so that the boundary's latch counts it: the DDA moves linearly over
/// the period, and the last rounding point it crosses is crossed at
/// `P * (h - sent) / d`; when that is too late, the landing moves past `h` within the
/// same step (by at most `d * W / (P - W)`; the next period's increment carries the
/// difference back). `d` itself when it crosses no rounding point, crosses in time, or
/// when no landing within the same step and `max` (the largest |increment| allowed)
/// crosses in time (steps closer together than the latency).
pub fn settled_increment(sent: i64, d: i64, period_clocks: u32, latency: u64, slots: u32, max: i64) -> i64 {
    let (q0, q1) = (quantised_steps(sent), quantised_steps(sent + d));
    let p = i128::from(period_clocks);
    let deadline = p - i128::from(latency) - i128::from(slots.max(1)) - 2;
    if q0 == q1 || deadline <= 0 {
        return d;
    }
    let step = 1i128 << 16;
    let half = step / 2;
    // Distance from the start to the last rounding point crossed, 2^-16 steps; the
    // crossing is at clock `dist * P / |d|`.
    let dist = if d > 0 {
        step * i128::from(q1) - half - i128::from(sent)
    } else {
        i128::from(sent) - (step * (i128::from(q1) + 1) - half)
    };
    let mag = i128::from(d.abs());
    if dist * p <= deadline * mag {
        return d;
    }
    // Strictly past the point (a decreasing position reaches the lower step only below it).
    let need = (dist * p + deadline - 1) / deadline + i128::from(d < 0);
    let Ok(need) = i64::try_from(need) else { return d };
    let settled = need * d.signum();
    if need > max || quantised_steps(sent + settled) != q1 {
        return d;
    }
    settled
}

/// Records queued before a board starts (slack for the host's jitter); a paced
/// simulated chip starts at one.
pub const BOARD_START_LEVEL: u16 = 3;

/// Where the chip is.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Transport {
    /// A board on Linux spidev, `spidev:/dev/spidevB.C[@SCK_HZ]`.
    Spidev {
        /// The device.
        path: PathBuf,
        /// SCK, Hz.
        sck_hz: u32,
    },
    /// A chip served by `finestep sim-chip SOCKET`, `sim:SOCKET`.
    Sim(PathBuf),
}

impl FromStr for Transport {
    type Err = HalError;

    fn from_str(text: &str) -> Result<Self, HalError> {
        let bad = |why: &str| HalError::BadBus { bus: text.to_string(), why: why.to_string() };
        if let Some(rest) = text.strip_prefix("spidev:") {
            let (path, sck_hz) = match rest.rsplit_once('@') {
                Some((path, sck)) => (path, sck.parse().map_err(|_| bad("the SCK is not a frequency in Hz"))?),
                None => (rest, DEFAULT_SCK_HZ),
            };
            if path.is_empty() {
                return Err(bad("no device path"));
            }
            return Ok(Transport::Spidev { path: path.into(), sck_hz });
        }
        if let Some(socket) = text.strip_prefix("sim:") {
            if socket.is_empty() {
                return Err(bad("no socket path"));
            }
            return Ok(Transport::Sim(socket.into()));
        }
        Err(bad("not spidev:/dev/spidevB.C[@SCK_HZ] or sim:SOCKET"))
    }
}

/// Why the driver failed. The HAL component prints the message and raises its error pin.
#[derive(Debug, thiserror::Error)]
pub enum HalError {
    /// The bus string names no transport.
    #[error("bus `{bus}`: {why}")]
    BadBus {
        /// What was given.
        bus: String,
        /// What is wrong with it.
        why: String,
    },
    /// Opening the transport or the identity check failed.
    #[error("{target}: {source}")]
    Open {
        /// The transport.
        target: String,
        /// What failed.
        source: BusError,
    },
    /// A bus operation failed.
    #[error("{target}: {source}")]
    Bus {
        /// The transport.
        target: String,
        /// What failed.
        source: BusError,
    },
    /// A position command or scale that is no position.
    #[error("stepgen.{axis:02}: position-cmd {position} * position-scale {scale} is not a position in steps")]
    BadCommand {
        /// The axis.
        axis: usize,
        /// `position-cmd`.
        position: f64,
        /// `position-scale`.
        scale: f64,
    },
    /// A drive timing the core cannot hold.
    #[error("stepgen.{axis:02}: {source}")]
    Timing {
        /// The axis.
        axis: usize,
        /// What is out of range.
        source: finestep_interface::TimingError,
    },
    /// A `step_type` the chip has no output mode for.
    #[error("stepgen.{axis:02}: step_type {step_type} is not 0 (step/dir), 1 (up/down) or 2 (quadrature)")]
    StepType {
        /// The axis.
        axis: usize,
        /// What was set.
        step_type: u32,
    },
    /// A servo period the core's period counter cannot hold.
    #[error("servo period {period_ns} ns is {clocks} clocks of the {clock_hz} Hz core: outside 1..={max}")]
    Period {
        /// The servo thread's period.
        period_ns: i64,
        /// In core clocks.
        clocks: i64,
        /// The core clock.
        clock_hz: u32,
        /// The longest period the core holds.
        max: u32,
    },
    /// A servo period that is not a whole number of the step engine's slots: the core
    /// would run it rounded down, and its periods would drift from the servo thread's.
    #[error(
        "servo period {period_ns} ns is {clocks} clocks of the {clock_hz} Hz core, not a multiple of its {slots} \
         step round (CAPS.STEP_ROUND_LOG2): choose a servo period of a multiple of {slots} clocks"
    )]
    PeriodSlots {
        /// The servo thread's period.
        period_ns: i64,
        /// In core clocks.
        clocks: i64,
        /// The core clock.
        clock_hz: u32,
        /// The step engine's slots.
        slots: u32,
    },
    /// Drive timing or step type changed while running (taken at the start only).
    #[error("stepgen.{axis:02}: steplen/stepspace/dirsetup/dirhold/step_type changed while running; they are taken when the machine is enabled")]
    ChangedWhileRunning {
        /// The axis.
        axis: usize,
    },
    /// The chip halted or ran dry while running.
    #[error("the chip stopped: STATUS {status:#04x} ({why})")]
    Stopped {
        /// The status byte.
        status: u8,
        /// Which fault.
        why: &'static str,
    },
    /// A record over the rated step rate (the clamp failed: a bug).
    #[error("stepgen.{axis:02}: {source}")]
    Rate {
        /// The axis.
        axis: usize,
        /// The rate check's error.
        source: finestep_interface::rate::RateError,
    },
    /// An index is not one of the chip's channels.
    #[error("{what} {index}: the chip has {count}")]
    NoSuch {
        /// What was indexed.
        what: &'static str,
        /// The index.
        index: usize,
        /// How many there are.
        count: usize,
    },
}

/// What LinuxCNC sets for one step generator: the pins and parameters of
/// `finestep.0.stepgen.NN`, named as hostmot2 names them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepgenCommand {
    /// `position-cmd`, machine units.
    pub position_cmd: f64,
    /// `position-scale`, steps per machine unit.
    pub position_scale: f64,
    /// `maxvel`, machine units per second; 0: the rated step rate of the drive timing.
    pub maxvel: f64,
    /// `maxaccel`, machine units per second squared; 0: no limit (LinuxCNC's planner
    /// keeps the joint's). A command that would need more (a jump) is approached at it,
    /// braking in time not to pass the command, the rest carried ([`StepgenFeedback::limited`]).
    pub maxaccel: f64,
    /// `enable`.
    pub enable: bool,
    /// `steplen`, `stepspace`, `dirsetup`, `dirhold` in ns.
    pub timing_ns: [u32; 4],
    /// `step_type`: 0 step/dir, 1 up/down, 2 quadrature (hostmot2's numbering).
    pub step_type: u32,
}

impl Default for StepgenCommand {
    /// At 0, scale 1, disabled, hostmot2's default-ish timing (2 us pulses, 5 us
    /// direction set-up and hold), step/dir.
    fn default() -> Self {
        StepgenCommand {
            position_cmd: 0.0,
            position_scale: 1.0,
            maxvel: 0.0,
            maxaccel: 0.0,
            enable: false,
            timing_ns: [2000, 2000, 5000, 5000],
            step_type: 0,
        }
    }
}

/// What LinuxCNC sets for one encoder channel: `finestep.0.encoder.NN`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EncoderCommand {
    /// `scale`, counts per machine unit.
    pub scale: f64,
    /// `reset`: while true, `count` reads 0.
    pub reset: bool,
    /// `counter-mode`: false quadrature x4, true step/dir (count on A, direction on B).
    pub counter_mode: bool,
    /// `filter`: true 15 samples, false 3.
    pub filter: bool,
    /// `index-enable` as LinuxCNC leaves it: true asks for `count` to be zeroed at the
    /// next index pulse (homing to an index); the driver clears it when the index came
    /// ([`EncoderFeedback::index_enable`]), as hostmot2's encoder does.
    pub index_enable: bool,
}

impl Default for EncoderCommand {
    fn default() -> Self {
        EncoderCommand { scale: 1.0, reset: false, counter_mode: false, filter: true, index_enable: false }
    }
}

/// What a read gives for one step generator.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct StepgenFeedback {
    /// `counts`: the chip's step position (wraps as an s32).
    pub counts: i32,
    /// `position-fb`: the step position in machine units (unwrapped).
    pub position_fb: f64,
    /// `velocity-fb`: machine units per second over the last period.
    pub velocity_fb: f64,
    /// Periods whose increment was clamped to the rated rate, `maxvel` or `maxaccel`.
    pub limited: u32,
}

/// What a read gives for one encoder channel.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct EncoderFeedback {
    /// `count`, since the last reset.
    pub count: i32,
    /// `position`: `count / scale`.
    pub position: f64,
    /// `velocity`: machine units per second over the last period.
    pub velocity: f64,
    /// `index-enable` after the read: what the command asked, false once the index came
    /// (`count` is then 0 at the index pulse).
    pub index_enable: bool,
}

/// The chip's state for the HAL component's status pins.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct ChipStatus {
    /// The E-stop input is released (`finestep.0.estop-ok`, for iocontrol's emc-enable-in).
    pub estop_ok: bool,
    /// The watchdog bit (`finestep.0.watchdog.has_bit`).
    pub watchdog_bit: bool,
    /// The driver is running records (enabled, no fault).
    pub running: bool,
    /// `STATUS[7:0]` with the last frame.
    pub status: u8,
}

#[derive(Clone, Copy, Debug, Default)]
struct AxisState {
    /// Commanded position sent so far, I16F16 steps.
    sent: i64,
    /// The step position, unwrapped.
    steps: i64,
    last_raw: i32,
    velocity: f64,
    limited: u32,
    /// The last increment sent, I16F16 steps a period (`maxaccel`'s reference).
    last_inc: i64,
}

#[derive(Clone, Copy, Debug, Default)]
struct EncoderState {
    /// The count extended to 64 bits by the host driver ([`finestep_host::FeedbackSnapshot::positions`]:
    /// also a core's narrow 16-bit counts, `VERSION.ENC_COUNT_16`).
    counts: i64,
    zero: i64,
    velocity: f64,
    applied: Option<(bool, bool)>,
    /// The chip's index latch is armed for `index-enable` (ENC_CONTROL.ARM_INDEX_LATCH):
    /// also `index-enable` as the last read leaves it.
    index_armed: bool,
}

/// The commanded position `units * scale` in I16F16 steps, rounded half up (the
/// quantisation every write uses); `None` when it is no position.
pub fn command_fixed(units: f64, scale: f64) -> Option<i64> {
    round_fixed(units * scale * 65536.0)
}

/// `scaled` (a position in units of 2^-16 steps: `units * scale * 65536`, which a HAL
/// `scale` component with gain `scale * 65536` computes bit for bit, the factor being a
/// power of two) rounded half up to a whole I16F16 value, as [`command_fixed`] does.
pub fn round_fixed(scaled: f64) -> Option<i64> {
    let fixed = (scaled + 0.5).floor();
    (fixed.is_finite() && fixed.abs() < 2f64.powi(62)).then_some(fixed as i64)
}

/// The whole step the chip stands on after a position of `fixed` I16F16 steps: rounded
/// half up, as the DDA rounds (docs/spec/dda_axis.md).
pub fn quantised_steps(fixed: i64) -> i64 {
    (fixed + 32768).div_euclid(65536)
}

/// hostmot2's `step_type` 0, 1, 2 are the chip's OUT_MODE values (step/dir, up/down,
/// quadrature); hostmot2's table modes have no counterpart.
/// The increment toward `want` (I16F16 steps still to go) after `last` (the last
/// period's increment) under an acceleration of `accel` I16F16 steps a period squared
/// (at least 1 LSB) and the rate limit `max`: as close to `want` as the change from `last`
/// allows, and no faster than one from which a stop at `accel` stays within the distance
/// left (the increments v, v - a, v - 2a, ... down to 0 add up to at most |want|), so the
/// command is approached without passing it.
pub fn accel_limited(want: i64, last: i64, accel: f64, max: i64) -> i64 {
    let accel = accel.max(1.0);
    let left = want.unsigned_abs() as f64;
    // v + (v - a) + ... + (v - m a) with m = floor(v / a): increasing in v.
    let stop = |v: f64| {
        let m = (v / accel).floor();
        (m + 1.0) * v - accel * m * (m + 1.0) / 2.0
    };
    let (mut fits, mut over) = (0.0, left + 1.0);
    while over - fits > 1.0 {
        let mid = ((fits + over) / 2.0).floor();
        if stop(mid) <= left {
            fits = mid;
        } else {
            over = mid;
        }
    }
    let toward = want.signum() as f64 * fits;
    let (lo, hi) = ((last as f64 - accel).ceil(), (last as f64 + accel).floor());
    (toward.clamp(lo, hi) as i64).clamp(-max, max)
}

/// The chip's setting of an encoder channel for LinuxCNC's `counter-mode` and `filter`
/// (the index active high).
fn encoder_setup(cmd: &EncoderCommand) -> EncoderSetup {
    EncoderSetup {
        mode: if cmd.counter_mode { CountMode::StepDir } else { CountMode::X4 },
        z_active_high: true,
        filter: if cmd.filter { 15 } else { 3 },
    }
}

fn out_mode(step_type: u32) -> Option<OutMode> {
    OutMode::ALL.into_iter().find(|mode| u32::from(mode.bits()) == step_type)
}

/// The `finestep` HAL driver on one chip.
pub struct Driver {
    machine: Machine<SpiBus<Box<dyn SpiTransfer>>>,
    target: String,
    paced: bool,
    start_level: u16,
    axes: Vec<AxisState>,
    encoders: Vec<EncoderState>,
    stepgens: Vec<StepgenCommand>,
    encoder_cmds: Vec<EncoderCommand>,
    /// Timing and step type taken at the start, per axis.
    applied: Vec<(DriveTiming, OutMode)>,
    rate: Option<RateChecker>,
    running: bool,
    wanted: bool,
    period_clocks: u32,
    enabled_mask: u32,
    watchdog_bit: bool,
    read_once: bool,
    records: u64,
    /// Reads that found POSITION holding a probe snapshot (ONE_SNAPSHOT).
    held_reads: u64,
    /// Such reads since the last live one.
    held_since_live: u32,
    /// A live step position was read (the unwrapping's base).
    steps_once: bool,
    /// The hand wheel's count (edges) and detents at the last read (0 without one).
    wheel: (i32, i32),
}

impl Driver {
    /// Opens `bus` (`spidev:/dev/spidevB.C[@SCK_HZ]` or `sim:SOCKET`) and checks the
    /// chip's identity, map version and CAPS.
    pub fn open(bus: &str) -> Result<Driver, HalError> {
        let transport: Transport = bus.parse()?;
        let open_err = |source| HalError::Open { target: bus.to_string(), source };
        let (link, paced): (Box<dyn SpiTransfer>, bool) = match &transport {
            Transport::Sim(socket) => {
                let link = finestep_host::sim_link::SimSocket::connect(socket).map_err(|e| open_err(e.into()))?;
                (Box::new(link), true)
            }
            #[cfg(all(target_os = "linux", feature = "spidev"))]
            Transport::Spidev { path, sck_hz } => {
                let text = path.to_string_lossy();
                let spi = finestep_host::spidev::Spidev::open(&text, *sck_hz, TopParams::default().clock_hz)
                    .map_err(open_err)?;
                (Box::new(spi), false)
            }
            #[cfg(not(all(target_os = "linux", feature = "spidev")))]
            Transport::Spidev { .. } => {
                return Err(HalError::BadBus { bus: bus.to_string(), why: "spidev is not built in".into() })
            }
        };
        let driver = Driver::connect(link, paced, bus)?;
        if let Transport::Spidev { sck_hz, .. } = transport {
            finestep_host::spi::check_sck(sck_hz, driver.machine.caps().clock_hz).map_err(open_err)?;
        }
        Ok(driver)
    }

    /// The driver on `link`, named `target` in messages; `paced`: the link is a
    /// simulated chip whose time the driver advances (one core period per write).
    pub fn connect(link: Box<dyn SpiTransfer>, paced: bool, target: &str) -> Result<Driver, HalError> {
        let open_err = |source| HalError::Open { target: target.to_string(), source };
        let mut machine = Machine::connect(SpiBus::new(link, 1)).map_err(open_err)?;
        let caps = machine.caps();
        machine.bus().set_n_axes(caps.n_axes);
        Ok(Driver {
            machine,
            target: target.to_string(),
            paced,
            start_level: if paced { 1 } else { BOARD_START_LEVEL },
            axes: vec![AxisState::default(); caps.n_axes],
            encoders: vec![EncoderState::default(); caps.n_enc],
            stepgens: vec![StepgenCommand::default(); caps.n_axes],
            encoder_cmds: vec![EncoderCommand::default(); caps.n_enc],
            applied: Vec::new(),
            rate: None,
            running: false,
            wanted: false,
            period_clocks: 0,
            enabled_mask: 0,
            watchdog_bit: false,
            read_once: false,
            records: 0,
            held_reads: 0,
            held_since_live: 0,
            steps_once: false,
            wheel: (0, 0),
        })
    }

    /// Step generators (`CAPS.N_AXES`).
    pub fn n_axes(&self) -> usize {
        self.axes.len()
    }

    /// Encoder channels (`CAPS.N_ENC`).
    pub fn n_enc(&self) -> usize {
        self.encoders.len()
    }

    /// The core clock, Hz.
    pub fn clock_hz(&self) -> u32 {
        self.machine.caps().clock_hz
    }

    /// Whether the driver advances a simulated chip's time.
    pub fn paced(&self) -> bool {
        self.paced
    }

    /// The transport, e.g. to drive a simulated chip's E-stop input.
    pub fn link_mut(&mut self) -> &mut dyn SpiTransfer {
        self.machine.bus().link_mut().as_mut()
    }

    /// Records queued since the driver opened.
    pub fn records(&self) -> u64 {
        self.records
    }

    /// Reads that found `POSITION` holding a probe snapshot (a `VERSION.ONE_SNAPSHOT`
    /// chip) and held the step feedback instead ([`Driver::read`]).
    pub fn held_reads(&self) -> u64 {
        self.held_reads
    }

    fn bus_err(&self) -> impl Fn(BusError) -> HalError + '_ {
        move |source| HalError::Bus { target: self.target.clone(), source }
    }

    /// Sets what LinuxCNC commands for axis `axis` (taken by the next write).
    pub fn set_stepgen(&mut self, axis: usize, cmd: StepgenCommand) -> Result<(), HalError> {
        let count = self.stepgens.len();
        let slot = self.stepgens.get_mut(axis).ok_or(HalError::NoSuch { what: "stepgen", index: axis, count })?;
        *slot = cmd;
        Ok(())
    }

    /// Sets encoder channel `channel`'s parameters (taken by the next read).
    pub fn set_encoder(&mut self, channel: usize, cmd: EncoderCommand) -> Result<(), HalError> {
        let count = self.encoder_cmds.len();
        let slot =
            self.encoder_cmds.get_mut(channel).ok_or(HalError::NoSuch { what: "encoder", index: channel, count })?;
        *slot = cmd;
        Ok(())
    }

    /// One coherent latched read of every step position and encoder count (the
    /// `finestep.0.read` function), with `period_ns` the servo period.
    ///
    /// On a chip with one position snapshot (`VERSION.ONE_SNAPSHOT`, the MAX II) whose
    /// probe has latched (`PROBE_STATUS.SEEN`), `POSITION` is the probe event's, not live:
    /// this read then leaves the step feedback as the last live read gave it (position
    /// and velocity held, [`Driver::held_reads`] counts it) and releases the snapshot
    /// (`PROBE_CONTROL.ARM`), so that the next period boundary's latch is live again; the
    /// next live read takes the steps of the whole time since the last live one (the
    /// positions are totals: nothing is lost) and its velocity over that time. The
    /// encoder counts are live either way (the period latch copies them while `SEEN`).
    pub fn read(&mut self, period_ns: i64) -> Result<(), HalError> {
        self.apply_encoder_setup()?;
        let snapshot = self.machine.feedback().map_err(self.bus_err())?;
        let dt = period_ns as f64 * 1e-9;
        if snapshot.probe_held {
            self.machine.release_probe_snapshot().map_err(self.bus_err())?;
            self.held_reads += 1;
            self.held_since_live += 1;
        } else {
            let elapsed = dt * (1 + self.held_since_live) as f64;
            self.held_since_live = 0;
            for (axis, &raw) in self.axes.iter_mut().zip(&snapshot.steps) {
                let delta = if self.steps_once { i64::from(raw.wrapping_sub(axis.last_raw)) } else { 0 };
                if !self.steps_once {
                    axis.steps = i64::from(raw);
                } else {
                    axis.steps += delta;
                }
                axis.last_raw = raw;
                axis.velocity = if elapsed > 0.0 { delta as f64 / elapsed } else { 0.0 };
            }
            self.steps_once = true;
        }
        for ((channel, &position), cmd) in self.encoders.iter_mut().zip(&snapshot.positions).zip(&self.encoder_cmds) {
            let delta = if self.read_once { position - channel.counts } else { 0 };
            channel.counts = position;
            if !self.read_once {
                channel.zero = channel.counts;
            }
            if cmd.reset {
                channel.zero = channel.counts;
            }
            channel.velocity = if dt > 0.0 { delta as f64 / dt } else { 0.0 };
        }
        self.index_enables()?;
        if self.machine.caps().has_mpg {
            let wheel = self.machine.hand_wheel().map_err(self.bus_err())?;
            self.wheel = (wheel.edges, wheel.detents);
        }
        self.read_once = true;
        self.note_status();
        Ok(())
    }

    /// The hand wheel (MPG) at the last read: its count in quadrature edges and in
    /// detents (`MPG_COUNT`, `MPG_DETENTS`); both 0 on a chip without one.
    pub fn hand_wheel(&self) -> (i32, i32) {
        self.wheel
    }

    /// Turns a simulated chip's hand wheel by `edges` quadrature edges (4 a detent),
    /// one edge every [`finestep_host::pins::WHEEL_EDGE_CLOCKS`] while its time passes;
    /// `false` on a board (the operator turns the wheel).
    pub fn turn_wheel(&mut self, edges: i64) -> Result<bool, HalError> {
        self.machine.bus().link_mut().turn_wheel(edges).map_err(self.bus_err())
    }

    /// `index-enable` of every channel, after the read's snapshot: a channel asked for
    /// arms the chip's index latch (the next index pulse latches the count and sets
    /// INDEX_SEEN); at a later read that finds INDEX_SEEN, `count` is re-zeroed at the
    /// latched count and `index-enable` cleared. The chip's count itself is never
    /// cleared (ARM_INDEX_CLEAR is not used), so the unwrapped count, the velocity and a
    /// `reset` stay continuous. A request withdrawn before the index disarms nothing on
    /// the chip: its latch is re-armed (INDEX_SEEN cleared) by the next request.
    fn index_enables(&mut self) -> Result<(), HalError> {
        for channel in 0..self.encoders.len() {
            let cmd = self.encoder_cmds[channel];
            if !cmd.index_enable {
                self.encoders[channel].index_armed = false;
                continue;
            }
            if !self.encoders[channel].index_armed {
                let setup = encoder_setup(&cmd);
                self.machine.arm_index(channel, &setup, true, false).map_err(self.bus_err())?;
                self.encoders[channel].index_armed = true;
                continue;
            }
            if let Some(latched) = self.machine.index_position(channel).map_err(self.bus_err())? {
                let state = &mut self.encoders[channel];
                // The latched count, extended by its distance from the snapshot's count
                // (after it when the index came after the snapshot's latch).
                state.zero = latched;
                state.index_armed = false;
            }
        }
        Ok(())
    }

    fn apply_encoder_setup(&mut self) -> Result<(), HalError> {
        for channel in 0..self.encoders.len() {
            let cmd = self.encoder_cmds[channel];
            let want = (cmd.counter_mode, cmd.filter);
            if self.encoders[channel].applied != Some(want) {
                let setup = encoder_setup(&cmd);
                self.machine.configure_encoder(channel, &setup).map_err(self.bus_err())?;
                self.encoders[channel].applied = Some(want);
            }
        }
        Ok(())
    }

    /// What the last read gave for axis `axis`.
    pub fn stepgen_feedback(&self, axis: usize) -> Option<StepgenFeedback> {
        let state = self.axes.get(axis)?;
        let scale = self.stepgens[axis].position_scale;
        let scale = if scale != 0.0 { scale } else { 1.0 };
        Some(StepgenFeedback {
            counts: state.steps as i32,
            position_fb: state.steps as f64 / scale,
            velocity_fb: state.velocity / scale,
            limited: state.limited,
        })
    }

    /// What the last read gave for encoder channel `channel`.
    pub fn encoder_feedback(&self, channel: usize) -> Option<EncoderFeedback> {
        let state = self.encoders.get(channel)?;
        let scale = self.encoder_cmds[channel].scale;
        let scale = if scale != 0.0 { scale } else { 1.0 };
        let count = state.counts - state.zero;
        Some(EncoderFeedback {
            count: count as i32,
            position: count as f64 / scale,
            velocity: state.velocity / scale,
            index_enable: state.index_armed,
        })
    }

    /// The status pins.
    pub fn status(&self) -> ChipStatus {
        let byte = self.machine.bus_ref().last_status();
        ChipStatus {
            estop_ok: status::ESTOP_ACTIVE.get(u32::from(byte)) == 0,
            watchdog_bit: self.watchdog_bit,
            running: self.running,
            status: byte,
        }
    }

    /// Lets the HAL user re-arm the watchdog bit (hostmot2's `has_bit` is cleared by
    /// writing false); the chip's fault is cleared at the next start.
    pub fn clear_watchdog_bit(&mut self) {
        self.watchdog_bit = false;
    }

    fn note_status(&mut self) {
        let byte = u32::from(self.machine.bus_ref().last_status());
        if status::FAULT_WATCHDOG.get(byte) != 0 && self.running {
            self.watchdog_bit = true;
        }
    }

    /// The `finestep.0.write` function: with `enable` (iocontrol's user-enable-out)
    /// and some stepgen enabled the driver runs: the first such write configures the
    /// chip (period from `period_ns`, drive timing, watchdog of `watchdog_timeout_ns`,
    /// 0 for none), clears its faults and starts it; every write while running queues
    /// one record. On a simulated chip it then advances the chip to just past the next
    /// period boundary.
    pub fn write(
        &mut self,
        period_ns: i64,
        enable: bool,
        watchdog_timeout_ns: u32,
        stepgens: &[StepgenCommand],
    ) -> Result<(), HalError> {
        for (axis, cmd) in stepgens.iter().enumerate() {
            self.set_stepgen(axis, *cmd)?;
        }
        self.write_set(period_ns, enable, watchdog_timeout_ns)
    }

    /// [`Driver::write`] with the commands given by [`Driver::set_stepgen`].
    pub fn write_set(&mut self, period_ns: i64, enable: bool, watchdog_timeout_ns: u32) -> Result<(), HalError> {
        let mask = self.stepgens.iter().enumerate().fold(0u32, |m, (i, s)| m | (u32::from(s.enable) << i));
        let wanted = enable && mask != 0;
        let mut result = Ok(());
        if wanted && !self.wanted {
            self.start(period_ns, watchdog_timeout_ns)?;
        } else if !wanted && self.wanted {
            self.stop()?;
        }
        self.wanted = wanted;
        if self.running {
            result = self.queue(mask);
            if result.is_err() {
                // Stop feeding: the chip holds, LinuxCNC sees the following error.
                self.running = false;
            }
        }
        if self.paced {
            self.pace()?;
        }
        result
    }

    fn period_from_ns(&self, period_ns: i64) -> Result<u32, HalError> {
        let caps = self.machine.caps();
        let clocks = ((period_ns as f64) * f64::from(caps.clock_hz) * 1e-9).round() as i64;
        let max = caps.period_max();
        if !(1..=i64::from(max)).contains(&clocks) {
            return Err(HalError::Period { period_ns, clocks, clock_hz: caps.clock_hz, max });
        }
        // Checked here, before start() stops and configures the chip.
        let slots = caps.step_slots;
        if clocks % i64::from(slots) != 0 {
            return Err(HalError::PeriodSlots { period_ns, clocks, clock_hz: caps.clock_hz, slots });
        }
        Ok(clocks as u32)
    }

    fn timings(&self) -> Result<Vec<(DriveTiming, OutMode)>, HalError> {
        let caps = self.machine.caps();
        self.stepgens
            .iter()
            .enumerate()
            .map(|(axis, cmd)| {
                let ns = cmd.timing_ns.map(f64::from);
                let timing = DriveTiming::from_ns(ns, f64::from(caps.clock_hz), caps.timing_max())
                    .map_err(|source| HalError::Timing { axis, source })?;
                let mode = out_mode(cmd.step_type).ok_or(HalError::StepType { axis, step_type: cmd.step_type })?;
                Ok((timing, mode))
            })
            .collect()
    }

    fn start(&mut self, period_ns: i64, watchdog_timeout_ns: u32) -> Result<(), HalError> {
        let period_clocks = self.period_from_ns(period_ns)?;
        let timings = self.timings()?;
        let err = |source| HalError::Bus { target: self.target.clone(), source };
        let m = &mut self.machine;
        m.set_control(false, false, true).map_err(err)?;
        m.command(command::FLUSH_FIFO.set(0, 1)).map_err(err)?;
        for (axis, (timing, mode)) in timings.iter().enumerate() {
            m.configure_axis(axis, &AxisSetup { timing: *timing, out_mode: *mode, invert: 0 }).map_err(err)?;
        }
        m.set_period(period_clocks).map_err(err)?;
        m.set_start_level(self.start_level).map_err(err)?;
        let clock_hz = u64::from(m.caps().clock_hz);
        let wd_clocks = (u64::from(watchdog_timeout_ns) * clock_hz).div_ceil(1_000_000_000);
        let wd_clocks = wd_clocks.clamp(1, u64::from(watchdog_timeout::CLOCKS.max())) as u32;
        m.bus().write(watchdog_timeout::ADDR, watchdog_timeout::CLOCKS.set(0, wd_clocks)).map_err(err)?;
        m.clear_faults_and_errors().map_err(err)?;
        // A probe snapshot held in POSITION (ONE_SNAPSHOT) goes back to the latch first,
        // which follows every clock while stopped: the resynchronisation reads live steps.
        if m.probe_holds_positions().map_err(err)? {
            m.release_probe_snapshot().map_err(err)?;
        }
        let positions = m.positions().map_err(err)?;
        for (axis, &steps) in self.axes.iter_mut().zip(&positions.steps) {
            // Resynchronise on the chip (after a fault it dropped its pending steps).
            axis.sent = i64::from(steps) << 16;
            axis.last_inc = 0;
        }
        let mask = self.stepgens.iter().enumerate().fold(0u32, |m, (i, s)| m | (u32::from(s.enable) << i));
        m.enable_axes(mask).map_err(err)?;
        m.set_control(true, watchdog_timeout_ns > 0, true).map_err(err)?;
        self.enabled_mask = mask;
        let timings_clocks: Vec<_> = timings.iter().map(|t| t.0).collect();
        self.rate = Some(RateChecker::with_slots(period_clocks, &timings_clocks, self.machine.caps().step_slots));
        self.applied = timings;
        self.period_clocks = period_clocks;
        self.running = true;
        if status::HALT.get(u32::from(self.machine.bus_ref().last_status())) != 0 {
            self.running = false;
            return Err(self.stopped());
        }
        Ok(())
    }

    fn stop(&mut self) -> Result<(), HalError> {
        let err = |source| HalError::Bus { target: self.target.clone(), source };
        self.machine.set_control(false, false, true).map_err(err)?;
        self.machine.enable_axes(0).map_err(err)?;
        self.running = false;
        self.enabled_mask = 0;
        Ok(())
    }

    fn stopped(&self) -> HalError {
        let byte = self.machine.bus_ref().last_status();
        let word = u32::from(byte);
        let why = if status::FAULT_ESTOP.get(word) != 0 {
            "E-stop"
        } else if status::FAULT_WATCHDOG.get(word) != 0 {
            "watchdog"
        } else if status::UNDERRUN.get(word) != 0 {
            "FIFO underrun: a write came late"
        } else if status::OVERFLOW.get(word) != 0 {
            "FIFO overflow"
        } else {
            "halted"
        };
        HalError::Stopped { status: byte, why }
    }

    /// Builds this period's record from the commands and queues it.
    fn queue(&mut self, mask: u32) -> Result<(), HalError> {
        let timings = self.timings()?;
        if let Some(axis) = (0..timings.len()).find(|&a| timings[a] != self.applied[a]) {
            return Err(HalError::ChangedWhileRunning { axis });
        }
        if mask != self.enabled_mask {
            self.machine.enable_axes(mask).map_err(self.bus_err())?;
            self.enabled_mask = mask;
        }
        let period_s = f64::from(self.period_clocks) / f64::from(self.machine.caps().clock_hz);
        let mut record = PeriodRecord::from_raw(&[], 0);
        let slots = self.machine.caps().step_slots;
        let Some(rate) = self.rate.as_mut() else { return Ok(()) };
        for (axis, (state, cmd)) in self.axes.iter_mut().zip(&self.stepgens).enumerate() {
            if !cmd.enable {
                continue;
            }
            let target = command_fixed(cmd.position_cmd, cmd.position_scale).ok_or(HalError::BadCommand {
                axis,
                position: cmd.position_cmd,
                scale: cmd.position_scale,
            })?;
            let want = target - state.sent;
            let sign = if want < 0 { -1 } else { 1 };
            let mut max = i64::from(rate.max_increment(axis, sign).to_bits());
            if cmd.maxvel > 0.0 {
                let by_maxvel = (cmd.maxvel * cmd.position_scale.abs() * period_s * 65536.0).floor();
                max = max.min(by_maxvel.max(0.0) as i64);
            }
            let mut d = want.clamp(-max, max);
            if cmd.maxaccel > 0.0 {
                let per_period = cmd.maxaccel * cmd.position_scale.abs() * period_s * period_s * 65536.0;
                d = accel_limited(want, state.last_inc, per_period, max);
            }
            if d != want {
                state.limited = state.limited.wrapping_add(1);
            } else {
                // The last step of the period is requested early enough for the
                // boundary's latch to count it (the whole step is the command's).
                let latency = count_latency_clocks(&self.applied[axis].0, slots);
                d = settled_increment(state.sent, d, self.period_clocks, latency, slots, max);
            }
            record.inc[axis] = Increment::from_bits(d as i32);
            state.last_inc = d;
        }
        // The clamp above keeps every increment within the rated maximum; the check is
        // the rate module's own, so a record the core would flag never goes out.
        rate.check(&record).map_err(|(axis, source)| HalError::Rate { axis, source })?;
        for (state, inc) in self.axes.iter_mut().zip(&record.inc) {
            state.sent += i64::from(inc.to_bits());
        }
        self.machine.bus().push_records(&[record]).map_err(self.bus_err())?;
        self.records += 1;
        let byte = u32::from(self.machine.bus_ref().last_status());
        if status::HALT.get(byte) != 0 || status::UNDERRUN.get(byte) != 0 || status::RUNNING.get(byte) == 0 {
            self.note_status();
            return Err(self.stopped());
        }
        Ok(())
    }

    /// Advances a simulated chip to [`PACE_MARGIN_CLOCKS`] past the next period
    /// boundary (one core period per servo period), or one period when not running.
    fn pace(&mut self) -> Result<(), HalError> {
        let period = u64::from(if self.period_clocks > 0 { self.period_clocks } else { 1 });
        let mut words = [0u32; 2];
        debug_assert_eq!(latch_time::ADDR, timestamp::ADDR + 1);
        self.machine.bus().read(timestamp::ADDR, &mut words).map_err(self.bus_err())?;
        let [now, latch] = words;
        let wait = if self.running {
            // Signed: a cycle whose frames ran past the target waits nothing.
            let target = latch.wrapping_add(period as u32).wrapping_add(PACE_MARGIN_CLOCKS);
            u64::try_from(target.wrapping_sub(now) as i32).unwrap_or(0)
        } else {
            period
        };
        self.machine.bus().wait(wait).map_err(self.bus_err())
    }
}

#[cfg(test)]
mod tests;

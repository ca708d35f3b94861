//! Machine configuration: axes, limits, period, clock, drive timing and tolerances,
//! read from a TOML file. Every key has a default, so an empty file (or none) gives a
//! machine that runs `tests/programs/`.
//!
//! ```toml
//! period_ms = 1.0               # interpolation period T
//! clock_hz = 50_000_000         # FPGA clock: the core's when absent, checked against it
//! profile = "trapezoid"         # or "s-curve"
//! path_tolerance_mm = 0.01      # G64 without P
//! chord_tolerance_mm = 0.001    # arcs: largest chord-to-circle distance
//! lookahead_moves = 2000        # every move is planned seeing at least this many ahead
//! parameter_file = "sim.var"    # LinuxCNC's parameter file: read before a program, the
//!                               # persistent parameters written back at its end (none)
//! ini_file = "sim.ini"          # LinuxCNC's INI file, for #<_ini[section]name> (none)
//! user_m_path = ["mcodes"]      # folders of the user M-code programs M100-M199 (none)
//! cutter_comp_entry = "tangent" # G41/G42 entry and G40 exit moves: "tangent" lines, or
//!                               # "linuxcnc" (LinuxCNC's, which can cut into the part;
//!                               # with its nearly tangent corners and corners at rapid)
//!
//! [drive]                       # step/dir timing of every axis, ns
//! step_len_ns = 2000
//! step_space_ns = 2000
//! dir_setup_ns = 5000
//! dir_hold_ns = 5000
//!
//! [spindle]                     # S, M3/M4/M5 (docs/spec/spindle.md)
//! max_rpm = 24000.0             # S at full level; a larger S is refused (file:line)
//! period_clocks = 1000          # PWM period / DAC frame interval, clocks
//! ramp_step = 0                 # most the level moves per period (0: no ramp)
//! dac = false                   # the SPI DAC instead of the PWM pin
//!
//! [gantry]                      # seed 001's gantry pair (docs/spec/gantry_sync.md)
//! enabled = false               # true: the slave axis follows the master's steps
//! master = "X"                  # the axis the program moves
//! slave = "A"                   # the second motor of that axis (the program must not move it)
//! enc_master = 0                # encoder channels on the two sides (0..=3, different)
//! enc_slave = 1
//! sync = true                   # corrections from the encoders (false: forward only)
//! tick_us = 100.0               # a correction decided at most every tick
//! deadband_counts = 2           # no correction while |error| <= deadband
//! limit_counts = 100            # the alarm (which halts the machine) past it
//!
//! [interpolation]               # G1/G2/G3 in one plane (docs/host.md, "Interpolation")
//! mode = "dda"                  # or "pbp": point-by-point records on a chip pair (HAS_PBP)
//! plane = "XY"                  # the plane's axes: the first on chip axis 2 * pair,
//! pair = 0                      # the second on 2 * pair + 1 (e.g. "XZ" for a lathe)
//! max_decision_hz = 10000.0     # pbp: the highest step rate the drives start at unramped
//!
//! [axes.X]                      # X, Y, Z (mm) and A (degrees); a listed [axes] table
//! steps_per_unit = 800.0        # replaces the default axes, missing keys take defaults
//! max_velocity = 100.0          # units/s
//! max_acceleration = 1000.0     # units/s^2
//! max_jerk = 100000.0           # units/s^3 (S-curve profile only)
//! ```
//!
//! A configuration is resolved against the core it will run on ([`CoreLimits`]: the
//! clock, `CAPS.P_WIDTH`, `CAPS.TIMING_W`, `CAPS.N_AXES` as read from the chip, or the
//! default build's when no chip is attached): the period in clocks, the drive timing and
//! the axes must fit that core, and a `clock_hz` given in the file must be its clock.

use std::collections::BTreeMap;
use std::path::Path;

use finestep_interface::rate::{forward_interval_in, reversal_interval_in};
use finestep_interface::{DriveTiming, TopParams};
use serde::Deserialize;

/// The axis names the planner knows, in record slot order.
pub const AXIS_NAMES: [&str; 4] = ["X", "Y", "Z", "A"];

/// Which feed profile along the path.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Default)]
pub enum ProfileKind {
    /// Constant acceleration phases (unbounded jerk): the default, as in grbl and
    /// LinuxCNC.
    #[default]
    #[serde(rename = "trapezoid")]
    Trapezoid,
    /// Jerk-limited: every speed change is a 7-segment-style S-curve half (jerk up,
    /// constant acceleration, jerk down), acceleration and deceleration planned separately.
    /// The jerk limit also holds where the path's curvature jumps (a line meeting an arc
    /// or a corner blend), which caps the speed there at about `sqrt(0.25 J T R)`
    /// (up to `sqrt(0.7 J T R)` beside lines and short elements, which take less of the
    /// jerk for themselves).
    #[serde(rename = "s-curve")]
    SCurve,
}

/// Limits and scale of one axis.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct AxisLimits {
    /// Steps per unit (mm, or degree for A).
    pub steps_per_unit: f64,
    /// Largest speed, units/s (capped by the drive's rated step rate).
    pub max_velocity: f64,
    /// Largest acceleration, units/s^2.
    pub max_acceleration: f64,
    /// Largest jerk, units/s^3 (used by the S-curve profile).
    pub max_jerk: f64,
}

impl Default for AxisLimits {
    fn default() -> Self {
        AxisLimits { steps_per_unit: 800.0, max_velocity: 100.0, max_acceleration: 1000.0, max_jerk: 100_000.0 }
    }
}

/// Step/direction timing of the drives as the file gives it, ns; resolved to a
/// [`DriveTiming`] in whole clocks by [`DriveTiming::from_ns`].
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DriveTimingNs {
    /// Step pulse length.
    pub step_len_ns: f64,
    /// Least space between pulses.
    pub step_space_ns: f64,
    /// Direction set-up before a step.
    pub dir_setup_ns: f64,
    /// Direction hold after a step.
    pub dir_hold_ns: f64,
}

impl Default for DriveTimingNs {
    fn default() -> Self {
        DriveTimingNs { step_len_ns: 2000.0, step_space_ns: 2000.0, dir_setup_ns: 5000.0, dir_hold_ns: 5000.0 }
    }
}

impl DriveTimingNs {
    /// The values in the order of [`DriveTiming::FIELDS`].
    pub fn to_array(&self) -> [f64; DriveTiming::COUNT] {
        let DriveTimingNs { step_len_ns, step_space_ns, dir_setup_ns, dir_hold_ns } = *self;
        [step_len_ns, step_space_ns, dir_setup_ns, dir_hold_ns]
    }
}

/// The machine as the planner sees it. Build with [`MachineConfig::default`],
/// [`MachineConfig::from_toml_str`] or [`MachineConfig::load`]; the loaders validate.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MachineConfig {
    /// Interpolation period T, ms.
    pub period_ms: f64,
    /// FPGA clock, Hz: when absent, the core's ([`CoreLimits::clock_hz`]); when given, it
    /// must be the core's.
    pub clock_hz: Option<f64>,
    /// Feed profile.
    pub profile: ProfileKind,
    /// Path tolerance of G64 without P, mm.
    pub path_tolerance_mm: f64,
    /// Largest distance between an arc and its per-period chords, mm.
    pub chord_tolerance_mm: f64,
    /// Every move is planned seeing at least this many programmed moves ahead.
    pub lookahead_moves: usize,
    /// Drive timing, the same for every axis.
    pub drive: DriveTimingNs,
    /// Axes by name (X, Y, Z, A); absent axes must not move.
    pub axes: BTreeMap<String, AxisLimits>,
    /// The tool table: radii for cutter compensation (G41/G42 D, or the tool in the
    /// spindle).
    pub tools: Vec<ToolConfig>,
    /// The spindle: what S means and how the level reaches the drive.
    pub spindle: SpindleConfig,
    /// `finestep measure`'s traverse and gratings (seed 000's roller gauge).
    pub measure: MeasureConfig,
    /// The gantry pair: a slave axis following a master, corrected from two encoders.
    pub gantry: GantryConfig,
    /// How G1/G2/G3 are interpolated: the DDA's period records (the default) or the
    /// chip's point-by-point interpolator on an axis pair.
    pub interpolation: InterpolationConfig,
    /// The host link the `finestep` tools talk over (`lockstep`, `model`,
    /// `spidev:/dev/spidevB.C[@SCK_HZ]`, `sim:SOCKET`); `--bus` overrides it. The planner
    /// does not read it.
    pub bus: Option<String>,
    /// LinuxCNC's parameter file (its `[RS274NGC]PARAMETER_FILE`, e.g. `sim.var`):
    /// `finestep run` reads it before the program and writes the persistent parameters
    /// back, crash-safe, when the program has run to its end. A relative path is taken
    /// from the configuration file's folder. The planner does not read it.
    pub parameter_file: Option<std::path::PathBuf>,
    /// The machine's LinuxCNC INI file, read by `finestep run` for the program's
    /// `#<_ini[section]name>` parameters (`finestep_gcode::Options::ini`; without one they
    /// are not defined). A relative path is taken from the configuration file's folder.
    /// The planner does not read it.
    pub ini_file: Option<std::path::PathBuf>,
    /// Folders searched for user M-code programs M100-M199 (LinuxCNC's
    /// `[RS274NGC]USER_M_PATH`; `finestep_gcode::Options::user_m_path`), relative ones
    /// from the configuration file's folder. The planner does not read it.
    pub user_m_path: Vec<std::path::PathBuf>,
    /// How cutter compensation lays out the entry move after G41/G42 and the exit move
    /// after G40, and with `linuxcnc` its corners ([`crate::cutter_comp::EntryExit`]).
    pub cutter_comp_entry: crate::cutter_comp::EntryExit,
    /// The core the configuration is resolved against (not read from the file; see
    /// [`MachineConfig::for_core`]): the default build's unless set.
    #[serde(skip)]
    pub core: CoreLimits,
}

/// What the configuration must fit: the core's clock and the build parameters it reports
/// in `CAPS` (read from the chip), or those of the default build.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CoreLimits {
    /// The core clock, Hz (`CLOCK_HZ`).
    pub clock_hz: f64,
    /// Bits of the period counter (`CAPS.P_WIDTH`).
    pub p_width: u32,
    /// Bits of each drive timing counter (`CAPS.TIMING_W`).
    pub timing_w: u32,
    /// Step/dir axes (`CAPS.N_AXES`).
    pub n_axes: usize,
    /// The point-by-point interpolator is in the core (`VERSION.HAS_PBP`).
    pub has_pbp: bool,
    /// The step engine's round `R`, the clocks between two visits of an axis
    /// (`2^CAPS.STEP_ROUND_LOG2`: the step engine's slots `S`, `S * 32 / STEP_DIGIT` with
    /// the digit-serial engine, 1 without either): the period must be a multiple of `R`,
    /// and the rated rates are those of timings rounded up to multiples of `R`
    /// (docs/spec/rated_rate.md).
    pub step_slots: u32,
}

impl Default for CoreLimits {
    /// The default build (`finestep_top`'s defaults in `hdl/interface.toml`).
    fn default() -> Self {
        CoreLimits::of_build(&TopParams::default())
    }
}

impl CoreLimits {
    /// The limits of the build `params` (its `CLOCK_HZ`, `P_WIDTH`, `TIMING_W`, `N_AXES`
    /// and step slots).
    pub fn of_build(params: &TopParams) -> CoreLimits {
        CoreLimits {
            clock_hz: f64::from(params.clock_hz),
            p_width: params.p_width,
            timing_w: params.timing_w,
            n_axes: params.n_axes,
            has_pbp: params.has_pbp,
            step_slots: params.core_params().step_slots(),
        }
    }

    /// The longest period in clocks, `2^P_WIDTH - 1`.
    pub fn period_max(&self) -> u32 {
        ((1u64 << self.p_width.min(32)) - 1) as u32
    }

    /// The largest drive timing in clocks, `2^TIMING_W - 1`.
    pub fn timing_max(&self) -> u32 {
        ((1u64 << self.timing_w.min(32)) - 1) as u32
    }
}

/// The spindle's scale and output (`[spindle]`).
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SpindleConfig {
    /// The speed at full level, rev/min: S maps linearly to the level, `S / max_rpm` of
    /// full scale; an S above it (or negative) is refused at its line.
    pub max_rpm: f64,
    /// The PWM period (the DAC frame and ramp interval), clocks.
    pub period_clocks: u16,
    /// The most the level moves per period (0: no limit).
    pub ramp_step: u16,
    /// The 12-bit SPI DAC instead of the PWM pin.
    pub dac: bool,
    /// The DAC's SCK half-period minus one, clocks (0..=15).
    pub dac_div: u8,
}

impl Default for SpindleConfig {
    /// 24000 rev/min at full level, PWM of 1000 clocks (50 kHz at 50 MHz), no ramp.
    fn default() -> Self {
        SpindleConfig { max_rpm: 24_000.0, period_clocks: 1000, ramp_step: 0, dac: false, dac_div: 0 }
    }
}

/// The gantry pair (`[gantry]`, seed 001; docs/spec/gantry_sync.md): two motors on one
/// axis. The slave axis's shaper takes the master's step requests; in synchronised mode
/// a correction from the difference of two encoder channels inserts or deletes a slave
/// step at most once a tick; an error past the limit raises the alarm, which halts the
/// machine. The planner does not read it (`finestep run` writes it to the chip).
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GantryConfig {
    /// Engage the pair for a run (the chip must have CAPS.HAS_GANTRY).
    pub enabled: bool,
    /// The master axis's name (X, Y, Z, A): the one the program moves.
    pub master: String,
    /// The slave axis's name: it follows the master (a program must not move it).
    pub slave: String,
    /// The encoder channel on the master's side (0..=3).
    pub enc_master: u8,
    /// The encoder channel on the slave's side (0..=3, not the master's).
    pub enc_slave: u8,
    /// Synchronised (corrections) or forward only (the slave copies the master).
    pub sync: bool,
    /// The correction tick, us: rounded to the chip's `16 * TICK + 15` clocks.
    pub tick_us: f64,
    /// No correction while |error| <= this, encoder counts.
    pub deadband_counts: u16,
    /// The alarm (a halt) when |error| > this, encoder counts; above the deadband.
    pub limit_counts: u16,
}

impl Default for GantryConfig {
    /// Off; X with A as its slave, channels 0 and 1, synchronised, 100 us ticks, a
    /// deadband of 2 counts and a limit of 100.
    fn default() -> Self {
        GantryConfig {
            enabled: false,
            master: "X".into(),
            slave: "A".into(),
            enc_master: 0,
            enc_slave: 1,
            sync: true,
            tick_us: 100.0,
            deadband_counts: 2,
            limit_counts: 100,
        }
    }
}

/// `[gantry]` resolved: record slots, channels and the chip's register fields.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ResolvedGantry {
    /// The master's record slot.
    pub master: u8,
    /// The slave's record slot.
    pub slave: u8,
    /// The master side's encoder channel.
    pub enc_master: u8,
    /// The slave side's encoder channel.
    pub enc_slave: u8,
    /// Synchronised mode.
    pub sync: bool,
    /// `GANTRY_CONTROL.TICK`: a tick every `16 * tick + 15` clocks.
    pub tick: u16,
    /// Deadband, counts.
    pub deadband: u16,
    /// Alarm limit, counts.
    pub limit: u16,
}

/// The highest encoder channel `GANTRY_CONTROL.ENC_MASTER`/`ENC_SLAVE` can name.
const GANTRY_CHANNEL_MAX: u8 = 3;

impl GantryConfig {
    /// Validates the section against a core of `n_axes` axes at `clock_hz`; `None` when
    /// not enabled (the values are checked all the same, but the axes against the core
    /// only when enabled). Errors name `gantry.<key>`.
    pub fn resolve(&self, n_axes: usize, clock_hz: f64) -> Result<Option<ResolvedGantry>, (String, String)> {
        let slot = |key: &str, name: &str| -> Result<u8, (String, String)> {
            let fail = |reason: String| (format!("gantry.{key}"), reason);
            let slot = AXIS_NAMES
                .iter()
                .position(|n| *n == name)
                .ok_or_else(|| fail(format!("\"{name}\" is not an axis (X, Y, Z, A)")))?;
            if self.enabled && slot >= n_axes {
                return Err(fail(format!("{name} is axis {slot}, but the core has {n_axes} axes (CAPS.N_AXES)")));
            }
            Ok(slot as u8)
        };
        let master = slot("master", &self.master)?;
        let slave = slot("slave", &self.slave)?;
        if master == slave {
            return Err(("gantry.slave".into(), format!("{} is the master too", self.slave)));
        }
        for (key, channel) in [("enc_master", self.enc_master), ("enc_slave", self.enc_slave)] {
            if channel > GANTRY_CHANNEL_MAX {
                return Err((
                    format!("gantry.{key}"),
                    format!("channel {channel} is not within 0..={GANTRY_CHANNEL_MAX}"),
                ));
            }
        }
        if self.enc_master == self.enc_slave {
            return Err(("gantry.enc_slave".into(), format!("channel {} is the master's too", self.enc_slave)));
        }
        if !(self.tick_us.is_finite() && self.tick_us > 0.0) {
            return Err(("gantry.tick_us".into(), format!("must be a positive finite time, got {}", self.tick_us)));
        }
        let clocks = (self.tick_us * 1e-6 * clock_hz).round();
        let tick = ((clocks - 15.0) / 16.0).round();
        if !(0.0..=f64::from(u16::MAX)).contains(&tick) {
            return Err((
                "gantry.tick_us".into(),
                format!(
                    "{} us is {clocks} clocks at {} MHz, outside the chip's 15..={} (16 * GANTRY_CONTROL.TICK + 15)",
                    self.tick_us,
                    clock_hz / 1e6,
                    16 * u32::from(u16::MAX) + 15
                ),
            ));
        }
        if self.limit_counts <= self.deadband_counts {
            return Err((
                "gantry.limit_counts".into(),
                format!(
                    "{} counts must exceed deadband_counts ({}): the alarm would come before any correction",
                    self.limit_counts, self.deadband_counts
                ),
            ));
        }
        Ok(self.enabled.then_some(ResolvedGantry {
            master,
            slave,
            enc_master: self.enc_master,
            enc_slave: self.enc_slave,
            sync: self.sync,
            tick: tick as u16,
            deadband: self.deadband_counts,
            limit: self.limit_counts,
        }))
    }
}

/// Which interpolation runs G1/G2/G3.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Default)]
pub enum InterpolationMode {
    /// The planner's period records, fine-interpolated by the DDAs (with acceleration).
    #[default]
    #[serde(rename = "dda")]
    Dda,
    /// Point-by-point comparison records (seed 003, docs/spec/pbp_interp.md): G1/G2/G3 in
    /// the plane as lines and arcs on one chip pair at a constant decision rate, no
    /// acceleration; G0 as the DDA's records. Needs a chip with `VERSION.HAS_PBP`.
    #[serde(rename = "pbp")]
    Pbp,
}

/// `[interpolation]`: the interpolation of G1/G2/G3 and, for point-by-point, the plane's
/// chip pair and the decision-rate limit (docs/host.md, "Interpolation").
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct InterpolationConfig {
    /// DDA or point-by-point.
    pub mode: InterpolationMode,
    /// The plane's two axes (of X, Y, Z), e.g. `"XY"` for G17, `"XZ"` or `"ZX"` for a
    /// lathe's G18: the first goes to chip axis `2 * pair`, the second to `2 * pair + 1`.
    pub plane: String,
    /// The chip pair (0..=3): chip axes `2 * pair` and `2 * pair + 1`.
    pub pair: u8,
    /// The highest decision rate, Hz: the highest step rate the drives start at without
    /// a ramp (a point-by-point move has no acceleration).
    pub max_decision_hz: f64,
}

impl Default for InterpolationConfig {
    /// The DDA; for point-by-point the XY plane on pair 0, at most 10 000 decisions a second.
    fn default() -> Self {
        InterpolationConfig { mode: InterpolationMode::Dda, plane: "XY".into(), pair: 0, max_decision_hz: 10_000.0 }
    }
}

/// `[interpolation]` resolved for point-by-point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ResolvedPbp {
    /// The record slots (0..4: X, Y, Z, A) of the plane's first and second axis: chip
    /// axes `2 * pair` and `2 * pair + 1`.
    pub slots: [usize; 2],
    /// The G-code plane they make (G17, G18, G19).
    pub plane: finestep_gcode::Plane,
    /// The slots are in the order opposite to the plane's own (G17 X->Y, G18 Z->X, G19
    /// Y->Z): the plane's counter-clockwise is clockwise on the pair.
    pub mirrored: bool,
    /// The chip pair.
    pub pair: u8,
    /// The fewest clocks between two decisions: `ceil(clock_hz / max_decision_hz)`, at
    /// least the drive timing's `R * (L_v + max(S_v, H_v + U_v))` (the step engine's
    /// visits `R`: a step may follow the last one on either axis in either direction).
    pub min_interval: u32,
    /// `interpolation.max_decision_hz`.
    pub max_decision_hz: f64,
}

/// The largest `tick_div + 1` a record carries (`pbp_interp`'s `DIV_W`, 24 bits).
pub const PBP_INTERVAL_MAX: u32 = 1 << finestep_interface::PbpLanes::DIV_W;

/// `finestep measure` (`[measure]`): a traverse of one axis at a steady feed while the chip
/// latches two encoder channels on one clock at every period boundary: the traverse
/// axis's own grating and a gauge. The planner does not read it.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MeasureConfig {
    /// The traverse axis (X, Y, Z or A).
    pub axis: String,
    /// The traverse's length from where the axis stands, mm (its sign is the direction).
    pub length_mm: f64,
    /// The traverse's feed, mm/s.
    pub feed_mm_s: f64,
    /// The encoder channel of the traverse axis's grating.
    pub axis_channel: u8,
    /// That grating's counts per mm.
    pub axis_counts_per_mm: f64,
    /// The encoder channel of the gauge.
    pub gauge_channel: u8,
    /// The gauge's resolution, um per count.
    pub gauge_um_per_count: f64,
}

impl Default for MeasureConfig {
    /// The demo's roller: Z over 6 mm at 20 mm/s, a 0.5 um grating on channel 0, a 0.5 um
    /// gauge on channel 1.
    fn default() -> Self {
        MeasureConfig {
            axis: "Z".into(),
            length_mm: 6.0,
            feed_mm_s: 20.0,
            axis_channel: 0,
            axis_counts_per_mm: 2000.0,
            gauge_channel: 1,
            gauge_um_per_count: 0.5,
        }
    }
}

/// One tool of the tool table.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ToolConfig {
    /// Tool number (T, and D in G41/G42).
    pub number: u32,
    /// Cutter radius, mm.
    pub radius_mm: f64,
}

impl Default for MachineConfig {
    /// X, Y at 800 steps/mm, Z at 400 steps/mm, A at 100 steps/degree; T = 1 ms at 50 MHz.
    fn default() -> Self {
        let axis = |steps_per_unit, max_velocity, max_acceleration, max_jerk| AxisLimits {
            steps_per_unit,
            max_velocity,
            max_acceleration,
            max_jerk,
        };
        let axes = [
            ("X", axis(800.0, 100.0, 1000.0, 100_000.0)),
            ("Y", axis(800.0, 100.0, 1000.0, 100_000.0)),
            ("Z", axis(400.0, 50.0, 500.0, 50_000.0)),
            ("A", axis(100.0, 180.0, 1800.0, 180_000.0)),
        ];
        MachineConfig {
            period_ms: 1.0,
            clock_hz: None,
            profile: ProfileKind::Trapezoid,
            path_tolerance_mm: 0.01,
            chord_tolerance_mm: 0.001,
            lookahead_moves: 2000,
            bus: None,
            parameter_file: None,
            ini_file: None,
            user_m_path: Vec::new(),
            cutter_comp_entry: crate::cutter_comp::EntryExit::Tangent,
            measure: MeasureConfig::default(),
            gantry: GantryConfig::default(),
            interpolation: InterpolationConfig::default(),
            spindle: SpindleConfig::default(),
            drive: DriveTimingNs::default(),
            axes: axes.into_iter().map(|(n, a)| (n.to_string(), a)).collect(),
            tools: vec![
                ToolConfig { number: 1, radius_mm: 3.0 },
                ToolConfig { number: 2, radius_mm: 1.5 },
                ToolConfig { number: 3, radius_mm: 0.5 },
            ],
            core: CoreLimits::default(),
        }
    }
}

/// A configuration that cannot be used: the file and the key, and why.
#[derive(Debug, thiserror::Error, PartialEq)]
#[error("{file}: {key}: {reason}")]
pub struct ConfigError {
    /// The file (or `<built-in>`).
    pub file: String,
    /// The TOML key, dotted (`axes.X.max_velocity`), or `-` for the whole file.
    pub key: String,
    /// What is wrong.
    pub reason: String,
}

/// One axis after validation, with its drive's rated limits folded in.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ResolvedAxis {
    /// Whether the axis exists on this machine.
    pub present: bool,
    /// Steps per unit.
    pub steps_per_unit: f64,
    /// Speed limit, units/s: the configured one, capped below the rated forward step rate.
    pub max_velocity: f64,
    /// Acceleration limit, units/s^2.
    pub max_acceleration: f64,
    /// Jerk limit, units/s^3.
    pub max_jerk: f64,
}

/// A validated configuration in the units the planner computes in.
#[derive(Clone, Debug, PartialEq)]
pub struct Resolved {
    /// The core clock, Hz (the core's, see [`CoreLimits`]).
    pub clock_hz: f64,
    /// Period T, s.
    pub period_s: f64,
    /// Period in FPGA clocks (as the core runs it: a multiple of `step_slots`).
    pub period_clocks: u32,
    /// The core's step slots `S` ([`CoreLimits::step_slots`]).
    pub step_slots: u32,
    /// The drive timing in clocks, one per record slot.
    pub timing: [DriveTiming; 4],
    /// Axes X, Y, Z, A.
    pub axes: [ResolvedAxis; 4],
    /// Profile.
    pub profile: ProfileKind,
    /// G64 tolerance without P, mm.
    pub path_tolerance_mm: f64,
    /// Chord tolerance, mm.
    pub chord_tolerance_mm: f64,
    /// Look-ahead in moves.
    pub lookahead_moves: usize,
    /// Runs of short G1 segments in G64 are smoothed into one curve within P
    /// ([`crate::smooth`]): on with the S-curve profile, whose jerk limit caps the speed
    /// at every blend squeezed between two short segments.
    pub smooth_short_segments: bool,
    /// S at full spindle level, rev/min.
    pub spindle_max_rpm: f64,
    /// The gantry pair, when `[gantry]` enables it.
    pub gantry: Option<ResolvedGantry>,
    /// Point-by-point interpolation, when `[interpolation]` selects it.
    pub pbp: Option<ResolvedPbp>,
    /// The chip axis of each record slot (X, Y, Z, A): the slot itself, but with
    /// point-by-point the plane's axes on the pair and the others on the chip axes left,
    /// in slot order.
    pub chip_axis: [usize; 4],
    /// What was adjusted (velocity caps), for the report.
    pub notes: Vec<String>,
}

impl MachineConfig {
    /// Parses and validates TOML text; `file` names it in errors. With no chip to ask,
    /// the file is checked against the default build at its own `clock_hz` and without
    /// step slots (a period that is a whole number of the chip's slots depends on the
    /// chip: 2 on a 2-axis build, 4 on the default); the chip's CAPS and clock are checked
    /// when it is resolved for the chip ([`Self::for_core`]).
    pub fn from_toml_str(text: &str, file: &str) -> Result<MachineConfig, ConfigError> {
        let config: MachineConfig = toml::from_str(text).map_err(|e| ConfigError {
            file: file.to_string(),
            key: "-".to_string(),
            reason: e.to_string().trim_end().replace('\n', " "),
        })?;
        let default_build = config.core;
        // The chip's HAS_PBP is checked when resolved for it, too.
        let at_its_clock = CoreLimits {
            clock_hz: config.clock_hz.unwrap_or(default_build.clock_hz),
            step_slots: 1,
            has_pbp: true,
            ..default_build
        };
        let config = config.for_core(at_its_clock);
        config.resolve_in(file)?;
        Ok(config.for_core(default_build))
    }

    /// Reads, parses and validates a TOML file.
    pub fn load(path: &Path) -> Result<MachineConfig, ConfigError> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| ConfigError {
            file: file.clone(),
            key: "-".into(),
            reason: e.to_string(),
        })?;
        MachineConfig::from_toml_str(&text, &file)
    }

    /// The tool table for cutter compensation.
    pub fn tool_table(&self) -> crate::cutter_comp::ToolTable {
        self.tools
            .iter()
            .fold(crate::cutter_comp::ToolTable::new(), |table, tool| table.with_radius_mm(tool.number, tool.radius_mm))
            .with_entry_exit(self.cutter_comp_entry)
    }

    /// The same configuration, to be resolved against `core` (the chip's CAPS and clock).
    pub fn for_core(self, core: CoreLimits) -> MachineConfig {
        MachineConfig { core, ..self }
    }

    /// Validates against [`MachineConfig::core`] and converts to planner units (file name
    /// `<built-in>` in errors).
    pub fn resolve(&self) -> Result<Resolved, ConfigError> {
        self.resolve_in("<built-in>")
    }

    /// [`MachineConfig::resolve`], naming `file` in errors.
    pub fn resolve_in(&self, file: &str) -> Result<Resolved, ConfigError> {
        let fail = |key: String, reason: String| ConfigError { file: file.to_string(), key, reason };
        let positive = |key: &str, value: f64| {
            if value.is_finite() && value > 0.0 {
                Ok(value)
            } else {
                Err(fail(key.to_string(), format!("must be a positive finite number, got {value}")))
            }
        };
        let period_s = positive("period_ms", self.period_ms)? * 1e-3;
        let core = &self.core;
        let clock_hz = positive("clock_hz", self.clock_hz.unwrap_or(core.clock_hz))?;
        if clock_hz != core.clock_hz {
            return Err(fail(
                "clock_hz".into(),
                format!("{clock_hz} Hz, but the core runs at {} Hz (CLOCK_HZ)", core.clock_hz),
            ));
        }
        let clocks = (period_s * clock_hz).round();
        if !(1.0..=f64::from(core.period_max())).contains(&clocks) {
            return Err(fail(
                "period_ms".into(),
                format!(
                    "{} ms is {clocks} clocks at {} MHz, outside the core's 1..={} (CAPS.P_WIDTH = {})",
                    self.period_ms,
                    clock_hz / 1e6,
                    core.period_max(),
                    core.p_width
                ),
            ));
        }
        let period_clocks = clocks as u32;
        if !period_clocks.is_multiple_of(core.step_slots) {
            return Err(fail(
                "period_ms".into(),
                format!(
                    "{} ms is {period_clocks} clocks at {} MHz, not a multiple of the core's step round of {} \
                     clocks (CAPS.STEP_ROUND_LOG2)",
                    self.period_ms,
                    clock_hz / 1e6,
                    core.step_slots
                ),
            ));
        }
        for (index, tool) in self.tools.iter().enumerate() {
            if !(tool.radius_mm.is_finite() && tool.radius_mm >= 0.0) {
                return Err(fail(
                    format!("tools[{index}].radius_mm"),
                    format!("must be a finite radius >= 0, got {}", tool.radius_mm),
                ));
            }
            if self.tools[..index].iter().any(|other| other.number == tool.number) {
                return Err(fail(format!("tools[{index}].number"), format!("tool {} appears twice", tool.number)));
            }
        }
        positive("path_tolerance_mm", self.path_tolerance_mm)?;
        positive("chord_tolerance_mm", self.chord_tolerance_mm)?;
        positive("spindle.max_rpm", self.spindle.max_rpm)?;
        positive("measure.feed_mm_s", self.measure.feed_mm_s)?;
        positive("measure.axis_counts_per_mm", self.measure.axis_counts_per_mm)?;
        positive("measure.gauge_um_per_count", self.measure.gauge_um_per_count)?;
        if !self.measure.length_mm.is_finite() || self.measure.length_mm == 0.0 {
            return Err(fail(
                "measure.length_mm".into(),
                format!("must be a finite non-zero length, got {}", self.measure.length_mm),
            ));
        }
        if self.measure.axis_channel == self.measure.gauge_channel {
            return Err(fail(
                "measure.gauge_channel".into(),
                format!("channel {} is the axis's grating too", self.measure.gauge_channel),
            ));
        }
        if !(2..=1_000_000).contains(&self.lookahead_moves) {
            return Err(fail(
                "lookahead_moves".into(),
                format!("must be within 2..=1000000, got {}", self.lookahead_moves),
            ));
        }
        // Up to whole clocks, ignoring the floating-point dust of exact multiples.
        let timing = DriveTiming::from_ns(self.drive.to_array(), clock_hz, core.timing_max()).map_err(|e| {
            let clocks = (e.ns * 1e-9 * clock_hz * (1.0 - 1e-12)).ceil();
            fail(
                format!("drive.{}_ns", e.field),
                format!(
                    "{} ns is {clocks} clocks at {} MHz, not within the core's 0..={} (CAPS.TIMING_W = {})",
                    e.ns,
                    clock_hz / 1e6,
                    e.max_clocks,
                    core.timing_w
                ),
            )
        })?;
        if let Some(name) = self.axes.keys().find(|n| !AXIS_NAMES.contains(&n.as_str())) {
            return Err(fail(format!("axes.{name}"), "unknown axis (the planner knows X, Y, Z, A)".into()));
        }
        let mut notes = Vec::new();
        let absent = ResolvedAxis {
            present: false,
            steps_per_unit: 1.0,
            max_velocity: 0.0,
            max_acceleration: 0.0,
            max_jerk: 0.0,
        };
        let mut axes = [absent; 4];
        for (slot, name) in AXIS_NAMES.iter().enumerate() {
            let Some(limits) = self.axes.get(*name) else { continue };
            if slot >= core.n_axes {
                return Err(fail(
                    format!("axes.{name}"),
                    format!("{name} is axis {slot}, but the core has {} axes (CAPS.N_AXES)", core.n_axes),
                ));
            }
            let key = |field: &str| format!("axes.{name}.{field}");
            let steps_per_unit = positive(&key("steps_per_unit"), limits.steps_per_unit)?;
            let mut max_velocity = positive(&key("max_velocity"), limits.max_velocity)?;
            let max_acceleration = positive(&key("max_acceleration"), limits.max_acceleration)?;
            let max_jerk = positive(&key("max_jerk"), limits.max_jerk)?;
            // Rated rates in steps per period (docs/spec/rated_rate.md), with 5 % kept back
            // for the Q16.16 rounding of positions.
            let forward = f64::from(period_clocks) / forward_interval_in(&timing, core.step_slots) as f64 * 0.95;
            let reverse = f64::from(period_clocks) / reversal_interval_in(&timing, core.step_slots) as f64 * 0.95;
            let rated_velocity = forward / period_s / steps_per_unit;
            if max_velocity > rated_velocity {
                notes.push(format!(
                    "{name} max velocity {max_velocity} capped at the drive's rated {rated_velocity:.3} units/s"
                ));
                max_velocity = rated_velocity;
            }
            // A reversing axis must stay within the reversal rate until it has moved two
            // steps: from rest with acceleration A (steps/period^2) it reaches sqrt(4A)
            // in two steps, plus one more period's A.
            let accel_steps = max_acceleration * steps_per_unit * period_s * period_s;
            if (4.0 * accel_steps).sqrt() + accel_steps > reverse {
                return Err(fail(
                    key("max_acceleration"),
                    format!("{max_acceleration} units/s^2 is too high for the drive's reversal rate ({reverse:.2} steps per period)"),
                ));
            }
            axes[slot] = ResolvedAxis { present: true, steps_per_unit, max_velocity, max_acceleration, max_jerk };
        }
        if !axes.iter().any(|a| a.present) {
            return Err(fail("axes".into(), "no axis configured".into()));
        }
        let gantry = self.gantry.resolve(core.n_axes, clock_hz).map_err(|(key, reason)| fail(key, reason))?;
        if let Some(g) = gantry {
            if !axes[usize::from(g.master)].present {
                return Err(fail(
                    "gantry.master".into(),
                    format!(
                        "{} is not configured in [axes]: the master is the axis the program moves",
                        self.gantry.master
                    ),
                ));
            }
        }
        let (pbp, chip_axis) = self.resolve_interpolation(file, &axes, &timing, clock_hz, gantry.is_some())?;
        Ok(Resolved {
            clock_hz,
            period_s,
            period_clocks,
            step_slots: core.step_slots,
            timing: [timing; 4],
            axes,
            profile: self.profile,
            path_tolerance_mm: self.path_tolerance_mm,
            chord_tolerance_mm: self.chord_tolerance_mm,
            lookahead_moves: self.lookahead_moves,
            smooth_short_segments: self.profile == ProfileKind::SCurve,
            spindle_max_rpm: self.spindle.max_rpm,
            gantry,
            pbp,
            chip_axis,
            notes,
        })
    }

    /// `[interpolation]` against the resolved axes and drive timing: `None` and the
    /// identity for the DDA; errors name `interpolation.<key>` (or `axes.<name>`).
    fn resolve_interpolation(
        &self,
        file: &str,
        axes: &[ResolvedAxis; 4],
        timing: &DriveTiming,
        clock_hz: f64,
        gantry: bool,
    ) -> Result<(Option<ResolvedPbp>, [usize; 4]), ConfigError> {
        let fail = |key: &str, reason: String| ConfigError { file: file.to_string(), key: key.into(), reason };
        let section = &self.interpolation;
        let identity = [0, 1, 2, 3];
        let plane_slots = |text: &str| -> Option<[usize; 2]> {
            let mut chars = text.chars();
            let (a, b) = (chars.next()?, chars.next()?);
            if chars.next().is_some() {
                return None;
            }
            let slot = |c: char| "XYZ".find(c.to_ascii_uppercase());
            let (a, b) = (slot(a)?, slot(b)?);
            (a != b).then_some([a, b])
        };
        let slots = plane_slots(&section.plane).ok_or_else(|| {
            fail(
                "interpolation.plane",
                format!("\"{}\" is not two different axes of X, Y, Z (e.g. \"XY\", \"XZ\")", section.plane),
            )
        })?;
        if !(section.max_decision_hz.is_finite() && section.max_decision_hz > 0.0) {
            return Err(fail(
                "interpolation.max_decision_hz",
                format!("must be a positive finite rate, got {}", section.max_decision_hz),
            ));
        }
        if section.mode == InterpolationMode::Dda {
            return Ok((None, identity));
        }
        if !self.core.has_pbp {
            return Err(fail(
                "interpolation.mode",
                "\"pbp\", but the chip has no point-by-point interpolator (VERSION.HAS_PBP 0)".into(),
            ));
        }
        if gantry {
            return Err(fail("interpolation.mode", "\"pbp\" with [gantry] enabled is not supported".into()));
        }
        let n_axes = self.core.n_axes;
        let pair = usize::from(section.pair);
        if section.pair > 3 || 2 * pair + 1 >= n_axes {
            return Err(fail(
                "interpolation.pair",
                format!(
                    "pair {} is chip axes {} and {}, but the core has {n_axes} axes (CAPS.N_AXES)",
                    section.pair,
                    2 * pair,
                    2 * pair + 1
                ),
            ));
        }
        for slot in slots {
            if !axes[slot].present {
                return Err(fail("interpolation.plane", format!("{} is not configured in [axes]", AXIS_NAMES[slot])));
            }
        }
        let (spu_u, spu_v) = (axes[slots[0]].steps_per_unit, axes[slots[1]].steps_per_unit);
        if spu_u != spu_v {
            return Err(fail(
                "interpolation.plane",
                format!(
                    "{} has {spu_u} steps per mm, {} {spu_v}: a point-by-point arc is a circle in steps, so the pair's axes need equal steps per unit",
                    AXIS_NAMES[slots[0]], AXIS_NAMES[slots[1]]
                ),
            ));
        }
        // The plane's axes on the pair, the others on the chip axes left, in slot order.
        let mut chip_axis = identity;
        chip_axis[slots[0]] = 2 * pair;
        chip_axis[slots[1]] = 2 * pair + 1;
        let mut free = (0..4).filter(|c| *c / 2 != pair);
        for slot in (0..4).filter(|s| !slots.contains(s)) {
            chip_axis[slot] = free.next().unwrap_or(slot);
            if axes[slot].present && chip_axis[slot] >= n_axes {
                return Err(fail(
                    &format!("axes.{}", AXIS_NAMES[slot]),
                    format!(
                        "{} goes to chip axis {} beside the pair {}, but the core has {n_axes} axes (CAPS.N_AXES)",
                        AXIS_NAMES[slot], chip_axis[slot], section.pair
                    ),
                ));
            }
        }
        let (plane, canonical) = match (slots[0].min(slots[1]), slots[0].max(slots[1])) {
            (0, 1) => (finestep_gcode::Plane::Xy, [0, 1]),
            (0, 2) => (finestep_gcode::Plane::Zx, [2, 0]),
            _ => (finestep_gcode::Plane::Yz, [1, 2]),
        };
        let slots_clocks = u64::from(self.core.step_slots.max(1));
        let drive = finestep_interface::rate::reversal_wait_in(timing, self.core.step_slots) + slots_clocks;
        let by_rate = (clock_hz / section.max_decision_hz * (1.0 - 1e-12)).ceil().max(1.0);
        let min_interval = by_rate.max(drive as f64);
        if min_interval > f64::from(PBP_INTERVAL_MAX) {
            return Err(fail(
                "interpolation.max_decision_hz",
                format!(
                    "{} Hz is a decision every {min_interval} clocks at {} MHz, beyond the record's {PBP_INTERVAL_MAX}",
                    section.max_decision_hz,
                    clock_hz / 1e6
                ),
            ));
        }
        let pbp = ResolvedPbp {
            slots,
            plane,
            mirrored: slots != canonical,
            pair: section.pair,
            min_interval: min_interval as u32,
            max_decision_hz: section.max_decision_hz,
        };
        Ok((Some(pbp), chip_axis))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_empty_file_gives_the_defaults() {
        let config = MachineConfig::from_toml_str("", "m.toml").unwrap();
        assert_eq!(config, MachineConfig::default());
        let resolved = config.resolve().unwrap();
        assert_eq!(resolved.period_clocks, 50_000);
        assert!(resolved.axes.iter().all(|a| a.present));
    }

    #[test]
    fn a_partial_file_overrides_what_it_names() {
        let text =
            "profile = \"s-curve\"\nperiod_ms = 2\n[axes.X]\nsteps_per_unit = 1000\n[axes.Z]\nmax_velocity = 20\n";
        let config = MachineConfig::from_toml_str(text, "m.toml").unwrap();
        let resolved = config.resolve().unwrap();
        assert_eq!(resolved.profile, ProfileKind::SCurve);
        assert_eq!(resolved.period_clocks, 100_000);
        assert_eq!(resolved.axes[0].steps_per_unit, 1000.0);
        assert_eq!(resolved.axes[0].max_velocity, 100.0);
        assert!(!resolved.axes[1].present && !resolved.axes[3].present);
        assert_eq!(resolved.axes[2].max_velocity, 20.0);
    }

    #[test]
    fn the_entry_and_exit_of_cutter_compensation_are_chosen_by_name() {
        use crate::cutter_comp::EntryExit;
        assert_eq!(MachineConfig::default().tool_table().entry_exit(), EntryExit::Tangent);
        let config = MachineConfig::from_toml_str("cutter_comp_entry = \"linuxcnc\"\n", "m.toml").unwrap();
        assert_eq!(config.tool_table().entry_exit(), EntryExit::LinuxCnc);
        assert_eq!(config.tool_table().radius_mm(1), Some(3.0));
        let err = MachineConfig::from_toml_str("cutter_comp_entry = \"sideways\"\n", "m.toml").unwrap_err();
        assert!(err.reason.contains("unknown variant `sideways`, expected `tangent` or `linuxcnc`"), "{err}");
    }

    #[test]
    fn errors_name_the_file_and_the_key() {
        let err = MachineConfig::from_toml_str("[axes.X]\nmax_velocity = -1\n", "m.toml").unwrap_err();
        assert_eq!(err.to_string(), "m.toml: axes.X.max_velocity: must be a positive finite number, got -1");
        let err = MachineConfig::from_toml_str("[axes.X]\nmax_vel = 1\n", "m.toml").unwrap_err();
        assert!(err.to_string().starts_with("m.toml: -:") && err.reason.contains("max_vel"), "{err}");
        let err = MachineConfig::from_toml_str("[axes.B]\n", "m.toml").unwrap_err();
        assert_eq!(err.key, "axes.B");
        let err = MachineConfig::from_toml_str("period_ms = 100\n", "m.toml").unwrap_err();
        assert_eq!(err.key, "period_ms");
        let err = MachineConfig::from_toml_str("[axes.X]\nmax_acceleration = 1e9\n", "m.toml").unwrap_err();
        assert_eq!(err.key, "axes.X.max_acceleration");
        let err = MachineConfig::from_toml_str("profile = \"cubic\"\n", "m.toml").unwrap_err();
        assert!(err.reason.contains("cubic"), "{err}");
        let err = MachineConfig::from_toml_str("[measure]\nfeed_mm_s = 0\n", "m.toml").unwrap_err();
        assert_eq!(err.key, "measure.feed_mm_s");
        let err = MachineConfig::from_toml_str("[measure]\nlength_mm = 0\n", "m.toml").unwrap_err();
        assert_eq!(err.key, "measure.length_mm");
        let err = MachineConfig::from_toml_str("[measure]\ngauge_channel = 0\n", "m.toml").unwrap_err();
        assert_eq!(err.to_string(), "m.toml: measure.gauge_channel: channel 0 is the axis's grating too");
    }

    #[test]
    fn the_core_limits_the_configuration() {
        let core = CoreLimits::default();
        let key = |core: CoreLimits, config: MachineConfig| config.for_core(core).resolve().unwrap_err().key;
        assert_eq!(key(CoreLimits { p_width: 15, ..core }, MachineConfig::default()), "period_ms");
        assert_eq!(key(CoreLimits { timing_w: 7, ..core }, MachineConfig::default()), "drive.dir_setup_ns");
        assert_eq!(key(CoreLimits { n_axes: 3, ..core }, MachineConfig::default()), "axes.A");
        let other_clock = CoreLimits { clock_hz: 48e6, ..core };
        let config = MachineConfig { clock_hz: Some(50e6), ..MachineConfig::default() };
        let err = config.for_core(other_clock).resolve().unwrap_err();
        assert_eq!(err.to_string(), "<built-in>: clock_hz: 50000000 Hz, but the core runs at 48000000 Hz (CLOCK_HZ)");
        // Without clock_hz the core's clock is taken.
        let resolved = MachineConfig::default().for_core(other_clock).resolve().unwrap();
        assert_eq!((resolved.clock_hz, resolved.period_clocks), (48e6, 48_000));
        // A file for a 48 MHz board loads; it is checked against the chip when resolved for it.
        let config = MachineConfig::from_toml_str("clock_hz = 48e6\n", "m.toml").unwrap();
        assert_eq!(config.for_core(other_clock).resolve().unwrap().period_clocks, 48_000);
        let err = MachineConfig::from_toml_str("clock_hz = 48e6\n", "m.toml").unwrap().resolve_in("m.toml");
        assert_eq!(err.unwrap_err().key, "clock_hz");
        // A period off the chip's step slots is refused by key; which periods are whole
        // slots depends on the chip, so a file for a 2-slot build loads.
        let two_slots = CoreLimits { step_slots: 2, ..core };
        let four_slots = CoreLimits { step_slots: 4, ..core };
        let config = MachineConfig::from_toml_str("period_ms = 0.10002\n", "m.toml").unwrap(); // 5 001 clocks
        assert_eq!(config.clone().for_core(four_slots).resolve().unwrap_err().key, "period_ms");
        assert_eq!(config.clone().for_core(two_slots).resolve().unwrap_err().key, "period_ms");
        let config = MachineConfig::from_toml_str("period_ms = 0.10004\n", "m.toml").unwrap(); // 5 002 clocks
        assert_eq!(config.clone().for_core(two_slots).resolve().unwrap().period_clocks, 5_002);
        let err = config.for_core(four_slots).resolve_in("m.toml").unwrap_err().to_string();
        assert!(
            err.contains("5002 clocks") && err.contains("not a multiple of the core's step round of 4 clocks"),
            "{err}"
        );
    }

    #[test]
    fn velocity_is_capped_at_the_rated_rate() {
        let text = "[axes.X]\nmax_velocity = 10000\n";
        let resolved = MachineConfig::from_toml_str(text, "m.toml").unwrap().resolve().unwrap();
        // 50 000 clocks / (100 + 100) clocks per step = 250 steps per ms, less 5 %.
        assert!((resolved.axes[0].max_velocity - 250.0 * 0.95 / 0.001 / 800.0).abs() < 1e-9);
        assert_eq!(resolved.notes.len(), 1);
    }

    #[test]
    fn gantry_section_enables_the_pair_with_its_limits() {
        let text = "[gantry]\nenabled = true\nmaster = \"Y\"\nslave = \"Z\"\nenc_master = 2\nenc_slave = 3\n\
                    sync = false\ntick_us = 20.0\ndeadband_counts = 4\nlimit_counts = 40\n";
        let resolved = MachineConfig::from_toml_str(text, "m.toml").unwrap().resolve().unwrap();
        // 20 us at 50 MHz: 1000 clocks, 16 * 62 + 15 = 1007 the nearest the chip has.
        let expected = ResolvedGantry {
            master: 1,
            slave: 2,
            enc_master: 2,
            enc_slave: 3,
            sync: false,
            tick: 62,
            deadband: 4,
            limit: 40,
        };
        assert_eq!(resolved.gantry, Some(expected));
        // Off by default, and off when the section says so.
        assert_eq!(MachineConfig::default().resolve().unwrap().gantry, None);
        let off = MachineConfig::from_toml_str("[gantry]\nlimit_counts = 7\n", "m.toml").unwrap();
        assert_eq!(off.resolve().unwrap().gantry, None);
    }

    #[test]
    fn bad_gantry_values_are_refused_by_key() {
        let err = |text: &str| MachineConfig::from_toml_str(text, "m.toml").unwrap_err();
        let cases = [
            ("[gantry]\nmaster = \"Q\"\n", "gantry.master", "\"Q\" is not an axis"),
            ("[gantry]\nslave = \"X\"\n", "gantry.slave", "X is the master too"),
            ("[gantry]\nenc_slave = 4\n", "gantry.enc_slave", "not within 0..=3"),
            ("[gantry]\nenc_slave = 0\n", "gantry.enc_slave", "channel 0 is the master's too"),
            ("[gantry]\ntick_us = 0\n", "gantry.tick_us", "positive finite"),
            ("[gantry]\ntick_us = 1e6\n", "gantry.tick_us", "outside the chip's 15..=1048575"),
            ("[gantry]\nlimit_counts = 2\n", "gantry.limit_counts", "must exceed deadband_counts (2)"),
            ("[gantry]\nlimit = 2\n", "-", "unknown field `limit`"),
            ("[gantry]\nlimit_counts = 70000\n", "-", "limit_counts"),
        ];
        for (text, key, reason) in cases {
            let e = err(text);
            assert_eq!(e.key, key, "{text}: {e}");
            assert!(e.reason.contains(reason), "{text}: {e}");
        }
        // The master must be an axis the program can move; the axes must be the core's.
        let e = err("[gantry]\nenabled = true\nmaster = \"Y\"\nslave = \"X\"\n[axes.X]\n");
        assert_eq!((e.key.as_str(), e.reason.contains("not configured in [axes]")), ("gantry.master", true), "{e}");
        let two_axes = CoreLimits { n_axes: 2, ..CoreLimits::default() };
        let xy: BTreeMap<String, AxisLimits> =
            MachineConfig::default().axes.into_iter().filter(|(name, _)| name == "X" || name == "Y").collect();
        // Not enabled, the default slave A does not stop a two-axis core.
        let config = MachineConfig { axes: xy.clone(), ..Default::default() };
        assert_eq!(config.for_core(two_axes).resolve().unwrap().gantry, None);
        // Enabled, it does.
        let gantry = GantryConfig { enabled: true, ..Default::default() };
        let enabled = MachineConfig { axes: xy, gantry, ..Default::default() };
        let e = enabled.for_core(two_axes).resolve_in("m.toml").unwrap_err();
        assert_eq!(e.key, "gantry.slave", "{e}");
        assert!(e.reason.contains("the core has 2 axes"), "{e}");
    }
}

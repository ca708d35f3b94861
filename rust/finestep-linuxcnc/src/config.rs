//! finestep under LinuxCNC, from the same machine configuration `finestep run` reads:
//!
//! - `finestep-linuxcnc config`: the INI and HAL files of a LinuxCNC mill (X, Y, Z and
//!   a rotary A when the configuration has one) in open loop
//!   (the `finestep` HAL component's step counts as feedback), one joint per axis of the
//!   configuration, as LinuxCNC-RIO generates its HAL and INI from its JSON: one file
//!   says how the machine is built. With `--record`, a HAL file that samples every servo
//!   period's commanded joint position (in 2^-16 steps) and the chip's step count.
//! - `finestep-linuxcnc check`: the open-loop check over such a recording: at every
//!   servo period each axis's step count on the chip equals LinuxCNC's commanded joint
//!   position quantised to steps as the driver quantises it.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::{bail, Context};
use finestep_hal::{count_latency_clocks, quantised_steps, round_fixed, FEEDBACK_LAG_PERIODS, LATCH_LAG_CLOCKS};
use finestep_interface::TopParams;
use finestep_planner::config::{CoreLimits, AXIS_NAMES};
use finestep_planner::MachineConfig;

use crate::closed_loop::{self, Loop};

/// Travel of every axis in the generated INI, machine units either side of 0 (the TOML
/// has no soft limits).
const TRAVEL: f64 = 10_000.0;

/// The hand wheel's travel per detent on every axis, machine units (mm or degrees): the
/// x1 step of a mill's wheel (the TOML has no hand wheel section).
const MPG_SCALE: f64 = 0.01;

/// The joints of a configuration: (record slot, axis name, steps per unit, max velocity,
/// max acceleration).
pub(crate) struct Joint {
    pub(crate) slot: usize,
    pub(crate) name: &'static str,
    pub(crate) scale: f64,
    pub(crate) max_velocity: f64,
    pub(crate) max_acceleration: f64,
}

fn joints(config: MachineConfig, file: &str) -> anyhow::Result<(Vec<Joint>, MachineConfig, f64)> {
    // The default build's limits (the chip's CAPS are checked again when the HAL
    // component connects).
    let core = CoreLimits::of_build(&TopParams::default());
    let config = config.for_core(core);
    let resolved = config.resolve_in(file)?;
    let joints: Vec<Joint> = (0..AXIS_NAMES.len())
        .filter(|&slot| resolved.axes[slot].present)
        .map(|slot| {
            let axis = &resolved.axes[slot];
            Joint {
                slot,
                name: AXIS_NAMES[slot],
                scale: axis.steps_per_unit,
                max_velocity: axis.max_velocity,
                max_acceleration: axis.max_acceleration,
            }
        })
        .collect();
    Ok((joints, config, resolved.period_s))
}

/// Writes `finestep.ini`, `finestep.hal`, `tool.tbl` (and `record.hal` with `record`)
/// into `out` for the configuration at `config_path` (the built-in machine when absent)
/// on the chip at `bus`; `display` is the INI's DISPLAY program.
/// `which` picks open loop or a closed loop (`pid`: the PID tuning's overrides,
/// [`closed_loop::tuning`]).
pub fn write(
    config_path: Option<&Path>,
    bus: &str,
    display: &str,
    out: &Path,
    record: bool,
    which: Loop,
    pid: Option<&str>,
) -> anyhow::Result<()> {
    let (config, name) = match config_path {
        Some(path) => (MachineConfig::load(path)?, path.display().to_string()),
        None => (MachineConfig::default(), "<built-in>".to_string()),
    };
    if which != Loop::Stepgen {
        bus.parse::<finestep_hal::Transport>()?;
    }
    let (joints, config, period_s) = joints(config, &name)?;
    if joints.is_empty() {
        bail!("{name}: no axes");
    }
    let gains = closed_loop::tuning(pid)?;
    let closed = (which != Loop::Open).then_some(gains.as_slice());
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let (hal_text, record_text) = match which {
        Loop::Open => (hal(&joints, bus, &name), record_hal(&joints)),
        _ => (closed_loop::hal(&joints, bus, &name, which), closed_loop::record_hal(&joints, which)),
    };
    let mut ini_text = ini(&joints, &config, period_s, display, &name, record, closed);
    if which == Loop::Stepgen {
        ini_text = ini_text
            .replace("SERVO_PERIOD = ", &format!("BASE_PERIOD = {}\nSERVO_PERIOD = ", closed_loop::BASE_PERIOD_NS));
    }
    let files = [
        ("finestep.ini", ini_text),
        ("finestep.hal", hal_text),
        ("postgui.hal", postgui_hal(&joints, &name)),
        ("tool.tbl", tools(&config)),
    ];
    for (file, text) in files.iter().chain(record.then_some(("record.hal", record_text)).iter()) {
        let path = out.join(file);
        std::fs::write(&path, text).with_context(|| format!("writing {}", path.display()))?;
    }
    println!(
        "finestep-linuxcnc config: {} joints ({}) from {name} into {}",
        joints.len(),
        joints.iter().map(|j| j.name).collect::<Vec<_>>().join(""),
        out.display()
    );
    Ok(())
}

/// `closed`: the PID tuning of a closed loop (its [PLANT] section and joint keys).
fn ini(
    joints: &[Joint],
    config: &MachineConfig,
    period_s: f64,
    display: &str,
    name: &str,
    record: bool,
    closed: Option<&[(&str, f64)]>,
) -> String {
    let coordinates: String = joints.iter().map(|j| j.name).collect();
    let max_velocity = joints.iter().filter(|j| j.name != "A").map(|j| j.max_velocity).fold(f64::INFINITY, f64::min);
    let mut text = format!(
        "# Generated by `finestep-linuxcnc config` from {name}: regenerate, do not edit.\n\
         # A {coordinates} mill in open loop on the finestep chip (docs/linuxcnc.md).\n\n\
         [EMC]\nVERSION = 1.1\nMACHINE = finestep\nDEBUG = 0\n\n\
         [DISPLAY]\nDISPLAY = {display}\nCYCLE_TIME = 0.100\nPOSITION_OFFSET = RELATIVE\nPOSITION_FEEDBACK = ACTUAL\n\
         MAX_FEED_OVERRIDE = 1.0\n\n\
         [TASK]\nTASK = milltask\nCYCLE_TIME = 0.010\n\n\
         [RS274NGC]\nPARAMETER_FILE = finestep.var\n\n\
         [EMCMOT]\nEMCMOT = motmod\n\
         # A simulated chip's servo period can take a second of wall time on a loaded machine.\n\
         COMM_TIMEOUT = 10.0\nSERVO_PERIOD = {servo_ns}\n\n\
         [EMCIO]\nEMCIO = io\nCYCLE_TIME = 0.100\nTOOL_TABLE = tool.tbl\n\n\
         [HAL]\nHALFILE = finestep.hal\n{record_line}HALUI = halui\n\
         # halui's pins exist once it runs: the display loads this after it starts.\n\
         POSTGUI_HALFILE = postgui.hal\n\n\
         [TRAJ]\nCOORDINATES = {coordinates}\nLINEAR_UNITS = mm\nANGULAR_UNITS = degree\n\
         DEFAULT_LINEAR_VELOCITY = {default_v}\nMAX_LINEAR_VELOCITY = {max_velocity}\n\n\
         [KINS]\nKINEMATICS = trivkins coordinates={coordinates}\nJOINTS = {n}\n\n",
        servo_ns = (period_s * 1e9).round() as u64,
        record_line = if record { "HALFILE = record.hal\n" } else { "" },
        default_v = max_velocity / 4.0,
        n = joints.len(),
    );
    if closed.is_some() {
        text.push_str(&closed_loop::ini_plant(TopParams::default().clock_hz));
    }
    let drive = &config.drive;
    for (index, joint) in joints.iter().enumerate() {
        let limits = format!(
            "MIN_LIMIT = {min}\nMAX_LIMIT = {TRAVEL}\nMAX_VELOCITY = {v}\nMAX_ACCELERATION = {a}\n",
            min = -TRAVEL,
            v = joint.max_velocity,
            a = joint.max_acceleration
        );
        let _ = write!(text, "[AXIS_{}]\n{limits}MPG_SCALE = {MPG_SCALE}\n\n", joint.name);
        let _ = write!(
            text,
            "[JOINT_{index}]\nTYPE = {kind}\nHOME = 0\n{limits}\
             # The step generator's own limit above the planner's, as hostmot2 configurations set it.\n\
             STEPGEN_MAXVEL = {stepgen_v}\n\
             SCALE = {scale}\nFINESTEP_SLOT = {slot}\n\
             # Open loop: the feedback lags the command by {lag} servo periods (docs/linuxcnc.md).\n\
             FERROR = 1.0\nMIN_FERROR = 0.25\n\
             STEPLEN = {l}\nSTEPSPACE = {s}\nDIRSETUP = {u}\nDIRHOLD = {h}\n\
             HOME_OFFSET = 0\nHOME_SEARCH_VEL = 0\nHOME_LATCH_VEL = 0\nHOME_SEQUENCE = 0\n{closed}\n",
            kind = if joint.name == "A" { "ANGULAR" } else { "LINEAR" },
            stepgen_v = joint.max_velocity * 1.25,
            scale = joint.scale,
            slot = joint.slot,
            lag = FEEDBACK_LAG_PERIODS,
            l = drive.step_len_ns.ceil(),
            s = drive.step_space_ns.ceil(),
            u = drive.dir_setup_ns.ceil(),
            h = drive.dir_hold_ns.ceil(),
            closed = closed.map_or(String::new(), |gains| closed_loop::ini_joint(joint, gains)),
        );
    }
    text
}

fn hal(joints: &[Joint], bus: &str, name: &str) -> String {
    let mut text = format!(
        "# Generated by `finestep-linuxcnc config` from {name}: regenerate, do not edit.\n\
         loadrt [KINS]KINEMATICS\n\
         loadrt [EMCMOT]EMCMOT servo_period_nsec=[EMCMOT]SERVO_PERIOD num_joints=[KINS]JOINTS\n\
         loadrt finestep bus={bus}\n\n\
         # One coherent latched read first, one period record last.\n\
         addf finestep.0.read servo-thread\n\
         addf motion-command-handler servo-thread\n\
         addf motion-controller servo-thread\n\
         addf finestep.0.write servo-thread\n\n\
         # E-stop chain as iocontrol wires it: the chip's E-stop input into emc-enable-in,\n\
         # LinuxCNC's enable out to the chip (the watchdog bit also holds the machine off).\n\
         net estop-out iocontrol.0.user-enable-out => finestep.0.enable\n\
         net estop-ok finestep.0.estop-ok => iocontrol.0.emc-enable-in\n\
         net tool-change-loop iocontrol.0.tool-change => iocontrol.0.tool-changed\n\
         net tool-prep-loop iocontrol.0.tool-prepare => iocontrol.0.tool-prepared\n"
    );
    for (index, joint) in joints.iter().enumerate() {
        let sg = format!("finestep.0.stepgen.{:02}", joint.slot);
        let _ = write!(
            text,
            "\n# Joint {index}: axis {axis}, record slot {slot}.\n\
             setp {sg}.position-scale [JOINT_{index}]SCALE\n\
             setp {sg}.maxvel [JOINT_{index}]STEPGEN_MAXVEL\n\
             setp {sg}.step_type 0\n\
             setp {sg}.steplen [JOINT_{index}]STEPLEN\n\
             setp {sg}.stepspace [JOINT_{index}]STEPSPACE\n\
             setp {sg}.dirsetup [JOINT_{index}]DIRSETUP\n\
             setp {sg}.dirhold [JOINT_{index}]DIRHOLD\n\
             net j{index}-pos-cmd joint.{index}.motor-pos-cmd => {sg}.position-cmd\n\
             net j{index}-pos-fb {sg}.position-fb => joint.{index}.motor-pos-fb\n\
             net j{index}-enable joint.{index}.amp-enable-out => {sg}.enable\n",
            axis = joint.name,
            slot = joint.slot,
        );
    }
    // The hand wheel jogs the selected axis (postgui.hal: halui's selection) by its
    // detents times MPG_SCALE, in position mode.
    let axes: Vec<String> = joints.iter().map(|j| j.name.to_lowercase()).collect();
    let counts: Vec<String> = axes.iter().map(|a| format!("axis.{a}.jog-counts")).collect();
    let _ = write!(text, "\n# Hand wheel: detents into every axis's jog counts; the selected axis jogs.\nnet mpg-detents finestep.0.mpg.detents => {}\n", counts.join(" "));
    for (joint, a) in joints.iter().zip(&axes) {
        let _ =
            write!(text, "setp axis.{a}.jog-scale [AXIS_{n}]MPG_SCALE\nsetp axis.{a}.jog-vel-mode 0\n", n = joint.name);
    }
    text
}

/// After halui starts (the display loads it): the axis halui selects is the one the
/// hand wheel jogs.
fn postgui_hal(joints: &[Joint], name: &str) -> String {
    let mut text = format!("# Generated by `finestep-linuxcnc config` from {name}: regenerate, do not edit.\n");
    for joint in joints {
        let a = joint.name.to_lowercase();
        let _ = writeln!(text, "net mpg-select-{a} halui.axis.{a}.is-selected => axis.{a}.jog-enable");
    }
    text
}

/// Samples, every servo period after the write: per joint the commanded position in
/// units of 2^-16 steps (a `scale` component with gain SCALE * 65536: exactly the
/// driver's product) and the chip's step count.
fn record_hal(joints: &[Joint]) -> String {
    let n = joints.len();
    let mut text = format!(
        "# Generated by `finestep-linuxcnc config --record`: the open-loop check's recording.\n\
         loadrt scale count={n}\n\
         loadrt sampler depth=16384 cfg={}b\n\
         net fs-running finestep.0.running => sampler.0.pin.{}\n",
        "fs".repeat(n),
        2 * n
    );
    for (index, joint) in joints.iter().enumerate() {
        let _ = write!(
            text,
            "setp scale.{index}.gain {gain:e}\n\
             net j{index}-pos-cmd scale.{index}.in\n\
             net j{index}-fixed scale.{index}.out => sampler.0.pin.{fixed}\n\
             net j{index}-counts finestep.0.stepgen.{slot:02}.counts => sampler.0.pin.{counts}\n\
             addf scale.{index} servo-thread\n",
            gain = joint.scale * 65536.0,
            fixed = 2 * index,
            counts = 2 * index + 1,
            slot = joint.slot,
        );
    }
    text.push_str("addf sampler.0 servo-thread\n");
    text
}

fn tools(config: &MachineConfig) -> String {
    let mut text = String::new();
    for tool in &config.tools {
        let _ = writeln!(text, "T{n} P{n} D{d} ;", n = tool.number, d = 2.0 * tool.radius_mm);
    }
    text
}

/// Half a unit of the last digit halsampler prints of a float (`%f`).
const RECORDED_HALF_UNIT: f64 = 5e-7;

/// What the open-loop check found.
#[derive(Debug, Default, PartialEq, Eq)]
pub struct CheckReport {
    /// Servo periods compared (rows after the lag).
    pub periods: usize,
    /// Joint-periods compared.
    pub compared: usize,
    /// Joint-periods whose step count differs from the quantised command.
    pub disagreements: usize,
    /// Of those, the ones the chip's pulse latency explains: one step short in the
    /// direction of motion, the command having crossed that step's rounding point within
    /// the last `window` clocks of the period (requested, not yet counted when the
    /// boundary latched the positions): [`finestep_hal::LATCH_LAG_CLOCKS`], plus the longest the step
    /// shaper may hold a request for the drive timing (a reversal's direction hold and
    /// set-up) when the check knows the timing.
    pub in_flight: usize,
    /// Joint-periods whose recorded command lies within the recording's resolution of a
    /// rounding point (not decidable from the text; expected 0).
    pub undecidable: usize,
    /// Samples lost by the sampler (gaps in the sample numbers).
    pub lost: u64,
    /// Largest |step count - quantised command|, steps.
    pub worst: i64,
    /// The first disagreement: (sample, joint, count, expected).
    pub first: Option<(u64, usize, i64, i64)>,
    /// Joint-periods in which the command moved.
    pub moving: usize,
    /// The first and the last sample whose command differs from the sample before (the
    /// span LinuxCNC's trajectory planner moved the machine).
    pub motion: Option<(u64, u64)>,
    /// What happened after the driver stopped while the command was running (an
    /// E-stop), if it did.
    pub stop: Option<StopReport>,
}

/// The driver stopped (LinuxCNC's E-stop) in the middle of a run.
#[derive(Debug, Default, PartialEq, Eq)]
pub struct StopReport {
    /// The first sample not running.
    pub sample: u64,
    /// Joint-periods after that sample whose step count differs from the final one
    /// (steps after the stop).
    pub steps_after: usize,
    /// Steps the final position of an axis lies beyond the positions of the last two
    /// records sent (an extra pulse), at most.
    pub beyond: i64,
}

/// One recorded servo period: the sample number, per joint the command in 2^-16 steps
/// and the step count, and whether the driver was running records.
struct Row {
    sample: u64,
    joints: Vec<(f64, i64)>,
    running: bool,
}

fn parse_rows(text: &str, joints: usize, file: &str) -> anyhow::Result<Vec<Row>> {
    let mut rows = Vec::new();
    for (line_no, line) in text.lines().enumerate() {
        let fields: Vec<&str> = line.split_whitespace().collect();
        if fields.is_empty() {
            continue;
        }
        let bad =
            || anyhow::anyhow!("{file}:{}: expected a sample number, {joints} pairs and the running bit", line_no + 1);
        if fields.len() != 2 + 2 * joints {
            return Err(bad());
        }
        let sample: u64 = fields[0].parse().map_err(|_| bad())?;
        let pairs = fields[1..=2 * joints]
            .chunks(2)
            .map(|pair| Ok((pair[0].parse::<f64>().map_err(|_| bad())?, pair[1].parse::<i64>().map_err(|_| bad())?)))
            .collect::<anyhow::Result<Vec<_>>>()?;
        let running = match fields[1 + 2 * joints] {
            "0" => false,
            "1" => true,
            _ => return Err(bad()),
        };
        rows.push(Row { sample, joints: pairs, running });
    }
    Ok(rows)
}

/// The step count `scaled` (2^-16 steps) quantises to, `None` when the six decimals
/// halsampler prints leave it on a rounding point.
fn steps_of(scaled: f64, what: &str) -> anyhow::Result<Option<i64>> {
    let steps_at = |x: f64| round_fixed(x).map(quantised_steps).with_context(|| format!("{what}: {scaled}"));
    let expected = steps_at(scaled)?;
    Ok((steps_at(scaled - RECORDED_HALF_UNIT)? == steps_at(scaled + RECORDED_HALF_UNIT)?).then_some(expected))
}

/// Checks a `halsampler -t` recording of `record.hal` (`joints` pairs and the running
/// bit per row): while the driver runs, row k's step count against row
/// k - [`FEEDBACK_LAG_PERIODS`]'s command; after it stops (an E-stop), that no step
/// follows and none went beyond the last two commands.
pub fn check_text(
    text: &str,
    joints: usize,
    period_clocks: f64,
    window: f64,
    file: &str,
) -> anyhow::Result<CheckReport> {
    let rows = parse_rows(text, joints, file)?;
    let mut report = CheckReport::default();
    for window in rows.windows(2) {
        report.lost += window[1].sample.saturating_sub(window[0].sample + 1);
        if window[1].joints.iter().zip(&window[0].joints).any(|(now, before)| now.0 != before.0) {
            let first = report.motion.map_or(window[1].sample, |m| m.0);
            report.motion = Some((first, window[1].sample));
        }
    }
    let lag = FEEDBACK_LAG_PERIODS;
    for k in lag..rows.len() {
        let (now, then) = (&rows[k], &rows[k - lag]);
        if now.sample - then.sample != lag as u64 || !rows[k - lag..=k].iter().all(|r| r.running) {
            continue;
        }
        report.periods += 1;
        for joint in 0..joints {
            let what = format!("{file}: sample {}", then.sample);
            let Some(expected) = steps_of(then.joints[joint].0, &what)? else {
                report.undecidable += 1;
                continue;
            };
            let count = now.joints[joint].1;
            // The s32 count wraps; compare modulo 2^32.
            let diff = i64::from((count as i32).wrapping_sub(expected as i32));
            report.compared += 1;
            if k > lag && then.joints[joint].0 != rows[k - lag - 1].joints[joint].0 {
                report.moving += 1;
            }
            if diff != 0 && k > lag {
                // Where the record that ended at this latch crossed the rounding point
                // of the step it is short of.
                let (end, start) = (then.joints[joint].0, rows[k - lag - 1].joints[joint].0);
                let d = end - start;
                let sign = d.signum() as i64;
                let point = (expected as f64 - 0.5 * sign as f64) * 65536.0;
                let crossed = (point - start) / d * period_clocks;
                if d != 0.0 && diff == -sign && period_clocks - crossed <= window {
                    report.in_flight += 1;
                }
            }
            if diff != 0 {
                report.disagreements += 1;
                report.worst = report.worst.max(diff.abs());
                report.first.get_or_insert((now.sample, joint, count, expected));
            }
        }
    }
    // A stop while running: the first row not running after one running.
    if let Some(r) = (1..rows.len()).find(|&r| rows[r - 1].running && !rows[r].running) {
        let last = rows.last().map_or(&rows[r], |row| row);
        let mut stop = StopReport { sample: rows[r].sample, ..StopReport::default() };
        for joint in 0..joints {
            let end = last.joints[joint].1;
            stop.steps_after += rows[r + 1..].iter().filter(|row| row.joints[joint].1 != end).count();
            // Row r's read is the first after the driver stopped, in write r - 1: the
            // record of write r - 2 was running and was cut, the one of write r - 3 had
            // run. Their commands bound where each axis may stand.
            let what = format!("{file}: sample {}", rows[r].sample);
            let bounds: Vec<i64> = [3, 2]
                .iter()
                .filter_map(|&back| r.checked_sub(back))
                .map(|i| steps_of(rows[i].joints[joint].0, &what))
                .collect::<anyhow::Result<Option<Vec<i64>>>>()?
                .unwrap_or_default();
            if let (Some(&lo), Some(&hi)) = (bounds.iter().min(), bounds.iter().max()) {
                stop.beyond = stop.beyond.max((lo - end).max(end - hi).max(0));
            }
        }
        report.stop = Some(stop);
    }
    Ok(report)
}

/// `finestep-linuxcnc check SAMPLES --joints N [--expect-stop]`: prints the open-loop
/// figures, fails on any disagreement or lost sample, on a step after a stop or beyond
/// the command, and with `expect_stop` when the recording shows no stop.
pub fn check(
    samples: &Path,
    joints: usize,
    period_ns: f64,
    config_path: Option<&Path>,
    expect_stop: bool,
) -> anyhow::Result<()> {
    let name = samples.display().to_string();
    let text = std::fs::read_to_string(samples).with_context(|| format!("reading {name}"))?;
    let build = TopParams::default();
    let clock_hz = f64::from(build.clock_hz);
    let period_clocks = period_ns * 1e-9 * clock_hz;
    // With the drive timing: the longest a requested step may take to be counted
    // (the driver requests each period's last step earlier than that); without it, the
    // latch's lag and one round of the step engine's slots.
    let slots = build.core_params().step_slots();
    let latency = match config_path {
        Some(path) => {
            let config = MachineConfig::load(path)?;
            let timing = finestep_interface::DriveTiming::from_ns(config.drive.to_array(), clock_hz, u32::MAX)
                .with_context(|| format!("{}: drive timing", path.display()))?;
            count_latency_clocks(&timing, slots)
        }
        None => LATCH_LAG_CLOCKS + u64::from(slots - 1),
    };
    let window = latency as f64;
    let report = check_text(&text, joints, period_clocks, window, &name)?;
    println!(
        "  open loop: {} servo periods, {} joint-periods compared ({} moving): {} disagreements \
         (step count vs commanded position quantised to steps, {} periods later; {} of them one step \
         in flight, requested in the period's last {} clocks), worst {} steps; {} undecidable, {} samples lost",
        report.periods,
        report.compared,
        report.moving,
        report.disagreements,
        FEEDBACK_LAG_PERIODS,
        report.in_flight,
        window,
        report.worst,
        report.undecidable,
        report.lost
    );
    if let Some((first, last)) = report.motion {
        println!(
            "  LinuxCNC's trajectory: the command moved from period {first} to {last}: {} periods",
            last - first + 1
        );
    }
    if let Some(stop) = &report.stop {
        println!(
            "  stop at period {}: {} joint-periods with a step after it, final positions at most {} steps \
             beyond the last two commanded",
            stop.sample, stop.steps_after, stop.beyond
        );
    }
    if let Some((sample, joint, count, expected)) = report.first {
        println!("  first disagreement: sample {sample}, joint {joint}: count {count}, expected {expected}");
    }
    if report.periods == 0 {
        bail!("{name}: nothing to compare");
    }
    if expect_stop && report.stop.is_none() {
        bail!("{name}: the run was to be stopped, and the recording shows no stop");
    }
    if report.stop.as_ref().is_some_and(|stop| stop.steps_after != 0 || stop.beyond != 0) {
        bail!("{name}: steps after the stop, or beyond the commanded position");
    }
    // The driver requests every period's last step early enough for the latch to count
    // it, so a step in flight at the latch is a failure too (counted apart to say why).
    if report.disagreements != 0 || report.lost != 0 {
        bail!(
            "{name}: {} disagreements ({} in flight), {} samples lost",
            report.disagreements,
            report.in_flight,
            report.lost
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_check_counts_disagreements_at_the_lag_and_lost_samples() {
        // One joint at 800 steps/mm: 0.5 mm = 400 steps = 26 214 400 in 2^-16 steps.
        let text = "0 0.000000 0 1\n1 26214400.000000 0 1\n2 26214400.000000 0 1\n3 26214400.000000 400 1\n\
                    4 52428800.000000 400 1\n5 52428800.000000 400 1\n6 52428800.000000 799 1\n";
        let report = check_text(text, 1, 50_000.0, 2.0, "t").unwrap();
        assert_eq!((report.periods, report.disagreements, report.worst, report.lost), (5, 1, 1, 0));
        assert_eq!(report.first, Some((6, 0, 799, 800)));
        assert_eq!(report.in_flight, 0, "400 steps a period: the 800th crossed far from the end");
        assert_eq!(report.motion, Some((1, 4)));
        assert_eq!(report.stop, None);
        let gap = "0 0 0 1\n1 0 0 1\n3 0 0 1\n4 0 0 1\n5 0 0 1\n";
        let report = check_text(gap, 1, 50_000.0, 2.0, "t").unwrap();
        assert_eq!((report.periods, report.lost), (1, 1));
        let err = check_text("0 1.0 0\n", 1, 50_000.0, 2.0, "s.txt").unwrap_err().to_string();
        assert_eq!(err, "s.txt:1: expected a sample number, 1 pairs and the running bit");
        // Half a step rounds up, as the DDA does: 32768 in 2^-16 steps is step 1.
        let report = check_text("0 32768.0 0 1\n1 0 0 1\n2 0 1 1\n", 1, 50_000.0, 2.0, "t").unwrap();
        assert_eq!(report.disagreements, 0);
        // Not running: nothing compared.
        let report = check_text("0 655360 0 0\n1 655360 0 0\n2 655360 0 0\n", 1, 50_000.0, 2.0, "t").unwrap();
        assert_eq!((report.periods, report.disagreements), (0, 0));
    }

    #[test]
    fn a_step_short_at_the_latch_is_in_flight_only_when_requested_in_the_last_clocks() {
        // From 100 to 117.50002 steps in a period of 50 000 clocks: 117.5 crossed
        // 0.00002 / 17.50002 * 50 000 = 0.06 clocks before the end; the count of 117 is in
        // flight. At 117.6 it crossed 286 clocks before: 117 is a real disagreement.
        let row = |k: u64, steps: f64, count: i64| format!("{k} {} {count} 1\n", (steps * 65536.0).round());
        let text: String =
            [row(0, 100.0, 100), row(1, 117.50002, 100), row(2, 117.50002, 100), row(3, 117.50002, 117)].concat();
        let report = check_text(&text, 1, 50_000.0, 2.0, "t").unwrap();
        assert_eq!((report.disagreements, report.in_flight), (1, 1));
        let text: String = [row(0, 100.0, 100), row(1, 117.6, 100), row(2, 117.6, 100), row(3, 117.6, 117)].concat();
        let report = check_text(&text, 1, 50_000.0, 2.0, "t").unwrap();
        assert_eq!((report.disagreements, report.in_flight), (1, 0));
        // Moving down, one step short is one above.
        let text: String =
            [row(0, 100.0, 100), row(1, 82.49998, 100), row(2, 82.49998, 100), row(3, 82.49998, 83)].concat();
        let report = check_text(&text, 1, 50_000.0, 2.0, "t").unwrap();
        assert_eq!((report.disagreements, report.in_flight), (1, 1));
    }

    #[test]
    fn a_stop_mid_move_is_checked_for_steps_after_it_and_beyond_the_command() {
        // Commands 10, 11, 12 steps; stopped before sample 3 at 11: within the commands of
        // samples 0 and 1, the last two records sent.
        let row = |k: u64, cmd: i64, count: i64, running: u8| format!("{k} {} {count} {running}\n", cmd * 65536);
        let text: String =
            [row(0, 10, 10, 1), row(1, 11, 10, 1), row(2, 12, 10, 1), row(3, 11, 11, 0), row(4, 11, 11, 0)].concat();
        let report = check_text(&text, 1, 50_000.0, 2.0, "t").unwrap();
        assert_eq!(report.stop, Some(StopReport { sample: 3, steps_after: 0, beyond: 0 }));
        // A step after the stop, and one beyond the command.
        let text: String =
            [row(0, 10, 10, 1), row(1, 11, 10, 1), row(2, 12, 10, 1), row(3, 12, 11, 0), row(4, 12, 13, 0)].concat();
        let report = check_text(&text, 1, 50_000.0, 2.0, "t").unwrap();
        assert_eq!(report.stop, Some(StopReport { sample: 3, steps_after: 0, beyond: 2 }));
        let text: String = [
            row(0, 10, 10, 1),
            row(1, 11, 10, 1),
            row(2, 12, 10, 1),
            row(3, 12, 11, 0),
            row(4, 12, 12, 0),
            row(5, 12, 11, 0),
        ]
        .concat();
        let report = check_text(&text, 1, 50_000.0, 2.0, "t").unwrap();
        assert_eq!(report.stop, Some(StopReport { sample: 3, steps_after: 1, beyond: 0 }));
    }

    #[test]
    fn the_generated_files_name_every_joint_and_the_pins_hostmot2_names() {
        let config = MachineConfig::from_toml_str(
            "[axes.X]\nsteps_per_unit = 800.0\n[axes.Y]\nsteps_per_unit = 800.0\n[axes.Z]\nsteps_per_unit = 400.0\n",
            "m.toml",
        )
        .unwrap();
        let (joints, config, period_s) = joints(config, "m.toml").unwrap();
        assert_eq!(joints.iter().map(|j| j.slot).collect::<Vec<_>>(), [0, 1, 2]);
        let ini = ini(&joints, &config, period_s, "/x/headless.py", "m.toml", true, None);
        assert!(ini.contains("SERVO_PERIOD = 1000000\n"), "{ini}");
        assert!(ini.contains("[JOINT_2]\nTYPE = LINEAR\n") && ini.contains("SCALE = 400\n"), "{ini}");
        assert!(ini.contains("KINEMATICS = trivkins coordinates=XYZ\nJOINTS = 3\n"), "{ini}");
        assert!(ini.contains("HALFILE = record.hal\n"), "{ini}");
        let hal = hal(&joints, "sim:/tmp/c.sock", "m.toml");
        assert!(hal.contains("loadrt finestep bus=sim:/tmp/c.sock\n"), "{hal}");
        assert!(hal.contains("net j2-pos-cmd joint.2.motor-pos-cmd => finestep.0.stepgen.02.position-cmd\n"), "{hal}");
        let record = record_hal(&joints);
        assert!(record.contains("cfg=fsfsfsb\n") && record.contains("setp scale.2.gain 2.62144e7\n"), "{record}");
        let (four, config, period_s) = super::joints(MachineConfig::default(), "d.toml").unwrap();
        let text = super::ini(&four, &config, period_s, "axis", "d.toml", false, None);
        assert!(
            text.contains("[JOINT_3]\nTYPE = ANGULAR\n") && text.contains("coordinates=XYZA\nJOINTS = 4\n"),
            "{text}"
        );
        assert!(!text.contains("record.hal"), "{text}");
    }
}

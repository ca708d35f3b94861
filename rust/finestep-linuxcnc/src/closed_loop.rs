//! Closed loop (docs/linuxcnc.md#closed-loop): the same mill with encoders through
//! LinuxCNC's `pid`, on the simulated closed-loop machine (`finestep_plant::PlantConfig::lagging`:
//! drives lagging their step pins, a linear grating on each), with either step generator:
//!
//! - [`Loop::Finestep`]: the `finestep` HAL component, its stepgens' `position-cmd` from
//!   the PID, its encoders as feedback; the machine on the simulated chip's pins
//!   (`finestep sim-chip --lag-clocks`);
//! - [`Loop::Stepgen`]: LinuxCNC's software `stepgen` in the base thread, its step/dir
//!   into the `fsplant` HAL component (the same plant, `rust/finestep-hal-plant`), the
//!   gratings' counts as feedback.
//!
//! Both get the same PID tuning, the same joint limits and the same stepgen limits from
//! the INI this module writes; `ferror` gives each joint's peak and RMS following error
//! over a recording.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::{bail, Context};

use crate::joints::Joint;

/// The closed-loop machine: the drives' lag time constant, core clocks (1 ms at 50 MHz:
/// a drive that takes a servo period to follow).
pub const LAG_CLOCKS: u64 = 50_000;

/// The gratings' counts per step.
pub const COUNTS_PER_STEP: u32 = 1;

/// LinuxCNC's base thread for the software stepgen, ns: the fastest step/dir at the
/// sample mill's timing (one base period high, one low) is then 100 kHz, over the
/// stepgen limit of X and Y (1.25 times 50 mm/s at 800 steps/mm: 50 kHz; stepgen refuses
/// that with a 10 µs base period); the simulated chip's clock makes it 250 clocks.
pub const BASE_PERIOD_NS: u64 = 5_000;

/// The PID tuning both loops get unless `--pid` says otherwise (pid(9)'s gains, as the
/// INI's [JOINT_n] keys): the output is a position command (FF0 = 1 passes the joint's
/// command through), corrected by P times the following error; no velocity feed-forward,
/// so the figures show each loop's own delay.
pub const PID: [(&str, f64); 9] = [
    ("P", 0.25),
    ("I", 0.0),
    ("D", 0.0),
    ("FF0", 1.0),
    ("FF1", 0.0),
    ("FF2", 0.0),
    ("BIAS", 0.0),
    ("DEADBAND", 0.0),
    ("MAX_OUTPUT", 0.0),
];

/// pid(9)'s parameter for each INI key of [`PID`].
const PID_PARAMS: [(&str, &str); 9] = [
    ("P", "Pgain"),
    ("I", "Igain"),
    ("D", "Dgain"),
    ("FF0", "FF0"),
    ("FF1", "FF1"),
    ("FF2", "FF2"),
    ("BIAS", "bias"),
    ("DEADBAND", "deadband"),
    ("MAX_OUTPUT", "maxoutput"),
];

/// Which step generator closes the loop.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Loop {
    /// Open loop on the finestep chip (its step counts as feedback).
    Open,
    /// finestep's stepgens and encoders, PID in between, the plant on the chip's pins.
    Finestep,
    /// LinuxCNC's software stepgen into the same plant (`fsplant`), PID in between.
    Stepgen,
}

/// The PID tuning: [`PID`] with `overrides` (`KEY=VALUE,...`, keys of [`PID`]) applied.
pub fn tuning(overrides: Option<&str>) -> anyhow::Result<Vec<(&'static str, f64)>> {
    let mut gains = PID.to_vec();
    for item in overrides.unwrap_or("").split(',').map(str::trim).filter(|s| !s.is_empty()) {
        let (key, value) = item.split_once('=').with_context(|| format!("--pid: `{item}` is not KEY=VALUE"))?;
        let value: f64 = value.trim().parse().with_context(|| format!("--pid: `{item}`: not a number"))?;
        let Some(gain) = gains.iter_mut().find(|(k, _)| k.eq_ignore_ascii_case(key.trim())) else {
            bail!("--pid: unknown key `{key}` (one of {})", PID.map(|(k, _)| k).join(", "));
        };
        gain.1 = value;
    }
    Ok(gains)
}

/// The INI lines a closed loop adds: [EMCMOT]BASE_PERIOD for the software stepgen (as
/// `(key, value)` for [EMCMOT]) and the [PLANT] section.
pub fn ini_plant(clock_hz: u32) -> String {
    format!(
        "[PLANT]\n# The simulated closed-loop machine (finestep_plant::PlantConfig::lagging), for the\n\
         # simulated chip (finestep sim-chip --lag-clocks) and fsplant alike.\n\
         LAG_CLOCKS = {LAG_CLOCKS}\nCOUNTS_PER_STEP = {COUNTS_PER_STEP}\nCLOCK_HZ = {clock_hz}\n\n"
    )
}

/// A joint's closed-loop INI keys: the PID tuning, the encoder scale, the software
/// stepgen's acceleration limit.
pub fn ini_joint(joint: &Joint, gains: &[(&str, f64)]) -> String {
    let mut text = String::from("# Closed loop: PID (pid(9)) from the joint's command and the grating's position.\n");
    for (key, value) in gains {
        let _ = writeln!(text, "{key} = {value}");
    }
    let _ = write!(
        text,
        "ENCODER_SCALE = {encoder}\nSTEPGEN_MAXACCEL = {accel}\n",
        encoder = joint.scale * f64::from(COUNTS_PER_STEP),
        accel = joint.max_acceleration * 1.25,
    );
    text
}

/// The HAL of a closed loop.
pub fn hal(joints: &[Joint], bus: &str, name: &str, which: Loop) -> String {
    let n = joints.len();
    let flag = if which == Loop::Stepgen { "stepgen" } else { "finestep" };
    let mut text = format!(
        "# Generated by `finestep-linuxcnc config --loop {flag}` from {name}: regenerate, do not edit.\n\
         loadrt [KINS]KINEMATICS\n"
    );
    match which {
        Loop::Stepgen => {
            let types = vec!["0"; n].join(",");
            let _ = write!(
                text,
                "loadrt [EMCMOT]EMCMOT servo_period_nsec=[EMCMOT]SERVO_PERIOD num_joints=[KINS]JOINTS\n\
                 loadrt stepgen step_type={types}\n\
                 loadrt fsplant axes={n} lag_clocks=[PLANT]LAG_CLOCKS counts_per_step=[PLANT]COUNTS_PER_STEP \
                 clock_hz=[PLANT]CLOCK_HZ base_ns=[EMCMOT]BASE_PERIOD servo_ns=[EMCMOT]SERVO_PERIOD\n\
                 loadrt pid num_chan={n}\n\n\
                 # No base thread: fsplant.0.run calls stepgen.make-pulses once per base period\n\
                 # ([EMCMOT]BASE_PERIOD) after stepgen.update-freq (linuxcnc/fsplant.c says why).\n\
                 addf fsplant.0.read servo-thread\n\
                 addf motion-command-handler servo-thread\n\
                 addf motion-controller servo-thread\n"
            );
        }
        Loop::Finestep | Loop::Open => {
            let _ = write!(
                text,
                "loadrt [EMCMOT]EMCMOT servo_period_nsec=[EMCMOT]SERVO_PERIOD num_joints=[KINS]JOINTS\n\
                 loadrt finestep bus={bus}\n\
                 loadrt pid num_chan={n}\n\n\
                 # One coherent latched read first, one period record last.\n\
                 addf finestep.0.read servo-thread\n\
                 addf motion-command-handler servo-thread\n\
                 addf motion-controller servo-thread\n"
            );
        }
    }
    for index in 0..n {
        let _ = writeln!(text, "addf pid.{index}.do-pid-calcs servo-thread");
    }
    match which {
        Loop::Stepgen => text.push_str(
            "addf stepgen.update-freq servo-thread\naddf fsplant.0.run servo-thread\n\n\
             # No E-stop input on this machine: LinuxCNC's enable loops back.\n\
             net estop-loop iocontrol.0.user-enable-out => iocontrol.0.emc-enable-in\n",
        ),
        Loop::Finestep | Loop::Open => text.push_str(
            "addf finestep.0.write servo-thread\n\n\
             # E-stop chain as iocontrol wires it (as in open loop).\n\
             net estop-out iocontrol.0.user-enable-out => finestep.0.enable\n\
             net estop-ok finestep.0.estop-ok => iocontrol.0.emc-enable-in\n",
        ),
    }
    text.push_str(
        "net tool-change-loop iocontrol.0.tool-change => iocontrol.0.tool-changed\n\
         net tool-prep-loop iocontrol.0.tool-prepare => iocontrol.0.tool-prepared\n",
    );
    for (index, joint) in joints.iter().enumerate() {
        let (sg, enc, cmd_pin) = match which {
            Loop::Stepgen => (
                format!("stepgen.{index}"),
                format!("fsplant.0.encoder.{index:02}"),
                format!("stepgen.{index}.position-cmd"),
            ),
            Loop::Finestep | Loop::Open => {
                let sg = format!("finestep.0.stepgen.{:02}", joint.slot);
                let cmd = format!("{sg}.position-cmd");
                (sg, format!("finestep.0.encoder.{:02}", joint.slot), cmd)
            }
        };
        let _ = write!(
            text,
            "\n# Joint {index}: axis {axis}.\n\
             setp {sg}.position-scale [JOINT_{index}]SCALE\n\
             setp {sg}.maxvel [JOINT_{index}]STEPGEN_MAXVEL\n\
             setp {sg}.steplen [JOINT_{index}]STEPLEN\n\
             setp {sg}.stepspace [JOINT_{index}]STEPSPACE\n\
             setp {sg}.dirsetup [JOINT_{index}]DIRSETUP\n\
             setp {sg}.dirhold [JOINT_{index}]DIRHOLD\n\
             setp {enc}.scale [JOINT_{index}]ENCODER_SCALE\n",
            axis = joint.name,
        );
        match which {
            Loop::Stepgen => {
                let _ = write!(
                    text,
                    "setp {sg}.maxaccel [JOINT_{index}]STEPGEN_MAXACCEL\n\
                     net j{index}-step {sg}.step => fsplant.0.axis.{index}.step\n\
                     net j{index}-dir {sg}.dir => fsplant.0.axis.{index}.dir\n"
                );
            }
            Loop::Finestep | Loop::Open => {
                let _ = writeln!(text, "setp {sg}.step_type 0");
            }
        }
        for (key, param) in PID_PARAMS {
            let _ = writeln!(text, "setp pid.{index}.{param} [JOINT_{index}]{key}");
        }
        let _ = write!(
            text,
            "net j{index}-pos-cmd joint.{index}.motor-pos-cmd => pid.{index}.command\n\
             net j{index}-pos-fb {enc}.position => pid.{index}.feedback joint.{index}.motor-pos-fb\n\
             net j{index}-output pid.{index}.output => {cmd_pin}\n\
             net j{index}-enable joint.{index}.amp-enable-out => {sg}.enable pid.{index}.enable\n"
        );
    }
    text
}

/// Samples, every servo period: per joint LinuxCNC's following error (`joint.N.f-error`)
/// and its command, then whether motion is enabled and the plant's lost locksteps
/// (`fsplant.0.sync-errors`; 0 on the chip).
pub fn record_hal(joints: &[Joint], which: Loop) -> String {
    let n = joints.len();
    let mut text = format!(
        "# Generated by `finestep-linuxcnc config --record`: the closed loop's recording.\n\
         loadrt sampler depth=16384 cfg={}bu\n\
         net motion-enabled motion.motion-enabled => sampler.0.pin.{}\n",
        "ff".repeat(n),
        2 * n
    );
    if which == Loop::Stepgen {
        let _ = writeln!(text, "net plant-sync-errors fsplant.0.sync-errors => sampler.0.pin.{}", 2 * n + 1);
    }
    for index in 0..n {
        let _ = write!(
            text,
            "net j{index}-ferror joint.{index}.f-error => sampler.0.pin.{e}\n\
             net j{index}-pos-cmd sampler.0.pin.{c}\n",
            e = 2 * index,
            c = 2 * index + 1
        );
    }
    text.push_str("addf sampler.0 servo-thread\n");
    text
}

/// One joint's following error over a run.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Ferror {
    /// Largest |f-error|, machine units, over the periods motion was enabled.
    pub peak: f64,
    /// Root mean square of f-error over the periods the command moved (first to last
    /// period any joint's command changed).
    pub rms: f64,
}

/// What `ferror` found in a recording.
#[derive(Debug, Default, PartialEq)]
pub struct FerrorReport {
    /// Per joint.
    pub joints: Vec<Ferror>,
    /// Periods in the moving span.
    pub moving: usize,
    /// Samples lost by the sampler.
    pub lost: u64,
    /// The plant's lost locksteps at the end (fsplant; 0 on the chip).
    pub sync_errors: u64,
}

/// Peak and RMS following error per joint over a `halsampler -t` recording of
/// [`record_hal`].
pub fn ferror_text(text: &str, joints: usize, file: &str) -> anyhow::Result<FerrorReport> {
    // (sample, per joint (f-error, command), motion enabled, lost locksteps)
    type Row = (u64, Vec<(f64, f64)>, bool, u64);
    let mut rows: Vec<Row> = Vec::new();
    for (line_no, line) in text.lines().enumerate() {
        let fields: Vec<&str> = line.split_whitespace().collect();
        if fields.is_empty() {
            continue;
        }
        let bad =
            || anyhow::anyhow!("{file}:{}: expected a sample number, {joints} pairs, a bit and a count", line_no + 1);
        if fields.len() != 3 + 2 * joints {
            return Err(bad());
        }
        let sample: u64 = fields[0].parse().map_err(|_| bad())?;
        let pairs = fields[1..=2 * joints]
            .chunks(2)
            .map(|p| Ok((p[0].parse::<f64>().map_err(|_| bad())?, p[1].parse::<f64>().map_err(|_| bad())?)))
            .collect::<anyhow::Result<Vec<_>>>()?;
        let enabled = match fields[1 + 2 * joints] {
            "0" => false,
            "1" => true,
            _ => return Err(bad()),
        };
        let errors: u64 = fields[2 + 2 * joints].parse().map_err(|_| bad())?;
        rows.push((sample, pairs, enabled, errors));
    }
    let mut report = FerrorReport { joints: vec![Ferror::default(); joints], ..FerrorReport::default() };
    let mut first = None;
    let mut last = 0;
    for (r, pair) in rows.windows(2).enumerate() {
        report.lost += pair[1].0.saturating_sub(pair[0].0 + 1);
        if pair[1].1.iter().zip(&pair[0].1).any(|(now, before)| now.1 != before.1) {
            first.get_or_insert(r + 1);
            last = r + 1;
        }
    }
    report.sync_errors = rows.last().map_or(0, |row| row.3);
    for row in rows.iter().filter(|row| row.2) {
        for (joint, &(ferror, _)) in report.joints.iter_mut().zip(&row.1) {
            joint.peak = joint.peak.max(ferror.abs());
        }
    }
    if let Some(first) = first {
        let span = &rows[first..=last];
        report.moving = span.len();
        for (j, joint) in report.joints.iter_mut().enumerate() {
            let sum: f64 = span.iter().map(|row| row.1[j].0 * row.1[j].0).sum();
            joint.rms = (sum / span.len() as f64).sqrt();
        }
    }
    Ok(report)
}

/// `finestep-linuxcnc ferror SAMPLES --joints N`: prints one line per joint (peak, RMS in
/// machine units and in steps) and fails on lost samples, lost locksteps or no motion.
pub fn ferror(samples: &Path, joints: usize, names: &str, scales: &[f64]) -> anyhow::Result<()> {
    let name = samples.display().to_string();
    let text = std::fs::read_to_string(samples).with_context(|| format!("reading {name}"))?;
    let report = ferror_text(&text, joints, &name)?;
    println!(
        "  closed loop: {} moving periods, {} samples lost, {} lost locksteps",
        report.moving, report.lost, report.sync_errors
    );
    for (j, joint) in report.joints.iter().enumerate() {
        let axis = names.chars().nth(j).unwrap_or('?');
        let scale = scales.get(j).copied().unwrap_or(1.0);
        println!(
            "  ferror {axis}: peak {:.6} RMS {:.6} (units); peak {:.2} RMS {:.2} (steps)",
            joint.peak,
            joint.rms,
            joint.peak * scale,
            joint.rms * scale
        );
    }
    if report.moving == 0 {
        bail!("{name}: no motion recorded");
    }
    if report.lost != 0 || report.sync_errors != 0 {
        bail!("{name}: {} samples lost, {} lost locksteps", report.lost, report.sync_errors);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn peak_over_the_enabled_periods_and_rms_over_the_moving_span() {
        // Two joints; joint 0's command moves in samples 1..=3.
        let text = "0 0.5 0.0 0.0 0.0 0 0\n1 0.1 1.0 0.0 0.0 1 0\n2 -0.2 2.0 0.02 0.0 1 0\n\
                    3 0.2 3.0 0.0 0.0 1 0\n4 0.0 3.0 0.0 0.0 1 0\n";
        let report = ferror_text(text, 2, "t").unwrap();
        assert_eq!(report.moving, 3);
        assert_eq!(report.joints[0].peak, 0.2, "sample 0 is not enabled");
        assert!((report.joints[0].rms - (0.09f64 / 3.0).sqrt()).abs() < 1e-12);
        assert_eq!(report.joints[1].peak, 0.02);
        assert_eq!((report.lost, report.sync_errors), (0, 0));
        let report = ferror_text("0 0 0 1 0\n2 0 1 1 3\n", 1, "t").unwrap();
        assert_eq!((report.lost, report.sync_errors), (1, 3));
        assert!(ferror_text("0 0 0 1\n", 1, "s").unwrap_err().to_string().starts_with("s:1: expected"));
    }

    #[test]
    fn the_tuning_takes_overrides_by_key() {
        let gains = tuning(Some("p=0.5, FF1=0.002")).unwrap();
        assert!(gains.contains(&("P", 0.5)) && gains.contains(&("FF1", 0.002)) && gains.contains(&("FF0", 1.0)));
        assert!(tuning(Some("Q=1")).is_err());
        assert!(tuning(Some("P")).is_err());
        assert_eq!(tuning(None).unwrap(), PID.to_vec());
    }
}

//! `finestep-linuxcnc check --socket SOCKET`: the step timing at the simulated chip's pins.
//! `finestep sim-chip` measures every axis's step and direction pins every clock it
//! simulates against the drive timing the driver wrote (`finestep_interface::pin_timing`);
//! after the run this asks it for the figures (the sim link's pin-timing request), prints
//! the shortest step high, step low, direction set-up and hold per axis beside the
//! configured `steplen`/`stepspace`/`dirsetup`/`dirhold`, and fails on any violation.

use anyhow::{bail, Context};
use finestep_host::sim_link::SimSocket;
use finestep_host::{PinTimingReport, SpiTransfer};

/// Clocks as nanoseconds at `clock_hz`.
fn ns(clocks: u64, clock_hz: u32) -> f64 {
    clocks as f64 * 1e9 / f64::from(clock_hz.max(1))
}

/// The report as lines (one per axis) and whether it passes: no broken rule, and every
/// axis that stepped measured as step/dir.
pub fn describe(report: &PinTimingReport) -> (Vec<String>, bool) {
    let hz = report.clock_hz;
    let mut lines = vec![format!(
        "  step timing at the pins, every clock of {} ({:.3} s of chip time): {} violations of the configured \
         steplen/stepspace/dirsetup/dirhold",
        report.clocks,
        report.clocks as f64 / f64::from(hz.max(1)),
        report.violations()
    )];
    let mut ok = report.violations() == 0;
    for (axis, a) in report.axes.iter().enumerate() {
        let f = &a.figures;
        if !a.step_dir {
            lines.push(format!("    axis {axis}: not in step/dir mode, not measured"));
            ok &= f.steps == 0;
            continue;
        }
        let shown = |value: Option<u64>, want: u32| match value {
            Some(v) => format!("{v} ({:.0} ns, >= {} ns)", ns(v, hz), ns(u64::from(want.max(1)), hz)),
            None => "-".to_string(),
        };
        let t = f.timing;
        lines.push(format!(
            "    axis {axis}: {} steps; shortest high {}, low {}, dir setup {}, dir hold {}; {} violations",
            f.steps,
            shown(f.high_min, t.step_len),
            shown(f.low_min, t.step_space),
            shown(f.setup_min, t.dir_setup),
            shown(f.hold_min, t.dir_hold),
            f.violations
        ));
        if let Some(v) = f.first {
            lines.push(format!("      first violation: {v}"));
        }
    }
    (lines, ok)
}

/// Asks the chip at `socket` for its pin timing, prints it and fails on a violation.
pub fn run(socket: &str) -> anyhow::Result<()> {
    let mut link = SimSocket::connect(socket).with_context(|| format!("sim:{socket}"))?;
    let report = link
        .pin_timing()
        .with_context(|| format!("sim:{socket}: the pin-timing request"))?
        .with_context(|| format!("sim:{socket}: no pin timing"))?;
    let (lines, ok) = describe(&report);
    for line in &lines {
        println!("{line}");
    }
    if !ok {
        bail!("the step timing at the chip's pins broke the configured drive timing");
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use finestep_interface::pin_timing::{AxisPinTiming, StepDirMonitor};
    use finestep_interface::DriveTiming;

    /// Step pulses high for `high` clocks every 10 clocks on one axis, after a `dir` edge.
    fn report(high: u64) -> PinTimingReport {
        let pins: Vec<(bool, bool)> = (0..100u64).map(|c| (c >= 20 && c % 10 < high, c >= 5)).collect();
        let figures = StepDirMonitor::measure(&pins, 0, DriveTiming::new(3, 3, 2, 2));
        PinTimingReport { clock_hz: 50_000_000, clocks: 100, axes: vec![AxisPinTiming { step_dir: true, figures }] }
    }

    #[test]
    fn a_short_pulse_fails_the_check_and_pulses_within_the_timing_pass() {
        let (lines, ok) = describe(&report(3));
        assert!(ok, "{lines:?}");
        assert!(lines[1].contains("8 steps; shortest high 3 (60 ns, >= 60 ns), low 7"), "{lines:?}");
        let (lines, ok) = describe(&report(2));
        assert!(!ok, "{lines:?}");
        assert!(lines[0].contains("8 violations"), "{lines:?}");
        assert!(lines[2].contains("first violation: cycle 22: steplen 2 clocks, want >= 3"), "{lines:?}");
    }
}

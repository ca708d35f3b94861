//! `finestep run FILE.ngc`: a part program through the planner, checked by the
//! independent checker and plotted, then into the core, in lockstep co-simulation (RTL
//! against the model) or through the model's fast path.

use std::path::Path;

use anyhow::{bail, Context};
use finestep_cosim::{Harness, ModelPath};
use finestep_model::{AxisConfig, Core, CoreInputs, CoreParams};
use finestep_planner::config::AXIS_NAMES;
use finestep_planner::{check_program, plan_program, CheckReport, MachineConfig, ProfileKind};
use indicatif::{ProgressBar, ProgressStyle};

use crate::plot::{plot_motion, plot_toolpath};

const AXIS_UNITS: [&str; 4] = ["mm", "mm", "mm", "deg"];

fn print_check(report: &CheckReport) {
    println!("  axis  max velocity / limit        max acceleration / limit     max jerk / limit  (units/s, /s^2, /s^3)");
    for a in (0..4).filter(|&a| report.axis_present[a]) {
        let [v, acc, j] = report.axis_max[a];
        let [lv, la, lj] = report.axis_limit[a];
        let jerk_limit = if lj.is_finite() { format!("{lj:.0}") } else { "- (trapezoid)".to_string() };
        println!("  {:<4} {v:>10.3} / {lv:<12.3} {acc:>12.2} / {la:<12.1} {j:>12.0} / {jerk_limit}", AXIS_NAMES[a]);
    }
    println!(
        "  path: max speed {:.3}, at most {:.1} % of the programmed feed; max acceleration {:.1}, max jerk {:.0}",
        report.path_max[0],
        report.max_feed_ratio * 100.0,
        report.path_max[1],
        report.path_max[2]
    );
    println!(
        "  max path deviation {:.5} mm (line {}), {} exact stops on the step",
        report.max_deviation, report.max_deviation_line, report.exact_stops
    );
    if report.passed() {
        println!("  checker: every limit held (quantisation tolerance: 2^-17 steps per position)");
    } else {
        println!("  checker: {} violations; the first:", report.violation_count);
        for v in &report.violations {
            println!("    {v}");
        }
    }
}

pub fn run(file: &Path, fast: bool, config_path: Option<&Path>, profile: Option<&str>, out: &Path) -> anyhow::Result<()> {
    let mut config = match config_path {
        Some(path) => MachineConfig::load(path)?,
        None => MachineConfig::default(),
    };
    match profile {
        Some("trapezoid") => config.profile = ProfileKind::Trapezoid,
        Some("s-curve") => config.profile = ProfileKind::SCurve,
        _ => {}
    }
    let resolved = config.resolve()?;
    let program = finestep_gcode::parse_file(file)?;
    let planned = plan_program(&config, &program).map_err(|e| anyhow::anyhow!("{}:{}: {}", file.display(), e.line, e.reason))?;
    let records = &planned.records;
    for note in &planned.notes {
        println!("  note: {note}");
    }
    println!(
        "finestep run {}: {} elements, {} periods of {} ms: {:.3} s of machining ({:?} profile), {}",
        file.display(),
        planned.elements,
        records.len(),
        resolved.period_s * 1e3,
        records.len() as f64 * resolved.period_s,
        resolved.profile,
        if fast { "model fast path" } else { "RTL in lockstep with the model, every pin every clock" }
    );
    let report = check_program(&config, &program, records)?;
    print_check(&report);
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let stem = file.file_stem().map(|s| s.to_string_lossy().to_string()).unwrap_or_else(|| "run".into());
    let toolpath = out.join(format!("{stem}-toolpath.png"));
    let motion = out.join(format!("{stem}-motion.png"));
    plot_toolpath(&toolpath, &report.samples)?;
    plot_motion(&motion, &report.samples, report.period_s)?;
    println!("  plots: {} {}", toolpath.display(), motion.display());

    let period_clocks = resolved.period_clocks;
    let mut inputs = CoreInputs { run: true, period_clocks, ..Default::default() };
    for (axis, timing) in inputs.axes.iter_mut().zip(&resolved.timing) {
        *axis = AxisConfig {
            step_len: timing.step_len,
            step_space: timing.step_space,
            dir_setup: timing.dir_setup,
            dir_hold: timing.dir_hold,
            mode: 0,
            invert: 0,
            enable: true,
        };
    }
    let progress = ProgressBar::new(records.len() as u64)
        .with_style(ProgressStyle::with_template("  {bar:40} {pos}/{len} periods {per_sec} {msg}")?);
    let drain = 2 * u64::from(period_clocks);
    let (positions, cycles) = if fast {
        let mut core = Core::new(CoreParams::default());
        let mut events = Vec::new();
        inputs.rec_valid = true;
        for (index, record) in records.iter().enumerate() {
            inputs.record = *record;
            while !core.run_chunk_fast(&inputs, u64::MAX, &mut events).consumed {}
            events.clear();
            if index % 1024 == 0 {
                progress.set_position(index as u64);
                progress.set_message(format!("line {}", planned.lines[index]));
            }
        }
        inputs.rec_valid = false;
        core.run_chunk_fast(&inputs, drain, &mut events);
        (core.outputs().positions, core.cycle())
    } else {
        let mut harness = Harness::new("run", ModelPath::PerClock);
        for (index, record) in records.iter().enumerate() {
            harness.feed(&mut inputs, [*record]).map_err(|m| anyhow::anyhow!("{m}"))?;
            if index % 16 == 0 {
                progress.set_position(index as u64);
                progress.set_message(format!("line {}", planned.lines[index]));
            }
        }
        harness.idle(&inputs, drain).map_err(|m| anyhow::anyhow!("{m}"))?;
        (harness.outputs().positions, harness.cycle())
    };
    progress.finish_and_clear();

    println!("  axis   final steps   final position   programmed end   error");
    let mut worst = 0i64;
    for axis in (0..4).filter(|&a| resolved.axes[a].present) {
        let scale = resolved.axes[axis].steps_per_unit;
        let steps = i64::from(positions[axis] as i32);
        let target = (planned.end[axis] * scale).round() as i64;
        worst = worst.max((steps - target).abs());
        println!(
            "  {:<4} {:>12} {:>12.4} {:<3} {:>12.4} {:<3} {:>4} steps",
            AXIS_NAMES[axis],
            steps,
            steps as f64 / scale,
            AXIS_UNITS[axis],
            planned.end[axis],
            AXIS_UNITS[axis],
            steps - target
        );
    }
    println!("  {cycles} clock cycles{}", if fast { "" } else { ", bit-exact RTL against the model" });
    if worst != 0 {
        bail!("the pulse train ended {worst} steps from the programmed end");
    }
    if !report.passed() {
        bail!("the checker found {} violations", report.violation_count);
    }
    Ok(())
}

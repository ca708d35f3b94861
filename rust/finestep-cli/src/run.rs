//! `finestep run FILE.ngc`: a part program through the planner, checked by the
//! independent checker and plotted, then into the chip: streamed over SPI by the host
//! driver into the bus-level top, RTL in lockstep with the model, or through the model
//! core's fast path.

use std::path::Path;

use anyhow::{anyhow, bail, Context};
use finestep_gcode::Program;
use finestep_host::stream::{self, StreamEvent};
use finestep_model::{Core, CoreInputs};
use finestep_planner::config::AXIS_NAMES;
use finestep_planner::{check_program, plan_program, CheckReport, MachineConfig, ProfileKind};
use indicatif::{ProgressBar, ProgressStyle};

use crate::bus::BusTarget;
use crate::machine_setup;
use crate::plot::{plot_motion, plot_toolpath};

const AXIS_UNITS: [&str; 4] = ["mm", "mm", "mm", "deg"];

fn print_check(report: &CheckReport) {
    println!(
        "  axis  max velocity / limit        max acceleration / limit     max jerk / limit  (units/s, /s^2, /s^3)"
    );
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

pub fn run(
    file: &Path,
    fast: bool,
    bus: Option<BusTarget>,
    config_path: Option<&Path>,
    profile: Option<&str>,
    out: &Path,
) -> anyhow::Result<()> {
    let (mut config, config_name) = match config_path {
        Some(path) => (crate::config_file::load(path)?, path.display().to_string()),
        None => (MachineConfig::default(), "<built-in>".to_string()),
    };
    match profile {
        Some("trapezoid") => config.profile = ProfileKind::Trapezoid,
        Some("s-curve") => config.profile = ProfileKind::SCurve,
        _ => {}
    }
    let bus = BusTarget::choose(bus, config.bus.as_deref(), &config_name)?;
    let program = finestep_gcode::parse_file(file)?;
    run_program_on(&program, &file.display().to_string(), fast, &bus, config, &config_name, out)
}

/// Plans, checks, plots and runs `program` (named `name` in messages and plot files) on
/// the machine `config` (named `config_name` in errors): on the chip, whose CAPS and
/// clock the configuration is resolved against, or with `fast` on the model's build.
pub fn run_program(
    program: &Program,
    name: &str,
    fast: bool,
    config: MachineConfig,
    config_name: &str,
    out: &Path,
) -> anyhow::Result<()> {
    run_program_on(program, name, fast, &BusTarget::Lockstep, config, config_name, out)
}

/// [`run_program`] with the chip on `bus` (unused with `fast`).
pub fn run_program_on(
    program: &Program,
    name: &str,
    fast: bool,
    bus: &BusTarget,
    config: MachineConfig,
    config_name: &str,
    out: &Path,
) -> anyhow::Result<()> {
    let stem = Path::new(name).file_stem().map(|s| s.to_string_lossy().to_string()).unwrap_or_else(|| "run".into());
    let clock_hz = config.clock_hz.map_or(machine_setup::model_params().clock_hz, |hz| hz as u32);
    let mut chip = if fast { None } else { Some(crate::bus::open(bus, &stem, clock_hz)?) };
    let core = match &chip {
        Some(chip) => machine_setup::chip_limits(&chip.caps()),
        None => machine_setup::model_limits(),
    };
    let (config, resolved) = machine_setup::resolve(config, core, config_name)?;
    let planned = plan_program(&config, program).map_err(|e| anyhow!("{name}:{}: {}", e.line, e.reason))?;
    let records = &planned.records;
    for note in &planned.notes {
        println!("  note: {note}");
    }
    println!(
        "finestep run {}: {} elements, {} periods of {} ms: {:.3} s of machining ({:?} profile), {}",
        name,
        planned.elements,
        records.len(),
        resolved.period_s * 1e3,
        records.len() as f64 * resolved.period_s,
        resolved.profile,
        if fast {
            "model fast path".to_string()
        } else if bus.is_lockstep() {
            "streamed over SPI; RTL in lockstep with the model, every pin every clock".to_string()
        } else {
            format!("streamed over SPI on {bus}")
        }
    );
    let report = check_program(&config, program, records)?;
    print_check(&report);
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let toolpath = out.join(format!("{stem}-toolpath.png"));
    let motion = out.join(format!("{stem}-motion.png"));
    plot_toolpath(&toolpath, &report.samples)?;
    plot_motion(&motion, &report.samples, report.period_s)?;
    println!("  plots: {} {}", toolpath.display(), motion.display());

    let period_clocks = resolved.period_clocks;
    let progress = ProgressBar::new(records.len() as u64)
        .with_style(ProgressStyle::with_template("  {bar:40} {pos}/{len} periods {per_sec} {msg}")?);
    let drain = 2 * u64::from(period_clocks);
    let (positions, cycles) = match &mut chip {
        None => {
            let mut inputs = CoreInputs { run: true, period_clocks, rec_valid: true, ..Default::default() };
            for (axis, slot) in inputs.axes.iter_mut().enumerate().take(resolved.timing.len()) {
                *slot = machine_setup::axis_config(&resolved, axis);
            }
            let mut core = Core::new(machine_setup::model_core_params());
            let mut events = Vec::new();
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
            (core.outputs().positions.map(|p| p as i32).to_vec(), core.cycle())
        }
        Some(chip) => {
            machine_setup::configure(chip, &resolved)?;
            let config = machine_setup::stream_config(&resolved);
            let streamed = stream::run(chip, records.iter().copied(), &config, |_, event| {
                if let StreamEvent::Queued { queued } = event {
                    progress.set_position(queued);
                    if let Some(line) = planned.lines.get((queued as usize).saturating_sub(1)) {
                        progress.set_message(format!("line {line}"));
                    }
                }
                Ok(())
            })?;
            if streamed.stream.underruns != 0 {
                bail!("{} FIFO underruns", streamed.stream.underruns);
            }
            (streamed.end.steps, streamed.cycles)
        }
    };
    progress.finish_and_clear();

    println!("  axis   final steps   final position   programmed end   error");
    let mut worst = 0i64;
    for axis in (0..4).filter(|&a| resolved.axes[a].present) {
        let scale = resolved.axes[axis].steps_per_unit;
        let steps = i64::from(positions[axis]);
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
    println!(
        "  {cycles} clock cycles{}",
        if !fast && bus.is_lockstep() { ", bit-exact RTL against the model" } else { "" }
    );
    if worst != 0 {
        bail!("the pulse train ended {worst} steps from the programmed end");
    }
    if !report.passed() {
        bail!("the checker found {} violations", report.violation_count);
    }
    Ok(())
}

//! `finestep run FILE.ngc`: a part program through the planner into the core, in
//! lockstep co-simulation (RTL against the model) or through the model's fast path.

use std::path::Path;

use anyhow::bail;
use finestep_cosim::{Harness, ModelPath};
use finestep_model::limits::{AxisTiming, RateChecker};
use finestep_model::{Core, CoreInputs, CoreParams, PeriodRecord};
use finestep_planner::{plan_program, Machine, MotionLimits};
use indicatif::{ProgressBar, ProgressStyle};

use crate::demo::{demo_axis, CLOCK_HZ};

const AXIS_NAMES: [&str; 4] = ["X", "Y", "Z", "A"];
const AXIS_UNITS: [&str; 4] = ["mm", "mm", "mm", "deg"];

/// The built-in machine until machine configuration files exist: X, Y at 800 steps/mm,
/// Z at 400 steps/mm, A at 100 steps/degree, T = 1 ms.
fn machine() -> Machine {
    Machine::new(vec![800.0, 800.0, 400.0, 100.0], 0.001)
}

fn limits() -> MotionLimits {
    MotionLimits { rapid_mm_s: 50.0, start_speed_mm_s: 1.0, accel_mm_s2: 500.0, chord_tolerance_mm: 0.001 }
}

pub fn run(file: &Path, fast: bool) -> anyhow::Result<()> {
    let program = finestep_gcode::parse_file(file)?;
    let machine = machine();
    let planned = plan_program(&machine, &limits(), &program)
        .map_err(|e| anyhow::anyhow!("{}:{}: {}", file.display(), e.line, e.reason))?;
    let period_clocks = (machine.period_s * CLOCK_HZ).round() as u32;
    let mut inputs = CoreInputs { run: true, period_clocks, ..Default::default() };
    for axis in inputs.axes.iter_mut().take(AXIS_NAMES.len()) {
        *axis = demo_axis();
    }
    let timings: Vec<AxisTiming> = inputs.axes.iter().map(AxisTiming::from).collect();
    let mut checker = RateChecker::new(CoreParams::default().effective_period(period_clocks), &timings);
    let mut records: Vec<PeriodRecord> = Vec::new();
    let mut max_speed = 0.0f64;
    for block in &planned.blocks {
        for record in &block.records {
            if let Err((axis, why)) = checker.check(record) {
                bail!("{}:{}: axis {}: {why}", file.display(), block.line, AXIS_NAMES.get(axis).unwrap_or(&"?"));
            }
            let speed = (0..3)
                .map(|a| (record.inc[a].to_num::<f64>() / machine.steps_per_unit[a]).powi(2))
                .sum::<f64>()
                .sqrt()
                / machine.period_s;
            max_speed = max_speed.max(speed);
            records.push(*record);
        }
    }
    for note in &planned.notes {
        println!("  note: {note}");
    }
    println!(
        "finestep run {}: {} blocks, {} periods of {} ms ({:.3} s of machining), {}",
        file.display(),
        planned.blocks.len(),
        records.len(),
        machine.period_s * 1e3,
        records.len() as f64 * machine.period_s,
        if fast { "model fast path" } else { "RTL in lockstep with the model, every pin every clock" }
    );

    let progress = ProgressBar::new(records.len() as u64)
        .with_style(ProgressStyle::with_template("  {bar:40} {pos}/{len} periods {per_sec}")?);
    let drain = 2 * u64::from(period_clocks);
    let (positions, cycles) = if fast {
        let mut core = Core::new(CoreParams::default());
        let mut events = Vec::new();
        inputs.rec_valid = true;
        for record in &records {
            inputs.record = *record;
            while !core.run_chunk_fast(&inputs, u64::MAX, &mut events).consumed {}
            events.clear();
            progress.inc(1);
        }
        inputs.rec_valid = false;
        core.run_chunk_fast(&inputs, drain, &mut events);
        (core.outputs().positions, core.cycle())
    } else {
        let mut harness = Harness::new("run", ModelPath::PerClock);
        for record in &records {
            harness.feed(&mut inputs, [*record]).map_err(|m| anyhow::anyhow!("{m}"))?;
            progress.inc(1);
        }
        harness.idle(&inputs, drain).map_err(|m| anyhow::anyhow!("{m}"))?;
        (harness.outputs().positions, harness.cycle())
    };
    progress.finish_and_clear();

    println!("  axis   final steps   final position   programmed end   error");
    let mut worst = 0i64;
    for axis in 0..AXIS_NAMES.len() {
        let steps = i64::from(positions[axis] as i32);
        let target = (planned.end[axis] * machine.steps_per_unit[axis]).round() as i64;
        worst = worst.max((steps - target).abs());
        println!(
            "  {:<4} {:>12} {:>12.4} {:<3} {:>12.4} {:<3} {:>4} steps",
            AXIS_NAMES[axis],
            steps,
            steps as f64 / machine.steps_per_unit[axis],
            AXIS_UNITS[axis],
            planned.end[axis],
            AXIS_UNITS[axis],
            steps - target
        );
    }
    println!("  max path speed (X/Y/Z) {:.2} mm/s, {} clock cycles", max_speed, cycles);
    if !fast {
        println!("  bit-exact over {cycles} cycles");
    }
    if worst != 0 {
        bail!("the pulse train ended {worst} steps from the programmed end");
    }
    Ok(())
}

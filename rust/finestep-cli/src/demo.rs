//! The seed-000 demo: a roller grinder's X (wheel), Z (table) and C (indexing head) move
//! together along one line, interpolated every 2 ms with a trapezoidal feed, fine
//! interpolated by the Verilated core in lockstep with the reference model.

use std::path::Path;

use anyhow::{bail, Context};
use finestep_cosim::{Harness, ModelPath, TraceDepth};
use finestep_model::limits::{AxisTiming, RateChecker};
use finestep_model::{AxisConfig, CoreInputs, PeriodRecord, MAX_AXES};
use finestep_planner::{interpolate_line, LineMove, Machine};
use indicatif::{ProgressBar, ProgressStyle};

use crate::plot::{plot_axes, AxisTrace};

/// The FPGA clock of the demo, Hz.
pub const CLOCK_HZ: f64 = 50e6;
const AXIS_NAMES: [&str; 3] = ["X", "Z", "C"];
const AXIS_UNITS: [&str; 3] = ["mm", "mm", "deg"];
/// Periods traced into the waveform (the start of the move: direction set-up, first steps).
const TRACED_PERIODS: u64 = 4;

/// Drive timing of the demo's drives, in clocks at 50 MHz: 2 us step, 2 us space,
/// 5 us dir setup and hold.
pub fn demo_axis() -> AxisConfig {
    AxisConfig { step_len: 100, step_space: 100, dir_setup: 250, dir_hold: 250, mode: 0, invert: 0, enable: true }
}

pub fn run(out: &Path) -> anyhow::Result<()> {
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let machine = Machine::new(vec![1000.0, 400.0, 100.0], 0.002);
    let line = LineMove {
        from_mm: vec![0.0, 0.0, 0.0],
        to_mm: vec![-2.0, 30.0, 45.0],
        feed_mm_s: 20.0,
        start_speed_mm_s: 1.0,
        accel_mm_s2: 100.0,
    };
    let records = interpolate_line(&machine, &line)?;
    let period_clocks = (machine.period_s * CLOCK_HZ).round() as u32;

    let mut inputs = CoreInputs { run: true, period_clocks, ..Default::default() };
    for axis in inputs.axes.iter_mut().take(AXIS_NAMES.len()) {
        *axis = demo_axis();
    }
    let mut checker = RateChecker::new(period_clocks, &inputs.axes.iter().map(AxisTiming::from).collect::<Vec<_>>());
    for (index, record) in records.iter().enumerate() {
        if let Err((axis, why)) = checker.check(record) {
            bail!("period {index}: axis {}: {why}", AXIS_NAMES.get(axis).unwrap_or(&"?"));
        }
    }

    println!(
        "finestep demo: seed 000 line X {:+} mm, Z {:+} mm, C {:+} deg at {} mm/s, T = {} ms, P = {} clocks at {} MHz",
        line.to_mm[0], line.to_mm[1], line.to_mm[2], line.feed_mm_s,
        machine.period_s * 1e3, period_clocks, CLOCK_HZ / 1e6
    );
    println!("  {} periods of coarse data; RTL (Verilator) in lockstep with the reference model, every pin every clock", records.len());

    let mut harness = Harness::new("demo", ModelPath::PerClock);
    let waveform = out.join(if finestep_rtl_sys::trace_is_fst() { "demo.fst" } else { "demo.vcd" });
    let mut traces: Vec<AxisTrace> = (0..AXIS_NAMES.len()).map(|_| AxisTrace::default()).collect();
    let mut commanded = [0i64; MAX_AXES];
    let progress = ProgressBar::new(records.len() as u64)
        .with_style(ProgressStyle::with_template("  {bar:40} {pos}/{len} periods {per_sec}")?);
    for record in records.iter().copied().chain(std::iter::once(PeriodRecord::default())) {
        harness.feed(&mut inputs, [record])?;
        // The record just consumed starts now; sample what the previous one left.
        let emitted = harness.outputs().positions;
        for (axis, trace) in traces.iter_mut().enumerate() {
            trace.commanded.push(commanded[axis] as f64 / 65536.0);
            trace.emitted.push(emitted[axis] as i32 as f64);
            commanded[axis] += i64::from(record.inc[axis].to_bits());
        }
        progress.inc(1);
    }
    progress.finish_and_clear();
    // Let the last period and the pulse train drain.
    harness.idle(&inputs, 2 * u64::from(period_clocks))?;

    let positions = harness.outputs().positions;
    let pulses = harness.pulses();
    println!("  axis  pulses   final steps   final position   commanded");
    for axis in 0..AXIS_NAMES.len() {
        let steps = positions[axis] as i32;
        let target = commanded[axis] as f64 / 65536.0;
        println!(
            "  {:<4} {:>7} {:>13} {:>12.4} {:<3} {:>10.4} {}",
            AXIS_NAMES[axis], pulses[axis], steps,
            f64::from(steps) / machine.steps_per_unit[axis], AXIS_UNITS[axis],
            target / machine.steps_per_unit[axis], AXIS_UNITS[axis]
        );
        if f64::from(steps) != target {
            bail!("axis {} ended at {steps} steps, commanded {target}", AXIS_NAMES[axis]);
        }
    }
    println!("  bit-exact over {} cycles ({:.3} s of machine time)", harness.cycle(), harness.cycle() as f64 / CLOCK_HZ);

    let traced = TRACED_PERIODS * u64::from(period_clocks);
    harness.write_waveform(&waveform, TraceDepth::Ports, 0, traced)?;
    let png = out.join("demo.png");
    plot_axes(&png, &traces, &AXIS_NAMES, machine.period_s)?;
    println!("  waveform of the ports, first {TRACED_PERIODS} periods: {}", waveform.display());
    println!("  plot: {}", png.display());
    Ok(())
}

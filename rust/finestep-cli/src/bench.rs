//! Throughput figures (not timed tests): RTL alone, model alone (per clock and fast
//! path), and the two in lockstep, for a 4-axis stream with reversals at 1 ms periods.

use std::time::Instant;

use finestep_cosim::{Harness, ModelPath};
use finestep_model::{Core, CoreInputs, Event, Increment, PeriodRecord};
use finestep_rtl_sys::Rtl;

use crate::demo::{demo_axis, CLOCK_HZ};

const PERIOD_CLOCKS: u32 = 50_000;
const AXES: usize = 4;

/// Sinusoidal velocities with different amplitudes and phases per axis, peaking near
/// the demo timing's rated rate.
fn stream(periods: u64) -> impl Iterator<Item = PeriodRecord> {
    (0..periods).map(|k| {
        let mut record = PeriodRecord::default();
        for axis in 0..AXES {
            let amplitude = 40.0 + 50.0 * axis as f64;
            let phase = k as f64 * std::f64::consts::TAU / 400.0 + axis as f64;
            record.inc[axis] = Increment::from_num(amplitude * phase.sin());
        }
        record
    })
}

fn inputs() -> CoreInputs {
    let mut inputs = CoreInputs { run: true, period_clocks: PERIOD_CLOCKS, rec_valid: true, ..Default::default() };
    for axis in inputs.axes.iter_mut().take(AXES) {
        *axis = demo_axis();
    }
    inputs
}

/// Feed `periods` records to a `run_chunk`-shaped simulator; returns cycles run.
fn drive(periods: u64, mut run_chunk: impl FnMut(&CoreInputs, &mut Vec<Event>) -> u64) -> u64 {
    let mut inputs = inputs();
    let mut events = Vec::new();
    let mut cycles = 0;
    for record in stream(periods) {
        inputs.record = record;
        events.clear();
        cycles += run_chunk(&inputs, &mut events);
    }
    cycles
}

fn report(what: &str, cycles: u64, seconds: f64) {
    println!(
        "  {what:<44} {:>7.2} M cycles/s  {:>9.0} periods/s  {:>7.3}x real time",
        cycles as f64 / seconds / 1e6,
        cycles as f64 / f64::from(PERIOD_CLOCKS) / seconds,
        cycles as f64 / CLOCK_HZ / seconds
    );
}

/// A CAM-like program of `moves` short G1 segments along a wavy spiral.
fn cam_program(moves: usize) -> String {
    let mut text = String::with_capacity(moves * 32);
    text.push_str("G21 G90 G17 G61\nF3000\n");
    for i in 0..moves {
        let t = i as f64 * 0.01;
        let r = 20.0 + 5.0 * (7.0 * t).sin();
        text.push_str(&format!("G1 X{:.4} Y{:.4} Z{:.4}\n", r * t.cos(), r * t.sin(), -0.001 * i as f64 % 5.0));
    }
    text
}

/// Parse and plan throughput on a 100 000-segment program.
fn front_end() -> anyhow::Result<()> {
    const MOVES: usize = 100_000;
    let text = cam_program(MOVES);
    let start = Instant::now();
    let program = finestep_gcode::parse_str(&text, "cam.ngc")?;
    let parse_s = start.elapsed().as_secs_f64();
    let machine = finestep_planner::Machine::new(vec![800.0, 800.0, 400.0, 100.0], 0.001);
    let limits = finestep_planner::MotionLimits {
        rapid_mm_s: 50.0,
        start_speed_mm_s: 1.0,
        accel_mm_s2: 500.0,
        chord_tolerance_mm: 0.001,
    };
    let start = Instant::now();
    let planned = finestep_planner::plan_program(&machine, &limits, &program).map_err(|e| anyhow::anyhow!("{e}"))?;
    let plan_s = start.elapsed().as_secs_f64();
    let periods: usize = planned.blocks.iter().map(|b| b.records.len()).sum();
    println!("  {:<44} {:>7.2} M lines/s", "parse G-code (100 000 short G1 segments)", (MOVES + 2) as f64 / parse_s / 1e6);
    println!(
        "  {:<44} {:>7.0} k moves/s  {:>9.0} periods/s",
        "plan + interpolate (exact stop, no look-ahead)",
        MOVES as f64 / plan_s / 1e3,
        periods as f64 / plan_s
    );
    Ok(())
}

pub fn run(cycles: u64) -> anyhow::Result<()> {
    let periods = (cycles / u64::from(PERIOD_CLOCKS)).max(1);
    let limit = u64::from(PERIOD_CLOCKS) + 8;
    println!("finestep bench: {AXES} axes, P = {PERIOD_CLOCKS} clocks, {periods} periods per figure, one core");

    let mut rtl = Rtl::new();
    let start = Instant::now();
    let n = drive(periods, |inputs, events| rtl.run_chunk(inputs, limit, events).cycles);
    report("RTL alone (Verilator, event capture)", n, start.elapsed().as_secs_f64());

    let mut model = Core::new(finestep_rtl_sys::params());
    let start = Instant::now();
    let n = drive(periods, |inputs, events| model.run_chunk(inputs, limit, events).cycles);
    report("model per-clock step()", n, start.elapsed().as_secs_f64());

    let mut model = Core::new(finestep_rtl_sys::params());
    let start = Instant::now();
    let n = drive(periods * 20, |inputs, events| model.run_chunk_fast(inputs, limit, events).cycles);
    report("model fast path", n, start.elapsed().as_secs_f64());

    for (what, path) in [
        ("lockstep RTL + model per-clock, compared", ModelPath::PerClock),
        ("lockstep RTL + model fast path, compared", ModelPath::Fast),
    ] {
        let mut harness = Harness::new("bench", path);
        let start = Instant::now();
        let mut inputs = inputs();
        harness.feed(&mut inputs, stream(periods)).map_err(|m| anyhow::anyhow!("{m}"))?;
        report(what, harness.cycle(), start.elapsed().as_secs_f64());
    }
    front_end()
}

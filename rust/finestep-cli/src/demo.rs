//! The seed-000 demo: a roller grinder's X (wheel), Z (table) and C (indexing head) move
//! together along one line, interpolated every 2 ms with a trapezoidal feed. The host
//! driver streams the period records over SPI (pin level, clk/8) into the position
//! FIFO of the bus-level top; the Verilated RTL and the reference model run in lockstep,
//! every pin on every clock.

use std::path::Path;

use anyhow::{anyhow, bail, Context};
use finestep_cosim::{TopLockstep, TraceDepth};
use finestep_host::AxisSetup;
use finestep_model::limits::{AxisTiming, RateChecker};
use finestep_model::PeriodRecord;
use finestep_planner::{interpolate_line, LineMove, Machine as Kinematics, MachineConfig};
use indicatif::{ProgressBar, ProgressStyle};

use crate::plot::{plot_axes, AxisTrace};
use crate::run::run_program;
use crate::spi_stream::{stream_over_spi, StreamSetup, BURST};

/// The FPGA clock of the demo, Hz.
pub const CLOCK_HZ: f64 = 50e6;
const AXIS_NAMES: [&str; 3] = ["X", "Z", "C"];
const AXIS_UNITS: [&str; 3] = ["mm", "mm", "deg"];
/// Periods traced into the waveform (the start of the move: direction set-up, first steps).
const TRACED_PERIODS: u64 = 4;

/// Drive timing of the demo's drives, in clocks at 50 MHz: 2 us step, 2 us space,
/// 5 us dir setup and hold.
pub fn demo_axis() -> AxisSetup {
    AxisSetup { step_len: 100, step_space: 100, dir_setup: 250, dir_hold: 250, out_mode: 0, invert: 0 }
}

/// The same drive timing as the core's axis configuration (for the core-level bench).
pub fn demo_axis_config() -> finestep_model::AxisConfig {
    let setup = demo_axis();
    finestep_model::AxisConfig {
        timing: finestep_model::DriveTiming::new(setup.step_len, setup.step_space, setup.dir_setup, setup.dir_hold),
        mode: 0,
        invert: 0,
        enable: true,
    }
}

pub fn run(out: &Path) -> anyhow::Result<()> {
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let kinematics = Kinematics::new(vec![1000.0, 400.0, 100.0], 0.002);
    let line = LineMove {
        from_mm: vec![0.0, 0.0, 0.0],
        to_mm: vec![-1.0, 10.0, 15.0],
        feed_mm_s: 20.0,
        start_speed_mm_s: 1.0,
        accel_mm_s2: 100.0,
    };
    let records = interpolate_line(&kinematics, &line)?;
    let period_clocks = (kinematics.period_s * CLOCK_HZ).round() as u32;
    let setup = demo_axis();
    let timing = AxisTiming {
        step_len: setup.step_len,
        step_space: setup.step_space,
        dir_setup: setup.dir_setup,
        dir_hold: setup.dir_hold,
    };
    let mut checker = RateChecker::new(period_clocks, &[timing; 3]);
    for (index, record) in records.iter().enumerate() {
        if let Err((axis, why)) = checker.check(record) {
            bail!("period {index}: axis {}: {why}", AXIS_NAMES.get(axis).unwrap_or(&"?"));
        }
    }

    println!(
        "finestep demo: seed 000 line X {:+} mm, Z {:+} mm, C {:+} deg at {} mm/s, T = {} ms, P = {} clocks at {} MHz",
        line.to_mm[0],
        line.to_mm[1],
        line.to_mm[2],
        line.feed_mm_s,
        kinematics.period_s * 1e3,
        period_clocks,
        CLOCK_HZ / 1e6
    );
    println!(
        "  {} period records streamed over SPI (SCK = clk/8, bursts of {BURST}, CRC-checked frames) into the FIFO;",
        records.len()
    );
    println!("  RTL (Verilator) in lockstep with the reference model at the pins, every pin every clock");
    let stream_setup = StreamSetup { period_clocks, axes: vec![setup; 3], clock_hz: CLOCK_HZ };
    let progress = ProgressBar::new(records.len() as u64)
        .with_style(ProgressStyle::with_template("  {bar:40} {pos}/{len} records queued {per_sec}")?);
    let (streamed, lockstep) = stream_over_spi(TopLockstep::new("demo"), &stream_setup, &records, |queued| {
        progress.set_position(queued as u64)
    })?;
    progress.finish_and_clear();

    println!("  axis   final steps   final position   commanded");
    let mut commanded = [0i64; 3];
    for record in &records {
        for (axis, total) in commanded.iter_mut().enumerate() {
            *total += i64::from(record.inc[axis].to_bits());
        }
    }
    for axis in 0..AXIS_NAMES.len() {
        let steps = streamed.positions[axis];
        let target = commanded[axis] as f64 / 65536.0;
        println!(
            "  {:<4} {:>13} {:>12.4} {:<3} {:>10.4} {}",
            AXIS_NAMES[axis],
            steps,
            f64::from(steps) / kinematics.steps_per_unit[axis],
            AXIS_UNITS[axis],
            target / kinematics.steps_per_unit[axis],
            AXIS_UNITS[axis]
        );
        if f64::from(steps) != target {
            bail!("axis {} ended at {steps} steps, commanded {target}", AXIS_NAMES[axis]);
        }
    }
    if streamed.underruns != 0 {
        bail!("{} FIFO underruns", streamed.underruns);
    }
    println!(
        "  {} bursts, 0 underruns; bit-exact over {} cycles ({:.3} s of machine time)",
        streamed.bursts,
        streamed.cycles,
        streamed.cycles as f64 / CLOCK_HZ
    );

    let waveform = out.join(if finestep_rtl_sys::trace_is_fst() { "demo.fst" } else { "demo.vcd" });
    let traced = lockstep.cycle() - streamed.cycles + TRACED_PERIODS * u64::from(period_clocks);
    lockstep.write_waveform(&waveform, TraceDepth::Ports, traced).map_err(|e| anyhow!(e))?;

    // Commanded positions at the period boundaries; emitted ones where the host sampled
    // the latched POSITION registers.
    let mut traces: Vec<AxisTrace> = (0..AXIS_NAMES.len()).map(|_| AxisTrace::default()).collect();
    let mut running = [0i64; 3];
    for record in std::iter::once(PeriodRecord::default()).chain(records.iter().copied()) {
        for (axis, trace) in traces.iter_mut().enumerate() {
            running[axis] += i64::from(record.inc[axis].to_bits());
            trace.commanded.push(running[axis] as f64 / 65536.0);
        }
    }
    for (t, steps) in &streamed.samples {
        for (axis, trace) in traces.iter_mut().enumerate() {
            trace.emitted.push((*t, f64::from(steps[axis])));
        }
    }
    let png = out.join("demo.png");
    plot_axes(&png, &traces, &AXIS_NAMES, kinematics.period_s)?;
    println!("  waveform of the ports, first {TRACED_PERIODS} periods: {}", waveform.display());
    println!("  plot: {}", png.display());

    println!();
    println!("finestep demo, part 2: a built-in part program (corners, an arc, a cutter-compensated contour)");
    let program = finestep_gcode::parse_str(DEMO_PART, "demo-part.ngc")?;
    run_program(&program, "demo-part.ngc", false, &MachineConfig::default(), out)?;
    crate::demo_feedback::run()
}

/// The demo's part program: an outside contour cut with cutter compensation (tool 3,
/// r = 0.5 mm), with a convex arc, a chamfer corner and square corners, blended (G64).
const DEMO_PART: &str = "\
( finestep demo part: an outside contour, compensated for tool 3, r = 0.5 mm )
G21 G90 G17 G64 P0.01
F6000
G0 X-4 Y-4
G42 D3
G1 X0 Y0
G1 X12
G3 X16 Y4 R4
G1 Y10
G1 X8 Y14
G1 X0
G1 Y0
G40
G1 X-4 Y-4
M2
";

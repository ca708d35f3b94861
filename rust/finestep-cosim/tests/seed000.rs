//! Seed 000's coarse data through the co-simulated core: time-division linear
//! interpolation with trapezoidal feed, random 3-axis lines, checked bit for bit against
//! the model and against the ideal: exact endpoints, and at every period boundary the
//! pulse train within one step of the commanded position.

mod common;

use finestep_cosim::{Harness, ModelPath};
use finestep_model::limits::RateChecker;
use finestep_model::{pins, AxisConfig, CoreInputs, DriveTiming, PeriodRecord};
use finestep_planner::config::{AxisLimits, CoreLimits, DriveTimingNs};
use finestep_planner::MachineConfig;
use proptest::prelude::*;

/// T = 1 ms with P = 2000 clocks (a 2 MHz clock): the core never sees the clock
/// frequency, and short periods keep the simulated cycle count low.
const PERIOD_CLOCKS: u32 = 2_000;
const CLOCK_HZ: f64 = 2e6;
const STEPS_PER_UNIT: [f64; 3] = [1000.0, 800.0, 100.0];

/// A line from the origin to `to` (X, Y, Z) at `feed_mm_s`, the axes accelerating at up to
/// `accel_mm_s2`, planned as a one-block program by the planner.
fn plan_line(to: &[f64], feed_mm_s: f64, accel_mm_s2: f64) -> Result<Vec<PeriodRecord>, TestCaseError> {
    let axes = ["X", "Y", "Z"]
        .iter()
        .zip(STEPS_PER_UNIT)
        .map(|(name, steps_per_unit)| {
            let limits =
                AxisLimits { steps_per_unit, max_velocity: 100.0, max_acceleration: accel_mm_s2, max_jerk: 1e6 };
            (name.to_string(), limits)
        })
        .collect();
    // 5 and 10 clocks at 2 MHz: the drive timing below.
    let drive = DriveTimingNs { step_len_ns: 2500.0, step_space_ns: 2500.0, dir_setup_ns: 5000.0, dir_hold_ns: 5000.0 };
    let config = MachineConfig { period_ms: 1.0, axes, drive, ..MachineConfig::default() }
        .for_core(CoreLimits { clock_hz: CLOCK_HZ, ..CoreLimits::default() });
    let text = format!("G1 X{} Y{} Z{} F{}\nM2\n", to[0], to[1], to[2], feed_mm_s * 60.0);
    let program = finestep_gcode::parse_str(&text, "line.ngc").map_err(|e| TestCaseError::fail(e.to_string()))?;
    let planned = finestep_planner::plan_program(&config, &program).map_err(|e| TestCaseError::fail(e.to_string()))?;
    Ok(planned.records)
}

fn run_line(to: &[f64], feed_mm_s: f64, accel_mm_s2: f64, path: ModelPath) -> Result<(), TestCaseError> {
    let records = plan_line(to, feed_mm_s, accel_mm_s2)?;
    let axis = AxisConfig { timing: DriveTiming::new(5, 5, 10, 10), mode: 0, invert: 0, enable: true };
    let mut inputs = CoreInputs { run: true, period_clocks: PERIOD_CLOCKS, ..Default::default() };
    inputs.axes[..3].copy_from_slice(&[axis; 3]);
    // The core this test runs (Harness::new: the shared step engine) and its rated rate.
    let mut checker = RateChecker::for_core(
        &finestep_rtl_sys::params(),
        PERIOD_CLOCKS,
        &inputs.axes.iter().map(|axis| axis.timing).collect::<Vec<_>>(),
    );
    // The parameter ranges below keep every line within the rated rate: a refusal is a
    // planner defect, not a case to skip.
    for (index, record) in records.iter().enumerate() {
        if let Err((axis, why)) = checker.check(record) {
            prop_assert!(false, "period {}: axis {}: {}", index, axis, why);
        }
    }
    let mut harness = Harness::new("seed000_lines", path);
    let mut commanded = [0i64; 3];
    for record in records.iter().copied().chain(std::iter::once(PeriodRecord::default())) {
        if let Err(mismatch) = harness.feed(&mut inputs, [record]) {
            prop_assert!(false, "{mismatch}");
        }
        let emitted = harness.outputs().positions;
        for axis in 0..3 {
            let error = f64::from(emitted[axis] as i32) - commanded[axis] as f64 / 65536.0;
            prop_assert!(
                error.abs() <= 1.0,
                "axis {axis}: emitted {} vs commanded {}",
                emitted[axis] as i32,
                commanded[axis] as f64 / 65536.0
            );
            commanded[axis] += i64::from(record.inc[axis].to_bits());
        }
    }
    if let Err(mismatch) = harness.idle(&inputs, 2 * u64::from(PERIOD_CLOCKS)) {
        prop_assert!(false, "{mismatch}");
    }
    let out = harness.outputs();
    for axis in 0..3 {
        let end = (to[axis] * STEPS_PER_UNIT[axis]).round() as i32;
        prop_assert_eq!(out.positions[axis] as i32, end, "axis {} endpoint", axis);
        prop_assert_eq!((out.pins >> pins::rate_error(axis)) & 1, 0, "rate error on axis {}", axis);
    }
    Ok(())
}

#[test]
fn seed000_lines_are_exact_and_bit_exact() {
    let mut runner = finestep_testkit::runner("seed000_lines_are_exact_and_bit_exact", 200);
    let coord = -10.0..10.0f64;
    let strategy = (
        proptest::collection::vec(coord, 3),
        20.0..100.0f64,
        200.0..5000.0f64,
        prop_oneof![Just(ModelPath::PerClock), Just(ModelPath::Fast)],
    );
    runner.run(&strategy, |(to, feed, accel, path)| run_line(&to, feed, accel, path)).unwrap();
}

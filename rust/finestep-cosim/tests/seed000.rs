//! Seed 000's coarse data through the co-simulated core: time-division linear
//! interpolation with trapezoidal feed, random 3-axis lines, checked bit for bit against
//! the model and against the ideal: exact endpoints, and at every period boundary the
//! pulse train within one step of the commanded position.

mod common;

use finestep_cosim::{Harness, ModelPath};
use finestep_model::limits::RateChecker;
use finestep_model::{pins, AxisConfig, CoreInputs, DriveTiming, PeriodRecord};
use finestep_planner::{interpolate_line, LineMove, Machine};
use proptest::prelude::*;

/// T = 1 ms with P = 2000 clocks (a 2 MHz clock): the core never sees the clock
/// frequency, and short periods keep the simulated cycle count low.
const PERIOD_CLOCKS: u32 = 2_000;
const PERIOD_S: f64 = 0.001;

fn run_line(line: &LineMove, path: ModelPath) -> Result<(), TestCaseError> {
    let machine = Machine::new(vec![1000.0, 800.0, 100.0], PERIOD_S);
    let records = interpolate_line(&machine, line).map_err(|e| TestCaseError::fail(e.to_string()))?;
    let axis = AxisConfig { timing: DriveTiming::new(5, 5, 10, 10), mode: 0, invert: 0, enable: true };
    let mut inputs = CoreInputs { run: true, period_clocks: PERIOD_CLOCKS, ..Default::default() };
    inputs.axes[..3].copy_from_slice(&[axis; 3]);
    let mut checker = RateChecker::new(PERIOD_CLOCKS, &inputs.axes.iter().map(|axis| axis.timing).collect::<Vec<_>>());
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
        let end = (line.to_mm[axis] * machine.steps_per_unit[axis]).round() as i32;
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
    runner
        .run(&strategy, |(to, feed, accel, path)| {
            let line = LineMove {
                from_mm: vec![0.0; 3],
                to_mm: to,
                feed_mm_s: feed,
                start_speed_mm_s: 1.0,
                accel_mm_s2: accel,
            };
            run_line(&line, path)
        })
        .unwrap();
}

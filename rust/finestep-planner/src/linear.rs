//! Seed 000's time-division linear interpolation with trapezoidal feed.

use finestep_interface::{PeriodRecord, MAX_AXES};

use crate::path::{check_endpoints, quantise, to_steps};
use crate::profile::FeedProfile;

pub use crate::path::FLAG_BLOCK_END;

/// The machine as the coarse interpolator sees it.
#[derive(Clone, Debug, PartialEq)]
pub struct Machine {
    /// Steps per unit (mm or degree) of each axis; its length is the axis count.
    pub steps_per_unit: Vec<f64>,
    /// The interpolation period T in seconds.
    pub period_s: f64,
}

impl Machine {
    /// A machine with these axis scales and period.
    pub fn new(steps_per_unit: Vec<f64>, period_s: f64) -> Machine {
        Machine { steps_per_unit, period_s }
    }
}

/// A straight move with a trapezoidal feed profile.
#[derive(Clone, Debug, PartialEq)]
pub struct LineMove {
    /// Start point, one coordinate per axis, in axis units.
    pub from_mm: Vec<f64>,
    /// End point, one coordinate per axis, in axis units.
    pub to_mm: Vec<f64>,
    /// Programmed feed along the path, units/s.
    pub feed_mm_s: f64,
    /// Start and stop speed along the path, units/s (the feed the drive can take at once).
    pub start_speed_mm_s: f64,
    /// Path acceleration and deceleration, units/s^2.
    pub accel_mm_s2: f64,
}

/// Why a move cannot be interpolated.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum PlanError {
    /// Coordinates and axes do not match.
    #[error("move has {coords} coordinates but the machine has {axes} axes (at most {MAX_AXES})")]
    AxisCount {
        /// coordinates given
        coords: usize,
        /// axes configured
        axes: usize,
    },
    /// A parameter is not a positive finite number.
    #[error("{name} must be positive and finite, got {value}")]
    NotPositive {
        /// parameter name
        name: &'static str,
        /// the value given
        value: f64,
    },
    /// An endpoint does not fit the core's 32-bit step position in Q16.16.
    #[error("axis {axis} endpoint {steps} steps is out of range")]
    OutOfRange {
        /// axis index
        axis: usize,
        /// the endpoint in steps
        steps: f64,
    },
    /// One period's move does not fit an I16F16 increment (32 767 steps).
    #[error("axis {axis} would move {steps} steps in one period, more than an I16F16 increment holds")]
    IncrementTooLarge {
        /// axis index
        axis: usize,
        /// the steps of that period
        steps: f64,
    },
}

/// One record per period moving from `from_mm` to `to_mm`, the last flagged
/// [`FLAG_BLOCK_END`]. Endpoints are first rounded to whole steps; the increments sum
/// exactly to the difference of the rounded endpoints.
pub fn interpolate_line(machine: &Machine, line: &LineMove) -> Result<Vec<PeriodRecord>, PlanError> {
    let axes = machine.steps_per_unit.len();
    if axes > MAX_AXES || line.from_mm.len() != axes || line.to_mm.len() != axes {
        return Err(PlanError::AxisCount { coords: line.to_mm.len(), axes });
    }
    let profile = FeedProfile::new(line.feed_mm_s, line.start_speed_mm_s, line.accel_mm_s2, machine.period_s)?;
    check_endpoints(machine, &line.from_mm)?;
    check_endpoints(machine, &line.to_mm)?;

    let start_steps = to_steps(machine, &line.from_mm);
    let end_steps = to_steps(machine, &line.to_mm);
    // The path between the endpoints rounded to whole steps: the one the increments take,
    // so that the feed and acceleration hold for it exactly.
    let length: f64 = (0..axes)
        .map(|a| ((end_steps[a] - start_steps[a]) as f64 / machine.steps_per_unit[a]).powi(2))
        .sum::<f64>()
        .sqrt();
    if length == 0.0 {
        return Ok(Vec::new());
    }

    let points = profile.distances(length).into_iter().map(|travelled| {
        let fraction = travelled / length;
        (0..axes)
            .map(|a| start_steps[a] as f64 + fraction * (end_steps[a] - start_steps[a]) as f64)
            .collect::<Vec<f64>>()
    });
    quantise(&start_steps, &end_steps, points)
}

#[cfg(test)]
mod tests {
    use super::*;
    use num_rational::BigRational;
    use proptest::prelude::*;

    fn sum_steps(records: &[PeriodRecord], axis: usize) -> BigRational {
        records.iter().map(|r| BigRational::new(r.inc[axis].to_bits().into(), 65536.into())).sum()
    }

    #[test]
    fn seed_000_line_sums_to_its_endpoint() {
        let machine = Machine::new(vec![800.0, 400.0, 100.0], 0.002);
        let line = LineMove {
            from_mm: vec![1.0, -2.0, 0.0],
            to_mm: vec![31.0, 18.0, 90.0],
            feed_mm_s: 40.0,
            start_speed_mm_s: 2.0,
            accel_mm_s2: 200.0,
        };
        let records = interpolate_line(&machine, &line).unwrap();
        let expected = [24000, 8000, 9000];
        for (axis, steps) in expected.into_iter().enumerate() {
            assert_eq!(sum_steps(&records, axis), BigRational::from_integer(steps.into()));
        }
        assert_eq!(records.iter().filter(|r| r.flags & FLAG_BLOCK_END != 0).count(), 1);
    }

    #[test]
    fn feed_ramps_up_holds_and_ramps_down() {
        let machine = Machine::new(vec![1000.0], 0.001);
        let line = LineMove {
            from_mm: vec![0.0],
            to_mm: vec![100.0],
            feed_mm_s: 50.0,
            start_speed_mm_s: 1.0,
            accel_mm_s2: 500.0,
        };
        let records = interpolate_line(&machine, &line).unwrap();
        let speeds: Vec<f64> = records.iter().map(|r| r.inc[0].to_num::<f64>() / 1000.0 / 0.001).collect();
        let peak = speeds.iter().cloned().fold(0.0, f64::max);
        assert!((peak - 50.0).abs() < 1e-3, "peak feed {peak}");
        for pair in speeds.windows(2) {
            // |dv| <= A T plus one grid quantum of velocity.
            assert!((pair[1] - pair[0]).abs() <= 500.0 * 0.001 + 1e-3, "{pair:?}");
        }
        assert!(speeds[0] < 2.0 && speeds[speeds.len() - 2] < 2.0);
    }

    #[test]
    fn bad_parameters_are_errors() {
        let machine = Machine::new(vec![1000.0], 0.001);
        let mut line =
            LineMove { from_mm: vec![0.0], to_mm: vec![1.0], feed_mm_s: 0.0, start_speed_mm_s: 1.0, accel_mm_s2: 1.0 };
        assert!(matches!(interpolate_line(&machine, &line), Err(PlanError::NotPositive { name: "feed", .. })));
        line.feed_mm_s = 1.0;
        line.to_mm = vec![1e9];
        assert!(matches!(interpolate_line(&machine, &line), Err(PlanError::OutOfRange { axis: 0, .. })));
        line.to_mm = vec![1.0, 2.0];
        assert!(matches!(interpolate_line(&machine, &line), Err(PlanError::AxisCount { .. })));
        // 100 000 steps/mm at 1 m/s: 100 000 steps in a 1 ms period do not fit I16F16.
        let fast = Machine::new(vec![100_000.0], 0.001);
        let long = LineMove {
            from_mm: vec![0.0],
            to_mm: vec![1000.0],
            feed_mm_s: 1000.0,
            start_speed_mm_s: 1000.0,
            accel_mm_s2: 1.0,
        };
        assert!(matches!(interpolate_line(&fast, &long), Err(PlanError::IncrementTooLarge { axis: 0, .. })));
    }

    #[test]
    fn random_lines_are_exact_and_stay_on_the_line() {
        let mut runner = finestep_testkit::runner("random_lines_are_exact_and_stay_on_the_line", 256);
        let coord = prop_oneof![-200.0..200.0f64, -0.05..0.05f64];
        let strategy = (proptest::collection::vec((coord.clone(), coord), 1..=4), 1.0..100.0f64, 10.0..2000.0f64);
        runner
            .run(&strategy, |(points, feed, accel)| {
                let machine = Machine::new(vec![200.0; points.len()], 0.001);
                let line = LineMove {
                    from_mm: points.iter().map(|p| p.0).collect(),
                    to_mm: points.iter().map(|p| p.1).collect(),
                    feed_mm_s: feed,
                    start_speed_mm_s: 0.5,
                    accel_mm_s2: accel,
                };
                let records = interpolate_line(&machine, &line).unwrap();
                let dominant = (0..points.len())
                    .max_by(|&a, &b| (points[a].1 - points[a].0).abs().total_cmp(&(points[b].1 - points[b].0).abs()))
                    .unwrap();
                let start: Vec<i64> = points.iter().map(|p| (p.0 * 200.0).round() as i64).collect();
                let end: Vec<i64> = points.iter().map(|p| (p.1 * 200.0).round() as i64).collect();
                let mut pos: Vec<i64> = start.iter().map(|s| s << 16).collect();
                for record in &records {
                    for (axis, p) in pos.iter_mut().enumerate() {
                        *p += record.inc[axis].to_bits() as i64;
                    }
                    // Every intermediate point lies on the line within one grid quantum.
                    let span = (end[dominant] - start[dominant]) as f64;
                    if span != 0.0 {
                        let t = (pos[dominant] as f64 / 65536.0 - start[dominant] as f64) / span;
                        for axis in 0..points.len() {
                            let on_line = start[axis] as f64 + t * (end[axis] - start[axis]) as f64;
                            prop_assert!((pos[axis] as f64 / 65536.0 - on_line).abs() < 1e-3);
                        }
                    }
                }
                for axis in 0..points.len() {
                    prop_assert_eq!(pos[axis], end[axis] << 16);
                }
                // Path speed from the increments alone: within the feed, and changing by at
                // most A*T per period, but for the start and stop speed jumps at the ends.
                let speeds: Vec<f64> = records
                    .iter()
                    .map(|r| {
                        (0..points.len()).map(|a| (r.inc[a].to_num::<f64>() / 200.0).powi(2)).sum::<f64>().sqrt()
                            / 0.001
                    })
                    .collect();
                let quantum = 4.0 * (points.len() as f64).sqrt() / 65536.0 / 200.0 / 0.001;
                for &v in &speeds {
                    prop_assert!(v <= feed + quantum, "speed {} over feed {}", v, feed);
                }
                for pair in speeds.windows(2).take(speeds.len().saturating_sub(2)) {
                    prop_assert!(
                        (pair[1] - pair[0]).abs() <= accel * 0.001 * (1.0 + 1e-9) + quantum,
                        "speed step {:?} over A*T = {}",
                        pair,
                        accel * 0.001
                    );
                }
                Ok(())
            })
            .unwrap();
    }
}

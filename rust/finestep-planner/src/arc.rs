//! Time-division interpolation of circular and helical arcs: every period ends on the
//! programmed circle (chords between them), with the feed capped so that the chord
//! error stays within a tolerance (seed 002: V <= (2/T) sqrt(r^2 - (r - delta)^2)) and the
//! centripetal acceleration within the acceleration limit (V <= sqrt(A r)).

use std::f64::consts::TAU;

use finestep_interface::{PeriodRecord, MAX_AXES};

use crate::linear::{Machine, PlanError};
use crate::path::{check_endpoints, quantise, to_steps};
use crate::profile::{positive, FeedProfile};

/// A circular arc in the plane of two axes, the other axes moving linearly (a helix).
#[derive(Clone, Debug, PartialEq)]
pub struct ArcMove {
    /// Start point, one coordinate per axis, in axis units.
    pub from_mm: Vec<f64>,
    /// End point, one coordinate per axis, in axis units.
    pub to_mm: Vec<f64>,
    /// The plane's axes `(first, second)`, ordered so that counter-clockwise turns from
    /// the first towards the second: G17 is (X, Y), G18 (Z, X), G19 (Y, Z).
    pub plane: (usize, usize),
    /// The centre in the plane's axes.
    pub centre_mm: (f64, f64),
    /// Clockwise (G2) or counter-clockwise (G3).
    pub clockwise: bool,
    /// Full turns beyond the first (a P word on G2/G3 minus one).
    pub extra_turns: u32,
    /// Programmed feed along the path, units/s.
    pub feed_mm_s: f64,
    /// Start and stop speed along the path, units/s.
    pub start_speed_mm_s: f64,
    /// Path acceleration and deceleration, units/s^2; also the centripetal limit.
    pub accel_mm_s2: f64,
    /// Largest distance allowed between a period's chord and the circle, units.
    pub chord_tolerance_mm: f64,
}

/// The signed angle swept from `start` to `end` (radians), full circle when they coincide.
fn sweep(start: f64, end: f64, clockwise: bool, extra_turns: u32) -> f64 {
    let ccw = (end - start).rem_euclid(TAU);
    let base = if clockwise { -((TAU - ccw) % TAU) } else { ccw };
    let base = if base == 0.0 {
        if clockwise {
            -TAU
        } else {
            TAU
        }
    } else {
        base
    };
    base + f64::from(extra_turns) * TAU * base.signum()
}

/// One record per period along the arc, the last flagged block end; the increments
/// sum exactly to the endpoints rounded to whole steps.
pub fn interpolate_arc(machine: &Machine, arc: &ArcMove) -> Result<Vec<PeriodRecord>, PlanError> {
    let axes = machine.steps_per_unit.len();
    let (first, second) = arc.plane;
    if axes > MAX_AXES
        || arc.from_mm.len() != axes
        || arc.to_mm.len() != axes
        || first >= axes
        || second >= axes
        || first == second
    {
        return Err(PlanError::AxisCount { coords: arc.to_mm.len(), axes });
    }
    check_endpoints(machine, &arc.from_mm)?;
    check_endpoints(machine, &arc.to_mm)?;
    let tolerance = positive("chord tolerance", arc.chord_tolerance_mm)?;
    let (cu, cv) = arc.centre_mm;
    let r0 = (arc.from_mm[first] - cu).hypot(arc.from_mm[second] - cv);
    let r1 = (arc.to_mm[first] - cu).hypot(arc.to_mm[second] - cv);
    positive("arc radius", r0.min(r1))?;
    let theta0 = (arc.from_mm[second] - cv).atan2(arc.from_mm[first] - cu);
    let theta1 = (arc.to_mm[second] - cv).atan2(arc.to_mm[first] - cu);
    let swept = sweep(theta0, theta1, arc.clockwise, arc.extra_turns);

    // Path length: the (slightly spiral, if r0 != r1) planar arc and the linear axes.
    let planar = swept.abs() * 0.5 * (r0 + r1);
    let linear: f64 =
        (0..axes).filter(|&a| a != first && a != second).map(|a| (arc.to_mm[a] - arc.from_mm[a]).powi(2)).sum();
    let length = (planar * planar + linear).sqrt();
    let along_path = length / planar;

    // Feed caps: chord error and centripetal acceleration, both on the planar speed.
    let radius = r0.max(r1);
    let period = positive("period", machine.period_s)?;
    let accel = positive("acceleration", arc.accel_mm_s2)?;
    let chord = 2.0 * (radius * radius - (radius - tolerance.min(radius)).powi(2)).sqrt();
    let chord_speed = chord / period * along_path;
    let centripetal_speed = (accel * r0.min(r1)).sqrt() * along_path;
    let feed = positive("feed", arc.feed_mm_s)?.min(chord_speed).min(centripetal_speed);
    let profile = FeedProfile::new(feed, arc.start_speed_mm_s, accel, period)?;

    let start_steps = to_steps(machine, &arc.from_mm);
    let end_steps = to_steps(machine, &arc.to_mm);
    let points = profile.distances(length).into_iter().map(|travelled| {
        let fraction = travelled / length;
        let theta = theta0 + fraction * swept;
        let r = r0 + fraction * (r1 - r0);
        (0..axes)
            .map(|a| {
                let mm = if a == first {
                    cu + r * theta.cos()
                } else if a == second {
                    cv + r * theta.sin()
                } else {
                    arc.from_mm[a] + fraction * (arc.to_mm[a] - arc.from_mm[a])
                };
                mm * machine.steps_per_unit[a]
            })
            .collect::<Vec<f64>>()
    });
    quantise(&start_steps, &end_steps, points)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    const SCALE: f64 = 1000.0;
    const T: f64 = 0.001;

    fn machine() -> Machine {
        Machine::new(vec![SCALE; 3], T)
    }

    /// Positions in mm at the end of every period, from the increments alone.
    fn positions(records: &[PeriodRecord], start: &[f64]) -> Vec<Vec<f64>> {
        let mut pos: Vec<i64> = start.iter().map(|&s| ((s * SCALE).round() as i64) << 16).collect();
        records
            .iter()
            .map(|r| {
                for (a, p) in pos.iter_mut().enumerate() {
                    *p += i64::from(r.inc[a].to_bits());
                }
                pos.iter().map(|&p| p as f64 / 65536.0 / SCALE).collect()
            })
            .collect()
    }

    fn quarter(clockwise: bool) -> ArcMove {
        ArcMove {
            from_mm: vec![10.0, 0.0, 0.0],
            to_mm: if clockwise { vec![0.0, -10.0, 2.0] } else { vec![0.0, 10.0, 2.0] },
            plane: (0, 1),
            centre_mm: (0.0, 0.0),
            clockwise,
            extra_turns: 0,
            feed_mm_s: 50.0,
            start_speed_mm_s: 1.0,
            accel_mm_s2: 1000.0,
            chord_tolerance_mm: 0.001,
        }
    }

    #[test]
    fn sweeps_have_the_right_sign_and_size() {
        assert!((sweep(0.0, TAU / 4.0, false, 0) - TAU / 4.0).abs() < 1e-12);
        assert!((sweep(0.0, TAU / 4.0, true, 0) + 3.0 * TAU / 4.0).abs() < 1e-12);
        assert!((sweep(1.0, 1.0, false, 0) - TAU).abs() < 1e-12);
        assert!((sweep(1.0, 1.0, true, 1) + 2.0 * TAU).abs() < 1e-12);
    }

    #[test]
    fn helical_quarter_ends_exactly_and_stays_on_the_circle() {
        for clockwise in [false, true] {
            let arc = quarter(clockwise);
            let records = interpolate_arc(&machine(), &arc).unwrap();
            let path = positions(&records, &arc.from_mm);
            let end = path.last().unwrap();
            for (got, want) in end.iter().zip(&arc.to_mm) {
                assert_eq!((got * SCALE).round(), (want * SCALE).round());
            }
            for p in &path {
                let r = p[0].hypot(p[1]);
                assert!((r - 10.0).abs() < 2e-3, "radius {r}");
                assert!(if clockwise { p[1] <= 1e-3 } else { p[1] >= -1e-3 }, "wrong side: {p:?}");
            }
        }
    }

    #[test]
    fn random_arcs_keep_chord_error_feed_and_acceleration() {
        let mut runner = finestep_testkit::runner("random_arcs_keep_chord_error_feed_and_acceleration", 128);
        let strategy = (0.5..40.0f64, -3.0..3.0f64, -3.0..3.0f64, 5.0..150.0f64, any::<bool>(), 0u32..2, 1e-4..0.01f64);
        runner
            .run(&strategy, |(radius, a0, a1, feed, clockwise, turns, tolerance)| {
                let arc = ArcMove {
                    from_mm: vec![radius * a0.cos(), radius * a0.sin(), 0.0],
                    to_mm: vec![radius * a1.cos(), radius * a1.sin(), 1.5],
                    plane: (0, 1),
                    centre_mm: (0.0, 0.0),
                    clockwise,
                    extra_turns: turns,
                    feed_mm_s: feed,
                    start_speed_mm_s: 0.5,
                    accel_mm_s2: 800.0,
                    chord_tolerance_mm: tolerance,
                };
                let records = interpolate_arc(&machine(), &arc).unwrap();
                let path = positions(&records, &arc.from_mm);
                let quantum = 2.0 / SCALE; // rounding of the endpoints and the grid
                let mut previous = arc.from_mm.iter().map(|&s| (s * SCALE).round() / SCALE).collect::<Vec<_>>();
                let mut speeds = Vec::new();
                let mut planar_speeds = Vec::new();
                for p in &path {
                    // The chord's midpoint is within the tolerance of the circle.
                    let (mu, mv) = (0.5 * (p[0] + previous[0]), 0.5 * (p[1] + previous[1]));
                    prop_assert!(
                        radius - mu.hypot(mv) <= tolerance + quantum,
                        "chord error {} > {}",
                        radius - mu.hypot(mv),
                        tolerance
                    );
                    let step: f64 = (0..3).map(|a| (p[a] - previous[a]).powi(2)).sum::<f64>().sqrt();
                    speeds.push(step / T);
                    planar_speeds.push((p[0] - previous[0]).hypot(p[1] - previous[1]) / T);
                    previous = p.clone();
                }
                for (&v, &planar) in speeds.iter().zip(&planar_speeds) {
                    prop_assert!(v <= feed + quantum / T, "speed {} over feed {}", v, feed);
                    // Centripetal acceleration of the planar motion within A.
                    prop_assert!(
                        planar * planar / radius <= 800.0 * (1.0 + 1e-6) + 2.0 * planar * quantum / T / radius,
                        "centripetal {} over 800",
                        planar * planar / radius
                    );
                }
                for pair in speeds.windows(2).take(speeds.len().saturating_sub(2)) {
                    prop_assert!((pair[1] - pair[0]).abs() <= 800.0 * T + 2.0 * quantum / T, "{:?}", pair);
                }
                Ok(())
            })
            .unwrap();
    }

    #[test]
    fn bad_arcs_are_errors() {
        let mut arc = quarter(false);
        arc.centre_mm = (10.0, 0.0); // the start is the centre: radius 0
        assert!(matches!(interpolate_arc(&machine(), &arc), Err(PlanError::NotPositive { name: "arc radius", .. })));
        let mut arc = quarter(false);
        arc.plane = (1, 1);
        assert!(matches!(interpolate_arc(&machine(), &arc), Err(PlanError::AxisCount { .. })));
        let mut arc = quarter(false);
        arc.chord_tolerance_mm = 0.0;
        assert!(matches!(interpolate_arc(&machine(), &arc), Err(PlanError::NotPositive { .. })));
    }
}

//! Seed 002's test part: a five-pointed star NURBS (`tests/programs/star.ngc`) on the
//! seed's machine (200 mm/s, 300 mm/s^2, 3 000 mm/s^3 per axis, 1 um contour error).
//! The planner must keep every limit (the independent checker's verdict) and use them:
//! the peak acceleration per axis must reach the floors below, measured on this plan.

mod common;

use finestep_planner::figures::seed_002;
use finestep_planner::{CheckReport, MachineConfig, ProfileKind};

use common::{plan_and_check, read, PROFILES};

/// Peak acceleration and jerk over X and Y as fractions of their limits (jerk: of the
/// configured jerk limit also for the trapezoid, where it is only reported).
fn peaks(report: &CheckReport, config: &MachineConfig) -> ([f64; 2], [f64; 2]) {
    let resolved = config.resolve().unwrap();
    let a = [0, 1].map(|i| report.axis_max[i][1] / resolved.axes[i].max_acceleration);
    let j = [0, 1].map(|i| report.axis_max[i][2] / resolved.axes[i].max_jerk);
    (a, j)
}

/// The least peak acceleration (fraction of the axis limit, the larger of X and Y) the
/// plan must reach, per profile, set from the value measured when the limits came to be
/// shared by the path's needs (the planner's `element` module): trapezoid 0.972 (the
/// issue's target 0.95 is the floor), S-curve 0.948 since runs of sub-pieces carry the
/// acceleration across their junctions and each sub-piece's caps are derived again at
/// the speed it reaches (0.863 before, when the acceleration returned to zero at every
/// sub-piece's end and the caps held the normal acceleration at the sub-piece's speed
/// cap; 0.945 at plan25), 0.973 since a run's speed change is held in each sub-piece to
/// the acceleration it has there, at the highest speed it has there (plan27: the issue's
/// target 0.95 is the floor). They were 0.800 and 0.500 with fixed shares.
const ACCEL_FLOOR: [(ProfileKind, f64); 2] = [(ProfileKind::Trapezoid, 0.95), (ProfileKind::SCurve, 0.95)];

/// The longest the S-curve star may take, s: 9.32 s measured with the runs (10.9 s
/// when every sub-piece's profile brought the acceleration back to zero), 9.14 s since
/// turning's jerk terms are each taken on the component they act along
/// (`element::turning_jerk`) and a run's speed change is held to the limits of the
/// elements it overlaps, 9.10 s since it is held to each one's limits at the speed and
/// acceleration it has there (plan27).
const SCURVE_TIME_CEILING: f64 = 9.15;

/// The least peak jerk (fraction of the axis limit, the larger of X and Y) the S-curve
/// plan must reach: the target 0.9, met since turning's jerk terms are each
/// taken on the component they act along (0.935 measured; 0.757 before, when the
/// curvature change's term was taken on the axis along the path too).
const SCURVE_JERK_FLOOR: f64 = 0.9;

#[test]
fn the_star_keeps_every_limit_and_uses_the_acceleration() {
    let program = read("star.ngc");
    let mut short = Vec::new();
    for profile in PROFILES {
        let config = seed_002(profile);
        let (planned, report) = plan_and_check("star.ngc", &program, &config);
        let (a, j) = peaks(&report, &config);
        let path_a = report.path_max[1] / 300.0;
        let path_j = report.path_max[2] / 3000.0;
        eprintln!(
            "star {profile:?}: {:.3} s, peak a X {:.3} Y {:.3} path {:.3}, peak j X {:.3} Y {:.3} path {:.3} (of 300 / 3000), deviation {:.4} mm",
            planned.records.len() as f64 * report.period_s,
            a[0],
            a[1],
            path_a,
            j[0],
            j[1],
            path_j,
            report.max_deviation
        );
        // Never above: the checker asserts each axis (its quantisation allowance aside).
        for i in 0..2 {
            assert!(a[i] <= 1.0 + 1e-3, "{profile:?}: axis {i} acceleration {:.4} of the limit", a[i]);
            if profile == ProfileKind::SCurve {
                assert!(j[i] <= 1.0 + 1e-3, "{profile:?}: axis {i} jerk {:.4} of the limit", j[i]);
            }
        }
        let time = planned.records.len() as f64 * report.period_s;
        if profile == ProfileKind::SCurve && time > SCURVE_TIME_CEILING {
            short.push(format!("{profile:?}: {time:.3} s, over the ceiling {SCURVE_TIME_CEILING} s"));
        }
        if profile == ProfileKind::SCurve && j[0].max(j[1]) < SCURVE_JERK_FLOOR {
            short.push(format!(
                "{profile:?}: peak jerk {:.3} of the limit, below the floor {SCURVE_JERK_FLOOR}",
                j[0].max(j[1])
            ));
        }
        let floor = ACCEL_FLOOR.iter().find(|(p, _)| *p == profile).unwrap().1;
        let reached = a[0].max(a[1]);
        if reached < floor {
            short.push(format!("{profile:?}: peak acceleration {reached:.3} of the limit, below the floor {floor}"));
        }
    }
    assert!(short.is_empty(), "{short:?}");
}

//! A lower bound on a program's machining time, computed from the path's geometry and
//! the machine's limits alone, so that the planner's time can be reported as a ratio
//! to it (issue 18). It shares nothing with the planner's speed caps, shares of the
//! limits, look-ahead or profiles: only the path the planner follows (programmed lines,
//! arcs, NURBS and the G64 blends, [`crate::geometry`]), read point by point through
//! [`Element::position`].
//!
//! Along the path, sampled densely, the speed may be at most
//!
//! - the programmed feed of the block the point is on ([`Element::feed`]: the block's
//!   own, not its line's, since one line may hold blocks of several feeds, a canned
//!   cycle's rapids and feeds; until plan26 the largest feed on the line was taken, so
//!   a G81 cycle's feeds were bounded as rapids: hole-circle.ngc 3.1 times its bound;
//!   rapids: the axes' limits);
//! - `V_a / |T_a|` for every axis a (T the unit tangent, from central differences of
//!   positions);
//! - `sqrt(A_a / |kappa_a|)`, the normal acceleration alone within each axis's full
//!   limit (kappa the curvature vector, from second differences);
//! - the chord tolerance's speed on the osculating circle, `2/T sqrt(2 rho delta -
//!   delta^2)`;
//! - at a junction where the tangent jumps, `A_a T / |dt_a|` (the jump read within one
//!   period at the full acceleration), and 0 at every exact stop and at both ends.
//!
//! The tangential acceleration may be at most `min_a A_a / |T_a|` (the normal
//! acceleration ignored, the jerk ignored). Between two samples the larger of their two
//! limits is taken, and each interval's time is the least a speed change from one
//! sample's speed to the next takes under those limits (accelerate, cruise, decelerate):
//! each relaxation only shortens the time, so the result is a lower bound on any motion
//! along this path within the limits, whatever its profile.

use finestep_gcode::Program;

use crate::config::{MachineConfig, Resolved};
use crate::cutter_comp::compensate;
use crate::element::Element;
use crate::error::ProgramError;
use crate::geometry::elements;
use crate::vec4::{norm, sub, Vec4};

/// Samples per unit of path length (at least [`MIN_SAMPLES`] an element, at most
/// [`MAX_SAMPLES`]).
pub const SAMPLES_PER_UNIT: f64 = 20.0;
/// The fewest samples of an element.
pub const MIN_SAMPLES: usize = 8;
/// The most samples of an element.
pub const MAX_SAMPLES: usize = 4000;

/// The lower bound on the machining time of `program` on `config`, s (module docs):
/// the motion only, dwells not counted.
pub fn time_lower_bound(config: &MachineConfig, program: &Program) -> Result<f64, ProgramError> {
    let resolved = config.resolve()?;
    let compensated = compensate(program, &config.tool_table()).map_err(|e| ProgramError::new(e.line, e.reason))?;
    let path = elements(&resolved, &compensated)?;
    Ok(bound_of_path(&resolved, &path.elements))
}

/// One sample: distance along the path, speed limit, tangential acceleration limit.
#[derive(Clone, Copy, Debug)]
struct Point {
    s: f64,
    v: f64,
    a: f64,
}

/// Tangent and curvature vector of `e` at `s`, from positions (central differences a
/// quarter of the sample spacing `spacing` apart: on a circle the second difference is
/// exact to `(h k)^2`, while a step much shorter than that reads the positions' rounding
/// as curvature, 1e-14 mm over h^2).
fn tangent_and_curvature(e: &Element, s: f64, spacing: f64) -> (Vec4, Vec4) {
    let h = (0.25 * spacing).min(0.25 * e.length);
    let (s0, s2) = ((s - h).max(0.0), (s + h).min(e.length));
    let s1 = 0.5 * (s0 + s2);
    let (p0, p1, p2) = (e.position(s0), e.position(s1), e.position(s2));
    let half = 0.5 * (s2 - s0);
    let d = sub(p2, p0);
    let tangent = d.map(|x| x / (2.0 * half));
    let speed = norm(tangent).max(1e-300);
    let mut curvature = [0.0; 4];
    for a in 0..4 {
        curvature[a] = (p2[a] - 2.0 * p1[a] + p0[a]) / (half * half) / (speed * speed);
    }
    (tangent.map(|x| x / speed), curvature)
}

/// The speed and acceleration limits at a point of tangent `t` and curvature `kappa`.
fn limits_at(config: &Resolved, feed: f64, t: Vec4, kappa: Vec4) -> (f64, f64) {
    let mut v = feed;
    let mut a = f64::INFINITY;
    for (i, axis) in config.axes.iter().enumerate() {
        if !axis.present {
            continue;
        }
        if t[i].abs() > 1e-12 {
            v = v.min(axis.max_velocity / t[i].abs());
            a = a.min(axis.max_acceleration / t[i].abs());
        }
        if kappa[i].abs() > 1e-12 {
            v = v.min((axis.max_acceleration / kappa[i].abs()).sqrt());
        }
    }
    let k = norm(kappa);
    if k > 1e-12 {
        let rho = 1.0 / k;
        let delta = config.chord_tolerance_mm.min(rho);
        v = v.min(2.0 / config.period_s * (2.0 * rho * delta - delta * delta).max(0.0).sqrt());
    }
    (v, a)
}

/// The least time over `length` from `v0` to `v1` with acceleration `a` and speed `cap`.
fn interval_time(length: f64, v0: f64, v1: f64, a: f64, cap: f64) -> f64 {
    if length <= 0.0 {
        return 0.0;
    }
    let peak = ((v0 * v0 + v1 * v1) / 2.0 + a * length).sqrt().min(cap.max(v0).max(v1));
    if peak <= 0.0 {
        return f64::INFINITY;
    }
    let up = (peak * peak - v0 * v0) / (2.0 * a);
    let down = (peak * peak - v1 * v1) / (2.0 * a);
    (peak - v0) / a + (peak - v1) / a + (length - up - down).max(0.0) / peak
}

fn bound_of_path(config: &Resolved, path: &[Element]) -> f64 {
    let mut points: Vec<Point> = vec![Point { s: 0.0, v: 0.0, a: f64::INFINITY }];
    let mut at = 0.0;
    for (index, e) in path.iter().enumerate() {
        let feed = e.feed;
        let n = ((e.length * SAMPLES_PER_UNIT).ceil() as usize).clamp(MIN_SAMPLES, MAX_SAMPLES);
        for i in 1..=n {
            let s = e.length * i as f64 / n as f64;
            let (t, kappa) = tangent_and_curvature(e, s.min(e.length * (1.0 - 0.5 / n as f64)), e.length / n as f64);
            let (v, a) = limits_at(config, feed, t, kappa);
            points.push(Point { s: at + s, v, a });
        }
        at += e.length;
        // The junction after the element.
        let last = points.last_mut().expect("a sample");
        if e.stop_after || index + 1 == path.len() {
            last.v = 0.0;
        } else {
            let next = &path[index + 1];
            let (before, _) = tangent_and_curvature(e, e.length, 1e-3 * e.length);
            let (after, _) = tangent_and_curvature(next, 0.0, 1e-3 * next.length);
            let jump = sub(after, before);
            for (i, axis) in config.axes.iter().enumerate() {
                if axis.present && jump[i].abs() > 1e-9 {
                    last.v = last.v.min(axis.max_acceleration * config.period_s / jump[i].abs());
                }
            }
        }
    }
    if points.len() > 1 {
        points[0].a = points[1].a;
    }
    // Forward and backward passes: the fastest speeds reachable at the samples.
    let mut v: Vec<f64> = points.iter().map(|p| p.v).collect();
    for i in 1..points.len() {
        let a = points[i - 1].a.max(points[i].a);
        let ds = points[i].s - points[i - 1].s;
        v[i] = v[i].min((v[i - 1] * v[i - 1] + 2.0 * a * ds).sqrt());
    }
    for i in (0..points.len().saturating_sub(1)).rev() {
        let a = points[i].a.max(points[i + 1].a);
        let ds = points[i + 1].s - points[i].s;
        v[i] = v[i].min((v[i + 1] * v[i + 1] + 2.0 * a * ds).sqrt());
    }
    (1..points.len())
        .map(|i| {
            let a = points[i - 1].a.max(points[i].a);
            let cap = points[i - 1].v.max(points[i].v);
            interval_time(points[i].s - points[i - 1].s, v[i - 1], v[i], a, cap)
        })
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bound(text: &str) -> f64 {
        let program = finestep_gcode::parse_str(text, "bound.ngc").unwrap();
        time_lower_bound(&MachineConfig::default(), &program).unwrap()
    }

    #[test]
    fn a_straight_move_is_bounded_by_its_trapezoid() {
        // 100 mm at 50 mm/s on X with A = 1000 mm/s^2: 0.05 s up, 0.05 s down, 1.95 s
        // of cruise: 2.05 s.
        let t = bound("G1 X100 F3000\nM2\n");
        assert!((t - 2.05).abs() < 1e-6, "{t}");
        // Too short to reach the feed: 2 sqrt(L / A).
        let t = bound("G1 X1 F3000\nM2\n");
        assert!((t - 2.0 * (1.0f64 / 1000.0).sqrt()).abs() < 1e-6, "{t}");
    }

    #[test]
    fn a_circle_is_bounded_by_its_normal_acceleration() {
        // R = 1 mm: v <= sqrt(A R) = 31.6 mm/s on the axis the normal points along.
        let t = bound("G2 X0 Y0 I1 J0 F6000\nM2\n");
        let circle = std::f64::consts::TAU;
        // The bound reads each axis's share of the normal, at most 1/R (sqrt(2) A R at 45
        // degrees): between 2 pi R / sqrt(sqrt(2) A R) and a little above 2 pi R / sqrt(A R).
        assert!(t > circle / (2f64.sqrt() * 1000.0).sqrt(), "{t}");
        assert!(t < 1.5 * circle / 1000f64.sqrt(), "{t}");
    }
}

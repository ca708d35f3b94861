//! Look-ahead: the speed at every junction between elements, from a backward pass
//! (the fastest speed from which the machine can still slow down in time for
//! everything ahead in the window, ending the window at rest) and a forward pass (the
//! fastest speed reachable from the start), each junction limited by its cap.
//!
//! # Junction caps
//!
//! - Exact stop (G61, dwell, pause, program end): 0.
//! - Both elements' speed caps.
//! - Turning at the junction. Sampled once per period, a tangent jump `dt` (unit tangent
//!   after minus before) at speed v changes axis a's per-period velocity by `v |dt_a|`
//!   within one period, which reads as an acceleration `v |dt_a| / T`; the normal
//!   acceleration `k_a v^2` of an arc on either side adds to it. Together they stay
//!   within [`GEOMETRIC_ACCEL_SHARE`] of the axis's limit:
//!   `k_a v^2 + v |dt_a| / T <= 0.45 A_a`.
//! - S-curve only: the same jumps read as jerk, `v |dt_a| / T^2` from the tangent jump
//!   and `|dk_a| v^2 / T` from a curvature jump (a line meeting an arc), within
//!   [`JUNCTION_JERK_SHARE`] of the axis's jerk limit.
//!
//! Blended corners are tangent-continuous, so only the curvature terms remain there; a
//! sharp corner that could not be blended gets a speed near zero, which is the exact
//! stop the acceleration limit asks for.
//!
//! # Window
//!
//! The passes run over a window of `4 * lookahead_moves` elements (a programmed move
//! is at most two elements: its line and the blend after it) ending at rest, and commit
//! the first half. Every committed element therefore saw at least `lookahead_moves`
//! programmed moves ahead of it (lines and arcs; a NURBS is one element or more per
//! knot span, [`crate::nurbs`], so on NURBS the window reaches fewer blocks ahead); the committed speeds stay feasible when the window
//! moves on, because a later window end only allows higher speeds.

use crate::config::{ProfileKind, Resolved};
use crate::element::{Element, GEOMETRIC_ACCEL_SHARE, JUNCTION_JERK_SHARE};
use crate::vec4::sub;
use crate::velocity::Limits;

/// The profile limits of an element.
pub fn element_limits(config: &Resolved, element: &Element) -> Limits {
    Limits { kind: config.profile, accel: element.accel, jerk: element.jerk }
}

/// Largest `v >= 0` with `alpha v^2 + beta v <= gamma`.
fn quadratic_cap(alpha: f64, beta: f64, gamma: f64) -> f64 {
    if alpha > 1e-300 {
        (-beta + (beta * beta + 4.0 * alpha * gamma).sqrt()) / (2.0 * alpha)
    } else if beta > 1e-300 {
        gamma / beta
    } else {
        f64::INFINITY
    }
}

/// The speed cap of the junction between `before` and `after` (module docs).
pub fn junction_cap(config: &Resolved, before: &Element, after: &Element) -> f64 {
    if before.stop_after {
        return 0.0;
    }
    let mut cap = before.v_cap.min(after.v_cap);
    let period = config.period_s;
    let tangent_jump = sub(after.tangent(false), before.tangent(true));
    let k_before = before.curvature(true);
    let k_after = after.curvature(false);
    let curvature_jump = sub(k_after, k_before);
    for (a, axis) in config.axes.iter().enumerate() {
        if !axis.present {
            continue;
        }
        let k = k_before[a].abs().max(k_after[a].abs());
        cap = cap.min(quadratic_cap(k, tangent_jump[a].abs() / period, GEOMETRIC_ACCEL_SHARE * axis.max_acceleration));
        if config.profile == ProfileKind::SCurve {
            cap = cap.min(quadratic_cap(
                curvature_jump[a].abs() / period,
                tangent_jump[a].abs() / (period * period),
                JUNCTION_JERK_SHARE * axis.max_jerk,
            ));
        }
    }
    cap.max(0.0)
}

/// Junction speeds `v[0..=n]` for `n` elements (`v[0]` is the start, `v[n]` the end,
/// both 0), by windowed backward and forward passes (module docs).
pub fn junction_speeds(config: &Resolved, elements: &[Element]) -> Vec<f64> {
    let n = elements.len();
    let mut caps = vec![0.0; n + 1];
    for i in 1..n {
        caps[i] = junction_cap(config, &elements[i - 1], &elements[i]);
    }
    let limits: Vec<Limits> = elements.iter().map(|e| element_limits(config, e)).collect();
    let window = 4 * config.lookahead_moves.max(1);
    let mut speeds = vec![0.0; n + 1];
    let mut backward = vec![0.0; n + 1];
    let mut fixed = 0;
    while fixed < n {
        let end = (fixed + window).min(n);
        backward[end] = 0.0;
        for i in (fixed..end).rev() {
            // A hair below the exact reach, so that rounding never leaves a profile short.
            let reach = limits[i].reachable(backward[i + 1], elements[i].length * (1.0 - 1e-12));
            backward[i] = caps[i].min(reach);
        }
        let commit = if end == n { n } else { fixed + window / 2 };
        for i in fixed..commit {
            let reach = limits[i].reachable(speeds[i], elements[i].length * (1.0 - 1e-12));
            speeds[i + 1] = backward[i + 1].min(reach);
        }
        fixed = commit;
    }
    speeds
}

//! An independent check of a planned program, from the emitted records and the parsed
//! program alone. It shares no code with the planner's geometry, look-ahead or profile
//! math: it rebuilds the programmed geometry from the G-code blocks itself, and reads
//! the machine's limits from the configuration.
//!
//! From the increments it rebuilds the commanded position at every period boundary
//! (the machine at rest at the origin before the first record and after the last),
//! and from its differences per-axis velocity `u_k = dx_k / T`, acceleration
//! `(u_k - u_{k-1}) / T` and jerk `(a_k - a_{k-1}) / T`, and the path's (vector norm over
//! the axes). It asserts:
//!
//! - every axis within its velocity and acceleration limit, and in S-curve mode its
//!   jerk limit (a trapezoid profile has unbounded jerk by design: reported only);
//! - path speed within the programmed feed of the block(s) the period runs on; path
//!   acceleration and jerk within the norm of the per-axis limits (which they must be
//!   when every axis is within its own);
//! - every period boundary within the allowed distance of the programmed path: the
//!   G64 tolerance P of a neighbouring corner (0 in G61), plus the chord tolerance,
//!   plus half a step per axis (vertices are rounded to whole steps); chord midpoints too.
//!   A NURBS is evaluated here from its own definition, the Cox-de Boor recursion of
//!   the rational basis functions (the planner uses de Boor's algorithm on homogeneous
//!   points), and the distance to it is found by dense sampling and a golden-section
//!   refinement around the nearest sample. The path is followed through the program in
//!   order (the current piece while the point is close enough to it, else the first
//!   close enough after it), so a later piece passing close by never takes over. The
//!   deviation reported is the distance in space (X, Y, Z, mm), to every piece the path
//!   may be on: A's degrees are checked, not added to millimetres;
//! - the position exactly (in Q16.16 steps) on every exact stop and the program end (a
//!   stop counts once the machine has moved since the previous one, unless its piece
//!   needs no motion: a program returning to its start has not ended before it begins;
//!   and only where the path can be at it (`stops_reached`): a line crossing the end
//!   point mid-program has not ended it);
//! - every record within the drive's rated rate (the model's `RateChecker`).
//!
//! # Quantisation tolerance
//!
//! Each position is the exact one rounded to the core's 2^-16 step grid, so it is off
//! by at most `e = 2^-17` steps, `e / steps_per_unit` units. A k-th difference of
//! positions sums k+1 of them with coefficients whose magnitudes add to 2^k, so the
//! velocity may read up to `2e/T` high, the acceleration `4e/T^2`, the jerk `8e/T^3`.
//! The limits are asserted with these added, and a relative 1e-9 for floating point.

use std::f64::consts::TAU;
use std::rc::Rc;

use finestep_gcode::{BlockKind, PathControl, Plane, Program};
use finestep_interface::rate::RateChecker;
use finestep_interface::PeriodRecord;

use crate::config::{ConfigError, MachineConfig, ProfileKind, AXIS_NAMES};

/// Motion at one period boundary, from the increments.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Sample {
    /// Commanded position, units.
    pub position: [f64; 4],
    /// Path speed over the period ending here, units/s.
    pub speed: f64,
    /// Path acceleration (norm), units/s^2.
    pub acceleration: f64,
    /// Path jerk (norm), units/s^3.
    pub jerk: f64,
}

/// What the check found.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct CheckReport {
    /// Periods checked.
    pub periods: usize,
    /// The period, s.
    pub period_s: f64,
    /// Largest per-axis velocity, acceleration and jerk seen, units/s^k.
    pub axis_max: [[f64; 3]; 4],
    /// Their limits (jerk: infinite unless the profile is S-curve).
    pub axis_limit: [[f64; 3]; 4],
    /// Which axes exist.
    pub axis_present: [bool; 4],
    /// Largest path speed, acceleration and jerk seen.
    pub path_max: [f64; 3],
    /// Largest ratio of path speed to the feed allowed there.
    pub max_feed_ratio: f64,
    /// Largest distance of a period boundary or chord midpoint from the programmed path
    /// in space (X, Y, Z), mm. The A axis is held to the path within the same allowance
    /// (in degrees) but not counted in this figure.
    pub max_deviation: f64,
    /// The source line where it occurs.
    pub max_deviation_line: usize,
    /// Final position minus the programmed end, steps (Q16.16 raw / 65536).
    pub endpoint_error_steps: [f64; 4],
    /// Exact stops checked.
    pub exact_stops: usize,
    /// Every period boundary.
    pub samples: Vec<Sample>,
    /// What broke a limit, the first few, with the period.
    pub violations: Vec<String>,
    /// How many violations in all.
    pub violation_count: usize,
}

impl CheckReport {
    fn violate(&mut self, message: String) {
        self.violation_count += 1;
        if self.violations.len() < 20 {
            self.violations.push(message);
        }
    }

    /// Whether every assertion held.
    pub fn passed(&self) -> bool {
        self.violation_count == 0
    }
}

/// An arc as the checker reads it: plane axes, centre, start radius, start angle and
/// signed sweep.
type ArcGeometry = ((usize, usize), (f64, f64), f64, f64, f64);

/// Samples of a NURBS per knot span for the distance search, before refinement.
const CURVE_SAMPLES_PER_SPAN: usize = 16;
/// Chords per bounding box of the distance search.
const CHORDS_PER_BOX: usize = 32;
/// Pieces ahead of the tracker's the path may be found on (the tracker's reach).
const TRACK_AHEAD: usize = 64;

/// A NURBS as the checker reads it: control points `(x, y, w)`, knots, order, and the
/// curve sampled densely as `(parameter, point)`.
#[derive(Debug)]
struct CheckCurve {
    points: Vec<(f64, f64, f64)>,
    knots: Vec<f64>,
    order: usize,
    samples: Vec<(f64, [f64; 2])>,
    /// The largest sag of a chord between samples (at its middle parameter).
    sag: f64,
    /// Blocks of consecutive chords: first and last sample, and their bounding box
    /// (min x, min y, max x, max y).
    boxes: Vec<(usize, usize, [f64; 4])>,
}

impl CheckCurve {
    fn new(points: Vec<(f64, f64, f64)>, knots: Vec<f64>, order: usize) -> CheckCurve {
        let mut curve = CheckCurve { points, knots, order, samples: Vec::new(), sag: 0.0, boxes: Vec::new() };
        let n = curve.points.len();
        let mut params = Vec::new();
        for i in order - 1..n {
            let (a, b) = (curve.knots[i], curve.knots[i + 1]);
            if b > a {
                params.extend(
                    (0..CURVE_SAMPLES_PER_SPAN).map(|j| a + (b - a) * j as f64 / CURVE_SAMPLES_PER_SPAN as f64),
                );
            }
        }
        params.push(curve.knots[n]);
        let coarse: Vec<(f64, [f64; 2])> = params.iter().map(|&u| (u, curve.point(u))).collect();
        let size: f64 = coarse.windows(2).map(|w| (w[1].1[0] - w[0].1[0]).hypot(w[1].1[1] - w[0].1[1])).sum();
        let finest = (size / 256.0).max(1e-6);
        // Bisect where a chord is long or sags (weights bunch the parameter up), so the
        // chords follow the curve closely everywhere.
        curve.samples.push(coarse[0]);
        for w in coarse.windows(2) {
            curve.refine(w[0], w[1], finest, 0);
        }
        // Bounding boxes of blocks of chords, for the distance search.
        let last = curve.samples.len() - 1;
        let mut j = 0;
        while j < last {
            let end = (j + CHORDS_PER_BOX).min(last);
            let mut bbox = [f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY];
            for &(_, p) in &curve.samples[j..=end] {
                bbox = [bbox[0].min(p[0]), bbox[1].min(p[1]), bbox[2].max(p[0]), bbox[3].max(p[1])];
            }
            curve.boxes.push((j, end, bbox));
            j = end;
        }
        curve
    }

    /// Appends the samples after `a` up to `b`, bisecting until chords are short and flat.
    fn refine(&mut self, a: (f64, [f64; 2]), b: (f64, [f64; 2]), finest: f64, depth: u32) {
        let chord = (b.1[0] - a.1[0]).hypot(b.1[1] - a.1[1]);
        let um = 0.5 * (a.0 + b.0);
        let m = self.point(um);
        let sag = (m[0] - 0.5 * (a.1[0] + b.1[0])).hypot(m[1] - 0.5 * (a.1[1] + b.1[1]));
        if depth < 24 && (chord > finest || sag > 1e-3 * finest) {
            self.refine(a, (um, m), finest, depth + 1);
            self.refine((um, m), b, finest, depth + 1);
        } else {
            self.sag = self.sag.max(sag);
            self.samples.push(b);
        }
    }

    /// The basis functions N_{i,order}(u) for every control point, by the Cox-de Boor
    /// recursion (0/0 taken as 0; the end of the domain belongs to the last span).
    fn basis(&self, u: f64) -> Vec<f64> {
        let t = &self.knots;
        let n = self.points.len();
        let end = t[n];
        let mut last_span = n - 1;
        while t[last_span] >= end {
            last_span -= 1;
        }
        let mut b: Vec<f64> = (0..t.len() - 1)
            .map(|i| {
                let inside = t[i] <= u && u < t[i + 1];
                if inside || (u >= end && i == last_span) {
                    1.0
                } else {
                    0.0
                }
            })
            .collect();
        for k in 2..=self.order {
            b = (0..t.len() - k)
                .map(|i| {
                    let left = if t[i + k - 1] > t[i] { (u - t[i]) / (t[i + k - 1] - t[i]) * b[i] } else { 0.0 };
                    let right =
                        if t[i + k] > t[i + 1] { (t[i + k] - u) / (t[i + k] - t[i + 1]) * b[i + 1] } else { 0.0 };
                    left + right
                })
                .collect();
        }
        b
    }

    fn point(&self, u: f64) -> [f64; 2] {
        let b = self.basis(u);
        let (mut x, mut y, mut w) = (0.0, 0.0, 0.0);
        for (n, &(px, py, pw)) in b.iter().zip(&self.points) {
            x += n * pw * px;
            y += n * pw * py;
            w += n * pw;
        }
        [x / w, y / w]
    }

    /// The smallest distance in the plane from `(qx, qy)` to the curve: on every chord
    /// between samples that comes within the largest sag of the nearest chord, a
    /// golden-section search on the parameter, finished by the distance to the chord of
    /// the last bracket (which errs low by at most its sag, far below a nanometre).
    fn distance(&self, qx: f64, qy: f64) -> f64 {
        let d = |p: [f64; 2]| (p[0] - qx).hypot(p[1] - qy);
        let segment = |p: [f64; 2], q: [f64; 2]| {
            let (ex, ey) = (q[0] - p[0], q[1] - p[1]);
            let len2 = ex * ex + ey * ey;
            let f = if len2 > 0.0 { (((qx - p[0]) * ex + (qy - p[1]) * ey) / len2).clamp(0.0, 1.0) } else { 0.0 };
            (p[0] + f * ex - qx).hypot(p[1] + f * ey - qy)
        };
        // Chords in the boxes that may hold the nearest one: a box whose distance exceeds
        // the nearest sample of any box cannot.
        let box_distance =
            |b: &[f64; 4]| (b[0] - qx).max(qx - b[2]).max(0.0).hypot((b[1] - qy).max(qy - b[3]).max(0.0));
        let upper = self
            .boxes
            .iter()
            .map(|&(j, _, _)| d(self.samples[j].1))
            .fold(d(self.samples[self.samples.len() - 1].1), f64::min);
        let mut chords: Vec<(usize, f64)> = Vec::new();
        for &(j0, j1, ref b) in &self.boxes {
            if box_distance(b) <= upper {
                chords.extend((j0..j1).map(|j| (j, segment(self.samples[j].1, self.samples[j + 1].1))));
            }
        }
        let best = chords.iter().map(|c| c.1).fold(f64::INFINITY, f64::min);
        let reach = best + 2.0 * self.sag + 1e-9;
        let mut result = f64::INFINITY;
        for &(j, _) in chords.iter().filter(|c| c.1 <= reach) {
            let (mut lo, mut hi) = (self.samples[j].0, self.samples[j + 1].0);
            let g = 0.5 * (5f64.sqrt() - 1.0);
            let (mut a, mut b) = (hi - g * (hi - lo), lo + g * (hi - lo));
            let (mut fa, mut fb) = (d(self.point(a)), d(self.point(b)));
            for _ in 0..20 {
                if fa < fb {
                    hi = b;
                    (b, fb) = (a, fa);
                    a = hi - g * (hi - lo);
                    fa = d(self.point(a));
                } else {
                    lo = a;
                    (a, fa) = (b, fb);
                    b = lo + g * (hi - lo);
                    fb = d(self.point(b));
                }
            }
            let last = segment(self.point(lo), self.point(hi));
            result = result.min(fa).min(fb).min(last).min(d(self.samples[j].1)).min(d(self.samples[j + 1].1));
        }
        result
    }
}

/// A programmed piece of path as the checker understands it.
#[derive(Clone, Debug)]
struct Piece {
    line: usize,
    start: [f64; 4],
    end: [f64; 4],
    /// Plane axes, centre, start radius, start angle, signed sweep for arcs.
    arc: Option<ArcGeometry>,
    /// The curve of a NURBS (in XY; Z and A stay at the start's).
    nurbs: Option<Rc<CheckCurve>>,
    feed: f64,
    /// G64 tolerance of its mode (0 in G61): the corner at its end.
    own_tolerance: f64,
    /// Allowed distance from it (corner tolerances of its two ends).
    allowance: f64,
    /// Stops exactly at its end.
    stops: bool,
    /// Everything it describes lies within half a step per axis of its start: the
    /// machine need not move for it.
    still: bool,
}

impl Piece {
    fn point(&self, f: f64) -> [f64; 4] {
        let mut p: [f64; 4] = std::array::from_fn(|a| self.start[a] + f * (self.end[a] - self.start[a]));
        if let Some(((u, v), (cu, cv), r0, theta0, sweep)) = self.arc {
            let r1 = (self.end[u] - cu).hypot(self.end[v] - cv);
            let r = r0 + f * (r1 - r0);
            let theta = theta0 + f * sweep;
            p[u] = cu + r * theta.cos();
            p[v] = cv + r * theta.sin();
        }
        p
    }

    /// Distance from `q` to the piece.
    fn distance(&self, q: &[f64; 4], present: &[bool; 4]) -> f64 {
        let dist =
            |p: [f64; 4]| -> f64 { (0..4).filter(|&a| present[a]).map(|a| (p[a] - q[a]).powi(2)).sum::<f64>().sqrt() };
        if let Some(curve) = &self.nurbs {
            let planar = curve.distance(q[0], q[1]);
            let off: f64 = (2..4).filter(|&a| present[a]).map(|a| (q[a] - self.start[a]).powi(2)).sum();
            return (planar * planar + off).sqrt();
        }
        match self.arc {
            None => {
                let mut along = 0.0;
                let mut len2 = 0.0;
                for a in (0..4).filter(|&a| present[a]) {
                    along += (q[a] - self.start[a]) * (self.end[a] - self.start[a]);
                    len2 += (self.end[a] - self.start[a]).powi(2);
                }
                let f = if len2 > 0.0 { (along / len2).clamp(0.0, 1.0) } else { 0.0 };
                dist(self.point(f))
            }
            Some(((u, v), (cu, cv), _, theta0, sweep)) => {
                // Start points for a local search: the parameter of q's angle on every
                // turn the arc makes, and of q's height along a helix's rise.
                let phi = (q[v] - cv).atan2(q[u] - cu);
                let base = (phi - theta0) / sweep;
                let turns = (sweep.abs() / TAU).ceil() as i64 + 1;
                let mut starts: Vec<f64> = (-turns..=turns)
                    .map(|k| base + k as f64 * TAU / sweep)
                    .filter(|f| (0.0..=1.0).contains(f))
                    .collect();
                let mut rise2 = 0.0;
                let mut along = 0.0;
                for a in (0..4).filter(|&a| present[a] && a != u && a != v) {
                    rise2 += (self.end[a] - self.start[a]).powi(2);
                    along += (q[a] - self.start[a]) * (self.end[a] - self.start[a]);
                }
                if rise2 > 0.0 {
                    starts.push((along / rise2).clamp(0.0, 1.0));
                }
                let d2 =
                    |f: f64| -> f64 { (0..4).filter(|&a| present[a]).map(|a| (self.point(f)[a] - q[a]).powi(2)).sum() };
                let mut best = dist(self.start).min(dist(self.end));
                for f0 in starts {
                    // Newton on the squared distance, numerically, kept within the arc.
                    let mut f = f0;
                    let h = 1e-5;
                    for _ in 0..12 {
                        let (lo, mid, hi) = (d2(f - h), d2(f), d2(f + h));
                        let slope = (hi - lo) / (2.0 * h);
                        let curve = (hi - 2.0 * mid + lo) / (h * h);
                        if curve.is_nan() || curve <= 0.0 {
                            break;
                        }
                        let next = (f - slope / curve).clamp(0.0, 1.0);
                        if (next - f).abs() < 1e-12 {
                            break;
                        }
                        f = next;
                    }
                    best = best.min(d2(f0).sqrt()).min(d2(f).sqrt());
                }
                best
            }
        }
    }
}

fn arc_sweep(theta0: f64, theta1: f64, clockwise: bool, extra_turns: u32) -> f64 {
    let mut ccw = theta1 - theta0;
    while ccw <= 1e-12 {
        ccw += TAU;
    }
    while ccw > TAU + 1e-12 {
        ccw -= TAU;
    }
    // A full turn when the ends coincide, else the short way round in the chosen sense.
    let one = if clockwise {
        if ccw >= TAU - 1e-12 {
            -TAU
        } else {
            ccw - TAU
        }
    } else {
        ccw
    };
    one + one.signum() * TAU * f64::from(extra_turns)
}

/// The programmed path, rounded nowhere: the checker measures against the program.
fn pieces(program: &Program, default_tolerance: f64, scale: &[f64; 4]) -> (Vec<Piece>, Vec<usize>) {
    let mut out: Vec<Piece> = Vec::new();
    let mut at = [0.0; 4];
    let mut tolerance = Some(default_tolerance);
    let mark_stop = |out: &mut Vec<Piece>| {
        if let Some(last) = out.last_mut() {
            last.stops = true;
        }
    };
    for block in &program.blocks {
        let mut nurbs = None;
        let mut probe = false;
        let (to, feed, arc) = match block.kind {
            BlockKind::Nurbs { to, ref control_points, order, ref knots, feed_mm_per_min } => {
                let points = control_points.iter().map(|c| (c.x_mm, c.y_mm, c.weight)).collect();
                nurbs = Some(Rc::new(CheckCurve::new(points, knots.clone(), order as usize)));
                (to, feed_mm_per_min / 60.0, None)
            }
            BlockKind::Rapid { to } => (to, f64::INFINITY, None),
            BlockKind::Linear { to, feed_mm_per_min } => (to, feed_mm_per_min / 60.0, None),
            // A probe move: an exact stop before it (the probe armed) and after it.
            BlockKind::Probe { to, feed_mm_per_min, .. } => {
                mark_stop(&mut out);
                probe = true;
                (to, feed_mm_per_min / 60.0, None)
            }
            BlockKind::Arc { to, centre, plane, clockwise, extra_turns, feed_mm_per_min } => {
                let (u, v) = match plane {
                    Plane::Xy => (0, 1),
                    Plane::Zx => (2, 0),
                    Plane::Yz => (1, 2),
                };
                let c = [centre.x_mm, centre.y_mm, centre.z_mm, centre.a_deg];
                let t = [to.x_mm, to.y_mm, to.z_mm, to.a_deg];
                let theta0 = (at[v] - c[v]).atan2(at[u] - c[u]);
                let theta1 = (t[v] - c[v]).atan2(t[u] - c[u]);
                let r0 = (at[u] - c[u]).hypot(at[v] - c[v]);
                let sweep = arc_sweep(theta0, theta1, clockwise, extra_turns);
                (to, feed_mm_per_min / 60.0, Some(((u, v), (c[u], c[v]), r0, theta0, sweep)))
            }
            // Spindle and coolant changes take effect at rest where they are written.
            BlockKind::Dwell { .. }
            | BlockKind::Pause
            | BlockKind::ToolChange { .. }
            | BlockKind::Spindle { .. }
            | BlockKind::Coolant { .. }
            | BlockKind::WaitInput { .. }
            | BlockKind::UserMCode { .. }
            | BlockKind::AnalogOutput { .. }
            // MSG and DEBUG wait for the motion before them (PRINT does not).
            | BlockKind::Message { kind: finestep_gcode::MessageKind::Msg | finestep_gcode::MessageKind::Debug, .. } => {
                mark_stop(&mut out);
                continue;
            }
            BlockKind::PathControl(PathControl::Blend { tolerance_mm }) => {
                tolerance = Some(tolerance_mm.filter(|&p| p > 0.0).unwrap_or(default_tolerance));
                continue;
            }
            BlockKind::PathControl(PathControl::ExactPath) => {
                tolerance = None;
                continue;
            }
            BlockKind::End => break,
            _ => continue,
        };
        let to = [to.x_mm, to.y_mm, to.z_mm, to.a_deg];
        if arc.is_none() && nurbs.is_none() && to == at {
            continue;
        }
        // The corner at a piece's end is blended in the piece's own mode; the corner at
        // its start in the previous piece's.
        let before = out.last().filter(|p| !p.stops).map_or(0.0, |p| p.own_tolerance);
        let own_tolerance = tolerance.unwrap_or(0.0);
        let allowance = own_tolerance.max(before);
        let within = |p: [f64; 4]| (0..4).all(|a| ((p[a] - at[a]) * scale[a]).abs() <= 0.5);
        let still = within(to)
            && arc.is_none_or(|(_, _, r0, _, _)| r0 * scale[0].max(scale[1]).max(scale[2]) <= 0.5)
            && nurbs.as_ref().is_none_or(|c| c.points.iter().all(|&(x, y, _)| within([x, y, at[2], at[3]])));
        out.push(Piece {
            line: block.line,
            start: at,
            end: to,
            arc,
            nurbs,
            feed,
            own_tolerance,
            allowance,
            stops: tolerance.is_none() || probe,
            still,
        });
        at = to;
    }
    mark_stop(&mut out);
    let stops = (0..out.len()).filter(|&i| out[i].stops).collect();
    (out, stops)
}

impl Piece {
    /// A length the machine's period chords cover at least along the piece: its length
    /// over the present axes, less what chords cut off (a chord within `chord` of a
    /// circle of radius r is at least `1 - chord / (3 r)` of its arc, never less than 2/3
    /// of it; a NURBS is taken at 2/3).
    fn chord_floor(&self, present: &[bool; 4], chord: f64) -> f64 {
        if self.still {
            return 0.0;
        }
        let span = |p: [f64; 4], q: [f64; 4]| -> f64 {
            (0..4).filter(|&a| present[a]).map(|a| (q[a] - p[a]).powi(2)).sum::<f64>().sqrt()
        };
        if let Some(curve) = &self.nurbs {
            let planar: f64 =
                curve.samples.windows(2).map(|w| (w[1].1[0] - w[0].1[0]).hypot(w[1].1[1] - w[0].1[1])).sum();
            return planar * 2.0 / 3.0;
        }
        match self.arc {
            None => span(self.start, self.end),
            Some(((u, v), (cu, cv), r0, _, sweep)) => {
                let r1 = (self.end[u] - cu).hypot(self.end[v] - cv);
                let n = (64.0 * (sweep.abs() / TAU).ceil()) as usize + 64;
                let polyline: f64 =
                    (0..n).map(|i| span(self.point(i as f64 / n as f64), self.point((i + 1) as f64 / n as f64))).sum();
                polyline * (1.0 - (chord / (3.0 * r0.min(r1).max(1e-12))).min(1.0 / 3.0))
            }
        }
    }
}

/// Counts the exact stops reached at the position `raw` (Q16.16 steps), from
/// `stops[*next_stop]` on, and moves the tracker past them.
///
/// A stop is reached on its point (exactly, in steps) after the machine has moved since
/// the last one (a program returning to its start is not at its end before it begins),
/// unless its piece asks for no motion, and only where the path can be at that stop:
/// the tracker on its piece or the one before, or every piece in between passing within
/// its allowance of the stop's point (short pieces the tracker stepped over), or the
/// machine having travelled since the last stop at least the chord floor of the pieces
/// up to this one less three allowances and two half steps a junction (a blend cuts at
/// most two P off a corner: the tracker stays on a piece the path reverses along).
/// Crossing
/// a later stop's point on the way elsewhere (a line through the point where the
/// program ends) is not reaching it.
#[allow(clippy::too_many_arguments)]
fn stops_reached(
    pieces: &[Piece],
    stops: &[usize],
    next_stop: &mut usize,
    piece: &mut usize,
    moved: &mut bool,
    raw: &[i64; 4],
    present: &[bool; 4],
    scale: &[f64; 4],
    base_allowance: f64,
    travelled: &mut f64,
    floor: &[f64],
) -> usize {
    let mut reached = 0;
    while let Some(&stop) = stops.get(*next_stop) {
        let target: [i64; 4] = std::array::from_fn(|a| ((pieces[stop].end[a] * scale[a]).round() as i64) << 16);
        let on_point = (0..4).all(|a| !present[a] || raw[a] == target[a]);
        let point: [f64; 4] = std::array::from_fn(|a| raw[a] as f64 / 65536.0 / scale[a]);
        let since = if *next_stop == 0 { 0 } else { stops[*next_stop - 1] + 1 };
        let on_the_way = || {
            stop <= *piece + 1
                || (*piece + 1..stop)
                    .all(|i| pieces[i].distance(&point, present) <= pieces[i].allowance + base_allowance)
                || *travelled >= floor[stop + 1] - floor[since]
        };
        if !((*moved || pieces[stop].still) && on_point && on_the_way()) {
            break;
        }
        reached += 1;
        *next_stop += 1;
        *moved = false;
        *travelled = 0.0;
        *piece = (stop + 1).min(pieces.len() - 1);
    }
    reached
}

/// Checks `records` as the plan of `program` on the machine `config` (module docs). The
/// geometry the records must follow is the tool-centre path: the program after cutter
/// compensation with the configuration's tool table (a program that cannot be
/// compensated is reported as a configuration error naming its line).
pub fn check_program(
    config: &MachineConfig,
    program: &Program,
    records: &[PeriodRecord],
) -> Result<CheckReport, ConfigError> {
    let compensated = crate::cutter_comp::compensate(program, &config.tool_table()).map_err(|e| ConfigError {
        file: "<program>".into(),
        key: format!("line {}", e.line),
        reason: e.reason,
    })?;
    let program = &compensated;
    let machine = config.resolve()?;
    let period = machine.period_s;
    let present: [bool; 4] = machine.axes.map(|a| a.present);
    let scale: [f64; 4] = machine.axes.map(|a| a.steps_per_unit);
    let mut report =
        CheckReport { periods: records.len(), period_s: period, axis_present: present, ..CheckReport::default() };
    let scurve = machine.profile == ProfileKind::SCurve;
    let (pieces, stops) = pieces(program, machine.path_tolerance_mm, &scale);

    let mut tolerance = [[0.0; 3]; 4];
    for a in 0..4 {
        let axis = &machine.axes[a];
        report.axis_limit[a] =
            [axis.max_velocity, axis.max_acceleration, if scurve { axis.max_jerk } else { f64::INFINITY }];
        let e = 0.5 / 65536.0 / scale[a];
        tolerance[a] = [2.0 * e / period, 4.0 * e / period.powi(2), 8.0 * e / period.powi(3)];
    }
    let norm_limit = |k: usize| -> f64 {
        (0..4).filter(|&a| present[a]).map(|a| report.axis_limit[a][k].powi(2)).sum::<f64>().sqrt()
            + (0..4).filter(|&a| present[a]).map(|a| tolerance[a][k]).sum::<f64>()
    };
    let path_limit = [0.0, norm_limit(1), norm_limit(2)];
    let linear: [bool; 4] = std::array::from_fn(|a| present[a] && a < 3);
    let rounding: f64 = (0..4).filter(|&a| present[a]).map(|a| (0.5 / scale[a]).powi(2)).sum::<f64>().sqrt();
    let base_allowance = machine.chord_tolerance_mm + rounding + 1e-9;

    let mut rate = RateChecker::with_slots(machine.period_clocks, &machine.timing, machine.step_slots);
    let mut raw = [0i64; 4];
    let mut velocity = [0.0f64; 4];
    let mut accel = [0.0f64; 4];
    let mut previous_point = [0.0f64; 4];
    let mut piece = 0usize;
    let mut next_stop = 0usize;
    let mut moved = false;
    // floor[i]: how far the machine travels at least over the pieces before i.
    let mut floor = vec![0.0; pieces.len() + 1];
    for (i, p) in pieces.iter().enumerate() {
        floor[i + 1] = floor[i]
            + (p.chord_floor(&present, machine.chord_tolerance_mm) - 3.0 * p.allowance - 2.0 * rounding).max(0.0);
    }
    let mut travelled = 0.0f64;
    let mut total_travelled = 0.0f64;
    // Stops of pieces that need no motion, reached before the first period.
    report.exact_stops += stops_reached(
        &pieces,
        &stops,
        &mut next_stop,
        &mut piece,
        &mut moved,
        &raw,
        &present,
        &scale,
        base_allowance,
        &mut travelled,
        &floor,
    );
    // Two rest periods after the end: the machine stops there.
    let rest = [PeriodRecord::default(); 2];
    for (k, record) in records.iter().chain(rest.iter()).enumerate() {
        let emitted = k < records.len();
        if emitted {
            if let Err((axis, why)) = rate.check(record) {
                report.violate(format!("period {k}: axis {}: {why}", AXIS_NAMES[axis]));
            }
        }
        let mut point = [0.0; 4];
        let mut new_velocity = [0.0; 4];
        let mut new_accel = [0.0; 4];
        let mut jerk = [0.0; 4];
        for a in 0..4 {
            raw[a] += i64::from(record.inc[a].to_bits());
            point[a] = raw[a] as f64 / 65536.0 / scale[a];
            new_velocity[a] = (point[a] - previous_point[a]) / period;
            new_accel[a] = (new_velocity[a] - velocity[a]) / period;
            jerk[a] = (new_accel[a] - accel[a]) / period;
            if !present[a] {
                if record.inc[a].to_bits() != 0 {
                    report.violate(format!("period {k}: axis {} is not configured but moves", AXIS_NAMES[a]));
                }
                continue;
            }
            let values = [new_velocity[a].abs(), new_accel[a].abs(), jerk[a].abs()];
            for q in 0..3 {
                report.axis_max[a][q] = report.axis_max[a][q].max(values[q]);
                let limit = report.axis_limit[a][q];
                if values[q] > limit * (1.0 + 1e-9) + tolerance[a][q] {
                    let what = ["velocity", "acceleration", "jerk"][q];
                    report.violate(format!("period {k}: axis {} {what} {:.6} over {limit}", AXIS_NAMES[a], values[q]));
                }
            }
        }
        let norm = |v: &[f64; 4]| (0..4).filter(|&a| present[a]).map(|a| v[a] * v[a]).sum::<f64>().sqrt();
        let path = [norm(&new_velocity), norm(&new_accel), norm(&jerk)];
        for q in 1..3 {
            report.path_max[q] = report.path_max[q].max(path[q]);
            if path[q] > path_limit[q] * (1.0 + 1e-9) {
                report.violate(format!(
                    "period {k}: path {} {:.6} over {}",
                    ["", "acceleration", "jerk"][q],
                    path[q],
                    path_limit[q]
                ));
            }
        }
        report.path_max[0] = report.path_max[0].max(path[0]);

        // Where on the program the period ends, and how far from it.
        if emitted && !pieces.is_empty() {
            let from_piece = piece;
            let chord =
                (0..4).filter(|&a| present[a]).map(|a| (point[a] - previous_point[a]).powi(2)).sum::<f64>().sqrt();
            // The path moves on through the program in order: the current piece while the
            // point is close enough to it, else the first close enough among the next
            // `TRACK_AHEAD`
            // (never the nearest of many: a later piece can pass close by, a line coming
            // back past a corner the path is rounding, or two circles crossing).
            let fits = |i: usize| {
                let d = pieces[i].distance(&point, &present);
                (d <= pieces[i].allowance + base_allowance).then_some(d)
            };
            let last = (piece + TRACK_AHEAD).min(pieces.len() - 1);
            let found = (piece..=last).find(|&i| fits(i).is_some());
            let within = found.is_some();
            let best = found.unwrap_or(piece);
            let deviation = (best.saturating_sub(1)..=(best + 1).min(pieces.len() - 1))
                .map(|i| pieces[i].distance(&point, &present))
                .fold(f64::INFINITY, f64::min);
            // The chord midpoint, against the pieces around the period.
            let midpoint: [f64; 4] = std::array::from_fn(|a| 0.5 * (point[a] + previous_point[a]));
            let lo = from_piece.min(best).saturating_sub(1);
            // One piece on: the period may have crossed a vertex the tracker has not passed.
            let around = &pieces[lo..=(best + 1).min(pieces.len() - 1)];
            let d_mid = around.iter().map(|p| p.distance(&midpoint, &present)).fold(f64::INFINITY, f64::min);
            let mid_fits = around.iter().any(|p| p.distance(&midpoint, &present) <= p.allowance + base_allowance);
            // The figure reported is the tool's distance in space: over X, Y and Z in mm.
            // A in degrees is held by the check above (its half step in the allowance)
            // but is no distance to add to millimetres. It is measured to every piece the
            // path may be on: after a reversal the tracker stays on the piece the path
            // came along while the point fits it, and the piece the path is on is one
            // coming back, or one after a run of pieces retracing it (the tracker stayed
            // four pieces behind on a path going back and forth within P, and the
            // figure read 0.1197 mm at P 0.1139 from the piece the tracker was on while
            // the path was 0.9 um from its own piece, seed 0x5b979e644444628e). The
            // pieces the path may be on reach up to the last one whose chord floor the
            // machine has travelled (`floor`), within the tracker's reach: first the
            // three ahead of the tracker, and only where they give a new largest figure
            // all of them (a figure that is not a new largest changes nothing).
            total_travelled += chord;
            let nearest = |q: &[f64; 4], ahead: &[Piece]| {
                ahead.iter().map(|p| p.distance(q, &linear)).fold(f64::INFINITY, f64::min)
            };
            let near = &pieces[lo..=(best + 3).min(pieces.len() - 1)];
            let mut spatial = nearest(&point, near).max(nearest(&midpoint, near));
            if spatial > report.max_deviation {
                // floor[j] is the least travel before piece j: the path may be on j once
                // it has travelled that far.
                let reachable = floor.partition_point(|&f| f <= total_travelled).saturating_sub(1);
                let furthest = reachable.max(best + 3).min(best + TRACK_AHEAD).min(pieces.len() - 1);
                let ahead = &pieces[lo..=furthest];
                spatial = nearest(&point, ahead).max(nearest(&midpoint, ahead));
            }
            if spatial > report.max_deviation {
                report.max_deviation = spatial;
                report.max_deviation_line = pieces[best].line;
            }
            if !within || !mid_fits {
                report.violate(format!(
                    "period {k} (line {}): {:.6} from the programmed path (chord midpoint {:.6})",
                    pieces[best].line, deviation, d_mid
                ));
            }
            piece = best;
            // Feed over the pieces the period may have run on: from where it began to the
            // furthest of the next three the point is close enough to. With a large G64
            // tolerance the tracker stays on a piece the path has already left (an
            // unblended arc-line vertex passed 0.6 mm back), so that piece's feed alone
            // would be the wrong bound.
            let furthest_fit =
                (best..=(best + 3).min(pieces.len() - 1)).rev().find(|&i| fits(i).is_some()).unwrap_or(best);
            let feed = pieces[from_piece.min(best)..=furthest_fit].iter().map(|p| p.feed).fold(0.0, f64::max);
            let speed_allowance = (0..4).filter(|&a| present[a]).map(|a| tolerance[a][0]).sum::<f64>();
            if feed.is_finite() {
                report.max_feed_ratio = report.max_feed_ratio.max(path[0] / feed);
                if path[0] > feed * (1.0 + 1e-9) + speed_allowance {
                    report.violate(format!("period {k}: path speed {:.6} over the feed {feed}", path[0]));
                }
            }
            // Exact stops, in order: one is missed once the path is two pieces past it
            // (one piece past may still be the vertex both pieces share).
            while next_stop < stops.len() && stops[next_stop] + 1 < piece {
                report.violate(format!(
                    "exact stop at the end of line {} was passed without stopping on it",
                    pieces[stops[next_stop]].line
                ));
                next_stop += 1;
            }
            moved |= record.inc.iter().any(|d| d.to_bits() != 0);
            travelled += chord;
            report.exact_stops += stops_reached(
                &pieces,
                &stops,
                &mut next_stop,
                &mut piece,
                &mut moved,
                &raw,
                &present,
                &scale,
                base_allowance,
                &mut travelled,
                &floor,
            );
        }
        report.samples.push(Sample { position: point, speed: path[0], acceleration: path[1], jerk: path[2] });
        previous_point = point;
        velocity = new_velocity;
        accel = new_accel;
    }
    report.samples.truncate(records.len());
    if next_stop < stops.len() {
        let line = pieces[stops[next_stop]].line;
        report.violate(format!(
            "{} exact stops not reached, the first at the end of line {line}",
            stops.len() - next_stop
        ));
    }
    let end = pieces.last().map(|p| p.end).unwrap_or([0.0; 4]);
    for a in 0..4 {
        let target = ((end[a] * scale[a]).round() as i64) << 16;
        report.endpoint_error_steps[a] = (raw[a] - target) as f64 / 65536.0;
        if present[a] && raw[a] != target {
            report.violate(format!(
                "axis {} ends {} steps from the programmed end",
                AXIS_NAMES[a], report.endpoint_error_steps[a]
            ));
        }
    }
    Ok(report)
}

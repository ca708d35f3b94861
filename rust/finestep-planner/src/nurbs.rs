//! NURBS pieces of the path (G5.2/G5.3) and their direct interpolation: the curve
//! parameter is stepped every period, the curve is never broken into lines.
//!
//! # Evaluation
//!
//! A NURBS of degree p is the projection of a B-spline in homogeneous coordinates
//! `(w x, w y, w)`. [`NurbsCurve`] evaluates that B-spline by de Boor's algorithm, and
//! its first and second derivatives by de Boor on the derivative curves (the hodographs,
//! B-splines of degree p - 1 and p - 2 whose control points are precomputed), then
//! projects: `C = A / w`, `C' = (A' - w' C) / w`, `C'' = (A'' - 2 w' C' - w'' C) / w`.
//!
//! # Pieces for the look-ahead
//!
//! The curve is split at its knots into spans, and each span into sub-pieces of nearly
//! constant speed limit ([`pieces`]): the span is sampled at [`SAMPLES_PER_SPAN`] + 1
//! parameters, bisected wherever the tangent turns more than [`MAX_SAMPLE_TURN`]
//! between neighbours (a cusp, where the curve stops and turns back, is refused), and
//! at each sample the curvature `k = |C' x C''| / |C'|^3` limits the speed
//!
//! - by the chord tolerance delta: a chord `v T` on the osculating circle of radius
//!   `rho = 1/k` sags at most delta when `v <= 2/T sqrt(2 rho delta - delta^2)`;
//! - by the normal acceleration `k v^2` within [`GEOMETRIC_ACCEL_SHARE`] of every
//!   axis's limit, as on an arc;
//! - in S-curve mode by the jerk of turning, `(k^2 + |dk/ds|) v^3` within
//!   [`ARC_JERK_SHARE`] of every axis's jerk limit.
//!
//! An interval between two samples takes the smallest limit of the four samples around
//! it (so a peak between samples is covered), and consecutive intervals whose limits
//! stay within [`PIECE_SPEED_RATIO`] of each other form one sub-piece, an [`Element`]
//! with the smallest of their limits, the per-axis velocity, acceleration and jerk
//! limits projected on the largest tangent component over it (parabolas through five
//! points of every interval find a maximum between samples), and its arc length
//! (Gauss-Legendre quadrature). The look-ahead treats the sub-pieces as any
//! other elements: their junctions are tangent (order >= 3), so they flow at speed.
//!
//! # Direct interpolation
//!
//! The profile of a sub-piece gives the arc length s the tool must have reached at the
//! end of each period. [`NurbsCursor`] advances the parameter from the previous period's
//! `(u, s)` by the second-order Taylor expansion of u(s),
//!
//! `u' = u + ds / |C'| - ds^2 (C' . C'') / (2 |C'|^4)`, with `ds = s_target - s`,
//!
//! and corrects the prediction by Newton steps on the arc length actually covered,
//! measured by 5-point Gauss-Legendre quadrature of `|C'|` from u to u', until it is
//! within [`ARC_TOLERANCE`] of ds. The covered length (not the target) is carried to the
//! next period, so what is left over is made up there: the feed error never accumulates.
//! The position is the curve at u', exactly (then quantised to the Q16.16 grid like
//! every other point); the first and last control points are on whole steps, so a
//! NURBS ending at an exact stop ends exactly there.

use std::sync::Arc;

use crate::config::{ProfileKind, Resolved};
use crate::geometry::{
    Element, Shape, Vec4, ARC_JERK_SHARE, GEOMETRIC_ACCEL_SHARE, TANGENTIAL_ACCEL_SHARE, TANGENTIAL_JERK_SHARE,
};

/// Samples of the speed limit per knot span.
pub const SAMPLES_PER_SPAN: usize = 64;
/// Consecutive intervals form one sub-piece while their speed limits stay within this ratio.
pub const PIECE_SPEED_RATIO: f64 = 1.25;
/// The arc length each period's parameter step must match, units.
pub const ARC_TOLERANCE: f64 = 1e-10;

/// Nodes and weights of 5-point Gauss-Legendre quadrature on [-1, 1].
const GAUSS: [(f64, f64); 5] = [
    (0.0, 0.568_888_888_888_888_9),
    (-0.538_469_310_105_683_1, 0.478_628_670_499_366_5),
    (0.538_469_310_105_683_1, 0.478_628_670_499_366_5),
    (-0.906_179_845_938_664, 0.236_926_885_056_189_1),
    (0.906_179_845_938_664, 0.236_926_885_056_189_1),
];

type H = [f64; 3];

/// A NURBS curve in the XY plane; the other axes stay at `base`.
#[derive(Clone, Debug, PartialEq)]
pub struct NurbsCurve {
    degree: usize,
    knots: Vec<f64>,
    /// Homogeneous control points `(w x, w y, w)`.
    points: Vec<H>,
    /// Control points of the first and second derivative (hodograph) curves.
    d1: Vec<H>,
    d2: Vec<H>,
    base: Vec4,
    /// The first and last control points, which the clamped curve passes exactly.
    ends: [[f64; 2]; 2],
}

/// Control points of the derivative of a B-spline of degree `p` on `knots`: degree
/// p - 1 on `knots[1..len - 1]`.
fn hodograph(points: &[H], knots: &[f64], p: usize) -> Vec<H> {
    if p == 0 {
        return Vec::new();
    }
    (0..points.len().saturating_sub(1))
        .map(|i| {
            let span = knots[i + p + 1] - knots[i + 1];
            let k = if span > 0.0 { p as f64 / span } else { 0.0 };
            [0, 1, 2].map(|c| k * (points[i + 1][c] - points[i][c]))
        })
        .collect()
}

/// De Boor's algorithm: the B-spline of degree `p` with control points `points` on
/// `knots` at `u` in the knot span `i` (`knots[i] <= u < knots[i + 1]`, p <= i).
fn de_boor(points: &[H], knots: &[f64], p: usize, i: usize, u: f64) -> H {
    let mut d = [[0.0; 3]; 24];
    for j in 0..=p {
        d[j] = points[j + i - p];
    }
    for r in 1..=p {
        for j in (r..=p).rev() {
            let lo = knots[j + i - p];
            let hi = knots[j + 1 + i - r];
            let alpha = if hi > lo { (u - lo) / (hi - lo) } else { 0.0 };
            let (before, this) = (d[j - 1], d[j]);
            d[j] = [0, 1, 2].map(|c| (1.0 - alpha) * before[c] + alpha * this[c]);
        }
    }
    d[p]
}

/// A point and its first two derivatives with respect to the parameter, in XY.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Derivatives {
    /// C(u).
    pub point: [f64; 2],
    /// C'(u).
    pub first: [f64; 2],
    /// C''(u).
    pub second: [f64; 2],
}

impl Derivatives {
    /// |C'(u)|.
    pub fn speed(&self) -> f64 {
        self.first[0].hypot(self.first[1])
    }
    /// Signed curvature `(C' x C'') / |C'|^3`.
    pub fn curvature(&self) -> f64 {
        let cross = self.first[0] * self.second[1] - self.first[1] * self.second[0];
        cross / self.speed().powi(3)
    }
}

impl NurbsCurve {
    /// The curve of control points `(x, y, weight)`, degree `degree` on `knots`
    /// (`points.len() + degree + 1` of them, non-decreasing, clamped), the other axes at
    /// `base`.
    pub fn new(points: &[(f64, f64, f64)], degree: usize, knots: &[f64], base: Vec4) -> Result<NurbsCurve, String> {
        if degree + 1 > points.len() || knots.len() != points.len() + degree + 1 || degree >= 23 {
            return Err(format!(
                "a NURBS of order {} with {} control points and {} knots",
                degree + 1,
                points.len(),
                knots.len()
            ));
        }
        if knots.iter().any(|k| !k.is_finite())
            || knots.windows(2).any(|w| w[0] > w[1])
            || knots[degree] >= knots[points.len()]
        {
            return Err("NURBS knots must increase".into());
        }
        if let Some(&(x, y, w)) =
            points.iter().find(|(x, y, w)| !(x.is_finite() && y.is_finite() && *w > 0.0 && w.is_finite()))
        {
            return Err(format!("NURBS control point ({x}, {y}) with weight {w}: weights must be positive"));
        }
        let homogeneous: Vec<H> = points.iter().map(|&(x, y, w)| [w * x, w * y, w]).collect();
        let d1 = hodograph(&homogeneous, knots, degree);
        let d2 = if degree >= 1 { hodograph(&d1, &knots[1..knots.len() - 1], degree - 1) } else { Vec::new() };
        let ends = [0, points.len() - 1].map(|i| [points[i].0, points[i].1]);
        Ok(NurbsCurve { degree, knots: knots.to_vec(), points: homogeneous, d1, d2, base, ends })
    }

    /// The parameter range.
    pub fn domain(&self) -> (f64, f64) {
        (self.knots[self.degree], self.knots[self.points.len()])
    }

    /// The knot spans of positive length, as parameter intervals.
    pub fn spans(&self) -> Vec<(f64, f64)> {
        (self.degree..self.points.len()).map(|i| (self.knots[i], self.knots[i + 1])).filter(|(a, b)| b > a).collect()
    }

    /// The span index of `u` (the last span for the end of the domain).
    fn span(&self, u: f64) -> usize {
        let n = self.points.len() - 1;
        if u >= self.knots[n + 1] {
            // The last span of positive length.
            let mut i = n;
            while i > self.degree && self.knots[i] >= self.knots[n + 1] {
                i -= 1;
            }
            return i;
        }
        if u <= self.knots[self.degree] {
            let mut i = self.degree;
            while i < n && self.knots[i + 1] <= self.knots[self.degree] {
                i += 1;
            }
            return i;
        }
        // knots[lo] <= u < knots[hi]
        let (mut lo, mut hi) = (self.degree, n + 1);
        while hi - lo > 1 {
            let mid = (lo + hi) / 2;
            if u < self.knots[mid] {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        lo
    }

    /// C, C' and C'' at `u`, by de Boor on the homogeneous curve and its hodographs
    /// (at a knot: the derivatives of the span starting there).
    pub fn derivatives(&self, u: f64) -> Derivatives {
        self.derivatives_on(u, u)
    }

    /// C, C' and C'' at `u` of the polynomial piece of the span holding `start`: at the
    /// end of a span its one-sided derivatives (where the curve is only C0 or C1 at
    /// the knot, they differ from the next span's).
    pub fn derivatives_on(&self, u: f64, start: f64) -> Derivatives {
        let p = self.degree;
        let i = self.span(start);
        let a = de_boor(&self.points, &self.knots, p, i, u);
        let inner = &self.knots[1..self.knots.len() - 1];
        let a1 = if p >= 1 { de_boor(&self.d1, inner, p - 1, i - 1, u) } else { [0.0; 3] };
        let a2 = if p >= 2 { de_boor(&self.d2, &inner[1..inner.len() - 1], p - 2, i - 2, u) } else { [0.0; 3] };
        let w = a[2];
        let point = [a[0] / w, a[1] / w];
        let first = [0, 1].map(|c| (a1[c] - a1[2] * point[c]) / w);
        let second = [0, 1].map(|c| (a2[c] - 2.0 * a1[2] * first[c] - a2[2] * point[c]) / w);
        Derivatives { point, first, second }
    }

    /// The point at `u` over all four axes (exactly the end control points at the ends
    /// of the domain).
    pub fn point(&self, u: f64) -> Vec4 {
        let (first, last) = self.domain();
        let mut q = self.base;
        let xy = if u <= first {
            self.ends[0]
        } else if u >= last {
            self.ends[1]
        } else {
            let a = de_boor(&self.points, &self.knots, self.degree, self.span(u), u);
            [a[0] / a[2], a[1] / a[2]]
        };
        q[0] = xy[0];
        q[1] = xy[1];
        q
    }

    /// |C'(u)| on the span holding `start`.
    fn speed(&self, u: f64, start: f64) -> f64 {
        self.derivatives_on(u, start).speed()
    }

    /// Arc length from `a` to `b` (within one span) by 5-point Gauss-Legendre quadrature.
    pub fn arc_length(&self, a: f64, b: f64) -> f64 {
        let (mid, half) = (0.5 * (a + b), 0.5 * (b - a));
        GAUSS.iter().map(|&(x, w)| w * self.speed(mid + half * x, a)).sum::<f64>() * half
    }

    /// Arc length from `a` to `b` (within one span), composite quadrature over `parts`.
    pub fn arc_length_composite(&self, a: f64, b: f64, parts: usize) -> f64 {
        let h = (b - a) / parts as f64;
        (0..parts).map(|k| self.arc_length(a + k as f64 * h, a + (k + 1) as f64 * h)).sum()
    }
}

/// The parameter at arc length `s` from `u0` towards `u1` (one span; `length` the arc
/// length of the whole of it): Newton on the quadrature, kept inside a bracket.
pub fn parameter_at(curve: &NurbsCurve, u0: f64, u1: f64, length: f64, s: f64) -> f64 {
    if s <= 0.0 {
        return u0;
    }
    if s >= length {
        return u1;
    }
    let (mut lo, mut hi) = (u0, u1);
    let mut u = u0 + (u1 - u0) * s / length;
    for _ in 0..60 {
        let covered = curve.arc_length_composite(u0, u, 4);
        let err = s - covered;
        if err.abs() <= ARC_TOLERANCE {
            break;
        }
        if err > 0.0 {
            lo = u;
        } else {
            hi = u;
        }
        let step = u + err / curve.speed(u, u0).max(1e-300);
        u = if step > lo && step < hi { step } else { 0.5 * (lo + hi) };
    }
    u
}

/// The parameter state of the sub-piece being interpolated (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NurbsCursor {
    /// The element it follows.
    pub element: usize,
    /// Parameter at the element's start.
    pub u0: f64,
    /// Parameter reached.
    pub u: f64,
    /// Arc length covered from the sub-piece's start to `u`.
    pub s: f64,
}

impl NurbsCursor {
    /// At the start `u0` of element `element`.
    pub fn new(element: usize, u0: f64) -> NurbsCursor {
        NurbsCursor { element, u0, u: u0, s: 0.0 }
    }

    /// Steps the parameter so that the arc length from the sub-piece's start reaches
    /// `s_target` (not beyond `u1`), and returns the new parameter.
    pub fn advance(&mut self, curve: &NurbsCurve, u1: f64, s_target: f64) -> f64 {
        let ds = s_target - self.s;
        if ds <= ARC_TOLERANCE {
            return self.u;
        }
        let d = curve.derivatives_on(self.u, self.u0);
        let sp2 = d.first[0] * d.first[0] + d.first[1] * d.first[1];
        let sp = sp2.sqrt();
        let along = d.first[0] * d.second[0] + d.first[1] * d.second[1];
        // Second-order Taylor expansion of u(s): du/ds = 1/|C'|, d2u/ds2 = -(C'.C'')/|C'|^4.
        let mut u = self.u + ds / sp - ds * ds * along / (2.0 * sp2 * sp2);
        if !(u > self.u && u.is_finite()) {
            u = self.u + ds / sp;
        }
        if !(u > self.u && u.is_finite()) {
            u = u1;
        }
        u = u.min(u1);
        // Corrector: Newton on the covered arc length, inside the bracket [u, u1].
        let (mut lo, mut hi) = (self.u, u1);
        let mut covered = curve.arc_length(self.u, u);
        for _ in 0..30 {
            let err = ds - covered;
            if err.abs() <= ARC_TOLERANCE {
                break;
            }
            if err > 0.0 {
                lo = u;
                if u >= u1 {
                    break; // the end of the sub-piece: the profile ends there too
                }
            } else {
                hi = u;
            }
            let step = u + err / curve.speed(u, self.u0).max(1e-300);
            u = if step > lo && step < hi { step } else { 0.5 * (lo + hi) };
            covered = curve.arc_length(self.u, u);
        }
        self.u = u;
        self.s += covered;
        u
    }
}

/// Largest turn of the tangent between neighbouring samples, radians (5 degrees).
pub const MAX_SAMPLE_TURN: f64 = 5.0 * std::f64::consts::PI / 180.0;

fn cusp_error(d: &Derivatives) -> String {
    format!(
        "the NURBS has a cusp (it stops and turns back) at X{:.4} Y{:.4}: a repeated or folded-back control point? Split the curve there",
        d.point[0], d.point[1]
    )
}

/// The sample parameters of the span `ua..ub`: [`SAMPLES_PER_SPAN`] + 1 uniform ones,
/// then bisected wherever the tangent turns by more than [`MAX_SAMPLE_TURN`] between
/// neighbours, so that no sharp bend hides between samples. A turn of more than a
/// right angle that bisection cannot resolve is a cusp: refused.
fn sample_parameters(curve: &NurbsCurve, ua: f64, ub: f64) -> Result<Vec<f64>, String> {
    let tangent = |u: f64| {
        let d = curve.derivatives_on(u, ua);
        let speed = d.speed();
        ([d.first[0] / speed, d.first[1] / speed], d)
    };
    let mut out = vec![ua];
    let mut stack: Vec<(f64, f64, u32)> = (0..SAMPLES_PER_SPAN)
        .rev()
        .map(|j| {
            (
                ua + (ub - ua) * j as f64 / SAMPLES_PER_SPAN as f64,
                ua + (ub - ua) * (j + 1) as f64 / SAMPLES_PER_SPAN as f64,
                0,
            )
        })
        .collect();
    while let Some((a, b, depth)) = stack.pop() {
        let (ta, _) = tangent(a);
        let (tb, db) = tangent(b);
        let cos = (ta[0] * tb[0] + ta[1] * tb[1]).clamp(-1.0, 1.0);
        if cos.is_nan() {
            return Err(cusp_error(&db));
        }
        if cos.acos() > MAX_SAMPLE_TURN {
            if depth < 48 && b - a > 1e-13 * (ub - ua) {
                let mid = 0.5 * (a + b);
                stack.push((mid, b, depth + 1));
                stack.push((a, mid, depth + 1));
                continue;
            }
            if cos < 0.0 {
                return Err(cusp_error(&db));
            }
        }
        out.push(b);
        if out.len() > 1 << 16 {
            return Err("the NURBS bends too sharply to be sampled (over 65 536 samples in one knot span)".into());
        }
    }
    Ok(out)
}

/// The speed limits at one sample of the curve.
struct Sample {
    u: f64,
    /// Curvature magnitude, 1/units.
    k: f64,
    /// Unit tangent (X, Y).
    tangent: [f64; 2],
    /// Speed cap from curvature, units/s.
    cap: f64,
}

/// The curve as elements ([`Shape::Nurbs`] sub-pieces with their own limits; module
/// docs), for the block on `line` at `feed` units/s; `Err` with the reason when the
/// curve cannot be followed (a cusp: the parametric speed vanishes).
pub fn pieces(config: &Resolved, curve: Arc<NurbsCurve>, feed: f64, line: usize) -> Result<Vec<Element>, String> {
    let scurve = config.profile == ProfileKind::SCurve;
    let plane_axes = [0usize, 1];
    let mut out = Vec::new();
    let (start_u, end_u) = curve.domain();
    let size = {
        let (a, b) = (curve.point(start_u), curve.point(end_u));
        (b[0] - a[0]).hypot(b[1] - a[1]).max(curve.arc_length_composite(start_u, end_u, 8)).max(1e-9)
    };
    for (ua, ub) in curve.spans() {
        let params = sample_parameters(&curve, ua, ub)?;
        let m = params.len() - 1;
        let mut samples: Vec<Sample> = Vec::with_capacity(m + 1);
        for &u in &params {
            let d = curve.derivatives_on(u, ua);
            let speed = d.speed();
            if speed.is_nan() || speed <= 1e-9 * size / (ub - ua).max(1e-300) || !speed.is_finite() {
                return Err(cusp_error(&d));
            }
            let k = d.curvature().abs();
            samples.push(Sample { u, k, tangent: [d.first[0] / speed, d.first[1] / speed], cap: f64::INFINITY });
        }
        // |dk/ds| by differences between samples.
        let ds: Vec<f64> = (0..m).map(|j| curve.arc_length_composite(samples[j].u, samples[j + 1].u, 2)).collect();
        let dk: Vec<f64> = (0..=m)
            .map(|j| {
                let back = if j > 0 { (samples[j].k - samples[j - 1].k).abs() / ds[j - 1].max(1e-300) } else { 0.0 };
                let ahead = if j < m { (samples[j + 1].k - samples[j].k).abs() / ds[j].max(1e-300) } else { 0.0 };
                back.max(ahead)
            })
            .collect();
        for (j, sample) in samples.iter_mut().enumerate() {
            let k = sample.k;
            let mut cap = f64::INFINITY;
            if k > 1e-12 {
                let rho = 1.0 / k;
                let delta = config.chord_tolerance_mm.min(rho);
                cap = cap.min(2.0 / config.period_s * (2.0 * rho * delta - delta * delta).max(0.0).sqrt());
            }
            for &a in &plane_axes {
                let limits = &config.axes[a];
                if !limits.present {
                    continue;
                }
                if k > 1e-12 {
                    cap = cap.min((GEOMETRIC_ACCEL_SHARE * limits.max_acceleration / k).sqrt());
                }
                let turning = k * k + dk[j];
                if scurve && turning > 1e-12 {
                    cap = cap.min((ARC_JERK_SHARE * limits.max_jerk / turning).cbrt());
                }
            }
            sample.cap = cap;
        }
        // Per interval and axis, the largest tangent component: parabolas through the
        // values at five points of the interval, at their vertices where those are inside
        // (an inflection between samples lets the tangent swing past both ends), kept a
        // millionth high.
        let tangent_max: Vec<[f64; 2]> = (0..m)
            .map(|j| {
                let (a, b) = (samples[j].u, samples[j + 1].u);
                let mut f = [samples[j].tangent; 5];
                f[4] = samples[j + 1].tangent;
                for (i, slot) in f.iter_mut().enumerate().take(4).skip(1) {
                    let d = curve.derivatives_on(a + (b - a) * i as f64 / 4.0, ua);
                    let speed = d.speed();
                    *slot = [d.first[0] / speed, d.first[1] / speed];
                }
                [0, 1].map(|c| {
                    let mut top = f.iter().map(|t| t[c].abs()).fold(0.0, f64::max);
                    for k in [0, 2] {
                        let (f0, fm, f1) = (f[k][c], f[k + 1][c], f[k + 2][c]);
                        let (lin, quad) = (-3.0 * f0 + 4.0 * fm - f1, 2.0 * f0 - 4.0 * fm + 2.0 * f1);
                        if quad.abs() > 1e-300 {
                            let t = -lin / (2.0 * quad);
                            if (0.0..=1.0).contains(&t) {
                                top = top.max((f0 + t * lin + t * t * quad).abs());
                            }
                        }
                    }
                    (top * (1.0 + 1e-6)).min(1.0)
                })
            })
            .collect();
        // Per interval: the smallest cap of the four samples around it.
        let interval_cap: Vec<f64> = (0..m)
            .map(|j| samples[j.saturating_sub(1)..=(j + 2).min(m)].iter().map(|s| s.cap).fold(f64::INFINITY, f64::min))
            .collect();
        let mut j = 0;
        while j < m {
            let (mut lo, mut hi) = (interval_cap[j], interval_cap[j]);
            let mut end = j + 1;
            while end < m {
                let c = interval_cap[end];
                let (nlo, nhi) = (lo.min(c), hi.max(c));
                if nhi.is_finite() && nhi > PIECE_SPEED_RATIO * nlo || (nhi.is_infinite() != nlo.is_infinite()) {
                    break;
                }
                (lo, hi) = (nlo, nhi);
                end += 1;
            }
            let window = &samples[j.saturating_sub(1)..=(end + 1).min(m)];
            let k_max = window.iter().map(|s| s.k).fold(0.0, f64::max);
            // Per axis the largest tangent component over the window; 1 where the
            // tangent passes through the axis's direction between two samples.
            let intervals = &tangent_max[j.saturating_sub(1)..(end + 1).min(m)];
            let weights = [0, 1].map(|c| {
                let through = window.windows(2).any(|w| w[0].tangent[1 - c] * w[1].tangent[1 - c] <= 0.0);
                if through {
                    1.0
                } else {
                    intervals.iter().map(|t| t[c]).fold(0.0, f64::max)
                }
            });
            let (u0, u1) = (samples[j].u, samples[end].u);
            let mut v_cap = feed.min(lo);
            let mut accel = f64::INFINITY;
            let mut jerk = f64::INFINITY;
            for (c, &a) in plane_axes.iter().enumerate() {
                let limits = &config.axes[a];
                let w = weights[c];
                if limits.present && w > 1e-12 {
                    v_cap = v_cap.min(limits.max_velocity / w);
                    accel = accel.min(TANGENTIAL_ACCEL_SHARE * limits.max_acceleration / w);
                    jerk = jerk.min(TANGENTIAL_JERK_SHARE * limits.max_jerk / w);
                }
            }
            if scurve && k_max > 1e-12 {
                for &a in &plane_axes {
                    let limits = &config.axes[a];
                    if limits.present {
                        // Tangential acceleration turning with the path: 3 k v a (as on arcs).
                        accel = accel.min(ARC_JERK_SHARE * limits.max_jerk / (3.0 * k_max * v_cap));
                    }
                }
            }
            let length: f64 = ds[j..end].iter().sum();
            let start = curve.point(u0);
            let end_point = curve.point(u1);
            out.push(Element {
                shape: Shape::Nurbs { curve: Arc::clone(&curve), u0, u1 },
                start,
                end: end_point,
                length,
                line,
                v_cap,
                accel,
                jerk,
                stop_after: false,
                dwell_periods: 0,
                dwell_line: 0,
                block_end: false,
            });
            j = end;
        }
    }
    if out.is_empty() {
        return Err("the NURBS has no length".into());
    }
    // The ends exactly on the control points (on whole steps).
    let first = curve.point(start_u);
    let last = curve.point(end_u);
    out[0].start = first;
    if let Some(e) = out.last_mut() {
        e.end = last;
    }
    Ok(out)
}

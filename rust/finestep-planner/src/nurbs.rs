//! The NURBS curve of a G5.2/G5.3 block and its direct interpolation: the curve
//! parameter is stepped every period, the curve is never broken into lines. Its split
//! into sub-pieces for the look-ahead is [`crate::nurbs_pieces`].
//!
//! # Evaluation
//!
//! A NURBS of degree p is the projection of a B-spline in homogeneous coordinates
//! `(w x, w y, w)`. [`NurbsCurve`] evaluates that B-spline by de Boor's algorithm, and
//! its first and second derivatives by de Boor on the derivative curves (the hodographs,
//! B-splines of degree p - 1 and p - 2 whose control points are precomputed), then
//! projects: `C = A / w`, `C' = (A' - w' C) / w`, `C'' = (A'' - 2 w' C' - w'' C) / w`.
//! A curve of degree 3 or below (the smoother's, most G5.2 curves) keeps each knot
//! span's homogeneous polynomial in power-basis form, taken once from de Boor at the
//! span's start, and evaluates it and its derivatives by Horner's scheme instead.
//!
//! # Direct interpolation
//!
//! The profile of a sub-piece gives the arc length s the tool must have reached at the
//! end of each period. [`NurbsCursor`] advances the parameter from the previous period's
//! `(u, s)` by the second-order Taylor expansion of u(s),
//!
//! `u' = u + ds / |C'| - ds^2 (C' . C'') / (2 |C'|^4)`, with `ds = s_target - s`
//! (to the third order on the smoother's cubic B-splines, whose C''' is constant on a
//! span: [`NurbsCursor::advance`]),
//!
//! and corrects the prediction by Newton steps on the arc length actually covered,
//! measured by 5-point Gauss-Legendre quadrature of `|C'|` from u to u', until it is
//! within [`ARC_TOLERANCE`] of ds (on the smoother's cubics a Newton step whose
//! remainder, bounded by the span's largest |C''|, is below a thousandth of the
//! tolerance is not measured again). The covered length (not the target) is carried to
//! the next period, so what is left over is made up there: the feed error never
//! accumulates.
//! The position is the curve at u', exactly (then quantised to the Q16.16 grid like
//! every other point); the first and last control points are on whole steps, so a
//! NURBS ending at an exact stop ends exactly there.

use crate::vec4::Vec4;

/// The arc length each period's parameter step must match, units.
pub const ARC_TOLERANCE: f64 = 1e-10;

const GAUSS: [(f64, f64); 5] = [
    (0.0, 0.568_888_888_888_888_9),
    (-0.538_469_310_105_683_1, 0.478_628_670_499_366_5),
    (0.538_469_310_105_683_1, 0.478_628_670_499_366_5),
    (-0.906_179_845_938_664, 0.236_926_885_056_189_1),
    (0.906_179_845_938_664, 0.236_926_885_056_189_1),
];

/// The largest relative spread of |C'| over the nodes of one 5-point quadrature before
/// [`NurbsCurve::arc_length`] halves the interval.
pub const QUADRATURE_SPEED_SPREAD: f64 = 0.05;

/// Homogeneous coordinates `(w x, w y, w z, w a, w)`.
type H = [f64; 5];

/// A NURBS curve over the four axes: a G5.2/G5.3 curve in the XY plane (Z and A at
/// `base`), or a curve of the path smoother ([`crate::smooth`]) over all four.
#[derive(Clone, Debug, PartialEq)]
pub struct NurbsCurve {
    degree: usize,
    knots: Vec<f64>,
    /// Homogeneous control points `(w x, w y, w)`.
    points: Vec<H>,
    /// Control points of the first and second derivative (hodograph) curves.
    d1: Vec<H>,
    d2: Vec<H>,
    /// Degree 3 and below: per knot span `i` (index `i - degree`) the homogeneous
    /// curve in power-basis form in `t = u - knots[i]`, `A(u) = c0 + c1 t + c2 t^2 +
    /// c3 t^3` (its Taylor coefficients at the span's start, from de Boor on the curve
    /// and its hodographs), so that a point or derivative costs one Horner scheme
    /// instead of three de Boor triangles; empty above degree 3.
    power: Vec<[H; 4]>,
    /// A B-spline of the smoother (weights 1) in power-basis form: per knot span the
    /// largest |C''| over it (C'' is linear in the parameter on a cubic's span, so the
    /// larger of its norms at the span's ends), for [`NurbsCursor::advance`]; empty
    /// otherwise.
    second_max: Vec<f64>,
    /// A B-spline of the smoother in power-basis form whose homogeneous weight is
    /// exactly 1 on every span (`c0` 1, `c1 .. c3` 0 in the last coordinate, as de
    /// Boor on weights of 1 gives them): its point and derivatives are the first four
    /// coordinates of the span's polynomial and its derivatives, the projection's
    /// divisions by 1 and subtractions of 0 skipped (the same values).
    unit: bool,
    base: Vec4,
    /// The first and last control points, which the clamped curve passes exactly.
    ends: [Vec4; 2],
    /// The curve stays in the XY plane (Z and A at `base`).
    planar: bool,
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
            std::array::from_fn(|c| k * (points[i + 1][c] - points[i][c]))
        })
        .collect()
}

/// A power-basis span `c0 + c1 t + c2 t^2 + c3 t^3` ([`NurbsCurve`]'s `power`) at `t`,
/// its first `N` coordinates (5: the homogeneous curve; 4: a curve of weight 1).
#[inline(always)]
fn span_value<const N: usize>(c0: &H, c1: &H, c2: &H, c3: &H, t: f64) -> [f64; N] {
    std::array::from_fn(|c| c0[c] + t * (c1[c] + t * (c2[c] + t * c3[c])))
}

/// The span's first derivative at `t` ([`span_value`]).
#[inline(always)]
fn span_first<const N: usize>(c1: &H, c2: &H, c3: &H, t: f64) -> [f64; N] {
    std::array::from_fn(|c| c1[c] + t * (2.0 * c2[c] + t * 3.0 * c3[c]))
}

/// The span's second derivative at `t` ([`span_value`]).
#[inline(always)]
fn span_second<const N: usize>(c2: &H, c3: &H, t: f64) -> [f64; N] {
    std::array::from_fn(|c| 2.0 * c2[c] + t * 6.0 * c3[c])
}

/// De Boor's algorithm: the B-spline of degree `p` with control points `points` on
/// `knots` at `u` in the knot span `i` (`knots[i] <= u < knots[i + 1]`, p <= i).
fn de_boor(points: &[H], knots: &[f64], p: usize, i: usize, u: f64) -> H {
    // Cubics and below (the smoother's curves, most G5.2 curves) on a small stack array,
    // the degree a constant (the triangle unrolled).
    match p {
        3 => de_boor_in::<4>(points, knots, 3, i, u),
        2 => de_boor_in::<4>(points, knots, 2, i, u),
        1 => de_boor_in::<4>(points, knots, 1, i, u),
        0 => de_boor_in::<4>(points, knots, 0, i, u),
        _ => de_boor_in::<24>(points, knots, p, i, u),
    }
}

/// [`de_boor`] with room for degree `N - 1`.
#[inline(always)]
fn de_boor_in<const N: usize>(points: &[H], knots: &[f64], p: usize, i: usize, u: f64) -> H {
    let mut d = [[0.0; 5]; N];
    for j in 0..=p {
        d[j] = points[j + i - p];
    }
    for r in 1..=p {
        for j in (r..=p).rev() {
            let lo = knots[j + i - p];
            let hi = knots[j + 1 + i - r];
            let alpha = if hi > lo { (u - lo) / (hi - lo) } else { 0.0 };
            let (before, this) = (d[j - 1], d[j]);
            d[j] = std::array::from_fn(|c| (1.0 - alpha) * before[c] + alpha * this[c]);
        }
    }
    d[p]
}

/// A point and its first two derivatives with respect to the parameter, over the four
/// axes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Derivatives {
    /// C(u).
    pub point: Vec4,
    /// C'(u).
    pub first: Vec4,
    /// C''(u).
    pub second: Vec4,
}

impl Derivatives {
    /// |C'(u)|.
    pub fn speed(&self) -> f64 {
        let f = &self.first;
        if f[2] == 0.0 && f[3] == 0.0 {
            f[0].hypot(f[1])
        } else {
            f.iter().map(|c| c * c).sum::<f64>().sqrt()
        }
    }
    /// Curvature `|C' x C''| / |C'|^3` (in XY signed: `(C' x C'')_z / |C'|^3`, positive
    /// turning left; over more axes its magnitude, from `|C'|^2 |C''|^2 - (C'.C'')^2`).
    pub fn curvature(&self) -> f64 {
        let (f, s) = (&self.first, &self.second);
        if f[2] == 0.0 && f[3] == 0.0 && s[2] == 0.0 && s[3] == 0.0 {
            let cross = f[0] * s[1] - f[1] * s[0];
            return cross / self.speed().powi(3);
        }
        let ff: f64 = f.iter().map(|c| c * c).sum();
        let ss: f64 = s.iter().map(|c| c * c).sum();
        let fs: f64 = f.iter().zip(s).map(|(a, b)| a * b).sum();
        (ff * ss - fs * fs).max(0.0).sqrt() / (ff * ff.sqrt())
    }
}

/// Why a NURBS cannot be built or followed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum NurbsError {
    /// The order, control points and knots do not make a clamped NURBS.
    #[error("a NURBS of order {order} with {points} control points and {knots} knots")]
    Shape {
        /// Order (degree + 1).
        order: usize,
        /// Control points.
        points: usize,
        /// Knots.
        knots: usize,
    },
    /// A knot is not finite, the knots decrease, or the domain is empty.
    #[error("NURBS knots must increase")]
    Knots,
    /// A control point that is not finite or has a weight that is not positive.
    #[error("NURBS control point ({x}, {y}) with weight {weight}: weights must be positive")]
    Weight {
        /// X.
        x: f64,
        /// Y.
        y: f64,
        /// Weight.
        weight: f64,
    },
    /// The curve stops and turns back (its parametric speed vanishes).
    #[error(
        "the NURBS has a cusp (it stops and turns back) at X{x:.4} Y{y:.4}: a repeated or folded-back control point? Split the curve there"
    )]
    Cusp {
        /// X of the cusp.
        x: f64,
        /// Y of the cusp.
        y: f64,
    },
    /// The tangent turns too fast for sampling.
    #[error("the NURBS bends too sharply to be sampled (over 65 536 samples in one knot span)")]
    TooSharp,
    /// The curve is a point.
    #[error("the NURBS has no length")]
    NoLength,
}

/// The curve's shape: `points + degree + 1` finite, non-decreasing knots (clamped, a
/// span of nonzero length) and a degree below 23.
fn check_shape(points: usize, degree: usize, knots: &[f64]) -> Result<(), NurbsError> {
    if degree + 1 > points || knots.len() != points + degree + 1 || degree >= 23 {
        return Err(NurbsError::Shape { order: degree + 1, points, knots: knots.len() });
    }
    if knots.iter().any(|k| !k.is_finite()) || knots.windows(2).any(|w| w[0] > w[1]) || knots[degree] >= knots[points] {
        return Err(NurbsError::Knots);
    }
    Ok(())
}

impl NurbsCurve {
    /// The curve of control points `(x, y, weight)`, degree `degree` on `knots`
    /// (`points.len() + degree + 1` of them, non-decreasing, clamped), the other axes at
    /// `base`.
    pub fn new(points: &[(f64, f64, f64)], degree: usize, knots: &[f64], base: Vec4) -> Result<NurbsCurve, NurbsError> {
        check_shape(points.len(), degree, knots)?;
        if let Some(&(x, y, w)) =
            points.iter().find(|(x, y, w)| !(x.is_finite() && y.is_finite() && *w > 0.0 && w.is_finite()))
        {
            return Err(NurbsError::Weight { x, y, weight: w });
        }
        let homogeneous: Vec<H> = points.iter().map(|&(x, y, w)| [w * x, w * y, w * base[2], w * base[3], w]).collect();
        let ends = [0, points.len() - 1].map(|i| [points[i].0, points[i].1, base[2], base[3]]);
        Ok(NurbsCurve::from_homogeneous(homogeneous, degree, knots, base, ends, true))
    }

    /// The (non-rational) B-spline of degree `degree` on `knots` (clamped) with control
    /// points `points` over all four axes: the path smoother's curve.
    pub fn spatial(points: &[Vec4], degree: usize, knots: &[f64]) -> Result<NurbsCurve, NurbsError> {
        check_shape(points.len(), degree, knots)?;
        if let Some(p) = points.iter().find(|p| p.iter().any(|c| !c.is_finite())) {
            return Err(NurbsError::Weight { x: p[0], y: p[1], weight: 1.0 });
        }
        let homogeneous: Vec<H> = points.iter().map(|p| [p[0], p[1], p[2], p[3], 1.0]).collect();
        let ends = [points[0], points[points.len() - 1]];
        Ok(NurbsCurve::from_homogeneous(homogeneous, degree, knots, points[0], ends, false))
    }

    fn from_homogeneous(
        points: Vec<H>,
        degree: usize,
        knots: &[f64],
        base: Vec4,
        ends: [Vec4; 2],
        planar: bool,
    ) -> NurbsCurve {
        let d1 = hodograph(&points, knots, degree);
        let d2 = if degree >= 1 { hodograph(&d1, &knots[1..knots.len() - 1], degree - 1) } else { Vec::new() };
        let mut curve = NurbsCurve {
            degree,
            knots: knots.to_vec(),
            points,
            d1,
            d2,
            power: Vec::new(),
            second_max: Vec::new(),
            unit: false,
            base,
            ends,
            planar,
        };
        if degree <= 3 {
            curve.power = curve.power_form();
            if !planar {
                curve.second_max = curve
                    .power
                    .iter()
                    .enumerate()
                    .map(|(k, [_, _, c2, c3])| {
                        let h = curve.knots[k + degree + 1] - curve.knots[k + degree];
                        let at = |t: f64| (0..4).map(|c| (2.0 * c2[c] + 6.0 * t * c3[c]).powi(2)).sum::<f64>().sqrt();
                        at(0.0).max(at(h)) * (1.0 + 1e-9)
                    })
                    .collect();
                curve.unit = curve
                    .power
                    .iter()
                    .all(|[c0, c1, c2, c3]| c0[4] == 1.0 && c1[4] == 0.0 && c2[4] == 0.0 && c3[4] == 0.0);
            }
        }
        curve
    }

    /// The power-basis coefficients of every knot span (degree 3 and below; see
    /// [`NurbsCurve::power`]): `c_k = A^(k)(knots[i]) / k!`, the derivatives one-sided
    /// within span `i` by de Boor in that span; the third derivative, constant over a
    /// cubic's span, from the third hodograph.
    fn power_form(&self) -> Vec<[H; 4]> {
        let p = self.degree;
        let knots = &self.knots;
        let inner = &knots[1..knots.len() - 1];
        let d3 = if p >= 3 { hodograph(&self.d2, &inner[1..inner.len() - 1], p - 2) } else { Vec::new() };
        (p..self.points.len())
            .map(|i| {
                let u = knots[i];
                let c0 = de_boor(&self.points, knots, p, i, u);
                let c1 = if p >= 1 { de_boor(&self.d1, inner, p - 1, i - 1, u) } else { [0.0; 5] };
                let c2 = if p >= 2 {
                    de_boor(&self.d2, &inner[1..inner.len() - 1], p - 2, i - 2, u).map(|c| 0.5 * c)
                } else {
                    [0.0; 5]
                };
                let c3 = if p >= 3 { d3[i - 3].map(|c| c / 6.0) } else { [0.0; 5] };
                [c0, c1, c2, c3]
            })
            .collect()
    }

    /// The homogeneous curve and its first two derivatives at `u` on knot span `i`
    /// (one-sided there): the power-basis form where there is one, else de Boor.
    #[inline]
    fn homogeneous_on(&self, i: usize, u: f64) -> (H, H, H) {
        let p = self.degree;
        if let Some([c0, c1, c2, c3]) = self.power.get(i - p) {
            let t = u - self.knots[i];
            let a = span_value(c0, c1, c2, c3, t);
            let a1 = span_first(c1, c2, c3, t);
            let a2 = span_second(c2, c3, t);
            return (a, a1, a2);
        }
        let a = de_boor(&self.points, &self.knots, p, i, u);
        let inner = &self.knots[1..self.knots.len() - 1];
        let a1 = if p >= 1 { de_boor(&self.d1, inner, p - 1, i - 1, u) } else { [0.0; 5] };
        let a2 = if p >= 2 { de_boor(&self.d2, &inner[1..inner.len() - 1], p - 2, i - 2, u) } else { [0.0; 5] };
        (a, a1, a2)
    }

    /// The homogeneous curve and its first derivative at `u` on knot span `i`.
    #[inline]
    fn homogeneous_first_on(&self, i: usize, u: f64) -> (H, H) {
        let p = self.degree;
        if let Some([c0, c1, c2, c3]) = self.power.get(i - p) {
            let t = u - self.knots[i];
            let a = span_value(c0, c1, c2, c3, t);
            let a1 = span_first(c1, c2, c3, t);
            return (a, a1);
        }
        let a = de_boor(&self.points, &self.knots, p, i, u);
        let inner = &self.knots[1..self.knots.len() - 1];
        let a1 = if p >= 1 { de_boor(&self.d1, inner, p - 1, i - 1, u) } else { [0.0; 5] };
        (a, a1)
    }

    /// The curve stays in the XY plane (a G5.2/G5.3 curve), Z and A fixed.
    pub fn planar(&self) -> bool {
        self.planar
    }

    /// The curve moves axis `a` (X, Y, Z, A): X and Y on a planar curve, else an axis
    /// whose control points differ.
    pub fn moves(&self, a: usize) -> bool {
        if self.planar {
            a < 2
        } else {
            self.points.iter().any(|p| p[a] != self.points[0][a])
        }
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
        self.derivatives_in(u, self.span(start))
    }

    /// C''' on knot span `i` where it is that span's constant: a B-spline of the
    /// smoother (weights 1) of degree 3 or below in power-basis form; `None` otherwise.
    fn third_in(&self, i: usize) -> Option<Vec4> {
        if self.planar {
            return None;
        }
        let c3 = self.power.get(i - self.degree)?[3];
        Some([6.0 * c3[0], 6.0 * c3[1], 6.0 * c3[2], 6.0 * c3[3]])
    }

    /// The knot span index of `u` (the last span for the end of the domain), for
    /// [`NurbsCurve::derivatives_in`].
    pub(crate) fn span_index(&self, u: f64) -> usize {
        self.span(u)
    }

    /// [`NurbsCurve::derivatives_on`] on knot span `i` ([`NurbsCurve::span_index`]).
    pub(crate) fn derivatives_in(&self, u: f64, i: usize) -> Derivatives {
        if self.unit {
            // Weight 1 (`NurbsCurve::unit`): the polynomial's first four coordinates.
            let [c0, c1, c2, c3] = &self.power[i - self.degree];
            let t = u - self.knots[i];
            return Derivatives {
                point: span_value(c0, c1, c2, c3, t),
                first: span_first(c1, c2, c3, t),
                second: span_second(c2, c3, t),
            };
        }
        let (a, a1, a2) = self.homogeneous_on(i, u);
        let w = a[4];
        let point: Vec4 = std::array::from_fn(|c| a[c] / w);
        if self.planar {
            // Z and A stay put: their derivatives are exactly 0.
            let first = [(a1[0] - a1[4] * point[0]) / w, (a1[1] - a1[4] * point[1]) / w, 0.0, 0.0];
            let second = [
                (a2[0] - 2.0 * a1[4] * first[0] - a2[4] * point[0]) / w,
                (a2[1] - 2.0 * a1[4] * first[1] - a2[4] * point[1]) / w,
                0.0,
                0.0,
            ];
            return Derivatives { point: [point[0], point[1], self.base[2], self.base[3]], first, second };
        }
        let first: Vec4 = std::array::from_fn(|c| (a1[c] - a1[4] * point[c]) / w);
        let second: Vec4 = std::array::from_fn(|c| (a2[c] - 2.0 * a1[4] * first[c] - a2[4] * point[c]) / w);
        Derivatives { point, first, second }
    }

    /// [`NurbsCurve::derivatives_in`] where only C' and C'' are read (the point left at
    /// 0 on a curve of weight 1, [`NurbsCurve::unit`], whose derivatives do not need it).
    pub(crate) fn slopes_in(&self, u: f64, i: usize) -> Derivatives {
        if self.unit {
            let [_, c1, c2, c3] = &self.power[i - self.degree];
            let t = u - self.knots[i];
            return Derivatives { point: [0.0; 4], first: span_first(c1, c2, c3, t), second: span_second(c2, c3, t) };
        }
        self.derivatives_in(u, i)
    }

    /// The point at `u` over all four axes (exactly the end control points at the ends
    /// of the domain).
    pub fn point(&self, u: f64) -> Vec4 {
        let (first, last) = self.domain();
        if u <= first {
            return self.ends[0];
        }
        if u >= last {
            return self.ends[1];
        }
        self.point_in(u, self.span(u))
    }

    /// [`NurbsCurve::point`] at `u` at or after the knot span `span`, which is moved
    /// on to the span of `u` (points taken in increasing `u` find their spans without
    /// a search).
    pub(crate) fn point_after(&self, u: f64, span: &mut usize) -> Vec4 {
        let (first, last) = self.domain();
        if u <= first || u >= last {
            return self.point(u);
        }
        while self.knots[*span + 1] <= u {
            *span += 1;
        }
        self.point_in(u, *span)
    }

    /// [`NurbsCurve::point`] at `u` inside the domain on knot span `i`
    /// ([`NurbsCurve::span_index`] of `u`).
    fn point_in(&self, u: f64, i: usize) -> Vec4 {
        if self.unit {
            let [c0, c1, c2, c3] = &self.power[i - self.degree];
            let t = u - self.knots[i];
            return span_value(c0, c1, c2, c3, t);
        }
        let a = match self.power.get(i - self.degree) {
            Some([c0, c1, c2, c3]) => {
                let t = u - self.knots[i];
                span_value(c0, c1, c2, c3, t)
            }
            None => de_boor(&self.points, &self.knots, self.degree, i, u),
        };
        if self.planar {
            return [a[0] / a[4], a[1] / a[4], self.base[2], self.base[3]];
        }
        std::array::from_fn(|c| a[c] / a[4])
    }

    /// |C'(u)| on the span holding `start`.
    /// (The first derivative alone, as [`NurbsCurve::derivatives_on`] computes it: the
    /// quadratures of the arc length need nothing else. A B-spline of the smoother,
    /// whose weights are all 1, needs only its hodograph.)
    fn speed(&self, u: f64, start: f64) -> f64 {
        self.speed_on(u, self.span(start))
    }

    /// |C'(u)| on knot span `i`.
    fn speed_on(&self, u: f64, i: usize) -> f64 {
        if self.degree == 0 {
            return 0.0;
        }
        if !self.planar {
            if let Some([_, c1, c2, c3]) = self.power.get(i - self.degree) {
                // Weights 1: C' is the derivative of the span's polynomial, no point needed.
                let t = u - self.knots[i];
                let a1: Vec4 = span_first(c1, c2, c3, t);
                return (a1[0] * a1[0] + a1[1] * a1[1] + a1[2] * a1[2] + a1[3] * a1[3]).sqrt();
            }
        }
        let (a, a1) = self.homogeneous_first_on(i, u);
        if self.planar {
            let w = a[4];
            let first = [0, 1].map(|c| (a1[c] - a1[4] * (a[c] / w)) / w);
            first[0].hypot(first[1])
        } else {
            // Weights 1: C' is the hodograph itself.
            (a1[0] * a1[0] + a1[1] * a1[1] + a1[2] * a1[2] + a1[3] * a1[3]).sqrt()
        }
    }

    /// [`NurbsCurve::speed_on`] at each of `us`, all on knot span `i`: the span's form
    /// looked up once for the quadrature's nodes (the same values, node by node).
    #[inline]
    fn speeds_on<const N: usize>(&self, us: [f64; N], i: usize) -> [f64; N] {
        if self.degree != 0 && !self.planar {
            if let Some([_, c1, c2, c3]) = self.power.get(i - self.degree) {
                let knot = self.knots[i];
                // (`from_fn`, not `map`: `map` left a call per node.)
                return std::array::from_fn(|k| {
                    let t = us[k] - knot;
                    let a1: Vec4 = span_first(c1, c2, c3, t);
                    (a1[0] * a1[0] + a1[1] * a1[1] + a1[2] * a1[2] + a1[3] * a1[3]).sqrt()
                });
            }
        }
        std::array::from_fn(|k| self.speed_on(us[k], i))
    }

    /// Arc length from `a` to `b` (within one span) by 5-point Gauss-Legendre quadrature,
    /// halved recursively wherever the speed |C'| varies by more than
    /// [`QUADRATURE_SPEED_SPREAD`] across the nodes. A heavy weight makes |C'| swing by
    /// orders of magnitude within a span (a weight of 1000 on the middle point of a
    /// quadratic: 2000 times its chord at the ends, a thousandth of it in the middle),
    /// where one 5-point rule was off by several per cent. Intervals whose spread times
    /// length is below a thousandth of [`ARC_TOLERANCE`] are not halved.
    pub fn arc_length(&self, a: f64, b: f64) -> f64 {
        self.arc_length_from(a, b, self.span(a), 0)
    }

    /// [`NurbsCurve::arc_length`] on knot span `i`.
    fn arc_length_in(&self, a: f64, b: f64, i: usize) -> f64 {
        self.arc_length_from(a, b, i, 0)
    }

    fn arc_length_from(&self, a: f64, b: f64, span: usize, depth: u32) -> f64 {
        let (mid, half) = (0.5 * (a + b), 0.5 * (b - a));
        let speeds = self.speeds_on(std::array::from_fn::<f64, 5, _>(|k| mid + half * GAUSS[k].0), span);
        let (lo, hi) = speeds.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &v| (lo.min(v), hi.max(v)));
        // Halving stops where the spread can no longer matter (it bounds what the rule
        // can miss, times the interval): near a cusp |C'| runs to zero and the intervals
        // there shrink geometrically.
        let matters = (hi - lo) * 2.0 * half.abs() > 1e-3 * ARC_TOLERANCE;
        if depth < 60 && matters && hi > lo * (1.0 + QUADRATURE_SPEED_SPREAD) && half.abs() > 1e-15 * mid.abs().max(1.0)
        {
            return self.arc_length_from(a, mid, span, depth + 1) + self.arc_length_from(mid, b, span, depth + 1);
        }
        GAUSS.iter().zip(speeds).map(|(&(_, w), v)| w * v).sum::<f64>() * half
    }

    /// Arc length from `a` to `b`, composite quadrature over `parts` (each within one
    /// span, the span of its start).
    pub fn arc_length_composite(&self, a: f64, b: f64, parts: usize) -> f64 {
        let h = (b - a) / parts as f64;
        (0..parts).map(|k| self.arc_length(a + k as f64 * h, a + (k + 1) as f64 * h)).sum()
    }

    /// [`NurbsCurve::arc_length_composite`] on knot span `i` (holding `a .. b`,
    /// [`NurbsCurve::span_index`]).
    pub(crate) fn arc_length_composite_in(&self, a: f64, b: f64, parts: usize, i: usize) -> f64 {
        let h = (b - a) / parts as f64;
        (0..parts).map(|k| self.arc_length_in(a + k as f64 * h, a + (k + 1) as f64 * h, i)).sum()
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
    for _ in 0..200 {
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
    /// The knot span the sub-piece lies in, once found (a sub-piece never crosses a
    /// knot: [`crate::nurbs_pieces`]).
    span: Option<usize>,
}

impl NurbsCursor {
    /// The curve's point at the parameter reached ([`NurbsCurve::point`], on the
    /// sub-piece's knot span once the cursor has found it).
    pub fn point(&self, curve: &NurbsCurve) -> Vec4 {
        let (first, last) = curve.domain();
        match self.span {
            Some(span) if self.u > first && self.u < last => curve.point_in(self.u, span),
            _ => curve.point(self.u),
        }
    }

    /// At the start `u0` of element `element`.
    pub fn new(element: usize, u0: f64) -> NurbsCursor {
        NurbsCursor { element, u0, u: u0, s: 0.0, span: None }
    }

    /// Steps the parameter so that the arc length from the sub-piece's start reaches
    /// `s_target` (not beyond `u1`), and returns the new parameter.
    pub fn advance(&mut self, curve: &NurbsCurve, u1: f64, s_target: f64) -> f64 {
        let ds = s_target - self.s;
        if ds <= ARC_TOLERANCE {
            return self.u;
        }
        let span = *self.span.get_or_insert_with(|| curve.span(self.u0));
        let d = curve.slopes_in(self.u, span);
        let sp2: f64 = d.first.iter().map(|c| c * c).sum();
        let sp = sp2.sqrt();
        let along: f64 = d.first.iter().zip(&d.second).map(|(a, b)| a * b).sum();
        // Second-order Taylor expansion of u(s): du/ds = 1/|C'|, d2u/ds2 = -(C'.C'')/|C'|^4.
        let mut u = self.u + ds / sp - ds * ds * along / (2.0 * sp2 * sp2);
        if let Some(third) = curve.third_in(span) {
            // The third-order term where C''' is known (the smoother's cubics), which
            // leaves the corrector nothing to do on most periods: with sigma = |C'|,
            // sigma' = C'.C'' / sigma, sigma'' = (|C''|^2 + C'.C''' - sigma'^2) / sigma,
            // d3u/ds3 = (3 sigma'^2 - sigma sigma'') / sigma^5.
            let sigma1 = along / sp;
            let second2: f64 = d.second.iter().map(|c| c * c).sum();
            let jerk: f64 = d.first.iter().zip(&third).map(|(a, b)| a * b).sum();
            let sigma2 = (second2 + jerk - sigma1 * sigma1) / sp;
            u += ds * ds * ds * (3.0 * sigma1 * sigma1 - sp * sigma2) / (6.0 * sp2 * sp2 * sp);
        }
        if !(u > self.u && u.is_finite()) {
            u = self.u + ds / sp;
        }
        if !(u > self.u && u.is_finite()) {
            u = u1;
        }
        u = u.min(u1);
        // Corrector: Newton on the covered arc length, inside the bracket [u, u1]; where
        // |C'| swings by orders of magnitude within the step (weights 10^5 apart on a
        // line), Newton leaves the bracket and bisection takes over: up to 200 steps.
        let (mut lo, mut hi) = (self.u, u1);
        let mut covered = curve.arc_length_in(self.u, u, span);
        // The largest |C''| over the span where it is known (the smoother's cubics):
        // after a Newton step `du` the covered length is off by at most `|C''| du^2 / 2`
        // (Taylor: s(u + du) = s(u) + |C'(u)| du + s''/2 du^2, |s''| = |C'.C''| / |C'|
        // <= |C''|), so where that is below a thousandth of ARC_TOLERANCE the step is
        // taken as covering what it aimed at, not measured again.
        let second_max = curve.second_max.get(span - curve.degree).copied();
        for _ in 0..200 {
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
            let du = err / curve.speed_on(u, span).max(1e-300);
            let step = u + du;
            if step > lo && step < hi {
                u = step;
                if second_max.is_some_and(|m| 0.5 * m * du * du <= 1e-3 * ARC_TOLERANCE) {
                    covered += err;
                    break;
                }
            } else {
                u = 0.5 * (lo + hi);
            }
            covered = curve.arc_length_in(self.u, u, span);
        }
        self.u = u;
        self.s += covered;
        u
    }
}

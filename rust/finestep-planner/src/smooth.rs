//! The path smoother: a run of short G1 segments in G64 P, nearly collinear at every
//! vertex, becomes one curve continuous in curvature across all of them (CAM smoothing),
//! so that the S-curve profile is not held at every vertex by the turning jerk of a
//! blend squeezed between two short segments ([`crate::geometry`]).
//!
//! # The fit
//!
//! The run's vertices (on whole steps) `p_0 .. p_m` are parameterised by chord length
//! `s` (0 to the polyline's length `L`). The curve is a clamped cubic B-spline over
//! all four axes on `S` uniform knot spans of `L` (`S + 3` control points `Q_j`):
//!
//! - `Q_0 = p_0` and `Q_{S+2} = p_m`: the curve ends exactly on the run's ends;
//! - `Q_1 = p_0 + h/3 d_0` and `Q_{S+1} = p_m - h/3 d_1` (`h = L / S`): it leaves along
//!   the direction `d_0` the path arrives in and ends along `d_1`, the direction of
//!   the line after the run where the path flows on into it, so the junctions at the
//!   run's ends are tangent;
//! - the others `Q_2 .. Q_S` by least squares on the vertices and the segments'
//!   midpoints, each at its chord-length parameter, with a small fairing term on the
//!   control points' second differences ([`FAIRING`]), which keeps the system regular
//!   where a span holds no data.
//!
//! The fit starts at [`SEGMENTS_PER_SPAN`] segments a span. The curve is then sampled
//! [`SAMPLES_PER_SEGMENT`] times per segment and each sample's distance to the
//! polyline (the segments around the sample's parameter) taken: above
//! [`DEVIATION_SHARE`] of the tolerance P, the spans are doubled in number and the fit
//! repeated, down to one segment a span; if that still deviates, the run is not
//! smoothed (its lines are blended corner by corner as before). The checker
//! ([`crate::checker`]) measures the deviation from the programmed lines independently.

use crate::nurbs::NurbsCurve;
use crate::vec4::{add_scaled, dot, norm, scale, sub, Vec4};

/// Uniform samples of the speed limit per knot span of a smoothed curve (before the
/// bisection of [`crate::nurbs_pieces`]; a G5.2 curve takes
/// [`crate::nurbs_pieces::SAMPLES_PER_SPAN`]).
pub const SAMPLES_PER_SPAN: usize = 8;
/// Segments of the run per knot span where the fit starts.
pub const SEGMENTS_PER_SPAN: usize = 6;
/// Largest distance of the curve from the polyline, as a share of the tolerance P
/// (the rest covers the samples' spacing).
pub const DEVIATION_SHARE: f64 = 0.8;
/// Curve samples per segment for the deviation.
pub const SAMPLES_PER_SEGMENT: usize = 4;
/// Weight of the fairing term (control points' second differences) against the data.
pub const FAIRING: f64 = 1e-2;
/// The most moves in one run (a longer stretch is several runs, tangent where they meet).
pub const MAX_RUN_MOVES: usize = 48;
/// The fewest moves a run must have to be smoothed.
pub const MIN_RUN_MOVES: usize = 4;
/// The most times the knot spans where the curve deviates are halved.
pub const MAX_REFINEMENTS: usize = 6;
/// A segment longer than this many times P is not smoothed (a long line stays a line).
pub const MAX_SEGMENT_TOLERANCES: f64 = 100.0;
/// The largest turn at a vertex inside a run, radians (20 degrees): a sharper vertex is
/// a corner, blended as a corner.
pub const MAX_TURN: f64 = 20.0 * std::f64::consts::PI / 180.0;

/// The non-zero cubic B-spline basis functions at `u` in span `i` (knots[i] <= u <
/// knots[i + 1]): `N_{i-3} .. N_i` (The NURBS Book, A2.2).
fn basis(knots: &[f64], i: usize, u: f64) -> [f64; 4] {
    let mut n = [0.0; 4];
    let (mut left, mut right) = ([0.0; 4], [0.0; 4]);
    n[0] = 1.0;
    for j in 1..=3 {
        left[j] = u - knots[i + 1 - j];
        right[j] = knots[i + j] - u;
        let mut saved = 0.0;
        for r in 0..j {
            let denom = right[r + 1] + left[j - r];
            let temp = if denom > 0.0 { n[r] / denom } else { 0.0 };
            n[r] = saved + right[r + 1] * temp;
            saved = left[j - r] * temp;
        }
        n[j] = saved;
    }
    n
}

/// The span of `u` in the clamped cubic `knots` (`knots[i] <= u < knots[i + 1]`, the
/// last span for the end of the domain).
fn span_of(knots: &[f64], u: f64) -> usize {
    knots.partition_point(|&k| k <= u).saturating_sub(1).clamp(3, knots.len() - 5)
}

/// Cholesky of a symmetric positive definite band matrix of half-bandwidth 3 (row `i`
/// holds `(i, i - d)` at `d`), solved in place for the right-hand sides `rhs`.
fn band_solve(mut m: Vec<[f64; 4]>, rhs: &mut [Vec4]) -> Option<()> {
    let n = m.len();
    for i in 0..n {
        for d in (0..=3.min(i)).rev() {
            let j = i - d;
            let mut sum = m[i][d];
            for k in j.saturating_sub(3).max(i.saturating_sub(3))..j {
                sum -= m[i][i - k] * m[j][j - k];
            }
            if d == 0 {
                if sum.is_nan() || sum <= 0.0 {
                    return None;
                }
                m[i][0] = sum.sqrt();
            } else {
                m[i][d] = sum / m[j][0];
            }
        }
    }
    // L y = b, then L^T x = y.
    for i in 0..n {
        let mut y = rhs[i];
        for d in 1..=3.min(i) {
            y = add_scaled(y, -m[i][d], rhs[i - d]);
        }
        rhs[i] = scale(1.0 / m[i][0], y);
    }
    for i in (0..n).rev() {
        let mut x = rhs[i];
        for d in 1..=3.min(n - 1 - i) {
            x = add_scaled(x, -m[i + d][d], rhs[i + d]);
        }
        rhs[i] = scale(1.0 / m[i][0], x);
    }
    Some(())
}

/// Squared distance from `p` to the segment `a`-`b` (the nearest of several is found on
/// the squares, and one square root taken: the same as the least of the distances).
fn to_segment_squared(p: Vec4, a: Vec4, b: Vec4) -> f64 {
    let d = sub(b, a);
    let dd = dot(d, d);
    let f = if dd > 0.0 { (dot(sub(p, a), d) / dd).clamp(0.0, 1.0) } else { 0.0 };
    let off = sub(p, add_scaled(a, f, d));
    dot(off, off)
}

/// The curve of `spans` spans through `points` (chord-length parameters `s`), leaving
/// along `d0` and ending along `d1` (module docs), or `None` if the system is singular.
fn fit_spans(points: &[Vec4], s: &[f64], d0: Vec4, k0: Option<Vec4>, d1: Vec4, inner: &[f64]) -> Option<NurbsCurve> {
    let total = *s.last()?;
    let spans = inner.len() + 1;
    let count = spans + 3;
    let mut knots = vec![0.0; 4];
    knots.extend_from_slice(inner);
    knots.extend([total; 4]);
    let (h_first, h_last) = (knots[4], total - knots[count - 1]);
    let (first, last) = (points[0], points[points.len() - 1]);
    let mut q = vec![[0.0; 4]; count];
    q[0] = first;
    q[1] = add_scaled(first, h_first / 3.0, d0);
    q[count - 2] = add_scaled(last, -h_last / 3.0, d1);
    q[count - 1] = last;
    // The curvature at the start given: C''(0) = 2 / h_1 (3 (Q_2 - Q_1) / u_5 - d_0) = k_0.
    let first_free = match k0 {
        Some(k) if spans >= 2 => {
            q[2] = add_scaled(q[1], knots[5] / 3.0, add_scaled(d0, 0.5 * h_first, k));
            3
        }
        _ => 2,
    };
    let free = (count - 2).saturating_sub(first_free);
    if free > 0 {
        let fixed = |j: usize| j < first_free || j >= count - 2;
        let mut m = vec![[0.0; 4]; free];
        let mut rhs = vec![[0.0; 4]; free];
        // One row of the normal equations: the fixed control points move to the target's
        // side, the free ones (consecutive indices here, rows of the band) add their
        // products.
        let add_row = |m: &mut [[f64; 4]], rhs: &mut [Vec4], coef: &[(usize, f64)], target: Vec4, weight: f64| {
            let mut r = target;
            let mut free_row = [(0usize, 0.0f64); 4];
            let mut n_free = 0;
            for &(j, c) in coef {
                if fixed(j) {
                    r = add_scaled(r, -c, q[j]);
                } else {
                    free_row[n_free] = (j - first_free, c);
                    n_free += 1;
                }
            }
            let free_row = &free_row[..n_free];
            for (x, &(a, c)) in free_row.iter().enumerate() {
                let wc = weight * c;
                rhs[a] = add_scaled(rhs[a], wc, r);
                for &(b, cb) in &free_row[..=x] {
                    m[a][a - b] += wc * cb;
                }
            }
        };
        let data = |k: usize| -> (Vec4, f64) {
            if k.is_multiple_of(2) {
                (points[k / 2], s[k / 2])
            } else {
                let (a, b) = (points[k / 2], points[k / 2 + 1]);
                (scale(0.5, [a[0] + b[0], a[1] + b[1], a[2] + b[2], a[3] + b[3]]), 0.5 * (s[k / 2] + s[k / 2 + 1]))
            }
        };
        for k in 0..2 * points.len() - 1 {
            let (p, u) = data(k);
            let i = span_of(&knots, u);
            let n = basis(&knots, i, u.min(total));
            if i >= first_free + 3 && i < count - 2 {
                // All four control points free (most rows): `add_row`'s products, in its
                // order, straight into the band.
                let a0 = i - 3 - first_free;
                for x in 0..4 {
                    rhs[a0 + x] = add_scaled(rhs[a0 + x], n[x], p);
                    for y in 0..=x {
                        m[a0 + x][x - y] += n[x] * n[y];
                    }
                }
                continue;
            }
            let coef: [(usize, f64); 4] = std::array::from_fn(|r| (i - 3 + r, n[r]));
            add_row(&mut m, &mut rhs, &coef, p, 1.0);
        }
        for j in 1..count - 1 {
            add_row(&mut m, &mut rhs, &[(j - 1, 1.0), (j, -2.0), (j + 1, 1.0)], [0.0; 4], FAIRING);
        }
        band_solve(m, &mut rhs)?;
        q[first_free..first_free + free].copy_from_slice(&rhs);
    }
    NurbsCurve::spatial(&q, 3, &knots).ok()
}

/// The parameters of the samples of `curve` farther than `limit` from the polyline
/// `points` (chord-length parameters `s`), over [`SAMPLES_PER_SEGMENT`] samples a
/// segment.
fn deviating(curve: &NurbsCurve, points: &[Vec4], s: &[f64], limit: f64) -> Vec<f64> {
    let segments = points.len() - 1;
    let total = s[segments];
    let samples = SAMPLES_PER_SEGMENT * segments;
    let mut out = Vec::new();
    let mut j = 0;
    let mut span = curve.span_index(0.0);
    for k in 1..samples {
        let u = total * k as f64 / samples as f64;
        while j + 1 < segments && s[j + 1] <= u {
            j += 1;
        }
        let p = curve.point_after(u, &mut span);
        // The segment the sample's parameter lies on first: where it is near enough,
        // so is the nearest of all, and the others need not be measured.
        if to_segment_squared(p, points[j], points[j + 1]).sqrt() <= limit {
            continue;
        }
        let near = (j.saturating_sub(2)..=(j + 2).min(segments - 1))
            .map(|i| to_segment_squared(p, points[i], points[i + 1]))
            .fold(f64::INFINITY, f64::min)
            .sqrt();
        if near.is_nan() || near > limit {
            out.push(u);
        }
    }
    out
}

/// The curve smoothing the polyline `points` (at least three), leaving along the unit
/// `d0` (with the curvature vector `k0` where given: the curve before it ends so) and
/// ending along the unit `d1`, within `DEVIATION_SHARE * tolerance` of it
/// (module docs); `None` when no fit stays within it.
pub fn fit(points: &[Vec4], d0: Vec4, k0: Option<Vec4>, d1: Vec4, tolerance: f64) -> Option<NurbsCurve> {
    if points.len() < 3 {
        return None;
    }
    let mut s = Vec::with_capacity(points.len());
    s.push(0.0);
    for w in points.windows(2) {
        let l = norm(sub(w[1], w[0]));
        if l.is_nan() || l <= 0.0 {
            return None;
        }
        s.push(s.last().copied().unwrap_or(0.0) + l);
    }
    let segments = points.len() - 1;
    let total = s[segments];
    let shortest = s.windows(2).map(|w| w[1] - w[0]).fold(f64::INFINITY, f64::min);
    let least = if k0.is_some() { 2 } else { 1 };
    let spans = segments.div_ceil(SEGMENTS_PER_SPAN).max(least);
    let mut inner: Vec<f64> = (1..spans).map(|j| total * j as f64 / spans as f64).collect();
    for _ in 0..MAX_REFINEMENTS {
        let curve = fit_spans(points, &s, d0, k0, d1, &inner)?;
        let bad = deviating(&curve, points, &s, DEVIATION_SHARE * tolerance);
        if bad.is_empty() {
            return Some(curve);
        }
        // Halve every span holding a sample too far (and its neighbours).
        let mut knots = vec![0.0];
        knots.extend_from_slice(&inner);
        knots.push(total);
        let mut split = vec![false; knots.len() - 1];
        for u in bad {
            let i = knots.partition_point(|&k| k <= u).saturating_sub(1).min(split.len() - 1);
            for j in i.saturating_sub(1)..=(i + 1).min(split.len() - 1) {
                split[j] = true;
            }
        }
        let mut refined = Vec::with_capacity(2 * inner.len() + 2);
        for (j, w) in knots.windows(2).enumerate() {
            if j > 0 {
                refined.push(w[0]);
            }
            if split[j] && w[1] - w[0] > 0.5 * shortest {
                refined.push(0.5 * (w[0] + w[1]));
            }
        }
        if refined.len() == inner.len() {
            return None;
        }
        inner = refined;
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_band_solver_solves_a_band_system() {
        // A random-ish SPD band matrix: diagonally dominant.
        let n = 9;
        let mut full = vec![vec![0.0; n]; n];
        for i in 0..n {
            for d in 1..=3 {
                if i >= d {
                    let v = 0.1 * ((i * 7 + d * 3) % 5) as f64 - 0.2;
                    full[i][i - d] = v;
                    full[i - d][i] = v;
                }
            }
            full[i][i] = 3.0 + i as f64 * 0.1;
        }
        let band: Vec<[f64; 4]> =
            (0..n).map(|i| std::array::from_fn(|d| if i >= d { full[i][i - d] } else { 0.0 })).collect();
        let x: Vec<Vec4> = (0..n).map(|i| [i as f64, 1.0 - i as f64, 0.5, -2.0 * i as f64]).collect();
        let mut b: Vec<Vec4> =
            (0..n).map(|i| std::array::from_fn(|c| (0..n).map(|j| full[i][j] * x[j][c]).sum())).collect();
        band_solve(band, &mut b).unwrap();
        for i in 0..n {
            for c in 0..4 {
                assert!((b[i][c] - x[i][c]).abs() < 1e-12, "{i} {c}: {} {}", b[i][c], x[i][c]);
            }
        }
    }

    #[test]
    fn the_basis_sums_to_one() {
        let knots = [0.0, 0.0, 0.0, 0.0, 1.0, 2.0, 3.0, 3.0, 3.0, 3.0];
        for k in 0..30 {
            let u = 3.0 * k as f64 / 30.0;
            let n = basis(&knots, span_of(&knots, u), u);
            assert!((n.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        }
    }
}

//! A NURBS (G5.2/G5.3) as path elements for the look-ahead: sub-pieces of the curve
//! ([`crate::nurbs::NurbsCurve`]) of nearly constant speed limit.
//!
//! The curve is split at its knots into spans, and each span into sub-pieces of nearly
//! constant speed limit ([`pieces`]): the span is sampled at [`SAMPLES_PER_SPAN`] + 1
//! parameters, bisected wherever the tangent turns more than [`MAX_SAMPLE_TURN`]
//! between neighbours (a cusp, where the curve stops and turns back, is refused) or the
//! curvature changes by more than [`MAX_SAMPLE_CURVATURE_CHANGE`] where the curve
//! bends, and
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

use std::sync::Arc;

use crate::config::{ProfileKind, Resolved};
use crate::element::{
    full_caps_turning, short_length, tangential_jerk_share, AxisShare, Caps, Element, Needs, Shape, ARC_JERK_SHARE,
    GEOMETRIC_ACCEL_SHARE, JUNCTION_JERK_SHARE, NORMAL_SHARE_MIN, SMOOTH_NORMAL_SHARE_MIN, SMOOTH_TURNING_JERK_SHARE,
    TANGENTIAL_ACCEL_SHARE, TURNING_JERK_SHARE,
};
use crate::nurbs::{Derivatives, NurbsCurve, NurbsError};
use crate::vec4::{norm, sub, Vec4};

/// Samples of the speed limit per knot span.
pub const SAMPLES_PER_SPAN: usize = 64;
/// Consecutive intervals form one sub-piece while their speed limits stay within this ratio.
pub const PIECE_SPEED_RATIO: f64 = 1.25;

/// Largest relative change of the curvature between neighbouring samples where the
/// curve bends there (module docs).
pub const MAX_SAMPLE_CURVATURE_CHANGE: f64 = 0.25;

/// Largest turn of the tangent between neighbouring samples, radians (5 degrees).
pub const MAX_SAMPLE_TURN: f64 = 5.0 * std::f64::consts::PI / 180.0;

fn cusp_error(d: &Derivatives) -> NurbsError {
    NurbsError::Cusp { x: d.point[0], y: d.point[1] }
}

/// One evaluation of the curve at a sample parameter: the derivatives there, with the
/// speed `|C'|`, the unit tangent and the curvature's magnitude read from them once.
#[derive(Clone, Copy)]
struct Eval {
    u: f64,
    d: Derivatives,
    speed: f64,
    tangent: Vec4,
    k: f64,
}

impl Eval {
    fn at(curve: &NurbsCurve, u: f64, span: usize) -> Eval {
        let d = curve.derivatives_in(u, span);
        let speed = d.speed();
        Eval { u, d, speed, tangent: std::array::from_fn(|c| d.first[c] / speed), k: d.curvature().abs() }
    }
}

/// The sample parameters of the span `ua..ub`: [`SAMPLES_PER_SPAN`] + 1 uniform ones,
/// then bisected wherever the tangent turns by more than [`MAX_SAMPLE_TURN`] between
/// neighbours, so that no sharp bend hides between samples. A turn of more than a
/// right angle that bisection cannot resolve is a cusp: refused.
/// With each parameter the curve's evaluation there ([`Eval`], once: an interval's end
/// is the next one's start, a bisected interval's start the first half's).
/// The evaluations go to `out` (cleared first), `stack` is room for the bisection.
fn sample_parameters(
    curve: &NurbsCurve,
    (ua, ub): (f64, f64),
    per_span: usize,
    out: &mut Vec<Eval>,
    stack: &mut Vec<(f64, f64, u32)>,
) -> Result<(), NurbsError> {
    let span = curve.span_index(ua);
    // The last two evaluations, by parameter.
    let first = Eval::at(curve, ua, span);
    let mut memo: [Eval; 2] = [Eval { u: f64::NAN, ..first }, first];
    // The slot the next evaluation replaces (the older one).
    let mut older = 0;
    let mut eval = |u: f64| {
        if let Some(e) = memo.iter().find(|m| m.u == u) {
            return *e;
        }
        memo[older] = Eval::at(curve, u, span);
        older ^= 1;
        memo[older ^ 1]
    };
    out.clear();
    out.push(eval(ua));
    stack.clear();
    stack.extend(
        (0..per_span).rev().map(|j| {
            (ua + (ub - ua) * j as f64 / per_span as f64, ua + (ub - ua) * (j + 1) as f64 / per_span as f64, 0)
        }),
    );
    while let Some((a, b, depth)) = stack.pop() {
        let ea = eval(a);
        let eb = eval(b);
        let (ta, tb) = (ea.tangent, eb.tangent);
        let cos = ta.iter().zip(&tb).map(|(a, b)| a * b).sum::<f64>().clamp(-1.0, 1.0);
        if cos.is_nan() {
            return Err(cusp_error(&eb.d));
        }
        // The curvature changing fast between samples (a heavy weight bends the curve
        // within a sliver of the parameter): halve until it changes by at most
        // MAX_SAMPLE_CURVATURE_CHANGE, where the bend there is more than a thousandth of
        // a radian, so that no peak of the normal acceleration hides between samples.
        let (da, db) = (&ea.d, &eb.d);
        let (ka, kb) = (ea.k, eb.k);
        let chord = if curve.planar() {
            (db.point[0] - da.point[0]).hypot(db.point[1] - da.point[1])
        } else {
            norm(sub(db.point, da.point))
        };
        let steep = (ka - kb).abs() > MAX_SAMPLE_CURVATURE_CHANGE * ka.max(kb) && ka.max(kb) * chord > 1e-3;
        if steep && depth < 48 && b - a > 1e-13 * (ub - ua) {
            let mid = 0.5 * (a + b);
            stack.push((mid, b, depth + 1));
            stack.push((a, mid, depth + 1));
            continue;
        }
        // acos(cos) > MAX_SAMPLE_TURN, without the arc cosine.
        if cos < MAX_SAMPLE_TURN.cos() {
            if depth < 48 && b - a > 1e-13 * (ub - ua) {
                let mid = 0.5 * (a + b);
                stack.push((mid, b, depth + 1));
                stack.push((a, mid, depth + 1));
                continue;
            }
            if cos < 0.0 {
                return Err(cusp_error(&eb.d));
            }
        }
        out.push(eb);
        if out.len() > 1 << 16 {
            return Err(NurbsError::TooSharp);
        }
    }
    Ok(())
}

/// The speed limits at one sample of the curve.
struct Sample {
    u: f64,
    /// Curvature magnitude, 1/units.
    k: f64,
    /// Unit tangent.
    tangent: Vec4,
    /// Speed cap from curvature, units/s.
    cap: f64,
}

/// The curve as elements ([`Shape::Nurbs`] sub-pieces with their own limits; module
/// docs), for the block on `line` at `feed` units/s; `Err` when the curve cannot be
/// followed (a cusp: the parametric speed vanishes).
pub fn pieces(config: &Resolved, curve: Arc<NurbsCurve>, feed: f64, line: usize) -> Result<Vec<Element>, NurbsError> {
    pieces_sampled(config, curve, feed, line, SAMPLES_PER_SPAN)
}

/// [`pieces`] with `per_span` uniform samples a knot span before bisection (the
/// smoother's cubic spans, a millimetre or two long, take fewer:
/// [`crate::smooth::SAMPLES_PER_SPAN`]).
pub fn pieces_sampled(
    config: &Resolved,
    curve: Arc<NurbsCurve>,
    feed: f64,
    line: usize,
    per_span: usize,
) -> Result<Vec<Element>, NurbsError> {
    let scurve = config.profile == ProfileKind::SCurve;
    // The axes the curve moves: X and Y for a G5.2 curve, those whose control points
    // differ for the smoother's.
    let plane_axes: Vec<usize> = (0..4).filter(|&a| curve.moves(a)).collect();
    let mut out = Vec::new();
    let (start_u, end_u) = curve.domain();
    let size = if curve.planar() {
        let (a, b) = (curve.point(start_u), curve.point(end_u));
        norm(sub(b, a)).max(curve.arc_length_composite(start_u, end_u, 8)).max(1e-9)
    } else {
        // The smoother's curves are parameterised by the chord length of their polyline.
        (end_u - start_u).max(1e-9)
    };
    // The axes' smallest acceleration and jerk: the caps below are the smallest
    // over the axes, and a square or cube root is monotone, so one root of the
    // smallest limit gives the least of the axes' caps.
    let (least_accel, least_jerk) = plane_axes
        .iter()
        .map(|&a| &config.axes[a])
        .filter(|limits| limits.present)
        .fold((f64::INFINITY, f64::INFINITY), |(a, j), l| (a.min(l.max_acceleration), j.min(l.max_jerk)));
    let cap_of = |k: f64, dk: f64| {
        let mut cap = f64::INFINITY;
        if k > 1e-12 {
            let rho = 1.0 / k;
            let delta = config.chord_tolerance_mm.min(rho);
            cap = cap.min(2.0 / config.period_s * (2.0 * rho * delta - delta * delta).max(0.0).sqrt());
            cap = cap.min((GEOMETRIC_ACCEL_SHARE * least_accel / k).sqrt());
        }
        let turning = k * k + dk;
        if scurve && turning > 1e-12 {
            // The cube root only where it binds: a cap whose cube is within the turning's
            // is kept as it is.
            let cubed = ARC_JERK_SHARE * least_jerk / turning;
            let kept = cap * cap * cap <= cubed;
            if !kept {
                cap = cap.min(cubed.cbrt());
            }
        }
        cap
    };
    // The smallest normal share and the turning's share of the jerk at the speed cap:
    // a G5.2 curve's (planar) `NORMAL_SHARE_MIN`, `TURNING_JERK_SHARE`; the smoother's
    // curves `SMOOTH_NORMAL_SHARE_MIN`, `SMOOTH_TURNING_JERK_SHARE`.
    let (normal_min, turning_jerk_share) = if curve.planar() {
        (NORMAL_SHARE_MIN, TURNING_JERK_SHARE)
    } else {
        (SMOOTH_NORMAL_SHARE_MIN, SMOOTH_TURNING_JERK_SHARE)
    };
    // The arc length between samples: a G5.2 curve by two 5-point quadratures (a heavy
    // weight swings |C'| within a span), a smoother's cubic (weights 1, |C'| the root of
    // a quartic in the parameter, its spans a millimetre or two) by one, which the
    // quadrature halves itself where |C'| spreads (`NurbsCurve::arc_length`).
    let quadrature_parts = if curve.planar() { 2 } else { 1 };
    // Room for every span's samples, kept from span to span.
    let (mut params, mut stack, mut samples) = (Vec::new(), Vec::new(), Vec::<Sample>::new());
    let (mut ds, mut dk, mut inner_d, mut inner_k) =
        (Vec::new(), Vec::new(), Vec::<[Derivatives; 3]>::new(), Vec::new());
    let (mut inner_cap, mut tangent_max, mut interval_cap) = (Vec::new(), Vec::<Vec4>::new(), Vec::new());
    for (ua, ub) in curve.spans() {
        let span = curve.span_index(ua);
        sample_parameters(&curve, (ua, ub), per_span, &mut params, &mut stack)?;
        let m = params.len() - 1;
        samples.clear();
        for e in &params {
            let speed = e.speed;
            if speed.is_nan() || speed <= 1e-9 * size / (ub - ua).max(1e-300) || !speed.is_finite() {
                return Err(cusp_error(&e.d));
            }
            samples.push(Sample { u: e.u, k: e.k, tangent: e.tangent, cap: f64::INFINITY });
        }
        // |dk/ds| by differences between samples.
        ds.clear();
        ds.extend(
            (0..m).map(|j| curve.arc_length_composite_in(samples[j].u, samples[j + 1].u, quadrature_parts, span)),
        );
        dk.clear();
        dk.extend((0..=m).map(|j| {
            let back = if j > 0 { (samples[j].k - samples[j - 1].k).abs() / ds[j - 1].max(1e-300) } else { 0.0 };
            let ahead = if j < m { (samples[j + 1].k - samples[j].k).abs() / ds[j].max(1e-300) } else { 0.0 };
            back.max(ahead)
        }));
        for (j, sample) in samples.iter_mut().enumerate() {
            sample.cap = cap_of(sample.k, dk[j]);
        }
        // The curvature inside each interval too, at the three points the tangent bound
        // below evaluates: a peak between samples lowers the interval's cap.
        // The derivatives at the three inner points of every interval, read for both.
        inner_d.clear();
        inner_d.extend((0..m).map(|j| {
            let (a, b) = (samples[j].u, samples[j + 1].u);
            std::array::from_fn(|i| curve.slopes_in(a + (b - a) * (i + 1) as f64 / 4.0, span))
        }));
        inner_k.clear();
        inner_k.extend(inner_d.iter().map(|d| d.iter().map(|d| d.curvature().abs()).fold(0.0, f64::max)));
        inner_cap.clear();
        inner_cap.extend((0..m).map(|j| cap_of(inner_k[j], dk[j].max(dk[j + 1]))));
        // Per interval and axis, the largest tangent component: parabolas through the
        // values at five points of the interval, at their vertices where those are inside
        // (an inflection between samples lets the tangent swing past both ends), kept a
        // millionth high.
        tangent_max.clear();
        tangent_max.extend((0..m).map(|j| {
            let mut f = [samples[j].tangent; 5];
            f[4] = samples[j + 1].tangent;
            for (i, slot) in f.iter_mut().enumerate().take(4).skip(1) {
                let d = &inner_d[j][i - 1];
                let speed = d.speed();
                *slot = std::array::from_fn(|c| d.first[c] / speed);
            }
            std::array::from_fn(|c| {
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
        }));
        // Per interval: the smallest cap of the four samples around it and of its inside.
        interval_cap.clear();
        interval_cap.extend(
            (0..m).map(|j| {
                samples[j.saturating_sub(1)..=(j + 2).min(m)].iter().map(|s| s.cap).fold(inner_cap[j], f64::min)
            }),
        );
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
            let weights: Vec4 = std::array::from_fn(|c| {
                if !plane_axes.contains(&c) {
                    return 0.0;
                }
                let through = window
                    .windows(2)
                    .any(|w| plane_axes.iter().filter(|&&d| d != c).all(|&d| w[0].tangent[d] * w[1].tangent[d] <= 0.0));
                if through {
                    1.0
                } else {
                    intervals.iter().map(|t| t[c]).fold(0.0, f64::max)
                }
            });
            let (u0, u1) = (samples[j].u, samples[end].u);
            let length: f64 = ds[j..end].iter().sum();
            let tangential_share = tangential_jerk_share(length, short_length(config));
            let mut v_cap = feed.min(lo);
            let mut accel = f64::INFINITY;
            let mut jerk = f64::INFINITY;
            for &a in &plane_axes {
                let limits = &config.axes[a];
                let w = weights[a];
                if limits.present && w > 1e-12 {
                    v_cap = v_cap.min(limits.max_velocity / w);
                    accel = accel.min(TANGENTIAL_ACCEL_SHARE * limits.max_acceleration / w);
                    jerk = jerk.min(tangential_share * limits.max_jerk / w);
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
            let shared = Caps { v_cap, accel, jerk };
            // The limits shared by what the sub-piece needs (`crate::element`): the
            // largest curvature and curvature change over it and the samples around it;
            // the normal's components are the tangent's, swapped.
            let k_top = inner_k[j..end].iter().fold(k_max, |a, &b| a.max(b));
            let dk_top = dk[j.saturating_sub(1)..=(end + 1).min(m)].iter().fold(0.0, |a: f64, &b| a.max(b));
            // What turning reads at the shared caps, `(k^2 + k') v^3 + 3 k v a_t`, at the
            // largest curvature and curvature change around the sub-piece, the most of
            // any axis (each term within ARC_JERK_SHARE by the caps above).
            let turning_share = if scurve {
                plane_axes
                    .iter()
                    .filter(|&&a| config.axes[a].present)
                    .map(|&a| {
                        let (k, v) = (k_top.max(k_max), shared.v_cap);
                        ((k * k + dk_top) * v.powi(3) + 3.0 * k * v * shared.accel) / config.axes[a].max_jerk
                    })
                    .fold(0.0, f64::max)
                    .min(2.0 * ARC_JERK_SHARE)
            } else {
                2.0 * ARC_JERK_SHARE
            };
            let mut v_limit = feed;
            if k_top > 1e-12 {
                let rho = 1.0 / k_top;
                let delta = config.chord_tolerance_mm.min(rho);
                v_limit = v_limit.min(2.0 / config.period_s * (2.0 * rho * delta - delta * delta).max(0.0).sqrt());
            }
            // The normal's largest component: in the plane the tangent's other one; over
            // more axes at most 1.
            let normal: Vec4 = std::array::from_fn(|c| {
                if !plane_axes.contains(&c) {
                    0.0
                } else if curve.planar() {
                    weights[1 - c]
                } else {
                    1.0
                }
            });
            let axes: [AxisShare; 4] = std::array::from_fn(|c| {
                let axis = &config.axes[c];
                let present = if axis.present { 1.0 } else { 0.0 };
                AxisShare {
                    w: present * weights[c],
                    n: present * normal[c],
                    velocity: axis.max_velocity,
                    accel: axis.max_acceleration,
                    jerk: axis.max_jerk,
                }
            });
            let Caps { v_cap, accel, jerk } =
                full_caps_turning(&axes, v_limit, k_top, dk_top, scurve, turning_jerk_share, normal_min);
            let start = curve.point(u0);
            let end_point = curve.point(u1);
            out.push(Element {
                shape: Shape::Nurbs { curve: Arc::clone(&curve), u0, u1 },
                start,
                end: end_point,
                length,
                line,
                feed,
                v_cap,
                accel,
                jerk,
                shared,
                needs: Some(Box::new(Needs {
                    axes,
                    k: k_top,
                    dk: dk_top,
                    scurve,
                    normal_min,
                    turning_share: turning_jerk_share,
                })),
                tangential_jerk_share: tangential_share,
                turning_jerk_share: turning_share,
                junction_jerk_share: JUNCTION_JERK_SHARE,
                jump_after: false,
                stop_after: false,
                dwell_periods: 0,
                dwell_line: 0,
                block_end: false,
                events: Vec::new(),
            });
            j = end;
        }
    }
    if out.is_empty() {
        return Err(NurbsError::NoLength);
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

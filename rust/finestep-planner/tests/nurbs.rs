//! NURBS (G5.2/G5.3) through the whole host side: the curve evaluation against an exact
//! ideal, known shapes (a quarter circle, which must run like the arc planner's arc),
//! the committed NURBS programs, and random curves on random machines, every plan
//! passed by the independent checker.

mod common;

use finestep_gcode::Program;
use finestep_planner::nurbs::NurbsCurve;
use finestep_planner::{check_program, plan_program, MachineConfig, PlannedProgram, ProfileKind};
use num_bigint::BigInt;
use num_rational::BigRational;
use num_traits::ToPrimitive;
use proptest::prelude::*;

use common::{config, parse, period_in_slots, plan_and_check, read, PROFILES};

fn positions_and_speeds(planned: &PlannedProgram, config: &MachineConfig) -> (Vec<[f64; 2]>, Vec<f64>) {
    let resolved = config.resolve().unwrap();
    let scale = [resolved.axes[0].steps_per_unit, resolved.axes[1].steps_per_unit];
    let (mut raw, mut out, mut speeds) = ([0i64; 2], Vec::new(), Vec::new());
    for r in &planned.records {
        let mut d2 = 0.0;
        for a in 0..2 {
            raw[a] += i64::from(r.inc[a].to_bits());
            d2 += (r.inc[a].to_num::<f64>() / scale[a]).powi(2);
        }
        out.push([raw[0] as f64 / 65536.0 / scale[0], raw[1] as f64 / 65536.0 / scale[1]]);
        speeds.push(d2.sqrt() / resolved.period_s);
    }
    (out, speeds)
}

// ---------------------------------------------------------------------------------
// The evaluation against an exact ideal.

fn exact(x: f64) -> BigRational {
    BigRational::from_float(x).expect("finite")
}

fn to_f64(x: &BigRational) -> f64 {
    x.to_f64().expect("representable")
}

/// N_{i,k}(u) and their derivatives for every i, exactly, by the Cox-de Boor
/// recursion on rationals (the end of the domain belongs to the last span).
fn exact_basis(
    knots: &[BigRational],
    order: usize,
    count: usize,
    u: &BigRational,
) -> (Vec<BigRational>, Vec<BigRational>) {
    let zero = BigRational::from_integer(BigInt::from(0));
    let one = BigRational::from_integer(BigInt::from(1));
    let end = &knots[count];
    let mut last_span = count - 1;
    while &knots[last_span] >= end {
        last_span -= 1;
    }
    let mut b: Vec<BigRational> = (0..knots.len() - 1)
        .map(|i| {
            if (&knots[i] <= u && u < &knots[i + 1]) || (u >= end && i == last_span) {
                one.clone()
            } else {
                zero.clone()
            }
        })
        .collect();
    let mut d = vec![zero.clone(); b.len()];
    for k in 2..=order {
        let kk = BigRational::from_integer(BigInt::from(k as i64 - 1));
        let mut nb = Vec::new();
        let mut nd = Vec::new();
        for i in 0..knots.len() - k {
            let (mut v, mut dv) = (zero.clone(), zero.clone());
            if knots[i + k - 1] > knots[i] {
                let span = &knots[i + k - 1] - &knots[i];
                v += (u - &knots[i]) / &span * &b[i];
                dv += &kk * &b[i] / &span;
            }
            if knots[i + k] > knots[i + 1] {
                let span = &knots[i + k] - &knots[i + 1];
                v += (&knots[i + k] - u) / &span * &b[i + 1];
                dv -= &kk * &b[i + 1] / &span;
            }
            nb.push(v);
            nd.push(dv);
        }
        b = nb;
        d = nd;
    }
    (b, d)
}

/// C(u) and C'(u) exactly: `A / W` and `(A' W - A W') / W^2`.
fn exact_point(points: &[(f64, f64, f64)], knots: &[f64], order: usize, u: f64) -> ([f64; 2], [f64; 2]) {
    let knots: Vec<BigRational> = knots.iter().map(|&k| exact(k)).collect();
    let u = exact(u);
    let (b, d) = exact_basis(&knots, order, points.len(), &u);
    let zero = BigRational::from_integer(BigInt::from(0));
    let (mut a, mut da) = ([zero.clone(), zero.clone()], [zero.clone(), zero.clone()]);
    let (mut w, mut dw) = (zero.clone(), zero.clone());
    for (i, &(x, y, weight)) in points.iter().enumerate() {
        let weight = exact(weight);
        for (c, value) in [x, y].into_iter().enumerate() {
            let value = exact(value);
            a[c] += &b[i] * &weight * &value;
            da[c] += &d[i] * &weight * &value;
        }
        w += &b[i] * &weight;
        dw += &d[i] * &weight;
    }
    let point = [0, 1].map(|c| to_f64(&(&a[c] / &w)));
    let first = [0, 1].map(|c| to_f64(&((&da[c] * &w - &a[c] * &dw) / (&w * &w))));
    (point, first)
}

#[test]
fn de_boor_agrees_with_exact_rational_evaluation() {
    let curve = (2usize..=5).prop_flat_map(|order| {
        (
            Just(order),
            prop::collection::vec((-50.0..50.0f64, -50.0..50.0f64, 0.2..5.0f64), order..order + 8),
            prop::collection::vec(0.0..1.0f64, 8),
        )
    });
    let mut runner = finestep_testkit::runner("de_boor_agrees_with_exact_rational_evaluation", 64);
    let worst = std::cell::Cell::new((0.0f64, 0.0f64));
    runner
        .run(&curve, |(order, points, at)| {
            let knots = finestep_gcode::nurbs_knots(points.len(), order);
            let curve = NurbsCurve::new(&points, order - 1, &knots, [0.0; 4]).unwrap();
            let (u0, u1) = curve.domain();
            for f in at.into_iter().chain([0.0, 1.0]) {
                let u = u0 + f * (u1 - u0);
                let (point, first) = exact_point(&points, &knots, order, u);
                let d = curve.derivatives(u);
                let p = curve.point(u);
                let size = 100.0;
                let point_error =
                    (d.point[0] - point[0]).hypot(d.point[1] - point[1]).max((p[0] - point[0]).hypot(p[1] - point[1]));
                let speed = first[0].hypot(first[1]).max(1.0);
                let first_error = (d.first[0] - first[0]).hypot(d.first[1] - first[1]) / speed;
                prop_assert!(point_error <= 1e-12 * size, "order {order} u {u}: point {:?} vs {point:?}", d.point);
                prop_assert!(first_error <= 1e-9, "order {order} u {u}: C' {:?} vs {first:?}", d.first);
                let (wp, wf) = worst.get();
                worst.set((wp.max(point_error), wf.max(first_error)));
                // C'' against central differences of the exact C'.
                if order >= 3 {
                    let h = 1e-5 * (u1 - u0);
                    if u - h > u0 && u + h < u1 {
                        let (_, lo) = exact_point(&points, &knots, order, u - h);
                        let (_, hi) = exact_point(&points, &knots, order, u + h);
                        let fd = [0, 1].map(|c| (hi[c] - lo[c]) / (2.0 * h));
                        let scale = fd[0].hypot(fd[1]).max(d.second[0].hypot(d.second[1])).max(1.0);
                        let err = (fd[0] - d.second[0]).hypot(fd[1] - d.second[1]) / scale;
                        // A knot inside (u - h, u + h) makes C'' jump for order 3.
                        let near_knot = knots.iter().any(|&k| (k - u).abs() <= h);
                        prop_assert!(near_knot || err <= 1e-4, "order {order} u {u}: C'' {:?} vs {fd:?}", d.second);
                    }
                }
            }
            Ok(())
        })
        .unwrap();
    let (wp, wf) = worst.get();
    eprintln!("de Boor vs exact: worst point error {wp:.2e} mm, worst relative C' error {wf:.2e}");
}

// ---------------------------------------------------------------------------------
// Known shapes.

/// A quarter circle of radius 10 about the origin from (10, 0) to (0, 10): as a NURBS
/// (order 3, weights 1, 1/sqrt 2, 1) and as an arc.
fn quarter_circle(feed: f64) -> (Program, Program) {
    let w = std::f64::consts::FRAC_1_SQRT_2;
    let nurbs = format!("G21 G90 G17\nG0 X10 Y0\nF{feed}\nG5.2 X10 Y10 P{w:.15}\nX0 Y10\nG5.3\nM2\n");
    let arc = format!("G21 G90 G17\nG0 X10 Y0\nF{feed}\nG3 X0 Y10 I-10 J0\nM2\n");
    (parse("quarter_nurbs.ngc", &nurbs), parse("quarter_arc.ngc", &arc))
}

#[test]
fn a_quarter_circle_nurbs_is_on_the_circle_at_the_arc_s_feed() {
    for profile in PROFILES {
        // F1200 (20 mm/s): the feed rules; F6000 (100 mm/s): the normal acceleration
        // (0.45 * 1000 mm/s^2 on r = 10 mm: 67 mm/s) rules.
        for feed in [1200.0, 6000.0] {
            let config = config(profile);
            let (nurbs, arc) = quarter_circle(feed);
            let (planned, report) = plan_and_check("quarter_nurbs.ngc", &nurbs, &config);
            let (arc_planned, _) = plan_and_check("quarter_arc.ngc", &arc, &config);
            // The periods of the curve (line 6) and of the arc (line 4), without the rapid.
            let on = |planned: &PlannedProgram, line: usize| -> (Vec<[f64; 2]>, Vec<f64>) {
                let (p, v) = positions_and_speeds(planned, &config);
                let keep: Vec<usize> = (0..p.len()).filter(|&k| planned.lines[k] == line).collect();
                (keep.iter().map(|&k| p[k]).collect(), keep.iter().map(|&k| v[k]).collect())
            };
            let (points, speeds) = on(&planned, 6);
            let (_, arc_speeds) = on(&arc_planned, 4);
            // Every period ends on the circle (Q16.16 rounding: 2^-17 steps of 1/800 mm per axis).
            let rounding = 2f64.sqrt() * 0.5 / 65536.0 / 800.0;
            let radial = points.iter().map(|p| (p[0].hypot(p[1]) - 10.0).abs()).fold(0.0, f64::max);
            assert!(radial <= rounding + 1e-9, "{profile:?} F{feed}: {radial} mm off the circle");
            // Chord midpoints within the chord tolerance.
            let sag = points
                .windows(2)
                .map(|w| 10.0 - (0.5 * (w[0][0] + w[1][0])).hypot(0.5 * (w[0][1] + w[1][1])))
                .fold(0.0, f64::max);
            assert!(sag <= 0.001 + rounding, "{profile:?} F{feed}: sag {sag}");
            // Period by period at the arc's speed; at cruise the feed or the normal
            // acceleration cap, as a chord per period of 2 r sin(v T / 2 r) / T.
            assert_eq!(speeds.len(), arc_speeds.len(), "{profile:?} F{feed}");
            let cap = (feed / 60.0f64).min((0.45f64 * 1000.0 * 10.0).sqrt());
            let chord_speed = 2.0 * 10.0 * (cap * 0.001 / 20.0).sin() / 0.001;
            // Q16.16 rounding of two positions: 2 * 2^-17 steps per axis over one period.
            let quantum = 2.0 * 2f64.sqrt() * 0.5 / 65536.0 / 800.0 / 0.001;
            let vs_arc = speeds.iter().zip(&arc_speeds).map(|(v, a)| (v - a).abs()).fold(0.0, f64::max);
            assert!(vs_arc <= 2.0 * quantum + 1e-9, "{profile:?} F{feed}: {vs_arc} mm/s from the arc's speed");
            // Cruising: the period and both neighbours within 1e-3 of the cruise speed (a
            // period where a ramp ends is not).
            let near = |v: f64| (v / chord_speed - 1.0).abs() < 1e-3;
            let cruising: Vec<f64> = (1..speeds.len() - 1)
                .filter(|&k| (k - 1..=k + 1).all(|i| near(arc_speeds[i])))
                .map(|k| speeds[k])
                .collect();
            assert!(
                cruising.len() * 5 > speeds.len(),
                "{profile:?} F{feed}: {} of {} periods at speed",
                cruising.len(),
                speeds.len()
            );
            let feed_error = cruising.iter().map(|v| (v / chord_speed - 1.0).abs()).fold(0.0, f64::max);
            // (An S-curve on this short arc may peak a hair below the cap.)
            if profile == ProfileKind::Trapezoid {
                assert!(feed_error <= quantum / chord_speed + 1e-9, "{profile:?} F{feed}: feed error {feed_error}");
            }
            let arc_error = vs_arc / chord_speed;
            let cruise = chord_speed;
            let periods = (speeds.len() as f64 - arc_speeds.len() as f64).abs();
            assert!(periods <= 2.0, "{profile:?} F{feed}: {} vs {} periods", speeds.len(), arc_speeds.len());
            eprintln!(
                "quarter circle {profile:?} F{feed}: {} periods (arc {}), cruise {cruise:.4} mm/s, feed error {feed_error:.2e} (against the arc {arc_error:.2e}), off the circle {radial:.2e} mm, max chord sag {sag:.2e} mm, checker deviation {:.2e} mm",
                speeds.len(),
                arc_speeds.len(),
                report.max_deviation
            );
        }
    }
}

#[test]
fn the_chord_tolerance_limits_the_speed_on_a_tight_curve() {
    // A quarter circle of radius 1 on a stiff machine: the chord tolerance (1 um) allows
    // 2/T sqrt(2 r delta - delta^2) = 89.4 mm/s, below the feed and the normal
    // acceleration cap; the chords then sag by the whole tolerance and no more.
    let w = std::f64::consts::FRAC_1_SQRT_2;
    let text = format!("G21 G90 G17\nG0 X1 Y0\nF6000\nG5.2 X1 Y1 P{w:.15}\nX0 Y1\nG5.3\nM2\n");
    let program = parse("tight.ngc", &text);
    for profile in PROFILES {
        let mut config = config(profile);
        for axis in config.axes.values_mut() {
            axis.max_acceleration = 2e4;
            axis.max_jerk = 1e7;
        }
        let (planned, report) = plan_and_check("tight.ngc", &program, &config);
        let (points, speeds) = positions_and_speeds(&planned, &config);
        let on: Vec<usize> = (0..points.len()).filter(|&k| planned.lines[k] == 6).collect();
        let sag = on
            .windows(2)
            .map(|k| 1.0 - (0.5 * (points[k[0]][0] + points[k[1]][0])).hypot(0.5 * (points[k[0]][1] + points[k[1]][1])))
            .fold(0.0, f64::max);
        let fastest = on.iter().map(|&k| speeds[k]).fold(0.0, f64::max);
        let rounding = 2f64.sqrt() * 0.5 / 65536.0 / 800.0;
        assert!(sag <= 0.001 + rounding && sag > 0.0009, "{profile:?}: sag {sag} mm");
        assert!(fastest < 89.5 && fastest > 85.0, "{profile:?}: {fastest} mm/s");
        eprintln!("tight quarter circle {profile:?}: fastest {fastest:.3} mm/s, max chord sag {sag:.3e} mm (tolerance 1e-3), checker deviation {:.3e} mm", report.max_deviation);
    }
}

#[test]
fn every_parameter_step_covers_the_arc_length_asked_for() {
    // The cursor alone on a free-form rational cubic, 0.05 mm (3 m/min at 1 ms) a step:
    // each step's arc length (measured by a finer quadrature) is the one asked for, and
    // the sum over a span is its length; the Taylor step alone is off by far more.
    let points =
        [(0.0, 0.0, 1.0), (5.0, 12.0, 3.0), (15.0, -8.0, 0.3), (25.0, 10.0, 1.0), (30.0, 0.0, 2.0), (40.0, 5.0, 1.0)];
    let knots = finestep_gcode::nurbs_knots(points.len(), 4);
    let curve = NurbsCurve::new(&points, 3, &knots, [0.0; 4]).unwrap();
    let (mut worst_step, mut worst_taylor, mut worst_end) = (0.0f64, 0.0f64, 0.0f64);
    for (ua, ub) in curve.spans() {
        let length = curve.arc_length_composite(ua, ub, 64);
        let mut cursor = finestep_planner::nurbs::NurbsCursor::new(0, ua);
        let mut s = 0.0;
        while s + 0.05 < length {
            s += 0.05;
            let (u_before, s_before) = (cursor.u, cursor.s);
            // The second-order Taylor step alone, for comparison.
            let d = curve.derivatives(u_before);
            let sp2 = d.first[0].powi(2) + d.first[1].powi(2);
            let along = d.first[0] * d.second[0] + d.first[1] * d.second[1];
            let ds = s - s_before;
            let taylor = u_before + ds / sp2.sqrt() - ds * ds * along / (2.0 * sp2 * sp2);
            worst_taylor = worst_taylor.max((curve.arc_length_composite(u_before, taylor, 16) - ds).abs());
            let u = cursor.advance(&curve, ub, s);
            worst_step = worst_step.max((curve.arc_length_composite(u_before, u, 16) - ds).abs());
        }
        worst_end = worst_end.max((curve.arc_length_composite(ua, cursor.u, 64) - s).abs());
    }
    eprintln!("parameter steps of 0.05 mm: worst step error {worst_step:.1e} mm (Taylor alone {worst_taylor:.1e} mm), worst accumulated {worst_end:.1e} mm");
    assert!(worst_step < 1e-9, "{worst_step}");
    assert!(worst_end < 1e-9, "{worst_end}");
    assert!(worst_taylor > 10.0 * worst_step, "{worst_taylor} vs {worst_step}");
}

#[test]
fn every_parameter_step_on_a_smoothed_cubic_covers_the_arc_length_asked_for() {
    // The cursor on a cubic B-spline over four axes, as the path smoother makes them
    // (weights 1, parameterised by about the chord length), where a Newton step whose
    // remainder bound (the span's largest |C''|) is small is not measured again: each
    // step's arc length (a finer quadrature) is the one asked for, to ARC_TOLERANCE,
    // at the steps of 3 m/min and of 0.6 m/min at 1 ms; the sum over a span is its length.
    let points: Vec<[f64; 4]> = (0..9)
        .map(|i| {
            let t = i as f64;
            [t, 0.4 * (1.3 * t).sin(), 0.2 * (0.7 * t).cos() - 0.01 * t, 0.0]
        })
        .collect();
    let knots = finestep_gcode::nurbs_knots(points.len(), 4);
    let knots: Vec<f64> = knots.iter().map(|k| k * 8.0).collect();
    let curve = NurbsCurve::spatial(&points, 3, &knots).unwrap();
    let tolerance = finestep_planner::nurbs::ARC_TOLERANCE;
    for step in [0.05, 0.01] {
        let (mut worst_step, mut worst_end) = (0.0f64, 0.0f64);
        for (ua, ub) in curve.spans() {
            let length = curve.arc_length_composite(ua, ub, 64);
            let mut cursor = finestep_planner::nurbs::NurbsCursor::new(0, ua);
            let mut s = 0.0;
            while s + step < length {
                s += step;
                let u_before = cursor.u;
                let ds = s - cursor.s;
                let u = cursor.advance(&curve, ub, s);
                worst_step = worst_step.max((curve.arc_length_composite(u_before, u, 16) - ds).abs());
            }
            worst_end = worst_end.max((curve.arc_length_composite(ua, cursor.u, 64) - s).abs());
        }
        eprintln!("smoothed cubic, steps of {step} mm: worst step error {worst_step:.1e} mm, worst accumulated {worst_end:.1e} mm");
        assert!(worst_step <= 2.0 * tolerance, "{step}: {worst_step}");
        assert!(worst_end < 1e-9, "{step}: {worst_end}");
    }
}

#[test]
fn a_free_form_cubic_ends_exactly_and_stays_on_the_curve() {
    // A rational cubic through the whole pipeline: on the curve within the chord
    // tolerance, at most the feed, and exactly on its last control point.
    let text = "G21 G90 G17\nG0 X0 Y0\nF3000\nG5.2 X5 Y12 P3 L4\nX15 Y-8 P0.3\nX25 Y10\nX30 Y0 P2\nX40 Y5\nG5.3\nM2\n";
    let program = parse("free.ngc", text);
    let config = config(ProfileKind::Trapezoid);
    let (planned, report) = plan_and_check("free.ngc", &program, &config);
    let (points, _) = positions_and_speeds(&planned, &config);
    assert_eq!(points.last().copied(), Some([40.0, 5.0]));
    assert!(report.max_deviation <= 0.001 + 0.001, "{}", report.max_deviation);
    eprintln!(
        "free-form cubic: {} periods, checker deviation {:.2e} mm, feed ratio {:.6}",
        planned.records.len(),
        report.max_deviation,
        report.max_feed_ratio
    );
}

#[test]
fn a_nurbs_smaller_than_a_step_moves_as_a_line() {
    // Control points within half a step (1/1600 mm) of the ends: a line on this machine,
    // here nothing at all (in G61) as it ends where it began. A curve of a few steps is
    // still a curve.
    for (text, line, periods_at_most) in [
        ("G21 G90 G17 G61\nG1 X1 Y2 F600\nG5.2 X1.0003 Y2.0002\nX1 Y2\nG5.3\nG1 X0 Y0\nM2\n", 5, 0),
        ("G21 G90 G17\nG1 X1 Y2 F600\nG5.2 X1.0003 Y2.0002\nX1.01 Y2.0003\nX1.01 Y2\nG5.3\nM2\n", 6, 20),
    ] {
        let program = parse("tiny.ngc", text);
        let config = config(ProfileKind::Trapezoid);
        let (planned, _) = plan_and_check("tiny.ngc", &program, &config);
        let on_curve = planned.lines.iter().filter(|&&l| l == line).count();
        assert!(on_curve <= periods_at_most, "{on_curve} periods\n{text}");
    }
}

#[test]
fn a_nurbs_with_cutter_compensation_or_a_cusp_is_refused() {
    let config = config(ProfileKind::Trapezoid);
    // A repeated control point of a quadratic makes the parametric speed vanish.
    let cusp = parse("cusp.ngc", "F600\nG5.2 X5 Y5\nX5 Y5\nX10 Y0\nG5.3\n");
    let error = plan_program(&config, &cusp).unwrap_err();
    assert_eq!(error.line, 5, "{error}");
    assert!(error.reason.contains("cusp"), "{error}");
    // The parser refuses G5.2 with compensation on; a program built otherwise is refused
    // by the compensation pass, never cut without its offset.
    use finestep_gcode::{Block, BlockKind, CompSide, NurbsPoint, Plane, Point};
    let point = |x_mm: f64, y_mm: f64| Point { x_mm, y_mm, ..Point::default() };
    let control_points = vec![
        NurbsPoint { x_mm: 5.0, y_mm: 0.0, weight: 1.0 },
        NurbsPoint { x_mm: 5.0, y_mm: 5.0, weight: 1.0 },
        NurbsPoint { x_mm: 0.0, y_mm: 5.0, weight: 1.0 },
    ];
    let kinds = [
        BlockKind::CutterComp { side: CompSide::Left, tool: Some(1), plane: Plane::Xy },
        BlockKind::Linear { to: point(5.0, 0.0), feed_mm_per_min: 600.0 },
        BlockKind::Nurbs {
            to: point(0.0, 5.0),
            control_points,
            order: 3,
            knots: finestep_gcode::nurbs_knots(3, 3),
            feed_mm_per_min: 600.0,
        },
    ];
    let program = Program {
        blocks: kinds.into_iter().enumerate().map(|(i, kind)| Block { line: i + 1, n: None, kind }).collect(),
    };
    let error = plan_program(&config, &program).unwrap_err();
    assert_eq!(error.line, 3, "{error}");
    assert!(error.reason.contains("not offset"), "{error}");
}

// ---------------------------------------------------------------------------------
// Random curves on random machines.

/// A random program: a lead-in line, a NURBS of random order, points and weights (now
/// and then a control point repeated, which may make a cusp), and a line out, in G64 or
/// G61.
fn random_nurbs_program() -> impl Strategy<Value = String> {
    let point = (-20.0..20.0f64, -20.0..20.0f64, 0.2..5.0f64, 0u8..10);
    (2u32..=4, prop::collection::vec(point, 1..10), 600.0..6000.0f64, any::<bool>(), 0.2..5.0f64).prop_map(
        |(order, points, feed, exact, first_weight)| {
            let mut text = format!("G21 G90 G17 {}\nG1 X1 Y2 F{feed:.0}\n", if exact { "G61" } else { "G64 P0.01" });
            text.push_str(&format!("G5.2 P{first_weight:.3} L{order}\n"));
            let (mut last_x, mut last_y) = (1.0, 2.0);
            for &(x, y, w, repeat) in &points {
                let (x, y) = if repeat == 0 { (last_x, last_y) } else { (x, y) };
                text.push_str(&format!("X{x:.4} Y{y:.4} P{w:.3}\n"));
                (last_x, last_y) = (x, y);
            }
            text.push_str("G5.3\nG1 X0 Y0\nM2\n");
            text
        },
    )
}

#[test]
fn random_nurbs_on_random_machines_plan_or_refuse_and_pass_the_checker() {
    let axis = (1.5..3.5f64, 1.0..3.0f64, 1.5..4.5f64, 3.0..7.0f64)
        .prop_map(|(s, v, a, j)| (10f64.powf(s), 10f64.powf(v), 10f64.powf(a), 10f64.powf(j)));
    let machine = (prop::array::uniform2(axis), 0.25..2.0f64, any::<bool>(), 1e-4..0.05f64);
    let mut runner =
        finestep_testkit::runner("random_nurbs_on_random_machines_plan_or_refuse_and_pass_the_checker", 32);
    let outcomes = std::cell::RefCell::new([0usize; 4]); // parse refused, machine refused, plan refused, planned
    runner
        .run(&(machine, random_nurbs_program()), |((axes, period_ms, scurve, chord_tolerance), text)| {
            let mut config = MachineConfig {
                period_ms: period_in_slots(period_ms),
                profile: if scurve { ProfileKind::SCurve } else { ProfileKind::Trapezoid },
                chord_tolerance_mm: chord_tolerance,
                ..MachineConfig::default()
            };
            for (name, (steps, velocity, accel, jerk)) in ["X", "Y"].into_iter().zip(axes) {
                config.axes.insert(
                    name.to_string(),
                    finestep_planner::config::AxisLimits {
                        steps_per_unit: steps,
                        max_velocity: velocity,
                        max_acceleration: accel,
                        max_jerk: jerk,
                    },
                );
            }
            let program = match finestep_gcode::parse_str(&text, "random_nurbs.ngc") {
                Ok(p) => p,
                Err(e) => {
                    // Too few control points for the order: a clear error on the G5.3 line.
                    prop_assert!(e.to_string().contains("control points"), "{e}\n{text}");
                    outcomes.borrow_mut()[0] += 1;
                    return Ok(());
                }
            };
            if config.resolve().is_err() {
                outcomes.borrow_mut()[1] += 1;
                return Ok(());
            }
            match plan_program(&config, &program) {
                Err(e) => {
                    prop_assert!(e.line > 0 && !e.reason.is_empty(), "{e}");
                    outcomes.borrow_mut()[2] += 1;
                    Ok(())
                }
                Ok(planned) => {
                    outcomes.borrow_mut()[3] += 1;
                    let report = check_program(&config, &program, &planned.records).unwrap();
                    prop_assert!(report.passed(), "{config:?}: {:#?}\n{}", report.violations, text);
                    prop_assert!(report.endpoint_error_steps == [0.0; 4]);
                    Ok(())
                }
            }
        })
        .unwrap();
    let outcomes = outcomes.into_inner();
    eprintln!("parse refused, machine refused, plan refused, planned: {outcomes:?}");
    assert!(outcomes[3] * 3 >= outcomes.iter().sum::<usize>(), "too few random NURBS planned: {outcomes:?}");
}

// ---------------------------------------------------------------------------------
// The committed NURBS programs (the corpus test plans and checks them too).

#[test]
fn a_circle_of_four_nurbs_runs_round_at_the_feed() {
    for profile in PROFILES {
        let config = config(profile);
        let (planned, report) = plan_and_check("nurbs_circle.ngc", &read("nurbs_circle.ngc"), &config);
        let (points, speeds) = positions_and_speeds(&planned, &config);
        // The four quarters (their G5.3 lines 10, 13, 16, 19), on the circle and at the feed, 50 mm/s:
        // the junctions between them are tangent with equal curvature.
        let on: Vec<usize> = (0..points.len()).filter(|&k| [10, 13, 16, 19].contains(&planned.lines[k])).collect();
        let radial =
            on.iter().map(|&k| ((points[k][0] - 50.0).hypot(points[k][1] - 30.0) - 20.0).abs()).fold(0.0, f64::max);
        assert!(radial < 1e-7, "{profile:?}: {radial} mm off the circle");
        // (S-curve: the curvature jump where the straight lead-in meets the circle holds
        // the speed to about sqrt(0.25 J T R) = 22 mm/s there, as for an arc; the junctions
        // between the quarters have none.)
        let middle: &[usize] = if profile == ProfileKind::Trapezoid { &[10, 13, 16, 19] } else { &[13, 16] };
        let slowest = on
            .iter()
            .filter(|&&k| middle.contains(&planned.lines[k]))
            .map(|&k| speeds[k])
            .fold(f64::INFINITY, f64::min);
        assert!(slowest > 49.99, "{profile:?}: {slowest} mm/s on the circle");
        assert!(
            report.max_deviation < 0.0015,
            "{profile:?}: {} on line {}",
            report.max_deviation,
            report.max_deviation_line
        );
        eprintln!("NURBS circle {profile:?}: {} periods, slowest {slowest:.4} mm/s on the circle, {radial:.1e} mm off it, checker deviation {:.2e} mm", on.len(), report.max_deviation);
    }
}

#[test]
fn a_free_form_contour_of_nurbs_passes_the_checker() {
    for profile in PROFILES {
        let config = config(profile);
        let (planned, report) = plan_and_check("nurbs_contour.ngc", &read("nurbs_contour.ngc"), &config);
        // Only chords and half a step of rounding: no corner is blended.
        assert!(
            report.max_deviation < 0.0015,
            "{profile:?}: {} on line {}",
            report.max_deviation,
            report.max_deviation_line
        );
        assert!(report.max_feed_ratio <= 1.0 + 1e-4, "{profile:?}: {}", report.max_feed_ratio);
        // The order-2 NURBS stops nearly dead at its corners (X0 Y20, 3 periods either side).
        let (points, speeds) = positions_and_speeds(&planned, &config);
        let corner = (0..points.len()).min_by(|&a, &b| {
            let d = |k: usize| points[k][0].hypot(points[k][1] - 20.0);
            d(a).total_cmp(&d(b))
        });
        let k = corner.unwrap();
        assert!(
            speeds[k.saturating_sub(3)..=k + 3].iter().any(|&v| v < 1.0),
            "{profile:?}: {:?}",
            &speeds[k - 3..=k + 3]
        );
        eprintln!(
            "NURBS contour {profile:?}: {} periods, checker deviation {:.2e} mm, feed ratio {:.6}",
            planned.records.len(),
            report.max_deviation,
            report.max_feed_ratio
        );
    }
}

// ---------------------------------------------------------------------------------
// Heavy and light weights (issue 18).

#[test]
fn a_heavy_weight_is_planned_within_the_feed() {
    // The curve: refused at emit time as a "planner bug" at P1000 (a jump of 490
    // steps in one period), the feed exceeded by 0.003 % at P50 and 0.56 % at P100. The
    // sub-pieces' lengths and the cursor's steps came from one 5-point quadrature where
    // |C'| swings by orders of magnitude.
    for weight in [1000.0, 100.0, 50.0, 1e4, 1e-3] {
        let source = format!("G0 X0 Y0\nF600\nG5.2 X10 Y10 P{weight}\nX20 Y0 P1\nG5.3\nM2\n");
        let program = parse("heavy.ngc", &source);
        for profile in PROFILES {
            let config = config(profile);
            let (planned, report) = plan_and_check("heavy.ngc", &program, &config);
            // Within the feed up to the Q16.16 rounding of a 0.01 mm period (2^-16 of a
            // step in 8 steps).
            assert!(report.max_feed_ratio <= 1.0 + 5e-6, "P{weight} {profile:?}: {}", report.max_feed_ratio);
            // And at the feed on the flat stretches: no period moves more than the feed
            // allows, and the curve (at most 28.3 mm) takes at least its length at 10 mm/s.
            let (_, speeds) = positions_and_speeds(&planned, &config);
            let covered: f64 = speeds.iter().sum::<f64>() * 1e-3;
            assert!(covered > 20.0 && covered < 28.4, "P{weight}: {covered} mm");
        }
    }
}

#[test]
fn the_arc_length_holds_at_heavy_weights() {
    // A quadratic with its middle weight over seven decades, against Simpson's rule on
    // 2^20 intervals of |C'| over the whole curve and parts of it (2^22 over the whole
    // at 10^4, where 2^20 is still 5e-7 mm off: 2^22 is within 2e-9 mm of 2^24).
    for (weight, n, parts) in [(1e-3, 20, 4), (0.1, 20, 4), (1.0, 20, 4), (10.0, 20, 4), (1e3, 20, 4), (1e4, 24, 1)] {
        let points = [(0.0, 0.0, 1.0), (10.0, 10.0, weight), (20.0, 0.0, 1.0)];
        let knots = finestep_gcode::nurbs_knots(points.len(), 3);
        let curve = NurbsCurve::new(&points, 2, &knots, [0.0; 4]).unwrap();
        let speed = |u: f64| curve.derivatives(u).speed();
        for &(a, b) in [(0.0, 1.0), (0.0, 0.3), (0.45, 0.55), (0.499, 0.5)].iter().take(parts) {
            let reference = simpson(&speed, a, b, 1 << n);
            let got = curve.arc_length(a, b);
            assert!((got - reference).abs() <= 1e-9 * reference.max(1.0), "P{weight} {a}..{b}: {got} vs {reference}");
        }
    }
}

/// Simpson's rule on `n` intervals of `f` over `a..b`.
fn simpson(f: &dyn Fn(f64) -> f64, a: f64, b: f64, n: usize) -> f64 {
    let h = (b - a) / n as f64;
    (0..n / 2)
        .map(|i| {
            let u = a + 2.0 * i as f64 * h;
            h / 3.0 * (f(u) + 4.0 * f(u + h) + f(u + 2.0 * h))
        })
        .sum()
}

#[test]
fn random_weights_plan_within_the_feed_or_refuse_a_cusp() {
    // Weights log-uniform over 10^-3..10^4 on curves of order 2 to 4: the plan passes
    // the checker within the feed, or the curve is refused as a cusp or too sharp, never
    // at emit time.
    let point = (-20.0..20.0f64, -20.0..20.0f64, -3.0..4.0f64);
    let curve = (2u32..=4, prop::collection::vec(point, 3..7), 300.0..6000.0f64, any::<bool>());
    let mut runner = finestep_testkit::runner("random_weights_plan_within_the_feed_or_refuse_a_cusp", 48);
    runner
        .run(&curve, |(order, points, feed, scurve)| {
            let mut text = format!("G21 G90 G17 G64 P0.01\nG1 X1 Y2 F{feed:.0}\nG5.2 L{order}\n");
            for &(x, y, w) in &points {
                text.push_str(&format!("X{x:.4} Y{y:.4} P{:.6}\n", 10f64.powf(w)));
            }
            text.push_str("G5.3\nG1 X0 Y0\nM2\n");
            let Ok(program) = finestep_gcode::parse_str(&text, "weights.ngc") else {
                return Ok(()); // fewer control points than the order
            };
            let profile = if scurve { ProfileKind::SCurve } else { ProfileKind::Trapezoid };
            let config = config(profile);
            match plan_program(&config, &program) {
                Err(e) => {
                    prop_assert!(
                        e.reason.contains("cusp") || e.reason.contains("too sharply"),
                        "{profile:?}: {e}\n{text}"
                    );
                }
                Ok(planned) => {
                    // Every record within the rated rate (the plan was emitted), every
                    // limit, the feed (the checker's bound, with the Q16.16 rounding), the
                    // path and the exact end. The acceleration at a sharp junction next to
                    // a heavy weight went up to 55 % over in one period (seeds
                    // 0x5780d0fb1e2da647 and 0x1234 at FINESTEP_CASES=300) until the
                    // junction cap stopped cancelling (lookahead::quadratic_cap).
                    let report = check_program(&config, &program, &planned.records).unwrap();
                    prop_assert!(report.passed(), "{profile:?}: {:#?}\n{text}", report.violations);
                    prop_assert!(report.endpoint_error_steps == [0.0; 4]);
                }
            }
            Ok(())
        })
        .unwrap();
}

#[test]
fn sharp_junctions_next_to_heavy_weights_keep_the_acceleration() {
    // Found by random_weights_plan_within_the_feed_or_refuse_a_cusp (seed
    // 0x5780d0fb1e2da647, 300 cases): an order-2 corner reversing at a weight of 8196,
    // whose straight spans read a curvature of 1e-13 (the junction cap cancelled to 2.5
    // times its value: X 1467 mm/s^2 of 1000), and NURBS ends reversing into a line
    // after sub-pieces shorter than a period's travel (their full tangential
    // acceleration read beside the jump: Y 1028 and 1055).
    let cases = [
        "G1 X1 Y2 F1128\nG5.2 L2\nX11.8528 Y-2.4564 P0.443244\nX-14.3517 Y4.6006 P8196.367451\n\
         X14.5670 Y9.3060 P7124.346411\nX-5.7417 Y13.3060 P3514.288610\nG5.3\nG1 X0 Y0\nM2\n",
        "G1 X1 Y2 F3134\nG5.2 L4\nX-10.2627 Y-6.5378 P74.714263\nX-6.3088 Y-7.9674 P0.003819\n\
         X-4.1372 Y8.5314 P0.029399\nX-15.8034 Y-18.4844 P1265.232038\nG5.3\nG1 X0 Y0\nM2\n",
        "G1 X1 Y2 F5702\nG5.2 L4\nX12.5127 Y14.0732 P1229.143105\nX-11.7672 Y8.8175 P0.002041\n\
         X12.8139 Y6.4662 P0.093901\nX10.1098 Y-12.0480 P3087.395748\nG5.3\nG1 X0 Y0\nM2\n",
    ];
    for text in cases {
        let program = parse("heavy.ngc", &format!("G21 G90 G17 G64 P0.01\n{text}"));
        for profile in PROFILES {
            plan_and_check("heavy.ngc", &program, &config(profile));
        }
    }
}

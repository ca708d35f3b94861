//! The path smoother ([`finestep_planner::smooth`]): runs of short G1 segments in G64 P
//! become one curve continuous in curvature (S-curve), within P of the programmed lines
//! as the independent checker measures it, ending exactly on the program's end; real
//! corners and long lines stay as they were.

mod common;

use finestep_planner::geometry::{elements, Element, Shape};
use finestep_planner::smooth::fit;
use finestep_planner::{check_program, plan_program, MachineConfig, ProfileKind};

fn scurve() -> MachineConfig {
    MachineConfig { profile: ProfileKind::SCurve, ..MachineConfig::default() }
}

fn path(config: &MachineConfig, text: &str) -> Vec<Element> {
    let program = finestep_gcode::parse_str(text, "smooth.ngc").unwrap();
    elements(&config.resolve().unwrap(), &program).unwrap().elements
}

/// Plans `text`, checks it with the independent checker (which must pass) and returns
/// the largest deviation it measured.
fn checked_deviation(config: &MachineConfig, text: &str) -> f64 {
    let program = finestep_gcode::parse_str(text, "smooth.ngc").unwrap();
    let planned = plan_program(config, &program).unwrap();
    let report = check_program(config, &program, &planned.records).unwrap();
    assert!(report.passed(), "{:?}", &report.violations[..report.violations.len().min(5)]);
    assert!(report.endpoint_error_steps.iter().all(|&e| e == 0.0), "{:?}", report.endpoint_error_steps);
    report.max_deviation
}

fn is_curve(e: &Element) -> bool {
    matches!(e.shape, Shape::Nurbs { .. })
}

/// The bench's CAM program (wavy spiral, Z staircase, G64 P0.01), its first `moves`.
fn cam(moves: usize) -> String {
    finestep_planner::figures::cam_program(moves) + "M2\n"
}

#[test]
fn short_segments_become_one_curve_within_p_ending_exactly() {
    let config = scurve();
    let text = cam(600);
    let made = path(&config, &text);
    let curves = made.iter().filter(|e| is_curve(e)).count();
    assert!(curves * 10 >= made.len() * 9, "{curves} of {} elements smoothed", made.len());
    // Corner blends only where a run begins or ends (the first, long, line from the
    // origin; the last line before the end), not at every vertex.
    let blends = made.iter().filter(|e| matches!(e.shape, Shape::Clothoid { .. })).count();
    assert!(blends <= 3, "{blends} corner blends");
    // Within P (0.01) plus the chord tolerance and half a step per axis, as measured by
    // the checker against the programmed lines.
    let rounding = 3f64.sqrt() * 0.5 / 800.0;
    let deviation = checked_deviation(&config, &text);
    assert!(deviation <= 0.01 + config.chord_tolerance_mm + rounding, "{deviation}");
    // And faster than corner by corner.
    let program = finestep_gcode::parse_str(&text, "smooth.ngc").unwrap();
    let smoothed = plan_program(&config, &program).unwrap().records.len();
    let corners = {
        let resolved = {
            let mut r = config.resolve().unwrap();
            r.smooth_short_segments = false;
            r
        };
        let path = elements(&resolved, &program).unwrap();
        finestep_planner::interpolate::Periods::new(resolved, path.elements, path.leading_dwell).count()
    };
    assert!((smoothed as f64) < 0.9 * corners as f64, "{smoothed} periods smoothed, {corners} corner by corner");
}

#[test]
fn a_tighter_tolerance_keeps_the_curve_closer() {
    let config = scurve();
    let text = cam(300).replace("P0.01", "P0.002");
    let elements = path(&config, &text);
    assert!(elements.iter().any(is_curve));
    let rounding = 3f64.sqrt() * 0.5 / 800.0;
    let deviation = checked_deviation(&config, &text);
    assert!(deviation <= 0.002 + config.chord_tolerance_mm + rounding, "{deviation}");
}

/// Short segments along X, a right-angle corner, short segments along Y: the corner is
/// blended as a corner (a clothoid pair within P), never smoothed over.
#[test]
fn a_real_corner_is_not_smoothed_over() {
    let config = scurve();
    let mut text = String::from("G21 G90 G64 P0.01\nF1200\n");
    for i in 1..=20 {
        text.push_str(&format!("G1 X{:.3} Y{:.4}\n", 0.2 * f64::from(i), 0.0004 * f64::from(i % 2)));
    }
    for i in 1..=20 {
        text.push_str(&format!("G1 X{:.4} Y{:.3}\n", 4.0 + 0.0004 * f64::from(i % 2), 0.2 * f64::from(i)));
    }
    text.push_str("M2\n");
    let elements = path(&config, &text);
    assert!(elements.iter().any(is_curve), "the straight runs are smoothed");
    // No curve reaches round the corner at (4, 0): each stays on one side of it.
    for e in elements.iter().filter(|e| is_curve(e)) {
        let along_x = e.start[1].abs() < 0.05 && e.end[1].abs() < 0.05;
        let along_y = (e.start[0] - 4.0).abs() < 0.05 && (e.end[0] - 4.0).abs() < 0.05;
        assert!(along_x || along_y, "a curve from {:?} to {:?}", e.start, e.end);
    }
    let corner =
        elements.iter().find(|e| matches!(e.shape, Shape::Clothoid { .. })).expect("the corner is a clothoid blend");
    assert!(corner.start[0] < 4.0 && corner.end[1] > 0.0);
    let rounding = 3f64.sqrt() * 0.5 / 800.0;
    let deviation = checked_deviation(&config, &text);
    assert!(deviation <= 0.01 + config.chord_tolerance_mm + rounding, "{deviation}");
}

/// A 10 mm line between runs of short segments stays a line of nearly its length (its
/// ends at most half a short segment, 0.1 mm, shorter where they are blended).
#[test]
fn a_long_line_is_not_smoothed() {
    let config = scurve();
    let mut text = String::from("G21 G90 G64 P0.01\nF1200\n");
    let mut x = 0.0;
    let wave = |x: f64| 0.2 * (x * 0.5).sin();
    for _ in 0..20 {
        x += 0.2;
        text.push_str(&format!("G1 X{x:.4} Y{:.4}\n", wave(x)));
    }
    x += 10.0;
    text.push_str(&format!("G1 X{x:.4} Y{:.4}\n", wave(x)));
    for _ in 0..20 {
        x += 0.2;
        text.push_str(&format!("G1 X{x:.4} Y{:.4}\n", wave(x)));
    }
    text.push_str("M2\n");
    let elements = path(&config, &text);
    assert!(elements.iter().filter(|e| is_curve(e)).count() >= 2);
    let longest =
        elements.iter().filter(|e| matches!(e.shape, Shape::Line { .. })).map(|e| e.length).fold(0.0, f64::max);
    assert!(longest > 9.79, "the longest line is {longest} mm");
    assert!(elements.iter().filter(|e| is_curve(e)).all(|e| e.length < 5.0));
    let rounding = 3f64.sqrt() * 0.5 / 800.0;
    let deviation = checked_deviation(&config, &text);
    assert!(deviation <= 0.01 + config.chord_tolerance_mm + rounding, "{deviation}");
}

/// In G61 (exact stops) and with the trapezoid profile nothing is smoothed.
#[test]
fn exact_stops_and_the_trapezoid_are_not_smoothed() {
    let text = cam(100);
    assert!(!path(&scurve(), &text.replace("G64 P0.01", "G61")).iter().any(is_curve));
    assert!(!path(&MachineConfig::default(), &text).iter().any(is_curve));
}

/// The fit alone: ends exactly on the polyline's ends along the given directions, and
/// within the share of the tolerance at dense samples; a zigzag no curve can follow
/// within P is refused.
#[test]
fn the_fit_ends_exactly_and_stays_within_the_tolerance() {
    let points: Vec<[f64; 4]> = (0..=40)
        .map(|i| {
            let t = f64::from(i) * 0.05;
            [10.0 * t.cos(), 10.0 * t.sin(), -0.01 * f64::from(i), 0.0]
        })
        .collect();
    let unit = |a: [f64; 4], b: [f64; 4]| {
        let d: [f64; 4] = std::array::from_fn(|c| b[c] - a[c]);
        let n = d.iter().map(|x| x * x).sum::<f64>().sqrt();
        d.map(|x| x / n)
    };
    let (d0, d1) = (unit(points[0], points[1]), unit(points[39], points[40]));
    let curve = fit(&points, d0, None, d1, 0.01).expect("a circle fits");
    let (u0, u1) = curve.domain();
    assert_eq!(curve.point(u0), points[0]);
    assert_eq!(curve.point(u1), points[40]);
    for (u, d) in [(u0, d0), (u1, d1)] {
        let t = curve.derivatives(u).first;
        let n = t.iter().map(|x| x * x).sum::<f64>().sqrt();
        assert!((0..4).all(|c| (t[c] / n - d[c]).abs() < 1e-9), "{t:?} against {d:?}");
    }
    let segment = |p: [f64; 4], a: [f64; 4], b: [f64; 4]| {
        let d: [f64; 4] = std::array::from_fn(|c| b[c] - a[c]);
        let dd: f64 = d.iter().map(|x| x * x).sum();
        let f = ((0..4).map(|c| (p[c] - a[c]) * d[c]).sum::<f64>() / dd).clamp(0.0, 1.0);
        (0..4).map(|c| (p[c] - a[c] - f * d[c]).powi(2)).sum::<f64>().sqrt()
    };
    for k in 0..=4000 {
        let p = curve.point(u0 + (u1 - u0) * f64::from(k) / 4000.0);
        let near = points.windows(2).map(|w| segment(p, w[0], w[1])).fold(f64::INFINITY, f64::min);
        assert!(near <= 0.01, "{near} at sample {k}");
    }
    // A zigzag of 0.1 mm across 0.1 mm segments: no curve within 0.001 mm smooths it.
    let zigzag: Vec<[f64; 4]> = (0..=20).map(|i| [0.1 * f64::from(i), 0.1 * f64::from(i % 2), 0.0, 0.0]).collect();
    let d = unit(zigzag[0], zigzag[1]);
    assert!(fit(&zigzag, d, None, d, 0.001).is_none());
}

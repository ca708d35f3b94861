//! The point-by-point comparison interpolator against exact geometry (docs/spec/pbp_interp.md).
//!
//! Exhaustive: every line with `|Xe|, |Ye| <= 16`; every arc start with `2 <= R^2 <= 144`
//! (radius up to 12), both directions, every point of its path as the end (arcs inside
//! a quadrant, across quadrants, full circles), and every other point of the box as an
//! end the host must refuse. Checked in integers: the end point and the decision count
//! exactly; after every decision a line's position is within `max(|Xe|, |Ye|) / L < 1`
//! of the segment (`|Xe*y - Ye*x| <= max(|Xe|, |Ye|)`), an arc's within one step of the
//! circle (`|sqrt(x^2 + y^2) - R| <= 1`, decided by squaring), `|F| <= 2R + 1`, never at the
//! centre. The cycle model takes the same decisions. proptest beyond, coordinates to 2^20.
//! `pbp_vs_dda_figure` prints the comparison with the DDA on the same paths.

use finestep_model::pbp_interp::{
    arc_steps, ArcError, ArcPath, Decision, LinePath, PbpInputs, PbpInterp, PbpParams, PbpRecord,
};
use proptest::prelude::*;

mod geometry;
use geometry::within_one_of_circle;

/// `|F| <= 2R + 1`: `F <= 1` or `(F - 1)^2 <= 4 R2`, and the same for `-F`.
fn f_within_bound(f: i128, big_r2: i128) -> bool {
    let ok = |g: i128| g <= 1 || (g - 1) * (g - 1) <= 4 * big_r2;
    ok(f) && ok(-f)
}

/// Checks one line exhaustively; returns the decisions.
fn check_line(xe: i64, ye: i64) -> Vec<Decision> {
    let (a, b) = (xe.abs(), ye.abs());
    let bound = a.max(b) as i128;
    let mut path = LinePath::new(xe, ye);
    let mut decisions = Vec::new();
    let mut last = (0i64, 0i64);
    for (d, (x, y)) in path.by_ref() {
        // One step on one axis, toward the end.
        assert_eq!((x - last.0).abs() + (y - last.1).abs(), 1, "line ({xe}, {ye}): not one step");
        assert!(x.abs() <= a && y.abs() <= b, "line ({xe}, {ye}): ({x}, {y}) outside the box");
        let cross = xe as i128 * y as i128 - ye as i128 * x as i128;
        assert!(cross.abs() <= bound, "line ({xe}, {ye}): ({x}, {y}) is {cross}/L from the line");
        // In the box the nearest point of the line lies on the segment, so the distance to
        // the segment is |cross| / L <= max(a, b) / L <= 1.
        let l2 = (xe as i128).pow(2) + (ye as i128).pow(2);
        assert!(cross * cross <= l2, "line ({xe}, {ye}): ({x}, {y}) farther than one step");
        decisions.push(d);
        last = (x, y);
    }
    assert_eq!(decisions.len() as i64, a + b, "line ({xe}, {ye}): decision count");
    assert_eq!(last, (xe, ye), "line ({xe}, {ye}): end point");
    decisions
}

/// The cycle model's requests with `tick_div = 0` after one record, until `done`.
fn run_block(rec: PbpRecord) -> Vec<Decision> {
    let mut block = PbpInterp::new(PbpParams::default());
    block.reset();
    block.step(&PbpInputs { rec_valid: true, rec, ..PbpInputs::default() });
    let idle = PbpInputs::default();
    let mut out = Vec::new();
    for _ in 0..1_000_000 {
        block.step(&idle);
        let o = block.outputs();
        assert!(!(o.req_valid[0] && o.req_valid[1]), "a step on both axes");
        for axis in 0..2 {
            if o.req_valid[axis] {
                out.push(Decision { axis, negative: o.req_negative[axis] });
            }
        }
        if o.done {
            assert!(!o.busy);
            return out;
        }
    }
    panic!("no done");
}

#[test]
fn every_line_up_to_16_reaches_its_end_within_one_step() {
    for xe in -16..=16 {
        for ye in -16..=16 {
            let decisions = check_line(xe, ye);
            if xe != 0 || ye != 0 {
                assert_eq!(run_block(PbpRecord::line(xe, ye)), decisions, "cycle model, line ({xe}, {ye})");
            }
        }
    }
}

/// Walks the full circle from `start`; checks every point; returns the points after each
/// decision and the decisions.
fn walk_circle(start: (i64, i64), cw: bool) -> (Vec<(i64, i64)>, Vec<Decision>) {
    let r2 = (start.0 * start.0 + start.1 * start.1) as i128;
    let n = arc_steps(start, start, cw).expect("full circle");
    let mut points = Vec::new();
    let mut decisions = Vec::new();
    let mut last = start;
    let mut path = ArcPath::new(start.0, start.1, cw);
    for _ in 0..n {
        let (d, (x, y)) = path.next().unwrap();
        assert_eq!((x - last.0).abs() + (y - last.1).abs(), 1);
        let p2 = (x * x + y * y) as i128;
        assert!(within_one_of_circle(p2, r2), "arc {start:?} cw {cw}: ({x}, {y}) more than one step off R^2 {r2}");
        assert_eq!(path.f as i128, p2 - r2, "F formula");
        assert!(f_within_bound(path.f as i128, r2), "arc {start:?}: F {} beyond 2R+1", path.f);
        assert!((x, y) != (0, 0), "arc {start:?}: at the centre");
        // The tangent's direction: CCW turns left (cross product of position and step >= 0
        // is not required on an axis, but the angle never goes backwards by more than the
        // step): x*dy - y*dx has CCW's sign or is 0.
        let turn = last.0 * (y - last.1) - last.1 * (x - last.0);
        assert!(
            if cw { turn <= 0 } else { turn >= 0 },
            "arc {start:?} cw {cw}: step against the direction at {last:?}"
        );
        points.push((x, y));
        decisions.push(d);
        last = (x, y);
    }
    assert_eq!(last, start, "arc {start:?} cw {cw}: full circle ends at the start after {n}");
    // The full circle's count: no earlier return.
    assert!(!points[..points.len() - 1].contains(&start));
    (points, decisions)
}

#[test]
fn every_arc_up_to_radius_12_reaches_its_end_within_one_step() {
    let mut arcs = 0u64;
    let mut refused = 0u64;
    let mut max_off: f64 = 0.0;
    for xs in -12i64..=12 {
        for ys in -12i64..=12 {
            let r2 = xs * xs + ys * ys;
            if r2 > 144 {
                continue;
            }
            for cw in [false, true] {
                if r2 < 2 {
                    assert!(matches!(arc_steps((xs, ys), (xs, ys), cw), Err(ArcError::TooSmall(_))));
                    continue;
                }
                let (points, decisions) = walk_circle((xs, ys), cw);
                for (k, p) in points.iter().enumerate() {
                    let r = ((p.0 * p.0 + p.1 * p.1) as f64).sqrt();
                    max_off = max_off.max((r - (r2 as f64).sqrt()).abs());
                    // First visit after k + 1 decisions: the count the host computes.
                    let n = arc_steps((xs, ys), *p, cw).unwrap_or_else(|e| panic!("{e}: ({xs}, {ys}) to {p:?}"));
                    assert_eq!(n, k as u64 + 1, "arc ({xs}, {ys}) to {p:?} cw {cw}");
                    arcs += 1;
                }
                // Every other point of the box is refused.
                for x in -14i64..=14 {
                    for y in -14i64..=14 {
                        if !points.contains(&(x, y)) {
                            assert_eq!(arc_steps((xs, ys), (x, y), cw), Err(ArcError::NotOnPath(x, y)));
                            refused += 1;
                        }
                    }
                }
                // The cycle model: the full circle and a partial arc.
                assert_eq!(run_block(PbpRecord::arc((xs, ys), (xs, ys), cw).unwrap()), decisions);
                let mid = points[points.len() / 3];
                let rec = PbpRecord::arc((xs, ys), mid, cw).unwrap();
                assert_eq!(run_block(rec), decisions[..rec.steps as usize]);
            }
        }
    }
    eprintln!("arcs: {arcs} (start, end, direction) checked, {refused} ends refused, max |r - R| = {max_off:.4} step");
    assert!(max_off <= 1.0);
}

fn check_arc_prefix(start: (i64, i64), cw: bool, k: u64) -> Result<(), TestCaseError> {
    let r2 = (start.0 as i128).pow(2) + (start.1 as i128).pow(2);
    let full = arc_steps(start, start, cw).unwrap();
    let k = k.min(full).max(1);
    let mut path = ArcPath::new(start.0, start.1, cw);
    let mut end = start;
    for _ in 0..k {
        let (_, p) = path.next().unwrap();
        prop_assert!(within_one_of_circle((p.0 as i128).pow(2) + (p.1 as i128).pow(2), r2), "{p:?} off the circle");
        prop_assert!(f_within_bound(path.f as i128, r2));
        end = p;
    }
    prop_assert_eq!(arc_steps(start, end, cw).unwrap(), k);
    Ok(())
}

#[test]
fn lines_to_2_pow_20_reach_their_end_within_one_step() {
    let mut runner = finestep_testkit::runner("pbp_lines_to_2_pow_20", 24);
    let coord = -(1i64 << 20)..=(1i64 << 20);
    runner
        .run(&(coord.clone(), coord), |(xe, ye)| {
            check_line(xe, ye);
            Ok(())
        })
        .unwrap();
}

#[test]
fn arcs_to_2_pow_20_reach_their_end_within_one_step() {
    let mut runner = finestep_testkit::runner("pbp_arcs_to_2_pow_20", 48);
    let big = -(1i64 << 20)..=(1i64 << 20);
    // One coordinate small: the first 30 000 decisions cross an axis.
    let start = (big.clone(), -3000i64..=3000, any::<bool>())
        .prop_map(|(a, b, swap)| if swap { (b, a) } else { (a, b) })
        .prop_filter("R^2 >= 2", |(x, y)| x * x + y * y >= 2);
    runner.run(&(start, any::<bool>(), 1u64..30_000), |(start, cw, k)| check_arc_prefix(start, cw, k)).unwrap();
    // Whole circles of radius up to 2^12.
    let mut runner = finestep_testkit::runner("pbp_circles_to_2_pow_12", 16);
    let small = -(1i64 << 12)..=(1i64 << 12);
    let start = (small.clone(), small).prop_filter("R^2 >= 2", |(x, y)| x * x + y * y >= 2);
    runner.run(&(start, any::<bool>()), |(start, cw)| check_arc_prefix(start, cw, u64::MAX)).unwrap();
}

/// Statistics of one axis's step times (in clocks).
fn intervals(times: &[u64]) -> (u64, u64, f64) {
    let gaps: Vec<u64> = times.windows(2).map(|w| w[1] - w[0]).collect();
    if gaps.is_empty() {
        return (0, 0, 0.0);
    }
    let mean = gaps.iter().sum::<u64>() as f64 / gaps.len() as f64;
    (*gaps.iter().min().unwrap(), *gaps.iter().max().unwrap(), mean)
}

/// The DDA of `dda_axis` on the path `target(k)` at the ends of `periods` periods of
/// `p` clocks (the increments are the differences of the I16F16-rounded targets): the
/// step times and positions after each step, per clock `floor((S + M/2) / M)`.
fn dda_run(p: u64, periods: u64, target: impl Fn(u64) -> (f64, f64)) -> Vec<(u64, (i64, i64))> {
    let m = p as i128 * 65536;
    let fix = |v: f64| (v * 65536.0).round() as i128;
    let mut sum = [0i128; 2];
    let mut pos = [0i64; 2];
    let mut events = Vec::new();
    let start = target(0);
    let origin = [fix(start.0), fix(start.1)];
    for k in 0..periods {
        let (a, b) = (target(k), target(k + 1));
        let inc = [fix(b.0) - fix(a.0), fix(b.1) - fix(a.1)];
        for c in 0..p {
            for axis in 0..2 {
                sum[axis] += inc[axis];
                let new = (sum[axis] + m / 2).div_euclid(m) as i64;
                if new != pos[axis] {
                    pos[axis] = new;
                    let t = k * p + c + 1;
                    let here = (
                        (origin[0] / 65536) as i64 + pos[0] + i64::from(origin[0] % 65536 >= 32768),
                        (origin[1] / 65536) as i64 + pos[1] + i64::from(origin[1] % 65536 >= 32768),
                    );
                    events.push((t, here));
                }
            }
        }
    }
    events
}

/// The comparison figure: maximum deviation from the ideal path (steps) and the
/// evenness of the step times, the point-by-point interpolator at one decision per
/// `tick` clocks against the DDA taking the same time on the same path.
#[test]
fn pbp_vs_dda_figure() {
    let tick = 10u64;
    println!("pbp_interp vs DDA (same path, same duration; pbp: one decision per {tick} clocks)");
    println!(
        "{:<34} {:>10} {:>10} | {:>22} {:>22}",
        "path", "dev pbp", "dev DDA", "X gaps pbp min/max/mean", "X gaps DDA min/max/mean"
    );
    for (xe, ye) in [(1000i64, 0i64), (1000, 1000), (1000, 577), (1000, 333), (1000, 1), (-700, 300)] {
        let l = ((xe * xe + ye * ye) as f64).sqrt();
        let dist = |(x, y): (i64, i64)| ((xe * y - ye * x) as f64).abs() / l;
        let mut pbp_dev: f64 = 0.0;
        let mut pbp_x = Vec::new();
        for (k, (d, p)) in LinePath::new(xe, ye).enumerate() {
            pbp_dev = pbp_dev.max(dist(p));
            if d.axis == 0 {
                pbp_x.push((k as u64 + 1) * tick);
            }
        }
        let n = (xe.abs() + ye.abs()) as u64;
        let events = dda_run(n * tick, 1, |k| if k == 0 { (0.0, 0.0) } else { (xe as f64, ye as f64) });
        let mut dda_dev: f64 = 0.0;
        let mut dda_x = Vec::new();
        let mut last_x = 0;
        for (t, p) in &events {
            dda_dev = dda_dev.max(dist(*p));
            if p.0 != last_x {
                dda_x.push(*t);
                last_x = p.0;
            }
        }
        let (a, b, c) = intervals(&pbp_x);
        let (d, e, f) = intervals(&dda_x);
        println!(
            "{:<34} {:>10.3} {:>10.3} | {:>8}/{:>5}/{:>7.1} {:>8}/{:>5}/{:>7.1}",
            format!("line ({xe}, {ye})"),
            pbp_dev,
            dda_dev,
            a,
            b,
            c,
            d,
            e,
            f
        );
        assert!(pbp_dev < 1.0);
    }
    println!(
        "{:<34} {:>10} {:>10} | {:>22} {:>22}",
        "arc", "dev pbp", "dev DDA", "feed max/min pbp", "feed max/min DDA"
    );
    for (r, periods) in [(1000i64, 400u64), (100, 80), (5000, 2000)] {
        let n = arc_steps((r, 0), (r, 0), false).unwrap();
        let rf = r as f64;
        let off = |(x, y): (i64, i64)| (((x * x + y * y) as f64).sqrt() - rf).abs();
        // Feed: the angle covered per window of a fiftieth of the run.
        let window = (n * tick / 50).max(1);
        let feed_ratio = |samples: &[(u64, (i64, i64))]| {
            let mut per_window = vec![0.0f64; 51];
            let mut last = 0.0f64;
            for (t, (x, y)) in samples {
                let mut angle = (*y as f64).atan2(*x as f64);
                while angle < last - std::f64::consts::PI {
                    angle += 2.0 * std::f64::consts::PI;
                }
                per_window[(*t / window).min(50) as usize] += angle - last;
                last = angle;
            }
            let inner = &per_window[1..49];
            inner.iter().cloned().fold(0.0, f64::max) / inner.iter().cloned().fold(f64::INFINITY, f64::min)
        };
        let mut pbp = Vec::new();
        let mut pbp_dev: f64 = 0.0;
        for (k, (_, p)) in ArcPath::new(r, 0, false).take(n as usize).enumerate() {
            pbp_dev = pbp_dev.max(off(p));
            pbp.push(((k as u64 + 1) * tick, p));
        }
        let p = n * tick / periods;
        let step = 2.0 * std::f64::consts::PI / periods as f64;
        let events = dda_run(p, periods, |k| {
            let a = step * k as f64;
            (rf * a.cos(), rf * a.sin())
        });
        let dda_dev = events.iter().map(|(_, q)| off(*q)).fold(0.0, f64::max);
        println!(
            "{:<34} {:>10.3} {:>10.3} | {:>22.3} {:>22.3}",
            format!("circle R {r}, {n} st, {periods} per"),
            pbp_dev,
            dda_dev,
            feed_ratio(&pbp),
            feed_ratio(&events)
        );
        assert!(pbp_dev <= 1.0);
    }
}

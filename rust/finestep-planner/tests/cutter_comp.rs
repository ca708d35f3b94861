//! Cutter radius compensation: directed cases with hand-computed answers, and
//! properties checked with geometry written here, apart from the construction code:
//! the distance from the tool path to the programmed contour, the Steiner length of an
//! outer offset, and offsetting an offset back onto the original.

use std::f64::consts::{PI, TAU};

use finestep_gcode::{parse_str, Block, BlockKind, CompSide, Plane, Point, Program};
use finestep_planner::cutter_comp::{compensate, CompError, EntryExit, ToolTable};
use proptest::prelude::*;
use proptest::test_runner::TestCaseError;

// ---------------------------------------------------------------- helpers

type P2 = (f64, f64);

fn parse(source: &str) -> Program {
    parse_str(source, "t.ngc").unwrap_or_else(|e| panic!("{e}"))
}

fn tool(radius_mm: f64) -> ToolTable {
    ToolTable::new().with_radius_mm(1, radius_mm)
}

fn run(source: &str, radius_mm: f64) -> Result<Program, CompError> {
    compensate(&parse(source), &tool(radius_mm))
}

fn err(source: &str, radius_mm: f64) -> String {
    match run(source, radius_mm) {
        Ok(p) => panic!("compensated without error: {p:#?}"),
        Err(e) => e.to_string(),
    }
}

fn sub(a: P2, b: P2) -> P2 {
    (a.0 - b.0, a.1 - b.1)
}
fn len(a: P2) -> f64 {
    a.0.hypot(a.1)
}
fn dist(a: P2, b: P2) -> f64 {
    len(sub(a, b))
}
fn xy(p: &Point) -> P2 {
    (p.x_mm, p.y_mm)
}

/// A piece of a planar path: a segment, or an arc from `start` turning `sweep` radians
/// (positive counter-clockwise) around `centre`.
#[derive(Clone, Copy, Debug)]
enum Piece {
    Seg(P2, P2),
    Arc { centre: P2, radius: f64, start: f64, sweep: f64 },
}

impl Piece {
    fn at(&self, t: f64) -> P2 {
        match *self {
            Piece::Seg(a, b) => (a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1)),
            Piece::Arc { centre, radius, start, sweep } => {
                let angle = start + t * sweep;
                (centre.0 + radius * angle.cos(), centre.1 + radius * angle.sin())
            }
        }
    }

    fn length(&self) -> f64 {
        match *self {
            Piece::Seg(a, b) => dist(a, b),
            Piece::Arc { radius, sweep, .. } => radius * sweep.abs(),
        }
    }

    /// Distance from `q` to the piece.
    fn distance(&self, q: P2) -> f64 {
        match *self {
            Piece::Seg(a, b) => {
                let (d, w) = (sub(b, a), sub(q, a));
                let l2 = d.0 * d.0 + d.1 * d.1;
                let t = if l2 == 0.0 { 0.0 } else { ((w.0 * d.0 + w.1 * d.1) / l2).clamp(0.0, 1.0) };
                dist(q, self.at(t))
            }
            Piece::Arc { centre, radius, start, sweep } => {
                let angle = (q.1 - centre.1).atan2(q.0 - centre.0);
                // Turned from the start in the arc's direction, in [0, 2 pi).
                let turned = ((angle - start) * sweep.signum()).rem_euclid(TAU);
                if turned <= sweep.abs() {
                    (dist(q, centre) - radius).abs()
                } else {
                    dist(q, self.at(0.0)).min(dist(q, self.at(1.0)))
                }
            }
        }
    }
}

fn contour_distance(contour: &[Piece], q: P2) -> f64 {
    contour.iter().map(|p| p.distance(q)).fold(f64::INFINITY, f64::min)
}

/// The signed sweep of a G2/G3 from `from` to `to` around `centre`, by the rule the
/// G-code front end documents (equal end points: a full circle), with extra turns.
fn sweep_of(from: P2, to: P2, centre: P2, clockwise: bool, extra_turns: u32) -> f64 {
    let a0 = (from.1 - centre.1).atan2(from.0 - centre.0);
    let a1 = (to.1 - centre.1).atan2(to.0 - centre.0);
    let mut ccw = (a1 - a0).rem_euclid(TAU);
    if clockwise {
        let mut cw = (TAU - ccw) % TAU;
        if cw == 0.0 {
            cw = TAU;
        }
        -(cw + TAU * f64::from(extra_turns))
    } else {
        if ccw == 0.0 {
            ccw = TAU;
        }
        ccw + TAU * f64::from(extra_turns)
    }
}

/// The XY path of a program from the origin, each piece with its block's line.
fn pieces(program: &Program) -> Vec<(usize, Piece)> {
    let mut at = (0.0, 0.0);
    let mut out = Vec::new();
    for block in &program.blocks {
        match block.kind {
            BlockKind::Rapid { to } | BlockKind::Linear { to, .. } => {
                out.push((block.line, Piece::Seg(at, xy(&to))));
                at = xy(&to);
            }
            BlockKind::Arc { to, centre, plane, clockwise, extra_turns, .. } => {
                assert_eq!(plane, Plane::Xy);
                let c = xy(&centre);
                out.push((
                    block.line,
                    Piece::Arc {
                        centre: c,
                        radius: dist(at, c),
                        start: (at.1 - c.1).atan2(at.0 - c.0),
                        sweep: sweep_of(at, xy(&to), c, clockwise, extra_turns),
                    },
                ));
                at = xy(&to);
            }
            _ => {}
        }
    }
    out
}

fn moves(program: &Program) -> Vec<BlockKind> {
    program
        .blocks
        .iter()
        .map(|b| b.kind.clone())
        .filter(|k| matches!(k, BlockKind::Rapid { .. } | BlockKind::Linear { .. } | BlockKind::Arc { .. }))
        .collect()
}

fn end_of(kind: &BlockKind) -> Point {
    match *kind {
        BlockKind::Rapid { to } | BlockKind::Linear { to, .. } | BlockKind::Arc { to, .. } => to,
        _ => panic!("not a move: {kind:?}"),
    }
}

/// The end of the last output block of source line `line`.
fn last_end(program: &Program, line: usize) -> Point {
    let block = program.blocks.iter().rev().find(|b| b.line == line);
    end_of(&block.unwrap_or_else(|| panic!("no block of line {line}: {program:#?}")).kind)
}

fn assert_near(actual: P2, expected: P2) {
    assert!(dist(actual, expected) < 1e-9, "{actual:?} is not {expected:?}");
}

// ---------------------------------------------------------------- squares

/// A 10 mm square, counter-clockwise from the middle of its bottom side, entered and
/// left from below: outside with G42, inside with G41.
fn square(side: &str, start: P2) -> String {
    format!(
        "G0 X{} Y{}\n{side} D1\nG1 X5 Y0 F600\nG1 X10\nG1 Y10\nG1 X0\nG1 Y0\nG1 X5\nG40\nG0 X{} Y{}\nM2\n",
        start.0, start.1, start.0, start.1
    )
}

#[test]
fn square_outside_gets_corner_arcs_and_a_tangent_entry_and_exit() {
    let out = run(&square("G42", (5.0, -5.0)), 2.0).unwrap();
    let m = moves(&out);
    // Entry: tangent from (5,-5) to the 2 mm circle around (5,0); it crosses the offset
    // of the bottom side (y = -2) before the tangent point and is cut back there.
    let theta = (2.0f64 / 5.0).asin();
    let entry_x = 5.0 + 3.0 * theta.tan();
    let expected: Vec<(P2, Option<P2>)> = vec![
        ((5.0, -5.0), None),
        ((entry_x, -2.0), None),
        ((10.0, -2.0), None),
        ((12.0, 0.0), Some((10.0, 0.0))),
        ((12.0, 10.0), None),
        ((10.0, 12.0), Some((10.0, 10.0))),
        ((0.0, 12.0), None),
        ((-2.0, 10.0), Some((0.0, 10.0))),
        ((-2.0, 0.0), None),
        ((0.0, -2.0), Some((0.0, 0.0))),
        ((10.0 - entry_x, -2.0), None),
        ((5.0, -5.0), None),
    ];
    assert_eq!(m.len(), expected.len(), "{m:#?}");
    for (kind, (to, centre)) in m.iter().zip(&expected) {
        assert_near(xy(&end_of(kind)), *to);
        match (kind, centre) {
            (BlockKind::Arc { centre: c, clockwise, extra_turns, .. }, Some(e)) => {
                assert_near(xy(c), *e);
                assert!(!clockwise, "outside corners of a counter-clockwise G42 path turn left");
                assert_eq!(*extra_turns, 0);
            }
            (BlockKind::Linear { feed_mm_per_min, .. }, None) => assert_eq!(*feed_mm_per_min, 600.0),
            (BlockKind::Rapid { .. }, None) => {}
            _ => panic!("{kind:?} where {centre:?} was expected"),
        }
    }
    // No CutterComp block is left, and the program still ends.
    assert!(!out.blocks.iter().any(|b| matches!(b.kind, BlockKind::CutterComp { .. })));
    assert!(matches!(out.blocks.last().unwrap().kind, BlockKind::End));
    // Corner arcs carry the line of the move after the corner.
    let arc_lines: Vec<usize> =
        out.blocks.iter().filter(|b| matches!(b.kind, BlockKind::Arc { .. })).map(|b| b.line).collect();
    assert_eq!(arc_lines, vec![5, 6, 7, 8]);
}

#[test]
fn square_inside_is_cut_back_at_every_corner() {
    let out = run(&square("G41", (5.0, 5.0)), 1.0).unwrap();
    let m = moves(&out);
    assert!(!m.iter().any(|k| matches!(k, BlockKind::Arc { .. })), "{m:#?}");
    let ends: Vec<P2> = m.iter().map(|k| xy(&end_of(k))).collect();
    assert_eq!(ends.len(), 8);
    assert_near(ends[2], (9.0, 1.0));
    assert_near(ends[3], (9.0, 9.0));
    assert_near(ends[4], (1.0, 9.0));
    assert_near(ends[5], (1.0, 1.0));
    assert_near(ends[7], (5.0, 5.0));
    // The entry from (5,5) down to (5,0) leans to its left (+x) by asin(1/5) and meets
    // y = 1 there.
    assert_near(ends[1], (5.0 + 4.0 * (0.2f64).asin().tan(), 1.0));
}

#[test]
fn both_sides_of_the_same_path_are_mirror_images() {
    // Clockwise square: G41 is now the outside.
    let cw = "G0 X5 Y-5\nG41 D1\nG1 X5 Y0 F600\nG1 X0\nG1 Y10\nG1 X10\nG1 Y0\nG1 X5\nG40\nG0 X5 Y-5\n";
    let left = run(cw, 2.0).unwrap();
    let right = run(&square("G42", (5.0, -5.0)), 2.0).unwrap();
    let (l, r) = (pieces(&left), pieces(&right));
    assert_eq!(l.len(), r.len());
    // (The first piece is the rapid from the origin.)
    for ((_, a), (_, b)) in l.iter().zip(&r).skip(1) {
        for t in [0.0, 0.5, 1.0] {
            let (p, q) = (a.at(t), b.at(t));
            assert_near(p, (10.0 - q.0, q.1));
        }
    }
}

// ---------------------------------------------------------------- triangles

const TRIANGLE: &str = "G0 X5 Y-5\n{side} D1\nG1 X5 Y0 F300\nG1 X20\nG1 X0 Y4\nG1 Y0\nG1 X5\nG40\nG0 X5 Y-5\n";

fn triangle(side: &str) -> String {
    TRIANGLE.replace("{side}", side)
}

#[test]
fn acute_corner_outside_gets_a_wide_corner_arc() {
    let out = run(&triangle("G42"), 1.0).unwrap();
    let arcs: Vec<f64> = pieces(&out)
        .iter()
        .filter_map(|(_, p)| match p {
            Piece::Arc { sweep, .. } => Some(*sweep),
            _ => None,
        })
        .collect();
    // The turn at (20,0) is pi minus the corner angle atan(4/20); at (0,0) a right angle.
    let acute = PI - (4.0f64 / 20.0).atan();
    assert_eq!(arcs.len(), 3);
    assert!((arcs[0] - acute).abs() < 1e-9, "{arcs:?}");
    assert!((arcs[2] - PI / 2.0).abs() < 1e-9, "{arcs:?}");
}

#[test]
fn acute_corner_inside_is_cut_back_far_or_refused() {
    let source = triangle("G41").replace("X5 Y-5", "X5 Y2.5");
    let out = run(&source, 0.5).unwrap();
    // The corner at (20,0) (angle alpha = atan(1/5)) is cut back r / tan(alpha/2) along
    // the bottom edge.
    let alpha = (4.0f64 / 20.0).atan();
    let back = 0.5 / (alpha / 2.0).tan();
    assert_near(xy(&last_end(&out, 4)), (20.0 - back, 0.5));
    // With r = 2 that is 20 mm: more than the bottom edge has after the entry.
    assert_eq!(
        err(&source, 2.0),
        "line 4: tool radius 2 mm is too large here: the compensated path of this move vanishes between its corners (it would gouge)"
    );
}

// ---------------------------------------------------------------- pockets with arcs

const POCKET: &str = "G0 X10 Y5\n{side} D1\nG1 X10 Y0 F300\nG1 X17\nG3 X20 Y3 I0 J3\nG1 Y7\nG3 X17 Y10 I-3 J0\nG1 X3\nG3 X0 Y7 I0 J-3\nG1 Y3\nG3 X3 Y0 I3 J0\nG1 X10\nG40\nG0 X10 Y5\nM2\n";

#[test]
fn rounded_pocket_inside_shrinks_its_arcs() {
    let out = run(&POCKET.replace("{side}", "G41"), 1.0).unwrap();
    let arcs: Vec<(P2, f64, f64)> = pieces(&out)
        .iter()
        .filter_map(|(_, p)| match p {
            Piece::Arc { centre, radius, sweep, .. } => Some((*centre, *radius, *sweep)),
            _ => None,
        })
        .collect();
    assert_eq!(arcs.len(), 4, "tangent joins need no corner arcs: {arcs:?}");
    for ((centre, radius, sweep), expected) in arcs.iter().zip([(17.0, 3.0), (17.0, 7.0), (3.0, 7.0), (3.0, 3.0)]) {
        assert_near(*centre, expected);
        assert!((radius - 2.0).abs() < 1e-9 && (sweep - PI / 2.0).abs() < 1e-9, "{radius} {sweep}");
    }
}

#[test]
fn rounded_pocket_outside_grows_its_arcs() {
    let source = POCKET.replace("{side}", "G42").replace("X10 Y5", "X10 Y-5");
    let out = run(&source, 1.5).unwrap();
    let radii: Vec<f64> = pieces(&out)
        .iter()
        .filter_map(|(_, p)| match p {
            Piece::Arc { radius, .. } => Some(*radius),
            _ => None,
        })
        .collect();
    assert_eq!(radii.len(), 4);
    assert!(radii.iter().all(|r| (r - 4.5).abs() < 1e-9), "{radii:?}");
}

#[test]
fn a_tool_not_smaller_than_a_concave_arc_is_an_error() {
    let inside = POCKET.replace("{side}", "G41");
    assert_eq!(err(&inside, 3.5), "line 5: tool radius 3.5 mm is larger than the concave arc radius 3 mm");
    // As large as the corners: the tool pivots at each corner's centre, where the sides'
    // offsets meet (LinuxCNC prints arcs of radius zero there).
    let pivots = run(&inside, 3.0).unwrap();
    assert!(!pivots.blocks.iter().any(|b| matches!(b.kind, BlockKind::Arc { .. })));
    assert!(run(&inside, 2.99).is_ok());
}

/// An L-shaped part: its reflex corner is an inside corner from outside and an outside
/// corner (rounded by an arc) from inside; every other corner the other way round.
#[test]
fn l_shape_both_sides_is_at_the_tool_radius() {
    let shape = Shape {
        vertices: vec![(0.0, 0.0), (20.0, 0.0), (20.0, 10.0), (10.0, 10.0), (10.0, 20.0), (0.0, 20.0)],
        bulges: vec![None; 6],
    };
    for (outside, corner_arcs) in [(true, 5), (false, 1)] {
        let (program, entry, exit) = shape.program(outside, 2.0, 1.0);
        let out = compensate(&program, &tool(2.0)).unwrap();
        check_distance(&shape.contour(), &out, 2.0, entry, exit).unwrap();
        let arcs = out.blocks.iter().filter(|b| matches!(b.kind, BlockKind::Arc { .. })).count();
        assert_eq!(arcs, corner_arcs, "outside {outside}");
    }
    // From inside, a 6 mm tool no longer fits the 10 mm wide arms.
    let (program, ..) = shape.program(false, 6.0, 1.0);
    assert!(compensate(&program, &tool(6.0)).unwrap_err().to_string().contains("vanishes"));
}

// ---------------------------------------------------------------- line-arc and arc-arc joins

#[test]
fn line_into_arc_concave_and_convex() {
    let path = "G1 X0 Y-5 F100\n{side} D1\nG1 X0 Y0\nG1 X10\nG2 X20 Y0 I5 J0\nG1 Y-5\nG40\nG1 X30\n";
    // G41: tool above the line and outside the cw arc (radius 6): concave corner at
    // (10,0), cut back to y = 1 on the circle of radius 6 around (15,0).
    let out = run(&path.replace("{side}", "G41"), 1.0).unwrap();
    assert_near(xy(&last_end(&out, 4)), (15.0 - 35f64.sqrt(), 1.0));
    // G42: tool below the line and inside the arc (radius 4): a 90 degree corner arc
    // around (10,0) from (10,-1) to (11,0).
    let out = run(&path.replace("{side}", "G42"), 1.0).unwrap();
    let p = pieces(&out);
    let corner = p.iter().find(|(_, piece)| matches!(piece, Piece::Arc { radius, .. } if (radius - 1.0).abs() < 1e-9));
    let Some((line, Piece::Arc { centre, sweep, .. })) = corner else { panic!("{p:#?}") };
    assert_eq!(*line, 5);
    assert_near(*centre, (10.0, 0.0));
    assert!((sweep - PI / 2.0).abs() < 1e-9);
    assert!(p.iter().any(|(_, piece)| matches!(piece, Piece::Arc { radius, .. } if (radius - 4.0).abs() < 1e-9)));
}

#[test]
fn arc_into_arc_concave_meets_at_the_circles_crossing() {
    // A ccw quarter circle around (0,0) from (5,0) to (0,5), heading -x at its end,
    // then a ccw half circle around (-5,5) heading +y at its start: a right turn,
    // concave for G42, which keeps the tool outside both (radius 6).
    let source = "G0 X5 Y-5\nG42 D1\nG1 X5 Y0 F100\nG3 X0 Y5 I-5 J0\nG3 X-10 Y5 I-5 J0\nG40\nG1 X-10 Y-5\n";
    let out = run(source, 1.0).unwrap();
    // Both arcs end at the crossing of the two circles of radius 6 nearest the corner.
    let h = (36.0 - 12.5f64).sqrt() / 2f64.sqrt();
    let crossing = (-2.5 + h, 2.5 + h);
    assert_near(xy(&last_end(&out, 4)), crossing);
    assert!((dist(crossing, (0.0, 0.0)) - 6.0).abs() < 1e-12 && (dist(crossing, (-5.0, 5.0)) - 6.0).abs() < 1e-12);
    let p = pieces(&out);
    let Some((_, Piece::Arc { centre, radius, .. })) = p.iter().find(|(l, _)| *l == 5) else { panic!("{p:#?}") };
    assert_near(*centre, (-5.0, 5.0));
    assert!((radius - 6.0).abs() < 1e-9);
    // G41 on the same path: a right turn is convex for it, a corner arc of radius 1.
    let out = run(&source.replace("G42", "G41").replace("X5 Y-5", "X-5 Y0"), 1.0).unwrap();
    let corner = pieces(&out)
        .into_iter()
        .find(|(l, p)| *l == 5 && matches!(p, Piece::Arc { radius, .. } if (radius - 1.0).abs() < 1e-9));
    let Some((_, Piece::Arc { centre, sweep, .. })) = corner else { panic!() };
    assert_near(centre, (0.0, 5.0));
    assert!((sweep + PI / 2.0).abs() < 1e-9, "{sweep}");
}

#[test]
fn a_line_turning_straight_back_goes_round_its_end() {
    let out = run("G0 X-5 Y0\nG41 D1\nG1 X0 Y0 F100\nG1 X10\nG1 X0\nG40\nG1 X-5 Y5\n", 1.0).unwrap();
    let p = pieces(&out);
    let turn = p.iter().find(|(line, piece)| *line == 5 && matches!(piece, Piece::Arc { .. }));
    let Some((_, Piece::Arc { centre, radius, sweep, start })) = turn else { panic!("{p:#?}") };
    assert_near(*centre, (10.0, 0.0));
    assert!((radius - 1.0).abs() < 1e-9 && (sweep + PI).abs() < 1e-9, "{sweep}");
    assert!((start - PI / 2.0).abs() < 1e-9);
}

/// A line into an arc whose start tangent is off the line's direction by a tiny angle
/// (rounded coordinates from CAM), and the same path backwards (arc into line): every
/// combination of kink sign, arc direction, travel direction and side joins, and the
/// path stays at the tool radius from the contour.
#[test]
fn near_tangent_kinks_join_at_the_tool_radius() {
    let radius = 1.0;
    for kink in [1e-12, 1e-9, 1e-6, 1e-4, -1e-12, -1e-9, -1e-6, -1e-4] {
        for clockwise in [false, true] {
            for side in [CompSide::Left, CompSide::Right] {
                for backwards in [false, true] {
                    let s = if side == CompSide::Left { 1.0 } else { -1.0 };
                    let t = (f64::cos(kink), f64::sin(kink));
                    let to_centre = if clockwise { (t.1, -t.0) } else { (-t.1, t.0) };
                    let centre = (10.0 + 5.0 * to_centre.0, 5.0 * to_centre.1);
                    let start_angle = (0.0 - centre.1).atan2(10.0 - centre.0);
                    let sweep = if clockwise { -PI / 2.0 } else { PI / 2.0 };
                    let arc = Piece::Arc { centre, radius: 5.0, start: start_angle, sweep };
                    let end = arc.at(1.0);
                    // The arc's tangent at its end, in the forward direction.
                    let radial = ((end.0 - centre.0) / 5.0, (end.1 - centre.1) / 5.0);
                    let end_tangent = if clockwise { (radial.1, -radial.0) } else { (-radial.1, radial.0) };
                    // A point 2 mm to the tool's side of `at` for travel along `tangent`.
                    let aside = |at: P2, tangent: P2| (at.0 - 2.0 * s * tangent.1, at.1 + 2.0 * s * tangent.0);
                    let mut b = Builder::default();
                    let (entry, exit);
                    if backwards {
                        b.rapid(aside(end, (-end_tangent.0, -end_tangent.1)));
                        b.comp(side);
                        entry = b.line(end);
                        b.arc((10.0, 0.0), centre, !clockwise);
                        b.line((0.0, 0.0));
                        b.comp(CompSide::Off);
                        exit = b.line(aside((0.0, 0.0), (-1.0, 0.0)));
                    } else {
                        b.rapid(aside((0.0, 0.0), (1.0, 0.0)));
                        b.comp(side);
                        entry = b.line((0.0, 0.0));
                        b.line((10.0, 0.0));
                        b.arc(end, centre, clockwise);
                        b.comp(CompSide::Off);
                        exit = b.line(aside(end, end_tangent));
                    }
                    let case = format!("kink {kink} cw {clockwise} {side:?} backwards {backwards}");
                    let out = compensate(&Program { blocks: b.blocks }, &tool(radius))
                        .unwrap_or_else(|e| panic!("{case}: {e}"));
                    let contour = [Piece::Seg((0.0, 0.0), (10.0, 0.0)), arc];
                    let length =
                        check_distance(&contour, &out, radius, entry, exit).unwrap_or_else(|e| panic!("{case}: {e}"));
                    assert!(length > 10.0, "{case}: {length}");
                }
            }
        }
    }
}

// ---------------------------------------------------------------- entry, exit, Z

#[test]
fn entry_follows_linuxcnc_tangent_rule_and_exit_ends_on_the_programmed_point() {
    let theta = (2.0f64 / 10.0).asin();
    // G42 from (0,-10) up to (0,0), then left along -x: the entry leans right by
    // theta and ends at the tangent point on the 2 mm circle around (0,0); the left turn
    // is an outside corner for G42, rounded by an arc to (0,2).
    let out = run("G0 X0 Y-10\nG42 D1\nG1 X0 Y0 F100\nG1 X-10 Y0\nG40\nG0 X-10 Y-10\n", 2.0).unwrap();
    let m = moves(&out);
    let tangent = (2.0 * theta.cos(), -2.0 * theta.sin());
    assert_near(xy(&end_of(&m[1])), tangent);
    // Tangent: the radius to the tangent point is perpendicular to the entry line.
    let along = sub(tangent, (0.0, -10.0));
    assert!((along.0 * tangent.0 + along.1 * tangent.1).abs() < 1e-9);
    let BlockKind::Arc { to, centre, clockwise, .. } = m[2] else { panic!("{m:#?}") };
    assert_near(xy(&to), (0.0, 2.0));
    assert_near(xy(&centre), (0.0, 0.0));
    assert!(!clockwise);
    // The exit ends exactly on the programmed point.
    assert_eq!(xy(&end_of(m.last().unwrap())), (-10.0, -10.0));
    // G41: the same turn is an inside corner: the entry is cut back where it meets the
    // offset of the second line, y = -2.
    let out = run("G0 X0 Y-10\nG41 D1\nG1 X0 Y0 F100\nG1 X-10 Y0\nG40\nG0 X-10 Y-10\n", 2.0).unwrap();
    let m = moves(&out);
    assert_near(xy(&end_of(&m[1])), (-8.0 * theta.tan(), -2.0));
    // The exit (leaning away from (-10,0) to the tool side, then down to (-10,-10)) is a
    // left turn too: the second line is cut back where it meets the exit line.
    let exit_start = (-10.0 + 2.0 * theta.cos(), -2.0 * theta.sin());
    assert_near(xy(&end_of(&m[2])), (exit_start.0 - (2.0 + exit_start.1) * theta.tan(), -2.0));
    assert_eq!(xy(&end_of(&m[3])), (-10.0, -10.0));
}

#[test]
fn moves_of_z_alone_keep_the_tool_where_it_is() {
    let source =
        "G0 X5 Y-5 Z5\nG42 D1\nG1 X5 Y0 F600\nG1 Z-1\nG1 X10\nG1 Y10 Z-2\nG1 X0\nG1 Y0\nG1 X5\nG40\nG0 Z5\nG0 X5 Y-5\n";
    let out = run(source, 2.0).unwrap();
    let find =
        |line: usize| -> Vec<Point> { out.blocks.iter().filter(|b| b.line == line).map(|b| end_of(&b.kind)).collect() };
    // The plunge happens where the entry ended.
    let entry_end = find(3)[0];
    let plunge = find(4);
    assert_eq!(plunge.len(), 1);
    assert_eq!(xy(&plunge[0]), xy(&entry_end));
    assert_eq!(plunge[0].z_mm, -1.0);
    // A ramp: the offset line keeps its Z end.
    let ramp = find(6);
    assert_near(xy(ramp.last().unwrap()), (12.0, 10.0));
    assert_eq!(ramp.last().unwrap().z_mm, -2.0);
    // After G40, Z alone goes up at the last offset point; the exit follows.
    let retract = find(11);
    assert_eq!(retract.len(), 1);
    assert_eq!(retract[0].z_mm, 5.0);
    assert!((retract[0].y_mm + 2.0).abs() < 1e-9, "{retract:?}");
    assert_eq!(find(12).last().unwrap(), &Point { x_mm: 5.0, y_mm: -5.0, z_mm: 5.0, ..Point::default() });
}

#[test]
fn helix_inside_a_circle_keeps_turns_and_depth() {
    let source = "G0 X0 Y0 Z0\nG41 D1\nG1 X10 Y0 F300\nG3 X10 Y0 I-10 J0 Z-3 P2\nG40\nG1 X0 Y0\n";
    let out = run(source, 1.0).unwrap();
    let helix: Vec<&Block> = out.blocks.iter().filter(|b| b.line == 4).collect();
    assert_eq!(helix.len(), 1);
    let BlockKind::Arc { to, centre, extra_turns, clockwise, .. } = helix[0].kind else { panic!() };
    assert_eq!(to.z_mm, -3.0);
    assert_eq!(centre.z_mm, 0.0);
    assert!(!clockwise);
    assert!((dist(xy(&to), (0.0, 0.0)) - 9.0).abs() < 1e-9);
    // Two turns less the bits cut back at the entry and exit corners: 1 extra turn.
    assert_eq!(extra_turns, 1);
    let p = pieces(&out);
    let Piece::Arc { radius, sweep, .. } = p.iter().find(|(l, _)| *l == 4).unwrap().1 else { panic!() };
    assert!((radius - 9.0).abs() < 1e-9);
    assert!(sweep > 3.0 * PI && sweep < 2.0 * TAU, "{sweep}");
}

#[test]
fn full_circle_boss_outside_is_one_arc_cut_back_at_entry_and_exit() {
    // G41 on a clockwise circle keeps the tool outside it: radius 10 + 2.
    let source = "G0 X-20 Y0\nG41 D1\nG1 X-10 Y0 F100\nG2 X-10 Y0 I10 J0\nG40\nG1 X-20 Y0\n";
    let out = run(source, 2.0).unwrap();
    let p = pieces(&out);
    let circle: Vec<&Piece> = p.iter().filter(|(l, _)| *l == 4).map(|(_, piece)| piece).collect();
    assert_eq!(circle.len(), 1, "{p:#?}");
    let Piece::Arc { centre, radius, sweep, .. } = *circle[0] else { panic!("{p:#?}") };
    assert_near(centre, (0.0, 0.0));
    assert!((radius - 12.0).abs() < 1e-9);
    // Nearly a whole turn, clockwise, less what the entry and exit cut back.
    assert!(sweep < -1.8 * PI && sweep > -TAU, "{sweep}");
    let contour = [Piece::Arc { centre: (0.0, 0.0), radius: 10.0, start: PI, sweep: -TAU }];
    check_distance(&contour, &out, 2.0, 3, 6).unwrap();
}

// ---------------------------------------------------------------- tools and errors

#[test]
fn radius_comes_from_d_or_from_the_tool_in_the_spindle() {
    let table = ToolTable::new().with_radius_mm(2, 1.0).with_radius_mm(3, 2.0);
    let with_d = compensate(&parse(&square("G42", (5.0, -5.0)).replace("D1", "D3")), &table).unwrap();
    let spindle =
        compensate(&parse(&format!("T2 M6\n{}", square("G42", (5.0, -5.0)).replace(" D1", ""))), &table).unwrap();
    let x_max = |p: &Program| moves(p).iter().map(|k| end_of(k).x_mm).fold(f64::MIN, f64::max);
    assert!((x_max(&with_d) - 12.0).abs() < 1e-9);
    assert!((x_max(&spindle) - 11.0).abs() < 1e-9);
}

#[test]
fn zero_radius_leaves_the_path_as_programmed() {
    let program = parse(&POCKET.replace("{side}", "G41"));
    let out = compensate(&program, &tool(0.0)).unwrap();
    let without_comp: Vec<Block> =
        program.blocks.iter().filter(|b| !matches!(b.kind, BlockKind::CutterComp { .. })).cloned().collect();
    assert_eq!(out.blocks, without_comp);
}

#[test]
fn bad_programs_and_tables_are_errors_naming_the_line() {
    let sq = square("G42", (5.0, -5.0));
    assert_eq!(
        compensate(&parse(&sq), &ToolTable::new()).unwrap_err().to_string(),
        "line 2: tool 1 is not in the tool table"
    );
    assert_eq!(
        compensate(&parse(&sq), &tool(-1.0)).unwrap_err().to_string(),
        "line 2: tool 1 has radius -1 mm; a radius must be finite and not negative"
    );
    assert!(compensate(&parse(&sq), &tool(f64::NAN))
        .unwrap_err()
        .to_string()
        .starts_with("line 2: tool 1 has radius NaN"));
    assert_eq!(
        err("G41 D1\nG2 X2 Y0 I1 J0 F100\n", 0.5),
        "line 2: the entry move after G41/G42 must be a straight line (G0/G1), not an arc"
    );
    assert_eq!(
        err("G41 D1\nG1 X1 F100\n", 1.0),
        "line 2: the entry move after G41/G42 moves 1 mm in XY; it must move more than the tool radius 1 mm"
    );
    assert_eq!(
        err("G41 D1\nG1 X5 F100\nG1 Y5\nG40\nG1 X5.5\n", 1.0),
        "line 5: the exit move after G40 moves 0.5 mm in XY; it must move more than the tool radius 1 mm"
    );
    assert_eq!(
        err("G41 D1\nG1 X5 F100\nG40\nG2 X7 Y0 I1 J0\n", 0.5),
        "line 4: the exit move after G40 must be a straight line (G0/G1), not an arc"
    );
    // A plane change while compensating is refused by the front end already.
    assert_eq!(
        finestep_gcode::parse_str("G41 D1\nG1 X5 F100\nG18\nG2 X7 Z0 I1 K0\n", "t.ngc").unwrap_err().to_string(),
        "t.ngc:3:1: Cannot change planes with cutter radius compensation on"
    );
    assert_eq!(
        err("G41 D1\nG1 X5 F100\nT2 M6\n", 0.5),
        "line 3: tool change (M6) with cutter compensation on (G40 first)"
    );
    assert_eq!(
        err("G41 D1\nG1 X5 F100\nG40\nT2 M6\n", 0.5),
        "line 4: tool change (M6) after G40 before the exit move; move out of compensation first"
    );
    assert_eq!(
        err("G0 Y-5\nG42 D1\nG0 X0 Y0\nG0 X-5\n", 0.5),
        "line 4: the corner arc before this rapid needs a feed rate; program a feed move (F) first"
    );
    // A convex corner between rapids takes the last feed.
    let out = run("G1 X0 Y-5 F123\nG41 D1\nG0 X0 Y0\nG0 X5\n", 0.5).unwrap();
    assert!(out
        .blocks
        .iter()
        .any(|b| matches!(b.kind, BlockKind::Arc { feed_mm_per_min, .. } if feed_mm_per_min == 123.0)));
}

#[test]
fn a_program_ending_with_compensation_on_ends_at_the_offset_point() {
    let out = run("G0 X-5\nG41 D1\nG1 X0 Y0 F100\nG1 X10\nG4 P1\nM2\n", 1.0).unwrap();
    let kinds: Vec<BlockKind> = out.blocks.iter().map(|b| b.kind.clone()).collect();
    let n = kinds.len();
    assert!(matches!(kinds[n - 1], BlockKind::End));
    assert!(matches!(kinds[n - 2], BlockKind::Dwell { .. }));
    assert_near(xy(&end_of(&kinds[n - 3])), (10.0, 1.0));
}

// ---------------------------------------------------------------- properties

/// A closed convex contour, counter-clockwise, first element a straight line.
#[derive(Clone, Debug)]
struct Shape {
    /// Vertices in order.
    vertices: Vec<P2>,
    /// Per edge from vertex i to i+1: `None` straight, `Some(half_angle)` an arc
    /// bulging outwards turning 2 * half_angle.
    bulges: Vec<Option<f64>>,
}

impl Shape {
    fn n(&self) -> usize {
        self.vertices.len()
    }

    /// Edge i as a piece (arcs counter-clockwise).
    fn edge(&self, i: usize) -> Piece {
        let (a, b) = (self.vertices[i], self.vertices[(i + 1) % self.n()]);
        match self.bulges[i] {
            None => Piece::Seg(a, b),
            Some(half) => {
                let chord = dist(a, b);
                let u = ((b.0 - a.0) / chord, (b.1 - a.1) / chord);
                let h = chord / 2.0 / half.tan();
                let centre = ((a.0 + b.0) / 2.0 - u.1 * h, (a.1 + b.1) / 2.0 + u.0 * h);
                Piece::Arc {
                    centre,
                    radius: chord / 2.0 / half.sin(),
                    start: (a.1 - centre.1).atan2(a.0 - centre.0),
                    sweep: 2.0 * half,
                }
            }
        }
    }

    fn tangent_turn_at(&self, i: usize) -> f64 {
        // Turn at vertex i between edge i-1's end and edge i's start.
        let tangent = |piece: Piece, at_end: bool| -> P2 {
            let (p, q) = if at_end { (piece.at(1.0 - 1e-7), piece.at(1.0)) } else { (piece.at(0.0), piece.at(1e-7)) };
            let d = sub(q, p);
            (d.0 / len(d), d.1 / len(d))
        };
        let a = tangent(self.edge((i + self.n() - 1) % self.n()), true);
        let b = tangent(self.edge(i), false);
        (a.0 * b.1 - a.1 * b.0).atan2(a.0 * b.0 + a.1 * b.1)
    }

    /// The program: entry to the middle of edge 0 from `entry_distance` beyond the tool
    /// radius on the tool's side, once round, back out the same way.
    fn program(&self, outside: bool, radius: f64, entry_distance: f64) -> (Program, usize, usize) {
        let (a, b) = (self.vertices[0], self.vertices[1]);
        let mid = ((a.0 + b.0) / 2.0, (a.1 + b.1) / 2.0);
        let l = dist(a, b);
        let out_normal = ((b.1 - a.1) / l, -(b.0 - a.0) / l);
        let k = if outside { radius + entry_distance } else { -(radius + entry_distance) };
        let start = (mid.0 + k * out_normal.0, mid.1 + k * out_normal.1);
        let mut builder = Builder::default();
        builder.rapid(start);
        builder.comp(if outside { CompSide::Right } else { CompSide::Left });
        let entry = builder.line(mid);
        builder.line(b);
        for i in 1..self.n() {
            let to = self.vertices[(i + 1) % self.n()];
            match self.edge(i) {
                Piece::Seg(..) => builder.line(to),
                Piece::Arc { centre, .. } => builder.arc(to, centre, false),
            };
        }
        builder.line(mid);
        builder.comp(CompSide::Off);
        let exit = builder.line(start);
        (Program { blocks: builder.blocks }, entry, exit)
    }

    fn contour(&self) -> Vec<Piece> {
        (0..self.n()).map(|i| self.edge(i)).collect()
    }

    fn perimeter(&self) -> f64 {
        self.contour().iter().map(Piece::length).sum()
    }
}

#[derive(Default)]
struct Builder {
    blocks: Vec<Block>,
}

impl Builder {
    fn push(&mut self, kind: BlockKind) -> usize {
        let line = self.blocks.len() + 1;
        self.blocks.push(Block { line, n: None, kind });
        line
    }
    fn point(p: P2) -> Point {
        Point { x_mm: p.0, y_mm: p.1, ..Point::default() }
    }
    fn rapid(&mut self, to: P2) -> usize {
        self.push(BlockKind::Rapid { to: Builder::point(to) })
    }
    fn line(&mut self, to: P2) -> usize {
        self.push(BlockKind::Linear { to: Builder::point(to), feed_mm_per_min: 500.0 })
    }
    fn arc(&mut self, to: P2, centre: P2, clockwise: bool) -> usize {
        self.push(BlockKind::Arc {
            to: Builder::point(to),
            centre: Builder::point(centre),
            plane: Plane::Xy,
            clockwise,
            extra_turns: 0,
            feed_mm_per_min: 500.0,
        })
    }
    fn comp(&mut self, side: CompSide) -> usize {
        self.push(BlockKind::CutterComp { side, tool: Some(1), plane: Plane::Xy })
    }
}

/// Convex shapes: vertices on a circle at random angles, some edges bulged outwards
/// (keeping every vertex convex).
fn shape_strategy() -> impl Strategy<Value = Shape> {
    (3usize..=7)
        .prop_flat_map(|n| {
            (
                proptest::collection::vec(0.35f64..1.0, n),
                proptest::collection::vec(0.0f64..1.0, n),
                4.0f64..40.0,
                (-50.0f64..50.0, -50.0f64..50.0),
                0.0..TAU,
            )
        })
        .prop_map(|(weights, bulge, circle, centre, phase)| {
            let n = weights.len();
            let total: f64 = weights.iter().sum();
            let gaps: Vec<f64> = weights.iter().map(|w| TAU * w / total).collect();
            let mut angle = phase;
            let mut vertices = Vec::new();
            for gap in &gaps {
                vertices.push((centre.0 + circle * angle.cos(), centre.1 + circle * angle.sin()));
                angle += gap;
            }
            // Exterior turn at vertex i of the inscribed polygon: half the two gaps.
            let turn = |i: usize| (gaps[(i + n - 1) % n] + gaps[i]) / 2.0;
            let bulges = (0..n)
                .map(|i| {
                    let limit = 0.45 * turn(i).min(turn((i + 1) % n));
                    let half = (bulge[i] - 0.4) / 0.6 * limit;
                    (i != 0 && half > 0.01).then_some(half)
                })
                .collect();
            Shape { vertices, bulges }
        })
}

/// Every point of the tool path except the entry and exit lines lies at distance r from
/// the contour (within 1e-9 mm); returns the length of that path.
fn check_distance(
    contour: &[Piece],
    out: &Program,
    radius: f64,
    entry: usize,
    exit: usize,
) -> Result<f64, TestCaseError> {
    let mut length = 0.0;
    for (line, piece) in pieces(out) {
        if line <= entry || line >= exit {
            continue;
        }
        length += piece.length();
        for k in 0..=16 {
            let q = piece.at(f64::from(k) / 16.0);
            let d = contour_distance(contour, q);
            prop_assert!((d - radius).abs() <= 1e-9, "line {line} {piece:?} at {q:?}: distance {d}, radius {radius}");
        }
    }
    Ok(length)
}

#[test]
fn outside_of_convex_shapes_is_at_the_tool_radius_and_as_long_as_steiner_says() {
    let mut runner = finestep_testkit::runner("cutter_comp_outside_convex", 256);
    runner
        .run(&(shape_strategy(), 0.001f64..1.0, 0.1f64..5.0), |(shape, radius_fraction, entry)| {
            // The entry cuts back at most r from the half of the first edge after it.
            let radius = radius_fraction * 0.45 * dist(shape.vertices[0], shape.vertices[1]);
            let (program, entry_line, exit_line) = shape.program(true, radius, entry);
            let out = compensate(&program, &tool(radius)).map_err(|e| TestCaseError::fail(e.to_string()))?;
            let length = check_distance(&shape.contour(), &out, radius, entry_line, exit_line)?;
            // Steiner: the outer parallel curve of a convex curve is longer by 2 pi r;
            // the entry and exit cut at most r each from the loop.
            let full = shape.perimeter() + TAU * radius;
            prop_assert!(length <= full + 1e-7 && length >= full - 2.0 * radius - 1e-7, "{length} vs {full}");
            // The path ends exactly where the program does.
            let Some(BlockKind::Linear { to, .. }) = program.blocks.last().map(|b| b.kind.clone()) else {
                unreachable!()
            };
            prop_assert_eq!(last_end(&out, exit_line), to);
            Ok(())
        })
        .unwrap();
}

#[test]
fn inside_of_convex_shapes_is_at_the_tool_radius_or_an_error_when_it_does_not_fit() {
    let mut runner = finestep_testkit::runner("cutter_comp_inside_convex", 256);
    runner
        .run(&(shape_strategy(), 0.01f64..1.0, 0.1f64..3.0), |(shape, radius_fraction, entry)| {
            // A radius between tiny and a large part of the shape's size.
            let size = shape.perimeter() / TAU;
            let radius = radius_fraction * radius_fraction * size;
            let (program, entry_line, exit_line) = shape.program(false, radius, entry);
            let contour = shape.contour();
            // Sizes that certainly fit (cut-backs well below half of every edge) and that
            // certainly do not (a concave arc no larger than the tool).
            let mut fits = 0.1 * (0..shape.n()).map(|i| contour[i].length()).fold(f64::INFINITY, f64::min);
            let mut too_large = false;
            for i in 0..shape.n() {
                let shortest = contour[i].length().min(contour[(i + shape.n() - 1) % shape.n()].length());
                fits = fits.min(0.2 * shortest / (shape.tangent_turn_at(i) / 2.0).tan());
                if let Piece::Arc { radius: arc, .. } = contour[i] {
                    fits = fits.min(0.25 * arc);
                    too_large |= arc <= radius;
                }
            }
            match compensate(&program, &tool(radius)) {
                Ok(out) => {
                    prop_assert!(!too_large, "a concave arc no larger than r = {radius} was accepted");
                    let length = check_distance(&contour, &out, radius, entry_line, exit_line)?;
                    prop_assert!(length > 0.0);
                    // Every programmed edge but the split one is still there.
                    for line in entry_line + 2..exit_line - 2 {
                        prop_assert!(out.blocks.iter().any(|b| b.line == line), "line {line} vanished");
                    }
                }
                Err(e) => {
                    prop_assert!(radius > fits, "r = {radius} fits (bound {fits}) but: {e}");
                    prop_assert!(e.line >= 1 && e.line <= program.blocks.len());
                    prop_assert!(e.to_string().contains("tool radius"), "{e}");
                }
            }
            Ok(())
        })
        .unwrap();
}

/// Convex polygons with every corner rounded by a fillet: tangent everywhere.
fn rounded_strategy() -> impl Strategy<Value = Vec<Piece>> {
    (shape_strategy(), proptest::collection::vec(0.05f64..1.0, 7)).prop_map(|(shape, fillets)| {
        let n = shape.n();
        let v = &shape.vertices;
        let turn: Vec<f64> = (0..n)
            .map(|i| {
                let (a, b, c) = (v[(i + n - 1) % n], v[i], v[(i + 1) % n]);
                let (d1, d2) = (sub(b, a), sub(c, b));
                (d1.0 * d2.1 - d1.1 * d2.0).atan2(d1.0 * d2.0 + d1.1 * d2.1)
            })
            .collect();
        // Fillet radius: the tangent length r tan(turn/2) at most 40 % of both edges.
        let radii: Vec<f64> = (0..n)
            .map(|i| {
                let shortest = dist(v[i], v[(i + n - 1) % n]).min(dist(v[i], v[(i + 1) % n]));
                fillets[i] * 0.4 * shortest / (turn[i] / 2.0).tan()
            })
            .collect();
        let mut pieces = Vec::new();
        for i in 0..n {
            let (a, b) = (v[i], v[(i + 1) % n]);
            let l = dist(a, b);
            let u = ((b.0 - a.0) / l, (b.1 - a.1) / l);
            let t0 = radii[i] * (turn[i] / 2.0).tan();
            let t1 = radii[(i + 1) % n] * (turn[(i + 1) % n] / 2.0).tan();
            let s = (a.0 + u.0 * t0, a.1 + u.1 * t0);
            let e = (b.0 - u.0 * t1, b.1 - u.1 * t1);
            pieces.push(Piece::Seg(s, e));
            // The fillet at b: centre r to the left of the edge at the tangent point.
            let r = radii[(i + 1) % n];
            let centre = (e.0 - u.1 * r, e.1 + u.0 * r);
            pieces.push(Piece::Arc {
                centre,
                radius: r,
                start: (e.1 - centre.1).atan2(e.0 - centre.0),
                sweep: turn[(i + 1) % n],
            });
        }
        pieces
    })
}

/// A program running `contour` (which starts with a line) from the middle of its first
/// line round to that point again, entered and left across it on the tool's side.
fn loop_program(contour: &[Piece], side: CompSide, radius: f64) -> (Program, usize, usize) {
    let Piece::Seg(a, b) = contour[0] else { panic!("starts with a line") };
    let mid = ((a.0 + b.0) / 2.0, (a.1 + b.1) / 2.0);
    let l = dist(a, b);
    let right = ((b.1 - a.1) / l, -(b.0 - a.0) / l);
    let k = if side == CompSide::Right { radius + 1.0 } else { -(radius + 1.0) };
    let start = (mid.0 + k * right.0, mid.1 + k * right.1);
    let mut builder = Builder::default();
    builder.rapid(start);
    builder.comp(side);
    let entry = builder.line(mid);
    builder.line(b);
    for piece in &contour[1..] {
        match *piece {
            Piece::Seg(_, e) => builder.line(e),
            Piece::Arc { centre, sweep, .. } => builder.arc(piece.at(1.0), centre, sweep < 0.0),
        };
    }
    builder.line(mid);
    builder.comp(CompSide::Off);
    let exit = builder.line(start);
    (Program { blocks: builder.blocks }, entry, exit)
}

#[test]
fn offsetting_an_offset_back_gives_the_original() {
    let mut runner = finestep_testkit::runner("cutter_comp_offset_back", 256);
    runner
        .run(&(rounded_strategy(), 0.001f64..1.0), |(contour, radius_fraction)| {
            // No small features: the first pass's entry cuts at most r from the second
            // half of the first line, the second pass enters in the middle of what is
            // left and cuts at most r again: r < l/6 leaves some of it.
            let radius = radius_fraction * 0.15 * contour[0].length();
            let (program, entry, exit) = loop_program(&contour, CompSide::Right, radius);
            let out = compensate(&program, &tool(radius)).map_err(|e| TestCaseError::fail(e.to_string()))?;
            check_distance(&contour, &out, radius, entry, exit)?;
            // The offset loop (tangent everywhere again) without the entry and exit.
            let offset: Vec<Piece> =
                pieces(&out).into_iter().filter(|(l, _)| *l > entry && *l < exit).map(|(_, p)| p).collect();
            prop_assert_eq!(offset.len(), contour.len() + 1, "a tangent loop gets no corner arcs");
            // Without its last piece (the rest of the first line), the loop runs from
            // the middle of its first piece round to there again.
            let (back, entry2, exit2) = loop_program(&offset[..offset.len() - 1], CompSide::Left, radius);
            let out2 = compensate(&back, &tool(radius)).map_err(|e| TestCaseError::fail(e.to_string()))?;
            // The path lies on the original contour ...
            let mut length = 0.0;
            for (line, piece) in pieces(&out2) {
                if line <= entry2 || line >= exit2 {
                    continue;
                }
                length += piece.length();
                for k in 0..=16 {
                    let q = piece.at(f64::from(k) / 16.0);
                    let d = contour_distance(&contour, q);
                    prop_assert!(d <= 1e-9, "line {line} {piece:?} at {q:?} is {d} off the original");
                }
            }
            // ... and covers it, less what the entry and exit cut back.
            let perimeter: f64 = contour.iter().map(Piece::length).sum();
            prop_assert!(
                length >= perimeter - 4.0 * radius - 1e-7 && length <= perimeter + 1e-7,
                "{length} vs {perimeter}"
            );
            Ok(())
        })
        .unwrap();
}

/// Coordinates the front end never gives (NaN, infinities, huge) are no reason to panic.
#[test]
fn non_finite_coordinates_do_not_panic() {
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY, 1e300, -1e300] {
        for position in 0..4 {
            let mut b = Builder::default();
            b.line((0.0, -5.0));
            b.comp(CompSide::Left);
            let mut points = [(0.0, 0.0), (10.0, 0.0), (10.0, 10.0), (0.0, 10.0)];
            points[position].1 = bad;
            b.line(points[0]);
            b.line(points[1]);
            b.arc(points[2], (10.0, 5.0), false);
            b.line(points[3]);
            b.comp(CompSide::Off);
            b.line((-5.0, 10.0));
            let _ = compensate(&Program { blocks: b.blocks }, &tool(1.0));
        }
    }
}

/// Random move sequences with compensation switched on and off: never a panic, and
/// an accepted program has finite coordinates.
#[test]
fn random_programs_never_panic() {
    let step = (0u8..8, -20.0f64..20.0, -20.0f64..20.0, -20.0f64..20.0, -20.0f64..20.0, any::<bool>());
    let mut runner = finestep_testkit::runner("cutter_comp_random_programs", 512);
    runner
        .run(&(proptest::collection::vec(step, 0..30), 0.0f64..5.0), |(steps, radius)| {
            let mut builder = Builder::default();
            for (what, x, y, cx, cy, cw) in steps {
                match what {
                    0 => builder.rapid((x, y)),
                    1 | 2 => builder.line((x, y)),
                    3 => builder.arc((x, y), (cx, cy), cw),
                    4 => builder.comp(if cw { CompSide::Left } else { CompSide::Right }),
                    5 => builder.comp(CompSide::Off),
                    6 => builder.push(BlockKind::Linear {
                        to: Point { x_mm: x, y_mm: y, z_mm: cx, a_deg: cy, ..Point::default() },
                        feed_mm_per_min: 100.0,
                    }),
                    _ => builder.push(BlockKind::Dwell { seconds: 0.1 }),
                };
            }
            let program = Program { blocks: builder.blocks };
            if let Ok(out) = compensate(&program, &tool(radius)) {
                for kind in moves(&out) {
                    let p = end_of(&kind);
                    prop_assert!(p.x_mm.is_finite() && p.y_mm.is_finite(), "{kind:?}");
                }
            }
            Ok(())
        })
        .unwrap();
}

// ---------------------------------------------------------------- LinuxCNC's entry and exit

/// `program` compensated with LinuxCNC's entry and exit (tool table as `table`) against
/// rs274's canonical output for it.
fn agrees_with_rs274(program: &str, table: ToolTable, rs274: &str) {
    use finestep_gcode::conformance::{compare, events_of, rs274_events};
    let compensated = compensate(&parse(program), &table.with_entry_exit(EntryExit::LinuxCnc)).unwrap();
    let theirs = rs274_events(rs274).unwrap();
    assert_eq!(compare(&events_of(&compensated), &theirs), None);
}

/// LinuxCNC's own example `comp-g1.ngc` (its part with tool 4, 1 inch in diameter):
/// rs274's entry ends on the normal of the programmed entry line and slides along that
/// line's offset to the first arc's offset (an inside corner), its exit leaves straight
/// from the last offset point. (Was a disagreement in `make conformance`: finestep's
/// tangent entry and exit, the default, differ there by design.)
#[test]
fn linuxcnc_entry_and_exit_agree_with_rs274_on_comp_g1() {
    let program = "G20 F60\nT4 M6\nG0 X0 Y3.5\nG1 Z0\nG41\nG1 X2 Y3\nG2 X3 Y2 J-1\nG1 Y-1\nG2 X2 Y-2 I-1\nG1 X-3\n\
                   G1 X1.4 Y2.8\nG2 X2 Y3 I.6 J-.8\nG40\nG1 X3 Y3.5\nM2\n";
    let rs274 = "\
            1 N..... USE_LENGTH_UNITS(CANON_UNITS_MM)\n\
            2 N..... SET_G5X_OFFSET(1, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            3 N..... SET_G92_OFFSET(0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            4 N..... SET_XY_ROTATION(0.0000)\n\
            5 N..... SET_FEED_REFERENCE(CANON_XYZ)\n\
            6 N..... ON_RESET()\n\
            7 N..... SET_FEED_RATE(60.0000)\n\
            8 N..... USE_LENGTH_UNITS(CANON_UNITS_INCHES)\n\
            9 N..... SELECT_TOOL(4)\n\
            10 N..... START_CHANGE()\n\
            11 N..... STOP_SPINDLE_TURNING(0)\n\
            12 N..... CHANGE_TOOL(4)\n\
            13 N..... STRAIGHT_TRAVERSE(0.0000, 3.5000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            14 N..... STRAIGHT_FEED(0.0000, 3.5000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            16 N..... STRAIGHT_FEED(2.1438, 3.9948, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            17 N..... ARC_FEED(4.0000, 2.0000, 2.0000, 2.0000, -1, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            18 N..... STRAIGHT_FEED(4.0000, -1.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            19 N..... ARC_FEED(2.0000, -3.0000, 2.0000, -1.0000, -1, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            20 N..... STRAIGHT_FEED(-3.0000, -3.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            21 N..... ARC_FEED(-3.7372, -1.3243, -3.0000, -2.0000, -1, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            22 N..... STRAIGHT_FEED(0.6628, 3.4757, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            23 N..... ARC_FEED(0.8000, 3.6000, 1.4000, 2.8000, -1, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            24 N..... ARC_FEED(2.0000, 4.0000, 2.0000, 2.0000, -1, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            26 N..... STRAIGHT_FEED(3.0000, 3.5000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            27 N..... SET_G5X_OFFSET(1, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            28 N..... SET_XY_ROTATION(0.0000)\n\
            29 N..... SET_FEED_MODE(0, 0)\n\
            30 N..... SET_FEED_RATE(0.0000)\n\
            31 N..... STOP_SPINDLE_TURNING(0)\n\
            32 N..... SET_SPINDLE_MODE(0 0.0000)\n\
            33 N..... PROGRAM_END()\n\
            34 N..... ON_RESET()\n\
            35 N..... ON_RESET()\n";
    agrees_with_rs274(program, ToolTable::new().with_radius_mm(4, 25.4), rs274);
    // The default (tangent) entry stays clear of the programmed corner by the radius.
    let tangent = compensate(&parse(program), &ToolTable::new().with_radius_mm(4, 25.4)).unwrap();
    let entry = tangent.blocks.iter().find(|b| b.line == 6).unwrap();
    let BlockKind::Linear { to, .. } = entry.kind else { panic!("{entry:?}") };
    assert!((len(sub((to.x_mm, to.y_mm), (50.8, 76.2))) - 25.4).abs() < 1e-9);
}

/// G41.1/G42.1 (the diameter in the block, a negative one taking the other side) with
/// LinuxCNC's entry and exit, against rs274.
#[test]
fn dynamic_compensation_agrees_with_rs274() {
    let program = "G20 F10\nG0 X0 Y5\nG41.1 D0.5 G1 X0 Y0\nG1 X5\nG3 X6 Y1 I0 J1\nG1 Y4\nG40\nG1 X8 Y3\n\
                   G42.1 D-0.5 G1 X8 Y0\nG1 X12\nG40 G1 X14 Y-2\nM2\n";
    let rs274 = "\
            1 N..... USE_LENGTH_UNITS(CANON_UNITS_MM)\n\
            2 N..... SET_G5X_OFFSET(1, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            3 N..... SET_G92_OFFSET(0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            4 N..... SET_XY_ROTATION(0.0000)\n\
            5 N..... SET_FEED_REFERENCE(CANON_XYZ)\n\
            6 N..... ON_RESET()\n\
            7 N..... SET_FEED_RATE(10.0000)\n\
            8 N..... USE_LENGTH_UNITS(CANON_UNITS_INCHES)\n\
            9 N..... STRAIGHT_TRAVERSE(0.0000, 5.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            11 N..... STRAIGHT_FEED(0.2500, 0.2500, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            12 N..... STRAIGHT_FEED(5.0000, 0.2500, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            13 N..... ARC_FEED(5.7500, 1.0000, 5.0000, 1.0000, 1, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            14 N..... STRAIGHT_FEED(5.7500, 4.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            16 N..... STRAIGHT_FEED(8.0000, 3.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            18 N..... STRAIGHT_FEED(8.2500, 0.2500, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            19 N..... STRAIGHT_FEED(12.0000, 0.2500, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            21 N..... STRAIGHT_FEED(14.0000, -2.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            22 N..... SET_G5X_OFFSET(1, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            23 N..... SET_XY_ROTATION(0.0000)\n\
            24 N..... SET_FEED_MODE(0, 0)\n\
            25 N..... SET_FEED_RATE(0.0000)\n\
            26 N..... STOP_SPINDLE_TURNING(0)\n\
            27 N..... SET_SPINDLE_MODE(0 0.0000)\n\
            28 N..... PROGRAM_END()\n\
            29 N..... ON_RESET()\n\
            30 N..... ON_RESET()\n";
    agrees_with_rs274(program, ToolTable::new(), rs274);
}

/// Compensation in G18 (a lathe's XZ plane, from LinuxCNC's `comp.ngc` with a tool it
/// fits: G42.1 and G41.1 D0.2 inch), lines and arcs both ways, against rs274.
#[test]
fn compensation_in_g18_agrees_with_rs274() {
    let program = "g20 g64 g18 f10\ng0x-.2z-.2y0\ng42.1 d0.2\ng1x0z0\ng1z1\ng2r.25x-.25z1.25\ng1x-.5\ng3r.25x-.75z1.5\ng1z1.75\ng40\ng0x.2z-.2y0\ng41.1 d0.2\ng1x0z0\ng1z1\ng2r.25x-.25z1.25\ng1x-.5\ng3r.25x-.75z1.5\ng1z1.75\ng40\ng0x.2z-.2y0\nm2\n";
    let rs274 = "\
            1 N..... USE_LENGTH_UNITS(CANON_UNITS_MM)\n\
            2 N..... SET_G5X_OFFSET(1, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            3 N..... SET_G92_OFFSET(0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            4 N..... SET_XY_ROTATION(0.0000)\n\
            5 N..... SET_FEED_REFERENCE(CANON_XYZ)\n\
            6 N..... ON_RESET()\n\
            7 N..... SET_FEED_RATE(10.0000)\n\
            8 N..... SELECT_PLANE(CANON_PLANE_XZ)\n\
            9 N..... USE_LENGTH_UNITS(CANON_UNITS_INCHES)\n\
            10 N..... SET_MOTION_CONTROL_MODE(CANON_CONTINUOUS, 0.000000)\n\
            11 N..... SET_NAIVECAM_TOLERANCE(0.0000)\n\
            12 N..... STRAIGHT_TRAVERSE(-0.2000, 0.0000, -0.2000, 0.0000, 0.0000, 0.0000)\n\
            14 N..... STRAIGHT_FEED(-0.1000, 0.0000, 0.0414, 0.0000, 0.0000, 0.0000)\n\
            15 N..... STRAIGHT_FEED(-0.1000, 0.0000, 1.0000, 0.0000, 0.0000, 0.0000)\n\
            16 N..... ARC_FEED(1.1500, -0.2500, 1.0000, -0.2500, -1, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            17 N..... STRAIGHT_FEED(-0.5000, 0.0000, 1.1500, 0.0000, 0.0000, 0.0000)\n\
            18 N..... ARC_FEED(1.5000, -0.8500, 1.5000, -0.5000, 1, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            19 N..... STRAIGHT_FEED(-0.8500, 0.0000, 1.7500, 0.0000, 0.0000, 0.0000)\n\
            21 N..... STRAIGHT_TRAVERSE(0.2000, 0.0000, -0.2000, 0.0000, 0.0000, 0.0000)\n\
            23 N..... STRAIGHT_FEED(0.1000, 0.0000, 0.0414, 0.0000, 0.0000, 0.0000)\n\
            24 N..... STRAIGHT_FEED(0.1000, 0.0000, 1.0000, 0.0000, 0.0000, 0.0000)\n\
            25 N..... ARC_FEED(1.3500, -0.2500, 1.0000, -0.2500, -1, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            26 N..... STRAIGHT_FEED(-0.5000, 0.0000, 1.3500, 0.0000, 0.0000, 0.0000)\n\
            27 N..... ARC_FEED(1.5000, -0.6500, 1.5000, -0.5000, 1, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            28 N..... STRAIGHT_FEED(-0.6500, 0.0000, 1.7500, 0.0000, 0.0000, 0.0000)\n\
            30 N..... STRAIGHT_TRAVERSE(0.2000, 0.0000, -0.2000, 0.0000, 0.0000, 0.0000)\n\
            31 N..... SET_G5X_OFFSET(1, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            32 N..... SET_XY_ROTATION(0.0000)\n\
            33 N..... SELECT_PLANE(CANON_PLANE_XY)\n\
            34 N..... SET_FEED_MODE(0, 0)\n\
            35 N..... SET_FEED_RATE(0.0000)\n\
            36 N..... STOP_SPINDLE_TURNING(0)\n\
            37 N..... SET_SPINDLE_MODE(0 0.0000)\n\
            38 N..... PROGRAM_END()\n\
            39 N..... ON_RESET()\n\
            40 N..... ON_RESET()\n";
    agrees_with_rs274(program, ToolTable::new(), rs274);
}

/// A concave arc as small as the tool (LinuxCNC's `comp.ngc`: R0.25 arcs, tool 1 of 0.5
/// inch): the tool pivots at the arc's centre, where its neighbours meet; rs274 prints an
/// arc of radius zero there, finestep a move of length zero. Where the neighbours do not
/// meet at the centre (finestep's tangent entry), it is refused with the line.
#[test]
fn a_concave_arc_as_small_as_the_tool_is_a_pivot_as_in_rs274() {
    let program = "g20 g64 g17 f30\ng0x-.2y-.2z0\ng42 d1\ng1x0y0\ng1y1\ng3r.25x-.25y1.25\ng1x-.5\ng2r.25x-.75y1.5\ng1y1.75\ng40\ng0x.2y-.2z0\ng41 d1\ng1x0y0\ng1y1\ng3r.25x-.25y1.25\ng1x-.5\ng2r.25x-.75y1.5\ng1y1.75\ng40\ng0x.2y-.2z0\nm2\n";
    let rs274 = "\
            1 N..... USE_LENGTH_UNITS(CANON_UNITS_MM)\n\
            2 N..... SET_G5X_OFFSET(1, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            3 N..... SET_G92_OFFSET(0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            4 N..... SET_XY_ROTATION(0.0000)\n\
            5 N..... SET_FEED_REFERENCE(CANON_XYZ)\n\
            6 N..... ON_RESET()\n\
            7 N..... SET_FEED_RATE(30.0000)\n\
            8 N..... SELECT_PLANE(CANON_PLANE_XY)\n\
            9 N..... USE_LENGTH_UNITS(CANON_UNITS_INCHES)\n\
            10 N..... SET_MOTION_CONTROL_MODE(CANON_CONTINUOUS, 0.000000)\n\
            11 N..... SET_NAIVECAM_TOLERANCE(0.0000)\n\
            12 N..... STRAIGHT_TRAVERSE(-0.2000, -0.2000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            14 N..... STRAIGHT_FEED(0.1768, -0.1768, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            15 N..... ARC_FEED(0.2500, 0.0000, 0.0000, 0.0000, 1, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            16 N..... STRAIGHT_FEED(0.2500, 1.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            17 N..... ARC_FEED(-0.2500, 1.5000, -0.2500, 1.0000, 1, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            18 N..... STRAIGHT_FEED(-0.5000, 1.5000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            19 N..... ARC_FEED(-0.5000, 1.5000, -0.5000, 1.5000, -1, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            20 N..... STRAIGHT_FEED(-0.5000, 1.7500, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            22 N..... STRAIGHT_TRAVERSE(0.2000, -0.2000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            24 N..... STRAIGHT_FEED(-0.1768, -0.1768, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            25 N..... ARC_FEED(-0.2500, 0.0000, 0.0000, 0.0000, -1, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            26 N..... STRAIGHT_FEED(-0.2500, 1.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            27 N..... ARC_FEED(-0.2500, 1.0000, -0.2500, 1.0000, 1, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            28 N..... STRAIGHT_FEED(-0.5000, 1.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            29 N..... ARC_FEED(-1.0000, 1.5000, -0.5000, 1.5000, -1, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            30 N..... STRAIGHT_FEED(-1.0000, 1.7500, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            32 N..... STRAIGHT_TRAVERSE(0.2000, -0.2000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            33 N..... SET_G5X_OFFSET(1, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            34 N..... SET_XY_ROTATION(0.0000)\n\
            35 N..... SET_FEED_MODE(0, 0)\n\
            36 N..... SET_FEED_RATE(0.0000)\n\
            37 N..... STOP_SPINDLE_TURNING(0)\n\
            38 N..... SET_SPINDLE_MODE(0 0.0000)\n\
            39 N..... PROGRAM_END()\n\
            40 N..... ON_RESET()\n\
            41 N..... ON_RESET()\n";
    agrees_with_rs274(program, ToolTable::new().with_radius_mm(1, 6.35), rs274);
    let err = compensate(&parse("G21 F100\nG0 X0 Y-10\nG41 D1\nG1 X0 Y0\nG3 X-2 Y2 R2\nG1 X-4\nM2\n"), &tool(2.0));
    assert!(err.unwrap_err().to_string().contains("can only pivot at its centre"));
}

/// The programs of tests/conformance/compensated/ (cutter compensation; the quick slice's
/// own test in finestep-gcode compares uncompensated paths) compensated with LinuxCNC's
/// entry and exit and the radii of tool.tbl (its D column, a diameter in inches), against
/// the output of `rs274 -g -t tool.tbl` committed beside each (scripts/conformance_expect.sh
/// writes it): lathe_orientation.ngc, G41.1/G42.1 L0-L9 in G18, where the path is shifted
/// from the nose's centre to the imaginary tool tip.
#[test]
fn compensated_programs_agree_with_rs274() {
    use finestep_gcode::conformance::{compare, events_of, rs274_events};
    use finestep_gcode::Options;
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/conformance");
    let table = std::fs::read_to_string(dir.join("tool.tbl")).unwrap();
    // rs274 without an INI file reads the tool table in inches.
    let options =
        Options { tools: Options::read_tool_table(&table, 25.4).unwrap(), machine_unit_mm: 25.4, ..Options::default() };
    let mut radii = ToolTable::new().with_entry_exit(EntryExit::LinuxCnc);
    for line in table.lines() {
        let word = |letter: char| {
            line.split(';').next().unwrap().split_whitespace().find_map(|w| w.strip_prefix(letter)?.parse::<f64>().ok())
        };
        if let (Some(tool), Some(diameter)) = (word('T'), word('D')) {
            radii.set_radius_mm(tool as u32, diameter * 25.4 / 2.0);
        }
    }
    let mut programs: Vec<_> = std::fs::read_dir(dir.join("compensated"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "ngc"))
        .collect();
    programs.sort();
    assert!(!programs.is_empty());
    let mut failures = Vec::new();
    for program in &programs {
        let theirs = std::fs::read_to_string(program.with_extension("rs274")).unwrap();
        let theirs = rs274_events(&theirs).unwrap();
        let ours = finestep_gcode::parse_file_with(program, &options).unwrap_or_else(|e| panic!("{e}"));
        match compensate(&ours, &radii) {
            Ok(ours) => {
                if let Some(diff) = compare(&events_of(&ours), &theirs) {
                    failures.push(format!("{}: {diff}", program.display()));
                }
            }
            Err(e) => failures.push(format!("{}: {e}", program.display())),
        }
    }
    assert!(failures.is_empty(), "{} of {} disagree:\n{}", failures.len(), programs.len(), failures.join("\n"));
}

//! Directed tests: every supported word, every error message with its exact place.

use crate::*;

const FILE: &str = "t.ngc";

fn parse(source: &str) -> Vec<BlockKind> {
    match parse_str(source, FILE) {
        Ok(p) => p.blocks.into_iter().map(|b| b.kind).collect(),
        Err(e) => panic!("{source:?} failed: {e}"),
    }
}

fn err(source: &str) -> String {
    match parse_str(source, FILE) {
        Ok(p) => panic!("{source:?} parsed: {p:?}"),
        Err(e) => e.to_string(),
    }
}

fn p(x_mm: f64, y_mm: f64, z_mm: f64, a_deg: f64) -> Point {
    Point { x_mm, y_mm, z_mm, a_deg, ..Point::default() }
}

fn close(a: Point, b: Point) -> bool {
    let d = [a.x_mm - b.x_mm, a.y_mm - b.y_mm, a.z_mm - b.z_mm, a.a_deg - b.a_deg];
    d.iter().all(|v| v.abs() < 1e-9)
}

/// The single arc of a program.
fn arc(source: &str) -> (Point, Point, Plane, bool, u32, f64) {
    let arcs: Vec<_> = parse(source)
        .into_iter()
        .filter_map(|k| match k {
            BlockKind::Arc { to, centre, plane, clockwise, extra_turns, feed_mm_per_min } => {
                Some((to, centre, plane, clockwise, extra_turns, feed_mm_per_min))
            }
            _ => None,
        })
        .collect();
    assert_eq!(arcs.len(), 1, "{source:?}");
    arcs[0]
}

#[test]
fn rapid_and_linear_with_lines_and_numbers() {
    let program = parse_str("%\n\nN10 G0 X1 Y2 Z3 A90\nn20 g1 x4 f100\n(comment)\nY5\n%\nG0 X99\n", FILE).unwrap();
    let got: Vec<_> = program.blocks.iter().map(|b| (b.line, b.n, b.kind.clone())).collect();
    assert_eq!(
        got,
        vec![
            (3, Some(10), BlockKind::Rapid { to: p(1.0, 2.0, 3.0, 90.0) }),
            (4, Some(20), BlockKind::Linear { to: p(4.0, 2.0, 3.0, 90.0), feed_mm_per_min: 100.0 }),
            (6, None, BlockKind::Linear { to: p(4.0, 5.0, 3.0, 90.0), feed_mm_per_min: 100.0 }),
        ]
    );
}

#[test]
fn percent_later_ends_the_program_and_m2_stops_reading() {
    assert_eq!(parse("G0 X1\n%\nG0 X2 Q1\n"), vec![BlockKind::Rapid { to: p(1.0, 0.0, 0.0, 0.0) }]);
    assert_eq!(
        parse("G0 X1 M2\nthis is not G-code\n"),
        vec![BlockKind::Rapid { to: p(1.0, 0.0, 0.0, 0.0) }, BlockKind::End]
    );
    assert_eq!(parse("M30\nQ"), vec![BlockKind::End]);
    assert_eq!(parse("M0"), vec![BlockKind::Pause]);
}

#[test]
fn spaces_case_crlf_and_block_delete() {
    assert_eq!(
        parse("g 1 x 1 0 . 5 f 6 0\r\n/G0 Y-2\r\n"),
        vec![
            BlockKind::Linear { to: p(10.5, 0.0, 0.0, 0.0), feed_mm_per_min: 60.0 },
            BlockKind::Rapid { to: p(10.5, -2.0, 0.0, 0.0) },
        ]
    );
}

#[test]
fn modal_motion_without_axes_sets_the_mode_only() {
    assert_eq!(parse("G1 F100\nG0\nX1\n"), vec![BlockKind::Rapid { to: p(1.0, 0.0, 0.0, 0.0) }]);
}

#[test]
fn units_convert_to_mm_and_a_stays_in_degrees() {
    assert_eq!(
        parse("G20 G0 X1 A10\nG1 Y2 F10\nG21 G1 Z3\n"),
        vec![
            BlockKind::Rapid { to: p(25.4, 0.0, 0.0, 10.0) },
            BlockKind::Linear { to: p(25.4, 50.8, 0.0, 10.0), feed_mm_per_min: 254.0 },
            // F keeps its mm/min value across a unit change.
            BlockKind::Linear { to: p(25.4, 50.8, 3.0, 10.0), feed_mm_per_min: 254.0 },
        ]
    );
    // As in LinuxCNC, F is read before G20 acts: F1 in a G20 block from G21 is 1 mm/min.
    assert_eq!(parse("F1 G20 G1 X1"), vec![BlockKind::Linear { to: p(25.4, 0.0, 0.0, 0.0), feed_mm_per_min: 1.0 }]);
}

#[test]
fn incremental_distances_resolve_to_absolute() {
    assert_eq!(
        parse("G0 X1 Y1 A5\nG91 G0 X1 A-10\nG0 X1 Y-3\nG90 G0 X0\nG91 G20 G0 Z1"),
        vec![
            BlockKind::Rapid { to: p(1.0, 1.0, 0.0, 5.0) },
            BlockKind::Rapid { to: p(2.0, 1.0, 0.0, -5.0) },
            BlockKind::Rapid { to: p(3.0, -2.0, 0.0, -5.0) },
            BlockKind::Rapid { to: p(0.0, -2.0, 0.0, -5.0) },
            BlockKind::Rapid { to: p(0.0, -2.0, 25.4, -5.0) },
        ]
    );
}

#[test]
fn dwell_spindle_coolant_tools_comp_path() {
    assert_eq!(
        parse("G4 P1.5\nS1000 M3\nM4\nS200\nM5\nM7\nM8\nM9\nM7 M8\nT3\nT4 M6\nM6\nG41 D3\nG40\nG42\nG40\nG61\nG64\nG64 P0.01\nG20 G64 P0.001\n"),
        vec![
            BlockKind::Dwell { seconds: 1.5 },
            BlockKind::Spindle { rotation: SpindleRotation::Clockwise, rpm: 1000.0, css: None },
            BlockKind::Spindle { rotation: SpindleRotation::CounterClockwise, rpm: 1000.0, css: None },
            BlockKind::Spindle { rotation: SpindleRotation::CounterClockwise, rpm: 200.0, css: None },
            BlockKind::Spindle { rotation: SpindleRotation::Off, rpm: 200.0, css: None },
            BlockKind::Coolant { mist: true, flood: false },
            BlockKind::Coolant { mist: true, flood: true },
            BlockKind::Coolant { mist: false, flood: false },
            BlockKind::Coolant { mist: true, flood: true },
            BlockKind::ToolSelect { tool: 3 },
            BlockKind::ToolSelect { tool: 4 },
            // M6 stops the spindle, as in LinuxCNC.
            BlockKind::Spindle { rotation: SpindleRotation::Off, rpm: 200.0, css: None },
            BlockKind::ToolChange { tool: 4 },
            BlockKind::Spindle { rotation: SpindleRotation::Off, rpm: 200.0, css: None },
            BlockKind::ToolChange { tool: 4 },
            BlockKind::CutterComp { side: CompSide::Left, tool: Some(3), plane: Plane::Xy },
            BlockKind::CutterComp { side: CompSide::Off, tool: None, plane: Plane::Xy },
            BlockKind::CutterComp { side: CompSide::Right, tool: None, plane: Plane::Xy },
            BlockKind::CutterComp { side: CompSide::Off, tool: None, plane: Plane::Xy },
            BlockKind::PathControl(PathControl::ExactPath),
            BlockKind::PathControl(PathControl::Blend { tolerance_mm: None }),
            BlockKind::PathControl(PathControl::Blend { tolerance_mm: Some(0.01) }),
            BlockKind::PathControl(PathControl::Blend { tolerance_mm: Some(0.0254) }),
        ]
    );
}

#[test]
fn one_block_runs_in_linuxcnc_order() {
    let got = parse("G1 X1 F100 M2 G4 P1 M8 M3 S500 T2 M6 G41 D1 G61");
    assert_eq!(
        got,
        vec![
            BlockKind::ToolSelect { tool: 2 },
            BlockKind::Spindle { rotation: SpindleRotation::Off, rpm: 500.0, css: None },
            BlockKind::ToolChange { tool: 2 },
            BlockKind::Spindle { rotation: SpindleRotation::Clockwise, rpm: 500.0, css: None },
            BlockKind::Coolant { mist: false, flood: true },
            BlockKind::Dwell { seconds: 1.0 },
            BlockKind::CutterComp { side: CompSide::Left, tool: Some(1), plane: Plane::Xy },
            BlockKind::PathControl(PathControl::ExactPath),
            BlockKind::Linear { to: p(1.0, 0.0, 0.0, 0.0), feed_mm_per_min: 100.0 },
            BlockKind::End,
        ]
    );
}

#[test]
fn arcs_centre_form_in_all_planes_with_helix() {
    // G17: quarter circle from (10,0) to (0,10) counter-clockwise round the origin,
    // Z rising 5 (helix), A turning.
    let (to, centre, plane, cw, turns, feed) = arc("G0 X10\nG3 X0 Y10 Z5 A30 I-10 J0 F50");
    assert_eq!((to, plane, cw, turns, feed), (p(0.0, 10.0, 5.0, 30.0), Plane::Xy, false, 0, 50.0));
    assert!(close(centre, p(0.0, 0.0, 0.0, 0.0)), "{centre:?}");
    // G18: Z-X plane, normal Y helix.
    let (to, centre, plane, cw, _, _) = arc("G18 G0 Z10\nG2 Z0 X10 Y-3 K-10 F50");
    assert_eq!((to, plane, cw), (p(10.0, -3.0, 0.0, 0.0), Plane::Zx, true));
    assert!(close(centre, p(0.0, 0.0, 0.0, 0.0)), "{centre:?}");
    // G19: Y-Z plane, normal X helix.
    let (to, centre, plane, cw, _, _) = arc("G19 G0 Y10\nG2 Y0 Z10 X7 J-10 F50");
    assert_eq!((to, plane, cw), (p(7.0, 0.0, 10.0, 0.0), Plane::Yz, true));
    assert!(close(centre, p(0.0, 0.0, 0.0, 0.0)), "{centre:?}");
}

#[test]
fn arc_centre_absolute_and_incremental_and_units() {
    let (_, centre, ..) = arc("G0 X10 Y5 Z2\nG90.1 G2 X20 Y5 I15 J5 F1");
    assert!(close(centre, p(15.0, 5.0, 2.0, 0.0)), "{centre:?}");
    let (_, centre, ..) = arc("G0 X10 Y5\nG90.1\nG91.1 G2 X20 Y5 I5 F1");
    assert!(close(centre, p(15.0, 5.0, 0.0, 0.0)), "{centre:?}");
    let (to, centre, ..) = arc("G20 G0 X1\nG91 G3 X-1 Y1 I-1 F1");
    assert!(close(to, p(0.0, 25.4, 0.0, 0.0)), "{to:?}");
    assert!(close(centre, p(0.0, 0.0, 0.0, 0.0)), "{centre:?}");
}

#[test]
fn full_circle_and_helix_turns() {
    let (to, centre, _, cw, turns, _) = arc("G0 X10\nG2 X10 Y0 Z-1 I-10 P3 F100");
    assert_eq!((to, cw, turns), (p(10.0, 0.0, -1.0, 0.0), true, 2));
    assert!(close(centre, p(0.0, 0.0, 0.0, 0.0)));
    // Only Z given: still a full circle (helix) in the plane.
    let (_, _, _, _, turns, _) = arc("G0 X10\nG3 Z-1 I-10 F100");
    assert_eq!(turns, 0);
}

#[test]
fn r_form_short_and_long_arcs() {
    let h = 3.0f64.sqrt(); // chord 2, radius 2: centre sqrt(3) off the chord's middle
    let cases = [
        ("G2", "R2", -h), // clockwise short arc: centre to the right of (0,0)->(2,0)
        ("G2", "R-2", h), // clockwise long arc: to the left
        ("G3", "R2", h),
        ("G3", "R-2", -h),
    ];
    for (g, r, y) in cases {
        let (_, centre, ..) = arc(&format!("{g} X2 {r} F10"));
        assert!(close(centre, p(1.0, y, 0.0, 0.0)), "{g} {r}: {centre:?}");
    }
    // A half circle: R exactly half the chord.
    let (_, centre, ..) = arc("G2 X2 R1 F10");
    assert!(close(centre, p(1.0, 0.0, 0.0, 0.0)), "{centre:?}");
    // In G18, G2 with R in inches.
    let (_, centre, ..) = arc("G18 G20 G2 Z2 R1 F10");
    assert!(close(centre, p(0.0, 0.0, 25.4, 0.0)), "{centre:?}");
}

#[test]
fn arc_end_tolerance_is_linuxcnc_s() {
    // 0.0015 mm off a 1 mm radius: within the absolute 0.002 mm.
    arc("G0 X1\nG3 X-1.0015 I-1 F1");
    // 0.05 mm off a 100 mm radius: within 0.1 %.
    arc("G0 X100\nG3 X-100.05 I-100 F1");
    assert_eq!(err("G0 X100\nG3 X-100.2 I-100 F1"), "t.ngc:2:1: arc end not on circle: radius differs by 0.200 mm");
    assert_eq!(err("G0 X10\nG2 X-10.012 I-10 F1"), "t.ngc:2:1: arc end not on circle: radius differs by 0.012 mm");
}

#[test]
fn file_api_and_io_errors() {
    let dir = std::env::temp_dir().join(format!("finestep-gcode-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("part.ngc");
    std::fs::write(&file, b"G0 X1 (\xff in a comment)\nG0 \xff\n").unwrap();
    let e = parse_file(&file).unwrap_err();
    assert_eq!(e.to_string(), format!("{}:2:4: unexpected character '\u{fffd}'", file.display()));
    assert_eq!((e.line(), e.column()), (Some(2), Some(4)));
    std::fs::write(&file, "G0 X1\n").unwrap();
    assert_eq!(parse_file(&file).unwrap().blocks.len(), 1);
    std::fs::remove_dir_all(&dir).unwrap();
    let e = parse_file(dir.join("missing.ngc")).unwrap_err();
    assert!(matches!(e, GcodeError::Io { .. }));
    assert_eq!((e.line(), e.column()), (None, None));
    assert!(e.to_string().starts_with(&format!("{}: ", dir.join("missing.ngc").display())));
}

#[test]
fn every_error_message_with_its_place() {
    let cases: &[(&str, &str)] = &[
        // Lexical (more in lexer.rs).
        ("G0 X1 (never closed", "1:7: unclosed comment"),
        ("\n  G0 X", "2:7: missing value for word X"),
        ("G0 X1.2.3", "1:5: bad number for word X"),
        ("G0 X12345678901234", "1:5: number out of range for word X"),
        ("N99999999999999 G0", "1:2: number out of range for word N"),
        ("G0 X1 @", "1:8: missing value for word @"),
        ("G0 X1 @1", "1:7: X or Y with polar coordinates @ ^ in one block"),
        (
            // No INI file given: not defined (rs274 without -i: 'Named parameter
            // #<_ini[axis_x]max_velocity> not defined').
            "G0 X#<_ini[axis_x]max_velocity>",
            "1:5: named parameter #<_ini[axis_x]max_velocity> is not defined",
        ),
        ("#<_hal[motion.spindle-speed-out]> = 1", "1:1: unsupported: #<_hal[...]> (finestep reads no HAL pins)"),
        ("G0 X[EXISTS[#<_hal[x]>]]", "1:13: unsupported: #<_hal[...]> (finestep reads no HAL pins)"),
        // Words.
        ("G0 X1 Q2", "1:7: Q word with no G5, G64, G73, G83, M19, M61, M66-M68 or M100-M199 to use it"),
        ("G64 P0.1 Q-1", "1:10: negative naive-CAM tolerance Q"),
        ("F1 G5.1 X1 Y1 I1 J0 B2", "1:21: axis B in a G5.1 spline: only X and Y move"),
        ("G95 F0.1\nG1 X1", "2:1: G1 with zero spindle speed in feed per revolution (G95): S first"),
        (
            "G0 X1e5",
            "1:6: unsupported: exponent in the number of word X (G-code numbers have no exponent: write the digits)",
        ),
        // rs274: 'E word with no G70, G76, M66, M67 or M68 to use it'.
        ("G0 X1 E5", "1:7: E word with no M66, M67 or M68 to use it"),
        ("E5", "1:1: E word with no M66, M67 or M68 to use it"),
        ("M3 S100 $0", "1:9: unsupported: $ spindle selection (finestep drives one spindle: leave $ out)"),
        // rs274: 'Parameter is readonly' for #5400-#5413 and #5420-#5428, not #5414-#5419.
        ("#5420 = 7", "1:1: #5420 is read-only"),
        ("#1 = 1 #[5400 + #1] = 7", "1:8: #5400 is read-only"),
        ("#5413 = 7", "1:1: #5413 is read-only"),
        // rs274 2.9, line by line: a global never set is not defined; NaN or an
        // infinity reaching a value is an error, MOD by zero is NaN (not an error).
        ("G0 X1 Y#<_never>", "1:8: named parameter #<_never> is not defined"),
        ("G0 X[3 MOD 0]", "1:5: calculation resulted in 'not a number'"),
        ("G0 X[1 GT [2 MOD 0]]", "1:11: calculation resulted in 'not a number'"),
        ("G0 X[1 + EXP[1000]]", "1:10: calculation resulted in an infinite value"),
        ("G0 X[ATAN[1 MOD 0]/[1]]", "1:6: calculation resulted in 'not a number'"),
        // rs274: "no matching while/do label: 'o1 break' (found 'repeat' in line 1)".
        (
            "o1 repeat [2]\no1 break\no1 endrepeat",
            "2:1: o1 break inside o1 repeat: LinuxCNC's break and continue serve while and do loops only",
        ),
        // rs274: "duplicate O-word label - already defined in line 1".
        (
            "o1 while [0]\no1 endwhile\no1 if [1]\no1 endif",
            "3:1: label o1 is already used on line 1: LinuxCNC gives each if, while, do and repeat its own label within \
             a subroutine (or the main program)",
        ),
        ("G0 X1 x2", "1:7: word X appears twice"),
        ("F1 G1 X1 F2", "1:10: word F appears twice"),
        ("N1 N2", "1:4: word N appears twice"),
        ("G0 N1", "1:4: N word must come first in the block"),
        ("N1.5 G0", "1:1: N word must be a non-negative integer"),
        (
            "G33 X1",
            "1:1: unsupported: G33 (spindle-synchronised motion needs the spindle feedback finestep does not have yet)",
        ),
        ("G1.23 X1", "1:1: unsupported: G1.23 (not a G-code finestep implements)"),
        ("G-1", "1:1: unsupported: G-1 (not a G-code finestep implements)"),
        ("M98", "1:1: unsupported: M98 (not an M-code finestep implements)"),
        ("M3.5", "1:1: unsupported: M3.5 (not an M-code finestep implements)"),
        // Modal groups.
        ("G0 G1 X1", "1:4: G0 and G1 are in the same modal group"),
        ("G1 G1 X1 F1", "1:4: G1 and G1 are in the same modal group"),
        ("G17 G18", "1:5: G17 and G18 are in the same modal group"),
        ("G90.1 G91.1", "1:7: G90.1 and G91.1 are in the same modal group"),
        ("G20 G21", "1:5: G20 and G21 are in the same modal group"),
        ("G41 G40", "1:5: G41 and G40 are in the same modal group"),
        ("G61 G64", "1:5: G61 and G64 are in the same modal group"),
        ("M3 M5", "1:4: M3 and M5 are in the same modal group"),
        ("M7 M9", "1:4: M7 and M9 are in the same modal group"),
        ("M7 M8 M8", "1:7: M7 and M8 are in the same modal group"),
        ("M0 M2", "1:4: M0 and M2 are in the same modal group"),
        ("M6 M6", "1:4: M6 and M6 are in the same modal group"),
        // Words with nothing to use them.
        ("X1", "1:1: axis word with no motion mode (G0, G1, G2, G3 or a cycle) to use it"),
        ("F100 Y2 X1", "1:6: axis word with no motion mode (G0, G1, G2, G3 or a cycle) to use it"),
        ("G0 X1 I1", "1:7: I word with no G2 or G3 to use it"),
        ("R1", "1:1: R word with no G2, G3, canned cycle, G10 or M19 to use it"),
        ("G0 X1 P1", "1:7: P word with no G4, G64, G2, G3, G5, G5.2, G10, G82, G86, G89, M19, M50-M53, M62-M66 or M100-M199 to use it"),
        ("G4 G64 P1", "1:8: P word is used by more than one code"),
        ("G4 P1 G2 X1 I1 F1", "1:4: P word is used by more than one code"),
        ("G40 D1", "1:5: D word with no G41, G41.1, G42, G42.1 or G96 to use it"),
        ("D1", "1:1: D word with no G41, G41.1, G42, G42.1 or G96 to use it"),
        ("G97 D100 S10", "1:5: D word with no G41, G41.1, G42, G42.1 or G96 to use it"),
        ("G96 D100", "1:1: S word missing with G96"),
        ("G96 G97 S1", "1:5: G96 and G97 are in the same modal group"),
        ("F1 G2 R1", "1:4: G2 with no axis words"),
        ("F1 G2 X1 I0.5\nI1", "2:1: G2 with no axis words"),
        ("F1 G3 X1 Y1 I1\nJ1", "2:1: G3 with no axis words"),
        // Values.
        ("F-1", "1:1: negative feed rate"),
        ("S-1", "1:1: negative spindle speed"),
        ("T1.5", "1:1: T word must be a non-negative integer"),
        ("T-1", "1:1: T word must be a non-negative integer"),
        ("G41 D-2", "1:5: D word must be a non-negative integer"),
        ("G4", "1:1: G4 with no P word"),
        ("G4 P-1", "1:4: negative dwell time"),
        ("G64 P-0.1", "1:5: negative path tolerance"),
        ("G41\nG42", "2:1: cutter compensation is already on (G40 first)"),
        ("G91 G0 X1000000000\nX1000000000\nX1000000000\nG20 X1000000000", "4:5: position out of range"),
        // Feed.
        ("G1 X1", "1:1: G1 with no feed rate"),
        ("G1 F0\n X1", "2:2: G1 with no feed rate"),
        ("G2 X1 I1", "1:1: G2 with no feed rate"),
        ("G3 X1 I1", "1:1: G3 with no feed rate"),
        // Arcs.
        ("F1 G2 X1", "1:4: G2 without I/J/K or R"),
        ("F1 G3 X1 Y1 I1\n Y2", "2:2: G3 without I/J/K or R"),
        ("F1 G2 X2 I1 R1", "1:13: G2 with both R and I/J/K"),
        ("F1 G2 X2 I1 K1", "1:13: K word not allowed for an arc in the G17 plane"),
        ("F1 G18 G2 X2 I1 J1", "1:17: J word not allowed for an arc in the G18 plane"),
        ("F1 G19 G2 Y2 I1 J1", "1:14: I word not allowed for an arc in the G19 plane"),
        ("F1 G2 X2 J0", "1:4: arc radius is zero"),
        ("F1 G2 X2 I1 P0", "1:13: P word for G2 must be a positive integer"),
        ("F1 G2 X2 I1 P1.5", "1:13: P word for G2 must be a positive integer"),
        ("F1 G2 X0 R1", "1:10: R-form arc needs an end point different from its start"),
        ("F1 G2 X2 Y0 R0.99", "1:13: arc radius 0.990 mm is less than half the chord 1.000 mm"),
        ("F1 G3 X2 R-0.5", "1:10: arc radius 0.500 mm is less than half the chord 1.000 mm"),
        ("G0 X10\nF1 G2 X-10.012 I-10", "2:4: arc end not on circle: radius differs by 0.012 mm"),
    ];
    for (source, expected) in cases {
        assert_eq!(err(source), format!("t.ngc:{expected}"), "{source:?}");
    }
}

#[test]
fn r_form_tolerates_rounding_of_the_half_chord() {
    let (_, centre, ..) = arc("F1 G2 X2 R0.999");
    assert!(close(centre, p(1.0, 0.0, 0.0, 0.0)), "{centre:?}");
}

#[test]
fn hostile_input_is_an_error_not_a_panic() {
    let long = format!("G0 X1 ({})", "a".repeat(10_000));
    assert_eq!(parse(&long).len(), 1);
    let long = format!("G0 {}", "X1 ".repeat(5_000));
    assert_eq!(err(&long), "t.ngc:1:7: word X appears twice");
    let digits = format!("G0 X{}", "9".repeat(10_000));
    assert_eq!(err(&digits), "t.ngc:1:5: number out of range for word X");
    assert_eq!(err("T99999999999"), "t.ngc:1:2: number out of range for word T");
    assert_eq!(err("T4294967296"), "t.ngc:1:2: number out of range for word T");
    assert_eq!(err(""), "t.ngc:1:1: the program is empty (no blocks)");
}

/// Compensation in G17 and G18 (carried by the block), not in G19, and the plane kept
/// while it is on: rs274's messages.
#[test]
fn compensation_in_the_xy_and_xz_planes() {
    let err = parse_str("G19\nG41 D1\n", "p.ngc").unwrap_err();
    assert_eq!(err.to_string(), "p.ngc:2:1: Cutter radius compensation allowed only in XY, XZ planes");
    let err = parse_str("G17 G41 D1\nG1 X1 F100\nG19\n", "p.ngc").unwrap_err();
    assert_eq!(err.to_string(), "p.ngc:3:1: Cannot change planes with cutter radius compensation on");
    let err = parse_str("G18 G41 D1\nG1 X1 F100\nG17\n", "p.ngc").unwrap_err();
    assert_eq!(err.to_string(), "p.ngc:3:1: Cannot change planes with cutter radius compensation on");
    assert!(parse_str("G17 G41 D1\nG1 X1 F100\nG40\nG18\n", "p.ngc").is_ok());
    let comps: Vec<BlockKind> = parse("G18 G42 D2\nG40\nG41.1 D1\nG40\n")
        .into_iter()
        .filter(|k| matches!(k, BlockKind::CutterComp { .. } | BlockKind::CutterCompRadius { .. }))
        .collect();
    assert_eq!(
        comps,
        [
            BlockKind::CutterComp { side: CompSide::Right, tool: Some(2), plane: Plane::Zx },
            BlockKind::CutterComp { side: CompSide::Off, tool: None, plane: Plane::Zx },
            BlockKind::CutterCompRadius { side: CompSide::Left, radius_mm: 0.5, plane: Plane::Zx, orientation: 0 },
            BlockKind::CutterComp { side: CompSide::Off, tool: None, plane: Plane::Zx },
        ]
    );
}

/// A NURBS as the tests read it: control points (x, y, w), order, knots, feed, end.
type NurbsParts = (Vec<(f64, f64, f64)>, u32, Vec<f64>, f64, Point);

/// The single NURBS of a program.
fn nurbs(source: &str) -> NurbsParts {
    let found: Vec<_> = parse(source)
        .into_iter()
        .filter_map(|k| match k {
            BlockKind::Nurbs { to, control_points, order, knots, feed_mm_per_min } => Some((
                control_points.iter().map(|c| (c.x_mm, c.y_mm, c.weight)).collect(),
                order,
                knots,
                feed_mm_per_min,
                to,
            )),
            _ => None,
        })
        .collect();
    assert_eq!(found.len(), 1, "{source:?}");
    found.into_iter().next().unwrap()
}

#[test]
fn nurbs_blocks_follow_linuxcnc() {
    // LinuxCNC's documented example: the current position is the first control point,
    // `G5.2 P1 L3` sets its weight and the order, the default order is 3.
    let (points, order, knots, feed, to) =
        nurbs("G0 X0 Y0 Z2\nF10\nG5.2 P1 L3\n X0 Y1 P1\n X2 Y2 P1\n X2 Y0 P1\n X0 Y0 P2\nG5.3\nM2\n");
    assert_eq!(points, vec![(0.0, 0.0, 1.0), (0.0, 1.0, 1.0), (2.0, 2.0, 1.0), (2.0, 0.0, 1.0), (0.0, 0.0, 2.0)]);
    assert_eq!(order, 3);
    assert_eq!(knots, vec![0.0, 0.0, 0.0, 1.0, 2.0, 3.0, 3.0, 3.0]);
    assert_eq!(feed, 10.0);
    assert!(close(to, p(0.0, 0.0, 2.0, 0.0)));
    // X Y on the G5.2 line is the second control point; weights default to 1; G20 and
    // G91 (relative to the NURBS's start) apply; the block comes on the G5.3 line.
    let source = "G0 X1 Y1\nG20 G91\nF1\nG5.2 X1 Y0 P0.5 L4\nX1 Y1\nX0 Y1 P2\nG5.3\nG1 X0.1\n";
    let (points, order, knots, feed, to) = nurbs(source);
    let i = 25.4;
    assert_eq!(points, vec![(1.0, 1.0, 1.0), (1.0 + i, 1.0, 0.5), (1.0 + i, 1.0 + i, 1.0), (1.0, 1.0 + i, 2.0)]);
    assert_eq!((order, knots, feed), (4, vec![0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0], i));
    assert!(close(to, p(1.0, 1.0 + i, 0.0, 0.0)));
    let program = parse_str(source, FILE).unwrap();
    assert_eq!(program.blocks.iter().map(|b| b.line).collect::<Vec<_>>(), vec![1, 7, 8]);
    let BlockKind::Linear { to, .. } = program.blocks[2].kind else { panic!() };
    assert!(close(to, p(1.0 + 0.1 * i, 1.0 + i, 0.0, 0.0)));
    // Order 2 is the control polygon; N words, comments and blank lines may stand inside.
    let (points, order, knots, ..) = nurbs("F600\nG5.2 X1 Y0 L2\n\n(corner)\nN30 X1 Y1\nG5.3 M2\n");
    assert_eq!((points.len(), order), (3, 2));
    assert_eq!(knots, vec![0.0, 0.0, 1.0, 2.0, 2.0]);
    assert_eq!(nurbs_knots(7, 3), vec![0.0, 0.0, 0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 5.0, 5.0]);
    // No motion mode after G5.3 (LinuxCNC's motion mode -1).
    assert_eq!(
        err("F600\nG5.2 X1 Y0\nX1 Y1\nG5.3\nX2\n"),
        "t.ngc:5:1: axis word with no motion mode (G0, G1, G2, G3 or a cycle) to use it"
    );
}

#[test]
fn nurbs_errors_with_their_place() {
    let cases: &[(&str, &str)] = &[
        (
            "F600\nG5.2 X1 Y0\nX1 Y1\nG5.3 X3\n",
            "4:6: G5.3 takes no axis words (control points go on the lines before it)",
        ),
        ("F600\nG5.3\n", "2:1: G5.3 without G5.2 first"),
        ("F600\nG5.2 X1 Y0\nG5.3\n", "3:1: a NURBS of order 3 needs at least 3 control points, this one has 2"),
        (
            "F600\nG5.2 X1 Y0 L4\nX2 Y2\nG5.3\n",
            "4:1: a NURBS of order 4 needs at least 4 control points, this one has 3",
        ),
        ("F600\nG5.2 X1 Y0 P0\n", "2:12: NURBS weight P must be positive"),
        ("F600\nG5.2 X1 Y0\nX2 Y1 P-1\n", "3:7: NURBS weight P must be positive"),
        ("F600\nG5.2 X1 Y0 L1\n", "2:12: NURBS order L must be an integer from 2 to 16"),
        ("F600\nG5.2 X1 Y0 L2.5\n", "2:12: NURBS order L must be an integer from 2 to 16"),
        ("F600\nG5.2 X1\n", "2:6: a NURBS control point needs both X and Y"),
        ("F600\nG5.2 X1 Y1\nY2\n", "3:1: a NURBS control point needs both X and Y"),
        (
            "F600\nG5.2 X1 Y1\nP2\n",
            "3:1: P without X and Y sets only the first control point's weight (on the G5.2 line)",
        ),
        ("F600\nG5.2 X1 Y1 Z1\n", "2:12: axis Z in a NURBS: only X and Y move in a NURBS (G17)"),
        ("F600\nG5.2 X1 Y1\nX2 Y2 A3\n", "3:7: axis A inside a NURBS block: only X and Y move in a NURBS (G17)"),
        ("F600\nG5.2 X1 Y1\nG1 X2 Y2\n", "3:1: G1 inside a NURBS block: only X, Y and P words until G5.3 closes it"),
        (
            "F600\nG5.2 X1 Y1\nX2 Y2\nG5.2 X3 Y3\n",
            "4:1: G5.2 inside a NURBS block: only X, Y and P words until G5.3 closes it",
        ),
        (
            "F600\nG5.2 X1 Y1\nX2 Y2 F100\n",
            "3:7: F word inside a NURBS block: only X, Y and P words until G5.3 closes it",
        ),
        (
            "F600\nG5.2 X1 Y1\nX2 Y2\nM2\n",
            "4:1: M word inside a NURBS block: only X, Y and P words until G5.3 closes it",
        ),
        ("G18 F600\nG5.2 X1 Y1\n", "2:1: G5.2 NURBS is supported in the G17 (XY) plane only"),
        ("F600\nG41 D1\nG5.2 X1 Y1\n", "3:1: G5.2 with cutter compensation on: a NURBS is not offset (G40 first)"),
        ("G5.2 X1 Y1\n", "1:1: G5.2 with no feed rate"),
        ("F600\nG1 X1 L3\n", "2:7: L word with no G5.2, G10, canned cycle or M66 to use it"),
        (
            "F600\nG5.2 X1 Y1\nX2 Y2\nG5.3 P2\n",
            "4:6: P word with no G4, G64, G2, G3, G5, G5.2, G10, G82, G86, G89, M19, M50-M53, M62-M66 or M100-M199 to use it",
        ),
        // The program ends inside the block: the error points at its G5.2.
        (
            "F600\nG0 X1\n G5.2 X1 Y1\nX2 Y2\nX3 Y1\n",
            "3:2: the program ends inside the NURBS block opened here (G5.3 missing)",
        ),
        ("F600\nG5.2 X1 Y1 M2\n", "2:1: the program ends inside the NURBS block opened here (G5.3 missing)"),
        (
            "%\nF600\nG5.2 X1 Y1\nX2 Y2\n%\nX9 Y9\nG5.3\n",
            "3:1: the program ends inside the NURBS block opened here (G5.3 missing)",
        ),
    ];
    for (source, expected) in cases {
        assert_eq!(err(source), format!("{FILE}:{expected}"), "{source:?}");
    }
}

/// The parameter file of `rs274 -g -v in.var t.ngc` (LinuxCNC 2.9, no INI file, so the
/// machine unit is the inch): G55 in use with X 1 Y -2 and a 90-degree rotation, G92 X
/// 0.5 in force, and #31 kept because the file lists it.
const VAR_IN: &str = "31\t4.000000\n5161\t0.000000\n5210\t1.000000\n5211\t0.500000\n5220\t2.000000\n\
                      5241\t1.000000\n5242\t-2.000000\n5250\t90.000000\n";

#[test]
fn parameter_file_sets_the_offsets_in_force_and_comes_back_as_rs274_writes_it() {
    let options =
        Options { machine_unit_mm: 25.4, parameters: Parameters::read(VAR_IN).unwrap(), ..Options::default() };
    let source = "G0 X1 Y0\n#1=[#5220] #2=[#5211] #3=[#5241]\nG1 F100 X[#1] Y[#2+#3]\nG54\nG0 X0\n\
                  #5221=3 #31=[#31+1] #32=5\nM2\n";
    let (program, parameters) = parse_str_with_parameters(source, FILE, &options).unwrap();
    // What rs274 printed for it, in program coordinates with its offsets (G54 loads
    // G92 X 12.7 mm again; M2 then loads #5221 = 3 in).
    let rs274 = "\
                     1 N..... USE_LENGTH_UNITS(CANON_UNITS_MM)\n\
                     2 N..... SET_G5X_OFFSET(2, 25.4000, -50.8000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
                     3 N..... SET_G92_OFFSET(12.7000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
                     4 N..... SET_XY_ROTATION(90.0000)\n\
                     5 N..... SET_FEED_REFERENCE(CANON_XYZ)\n\
                     6 N..... ON_RESET()\n\
                     7 N..... STRAIGHT_TRAVERSE(1.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
                     8 N..... SET_FEED_RATE(100.0000)\n\
                     9 N..... STRAIGHT_FEED(2.0000, 1.5000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
                    10 N..... SET_G5X_OFFSET(1, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
                    11 N..... SET_G92_OFFSET(12.7000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
                    12 N..... SET_XY_ROTATION(0.0000)\n\
                    13 N..... STRAIGHT_TRAVERSE(0.0000, -36.1000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
                    14 N..... SET_G5X_OFFSET(1, 76.2000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
                    15 N..... SET_XY_ROTATION(0.0000)\n\
                    16 N..... SET_FEED_MODE(0, 0)\n\
                    17 N..... SET_FEED_RATE(0.0000)\n\
                    18 N..... STOP_SPINDLE_TURNING(0)\n\
                    19 N..... SET_SPINDLE_MODE(0 0.0000)\n\
                    20 N..... PROGRAM_END()\n\
                    21 N..... ON_RESET()\n\
                    22 N..... ON_RESET()\n";
    let theirs = conformance::rs274_events(rs274).unwrap();
    assert_eq!(conformance::compare(&conformance::events_of(&program), &theirs), None);
    // Hand-derived: program (1, 0) + G92 (12.7, 0), turned 90 degrees: (0, 13.7), plus
    // G55 (25.4, -50.8).
    let BlockKind::Rapid { to } = program.blocks[0].kind else { panic!("{:?}", program.blocks[0]) };
    assert!(close(to, p(25.4, -37.1, 0.0, 0.0)), "{to:?}");
    // rs274 wrote its 119 required parameters and #31 (listed in the file), not #32.
    assert_eq!(parameters.values.len(), 120);
    assert_eq!(required_parameters().count(), 119);
    let value = |n: usize| parameters.values[&n];
    assert_eq!(value(5220), 1.0);
    assert!((value(5221) - 3.0).abs() < 1e-9);
    assert_eq!((value(31), value(5210), value(5250)), (5.0, 1.0, 90.0));
    assert!((value(5211) - 0.5).abs() < 1e-9 && (value(5242) + 2.0).abs() < 1e-9);
    assert!(!parameters.values.contains_key(&32));
    let text = parameters.to_text();
    assert!(text.starts_with("31\t5.000000\n5161\t0.000000\n"), "{text}");
    assert!(text.contains("\n5220\t1.000000\n5221\t3.000000\n"), "{text}");
    assert_eq!(Parameters::read(&text).unwrap().values.len(), 120);
    // Without a parameter file nothing is in force and the required ones are zero but
    // #5220 (G54).
    let (_, parameters) = parse_str_with_parameters("G0 X1\n", FILE, &Options::default()).unwrap();
    assert_eq!(parameters.values.len(), 119);
    assert!(parameters.values.iter().all(|(&n, &v)| v == if n == 5220 { 1.0 } else { 0.0 }));
    // M2 and M30 put G54 back in force, as rs274's M2 does (`G55`, `M2`: #5220 is 1 in
    // the file rs274 -v writes); a program stopped before its end leaves G55.
    for (source, system) in [("G55\nM2\n", 1.0), ("G55\nM30\n", 1.0), ("G55\nG0 X1\n", 2.0)] {
        let (_, parameters) = parse_str_with_parameters(source, FILE, &Options::default()).unwrap();
        assert_eq!(parameters.values[&5220], system, "{source:?}");
    }
}

#[test]
fn parameter_file_errors() {
    assert_eq!(
        Parameters::read("5161 0\n5161 1\n").unwrap_err().to_string(),
        "parameter file line 2: parameter 5161 out of order (after 5161)"
    );
    assert_eq!(
        Parameters::read("0 1\n").unwrap_err().to_string(),
        "parameter file line 1: parameter number 0 out of range (1 to 5601)"
    );
    assert_eq!(
        Parameters::read("5602 1\n").unwrap_err().to_string(),
        "parameter file line 1: parameter number 5602 out of range (1 to 5601)"
    );
    assert_eq!(
        Parameters::read("10 inf\n").unwrap_err().to_string(),
        "parameter file line 1: the value of parameter 10 is not a finite number"
    );
    // Lines that do not start with an index and a value are skipped, as LinuxCNC does.
    let read = Parameters::read("# comment\n\n5161 1.5 trailing\nabc 1\n").unwrap();
    assert_eq!(read.values.into_iter().collect::<Vec<_>>(), vec![(5161, 1.5)]);
    let options = Options { parameters: Parameters::read("5220 10\n").unwrap(), ..Options::default() };
    assert_eq!(
        parse_str_with("G0 X1\n", FILE, &options).unwrap_err().to_string(),
        "parameter file: parameter 5220 (the coordinate system in use) is 10: it must be 1 (G54) to 9 (G59.3)"
    );
}

#[test]
fn g64_q_is_accepted_and_not_used() {
    // melfa-sim/example.ngc, which rs274 accepts: G64 P0.1 Q1 (Q, the naive-CAM
    // tolerance, merges nothing here: every segment is kept).
    assert_eq!(
        parse("G90 G64 P0.1 Q1\n"),
        vec![BlockKind::PathControl(PathControl::Blend { tolerance_mm: Some(0.1) })]
    );
}

#[test]
fn exists_nan_and_globals_as_rs274() {
    // rs274 -g printed STRAIGHT_TRAVERSE(1, 0, 2, ...) for line 1 and X 3 for line 3:
    // EXISTS of a global never set is 0 (and no error), of a predefined one 1; 2 MOD 0 is
    // NaN, 1 GT NaN is 0 inside one expression; a global set to 0 exists.
    let blocks = parse(
        "G0 X[EXISTS[#<_never>]+1] Y[1 GT 2 MOD 0 + 5] Z[EXISTS[#<_x>] + 1]\n#<_set> = 0\n\
         G0 X[EXISTS[#<_set>] + 2 + #<_value> + #<_value_returned> + #<_call_level>]\n",
    );
    assert_eq!(
        blocks,
        vec![BlockKind::Rapid { to: p(1.0, 0.0, 2.0, 0.0) }, BlockKind::Rapid { to: p(3.0, 0.0, 2.0, 0.0) }]
    );
    // #<_call_level> is 1 inside a call.
    let blocks = parse("o<s> sub\nG0 X#<_call_level>\no<s> endsub\no<s> call\n");
    assert_eq!(blocks, vec![BlockKind::Rapid { to: p(1.0, 0.0, 0.0, 0.0) }]);
}

#[test]
fn value_after_a_return_without_one_is_zero() {
    // rs274 -g: STRAIGHT_TRAVERSE(7, 1, ...) then (0, 0, ...).
    let blocks = parse(
        "o<s> sub\no<s> return [7]\no<s> endsub\no<t> sub\no<t> endsub\no<s> call\n\
         G0 X#<_value> Y#<_value_returned>\no<t> call\nG0 X#<_value> Y#<_value_returned>\nM2\n",
    );
    assert_eq!(
        blocks,
        vec![
            BlockKind::Rapid { to: p(7.0, 1.0, 0.0, 0.0) },
            BlockKind::Rapid { to: p(0.0, 0.0, 0.0, 0.0) },
            BlockKind::End
        ]
    );
}

#[test]
fn calls_nest_nine_deep_as_rs274() {
    // rs274 -g: a recursion of 9 runs (traverses to X 1 ... 9); of 10 it stops with
    // "Too many subroutine levels" after X 9.
    let program = |n: u32| {
        format!(
            "o<r> sub\nG0 X#<_call_level>\no1 if [#1 GT 1]\no<r> call [#1 - 1]\no1 endif\no<r> endsub\n\
             o<r> call [{n}]\nM2\n"
        )
    };
    let blocks = parse(&program(9));
    assert_eq!(blocks.len(), 10);
    assert_eq!(blocks[8], BlockKind::Rapid { to: p(9.0, 0.0, 0.0, 0.0) });
    assert_eq!(
        err(&program(10)),
        "t.ngc:4:1: subroutine calls nest more than 9 deep (LinuxCNC's limit: too many subroutine levels)"
    );
}

/// G93 inverse-time feed and back to G94, and G61.1, against what LinuxCNC 2.9's `rs274
/// -g` printed for the same program: each move's feed is its length (X Y Z, or A alone,
/// or the helix) times F, at least 0.1 program units a minute (F0 too).
#[test]
fn inverse_time_feed_and_exact_stop_agree_with_rs274() {
    let source = "G21 G93\nG1 X10 F2\nG2 X20 I5 F1\nG2 X21 Y1 Z2 I1 F2\nG1 A90 F3\nG3 X21 Y1 I0 J-1 P2 F1\n\
                  G0 X0 Y0 Z0\nG94 F100\nG1 X1\nG61.1\nG1 X2\nG20 G93 G1 X0 F0.5\nM2\n";
    let program = parse_str(source, FILE).unwrap();
    let rs274 = "\
         7 N..... COMMENT(\"interpreter: feed mode set to inverse time\")\n\
         8 N..... SET_FEED_MODE(0, 0)\n\
         9 N..... USE_LENGTH_UNITS(CANON_UNITS_MM)\n\
        10 N..... SET_FEED_RATE(20.0000)\n\
        11 N..... STRAIGHT_FEED(10.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
        12 N..... SET_FEED_RATE(15.7080)\n\
        13 N..... ARC_FEED(20.0000, 0.0000, 15.0000, 0.0000, -1, 0.0000, 0.0000, 0.0000, 0.0000)\n\
        14 N..... SET_FEED_RATE(5.0862)\n\
        15 N..... ARC_FEED(21.0000, 1.0000, 21.0000, 0.0000, -1, 2.0000, 0.0000, 0.0000, 0.0000)\n\
        16 N..... SET_FEED_RATE(270.0000)\n\
        17 N..... STRAIGHT_FEED(21.0000, 1.0000, 2.0000, 90.0000, 0.0000, 0.0000)\n\
        18 N..... SET_FEED_RATE(12.5664)\n\
        19 N..... ARC_FEED(21.0000, 1.0000, 21.0000, 0.0000, 2, 2.0000, 90.0000, 0.0000, 0.0000)\n\
        20 N..... STRAIGHT_TRAVERSE(0.0000, 0.0000, 0.0000, 90.0000, 0.0000, 0.0000)\n\
        21 N..... COMMENT(\"interpreter: feed mode set to units per minute\")\n\
        22 N..... SET_FEED_MODE(0, 0)\n\
        23 N..... SET_FEED_RATE(0.0000)\n\
        24 N..... SET_FEED_RATE(100.0000)\n\
        25 N..... STRAIGHT_FEED(1.0000, 0.0000, 0.0000, 90.0000, 0.0000, 0.0000)\n\
        26 N..... SET_MOTION_CONTROL_MODE(CANON_EXACT_STOP)\n\
        27 N..... STRAIGHT_FEED(2.0000, 0.0000, 0.0000, 90.0000, 0.0000, 0.0000)\n\
        28 N..... COMMENT(\"interpreter: feed mode set to inverse time\")\n\
        29 N..... SET_FEED_MODE(0, 0)\n\
        30 N..... USE_LENGTH_UNITS(CANON_UNITS_INCHES)\n\
        31 N..... SET_FEED_RATE(0.1000)\n\
        32 N..... STRAIGHT_FEED(0.0000, 0.0000, 0.0000, 90.0000, 0.0000, 0.0000)\n\
        39 N..... PROGRAM_END()\n";
    let theirs = conformance::rs274_events(rs274).unwrap();
    assert_eq!(conformance::compare(&conformance::events_of(&program), &theirs), None);
    let feeds: Vec<f64> = program
        .blocks
        .iter()
        .filter_map(|b| match b.kind {
            BlockKind::Linear { feed_mm_per_min, .. } | BlockKind::Arc { feed_mm_per_min, .. } => Some(feed_mm_per_min),
            _ => None,
        })
        .collect();
    let expected = [20.0, 5.0 * std::f64::consts::PI, 2.0 * (std::f64::consts::FRAC_PI_2.hypot(2.0)), 270.0];
    for (got, want) in feeds.iter().zip(expected) {
        assert!((got - want).abs() < 1e-9, "{feeds:?}");
    }
    assert!((feeds[4] - 4.0 * std::f64::consts::PI).abs() < 1e-9 && feeds[5..8] == [100.0, 100.0, 2.54], "{feeds:?}");
    assert!(program.blocks.iter().any(|b| b.kind == BlockKind::PathControl(PathControl::ExactPath)));
    // rs274's refusals: no F on the move's own block (an F alone on a line before does not
    // count); a canned cycle in G93 (rs274: "Cannot feed with zero feed rate").
    for (source, expected) in [
        ("G93 G1 X1\n", "1:5: G1 in inverse-time feed (G93) without F on its block"),
        ("G93 G1 X1 F1\nF2\nG1 X3\n", "3:1: G1 in inverse-time feed (G93) without F on its block"),
        ("G93\nG2 X2 I1\n", "2:1: G2 in inverse-time feed (G93) without F on its block"),
        ("G93 G81 X1 Y1 Z-1 R1 F1\n", "1:9: G81 in inverse-time feed (G93): G94 first"),
        ("G94 F10\nG93\nG94\nG1 X1\n", "4:1: G1 with no feed rate"),
    ] {
        assert_eq!(err(source), format!("{FILE}:{expected}"), "{source:?}");
    }
}

/// M48-M53 as modal state: what `#<_feed_override>` + 2 `#<_speed_override>` + 4
/// `#<_adaptive_feed>` + 8 `#<_feed_hold>` reads after each, as LinuxCNC 2.9's rs274
/// printed it for the same program (a `G0 X` of that sum after each code); each emits
/// the switches as an event.
#[test]
fn override_switches_read_back_as_rs274_reads_them() {
    let sum = "[#<_feed_override> + 2 * #<_speed_override> + 4 * #<_adaptive_feed> + 8 * #<_feed_hold>]";
    let codes = ["", "M49", "M50", "M51 P2", "M52 P1", "M53 P0", "M50 P0", "M48", "M52 P0"];
    let source: String = codes.iter().map(|code| format!("{code}\nG0 X{sum}\n")).collect::<String>() + "M2\n";
    let program = parse_str(&source, FILE).unwrap();
    let xs: Vec<f64> = program
        .blocks
        .iter()
        .filter_map(|b| if let BlockKind::Rapid { to } = b.kind { Some(to.x_mm) } else { None })
        .collect();
    assert_eq!(xs, [11.0, 8.0, 9.0, 11.0, 15.0, 7.0, 6.0, 7.0, 3.0]);
    let events: Vec<Overrides> = program
        .blocks
        .iter()
        .filter_map(|b| if let BlockKind::Overrides(o) = b.kind { Some(o) } else { None })
        .collect();
    assert_eq!(events.len(), 8);
    assert_eq!(events[3], Overrides { feed: true, speed: true, adaptive_feed: true, feed_hold: true });
    // rs274: "Two m codes used from same modal group"; P needs M50-M53.
    assert_eq!(err("M48 M53\n"), format!("{FILE}:1:5: M48 and M53 are in the same modal group"));
    assert_eq!(
        err("M48 P1\n"),
        format!("{FILE}:1:5: P word with no G4, G64, G2, G3, G5, G5.2, G10, G82, G86, G89, M19, M50-M53, M62-M66 or M100-M199 to use it")
    );
}

/// G43.2 H adds tool H's length to the offset in force (H0 adds nothing), against LinuxCNC
/// 2.9's `rs274 -g -t tests/conformance/tool.tbl` for the same program (tool 1 Z 1.25 in,
/// tool 2 Z 2.5 in); the axis-word form adds the words, as LinuxCNC's documentation says.
#[test]
fn additional_tool_length_offset_agrees_with_rs274() {
    let tools =
        [(1, [0.0, 0.0, 31.75, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]), (2, [0.0, 0.0, 63.5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])]
            .into_iter()
            .collect();
    let options = Options { machine_unit_mm: 25.4, tools, ..Options::default() };
    let source =
        "G21\nG43 H1\nG0 X1 Z0\nG43.2 H2\nG0 X2 Z0\nG43.2 H0\nG0 X3 Z0\nG43.2 H1\nG0 X4 Z0\nG49\nG0 X5 Z0\nM2\n";
    let program = parse_str_with(source, FILE, &options).unwrap();
    let rs274 = "\
            8 N..... USE_TOOL_LENGTH_OFFSET(0.0000 0.0000 31.7500, 0.0000 0.0000 0.0000, 0.0000 0.0000 0.0000)\n\
            9 N..... STRAIGHT_TRAVERSE(1.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
           10 N..... USE_TOOL_LENGTH_OFFSET(0.0000 0.0000 95.2500, 0.0000 0.0000 0.0000, 0.0000 0.0000 0.0000)\n\
           11 N..... STRAIGHT_TRAVERSE(2.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
           12 N..... USE_TOOL_LENGTH_OFFSET(0.0000 0.0000 95.2500, 0.0000 0.0000 0.0000, 0.0000 0.0000 0.0000)\n\
           13 N..... STRAIGHT_TRAVERSE(3.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
           14 N..... USE_TOOL_LENGTH_OFFSET(0.0000 0.0000 127.0000, 0.0000 0.0000 0.0000, 0.0000 0.0000 0.0000)\n\
           15 N..... STRAIGHT_TRAVERSE(4.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
           16 N..... USE_TOOL_LENGTH_OFFSET(0.0000 0.0000 0.0000, 0.0000 0.0000 0.0000, 0.0000 0.0000 0.0000)\n\
           17 N..... STRAIGHT_TRAVERSE(5.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
           24 N..... PROGRAM_END()\n";
    let theirs = conformance::rs274_events(rs274).unwrap();
    assert_eq!(conformance::compare(&conformance::events_of(&program), &theirs), None);
    let zs: Vec<f64> = program
        .blocks
        .iter()
        .filter_map(|b| if let BlockKind::Rapid { to } = b.kind { Some(to.z_mm) } else { None })
        .collect();
    assert_eq!(zs, [31.75, 95.25, 95.25, 127.0, 0.0]);
    // The axis-word form (rs274 2.9 refuses it: "Requested tool -1 not found").
    let program = parse_str_with("G43.2 Z1 X0.5\nG0 X0 Z0\nG20 G43.2 Z1\nG0 Z0\nM2\n", FILE, &options).unwrap();
    let BlockKind::Rapid { to } = program.blocks[0].kind else { panic!() };
    assert_eq!((to.x_mm, to.z_mm), (0.5, 1.0));
    let BlockKind::Rapid { to } = program.blocks[1].kind else { panic!() };
    assert_eq!(to.z_mm, 26.4);
    // rs274's refusals, at their words.
    let err_with = |source: &str| parse_str_with(source, FILE, &options).unwrap_err().to_string();
    assert_eq!(err_with("G43.2\n"), format!("{FILE}:1:1: G43.2 with no H word and no axis words"));
    assert_eq!(err_with("G43.2 H1 Z1\n"), format!("{FILE}:1:10: G43.2 with both H and axis words"));
    assert_eq!(err_with("G43.2 H99\n"), format!("{FILE}:1:1: G43.2: tool 99 is not in the tool table"));
}

/// #5400-#5409 are the tool in the spindle and its tool-table entry, in the table's unit,
/// as LinuxCNC 2.9's `Interp::set_tool_parameters` (rs274ngc_pre.cc) copies them from
/// `tool_table[0]`, the spindle's entry: neither G20/G21 nor G43/G43.1 changes them, G10
/// L1 on the loaded tool does. `rs274 -g -t tests/conformance/tool.tbl` (tool 2 Z2.5,
/// tool 4 Z5, tool 5 Z6.25, inches) on the program below with `T4 M6` and `T0 M6` for the
/// two M61 prints `" 0.000000 0.000000"`, `" 2.000000 2.500000"` (after T2 M6, after
/// G43.1 Z7, in G20), `" 4.000000 5.000000"`, `" 4.000000 0.196850"` (G10 L1 P4 Z5 in
/// G21) and `" 5.000000 6.250000"` after T0 M6 (its stand-alone canon's `CHANGE_TOOL(0)`
/// copies index 0 onto itself; LinuxCNC's iocontrol `load_tool(0)` empties the spindle).
///
/// M61 loads the spindle's entry as M6 does: interp_convert.cc `convert_m` case 61 sets
/// `current_pocket` and `toolchange_flag` and calls `CHANGE_TOOL_NUMBER`; LinuxCNC's task
/// sends that to iocontrol as `EMC_TOOL_SET_NUMBER`, whose `load_tool` (ioControl.cc)
/// copies the tool's entry to index 0 (the spindle), then re-synchronises the
/// interpreter, whose `read_inputs` (toolchange_flag set) calls `load_tool_table` ->
/// `set_tool_parameters` before the next line. rs274's stand-alone `CHANGE_TOOL_NUMBER`
/// (saicanon.cc) only records the slot, so there #5400-#5409 keep the last M6's tool
/// (`" 2.000000 2.500000"` after M61 Q4): an artefact of rs274 that the conformance
/// harness re-checks with M61 given as M6.
#[test]
fn tool_parameters_are_the_spindle_tools_table_entry_as_linuxcnc_sets_them() {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../tests/conformance/tool.tbl"))
        .expect("the conformance tool table");
    let tools = Options::read_tool_table(&text, 25.4).unwrap();
    let options = Options { machine_unit_mm: 25.4, tools, ..Options::default() };
    let debug = "(DEBUG, #5400 #5403)\n";
    let source = format!(
        "{debug}T2 M6\n{debug}G43.1 Z7\n{debug}G20 {debug}G21 M61 Q4\n{debug}G10 L1 P4 Z5\n{debug}T5 M6\nM61 Q0\n{debug}M2\n"
    );
    let messages = |source: &str| -> Vec<String> {
        parse_str_with(source, FILE, &options)
            .unwrap()
            .blocks
            .into_iter()
            .filter_map(|b| match b.kind {
                BlockKind::Message { text, .. } => Some(text),
                _ => None,
            })
            .collect()
    };
    let zero = " 0.000000 0.000000";
    let two = " 2.000000 2.500000";
    let after_g10 = " 4.000000 0.196850";
    assert_eq!(messages(&source), [zero, two, two, two, " 4.000000 5.000000", after_g10, zero]);
    // M6 in place of M61: the same, but for T0 M6 in rs274 (above).
    let with_m6 = source.replace("M61 Q", "M6 T");
    assert_eq!(messages(&with_m6), [zero, two, two, two, " 4.000000 5.000000", after_g10, zero]);
    // G43 without H on the line of M61 takes the new tool's length (convert_tool_length_offset:
    // toolchange_flag set, the index M61 chose), as on a later line.
    for g43 in ["M61 Q3 G43\nG0 Z0\nM2\n", "M61 Q3\nG43\nG0 Z0\nM2\n"] {
        let program = parse_str_with(g43, FILE, &options).unwrap();
        let Some(BlockKind::Rapid { to }) =
            program.blocks.iter().map(|b| b.kind.clone()).find(|k| matches!(k, BlockKind::Rapid { .. }))
        else {
            panic!("{g43:?}: no rapid")
        };
        assert!((to.z_mm - 95.25).abs() < 1e-9, "{g43:?}: {}", to.z_mm);
    }
}

/// G10 L10 and L11 set a tool's length from where the machine stands, against LinuxCNC
/// 2.9's `rs274 -g -t tests/conformance/tool.tbl` for the same program (G54 and G92 in
/// force for L10, G59.3 without G92 for L11).
#[test]
fn tool_table_set_from_the_position_agrees_with_rs274() {
    let options = Options { machine_unit_mm: 25.4, ..Options::default() };
    let source = "G21\nG10 L2 P1 X1 Y2 Z3\nG10 L2 P9 Z-4\nG92 X0.5 Z0.25\nG0 X10 Y10 Z10\nG10 L10 P1 Z2 X1\nG43 H1\n\
                  G0 X10 Y10 Z10\nG10 L11 P2 Z1\nG43 H2\nG0 X5 Z5\nG10 L10 P3 Z0\nG43 H3\nG0 Z1\nM2\n";
    let program = parse_str_with(source, FILE, &options).unwrap();
    let rs274 = "\
               2 N..... SET_G5X_OFFSET(1, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
               3 N..... SET_G92_OFFSET(0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
               4 N..... SET_XY_ROTATION(0.0000)\n\
               8 N..... SET_G5X_OFFSET(1, 1.0000, 2.0000, 3.0000, 0.0000, 0.0000, 0.0000)\n\
               9 N..... SET_XY_ROTATION(0.0000)\n\
              11 N..... SET_G92_OFFSET(-1.5000, 0.0000, -3.2500, 0.0000, 0.0000, 0.0000)\n\
              12 N..... STRAIGHT_TRAVERSE(10.0000, 10.0000, 10.0000, 0.0000, 0.0000, 0.0000)\n\
              15 N..... USE_TOOL_LENGTH_OFFSET(9.0000 0.0000 8.0000, 0.0000 0.0000 0.0000, 0.0000 0.0000 0.0000)\n\
              16 N..... STRAIGHT_TRAVERSE(10.0000, 10.0000, 10.0000, 0.0000, 0.0000, 0.0000)\n\
              18 N..... USE_TOOL_LENGTH_OFFSET(0.0000 0.0000 20.7500, 0.0000 0.0000 0.0000, 0.0000 0.0000 0.0000)\n\
              19 N..... STRAIGHT_TRAVERSE(5.0000, 10.0000, 5.0000, 0.0000, 0.0000, 0.0000)\n\
              21 N..... USE_TOOL_LENGTH_OFFSET(0.0000 0.0000 25.7500, 0.0000 0.0000 0.0000, 0.0000 0.0000 0.0000)\n\
              22 N..... STRAIGHT_TRAVERSE(5.0000, 10.0000, 1.0000, 0.0000, 0.0000, 0.0000)\n\
              23 N..... SET_G5X_OFFSET(1, 1.0000, 2.0000, 3.0000, 0.0000, 0.0000, 0.0000)\n\
              24 N..... SET_XY_ROTATION(0.0000)\n\
              29 N..... PROGRAM_END()\n";
    let theirs = conformance::rs274_events(rs274).unwrap();
    assert_eq!(conformance::compare(&conformance::events_of(&program), &theirs), None);
    let ends: Vec<(f64, f64)> = program
        .blocks
        .iter()
        .filter_map(|b| if let BlockKind::Rapid { to } = b.kind { Some((to.x_mm, to.z_mm)) } else { None })
        .collect();
    assert_eq!(ends, [(9.5, 9.75), (18.5, 17.75), (4.5, 25.5), (4.5, 26.5)]);
    assert_eq!(err("G10 L10 P0 Z1\n"), format!("{FILE}:1:9: G10 L10 P0: tool 0 is no tool"));
    assert_eq!(
        err("G10 L2 P1 R30\nG10 L10 P1 X1\n"),
        format!("{FILE}:2:1: unsupported: G10 L10 X/Y under an XY rotation (the tool table is set in the unrotated frame only)")
    );
}

/// G86 (bore, spindle stop at the bottom, traverse out, spindle on again) with G98 and
/// G99, against LinuxCNC 2.9's `rs274 -g` for the same program (spindle M4 at S500).
#[test]
fn boring_cycle_g86_agrees_with_rs274() {
    let source = "G21 G17 F100 S500 M4\nG0 X0 Y0 Z5\nG98 G86 X1 Y1 Z-2 R1 P0.5\nG99 X2\nG80\nM2\n";
    let program = parse_str(source, FILE).unwrap();
    let rs274 = "\
            1 N..... USE_LENGTH_UNITS(CANON_UNITS_MM)\n\
            2 N..... SET_G5X_OFFSET(1, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            3 N..... SET_G92_OFFSET(0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            4 N..... SET_XY_ROTATION(0.0000)\n\
            5 N..... SET_FEED_REFERENCE(CANON_XYZ)\n\
            6 N..... ON_RESET()\n\
            7 N..... SET_FEED_RATE(100.0000)\n\
            8 N..... SET_SPINDLE_SPEED(0, 500.0000)\n\
            9 N..... START_SPINDLE_COUNTERCLOCKWISE(0)\n\
           10 N..... SELECT_PLANE(CANON_PLANE_XY)\n\
           11 N..... USE_LENGTH_UNITS(CANON_UNITS_MM)\n\
           12 N..... STRAIGHT_TRAVERSE(0.0000, 0.0000, 5.0000, 0.0000, 0.0000, 0.0000)\n\
           13 N..... COMMENT(\"interpreter: retract mode set to old_z\")\n\
           14 N..... SET_MOTION_CONTROL_MODE(CANON_EXACT_PATH)\n\
           15 N..... STRAIGHT_TRAVERSE(1.0000, 1.0000, 5.0000, 0.0000, 0.0000, 0.0000)\n\
           16 N..... STRAIGHT_TRAVERSE(1.0000, 1.0000, 1.0000, 0.0000, 0.0000, 0.0000)\n\
           17 N..... STRAIGHT_FEED(1.0000, 1.0000, -2.0000, 0.0000, 0.0000, 0.0000)\n\
           18 N..... DWELL(0.5000)\n\
           19 N..... STOP_SPINDLE_TURNING(0)\n\
           20 N..... STRAIGHT_TRAVERSE(1.0000, 1.0000, 5.0000, 0.0000, 0.0000, 0.0000)\n\
           21 N..... START_SPINDLE_COUNTERCLOCKWISE(0)\n\
           22 N..... SET_MOTION_CONTROL_MODE(CANON_CONTINUOUS, 0.000000)\n\
           23 N..... SET_NAIVECAM_TOLERANCE(0.0000)\n\
           24 N..... COMMENT(\"interpreter: retract mode set to r_plane\")\n\
           25 N..... SET_MOTION_CONTROL_MODE(CANON_EXACT_PATH)\n\
           26 N..... STRAIGHT_TRAVERSE(2.0000, 1.0000, 5.0000, 0.0000, 0.0000, 0.0000)\n\
           27 N..... STRAIGHT_TRAVERSE(2.0000, 1.0000, 1.0000, 0.0000, 0.0000, 0.0000)\n\
           28 N..... STRAIGHT_FEED(2.0000, 1.0000, -2.0000, 0.0000, 0.0000, 0.0000)\n\
           29 N..... DWELL(0.5000)\n\
           30 N..... STOP_SPINDLE_TURNING(0)\n\
           31 N..... STRAIGHT_TRAVERSE(2.0000, 1.0000, 1.0000, 0.0000, 0.0000, 0.0000)\n\
           32 N..... START_SPINDLE_COUNTERCLOCKWISE(0)\n\
           33 N..... SET_MOTION_CONTROL_MODE(CANON_CONTINUOUS, 0.000000)\n\
           34 N..... SET_NAIVECAM_TOLERANCE(0.0000)\n\
           35 N..... COMMENT(\"interpreter: motion mode set to none\")\n\
           36 N..... SET_G5X_OFFSET(1, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
           37 N..... SET_XY_ROTATION(0.0000)\n\
           38 N..... SET_FEED_MODE(0, 0)\n\
           39 N..... SET_FEED_RATE(0.0000)\n\
           40 N..... STOP_SPINDLE_TURNING(0)\n\
           41 N..... SET_SPINDLE_MODE(0 0.0000)\n\
           42 N..... PROGRAM_END()\n\
           43 N..... ON_RESET()\n\
           44 N..... ON_RESET()\n";
    let theirs = conformance::rs274_events(rs274).unwrap();
    assert_eq!(conformance::compare(&conformance::events_of(&program), &theirs), None);
    let spindle: Vec<SpindleRotation> = program
        .blocks
        .iter()
        .filter_map(|b| if let BlockKind::Spindle { rotation, .. } = b.kind { Some(rotation) } else { None })
        .collect();
    use SpindleRotation::*;
    assert_eq!(spindle, [CounterClockwise, Off, CounterClockwise, Off, CounterClockwise]);
    assert_eq!(err("G86 X1 Z-1 R1 P1 F10\n"), format!("{FILE}:1:5: G86 with the spindle not turning (M3 or M4 first)"));
    assert_eq!(err("M3 S100 G86 X1 Z-1 R1 F10\n"), format!("{FILE}:1:13: G86 with no P (dwell)"));
}

/// M62-M65 give the digital output events (rs274 prints SET_MOTION_OUTPUT_BIT /
/// SET_AUX_OUTPUT_BIT and their CLEAR_ forms for them); P is required and 0 to 63.
#[test]
fn digital_outputs_are_events() {
    let program = parse_str("M62 P0\nM63 P0\nM64 P7\nM65 P63\nM2\n", FILE).unwrap();
    let outputs: Vec<(u32, bool)> = program
        .blocks
        .iter()
        .filter_map(|b| if let BlockKind::DigitalOutput { index, on } = b.kind { Some((index, on)) } else { None })
        .collect();
    assert_eq!(outputs, [(0, true), (0, false), (7, true), (63, false)]);
    assert_eq!(err("M64\n"), format!("{FILE}:1:1: M64 with no P (the output)"));
    assert_eq!(err("M64 P64\n"), format!("{FILE}:1:5: digital output P must be an integer 0 to 63"));
    assert_eq!(err("M64 P1 M65 P2\n"), format!("{FILE}:1:8: M64 and M65 are in the same modal group"));
}

/// G5 as LinuxCNC's `convert_spline`: I J the first control point from the start, P Q
/// the second from the end, an order-4 NURBS; without I J the last G5's P Q negated (0 0
/// before any G5), so a chain stays tangent; not modal; G17 only; the errors at their
/// words.
#[test]
fn cubic_spline_g5_as_linuxcnc() {
    let source = "G21 G17 F100\nG0 X1 Y1\nG5 X10 Y0 I2 J5 P-2 Q5\nG5 X20 Y0 P-2 Q-5\nG91 G5 X1 Y1 I1 J0 P0 Q1\nM2\n";
    /// Control points (x, y, w), order, knots, end.
    type Spline = (Vec<(f64, f64, f64)>, u32, Vec<f64>, Point);
    let splines: Vec<Spline> = parse(source)
        .into_iter()
        .filter_map(|k| match k {
            BlockKind::Nurbs { to, control_points, order, knots, .. } => {
                Some((control_points.iter().map(|c| (c.x_mm, c.y_mm, c.weight)).collect(), order, knots, to))
            }
            _ => None,
        })
        .collect();
    let knots = vec![0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0];
    assert_eq!(
        splines,
        vec![
            (
                vec![(1.0, 1.0, 1.0), (3.0, 6.0, 1.0), (8.0, 5.0, 1.0), (10.0, 0.0, 1.0)],
                4,
                knots.clone(),
                p(10.0, 0.0, 0.0, 0.0)
            ),
            (
                vec![(10.0, 0.0, 1.0), (12.0, -5.0, 1.0), (18.0, -5.0, 1.0), (20.0, 0.0, 1.0)],
                4,
                knots.clone(),
                p(20.0, 0.0, 0.0, 0.0)
            ),
            (
                vec![(20.0, 0.0, 1.0), (21.0, 0.0, 1.0), (21.0, 2.0, 1.0), (21.0, 1.0, 1.0)],
                4,
                knots,
                p(21.0, 1.0, 0.0, 0.0)
            ),
        ]
    );
    // The first G5 without I J: its first control point is its start (rs274's 0 0).
    let (points, ..) = nurbs("F10 G5 X4 Y0 P-1 Q1\n");
    assert_eq!(points[1], (0.0, 0.0, 1.0));
    assert_eq!(err("F10 G5 X1 Y1 I1 P1 Q1\n"), format!("{FILE}:1:14: G5 needs both I and J, or neither"));
    assert_eq!(err("F10 G5 X1 Y1 I1 J1 P1\n"), format!("{FILE}:1:5: G5 needs both P and Q"));
    assert_eq!(err("F10 G5 I1 J1 P1 Q1\n"), format!("{FILE}:1:5: G5 with no axis words"));
    assert_eq!(err("F10 G5 X1 Y1 Z1 I1 J1 P1 Q1\n"), format!("{FILE}:1:14: axis Z in a G5 spline: only X and Y move"));
    assert_eq!(err("F10 G18 G5 X1 I1 J1 P1 Q1\n"), format!("{FILE}:1:12: G5 is for the G17 (XY) plane"));
    assert_eq!(
        err("F10 G5 X1 Y1 I1 J1 P1 Q1\nX2 Y2\n"),
        format!("{FILE}:2:1: axis word with no motion mode (G0, G1, G2, G3 or a cycle) to use it")
    );
    assert_eq!(err("G5 X1 Y1 I1 J1 P1 Q1\n"), format!("{FILE}:1:1: G5 with no feed rate"));
}

/// G7: X words are diameters (moves, G92, G10 L2, G28), I and R radii; G8 back to radius
/// mode: checked against rs274's output.
#[test]
fn lathe_diameter_mode_agrees_with_rs274() {
    let source =
        "G18 G7 F10\nG0 X10 Z0\nG3 X14 Z-2 I0 K-2\nG91 G1 X2\nG90 G92 X20\nG0 X10\nG92.1\nG10 L2 P1 X4\nG0 X10\n\
                  G10 L2 P1 X0\nG28 X6\nG8 G0 X10\nM2\n";
    let program = parse_str(source, FILE).unwrap();
    let rs274 = "\
            1 N..... USE_LENGTH_UNITS(CANON_UNITS_MM)\n\
            2 N..... SET_G5X_OFFSET(1, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            3 N..... SET_G92_OFFSET(0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            4 N..... SET_XY_ROTATION(0.0000)\n\
            5 N..... SET_FEED_REFERENCE(CANON_XYZ)\n\
            6 N..... ON_RESET()\n\
            7 N..... SET_FEED_RATE(10.0000)\n\
            8 N..... SELECT_PLANE(CANON_PLANE_XZ)\n\
            10 N..... STRAIGHT_TRAVERSE(5.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            11 N..... ARC_FEED(-2.0000, 7.0000, -2.0000, 5.0000, 1, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            13 N..... STRAIGHT_FEED(8.0000, 0.0000, -2.0000, 0.0000, 0.0000, 0.0000)\n\
            15 N..... SET_G92_OFFSET(-2.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            16 N..... STRAIGHT_TRAVERSE(5.0000, 0.0000, -2.0000, 0.0000, 0.0000, 0.0000)\n\
            17 N..... SET_G92_OFFSET(0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            18 N..... SET_G5X_OFFSET(1, 2.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            19 N..... SET_XY_ROTATION(0.0000)\n\
            20 N..... STRAIGHT_TRAVERSE(5.0000, 0.0000, -2.0000, 0.0000, 0.0000, 0.0000)\n\
            21 N..... SET_G5X_OFFSET(1, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            22 N..... SET_XY_ROTATION(0.0000)\n\
            23 N..... STRAIGHT_TRAVERSE(3.0000, 0.0000, -2.0000, 0.0000, 0.0000, 0.0000)\n\
            24 N..... STRAIGHT_TRAVERSE(0.0000, 0.0000, -2.0000, 0.0000, 0.0000, 0.0000)\n\
            26 N..... STRAIGHT_TRAVERSE(10.0000, 0.0000, -2.0000, 0.0000, 0.0000, 0.0000)\n\
            27 N..... SET_G5X_OFFSET(1, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            28 N..... SET_XY_ROTATION(0.0000)\n\
            29 N..... SELECT_PLANE(CANON_PLANE_XY)\n\
            30 N..... SET_FEED_MODE(0, 0)\n\
            31 N..... SET_FEED_RATE(0.0000)\n\
            32 N..... STOP_SPINDLE_TURNING(0)\n\
            33 N..... SET_SPINDLE_MODE(0 0.0000)\n\
            34 N..... PROGRAM_END()\n\
            35 N..... ON_RESET()\n\
            36 N..... ON_RESET()\n";
    let theirs = conformance::rs274_events(rs274).unwrap();
    assert_eq!(conformance::compare(&conformance::events_of(&program), &theirs), None);
    let flags = |s: &str| {
        let program = parse_str(
            &format!("{s}\n#1 = #<_lathe_diameter_mode>\n#2 = #<_lathe_radius_mode>\nG0 X#1 Y#2\nM2\n"),
            FILE,
        )
        .unwrap();
        program.blocks.iter().rev().find_map(|b| {
            if let BlockKind::Rapid { to } = b.kind {
                Some((to.x_mm, to.y_mm))
            } else {
                None
            }
        })
    };
    // X#1 is read in diameter mode as well: 1 / 2.
    assert_eq!(flags("G7"), Some((0.5, 0.0)));
    assert_eq!(flags("G8"), Some((0.0, 1.0)));
}

/// G41.1/G42.1 carry the radius (half of D, in program units; a negative D the other
/// side); L is refused outside G18, D is required, as rs274 does.
#[test]
fn dynamic_compensation_carries_the_radius() {
    // The compensation blocks of a program.
    let radius_blocks = |source: &str| -> Vec<BlockKind> {
        parse(source).into_iter().filter(|k| matches!(k, BlockKind::CutterCompRadius { .. })).collect()
    };
    let comps = radius_blocks("G20 G41.1 D0.5\nG40\nG42.1 D-1\nG40\nG21 G42.1 D3\nG40\n");
    assert_eq!(
        comps,
        vec![
            BlockKind::CutterCompRadius { side: CompSide::Left, radius_mm: 6.35, plane: Plane::Xy, orientation: 0 },
            BlockKind::CutterCompRadius { side: CompSide::Left, radius_mm: 12.7, plane: Plane::Xy, orientation: 0 },
            BlockKind::CutterCompRadius { side: CompSide::Right, radius_mm: 1.5, plane: Plane::Xy, orientation: 0 },
        ]
    );
    assert_eq!(err("G41.1 D1 L3\n"), format!("{FILE}:1:10: G41.1 with L word, but plane is not G18"));
    assert_eq!(err("G42.1 G1 X1 F1\n"), format!("{FILE}:1:1: G42.1 with no D word"));
    assert_eq!(err("G41.1 D1\nG42.1 D1\n"), format!("{FILE}:2:1: cutter compensation is already on (G40 first)"));
    assert_eq!(err("G19\nG41.1 D1\n"), format!("{FILE}:2:1: Cutter radius compensation allowed only in XY, XZ planes"));
    // L, a lathe tool's orientation, in G18 (given in the block or before it).
    let comps = radius_blocks("G18 G42.1 D0.3 L2\nG40\nG21 G41.1 D-2 L9\nG40\nG17\nG18 G41.1 D1 L0\nG40\n");
    assert_eq!(
        comps,
        vec![
            BlockKind::CutterCompRadius { side: CompSide::Right, radius_mm: 0.15, plane: Plane::Zx, orientation: 2 },
            BlockKind::CutterCompRadius { side: CompSide::Right, radius_mm: 1.0, plane: Plane::Zx, orientation: 9 },
            BlockKind::CutterCompRadius { side: CompSide::Left, radius_mm: 0.5, plane: Plane::Zx, orientation: 0 },
        ]
    );
    assert_eq!(err("G18\nG17 G41.1 D1 L3\n"), format!("{FILE}:2:14: G41.1 with L word, but plane is not G18"));
    assert_eq!(
        err("G18 G41.1 D1 L2.5\n"),
        format!("{FILE}:1:14: L (the lathe tool's orientation) must be a non-negative integer")
    );
}

/// M19 with R or P is an orientation event (the spindle stopped after it), a bare M19
/// sends nothing; M60 stops as M0: checked against rs274's output (ORIENT_SPINDLE,
/// PALLET_SHUTTLE and PROGRAM_STOP).
#[test]
fn spindle_orientation_and_pallet_stop_agree_with_rs274() {
    let source = "S100 M3\nM19 R30 P1 Q2\nG1 X1 F10\nS200 M4\nM19\nG1 X2\nM60\nM2\n";
    let program = parse_str(source, FILE).unwrap();
    let rs274 = "\
            1 N..... USE_LENGTH_UNITS(CANON_UNITS_MM)\n\
            2 N..... SET_G5X_OFFSET(1, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            3 N..... SET_G92_OFFSET(0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            4 N..... SET_XY_ROTATION(0.0000)\n\
            5 N..... SET_FEED_REFERENCE(CANON_XYZ)\n\
            6 N..... ON_RESET()\n\
            7 N..... SET_SPINDLE_SPEED(0, 100.0000)\n\
            8 N..... START_SPINDLE_CLOCKWISE(0)\n\
            9 N..... ORIENT_SPINDLE(0, 30.0000, 1)\n\
            10 N..... SPINDLE.0.WAIT_ORIENT_COMPLETE(2.0000)\n\
            11 N..... SET_FEED_RATE(10.0000)\n\
            12 N..... STRAIGHT_FEED(1.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            13 N..... SET_SPINDLE_SPEED(0, 200.0000)\n\
            14 N..... START_SPINDLE_COUNTERCLOCKWISE(0)\n\
            15 N..... STRAIGHT_FEED(2.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            16 N..... PALLET_SHUTTLE()\n\
            17 N..... PROGRAM_STOP()\n\
            18 N..... SET_G5X_OFFSET(1, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            19 N..... SET_XY_ROTATION(0.0000)\n\
            20 N..... SET_FEED_MODE(0, 0)\n\
            21 N..... SET_FEED_RATE(0.0000)\n\
            22 N..... STOP_SPINDLE_TURNING(0)\n\
            23 N..... SET_SPINDLE_MODE(0 0.0000)\n\
            24 N..... PROGRAM_END()\n\
            25 N..... ON_RESET()\n\
            26 N..... ON_RESET()\n";
    let theirs = conformance::rs274_events(rs274).unwrap();
    assert_eq!(conformance::compare(&conformance::events_of(&program), &theirs), None);
    let kinds: Vec<&BlockKind> = program.blocks.iter().map(|b| &b.kind).collect();
    assert!(kinds.contains(&&BlockKind::SpindleOrient { angle_deg: 30.0, direction: 1, timeout_s: Some(2.0) }));
    assert_eq!(kinds.iter().filter(|k| matches!(k, BlockKind::SpindleOrient { .. })).count(), 1);
    assert!(kinds.contains(&&BlockKind::Pause));
    assert_eq!(err("M19 R400\n"), format!("{FILE}:1:5: R value must be within 0..360 with M19"));
    assert_eq!(err("M19 P3\n"), format!("{FILE}:1:5: P value must be 0, 1 or 2 with M19"));
    assert_eq!(err("M19 R1 Q0\n"), format!("{FILE}:1:8: Q value must be positive with M19"));
    assert_eq!(err("M3 M19\n"), format!("{FILE}:1:4: M3 and M19 are in the same modal group"));
}

/// G87 (back boring) as rs274 runs it, in G98 and G99, G20 and G91, with M3 and M4; the
/// spindle must turn, I J K are required (and sticky).
#[test]
fn back_boring_g87_agrees_with_rs274() {
    let source = "G20 F10 S100 M3 G0 Z5\nG98 G87 X1 Y2 Z-3 R1 I0.5 J0.2 K-1\nG99 X3\nG80\nM4\nG91 G87 X1 Y0 Z-3 R-1 I-0.5 J0 K1\nM2\n";
    let program = parse_str(source, FILE).unwrap();
    let rs274 = "\
            1 N..... USE_LENGTH_UNITS(CANON_UNITS_MM)\n\
            2 N..... SET_G5X_OFFSET(1, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            3 N..... SET_G92_OFFSET(0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            4 N..... SET_XY_ROTATION(0.0000)\n\
            5 N..... SET_FEED_REFERENCE(CANON_XYZ)\n\
            6 N..... ON_RESET()\n\
            7 N..... SET_FEED_RATE(10.0000)\n\
            8 N..... SET_SPINDLE_SPEED(0, 100.0000)\n\
            9 N..... START_SPINDLE_CLOCKWISE(0)\n\
            10 N..... USE_LENGTH_UNITS(CANON_UNITS_INCHES)\n\
            11 N..... STRAIGHT_TRAVERSE(0.0000, 0.0000, 5.0000, 0.0000, 0.0000, 0.0000)\n\
            13 N..... SET_MOTION_CONTROL_MODE(CANON_EXACT_PATH)\n\
            14 N..... STRAIGHT_TRAVERSE(1.0000, 2.0000, 5.0000, 0.0000, 0.0000, 0.0000)\n\
            15 N..... STRAIGHT_TRAVERSE(1.0000, 2.0000, 1.0000, 0.0000, 0.0000, 0.0000)\n\
            16 N..... STRAIGHT_TRAVERSE(1.5000, 2.2000, 1.0000, 0.0000, 0.0000, 0.0000)\n\
            17 N..... STOP_SPINDLE_TURNING(0)\n\
            18 N..... ORIENT_SPINDLE(0, 0.0000, 2)\n\
            19 N..... STRAIGHT_TRAVERSE(1.5000, 2.2000, -3.0000, 0.0000, 0.0000, 0.0000)\n\
            20 N..... STRAIGHT_TRAVERSE(1.0000, 2.0000, -3.0000, 0.0000, 0.0000, 0.0000)\n\
            21 N..... START_SPINDLE_CLOCKWISE(0)\n\
            22 N..... STRAIGHT_FEED(1.0000, 2.0000, -1.0000, 0.0000, 0.0000, 0.0000)\n\
            23 N..... STRAIGHT_FEED(1.0000, 2.0000, -3.0000, 0.0000, 0.0000, 0.0000)\n\
            24 N..... STOP_SPINDLE_TURNING(0)\n\
            25 N..... ORIENT_SPINDLE(0, 0.0000, 2)\n\
            26 N..... STRAIGHT_TRAVERSE(1.5000, 2.2000, -3.0000, 0.0000, 0.0000, 0.0000)\n\
            27 N..... STRAIGHT_TRAVERSE(1.5000, 2.2000, 5.0000, 0.0000, 0.0000, 0.0000)\n\
            28 N..... STRAIGHT_TRAVERSE(1.0000, 2.0000, 5.0000, 0.0000, 0.0000, 0.0000)\n\
            29 N..... START_SPINDLE_CLOCKWISE(0)\n\
            30 N..... SET_MOTION_CONTROL_MODE(CANON_CONTINUOUS, 0.000000)\n\
            31 N..... SET_NAIVECAM_TOLERANCE(0.0000)\n\
            33 N..... SET_MOTION_CONTROL_MODE(CANON_EXACT_PATH)\n\
            34 N..... STRAIGHT_TRAVERSE(3.0000, 2.0000, 5.0000, 0.0000, 0.0000, 0.0000)\n\
            35 N..... STRAIGHT_TRAVERSE(3.0000, 2.0000, 1.0000, 0.0000, 0.0000, 0.0000)\n\
            36 N..... STRAIGHT_TRAVERSE(3.5000, 2.2000, 1.0000, 0.0000, 0.0000, 0.0000)\n\
            37 N..... STOP_SPINDLE_TURNING(0)\n\
            38 N..... ORIENT_SPINDLE(0, 0.0000, 2)\n\
            39 N..... STRAIGHT_TRAVERSE(3.5000, 2.2000, -3.0000, 0.0000, 0.0000, 0.0000)\n\
            40 N..... STRAIGHT_TRAVERSE(3.0000, 2.0000, -3.0000, 0.0000, 0.0000, 0.0000)\n\
            41 N..... START_SPINDLE_CLOCKWISE(0)\n\
            42 N..... STRAIGHT_FEED(3.0000, 2.0000, -1.0000, 0.0000, 0.0000, 0.0000)\n\
            43 N..... STRAIGHT_FEED(3.0000, 2.0000, -3.0000, 0.0000, 0.0000, 0.0000)\n\
            44 N..... STOP_SPINDLE_TURNING(0)\n\
            45 N..... ORIENT_SPINDLE(0, 0.0000, 2)\n\
            46 N..... STRAIGHT_TRAVERSE(3.5000, 2.2000, -3.0000, 0.0000, 0.0000, 0.0000)\n\
            47 N..... STRAIGHT_TRAVERSE(3.5000, 2.2000, 1.0000, 0.0000, 0.0000, 0.0000)\n\
            48 N..... STRAIGHT_TRAVERSE(3.0000, 2.0000, 1.0000, 0.0000, 0.0000, 0.0000)\n\
            49 N..... START_SPINDLE_CLOCKWISE(0)\n\
            50 N..... SET_MOTION_CONTROL_MODE(CANON_CONTINUOUS, 0.000000)\n\
            51 N..... SET_NAIVECAM_TOLERANCE(0.0000)\n\
            53 N..... START_SPINDLE_COUNTERCLOCKWISE(0)\n\
            55 N..... SET_MOTION_CONTROL_MODE(CANON_EXACT_PATH)\n\
            56 N..... STRAIGHT_TRAVERSE(4.0000, 2.0000, 1.0000, 0.0000, 0.0000, 0.0000)\n\
            57 N..... STRAIGHT_TRAVERSE(4.0000, 2.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            58 N..... STRAIGHT_TRAVERSE(3.5000, 2.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            59 N..... STOP_SPINDLE_TURNING(0)\n\
            60 N..... ORIENT_SPINDLE(0, 0.0000, 3)\n\
            61 N..... STRAIGHT_TRAVERSE(3.5000, 2.0000, -3.0000, 0.0000, 0.0000, 0.0000)\n\
            62 N..... STRAIGHT_TRAVERSE(4.0000, 2.0000, -3.0000, 0.0000, 0.0000, 0.0000)\n\
            63 N..... START_SPINDLE_COUNTERCLOCKWISE(0)\n\
            64 N..... STRAIGHT_FEED(4.0000, 2.0000, -2.0000, 0.0000, 0.0000, 0.0000)\n\
            65 N..... STRAIGHT_FEED(4.0000, 2.0000, -3.0000, 0.0000, 0.0000, 0.0000)\n\
            66 N..... STOP_SPINDLE_TURNING(0)\n\
            67 N..... ORIENT_SPINDLE(0, 0.0000, 3)\n\
            68 N..... STRAIGHT_TRAVERSE(3.5000, 2.0000, -3.0000, 0.0000, 0.0000, 0.0000)\n\
            69 N..... STRAIGHT_TRAVERSE(3.5000, 2.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            70 N..... STRAIGHT_TRAVERSE(4.0000, 2.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            71 N..... START_SPINDLE_COUNTERCLOCKWISE(0)\n\
            72 N..... SET_MOTION_CONTROL_MODE(CANON_CONTINUOUS, 0.000000)\n\
            73 N..... SET_NAIVECAM_TOLERANCE(0.0000)\n\
            74 N..... SET_G5X_OFFSET(1, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
            75 N..... SET_XY_ROTATION(0.0000)\n\
            76 N..... SET_FEED_MODE(0, 0)\n\
            77 N..... SET_FEED_RATE(0.0000)\n\
            78 N..... STOP_SPINDLE_TURNING(0)\n\
            79 N..... SET_SPINDLE_MODE(0 0.0000)\n\
            80 N..... PROGRAM_END()\n\
            81 N..... ON_RESET()\n\
            82 N..... ON_RESET()\n";
    let theirs = conformance::rs274_events(rs274).unwrap();
    assert_eq!(conformance::compare(&conformance::events_of(&program), &theirs), None);
    assert_eq!(
        err("F10 G87 X1 Z-1 R1 I1 J0 K0\n"),
        format!("{FILE}:1:9: G87 with the spindle not turning (M3 or M4 first)")
    );
    assert_eq!(err("M3 F10 G87 X1 Z-1 R1 I1 K0\n"), format!("{FILE}:1:12: G87 with no J (back boring)"));
}

/// `skeleton.ngc`'s `T1 M6 G43 H1` on one line, then a move without Z: the machine's Z
/// stays where it is (the tool tip is then at program Z minus the tool's length), as on
/// separate lines, where rs274 agrees (`T1 M6`, `G43 H1`, `G0 X1`: STRAIGHT_TRAVERSE(1,
/// 0, -1.25) with the offset 1.25, machine Z 0). On one line rs274 prints Z 0, machine
/// Z 1.25 inch: after M6 its interpreter reads the position back from the canonical
/// layer, and rs274's stand-alone one (saicanon's `GET_EXTERNAL_POSITION_Z`, the last Z
/// it printed) leaves out the length offset applied in that block, which LinuxCNC's
/// task (emccanon) takes off. finestep keeps the machine's position, as LinuxCNC does.
#[test]
fn a_tool_length_offset_with_the_tool_change_leaves_the_machine_where_it_is() {
    let tools = [(1, [0.0, 0.0, 31.75, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])].into_iter().collect();
    let options = Options { machine_unit_mm: 25.4, tools, ..Options::default() };
    for source in ["G20\nT1 M6 G43 H1\nG0 X1\nM2\n", "G20\nT1 M6\nG43 H1\nG0 X1\nM2\n"] {
        let program = parse_str_with(source, FILE, &options).unwrap();
        let rapids: Vec<Point> = program
            .blocks
            .iter()
            .filter_map(|b| if let BlockKind::Rapid { to } = b.kind { Some(to) } else { None })
            .collect();
        assert_eq!(rapids, [p(25.4, 0.0, 0.0, 0.0)], "{source:?}");
    }
}

/// G10 L20 with R: rs274 2.9 refuses it ("R not allowed in G10 L20"), so does finestep.
#[test]
fn g10_l20_takes_no_rotation_as_rs274() {
    assert_eq!(err("G0 X3 Y4\nG10 L20 P1 X0 R10\n"), format!("{FILE}:2:15: R not allowed in G10 L20"));
}

#[test]
fn the_axes_b_c_u_v_w_move_with_their_units_offsets_and_parameters() {
    // B and C are rotary (degrees whatever G20 says), U V W linear (scaled by G20), as
    // LinuxCNC's X Y Z A B C U V W; G92, G10 L2 and #5420-#5428 / #<_u> cover them all.
    let source = "G20 G0 B30 C-45 U1 V2 W3\nG92 U0 B0\nG10 L2 P1 V1\nG0 U1 B10 V[#<_v> + #5427]\n\
                  G91 G0 W-0.5 C5\nM2\n";
    let program = parse_str(source, "t.ngc").unwrap();
    let ends: Vec<[f64; 9]> = program
        .blocks
        .iter()
        .filter_map(|b| match b.kind {
            BlockKind::Rapid { to } => Some(to.to_array()),
            _ => None,
        })
        .collect();
    let inch = 25.4;
    assert_eq!(ends[0], [0.0, 0.0, 0.0, 0.0, 30.0, -45.0, inch, 2.0 * inch, 3.0 * inch]);
    // G92 U0 B0 there: U1 is 2 inches in the machine frame, B10 is 40 degrees; V: G54's
    // V offset of 1 inch, the program's V (2 - 1 = 1 inch) read twice, plus the offset.
    let second = ends[1];
    assert!((second[6] - 2.0 * inch).abs() < 1e-9, "{second:?}");
    assert!((second[4] - 40.0).abs() < 1e-9, "{second:?}");
    assert!((second[7] - 3.0 * inch).abs() < 1e-9, "{second:?}");
    let third = ends[2];
    assert!((third[8] - 2.5 * inch).abs() < 1e-9 && (third[5] + 40.0).abs() < 1e-9, "{third:?}");
}

/// G38.2-G38.5 as rs274 runs them (its output for this program, `rs274 -g`: the probe
/// moves' ends and the position after each, 0.254 mm short of the end towards the start
/// in X Y Z, #5061-#5066 the end, #5070 0; `probe.ngc` in tests/conformance holds more).
#[test]
fn straight_probe_as_rs274() {
    // rs274: STRAIGHT_PROBE(1, 2, -10), then STRAIGHT_FEED(5, 2, -9.746) and, after
    // G38.3 X10 Y5 from (5, 2), #<_x> 9.782197.
    let source =
        "G0 X1 Y2 Z3\nG38.2 Z-10 F100\n#1 = #5063\n#2 = #5070\nG1 X5\nG38.3 X10 Y5 F50\nG1 X[#<_x>] Y[#1] Z[#2]\nM2\n";
    let kinds = parse(source);
    let probes: Vec<(Point, f64, bool, bool, Point)> = kinds
        .iter()
        .filter_map(|k| match *k {
            BlockKind::Probe { to, feed_mm_per_min, on_contact, must_change, resume } => {
                Some((to, feed_mm_per_min, on_contact, must_change, resume))
            }
            _ => None,
        })
        .collect();
    assert_eq!(probes.len(), 2);
    assert_eq!((probes[0].0, probes[0].1, probes[0].2, probes[0].3), (p(1.0, 2.0, -10.0, 0.0), 100.0, true, true));
    assert!(close(probes[0].4, p(1.0, 2.0, -9.746, 0.0)));
    assert_eq!((probes[1].1, probes[1].2, probes[1].3), (50.0, true, false));
    let back = 0.254 / 34f64.sqrt();
    assert!(close(probes[1].4, p(10.0 - 5.0 * back, 5.0 - 3.0 * back, -9.746, 0.0)));
    let feeds: Vec<Point> =
        kinds.iter().filter_map(|k| if let BlockKind::Linear { to, .. } = *k { Some(to) } else { None }).collect();
    assert!(close(feeds[0], p(5.0, 2.0, -9.746, 0.0)));
    // #5063 read the end, #5070 0 (rs274's canon reports no trip).
    assert!(close(feeds[1], p(10.0 - 5.0 * back, -10.0, 0.0, 0.0)));
    // G38.4/G38.5 stop on losing contact; inches: 0.01 inch back.
    let kinds = parse("G20 F10\nG38.4 X1\nG38.5 Z-1\nG1 Y1\nM2\n");
    let resumes: Vec<(bool, bool, Point)> = kinds
        .iter()
        .filter_map(|k| match *k {
            BlockKind::Probe { on_contact, must_change, resume, .. } => Some((on_contact, must_change, resume)),
            _ => None,
        })
        .collect();
    assert_eq!((resumes[0].0, resumes[0].1, resumes[1].0, resumes[1].1), (false, true, false, false));
    assert!(close(resumes[0].2, p(25.4 - 0.254, 0.0, 0.0, 0.0)));
    assert!(close(resumes[1].2, p(25.4 - 0.254, 0.0, -25.4 + 0.254, 0.0)));
    // rs274's refusals, at their words.
    assert_eq!(err("F10\nG38.2 Z0\n"), format!("{FILE}:2:1: G38.2 to the point where the probe is: nothing to probe"));
    assert_eq!(err("G38.2 Z-1\n"), format!("{FILE}:1:1: G38.2 with no feed rate"));
    assert_eq!(
        err("F10 G41\nG38.3 Z-1\n"),
        format!("{FILE}:2:1: G38.3 with cutter radius compensation on (G40 first)")
    );
    assert_eq!(
        err("G93 G38.2 Z-1 F10\n"),
        format!("{FILE}:1:5: G38.2 in inverse-time feed (G93): a probe move takes units per minute (G94)")
    );
    assert_eq!(err("F10 G38.2\n"), format!("{FILE}:1:5: G38.2 with no axis words"));
    assert_eq!(
        err("F10 G38.2 Z-1 R2\n"),
        format!("{FILE}:1:15: R word with no G2, G3, canned cycle, G10 or M19 to use it")
    );
    // G38.3 to where it stands is accepted (it reports in #5070), as in rs274.
    assert!(parse("F10\nG38.3 Z0\nM2\n").iter().any(|k| matches!(k, BlockKind::Probe { .. })));
}

/// M66 (wait on an input: #5399 as rs274 leaves it), M67/M68 (analog outputs), and
/// their refusals as rs274 makes them.
#[test]
fn inputs_and_analog_outputs_are_events() {
    let source = "#5399 = 3\nM66 P1 L1 Q5\nG0 X#5399\nM66 E2\nM67 E0 Q2.5\nM68 E63 Q-1.25\nM2\n";
    let kinds = parse(source);
    let io: Vec<&BlockKind> =
        kinds.iter().filter(|k| matches!(k, BlockKind::WaitInput { .. } | BlockKind::AnalogOutput { .. })).collect();
    assert_eq!(
        io,
        [
            &BlockKind::WaitInput { input: Input::Digital(1), mode: WaitMode::Rise, timeout_s: 5.0 },
            &BlockKind::WaitInput { input: Input::Analog(2), mode: WaitMode::Immediate, timeout_s: 0.0 },
            &BlockKind::AnalogOutput { index: 0, value: 2.5, synchronised: true },
            &BlockKind::AnalogOutput { index: 63, value: -1.25, synchronised: false },
        ]
    );
    // A digital read leaves #5399 as 0 or 1 (rs274's canon reads no input).
    assert!(kinds.contains(&BlockKind::Rapid { to: p(1.0, 0.0, 0.0, 0.0) }));
    let cases = [
        ("M66 P1 E1\n", "1:8: M66 with both P (a digital input) and E (an analog one)"),
        ("M66\n", "1:1: M66 with no P (a digital input) or E (an analog one)"),
        ("M66 L1 P1\n", "1:1: M66 waiting (L1-L4) needs a timeout Q above 0 seconds"),
        ("M66 P1 L3 Q0\n", "1:11: M66 waiting (L1-L4) needs a timeout Q above 0 seconds"),
        ("M66 E1 L3 Q2\n", "1:8: M66 reads an analog input (E) at once only: L0"),
        ("M66 P1 L5 Q1\n", "1:8: M66 L must be 0 (read at once), 1 (rise), 2 (fall), 3 (high) or 4 (low)"),
        ("M66 P64\n", "1:5: P word of M66 must be an integer 0 to 63"),
        ("M67 Q1\n", "1:1: M67 with no E (the analog output)"),
        ("M68 E1\n", "1:1: M68 with no Q (the value)"),
        ("M68 E-1 Q1\n", "1:5: E word of M68 must be an integer 0 to 63"),
        (
            "M67 E1 Q1 P2\n",
            "1:11: P word with no G4, G64, G2, G3, G5, G5.2, G10, G82, G86, G89, M19, M50-M53, M62-M66 or M100-M199 to use it",
        ),
        ("G1 X1 E5 F10\n", "1:7: E word with no M66, M67 or M68 to use it"),
        ("F10 G41\nM68 E1 Q1\n", "2:1: M68 with cutter radius compensation on (G40 first)"),
        ("M66 P1 M62 P2\n", "1:8: M66 and M62 are in the same modal group"),
    ];
    for (source, message) in cases {
        assert_eq!(err(source), format!("{FILE}:{message}"), "{source:?}");
    }
}

/// A lathe profile (O1) of `body` for the cycle line `cycle`, in G18.
fn lathe(body: &str, cycle: &str) -> String {
    format!("G18 F100\nO1 SUB\n{body}\nO1 ENDSUB\n{cycle}\nM2\n")
}

#[test]
fn lathe_cycle_errors_are_rs274s_at_their_word() {
    let profile = "G1 X2 Z0\nG1 X4 Z-5";
    assert_eq!(err(&lathe(profile, "G70 X8 Z2")), "t.ngc:6:1: G70 requires a Q word (the profile's subroutine)");
    assert_eq!(
        err(&lathe(profile, "G41 D1\nG71 Q1 X8 Z2")),
        "t.ngc:7:1: G71 cannot be used with cutter compensation enabled"
    );
    assert_eq!(err(&lathe(profile, "G17 G72.1 Q1 X8 Z2")), "t.ngc:6:5: G72.1 can only be used in XZ plane (G18)");
    assert_eq!(err(&lathe(profile, "G71.2 Q1 X8 Z2 I0")), "t.ngc:6:16: G71.2: I must be greater than zero");
    assert_eq!(err(&lathe("G1 X2 Z0\nG1 X4 Z-5\nG1 X3 Z-3", "G70 Q1 X8 Z2")), "t.ngc:7:1: G7X error: Not monotonic");
    // A profile of moves shorter than the tolerance alone (the fuzz's lathe cycles at 10^6
    // cases found it: an index into no segments; rs274 2.9 ends in a segmentation fault).
    assert_eq!(
        err(&lathe("o9 repeat [2]\nG1 W0.001\no9 endrepeat", "G70 Q1 X0 Z10.964 P1")),
        "t.ngc:7:1: G7X error: the profile has no move longer than the tolerance"
    );
    assert_eq!(
        err(&lathe(profile, "G70 Q2 X8 Z2")),
        "t.ngc:6:5: subroutine o2 is not defined here nor in a file of the subroutine path"
    );
    assert_eq!(
        err(&lathe("G2 X2 Z0 R3 I1", "G70 Q1 X8 Z2")),
        "t.ngc:3:10: G7X error: both R and I or K flag used for arc"
    );
    assert_eq!(err(&lathe("G2 X2 Z0", "G70 Q1 X8 Z2")), "t.ngc:3:1: G7X error: either I or K must be present for arc");
    assert_eq!(
        err(&lathe("G1 X2 Z0 A1 C1", "G70 Q1 X8 Z2")),
        "t.ngc:3:13: G7X error: Both A and C parameters on a corner"
    );
    assert_eq!(err(&lathe("G1 X2 U1", "G70 Q1 X8 Z2")), "t.ngc:3:4: G7x error: Cannot use U and X in the same block");
    assert_eq!(
        err(&format!("G91\n{}", lathe("G1 W-1", "G70 Q1 X8 Z2"))),
        "t.ngc:4:4: G7x error: Cannot use W in incremental mode (G91)"
    );
}

#[test]
fn a_lathe_profile_is_read_not_run() {
    // The profile's lines make no moves and run no other words (M3, F, the M2 too):
    // LinuxCNC reads only their motion; the cycle then makes its own moves.
    let kinds = parse(&lathe("M3 S100 F5\nG1 X2 Z0\nG1 X4 Z-5\nM2", "G70 Q1 X8 Z2"));
    let moves: Vec<_> = kinds
        .iter()
        .filter_map(|k| match *k {
            BlockKind::Rapid { to } => Some(('R', to.x_mm, to.z_mm)),
            BlockKind::Linear { to, feed_mm_per_min } => {
                assert_eq!(feed_mm_per_min, 100.0);
                Some(('F', to.x_mm, to.z_mm))
            }
            _ => None,
        })
        .collect();
    // The move to the start point, then one pass at D 0: a rapid to the start, to the
    // profile's first point, and the profile fed.
    assert_eq!(moves, [('R', 8.0, 2.0), ('R', 8.0, 2.0), ('R', 2.0, 0.0), ('F', 4.0, -5.0)]);
    assert!(!kinds.iter().any(|k| matches!(k, BlockKind::Spindle { .. })));
}

/// `#<_ini[section]name>` from the machine's INI file, as rs274 2.9 reads it with
/// `-i FILE.ini` (each case run there: `[TRAJ] MAX_LINEAR_VELOCITY = 12.5` gives
/// `STRAIGHT_TRAVERSE(12.5000, ...)` for `G0 X#<_ini[traj]max_linear_velocity>`, in any
/// case of the letters; `Name = 3` is not found (the lookup is upper case), nor
/// `B = 2.5 # c` (not a number): 'Named parameter #<_ini[traj]name> not defined'; EXISTS
/// is 1; an assignment is 'Cannot assign to read-only parameter #<_ini[traj]...>'; of
/// two `MAX_VELOCITY` in `[AXIS_X]` the first, -4, is read: `STRAIGHT_TRAVERSE(-4.0000,
/// ...)`).
#[test]
fn ini_parameters_are_read_from_the_machines_ini_file_as_rs274_reads_them() {
    let ini = "# the machine\n[RS274NGC]\nFEATURES = 12\n[TRAJ]\nMAX_LINEAR_VELOCITY = 12.5\nName = 3\nB = 2.5 # c\n\
               ; a comment\n[AXIS_X]\nMAX_VELOCITY=-4\nMAX_VELOCITY=9\n";
    let options = Options { ini: Options::read_ini(ini), ..Options::default() };
    assert_eq!(options.ini.get(&("TRAJ".to_string(), "Name".to_string())).map(String::as_str), Some("3"));
    let rapid = |source: &str| -> Result<Point, String> {
        let program = parse_str_with(&format!("{source}\nM2\n"), FILE, &options).map_err(|e| e.to_string())?;
        Ok(program
            .blocks
            .iter()
            .find_map(|b| if let BlockKind::Rapid { to } = b.kind { Some(to) } else { None })
            .expect("a rapid"))
    };
    assert_eq!(rapid("G0 X#<_ini[traj]max_linear_velocity> Y#<_INI[Axis_X]MAX_velocity>"), Ok(p(12.5, -4.0, 0.0, 0.0)));
    assert_eq!(rapid("G0 X[EXISTS[#<_ini[traj]max_linear_velocity>]]"), Ok(p(1.0, 0.0, 0.0, 0.0)));
    assert_eq!(rapid("G0 X[EXISTS[#<_ini[traj]name>]]"), Ok(p(0.0, 0.0, 0.0, 0.0)));
    assert_eq!(
        rapid("G0 X#<_ini[traj]name>"),
        Err(format!("{FILE}:1:5: named parameter #<_ini[traj]name> is not defined"))
    );
    assert_eq!(rapid("G0 X#<_ini[traj]b>"), Err(format!("{FILE}:1:5: named parameter #<_ini[traj]b> is not defined")));
    assert_eq!(
        rapid("#<_ini[traj]max_linear_velocity> = 3"),
        Err(format!("{FILE}:1:1: Cannot assign to read-only parameter #<_ini[traj]max_linear_velocity>"))
    );
    // Inside a subroutine too (a global).
    assert_eq!(rapid("o1 sub\nG0 X#<_ini[traj]max_linear_velocity>\no1 endsub\no1 call"), Ok(p(12.5, 0.0, 0.0, 0.0)));
}

/// M100-M199: the user M-code's program `M1nn` is looked for in the user M-code path
/// (LinuxCNC's USER_M_PATH), executable; found, the block is an event naming the code
/// with P and Q (0 when absent), in LinuxCNC's order of execution (after the overrides,
/// before the dwell and the motion). rs274 refuses every one (`Unknown m code used:
/// M101`: its stand-alone canon has no user M-codes), so these are unit tests only.
#[test]
fn user_m_codes_are_events_with_p_and_q_when_their_program_is_in_the_path() {
    let dir = std::env::temp_dir().join(format!("finestep-user-m-{}", std::process::id()));
    let (first, second) = (dir.join("a"), dir.join("b"));
    std::fs::create_dir_all(&first).unwrap();
    std::fs::create_dir_all(&second).unwrap();
    let make = |path: std::path::PathBuf, mode: u32| {
        std::fs::write(&path, "#!/bin/sh\nexit 0\n").unwrap();
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            std::fs::set_permissions(&path, std::fs::Permissions::from_mode(mode)).unwrap();
        }
    };
    make(second.join("M101"), 0o755);
    make(first.join("M102"), 0o644);
    let options = Options { user_m_path: vec![first.clone(), second.clone()], ..Options::default() };
    let kinds = |source: &str| -> Result<Vec<BlockKind>, String> {
        parse_str_with(source, FILE, &options)
            .map(|p| p.blocks.into_iter().map(|b| b.kind).collect())
            .map_err(|e| e.to_string())
    };
    let got = kinds("G0 X1\nM101 P1.5 Q-2\nM101\nM2\n");
    let user: Vec<BlockKind> = got.unwrap().into_iter().filter(|k| matches!(k, BlockKind::UserMCode { .. })).collect();
    assert_eq!(
        user,
        [BlockKind::UserMCode { code: 101, p: 1.5, q: -2.0 }, BlockKind::UserMCode { code: 101, p: 0.0, q: 0.0 }]
    );
    // The dwell's P is P for both: LinuxCNC's P is one word a block.
    assert!(kinds("M101 P1 G4 P2\nM2\n").unwrap_err().ends_with("word P appears twice"));
    // Before the motion of its block.
    let order = kinds("M101 G0 X1\nM2\n").unwrap();
    assert!(matches!(order[..], [BlockKind::UserMCode { .. }, BlockKind::Rapid { .. }, ..]), "{order:?}");
    // Not executable, not in the path, no path at all.
    assert_eq!(
        kinds("M102\nM2\n"),
        Err(format!("{FILE}:1:1: Unknown M code used: M102 (no executable M102 in the user M-code path)"))
    );
    assert_eq!(
        kinds("G0 X1 M199\nM2\n"),
        Err(format!("{FILE}:1:7: Unknown M code used: M199 (no executable M199 in the user M-code path)"))
    );
    assert_eq!(
        err("M101 P1\n"),
        format!(
            "{FILE}:1:1: Unknown M code used: M101 (no executable M101 in the user M-code path, which the machine \
             configuration does not give)"
        )
    );
    // One user M-code a block (LinuxCNC's modal group 10).
    assert!(kinds("M101 M101\nM2\n").is_err());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// G96's spindle block carries S in mm/min (m/min in G21, ft/min in G20), D, and the
/// spindle's axis at the X offsets in force (G5x + G92 + tool length, unrotated), as
/// LinuxCNC's canon takes them with the speed; G97 and G96 D0 carry none.
#[test]
fn constant_surface_speed_carries_the_speed_its_maximum_and_the_axis() {
    let text =
        "G10 L2 P2 X3\nG55 G92 X-1\nG43.1 X2\nG96 S100 D2000 M3\nG20\nG96 S10\nG96 S10 G21\nG97 S300\nG96 S5 D0\nM2\n";
    let program = parse_str(text, "css.ngc").unwrap();
    let css: Vec<(f64, Option<SurfaceSpeed>)> = program
        .blocks
        .iter()
        .filter_map(|b| if let BlockKind::Spindle { rpm, css, .. } = b.kind { Some((rpm, css)) } else { None })
        .collect();
    // G55's X 3; G92 X-1 at machine X 0 under it is an offset of -2; the tool's X 2.
    let axis = 3.0 - 2.0 + 2.0;
    let want = [
        (100.0, Some(SurfaceSpeed { mm_per_min: 100_000.0, max_rpm: Some(2000.0), axis_x_mm: axis })),
        (10.0, Some(SurfaceSpeed { mm_per_min: 3048.0, max_rpm: None, axis_x_mm: axis })),
        // G21 on the line acts after the spindle's calls (LinuxCNC's order): ft/min still.
        (10.0, Some(SurfaceSpeed { mm_per_min: 3048.0, max_rpm: None, axis_x_mm: axis })),
        (300.0, None),
        (5.0, None),
    ];
    assert_eq!(css.len(), want.len(), "{css:?}");
    for ((rpm, got), (want_rpm, want)) in css.iter().zip(want) {
        assert_eq!(*rpm, want_rpm);
        match (got, want) {
            (Some(g), Some(w)) => {
                assert!((g.mm_per_min - w.mm_per_min).abs() < 1e-9, "{g:?} {w:?}");
                assert_eq!(g.max_rpm, w.max_rpm);
                assert!((g.axis_x_mm - w.axis_x_mm).abs() < 1e-9, "{g:?} against {w:?}");
            }
            (g, w) => assert_eq!(*g, w),
        }
    }
    assert_eq!(SurfaceSpeed { mm_per_min: 1000.0, max_rpm: None, axis_x_mm: 2.0 }.rpm_at(2.0), f64::INFINITY);
}

/// The message blocks of `source`: (line, N, kind, text).
fn messages(source: &str) -> Vec<(usize, Option<u32>, MessageKind, String)> {
    let program = parse_str(source, FILE).unwrap_or_else(|e| panic!("{source:?} failed: {e}"));
    program
        .blocks
        .into_iter()
        .filter_map(|b| match b.kind {
            BlockKind::Message { kind, text } => Some((b.line, b.n, kind, text)),
            _ => None,
        })
        .collect()
}

/// Checked against `rs274 -g` (LinuxCNC 2.9) on this program, which printed (the other
/// calls left out; PRINT's text bare on standard output, in order):
/// ```text
///     7 N..... MESSAGE(" hello World")
///     8 N..... MESSAGE("lower case")
///     9 N..... COMMENT("MSG , spaced")
///    10 N..... MESSAGE(" one 2.500000 foo 3.000000 x")
///    11 N..... MESSAGE("low 2.500000")
///  p 2.500000 3.000000
///    12 N..... MESSAGE(" with move")
///    13 N..... STRAIGHT_TRAVERSE(1.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)
///    14 N..... MESSAGE(" second")
///    15 N..... COMMENT("comment")
///    16 N..... STRAIGHT_TRAVERSE(1.0000, 2.0000, 0.0000, 0.0000, 0.0000, 0.0000)
///    17 N..... MESSAGE(" unknown ###### end 1.000000")
///    18 N..... STRAIGHT_TRAVERSE(1.0000, 2.0000, 0.0000, 0.0000, 0.0000, 0.0000)
///    19 N10    MESSAGE(" with N")
///  printed
///    20 N..... MESSAGE("")
/// ```
/// (`;` comments and an O-word line's comment give nothing; #5599 = 0 silences DEBUG
/// but not PRINT.)
#[test]
fn message_comments_as_rs274_gives_them() {
    let source = "#1 = 2.5\n\
                  #<foo> = 3\n\
                  (MSG, hello World)\n\
                  (msg,lower case)\n\
                  (  MSG , spaced)\n\
                  (DEBUG, one #1 foo #<foo> x)\n\
                  (debug,low #1)\n\
                  (PRINT, p #1 #<foo>)\n\
                  G0 X1 (MSG, with move)\n\
                  (MSG, first) (MSG, second)\n\
                  G0 Y2 (MSG, a) (comment)\n\
                  (DEBUG, unknown #<nope> end #<_x>)\n\
                  G0 X1 ; (MSG, semi)\n\
                  o100 if [1] (MSG, in if)\n\
                  o100 endif\n\
                  N10 (MSG, with N)\n\
                  #5599 = 0\n\
                  (DEBUG, silent)\n\
                  (PRINT, printed)\n\
                  (MSG,)\n\
                  M2\n";
    use MessageKind::*;
    let m = |line, n, kind, text: &str| (line, n, kind, text.to_string());
    assert_eq!(
        messages(source),
        vec![
            m(3, None, Msg, " hello World"),
            m(4, None, Msg, "lower case"),
            m(6, None, Debug, " one 2.500000 foo 3.000000 x"),
            m(7, None, Debug, "low 2.500000"),
            m(8, None, Print, " p 2.500000 3.000000"),
            m(9, None, Msg, " with move"),
            m(10, None, Msg, " second"),
            m(12, None, Debug, " unknown ###### end 1.000000"),
            m(16, Some(10), Msg, " with N"),
            m(19, None, Print, " printed"),
            m(20, None, Msg, ""),
        ]
    );
    // The message comes first in its block, before the move.
    let kinds = parse("G0 X1 (MSG, with move)\nM2\n");
    assert!(matches!(&kinds[0], BlockKind::Message { text, .. } if text == " with move"));
    assert!(matches!(kinds[1], BlockKind::Rapid { .. }));
}

/// rs274: `#1=2.5` then `#1=7 (DEBUG, #1)` gives `MESSAGE(" 7.000000")` (the line's
/// assignments act first); in a loop each pass gives its own (`o100 repeat [2]` ...
/// `G1 F100 X[#<_x> + 1] (DEBUG, pass at x %.1f#<_x>)` from X1: `MESSAGE(" pass at x
/// 1.0")` then `MESSAGE(" pass at x 2.0")`, the comment acting before the move).
#[test]
fn debug_reads_the_line_s_assignments_and_each_loop_pass() {
    let got = messages("#1=2.5\n#1=7 (DEBUG, #1)\nG0 X1\no100 repeat [2]\nG1 F100 X[#<_x> + 1] (DEBUG, pass at x %.1f#<_x>)\no100 endrepeat\nM2\n");
    let texts: Vec<&str> = got.iter().map(|m| m.3.as_str()).collect();
    assert_eq!(texts, [" 7.000000", " pass at x 1.0", " pass at x 2.0"]);
}

/// `#<_vmajor>` and `#<_vminor>` as LinuxCNC 2.9.0 gives them: rs274 prints
/// `MESSAGE(" _vmajor: = 2.900000")` and `MESSAGE(" _vminor: = 0.000000")` for
/// `(DEBUG, _vmajor: = #<_vmajor>)` (roparams.ngc in make conformance).
#[test]
fn version_parameters_are_linuxcnc_2_9_0s() {
    let program = parse_str_with("G0 X#<_vmajor> Y#<_vminor>\nM2\n", FILE, &Options::default()).unwrap();
    let to = program.blocks.iter().find_map(|b| if let BlockKind::Rapid { to } = b.kind { Some(to) } else { None });
    assert_eq!(to, Some(p(2.9, 0.0, 0.0, 0.0)));
    // _tool_offset, _retract_r_plane, _retract_old_z at the start: 0, 1 (G99), 0; after
    // G98 _retract_r_plane 0 and _retract_old_z 1 (rs274: MESSAGE(" 0.000000 1.000000")).
    let source = "G0 X#<_tool_offset> Y#<_retract_r_plane> Z#<_retract_old_z>\nG98\nG0 X#<_retract_r_plane> Y#<_retract_old_z>\nM2\n";
    let program = parse_str_with(source, FILE, &Options::default()).unwrap();
    let rapids: Vec<Point> = program
        .blocks
        .iter()
        .filter_map(|b| if let BlockKind::Rapid { to } = b.kind { Some(to) } else { None })
        .collect();
    assert_eq!(rapids, [p(0.0, 1.0, 0.0, 0.0), p(0.0, 1.0, 0.0, 0.0)]);
}

/// The log comments, checked against `rs274 -g` (LinuxCNC 2.9) on this program, which
/// printed (the other calls left out):
/// ```text
///     7 N..... LOGOPEN(" /tmp/e7log.txt")
///     8 N..... LOG(" x is 2.500000")
///     9 N..... LOG("lower 2.500000 ")
///    10 N..... STRAIGHT_TRAVERSE(1.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)
///    11 N..... LOGAPPEND("Other.TXT")
///    12 N..... LOGCLOSE()
///    13 N..... COMMENT("logclose ")
///    14 N..... LOG(" after close")
/// ```
/// (LinuxCNC's `convert_comment`: LOG expanded as DEBUG, LOGOPEN and LOGAPPEND's file
/// name as written, `LOGCLOSE` only when it is the whole comment: `(logclose )` is a
/// plain one.)
#[test]
fn log_comments_as_rs274_gives_them() {
    let source = "#1 = 2.5\n\
                  (LOGOPEN, /tmp/e7log.txt)\n\
                  (LOG, x is #1)\n\
                  ( log,lower #1 )\n\
                  G0 X1\n\
                  (LOGAPPEND,Other.TXT)\n\
                  (LOGCLOSE)\n\
                  (logclose )\n\
                  (LOG, after close)\n\
                  M2\n";
    use MessageKind::*;
    let m = |line, kind, text: &str| (line, None, kind, text.to_string());
    assert_eq!(
        messages(source),
        vec![
            m(2, LogOpen, " /tmp/e7log.txt"),
            m(3, Log, " x is 2.500000"),
            m(4, Log, "lower 2.500000 "),
            m(6, LogAppend, "Other.TXT"),
            m(7, LogClose, ""),
            m(9, Log, " after close"),
        ]
    );
    let rs274 = "    7 N..... LOGOPEN(\" /tmp/e7log.txt\")\n    8 N..... LOG(\" x is 2.500000\")\n    \
                 9 N..... LOG(\"lower 2.500000 \")\n   10 N..... STRAIGHT_TRAVERSE(1.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n   \
                 11 N..... LOGAPPEND(\"Other.TXT\")\n   12 N..... LOGCLOSE()\n   13 N..... COMMENT(\"logclose \")\n   \
                 14 N..... LOG(\" after close\")\n   21 N..... PROGRAM_END()\n";
    let ours = conformance::events_of(&parse_str(source, FILE).unwrap());
    assert_eq!(conformance::compare(&ours, &conformance::rs274_events(rs274).unwrap()), None);
    let other = rs274.replace("lower 2.500000 ", "lower 2.500000");
    assert!(conformance::compare(&ours, &conformance::rs274_events(&other).unwrap()).is_some());
}

/// `LogFile` writes what the blocks say: LOGOPEN empties the file, LOGAPPEND adds to it,
/// a LOG with no file open writes nothing; a file that cannot be opened is an error
/// naming it.
#[test]
fn the_log_file_is_written_as_the_comments_say() {
    let dir = std::env::temp_dir().join(format!("finestep-log-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("probe.txt");
    std::fs::write(&path, "old\n").unwrap();
    let name = path.to_str().unwrap();
    let source = format!("(LOG, before)\n(LOGOPEN,{name})\n#1=1.5 (LOG,X#1)\n(LOGCLOSE)\n(LOG, closed)\n(LOGAPPEND,{name})\n(LOG,%d#1)\nM2\n");
    let mut log = LogFile::default();
    for block in parse_str(&source, FILE).unwrap().blocks {
        if let BlockKind::Message { kind, text } = block.kind {
            log.apply(kind, &text).unwrap();
        }
    }
    log.close().unwrap();
    assert_eq!(std::fs::read_to_string(&path).unwrap(), "X1.500000\n2\n");
    let missing = dir.join("no/such/folder.txt");
    let e = LogFile::default().apply(MessageKind::LogOpen, missing.to_str().unwrap()).unwrap_err();
    assert!(e.to_string().contains("no/such/folder.txt"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `(ABORT, text)` stops the program at the comment with its text expanded as DEBUG's
/// (LinuxCNC's `convert_comment`: `setSavedError(expanded)`, INTERP_ERROR), before the
/// block's own words run; rs274 on `#1 = 2.5`, `G0 X1`, `(ABORT, stop here #1 and
/// #<_x>)`, `G0 X2` prints the traverse to X1, then ` stop here 2.500000 and 1.000000`
/// and exits with 1. Only the line's last comment counts, and a skipped branch's ABORT
/// does nothing. `(PY, ...)`, `(PYRUN, ...)` and `(PYRELOAD` (embedded Python, which
/// rs274 runs) are refused as unsupported; an unclosed or nested comment on a line of
/// its own is refused as rs274 refuses it (`Unclosed comment found`, `Nested comment
/// found`).
#[test]
fn abort_stops_the_program_with_its_text() {
    assert_eq!(
        err("#1 = 2.5\nG0 X1\n(ABORT, stop here #1 and #<_x>)\nG0 X2\nM2\n"),
        format!("{FILE}:3:1: ABORT: stop here 2.500000 and 1.000000")
    );
    assert_eq!(err("G0 X1 #1=3 (abort,%d#1)\nM2\n"), format!("{FILE}:1:12: ABORT:3"));
    assert_eq!(
        err("#5599=0\n  (Abort, silent DEBUG does not matter)\n"),
        format!("{FILE}:2:3: ABORT: silent DEBUG does not matter")
    );
    // Not the last comment, a skipped branch, an O-word line's comment, after `;`.
    let kinds = parse("G0 X1 (ABORT, no) (plain)\no1 if [0]\n(ABORT, skipped)\no1 endif\no2 if [1] (ABORT, oword)\no2 endif\nG0 X2 ; (ABORT, semi)\nM2\n");
    assert_eq!(kinds.iter().filter(|k| matches!(k, BlockKind::Rapid { .. })).count(), 2);
    let python = "unsupported: (PY, ...) (finestep runs no embedded Python, the code LinuxCNC's PY comments execute)";
    assert_eq!(err("(PY, x = 1)\nM2\n"), format!("{FILE}:1:1: {python}"));
    assert_eq!(err("G0 X1 (pyrun,f)\nM2\n"), format!("{FILE}:1:7: {python}"));
    assert_eq!(err("(PYRELOAD)\nM2\n"), format!("{FILE}:1:1: {python}"));
    assert_eq!(err("G0 X1\n(abc\nM2\n"), format!("{FILE}:2:1: unclosed comment"));
    assert_eq!(err("G0 X1\n(a (b)\nM2\n"), format!("{FILE}:2:4: nested comment"));
}

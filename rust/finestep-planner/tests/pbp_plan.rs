//! Point-by-point planning (`[interpolation] mode = "pbp"`, `finestep_planner::pbp::plan_pbp`):
//! the decision divider's rounding, the plane's mapping onto a chip pair, the refusals by
//! key and by line, and seed 003's lathe part (`tests/programs/lathe_pbp.ngc` with
//! `tests/machines/lathe_pbp.toml`) ending exactly on its programmed end.

use finestep_interface::flags;
use finestep_interface::pbp::{arc_steps, PbpLanes};
use finestep_planner::config::{CoreLimits, InterpolationMode, PBP_INTERVAL_MAX};
use finestep_planner::pbp::{decision_interval, plan_pbp, record_clocks, record_decisions};
use finestep_planner::{IoAction, MachineConfig};

fn repo(path: &str) -> String {
    let full = format!("{}/../../{path}", env!("CARGO_MANIFEST_DIR"));
    std::fs::read_to_string(&full).unwrap_or_else(|e| panic!("{full}: {e}"))
}

/// The lathe's configuration, resolved for a 4-axis core with the interpolator.
fn lathe() -> MachineConfig {
    let config = MachineConfig::from_toml_str(&repo("tests/machines/lathe_pbp.toml"), "lathe_pbp.toml").unwrap();
    config.for_core(CoreLimits { has_pbp: true, ..CoreLimits::default() })
}

fn with(text: &str) -> MachineConfig {
    MachineConfig::from_toml_str(text, "m.toml")
        .unwrap()
        .for_core(CoreLimits { has_pbp: true, ..CoreLimits::default() })
}

#[test]
fn the_divider_keeps_the_mean_speed_at_or_below_the_feed() {
    // 1 mm at F600 (10 mm/s) in 100 decisions: 0.1 s, 50 000 clocks each, exact.
    assert_eq!(decision_interval(50e6, 1.0, 600.0, 100, 625), Some(50_000));
    // A fraction of a clock rounds up (never faster than F): 1 mm at F600 in 300
    // decisions is 16 666.67 clocks each.
    assert_eq!(decision_interval(50e6, 1.0, 600.0, 300, 625), Some(16_667));
    // The rate limit and the drive timing's floor win over a fast feed.
    assert_eq!(decision_interval(50e6, 1.0, 600_000.0, 100, 6_250), Some(6_250));
    // Beyond the 24-bit divider: refused, not clamped (that would run faster than F):
    // 100 mm at F600 in 3 decisions is 3.3 s, 1.7 * 10^8 clocks each.
    assert_eq!(PBP_INTERVAL_MAX, 1 << 24);
    assert_eq!(decision_interval(50e6, 100.0, 600.0, 3, 625), None);
    let longest = f64::from(PBP_INTERVAL_MAX) * 100.0 / 50e6 * 10.0;
    assert_eq!(decision_interval(50e6, longest, 600.0, 100, 1), Some(PBP_INTERVAL_MAX));
    assert_eq!(decision_interval(50e6, longest * 1.001, 600.0, 100, 1), None);
}

#[test]
fn the_plane_maps_onto_the_pair_and_the_other_axes_onto_the_rest() {
    let resolved = lathe().resolve().unwrap();
    let pbp = resolved.pbp.unwrap();
    assert_eq!((pbp.slots, pbp.pair, pbp.mirrored), ([0, 2], 0, true), "X, Z on pair 0; G18's own order is Z->X");
    assert_eq!(resolved.chip_axis, [0, 2, 1, 3], "X on chip axis 0, Z on 1, Y and A on 2 and 3");
    // 8 kHz at 50 MHz: 6250 clocks, above the drive's 2 + max(2, 5 + 5) us = 600.
    assert_eq!(pbp.min_interval, 6_250);
    let all = "[axes.X]\n[axes.Y]\n[axes.Z]\n[axes.A]\n";
    let zx = with(&format!("[interpolation]\nmode = \"pbp\"\nplane = \"ZX\"\npair = 1\n{all}")).resolve().unwrap();
    let p = zx.pbp.unwrap();
    assert_eq!((p.slots, p.mirrored, zx.chip_axis), ([2, 0], false, [3, 0, 2, 1]));
    let xy = with("[interpolation]\nmode = \"pbp\"\nmax_decision_hz = 1e6\n").resolve().unwrap();
    assert_eq!((xy.pbp.unwrap().mirrored, xy.chip_axis), (false, [0, 1, 2, 3]));
    // The drive timing's floor: 2 us + max(2 us, 5 + 5 us) = 600 clocks; with the default
    // build's step engine (4 slots) in whole visits, 4 * (25 + max(25, 63 + 63)) = 604.
    assert_eq!(xy.pbp.unwrap().min_interval, 604);
    // The DDA (the default) maps nothing.
    let dda = MachineConfig::default().resolve().unwrap();
    assert_eq!((dda.pbp, dda.chip_axis), (None, [0, 1, 2, 3]));
    assert_eq!(MachineConfig::default().interpolation.mode, InterpolationMode::Dda);
}

#[test]
fn configurations_that_cannot_run_are_refused_by_key() {
    let pbp = "[interpolation]\nmode = \"pbp\"\n";
    // Refused when the file is read (against the default build) or when resolved for the
    // chip.
    let key = |text: &str, core: CoreLimits| {
        let err = match MachineConfig::from_toml_str(text, "m.toml") {
            Ok(config) => config.for_core(core).resolve_in("m.toml").unwrap_err(),
            Err(err) => err,
        };
        (err.key.clone(), err.to_string())
    };
    let core = CoreLimits { has_pbp: true, ..CoreLimits::default() };
    let (k, e) = key(pbp, CoreLimits { has_pbp: false, ..core });
    assert_eq!(k, "interpolation.mode");
    assert!(e.starts_with("m.toml: interpolation.mode:") && e.contains("VERSION.HAS_PBP 0"), "{e}");
    assert_eq!(key(&format!("{pbp}pair = 2\n"), core).0, "interpolation.pair");
    let xz = "plane = \"XZ\"\n[axes.X]\n[axes.Z]\n";
    assert_eq!(key(&format!("{pbp}pair = 1\n{xz}"), CoreLimits { n_axes: 3, ..core }).0, "interpolation.pair");
    for plane in ["XA", "XX", "X", "XYZ"] {
        let (k, e) = key(&format!("{pbp}plane = \"{plane}\"\n"), core);
        assert_eq!(k, "interpolation.plane", "{plane}: {e}");
    }
    let (k, e) = key(&format!("{pbp}plane = \"XZ\"\n"), core);
    assert!(k == "interpolation.plane" && e.contains("equal steps per unit"), "{e}");
    let (k, e) = key(&format!("{pbp}plane = \"XY\"\n[axes.X]\n"), core);
    assert!(k == "interpolation.plane" && e.contains("Y is not configured"), "{e}");
    assert_eq!(key(&format!("{pbp}max_decision_hz = 0\n"), core).0, "interpolation.max_decision_hz");
    assert_eq!(key(&format!("{pbp}max_decision_hz = 2\n"), core).0, "interpolation.max_decision_hz");
    assert_eq!(key("[interpolation]\nmode = \"pbp\"\n[gantry]\nenabled = true\n", core).0, "interpolation.mode");
    assert!(MachineConfig::from_toml_str("[interpolation]\nmode = \"fast\"\n", "m.toml").is_err());
}

#[test]
fn moves_that_leave_the_plane_are_refused_by_line() {
    let config = lathe();
    let refused = |text: &str| {
        let program = finestep_gcode::parse_str(text, "p.ngc").unwrap();
        let err = plan_pbp(&config, &program).unwrap_err();
        (err.line, err.reason)
    };
    // An arc in G17 on a lathe whose pair is XZ.
    let (line, why) = refused("G17\nG1 X1 F600\nG2 X2 Y1 I1 J0\nM2\n");
    assert!(line == 3 && why.contains("the point-by-point pair is the plane XZ"), "{line}: {why}");
    // The lathe has no Y.
    let (line, why) = refused("G18\nG1 X1 Z1 F600\nG0 Y1\nM2\n");
    assert!(line == 3 && why.contains("moves Y, which is not configured in [axes]"), "{line}: {why}");
    // A machine with Y: G1 with a third axis, and a helix in G18 (Y moves with the arc).
    let xyz = with("[interpolation]\nmode = \"pbp\"\nplane = \"XZ\"\n[axes.X]\n[axes.Y]\n[axes.Z]\n");
    let refused_xyz = |text: &str| {
        let err = plan_pbp(&xyz, &finestep_gcode::parse_str(text, "p.ngc").unwrap()).unwrap_err();
        (err.line, err.reason)
    };
    let (line, why) = refused_xyz("G18\nG1 X1 Z1 F600\nG1 X2 Y1\nM2\n");
    assert!(line == 3 && why.contains("moves Y, outside the point-by-point plane XZ"), "{line}: {why}");
    let (line, why) = refused_xyz("G18\nG1 X2 F600\nG3 X0 Z2 Y1 I-2 K0\nM2\n");
    assert!(line == 3 && why.contains("the arc (a helix) moves Y"), "{line}: {why}");
    let (line, why) = refused("G18\nG96 S100 M3\nG1 X1 F600\nM2\n");
    assert!(line == 2 && why.contains("G96"), "{line}: {why}");
    // 1 mm at F1: 100 decisions of 0.6 s each, beyond the 24-bit divider (2^24 clocks,
    // 0.34 s at 50 MHz: F1.79 at least); at F60 (a finishing feed the 16-bit divider
    // refused below F458) a decision every 500 000 clocks.
    let (line, why) = refused("G18\nG1 X1 F1\nM2\n");
    assert!(line == 2 && why.contains("too slow for the point-by-point divider"), "{line}: {why}");
    assert!(why.contains("at least F1.788"), "{why}");
    let slow = plan_pbp(&config, &finestep_gcode::parse_str("G18\nG1 X1 F60\nM2\n", "p.ngc").unwrap()).unwrap();
    assert_eq!(slow.min_interval, Some(500_000));
    let (line, why) = refused("G18\nG41 D1\nG1 X1 F600\nM2\n");
    assert!(line == 2 && why.contains("cutter compensation"), "{line}: {why}");
    // G0 moves any axis, Y included, as the DDA's records.
    let program = finestep_gcode::parse_str("G0 Y1\nG18 G1 X1 F600\nM2\n", "p.ngc").unwrap();
    let plan = plan_pbp(&xyz, &program).unwrap();
    assert_eq!(plan.planned.end, [1.0, 1.0, 0.0, 0.0]);
    // Y is slot 1, on chip axis 2 beside the pair (X 0, Z 1).
    let y: i64 =
        plan.planned.records.iter().filter(|r| r.pbp_lanes().is_none()).map(|r| i64::from(r.inc[2].to_bits())).sum();
    assert_eq!(y, 800 << 16);
}

#[test]
fn the_lathe_part_ends_exactly_on_its_programmed_end() {
    let config = lathe();
    let resolved = config.resolve().unwrap();
    let program = finestep_gcode::parse_file(std::path::Path::new(&format!(
        "{}/../../tests/programs/lathe_pbp.ngc",
        env!("CARGO_MANIFEST_DIR")
    )))
    .unwrap();
    let plan = plan_pbp(&config, &program).unwrap();
    let planned = &plan.planned;
    assert_eq!(planned.end, [6.0, 0.0, 0.5, 0.0], "G7: X12 is a radius of 6 mm");
    assert!(planned.notes.iter().all(|n| !n.contains("arc ends")), "{:?}", planned.notes);
    // Walk the records on the chip's axes: X on 0, Z on 1; the DDA's sums and the pbp
    // records' displacements (a line's end, an arc's from arc_steps) meet every exact stop.
    let mut at = [0i64; 2];
    let mut dda = [0i64; 2];
    let mut arcs = Vec::new();
    for record in &planned.records {
        match record.pbp_lanes() {
            None => {
                for (axis, sum) in dda.iter_mut().enumerate() {
                    *sum += i64::from(record.inc[axis].to_bits());
                }
                assert_eq!(record.inc[2].to_bits() | record.inc[3].to_bits(), 0);
                if record.block_end() {
                    assert!(dda.iter().all(|d| d & 0xFFFF == 0), "{dda:?}");
                    at = [at[0] + (dda[0] >> 16), at[1] + (dda[1] >> 16)];
                    dda = [0, 0];
                }
            }
            Some(lanes) => {
                assert_eq!(dda, [0, 0], "a pbp record after a DDA record at rest");
                assert!(record.flags & flags::BLOCK_END != 0 && lanes.pair == 0);
                assert!(lanes.tick_div + 1 >= 6_250, "{lanes:?}: faster than 8 kHz");
                if lanes.arc {
                    arcs.push(lanes);
                    // The arc's start relative to its centre is (x, y); it ends after
                    // `steps` decisions where arc_steps says: here the programmed end.
                    let centre = [at[0] - i64::from(lanes.x), at[1] - i64::from(lanes.y)];
                    let end = [500 - centre[0], -700 - centre[1]];
                    assert_eq!(
                        arc_steps((lanes.x.into(), lanes.y.into()), (end[0], end[1]), lanes.cw),
                        Ok(lanes.steps)
                    );
                    at = [500, -700];
                } else {
                    at = [at[0] + i64::from(lanes.x), at[1] + i64::from(lanes.y)];
                }
            }
        }
    }
    assert_eq!(at, [600, 50], "the records end on X 6 mm (radius), Z 0.5 mm");
    // The shoulder: from (400, -600) around (500, -600), counter-clockwise on (X, Z) for
    // G2 in G18 (whose own order is Z->X): a quarter of radius 100, 200 decisions.
    assert_eq!(
        arcs,
        [PbpLanes { arc: true, cw: false, pair: 0, x: -100, y: 0, steps: 200, tick_div: arcs[0].tick_div }]
    );
    // At F2400 (40 mm/s) a quarter of 157.08 steps' length in 200 decisions: 0.98 ms each.
    let expected = (50e6 * (std::f64::consts::FRAC_PI_2 * 100.0 / 100.0) / 40.0 / 200.0).ceil() as u32;
    assert_eq!(arcs[0].tick_div + 1, expected.max(6_250));
    // The face to the centre at F6000 (100 mm/s: 10 000 steps/s on X, 5000 clocks a
    // decision) is held to 8 kHz (6250 clocks), a line of 600 steps.
    let face = planned.records.iter().filter_map(|r| r.pbp_lanes()).next().unwrap();
    assert_eq!((face.x, face.y, face.tick_div), (-600, 0, 6_249));
    // Spindle and coolant at their exact stops, each after a record at rest.
    let actions: Vec<_> = planned.events.iter().map(|t| (t.period, t.event.action.clone())).collect();
    assert_eq!(actions.len(), 5, "{actions:?}");
    assert!(matches!(actions[0].1, IoAction::Spindle { rpm: 0.0, .. }), "G97's own, before any S");
    assert!(matches!(actions[1].1, IoAction::Spindle { fraction, .. } if (fraction - 0.4).abs() < 1e-12));
    assert!(matches!(actions[2].1, IoAction::Coolant { flood: true, mist: false }));
    assert_eq!((actions[0].0, actions[1].0, actions[2].0), (0, 0, 0));
    for (period, _) in &actions[3..] {
        assert_eq!(*period as usize, planned.records.len(), "M9 and M5 after the last record");
    }
    assert!(planned.records.last().unwrap().block_end());
    // The machining time: the pbp records' decisions at their intervals and a period per
    // DDA record.
    let clocks: u64 = planned.records.iter().map(|r| record_clocks(r, resolved.period_clocks)).sum();
    assert_eq!(clocks, plan.clocks);
    let decisions: u64 = planned.records.iter().filter_map(record_decisions).map(|(d, _)| d).sum();
    assert_eq!(decisions, plan.decisions);
    assert_eq!(plan.min_interval, Some(6_250), "the face, held to the limit");
}

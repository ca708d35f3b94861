//! Machining time against the independent lower bound ([`finestep_planner::bound`]) on
//! every program of `tests/programs/`, both profiles: the plan may never beat the bound
//! (that would make it no bound, or the plan break a limit), and the ratios are printed
//! (the figures of `finestep bench --host-only`).

mod common;

use finestep_planner::{plan_program, time_lower_bound, ProfileKind};

use common::{config, parse, plan_and_check, program_names, read, PROFILES};

/// The bench's CAM program of 2 000 short blended G1 segments on a wavy spiral, Z going
/// down by `dz` per move.
fn short_segments(dz: f64) -> finestep_gcode::Program {
    let mut text = String::from("G21 G90 G17 G64 P0.01\nF3000\n");
    for i in 0..2000 {
        let t = i as f64 * 0.01;
        let r = 20.0 + 5.0 * (7.0 * t).sin();
        text.push_str(&format!("G1 X{:.4} Y{:.4} Z{:.4}\n", r * t.cos(), r * t.sin(), dz * i as f64));
    }
    text.push_str("M2\n");
    parse("cam.ngc", &text)
}

/// Machining time over the bound for one program and profile: (time, bound) in s.
fn timed(name: &str, profile: ProfileKind) -> (f64, f64) {
    timed_program(&read(name), profile)
}

fn timed_program(program: &finestep_gcode::Program, profile: ProfileKind) -> (f64, f64) {
    let program = program.clone();
    let config = config(profile);
    let planned = plan_program(&config, &program).unwrap();
    // Dwells are not motion: the bound leaves them out, so does the time here.
    let moving = planned.records.iter().filter(|r| r.inc.iter().any(|i| i.to_bits() != 0)).count();
    let resolved = config.resolve().unwrap();
    (moving as f64 * resolved.period_s, time_lower_bound(&config, &program).unwrap())
}

#[test]
fn no_plan_beats_the_time_lower_bound() {
    let names = program_names();
    for profile in PROFILES {
        let (mut time, mut bound) = (0.0, 0.0);
        for name in &names {
            let (t, b) = timed(name, profile);
            eprintln!("{name} {profile:?}: {t:.3} s, bound {b:.3} s, ratio {:.3}", t / b);
            assert!(t >= b, "{name} {profile:?}: {t} s is below the lower bound {b} s");
            time += t;
            bound += b;
        }
        eprintln!("corpus {profile:?}: {time:.3} s, bound {bound:.3} s, ratio {:.3}", time / bound);
    }
}

/// Short blended segments on a wavy spiral (the bench's CAM program, 2 000 moves): the
/// blends' curvature read from positions must not make the bound too high (it was, by
/// 2.5 %, while the second differences were taken 1e-4 of a 5 um blend apart).
#[test]
fn short_segments_do_not_beat_the_bound() {
    let program = short_segments(-0.0005);

    for profile in PROFILES {
        let (t, b) = timed_program(&program, profile);
        eprintln!("cam {profile:?}: {t:.3} s, bound {b:.3} s, ratio {:.3}", t / b);
        assert!(t >= b, "{profile:?}: {t} s is below the lower bound {b} s");
    }
}

/// Short segments, where the jumps around short elements take the jerk those elements
/// leave (`finestep_planner::element::jump_jerk_share`): every limit held by the
/// independent checker, with the Z staircase of the bench's program (0 or 1 step of Z
/// per move, so the blends' Z curvature turns over at every short line) and without Z.
#[test]
fn short_segments_keep_every_limit() {
    for dz in [-0.001, 0.0] {
        let program = short_segments(dz);
        for profile in PROFILES {
            let (planned, report) = plan_and_check("cam.ngc", &program, &config(profile));
            eprintln!(
                "cam dz {dz} {profile:?}: {:.3} s, peak jerk X {:.0} Y {:.0} Z {:.0}",
                planned.records.len() as f64 * report.period_s,
                report.axis_max[0][2],
                report.axis_max[1][2],
                report.axis_max[2][2]
            );
        }
    }
}

/// A canned cycle puts its rapids and its feeds on one line: the bound takes each
/// block's own feed (`Element::feed`), not the largest on the line. Until plan26 it
/// took the line's largest, the rapids', so the drilling feeds were bounded as rapids
/// (LinuxCNC's hole-circle.ngc read 3.1 times its bound). Four holes, each fed 10 mm at
/// 120 mm/min: at least 20 s of feeding.
#[test]
fn a_canned_cycle_is_bounded_at_its_feeds() {
    let program = parse("drill.ngc", "G21 G17 G90\nG0 X10 Y0 Z0\nG91 G81 R1 Z-10 X5 L4 F120\nG90\nM2\n");
    for profile in PROFILES {
        let (t, b) = timed_program(&program, profile);
        eprintln!("drill {profile:?}: {t:.3} s, bound {b:.3} s, ratio {:.3}", t / b);
        assert!(b >= 4.0 * 10.0 / 2.0, "{profile:?}: bound {b} s below the 20 s of feeding");
        assert!(t >= b, "{profile:?}: {t} s is below the lower bound {b} s");
    }
}

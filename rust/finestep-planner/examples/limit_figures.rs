//! The limit figures of `finestep bench --host-only` (issue 18) without the CLI's
//! simulation crates: seed 002's star peaks, machining time over the lower bound on
//! `tests/programs` and on 20 000 short segments, and plan + interpolate throughput on
//! 100 000 short segments, per profile. `cargo run --release -p finestep-planner
//! --example limit_figures [-- --no-throughput]`.

use std::time::Instant;

use finestep_planner::{check_program, plan_program, plan_stream, time_lower_bound, MachineConfig, ProfileKind};

/// The bench's CAM program: `moves` short G1 segments along a wavy spiral (G64 P0.01).
fn cam_program(moves: usize) -> String {
    let mut text = String::from("G21 G90 G17 G64 P0.01\nF3000\n");
    for i in 0..moves {
        let t = i as f64 * 0.01;
        let r = 20.0 + 5.0 * (7.0 * t).sin();
        text.push_str(&format!("G1 X{:.4} Y{:.4} Z{:.4}\n", r * t.cos(), r * t.sin(), -0.001 * i as f64 % 5.0));
    }
    text + "M2\n"
}

fn seed_002(profile: ProfileKind) -> MachineConfig {
    let mut config = MachineConfig { profile, chord_tolerance_mm: 0.001, ..MachineConfig::default() };
    for (name, axis) in config.axes.iter_mut() {
        if name == "X" || name == "Y" {
            (axis.max_velocity, axis.max_acceleration, axis.max_jerk) = (200.0, 300.0, 3000.0);
        }
    }
    config
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let throughput = !std::env::args().any(|a| a == "--no-throughput");
    let dir = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../../tests/programs"));
    let mut names: Vec<String> = std::fs::read_dir(dir)?
        .filter_map(|e| e.ok().map(|e| e.file_name().to_string_lossy().to_string()))
        .filter(|n| n.ends_with(".ngc"))
        .collect();
    names.sort();
    let programs: Vec<(String, finestep_gcode::Program)> = names
        .into_iter()
        .map(|n| {
            let p = finestep_gcode::parse_file(dir.join(&n)).expect("parses");
            (n, p)
        })
        .collect();
    let fail = |name: &str, e: finestep_planner::ProgramError| format!("{name}:{}: {}", e.line, e.reason);
    for profile in [ProfileKind::Trapezoid, ProfileKind::SCurve] {
        let (_, star) = programs.iter().find(|(n, _)| n == "star.ngc").expect("star.ngc");
        let config = seed_002(profile);
        let planned = plan_program(&config, star).map_err(|e| fail("star", e))?;
        let report = check_program(&config, star, &planned.records)?;
        assert!(report.passed(), "star ({profile:?}): {:?}", report.violations);
        let [x, y] = [0, 1].map(|a| report.axis_max[a]);
        println!(
            "star {profile:?}: a X {:.3} Y {:.3} path {:.3}  j X {:.3} Y {:.3} path {:.3}  ({:.3} s)",
            x[1] / 300.0,
            y[1] / 300.0,
            report.path_max[1] / 300.0,
            x[2] / 3000.0,
            y[2] / 3000.0,
            report.path_max[2] / 3000.0,
            planned.records.len() as f64 * report.period_s
        );
        let (mut time, mut bound, mut worst) = (0.0, 0.0, (0.0f64, String::new()));
        for (name, program) in &programs {
            let config = MachineConfig { profile, ..MachineConfig::default() };
            let planned = plan_program(&config, program).map_err(|e| fail(name, e))?;
            let report = check_program(&config, program, &planned.records)?;
            assert!(report.passed(), "{name} ({profile:?}): {:?}", report.violations);
            let moving = planned.records.iter().filter(|r| r.inc.iter().any(|i| i.to_bits() != 0)).count();
            let t = moving as f64 * config.period_ms * 1e-3;
            let b = time_lower_bound(&config, program).map_err(|e| fail(name, e))?;
            println!("    {name:<24} {:.3}", t / b);
            if t / b > worst.0 {
                worst = (t / b, name.clone());
            }
            time += t;
            bound += b;
        }
        println!(
            "corpus {profile:?}: {:.3} (worst {:.3} on {}; {:.2} s against {:.2} s)",
            time / bound,
            worst.0,
            worst.1,
            time,
            bound
        );
        let cam = finestep_gcode::parse_str(&cam_program(20_000), "cam.ngc")?;
        let config = MachineConfig { profile, ..MachineConfig::default() };
        let planned = plan_program(&config, &cam).map_err(|e| fail("cam", e))?;
        let report = check_program(&config, &cam, &planned.records)?;
        let moving = planned.records.iter().filter(|r| r.inc.iter().any(|i| i.to_bits() != 0)).count();
        let t = moving as f64 * config.period_ms * 1e-3;
        let b = time_lower_bound(&config, &cam).map_err(|e| fail("cam", e))?;
        println!(
            "short segments {profile:?}: {:.3} ({t:.2} s against {b:.2} s; checker {}, deviation {:.4} mm, path a {:.0} j {:.0})",
            t / b,
            if report.passed() { "passes".to_string() } else { format!("{} violations", report.violations.len()) },
            report.max_deviation,
            report.path_max[1],
            report.path_max[2],
        );
        if throughput {
            let cam = finestep_gcode::parse_str(&cam_program(100_000), "cam.ngc")?;
            let mut best = f64::INFINITY;
            for _ in 0..3 {
                let start = Instant::now();
                let stream = plan_stream(&config, &cam).map_err(|e| fail("cam", e))?;
                for period in stream.periods {
                    period.map_err(|e| fail("cam", e))?;
                }
                best = best.min(start.elapsed().as_secs_f64());
            }
            println!("plan + interpolate {profile:?}: {:.0} k moves/s (best of 3)", 100_000.0 / best / 1e3);
        }
    }
    Ok(())
}

//! The limit figures of `finestep bench --host-only` (issue 18) without the CLI's
//! simulation crates ([`finestep_planner::figures`]): seed 002's star peaks, machining
//! time over the lower bound on `tests/programs` and on 20 000 short segments, and plan +
//! interpolate throughput on 100 000 short segments, per profile. `cargo run --release
//! -p finestep-planner --example limit_figures [-- --no-throughput]`.

use std::time::Instant;

use finestep_planner::figures::{cam_program, limit_figures, test_programs};
use finestep_planner::{plan_stream, MachineConfig, ProfileKind};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let throughput = !std::env::args().any(|a| a == "--no-throughput");
    let programs = test_programs()?;
    for profile in [ProfileKind::Trapezoid, ProfileKind::SCurve] {
        for line in limit_figures(&programs, profile)? {
            println!("{line}");
        }
        if throughput {
            let config = MachineConfig { profile, ..MachineConfig::default() };
            let cam = finestep_gcode::parse_str(&(cam_program(100_000) + "M2\n"), "cam.ngc")?;
            let mut best = f64::INFINITY;
            for _ in 0..3 {
                let start = Instant::now();
                for period in plan_stream(&config, &cam).map_err(|e| e.reason)?.periods {
                    period.map_err(|e| e.reason)?;
                }
                best = best.min(start.elapsed().as_secs_f64());
            }
            println!("plan + interpolate {profile:?}: {:.0} k moves/s (best of 3)", 100_000.0 / best / 1e3);
        }
    }
    Ok(())
}

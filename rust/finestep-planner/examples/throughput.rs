//! Plan + interpolate throughput of `finestep bench --host-only` on 100 000 short G1
//! segments (the bench's CAM program), best of three, per profile, without the CLI's
//! simulation crates: `cargo run --release -p finestep-planner --example throughput
//! [-- trapezoid | s-curve]` (one profile alone, for a profiler).

use std::time::Instant;

use finestep_planner::{plan_stream, MachineConfig, ProfileKind};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut text = String::from("G21 G90 G17 G64 P0.01\nF3000\n");
    for i in 0..100_000 {
        let t = i as f64 * 0.01;
        let r = 20.0 + 5.0 * (7.0 * t).sin();
        text.push_str(&format!("G1 X{:.4} Y{:.4} Z{:.4}\n", r * t.cos(), r * t.sin(), -0.001 * i as f64 % 5.0));
    }
    text.push_str("M2\n");
    let cam = finestep_gcode::parse_str(&text, "cam.ngc")?;
    let only = std::env::args().nth(1);
    for profile in [ProfileKind::Trapezoid, ProfileKind::SCurve] {
        let name = if profile == ProfileKind::SCurve { "s-curve" } else { "trapezoid" };
        if only.as_deref().is_some_and(|o| o != name) {
            continue;
        }
        let config = MachineConfig { profile, ..MachineConfig::default() };
        let mut best = f64::INFINITY;
        for _ in 0..3 {
            let start = Instant::now();
            let stream = plan_stream(&config, &cam).map_err(|e| format!("{}: {}", e.line, e.reason))?;
            for period in stream.periods {
                period.map_err(|e| format!("{}: {}", e.line, e.reason))?;
            }
            best = best.min(start.elapsed().as_secs_f64());
        }
        println!("plan + interpolate {profile:?}: {:.0} k moves/s (best of 3)", 100_000.0 / best / 1e3);
    }
    Ok(())
}

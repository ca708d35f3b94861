//! Throughput figures (not timed tests): RTL alone, model alone (per clock and fast
//! path), and the two in lockstep, for a 4-axis stream with reversals at 1 ms periods.

use std::time::Instant;

use finestep_cosim::{Harness, ModelPath};
use finestep_model::{Core, CoreInputs, Event, Increment, PeriodRecord};
use finestep_planner::config::Resolved;
use finestep_planner::MachineConfig;
use finestep_rtl_sys::Rtl;

use crate::machine_setup;

const AXES: usize = 4;

/// Sinusoidal velocities with different amplitudes and phases per axis, peaking near
/// the demo timing's rated rate.
fn stream(periods: u64) -> impl Iterator<Item = PeriodRecord> {
    (0..periods).map(|k| {
        let mut record = PeriodRecord::default();
        for axis in 0..AXES {
            let amplitude = 40.0 + 50.0 * axis as f64;
            let phase = k as f64 * std::f64::consts::TAU / 400.0 + axis as f64;
            record.inc[axis] = Increment::from_num(amplitude * phase.sin());
        }
        record
    })
}

/// The benches' machine: the built-in configuration (T = 1 ms, 4 axes, the default
/// drives), resolved against the model's build.
pub(crate) fn bench_machine() -> anyhow::Result<Resolved> {
    Ok(machine_setup::resolve(MachineConfig::default(), machine_setup::model_limits(), "<built-in>")?.1)
}

fn inputs(machine: &Resolved) -> CoreInputs {
    let period_clocks = machine.period_clocks;
    let mut inputs = CoreInputs { run: true, period_clocks, rec_valid: true, ..Default::default() };
    for (axis, slot) in inputs.axes.iter_mut().enumerate().take(AXES) {
        *slot = machine_setup::axis_config(machine, axis);
    }
    inputs
}

/// Feed `periods` records to a `run_chunk`-shaped simulator; returns cycles run.
fn drive(machine: &Resolved, periods: u64, mut run_chunk: impl FnMut(&CoreInputs, &mut Vec<Event>) -> u64) -> u64 {
    let mut inputs = inputs(machine);
    let mut events = Vec::new();
    let mut cycles = 0;
    for record in stream(periods) {
        inputs.record = record;
        events.clear();
        cycles += run_chunk(&inputs, &mut events);
    }
    cycles
}

/// The CPU time of the calling thread: the simulation figures are per CPU second of the
/// thread that simulates (Verilator and the model run on it alone), so they do not move
/// with what else the machine runs, as wall-clock figures do on a shared machine.
pub(crate) struct CpuClock(cpu_time::ThreadTime);

impl CpuClock {
    pub(crate) fn start() -> CpuClock {
        CpuClock(cpu_time::ThreadTime::now())
    }

    /// CPU seconds of this thread since [`CpuClock::start`].
    pub(crate) fn seconds(&self) -> f64 {
        self.0.elapsed().as_secs_f64()
    }
}

/// One throughput figure of `cycles` simulated in `seconds` on `machine`'s period and clock.
pub(crate) fn report(machine: &Resolved, what: &str, cycles: u64, seconds: f64) {
    println!(
        "  {what:<44} {:>7.2} M cycles/s  {:>9.0} periods/s  {:>7.3}x real time",
        cycles as f64 / seconds / 1e6,
        cycles as f64 / f64::from(machine.period_clocks) / seconds,
        cycles as f64 / machine.clock_hz / seconds
    );
}

/// The bench's CAM program ([`finestep_planner::figures::cam_program`]).
pub use finestep_planner::figures::cam_program;

/// A parameter- and expression-heavy program: a `while` loop of `moves` passes, each a
/// G1 whose coordinates are expressions of a counter (a spiral), and the number of lines
/// it executes.
pub fn expression_program(moves: usize) -> (String, usize) {
    let text = format!(
        "G21 G90 G17 G64 P0.01\nF3000\n#<i> = 0\no1 while [#<i> LT {moves}]\n  \
         G1 X[[20 + 5 * sin[#<i> * 4]] * cos[#<i> * 0.573]] Y[[20 + 5 * sin[#<i> * 4]] * sin[#<i> * 0.573]] \
         Z[-0.001 * [#<i> MOD 5000]]\n  #<i> = [#<i> + 1]\no1 endwhile\nM2\n"
    );
    (text, 3 + moves * 3 + 2)
}

/// A chain of `blocks` cubic NURBS (G5.2 L4, seven control points each, weights 0.5 to
/// 2) along a wave, each leaving its end along the direction it arrived in (tangent).
pub fn nurbs_program(blocks: usize) -> String {
    let mut text = String::from("G21 G90 G17 G64 P0.01\nF3000\nG1 X1 Y0\n");
    let (mut x, mut y, mut dy) = (1.0f64, 0.0f64, 0.0f64);
    for b in 0..blocks {
        text.push_str("G5.2 L4\n");
        for i in 1..=6 {
            let (nx, ny) = if i == 1 { (x + 1.0, y + dy) } else { (x + 1.0, 4.0 * ((b * 6 + i) as f64 * 0.7).sin()) };
            let weight = 1.25 + 0.75 * ((b + i) as f64).cos();
            text.push_str(&format!("X{nx:.4} Y{ny:.4} P{weight:.3}\n"));
            dy = ny - y;
            (x, y) = (nx, ny);
        }
        text.push_str("G5.3\n");
    }
    text.push_str("M2\n");
    text
}

/// One program planned and interpolated with the default machine and `profile`, timed.
struct Timed {
    elements: usize,
    /// Path and blends, s.
    path_s: f64,
    /// The look-ahead over the whole path at once, s.
    speeds_s: f64,
    /// The record stream (its windowed look-ahead included), s.
    stream_s: f64,
    periods: f64,
    period_s: f64,
}

fn plan_timed(profile: finestep_planner::ProfileKind, program: &finestep_gcode::Program) -> anyhow::Result<Timed> {
    use finestep_planner::{geometry, interpolate, lookahead};
    let profiled = MachineConfig { profile, ..MachineConfig::default() };
    let (_, config) = machine_setup::resolve(profiled, machine_setup::model_limits(), "<built-in>")?;
    let start = Instant::now();
    let path = geometry::elements(&config, program)?;
    let path_s = start.elapsed().as_secs_f64();
    let start = Instant::now();
    let speeds = lookahead::junction_speeds(&config, &path.elements);
    let speeds_s = start.elapsed().as_secs_f64();
    drop(speeds);
    let elements = path.elements.len();
    let period_s = config.period_s;
    let start = Instant::now();
    let mut periods = 0u64;
    for period in interpolate::Periods::new(config, path.elements, path.leading_dwell) {
        period?;
        periods += 1;
    }
    Ok(Timed { elements, path_s, speeds_s, stream_s: start.elapsed().as_secs_f64(), periods: periods as f64, period_s })
}

/// The programs of the memory figures: a straight move of about 10 h, a 1 000 000 mm
/// half circle, and the CAM program of 100 000 and of 1 000 000 short segments.
fn memory_program(case: &str) -> anyhow::Result<String> {
    Ok(match case {
        "line" => "G21 G90 G1 X1000000 F1666\nM2\n".to_string(),
        "arc" => "G21 G90 G17 G2 X1000000 Y0 I500000 J0 F6000\nM2\n".to_string(),
        "program" => cam_program(100_000) + "M2\n",
        "program-1m" => cam_program(1_000_000) + "M2\n",
        other => anyhow::bail!("no memory case {other:?} (line, arc, program, program-1m)"),
    })
}

/// The process's peak resident set so far, kB (Linux `VmHWM`).
fn peak_rss_kb() -> anyhow::Result<u64> {
    let status = std::fs::read_to_string("/proc/self/status")?;
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
        .ok_or_else(|| anyhow::anyhow!("no VmHWM in /proc/self/status"))
}

/// Plans `file` through the record stream on the built-in machine, reading every record
/// and keeping none: the program read as it is planned (`finestep_gcode::stream_file`
/// into `plan_blocks`, as `finestep run` reads it), or with `whole` parsed whole first
/// (`plan_stream`). Prints `first` as the first record is read, then: periods, seconds
/// from `start` (the process's start) to the first record, seconds in all, peak RSS in
/// kB, and the most path elements the stream kept at once (run in a process of its own
/// by [`memory_figures`]).
pub fn plan_memory(file: &std::path::Path, whole: bool) -> anyhow::Result<()> {
    use std::io::Write;
    let start = crate::PROCESS_START.get().copied().unwrap_or_else(Instant::now);
    let name = file.display().to_string();
    let fail = |e: finestep_planner::ProgramError| anyhow::anyhow!("{}", e.in_file(&name));
    let config = MachineConfig::default();
    let program;
    let mut stream = if whole {
        program = finestep_gcode::parse_file(file)?;
        finestep_planner::plan_stream(&config, &program).map_err(fail)?
    } else {
        let blocks = finestep_gcode::stream_file(file, &finestep_gcode::Options::default())?;
        finestep_planner::plan_blocks(&config, blocks).map_err(fail)?
    };
    let (mut periods, mut first) = (0u64, None);
    for period in stream.periods.by_ref() {
        period.map_err(fail)?;
        if first.is_none() {
            first = Some(start.elapsed().as_secs_f64());
            let mut out = std::io::stdout().lock();
            writeln!(out, "first")?;
            out.flush()?;
        }
        periods += 1;
    }
    println!(
        "{periods} {} {} {} {}",
        first.unwrap_or(f64::NAN),
        start.elapsed().as_secs_f64(),
        peak_rss_kb()?,
        stream.periods.peak_elements_kept()
    );
    Ok(())
}

/// Peak memory of planning and the first record's latency, each case in a fresh
/// process (`finestep plan-memory FILE`) planning a program file: read as it is planned
/// and, for the long programs, parsed whole first as before. The latency is from the
/// spawn of the process to its `first` line (measured here) and from its own start.
fn memory_figures() -> anyhow::Result<()> {
    use std::io::BufRead;
    let exe = std::env::current_exe()?;
    let dir = std::env::temp_dir().join(format!("finestep-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    for (case, what) in [
        ("line", "G1 X1000000 F1666 (10.0 h)"),
        ("arc", "G2 X1000000 I500000 F6000"),
        ("program", "100 000 short G1 segments"),
        ("program-1m", "1 000 000 short G1 segments"),
    ] {
        let file = dir.join(format!("{case}.ngc"));
        std::fs::write(&file, memory_program(case)?)?;
        let ways: &[bool] = if case.starts_with("program") { &[false, true] } else { &[false] };
        for &whole in ways {
            let mut command = std::process::Command::new(&exe);
            command.arg("plan-memory").arg(&file).stdout(std::process::Stdio::piped());
            if whole {
                command.arg("--whole");
            }
            let spawned = Instant::now();
            let mut child = command.spawn()?;
            let stdout = child.stdout.take().ok_or_else(|| anyhow::anyhow!("plan-memory {case}: no stdout"))?;
            let (mut first_s, mut last) = (f64::NAN, String::new());
            for line in std::io::BufReader::new(stdout).lines() {
                let line = line?;
                if line == "first" {
                    first_s = spawned.elapsed().as_secs_f64();
                } else {
                    last = line;
                }
            }
            anyhow::ensure!(child.wait()?.success(), "plan-memory {case} failed");
            let fields: Vec<f64> = last.split_whitespace().filter_map(|w| w.parse().ok()).collect();
            anyhow::ensure!(fields.len() == 5, "plan-memory {case} printed {last:?}");
            println!(
                "  {:<44} {:>7.1} MB peak RSS  {:>11.0} periods  first record {:.3} s after the spawn ({:.3} s after main), all {:.1} s, {} elements kept at most",
                format!("plan {}: {what}", if whole { "(parsed whole)" } else { "(read as planned)" }),
                fields[3] / 1024.0,
                fields[0],
                first_s,
                fields[1],
                fields[2],
                fields[4]
            );
        }
        std::fs::remove_file(&file)?;
    }
    std::fs::remove_dir(&dir)?;
    Ok(())
}

/// Plan and interpolate throughput on a chain of NURBS, per profile.
fn nurbs_figures() -> anyhow::Result<()> {
    use finestep_planner::ProfileKind;
    const BLOCKS: usize = 500;
    let program = finestep_gcode::parse_str(&nurbs_program(BLOCKS), "nurbs.ngc")?;
    for profile in [ProfileKind::Trapezoid, ProfileKind::SCurve] {
        let Timed { elements, path_s, speeds_s, stream_s, periods, period_s } = plan_timed(profile, &program)?;
        println!(
            "  {:<44} {:>7.0} NURBS/s   ({} sub-pieces)",
            format!("plan NURBS: sub-pieces, look-ahead ({profile:?})"),
            BLOCKS as f64 / (path_s + speeds_s),
            elements
        );
        println!(
            "  {:<44} {:>7.2} M periods/s  ({:.1} s of machining)",
            format!("interpolate NURBS directly ({profile:?})"),
            periods / stream_s / 1e6,
            periods * period_s
        );
    }
    Ok(())
}

/// How much of the limits the plans use, per profile ([`finestep_planner::figures`]):
/// seed 002's star peaks over the limits, machining time over the independent lower
/// bound on every program of `tests/programs/` and on 20 000 short segments.
fn limit_figures() -> anyhow::Result<()> {
    let programs = finestep_planner::figures::test_programs()?;
    for profile in [finestep_planner::ProfileKind::Trapezoid, finestep_planner::ProfileKind::SCurve] {
        for line in finestep_planner::figures::limit_figures(&programs, profile)? {
            println!("  {line}");
        }
    }
    Ok(())
}

/// Parse, plan and interpolate throughput on a 100 000-segment program, per profile.
pub fn front_end() -> anyhow::Result<()> {
    use finestep_planner::ProfileKind;
    const MOVES: usize = 100_000;
    let text = cam_program(MOVES);
    // The best of three: one cold run on a shared machine varies by a factor of two.
    let mut parse_s = f64::INFINITY;
    let mut program = None;
    for _ in 0..3 {
        let start = Instant::now();
        program = Some(finestep_gcode::parse_str(&text, "cam.ngc")?);
        parse_s = parse_s.min(start.elapsed().as_secs_f64());
    }
    let program = program.expect("parsed");
    println!(
        "  {:<44} {:>7.2} M lines/s",
        "parse G-code (100 000 short G1 segments)",
        (MOVES + 2) as f64 / parse_s / 1e6
    );
    let (text, executed) = expression_program(MOVES);
    let mut loop_s = f64::INFINITY;
    for _ in 0..3 {
        let start = Instant::now();
        finestep_gcode::parse_str(&text, "loop.ngc")?;
        loop_s = loop_s.min(start.elapsed().as_secs_f64());
    }
    println!(
        "  {:<44} {:>7.2} M lines/s",
        "parse G-code (O-word loop, #params, [expr])",
        executed as f64 / loop_s / 1e6
    );
    for profile in [ProfileKind::Trapezoid, ProfileKind::SCurve] {
        let Timed { elements, path_s, speeds_s, stream_s, periods, period_s } = plan_timed(profile, &program)?;
        let name = format!("{profile:?}");
        println!(
            "  {:<44} {:>7.0} k moves/s  ({} elements with blends)",
            format!("plan: path, blends, look-ahead ({name})"),
            MOVES as f64 / (path_s + speeds_s) / 1e3,
            elements
        );
        println!(
            "  {:<44} {:>7.0} k moves/s  {:>9.2} M periods/s",
            format!("stream: look-ahead + interpolate ({name})"),
            MOVES as f64 / stream_s / 1e3,
            periods / stream_s / 1e6
        );
        println!(
            "  {:<44} {:>7.0} k moves/s  {:>9.2} M periods/s  ({:.1} s of machining)",
            format!("plan + interpolate ({name})"),
            MOVES as f64 / (path_s + stream_s) / 1e3,
            periods / (path_s + stream_s) / 1e6,
            periods * period_s
        );
    }
    nurbs_figures()?;
    limit_figures()?;
    memory_figures()
}

pub fn run(cycles: u64) -> anyhow::Result<()> {
    let machine = bench_machine()?;
    let period_clocks = machine.period_clocks;
    let periods = (cycles / u64::from(period_clocks)).max(1);
    let limit = u64::from(period_clocks) + 8;
    println!("finestep bench: {AXES} axes, P = {period_clocks} clocks, {periods} periods per figure, M cycles per CPU second of the simulating thread");

    let mut rtl = Rtl::new();
    let start = CpuClock::start();
    let n = drive(&machine, periods, |inputs, events| rtl.run_chunk(inputs, limit, events).cycles);
    report(&machine, "RTL alone (Verilator, event capture)", n, start.seconds());

    let mut model = Core::new(finestep_rtl_sys::params());
    let start = CpuClock::start();
    let n = drive(&machine, periods, |inputs, events| model.run_chunk(inputs, limit, events).cycles);
    report(&machine, "model per-clock step()", n, start.seconds());

    let mut model = Core::new(finestep_rtl_sys::params());
    let start = CpuClock::start();
    let n = drive(&machine, periods * 20, |inputs, events| model.run_chunk_fast(inputs, limit, events).cycles);
    report(&machine, "model fast path", n, start.seconds());

    for (what, path) in [
        ("lockstep RTL + model per-clock, compared", ModelPath::PerClock),
        ("lockstep RTL + model fast path, compared", ModelPath::Fast),
    ] {
        let mut harness = Harness::new("bench", path);
        let start = CpuClock::start();
        let mut inputs = inputs(&machine);
        harness.feed(&mut inputs, stream(periods))?;
        report(&machine, what, harness.cycle(), start.seconds());
    }
    Ok(())
}

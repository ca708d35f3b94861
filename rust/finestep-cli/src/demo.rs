//! The seed-000 demo: a roller grinder's X (wheel), Z (table) and C (indexing head) move
//! together along one line, interpolated every 2 ms with a trapezoidal feed. The host
//! driver streams the period records over SPI (pin level, clk/8) into the position
//! FIFO of the bus-level top; the Verilated RTL and the reference model run in lockstep,
//! every pin on every clock.

use std::path::Path;

use anyhow::{bail, Context};
use finestep_cosim::{TopLockstep, TraceDepth};
use finestep_host::stream::{self, StreamEvent};
use finestep_host::{Bus, Machine};
use finestep_model::limits::RateChecker;
use finestep_model::PeriodRecord;
use finestep_planner::MachineConfig;
use indicatif::{ProgressBar, ProgressStyle};

use crate::bus::BusTarget;
use crate::machine_setup::{self, BURST};
use crate::plot::{plot_axes, AxisTrace};
use crate::run::{run_program_on, ChipLacksPbp};

const AXIS_NAMES: [&str; 3] = ["X", "Z", "C"];
const AXIS_UNITS: [&str; 3] = ["mm", "mm", "deg"];
/// Steps per unit of X (wheel slide, mm), Z (table, mm) and C (indexing head, degree).
const STEPS_PER_UNIT: [f64; 3] = [1000.0, 400.0, 100.0];
/// Periods traced into the waveform (the start of the move: direction set-up, first steps).
const TRACED_PERIODS: u64 = 4;

/// The demo on the Verilated chip in lockstep with the model, or with `bus`, parts 1
/// and 2 (and 5) on that chip (a board, a served chip, the model alone); parts 3, 4 and 6
/// need the simulated machine on the chip's pins and run only in lockstep.
pub fn run(out: &Path, bus: Option<BusTarget>) -> anyhow::Result<()> {
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let bus = bus.unwrap_or(BusTarget::Lockstep);
    if bus.is_lockstep() {
        let mut chip = machine_setup::open(TopLockstep::motion("demo"))?;
        let line = part_1(&mut chip, out, &bus)?;
        let lockstep = chip.into_bus().into_link().into_target();
        let waveform = out.join(if finestep_rtl_sys::trace_is_fst() { "demo.fst" } else { "demo.vcd" });
        let traced = lockstep.cycle() - line.cycles + TRACED_PERIODS * u64::from(line.period_clocks);
        // The motion chip (what every board builds) is Verilated without tracing: its
        // waveform needs a traced build, which the crate does not make (build time).
        match lockstep.write_waveform(&waveform, TraceDepth::Ports, traced) {
            Ok(()) => println!("  waveform of the ports, first {TRACED_PERIODS} periods: {}", waveform.display()),
            Err(error) => println!("  waveform not written: {error}"),
        }
    } else {
        let mut chip = crate::bus::open(&bus, "demo", machine_setup::model_params().clock_hz)?;
        part_1(&mut chip, out, &bus)?;
    }

    println!();
    println!("finestep demo, part 2: a built-in part program (corners, an arc, a cutter-compensated contour)");
    let program = finestep_gcode::parse_str(DEMO_PART, "demo-part.ngc")?;
    run_program_on(&program, "demo-part.ngc", false, &bus, MachineConfig::default(), "<built-in>", out, None, &|| {
        Ok(())
    })?;
    if !bus.is_lockstep() {
        lathe_part(&bus, out)?;
        println!();
        println!(
            "finestep demo, parts 3, 4 and 6 (feedback, hand wheel, roller compensation, the gantry card): skipped on \
             {bus}; they need the simulated machine on the chip's pins (run `finestep demo` without --bus)"
        );
        return Ok(());
    }
    crate::demo_feedback::run()?;
    crate::roller::demo(out)?;
    lathe_part(&bus, out)?;
    crate::demo_gantry::run(out)
}

/// Seed 003's lathe part (`tests/programs/lathe_pbp.ngc`) on its machine
/// (`tests/machines/lathe_pbp.toml`).
const LATHE_PART: &str = include_str!("../../../tests/programs/lathe_pbp.ngc");
const LATHE_MACHINE: &str = include_str!("../../../tests/machines/lathe_pbp.toml");

/// Part 5: seed 003's lathe part in G18 G7 (a face, a taper, an arc shoulder), G1/G2/G3
/// by the chip's point-by-point interpolator, spindle and flood coolant on while it cuts,
/// on `bus` (in lockstep without --bus); skipped, saying why, on a chip without
/// `VERSION.HAS_PBP`.
fn lathe_part(bus: &BusTarget, out: &Path) -> anyhow::Result<()> {
    println!();
    println!(
        "finestep demo, part 5: seed 003's lathe part (G18 G7: a face, a taper, an arc shoulder) by point-by-point \
         comparison, spindle and flood coolant on"
    );
    let program = finestep_gcode::parse_str(LATHE_PART, "lathe_pbp.ngc")?;
    let config = MachineConfig::from_toml_str(LATHE_MACHINE, "lathe_pbp.toml")?;
    match run_program_on(&program, "lathe_pbp.ngc", false, bus, config, "lathe_pbp.toml", out, None, &|| Ok(())) {
        Err(error) if error.downcast_ref::<ChipLacksPbp>().is_some() => {
            println!("  skipped: {error}");
            Ok(())
        }
        result => result,
    }
}

/// What part 1's stream took, for the waveform of its first periods.
struct LineRun {
    cycles: u64,
    period_clocks: u32,
}

/// Part 1: the seed-000 line streamed on `chip`; checks the end positions, plots them.
fn part_1<B: Bus>(chip: &mut Machine<B>, out: &Path, bus: &BusTarget) -> anyhow::Result<LineRun> {
    let core = machine_setup::chip_limits(&chip.caps());
    let (config, resolved) =
        machine_setup::resolve(machine_setup::demo_config(&STEPS_PER_UNIT), core, "<demo part 1>")?;
    // X, Z and C in record slots 0, 1 and 2.
    let target = [-1.0, 10.0, 15.0];
    let feed_mm_s = 20.0;
    let records = machine_setup::plan_line(&config, [target[0], target[1], target[2], 0.0], feed_mm_s)?;
    let period_clocks = resolved.period_clocks;
    let mut checker = RateChecker::with_slots(period_clocks, &resolved.timing[..AXIS_NAMES.len()], resolved.step_slots);
    for (index, record) in records.iter().enumerate() {
        if let Err((axis, why)) = checker.check(record) {
            bail!("period {index}: axis {}: {why}", AXIS_NAMES.get(axis).unwrap_or(&"?"));
        }
    }

    println!(
        "finestep demo: seed 000 line X {:+} mm, Z {:+} mm, C {:+} deg at {} mm/s, T = {} ms, P = {} clocks at {} MHz",
        target[0],
        target[1],
        target[2],
        feed_mm_s,
        resolved.period_s * 1e3,
        period_clocks,
        resolved.clock_hz / 1e6
    );
    println!(
        "  {} period records streamed over SPI on {bus} (bursts of {BURST}, CRC-checked frames) into the FIFO;",
        records.len()
    );
    if bus.is_lockstep() {
        println!(
            "  RTL (Verilator) in lockstep with the reference model at the pins, every pin every clock (SCK = clk/8)"
        );
    }
    machine_setup::configure(chip, &resolved)?;
    // Counted from where the axes stand (a served chip or a board keeps its positions).
    let start = chip.positions()?.steps;
    let progress = ProgressBar::new(records.len() as u64)
        .with_style(ProgressStyle::with_template("  {bar:40} {pos}/{len} records queued {per_sec}")?);
    // The latched positions the host reads while it waits: (LATCH_TIME, steps).
    let mut samples = Vec::new();
    let report =
        stream::run(chip, records.iter().copied(), &machine_setup::stream_config(&resolved), |chip, event| {
            match event {
                StreamEvent::Queued { queued } => progress.set_position(queued),
                StreamEvent::Waited => {
                    let positions = chip.positions()?;
                    samples.push((positions.latch_time, positions.steps));
                }
            }
            Ok(())
        })?;
    progress.finish_and_clear();

    println!("  axis   steps moved   end position   commanded");
    let mut commanded = [0i64; 3];
    for record in &records {
        for (axis, total) in commanded.iter_mut().enumerate() {
            *total += i64::from(record.inc[axis].to_bits());
        }
    }
    for axis in 0..AXIS_NAMES.len() {
        let steps = report.end.steps[axis].wrapping_sub(start[axis]);
        let target = commanded[axis] as f64 / 65536.0;
        println!(
            "  {:<4} {:>13} {:>12.4} {:<3} {:>10.4} {}",
            AXIS_NAMES[axis],
            steps,
            f64::from(steps) / STEPS_PER_UNIT[axis],
            AXIS_UNITS[axis],
            target / STEPS_PER_UNIT[axis],
            AXIS_UNITS[axis]
        );
        if f64::from(steps) != target {
            bail!("axis {} ended at {steps} steps, commanded {target}", AXIS_NAMES[axis]);
        }
    }
    if report.stream.underruns != 0 {
        bail!("{} FIFO underruns", report.stream.underruns);
    }
    println!(
        "  {} bursts, 0 underruns;{} {} cycles ({:.3} s of machine time)",
        report.stream.bursts,
        if bus.is_lockstep() { " bit-exact over" } else { "" },
        report.cycles,
        report.cycles as f64 / resolved.clock_hz
    );

    // Commanded positions at the period boundaries; emitted ones where the host sampled
    // the latched POSITION registers, timed from the first boundary.
    let mut traces: Vec<AxisTrace> = (0..AXIS_NAMES.len()).map(|_| AxisTrace::default()).collect();
    let mut running = [0i64; 3];
    for record in std::iter::once(PeriodRecord::default()).chain(records.iter().copied()) {
        for (axis, trace) in traces.iter_mut().enumerate() {
            running[axis] += i64::from(record.inc[axis].to_bits());
            trace.commanded.push(running[axis] as f64 / 65536.0);
        }
    }
    for (latch_time, steps) in &samples {
        let t = f64::from(latch_time.wrapping_sub(report.first_boundary)) / resolved.clock_hz;
        for (axis, trace) in traces.iter_mut().enumerate() {
            trace.emitted.push((t, f64::from(steps[axis].wrapping_sub(start[axis]))));
        }
    }
    let png = out.join("demo.png");
    plot_axes(&png, &traces, &AXIS_NAMES, resolved.period_s)?;
    println!("  plot: {}", png.display());
    Ok(LineRun { cycles: report.cycles, period_clocks })
}

/// The demo's part program: an outside contour cut with cutter compensation (tool 3,
/// r = 0.5 mm), with a convex arc, a chamfer corner and square corners, blended (G64).
const DEMO_PART: &str = "\
( finestep demo part: an outside contour, compensated for tool 3, r = 0.5 mm )
G21 G90 G17 G64 P0.01
F6000
G0 X-4 Y-4
G42 D3
G1 X0 Y0
G1 X12
G3 X16 Y4 R4
G1 Y10
G1 X8 Y14
G1 X0
G1 Y0
G40
G1 X-4 Y-4
M2
";

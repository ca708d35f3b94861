//! The seed-000 demo: a roller grinder's X (wheel), Z (table) and C (indexing head) move
//! together along one line, interpolated every 2 ms with a trapezoidal feed. The host
//! driver streams the period records over SPI (pin level, clk/8) into the position
//! FIFO of the bus-level top; the Verilated RTL and the reference model run in lockstep,
//! every pin on every clock.

use std::path::Path;

use anyhow::{anyhow, bail, Context};
use finestep_cosim::{TopLockstep, TraceDepth};
use finestep_host::regs::{fifo_level, latch_time, status, underrun_count};
use finestep_host::{AxisSetup, Bus, Machine, PinHost, PinTiming, SpiBus};
use finestep_model::limits::{AxisTiming, RateChecker};
use finestep_model::PeriodRecord;
use finestep_planner::{interpolate_line, LineMove, Machine as Kinematics};
use indicatif::{ProgressBar, ProgressStyle};

use crate::plot::{plot_axes, AxisTrace};

/// The FPGA clock of the demo, Hz.
pub const CLOCK_HZ: f64 = 50e6;
const AXIS_NAMES: [&str; 3] = ["X", "Z", "C"];
const AXIS_UNITS: [&str; 3] = ["mm", "mm", "deg"];
/// Periods traced into the waveform (the start of the move: direction set-up, first steps).
const TRACED_PERIODS: u64 = 4;
/// Records per SPI burst and the FIFO level at which motion starts.
const BURST: usize = 32;
const START_LEVEL: u16 = 16;

/// Drive timing of the demo's drives, in clocks at 50 MHz: 2 us step, 2 us space,
/// 5 us dir setup and hold.
pub fn demo_axis() -> AxisSetup {
    AxisSetup { step_len: 100, step_space: 100, dir_setup: 250, dir_hold: 250, out_mode: 0, invert: 0 }
}

/// The same drive timing as the core's axis configuration (for the core-level bench).
pub fn demo_axis_config() -> finestep_model::AxisConfig {
    let setup = demo_axis();
    finestep_model::AxisConfig {
        step_len: setup.step_len,
        step_space: setup.step_space,
        dir_setup: setup.dir_setup,
        dir_hold: setup.dir_hold,
        mode: 0,
        invert: 0,
        enable: true,
    }
}

fn bus_error(e: finestep_host::BusError) -> anyhow::Error {
    anyhow!("{e}")
}

pub fn run(out: &Path) -> anyhow::Result<()> {
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let kinematics = Kinematics::new(vec![1000.0, 400.0, 100.0], 0.002);
    let line = LineMove {
        from_mm: vec![0.0, 0.0, 0.0],
        to_mm: vec![-1.0, 10.0, 15.0],
        feed_mm_s: 20.0,
        start_speed_mm_s: 1.0,
        accel_mm_s2: 100.0,
    };
    let records = interpolate_line(&kinematics, &line)?;
    let period_clocks = (kinematics.period_s * CLOCK_HZ).round() as u32;
    let setup = demo_axis();
    let timing = AxisTiming { step_len: setup.step_len, step_space: setup.step_space, dir_setup: setup.dir_setup, dir_hold: setup.dir_hold };
    let mut checker = RateChecker::new(period_clocks, &[timing; 3]);
    for (index, record) in records.iter().enumerate() {
        if let Err((axis, why)) = checker.check(record) {
            bail!("period {index}: axis {}: {why}", AXIS_NAMES.get(axis).unwrap_or(&"?"));
        }
    }

    println!(
        "finestep demo: seed 000 line X {:+} mm, Z {:+} mm, C {:+} deg at {} mm/s, T = {} ms, P = {} clocks at {} MHz",
        line.to_mm[0], line.to_mm[1], line.to_mm[2], line.feed_mm_s,
        kinematics.period_s * 1e3, period_clocks, CLOCK_HZ / 1e6
    );
    println!(
        "  {} period records streamed over SPI (SCK = clk/8, bursts of {BURST}, CRC-checked frames) into the FIFO;",
        records.len()
    );
    println!("  RTL (Verilator) in lockstep with the reference model at the pins, every pin every clock");

    let mut host = PinHost::new(TopLockstep::new("demo"), PinTiming::default());
    host.reset(4).map_err(bus_error)?;
    let mut machine = Machine::connect(SpiBus::new(host, 4)).map_err(bus_error)?;
    let caps = machine.caps();
    println!("  core: {} axes, FIFO {} records, clock {} Hz", caps.n_axes, caps.fifo_depth, caps.clock_hz);
    for axis in 0..AXIS_NAMES.len() {
        machine.configure_axis(axis, &setup).map_err(bus_error)?;
    }
    machine.enable_axes(0b111).map_err(bus_error)?;
    machine.set_period(period_clocks).map_err(bus_error)?;
    machine.set_start_level(START_LEVEL).map_err(bus_error)?;
    machine.clear_faults_and_errors().map_err(bus_error)?;

    // Queue the first records, then start: the first period boundary after RUN takes
    // record 0, and the position latch holds that boundary's time.
    let mut pending = records.iter().copied().peekable();
    let first: Vec<PeriodRecord> = pending.by_ref().take(2 * BURST).collect();
    for burst in first.chunks(BURST) {
        machine.bus().push_records(burst).map_err(bus_error)?;
    }
    machine.set_control(true, false, true).map_err(bus_error)?;
    let t_first = f64::from(machine.bus().read_one(latch_time::ADDR).map_err(bus_error)?) / CLOCK_HZ;

    let progress = ProgressBar::new(records.len() as u64)
        .with_style(ProgressStyle::with_template("  {bar:40} {pos}/{len} records queued {per_sec}")?);
    progress.inc(first.len() as u64);
    let mut samples: Vec<(f64, Vec<i32>)> = Vec::new();
    let mut bursts = first.chunks(BURST).len() as u64;
    let poll = u64::from(period_clocks) / 2;
    let start_clock = machine.bus().link_mut().target().cycle();
    loop {
        let bus = machine.bus();
        let level_word = bus.read_one(fifo_level::ADDR).map_err(bus_error)?;
        let free = fifo_level::FREE.get(level_word) as usize;
        let left = pending.len();
        if left > 0 && (free >= BURST || (free >= left)) {
            let burst: Vec<PeriodRecord> = pending.by_ref().take(free.min(BURST)).collect();
            bus.push_records(&burst).map_err(bus_error)?;
            bursts += 1;
            progress.inc(burst.len() as u64);
            continue;
        }
        let streaming = status::STREAMING.get(bus.read_one(status::ADDR).map_err(bus_error)?) != 0;
        if left == 0 && fifo_level::LEVEL.get(level_word) == 0 && !streaming {
            break;
        }
        bus.wait(poll).map_err(bus_error)?;
        let positions = machine.positions().map_err(bus_error)?;
        samples.push((f64::from(positions.latch_time) / CLOCK_HZ, positions.steps));
    }
    progress.finish_and_clear();
    machine.bus().wait(2 * u64::from(period_clocks)).map_err(bus_error)?;
    let underruns = machine.bus().read_one(underrun_count::ADDR).map_err(bus_error)?;
    let positions = machine.positions().map_err(bus_error)?;
    let cycles = machine.bus().link_mut().target().cycle() - start_clock;

    println!("  axis   final steps   final position   commanded");
    let mut commanded = [0i64; 3];
    for record in &records {
        for (axis, total) in commanded.iter_mut().enumerate() {
            *total += i64::from(record.inc[axis].to_bits());
        }
    }
    for axis in 0..AXIS_NAMES.len() {
        let steps = positions.steps[axis];
        let target = commanded[axis] as f64 / 65536.0;
        println!(
            "  {:<4} {:>13} {:>12.4} {:<3} {:>10.4} {}",
            AXIS_NAMES[axis], steps,
            f64::from(steps) / kinematics.steps_per_unit[axis], AXIS_UNITS[axis],
            target / kinematics.steps_per_unit[axis], AXIS_UNITS[axis]
        );
        if f64::from(steps) != target {
            bail!("axis {} ended at {steps} steps, commanded {target}", AXIS_NAMES[axis]);
        }
    }
    if underruns != 0 {
        bail!("{underruns} FIFO underruns");
    }
    println!(
        "  {bursts} bursts, 0 underruns; bit-exact over {cycles} cycles ({:.3} s of machine time)",
        cycles as f64 / CLOCK_HZ
    );

    let waveform = out.join(if finestep_rtl_sys::trace_is_fst() { "demo.fst" } else { "demo.vcd" });
    let lockstep = machine.bus().link_mut().target();
    let traced = start_clock + TRACED_PERIODS * u64::from(period_clocks);
    lockstep.write_waveform(&waveform, TraceDepth::Ports, traced).map_err(|e| anyhow!(e))?;

    // Commanded positions at the period boundaries; emitted ones where the host sampled
    // the latched POSITION registers.
    let mut traces: Vec<AxisTrace> = (0..AXIS_NAMES.len()).map(|_| AxisTrace::default()).collect();
    let mut running = [0i64; 3];
    for record in std::iter::once(PeriodRecord::default()).chain(records.iter().copied()) {
        for (axis, trace) in traces.iter_mut().enumerate() {
            running[axis] += i64::from(record.inc[axis].to_bits());
            trace.commanded.push(running[axis] as f64 / 65536.0);
        }
    }
    for (t, steps) in &samples {
        for (axis, trace) in traces.iter_mut().enumerate() {
            trace.emitted.push((t - t_first, f64::from(steps[axis])));
        }
    }
    let png = out.join("demo.png");
    plot_axes(&png, &traces, &AXIS_NAMES, kinematics.period_s)?;
    println!("  waveform of the ports, first {TRACED_PERIODS} periods: {}", waveform.display());
    println!("  plot: {}", png.display());
    Ok(())
}

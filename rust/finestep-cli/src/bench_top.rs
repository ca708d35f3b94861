//! Throughput of the chip-level simulation (not timed tests): a 4-axis move streamed
//! over SPI by the host driver into the bus-level top, on the Verilated RTL alone, the
//! model alone and both in lockstep: the motion chip without the hand wheel and the jog
//! (as the HX8K and MachXO3 boards build it; the move turns no wheel), then the lockstep
//! of the motion chip with them, then the RTL and the lockstep of `finestep_top`'s
//! defaults (with the spindle and the logic outputs).

use std::time::Instant;

use anyhow::bail;
use finestep_cosim::{rtl_top_params, rtl_top_params_of, ModelPins, RtlPins, TopLockstep, TopVariant};
use finestep_host::stream;
use finestep_host::PinTarget;
use finestep_model::top::Top;
use finestep_model::{Increment, PeriodRecord};
use finestep_planner::MachineConfig;

use crate::bench::{report, CpuClock};
use crate::bus::BusTarget;
use crate::machine_setup;

const AXES: usize = 4;

fn records(periods: usize) -> Vec<PeriodRecord> {
    (0..periods)
        .map(|k| {
            let mut record = PeriodRecord::default();
            for axis in 0..AXES {
                let amplitude = 40.0 + 50.0 * axis as f64;
                let phase = k as f64 * std::f64::consts::TAU / 400.0 + axis as f64;
                record.inc[axis] = Increment::from_num(amplitude * phase.sin());
            }
            record.flags = u8::from(k + 1 == periods);
            record
        })
        .collect()
}

/// Streams `periods` records into `target` over SPI with the host driver's streamer, the
/// built-in machine resolved against the chip; prints the figure as `what`.
fn streamed<T: PinTarget>(what: &str, target: T, periods: usize, cycles: impl Fn(&T) -> u64) -> anyhow::Result<()> {
    let mut machine = machine_setup::open(target)?;
    let core = machine_setup::chip_limits(&machine.caps());
    let (_, resolved) = machine_setup::resolve(MachineConfig::default(), core, "<built-in>")?;
    machine_setup::configure(&mut machine, &resolved)?;
    let started = CpuClock::start();
    let begin = cycles(machine.bus().link().target());
    let config = machine_setup::stream_config(&resolved);
    let streamed = stream::run(&mut machine, records(periods), &config, |_, _| Ok(()))?;
    if streamed.stream.underruns != 0 {
        bail!("{} underruns while benchmarking", streamed.stream.underruns);
    }
    let seconds = started.seconds();
    report(&resolved, what, cycles(machine.bus().link().target()) - begin, seconds);
    Ok(())
}

/// The same move on the chip at `target` (`finestep bench --bus`): a board's figure is
/// its link's, cycles by the chip's LATCH_TIME against the wall clock.
pub fn on_bus(target: &BusTarget, periods: usize) -> anyhow::Result<()> {
    let mut machine = crate::bus::open(target, "bench", rtl_top_params().clock_hz)?;
    let core = machine_setup::chip_limits(&machine.caps());
    let (_, resolved) = machine_setup::resolve(MachineConfig::default(), core, "<built-in>")?;
    machine_setup::configure(&mut machine, &resolved)?;
    println!("finestep bench on {target}: {AXES} axes, P = {} clocks, {periods} periods", resolved.period_clocks);
    let started = Instant::now();
    let config = machine_setup::stream_config(&resolved);
    let streamed = stream::run(&mut machine, records(periods), &config, |_, _| Ok(()))?;
    if streamed.stream.underruns != 0 {
        bail!("{} underruns while benchmarking on {target}", streamed.stream.underruns);
    }
    report(&resolved, &format!("streamed over SPI on {target}"), streamed.cycles, started.elapsed().as_secs_f64());
    Ok(())
}

/// Prints the chip-level figures for a move of `periods` periods of the built-in machine.
pub fn run(periods: usize) -> anyhow::Result<()> {
    let machine = crate::bench::bench_machine()?;
    println!(
        "finestep bench, chip level: {AXES} axes, P = {} clocks, {periods} periods streamed over SPI at clk/8, per CPU second",
        machine.period_clocks
    );
    // The motion chip, as every board top builds it (no spindle, no logic outputs), and
    // without the hand wheel and the jog, which this move does not use.
    let motion = TopVariant::MotionNoMpg;
    streamed("RTL top alone (Verilator), SPI-driven", RtlPins::of(motion), periods, RtlPins::cycle)?;
    let model = ModelPins(Top::new(rtl_top_params_of(motion)));
    streamed("model top alone, per clock, SPI-driven", model, periods, ModelPins::cycle)?;
    let lockstep = TopLockstep::motion_no_mpg("bench");
    streamed("lockstep RTL + model top, every pin compared", lockstep, periods, TopLockstep::cycle)?;
    // The motion chip with the hand wheel and the jog (as the ECP5 board builds it).
    let wheel_lockstep = TopLockstep::motion("bench-mpg");
    streamed("lockstep, motion chip with hand wheel + jog", wheel_lockstep, periods, TopLockstep::cycle)?;
    // finestep_top's defaults: the same move with the spindle and the logic outputs built.
    let full = TopVariant::Full;
    streamed("RTL top with spindle + outputs (finestep_top's defaults)", RtlPins::of(full), periods, RtlPins::cycle)?;
    let full_lockstep = TopLockstep::of(full, "bench-full");
    streamed("lockstep, top with spindle + outputs", full_lockstep, periods, TopLockstep::cycle)?;
    Ok(())
}

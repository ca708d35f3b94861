//! Throughput of the chip-level simulation (not timed tests): a 4-axis move streamed
//! over SPI by the host driver into the bus-level top, on the Verilated RTL alone, the
//! model alone and both in lockstep.

use std::time::Instant;

use anyhow::anyhow;
use finestep_cosim::{rtl_top_params, ModelPins, RtlPins, TopLockstep};
use finestep_host::stream::{stream, wait_idle, StreamConfig};
use finestep_host::{AxisSetup, Machine, PinHost, PinTarget, PinTiming, SpiBus};
use finestep_model::top::Top;
use finestep_model::{Increment, PeriodRecord};

use crate::bench::report;

const PERIOD_CLOCKS: u32 = 50_000;
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

/// Streams `periods` records into `target` over SPI; returns (clocks, seconds).
fn streamed<T: PinTarget>(target: T, periods: usize, cycles: impl Fn(&T) -> u64) -> anyhow::Result<(u64, f64)> {
    let e = |e: finestep_host::BusError| anyhow!("{e}");
    let mut host = PinHost::new(target, PinTiming::default());
    host.reset(4).map_err(e)?;
    let mut machine = Machine::connect(SpiBus::new(host, AXES)).map_err(e)?;
    let setup = AxisSetup { step_len: 100, step_space: 100, dir_setup: 250, dir_hold: 250, ..AxisSetup::default() };
    for axis in 0..AXES {
        machine.configure_axis(axis, &setup).map_err(e)?;
    }
    machine.enable_axes(0xF).map_err(e)?;
    machine.set_period(PERIOD_CLOCKS).map_err(e)?;
    machine.set_start_level(16).map_err(e)?;
    machine.clear_faults_and_errors().map_err(e)?;
    machine.set_control(true, false, true).map_err(e)?;
    let started = Instant::now();
    let begin = cycles(machine.bus().link_mut().target());
    let report = stream(machine.bus(), records(periods), StreamConfig { burst: 32, poll_clocks: 25_000 }).map_err(e)?;
    wait_idle(machine.bus(), 25_000, u64::from(PERIOD_CLOCKS) * periods as u64 * 2).map_err(e)?;
    if report.underruns != 0 {
        return Err(anyhow!("{} underruns while benchmarking", report.underruns));
    }
    Ok((cycles(machine.bus().link_mut().target()) - begin, started.elapsed().as_secs_f64()))
}

/// Prints the chip-level figures for a move of `periods` periods of 1 ms.
pub fn run(periods: usize) -> anyhow::Result<()> {
    println!("finestep bench, chip level: {AXES} axes, P = {PERIOD_CLOCKS} clocks, {periods} periods streamed over SPI at clk/8");
    let (cycles, seconds) = streamed(RtlPins::new(), periods, RtlPins::cycle)?;
    report("RTL top alone (Verilator), SPI-driven", cycles, seconds);
    let (cycles, seconds) = streamed(ModelPins(Top::new(rtl_top_params())), periods, ModelPins::cycle)?;
    report("model top alone, per clock, SPI-driven", cycles, seconds);
    let (cycles, seconds) = streamed(TopLockstep::new("bench"), periods, TopLockstep::cycle)?;
    report("lockstep RTL + model top, every pin compared", cycles, seconds);
    Ok(())
}

//! Running period records on the simulated chip the way a host does on a board: the
//! host driver configures the core over SPI (pin level, SCK = clk/8), pre-fills the
//! FIFO, starts the run and keeps the FIFO fed in bursts, sampling the latched positions
//! while it waits.

use anyhow::{anyhow, bail};
use finestep_host::regs::{fifo_level, latch_time, status, underrun_count};
use finestep_host::{AxisSetup, Bus, BusError, Machine, PinHost, PinTarget, PinTiming, SpiBus};
use finestep_model::PeriodRecord;

/// Records per SPI burst.
pub const BURST: usize = 32;

/// How the chip is set up for a stream.
pub struct StreamSetup {
    /// The period in clocks.
    pub period_clocks: u32,
    /// Drive timing and output mode per axis (axes beyond the list are left disabled).
    pub axes: Vec<AxisSetup>,
    /// The core clock, Hz (for sample times).
    pub clock_hz: f64,
}

/// What a stream did.
pub struct Streamed {
    /// Final latched positions, steps per axis.
    pub positions: Vec<i32>,
    /// Clock cycles from the start of the stream to the end.
    pub cycles: u64,
    /// SPI bursts of records.
    pub bursts: u64,
    /// Underruns counted by the core (0 unless the host fell behind).
    pub underruns: u32,
    /// Latched positions read while waiting: (time from the first boundary in s, steps).
    pub samples: Vec<(f64, Vec<i32>)>,
}

fn bus_error(e: BusError) -> anyhow::Error {
    anyhow!("{e}")
}

/// Streams `records` into the chip behind `target`; `progress` gets the records queued
/// so far. Returns the report and the target (for waveforms).
pub fn stream_over_spi<T: PinTarget>(
    target: T,
    setup: &StreamSetup,
    records: &[PeriodRecord],
    mut progress: impl FnMut(usize),
) -> anyhow::Result<(Streamed, T)> {
    let mut host = PinHost::new(target, PinTiming::default());
    host.reset(4).map_err(bus_error)?;
    let mut machine = Machine::connect(SpiBus::new(host, 4)).map_err(bus_error)?;
    let caps = machine.caps();
    if setup.axes.len() > caps.n_axes {
        bail!("{} axes configured, the core has {}", setup.axes.len(), caps.n_axes);
    }
    for (axis, axis_setup) in setup.axes.iter().enumerate() {
        machine.configure_axis(axis, axis_setup).map_err(bus_error)?;
    }
    machine.enable_axes((1 << setup.axes.len()) - 1).map_err(bus_error)?;
    machine.set_period(setup.period_clocks).map_err(bus_error)?;
    machine.set_start_level(1).map_err(bus_error)?;
    machine.clear_faults_and_errors().map_err(bus_error)?;

    // Queue the first records, then start: the first period boundary after RUN takes
    // record 0, and the position latch then holds that boundary's time.
    let mut queued = 0;
    let mut bursts = 0u64;
    for burst in records[..records.len().min(2 * BURST)].chunks(BURST) {
        machine.bus().push_records(burst).map_err(bus_error)?;
        queued += burst.len();
        bursts += 1;
    }
    progress(queued);
    let before_run = machine.positions().map_err(bus_error)?.latch_time;
    machine.set_control(true, false, true).map_err(bus_error)?;
    let first_boundary = machine.bus().read_one(latch_time::ADDR).map_err(bus_error)?;
    let seconds = |clock: u32| f64::from(clock.wrapping_sub(first_boundary)) / setup.clock_hz;

    let mut samples = Vec::new();
    let poll = u64::from(setup.period_clocks) / 2;
    loop {
        let level_word = machine.bus().read_one(fifo_level::ADDR).map_err(bus_error)?;
        let free = fifo_level::FREE.get(level_word) as usize;
        let left = records.len() - queued;
        if left > 0 && (free >= BURST || free >= left) {
            let take = free.min(BURST).min(left);
            machine.bus().push_records(&records[queued..queued + take]).map_err(bus_error)?;
            queued += take;
            bursts += 1;
            progress(queued);
            continue;
        }
        let streaming = status::STREAMING.get(machine.bus().read_one(status::ADDR).map_err(bus_error)?) != 0;
        if left == 0 && fifo_level::LEVEL.get(level_word) == 0 && !streaming {
            break;
        }
        machine.bus().wait(poll).map_err(bus_error)?;
        let positions = machine.positions().map_err(bus_error)?;
        samples.push((seconds(positions.latch_time), positions.steps));
    }
    machine.bus().wait(2 * u64::from(setup.period_clocks)).map_err(bus_error)?;
    let underruns = machine.bus().read_one(underrun_count::ADDR).map_err(bus_error)?;
    let end = machine.positions().map_err(bus_error)?;
    let cycles = u64::from(end.latch_time.wrapping_sub(before_run));
    let target = machine.into_bus().into_link().into_target();
    Ok((Streamed { positions: end.steps, cycles, bursts, underruns, samples }, target))
}

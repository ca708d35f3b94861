//! Streaming period records into the position FIFO: the host's half of seed 000's
//! position-control buffer, which must never run dry during a move.
//!
//! - [`run`]: a whole run as a host does it on a board: pre-fill the FIFO, start, keep
//!   it fed in bursts, wait until the last record ran, and report the final positions.
//! - [`stream`] and [`wait_idle`]: the two halves of it, for a core already started.
//!
//! [`run`] and the `_observed` forms call an observer with the machine after every
//! burst and every wait, e.g. to sample the latched positions, poll the probe or drive a
//! progress display; an error it returns ends the stream.
//!
//! ```no_run
//! # fn demo<B: finestep_host::Bus>(machine: &mut finestep_host::Machine<B>,
//! #         records: &[finestep_interface::PeriodRecord]) -> Result<(), finestep_host::BusError> {
//! use finestep_host::stream::{run, StreamConfig};
//! let report = run(machine, records.iter().copied(), &StreamConfig::default(), |_, _| Ok(()))?;
//! assert_eq!(report.stream.underruns, 0);
//! # Ok(()) }
//! ```

use finestep_interface::PeriodRecord;

use crate::frame::MAX_COUNT;
use crate::regs::{fifo_level, latch_time, start_level, status, underrun_count};
use crate::{Bus, BusError, Machine, Positions};

/// How the streamer polls and fills.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StreamConfig {
    /// Records per burst at most (<= 255).
    pub burst: usize,
    /// Clocks to wait when the FIFO has less room than a burst.
    pub poll_clocks: u64,
    /// [`run`]: records queued before the run starts (the FIFO's depth at most).
    pub prefill: usize,
    /// [`run`]: the E-stop input's polarity written with the run request.
    pub estop_active_high: bool,
    /// [`run`]: whether the run request arms the watchdog.
    pub watchdog: bool,
    /// The longest one record may run, clocks (0: one period). A point-by-point record
    /// (the flag PBP) runs its decisions however long they take: the waits for the last
    /// records give up after twice the FIFO's records of this length.
    pub record_clocks_max: u64,
}

impl Default for StreamConfig {
    /// Bursts of 32, a poll every 2000 clocks, two bursts before the start, E-stop
    /// active high, no watchdog, records of one period.
    fn default() -> Self {
        StreamConfig {
            burst: 32,
            poll_clocks: 2000,
            prefill: 64,
            estop_active_high: true,
            watchdog: false,
            record_clocks_max: 0,
        }
    }
}

/// What the streamer tells its observer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StreamEvent {
    /// A burst went into the FIFO: `queued` records so far.
    Queued {
        /// Records queued so far.
        queued: u64,
    },
    /// `poll_clocks` passed while the FIFO had no room for a burst, or while the last
    /// records ran.
    Waited,
}

/// What a stream did.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct StreamReport {
    /// Records queued.
    pub records: u64,
    /// Bursts sent.
    pub bursts: u64,
    /// FIFO level reads.
    pub polls: u64,
    /// Underruns counted by the core during the stream (UNDERRUN_COUNT difference).
    pub underruns: u16,
}

/// What a [`run`] did.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RunReport {
    /// Records, bursts and polls of the whole run (pre-fill included), and the underruns
    /// the core counted from before the pre-fill to the end.
    pub stream: StreamReport,
    /// `LATCH_TIME` read just after the run request: the timestamp of the first period
    /// boundary, which takes the first record.
    pub first_boundary: u32,
    /// Clock cycles from just before the run request to the final positions.
    pub cycles: u64,
    /// The positions after the last record ran and the step trains settled.
    pub end: Positions,
}

/// Where the streamer's loops run: a bare bus, or a whole machine (then the observer
/// may use every [`Machine`] method: positions, probe, feedback).
trait Feed {
    type Bus: Bus;
    fn feed_bus(&mut self) -> &mut Self::Bus;
}

impl<B: Bus> Feed for Machine<B> {
    type Bus = B;
    fn feed_bus(&mut self) -> &mut B {
        self.bus()
    }
}

struct Bare<'a, B>(&'a mut B);

impl<B: Bus> Feed for Bare<'_, B> {
    type Bus = B;
    fn feed_bus(&mut self) -> &mut B {
        self.0
    }
}

fn underruns<B: Bus>(bus: &mut B) -> Result<u16, BusError> {
    Ok(underrun_count::COUNT.get(bus.read_one(underrun_count::ADDR)?) as u16)
}

/// `STATUS` and `FIFO_LEVEL` in one read (adjacent registers): the streamer's poll. A
/// halt (E-stop, watchdog, the gantry's alarm) flushes the FIFO and clears `RUN`, so the
/// room that appears then is not records having run: every poll looks at `HALT` first.
struct Poll {
    status: u32,
    free: usize,
}

const _: () = assert!(fifo_level::ADDR == status::ADDR + 1, "STATUS and FIFO_LEVEL are read in one frame");

fn poll<B: Bus>(bus: &mut B) -> Result<Poll, BusError> {
    let mut words = [0u32; 2];
    bus.read(status::ADDR, &mut words)?;
    let [status, level] = words;
    if status::HALT.get(status) != 0 {
        return Err(BusError::Halted { status });
    }
    Ok(Poll { status, free: fifo_level::FREE.get(level) as usize })
}

/// Queues `records` as the FIFO makes room. Ends with [`BusError::Halted`] at the first
/// poll that finds the core halted, and, with `stall_clocks`, with [`BusError::Stalled`]
/// once the room has not grown for that many clocks of waiting (`RUN` cleared by
/// another, or a record running far longer than the configuration says).
fn queue<F: Feed>(
    target: &mut F,
    records: impl IntoIterator<Item = PeriodRecord>,
    config: &StreamConfig,
    stall_clocks: Option<u64>,
    mut observe: impl FnMut(&mut F, StreamEvent) -> Result<(), BusError>,
) -> Result<StreamReport, BusError> {
    let burst_max = config.burst.clamp(1, MAX_COUNT);
    let underruns_before = underruns(target.feed_bus())?;
    let mut report = StreamReport::default();
    let mut records = records.into_iter().peekable();
    let mut burst = Vec::with_capacity(burst_max);
    // Clocks waited since the room last grew, and that room.
    let (mut stalled, mut room) = (0u64, 0usize);
    while records.peek().is_some() {
        let bus = target.feed_bus();
        let Poll { status: word, free } = poll(bus)?;
        report.polls += 1;
        if free > room {
            stalled = 0;
        }
        room = free;
        if free < burst_max {
            // Fill only in whole bursts while more than a burst is left, so the frame
            // overhead stays small; the tail goes as soon as it fits.
            let tail_fits = records.size_hint().1.is_some_and(|left| left <= free) && free > 0;
            if !tail_fits {
                if stall_clocks.is_some_and(|limit| stalled >= limit) {
                    return Err(BusError::Stalled { clocks: stalled, status: word });
                }
                bus.wait(config.poll_clocks)?;
                stalled += config.poll_clocks;
                observe(target, StreamEvent::Waited)?;
                continue;
            }
        }
        burst.clear();
        burst.extend(records.by_ref().take(free.min(burst_max)));
        room -= burst.len();
        bus.push_records(&burst)?;
        report.records += burst.len() as u64;
        report.bursts += 1;
        observe(target, StreamEvent::Queued { queued: report.records })?;
    }
    report.underruns = underruns(target.feed_bus())?.wrapping_sub(underruns_before);
    Ok(report)
}

fn idle<F: Feed>(
    target: &mut F,
    poll_clocks: u64,
    max_clocks: u64,
    mut observe: impl FnMut(&mut F, StreamEvent) -> Result<(), BusError>,
) -> Result<(), BusError> {
    let mut waited = 0;
    loop {
        let bus = target.feed_bus();
        // FIFO_LEVEL, then STATUS: an empty FIFO and a closed gate after it is the end.
        let level = fifo_level::LEVEL.get(bus.read_one(fifo_level::ADDR)?);
        let word = bus.read_one(status::ADDR)?;
        // A halt flushes the FIFO: an empty FIFO then is not the end of the records.
        if status::HALT.get(word) != 0 {
            return Err(BusError::Halted { status: word });
        }
        if level == 0 && status::STREAMING.get(word) == 0 {
            return Ok(());
        }
        if waited >= max_clocks {
            return Err(BusError::StillStreaming { clocks: waited });
        }
        bus.wait(poll_clocks)?;
        waited += poll_clocks;
        observe(target, StreamEvent::Waited)?;
    }
}

/// The longest wait for the last records: twice the FIFO's records (and two more) of a
/// period or of [`StreamConfig::record_clocks_max`], whichever is longer.
fn idle_limit(fifo_depth: usize, period: u64, config: &StreamConfig) -> u64 {
    2 * (fifo_depth as u64 + 2) * period.max(config.record_clocks_max)
}

/// Queues every record of `records` into a running core, keeping the FIFO as full as
/// the bursts allow, and returns once the last one is queued (not executed: see
/// [`wait_idle`]).
pub fn stream<B: Bus>(
    bus: &mut B,
    records: impl IntoIterator<Item = PeriodRecord>,
    config: StreamConfig,
) -> Result<StreamReport, BusError> {
    queue(&mut Bare(bus), records, &config, None, |_, _| Ok(()))
}

/// [`stream`] on a machine, calling `observe` after every burst and every wait.
pub fn stream_observed<B: Bus>(
    machine: &mut Machine<B>,
    records: impl IntoIterator<Item = PeriodRecord>,
    config: &StreamConfig,
    observe: impl FnMut(&mut Machine<B>, StreamEvent) -> Result<(), BusError>,
) -> Result<StreamReport, BusError> {
    let limit = idle_limit(machine.caps().fifo_depth, u64::from(machine.period_clocks()), config);
    queue(machine, records, config, Some(limit), observe)
}

/// Waits until the FIFO is empty and the gate has closed (the last record ran), polling
/// every `poll_clocks`; gives up after `max_clocks` with [`BusError::StillStreaming`].
pub fn wait_idle<B: Bus>(bus: &mut B, poll_clocks: u64, max_clocks: u64) -> Result<(), BusError> {
    idle(&mut Bare(bus), poll_clocks, max_clocks, |_, _| Ok(()))
}

/// [`wait_idle`] on a machine, calling `observe` after every wait.
pub fn wait_idle_observed<B: Bus>(
    machine: &mut Machine<B>,
    poll_clocks: u64,
    max_clocks: u64,
    observe: impl FnMut(&mut Machine<B>, StreamEvent) -> Result<(), BusError>,
) -> Result<(), BusError> {
    idle(machine, poll_clocks, max_clocks, observe)
}

/// Runs `records` on a configured, stopped core: queues the first `config.prefill`
/// records, requests the run (the first period boundary after it takes the first record,
/// and the position latch then holds that boundary's time), keeps the FIFO fed, waits
/// until the last record ran and two more periods for the step trains to settle, and
/// reads the final positions. `observe` is called after every burst (the count includes
/// the pre-fill) and every wait. A core halted before the start, or during the run, ends
/// it with [`BusError::Halted`] (before the pre-fill is written; at the first poll after
/// the halt).
pub fn run<B: Bus>(
    machine: &mut Machine<B>,
    records: impl IntoIterator<Item = PeriodRecord>,
    config: &StreamConfig,
    mut observe: impl FnMut(&mut Machine<B>, StreamEvent) -> Result<(), BusError>,
) -> Result<RunReport, BusError> {
    let burst_max = config.burst.clamp(1, MAX_COUNT);
    let period = u64::from(machine.period_clocks());
    let fifo_depth = machine.caps().fifo_depth;
    // A halted core would take the pre-fill and never run it: refused before anything
    // is written.
    poll(machine.bus())?;
    let underruns_before = underruns(machine.bus())?;
    let mut records = records.into_iter();
    let first: Vec<PeriodRecord> = records.by_ref().take(config.prefill.min(fifo_depth)).collect();
    let mut prefill = StreamReport::default();
    for burst in first.chunks(burst_max) {
        machine.bus().push_records(burst)?;
        prefill.records += burst.len() as u64;
        prefill.bursts += 1;
    }
    if prefill.records > 0 {
        observe(machine, StreamEvent::Queued { queued: prefill.records })?;
    }
    let before_run = machine.positions()?.latch_time;
    machine.set_control(true, config.watchdog, config.estop_active_high)?;
    let first_boundary = machine.bus().read_one(latch_time::ADDR)?;
    let streamed =
        queue(machine, records, config, Some(idle_limit(fifo_depth, period, config)), |machine, event| match event {
            StreamEvent::Queued { queued } => {
                observe(machine, StreamEvent::Queued { queued: prefill.records + queued })
            }
            StreamEvent::Waited => observe(machine, event),
        })?;
    // Once the last record is queued the FIFO holds at most its depth, each record one
    // period (or the longest a record runs): twice that is a core that stopped taking
    // records.
    let max_clocks = idle_limit(fifo_depth, period, config);
    idle(machine, config.poll_clocks, max_clocks, &mut observe)?;
    machine.bus().wait(2 * period)?;
    let underruns = underruns(machine.bus())?.wrapping_sub(underruns_before);
    let end = machine.positions()?;
    Ok(RunReport {
        stream: StreamReport {
            records: prefill.records + streamed.records,
            bursts: prefill.bursts + streamed.bursts,
            polls: streamed.polls,
            underruns,
        },
        first_boundary,
        cycles: u64::from(end.latch_time.wrapping_sub(before_run)),
        end,
    })
}

/// [`run`] with actions between records: `events` gives `(period, action)` in order of
/// `period`, and each action is applied (by `apply`) once the first `period` records have
/// run and the core is at rest: the streamer queues the records up to that point, waits
/// until the FIFO is empty and the gate has closed, applies the action, and goes on. The
/// record before each event must end at rest (`BLOCK_END`), or the drain counts as an
/// underrun. Each stretch of records starts once all of it, or `config.prefill`
/// records, are queued (START_LEVEL is set for it; the value read before the run is
/// written back at the end). An action at period 0 is applied after the run request,
/// before the first record is queued. `first_boundary` is `LATCH_TIME` read just after
/// the run request, the FIFO empty (not the boundary that took the first record).
pub fn run_with_events<B: Bus, E>(
    machine: &mut Machine<B>,
    records: impl IntoIterator<Item = PeriodRecord>,
    events: impl IntoIterator<Item = (u64, E)>,
    config: &StreamConfig,
    mut observe: impl FnMut(&mut Machine<B>, StreamEvent) -> Result<(), BusError>,
    mut apply: impl FnMut(&mut Machine<B>, E) -> Result<(), BusError>,
) -> Result<RunReport, BusError> {
    let period = u64::from(machine.period_clocks());
    let fifo_depth = machine.caps().fifo_depth;
    poll(machine.bus())?;
    let start_level_before = machine.bus().read_one(start_level::ADDR)?;
    let underruns_before = underruns(machine.bus())?;
    let mut records = records.into_iter().peekable();
    let mut events = events.into_iter().peekable();
    let before_run = machine.positions()?.latch_time;
    machine.set_control(true, config.watchdog, config.estop_active_high)?;
    let first_boundary = machine.bus().read_one(latch_time::ADDR)?;
    let mut report = StreamReport::default();
    let max_clocks = idle_limit(fifo_depth, period, config);
    loop {
        while let Some((_, action)) = events.next_if(|(at, _)| *at <= report.records) {
            apply(machine, action)?;
        }
        let until = events.peek().map(|(at, _)| *at);
        let stretch: Vec<PeriodRecord> = match until {
            Some(at) => records.by_ref().take((at - report.records) as usize).collect(),
            None => records.by_ref().collect(),
        };
        if !stretch.is_empty() {
            let start = stretch.len().min(config.prefill).min(fifo_depth).max(1);
            machine.set_start_level(start as u16)?;
            let queued_before = report.records;
            let streamed = queue(machine, stretch, config, Some(max_clocks), |machine, event| match event {
                StreamEvent::Queued { queued } => {
                    observe(machine, StreamEvent::Queued { queued: queued_before + queued })
                }
                StreamEvent::Waited => observe(machine, event),
            })?;
            report.records += streamed.records;
            report.bursts += streamed.bursts;
            report.polls += streamed.polls;
            idle(machine, config.poll_clocks, max_clocks, &mut observe)?;
        }
        if until.is_none() || (records.peek().is_none() && until.is_some_and(|at| at > report.records)) {
            // The records ran out; events after their end are applied at the end.
            for (_, action) in events {
                apply(machine, action)?;
            }
            break;
        }
    }
    machine.bus().wait(2 * period)?;
    machine.bus().write(start_level::ADDR, start_level_before)?;
    report.underruns = underruns(machine.bus())?.wrapping_sub(underruns_before);
    let end = machine.positions()?;
    Ok(RunReport { stream: report, first_boundary, cycles: u64::from(end.latch_time.wrapping_sub(before_run)), end })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A core whose FIFO never makes room: `FREE` stays at `free`, `STATUS` is `status`;
    /// counts the clocks waited and the records pushed.
    struct Stuck {
        status: u32,
        free: u32,
        waited: u64,
        pushed: usize,
    }

    impl Bus for Stuck {
        fn read(&mut self, addr: u8, out: &mut [u32]) -> Result<(), BusError> {
            for (i, word) in out.iter_mut().enumerate() {
                *word = match addr as usize + i {
                    a if a == usize::from(status::ADDR) => self.status,
                    a if a == usize::from(fifo_level::ADDR) => fifo_level::FREE.set(0, self.free),
                    _ => 0,
                };
            }
            Ok(())
        }
        fn write(&mut self, _: u8, _: u32) -> Result<(), BusError> {
            Ok(())
        }
        fn push_records(&mut self, records: &[PeriodRecord]) -> Result<(), BusError> {
            self.pushed += records.len();
            self.free -= records.len() as u32;
            Ok(())
        }
        fn wait(&mut self, clocks: u64) -> Result<(), BusError> {
            self.waited += clocks;
            Ok(())
        }
    }

    fn records(n: usize) -> Vec<PeriodRecord> {
        vec![PeriodRecord::from_raw(&[1 << 16], 0); n]
    }

    #[test]
    fn a_fifo_that_never_makes_room_ends_the_stream_after_the_limit() {
        let config = StreamConfig { poll_clocks: 100, ..StreamConfig::default() };
        let mut bus = Stuck { status: status::RUNNING.mask(), free: 40, waited: 0, pushed: 0 };
        let result = queue(&mut Bare(&mut bus), records(100), &config, Some(1000), |_, _| Ok(()));
        assert!(matches!(result, Err(BusError::Stalled { clocks: 1000, .. })), "{result:?}");
        // One burst of 32 fits; then the 8 left are never a whole burst and never the tail.
        assert_eq!((bus.pushed, bus.waited), (32, 1000));
    }

    #[test]
    fn a_halted_core_ends_the_stream_at_the_first_poll() {
        let config = StreamConfig::default();
        let mut bus =
            Stuck { status: status::HALT.mask() | status::FAULT_ESTOP.mask(), free: 256, waited: 0, pushed: 0 };
        let result = queue(&mut Bare(&mut bus), records(10), &config, None, |_, _| Ok(()));
        assert!(matches!(result, Err(BusError::Halted { status }) if status == bus.status), "{result:?}");
        assert_eq!((bus.pushed, bus.waited), (0, 0), "nothing queued into the flushed FIFO");
    }
}

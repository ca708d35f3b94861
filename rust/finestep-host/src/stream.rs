//! Streaming period records into the position FIFO: the host's half of seed 000's
//! position-control buffer, which must never run dry during a move.

use finestep_model::PeriodRecord;

use crate::frame::MAX_COUNT;
use crate::regs::{fifo_level, status, underrun_count};
use crate::{Bus, BusError};

/// How the streamer polls and fills.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StreamConfig {
    /// Records per burst at most (<= 255).
    pub burst: usize,
    /// Clocks to wait when the FIFO has less room than a burst.
    pub poll_clocks: u64,
}

impl Default for StreamConfig {
    fn default() -> Self {
        StreamConfig { burst: 32, poll_clocks: 2000 }
    }
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

/// Queues every record of `records`, keeping the FIFO as full as the bursts allow,
/// and returns once the last one is queued (not executed: see [`wait_idle`]).
pub fn stream<B: Bus>(
    bus: &mut B,
    records: impl IntoIterator<Item = PeriodRecord>,
    config: StreamConfig,
) -> Result<StreamReport, BusError> {
    let burst_max = config.burst.clamp(1, MAX_COUNT);
    let underruns_before = bus.read_one(underrun_count::ADDR)? as u16;
    let mut report = StreamReport::default();
    let mut records = records.into_iter().peekable();
    let mut burst = Vec::with_capacity(burst_max);
    while records.peek().is_some() {
        let free = fifo_level::FREE.get(bus.read_one(fifo_level::ADDR)?) as usize;
        report.polls += 1;
        if free < burst_max {
            // Fill only in whole bursts while more than a burst is left, so the frame
            // overhead stays small; the tail goes as soon as it fits.
            let tail_fits = records.size_hint().1.is_some_and(|left| left <= free) && free > 0;
            if !tail_fits {
                bus.wait(config.poll_clocks)?;
                continue;
            }
        }
        burst.clear();
        burst.extend(records.by_ref().take(free.min(burst_max)));
        bus.push_records(&burst)?;
        report.records += burst.len() as u64;
        report.bursts += 1;
    }
    report.underruns = (bus.read_one(underrun_count::ADDR)? as u16).wrapping_sub(underruns_before);
    Ok(report)
}

/// Waits until the FIFO is empty and the gate has closed (the last record ran), polling
/// every `poll_clocks`; gives up after `max_clocks`.
pub fn wait_idle<B: Bus>(bus: &mut B, poll_clocks: u64, max_clocks: u64) -> Result<(), BusError> {
    let mut waited = 0;
    loop {
        let level = fifo_level::LEVEL.get(bus.read_one(fifo_level::ADDR)?);
        let streaming = status::STREAMING.get(bus.read_one(status::ADDR)?) != 0;
        if level == 0 && !streaming {
            return Ok(());
        }
        if waited >= max_clocks {
            return Err(BusError::Protocol(format!("still streaming after {max_clocks} clocks")));
        }
        bus.wait(poll_clocks)?;
        waited += poll_clocks;
    }
}

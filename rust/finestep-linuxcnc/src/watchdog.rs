//! `finestep-linuxcnc watchdog`: what a simulated chip does after its host vanished.
//! `scripts/linuxcnc_run.sh` kills LinuxCNC's realtime process mid-program; the
//! simulated chip's time stands still while it has no client (it advances only by
//! frames and waits), so this tool, connecting next, starts at the instant of the kill.
//! It only reads (a read does not kick the watchdog) and lets simulated time pass in
//! small waits, sampling STATUS and the step positions: the watchdog must trip within
//! its timeout of the kill, and no step may follow the halt.

use anyhow::{bail, Context};
use finestep_host::regs::{position, status, timestamp};
use finestep_host::sim_link::SimSocket;
use finestep_host::{Bus, Machine, SpiBus};

/// Clocks between samples.
const SAMPLE_CLOCKS: u64 = 250;

/// What the chip did after the kill.
#[derive(Debug, Default, PartialEq, Eq)]
pub struct WatchReport {
    /// The watchdog timeout, clocks.
    pub timeout_clocks: u64,
    /// Clocks from the kill to the first sample showing FAULT_WATCHDOG.
    pub tripped_after: Option<u64>,
    /// Clocks from the kill to the first sample showing UNDERRUN (the FIFO ran dry).
    pub underrun_after: Option<u64>,
    /// Steps (summed over axes) between the kill and the halt: the records already queued.
    pub steps_before_halt: u64,
    /// Steps after the first sample showing the halt.
    pub steps_after_halt: u64,
}

/// Watches the chip served at `socket` for twice `timeout_ns` after the kill.
pub fn watch(socket: &str, timeout_ns: u64) -> anyhow::Result<WatchReport> {
    let link = SimSocket::connect(socket).with_context(|| format!("sim:{socket}"))?;
    let mut machine = Machine::connect(SpiBus::new(link, 1)).with_context(|| format!("sim:{socket}: identity"))?;
    let caps = machine.caps();
    machine.bus().set_n_axes(caps.n_axes);
    let timeout_clocks = (u128::from(timeout_ns) * u128::from(caps.clock_hz)).div_ceil(1_000_000_000) as u64;
    let bus = machine.bus();
    let start = bus.read_one(timestamp::ADDR)?;
    let read_steps = |bus: &mut SpiBus<SimSocket>| -> anyhow::Result<Vec<i32>> {
        let mut words = vec![0u32; caps.n_axes];
        bus.read(position::addr(0), &mut words)?;
        Ok(words.into_iter().map(|w| w as i32).collect())
    };
    let first = read_steps(bus)?;
    let mut report = WatchReport { timeout_clocks, ..WatchReport::default() };
    let mut halted_at: Option<Vec<i32>> = None;
    let mut last: Vec<i32>;
    loop {
        let word = bus.read_one(status::ADDR)?;
        let now = u64::from(bus.read_one(timestamp::ADDR)?.wrapping_sub(start));
        let steps = read_steps(bus)?;
        if status::FAULT_WATCHDOG.get(word) != 0 && report.tripped_after.is_none() {
            report.tripped_after = Some(now);
        }
        if status::UNDERRUN.get(word) != 0 && report.underrun_after.is_none() {
            report.underrun_after = Some(now);
        }
        if status::HALT.get(word) != 0 && halted_at.is_none() {
            halted_at = Some(steps.clone());
        }
        last = steps;
        if now > 2 * timeout_clocks {
            break;
        }
        bus.wait(SAMPLE_CLOCKS)?;
    }
    let moved = |a: &[i32], b: &[i32]| a.iter().zip(b).map(|(x, y)| u64::from(x.wrapping_sub(*y).unsigned_abs())).sum();
    if let Some(at_halt) = &halted_at {
        report.steps_before_halt = moved(at_halt, &first);
        report.steps_after_halt = moved(&last, at_halt);
    } else {
        report.steps_before_halt = moved(&last, &first);
    }
    Ok(report)
}

/// Prints the figures; fails unless the watchdog tripped within its timeout of the kill
/// (plus the spec's 2 clocks and one sample) and no step followed the halt.
pub fn run(socket: &str, timeout_ns: u64) -> anyhow::Result<()> {
    let report = watch(socket, timeout_ns)?;
    println!(
        "  LinuxCNC killed: underrun after {}, watchdog tripped after {} of its {} clocks, {} steps between the kill \
         and the halt (records already queued), {} after it",
        report.underrun_after.map_or("-".into(), |c| format!("{c} clocks")),
        report.tripped_after.map_or("never".into(), |c| format!("{c} clocks")),
        report.timeout_clocks,
        report.steps_before_halt,
        report.steps_after_halt
    );
    match report.tripped_after {
        None => bail!("the watchdog did not trip"),
        Some(after) if after > report.timeout_clocks + 2 + SAMPLE_CLOCKS => {
            bail!("the watchdog tripped {after} clocks after the kill, over its {} clocks", report.timeout_clocks)
        }
        Some(_) => {}
    }
    if report.steps_after_halt != 0 {
        bail!("{} steps after the halt", report.steps_after_halt);
    }
    Ok(())
}

//! `finestep selftest`: what a builder runs on a new board, as a pass/fail table:
//! identity, map version and CAPS; write/read-back patterns on read-write registers; a
//! frame with a bad CRC refused and counted; the FIFO's start threshold and underrun;
//! the watchdog tripping, halting every axis and recovering on clear; the E-stop input
//! (driven where the link can, a simulated chip; otherwise it needs the operator); and
//! with a loopback (axis 0's step/dir pins on encoder channel 0, or the plant in
//! simulation) a commanded move counted back exactly. Everything goes through the host
//! driver on the chosen bus, the code a board runs.

use anyhow::bail;
use finestep_host::frame::{self, FrameResult};
use finestep_host::regs::{
    crc_error_count, id, period_clocks, start_level, status, underrun_count, version, watchdog_timeout,
};
use finestep_host::{AxisSetup, Bus, EncoderSetup, Increment, OutMode, PeriodRecord, SpiTransfer};

use crate::bus::{self, BusMachine, BusTarget};

/// The period of the FIFO, watchdog and loopback checks, clocks (40 us at 50 MHz).
const PERIOD: u32 = 2_000;
/// Steps of the loopback move: 4 a period for 50 periods.
const LOOPBACK_STEPS: i32 = 200;

/// One row of the table.
struct Row {
    check: &'static str,
    outcome: Outcome,
    detail: String,
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Outcome {
    Pass,
    Fail,
    /// Not tested on this target (and why, in the detail); not a failure.
    Skip,
}

type Check = anyhow::Result<(Outcome, String)>;

/// One check on a connected chip.
type CheckFn = fn(&mut BusMachine) -> Check;

fn pass(detail: impl Into<String>) -> Check {
    Ok((Outcome::Pass, detail.into()))
}

fn fail(detail: impl Into<String>) -> Check {
    Ok((Outcome::Fail, detail.into()))
}

fn status_word(machine: &mut BusMachine) -> anyhow::Result<u32> {
    Ok(machine.status()?)
}

/// Back to a stopped core with faults and errors cleared and the reset period.
fn quiesce(machine: &mut BusMachine) -> anyhow::Result<()> {
    machine.set_control(false, false, true)?;
    machine.command(finestep_host::regs::command::FLUSH_FIFO.set(0, 1))?;
    machine.bus().wait(2 * u64::from(PERIOD))?;
    machine.clear_faults_and_errors()?;
    Ok(())
}

fn registers(machine: &mut BusMachine) -> Check {
    let caps = machine.caps();
    let targets = [
        ("PERIOD_CLOCKS", period_clocks::ADDR, period_clocks::CLOCKS, caps.period_max(), period_clocks::CLOCKS_RESET),
        (
            "WATCHDOG_TIMEOUT",
            watchdog_timeout::ADDR,
            watchdog_timeout::CLOCKS,
            watchdog_timeout::CLOCKS.max(),
            watchdog_timeout::CLOCKS_RESET,
        ),
        ("START_LEVEL", start_level::ADDR, start_level::LEVEL, start_level::LEVEL.max(), start_level::LEVEL_RESET),
    ];
    let patterns = [0xFFFF_FFFF, 0x5555_5555, 0xAAAA_AAAA, 0x0000_0001, 0x8000_0000];
    let mut tried = 0;
    for (name, addr, field, mask, reset) in targets {
        for pattern in patterns {
            let value = pattern & mask;
            machine.bus().write(addr, field.set(0, value))?;
            let read = field.get(machine.bus().read_one(addr)?);
            tried += 1;
            if read != value {
                machine.bus().write(addr, field.set(0, reset))?;
                return fail(format!("{name}: wrote {value:#x}, read {read:#x}"));
            }
        }
        machine.bus().write(addr, field.set(0, reset))?;
    }
    pass(format!("{tried} patterns on PERIOD_CLOCKS, WATCHDOG_TIMEOUT, START_LEVEL read back"))
}

fn bad_crc(machine: &mut BusMachine) -> Check {
    let before = crc_error_count::COUNT.get(machine.bus().read_one(crc_error_count::ADDR)?);
    let level = start_level::LEVEL.get(machine.bus().read_one(start_level::ADDR)?);
    let mut tx = frame::write_request(start_level::ADDR, start_level::LEVEL.set(0, 77));
    let crc_at = tx.len() - 2;
    tx[crc_at] ^= 0x5A;
    let rx = machine.bus().link_mut().transfer(&tx)?;
    let result = frame::write_result(&rx);
    let after = crc_error_count::COUNT.get(machine.bus().read_one(crc_error_count::ADDR)?);
    let level_after = start_level::LEVEL.get(machine.bus().read_one(start_level::ADDR)?);
    machine.clear_faults_and_errors()?;
    if result != FrameResult::CrcMismatch {
        return fail(format!("answered {result:?}, not CrcMismatch"));
    }
    if after != before.wrapping_add(1) & crc_error_count::COUNT.max() {
        return fail(format!("CRC_ERROR_COUNT {before} -> {after}, not +1"));
    }
    if level_after != level {
        return fail(format!("START_LEVEL changed {level} -> {level_after}: the frame was applied"));
    }
    pass(format!("answered CrcMismatch, CRC_ERROR_COUNT {before} -> {after}, nothing written"))
}

fn still(n_axes: usize) -> PeriodRecord {
    PeriodRecord::from_raw(&vec![0; n_axes], 0)
}

fn fifo(machine: &mut BusMachine) -> Check {
    let caps = machine.caps();
    let period = u64::from(PERIOD);
    machine.set_period(PERIOD)?;
    machine.set_start_level(4)?;
    machine.clear_faults_and_errors()?;
    let underruns = underrun_count::COUNT.get(machine.bus().read_one(underrun_count::ADDR)?);
    machine.bus().push_records(&[still(caps.n_axes); 3])?;
    let (level, free) = machine.fifo()?;
    if level != 3 || level + free != caps.fifo_depth as u32 {
        return fail(format!("3 records queued: FIFO_LEVEL {level}, FREE {free} (depth {})", caps.fifo_depth));
    }
    machine.set_control(true, false, true)?;
    machine.bus().wait(3 * period)?;
    let waiting = status_word(machine)?;
    if status::STREAMING.get(waiting) != 0 {
        return fail("streaming with 3 records queued and a start level of 4");
    }
    machine.bus().push_records(&[still(caps.n_axes)])?;
    machine.bus().wait(period)?;
    let started = status_word(machine)?;
    if status::STREAMING.get(started) == 0 {
        return fail(format!("not streaming at the start level (STATUS {started:#x})"));
    }
    machine.bus().wait(8 * period)?;
    let ended = status_word(machine)?;
    let after = underrun_count::COUNT.get(machine.bus().read_one(underrun_count::ADDR)?);
    quiesce(machine)?;
    machine.set_start_level(start_level::LEVEL_RESET as u16)?;
    if status::UNDERRUN.get(ended) == 0 || after == underruns {
        return fail(format!("ran dry mid-block: STATUS {ended:#x}, UNDERRUN_COUNT {underruns} -> {after}"));
    }
    pass(format!(
        "depth {}, held at 3 of 4, started at 4, ran dry: UNDERRUN_COUNT {underruns} -> {after}",
        caps.fifo_depth
    ))
}

fn moving(n_axes: usize, steps_per_period: i32) -> PeriodRecord {
    let mut raw = vec![0; n_axes];
    raw.iter_mut().for_each(|r| *r = steps_per_period << 16);
    PeriodRecord::from_raw(&raw, 0)
}

fn watchdog(machine: &mut BusMachine) -> Check {
    let caps = machine.caps();
    let period = u64::from(PERIOD);
    let timeout = 20 * PERIOD;
    for axis in 0..caps.n_axes {
        machine.configure_axis(axis, &AxisSetup::default())?;
    }
    machine.enable_axes((1 << caps.n_axes) - 1)?;
    machine.set_period(PERIOD)?;
    machine.set_start_level(1)?;
    machine.bus().write(watchdog_timeout::ADDR, watchdog_timeout::CLOCKS.set(0, timeout))?;
    machine.clear_faults_and_errors()?;
    machine.bus().push_records(&vec![moving(caps.n_axes, 1); 64])?;
    machine.set_control(true, true, true)?;
    machine.bus().wait(4 * period)?;
    let running = status_word(machine)?;
    machine.bus().wait(u64::from(timeout) + 4 * period)?;
    let tripped = status_word(machine)?;
    let at_trip = machine.positions()?.steps;
    machine.bus().wait(8 * period)?;
    let later = machine.positions()?.steps;
    machine.set_control(false, false, true)?;
    machine.clear_faults_and_errors()?;
    let cleared = status_word(machine)?;
    machine.bus().write(watchdog_timeout::ADDR, watchdog_timeout::CLOCKS.set(0, watchdog_timeout::CLOCKS_RESET))?;
    quiesce(machine)?;
    if status::RUNNING.get(running) == 0 || status::HALT.get(running) != 0 {
        return fail(format!("did not run with the watchdog fed (STATUS {running:#x})"));
    }
    if status::FAULT_WATCHDOG.get(tripped) == 0 || status::HALT.get(tripped) == 0 {
        return fail(format!("no trip {timeout} clocks without a frame (STATUS {tripped:#x})"));
    }
    if at_trip != later {
        return fail(format!("axes moved while halted: {at_trip:?} -> {later:?}"));
    }
    if status::HALT.get(cleared) != 0 || status::FAULT_WATCHDOG.get(cleared) != 0 {
        return fail(format!("still halted after CLEAR_FAULTS (STATUS {cleared:#x})"));
    }
    pass(format!("tripped after {timeout} clocks unfed, every axis held at {at_trip:?}, cleared"))
}

fn estop(machine: &mut BusMachine) -> Check {
    if !machine.bus().link_mut().drive_estop(true)? {
        return Ok((Outcome::Skip, "needs the operator: press E-stop, watch HALT, release, clear".into()));
    }
    machine.bus().wait(1_000)?;
    let pressed = status_word(machine)?;
    machine.clear_faults_and_errors()?;
    let held = status_word(machine)?;
    machine.bus().link_mut().drive_estop(false)?;
    machine.bus().wait(1_000)?;
    machine.clear_faults_and_errors()?;
    let released = status_word(machine)?;
    let bits = |w: u32| (status::ESTOP_ACTIVE.get(w), status::FAULT_ESTOP.get(w), status::HALT.get(w));
    if bits(pressed) != (1, 1, 1) {
        return fail(format!("pressed: STATUS {pressed:#x} (ESTOP_ACTIVE, FAULT_ESTOP, HALT not all set)"));
    }
    if status::HALT.get(held) == 0 {
        return fail(format!("CLEAR_FAULTS released the halt with E-stop still pressed (STATUS {held:#x})"));
    }
    if bits(released) != (0, 0, 0) {
        return fail(format!("released and cleared: STATUS {released:#x}"));
    }
    pass("pressed: ESTOP_ACTIVE, FAULT_ESTOP, HALT; held through a clear; released and cleared")
}

/// The move counted back with the plant on a simulated chip's pins (its drive follows
/// step/dir, its grating counts one per step).
fn loopback(machine: &mut BusMachine) -> Check {
    loopback_in(machine, OutMode::StepDir)
}

/// The move counted back on a board with axis 0's pins A/B wired to encoder 0's A/B:
/// axis 0 in quadrature output mode, one x4 count per step.
fn loopback_wired(machine: &mut BusMachine) -> Check {
    loopback_in(machine, OutMode::Quadrature)
}

fn loopback_in(machine: &mut BusMachine, out_mode: OutMode) -> Check {
    let caps = machine.caps();
    machine.configure_axis(0, &AxisSetup { out_mode, ..AxisSetup::default() })?;
    machine.enable_axes((1 << caps.n_axes) - 1)?;
    machine.configure_encoder(0, &EncoderSetup::default())?;
    machine.set_period(PERIOD)?;
    machine.set_start_level(1)?;
    machine.clear_faults_and_errors()?;
    let before = machine.feedback()?;
    let periods = LOOPBACK_STEPS / 4;
    let mut records = vec![
        {
            let mut r = still(caps.n_axes);
            r.inc[0] = Increment::from_num(4);
            r
        };
        periods as usize
    ];
    if let Some(last) = records.last_mut() {
        last.flags = 1;
    }
    for burst in records.chunks(32) {
        machine.bus().push_records(burst)?;
    }
    machine.set_control(true, false, true)?;
    machine.bus().wait(u64::from(PERIOD) * (periods as u64 + 8))?;
    let after = machine.feedback()?;
    quiesce(machine)?;
    machine.configure_axis(0, &AxisSetup::default())?;
    let steps = after.steps[0].wrapping_sub(before.steps[0]);
    let counts = after.counts[0].wrapping_sub(before.counts[0]);
    if steps != LOOPBACK_STEPS {
        return fail(format!("axis 0 made {steps} steps of {LOOPBACK_STEPS}"));
    }
    if counts != steps {
        return fail(format!("axis 0 made {steps} steps, encoder 0 counted {counts}"));
    }
    pass(format!("axis 0: {steps} steps, encoder 0: {counts} counts"))
}

/// Runs every check on `target` and prints the table; an error when any failed.
pub fn run(target: Option<BusTarget>, wired: bool) -> anyhow::Result<()> {
    let target = BusTarget::choose(target, None, "<command line>")?;
    let simulated = matches!(target, BusTarget::Lockstep | BusTarget::Model);
    let n_axes = finestep_cosim::rtl_top_params().n_axes;
    let plant = if simulated { Some(bus::loopback_plant(n_axes, false)?) } else { None };
    let clock_hz = finestep_cosim::rtl_top_params().clock_hz;
    println!("finestep selftest on {target}");
    let mut rows = Vec::new();
    match bus::open_with(&target, "selftest", clock_hz, plant) {
        Err(e) => rows.push(Row { check: "identity, map, CAPS", outcome: Outcome::Fail, detail: format!("{e:#}") }),
        Ok(mut machine) => {
            let caps = machine.caps();
            let mut words = [0u32; 2];
            machine.bus().read(id::ADDR, &mut words)?;
            rows.push(Row {
                check: "identity, map, CAPS",
                outcome: Outcome::Pass,
                detail: format!(
                    "ID {:#010x}, map {}.{}, {} axes, FIFO {}, P_WIDTH {}, TIMING_W {}, {} encoders, step slots {}, {} Hz",
                    words[0],
                    version::MAJOR.get(words[1]),
                    version::MINOR.get(words[1]),
                    caps.n_axes,
                    caps.fifo_depth,
                    caps.p_width,
                    caps.timing_w,
                    caps.n_enc,
                    caps.step_slots,
                    caps.clock_hz
                ),
            });
            let has_loopback = simulated || wired;
            let checks: [(&'static str, CheckFn); 6] = [
                ("register read-back", registers),
                ("bad CRC refused", bad_crc),
                ("FIFO threshold, underrun", fifo),
                ("watchdog halt, clear", watchdog),
                ("E-stop input", estop),
                ("loopback move", if matches!(target, BusTarget::Spidev { .. }) { loopback_wired } else { loopback }),
            ];
            for (check, run) in checks {
                let (outcome, detail) = if check == "loopback move" && !has_loopback {
                    (Outcome::Skip, "needs axis 0's step/dir wired to encoder 0 (--loopback)".to_string())
                } else {
                    match run(&mut machine) {
                        Ok(result) => result,
                        Err(e) => (Outcome::Fail, format!("{e:#}")),
                    }
                };
                rows.push(Row { check, outcome, detail });
            }
        }
    }
    println!("  {:<26} {:<6} detail", "check", "result");
    for row in &rows {
        let outcome = match row.outcome {
            Outcome::Pass => "PASS",
            Outcome::Fail => "FAIL",
            Outcome::Skip => "SKIP",
        };
        println!("  {:<26} {:<6} {}", row.check, outcome, row.detail);
    }
    let failed = rows.iter().filter(|r| r.outcome == Outcome::Fail).count();
    if failed != 0 {
        bail!("selftest: {failed} of {} checks failed", rows.len());
    }
    println!("selftest: every check passed ({} skipped)", rows.iter().filter(|r| r.outcome == Outcome::Skip).count());
    Ok(())
}

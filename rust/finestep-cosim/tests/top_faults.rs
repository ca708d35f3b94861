//! Fault scenarios on the bus-level top, RTL and model in lockstep, driven through the
//! host driver: a forced underrun, FIFO overflow (SPI and 8080), the watchdog, the
//! E-stop (also mid-stream, through the streamer), and coherent position reads while
//! moving.
//!
//! Every expectation is computed here from docs/spec/, not taken from the model: pulse
//! counts are the DDA's round-half-up of the summed increments, counters and flags are
//! what the spec says they count, latencies are the spec's. The drive pins are watched
//! on every clock by [`Probe`] (a [`PinTarget`] wrapping [`TopLockstep`]), so step
//! pulses are counted on the pins themselves and compared with `POSITION`.

mod pin_probe;

use finestep_cosim::TopVariant;
use finestep_host::frame::{self, FrameResult};
use finestep_host::regs::{
    axis_status, command, control, crc_error_count, estop_filter, frame_error_count, parallel_error_count, record_inc,
    record_push, refused_record_count, start_level, status, underrun_count, watchdog_timeout,
};
use finestep_host::stream::{self, wait_idle, StreamConfig, StreamEvent};
use finestep_host::{AxisSetup, Bus, BusError, Machine, PinHost, PinTiming};
use finestep_model::{DriveTiming, PeriodRecord};
use pin_probe::{
    all_rounded, ok, positions, records, rounded, ParallelMachine, Probe, SpiMachine, N_AXES, RESET_CYCLES,
};

const FIFO_DEPTH: usize = 256;
/// Step timing of every axis: L = 3, S = 3, U = 2, H = 2, so I_fwd = 6 and
/// I_rev = 2 * (3 + max(3, 2 + 2) - 1) = 12 clocks; with the step engine's 4 slots
/// (docs/spec/rated_rate.md) every timing is one visit: I_fwd = 8, I_rev = 16 clocks.
const STEP_LEN: u64 = 3;
const AXIS: AxisSetup =
    AxisSetup { timing: DriveTiming::new(3, 3, 2, 2), out_mode: finestep_host::OutMode::StepDir, invert: 0 };

/// The motion chip without the hand wheel (the boards' build), its step pulses `STEP_LEN`
/// rounded up to whole visits of the step engine (docs/spec/step_engine.md).
fn chip(name: &str) -> Probe {
    let params = finestep_cosim::rtl_top_params_of(TopVariant::MotionNoMpg);
    let slots = u64::from(params.core_params().step_slots());
    Probe::new(TopVariant::MotionNoMpg, name, STEP_LEN.div_ceil(slots) * slots)
}

fn spi_machine(name: &str) -> SpiMachine {
    pin_probe::spi_machine(chip(name))
}

fn parallel_machine(name: &str) -> ParallelMachine {
    pin_probe::parallel_machine(chip(name))
}

fn host(machine: &mut SpiMachine) -> &mut PinHost<Probe> {
    machine.bus().link_mut()
}

fn probe(machine: &mut SpiMachine) -> &Probe {
    machine.bus().link_mut().target()
}

fn parallel_probe(machine: &mut ParallelMachine) -> &Probe {
    machine.bus().host_mut().target()
}

/// Axis timing, enables, period and start level; clears the power-on E-stop fault.
fn setup<B: Bus>(machine: &mut Machine<B>, period: u32, start: u16) {
    pin_probe::setup(machine, &AXIS, period, start);
}

fn read<B: Bus>(machine: &mut Machine<B>, addr: u8) -> u32 {
    ok(machine.bus().read_one(addr))
}

fn push_all<B: Bus>(machine: &mut Machine<B>, records: &[PeriodRecord]) {
    for chunk in records.chunks(frame::MAX_COUNT) {
        ok(machine.bus().push_records(chunk));
    }
}

fn level<B: Bus>(machine: &mut Machine<B>) -> u32 {
    ok(machine.fifo()).0
}

/// Polls STATUS every `poll` clocks until `done(status)`, at most `max` clocks.
fn wait_status<B: Bus>(machine: &mut Machine<B>, poll: u64, max: u64, done: impl Fn(u32) -> bool) -> u32 {
    let mut waited = 0;
    loop {
        let word = ok(machine.status());
        if done(word) {
            return word;
        }
        assert!(waited < max, "STATUS {word:#x} after {max} clocks");
        ok(machine.bus().wait(poll));
        waited += poll;
    }
}

/// The FIFO ran dry mid-block: every axis holds, UNDERRUN and one count, the gate stays
/// shut (even with the FIFO above the threshold) until CLEAR_ERRORS and the threshold,
/// then the rest of the move runs and ends exactly.
#[test]
fn forced_underrun_holds_and_resumes_exactly() {
    const P: u32 = 600;
    let mut m = spi_machine("forced_underrun_holds_and_resumes_exactly");
    setup(&mut m, P, 8);
    ok(m.set_control(true, false, true));

    // Eight records of a block that does not end here: the gate opens at 8, they run,
    // and the boundary after the eighth finds the FIFO empty.
    let first = records(8, 1, false);
    push_all(&mut m, &first);
    let word = wait_status(&mut m, 500, 20 * u64::from(P), |w| status::UNDERRUN.get(w) == 1);
    assert_eq!(status::STREAMING.get(word), 0, "the gate shuts at the underrun: {word:#x}");
    assert_eq!(status::RUNNING.get(word), 1, "periods keep running: {word:#x}");
    assert_eq!(read(&mut m, underrun_count::ADDR), 1);
    assert_eq!(level(&mut m), 0);
    ok(m.bus().wait(200));
    let held = positions(&mut m);
    assert_eq!(held, all_rounded(&first), "positions at the underrun");
    assert_eq!(probe(&mut m).all_pin_steps(), held, "pulses on the pins");
    let rises_at_underrun = probe(&mut m).rise_count();

    // Refilled above the threshold, the gate stays shut while UNDERRUN is set.
    let second = records(10, 2, false);
    push_all(&mut m, &second);
    ok(m.bus().wait(4 * u64::from(P)));
    let word = ok(m.status());
    assert_eq!(status::STREAMING.get(word) | status::UNDERRUN.get(word) << 1, 0b10, "{word:#x}");
    assert_eq!(level(&mut m), 10);
    assert_eq!(positions(&mut m), held, "every axis holds while the gate is shut");

    // Errors cleared, but the (raised) threshold is not reached: still shut.
    ok(m.bus().write(start_level::ADDR, 12));
    ok(m.command(command::CLEAR_ERRORS.set(0, 1)));
    ok(m.bus().wait(4 * u64::from(P)));
    let word = ok(m.status());
    assert_eq!(status::STREAMING.get(word) | status::UNDERRUN.get(word), 0, "{word:#x}");
    assert_eq!(level(&mut m), 10);
    assert_eq!(positions(&mut m), held);
    assert_eq!(probe(&mut m).rise_count(), rises_at_underrun, "no pulse while held");

    // The threshold reached: the rest of the block runs and ends at rest (no underrun).
    let third = records(2, 3, true);
    push_all(&mut m, &third);
    ok(wait_idle(m.bus(), 500, 30 * u64::from(P)));
    ok(m.bus().wait(200));
    let all: Vec<PeriodRecord> = first.iter().chain(&second).chain(&third).copied().collect();
    let end = positions(&mut m);
    assert_eq!(end, all_rounded(&all), "final positions");
    assert_eq!(probe(&mut m).all_pin_steps(), end, "pulses on the pins");
    assert_eq!(read(&mut m, underrun_count::ADDR), 1, "a block ending with BLOCK_END is no underrun");
    let word = ok(m.status());
    assert_eq!(word & 0xFC0, 0, "no sticky error: {word:#x}");
    assert_eq!(read(&mut m, axis_status::ADDR), 0);
    probe(&mut m).assert_pulses_exact();
}

/// Writes a 32-bit register over the 8080 pins (low half, then high half).
fn parallel_write(host: &mut PinHost<Probe>, addr: u8, value: u32) {
    ok(host.parallel_write16(addr << 1, value as u16));
    ok(host.parallel_write16(addr << 1 | 1, (value >> 16) as u16));
}

/// Queues one record with RECORD_INC and RECORD_PUSH over the 8080 pins.
fn parallel_push(host: &mut PinHost<Probe>, record: &PeriodRecord) {
    for axis in 0..N_AXES {
        parallel_write(host, record_inc::addr(axis), record.inc[axis].to_bits() as u32);
    }
    parallel_write(host, record_push::ADDR, u32::from(record.flags));
}

/// A full FIFO refuses an SPI FIFO frame (whole, with 0xE3) and an 8080 RECORD_PUSH,
/// counting every refused record; nothing is overwritten, lost or duplicated.
#[test]
fn overflow_refuses_and_loses_nothing() {
    const P: u32 = 128;
    let mut m = spi_machine("overflow_refuses_and_loses_nothing");
    setup(&mut m, P, 1);
    // Records that must never run: 7.5 steps per period on every axis.
    let intruder = PeriodRecord::from_raw(&[15 << 15, 15 << 15, 15 << 15, 15 << 15], 0);
    let mut refused = 0u32;
    let mut expected = vec![0i32; N_AXES];

    for round in 0..2u64 {
        // Round 0 fills over SPI only; round 1 mostly over SPI and the last records
        // through RECORD_PUSH on the 8080 bus.
        let accepted = records(FIFO_DEPTH, 10 + round, true);
        let over_spi = if round == 0 { FIFO_DEPTH } else { FIFO_DEPTH - 6 };
        push_all(&mut m, &accepted[..over_spi]);
        for record in &accepted[over_spi..] {
            parallel_push(host(&mut m), record);
        }
        let (lvl, free) = ok(m.fifo());
        assert_eq!((lvl, free), (FIFO_DEPTH as u32, 0));
        assert_eq!(status::OVERFLOW.get(ok(m.status())), 0, "filling to the brim is no overflow");

        // One more record over SPI: the frame is refused at its header.
        match m.bus().push_records(&[intruder]) {
            Err(BusError::Refused(FrameResult::FifoRefused)) => {}
            other => panic!("a FIFO frame on a full FIFO answered {other:?}"),
        }
        refused += 1;
        assert_eq!(status::OVERFLOW.get(ok(m.status())), 1);
        assert_eq!(read(&mut m, refused_record_count::ADDR), refused);
        // A frame of three: all three refused.
        match m.bus().push_records(&[intruder; 3]) {
            Err(BusError::Refused(FrameResult::FifoRefused)) => {}
            other => panic!("a FIFO frame on a full FIFO answered {other:?}"),
        }
        refused += 3;
        assert_eq!(read(&mut m, refused_record_count::ADDR), refused);
        // RECORD_PUSH on the full FIFO: one refused record.
        ok(m.command(command::CLEAR_ERRORS.set(0, 1)));
        assert_eq!(status::OVERFLOW.get(ok(m.status())), 0);
        parallel_push(host(&mut m), &intruder);
        refused += 1;
        let word = ok(m.status());
        assert_eq!(status::OVERFLOW.get(word), 1, "{word:#x}");
        assert_eq!(status::BUS_ERROR.get(word), 0, "a refusal is no bus error: {word:#x}");
        assert_eq!(read(&mut m, refused_record_count::ADDR), refused);
        assert_eq!(ok(m.fifo()), (FIFO_DEPTH as u32, 0));
        for counter in [crc_error_count::ADDR, frame_error_count::ADDR, parallel_error_count::ADDR] {
            assert_eq!(read(&mut m, counter), 0, "counter {counter:#x}");
        }

        // Run them out: exactly the accepted records, in full.
        ok(m.set_control(true, false, true));
        ok(wait_idle(m.bus(), 2000, 2 * FIFO_DEPTH as u64 * u64::from(P)));
        ok(m.set_control(false, false, true));
        ok(m.bus().wait(100));
        for (axis, slot) in expected.iter_mut().enumerate() {
            *slot += rounded(&accepted, axis);
        }
        let end = positions(&mut m);
        assert_eq!(end, expected, "round {round}: positions after the full FIFO ran out");
        assert_eq!(probe(&mut m).all_pin_steps(), end, "pulses on the pins");
        assert_eq!(read(&mut m, underrun_count::ADDR), 0);
        assert_eq!(read(&mut m, axis_status::ADDR), 0, "within the rated rate");
        ok(m.command(command::CLEAR_ERRORS.set(0, 1)));
    }
    probe(&mut m).assert_pulses_exact();
}

/// Sends a WRITE frame bit by bit and returns the first cycle in which SCK is high for
/// the last bit of the CRC (the byte that applies the write).
fn timed_write(host: &mut PinHost<Probe>, addr: u8, value: u32, sck_half: u64) -> u64 {
    let bytes = frame::write_request(addr, value);
    ok(host.spi_begin());
    ok(host.spi_send_bits(&bytes, 9 * 8));
    let last_rise = host.target().cycle - sck_half;
    ok(host.spi_send_bits(&bytes[9..], 8));
    ok(host.spi_end());
    last_rise
}

/// After a halt in cycle `halt` (the enables drop in `halt + 1`): every enable low from
/// then on, no step pulse begins after that, and every pulse lasts exactly L (also the
/// one in flight). Returns whether a pulse was high when the halt came.
fn check_halted_pins(probe: &Probe, halt: u64) -> bool {
    let drop = halt + 1;
    let (last_change, mask) = *probe.enables.last().unwrap();
    assert_eq!((last_change, mask), (drop, 0), "enables: {:?}", probe.enables);
    for axis in 0..N_AXES {
        if let Some(&(rise, _)) = probe.rises[axis].iter().find(|&&(c, _)| c > drop) {
            panic!("axis {axis}: a step pulse rose in cycle {rise}, after the halt in cycle {halt}");
        }
    }
    probe.assert_pulses_exact();
    probe.pulses.iter().any(|&(_, rose, width)| rose <= drop && rose + width > drop)
}

/// The state after a halt: HALT and the fault, RUN cleared, the FIFO flushed, every
/// axis stopped where its pins stopped.
fn check_halted_state(m: &mut SpiMachine, fault: u32) -> Vec<i32> {
    let word = ok(m.status());
    assert_eq!(status::HALT.get(word), 1, "{word:#x}");
    assert_eq!(word & (status::FAULT_ESTOP.mask() | status::FAULT_WATCHDOG.mask()), fault, "{word:#x}");
    assert_eq!(status::RUNNING.get(word) | status::STREAMING.get(word), 0, "{word:#x}");
    assert_eq!(control::RUN.get(read(m, control::ADDR)), 0, "RUN cleared by the halt");
    assert_eq!(ok(m.fifo()), (0, FIFO_DEPTH as u32), "the halt flushed the FIFO");
    let stopped = positions(m);
    assert_eq!(probe(m).all_pin_steps(), stopped, "POSITION against the pulses on the pins");
    stopped
}

/// Clears the fault and runs a new move from rest: it ends exactly `from + rounded(move)`.
fn resume_exactly(m: &mut SpiMachine, from: &[i32], seed: u64, period: u32) {
    let word = ok(m.status());
    assert_eq!(status::HALT.get(word), 0, "{word:#x}");
    assert_eq!(probe(m).enables.last().unwrap().1, (1 << N_AXES) - 1, "enables back on");
    let again = records(12, seed, true);
    push_all(m, &again);
    ok(m.set_control(true, false, true));
    ok(wait_idle(m.bus(), 1000, 30 * u64::from(period)));
    ok(m.bus().wait(200));
    let expected: Vec<i32> = (0..N_AXES).map(|axis| from[axis] + rounded(&again, axis)).collect();
    let end = positions(m);
    assert_eq!(end, expected, "the move after the fault");
    assert_eq!(probe(m).all_pin_steps(), end);
    probe(m).assert_pulses_exact();
}

/// The watchdog: the last write kicks it; reads do not; timeout + 2 clocks later the
/// machine halts mid-move with every pin as the spec says, and CLEAR_FAULTS clears it.
#[test]
fn watchdog_halts_mid_move() {
    const P: u32 = 400;
    // Chosen so that a step pulse is high when the halt comes (3007..=3009 are).
    const TIMEOUT: u64 = 3008;
    let sck_half = PinTiming::default().sck_half;
    let mut m = spi_machine("watchdog_halts_mid_move");
    setup(&mut m, P, 4);
    ok(m.bus().write(watchdog_timeout::ADDR, TIMEOUT as u32));
    let planned = records(40, 20, true);
    push_all(&mut m, &planned);
    let run_wd = control::ESTOP_ACTIVE_HIGH.mask() | control::WATCHDOG_ENABLE.mask() | control::RUN.mask();
    let last_rise = timed_write(host(&mut m), control::ADDR, run_wd, sck_half);
    // The CRC's last byte is received 3 clocks after its 8th rising SCK edge; the write
    // it requests is granted in the next cycle, served from the register file's bus stage
    // in the one after, and kicks in the one after that.
    let kick = last_rise + 3 + 1 + 1 + 1;
    // Reads do not kick the watchdog.
    assert_eq!(read(&mut m, control::ADDR), run_wd);
    assert_eq!(status::STREAMING.get(ok(m.status())), 1);
    ok(m.bus().wait(TIMEOUT + 300));

    let halt = kick + TIMEOUT + 2;
    let in_flight = check_halted_pins(probe(&mut m), halt);
    assert!(in_flight, "the timeout is chosen so that a pulse is high at the halt");
    let stopped = check_halted_state(&mut m, status::FAULT_WATCHDOG.mask());
    assert_ne!(stopped, all_rounded(&planned), "halted mid-move");
    // Held: nothing moves however long we wait.
    let rises = probe(&mut m).rise_count();
    ok(m.bus().wait(5 * u64::from(P)));
    assert_eq!(probe(&mut m).rise_count(), rises);
    assert_eq!(positions(&mut m), stopped);

    // CLEAR_FAULTS kicks in the same cycle, so the watchdog is not expired: cleared.
    ok(m.command(command::CLEAR_FAULTS.set(0, 1)));
    let word = ok(m.status());
    assert_eq!(status::FAULT_WATCHDOG.get(word) | status::HALT.get(word), 0, "{word:#x}");
    ok(m.set_control(false, false, true));
    resume_exactly(&mut m, &stopped, 21, P);
}

/// The E-stop: a glitch shorter than the filter does nothing; held, it halts within
/// 3 + ESTOP_FILTER clocks; clearing while pressed does nothing; released and cleared,
/// the machine runs again.
#[test]
fn estop_halts_mid_move() {
    const P: u32 = 400;
    const FILTER: u64 = 10;
    let mut m = spi_machine("estop_halts_mid_move");
    setup(&mut m, P, 4);
    ok(m.bus().write(estop_filter::ADDR, FILTER as u32));
    let planned = records(40, 30, true);
    push_all(&mut m, &planned);
    ok(m.set_control(true, false, true));
    ok(m.bus().wait(3000));
    let enables_before = probe(&mut m).enables.len();

    // A glitch of FILTER - 1 samples: filtered out.
    host(&mut m).set_estop_pin(true);
    ok(m.bus().wait(FILTER - 1));
    host(&mut m).set_estop_pin(false);
    ok(m.bus().wait(FILTER + 10));
    assert_eq!(probe(&mut m).enables.len(), enables_before, "the glitch dropped an enable");
    let word = ok(m.status());
    assert_eq!(word & 0x3F, status::RUNNING.mask() | status::STREAMING.mask(), "{word:#x}");

    // Pressed and held: the first cycle the pin is active is `pressed`.
    // (Timed so that a step pulse is high when the halt comes: 1512..=1514 are.)
    ok(m.bus().wait(1513));
    let pressed = probe(&mut m).cycle;
    host(&mut m).set_estop_pin(true);
    ok(m.bus().wait(FILTER + 200));
    let drop = probe(&mut m).enables.last().unwrap().0;
    let halt = drop - 1;
    assert!(
        halt >= pressed + FILTER && halt <= pressed + 3 + FILTER,
        "pressed in cycle {pressed}, halted in cycle {halt}: outside FILTER ..= 3 + FILTER"
    );
    let in_flight = check_halted_pins(probe(&mut m), halt);
    assert!(in_flight, "the press is timed so that a pulse is high at the halt");
    let stopped = check_halted_state(&mut m, status::FAULT_ESTOP.mask());
    assert_ne!(stopped, all_rounded(&planned), "halted mid-move");
    assert_eq!(status::ESTOP_ACTIVE.get(ok(m.status())), 1);

    // Clearing while pressed does nothing.
    ok(m.command(command::CLEAR_FAULTS.set(0, 1)));
    let word = ok(m.status());
    assert_eq!(status::FAULT_ESTOP.get(word) & status::HALT.get(word), 1, "{word:#x}");
    // Released: the fault stays until cleared.
    host(&mut m).set_estop_pin(false);
    ok(m.bus().wait(FILTER + 5));
    let word = ok(m.status());
    assert_eq!(status::ESTOP_ACTIVE.get(word), 0, "{word:#x}");
    assert_eq!(status::FAULT_ESTOP.get(word) & status::HALT.get(word), 1, "sticky: {word:#x}");
    assert_eq!(positions(&mut m), stopped);
    ok(m.command(command::CLEAR_FAULTS.set(0, 1)));
    resume_exactly(&mut m, &stopped, 31, P);
}

/// An E-stop while the streamer waits for room: the halt flushes the FIFO and clears
/// RUN, so the room that appears is not records having run; `stream::run` polls STATUS
/// with FIFO_LEVEL and ends with `BusError::Halted` at the first poll after the halt
/// (it neither spins nor refills the flushed FIFO); a run started while halted is refused
/// before it writes a record. The pins stop as on any halt.
#[test]
fn estop_mid_stream_ends_the_run() {
    // Long enough for SPI to refill the FIFO faster than it runs (no underrun before the
    // press: the halt's STATUS shows none).
    const P: u32 = 4000;
    const FILTER: u64 = 10;
    const POLL: u64 = 150;
    let mut m = spi_machine("estop_mid_stream_ends_the_run");
    setup(&mut m, P, 4);
    ok(m.bus().write(estop_filter::ADDR, FILTER as u32));
    let planned = records(FIFO_DEPTH + 200, 41, true);
    let config = StreamConfig { poll_clocks: POLL, prefill: 32, ..StreamConfig::default() };
    let mut pressed = None;
    let result = stream::run(&mut m, planned.iter().copied(), &config, |m, event| {
        // Pressed at the first wait for room after the FIFO was filled once.
        if let (StreamEvent::Waited, None) = (event, pressed) {
            let host = m.bus().link_mut();
            pressed = Some(host.target().cycle);
            host.set_estop_pin(true);
        }
        Ok(())
    });
    let pressed = pressed.expect("the streamer waited for room");
    let ended = probe(&mut m).cycle;
    match result {
        Err(BusError::Halted { status: word }) => {
            assert_eq!(status::FAULT_ESTOP.get(word), 1, "{word:#x}");
            assert_eq!(status::UNDERRUN.get(word), 0, "the stream kept up until the halt: {word:#x}");
        }
        other => panic!("expected BusError::Halted, got {other:?}"),
    }
    let drop = probe(&mut m).enables.last().unwrap().0;
    let halt = drop - 1;
    assert!(halt >= pressed + FILTER && halt <= pressed + 3 + FILTER, "pressed {pressed}, halted {halt}");
    // Seen at the next poll: a wait and two read frames at most.
    let limit = POLL + 2_000;
    assert!(ended - halt <= limit, "the streamer saw the halt {} clocks after it (at most {limit})", ended - halt);
    check_halted_pins(probe(&mut m), halt);
    let stopped = check_halted_state(&mut m, status::FAULT_ESTOP.mask());
    assert_ne!(stopped, all_rounded(&planned), "halted mid-stream");

    // Still halted (the pin is held): a new run is refused, nothing queued or moved.
    let again = records(FIFO_DEPTH + 40, 43, true);
    let result = stream::run(&mut m, again.iter().copied(), &config, |_, _| Ok(()));
    assert!(matches!(result, Err(BusError::Halted { .. })), "{result:?}");
    assert_eq!(ok(m.fifo()), (0, FIFO_DEPTH as u32), "the refused run queued nothing");
    assert_eq!(positions(&mut m), stopped);
    host(&mut m).set_estop_pin(false);
    ok(m.bus().wait(FILTER + 5));
    ok(m.command(command::CLEAR_FAULTS.set(0, 1)));
    resume_exactly(&mut m, &stopped, 45, P);
}

/// Positions read while moving are coherent: all axes from one clock, the clock
/// LATCH_TIME says, and exactly the steps the pins had given by then.
fn coherent_positions<B: Bus>(m: &mut Machine<B>, probe: fn(&mut Machine<B>) -> &Probe) {
    const P: u32 = 500;
    setup(m, P, 4);
    let planned = records(40, 40, true);
    push_all(m, &planned);
    ok(m.set_control(true, false, true));
    let mut latch_times = Vec::new();
    for k in 0..12u64 {
        ok(m.bus().wait(137 * k));
        let read = ok(m.positions());
        // TIMESTAMP is 0 in the first cycle after reset: the latch took cycle `n`'s
        // positions, and a step counted in cycle `n` shows on its pin in `n + 1`.
        let n = u64::from(read.latch_time) + RESET_CYCLES;
        let p = probe(m);
        let pins: Vec<i32> = (0..N_AXES).map(|axis| p.pin_steps(axis, n + 1)).collect();
        assert_eq!(read.steps, pins, "read {k}: positions latched at TIMESTAMP {}", read.latch_time);
        latch_times.push(read.latch_time);
    }
    // While running the latch is on period boundaries.
    for pair in latch_times.windows(2) {
        assert_eq!((pair[1] - pair[0]) % P, 0, "latch times {latch_times:?}");
    }
    assert!(latch_times.windows(2).any(|w| w[0] != w[1]), "the reads spanned several periods");
    ok(wait_idle(m.bus(), 1000, 60 * u64::from(P)));
    ok(m.bus().wait(200));
    assert_eq!(ok(m.positions()).steps, all_rounded(&planned));
}

#[test]
fn positions_coherent_while_moving_over_spi() {
    let mut m = spi_machine("positions_coherent_while_moving_over_spi");
    coherent_positions(&mut m, probe);
}

#[test]
fn positions_coherent_while_moving_over_8080() {
    let mut m = parallel_machine("positions_coherent_while_moving_over_8080");
    coherent_positions(&mut m, parallel_probe);
}

//! The chip with the core's digit-serial step engine, as the CPLD board tops build it
//! (`finestep_top` with `STEP_DIGIT` > 0: [`TopVariant::MotionSerial`]), RTL and model in
//! lockstep at every pin on every clock, driven through the host driver over the 8080
//! bus (the CPLD boards' link) and SPI: the chip reports its round R in
//! `CAPS.STEP_ROUND_LOG2` and the driver keeps periods to multiples of it; a move ends
//! exactly on the rounded sums with every step pulse on the pins; an E-stop mid-move
//! stops the pins as the spec says and the next move ends exactly.
//!
//! Expectations come from docs/spec/ (step_serial.md: R = S * 32 / STEP_DIGIT clocks, the
//! drive timings in whole rounds; finestep_core.md: the DDA's round half up), not from
//! the model. The drive pins are watched on every clock by [`Probe`].

mod pin_probe;

use finestep_cosim::{rtl_top_params_of, TopVariant};
use finestep_host::regs::{
    axis_mode, axis_timing_a, axis_timing_b, estop_filter, fifo_level, record_inc, record_push, refused_record_count,
    status, underrun_count, version,
};
use finestep_host::stream::wait_idle;
use finestep_host::{AxisSetup, Bus, BusError, Machine};
use finestep_model::{DriveTiming, PeriodRecord, RateChecker};
use pin_probe::{ok, positions, rounded, ParallelMachine, Probe, N_AXES};

/// Step timing of every axis: L = 3, S = 3, U = 2, H = 2 clocks, each one round of the
/// serial engine once rounded up (docs/spec/step_serial.md).
const STEP_LEN: u64 = 3;
const AXIS: AxisSetup =
    AxisSetup { timing: DriveTiming::new(3, 3, 2, 2), out_mode: finestep_host::OutMode::StepDir, invert: 0 };

/// R: the clocks between two visits of an axis, from the spec's formula and the build's
/// parameters (S = 4 slots for 4 axes, 32 / STEP_DIGIT clocks a visit).
fn round() -> u32 {
    let build = finestep_rtl_sys::top_build_of(TopVariant::MotionSerial);
    assert!(build.step_shared && build.step_digit != 0, "the serial variant has the serial engine: {build:?}");
    let slots = 1u32 << (usize::BITS - (build.n_axes.max(2) - 1).leading_zeros());
    slots * 32 / build.step_digit
}

/// The serial chip, its step pulses L rounded up to whole rounds.
fn chip(name: &str) -> Probe {
    let r = u64::from(round());
    Probe::new(TopVariant::MotionSerial, name, STEP_LEN.div_ceil(r) * r)
}

fn parallel_machine(name: &str) -> ParallelMachine {
    pin_probe::parallel_machine(chip(name))
}

fn probe(m: &mut ParallelMachine) -> &Probe {
    m.bus().host_mut().target()
}

fn setup<B: Bus>(m: &mut Machine<B>, period: u32, start: u16) {
    pin_probe::setup(m, &AXIS, period, start);
}

/// [`pin_probe::records`] with a block end on the last, each checked against the serial
/// core's rated rate at `period`.
fn records(n: usize, seed: u64, period: u32) -> Vec<PeriodRecord> {
    let core = rtl_top_params_of(TopVariant::MotionSerial).core_params();
    let mut checker = RateChecker::for_core(&core, period, &[AXIS.timing; N_AXES]);
    let records = pin_probe::records(n, seed, true);
    for (k, record) in records.iter().enumerate() {
        checker.check(record).unwrap_or_else(|(axis, e)| panic!("record {k}, axis {axis}: {e}"));
    }
    records
}

fn push_all<B: Bus>(m: &mut Machine<B>, records: &[PeriodRecord]) {
    for record in records {
        ok(m.bus().push_records(std::slice::from_ref(record)));
    }
}

/// The chip reports R (not the step engine's S) and the driver refuses a period off it.
#[test]
fn serial_chip_reports_its_round() {
    let r = round();
    assert_eq!(r, 32, "4 axes, 4 bits a clock: S = 4, 8 clocks a visit");
    let mut m = parallel_machine("serial_chip_reports_its_round");
    assert_eq!(m.caps().step_slots, r, "{:?}", m.caps());
    assert!(matches!(m.set_period(13 * r + 16), Err(BusError::PeriodSlots { .. })));
    ok(m.set_period(13 * r));
    // Over SPI too: the same CAPS.
    let spi = pin_probe::spi_machine(chip("serial_chip_reports_its_round_spi"));
    assert_eq!(spi.caps().step_slots, r);
}

/// The chip reports the MAX II's register shapes in VERSION's capability bits (CAPS is
/// full): ONE_SNAPSHOT and INC_WRITE_ONLY, read through the driver in lockstep with the
/// model; and its RECORD_INC reads 0 after a write (docs/spec/register_file.md), while the
/// default chip reports neither.
#[test]
fn serial_chip_reports_its_register_shapes() {
    let build = rtl_top_params_of(TopVariant::MotionSerial);
    assert!(
        build.one_snapshot
            && build.inc_write_only
            && build.axis_write_only
            && build.inc_direct
            && build.enc_count_w == 16,
        "the serial chip has the MAX II's shapes: {build:?}"
    );
    let mut m = parallel_machine("serial_chip_reports_its_register_shapes");
    let caps = m.caps();
    assert!(
        caps.one_snapshot && caps.inc_write_only && caps.axis_write_only && caps.inc_direct && caps.enc_count_w == 16,
        "{caps:?}"
    );
    let word = ok(m.bus().read_one(version::ADDR));
    assert_eq!((version::MAJOR.get(word), version::MINOR.get(word), version::PATCH.get(word)), (1, 1, 0));
    let bits = [
        version::ONE_SNAPSHOT,
        version::INC_WRITE_ONLY,
        version::AXIS_WRITE_ONLY,
        version::INC_DIRECT,
        version::ENC_COUNT_16,
    ]
    .map(|f| f.get(word));
    assert_eq!(bits, [1, 1, 1, 1, 1], "{word:#x}");
    ok(m.bus().write(record_inc::addr(1), 0x1234_5678));
    assert_eq!(ok(m.bus().read_one(record_inc::addr(1))), 0, "RECORD_INC is write-only");
    // INC_DIRECT (docs/spec/register_file.md#record_inc-straight-into-the-fifo): a push with
    // one axis's RECORD_INC written is refused and queues nothing; with every axis's
    // written it is queued, and the same push again without writes is refused.
    let level = |m: &mut ParallelMachine| fifo_level::LEVEL.get(ok(m.bus().read_one(fifo_level::ADDR)));
    let refused = |m: &mut ParallelMachine| ok(m.bus().read_one(refused_record_count::ADDR));
    ok(m.bus().write(record_push::ADDR, 0));
    assert_eq!((level(&mut m), refused(&mut m)), (0, 1));
    for axis in 0..N_AXES {
        ok(m.bus().write(record_inc::addr(axis), 0));
    }
    ok(m.bus().write(record_push::ADDR, 0));
    ok(m.bus().write(record_push::ADDR, 0));
    assert_eq!((level(&mut m), refused(&mut m)), (1, 2));
    // The axis registers too; the core still takes what was written (the rated-rate
    // and pulse checks of the other tests run on the timings written).
    ok(m.configure_axis(2, &AXIS));
    for addr in [axis_timing_a::addr(2), axis_timing_b::addr(2), axis_mode::addr(2)] {
        assert_eq!(ok(m.bus().read_one(addr)), 0, "{addr:#x} is write-only");
    }
    // No probe event yet: the positions are the period latch's.
    assert!(!ok(m.probe_holds_positions()));
    let spi =
        pin_probe::spi_machine(Probe::new(TopVariant::Motion, "serial_chip_reports_its_register_shapes_default", 1));
    let caps = spi.caps();
    assert!(!caps.one_snapshot && !caps.inc_write_only && !caps.axis_write_only, "{caps:?}");
    assert_eq!(caps.enc_count_w, 32, "{caps:?}");
}

/// A move over the 8080 bus ends exactly on every axis's rounded sum, every step on the
/// pins, every pulse L rounded up to rounds; no underrun.
#[test]
fn serial_chip_moves_exactly_over_8080() {
    let period = 40 * round();
    let mut m = parallel_machine("serial_chip_moves_exactly_over_8080");
    setup(&mut m, period, 2);
    let planned = records(24, 7, period);
    push_all(&mut m, &planned);
    ok(m.set_control(true, false, true));
    ok(wait_idle(m.bus(), 1000, 40 * u64::from(period)));
    ok(m.bus().wait(500));
    let expected: Vec<i32> = (0..N_AXES).map(|axis| rounded(&planned, axis)).collect();
    assert!(expected.iter().all(|&e| e != 0), "every axis moves: {expected:?}");
    let end = positions(&mut m);
    assert_eq!(end, expected);
    assert_eq!(probe(&mut m).all_pin_steps(), end, "POSITION against the pulses on the pins");
    probe(&mut m).assert_pulses_exact();
    assert_eq!(ok(m.bus().read_one(underrun_count::ADDR)), 0);
    let word = ok(m.status());
    assert_eq!(status::RATE_ERROR.get(word) | status::UNDERRUN.get(word), 0, "{word:#x}");
}

/// An E-stop mid-move: the enables drop, no pulse rises after, the positions are the
/// pins' count; cleared, the next move ends exactly from there.
#[test]
fn serial_chip_estop_halts_mid_move() {
    const FILTER: u64 = 10;
    let period = 40 * round();
    let mut m = parallel_machine("serial_chip_estop_halts_mid_move");
    setup(&mut m, period, 2);
    ok(m.bus().write(estop_filter::ADDR, FILTER as u32));
    let planned = records(12, 30, period);
    push_all(&mut m, &planned);
    ok(m.set_control(true, false, true));
    ok(m.bus().wait(3 * u64::from(period) + 123));
    let pressed = probe(&mut m).cycle;
    m.bus().host_mut().set_estop_pin(true);
    ok(m.bus().wait(FILTER + 200));
    let (drop, mask) = *probe(&mut m).enables.last().unwrap();
    assert_eq!(mask, 0, "enables dropped");
    assert!(drop > pressed + FILTER && drop <= pressed + FILTER + 4, "pressed {pressed}, enables dropped {drop}");
    for axis in 0..N_AXES {
        let late = probe(&mut m).rises[axis].iter().find(|&&(c, _)| c > drop).copied();
        assert_eq!(late, None, "axis {axis}: a pulse rose after the halt");
    }
    let word = ok(m.status());
    assert_eq!(status::HALT.get(word) & status::FAULT_ESTOP.get(word), 1, "{word:#x}");
    ok(m.bus().wait(4 * u64::from(round())));
    probe(&mut m).assert_pulses_exact();
    let stopped = positions(&mut m);
    assert_eq!(probe(&mut m).all_pin_steps(), stopped);
    let all: Vec<i32> = (0..N_AXES).map(|axis| rounded(&planned, axis)).collect();
    assert_ne!(stopped, all, "halted mid-move");

    m.bus().host_mut().set_estop_pin(false);
    ok(m.bus().wait(FILTER + 5));
    ok(m.clear_faults_and_errors());
    assert_eq!(status::HALT.get(ok(m.status())), 0);
    let again = records(8, 31, period);
    push_all(&mut m, &again);
    ok(m.set_control(true, false, true));
    ok(wait_idle(m.bus(), 1000, 30 * u64::from(period)));
    ok(m.bus().wait(500));
    let expected: Vec<i32> = (0..N_AXES).map(|axis| stopped[axis] + rounded(&again, axis)).collect();
    let end = positions(&mut m);
    assert_eq!(end, expected, "the move after the E-stop");
    assert_eq!(probe(&mut m).all_pin_steps(), end);
    probe(&mut m).assert_pulses_exact();
}

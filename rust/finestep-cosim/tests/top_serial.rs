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

use finestep_cosim::{rtl_top_params_of, TopLockstep, TopVariant};
use finestep_host::pins::layout::{OUT_PIN_A0, OUT_PIN_B0, OUT_PIN_EN0};
use finestep_host::regs::{estop_filter, position, status, underrun_count};
use finestep_host::stream::wait_idle;
use finestep_host::{AxisSetup, Bus, BusError, Machine, ParallelBus, PinHost, PinTarget, PinTiming, SpiBus};
use finestep_model::{DriveTiming, PeriodRecord, RateChecker};

const N_AXES: usize = 4;
/// Step timing of every axis: L = 3, S = 3, U = 2, H = 2 clocks, each one round of the
/// serial engine once rounded up (docs/spec/step_serial.md).
const STEP_LEN: u64 = 3;
const AXIS: AxisSetup =
    AxisSetup { timing: DriveTiming::new(3, 3, 2, 2), out_mode: finestep_host::OutMode::StepDir, invert: 0 };
/// Largest |increment| the record generator makes, in steps.
const MAX_STEPS: i64 = 8;
const RESET_CYCLES: u64 = 4;

fn ok<T>(result: Result<T, BusError>) -> T {
    result.unwrap_or_else(|e| panic!("{e}"))
}

/// R: the clocks between two visits of an axis, from the spec's formula and the build's
/// parameters (S = 4 slots for 4 axes, 32 / STEP_DIGIT clocks a visit).
fn round() -> u32 {
    let build = finestep_rtl_sys::top_build_of(TopVariant::MotionSerial);
    assert!(build.step_shared && build.step_digit != 0, "the serial variant has the serial engine: {build:?}");
    let slots = 1u32 << (usize::BITS - (build.n_axes.max(2) - 1).leading_zeros());
    slots * 32 / build.step_digit
}

/// [`TopLockstep`] stepped one clock at a time, recording the drive pins.
struct Probe {
    inner: TopLockstep,
    cycle: u64,
    outputs: u64,
    /// Per axis: (cycle pin A rose, +1 with pin B high, -1 with it low).
    rises: Vec<Vec<(u64, i32)>>,
    high_since: Vec<Option<u64>>,
    /// Every completed step pulse: (axis, rise cycle, cycles high).
    pulses: Vec<(usize, u64, u64)>,
    /// Every change of the enable pins: (cycle, mask).
    enables: Vec<(u64, u32)>,
}

impl Probe {
    fn new(name: &str) -> Probe {
        let inner = TopLockstep::motion_serial(name);
        let outputs = inner.outputs();
        Probe {
            inner,
            cycle: 0,
            outputs,
            rises: vec![Vec::new(); N_AXES],
            high_since: vec![None; N_AXES],
            pulses: Vec::new(),
            enables: vec![(0, enable_mask(outputs))],
        }
    }

    fn observe(&mut self, out: u64) {
        let was = self.outputs;
        for axis in 0..N_AXES {
            let a = out >> (OUT_PIN_A0 + axis as u32) & 1;
            let a_was = was >> (OUT_PIN_A0 + axis as u32) & 1;
            if a == 1 && a_was == 0 {
                let dir = if out >> (OUT_PIN_B0 + axis as u32) & 1 == 1 { 1 } else { -1 };
                self.rises[axis].push((self.cycle, dir));
                self.high_since[axis] = Some(self.cycle);
            } else if a == 0 && a_was == 1 {
                let rose = self.high_since[axis].take().expect("a fall after a rise");
                self.pulses.push((axis, rose, self.cycle - rose));
            }
        }
        if enable_mask(out) != enable_mask(was) {
            self.enables.push((self.cycle, enable_mask(out)));
        }
        self.outputs = out;
    }

    fn all_pin_steps(&self) -> Vec<i32> {
        self.rises.iter().map(|r| r.iter().map(|&(_, d)| d).sum()).collect()
    }

    /// Every pulse was high exactly L rounded up to whole rounds; none is still high.
    fn assert_pulses_exact(&self) {
        let r = u64::from(round());
        let high = STEP_LEN.div_ceil(r) * r;
        for &(axis, rose, width) in &self.pulses {
            assert_eq!(width, high, "axis {axis}: the pulse rising in cycle {rose} was high {width} cycles");
        }
        assert!(self.high_since.iter().all(Option::is_none), "a step pulse is still high: {:?}", self.high_since);
    }
}

fn enable_mask(out: u64) -> u32 {
    (out >> OUT_PIN_EN0) as u32 & ((1 << N_AXES) - 1)
}

impl PinTarget for Probe {
    fn drive(&mut self, inputs: u64, cycles: u64) -> Result<(), BusError> {
        for _ in 0..cycles {
            self.inner.drive(inputs, 1)?;
            self.cycle += 1;
            let out = self.inner.outputs();
            self.observe(out);
        }
        Ok(())
    }

    fn outputs(&self) -> u64 {
        self.outputs
    }
}

type ParallelMachine = Machine<ParallelBus<Probe>>;

fn parallel_machine(name: &str) -> ParallelMachine {
    let mut host = PinHost::new(Probe::new(name), PinTiming::default());
    ok(host.reset(RESET_CYCLES));
    ok(host.idle(4));
    ok(Machine::connect(ParallelBus::new(host, N_AXES)))
}

fn probe(m: &mut ParallelMachine) -> &Probe {
    m.bus().host_mut().target()
}

fn setup<B: Bus>(m: &mut Machine<B>, period: u32, start: u16) {
    for axis in 0..N_AXES {
        ok(m.configure_axis(axis, &AXIS));
    }
    ok(m.enable_axes((1 << N_AXES) - 1));
    ok(m.set_period(period));
    ok(m.set_start_level(start));
    ok(m.clear_faults_and_errors());
    assert_eq!(status::HALT.get(ok(m.status())), 0);
}

/// `n` records from a linear congruential generator, |increment| <= MAX_STEPS steps with
/// a random fraction: axis 0 forwards, 1 backwards, 2 and 3 both ways; each checked
/// against the serial core's rated rate at `period`.
fn records(n: usize, seed: u64, period: u32) -> Vec<PeriodRecord> {
    let mut state = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
    let span = ((2 * MAX_STEPS) << 16) as u64 + 1;
    let core = rtl_top_params_of(TopVariant::MotionSerial).core_params();
    let mut checker = RateChecker::for_core(&core, period, &[AXIS.timing; N_AXES]);
    (0..n)
        .map(|k| {
            let mut raw = [0i32; N_AXES];
            for (axis, slot) in raw.iter_mut().enumerate() {
                state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                let value = ((state >> 20) % span) as i64 - (MAX_STEPS << 16);
                *slot = match axis {
                    0 => value.abs(),
                    1 => -value.abs(),
                    3 => value / 5,
                    _ => value,
                } as i32;
            }
            let record = PeriodRecord::from_raw(&raw, u8::from(k + 1 == n));
            checker.check(&record).unwrap_or_else(|(axis, e)| panic!("record {k}, axis {axis}: {e}"));
            record
        })
        .collect()
}

fn rounded(records: &[PeriodRecord], axis: usize) -> i32 {
    let total: i64 = records.iter().map(|r| i64::from(r.inc[axis].to_bits())).sum();
    ((total + (1 << 15)) >> 16) as i32
}

fn push_all<B: Bus>(m: &mut Machine<B>, records: &[PeriodRecord]) {
    for record in records {
        ok(m.bus().push_records(std::slice::from_ref(record)));
    }
}

/// Positions at rest: read twice, equal.
fn positions<B: Bus>(m: &mut Machine<B>) -> Vec<i32> {
    let read_once = |m: &mut Machine<B>| {
        let mut words = vec![0u32; N_AXES];
        ok(m.bus().read(position::addr(0), &mut words));
        words.into_iter().map(|w| w as i32).collect::<Vec<i32>>()
    };
    let first = read_once(m);
    assert_eq!(read_once(m), first, "positions still changing");
    first
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
    let mut host = PinHost::new(Probe::new("serial_chip_reports_its_round_spi"), PinTiming::default());
    ok(host.reset(RESET_CYCLES));
    ok(host.idle(4));
    let spi = ok(Machine::connect(SpiBus::new(host, N_AXES)));
    assert_eq!(spi.caps().step_slots, r);
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

//! The chip at its pins, RTL and model in lockstep, driven through the host driver:
//! [`Probe`] (a [`PinTarget`] wrapping [`TopLockstep`]) steps one clock at a time and
//! records the drive pins of every cycle, so step pulses are counted and timed on the
//! pins themselves; with the machines over SPI and the 8080 bus built on it, the set-up
//! the chip-level motion tests share, and the spec's arithmetic they compare with.

#![allow(dead_code)]

use finestep_cosim::{TopLockstep, TopVariant};
use finestep_host::pins::layout::{OUT_PIN_A0, OUT_PIN_B0, OUT_PIN_EN0};
use finestep_host::regs::{position, status};
use finestep_host::{AxisSetup, Bus, BusError, Machine, ParallelBus, PinHost, PinTarget, PinTiming, SpiBus};
use finestep_model::PeriodRecord;

/// Axes of the chips the tests run.
pub const N_AXES: usize = 4;
/// Largest |increment| [`records`] makes, in steps: within the rated rate (|D| * I_rev
/// <= P) of the tests' axis timing at every period they use (P >= 128 on the step engine).
pub const MAX_STEPS: i64 = 8;
/// Cycles of reset [`PinHost::reset`] is given; `TIMESTAMP` is 0 in the first cycle after.
pub const RESET_CYCLES: u64 = 4;

/// Unwraps a bus result, printing a co-simulation mismatch in full.
pub fn ok<T>(result: Result<T, BusError>) -> T {
    result.unwrap_or_else(|e| panic!("{e}"))
}

/// [`TopLockstep`] stepped one clock at a time, recording the drive pins of every cycle.
pub struct Probe {
    inner: TopLockstep,
    /// Cycles run (the same count as `TopLockstep::cycle`).
    pub cycle: u64,
    outputs: u64,
    /// Per axis: (cycle pin A rose, +1 with pin B high in that cycle, -1 with it low).
    pub rises: Vec<Vec<(u64, i32)>>,
    /// Per axis: the cycle pin A rose, while it is high.
    high_since: Vec<Option<u64>>,
    /// Every completed step pulse: (axis, rise cycle, cycles high).
    pub pulses: Vec<(usize, u64, u64)>,
    /// Every change of the enable pins: (cycle, pin_en mask).
    pub enables: Vec<(u64, u32)>,
    /// Cycles every step pulse is high (the step length as the chip's engine places it).
    pulse_high: u64,
}

impl Probe {
    /// The chip `variant` at power-on, its step pulses expected `pulse_high` cycles high.
    pub fn new(variant: TopVariant, name: &str, pulse_high: u64) -> Probe {
        let inner = TopLockstep::of(variant, name);
        let outputs = inner.outputs();
        Probe {
            inner,
            cycle: 0,
            outputs,
            rises: vec![Vec::new(); N_AXES],
            high_since: vec![None; N_AXES],
            pulses: Vec::new(),
            enables: vec![(0, enable_mask(outputs))],
            pulse_high,
        }
    }

    fn observe(&mut self, out: u64) {
        let prev = self.outputs;
        for axis in 0..N_AXES {
            let a = out >> (OUT_PIN_A0 + axis as u32) & 1 != 0;
            let was = prev >> (OUT_PIN_A0 + axis as u32) & 1 != 0;
            if a && !was {
                let dir = if out >> (OUT_PIN_B0 + axis as u32) & 1 != 0 { 1 } else { -1 };
                self.rises[axis].push((self.cycle, dir));
                self.high_since[axis] = Some(self.cycle);
            }
            if !a && was {
                let rose = self.high_since[axis].take().expect("a fall after a rise");
                self.pulses.push((axis, rose, self.cycle - rose));
            }
        }
        if enable_mask(out) != enable_mask(prev) {
            self.enables.push((self.cycle, enable_mask(out)));
        }
        self.outputs = out;
    }

    /// Steps counted on the pins of `axis` (pin A rising edges, signed by pin B) in the
    /// cycles up to and including `cycle`.
    pub fn pin_steps(&self, axis: usize, cycle: u64) -> i32 {
        self.rises[axis].iter().filter(|&&(c, _)| c <= cycle).map(|&(_, d)| d).sum()
    }

    /// Steps counted on the pins of every axis so far.
    pub fn all_pin_steps(&self) -> Vec<i32> {
        (0..N_AXES).map(|axis| self.pin_steps(axis, u64::MAX)).collect()
    }

    /// Step pulses begun so far, every axis.
    pub fn rise_count(&self) -> usize {
        self.rises.iter().map(Vec::len).sum()
    }

    /// Every step pulse so far was high exactly the cycles given at construction, none is
    /// still high.
    pub fn assert_pulses_exact(&self) {
        for &(axis, rose, width) in &self.pulses {
            assert_eq!(width, self.pulse_high, "axis {axis}: the pulse rising in cycle {rose} was high {width} cycles");
        }
        assert!(self.high_since.iter().all(Option::is_none), "a step pulse is still high: {:?}", self.high_since);
    }
}

/// The enable pins of `out` as a mask, axis 0 in bit 0.
pub fn enable_mask(out: u64) -> u32 {
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

/// The host driver over SPI on a probed chip.
pub type SpiMachine = Machine<SpiBus<PinHost<Probe>>>;
/// The host driver over the 8080 bus on a probed chip.
pub type ParallelMachine = Machine<ParallelBus<Probe>>;

/// `probe`'s chip reset, then connected over SPI.
pub fn spi_machine(probe: Probe) -> SpiMachine {
    let mut host = PinHost::new(probe, PinTiming::default());
    ok(host.reset(RESET_CYCLES));
    ok(host.idle(4));
    ok(Machine::connect(SpiBus::new(host, N_AXES)))
}

/// `probe`'s chip reset, then connected over the 8080 bus.
pub fn parallel_machine(probe: Probe) -> ParallelMachine {
    let mut host = PinHost::new(probe, PinTiming::default());
    ok(host.reset(RESET_CYCLES));
    ok(host.idle(4));
    ok(Machine::connect(ParallelBus::new(host, N_AXES)))
}

/// Every axis set up as `axis`, enabled; the period and start level; the power-on
/// E-stop fault cleared.
pub fn setup<B: Bus>(machine: &mut Machine<B>, axis: &AxisSetup, period: u32, start: u16) {
    for n in 0..N_AXES {
        ok(machine.configure_axis(n, axis));
    }
    ok(machine.enable_axes((1 << N_AXES) - 1));
    ok(machine.set_period(period));
    ok(machine.set_start_level(start));
    ok(machine.clear_faults_and_errors());
    let word = ok(machine.status());
    assert_eq!(status::HALT.get(word), 0, "status {word:#x}");
}

/// `n` records from a small linear congruential generator, every increment within
/// +-MAX_STEPS steps with a random fraction; `block_end` on the last one if asked.
pub fn records(n: usize, seed: u64, block_end: bool) -> Vec<PeriodRecord> {
    let mut state = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
    let span = ((2 * MAX_STEPS) << 16) as u64 + 1;
    (0..n)
        .map(|k| {
            let mut raw = [0i32; N_AXES];
            for (axis, slot) in raw.iter_mut().enumerate() {
                state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                let value = ((state >> 20) % span) as i64 - (MAX_STEPS << 16);
                // Axis 0 only forwards, axis 1 only backwards, 2 and 3 both ways.
                *slot = match axis {
                    0 => value.abs(),
                    1 => -value.abs(),
                    3 => value / 5,
                    _ => value,
                } as i32;
            }
            PeriodRecord::from_raw(&raw, u8::from(block_end && k + 1 == n))
        })
        .collect()
}

/// The DDA's position after `records`: the summed increments rounded half up.
pub fn rounded(records: &[PeriodRecord], axis: usize) -> i32 {
    let total: i64 = records.iter().map(|r| i64::from(r.inc[axis].to_bits())).sum();
    ((total + (1 << 15)) >> 16) as i32
}

/// [`rounded`] for every axis.
pub fn all_rounded(records: &[PeriodRecord]) -> Vec<i32> {
    (0..N_AXES).map(|axis| rounded(records, axis)).collect()
}

/// Every axis's position once the axes are at rest (motion over, or halted): read
/// twice, equal. Not `Machine::positions`, which cannot read a stopped core
/// (LATCH_TIME changes every clock while not running, so its before/after check never
/// passes).
pub fn positions<B: Bus>(machine: &mut Machine<B>) -> Vec<i32> {
    let read_once = |machine: &mut Machine<B>| {
        let mut words = vec![0u32; N_AXES];
        ok(machine.bus().read(position::addr(0), &mut words));
        words.into_iter().map(|w| w as i32).collect::<Vec<i32>>()
    };
    let first = read_once(machine);
    assert_eq!(read_once(machine), first, "positions still changing");
    first
}

//! The spindle, the logic outputs and the interlock at the chip's pins, RTL and model in
//! lockstep every clock (`TopLockstep`), driven through the host driver over SPI.
//!
//! Every expectation is stated here from docs/spec/spindle.md and
//! docs/spec/logic_outputs.md, not read from the model: the PWM's high clocks per period
//! and its period counted on the pin, the ramp's steps, the DAC frames decoded from
//! CS_n/SCK/SDI as an MCP4921 does, the halt's safe state on the clock after the axes'
//! enables drop (the same halt), and the interlock holding a run's start.

use finestep_cosim::TopLockstep;
use finestep_host::pins::layout::*;
use finestep_host::regs::{command, estop_filter, interlock, outputs_safe, spindle_control, status, watchdog_timeout};
use finestep_host::{
    Bus, BusError, InterlockSetup, Machine, Outputs, PeriodRecord, PinHost, PinTarget, PinTiming, SpiBus, SpindleSetup,
};

const N_AXES: usize = 4;

fn ok<T>(result: Result<T, BusError>) -> T {
    result.unwrap_or_else(|e| panic!("{e}"))
}

/// [`TopLockstep`] one clock at a time, keeping the packed outputs of every cycle.
struct Recorder {
    inner: TopLockstep,
    trace: Vec<u64>,
}

impl PinTarget for Recorder {
    fn drive(&mut self, inputs: u64, cycles: u64) -> Result<(), BusError> {
        for _ in 0..cycles {
            self.inner.drive(inputs, 1)?;
            self.trace.push(self.inner.outputs());
        }
        Ok(())
    }

    fn outputs(&self) -> u64 {
        self.inner.outputs()
    }
}

type M = Machine<SpiBus<PinHost<Recorder>>>;

fn machine(name: &str) -> M {
    let recorder = Recorder { inner: TopLockstep::new(name), trace: Vec::new() };
    let mut host = PinHost::new(recorder, PinTiming::default());
    ok(host.reset(4));
    ok(host.idle(4));
    let mut m = ok(Machine::connect(SpiBus::new(host, N_AXES)));
    assert!(m.caps().has_spindle && m.caps().has_outputs, "finestep_top's default builds both");
    ok(m.enable_axes((1 << N_AXES) - 1));
    ok(m.clear_faults_and_errors());
    assert_eq!(status::HALT.get(ok(m.status())), 0);
    m
}

fn trace(m: &mut M) -> &Vec<u64> {
    &m.bus().link_mut().target().trace
}

fn bit(word: u64, index: u32) -> bool {
    word >> index & 1 != 0
}

/// The cycle (trace index) the axes' enables dropped: the halt's first clock + 1.
fn enables_drop(t: &[u64]) -> usize {
    let mask = ((1u64 << N_AXES) - 1) << OUT_PIN_EN0;
    (1..t.len()).find(|&i| t[i - 1] & mask == mask && t[i] & mask == 0).expect("the enables dropped")
}

/// Frames decoded as the DAC does: the bits at rising SCK while CS_n is low, latched at
/// CS_n's rise; (the cycle CS_n fell, the word, the count of bits).
fn dac_frames(t: &[u64]) -> Vec<(usize, u32, u32)> {
    let mut frames = Vec::new();
    let (mut start, mut word, mut bits) = (0, 0u32, 0u32);
    for i in 1..t.len() {
        let (prev, now) = (t[i - 1], t[i]);
        if bit(prev, OUT_DAC_CS_N) && !bit(now, OUT_DAC_CS_N) {
            (start, word, bits) = (i, 0, 0);
        }
        if !bit(now, OUT_DAC_CS_N) && bit(now, OUT_DAC_SCK) && !bit(prev, OUT_DAC_SCK) {
            word = word << 1 | u32::from(bit(now, OUT_DAC_SDI));
            bits += 1;
        }
        if bit(now, OUT_DAC_SCK) && bit(prev, OUT_DAC_SCK) {
            assert_eq!(bit(now, OUT_DAC_SDI), bit(prev, OUT_DAC_SDI), "SDI moved while SCK was high ({i})");
        }
        if bit(now, OUT_DAC_CS_N) {
            assert!(!bit(now, OUT_DAC_SCK) && !bit(now, OUT_DAC_SDI), "SCK/SDI with CS_n high ({i})");
        }
        if !bit(prev, OUT_DAC_CS_N) && bit(now, OUT_DAC_CS_N) {
            frames.push((start, word, bits));
        }
    }
    frames
}

/// PWM at the pin with a ramp, then the E-stop while the spindle runs: the pins go off
/// on the clock the axes' enables drop, ENABLE is cleared, the outputs go safe.
#[test]
fn spindle_pwm_ramp_and_estop() {
    const P: u16 = 60;
    const LEVEL: u16 = 45;
    const RAMP: u16 = 10;
    let mut m = machine("spindle_pwm_ramp_and_estop");
    ok(m.bus().write(estop_filter::ADDR, 4));
    ok(m.configure_spindle(&SpindleSetup { period_clocks: P, ramp_step: RAMP, dac: false, dac_div: 0 }));
    let safe = Outputs { mist: false, flood: false, light: true, gpio: 0b0001 };
    ok(m.set_safe_outputs(&safe));
    ok(m.set_outputs(&Outputs { mist: true, flood: true, light: false, gpio: 0b1010 }));
    let start = trace(&mut m).len();
    ok(m.set_spindle(true, true, LEVEL));
    ok(m.bus().wait(40 * u64::from(P)));
    let t = trace(&mut m)[start..].to_vec();
    // Periods at the pin: rising edges P clocks apart; high clocks per period ramp up by
    // at most RAMP and settle at LEVEL exactly.
    let rises: Vec<usize> =
        (1..t.len()).filter(|&i| bit(t[i], OUT_SPINDLE_PWM) && !bit(t[i - 1], OUT_SPINDLE_PWM)).collect();
    assert!(rises.len() > 20);
    let highs: Vec<u16> = rises
        .windows(2)
        .map(|w| {
            assert_eq!(w[1] - w[0], usize::from(P), "the PWM period");
            (w[0]..w[1]).filter(|&i| bit(t[i], OUT_SPINDLE_PWM)).count() as u16
        })
        .collect();
    assert!(highs.windows(2).all(|w| w[1] >= w[0] && w[1] - w[0] <= RAMP), "ramp: {highs:?}");
    assert_eq!(*highs.last().unwrap(), LEVEL);
    assert_eq!(highs.iter().filter(|&&h| h < LEVEL).count(), (usize::from(LEVEL) - 1) / usize::from(RAMP));
    let last = *t.last().unwrap();
    assert!(bit(last, OUT_SPINDLE_EN) && bit(last, OUT_SPINDLE_DIR) && bit(last, OUT_DAC_CS_N));
    assert!(bit(last, OUT_COOLANT_MIST) && bit(last, OUT_COOLANT_FLOOD) && !bit(last, OUT_LIGHT));
    assert_eq!(last >> OUT_GPIO0 & 0xF, 0b1010);
    let status = ok(m.spindle_status());
    assert!(status.at_speed && status.enabled && status.level == LEVEL, "{status:?}");

    // The E-stop mid-period, held.
    let before = trace(&mut m).len();
    m.bus().link_mut().set_estop_pin(true);
    ok(m.bus().wait(200));
    let t = trace(&mut m)[before..].to_vec();
    let drop = enables_drop(&t);
    for (i, &out) in t.iter().enumerate().skip(drop) {
        assert!(!bit(out, OUT_SPINDLE_EN) && !bit(out, OUT_SPINDLE_PWM), "spindle on after the halt ({i})");
        assert!(!bit(out, OUT_COOLANT_MIST) && !bit(out, OUT_COOLANT_FLOOD) && bit(out, OUT_LIGHT));
        assert_eq!(out >> OUT_GPIO0 & 0xF, 0b0001, "safe levels");
    }
    assert!(bit(t[drop - 1], OUT_SPINDLE_EN) && bit(t[drop - 1], OUT_COOLANT_MIST), "on until the halt");
    assert_eq!(spindle_control::ENABLE.get(ok(m.bus().read_one(spindle_control::ADDR))), 0);
    assert_eq!(ok(m.outputs()), safe, "OUTPUTS holds the safe levels");
    // Released and cleared: the spindle stays off until the host enables it.
    m.bus().link_mut().set_estop_pin(false);
    ok(m.bus().wait(20));
    ok(m.command(command::CLEAR_FAULTS.set(0, 1)));
    ok(m.bus().wait(5 * u64::from(P)));
    let after = *trace(&mut m).last().unwrap();
    assert!(!bit(after, OUT_SPINDLE_EN) && !bit(after, OUT_SPINDLE_PWM));
}

/// The DAC: every frame is 16 bits carrying 0x3000 | level; the watchdog's halt aborts
/// the frame in flight and the next frame commands 0.
#[test]
fn spindle_dac_frames_and_watchdog() {
    const P: u16 = 150;
    const LEVEL: u16 = 2345;
    const TIMEOUT: u32 = 3000;
    let mut m = machine("spindle_dac_frames_and_watchdog");
    ok(m.configure_spindle(&SpindleSetup { period_clocks: P, ramp_step: 0, dac: true, dac_div: 1 }));
    let start = trace(&mut m).len();
    ok(m.set_spindle(true, false, LEVEL));
    ok(m.bus().write(watchdog_timeout::ADDR, TIMEOUT));
    ok(m.set_control(false, true, true));
    ok(m.bus().wait(u64::from(TIMEOUT) + 1000));
    let t = trace(&mut m)[start..].to_vec();
    let drop = (1..t.len()).find(|&i| bit(t[i - 1], OUT_SPINDLE_EN) && !bit(t[i], OUT_SPINDLE_EN)).expect("halted");
    assert_eq!(status::FAULT_WATCHDOG.get(ok(m.status())), 1);
    let frames = dac_frames(&t);
    let before: Vec<_> = frames.iter().filter(|f| f.0 < drop).collect();
    let after: Vec<_> = frames.iter().filter(|f| f.0 >= drop).collect();
    assert!(before.len() >= 10 && after.len() >= 3);
    for f in &frames {
        assert_eq!(f.2, 16, "bits in the frame at {}", f.0);
    }
    // Level 0 until the writes (no ramp) take effect at a period's end, then the level.
    let words: Vec<u32> = before.iter().map(|f| f.1).collect();
    let zeros = words.iter().take_while(|&&w| w == 0x3000).count();
    assert!(zeros < words.len() && words[zeros..].iter().all(|&w| w == 0x3000 | u32::from(LEVEL)), "{words:x?}");
    // The frame in flight at the halt (if any) was aborted: CS_n high on the drop clock,
    // and the next frame, starting the clock after, commands 0.
    assert!(bit(t[drop], OUT_DAC_CS_N) && !bit(t[drop], OUT_DAC_SCK));
    assert_eq!(after[0].0, drop + 1, "the zero frame starts the clock after the halt");
    assert!(after.iter().all(|f| f.1 == 0x3000), "{after:x?}");
    // Frames never start less than a period apart, and exactly P apart while running.
    assert!(before.windows(2).skip(1).all(|w| w[1].0 - w[0].0 == usize::from(P)));
}

/// The interlock: active, it holds a run's start (BLOCKED set, nothing streams); released,
/// the gate opens and the records run.
#[test]
fn interlock_holds_the_start() {
    let mut m = machine("interlock_holds_the_start");
    ok(m.set_period(200));
    ok(m.set_start_level(2));
    // A prescale the 14-bit field cannot hold is refused before anything is written.
    let wide = InterlockSetup { enable: true, active_high: true, filter_samples: 3, prescale: 1 << 14 };
    assert!(matches!(m.configure_interlock(&wide), Err(BusError::SettingRange { max: 0x3FFF, .. })));
    // 3 samples of 7 clocks: active 21-27 clocks after the pin (plus the synchroniser),
    // once the prescaler has counted down the reset setting's 5 000 clocks (a new
    // PRESCALE takes effect at the next sample).
    ok(m.configure_interlock(&InterlockSetup { enable: true, active_high: true, filter_samples: 3, prescale: 6 }));
    ok(m.bus().wait(5_000));
    m.bus().link_mut().set_interlock_pin(true);
    ok(m.bus().wait(30));
    assert_eq!(ok(m.interlock()), (true, false));
    let records: Vec<PeriodRecord> = (0..4).map(|_| PeriodRecord::from_raw(&[1 << 16, 0, 0, 0], 0)).collect();
    ok(m.bus().push_records(&records));
    ok(m.set_control(true, false, true));
    ok(m.bus().wait(1000));
    let word = ok(m.status());
    assert_eq!(status::STREAMING.get(word), 0, "the interlock holds the gate: {word:#x}");
    assert_eq!(ok(m.interlock()), (true, true));
    assert_eq!(ok(m.fifo()).0, 4, "nothing consumed");
    // A glitch-free release: the gate opens and the records run.
    m.bus().link_mut().set_interlock_pin(false);
    ok(m.bus().wait(2000));
    assert_eq!(ok(m.fifo()).0, 0, "consumed after the release");
    assert_eq!(ok(m.positions()).steps[0], 4);
    assert_eq!(ok(m.interlock()), (false, true), "BLOCKED is sticky");
    ok(m.command(command::CLEAR_ERRORS.set(0, 1)));
    assert_eq!(ok(m.interlock()), (false, false));
    // The interlock rising under an open gate neither closes it nor reports a blocked
    // start (BLOCKED is for a gate it holds shut): a mutant that pulsed start_blocked
    // whenever the threshold was reached survived every other check.
    // Stopped, periods of 4 000 clocks and 8 records queued, then run: the host's reads
    // (hundreds of clocks each over SPI) leave more than the threshold queued while the
    // interlock rises.
    ok(m.set_control(false, false, true));
    ok(m.set_period(4000));
    let records: Vec<PeriodRecord> = (0..8).map(|_| PeriodRecord::from_raw(&[1 << 16, 0, 0, 0], 0)).collect();
    ok(m.bus().push_records(&records));
    ok(m.set_control(true, false, true));
    ok(m.bus().wait(300));
    assert_eq!(status::STREAMING.get(ok(m.status())), 1, "the gate opened");
    m.bus().link_mut().set_interlock_pin(true);
    ok(m.bus().wait(60));
    let word = ok(m.status());
    assert_eq!(status::STREAMING.get(word), 1, "an open gate stays open: {word:#x}");
    assert_eq!(ok(m.interlock()), (true, false), "no blocked start under an open gate");
    assert!(ok(m.fifo()).0 >= 2, "the threshold still reached while the interlock was active");
}

/// Polls INTERLOCK (each read goes out on MISO, compared with the model's) until ACTIVE
/// reads `active`, a short wait between reads; returns the clocks from trace index `from`
/// to the end of that read.
fn poll_interlock(m: &mut M, active: bool, from: usize, limit: usize) -> usize {
    loop {
        let (now, _) = ok(m.interlock());
        let at = trace(m).len() - from;
        if now == active {
            return at;
        }
        assert!(at < limit, "ACTIVE not {active} {at} clocks after the pin");
        ok(m.bus().wait(50));
    }
}

/// The interlock filter counts exactly FILTER samples (0 and 1 alike: one) at an even
/// PRESCALE, both ways: INTERLOCK is read right after reset (the map's reset values,
/// ACTIVE 0), then for FILTER 1, 3, 5, 4 and 0 at PRESCALE 1000 (a sample every 1001
/// clocks) the pin is raised and dropped and INTERLOCK polled every few hundred clocks
/// (an SPI read frame and 50 clocks), so a level taken one sample early or late is a
/// different read; FILTER and PRESCALE read back as written. Per docs/spec/input_filter.md
/// the level follows 2 clocks plus max(FILTER, 1) samples after the pin. (The older
/// interlock test, FILTER 3 at PRESCALE 6 read hundreds of clocks after the pin, missed
/// filters one or several samples off, mutants 32-56 of the 5c605a1 draw.)
#[test]
fn interlock_filter_counts_its_samples() {
    const PRESCALE: u16 = 1000;
    const SAMPLE: usize = PRESCALE as usize + 1;
    let mut m = machine("interlock_filter_counts_its_samples");
    let word = ok(m.bus().read_one(interlock::ADDR));
    assert_eq!(
        (interlock::ENABLE.get(word), interlock::ACTIVE_HIGH.get(word), interlock::FILTER.get(word)),
        (0, 1, 50),
        "{word:#x}"
    );
    assert_eq!((interlock::PRESCALE.get(word), interlock::ACTIVE.get(word)), (4999, 0), "{word:#x}");
    for filter in [1u8, 3, 5, 4, 0] {
        let setup = InterlockSetup { enable: true, active_high: true, filter_samples: filter, prescale: PRESCALE };
        ok(m.configure_interlock(&setup));
        let word = ok(m.bus().read_one(interlock::ADDR));
        assert_eq!(interlock::FILTER.get(word), u32::from(filter), "FILTER read back: {word:#x}");
        assert_eq!(interlock::PRESCALE.get(word), u32::from(PRESCALE), "PRESCALE read back: {word:#x}");
        // The reset PRESCALE's 5 000 clocks run out before the new one counts (the first
        // round); then two samples at rest.
        ok(m.bus().wait(if filter == 1 { 5_000 } else { 2 * SAMPLE as u64 }));
        let samples = usize::from(filter.max(1));
        for active in [true, false] {
            let from = trace(&mut m).len();
            m.bus().link_mut().set_interlock_pin(active);
            let seen = poll_interlock(&mut m, active, from, (samples + 3) * SAMPLE);
            assert!(
                seen > (samples - 1) * SAMPLE && seen <= samples * SAMPLE + 1000,
                "FILTER {filter}: ACTIVE {active} read {seen} clocks after the pin"
            );
            // Held a while at the new level: one more read, unchanged.
            ok(m.bus().wait(SAMPLE as u64));
            assert_eq!(ok(m.interlock()).0, active, "FILTER {filter}");
        }
    }
}

/// The safe levels both ways: OUTPUTS_SAFE written with a pattern and its complement
/// (every field 0 in one and 1 in the other), read back each time; a halt (the E-stop)
/// with the outputs at the complement drives the safe pattern to the pins on the clock
/// after the axes' enables drop, and OUTPUTS reads it. (`spindle_pwm_ramp_and_estop`'s
/// one pattern, GPIO 0b0001, left mutants 84 and 88 of the 5c605a1 draw alive: a safe
/// GPIO1 stuck at 0 and a safe GPIO0 stuck at 1.)
#[test]
fn safe_outputs_take_both_patterns() {
    let mut m = machine("safe_outputs_take_both_patterns");
    ok(m.bus().write(estop_filter::ADDR, 4));
    let safe = Outputs { mist: true, flood: true, light: false, gpio: 0b1110 };
    let other = Outputs { mist: false, flood: false, light: true, gpio: 0b0001 };
    for pattern in [other, safe, other, safe] {
        ok(m.set_safe_outputs(&pattern));
        let word = ok(m.bus().read_one(outputs_safe::ADDR));
        assert_eq!(word, safe_word(&pattern), "OUTPUTS_SAFE read back");
    }
    ok(m.set_outputs(&other));
    ok(m.bus().wait(20));
    assert_eq!(ok(m.outputs()), other);
    let before = trace(&mut m).len();
    m.bus().link_mut().set_estop_pin(true);
    ok(m.bus().wait(200));
    let t = trace(&mut m)[before..].to_vec();
    let drop = enables_drop(&t);
    assert!(!bit(t[drop - 1], OUT_COOLANT_MIST) && bit(t[drop - 1], OUT_LIGHT), "the outputs until the halt");
    assert_eq!(t[drop - 1] >> OUT_GPIO0 & 0xF, 0b0001);
    for (i, &out) in t.iter().enumerate().skip(drop) {
        assert!(bit(out, OUT_COOLANT_MIST) && bit(out, OUT_COOLANT_FLOOD) && !bit(out, OUT_LIGHT), "({i})");
        assert_eq!(out >> OUT_GPIO0 & 0xF, 0b1110, "safe levels ({i})");
    }
    assert_eq!(ok(m.outputs()), safe, "OUTPUTS holds the safe levels");
    assert_eq!(ok(m.bus().read_one(outputs_safe::ADDR)), safe_word(&safe));
}

/// OUTPUTS_SAFE's word for `o` (the map's layout).
fn safe_word(o: &Outputs) -> u32 {
    let word = outputs_safe::MIST.set(0, u32::from(o.mist));
    let word = outputs_safe::FLOOD.set(word, u32::from(o.flood));
    let word = outputs_safe::LIGHT.set(word, u32::from(o.light));
    outputs_safe::GPIO.set(word, u32::from(o.gpio))
}

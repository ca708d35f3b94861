//! The gantry block in a closed loop, RTL and model in lockstep on every pin and every
//! gantry output each clock: axis 0 (master) and axis 1 (slave) drive two sides of one
//! gantry; each side's encoder counts 4 per step of its motor; the slave's motor loses
//! steps (a stall) and synchronised mode puts them back (deleting master steps rather than
//! reversing the slave), forward mode does not, and a racking past the limit raises the
//! alarm.

use finestep_cosim::gantry_pair::{GantryPair, MASTER, SLAVE};
use finestep_cosim::{Harness, ModelPath};
use finestep_model::{CoreInputs, GantryInputs, Increment};

const PERIOD: u32 = 200;
const COUNTS_PER_STEP: i64 = GantryPair::COUNTS_PER_STEP;

struct Outcome {
    master: i64,
    slave: i64,
    /// Step pulses the slave's pin A made (every direction).
    slave_pulses: u64,
    corrections: i16,
    error: i32,
    alarm: bool,
}

/// Streams `periods` records moving the master at 0.75 step a period; the slave's motor
/// loses `lost` steps at period `at`. The encoders are read once per period (the counts
/// the chip sees lag the motors by up to a period, as a slow feedback path would).
fn run(path: ModelPath, sync: bool, lost: i64, at: usize, periods: usize, limit: u16) -> Outcome {
    let mut pair = GantryPair::new("gantry", path, sync, PERIOD, 0.75, (COUNTS_PER_STEP / 2) as u16, limit);
    let mut slave_loss = 0i64;
    for period in 0..periods {
        if period == at {
            slave_loss = lost;
        }
        pair.feed_period(slave_loss).unwrap_or_else(|m| panic!("{m}"));
    }
    // Hold still long enough for the last corrections (one per tick) to land.
    pair.record.inc[MASTER] = Increment::ZERO;
    for _ in 0..(4 * lost.unsigned_abs() as usize + 20) {
        pair.feed_period(slave_loss).unwrap_or_else(|m| panic!("{m}"));
    }
    let out = pair.outputs();
    Outcome {
        master: i64::from(out.positions[MASTER] as i32),
        slave: i64::from(out.positions[SLAVE] as i32),
        slave_pulses: pair.harness.pulses()[SLAVE],
        corrections: out.gantry_corrections as i16,
        error: out.gantry_error as i32,
        alarm: out.gantry_flags & 2 != 0,
    }
}

#[test]
fn synchronised_mode_puts_back_the_steps_the_slave_lost() {
    for path in [ModelPath::PerClock, ModelPath::Fast] {
        for lost in [5, -7] {
            let out = run(path, true, lost, 100, 300, 1000);
            assert_eq!(out.master, (300.0 * 0.75f64).round() as i64, "{path:?}");
            // The slave commanded `lost` more steps than the master: its motor is square.
            assert_eq!(out.slave, out.master + lost, "{path:?} lost {lost}");
            assert_eq!(i64::from(out.corrections), lost, "{path:?}");
            // The master only moves forward and every correction lands while it moves:
            // those against it delete master steps, those with it add steps, so the
            // slave never reverses (each of its pulses is a step forward).
            assert_eq!(out.slave_pulses as i64, out.slave, "{path:?} lost {lost}: the slave reversed");
            assert!(out.error.unsigned_abs() <= 2, "{path:?}: error {}", out.error);
            assert!(!out.alarm);
        }
    }
}

#[test]
fn forward_mode_copies_the_master_and_leaves_the_error() {
    for path in [ModelPath::PerClock, ModelPath::Fast] {
        let out = run(path, false, 5, 100, 200, 1000);
        assert_eq!(out.slave, out.master, "{path:?}: a plain copy");
        assert_eq!(out.corrections, 0);
        assert_eq!(i64::from(out.error), 5 * COUNTS_PER_STEP, "{path:?}");
        assert!(!out.alarm);
    }
}

#[test]
fn racking_past_the_limit_raises_the_alarm() {
    for path in [ModelPath::PerClock, ModelPath::Fast] {
        // 60 steps lost: 240 counts against a limit of 100, in forward mode (nothing
        // corrects it) and in synchronised mode (the corrections come too slowly to stop
        // the alarm, which is sticky).
        for sync in [false, true] {
            let out = run(path, sync, 60, 50, 120, 100);
            assert!(out.alarm, "{path:?} sync {sync}");
        }
        let out = run(path, false, 20, 50, 120, 100);
        assert!(!out.alarm, "{path:?}: 80 counts is within the limit");
    }
}

/// The arithmetic's edge values through RTL and model in lockstep (random stimulus
/// rarely reaches them): counts wrapping through 0, an error of -65 535 against a
/// deadband of 65 534 (a correction; the compare is 33 bits wide) and the widest limit
/// (65 535: no alarm), -65 536 (alarm), and -2^31 (|error| = 2^31 as an unsigned value).
#[test]
fn edge_values_of_the_error_agree() {
    for path in [ModelPath::PerClock, ModelPath::Fast] {
        let mut harness = Harness::with_gantry("gantry_edges", path);
        let mut inputs = CoreInputs { run: true, period_clocks: PERIOD, ..Default::default() };
        inputs.axes[MASTER].enable = true;
        inputs.axes[SLAVE].enable = true;
        inputs.gantry = GantryInputs {
            enable: true,
            sync: true,
            master: MASTER as u8,
            slave: SLAVE as u8,
            tick: 7,
            deadband: u16::MAX - 1,
            limit: u16::MAX,
            enc_master: 5,
            enc_slave: 5,
            ..Default::default()
        };
        let step = |harness: &mut Harness, inputs: &CoreInputs, cycles: u64| {
            harness.idle(inputs, cycles).unwrap_or_else(|m| panic!("{m}"));
            harness.outputs()
        };
        let out = step(&mut harness, &inputs, 4);
        assert_eq!((out.gantry_flags & 1, out.gantry_error), (1, 0), "{path:?}: engaged square");
        // Through 0: the slave's channel wraps below 0 as the master's stays: error 6.
        inputs.gantry.enc_slave = u32::MAX;
        let out = step(&mut harness, &inputs, 4);
        assert_eq!(out.gantry_error, 6, "{path:?}");
        // -65 535 against a deadband of 65 534: -1 decided at the next tick and applied
        // at rest (an inserted step), counted; |error| is not past the limit 65 535.
        inputs.gantry.enc_slave = inputs.gantry.enc_master.wrapping_add(65_535);
        let out = step(&mut harness, &inputs, 20);
        assert_eq!(out.gantry_error as i32, -65_535, "{path:?}");
        // Open loop (the counts stay): a -1 at each tick since.
        assert!((out.gantry_corrections as i16) < 0, "{path:?}: corrected");
        assert_eq!(out.gantry_flags & 2, 0, "{path:?}: within the limit");
        inputs.gantry.enc_slave = inputs.gantry.enc_master.wrapping_add(65_536);
        let out = step(&mut harness, &inputs, 6);
        assert_eq!(out.gantry_flags & 2, 2, "{path:?}: 65 536 is past the limit 65 535");
        // -2^31: |error| = 2^31 as an unsigned value.
        inputs.gantry.clear_counters = true;
        inputs.gantry.enc_slave = inputs.gantry.enc_master.wrapping_add(1 << 31);
        let out = step(&mut harness, &inputs, 12);
        assert_eq!(out.gantry_error, 1 << 31, "{path:?}");
        assert_eq!((out.gantry_flags & 2, out.gantry_corrections), (2, 0), "{path:?}: alarm, nothing corrected");
    }
}

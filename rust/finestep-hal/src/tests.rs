//! The driver against the reference model at its pins (in-process, behind the host
//! driver's SPI master): the same SPI frames a board or `finestep sim-chip` gets.

use super::*;
use finestep_host::pins::layout::{IN_ENC_A0, IN_ENC_B0, IN_ENC_Z0, IN_PROBE};
use finestep_host::regs::probe_status;
use finestep_host::{PinHost, PinTarget, PinTiming};
use finestep_model::top::{Top, TopInputs, TopParams};
use std::cell::Cell;
use std::rc::Rc;

/// Clocks between two edges of the test's encoder.
const EDGE_CLOCKS: u64 = 2_000;

/// Encoder channel 0 turned by a test while clocks pass: one quadrature edge every
/// [`EDGE_CLOCKS`] while edges are pending (the sign is the direction), the index pulse
/// (Z high) in the middle of the stretch at `index_at`, either way through it.
#[derive(Clone, Copy, Debug, Default)]
struct Turning {
    position: i64,
    pending: i64,
    clock: u64,
    index_at: i64,
    /// The probe pin high (PROBE_CONTROL.ACTIVE_HIGH's reset polarity: touching).
    probe: bool,
}

/// The reference model at its pins (finestep-cosim's `ModelPins`, without the crate's
/// Verilated half), encoder channel 0 turned as the shared [`Turning`] says.
struct ModelPins(Top, Rc<Cell<Turning>>);

impl PinTarget for ModelPins {
    fn drive(&mut self, inputs: u64, cycles: u64) -> Result<(), BusError> {
        let mut turning = self.1.get();
        let inputs = inputs & !(1 << IN_PROBE) | u64::from(turning.probe) << IN_PROBE;
        let idle = TopInputs::unpack(inputs);
        for _ in 0..cycles {
            if turning.pending == 0 {
                self.0.step(&idle);
                continue;
            }
            turning.clock += 1;
            if turning.clock == EDGE_CLOCKS {
                let step = turning.pending.signum();
                turning.clock = 0;
                turning.position += step;
                turning.pending -= step;
            }
            let (a, b) =
                [(false, false), (true, false), (true, true), (false, true)][turning.position.rem_euclid(4) as usize];
            let z =
                turning.position == turning.index_at && (EDGE_CLOCKS / 4..3 * EDGE_CLOCKS / 4).contains(&turning.clock);
            let pins = inputs & !(1 << IN_ENC_A0 | 1 << IN_ENC_B0 | 1 << IN_ENC_Z0)
                | u64::from(a) << IN_ENC_A0
                | u64::from(b) << IN_ENC_B0
                | u64::from(z) << IN_ENC_Z0;
            self.0.step(&TopInputs::unpack(pins));
        }
        self.1.set(turning);
        Ok(())
    }

    fn outputs(&self) -> u64 {
        self.0.outputs().pack()
    }
}

/// A servo period of 0.2 ms (10 000 clocks at 50 MHz) keeps the tests quick.
const PERIOD_NS: i64 = 200_000;

fn driver() -> Driver {
    driver_turning(Rc::default())
}

/// A driver on a model chip whose encoder channel 0 `turning` turns.
fn driver_turning(turning: Rc<Cell<Turning>>) -> Driver {
    driver_on(TopParams::default(), turning)
}

/// A driver on a model chip built with `params`.
fn driver_on(params: TopParams, turning: Rc<Cell<Turning>>) -> Driver {
    let mut host = PinHost::new(ModelPins(Top::new(params), turning), PinTiming::default());
    host.reset(4).unwrap();
    host.idle(8).unwrap();
    Driver::connect(Box::new(host), true, "model").unwrap()
}

fn stepgen(position_cmd: f64, scale: f64) -> StepgenCommand {
    StepgenCommand { position_cmd, position_scale: scale, enable: true, ..StepgenCommand::default() }
}

/// One servo period as LinuxCNC's thread runs it: read, then write.
fn cycle(driver: &mut Driver, enable: bool, cmds: &[StepgenCommand]) -> Vec<i32> {
    driver.read(PERIOD_NS).unwrap();
    let counts = (0..driver.n_axes()).map(|a| driver.stepgen_feedback(a).unwrap().counts).collect();
    driver.write(PERIOD_NS, enable, 0, cmds).unwrap();
    counts
}

#[test]
fn every_period_lands_the_commanded_position_in_steps() {
    let mut driver = driver();
    let scales = [800.0, -533.3, 1000.0 / 3.0, 100.0];
    let n = driver.n_axes();
    let mut history: Vec<Vec<f64>> = Vec::new();
    let mut checked = 0;
    for k in 0..400 {
        let t = k as f64 * PERIOD_NS as f64 * 1e-9;
        // Smooth moves with reversals: up to 40 mm/s at 800 steps/mm (6.4 steps a period).
        let positions: Vec<f64> =
            (0..n).map(|a| (1.0 + a as f64) * 0.5 * (1.0 - (t * 40.0 / (1.0 + a as f64)).cos())).collect();
        let cmds: Vec<StepgenCommand> = (0..n).map(|a| stepgen(positions[a], scales[a])).collect();
        let counts = cycle(&mut driver, true, &cmds);
        if k > FEEDBACK_LAG_PERIODS {
            let sent = &history[k - FEEDBACK_LAG_PERIODS];
            for a in 0..n {
                let expected = quantised_steps(command_fixed(sent[a], scales[a]).unwrap());
                assert_eq!(i64::from(counts[a]), expected, "period {k} axis {a}");
                checked += 1;
            }
        }
        history.push(positions);
    }
    assert_eq!(checked, (400 - FEEDBACK_LAG_PERIODS - 1) * n);
    for a in 0..n {
        assert_eq!(driver.stepgen_feedback(a).unwrap().limited, 0, "axis {a}");
    }
    let status = driver.machine.status().unwrap();
    assert_eq!(status::RATE_ERROR.get(status) | status::UNDERRUN.get(status) | status::HALT.get(status), 0);
}

/// A chip with one position snapshot (ONE_SNAPSHOT, the MAX II's): a probe event holds
/// POSITION at the event until the probe is armed again. The driver sees it in VERSION,
/// holds the step feedback on a read that finds the probe's snapshot (it does not take it
/// as the position), releases the snapshot, and lands every other period on the command
/// exactly, as on the default chip; the step feedback never jumps back. A servo period
/// of 1 ms: the probe's frames (the arm, the release, PROBE_STATUS read every period on
/// such a chip) do not fit the 0.2 ms of the other tests at the pins' SPI rate.
#[test]
fn a_probe_snapshot_is_not_taken_as_the_position() {
    const PERIOD_NS: i64 = 1_000_000;
    let cycle = |driver: &mut Driver, cmds: &[StepgenCommand]| -> Vec<i32> {
        driver.read(PERIOD_NS).unwrap();
        let counts = (0..driver.n_axes()).map(|a| driver.stepgen_feedback(a).unwrap().counts).collect();
        driver.write(PERIOD_NS, true, 0, cmds).unwrap();
        counts
    };
    let params = TopParams { one_snapshot: true, inc_write_only: true, ..TopParams::default() };
    let turning: Rc<Cell<Turning>> = Rc::default();
    let mut driver = driver_on(params, turning.clone());
    let caps = driver.machine.caps();
    assert!(caps.one_snapshot && caps.inc_write_only, "{caps:?}");
    let scale = 800.0;
    let n = driver.n_axes();
    let mut history: Vec<f64> = Vec::new();
    let mut last = 0;
    let mut held = 0;
    for k in 0..300 {
        if k == 100 {
            driver.machine.arm_probe(true, 1).unwrap();
        }
        // The probe touches for 20 periods, then lets go.
        let mut pins = turning.get();
        pins.probe = (150..170).contains(&k);
        turning.set(pins);
        let t = k as f64 * PERIOD_NS as f64 * 1e-9;
        let position = 0.5 * (1.0 - (t * 8.0).cos());
        let cmds: Vec<StepgenCommand> = (0..n).map(|_| stepgen(position, scale)).collect();
        let before = driver.held_reads();
        let counts = cycle(&mut driver, &cmds);
        if driver.held_reads() > before {
            assert!((150..172).contains(&k), "period {k}: held without a probe event");
            assert_eq!(counts[0], last, "period {k}: the feedback held");
            held += 1;
        } else if k > FEEDBACK_LAG_PERIODS {
            let expected = quantised_steps(command_fixed(history[k - FEEDBACK_LAG_PERIODS], scale).unwrap());
            assert_eq!(i64::from(counts[0]), expected, "period {k}");
        }
        last = counts[0];
        history.push(position);
    }
    assert!(held >= 1, "the probe's snapshot was seen");
    let probe = driver.machine.bus().read_one(probe_status::ADDR).unwrap();
    assert_eq!(probe_status::SEEN.get(probe), 0, "released: {probe:#x}");
}

#[test]
fn a_jump_is_clamped_to_the_rated_rate_and_caught_up() {
    let mut driver = driver();
    let n = driver.n_axes();
    let mut cmds = vec![stepgen(0.0, 1.0); n];
    cycle(&mut driver, true, &cmds);
    // 2 us + 2 us pulses: 50 steps in a 0.2 ms period at most; ask for 400 at once.
    cmds[1].position_cmd = 400.0;
    // maxvel 20 steps a period.
    cmds[2] = StepgenCommand { maxvel: 100_000.0, ..stepgen(300.0, 1.0) };
    let mut last = Vec::new();
    for _ in 0..(300 / 20 + FEEDBACK_LAG_PERIODS) {
        last = cycle(&mut driver, true, &cmds);
    }
    assert_eq!(last[1], 400);
    assert_eq!(last[2], 300);
    assert_eq!(driver.stepgen_feedback(1).unwrap().limited, 7, "50 steps x 8 periods");
    assert_eq!(driver.stepgen_feedback(2).unwrap().limited, 14, "20 steps x 15 periods");
    let status = driver.machine.status().unwrap();
    assert_eq!(status::RATE_ERROR.get(status), 0);
}

#[test]
fn e_stop_halts_the_chip_and_no_step_follows() {
    let mut driver = driver();
    let n = driver.n_axes();
    let mut cmds = vec![stepgen(0.0, 1000.0); n];
    for k in 0..20 {
        cmds[0].position_cmd = k as f64 * 0.01;
        cycle(&mut driver, true, &cmds);
    }
    assert!(driver.status().running && driver.status().estop_ok);
    assert!(driver.link_mut().drive_estop(true).unwrap());
    driver.read(PERIOD_NS).unwrap();
    let at_stop = driver.stepgen_feedback(0).unwrap().counts;
    let err = driver.write(PERIOD_NS, true, 0, &cmds).unwrap_err().to_string();
    assert!(err.contains("E-stop"), "{err}");
    assert!(!driver.status().running && !driver.status().estop_ok);
    for k in 20..30 {
        cmds[0].position_cmd = k as f64 * 0.01;
        driver.read(PERIOD_NS).unwrap();
        driver.write(PERIOD_NS, true, 0, &cmds).unwrap();
    }
    driver.read(PERIOD_NS).unwrap();
    // Halted: at most the steps already requested before the filter saw the E-stop.
    let held = driver.stepgen_feedback(0).unwrap().counts;
    assert!((held - at_stop).abs() <= 10, "{at_stop} -> {held}");
    // Released, LinuxCNC resets the E-stop and enables again: resynchronised, no jump.
    assert!(driver.link_mut().drive_estop(false).unwrap());
    driver.link_mut().wait(1000).unwrap();
    cmds[0].position_cmd = f64::from(held) / 1000.0;
    cycle(&mut driver, false, &cmds);
    assert!(driver.status().estop_ok);
    for _ in 0..4 {
        cycle(&mut driver, true, &cmds);
    }
    assert!(driver.status().running);
    assert_eq!(cycle(&mut driver, true, &cmds)[0], held);
}

#[test]
fn bad_commands_and_settings_are_errors_not_panics() {
    let mut driver = driver();
    let n = driver.n_axes();
    let mut cmds = vec![stepgen(0.0, 1.0); n];
    cmds[0].step_type = 7;
    let err = driver.write(PERIOD_NS, true, 0, &cmds).unwrap_err().to_string();
    assert_eq!(err, "stepgen.00: step_type 7 is not 0 (step/dir), 1 (up/down) or 2 (quadrature)");
    cmds[0].step_type = 0;
    let err = driver.write(1, true, 0, &cmds).unwrap_err().to_string();
    assert_eq!(err, "servo period 1 ns is 0 clocks of the 50000000 Hz core: outside 1..=1048575");
    // 200 020 ns is 10 001 clocks: the step engine (4 slots) would run 10 000.
    let err = driver.write(PERIOD_NS + 20, true, 0, &cmds).unwrap_err().to_string();
    assert!(
        err.starts_with("servo period 200020 ns is 10001 clocks of the 50000000 Hz core, not a multiple of its 4"),
        "{err}"
    );
    driver.write(PERIOD_NS, true, 0, &cmds).unwrap();
    cmds[3].position_cmd = f64::NAN;
    let err = driver.write(PERIOD_NS, true, 0, &cmds).unwrap_err().to_string();
    assert_eq!(err, "stepgen.03: position-cmd NaN * position-scale 1 is not a position in steps");
    assert!(driver.set_stepgen(n, cmds[0]).is_err());
    for bad in ["usb", "sim:", "spidev:", "spidev:/dev/spidev0.0@fast"] {
        assert!(bad.parse::<Transport>().is_err(), "{bad}");
    }
    assert_eq!(
        "spidev:/dev/spidev0.1".parse::<Transport>().unwrap(),
        Transport::Spidev { path: "/dev/spidev0.1".into(), sck_hz: DEFAULT_SCK_HZ }
    );
}

#[test]
fn quantisation_rounds_half_up_like_the_dda() {
    assert_eq!(quantised_steps(command_fixed(0.5, 1.0).unwrap()), 1);
    assert_eq!(quantised_steps(command_fixed(-0.5, 1.0).unwrap()), 0);
    assert_eq!(quantised_steps(command_fixed(-0.50002, 1.0).unwrap()), -1);
    assert_eq!(quantised_steps(command_fixed(2.4999, 1.0).unwrap()), 2);
    assert_eq!(command_fixed(f64::INFINITY, 1.0), None);
}

#[test]
fn a_step_crossed_at_the_end_of_a_period_is_requested_in_time_for_the_latch() {
    // Every period lands 0.00002 steps past a rounding point: the DDA would request the
    // period's last step 0.02 clocks before the boundary, after the latch's lag. The
    // driver lands past the point within the same step, early enough to be counted.
    let mut driver = driver();
    let n = driver.n_axes();
    let mut history: Vec<Vec<f64>> = Vec::new();
    let mut checked = 0;
    for k in 0..60 {
        // Axis 0 up at 10 steps a period, axis 1 down at 7 (the chip starts pointing up:
        // a reversal, rated 8.3 steps a period with the default timing), axis 2
        // reverses every 10 periods.
        let zigzag = if (k / 10) % 2 == 0 { (k % 10) as f64 } else { (10 - k % 10) as f64 };
        let positions = [k as f64 * 10.0 + 0.50002, -(k as f64) * 7.0 - 0.50002, zigzag * 7.0 + 0.50002, 0.0];
        let cmds: Vec<StepgenCommand> = (0..n).map(|a| stepgen(positions[a], 1.0)).collect();
        let counts = cycle(&mut driver, true, &cmds);
        if k > FEEDBACK_LAG_PERIODS {
            let sent = &history[k - FEEDBACK_LAG_PERIODS];
            for a in 0..n {
                let expected = quantised_steps(command_fixed(sent[a], 1.0).unwrap());
                assert_eq!(i64::from(counts[a]), expected, "period {k} axis {a}");
                checked += 1;
            }
        }
        history.push(positions[..n].to_vec());
    }
    assert!(checked > 200);
    for a in 0..n {
        assert_eq!(driver.stepgen_feedback(a).unwrap().limited, 0, "axis {a}");
    }
    let status = driver.machine.status().unwrap();
    assert_eq!(status::RATE_ERROR.get(status) | status::UNDERRUN.get(status) | status::HALT.get(status), 0);
}

#[test]
fn the_settled_increment_keeps_the_step_and_moves_only_a_late_crossing() {
    let (p, latency, slots, max) = (10_000u32, 100u64, 4u32, 1i64 << 30);
    let deadline = i64::from(p) - 100 - 4 - 2;
    // 10.00002 steps from 0.5: crosses 10.5 at 0.02 clocks before the end.
    let d = 655_361;
    let s = settled_increment(32768, d, p, latency, slots, max);
    assert!(s > d && quantised_steps(32768 + s) == quantised_steps(32768 + d), "{s}");
    // The last point (10.5 steps, 10 steps from the start) is now crossed by the deadline.
    assert!(10 * 65536 * i64::from(p) <= deadline * s, "{s}");
    // Downwards likewise, strictly below the point.
    let s = settled_increment(-32768, -d, p, latency, slots, max);
    assert!(s < -d && quantised_steps(-32768 + s) == quantised_steps(-32768 - d), "{s}");
    // Early crossings, no crossing, and a move whose steps are closer than the latency
    // (no landing in the same step helps) are left alone.
    assert_eq!(settled_increment(0, 655_360 + 30_000, p, latency, slots, max), 655_360 + 30_000);
    assert_eq!(settled_increment(0, 20_000, p, latency, slots, max), 20_000);
    assert_eq!(settled_increment(32768, 200 * 65536 + 1, p, latency, slots, max), 200 * 65536 + 1);
    // Nor past the largest increment allowed.
    assert_eq!(settled_increment(32768, d, p, latency, slots, d), d);
}

/// `index-enable` as LinuxCNC's homing and the C component use it: the pin is passed in
/// before each read and set from the read after it. A request withdrawn before the index
/// changes nothing; one left standing zeroes `count` at the index pulse, either way
/// through it, and clears the pin in the read that finds it.
#[test]
fn index_enable_zeroes_the_count_at_the_index_and_clears_itself() {
    let turning = Rc::new(Cell::new(Turning { index_at: 250, ..Turning::default() }));
    let mut driver = driver_turning(turning.clone());
    let mut pin = false;
    fn period(driver: &mut Driver, pin: &mut bool) -> EncoderFeedback {
        driver.link_mut().wait(10_000).unwrap();
        driver.set_encoder(0, EncoderCommand { index_enable: *pin, ..EncoderCommand::default() }).unwrap();
        driver.read(PERIOD_NS).unwrap();
        let fb = driver.encoder_feedback(0).unwrap();
        *pin = fb.index_enable;
        fb
    }
    // One period (the request armed there), then the turn, then two periods for the
    // filter and the latch.
    let turn = |driver: &mut Driver, pin: &mut bool, edges: i64| {
        period(driver, pin);
        turning.set(Turning { pending: edges, ..turning.get() });
        while turning.get().pending != 0 {
            period(driver, pin);
        }
        period(driver, pin);
        period(driver, pin);
    };
    period(&mut driver, &mut pin);
    turn(&mut driver, &mut pin, 100);
    let count = period(&mut driver, &mut pin).count;
    assert_eq!(count.abs(), 100, "{count}");
    let sign = count.signum();
    // Requested, then withdrawn before the index: the count runs on through it.
    pin = true;
    assert!(period(&mut driver, &mut pin).index_enable);
    pin = false;
    turn(&mut driver, &mut pin, 200);
    let fb = period(&mut driver, &mut pin);
    assert_eq!((fb.count, fb.index_enable), (300 * sign, false));
    // Left standing, turning down through the index: 0 there, the pin cleared.
    pin = true;
    assert!(period(&mut driver, &mut pin).index_enable);
    turn(&mut driver, &mut pin, -100);
    let fb = period(&mut driver, &mut pin);
    assert_eq!((fb.count, fb.index_enable), (-50 * sign, false));
    assert_eq!(fb.position, f64::from(-50 * sign));
    // And up through it again, asked once more.
    pin = true;
    turn(&mut driver, &mut pin, 80);
    let fb = period(&mut driver, &mut pin);
    assert_eq!((fb.count, fb.index_enable), (30 * sign, false));
}

/// `maxaccel` against exact arithmetic: from rest to a jump's target and back, the
/// increments change by at most the acceleration each period, never pass the command,
/// and land on it exactly (in I16F16, the driver's own unit).
#[test]
fn accel_limited_approaches_without_passing_and_lands_exactly() {
    for &(target, accel, max) in &[
        (400i64 << 16, 3.0 * 65536.0, 50i64 << 16),
        (-(123_457i64), 1000.0, 1 << 30),
        (7 << 16, 0.375 * 65536.0, 1 << 30),
        (1, 1.0, 1 << 30),
        (10_000_000, 24_576.0, 20 << 16),
    ] {
        let (mut sent, mut last, mut periods) = (0i64, 0i64, 0);
        while sent != target || last != 0 {
            let d = accel_limited(target - sent, last, accel, max);
            assert!(((d - last) as f64).abs() <= accel, "{target}: {last} -> {d} over {accel}");
            assert!(d.abs() <= max);
            sent += d;
            assert!(sent.signum() * target.signum() >= 0 && sent.abs() <= target.abs(), "{target}: passed at {sent}");
            last = d;
            periods += 1;
            assert!(periods < 100_000, "{target}: never landed ({sent})");
        }
    }
    // Moving the wrong way at speed: the acceleration wins, then the command is reached.
    let (mut sent, mut last) = (0i64, -(20i64 << 16));
    for _ in 0..1000 {
        let d = accel_limited((5 << 16) - sent, last, 65536.0, 1 << 30);
        assert!((d - last).abs() <= 65536);
        sent += d;
        last = d;
    }
    assert_eq!((sent, last), (5 << 16, 0));
}

/// `maxaccel` on the chip: a jump of the command is followed within the acceleration
/// (the step count's second difference, with one step of quantisation either side), the
/// rest carried, and landed exactly; 0 leaves the rated-rate clamp alone.
#[test]
fn a_jump_is_approached_at_maxaccel_and_landed() {
    let mut driver = driver();
    let n = driver.n_axes();
    let mut cmds = vec![stepgen(0.0, 1.0); n];
    cycle(&mut driver, true, &cmds);
    // 2 steps a period squared at 0.2 ms periods: 2 / (2e-4)^2 steps/s^2.
    cmds[0] = StepgenCommand { maxaccel: 2.0 / (2e-4 * 2e-4), ..stepgen(300.0, 1.0) };
    let mut counts = Vec::new();
    for _ in 0..60 {
        counts.push(cycle(&mut driver, true, &cmds)[0]);
    }
    assert_eq!(*counts.last().unwrap(), 300);
    assert!(counts.windows(2).all(|w| w[1] >= w[0] && w[1] <= 300), "{counts:?}");
    for w in counts.windows(3) {
        let second = (w[2] - 2 * w[1] + w[0]).abs();
        assert!(second <= 2 + 2, "{counts:?}");
    }
    // About sqrt(4 * 300 / 2) = 24.5 periods to land: the limit did act.
    let moving = counts.iter().filter(|&&c| c > 0 && c < 300).count();
    assert!(moving >= 20, "{moving}: {counts:?}");
    assert!(driver.stepgen_feedback(0).unwrap().limited > 0);
}

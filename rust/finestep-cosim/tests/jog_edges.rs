//! The jog's edge cases at the chip's pins, RTL and model in lockstep on every clock (the
//! jog's state reaches the pins as steps and as the JOG_STATUS / JOG_REMAINING /
//! JOG_VELOCITY reads on MISO, polled often): drop mode with large windows and scales and
//! negative travel; a bouncing wheel sampled every clock, so that the detent count moves
//! on consecutive clocks; JOG_SCALE, JOG_CONTROL.MULTIPLIER and JOG_WINDOW written in the
//! middle of a burst of detents; halt and disengage mid-move; and the velocity
//! computation's extremes: |target - cmd| >= 2^40 (JOG_SCALE near 2^31 at x100, several
//! detents followed), JOG_ACCEL near 2^31 with a small JOG_VMAX, a large JOG_ACCEL braking
//! below JOG_VMAX, and JOG_VMAX = 0.

use finestep_host::regs::{jog_control, jog_scale, jog_vmax, jog_window};
use finestep_host::{Bus, JogMultiplier, JogSetup, JogState};
use finestep_model::Increment;
use finestep_plant::{Bounce, DriveConfig, HandWheelConfig, Plant, PlantConfig};

mod plant_chip;

use plant_chip::{connect, turn, Chip, PERIOD};

/// A wheel whose contacts bounce `extra` pairs of toggles within `within` cycles of each
/// edge (none: a clean wheel).
fn wheel_plant(bounce: Option<Bounce>) -> Plant {
    Plant::new(
        PlantConfig {
            drives: vec![DriveConfig::default(); 2],
            channels: vec![],
            probe: None,
            hand_wheel: Some(HandWheelConfig { rest_phase: 2, bounce }),
        },
        7,
    )
    .unwrap()
}

/// Bounce toggles on distinct cycles within 5 of an edge: with the wheel sampled every
/// clock and no filter, the count crosses a detent boundary back and forth on
/// consecutive clocks.
const FAST_BOUNCE: Option<Bounce> = Some(Bounce { extra: 2, within: 5 });

fn wheel_done(machine: &Chip) -> bool {
    let plant_loop = machine.bus_ref().link().target();
    plant_loop.plant().hand_wheel().unwrap().script_end() <= plant_loop.cycle()
}

fn setup(multiplier: JogMultiplier, follow: bool, scale: i32, window: u16) -> JogSetup {
    JogSetup {
        axis: 0,
        multiplier,
        follow,
        scale: Increment::from_bits(scale),
        vmax: Increment::from_num(4),
        accel: Increment::from_num(0.25),
        window,
    }
}

/// Reads the jog's status every `step` clocks for `clocks` clocks (each read goes out on
/// MISO, compared with the model's); returns the last.
fn poll(machine: &mut Chip, clocks: u64, step: u64) -> JogState {
    let mut waited = 0;
    let mut jog = machine.jog().unwrap();
    while waited < clocks {
        machine.bus().wait(step).unwrap();
        waited += step;
        jog = machine.jog().unwrap();
    }
    jog
}

/// The hand wheel sampled every clock, with no filter (a detent can follow a detent on
/// the next clock).
fn wheel_every_clock(machine: &mut Chip) {
    machine.configure_hand_wheel(0, 0).unwrap();
}

/// JOG_CONTROL with a raw multiplier field (3 acts as x100).
fn control_word(enable: bool, follow: bool, multiplier: u32) -> u32 {
    let word = jog_control::ENABLE.set(0, enable.into());
    let word = jog_control::AXIS.set(word, 0);
    let word = jog_control::MULTIPLIER.set(word, multiplier);
    jog_control::FOLLOW.set(word, follow.into())
}

/// Drop mode with windows from 0 to the largest, travels from a fraction of a step to
/// 100 * 2^31 / 65536 steps, both signs, on a bouncing wheel read every clock: detents
/// arrive on consecutive clocks, some within the window (also exactly on its edge), some
/// dropped. Then a halt mid-move.
#[test]
fn drop_mode_large_windows_and_scales() {
    let cases: [(JogMultiplier, i32, u16, i64); 10] = [
        (JogMultiplier::X100, 3 << 16 | 12345, 1000, 12), // ~319 steps a detent, 3 fit
        (JogMultiplier::X100, -(3 << 16 | 12345), 1000, -12), // negative travel
        (JogMultiplier::X1, i32::MAX, 65535, 5),          // 32768 steps: two fit
        (JogMultiplier::X1, i32::MIN, 65535, -5),         // -32768 steps near the largest window
        (JogMultiplier::X10, 100 << 16, 3000, 7),         // exactly on the window's edge
        (JogMultiplier::X100, i32::MIN, 65535, 3),        // the largest travel: all dropped
        (JogMultiplier::X10, -(7 << 16 | 1), 0, 6),       // no window
        (JogMultiplier::X1, 1, 0, -9),                    // 1/65536 step with no window: all dropped
        // -1.5 steps a detent (bit 15 of the travel set), window 3: from rest the 2nd quick
        // detent lands exactly on -W, followed (mutant 66 of the 5c605a1 draw, the bound's
        // half step dropped, survived the cases above).
        (JogMultiplier::X1, -(3 << 15), 3, 6),
        // -43691 LSB a detent (bit 1 clear), window 2: the 3rd quick detent from rest
        // leaves the bound 1 LSB short, dropped (mutant 70, the bound off by 2 LSB).
        (JogMultiplier::X1, -43691, 2, 3),
    ];
    for (i, (multiplier, scale, window, detents)) in cases.into_iter().enumerate() {
        let mut machine = connect(&format!("drop_mode_large_windows_and_scales_{i}"), wheel_plant(FAST_BOUNCE));
        wheel_every_clock(&mut machine);
        let setup = setup(multiplier, false, scale, window);
        machine.configure_jog(&setup).unwrap();
        machine.enable_jog(&setup, true).unwrap();
        turn(&mut machine, detents, 6);
        turn(&mut machine, -detents / 2, 7);
        turn(&mut machine, detents, 6);
        let jog = poll(&mut machine, 3 * u64::from(PERIOD), 97);
        assert!(wheel_done(&machine));
        assert!(jog.engaged, "case {i}: {jog:?}");
        assert!(jog.dropped > 0, "case {i}: {jog:?}");
        if (5..8).contains(&i) {
            // Every detent dropped: the target never moved.
            assert!(jog.remaining == 0 && jog.velocity == Increment::ZERO, "case {i}: {jog:?}");
        }
        // A halt (E-stop) mid-move: disengaged, at rest, at position 0 of the jog.
        machine.bus().link_mut().set_estop_pin(true);
        let jog = poll(&mut machine, 400, 50);
        assert!(!jog.engaged && jog.remaining == 0 && jog.velocity == Increment::ZERO, "case {i}: {jog:?}");
    }
}

/// JOG_SCALE, JOG_CONTROL.MULTIPLIER (0 to 3) and .FOLLOW, and JOG_WINDOW written while
/// the wheel turns fast and bounces: each write reaches the detents two cycles after it is
/// served, on whichever clock that is. Then a disengage (ENABLE = 0) mid-move.
#[test]
fn configuration_written_in_a_burst_of_detents() {
    for (i, follow) in [false, true].into_iter().enumerate() {
        let mut machine =
            connect(&format!("configuration_written_in_a_burst_of_detents_{i}"), wheel_plant(FAST_BOUNCE));
        wheel_every_clock(&mut machine);
        let setup = setup(JogMultiplier::X1, follow, 5 << 16 | 777, 200);
        machine.configure_jog(&setup).unwrap();
        machine.enable_jog(&setup, true).unwrap();
        for _ in 0..4 {
            turn(&mut machine, 40, 6);
            turn(&mut machine, -60, 7);
            turn(&mut machine, 40, 6);
        }
        let scales = [-(9 << 16) - 5, 1 << 20, i32::MAX, -(1 << 16), 3, i32::MIN / 100, 12 << 16 | 1];
        let windows = [0u32, 65535, 17, 300, 1, 2000, 40];
        for round in 0..21 {
            let k = round % 7;
            machine.bus().write(jog_scale::ADDR, scales[k] as u32).unwrap();
            machine.bus().wait(3 + round as u64).unwrap();
            // Follow mode switched on and off too: drop-mode checks of a distance that
            // followed detents made large.
            let follow_now = follow != (round % 3 == 1);
            machine.bus().write(jog_control::ADDR, control_word(true, follow_now, (round % 4) as u32)).unwrap();
            machine.bus().write(jog_window::ADDR, jog_window::STEPS.set(0, windows[k])).unwrap();
            let jog = machine.jog().unwrap();
            assert!(jog.engaged, "round {round}: {jog:?}");
        }
        poll(&mut machine, u64::from(PERIOD), 101);
        // Back to a small travel, then stop mid-move: the jog brakes at A and disengages.
        machine.bus().write(jog_scale::ADDR, (1 << 16) as u32).unwrap();
        machine.bus().write(jog_window::ADDR, jog_window::STEPS.set(0, 50)).unwrap();
        machine.enable_jog(&setup, false).unwrap();
        let mut jog = machine.jog().unwrap();
        for _ in 0..400 {
            if !jog.engaged {
                break;
            }
            jog = poll(&mut machine, u64::from(PERIOD), 500);
        }
        assert!(!jog.engaged && jog.velocity == Increment::ZERO, "{jog:?}");
    }
}

/// |target - cmd| >= 2^40: JOG_SCALE 2^31 - 1 at x100 (about 2^37.6 a detent), 16
/// detents followed, then 40 back (both signs beyond 2^40), for some periods; then a halt.
#[test]
fn distance_beyond_two_to_the_forty() {
    let mut machine = connect("distance_beyond_two_to_the_forty", wheel_plant(None));
    machine.configure_hand_wheel(1, 1).unwrap();
    let setup = setup(JogMultiplier::X100, true, i32::MAX, 0);
    machine.configure_jog(&setup).unwrap();
    machine.enable_jog(&setup, true).unwrap();
    turn(&mut machine, 16, 20);
    let jog = poll(&mut machine, 12 * u64::from(PERIOD), 333);
    // remaining = (target - cmd)[47:16]: 16 * 100 * (2^31 - 1) / 65536 less a little travel.
    assert!(jog.remaining > 40_000_000, "{jog:?}");
    assert!(jog.velocity > Increment::ZERO && jog.velocity <= setup.vmax, "{jog:?}");
    turn(&mut machine, -40, 20);
    let jog = poll(&mut machine, 30 * u64::from(PERIOD), 333);
    assert!(jog.remaining < -60_000_000, "{jog:?}");
    assert!(jog.velocity < Increment::ZERO && jog.velocity >= -setup.vmax, "{jog:?}");
    machine.bus().link_mut().set_estop_pin(true);
    let jog = poll(&mut machine, 400, 50);
    assert!(!jog.engaged && jog.remaining == 0, "{jog:?}");
}

/// JOG_ACCEL 2^31 - 1 (in one period from rest to any speed) with a small JOG_VMAX: the
/// speed jumps to VM and lands in one step; both ways, in lockstep.
#[test]
fn huge_acceleration_small_velocity_limit() {
    for (i, vmax) in [3i32, 1 << 16, 5 << 15].into_iter().enumerate() {
        let mut machine = connect(&format!("huge_acceleration_small_velocity_limit_{i}"), wheel_plant(None));
        machine.configure_hand_wheel(1, 1).unwrap();
        let setup = JogSetup {
            vmax: Increment::from_bits(vmax),
            accel: Increment::from_bits(i32::MAX),
            ..setup(JogMultiplier::X1, true, 3 << 16 | 999, 0)
        };
        machine.configure_jog(&setup).unwrap();
        machine.enable_jog(&setup, true).unwrap();
        turn(&mut machine, 2, 20);
        let jog = poll(&mut machine, 10 * u64::from(PERIOD), 257);
        assert!(jog.velocity.abs() <= setup.vmax, "{jog:?}");
        turn(&mut machine, -3, 20);
        poll(&mut machine, 10 * u64::from(PERIOD), 257);
        if vmax >= 1 << 16 {
            // Fast enough to land within the periods waited.
            let jog = poll(&mut machine, 10 * u64::from(PERIOD), 257);
            assert_eq!((jog.remaining, jog.velocity), (0, Increment::ZERO), "{jog:?}");
        }
        machine.enable_jog(&setup, false).unwrap();
        let jog = poll(&mut machine, 4 * u64::from(PERIOD), 257);
        assert!(!jog.engaged, "{jog:?}");
    }
}

/// JOG_ACCEL 8.5 steps a period each period (bit 19 of the field set) under a JOG_VMAX of
/// 24: the speed rises to the limit and brakes on the root sqrt(2 A |e|) - A, below the
/// limit, from 60 steps away; the axis lands exactly, both ways, in lockstep. (The other
/// edge tests brake under a limit only with accelerations below bit 19, or hold a limit
/// below the acceleration, where the root never decides the speed.)
#[test]
fn large_acceleration_brakes_below_the_limit() {
    let mut machine = connect("large_acceleration_brakes_below_the_limit", wheel_plant(None));
    machine.configure_hand_wheel(1, 1).unwrap();
    let setup = JogSetup {
        vmax: Increment::from_num(24),
        accel: Increment::from_bits(0x8_8000),
        ..setup(JogMultiplier::X10, true, 1 << 16, 0)
    };
    machine.configure_jog(&setup).unwrap();
    machine.enable_jog(&setup, true).unwrap();
    turn(&mut machine, 6, 20);
    let jog = poll(&mut machine, 12 * u64::from(PERIOD), 257);
    assert_eq!((jog.remaining, jog.velocity), (0, Increment::ZERO), "{jog:?}");
    assert_eq!(machine.positions().unwrap().steps[0], 60);
    turn(&mut machine, -4, 20);
    let jog = poll(&mut machine, 12 * u64::from(PERIOD), 257);
    assert_eq!((jog.remaining, jog.velocity), (0, Increment::ZERO), "{jog:?}");
    assert_eq!(machine.positions().unwrap().steps[0], 20);
}

/// JOG_VMAX = 0 (written directly: the driver refuses it): the detents move the target,
/// the axis never moves, and a disengage takes effect at the next boundary.
#[test]
fn zero_velocity_limit() {
    let mut machine = connect("zero_velocity_limit", wheel_plant(None));
    machine.configure_hand_wheel(1, 1).unwrap();
    let setup = setup(JogMultiplier::X10, true, 1 << 16, 0);
    machine.configure_jog(&setup).unwrap();
    machine.bus().write(jog_vmax::ADDR, 0).unwrap();
    machine.enable_jog(&setup, true).unwrap();
    turn(&mut machine, 5, 20);
    let jog = poll(&mut machine, 8 * u64::from(PERIOD), 211);
    assert_eq!((jog.remaining, jog.velocity), (50, Increment::ZERO), "{jog:?}");
    machine.enable_jog(&setup, false).unwrap();
    let jog = poll(&mut machine, 2 * u64::from(PERIOD) + 200, 211);
    assert!(!jog.engaged && jog.remaining == 50, "{jog:?}");
    assert_eq!(machine.positions().unwrap().steps[0], 0);
}

/// JOG_ACCEL of 1 to 3 LSBs (1/65536 step a period each period): the braking bound
/// sqrt(2 A e) is taken of small radicands near the end of every move, where a perfect
/// square is never far (the root's last digits decide the speed there); the axis lands
/// exactly, both ways, in lockstep.
#[test]
fn tiny_acceleration_lands_exactly() {
    for (i, accel) in [1i32, 2, 3].into_iter().enumerate() {
        let mut machine = connect(&format!("tiny_acceleration_lands_exactly_{i}"), wheel_plant(None));
        machine.configure_hand_wheel(1, 1).unwrap();
        let setup = JogSetup { accel: Increment::from_bits(accel), ..setup(JogMultiplier::X1, true, 1 << 16, 0) };
        machine.configure_jog(&setup).unwrap();
        machine.enable_jog(&setup, true).unwrap();
        turn(&mut machine, 2, 20);
        let jog = poll(&mut machine, 900 * u64::from(PERIOD), 1999);
        assert_eq!((jog.remaining, jog.velocity), (0, Increment::ZERO), "accel {accel}: {jog:?}");
        assert_eq!(machine.positions().unwrap().steps[0], 2, "accel {accel}");
        turn(&mut machine, -1, 20);
        let jog = poll(&mut machine, 650 * u64::from(PERIOD), 1999);
        assert_eq!((jog.remaining, jog.velocity), (0, Increment::ZERO), "accel {accel}: {jog:?}");
        assert_eq!(machine.positions().unwrap().steps[0], 1, "accel {accel}");
    }
}

//! The LinuxCNC HAL component's driver (`finestep-hal`) on `finestep sim-chip`'s socket,
//! the transport the component uses in simulation, with the loopback machine on the
//! chip's pins (encoder channel 0 counts axis 0's steps, one count per step): the
//! stepgen's moves come back on the encoder, scaled, with a velocity, and reset zeroes it.

mod common;

use common::serve;
use finestep_hal::{Driver, EncoderCommand, StepgenCommand};

/// 1 ms servo periods (50 000 clocks). At 0.2 ms the frames of one servo period (about
/// 110 bytes at SCK = clk/8: 7 000 clocks, more with the encoder setup) leave too little
/// of the period's 10 000 clocks, and the FIFO runs dry: the driver reports the underrun.
const PERIOD_NS: i64 = 1_000_000;

/// One servo period as LinuxCNC runs it: read, then write.
fn cycle(driver: &mut Driver, cmds: &[StepgenCommand]) {
    driver.read(PERIOD_NS).unwrap();
    driver.write(PERIOD_NS, true, 0, cmds).unwrap();
}

#[test]
fn the_encoder_counts_the_stepgen_moves_scaled_and_resets() {
    let server = serve("hal-driver", &["--plant", "--target", "model"]);
    let mut driver = Driver::open(&format!("sim:{}", server.socket.display())).unwrap();
    assert!(driver.paced());
    let stepgen = StepgenCommand { position_scale: 100.0, enable: true, ..StepgenCommand::default() };
    let mut cmds = vec![stepgen; driver.n_axes()];
    driver.set_encoder(0, EncoderCommand { scale: 100.0, ..EncoderCommand::default() }).unwrap();
    // Axis 0 from 0 to 2 units (200 steps) at 10 steps a period, then held.
    let mut moving = None;
    for k in 0..30 {
        cmds[0].position_cmd = f64::from(k.min(20)) * 0.1;
        cycle(&mut driver, &cmds);
        if k == 12 {
            moving = driver.encoder_feedback(0);
        }
    }
    driver.read(PERIOD_NS).unwrap();
    let steps = driver.stepgen_feedback(0).unwrap();
    let encoder = driver.encoder_feedback(0).unwrap();
    assert_eq!((steps.counts, steps.position_fb, steps.limited), (200, 2.0, 0));
    assert_eq!((encoder.count, encoder.position, encoder.velocity), (200, 2.0, 0.0));
    // 10 counts a period of 1 ms at 100 counts a unit: 100 units/s.
    let velocity = moving.unwrap().velocity;
    assert!((velocity - 100.0).abs() <= 10.0, "{velocity}");

    // reset holds the count at 0; released, it counts from there.
    driver.set_encoder(0, EncoderCommand { scale: 100.0, reset: true, ..EncoderCommand::default() }).unwrap();
    cycle(&mut driver, &cmds);
    assert_eq!(driver.encoder_feedback(0).unwrap().count, 0);
    driver.set_encoder(0, EncoderCommand { scale: 100.0, ..EncoderCommand::default() }).unwrap();
    for k in 0..15 {
        cmds[0].position_cmd = 2.0 - f64::from(k.min(10)) * 0.1;
        cycle(&mut driver, &cmds);
    }
    driver.read(PERIOD_NS).unwrap();
    assert_eq!(driver.encoder_feedback(0).unwrap().count, -100);
    assert_eq!(driver.stepgen_feedback(0).unwrap().counts, 100);
}

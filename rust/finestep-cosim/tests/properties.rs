//! proptest: random streams, periods, timing settings and output modes, RTL against the
//! model on every pin every clock, on both model paths, for the core with a DDA and a
//! shaper per axis (and the gantry block), for the core with the shared step engine and
//! for the core with the digit-serial step engine. Failures shrink to a minimal
//! scenario, print the seed (rerun with FINESTEP_SEED) and leave a waveform window in
//! target/cosim-failures/.

mod common;

use finestep_cosim::ModelPath;
use proptest::prelude::*;

#[test]
fn random_streams_are_bit_exact_per_clock_model() {
    let mut runner = finestep_testkit::runner("random_streams_are_bit_exact_per_clock_model", 5000);
    runner
        .run(&common::scenario(60), |scenario| {
            if let Err(mismatch) = common::play("random_streams_per_clock", ModelPath::PerClock, &scenario) {
                prop_assert!(false, "{mismatch}");
            }
            Ok(())
        })
        .unwrap();
}

#[test]
fn random_streams_are_bit_exact_fast_model() {
    let mut runner = finestep_testkit::runner("random_streams_are_bit_exact_fast_model", 5000);
    runner
        .run(&common::scenario(60), |scenario| {
            if let Err(mismatch) = common::play("random_streams_fast", ModelPath::Fast, &scenario) {
                prop_assert!(false, "{mismatch}");
            }
            Ok(())
        })
        .unwrap();
}

#[test]
fn random_streams_are_bit_exact_step_engine_per_clock_model() {
    let mut runner = finestep_testkit::runner("random_streams_are_bit_exact_step_engine_per_clock_model", 5000);
    runner
        .run(&common::scenario(60), |scenario| {
            if let Err(mismatch) =
                common::play_engine("random_streams_engine_per_clock", ModelPath::PerClock, &scenario)
            {
                prop_assert!(false, "{mismatch}");
            }
            Ok(())
        })
        .unwrap();
}

#[test]
fn random_streams_are_bit_exact_step_engine_fast_model() {
    let mut runner = finestep_testkit::runner("random_streams_are_bit_exact_step_engine_fast_model", 5000);
    runner
        .run(&common::scenario(60), |scenario| {
            if let Err(mismatch) = common::play_engine("random_streams_engine_fast", ModelPath::Fast, &scenario) {
                prop_assert!(false, "{mismatch}");
            }
            Ok(())
        })
        .unwrap();
}

#[test]
fn random_streams_are_bit_exact_step_serial_per_clock_model() {
    let mut runner = finestep_testkit::runner("random_streams_are_bit_exact_step_serial_per_clock_model", 5000);
    runner
        .run(&common::scenario(60), |scenario| {
            if let Err(mismatch) =
                common::play_serial("random_streams_serial_per_clock", ModelPath::PerClock, &scenario)
            {
                prop_assert!(false, "{mismatch}");
            }
            Ok(())
        })
        .unwrap();
}

#[test]
fn random_streams_are_bit_exact_step_serial_fast_model() {
    let mut runner = finestep_testkit::runner("random_streams_are_bit_exact_step_serial_fast_model", 5000);
    runner
        .run(&common::scenario(60), |scenario| {
            if let Err(mismatch) = common::play_serial("random_streams_serial_fast", ModelPath::Fast, &scenario) {
                prop_assert!(false, "{mismatch}");
            }
            Ok(())
        })
        .unwrap();
}

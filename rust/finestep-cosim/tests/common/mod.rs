//! Random stimulus for co-simulation tests: sequences of actions on the core's inputs.

#![allow(dead_code)]

use finestep_cosim::{Harness, Mismatch, ModelPath};
use finestep_model::{AxisConfig, CoreInputs, DriveTiming, GantryInputs, Increment, PeriodRecord, MAX_AXES};
use proptest::prelude::*;

/// Axes of the Verilated core.
pub const AXES: usize = 4;

/// One thing done to the core's inputs.
#[derive(Clone, Debug)]
pub enum Action {
    /// Offer this record until it is consumed (with clear_errors held if the flag is set).
    Feed(PeriodRecord, bool),
    /// Keep the inputs, no record offered, for this many cycles.
    Idle(u64),
    /// Drop `run` for this many cycles (abort), offering a record meanwhile if given,
    /// then raise it again.
    Stop(u64, Option<PeriodRecord>),
    /// Pulse clear_errors for one cycle.
    Clear,
    /// New configuration for one axis (takes effect at once).
    Configure(usize, AxisConfig),
    /// New `period_clocks` input (sampled before the next run starts); may exceed
    /// P_WIDTH bits, which the core masks off.
    Period(u32),
    /// Hold `halt` for this many cycles, with `run` dropped as the top does or (flag
    /// false) left as it is, then release it.
    Halt(u64, bool),
    /// New gantry configuration (the encoder counts and clear_counters are kept).
    Gantry(GantryInputs),
    /// The two gantry channels' counts move by these amounts (wrapping), as a machine's
    /// encoders would between two looks.
    Counts(i32, i32),
    /// Pulse the gantry's clear_counters for one cycle.
    ClearCounters,
}

/// A test case: the period and per-axis configuration, then the actions.
#[derive(Clone, Debug)]
pub struct Scenario {
    pub period_clocks: u32,
    pub axes: [AxisConfig; AXES],
    pub gantry: GantryInputs,
    pub actions: Vec<Action>,
}

pub fn axis_config() -> impl Strategy<Value = AxisConfig> {
    let timing = prop_oneof![4 => 0u32..6, 1 => 0u32..40, 1 => Just(4095u32), 1 => any::<u32>()];
    (timing.clone(), timing.clone(), timing.clone(), timing, 0u8..4, 0u8..8, any::<bool>()).prop_map(
        |(step_len, step_space, dir_setup, dir_hold, mode, invert, enable)| AxisConfig {
            timing: DriveTiming::new(step_len, step_space, dir_setup, dir_hold),
            mode,
            invert,
            enable,
        },
    )
}

/// Raw Q16.16 increments around what a period of `p` clocks can take.
fn increment(p: u32) -> impl Strategy<Value = Increment> {
    let max = i64::from(p) * 65536 - 1;
    let raw = prop_oneof![
        3 => Just(0i64),
        3 => -131072i64..131072,                    // fractions of a step per period
        3 => (-max / 8)..=(max / 8),                // comfortably within one step per clock
        1 => (-max)..=max,                          // up to one step per clock (over-rate)
        1 => prop_oneof![Just(max), Just(-max), Just(max + 1), Just(-max - 1)], // the limit, and just past it
        1 => any::<i32>().prop_map(i64::from),      // anything, mostly unacceptable records
    ];
    raw.prop_map(|r| Increment::from_bits(r.clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32))
}

fn record(p: u32) -> impl Strategy<Value = PeriodRecord> {
    (proptest::collection::vec(increment(p), AXES), any::<u8>()).prop_map(|(incs, flags)| {
        let mut record = PeriodRecord { flags, ..Default::default() };
        record.inc[..AXES].copy_from_slice(&incs);
        record
    })
}

fn period() -> impl Strategy<Value = u32> {
    prop_oneof![1 => 0u32..4, 4 => 4u32..64, 2 => 64u32..600, 1 => (0u32..64).prop_map(|p| (1 << 20) | p)]
}

/// Gantry settings: mostly a valid pair, short ticks so corrections come often, small
/// deadbands and limits so that both the corrections and the alarm happen.
pub fn gantry() -> impl Strategy<Value = GantryInputs> {
    let axis = prop_oneof![8 => 0u8..AXES as u8, 1 => 0u8..8];
    let tick = prop_oneof![3 => 0u32..40, 1 => 0u32..2000, 1 => any::<u32>()];
    let small = prop_oneof![3 => 0u16..8, 1 => any::<u16>()];
    (any::<bool>(), any::<bool>(), axis.clone(), axis, tick, small.clone(), small).prop_map(
        |(enable, sync, master, slave, tick, deadband, limit)| GantryInputs {
            enable,
            sync,
            master,
            slave,
            tick,
            deadband,
            limit,
            ..Default::default()
        },
    )
}

fn counts() -> impl Strategy<Value = Action> {
    let delta = prop_oneof![4 => -8i32..8, 1 => -5000i32..5000, 1 => any::<i32>()];
    (delta.clone(), delta).prop_map(|(m, s)| Action::Counts(m, s))
}

fn action(p: u32) -> impl Strategy<Value = Action> {
    prop_oneof![
        12 => (record(p), proptest::bool::weighted(0.1)).prop_map(|(r, clear)| Action::Feed(r, clear)),
        2 => prop_oneof![1u64..20, 1u64..5000].prop_map(Action::Idle),
        1 => (1u64..4, proptest::option::of(record(p))).prop_map(|(cycles, offer)| Action::Stop(cycles, offer)),
        1 => Just(Action::Clear),
        1 => (0..AXES, axis_config()).prop_map(|(axis, config)| Action::Configure(axis, config)),
        1 => period().prop_map(Action::Period),
        1 => (prop_oneof![1u64..8, 1u64..300], any::<bool>()).prop_map(|(cycles, stop)| Action::Halt(cycles, stop)),
        1 => gantry().prop_map(Action::Gantry),
        3 => counts(),
        1 => Just(Action::ClearCounters),
    ]
}

/// Random scenarios with short periods (so each case is a few thousand cycles).
pub fn scenario(max_actions: usize) -> impl Strategy<Value = Scenario> {
    period().prop_flat_map(move |p| {
        (
            proptest::collection::vec(axis_config(), AXES),
            prop_oneof![2 => Just(GantryInputs::default()), 1 => gantry()],
            proptest::collection::vec(action(effective(p)), 1..max_actions),
        )
            .prop_map(move |(axes, gantry, actions)| Scenario {
                period_clocks: p,
                axes: axes.try_into().unwrap(),
                gantry,
                actions,
            })
    })
}

/// Play a scenario on RTL and model side by side, both with the gantry block (and a DDA
/// and a shaper per axis); the first difference is an error.
pub fn play(name: &str, path: ModelPath, scenario: &Scenario) -> Result<Harness, Box<Mismatch>> {
    play_on(Harness::with_gantry(name, path), scenario)
}

/// The same on the core with the shared step engine (no gantry block: its inputs are
/// ignored by both sides).
pub fn play_engine(name: &str, path: ModelPath, scenario: &Scenario) -> Result<Harness, Box<Mismatch>> {
    play_on(Harness::new(name, path), scenario)
}

/// The same on the core with the digit-serial step engine (the CPLD's).
pub fn play_serial(name: &str, path: ModelPath, scenario: &Scenario) -> Result<Harness, Box<Mismatch>> {
    play_on(Harness::serial(name, path), scenario)
}

fn play_on(mut harness: Harness, scenario: &Scenario) -> Result<Harness, Box<Mismatch>> {
    let mut inputs =
        CoreInputs { run: true, period_clocks: scenario.period_clocks, gantry: scenario.gantry, ..Default::default() };
    inputs.axes[..AXES].copy_from_slice(&scenario.axes);
    for action in &scenario.actions {
        match action {
            Action::Feed(record, clear) => {
                inputs.clear_errors = *clear;
                harness.feed(&mut inputs, [*record])?;
                inputs.clear_errors = false;
            }
            Action::Idle(cycles) => harness.idle(&inputs, *cycles)?,
            Action::Stop(cycles, offer) => {
                let stopped =
                    CoreInputs { run: false, rec_valid: offer.is_some(), record: offer.unwrap_or_default(), ..inputs };
                // A record offered while stopping is consumed at most once, and discarded.
                let end = harness.run_chunk(&stopped, *cycles)?;
                let rest = CoreInputs { rec_valid: false, ..stopped };
                harness.idle(&rest, cycles - end.cycles)?;
            }
            Action::Period(p) => inputs.period_clocks = *p,
            Action::Clear => {
                let clearing = CoreInputs { clear_errors: true, ..inputs };
                harness.idle(&clearing, 1)?;
            }
            Action::Configure(axis, config) => inputs.axes[*axis] = *config,
            Action::Halt(cycles, stop) => {
                let halted = CoreInputs { halt: true, run: inputs.run && !stop, rec_valid: false, ..inputs };
                harness.idle(&halted, *cycles)?;
            }
            Action::Gantry(config) => {
                inputs.gantry = GantryInputs {
                    enc_master: inputs.gantry.enc_master,
                    enc_slave: inputs.gantry.enc_slave,
                    ..*config
                };
            }
            Action::Counts(master, slave) => {
                inputs.gantry.enc_master = inputs.gantry.enc_master.wrapping_add(*master as u32);
                inputs.gantry.enc_slave = inputs.gantry.enc_slave.wrapping_add(*slave as u32);
            }
            Action::ClearCounters => {
                let clearing = CoreInputs { gantry: GantryInputs { clear_counters: true, ..inputs.gantry }, ..inputs };
                harness.idle(&clearing, 1)?;
            }
        }
    }
    // Drain: a few idle periods so every pending step reaches the pins.
    let drain = 3 * u64::from(effective(inputs.period_clocks).max(effective(scenario.period_clocks))) + 4 * 4096;
    harness.idle(&inputs, drain)?;
    Ok(harness)
}

/// The period the core runs with for a `period_clocks` input.
pub fn effective(period_clocks: u32) -> u32 {
    finestep_rtl_sys::params().effective_period(period_clocks)
}

/// Unused axes stay zero in the record; every axis config is within MAX_AXES.
pub const _CHECK: () = assert!(AXES <= MAX_AXES);

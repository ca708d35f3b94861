//! `run_chunk_fast` against the per-clock `run_chunk` (the definition, itself checked
//! against a literal loop of `step` and `outputs`): for random parameters, settings and
//! chunk sequences, identical events, chunk ends and states, with the gantry pair
//! engaging, disengaging and being refused mid-run and its channel counts changing
//! between chunks; and for cores built with the step engine (`step_shared`, no gantry
//! block), whose visits the fast path skips as exactly, and with the digit-serial engine
//! (`step_digit`), which it runs clock by clock.

use finestep_model::{
    AxisConfig, ChunkEnd, Core, CoreInputs, CoreParams, DriveTiming, Event, GantryInputs, Increment, PeriodRecord,
    MAX_AXES,
};
use proptest::prelude::*;

/// One chunk: the inputs held for it and its length.
#[derive(Clone, Debug)]
struct Chunk {
    run: bool,
    /// The core's `halt` (safety monitor), independent of `run` at this level.
    halt: bool,
    /// A new `period_clocks`, else the previous one.
    period: Option<u32>,
    clear_errors: bool,
    /// A new setting for one axis, else the previous ones.
    axis: Option<(usize, AxisConfig)>,
    rec_valid: bool,
    /// Per axis: the kind of increment and a random word (see `increment`).
    incs: [(u8, u32); MAX_AXES],
    flags: u8,
    max_cycles: u64,
    gantry: GantryChunk,
}

/// The gantry inputs of one chunk.
#[derive(Clone, Debug)]
struct GantryChunk {
    /// New settings (`enc_*` and `clear_counters` ignored), else the previous ones.
    settings: Option<GantryInputs>,
    /// How the channel counts move before the chunk (see `counts`).
    counts: Option<(u8, i32, i32)>,
    clear_counters: bool,
}

#[derive(Clone, Debug)]
struct Case {
    params: CoreParams,
    period: u32,
    axes: [AxisConfig; MAX_AXES],
    chunks: Vec<Chunk>,
}

fn timing_value() -> impl Strategy<Value = u32> {
    prop_oneof![
        2 => Just(0u32),
        2 => Just(1u32),
        4 => 0..8u32,
        2 => 0..70u32,
        1 => Just(u32::MAX),
        1 => any::<u32>(),
    ]
}

fn axis_config() -> impl Strategy<Value = AxisConfig> {
    (
        (timing_value(), timing_value(), timing_value(), timing_value()),
        prop_oneof![0..4u8, any::<u8>()],
        prop_oneof![Just(0u8), 0..8u8, any::<u8>()],
        prop::bool::weighted(0.8),
    )
        .prop_map(|((step_len, step_space, dir_setup, dir_hold), mode, invert, enable)| AxisConfig {
            timing: DriveTiming::new(step_len, step_space, dir_setup, dir_hold),
            mode,
            invert,
            enable,
        })
}

fn period_value() -> impl Strategy<Value = u32> {
    prop_oneof![
        1 => Just(0u32),
        3 => 1..5u32,
        4 => 5..200u32,
        2 => 200..5000u32,
        1 => (1u32 << 19)..(1 << 20),
        1 => any::<u32>(),
    ]
}

fn max_cycles() -> impl Strategy<Value = u64> {
    prop_oneof![
        1 => Just(0u64),
        3 => 1..4u64,
        4 => 1..200u64,
        3 => 1..5000u64,
        1 => 1..200_000u64,
    ]
}

fn gantry_settings() -> impl Strategy<Value = GantryInputs> {
    (
        prop::bool::weighted(0.7),
        prop::bool::weighted(0.7),
        prop_oneof![4 => (0..4u8, 0..4u8), 1 => (any::<u8>(), any::<u8>())],
        prop_oneof![
            2 => Just(0u32),
            2 => Just(1u32),
            3 => 2..20u32,
            3 => 20..3000u32,
            1 => any::<u32>(),
        ],
        prop_oneof![3 => 0..4u16, 1 => any::<u16>()],
        prop_oneof![3 => 0..40u16, 1 => any::<u16>()],
    )
        .prop_map(|(enable, sync, (master, slave), tick, deadband, limit)| GantryInputs {
            enable,
            sync,
            master,
            slave,
            tick,
            deadband,
            limit,
            ..GantryInputs::default()
        })
}

fn gantry_chunk() -> impl Strategy<Value = GantryChunk> {
    (
        prop::option::weighted(0.15, gantry_settings()),
        prop::option::weighted(0.5, (0..3u8, -6..6i32, any::<i32>())),
        prop::bool::weighted(0.05),
    )
        .prop_map(|(settings, counts, clear_counters)| GantryChunk { settings, counts, clear_counters })
}

/// The channel counts for a chunk: a small random move of each, both following their
/// axis's position (`2 * position`, the slave's less a disturbance `dx`), or anything.
fn counts(core: &Core, g: &mut GantryInputs, (kind, dx, x): (u8, i32, i32)) {
    let pos = |axis: u8| core.outputs().positions[usize::from(axis & 7)];
    match kind {
        0 => {
            g.enc_master = g.enc_master.wrapping_add_signed(dx);
            g.enc_slave = g.enc_slave.wrapping_add_signed(x % 7);
        }
        1 => {
            g.enc_master = pos(g.master).wrapping_mul(2);
            g.enc_slave = pos(g.slave).wrapping_mul(2).wrapping_add_signed(-dx);
        }
        _ => {
            g.enc_master = x as u32;
            g.enc_slave = dx as u32;
        }
    }
}

fn chunk() -> impl Strategy<Value = Chunk> {
    (
        (prop::bool::weighted(0.85), prop::bool::weighted(0.12)),
        prop::option::weighted(0.1, period_value()),
        prop::bool::weighted(0.08),
        prop::option::weighted(0.1, (0..MAX_AXES, axis_config())),
        prop::bool::weighted(0.75),
        prop::array::uniform8((0..8u8, any::<u32>())),
        any::<u8>(),
        (max_cycles(), gantry_chunk()),
    )
        .prop_map(|((run, halt), period, clear_errors, axis, rec_valid, incs, flags, (max_cycles, gantry))| {
            Chunk { run, halt, period, clear_errors, axis, rec_valid, incs, flags, max_cycles, gantry }
        })
}

fn case() -> impl Strategy<Value = Case> {
    let params = (
        1..=MAX_AXES,
        prop_oneof![Just(20u32), 1..=24u32, Just(32u32)],
        prop_oneof![Just(12u32), Just(4u32), 1..=16u32, Just(32u32)],
        prop::bool::weighted(0.8),
        prop::bool::weighted(0.4),
        prop_oneof![3 => Just(0u32), 1 => Just(1u32), 1 => Just(2u32), 1 => Just(4u32), 1 => Just(8u32)],
        prop::bool::weighted(0.3),
    )
        .prop_map(|(n_axes, p_width, timing_width, has_gantry, step_shared, step_digit, has_pbp)| {
            let params = CoreParams {
                n_axes,
                p_width,
                timing_width,
                has_gantry,
                step_shared: false,
                step_digit: 0,
                has_pbp: false,
            };
            let built = if step_shared && step_digit != 0 {
                // The digit-serial engine (its constraints: log2 R < TIMING_W <= 16,
                // log2 R < P_WIDTH <= log2 R + 15).
                let serial = CoreParams { step_shared, step_digit, ..params };
                let lr = serial.step_round_bits();
                let p_width = p_width.clamp(lr + 1, lr + 15);
                let timing_width = timing_width.clamp(lr + 1, 16);
                CoreParams { p_width, timing_width, ..serial }
            } else if step_shared {
                // The engine needs a period register holding S = 2^SL; it builds no
                // gantry whatever has_gantry says (the gantry inputs still change).
                let p_width = p_width.max(params.step_slot_bits() + 1);
                CoreParams { step_shared, p_width, ..params }
            } else {
                params
            };
            // The pbp block where it can be built (4 axes or more, not the digit-serial
            // engine): the records' random flags make about half of them pbp records.
            let has_pbp = has_pbp && built.n_axes >= 4 && !(built.step_shared && built.step_digit != 0);
            CoreParams { has_pbp, ..built }
        });
    (params, period_value(), prop::array::uniform8(axis_config()), prop::collection::vec(chunk(), 1..40))
        .prop_map(|(params, period, axes, chunks)| Case { params, period, axes, chunks })
}

/// A raw increment of the given kind for a period of `p` clocks: zero, under a step,
/// up to the forward maximum of fast timing, just under one step per clock
/// (over-rate), at or over one step per clock (unacceptable), or anything.
fn increment(kind: u8, x: u32, p: u32) -> Increment {
    let m = i64::from(p.max(1)) << 16;
    let sign = if x & 1 == 0 { 1 } else { -1 };
    let x = i64::from(x >> 1);
    let magnitude = match kind {
        0 | 1 => 0,
        2 => x % 65536,
        3 => x % (m / 2 + 1),
        4 => m / 2 + x % 4,
        5 => m - 1 - x % 65536,
        6 => m + x % (1 << 20),
        _ => return Increment::from_bits(x as i32 ^ (sign as i32)),
    };
    Increment::from_bits((sign * magnitude).clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32)
}

/// `run_chunk` written literally from its definition: outputs compared before and
/// after every `step`.
fn literal_chunk(core: &mut Core, inputs: &CoreInputs, max_cycles: u64, events: &mut Vec<Event>) -> ChunkEnd {
    for ran in 1..=max_cycles {
        let before = core.outputs();
        let consumed = before.rec_ready() && inputs.rec_valid;
        core.step(inputs);
        let after = core.outputs();
        if after != before {
            events.push(Event { cycle: core.cycle(), outputs: after });
        }
        if consumed {
            return ChunkEnd { cycles: ran, consumed: true };
        }
    }
    ChunkEnd { cycles: max_cycles, consumed: false }
}

/// Total per-clock cycles allowed per case, to bound the test's run time.
const CYCLE_BUDGET: u64 = 400_000;

#[test]
fn fast_path_is_identical_to_per_clock() {
    let mut runner = finestep_testkit::runner("fast_path_is_identical_to_per_clock", 2000);
    runner
        .run(&case(), |case| {
            let mut slow = Core::new(case.params);
            let mut fast = slow.clone();
            let mut literal = slow.clone();
            let mut ev_literal = vec![];
            let mut inputs = CoreInputs { period_clocks: case.period, axes: case.axes, ..CoreInputs::default() };
            let mut budget = CYCLE_BUDGET;
            let (mut ev_slow, mut ev_fast): (Vec<Event>, Vec<Event>) = (vec![], vec![]);
            for (k, chunk) in case.chunks.iter().enumerate() {
                inputs.run = chunk.run;
                inputs.halt = chunk.halt;
                if let Some(p) = chunk.period {
                    inputs.period_clocks = p;
                }
                inputs.clear_errors = chunk.clear_errors;
                if let Some((i, cfg)) = chunk.axis {
                    inputs.axes[i] = cfg;
                }
                inputs.rec_valid = chunk.rec_valid;
                // Increments sized for the period in force (or about to be sampled).
                let p = slow.timer().p_act().max(case.params.effective_period(inputs.period_clocks));
                for (slot, &(kind, x)) in inputs.record.inc.iter_mut().zip(&chunk.incs) {
                    *slot = increment(kind, x, p);
                }
                inputs.record.flags = chunk.flags;
                if let Some(g) = chunk.gantry.settings {
                    inputs.gantry =
                        GantryInputs { enc_master: inputs.gantry.enc_master, enc_slave: inputs.gantry.enc_slave, ..g };
                }
                if let Some(c) = chunk.gantry.counts {
                    counts(&slow, &mut inputs.gantry, c);
                }
                inputs.gantry.clear_counters = chunk.gantry.clear_counters;
                let max = chunk.max_cycles.min(budget);
                ev_slow.clear();
                ev_fast.clear();
                ev_literal.clear();
                let end_literal = literal_chunk(&mut literal, &inputs, max, &mut ev_literal);
                let end_slow = slow.run_chunk(&inputs, max, &mut ev_slow);
                let end_fast = fast.run_chunk_fast(&inputs, max, &mut ev_fast);
                budget -= end_slow.cycles;
                prop_assert_eq!(end_literal, end_slow, "chunk {} end (run_chunk)", k);
                prop_assert!(ev_literal == ev_slow, "chunk {}: run_chunk events differ from the literal ones", k);
                prop_assert_eq!(end_slow, end_fast, "chunk {} end", k);
                if let Some(i) = (0..ev_slow.len().max(ev_fast.len())).find(|&i| ev_slow.get(i) != ev_fast.get(i)) {
                    return Err(TestCaseError::fail(format!(
                        "chunk {k}: event {i} differs: per-clock {:?}, fast {:?}",
                        ev_slow.get(i),
                        ev_fast.get(i)
                    )));
                }
                prop_assert_eq!(&slow, &fast, "chunk {} end state", k);
            }
            Ok(())
        })
        .unwrap();
}

/// With the step engine the fast path skips as well: a long slow move of 4 axes
/// (S = 4) identical to per-clock, and a billion idle running cycles at once.
#[test]
fn fast_path_skips_with_the_step_engine() {
    let axis = AxisConfig { timing: DriveTiming::new(9, 7, 3, 5), enable: true, ..AxisConfig::default() };
    let params = CoreParams { step_shared: true, has_gantry: false, ..CoreParams::default() };
    let mut inputs = CoreInputs { period_clocks: 100_003, axes: [axis; MAX_AXES], ..CoreInputs::default() };
    let mut slow = Core::new(params);
    let mut fast = slow.clone();
    let (mut ev_slow, mut ev_fast) = (vec![], vec![]);
    inputs.record = PeriodRecord::from_raw(&[37 << 16, -(5 << 16) - 123, 0, 1], 1);
    for (run, valid, max) in [(false, false, 10), (true, false, 3), (true, true, u64::MAX), (true, false, 250_000)] {
        inputs.run = run;
        inputs.rec_valid = valid;
        let a = slow.run_chunk(&inputs, max, &mut ev_slow);
        let b = fast.run_chunk_fast(&inputs, max, &mut ev_fast);
        assert_eq!(a, b);
        assert_eq!(ev_slow, ev_fast);
        assert_eq!(slow, fast);
    }
    assert_eq!(fast.outputs().position(0), 37);
    assert_eq!(fast.outputs().position(1), -5);
    assert_eq!(fast.timer().p_act(), 100_000, "P rounded down to a multiple of S = 4");
    // Idle periods of 2^20 - 4 clocks: a billion cycles in about a thousand boundaries.
    inputs.run = false;
    inputs.period_clocks = (1 << 20) - 1;
    fast.run_chunk_fast(&inputs, 1, &mut ev_fast);
    inputs.run = true;
    ev_fast.clear();
    let end = fast.run_chunk_fast(&inputs, 1_000_000_000, &mut ev_fast);
    assert_eq!(end.cycles, 1_000_000_000);
    assert!(ev_fast.iter().all(|e| e.outputs.positions[..2] == [37, (-5i32) as u32]));
    assert!((1900..=1920).contains(&ev_fast.len()), "rec_ready up and down per period: {}", ev_fast.len());
}

/// Long quiet stretches cost the fast path nothing: a billion idle cycles, and a long
/// slow move, finish at once and agree with each other's outputs.
#[test]
fn fast_path_skips_long_quiet_stretches() {
    let axis = AxisConfig { timing: DriveTiming::new(500, 500, 100, 100), enable: true, ..AxisConfig::default() };
    let mut core = Core::new(CoreParams::default());
    let mut inputs = CoreInputs { period_clocks: 1, axes: [axis; MAX_AXES], ..CoreInputs::default() };
    let mut events = vec![];
    core.run_chunk_fast(&inputs, 1, &mut events);
    inputs.run = true;
    let end = core.run_chunk_fast(&inputs, 1_000_000_000, &mut events);
    assert_eq!(end, ChunkEnd { cycles: 1_000_000_000, consumed: false });
    assert_eq!(events.len(), 2, "enable/dir pins, then rec_ready");
    let end = core.run_chunk_fast(&inputs, u64::MAX - 1, &mut events);
    assert_eq!(end.cycles, u64::MAX - 1, "idle at P = 1 is quiet for ever");
    assert_eq!(events.len(), 2);

    let mut core = Core::new(CoreParams::default());
    inputs.run = false;
    inputs.period_clocks = 1_000_000;
    core.run_chunk_fast(&inputs, 1, &mut events);
    inputs.run = true;
    inputs.rec_valid = true;
    inputs.record = PeriodRecord::from_raw(&[-(100 << 16), 250 << 16, 3, 0], 0);
    for _ in 0..1000 {
        let end = core.run_chunk_fast(&inputs, u64::MAX, &mut events);
        assert!(end.consumed);
    }
    inputs.rec_valid = false;
    core.run_chunk_fast(&inputs, 2_000_000, &mut events);
    let out = core.outputs();
    assert_eq!((out.position(0), out.position(1), out.position(2)), (-100_000, 250_000, 0));
}

/// With the pbp block built the fast path skips while the block is idle and runs its
/// records clock by clock: lines and arcs on both pairs between increment records and
/// idle stretches, with a DDA and a shaper per axis and with the step engine (its
/// requests held for the shaper visits), identical to per-clock chunk by chunk; and a
/// billion idle cycles after them at once.
#[test]
fn fast_path_skips_around_pbp_records() {
    use finestep_interface::pbp::{arc_steps, PbpLanes};
    let axis = AxisConfig { timing: DriveTiming::new(3, 2, 1, 2), enable: true, ..AxisConfig::default() };
    let arc = |pair, (x, y): (i32, i32), end: (i64, i64), cw, tick_div| {
        let steps = arc_steps((x.into(), y.into()), end, cw).unwrap();
        PeriodRecord::pbp(&PbpLanes { arc: true, cw, pair, x, y, steps, tick_div }, 0)
    };
    let line = |pair, x, y, tick_div| {
        PeriodRecord::pbp(&PbpLanes { arc: false, cw: false, pair, x, y, steps: 0, tick_div }, 0)
    };
    let records = [
        line(0, 40, -17, 9),
        PeriodRecord::from_raw(&[3 << 16, -(2 << 16), 1 << 15, 0], 0),
        arc(1, (30, 0), (0, 30), false, 5),
        line(1, -25, 0, 3),
        line(3, 9, 9, 3),
        arc(0, (0, -12), (12, 0), true, 20),
        PeriodRecord::from_raw(&[0; 4], 0),
    ];
    for step_shared in [false, true] {
        let params = CoreParams { step_shared, has_gantry: false, has_pbp: true, ..CoreParams::default() };
        let mut inputs = CoreInputs { period_clocks: 2_000, axes: [axis; MAX_AXES], ..CoreInputs::default() };
        let mut slow = Core::new(params);
        let mut fast = slow.clone();
        let (mut ev_slow, mut ev_fast) = (vec![], vec![]);
        let mut chunks = vec![(false, false, 10, records[0]), (true, false, 5_000, records[0])];
        for record in records {
            chunks.push((true, true, u64::MAX, record));
            chunks.push((true, false, 7_000, record));
        }
        for (k, (run, valid, max, record)) in chunks.into_iter().enumerate() {
            inputs.run = run;
            inputs.rec_valid = valid;
            inputs.record = record;
            ev_slow.clear();
            ev_fast.clear();
            let a = slow.run_chunk(&inputs, max, &mut ev_slow);
            let b = fast.run_chunk_fast(&inputs, max, &mut ev_fast);
            assert_eq!(a, b, "step_shared {step_shared}, chunk {k}");
            assert_eq!(ev_slow, ev_fast, "step_shared {step_shared}, chunk {k}");
            assert_eq!(slow, fast, "step_shared {step_shared}, chunk {k}");
        }
        let out = fast.outputs();
        let at = |i| out.position(i);
        // The lines' and arcs' end points, the increments' 3 and -2 steps, and axis 2's
        // half step rounded up (the DDA starts from M / 2); pair 3 is not built (4
        // axes): that record is refused.
        assert_eq!(
            (at(0), at(1), at(2), at(3)),
            (40 + 12 + 3, -17 + 12 - 2, -30 - 25 + 1, 30),
            "step_shared {step_shared}"
        );
        inputs.rec_valid = false;
        let end = fast.run_chunk_fast(&inputs, 1_000_000_000, &mut ev_fast);
        assert_eq!(end.cycles, 1_000_000_000);
    }
}

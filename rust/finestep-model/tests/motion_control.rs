//! Motion control in `finestep_top`, through the pins: the FIFO gate opens at the start
//! threshold, records are consumed one per period on the period grid, an underrun in the
//! middle of a block holds every axis and is counted exactly one clock after the
//! boundary that found the FIFO dry, and a block end is a normal stop.

mod host;

use finestep_interface::regs;
use finestep_model::top::TopParams;
use finestep_model::{PeriodRecord, MAX_AXES};
use host::*;
use proptest::prelude::*;

/// Settings of one scenario.
#[derive(Clone, Debug)]
struct Scenario {
    n_axes: usize,
    /// Built with the step engine (`STEP_SHARED`): `S` slots, else 1.
    step_shared: bool,
    period: u32,
    start_level: u32,
    step_len: u32,
    step_space: u32,
    /// Raw increments (non-negative: no reversals) per record.
    records: Vec<[i32; MAX_AXES]>,
}

/// The step engine's slots `S` of the build (docs/spec/step_engine.md: 2 for up to 2
/// axes, 4 for up to 4), 1 with a DDA and a shaper per axis.
fn slots(n_axes: usize, step_shared: bool) -> u32 {
    match (step_shared, n_axes) {
        (false, _) => 1,
        (true, 1..=2) => 2,
        (true, _) => 4,
    }
}

/// A drive timing as the core runs it: rounded up to whole visits of `s` clocks, at
/// least one (docs/spec/step_engine.md#what-sharing-changes-at-the-pins).
fn in_visits(timing: u32, s: u32) -> u32 {
    timing.max(1).div_ceil(s) * s
}

/// The period the core runs: `P` rounded down to a multiple of `S`, at least `S`.
fn period_run(sc: &Scenario) -> usize {
    let s = slots(sc.n_axes, sc.step_shared);
    (sc.period - sc.period % s).max(s) as usize
}

fn scenario() -> impl Strategy<Value = Scenario> {
    (1..=4usize, any::<bool>(), 60..300u32, 0..5u32, 1..4u32, 1..4u32).prop_flat_map(
        |(n_axes, step_shared, period, start_level, l, s)| {
            // Within the rated rate: D * (L + S) <= P, the timings and the period as the
            // core runs them.
            let slot = slots(n_axes, step_shared);
            let run = (period - period % slot).max(slot);
            let max_raw =
                (i64::from(run / (in_visits(l, slot) + in_visits(s, slot))) << 16).min(i64::from(i32::MAX)) as i32;
            let records = prop::collection::vec(prop::array::uniform8(0..=max_raw), start_level.max(1) as usize..8);
            (Just(n_axes), Just(step_shared), Just(period), Just(start_level), Just(l), Just(s), records).prop_map(
                |(n_axes, step_shared, period, start_level, step_len, step_space, records)| Scenario {
                    n_axes,
                    step_shared,
                    period,
                    start_level,
                    step_len,
                    step_space,
                    records,
                },
            )
        },
    )
}

/// A brought-up machine configured for `sc`, running (RUN = 1) with an empty FIFO.
fn running(sc: &Scenario) -> (Bench, ParallelMaster, SpiMaster) {
    let p = TopParams { n_axes: sc.n_axes, step_shared: sc.step_shared, has_pbp: false, ..TopParams::default() };
    let bus = ParallelMaster::default();
    let spi = SpiMaster::default();
    let mut bench = Bench::new(p);
    bench.bring_up(&bus);
    bus.write32(&mut bench, regs::period_clocks::ADDR, sc.period);
    bus.write32(&mut bench, regs::start_level::ADDR, sc.start_level);
    for axis in 0..sc.n_axes {
        bus.write32(&mut bench, regs::axis_timing_a::addr(axis), timing_a(sc.step_len, sc.step_space));
        bus.write32(&mut bench, regs::axis_timing_b::addr(axis), timing_b(1, 1));
    }
    bus.write32(&mut bench, regs::axis_enable::ADDR, (1 << sc.n_axes) - 1);
    bus.write32(&mut bench, regs::control::ADDR, regs::control::RUN.set(regs::control::reset_word(), 1));
    (bench, bus, spi)
}

/// The first cycle index at which `f` holds, after `from`.
fn first(trace: &[Sample], from: usize, f: impl Fn(&Sample) -> bool) -> Option<usize> {
    (from..trace.len()).find(|&i| f(&trace[i]))
}

#[test]
fn threshold_period_grid_and_underrun_timing() {
    let mut runner = finestep_testkit::runner("motion_threshold_grid_underrun", 64);
    runner
        .run(&scenario(), |sc| {
            let (mut bench, _bus, spi) = running(&sc);
            bench.trace = Some(vec![]);
            let records: Vec<PeriodRecord> = sc.records.iter().map(|raw| record(raw, 0, sc.n_axes)).collect();
            // One record per frame up to one below the threshold (each frame lasts
            // several periods, nothing may move), then the rest in one frame.
            let start = sc.start_level.max(1) as usize;
            for rec in &records[..start - 1] {
                let (_, result) = spi.fifo(&mut bench, std::slice::from_ref(rec), sc.n_axes);
                prop_assert_eq!(result, ACK);
            }
            let (_, result) = spi.fifo(&mut bench, &records[start - 1..], sc.n_axes);
            prop_assert_eq!(result, ACK);
            bench.clock(u64::from(sc.period) * (records.len() as u64 + 3) + 50);
            let trace = bench.trace.take().unwrap();

            // Boundaries lie on the grid of the period run from the first one.
            let period = period_run(&sc);
            let b0 = first(&trace, 0, Sample::boundary).expect("no boundary");
            for (i, s) in trace.iter().enumerate().skip(b0) {
                prop_assert_eq!(s.boundary(), (i - b0) % period == 0, "boundary grid at {}", i);
            }
            // Nothing is consumed before the threshold is reached.
            let reached = first(&trace, 0, |s| s.fifo_level >= start).expect("threshold never reached");
            let pops: Vec<usize> =
                (1..trace.len()).filter(|&i| trace[i].fifo_level < trace[i - 1].fifo_level).collect();
            prop_assert_eq!(pops.len(), records.len(), "every record consumed once");
            // The gate opens at the edge after the threshold; the first pop is at the
            // first boundary from then on.
            let first_boundary = (reached + 1..).find(|&i| i >= b0 && (i - b0) % period == 0).unwrap();
            prop_assert_eq!(pops[0], first_boundary + 1);
            // Then one record per period, on consecutive boundaries.
            for (j, &pop) in pops.iter().enumerate() {
                prop_assert_eq!(pop, pops[0] + j * period, "pop {}", j);
            }
            let last_pop = *pops.last().unwrap();
            // The boundary after the last record finds the FIFO dry mid-block.
            let dry = last_pop - 1 + period;
            prop_assert_eq!(trace[dry].underrun_count, 0);
            prop_assert_eq!(trace[dry + 1].underrun_count, 1, "counted one clock after boundary {}", dry);
            prop_assert!(!trace[dry + 1].gate);
            // Every axis holds from there on at the rounded sum of what was consumed.
            let end = trace.last().unwrap();
            for axis in 0..sc.n_axes {
                let sum: i64 = sc.records.iter().map(|r| i64::from(r[axis])).sum();
                prop_assert_eq!(i64::from(end.positions[axis]), rounded_steps(sum), "axis {}", axis);
            }
            prop_assert_eq!(regs::status::UNDERRUN.get(bench.reg(regs::status::ADDR)), 1);
            Ok(())
        })
        .unwrap();
}

#[test]
fn a_block_end_is_a_normal_stop_and_an_underrun_waits_for_clear_errors() {
    for step_shared in [false, true] {
        block_end_and_underrun(step_shared);
    }
}

fn block_end_and_underrun(step_shared: bool) {
    let sc =
        Scenario { n_axes: 2, step_shared, period: 200, start_level: 2, step_len: 2, step_space: 2, records: vec![] };
    let (mut bench, bus, spi) = running(&sc);
    let step = 1 << 16; // one step per period
    let block = [record(&[step, 2 * step], 0, 2), record(&[step, 2 * step], regs_block_end(), 2)];
    assert_eq!(spi.fifo(&mut bench, &block, 2).1, ACK);
    bench.clock(1000);
    assert_eq!(bench.top.fifo_level(), 0);
    assert_eq!(bench.reg(regs::underrun_count::ADDR), 0, "BLOCK_END then dry: a normal stop");
    assert_eq!(regs::status::STREAMING.get(bench.reg(regs::status::ADDR)), 0);
    assert_eq!(bench.sample().positions[..2], [2, 4]);

    // Below the threshold nothing moves; at it, motion resumes.
    assert_eq!(spi.fifo(&mut bench, &block[..1], 2).1, ACK);
    bench.clock(1000);
    assert_eq!(bench.top.fifo_level(), 1);
    assert_eq!(spi.fifo(&mut bench, &block[..1], 2).1, ACK);
    bench.clock(1000);
    assert_eq!(bench.sample().positions[..2], [4, 8]);
    assert_eq!(bench.reg(regs::underrun_count::ADDR), 1, "two records without BLOCK_END, then dry");

    // After an underrun the gate stays shut until CLEAR_ERRORS.
    assert_eq!(spi.fifo(&mut bench, &block, 2).1, ACK);
    bench.clock(1000);
    assert_eq!(bench.top.fifo_level(), 2);
    bus.write32(&mut bench, regs::command::ADDR, regs::command::CLEAR_ERRORS.set(0, 1));
    bench.clock(1000);
    assert_eq!(bench.top.fifo_level(), 0);
    assert_eq!(bench.sample().positions[..2], [6, 12]);
    assert_eq!(regs::status::UNDERRUN.get(bench.reg(regs::status::ADDR)), 0);
    assert_eq!(bench.reg(regs::underrun_count::ADDR), 1);
    // CLEAR_COUNTERS zeroes the count.
    bus.write32(&mut bench, regs::command::ADDR, regs::command::CLEAR_COUNTERS.set(0, 1));
    bench.clock(2);
    assert_eq!(bench.reg(regs::underrun_count::ADDR), 0);
}

/// The record flag `BLOCK_END`.
fn regs_block_end() -> u8 {
    finestep_model::record::flags::BLOCK_END
}

#[test]
fn record_push_queues_the_record_inc_registers() {
    for step_shared in [false, true] {
        record_push(step_shared);
    }
}

fn record_push(step_shared: bool) {
    let sc =
        Scenario { n_axes: 3, step_shared, period: 100, start_level: 1, step_len: 1, step_space: 1, records: vec![] };
    let (mut bench, bus, _spi) = running(&sc);
    bus.write32(&mut bench, regs::control::ADDR, regs::control::reset_word()); // stop: keep the record
    for (axis, raw) in [0x0001_8000u32, 0xFFFF_0000, 0x0000_0001].iter().enumerate() {
        bus.write32(&mut bench, regs::record_inc::addr(axis), *raw);
    }
    bus.write32(&mut bench, regs::record_push::ADDR, 0xA5);
    // The push writes the FIFO's record a RECORD_INC a cycle, then commits it.
    bench.clock(sc.n_axes as u64 + 2);
    let held: Vec<PeriodRecord> = bench.top.fifo().records().copied().collect();
    let raw = [0x0001_8000u32 as i32, 0xFFFF_0000u32 as i32, 1];
    assert_eq!(held, vec![record(&raw, 0xA5, 3)]);
    // A full FIFO refuses a push: OVERFLOW and one refused record.
    for _ in 0..(1usize << TopParams::default().fifo_depth_log2) {
        bus.write32(&mut bench, regs::record_push::ADDR, 0);
    }
    bench.clock(sc.n_axes as u64 + 2);
    assert_eq!(bench.top.fifo_level(), 1 << TopParams::default().fifo_depth_log2);
    assert_eq!(bench.reg(regs::refused_record_count::ADDR), 1);
    assert_eq!(regs::status::OVERFLOW.get(bench.reg(regs::status::ADDR)), 1);
}

/// An SPI READ of `LATCH_TIME` .. `POSITION[n-1]` during motion: the positions are those
/// of the core in one cycle, a period boundary, and `LATCH_TIME` names that cycle
/// (`TIMESTAMP` counts clocks from reset), although many boundaries pass during the
/// frame.
#[test]
fn positions_read_during_motion_are_latched_together_at_a_boundary() {
    let mut runner = finestep_testkit::runner("positions_latched_together", 24);
    runner
        .run(&(scenario(), 0..3000u64), |(sc, delay)| {
            let sc = Scenario { start_level: 1, ..sc };
            let (mut bench, _bus, spi) = running(&sc);
            let mut records: Vec<PeriodRecord> = sc.records.iter().map(|raw| record(raw, 0, sc.n_axes)).collect();
            // Enough records to keep moving through the read.
            while records.len() < 120 {
                records.extend_from_within(..records.len().min(120 - records.len()));
            }
            // Trace from before the records are queued: the latch the read returns may
            // be from any boundary since (the periods run while the FIFO fills).
            bench.trace = Some(vec![]);
            prop_assert_eq!(spi.fifo(&mut bench, &records, sc.n_axes).1, ACK);
            bench.clock(delay);
            let first = regs::latch_time::ADDR;
            let count = regs::position::addr(sc.n_axes - 1) - first + 1;
            let (_, words) = spi.read(&mut bench, first, count);
            let trace = bench.trace.take().unwrap();
            let latch_time = u64::from(words[0]);
            let origin = trace[0].cycle;
            prop_assert!(latch_time >= origin, "latched before the trace");
            let latched = &trace[(latch_time - origin) as usize];
            prop_assert!(latched.boundary(), "LATCH_TIME {} is not a boundary", latch_time);
            let positions_at = usize::from(regs::position::ADDR - first);
            for axis in 0..sc.n_axes {
                prop_assert_eq!(words[positions_at + axis] as i32, latched.positions[axis], "axis {}", axis);
            }
            // Boundaries passed while the frame was read, so the hold was needed.
            let later = trace.iter().filter(|s| s.cycle > latch_time && s.boundary()).count();
            prop_assert!(later >= 1, "no boundary passed during the frame: the test proves nothing");
            Ok(())
        })
        .unwrap();
}

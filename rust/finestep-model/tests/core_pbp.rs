//! The core model with the point-by-point comparison interpolator (`HAS_PBP`,
//! docs/spec/pbp_interp.md#in-the-core) against exact geometry, at the core's outputs:
//! the positions its step shapers count, read every clock. Every line with
//! `|Xe|, |Ye| <= 10` and arcs from every start with `2 <= R^2 <= 64` (both directions,
//! a quarter, a half, a whole turn and a short prefix) on both axis pairs, between DDA
//! records: after every step the pair moved one step on one axis, a line's position is
//! within one step of its segment, an arc's within one step of its circle; the end point
//! is exact, and the axes off the pair do not move. Both with a DDA and a shaper per axis
//! and with the step engine (`STEP_SHARED = 1`, the board tops'), which takes the block's
//! requests at its shaper visits; a record whose decisions come closer than a visit (`S`
//! clocks) is refused there. The ideals are the integer ones of the block's own test
//! (tests/geometry), not the model's helpers.

use finestep_interface::{flags, PbpLanes};
use finestep_model::{AxisConfig, Core, CoreInputs, CoreParams, DriveTiming, PeriodRecord, MAX_AXES};

mod geometry;
use geometry::{within_one_of_circle, within_one_of_segment};

const PERIOD: u32 = 16;

/// What a record's path must stay within.
#[derive(Clone, Copy, Debug)]
enum Ideal {
    /// The segment from the start to `start + (xe, ye)`.
    Line(i64, i64),
    /// The circle through the start around `start - (x0, y0)`, `R^2 = x0^2 + y0^2`.
    Arc(i64, i64),
}

struct Bench {
    core: Core,
    inputs: CoreInputs,
    /// The decision divider: a decision every `tick_div + 1` clocks, at least the
    /// drive timing's step (with the engine its timings are whole visits: 2 S clocks).
    tick_div: u32,
}

impl Bench {
    /// With the step engine (`shared`) or a DDA and a shaper per axis.
    fn new(shared: bool) -> Bench {
        let params = CoreParams { has_pbp: true, step_shared: shared, has_gantry: false, ..CoreParams::default() };
        let mut core = Core::new(params);
        let axis = AxisConfig { timing: DriveTiming::new(1, 1, 1, 1), enable: true, ..AxisConfig::default() };
        let mut inputs =
            CoreInputs { run: false, period_clocks: PERIOD, axes: [axis; MAX_AXES], ..CoreInputs::default() };
        core.step(&inputs);
        inputs.run = true;
        let tick_div = if shared { 2 * params.step_slots() - 1 } else { 2 };
        Bench { core, inputs, tick_div }
    }

    fn positions(&self) -> [i64; 4] {
        let out = self.core.outputs();
        std::array::from_fn(|i| i64::from(out.position(i)))
    }

    /// Offers `record` until taken, then runs until the core takes the next (an idle
    /// record, after the pbp record's done) and a period more; checks every clock's
    /// positions against `ideal` on `pair` (none for a DDA record). Returns the pair's
    /// end relative to its start.
    fn run(&mut self, record: PeriodRecord, pair: usize, ideal: Option<Ideal>, what: &str) -> (i64, i64) {
        let start = self.positions();
        let mut last = start;
        let mut check = |core: &Core| {
            let out = core.outputs();
            let now: [i64; 4] = std::array::from_fn(|i| i64::from(out.position(i)));
            if now == last || ideal.is_none() {
                return;
            }
            for axis in (0..4).filter(|a| a / 2 != pair) {
                assert_eq!(now[axis], start[axis], "{what}: axis {axis} off the pair moved");
            }
            let (dx, dy) = (now[2 * pair] - last[2 * pair], now[2 * pair + 1] - last[2 * pair + 1]);
            assert_eq!(dx.abs() + dy.abs(), 1, "{what}: not one step on one axis ({last:?} -> {now:?})");
            let (x, y) = (now[2 * pair] - start[2 * pair], now[2 * pair + 1] - start[2 * pair + 1]);
            match ideal {
                Some(Ideal::Line(xe, ye)) => {
                    assert!(within_one_of_segment(xe, ye, x, y), "{what}: ({x}, {y}) more than a step off the line")
                }
                Some(Ideal::Arc(x0, y0)) => {
                    let (cx, cy) = (x + x0, y + y0);
                    let r2 = (cx as i128).pow(2) + (cy as i128).pow(2);
                    let big_r2 = (x0 as i128).pow(2) + (y0 as i128).pow(2);
                    assert!(within_one_of_circle(r2, big_r2), "{what}: ({cx}, {cy}) more than a step off R^2 {big_r2}");
                    assert!((cx, cy) != (0, 0), "{what}: at the centre");
                }
                None => unreachable!("returned above"),
            }
            last = now;
        };
        for (offered, limit) in [(record, 100 * PERIOD), (PeriodRecord::default(), 100_000)] {
            self.inputs.rec_valid = true;
            self.inputs.record = offered;
            let mut taken = false;
            for _ in 0..limit {
                taken = self.core.outputs().rec_ready();
                self.core.step(&self.inputs);
                check(&self.core);
                if taken {
                    break;
                }
            }
            assert!(taken, "{what}: a record was not taken");
        }
        self.inputs.rec_valid = false;
        for _ in 0..2 * PERIOD + 8 {
            self.core.step(&self.inputs);
            check(&self.core);
        }
        assert!(!self.core.outputs().record_error(), "{what}: record error");
        let end = self.positions();
        if ideal.is_none() {
            return (0, 0);
        }
        (end[2 * pair] - start[2 * pair], end[2 * pair + 1] - start[2 * pair + 1])
    }
}

fn line(pair: u8, xe: i64, ye: i64, tick_div: u32) -> PeriodRecord {
    let lanes = PbpLanes { pair, x: xe as i32, y: ye as i32, tick_div, ..PbpLanes::default() };
    PeriodRecord::pbp(&lanes, 0)
}

#[test]
fn every_line_up_to_10_on_both_pairs_stays_within_a_step_and_ends_exactly() {
    for shared in [false, true] {
        let mut bench = Bench::new(shared);
        for pair in 0..2u8 {
            for xe in -10i64..=10 {
                for ye in -10i64..=10 {
                    let what = format!("line ({xe}, {ye}) on pair {pair}, engine {shared}");
                    let record = line(pair, xe, ye, bench.tick_div);
                    let end = bench.run(record, usize::from(pair), Some(Ideal::Line(xe, ye)), &what);
                    assert_eq!(end, (xe, ye), "{what}: end point");
                }
                // A DDA record between: the pbp records start from wherever it left the axes.
                let dda = PeriodRecord::from_raw(&[1 << 16, -(2 << 16), 3 << 16, -(1 << 16)], flags::BLOCK_END);
                bench.run(dda, 2, None, "dda");
            }
        }
    }
}

#[test]
fn with_the_step_engine_decisions_closer_than_a_visit_are_refused() {
    let mut bench = Bench::new(true);
    let slots = bench.core.params().step_slots();
    let start = bench.positions();
    // S - 1 clocks apart: refused, an idle period, record_error; S apart: taken.
    bench.inputs.rec_valid = true;
    bench.inputs.record = line(0, 5, 3, slots - 2);
    for _ in 0..4 * PERIOD {
        bench.core.step(&bench.inputs);
    }
    bench.inputs.rec_valid = false;
    for _ in 0..4 * PERIOD {
        bench.core.step(&bench.inputs);
    }
    assert!(bench.core.outputs().record_error(), "refused");
    assert_eq!(bench.positions(), start, "a refused record moves nothing");
    bench.inputs.clear_errors = true;
    bench.core.step(&bench.inputs);
    bench.inputs.clear_errors = false;
    bench.tick_div = slots - 1;
    // (the shaper falls behind at this rate, as the block's spec says, and catches up)
    let what = "line (5, 3) with decisions S clocks apart";
    let end = bench.run(line(0, 5, 3, slots - 1), 0, Some(Ideal::Line(5, 3)), what);
    assert_eq!(end, (5, 3), "{what}");
}

#[test]
fn arcs_up_to_r2_64_stay_within_a_step_of_the_circle_and_end_exactly() {
    for shared in [false, true] {
        arcs(shared);
    }
}

fn arcs(shared: bool) {
    use finestep_model::pbp_interp::arc_steps;
    let mut bench = Bench::new(shared);
    let mut count = 0;
    for x0 in -8i64..=8 {
        for y0 in -8i64..=8 {
            let r2 = x0 * x0 + y0 * y0;
            if !(2..=64).contains(&r2) {
                continue;
            }
            for cw in [false, true] {
                let full = arc_steps((x0, y0), (x0, y0), cw).expect("a whole turn");
                for k in [1, full / 4, full / 2, full, (x0 * 7 + y0 * 3).rem_euclid(full as i64) as u64 + 1] {
                    let k = k.max(1);
                    // The end: the ideal decides nothing here; the count is what the host
                    // sends for an end on the path, and the end is checked exactly below
                    // against the circle and the count's own end (arc_steps of it is k).
                    let lanes = PbpLanes {
                        arc: true,
                        cw,
                        pair: (count % 2) as u8,
                        x: x0 as i32,
                        y: y0 as i32,
                        steps: k,
                        tick_div: bench.tick_div.max(3),
                    };
                    let pair = count % 2;
                    count += 1;
                    let what = format!("arc from ({x0}, {y0}) cw {cw}, {k} of {full} decisions, engine {shared}");
                    let (dx, dy) = bench.run(PeriodRecord::pbp(&lanes, 0), pair, Some(Ideal::Arc(x0, y0)), &what);
                    let end = (x0 + dx, y0 + dy);
                    let end_r2 = (end.0 as i128).pow(2) + (end.1 as i128).pow(2);
                    assert!(within_one_of_circle(end_r2, i128::from(r2)), "{what}: end {end:?} off the circle");
                    // The end is the point the host asked for: its count from the start is k.
                    assert_eq!(arc_steps((x0, y0), end, cw), Ok(k), "{what}: end {end:?}");
                    if k == full {
                        assert_eq!(end, (x0, y0), "{what}: a whole turn ends at its start");
                    }
                }
            }
        }
    }
}

//! The core with the point-by-point comparison interpolator (`HAS_PBP`,
//! docs/spec/pbp_interp.md#in-the-core): the Verilated core against the model, every
//! output (pins, positions, `rec_ready`, `record_error`, `block_end`) on every clock, over
//! streams that mix DDA records with pbp lines and arcs on both axis pairs: every
//! quadrant, CW and CCW, arcs crossing quadrants and whole turns, random decision
//! dividers and `BLOCK_END`s; a halt (E-stop) in the middle of a pbp record and the
//! motion after it; a record on a pair the core does not have. Both cores: with a DDA and
//! a shaper per axis and the gantry block (`Vfinestep_core_pbp`: disengaged, and engaged
//! in forward and synchronised mode with pbp lines and arcs on the master's pair: the
//! slave follows the block's requests as the DDAs', its own pair's are ignored) and with
//! the step engine (`Vfinestep_core_pbp_shared`, `STEP_SHARED = 1` as every board top),
//! whose shaper visits take the block's requests and which refuses a divider below a
//! visit. The period timer's boundary (`period_boundary`) is compared too: it goes on
//! through a pbp record while `rec_ready` is low. The end positions are
//! checked against the records' displacements (a line's end point, an arc's end minus its
//! start), exact. A failure prints the seed (rerun with FINESTEP_SEED) and the first
//! cycle, signal, expected and actual value. The gantry sees a pbp record's motion: an
//! engagement asked in the middle of a record on the master's or the slave's pair waits
//! to the clock after its `done`, and a random mix enables and disables the gantry at
//! random clocks, in and between records.

use finestep_cosim::{Harness, ModelPath};
use finestep_interface::{flags, PbpLanes};
use finestep_model::pbp_interp::{arc_steps, ArcPath};
use finestep_model::{AxisConfig, CoreInputs, DriveTiming, GantryInputs, Increment, PeriodRecord, MAX_AXES};

const PERIOD: u32 = 40;
const AXES: usize = 4;

/// One of the two Verilated cores with the block.
#[derive(Clone, Copy, Debug)]
enum Variant {
    /// A DDA and a shaper per axis (`STEP_SHARED = 0`).
    PerAxis,
    /// The step engine (`STEP_SHARED = 1`).
    Shared,
}

impl Variant {
    const ALL: [Variant; 2] = [Variant::PerAxis, Variant::Shared];

    fn harness(self, name: &str, path: ModelPath) -> Harness {
        match self {
            Variant::PerAxis => Harness::with_pbp(name, path),
            Variant::Shared => Harness::with_pbp_shared(name, path),
        }
    }

    /// Added to the streams' decision dividers (3 and up): with the engine the drive
    /// timing's step is whole visits, 2 S = 8 clocks, and a divider below S - 1 is refused.
    fn slower(self) -> u32 {
        match self {
            Variant::PerAxis => 0,
            Variant::Shared => 4,
        }
    }
}

/// xorshift64*: the stream's choices, from the printed seed.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    /// Uniform in `lo..=hi`.
    fn range(&mut self, lo: i64, hi: i64) -> i64 {
        lo + (self.next() % (hi - lo + 1) as u64) as i64
    }
    fn coin(&mut self) -> bool {
        self.next() & 1 == 1
    }
}

/// One record of a stream and the displacement it commands on each axis.
struct Move {
    record: PeriodRecord,
    delta: [i64; AXES],
}

fn inputs() -> CoreInputs {
    // L + max(S, H + U) = 4 clocks: a decision every 4 or more clocks keeps the timing.
    let axis = AxisConfig { timing: DriveTiming::new(2, 2, 1, 1), enable: true, ..AxisConfig::default() };
    CoreInputs { run: false, period_clocks: PERIOD, axes: [axis; MAX_AXES], ..CoreInputs::default() }
}

/// A line to `(xe, ye)` on `pair`.
fn line(pair: u8, xe: i64, ye: i64, tick_div: u32, flags: u8) -> Move {
    let lanes = PbpLanes { pair, x: xe as i32, y: ye as i32, tick_div, ..PbpLanes::default() };
    assert!(lanes.fits());
    let mut delta = [0; AXES];
    delta[2 * usize::from(pair)] = xe;
    delta[2 * usize::from(pair) + 1] = ye;
    Move { record: PeriodRecord::pbp(&lanes, flags), delta }
}

/// An arc from `start` (relative to its centre) over `k` decisions of its path, on `pair`.
fn arc(pair: u8, start: (i64, i64), cw: bool, k: usize, tick_div: u32, flags: u8) -> Move {
    let end = ArcPath::new(start.0, start.1, cw).nth(k - 1).expect("an arc's path is endless").1;
    let steps = arc_steps(start, end, cw).expect("the end is on the path");
    let lanes = PbpLanes { arc: true, cw, pair, x: start.0 as i32, y: start.1 as i32, steps, tick_div };
    assert!(lanes.fits());
    let mut delta = [0; AXES];
    delta[2 * usize::from(pair)] = end.0 - start.0;
    delta[2 * usize::from(pair) + 1] = end.1 - start.1;
    Move { record: PeriodRecord::pbp(&lanes, flags), delta }
}

/// A DDA record of whole steps per period (exactly that many steps in the period).
fn dda(steps: [i64; AXES], flags: u8) -> Move {
    let raw: Vec<i32> = steps.iter().map(|&s| (s as i32) << 16).collect();
    Move { record: PeriodRecord::from_raw(&raw, flags), delta: steps }
}

/// Lines and arcs in every quadrant, both directions, on both pairs, between DDA records;
/// the dividers `slower` more than 3 to 5.
fn fixed_moves(slower: u32) -> Vec<Move> {
    let mut moves = Vec::new();
    let (t3, t4, t5) = (3 + slower, 4 + slower, 5 + slower);
    for (q, &(sx, sy)) in [(1, 1), (-1, 1), (-1, -1), (1, -1)].iter().enumerate() {
        let pair = (q % 2) as u8;
        moves.push(line(pair, 9 * sx, 4 * sy, t3, 0));
        moves.push(dda([sx, -sy, 2 * sy, 0], 0));
        for cw in [false, true] {
            // A quarter and more from inside the quadrant: crosses an axis.
            moves.push(arc(pair, (5 * sx, 3 * sy), cw, 14, t4, 0));
        }
        moves.push(line(pair, 0, 7 * sy, t5, flags::BLOCK_END));
        moves.push(line(1 - pair, 6 * sx, 0, t5, 0));
    }
    // Whole turns both ways, and an arc from an axis point.
    moves.push(arc(0, (4, 0), false, arc_steps((4, 0), (4, 0), false).unwrap() as usize, t3, 0));
    moves.push(arc(1, (0, -6), true, arc_steps((0, -6), (0, -6), true).unwrap() as usize, t3, flags::BLOCK_END));
    moves
}

fn random_moves(rng: &mut Rng, count: usize, slower: u32) -> Vec<Move> {
    let mut moves = Vec::new();
    while moves.len() < count {
        let pair = rng.range(0, 1) as u8;
        let tick = rng.range(3, 9) as u32 + slower;
        let end = if rng.range(0, 4) == 0 { flags::BLOCK_END } else { 0 };
        match rng.range(0, 2) {
            0 => {
                let steps = [0; AXES].map(|_: i64| rng.range(-4, 4));
                moves.push(dda(steps, end));
            }
            1 => moves.push(line(pair, rng.range(-40, 40), rng.range(-40, 40), tick, end)),
            _ => {
                let start = (rng.range(-15, 15), rng.range(-15, 15));
                if start.0 * start.0 + start.1 * start.1 < 2 {
                    continue;
                }
                let cw = rng.coin();
                let full = arc_steps(start, start, cw).unwrap() as i64;
                let k = rng.range(1, full) as usize;
                moves.push(arc(pair, start, cw, k, tick, end));
            }
        }
    }
    moves
}

fn positions(h: &Harness) -> [i64; AXES] {
    let out = h.outputs();
    std::array::from_fn(|i| i64::from(out.position(i)))
}

/// Feeds `moves` and waits until they have run; returns the positions.
fn stream(h: &mut Harness, inp: &mut CoreInputs, moves: &[Move], seed: u64) -> [i64; AXES] {
    for m in moves {
        h.feed(inp, [m.record]).unwrap_or_else(|e| panic!("FINESTEP_SEED={seed:#x}: {e}"));
    }
    // An idle record is taken only after the last pbp record's done; then its period.
    h.feed(inp, [PeriodRecord::default()]).unwrap_or_else(|e| panic!("FINESTEP_SEED={seed:#x}: {e}"));
    h.idle(inp, u64::from(3 * PERIOD)).unwrap_or_else(|e| panic!("FINESTEP_SEED={seed:#x}: {e}"));
    positions(h)
}

fn sum(moves: &[Move]) -> [i64; AXES] {
    let mut total = [0; AXES];
    for m in moves {
        for (t, d) in total.iter_mut().zip(m.delta) {
            *t += d;
        }
    }
    total
}

#[test]
fn pbp_and_dda_records_in_lockstep_and_exact() {
    let seed = finestep_testkit::seed("core_pbp_stream");
    eprintln!("core_pbp_stream: FINESTEP_SEED={seed:#x} (rerun with this to reproduce)");
    for variant in Variant::ALL {
        let mut rng = Rng(seed | 1);
        let mut moves = fixed_moves(variant.slower());
        moves.extend(random_moves(&mut rng, finestep_testkit::cases(60) as usize, variant.slower()));
        for path in [ModelPath::PerClock, ModelPath::Fast] {
            let mut h = variant.harness("core_pbp_stream", path);
            let mut inp = inputs();
            h.idle(&inp, 4).unwrap();
            inp.run = true;
            let end = stream(&mut h, &mut inp, &moves, seed);
            assert_eq!(end, sum(&moves), "{variant:?} {path:?} FINESTEP_SEED={seed:#x}: end positions");
            assert!(!h.outputs().record_error(), "{variant:?}");
        }
    }
}

#[test]
fn with_the_step_engine_a_divider_below_a_visit_is_refused() {
    for path in [ModelPath::PerClock, ModelPath::Fast] {
        let mut h = Variant::Shared.harness("core_pbp_divider", path);
        let mut inp = inputs();
        h.idle(&inp, 4).unwrap();
        inp.run = true;
        // S = 4 slots: decisions 3 clocks apart are refused (an idle period), 4 apart run.
        let refused = line(0, 7, -3, 2, 0);
        h.feed(&mut inp, [refused.record]).unwrap();
        h.idle(&inp, u64::from(3 * PERIOD)).unwrap();
        assert_eq!(positions(&h), [0; AXES], "{path:?}: the refused record moved nothing");
        assert!(h.outputs().record_error(), "{path:?}: refused");
        inp.clear_errors = true;
        h.idle(&inp, 2).unwrap();
        inp.clear_errors = false;
        let taken = line(0, 7, -3, 3, 0);
        let end = stream(&mut h, &mut inp, &[taken], 0);
        assert_eq!(end, [7, -3, 0, 0], "{path:?}");
        assert!(!h.outputs().record_error(), "{path:?}");
    }
}

#[test]
fn a_halt_stops_a_pbp_record_and_the_motion_after_it_is_exact() {
    for (variant, path) in Variant::ALL.into_iter().flat_map(|v| [(v, ModelPath::PerClock), (v, ModelPath::Fast)]) {
        let slower = variant.slower();
        let mut h = variant.harness("core_pbp_halt", path);
        let mut inp = inputs();
        h.idle(&inp, 4).unwrap();
        inp.run = true;
        // A long line on pair 1, halted in its middle (E-stop: the top raises halt, then
        // drops run and empties the FIFO).
        let long = line(1, 150, -70, 5 + slower, 0);
        h.feed(&mut inp, [long.record]).unwrap();
        h.idle(&inp, 400).unwrap();
        let before = positions(&h);
        assert!(before[2] > 0 && before[2] < 150, "{variant:?} {path:?}: the line is under way: {before:?}");
        inp.halt = true;
        h.idle(&inp, 3).unwrap();
        let halted = positions(&h);
        h.idle(&inp, 300).unwrap();
        assert_eq!(positions(&h), halted, "{variant:?} {path:?}: no step after the halt");
        inp.run = false;
        h.idle(&inp, 10).unwrap();
        inp.halt = false;
        h.idle(&inp, 10).unwrap();
        assert_eq!(positions(&h), halted, "{variant:?} {path:?}: nothing moves while stopped and released");
        // The motion after it: from where the halt left the axes.
        inp.run = true;
        let after = [
            line(1, -9, 12, 4 + slower, 0),
            dda([1, -2, 0, 3], 0),
            arc(0, (6, -2), true, 20, 4 + slower, flags::BLOCK_END),
        ];
        let end = stream(&mut h, &mut inp, &after, 0);
        let mut expect = halted;
        for (e, d) in expect.iter_mut().zip(sum(&after)) {
            *e += d;
        }
        assert_eq!(end, expect, "{variant:?} {path:?}");
        // A record on pair 3 (pair 1's record with bit 1 of PAIR also set: axes 6 and 7,
        // not built): refused, an idle period.
        let refused = line(1, 5, 5, 4, 0);
        let mut record = refused.record;
        record.inc[0] = Increment::from_bits(record.inc[0].to_bits() | (2 << (PbpLanes::TOP + 4)));
        let end = {
            h.feed(&mut inp, [record]).unwrap();
            h.idle(&inp, u64::from(3 * PERIOD)).unwrap();
            positions(&h)
        };
        assert_eq!(end, expect, "{variant:?} {path:?}: the refused record moved nothing");
        assert!(h.outputs().record_error(), "{variant:?} {path:?}: refused");
        inp.clear_errors = true;
        h.idle(&inp, 2).unwrap();
        assert!(!h.outputs().record_error(), "{variant:?} {path:?}: cleared");
    }
}

#[test]
fn the_period_boundary_goes_on_through_a_pbp_record() {
    for variant in Variant::ALL {
        let mut h = variant.harness("core_pbp_boundary", ModelPath::PerClock);
        let mut inp = inputs();
        h.idle(&inp, 4).unwrap();
        inp.run = true;
        let long = line(0, 60, 25, 5 + variant.slower(), 0);
        h.feed(&mut inp, [long.record]).unwrap();
        // The record runs for (60 + 25) decisions of 6 clocks or more: several periods.
        let (mut boundaries, mut ready) = (0, 0);
        for _ in 0..(4 * PERIOD) {
            h.idle(&inp, 1).unwrap();
            let out = h.outputs();
            boundaries += u32::from(out.period_boundary());
            ready += u32::from(out.rec_ready());
        }
        assert!(boundaries >= 3, "{variant:?}: {boundaries} boundaries in 4 periods of the record");
        assert_eq!(ready, 0, "{variant:?}: rec_ready low while the record runs");
    }
}

#[test]
fn with_the_gantry_engaged_the_slave_follows_pbp_moves_of_the_master() {
    let seed = finestep_testkit::seed("core_pbp_gantry");
    eprintln!("core_pbp_gantry: FINESTEP_SEED={seed:#x} (rerun with this to reproduce)");
    // Master axis 0 (X of pair 0), slave axis 3 (Y of pair 1).
    let (master, slave) = (0, 3);
    for sync in [false, true] {
        let mut rng = Rng(seed | 1);
        // Lines and arcs on pair 0 (the master's) between DDA records that also ask the
        // slave's own DDA for steps, and lines on pair 1, whose Y is the slave: both
        // ignored while engaged.
        let mut moves = vec![
            line(0, 17, -6, 4, 0),
            dda([2, -1, 1, 3], 0),
            arc(0, (-5, 7), true, 30, 5, 0),
            line(1, 8, -9, 4, 0),
            arc(0, (6, 2), false, 25, 4, flags::BLOCK_END),
        ];
        moves.extend(random_moves(&mut rng, finestep_testkit::cases(12) as usize, 0));
        for path in [ModelPath::PerClock, ModelPath::Fast] {
            let mut h = Variant::PerAxis.harness("core_pbp_gantry", path);
            let mut inp = inputs();
            inp.gantry = GantryInputs {
                master: 0,
                slave: 3,
                sync,
                tick: 23,
                deadband: 0,
                limit: 1000,
                ..GantryInputs::default()
            };
            h.idle(&inp, 4).unwrap();
            inp.gantry.enable = true;
            h.idle(&inp, 4).unwrap();
            assert_ne!(h.outputs().gantry_flags & 1, 0, "engaged at rest");
            inp.run = true;
            let half = moves.len() / 2;
            stream(&mut h, &mut inp, &moves[..half], seed);
            // Synchronised: the master's channel 2 counts ahead from here, so corrections
            // (insertions and deletions of the master's pbp and DDA steps) run under the
            // second half's moves; the channels square up again before its end.
            if sync {
                inp.gantry.enc_master = 2;
            }
            for m in &moves[half..] {
                h.feed(&mut inp, [m.record]).unwrap_or_else(|e| panic!("FINESTEP_SEED={seed:#x}: {e}"));
                if sync && inp.gantry.enc_master != 0 && h.outputs().gantry_corrections as i16 != 0 {
                    inp.gantry.enc_slave = 2;
                }
            }
            let end = stream(&mut h, &mut inp, &[], seed);
            let out = h.outputs();
            let corrections = i64::from(out.gantry_corrections as i16);
            let want = sum(&moves);
            let what = format!("sync {sync} {path:?} FINESTEP_SEED={seed:#x}");
            assert_eq!([end[0], end[1], end[2]], [want[0], want[1], want[2]], "{what}: the other axes");
            assert_eq!(end[slave], end[master] + corrections, "{what}: the slave is the master plus its corrections");
            if sync {
                assert_ne!(corrections, 0, "{what}: corrections applied");
            } else {
                assert_eq!(corrections, 0, "{what}");
            }
            assert_eq!(out.gantry_flags & 0b110, 0, "{what}: no alarm, no refusal");
            assert!(!out.record_error() && !out.step_lost(slave), "{what}");
        }
    }
}

/// The gantry's engaged flag.
fn engaged(h: &Harness) -> bool {
    h.outputs().gantry_flags & 1 != 0
}

#[test]
fn a_gantry_engagement_asked_in_a_pbp_record_on_its_pairs_waits_to_the_records_end() {
    // (master, slave, the record's pair, its end point, whether the engagement waits): a
    // record on the master's pair, on the slave's, a line on the master's pair that does
    // not move the master (X = 0: the pair is busy all the same), and one on another pair.
    let cases = [
        (0u8, 3u8, 0u8, (31, -17), true),
        (0, 3, 1, (-12, 25), true),
        (0, 3, 0, (0, 40), true),
        (2, 3, 0, (22, 14), false),
        (1, 0, 1, (-9, -30), false),
    ];
    for (master, slave, pair, (xe, ye), waits) in cases {
        for path in [ModelPath::PerClock, ModelPath::Fast] {
            let what = format!("master {master} slave {slave}, a line on pair {pair}, {path:?}");
            let mut h = Variant::PerAxis.harness("core_pbp_gantry_engage", path);
            let mut inp = inputs();
            inp.gantry = GantryInputs { master, slave, sync: true, tick: 7, limit: 1000, ..GantryInputs::default() };
            h.idle(&inp, 4).unwrap();
            inp.run = true;
            let m = line(pair, xe, ye, 4, flags::BLOCK_END);
            h.feed(&mut inp, [m.record]).unwrap();
            // In the middle of the record: the gantry is asked to engage.
            h.idle(&inp, 60).unwrap();
            assert!(
                !h.outputs().rec_ready() && h.model().pbp_motion()[usize::from(2 * pair)].busy,
                "{what}: the record runs"
            );
            inp.gantry.enable = true;
            let asked = h.cycle();
            let (mut end, mut at) = (None, None);
            for _ in 0..(5 * 60 + 40) {
                h.idle(&inp, 1).unwrap();
                if h.outputs().block_end() {
                    end = Some(h.cycle());
                }
                if engaged(&h) {
                    at = Some(h.cycle());
                    break;
                }
            }
            let at = at.unwrap_or_else(|| panic!("{what}: never engaged"));
            if waits {
                let end = end.unwrap_or_else(|| panic!("{what}: engaged before the record's end"));
                assert_eq!(at, end + 1, "{what}: engaged the clock after done");
            } else {
                assert_eq!((at, end), (asked + 1, None), "{what}: engaged at once, the record runs on");
            }
            // The rest of the record (if any) and an idle period: the positions are the line's.
            let end = stream(&mut h, &mut inp, &[], 0);
            assert_eq!(end, m.delta, "{what}");
            assert_eq!(h.outputs().gantry_flags & 0b110, 0, "{what}: no alarm, no refusal");
        }
    }
}

#[test]
fn random_gantry_engagements_and_corrections_in_pbp_records_in_lockstep() {
    let seed = finestep_testkit::seed("core_pbp_gantry_mix");
    eprintln!("core_pbp_gantry_mix: FINESTEP_SEED={seed:#x} (rerun with this to reproduce)");
    let mut rng = Rng(seed | 1);
    // Cycles in which an engagement was asked and held by a pbp record on the gantry's
    // pairs, and in which a correction was pending against the master's pbp motion.
    let (mut held, mut waited) = (0u64, 0u64);
    for run in 0..finestep_testkit::cases(6) {
        let pairs = [(0u8, 3u8), (0, 1), (2, 1), (3, 0)];
        let (master, slave) = pairs[rng.range(0, 3) as usize];
        let path = if run % 2 == 0 { ModelPath::PerClock } else { ModelPath::Fast };
        let what = format!("run {run} master {master} slave {slave} {path:?} FINESTEP_SEED={seed:#x}");
        let mut h = Variant::PerAxis.harness("core_pbp_gantry_mix", path);
        let mut inp = inputs();
        inp.gantry = GantryInputs {
            master,
            slave,
            sync: rng.range(0, 3) != 0,
            tick: rng.range(1, 30) as u32,
            deadband: rng.range(0, 1) as u16,
            limit: 60_000,
            ..GantryInputs::default()
        };
        h.idle(&inp, 4).unwrap();
        inp.run = true;
        let moves = random_moves(&mut rng, finestep_testkit::cases(24) as usize, 0);
        for mv in &moves {
            h.feed(&mut inp, [mv.record]).unwrap_or_else(|e| panic!("{what}: {e}"));
            // Some clocks in the record (or the period) just taken: the gantry enabled or
            // disabled at a random clock, the channels apart so that corrections run.
            for _ in 0..rng.range(0, 3) {
                h.idle(&inp, rng.range(1, 120) as u64).unwrap_or_else(|e| panic!("{what}: {e}"));
                match rng.range(0, 3) {
                    0 => inp.gantry.enable = !inp.gantry.enable,
                    1 => inp.gantry.enc_master = inp.gantry.enc_master.wrapping_add(rng.range(-3, 3) as u32),
                    2 => inp.gantry.enc_slave = inp.gantry.enc_slave.wrapping_add(rng.range(-3, 3) as u32),
                    _ => inp.gantry.enable = true,
                }
                for _ in 0..rng.range(1, 40) {
                    h.idle(&inp, 1).unwrap_or_else(|e| panic!("{what}: {e}"));
                    let motion = h.model().pbp_motion();
                    let (m, s) = (usize::from(master), usize::from(slave));
                    let g = h.model().gantry();
                    if inp.gantry.enable && !g.engaged() && (motion[m].busy || motion[s].busy) {
                        held += 1;
                    }
                    if g.engaged() && ((g.corr() > 0 && motion[m].down) || (g.corr() < 0 && motion[m].up)) {
                        waited += 1;
                    }
                }
            }
        }
        stream(&mut h, &mut inp, &[], seed);
        assert!(!h.outputs().record_error(), "{what}");
    }
    eprintln!("core_pbp_gantry_mix: {held} clocks of an engagement held by a pbp record, {waited} of a correction pending against the master's pbp motion");
    assert!(held > 0 && waited > 0, "FINESTEP_SEED={seed:#x}: the mix covers held engagements ({held}) and corrections against pbp motion ({waited})");
}

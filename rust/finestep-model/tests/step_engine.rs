//! The shared step engine (`STEP_SHARED = 1`, docs/spec/step_engine.md) checked against
//! ideals computed from the spec alone: the slot schedule (`S = 2, 2, 4, 4` for 1 to 4
//! axes), the period rounded down to a multiple of `S` and started at `slot == S - 1`,
//! the exact commanded position per DDA visit (`BigRational` and `i128`), and the
//! pulse timing at the pins in multiples of `S`. Random streams are kept within the
//! engine's rated rate (docs/spec/rated_rate.md, "With the shared step engine"), whose
//! intervals are computed here from the spec's formulas and compared with
//! `finestep_interface::rate`.

mod common;

use finestep_interface::pin_timing::StepDirMonitor;
use finestep_model::limits::{forward_interval_in, max_increment_in, reversal_interval_in, reversal_wait_in};
use finestep_model::{
    AxisConfig, Core, CoreInputs, CoreOutputs, CoreParams, DriveTiming, Increment, PeriodRecord, RateChecker, MAX_AXES,
};
use num_bigint::BigInt;
use num_rational::BigRational;
use num_traits::{One, Zero};
use proptest::prelude::*;

/// `S` for `n` axes, from the spec's table (`SL` 1 up to 2 axes, 2 up to 4, 3 up to 8).
fn slots_for(n: usize) -> u64 {
    match n {
        1 | 2 => 2,
        3 | 4 => 4,
        _ => 8,
    }
}

/// A timing value in whole visits: `max(ceil(x / S), 1)`.
fn visits(x: u32, s: u64) -> u64 {
    u64::from(x).div_ceil(s).max(1)
}

/// The spec's intervals in clocks: `I_fwd = S (L_v + S_v)`, `W = S (L_v + max(S_v, H_v + U_v) - 1)`.
fn ideal_intervals(t: &DriveTiming, s: u64) -> (u64, u64) {
    let v = |x| visits(x, s);
    let fwd = s * (v(t.step_len) + v(t.step_space));
    let wait = s * (v(t.step_len) + v(t.step_space).max(v(t.dir_hold) + v(t.dir_setup)) - 1);
    (fwd, wait)
}

fn timing(l: u32, s: u32, u: u32, h: u32) -> DriveTiming {
    DriveTiming::new(l, s, u, h)
}

fn params(n: usize, timing_width: u32) -> CoreParams {
    CoreParams {
        n_axes: n,
        p_width: 20,
        timing_width,
        has_gantry: false,
        step_shared: true,
        step_digit: 0,
        has_pbp: false,
    }
}

fn raw(x: Increment) -> i64 {
    i64::from(x.to_bits())
}

/// One drive of an engine core from reset.
#[derive(Clone, Debug)]
struct Drive {
    n: usize,
    timing_width: u32,
    /// `period_clocks` as given (the core rounds it).
    p: u32,
    /// The cycle `run` rises (it is 0 before).
    start: u64,
    axes: [AxisConfig; MAX_AXES],
    records: Vec<PeriodRecord>,
    drain: u64,
    /// `(h, release)`: `halt` and `run = 0` from cycle `h`, `halt` released at `release`.
    halt: Option<(u64, u64)>,
}

/// What a drive saw.
struct Trace {
    s: u64,
    /// The period run: `max(P with the low SL bits cleared, S)`.
    ps: u64,
    /// The first boundary.
    b0: u64,
    /// Outputs in cycles `0..len`.
    outputs: Vec<CoreOutputs>,
    /// `dda(a).req()` in cycles `0..len`.
    reqs: Vec<[i8; MAX_AXES]>,
    /// `shaper(a).pending()` in the halt cycle.
    pending_at_halt: [i8; MAX_AXES],
}

impl Drive {
    fn run(&self) -> Trace {
        let params = params(self.n, self.timing_width);
        let s = slots_for(self.n);
        let p = u64::from(self.p & 0xF_FFFF);
        let ps = (p - p % s).max(s);
        // run rises at `start`; the timer starts in the first cycle from then on with
        // slot S - 2 (slot = cycle mod S), and the next cycle is the first boundary.
        let b0 = (self.start..).find(|c| c % s == s - 2).unwrap() + 1;
        let end = match self.halt {
            Some((_, release)) => release + self.drain,
            None => b0 + self.records.len() as u64 * ps + self.drain,
        };
        let mut core = Core::new(params);
        let mut inputs = CoreInputs { period_clocks: self.p, axes: self.axes, ..CoreInputs::default() };
        let mut trace = Trace {
            s,
            ps,
            b0,
            outputs: vec![core.outputs()],
            reqs: vec![[0; MAX_AXES]],
            pending_at_halt: [0; MAX_AXES],
        };
        let mut next = 0;
        for c in 0..end {
            let halted = self.halt.is_some_and(|(h, _)| c >= h);
            inputs.run = c >= self.start && !halted;
            inputs.halt = self.halt.is_some_and(|(h, release)| c >= h && c < release);
            if self.halt.is_some_and(|(h, _)| c == h) {
                for (a, slot) in trace.pending_at_halt.iter_mut().enumerate() {
                    *slot = core.shaper(a).pending();
                }
            }
            inputs.rec_valid = next < self.records.len() && !halted;
            if inputs.rec_valid {
                inputs.record = self.records[next];
            }
            let ready = core.outputs().rec_ready();
            if inputs.run && !halted {
                let want = c >= b0 && (c - b0) % ps == 0;
                assert_eq!(ready, want, "cycle {c}: rec_ready (b0 {b0}, Ps {ps})");
            }
            if ready && inputs.rec_valid {
                assert_eq!(c, b0 + next as u64 * ps, "record {next} consumed off schedule");
                next += 1;
            }
            core.step(&inputs);
            trace.outputs.push(core.outputs());
            let mut reqs = [0; MAX_AXES];
            for (a, r) in reqs.iter_mut().enumerate().take(self.n) {
                *r = core.dda(a).req();
            }
            trace.reqs.push(reqs);
        }
        if self.halt.is_none() {
            assert_eq!(next, self.records.len(), "every record consumed");
        }
        trace
    }

    fn d(&self, axis: usize) -> Vec<i64> {
        self.records.iter().map(|r| raw(r.inc[axis])).collect()
    }
}

impl Trace {
    fn position(&self, n: u64, axis: usize) -> i64 {
        i64::from(self.outputs[n as usize].position(axis))
    }

    fn len(&self) -> u64 {
        self.outputs.len() as u64
    }

    /// `M = (Ps / S) * 65536`.
    fn m(&self) -> i128 {
        i128::from(self.ps / self.s) << 16
    }

    /// DDA visits of `axis` in cycles `lo < c <= hi`.
    fn visits_between(&self, axis: usize, lo: i128, hi: i128) -> i128 {
        let s = i128::from(self.s);
        let a = axis as i128;
        if hi <= lo {
            return 0;
        }
        (hi - a).div_euclid(s) - (lo - a).div_euclid(s)
    }

    /// `T` after the DDA visits of `axis` in cycles `..= m`: record `k`'s increment at
    /// each visit in `b0 + k Ps < c <= b0 + (k + 1) Ps`.
    fn t(&self, d: &[i64], axis: usize, m: u64) -> i128 {
        let (b0, ps) = (i128::from(self.b0), i128::from(self.ps));
        let m = i128::from(m);
        d.iter()
            .enumerate()
            .map(|(k, &x)| {
                let lo = b0 + k as i128 * ps;
                i128::from(x) * self.visits_between(axis, lo, m.min(lo + ps))
            })
            .sum()
    }
}

/// `floor(sum of D + 1/2)` by exact rational arithmetic.
fn rounded_sum(d: &[i64]) -> i64 {
    let mut sum = BigRational::zero();
    for &x in d {
        sum += BigRational::new(BigInt::from(x), BigInt::from(65536));
    }
    let rounded = (sum + BigRational::new(BigInt::one(), BigInt::from(2))).floor().to_integer();
    i64::try_from(rounded).expect("fits")
}

/// Pins A, B of `axis` with the inversions undone, per cycle.
fn pins(trace: &Trace, drive: &Drive, axis: usize) -> Vec<(bool, bool)> {
    let inv = drive.axes[axis].invert;
    trace.outputs.iter().map(|o| (o.pin_a(axis) ^ (inv & 1 != 0), o.pin_b(axis) ^ (inv & 2 != 0))).collect()
}

/// The cycle from which every axis's pins show its state (each had a shaper visit, in
/// the cycles before `S`).
fn settled(trace: &Trace) -> u64 {
    trace.s
}

/// Pins A and B of `axis` change only in the cycle after one of its shaper visits
/// (`slot == (axis + 1) mod S`); the first violation.
fn first_off_visit_edge(trace: &Trace, axis: usize) -> Option<String> {
    let s = trace.s;
    let mask = (1u64 << (3 * axis)) * 0b11;
    (1..trace.len()).find_map(|c| {
        let changed = (trace.outputs[c as usize].pins ^ trace.outputs[c as usize - 1].pins) & mask != 0;
        (changed && (c - 1) % s != (axis as u64 + 1) % s)
            .then(|| format!("axis {axis}: pins change in cycle {c}, not after a shaper visit"))
    })
}

/// The position decoded from the pins in the axis's mode is `position` in the same
/// cycle (pin edge and `position` both in `n + 2`); the first cycle where it is not.
fn first_pin_mismatch(trace: &Trace, drive: &Drive, axis: usize) -> Option<String> {
    let mode = drive.axes[axis].mode & 3;
    let p = pins(trace, drive, axis);
    let c0 = settled(trace);
    let mut pos = trace.position(c0, axis);
    for c in c0 as usize + 1..p.len() {
        match common::pin_step(mode, p[c - 1], p[c]) {
            Some(step) => pos += step,
            None => return Some(format!("axis {axis}: cycle {c}: quadrature skipped a phase")),
        }
        let want = trace.position(c as u64, axis);
        if pos != want {
            return Some(format!("axis {axis}: cycle {c}: pins say {pos} but position = {want}"));
        }
    }
    None
}

/// The step/dir timing at the pins in multiples of `S`: high exactly `S ceil(L/S)`, low
/// at least `S ceil(Sp/S)`, `dir` changing only while low, at least `S ceil(H/S)` after
/// a fall, a rise at least `S ceil(U/S)` after a `dir` change (the one pin-timing check,
/// [`StepDirMonitor`], against the timing in whole visits). The first violation.
fn first_timing_violation(p: &[(bool, bool)], from: usize, t: &DriveTiming, s: u64) -> Option<String> {
    let q = |x: u32| (s * visits(x, s)) as u32;
    let quantised = DriveTiming::new(q(t.step_len), q(t.step_space), q(t.dir_setup), q(t.dir_hold));
    let f = StepDirMonitor::measure(&p[from.min(p.len())..], from as u64, quantised);
    if let Some(v) = f.first {
        return Some(v.to_string());
    }
    let l = u64::from(quantised.step_len);
    f.high_max.filter(|&high| high != l).map(|high| format!("a pulse high for {high} cycles, want exactly {l}"))
}

/// Property (b) in the engine's form: at every DDA visit `m` of `axis`,
/// `|position(m + 2) - X(m)| <= 1`; and every step moves towards `R(m)`. The first
/// violation.
fn first_lag_violation(trace: &Trace, drive: &Drive, axis: usize) -> Option<String> {
    let d = drive.d(axis);
    let m_mod = trace.m();
    let mut visit = axis as u64;
    while visit + 2 < trace.len() {
        let t = trace.t(&d, axis, visit);
        let pos = i128::from(trace.position(visit + 2, axis));
        if (pos * m_mod - t).abs() > m_mod {
            return Some(format!(
                "axis {axis}: visit {visit}: X = {:.4} but position(m+2) = {pos}",
                t as f64 / m_mod as f64
            ));
        }
        let r = (t + m_mod / 2).div_euclid(m_mod) as i64;
        let (before, after) = (trace.position(visit + 1, axis), trace.position(visit + 2, axis));
        let toward = match after - before {
            0 => true,
            1 => after <= r,
            -1 => after >= r,
            _ => false,
        };
        if !toward {
            return Some(format!("axis {axis}: visit {visit}: position {before} -> {after} with R = {r}"));
        }
        visit += trace.s;
    }
    None
}

/// Property (a): after `k` whole periods the net requests of `axis` (the DDA's `req` after
/// each of its visits) are `floor(sum of the first k D + 1/2)`, for every `k`.
fn first_request_count_violation(trace: &Trace, drive: &Drive, axis: usize) -> Option<String> {
    let d = drive.d(axis);
    let mut net = 0i64;
    let mut k = 0;
    for visit in (axis as u64..trace.len() - 1).step_by(trace.s as usize) {
        // Periods ended before this visit.
        while k < d.len() && trace.b0 + (k as u64 + 1) * trace.ps < visit {
            k += 1;
            let want = rounded_sum(&d[..k]);
            if net != want {
                return Some(format!("axis {axis}: after {k} periods {net} requests, want {want}"));
            }
        }
        net += i64::from(trace.reqs[visit as usize + 1][axis]);
    }
    None
}

/// A random stream within the engine's rated rate.
#[derive(Clone, Debug)]
struct Spec {
    n: usize,
    timing_width: u32,
    p: u32,
    start: u64,
    axes: Vec<(DriveTiming, u8, u8)>,
    quantum: i64,
    choices: Vec<Vec<(u8, u32)>>,
}

fn timing_strategy(max: u32) -> impl Strategy<Value = DriveTiming> {
    let value = prop_oneof![3 => 0..=4u32, 2 => 0..=max.min(12), 1 => 0..=max];
    (value.clone(), value.clone(), value.clone(), value).prop_map(|(l, s, u, h)| timing(l, s, u, h))
}

fn spec_strategy(max_cycles: u32) -> impl Strategy<Value = Spec> {
    let p = prop_oneof![1..=16u32, 2..=64u32, 64..=600u32, 600..=3000u32];
    let widths = prop_oneof![3 => Just(12u32), 1 => Just(4u32)];
    (p, widths, 1..=4usize, 1..=12u64).prop_flat_map(move |(p, tw, n, start)| {
        let max_t = if tw == 4 { 15 } else { 60 };
        let periods = (max_cycles / p).clamp(1, 60) as usize;
        (
            prop::collection::vec((timing_strategy(max_t), 0..4u8, 0..8u8), n),
            prop_oneof![Just(1i64), Just(8192), Just(16384), Just(32768)],
            prop::collection::vec(prop::collection::vec((0..9u8, any::<u32>()), n), 1..=periods),
        )
            .prop_map(move |(axes, quantum, choices)| Spec {
                n,
                timing_width: tw,
                p,
                start,
                axes,
                quantum,
                choices,
            })
    })
}

impl Spec {
    fn s(&self) -> u64 {
        slots_for(self.n)
    }

    /// `Ps`, the period the core runs.
    fn ps(&self) -> u32 {
        let s = self.s() as u32;
        (self.p - self.p % s).max(s)
    }

    /// The timings as the core sees them (masked to `TIMING_W`).
    fn timings(&self) -> Vec<DriveTiming> {
        self.axes.iter().map(|a| a.0.masked(self.timing_width)).collect()
    }

    /// The records, each accepted by the interface's `RateChecker` for the engine
    /// (asserted), whose intervals are first checked against the spec's formulas.
    fn build(&self) -> Vec<PeriodRecord> {
        let s = self.s();
        for t in self.timings() {
            let (fwd, wait) = ideal_intervals(&t, s);
            assert_eq!(forward_interval_in(&t, s as u32), fwd, "{t:?}");
            assert_eq!(reversal_wait_in(&t, s as u32), wait, "{t:?}");
            assert_eq!(reversal_interval_in(&t, s as u32), 2 * wait, "{t:?}");
        }
        let mut checker = RateChecker::for_core(&params(self.n, self.timing_width), self.p, &self.timings());
        let mut records = vec![];
        for period in &self.choices {
            let mut rec = PeriodRecord::default();
            for (i, &(kind, x)) in period.iter().enumerate() {
                let last = checker.last_nonzero_sign(i);
                let random_sign = if x & 1 == 0 { 1 } else { -1 };
                let fraction = |max: i64| max * i64::from(x % 1001) / 1000;
                let quantise = |d: i64| d / self.quantum * self.quantum;
                let at_max = |sign: i8| raw(checker.max_increment(i, sign)) * i64::from(sign);
                let d = match kind {
                    0 => 0,
                    1 => at_max(last),
                    2 => at_max(-last),
                    3 => quantise(fraction(at_max(random_sign))),
                    4 => {
                        let tiny = i64::from(((x >> 1) % 65536) >> ((x >> 20) % 17));
                        tiny.min(at_max(random_sign).abs()) * i64::from(random_sign)
                    }
                    5 => quantise(fraction(at_max(last))),
                    6 => at_max(random_sign),
                    _ => quantise(fraction(at_max(-last))),
                };
                rec.inc[i] = Increment::from_bits(d as i32);
            }
            if let Err((axis, e)) = checker.check(&rec) {
                panic!("generator made an unrated increment on axis {axis}: {e}");
            }
            records.push(rec);
        }
        records
    }

    fn drive(&self, records: Vec<PeriodRecord>, halt: Option<(u64, u64)>) -> Drive {
        let mut axes = [AxisConfig::default(); MAX_AXES];
        for (slot, &(timing, mode, invert)) in axes.iter_mut().zip(&self.axes) {
            *slot = AxisConfig { timing, mode, invert, enable: true };
        }
        let rev = self.timings().iter().map(|t| 2 * ideal_intervals(t, self.s()).1).max().unwrap_or(0);
        Drive {
            n: self.n,
            timing_width: self.timing_width,
            p: self.p,
            start: self.start,
            axes,
            records,
            drain: 2 * u64::from(self.ps()) + 4 * rev + 16 * self.s(),
            halt,
        }
    }
}

/// Every guarantee for a stream within the rated rate.
fn check_rated(drive: &Drive, trace: &Trace) -> Result<(), TestCaseError> {
    prop_assert_eq!(trace.b0 % trace.s, trace.s - 1, "the first boundary has slot S - 1");
    prop_assert_eq!(trace.ps % trace.s, 0);
    for a in 0..drive.n {
        for (n, out) in trace.outputs.iter().enumerate() {
            prop_assert!(!out.rate_error(a), "axis {}: rate_error set in cycle {}", a, n);
            prop_assert!(!out.step_lost(a), "axis {}: step_lost set in cycle {}", a, n);
            prop_assert!(!out.record_error(), "record_error in cycle {}", n);
        }
        let d = drive.d(a);
        let failures = [
            first_lag_violation(trace, drive, a),
            first_request_count_violation(trace, drive, a),
            first_pin_mismatch(trace, drive, a),
            first_off_visit_edge(trace, a),
        ];
        if let Some(v) = failures.into_iter().flatten().next() {
            return Err(TestCaseError::fail(v));
        }
        // (a) at the pins: after the periods and the drain, exactly the rounded sum.
        prop_assert_eq!(trace.position(trace.len() - 1, a), rounded_sum(&d), "axis {}: final", a);
        if drive.axes[a].mode & 1 == drive.axes[a].mode >> 1 & 1 {
            // Step/dir (modes 0 and 3).
            let t = drive.axes[a].timing.masked(drive.timing_width);
            let p = pins(trace, drive, a);
            if let Some(v) = first_timing_violation(&p, settled(trace) as usize, &t, trace.s) {
                return Err(TestCaseError::fail(format!("axis {a}: {v}")));
            }
        }
    }
    Ok(())
}

#[test]
fn rated_streams_follow_the_ideal_within_one_step() {
    let mut runner = finestep_testkit::runner("step_engine_rated_streams_follow_the_ideal", 1500);
    runner
        .run(&spec_strategy(30_000), |spec| {
            let records = spec.build();
            let drive = spec.drive(records, None);
            check_rated(&drive, &drive.run())
        })
        .unwrap();
}

/// Random increments of any size the engine accepts (`|D| < P / S`), short enough that
/// `pending` cannot overflow: the pulses may lag (and `rate_error` may set), but every
/// step comes out at the pins with the drive timing in multiples of `S`, on the
/// axis's visits.
#[test]
fn any_acceptable_stream_keeps_every_step_and_the_timing() {
    let mut runner = finestep_testkit::runner("step_engine_any_acceptable_stream", 600);
    let strategy = (
        1..=4usize,
        timing_strategy(40),
        4..=200u32,
        prop::collection::vec(any::<i32>(), 1..=12),
        0..4u8,
        0..8u8,
        1..=8u64,
    );
    runner
        .run(&strategy, |(n, t, p, xs, mode, invert, start)| {
            let s = slots_for(n);
            let ps = (u64::from(p) - u64::from(p) % s).max(s);
            let m = ((ps / s) << 16) as i64;
            let mut budget = 100 * 65536i64;
            let mut records = vec![];
            for x in xs {
                let d = i64::from(x) % m;
                let d = d.signum() * d.abs().min(budget);
                budget -= d.abs();
                // The last axis moves, the others stay.
                let mut raw_inc = [0i32; MAX_AXES];
                raw_inc[n - 1] = d as i32;
                records.push(PeriodRecord::from_raw(&raw_inc, 0));
            }
            let spec =
                Spec { n, timing_width: 12, p, start, axes: vec![(t, mode, invert); n], quantum: 1, choices: vec![] };
            let mut drive = spec.drive(records, None);
            drive.drain = 110 * 2 * ideal_intervals(&t, s).1 + 2 * ps;
            let trace = drive.run();
            let a = n - 1;
            let last = trace.outputs.last().unwrap();
            prop_assert!(!last.step_lost(a) && !last.record_error());
            prop_assert_eq!(trace.position(trace.len() - 1, a), rounded_sum(&drive.d(a)));
            if let Some(v) = first_request_count_violation(&trace, &drive, a) {
                return Err(TestCaseError::fail(v));
            }
            if let Some(v) = first_pin_mismatch(&trace, &drive, a).or_else(|| first_off_visit_edge(&trace, a)) {
                return Err(TestCaseError::fail(v));
            }
            if mode == 0 || mode == 3 {
                if let Some(v) = first_timing_violation(&pins(&trace, &drive, a), settled(&trace) as usize, &t, s) {
                    return Err(TestCaseError::fail(v));
                }
            }
            Ok(())
        })
        .unwrap();
}

/// `I_fwd = S (L_v + S_v)` is tight: with `P = I_fwd` (a multiple of `S`) one step per
/// period is followed for ever, one raw unit more gains a whole step on the pulse train
/// within 65536 periods and sets `rate_error`. Also with `P` given `S - 1` clocks
/// longer: the core runs the rounded period.
#[test]
fn forward_limit_is_tight() {
    for (n, t) in [(1, timing(1, 1, 1, 1)), (2, timing(3, 2, 4, 5)), (3, timing(5, 1, 1, 1)), (4, timing(7, 12, 1, 1))]
    {
        let s = slots_for(n);
        let (fwd, _) = ideal_intervals(&t, s);
        let p = fwd as u32;
        let max = raw(max_increment_in(&t, p, false, s as u32));
        assert_eq!(max, 65536, "{t:?}");
        for (given, d, behind) in [(p, max, false), (p + s as u32 - 1, max, false), (p, max + 1, true)] {
            let mut core = Core::new(params(n, 12));
            let axis = AxisConfig { timing: t, enable: true, ..AxisConfig::default() };
            let mut inputs = CoreInputs {
                period_clocks: given,
                axes: [axis; MAX_AXES],
                record: PeriodRecord::from_raw(&[d as i32; MAX_AXES], 0),
                ..CoreInputs::default()
            };
            core.step(&inputs);
            inputs.run = true;
            inputs.rec_valid = true;
            for _ in 0..70_000 * u64::from(p) {
                core.step(&inputs);
            }
            assert_eq!(core.timer().p_act(), p, "P = {given} runs as {p}");
            for a in 0..n {
                assert_eq!(core.outputs().rate_error(a), behind, "N {n}, axis {a}, {t:?}, d = {d}");
            }
            assert!(!core.outputs().record_error());
        }
    }
}

/// A request against `dir` right after a rise waits `W = S (L_v + max(S_v, H_v + U_v) - 1)`
/// clocks; `I_rev = 2W` is tight: with `P = I_rev - S` (the largest multiple of `S`
/// below) and the commanded position on a rounding point at the reversal, `D = -1`
/// (just over `P / I_rev`) puts the position more than one step from the ideal at a
/// visit; at the rated maximum it does not.
#[test]
fn reversal_limit_is_tight() {
    for (n, t) in [
        (1, timing(1, 1, 1, 1)),
        (2, timing(3, 2, 4, 5)),
        (3, timing(2, 9, 1, 1)),
        (4, timing(5, 1, 7, 2)),
        (4, timing(4, 4, 4, 4)),
    ] {
        let s = slots_for(n);
        let (_, w) = ideal_intervals(&t, s);
        let p = (2 * w - s) as u32;
        let spec = Spec { n, timing_width: 12, p, start: 1, axes: vec![(t, 0, 0); n], quantum: 1, choices: vec![] };
        let record = |d: i64| PeriodRecord::from_raw(&[d as i32; MAX_AXES], 0);
        let over = vec![record(32768), record(-65536)];
        let mut checker = RateChecker::for_core(&params(n, 12), p, &vec![t; n]);
        assert!(checker.check(&over[0]).is_ok());
        assert!(checker.check(&over[1]).is_err(), "{t:?}: -1 step is over the limit");
        let mut drive = spec.drive(over, None);
        drive.drain = 4 * w;
        let trace = drive.run();
        for a in 0..n {
            assert!(
                first_lag_violation(&trace, &drive, a).is_some(),
                "N {n} axis {a} {t:?}: -1 at P = 2W - S must lag"
            );
        }
        let at_limit = -raw(max_increment_in(&t, p, true, s as u32));
        let mut drive = spec.drive(vec![record(32768), record(at_limit)], None);
        drive.drain = 4 * w;
        let trace = drive.run();
        for a in 0..n {
            assert_eq!(first_lag_violation(&trace, &drive, a), None, "N {n} axis {a} {t:?}");
        }
    }
}

/// A record is acceptable only with `|D| < P / S` on every axis: `P / S` steps (that a
/// per-axis core would take) is refused with `record_error` and gives an idle period;
/// one raw unit less is taken.
#[test]
fn records_need_less_than_one_step_per_visit() {
    for n in 1..=4 {
        let s = slots_for(n);
        let p = 10 * s as u32 + 1;
        let v = 10i64;
        let t = timing(1, 1, 1, 1);
        let spec = Spec { n, timing_width: 12, p, start: 2, axes: vec![(t, 0, 0); n], quantum: 1, choices: vec![] };
        for (d, refused) in [(v << 16, true), (-(v << 16), true), ((v << 16) - 1, false), (-(v << 16) + 1, false)] {
            let mut raw_inc = [0i32; MAX_AXES];
            raw_inc[n - 1] = d as i32;
            let mut drive = spec.drive(vec![PeriodRecord::from_raw(&raw_inc, 0)], None);
            drive.drain = 4 * u64::from(p);
            let trace = drive.run();
            let last = trace.outputs.last().unwrap();
            assert_eq!(last.record_error(), refused, "N {n}, d = {d}");
            let want = if refused { 0 } else { rounded_sum(&[d]) };
            assert_eq!(trace.position(trace.len() - 1, n - 1), want, "N {n}, d = {d}");
            // The error sets in the cycle after the boundary that took the record.
            let first = trace.outputs.iter().position(|o| o.record_error()).map(|c| c as u64);
            assert_eq!(first, refused.then_some(trace.b0 + 1));
        }
    }
}

/// The latency and the look after reset: the first DDA visit of a period wraps (one
/// step per period at two visits per period, acc preset to M / 2), so the step shows
/// in `position` and at pin A two cycles after that visit, the cycle after the shaper
/// visit; pin B shows `dir = 1` from the cycle after the axis's first shaper visit,
/// `pin_en` from cycle 1.
#[test]
fn latency_and_reset() {
    for (n, start) in (1..=4).flat_map(|n| (1..=slots_for(n) + 1).map(move |start| (n, start))) {
        let s = slots_for(n);
        let t = timing(1, 1, 1, 1);
        let mut core = Core::new(params(n, 12));
        let axis = AxisConfig { timing: t, enable: true, ..AxisConfig::default() };
        let mut inputs = CoreInputs { period_clocks: 2 * s as u32, axes: [axis; MAX_AXES], ..CoreInputs::default() };
        inputs.record = PeriodRecord::from_raw(&[65536; MAX_AXES], 0);
        assert_eq!(core.outputs(), CoreOutputs::default(), "every output 0 in reset");
        let mut outputs = vec![core.outputs()];
        for c in 0..40u64 {
            inputs.run = c >= start;
            inputs.rec_valid = c >= start;
            core.step(&inputs);
            outputs.push(core.outputs());
        }
        let b0 = (start..).find(|c| c % s == s - 2).unwrap() + 1;
        assert!(outputs[b0 as usize].rec_ready() && !outputs[b0 as usize - 1].rec_ready());
        for a in 0..n {
            assert!(outputs[1].pin_en(a), "N {n} axis {a}: enable from cycle 1");
            let first_shaper_visit = (a as u64 + 1) % s;
            for (c, o) in outputs.iter().enumerate().take(8) {
                assert_eq!(o.pin_b(a), c as u64 > first_shaper_visit, "N {n} axis {a}: dir pin in cycle {c}");
            }
            // The first visit with the record: cycle b0 + 1 has slot 0.
            let m = b0 + 1 + a as u64;
            let first_step = outputs.iter().position(|o| o.position(a) != 0).unwrap() as u64;
            let first_pin = outputs.iter().position(|o| o.pin_a(a)).unwrap() as u64;
            assert_eq!((first_step, first_pin), (m + 2, m + 2), "N {n} axis {a} start {start}");
        }
    }
}

/// Halt (with `run` dropped, as the top does) in the middle of a rated stream with one
/// axis over the rate (a backlog in `pending`): no rise shown after the halt cycle, a
/// pulse already high lasts its full `S ceil(L / S)`, `dir` holds, the enables drop in
/// the next cycle, and the pending steps are dropped: nothing moves after the release.
/// (`halt` is seen by an axis at its shaper visits only: the halt is held `S` cycles
/// or more here.)
#[test]
fn halt_finishes_the_pulse_and_drops_pending() {
    let mut runner = finestep_testkit::runner("step_engine_halt", 300);
    let strategy = (spec_strategy(6_000), 0..4000u64, 1..=3i64, 1..200u64);
    let with_backlog = std::cell::Cell::new(0);
    runner
        .run(&strategy, |(spec, halt_after, excess, hold)| {
            let mut records = spec.build();
            // The last axis over its forward rate (still acceptable).
            let a = spec.n - 1;
            let s = spec.s();
            let ps = i64::from(spec.ps());
            let (fwd, _) = ideal_intervals(&spec.timings()[a], s);
            let over = ((ps << 16) / fwd as i64 + excess * 65536).min(((ps / s as i64) << 16) - 1);
            for r in &mut records {
                r.inc[a] = Increment::from_bits(over as i32);
            }
            let h = spec.start + 2 + halt_after.min(records.len() as u64 * spec.ps() as u64);
            // The halt lasts at least S cycles (in the top it is a sticky fault): a
            // shorter one may miss an axis's shaper visits, which alone see it.
            let hold = hold + s;
            let drive = spec.drive(records, Some((h, h + hold)));
            let trace = drive.run();
            if trace.pending_at_halt[a] != 0 {
                with_backlog.set(with_backlog.get() + 1);
            }
            let h = h as usize;
            for i in 0..spec.n {
                let p = pins(&trace, &drive, i);
                let t = drive.axes[i].timing.masked(drive.timing_width);
                let l = (s * visits(t.step_len, s)) as usize;
                let inactive = drive.axes[i].invert & 4 != 0;
                for c in h + 1..p.len() {
                    if c <= (h as u64 + hold) as usize {
                        prop_assert_eq!(trace.outputs[c].pin_en(i), inactive, "axis {}: enable in cycle {}", i, c);
                    }
                    if drive.axes[i].mode & 3 != 2 {
                        // A rising pin A (or B in up/down) is a step.
                        let rose = p[c].0 && !p[c - 1].0;
                        prop_assert!(!rose, "axis {}: pin A rose at {}, halt at {}", i, c, h);
                    }
                }
                if drive.axes[i].mode & 1 == drive.axes[i].mode >> 1 & 1 {
                    // Step/dir: dir holds from the cycle after the halt; a high pulse finishes.
                    prop_assert!(p[h + 1..].iter().all(|x| x.1 == p[h].1), "axis {}: dir moved after the halt", i);
                    if let Some(v) = first_timing_violation(&p, settled(&trace) as usize, &t, s) {
                        return Err(TestCaseError::fail(format!("axis {i}: {v}")));
                    }
                    let fall = (h..p.len()).find(|&c| !p[c].0).unwrap();
                    let rise = (0..=h).rev().find(|&c| !p[c].0).map_or(0, |c| c + 1);
                    prop_assert!(
                        fall == h || fall - rise == l,
                        "axis {}: pulse {}..{} over the halt, L = {}",
                        i,
                        rise,
                        fall,
                        l
                    );
                }
                // Nothing moves after the halt cycle (a rise decided at the visit before
                // it counts in the halt cycle), not even after the release: the pending
                // steps are dropped.
                let frozen = trace.position(h as u64, i);
                prop_assert!(
                    (h..trace.outputs.len()).all(|c| trace.position(c as u64, i) == frozen),
                    "axis {}: moved after the halt",
                    i
                );
                let tail = &p[h + l + 2..];
                prop_assert!(tail.iter().all(|x| *x == tail[0]), "axis {}: pins moved after the halt", i);
            }
            Ok(())
        })
        .unwrap();
    let with_backlog = with_backlog.get();
    assert!(with_backlog > 30, "only {with_backlog} cases halted with steps pending");
}

/// A stop of any length, also one shorter than `S` cycles (between two visits of an
/// axis), restarts every accumulator at `M / 2` of the running period: after a period of
/// `D = 0.3` (no step, the accumulator left at `0.8 M`) and a stop, another `0.3` makes
/// no step either (`0.8 + 0.3` would).
#[test]
fn a_stop_of_any_length_restarts_every_accumulator() {
    let d = (0.3f64 * 65536.0) as i32;
    for n in 1..=4 {
        let s = slots_for(n);
        for stop in 1..=2 * s {
            for late in 0..s {
                let axis = AxisConfig { timing: timing(1, 1, 1, 1), enable: true, ..AxisConfig::default() };
                let mut core = Core::new(params(n, 12));
                let mut inputs =
                    CoreInputs { period_clocks: 8 * s as u32, axes: [axis; MAX_AXES], ..CoreInputs::default() };
                inputs.record = PeriodRecord::from_raw(&[d; MAX_AXES], 0);
                core.step(&inputs);
                for _ in 0..2 {
                    inputs.run = true;
                    inputs.rec_valid = true;
                    let mut consumed = false;
                    while !consumed {
                        consumed = core.outputs().rec_ready();
                        core.step(&inputs);
                    }
                    // The period runs out, `late` cycles more, then the stop.
                    inputs.rec_valid = false;
                    for _ in 0..8 * s + late {
                        core.step(&inputs);
                    }
                    inputs.run = false;
                    for _ in 0..stop {
                        core.step(&inputs);
                    }
                }
                for a in 0..n {
                    assert_eq!(core.outputs().position(a), 0, "N {n}, stop {stop}, late {late}: axis {a}");
                }
            }
        }
    }
}

/// `clear_errors` clears `rate_error` and `step_lost` in any cycle, not only at the
/// axis's visits, and a set at a shaper visit wins: while the pulse train is behind
/// (`|pending + r| >= 2` at every visit) with `clear_errors` held, `rate_error` shows
/// exactly in the cycles after the axis's shaper visits.
#[test]
fn flags_clear_in_any_cycle_and_a_set_at_a_visit_wins() {
    let n = 3;
    let s = slots_for(n);
    let axis = AxisConfig { timing: timing(1000, 1000, 1, 1), enable: true, ..AxisConfig::default() };
    let mut core = Core::new(params(n, 12));
    // P = 100 000: 1000 steps per period on axis 1, 50 rated; the backlog overflows.
    let mut inputs = CoreInputs { period_clocks: 100_000, axes: [axis; MAX_AXES], ..CoreInputs::default() };
    inputs.record = PeriodRecord::from_raw(&[0, 1000 << 16, 0], 0);
    let mut events = vec![];
    core.run_chunk_fast(&inputs, 2 * s, &mut events);
    inputs.run = true;
    inputs.rec_valid = true;
    for _ in 0..2 {
        assert!(core.run_chunk_fast(&inputs, 1_000_000, &mut events).consumed);
    }
    core.run_chunk_fast(&inputs, 50_000, &mut events);
    inputs.rec_valid = false;
    let out = core.outputs();
    assert!(out.rate_error(1) && out.step_lost(1) && !out.rate_error(0));
    // Behind: with clear_errors held, set after each shaper visit of axis 1 (slot 2),
    // cleared after every other cycle.
    inputs.clear_errors = true;
    for _ in 0..3 * s {
        let visit = u64::from(core.engine().unwrap().slot()) == 2;
        core.step(&inputs);
        assert_eq!(core.outputs().rate_error(1), visit, "cycle {}", core.cycle());
        assert!(!core.outputs().step_lost(1), "cycle {}: step_lost cleared", core.cycle());
    }
    // Drain the backlog: no set any more; then one cycle of clear_errors at each slot.
    inputs.clear_errors = false;
    core.run_chunk_fast(&inputs, 600_000, &mut events);
    assert_eq!(core.shaper(1).pending(), 0);
    for slot in 0..s {
        // Set the flag again: one period of 60 steps, 10 over the rate.
        inputs.rec_valid = true;
        inputs.record = PeriodRecord::from_raw(&[0, 60 << 16, 0], 0);
        while !core.run_chunk_fast(&inputs, u64::MAX, &mut events).consumed {}
        inputs.rec_valid = false;
        core.run_chunk_fast(&inputs, 150_000, &mut events);
        assert!(core.outputs().rate_error(1) && core.shaper(1).pending() == 0);
        while u64::from(core.engine().unwrap().slot()) != slot {
            core.step(&inputs);
        }
        inputs.clear_errors = true;
        core.step(&inputs);
        inputs.clear_errors = false;
        assert!(!core.outputs().rate_error(1), "cleared by clear_errors in a cycle with slot {slot}");
    }
}

/// With the engine no gantry block is built, whatever `HAS_GANTRY` says: its inputs are
/// ignored (an engaged pair with a large error makes no correction) and its outputs
/// read 0, every output as without it.
#[test]
fn no_gantry_with_the_engine() {
    let mut with = Core::new(CoreParams { has_gantry: true, ..params(4, 12) });
    let mut without = Core::new(params(4, 12));
    let axis = AxisConfig { timing: timing(2, 2, 1, 1), enable: true, ..AxisConfig::default() };
    let mut inputs = CoreInputs { period_clocks: 64, axes: [axis; MAX_AXES], ..CoreInputs::default() };
    inputs.record = PeriodRecord::from_raw(&[3 << 16, -(2 << 16), 1 << 15, 0], 0);
    inputs.gantry = finestep_model::GantryInputs {
        enable: true,
        sync: true,
        master: 0,
        slave: 3,
        tick: 5,
        deadband: 1,
        limit: 10,
        enc_master: 1000,
        ..Default::default()
    };
    for c in 0..2000 {
        inputs.run = c >= 1;
        inputs.rec_valid = (1..1000).contains(&c);
        with.step(&inputs);
        without.step(&inputs);
        assert_eq!(with.outputs(), without.outputs(), "cycle {c}");
    }
    let out = with.outputs();
    assert_eq!((out.gantry_error, out.gantry_corrections, out.gantry_flags), (0, 0, 0));
    assert_eq!(out.position(3), 0, "no correction reached the slave");
    assert_ne!(out.position(0), 0);
}

/// (c) in visits: a constant increment gives step intervals of `floor(M / |d|)` or
/// `ceil(M / |d|)` visits, `S` clocks each (`M = (P / S) * 65536`), the first step of a
/// reversal excepted.
#[test]
fn constant_increment_gives_even_step_intervals() {
    let mut runner = finestep_testkit::runner("step_engine_constant_increment_even_intervals", 500);
    let strategy = (
        1..=4usize,
        timing_strategy(40),
        prop_oneof![2..=64u32, 64..=2000u32],
        100..=1000i64,
        any::<bool>(),
        2..=20usize,
    );
    runner
        .run(&strategy, |(n, t, p, per_mille, negative, periods)| {
            let s = slots_for(n);
            let ps = (u64::from(p) - u64::from(p) % s).max(s);
            let checker = RateChecker::with_slots(ps as u32, &[t], s as u32);
            let sign = if negative { -1 } else { 1 };
            let d = raw(checker.max_increment(0, sign)) * per_mille / 1000 * i64::from(sign);
            prop_assume!(d != 0);
            let periods = periods.max((5 * 65536 / d.abs() + 1) as usize);
            let mut raw_inc = [0i32; MAX_AXES];
            raw_inc[n - 1] = d as i32;
            let records = vec![PeriodRecord::from_raw(&raw_inc, 0); periods];
            let spec = Spec { n, timing_width: 12, p, start: 1, axes: vec![(t, 0, 0); n], quantum: 1, choices: vec![] };
            let mut drive = spec.drive(records, None);
            drive.drain = 0;
            let trace = drive.run();
            let a = n - 1;
            let changes: Vec<u64> =
                (1..trace.len()).filter(|&c| trace.position(c, a) != trace.position(c - 1, a)).collect();
            let intervals: Vec<u64> = changes.windows(2).map(|w| w[1] - w[0]).skip(usize::from(negative)).collect();
            prop_assert!(intervals.len() >= 2, "steps at {:?}", changes);
            let m = ((ps / s) << 16) as i64;
            let lo = s * (m / d.abs()) as u64;
            let hi = s * ((m + d.abs() - 1) / d.abs()) as u64;
            for &x in &intervals {
                prop_assert!(lo <= x && x <= hi, "interval {} outside [{}, {}]: {:?}", x, lo, hi, intervals);
            }
            Ok(())
        })
        .unwrap();
}

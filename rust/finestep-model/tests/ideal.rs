//! The spec's guarantees checked against an independent ideal (exact arithmetic on the
//! increments alone), for random streams within the rated maximum of
//! `finestep_model::limits`, and directed streams showing the limits are tight.

mod common;

use common::{first_timing_violation, Run};
use finestep_model::limits::{forward_interval, max_increment, reversal_interval, reversal_wait};
use finestep_model::{AxisConfig, CoreInputs, CoreParams, DriveTiming, Increment, PeriodRecord, RateChecker, MAX_AXES};
use proptest::prelude::*;

fn axis(timing: DriveTiming, mode: u8, invert: u8) -> AxisConfig {
    AxisConfig { timing, mode, invert, enable: true }
}

fn timing(l: u32, s: u32, u: u32, h: u32) -> DriveTiming {
    DriveTiming::new(l, s, u, h)
}

fn raw(x: Increment) -> i64 {
    i64::from(x.to_bits())
}

fn inc(d: i64) -> Increment {
    Increment::from_bits(i32::try_from(d).expect("increment fits I16F16"))
}

/// A random rated stream: the axes, the period, and per period and axis a choice that
/// `build` turns into an increment the [`RateChecker`] accepts.
#[derive(Clone, Debug)]
struct Spec {
    timing_width: u32,
    p: u32,
    axes: Vec<(DriveTiming, u8, u8)>,
    /// Increments of the "fraction" kinds are rounded towards 0 to a multiple of this
    /// (1/8, 1/4, 1/2 step), so the commanded position often lands exactly on a
    /// rounding point.
    quantum: i64,
    choices: Vec<Vec<(u8, u32)>>,
}

fn timing_strategy(max: u32) -> impl Strategy<Value = DriveTiming> {
    let value = prop_oneof![3 => 0..=4u32, 2 => 0..=max.min(12), 1 => 0..=max];
    (value.clone(), value.clone(), value.clone(), value).prop_map(|(l, s, u, h)| timing(l, s, u, h))
}

fn spec_strategy(max_cycles: u32) -> impl Strategy<Value = Spec> {
    let p = prop_oneof![1..=8u32, 2..=64u32, 64..=600u32, 600..=3000u32];
    let widths = prop_oneof![3 => Just(12u32), 1 => Just(4u32)];
    (p, widths, 1..=4usize).prop_flat_map(move |(p, tw, n)| {
        let max_t = if tw == 4 { 15 } else { 60 };
        let periods = (max_cycles / p).clamp(1, 80) as usize;
        (
            Just(p),
            Just(tw),
            prop::collection::vec((timing_strategy(max_t), 0..4u8, 0..8u8), n),
            prop_oneof![Just(1i64), Just(8192), Just(16384), Just(32768)],
            prop::collection::vec(prop::collection::vec((0..9u8, any::<u32>()), n), 1..=periods),
        )
            .prop_map(|(p, timing_width, axes, quantum, choices)| Spec {
                timing_width,
                p,
                axes,
                quantum,
                choices,
            })
    })
}

impl Spec {
    fn timings(&self) -> Vec<DriveTiming> {
        self.axes.iter().map(|a| a.0).collect()
    }

    /// The records, each accepted by a `RateChecker` (asserted).
    fn build(&self) -> Vec<PeriodRecord> {
        let mut checker = RateChecker::new(self.p, &self.timings());
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
                rec.inc[i] = inc(d);
            }
            if let Err((axis, e)) = checker.check(&rec) {
                panic!("generator made an unrated increment on axis {axis}: {e}");
            }
            records.push(rec);
        }
        records
    }

    fn run(&self, records: Vec<PeriodRecord>, drain: u64) -> Run {
        let params = CoreParams {
            n_axes: self.axes.len(),
            p_width: 20,
            timing_width: self.timing_width,
            ..CoreParams::default()
        };
        let mut axes = [AxisConfig::default(); MAX_AXES];
        for (slot, &(t, mode, invert)) in axes.iter_mut().zip(&self.axes) {
            *slot = axis(t, mode, invert);
        }
        Run::drive(params, axes, self.p, records, drain)
    }

    fn drain(&self) -> u64 {
        let rev = self.timings().iter().map(reversal_interval).max().unwrap_or(0);
        2 * u64::from(self.p) + 4 * rev + 16
    }
}

/// Checks every guarantee for a stream within the rated maximum.
fn check_rated(spec: &Spec, run: &Run) -> Result<(), TestCaseError> {
    for i in 0..spec.axes.len() {
        let ideal = run.ideal(i);
        // (b) and no flag ever.
        for (n, out) in run.outputs.iter().enumerate() {
            prop_assert!(!out.rate_error(i), "axis {i}: rate_error set in cycle {n}");
            prop_assert!(!out.step_lost(i), "axis {i}: step_lost set in cycle {n}");
            prop_assert!(!out.record_error(), "record_error in cycle {n}");
        }
        if let Some(v) = run.first_lag_violation(i) {
            return Err(TestCaseError::fail(v));
        }
        // (d): steps only towards the request, never overshooting, never lost.
        if let Some(v) = run.first_overshoot(i) {
            return Err(TestCaseError::fail(v));
        }
        // (a): after the periods and the drain, exactly the rounded sum.
        prop_assert_eq!(run.final_position(i), ideal.final_steps(), "axis {}: final", i);
        // The pins say what the position says, one cycle later, in every mode.
        if let Some(v) = run.first_pin_mismatch(i) {
            return Err(TestCaseError::fail(v));
        }
        if spec.axes[i].1 & 3 == 0 || spec.axes[i].1 & 3 == 3 {
            if let Some(v) = first_timing_violation(&run.pins(i), &spec.axes[i].0) {
                return Err(TestCaseError::fail(format!("axis {i}: {v}")));
            }
        }
    }
    Ok(())
}

#[test]
fn rated_streams_follow_the_ideal_within_one_step() {
    let mut runner = finestep_testkit::runner("rated_streams_follow_the_ideal_within_one_step", 3000);
    runner
        .run(&spec_strategy(40_000), |spec| {
            let records = spec.build();
            let run = spec.run(records, spec.drain());
            check_rated(&spec, &run)
        })
        .unwrap();
}

/// (c) A constant increment gives step intervals of `floor(M/|d|)` or `ceil(M/|d|)`
/// clocks, so any two differ by at most 1 (the first step of a reversal excepted).
#[test]
fn constant_increment_gives_even_step_intervals() {
    let mut runner = finestep_testkit::runner("constant_increment_gives_even_step_intervals", 1000);
    let strategy =
        (timing_strategy(40), prop_oneof![2..=64u32, 64..=2000u32], 100..=1000i64, any::<bool>(), 2..=20usize);
    runner
        .run(&strategy, |(t, p, per_mille, negative, periods)| {
            let checker = RateChecker::new(p, &[t]);
            let sign = if negative { -1 } else { 1 };
            let d = raw(checker.max_increment(0, sign)) * per_mille / 1000 * i64::from(sign);
            prop_assert!(d != 0);
            // At least 5 steps: enough periods for 4 intervals.
            let periods = periods.max((5 * 65536 / d.abs() + 1) as usize);
            let records = vec![PeriodRecord::from_raw(&[d as i32], 0); periods];
            let spec = Spec { timing_width: 12, p, axes: vec![(t, 0, 0)], quantum: 1, choices: vec![] };
            let run = spec.run(records, 0);
            let changes: Vec<usize> =
                (1..run.outputs.len()).filter(|&n| run.position(n, 0) != run.position(n - 1, 0)).collect();
            let intervals: Vec<usize> = changes.windows(2).map(|w| w[1] - w[0]).skip(usize::from(negative)).collect();
            prop_assert!(intervals.len() >= 2, "steps at {:?}", changes);
            let m = i64::from(p) << 16;
            let lo = (m / d.abs()) as usize;
            let hi = ((m + d.abs() - 1) / d.abs()) as usize;
            for &x in &intervals {
                prop_assert!(lo <= x && x <= hi, "interval {} outside [{}, {}]: {:?}", x, lo, hi, intervals);
            }
            Ok(())
        })
        .unwrap();
}

/// Over the rated maximum (but acceptable): `rate_error` sets, yet every step is still
/// output (no `step_lost` while the backlog stays below 127).
#[test]
fn over_rate_sets_rate_error_and_keeps_every_step() {
    let mut runner = finestep_testkit::runner("over_rate_sets_rate_error_and_keeps_every_step", 1000);
    let strategy = (timing_strategy(20), 4..=40u32, 1..=3i64, 5..=12usize, 0..4u8);
    runner
        .run(&strategy, |(t, scale, excess, periods, mode)| {
            let p = scale * forward_interval(&t) as u32;
            let rated = raw(max_increment(&t, p, false));
            let d = rated + excess * 65536;
            // Acceptable (under one step per clock), and a backlog well under 127 steps.
            prop_assert!(d < i64::from(p) << 16);
            prop_assert!(excess * periods as i64 <= 100);
            let records = vec![PeriodRecord::from_raw(&[d as i32], 0); periods];
            let spec = Spec { timing_width: 12, p, axes: vec![(t, mode, 0)], quantum: 1, choices: vec![] };
            let run = spec.run(records, 130 * reversal_interval(&t) + 2 * u64::from(p));
            let last = run.outputs.last().unwrap();
            prop_assert!(last.rate_error(0), "rate_error must set");
            prop_assert!(!last.step_lost(0));
            prop_assert_eq!(run.final_position(0), run.ideal(0).final_steps());
            if mode == 0 || mode == 3 {
                if let Some(v) = first_timing_violation(&run.pins(0), &t) {
                    return Err(TestCaseError::fail(v));
                }
            }
            Ok(())
        })
        .unwrap();
}

/// Random increments of either sign and any size below one step per clock, short
/// enough that `pending` cannot overflow: the pulses may lag, but every step comes out,
/// with the drive timing, and the pins agree with the position.
#[test]
fn any_acceptable_stream_keeps_every_step_and_the_timing() {
    let mut runner = finestep_testkit::runner("any_acceptable_stream_keeps_every_step_and_the_timing", 1000);
    let strategy = (
        timing_strategy(40),
        prop_oneof![Just(12u32), Just(4u32)],
        2..=200u32,
        prop::collection::vec(any::<i32>(), 1..=12),
        0..4u8,
        0..8u8,
    );
    runner
        .run(&strategy, |(t, timing_width, p, xs, mode, invert)| {
            // With TIMING_W = 4 the core masks the settings (16 becomes 0, acting as 1).
            let masked = t.masked(timing_width);
            let m = i64::from(p) << 16;
            let mut budget = 100 * 65536i64;
            let mut records = vec![];
            for x in xs {
                let d = i64::from(x) % m;
                let d = d.signum() * d.abs().min(budget);
                budget -= d.abs();
                records.push(PeriodRecord::from_raw(&[d as i32], 0));
            }
            let spec = Spec { timing_width, p, axes: vec![(t, mode, invert)], quantum: 1, choices: vec![] };
            let run = spec.run(records, 110 * reversal_interval(&masked) + 2 * u64::from(p));
            prop_assert!(!run.outputs.last().unwrap().step_lost(0));
            prop_assert_eq!(run.final_position(0), run.ideal(0).final_steps());
            if let Some(v) = run.first_overshoot(0) {
                return Err(TestCaseError::fail(v));
            }
            if let Some(v) = run.first_pin_mismatch(0) {
                return Err(TestCaseError::fail(v));
            }
            if mode == 0 || mode == 3 {
                if let Some(v) = first_timing_violation(&run.pins(0), &masked) {
                    return Err(TestCaseError::fail(v));
                }
            }
            Ok(())
        })
        .unwrap();
}

/// (a) over many periods: no drift, with fractional increments that never sum to a
/// whole number of steps until the end.
#[test]
fn no_drift_over_many_periods() {
    let t = timing(1, 1, 1, 1);
    for (p, d, periods) in [(3u32, 21845i32, 3000usize), (7, -1, 5000), (1000, 123_457, 400)] {
        let records = vec![PeriodRecord::from_raw(&[d], 0); periods];
        let spec = Spec { timing_width: 12, p, axes: vec![(t, 0, 0)], quantum: 1, choices: vec![] };
        let run = spec.run(records, 2 * u64::from(p) + 16);
        assert_eq!(run.final_position(0), run.ideal(0).final_steps(), "P {p}, d {d}");
        assert!(run.first_lag_violation(0).is_none());
    }
}

/// (d) Sign changes at the rated maxima: every step in the right direction, none lost
/// or added, pins and position agree.
#[test]
fn sign_changes_at_the_rated_maximum() {
    let t = timing(3, 2, 4, 5);
    let p = 4 * reversal_interval(&t) as u32;
    let mut checker = RateChecker::new(p, &[t]);
    let mut records = vec![];
    for sign in [1i8, 1, 1, -1, -1, -1, -1, 1, -1, 1, 1, 1] {
        let d = i64::from(sign) * raw(checker.max_increment(0, sign));
        let rec = PeriodRecord::from_raw(&[d as i32], 0);
        checker.check(&rec).unwrap();
        records.push(rec);
    }
    let spec = Spec { timing_width: 12, p, axes: vec![(t, 0, 0)], quantum: 1, choices: vec![] };
    let run = spec.run(records, 2 * u64::from(p));
    check_rated(&spec, &run).unwrap();
}

/// A request against `dir` that comes right after a rise waits
/// `W = L + max(S, H + U) - 1` clocks; `I_rev = 2W` is tight: with `P = 2W - 1` and the
/// commanded position on a rounding point at the reversal, `D = -1` (just over
/// `P / I_rev`) puts the position more than one step from the ideal.
#[test]
fn reversal_limit_is_tight() {
    for t in [timing(1, 1, 1, 1), timing(3, 2, 4, 5), timing(2, 9, 1, 1), timing(5, 1, 7, 2)] {
        let w = reversal_wait(&t);
        let p = (2 * w - 1) as u32;
        let spec = Spec { timing_width: 12, p, axes: vec![(t, 0, 0)], quantum: 1, choices: vec![] };
        let over = vec![PeriodRecord::from_raw(&[32768], 0), PeriodRecord::from_raw(&[-65536], 0)];
        let mut checker = RateChecker::new(p, &[t]);
        assert!(checker.check(&over[0]).is_ok());
        assert!(checker.check(&over[1]).is_err(), "{t:?}: -1 step is over the limit");
        let run = spec.run(over, 4 * w);
        assert!(run.first_lag_violation(0).is_some(), "{t:?}: -1 at P = 2W - 1 must lag");
        let at_limit = -raw(max_increment(&t, p, true));
        let within = vec![PeriodRecord::from_raw(&[32768], 0), PeriodRecord::from_raw(&[at_limit as i32], 0)];
        let run = spec.run(within, 4 * w);
        assert_eq!(run.first_lag_violation(0), None, "{t:?}");
    }
}

/// `I_fwd = L + S` is tight: with `P = I_fwd`, a constant increment of one step per
/// period (the maximum) is followed forever, one raw unit more (1/65536 step) gains a
/// whole step on the pulse train within 65536 periods and sets `rate_error`.
#[test]
fn forward_limit_is_tight() {
    for t in [timing(1, 1, 1, 1), timing(3, 2, 4, 5), timing(7, 12, 1, 1)] {
        let p = forward_interval(&t) as u32;
        let max = raw(max_increment(&t, p, false));
        assert_eq!(max, 65536);
        for (d, behind) in [(max, false), (max + 1, true)] {
            let mut core = finestep_model::Core::new(CoreParams::default());
            let mut inputs = CoreInputs {
                period_clocks: p,
                axes: [axis(t, 0, 0); MAX_AXES],
                record: PeriodRecord::from_raw(&[d as i32], 0),
                ..CoreInputs::default()
            };
            core.step(&inputs);
            inputs.run = true;
            inputs.rec_valid = true;
            for _ in 0..(70_000 * u64::from(p)) {
                core.step(&inputs);
            }
            assert_eq!(core.outputs().rate_error(0), behind, "{t:?}, d = {d}");
        }
    }
}

/// The reversal limit must also cover the increments after the sign change until the
/// axis has travelled 2 steps the new way: here the sign change itself is tiny
/// (-0.25), leaving the commanded position on the rounding point, and the first step
/// against `dir` is requested in the next period, at the forward maximum. It waits `U`
/// clocks for the direction setup while the ideal runs several steps ahead.
#[test]
fn reversal_limit_covers_the_first_two_steps() {
    let t = timing(1, 1, 10, 1);
    let p = 100;
    let records: Vec<PeriodRecord> =
        [0.75f64, -0.25, -50.0, -50.0].iter().map(|&x| PeriodRecord::from_raw(&[(x * 65536.0) as i32], 0)).collect();
    // The third increment is within the forward limit and has the sign of the one before.
    assert!(finestep_model::limits::check_increment(&t, p, -1, records[2].inc[0]).is_ok());
    let mut checker = RateChecker::new(p, &[t]);
    assert!(checker.check(&records[0]).is_ok());
    assert!(checker.check(&records[1]).is_ok());
    assert!(checker.check(&records[2]).is_err(), "still reversing: 0.25 of 2 steps");
    let spec = Spec { timing_width: 12, p, axes: vec![(t, 0, 0)], quantum: 1, choices: vec![] };
    let run = spec.run(records, 200);
    assert!(run.first_lag_violation(0).is_some());
    assert!(run.outputs.iter().any(|o| o.rate_error(0)));
    assert_eq!(run.final_position(0), run.ideal(0).final_steps());
}

/// The idle core as the harness sees it: enables and dir only, for any inputs.
#[test]
fn unused_axes_stay_zero() {
    let params = CoreParams { n_axes: 3, ..CoreParams::default() };
    let mut core = finestep_model::Core::new(params);
    let mut inputs = CoreInputs { run: true, period_clocks: 5, rec_valid: true, ..CoreInputs::default() };
    inputs.record = PeriodRecord::from_raw(&[1 << 16; 8], 1);
    for a in &mut inputs.axes {
        a.enable = true;
        a.invert = 7;
    }
    for _ in 0..100 {
        core.step(&inputs);
        let out = core.outputs();
        let used = 0x1FF | (0b111 << 24) | (0b111 << 32) | (0b111 << 40) | (1 << finestep_model::pins::PERIOD_BOUNDARY);
        assert_eq!(out.pins & !used, 0);
        assert_eq!(out.positions[3..], [0; 5]);
    }
}

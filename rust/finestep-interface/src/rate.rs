//! The rated rate (docs/spec/rated_rate.md): the increments within which `rate_error`
//! never sets and the output position stays within one step of the ideal one.
//!
//! For an axis with timing `L, S, U, H` (each taken as at least 1):
//! - `I_fwd = L + S` clocks, the shortest step interval the pulse train follows;
//! - a request against `dir` waits at most `W = L + max(S, H + U) - 1` clocks before its
//!   rising edge is decided, and `I_rev = 2 * W` clocks is the shortest step interval
//!   allowed while the axis is *reversing*.
//!
//! An increment `D` is within the rated maximum when `|D| * I_fwd <= P` and, while the
//! axis is reversing, `|D| * I_rev <= P`. The axis is reversing from a non-zero
//! increment whose sign differs from the last non-zero one until the increments of the
//! new sign add up to at least 2 steps (the period that reaches 2 steps included). After
//! reset the axis counts as settled in the positive direction (`dir` resets to 1).
//!
//! # With the shared step engine
//!
//! A core built with `STEP_SHARED = 1` serves each axis once every `S = 2^SL` clocks
//! ([`CoreParams::step_slots`](crate::CoreParams::step_slots)); its pulse train is the
//! one above in visits, with each timing rounded up to whole visits,
//! `L_v = max(ceil(L / S), 1)` and likewise `S_v`, `U_v`, `H_v`:
//! `I_fwd = S * (L_v + S_v)` and `I_rev = 2 * S * (L_v + max(S_v, H_v + U_v) - 1)` clocks,
//! with the same conditions and `P` the period the core runs (a multiple of `S`,
//! [`CoreParams::effective_period`](crate::CoreParams::effective_period)). The `*_in`
//! functions and [`RateChecker::with_slots`] take `S` (`slots`, 0 acting as 1); `S = 1`
//! is a DDA and a shaper per axis, what the functions without `slots` state.

use crate::{CoreParams, DriveTiming, Increment, PeriodRecord, MAX_AXES};

/// A timing value in whole visits of `slots` clocks: `max(ceil(x / slots), 1)`.
fn visits(x: u32, slots: u32) -> u64 {
    u64::from(x.div_ceil(slots.max(1)).max(1))
}

/// `I_fwd = L + S` clocks: the shortest step interval the pulse train can follow
/// (a DDA and a shaper per axis: [`forward_interval_in`] with one slot).
pub fn forward_interval(t: &DriveTiming) -> u64 {
    forward_interval_in(t, 1)
}

/// `I_fwd = S * (L_v + S_v)` clocks for an engine visiting each axis every `slots`
/// clocks (0 acts as 1).
pub fn forward_interval_in(t: &DriveTiming, slots: u32) -> u64 {
    u64::from(slots.max(1)) * (visits(t.step_len, slots) + visits(t.step_space, slots))
}

/// `W = L + max(S, H + U) - 1` clocks: the longest a step request against the current
/// direction waits before its rising edge is decided (when it comes right after a rise).
pub fn reversal_wait(t: &DriveTiming) -> u64 {
    reversal_wait_in(t, 1)
}

/// `W = S * (L_v + max(S_v, H_v + U_v) - 1)` clocks for an engine visiting each axis
/// every `slots` clocks (0 acts as 1): [`reversal_wait`] in visits.
pub fn reversal_wait_in(t: &DriveTiming, slots: u32) -> u64 {
    let hold_setup = visits(t.dir_hold, slots) + visits(t.dir_setup, slots);
    u64::from(slots.max(1)) * (visits(t.step_len, slots) + visits(t.step_space, slots).max(hold_setup) - 1)
}

/// `I_rev = 2 * (L + max(S, H + U) - 1)` clocks: the shortest step interval allowed
/// while the axis is reversing. Never below [`forward_interval`].
pub fn reversal_interval(t: &DriveTiming) -> u64 {
    reversal_interval_in(t, 1)
}

/// `I_rev = 2 * S * (L_v + max(S_v, H_v + U_v) - 1)` clocks for an engine visiting each
/// axis every `slots` clocks (0 acts as 1). Never below [`forward_interval_in`].
pub fn reversal_interval_in(t: &DriveTiming, slots: u32) -> u64 {
    2 * reversal_wait_in(t, slots)
}

/// The largest increment (raw value `floor(65536 * P / I)`, at most [`Increment::MAX`])
/// within the rated maximum for a period of `period_clocks` (0 acts as 1), with
/// `I = I_rev` if `reversing`, else `I_fwd`. Its negation is the most negative one.
pub fn max_increment(t: &DriveTiming, period_clocks: u32, reversing: bool) -> Increment {
    max_increment_in(t, period_clocks, reversing, 1)
}

/// [`max_increment`] for an engine visiting each axis every `slots` clocks (0 acts as
/// 1); `period_clocks` is the period the core runs (a multiple of `slots`).
pub fn max_increment_in(t: &DriveTiming, period_clocks: u32, reversing: bool, slots: u32) -> Increment {
    let interval = if reversing { reversal_interval_in(t, slots) } else { forward_interval_in(t, slots) };
    max_raw(period_clocks, interval)
}

fn max_raw(period_clocks: u32, interval: u64) -> Increment {
    let raw = (u64::from(period_clocks.max(1)) << 16) / interval;
    Increment::from_bits(raw.min(i32::MAX as u64) as i32)
}

/// Which rated limit an increment exceeds, with the numbers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum RateError {
    /// `|D| * I_fwd > P`.
    #[error(
        "increment {increment} steps/period exceeds the forward rated maximum {max} \
         (|D| * I_fwd <= P with I_fwd = {interval} clocks, P = {period_clocks} clocks)"
    )]
    Forward {
        /// The increment refused.
        increment: Increment,
        /// The largest magnitude allowed.
        max: Increment,
        /// `I_fwd` in clocks.
        interval: u64,
        /// `P` in clocks.
        period_clocks: u32,
    },
    /// `|D| * I_rev > P` while reversing.
    #[error(
        "increment {increment} steps/period while reversing exceeds the reversal rated \
         maximum {max} (|D| * I_rev <= P with I_rev = {interval} clocks, P = {period_clocks} clocks)"
    )]
    Reversal {
        /// The increment refused.
        increment: Increment,
        /// The largest magnitude allowed.
        max: Increment,
        /// `I_rev` in clocks.
        interval: u64,
        /// `P` in clocks.
        period_clocks: u32,
    },
}

/// Checks one increment `d` against the rated maximum for a period of `period_clocks`
/// (0 acts as 1).
///
/// `last_nonzero_sign` is the sign (+1 or -1) of the last non-zero increment of the axis
/// once its reversal is complete (see the module docs), or 0 while it is not (or nothing
/// is known): the reversal limit applies when `d` is non-zero and its sign differs from
/// `last_nonzero_sign`. [`RateChecker`] tracks this over a stream of records.
pub fn check_increment(
    t: &DriveTiming,
    period_clocks: u32,
    last_nonzero_sign: i8,
    d: Increment,
) -> Result<(), RateError> {
    check_increment_in(t, period_clocks, last_nonzero_sign, d, 1)
}

/// [`check_increment`] for an engine visiting each axis every `slots` clocks (0 acts as
/// 1); `period_clocks` is the period the core runs (a multiple of `slots`).
pub fn check_increment_in(
    t: &DriveTiming,
    period_clocks: u32,
    last_nonzero_sign: i8,
    d: Increment,
    slots: u32,
) -> Result<(), RateError> {
    let magnitude = u64::from(d.to_bits().unsigned_abs());
    let p = u64::from(period_clocks.max(1));
    let forward = forward_interval_in(t, slots);
    if magnitude * forward > p << 16 {
        return Err(RateError::Forward {
            increment: d,
            max: max_raw(period_clocks, forward),
            interval: forward,
            period_clocks,
        });
    }
    let reversing = magnitude != 0 && sign(d) != last_nonzero_sign;
    let reversal = reversal_interval_in(t, slots);
    if reversing && magnitude * reversal > p << 16 {
        return Err(RateError::Reversal {
            increment: d,
            max: max_raw(period_clocks, reversal),
            interval: reversal,
            period_clocks,
        });
    }
    Ok(())
}

fn sign(d: Increment) -> i8 {
    d.to_bits().signum() as i8
}

/// Two steps, raw: the travel that completes a reversal.
const REVERSAL_TRAVEL: u64 = 2 << 16;

/// Direction state of one axis, see the module docs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Direction {
    /// Sign of the last non-zero increment.
    last: i8,
    /// Raw travel in the direction `last` since it last changed, up to 2 steps.
    travel: u64,
}

impl Direction {
    fn settled_sign(&self) -> i8 {
        if self.travel >= REVERSAL_TRAVEL {
            self.last
        } else {
            0
        }
    }

    fn apply(&mut self, d: Increment) {
        let s = sign(d);
        let magnitude = u64::from(d.to_bits().unsigned_abs());
        if s == 0 {
            return;
        }
        if s != self.last {
            self.last = s;
            self.travel = 0;
        }
        self.travel = (self.travel + magnitude).min(REVERSAL_TRAVEL);
    }
}

/// Checks a stream of records against the rated maximum, tracking each axis's
/// direction (the last non-zero sign and whether its reversal is complete). It mirrors
/// one core from reset, whose records are all applied in order.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RateChecker {
    period_clocks: u32,
    /// `S`: the clocks between two visits of an axis (1: a DDA and a shaper per axis).
    slots: u32,
    timings: Vec<DriveTiming>,
    /// Per axis `I_fwd` and `I_rev` in clocks ([`forward_interval_in`],
    /// [`reversal_interval_in`] of its timing), computed once.
    intervals: [(u64, u64); MAX_AXES],
    axes: [Direction; MAX_AXES],
}

impl RateChecker {
    /// A checker for axes with `timings` (at most [`MAX_AXES`], extra ones ignored) and a
    /// period of `period_clocks`, every axis settled positive as after reset. The period
    /// is the one the core runs with: pass a `period_clocks` input through
    /// [`CoreParams::effective_period`](crate::CoreParams::effective_period) first (it
    /// masks the input to `P_WIDTH` bits, as the core does).
    pub fn new(period_clocks: u32, timings: &[DriveTiming]) -> Self {
        Self::with_slots(period_clocks, timings, 1)
    }

    /// A checker for a core whose engine visits each axis every `slots` clocks (0 acts as
    /// 1; [`CoreParams::step_slots`]), with `period_clocks` the period it runs (a
    /// multiple of `slots`, [`CoreParams::effective_period`]).
    pub fn with_slots(period_clocks: u32, timings: &[DriveTiming], slots: u32) -> Self {
        let timings: Vec<DriveTiming> = timings.iter().take(MAX_AXES).copied().collect();
        let mut intervals = [(0, 0); MAX_AXES];
        for (interval, t) in intervals.iter_mut().zip(&timings) {
            *interval = (forward_interval_in(t, slots), reversal_interval_in(t, slots));
        }
        RateChecker {
            period_clocks,
            slots: slots.max(1),
            timings,
            intervals,
            axes: [Direction { last: 1, travel: REVERSAL_TRAVEL }; MAX_AXES],
        }
    }

    /// A checker for a core built with `params` and given `period_clocks` as its input:
    /// the period it runs and its slots are taken from `params`.
    pub fn for_core(params: &CoreParams, period_clocks: u32, timings: &[DriveTiming]) -> Self {
        Self::with_slots(params.effective_period(period_clocks), timings, params.step_slots())
    }

    /// `S`: the clocks between two visits of an axis (1 for a DDA and a shaper per axis).
    pub fn slots(&self) -> u32 {
        self.slots
    }

    /// Checks `record` (axis by axis, the first failure reported). On success the
    /// directions are updated; a refused record changes nothing.
    pub fn check(&mut self, record: &PeriodRecord) -> Result<(), (usize, RateError)> {
        let p = u64::from(self.period_clocks.max(1)) << 16;
        for (axis, t) in self.timings.iter().enumerate() {
            // Within both limits whatever the direction: nothing more to read (most
            // increments).
            let (forward, reversal) = self.intervals[axis];
            let magnitude = u64::from(record.inc[axis].to_bits().unsigned_abs());
            if magnitude * forward <= p && magnitude * reversal <= p {
                continue;
            }
            let settled = self.axes[axis].settled_sign();
            // The conditions of `check_increment_in` on the intervals computed once; it
            // states the error where one holds.
            let d = record.inc[axis];
            let reversing = magnitude != 0 && sign(d) != settled;
            if magnitude * forward > p || reversing && magnitude * reversal > p {
                check_increment_in(t, self.period_clocks, settled, d, self.slots).map_err(|e| (axis, e))?;
            }
        }
        for (dir, d) in self.axes.iter_mut().zip(&record.inc).take(self.timings.len()) {
            dir.apply(*d);
        }
        Ok(())
    }

    /// The sign of `axis`'s last non-zero increment (+1 after reset).
    ///
    /// # Panics
    /// If `axis >= MAX_AXES`.
    pub fn last_nonzero_sign(&self, axis: usize) -> i8 {
        self.axes[axis].last
    }

    /// The sign `axis` is settled in, 0 while it is reversing: what [`Self::check`]
    /// passes to [`check_increment`] as `last_nonzero_sign`.
    ///
    /// # Panics
    /// If `axis >= MAX_AXES`.
    pub fn settled_sign(&self, axis: usize) -> i8 {
        self.axes[axis].settled_sign()
    }

    /// The largest magnitude an increment of sign `sign` (+1 or -1) may have in the next
    /// record for `axis`.
    ///
    /// # Panics
    /// If `axis` is not one of the checker's axes.
    pub fn max_increment(&self, axis: usize, sign: i8) -> Increment {
        let reversing = sign != self.settled_sign(axis);
        max_increment_in(&self.timings[axis], self.period_clocks, reversing, self.slots)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn timing(l: u32, s: u32, u: u32, h: u32) -> DriveTiming {
        DriveTiming::new(l, s, u, h)
    }

    #[test]
    fn zero_acts_as_one() {
        assert_eq!(forward_interval(&timing(0, 1, 15, 3)), 2);
    }

    #[test]
    fn intervals() {
        let t = timing(10, 20, 5, 30);
        assert_eq!(forward_interval(&t), 30);
        assert_eq!(reversal_wait(&t), 10 + 35 - 1);
        assert_eq!(reversal_interval(&t), 88);
        let zero = timing(0, 0, 0, 0);
        assert_eq!(forward_interval(&zero), 2);
        assert_eq!(reversal_interval(&zero), 4);
        assert!(reversal_interval(&timing(7, 9, 1, 1)) >= forward_interval(&timing(7, 9, 1, 1)));
    }

    #[test]
    fn intervals_in_visits() {
        // S = 4: L 5 -> 2 visits, S 1 -> 1, U 0 -> 1, H 8 -> 2.
        let t = timing(5, 1, 0, 8);
        assert_eq!(forward_interval_in(&t, 4), 4 * 3);
        assert_eq!(reversal_wait_in(&t, 4), 4 * (2 + 3 - 1));
        assert_eq!(reversal_interval_in(&t, 4), 32);
        for slots in [0, 1] {
            assert_eq!(forward_interval_in(&t, slots), forward_interval(&t));
            assert_eq!(reversal_interval_in(&t, slots), reversal_interval(&t));
        }
        // Multiples of S: I_fwd unchanged; the wait's "- 1" is one visit, S clocks.
        let even = timing(4, 8, 2, 6);
        assert_eq!(forward_interval_in(&even, 2), forward_interval(&even));
        assert_eq!(reversal_interval_in(&even, 2), 2 * 2 * (2 + 4 - 1));
        assert_eq!(max_increment_in(&t, 1000, false, 4), Increment::from_bits((1000 << 16) / 12));
        let params = CoreParams { n_axes: 3, step_shared: true, has_gantry: false, ..CoreParams::default() };
        let mut c = RateChecker::for_core(&params, 99, &[t]);
        assert_eq!(c.slots(), 4);
        // P runs as 96: 96 / 12 = 8 steps forward, 96 / 32 = 3 reversing.
        assert_eq!(c.max_increment(0, 1), Increment::from_num(8));
        assert_eq!(c.max_increment(0, -1), Increment::from_num(3));
        let rec = |x: f64| PeriodRecord { inc: [Increment::from_num(x); MAX_AXES], flags: 0 };
        assert!(matches!(c.check(&rec(8.5)), Err((0, RateError::Forward { interval: 12, period_clocks: 96, .. }))));
        assert!(c.check(&rec(8.0)).is_ok());
        assert!(matches!(c.check(&rec(-3.5)), Err((0, RateError::Reversal { interval: 32, .. }))));
    }

    #[test]
    fn max_increment_is_the_largest_within() {
        let t = timing(3, 4, 2, 2);
        for p in [1, 7, 1000, 1_048_575] {
            for reversing in [false, true] {
                let max = max_increment(&t, p, reversing);
                let last = if reversing { -1 } else { 1 };
                assert!(check_increment(&t, p, last, max).is_ok());
                assert!(check_increment(&t, p, last, -max).is_ok() || !reversing);
                if max < Increment::MAX {
                    let above = Increment::from_bits(max.to_bits() + 1);
                    assert!(check_increment(&t, p, last, above).is_err());
                }
            }
        }
        let huge = max_increment(&timing(1, 1, 1, 1), u32::MAX, false);
        assert_eq!(huge, Increment::MAX);
        // Likewise in visits, for every slot count.
        for slots in [1, 2, 4, 8] {
            for p in [slots, 7 * slots, 1000 * slots] {
                for reversing in [false, true] {
                    let max = max_increment_in(&t, p, reversing, slots);
                    let last = if reversing { -1 } else { 1 };
                    assert!(check_increment_in(&t, p, last, max, slots).is_ok());
                    let above = Increment::from_bits(max.to_bits() + 1);
                    assert!(check_increment_in(&t, p, last, above, slots).is_err(), "S {slots}, P {p}");
                }
            }
        }
    }

    #[test]
    fn errors_say_which_limit() {
        let t = timing(1, 1, 1, 1);
        let d = Increment::from_num(-0.75);
        let e = check_increment(&t, 2, 1, d).unwrap_err();
        assert!(matches!(e, RateError::Reversal { interval: 4, .. }), "{e}");
        assert!(e.to_string().contains("I_rev = 4"));
        let e = check_increment(&t, 2, -1, Increment::from_num(-1.5)).unwrap_err();
        assert!(matches!(e, RateError::Forward { interval: 2, .. }), "{e}");
        assert!(check_increment(&t, 2, -1, d).is_ok());
        assert!(check_increment(&t, 0, 0, Increment::ZERO).is_ok());
    }

    #[test]
    fn the_checker_decides_as_check_increment_in() {
        // Records of random increments around the limits, on several timings and slot
        // counts: the checker's verdict (on its intervals computed once) is that of
        // `check_increment_in` with the axis's settled sign, error included.
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            seed
        };
        for slots in [1, 2, 4] {
            let timings = [timing(1, 1, 1, 1), timing(3, 2, 5, 1), timing(8, 8, 2, 9), timing(1, 6, 1, 2)];
            let period = 64 * slots;
            let mut checker = RateChecker::with_slots(period, &timings, slots);
            let mut refused = 0;
            for _ in 0..4000 {
                let mut record = PeriodRecord::default();
                for (axis, inc) in record.inc.iter_mut().enumerate().take(timings.len()) {
                    let most = max_increment_in(&timings[axis], period, false, slots).to_bits();
                    let raw = (next() % (2 * most as u64 + 64)) as i32 - most - 32;
                    *inc = Increment::from_bits(if next() % 4 == 0 { 0 } else { raw });
                }
                let expected = (0..timings.len()).find_map(|axis| {
                    let settled = checker.settled_sign(axis);
                    check_increment_in(&timings[axis], period, settled, record.inc[axis], slots)
                        .err()
                        .map(|e| (axis, e))
                });
                let got = checker.check(&record);
                assert_eq!(got.err(), expected, "slots {slots}: {record:?}");
                refused += usize::from(expected.is_some());
            }
            assert!(refused > 100 && refused < 3900, "slots {slots}: {refused} refused");
        }
    }

    #[test]
    fn checker_keeps_reversing_until_two_steps() {
        let t = timing(1, 1, 1, 1); // I_fwd 2, I_rev 4
        let mut c = RateChecker::new(8, &[t]);
        let rec = |x: f64| PeriodRecord { inc: [Increment::from_num(x); MAX_AXES], flags: 0 };
        assert!(c.check(&rec(4.0)).is_ok(), "settled positive after reset");
        assert!(c.check(&rec(-2.5)).is_err(), "reversal: at most 2");
        assert_eq!(c.last_nonzero_sign(0), 1, "refused record changes nothing");
        assert!(c.check(&rec(-1.5)).is_ok());
        assert_eq!((c.last_nonzero_sign(0), c.settled_sign(0)), (-1, 0));
        assert_eq!(c.max_increment(0, -1), Increment::from_num(2));
        assert!(c.check(&rec(0.0)).is_ok());
        assert!(c.check(&rec(-2.5)).is_err(), "still reversing after 1.5 steps");
        assert!(c.check(&rec(-0.5)).is_ok());
        assert_eq!(c.settled_sign(0), -1);
        assert!(c.check(&rec(-4.0)).is_ok(), "settled: forward limit");
        assert!(c.check(&rec(1.0)).is_ok());
        assert!(c.check(&rec(-1.0)).is_ok(), "reversal back");
    }
}

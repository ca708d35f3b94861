//! `period_timer`: counts the interpolation period, takes one [`PeriodRecord`] per
//! period boundary over valid/ready, and holds the increments every DDA uses.
//!
//! Specification: docs/spec/period_timer.md
//!
//! `rec_ready = active && remaining == 0`; a cycle with `rec_ready` is a period boundary.
//! A record taken at boundary `b` is applied in cycles `b+1 ..= b+P` and the next
//! boundary is `b+P`. A missing or unacceptable record gives an idle period (all
//! increments 0); an unacceptable one also sets the sticky `record_error`.
//!
//! With the shared [step engine](crate::step_engine) (`STEP_SHARED = 1`, `S = 2^SL`
//! slots) three rules change: the sampled period is `Ps = max(P with its low SL bits
//! cleared, S)` (the core passes it as `TimerInputs::period`); the run starts
//! (`active <- 1`) only in a cycle with `slot == S - 2 (mod S)`, so every boundary has
//! `slot == S - 1`; and a record is acceptable when `|D| < P / S` for every axis. A
//! timer without the engine is the case `SL = 0` (`S = 1`): every cycle may start, and
//! `|D| < P`. With the engine `p_act` resets to `S`.

use crate::record::{raw_acceptable, PeriodRecord};
use crate::MAX_AXES;

/// State of the period timer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PeriodTimer {
    pub(crate) active: bool,
    pub(crate) remaining: u32,
    pub(crate) p_act: u32,
    pub(crate) inc: [i32; MAX_AXES],
    pub(crate) cur_end: bool,
    pub(crate) block_end: bool,
    pub(crate) record_error: bool,
}

impl Default for PeriodTimer {
    /// The reset state: inactive, `p_act = 1`, idle.
    fn default() -> Self {
        Self::with_reset_period(1)
    }
}

impl PeriodTimer {
    /// The reset state with `p_act = reset_period`: 1, or `S` with the step engine.
    pub(crate) fn with_reset_period(reset_period: u32) -> Self {
        PeriodTimer {
            active: false,
            remaining: 0,
            p_act: reset_period,
            inc: [0; MAX_AXES],
            cur_end: false,
            block_end: false,
            record_error: false,
        }
    }
}

/// This cycle's inputs of the period timer (already masked).
#[derive(Clone, Copy, Debug)]
pub(crate) struct TimerInputs<'a> {
    pub(crate) run: bool,
    /// `max(period_clocks, 1)`, masked to `P_WIDTH`.
    pub(crate) period: u32,
    pub(crate) clear_errors: bool,
    pub(crate) rec_valid: bool,
    pub(crate) record: &'a PeriodRecord,
    pub(crate) n_axes: usize,
    /// `SL`: the step engine's slot bits, 0 without the engine (`S = 2^SL`).
    pub(crate) slot_bits: u32,
    /// The engine's `slot` in this cycle (0 without the engine).
    pub(crate) slot: u32,
}

impl PeriodTimer {
    /// Output `rec_ready`: this cycle is a period boundary.
    #[inline]
    pub fn rec_ready(&self) -> bool {
        self.active && self.remaining == 0
    }

    /// Whether periods are running (`run` has been 1 since the cycle before).
    pub fn active(&self) -> bool {
        self.active
    }

    /// Clocks left before the next boundary.
    pub fn remaining(&self) -> u32 {
        self.remaining
    }

    /// The period in clocks in force (sampled while stopped).
    pub fn p_act(&self) -> u32 {
        self.p_act
    }

    /// The raw I16F16 increments the DDAs use in this cycle.
    pub fn increments(&self) -> &[i32; MAX_AXES] {
        &self.inc
    }

    /// The current period is the last of a block.
    pub fn cur_end(&self) -> bool {
        self.cur_end
    }

    /// Output `block_end`: one-cycle pulse after a block's last period.
    pub fn block_end(&self) -> bool {
        self.block_end
    }

    /// Output `record_error` (sticky): an unacceptable record was consumed.
    pub fn record_error(&self) -> bool {
        self.record_error
    }

    /// The outputs (`rec_ready`, `record_error`, `block_end`) in one word, to see
    /// whether they changed.
    #[inline]
    pub(crate) fn output_bits(&self) -> u8 {
        u8::from(self.rec_ready()) | (u8::from(self.record_error) << 1) | (u8::from(self.block_end) << 2)
    }

    /// One rising edge.
    #[inline]
    pub(crate) fn step(&mut self, inp: &TimerInputs<'_>) {
        let boundary = self.rec_ready();
        let mut error = false;
        self.block_end = boundary && self.cur_end && inp.run;
        if !inp.run {
            self.active = false;
            self.remaining = 0;
            self.inc = [0; MAX_AXES];
            self.cur_end = false;
            self.p_act = inp.period;
        } else if !self.active {
            // With the engine only in a cycle with slot == S - 2 (mod S): the first
            // boundary, the next cycle, has slot == S - 1.
            let last_slot = (1u32 << inp.slot_bits) - 1;
            self.active = inp.slot == last_slot.wrapping_sub(1) & last_slot;
            self.p_act = inp.period;
        } else if self.remaining != 0 {
            self.remaining -= 1;
        } else {
            self.remaining = self.p_act - 1;
            let n = inp.n_axes;
            let record = inp.record;
            // At most one step per visit: |D| < P / S (S = 1 without the engine).
            let visits = self.p_act >> inp.slot_bits;
            let accept = inp.rec_valid && record.inc[..n].iter().all(|d| raw_acceptable(d.to_bits(), visits));
            if accept {
                for (slot, d) in self.inc[..n].iter_mut().zip(&record.inc[..n]) {
                    *slot = d.to_bits();
                }
                self.cur_end = record.flags & crate::record::flags::BLOCK_END != 0;
            } else {
                self.inc = [0; MAX_AXES];
                self.cur_end = false;
                error = inp.rec_valid;
            }
        }
        self.record_error = error || (self.record_error && !inp.clear_errors);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::record::flags::BLOCK_END;

    fn inputs(run: bool, rec_valid: bool, record: &PeriodRecord) -> TimerInputs<'_> {
        TimerInputs { run, period: 3, clear_errors: false, rec_valid, record, n_axes: 2, slot_bits: 0, slot: 0 }
    }

    #[test]
    fn with_the_engine_the_run_starts_at_slot_s_minus_2_and_records_need_d_below_p_over_s() {
        let rec = PeriodRecord::from_raw(&[2 * 65536 - 1, -2 * 65536], 0);
        for (slot_bits, start_slot) in [(1u32, 0u32), (2, 2), (3, 6)] {
            let s = 1u32 << slot_bits;
            let mut t = PeriodTimer::default();
            let engine = |slot: u32, run: bool, rec_valid: bool| TimerInputs {
                period: 2 * s,
                slot_bits,
                slot: slot % s,
                ..inputs(run, rec_valid, &rec)
            };
            t.step(&engine(0, false, false));
            let mut slot = 1;
            while !t.active() {
                t.step(&engine(slot, true, false));
                assert!(slot < 1 + s, "started by slot {slot}");
                slot += 1;
            }
            assert_eq!((slot - 1) % s, start_slot, "S = {s}");
            assert_eq!(slot % s, s - 1, "the first boundary has slot S - 1");
            assert!(t.rec_ready());
            // P / S = 2 visits: 2 - 1/65536 steps is accepted, -2 is not.
            t.step(&engine(slot, true, true));
            assert!(t.record_error(), "S = {s}: |D| = 2 refused");
            assert_eq!(t.increments()[..2], [0, 0]);
            let ok = PeriodRecord::from_raw(&[2 * 65536 - 1, -(2 * 65536 - 1)], 0);
            for _ in 0..2 * s - 1 {
                t.step(&engine(0, true, false));
            }
            assert!(t.rec_ready());
            t.step(&TimerInputs { record: &ok, clear_errors: true, ..engine(0, true, true) });
            assert!(!t.record_error());
            assert_eq!(t.increments()[..2], [2 * 65536 - 1, -(2 * 65536 - 1)]);
        }
    }

    #[test]
    fn boundaries_every_period_and_records_apply_for_p_cycles() {
        let rec = PeriodRecord::from_raw(&[1000, -1000], BLOCK_END);
        let mut t = PeriodTimer::default();
        t.step(&inputs(false, false, &rec));
        assert_eq!(t.p_act(), 3);
        t.step(&inputs(true, false, &rec));
        assert!(t.rec_ready(), "first cycle after run rose is a boundary");
        t.step(&inputs(true, true, &rec));
        assert_eq!(t.increments()[..2], [1000, -1000]);
        let mut ready = vec![];
        let mut ends = vec![];
        for _ in 0..6 {
            ready.push(t.rec_ready());
            t.step(&inputs(true, false, &rec));
            ends.push(t.block_end());
        }
        assert_eq!(ready, [false, false, true, false, false, true]);
        assert_eq!(ends, [false, false, true, false, false, false]);
        assert_eq!(t.increments()[..2], [0, 0], "no record: idle period");
    }

    #[test]
    fn unacceptable_record_is_idle_and_sets_the_sticky_error() {
        let rec = PeriodRecord::from_raw(&[0, -3 * 65536], 0);
        let mut t = PeriodTimer::default();
        t.step(&inputs(false, false, &rec));
        t.step(&inputs(true, false, &rec));
        t.step(&inputs(true, true, &rec));
        assert!(t.record_error());
        assert_eq!(t.increments()[..2], [0, 0]);
        let clear = TimerInputs { clear_errors: true, ..inputs(true, false, &rec) };
        t.step(&clear);
        assert!(!t.record_error());
    }

    #[test]
    fn a_record_taken_while_stopping_is_discarded() {
        let rec = PeriodRecord::from_raw(&[7 << 16, 0], BLOCK_END);
        let mut t = PeriodTimer::default();
        t.step(&inputs(false, false, &rec));
        t.step(&inputs(true, false, &rec));
        assert!(t.rec_ready());
        t.step(&inputs(false, true, &rec));
        assert!(!t.active());
        assert_eq!(t.increments()[..2], [0, 0]);
        assert!(!t.record_error() && !t.block_end() && !t.cur_end());
    }
}

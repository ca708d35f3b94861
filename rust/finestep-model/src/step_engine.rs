//! `step_engine`: with `STEP_SHARED = 1`, one DDA and one step shaper visiting the axes
//! in turn instead of one of each per axis.
//!
//! Specification: docs/spec/step_engine.md
//!
//! `S = 2^SL` slots (`SL` 1 for up to 2 axes, 2 for up to 4, 3 for up to 8); `slot`
//! (reset 0) counts every cycle modulo `S`, nothing stalls it. A cycle with
//! `slot == a` is the DDA visit of axis `a`, the next one (`slot == (a + 1) mod S`) its
//! shaper visit. Each visit applies the per-axis rule once (`DdaAxis::step`,
//! `StepShaper::decide` and `StepShaper::apply`) to that axis's store: the DDA with
//! `V = p_act / S` steps of a period, the shaper with its counters counting visits and
//! every compare `cnt >= X` read as `cnt * S >= X`. Between visits an axis's state holds
//! but for `clear_errors`, which clears `rate_error` and `step_lost` in any cycle (a set
//! at a visit wins).
//!
//! The DDA has no stopped preset: `live[a]` (reset 0) is cleared in every cycle the DDAs
//! do not run (`run && active` low), for every axis; the first running visit of an axis
//! starts from `b = M / 2` of the running period instead of `acc[a]`, and sets `live[a]`.
//! A stopped visit only clears `req[a]`.
//!
//! Pins: `pin_a`, `pin_b` change only at the edge ending a shaper visit, to the pin
//! functions of the state that visit leaves (the mode and inversion of the visit cycle);
//! `pin_en <- (axis_enable && !halt) ^ invert[2]` in every cycle. Latency: a DDA visit in
//! cycle `n`, the rise decision in `n + 1`, `position` and the pin edge in `n + 2`.
//!
//! Requests from outside the DDA (`EXT_REQ`: the core's pbp block,
//! docs/spec/step_engine.md#requests-from-outside): one in cycle `m` is held for its axis
//! (`held`) and taken by the axis's first shaper visit after `m` (`m + 1 ..= m + S`) as
//! that visit's request, in place of the DDA's; the sender keeps them `S` clocks apart.
//!
//! The per-axis stores (`acc`, `req`; `pending`, `level`, `dir`, `cnt`, `dcnt`, `quad`,
//! `position`, the flags and the pins) are the core's [`DdaAxis`] and [`StepShaper`]
//! arrays, the engine's RAM: [`Core::dda`](crate::Core::dda) and
//! [`Core::shaper`](crate::Core::shaper) read them. This module holds the schedule and
//! the visits.

use crate::config::AxisSettings;
use crate::dda_axis::{DdaAxis, ONE_STEP};
use crate::step_shaper::{enable_pin, StepShaper, PIN_EN};
use crate::MAX_AXES;

/// The engine's schedule (`SL`, `slot`) and each axis's `live` bit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StepEngine {
    /// `SL`: `S = 2^SL` slots.
    pub(crate) slot_bits: u32,
    /// The slot of this cycle, `0..S`.
    pub(crate) slot: u32,
    /// `live[a]` at bit `a`: axis `a`'s accumulator holds a running value (else its next
    /// running visit starts from `M / 2`).
    pub(crate) live: u8,
    /// A request from outside held for axis `a` at bit `a` (its next shaper visit takes
    /// it), and its sign (bit set: negative).
    pub(crate) held: u8,
    pub(crate) held_negative: u8,
}

/// This cycle's inputs of the engine that are not per axis.
#[derive(Clone, Copy, Debug)]
pub(crate) struct EngineInputs<'a> {
    /// The DDAs' run, `run && active`: a DDA visit steps the accumulator (else it only
    /// clears the request), and every `live` bit clears while it is low.
    pub(crate) running: bool,
    /// The timer's `p_act` of this cycle (`M = p_act / S * 65536`).
    pub(crate) p_act: u32,
    /// The timer's current increments.
    pub(crate) inc: &'a [i32],
    pub(crate) clear_errors: bool,
    /// Saturation value of `cnt` and `dcnt`, `2^TIMING_W - 1`.
    pub(crate) counter_max: u32,
    /// The requests from outside in this cycle, per axis (+1, -1 or 0).
    pub(crate) ext: [i8; MAX_AXES],
}

impl StepEngine {
    /// The reset state (`slot = 0`, no axis live) for `slot_bits = SL`.
    pub fn new(slot_bits: u32) -> StepEngine {
        StepEngine { slot_bits, slot: 0, live: 0, held: 0, held_negative: 0 }
    }

    /// `S = 2^SL`: the clocks between two visits of an axis.
    pub fn slots(&self) -> u32 {
        1 << self.slot_bits
    }

    /// The slot of this cycle, `0..S`.
    pub fn slot(&self) -> u32 {
        self.slot
    }

    /// `live[axis]`: the axis's accumulator holds a running value (its next running
    /// visit adds to it rather than starting from `M / 2`).
    pub fn live(&self, axis: usize) -> bool {
        axis < 8 && self.live & (1 << axis) != 0
    }

    /// A request from outside is in this cycle's inputs (`ext`) or held: one that has
    /// not reached its axis's shaper visit.
    pub fn ext_pending(&self, ext: &[i8]) -> bool {
        self.held != 0 || ext.iter().any(|&r| r != 0)
    }

    /// The request a shaper visit of `axis` takes: the held one, else the DDA's `req`.
    #[inline(always)]
    fn visit_request(&self, axis: usize, req: i8) -> i8 {
        match (self.held >> axis & 1 != 0, self.held_negative >> axis & 1 != 0) {
            (true, true) => -1,
            (true, false) => 1,
            _ => req,
        }
    }

    /// The axis whose DDA this cycle visits (`slot`; `None` at and above `n_axes`).
    #[inline]
    pub fn dda_axis(&self, n_axes: usize) -> Option<usize> {
        let a = self.slot as usize;
        (a < n_axes).then_some(a)
    }

    /// The axis whose shaper this cycle visits (`(slot - 1) mod S`; `None` at and above
    /// `n_axes`).
    #[inline]
    pub fn shaper_axis(&self, n_axes: usize) -> Option<usize> {
        let a = (self.slot.wrapping_sub(1) & (self.slots() - 1)) as usize;
        (a < n_axes).then_some(a)
    }

    /// The shaper rules' counter compare in visits: `count * S >= x`, exact.
    #[inline(always)]
    pub(crate) fn reached(slot_bits: u32, count: u32, x: u32) -> bool {
        (u64::from(count) << slot_bits) >= u64::from(x)
    }

    /// One rising edge over the stores `dda` and `shaper` (the first `n_axes` entries
    /// are the axes); `axis(i)` gives axis `i`'s masked settings. Returns whether an
    /// output (pins, flags, position) changed.
    /// `EXT`: requests from outside may come (the core's pbp block); without them none
    /// of their handling is compiled in.
    #[inline]
    pub(crate) fn step<const EXT: bool>(
        &mut self,
        inp: &EngineInputs<'_>,
        axis: impl Fn(usize) -> AxisSettings,
        dda: &mut [DdaAxis],
        shaper: &mut [StepShaper],
    ) -> bool {
        let n = shaper.len().min(dda.len());
        let visited = self.shaper_axis(n);
        let mut changed = false;
        for (i, sh) in shaper[..n].iter_mut().enumerate() {
            let set = axis(i);
            let before = sh.output_bits();
            if visited == Some(i) {
                // The request held for the axis, else the one the DDA visit of the
                // previous cycle left.
                let r = if EXT { self.visit_request(i, dda[i].req) } else { dda[i].req };
                let d = sh.decide(r, &set, |count, x| Self::reached(self.slot_bits, count, x));
                sh.apply(d, set.halt, inp.counter_max, inp.clear_errors);
                // Pins A and B from the state the visit leaves.
                sh.pins = sh.step_pins(&set) | enable_pin(&set);
                changed |= d.rise;
            } else {
                sh.pins = (sh.pins & !PIN_EN) | enable_pin(&set);
                sh.clear_flags(inp.clear_errors);
            }
            changed |= sh.output_bits() != before;
        }
        if let Some(a) = self.dda_axis(n) {
            if inp.running {
                // One DDA step of a period of V = p_act / S visits, from M / 2 at the
                // first running visit (rounding to nearest).
                let m = i64::from(inp.p_act >> self.slot_bits) * ONE_STEP;
                if !self.live(a) {
                    dda[a].acc = m / 2;
                }
                self.live |= 1 << a;
                dda[a].step(true, 0, inp.inc[a], m);
            } else {
                dda[a].req = 0;
            }
        }
        if !inp.running {
            // A stop of any length restarts every accumulator.
            self.live = 0;
        }
        // The requests from outside: held from the next cycle until their axis's shaper
        // visit (the visit of this cycle takes the one held before, not one coming now).
        // Nothing to do while none is held or coming (always without the pbp block).
        if EXT && (self.held != 0 || inp.ext != [0; MAX_AXES]) {
            for (a, &r) in inp.ext.iter().enumerate().take(n) {
                let bit = 1u8 << a;
                if r != 0 {
                    self.held |= bit;
                    self.held_negative = if r < 0 { self.held_negative | bit } else { self.held_negative & !bit };
                } else if visited == Some(a) {
                    self.held &= !bit;
                }
            }
        }
        self.slot = (self.slot + 1) & (self.slots() - 1);
        changed
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::DriveTiming;

    #[test]
    fn visits_follow_the_slot() {
        for (sl, n, dda, shaper) in [
            (1, 1, [Some(0), None].as_slice(), [None, Some(0)].as_slice()),
            (1, 2, &[Some(0), Some(1)], &[Some(1), Some(0)]),
            (2, 3, &[Some(0), Some(1), Some(2), None], &[None, Some(0), Some(1), Some(2)]),
        ] {
            let mut e = StepEngine::new(sl);
            let inc = [0; 8];
            let inp = EngineInputs {
                running: false,
                p_act: 8,
                inc: &inc,
                clear_errors: false,
                counter_max: 15,
                ext: [0; MAX_AXES],
            };
            let mut d = [DdaAxis::default(); 8];
            let mut s = [StepShaper::new(15); 8];
            for round in 0..3 {
                for k in 0..e.slots() as usize {
                    assert_eq!(e.slot() as usize, k, "round {round}");
                    assert_eq!((e.dda_axis(n), e.shaper_axis(n)), (dda[k], shaper[k]), "SL {sl} slot {k}");
                    e.step::<false>(&inp, |_| AxisSettings::default(), &mut d[..n], &mut s[..n]);
                }
            }
        }
    }

    #[test]
    fn the_first_running_visit_starts_from_half_a_step_and_a_stop_restarts() {
        let mut e = StepEngine::new(1);
        let inc = [5 << 15, -1, 0, 0, 0, 0, 0, 0];
        // P = 8, S = 2: V = 4, M = 4 * 65536.
        let m = 4 * ONE_STEP;
        let running = |running| EngineInputs {
            running,
            p_act: 8,
            inc: &inc,
            clear_errors: false,
            counter_max: 15,
            ext: [0; MAX_AXES],
        };
        let mut d = [DdaAxis { acc: 12345, req: 1 }; 2];
        let mut s = [StepShaper::new(15); 2];
        e.step::<false>(&running(false), |_| AxisSettings::default(), &mut d, &mut s);
        assert_eq!((d[0].acc, d[0].req), (12345, 0), "stopped: the request clears, acc is left");
        e.step::<false>(&running(true), |_| AxisSettings::default(), &mut d, &mut s);
        assert_eq!((d[1].acc, d[1].req, e.live), (m / 2 - 1, 0, 0b10), "axis 1 from M/2");
        e.step::<false>(&running(true), |_| AxisSettings::default(), &mut d, &mut s);
        assert_eq!((d[0].acc, d[0].req, e.live), (m / 2 + (5 << 15) - m, 1, 0b11), "axis 0 from M/2, wraps");
        // One stopped cycle (a visit of axis 1 only) restarts axis 0 too.
        e.step::<false>(&running(false), |_| AxisSettings::default(), &mut d, &mut s);
        assert_eq!(e.live, 0);
        e.step::<false>(&running(true), |_| AxisSettings::default(), &mut d, &mut s);
        assert_eq!((d[0].acc, d[0].req), (m / 2 + (5 << 15) - m, 1), "from M/2 again");
    }

    #[test]
    fn a_request_from_outside_waits_for_its_axis_s_next_shaper_visit() {
        // S = 4, 4 axes, the DDAs stopped: only the requests from outside move axis 1,
        // whose shaper visits are the cycles with slot 2.
        let inc = [0; 8];
        let mut ext = [0i8; MAX_AXES];
        let mut e = StepEngine::new(2);
        let mut d = [DdaAxis::default(); 4];
        let mut s = [StepShaper::new(15); 4];
        let set = |_| AxisSettings { timing: DriveTiming::new(1, 1, 1, 1), ..AxisSettings::default() };
        let edge = |e: &mut StepEngine, d: &mut [DdaAxis], s: &mut [StepShaper], ext: [i8; MAX_AXES]| {
            let inp = EngineInputs { running: false, p_act: 8, inc: &inc, clear_errors: false, counter_max: 15, ext };
            e.step::<true>(&inp, set, d, s);
        };
        // (slot of the request's cycle m, the cycle m + wait of the visit that takes it)
        for (slot, wait) in [(1, 1), (2, 4), (3, 3), (0, 2)] {
            while e.slot() != slot {
                edge(&mut e, &mut d, &mut s, ext);
            }
            let before = (s[1].position, s[1].pending);
            ext[1] = 1;
            // The edges ending cycles m .. m + wait - 1: held, not yet taken.
            for k in 0..wait {
                edge(&mut e, &mut d, &mut s, ext);
                ext[1] = 0;
                assert_eq!((s[1].position, s[1].pending), before, "slot {slot}: taken in cycle m + {k}");
                assert!(e.ext_pending(&ext), "slot {slot}: held after cycle m + {k}");
            }
            // The edge ending the visit in m + wait takes it.
            edge(&mut e, &mut d, &mut s, ext);
            assert_ne!((s[1].position, s[1].pending), before, "slot {slot}: taken in cycle m + {wait}");
            assert!(!e.ext_pending(&ext), "slot {slot}: no longer held");
            // The step goes out; then the next request.
            for _ in 0..16 {
                edge(&mut e, &mut d, &mut s, ext);
            }
        }
        assert_eq!(s[1].position, 4, "four requests, four steps");
        assert_eq!([s[0].position, s[2].position, s[3].position], [0; 3], "the other axes stay");
    }

    #[test]
    fn compares_count_visits_of_s_clocks() {
        assert!(StepEngine::reached(2, 1, 4) && !StepEngine::reached(2, 1, 5) && StepEngine::reached(2, 2, 5));
        assert!(StepEngine::reached(3, 1, 0), "0 acts as 1");
        assert!(StepEngine::reached(3, u32::MAX, u32::MAX), "exact, no overflow");
        let set = AxisSettings { timing: DriveTiming::new(5, 1, 1, 1), ..AxisSettings::default() };
        let mut sh = StepShaper::new(15);
        sh.level = true;
        sh.cnt = 2;
        assert!(!sh.decide(0, &set, |c, x| StepEngine::reached(1, c, x)).fall, "2 visits of 2 clocks < 5");
        assert!(sh.decide(0, &set, |c, x| StepEngine::reached(2, c, x)).fall, "2 visits of 4 clocks >= 5");
    }
}

//! The fast path: [`Core::run_chunk_fast`] gives exactly what [`Core::run_chunk`]
//! gives, but skips runs of *quiet* cycles arithmetically.
//!
//! With the inputs constant over a chunk, a cycle is quiet when its edge changes no
//! output and changes the state only by counting: the period timer counts `remaining`
//! down without reaching 0 (or sits stopped, or idles at `P = 1`), no DDA wraps (no step
//! request is made or seen), no shaper decides a rise, fall or direction change, and no
//! pin or flag changes. Over `k` quiet cycles `remaining -= k`, `acc += k * d` and the
//! shaper counters saturate at `cnt + k`, `dcnt + k`. The length of a quiet run is the
//! smallest of: the clocks to the boundary, per axis the clocks to the next DDA wrap
//! (closed form: for `acc` in `[0, M)` and increment `d > 0` the update in `j` cycles'
//! time wraps first for `j = ceil((M - acc) / d) - 1`, for `d < 0` for
//! `j = floor(acc / |d|)`), and per axis the clocks until the shaper's counters reach
//! the threshold of its next decision (while `halt`, only a fall is decided, and a cycle
//! with `pending != 0` is not quiet since the edge drops it), and the clocks to the
//! gantry's next tick. The gantry is quiet when its edge (with no DDA request, which a
//! quiet cycle has) would leave its state unchanged but for `tick_cnt` counting, and
//! this cycle is not a tick: then its next cycle is the same but for `tick_cnt`, so the
//! run lasts until the tick (`corr != 0` is never quiet: it is applied or dropped; a
//! count change is not, `diff` follows it). Every other cycle is run by the per-clock
//! [`Core::step`], so the cost is O(output changes + requests + periods), not O(cycles).
//!
//! With the step engine (`step_shared`) the same holds visit by visit, and the skip is
//! exact too: a quiet run ends before the first cycle in which the engine would change
//! more than counting, i.e. before a stopped cycle that clears a `live` bit, before the
//! DDA visit of an axis that wraps (or starts from `M / 2`, or clears a request), and
//! before the shaper visit that sees a request, decides a rise, fall or direction
//! change, moves pins A/B, drops `pending` while halted or sets `rate_error`. In `k`
//! cycles from `slot`, an axis whose visit is `c` cycles away is visited
//! `ceil((k - c) / S)` times (0 when `k <= c`): `acc` adds `d` per DDA visit, `cnt` and
//! `dcnt` count (saturating) per shaper visit, and `slot` moves on by `k`.
//!
//! With the pbp block (`has_pbp`) a cycle is quiet only while the block is idle (no
//! record runs or waits, no `done` pulse, no refusal to clear): its records run clock by
//! clock, and between them the skip is the one above.

use crate::core::{ChunkEnd, Core, Event, Settings};
use crate::dda_axis::{HALF_STEP, ONE_STEP};
use crate::gantry_sync::GantryContext;
use crate::step_engine::StepEngine;
use crate::step_shaper::{enable_pin, PIN_A, PIN_B, PIN_EN};
use crate::CoreInputs;

impl Core {
    /// Same as [`Core::run_chunk`] (same events, same [`ChunkEnd`], same end state) but
    /// skipping quiet cycles, so the cost grows with the number of output changes, step
    /// requests and periods rather than with `max_cycles`.
    pub fn run_chunk_fast(&mut self, inputs: &CoreInputs, max_cycles: u64, events: &mut Vec<Event>) -> ChunkEnd {
        let set = self.settings(inputs);
        let mut ran = 0;
        while ran < max_cycles {
            // The digit-serial engine has no skip rule yet: its cycles run one by one
            // (exact, as fast as the per-clock path). The pbp block is quiet while idle.
            let quiet = match self.engine {
                _ if self.serial.is_some() || !self.pbp_quiet(inputs) => 0,
                Some(engine) => self.engine_quiet_cycles(&engine, &set, inputs),
                None => self.quiet_cycles(&set, inputs),
            }
            .min(max_cycles - ran);
            if quiet > 0 {
                match self.engine {
                    Some(engine) => self.engine_skip_quiet(engine, quiet, inputs),
                    None => self.skip_quiet(quiet, inputs),
                }
                ran += quiet;
                continue;
            }
            ran += 1;
            if self.chunk_edge(&set, inputs, events) {
                return ChunkEnd { cycles: ran, consumed: true };
            }
        }
        ChunkEnd { cycles: ran, consumed: false }
    }

    /// Whether the pbp block (if built) lets this cycle be quiet: it does not hold the
    /// record port ([`Core::pbp_waits`]: no record runs, none of its requests waits for
    /// the step engine), its `done` pulse of the last edge is over (a request comes only
    /// while a record runs or with `done`) and `clear_errors` has no refusal to clear.
    /// Its edge then changes nothing, since a quiet cycle offers it no record
    /// (`rec_ready` is low, or the idle `P = 1` boundary is offered none): the block sits
    /// out the whole run, and the step engine and the gantry see no request or motion.
    fn pbp_quiet(&self, inputs: &CoreInputs) -> bool {
        let Some(p) = &self.pbp else { return true };
        p.settled(inputs.clear_errors) && !self.pbp_waits()
    }

    /// How many cycles from the current one on are quiet with these inputs (0: the
    /// current cycle is not; `u64::MAX`: all of them).
    fn quiet_cycles(&self, set: &Settings, inputs: &CoreInputs) -> u64 {
        let n = self.params.n_axes;
        let clear = inputs.clear_errors;
        let t = &self.timer;
        let idle = t.inc[..n].iter().all(|&d| d == 0) && !t.cur_end;
        if t.block_end || (t.record_error && clear) {
            return 0;
        }
        let mut quiet = self.gantry_quiet_cycles(inputs);
        if quiet == 0 {
            return 0;
        }
        if !inputs.run {
            // Stopped: quiet once the edge changes nothing in the timer and DDAs.
            if t.active || t.remaining != 0 || !idle || t.p_act != set.period {
                return 0;
            }
        } else if !t.active {
            return 0;
        } else if t.remaining >= 2 {
            quiet = quiet.min(u64::from(t.remaining - 1));
        } else if t.remaining == 1 {
            // rec_ready rises at this edge.
            return 0;
        } else if !(t.p_act == 1 && !inputs.rec_valid && idle) {
            // A boundary; only an idle boundary at P = 1 (rec_ready stays 1) is quiet.
            return 0;
        }
        let m = i64::from(t.p_act) * ONE_STEP;
        for i in 0..n {
            let dda = &self.dda[i];
            if dda.req != 0 {
                return 0;
            }
            let d = i64::from(t.inc[i]);
            if !inputs.run {
                if dda.acc != i64::from(set.period) * HALF_STEP {
                    return 0;
                }
            } else if d > 0 {
                let to_wrap = (m - dda.acc + d - 1) / d - 1;
                quiet = quiet.min(to_wrap as u64);
            } else if d < 0 {
                quiet = quiet.min((dda.acc / -d) as u64);
            }

            let sh = &self.shaper[i];
            let axis = &set.axes[i];
            let e = sh.pending;
            // Halted, the edge zeroes `pending`: quiet only once it is 0.
            if axis.halt && e != 0 {
                return 0;
            }
            if sh.pins != sh.next_pins(axis)
                || (sh.step_lost && clear)
                || (e.unsigned_abs() >= 2 || (sh.rate_error && !clear)) != sh.rate_error
            {
                return 0;
            }
            let to_decision = if sh.level {
                axis.timing.step_len.saturating_sub(sh.cnt)
            } else if e == 0 || axis.halt {
                u32::MAX
            } else if (e > 0) == sh.dir {
                axis.timing.step_space.saturating_sub(sh.cnt).max(axis.timing.dir_setup.saturating_sub(sh.dcnt))
            } else {
                axis.timing.dir_hold.saturating_sub(sh.cnt)
            };
            if to_decision != u32::MAX {
                quiet = quiet.min(u64::from(to_decision));
            }
            if quiet == 0 {
                return 0;
            }
        }
        quiet
    }

    /// How many cycles from the current one on the gantry is quiet (given no DDA
    /// request, which [`Self::quiet_cycles`] checks): its edge changes nothing but
    /// `tick_cnt` counting, up to the cycle before its next tick.
    fn gantry_quiet_cycles(&self, inputs: &CoreInputs) -> u64 {
        if !self.params.gantry_built() {
            return u64::MAX;
        }
        let g = &self.gantry;
        if g.corr != 0 {
            return 0;
        }
        let mut next = *g;
        next.step(
            &inputs.gantry,
            &GantryContext {
                n_axes: self.params.n_axes,
                master_req: 0,
                inc: self.timer.inc,
                ext: self.pbp_motion(),
                halt: inputs.halt,
                clear_errors: inputs.clear_errors,
            },
        );
        if next != g.counted() {
            return 0;
        }
        g.cycles_to_tick(inputs.gantry.tick)
    }

    /// Advances `k` quiet cycles (as found by [`Self::quiet_cycles`]) at once.
    fn skip_quiet(&mut self, k: u64, inputs: &CoreInputs) {
        let n = self.params.n_axes;
        if inputs.run {
            if self.timer.remaining != 0 {
                // k <= remaining - 1 here.
                self.timer.remaining -= k as u32;
            }
            for (dda, &d) in self.dda[..n].iter_mut().zip(&self.timer.inc[..n]) {
                if d != 0 {
                    // k is at most the cycles to this DDA's next wrap.
                    dda.acc += k as i64 * i64::from(d);
                }
            }
        }
        let max = u64::from(self.counter_max);
        for sh in &mut self.shaper[..n] {
            sh.cnt = u64::from(sh.cnt).saturating_add(k).min(max) as u32;
            sh.dcnt = u64::from(sh.dcnt).saturating_add(k).min(max) as u32;
        }
        if self.params.gantry_built() {
            self.gantry.skip(k);
        }
        self.cycle = self.cycle.wrapping_add(k);
    }
}

/// Of the next `k` cycles, how many are visits of an axis whose next visit is `c`
/// cycles away (`c < slots`), one every `slots` cycles.
fn visits_within(k: u64, c: u64, slots: u64) -> u64 {
    if k > c {
        (k - 1 - c) / slots + 1
    } else {
        0
    }
}

impl Core {
    /// [`Self::quiet_cycles`] for a core with the step engine (schedule `e`).
    fn engine_quiet_cycles(&self, e: &StepEngine, set: &Settings, inputs: &CoreInputs) -> u64 {
        let n = self.params.n_axes;
        let clear = inputs.clear_errors;
        let t = &self.timer;
        let idle = t.inc[..n].iter().all(|&d| d == 0) && !t.cur_end;
        if t.block_end || (t.record_error && clear) {
            return 0;
        }
        let running = inputs.run && t.active;
        let mut quiet = u64::MAX;
        if !inputs.run {
            // Stopped: quiet once the edge changes nothing in the timer.
            if t.active || t.remaining != 0 || !idle || t.p_act != set.period {
                return 0;
            }
        } else if !t.active || t.remaining < 2 {
            // Waiting for the start slot, rec_ready rising, or a boundary (P >= S >= 2).
            return 0;
        } else {
            quiet = u64::from(t.remaining - 1);
        }
        if !running && e.live != 0 {
            // This edge clears the live bits.
            return 0;
        }
        let sl = e.slot_bits;
        let slots = u64::from(e.slots());
        let mask = slots - 1;
        let slot = u64::from(e.slot);
        let m = i64::from(t.p_act >> sl) * ONE_STEP;
        // Visits in whole visits: the least v with (count + v) * S >= x.
        let visits_to = |count: u32, x: u32| u64::from(x.div_ceil(1 << sl)).saturating_sub(u64::from(count));
        for i in 0..n {
            // Cycles to the axis's next DDA visit and next shaper visit (0: this cycle).
            let to_dda = (i as u64).wrapping_sub(slot) & mask;
            let to_shaper = (i as u64 + 1).wrapping_sub(slot) & mask;
            let dda = &self.dda[i];
            if dda.req != 0 {
                // The shaper visit takes it, or the DDA visit replaces it.
                quiet = quiet.min(to_dda.min(to_shaper));
            }
            if !running {
                // A stopped visit only clears `req` (above); `live` is 0 (below).
            } else if !e.live(i) {
                // The first running visit starts the accumulator.
                quiet = quiet.min(to_dda);
            } else {
                let d = i64::from(t.inc[i]);
                // Visits that do not wrap (acc in [0, M), else the next one may).
                let plain = if dda.acc < 0 || dda.acc >= m {
                    Some(0)
                } else if d > 0 {
                    Some(((m - dda.acc + d - 1) / d - 1) as u64)
                } else if d < 0 {
                    Some((dda.acc / -d) as u64)
                } else {
                    None
                };
                if let Some(v) = plain {
                    quiet = quiet.min(to_dda.saturating_add(v.saturating_mul(slots)));
                }
            }

            let sh = &self.shaper[i];
            let axis = &set.axes[i];
            if sh.pins & PIN_EN != enable_pin(axis) || (clear && (sh.rate_error || sh.step_lost)) {
                return 0;
            }
            // At the next shaper visit (no request seen before the run ends): pins A/B,
            // a halt's drop of `pending` and `rate_error` must stay.
            let e = sh.pending;
            if sh.pins & (PIN_A | PIN_B) != sh.step_pins(axis)
                || (axis.halt && e != 0)
                || (e.unsigned_abs() >= 2 && !sh.rate_error)
            {
                quiet = quiet.min(to_shaper);
            }
            let to_decision = if sh.level {
                Some(visits_to(sh.cnt, axis.timing.step_len))
            } else if e == 0 || axis.halt {
                None
            } else if (e > 0) == sh.dir {
                Some(visits_to(sh.cnt, axis.timing.step_space).max(visits_to(sh.dcnt, axis.timing.dir_setup)))
            } else {
                Some(visits_to(sh.cnt, axis.timing.dir_hold))
            };
            if let Some(v) = to_decision {
                quiet = quiet.min(to_shaper.saturating_add(v.saturating_mul(slots)));
            }
            if quiet == 0 {
                return 0;
            }
        }
        quiet
    }

    /// Advances `k` quiet cycles (as found by [`Self::engine_quiet_cycles`]) at once.
    fn engine_skip_quiet(&mut self, mut e: StepEngine, k: u64, inputs: &CoreInputs) {
        let n = self.params.n_axes;
        let slots = u64::from(e.slots());
        let slot = u64::from(e.slot);
        let running = inputs.run && self.timer.active;
        if running {
            // k <= remaining - 1 here.
            self.timer.remaining -= k as u32;
        }
        let max = u64::from(self.counter_max);
        for i in 0..n {
            let to_dda = (i as u64).wrapping_sub(slot) & (slots - 1);
            let to_shaper = (i as u64 + 1).wrapping_sub(slot) & (slots - 1);
            let d = self.timer.inc[i];
            if running && d != 0 {
                // None of these visits wraps.
                self.dda[i].acc += visits_within(k, to_dda, slots) as i64 * i64::from(d);
            }
            let seen = visits_within(k, to_shaper, slots);
            let sh = &mut self.shaper[i];
            sh.cnt = u64::from(sh.cnt).saturating_add(seen).min(max) as u32;
            sh.dcnt = u64::from(sh.dcnt).saturating_add(seen).min(max) as u32;
        }
        e.slot = (slot.wrapping_add(k) & (slots - 1)) as u32;
        self.engine = Some(e);
        self.cycle = self.cycle.wrapping_add(k);
    }
}

#[cfg(test)]
mod tests {
    use crate::{AxisConfig, Core, CoreInputs, CoreParams, DriveTiming, PeriodRecord, MAX_AXES};

    #[test]
    fn a_long_move_costs_few_iterations_and_matches_per_clock() {
        let axis = AxisConfig { timing: DriveTiming::new(100, 100, 50, 50), enable: true, ..AxisConfig::default() };
        let mut inp =
            CoreInputs { run: false, period_clocks: 100_000, axes: [axis; MAX_AXES], ..CoreInputs::default() };
        let mut slow = Core::new(CoreParams::default());
        let mut fast = slow.clone();
        let (mut ev_slow, mut ev_fast) = (vec![], vec![]);
        let chunks = [(false, false, 10), (true, false, 1), (true, true, u64::MAX), (true, false, 250_000)];
        inp.record = PeriodRecord::from_raw(&[37 << 16, -(5 << 16) - 123, 0, 1], 1);
        for (run, valid, max) in chunks {
            inp.run = run;
            inp.rec_valid = valid;
            let a = slow.run_chunk(&inp, max, &mut ev_slow);
            let b = fast.run_chunk_fast(&inp, max, &mut ev_fast);
            assert_eq!(a, b);
            assert_eq!(ev_slow, ev_fast);
            assert_eq!(slow, fast);
        }
        assert_eq!(fast.outputs().position(0), 37);
        assert_eq!(fast.outputs().position(1), -5);
    }
}

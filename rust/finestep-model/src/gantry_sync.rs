//! `gantry_sync`: two motors on one gantry axis. The **slave** axis's step shaper gets
//! the **master** axis's DDA requests instead of its own DDA's, plus (in synchronised
//! mode) one correction step per tick from the difference of two channel counts, one
//! on each side of the gantry.
//!
//! Specification: docs/spec/gantry_sync.md
//!
//! A correction inserts a slave request where the master has none, or deletes a master
//! request of the opposite sign; it waits while the master requests in its own
//! direction, and against the master's motion it waits to delete (the slave never
//! reverses while the master moves). Forward mode copies the master's requests
//! unchanged. In both modes the difference is measured against the one at engagement
//! (which waits for both axes at rest: no increment, and no [`ExtMotion`] `busy`, the
//! core's pbp block running a record on the axis's pair) and `alarm` set past `limit`;
//! the alarm stops the corrections. The master's motion is its increment's sign or its
//! [`ExtMotion`] direction.
//!
//! Latency: a count change in cycle `n` reaches `diff` in `n+1`, `error` in `n+2` and
//! `alarm` in `n+3`; a tick in cycle `t` decides from `error` of cycle `t`, and the
//! correction reaches the slave's shaper in `t+1`. Every output, the slave's request
//! included, is a function of the state (the DDA requests and the increments are DDA and
//! period-timer state) and of the `sync` and `enable` inputs.
//!
//! Invariants: `corr == 0` while not engaged, and `tick_cnt == 0` while not engaged; at
//! most one correction is applied per tick.

use crate::config::GantryInputs;

/// `TICK_W`: width of the `tick` input and of `tick_cnt`, in bits.
pub const TICK_W: u32 = 24;
/// All ones in the low [`TICK_W`] bits.
const TICK_MASK: u32 = (1 << TICK_W) - 1;
/// Width mask of the `master` and `slave` inputs (3 bits: axes 0..=7).
const AXIS_MASK: u8 = 0b111;

/// Bits of [`GantrySync::flags`] (and of `CoreOutputs::gantry_flags`).
pub mod flags {
    /// The pair is engaged.
    pub const ENGAGED: u8 = 1 << 0;
    /// Sticky: `|error|` passed `limit` while engaged.
    pub const ALARM: u8 = 1 << 1;
    /// Sticky: an engagement was refused (`master`/`slave` not valid).
    pub const REFUSED: u8 = 1 << 2;
}

/// An axis's motion besides its increment (the core's pbp block, see
/// docs/spec/pbp_interp.md#in-the-core): `busy` (a record runs on the axis's pair: the
/// axis is not at rest) and the direction the block's next step on it would take, `up`
/// or `down` (neither on a line's axis of zero coordinate). All false for a core
/// without the block.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ExtMotion {
    /// Not at rest: a pbp record runs on the axis's pair.
    pub busy: bool,
    /// The next step would be +1.
    pub up: bool,
    /// The next step would be -1.
    pub down: bool,
}

/// No motion besides the increments, on every axis.
pub const NO_EXT: [ExtMotion; crate::MAX_AXES] = [ExtMotion { busy: false, up: false, down: false }; crate::MAX_AXES];

/// State of the gantry synchronisation.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct GantrySync {
    pub(crate) engaged: bool,
    /// The master axis, sampled at engagement.
    pub(crate) m: u8,
    /// The slave axis, sampled at engagement.
    pub(crate) s: u8,
    /// `enc_master - enc_slave` of the cycle before.
    pub(crate) diff: u32,
    /// `diff` at engagement.
    pub(crate) offset: u32,
    /// `diff - offset` of the cycle before while engaged, else 0.
    pub(crate) error: u32,
    /// Cycles since the last tick (`TICK_W` bits, wraps).
    pub(crate) tick_cnt: u32,
    /// The correction waiting to be applied: -1, 0 or +1.
    pub(crate) corr: i8,
    /// Net applied corrections (wraps).
    pub(crate) corrections: u16,
    pub(crate) alarm: bool,
    pub(crate) refused: bool,
}

/// The gantry block's other inputs in a cycle (from the core).
#[derive(Clone, Copy, Debug)]
pub(crate) struct GantryContext {
    /// `N_AXES`, for the `valid` check.
    pub(crate) n_axes: usize,
    /// `r[m]`: the master's DDA request in this cycle (with `m` the state's).
    pub(crate) master_req: i8,
    /// Every axis's increment in this period (the period timer's), 0 above `N_AXES`.
    pub(crate) inc: [i32; crate::MAX_AXES],
    /// Every axis's motion besides its increment (none above `N_AXES`).
    pub(crate) ext: [ExtMotion; crate::MAX_AXES],
    /// The core's `halt`.
    pub(crate) halt: bool,
    /// The core's `clear_errors`.
    pub(crate) clear_errors: bool,
}

impl GantrySync {
    /// The pair is engaged: the slave's shaper takes [`Self::slave_request`].
    pub fn engaged(&self) -> bool {
        self.engaged
    }

    /// The master axis (sampled at engagement).
    pub fn master(&self) -> usize {
        usize::from(self.m)
    }

    /// The slave axis (sampled at engagement).
    pub fn slave(&self) -> usize {
        usize::from(self.s)
    }

    /// `diff`: `enc_master - enc_slave` as registered (wraps).
    pub fn diff(&self) -> u32 {
        self.diff
    }

    /// `offset`: `enc_master - enc_slave` in the engaging cycle.
    pub fn offset(&self) -> u32 {
        self.offset
    }

    /// `error`: `diff - offset` (two's complement counts); 0 while not engaged.
    pub fn error(&self) -> u32 {
        self.error
    }

    /// Cycles since the last tick.
    pub fn tick_cnt(&self) -> u32 {
        self.tick_cnt
    }

    /// The correction waiting to be applied: -1, 0 or +1.
    pub fn corr(&self) -> i8 {
        self.corr
    }

    /// Net corrections applied (wraps at 16 bits).
    pub fn corrections(&self) -> u16 {
        self.corrections
    }

    /// Sticky: `|error|` passed `limit` while engaged.
    pub fn alarm(&self) -> bool {
        self.alarm
    }

    /// Sticky: an engagement was refused.
    pub fn refused(&self) -> bool {
        self.refused
    }

    /// `engaged`, `alarm` and `refused` packed as in [`flags`].
    pub fn flags(&self) -> u8 {
        (u8::from(self.engaged) * flags::ENGAGED)
            | (u8::from(self.alarm) * flags::ALARM)
            | (u8::from(self.refused) * flags::REFUSED)
    }

    /// Whether the correction goes into the slave's request in this cycle, with `r` the
    /// master's request, `d` the master's increment, `e` its motion besides it and this
    /// cycle's `sync` and `enable`: synchronised, enabled and no alarm; then as a
    /// deletion (`r == -corr`), or as an insertion (`r == 0`) unless the master moves
    /// against it (up: `d > 0` or `e.up`; down: `d < 0` or `e.down`; against `+1` is
    /// down, against `-1` up: the correction waits to delete a master step instead).
    #[inline]
    pub fn takes(&self, r: i8, d: i32, e: ExtMotion, sync: bool, enable: bool) -> bool {
        let c = self.corr;
        let (up, down) = (d > 0 || e.up, d < 0 || e.down);
        let against = (c < 0 && up) || (c > 0 && down);
        self.engaged && c != 0 && sync && enable && !self.alarm && if r != 0 { r == -c } else { !against }
    }

    /// The request the engaged pair gives the slave's shaper when the master's DDA
    /// requests `r` in this cycle (see [`Self::takes`] for `d`, `e`, `sync`, `enable`):
    /// `r + corr` when the correction goes in (a step inserted, or a master step
    /// deleted), else `r`.
    #[inline]
    pub fn slave_request(&self, r: i8, d: i32, e: ExtMotion, sync: bool, enable: bool) -> i8 {
        if self.takes(r, d, e, sync, enable) {
            r + self.corr
        } else {
            r
        }
    }

    /// The request-selection rule: the request the step shaper of `axis` takes in this
    /// cycle, given every axis's own request `reqs`, increment `inc` and motion besides
    /// it `ext` of this cycle: the gantry's [`Self::slave_request`] when engaged and
    /// `axis` is the slave, else its own request.
    #[inline]
    pub fn shaper_request(&self, axis: usize, reqs: &[i8], inc: &[i32], ext: &[ExtMotion], inp: &GantryInputs) -> i8 {
        if self.engaged && axis == self.slave() {
            let m = self.master();
            self.slave_request(reqs[m], inc[m], ext[m], inp.sync, inp.enable)
        } else {
            reqs[axis]
        }
    }

    /// Whether the correction is applied in this cycle: it goes in and the core is not
    /// halted (a halted shaper drops every request).
    #[inline]
    fn applied(&self, r: i8, d: i32, e: ExtMotion, inp: &GantryInputs, halt: bool) -> bool {
        self.takes(r, d, e, inp.sync, inp.enable) && !halt
    }

    /// The next `tick_cnt` in a cycle without engagement or disengagement, and whether
    /// this cycle is a tick.
    #[inline]
    fn tick(&self, tick: u32) -> (bool, u32) {
        if !self.engaged {
            return (false, self.tick_cnt);
        }
        let period = (tick & TICK_MASK).max(1);
        if self.tick_cnt >= period - 1 {
            (true, 0)
        } else {
            (false, (self.tick_cnt + 1) & TICK_MASK)
        }
    }

    /// Cycles from this one to the next tick (0: this cycle is one) with `tick` held;
    /// `u64::MAX` while not engaged (no tick comes).
    pub(crate) fn cycles_to_tick(&self, tick: u32) -> u64 {
        if !self.engaged {
            return u64::MAX;
        }
        let period = (tick & TICK_MASK).max(1);
        u64::from((period - 1).saturating_sub(self.tick_cnt))
    }

    /// Advances `tick_cnt` over `k` cycles that are not ticks and change nothing else.
    pub(crate) fn skip(&mut self, k: u64) {
        if self.engaged {
            self.tick_cnt = (u64::from(self.tick_cnt) + k) as u32 & TICK_MASK;
        }
    }

    /// The state after this cycle's edge with the same inputs, except that `tick_cnt`
    /// counts (the state a quiet cycle leads to).
    pub(crate) fn counted(&self) -> GantrySync {
        GantrySync { tick_cnt: if self.engaged { (self.tick_cnt + 1) & TICK_MASK } else { self.tick_cnt }, ..*self }
    }

    /// The outputs together, to see whether they changed.
    #[inline]
    fn output_bits(&self) -> (u32, u16, u8) {
        (self.error, self.corrections, self.flags())
    }

    /// One rising edge. Returns whether an output (`error`, `corrections`, the flags)
    /// changed.
    #[inline]
    pub(crate) fn step(&mut self, inp: &GantryInputs, ctx: &GantryContext) -> bool {
        let before = self.output_bits();
        let master = inp.master & AXIS_MASK;
        let slave = inp.slave & AXIS_MASK;
        let valid = master != slave && usize::from(master) < ctx.n_axes && usize::from(slave) < ctx.n_axes;
        let (mi, si) = (usize::from(master), usize::from(slave));
        let at_rest = ctx.inc[mi] == 0 && ctx.inc[si] == 0 && !ctx.ext[mi].busy && !ctx.ext[si].busy;
        let engage = !self.engaged && inp.enable && valid && at_rest;
        let disengage = self.engaged && !inp.enable;
        let clear = ctx.clear_errors;
        let applied = self.applied(ctx.master_req, ctx.inc[self.master()], ctx.ext[self.master()], inp, ctx.halt);
        let (tick, tick_cnt) = self.tick(inp.tick);

        let error = self.error as i32;
        let deadband = i64::from(inp.deadband);
        let decision = if i64::from(error) > deadband {
            1
        } else if i64::from(error) < -deadband {
            -1
        } else {
            0
        };
        let corr = if engage || disengage || ctx.halt || self.alarm || !self.engaged || !inp.sync {
            0
        } else if tick {
            decision
        } else if applied {
            0
        } else {
            self.corr
        };

        let next = GantrySync {
            engaged: (self.engaged || engage) && !disengage,
            m: if engage { master } else { self.m },
            s: if engage { slave } else { self.s },
            diff: inp.enc_master.wrapping_sub(inp.enc_slave),
            offset: if engage { inp.enc_master.wrapping_sub(inp.enc_slave) } else { self.offset },
            error: if self.engaged { self.diff.wrapping_sub(self.offset) } else { 0 },
            tick_cnt: if engage || disengage { 0 } else { tick_cnt },
            corr,
            corrections: if inp.clear_counters {
                0
            } else if applied {
                self.corrections.wrapping_add_signed(i16::from(self.corr))
            } else {
                self.corrections
            },
            alarm: (self.engaged && error.unsigned_abs() > u32::from(inp.limit)) || (self.alarm && !clear),
            refused: (inp.enable && !valid && !self.engaged) || (self.refused && !clear),
        };
        *self = next;
        self.output_bits() != before
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const N: usize = 4;

    fn ctx(master_req: i8) -> GantryContext {
        GantryContext {
            n_axes: N,
            master_req,
            inc: [0; crate::MAX_AXES],
            ext: NO_EXT,
            halt: false,
            clear_errors: false,
        }
    }

    /// Enabled and synchronised, the rest default.
    const ON: GantryInputs = GantryInputs {
        enable: true,
        sync: true,
        master: 0,
        slave: 0,
        tick: 0,
        deadband: 0,
        limit: 0,
        enc_master: 0,
        enc_slave: 0,
        clear_counters: false,
    };
    const REST: [i32; crate::MAX_AXES] = [0; crate::MAX_AXES];

    fn inputs(master: u8, slave: u8) -> GantryInputs {
        GantryInputs {
            enable: true,
            sync: true,
            master,
            slave,
            tick: 4,
            deadband: 2,
            limit: 100,
            ..GantryInputs::default()
        }
    }

    /// An engaged pair (master 0, slave 1) with zero counts, `error` settled at 0.
    /// Engaged square at counts 0 (the offset is 0), with `inp`'s settings.
    fn engaged(inp: &GantryInputs) -> GantrySync {
        let mut g = GantrySync::default();
        g.step(&GantryInputs { enc_master: 0, enc_slave: 0, ..*inp }, &ctx(0));
        assert!(g.engaged());
        g
    }

    #[test]
    fn engages_with_valid_axes_and_refuses_others() {
        let mut g = GantrySync::default();
        let mut inp = inputs(2, 3);
        inp.enable = false;
        g.step(&inp, &ctx(0));
        assert_eq!(g.flags(), 0, "not enabled: nothing");
        for (master, slave) in [(1, 1), (4, 0), (0, 4), (7, 7), (8, 0)] {
            let mut g = GantrySync::default();
            g.step(&inputs(master, slave), &ctx(0));
            assert_eq!(g.flags(), flags::REFUSED, "master {master} slave {slave}");
        }
        // 8 + 3 masks to 3: the inputs are 3 bits wide.
        g.step(&inputs(2, 8 + 3), &ctx(0));
        assert_eq!(g.flags(), flags::ENGAGED);
        assert_eq!((g.master(), g.slave(), g.tick_cnt(), g.corr()), (2, 3, 0, 0));
        // While engaged a new master/slave (even an invalid one) has no effect.
        g.step(&inputs(3, 3), &ctx(0));
        assert_eq!((g.flags(), g.master(), g.slave()), (flags::ENGAGED, 2, 3));
    }

    #[test]
    fn refused_and_alarm_clear_with_clear_errors_set_wins() {
        let mut g = GantrySync::default();
        g.step(&inputs(1, 1), &ctx(0));
        assert!(g.refused());
        let clearing = GantryContext { clear_errors: true, ..ctx(0) };
        g.step(&inputs(1, 1), &clearing);
        assert!(g.refused(), "set in the clearing cycle: stays set");
        g.step(&GantryInputs::default(), &clearing);
        assert!(!g.refused());
        // Alarm: error 5 > limit 3.
        let mut inp = inputs(0, 1);
        inp.limit = 3;
        let mut g = engaged(&inp);
        inp.enc_master = 5;
        for _ in 0..3 {
            g.step(&inp, &ctx(0));
        }
        assert!(g.alarm());
        g.step(&inp, &clearing);
        assert!(g.alarm(), "|error| still past the limit: set wins");
        inp.enc_master = 3;
        g.step(&inp, &ctx(0)); // diff 3
        g.step(&inp, &ctx(0)); // error 3 (alarm decided from error 5)
        g.step(&inp, &clearing);
        assert!(!g.alarm(), "|error| = 3 is not past 3: cleared");
    }

    #[test]
    fn disengages_and_zeroes_corr_and_tick() {
        let inp = inputs(0, 1);
        let mut g = engaged(&inp);
        g.step(&inp, &ctx(0));
        g.corr = 1;
        assert_eq!(g.tick_cnt(), 1);
        let off = GantryInputs { enable: false, ..inp };
        g.step(&off, &ctx(0));
        assert!(!g.engaged());
        assert_eq!((g.corr(), g.tick_cnt()), (0, 0));
        assert_eq!(g.corrections(), 0, "the disengaging cycle passes the master's request unchanged");
        assert_eq!(g.shaper_request(1, &[1, -1, 0, 0], &REST, &NO_EXT, &off), -1, "own DDA again");
        // Not engaged: tick_cnt does not count.
        g.step(&off, &ctx(0));
        assert_eq!(g.tick_cnt(), 0);
    }

    #[test]
    fn offset_takes_the_counts_of_the_engaging_cycle() {
        let mut g = GantrySync::default();
        let mut inp = inputs(0, 1);
        inp.enable = false;
        inp.enc_master = 1000;
        inp.enc_slave = 10;
        g.step(&inp, &ctx(0)); // diff 990
        inp.enable = true;
        inp.enc_master = 2000; // this cycle's difference 1990 (the register still 990)
        g.step(&inp, &ctx(0));
        assert_eq!((g.engaged(), g.offset(), g.diff(), g.error()), (true, 1990, 1990, 0));
        g.step(&inp, &ctx(0));
        assert_eq!(g.error(), 0, "square from the engaging cycle on");
        // Wrapping: a channel through 0.
        inp.enc_slave = u32::MAX - 4; // diff 2005 (wrapped)
        g.step(&inp, &ctx(0));
        g.step(&inp, &ctx(0));
        assert_eq!(g.error(), 15);
    }

    #[test]
    fn count_reaches_diff_error_alarm_in_n1_n2_n3() {
        let mut inp = inputs(0, 1);
        inp.limit = 0;
        let mut g = engaged(&inp);
        for _ in 0..3 {
            g.step(&inp, &ctx(0));
        }
        assert_eq!((g.diff(), g.error(), g.alarm()), (0, 0, false));
        // Cycle n: the count changes.
        inp.enc_slave = 1;
        g.step(&inp, &ctx(0));
        assert_eq!((g.diff(), g.error(), g.alarm()), (u32::MAX, 0, false), "n+1");
        g.step(&inp, &ctx(0));
        assert_eq!((g.error(), g.alarm()), (u32::MAX, false), "n+2");
        g.step(&inp, &ctx(0));
        assert!(g.alarm(), "n+3");
    }

    #[test]
    fn alarm_takes_the_unsigned_magnitude() {
        let mut inp = inputs(0, 1);
        inp.limit = u16::MAX;
        let mut g = engaged(&inp);
        g.error = 0x8000_0000; // -2^31: |error| = 2^31, not -2^31
        inp.enc_master = 0x8000_0000; // keeps it there
        g.diff = 0x8000_0000;
        g.step(&inp, &ctx(0));
        assert!(g.alarm());
        let mut g = engaged(&inp);
        g.error = (-i32::from(u16::MAX)) as u32;
        g.diff = g.error;
        inp.enc_master = g.error;
        g.step(&inp, &ctx(0));
        assert!(!g.alarm(), "|error| = limit is not past it");
        g.error = (-i32::from(u16::MAX) - 1) as u32;
        g.step(&inp, &ctx(0));
        assert!(g.alarm());
        // Not engaged: no alarm.
        let mut g = GantrySync { error: 0x8000_0000, ..GantrySync::default() };
        g.step(&GantryInputs::default(), &ctx(0));
        assert!(!g.alarm());
    }

    /// Tick cycles (as indices from the first engaged cycle) over `cycles` cycles.
    fn ticks(tick: u32, cycles: usize) -> Vec<usize> {
        let mut inp = inputs(0, 1);
        inp.tick = tick;
        let mut g = engaged(&inp);
        (0..cycles)
            .filter(|_| {
                let (is_tick, _) = g.tick(inp.tick);
                assert_eq!(is_tick, g.cycles_to_tick(inp.tick) == 0);
                g.step(&inp, &ctx(0));
                is_tick
            })
            .collect()
    }

    #[test]
    fn ticks_every_max_tick_1_cycles() {
        assert_eq!(ticks(0, 4), [0, 1, 2, 3], "0 acts as 1");
        assert_eq!(ticks(1, 4), [0, 1, 2, 3]);
        assert_eq!(ticks(3, 10), [2, 5, 8]);
        assert_eq!(ticks(1 << 24 | 2, 6), [1, 3, 5], "24 bits used");
        let mut g = GantrySync { engaged: true, tick_cnt: TICK_MASK, ..GantrySync::default() };
        assert_eq!(g.cycles_to_tick(5), 0, "past the tick (lowered while engaged): at once");
        g.step(&GantryInputs { enable: true, tick: 5, ..GantryInputs::default() }, &ctx(0));
        assert_eq!(g.tick_cnt(), 0);
    }

    #[test]
    fn the_four_request_cases_and_the_counter() {
        let g = |corr| GantrySync { engaged: true, m: 2, s: 0, corr, ..GantrySync::default() };
        let reqs = |r| [5, 6, r, 7];
        // (corr, master request) -> slave request, applied.
        let cases = [
            (0, 1, 1, false),
            (0, -1, -1, false),
            (0, 0, 0, false),
            (1, 0, 1, true),
            (-1, 0, -1, true),
            (1, -1, 0, true),
            (-1, 1, 0, true),
            (1, 1, 1, false),
            (-1, -1, -1, false),
        ];
        for (corr, r, want, applied) in cases {
            let g = g(corr);
            assert_eq!(g.shaper_request(0, &reqs(r), &REST, &NO_EXT, &ON), want, "corr {corr} r {r}");
            assert_eq!(g.shaper_request(1, &reqs(r), &REST, &NO_EXT, &ON), 6, "other axes: own DDA");
            assert_eq!(g.shaper_request(2, &reqs(r), &REST, &NO_EXT, &ON), r, "the master: own DDA");
            assert_eq!(g.applied(r, 0, ExtMotion::default(), &ON, false), applied);
            let mut next = g;
            let inp = GantryInputs { enable: true, sync: true, tick: 100, ..GantryInputs::default() };
            next.step(&inp, &ctx(r));
            let counted = i16::from(corr) * i16::from(applied);
            assert_eq!(next.corrections(), counted as u16);
            assert_eq!(next.corr(), if applied { 0 } else { corr }, "waits until applied");
        }
        // Not engaged: the slave's own request.
        let off = GantrySync { engaged: false, ..g(1) };
        assert_eq!(off.shaper_request(0, &reqs(1), &REST, &NO_EXT, &ON), 5);
        // The counter wraps both ways.
        let mut w = GantrySync { corrections: u16::MAX, ..g(1) };
        let inp = GantryInputs { enable: true, sync: true, tick: 100, ..GantryInputs::default() };
        w.step(&inp, &ctx(0));
        assert_eq!(w.corrections(), 0);
        w.corr = -1;
        w.step(&inp, &ctx(0));
        assert_eq!(w.corrections(), u16::MAX);
    }

    #[test]
    fn tick_decides_from_error_with_a_signed_unsigned_compare() {
        for (error, deadband, want) in [
            (3, 2, 1),
            (2, 2, 0),
            (-2, 2, 0),
            (-3, 2, -1),
            (i32::MIN, u16::MAX, -1),
            (i32::MAX, u16::MAX, 1),
            (-65535, u16::MAX, 0),
            (-65536, u16::MAX, -1),
            (1, 0, 1),
            (0, 0, 0),
        ] {
            let mut g =
                GantrySync { engaged: true, s: 1, error: error as u32, diff: error as u32, ..GantrySync::default() };
            let inp = GantryInputs {
                enable: true,
                sync: true,
                slave: 1,
                tick: 1,
                deadband,
                limit: u16::MAX,
                enc_master: error as u32,
                ..GantryInputs::default()
            };
            g.step(&inp, &ctx(0));
            assert_eq!(g.corr(), want, "error {error} deadband {deadband}");
        }
    }

    #[test]
    fn a_tick_when_a_correction_is_applied_counts_it_and_loads_the_next() {
        let mut inp = inputs(0, 1);
        inp.tick = 3;
        let mut g = engaged(&inp);
        g.error = 10;
        g.diff = 10;
        inp.enc_master = 10;
        g.corr = 1;
        g.tick_cnt = 1; // not a tick: applied, corr cleared
        g.step(&inp, &ctx(0));
        assert_eq!((g.corr(), g.corrections(), g.tick_cnt()), (0, 1, 2));
        g.corr = 1; // now a tick with an applied correction
        g.step(&inp, &ctx(0));
        assert_eq!((g.corr(), g.corrections(), g.tick_cnt()), (1, 2, 0));
        // A tick while the correction waits (master in its direction): not applied, new
        // decision loaded.
        g.tick_cnt = 2;
        g.step(&inp, &ctx(1));
        assert_eq!((g.corr(), g.corrections()), (1, 2));
        // Waiting across cycles: at most one correction per tick.
        let mut applied = 0;
        for r in [1, 1, 0, 0, 0, 0] {
            let before = g.corrections();
            g.step(&inp, &ctx(r));
            applied += g.corrections() - before;
        }
        assert_eq!(applied, 2, "the waiting one at the tick of cycle 2, that tick's in cycle 3");
    }

    #[test]
    fn halt_forward_mode_and_disengaged_zero_the_correction() {
        let mut inp = inputs(0, 1);
        inp.tick = 1;
        let base = {
            let mut g = engaged(&inp);
            g.error = 10;
            g.diff = 10;
            g
        };
        inp.enc_master = 10;
        let mut g = base;
        g.step(&inp, &ctx(0));
        assert_eq!(g.corr(), 1, "synchronised: +1 at the tick");
        let mut halted = base;
        halted.corr = 1;
        halted.step(&inp, &GantryContext { halt: true, ..ctx(0) });
        assert_eq!(halted.corr(), 0, "halt: no correction");
        assert_eq!(halted.corrections(), 0, "halted: the shaper drops it, so it does not count");
        let mut forward = base;
        forward.step(&GantryInputs { sync: false, ..inp }, &ctx(0));
        assert_eq!((forward.corr(), forward.error()), (0, 10), "forward: measured, not corrected");
    }

    #[test]
    fn forward_mode_copies_the_master_exactly() {
        let inp = GantryInputs { sync: false, tick: 1, enc_master: 1000, ..inputs(3, 0) };
        let mut g = engaged(&inp);
        let mut reqs = [0i8; N];
        for k in 0..200u32 {
            reqs[3] = [0, 1, -1, 1, 0, 0, -1][(k % 7) as usize];
            reqs[0] = -reqs[3];
            assert_eq!(g.shaper_request(0, &reqs, &REST, &NO_EXT, &inp), reqs[3]);
            g.step(&inp, &ctx(reqs[3]));
            assert_eq!(g.corr(), 0);
        }
        assert!(g.error() == 1000 && g.alarm(), "the error is still measured");
        assert_eq!(g.corrections(), 0);
    }

    #[test]
    fn clear_counters_wins_over_an_applied_correction() {
        let inp = inputs(0, 1);
        let mut g = engaged(&inp);
        g.corrections = 7;
        g.corr = -1;
        g.step(&GantryInputs { clear_counters: true, ..inp }, &ctx(0));
        assert_eq!((g.corrections(), g.corr()), (0, 0));
        // clear_errors does not touch the counter; clear_counters not the flags.
        g.refused = true;
        g.step(&GantryInputs { clear_counters: true, ..inp }, &ctx(0));
        assert!(g.refused());
        g.corrections = 7;
        g.step(&inp, &GantryContext { clear_errors: true, ..ctx(0) });
        assert_eq!((g.corrections(), g.refused()), (7, false));
    }

    #[test]
    fn against_the_motion_a_correction_deletes_a_master_step_instead_of_reversing() {
        // Master axis 2 moving up (increment > 0), slave axis 0 ahead: corr = -1.
        let g = GantrySync { engaged: true, m: 2, s: 0, corr: -1, ..GantrySync::default() };
        let mut inc = REST;
        inc[2] = 1000;
        assert!(!g.takes(0, inc[2], ExtMotion::default(), true, true), "no reverse step while the master moves up");
        assert_eq!(g.shaper_request(0, &[0, 0, 0, 0], &inc, &NO_EXT, &ON), 0);
        assert_eq!(g.shaper_request(0, &[0, 0, 1, 0], &inc, &NO_EXT, &ON), 0, "the next master step is deleted");
        assert!(g.takes(1, inc[2], ExtMotion::default(), true, true));
        // With the motion (corr = +1 while moving up): inserted between master steps.
        let with = GantrySync { corr: 1, ..g };
        assert_eq!(with.shaper_request(0, &[0, 0, 0, 0], &inc, &NO_EXT, &ON), 1);
        // At rest either way is an insertion.
        assert_eq!(g.shaper_request(0, &[0, 0, 0, 0], &REST, &NO_EXT, &ON), -1);
        // Forward mode, a disabled pair or an alarm: the master's request unchanged.
        assert_eq!(g.shaper_request(0, &[0, 0, 1, 0], &inc, &NO_EXT, &GantryInputs { sync: false, ..ON }), 1);
        assert_eq!(g.shaper_request(0, &[0, 0, 1, 0], &inc, &NO_EXT, &GantryInputs { enable: false, ..ON }), 1);
        let alarmed = GantrySync { alarm: true, ..g };
        assert_eq!(alarmed.shaper_request(0, &[0, 0, 1, 0], &inc, &NO_EXT, &ON), 1);
    }

    #[test]
    fn the_alarm_stops_the_corrections_and_engagement_waits_for_rest() {
        let inp = GantryInputs { master: 1, slave: 0, tick: 1, enc_master: 400, enc_slave: 100, ..ON };
        // Engagement waits while either axis has an increment; the offset is this cycle's.
        let mut g = GantrySync::default();
        let mut moving = ctx(0);
        moving.inc[0] = -5;
        g.step(&inp, &moving);
        assert!(!g.engaged() && !g.refused(), "waits, not refused");
        g.step(&inp, &ctx(0));
        assert!(g.engaged());
        assert_eq!(g.offset, 300, "the counts of the engaging cycle");
        // An alarm: no correction is decided or applied while it is set.
        let mut alarmed = GantrySync { alarm: true, error: 50, corr: 1, ..g };
        alarmed.step(&GantryInputs { limit: 1000, ..inp }, &ctx(0));
        assert_eq!((alarmed.corr(), alarmed.corrections()), (0, 0));
    }

    #[test]
    fn a_pbp_record_on_either_axis_holds_engagement_and_its_direction_is_the_masters_motion() {
        let inp = GantryInputs { master: 2, slave: 0, tick: 1, ..ON };
        // The slave's or the master's pair busy (even without a direction: a line's axis
        // of zero coordinate): no engagement; free again, it engages.
        for (axis, e) in [
            (0, ExtMotion { busy: true, ..ExtMotion::default() }),
            (2, ExtMotion { busy: true, up: true, down: false }),
        ] {
            let mut g = GantrySync::default();
            let mut held = ctx(0);
            held.ext[axis] = e;
            g.step(&inp, &held);
            assert!(!g.engaged() && !g.refused(), "axis {axis} busy: waits");
            g.step(&inp, &ctx(0));
            assert!(g.engaged());
        }
        // Another pair's record does not hold it.
        let mut g = GantrySync::default();
        let mut other = ctx(0);
        other.ext[1] = ExtMotion { busy: true, up: true, down: false };
        g.step(&inp, &other);
        assert!(g.engaged());
        // Engaged, the master moving down by pbp (zero increment): +1 waits to delete a
        // master step, -1 goes in; up: the other way round; busy without a direction: both.
        let g = GantrySync { engaged: true, m: 2, s: 0, corr: 1, ..GantrySync::default() };
        let down = ExtMotion { busy: true, up: false, down: true };
        let up = ExtMotion { busy: true, up: true, down: false };
        let busy = ExtMotion { busy: true, up: false, down: false };
        for (e, plus, minus) in [(down, false, true), (up, true, false), (busy, true, true)] {
            assert_eq!(g.takes(0, 0, e, true, true), plus, "{e:?} +1");
            assert_eq!(GantrySync { corr: -1, ..g }.takes(0, 0, e, true, true), minus, "{e:?} -1");
        }
        let mut ext = NO_EXT;
        ext[2] = down;
        assert_eq!(g.shaper_request(0, &[0, 0, 0, 0], &REST, &ext, &ON), 0, "waits");
        assert_eq!(g.shaper_request(0, &[0, 0, -1, 0], &REST, &ext, &ON), 0, "the master's step deleted");
        // The applied count follows the same rule.
        let mut w = g;
        let mut c = ctx(0);
        c.ext[2] = down;
        w.step(&GantryInputs { tick: 100, ..inp }, &c);
        assert_eq!((w.corr(), w.corrections()), (1, 0), "not applied against the pbp motion");
    }
}

//! `step_shaper`: turns an axis's step requests into pulses with the drive's timing.
//!
//! Specification: docs/spec/step_shaper.md
//!
//! Requests add to `pending`; a pulse (`level` high exactly `L` clocks) is started when
//! the level has been low at least `S` clocks and `dir` has been stable at least `U`
//! clocks; `dir` changes only while low and at least `H` clocks after the fall. The pins
//! are registered from the state (one clock behind it).
//!
//! While `halt` (the safety monitor's) is 1 no pulse starts and `dir` holds, a pulse
//! already high still lasts its full `L` (a drive never sees a runt pulse), `pending` is
//! dropped without flagging `rate_error` or `step_lost`, and the enable pin goes
//! inactive in the next cycle.

use crate::config::{mode, AxisSettings};

/// State of one step shaper.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StepShaper {
    pub(crate) pending: i8,
    pub(crate) level: bool,
    pub(crate) dir: bool,
    pub(crate) cnt: u32,
    pub(crate) dcnt: u32,
    pub(crate) quad: u8,
    pub(crate) position: u32,
    pub(crate) rate_error: bool,
    pub(crate) step_lost: bool,
    /// Registered pins: bit 0 pin A, bit 1 pin B, bit 2 the enable pin.
    pub(crate) pins: u8,
}

/// Limit of `|pending|`.
pub(crate) const PENDING_MAX: i32 = 127;

/// Pin bits of [`StepShaper::pins`].
pub(crate) const PIN_A: u8 = 1 << 0;
pub(crate) const PIN_B: u8 = 1 << 1;
pub(crate) const PIN_EN: u8 = 1 << 2;

/// The enable pin bit ([`PIN_EN`]) for `set`: `(axis_enable && !halt) ^ invert[2]`.
#[inline]
pub(crate) fn enable_pin(set: &AxisSettings) -> u8 {
    (u8::from(set.enable) * PIN_EN) ^ (set.invert & PIN_EN)
}

/// What one edge of a shaper decides: `e = pending + r`, and whether the step level
/// falls, rises, or `dir` turns (at most one of them).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Decision {
    pub(crate) e: i32,
    pub(crate) rise: bool,
    pub(crate) fall: bool,
    pub(crate) turn: bool,
}

impl StepShaper {
    /// The reset state: no pending step, level low, `dir` positive, both counters all
    /// ones (`counter_max`), position 0, flags and pins 0.
    pub fn new(counter_max: u32) -> Self {
        StepShaper {
            pending: 0,
            level: false,
            dir: true,
            cnt: counter_max,
            dcnt: counter_max,
            quad: 0,
            position: 0,
            rate_error: false,
            step_lost: false,
            pins: 0,
        }
    }

    /// Requests not yet output (positive: steps in the positive direction).
    pub fn pending(&self) -> i8 {
        self.pending
    }

    /// The internal step level.
    pub fn level(&self) -> bool {
        self.level
    }

    /// The internal direction (true = positive).
    pub fn dir(&self) -> bool {
        self.dir
    }

    /// Cycles the current level has lasted, this one included (saturating).
    pub fn cnt(&self) -> u32 {
        self.cnt
    }

    /// Cycles since `dir` last changed, this one included (saturating).
    pub fn dcnt(&self) -> u32 {
        self.dcnt
    }

    /// The quadrature phase 0..=3.
    pub fn quad(&self) -> u8 {
        self.quad
    }

    /// Steps output, two's complement, wrapping.
    pub fn position(&self) -> u32 {
        self.position
    }

    /// Sticky: the pulse train fell behind the DDA (`|pending + req| >= 2`).
    pub fn rate_error(&self) -> bool {
        self.rate_error
    }

    /// Sticky: `pending` overflowed and a step was lost.
    pub fn step_lost(&self) -> bool {
        self.step_lost
    }

    /// The pins (A, B, enable) in this cycle.
    pub fn pins(&self) -> (bool, bool, bool) {
        (self.pins & PIN_A != 0, self.pins & PIN_B != 0, self.pins & PIN_EN != 0)
    }

    /// The pin bits the next cycle shows for the current state and settings.
    #[inline]
    pub(crate) fn next_pins(&self, set: &AxisSettings) -> u8 {
        self.step_pins(set) | enable_pin(set)
    }

    /// Pins A and B (the bits [`PIN_A`], [`PIN_B`]) for the state's `level`, `dir` and
    /// `quad` in the mode and with the inversion of `set` (the table of the spec).
    #[inline]
    pub(crate) fn step_pins(&self, set: &AxisSettings) -> u8 {
        let (a, b) = match set.mode {
            mode::UP_DOWN => (self.level && self.dir, self.level && !self.dir),
            // quad 0..3 -> A 0,1,1,0 and B 0,0,1,1.
            mode::QUADRATURE => ((self.quad ^ (self.quad >> 1)) & 1 != 0, self.quad & 2 != 0),
            _ => (self.level, self.dir),
        };
        ((u8::from(a) * PIN_A) | (u8::from(b) * PIN_B)) ^ (set.invert & (PIN_A | PIN_B))
    }

    /// The decisions of one edge for the request `r` (docs/spec/step_shaper.md): `e`, and
    /// whether the level falls, rises or `dir` turns. `reached(count, x)` is the
    /// counter compare `cnt >= x` (and `dcnt >= x`): `count >= x` for a shaper of its
    /// own, `count * S >= x` for the [step engine](crate::step_engine), whose counters
    /// count visits of `S` clocks.
    #[inline(always)]
    pub(crate) fn decide(&self, r: i8, set: &AxisSettings, reached: impl Fn(u32, u32) -> bool) -> Decision {
        let e = i32::from(self.pending) + i32::from(r);
        let mut d = Decision { e, rise: false, fall: false, turn: false };
        if self.level {
            d.fall = reached(self.cnt, set.timing.step_len);
        } else if set.halt {
            // Halted: only a running pulse may end.
        } else if e != 0 {
            if (e > 0) == self.dir {
                d.rise = reached(self.cnt, set.timing.step_space) && reached(self.dcnt, set.timing.dir_setup);
            } else {
                d.turn = reached(self.cnt, set.timing.dir_hold);
            }
        }
        d
    }

    /// The next state after the decisions `d` (everything but the pins): level,
    /// counters, direction, `pending` (zeroed when `halt`), position, quadrature phase
    /// and the sticky flags, `clear` clearing them (a set wins).
    #[inline(always)]
    pub(crate) fn apply(&mut self, d: Decision, halt: bool, counter_max: u32, clear: bool) {
        let step: i32 = match (d.rise, self.dir) {
            (false, _) => 0,
            (true, true) => 1,
            (true, false) => -1,
        };
        if d.rise || d.fall {
            self.level = d.rise;
            self.cnt = 1;
        } else if self.cnt < counter_max {
            self.cnt += 1;
        }
        if d.turn {
            self.dir = !self.dir;
            self.dcnt = 1;
        } else if self.dcnt < counter_max {
            self.dcnt += 1;
        }
        self.position = self.position.wrapping_add_signed(step);
        self.quad = (i32::from(self.quad) + step) as u8 & 0b11;
        if halt {
            // The dropped requests flag nothing.
            self.pending = 0;
            self.clear_flags(clear);
        } else {
            let left = d.e - step;
            let kept = left.clamp(-PENDING_MAX, PENDING_MAX);
            self.pending = kept as i8;
            self.rate_error = d.e.abs() >= 2 || (self.rate_error && !clear);
            self.step_lost = kept != left || (self.step_lost && !clear);
        }
    }

    /// `clear_errors` in a cycle that sets no flag.
    #[inline(always)]
    pub(crate) fn clear_flags(&mut self, clear: bool) {
        self.rate_error &= !clear;
        self.step_lost &= !clear;
    }

    /// One rising edge: `r` is the DDA's request in this cycle, `counter_max` the
    /// saturation value of `cnt` and `dcnt`, `set.halt` the core's `halt`. Returns
    /// whether an output (pins, flags, position) changed.
    #[inline]
    pub(crate) fn step(&mut self, r: i8, set: &AxisSettings, counter_max: u32, clear: bool) -> bool {
        let outputs_before = self.output_bits();
        self.pins = self.next_pins(set);
        let d = self.decide(r, set, |count, x| count >= x);
        self.apply(d, set.halt, counter_max, clear);
        d.rise || self.output_bits() != outputs_before
    }

    /// Pins and flags in one word, to see whether they changed.
    #[inline]
    pub(crate) fn output_bits(&self) -> u8 {
        self.pins | (u8::from(self.rate_error) << 3) | (u8::from(self.step_lost) << 4)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn settings(l: u32, s: u32, u: u32, h: u32) -> AxisSettings {
        AxisSettings { timing: crate::DriveTiming::new(l, s, u, h), ..AxisSettings::default() }
    }

    /// Runs the shaper over a request sequence and returns (level, dir) per cycle.
    fn trace(set: &AxisSettings, reqs: &[i8]) -> Vec<(bool, bool)> {
        let mut sh = StepShaper::new(15);
        reqs.iter()
            .map(|&r| {
                sh.step(r, set, 15, false);
                (sh.level(), sh.dir())
            })
            .collect()
    }

    #[test]
    fn pulse_is_l_high_and_s_low() {
        let set = settings(2, 3, 1, 1);
        let levels: Vec<bool> = trace(&set, &[1, 1, 0, 0, 0, 0, 0, 0]).iter().map(|x| x.0).collect();
        // rise decided at 0, high 2 cycles, low 3 cycles, second rise decided at 5.
        assert_eq!(levels, [true, true, false, false, false, true, true, false]);
    }

    #[test]
    fn reversal_waits_for_fall_hold_and_setup() {
        let set = settings(1, 1, 2, 3);
        let t = trace(&set, &[1, -1, 0, 0, 0, 0, 0, 0, 0]);
        // State after each edge. Edge 0: rise (+). 1: fall (the -1 waits). 2, 3: cnt 1, 2
        // < H. 4: cnt 3 >= H, turn. 5: dcnt 1 < U. 6: dcnt 2 >= U, rise (-).
        let want = [
            (true, true),
            (false, true),
            (false, true),
            (false, true),
            (false, false),
            (false, false),
            (true, false),
            (false, false),
            (false, false),
        ];
        assert_eq!(t, want);
    }

    #[test]
    fn opposite_requests_cancel() {
        let set = settings(4, 4, 1, 1);
        let mut sh = StepShaper::new(15);
        sh.step(1, &set, 15, false);
        sh.step(1, &set, 15, false);
        assert_eq!(sh.pending(), 1);
        sh.step(-1, &set, 15, false);
        assert_eq!(sh.pending(), 0);
        assert_eq!(sh.position(), 1);
        assert!(!sh.rate_error(), "|pending + req| never reached 2");
        sh.step(1, &set, 15, false);
        sh.step(1, &set, 15, false);
        assert!(sh.rate_error(), "pending 1 plus a request: behind the DDA");
    }

    #[test]
    fn pending_saturates_and_sets_step_lost() {
        let set = settings(15, 15, 1, 1);
        let mut sh = StepShaper::new(15);
        for _ in 0..200 {
            sh.step(1, &set, 15, false);
        }
        assert_eq!(sh.pending(), 127);
        assert!(sh.step_lost() && sh.rate_error());
        sh.step(0, &set, 15, true);
        assert!(!sh.step_lost(), "cleared");
        assert!(sh.rate_error(), "set again in the clearing cycle: set wins");
    }

    #[test]
    fn halt_finishes_the_pulse_drops_pending_and_the_enable() {
        let run = AxisSettings { enable: true, ..settings(4, 1, 1, 1) };
        let halted = AxisSettings { halt: true, enable: false, ..run };
        let mut sh = StepShaper::new(15);
        sh.step(1, &run, 15, false);
        sh.step(1, &run, 15, false);
        sh.step(1, &run, 15, false);
        assert!(sh.level() && sh.pending() == 2 && sh.rate_error());
        // Halted from the pulse's third cycle on: it still lasts L = 4 cycles.
        let mut levels = vec![];
        for _ in 0..4 {
            sh.step(-1, &halted, 15, true);
            levels.push(sh.level());
        }
        assert_eq!(levels, [true, false, false, false]);
        assert_eq!((sh.pending(), sh.position(), sh.dir()), (0, 1, true));
        assert!(!sh.rate_error() && !sh.step_lost(), "cleared; the dropped steps flag nothing");
        assert_eq!(sh.pins & PIN_EN, 0, "enable inactive while halted");
        sh.step(0, &run, 15, false);
        assert_eq!(sh.pins & PIN_EN, PIN_EN);
    }

    #[test]
    fn pins_follow_the_mode_one_cycle_late() {
        let mut sh = StepShaper::new(15);
        sh.level = true;
        sh.dir = false;
        sh.quad = 2;
        let base = settings(1, 1, 1, 1);
        let with = |mode, invert| AxisSettings { mode, invert, enable: true, ..base };
        assert_eq!(sh.next_pins(&with(0, 0)), PIN_A | PIN_EN);
        assert_eq!(sh.next_pins(&with(3, 0)), PIN_A | PIN_EN);
        assert_eq!(sh.next_pins(&with(1, 0)), PIN_B | PIN_EN);
        assert_eq!(sh.next_pins(&with(2, 0)), PIN_A | PIN_B | PIN_EN);
        assert_eq!(sh.next_pins(&with(0, 7)), PIN_B);
        for (quad, a, b) in [(0, false, false), (1, true, false), (2, true, true), (3, false, true)] {
            sh.quad = quad;
            let pins = sh.next_pins(&with(2, 0));
            assert_eq!((pins & PIN_A != 0, pins & PIN_B != 0), (a, b));
        }
    }
}

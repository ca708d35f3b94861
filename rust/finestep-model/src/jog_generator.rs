//! `jog_generator`: moves one axis after the hand wheel, through the core.
//!
//! Specification: docs/spec/jog_generator.md (`jog_velocity` is its "Computation")
//!
//! The jog's increments are ordinary period records (the jog offers one at every
//! boundary while engaged), so the DDA, the step shaper's timing, the rate checks and
//! `POSITION` work exactly as for streamed motion; the jog and a FIFO run never both
//! drive the core (`CONTROL.RUN` is forced to 0 while engaged, and `ENABLE` with `RUN`
//! is refused).
//!
//! Units: positions (`target`, `cmd`) in 1/65536 step, 48-bit two's complement;
//! velocities (`vel`, `next_vel`) in I16F16 steps per period. Each detent moves
//! `target`; the velocity follows it under the limits `|next_vel - vel| <= A` and
//! `|next_vel| <= max(VM, |vel|)`. The next period's velocity is computed once per
//! period, from the state in the cycle after a boundary, and is ready 80 clocks later
//! (the latency of a serial square root in the RTL): a period of 81 clocks or more
//! always gets a fresh value, a shorter one holds the speed.

use crate::record::PeriodRecord;
use crate::Increment;

/// Jogging needs `PERIOD_CLOCKS >= 128`, so every period outlasts the computation.
pub const MIN_PERIOD_CLOCKS: u32 = 128;

/// The computation writes `next_vel` at the edge ending cycle `b + LATENCY` after a
/// boundary `b`.
pub const LATENCY: u32 = 80;

/// Width of `target` and `cmd` (1/65536 step).
pub const POSITION_BITS: u32 = 48;

/// `|e|` saturates here in the square root's argument (only lowering the speed), so the
/// product `2 * A * |e|` fits 72 bits.
pub const DISTANCE_SATURATION: u64 = (1 << 40) - 1;

/// `x` wrapped to a 48-bit two's complement value.
pub fn wrap48(x: i64) -> i64 {
    (x << (64 - POSITION_BITS)) >> (64 - POSITION_BITS)
}

/// `m` of `JOG_CONTROL.MULTIPLIER`: 1, 10, 100, and 100 for 3 (the interface's
/// `JOG_MULTIPLIER`).
pub fn multiplier(bits: u32) -> i64 {
    i64::from(finestep_interface::JogMultiplier::from_bits(bits).factor())
}

/// Integer square root, `floor(sqrt(n))`.
pub fn isqrt(n: u128) -> u128 {
    if n < 2 {
        return n;
    }
    // Newton from above: start at a power of two not below the root.
    let bits = 128 - n.leading_zeros();
    let mut x = 1u128 << bits.div_ceil(2);
    loop {
        let y = (x + n / x) / 2;
        if y >= x {
            return x;
        }
        x = y;
    }
}

/// The computation: the next period's velocity `v'` from the distance to go
/// `e = target - cmd` (after the current period), the current velocity `vel`, `EN`,
/// `VM = JOG_VMAX` and `A = JOG_ACCEL`.
///
/// Stopping (`!EN`) brakes towards 0 at `A`. Otherwise, if the rest of the way fits in
/// one period and the axis can stop after it (`|e| <= min(VM, A)`, `|e - vel| <= A`), it
/// is taken (`v' = e`); else the speed heads for
/// `u = max(isqrt(2 A min(|e|, 2^40 - 1)) - A, min(|e|, A))`, the largest from which the
/// axis can still stop within `|e|` braking at `A` per period (never below the last
/// step's size, so short moves finish), capped at `VM`, changing by at most `A`.
pub fn next_velocity(e: i64, vel: i32, enable: bool, vmax: u32, accel: u32) -> i32 {
    let a = i64::from(accel);
    let vm = i64::from(vmax);
    let vel = i64::from(vel);
    let clamp = |x: i64| x.min(vel + a).max(vel - a);
    let v = if !enable {
        clamp(0)
    } else if e.abs() <= vm.min(a) && (e - vel).abs() <= a {
        e
    } else {
        let distance = e.unsigned_abs().min(DISTANCE_SATURATION);
        let root = isqrt(2 * u128::from(accel) * u128::from(distance)) as i64;
        let u = (root - a).max(e.abs().min(a));
        clamp(e.signum() * vm.min(u))
    };
    // Every branch lands within [-2^31, 2^31): |e| <= VM, or between `vel` and a value
    // of magnitude <= VM.
    v as i32
}

/// The jog's settings and inputs from the rest of the top in one cycle.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct JogInputs {
    /// `JOG_CONTROL.ENABLE` (`EN`).
    pub enable: bool,
    /// `JOG_CONTROL.AXIS`.
    pub axis: u8,
    /// `JOG_CONTROL.MULTIPLIER` (2 bits).
    pub multiplier: u8,
    /// `JOG_CONTROL.FOLLOW`.
    pub follow: bool,
    /// `JOG_SCALE`: I16F16 steps per detent at x1.
    pub scale: i32,
    /// `JOG_VMAX` (`VM`).
    pub vmax: u32,
    /// `JOG_ACCEL` (`A`).
    pub accel: u32,
    /// `JOG_WINDOW`: whole steps.
    pub window: u16,
    /// `CONTROL.RUN`.
    pub run: bool,
    /// The safety monitor's `halt`.
    pub halt: bool,
    /// `PERIOD_CLOCKS` (as stored, `P_WIDTH` bits).
    pub period_clocks: u32,
    /// `N_AXES`.
    pub n_axes: usize,
    /// `MPG_DETENTS`.
    pub detents: i32,
    /// The core's `rec_ready`.
    pub rec_ready: bool,
    /// A write of `CONTROL` with `RUN = 1` is served in this cycle.
    pub run_written: bool,
    /// `clear_errors` pulse: clears `REFUSED` (a set wins).
    pub clear_errors: bool,
    /// `clear_counters` pulse: zeroes `DROPPED` (wins).
    pub clear_counters: bool,
}

/// The jog's register view.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct JogStatus {
    /// `JOG_STATUS.ENGAGED`.
    pub engaged: bool,
    /// `JOG_STATUS.STOPPING`: engaged with `ENABLE` 0.
    pub stopping: bool,
    /// `JOG_STATUS.REFUSED`.
    pub refused: bool,
    /// `JOG_STATUS.DROPPED`.
    pub dropped: u16,
    /// `JOG_REMAINING`: `(target - cmd)[47:16]`.
    pub remaining: u32,
    /// `JOG_VELOCITY`: `vel`.
    pub velocity: u32,
}

/// State of the jog generator.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct JogGenerator {
    engaged: bool,
    axis: u8,
    target: i64,
    cmd: i64,
    vel: i32,
    next_vel: i32,
    last_det: i32,
    dropped: u16,
    refused: bool,
    /// Cycles since the boundary that started the computation (1 in `b + 1`); 0: none
    /// runs.
    comp_age: u32,
    /// The computation's result, taken from the state of `b + 1`.
    comp_result: i32,
    /// `m * JOG_SCALE` and `JOG_WINDOW * 65536` of the previous cycle (the first of the
    /// two registers the detent configuration passes).
    travel_cfg: i64,
    window_cfg: i64,
    /// The travel and window a detent uses: the configuration of two cycles before.
    travel: i64,
    window: i64,
}

impl JogGenerator {
    /// The jog drives the core.
    pub fn engaged(&self) -> bool {
        self.engaged
    }

    /// The axis moved (taken at engagement).
    pub fn axis(&self) -> usize {
        usize::from(self.axis)
    }

    /// Where the wheel wants the axis, 1/65536 step (48-bit).
    pub fn target(&self) -> i64 {
        self.target
    }

    /// The sum of the records taken since engagement, 1/65536 step (48-bit).
    pub fn cmd(&self) -> i64 {
        self.cmd
    }

    /// The increment of the current period.
    pub fn vel(&self) -> i32 {
        self.vel
    }

    /// The increment the next boundary takes.
    pub fn next_vel(&self) -> i32 {
        self.next_vel
    }

    /// `detents` of the previous cycle.
    pub fn last_det(&self) -> i32 {
        self.last_det
    }

    /// `DROPPED`.
    pub fn dropped(&self) -> u16 {
        self.dropped
    }

    /// Sticky `REFUSED`.
    pub fn refused(&self) -> bool {
        self.refused
    }

    /// `rec_valid` towards the core: the jog offers a record while engaged.
    pub fn rec_valid(&self) -> bool {
        self.engaged
    }

    /// The record offered: `next_vel` on the jogged axis, 0 elsewhere, flags 0.
    pub fn record(&self) -> PeriodRecord {
        // `axis` is 3 bits and below N_AXES <= MAX_AXES.
        let mut record = PeriodRecord::default();
        record.inc[self.axis()] = Increment::from_bits(self.next_vel);
        record
    }

    /// The register view with this cycle's `ENABLE`.
    pub fn status(&self, enable: bool) -> JogStatus {
        JogStatus {
            engaged: self.engaged,
            stopping: self.engaged && !enable,
            refused: self.refused,
            dropped: self.dropped,
            remaining: (wrap48(self.target - self.cmd) >> 16) as u32,
            velocity: self.vel as u32,
        }
    }

    /// One rising clock edge.
    pub fn step(&mut self, inp: &JogInputs) {
        let en = inp.enable;
        let delta = inp.detents.wrapping_sub(self.last_det);
        self.last_det = inp.detents;
        let can_engage = inp.period_clocks >= MIN_PERIOD_CLOCKS && usize::from(inp.axis) < inp.n_axes;

        let refuse = (en && inp.run) || (en && !self.engaged && !can_engage) || (inp.run_written && self.engaged);
        self.refused = refuse || (self.refused && !inp.clear_errors);
        let mut dropped = false;

        if inp.halt {
            self.engaged = false;
            self.clear_motion();
        } else if !self.engaged {
            if en && !inp.run && can_engage {
                self.engaged = true;
                self.axis = inp.axis;
                self.clear_motion();
            }
        } else {
            // The computation samples the state of b + 1, before this edge's updates.
            if self.comp_age == 1 {
                let e = wrap48(self.target - self.cmd);
                self.comp_result = next_velocity(e, self.vel, en, inp.vmax, inp.accel);
            }

            // Follow: a detent moves the target, or is dropped in drop mode.
            if en && delta != 0 {
                let step = i64::from(delta.signum()) * self.travel;
                let cand = wrap48(self.target + step);
                if inp.follow || wrap48(cand - self.cmd).abs() <= self.window {
                    self.target = cand;
                } else {
                    dropped = true;
                }
            }

            if inp.rec_ready {
                // Boundary: the core takes next_vel; a result due at this very edge
                // (a period of 80 clocks or fewer) is discarded and the speed held.
                let stop = !en && self.vel == 0 && self.next_vel == 0;
                self.cmd = wrap48(self.cmd + i64::from(self.next_vel));
                self.vel = self.next_vel;
                if stop {
                    self.engaged = false;
                    self.comp_age = 0;
                } else {
                    self.comp_age = 1;
                }
            } else if self.comp_age == LATENCY {
                self.next_vel = self.comp_result;
                self.comp_age = 0;
            } else if self.comp_age != 0 {
                self.comp_age += 1;
            }
        }

        self.dropped = if inp.clear_counters { 0 } else { self.dropped.wrapping_add(u16::from(dropped)) };
        self.travel = self.travel_cfg;
        self.window = self.window_cfg;
        self.travel_cfg = multiplier(inp.multiplier.into()) * i64::from(inp.scale);
        self.window_cfg = i64::from(inp.window) << 16;
    }

    /// `target, cmd, vel, next_vel <- 0`, the computation dropped.
    fn clear_motion(&mut self) {
        self.target = 0;
        self.cmd = 0;
        self.vel = 0;
        self.next_vel = 0;
        self.comp_age = 0;
        self.comp_result = 0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn isqrt_is_the_floor_of_the_root() {
        for n in 0..10_000u128 {
            let r = isqrt(n);
            assert!(r * r <= n && (r + 1) * (r + 1) > n, "isqrt({n}) = {r}");
        }
        let big = (1u128 << 72) - 1;
        let r = isqrt(big);
        assert!(r * r <= big && (r + 1) * (r + 1) > big);
        assert_eq!(isqrt(u128::MAX), u128::from(u64::MAX));
    }

    #[test]
    fn the_computation_arrives_brakes_and_heads_for_u() {
        // Arrive: the rest fits in one period and the axis can stop after it.
        assert_eq!(next_velocity(15, 10, true, 1000, 20), 15);
        // Not from above A: 100 away at 90 is no last step, u = max(63 - 20, 20) = 43.
        assert_eq!(next_velocity(100, 90, true, 1000, 20), 70);
        // A short move with VM below it still goes: u = max(isqrt(2 * 20 * 15) - 20, 15).
        assert_eq!(next_velocity(15, 0, true, 10, 20), 10);
        // Stopping brakes towards 0.
        assert_eq!(next_velocity(1 << 30, 500, false, 1000, 20), 480);
        assert_eq!(next_velocity(1 << 30, -10, false, 1000, 20), 0);
        // Far away from rest: accelerate by A.
        assert_eq!(next_velocity(1 << 30, 0, true, 1000, 20), 20);
        // Cruising at VM far away: hold VM.
        assert_eq!(next_velocity(-(1 << 40), -1000, true, 1000, 20), -1000);
        // u = isqrt(2 * 20 * 1000) - 20 = 200 - 20 = 180: brake from 300 by A.
        assert_eq!(next_velocity(1000, 300, true, 1000, 20), 280);
        assert_eq!(next_velocity(1000, 190, true, 1000, 20), 180);
    }

    fn engaged_inputs() -> JogInputs {
        JogInputs {
            enable: true,
            scale: 65536,
            vmax: 65536,
            accel: 4096,
            window: 1000,
            period_clocks: 200,
            n_axes: 4,
            axis: 2,
            ..Default::default()
        }
    }

    #[test]
    fn a_detent_uses_the_configuration_of_two_cycles_before() {
        let mut jog = JogGenerator::default();
        let mut inp = engaged_inputs();
        jog.step(&inp);
        jog.step(&inp);
        inp.multiplier = 1; // x10, written now: the next detent still moves x1
        inp.detents = 1;
        jog.step(&inp);
        assert_eq!(jog.target(), 65536);
        inp.detents = 2;
        jog.step(&inp);
        assert_eq!(jog.target(), 2 * 65536, "one cycle after the write: still x1");
        inp.detents = 3;
        jog.step(&inp);
        assert_eq!(jog.target(), 12 * 65536, "two cycles after: x10");
    }

    #[test]
    fn engages_only_when_allowed_and_refuses_otherwise() {
        let mut jog = JogGenerator::default();
        let short = JogInputs { period_clocks: 127, ..engaged_inputs() };
        jog.step(&short);
        assert!(!jog.engaged() && jog.refused());
        jog.step(&JogInputs { clear_errors: true, ..engaged_inputs() });
        assert!(jog.engaged() && !jog.refused() && jog.axis() == 2);
        assert_eq!(jog.record(), PeriodRecord::default());
        jog.step(&JogInputs { run_written: true, ..engaged_inputs() });
        assert!(jog.refused(), "RUN written while engaged");
        jog.step(&JogInputs { halt: true, ..engaged_inputs() });
        assert!(!jog.engaged());
    }

    #[test]
    fn the_result_lands_80_clocks_after_the_cycle_after_the_boundary() {
        let mut jog = JogGenerator::default();
        let mut inp = engaged_inputs();
        jog.step(&inp);
        jog.step(&inp); // the configuration reaches the detents two cycles after it is set
        inp.detents = 1;
        jog.step(&inp);
        inp.rec_ready = true;
        jog.step(&inp); // boundary b
        inp.rec_ready = false;
        assert_eq!(jog.target(), 65536);
        for cycle in 1..=LATENCY {
            assert_eq!(jog.next_vel(), 0, "b + {cycle}");
            jog.step(&inp);
        }
        assert_eq!(jog.next_vel(), 4096, "written at the edge ending b + 80");
    }
}

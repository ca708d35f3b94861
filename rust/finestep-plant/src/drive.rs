//! A drive following one axis's step pulses: an exact commanded position and a
//! mechanical (actual) position that is either the commanded one or lags it.
//!
//! # Input
//!
//! Per cycle the drive sees the axis's pin A and pin B (after its own optional
//! inversion). [`StepInput::StepDir`]: a rising edge of A is one step, in the direction
//! B has in that cycle (1 = positive). [`StepInput::UpDown`]: a rising A is +1, a rising
//! B is -1. [`StepInput::Quadrature`]: a Gray step of (A, B) is +1 or -1 (A leading B is
//! positive), both changing at once is counted in [`Drive::illegal_inputs`] and ignored.
//! An edge seen in cycle `t` moves the commanded position from cycle `t + 1` on.
//!
//! # The lag, exactly
//!
//! [`Mechanics::Lag`] with time constant `tau` cycles is the discrete first-order lag
//! `x[n+1] = x[n] + (c[n] - x[n]) / tau`: each cycle the actual position `x` covers
//! `1/tau` of the following error `e = c - x` (the continuous lag with time constant
//! `-1/ln(1 - 1/tau)`, about `tau - 1/2` cycles). Between commanded changes the error
//! decays as `e[n] = e[a] * r^(n - a)` with `r = 1 - 1/tau`, so the drive keeps only
//! an anchor (cycle `a`, commanded position, error) and evaluates any cycle from it in
//! closed form: `r^k` by binary powering, IEEE multiplications only, so the result is
//! bit-identical on every platform and independent of how the cycles were stepped. A
//! step moves the anchor: `e[a'] = e[a] * r^(a' - a) + delta`. An error below
//! [`SETTLED`] steps counts as 0: the axis comes to rest exactly on the commanded
//! position (some 22 + ln(error) time constants after the last step).
//!
//! Between inputs the position is monotone, so the cycle at which the count at any
//! resolution next changes is found by bisection over exact evaluations: no
//! logarithms, no per-cycle iteration.

use crate::{CountsPerStep, Motion, PlantError, Steps};

/// A following error below this (in steps) is 0: the axis is at rest.
pub const SETTLED: f64 = 1.0 / 4_294_967_296.0;

/// The largest lag time constant in cycles (86 s at 50 MHz): keeps `r^k` monotone in
/// `k` despite rounding, which the bisection needs.
pub const MAX_TAU: u64 = 1 << 32;

/// How the drive reads its two input pins.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum StepInput {
    /// A rising edge of pin A is a step in the direction of pin B (1 = positive).
    #[default]
    StepDir,
    /// A rising edge of pin A is +1, of pin B is -1 (CW/CCW).
    UpDown,
    /// (A, B) quadrature, A leading B is positive.
    Quadrature,
}

/// How the mechanical position follows the commanded one.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Mechanics {
    /// The actual position is the commanded position.
    #[default]
    Ideal,
    /// A first-order lag with time constant `tau` cycles (`1..=MAX_TAU`).
    Lag {
        /// Time constant in cycles.
        tau: u64,
    },
}

/// A drive's settings.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DriveConfig {
    /// How the pins are read.
    pub input: StepInput,
    /// The drive inverts pin A before reading it.
    pub invert_a: bool,
    /// The drive inverts pin B before reading it.
    pub invert_b: bool,
    /// How the mechanics follow.
    pub mechanics: Mechanics,
}

/// From `cycle` on (until the next anchor) the commanded position is `commanded` and
/// the following error is `error * r^(n - cycle)`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Anchor {
    cycle: u64,
    commanded: i64,
    error: f64,
}

/// One axis's drive (see the module documentation).
#[derive(Clone, Debug)]
pub struct Drive {
    config: DriveConfig,
    /// Error decay per cycle, `1 - 1/tau` (unused by an ideal drive).
    r: f64,
    now: u64,
    last_input: u64,
    a: bool,
    b: bool,
    current: Anchor,
    /// The anchor before `current`, for the cycle of an input (which still runs on it).
    previous: Anchor,
    /// The first cycle from which the error is 0.
    rest: u64,
    illegal_inputs: u64,
}

impl Drive {
    /// A drive at position 0 in cycle 0, its pins low.
    pub fn new(config: DriveConfig) -> Result<Drive, PlantError> {
        let r = match config.mechanics {
            Mechanics::Ideal => 0.0,
            Mechanics::Lag { tau } if (1..=MAX_TAU).contains(&tau) => 1.0 - 1.0 / tau as f64,
            Mechanics::Lag { tau } => return Err(PlantError::Tau { tau }),
        };
        let anchor = Anchor { cycle: 0, commanded: 0, error: 0.0 };
        Ok(Drive {
            config,
            r,
            now: 0,
            last_input: 0,
            a: config.invert_a,
            b: config.invert_b,
            current: anchor,
            previous: anchor,
            rest: 0,
            illegal_inputs: 0,
        })
    }

    /// The settings.
    pub fn config(&self) -> &DriveConfig {
        &self.config
    }

    /// The drive's current cycle.
    pub fn cycle(&self) -> u64 {
        self.now
    }

    /// Move to `cycle` (the drive itself changes only on input; this sets the cycle
    /// its position readings refer to).
    ///
    /// # Panics
    ///
    /// If `cycle` is before the current cycle.
    pub fn advance_to(&mut self, cycle: u64) {
        assert!(cycle >= self.now, "drive: advance_to({cycle}) before cycle {}", self.now);
        self.now = cycle;
    }

    /// The pin levels from `cycle` on (`pin_a`, `pin_b` as on the chip's pins, before
    /// the drive's inversion). An edge here moves the commanded position from
    /// `cycle + 1`. Calls with unchanged levels do nothing. Also moves to `cycle`.
    ///
    /// Followers of this drive (encoders, the probe) must have been advanced to
    /// `cycle` first; [`crate::Plant`] does that.
    ///
    /// # Panics
    ///
    /// If `cycle` is before the drive's current cycle.
    pub fn input(&mut self, cycle: u64, pin_a: bool, pin_b: bool) {
        self.advance_to(cycle);
        let (a, b) = (pin_a ^ self.config.invert_a, pin_b ^ self.config.invert_b);
        let delta = match self.config.input {
            StepInput::StepDir => match (a && !self.a, b) {
                (true, true) => 1,
                (true, false) => -1,
                (false, _) => 0,
            },
            StepInput::UpDown => i64::from(a && !self.a) - i64::from(b && !self.b),
            StepInput::Quadrature => {
                let from = crate::quadrature_index(self.a, self.b);
                match (crate::quadrature_index(a, b) - from).rem_euclid(4) {
                    1 => 1,
                    3 => -1,
                    2 => {
                        self.illegal_inputs += 1;
                        0
                    }
                    _ => 0,
                }
            }
        };
        self.a = a;
        self.b = b;
        self.last_input = cycle;
        if delta != 0 {
            self.command(cycle + 1, delta);
        }
    }

    /// The commanded position changes by `delta` from cycle `at`.
    fn command(&mut self, at: u64, delta: i64) {
        let error = self.error_at(at);
        if at != self.current.cycle {
            self.previous = self.current;
        }
        self.current = Anchor {
            cycle: at,
            commanded: self.current.commanded + delta,
            error: match self.config.mechanics {
                Mechanics::Ideal => 0.0,
                Mechanics::Lag { .. } => error + delta as f64,
            },
        };
        self.rest = self.rest_cycle();
    }

    /// The first cycle from which the current anchor's error is 0.
    fn rest_cycle(&self) -> u64 {
        let error = self.current.error;
        if error == 0.0 {
            return self.current.cycle;
        }
        let settled = |k: u64| decay(error, self.r, k) == 0.0;
        // Double to a bound, then bisect: `settled` is monotone in k.
        let mut hi = 1u64;
        while !settled(hi) {
            hi *= 2;
        }
        let mut lo = hi / 2; // not settled (0 is not: error != 0)
        while hi - lo > 1 {
            let mid = lo + (hi - lo) / 2;
            if settled(mid) {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        self.current.cycle.saturating_add(hi)
    }

    fn anchor_at(&self, cycle: u64) -> &Anchor {
        if cycle >= self.current.cycle {
            &self.current
        } else {
            debug_assert!(cycle >= self.previous.cycle, "drive: cycle {cycle} is before the last input");
            &self.previous
        }
    }

    fn error_at(&self, cycle: u64) -> f64 {
        let anchor = self.anchor_at(cycle);
        decay(anchor.error, self.r, cycle - anchor.cycle)
    }

    /// The commanded position in the current cycle, in steps.
    pub fn commanded(&self) -> i64 {
        self.anchor_at(self.now).commanded
    }

    /// The following error (commanded - actual) in the current cycle, in steps.
    pub fn following_error(&self) -> Steps {
        Steps::from_num(self.error_at(self.now))
    }

    /// The actual (mechanical) position in the current cycle, in steps.
    pub fn actual(&self) -> Steps {
        Steps::from_num(self.commanded()) - self.following_error()
    }

    /// The first cycle from which, without new input, the actual position equals the
    /// commanded position.
    pub fn settles_at(&self) -> u64 {
        self.rest
    }

    /// Quadrature inputs in which both pins changed at once (ignored).
    pub fn illegal_inputs(&self) -> u64 {
        self.illegal_inputs
    }
}

impl Motion for Drive {
    fn count_at(&self, cycle: u64, scale: CountsPerStep) -> i64 {
        let anchor = self.anchor_at(cycle);
        scale.count(anchor.commanded, decay(anchor.error, self.r, cycle - anchor.cycle))
    }

    fn next_exit(&self, after: u64, scale: CountsPerStep, lo: i64, hi: i64) -> Option<u64> {
        let first = after.checked_add(1)?;
        assert!(
            first >= self.current.cycle,
            "drive: followers must be advanced to an input's cycle before the input \
             (asked after cycle {after}, input in cycle {})",
            self.last_input
        );
        let outside = |cycle| !(lo..=hi).contains(&self.count_at(cycle, scale));
        if outside(first) {
            return Some(first);
        }
        // Monotone from `first` and constant from `rest`: if the end is inside, so is
        // everything in between.
        let mut end = self.rest.max(first);
        if !outside(end) {
            return None;
        }
        let mut inside = first;
        while end - inside > 1 {
            let mid = inside + (end - inside) / 2;
            if outside(mid) {
                end = mid;
            } else {
                inside = mid;
            }
        }
        Some(end)
    }
}

/// `error * r^k`, 0 once below [`SETTLED`]. `r^k` by binary powering (deterministic).
fn decay(error: f64, r: f64, k: u64) -> f64 {
    if error == 0.0 || k == 0 {
        return error;
    }
    let mut acc = 1.0f64;
    let mut base = r;
    let mut k = k;
    loop {
        if k & 1 == 1 {
            acc *= base;
        }
        k >>= 1;
        if k == 0 || acc == 0.0 {
            break;
        }
        base *= base;
    }
    let value = error * acc;
    if value.abs() < SETTLED {
        0.0
    } else {
        value
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testutil::{step_pins, StepPlan};
    use proptest::prelude::*;

    fn drive(input: StepInput, mechanics: Mechanics) -> Drive {
        Drive::new(DriveConfig { input, mechanics, ..DriveConfig::default() }).unwrap()
    }

    #[test]
    fn step_dir_counts_rising_edges_from_the_next_cycle() {
        let mut d = drive(StepInput::StepDir, Mechanics::Ideal);
        d.input(10, true, true);
        assert_eq!(d.commanded(), 0, "the edge's own cycle still runs on the old position");
        d.advance_to(11);
        assert_eq!(d.commanded(), 1);
        d.input(12, true, false); // dir changes while step is high: no step
        d.input(13, false, false);
        d.input(14, true, false);
        d.advance_to(15);
        assert_eq!(d.commanded(), 0);
        assert_eq!(d.actual(), Steps::ZERO);
    }

    #[test]
    fn up_down_quadrature_and_inversion() {
        let mut d = drive(StepInput::UpDown, Mechanics::Ideal);
        d.input(1, true, false);
        d.input(2, false, false);
        d.input(3, false, true);
        d.input(4, false, false);
        d.input(5, false, true);
        d.advance_to(6);
        assert_eq!(d.commanded(), -1);

        let mut d = drive(StepInput::Quadrature, Mechanics::Ideal);
        for (n, (a, b)) in
            [(true, false), (true, true), (false, true), (false, false), (true, true)].into_iter().enumerate()
        {
            d.input(n as u64 + 1, a, b);
        }
        d.advance_to(10);
        assert_eq!(d.commanded(), 4);
        assert_eq!(d.illegal_inputs(), 1);

        let mut d = Drive::new(DriveConfig { invert_a: true, ..DriveConfig::default() }).unwrap();
        d.input(1, true, true); // pin high = inverted step low: nothing
        d.input(2, false, true); // pin falls = step rises
        d.advance_to(3);
        assert_eq!(d.commanded(), 1);
    }

    #[test]
    fn bad_tau_is_an_error() {
        assert!(Drive::new(DriveConfig { mechanics: Mechanics::Lag { tau: 0 }, ..DriveConfig::default() }).is_err());
    }

    /// The lag is the per-cycle recurrence `x += (c - x) / tau`, evaluated in closed
    /// form, and comes to rest exactly on the commanded position.
    #[test]
    fn lag_follows_the_recurrence_and_converges() {
        let mut runner = finestep_testkit::runner("lag_follows_the_recurrence_and_converges", 64);
        let strategy = (1u64..=400, StepPlan::strategy(1, 40, 60));
        runner
            .run(&strategy, |(tau, plan)| {
                let mut d = drive(StepInput::StepDir, Mechanics::Lag { tau });
                let pins = step_pins(&plan);
                let end = pins.last().map_or(0, |p| p.0) + 60 * tau + 100;
                let (mut x, mut c) = (0.0f64, 0i64);
                let mut next = pins.iter().peekable();
                for n in 0..=end {
                    d.advance_to(n);
                    prop_assert_eq!(d.commanded(), c, "cycle {}", n);
                    let actual: f64 = d.actual().to_num();
                    let tolerance = 1e-9 * (1.0 + c.abs() as f64);
                    prop_assert!(
                        (actual - x).abs() <= tolerance.max(2.0 * SETTLED),
                        "cycle {}: closed form {} recurrence {}",
                        n,
                        actual,
                        x
                    );
                    // Reference: x[n+1] = x[n] + (c[n] - x[n]) / tau.
                    x += (c as f64 - x) / tau as f64;
                    while let Some(&&(at, step, dir)) = next.peek().filter(|p| p.0 == n) {
                        d.input(at, step, dir);
                        next.next();
                    }
                    // The commanded value of cycle n + 1.
                    d.advance_to(n + 1);
                    c = d.commanded();
                }
                prop_assert!(d.settles_at() <= end, "settles at {} after end {}", d.settles_at(), end);
                prop_assert_eq!(d.following_error(), Steps::ZERO);
                prop_assert_eq!(d.actual(), Steps::from_num(plan.net()));
                Ok(())
            })
            .unwrap();
    }

    /// `next_exit` is the first exit: bisection agrees with a scan, at any scale.
    #[test]
    fn next_exit_is_the_first_exit() {
        let mut runner = finestep_testkit::runner("next_exit_is_the_first_exit", 64);
        let strategy = (1u64..=300, 1u32..=8, 1u32..=8, StepPlan::strategy(1, 12, 40));
        runner
            .run(&strategy, |(tau, num, den, plan)| {
                let scale = CountsPerStep::new(num, den).unwrap();
                let mut d = drive(StepInput::StepDir, Mechanics::Lag { tau });
                let pins = step_pins(&plan);
                let end = pins.last().map_or(0, |p| p.0) + 40 * tau;
                let mut next = pins.iter().peekable();
                let mut n = 0;
                while n < end {
                    let k = d.count_at(n, scale);
                    let exit = d.next_exit(n, scale, k, k);
                    let input = next.peek().map(|p| p.0);
                    let scan_to = exit.unwrap_or(end).min(input.unwrap_or(u64::MAX)).min(end);
                    for m in n + 1..scan_to {
                        prop_assert_eq!(d.count_at(m, scale), k, "cycle {} before exit {:?}", m, exit);
                    }
                    if let Some(t) = exit.filter(|&t| t <= scan_to) {
                        prop_assert!(d.count_at(t, scale) != k);
                    }
                    n = scan_to;
                    d.advance_to(n);
                    while let Some(&&(at, step, dir)) = next.peek().filter(|p| p.0 == n) {
                        d.input(at, step, dir);
                        next.next();
                    }
                }
                Ok(())
            })
            .unwrap();
    }
}

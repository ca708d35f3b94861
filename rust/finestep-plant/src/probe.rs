//! A touch probe over a surface along one axis: the probe pin is active while the
//! axis's position, as a count at some resolution, lies in one of the surface's
//! contact ranges (for the chip's probe latch: every channel and axis latched on the
//! clock the pin goes active).
//!
//! Ranges are merged when they overlap or touch, so the pin changes exactly when the
//! position crosses a range's end; a position that jumps over a gap in one cycle (an
//! ideal drive at a coarse scale) changes nothing.

use std::ops::RangeInclusive;

use crate::{CountsPerStep, Motion};

/// A probe's settings.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ProbeConfig {
    /// The axis (drive) the probe moves with (used by [`crate::Plant`]).
    pub axis: usize,
    /// The resolution the contact ranges are given in (counts per step; 1 for steps).
    pub counts_per_step: CountsPerStep,
    /// Positions (counts) at which the probe touches the surface.
    pub touching: Vec<RangeInclusive<i64>>,
    /// The pin is high while touching (else low while touching).
    pub active_high: bool,
}

/// A probe (see the module documentation).
#[derive(Clone, Debug)]
pub struct Probe {
    scale: CountsPerStep,
    /// Merged, sorted, disjoint and not adjacent.
    ranges: Vec<(i64, i64)>,
    active_high: bool,
    cursor: u64,
    count: i64,
    touching: bool,
}

impl Probe {
    /// A probe following `motion` from `cycle`.
    pub fn new(config: &ProbeConfig, motion: &impl Motion, cycle: u64) -> Probe {
        let mut ranges: Vec<(i64, i64)> =
            config.touching.iter().filter(|r| !r.is_empty()).map(|r| (*r.start(), *r.end())).collect();
        ranges.sort_unstable();
        let mut merged: Vec<(i64, i64)> = Vec::with_capacity(ranges.len());
        for (lo, hi) in ranges {
            match merged.last_mut() {
                Some(last) if lo <= last.1.saturating_add(1) => last.1 = last.1.max(hi),
                _ => merged.push((lo, hi)),
            }
        }
        let count = motion.count_at(cycle, config.counts_per_step);
        let mut probe = Probe {
            scale: config.counts_per_step,
            ranges: merged,
            active_high: config.active_high,
            cursor: cycle,
            count,
            touching: false,
        };
        probe.touching = probe.touches(count);
        probe
    }

    fn touches(&self, count: i64) -> bool {
        self.ranges.iter().any(|&(lo, hi)| (lo..=hi).contains(&count))
    }

    /// The counts around `count` in which the probe stays as it is at `count`.
    fn stretch(&self, count: i64) -> (i64, i64) {
        let mut lo = i64::MIN;
        for &(a, b) in &self.ranges {
            if count < a {
                return (lo, a - 1);
            }
            if count <= b {
                return (a, b);
            }
            lo = b + 1;
        }
        (lo, i64::MAX)
    }

    /// The probe's current cycle.
    pub fn cycle(&self) -> u64 {
        self.cursor
    }

    /// The position count in the current cycle.
    pub fn count(&self) -> i64 {
        self.count
    }

    /// The probe touches the surface in the current cycle.
    pub fn touching(&self) -> bool {
        self.touching
    }

    /// The probe pin in the current cycle.
    pub fn pin(&self) -> bool {
        self.touching == self.active_high
    }

    /// The first cycle after the current one in which the pin differs, following
    /// `motion` without new input.
    pub fn next_change(&self, motion: &impl Motion) -> Option<u64> {
        let (mut after, mut count) = (self.cursor, self.count);
        loop {
            let (lo, hi) = self.stretch(count);
            let t = motion.next_exit(after, self.scale, lo, hi)?;
            count = motion.count_at(t, self.scale);
            if self.touches(count) != self.touching {
                return Some(t);
            }
            after = t;
        }
    }

    /// Move to `cycle`, following `motion`.
    ///
    /// # Panics
    ///
    /// If `cycle` is before the current cycle.
    pub fn advance_to(&mut self, cycle: u64, motion: &impl Motion) {
        assert!(cycle >= self.cursor, "probe: advance_to({cycle}) before cycle {}", self.cursor);
        loop {
            let (lo, hi) = self.stretch(self.count);
            match motion.next_exit(self.cursor, self.scale, lo, hi) {
                Some(t) if t <= cycle => {
                    self.cursor = t;
                    self.count = motion.count_at(t, self.scale);
                    self.touching = self.touches(self.count);
                }
                _ => break,
            }
        }
        self.cursor = cycle;
        self.count = motion.count_at(cycle, self.scale);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testutil::{StepPlan, Stepper};
    use crate::{Drive, DriveConfig};

    #[test]
    // `3..=2` is deliberate: an empty contact range must touch nowhere.
    #[allow(clippy::reversed_empty_ranges)]
    fn pin_follows_the_surface() {
        let config = ProbeConfig {
            axis: 0,
            counts_per_step: CountsPerStep::integer(1).unwrap(),
            touching: vec![5..=6, 7..=7, 10..=20, 3..=2],
            active_high: false,
        };
        let mut stepper = Stepper::new(Drive::new(DriveConfig::default()).unwrap(), &StepPlan::forward(12, 10));
        let mut probe = Probe::new(&config, stepper.drive(), 0);
        assert!(probe.pin() && !probe.touching());
        let mut seen = Vec::new();
        for n in 0..200 {
            probe.advance_to(n, stepper.drive());
            let predicted = probe.next_change(stepper.drive());
            if n > 0 && probe.touching() != seen.last().is_some_and(|s: &(u64, i64, bool)| s.2) {
                seen.push((n, probe.count(), probe.touching()));
            }
            stepper.input(n);
            if let Some(t) = predicted {
                assert!(t > n);
            }
        }
        // Enters 5..=7 (merged) at position 5, leaves at 8, enters 10.
        let positions: Vec<(i64, bool)> = seen.iter().map(|s| (s.1, s.2)).collect();
        assert_eq!(positions, [(5, true), (8, false), (10, true)]);
        assert!(!probe.pin());
    }
}

//! `logic_outputs`: coolant, light and general outputs with their safe levels, and the
//! interlock input.
//!
//! Specification: docs/spec/logic_outputs.md
//!
//! The output pins are the register file's `OUTPUTS` bits (it sets them to
//! `OUTPUTS_SAFE` while the machine halts). This block holds the interlock: the pin
//! passes a two-flop synchroniser, then a filter sampled every `PRESCALE + 1` clocks (the
//! hand wheel's [`Prescaler`], first sample in the third cycle after reset) whose level
//! takes the synchronised value once it has differed from the level on `max(FILTER, 1)`
//! samples in a row (the first sample adopts it: `primed`). `inhibit` = ENABLE and the
//! filtered input active; `BLOCKED` is sticky when motion control reports a gate it held
//! shut.

use crate::input_filter::Prescaler;

/// The interlock's configuration (`INTERLOCK`'s rw fields).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct InterlockConfig {
    /// `ENABLE`.
    pub enable: bool,
    /// `ACTIVE_HIGH`.
    pub active_high: bool,
    /// `FILTER` (0 acts as 1): samples.
    pub filter: u32,
    /// `PRESCALE`: a sample every `PRESCALE + 1` clocks.
    pub prescale: u16,
}

/// The interlock's state.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Interlock {
    prescaler: Prescaler,
    sync: [bool; 2],
    level: bool,
    differing: u32,
    primed: bool,
    blocked: bool,
}

impl Interlock {
    /// The filtered input is active (whatever `ENABLE` says): `INTERLOCK.ACTIVE`.
    pub fn active(&self, config: &InterlockConfig) -> bool {
        self.primed && self.level == config.active_high
    }

    /// Motion control may not open its gate.
    pub fn inhibit(&self, config: &InterlockConfig) -> bool {
        config.enable && self.active(config)
    }

    /// `INTERLOCK.BLOCKED`.
    pub fn blocked(&self) -> bool {
        self.blocked
    }

    /// One rising clock edge: the pin, the configuration, motion control's
    /// `start_blocked` and `clear_errors` of this cycle.
    pub fn step(&mut self, pin: bool, config: &InterlockConfig, start_blocked: bool, clear_errors: bool) {
        if self.prescaler.sample() {
            let sample = self.sync[1];
            // Adopt the sample: the first one, the same level again, or enough in a row.
            if !self.primed || sample == self.level || self.differing + 1 >= config.filter.max(1) {
                self.level = sample;
                self.differing = 0;
            } else {
                self.differing += 1;
            }
            self.primed = true;
        }
        self.prescaler.step(config.prescale);
        self.sync = [pin, self.sync[0]];
        self.blocked = start_blocked || (self.blocked && !clear_errors);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_interlock_needs_filter_samples_of_the_other_level() {
        let config = InterlockConfig { enable: true, active_high: true, filter: 5, prescale: 0 };
        let mut lock = Interlock::default();
        for _ in 0..4 {
            lock.step(false, &config, false, false);
        }
        assert!(!lock.inhibit(&config));
        // A glitch of 4 clocks never shows; 5 clocks do, 2 + 5 clocks after the pin.
        for width in [4usize, 5] {
            let mut seen = None;
            for t in 0..20 {
                lock.step(t < width, &config, false, false);
                if lock.inhibit(&config) && seen.is_none() {
                    seen = Some(t + 1);
                }
            }
            assert_eq!(seen, (width == 5).then_some(7), "width {width}");
        }
        assert!(!lock.inhibit(&InterlockConfig { enable: false, ..config }));
    }

    /// Sampled every `PRESCALE + 1` clocks, a pulse covers `FILTER` samples in a row (and
    /// shows) whatever its phase iff it lasts `FILTER * (PRESCALE + 1)` clocks; one of
    /// `(FILTER - 1) * (PRESCALE + 1)` clocks covers at most `FILTER - 1` and never shows.
    #[test]
    fn the_prescaler_stretches_the_filter_to_whole_sample_periods() {
        for (filter, prescale) in [(3u32, 9u16), (5, 0), (1, 4), (4, 6)] {
            let config = InterlockConfig { enable: true, active_high: true, filter, prescale };
            let period = usize::from(prescale) + 1;
            for phase in 0..period {
                for (width, shows) in [((filter as usize - 1) * period, false), (filter as usize * period, true)] {
                    let mut lock = Interlock::default();
                    let mut seen = false;
                    for t in 0..(phase + 40 + 3 * width) {
                        let pin = t >= phase + 20 && t < phase + 20 + width;
                        lock.step(pin, &config, false, false);
                        seen |= lock.inhibit(&config);
                    }
                    assert_eq!(seen, shows, "filter {filter}, prescale {prescale}, phase {phase}, width {width}");
                }
            }
        }
    }

    #[test]
    fn blocked_is_sticky_until_cleared() {
        let config = InterlockConfig::default();
        let mut lock = Interlock::default();
        lock.step(false, &config, true, false);
        lock.step(false, &config, false, false);
        assert!(lock.blocked());
        lock.step(false, &config, true, true);
        assert!(lock.blocked(), "a block in the clearing cycle wins");
        lock.step(false, &config, false, true);
        assert!(!lock.blocked());
    }
}

//! `input_filter`: the sampling prescaler and, per feedback pin, a two-flop synchroniser
//! and a glitch filter.
//!
//! Specification: docs/spec/input_filter.md
//!
//! The prescaler fixes *when* the pins are looked at (every `PRESCALE + 1` clocks), the
//! filter *what* is believed: the filtered `level` takes a new value only after
//! `max(FILTER, 1)` samples of it in a row, so a pulse with fewer samples than that never
//! reaches it. The first sample is adopted as it is (`primed`): an encoder resting in
//! any state at power-on is not a transition. A change on a pin reaches `level` 2 clocks
//! (the synchroniser) plus `max(FILTER, 1)` samples later.
//!
//! The rule itself is [`filter_step`], one statement for every filter of the core:
//! [`InputFilter`] (the probe) applies it to its own state, the encoder bank's shared
//! decoder and the hand wheel to the filter state a [`QuadratureChannel`] keeps.
//!
//! [`QuadratureChannel`]: crate::quadrature_channel::QuadratureChannel

/// Width of a filter setting and of the filter's `count` (4 bits: up to 15 samples).
pub const FILTER_WIDTH: u32 = 4;

/// The largest filter setting.
pub const FILTER_MAX: u8 = (1 << FILTER_WIDTH) - 1;

/// The sampling prescaler: `sample` every `PRESCALE + 1` clocks.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Prescaler {
    presc: u16,
}

impl Prescaler {
    /// `presc` after reset. 2 puts the first sample in the third cycle after reset, when
    /// both synchroniser flops hold a pin value and no longer their reset 0.
    pub const RESET: u16 = 2;

    /// The count down to the next sample (`presc`).
    pub fn presc(&self) -> u16 {
        self.presc
    }

    /// `sample = (presc == 0)`: the filters take a sample in this cycle.
    pub fn sample(&self) -> bool {
        self.presc == 0
    }

    /// One rising clock edge with the `PRESCALE` setting of this cycle.
    pub fn step(&mut self, prescale: u16) {
        self.presc = if self.sample() { prescale } else { self.presc - 1 };
    }
}

impl Default for Prescaler {
    /// The reset state, `presc = 2`.
    fn default() -> Self {
        Prescaler { presc: Prescaler::RESET }
    }
}

/// The filter's state besides `primed`: the filtered `level` and `count`, the samples of
/// the other level seen in a row so far.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FilterState {
    /// The filtered level.
    pub level: bool,
    /// Samples of the other level in a row so far (4 bits).
    pub count: u8,
}

/// The filter rule at one sample (`filter_step` in the HDL): the state after a sample of
/// `raw`, with `primed` (the first sample has been adopted before this one) and the
/// `FILTER` setting (low 4 bits; 0 acts as 1). Not primed: `level <- raw`, `count <- 0`;
/// else `raw == level`: `count <- 0`; else `count + 1 >= max(FILTER, 1)`: `level <- raw`,
/// `count <- 0`; else `count <- count + 1`. The caller sets `primed` after it.
pub fn filter_step(state: FilterState, raw: bool, primed: bool, filter: u8) -> FilterState {
    let needed = (filter & FILTER_MAX).max(1);
    // Adopted, the same level again (`level <- raw` keeps it), or enough in a row.
    if !primed || raw == state.level || state.count + 1 >= needed {
        FilterState { level: raw, count: 0 }
    } else {
        FilterState { level: state.level, count: state.count + 1 }
    }
}

/// A two-flop synchroniser (reset 0): `raw` is the pin two clocks before.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Synchroniser {
    /// `sync[0]` takes the pin, `sync[1]` is `raw`.
    sync: [bool; 2],
}

impl Synchroniser {
    /// `raw`: the synchronised pin.
    pub fn raw(&self) -> bool {
        self.sync[1]
    }

    /// One rising clock edge with the pin of this cycle.
    pub fn step(&mut self, pin: bool) {
        self.sync = [pin, self.sync[0]];
    }
}

/// The synchroniser and glitch filter of one pin, with its own `primed`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct InputFilter {
    sync: Synchroniser,
    state: FilterState,
    primed: bool,
}

impl InputFilter {
    /// `raw`: the synchronised pin.
    pub fn raw(&self) -> bool {
        self.sync.raw()
    }

    /// The filtered level.
    pub fn level(&self) -> bool {
        self.state.level
    }

    /// Samples of the other level seen in a row so far.
    pub fn count(&self) -> u8 {
        self.state.count
    }

    /// The first sample has been adopted: `level` is a pin value, not the reset 0.
    pub fn primed(&self) -> bool {
        self.primed
    }

    /// One rising clock edge: the pin of this cycle, this cycle's `sample`, and the
    /// `FILTER` setting (low 4 bits; 0 acts as 1).
    pub fn step(&mut self, pin: bool, sample: bool, filter: u8) {
        let raw = self.raw();
        self.sync.step(pin);
        if sample {
            self.state = filter_step(self.state, raw, self.primed, filter);
            self.primed = true;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_prescaler_samples_first_in_the_third_cycle_then_every_prescale_plus_one() {
        let mut presc = Prescaler::default();
        let samples: Vec<bool> = (0..12)
            .map(|_| {
                let s = presc.sample();
                presc.step(3);
                s
            })
            .collect();
        let at: Vec<usize> = samples.iter().enumerate().filter(|(_, &s)| s).map(|(i, _)| i).collect();
        assert_eq!(at, [2, 6, 10]);
    }

    #[test]
    fn the_first_sample_adopts_the_pin_and_later_changes_need_filter_samples() {
        let mut f = InputFilter::default();
        // Pin high from reset; sample every cycle.
        f.step(true, false, 3);
        f.step(true, false, 3);
        assert!(f.raw() && !f.primed());
        f.step(true, true, 3);
        assert!(f.primed() && f.level(), "adopted without filtering");
        // Two low samples then a high one: filtered out.
        for pin in [false, false, true, true, true] {
            f.step(pin, true, 3);
            assert!(f.level());
        }
        // Three low samples in a row change it, 2 synchroniser clocks later.
        let mut clocks = 0;
        while f.level() {
            f.step(false, true, 3);
            clocks += 1;
        }
        assert_eq!(clocks, 2 + 3);
    }

    #[test]
    fn a_filter_of_zero_acts_as_one() {
        let mut f = InputFilter::default();
        for _ in 0..3 {
            f.step(false, true, 0);
        }
        assert!(f.primed() && !f.level());
        f.step(true, true, 0);
        f.step(true, true, 0);
        f.step(true, true, 0);
        assert!(f.level());
    }
}

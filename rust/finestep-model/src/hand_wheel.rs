//! `hand_wheel`: the manual pulse generator (MPG). A quadrature channel in x4 with no
//! index, on its own prescaler and filter (`MPG_CONTROL`): hand wheels have mechanical
//! contacts whose bounce outlasts any encoder's edge, so they are sampled slowly
//! (the reset setting, PRESCALE 499 and FILTER 4, rejects bounce under 40 us at 50 MHz).
//! The channel is a [`QuadratureChannel`] in flip-flops of its own, visited in every
//! cycle; the visit samples when the prescaler says `sample`, so the count changes at the
//! edge ending the sample that decodes it.
//!
//! Specification: docs/spec/hand_wheel.md
//!
//! The wheel's position in detents is `floor((count + 2) / 4)`: a 100-pulse wheel makes
//! 4 edges per detent, and one resting where it was at reset sits in the middle of
//! detent 0, two edges from either boundary, so bounce at rest never changes it.

use crate::input_filter::{Prescaler, Synchroniser};
use crate::quadrature_channel::{ChannelInputs, CountMode, QuadratureChannel};

/// Edges per detent.
pub const EDGES_PER_DETENT: i64 = 4;

/// `floor((count + 2) / 4)` of a two's complement `count`, exactly (no wrap of the sum):
/// what `MPG_DETENTS` reads as long as the count has not wrapped.
pub fn detents_of(count: u32) -> i32 {
    let count = i64::from(count as i32);
    (count + EDGES_PER_DETENT / 2).div_euclid(EDGES_PER_DETENT) as i32
}

/// What the hand wheel sees in one cycle.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct HandWheelInputs {
    /// `mpg_a` pin.
    pub mpg_a: bool,
    /// `mpg_b` pin.
    pub mpg_b: bool,
    /// `MPG_CONTROL.PRESCALE`.
    pub prescale: u16,
    /// `MPG_CONTROL.FILTER` (4 bits; 0 acts as 1).
    pub filter: u8,
    /// `clear_errors` pulse.
    pub clear_errors: bool,
    /// `clear_counters` pulse.
    pub clear_counters: bool,
}

/// The hand wheel's register view.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct HandWheelStatus {
    /// `MPG_COUNT`.
    pub count: u32,
    /// `MPG_DETENTS`.
    pub detents: i32,
    /// `MPG_STATUS.ILLEGAL`.
    pub illegal: bool,
    /// `MPG_STATUS.ILLEGAL_COUNT`.
    pub illegal_count: u16,
    /// `MPG_STATUS.A`: filtered A.
    pub a: bool,
    /// `MPG_STATUS.B`: filtered B.
    pub b: bool,
}

/// State of the hand wheel.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct HandWheel {
    prescaler: Prescaler,
    /// The synchronisers of `[a, b]`.
    sync: [Synchroniser; 2],
    channel: QuadratureChannel,
    /// The count's low two bits in the previous cycle.
    count_low_prev: u32,
    /// `detents` in the previous cycle.
    detents_prev: i32,
}

impl HandWheel {
    /// The decoder and counter.
    pub fn channel(&self) -> &QuadratureChannel {
        &self.channel
    }

    /// The synchronisers of the pins, `[a, b]`.
    pub fn synchronisers(&self) -> &[Synchroniser; 2] {
        &self.sync
    }

    /// The prescaler.
    pub fn prescaler(&self) -> &Prescaler {
        &self.prescaler
    }

    /// `MPG_COUNT`: edges, x4.
    pub fn count(&self) -> u32 {
        self.channel.count()
    }

    /// `MPG_DETENTS`: the detent boundaries crossed, counted as the count's low bits go
    /// 1 -> 2 (+1) or 2 -> 1 (-1); `floor((MPG_COUNT + 2) / 4)` until the count wraps,
    /// and it wraps with the count instead of jumping.
    pub fn detents(&self) -> i32 {
        match (self.count_low_prev, self.count() & 3) {
            (1, 2) => self.detents_prev.wrapping_add(1),
            (2, 1) => self.detents_prev.wrapping_sub(1),
            _ => self.detents_prev,
        }
    }

    /// The register view.
    pub fn status(&self) -> HandWheelStatus {
        HandWheelStatus {
            count: self.count(),
            detents: self.detents(),
            illegal: self.channel.illegal(),
            illegal_count: self.channel.illegal_count(),
            a: self.channel.a(),
            b: self.channel.b(),
        }
    }

    /// One rising clock edge.
    pub fn step(&mut self, inp: &HandWheelInputs) {
        let sample = self.prescaler.sample();
        self.detents_prev = self.detents();
        self.count_low_prev = self.count() & 3;
        self.channel.step(&ChannelInputs {
            sample,
            raw_a: self.sync[0].raw(),
            raw_b: self.sync[1].raw(),
            // No index: z stays inactive.
            raw_z: false,
            z_active_high: true,
            mode: CountMode::X4,
            filter: inp.filter,
            clear_errors: inp.clear_errors,
            clear_counters: inp.clear_counters,
            ..ChannelInputs::default()
        });
        self.sync[0].step(inp.mpg_a);
        self.sync[1].step(inp.mpg_b);
        self.prescaler.step(inp.prescale);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn detents_are_centred_on_the_reset_position() {
        let at = |count: i32| detents_of(count as u32);
        assert_eq!([at(-3), at(-2), at(-1), at(0), at(1), at(2)], [-1, 0, 0, 0, 0, 1]);
        assert_eq!(at(i32::MAX), 1 << 29);
        assert_eq!(at(i32::MIN), -(1 << 29));
    }

    #[test]
    fn the_count_changes_at_the_edge_ending_the_sample_that_decodes_it() {
        // PRESCALE 2: samples in cycles 2, 5, 8, ...; A rises in cycle 4, raw from 6.
        let mut wheel = HandWheel::default();
        let mut counted = Vec::new();
        for cycle in 0..20 {
            let sample = wheel.prescaler().sample();
            let before = wheel.count();
            wheel.step(&HandWheelInputs { mpg_a: cycle >= 4, prescale: 2, filter: 1, ..Default::default() });
            if wheel.count() != before {
                counted.push((cycle, sample));
            }
        }
        assert_eq!(counted, [(8, true)]);
    }

    #[test]
    fn one_forward_detent_turns_the_count_by_four() {
        let mut wheel = HandWheel::default();
        let mut inp = HandWheelInputs { prescale: 0, filter: 1, ..Default::default() };
        let states = [(false, false), (true, false), (true, true), (false, true), (false, false)];
        for &(a, b) in &states {
            inp.mpg_a = a;
            inp.mpg_b = b;
            for _ in 0..5 {
                wheel.step(&inp);
            }
        }
        assert_eq!((wheel.count(), wheel.detents()), (4, 1));
        assert!(!wheel.status().illegal);
    }

    #[test]
    fn detents_follow_the_exact_quotient_both_ways() {
        let mut wheel = HandWheel::default();
        let mut inp = HandWheelInputs { prescale: 0, filter: 1, ..Default::default() };
        let states = [(false, false), (true, false), (true, true), (false, true)];
        let mut phase = 0i64;
        for k in 0..200i64 {
            phase += if (k / 37) % 2 == 0 { 1 } else { -1 };
            let (a, b) = states[phase.rem_euclid(4) as usize];
            inp.mpg_a = a;
            inp.mpg_b = b;
            for _ in 0..5 {
                wheel.step(&inp);
                assert_eq!(wheel.detents(), detents_of(wheel.count()));
            }
        }
        assert!(wheel.count() != 0);
    }
}

//! `quadrature_channel`: one encoder channel's filters, decoder, counter and index
//! logic: what one visit of the encoder bank's shared decoder does to it.
//!
//! Specification: docs/spec/quadrature_channel.md
//!
//! The channel's state lives in the bank's store and changes only at its visits, except
//! by the host's pulses (arms, `clear_errors`, `clear_counters`), which act in any cycle.
//! A *sampling* visit passes the synchronised pins through the three filters (the rule
//! of [`filter_step`], sharing one `primed`) and decodes the step from the filtered
//! levels before the visit to those after it in the same visit, so the count moves at
//! most one per visit. Forward is A leading B, the step shaper's quadrature order (A,B)
//! 00 -> 10 -> 11 -> 01: an axis driven in quadrature mode and read back by a channel
//! counts up when its position does. Both inputs changing at one sample cannot be
//! decoded (the direction is unknown): the count holds and the transition is flagged and
//! counted instead of guessed.
//!
//! Nothing is decoded at the first sample (`live = primed` before the visit): it only
//! adopts the pins' levels, so the power-on levels are never taken for an edge.
//!
//! The hand wheel is the same channel in flip-flops of its own, visited every cycle.

use crate::input_filter::{filter_step, FilterState};

/// How the channel turns edges into counts (`ENC_CONTROL.MODE`): the interface's
/// `COUNT_MODE`.
pub use finestep_interface::CountMode;

/// The count change from the filtered levels before (`a_p`, `b_p`) to after (`a`, `b`) a
/// sample: `(delta, illegal)`, `delta` in {-1, 0, +1}. Only meaningful while `live`.
pub fn decode(mode: CountMode, a: bool, b: bool, a_p: bool, b_p: bool) -> (i32, bool) {
    let da = a != a_p;
    let db = b != b_p;
    let forward = (da && a != b) || (db && a == b);
    let signed = |up: bool| if up { 1 } else { -1 };
    match mode {
        CountMode::StepDir => (if a && !a_p { signed(b) } else { 0 }, false),
        _ if da && db => (0, true),
        CountMode::X4 if da != db => (signed(forward), false),
        CountMode::X2 if da => (signed(forward), false),
        CountMode::X1 if da && !b => (signed(a), false),
        _ => (0, false),
    }
}

/// What a channel sees in one cycle besides its own state.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ChannelInputs {
    /// This cycle is a sampling visit of the channel: the filters sample and the decoder
    /// runs. Otherwise only the host pulses act.
    pub sample: bool,
    /// `raw_a`: the synchronised A pin in this cycle.
    pub raw_a: bool,
    /// `raw_b`.
    pub raw_b: bool,
    /// `raw_z`: the synchronised index pin, before polarity.
    pub raw_z: bool,
    /// `ENC_CONTROL.MODE`.
    pub mode: CountMode,
    /// `ENC_CONTROL.Z_ACTIVE_HIGH`.
    pub z_active_high: bool,
    /// `ENC_CONTROL.FILTER` (4 bits; 0 acts as 1).
    pub filter: u8,
    /// `ARM_INDEX_LATCH` pulse.
    pub arm_index_latch: bool,
    /// `ARM_INDEX_CLEAR` pulse.
    pub arm_index_clear: bool,
    /// `clear_errors` pulse: clears `ILLEGAL` (a set in the same cycle wins).
    pub clear_errors: bool,
    /// `clear_counters` pulse: zeroes `ILLEGAL_COUNT` (wins over a count).
    pub clear_counters: bool,
    /// `TIMESTAMP` of this cycle, for `edge_time`.
    pub timestamp: u32,
}

/// The index after polarity: `z = z_level ^ !Z_ACTIVE_HIGH`.
pub fn index_active(z_level: bool, z_active_high: bool) -> bool {
    z_level == z_active_high
}

/// State of one channel (the bank's store for it).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct QuadratureChannel {
    /// Filters of A, B and the index (`z_level`, before polarity).
    a: FilterState,
    b: FilterState,
    z: FilterState,
    /// The filters have adopted their first sample.
    primed: bool,
    count: u32,
    edge_time: u32,
    illegal: bool,
    illegal_count: u16,
    latch_armed: bool,
    clear_armed: bool,
    index_latch: u32,
    index_seen: bool,
}

impl QuadratureChannel {
    /// The count (two's complement, wraps).
    pub fn count(&self) -> u32 {
        self.count
    }

    /// `TIMESTAMP` of the last visit whose decoding changed the count.
    pub fn edge_time(&self) -> u32 {
        self.edge_time
    }

    /// The filters have adopted their first sample: the next sampling visit decodes
    /// (`live`).
    pub fn primed(&self) -> bool {
        self.primed
    }

    /// Filtered A.
    pub fn a(&self) -> bool {
        self.a.level
    }

    /// Filtered B.
    pub fn b(&self) -> bool {
        self.b.level
    }

    /// Filtered index before polarity (`z_level`).
    pub fn z_level(&self) -> bool {
        self.z.level
    }

    /// The filters' counters, `[a, b, z]`.
    pub fn filter_counts(&self) -> [u8; 3] {
        [self.a.count, self.b.count, self.z.count]
    }

    /// Sticky `ILLEGAL`: A and B changed at one sample (quadrature modes).
    pub fn illegal(&self) -> bool {
        self.illegal
    }

    /// `ILLEGAL_COUNT`, saturating at 65535.
    pub fn illegal_count(&self) -> u16 {
        self.illegal_count
    }

    /// `LATCH_ARMED`: the next index event latches the count.
    pub fn latch_armed(&self) -> bool {
        self.latch_armed
    }

    /// `CLEAR_ARMED`: the next index event zeroes the count.
    pub fn clear_armed(&self) -> bool {
        self.clear_armed
    }

    /// `INDEX_LATCH`: the count at the last armed index event.
    pub fn index_latch(&self) -> u32 {
        self.index_latch
    }

    /// `INDEX_SEEN`: an armed index event latched since the last `ARM_INDEX_LATCH`.
    pub fn index_seen(&self) -> bool {
        self.index_seen
    }

    /// One rising clock edge: a sampling visit if `inp.sample`, the host pulses always.
    pub fn step(&mut self, inp: &ChannelInputs) {
        // Without a sample, an arm or a clear every update below keeps its state (the
        // channels not visited in a cycle, nearly all of them): skip them.
        if !(inp.sample || inp.arm_index_latch || inp.arm_index_clear || inp.clear_errors || inp.clear_counters) {
            return;
        }
        let mut delta = 0;
        let mut illegal_now = false;
        let mut index_event = false;
        if inp.sample {
            let live = self.primed;
            let a = filter_step(self.a, inp.raw_a, self.primed, inp.filter);
            let b = filter_step(self.b, inp.raw_b, self.primed, inp.filter);
            let z = filter_step(self.z, inp.raw_z, self.primed, inp.filter);
            if live {
                (delta, illegal_now) = decode(inp.mode, a.level, b.level, self.a.level, self.b.level);
                index_event =
                    index_active(z.level, inp.z_active_high) && !index_active(self.z.level, inp.z_active_high);
            }
            (self.a, self.b, self.z) = (a, b, z);
            self.primed = true;
        }

        if index_event && self.latch_armed {
            self.index_latch = self.count;
        }
        self.index_seen = !inp.arm_index_latch && (self.index_seen || (index_event && self.latch_armed));
        if delta != 0 {
            self.edge_time = inp.timestamp;
        }
        self.count = if index_event && self.clear_armed { 0 } else { self.count.wrapping_add(delta as u32) };
        self.latch_armed = inp.arm_index_latch || (self.latch_armed && !index_event);
        self.clear_armed = inp.arm_index_clear || (self.clear_armed && !index_event);

        self.illegal = illegal_now || (self.illegal && !inp.clear_errors);
        self.illegal_count =
            if inp.clear_counters { 0 } else { self.illegal_count.saturating_add(u16::from(illegal_now)) };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The quadrature states in forward order.
    const GRAY: [(bool, bool); 4] = [(false, false), (true, false), (true, true), (false, true)];

    #[test]
    fn every_mode_decodes_a_forward_and_a_backward_turn() {
        for (mode, per_turn) in [(CountMode::X4, 4), (CountMode::X2, 2), (CountMode::X1, 1)] {
            let mut total = 0;
            for k in 0..8 {
                let (a_p, b_p) = GRAY[k % 4];
                let (a, b) = GRAY[(k + 1) % 4];
                let (d, illegal) = decode(mode, a, b, a_p, b_p);
                assert!(!illegal);
                total += d;
            }
            assert_eq!(total, 2 * per_turn, "{mode:?} forward");
            let mut total = 0;
            for k in (1..=8).rev() {
                let (a_p, b_p) = GRAY[k % 4];
                let (a, b) = GRAY[(k - 1) % 4];
                total += decode(mode, a, b, a_p, b_p).0;
            }
            assert_eq!(total, -2 * per_turn, "{mode:?} backward");
        }
        assert_eq!(decode(CountMode::StepDir, true, true, false, true), (1, false));
        assert_eq!(decode(CountMode::StepDir, true, false, false, false), (-1, false));
        assert_eq!(decode(CountMode::StepDir, true, true, false, false), (1, false), "no illegal in step/dir");
        assert_eq!(decode(CountMode::X4, true, true, false, false), (0, true));
    }

    /// Inputs of a sampling visit, x4, index active high, FILTER 1.
    fn visit() -> ChannelInputs {
        ChannelInputs { sample: true, z_active_high: true, filter: 1, ..Default::default() }
    }

    /// A channel after its first (adopting) sample of `(a, b)`.
    fn primed_at(a: bool, b: bool) -> QuadratureChannel {
        let mut ch = QuadratureChannel::default();
        ch.step(&ChannelInputs { raw_a: a, raw_b: b, ..visit() });
        ch
    }

    #[test]
    fn the_first_sample_adopts_and_later_visits_decode_in_the_same_visit() {
        let mut ch = QuadratureChannel::default();
        // Cycles that are not sampling visits change nothing, whatever the pins.
        ch.step(&ChannelInputs { sample: false, raw_a: true, raw_b: true, ..visit() });
        assert_eq!(ch, QuadratureChannel::default());
        // The first sample adopts A = B = 1: no count, no illegal transition.
        ch.step(&ChannelInputs { raw_a: true, raw_b: true, timestamp: 3, ..visit() });
        assert!(ch.primed() && ch.a() && ch.b());
        assert_eq!((ch.count(), ch.edge_time(), ch.illegal()), (0, 0, false));
        // 11 -> 01 is forward: counted by the visit that sees it, at its timestamp.
        ch.step(&ChannelInputs { raw_a: false, raw_b: true, timestamp: 9, ..visit() });
        assert_eq!((ch.count(), ch.edge_time()), (1, 9));
        // A pin change between samples waits for the next sampling visit.
        ch.step(&ChannelInputs { sample: false, raw_a: false, raw_b: false, timestamp: 10, ..visit() });
        assert_eq!((ch.count(), ch.b()), (1, true));
        ch.step(&ChannelInputs { raw_a: false, raw_b: false, timestamp: 11, ..visit() });
        assert_eq!((ch.count(), ch.edge_time(), ch.b()), (2, 11, false));
    }

    #[test]
    fn a_level_needs_filter_samples_in_a_row_and_is_decoded_at_the_last() {
        let mut ch = primed_at(false, false);
        let filtered = |raw_a: bool, timestamp: u32| ChannelInputs { raw_a, filter: 3, timestamp, ..visit() };
        for (t, raw_a) in [(1, true), (2, true), (3, false), (4, true), (5, true)] {
            ch.step(&filtered(raw_a, t));
            assert_eq!(ch.count(), 0, "sample {t}");
        }
        assert_eq!(ch.filter_counts(), [2, 0, 0]);
        ch.step(&filtered(true, 6));
        assert_eq!((ch.a(), ch.count(), ch.edge_time(), ch.filter_counts()), (true, 1, 6, [0, 0, 0]));
    }

    #[test]
    fn x1_and_step_dir_use_the_levels_after_the_sample() {
        // x1 counts A's edges while B (after the sample) is low.
        let mut ch = primed_at(false, false);
        ch.step(&ChannelInputs { raw_a: true, mode: CountMode::X1, ..visit() });
        assert_eq!(ch.count(), 1);
        let mut ch = primed_at(false, false);
        ch.step(&ChannelInputs { raw_a: true, raw_b: true, mode: CountMode::X1, ..visit() });
        assert_eq!((ch.count(), ch.illegal()), (0, true));
        // Step/dir: a rising step counts in the direction B has after the same sample.
        let mut ch = primed_at(false, false);
        ch.step(&ChannelInputs { raw_a: true, raw_b: true, mode: CountMode::StepDir, ..visit() });
        assert_eq!((ch.count(), ch.illegal()), (1, false));
    }

    #[test]
    fn index_latch_and_clear_act_once_on_the_rising_index() {
        let mut ch = primed_at(false, false);
        let mut inp = visit();
        // Count up to 3.
        for &(a, b) in &GRAY[1..] {
            (inp.raw_a, inp.raw_b) = (a, b);
            ch.step(&inp);
        }
        assert_eq!(ch.count(), 3);
        // The arms act in a cycle that is not a visit.
        ch.step(&ChannelInputs { sample: false, arm_index_latch: true, arm_index_clear: true, ..inp });
        assert!(ch.latch_armed() && ch.clear_armed() && !ch.index_seen());
        // Index rises together with a forward edge: latch sees 3, the count is cleared
        // over the decoding, edge_time still follows the decoding.
        inp.raw_z = true;
        (inp.raw_a, inp.raw_b) = (false, false);
        inp.timestamp = 77;
        ch.step(&inp);
        assert_eq!((ch.index_latch(), ch.count(), ch.edge_time()), (3, 0, 77));
        assert!(ch.index_seen() && !ch.latch_armed() && !ch.clear_armed());
        // Held high: no second event.
        inp.raw_a = true;
        ch.step(&inp);
        assert_eq!(ch.count(), 1);
        // An arm in the cycle of an event wins; active-low index: z_level falling is the event.
        let mut ch = primed_at(false, false);
        ch.step(&ChannelInputs { raw_z: true, z_active_high: false, ..visit() });
        let event = ChannelInputs { raw_z: false, z_active_high: false, arm_index_latch: true, ..visit() };
        ch.step(&ChannelInputs { sample: false, ..event });
        ch.step(&event);
        assert!(ch.latch_armed() && !ch.index_seen(), "the arm of the event's cycle stays");
    }

    #[test]
    fn the_first_sample_of_an_active_index_is_no_event() {
        let mut ch = QuadratureChannel::default();
        ch.step(&ChannelInputs { arm_index_clear: true, sample: false, ..visit() });
        ch.step(&ChannelInputs { raw_z: true, ..visit() });
        assert!(ch.clear_armed(), "adopted, not an event");
    }

    #[test]
    fn illegal_transitions_hold_the_count_and_saturate_the_counter() {
        let mut ch = QuadratureChannel { illegal_count: u16::MAX - 2, ..primed_at(false, false) };
        let mut inp = visit();
        for _ in 0..3 {
            inp.raw_a = !inp.raw_a;
            inp.raw_b = !inp.raw_b;
            ch.step(&inp);
        }
        assert_eq!(ch.count(), 0);
        assert!(ch.illegal());
        assert_eq!(ch.illegal_count(), u16::MAX);
        // The pulses act outside visits.
        ch.step(&ChannelInputs { sample: false, clear_errors: true, clear_counters: true, ..inp });
        assert!(!ch.illegal() && ch.illegal_count() == 0);
        // A set in the cycle of clear_errors wins; clear_counters wins over a count.
        inp.raw_a = !inp.raw_a;
        inp.raw_b = !inp.raw_b;
        ch.step(&ChannelInputs { clear_errors: true, clear_counters: true, ..inp });
        assert!(ch.illegal() && ch.illegal_count() == 0);
    }
}

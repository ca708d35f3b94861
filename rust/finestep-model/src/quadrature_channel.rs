//! `quadrature_channel`: one encoder channel's decoder, counter, index logic and
//! snapshots, from the filtered levels of its pins.
//!
//! Specification: docs/spec/quadrature_channel.md
//!
//! The decoder compares the filtered `a`, `b` with their values one clock before
//! (`a_p`, `b_p`), so the count moves at most one per clock. Forward is A leading B, the
//! step shaper's quadrature order (A,B) 00 -> 10 -> 11 -> 01: an axis driven in
//! quadrature mode and read back by a channel counts up when its position does. Both
//! inputs changing in one clock cannot be decoded (the direction is unknown): the count
//! holds and the transition is flagged and counted instead of guessed.
//!
//! Nothing is decoded until `live` (the cycle after the filters' first adopted sample
//! is visible), so the power-on levels are never taken for an edge.

/// How the channel turns edges into counts (`ENC_CONTROL.MODE`): the interface's
/// `COUNT_MODE`.
pub use finestep_interface::CountMode;

/// The count change from one clock's filtered levels: `(delta, illegal)`, `delta` in
/// {-1, 0, +1}. Only meaningful while `live`.
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
    /// Filtered A.
    pub a: bool,
    /// Filtered B.
    pub b: bool,
    /// Filtered index, before polarity (`z_level`).
    pub z_level: bool,
    /// The filters have adopted their first sample (`live` follows it one clock later).
    pub primed: bool,
    /// `ENC_CONTROL.MODE`.
    pub mode: CountMode,
    /// `ENC_CONTROL.Z_ACTIVE_HIGH`.
    pub z_active_high: bool,
    /// `ARM_INDEX_LATCH` pulse.
    pub arm_index_latch: bool,
    /// `ARM_INDEX_CLEAR` pulse.
    pub arm_index_clear: bool,
    /// A probe event in this cycle: `PROBE_LATCH` takes the count.
    pub probe_event: bool,
    /// `clear_errors` pulse: clears `ILLEGAL` (a set in the same cycle wins).
    pub clear_errors: bool,
    /// `clear_counters` pulse: zeroes `ILLEGAL_COUNT` (wins over a count).
    pub clear_counters: bool,
    /// `TIMESTAMP` of this cycle, for `edge_time`.
    pub timestamp: u32,
}

impl ChannelInputs {
    /// The index after polarity: `z = z_level` if `Z_ACTIVE_HIGH` else `!z_level`.
    pub fn z(&self) -> bool {
        self.z_level == self.z_active_high
    }
}

/// State of one channel.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct QuadratureChannel {
    a_p: bool,
    b_p: bool,
    /// The index *after polarity* one clock before (the edge detector of `z`).
    z_p: bool,
    live: bool,
    count: u32,
    edge_time: u32,
    illegal: bool,
    illegal_count: u16,
    latch_armed: bool,
    clear_armed: bool,
    index_latch: u32,
    index_seen: bool,
    probe_latch: u32,
}

impl QuadratureChannel {
    /// The count (two's complement, wraps).
    pub fn count(&self) -> u32 {
        self.count
    }

    /// `TIMESTAMP` of the last cycle whose decoding changed the count.
    pub fn edge_time(&self) -> u32 {
        self.edge_time
    }

    /// Decoding runs (the filters' first samples are in).
    pub fn live(&self) -> bool {
        self.live
    }

    /// Sticky `ILLEGAL`: A and B changed in one clock (quadrature modes).
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

    /// `PROBE_LATCH`: the count at the last probe event.
    pub fn probe_latch(&self) -> u32 {
        self.probe_latch
    }

    /// One rising clock edge.
    pub fn step(&mut self, inp: &ChannelInputs) {
        let z = inp.z();
        let (delta, illegal_now) =
            if self.live { decode(inp.mode, inp.a, inp.b, self.a_p, self.b_p) } else { (0, false) };
        let index_event = self.live && z && !self.z_p;

        if index_event && self.latch_armed {
            self.index_latch = self.count;
        }
        self.index_seen = !inp.arm_index_latch && (self.index_seen || (index_event && self.latch_armed));
        if inp.probe_event {
            self.probe_latch = self.count;
        }
        if delta != 0 {
            self.edge_time = inp.timestamp;
        }
        self.count = if index_event && self.clear_armed { 0 } else { self.count.wrapping_add(delta as u32) };
        self.latch_armed = inp.arm_index_latch || (self.latch_armed && !index_event);
        self.clear_armed = inp.arm_index_clear || (self.clear_armed && !index_event);

        self.illegal = illegal_now || (self.illegal && !inp.clear_errors);
        self.illegal_count =
            if inp.clear_counters { 0 } else { self.illegal_count.saturating_add(u16::from(illegal_now)) };

        self.a_p = inp.a;
        self.b_p = inp.b;
        self.z_p = z;
        self.live = inp.primed;
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

    fn live_inputs() -> ChannelInputs {
        ChannelInputs { primed: true, z_active_high: true, ..Default::default() }
    }

    #[test]
    fn index_latch_and_clear_act_once_on_the_rising_index() {
        let mut ch = QuadratureChannel::default();
        let mut inp = live_inputs();
        ch.step(&inp);
        ch.step(&inp);
        assert!(ch.live());
        // Count up to 3.
        for &(a, b) in &GRAY[1..] {
            inp.a = a;
            inp.b = b;
            ch.step(&inp);
        }
        assert_eq!(ch.count(), 3);
        inp.arm_index_latch = true;
        inp.arm_index_clear = true;
        ch.step(&inp);
        inp.arm_index_latch = false;
        inp.arm_index_clear = false;
        assert!(ch.latch_armed() && ch.clear_armed() && !ch.index_seen());
        // Index rises together with a forward edge: latch sees 3, the count is cleared
        // over the decoding, edge_time still follows the decoding.
        inp.z_level = true;
        inp.a = false;
        inp.b = false;
        inp.timestamp = 77;
        ch.step(&inp);
        assert_eq!((ch.index_latch(), ch.count(), ch.edge_time()), (3, 0, 77));
        assert!(ch.index_seen() && !ch.latch_armed() && !ch.clear_armed());
        // Held high: no second event.
        inp.a = true;
        ch.step(&inp);
        assert_eq!(ch.count(), 1);
    }

    #[test]
    fn illegal_transitions_hold_the_count_and_saturate_the_counter() {
        let mut ch = QuadratureChannel { illegal_count: u16::MAX - 1, ..Default::default() };
        let mut inp = live_inputs();
        ch.step(&inp);
        for _ in 0..3 {
            inp.a = !inp.a;
            inp.b = !inp.b;
            ch.step(&inp);
        }
        assert_eq!(ch.count(), 0);
        assert!(ch.illegal());
        assert_eq!(ch.illegal_count(), u16::MAX);
        inp.clear_errors = true;
        inp.clear_counters = true;
        ch.step(&inp);
        assert!(!ch.illegal() && ch.illegal_count() == 0);
    }
}

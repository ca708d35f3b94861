//! `encoder_bank`: the `N_ENC` encoder channels served by one shared decoder in turn,
//! the probe, and the register copies of the counts.
//!
//! Specification: docs/spec/encoder_bank.md
//!
//! `S = max(N_ENC, 2)` slots: in every cycle the decoder visits the channel of the
//! current `slot` (slots at and above `N_ENC` visit nothing) and the slot moves on, unless
//! the register bus serves in this cycle a read of the visited channel's count, edge
//! time or latches (`stall`): the copies live in a RAM whose read port serves the bus and
//! whose write port the visit uses, and the stall keeps a read and a write of the same
//! word out of one clock. A round of `S` slots ends with the prescaler (`ENC_PRESCALE`,
//! counted in rounds); the visits of a round sample their channel's pins when the round
//! before set `sampling`, so each channel is sampled every `S * (ENC_PRESCALE + 1)`
//! clocks, at its own slot. The probe's filter samples at the first visit of each
//! sampling round.
//!
//! A probe event snapshots every axis's step position and `TIMESTAMP` in its cycle and
//! asks for every channel's count; the host-visible `ENC_COUNT`/`ENC_EDGE_TIME` are
//! asked for with `POSITION` (every period boundary, every clock while stopped). A
//! channel's count and edge time change only at its visits, so the copy taken at its
//! first visit at or after the asking cycle (before that visit's update) is exactly the
//! value of the asking cycle: seed 000 measures a roller's surface with the gratings
//! while Z traverses, and the samples must belong together.

use crate::input_filter::{InputFilter, Synchroniser};
use crate::quadrature_channel::{index_active, ChannelInputs, CountMode, QuadratureChannel};
use crate::MAX_AXES;
use finestep_interface::regs;

/// The most encoder channels (`N_ENC <= 4`: the register map has room for four).
pub const MAX_CHANNELS: usize = finestep_interface::params::finestep_top::N_ENC.max as usize;

/// The index of each pin's synchroniser in a channel's `[a, b, z]`.
const PIN_A: usize = 0;
const PIN_B: usize = 1;
const PIN_Z: usize = 2;

/// The registers whose reads stall the visit of their channel: they read the copies in
/// the store (`ENC_COUNT`, `ENC_INDEX_LATCH`, `ENC_PROBE_LATCH`, `ENC_EDGE_TIME`), as
/// `(base address, stride)`.
const STORE_REGISTERS: [(u8, u8); 4] = [
    (regs::enc_count::ADDR, regs::enc_count::STRIDE),
    (regs::enc_index_latch::ADDR, regs::enc_index_latch::STRIDE),
    (regs::enc_probe_latch::ADDR, regs::enc_probe_latch::STRIDE),
    (regs::enc_edge_time::ADDR, regs::enc_edge_time::STRIDE),
];

/// What a register read of a count (`ENC_COUNT`, `ENC_INDEX_LATCH`, `ENC_PROBE_LATCH`)
/// returns in a build whose counts are `count_w` bits (`ENC_COUNT_W`, 16 or 32): the count
/// modulo `2^count_w` as a signed number, sign-extended to 32 bits
/// (docs/spec/encoder_bank.md#narrow-words).
pub fn read_count(count: u32, count_w: u32) -> u32 {
    if count_w >= 32 {
        return count;
    }
    let shift = 32 - count_w;
    (((count << shift) as i32) >> shift) as u32
}

/// What a register read of an edge time (`ENC_EDGE_TIME`) returns in a build whose words
/// are `count_w` bits: `TIMESTAMP`'s low `count_w` bits, zero-extended.
pub fn read_edge_time(edge_time: u32, count_w: u32) -> u32 {
    if count_w >= 32 {
        return edge_time;
    }
    edge_time & ((1u32 << count_w) - 1)
}

/// `S = max(N_ENC, 2)`: the slots of a round for `n_enc` channels.
pub fn slots(n_enc: usize) -> usize {
    n_enc.max(2)
}

/// The channel (below `n_enc`) whose stored registers a read of `addr` (7 bits; higher
/// bits ignored) reads, if any.
pub fn store_channel(addr: u8, n_enc: usize) -> Option<usize> {
    let addr = addr & ((1u32 << regs::ADDRESS_BITS) - 1) as u8;
    STORE_REGISTERS.iter().find_map(|&(base, stride)| {
        let offset = addr.checked_sub(base)?;
        let c = usize::from(offset / stride);
        (offset % stride == 0 && c < n_enc).then_some(c)
    })
}

/// One channel's settings and pulses from its `ENC_CONTROL`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ChannelConfig {
    /// `MODE`.
    pub mode: CountMode,
    /// `Z_ACTIVE_HIGH`.
    pub z_active_high: bool,
    /// `FILTER` (4 bits; 0 acts as 1).
    pub filter: u8,
    /// `ARM_INDEX_LATCH` pulse, high in this cycle.
    pub arm_index_latch: bool,
    /// `ARM_INDEX_CLEAR` pulse, high in this cycle.
    pub arm_index_clear: bool,
}

/// The probe's settings and pulse from `PROBE_CONTROL`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ProbeConfig {
    /// `ACTIVE_HIGH`.
    pub active_high: bool,
    /// `FILTER` (4 bits; 0 acts as 1).
    pub filter: u8,
    /// `ARM` pulse, high in this cycle.
    pub arm: bool,
}

/// What the bank sees in one cycle besides its own state.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct EncoderBankInputs {
    /// `enc_a` pins, bit `c` for channel `c`.
    pub enc_a: u8,
    /// `enc_b` pins.
    pub enc_b: u8,
    /// `enc_z` pins.
    pub enc_z: u8,
    /// `probe_pin`.
    pub probe_pin: bool,
    /// `ENC_PRESCALE`.
    pub prescale: u16,
    /// Each channel's `ENC_CONTROL`.
    pub channels: [ChannelConfig; MAX_CHANNELS],
    /// `PROBE_CONTROL`.
    pub probe: ProbeConfig,
    /// `clear_errors` pulse.
    pub clear_errors: bool,
    /// `clear_counters` pulse.
    pub clear_counters: bool,
    /// `TIMESTAMP` of this cycle.
    pub timestamp: u32,
    /// The core's `position` of every axis in this cycle.
    pub positions: [u32; MAX_AXES],
    /// The position latch takes `POSITION` in this cycle (`latch_now`): the counts and
    /// edge times of this cycle are asked for with it.
    pub latch: bool,
    /// The address of the read the register bus serves in this cycle (its bus stage: the
    /// read granted in the cycle before), if it serves a read: a read of the store of the
    /// channel the decoder would visit stalls the visit.
    pub served_read: Option<u8>,
}

/// One channel's register view (all 0 for a channel the build does not have).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ChannelStatus {
    /// `ENC_COUNT`: the count as copied with `POSITION`.
    pub count: u32,
    /// `ENC_INDEX_LATCH`.
    pub index_latch: u32,
    /// `ENC_PROBE_LATCH`.
    pub probe_latch: u32,
    /// `ENC_EDGE_TIME`: the edge time as copied with `POSITION`.
    pub edge_time: u32,
    /// `ENC_STATUS.ILLEGAL`.
    pub illegal: bool,
    /// `ENC_STATUS.ILLEGAL_COUNT`.
    pub illegal_count: u16,
    /// `ENC_STATUS.INDEX_SEEN`.
    pub index_seen: bool,
    /// `ENC_STATUS.LATCH_ARMED`.
    pub latch_armed: bool,
    /// `ENC_STATUS.CLEAR_ARMED`.
    pub clear_armed: bool,
    /// `ENC_STATUS.A`: filtered A.
    pub a: bool,
    /// `ENC_STATUS.B`: filtered B.
    pub b: bool,
    /// `ENC_STATUS.Z`: filtered index after polarity.
    pub z: bool,
}

/// The bank's register view in one cycle.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct EncoderBankStatus {
    /// Per channel.
    pub channels: [ChannelStatus; MAX_CHANNELS],
    /// `PROBE_STATUS.ARMED`.
    pub probe_armed: bool,
    /// `PROBE_STATUS.SEEN`.
    pub probe_seen: bool,
    /// `PROBE_STATUS.ACTIVE`: the filtered probe is active now.
    pub probe_active: bool,
    /// `PROBE_TIME`.
    pub probe_time: u32,
    /// `PROBE_POSITION[i]`.
    pub probe_positions: [u32; MAX_AXES],
}

impl EncoderBankStatus {
    /// Some channel's `ILLEGAL` is set.
    pub fn any_illegal(&self) -> bool {
        self.channels.iter().any(|c| c.illegal)
    }
}

/// State of the encoder bank.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct EncoderBank {
    n_enc: usize,
    /// `ENC_COUNT_W`: the bits of the counts and edge times the registers show.
    count_w: u32,
    /// The slot of this cycle, `0..S`.
    slot: usize,
    /// The prescaler, counted in rounds.
    presc: u16,
    /// The visits of this round sample.
    sampling: bool,
    /// The synchronisers of every channel's `[a, b, z]` (every clock).
    sync: [[Synchroniser; 3]; MAX_CHANNELS],
    channels: [QuadratureChannel; MAX_CHANNELS],
    /// A position latch asked for the channel's count and edge time; not yet visited.
    latch_pending: [bool; MAX_CHANNELS],
    /// A probe event asked for the channel's count; not yet visited.
    probe_pending: [bool; MAX_CHANNELS],
    /// `ENC_COUNT`: the count copied for the position latch.
    count_copy: [u32; MAX_CHANNELS],
    /// `ENC_EDGE_TIME`: the edge time copied for the position latch.
    edge_time_copy: [u32; MAX_CHANNELS],
    /// `ENC_PROBE_LATCH`: the count copied for the probe.
    probe_copy: [u32; MAX_CHANNELS],
    probe_filter: InputFilter,
    /// The probe's `live`: its filter's `primed` one clock before.
    probe_live: bool,
    /// The probe's `active` one clock before.
    probe_active_p: bool,
    probe_armed: bool,
    probe_seen: bool,
    probe_time: u32,
    probe_positions: [u32; MAX_AXES],
}

impl EncoderBank {
    /// The reset state of a bank of `n_enc` channels (at most [`MAX_CHANNELS`]; more are
    /// not built).
    pub fn new(n_enc: usize) -> Self {
        Self::with_count_width(n_enc, 32)
    }

    /// The reset state of a bank of `n_enc` channels whose counts and edge times are
    /// `count_w` bits (`ENC_COUNT_W`: 16 or 32; 32 and above act as 32).
    pub fn with_count_width(n_enc: usize, count_w: u32) -> Self {
        EncoderBank {
            n_enc: n_enc.min(MAX_CHANNELS),
            count_w: count_w.min(32),
            slot: 0,
            presc: 0,
            sampling: false,
            sync: [[Synchroniser::default(); 3]; MAX_CHANNELS],
            channels: [QuadratureChannel::default(); MAX_CHANNELS],
            latch_pending: [false; MAX_CHANNELS],
            probe_pending: [false; MAX_CHANNELS],
            count_copy: [0; MAX_CHANNELS],
            edge_time_copy: [0; MAX_CHANNELS],
            probe_copy: [0; MAX_CHANNELS],
            probe_filter: InputFilter::default(),
            probe_live: false,
            probe_active_p: false,
            probe_armed: false,
            probe_seen: false,
            probe_time: 0,
            probe_positions: [0; MAX_AXES],
        }
    }

    /// `N_ENC`.
    pub fn n_enc(&self) -> usize {
        self.n_enc
    }

    /// `ENC_COUNT_W`.
    pub fn count_width(&self) -> u32 {
        self.count_w
    }

    /// `S = max(N_ENC, 2)`, the slots of a round.
    pub fn slots(&self) -> usize {
        slots(self.n_enc)
    }

    /// The slot of this cycle.
    pub fn slot(&self) -> usize {
        self.slot
    }

    /// The prescaler's count of rounds to the next sampling round (`presc`).
    pub fn presc(&self) -> u16 {
        self.presc
    }

    /// The visits of this round sample their channel's pins.
    pub fn sampling(&self) -> bool {
        self.sampling
    }

    /// `stall` in this cycle if the bus serves a read of `served_read`.
    pub fn stall(&self, served_read: Option<u8>) -> bool {
        served_read.is_some_and(|addr| store_channel(addr, self.n_enc) == Some(self.slot))
    }

    /// The channel visited in this cycle if the bus serves a read of `served_read`.
    pub fn visit(&self, served_read: Option<u8>) -> Option<usize> {
        (self.slot < self.n_enc && !self.stall(served_read)).then_some(self.slot)
    }

    /// Channel `c`'s state (a channel at or above `N_ENC` stays in reset).
    ///
    /// # Panics
    /// If `c >= MAX_CHANNELS`.
    pub fn channel(&self, c: usize) -> &QuadratureChannel {
        &self.channels[c]
    }

    /// Channel `c`'s pin synchronisers, `[a, b, z]`.
    ///
    /// # Panics
    /// If `c >= MAX_CHANNELS`.
    pub fn synchronisers(&self, c: usize) -> &[Synchroniser; 3] {
        &self.sync[c]
    }

    /// Channel `c`'s `(latch_pending, probe_pending)`.
    ///
    /// # Panics
    /// If `c >= MAX_CHANNELS`.
    pub fn pending(&self, c: usize) -> (bool, bool) {
        (self.latch_pending[c], self.probe_pending[c])
    }

    /// The probe pin's filter.
    pub fn probe_filter(&self) -> &InputFilter {
        &self.probe_filter
    }

    /// The filtered probe is active (`level` after polarity).
    pub fn probe_active(&self, probe: &ProbeConfig) -> bool {
        self.probe_filter.level() == probe.active_high
    }

    /// A probe event in this cycle: the probe became active while armed (and live).
    pub fn probe_event(&self, probe: &ProbeConfig) -> bool {
        self.probe_live && self.probe_active(probe) && !self.probe_active_p && self.probe_armed
    }

    /// `PROBE_STATUS.SEEN`: an event since the last arm.
    pub fn probe_seen(&self) -> bool {
        self.probe_seen
    }

    /// The register view with these settings (polarities decide `Z` and `ACTIVE`).
    pub fn status(&self, channels: &[ChannelConfig; MAX_CHANNELS], probe: &ProbeConfig) -> EncoderBankStatus {
        let mut status = EncoderBankStatus {
            probe_armed: self.probe_armed,
            probe_seen: self.probe_seen,
            probe_active: self.probe_active(probe),
            probe_time: self.probe_time,
            probe_positions: self.probe_positions,
            ..EncoderBankStatus::default()
        };
        for (c, (ch, config)) in self.channels.iter().zip(channels).take(self.n_enc).enumerate() {
            // A narrow build's words (ENC_COUNT_W 16) as its registers read them.
            let w = self.count_w;
            status.channels[c] = ChannelStatus {
                count: read_count(self.count_copy[c], w),
                index_latch: read_count(ch.index_latch(), w),
                probe_latch: read_count(self.probe_copy[c], w),
                edge_time: read_edge_time(self.edge_time_copy[c], w),
                illegal: ch.illegal(),
                illegal_count: ch.illegal_count(),
                index_seen: ch.index_seen(),
                latch_armed: ch.latch_armed(),
                clear_armed: ch.clear_armed(),
                a: ch.a(),
                b: ch.b(),
                z: index_active(ch.z_level(), config.z_active_high),
            };
        }
        status
    }

    /// Some channel's `ILLEGAL` (what [`Self::status`] shows, without building it).
    pub fn any_illegal(&self) -> bool {
        self.channels.iter().take(self.n_enc).any(|channel| channel.illegal())
    }

    /// One rising clock edge.
    pub fn step(&mut self, inp: &EncoderBankInputs) {
        let stall = self.stall(inp.served_read);
        let visit = self.visit(inp.served_read);
        let probe_event = self.probe_event(&inp.probe);
        let probe_active = self.probe_active(&inp.probe);

        for c in 0..self.n_enc {
            let cfg = &inp.channels[c];
            let channel = &mut self.channels[c];
            let sync = &mut self.sync[c];
            let visited = visit == Some(c);
            if visited {
                // The copies, from the values before this visit's update.
                if self.latch_pending[c] || inp.latch {
                    self.count_copy[c] = channel.count();
                    self.edge_time_copy[c] = channel.edge_time();
                }
                if self.probe_pending[c] || probe_event {
                    self.probe_copy[c] = channel.count();
                }
            }
            self.latch_pending[c] = !visited && (self.latch_pending[c] || inp.latch);
            self.probe_pending[c] = !visited && (self.probe_pending[c] || probe_event);
            channel.step(&ChannelInputs {
                sample: visited && self.sampling,
                raw_a: sync[PIN_A].raw(),
                raw_b: sync[PIN_B].raw(),
                raw_z: sync[PIN_Z].raw(),
                mode: cfg.mode,
                z_active_high: cfg.z_active_high,
                filter: cfg.filter,
                arm_index_latch: cfg.arm_index_latch,
                arm_index_clear: cfg.arm_index_clear,
                clear_errors: inp.clear_errors,
                clear_counters: inp.clear_counters,
                timestamp: inp.timestamp,
            });
            let pins = [inp.enc_a, inp.enc_b, inp.enc_z].map(|mask| mask >> c & 1 != 0);
            for (flops, pin) in sync.iter_mut().zip(pins) {
                flops.step(pin);
            }
        }

        if probe_event {
            self.probe_positions = inp.positions;
            self.probe_time = inp.timestamp;
        }
        self.probe_seen = !inp.probe.arm && (self.probe_seen || probe_event);
        self.probe_armed = inp.probe.arm || (self.probe_armed && !probe_event);
        self.probe_active_p = probe_active;
        self.probe_live = self.probe_filter.primed();
        let probe_sample = self.slot == 0 && !stall && self.sampling;
        self.probe_filter.step(inp.probe_pin, probe_sample, inp.probe.filter);

        if !stall {
            let last = self.slots() - 1;
            if self.slot == last {
                self.sampling = self.presc == 0;
                self.presc = if self.presc == 0 { inp.prescale } else { self.presc - 1 };
                self.slot = 0;
            } else {
                self.slot += 1;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn inputs() -> EncoderBankInputs {
        let channel = ChannelConfig { z_active_high: true, filter: 1, ..Default::default() };
        EncoderBankInputs {
            channels: [channel; MAX_CHANNELS],
            probe: ProbeConfig { active_high: true, filter: 1, arm: false },
            ..Default::default()
        }
    }

    /// The quadrature states in forward order.
    const GRAY: [(bool, bool); 4] = [(false, false), (true, false), (true, true), (false, true)];

    /// A small deterministic generator for the pin and bus patterns.
    struct Rng(u64);

    impl Rng {
        fn below(&mut self, n: u64) -> u64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            self.0 % n
        }
    }

    /// Round `r` (cycles `r * S .. r * S + S - 1` without stalls) samples: from round 1,
    /// every `PRESCALE + 1` rounds.
    fn sampling_round(round: u64, prescale: u16) -> bool {
        round >= 1 && (round - 1) % (u64::from(prescale) + 1) == 0
    }

    #[test]
    fn narrow_words_read_counts_sign_extended_and_edge_times_zero_extended() {
        // docs/spec/encoder_bank.md#narrow-words: the count modulo 2^16 as a signed number.
        assert_eq!(read_count(0x7FFF, 16), 0x7FFF);
        assert_eq!(read_count(0x8000, 16), 0xFFFF_8000);
        assert_eq!(read_count(0xFFFF_FFFF, 16), 0xFFFF_FFFF, "-1 stays -1");
        assert_eq!(read_count(0x0001_0005, 16), 5, "the count wrapped at 2^16");
        assert_eq!(read_count(0xFFFE_7FFF, 16), 0x7FFF, "-98 305 wraps to +32 767");
        assert_eq!(read_edge_time(0xABCD_8001, 16), 0x8001, "TIMESTAMP's low bits, not sign-extended");
        for value in [0u32, 1, 0x8000_0000, 0xFFFF_FFFF] {
            assert_eq!((read_count(value, 32), read_edge_time(value, 32)), (value, value));
        }
        // Through the register view: a channel's copy as the narrow build reads it.
        let mut bank = EncoderBank::with_count_width(2, 16);
        bank.count_copy[1] = 0x0001_8000;
        bank.edge_time_copy[1] = 0x1234_FEDC;
        bank.probe_copy[1] = 0xFFFF_0001;
        let status = bank.status(&[ChannelConfig::default(); MAX_CHANNELS], &ProbeConfig::default()).channels[1];
        assert_eq!((status.count, status.edge_time, status.probe_latch), (0xFFFF_8000, 0xFEDC, 1));
        assert_eq!(bank.count_width(), 16);
        assert_eq!(EncoderBank::new(2).count_width(), 32);
    }

    #[test]
    fn the_schedule_visits_the_channels_in_turn_and_samples_every_prescale_plus_one_rounds() {
        for n_enc in 1..=MAX_CHANNELS {
            for prescale in [0u16, 1, 3] {
                let mut bank = EncoderBank::new(n_enc);
                let s = slots(n_enc) as u64;
                assert_eq!((bank.slot(), bank.presc(), bank.sampling()), (0, 0, false), "reset");
                let inp = EncoderBankInputs { prescale, ..inputs() };
                for cycle in 0..40 * s {
                    let slot = (cycle % s) as usize;
                    assert_eq!(bank.slot(), slot, "N_ENC {n_enc} cycle {cycle}");
                    let visit = (slot < n_enc).then_some(slot);
                    assert_eq!(bank.visit(None), visit);
                    assert_eq!(bank.sampling(), sampling_round(cycle / s, prescale), "N_ENC {n_enc} cycle {cycle}");
                    bank.step(&inp);
                }
            }
        }
    }

    #[test]
    fn a_sampling_visit_samples_its_channel_and_decodes_in_the_same_visit() {
        // Channel 2 of 4, PRESCALE 1: its sampling visits are cycles 4 + 2 + 8k.
        let mut bank = EncoderBank::new(4);
        let mut inp = EncoderBankInputs { prescale: 1, ..inputs() };
        let mut counted = Vec::new();
        for cycle in 0..60u32 {
            // A rises at cycle 8: raw from cycle 10; first sampled at cycle 14 (the first
            // sample, cycle 6, adopted A = 0).
            inp.enc_a = if cycle >= 8 { 0b100 } else { 0 };
            inp.timestamp = cycle;
            let before = bank.channel(2).count();
            bank.step(&inp);
            if bank.channel(2).count() != before {
                counted.push(cycle);
            }
            if cycle == 6 {
                let primed: Vec<bool> = (0..4).map(|c| bank.channel(c).primed()).collect();
                assert_eq!(primed, [true, true, true, false], "round 1 samples, channel c at cycle 4 + c");
            }
        }
        assert_eq!(counted, [14]);
        assert_eq!(bank.channel(2).edge_time(), 14);
        // A change at cycle 9 (raw from 11, before the sample at 14) counts at 14 too;
        // at cycle 13 (raw from 15) it waits for 22.
        for (rise, counts_at) in [(9u32, 14u32), (12, 14), (13, 22)] {
            let mut bank = EncoderBank::new(4);
            let mut at = None;
            for cycle in 0..40u32 {
                inp.enc_a = if cycle >= rise { 0b100 } else { 0 };
                inp.timestamp = cycle;
                bank.step(&inp);
                if at.is_none() && bank.channel(2).count() == 1 {
                    at = Some(cycle);
                }
            }
            assert_eq!(at, Some(counts_at), "A rising at cycle {rise}");
        }
    }

    #[test]
    fn a_stall_moves_a_visit_by_one_cycle_and_loses_nothing() {
        for n_enc in 1..=MAX_CHANNELS {
            let mut rng = Rng(0x9E37_79B9_7F4A_7C15 ^ n_enc as u64);
            let mut free = EncoderBank::new(n_enc);
            let mut stalled = EncoderBank::new(n_enc);
            let mut inp = EncoderBankInputs { prescale: 1, ..inputs() };
            let mut phase = [0usize; MAX_CHANNELS];
            let mut free_visits = Vec::new();
            let mut stalled_visits = Vec::new();
            let mut stalls = 0;
            // Slow pins (8 rounds a state), so the stalls' delays never lose a state.
            let hold = 16 * slots(n_enc) as u64;
            let mut reads = [0usize; 6];
            for cycle in 0..4000u64 {
                if cycle % hold == 0 {
                    for (c, ph) in phase.iter_mut().enumerate().take(n_enc) {
                        *ph = (*ph + if c % 2 == 0 { 1 } else { 3 }) % 4;
                        let (a, b) = GRAY[*ph];
                        inp.enc_a = inp.enc_a & !(1 << c) | u8::from(a) << c;
                        inp.enc_b = inp.enc_b & !(1 << c) | u8::from(b) << c;
                    }
                }
                inp.latch = cycle % 7 == 0;
                // Reads of every channel's registers, the store's and others.
                let kind = rng.below(6) as usize;
                let bases = [
                    regs::enc_count::ADDR,
                    regs::enc_index_latch::ADDR,
                    regs::enc_probe_latch::ADDR,
                    regs::enc_edge_time::ADDR,
                    regs::enc_status::ADDR,
                    regs::enc_control::ADDR,
                ];
                let addr = bases[kind] + rng.below(MAX_CHANNELS as u64) as u8;
                let read = (rng.below(3) == 0).then_some(addr);
                let stall = stalled.stall(read);
                let expected_stall = kind < 4 && read.is_some() && usize::from(addr - bases[kind]) == stalled.slot();
                assert_eq!(stall, expected_stall && stalled.slot() < n_enc, "cycle {cycle}, read {read:?}");
                let slot = stalled.slot();
                if stall {
                    stalls += 1;
                    reads[kind] += 1;
                } else {
                    stalled_visits.push((stalled.visit(read), stalled.sampling()));
                    // The unstalled bank runs one cycle per unstalled cycle of the other.
                    free_visits.push((free.visit(None), free.sampling()));
                }
                stalled.step(&EncoderBankInputs { served_read: read, ..inp });
                if stall {
                    assert_eq!(stalled.slot(), slot, "a stall keeps the slot");
                } else {
                    free.step(&inp);
                }
            }
            assert!(stalls > 100 && reads[..4].iter().all(|&r| r > 10), "N_ENC {n_enc}: {stalls} stalls {reads:?}");
            let first_difference = stalled_visits.iter().zip(&free_visits).position(|(s, f)| s != f);
            assert_eq!(first_difference, None, "N_ENC {n_enc}: the visits in order");
            assert!(free_visits.len() + stalls == 4000);
            for c in 0..n_enc {
                let (f, s) = (free.channel(c), stalled.channel(c));
                assert_eq!((s.count(), s.illegal()), (f.count(), false), "N_ENC {n_enc} channel {c}");
                assert!(f.count() as i32 != 0);
            }
        }
    }

    #[test]
    fn copies_are_the_counts_of_the_asking_cycle_within_s_cycles() {
        for n_enc in 1..=MAX_CHANNELS {
            let s = slots(n_enc) as u64;
            let mut rng = Rng(0x2545_F491_4F6C_DD1D ^ n_enc as u64);
            let mut bank = EncoderBank::new(n_enc);
            let mut inp = inputs();
            let mut phase = [0usize; MAX_CHANNELS];
            // Per channel: the asked (count, edge time) and the cycle asked, until visited.
            let mut asked: [Option<(u32, u32, u64)>; MAX_CHANNELS] = [None; MAX_CHANNELS];
            let mut probe_asked: [Option<(u32, u64)>; MAX_CHANNELS] = [None; MAX_CHANNELS];
            let mut copies = 0;
            for cycle in 0..6000u64 {
                // Quadrature moving each channel's count every S to 3S clocks.
                if rng.below(s) == 0 {
                    let c = rng.below(n_enc as u64) as usize;
                    phase[c] = (phase[c] + if rng.below(3) == 0 { 3 } else { 1 }) % 4;
                    let (a, b) = GRAY[phase[c]];
                    inp.enc_a = inp.enc_a & !(1 << c) | u8::from(a) << c;
                    inp.enc_b = inp.enc_b & !(1 << c) | u8::from(b) << c;
                }
                // Bursts of latches (a stopped machine latches every cycle), and single ones.
                inp.latch = if cycle % 500 < 40 { true } else { rng.below(2 * s) == 0 };
                inp.probe.arm = rng.below(4 * s) == 0;
                inp.probe_pin = rng.below(3 * s) != 0 && cycle % 50 > 10;
                inp.timestamp = cycle as u32;
                let read = (rng.below(4) == 0).then(|| regs::enc_count::ADDR + rng.below(4) as u8);
                let visit = bank.visit(read);
                let probe_event = bank.probe_event(&inp.probe);
                for c in 0..n_enc {
                    let ch = bank.channel(c);
                    if inp.latch {
                        asked[c] = Some((ch.count(), ch.edge_time(), cycle));
                    }
                    if probe_event {
                        probe_asked[c] = Some((ch.count(), cycle));
                    }
                }
                bank.step(&EncoderBankInputs { served_read: read, ..inp });
                let status = bank.status(&inp.channels, &inp.probe);
                if probe_event {
                    // An arm in the event's cycle wins over SEEN.
                    assert_eq!((status.probe_time, status.probe_seen), (cycle as u32, !inp.probe.arm));
                }
                let Some(c) = visit else { continue };
                assert_eq!(bank.pending(c), (false, false), "a visit takes every copy asked for");
                if let Some((count, edge_time, at)) = asked[c].take() {
                    let copy = status.channels[c];
                    assert_eq!((copy.count, copy.edge_time), (count, edge_time), "N_ENC {n_enc} ch {c} asked {at}");
                    copies += 1;
                }
                if let Some((count, at)) = probe_asked[c].take() {
                    assert_eq!(status.channels[c].probe_latch, count, "N_ENC {n_enc} ch {c} probed {at}");
                    copies += 1;
                }
                for other in (0..n_enc).filter(|&o| o != c) {
                    let waited = [asked[other].map(|a| a.2), probe_asked[other].map(|a| a.1)];
                    for at in waited.into_iter().flatten() {
                        assert!(cycle - at < s + 8, "N_ENC {n_enc} ch {other} waits since {at} at {cycle}");
                    }
                }
            }
            assert!(copies > 1000, "N_ENC {n_enc}: {copies} copies checked");
        }
    }

    #[test]
    fn a_copy_appears_at_the_first_visit_at_or_after_the_asking_cycle() {
        let mut bank = EncoderBank::new(4);
        let mut inp = inputs();
        for cycle in 0..16 {
            // Channel 1 forward by one edge at cycle 8: raw from 10, counted at 13.
            inp.enc_a = if cycle >= 8 { 0b10 } else { 0 };
            inp.timestamp = cycle;
            bank.step(&inp);
        }
        assert_eq!(bank.channel(1).count(), 1);
        assert_eq!(bank.status(&inp.channels, &inp.probe).channels[1].count, 0);
        // Cycle 16 (slot 0) asks; channels 0..3 copy at cycles 16..19, channel 1 at 17.
        bank.step(&EncoderBankInputs { latch: true, ..inp });
        assert_eq!(bank.pending(1), (true, false));
        assert_eq!(bank.status(&inp.channels, &inp.probe).channels[1].count, 0);
        // A read of ENC_COUNT[1] served at 17 stalls channel 1's visit to 18.
        bank.step(&EncoderBankInputs { served_read: Some(regs::enc_count::addr(1)), ..inp });
        assert_eq!((bank.slot(), bank.pending(1)), (1, (true, false)));
        bank.step(&inp);
        assert_eq!(bank.pending(1), (false, false));
        let status = bank.status(&inp.channels, &inp.probe).channels[1];
        assert_eq!((status.count, status.edge_time), (1, 13));
        assert_eq!(bank.pending(3), (true, false));
    }

    #[test]
    fn one_channel_has_an_idle_slot() {
        let mut bank = EncoderBank::new(1);
        let inp = inputs();
        assert_eq!(bank.slots(), 2);
        for cycle in 0..20 {
            let idle = cycle % 2 == 1;
            assert_eq!(bank.visit(None), (!idle).then_some(0), "cycle {cycle}");
            // A read of channel 0's count stalls slot 0 only.
            let read = Some(regs::enc_count::addr(0));
            assert_eq!(bank.stall(read), !idle);
            assert!(!bank.stall(Some(regs::enc_count::addr(1))), "no channel 1");
            bank.step(&inp);
        }
    }

    #[test]
    fn a_probe_event_snapshots_every_channel_and_axis_on_one_clock() {
        let mut bank = EncoderBank::new(2);
        let mut inp = inputs();
        // Power on with channel 1 resting at A = B = 1: adopted, no count, no illegal.
        inp.enc_a = 0b10;
        inp.enc_b = 0b10;
        for _ in 0..4 {
            bank.step(&inp);
        }
        assert!(bank.channel(1).primed() && bank.channel(1).count() == 0 && !bank.channel(1).illegal());
        assert!(bank.probe_filter().primed(), "sampled at the first visit of the round (cycle 2)");
        // Channel 0 forward by one edge.
        inp.enc_a = 0b11;
        for _ in 0..4 {
            bank.step(&inp);
        }
        assert_eq!(bank.channel(0).count(), 1);
        inp.probe.arm = true;
        bank.step(&inp);
        inp.probe.arm = false;
        let probe = inp.probe;
        assert!(bank.status(&inp.channels, &probe).probe_armed);
        // Cycle 9: the pin rises; raw from 11; sampled at slot 0 of cycle 12; event at 13.
        inp.probe_pin = true;
        inp.positions[3] = 1234;
        let mut cycle = 9;
        while !bank.probe_event(&probe) {
            inp.timestamp = cycle;
            bank.step(&inp);
            cycle += 1;
        }
        assert_eq!(cycle, 13);
        // Cycle 13 is slot 1: channel 1 copies in the event's cycle, channel 0 at its
        // visit in 14. Channel 0 moves back from cycle 13 on (counted at 16): the copy
        // is still the count of the event's cycle.
        inp.timestamp = 13;
        inp.enc_a = 0b10;
        bank.step(&inp);
        assert_eq!(bank.pending(0), (false, true));
        let status = bank.status(&inp.channels, &probe);
        assert!(status.probe_seen && !status.probe_armed && status.probe_active);
        assert_eq!((status.probe_time, status.probe_positions[3]), (13, 1234));
        assert_eq!(status.channels[1].probe_latch, 0);
        for _ in 0..8 {
            bank.step(&inp);
        }
        let status = bank.status(&inp.channels, &probe);
        assert_eq!(bank.channel(0).count(), 0, "channel 0 went back after the event");
        assert_eq!((status.channels[0].probe_latch, status.channels[1].probe_latch), (1, 0));
        assert_eq!(status.channels[2], ChannelStatus::default(), "channel 2 is not built");
    }

    #[test]
    fn arm_wins_over_an_event_in_its_cycle() {
        let mut bank = EncoderBank::new(2);
        let mut inp = inputs();
        for _ in 0..4 {
            bank.step(&inp);
        }
        bank.step(&EncoderBankInputs { probe: ProbeConfig { arm: true, ..inp.probe }, ..inp });
        inp.probe_pin = true;
        while !bank.probe_event(&inp.probe) {
            bank.step(&inp);
        }
        bank.step(&EncoderBankInputs { probe: ProbeConfig { arm: true, ..inp.probe }, ..inp });
        let status = bank.status(&inp.channels, &inp.probe);
        assert!(status.probe_armed && !status.probe_seen);
    }
}

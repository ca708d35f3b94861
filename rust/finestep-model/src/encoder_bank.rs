//! `encoder_bank`: the `N_ENC` encoder channels on one sampling prescaler, the probe,
//! and the register copies of the counts.
//!
//! Specification: docs/spec/encoder_bank.md
//!
//! The channels and the probe share one prescaler (`ENC_PRESCALE`) so that every
//! filtered input moves on the same clocks. A probe event snapshots every channel's
//! count, every axis's step position and `TIMESTAMP` on one clock: seed 000 measures a
//! roller's surface with the gratings while Z traverses, and the samples must belong
//! together. For the same reason the host-visible `ENC_COUNT`/`ENC_EDGE_TIME` are copies
//! taken together with `POSITION` (every period boundary, every clock while stopped), so
//! positions, counts and edge times read after a boundary come from one clock.

use crate::input_filter::{InputFilter, Prescaler};
use crate::quadrature_channel::{ChannelInputs, CountMode, QuadratureChannel};
use crate::MAX_AXES;

/// The most encoder channels (`N_ENC <= 4`: the register map has room for four).
pub const MAX_CHANNELS: usize = finestep_interface::params::finestep_top::N_ENC.max as usize;

/// The index of each pin's filter in a channel's `[a, b, z]`.
const PIN_A: usize = 0;
const PIN_B: usize = 1;
const PIN_Z: usize = 2;

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
    /// The position latch takes `POSITION` in this cycle: the counts and edge times are
    /// copied with it.
    pub latch: bool,
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
    prescaler: Prescaler,
    filters: [[InputFilter; 3]; MAX_CHANNELS],
    channels: [QuadratureChannel; MAX_CHANNELS],
    probe_filter: InputFilter,
    probe_live: bool,
    /// The probe's `active` one clock before.
    probe_active_p: bool,
    probe_armed: bool,
    probe_seen: bool,
    probe_time: u32,
    probe_positions: [u32; MAX_AXES],
    latched_count: [u32; MAX_CHANNELS],
    latched_edge_time: [u32; MAX_CHANNELS],
}

impl EncoderBank {
    /// The reset state of a bank of `n_enc` channels (at most [`MAX_CHANNELS`]; more are
    /// not built).
    pub fn new(n_enc: usize) -> Self {
        EncoderBank {
            n_enc: n_enc.min(MAX_CHANNELS),
            prescaler: Prescaler::default(),
            filters: [[InputFilter::default(); 3]; MAX_CHANNELS],
            channels: [QuadratureChannel::default(); MAX_CHANNELS],
            probe_filter: InputFilter::default(),
            probe_live: false,
            probe_active_p: false,
            probe_armed: false,
            probe_seen: false,
            probe_time: 0,
            probe_positions: [0; MAX_AXES],
            latched_count: [0; MAX_CHANNELS],
            latched_edge_time: [0; MAX_CHANNELS],
        }
    }

    /// `N_ENC`.
    pub fn n_enc(&self) -> usize {
        self.n_enc
    }

    /// The shared prescaler.
    pub fn prescaler(&self) -> &Prescaler {
        &self.prescaler
    }

    /// Channel `c`'s decoder and counter (a channel at or above `N_ENC` stays in reset).
    ///
    /// # Panics
    /// If `c >= MAX_CHANNELS`.
    pub fn channel(&self, c: usize) -> &QuadratureChannel {
        &self.channels[c]
    }

    /// Channel `c`'s pin filters, `[a, b, z]`.
    ///
    /// # Panics
    /// If `c >= MAX_CHANNELS`.
    pub fn filters(&self, c: usize) -> &[InputFilter; 3] {
        &self.filters[c]
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
        let built = self.channels.iter().zip(&self.filters).zip(channels).take(self.n_enc);
        for (c, ((ch, filters), config)) in built.enumerate() {
            status.channels[c] = ChannelStatus {
                count: self.latched_count[c],
                index_latch: ch.index_latch(),
                probe_latch: ch.probe_latch(),
                edge_time: self.latched_edge_time[c],
                illegal: ch.illegal(),
                illegal_count: ch.illegal_count(),
                index_seen: ch.index_seen(),
                latch_armed: ch.latch_armed(),
                clear_armed: ch.clear_armed(),
                a: filters[PIN_A].level(),
                b: filters[PIN_B].level(),
                z: filters[PIN_Z].level() == config.z_active_high,
            };
        }
        status
    }

    /// One rising clock edge.
    pub fn step(&mut self, inp: &EncoderBankInputs) {
        let sample = self.prescaler.sample();
        let probe_event = self.probe_event(&inp.probe);
        let probe_active = self.probe_active(&inp.probe);

        for c in 0..self.n_enc {
            let cfg = &inp.channels[c];
            let filters = &mut self.filters[c];
            let channel = &mut self.channels[c];
            if inp.latch {
                self.latched_count[c] = channel.count();
                self.latched_edge_time[c] = channel.edge_time();
            }
            channel.step(&ChannelInputs {
                a: filters[PIN_A].level(),
                b: filters[PIN_B].level(),
                z_level: filters[PIN_Z].level(),
                primed: filters.iter().all(InputFilter::primed),
                mode: cfg.mode,
                z_active_high: cfg.z_active_high,
                arm_index_latch: cfg.arm_index_latch,
                arm_index_clear: cfg.arm_index_clear,
                probe_event,
                clear_errors: inp.clear_errors,
                clear_counters: inp.clear_counters,
                timestamp: inp.timestamp,
            });
            let pins = [inp.enc_a, inp.enc_b, inp.enc_z].map(|mask| mask >> c & 1 != 0);
            for (filter, pin) in filters.iter_mut().zip(pins) {
                filter.step(pin, sample, cfg.filter);
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
        self.probe_filter.step(inp.probe_pin, sample, inp.probe.filter);
        self.prescaler.step(inp.prescale);
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

    #[test]
    fn a_probe_event_snapshots_every_channel_and_axis_on_one_clock() {
        let mut bank = EncoderBank::new(2);
        let mut inp = inputs();
        // Power on with channel 1 resting at A = B = 1: adopted, no count, no illegal.
        inp.enc_a = 0b10;
        inp.enc_b = 0b10;
        for _ in 0..6 {
            bank.step(&inp);
        }
        assert!(bank.channel(1).live() && bank.channel(1).count() == 0 && !bank.channel(1).illegal());
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
        inp.probe_pin = true;
        inp.positions[3] = 1234;
        inp.timestamp = 99;
        let mut clocks = 0;
        while !bank.probe_event(&probe) {
            bank.step(&inp);
            clocks += 1;
        }
        assert_eq!(clocks, 3, "2 synchroniser clocks and 1 sample");
        bank.step(&inp);
        let status = bank.status(&inp.channels, &probe);
        assert!(status.probe_seen && !status.probe_armed && status.probe_active);
        assert_eq!((status.probe_time, status.probe_positions[3]), (99, 1234));
        assert_eq!((status.channels[0].probe_latch, status.channels[1].probe_latch), (1, 0));
        assert_eq!(status.channels[2], ChannelStatus::default(), "channel 2 is not built");
    }

    #[test]
    fn counts_and_edge_times_reach_the_registers_only_with_the_latch() {
        let mut bank = EncoderBank::new(1);
        let mut inp = inputs();
        for _ in 0..4 {
            bank.step(&inp);
        }
        inp.enc_a = 1;
        inp.timestamp = 5;
        for _ in 0..4 {
            bank.step(&inp);
        }
        assert_eq!(bank.channel(0).count(), 1);
        assert_eq!(bank.status(&inp.channels, &inp.probe).channels[0].count, 0);
        inp.latch = true;
        bank.step(&inp);
        let status = bank.status(&inp.channels, &inp.probe).channels[0];
        assert_eq!((status.count, status.edge_time), (1, 5));
    }
}

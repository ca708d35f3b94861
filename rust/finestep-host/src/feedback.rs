//! The feedback side of a [`Machine`]: encoder and grating counters, the probe, the hand
//! wheel and the jog, at the level a machine builder thinks in, plus velocity estimation
//! from the counters' edge timestamps.

use finestep_interface::rate::max_increment_in;
use finestep_interface::{DriveTiming, Increment};

use crate::regs::{
    command, enc_control, enc_count, enc_edge_time, enc_index_latch, enc_prescale, enc_probe_latch, enc_status,
    jog_accel, jog_control, jog_remaining, jog_scale, jog_status, jog_velocity, jog_vmax, jog_window, mpg_control,
    mpg_count, mpg_detents, mpg_status, position, probe_control, probe_position, probe_status, probe_time,
};
use crate::{Bus, BusError, Machine};

/// How a channel decodes its A/B inputs (`ENC_CONTROL.MODE`), and the jog's detent
/// multiplier (`JOG_CONTROL.MULTIPLIER`): the interface's field values.
pub use finestep_interface::{CountMode, JogMultiplier};

/// Configuration of one encoder channel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EncoderSetup {
    /// Decoding.
    pub mode: CountMode,
    /// The index input is active high.
    pub z_active_high: bool,
    /// Samples of the other level before a filtered input changes (0 acts as 1, at most 15).
    pub filter: u8,
}

impl Default for EncoderSetup {
    /// The reset state: x4, index active high, the shortest filter.
    fn default() -> Self {
        EncoderSetup { mode: CountMode::X4, z_active_high: true, filter: 1 }
    }
}

/// Every axis's step position and every channel's count and last edge time, all latched
/// on one clock.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FeedbackSnapshot {
    /// Steps per axis.
    pub steps: Vec<i32>,
    /// Counts per encoder channel, as `ENC_COUNT` reads (sign-extended from 16 bits on a
    /// core with narrow words, [`crate::Caps::enc_count_w`]).
    pub counts: Vec<i32>,
    /// Counts per encoder channel extended to 64 bits by this driver: the first read's
    /// count plus every later read's difference from the one before, taken modulo
    /// `2^enc_count_w` as a signed number (exact while a channel moves fewer than
    /// `2^(enc_count_w - 1)` counts between two reads; docs/spec/encoder_bank.md#narrow-words).
    pub positions: Vec<i64>,
    /// `TIMESTAMP` of each channel's last count change ([`EdgeTimeExtender`]: on a core
    /// with narrow words, extended from its low 16 bits against `latch_time`).
    pub edge_times: Vec<u32>,
    /// `TIMESTAMP` of the latch.
    pub latch_time: u32,
    /// `steps` and `latch_time` are the probe event's snapshot, not the period latch's: a
    /// core with [`crate::Caps::one_snapshot`] whose probe has latched
    /// ([`Machine::probe_holds_positions`]), or whose released snapshot the period latch
    /// has not replaced yet ([`Machine::release_probe_snapshot`]); the counts and edge
    /// times are the period latch's still (docs/spec/register_file.md#one-snapshot).
    pub probe_held: bool,
}

/// What a probe event latched.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ProbeHit {
    /// Counts per encoder channel at the event, as `ENC_PROBE_LATCH` reads.
    pub counts: Vec<i32>,
    /// The same on the scale of [`FeedbackSnapshot::positions`]: extended against the
    /// last [`Machine::feedback`]'s position (exact while the channel moved fewer than
    /// `2^(enc_count_w - 1)` counts between the event and that read).
    pub positions: Vec<i64>,
    /// Steps per axis at the event.
    pub steps: Vec<i32>,
    /// `TIMESTAMP` of the event.
    pub time: u32,
}

/// The hand wheel's counters and health.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HandWheelState {
    /// Edges counted x4.
    pub edges: i32,
    /// Detents of 4 edges.
    pub detents: i32,
    /// Sticky: an illegal transition was seen.
    pub illegal: bool,
    /// Illegal transitions counted (saturating).
    pub illegal_count: u16,
}

/// Configuration of the hand-wheel jog.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JogSetup {
    /// The axis moved.
    pub axis: usize,
    /// Detent multiplier.
    pub multiplier: JogMultiplier,
    /// Follow every detent, later if need be (true), or drop detents beyond `window`.
    pub follow: bool,
    /// Axis travel per detent at x1, in steps (negative reverses the wheel).
    pub scale: Increment,
    /// Velocity limit in steps per period.
    pub vmax: Increment,
    /// Acceleration limit: the largest change of the increment per period, steps.
    pub accel: Increment,
    /// Drop mode's largest target distance, whole steps.
    pub window: u16,
}

/// The jog's state.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct JogState {
    /// The jog drives the core.
    pub engaged: bool,
    /// Decelerating to disengage.
    pub stopping: bool,
    /// Sticky: a jog and a FIFO run were both requested, or the jog could not engage.
    pub refused: bool,
    /// Detents dropped in drop mode.
    pub dropped: u16,
    /// Target minus commanded position, whole steps (floor).
    pub remaining: i32,
    /// The current increment, steps per period.
    pub velocity: Increment,
}

/// Why a feedback request was refused before anything was written.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum FeedbackError {
    /// The channel does not exist in this core.
    #[error("encoder channel {0}: the core has {1} channels")]
    Channel(usize, usize),
    /// The axis does not exist in this core.
    #[error("axis {0}: the core has {1} axes")]
    Axis(usize, usize),
    /// The core was built without the hand wheel.
    #[error("the core has no hand wheel")]
    NoHandWheel,
    /// A filter length over 15 samples.
    #[error("filter length {0} exceeds 15 samples")]
    Filter(u8),
    /// The jog's velocity limit is over the axis's rated rate while reversing.
    #[error("jog vmax {vmax} steps/period exceeds the axis's rated rate {max} (reversing, P = {period} clocks)")]
    Rate {
        /// Requested limit.
        vmax: Increment,
        /// Largest allowed.
        max: Increment,
        /// The period in clocks.
        period: u32,
    },
    /// A negative or zero limit where a positive one is needed.
    #[error("jog {0} must be positive")]
    Limit(&'static str),
    /// The jog needs a period of at least 128 clocks.
    #[error("the jog needs PERIOD_CLOCKS >= 128, it is {0}")]
    Period(u32),
}

impl<B: Bus> Machine<B> {
    fn check_channel(&self, channel: usize) -> Result<(), FeedbackError> {
        if channel >= self.caps.n_enc {
            return Err(FeedbackError::Channel(channel, self.caps.n_enc));
        }
        Ok(())
    }

    /// The encoders' and the probe's sampling: every `prescale + 1` rounds of the encoder
    /// bank's `S = max(N_ENC, 2)` slots, so a channel is sampled every `S * (prescale + 1)`
    /// clocks (docs/spec/encoder_bank.md).
    pub fn set_encoder_prescale(&mut self, prescale: u16) -> Result<(), BusError> {
        self.bus.write(enc_prescale::ADDR, enc_prescale::PRESCALE.set(0, u32::from(prescale)))
    }

    fn encoder_control_word(setup: &EncoderSetup) -> u32 {
        let word = enc_control::MODE.set(0, setup.mode.bits().into());
        let word = enc_control::Z_ACTIVE_HIGH.set(word, setup.z_active_high.into());
        enc_control::FILTER.set(word, u32::from(setup.filter))
    }

    /// Configures encoder channel `channel`.
    pub fn configure_encoder(&mut self, channel: usize, setup: &EncoderSetup) -> Result<(), BusError> {
        self.check_channel(channel)?;
        if setup.filter > 15 {
            return Err(FeedbackError::Filter(setup.filter).into());
        }
        self.bus.write(enc_control::addr(channel), Self::encoder_control_word(setup))
    }

    /// Arms channel `channel`'s index: latch the count at the next index event, and/or
    /// zero it then. `setup` is written again with the arms (the register holds both).
    pub fn arm_index(
        &mut self,
        channel: usize,
        setup: &EncoderSetup,
        latch: bool,
        clear: bool,
    ) -> Result<(), BusError> {
        self.check_channel(channel)?;
        let word = Self::encoder_control_word(setup);
        let word = enc_control::ARM_INDEX_LATCH.set(word, latch.into());
        let word = enc_control::ARM_INDEX_CLEAR.set(word, clear.into());
        self.bus.write(enc_control::addr(channel), word)
    }

    /// The count latched at channel `channel`'s last armed index event, if one came
    /// since the last arming.
    pub fn index_latch(&mut self, channel: usize) -> Result<Option<i32>, BusError> {
        self.check_channel(channel)?;
        let status = self.bus.read_one(enc_status::addr(channel))?;
        if enc_status::INDEX_SEEN.get(status) == 0 {
            return Ok(None);
        }
        Ok(Some(self.bus.read_one(enc_index_latch::addr(channel))? as i32))
    }

    /// [`Machine::index_latch`] on the scale of [`FeedbackSnapshot::positions`]: extended
    /// against the last [`Machine::feedback`]'s position of the channel (exact while the
    /// channel moved fewer than `2^(enc_count_w - 1)` counts between the index and that read).
    pub fn index_position(&mut self, channel: usize) -> Result<Option<i64>, BusError> {
        let Some(word) = self.index_latch(channel)? else {
            return Ok(None);
        };
        Ok(Some(self.encoder_tracks[channel].0.latched(word as u32)))
    }

    /// Illegal transitions of channel `channel`: the sticky flag and the count.
    pub fn encoder_errors(&mut self, channel: usize) -> Result<(bool, u16), BusError> {
        self.check_channel(channel)?;
        let status = self.bus.read_one(enc_status::addr(channel))?;
        Ok((enc_status::ILLEGAL.get(status) != 0, enc_status::ILLEGAL_COUNT.get(status) as u16))
    }

    /// Positions, counts and edge times, all from one clock. The latch moves at period
    /// boundaries while running and every clock while stopped; as for
    /// [`Machine::positions`], LATCH_TIME is read around the data and the read retried
    /// when it moved (over SPI, one read frame holds the latch for its whole length).
    pub fn feedback(&mut self) -> Result<FeedbackSnapshot, BusError> {
        let (n_axes, n_enc) = (self.caps.n_axes, self.caps.n_enc);
        let ((steps, counts, edge_times), latch_time) = self.read_latched(16, "feedback", |bus| {
            let mut steps = vec![0u32; n_axes];
            bus.read(position::addr(0), &mut steps)?;
            let mut counts = vec![0u32; n_enc];
            bus.read(enc_count::addr(0), &mut counts)?;
            let mut edge_times = vec![0u32; n_enc];
            bus.read(enc_edge_time::addr(0), &mut edge_times)?;
            Ok((steps, counts, edge_times))
        })?;
        let mut positions = Vec::with_capacity(n_enc);
        let mut extended_edges = Vec::with_capacity(n_enc);
        for ((count, edge), (counter, edger)) in counts.iter().zip(&edge_times).zip(&mut self.encoder_tracks) {
            let position = counter.extend(*count);
            positions.push(position);
            extended_edges.push(edger.extend(*edge, latch_time, position));
        }
        // Read after the positions: SEEN stays set until the host arms the probe, so a 0
        // here (and a LATCH_TIME not the released snapshot's) says they were the period
        // latch's.
        let probe_held = self.snapshot_is_the_probes(latch_time)?;
        Ok(FeedbackSnapshot {
            steps: steps.into_iter().map(|w| w as i32).collect(),
            counts: counts.into_iter().map(|w| w as i32).collect(),
            positions,
            edge_times: extended_edges,
            latch_time,
            probe_held,
        })
    }

    /// Configures the probe (polarity, filter) and arms it for one event.
    pub fn arm_probe(&mut self, active_high: bool, filter: u8) -> Result<(), BusError> {
        if filter > 15 {
            return Err(FeedbackError::Filter(filter).into());
        }
        let word = probe_control::ACTIVE_HIGH.set(0, active_high.into());
        let word = probe_control::FILTER.set(word, u32::from(filter));
        self.bus.write(probe_control::ADDR, probe_control::ARM.set(word, 1))
    }

    /// What the last probe event latched, if one came since the probe was armed.
    pub fn probe_hit(&mut self) -> Result<Option<ProbeHit>, BusError> {
        let status = self.bus.read_one(probe_status::ADDR)?;
        if probe_status::SEEN.get(status) == 0 {
            return Ok(None);
        }
        let mut counts = vec![0u32; self.caps.n_enc];
        self.bus.read(enc_probe_latch::addr(0), &mut counts)?;
        let mut steps = vec![0u32; self.caps.n_axes];
        self.bus.read(probe_position::addr(0), &mut steps)?;
        let time = self.bus.read_one(probe_time::ADDR)?;
        let positions = counts.iter().zip(&self.encoder_tracks).map(|(&w, (counter, _))| counter.latched(w)).collect();
        Ok(Some(ProbeHit {
            positions,
            counts: counts.into_iter().map(|w| w as i32).collect(),
            steps: steps.into_iter().map(|w| w as i32).collect(),
            time,
        }))
    }

    fn check_hand_wheel(&self) -> Result<(), FeedbackError> {
        if !self.caps.has_mpg {
            return Err(FeedbackError::NoHandWheel);
        }
        Ok(())
    }

    /// The hand wheel's filter: sampled every `prescale + 1` clocks, `filter` samples.
    pub fn configure_hand_wheel(&mut self, prescale: u16, filter: u8) -> Result<(), BusError> {
        self.check_hand_wheel()?;
        if filter > 15 {
            return Err(FeedbackError::Filter(filter).into());
        }
        let word = mpg_control::PRESCALE.set(0, u32::from(prescale));
        self.bus.write(mpg_control::ADDR, mpg_control::FILTER.set(word, u32::from(filter)))
    }

    /// The hand wheel's counters.
    pub fn hand_wheel(&mut self) -> Result<HandWheelState, BusError> {
        self.check_hand_wheel()?;
        let status = self.bus.read_one(mpg_status::ADDR)?;
        let mut words = [0u32; 2];
        debug_assert_eq!(mpg_detents::ADDR, mpg_count::ADDR + 1);
        self.bus.read(mpg_count::ADDR, &mut words)?;
        Ok(HandWheelState {
            edges: words[0] as i32,
            detents: words[1] as i32,
            illegal: mpg_status::ILLEGAL.get(status) != 0,
            illegal_count: mpg_status::ILLEGAL_COUNT.get(status) as u16,
        })
    }

    /// Writes the jog's configuration (without enabling it). Refuses a velocity limit
    /// over the axis's rated rate while reversing (the jog reverses whenever the wheel
    /// does), with the step timing and period this driver last wrote.
    pub fn configure_jog(&mut self, setup: &JogSetup) -> Result<(), BusError> {
        self.check_hand_wheel()?;
        if setup.axis >= self.caps.n_axes {
            return Err(FeedbackError::Axis(setup.axis, self.caps.n_axes).into());
        }
        if setup.vmax <= 0 {
            return Err(FeedbackError::Limit("vmax").into());
        }
        if setup.accel <= 0 {
            return Err(FeedbackError::Limit("accel").into());
        }
        if self.period_clocks < 128 {
            return Err(FeedbackError::Period(self.period_clocks).into());
        }
        let timing: DriveTiming = self.timings[setup.axis];
        let max = max_increment_in(&timing, self.period_clocks, true, self.caps.step_slots);
        if setup.vmax > max {
            return Err(FeedbackError::Rate { vmax: setup.vmax, max, period: self.period_clocks }.into());
        }
        self.bus.write(jog_scale::ADDR, setup.scale.to_bits() as u32)?;
        self.bus.write(jog_vmax::ADDR, setup.vmax.to_bits() as u32)?;
        self.bus.write(jog_accel::ADDR, setup.accel.to_bits() as u32)?;
        self.bus.write(jog_window::ADDR, jog_window::STEPS.set(0, u32::from(setup.window)))?;
        self.bus.write(jog_control::ADDR, Self::jog_control_word(setup, false))?;
        Ok(())
    }

    fn jog_control_word(setup: &JogSetup, enable: bool) -> u32 {
        let multiplier = u32::from(setup.multiplier.bits());
        let word = jog_control::ENABLE.set(0, enable.into());
        let word = jog_control::AXIS.set(word, setup.axis as u32);
        let word = jog_control::MULTIPLIER.set(word, multiplier);
        jog_control::FOLLOW.set(word, setup.follow.into())
    }

    /// Engages (true) or stops (false) the jog with `setup` (as written by
    /// [`Machine::configure_jog`]). The core must not be running from the FIFO.
    pub fn enable_jog(&mut self, setup: &JogSetup, enable: bool) -> Result<(), BusError> {
        self.check_hand_wheel()?;
        self.bus.write(jog_control::ADDR, Self::jog_control_word(setup, enable))
    }

    /// The jog's state.
    pub fn jog(&mut self) -> Result<JogState, BusError> {
        self.check_hand_wheel()?;
        let mut words = [0u32; 3];
        debug_assert_eq!((jog_remaining::ADDR, jog_velocity::ADDR), (jog_status::ADDR + 1, jog_status::ADDR + 2));
        self.bus.read(jog_status::ADDR, &mut words)?;
        let [status, remaining, velocity] = words;
        Ok(JogState {
            engaged: jog_status::ENGAGED.get(status) != 0,
            stopping: jog_status::STOPPING.get(status) != 0,
            refused: jog_status::REFUSED.get(status) != 0,
            dropped: jog_status::DROPPED.get(status) as u16,
            remaining: remaining as i32,
            velocity: Increment::from_bits(velocity as i32),
        })
    }

    /// Zeroes every error counter (also the encoders' and the hand wheel's).
    pub fn clear_counters(&mut self) -> Result<(), BusError> {
        self.command(command::CLEAR_COUNTERS.set(0, 1))
    }
}

/// `to - from` for two count words of a core whose counts are `width` bits (16 or 32,
/// [`crate::Caps::enc_count_w`]): their difference modulo `2^width` as a signed number,
/// `-2^(width-1) .. 2^(width-1) - 1` (the move between two reads, if it was shorter than
/// `2^(width-1)` counts). Higher bits of the words are ignored.
pub fn count_delta(width: u32, from: u32, to: u32) -> i64 {
    let diff = to.wrapping_sub(from);
    let shift = 32 - width.clamp(1, 32);
    i64::from(((diff << shift) as i32) >> shift)
}

/// Extends one channel's count reads (`ENC_COUNT`, [`crate::Caps::enc_count_w`] bits) to a
/// 64-bit position: the first read's count as a signed number, then each read's
/// [`count_delta`] from the one before added (docs/spec/encoder_bank.md#narrow-words: the
/// host reads a channel at least once per `2^(width-1)` counts).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CountExtender {
    width: u32,
    /// The last read's word and the position it gave.
    last: Option<(u32, i64)>,
}

impl CountExtender {
    /// No read yet, counts of `width` bits.
    pub fn new(width: u32) -> Self {
        CountExtender { width, last: None }
    }

    /// The position of this read's count `word`.
    pub fn extend(&mut self, word: u32) -> i64 {
        let position = self.latched(word);
        self.last = Some((word, position));
        position
    }

    /// The position of a count the core latched (`ENC_INDEX_LATCH`, `ENC_PROBE_LATCH`),
    /// on the scale of [`Self::extend`]: its [`count_delta`] from the last read (exact if
    /// the channel moved fewer than `2^(width-1)` counts between the event and that read);
    /// the word as a signed number before any read.
    pub fn latched(&self, word: u32) -> i64 {
        match self.last {
            Some((raw, position)) => position + count_delta(self.width, raw, word),
            None => count_delta(self.width, 0, word),
        }
    }

    /// The last read's position.
    pub fn position(&self) -> Option<i64> {
        self.last.map(|(_, position)| position)
    }
}

/// Extends one channel's edge-time reads (`ENC_EDGE_TIME`, `TIMESTAMP`'s low `width` bits)
/// to 32-bit `TIMESTAMP`s: the latest time at or before the read's `LATCH_TIME` with those
/// low bits, exact for an edge fewer than `2^width` clocks before the latch (every edge
/// since the previous read when the host reads at least every `2^width` clocks). A read
/// whose count and word are those of the previous read saw no new edge: it keeps the
/// previous edge time, whatever its age. With `width` 32 the word is the time.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EdgeTimeExtender {
    width: u32,
    /// The last read's word, the edge time it gave, and the channel's position then.
    last: Option<(u32, u32, i64)>,
}

impl EdgeTimeExtender {
    /// No read yet, edge times of `width` bits.
    pub fn new(width: u32) -> Self {
        EdgeTimeExtender { width, last: None }
    }

    /// The edge time of this read's `word`, latched at `latch_time` with the channel at
    /// `position` ([`CountExtender::extend`] of the same read).
    pub fn extend(&mut self, word: u32, latch_time: u32, position: i64) -> u32 {
        let mask = if self.width >= 32 { u32::MAX } else { (1u32 << self.width) - 1 };
        let edge = match self.last {
            Some((last_word, last_edge, last_position)) if last_word == word && last_position == position => last_edge,
            _ => latch_time.wrapping_sub(latch_time.wrapping_sub(word) & mask),
        };
        self.last = Some((word, edge, position));
        edge
    }
}

/// Velocity of one encoder channel from successive [`FeedbackSnapshot`]s, in counts per
/// clock, the way hostmot2's encoder does it: over the counts that changed between two
/// snapshots, divided by the time between their last edges (not between the reads), so
/// a slow encoder is not quantised to whole counts per sample; when no count changed,
/// the speed is at most one count over the time since the last edge, and the estimate
/// decays toward zero as that bound does.
#[derive(Clone, Copy, Debug, Default)]
pub struct VelocityEstimator {
    last: Option<(i32, u32)>,
    velocity: f64,
}

impl VelocityEstimator {
    /// A new estimator: zero until two snapshots with movement between them.
    pub fn new() -> Self {
        Self::default()
    }

    /// Takes channel values `count`, `edge_time` latched at `latch_time`; returns the
    /// velocity in counts per clock.
    pub fn update(&mut self, count: i32, edge_time: u32, latch_time: u32) -> f64 {
        match self.last {
            Some((last_count, last_edge)) if count != last_count => {
                let dt = edge_time.wrapping_sub(last_edge).max(1);
                self.velocity = f64::from(count.wrapping_sub(last_count)) / f64::from(dt);
                self.last = Some((count, edge_time));
            }
            Some((_, last_edge)) => {
                // No edge since the last one: |v| <= 1 count / (time since that edge).
                let since = latch_time.wrapping_sub(last_edge).max(1);
                let bound = 1.0 / f64::from(since);
                if self.velocity.abs() > bound {
                    self.velocity = bound.copysign(self.velocity);
                }
            }
            None => self.last = Some((count, edge_time)),
        }
        self.velocity
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// What a core with `width`-bit counts reads for the count `position`: its low
    /// `width` bits, sign-extended (docs/spec/encoder_bank.md#narrow-words).
    fn register(position: i64, width: u32) -> u32 {
        let shift = 64 - width;
        ((position << shift) >> shift) as u32
    }

    #[test]
    fn count_delta_is_the_signed_difference_modulo_the_width() {
        assert_eq!(count_delta(16, 0x7FFF, 0xFFFF_8000), 1, "forward across +2^15");
        assert_eq!(count_delta(16, 0xFFFF_8000, 0x7FFF), -1, "backward across -2^15");
        assert_eq!(count_delta(16, 0xFFFF_FFFF, 0), 1);
        assert_eq!(count_delta(16, 5, 5 + 0x7FFF), 0x7FFF, "the longest move forward");
        assert_eq!(count_delta(16, 5, 5u32.wrapping_sub(0x8000)), -0x8000, "the longest move backward");
        assert_eq!(count_delta(16, 0x1_0000, 0x2_0003), 3, "bits above the width are ignored");
        assert_eq!(count_delta(32, 0x7FFF_FFFF, 0x8000_0000), 1);
        assert_eq!(count_delta(32, 0, 0xFFFF_FFFE), -2);
    }

    #[test]
    fn narrow_counts_extend_to_the_true_position_across_wraps_in_both_directions() {
        for width in [16u32, 32] {
            let longest = (1i64 << (width - 1)) - 1;
            let mut counter = CountExtender::new(width);
            // Start near the negative end of the narrow range, run forward through many
            // wraps of 2^width in moves up to the longest allowed, then back past 0 and
            // through as many wraps the other way.
            let mut truth: i64 = -(1 << (width - 1)) + 3;
            assert_eq!(counter.extend(register(truth, width)), truth, "first read, width {width}");
            let moves = [longest, 1, 12_345, longest, 0, 7, longest - 1];
            for k in 0..40 {
                truth += moves[k % moves.len()];
                assert_eq!(counter.extend(register(truth, width)), truth, "forward, width {width}, move {k}");
            }
            assert!(truth > 8 << width, "ran through many wraps: {truth}");
            for k in 0..90 {
                truth -= moves[k % moves.len()];
                assert_eq!(counter.extend(register(truth, width)), truth, "backward, width {width}, move {k}");
            }
            assert!(truth < -(8 << width), "ran back through many wraps: {truth}");
            assert_eq!(counter.position(), Some(truth));
            // A latched count (index, probe) within the longest move of the last read.
            for offset in [-longest - 1, -1, 0, 1, longest] {
                assert_eq!(counter.latched(register(truth + offset, width)), truth + offset, "width {width}");
            }
        }
        // One move of 2^15 counts or more between two reads is beyond the rule: taken the
        // other way (the host must read more often).
        let mut counter = CountExtender::new(16);
        counter.extend(register(0, 16));
        assert_eq!(counter.extend(register(1 << 15, 16)), -(1 << 15));
    }

    #[test]
    fn narrow_edge_times_extend_against_the_latch_time() {
        let mut edges = EdgeTimeExtender::new(16);
        // An edge 100 clocks before a latch just past a 2^16 boundary of TIMESTAMP, and
        // one just before TIMESTAMP wraps at 2^32.
        for (edge, latch) in [(0x0003_FFB0u32, 0x0004_0014u32), (0xFFFF_FFF0, 0x0000_0020), (70_000, 70_000)] {
            let position = i64::from(edge);
            assert_eq!(edges.extend(edge & 0xFFFF, latch, position), edge, "edge {edge:#x} latched at {latch:#x}");
        }
        // No new edge (same count, same word) for longer than 2^16 clocks: the last edge
        // time stays.
        assert_eq!(edges.extend(70_000 & 0xFFFF, 70_000 + 200_000, 70_000), 70_000);
        // A new edge (the count moved) 2^16 - 1 clocks before the latch: the oldest exact.
        let latch = 1_000_000u32;
        let edge = latch - 0xFFFF;
        assert_eq!(edges.extend(edge & 0xFFFF, latch, 1), edge);
        // With 32-bit words the word is the time.
        let mut wide = EdgeTimeExtender::new(32);
        assert_eq!(wide.extend(0x1234_5678, 0x0000_0010, 0), 0x1234_5678);
    }

    #[test]
    fn velocity_from_edge_times_is_exact_for_a_constant_rate() {
        // One count every 250 clocks, sampled every 1000 clocks at awkward phases.
        let mut est = VelocityEstimator::new();
        let mut v = 0.0;
        for k in 1..20u32 {
            let latch = 1000 * k + 37;
            let count = (latch / 250) as i32;
            let edge = count as u32 * 250;
            v = est.update(count, edge, latch);
        }
        assert!((v - 1.0 / 250.0).abs() < 1e-12, "{v}");
    }

    #[test]
    fn velocity_decays_when_the_encoder_stops() {
        let mut est = VelocityEstimator::new();
        est.update(0, 0, 10);
        assert!((est.update(10, 1000, 1010) - 0.01).abs() < 1e-12);
        let later = est.update(10, 1000, 1_000_000);
        assert!(later > 0.0 && later <= 1.0 / 999_000.0 + 1e-15, "{later}");
    }
}

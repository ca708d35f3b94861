//! The machine: drives, the encoder channels following them, a probe and a hand wheel,
//! with the chip's feedback pins packed as in `finestep_top` (`enc_a[c]`, `enc_b[c]`,
//! `enc_z[c]`, `probe_pin`, `mpg_a`, `mpg_b`).
//!
//! Channel `c` is bit `c` of the encoder masks. Any number of channels may follow one
//! axis at their own resolutions: a motor encoder and a linear grating on the same
//! axis are two channels with different [`CountsPerStep`](crate::CountsPerStep).

use crate::{
    CountsPerStep, Drive, DriveConfig, Encoder, EncoderConfig, HandWheel, HandWheelConfig, Levels, PlantError, Probe,
    ProbeConfig, Roller, RollerConfig, RollerMode,
};

/// Encoder channels the pin masks hold.
pub const MAX_CHANNELS: usize = 8;

/// Bits per axis in the chip's packed step pins (`finestep_model::pins`: pin A at
/// `3 * axis`, pin B at `3 * axis + 1`, enable at `3 * axis + 2`).
pub const CORE_PINS_PER_AXIS: u32 = 3;

/// One encoder channel: which axis it follows and how.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ChannelConfig {
    /// The axis (index into [`PlantConfig::drives`]).
    pub axis: usize,
    /// The encoder or grating.
    pub encoder: EncoderConfig,
}

/// The whole machine.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct PlantConfig {
    /// One drive per axis, axis `i` at index `i`.
    pub drives: Vec<DriveConfig>,
    /// Encoder channels, channel `c` at index `c` (at most [`MAX_CHANNELS`]).
    pub channels: Vec<ChannelConfig>,
    /// The probe (its pin is low without one).
    pub probe: Option<ProbeConfig>,
    /// The hand wheel (its pins are low without one).
    pub hand_wheel: Option<HandWheelConfig>,
}

/// The seed of [`PlantConfig::lagging`]'s machine (its gratings have no faults, so
/// nothing is drawn from it; one constant so that both ways of driving it agree).
pub const LAGGING_SEED: u64 = 0x1A66;

impl PlantConfig {
    /// The closed-loop machine LinuxCNC's PID runs against (docs/linuxcnc.md#closed-loop):
    /// `axes` step/dir drives, each a first-order lag of `tau` cycles, and on the first
    /// `channels` axes a linear grating of `counts_per_step` (channel `c` on axis `c`).
    /// The one definition both ways of driving it take: the simulated finestep chip's
    /// pins (`finestep sim-chip --lag-clocks`) and LinuxCNC's software stepgen (the
    /// `fsplant` HAL component), so the two runs differ only in the step generator.
    pub fn lagging(axes: usize, channels: usize, tau: u64, counts_per_step: CountsPerStep) -> PlantConfig {
        let drive = DriveConfig { mechanics: crate::Mechanics::Lag { tau }, ..DriveConfig::default() };
        PlantConfig {
            drives: vec![drive; axes],
            channels: (0..channels.min(axes))
                .map(|axis| ChannelConfig { axis, encoder: EncoderConfig::linear_grating(counts_per_step, None) })
                .collect(),
            probe: None,
            hand_wheel: None,
        }
    }
}

/// The plant's output pins, the chip's feedback inputs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct PlantPins {
    /// `enc_a`, channel `c` at bit `c`.
    pub enc_a: u8,
    /// `enc_b`, channel `c` at bit `c`.
    pub enc_b: u8,
    /// `enc_z`, channel `c` at bit `c`.
    pub enc_z: u8,
    /// `probe_pin`.
    pub probe: bool,
    /// `mpg_a`.
    pub mpg_a: bool,
    /// `mpg_b`.
    pub mpg_b: bool,
}

/// The simulated machine (see the module and crate documentation).
#[derive(Clone, Debug)]
pub struct Plant {
    cycle: u64,
    drives: Vec<Drive>,
    channels: Vec<(usize, Encoder)>,
    probe: Option<(usize, Probe)>,
    hand_wheel: Option<HandWheel>,
    roller: Option<Roller>,
}

/// Seed components: channel `c` is `c`, the hand wheel this.
const HAND_WHEEL_COMPONENT: u64 = 0x100;
/// Mixed into the seed of a roller's gauge.
const ROLLER_SALT: u64 = 0x5011_E500;

impl Plant {
    /// The machine at rest in cycle 0, every position 0, faults drawn from `seed`.
    pub fn new(config: PlantConfig, seed: u64) -> Result<Plant, PlantError> {
        use rand::Rng;
        let drives = config.drives.iter().map(|&d| Drive::new(d)).collect::<Result<Vec<_>, _>>()?;
        if config.channels.len() > MAX_CHANNELS {
            return Err(PlantError::Channels { channels: config.channels.len() });
        }
        let axis =
            |what: String, axis: usize| drives.get(axis).ok_or(PlantError::Axis { what, axis, axes: drives.len() });
        let sub_seed = |component: u64| crate::stream(seed, component, 0xFFFF).next_u64();
        let mut channels = Vec::with_capacity(config.channels.len());
        for (c, ch) in config.channels.iter().enumerate() {
            let drive = axis(format!("encoder channel {c}"), ch.axis)?;
            channels.push((ch.axis, Encoder::new(ch.encoder, sub_seed(c as u64), drive, 0)?));
        }
        let probe = match &config.probe {
            Some(p) => Some((p.axis, Probe::new(p, axis("the probe".into(), p.axis)?, 0))),
            None => None,
        };
        let hand_wheel = match config.hand_wheel {
            Some(h) => Some(HandWheel::new(h, sub_seed(HAND_WHEEL_COMPONENT))?),
            None => None,
        };
        Ok(Plant { cycle: 0, drives, channels, probe, hand_wheel, roller: None })
    }

    /// The plant with a roller on its table (see [`crate::roller`]). A measuring roller's
    /// gauge is the encoder channel after the configured ones (channel
    /// [`Plant::channels`]).
    pub fn with_roller(mut self, config: RollerConfig, seed: u64) -> Result<Plant, PlantError> {
        if matches!(config.mode, RollerMode::Measure { .. }) && self.channels.len() >= MAX_CHANNELS {
            return Err(PlantError::Channels { channels: self.channels.len() + 1 });
        }
        self.roller = Some(Roller::new(config, &self.drives, seed ^ ROLLER_SALT, self.cycle)?);
        Ok(self)
    }

    /// The roller.
    pub fn roller(&self) -> Option<&Roller> {
        self.roller.as_ref()
    }

    /// The plant's current cycle.
    pub fn cycle(&self) -> u64 {
        self.cycle
    }

    /// The pins in the current cycle.
    pub fn pins(&self) -> PlantPins {
        let mut pins = PlantPins::default();
        for (c, (_, encoder)) in self.channels.iter().enumerate() {
            let Levels { a, b, z } = encoder.levels();
            pins.enc_a |= u8::from(a) << c;
            pins.enc_b |= u8::from(b) << c;
            pins.enc_z |= u8::from(z) << c;
        }
        if let Some(Levels { a, b, z }) = self.roller.as_ref().and_then(Roller::levels) {
            let c = self.channels.len();
            pins.enc_a |= u8::from(a) << c;
            pins.enc_b |= u8::from(b) << c;
            pins.enc_z |= u8::from(z) << c;
        }
        pins.probe = self.probe.as_ref().is_some_and(|(_, p)| p.pin());
        if let Some(w) = &self.hand_wheel {
            (pins.mpg_a, pins.mpg_b) = w.levels();
        }
        pins
    }

    /// The first cycle after the current one in which [`Plant::pins`] differ, if no
    /// new input comes; `None` if they never change. Exact: each part's answer is exact
    /// and the parts drive different pins.
    pub fn next_change(&self) -> Option<u64> {
        let encoders = self.channels.iter().filter_map(|(axis, encoder)| encoder.next_change(&self.drives[*axis]));
        let probe = self.probe.iter().filter_map(|(axis, p)| p.next_change(&self.drives[*axis]));
        let wheel = self.hand_wheel.iter().filter_map(HandWheel::next_change);
        let roller = self.roller.iter().filter_map(|r| r.next_change(&self.drives));
        encoders.chain(probe).chain(wheel).chain(roller).min()
    }

    /// Move to `cycle` (every change up to and including it).
    ///
    /// # Panics
    ///
    /// If `cycle` is before the current cycle.
    pub fn advance_to(&mut self, cycle: u64) {
        assert!(cycle >= self.cycle, "plant: advance_to({cycle}) before cycle {}", self.cycle);
        for (axis, encoder) in &mut self.channels {
            encoder.advance_to(cycle, &self.drives[*axis]);
        }
        if let Some((axis, probe)) = &mut self.probe {
            probe.advance_to(cycle, &self.drives[*axis]);
        }
        if let Some(w) = &mut self.hand_wheel {
            w.advance_to(cycle);
        }
        if let Some(roller) = &mut self.roller {
            roller.advance_to(cycle, &self.drives);
        }
        for drive in &mut self.drives {
            drive.advance_to(cycle);
        }
        self.cycle = cycle;
    }

    /// Axis `axis`'s step pins have these levels from `cycle` on (the drive reacts from
    /// `cycle + 1`). Moves the plant to `cycle` first.
    ///
    /// # Panics
    ///
    /// If `cycle` is before the current cycle, or there is no such axis.
    pub fn set_step_pins(&mut self, cycle: u64, axis: usize, pin_a: bool, pin_b: bool) {
        self.advance_to(cycle);
        self.drives[axis].input(cycle, pin_a, pin_b);
    }

    /// Every axis's step pins from the chip's packed pin word (layout
    /// [`CORE_PINS_PER_AXIS`], as `finestep_model::pins`) from `cycle` on.
    ///
    /// # Panics
    ///
    /// If `cycle` is before the current cycle.
    pub fn set_core_pins(&mut self, cycle: u64, pins: u64) {
        self.advance_to(cycle);
        for (axis, drive) in self.drives.iter_mut().enumerate() {
            let shift = CORE_PINS_PER_AXIS * axis as u32;
            if shift + 1 < u64::BITS {
                drive.input(cycle, pins >> shift & 1 == 1, pins >> (shift + 1) & 1 == 1);
            }
        }
    }

    /// The drives.
    pub fn drives(&self) -> &[Drive] {
        &self.drives
    }

    /// Axis `axis`'s drive.
    ///
    /// # Panics
    ///
    /// If there is no such axis.
    pub fn drive(&self, axis: usize) -> &Drive {
        &self.drives[axis]
    }

    /// Channels configured.
    pub fn channels(&self) -> usize {
        self.channels.len()
    }

    /// Channel `channel`'s encoder (ideal count, faults, decoded count).
    ///
    /// # Panics
    ///
    /// If there is no such channel.
    pub fn encoder(&self, channel: usize) -> &Encoder {
        &self.channels[channel].1
    }

    /// The probe.
    pub fn probe(&self) -> Option<&Probe> {
        self.probe.as_ref().map(|(_, p)| p)
    }

    /// The hand wheel.
    pub fn hand_wheel(&self) -> Option<&HandWheel> {
        self.hand_wheel.as_ref()
    }

    /// The hand wheel, to queue turns (they start at the plant's current cycle at the
    /// earliest).
    pub fn hand_wheel_mut(&mut self) -> Option<&mut HandWheel> {
        self.hand_wheel.as_mut()
    }
}

#[cfg(test)]
mod tests {
    /// A test input at a cycle: a core pin word, or a hand-wheel turn (detents, cycles per edge).
    type TimedInput = (u64, Option<u64>, Option<(i64, u64)>);

    use super::*;
    use crate::testutil::{jump_through, step_pins, StepPlan, X4};
    use crate::{CountsPerStep, Faults, Glitches, Mechanics};
    use proptest::prelude::*;

    /// A machine with every part: axis 0 lagging with a motor encoder (channel 0, all
    /// faults) and a grating (channel 1), axis 1 ideal with a coarse grating (channel 2,
    /// reference mark) and the probe, and a bouncing hand wheel.
    fn config(tau: u64, faults: Faults, rest_phase: u8) -> PlantConfig {
        let one = CountsPerStep::integer(1).unwrap();
        let mut motor = EncoderConfig::rotary(CountsPerStep::integer(4).unwrap(), 200, 3);
        motor.faults = faults;
        PlantConfig {
            drives: vec![
                DriveConfig { mechanics: Mechanics::Lag { tau }, ..DriveConfig::default() },
                DriveConfig::default(),
            ],
            channels: vec![
                ChannelConfig { axis: 0, encoder: motor },
                ChannelConfig {
                    axis: 0,
                    encoder: EncoderConfig::linear_grating(CountsPerStep::new(5, 2).unwrap(), None),
                },
                ChannelConfig {
                    axis: 1,
                    encoder: EncoderConfig::linear_grating(CountsPerStep::new(2, 5).unwrap(), Some(1)),
                },
            ],
            probe: Some(ProbeConfig {
                axis: 1,
                counts_per_step: one,
                touching: vec![3..=4, 9..=30],
                active_high: true,
            }),
            hand_wheel: Some(HandWheelConfig { rest_phase, bounce: Some(crate::Bounce { extra: 2, within: 9 }) }),
        }
    }

    /// Both axes' pins as packed core pins: (cycle, word).
    fn core_pins(plans: &[StepPlan; 2]) -> Vec<(u64, u64)> {
        let mut events: Vec<(u64, usize, bool, bool)> = Vec::new();
        for (axis, plan) in plans.iter().enumerate() {
            events.extend(step_pins(plan).into_iter().map(|(t, s, d)| (t, axis, s, d)));
        }
        events.sort_by_key(|e| (e.0, e.1));
        let mut word = 0u64;
        let mut out: Vec<(u64, u64)> = Vec::new();
        for (t, axis, s, d) in events {
            let shift = CORE_PINS_PER_AXIS * axis as u32;
            word = word & !(3 << shift) | (u64::from(s) << shift) | (u64::from(d) << (shift + 1));
            match out.last_mut() {
                Some(last) if last.0 == t => last.1 = word,
                _ => out.push((t, word)),
            }
        }
        out
    }

    fn plan_strategy() -> impl Strategy<Value = [StepPlan; 2]> {
        // Axis 0 at 4 counts per step with tau >= 12: steps at least 12 apart.
        (StepPlan::strategy(12, 40, 40), StepPlan::strategy(3, 40, 30)).prop_map(|(a, b)| [a, b])
    }

    /// The harness's loop (jumping to `min(next input, next change)`) and stepping cycle
    /// by cycle see the same pin changes; every jump is a change.
    #[test]
    fn next_change_is_exact() {
        let mut runner = finestep_testkit::runner("plant_next_change_is_exact", 64);
        let faults =
            (0u64..=3, any::<bool>(), prop::option::of(2u32..=12)).prop_map(|(jitter, glitch, missing)| Faults {
                jitter,
                glitches: glitch.then_some(Glitches {
                    a: true,
                    b: false,
                    z: true,
                    shorter_than: 3,
                    mean_interval: 400,
                    from: 0,
                }),
                missing_one_in: missing,
                swap_ab: false,
            });
        let turns = prop::collection::vec((0u64..=3000, -3i64..=3, 10u64..=30), 0..=4);
        let strategy = (12u64..=200, faults, 0u8..=3, plan_strategy(), turns, any::<u64>());
        runner
            .run(&strategy, |(tau, faults, phase, plans, mut turns, seed)| {
                turns.sort_by_key(|t| t.0);
                let pins = core_pins(&plans);
                let end = pins.last().map_or(0, |p| p.0).max(3000) + 40 * tau + 4 * 30 * 12;
                // Inputs: core pin words and hand wheel turns, in cycle order.
                let mut inputs: Vec<TimedInput> = pins.iter().map(|&(t, w)| (t, Some(w), None)).collect();
                inputs.extend(turns.iter().map(|&(t, d, cpe)| (t, None, Some((d, cpe)))));
                inputs.sort_by_key(|i| (i.0, i.1.is_none()));
                let apply = |plant: &mut Plant, input: &TimedInput| {
                    if let Some(w) = input.1 {
                        plant.set_core_pins(input.0, w);
                    }
                    if let Some((d, cpe)) = input.2 {
                        plant.advance_to(input.0);
                        plant.hand_wheel_mut().unwrap().turn(d, cpe).unwrap();
                    }
                };

                let mut stepped = Plant::new(config(tau, faults, phase), seed).unwrap();
                let mut expected = Vec::new();
                let mut before = stepped.pins();
                let mut next = inputs.iter().peekable();
                for n in 0..=end {
                    stepped.advance_to(n);
                    if stepped.pins() != before {
                        before = stepped.pins();
                        expected.push((n, before));
                    }
                    while let Some(input) = next.peek().filter(|i| i.0 == n) {
                        apply(&mut stepped, input);
                        next.next();
                    }
                }

                let mut jumped = Plant::new(config(tau, faults, phase), seed).unwrap();
                let found = jump_through(&mut jumped, &inputs, end, |i| i.0, apply)?;
                prop_assert_eq!(&found, &expected);
                for c in 0..jumped.channels() {
                    prop_assert_eq!(jumped.encoder(c).decoded(), stepped.encoder(c).decoded());
                    prop_assert_eq!(jumped.encoder(c).faults(), stepped.encoder(c).faults());
                }

                // Fault-free channels read the axis's final position, the probe sees it.
                let final0 = plans[0].net();
                let final1 = plans[1].net();
                prop_assert_eq!(jumped.drive(0).actual(), crate::Steps::from_num(final0));
                prop_assert_eq!(jumped.encoder(1).ideal_count(), (5 * final0).div_euclid(2));
                prop_assert_eq!(jumped.encoder(1).decoded().count, jumped.encoder(1).ideal_count());
                prop_assert_eq!(jumped.encoder(2).decoded().count, (2 * final1).div_euclid(5));
                let touching = (3..=4).contains(&final1) || (9..=30).contains(&final1);
                prop_assert_eq!(jumped.pins().probe, touching);
                Ok(())
            })
            .unwrap();
    }

    #[test]
    fn pins_pack_channels_and_validation() {
        let mut plant = Plant::new(config(50, Faults::default(), 2), 7).unwrap();
        // Channel 2 sits on its reference mark? No: mark at count 1, position 0.
        let pins = plant.pins();
        assert_eq!(pins, PlantPins { enc_a: 0, enc_b: 0, enc_z: 0, probe: false, mpg_a: true, mpg_b: true });
        // Axis 1 forward 3 steps (grating at 2/5: count 1 at 2.5 steps, the mark).
        let mut word = 0;
        for step in 0..3u64 {
            let t = 10 + 10 * step;
            word |= 1 << 4; // dir
            plant.set_core_pins(t - 1, word);
            plant.set_core_pins(t, word | 1 << 3);
            plant.set_core_pins(t + 1, word);
        }
        plant.advance_to(100);
        let pins = plant.pins();
        assert_eq!(pins.enc_a, 0b100);
        assert_eq!(pins.enc_z, 0b100);
        assert!(pins.probe, "position 3 touches");
        let mut x4 = X4::new(false, false, 0);
        x4.sample(pins.enc_a & 4 != 0, pins.enc_b & 4 != 0);
        assert_eq!(x4.count, 1);

        let mut bad = config(50, Faults::default(), 0);
        bad.channels[1].axis = 2;
        assert!(matches!(Plant::new(bad, 0), Err(PlantError::Axis { axis: 2, axes: 2, .. })));
        let mut bad = config(50, Faults::default(), 0);
        bad.channels = vec![bad.channels[0]; 9];
        assert!(matches!(Plant::new(bad, 0), Err(PlantError::Channels { channels: 9 })));
    }
}

//! A quadrature encoder (or linear grating) turning a [`Motion`]'s position into A, B
//! and Z levels, with injectable faults.
//!
//! # The ideal waveform
//!
//! The ideal count is `floor(position * counts_per_step) + offset`. Its x4 quadrature
//! state is `count mod 4` = 0, 1, 2, 3 for (A, B) = 00, 10, 11, 01: counting up, A
//! leads B (the order the chip's `quadrature_channel` counts forward). Z (the index) is
//! high while the count is at an index position ([`Index`]): one count wide, once per
//! revolution at a phase, or once at a linear grating's reference mark; its edges ride
//! on the A or B edge of the same count change. A count change of more than one in a
//! single cycle (the position outran the encoder's resolution) cannot be a legal
//! waveform: the levels jump to the new count's state (a decoder sees an illegal
//! transition, or nothing at a jump of 4) and [`FaultLog::overspeed`] counts it.
//!
//! # Faults (all off by default)
//!
//! - **Jitter** (`jitter = j`): the count change of cycle `t` appears on the pins in
//!   cycle `max(t + d, previous + 1)`, `d` uniform in `0..=j` and `previous` the cycle
//!   the previous count change appeared in. Count changes are emitted as whole states
//!   in order, one per cycle at most, so A and B edges are never reordered or merged;
//!   the delay stays at most `j` (by induction: `previous + 1 - t <= previous delay`).
//! - **Glitches** on chosen pins: pulses of the opposite level, `1..shorter_than`
//!   cycles long, with gaps of `1..2 * mean_interval` cycles between them (from one's
//!   end to the next's start; the first gap from cycle `from`, or the creation). A glitch is an XOR on the pin, so the pin differs from
//!   its (possibly jittered) ideal level exactly during glitches; an edge falling inside
//!   one appears at the glitch's end.
//! - **Missing edges** (`one in n` count changes, drawn per change): the change's A/B
//!   part is not emitted, the pins keep their levels (Z still follows); the next count
//!   change sets both pins to their proper levels, so unless the count returns, an x4
//!   decoder sees an illegal transition (`ILLEGAL` on the chip) or a count off by a
//!   multiple of 4. [`FaultLog`] records that and when it happened.
//! - **Swapped A/B**: the pins exchange: the waveform counts backwards.
//!
//! Each fault draws from its own seeded stream, so enabling one never changes the
//! draws of another.
//!
//! # Events
//!
//! [`Encoder::next_change`] is exact: it runs a copy of the encoder over its internal
//! events (count changes of the motion, emissions, glitch starts and ends) until the
//! pins change. [`Encoder::decoded`] is what an exact x4 decoder sampling the pins
//! every cycle reads.

use std::collections::VecDeque;

use rand::rngs::Xoshiro256PlusPlus;
use rand::RngExt;

use crate::{quadrature, quadrature_index, CountsPerStep, Motion, PlantError};

/// Internal events [`Encoder::next_change`] looks through before it answers with the
/// next event's cycle (a harmless early wake-up): bounds the search when faults keep
/// cancelling each other.
const LOOKAHEAD_EVENTS: usize = 1 << 16;

/// Where the index (Z) is high.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Index {
    /// No index: Z stays low.
    #[default]
    None,
    /// Once per revolution: Z is high at counts `phase + k * counts_per_rev`.
    PerRev {
        /// Counts per revolution (at least 1).
        counts_per_rev: u64,
        /// The count (mod `counts_per_rev`) at which Z is high.
        phase: u64,
    },
    /// A linear grating's reference mark: Z is high at this one count.
    Reference {
        /// The count of the mark.
        count: i64,
    },
}

impl Index {
    fn at(self, count: i64) -> bool {
        match self {
            Index::None => false,
            Index::PerRev { counts_per_rev, phase } => {
                (i128::from(count) - i128::from(phase)).rem_euclid(i128::from(counts_per_rev)) == 0
            }
            Index::Reference { count: mark } => count == mark,
        }
    }
}

/// Short glitches on the pins.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Glitches {
    /// Glitch pin A.
    pub a: bool,
    /// Glitch pin B.
    pub b: bool,
    /// Glitch pin Z.
    pub z: bool,
    /// Every glitch lasts fewer cycles than this (at least 2).
    pub shorter_than: u64,
    /// Mean gap between glitches of one pin, in cycles (at least 1).
    pub mean_interval: u64,
    /// No glitch starts before this cycle: the first gap counts from it (or from the
    /// encoder's creation, if later). A test that sets the chip's filter first lets the
    /// glitches start once the setting is in force (0: from creation).
    pub from: u64,
}

/// Injected faults (the default: none).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Faults {
    /// Each count change appears up to this many cycles late (0: exact timing).
    pub jitter: u64,
    /// Short glitches.
    pub glitches: Option<Glitches>,
    /// One in this many count changes loses its A/B edge (at least 2).
    pub missing_one_in: Option<u32>,
    /// A and B exchanged.
    pub swap_ab: bool,
}

/// An encoder channel's settings.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EncoderConfig {
    /// Resolution: counts per step of the motion followed.
    pub counts_per_step: CountsPerStep,
    /// Added to the count: sets the quadrature state at position 0 (`offset mod 4`).
    pub offset: i64,
    /// The index.
    pub index: Index,
    /// Z is low at the index and high elsewhere.
    pub z_active_low: bool,
    /// Injected faults.
    pub faults: Faults,
}

impl EncoderConfig {
    /// A rotary encoder with an index once per revolution, high at count `index_phase`
    /// (mod `counts_per_rev`); no faults.
    pub fn rotary(counts_per_step: CountsPerStep, counts_per_rev: u64, index_phase: u64) -> EncoderConfig {
        EncoderConfig {
            counts_per_step,
            offset: 0,
            index: Index::PerRev { counts_per_rev, phase: index_phase },
            z_active_low: false,
            faults: Faults::default(),
        }
    }

    /// A linear grating (a digital micrometer): the same A/B, no index or one
    /// reference mark at a count; no faults.
    pub fn linear_grating(counts_per_step: CountsPerStep, reference_mark: Option<i64>) -> EncoderConfig {
        EncoderConfig {
            counts_per_step,
            offset: 0,
            index: reference_mark.map_or(Index::None, |count| Index::Reference { count }),
            z_active_low: false,
            faults: Faults::default(),
        }
    }

    /// Checks the settings.
    pub fn validate(&self) -> Result<(), PlantError> {
        if let Index::PerRev { counts_per_rev, .. } = self.index {
            if counts_per_rev == 0 || counts_per_rev > i64::MAX as u64 {
                return Err(PlantError::CountsPerRev);
            }
        }
        if let Some(g) = self.faults.glitches {
            if g.shorter_than < 2 || g.mean_interval == 0 {
                return Err(PlantError::Glitches { shorter_than: g.shorter_than, mean_interval: g.mean_interval });
            }
        }
        if let Some(one_in) = self.faults.missing_one_in {
            if one_in < 2 {
                return Err(PlantError::MissingRate { one_in });
            }
        }
        Ok(())
    }
}

/// The levels of an encoder's pins.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Levels {
    /// Pin A.
    pub a: bool,
    /// Pin B.
    pub b: bool,
    /// Pin Z (index).
    pub z: bool,
}

/// The faults that happened so far.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FaultLog {
    /// Count changes whose A/B edge was dropped.
    pub missing_edges: u64,
    /// The cycle of the first dropped count change (when it should have appeared).
    pub first_missing_edge: Option<u64>,
    /// Glitches started.
    pub glitches: u64,
    /// Count changes of more than one count in one cycle.
    pub overspeed: u64,
    /// The cycle of the first overspeed change.
    pub first_overspeed: Option<u64>,
}

/// What an exact x4 decoder sampling the pins every cycle reads, starting from the
/// ideal count at the encoder's creation.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Decoded {
    /// The count.
    pub count: i64,
    /// Transitions in which A and B changed together (not counted).
    pub illegal: u64,
}

/// Glitch state of one pin.
#[derive(Clone, Debug)]
struct GlitchPin {
    rng: Xoshiro256PlusPlus,
    active: bool,
    /// The cycle the glitch starts (inactive) or ends (active).
    next: u64,
}

/// An encoder channel (see the module documentation).
#[derive(Clone, Debug)]
pub struct Encoder {
    config: EncoderConfig,
    cursor: u64,
    /// The ideal count in `cursor`.
    count: i64,
    /// Count changes waiting to appear: (cycle, levels before swap and glitches).
    queue: VecDeque<(u64, Levels)>,
    /// The levels after every queued change.
    scheduled: Levels,
    /// The cycle the last queued change appears in.
    last_scheduled: Option<u64>,
    /// The levels emitted so far (before swap and glitches).
    emitted: Levels,
    glitch: [Option<GlitchPin>; 3],
    jitter_rng: Xoshiro256PlusPlus,
    missing_rng: Xoshiro256PlusPlus,
    out: Levels,
    faults: FaultLog,
    decoded: Decoded,
}

impl Encoder {
    /// An encoder following `motion` from `cycle`, faults drawn from `seed`.
    pub fn new(config: EncoderConfig, seed: u64, motion: &impl Motion, cycle: u64) -> Result<Encoder, PlantError> {
        config.validate()?;
        let count = motion.count_at(cycle, config.counts_per_step) + config.offset;
        let levels = ideal_levels(&config, count);
        let glitch = std::array::from_fn(|pin| {
            let g = config.faults.glitches?;
            if ![g.a, g.b, g.z][pin] {
                return None;
            }
            let mut rng = crate::stream(seed, 0, 2 + pin as u64);
            let next = cycle.max(g.from).saturating_add(gap(&mut rng, g.mean_interval));
            Some(GlitchPin { rng, active: false, next })
        });
        let mut encoder = Encoder {
            config,
            cursor: cycle,
            count,
            queue: VecDeque::new(),
            scheduled: levels,
            last_scheduled: None,
            emitted: levels,
            glitch,
            jitter_rng: crate::stream(seed, 0, 0),
            missing_rng: crate::stream(seed, 0, 1),
            out: Levels::default(),
            faults: FaultLog::default(),
            decoded: Decoded { count, illegal: 0 },
        };
        encoder.out = encoder.output();
        if config.faults.swap_ab {
            encoder.decoded.count = -count;
        }
        Ok(encoder)
    }

    /// The settings.
    pub fn config(&self) -> &EncoderConfig {
        &self.config
    }

    /// The encoder's current cycle.
    pub fn cycle(&self) -> u64 {
        self.cursor
    }

    /// The ideal count in the current cycle: what an exact x4 decoder of a fault-free
    /// encoder reads (relative to its start).
    pub fn ideal_count(&self) -> i64 {
        self.count
    }

    /// The levels a fault-free encoder shows in the current cycle.
    pub fn ideal_levels(&self) -> Levels {
        ideal_levels(&self.config, self.count)
    }

    /// The pin levels in the current cycle.
    pub fn levels(&self) -> Levels {
        self.out
    }

    /// The faults that happened up to the current cycle.
    pub fn faults(&self) -> &FaultLog {
        &self.faults
    }

    /// What an exact x4 decoder sampling the pins every cycle reads. It starts at the
    /// ideal count at creation (negated with swapped pins, which count backwards).
    pub fn decoded(&self) -> Decoded {
        self.decoded
    }

    /// The first cycle after the current one in which the pins differ, following
    /// `motion` without new input; `None` if they never change.
    pub fn next_change(&self, motion: &impl Motion) -> Option<u64> {
        let mut copy = self.clone();
        for _ in 0..LOOKAHEAD_EVENTS {
            let t = copy.next_event(motion)?;
            copy.process(t, motion);
            if copy.out != self.out {
                return Some(t);
            }
        }
        copy.next_event(motion)
    }

    /// Move to `cycle`, following `motion`.
    ///
    /// # Panics
    ///
    /// If `cycle` is before the current cycle.
    pub fn advance_to(&mut self, cycle: u64, motion: &impl Motion) {
        assert!(cycle >= self.cursor, "encoder: advance_to({cycle}) before cycle {}", self.cursor);
        while let Some(t) = self.next_event(motion).filter(|&t| t <= cycle) {
            self.process(t, motion);
        }
        self.cursor = cycle;
    }

    /// The next cycle something happens inside the encoder.
    fn next_event(&self, motion: &impl Motion) -> Option<u64> {
        let raw = self.count - self.config.offset;
        let mut next = motion.next_exit(self.cursor, self.config.counts_per_step, raw, raw);
        let queued = self.queue.front().map(|&(at, _)| at);
        let glitches = self.glitch.iter().flatten().map(|g| g.next);
        for t in queued.into_iter().chain(glitches) {
            next = Some(next.map_or(t, |n| n.min(t)));
        }
        next
    }

    /// Everything that happens in cycle `t` (no event between the cursor and `t`).
    fn process(&mut self, t: u64, motion: &impl Motion) {
        self.cursor = t;
        let count = motion.count_at(t, self.config.counts_per_step) + self.config.offset;
        if count != self.count {
            self.change_count(t, count);
        }
        while let Some(&(at, levels)) = self.queue.front() {
            if at > t {
                break;
            }
            self.emitted = levels;
            self.queue.pop_front();
        }
        if let Some(g) = self.config.faults.glitches {
            for pin in self.glitch.iter_mut().flatten().filter(|p| p.next == t) {
                if pin.active {
                    pin.active = false;
                    pin.next = t.saturating_add(gap(&mut pin.rng, g.mean_interval));
                } else {
                    pin.active = true;
                    pin.next = t.saturating_add(pin.rng.random_range(1..g.shorter_than));
                    self.faults.glitches += 1;
                }
            }
        }
        let out = self.output();
        if out != self.out {
            let step = quadrature_index(out.a, out.b) - quadrature_index(self.out.a, self.out.b);
            match step.rem_euclid(4) {
                1 => self.decoded.count += 1,
                3 => self.decoded.count -= 1,
                2 => self.decoded.illegal += 1,
                _ => {}
            }
            self.out = out;
        }
    }

    /// The ideal count changes to `count` in cycle `t`: queue its levels.
    fn change_count(&mut self, t: u64, count: i64) {
        let faults = self.config.faults;
        if count.abs_diff(self.count) > 1 {
            self.faults.overspeed += 1;
            self.faults.first_overspeed.get_or_insert(t);
        }
        let mut target = ideal_levels(&self.config, count);
        if let Some(one_in) = faults.missing_one_in {
            let drop = self.missing_rng.random_range(0..one_in) == 0;
            if drop && (target.a, target.b) != (self.scheduled.a, self.scheduled.b) {
                target.a = self.scheduled.a;
                target.b = self.scheduled.b;
                self.faults.missing_edges += 1;
                self.faults.first_missing_edge.get_or_insert(t);
            }
        }
        let delay = if faults.jitter > 0 { self.jitter_rng.random_range(0..=faults.jitter) } else { 0 };
        let earliest = self.last_scheduled.map_or(t, |last| last + 1);
        let at = t.saturating_add(delay).max(earliest);
        self.queue.push_back((at, target));
        self.scheduled = target;
        self.last_scheduled = Some(at);
        self.count = count;
    }

    /// The pins: emitted levels, swapped, glitched.
    fn output(&self) -> Levels {
        let mut out = self.emitted;
        if self.config.faults.swap_ab {
            (out.a, out.b) = (out.b, out.a);
        }
        let active = |pin: usize| self.glitch[pin].as_ref().is_some_and(|g| g.active);
        out.a ^= active(0);
        out.b ^= active(1);
        out.z ^= active(2);
        out
    }
}

fn ideal_levels(config: &EncoderConfig, count: i64) -> Levels {
    let (a, b) = quadrature(count);
    Levels { a, b, z: config.index.at(count) ^ config.z_active_low }
}

/// A gap between glitches: uniform in `1..=2 * mean - 1` (mean `mean`).
fn gap(rng: &mut Xoshiro256PlusPlus, mean: u64) -> u64 {
    rng.random_range(1..=mean.saturating_mul(2).saturating_sub(1).max(1))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testutil::{step_pins, StepPlan, Stepper, X4};
    use crate::{Drive, DriveConfig, Mechanics};
    use proptest::prelude::*;

    /// A drive fast enough to exercise the encoder and slow enough that the count never
    /// changes by more than one per cycle: for `k = ceil(counts per step)`, steps at
    /// least `3k` cycles apart and, above one count per step, a lag of `tau >= 3k`
    /// (speed at most `1 / (tau (1 - e^(-3k/tau)))` steps per cycle, under 0.53 counts).
    #[derive(Clone, Debug)]
    struct Case {
        scale: CountsPerStep,
        mechanics: Mechanics,
        plan: StepPlan,
        offset: i64,
        index: Index,
    }

    fn case_strategy() -> impl Strategy<Value = Case> {
        (
            1u32..=8,
            1u32..=8,
            prop::option::of(1u64..=300),
            StepPlan::strategy(3, 60, 30),
            -6i64..=6,
            prop_oneof![
                Just(Index::None),
                (1u64..=40, 0u64..=40).prop_map(|(counts_per_rev, phase)| Index::PerRev { counts_per_rev, phase }),
                (-10i64..=10).prop_map(|count| Index::Reference { count }),
            ],
        )
            .prop_map(|(num, den, tau, plan, offset, index)| {
                let scale = CountsPerStep::new(num, den).unwrap();
                let k = u64::from(scale.num().div_ceil(scale.den()));
                let mechanics = match tau {
                    None if k == 1 => Mechanics::Ideal,
                    tau => Mechanics::Lag { tau: tau.unwrap_or(1).max(if k > 1 { 3 * k } else { 1 }) },
                };
                Case { scale, mechanics, plan: plan.stretched(k), offset, index }
            })
    }

    impl Case {
        fn drive(&self) -> Drive {
            Drive::new(DriveConfig { mechanics: self.mechanics, ..DriveConfig::default() }).unwrap()
        }

        fn config(&self, faults: Faults) -> EncoderConfig {
            EncoderConfig {
                counts_per_step: self.scale,
                offset: self.offset,
                index: self.index,
                z_active_low: false,
                faults,
            }
        }

        fn end(&self) -> u64 {
            let tau = match self.mechanics {
                Mechanics::Ideal => 0,
                Mechanics::Lag { tau } => tau,
            };
            step_pins(&self.plan).last().map_or(0, |p| p.0) + 30 * tau + 50
        }

        /// Every cycle's levels, cycle by cycle.
        fn levels(&self, faults: Faults, seed: u64) -> (Vec<Levels>, Vec<i64>, Encoder) {
            let mut stepper = Stepper::new(self.drive(), &self.plan);
            let mut encoder = Encoder::new(self.config(faults), seed, stepper.drive(), 0).unwrap();
            let (mut levels, mut ideal) = (Vec::new(), Vec::new());
            for n in 0..=self.end() {
                encoder.advance_to(n, stepper.drive());
                levels.push(encoder.levels());
                ideal.push(encoder.ideal_count());
                stepper.input(n);
            }
            (levels, ideal, encoder)
        }
    }

    /// Without faults, an independent x4 decoder of the waveform reads the ideal count
    /// in every cycle, and Z is high exactly at the index counts.
    #[test]
    fn waveform_decodes_to_the_ideal_count() {
        let mut runner = finestep_testkit::runner("waveform_decodes_to_the_ideal_count", 128);
        runner
            .run(&case_strategy(), |case| {
                let (levels, ideal, encoder) = case.levels(Faults::default(), 0);
                prop_assert_eq!(encoder.faults().overspeed, 0);
                let mut x4 = X4::new(levels[0].a, levels[0].b, ideal[0]);
                for (n, (l, &count)) in levels.iter().zip(&ideal).enumerate() {
                    x4.sample(l.a, l.b);
                    prop_assert_eq!(x4.count, count, "cycle {}", n);
                    let z = match case.index {
                        Index::None => false,
                        Index::PerRev { counts_per_rev, phase } => {
                            (count - phase as i64).rem_euclid(counts_per_rev as i64) == 0
                        }
                        Index::Reference { count: mark } => count == mark,
                    };
                    prop_assert_eq!(l.z, z, "cycle {}: Z at count {}", n, count);
                }
                prop_assert_eq!(x4.illegal, 0);
                prop_assert_eq!(encoder.decoded(), Decoded { count: *ideal.last().unwrap(), illegal: 0 });
                // The ideal count is that of the drive's final position.
                let net = case.plan.net();
                prop_assert_eq!(*ideal.last().unwrap(), case.scale.count_of(net) + case.offset);
                Ok(())
            })
            .unwrap();
    }

    /// The cycles in which any pin changed, with the new levels.
    fn changes(levels: &[Levels]) -> Vec<(u64, Levels)> {
        levels.windows(2).enumerate().filter(|(_, w)| w[0] != w[1]).map(|(n, w)| (n as u64 + 1, w[1])).collect()
    }

    /// Jitter delays each change by at most `j` cycles and keeps the order: the same
    /// sequence of states as without jitter, never A and B in one cycle.
    #[test]
    fn jitter_never_reorders_edges() {
        let mut runner = finestep_testkit::runner("jitter_never_reorders_edges", 128);
        runner
            .run(&(case_strategy(), 1u64..=12, any::<u64>()), |(case, jitter, seed)| {
                let (exact, _, _) = case.levels(Faults::default(), seed);
                let faults = Faults { jitter, ..Faults::default() };
                let (jittered, _, encoder) = case.levels(faults, seed);
                let first = jittered[0];
                let (exact, jittered) = (changes(&exact), changes(&jittered));
                prop_assert_eq!(exact.len(), jittered.len());
                for (e, j) in exact.iter().zip(&jittered) {
                    prop_assert_eq!(e.1, j.1, "states reordered");
                    prop_assert!(e.0 <= j.0 && j.0 <= e.0 + jitter, "delay {} > {}", j.0 - e.0, jitter);
                }
                let mut previous = X4::new(first.a, first.b, 0);
                for j in &jittered {
                    let a_changed = j.1.a != previous.a;
                    let b_changed = j.1.b != previous.b;
                    prop_assert!(!(a_changed && b_changed), "A and B together in cycle {}", j.0);
                    previous.sample(j.1.a, j.1.b);
                }
                prop_assert_eq!(encoder.decoded().illegal, 0);
                Ok(())
            })
            .unwrap();
    }

    /// Glitches make a pin differ from its glitch-free twin for runs shorter than
    /// configured, one run per glitch.
    #[test]
    fn glitches_are_shorter_than_configured() {
        let mut runner = finestep_testkit::runner("glitches_are_shorter_than_configured", 128);
        let strategy = (case_strategy(), 2u64..=10, 1u64..=200, any::<[bool; 3]>(), 0u64..=3, any::<u64>());
        runner
            .run(&strategy, |(case, shorter_than, mean_interval, [a, b, z], jitter, seed)| {
                let base = Faults { jitter, ..Faults::default() };
                let glitches = Glitches { a, b, z, shorter_than, mean_interval, from: 0 };
                let faults = Faults { glitches: Some(glitches), ..base };
                let (clean, _, _) = case.levels(base, seed);
                let (glitched, _, encoder) = case.levels(faults, seed);
                let mut runs = 0;
                for (pin, enabled) in [a, b, z].into_iter().enumerate() {
                    let level = |l: &Levels| [l.a, l.b, l.z][pin];
                    let mut run = 0;
                    for (n, (c, g)) in clean.iter().zip(&glitched).enumerate() {
                        if level(c) != level(g) {
                            prop_assert!(enabled, "pin {} differs in cycle {} without glitches", pin, n);
                            if run == 0 {
                                runs += 1;
                            }
                            run += 1;
                            prop_assert!(run < shorter_than, "pin {}: glitch of {} cycles at {}", pin, run, n);
                        } else {
                            run = 0;
                        }
                    }
                }
                prop_assert_eq!(runs, encoder.faults().glitches);
                Ok(())
            })
            .unwrap();
    }

    /// No glitch starts before `from`: on an encoder at rest, the pins with the glitches
    /// from cycle `from` are those from the creation, `from` cycles later.
    #[test]
    fn glitches_start_from() {
        let drive = Drive::new(DriveConfig::default()).unwrap();
        let levels = |from: u64, end: u64| {
            let glitches = Glitches { a: true, b: true, z: true, shorter_than: 9, mean_interval: 40, from };
            let mut config = EncoderConfig::rotary(CountsPerStep::integer(1).unwrap(), 4, 1);
            config.faults.glitches = Some(glitches);
            let mut encoder = Encoder::new(config, 7, &drive, 0).unwrap();
            (0..end)
                .map(|n| {
                    encoder.advance_to(n, &drive);
                    encoder.levels()
                })
                .collect::<Vec<_>>()
        };
        let (from, end) = (1000u64, 3000u64);
        let (early, late) = (levels(0, end - from), levels(from, end));
        assert!(late[..=from as usize].iter().all(|&l| l == late[0]), "a glitch before cycle {from}");
        assert_eq!(&late[from as usize..], &early[..]);
        assert!(early.iter().any(|&l| l != early[0]), "no glitch at all");
    }

    /// A missing edge shows: the decoder first differs from the ideal count exactly
    /// in the cycle of the first dropped edge, and never without one.
    #[test]
    fn missing_edges_show_as_a_mismatch() {
        let mut runner = finestep_testkit::runner("missing_edges_show_as_a_mismatch", 128);
        runner
            .run(&(case_strategy(), 2u32..=20, any::<u64>()), |(case, one_in, seed)| {
                let faults = Faults { missing_one_in: Some(one_in), ..Faults::default() };
                let (levels, ideal, encoder) = case.levels(faults, seed);
                let mut x4 = X4::new(levels[0].a, levels[0].b, ideal[0]);
                let mut first_mismatch = None;
                for (n, (l, &count)) in levels.iter().zip(&ideal).enumerate() {
                    x4.sample(l.a, l.b);
                    if x4.count != count || x4.illegal > 0 {
                        first_mismatch.get_or_insert(n as u64);
                    }
                }
                prop_assert_eq!(first_mismatch, encoder.faults().first_missing_edge);
                prop_assert_eq!(x4.illegal, encoder.decoded().illegal);
                prop_assert_eq!(x4.count, encoder.decoded().count);
                Ok(())
            })
            .unwrap();
    }

    /// Swapped pins count backwards.
    #[test]
    fn swapped_pins_count_backwards() {
        let mut runner = finestep_testkit::runner("swapped_pins_count_backwards", 64);
        runner
            .run(&case_strategy(), |case| {
                let faults = Faults { swap_ab: true, ..Faults::default() };
                let (levels, ideal, encoder) = case.levels(faults, 0);
                let mut x4 = X4::new(levels[0].a, levels[0].b, -ideal[0]);
                for (l, &count) in levels.iter().zip(&ideal) {
                    x4.sample(l.a, l.b);
                    prop_assert_eq!(x4.count, -count);
                }
                prop_assert_eq!(encoder.decoded().count, -ideal.last().unwrap());
                Ok(())
            })
            .unwrap();
    }

    /// Too fast for the resolution: an ideal drive at 4 counts per step jumps 4 counts,
    /// which shows no edge at all, and the fault says so.
    #[test]
    fn overspeed_is_reported() {
        let mut stepper = Stepper::new(Drive::new(DriveConfig::default()).unwrap(), &StepPlan::forward(3, 10));
        let config = EncoderConfig::linear_grating(CountsPerStep::integer(4).unwrap(), None);
        let mut encoder = Encoder::new(config, 0, stepper.drive(), 0).unwrap();
        for n in 0..100 {
            encoder.advance_to(n, stepper.drive());
            stepper.input(n);
        }
        assert_eq!(encoder.ideal_count(), 12);
        assert_eq!(encoder.faults().overspeed, 3);
        assert_eq!(encoder.decoded().count, 0);
    }

    /// Stepping cycle by cycle and jumping by `next_change` give the same changes, and
    /// every jump lands on a change: with every fault on, and overspeed allowed.
    #[test]
    fn next_change_is_exact() {
        let mut runner = finestep_testkit::runner("encoder_next_change_is_exact", 128);
        let faults = (
            0u64..=6,
            prop::option::of((any::<[bool; 3]>(), 2u64..=8, 1u64..=100)),
            prop::option::of(2u32..=10),
            any::<bool>(),
        )
            .prop_map(|(jitter, glitches, missing_one_in, swap_ab)| Faults {
                jitter,
                glitches: glitches.map(|([a, b, z], shorter_than, mean_interval)| Glitches {
                    a,
                    b,
                    z,
                    shorter_than,
                    mean_interval,
                    from: 0,
                }),
                missing_one_in,
                swap_ab,
            });
        let strategy = (case_strategy(), faults, any::<u64>(), 0u64..=2);
        runner
            .run(&strategy, |(mut case, faults, seed, squeeze)| {
                // Squeezed plans run too fast on purpose (overspeed, illegal states).
                if squeeze > 0 {
                    case.plan = case.plan.squeezed(squeeze);
                }
                let (levels, _, stepped) = case.levels(faults, seed);
                let expected = changes(&levels);
                let end = case.end();
                let mut stepper = Stepper::new(case.drive(), &case.plan);
                let mut encoder = Encoder::new(case.config(faults), seed, stepper.drive(), 0).unwrap();
                let mut found = Vec::new();
                let mut n = 0;
                while n <= end {
                    let input = stepper.next_input().unwrap_or(u64::MAX).max(n);
                    let stop = input.min(end);
                    while let Some(t) = encoder.next_change(stepper.drive()).filter(|&t| t <= stop) {
                        let before = encoder.levels();
                        encoder.advance_to(t, stepper.drive());
                        prop_assert!(encoder.levels() != before, "jump to {} changed nothing", t);
                        found.push((t, encoder.levels()));
                    }
                    encoder.advance_to(stop, stepper.drive());
                    stepper.input(stop);
                    n = stop + 1;
                }
                prop_assert_eq!(&found, &expected);
                prop_assert_eq!(encoder.faults(), stepped.faults());
                prop_assert_eq!(encoder.decoded(), stepped.decoded());
                Ok(())
            })
            .unwrap();
    }

    #[test]
    fn grating_reference_mark_and_validation() {
        let drive = Drive::new(DriveConfig::default()).unwrap();
        let config = EncoderConfig::linear_grating(CountsPerStep::integer(1).unwrap(), Some(0));
        let encoder = Encoder::new(config, 0, &drive, 0).unwrap();
        assert_eq!(encoder.levels(), Levels { a: false, b: false, z: true });
        let mut bad = EncoderConfig::rotary(CountsPerStep::integer(1).unwrap(), 0, 0);
        assert_eq!(Encoder::new(bad, 0, &drive, 0).unwrap_err(), PlantError::CountsPerRev);
        bad.index = Index::None;
        bad.faults.missing_one_in = Some(1);
        assert!(Encoder::new(bad, 0, &drive, 0).is_err());
    }
}

//! A clock-accurate simulated machine for finestep's co-simulation: what sits between
//! the chip's step outputs and its feedback inputs.
//!
//! The loop it closes: the core's step/dir (or up/down, or quadrature) pins drive a
//! [`Drive`] per axis; each drive's mechanical position turns [`Encoder`]s (motor
//! encoders with an index, or linear gratings: the digital micrometers of seed 000)
//! into A/B/Z levels for the chip's `enc_a`, `enc_b`, `enc_z` pins; a [`Probe`] touches
//! a surface along an axis (`probe_pin`); a [`HandWheel`] gives `mpg_a`, `mpg_b`. The
//! [`Plant`] composes them and packs the pins into [`PlantPins`].
//!
//! Everything counts core clock cycles (`u64`) and is deterministic given one seed:
//! faults draw from seeded Xoshiro256++ streams, one stream per fault kind and pin, so
//! enabling one fault never changes the draws of another; the drive's lag is a closed
//! form evaluated with IEEE multiplications only (see [`drive`]).
//!
//! # The cycle interface
//!
//! The co-simulation runs the RTL in chunks of cycles with constant inputs, so every
//! component (and the [`Plant`]) answers, without changing:
//! - `next_change()`: the first cycle after its current one in which its output levels
//!   differ, if no new input comes (exact: no cycle in between changes, and the levels
//!   do change in that cycle);
//! - `advance_to(cycle)`: move to `cycle` (all changes up to and including it);
//! - inputs at a cycle (`Plant::set_step_pins(cycle, ..)`): levels the drive sees from
//!   `cycle` on. A drive reacts one cycle later (a step edge seen in cycle `t` moves the
//!   commanded position from `t + 1`), so the plant's pins in cycle `t` never depend on
//!   the chip's pins in `t`: there is no combinational loop to resolve.
//!
//! A harness runs the chip with the plant's pins as inputs until
//! `min(plant.next_change(), the chip's next output change)`, then gives the chip's new
//! output levels to the plant (`set_core_pins`) or the plant's new levels to the chip.
//!
//! # Example
//!
//! Ten steps of an axis with a lagging drive and a 4-counts-per-step encoder, the
//! chip's pins played by hand; then the plant runs from change to change until rest:
//!
//! ```
//! use finestep_plant::{
//!     ChannelConfig, CountsPerStep, DriveConfig, EncoderConfig, Mechanics, Plant,
//!     PlantConfig,
//! };
//!
//! let config = PlantConfig {
//!     drives: vec![DriveConfig { mechanics: Mechanics::Lag { tau: 200 }, ..DriveConfig::default() }],
//!     channels: vec![ChannelConfig {
//!         axis: 0,
//!         encoder: EncoderConfig::rotary(CountsPerStep::integer(4).unwrap(), 800, 0),
//!     }],
//!     probe: None,
//!     hand_wheel: None,
//! };
//! let mut plant = Plant::new(config, 42).unwrap();
//! // dir = 1, a step pulse of 5 cycles every 100 cycles: (cycle, step level)
//! let pins = (0..10u64).flat_map(|s| [(100 * s + 10, true), (100 * s + 15, false)]);
//! let mut changes = 0;
//! for (cycle, step) in pins {
//!     while let Some(t) = plant.next_change().filter(|&t| t <= cycle) {
//!         plant.advance_to(t); // here a harness hands plant.pins() to the chip
//!         changes += 1;
//!     }
//!     plant.set_step_pins(cycle, 0, step, true);
//! }
//! while let Some(t) = plant.next_change() {
//!     plant.advance_to(t);
//!     changes += 1;
//! }
//! assert_eq!(plant.drive(0).commanded(), 10);
//! assert_eq!(plant.encoder(0).ideal_count(), 40);
//! assert_eq!(plant.encoder(0).decoded().count, 40);
//! assert_eq!(changes, 40); // one quadrature edge per count (Z rides on the first)
//! ```

#![warn(missing_docs)]

pub mod drive;
pub mod encoder;
pub mod hand_wheel;
pub mod plant;
pub mod probe;
pub mod roller;

#[cfg(test)]
mod testutil;

pub use drive::{Drive, DriveConfig, Mechanics, StepInput};
pub use encoder::{Decoded, Encoder, EncoderConfig, FaultLog, Faults, Glitches, Index, Levels};
pub use hand_wheel::{Bounce, HandWheel, HandWheelConfig};
pub use plant::{ChannelConfig, Plant, PlantConfig, PlantPins, LAGGING_SEED, MAX_CHANNELS};
pub use probe::{Probe, ProbeConfig};
pub use roller::{Roller, RollerConfig, RollerMode, Surface};

use rand::rngs::Xoshiro256PlusPlus;
use rand::SeedableRng;

/// A position in steps, 64.64 fixed point (what the drive reports; counts use exact
/// integer arithmetic on the drive's internal value).
pub type Steps = fixed::types::I64F64;

/// A configuration the plant cannot simulate.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum PlantError {
    /// Counts per step must be a ratio of two numbers in `1..=2^24`.
    #[error("counts per step {num}/{den}: both must be in 1..=16777216")]
    Scale {
        /// Numerator given.
        num: u32,
        /// Denominator given.
        den: u32,
    },
    /// The lag's time constant must be in `1..=2^32` cycles.
    #[error("lag time constant {tau} cycles: must be in 1..=4294967296")]
    Tau {
        /// Time constant given.
        tau: u64,
    },
    /// An index once per revolution needs at least one count per revolution.
    #[error("index: counts per revolution must be at least 1")]
    CountsPerRev,
    /// Glitches must be allowed at least one cycle and come at least every so often.
    #[error("glitches shorter than {shorter_than} cycles every {mean_interval} cycles: need shorter_than >= 2 and mean_interval >= 1")]
    Glitches {
        /// Exclusive upper bound of a glitch's length given.
        shorter_than: u64,
        /// Mean gap given.
        mean_interval: u64,
    },
    /// A missing-edge rate of one in `one_in` needs `one_in >= 2`.
    #[error("missing edges one in {one_in}: must be at least 2")]
    MissingRate {
        /// Rate given.
        one_in: u32,
    },
    /// The hand wheel's rest phase is a quadrature state, 0 to 3.
    #[error("hand wheel rest phase {phase}: must be 0..=3")]
    RestPhase {
        /// Phase given.
        phase: u8,
    },
    /// Contact bounce of `extra` toggle pairs does not fit in `within` cycles.
    #[error("bounce of {extra} toggle pairs within {within} cycles: need 2 * extra <= within")]
    Bounce {
        /// Pairs of toggles given.
        extra: u32,
        /// Window given.
        within: u64,
    },
    /// The hand wheel's edges must come at least one cycle apart and after each
    /// edge's bounce has settled.
    #[error(
        "hand wheel edge every {cycles_per_edge} cycles: must be at least 1 and more than the bounce window {within}"
    )]
    EdgeRate {
        /// Cycles per edge given.
        cycles_per_edge: u64,
        /// The bounce window (0 without bounce).
        within: u64,
    },
    /// A roller the plant cannot simulate.
    #[error("roller: {why}")]
    Roller {
        /// What is wrong.
        why: String,
    },
    /// A scripted turn or pause would end past the last representable cycle.
    #[error("hand wheel script ends past cycle 2^64")]
    ScriptOverflow,
    /// The plant packs at most [`MAX_CHANNELS`] encoder channels.
    #[error("{channels} encoder channels: at most {MAX_CHANNELS}")]
    Channels {
        /// Channels given.
        channels: usize,
    },
    /// A channel or the probe names an axis the plant has no drive for.
    #[error("{what} follows axis {axis}, but the plant has {axes} drives")]
    Axis {
        /// Which part.
        what: String,
        /// Axis given.
        axis: usize,
        /// Drives configured.
        axes: usize,
    },
}

/// Encoder counts per motor step, an exact ratio: `4/1` for a 4-counts-per-step motor
/// encoder, `2/5` for one count per 2.5 steps.
///
/// The count of a position `x` (steps) is `floor(x * num / den)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CountsPerStep {
    num: u32,
    den: u32,
}

impl CountsPerStep {
    /// The largest numerator and denominator: keeps the count arithmetic exact.
    pub const MAX_TERM: u32 = 1 << 24;

    /// `num / den` counts per step, reduced.
    pub fn new(num: u32, den: u32) -> Result<CountsPerStep, PlantError> {
        if num == 0 || den == 0 || num > Self::MAX_TERM || den > Self::MAX_TERM {
            return Err(PlantError::Scale { num, den });
        }
        let g = gcd(num, den);
        Ok(CountsPerStep { num: num / g, den: den / g })
    }

    /// `n` counts per step.
    pub fn integer(n: u32) -> Result<CountsPerStep, PlantError> {
        CountsPerStep::new(n, 1)
    }

    /// The reduced numerator.
    pub fn num(self) -> u32 {
        self.num
    }

    /// The reduced denominator.
    pub fn den(self) -> u32 {
        self.den
    }

    /// `floor((steps - lag) * num / den)`, exact for the given `lag` value: with
    /// `q = lag * num` (one IEEE rounding), `floor((steps * num - q) / den) =
    /// floor((steps * num - ceil(q)) / den)`, all integers.
    pub(crate) fn count(self, steps: i64, lag: f64) -> i64 {
        let p = i128::from(steps) * i128::from(self.num);
        let q = (lag * f64::from(self.num)).ceil() as i128;
        (p - q).div_euclid(i128::from(self.den)) as i64
    }

    /// The count of a whole number of steps.
    pub fn count_of(self, steps: i64) -> i64 {
        self.count(steps, 0.0)
    }
}

fn gcd(mut a: u32, mut b: u32) -> u32 {
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

/// A position that moves in time, read as counts at some [`CountsPerStep`]: what an
/// [`Encoder`] or a [`Probe`] follows. [`Drive`] is one; a test may script its own.
pub trait Motion {
    /// The count (position floored at `scale`) in `cycle`. Defined for cycles at or
    /// after the motion's last input.
    fn count_at(&self, cycle: u64, scale: CountsPerStep) -> i64;

    /// The first cycle after `after` whose count at `scale` lies outside `lo..=hi`
    /// (the count in `after` lying inside), or `None` if it never leaves without a new
    /// input.
    fn next_exit(&self, after: u64, scale: CountsPerStep, lo: i64, hi: i64) -> Option<u64>;
}

/// The x4 quadrature state of a count: `count mod 4` = 0, 1, 2, 3 gives (A, B) = 00,
/// 10, 11, 01, so counting up A leads B (the step shaper's order).
pub(crate) fn quadrature(count: i64) -> (bool, bool) {
    match count.rem_euclid(4) {
        0 => (false, false),
        1 => (true, false),
        2 => (true, true),
        _ => (false, true),
    }
}

/// The quadrature state index of (A, B), the inverse of [`quadrature`].
pub(crate) fn quadrature_index(a: bool, b: bool) -> i64 {
    match (a, b) {
        (false, false) => 0,
        (true, false) => 1,
        (true, true) => 2,
        (false, true) => 3,
    }
}

/// One seeded random stream: `component` (a channel, the hand wheel) and `stream` (a
/// fault kind or pin) select independent streams from one plant seed.
pub(crate) fn stream(seed: u64, component: u64, stream: u64) -> Xoshiro256PlusPlus {
    const GOLDEN: u64 = 0x9E37_79B9_7F4A_7C15;
    let salt = ((component << 16) | stream).wrapping_add(1).wrapping_mul(GOLDEN);
    Xoshiro256PlusPlus::seed_from_u64(seed ^ salt.rotate_left(29))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_floor_exactly() {
        let s = CountsPerStep::new(4, 1).unwrap();
        assert_eq!(s.count(1, 0.0), 4);
        assert_eq!(s.count(1, 1e-12), 3);
        assert_eq!(s.count(1, -1e-12), 4);
        assert_eq!(s.count(-1, 0.0), -4);
        let s = CountsPerStep::new(4, 10).unwrap(); // 2/5: one count per 2.5 steps
        assert_eq!((s.num(), s.den()), (2, 5));
        assert_eq!(s.count_of(2), 0);
        assert_eq!(s.count_of(3), 1);
        assert_eq!(s.count_of(5), 2);
        assert_eq!(s.count_of(-1), -1);
        assert_eq!(s.count(3, 0.5), 1); // 2.5 steps: on the boundary
        assert_eq!(s.count(3, 0.500001), 0);
        assert!(CountsPerStep::new(0, 1).is_err());
        assert!(CountsPerStep::new(1, (1 << 24) + 1).is_err());
    }

    #[test]
    fn quadrature_is_a_gray_code_forward_with_a_leading() {
        for k in -8..8i64 {
            let (a0, b0) = quadrature(k);
            let (a1, b1) = quadrature(k + 1);
            assert_eq!(u8::from(a0 != a1) + u8::from(b0 != b1), 1);
            assert_eq!(quadrature_index(a0, b0), k.rem_euclid(4));
        }
        assert_eq!(quadrature(1), (true, false));
    }
}

//! Test helpers: step pulse plans for a drive, and an x4 decoder written from the
//! chip's decoding rule (independent of the encoder's own tables).

use proptest::prelude::*;
use proptest::test_runner::TestCaseError;

use crate::{Drive, Plant, PlantPins};

/// Steps of one axis: (cycles since the previous step's rising edge, direction).
#[derive(Clone, Debug)]
pub struct StepPlan {
    pub steps: Vec<(u64, bool)>,
}

impl StepPlan {
    /// Up to `max_steps` steps at least `min_gap` (and 3) cycles apart, mostly up to
    /// `max_gap`, sometimes a long pause; the direction flips now and then.
    pub fn strategy(min_gap: u64, max_steps: usize, max_gap: u64) -> impl Strategy<Value = StepPlan> {
        let min_gap = min_gap.max(3);
        let max_gap = max_gap.max(min_gap);
        let gap = prop_oneof![
            4 => min_gap..=max_gap,
            1 => 5 * max_gap..=20 * max_gap,
        ];
        (any::<bool>(), prop::collection::vec((gap, prop::bool::weighted(0.25)), 0..=max_steps)).prop_map(
            |(mut dir, raw)| StepPlan {
                steps: raw
                    .into_iter()
                    .map(|(gap, flip)| {
                        dir ^= flip;
                        (gap, dir)
                    })
                    .collect(),
            },
        )
    }

    /// `n` positive steps `gap` cycles apart.
    pub fn forward(n: usize, gap: u64) -> StepPlan {
        StepPlan { steps: vec![(gap, true); n] }
    }

    /// Gaps multiplied by `k`.
    pub fn stretched(mut self, k: u64) -> StepPlan {
        for step in &mut self.steps {
            step.0 *= k;
        }
        self
    }

    /// Gaps divided by `1 + s` (at least 3).
    pub fn squeezed(mut self, s: u64) -> StepPlan {
        for step in &mut self.steps {
            step.0 = (step.0 / (1 + s)).max(3);
        }
        self
    }

    /// The net steps.
    pub fn net(&self) -> i64 {
        self.steps.iter().map(|&(_, dir)| if dir { 1 } else { -1 }).sum()
    }
}

/// The pin levels (cycle, step, dir) of a plan in step/dir form: dir set one cycle
/// before the rising edge, one-cycle pulses.
pub fn step_pins(plan: &StepPlan) -> Vec<(u64, bool, bool)> {
    let mut pins = Vec::new();
    let mut rise = 5;
    let mut level = false;
    for &(gap, dir) in &plan.steps {
        rise += gap;
        if dir != level {
            pins.push((rise - 1, false, dir));
            level = dir;
        }
        pins.push((rise, true, dir));
        pins.push((rise + 1, false, dir));
    }
    pins
}

/// A drive played a plan's pins.
pub struct Stepper {
    drive: Drive,
    pins: Vec<(u64, bool, bool)>,
    next: usize,
}

impl Stepper {
    pub fn new(drive: Drive, plan: &StepPlan) -> Stepper {
        Stepper { drive, pins: step_pins(plan), next: 0 }
    }

    pub fn drive(&self) -> &Drive {
        &self.drive
    }

    /// Gives the drive the pins of cycle `n`, if they change in it.
    pub fn input(&mut self, n: u64) {
        while let Some(&(at, step, dir)) = self.pins.get(self.next).filter(|p| p.0 == n) {
            self.drive.input(at, step, dir);
            self.next += 1;
        }
    }

    /// The next cycle the pins change.
    pub fn next_input(&self) -> Option<u64> {
        self.pins.get(self.next).map(|p| p.0)
    }
}

/// An x4 decoder by the chip's rule: forward when `(da && a != b) || (db && a == b)`,
/// both changing is illegal.
#[derive(Clone, Copy, Debug)]
pub struct X4 {
    pub a: bool,
    pub b: bool,
    pub count: i64,
    pub illegal: u64,
}

impl X4 {
    pub fn new(a: bool, b: bool, count: i64) -> X4 {
        X4 { a, b, count, illegal: 0 }
    }

    pub fn sample(&mut self, a: bool, b: bool) {
        let (da, db) = (a != self.a, b != self.b);
        if da && db {
            self.illegal += 1;
        } else if da || db {
            let forward = (da && a != b) || (db && a == b);
            self.count += if forward { 1 } else { -1 };
        }
        self.a = a;
        self.b = b;
    }
}

/// Runs `plant` to `end` the way a closed loop does, jumping from pin change to pin
/// change (`next_change`) and applying each of `events` (sorted by `at`) at its cycle;
/// returns every (cycle, pins) change, and fails if a jump changes nothing.
pub fn jump_through<E>(
    plant: &mut Plant,
    events: &[E],
    end: u64,
    at: impl Fn(&E) -> u64,
    mut apply: impl FnMut(&mut Plant, &E),
) -> Result<Vec<(u64, PlantPins)>, TestCaseError> {
    let mut found = Vec::new();
    let mut next = events.iter().peekable();
    loop {
        let stop = next.peek().map_or(end, |e| at(e));
        while let Some(t) = plant.next_change().filter(|&t| t <= stop) {
            let before = plant.pins();
            plant.advance_to(t);
            prop_assert!(plant.pins() != before, "jump to {} changed nothing", t);
            found.push((t, plant.pins()));
        }
        plant.advance_to(stop);
        if next.peek().is_none() {
            return Ok(found);
        }
        while let Some(event) = next.next_if(|e| at(e) == stop) {
            apply(plant, event);
        }
    }
}

//! A hand wheel (MPG): 100 pulses per revolution, 4 quadrature edges per detent, turned
//! by a script, with contact bounce.
//!
//! At rest the wheel sits in a detent, its (A, B) in the quadrature state `rest_phase`
//! (0..=3 for 00, 10, 11, 01: wheels differ). A detent forward is four edges through
//! the states in the order A leading B. The ideal edge count starts at 0 and
//! [`HandWheel::detents`] is `floor((edges + 2) / 4)`, the chip's `MPG_DETENTS` of an
//! exact decoder: at rest it is the detent, mid-way it rounds.
//!
//! The script ([`HandWheel::turn`], [`HandWheel::pause`]) queues turns of whole
//! detents, each with its edges evenly spaced `cycles_per_edge` apart (a rate in
//! detents per second gives `clock / (4 * rate)`, [`HandWheel::cycles_per_edge`]),
//! reversals as turns of the other sign, and pauses. A turn starts when the previous
//! one ends, or in the current cycle when the wheel is idle; its first edge comes
//! `cycles_per_edge` after its start.
//!
//! **Bounce**: after each edge the contact toggles `2 * extra` more times (pairs: back
//! to the old level and again to the new), at distinct seeded cycles within `within`
//! cycles after the edge, then rests at the new level. The window must be shorter than
//! the edge spacing, so a pin's bounce has settled before either pin's next edge; a
//! filter accepting a level held `within + 1` cycles reads the ideal edges in order.

use std::collections::{BTreeSet, VecDeque};

use rand::rngs::Xoshiro256PlusPlus;
use rand::RngExt;

use crate::{quadrature, PlantError};

/// Pulses (detents) per revolution.
pub const DETENTS_PER_REV: u32 = 100;

/// Quadrature edges per detent.
pub const EDGES_PER_DETENT: u64 = 4;

/// Contact bounce after each edge.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Bounce {
    /// Extra bounces per edge, each a pair of toggles.
    pub extra: u32,
    /// All toggles fall within this many cycles after the edge (`2 * extra <= within`).
    pub within: u64,
}

/// The hand wheel's make.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct HandWheelConfig {
    /// The quadrature state at rest in a detent, 0..=3 for (A, B) = 00, 10, 11, 01.
    pub rest_phase: u8,
    /// Contact bounce.
    pub bounce: Option<Bounce>,
}

/// A scripted turn: `edges` edges of sign `dir`, the `i`-th at `start + i * cycles_per_edge`.
#[derive(Clone, Copy, Debug)]
struct Turn {
    start: u64,
    cycles_per_edge: u64,
    edges: u64,
    dir: i64,
    done: u64,
}

impl Turn {
    fn next_edge(&self) -> u64 {
        self.start + (self.done + 1) * self.cycles_per_edge
    }
}

/// A hand wheel (see the module documentation).
#[derive(Clone, Debug)]
pub struct HandWheel {
    config: HandWheelConfig,
    rng: Xoshiro256PlusPlus,
    cursor: u64,
    edges: i64,
    script: VecDeque<Turn>,
    script_end: u64,
    /// Pending bounce toggles (cycle, pin 0 = A, 1 = B), in order.
    toggles: VecDeque<(u64, usize)>,
    /// Pins currently inverted by bounce.
    flip: [bool; 2],
}

impl HandWheel {
    /// A wheel at rest in detent 0 in cycle 0; bounce drawn from `seed`.
    pub fn new(config: HandWheelConfig, seed: u64) -> Result<HandWheel, PlantError> {
        if config.rest_phase > 3 {
            return Err(PlantError::RestPhase { phase: config.rest_phase });
        }
        if let Some(b) = config.bounce {
            if 2 * u64::from(b.extra) > b.within {
                return Err(PlantError::Bounce { extra: b.extra, within: b.within });
            }
        }
        Ok(HandWheel {
            config,
            rng: crate::stream(seed, 0, 0),
            cursor: 0,
            edges: 0,
            script: VecDeque::new(),
            script_end: 0,
            toggles: VecDeque::new(),
            flip: [false; 2],
        })
    }

    /// Cycles per edge for a rate in detents per second at a clock in Hz (at least 1;
    /// a rate of 0 counts as 1).
    pub fn cycles_per_edge(clock_hz: u64, detents_per_second: u64) -> u64 {
        (clock_hz / detents_per_second.max(1).saturating_mul(EDGES_PER_DETENT)).max(1)
    }

    /// The settings.
    pub fn config(&self) -> &HandWheelConfig {
        &self.config
    }

    /// Queue a turn of `detents` (negative: backwards), one edge every
    /// `cycles_per_edge` cycles.
    pub fn turn(&mut self, detents: i64, cycles_per_edge: u64) -> Result<(), PlantError> {
        let within = self.config.bounce.map_or(0, |b| b.within);
        if cycles_per_edge == 0 || cycles_per_edge <= within {
            return Err(PlantError::EdgeRate { cycles_per_edge, within });
        }
        if detents == 0 {
            return Ok(());
        }
        let start = self.script_end.max(self.cursor);
        let edges = detents.unsigned_abs().checked_mul(EDGES_PER_DETENT).ok_or(PlantError::ScriptOverflow)?;
        let end =
            edges.checked_mul(cycles_per_edge).and_then(|d| start.checked_add(d)).ok_or(PlantError::ScriptOverflow)?;
        self.script.push_back(Turn { start, cycles_per_edge, edges, dir: detents.signum(), done: 0 });
        self.script_end = end;
        Ok(())
    }

    /// Queue a pause of `cycles`.
    pub fn pause(&mut self, cycles: u64) -> Result<(), PlantError> {
        self.script_end = self.script_end.max(self.cursor).checked_add(cycles).ok_or(PlantError::ScriptOverflow)?;
        Ok(())
    }

    /// The cycle the script ends in (its last edge or pause).
    pub fn script_end(&self) -> u64 {
        self.script_end
    }

    /// The wheel's current cycle.
    pub fn cycle(&self) -> u64 {
        self.cursor
    }

    /// The ideal edge count (x4 counts from the start).
    pub fn edges(&self) -> i64 {
        self.edges
    }

    /// The ideal detent count, `floor((edges + 2) / 4)`.
    pub fn detents(&self) -> i64 {
        (self.edges + 2).div_euclid(EDGES_PER_DETENT as i64)
    }

    /// The pins (A, B) in the current cycle.
    pub fn levels(&self) -> (bool, bool) {
        let (a, b) = quadrature(self.edges + i64::from(self.config.rest_phase));
        (a ^ self.flip[0], b ^ self.flip[1])
    }

    /// The first cycle after the current one in which the pins differ; `None` when the
    /// script is done and the bounce has settled. Exact: every edge and every toggle
    /// changes a pin (bounce settles before the next edge, toggles are distinct).
    pub fn next_change(&self) -> Option<u64> {
        let edge = self.script.front().map(Turn::next_edge);
        let toggle = self.toggles.front().map(|t| t.0);
        match (edge, toggle) {
            (Some(e), Some(t)) => Some(e.min(t)),
            (e, t) => e.or(t),
        }
    }

    /// Move to `cycle`.
    ///
    /// # Panics
    ///
    /// If `cycle` is before the current cycle.
    pub fn advance_to(&mut self, cycle: u64) {
        assert!(cycle >= self.cursor, "hand wheel: advance_to({cycle}) before cycle {}", self.cursor);
        while let Some(t) = self.next_change().filter(|&t| t <= cycle) {
            self.cursor = t;
            self.edge_at(t);
            while let Some(&(_, pin)) = self.toggles.front().filter(|p| p.0 == t) {
                self.flip[pin] ^= true;
                self.toggles.pop_front();
            }
        }
        self.cursor = cycle;
    }

    /// The scripted edge of cycle `t`, if any, and its bounce.
    fn edge_at(&mut self, t: u64) {
        let Some(turn) = self.script.front_mut().filter(|turn| turn.next_edge() == t) else {
            return;
        };
        turn.done += 1;
        let dir = turn.dir;
        if turn.done == turn.edges {
            self.script.pop_front();
        }
        let phase = i64::from(self.config.rest_phase);
        let (a0, _) = quadrature(self.edges + phase);
        self.edges += dir;
        let (a1, _) = quadrature(self.edges + phase);
        let pin = if a0 != a1 { 0 } else { 1 };
        if let Some(b) = self.config.bounce {
            let mut at = BTreeSet::new();
            while at.len() < 2 * b.extra as usize {
                at.insert(t + self.rng.random_range(1..=b.within));
            }
            self.toggles.extend(at.into_iter().map(|c| (c, pin)));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testutil::X4;
    use proptest::prelude::*;

    /// A script: (detents, cycles per edge, pause after).
    type Script = Vec<(i64, u64, u64)>;

    fn script_strategy(min_cycles_per_edge: u64) -> impl Strategy<Value = Script> {
        prop::collection::vec(
            (
                prop_oneof![-5i64..=5, -40i64..=40],
                min_cycles_per_edge..=min_cycles_per_edge + 60,
                prop_oneof![Just(0u64), 0u64..=500],
            ),
            0..=8,
        )
    }

    fn wheel(config: HandWheelConfig, seed: u64, script: &Script) -> HandWheel {
        let mut w = HandWheel::new(config, seed).unwrap();
        for &(detents, cpe, pause) in script {
            w.turn(detents, cpe).unwrap();
            w.pause(pause).unwrap();
        }
        w
    }

    /// A per-pin filter: a level is taken after it has held `hold` cycles in a row.
    struct Filter {
        hold: u64,
        level: [bool; 2],
        candidate: [bool; 2],
        since: [u64; 2],
    }

    impl Filter {
        fn new(hold: u64, a: bool, b: bool) -> Filter {
            Filter { hold, level: [a, b], candidate: [a, b], since: [0; 2] }
        }

        fn sample(&mut self, n: u64, pins: [bool; 2]) -> (bool, bool) {
            for (i, &pin) in pins.iter().enumerate() {
                if pin != self.candidate[i] {
                    self.candidate[i] = pin;
                    self.since[i] = n;
                }
                if n + 1 - self.since[i] >= self.hold {
                    self.level[i] = self.candidate[i];
                }
            }
            (self.level[0], self.level[1])
        }
    }

    /// Without bounce an x4 decoder reads the ideal edges every cycle; with bounce, a
    /// filter holding `within + 1` cycles sees no illegal transition and its decoder
    /// reads the ideal edges whenever the wheel has been still for the filter's delay,
    /// so the detents match.
    #[test]
    fn detents_match_a_decoder_with_bounce_filtered() {
        let mut runner = finestep_testkit::runner("detents_match_a_decoder_with_bounce_filtered", 128);
        let bounce = prop::option::of(
            (0u32..=4, 0u64..=30).prop_map(|(extra, slack)| Bounce { extra, within: 2 * u64::from(extra) + slack }),
        );
        let strategy = (bounce, 0u8..=3).prop_flat_map(|(bounce, rest_phase)| {
            let min = bounce.map_or(1, |b| b.within + 1);
            (Just(HandWheelConfig { rest_phase, bounce }), script_strategy(min), any::<u64>())
        });
        runner
            .run(&strategy, |(config, script, seed)| {
                let mut w = wheel(config, seed, &script);
                let within = config.bounce.map_or(0, |b| b.within);
                let hold = within + 1;
                let end = w.script_end() + 2 * hold + 5;
                let (a, b) = w.levels();
                let mut filter = Filter::new(hold, a, b);
                let mut x4 = X4::new(a, b, 0);
                let mut last_edge = 0;
                let mut edges = 0;
                // The raw pins: only the pin of the latest edge may differ from the
                // ideal state, only within the bounce window, toggling 1 + 2 * extra
                // times per edge.
                let phase = i64::from(config.rest_phase);
                let mut edge_pin = None;
                let (mut raw, mut toggles, mut moves) = (w.levels(), 0u64, 0u64);
                for n in 0..=end {
                    w.advance_to(n);
                    if w.edges() != edges {
                        prop_assert_eq!((w.edges() - edges).abs(), 1);
                        let (a0, _) = crate::quadrature(edges + phase);
                        let (a1, _) = crate::quadrature(w.edges() + phase);
                        edge_pin = Some(if a0 != a1 { 0 } else { 1 });
                        edges = w.edges();
                        last_edge = n;
                        moves += 1;
                    }
                    let (a, b) = w.levels();
                    toggles += u64::from(a != raw.0) + u64::from(b != raw.1);
                    raw = (a, b);
                    let (ia, ib) = crate::quadrature(edges + phase);
                    for (pin, (level, ideal)) in [(a, ia), (b, ib)].into_iter().enumerate() {
                        if level != ideal {
                            prop_assert_eq!(edge_pin, Some(pin), "cycle {}: pin {} bounces", n, pin);
                            prop_assert!(n <= last_edge + within, "cycle {}: bounce after the window", n);
                        }
                    }
                    let (fa, fb) = filter.sample(n, [a, b]);
                    x4.sample(fa, fb);
                    prop_assert_eq!(x4.illegal, 0, "illegal transition in cycle {}", n);
                    if config.bounce.is_none() {
                        prop_assert_eq!(x4.count, w.edges(), "cycle {}", n);
                    } else if n >= last_edge + 2 * hold {
                        prop_assert_eq!(x4.count, w.edges(), "cycle {}, still since {}", n, last_edge);
                    }
                }
                let extra = config.bounce.map_or(0, |b| u64::from(b.extra));
                prop_assert_eq!(toggles, moves * (1 + 2 * extra));
                let net: i64 = script.iter().map(|s| s.0).sum();
                prop_assert_eq!(w.detents(), net);
                prop_assert_eq!(w.edges(), 4 * net);
                prop_assert_eq!((x4.count + 2).div_euclid(4), net);
                Ok(())
            })
            .unwrap();
    }

    /// Jumping by `next_change` (turns queued at random cycles in between) gives the
    /// changes of stepping cycle by cycle, and every jump lands on a change.
    #[test]
    fn next_change_is_exact() {
        let mut runner = finestep_testkit::runner("hand_wheel_next_change_is_exact", 128);
        let strategy = (0u32..=3, 0u64..=10, 0u8..=3, any::<u64>()).prop_flat_map(|(extra, slack, phase, seed)| {
            let within = 2 * u64::from(extra) + slack;
            let bounce = (extra > 0).then_some(Bounce { extra, within });
            let config = HandWheelConfig { rest_phase: phase, bounce };
            let pushes = prop::collection::vec((0u64..=2000, -6i64..=6, within + 1..=within + 40), 0..=6);
            (Just(config), Just(seed), pushes)
        });
        runner
            .run(&strategy, |(config, seed, mut pushes)| {
                pushes.sort_by_key(|p| p.0);
                let end = 2000 + 6 * 4 * 60 * 6 + 100;
                let mut stepped = HandWheel::new(config, seed).unwrap();
                let mut expected = Vec::new();
                let mut queue = pushes.iter().peekable();
                let mut before = stepped.levels();
                for n in 0..=end {
                    stepped.advance_to(n);
                    if stepped.levels() != before {
                        expected.push((n, stepped.levels()));
                        before = stepped.levels();
                    }
                    while let Some(&&(_, d, cpe)) = queue.peek().filter(|p| p.0 == n) {
                        stepped.turn(d, cpe).unwrap();
                        queue.next();
                    }
                }
                let mut jumped = HandWheel::new(config, seed).unwrap();
                let mut found = Vec::new();
                let stops = pushes.iter().map(|p| p.0).chain(std::iter::once(end));
                let mut queue = pushes.iter().peekable();
                for stop in stops {
                    while let Some(t) = jumped.next_change().filter(|&t| t <= stop) {
                        let before = jumped.levels();
                        jumped.advance_to(t);
                        prop_assert!(jumped.levels() != before, "jump to {} changed nothing", t);
                        found.push((t, jumped.levels()));
                    }
                    jumped.advance_to(stop);
                    while let Some(&&(_, d, cpe)) = queue.peek().filter(|p| p.0 == stop) {
                        jumped.turn(d, cpe).unwrap();
                        queue.next();
                    }
                }
                prop_assert_eq!(found, expected);
                prop_assert_eq!(jumped.edges(), stepped.edges());
                Ok(())
            })
            .unwrap();
    }

    #[test]
    fn rates_and_validation() {
        assert_eq!(HandWheel::cycles_per_edge(50_000_000, 100), 125_000);
        let config = HandWheelConfig { rest_phase: 0, bounce: Some(Bounce { extra: 2, within: 10 }) };
        let mut w = HandWheel::new(config, 1).unwrap();
        assert!(w.turn(1, 10).is_err(), "edges must come after the bounce settles");
        assert!(w.turn(1, 11).is_ok());
        assert!(HandWheel::new(HandWheelConfig { rest_phase: 4, bounce: None }, 0).is_err());
        let bad = HandWheelConfig { rest_phase: 0, bounce: Some(Bounce { extra: 3, within: 5 }) };
        assert!(HandWheel::new(bad, 0).is_err());
    }

    #[test]
    fn rest_phase_sets_the_levels_at_rest() {
        for (phase, levels) in [(0, (false, false)), (1, (true, false)), (2, (true, true)), (3, (false, true))] {
            let mut w = HandWheel::new(HandWheelConfig { rest_phase: phase, bounce: None }, 0).unwrap();
            assert_eq!(w.levels(), levels);
            w.turn(1, 5).unwrap();
            w.advance_to(100);
            assert_eq!((w.levels(), w.detents()), (levels, 1));
        }
    }
}

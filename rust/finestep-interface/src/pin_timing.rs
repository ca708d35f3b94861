//! The drive timing as measured at a step/dir axis's pins: the one statement of the rules
//! of `steplen`/`stepspace`/`dirsetup`/`dirhold` ([`DriveTiming`], docs/spec/step_shaper.md)
//! read back from pin levels, clock by clock. The model's tests check the step shaper and
//! the step engine with it, and `finestep sim-chip` measures the simulated chip's pins with
//! it for the LinuxCNC runs.
//!
//! The pins are un-inverted: `step` high is a pulse, `dir` the direction level. With the
//! levels at cycle `c` differing from those at `c - 1` ("an edge at `c`"):
//!
//! - a step pulse is high from its rise to its fall: `fall - rise >= L`;
//! - a step's low time, from the previous fall to its rise: `rise - fall >= S`;
//! - the direction set-up, from a `dir` edge to the next rise: `rise - turn >= U`;
//! - the direction hold, from a fall to the next `dir` edge: `turn - fall >= H`;
//! - `dir` never changes while `step` is high (at `c - 1`): counted as a hold of 0 (the
//!   direction left before the pulse ended); a `dir` edge on a rise's cycle is a set-up
//!   of 0.
//!
//! Each value 0 acts as 1, as in the core. A measurement with no earlier edge to measure
//! from (the first rise, a fall with no rise seen) is not counted.
//!
//! ```
//! use finestep_interface::{pin_timing::StepDirMonitor, DriveTiming};
//! let mut m = StepDirMonitor::new(DriveTiming::new(2, 2, 1, 1));
//! // The first observation only sets the levels: the rise at 10 is an edge from 9's.
//! for (cycle, step) in [(9, false), (10, true), (11, false)] {
//!     m.observe(cycle, step, false);
//! }
//! assert_eq!(m.figures().violations, 1); // high for 1 clock, L = 2
//! ```

use crate::DriveTiming;

/// Which rule an edge broke.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Rule {
    /// A pulse shorter than `L`.
    StepLen,
    /// A low time shorter than `S`.
    StepSpace,
    /// A rise sooner than `U` after a `dir` edge.
    DirSetup,
    /// A `dir` edge sooner than `H` after a fall, or next to a high step level.
    DirHold,
}

impl Rule {
    /// The rule's name as LinuxCNC's stepgen names its parameter.
    pub fn name(self) -> &'static str {
        match self {
            Rule::StepLen => "steplen",
            Rule::StepSpace => "stepspace",
            Rule::DirSetup => "dirsetup",
            Rule::DirHold => "dirhold",
        }
    }
}

/// The first broken rule: where, which, measured and required, clocks.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Violation {
    /// The cycle of the edge that broke it.
    pub cycle: u64,
    /// The rule.
    pub rule: Rule,
    /// The clocks measured.
    pub measured: u64,
    /// The clocks required (at least).
    pub required: u64,
}

impl std::fmt::Display for Violation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "cycle {}: {} {} clocks, want >= {}", self.cycle, self.rule.name(), self.measured, self.required)
    }
}

/// What one axis's pins showed, in clocks: the shortest of each interval (`None` when none
/// was measured) and the broken rules.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StepDirFigures {
    /// The timing measured against (the last given to [`StepDirMonitor::set_timing`]).
    pub timing: DriveTiming,
    /// Step pulses seen (rises).
    pub steps: u64,
    /// The shortest step high.
    pub high_min: Option<u64>,
    /// The longest step high.
    pub high_max: Option<u64>,
    /// The shortest step low between two pulses.
    pub low_min: Option<u64>,
    /// The shortest `dir` set-up before a rise.
    pub setup_min: Option<u64>,
    /// The shortest `dir` hold after a fall (0 for a `dir` edge while the step is high).
    pub hold_min: Option<u64>,
    /// Intervals shorter than the timing allows.
    pub violations: u64,
    /// The first of them.
    pub first: Option<Violation>,
}

/// Measures one step/dir axis's pins edge by edge against a [`DriveTiming`].
#[derive(Clone, Debug)]
pub struct StepDirMonitor {
    figures: StepDirFigures,
    levels: Option<(bool, bool)>,
    last_cycle: u64,
    rise: Option<u64>,
    fall: Option<u64>,
    turn: Option<u64>,
}

fn shortest(slot: &mut Option<u64>, value: u64) {
    *slot = Some(slot.map_or(value, |v| v.min(value)));
}

impl StepDirMonitor {
    /// A monitor that has seen no pin level yet, measuring against `timing`.
    pub fn new(timing: DriveTiming) -> StepDirMonitor {
        StepDirMonitor {
            figures: StepDirFigures { timing, ..StepDirFigures::default() },
            levels: None,
            last_cycle: 0,
            rise: None,
            fall: None,
            turn: None,
        }
    }

    /// Measures from now on against `timing`.
    pub fn set_timing(&mut self, timing: DriveTiming) {
        self.figures.timing = timing;
    }

    /// Forgets the edges seen (the figures stay): the next levels start afresh, as after a
    /// change of the pins' meaning (an inversion or an output mode).
    pub fn restart(&mut self) {
        (self.levels, self.rise, self.fall, self.turn) = (None, None, None, None);
    }

    /// The figures so far.
    pub fn figures(&self) -> StepDirFigures {
        self.figures
    }

    fn check(&mut self, cycle: u64, rule: Rule, measured: u64, required: u32) {
        let required = u64::from(required.max(1));
        if measured < required {
            self.figures.violations += 1;
            self.figures.first.get_or_insert(Violation { cycle, rule, measured, required });
        }
    }

    /// The levels `step`, `dir` from cycle `cycle` on (non-decreasing cycles; levels equal
    /// to the last are no edge). A level held since the last call is the last call's.
    pub fn observe(&mut self, cycle: u64, step: bool, dir: bool) {
        let Some((step0, dir0)) = self.levels.replace((step, dir)) else {
            self.last_cycle = cycle;
            return;
        };
        debug_assert!(cycle >= self.last_cycle, "cycles go forward");
        self.last_cycle = cycle;
        let t = self.figures.timing;
        if dir != dir0 {
            let hold = if step0 { Some(0) } else { self.fall.map(|f| cycle - f) };
            if let Some(hold) = hold {
                shortest(&mut self.figures.hold_min, hold);
                self.check(cycle, Rule::DirHold, hold, t.dir_hold);
            }
            self.turn = Some(cycle);
        }
        if step && !step0 {
            self.figures.steps += 1;
            if let Some(f) = self.fall {
                shortest(&mut self.figures.low_min, cycle - f);
                self.check(cycle, Rule::StepSpace, cycle - f, t.step_space);
            }
            if let Some(d) = self.turn {
                shortest(&mut self.figures.setup_min, cycle - d);
                self.check(cycle, Rule::DirSetup, cycle - d, t.dir_setup);
            }
            self.rise = Some(cycle);
        }
        if !step && step0 {
            if let Some(r) = self.rise {
                let high = cycle - r;
                shortest(&mut self.figures.high_min, high);
                self.figures.high_max = Some(self.figures.high_max.map_or(high, |v| v.max(high)));
                self.check(cycle, Rule::StepLen, high, t.step_len);
            }
            self.fall = Some(cycle);
        }
    }

    /// Every level of `pins` (`(step, dir)` at cycles `from, from + 1, ...`) against
    /// `timing`: the figures.
    pub fn measure(pins: &[(bool, bool)], from: u64, timing: DriveTiming) -> StepDirFigures {
        let mut monitor = StepDirMonitor::new(timing);
        for (c, &(step, dir)) in pins.iter().enumerate() {
            monitor.observe(from + c as u64, step, dir);
        }
        monitor.figures()
    }
}

/// One axis of a [`PinTimingReport`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AxisPinTiming {
    /// Whether the axis was in step/dir mode whenever it moved (an up/down or quadrature
    /// axis is not measured by these rules: its figures count nothing).
    pub step_dir: bool,
    /// What its pins showed.
    pub figures: StepDirFigures,
}

/// What a simulated chip measured at its step pins, every clock it simulated.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct PinTimingReport {
    /// The core clock, Hz (to give the figures in ns).
    pub clock_hz: u32,
    /// Clocks measured.
    pub clocks: u64,
    /// Per axis.
    pub axes: Vec<AxisPinTiming>,
}

impl PinTimingReport {
    /// Broken rules over every axis.
    pub fn violations(&self) -> u64 {
        self.axes.iter().map(|a| a.figures.violations).sum()
    }

    /// The report as little-endian words (the sim link's payload): `clock_hz: u32`,
    /// `clocks: u64`, `axes: u32`, then per axis `step_dir: u32`, the timing `L S U H: u32`,
    /// `steps`, `high_min`, `high_max`, `low_min`, `setup_min`, `hold_min`, `violations`
    /// (`u64`, `u64::MAX` for none), and the first violation as `cycle: u64` (`u64::MAX`
    /// for none), `rule: u32` (0 L, 1 S, 2 U, 3 H), `measured: u64`, `required: u64`.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = Vec::new();
        out.extend_from_slice(&self.clock_hz.to_le_bytes());
        out.extend_from_slice(&self.clocks.to_le_bytes());
        out.extend_from_slice(&(self.axes.len() as u32).to_le_bytes());
        let opt = |v: Option<u64>| v.unwrap_or(u64::MAX).to_le_bytes();
        for axis in &self.axes {
            let f = &axis.figures;
            out.extend_from_slice(&u32::from(axis.step_dir).to_le_bytes());
            for value in f.timing.to_array() {
                out.extend_from_slice(&value.to_le_bytes());
            }
            out.extend_from_slice(&f.steps.to_le_bytes());
            for value in [f.high_min, f.high_max, f.low_min, f.setup_min, f.hold_min] {
                out.extend_from_slice(&opt(value));
            }
            out.extend_from_slice(&f.violations.to_le_bytes());
            let v = f.first.unwrap_or(Violation { cycle: u64::MAX, rule: Rule::StepLen, measured: 0, required: 0 });
            let rule =
                [Rule::StepLen, Rule::StepSpace, Rule::DirSetup, Rule::DirHold].iter().position(|&r| r == v.rule);
            out.extend_from_slice(&v.cycle.to_le_bytes());
            out.extend_from_slice(&(rule.unwrap_or(0) as u32).to_le_bytes());
            out.extend_from_slice(&v.measured.to_le_bytes());
            out.extend_from_slice(&v.required.to_le_bytes());
        }
        out
    }

    /// The report from [`PinTimingReport::to_bytes`]'s words; `None` when they are not one.
    pub fn from_bytes(bytes: &[u8]) -> Option<PinTimingReport> {
        let mut at = 0usize;
        let mut take = |n: usize| -> Option<&[u8]> {
            let part = bytes.get(at..at + n)?;
            at += n;
            Some(part)
        };
        let u32_of = |b: &[u8]| u32::from_le_bytes(b.try_into().expect("4 bytes"));
        let u64_of = |b: &[u8]| u64::from_le_bytes(b.try_into().expect("8 bytes"));
        let clock_hz = u32_of(take(4)?);
        let clocks = u64_of(take(8)?);
        let n = u32_of(take(4)?) as usize;
        let mut axes = Vec::new();
        for _ in 0..n {
            let step_dir = u32_of(take(4)?) != 0;
            let mut timing = [0u32; DriveTiming::COUNT];
            for value in &mut timing {
                *value = u32_of(take(4)?);
            }
            let steps = u64_of(take(8)?);
            let mut opts = [None; 5];
            for value in &mut opts {
                *value = Some(u64_of(take(8)?)).filter(|&v| v != u64::MAX);
            }
            let violations = u64_of(take(8)?);
            let cycle = u64_of(take(8)?);
            let rule =
                *[Rule::StepLen, Rule::StepSpace, Rule::DirSetup, Rule::DirHold].get(u32_of(take(4)?) as usize)?;
            let (measured, required) = (u64_of(take(8)?), u64_of(take(8)?));
            let first = (cycle != u64::MAX).then_some(Violation { cycle, rule, measured, required });
            let [high_min, high_max, low_min, setup_min, hold_min] = opts;
            let figures = StepDirFigures {
                timing: DriveTiming::from_array(timing),
                steps,
                high_min,
                high_max,
                low_min,
                setup_min,
                hold_min,
                violations,
                first,
            };
            axes.push(AxisPinTiming { step_dir, figures });
        }
        (at == bytes.len()).then_some(PinTimingReport { clock_hz, clocks, axes })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Levels over cycles from `(cycle, step, dir)` edges, held between them.
    fn trace(edges: &[(u64, bool, bool)], end: u64) -> Vec<(bool, bool)> {
        let mut pins = Vec::new();
        let mut level = (false, false);
        let mut e = edges.iter().peekable();
        for c in 0..end {
            if let Some(&(_, s, d)) = e.next_if(|x| x.0 == c) {
                level = (s, d);
            }
            pins.push(level);
        }
        pins
    }

    const T: DriveTiming = DriveTiming::new(4, 3, 5, 2);

    #[test]
    fn pulses_within_the_timing_pass_and_give_the_shortest_intervals() {
        // dir up at 10, rise 15 (U 5), fall 19 (L 4), rise 22 (S 3), fall 27 (L 5),
        // dir down at 29 (H 2), rise 34 (U 5), fall 38.
        let edges = [
            (10, false, true),
            (15, true, true),
            (19, false, true),
            (22, true, true),
            (27, false, true),
            (29, false, false),
            (34, true, false),
            (38, false, false),
        ];
        let f = StepDirMonitor::measure(&trace(&edges, 50), 0, T);
        assert_eq!(f.violations, 0, "{:?}", f.first);
        assert_eq!(f.steps, 3);
        assert_eq!((f.high_min, f.high_max, f.low_min), (Some(4), Some(5), Some(3)));
        assert_eq!((f.setup_min, f.hold_min), (Some(5), Some(2)));
    }

    #[test]
    fn each_short_interval_is_a_violation_of_its_rule() {
        type Edges = &'static [(u64, bool, bool)];
        let cases: [(Edges, Rule, u64); 5] = [
            (&[(10, true, false), (13, false, false)], Rule::StepLen, 3),
            (&[(10, true, false), (14, false, false), (16, true, false), (20, false, false)], Rule::StepSpace, 2),
            (&[(10, false, true), (14, true, true), (18, false, true)], Rule::DirSetup, 4),
            (&[(10, true, false), (14, false, false), (15, false, true)], Rule::DirHold, 1),
            (&[(10, true, false), (12, true, true), (14, false, true)], Rule::DirHold, 0),
        ];
        for (edges, rule, measured) in cases {
            let f = StepDirMonitor::measure(&trace(edges, 30), 0, T);
            let first = f.first.unwrap_or_else(|| panic!("{edges:?}: no violation"));
            assert_eq!((first.rule, first.measured), (rule, measured), "{edges:?}");
            assert_eq!(f.violations, 1, "{edges:?}");
        }
    }

    #[test]
    fn zero_acts_as_one_and_a_restart_forgets_the_edges() {
        let f =
            StepDirMonitor::measure(&trace(&[(3, true, false), (4, false, false)], 8), 0, DriveTiming::new(0, 0, 0, 0));
        assert_eq!((f.violations, f.high_min), (0, Some(1)));
        let mut m = StepDirMonitor::new(T);
        m.observe(0, false, false);
        m.observe(5, true, false);
        m.restart();
        // An inverted pin's first level is no fall.
        m.observe(6, false, false);
        m.observe(20, true, true);
        assert_eq!(m.figures().high_min, None);
        let first = m.figures().first.expect("dir on the rise's cycle");
        assert_eq!((m.figures().violations, first.rule, first.measured), (1, Rule::DirSetup, 0));
    }

    #[test]
    fn a_report_round_trips_through_its_bytes() {
        let short = StepDirMonitor::measure(&trace(&[(10, true, false), (13, false, false)], 20), 0, T);
        let good = StepDirMonitor::measure(&trace(&[(2, true, false), (9, false, false)], 20), 0, T);
        let report = PinTimingReport {
            clock_hz: 50_000_000,
            clocks: 1234,
            axes: vec![
                AxisPinTiming { step_dir: true, figures: short },
                AxisPinTiming { step_dir: false, figures: good },
            ],
        };
        let bytes = report.to_bytes();
        assert_eq!(PinTimingReport::from_bytes(&bytes), Some(report.clone()));
        assert_eq!(report.violations(), 1);
        assert_eq!(PinTimingReport::from_bytes(&bytes[..bytes.len() - 1]), None);
    }
}

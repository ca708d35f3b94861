//! Look-ahead: the speed at every junction between elements, from a backward pass
//! (the fastest speed from which the machine can still slow down in time for
//! everything ahead in the window, ending the window at rest) and a forward pass (the
//! fastest speed reachable from the start), each junction limited by its cap.
//!
//! # Junction caps
//!
//! - Exact stop (G61, dwell, pause, program end): 0.
//! - Both elements' speed caps.
//! - Where the junction jumps ([`junction_jumps`]: its jumps read as more than
//!   [`JUMP_READING`] of a limit), turning at the junction, below; where it does not,
//!   nothing more: the elements' caps keep each side within the limits, and the
//!   acceleration read over the periods around the junction averages the two sides
//!   ([`crate::element`]). Turning at a junction that jumps: Sampled once per period, a tangent jump `dt` (unit tangent
//!   after minus before) at speed v changes axis a's per-period velocity by `v |dt_a|`
//!   within one period, which reads as an acceleration `v |dt_a| / T`; the normal
//!   acceleration `k_a v^2` of an arc on either side adds to it. Together they stay
//!   within [`GEOMETRIC_ACCEL_SHARE`] of the axis's limit:
//!   `k_a v^2 + v |dt_a| / T <= 0.45 A_a`.
//!   The elements within three periods' travel of it take the fixed shares
//!   ([`crate::element::Element::shared`], [`crate::geometry::JUMP_REACH_PERIODS`]).
//! - S-curve only: the same jumps read as jerk, `v |dt_a| / T^2` from the tangent jump
//!   and `|dk_a| v^2 / T` from a curvature jump (a line meeting an arc), within the
//!   junction's share of the axis's jerk limit ([`Element::junction_jerk_share`]: what
//!   the tangential jerk and turning of the elements within its reach leave, at least
//!   [`crate::element::JUNCTION_JERK_SHARE`]). Around a line shorter than the
//!   jerk's three periods of travel (the line left between two blends on short
//!   segments) both junctions' jumps are read together ([`pair_jerk_cap`]): the
//!   curvature jump across the line at 3/4, plus the curvature the line interrupts over
//!   its length; where the blends on either side turn the same way this reads far less
//!   than either blend's own curvature jump.
//!
//! Blended corners are tangent-continuous, so only the curvature terms remain there; a
//! sharp corner that could not be blended gets a speed near zero, which is the exact
//! stop the acceleration limit asks for.
//!
//! # Window
//!
//! The passes run over a window of `4 * lookahead_moves` elements (a programmed move
//! is at most two elements: its line and the blend after it) ending at rest, and commit
//! the first half. Every committed element therefore saw at least `lookahead_moves`
//! programmed moves ahead of it (lines and arcs; a NURBS is one element or more per
//! knot span, [`crate::nurbs`], so on NURBS the window reaches fewer blocks ahead); the committed speeds stay feasible when the window
//! moves on, because a later window end only allows higher speeds.

use crate::config::{ProfileKind, Resolved};
use crate::element::{Element, GEOMETRIC_ACCEL_SHARE, JUMP_READING};
use crate::error::ProgramError;
use crate::vec4::sub;
use crate::velocity::Limits;

/// The profile limits of an element.
pub fn element_limits(config: &Resolved, element: &Element) -> Limits {
    Limits { kind: config.profile, accel: element.accel, jerk: element.jerk }
}

/// Largest `v >= 0` with `alpha v^2 + beta v <= gamma`, in the form
/// `2 gamma / (beta + sqrt(beta^2 + 4 alpha gamma))`, which does not cancel: the
/// textbook `(-beta + sqrt(...)) / (2 alpha)` lost every digit where alpha is tiny
/// (a straight NURBS span reads a curvature of 1e-13 from rounding) and read a sharp
/// NURBS corner's cap 2.5 times too high (issue 18's acceleration excursions, seed
/// 0x5780d0fb1e2da647).
fn quadratic_cap(alpha: f64, beta: f64, gamma: f64) -> f64 {
    let root = beta + (beta * beta + 4.0 * alpha * gamma).sqrt();
    if root > 1e-300 {
        2.0 * gamma / root
    } else {
        f64::INFINITY
    }
}

/// Whether the junction between `before` and `after` jumps: its tangent jump (or in
/// S-curve mode its tangent or curvature jump) read within a period at the speed both
/// elements allow is more than [`JUMP_READING`] of an axis's acceleration (jerk). An
/// exact stop does not jump. Where a junction jumps, the junction cap below and the
/// fixed shares of the elements beside it keep the limits; elsewhere the elements'
/// own caps do ([`crate::element`]).
pub fn junction_jumps(config: &Resolved, before: &Element, after: &Element) -> bool {
    if before.stop_after {
        return false;
    }
    let v = before.v_cap.min(after.v_cap);
    let period = config.period_s;
    let (tangent_before, curvature_before) = before.tangent_and_curvature(true);
    let (tangent_after, curvature_after) = after.tangent_and_curvature(false);
    let tangent_jump = sub(tangent_after, tangent_before);
    let curvature_jump = sub(curvature_after, curvature_before);
    config.axes.iter().enumerate().filter(|(_, axis)| axis.present).any(|(a, axis)| {
        let accel = v * tangent_jump[a].abs() / period;
        let jerk = accel / period + curvature_jump[a].abs() * v * v / period;
        // A reading that is not a number counts as a jump.
        let over = |reading: f64, limit: f64| reading.is_nan() || reading > JUMP_READING * limit;
        over(accel, axis.max_acceleration) || config.profile == ProfileKind::SCurve && over(jerk, axis.max_jerk)
    })
}

/// Elements the look-ahead reads at a time before taking their junctions' caps
/// ([`WindowedSpeeds`]).
const READ_CHUNK: usize = 64;

/// The speed cap of the junction between `before` and `after` (module docs).
pub fn junction_cap(config: &Resolved, before: &Element, after: &Element) -> f64 {
    junction_cap_with(config, before, after, &[])
}

/// [`junction_cap`], the junction's jerk read with the jumps of the pairs it belongs to
/// ([`pair_jerk_cap`]) where there are any, else on its own.
fn junction_cap_with(config: &Resolved, before: &Element, after: &Element, pairs: &[PairCap]) -> f64 {
    if before.stop_after {
        return 0.0;
    }
    let mut cap = before.v_cap.min(after.v_cap);
    if !before.jump_after {
        return cap.max(0.0);
    }
    let period = config.period_s;
    let tangent_jump = sub(after.tangent(false), before.tangent(true));
    let k_before = before.curvature(true);
    let k_after = after.curvature(false);
    for (a, axis) in config.axes.iter().enumerate() {
        if !axis.present {
            continue;
        }
        let k = k_before[a].abs().max(k_after[a].abs());
        cap = cap.min(quadratic_cap(k, tangent_jump[a].abs() / period, GEOMETRIC_ACCEL_SHARE * axis.max_acceleration));
    }
    if config.profile == ProfileKind::SCurve {
        if pairs.is_empty() {
            cap = cap.min(single_jerk_cap(config, before, after, 1.0));
        } else {
            // The junction alone only where it could raise the cap (computed once).
            let mut alone = None;
            for pair in pairs {
                let apart = if pair.apart_below > pair.both {
                    let alone = *alone.get_or_insert_with(|| single_jerk_cap(config, before, after, PAIR_JUMP_READING));
                    pair.apart_below.min(alone)
                } else {
                    0.0
                };
                cap = cap.min(pair.both.max(apart));
            }
        }
    }
    cap.max(0.0)
}

/// S-curve: the speed at which the jumps of one junction alone read within
/// the junction's share of every axis's jerk ([`Element::junction_jerk_share`]):
/// `v |dt_a| / T^2 + r |dk_a| v^2 / T`,
/// the curvature jump read at the share `r` (1, or [`PAIR_JUMP_READING`] where no
/// other jump is read with it, [`pair_jerk_cap`]).
fn single_jerk_cap(config: &Resolved, before: &Element, after: &Element, r: f64) -> f64 {
    let period = config.period_s;
    let tangent_jump = sub(after.tangent(false), before.tangent(true));
    let curvature_jump = sub(after.curvature(false), before.curvature(true));
    let mut cap = f64::INFINITY;
    for (a, axis) in config.axes.iter().enumerate() {
        if axis.present {
            cap = cap.min(quadratic_cap(
                r * curvature_jump[a].abs() / period,
                tangent_jump[a].abs() / (period * period),
                before.junction_jerk_share * axis.max_jerk,
            ));
        }
    }
    cap
}

/// The largest share of a curvature jump that the jerk read over four period
/// boundaries at steady speed sees ([`pair_jerk_cap`]).
pub const PAIR_JUMP_READING: f64 = 0.75;

/// The jerk caps of a pair of junctions around a line ([`pair_jerk_cap`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PairCap {
    /// Below this speed both junctions' jumps together read within the share.
    pub both: f64,
    /// Below this speed no reading sees both junctions, and each junction's jumps read
    /// alone hold it ([`single_jerk_cap`] at [`PAIR_JUMP_READING`]).
    pub apart_below: f64,
}

/// S-curve: the jerk cap of both junctions around a line of length `d` between
/// `before` and `after` (a blend, a line, a blend: the line left between two blends on
/// short segments is often a small part of a period's travel).
///
/// At a speed v the jerk read from the positions of four period boundaries is, where
/// the speed is steady, `v^2 / T` times the integral of the curvature against the
/// difference `D(x) = w(x - h) - w(x)` of two triangular weights
/// `w(x) = (h - |x|) / h^2` (`h = v T`, the acceleration read over two periods is the
/// curvature's average under w). Its integral `G = W(x - h) - W(x)` (W the integral of
/// w) is at most [`PAIR_JUMP_READING`] = 3/4 in magnitude (at `x = h/2`), and `|D| <= 1/h`.
/// Two curvature jumps `-k0` (leaving `before`) and `+k2` (entering `after`) a distance
/// d apart read `k2 G(s2) - k0 G(s1) = (k2 - k0) G(s2) + k0 (G(s2) - G(s1))` (or the
/// same with k0 and k2 exchanged), so at most
/// `3/4 |k2 - k0| v^2 / T + min(|k0|, |k2|) d v / T^2` whatever the phase, the tangent
/// jumps adding `v |dt| / T^2` each: within the smaller of the two junctions' shares
/// ([`Element::junction_jerk_share`]) of every axis's jerk
/// below the first cap returned ([`PairCap::both`]). Each junction reads on its own
/// ([`single_jerk_cap`], its curvature jump at 3/4 as above) only when no reading sees
/// both, below `d / (3 T)` (the jerk's readings span three periods,
/// [`PairCap::apart_below`]): for each junction the larger of the two caps holds.
/// Where the curvature turns over at the line (a zigzag of blends) the pair reads more
/// than either junction alone, and its cap is the lower. `None` where the rule does not
/// apply (not S-curve, `line` not a line, an exact stop at either junction).
pub fn pair_jerk_cap(config: &Resolved, before: &Element, line: &Element, after: &Element) -> Option<PairCap> {
    if config.profile != ProfileKind::SCurve
        || before.stop_after
        || line.stop_after
        || !matches!(line.shape, crate::element::Shape::Line { .. })
    {
        return None;
    }
    let period = config.period_s;
    let d = line.length;
    let k0 = before.curvature(true);
    let k2 = after.curvature(false);
    let dt0 = sub(line.tangent(false), before.tangent(true));
    let dt2 = sub(after.tangent(false), line.tangent(true));
    // Both jumps' reaches together: the smaller of their shares.
    let share = before.junction_jerk_share.min(line.junction_jerk_share);
    let mut pair = f64::INFINITY;
    for (a, axis) in config.axes.iter().enumerate() {
        if axis.present {
            pair = pair.min(quadratic_cap(
                PAIR_JUMP_READING * (k2[a] - k0[a]).abs() / period,
                (dt0[a].abs() + dt2[a].abs() + k0[a].abs().min(k2[a].abs()) * d) / (period * period),
                share * axis.max_jerk,
            ));
        }
    }
    Some(PairCap { both: pair, apart_below: d / (3.0 * period) })
}

/// Junction speeds `v[0..=n]` for `n` elements (`v[0]` is the start, `v[n]` the end,
/// both 0), by windowed backward and forward passes (module docs): all of them at once.
pub fn junction_speeds(config: &Resolved, elements: &[Element]) -> Vec<f64> {
    let mut windows = WindowedSpeeds::new(config);
    (0..=elements.len()).map(|i| windows.speed(config, elements, i)).collect()
}

/// The elements of a path as far as they are known: a whole path ([`Whole`]) or one
/// produced as it is read ([`crate::interpolate::Periods`] over a
/// [`crate::geometry::PathStream`]), of which only a window is kept.
pub trait ElementWindow {
    /// Makes the elements before `upto` known (all of them on a shorter path), or the
    /// error that ends the path.
    fn reach(&mut self, upto: usize) -> Result<(), ProgramError>;
    /// How many elements are known (those below this index, less any released).
    fn known(&self) -> usize;
    /// Whether the path has no more elements than those known.
    fn complete(&self) -> bool;
    /// Element `i`, known and not released.
    fn element(&self, i: usize) -> &Element;
}

/// A whole path as an [`ElementWindow`].
#[derive(Clone, Copy, Debug)]
pub struct Whole<'a>(pub &'a [Element]);

impl ElementWindow for Whole<'_> {
    fn reach(&mut self, _upto: usize) -> Result<(), ProgramError> {
        Ok(())
    }
    fn known(&self) -> usize {
        self.0.len()
    }
    fn complete(&self) -> bool {
        true
    }
    fn element(&self, i: usize) -> &Element {
        &self.0[i]
    }
}

/// The junction speeds computed a window at a time, as the interpolation reaches them
/// (module docs): the first is known after one window of `4 * lookahead_moves` elements,
/// whatever the program's length, and only the junctions of the current window and those
/// not yet released are kept. The path is read one window (and one element) ahead of
/// the last committed junction, never further.
#[derive(Clone, Debug)]
pub struct WindowedSpeeds {
    window: usize,
    /// Speeds of junctions `base..=fixed`.
    speeds: std::collections::VecDeque<f64>,
    base: usize,
    fixed: usize,
    /// Caps of junctions `fixed..fixed + caps.len()` (computed once per junction).
    caps: std::collections::VecDeque<f64>,
    /// The profile limits and the length the passes read (a hair below the element's)
    /// of elements `fixed..fixed + caps.len()`, taken with each junction's cap: the
    /// passes read these instead of the elements, which lie apart in memory.
    reach: std::collections::VecDeque<(Limits, f64)>,
    /// The backward pass of the current window (junctions from `fixed`), and of the
    /// window before it (junctions from `previous_fixed`).
    backward: Vec<f64>,
    previous: Vec<f64>,
    previous_fixed: usize,
    /// The jerk cap of the junction after a line paired with the one before it
    /// ([`pair_jerk_cap`]): junction, cap.
    paired: Option<(usize, PairCap)>,
}

impl WindowedSpeeds {
    /// At the start of a program (junction 0 at rest).
    pub fn new(config: &Resolved) -> WindowedSpeeds {
        WindowedSpeeds {
            window: 4 * config.lookahead_moves.max(1),
            speeds: std::collections::VecDeque::from([0.0]),
            base: 0,
            fixed: 0,
            caps: std::collections::VecDeque::new(),
            reach: std::collections::VecDeque::new(),
            backward: Vec::new(),
            previous: Vec::new(),
            previous_fixed: 0,
            paired: None,
        }
    }

    /// The elements of the look-ahead window: the passes read at most this many
    /// elements past the last committed junction, and one more for its last junction.
    pub fn window(&self) -> usize {
        self.window
    }

    /// The speed at junction `i` (`0..=elements.len()`) of a whole path, planning
    /// further windows as needed.
    pub fn speed(&mut self, config: &Resolved, elements: &[Element], i: usize) -> f64 {
        match self.speed_in(config, &mut Whole(elements), i) {
            Ok(v) => v,
            Err(error) => unreachable!("a whole path reads without errors: {error}"),
        }
    }

    /// The speed at junction `i` of `path`, reading it and planning further windows as
    /// needed, or the error that ends the path before the window is read.
    pub fn speed_in<W: ElementWindow + ?Sized>(
        &mut self,
        config: &Resolved,
        path: &mut W,
        i: usize,
    ) -> Result<f64, ProgramError> {
        assert!(i >= self.base, "junction {i} released");
        while i > self.fixed {
            assert!(!(path.complete() && self.fixed >= path.known()), "junction {i} beyond the path");
            self.advance(config, path)?;
        }
        Ok(self.speeds[i - self.base])
    }

    /// Forgets the junctions before `i`.
    pub fn release(&mut self, i: usize) {
        while self.base < i.min(self.fixed) {
            self.speeds.pop_front();
            self.base += 1;
        }
    }

    /// The caps of the junctions before `to` not yet taken, `n` the path's element count
    /// (`usize::MAX` while unknown): each is computed with the element after it known
    /// (where there is one), so that a pair around a short line ([`pair_jerk_cap`]) is
    /// read the same in every window as on the whole path; with each, the limits and
    /// length the passes read of the element after it.
    fn cap_junctions<W: ElementWindow + ?Sized>(&mut self, config: &Resolved, path: &W, to: usize, n: usize) {
        while self.fixed + self.caps.len() < to {
            let i = self.fixed + self.caps.len();
            let cap = if i == 0 || i == n {
                0.0
            } else {
                let (before, after) = (path.element(i - 1), path.element(i));
                // The pair this junction ends, and the one it starts (around `after`).
                let mut pairs = [PairCap { both: 0.0, apart_below: 0.0 }; 2];
                let mut count = 0;
                if let Some((_, pair)) = self.paired.take().filter(|&(j, _)| j == i) {
                    pairs[count] = pair;
                    count += 1;
                }
                if i + 1 < path.known() {
                    if let Some(pair) = pair_jerk_cap(config, before, after, path.element(i + 1)) {
                        self.paired = Some((i + 1, pair));
                        pairs[count] = pair;
                        count += 1;
                    }
                }
                junction_cap_with(config, before, after, &pairs[..count])
            };
            self.caps.push_back(cap);
            // A hair below the exact reach, so that rounding never leaves a profile short.
            let element = path.element(i);
            self.reach.push_back((element_limits(config, element), element.length * (1.0 - 1e-12)));
        }
    }

    /// One window: backward from rest at its end, forward from the last fixed junction,
    /// the first half committed (all of it at the path's end).
    fn advance<W: ElementWindow + ?Sized>(&mut self, config: &Resolved, path: &mut W) -> Result<(), ProgramError> {
        let fixed = self.fixed;
        // The window's elements and the one after it (the window's last junction), read
        // [`READ_CHUNK`] at a time, each junction's cap taken as soon as the element
        // after it is known (or the path has ended), while the elements are fresh in the
        // cache: the same caps as read after the whole window.
        let target = fixed + self.window + 1;
        loop {
            if !path.complete() && path.known() < target {
                path.reach((path.known() + READ_CHUNK).min(target))?;
            }
            let n = if path.complete() { path.known() } else { usize::MAX };
            let end = (fixed + self.window).min(n);
            let capped_to = if path.complete() { end } else { end.min(path.known().saturating_sub(1)) };
            self.cap_junctions(config, path, capped_to, n);
            if path.complete() || path.known() >= target {
                break;
            }
        }
        let n = if path.complete() { path.known() } else { usize::MAX };
        let end = (fixed + self.window).min(n);
        // Backward from rest at the window's end. Each junction's speed is a function of
        // the one after it alone, so where it comes out as the window before had it
        // (the end of that window's braking reached), so does every junction before it:
        // those are taken as they were.
        std::mem::swap(&mut self.backward, &mut self.previous);
        self.backward.clear();
        self.backward.resize(end - fixed + 1, 0.0);
        let previous_end = self.previous_fixed + self.previous.len();
        for i in (fixed..end).rev() {
            let (limits, length) = self.reach[i - fixed];
            let v = self.caps[i - fixed].min(limits.reachable(self.backward[i + 1 - fixed], length));
            self.backward[i - fixed] = v;
            // (`fixed` never moves back: the window before starts at or before it.)
            if i < previous_end && self.previous[i - self.previous_fixed].to_bits() == v.to_bits() {
                let from = fixed - self.previous_fixed;
                self.backward[..i - fixed].copy_from_slice(&self.previous[from..from + i - fixed]);
                break;
            }
        }
        self.previous_fixed = fixed;
        let commit = if end == n { n } else { fixed + self.window / 2 };
        for i in fixed..commit {
            let (limits, length) = self.reach[i - fixed];
            let from = self.speeds[i - self.base];
            let reach = limits.reachable(from, length);
            self.speeds.push_back(self.backward[i + 1 - fixed].min(reach));
        }
        for _ in fixed..commit {
            self.caps.pop_front();
            self.reach.pop_front();
        }
        self.fixed = commit;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::quadratic_cap;

    #[test]
    fn the_quadratic_cap_holds_at_tiny_curvatures() {
        // alpha v^2 + beta v = gamma at the cap, to the last digits, however small alpha.
        for &(alpha, beta, gamma) in
            &[(2e-13, 1952.6, 450.0), (1e-300, 3.0, 2.0), (0.0, 5.0, 10.0), (4.0, 0.0, 16.0), (1.0, 1.0, 0.0)]
        {
            let v = quadratic_cap(alpha, beta, gamma);
            let lhs = alpha * v * v + beta * v;
            assert!((lhs - gamma).abs() <= 1e-12 * gamma.max(1.0), "{alpha} {beta} {gamma}: {v} gives {lhs}");
        }
        assert_eq!(quadratic_cap(0.0, 0.0, 1.0), f64::INFINITY);
    }
}

//! Time-division interpolation of the planned path: at the end of every period T the
//! position on the path is taken from the elements' speed profiles (a period may
//! straddle several elements), quantised to the core's Q16.16 step grid from its exact
//! value, and differenced into per-period increments; no rounding accumulates. At an
//! exact stop the period ends on the stop point snapped to whole steps (the vertices
//! are on whole steps already), so the increments sum exactly to it, and the next move
//! starts with the next period. Every record is checked against the drive's rated rate
//! ([`RateChecker`]) before it is emitted.
//!
//! [`Periods`] produces the records one at a time as they are consumed, planning the
//! junction speeds a look-ahead window at a time ([`WindowedSpeeds`]) and reading the
//! path's elements from their source ([`crate::geometry::PathStream`]) only as far as
//! that window reaches, forgetting each once the interpolation has left it: nothing
//! grows with the number of periods or of moves, so a move or a program of any duration
//! or length streams in the same memory, and the first record is out after the first
//! window is planned.
//!
//! NURBS sub-pieces are interpolated directly: a [`NurbsCursor`] carries the curve
//! parameter from period to period and steps it by the arc length the profile asks
//! for (second-order Taylor step and Newton correction, [`crate::nurbs`]). In S-curve
//! mode, where the junction speeds of consecutive smooth sub-pieces rise (or fall) all
//! the way, they take one profile over the run ([`crate::velocity::run_profiles`]),
//! each sub-piece its part of it, so the acceleration is not brought to zero at every
//! sub-piece's end.

use finestep_interface::rate::RateChecker;
use finestep_interface::{Increment, PeriodRecord};

use crate::config::{ProfileKind, Resolved, AXIS_NAMES};
use crate::element::{Element, IoEvent, Shape, TimedEvent};
use crate::error::ProgramError;
use crate::lookahead::{element_limits, ElementWindow, WindowedSpeeds};
use crate::nurbs::NurbsCursor;
use crate::vec4::Vec4;
use crate::velocity::{run_profiles_into, Limits, Profile, RunElement, MAX_RUN_ELEMENTS};
use finestep_interface::flags::BLOCK_END;
use std::collections::VecDeque;

/// The records of a path, one per period, produced as they are asked for (module docs):
/// `(record, source line being executed at the end of the period)`, or the error that
/// stops the stream (a record over the rated rate: a planner bug, refused).
#[derive(Debug)]
pub struct Periods<'p> {
    config: Resolved,
    path: PathWindow<'p>,
    speeds: WindowedSpeeds,
    checker: RateChecker,
    /// Position at the end of the last record, Q16.16 steps.
    last: [i64; 4],
    /// Idle periods still owed (a dwell), and their line.
    idle: u64,
    idle_line: usize,
    index: usize,
    profile: Profile,
    t: f64,
    cursor: NurbsCursor,
    started: bool,
    done: bool,
    /// Records emitted so far.
    emitted: u64,
    /// I/O events placed but not yet taken ([`Periods::take_events`]).
    events: Vec<TimedEvent>,
    /// The profiles of the run of elements from `run_first` on planned as one
    /// ([`Periods::try_run`]).
    run: Vec<Profile>,
    run_first: usize,
    /// Room for [`Periods::try_run`]: the junction speeds and elements of a run tried,
    /// and its profiles before they replace `run`, kept from run to run.
    run_speeds: Vec<f64>,
    run_elements: Vec<RunElement>,
    run_trial: Vec<Profile>,
}

/// A source of a path's elements, in order, or the error that ends the path. Boxed,
/// as the path stream makes them ([`crate::geometry::PathStream`]): the window moves
/// pointers, not elements.
pub type ElementSource<'p> = Box<dyn Iterator<Item = Result<Box<Element>, ProgramError>> + Send + 'p>;

/// The elements of a path read from their source as far as the look-ahead asks, those
/// the interpolation has left forgotten.
struct PathWindow<'p> {
    source: ElementSource<'p>,
    /// Elements `base..base + elements.len()`.
    elements: VecDeque<Box<Element>>,
    base: usize,
    complete: bool,
    error: Option<ProgramError>,
    /// The most elements kept at once.
    peak: usize,
}

impl std::fmt::Debug for PathWindow<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PathWindow")
            .field("base", &self.base)
            .field("kept", &self.elements.len())
            .field("complete", &self.complete)
            .field("error", &self.error)
            .finish_non_exhaustive()
    }
}

impl PathWindow<'_> {
    /// Forgets the elements before `i`.
    fn release(&mut self, i: usize) {
        let gone = i.saturating_sub(self.base).min(self.elements.len());
        self.elements.drain(..gone);
        self.base += gone;
    }
}

impl ElementWindow for PathWindow<'_> {
    fn reach(&mut self, upto: usize) -> Result<(), ProgramError> {
        while !self.complete && self.known() < upto {
            if let Some(error) = &self.error {
                return Err(error.clone());
            }
            match self.source.next() {
                Some(Ok(e)) => {
                    self.elements.push_back(e);
                    self.peak = self.peak.max(self.elements.len());
                }
                Some(Err(error)) => {
                    self.error = Some(error.clone());
                    return Err(error);
                }
                None => self.complete = true,
            }
        }
        Ok(())
    }

    fn known(&self) -> usize {
        self.base + self.elements.len()
    }

    fn complete(&self) -> bool {
        self.complete
    }

    fn element(&self, i: usize) -> &Element {
        &self.elements[i - self.base]
    }
}

impl<'p> Periods<'p> {
    /// The periods of `elements`, after `leading_dwell` idle periods, from rest at the origin.
    pub fn new(config: Resolved, elements: Vec<Element>, leading_dwell: u64) -> Periods<'static> {
        Periods::from_source(config, Box::new(elements.into_iter().map(|e| Ok(Box::new(e)))), leading_dwell)
    }

    /// The periods of the elements `source` produces, read as the look-ahead needs them,
    /// after `leading_dwell` idle periods, from rest at the origin. An error from the
    /// source ends the records there.
    pub fn from_source(config: Resolved, source: ElementSource<'p>, leading_dwell: u64) -> Periods<'p> {
        let checker = RateChecker::with_slots(config.period_clocks, &config.timing, config.step_slots);
        let speeds = WindowedSpeeds::new(&config);
        let mut path = PathWindow { source, elements: VecDeque::new(), base: 0, complete: false, error: None, peak: 0 };
        // The dwell before the first move is on the first element's line; an error here
        // comes back with the first moving period.
        let _ = path.reach(1);
        let idle_line = path.elements.front().map_or(0, |e| e.line);
        Periods {
            config,
            path,
            speeds,
            checker,
            last: [0; 4],
            idle: leading_dwell,
            idle_line,
            index: 0,
            profile: Profile::default(),
            t: 0.0,
            cursor: NurbsCursor::new(usize::MAX, 0.0),
            started: false,
            done: false,
            emitted: 0,
            events: Vec::new(),
            run: Vec::new(),
            run_first: usize::MAX,
            run_speeds: Vec::new(),
            run_elements: Vec::new(),
            run_trial: Vec::new(),
        }
    }

    /// With the I/O events before the first move, each after that many of the leading
    /// idle periods ([`crate::geometry::PathElements::leading_events`]).
    pub fn with_leading_events(mut self, events: &[(u64, IoEvent)]) -> Periods<'p> {
        self.events.extend(events.iter().map(|(period, event)| TimedEvent { period: *period, event: event.clone() }));
        self
    }

    /// The I/O events placed so far and not yet taken, in order. An event is placed when
    /// the record that stops before it is produced (its `period` is at most the count of
    /// records produced plus the dwell that precedes it), so a consumer that reads all
    /// records and then takes the events has them all.
    pub fn take_events(&mut self) -> Vec<TimedEvent> {
        std::mem::take(&mut self.events)
    }

    /// The path's elements read so far (all of them once the records have ended).
    pub fn elements_read(&self) -> usize {
        self.path.known()
    }

    /// The most path elements kept at once so far: within the look-ahead window
    /// ([`WindowedSpeeds::window`]) and the two junctions around it.
    pub fn peak_elements_kept(&self) -> usize {
        self.path.peak
    }

    /// The look-ahead window, in elements.
    pub fn window(&self) -> usize {
        self.speeds.window()
    }

    fn profile_of(&mut self, i: usize) -> Result<Profile, ProgramError> {
        if let Some(profile) = i.checked_sub(self.run_first).and_then(|k| self.run.get(k)) {
            let profile = *profile;
            self.speeds.release(i);
            self.path.release(i);
            return Ok(profile);
        }
        let v0 = self.speeds.speed_in(&self.config, &mut self.path, i)?;
        let v1 = self.speeds.speed_in(&self.config, &mut self.path, i + 1)?;
        self.speeds.release(i);
        self.path.release(i);
        if self.config.profile == ProfileKind::SCurve && self.try_run(i, v0, v1)? {
            return Ok(self.run[0]);
        }
        let e = self.path.element(i);
        let profile = Profile::new(&element_limits(&self.config, e), e.length, v0, v1, e.v_cap);
        if self.config.profile == ProfileKind::SCurve {
            // The caps again at the speed the profile reaches, where that is below the
            // element's cap (`Needs::caps_at`): the faster profile where it fits.
            let top = profile.peak();
            if let Some((limits, cap)) = needs_limits(&self.config, e, top) {
                let again = Profile::new(&limits, e.length, v0, v1, cap);
                if again.covers() && again.duration < profile.duration {
                    return Ok(again);
                }
            }
        }
        Ok(profile)
    }

    /// S-curve: plans the NURBS sub-pieces from `i` on whose junction speeds rise (or
    /// fall) all the way as one run ([`run_profiles`]), so that the acceleration is
    /// carried across their junctions; the longest such run (at most
    /// [`MAX_RUN_ELEMENTS`]) where that is possible and faster, else halves of it. Each
    /// sub-piece's limits are derived at the run's higher end, and again at the highest
    /// speed the run's speed change has in it ([`needs_limits`], `limits_at` of
    /// [`run_profiles_into`]). Whether a run was planned (its profiles in `self.run`
    /// from `i`).
    fn try_run(&mut self, i: usize, v0: f64, v1: f64) -> Result<bool, ProgramError> {
        let smooth = |e: &Element| matches!(e.shape, Shape::Nurbs { .. }) && !e.stop_after && !e.jump_after;
        if v0 == v1 || !smooth(self.path.element(i)) {
            return Ok(false);
        }
        let rising = v1 > v0;
        let mut speeds = std::mem::take(&mut self.run_speeds);
        speeds.clear();
        speeds.extend([v0, v1]);
        let planned = self.plan_run(i, rising, &mut speeds);
        self.run_speeds = speeds;
        planned
    }

    /// [`Periods::try_run`] from `i` with the run's first junction speeds in `speeds`.
    fn plan_run(&mut self, i: usize, rising: bool, speeds: &mut Vec<f64>) -> Result<bool, ProgramError> {
        let smooth = |e: &Element| matches!(e.shape, Shape::Nurbs { .. }) && !e.stop_after && !e.jump_after;
        // Elements i..i + speeds.len() - 1 so far; extend while the junction after the
        // last is smooth and the speeds keep going the same way.
        while speeds.len() <= MAX_RUN_ELEMENTS {
            let last = i + speeds.len() - 2;
            if !smooth(self.path.element(last)) {
                break;
            }
            self.path.reach(last + 2)?;
            if self.path.known() <= last + 1 || !matches!(self.path.element(last + 1).shape, Shape::Nurbs { .. }) {
                break;
            }
            let v = self.speeds.speed_in(&self.config, &mut self.path, last + 2)?;
            let previous = speeds[speeds.len() - 1];
            if v == previous || (v > previous) != rising {
                break;
            }
            speeds.push(v);
        }
        // The speed never passes the run's higher end: each element's caps at it.
        let top = speeds[0].max(speeds[speeds.len() - 1]);
        let mut elements = std::mem::take(&mut self.run_elements);
        elements.clear();
        elements.extend((0..speeds.len() - 1).map(|k| {
            let e = self.path.element(i + k);
            match needs_limits(&self.config, e, top) {
                Some((limits, cap)) => RunElement { length: e.length, limits, cap },
                None => RunElement { length: e.length, limits: element_limits(&self.config, e), cap: e.v_cap },
            }
        }));
        let mut n = elements.len();
        let mut planned = false;
        while n >= 2 {
            let (config, path) = (&self.config, &self.path);
            let limits_at = |k: usize, v: f64| needs_limits(config, path.element(i + k), v).map(|(limits, _)| limits);
            if run_profiles_into(&elements[..n], &speeds[..=n], &mut self.run_trial, &limits_at) {
                std::mem::swap(&mut self.run, &mut self.run_trial);
                self.run_first = i;
                planned = true;
                break;
            }
            n /= 2;
        }
        self.run_elements = elements;
        Ok(planned)
    }

    fn emit(&mut self, grid: [i64; 4], flags: u8, line: usize) -> Result<(PeriodRecord, usize), ProgramError> {
        let mut record = PeriodRecord { flags, ..PeriodRecord::default() };
        for a in 0..4 {
            let delta = grid[a] - self.last[a];
            let raw = i32::try_from(delta).map_err(|_| {
                let reason =
                    format!("axis {} would move {} steps in one period", AXIS_NAMES[a], delta as f64 / 65536.0);
                ProgramError::new(line, reason)
            })?;
            record.inc[a] = Increment::from_bits(raw);
        }
        self.checker.check(&record).map_err(|(axis, why)| {
            let axis = AXIS_NAMES.get(axis).unwrap_or(&"?");
            ProgramError::new(line, format!("axis {axis}: {why} (planner bug: refusing to emit)"))
        })?;
        self.last = grid;
        self.emitted += 1;
        Ok((record, line))
    }

    fn grid(&self, p: Vec4) -> [i64; 4] {
        let mut g = [0i64; 4];
        for (a, axis) in self.config.axes.iter().enumerate() {
            g[a] = round_to_i64(p[a] * axis.steps_per_unit * 65536.0);
        }
        g
    }

    fn grid_exact(&self, p: Vec4) -> [i64; 4] {
        let mut g = [0i64; 4];
        for (a, axis) in self.config.axes.iter().enumerate() {
            g[a] = ((p[a] * axis.steps_per_unit).round() as i64) << 16;
        }
        g
    }

    /// The next moving period (or the stop that ends an element), `None` at the end.
    fn step(&mut self) -> Option<Result<(PeriodRecord, usize), ProgramError>> {
        if !self.started {
            self.started = true;
            if let Err(error) = self.path.reach(1) {
                return Some(Err(error));
            }
            if self.path.complete() && self.path.known() == 0 {
                self.done = true;
                return None;
            }
            self.profile = match self.profile_of(0) {
                Ok(profile) => profile,
                Err(error) => return Some(Err(error)),
            };
        }
        self.t += self.config.period_s;
        let mut flags = 0;
        while self.t >= self.profile.duration {
            let (block_end, stop_after, end, line) = {
                let e = self.path.element(self.index);
                (e.block_end, e.stop_after, e.end, e.line)
            };
            if block_end {
                flags |= BLOCK_END;
            }
            if let Err(error) = self.path.reach(self.index + 2) {
                return Some(Err(error));
            }
            let last_element = self.path.complete() && self.index + 1 == self.path.known();
            if stop_after || last_element {
                // An exact stop (the last element always stops): the period ends on it,
                // at rest (block end), and its I/O events follow it and the dwell before
                // each.
                let grid = self.grid_exact(end);
                let out = self.emit(grid, flags | BLOCK_END, line);
                let e = self.path.element(self.index);
                (self.idle, self.idle_line) = (e.dwell_periods, e.dwell_line);
                let emitted = self.emitted;
                self.events
                    .extend(e.events.iter().map(|(d, event)| TimedEvent { period: emitted + d, event: event.clone() }));
                self.index += 1;
                if last_element {
                    self.done = true;
                } else {
                    match self.profile_of(self.index) {
                        Ok(profile) => self.profile = profile,
                        Err(error) => return Some(Err(error)),
                    }
                    self.t = 0.0;
                }
                return Some(out);
            }
            self.t -= self.profile.duration;
            self.index += 1;
            match self.profile_of(self.index) {
                Ok(profile) => self.profile = profile,
                Err(error) => return Some(Err(error)),
            }
        }
        let s = self.profile.distance_at(self.t);
        let element = self.path.element(self.index);
        let point = match element.shape {
            Shape::Nurbs { ref curve, u0, u1 } => {
                if self.cursor.element != self.index {
                    self.cursor = NurbsCursor::new(self.index, u0);
                }
                if s >= element.length {
                    element.end
                } else {
                    self.cursor.advance(curve, u1, s);
                    self.cursor.point(curve)
                }
            }
            _ => element.position(s),
        };
        let line = element.line;
        let grid = self.grid(point);
        Some(self.emit(grid, flags, line))
    }
}

/// `x.round() as i64` (half away from zero, saturating, NaN to 0) without the library
/// call `f64::round` is on the baseline x86-64 target: the fraction `x - trunc(x)` is
/// exact, so comparing it with one half decides the rounding exactly.
#[inline]
fn round_to_i64(x: f64) -> i64 {
    let t = x as i64;
    let fraction = x - t as f64;
    if fraction >= 0.5 {
        t.saturating_add(1)
    } else if fraction <= -0.5 {
        t.saturating_sub(1)
    } else {
        t
    }
}

/// The profile limits and speed cap of `e` where its speed stays at or below `top`, from
/// what its caps were derived from ([`crate::element::Needs::caps_at`]); `None` where
/// they cannot be derived again or `top` is not below its cap.
fn needs_limits(config: &Resolved, e: &Element, top: f64) -> Option<(Limits, f64)> {
    let needs = e.needs.as_deref()?;
    if !(top > 0.0 && top < e.v_cap * (1.0 - 1e-9)) {
        return None;
    }
    let caps = needs.caps_at(top, e.v_cap, e.accel, e.jerk);
    (caps.accel >= e.accel && caps.jerk >= e.jerk && caps.v_cap >= top * (1.0 - 1e-12))
        .then_some((Limits { kind: config.profile, accel: caps.accel, jerk: caps.jerk }, top))
}

impl Iterator for Periods<'_> {
    type Item = Result<(PeriodRecord, usize), ProgramError>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.idle > 0 {
            self.idle -= 1;
            // At rest: block end, so the FIFO may run dry after it (an I/O event).
            return Some(self.emit(self.last, BLOCK_END, self.idle_line));
        }
        if self.done {
            return None;
        }
        let out = self.step();
        if matches!(out, Some(Err(_))) {
            self.done = true;
            self.idle = 0;
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::round_to_i64;

    /// The rounding of the grid agrees with `f64::round` everywhere it is used and at the
    /// edges: halves either side of zero, the largest exact integers, beyond i64, NaN.
    #[test]
    fn rounding_to_the_grid_agrees_with_the_library() {
        let mut values = vec![0.0, -0.0, 0.5, -0.5, 1.5, -1.5, 2.5, -2.5, 0.49999999999999994, -0.49999999999999994];
        values.extend([4503599627370495.5, -4503599627370495.5, 9007199254740993.0, 1e19, -1e19, f64::NAN]);
        values.extend([f64::INFINITY, f64::NEG_INFINITY, 1e-300, -1e-300]);
        let mut x = 0.123_456_789f64;
        for _ in 0..100_000 {
            x = (x * 3.987_654_321 + 0.5).fract() * 2e9 - 1e9;
            values.push(x);
            values.push(x.trunc() + 0.5);
            values.push(x.trunc() - 0.5);
        }
        for v in values {
            assert_eq!(round_to_i64(v), v.round() as i64, "{v:e}");
        }
    }
}

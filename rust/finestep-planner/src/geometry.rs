//! The path as the planner follows it: programmed lines and arcs, vertices rounded to
//! whole steps, and (in G64) line-line corners replaced by blend arcs (S-curve: pairs of
//! clothoids). A NURBS
//! (G5.2/G5.3) becomes [`Shape::Nurbs`] sub-pieces of the curve itself, its first and
//! last control points on whole steps, with limits from its curvature
//! ([`crate::nurbs`]); it is not blended with its neighbours.
//!
//! # Corner blending and the path tolerance criterion
//!
//! Where two lines meet at a corner C turning by an angle phi, the first of them in G64
//! with tolerance P (G64 without P: the configured `path_tolerance_mm`), the
//! corner is replaced by the circle tangent to both lines whose midpoint is P from C:
//! radius `R = P / (1/cos(phi/2) - 1)`, tangent points `t = R tan(phi/2)` before and
//! after C. `t` is at most half of either line (so neighbouring blends never overlap),
//! which shrinks R for short lines. The blend is an arc element like any other: its
//! speed is capped by the normal acceleration it needs (`v^2/R`), by the chord tolerance
//! and in S-curve mode by the jerk of turning, and every point of it is within P of the
//! programmed corner. Corners involving programmed arcs, reversals, and corners in G61
//! are not blended; their speed comes from the junction criterion in
//! [`crate::lookahead`].
//!
//! With the S-curve profile the blend is continuous in curvature instead: two mirrored
//! clothoids ([`Shape::Clothoid`], curvature rising linearly from the line's 0 to a peak
//! at the bisector and back), whose meeting point on the bisector is at most P from C
//! and which leave the lines at most half of either line from C. A circle's curvature
//! jumps from 0 to 1/R where it meets its lines, and the jerk limit read over the
//! periods around that jump (`|dk| v^2 / T`) capped the speed at every blend; the
//! clothoids' curvature changes at `k' = phi / L^2` (L each clothoid's length), whose
//! jerk `k' v^3` the element's own caps keep (its turning takes
//! [`BLEND_TURNING_JERK_SHARE`] of each axis's jerk), so its junctions with the lines
//! flow at the speed both allow. For the same P the clothoids reach further along the
//! lines than the circle (about 1.5 times for small angles) and peak at a higher
//! curvature (about 4/3 of the circle's).
//!
//! # Smoothing short segments (S-curve)
//!
//! A blend has at most half of either line, so on short segments (CAM output) every
//! vertex turns within the two segments around it and the clothoids' turning jerk caps
//! the speed there. With [`Resolved::smooth_short_segments`] (the S-curve profile) a run
//! of fed lines in G64, each at most [`crate::smooth::MAX_SEGMENT_TOLERANCES`] times P
//! long, turning at most [`crate::smooth::MAX_TURN`] at every vertex, with the same
//! feed and P and nothing between them (no dwell, I/O or stop), becomes one cubic
//! B-spline within P of the lines ([`crate::smooth::fit`]), as NURBS sub-pieces
//! ([`crate::nurbs_pieces`]). The curve leaves along the run's first line (a corner
//! blend before it ends tangent to it); where the run flows on into the next run it
//! ends along the bisector of the vertex there, and the next curve starts with the same
//! tangent and curvature; where it turns a corner the run's last line stays a line and
//! the corner is blended as before. Runs hold at most [`crate::smooth::MAX_RUN_MOVES`]
//! moves and at least [`crate::smooth::MIN_RUN_MOVES`]; a run whose fit is not within
//! P is made line by line. The curve's pieces take the lines of the moves they start on;
//! only the last carries the block end.

use std::borrow::Cow;
use std::collections::VecDeque;
use std::f64::consts::TAU;
use std::sync::{Arc, OnceLock};

use finestep_gcode::{Block, BlockKind, CompSide, MessageKind, PathControl, Plane, Point, Program};

use crate::config::{ProfileKind, Resolved, AXIS_NAMES};
pub use crate::element::{
    full_caps, full_caps_turning, AxisShare, Caps, Element, Shape, ARC_JERK_SHARE, BLEND_TURNING_JERK_SHARE,
    GEOMETRIC_ACCEL_SHARE, JUMP_REACH_PERIODS, JUNCTION_JERK_SHARE, NORMAL_SHARE_MIN, TANGENTIAL_ACCEL_SHARE,
    TANGENTIAL_JERK_SHARE, TURNING_JERK_SHARE,
};
use crate::element::{jump_jerk_share, short_length, tangential_jerk_share, IoAction, IoEvent};
use crate::error::ProgramError;
use crate::nurbs::NurbsCurve;
use crate::nurbs_pieces;
pub use crate::vec4::Vec4;
use crate::vec4::{add_scaled, dot, norm, scale, sub};

/// A programmed move before blending, vertices rounded to whole steps.
#[derive(Clone, Debug)]
struct Move {
    /// The curve of a NURBS move (its end control points on whole steps).
    nurbs: Option<Arc<NurbsCurve>>,
    line: usize,
    start: Vec4,
    end: Vec4,
    /// Path feed, units/s (infinite for rapids: the axes limit them).
    feed: f64,
    /// `Some(centre, plane axes, clockwise, extra turns)` for arcs.
    arc: Option<(Vec4, (usize, usize), bool, u32)>,
    /// Start and end as programmed, before rounding (arcs take their sweep from these).
    programmed: (Vec4, Vec4),
    /// Blend tolerance with the next move (None: exact stop).
    blend: Option<f64>,
    stop_after: bool,
    dwell_periods: u64,
    dwell_line: usize,
    /// I/O events at the stop after the move, each after that many dwell periods.
    events: Vec<(u64, IoEvent)>,
}

/// The element `e` made from `m` takes the stop, dwell and events after `m`.
fn take_after(e: &mut Element, m: &Move) {
    e.stop_after = m.stop_after;
    e.dwell_periods = m.dwell_periods;
    e.dwell_line = m.dwell_line;
    e.events = m.events.clone();
}

/// `m` made no element: the stop, dwell and events after it go after `last`.
fn merge_after(last: &mut Element, m: &Move) {
    last.stop_after |= m.stop_after;
    last.events.extend(m.events.iter().map(|(d, event)| (last.dwell_periods + d, event.clone())));
    last.dwell_periods += m.dwell_periods;
    last.dwell_line = last.dwell_line.max(m.dwell_line);
}

fn coords(p: &Point) -> Vec4 {
    [p.x_mm, p.y_mm, p.z_mm, p.a_deg]
}

/// A point moved to the nearest whole step on every axis.
pub(crate) fn round_to_steps(config: &Resolved, p: Vec4) -> Vec4 {
    let mut q = p;
    for (a, axis) in config.axes.iter().enumerate() {
        q[a] = (p[a] * axis.steps_per_unit).round() / axis.steps_per_unit;
    }
    q
}

/// The smallest arc radius interpolated, in steps of either plane axis.
pub const MIN_ARC_RADIUS_STEPS: f64 = 10.0;

/// The signed angle from `start` to `end`, a full turn when they coincide.
fn sweep_angle(start: f64, end: f64, clockwise: bool, extra_turns: u32) -> f64 {
    let ccw = (end - start).rem_euclid(TAU);
    let base = if clockwise { -((TAU - ccw) % TAU) } else { ccw };
    let base = if base.abs() < 1e-12 {
        if clockwise {
            -TAU
        } else {
            TAU
        }
    } else {
        base
    };
    base + f64::from(extra_turns) * TAU * base.signum()
}

/// Reads the program's moves one at a time: positions rounded to steps, modes
/// resolved. A move is handed on once the move after it is read (or the program has
/// ended), because what follows it until then (a dwell, an I/O change, G61) puts a stop,
/// a dwell or an event after it.
#[derive(Debug)]
struct MoveReader {
    at: Vec4,
    /// The last programmed point read, on whole steps ([`program_end`] once the program
    /// has ended).
    end: Vec4,
    at_programmed: Vec4,
    blend: Option<f64>,
    /// The spindle and coolant as the program leaves them: M2 or M30 (or the program's
    /// last line) turns on ones off, as LinuxCNC's M2 does (M5, M9).
    left_on: (Option<IoAction>, bool),
    /// G96: the surface speed in force ([`crate::css`]).
    css: Option<finestep_gcode::SurfaceSpeed>,
    last_line: usize,
    /// Idle periods and I/O events before the first move (final once it is read).
    leading_dwell: u64,
    leading_events: Vec<(u64, IoEvent)>,
    /// The last move read, what follows it not yet known.
    pending: Option<Move>,
    finished: bool,
}

impl MoveReader {
    fn new(config: &Resolved) -> MoveReader {
        MoveReader {
            at: [0.0; 4],
            end: [0.0; 4],
            at_programmed: [0.0; 4],
            blend: Some(config.path_tolerance_mm), // LinuxCNC starts in G64
            left_on: (None, false),
            css: None,
            last_line: 0,
            leading_dwell: 0,
            leading_events: Vec::new(),
            pending: None,
            finished: false,
        }
    }

    /// An exact stop after the last move read, with `dwell` idle periods (line `line`);
    /// false before the first move.
    fn stop_previous(&mut self, dwell: u64, line: usize) -> bool {
        if let Some(last) = self.pending.as_mut() {
            last.stop_after = true;
            last.blend = None;
            last.dwell_periods += dwell;
            if dwell > 0 {
                last.dwell_line = line;
            }
            true
        } else {
            false
        }
    }

    /// An exact stop after the last move read (or before the first), with `event` at it
    /// after that stop's dwell.
    fn event_at_stop(&mut self, event: IoEvent) {
        match self.pending.as_mut() {
            Some(last) => {
                last.stop_after = true;
                last.blend = None;
                last.events.push((last.dwell_periods, event));
            }
            None => self.leading_events.push((self.leading_dwell, event)),
        }
    }

    /// G96 with the spindle turning: the speed of the move from the last programmed point
    /// to `to` (an arc about `arc`'s centre, a NURBS of `nurbs`' control points), set at
    /// an exact stop before it where it differs from the speed now ([`crate::css`]).
    fn surface_speed_for(
        &mut self,
        config: &Resolved,
        line: usize,
        to: Vec4,
        arc: Option<(Vec4, (usize, usize), bool, u32)>,
        nurbs: Option<&[(f64, f64, f64)]>,
    ) {
        let (Some(css), Some(IoAction::Spindle { rotation, rpm: now, .. })) = (self.css, self.left_on.0.clone()) else {
            return;
        };
        let from = self.at_programmed;
        let span = arc.filter(|&(_, (a, b), ..)| a == 0 || b == 0).map(|(c, (a, b), clockwise, turns)| {
            let angle = |p: Vec4| (p[b] - c[b]).atan2(p[a] - c[a]);
            crate::css::ArcSpan {
                centre_x: c[0],
                radius: (from[a] - c[a]).hypot(from[b] - c[b]),
                start: angle(from),
                sweep: sweep_angle(angle(from), angle(to), clockwise, turns),
                x_first: a == 0,
            }
        });
        let control_x: Vec<f64> = nurbs.unwrap_or(&[]).iter().map(|p| p.0).collect();
        let max = config.spindle_max_rpm;
        let rpm = crate::css::move_rpm(&css, max, from[0], to[0], span.as_ref(), &control_x);
        if rpm != now {
            let action = IoAction::Spindle { rotation, rpm, fraction: rpm / max };
            self.left_on.0 = Some(action.clone());
            self.event_at_stop(IoEvent { line, action });
        }
    }

    /// The program has ended: the last move stops, and what the program left on is
    /// turned off after it.
    fn finish(&mut self) {
        self.finished = true;
        let mut off = Vec::new();
        if let Some(IoAction::Spindle { rpm, fraction, .. }) = self.left_on.0 {
            let rotation = finestep_gcode::SpindleRotation::Off;
            off.push(IoEvent { line: self.last_line, action: IoAction::Spindle { rotation, rpm, fraction } });
        }
        if self.left_on.1 {
            off.push(IoEvent { line: self.last_line, action: IoAction::Coolant { mist: false, flood: false } });
        }
        match self.pending.as_mut() {
            Some(last) => {
                last.stop_after = true;
                last.blend = None;
                let dwell = last.dwell_periods;
                last.events.extend(off.into_iter().map(|event| (dwell, event)));
            }
            None => {
                let dwell = self.leading_dwell;
                self.leading_events.extend(off.into_iter().map(|event| (dwell, event)));
            }
        }
    }

    /// The next move with what follows it settled, `None` after the last.
    fn next_move(&mut self, config: &Resolved, blocks: &mut BlockSource<'_>) -> Result<Option<Move>, ProgramError> {
        while !self.finished {
            let block = match blocks.next() {
                Some(block) => block?,
                None => {
                    self.finish();
                    break;
                }
            };
            let block = &block;
            let fail = |reason: String| ProgramError::new(block.line, reason);
            // The program's last line: that of M2 or M30, or of the last block.
            self.last_line = block.line;
            // G38.x: the probe armed at an exact stop before the move, checked at one after.
            let probe_check = if let BlockKind::Probe { on_contact, must_change, .. } = block.kind {
                self.event_at_stop(IoEvent {
                    line: block.line,
                    action: IoAction::ProbeArm { on_contact, must_change },
                });
                Some(IoEvent { line: block.line, action: IoAction::ProbeCheck { must_change } })
            } else {
                None
            };
            let action = match block.kind {
                BlockKind::Spindle { rotation, rpm, css } => {
                    let max = config.spindle_max_rpm;
                    self.css = css;
                    // G96: the speed where the tool stands; each move sets its own below.
                    let rpm = match css {
                        Some(css) => {
                            let x = self.at_programmed[0];
                            crate::css::move_rpm(&css, max, x, x, None, &[])
                        }
                        None if !(0.0..=max).contains(&rpm) => {
                            return Err(fail(format!("S{rpm} is outside 0..={max} rev/min (spindle.max_rpm)")))
                        }
                        None => rpm,
                    };
                    Some(IoAction::Spindle { rotation, rpm, fraction: rpm / max })
                }
                BlockKind::Coolant { mist, flood } => Some(IoAction::Coolant { mist, flood }),
                BlockKind::DigitalOutput { index, on } => {
                    if index > 7 {
                        return Err(fail(format!("digital output P{index}: the chip has outputs 0 to 7")));
                    }
                    Some(IoAction::Output { index, on })
                }
                BlockKind::WaitInput { input, mode, timeout_s } => Some(IoAction::WaitInput { input, mode, timeout_s }),
                BlockKind::AnalogOutput { index, value, .. } => Some(IoAction::AnalogOutput { index, value }),
                BlockKind::UserMCode { code, p, q } => Some(IoAction::UserMCode { code, p, q }),
                // MSG and DEBUG go out once the motion before them has ended, as in
                // LinuxCNC; PRINT is written as the program is read (by its reader).
                BlockKind::Message { kind: kind @ (MessageKind::Msg | MessageKind::Debug), ref text } => {
                    Some(IoAction::Message { kind, text: text.clone() })
                }
                _ => None,
            };
            if let Some(action) = action {
                match &action {
                    IoAction::Spindle { rotation, .. } => {
                        self.left_on.0 = (*rotation != finestep_gcode::SpindleRotation::Off).then(|| action.clone())
                    }
                    IoAction::Coolant { mist, flood } => self.left_on.1 = *mist || *flood,
                    _ => {}
                }
                // An exact stop where the block is: the change takes effect at rest there.
                self.event_at_stop(IoEvent { line: block.line, action });
                continue;
            }
            let mut nurbs: Option<Vec<(f64, f64, f64)>> = None;
            let mut nurbs_shape: (usize, &[f64]) = (0, &[]);
            let (to, feed, arc) = match block.kind {
                BlockKind::Nurbs { to, ref control_points, order, ref knots, feed_mm_per_min } => {
                    nurbs = Some(control_points.iter().map(|c| (c.x_mm, c.y_mm, c.weight)).collect());
                    nurbs_shape = (order as usize, knots);
                    (coords(&to), feed_mm_per_min / 60.0, None)
                }
                BlockKind::Rapid { to } => (coords(&to), f64::INFINITY, None),
                // The probe move runs to its end: it is the host that acts on the latch.
                BlockKind::Probe { to, feed_mm_per_min, .. } => (coords(&to), feed_mm_per_min / 60.0, None),
                BlockKind::Linear { to, feed_mm_per_min } => (coords(&to), feed_mm_per_min / 60.0, None),
                BlockKind::Arc { to, centre, plane, clockwise, extra_turns, feed_mm_per_min } => {
                    let axes = match plane {
                        Plane::Xy => (0, 1),
                        Plane::Zx => (2, 0),
                        Plane::Yz => (1, 2),
                    };
                    (coords(&to), feed_mm_per_min / 60.0, Some((coords(&centre), axes, clockwise, extra_turns)))
                }
                BlockKind::Dwell { seconds } => {
                    let periods = (seconds / config.period_s).ceil();
                    if !(0.0..=1e9).contains(&periods) {
                        return Err(fail(format!("dwell of {seconds} s is out of range")));
                    }
                    if !self.stop_previous(periods as u64, block.line) {
                        self.leading_dwell += periods as u64;
                    }
                    continue;
                }
                BlockKind::SpindleOrient { .. } => {
                    return Err(fail(
                        "spindle orientation (M19, G87) needs a spindle position encoder, which finestep does not read (the spindle runs open loop)".into(),
                    ));
                }
                BlockKind::CutterComp { side: CompSide::Left | CompSide::Right, .. }
                | BlockKind::CutterCompRadius { .. } => {
                    return Err(fail(
                        "cutter radius compensation (G41/G42) is not wired into the planner yet; refusing to cut uncompensated".into(),
                    ));
                }
                BlockKind::PathControl(PathControl::Blend { tolerance_mm }) => {
                    self.blend = Some(tolerance_mm.filter(|&p| p > 0.0).unwrap_or(config.path_tolerance_mm));
                    continue;
                }
                BlockKind::PathControl(PathControl::ExactPath) => {
                    self.blend = None;
                    continue;
                }
                BlockKind::Pause | BlockKind::ToolChange { .. } => {
                    self.stop_previous(0, block.line);
                    continue;
                }
                BlockKind::End => {
                    self.finish();
                    break;
                }
                _ => continue,
            };
            if let BlockKind::Rapid { to }
            | BlockKind::Linear { to, .. }
            | BlockKind::Arc { to, .. }
            | BlockKind::Nurbs { to, .. }
            | BlockKind::Probe { to, .. } = block.kind
            {
                if let Some(axis) = to.extra_axis_away() {
                    return Err(fail(format!(
                        "axis {axis} moves, but the chip drives the axes X Y Z A (B C U V W are interpreted, not driven)"
                    )));
                }
            }
            if feed.is_nan() || feed <= 0.0 {
                return Err(fail(format!("feed {} mm/min must be positive", feed * 60.0)));
            }
            self.surface_speed_for(config, block.line, to, arc, nurbs.as_deref());
            let programmed = (self.at_programmed, to);
            self.at_programmed = to;
            let to = round_to_steps(config, to);
            self.end = to;
            for (a, axis) in config.axes.iter().enumerate() {
                if !axis.present && to[a] != self.at[a] {
                    return Err(fail(format!("axis {} moves but is not configured", AXIS_NAMES[a])));
                }
                let steps = (to[a] * axis.steps_per_unit).abs();
                if axis.present && (steps.is_nan() || steps >= 2f64.powi(31)) {
                    return Err(fail(format!(
                        "axis {} endpoint {} is outside the core's 32-bit step position",
                        AXIS_NAMES[a], to[a]
                    )));
                }
            }
            let curve = match nurbs {
                Some(mut points) => {
                    // The first control point is where the tool is (on whole steps), the last
                    // the rounded end: the curve moves by at most half a step per axis.
                    for (x, y, _) in &points {
                        for (a, value) in [(0usize, *x), (1, *y)] {
                            let axis = &config.axes[a];
                            if !axis.present && value != self.at[a] {
                                return Err(fail(format!("axis {} moves but is not configured", AXIS_NAMES[a])));
                            }
                            let steps = (value * axis.steps_per_unit).abs();
                            if axis.present && (steps.is_nan() || steps >= 2f64.powi(31)) {
                                return Err(fail(format!(
                                    "NURBS control point {AXIS_NAMES}{value} is outside the core's 32-bit step position",
                                    AXIS_NAMES = AXIS_NAMES[a]
                                )));
                            }
                        }
                    }
                    let n = points.len();
                    points[0].0 = self.at[0];
                    points[0].1 = self.at[1];
                    points[n - 1].0 = to[0];
                    points[n - 1].1 = to[1];
                    // A curve whose control points all lie within half a step (per axis) of its
                    // ends is no curve on this machine: it moves as a line (or not at all).
                    let near = |x: f64, y: f64, q: Vec4| {
                        (0..2)
                            .all(|a| ((if a == 0 { x } else { y } - q[a]) * config.axes[a].steps_per_unit).abs() <= 0.5)
                    };
                    if points.iter().all(|&(x, y, _)| near(x, y, self.at) || near(x, y, to)) {
                        None
                    } else {
                        let (order, knots) = nurbs_shape;
                        let curve = NurbsCurve::new(&points, order.saturating_sub(1), knots, self.at)
                            .map_err(|e| fail(e.to_string()))?;
                        Some(Arc::new(curve))
                    }
                }
                None => None,
            };
            if arc.is_none() && curve.is_none() && to == self.at {
                // Nothing to move on this machine; keeps neighbouring corners blendable. In
                // G61 the move still ends in an exact stop, here: where the move before ends.
                // A probe move that stays put is checked where it stands.
                if let Some(check) = probe_check {
                    self.event_at_stop(check);
                } else if self.blend.is_none() {
                    self.stop_previous(0, block.line);
                }
                continue;
            }
            // G61 stops at the end of every move.
            let m = Move {
                nurbs: curve,
                line: block.line,
                start: self.at,
                end: to,
                feed,
                arc,
                programmed,
                blend: if probe_check.is_some() { None } else { self.blend },
                stop_after: self.blend.is_none() || probe_check.is_some(),
                dwell_periods: 0,
                dwell_line: 0,
                events: probe_check.into_iter().map(|check| (0, check)).collect(),
            };
            self.at = to;
            if let Some(done) = self.pending.replace(m) {
                return Ok(Some(done));
            }
        }
        Ok(self.pending.take())
    }
}

/// Per-axis shares of the path speed for a unit path speed (an upper bound on arcs);
/// `normal` the shape's per-axis normal shares ([`normal_shares`]), which an arc's
/// weights are made of.
fn axis_weights(shape: &Shape, length: f64, normal: &Vec4) -> Vec4 {
    match *shape {
        Shape::Line { dir } => dir.map(f64::abs),
        Shape::Nurbs { .. } => [1.0, 1.0, 0.0, 0.0], // sub-pieces get their limits in `nurbs`
        // The tangent cos(theta) d1 + sin(theta) n1 for theta from 0 to the turn.
        Shape::Clothoid { d1, n1, half, sharpness, .. } => {
            let turn = Turn::new(sharpness * half * half);
            std::array::from_fn(|a: usize| turn.largest(d1[a], n1[a]).min(1.0))
        }
        Shape::Arc { r0, r1, sweep, rise, .. } => {
            let planar = (r0.max(r1) * sweep.abs() / length).min(1.0);
            let radial = (r1 - r0).abs() / length;
            std::array::from_fn(|a: usize| ((planar + radial) * normal[a] + (rise[a] / length).abs()).min(1.0))
        }
    }
}

/// Per-axis shares of the normal direction over an element (what its normal
/// acceleration and turning put on each axis, per unit): `hypot(e1, e2)` on an arc,
/// the largest of the normal `n1 cos(theta) - d1 sin(theta)` over a clothoid pair's
/// turn, 0 on a line and a NURBS sub-piece (its limits come from [`crate::nurbs`]).
/// Computed once per element: [`limit`] reads them for both its caps.
fn normal_shares(shape: &Shape) -> Vec4 {
    match *shape {
        Shape::Arc { e1, e2, .. } => std::array::from_fn(|a: usize| e1[a].hypot(e2[a])),
        Shape::Clothoid { d1, n1, half, sharpness, .. } => {
            let turn = Turn::new(sharpness * half * half);
            std::array::from_fn(|a: usize| turn.largest(n1[a], -d1[a]))
        }
        Shape::Line { .. } | Shape::Nurbs { .. } => [0.0; 4],
    }
}

/// A turn by `angle` (at most pi), its cosine and sine taken once for every axis.
struct Turn {
    angle: f64,
    cos: f64,
    sin: f64,
}

impl Turn {
    fn new(angle: f64) -> Turn {
        Turn { angle, cos: angle.cos(), sin: angle.sin() }
    }

    /// The largest `|a cos(theta) + b sin(theta)|` for theta in `0..=angle`: at an end,
    /// or `hypot(a, b)` where the stationary angle `atan2(b, a)` (mod pi) lies within
    /// the turn.
    fn largest(&self, a: f64, b: f64) -> f64 {
        let ends = a.abs().max((a * self.cos + b * self.sin).abs());
        if b.atan2(a).rem_euclid(std::f64::consts::PI) <= self.angle {
            ends.max(a.hypot(b))
        } else {
            ends
        }
    }
}

/// A new element of `shape` with its limits set by [`limit`], boxed where it is made
/// (the path hands elements on boxed, [`PathStream`]) and limited in place.
fn limited(
    config: &Resolved,
    shape: Shape,
    start: Vec4,
    end: Vec4,
    length: f64,
    line: usize,
    feed: f64,
) -> Box<Element> {
    let mut element = Box::new(Element {
        shape,
        start,
        end,
        length,
        line,
        feed,
        v_cap: 0.0,
        accel: 0.0,
        jerk: 0.0,
        shared: Caps::default(),
        needs: None,
        tangential_jerk_share: tangential_jerk_share(length, short_length(config)),
        turning_jerk_share: 0.0,
        junction_jerk_share: JUNCTION_JERK_SHARE,
        jump_after: false,
        stop_after: false,
        dwell_periods: 0,
        dwell_line: 0,
        block_end: false,
        events: Vec::new(),
    });
    limit(config, &mut element, feed);
    element
}

/// Fills in the speed, acceleration and jerk limits of an element.
fn limit(config: &Resolved, element: &mut Element, feed: f64) {
    let normal = normal_shares(&element.shape);
    let weights = axis_weights(&element.shape, element.length, &normal);
    let mut v_cap = feed;
    let mut accel = f64::INFINITY;
    let mut jerk = f64::INFINITY;
    for (axis, &w) in config.axes.iter().zip(&weights) {
        if w > 1e-12 && axis.present {
            v_cap = v_cap.min(axis.max_velocity / w);
            accel = accel.min(TANGENTIAL_ACCEL_SHARE * axis.max_acceleration / w);
            jerk = jerk.min(element.tangential_jerk_share * axis.max_jerk / w);
        }
    }
    // The path's curvature, its change and the speed the chord error allows (seed
    // 002), for both caps below: 0 and the feed on a line.
    let (mut k, mut dk, mut v_limit) = (0.0, 0.0, feed);
    if let Shape::Arc { .. } = element.shape {
        let (planar, r) = element.planar_fraction_and_radius();
        k = planar * planar / r; // curvature of the path
        let scurve = config.profile == ProfileKind::SCurve;
        // Chord error (seed 002): a chord of length c on radius r sags r - sqrt(r^2 - c^2/4).
        let delta = config.chord_tolerance_mm.min(r);
        let chord = 2.0 * (r * r - (r - delta).powi(2)).sqrt();
        let chord_cap = chord / config.period_s / planar.max(1e-12);
        v_cap = v_cap.min(chord_cap);
        v_limit = v_limit.min(chord_cap);
        for (axis, &h) in normal.iter().enumerate() {
            let limits = &config.axes[axis];
            if h < 1e-12 || !limits.present {
                continue;
            }
            // Normal acceleration k v^2 within its share.
            v_cap = v_cap.min((GEOMETRIC_ACCEL_SHARE * limits.max_acceleration / (k * h)).sqrt());
            if scurve {
                // Rotation of the normal acceleration: k^2 v^3.
                v_cap = v_cap.min((ARC_JERK_SHARE * limits.max_jerk / (k * k * h)).cbrt());
            }
        }
        if scurve {
            for (axis, &h) in normal.iter().enumerate() {
                let limits = &config.axes[axis];
                if h >= 1e-12 && limits.present {
                    // Tangential acceleration turning with the path: 3 k v a.
                    accel = accel.min(ARC_JERK_SHARE * limits.max_jerk / (3.0 * k * v_cap * h));
                }
            }
        }
        // What turning reads at these caps, the most of any axis (each term within
        // ARC_JERK_SHARE by the caps above; both ARC_JERK_SHARE where not S-curve).
        element.turning_jerk_share = if scurve {
            (0..4)
                .filter(|&axis| config.axes[axis].present && normal[axis] >= 1e-12)
                .map(|axis| {
                    let h = normal[axis];
                    (k * k * v_cap.powi(3) * h + 3.0 * k * v_cap * accel * h) / config.axes[axis].max_jerk
                })
                .fold(0.0, f64::max)
                .min(2.0 * ARC_JERK_SHARE)
        } else {
            2.0 * ARC_JERK_SHARE
        };
    }
    if let Shape::Clothoid { half, sharpness, .. } = element.shape {
        // As an arc of the peak curvature whose curvature also changes: the turning
        // terms (k^2 + |k'|) v^3 and 3 k v a_t within ARC_JERK_SHARE each.
        (k, dk) = (sharpness * half, sharpness);
        let scurve = config.profile == ProfileKind::SCurve;
        let delta = config.chord_tolerance_mm.min(1.0 / k);
        let chord = 2.0 * (2.0 * delta / k - delta * delta).sqrt();
        v_cap = v_cap.min(chord / config.period_s);
        v_limit = v_limit.min(chord / config.period_s);
        for (axis, &h) in normal.iter().enumerate() {
            let limits = &config.axes[axis];
            if h < 1e-12 || !limits.present {
                continue;
            }
            v_cap = v_cap.min((GEOMETRIC_ACCEL_SHARE * limits.max_acceleration / (k * h)).sqrt());
            if scurve {
                v_cap = v_cap.min((ARC_JERK_SHARE * limits.max_jerk / ((k * k + dk) * h)).cbrt());
            }
        }
        let mut turning = 0.0f64;
        if scurve {
            for (axis, &h) in normal.iter().enumerate() {
                let limits = &config.axes[axis];
                if h >= 1e-12 && limits.present {
                    accel = accel.min(ARC_JERK_SHARE * limits.max_jerk / (3.0 * k * v_cap * h));
                }
            }
            for (axis, &h) in normal.iter().enumerate() {
                let limits = &config.axes[axis];
                if h >= 1e-12 && limits.present {
                    let w = weights[axis].max(h);
                    let reads = (k * k + dk) * v_cap.powi(3) * w + 3.0 * k * v_cap * accel * h;
                    turning = turning.max(reads / limits.max_jerk);
                }
            }
        }
        element.turning_jerk_share = if scurve { turning.min(2.0 * ARC_JERK_SHARE) } else { 2.0 * ARC_JERK_SHARE };
    }
    element.shared = Caps { v_cap, accel, jerk };
    // The limits shared by what the element needs (`crate::element`).
    // An absent axis has no share (w = n = 0).
    let axes: [AxisShare; 4] = std::array::from_fn(|a| {
        let axis = &config.axes[a];
        let present = if axis.present { 1.0 } else { 0.0 };
        AxisShare {
            w: present * weights[a],
            n: present * normal[a],
            velocity: axis.max_velocity,
            accel: axis.max_acceleration,
            jerk: axis.max_jerk,
        }
    });
    // A blend between lines turns more than it speeds up: its turning takes the larger share.
    let turning_share =
        if matches!(element.shape, Shape::Clothoid { .. }) { BLEND_TURNING_JERK_SHARE } else { TURNING_JERK_SHARE };
    let full = full_caps_turning(
        &axes,
        v_limit,
        k,
        dk,
        config.profile == ProfileKind::SCurve,
        turning_share,
        NORMAL_SHARE_MIN,
    );
    element.v_cap = full.v_cap;
    element.accel = full.accel;
    element.jerk = full.jerk;
}

fn line_element(config: &Resolved, m: &Move, start: Vec4, end: Vec4, feed: f64) -> Option<Box<Element>> {
    let delta = sub(end, start);
    let length = norm(delta);
    if length < 1e-12 {
        return None;
    }
    let shape = Shape::Line { dir: scale(1.0 / length, delta) };
    Some(limited(config, shape, start, end, length, m.line, feed))
}

/// The element of an arc move; `None` when rounding to steps left nothing to move.
fn arc_element(config: &Resolved, m: &Move) -> Result<Option<Box<Element>>, ProgramError> {
    let (centre, (u, v), clockwise, extra_turns) = m.arc.expect("arc move");
    let fail = |reason: String| ProgramError::new(m.line, reason);
    let (cu, cv) = (centre[u], centre[v]);
    let r0 = (m.start[u] - cu).hypot(m.start[v] - cv);
    let r1 = (m.end[u] - cu).hypot(m.end[v] - cv);
    if r0.min(r1).is_nan() || r0.min(r1) <= 1e-9 || !r0.is_finite() || !r1.is_finite() {
        return Err(fail(format!("arc radius {} is too small to interpolate", r0.min(r1))));
    }
    // Rounding the ends to whole steps bends an arc of a few steps' radius out of shape
    // (its angle moves by up to half a step over the radius): refuse those.
    let (p0, _) = m.programmed;
    let programmed_radius = (p0[u] - cu).hypot(p0[v] - cv);
    for axis in [u, v] {
        let steps = programmed_radius * config.axes[axis].steps_per_unit;
        if steps < MIN_ARC_RADIUS_STEPS {
            return Err(fail(format!(
                "arc radius {programmed_radius} is only {steps:.1} steps of axis {}: at least {MIN_ARC_RADIUS_STEPS} are needed",
                AXIS_NAMES[axis]
            )));
        }
    }
    let theta0 = (m.start[v] - cv).atan2(m.start[u] - cu);
    let theta1 = (m.end[v] - cv).atan2(m.end[u] - cu);
    // The sweep as programmed, then moved by the small angle rounding the endpoints to
    // steps turned them through: rounding must not turn a tiny arc into a full circle.
    let (p0, p1) = m.programmed;
    let programmed_theta0 = (p0[v] - cv).atan2(p0[u] - cu);
    let programmed_theta1 = (p1[v] - cv).atan2(p1[u] - cu);
    let programmed_sweep = sweep_angle(programmed_theta0, programmed_theta1, clockwise, extra_turns);
    let wrap = |angle: f64| (angle + std::f64::consts::PI).rem_euclid(TAU) - std::f64::consts::PI;
    let sweep = programmed_sweep + wrap(theta1 - programmed_theta1) - wrap(theta0 - programmed_theta0);
    let mut unit_u = [0.0; 4];
    unit_u[u] = 1.0;
    let mut unit_v = [0.0; 4];
    unit_v[v] = 1.0;
    let e1 = add_scaled(scale(theta0.cos(), unit_u), theta0.sin(), unit_v);
    let e2 = add_scaled(scale(-theta0.sin(), unit_u), theta0.cos(), unit_v);
    let mut rise = sub(m.end, m.start);
    rise[u] = 0.0;
    rise[v] = 0.0;
    let mut c = m.start;
    c[u] = cu;
    c[v] = cv;
    // The path parameter runs uniformly in angle, so the speed along the path is
    // |dp/df| / length with |dp/df|^2 = (r1 - r0)^2 + r^2 sweep^2 + |rise|^2: taking the
    // larger radius makes `length` an upper bound on it, so the real speed never exceeds
    // the planned one (a spiral from rounded endpoints is a hair shorter than planned).
    let planar = r0.max(r1) * sweep.abs();
    let length = (planar * planar + (r1 - r0).powi(2) + dot(rise, rise)).sqrt();
    if !length.is_finite() {
        return Err(fail("arc is too long".into()));
    }
    if length < 1e-12 {
        return Ok(None);
    }
    let shape = Shape::Arc { centre: c, e1, e2, r0, r1, sweep, rise };
    Ok(Some(limited(config, shape, m.start, m.end, length, m.line, m.feed)))
}

/// The blend arc for the corner between lines `d1` then `d2` at `corner`, with the
/// tangent distance along each line: `None` when the corner needs none (straight on)
/// or cannot have one (reversal, no room).
fn blend_arc(corner: Vec4, d1: Vec4, d2: Vec4, tolerance: f64, room: f64) -> Option<(Vec4, Vec4, Shape, f64)> {
    let cos_phi = dot(d1, d2).clamp(-1.0, 1.0);
    let phi = cos_phi.acos();
    if !(1e-6..=std::f64::consts::PI - 1e-3).contains(&phi) {
        return None;
    }
    let half = 0.5 * phi;
    let r_tolerance = tolerance / (1.0 / half.cos() - 1.0);
    let radius = r_tolerance.min(room / half.tan());
    let t = radius * half.tan();
    if !(radius > 1e-9 && t > 1e-9) {
        return None;
    }
    let a = add_scaled(corner, -t, d1);
    let b = add_scaled(corner, t, d2);
    let across = add_scaled(d2, -cos_phi, d1);
    let n = scale(1.0 / norm(across), across);
    let centre = add_scaled(a, radius, n);
    let shape = Shape::Arc { centre, e1: scale(-1.0, n), e2: d1, r0: radius, r1: radius, sweep: phi, rise: [0.0; 4] };
    Some((a, b, shape, radius * phi))
}

/// The blend continuous in curvature for the corner between lines `d1` then `d2` at
/// `corner` (S-curve mode): two mirrored clothoids ([`Shape::Clothoid`]) turning by
/// the corner's angle phi, each of length `L`. Their meeting point lies on the corner's
/// bisector at `h = Y / cos(phi/2)` from the corner, and they leave the lines
/// `t = X + Y tan(phi/2)` before and after it, where `(X, Y)` is the end of one
/// clothoid in its own frame (both linear in `L` for a given phi); `L` is the largest
/// with `h <= tolerance` (every point of the blend is then within the tolerance of the
/// programmed corner) and `t <= room`. `None` as for [`blend_arc`].
fn clothoid_blend(corner: Vec4, d1: Vec4, d2: Vec4, tolerance: f64, room: f64) -> Option<(Vec4, Vec4, Shape, f64)> {
    let cos_phi = dot(d1, d2).clamp(-1.0, 1.0);
    let phi = cos_phi.acos();
    if !(1e-6..=std::f64::consts::PI - 1e-3).contains(&phi) {
        return None;
    }
    let half_angle = 0.5 * phi;
    // The clothoid of unit length turning by phi/2: sharpness phi.
    let (x1, y1) = crate::element::clothoid_xy(1.0, phi);
    let half = (tolerance * half_angle.cos() / y1).min(room / (x1 + y1 * half_angle.tan()));
    let t = half * (x1 + y1 * half_angle.tan());
    if !(half > 1e-9 && t > 1e-9 && t <= room * (1.0 + 1e-12)) {
        return None;
    }
    let across1 = add_scaled(d2, -cos_phi, d1);
    let across2 = add_scaled(scale(-1.0, d1), cos_phi, d2);
    let n1 = scale(1.0 / norm(across1), across1);
    let n2 = scale(1.0 / norm(across2), across2);
    let a = add_scaled(corner, -t, d1);
    let b = add_scaled(corner, t, d2);
    let shape = Shape::Clothoid { d1, n1, d2, n2, half, sharpness: phi / (half * half) };
    Some((a, b, shape, 2.0 * half))
}

/// The path of a program.
#[derive(Clone, Debug, PartialEq)]
pub struct PathElements {
    /// Elements in order; the last one stops.
    pub elements: Vec<Element>,
    /// Idle periods before the first move (G4 first).
    pub leading_dwell: u64,
    /// I/O events before the first move, each after that many of the leading idle periods.
    pub leading_events: Vec<(u64, IoEvent)>,
    /// Where the program ends, on whole steps.
    pub end: Vec4,
    /// Remarks for the report.
    pub notes: Vec<String>,
}

/// The program as elements, and where it ends: the whole path at once ([`PathStream`]
/// collected).
pub fn elements(config: &Resolved, program: &Program) -> Result<PathElements, ProgramError> {
    let mut stream = PathStream::new(config, Cow::Borrowed(program))?;
    let elements = stream.by_ref().map(|e| e.map(|e| *e)).collect::<Result<Vec<Element>, ProgramError>>()?;
    let (leading_dwell, leading_events) = (stream.leading_dwell(), stream.leading_events().to_vec());
    Ok(PathElements { elements, leading_dwell, leading_events, end: program_end(config, program), notes: Vec::new() })
}

/// Where `program` ends on the machine `config`, on whole steps: the last programmed
/// point before the program's end, without planning the path (what [`PathStream`]
/// reaches at its end when the program can be planned).
pub fn program_end(config: &Resolved, program: &Program) -> Vec4 {
    let mut at = [0.0; 4];
    for block in &program.blocks {
        match block.kind {
            BlockKind::Rapid { to }
            | BlockKind::Linear { to, .. }
            | BlockKind::Arc { to, .. }
            | BlockKind::Nurbs { to, .. } => at = round_to_steps(config, coords(&to)),
            BlockKind::End => break,
            _ => {}
        }
    }
    at
}

/// The path of a program produced as it is read ([`Iterator`] of elements): the
/// program's moves are read one at a time ([`MoveReader`]), a line's corner blend is
/// made once the move after it is known, and an element is handed on once no junction
/// still to come can make it take the fixed shares of the limits ([`Sharing`]). Memory
/// stays within a few elements and the sharing stage's hold (at most
/// [`Sharing::max_held`] elements), whatever the program's length. An error ends the
/// stream at the block that causes it.
pub struct PathStream<'p> {
    config: Resolved,
    blocks: BlockSource<'p>,
    reader: MoveReader,
    /// The move read and not yet made into elements: the move after it decides its blend.
    current: Option<Move>,
    /// Where the current move's element starts (after the previous blend).
    start: Vec4,
    pending_blend: Option<Box<Element>>,
    /// Elements made, the last held back: a move that makes no element puts its stop,
    /// dwell and events after it. Boxed from here to the look-ahead window, so that
    /// handing an element on from stage to stage moves a pointer, not the element.
    made: VecDeque<Box<Element>>,
    sharing: Sharing,
    /// Elements ready to hand on, in order.
    ready: VecDeque<Box<Element>>,
    done: bool,
    end: Arc<OnceLock<Vec4>>,
    /// Short lines read for the smoother ([`crate::smooth`]), not yet made.
    run: Vec<Move>,
    /// Runs of short lines are smoothed ([`Resolved::smooth_short_segments`]).
    smoothing: bool,
    /// Where the last smoothed curve ended, flowing on into the next run, its unit
    /// tangent and curvature vector there: the next curve starts with them.
    joint: Option<(Vec4, Vec4, Vec4)>,
}

/// Canonical blocks as the path reads them, one at a time; an error ends them.
pub type BlockSource<'p> = Box<dyn Iterator<Item = Result<Block, ProgramError>> + Send + 'p>;

impl std::fmt::Debug for PathStream<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PathStream").field("reader", &self.reader).field("done", &self.done).finish_non_exhaustive()
    }
}

impl<'p> PathStream<'p> {
    /// The path of `program` on the machine `config`, read up to its first move (so
    /// that [`PathStream::leading_dwell`] and [`PathStream::leading_events`] are known).
    pub fn new(config: &Resolved, program: Cow<'p, Program>) -> Result<PathStream<'p>, ProgramError> {
        let blocks: BlockSource<'p> = match program {
            Cow::Borrowed(program) => Box::new(program.blocks.iter().cloned().map(Ok)),
            Cow::Owned(program) => Box::new(program.blocks.into_iter().map(Ok)),
        };
        PathStream::from_blocks(config, blocks)
    }

    /// The path of the program whose blocks `blocks` gives as it is read (a parser's
    /// stream, [`finestep_gcode::BlockStream`]), read up to its first move.
    pub fn from_blocks(config: &Resolved, mut blocks: BlockSource<'p>) -> Result<PathStream<'p>, ProgramError> {
        let mut reader = MoveReader::new(config);
        let current = reader.next_move(config, &mut blocks)?;
        let start = current.as_ref().map(|m| m.start).unwrap_or([0.0; 4]);
        let done = current.is_none();
        let end = Arc::new(OnceLock::new());
        if done {
            let _ = end.set(reader.end);
        }
        Ok(PathStream {
            config: config.clone(),
            blocks,
            reader,
            current,
            start,
            pending_blend: None,
            made: VecDeque::new(),
            sharing: Sharing::new(config),
            ready: VecDeque::new(),
            done,
            end,
            run: Vec::new(),
            smoothing: config.smooth_short_segments,
            joint: None,
        })
    }

    /// Idle periods before the first move (G4 first).
    pub fn leading_dwell(&self) -> u64 {
        self.reader.leading_dwell
    }

    /// I/O events before the first move, each after that many of the leading idle periods.
    pub fn leading_events(&self) -> &[(u64, IoEvent)] {
        &self.reader.leading_events
    }

    /// Where the program ends, on whole steps ([`program_end`]): set once the path has
    /// been read to the program's end without an error.
    pub fn end(&self) -> Arc<OnceLock<Vec4>> {
        Arc::clone(&self.end)
    }

    /// The most elements the sharing stage has held at once so far.
    pub fn peak_held(&self) -> usize {
        self.sharing.peak
    }

    /// Reads one move and makes the elements of the move before it (or keeps it for a
    /// run of short lines to smooth, made once the run ends).
    fn advance(&mut self) -> Result<(), ProgramError> {
        let next = self.reader.next_move(&self.config, &mut self.blocks)?;
        if let Some(m) = self.current.take() {
            if self.smoothing && smoothable(&m) {
                let goes_on = !m.stop_after
                    && self.run.len() + 1 < crate::smooth::MAX_RUN_MOVES
                    && next.as_ref().is_some_and(|n| smoothable(n) && continues(&m, n));
                self.run.push(m);
                if !goes_on {
                    self.flush_run(next.as_ref())?;
                }
            } else {
                self.make(&m, next.as_ref())?;
            }
        }
        self.current = next;
        if self.current.is_none() {
            // The end: everything made goes on.
            if let Some(b) = self.pending_blend.take() {
                self.made.push_back(b);
            }
            while let Some(e) = self.made.pop_front() {
                self.sharing.push(&self.config, e, &mut self.ready);
            }
            self.sharing.finish(&mut self.ready);
            self.done = true;
            let _ = self.end.set(self.reader.end);
        }
        Ok(())
    }

    /// The run of short lines kept ([`PathStream::run`]), `following` the move after
    /// it: one smoothed curve ([`crate::smooth`]) when the run is long enough and the
    /// fit stays within P, else line by line. Where the path turns a corner into
    /// `following` (or it is no line), the run's last line is made as a line, so that
    /// its corner is blended as before and the curve ends tangent to it.
    fn flush_run(&mut self, following: Option<&Move>) -> Result<(), ProgramError> {
        let run = std::mem::take(&mut self.run);
        let Some(last) = run.last() else { return Ok(()) };
        let flows = following.is_some_and(|n| smoothable(n) && continues(last, n));
        let curved = if flows || last.stop_after { run.len() } else { run.len() - 1 };
        let mut made_to = 0;
        if curved >= crate::smooth::MIN_RUN_MOVES {
            // The curve ends along the line made after it, or where the next run takes
            // over, along the bisector of the two lines there (the tangent a smooth path
            // through the vertex has), or along its last line at a stop.
            let d1 = match following {
                _ if curved < run.len() => unit(&run[curved]),
                Some(n) if flows => unit_sum(unit(last), unit(n)),
                _ => unit(last),
            };
            if let Some((pieces, joint)) = self.smoothed(&run[..curved], d1)? {
                self.joint = (curved == run.len() && flows).then_some(joint);
                if let Some(b) = self.pending_blend.take() {
                    self.made.push_back(b);
                }
                self.made.extend(pieces.into_iter().map(Box::new));
                self.start = run[curved - 1].end;
                while self.made.len() > 1 {
                    let e = self.made.pop_front().expect("an element");
                    self.sharing.push(&self.config, e, &mut self.ready);
                }
                made_to = curved;
            }
        }
        for i in made_to..run.len() {
            self.make(&run[i], run.get(i + 1).or(following))?;
        }
        Ok(())
    }

    /// The elements of the curve smoothing `run` from where the path is
    /// ([`PathStream::start`]: along the run's first line, or as the curve before
    /// ended), ending along `d1`, and its end, tangent and curvature vector; `None` when
    /// the fit is not within the tolerance.
    #[allow(clippy::type_complexity)]
    fn smoothed(&self, run: &[Move], d1: Vec4) -> Result<Option<(Vec<Element>, (Vec4, Vec4, Vec4))>, ProgramError> {
        let first = &run[0];
        let last = &run[run.len() - 1];
        let tolerance = first.blend.unwrap_or(0.0);
        let mut points = Vec::with_capacity(run.len() + 1);
        points.push(self.start);
        points.extend(run.iter().map(|m| m.end));
        points.dedup_by(|b, a| norm(sub(*b, *a)) < 1e-9);
        let joint = self.joint.filter(|(p, _, _)| *p == self.start && self.pending_blend.is_none());
        let (d0, k0) = match joint {
            Some((_, d, k)) => (d, Some(k)),
            None => (unit(first), None),
        };
        let Some(curve) = crate::smooth::fit(&points, d0, k0, d1, tolerance) else { return Ok(None) };
        let curve = Arc::new(curve);
        let per_span = crate::smooth::SAMPLES_PER_SPAN;
        let Ok(mut pieces) = nurbs_pieces::pieces_sampled(&self.config, curve, first.feed, first.line, per_span) else {
            return Ok(None);
        };
        // Each piece takes the line of the move its start lies on (by chord length).
        let mut s = 0.0;
        let ends: Vec<f64> = std::iter::once(self.start)
            .chain(run.iter().map(|m| m.end))
            .collect::<Vec<_>>()
            .windows(2)
            .map(|w| {
                s += norm(sub(w[1], w[0]));
                s
            })
            .collect();
        for piece in pieces.iter_mut() {
            if let Shape::Nurbs { u0, .. } = piece.shape {
                let i = ends.partition_point(|&e| e <= u0).min(run.len() - 1);
                piece.line = run[i].line;
            }
        }
        let end = pieces.last_mut().expect("a curve has a piece");
        end.block_end = true;
        take_after(end, last);
        let joint = (end.end, d1, end.curvature(true));
        Ok(Some((pieces, joint)))
    }

    /// The elements of move `m`, `next` the move after it (a line blends into a line).
    fn make(&mut self, m: &Move, next: Option<&Move>) -> Result<(), ProgramError> {
        self.joint = None;
        let config = &self.config;
        let out = &mut self.made;
        if let Some(b) = self.pending_blend.take() {
            out.push_back(b);
        }
        if let Some(curve) = &m.nurbs {
            let mut pieces = nurbs_pieces::pieces(config, Arc::clone(curve), m.feed, m.line)
                .map_err(|e| ProgramError::new(m.line, e.to_string()))?;
            let last = pieces.last_mut().expect("a NURBS has a piece");
            last.block_end = true;
            take_after(last, m);
            out.extend(pieces.into_iter().map(Box::new));
            self.start = m.end;
        } else if m.arc.is_some() {
            if let Some(mut e) = arc_element(config, m)? {
                e.block_end = true;
                take_after(&mut e, m);
                out.push_back(e);
            } else if let Some(last) = out.back_mut() {
                merge_after(last, m);
            }
            self.start = m.end;
        } else {
            // A line: blend into the next line when both are lines and the mode allows.
            let next = next.filter(|n| n.arc.is_none() && n.nurbs.is_none());
            let mut end_here = m.end;
            if let (Some(tolerance), Some(n)) = (m.blend, next) {
                let d1 = sub(m.end, m.start);
                let d2 = sub(n.end, n.start);
                let (l1, l2) = (norm(d1), norm(d2));
                let room = 0.5 * l1.min(l2);
                // S-curve: blends continuous in curvature, so the jerk limit does not cap
                // the speed at a curvature jump where each blend meets its lines.
                let blend = if config.profile == ProfileKind::SCurve { clothoid_blend } else { blend_arc };
                if let Some((a, b, shape, length)) =
                    blend(m.end, scale(1.0 / l1, d1), scale(1.0 / l2, d2), tolerance, room)
                {
                    self.pending_blend = Some(limited(config, shape, a, b, length, n.line, m.feed.min(n.feed)));
                    end_here = a;
                }
            }
            if let Some(mut e) = line_element(config, m, self.start, end_here, m.feed) {
                e.block_end = true;
                take_after(&mut e, m);
                out.push_back(e);
            } else if let Some(last) = out.back_mut() {
                merge_after(last, m);
            }
            self.start = self.pending_blend.as_ref().map(|b| b.end).unwrap_or(m.end);
        }
        // All but the last element made are settled.
        while self.made.len() > 1 {
            let e = self.made.pop_front().expect("an element");
            self.sharing.push(&self.config, e, &mut self.ready);
        }
        Ok(())
    }
}

/// The unit direction of a line move.
fn unit(m: &Move) -> Vec4 {
    let d = sub(m.end, m.start);
    scale(1.0 / norm(d), d)
}

/// The unit bisector of the unit directions `a` and `b`.
fn unit_sum(a: Vec4, b: Vec4) -> Vec4 {
    let d = add_scaled(a, 1.0, b);
    scale(1.0 / norm(d), d)
}

/// A move the smoother may take into a run: a fed line in G64 (not A), no longer than
/// [`crate::smooth::MAX_SEGMENT_TOLERANCES`] times its tolerance, with nothing at its end
/// but perhaps an exact stop.
fn smoothable(m: &Move) -> bool {
    let Some(tolerance) = m.blend else { return false };
    let length = norm(sub(m.end, m.start));
    m.arc.is_none()
        && m.nurbs.is_none()
        && m.feed.is_finite()
        && m.start[3] == m.end[3]
        && m.dwell_periods == 0
        && m.events.is_empty()
        && length > 0.0
        && length <= crate::smooth::MAX_SEGMENT_TOLERANCES * tolerance
}

/// `n` continues the run after `m`: the same feed and tolerance, and a turn of at most
/// [`crate::smooth::MAX_TURN`] between them.
fn continues(m: &Move, n: &Move) -> bool {
    let (a, b) = (sub(m.end, m.start), sub(n.end, n.start));
    let cos = dot(a, b) / (norm(a) * norm(b));
    !m.stop_after && m.feed == n.feed && m.blend == n.blend && cos >= crate::smooth::MAX_TURN.cos()
}

impl Iterator for PathStream<'_> {
    type Item = Result<Box<Element>, ProgramError>;

    fn next(&mut self) -> Option<Self::Item> {
        loop {
            if let Some(e) = self.ready.pop_front() {
                return Some(Ok(e));
            }
            if self.done {
                return None;
            }
            if let Err(error) = self.advance() {
                self.done = true;
                self.ready.clear();
                return Some(Err(error));
            }
        }
    }
}

/// Where a junction jumps (`lookahead::junction_jumps`), the elements beside it take
/// the fixed shares of the limits (`crate::element`): every element within
/// [`JUMP_REACH_PERIODS`] periods' travel of it (at the elements' caps), so that
/// sub-pieces shorter than a period's travel (a NURBS near a heavy weight) do not put
/// their full tangential acceleration into the periods that read the jump. An exact
/// stop ends the reach.
///
/// Elements pass through in order. The reach after a jump is applied to the elements
/// as they come; the reach before it to the elements held. An element is handed on once
/// no junction still to come can reach back to it: an exact stop at or after it, or the
/// elements after it covering the reach at the fastest speed any element can have (the
/// norm of the axes' velocity limits: an element's cap keeps every axis within its own
/// limit, so its speed is within that norm). Should more than [`Sharing::max_held`]
/// elements be held (thousands of elements within three periods' travel), the first
/// is handed on with the fixed shares, which are within the limits wherever it is.
///
/// Each jump's share of the jerk ([`Element::junction_jerk_share`]) is set once its
/// reach is closed on both sides, from the most of the jerk the elements within it use
/// ([`crate::element::jump_jerk_share`]); a reach still open when its element
/// is handed on (forced, or at the path's end) leaves [`JUNCTION_JERK_SHARE`], which
/// holds beside any element.
#[derive(Debug)]
struct Sharing {
    /// Elements held, each with whether it takes the fixed shares.
    held: VecDeque<(Box<Element>, bool)>,
    /// Length of the held elements after the first.
    behind_first: f64,
    /// Held elements that stop after them.
    stops_held: usize,
    /// Reaches after jumps still open: length covered, fastest cap met, the number of
    /// the element before the jump, the most of the jerk an element met uses.
    forward: Vec<(f64, f64, usize, f64)>,
    /// Elements pushed so far (the number of the next).
    pushed: usize,
    /// Travel of the reach at the fastest speed any element can have.
    full_reach: f64,
    reach: f64,
    max_held: usize,
    peak: usize,
}

impl Sharing {
    fn new(config: &Resolved) -> Sharing {
        let fastest: f64 =
            config.axes.iter().filter(|a| a.present).map(|a| a.max_velocity * a.max_velocity).sum::<f64>().sqrt();
        let reach = JUMP_REACH_PERIODS * config.period_s;
        Sharing {
            held: VecDeque::new(),
            behind_first: 0.0,
            stops_held: 0,
            forward: Vec::new(),
            pushed: 0,
            full_reach: reach * fastest * (1.0 + 1e-9),
            reach,
            max_held: Sharing::max_held(config),
            peak: 0,
        }
    }

    /// The most elements held before the first is handed on with the fixed shares: the
    /// look-ahead window's.
    fn max_held(config: &Resolved) -> usize {
        4 * config.lookahead_moves.max(1)
    }

    fn push(&mut self, config: &Resolved, mut e: Box<Element>, ready: &mut VecDeque<Box<Element>>) {
        let reach = self.reach;
        let mut shared = false;
        if let Some((before, _)) = self.held.back_mut() {
            let jump = crate::lookahead::junction_jumps(config, before, &e);
            before.jump_after = jump;
            if jump {
                // Backward from the junction at the fastest cap met so far.
                let (mut covered, mut fastest, mut share) = (0.0, 0.0f64, 0.0f64);
                let last = self.held.len() - 1;
                for j in (0..=last).rev() {
                    let (element, take) = &mut self.held[j];
                    if j < last && element.stop_after {
                        break;
                    }
                    *take = true;
                    covered += element.length;
                    fastest = fastest.max(element.v_cap);
                    share = share.max(element.tangential_jerk_share + element.turning_jerk_share);
                    if covered >= reach * fastest {
                        break;
                    }
                }
                self.forward.push((0.0, 0.0, self.pushed - 1, share));
            }
        }
        // Forward from every open reach; a reach closed sets its jump's share.
        let first = self.pushed - self.held.len();
        let mut closed = Vec::new();
        self.forward.retain_mut(|(covered, fastest, before, share)| {
            shared = true;
            *covered += e.length;
            *fastest = fastest.max(e.v_cap);
            *share = share.max(e.tangential_jerk_share + e.turning_jerk_share);
            let open = !(*covered >= reach * *fastest || e.stop_after);
            if !open {
                closed.push((*before, *share));
            }
            open
        });
        for (before, share) in closed {
            if let Some((element, _)) = before.checked_sub(first).and_then(|j| self.held.get_mut(j)) {
                element.junction_jerk_share = jump_jerk_share(share);
            }
        }
        self.pushed += 1;
        if !self.held.is_empty() {
            self.behind_first += e.length;
        }
        self.stops_held += usize::from(e.stop_after);
        e.jump_after = false;
        self.held.push_back((e, shared));
        self.peak = self.peak.max(self.held.len());
        // Hand on what no junction to come can reach.
        loop {
            let settled = self.stops_held > 0 || self.behind_first >= self.full_reach;
            let forced = self.held.len() > self.max_held;
            if self.held.is_empty() || !(settled || forced) {
                break;
            }
            self.release(forced && !settled, ready);
        }
    }

    /// Hands on the first element held (with the fixed shares if `force`).
    fn release(&mut self, force: bool, ready: &mut VecDeque<Box<Element>>) {
        let (mut e, take) = self.held.pop_front().expect("an element held");
        self.stops_held -= usize::from(e.stop_after);
        match self.held.front() {
            Some((next, _)) => self.behind_first -= next.length,
            None => self.behind_first = 0.0,
        }
        if take || force {
            let Caps { v_cap, accel, jerk } = e.shared;
            (e.v_cap, e.accel, e.jerk) = (v_cap, accel, jerk);
            e.needs = None;
        }
        ready.push_back(e);
    }

    /// The path's end: everything held goes on.
    fn finish(&mut self, ready: &mut VecDeque<Box<Element>>) {
        while !self.held.is_empty() {
            self.release(false, ready);
        }
    }
}

// The pair rule of `lookahead` read on a path this module builds: the test lives here,
// where the path is made, so that `lookahead` needs nothing of `geometry`.
#[cfg(test)]
mod tests {
    use crate::config::{MachineConfig, ProfileKind};
    use crate::element::Element;
    use crate::lookahead::pair_jerk_cap;

    /// The position `s` along the elements laid end to end.
    fn position(elements: &[Element], mut s: f64) -> [f64; 4] {
        for e in elements {
            if s <= e.length {
                return e.position(s);
            }
            s -= e.length;
        }
        elements.last().expect("elements").end
    }

    /// The clothoid pair's Fresnel series against Simpson's rule on its definition, up
    /// to the largest half turn a blend has (pi/2 at the middle).
    #[test]
    fn the_clothoid_series_matches_its_integrals() {
        for &(s, sharpness) in &[(1.0, 1e-6), (0.3, 0.7), (1.0, 3.1), (2.0, 0.78), (0.05, 400.0)] {
            let (x, y) = crate::element::clothoid_xy(s, sharpness);
            let n = 20_000;
            let h = s / f64::from(n);
            let (mut sx, mut sy) = (0.0, 0.0);
            for i in 0..=n {
                let sigma = f64::from(i) * h;
                let theta = 0.5 * sharpness * sigma * sigma;
                let w = if i == 0 || i == n {
                    1.0
                } else if i % 2 == 1 {
                    4.0
                } else {
                    2.0
                };
                sx += w * theta.cos();
                sy += w * theta.sin();
            }
            let (sx, sy) = (sx * h / 3.0, sy * h / 3.0);
            assert!((x - sx).abs() < 1e-12 && (y - sy).abs() < 1e-12, "{s} {sharpness}: {x} {y} against {sx} {sy}");
        }
    }

    /// A clothoid blend on corners of every angle in a tilted 3-D plane: it starts and
    /// ends on the lines, along them, with no curvature there (finite differences); the
    /// two clothoids meet at the middle in position and tangent; the curvature peaks at
    /// `sharpness * half` there; no point is farther than the tolerance from the corner
    /// and the turn is the corner's; it leaves the lines within the room.
    #[test]
    fn a_clothoid_blend_is_tangent_and_flat_at_its_ends_and_within_the_tolerance() {
        use crate::vec4::{add_scaled, dot, norm, scale, sub};
        let tilt = |v: [f64; 3]| -> [f64; 4] {
            // A fixed rotation about the axis (1, 1, 1): the corner's plane is not XY.
            let (c, s) = (0.8f64, 0.6f64);
            let k = [1.0 / 3f64.sqrt(); 3];
            let kv = k[0] * v[0] + k[1] * v[1] + k[2] * v[2];
            let cross = [k[1] * v[2] - k[2] * v[1], k[2] * v[0] - k[0] * v[2], k[0] * v[1] - k[1] * v[0]];
            let r: [f64; 3] = std::array::from_fn(|i| v[i] * c + cross[i] * s + k[i] * kv * (1.0 - c));
            [r[0], r[1], r[2], 0.0]
        };
        let corner = [3.0, -2.0, 1.0, 0.0];
        for &phi in &[1e-4f64, 0.01, 0.3, 1.0, 1.5, 2.5, 3.1] {
            for &(tolerance, room) in &[(0.01, 5.0), (0.01, 0.05), (2.0, 0.7)] {
                let d1 = tilt([1.0, 0.0, 0.0]);
                let d2 = tilt([phi.cos(), phi.sin(), 0.0]);
                let Some((a, b, shape, length)) = super::clothoid_blend(corner, d1, d2, tolerance, room) else {
                    panic!("{phi}: no blend");
                };
                let super::Shape::Clothoid { half, sharpness, .. } = shape else { panic!("{shape:?}") };
                let e =
                    super::limited(&MachineConfig::default().resolve().unwrap(), shape.clone(), a, b, length, 1, 50.0);
                let t = norm(sub(corner, a));
                assert!(t <= room * (1.0 + 1e-12) && (norm(sub(b, corner)) - t).abs() < 1e-12, "{phi}: {t}");
                assert!(norm(sub(e.position(0.0), a)) < 1e-12 && norm(sub(e.position(length), b)) < 1e-12);
                // Tangent and curvature at the ends, and the middle, from positions.
                let h = 1e-3 * length;
                // Rounding of positions (about 4e-16 of them) read by a second difference.
                let noise = 1e-14 / (h * h);
                let at = |s: f64| e.position(s);
                let tangent = |s0: f64, s1: f64| scale(1.0 / (s1 - s0), sub(at(s1), at(s0)));
                assert!(norm(sub(tangent(0.0, h), d1)) < 1e-3 && norm(sub(tangent(length - h, length), d2)) < 1e-3);
                let second =
                    |s: f64| scale(1.0 / (h * h), add_scaled(add_scaled(at(s - h), -2.0, at(s)), 1.0, at(s + h)));
                assert!(norm(second(h)) <= 2.0 * sharpness * h + noise, "{phi}: {:?}", second(h));
                assert!(norm(second(length - h)) <= 2.0 * sharpness * h + noise);
                let peak = norm(second(half));
                assert!((peak - sharpness * half).abs() <= 1e-3 * sharpness * half + noise, "{phi}: {peak}");
                let before = tangent(half - h, half);
                let after = tangent(half, half + h);
                assert!(norm(sub(before, after)) < 2.0 * sharpness * half * h + 1e-9);
                assert!((sharpness * half * half - phi).abs() < 1e-9 * phi.max(1.0));
                let mut farthest = 0.0f64;
                for i in 0..=1000 {
                    let p = at(length * f64::from(i) / 1000.0);
                    // Distance to the programmed path: the ray into the corner, the ray out.
                    let off = sub(p, corner);
                    let to_ray = |d: [f64; 4], sign: f64| {
                        let along = sign * dot(off, d);
                        if along > 0.0 {
                            norm(add_scaled(off, -sign * along, d))
                        } else {
                            norm(off)
                        }
                    };
                    farthest = farthest.max(to_ray(d1, -1.0).min(to_ray(d2, 1.0)));
                    // In the corner's plane.
                    let normal = {
                        let (u, v) = (d1, d2);
                        [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0], 0.0]
                    };
                    assert!(dot(off, normal).abs() < 1e-9, "{phi}: off the plane");
                }
                let middle = norm(sub(at(half), corner));
                assert!(middle <= tolerance * (1.0 + 1e-9), "{phi}: {middle}");
                assert!(farthest <= tolerance * (1.0 + 1e-9), "{phi}: {farthest}");
            }
        }
    }

    /// 300 short lines on a wavy spiral with a Z staircase (the bench's CAM program's
    /// shape), G64 P0.01.
    fn wavy_staircase() -> finestep_gcode::Program {
        let mut text = String::from("G21 G90 G17 G64 P0.01\nF3000\n");
        for i in 0..300 {
            let t = f64::from(i) * 0.01;
            let r = 20.0 + 5.0 * (7.0 * t).sin();
            text.push_str(&format!("G1 X{:.4} Y{:.4} Z{:.4}\n", r * t.cos(), r * t.sin(), -0.001 * f64::from(i)));
        }
        text.push_str("M2\n");
        finestep_gcode::parse_str(&text, "cam.ngc").unwrap()
    }

    /// S-curve without the smoother: on the short segments of a CAM program with a Z
    /// staircase every line-line corner is a clothoid blend, and no junction jumps (the circles of
    /// trapezoid mode jump in curvature at nearly every one in S-curve terms), so every
    /// junction flows at the speed of the elements around it.
    #[test]
    fn s_curve_blends_short_segments_without_a_curvature_jump() {
        let program = wavy_staircase();
        // Corner by corner, the smoother off (with it the runs become one curve).
        let mut config = MachineConfig { profile: ProfileKind::SCurve, ..MachineConfig::default() }.resolve().unwrap();
        config.smooth_short_segments = false;
        let path = super::elements(&config, &program).unwrap().elements;
        let blends = path.iter().filter(|e| matches!(e.shape, super::Shape::Clothoid { .. })).count();
        assert!(blends >= 290, "{blends} clothoid blends");
        assert!(path.iter().all(|e| !matches!(e.shape, super::Shape::Arc { .. })));
        let jumps = path.windows(2).filter(|w| crate::lookahead::junction_jumps(&config, &w[0], &w[1])).count();
        assert_eq!(jumps, 0);
        // The same corners blended by circles jump in S-curve terms.
        let trapezoid = MachineConfig::default().resolve().unwrap();
        let circles = super::elements(&trapezoid, &program).unwrap().elements;
        let jumps = circles.windows(2).filter(|w| crate::lookahead::junction_jumps(&config, &w[0], &w[1])).count();
        assert!(jumps > 290, "{jumps}");
    }

    /// On short blended segments with a Z staircase (the bench's CAM program, whose Z
    /// blends turn over at every short line), the jerk read from four period boundaries
    /// at steady speed across a blend, a short line and a blend stays within the
    /// junction share of every axis's jerk at the pair's cap, whatever the phase, and
    /// comes close to it (the bound is not loose).
    #[test]
    fn the_pair_cap_bounds_the_jerk_read_across_a_short_line() {
        let program = wavy_staircase();
        // Blended by circles, as in trapezoid mode: S-curve blends line-line corners by
        // clothoids, which meet their lines without a curvature jump; the pair rule reads
        // the line between two jumps (as between programmed arcs), here those of circles.
        let circles = MachineConfig { profile: ProfileKind::Trapezoid, ..MachineConfig::default() }.resolve().unwrap();
        let config = MachineConfig { profile: ProfileKind::SCurve, ..MachineConfig::default() }.resolve().unwrap();
        let path = super::elements(&circles, &program).unwrap().elements;
        let (mut pairs, mut closest) = (0, 0.0f64);
        for w in path.windows(3) {
            let Some(pair) = pair_jerk_cap(&config, &w[0], &w[1], &w[2]) else { continue };
            if pair.both <= pair.apart_below {
                continue;
            }
            pairs += 1;
            let junction_share = w[0].junction_jerk_share.min(w[1].junction_jerk_share);
            let v = pair.both;
            let step = v * config.period_s;
            let total: f64 = w.iter().map(|e| e.length).sum();
            let t3 = config.period_s.powi(3);
            for phase in 0..40 {
                let mut s = step * f64::from(phase) / 40.0;
                while s + 3.0 * step <= total {
                    let p = [0.0, 1.0, 2.0, 3.0].map(|k| position(w, s + k * step));
                    for (a, axis) in config.axes.iter().enumerate().filter(|(_, axis)| axis.present) {
                        let jerk = (p[3][a] - 3.0 * p[2][a] + 3.0 * p[1][a] - p[0][a]).abs() / t3;
                        let share = jerk / (junction_share * axis.max_jerk);
                        assert!(share <= 1.0 + 1e-6, "axis {a} at {v} mm/s reads {jerk}");
                        closest = closest.max(share);
                    }
                    s += step;
                }
            }
        }
        assert!(pairs > 100, "{pairs} pairs");
        assert!(closest > 0.5, "the most read is {closest} of the share");
    }
}

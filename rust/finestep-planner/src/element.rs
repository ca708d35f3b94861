//! One element of the planned path (a line, an arc or a NURBS sub-piece) with its
//! speed, acceleration and jerk caps, and how each axis's limits are shared between the
//! motion along the path and turning.
//!
//! # Sharing the limits by what the path needs
//!
//! At a point of curvature k on a path moving at speed v with tangential acceleration
//! a_t and jerk j_t, axis a (tangent component T_a, normal component N_a) sees
//!
//! - acceleration `a_t T_a + k v^2 N_a`,
//! - jerk `(j_t - k^2 v^3) T_a + (3 k v a_t + k' v^3) N_a` (k' = dk/ds).
//!
//! Each element gets its caps from these ([`full_caps`]), with the largest |T_a| (`w`)
//! and |N_a| (`n`) over it: the speed cap first, where the normal acceleration takes
//! the share `f` of the axis's limit that the path needs (the most, [`NORMAL_SHARE_MAX`],
//! where the curvature is constant or at its extremum; less where it changes fast, so
//! that the tangential acceleration needed to follow the curvature's speed limit,
//! `f A k' / (2 k^2)`, is left), then the tangential acceleration takes all that the
//! normal acceleration at the cap leaves, and the tangential jerk all that the turning
//! terms leave, each within [`FULL_SHARE`] of the limit. A line takes [`FULL_SHARE`]
//! of every limit along it.
//!
//! Where a junction jumps (a corner the path takes with a tangent jump, or in S-curve
//! mode a curvature jump, that reads as more than [`JUMP_READING`] of a limit within a
//! period), the jump takes its own share of the limits ([`GEOMETRIC_ACCEL_SHARE`],
//! [`JUNCTION_JERK_SHARE`]) and the elements within three periods' travel of it (the
//! periods whose readings include the jump; several elements where NURBS sub-pieces are
//! shorter than a period's travel) take the fixed shares ([`Element::shared`]:
//! [`TANGENTIAL_ACCEL_SHARE`], [`TANGENTIAL_JERK_SHARE`], [`ARC_JERK_SHARE`]), as
//! [`crate::lookahead`] describes. The jerk's split between a jump and the tangential
//! jerk of the elements within its reach follows their lengths: an element shorter than
//! [`short_length`] takes [`SHORT_TANGENTIAL_JERK_SHARE`] (on short segments the jumps
//! cap the speed, not the time the speed changes take), and a jump takes what the
//! elements within its reach leave of [`JUMP_BUDGET_JERK_SHARE`], their tangential share
//! and what their turning reads at their caps ([`jump_jerk_share`]): at least
//! [`JUNCTION_JERK_SHARE`], more beside lines, gentle arcs and short elements. Where the path is smooth,
//! the acceleration read over the periods around a junction is an average of the
//! accelerations on either side, each within the limit, so no share is kept for it.

use std::sync::Arc;

use crate::nurbs::{parameter_at, NurbsCurve};
use crate::vec4::{add_scaled, norm, scale, Vec4};

/// The shape of one element.
#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    /// A straight line from the element's start along a unit direction.
    Line {
        /// Unit direction.
        dir: Vec4,
    },
    /// `centre + r(f) (cos(f sweep) e1 + sin(f sweep) e2) + f rise` for f in 0..=1, with
    /// `r(f) = r0 + f (r1 - r0)`: a circle, spiral (rounded endpoints) or helix.
    Arc {
        /// Centre at f = 0.
        centre: Vec4,
        /// Unit vector from the centre to the start.
        e1: Vec4,
        /// Unit vector a quarter turn on (the direction of motion at the start for sweep > 0).
        e2: Vec4,
        /// Start radius.
        r0: f64,
        /// End radius.
        r1: f64,
        /// Signed angle swept, radians.
        sweep: f64,
        /// Motion of the axes outside the plane over the whole arc.
        rise: Vec4,
    },
    /// A corner blend continuous in curvature (S-curve mode, [`crate::geometry`]): two
    /// clothoids mirrored about the corner's bisector. From the start (on the line
    /// entering the corner, direction `d1`) the curvature rises linearly with the path
    /// length, `k(s) = sharpness s`, to its peak `sharpness * half` at the middle, and
    /// falls back to 0 at the end (on the line leaving it, direction `d2`): the tangent
    /// turns by `sharpness * half^2` in all, in the plane of `d1` and `d2`, and the
    /// curvature meets the lines' 0 at both ends.
    Clothoid {
        /// Unit direction of the line entering the corner.
        d1: Vec4,
        /// Unit normal to `d1` in the corner's plane, towards the turn.
        n1: Vec4,
        /// Unit direction of the line leaving the corner.
        d2: Vec4,
        /// Unit normal to `d2` in the corner's plane, towards the turn.
        n2: Vec4,
        /// Length of each clothoid (half the blend), units.
        half: f64,
        /// Curvature gained per unit length, 1/units^2.
        sharpness: f64,
    },
    /// The part `u0..=u1` (within one knot span) of a NURBS curve in XY
    /// ([`crate::nurbs`]), interpolated along the curve itself.
    Nurbs {
        /// The whole curve, shared by its sub-pieces.
        curve: Arc<NurbsCurve>,
        /// Parameter at the start.
        u0: f64,
        /// Parameter at the end.
        u1: f64,
    },
}

/// One piece of the path with its own speed limits.
#[derive(Clone, Debug, PartialEq)]
pub struct Element {
    /// Shape.
    pub shape: Shape,
    /// Start point, units.
    pub start: Vec4,
    /// End point, units.
    pub end: Vec4,
    /// Path length, units.
    pub length: f64,
    /// Source line of the block.
    pub line: usize,
    /// The programmed feed along the element, units/s (infinite for rapids; a blend's,
    /// the smaller of its two moves'): the block's own, where one line holds blocks of
    /// different feeds (a canned cycle's rapids and feeds, a loop's changing F).
    pub feed: f64,
    /// Speed cap along the element, units/s: feed, per-axis speeds, arc limits.
    pub v_cap: f64,
    /// Tangential acceleration limit, units/s^2.
    pub accel: f64,
    /// Tangential jerk limit, units/s^3.
    pub jerk: f64,
    /// The caps under the fixed shares of the limits, which the element takes when a
    /// junction beside it jumps (module docs).
    pub shared: Caps,
    /// The share of the tangential jerk [`Element::shared`] takes
    /// ([`tangential_jerk_share`]).
    pub tangential_jerk_share: f64,
    /// The most of any axis's jerk (as a share of its limit) turning takes on this
    /// element at the caps of [`Element::shared`]: 0 on a line, what `k^2 v^3` and
    /// `3 k v a_t` read at those caps on an arc or a NURBS sub-piece (with its curvature
    /// change, `k'` v^3, on a NURBS), at most `2 * ARC_JERK_SHARE`.
    pub turning_jerk_share: f64,
    /// The share of each axis's jerk the jump at the junction after this element may
    /// take ([`jump_jerk_share`] of the most the elements within its reach use, set
    /// where the path is built; [`JUNCTION_JERK_SHARE`] until then).
    pub junction_jerk_share: f64,
    /// What the element's caps were derived from where it takes the limits by what the
    /// path needs (a NURBS sub-piece away from jumps): its caps may be derived again
    /// for a lower speed cap ([`Needs::caps_at`]); `None` elsewhere.
    pub needs: Option<Box<Needs>>,
    /// The junction after this element jumps ([`crate::lookahead::junction_jumps`],
    /// decided on the path's caps before the fixed shares are taken).
    pub jump_after: bool,
    /// The junction after this element is an exact stop; `dwell_periods` idle periods follow.
    pub stop_after: bool,
    /// Idle periods after the stop (G4).
    pub dwell_periods: u64,
    /// Source line of the dwell.
    pub dwell_line: usize,
    /// The last element of a programmed block (its period gets the block-end flag).
    pub block_end: bool,
    /// Machine-I/O changes at the exact stop after this element, each after that many of
    /// its dwell periods (`stop_after` is set whenever this is not empty).
    pub events: Vec<(u64, IoEvent)>,
}

/// A machine-I/O action the program takes at a point of the path (S, M3/M4/M5,
/// M7/M8/M9, M62-M68, the probe of G38.x, a MSG or DEBUG message), applied at an exact
/// stop.
#[derive(Clone, Debug, PartialEq)]
pub enum IoAction {
    /// The spindle after the block.
    Spindle {
        /// M3, M4 or M5.
        rotation: finestep_gcode::SpindleRotation,
        /// The programmed speed (the last S), rev/min.
        rpm: f64,
        /// `rpm` over the configuration's `spindle.max_rpm` (0..=1).
        fraction: f64,
    },
    /// M62-M65: general output `index` (the chip's GPIO bit) on or off.
    Output {
        /// The output, 0 to 7 (the chip has 8 at most).
        index: u32,
        /// On or off.
        on: bool,
    },
    /// The coolant after the block.
    Coolant {
        /// M7.
        mist: bool,
        /// M8.
        flood: bool,
    },
    /// G38.2-G38.5: arm the probe latch for the probe move that follows this stop (the
    /// move ends in an exact stop with [`IoAction::ProbeCheck`]).
    ProbeArm {
        /// G38.2/G38.3: the event is the probe making contact; G38.4/G38.5: losing it.
        on_contact: bool,
        /// G38.2/G38.4: the move must end with the probe changed.
        must_change: bool,
    },
    /// The end of a probe move: read the probe latch (and, for G38.2/G38.4, fail
    /// without an event).
    ProbeCheck {
        /// G38.2/G38.4.
        must_change: bool,
    },
    /// M66: wait for (or read at once) an input.
    WaitInput {
        /// The input.
        input: finestep_gcode::Input,
        /// What to wait for.
        mode: finestep_gcode::WaitMode,
        /// The longest wait, seconds.
        timeout_s: f64,
    },
    /// M100-M199: run the user M-code program `M<code>` (found in the configuration's
    /// `user_m_path`) with P and Q as its arguments, at rest, and go on when it ends.
    UserMCode {
        /// The M number, 100 to 199.
        code: u32,
        /// P.
        p: f64,
        /// Q.
        q: f64,
    },
    /// M67/M68: analog output `index` set to `value` (M67's, synchronised with the next
    /// move in LinuxCNC, acts at rest before it, as M62/M63 do).
    AnalogOutput {
        /// The output.
        index: u32,
        /// The value.
        value: f64,
    },
    /// `(MSG, text)` or `(DEBUG, text)`: show `text` to the operator once the motion
    /// before it has ended (LinuxCNC's task sends an operator message when everything
    /// queued before it is done). PRINT gives no event: LinuxCNC writes it as the
    /// program is interpreted.
    Message {
        /// [`finestep_gcode::MessageKind::Msg`] or [`finestep_gcode::MessageKind::Debug`].
        kind: finestep_gcode::MessageKind,
        /// The text (DEBUG's with its parameters substituted).
        text: String,
    },
}

/// An [`IoAction`] and the source line that wrote it.
#[derive(Clone, Debug, PartialEq)]
pub struct IoEvent {
    /// 1-based source line.
    pub line: usize,
    /// What changes.
    pub action: IoAction,
}

/// An [`IoEvent`] placed in the record stream: it takes effect once the first `period`
/// records have run (the one before it ends at rest, with the block-end flag).
#[derive(Clone, Debug, PartialEq)]
pub struct TimedEvent {
    /// Records before the event.
    pub period: u64,
    /// The event.
    pub event: IoEvent,
}

impl Element {
    /// The point at path distance `s` (0..=length).
    #[inline]
    pub fn position(&self, s: f64) -> Vec4 {
        if s >= self.length {
            return self.end;
        }
        match self.shape {
            Shape::Line { dir } => add_scaled(self.start, s, dir),
            Shape::Clothoid { d1, n1, d2, n2, half, sharpness } => {
                if s <= half {
                    let (x, y) = clothoid_xy(s, sharpness);
                    add_scaled(add_scaled(self.start, x, d1), y, n1)
                } else {
                    // The second clothoid is the first mirrored, run back from the end.
                    let (x, y) = clothoid_xy((2.0 * half - s).max(0.0), sharpness);
                    add_scaled(add_scaled(self.end, -x, d2), y, n2)
                }
            }
            Shape::Nurbs { ref curve, u0, u1 } => curve.point(parameter_at(curve, u0, u1, self.length, s)),
            Shape::Arc { centre, e1, e2, r0, r1, sweep, rise } => {
                let f = s / self.length;
                let r = r0 + f * (r1 - r0);
                let (sin, cos) = (f * sweep).sin_cos();
                let mut p = [0.0; 4];
                for a in 0..4 {
                    p[a] = centre[a] + r * (cos * e1[a] + sin * e2[a]) + f * rise[a];
                }
                p
            }
        }
    }

    /// Unit tangent at fraction 0 or 1.
    pub fn tangent(&self, at_end: bool) -> Vec4 {
        match self.shape {
            Shape::Line { dir } => dir,
            Shape::Clothoid { d1, d2, .. } => {
                if at_end {
                    d2
                } else {
                    d1
                }
            }
            Shape::Nurbs { ref curve, u0, u1 } => {
                let d = curve.derivatives_on(if at_end { u1 } else { u0 }, u0);
                let speed = d.speed();
                std::array::from_fn(|c| d.first[c] / speed)
            }
            Shape::Arc { e1, e2, r0, r1, sweep, rise, .. } => arc_end_tangent(e1, e2, r0, r1, sweep, rise, at_end).0,
        }
    }

    /// [`Element::tangent`] and [`Element::curvature`] at the same end, the shape
    /// evaluated there once for both (a NURBS sub-piece's derivatives, an arc's angle):
    /// the same values as the two apart, for the junction test every element meets
    /// ([`crate::lookahead::junction_jumps`]).
    pub fn tangent_and_curvature(&self, at_end: bool) -> (Vec4, Vec4) {
        match self.shape {
            Shape::Nurbs { ref curve, u0, u1 } => {
                let d = curve.derivatives_on(if at_end { u1 } else { u0 }, u0);
                let speed = d.speed();
                let t: Vec4 = std::array::from_fn(|c| d.first[c] / speed);
                let along: f64 = d.second.iter().zip(&t).map(|(a, b)| a * b).sum();
                (t, std::array::from_fn(|c| (d.second[c] - along * t[c]) / (speed * speed)))
            }
            Shape::Arc { e1, e2, r0, r1, sweep, rise, .. } => {
                let (t, sin, cos) = arc_end_tangent(e1, e2, r0, r1, sweep, rise, at_end);
                let (planar, r) = self.planar_fraction_and_radius();
                let k = planar * planar / r;
                (t, scale(-k, std::array::from_fn(|a: usize| cos * e1[a] + sin * e2[a])))
            }
            Shape::Line { .. } | Shape::Clothoid { .. } => (self.tangent(at_end), self.curvature(at_end)),
        }
    }

    /// Curvature vector (acceleration per unit speed squared) at fraction 0 or 1.
    pub fn curvature(&self, at_end: bool) -> Vec4 {
        match self.shape {
            Shape::Line { .. } | Shape::Clothoid { .. } => [0.0; 4],
            Shape::Nurbs { ref curve, u0, u1 } => {
                // (C'' - (C''.T) T) / |C'|^2
                let d = curve.derivatives_on(if at_end { u1 } else { u0 }, u0);
                let speed = d.speed();
                let t: Vec4 = std::array::from_fn(|c| d.first[c] / speed);
                let along: f64 = d.second.iter().zip(&t).map(|(a, b)| a * b).sum();
                std::array::from_fn(|c| (d.second[c] - along * t[c]) / (speed * speed))
            }
            Shape::Arc { e1, e2, sweep, .. } => {
                let (planar, r) = self.planar_fraction_and_radius();
                let f: f64 = if at_end { 1.0 } else { 0.0 };
                let (sin, cos) = (f * sweep).sin_cos();
                let k = planar * planar / r;
                scale(-k, std::array::from_fn(|a: usize| cos * e1[a] + sin * e2[a]))
            }
        }
    }

    /// For arcs: the share of the speed in the plane, and the smaller radius.
    pub(crate) fn planar_fraction_and_radius(&self) -> (f64, f64) {
        match self.shape {
            Shape::Line { .. } | Shape::Clothoid { .. } | Shape::Nurbs { .. } => (0.0, f64::INFINITY),
            Shape::Arc { r0, r1, sweep, .. } => {
                let planar = (r0.max(r1) * sweep.abs() / self.length).min(1.0);
                (planar, r0.min(r1))
            }
        }
    }
}

/// An arc's (helix's) unit tangent at its start or end, with the sine and cosine of the
/// angle there (the curvature's direction needs them): its derivative along the
/// parameter, `(r1 - r0) (cos e1 + sin e2) + r sweep (cos e2 - sin e1) + rise`, normed.
fn arc_end_tangent(e1: Vec4, e2: Vec4, r0: f64, r1: f64, sweep: f64, rise: Vec4, at_end: bool) -> (Vec4, f64, f64) {
    let f: f64 = if at_end { 1.0 } else { 0.0 };
    let r = r0 + f * (r1 - r0);
    let (sin, cos) = (f * sweep).sin_cos();
    let mut d = [0.0; 4];
    for a in 0..4 {
        d[a] = (r1 - r0) * (cos * e1[a] + sin * e2[a]) + r * sweep * (cos * e2[a] - sin * e1[a]) + rise[a];
    }
    let n = norm(d);
    (scale(1.0 / n, d), sin, cos)
}

/// The point at length `s` along a clothoid of curvature `sharpness * s` starting
/// straight at the origin along x, turning towards +y: `(x, y)`, the Fresnel integrals
/// `x = int_0^s cos(theta)`, `y = int_0^s sin(theta)`, `theta = sharpness sigma^2 / 2`, by
/// their power series in theta (`x = s sum (-1)^n theta^2n / ((2n)! (4n + 1))`,
/// `y = s sum (-1)^n theta^(2n+1) / ((2n+1)! (4n + 3))`), summed until a term no longer
/// changes the sums. A blend turns by less than pi, so theta stays below pi/2 on each
/// clothoid and the terms fall at once.
pub fn clothoid_xy(s: f64, sharpness: f64) -> (f64, f64) {
    let theta = 0.5 * sharpness * s * s;
    let t2 = theta * theta;
    // term_c = (-1)^n theta^2n / (2n)!, term_s = (-1)^n theta^(2n+1) / (2n+1)!
    let (mut term_c, mut term_s) = (1.0, theta);
    let (mut x, mut y) = (0.0, 0.0);
    for n in 0..40 {
        let k = n as f64;
        let (dx, dy) = (term_c / (4.0 * k + 1.0), term_s / (4.0 * k + 3.0));
        x += dx;
        y += dy;
        if dx.abs() <= 1e-17 * x.abs() && dy.abs() <= 1e-17 * y.abs().max(1e-300) {
            break;
        }
        term_c *= -t2 / ((2.0 * k + 1.0) * (2.0 * k + 2.0));
        term_s *= -t2 / ((2.0 * k + 2.0) * (2.0 * k + 3.0));
    }
    (s * x, s * y)
}

/// The inputs of [`full_caps`] an element's caps came from (X, Y, Z, A; an axis the
/// element does not move has `w` and `n` 0).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Needs {
    /// The axes as the element sees them.
    pub axes: [AxisShare; 4],
    /// Largest curvature, 1/units.
    pub k: f64,
    /// Largest |dk/ds|, 1/units^2.
    pub dk: f64,
    /// S-curve.
    pub scurve: bool,
    /// The smallest share of an axis's acceleration the normal acceleration takes
    /// ([`full_caps_turning`]: [`NORMAL_SHARE_MIN`], or [`SMOOTH_NORMAL_SHARE_MIN`] on
    /// the path smoother's curves).
    pub normal_min: f64,
    /// The share of each axis's jerk turning takes at the speed cap
    /// ([`TURNING_JERK_SHARE`], or [`SMOOTH_TURNING_JERK_SHARE`] on the smoother's curves).
    pub turning_share: f64,
}

impl Needs {
    /// The caps where the speed stays at or below `v` (below the element's cap): the
    /// normal acceleration and turning at `v` leave more of each limit to the
    /// tangential acceleration than at the element's cap. The tangential jerk is kept
    /// at least `jerk` by holding the acceleration's turning term `3 k v a_t` at or below
    /// its value at (`v_cap`, `accel`).
    pub fn caps_at(&self, v: f64, v_cap: f64, accel: f64, jerk: f64) -> Caps {
        let caps = full_caps_turning(&self.axes, v, self.k, self.dk, self.scurve, self.turning_share, self.normal_min);
        if caps.jerk >= jerk {
            return caps;
        }
        // The acceleration held to `accel * v_cap / v`, the jerk again at it.
        let accel_kept = caps.accel.min(accel * v_cap / v.max(1e-300)).max(accel);
        let mut jerk_kept = f64::INFINITY;
        for axis in self.axes.iter().filter(|a| a.w > 1e-12) {
            let turning_jerk = if self.scurve { turning_jerk(axis, self.k, self.dk, v, accel_kept) } else { 0.0 };
            jerk_kept = jerk_kept.min((FULL_SHARE * axis.jerk - turning_jerk) / axis.w);
        }
        Caps { v_cap: caps.v_cap, accel: accel_kept, jerk: jerk_kept }
    }
}

/// The speed, tangential acceleration and tangential jerk caps of an element.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Caps {
    /// Speed cap, units/s.
    pub v_cap: f64,
    /// Tangential acceleration, units/s^2.
    pub accel: f64,
    /// Tangential jerk, units/s^3.
    pub jerk: f64,
}

/// The share of every limit an element uses where the path is smooth; the rest covers
/// the jumps below [`JUMP_READING`] at its junctions.
pub const FULL_SHARE: f64 = 0.98;
/// The largest share of an axis's acceleration the normal acceleration takes.
pub const NORMAL_SHARE_MAX: f64 = 0.9;
/// The smallest share of an axis's acceleration the normal acceleration takes where the
/// curvature changes fast.
pub const NORMAL_SHARE_MIN: f64 = 0.5;
/// [`NORMAL_SHARE_MIN`] on the sub-pieces of the path smoother's curves
/// ([`crate::smooth`]): there the normal share is not lowered where the curvature
/// changes. Their sub-pieces are short (about a knot span, a millimetre or two), each
/// with one speed cap at its largest curvature, so their speed does not follow the
/// curvature's limit inside them, and the speed changes between them are planned within
/// each one's tangential acceleration (what the normal acceleration at its cap leaves),
/// as on any element. On the bench's 20 000 short segments (S-curve) the smallest
/// share 0.5, 0.7, 0.8 and 0.9 gave 1.348, 1.306, 1.285 and 1.266 times the lower bound:
/// the normal acceleration's cap bound almost everywhere (its time alone 162.5 s of the
/// 163.8 s at the caps with 0.5), with the dk rule lowering the share on 6 175 of the
/// path's 6 250 mm. On a G5.2 curve (a long sub-piece of the star) the rule stays: taken
/// away there, the trapezoid's star took 7.72 s instead of 5.48.
pub const SMOOTH_NORMAL_SHARE_MIN: f64 = NORMAL_SHARE_MAX;
/// S-curve: [`TURNING_JERK_SHARE`] on the sub-pieces of the path smoother's curves:
/// with the normal share at its largest ([`SMOOTH_NORMAL_SHARE_MIN`]) their turning,
/// `(k^2 + |k'|) v^3` at the wave's crests, caps them next (on the bench's 20 000 short
/// segments 0.25, 0.3, 0.35, 0.4, 0.45 and 0.5 gave 1.266, 1.250, 1.240, 1.235, 1.237
/// and 1.241 times the lower bound).
pub const SMOOTH_TURNING_JERK_SHARE: f64 = 0.4;
/// S-curve: the largest share of an axis's jerk spent on turning, `(k^2 + |k'|) v^3`.
pub const TURNING_JERK_SHARE: f64 = 0.25;
/// S-curve: [`TURNING_JERK_SHARE`] on a corner blend between lines
/// ([`Shape::Clothoid`]): where the segments are short its turning, `|k'| v^3`, caps the
/// speed, not the speed changes along it (on the bench's 20 000 short segments 0.4,
/// 0.5, 0.6 and 0.75 gave 1.744, 1.708, 1.716 and 1.777 times the lower bound; above
/// 0.5 the acceleration's turning term, which takes half of what turning leaves, holds
/// the speed changes back).
pub const BLEND_TURNING_JERK_SHARE: f64 = 0.5;
/// S-curve: the largest share of an axis's jerk spent on the tangential acceleration
/// turning with the path, `3 k v a_t`.
pub const TURNING_ACCEL_JERK_SHARE: f64 = 0.5;
/// A junction jumps when its tangent or curvature jump reads as more than this share of
/// an axis's acceleration (or jerk) within a period.
pub const JUMP_READING: f64 = 0.01;

/// One axis as an element sees it: its largest tangent component `w`, normal component
/// `n` (both 0 for an axis the machine does not have), and its velocity, acceleration
/// and jerk limits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AxisShare {
    /// Largest |T_a| over the element.
    pub w: f64,
    /// Largest |N_a| over the element.
    pub n: f64,
    /// Velocity limit, units/s.
    pub velocity: f64,
    /// Acceleration limit, units/s^2.
    pub accel: f64,
    /// Jerk limit, units/s^3.
    pub jerk: f64,
}

/// The most of `axis`'s jerk that turning takes at speed `v` and tangential acceleration
/// `accel` on an element of largest curvature `k` and curvature change `dk`: each
/// term of the jerk (module docs) on the component it acts along, `k^2 v^3` along the
/// tangent (`w`), `k' v^3` and `3 k v a_t` along the normal (`n`). (Until plan25 both
/// curvature terms were taken on the larger of the two components: on seed 002's star
/// the curvature change read on the axis along the path held its tangential jerk at
/// 0.72 of the limit.)
pub fn turning_jerk(axis: &AxisShare, k: f64, dk: f64, v: f64, accel: f64) -> f64 {
    (k * k * axis.w + dk * axis.n) * v.powi(3) + 3.0 * k * v * accel * axis.n
}

/// The caps of an element of largest curvature `k` and curvature change `dk` (|dk/ds|)
/// under the speed limit `v_limit` (feed, chord tolerance), the limits shared by what
/// the path needs (module docs).
pub fn full_caps(axes: &[AxisShare], v_limit: f64, k: f64, dk: f64, scurve: bool) -> Caps {
    full_caps_turning(axes, v_limit, k, dk, scurve, TURNING_JERK_SHARE, NORMAL_SHARE_MIN)
}

/// [`full_caps`] with `turning_share` of each axis's jerk for turning,
/// `(k^2 + |k'|) v^3`, instead of [`TURNING_JERK_SHARE`], and `normal_min` as the
/// smallest normal share instead of [`NORMAL_SHARE_MIN`].
pub fn full_caps_turning(
    axes: &[AxisShare],
    v_limit: f64,
    k: f64,
    dk: f64,
    scurve: bool,
    turning_share: f64,
    normal_min: f64,
) -> Caps {
    let curved = k > 1e-12;
    // The normal share: what following the curvature's speed limit leaves.
    let f = if curved { (1.0 / (1.0 + dk / (2.0 * k * k))).clamp(normal_min, NORMAL_SHARE_MAX) } else { 0.0 };
    let turning = k * k + dk;
    // Where turning takes more than TURNING_JERK_SHARE, the acceleration's turning term
    // takes half of what it leaves at most (the other half stays with the tangential jerk).
    let accel_turning_share = if turning_share > TURNING_JERK_SHARE {
        TURNING_ACCEL_JERK_SHARE.min(0.5 * (FULL_SHARE - turning_share))
    } else {
        TURNING_ACCEL_JERK_SHARE
    };
    let mut v_cap = v_limit;
    // The least over the axes of the squares and cubes of their caps from the normal
    // acceleration and from turning: the roots are monotone, so one root of each least
    // is the least of the axes' caps.
    let (mut squared, mut cubed) = (f64::INFINITY, f64::INFINITY);
    for axis in axes.iter().filter(|a| a.w.max(a.n) > 1e-12) {
        if axis.w > 1e-12 {
            v_cap = v_cap.min(axis.velocity / axis.w);
        }
        if curved && axis.n > 1e-12 {
            squared = squared.min(f * axis.accel / (k * axis.n));
        }
        if scurve && turning > 1e-12 {
            cubed = cubed.min(turning_share * axis.jerk / (turning * axis.w.max(axis.n)));
        }
    }
    v_cap = v_cap.min(squared.sqrt()).min(cubed.cbrt());
    let mut accel = f64::INFINITY;
    for axis in axes {
        if axis.w > 1e-12 {
            accel = accel.min((FULL_SHARE * axis.accel - k * v_cap * v_cap * axis.n) / axis.w);
        }
        if scurve && curved && axis.n > 1e-12 {
            accel = accel.min(accel_turning_share * axis.jerk / (3.0 * k * v_cap * axis.n));
        }
    }
    let mut jerk = f64::INFINITY;
    for axis in axes.iter().filter(|a| a.w > 1e-12) {
        // A trapezoid's jerk is unbounded by design: the jerk cap is not used there.
        let turning_jerk = if scurve { turning_jerk(axis, k, dk, v_cap, accel) } else { 0.0 };
        jerk = jerk.min((FULL_SHARE * axis.jerk - turning_jerk) / axis.w);
    }
    Caps { v_cap, accel, jerk }
}

/// Share of each axis's acceleration the planner spends on speeding up and slowing
/// down along the path; [`GEOMETRIC_ACCEL_SHARE`] goes to turning (arcs, junctions).
pub const TANGENTIAL_ACCEL_SHARE: f64 = 0.5;
/// Share of each axis's acceleration spent on turning at a jump (and inside the
/// elements beside it).
pub const GEOMETRIC_ACCEL_SHARE: f64 = 0.45;
/// Share of each axis's jerk spent on changing the acceleration along the path, on an
/// element beside a jump that is at least [`short_length`] long.
pub const TANGENTIAL_JERK_SHARE: f64 = 0.4;
/// [`TANGENTIAL_JERK_SHARE`] on an element shorter than [`short_length`] (short
/// segments): there the jumps around it cap the speed far more than the speed changes
/// along it take time, so the jerk goes to the jumps ([`jump_jerk_share`]).
pub const SHORT_TANGENTIAL_JERK_SHARE: f64 = 0.25;
/// Share of each axis's jerk spent inside arcs (rotation of the normal acceleration, and
/// the tangential acceleration turning with the path), each.
pub const ARC_JERK_SHARE: f64 = 0.15;
/// Share of each axis's jerk spent at a junction (tangent or curvature jump within a
/// period) where an element within its reach may take [`TANGENTIAL_JERK_SHARE`].
pub const JUNCTION_JERK_SHARE: f64 = 0.25;
/// Share of each axis's jerk for a jump, the tangential jerk of the elements within its
/// reach and their turning (on arcs, each at most `2 * ARC_JERK_SHARE`) together.
pub const JUMP_BUDGET_JERK_SHARE: f64 = JUNCTION_JERK_SHARE + TANGENTIAL_JERK_SHARE + 2.0 * ARC_JERK_SHARE;

/// Periods either side of a junction whose readings can include its jump: the jerk
/// reads four positions, three periods.
pub const JUMP_REACH_PERIODS: f64 = 3.0;

/// The length under which an element is short: the travel of [`JUMP_REACH_PERIODS`]
/// periods at the fastest speed any element can have (the norm of the axes' velocity
/// limits), so that every element within a jump's reach beyond an element beside it
/// has a short element for a neighbour.
pub fn short_length(config: &crate::config::Resolved) -> f64 {
    let fastest: f64 =
        config.axes.iter().filter(|a| a.present).map(|a| a.max_velocity * a.max_velocity).sum::<f64>().sqrt();
    JUMP_REACH_PERIODS * config.period_s * fastest * (1.0 + 1e-9)
}

/// The share of each axis's jerk an element of `length` takes for its tangential jerk
/// where a jump is within reach: [`SHORT_TANGENTIAL_JERK_SHARE`] under
/// [`short_length`], else [`TANGENTIAL_JERK_SHARE`].
pub fn tangential_jerk_share(length: f64, short_length: f64) -> f64 {
    if length < short_length {
        SHORT_TANGENTIAL_JERK_SHARE
    } else {
        TANGENTIAL_JERK_SHARE
    }
}

/// The share of each axis's jerk a jump may take when the elements within its reach
/// take at most `used` of it for their tangential jerk and turning together
/// ([`Element::tangential_jerk_share`] + [`Element::turning_jerk_share`]).
pub fn jump_jerk_share(used: f64) -> f64 {
    JUMP_BUDGET_JERK_SHARE - used
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Over a grid of curvatures, curvature changes and directions, the caps keep every
    /// axis's acceleration and (S-curve) jerk within FULL_SHARE of its limit at the cap,
    /// with the tangential acceleration at its cap, and leave the tangential parts room.
    #[test]
    fn full_caps_keep_every_axis_within_its_limits() {
        for scurve in [false, true] {
            for &k in &[0.0, 1e-3, 0.05, 1.0, 40.0] {
                for &dk in &[0.0, 1e-3, 0.3, 50.0] {
                    for &angle in &[0.0f64, 0.3, 0.785, 1.2] {
                        let (w, n) = (angle.cos().abs(), angle.sin().abs());
                        let axes = [
                            AxisShare { w, n, velocity: 200.0, accel: 300.0, jerk: 3000.0 },
                            AxisShare { w: n, n: w, velocity: 100.0, accel: 1000.0, jerk: 1e5 },
                        ];
                        let c = full_caps(&axes, 150.0, k, dk, scurve);
                        assert!(c.v_cap > 0.0 && c.accel > 0.0 && c.jerk > 0.0, "{c:?}");
                        for axis in &axes {
                            let v = c.v_cap;
                            assert!(v * axis.w <= axis.velocity * (1.0 + 1e-12));
                            let accel = c.accel * axis.w + k * v * v * axis.n;
                            assert!(accel <= FULL_SHARE * axis.accel * (1.0 + 1e-9), "{k} {dk} {angle}: {accel}");
                            if scurve {
                                let jerk = c.jerk * axis.w
                                    + k * k * v.powi(3) * axis.w
                                    + dk * v.powi(3) * axis.n
                                    + 3.0 * k * v * c.accel * axis.n;
                                assert!(jerk <= FULL_SHARE * axis.jerk * (1.0 + 1e-9), "{k} {dk} {angle}: {jerk}");
                            }
                        }
                    }
                }
            }
        }
    }

    /// On the smoother's curves the normal share stays at its largest where the
    /// curvature changes fast (SMOOTH_NORMAL_SHARE_MIN), elsewhere it falls to
    /// NORMAL_SHARE_MIN; both pairs of shares the planner uses (a G5.2 curve's and the
    /// smoother's) keep every axis within its limits (the grid above, again).
    #[test]
    fn the_smoothers_normal_share_stays_where_the_curvature_changes() {
        let axes = [AxisShare { w: 1.0, n: 1.0, velocity: 200.0, accel: 1000.0, jerk: 1e9 }];
        let (k, dk) = (1.0, 50.0);
        for (normal_min, share) in [(NORMAL_SHARE_MIN, NORMAL_SHARE_MIN), (SMOOTH_NORMAL_SHARE_MIN, NORMAL_SHARE_MAX)] {
            let c = full_caps_turning(&axes, 1e9, k, dk, true, TURNING_JERK_SHARE, normal_min);
            assert!((c.v_cap - (share * 1000.0 / k).sqrt()).abs() < 1e-9, "{normal_min}: {c:?}");
            assert!(c.accel * 1.0 + k * c.v_cap * c.v_cap <= FULL_SHARE * 1000.0 * (1.0 + 1e-12), "{c:?}");
        }
        for &k in &[1e-3, 0.05, 1.0, 40.0] {
            for &dk in &[0.0, 0.3, 50.0] {
                for &angle in &[0.0f64, 0.785, 1.2] {
                    let (w, n) = (angle.cos().abs(), angle.sin().abs());
                    let axes = [
                        AxisShare { w, n, velocity: 200.0, accel: 300.0, jerk: 3000.0 },
                        AxisShare { w: n, n: w, velocity: 100.0, accel: 1000.0, jerk: 1e5 },
                    ];
                    for (turning_share, normal_min) in
                        [(TURNING_JERK_SHARE, NORMAL_SHARE_MIN), (SMOOTH_TURNING_JERK_SHARE, SMOOTH_NORMAL_SHARE_MIN)]
                    {
                        let c = full_caps_turning(&axes, 150.0, k, dk, true, turning_share, normal_min);
                        assert!(c.v_cap > 0.0 && c.accel > 0.0 && c.jerk > 0.0, "{c:?}");
                        for axis in &axes {
                            let v = c.v_cap;
                            let accel = c.accel * axis.w + k * v * v * axis.n;
                            assert!(accel <= FULL_SHARE * axis.accel * (1.0 + 1e-9), "{k} {dk} {angle}: {accel}");
                            let jerk = c.jerk * axis.w
                                + k * k * v.powi(3) * axis.w
                                + dk * v.powi(3) * axis.n
                                + 3.0 * k * v * c.accel * axis.n;
                            assert!(jerk <= FULL_SHARE * axis.jerk * (1.0 + 1e-9), "{k} {dk} {angle}: {jerk}");
                        }
                    }
                }
            }
        }
    }

    /// The caps derived again at a lower speed (`Needs::caps_at`) use the shares the
    /// element's caps came from: at the element's own cap they are its caps.
    #[test]
    fn caps_derived_again_keep_the_elements_shares() {
        let none = AxisShare { w: 0.0, n: 0.0, velocity: 100.0, accel: 1000.0, jerk: 1e5 };
        let axes = [
            AxisShare { w: 0.8, n: 0.6, velocity: 100.0, accel: 1000.0, jerk: 1e5 },
            AxisShare { w: 0.6, n: 0.8, velocity: 100.0, accel: 1000.0, jerk: 1e5 },
            none,
            none,
        ];
        let (k, dk) = (1.0, 2.0);
        for (turning_share, normal_min) in
            [(TURNING_JERK_SHARE, NORMAL_SHARE_MIN), (SMOOTH_TURNING_JERK_SHARE, SMOOTH_NORMAL_SHARE_MIN)]
        {
            let caps = full_caps_turning(&axes, 50.0, k, dk, true, turning_share, normal_min);
            let needs = Needs { axes, k, dk, scurve: true, normal_min, turning_share };
            let again = needs.caps_at(caps.v_cap, caps.v_cap, caps.accel, caps.jerk);
            assert_eq!(again, caps, "{turning_share} {normal_min}");
        }
        let smooth = full_caps_turning(&axes, 50.0, k, dk, true, SMOOTH_TURNING_JERK_SHARE, SMOOTH_NORMAL_SHARE_MIN);
        let nurbs = full_caps_turning(&axes, 50.0, k, dk, true, TURNING_JERK_SHARE, NORMAL_SHARE_MIN);
        assert!(smooth.v_cap > nurbs.v_cap, "{smooth:?} {nurbs:?}");
    }

    /// A line takes FULL_SHARE of the limits along it, a constant curvature
    /// NORMAL_SHARE_MAX of the acceleration for turning.
    #[test]
    fn a_line_takes_the_full_limits_and_an_arc_the_normal_share() {
        let axes = [AxisShare { w: 1.0, n: 0.0, velocity: 200.0, accel: 300.0, jerk: 3000.0 }];
        let line = full_caps(&axes, 1e9, 0.0, 0.0, true);
        assert_eq!((line.v_cap, line.accel, line.jerk), (200.0, FULL_SHARE * 300.0, FULL_SHARE * 3000.0));
        let axes = [AxisShare { w: 1.0, n: 1.0, velocity: 200.0, accel: 300.0, jerk: 3000.0 }];
        let arc = full_caps(&axes, 1e9, 0.1, 0.0, false);
        assert!((arc.v_cap - (NORMAL_SHARE_MAX * 300.0 / 0.1f64).sqrt()).abs() < 1e-9, "{arc:?}");
        assert!((arc.accel - (FULL_SHARE - NORMAL_SHARE_MAX) * 300.0).abs() < 1e-9, "{arc:?}");
    }
}

//! One element of the planned path (a line, an arc or a NURBS sub-piece) with its
//! speed, acceleration and jerk caps, and the shares of each axis's limits the planner
//! gives to the motion along the path and to turning.

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
    /// Speed cap along the element, units/s: feed, per-axis speeds, arc limits.
    pub v_cap: f64,
    /// Tangential acceleration limit, units/s^2.
    pub accel: f64,
    /// Tangential jerk limit, units/s^3.
    pub jerk: f64,
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

/// A spindle or coolant change the program makes at a point of the path (S, M3/M4/M5,
/// M7/M8/M9), applied at an exact stop.
#[derive(Clone, Copy, Debug, PartialEq)]
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
    /// The coolant after the block.
    Coolant {
        /// M7.
        mist: bool,
        /// M8.
        flood: bool,
    },
}

/// An [`IoAction`] and the source line that wrote it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IoEvent {
    /// 1-based source line.
    pub line: usize,
    /// What changes.
    pub action: IoAction,
}

/// An [`IoEvent`] placed in the record stream: it takes effect once the first `period`
/// records have run (the one before it ends at rest, with the block-end flag).
#[derive(Clone, Copy, Debug, PartialEq)]
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
            Shape::Nurbs { ref curve, u0, u1 } => {
                let d = curve.derivatives_on(if at_end { u1 } else { u0 }, u0);
                let speed = d.speed();
                [d.first[0] / speed, d.first[1] / speed, 0.0, 0.0]
            }
            Shape::Arc { e1, e2, r0, r1, sweep, rise, .. } => {
                let f: f64 = if at_end { 1.0 } else { 0.0 };
                let r = r0 + f * (r1 - r0);
                let (sin, cos) = (f * sweep).sin_cos();
                let mut d = [0.0; 4];
                for a in 0..4 {
                    d[a] = (r1 - r0) * (cos * e1[a] + sin * e2[a]) + r * sweep * (cos * e2[a] - sin * e1[a]) + rise[a];
                }
                let n = norm(d);
                scale(1.0 / n, d)
            }
        }
    }

    /// Curvature vector (acceleration per unit speed squared) at fraction 0 or 1.
    pub fn curvature(&self, at_end: bool) -> Vec4 {
        match self.shape {
            Shape::Line { .. } => [0.0; 4],
            Shape::Nurbs { ref curve, u0, u1 } => {
                // (C'' - (C''.T) T) / |C'|^2
                let d = curve.derivatives_on(if at_end { u1 } else { u0 }, u0);
                let speed = d.speed();
                let t = [d.first[0] / speed, d.first[1] / speed];
                let along = d.second[0] * t[0] + d.second[1] * t[1];
                let k = [0, 1].map(|c| (d.second[c] - along * t[c]) / (speed * speed));
                [k[0], k[1], 0.0, 0.0]
            }
            Shape::Arc { e1, e2, sweep, .. } => {
                let (planar, r) = self.planar_fraction_and_radius();
                let f: f64 = if at_end { 1.0 } else { 0.0 };
                let (sin, cos) = (f * sweep).sin_cos();
                let k = planar * planar / r;
                scale(-k, [0, 1, 2, 3].map(|a| cos * e1[a] + sin * e2[a]))
            }
        }
    }

    /// For arcs: the share of the speed in the plane, and the smaller radius.
    pub(crate) fn planar_fraction_and_radius(&self) -> (f64, f64) {
        match self.shape {
            Shape::Line { .. } | Shape::Nurbs { .. } => (0.0, f64::INFINITY),
            Shape::Arc { r0, r1, sweep, .. } => {
                let planar = (r0.max(r1) * sweep.abs() / self.length).min(1.0);
                (planar, r0.min(r1))
            }
        }
    }
}

/// Share of each axis's acceleration the planner spends on speeding up and slowing
/// down along the path; [`GEOMETRIC_ACCEL_SHARE`] goes to turning (arcs, junctions).
pub const TANGENTIAL_ACCEL_SHARE: f64 = 0.5;
/// Share of each axis's acceleration spent on turning.
pub const GEOMETRIC_ACCEL_SHARE: f64 = 0.45;
/// Share of each axis's jerk spent on changing the acceleration along the path.
pub const TANGENTIAL_JERK_SHARE: f64 = 0.4;
/// Share of each axis's jerk spent inside arcs (rotation of the normal acceleration, and
/// the tangential acceleration turning with the path), each.
pub const ARC_JERK_SHARE: f64 = 0.15;
/// Share of each axis's jerk spent at a junction (tangent or curvature jump within a period).
pub const JUNCTION_JERK_SHARE: f64 = 0.25;

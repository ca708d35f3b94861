//! G96, constant surface speed: the spindle's speed for a move. LinuxCNC's motion
//! controller sets the speed every servo period from the distance r of the tool from the
//! spindle's axis along X (`S / (2 pi r)`, at most D). finestep sets the spindle at rest
//! between moves ([`crate::element::IoAction::Spindle`] at an exact stop), so a move
//! runs at one speed: the one at its point farthest from the axis, so that the surface
//! speed reaches S there and stays below it everywhere else on the move (never above
//! it, as one fixed speed must err on the side of the tool). The speed changes only
//! where a move's farthest point differs from the last move's: a turning pass along Z
//! keeps one speed and its blends; a facing move ends at a stop and the next runs faster.

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use finestep_gcode::SurfaceSpeed;

/// An arc's span in the X-bearing plane: its centre's X, its radius, the angle of its
/// start and the signed angle it sweeps (radians; positive counter-clockwise), with the
/// angle measured from the plane's first axis toward its second, and whether X is the
/// plane's first axis (G17) or second (G18).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct ArcSpan {
    /// The centre's X, mm.
    pub centre_x: f64,
    /// mm.
    pub radius: f64,
    /// Radians.
    pub start: f64,
    /// Radians, signed.
    pub sweep: f64,
    /// X is the plane's first axis (G17: X Y); else its second (G18: Z X).
    pub x_first: bool,
}

impl ArcSpan {
    /// The X values of the arc's extremes in X that it passes.
    fn x_extremes(&self) -> impl Iterator<Item = f64> + '_ {
        // X is centre + r cos(theta) (first axis) or centre + r sin(theta) (second).
        let (high, low) = if self.x_first { (0.0, PI) } else { (FRAC_PI_2, 3.0 * FRAC_PI_2) };
        [(high, self.radius), (low, -self.radius)].into_iter().filter_map(move |(angle, offset)| {
            let along = if self.sweep >= 0.0 {
                (angle - self.start).rem_euclid(TAU)
            } else {
                (self.start - angle).rem_euclid(TAU)
            };
            (along <= self.sweep.abs()).then_some(self.centre_x + offset)
        })
    }
}

/// The speed of a move under `css` on a spindle of at most `max_rpm`: the speed at the
/// move's X farthest from the axis (`from_x`, `to_x`, the X extremes of `arc`, the
/// control points' X of a NURBS, whose curve lies within their hull), at most
/// `max_rpm` (the spindle's top speed is a D the machine sets).
pub(crate) fn move_rpm(
    css: &SurfaceSpeed,
    max_rpm: f64,
    from_x: f64,
    to_x: f64,
    arc: Option<&ArcSpan>,
    control_x: &[f64],
) -> f64 {
    let far = [from_x, to_x]
        .into_iter()
        .chain(arc.into_iter().flat_map(ArcSpan::x_extremes))
        .chain(control_x.iter().copied())
        .fold(from_x, |far, x| if (x - css.axis_x_mm).abs() > (far - css.axis_x_mm).abs() { x } else { far });
    css.rpm_at(far).min(max_rpm)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn css(max: Option<f64>) -> SurfaceSpeed {
        // 100 m/min about X = 5.
        SurfaceSpeed { mm_per_min: 100_000.0, max_rpm: max, axis_x_mm: 5.0 }
    }

    #[test]
    fn a_line_runs_at_the_speed_of_its_end_farthest_from_the_axis() {
        // From r = 20 to r = 10: 100 000 / (2 pi 20) = 795.77 rev/min.
        let rpm = move_rpm(&css(None), 24_000.0, 25.0, 15.0, None, &[]);
        assert!((rpm - 100_000.0 / (TAU * 20.0)).abs() < 1e-9, "{rpm}");
        // Across the axis: r = 3 on the far side counts (|-2 - 5| = 7 > 3).
        let rpm = move_rpm(&css(None), 24_000.0, 8.0, -2.0, None, &[]);
        assert!((rpm - 100_000.0 / (TAU * 7.0)).abs() < 1e-9, "{rpm}");
    }

    #[test]
    fn d_and_the_spindles_top_speed_cap_it_and_the_axis_itself_runs_at_d() {
        assert_eq!(move_rpm(&css(Some(500.0)), 24_000.0, 6.0, 5.5, None, &[]), 500.0);
        assert_eq!(move_rpm(&css(Some(500.0)), 24_000.0, 5.0, 5.0, None, &[]), 500.0);
        assert_eq!(move_rpm(&css(None), 3_000.0, 5.0, 5.0, None, &[]), 3_000.0);
    }

    #[test]
    fn an_arc_counts_the_x_extremes_it_passes() {
        // G18 (Z X): centre X 15, radius 5, X is the second axis; from the top of X
        // (theta pi/2, X 20) clockwise a quarter to theta 0 (X 15): the far point is
        // X 20 at the start.
        let quarter = ArcSpan { centre_x: 15.0, radius: 5.0, start: FRAC_PI_2, sweep: -FRAC_PI_2, x_first: false };
        let rpm = move_rpm(&css(None), 24_000.0, 20.0, 15.0, Some(&quarter), &[]);
        assert!((rpm - 100_000.0 / (TAU * 15.0)).abs() < 1e-9);
        // From theta 0 counter-clockwise a half turn passes X 20 (theta pi/2) between its
        // ends at X 15.
        let half = ArcSpan { centre_x: 15.0, radius: 5.0, start: 0.0, sweep: PI, x_first: false };
        let rpm = move_rpm(&css(None), 24_000.0, 15.0, 15.0, Some(&half), &[]);
        assert!((rpm - 100_000.0 / (TAU * 15.0)).abs() < 1e-9, "{rpm}");
        // Clockwise from 0 a half turn passes X 10 (theta 3 pi / 2), nearer the axis:
        // the ends (r = 10) are the farthest.
        let other = ArcSpan { sweep: -PI, ..half };
        let rpm = move_rpm(&css(None), 24_000.0, 15.0, 15.0, Some(&other), &[]);
        assert!((rpm - 100_000.0 / (TAU * 10.0)).abs() < 1e-9, "{rpm}");
        // G17: X first; a full turn passes both extremes.
        let full = ArcSpan { centre_x: 15.0, radius: 5.0, start: 1.0, sweep: TAU, x_first: true };
        let rpm = move_rpm(&css(None), 24_000.0, 15.0, 15.0, Some(&full), &[]);
        assert!((rpm - 100_000.0 / (TAU * 15.0)).abs() < 1e-9, "{rpm}");
    }

    #[test]
    fn a_nurbs_counts_its_control_points() {
        let rpm = move_rpm(&css(None), 24_000.0, 10.0, 10.0, None, &[10.0, 45.0, 10.0]);
        assert!((rpm - 100_000.0 / (TAU * 40.0)).abs() < 1e-9, "{rpm}");
    }
}

//! Speed along one element: an acceleration half, a cruise and a deceleration half,
//! each half planned on its own (seed 002). A trapezoid half changes speed at constant
//! acceleration; an S-curve half raises the acceleration at constant jerk, holds it,
//! and lowers it again, so the acceleration is zero at both ends of every half (and so
//! at every junction) and the jerk is bounded everywhere.
//!
//! For a half from v_a to v_b (dv = |v_b - v_a|) with limits a and j, the S-curve takes
//! `t = dv/a + a/j` when `dv >= a^2/j` (the acceleration reaches a) and `t = 2 sqrt(dv/j)`
//! otherwise; its speed is point-symmetric about the middle, so it covers
//! `(v_a + v_b)/2 * t`. The trapezoid takes `t = dv/a`.

use crate::config::ProfileKind;

/// Limits for one element's profile.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Limits {
    /// Profile kind.
    pub kind: ProfileKind,
    /// Tangential acceleration, units/s^2.
    pub accel: f64,
    /// Tangential jerk, units/s^3 (S-curve).
    pub jerk: f64,
}

impl Limits {
    /// Time for a speed change of `dv >= 0`.
    #[inline]
    pub fn change_time(&self, dv: f64) -> f64 {
        match self.kind {
            ProfileKind::Trapezoid => dv / self.accel,
            ProfileKind::SCurve => {
                let a2j = self.accel * self.accel / self.jerk;
                if dv >= a2j {
                    dv / self.accel + self.accel / self.jerk
                } else {
                    2.0 * (dv / self.jerk).sqrt()
                }
            }
        }
    }

    /// Least distance for a speed change between `v0` and `v1`.
    #[inline]
    pub fn change_distance(&self, v0: f64, v1: f64) -> f64 {
        0.5 * (v0 + v1) * self.change_time((v1 - v0).abs())
    }

    /// The largest speed reachable from `v` (either way in time) within `length`.
    pub fn reachable(&self, v: f64, length: f64) -> f64 {
        match self.kind {
            ProfileKind::Trapezoid => (v * v + 2.0 * self.accel * length).sqrt(),
            ProfileKind::SCurve => {
                let (a, j) = (self.accel, self.jerk);
                let a2j = a * a / j;
                // Long change: (x + v)(x - v)/a + (x + v) a/j = 2L, a quadratic in x.
                let disc = a2j * a2j - 4.0 * (v * a2j - v * v - 2.0 * length * a);
                let x = 0.5 * (-a2j + disc.max(0.0).sqrt());
                if x - v >= a2j {
                    return x;
                }
                // Short change: (2v + y) sqrt(y/j) = L for y = x - v < a^2/j. With
                // z = sqrt(y/j): j z^3 + 2 v z - L = 0, increasing and convex for z > 0, so
                // Newton from an upper bound converges from above.
                let mut z = (length / j).cbrt().min(if v > 0.0 { length / (2.0 * v) } else { f64::INFINITY });
                for _ in 0..60 {
                    let step = (j * z * z * z + 2.0 * v * z - length) / (3.0 * j * z * z + 2.0 * v);
                    if step.is_nan() || step <= 1e-15 * z {
                        break;
                    }
                    z -= step;
                }
                v + (j * z * z).min(a2j)
            }
        }
    }
}

/// One half: a monotone speed change.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
struct Half {
    v_from: f64,
    /// +1 speeding up, -1 slowing down.
    sign: f64,
    /// Jerk phase length (S-curve), s.
    t_jerk: f64,
    /// Constant-acceleration phase length, s.
    t_accel: f64,
    /// Acceleration magnitude reached.
    a_peak: f64,
    jerk: f64,
    time: f64,
    distance: f64,
}

impl Half {
    fn new(limits: &Limits, v_from: f64, v_to: f64) -> Half {
        let dv = (v_to - v_from).abs();
        let sign = if v_to >= v_from { 1.0 } else { -1.0 };
        let time = limits.change_time(dv);
        let distance = 0.5 * (v_from + v_to) * time;
        match limits.kind {
            ProfileKind::Trapezoid => {
                Half { v_from, sign, t_jerk: 0.0, t_accel: time, a_peak: limits.accel, jerk: 0.0, time, distance }
            }
            ProfileKind::SCurve => {
                let a2j = limits.accel * limits.accel / limits.jerk;
                let (t_jerk, t_accel, a_peak) = if dv >= a2j {
                    (limits.accel / limits.jerk, dv / limits.accel - limits.accel / limits.jerk, limits.accel)
                } else {
                    let t = (dv / limits.jerk).sqrt();
                    (t, 0.0, limits.jerk * t)
                };
                Half { v_from, sign, t_jerk, t_accel, a_peak, jerk: limits.jerk, time, distance }
            }
        }
    }

    /// Distance covered `t` (0..=time) into the half.
    #[inline]
    fn distance_at(&self, t: f64) -> f64 {
        let (s, v0, tj, ta, ap, j) = (self.sign, self.v_from, self.t_jerk, self.t_accel, self.a_peak, self.jerk);
        if t <= tj {
            return v0 * t + s * j * t * t * t / 6.0;
        }
        let d1 = v0 * tj + s * j * tj * tj * tj / 6.0;
        let v1 = v0 + s * 0.5 * j * tj * tj;
        let t2 = t - tj;
        if t2 <= ta {
            return d1 + v1 * t2 + s * 0.5 * ap * t2 * t2;
        }
        let d2 = d1 + v1 * ta + s * 0.5 * ap * ta * ta;
        let v2 = v1 + s * ap * ta;
        let t3 = (t2 - ta).min(tj);
        d2 + v2 * t3 + s * (0.5 * ap * t3 * t3 - j * t3 * t3 * t3 / 6.0)
    }
}

/// The speed profile of one element: accelerate, cruise, decelerate.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Profile {
    up: Half,
    cruise_speed: f64,
    cruise_time: f64,
    down: Half,
    length: f64,
    /// Duration, s.
    pub duration: f64,
}

impl Profile {
    /// The fastest profile over `length` from `v0` to `v1` under `cap`. The junction
    /// speeds must be feasible (the look-ahead passes make them so); small shortfalls
    /// from rounding are absorbed by lowering the peak.
    pub fn new(limits: &Limits, length: f64, v0: f64, v1: f64, cap: f64) -> Profile {
        let floor = v0.max(v1);
        let fits = |vp: f64| limits.change_distance(v0, vp) + limits.change_distance(vp, v1) <= length;
        let peak = if fits(cap.max(floor)) {
            cap.max(floor)
        } else {
            match limits.kind {
                ProfileKind::Trapezoid => {
                    // v_p^2 = a L + (v0^2 + v1^2)/2
                    (limits.accel * length + 0.5 * (v0 * v0 + v1 * v1)).sqrt().clamp(floor, cap.max(floor))
                }
                ProfileKind::SCurve => {
                    // Regula falsi (Illinois) on the covered distance, which rises with the
                    // peak; `lo` always fits.
                    let total = |vp: f64| limits.change_distance(v0, vp) + limits.change_distance(vp, v1);
                    let (mut lo, mut hi) = (floor, cap.min(limits.reachable(v0.min(v1), length)).max(floor));
                    let (mut g_lo, mut g_hi) = (total(lo) - length, total(hi) - length);
                    if g_hi <= 0.0 {
                        lo = hi;
                    }
                    let mut side = 0;
                    for _ in 0..100 {
                        if g_hi <= 0.0 || hi - lo <= 1e-9 * hi {
                            break;
                        }
                        let mid = (lo * g_hi - hi * g_lo) / (g_hi - g_lo);
                        let mid = if mid > lo && mid < hi { mid } else { 0.5 * (lo + hi) };
                        let g = total(mid) - length;
                        if g <= 0.0 {
                            lo = mid;
                            g_lo = g;
                            if side == -1 {
                                g_hi *= 0.5;
                            }
                            side = -1;
                        } else {
                            hi = mid;
                            g_hi = g;
                            if side == 1 {
                                g_lo *= 0.5;
                            }
                            side = 1;
                        }
                    }
                    lo
                }
            }
        };
        let up = Half::new(limits, v0, peak);
        let down = Half::new(limits, peak, v1);
        let rest = (length - up.distance - down.distance).max(0.0);
        let cruise_time = if peak > 0.0 { rest / peak } else { 0.0 };
        let duration = up.time + cruise_time + down.time;
        Profile { up, cruise_speed: peak, cruise_time, down, length, duration }
    }

    /// Distance along the element `t` seconds after its start (clamped to the length).
    #[inline]
    pub fn distance_at(&self, t: f64) -> f64 {
        let s = if t <= self.up.time {
            self.up.distance_at(t)
        } else if t <= self.up.time + self.cruise_time {
            self.up.distance + self.cruise_speed * (t - self.up.time)
        } else {
            let into = (t - self.up.time - self.cruise_time).min(self.down.time);
            self.up.distance + self.cruise_speed * self.cruise_time + self.down.distance_at(into)
        };
        s.clamp(0.0, self.length)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn limits(kind: ProfileKind) -> Limits {
        Limits { kind, accel: 500.0, jerk: 20_000.0 }
    }

    #[test]
    fn reachable_inverts_the_change_distance() {
        for kind in [ProfileKind::Trapezoid, ProfileKind::SCurve] {
            let l = limits(kind);
            for &v in &[0.0, 0.3, 5.0, 40.0] {
                for &length in &[1e-4, 0.01, 0.3, 7.0, 100.0] {
                    let x = l.reachable(v, length);
                    let d = l.change_distance(v, x);
                    assert!(
                        (d - length).abs() <= 1e-9 * length.max(1.0) + 1e-9,
                        "{kind:?} v {v} L {length}: {x} covers {d}"
                    );
                }
            }
        }
    }

    #[test]
    fn profiles_cover_the_length_with_bounded_derivatives() {
        for kind in [ProfileKind::Trapezoid, ProfileKind::SCurve] {
            let l = limits(kind);
            for &(length, v0, v1, cap) in &[
                (10.0f64, 0.0f64, 0.0f64, 50.0f64),
                (0.5, 3.0, 1.0, 50.0),
                (100.0, 20.0, 0.0, 60.0),
                (1.0, 0.0, 30.0, 40.0),
            ] {
                let v1 = v1.min(l.reachable(v0, length));
                let p = Profile::new(&l, length, v0, v1, cap);
                assert!((p.distance_at(p.duration) - length).abs() < 1e-9);
                let dt = 1e-4;
                let n = (p.duration / dt).floor() as usize;
                let s: Vec<f64> = (0..=n).map(|i| p.distance_at(i as f64 * dt)).collect();
                for w in s.windows(3) {
                    let v = (w[1] - w[0]) / dt;
                    assert!(v <= cap.max(v0).max(v1) + 1e-6, "{kind:?}: speed {v}");
                    let a = (w[2] - 2.0 * w[1] + w[0]) / dt / dt;
                    assert!(a.abs() <= l.accel * (1.0 + 1e-6) + 1e-3, "{kind:?}: accel {a}");
                }
            }
        }
    }
}

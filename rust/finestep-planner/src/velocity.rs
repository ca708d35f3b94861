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
//!
//! A run of elements whose junction speeds rise (or fall) all the way may instead be
//! planned as one speed change over their whole length ([`run_profiles`]; the
//! interpolation does so on NURBS sub-pieces in S-curve mode), so that the
//! acceleration is carried across the junctions inside the run.

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

    /// Speed `t` (0..=time) into the half.
    fn speed_at(&self, t: f64) -> f64 {
        let (s, v0, tj, ta, ap, j) = (self.sign, self.v_from, self.t_jerk, self.t_accel, self.a_peak, self.jerk);
        if t <= tj {
            return v0 + s * 0.5 * j * t * t;
        }
        let v1 = v0 + s * 0.5 * j * tj * tj;
        let t2 = t - tj;
        if t2 <= ta {
            return v1 + s * ap * t2;
        }
        let v2 = v1 + s * ap * ta;
        let t3 = (t2 - ta).min(tj);
        v2 + s * (ap * t3 - 0.5 * j * t3 * t3)
    }

    /// The time into the half at which its speed passes `v` (between its ends), from
    /// the speed's closed form phase by phase ([`Half::speed_at`]): the square root of
    /// the first jerk phase, the line of the constant acceleration, the quadratic of the
    /// last jerk phase (in the form without cancellation).
    fn time_to_speed(&self, v: f64) -> f64 {
        let target = (self.sign * (v - self.v_from)).max(0.0);
        let (tj, ta, ap, j) = (self.t_jerk, self.t_accel, self.a_peak, self.jerk);
        let gain_jerk = 0.5 * j * tj * tj;
        if target <= gain_jerk {
            return if j > 0.0 { (2.0 * target / j).sqrt().min(tj) } else { 0.0 };
        }
        let gain_accel = ap * ta;
        if target <= gain_jerk + gain_accel {
            return tj + ((target - gain_jerk) / ap).min(ta);
        }
        // ap t - j t^2 / 2 = r for t in 0..=tj: t = 2 r / (ap + sqrt(ap^2 - 2 j r)).
        let r = target - gain_jerk - gain_accel;
        let root = (ap * ap - 2.0 * j * r).max(0.0).sqrt();
        let t3 = if ap + root > 0.0 { 2.0 * r / (ap + root) } else { tj };
        (tj + ta + t3.min(tj)).min(self.time)
    }

    /// The distance into the half at which its speed passes `v` (between its ends).
    fn distance_to_speed(&self, v: f64) -> f64 {
        self.distance_at(self.time_to_speed(v))
    }

    /// The time into the half at which it has covered `d` (clamped to the half): Newton
    /// on the distance (its derivative the speed) inside a bracket that bisection
    /// narrows wherever a Newton step leaves it.
    fn time_at_distance(&self, d: f64) -> f64 {
        if d <= 0.0 {
            return 0.0;
        }
        if d >= self.distance {
            return self.time;
        }
        invert_rising(
            |t| self.distance_at(t),
            |t| self.speed_at(t),
            d,
            (0.0, self.time),
            self.time * d / self.distance,
            (1e-13 * self.distance, 1e-15 * self.time),
        )
    }

    /// The largest acceleration magnitude the half has between `t1` and `t2` (its
    /// acceleration rises, holds and falls), and its jerk where it changes the
    /// acceleration anywhere between them (else 0).
    fn most_between(&self, t1: f64, t2: f64) -> (f64, f64) {
        let (tj, ta, ap) = (self.t_jerk, self.t_accel, self.a_peak);
        let accel_at = |t: f64| {
            if t <= tj {
                if tj > 0.0 {
                    ap * t / tj
                } else {
                    ap
                }
            } else if t <= tj + ta {
                ap
            } else if tj > 0.0 {
                (ap * (1.0 - (t - tj - ta) / tj)).max(0.0)
            } else {
                0.0
            }
        };
        let accel = if t1 <= tj + ta && t2 >= tj { ap } else { accel_at(t1).max(accel_at(t2)) };
        let jerk = if tj > 0.0 && t2 > t1 && (t1 < tj || t2 > tj + ta) { self.jerk } else { 0.0 };
        (accel, jerk)
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

/// The speed profile of one element: accelerate, cruise, decelerate; or the part of a
/// run's profile ([`run_profiles`]) on one of its elements: a cruise before the
/// acceleration and one after the deceleration, read from `t0` and `s0` on.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Profile {
    /// Cruise at `up.v_from` before the acceleration (a run's), s.
    pre_time: f64,
    up: Half,
    cruise_speed: f64,
    cruise_time: f64,
    down: Half,
    /// Cruise at `end_speed` after the deceleration (a run's), s.
    post_time: f64,
    end_speed: f64,
    /// Where this element's part of a run's profile starts: time and distance into it.
    t0: f64,
    s0: f64,
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
        Profile { up, cruise_speed: peak, cruise_time, down, end_speed: v1, length, duration, ..Profile::default() }
    }

    /// The highest speed of the profile (an element's own).
    pub fn peak(&self) -> f64 {
        self.cruise_speed.max(self.up.v_from).max(self.end_speed)
    }

    /// Whether the profile's speed changes fit in its length (an element's own profile
    /// reaches its end speed within the element).
    pub fn covers(&self) -> bool {
        self.up.distance + self.down.distance <= self.length * (1.0 + 1e-9)
    }

    /// Distance along the element `t` seconds after its start (clamped to the length).
    #[inline]
    pub fn distance_at(&self, t: f64) -> f64 {
        (self.raw_distance_at(t + self.t0) - self.s0).clamp(0.0, self.length)
    }

    /// Distance along the whole profile (a run's, from its start) `t` seconds into it.
    #[inline]
    fn raw_distance_at(&self, t: f64) -> f64 {
        let pre = self.up.v_from * self.pre_time;
        if t <= self.pre_time {
            return self.up.v_from * t;
        }
        let t = t - self.pre_time;
        if t <= self.up.time {
            pre + self.up.distance_at(t)
        } else if t <= self.up.time + self.cruise_time {
            pre + self.up.distance + self.cruise_speed * (t - self.up.time)
        } else {
            let into = t - self.up.time - self.cruise_time;
            let before = pre + self.up.distance + self.cruise_speed * self.cruise_time;
            if into <= self.down.time {
                before + self.down.distance_at(into)
            } else {
                before + self.down.distance + self.end_speed * (into - self.down.time).min(self.post_time)
            }
        }
    }

    /// Speed along the whole profile (a run's, from its start) `t` seconds into it.
    #[inline]
    fn raw_speed_at(&self, t: f64) -> f64 {
        if t <= self.pre_time {
            return self.up.v_from;
        }
        let t = t - self.pre_time;
        if t <= self.up.time {
            self.up.speed_at(t)
        } else if t <= self.up.time + self.cruise_time {
            self.cruise_speed
        } else {
            let into = t - self.up.time - self.cruise_time;
            if into <= self.down.time {
                self.down.speed_at(into)
            } else {
                self.end_speed
            }
        }
    }

    /// The time into the whole profile at which it has covered `s`, at or after `from`
    /// (where it has covered at most `s`): Newton on the distance (its derivative the
    /// speed) from `from`, inside a bracket that bisection narrows wherever a Newton
    /// step leaves it (the distance rises with time).
    fn raw_time_at(&self, s: f64, from: f64, total: f64) -> f64 {
        let lo = from.clamp(0.0, total);
        invert_rising(
            |t| self.raw_distance_at(t),
            |t| self.raw_speed_at(t),
            s,
            (lo, total),
            lo,
            (1e-15 * s.abs().max(1e-300), 1e-15 * total),
        )
    }
}

/// The time at which a rising `distance` (its derivative `speed`) reaches `target`:
/// Newton from `start` inside the bracket `(lo, hi)`, which bisection narrows wherever a
/// Newton step would leave it; stops once the distance is within `tolerance.0` of the
/// target or the bracket is narrower than `tolerance.1` (100 iterations at most).
fn invert_rising(
    distance: impl Fn(f64) -> f64,
    speed: impl Fn(f64) -> f64,
    target: f64,
    (mut lo, mut hi): (f64, f64),
    start: f64,
    tolerance: (f64, f64),
) -> f64 {
    let mut t = start;
    for _ in 0..100 {
        let err = distance(t) - target;
        if err < 0.0 {
            lo = t;
        } else {
            hi = t;
        }
        if err.abs() <= tolerance.0 || hi - lo <= tolerance.1 {
            break;
        }
        let v = speed(t);
        let step = t - err / v;
        t = if v > 0.0 && step > lo && step < hi { step } else { 0.5 * (lo + hi) };
    }
    t
}

/// One element of a run for [`run_profiles`]: its length, profile limits and speed cap.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RunElement {
    /// Path length, units.
    pub length: f64,
    /// Its tangential acceleration and jerk limits.
    pub limits: Limits,
    /// Its speed cap, units/s.
    pub cap: f64,
}

/// The most elements a run planned as one profile spans ([`run_profiles`]).
pub const MAX_RUN_ELEMENTS: usize = 64;

/// A run of elements whose junction speeds `speeds` (one more than `elements`) rise
/// (or fall) all the way, planned as one speed change instead of one per element, so
/// that the acceleration is carried across the junctions inside the run instead of
/// returning to zero at each: a cruise at the first speed, one half from the first to
/// the last speed, and a cruise at the last speed. The half is planned first under the
/// smallest acceleration and jerk limits of the run's elements, then under wider ones
/// where every element it overlaps allows the acceleration and jerk the half has within
/// it (with [`run_profiles_into`]'s `limits_at`, at the highest speed it has there;
/// until plan27 under the least limits of the elements it overlaps, each taken at the
/// run's higher end: on seed 002's star a long sub-piece the half entered at the top
/// speed in its jerk phase held the whole deceleration into a tip to 0.945 of the
/// axis's limit, 0.973 since). The half is placed as early (rising) or as
/// late (falling) as every element's speed cap allows (the speed is monotone, so it is
/// checked at the end of each element where it rises and at its start where it
/// falls). The run starts and ends at its junction speeds with zero acceleration, as
/// the per-element profiles do, so everything outside it is unchanged and its limits
/// hold inside: every element's speed cap, and the acceleration and jerk within each
/// element's. Each element's part as a [`Profile`]; `None` where the run is not
/// monotone, the half does not fit, a cap cannot be kept, or the run would not be
/// faster than the per-element profiles.
pub fn run_profiles(elements: &[RunElement], speeds: &[f64]) -> Option<Vec<Profile>> {
    let mut out = Vec::with_capacity(elements.len());
    run_profiles_into(elements, speeds, &mut out, &|_, _| None).then_some(out)
}

/// [`run_profiles`] into `out` (cleared first; its room kept from run to run), with
/// `limits_at(k, v)`: element k's limits where its speed stays at or below `v` (below
/// its cap), where they can be derived for that speed: the half is held in each element
/// to its limits at the highest speed it has there. Whether the run was planned.
pub fn run_profiles_into(
    elements: &[RunElement],
    speeds: &[f64],
    out: &mut Vec<Profile>,
    limits_at: &dyn Fn(usize, f64) -> Option<Limits>,
) -> bool {
    out.clear();
    run_profiles_in(elements, speeds, out, limits_at).is_some()
}

fn run_profiles_in(
    elements: &[RunElement],
    speeds: &[f64],
    out: &mut Vec<Profile>,
    limits_at: &dyn Fn(usize, f64) -> Option<Limits>,
) -> Option<()> {
    let n = elements.len();
    if n < 2 || speeds.len() != n + 1 {
        return None;
    }
    let (v_a, v_b) = (speeds[0], speeds[n]);
    let rising = v_b > v_a;
    if v_a == v_b || speeds.windows(2).any(|w| (w[1] > w[0]) != rising || w[1] == w[0]) {
        return None;
    }
    let kind = elements[0].limits.kind;
    let limits = Limits {
        kind,
        accel: elements.iter().map(|e| e.limits.accel).fold(f64::INFINITY, f64::min),
        jerk: elements.iter().map(|e| e.limits.jerk).fold(f64::INFINITY, f64::min),
    };
    if !(limits.accel > 0.0 && limits.jerk > 0.0) || elements.iter().any(|e| e.limits.kind != kind) {
        return None;
    }
    let length: f64 = elements.iter().map(|e| e.length).sum();
    let (mut limits, (mut half, mut spare, mut x)) = (limits, place_half(elements, &limits, v_a, v_b, length)?);
    // The acceleration and jerk are zero outside the half: only the elements it overlaps
    // need hold it, each the acceleration and jerk the half has within it, at the highest
    // speed it has there (`limits_at`: the normal acceleration and turning take less of
    // the limits at a lower speed, and an element the half crosses in a jerk phase needs
    // only the acceleration reached there). Planned again under wider limits read from
    // what the elements allow ([`read_half`]), the half is kept where it still fits every
    // element it then overlaps and the run takes less time; else halfway to them.
    let run_time = |h: &Half, sp: f64, xx: f64| {
        let pre = if xx > 0.0 { xx / v_a } else { 0.0 };
        let post = if sp - xx > 0.0 && v_b > 0.0 { (sp - xx) / v_b } else { 0.0 };
        pre + h.time + post
    };
    let mut time = run_time(&half, spare, x);
    for _ in 0..4 {
        let (_, wider) = read_half(elements, &limits, (&half, x), length, limits_at, false);
        if wider.accel <= limits.accel && wider.jerk <= limits.jerk {
            break;
        }
        let mut candidate =
            Limits { accel: wider.accel.max(limits.accel), jerk: wider.jerk.max(limits.jerk), ..limits };
        let mut kept = false;
        for _ in 0..3 {
            if let Some((h, sp, xx)) = place_half(elements, &candidate, v_a, v_b, length) {
                let t = run_time(&h, sp, xx);
                if t < time && read_half(elements, &candidate, (&h, xx), length, limits_at, true).0 {
                    (limits, half, spare, x, time) = (candidate, h, sp, xx, t);
                    kept = true;
                    break;
                }
            }
            candidate.accel = 0.5 * (candidate.accel + limits.accel);
            candidate.jerk = 0.5 * (candidate.jerk + limits.jerk);
        }
        if !kept {
            break;
        }
    }
    let pre_time = if x > 0.0 { x / v_a } else { 0.0 };
    let post = spare - x;
    let post_time = if post > 0.0 && v_b > 0.0 { post / v_b } else { 0.0 };
    let total = pre_time + half.time + post_time;
    let separate: f64 = elements
        .iter()
        .zip(speeds.windows(2))
        .map(|(e, v)| Profile::new(&e.limits, e.length, v[0], v[1], e.cap).duration)
        .sum();
    if total.is_nan() || total >= separate * (1.0 - 1e-9) {
        return None;
    }
    let still = |v: f64| Half::new(&limits, v, v);
    let base = if rising {
        Profile {
            pre_time,
            up: half,
            cruise_speed: v_b,
            cruise_time: post_time,
            down: still(v_b),
            end_speed: v_b,
            ..Profile::default()
        }
    } else {
        Profile {
            up: still(v_a),
            cruise_speed: v_a,
            cruise_time: pre_time,
            down: half,
            post_time,
            end_speed: v_b,
            ..Profile::default()
        }
    };
    let (mut s0, mut t0) = (0.0, 0.0);
    for (k, e) in elements.iter().enumerate() {
        let t1 = if k + 1 == n { total } else { base.raw_time_at(s0 + e.length, t0, total) };
        out.push(Profile { t0, s0, length: e.length, duration: (t1 - t0).max(0.0), ..base });
        s0 += e.length;
        t0 = t1;
    }
    Some(())
}

/// What `half` (planned under `limits`), placed `x` into the run's `elements` (of total
/// `length`), asks of each element it overlaps against what the element allows: its
/// limits at the highest speed the half has in it (at the element's end where the half
/// rises, at its start where it falls) from `limits_at` where that gives them and they
/// are at least the element's own, else the element's own. Whether every element
/// allows the largest acceleration the half has within it and, where the half changes
/// its acceleration there, the half's jerk; and the limits read as wider from them:
/// the least over the elements of each limit scaled by the room the element leaves
/// (the acceleration by what it allows over what the half has in it, which for an
/// element the half crosses at its peak is what it allows). With `check_only`, only
/// whether it fits (the limits read are not all read): an element whose own limits
/// hold the half is not asked for its limits at the speed, and the first that does not
/// allow the half ends the reading.
fn read_half(
    elements: &[RunElement],
    limits: &Limits,
    (half, x): (&Half, f64),
    length: f64,
    limits_at: &dyn Fn(usize, f64) -> Option<Limits>,
    check_only: bool,
) -> (bool, Limits) {
    let margin = 1e-9 * length;
    let rising = half.sign > 0.0;
    let (mut start, mut fits) = (0.0, true);
    let mut wider = Limits { kind: limits.kind, accel: f64::INFINITY, jerk: f64::INFINITY };
    for (k, e) in elements.iter().enumerate() {
        let end = start + e.length;
        if start < x + half.distance + margin && end > x - margin {
            let (t1, t2) = (half.time_at_distance(start - x), half.time_at_distance(end - x));
            let (accel, jerk) = half.most_between(t1, t2);
            let within = |l: &Limits| accel <= l.accel * (1.0 + 1e-12) && jerk <= l.jerk * (1.0 + 1e-12);
            if check_only && within(&e.limits) {
                start = end;
                continue;
            }
            let v = half.speed_at(if rising { t2 } else { t1 }) * (1.0 + 1e-9);
            let allowed =
                limits_at(k, v).filter(|l| l.accel >= e.limits.accel && l.jerk >= e.limits.jerk).unwrap_or(e.limits);
            fits &= within(&allowed);
            if check_only && !fits {
                break;
            }
            if accel > 0.0 {
                wider.accel = wider.accel.min(limits.accel * allowed.accel / accel);
            }
            if jerk > 0.0 {
                wider.jerk = wider.jerk.min(allowed.jerk);
            }
        }
        start = end;
    }
    (fits, wider)
}

/// The run's speed change from `v_a` to `v_b` under `limits` placed over the
/// `elements` (of total `length`) as early (rising) or as late (falling) as their
/// speed caps allow ([`run_profiles`]): the half, the length left over for the cruises
/// and the cruise before the half; `None` where it does not fit or a cap cannot be kept.
fn place_half(elements: &[RunElement], limits: &Limits, v_a: f64, v_b: f64, length: f64) -> Option<(Half, f64, f64)> {
    let rising = v_b > v_a;
    let half = Half::new(limits, v_a, v_b);
    let spare = length - half.distance;
    if spare.is_nan() || spare < 0.0 {
        return None;
    }
    // The cruise before the half, x units long.
    let mut start = 0.0;
    let x = if rising {
        // The speed at each element's end within its cap: the half reaches the cap at or
        // after that end.
        let mut x: f64 = 0.0;
        for e in elements {
            start += e.length;
            if e.cap < v_a {
                return None;
            }
            if e.cap < v_b {
                x = x.max(start - half.distance_to_speed(e.cap));
            }
        }
        if x > spare || x > 0.0 && v_a <= 0.0 {
            return None;
        }
        x
    } else {
        // The speed at each element's start within its cap: the half has come down to
        // the cap at or before that start.
        let mut x = spare;
        for e in elements {
            if e.cap < v_b {
                return None;
            }
            if e.cap < v_a {
                x = x.min(start - half.distance_to_speed(e.cap));
            }
            start += e.length;
        }
        if x < 0.0 || spare - x > 1e-12 * length && v_b <= 0.0 {
            return None;
        }
        x
    };
    Some((half, spare, x))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn limits(kind: ProfileKind) -> Limits {
        Limits { kind, accel: 500.0, jerk: 20_000.0 }
    }

    /// The closed-form inverses agree with bisection on the distance and the speed:
    /// `Half::time_to_speed` on every phase of rising and falling halves, and
    /// `Profile::raw_time_at` over a run's profile with cruises before and after.
    #[test]
    fn the_inverses_agree_with_bisection() {
        let l = limits(ProfileKind::SCurve);
        for (v0, v1) in [(0.0, 60.0), (60.0, 0.0), (5.0, 9.0), (9.0, 5.0), (10.0, 200.0), (200.0, 3.0)] {
            let half = Half::new(&l, v0, v1);
            for k in 1..40 {
                let v = v0 + (v1 - v0) * k as f64 / 40.0;
                let (mut lo, mut hi) = (0.0, half.time);
                for _ in 0..200 {
                    let mid = 0.5 * (lo + hi);
                    if half.sign * (half.speed_at(mid) - v0) < half.sign * (v - v0) {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                let t = half.time_to_speed(v);
                assert!((t - lo).abs() <= 1e-12 * half.time.max(1.0), "{v0} -> {v1} at {v}: {t} against {lo}");
                assert!((half.speed_at(t) - v).abs() <= 1e-9 * v0.max(v1), "{v0} -> {v1}: {} at {v}", half.speed_at(t));
            }
        }
        let elements = [
            RunElement { length: 2.0, limits: l, cap: 40.0 },
            RunElement { length: 5.0, limits: l, cap: 90.0 },
            RunElement { length: 8.0, limits: l, cap: 120.0 },
        ];
        let run = run_profiles(&elements, &[10.0, 30.0, 60.0, 80.0]).expect("a run");
        let base = run[0];
        let total: f64 = run.iter().map(|p| p.duration).sum();
        let length: f64 = elements.iter().map(|e| e.length).sum();
        for k in 1..50 {
            let s = length * k as f64 / 50.0;
            let t = base.raw_time_at(s, 0.0, total);
            assert!((base.raw_distance_at(t) - s).abs() <= 1e-12 * length, "{s}: {}", base.raw_distance_at(t));
        }
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

    /// A run of elements with rising (then falling) junction speeds and different caps
    /// and limits, planned as one: faster than the elements one by one, its speed
    /// within each element's cap, its acceleration and jerk within each element's
    /// limits, continuous across the junctions (so not back to zero there), and each
    /// element's part covering its length.
    #[test]
    fn a_run_carries_the_acceleration_within_every_element_limit() {
        let l = |accel: f64, jerk: f64| Limits { kind: ProfileKind::SCurve, accel, jerk };
        let elements = [
            RunElement { length: 0.6, limits: l(280.0, 2900.0), cap: 40.0 },
            RunElement { length: 1.1, limits: l(250.0, 2500.0), cap: 60.0 },
            RunElement { length: 2.0, limits: l(290.0, 2800.0), cap: 90.0 },
            RunElement { length: 3.0, limits: l(260.0, 2950.0), cap: 120.0 },
        ];
        // Junction speeds of the per-element plan: each element a half from rest
        // acceleration, within the caps.
        let mut rising = vec![10.0];
        for e in &elements {
            let v = *rising.last().unwrap();
            rising.push(e.limits.reachable(v, e.length * (1.0 - 1e-12)).min(e.cap));
        }
        let mut reversed: Vec<RunElement> = elements.to_vec();
        reversed.reverse();
        let mut falling = rising.clone();
        falling.reverse();
        for (elements, speeds) in [(&elements[..], &rising), (&reversed[..], &falling)] {
            let run = run_profiles(elements, speeds).expect("a run");
            let separate: f64 = elements
                .iter()
                .zip(speeds.windows(2))
                .map(|(e, v)| Profile::new(&e.limits, e.length, v[0], v[1], e.cap).duration)
                .sum();
            let total: f64 = run.iter().map(|p| p.duration).sum();
            assert!(total < 0.97 * separate, "run {total} s against {separate} s");
            // Sample the whole run at dt, element by element.
            let dt = 1e-4;
            let mut samples: Vec<(f64, usize)> = Vec::new();
            let mut offset = 0.0;
            let mut t = 0.0;
            for (k, (p, e)) in run.iter().zip(elements).enumerate() {
                assert!((p.distance_at(p.duration) - e.length).abs() < 1e-9, "element {k} short");
                while t <= p.duration {
                    samples.push((offset + p.distance_at(t), k));
                    t += dt;
                }
                t -= p.duration;
                offset += e.length;
            }
            let mut a_top: f64 = 0.0;
            for w in samples.windows(4) {
                let k = w[3].1.max(w[0].1);
                let e = &elements[k];
                let lo = &elements[w[0].1];
                let v = (w[3].0 - w[2].0) / dt;
                assert!(v <= e.cap.max(lo.cap) + 1e-6, "speed {v} over the cap");
                assert!(v <= elements[w[2].1].cap + 0.02 * e.cap, "speed {v} in element {}", w[2].1);
                let a = (w[3].0 - 2.0 * w[2].0 + w[1].0) / dt / dt;
                let limit = e.limits.accel.max(lo.limits.accel);
                assert!(a.abs() <= limit * (1.0 + 1e-4) + 1e-2, "accel {a}");
                let j = (w[3].0 - 3.0 * w[2].0 + 3.0 * w[1].0 - w[0].0) / dt / dt / dt;
                let limit = e.limits.jerk.max(lo.limits.jerk);
                assert!(j.abs() <= limit * (1.0 + 1e-3) + 1.0, "jerk {j}");
                a_top = a_top.max(a.abs());
            }
            // One half over the run under its smallest limits (250, 2500), not four: its
            // peak acceleration is that of the whole speed change.
            let dv = (speeds[speeds.len() - 1] - speeds[0]).abs();
            let expected = (dv * 2500.0).sqrt().min(250.0);
            assert!(a_top > 0.98 * expected, "peak acceleration {a_top}, {expected} expected");
        }
    }

    /// A falling run whose elements allow more acceleration at lower speeds (their
    /// limits at the run's top speed as their own; `limits_at` as a normal acceleration
    /// `c_k v^2` leaves more of 294 below it), its first element long and the most
    /// curved: with `limits_at` the half is held in each element to its limits at the
    /// speed it has there, and to the acceleration it has there (it crosses the first
    /// element in its jerk phase): faster than under the elements' own limits, its peak
    /// acceleration near what the last elements allow, and at every sample within the
    /// limit at the sample's own speed.
    #[test]
    fn a_run_takes_each_elements_limits_at_the_speed_it_has_there() {
        let curvature = [0.02, 0.012, 0.006, 0.003, 0.0];
        let lengths = [9.6, 1.1, 1.0, 1.1, 0.85];
        let top = 52.0;
        let at =
            |k: usize, v: f64| Limits { kind: ProfileKind::SCurve, accel: 294.0 - curvature[k] * v * v, jerk: 2900.0 };
        let elements: Vec<RunElement> =
            (0..5).map(|k| RunElement { length: lengths[k], limits: at(k, top), cap: top }).collect();
        // Junction speeds of the per-element plan, backward from 11.5 at the end.
        let mut speeds = vec![11.5];
        for e in elements.iter().rev() {
            let v = *speeds.last().unwrap();
            speeds.push(e.limits.reachable(v, e.length * (1.0 - 1e-12)).min(e.cap));
        }
        speeds.reverse();
        let fixed = run_profiles(&elements, &speeds).expect("a run under the elements' own limits");
        let mut by_speed = Vec::new();
        let limits_at = |k: usize, v: f64| Some(at(k, v));
        assert!(run_profiles_into(&elements, &speeds, &mut by_speed, &limits_at), "a run at the speeds");
        let duration = |run: &[Profile]| run.iter().map(|p| p.duration).sum::<f64>();
        assert!(duration(&by_speed) < duration(&fixed), "{} s against {} s", duration(&by_speed), duration(&fixed));
        let dt = 1e-4;
        let mut samples: Vec<(f64, usize)> = Vec::new();
        let (mut offset, mut t) = (0.0, 0.0);
        for (k, p) in by_speed.iter().enumerate() {
            while t <= p.duration {
                samples.push((offset + p.distance_at(t), k));
                t += dt;
            }
            t -= p.duration;
            offset += lengths[k];
        }
        let mut a_top: f64 = 0.0;
        for w in samples.windows(4) {
            let v = (w[3].0 - w[2].0) / dt;
            let a = (w[3].0 - 2.0 * w[2].0 + w[1].0) / dt / dt;
            let limit = at(w[3].1, v).accel.max(at(w[0].1, v).accel);
            assert!(a.abs() <= limit * (1.0 + 1e-4) + 1e-2, "accel {a} at {v} in element {}", w[3].1);
            let j = (w[3].0 - 3.0 * w[2].0 + 3.0 * w[1].0 - w[0].0) / dt / dt / dt;
            assert!(j.abs() <= 2900.0 * (1.0 + 1e-3) + 1.0, "jerk {j}");
            a_top = a_top.max(a.abs());
        }
        // Under the own limits the half is held to the first element's 294 - 0.02 52^2.
        let own = at(0, top).accel;
        assert!(a_top > own + 0.5 * (294.0 - own), "peak acceleration {a_top}, {own} under the own limits");
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

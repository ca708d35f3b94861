//! The feed profile along a path: seed 000's per-period acceleration and deceleration.

use crate::linear::PlanError;

/// Feed limits along a path, in path units (mm) and seconds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FeedProfile {
    /// Programmed feed, units/s.
    pub feed: f64,
    /// Start and stop speed, units/s (at most the feed).
    pub start_speed: f64,
    /// Path acceleration and deceleration, units/s^2.
    pub accel: f64,
    /// The interpolation period T, s.
    pub period: f64,
}

impl FeedProfile {
    /// A profile after checking every value is positive and finite.
    pub fn new(feed: f64, start_speed: f64, accel: f64, period: f64) -> Result<Self, PlanError> {
        let feed = positive("feed", feed)?;
        Ok(FeedProfile {
            feed,
            start_speed: positive("start speed", start_speed)?.min(feed),
            accel: positive("acceleration", accel)?,
            period: positive("period", period)?,
        })
    }

    /// The distance travelled at the end of each period along a path of `length`: the
    /// first period at the start speed, then raised every period by at most A*T towards
    /// the feed and lowered again so that the path ends at the stop speed; the last value
    /// is exactly `length`.
    pub fn distances(&self, length: f64) -> Vec<f64> {
        let (period, stop, step) = (self.period, self.start_speed, self.accel * self.period);
        let mut out = Vec::new();
        let mut travelled = 0.0_f64;
        let mut speed = stop - step;
        while travelled < length {
            let remaining = length - travelled;
            let ceiling = (speed + step).min(self.feed);
            speed = if can_stop(ceiling, remaining, stop, step, period) {
                ceiling
            } else {
                fastest_stoppable(ceiling, remaining, stop, step, period)
            };
            travelled = (travelled + speed * period).min(length);
            out.push(travelled);
        }
        out
    }
}

pub(crate) fn positive(name: &'static str, value: f64) -> Result<f64, PlanError> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(PlanError::NotPositive { name, value })
    }
}

/// Distance covered after a period at `speed` when every later period is `step` slower,
/// down to the stop speed: T * sum over j = 1..k of (speed - j*step), k = floor((speed - stop) / step).
fn braking_distance(speed: f64, stop: f64, step: f64, period: f64) -> f64 {
    let k = ((speed - stop) / step).floor().max(0.0);
    period * (k * speed - step * k * (k + 1.0) / 2.0)
}

/// Whether a period at `speed` still leaves room to brake to the stop speed.
fn can_stop(speed: f64, remaining: f64, stop: f64, step: f64, period: f64) -> bool {
    remaining - speed * period >= braking_distance(speed, stop, step, period)
}

/// The largest speed in [stop, ceiling] that can still brake in time (bisection; the
/// stop speed itself when none can: the last, partial period).
fn fastest_stoppable(ceiling: f64, remaining: f64, stop: f64, step: f64, period: f64) -> f64 {
    let (mut lo, mut hi) = (stop, ceiling);
    if !can_stop(lo, remaining, stop, step, period) {
        return stop;
    }
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if can_stop(mid, remaining, stop, step, period) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

//! The jog generator against its limits and an ideal of where it should go.
//!
//! A harness steps `JogGenerator` clock by clock with the period timer's `rec_ready`
//! (the spec's timer: the run starts the cycle after engagement, the first boundary
//! comes one cycle later, then one every `P` clocks) and random hand-wheel detents at
//! random clocks. At every boundary the record taken is checked against the limits
//! (`|next_vel - vel| <= A`, `|next_vel| <= max(VM, |vel|)`), and `cmd` against the sum
//! of the records; the target against the detents (follow mode: every detent moves it
//! by `m * JOG_SCALE`; drop mode: a detent is taken only if it lands within
//! `JOG_WINDOW` of `cmd`, else counted in `DROPPED`).
//!
//! With a fixed target and starting at rest, the jog must never overshoot and must land
//! on it exactly, within the continuous-time reference: covering `|e|` with acceleration
//! and deceleration `A` and a speed limit `VM` takes at most `2 sqrt(|e| / A) + |e| / VM`
//! periods. The first version of the spec's rules failed both (the cases are kept below
//! as `first_spec_counterexample_*`); the spec's rules now pass them.

use finestep_model::jog_generator::{multiplier, JogGenerator, JogInputs, MIN_PERIOD_CLOCKS};
use proptest::prelude::*;

/// The jog and the period timer that gives it `rec_ready`.
struct Harness {
    jog: JogGenerator,
    inputs: JogInputs,
    period: u32,
    active: bool,
    remaining: u32,
    clocks: u64,
}

/// What one edge did.
#[derive(Clone, Copy, Debug, Default)]
struct Edge {
    /// The record the core took at this edge (a boundary while engaged).
    record: Option<i32>,
    /// `target` before and after.
    target: (i64, i64),
    /// `cmd` before the edge.
    cmd_before: i64,
    /// `DROPPED` went up.
    dropped: bool,
}

impl Harness {
    fn new(inputs: JogInputs, period: u32) -> Harness {
        assert!(period >= MIN_PERIOD_CLOCKS);
        let inputs = JogInputs { period_clocks: period, n_axes: 4, ..inputs };
        Harness { jog: JogGenerator::default(), inputs, period, active: false, remaining: 0, clocks: 0 }
    }

    /// One clock with the wheel at `detents`.
    fn step(&mut self, detents: i32) -> Edge {
        let rec_ready = self.active && self.remaining == 0;
        let engaged = self.jog.engaged();
        let axis = self.jog.axis();
        let mut edge = Edge {
            record: (engaged && rec_ready).then(|| self.jog.record().inc[axis].to_bits()),
            target: (self.jog.target(), 0),
            cmd_before: self.jog.cmd(),
            dropped: false,
        };
        let dropped = self.jog.dropped();
        self.inputs.detents = detents;
        self.inputs.rec_ready = rec_ready;
        self.jog.step(&self.inputs);
        edge.target.1 = self.jog.target();
        edge.dropped = self.jog.dropped() != dropped;
        // The core runs while the jog is engaged (RUN is 0 here).
        if !engaged {
            self.active = false;
            self.remaining = 0;
        } else if !self.active {
            self.active = true;
        } else if self.remaining == 0 {
            self.remaining = self.period - 1;
        } else {
            self.remaining -= 1;
        }
        self.clocks += 1;
        edge
    }
}

/// Checks the limits and the bookkeeping over a run, boundary by boundary.
#[derive(Debug, Default)]
struct Books {
    vel: i64,
    sum: i64,
    records: Vec<i32>,
}

impl Books {
    fn take(&mut self, jog: &JogGenerator, record: i32, vmax: u32, accel: u32) -> Result<(), TestCaseError> {
        let r = i64::from(record);
        prop_assert!((r - self.vel).abs() <= i64::from(accel), "acceleration: {} after {}", r, self.vel);
        prop_assert!(
            r.abs() <= i64::from(vmax).max(self.vel.abs()),
            "velocity: {} after {} with VM {}",
            r,
            self.vel,
            vmax
        );
        self.vel = r;
        self.sum += r;
        self.records.push(record);
        prop_assert_eq!(jog.cmd(), self.sum, "cmd is the sum of the records");
        prop_assert_eq!(i64::from(jog.vel()), r);
        Ok(())
    }
}

/// A jog configuration.
#[derive(Clone, Copy, Debug)]
struct Config {
    vmax: u32,
    accel: u32,
    scale: i32,
    multiplier: u8,
    window: u16,
    follow: bool,
    period: u32,
}

fn config() -> impl Strategy<Value = Config> {
    let vmax = prop_oneof![1..=64u32, 1..=(1u32 << 22)];
    let accel = prop_oneof![1..=64u32, 1..=(1u32 << 18)];
    let scale = prop_oneof![(1..=(1i32 << 22)), (-(1i32 << 22)..=-1)];
    (vmax, accel, scale, 0..=3u8, prop_oneof![Just(0u16), 0..=50u16, 0..=2000u16], any::<bool>(), 128..=400u32)
        .prop_map(|(vmax, accel, scale, multiplier, window, follow, period)| Config {
            vmax,
            accel,
            scale,
            multiplier,
            window,
            follow,
            period,
        })
}

fn inputs(c: &Config) -> JogInputs {
    JogInputs {
        enable: true,
        axis: 1,
        multiplier: c.multiplier,
        follow: c.follow,
        scale: c.scale,
        vmax: c.vmax,
        accel: c.accel,
        window: c.window,
        ..JogInputs::default()
    }
}

/// The ideal distance of one detent, `m * JOG_SCALE`.
fn detent_step(c: &Config) -> i64 {
    multiplier(c.multiplier.into()) * i64::from(c.scale)
}

#[test]
fn the_jog_keeps_its_limits_and_books_every_record_and_detent() {
    let mut runner = finestep_testkit::runner("the_jog_keeps_its_limits_and_books_every_record_and_detent", 128);
    // Detents: (clocks before it, direction).
    let wheel = prop::collection::vec((1..=1500u64, any::<bool>()), 0..40);
    runner
        .run(&(config(), wheel), |(c, wheel)| {
            let mut h = Harness::new(inputs(&c), c.period);
            let mut books = Books::default();
            let mut detents = 0i32;
            let mut ideal_target = 0i64;
            let mut dropped = 0u16;
            let window = i64::from(c.window) << 16;
            let check = |h: &mut Harness, detents: i32, books: &mut Books| -> Result<Edge, TestCaseError> {
                let edge = h.step(detents);
                if let Some(record) = edge.record {
                    books.take(&h.jog, record, c.vmax, c.accel)?;
                }
                prop_assert!(h.jog.engaged(), "the jog disengaged while enabled");
                Ok(edge)
            };
            // The detent configuration reaches the detents two cycles after it is set.
            check(&mut h, detents, &mut books)?;
            check(&mut h, detents, &mut books)?;
            for (gap, up) in wheel {
                for _ in 1..gap {
                    check(&mut h, detents, &mut books)?;
                }
                detents += if up { 1 } else { -1 };
                let step = if up { detent_step(&c) } else { -detent_step(&c) };
                let edge = check(&mut h, detents, &mut books)?;
                if c.follow {
                    ideal_target += step;
                    prop_assert_eq!(h.jog.target(), ideal_target, "follow mode takes every detent");
                } else if edge.dropped {
                    dropped += 1;
                    prop_assert_eq!(edge.target.1, edge.target.0);
                    prop_assert!((edge.target.0 + step - edge.cmd_before).abs() > window, "dropped within the window");
                } else {
                    prop_assert_eq!(edge.target.1, edge.target.0 + step);
                    prop_assert!((edge.target.1 - edge.cmd_before).abs() <= window, "taken outside the window");
                }
                prop_assert_eq!(h.jog.dropped(), dropped);
            }
            // Disable: the jog brakes at A and disengages once at rest (the velocity may
            // still rise once: the period under way was computed while enabled).
            h.inputs.enable = false;
            let limit = books.vel.unsigned_abs() / u64::from(c.accel) + 4;
            let mut boundaries = 0;
            while h.jog.engaged() {
                let edge = h.step(detents);
                if let Some(record) = edge.record {
                    books.take(&h.jog, record, c.vmax, c.accel)?;
                    boundaries += 1;
                    prop_assert!(boundaries <= limit, "still engaged after {} periods of braking", boundaries);
                }
            }
            prop_assert_eq!(books.records.last().copied(), Some(0), "the run ends on a zero record");
            Ok(())
        })
        .unwrap();
}

/// From rest with the target put `e` away by one detent and the wheel then still: the
/// records until the jog is back at rest on the target (or `limit` periods).
fn land(vmax: u32, accel: u32, e: i32, period: u32, limit: usize) -> Result<(Vec<i32>, JogGenerator), TestCaseError> {
    let c = Config { vmax, accel, scale: e, multiplier: 0, window: 0, follow: true, period };
    let mut h = Harness::new(inputs(&c), period);
    let mut books = Books::default();
    h.step(0);
    h.step(0); // the detent configuration takes two cycles to reach the detents
    h.step(1);
    prop_assert_eq!(h.jog.target(), i64::from(e));
    while books.records.len() < limit {
        let edge = h.step(1);
        if let Some(record) = edge.record {
            books.take(&h.jog, record, vmax, accel)?;
            let settled = h.jog.cmd() == h.jog.target() && h.jog.vel() == 0 && h.jog.next_vel() == 0;
            if settled {
                break;
            }
        }
    }
    Ok((books.records, h.jog))
}

/// The continuous-time bound on the periods to cover `|e|` from rest to rest.
fn periods_bound(vmax: u32, accel: u32, e: i32) -> f64 {
    let e = f64::from(e).abs();
    2.0 * (e / f64::from(accel)).sqrt() + e / f64::from(vmax)
}

/// A fixed target with the velocity limit no lower than the acceleration (the usual
/// setting: full speed takes several periods) is reached exactly. The reset
/// settings (`JOG_VMAX` 1 step, `JOG_ACCEL` 1/16 step) are among them. (Not always in
/// the continuous-time bound: the overshoot below costs periods.)
#[test]
fn a_fixed_target_is_reached_exactly() {
    let mut runner = finestep_testkit::runner("a_fixed_target_is_reached_exactly", 256);
    let case =
        (1..=(1u32 << 16), 1..=64u32, prop_oneof![1..=(1i32 << 16), 1..=(1i32 << 24)], any::<bool>(), 128..=300u32);
    runner
        .run(&case, |(accel, ratio, e, negative, period)| {
            let vmax = accel.saturating_mul(ratio).min(1 << 30);
            let e = if negative { -e } else { e };
            let limit = 4.0 * periods_bound(vmax, accel, e) + 20.0;
            let (records, jog) = land(vmax, accel, e, period, limit as usize)?;
            prop_assert_eq!(
                jog.cmd(),
                i64::from(e),
                "not on the target after {} periods: {:?}",
                records.len(),
                records
            );
            prop_assert!(jog.vel() == 0 && jog.next_vel() == 0, "not at rest");
            Ok(())
        })
        .unwrap();
}

/// The first spec: "with a target that stays put the jog never overshoots". It does, by the
/// spec's own rules: see `spec_counterexample_arrive_overshoots`. Kept as the property
/// a fixed spec must pass, with the time to arrive: the continuous-time bound plus a
/// few periods (the boundary before the first record, the computation's period of lag,
/// the discrete rounding).
#[test]
fn a_fixed_target_is_reached_in_time_without_overshoot() {
    let mut runner = finestep_testkit::runner("a_fixed_target_is_reached_in_time_without_overshoot", 256);
    let case = (1..=(1u32 << 16), 1..=(1u32 << 22), 1..=(1i32 << 24), 128..=300u32);
    runner
        .run(&case, |(accel, vmax, e, period)| {
            let bound = periods_bound(vmax, accel, e) + 6.0;
            let (records, jog) = land(vmax, accel, e, period, 10 * bound as usize + 100)?;
            let mut cmd = 0i64;
            for &r in &records {
                cmd += i64::from(r);
                prop_assert!((0..=i64::from(e)).contains(&cmd), "cmd {} outside 0..={}: {:?}", cmd, e, records);
            }
            prop_assert_eq!(jog.cmd(), i64::from(e));
            prop_assert!(records.len() as f64 <= bound, "{} periods, bound {}: {:?}", records.len(), bound, records);
            Ok(())
        })
        .unwrap();
}

/// The first spec: "... and lands on it exactly". Not when `VM` is below about `A / 2`: see
/// `spec_counterexample_slow_jog_never_arrives`.
#[test]
fn every_fixed_target_is_reached() {
    let mut runner = finestep_testkit::runner("every_fixed_target_is_reached", 256);
    let case = (1..=(1u32 << 16), 1..=(1u32 << 16), 1..=(1i32 << 20), 128..=300u32);
    runner
        .run(&case, |(accel, vmax, e, period)| {
            let bound = periods_bound(vmax, accel, e) + 6.0;
            let (records, jog) = land(vmax, accel, e, period, 10 * bound as usize + 100)?;
            prop_assert_eq!(jog.cmd(), i64::from(e), "{:?}", records);
            Ok(())
        })
        .unwrap();
}

/// Worked by hand from the spec's rules, at the reset settings `A = 4096`,
/// `VM = 65536` and a target of `2A + 1 = 8193` (1/8 step): from rest `u = isqrt(2 A e)
/// - A = 8192 - 4096 = 4096`, so `v1 = 4096`; then `e = 4097`, `vel = 4096`: arrive
/// (`|e| <= VM`, `|e - vel| = 1 <= A`), `v2 = 4097`, `e = 0`; then `vel = 4097 > A`, so
/// `v3 = clamp(0, vel - A, vel + A) = 1`: one unit past the target, then back. Almost
/// every move at these settings ends this way (by up to a few A), because the arrive
/// rule takes `v' = e` whenever it is within `A` of `vel`, also when `|e| > A`, after
/// which the next period cannot brake to 0. A fix that passes the properties above in
/// simulation: arrive only when also `|e| <= A`.
#[test]
fn first_spec_counterexample_arrive_overshoots() {
    let (records, jog) = land(65536, 4096, 8193, 200, 50).unwrap();
    // Now: up at A, then the floor min(|e|, A) and the last step of 1.
    assert_eq!(&records[..4], &[4096, 4096, 1, 0], "{records:?}");
    assert_eq!(jog.cmd(), 8193);
}

/// Worked by hand: `A = 4096`, `VM = 1000`, target `1500`. From rest: not arrive
/// (`|e| > VM`); `u = max(isqrt(2 * 4096 * 1500) - 4096, 0) = max(3505 - 4096, 0) = 0`,
/// so `v' = 0`, forever. A fix that passes the properties above in simulation (with the
/// arrive fix): `u = max(isqrt(2 A |e|) - A, min(|e|, A))`.
#[test]
fn first_spec_counterexample_slow_jog_never_arrives() {
    let (records, jog) = land(1000, 4096, 1500, 200, 100).unwrap();
    assert_eq!(&records[..3], &[1000, 500, 0], "{records:?}");
    assert_eq!((jog.cmd(), jog.target()), (1500, 1500));
}

/// Turning one way, `|target - cmd|` stays within the window at every clock.
#[test]
fn drop_mode_turning_one_way_stays_within_the_window() {
    let mut runner = finestep_testkit::runner("drop_mode_turning_one_way_stays_within_the_window", 128);
    let wheel = prop::collection::vec(1..=1500u64, 0..40);
    runner
        .run(&(config(), any::<bool>(), wheel), |(c, up, wheel)| {
            let c = Config { follow: false, window: c.window.max(1), ..c };
            let window = i64::from(c.window) << 16;
            let mut h = Harness::new(inputs(&c), c.period);
            let mut detents = 0;
            for gap in wheel {
                for k in 0..gap {
                    if k + 1 == gap {
                        detents += if up { 1 } else { -1 };
                    }
                    h.step(detents);
                    let e = h.jog.target() - h.jog.cmd();
                    prop_assert!(e.abs() <= window, "|target - cmd| = {} > {}", e.abs(), window);
                }
            }
            Ok(())
        })
        .unwrap();
}

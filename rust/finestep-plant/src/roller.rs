//! A roller on seed 000's grinder: its surface along the table (Z), read by a measuring
//! gauge with a grating, or cut by the grinding wheel (X).
//!
//! The surface is the roller's radius deviation, in nm, at every count of the table's
//! position at a fixed resolution (`z_counts_per_step`, the Z grating's: one point per
//! count), from `first_count` on; beyond its ends it continues at its end values.
//!
//! - **Measuring** ([`RollerMode::Measure`]): a gauge rides on the surface at the table's
//!   position; its grating (an [`Encoder`] whose counts per step are counts per nm)
//!   gives the radius deviation as A/B levels on the next encoder channel. The gauge's
//!   count changes only when the table's count does, so its next change is found
//!   exactly from the table drive's ([`Motion::next_exit`] over the run of table counts
//!   at which the gauge count stays).
//! - **Grinding** ([`RollerMode::Grind`]): every time the table's count changes (in
//!   cycle `t`, to `z`), the wheel's position in cycle `t` cuts the point: `radius[z] =
//!   min(radius[z], wheel_nm(t) + error[z] + roughness)`, where `error` is the machine's
//!   form error (what a straight pass leaves: bed, deflection) and `roughness` a seeded
//!   draw in `-roughness_nm..=roughness_nm`. Table counts skipped in one cycle are cut
//!   at that cycle's wheel position. Grinding changes no pin.

use crate::{CountsPerStep, Drive, Encoder, EncoderConfig, Levels, Motion, PlantError};

/// A radius deviation along the table, nm per table count (see the module documentation).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Surface {
    first_count: i64,
    radius_nm: Vec<i64>,
}

impl Surface {
    /// Points `radius_nm[i]` at table counts `first_count + i`; at least one point.
    pub fn new(first_count: i64, radius_nm: Vec<i64>) -> Result<Surface, PlantError> {
        if radius_nm.is_empty() {
            return Err(PlantError::Roller { why: "a surface needs at least one point".into() });
        }
        Ok(Surface { first_count, radius_nm })
    }

    /// The table count of the first point.
    pub fn first_count(&self) -> i64 {
        self.first_count
    }

    /// The points, nm.
    pub fn radius_nm(&self) -> &[i64] {
        &self.radius_nm
    }

    fn index(&self, count: i64) -> usize {
        (count.saturating_sub(self.first_count)).clamp(0, self.radius_nm.len() as i64 - 1) as usize
    }

    /// The radius deviation at table count `count` (the end values beyond the ends).
    pub fn radius_at(&self, count: i64) -> i64 {
        self.radius_nm[self.index(count)]
    }

    /// The largest run of table counts around `count` whose radii all satisfy `keep`
    /// (which the radius at `count` does); unbounded past an end that keeps.
    fn run(&self, count: i64, keep: impl Fn(i64) -> bool) -> (i64, i64) {
        let i = self.index(count);
        let last = self.radius_nm.len() - 1;
        let mut lo = i;
        while lo > 0 && keep(self.radius_nm[lo - 1]) {
            lo -= 1;
        }
        let mut hi = i;
        while hi < last && keep(self.radius_nm[hi + 1]) {
            hi += 1;
        }
        // Counts beyond an end read the end value: a run that reaches an end goes on.
        let at = |j: usize| self.first_count + j as i64;
        (if lo == 0 { i64::MIN } else { at(lo) }, if hi == last { i64::MAX } else { at(hi) })
    }
}

/// A draw in `-amplitude..=amplitude` fixed by `seed` and `index` (SplitMix64): the same
/// point of a surface always gets the same roughness, in whatever order it is cut.
pub fn roughness_nm(seed: u64, index: i64, amplitude: i64) -> i64 {
    if amplitude <= 0 {
        return 0;
    }
    let mut z = seed ^ (index as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z % (2 * amplitude as u64 + 1)) as i64 - amplitude
}

/// What the roller is doing.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum RollerMode {
    /// A gauge reads the surface on the encoder channel after the plant's channels.
    Measure {
        /// The gauge's grating: counts per step are counts per nm (e.g. `1/500` for
        /// 0.5 um), usually without faults.
        gauge: EncoderConfig,
    },
    /// The wheel cuts the surface.
    Grind {
        /// The wheel slide's axis (drive).
        wheel_axis: usize,
        /// nm per wheel step.
        wheel_nm_per_step: u32,
        /// The machine's form error, nm per table count, over the surface's counts.
        error_nm: Vec<i64>,
        /// The roughness a cut leaves, nm (each point: a draw in `-r..=r`).
        roughness_nm: i64,
        /// The roughness's seed.
        seed: u64,
    },
}

/// A roller on the table.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RollerConfig {
    /// The table's axis (drive).
    pub table_axis: usize,
    /// Table counts (surface points) per table step.
    pub z_counts_per_step: CountsPerStep,
    /// The surface.
    pub surface: Surface,
    /// Measuring or grinding.
    pub mode: RollerMode,
}

/// The gauge's motion: the surface's radius (nm) under the table's position.
struct GaugeMotion<'a> {
    table: &'a Drive,
    z_scale: CountsPerStep,
    surface: &'a Surface,
}

impl Motion for GaugeMotion<'_> {
    fn count_at(&self, cycle: u64, scale: CountsPerStep) -> i64 {
        scale.count_of(self.surface.radius_at(self.table.count_at(cycle, self.z_scale)))
    }

    fn next_exit(&self, after: u64, scale: CountsPerStep, lo: i64, hi: i64) -> Option<u64> {
        let inside = |radius: i64| (lo..=hi).contains(&scale.count_of(radius));
        let mut t = after;
        loop {
            let z = self.table.count_at(t, self.z_scale);
            let (z_lo, z_hi) = self.surface.run(z, inside);
            t = self.table.next_exit(t, self.z_scale, z_lo, z_hi)?;
            if !inside(self.surface.radius_at(self.table.count_at(t, self.z_scale))) {
                return Some(t);
            }
        }
    }
}

fn gauge_motion<'a>(config: &'a RollerConfig, drives: &'a [Drive]) -> GaugeMotion<'a> {
    GaugeMotion { table: &drives[config.table_axis], z_scale: config.z_counts_per_step, surface: &config.surface }
}

/// The roller (see the module documentation).
#[derive(Clone, Debug)]
pub struct Roller {
    config: RollerConfig,
    gauge: Option<Encoder>,
    wheel_scale: CountsPerStep,
    cursor: u64,
    z_count: i64,
}

impl Roller {
    /// The roller over `drives` in `cycle`; the gauge's faults drawn from `seed`.
    pub(crate) fn new(config: RollerConfig, drives: &[Drive], seed: u64, cycle: u64) -> Result<Roller, PlantError> {
        let axis = |what: &str, axis: usize| {
            drives.get(axis).ok_or(PlantError::Axis { what: what.into(), axis, axes: drives.len() })
        };
        let table = axis("the roller's table", config.table_axis)?;
        let mut wheel_scale = CountsPerStep::integer(1)?;
        if let RollerMode::Grind { wheel_axis, wheel_nm_per_step, error_nm, .. } = &config.mode {
            axis("the grinding wheel", *wheel_axis)?;
            wheel_scale = CountsPerStep::integer(*wheel_nm_per_step)?;
            if error_nm.len() != config.surface.radius_nm.len() {
                return Err(PlantError::Roller {
                    why: format!(
                        "the machine error has {} points, the surface {}",
                        error_nm.len(),
                        config.surface.radius_nm.len()
                    ),
                });
            }
        }
        let z_count = table.count_at(cycle, config.z_counts_per_step);
        let gauge = match &config.mode {
            RollerMode::Measure { gauge } => Some(Encoder::new(*gauge, seed, &gauge_motion(&config, drives), cycle)?),
            RollerMode::Grind { .. } => None,
        };
        let mut roller = Roller { config, gauge, wheel_scale, cursor: cycle, z_count };
        roller.cut(z_count, z_count, drives, cycle);
        Ok(roller)
    }

    /// The surface as it is now.
    pub fn surface(&self) -> &Surface {
        &self.config.surface
    }

    /// The gauge's grating, when measuring.
    pub fn gauge(&self) -> Option<&Encoder> {
        self.gauge.as_ref()
    }

    /// The roller's settings (the surface as it was given).
    pub fn mode(&self) -> &RollerMode {
        &self.config.mode
    }

    pub(crate) fn levels(&self) -> Option<Levels> {
        self.gauge.as_ref().map(Encoder::levels)
    }

    /// The gauge's next pin change (grinding changes none).
    pub(crate) fn next_change(&self, drives: &[Drive]) -> Option<u64> {
        self.gauge.as_ref()?.next_change(&gauge_motion(&self.config, drives))
    }

    /// Cuts table counts `from..=to` (either order) at the wheel's position in `cycle`.
    fn cut(&mut self, from: i64, to: i64, drives: &[Drive], cycle: u64) {
        let RollerMode::Grind { wheel_axis, error_nm, roughness_nm: r, seed, .. } = &self.config.mode else {
            return;
        };
        let wheel = drives[*wheel_axis].count_at(cycle, self.wheel_scale);
        let surface = &mut self.config.surface;
        for z in from.min(to)..=from.max(to) {
            let Some(i) = z.checked_sub(surface.first_count).and_then(|i| usize::try_from(i).ok()) else { continue };
            if let Some(point) = surface.radius_nm.get_mut(i) {
                *point = (*point).min(wheel + error_nm[i] + roughness_nm(*seed, z, *r));
            }
        }
    }

    /// Moves to `cycle` over `drives` (not yet advanced past the roller's cycle).
    pub(crate) fn advance_to(&mut self, cycle: u64, drives: &[Drive]) {
        if let Some(gauge) = &mut self.gauge {
            gauge.advance_to(cycle, &gauge_motion(&self.config, drives));
        } else {
            let table = &drives[self.config.table_axis];
            let scale = self.config.z_counts_per_step;
            while let Some(t) = table.next_exit(self.cursor, scale, self.z_count, self.z_count).filter(|&t| t <= cycle)
            {
                let z = table.count_at(t, scale);
                let from = if z > self.z_count { self.z_count + 1 } else { self.z_count - 1 };
                self.cut(from, z, drives, t);
                (self.z_count, self.cursor) = (z, t);
            }
        }
        self.cursor = cycle;
        self.z_count = drives[self.config.table_axis].count_at(cycle, self.config.z_counts_per_step);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testutil::{jump_through, step_pins, StepPlan};
    use crate::{ChannelConfig, DriveConfig, Mechanics, Plant, PlantConfig, PlantPins};
    use proptest::prelude::*;

    /// Table (axis 1, lagging) and wheel (axis 0, lagging) pins as (cycle, axis, step, dir).
    fn pins(table: &StepPlan, wheel: &StepPlan) -> Vec<(u64, usize, bool, bool)> {
        let mut events: Vec<(u64, usize, bool, bool)> = Vec::new();
        for (axis, plan) in [(1, table), (0, wheel)] {
            events.extend(step_pins(plan).into_iter().map(|(t, s, d)| (t, axis, s, d)));
        }
        events.sort_by_key(|e| (e.0, e.1));
        events
    }

    fn plant(tau: u64, mode: RollerMode, surface: Surface) -> Plant {
        let lag = DriveConfig { mechanics: Mechanics::Lag { tau }, ..DriveConfig::default() };
        let z_grating = EncoderConfig::linear_grating(CountsPerStep::new(5, 2).unwrap(), None);
        let config = PlantConfig {
            drives: vec![lag, lag],
            channels: vec![ChannelConfig { axis: 1, encoder: z_grating }],
            probe: None,
            hand_wheel: None,
        };
        let roller =
            RollerConfig { table_axis: 1, z_counts_per_step: CountsPerStep::new(5, 2).unwrap(), surface, mode };
        Plant::new(config, 3).unwrap().with_roller(roller, 11).unwrap()
    }

    /// Measuring: the plant jumping from change to change and stepping cycle by cycle see
    /// the same pins; in every cycle the gauge reads the surface under the table. Grinding:
    /// the surface is what a cut at every change of the table's count, cycle by cycle, leaves.
    #[test]
    fn the_gauge_reads_the_surface_and_the_wheel_cuts_it() {
        let mut runner = finestep_testkit::runner("plant_roller", 48);
        // A walk of less than a gauge count (500 nm) a point: the gauge never outruns its
        // grating while the table moves a count at a time.
        let walk = prop::collection::vec(-499i64..=499, 1..=40)
            .prop_map(|steps| steps.iter().scan(-1000, |r, s| Some(std::mem::replace(r, *r + s))).collect());
        let surface = (-3i64..=3, walk);
        let strategy = (12u64..=120, StepPlan::strategy(12, 40, 40), StepPlan::strategy(12, 30, 60), surface);
        runner
            .run(&strategy, |(tau, table, wheel, (first, radius)): (u64, StepPlan, StepPlan, (i64, Vec<i64>))| {
                let gauge_scale = CountsPerStep::new(1, 500).unwrap();
                let z_scale = CountsPerStep::new(5, 2).unwrap();
                let surface = Surface::new(first, radius).unwrap();
                let events = pins(&table, &wheel);
                let end = events.last().map_or(0, |e| e.0) + 40 * tau;
                let measure = RollerMode::Measure { gauge: EncoderConfig::linear_grating(gauge_scale, None) };

                let mut stepped = plant(tau, measure.clone(), surface.clone());
                let mut expected: Vec<(u64, PlantPins)> = Vec::new();
                let mut next = events.iter().peekable();
                for n in 1..=end {
                    let before = stepped.pins();
                    stepped.advance_to(n);
                    let z = stepped.drive(1).count_at(n, z_scale);
                    let gauge = stepped.roller().unwrap().gauge().unwrap();
                    prop_assert_eq!(gauge.ideal_count(), gauge_scale.count_of(surface.radius_at(z)), "cycle {}", n);
                    if stepped.pins() != before {
                        expected.push((n, stepped.pins()));
                    }
                    while let Some(&&(_, axis, s, d)) = next.peek().filter(|e| e.0 == n) {
                        stepped.set_step_pins(n, axis, s, d);
                        next.next();
                    }
                }
                let mut jumped = plant(tau, measure, surface.clone());
                let found = jump_through(
                    &mut jumped,
                    &events,
                    end,
                    |e| e.0,
                    |p, &(t, axis, s, d)| p.set_step_pins(t, axis, s, d),
                )?;
                prop_assert_eq!(&found, &expected);
                let gauge = jumped.roller().unwrap().gauge().unwrap();
                prop_assert_eq!(gauge.decoded().count, gauge.ideal_count());

                // Grinding, against a cut at every cycle in which the table's count moved.
                let error: Vec<i64> = (0..surface.radius_nm().len() as i64).map(|i| 50 * i - 400).collect();
                let grind = RollerMode::Grind {
                    wheel_axis: 0,
                    wheel_nm_per_step: 700,
                    error_nm: error.clone(),
                    roughness_nm: 90,
                    seed: 5,
                };
                let mut ground = plant(tau, grind, surface.clone());
                let mut reference = surface.radius_nm().to_vec();
                let mut cut = |z: i64, wheel: i64| {
                    if let Some(i) = usize::try_from(z - first).ok().filter(|&i| i < reference.len()) {
                        reference[i] = reference[i].min(wheel + error[i] + roughness_nm(5, z, 90));
                    }
                };
                cut(0, 0);
                let mut z_before = 0;
                let mut next = events.iter().peekable();
                for n in 1..=end {
                    ground.advance_to(n);
                    let z = ground.drive(1).count_at(n, z_scale);
                    let wheel = ground.drive(0).count_at(n, CountsPerStep::integer(700).unwrap());
                    let step = if z > z_before { 1 } else { -1 };
                    let mut at = z_before;
                    while at != z {
                        at += step;
                        cut(at, wheel);
                    }
                    z_before = z;
                    while let Some(&&(_, axis, s, d)) = next.peek().filter(|e| e.0 == n) {
                        ground.set_step_pins(n, axis, s, d);
                        next.next();
                    }
                }
                prop_assert_eq!(ground.roller().unwrap().surface().radius_nm(), &reference[..]);
                prop_assert!(ground.next_change().is_none_or(|t| t > end), "grinding changes no pin");
                Ok(())
            })
            .unwrap();
    }

    #[test]
    fn runs_reach_past_the_ends_that_keep() {
        let s = Surface::new(10, vec![1, 1, 5, 5, 5, 2]).unwrap();
        assert_eq!(s.radius_at(-100), 1);
        assert_eq!(s.radius_at(15), 2);
        assert_eq!(s.radius_at(1000), 2);
        assert_eq!(s.run(10, |r| r == 1), (i64::MIN, 11));
        assert_eq!(s.run(3, |r| r == 1), (i64::MIN, 11));
        assert_eq!(s.run(13, |r| r == 5), (12, 14));
        assert_eq!(s.run(15, |r| r == 2), (15, i64::MAX));
        assert_eq!(s.run(40, |r| r == 2), (15, i64::MAX));
        assert_eq!(s.run(12, |r| r >= 1), (i64::MIN, i64::MAX));
        assert!(Surface::new(0, Vec::new()).is_err());
    }

    #[test]
    fn roughness_is_bounded_and_fixed_by_seed_and_point() {
        let draws: Vec<i64> = (0..2000).map(|i| roughness_nm(7, i, 300)).collect();
        assert!(draws.iter().all(|d| d.abs() <= 300));
        assert!(draws.iter().any(|&d| d > 250) && draws.iter().any(|&d| d < -250));
        assert_eq!(roughness_nm(7, 5, 300), draws[5]);
        assert_ne!((0..50).map(|i| roughness_nm(8, i, 300)).collect::<Vec<_>>(), draws[..50]);
        assert_eq!(roughness_nm(7, 5, 0), 0);
    }
}

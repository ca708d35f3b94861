//! From points along a path, in steps, to period records on the core's Q16.16 grid.

use finestep_interface::{Increment, PeriodRecord};

use crate::linear::{Machine, PlanError};
use crate::profile::positive;

/// Flag bit of [`PeriodRecord::flags`]: the last period of a block.
pub const FLAG_BLOCK_END: u8 = 1;

/// Position on the Q16.16 grid: steps * 2^16, rounded to nearest.
fn grid(steps: f64) -> i64 {
    (steps * 65536.0).round() as i64
}

/// Refuses a point that is not finite or not within the core's 32-bit step position.
pub(crate) fn check_endpoints(machine: &Machine, point_mm: &[f64]) -> Result<(), PlanError> {
    for (axis, (&scale, &coord)) in machine.steps_per_unit.iter().zip(point_mm).enumerate() {
        positive("steps per unit", scale)?;
        let steps = coord * scale;
        if !steps.is_finite() || steps.abs() >= 2f64.powi(31) {
            return Err(PlanError::OutOfRange { axis, steps });
        }
    }
    Ok(())
}

/// A point rounded to whole steps per axis.
pub(crate) fn to_steps(machine: &Machine, point_mm: &[f64]) -> Vec<i64> {
    point_mm.iter().zip(&machine.steps_per_unit).map(|(&mm, &scale)| (mm * scale).round() as i64).collect()
}

/// One record per point (the position at the end of each period, in steps per axis),
/// the last point replaced by `end_steps` exactly and its record flagged
/// [`FLAG_BLOCK_END`]. Positions are quantised from their exact values, so the
/// increments sum exactly to `end_steps - start_steps` and no rounding accumulates.
pub(crate) fn quantise(
    start_steps: &[i64],
    end_steps: &[i64],
    points: impl ExactSizeIterator<Item = Vec<f64>>,
) -> Result<Vec<PeriodRecord>, PlanError> {
    let count = points.len();
    let mut last_grid: Vec<i64> = start_steps.iter().map(|&s| s << 16).collect();
    let mut records = Vec::with_capacity(count);
    for (index, point) in points.enumerate() {
        let mut record = PeriodRecord::default();
        for axis in 0..start_steps.len() {
            let target = if index + 1 == count { end_steps[axis] << 16 } else { grid(point[axis]) };
            let raw = i32::try_from(target - last_grid[axis]).map_err(|_| PlanError::IncrementTooLarge {
                axis,
                steps: (target - last_grid[axis]) as f64 / 65536.0,
            })?;
            record.inc[axis] = Increment::from_bits(raw);
            last_grid[axis] = target;
        }
        records.push(record);
    }
    if let Some(last) = records.last_mut() {
        last.flags |= FLAG_BLOCK_END;
    }
    Ok(records)
}

//! The joints LinuxCNC drives, read from the machine configuration: what the open-loop
//! files (`config`) and the closed-loop ones (`closed_loop`) both write from.

use finestep_interface::TopParams;
use finestep_planner::config::{CoreLimits, AXIS_NAMES};
use finestep_planner::MachineConfig;

/// The joints of a configuration: (record slot, axis name, steps per unit, max velocity,
/// max acceleration).
pub(crate) struct Joint {
    pub(crate) slot: usize,
    pub(crate) name: &'static str,
    pub(crate) scale: f64,
    pub(crate) max_velocity: f64,
    pub(crate) max_acceleration: f64,
}

pub(crate) fn joints(config: MachineConfig, file: &str) -> anyhow::Result<(Vec<Joint>, MachineConfig, f64)> {
    // The default build's limits (the chip's CAPS are checked again when the HAL
    // component connects).
    let core = CoreLimits::of_build(&TopParams::default());
    let config = config.for_core(core);
    let resolved = config.resolve_in(file)?;
    let joints: Vec<Joint> = (0..AXIS_NAMES.len())
        .filter(|&slot| resolved.axes[slot].present)
        .map(|slot| {
            let axis = &resolved.axes[slot];
            Joint {
                slot,
                name: AXIS_NAMES[slot],
                scale: axis.steps_per_unit,
                max_velocity: axis.max_velocity,
                max_acceleration: axis.max_acceleration,
            }
        })
        .collect();
    Ok((joints, config, resolved.period_s))
}

//! The chip and the configuration it runs, resolved in one place: the co-simulated
//! chip is opened through the host driver (identity, `CAPS`, `CLOCK_HZ`), the machine
//! configuration is resolved once against what it reports, and the result is written to
//! it. `run`, the demo's parts and the benches build on this; every clock, period and
//! drive timing they use or print comes from the [`Resolved`] made here.

use std::collections::BTreeMap;

use anyhow::{bail, Context};
use finestep_host::stream::StreamConfig;
use finestep_host::{AxisSetup, Bus, Caps, GantrySetup, Machine, PinHost, PinTarget, PinTiming, SpiBus};
use finestep_model::top::TopParams;
use finestep_model::{AxisConfig, CoreParams};
use finestep_model::{Increment, PeriodRecord};
use finestep_planner::config::{AxisLimits, CoreLimits, Resolved};
use finestep_planner::MachineConfig;

/// A chip on the host driver's SPI master at its pins.
pub type Chip<T> = Machine<SpiBus<PinHost<T>>>;

/// Records per SPI burst.
pub const BURST: usize = 32;

/// Resets the chip behind `target` and connects to it: checks its identity and reads
/// its capabilities and clock.
pub fn open<T: PinTarget>(target: T) -> anyhow::Result<Chip<T>> {
    let mut host = PinHost::new(target, PinTiming::default());
    host.reset(4)?;
    host.idle(8)?;
    let mut machine = Machine::connect(SpiBus::new(host, 1)).context("connecting to the chip (ID, VERSION, CAPS)")?;
    let n_axes = machine.caps().n_axes;
    machine.bus().set_n_axes(n_axes);
    Ok(machine)
}

/// The core clock a configuration expects before the chip is asked (its `clock_hz`, else
/// the default build's): what a spidev SCK is checked against before anything is sent.
pub fn expected_clock_hz(config: &MachineConfig) -> u32 {
    config.clock_hz.map_or(model_params().clock_hz, |hz| hz as u32)
}

/// What a configuration must fit, as the chip reports it.
pub fn chip_limits(caps: &Caps) -> CoreLimits {
    CoreLimits {
        clock_hz: f64::from(caps.clock_hz),
        p_width: caps.p_width,
        timing_w: caps.timing_w,
        n_axes: caps.n_axes,
        has_pbp: caps.has_pbp,
        step_slots: caps.step_slots,
    }
}

/// The reference model's build, for runs with no chip to ask (`run --fast`, the
/// core-level bench): its `TopParams`, clock included.
pub fn model_params() -> TopParams {
    TopParams::default()
}

/// What a configuration must fit on the model of [`model_params`].
pub fn model_limits() -> CoreLimits {
    CoreLimits::of_build(&model_params())
}

/// The core parameters of the model of [`model_params`].
pub fn model_core_params() -> CoreParams {
    model_params().core_params()
}

/// Resolves `config` (named `file` in errors) against `core`: the only place the CLI
/// resolves a configuration. Returns the configuration bound to that core (for the
/// planner and the checker) and its resolution; an error names the file and the field.
pub fn resolve(config: MachineConfig, core: CoreLimits, file: &str) -> anyhow::Result<(MachineConfig, Resolved)> {
    let config = config.for_core(core);
    let resolved = config.resolve_in(file).with_context(|| {
        format!(
            "the machine configuration does not fit the core ({} MHz, CAPS: P_WIDTH {}, TIMING_W {}, {} axes)",
            core.clock_hz / 1e6,
            core.p_width,
            core.timing_w,
            core.n_axes
        )
    })?;
    Ok((config, resolved))
}

/// The resolved drive timing of record slot `axis`, as the host driver writes it.
pub fn axis_setup(resolved: &Resolved, axis: usize) -> AxisSetup {
    AxisSetup { timing: resolved.timing[axis], ..AxisSetup::default() }
}

/// The same as the core's axis configuration, enabled (for the core-level bench).
pub fn axis_config(resolved: &Resolved, axis: usize) -> AxisConfig {
    let setup = axis_setup(resolved, axis);
    AxisConfig { timing: setup.timing, mode: 0, invert: 0, enable: true }
}

/// Writes `resolved` to the chip: drive timing of every configured axis on its chip axis
/// ([`Resolved::chip_axis`]; and only those enabled), the period, a start level of one record; clears faults and errors. With
/// `[gantry]` enabled, the slave is configured and enabled too, the pair's registers and
/// mode written and the pair engaged (the axes are at rest before a run); a chip
/// without the gantry (CAPS.HAS_GANTRY 0) is refused before anything is written.
pub fn configure<B: Bus>(machine: &mut Machine<B>, resolved: &Resolved) -> anyhow::Result<()> {
    if resolved.gantry.is_some() && !machine.caps().has_gantry {
        bail!(
            "the configuration enables [gantry], but the chip has no gantry (CAPS.HAS_GANTRY 0: a build with \
             HAS_GANTRY 1 and STEP_SHARED 0)"
        );
    }
    let slave = resolved.gantry.map(|g| usize::from(g.slave));
    let mut mask = 0;
    // Each configured slot on its chip axis (the slot itself but with point-by-point,
    // which puts the plane's axes on the chip pair: Resolved::chip_axis).
    for slot in (0..resolved.axes.len()).filter(|&a| resolved.axes[a].present || Some(a) == slave) {
        let axis = resolved.chip_axis[slot];
        machine.configure_axis(axis, &axis_setup(resolved, slot))?;
        mask |= 1 << axis;
    }
    machine.enable_axes(mask)?;
    machine.set_period(resolved.period_clocks)?;
    machine.set_start_level(1)?;
    machine.clear_faults_and_errors()?;
    if let Some(g) = resolved.gantry {
        let setup = GantrySetup {
            master: g.master,
            slave: g.slave,
            enc_master: g.enc_master,
            enc_slave: g.enc_slave,
            tick: g.tick,
            deadband: g.deadband,
            limit: g.limit,
        };
        machine.configure_gantry(&setup)?;
        machine.set_gantry_mode(Some(g.sync))?;
        machine.enable_gantry(true)?;
    }
    Ok(())
}

/// Refuses `records` that move the gantry's slave axis when `resolved` enables the pair
/// (the slave follows the master: its own increments would be dropped), naming `name`.
pub fn check_gantry_records(resolved: &Resolved, records: &[PeriodRecord], name: &str) -> anyhow::Result<()> {
    if let Some(g) = resolved.gantry {
        let (slave, master) = (usize::from(g.slave), usize::from(g.master));
        if let Some(period) = records.iter().position(|r| r.inc[slave] != Increment::ZERO) {
            let names = finestep_planner::config::AXIS_NAMES;
            bail!(
                "{name}: the program moves {} (period {period}), the gantry's slave: it follows {} ([gantry])",
                names[slave],
                names[master]
            );
        }
    }
    Ok(())
}

/// How the CLI streams: bursts of [`BURST`], two of them before the start, a poll every
/// half period.
pub fn stream_config(resolved: &Resolved) -> StreamConfig {
    StreamConfig {
        burst: BURST,
        poll_clocks: u64::from(resolved.period_clocks / 2).max(1),
        prefill: 2 * BURST,
        ..StreamConfig::default()
    }
}

/// The demo's machine: T = 2 ms, the default drives (2 us step and space, 5 us direction
/// set-up and hold), and the axes `steps_per_unit` in record slots 0, 1, ... (the planner
/// names them X, Y, Z, A). The demo's moves stay well within the limits given here.
pub fn demo_config(steps_per_unit: &[f64]) -> MachineConfig {
    let names = finestep_planner::config::AXIS_NAMES;
    let axes: BTreeMap<String, AxisLimits> = names
        .iter()
        .zip(steps_per_unit)
        .map(|(name, &steps_per_unit)| {
            let limits = AxisLimits { steps_per_unit, max_velocity: 50.0, max_acceleration: 500.0, max_jerk: 50_000.0 };
            (name.to_string(), limits)
        })
        .collect();
    MachineConfig { period_ms: 2.0, axes, ..MachineConfig::default() }
}

/// A straight move from the origin to `target` (record slots X, Y, Z, A in axis units) at
/// `feed_mm_s`, planned as a one-block part program by the planner the `run` command
/// uses: trapezoidal feed within the configured limits, exact end on whole steps.
pub fn plan_line(config: &MachineConfig, target: [f64; 4], feed_mm_s: f64) -> anyhow::Result<Vec<PeriodRecord>> {
    let text =
        format!("G90 G64\nG1 X{} Y{} Z{} A{} F{}\nM2\n", target[0], target[1], target[2], target[3], feed_mm_s * 60.0);
    let program = finestep_gcode::parse_str(&text, "<line>")?;
    let planned = finestep_planner::plan_program(config, &program).map_err(|e| anyhow::anyhow!("<line>:{e}"))?;
    Ok(planned.records)
}

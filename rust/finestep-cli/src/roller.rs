//! Seed 000's measured-curve compensation: `finestep measure` traverses the table along
//! the roller while the chip latches both gratings (the table's Z and the gauge's X
//! deviation) on one clock at every period boundary, `finestep compensate` turns the
//! profile into a compensated X(Z) grinding program, and the demo's part 4 measures,
//! compensates, grinds and measures again on the simulated machine.
//!
//! The drive lag is removed by the latch: Z is the table's grating read on the same clock
//! as the gauge, not the commanded position (which leads it by the lag; both are in the
//! profile file). The gauge is zeroed where the traverse starts (the chip's counts start
//! at 0).
//!
//! The simulated machine: X (wheel slide, 1000 steps/mm) and Z (table, 400 steps/mm)
//! with drives lagging 1 ms; a Z grating of 0.5 um on encoder channel 0, the gauge (0.5
//! um) on channel 1. The machine leaves a form error on a straight pass (a taper of 8 um
//! and a crown of 6 um over the roller's 6 mm); the roller to measure is one such pass
//! with +-0.5 um of smooth noise on it; grinding leaves +-0.2 um of roughness.

use std::path::Path;

use anyhow::{bail, Context};
use finestep_cosim::{rtl_top_params, ModelPins, PlantLoop};
use finestep_host::stream::{self, StreamEvent};
use finestep_host::{Bus, EncoderSetup, Machine};
use finestep_model::top::Top;
use finestep_planner::config::Resolved;
use finestep_planner::{MachineConfig, MeasureConfig};
use finestep_plant::roller::roughness_nm;
use finestep_plant::{
    ChannelConfig, CountsPerStep, DriveConfig, EncoderConfig, Mechanics, Plant, PlantConfig, RollerConfig, RollerMode,
    Surface,
};
use finestep_profile::{compensate, form_error, CompensateOptions, Profile, Sample, Target};

use crate::bus::BusTarget;
use crate::machine_setup::{self, Chip};

/// X, Y (unused), Z steps per mm: the planner's slots 0, 1, 2.
const STEPS_PER_MM: [f64; 3] = [1000.0, 400.0, 400.0];
/// Table counts (0.5 um) per Z step.
const Z_COUNTS_PER_STEP: u32 = 5;
/// nm per gauge count (0.5 um).
const GAUGE_NM: u32 = 500;
/// The roller's length, mm, and where the traverse starts and ends.
const ROLLER_MM: f64 = 6.0;
/// The drives' time constant: 1 ms at 50 MHz.
const DRIVE_TAU_CLOCKS: u64 = 50_000;
/// The measuring traverse's feed, mm/s.
const MEASURE_FEED_MM_S: f64 = 20.0;
/// What the demo grinds to: a cylinder 20 um under the nominal radius.
const TARGET_MM: f64 = -0.020;
/// The compensation's noise filter window, mm.
const WINDOW_MM: f64 = 1.5;

/// Surface points (one per table count) over the roller.
fn points() -> usize {
    (ROLLER_MM * STEPS_PER_MM[2] * f64::from(Z_COUNTS_PER_STEP)) as usize + 1
}

fn z_of(point: usize) -> f64 {
    point as f64 / (STEPS_PER_MM[2] * f64::from(Z_COUNTS_PER_STEP))
}

/// The machine's form error at `z`, nm: a taper of 8 um and a crown of 6 um.
fn machine_error_nm(z: f64) -> i64 {
    let u = z / ROLLER_MM;
    (8000.0 * (u - 0.5) + 6000.0 * (1.0 - (2.0 * u - 1.0).powi(2))).round() as i64
}

/// Smooth noise: seeded draws every 0.1 mm, linear between.
fn noise_nm(seed: u64, z: f64, amplitude: i64) -> i64 {
    let node = z / 0.1;
    let (k, u) = (node.floor() as i64, node - node.floor());
    let (a, b) = (roughness_nm(seed, k, amplitude) as f64, roughness_nm(seed, k + 1, amplitude) as f64);
    (a + (b - a) * u).round() as i64
}

/// The roller as a straight pass at X = 0 left it: the machine's form error and noise.
pub fn initial_surface() -> anyhow::Result<Surface> {
    let radius = (0..points()).map(|i| machine_error_nm(z_of(i)) + noise_nm(0xC0FFEE, z_of(i), 500)).collect();
    Ok(Surface::new(0, radius)?)
}

fn plant(mode: RollerMode, surface: Surface) -> anyhow::Result<Plant> {
    let lag = DriveConfig { mechanics: Mechanics::Lag { tau: DRIVE_TAU_CLOCKS }, ..DriveConfig::default() };
    let z_grating = EncoderConfig::linear_grating(CountsPerStep::integer(Z_COUNTS_PER_STEP)?, None);
    let x_grating = EncoderConfig::linear_grating(CountsPerStep::integer(1)?, None);
    let config = PlantConfig {
        drives: vec![lag; 3],
        channels: match mode {
            RollerMode::Measure { .. } => vec![ChannelConfig { axis: 2, encoder: z_grating }],
            RollerMode::Grind { .. } => {
                vec![ChannelConfig { axis: 2, encoder: z_grating }, ChannelConfig { axis: 0, encoder: x_grating }]
            }
        },
        probe: None,
        hand_wheel: None,
    };
    let roller =
        RollerConfig { table_axis: 2, z_counts_per_step: CountsPerStep::integer(Z_COUNTS_PER_STEP)?, surface, mode };
    Ok(Plant::new(config, 0x2011)?.with_roller(roller, 0x2012)?)
}

/// The simulated machine on the reference model's pins, configured (T = 2 ms).
fn connect(plant: Plant) -> anyhow::Result<(Chip<PlantLoop<ModelPins>>, MachineConfig, Resolved)> {
    let mut machine = machine_setup::open(PlantLoop::new(ModelPins(Top::new(rtl_top_params())), plant))?;
    let core = machine_setup::chip_limits(&machine.caps());
    let mut config = machine_setup::demo_config(&STEPS_PER_MM);
    config.measure = MeasureConfig {
        axis: "Z".into(),
        length_mm: ROLLER_MM,
        feed_mm_s: MEASURE_FEED_MM_S,
        axis_channel: 0,
        axis_counts_per_mm: STEPS_PER_MM[2] * f64::from(Z_COUNTS_PER_STEP),
        gauge_channel: 1,
        gauge_um_per_count: f64::from(GAUGE_NM) * 1e-3,
    };
    let (config, resolved) = machine_setup::resolve(config, core, "<roller>")?;
    machine_setup::configure(&mut machine, &resolved)?;
    for channel in 0..2 {
        machine.configure_encoder(channel, &EncoderSetup { filter: 3, ..EncoderSetup::default() })?;
    }
    Ok((machine, config, resolved))
}

/// A measuring traverse of `config.measure`'s axis (Z over the roller): its grating and
/// the gauge latched at every period boundary, read back while the host streams. The
/// grating, the gauge and the steps read from 0 where the traverse starts (the counts
/// the chip shows at rest before it); samples where the axis stands still repeat a point
/// and are dropped, as are those outside the traverse's length.
fn traverse<B: Bus>(machine: &mut Machine<B>, config: &MachineConfig, resolved: &Resolved) -> anyhow::Result<Profile> {
    let m = &config.measure;
    let slot = finestep_planner::config::AXIS_NAMES
        .iter()
        .position(|name| *name == m.axis && config.axes.contains_key(*name))
        .with_context(|| format!("measure.axis: `{}` is not an axis of this machine", m.axis))?;
    let channels = machine.caps().n_enc;
    for (key, channel) in [("measure.axis_channel", m.axis_channel), ("measure.gauge_channel", m.gauge_channel)] {
        if usize::from(channel) >= channels {
            bail!("{key}: channel {channel}, but the chip has {channels} encoder channels (CAPS.N_ENC)");
        }
    }
    let (axis_ch, gauge_ch) = (usize::from(m.axis_channel), usize::from(m.gauge_channel));
    let steps_per_mm = resolved.axes[slot].steps_per_unit;
    let mut target = [0.0; 4];
    target[slot] = m.length_mm;
    let records = machine_setup::plan_line(config, target, m.feed_mm_s)?;
    let start = machine.feedback()?;
    let (z0, x0, s0) = (start.counts[axis_ch], start.counts[gauge_ch], start.steps[slot]);
    let stream_config = machine_setup::stream_config(resolved);
    let stream_config = stream::StreamConfig { poll_clocks: u64::from(resolved.period_clocks / 4), ..stream_config };
    let mut samples: Vec<Sample> = Vec::new();
    let mut last_latch = None;
    let mut first = None;
    let report = stream::run(machine, records.iter().copied(), &stream_config, |machine, event| {
        if event != StreamEvent::Waited {
            return Ok(());
        }
        let snapshot = machine.feedback()?;
        if last_latch == Some(snapshot.latch_time) {
            return Ok(());
        }
        last_latch = Some(snapshot.latch_time);
        let t0 = *first.get_or_insert(snapshot.latch_time);
        samples.push(Sample {
            z_mm: f64::from(snapshot.counts[axis_ch].wrapping_sub(z0)) / m.axis_counts_per_mm,
            x_mm: f64::from(snapshot.counts[gauge_ch].wrapping_sub(x0)) * m.gauge_um_per_count * 1e-3,
            z_commanded_mm: f64::from(snapshot.steps[slot].wrapping_sub(s0)) / steps_per_mm,
            time_s: f64::from(snapshot.latch_time.wrapping_sub(t0)) / resolved.clock_hz,
        });
        Ok(())
    })?;
    if report.stream.underruns != 0 {
        bail!("{} FIFO underruns during the traverse", report.stream.underruns);
    }
    // Samples on the roller, the table moving (at rest the same point repeats).
    samples.dedup_by(|a, b| a.z_mm == b.z_mm);
    let (low, high) = if m.length_mm > 0.0 { (0.0, m.length_mm) } else { (m.length_mm, 0.0) };
    samples.retain(|s| s.z_mm > low && s.z_mm < high);
    if samples.is_empty() {
        bail!(
            "measure: the {} grating (channel {axis_ch}) did not move over the traverse: nothing on the chip's \
             encoder pins, or another channel",
            m.axis
        );
    }
    Ok(Profile { samples, z_resolution_mm: 1.0 / m.axis_counts_per_mm, x_resolution_mm: m.gauge_um_per_count * 1e-3 })
}

/// Measures `surface` on the simulated machine.
fn measure_surface(surface: Surface) -> anyhow::Result<Profile> {
    let gauge = EncoderConfig::linear_grating(CountsPerStep::new(1, GAUGE_NM)?, None);
    let (mut machine, config, resolved) = connect(plant(RollerMode::Measure { gauge }, surface)?)?;
    traverse(&mut machine, &config, &resolved)
}

/// Grinds `surface` with `program` on the simulated machine; returns the new surface.
fn grind(surface: Surface, program: &str) -> anyhow::Result<Surface> {
    let error_nm = (0..points()).map(|i| machine_error_nm(z_of(i))).collect();
    let mode = RollerMode::Grind { wheel_axis: 0, wheel_nm_per_step: 1000, error_nm, roughness_nm: 200, seed: 7 };
    let (mut machine, config, resolved) = connect(plant(mode, surface)?)?;
    let parsed = finestep_gcode::parse_str(program, "compensated.ngc")?;
    let planned = finestep_planner::plan_program(&config, &parsed)
        .map_err(|e| anyhow::anyhow!("compensated.ngc:{}: {}", e.line, e.reason))?;
    let report = stream::run(
        &mut machine,
        planned.records.iter().copied(),
        &machine_setup::stream_config(&resolved),
        |_, _| Ok(()),
    )?;
    if report.stream.underruns != 0 {
        bail!("{} FIFO underruns while grinding", report.stream.underruns);
    }
    let plant = machine.bus().link().target().plant();
    Ok(plant.roller().context("the plant has its roller")?.surface().clone())
}

const PROFILE_COMMENT: &str = "finestep measure: the roller's radius deviation X along Z (seed 000)\n\
    sampled on the chip's position latch at every period boundary: Z grating and gauge on one clock\n\
    z_mm: Z by its grating; x_mm: the gauge (zeroed at the start); z_commanded_mm: the step generator's Z;\n\
    lag_um: how far the commanded Z leads the grating (the drive's lag, removed by taking Z from the grating)";

/// `finestep measure`: a measuring traverse over the simulated roller, or with a bus (the
/// command line's or the configuration's) on that chip with the configuration's
/// `[measure]` traverse and channels; writes `out`.
pub fn measure(out: &Path, bus: Option<BusTarget>, config_path: Option<&Path>) -> anyhow::Result<()> {
    let (config, config_name) = crate::config_file::load_or_builtin(config_path)?;
    let profile = if bus.is_some() || config.bus.is_some() {
        let target = BusTarget::choose(bus, config.bus.as_deref(), &config_name)?;
        let clock_hz = machine_setup::expected_clock_hz(&config);
        let mut machine = crate::bus::open(&target, "measure", clock_hz)?;
        let core = machine_setup::chip_limits(&machine.caps());
        let (config, resolved) = machine_setup::resolve(config, core, &config_name)?;
        machine_setup::configure(&mut machine, &resolved)?;
        let m = &config.measure;
        println!(
            "finestep measure on {target}: {} over {} mm at {} mm/s, grating on channel {}, gauge on channel {}",
            m.axis, m.length_mm, m.feed_mm_s, m.axis_channel, m.gauge_channel
        );
        traverse(&mut machine, &config, &resolved)?
    } else {
        measure_surface(initial_surface()?)?
    };
    let text = profile.to_text(PROFILE_COMMENT);
    std::fs::write(out, text).with_context(|| format!("writing {}", out.display()))?;
    let form = form_error(&profile, &Target::Constant(0.0), WINDOW_MM)?;
    let lag = profile.samples.iter().map(|s| s.z_commanded_mm - s.z_mm).fold(0.0, f64::max);
    println!(
        "finestep measure: {} samples over Z {:.3} to {:.3} mm -> {}; form error {:.2} um peak to valley \
         ({:.2} um filtered), RMS {:.2} um; the drive lag removed: up to {:.1} um",
        profile.samples.len(),
        profile.samples.first().map_or(0.0, |s| s.z_mm),
        profile.samples.last().map_or(0.0, |s| s.z_mm),
        out.display(),
        form.pv_mm * 1e3,
        form.filtered_pv_mm * 1e3,
        form.rms_mm * 1e3,
        lag * 1e3
    );
    Ok(())
}

fn read_profile(path: &Path) -> anyhow::Result<Profile> {
    let text = std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    Ok(Profile::parse(&text, &path.display().to_string())?)
}

/// The demo machine's compensation options: its X acceleration limit.
fn options(window_mm: f64, tolerance_mm: f64) -> CompensateOptions {
    CompensateOptions { window_mm, tolerance_mm, x_acceleration_mm_s2: 500.0, ..CompensateOptions::default() }
}

/// `finestep compensate PROFILE`: the compensated program, to `out` (or stdout).
pub fn compensate_file(
    profile: &Path,
    target: Option<&Path>,
    target_x: f64,
    window_mm: f64,
    tolerance_mm: f64,
    out: Option<&Path>,
) -> anyhow::Result<()> {
    let measured = read_profile(profile)?;
    let target = match target {
        Some(path) => Target::from_profile(&read_profile(path)?)?,
        None => Target::Constant(target_x),
    };
    let c = compensate(&measured, &target, &options(window_mm, tolerance_mm))?;
    match out {
        Some(path) => {
            std::fs::write(path, &c.program).with_context(|| format!("writing {}", path.display()))?;
            eprintln!(
                "finestep compensate: {} G1 moves at F{:.0} -> {}",
                c.path.len() - 1,
                c.feed_mm_min,
                path.display()
            );
        }
        None => print!("{}", c.program),
    }
    Ok(())
}

/// Demo part 4: measure, compensate, grind, measure again; the figures and a plot.
pub fn demo(out: &Path) -> anyhow::Result<()> {
    println!();
    println!("finestep demo, part 4: measured-curve compensation of a roller (seed 000) on the simulated machine");
    println!(
        "  (the model at its pins; gauge and Z grating 0.5 um; the machine leaves a taper of 8 um and a crown of 6 um)"
    );
    let surface = initial_surface()?;
    let before = measure_surface(surface.clone())?;
    let target = Target::Constant(TARGET_MM);
    let profile_path = out.join("roller-before.csv");
    std::fs::write(&profile_path, before.to_text(PROFILE_COMMENT))?;
    let c = compensate(&before, &target, &options(WINDOW_MM, 0.0002))?;
    let program_path = out.join("roller-compensated.ngc");
    std::fs::write(&program_path, &c.program)?;
    let ground = grind(surface, &c.program)?;
    let after = measure_surface(ground)?;
    std::fs::write(out.join("roller-after.csv"), after.to_text(PROFILE_COMMENT))?;
    let f_before = form_error(&before, &target, WINDOW_MM)?;
    let f_after = form_error(&after, &target, WINDOW_MM)?;
    println!(
        "  measured {} samples ({}), compensated: {} G1 moves at F{:.0} ({})",
        before.samples.len(),
        profile_path.display(),
        c.path.len() - 1,
        c.feed_mm_min,
        program_path.display()
    );
    println!("  form error         peak-to-valley   filtered   RMS     (gauge resolution 0.5 um)");
    for (name, f) in [("before", f_before), ("after", f_after)] {
        println!(
            "    {name:<16} {:>10.2} um {:>8.2} um {:>6.2} um",
            f.pv_mm * 1e3,
            f.filtered_pv_mm * 1e3,
            f.rms_mm * 1e3
        );
    }
    let png = out.join("roller.png");
    crate::plot::plot_profiles(&png, &[("before", &before), ("after", &after)], &c.curve)?;
    println!("  plot: {}", png.display());
    if f_after.filtered_pv_mm > 0.25 * f_before.filtered_pv_mm {
        bail!(
            "the compensation left {:.2} um of {:.2} um",
            f_after.filtered_pv_mm * 1e3,
            f_before.filtered_pv_mm * 1e3
        );
    }
    Ok(())
}

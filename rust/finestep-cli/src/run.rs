//! `finestep run FILE.ngc`: a part program through the planner, checked by the
//! independent checker and plotted, then into the chip: streamed over SPI by the host
//! driver into the bus-level top, RTL in lockstep with the model, or through the model
//! core's fast path.

use std::path::Path;

use anyhow::{anyhow, bail, Context};
use finestep_gcode::{BlockKind, MessageKind, Program, SpindleRotation};
use finestep_host::regs::underrun_count;
use finestep_host::stream::{self, RunReport, StreamEvent};
use finestep_host::{Bus, BusError, Machine, Outputs, SpindleSetup};
use finestep_model::{Core, CoreInputs, PeriodRecord};
use finestep_planner::config::AXIS_NAMES;
use finestep_planner::config::{InterpolationMode, Resolved};
use finestep_planner::pbp::{plan_pbp, record_clocks, record_decisions};
use finestep_planner::{
    check_program, plan_program, CheckReport, IoAction, IoEvent, MachineConfig, PlannedProgram, SpindleConfig,
};
use indicatif::{ProgressBar, ProgressStyle};

use crate::bus::BusTarget;
use crate::machine_setup;
use crate::plot::{plot_motion, plot_toolpath, MotionLimits};
use crate::view::{self, Live, Scene};

/// `finestep run --view`: the 3-D view served during the run.
#[derive(Clone, Debug, Default)]
pub struct ViewOptions {
    /// The port on 127.0.0.1 (0: a free one).
    pub port: u16,
    /// Run the fast path at this many times real time (the view follows it); as fast as
    /// it goes without.
    pub pace: Option<f64>,
    /// The page's directory ([`view::web_dir`] without).
    pub web: Option<std::path::PathBuf>,
}

/// How often a run under the view reads the chip back, s (wall clock).
const VIEW_UPDATE_S: f64 = 0.05;

const AXIS_UNITS: [&str; 4] = ["mm", "mm", "mm", "deg"];

fn print_check(report: &CheckReport) {
    println!(
        "  axis  max velocity / limit        max acceleration / limit     max jerk / limit  (units/s, /s^2, /s^3)"
    );
    for a in (0..4).filter(|&a| report.axis_present[a]) {
        let [v, acc, j] = report.axis_max[a];
        let [lv, la, lj] = report.axis_limit[a];
        let jerk_limit = if lj.is_finite() { format!("{lj:.0}") } else { "- (trapezoid)".to_string() };
        println!("  {:<4} {v:>10.3} / {lv:<12.3} {acc:>12.2} / {la:<12.1} {j:>12.0} / {jerk_limit}", AXIS_NAMES[a]);
    }
    println!(
        "  path: max speed {:.3}, at most {:.1} % of the programmed feed; max acceleration {:.1}, max jerk {:.0}",
        report.path_max[0],
        report.max_feed_ratio * 100.0,
        report.path_max[1],
        report.path_max[2]
    );
    println!(
        "  max path deviation {:.5} mm (line {}), {} exact stops on the step",
        report.max_deviation, report.max_deviation_line, report.exact_stops
    );
    if report.passed() {
        println!("  checker: every limit held (quantisation tolerance: 2^-17 steps per position)");
    } else {
        println!("  checker: {} violations; the first:", report.violation_count);
        for v in &report.violations {
            println!("    {v}");
        }
    }
}

/// Configures `chip` for `resolved` and streams `planned` into it, applying its spindle
/// and coolant changes ([`PlannedProgram::events`]) at their exact stops: each once the
/// records before it have run and the axes are at rest ([`stream::run_with_events`]).
/// The spindle is set up from `spindle` when the program uses it; a chip built without
/// the spindle or the logic outputs the program needs is refused before anything moves
/// (`name`:line). `watch` is called with the chip and the count of records queued so far
/// after every burst and every wait for room (`finestep run --view` reads the chip there).
pub fn stream_planned<B: Bus>(
    chip: &mut Machine<B>,
    planned: &PlannedProgram,
    resolved: &Resolved,
    spindle: &SpindleConfig,
    name: &str,
    mut watch: impl FnMut(&mut Machine<B>, u64) -> Result<(), BusError>,
) -> anyhow::Result<RunReport> {
    machine_setup::check_gantry_records(resolved, &planned.records, name)?;
    // Point-by-point records (plan_pbp's) are checked against the chip before anything
    // is written: its interpolator, the pair, the fields, the engine's visit.
    for (index, record) in planned.records.iter().enumerate() {
        if let Some(lanes) = record.pbp_lanes() {
            chip.pbp_record(&lanes, record.flags).with_context(|| {
                format!("{name}:{}: record {index}", planned.lines.get(index).copied().unwrap_or(0))
            })?;
        }
    }
    machine_setup::configure(chip, resolved)?;
    let mut config = machine_setup::stream_config(resolved);
    // A point-by-point record runs for its decisions, not a period.
    config.record_clocks_max =
        planned.records.iter().map(|r| record_clocks(r, resolved.period_clocks)).max().unwrap_or(0);
    let mut queued_so_far = 0;
    let observe = |chip: &mut Machine<B>, event: StreamEvent| {
        if let StreamEvent::Queued { queued } = event {
            queued_so_far = queued;
        }
        watch(chip, queued_so_far)
    };
    let streamed = if planned.events.is_empty() {
        stream::run(chip, planned.records.iter().copied(), &config, observe)?
    } else {
        let caps = chip.caps();
        let setup = SpindleSetup {
            period_clocks: spindle.period_clocks,
            ramp_step: spindle.ramp_step,
            dac: spindle.dac,
            dac_div: spindle.dac_div,
        };
        let mut outputs = Outputs::default();
        let mut spindle_set_up = false;
        for timed in &planned.events {
            let line = timed.event.line;
            match timed.event.action {
                IoAction::Spindle { .. } if !caps.has_spindle => {
                    bail!("{name}:{line}: the program sets the spindle, but the chip has no spindle (CAPS)")
                }
                IoAction::Spindle { .. } if !spindle_set_up => {
                    chip.configure_spindle(&setup)?;
                    spindle_set_up = true;
                }
                IoAction::Coolant { .. } | IoAction::Output { .. } if !caps.has_outputs => {
                    bail!("{name}:{line}: the program sets the coolant or an output, but the chip has no logic outputs (CAPS)")
                }
                IoAction::Coolant { .. } | IoAction::Output { .. } if outputs == Outputs::default() => {
                    outputs = chip.outputs()?
                }
                IoAction::ProbeArm { .. } if caps.n_enc == 0 => {
                    bail!("{name}:{line}: the program probes (G38.x), but the chip has no probe input (no encoder bank, CAPS)")
                }
                IoAction::WaitInput { .. } => {
                    bail!("{name}:{line}: unsupported: M66 on this chip (it has no general inputs to wait on or read)")
                }
                IoAction::AnalogOutput { .. } => bail!(
                    "{name}:{line}: unsupported: M67/M68 on this chip (it has no analog outputs: its DAC is the spindle's)"
                ),
                IoAction::UserMCode { code, .. } => bail!(
                    "{name}:{line}: M{code} runs a user M-code program, which `finestep run` does not do yet (the planner carries it as an event)"
                ),
                _ => {}
            }
        }
        // The probe moves' outcomes, in order: whether the latch saw the probe change.
        let mut probes: Vec<(usize, bool, bool)> = Vec::new();
        let events = planned.events.iter().map(|timed| (timed.period, timed.event.clone()));
        let streamed =
            stream::run_with_events(chip, planned.records.iter().copied(), events, &config, observe, |chip, event| {
                match event.action {
                    IoAction::Spindle { rotation, fraction, .. } => chip.set_spindle(
                        rotation != SpindleRotation::Off,
                        rotation == SpindleRotation::CounterClockwise,
                        setup.level_for(fraction),
                    ),
                    IoAction::Output { index, on } => {
                        let bit = 1u8 << index;
                        outputs.gpio = if on { outputs.gpio | bit } else { outputs.gpio & !bit };
                        chip.set_outputs(&outputs)
                    }
                    IoAction::Coolant { mist, flood } => {
                        outputs.mist = mist;
                        outputs.flood = flood;
                        chip.set_outputs(&outputs)
                    }
                    // The latch's event: the probe's signal going active (contact), or, for
                    // G38.4/G38.5, inactive (armed with the polarity inverted).
                    IoAction::ProbeArm { on_contact, .. } => chip.arm_probe(on_contact, PROBE_FILTER),
                    // A chip with one position snapshot (VERSION.ONE_SNAPSHOT) holds the
                    // probe's positions in POSITION once read: handed back to the period
                    // latch, or the run's later position reads would be refused.
                    IoAction::ProbeCheck { must_change } => {
                        let hit = chip.probe_hit()?;
                        probes.push((event.line, must_change, hit.is_some()));
                        if hit.is_some() {
                            chip.release_probe_snapshot()?;
                        }
                        Ok(())
                    }
                    IoAction::Message { .. } => {
                        print_message(name, &event);
                        Ok(())
                    }
                    // Refused above.
                    IoAction::WaitInput { .. } | IoAction::AnalogOutput { .. } | IoAction::UserMCode { .. } => Ok(()),
                }
            })?;
        // LinuxCNC stops a G38.2/G38.4 move whose probe did not change with an error.
        if let Some((line, ..)) = probes.iter().find(|&&(_, must, hit)| must && !hit) {
            bail!("{name}:{line}: the probe move ended without the probe changing (G38.2/G38.4 need it to)");
        }
        streamed
    };
    if streamed.stream.underruns != 0 {
        bail!("{} FIFO underruns", streamed.stream.underruns);
    }
    Ok(streamed)
}

/// Shows a MSG or DEBUG message (`name`:line: MSG: text on standard output), when the
/// motion before it has ended.
fn print_message(name: &str, event: &IoEvent) {
    if let IoAction::Message { text, .. } = &event.action {
        println!("{name}:{}: MSG: {text}", event.line);
    }
}

/// The probe input's filter (`PROBE_CONTROL.FILTER`, samples that must agree) for G38.x.
const PROBE_FILTER: u8 = 2;

pub fn run(
    file: &Path,
    fast: bool,
    bus: Option<BusTarget>,
    config_path: Option<&Path>,
    profile: Option<&str>,
    out: &Path,
    view: Option<&ViewOptions>,
) -> anyhow::Result<()> {
    let (mut config, config_name) = crate::config_file::load_or_builtin(config_path)?;
    crate::config_file::set_profile(&mut config, profile);
    let bus = BusTarget::choose(bus, config.bus.as_deref(), &config_name)?;
    // LinuxCNC's parameter file: the program starts from what the last one left and its
    // persistent parameters are written back when it has run to its end (before a
    // `--view` run goes on serving its page).
    let parameter_file = crate::parameter_file::path_of(config.parameter_file.as_deref(), config_path);
    let mut options = finestep_gcode::Options::default();
    if let Some(path) = &parameter_file {
        options.parameters = crate::parameter_file::load(path)?;
    }
    // The machine's INI file, for `#<_ini[section]name>` (relative to the configuration
    // as the parameter file is).
    if let Some(path) = crate::parameter_file::path_of(config.ini_file.as_deref(), config_path) {
        let text = std::fs::read_to_string(&path).with_context(|| format!("reading {}", path.display()))?;
        options.ini = finestep_gcode::Options::read_ini(&text);
    }
    options.user_m_path = config
        .user_m_path
        .iter()
        .filter_map(|dir| crate::parameter_file::path_of(Some(dir.as_path()), config_path))
        .collect();
    let (program, parameters) = finestep_gcode::parse_file_with_parameters(file, &options)?;
    let write_back = || -> anyhow::Result<()> {
        if let Some(path) = &parameter_file {
            let generation = crate::parameter_file::save(path, &parameters)?;
            println!("  parameters: {} written (generation {generation})", path.display());
        }
        Ok(())
    };
    run_program_on(&program, &file.display().to_string(), fast, &bus, config, &config_name, out, view, &write_back)
}

/// Plans, checks, plots and runs `program` (named `name` in messages and plot files) on
/// the machine `config` (named `config_name` in errors): on the chip on `bus`, whose
/// CAPS and clock the configuration is resolved against, or with `fast` on the model's
/// build (no chip); `on_end` runs when it has run to its end without an error. With
/// `view`, the 3-D view is served during the run and after it, until
/// the process ends.
#[allow(clippy::too_many_arguments)]
pub fn run_program_on(
    program: &Program,
    name: &str,
    fast: bool,
    bus: &BusTarget,
    config: MachineConfig,
    config_name: &str,
    out: &Path,
    view: Option<&ViewOptions>,
    on_end: &dyn Fn() -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    let stem = Path::new(name).file_stem().map(|s| s.to_string_lossy().to_string()).unwrap_or_else(|| "run".into());
    let clock_hz = machine_setup::expected_clock_hz(&config);
    let mut chip = if fast { None } else { Some(crate::bus::open(bus, &stem, clock_hz)?) };
    let core = match &chip {
        Some(chip) => machine_setup::chip_limits(&chip.caps()),
        None => machine_setup::model_limits(),
    };
    if config.interpolation.mode == InterpolationMode::Pbp {
        if view.is_some() {
            bail!("{config_name}: interpolation.mode = \"pbp\": --view is not supported in point-by-point mode yet");
        }
        // The chip's CAPS, or the model's build with --fast.
        if !core.has_pbp {
            return Err(ChipLacksPbp { config: config_name.to_string() }.into());
        }
        let (config, resolved) = machine_setup::resolve(config, core, config_name)?;
        return run_pbp(chip.as_mut(), program, name, bus, &config, &resolved, on_end);
    }
    let (config, resolved) = machine_setup::resolve(config, core, config_name)?;
    let planned = plan_program(&config, program).map_err(|e| anyhow!("{name}:{}: {}", e.line, e.reason))?;
    let records = &planned.records;
    machine_setup::check_gantry_records(&resolved, records, name)?;
    for note in &planned.notes {
        println!("  note: {note}");
    }
    // PRINT goes to standard error and the log comments to their file as the program is
    // interpreted (LinuxCNC's interpreter writes them while reading ahead, not in step
    // with the motion).
    let mut log = finestep_gcode::LogFile::default();
    for block in &program.blocks {
        match &block.kind {
            BlockKind::Message { kind: MessageKind::Print, text } => eprintln!("{name}:{}: PRINT: {text}", block.line),
            BlockKind::Message { kind, text } => {
                log.apply(*kind, text).with_context(|| format!("{name}:{}", block.line))?
            }
            _ => {}
        }
    }
    log.close().with_context(|| format!("{name}: the log file"))?;
    println!(
        "finestep run {}: {} elements, {} periods of {} ms: {:.3} s of machining ({:?} profile), {}",
        name,
        planned.elements,
        records.len(),
        resolved.period_s * 1e3,
        records.len() as f64 * resolved.period_s,
        resolved.profile,
        if fast {
            "model fast path".to_string()
        } else if bus.is_lockstep() {
            "streamed over SPI; RTL in lockstep with the model, every pin every clock".to_string()
        } else {
            format!("streamed over SPI on {bus}")
        }
    );
    let report = check_program(&config, program, records)?;
    print_check(&report);
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let toolpath = out.join(format!("{stem}-toolpath.png"));
    let motion = out.join(format!("{stem}-motion.png"));
    let scene = Scene::new(name, program, &config, &resolved, &planned, &report.samples)?;
    let programmed: Vec<[f64; 3]> =
        scene.programmed.points.chunks(3).map(|p| [f64::from(p[0]), f64::from(p[1]), f64::from(p[2])]).collect();
    plot_toolpath(&toolpath, &programmed, &report.samples)?;
    plot_motion(&motion, &report.samples, report.period_s, &motion_limits(program, &planned, &report))?;
    println!("  plots: {} {}", toolpath.display(), motion.display());

    let source = if fast {
        "the model's fast path".to_string()
    } else if bus.is_lockstep() {
        "the co-simulated chip (RTL in lockstep with the model), read back over SPI".to_string()
    } else {
        format!("the chip on {bus}, read back")
    };
    let viewer = match view {
        None => None,
        Some(options) => {
            let live = Live::default();
            {
                let mut state = live.lock();
                state.source = source;
                state.running = true;
                state.periods = scene.periods;
            }
            let web = options.web.clone().unwrap_or_else(view::web_dir);
            let server = view::serve(options.port, &web, &scene, live.clone())?;
            println!("view-figures {}", scene.figures());
            println!("  view: {} (follows the run)", server.url());
            Some((server, live, options.pace.filter(|p| *p > 0.0)))
        }
    };
    let result = run_records(&mut chip, &planned, &resolved, &config, name, fast, viewer.as_ref().map(|v| (&v.1, v.2)));
    let result = result.and_then(|(positions, cycles)| {
        report_end(&planned, &resolved, &positions, cycles, fast, bus)?;
        if !report.passed() {
            bail!("the checker found {} violations", report.violation_count);
        }
        on_end()
    });
    if let Some((server, live, _)) = viewer {
        {
            let mut state = live.lock();
            state.running = false;
            state.done = true;
            if let Err(error) = &result {
                state.errors.push(format!("{error:#}"));
            }
            println!(
                "view-final {}",
                serde_json::json!({"period": state.period, "position": state.position, "errors": state.errors.len()})
            );
        }
        if let Err(error) = &result {
            eprintln!("Error: {error:#}");
        }
        println!("  view: the run has ended; still serving {} (Ctrl-C ends)", server.url());
        server.wait();
    }
    result
}

/// A point-by-point configuration (`[interpolation] mode = "pbp"`) on a chip without
/// the interpolator (`VERSION.HAS_PBP` 0): refused before anything is written.
#[derive(Debug)]
pub struct ChipLacksPbp {
    /// The configuration's name.
    pub config: String,
}

impl std::fmt::Display for ChipLacksPbp {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{}: interpolation.mode = \"pbp\", but the chip has no point-by-point interpolator (VERSION.HAS_PBP 0)",
            self.config
        )
    }
}

impl std::error::Error for ChipLacksPbp {}

/// `finestep run` in point-by-point mode: `program` planned by [`plan_pbp`] (G1/G2/G3 in
/// the plane as point-by-point records on the chip pair, G0 as the DDA's records, the
/// spindle and coolant at their exact stops), its decision rates checked against
/// `interpolation.max_decision_hz`, streamed into `chip` (or, with none, run on the
/// model's core through its fast path: [`run_pbp_on_model`]), and the end positions read
/// back (`POSITION`, on the chip axes the configuration maps the slots to) checked against
/// where the records end, exactly.
fn run_pbp<B: Bus>(
    chip: Option<&mut Machine<B>>,
    program: &Program,
    name: &str,
    bus: &BusTarget,
    config: &MachineConfig,
    resolved: &Resolved,
    on_end: &dyn Fn() -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    let pbp = resolved.pbp.context("point-by-point mode without its resolution")?;
    let plan = plan_pbp(config, program).map_err(|e| anyhow!("{}", e.in_file(name)))?;
    let planned = &plan.planned;
    for note in &planned.notes {
        println!("  note: {note}");
    }
    for block in &program.blocks {
        if let BlockKind::Message { kind: MessageKind::Print, text } = &block.kind {
            eprintln!("{name}:{}: PRINT: {text}", block.line);
        }
    }
    let [u, v] = pbp.slots;
    let dda = planned.records.len() - plan.pbp_records;
    println!(
        "finestep run {name}: point-by-point on chip pair {} ({} on chip axis {}, {} on {}): {} pbp records ({} decisions) for G1/G2/G3, {} DDA records of {} ms for G0: {:.3} s of machining, {}",
        pbp.pair,
        AXIS_NAMES[u],
        resolved.chip_axis[u],
        AXIS_NAMES[v],
        resolved.chip_axis[v],
        plan.pbp_records,
        plan.decisions,
        dda,
        resolved.period_s * 1e3,
        plan.clocks as f64 / resolved.clock_hz,
        if chip.is_none() {
            "model fast path".to_string()
        } else if bus.is_lockstep() {
            "streamed over SPI; RTL in lockstep with the model, every pin every clock".to_string()
        } else {
            format!("streamed over SPI on {bus}")
        }
    );
    // The rate: one step per decision, so no axis steps faster than the decisions come.
    for (index, record) in planned.records.iter().enumerate() {
        if let Some((_, tick_div)) = record_decisions(record) {
            if tick_div + 1 < pbp.min_interval {
                bail!(
                    "{name}:{}: a decision every {} clocks, faster than interpolation.max_decision_hz or the drive timing allow ({} clocks)",
                    planned.lines[index],
                    tick_div + 1,
                    pbp.min_interval
                );
            }
        }
    }
    if let Some(interval) = plan.min_interval {
        println!(
            "  fastest decision rate {:.0} Hz, a decision every {interval} clocks (limit {} Hz: {} clocks with the drive timing)",
            resolved.clock_hz / f64::from(interval),
            pbp.max_decision_hz,
            pbp.min_interval
        );
    }
    let fast = chip.is_none();
    // The steps moved per chip axis and the clocks.
    let (moved, cycles) = match chip {
        Some(chip) => {
            let start = chip.positions()?.steps;
            let streamed = stream_planned(chip, planned, resolved, &config.spindle, name, |_, _| Ok(()))?;
            println!(
                "  {} records in {} bursts, {} underruns",
                streamed.stream.records, streamed.stream.bursts, streamed.stream.underruns
            );
            let moved = streamed.end.steps.iter().zip(&start).map(|(end, start)| end.wrapping_sub(*start)).collect();
            (moved, streamed.cycles)
        }
        None => run_pbp_on_model(planned, resolved, name)?,
    };
    // Back in slot order (X, Y, Z, A).
    let moved: Vec<i32> = (0..4).map(|slot| moved.get(resolved.chip_axis[slot]).copied().unwrap_or(0)).collect();
    report_end(planned, resolved, &moved, cycles, fast, bus)?;
    on_end()
}

/// `run --fast` in point-by-point mode: the records (pbp and DDA, in chip-axis lanes) fed
/// to the model's core ([`machine_setup::model_core_params`], which has the pbp block)
/// through its fast path, each configured slot's drive timing on its chip axis as
/// [`machine_setup::configure`] writes it to a chip. The core takes the next record only
/// once a pbp record has run out, so an idle record offered after the last one is taken
/// only when the motion has ended; two periods more let the last steps reach the pins.
/// A record the core refused (`record_error`) or an axis's rate or lost-step flag fails
/// the run, as the chip's error bits do. Returns the steps moved per chip axis and the
/// clocks; the spindle and coolant are not carried out (the core alone).
fn run_pbp_on_model(planned: &PlannedProgram, resolved: &Resolved, name: &str) -> anyhow::Result<(Vec<i32>, u64)> {
    let machine_events = planned.events.iter().filter(|t| !matches!(t.event.action, IoAction::Message { .. })).count();
    if machine_events != 0 {
        println!(
            "  note: the fast path runs the motion core alone: {machine_events} spindle/coolant changes not carried out"
        );
    }
    let mut inputs =
        CoreInputs { run: true, period_clocks: resolved.period_clocks, rec_valid: true, ..Default::default() };
    for slot in (0..resolved.axes.len()).filter(|&a| resolved.axes[a].present) {
        inputs.axes[resolved.chip_axis[slot]] = machine_setup::axis_config(resolved, slot);
    }
    let mut core = Core::new(machine_setup::model_core_params());
    let mut events = Vec::new();
    let idle = PeriodRecord::default();
    for record in planned.records.iter().chain(std::iter::once(&idle)) {
        inputs.record = *record;
        while !core.run_chunk_fast(&inputs, u64::MAX, &mut events).consumed {}
        events.clear();
    }
    inputs.rec_valid = false;
    core.run_chunk_fast(&inputs, 2 * u64::from(resolved.period_clocks), &mut events);
    let outputs = core.outputs();
    if outputs.record_error() {
        bail!("{name}: the model's core refused a record (record_error)");
    }
    for axis in 0..core.params().n_axes {
        if outputs.rate_error(axis) || outputs.step_lost(axis) {
            bail!("{name}: chip axis {axis} stepped faster than its drive timing allows (rate or lost-step flag)");
        }
    }
    Ok((outputs.positions.iter().map(|&p| p as i32).collect(), core.cycle()))
}

/// The motion plot's limits: the programmed feed of the block each period runs on, and the
/// norms of the present axes' acceleration and jerk limits (the checker's path bounds).
fn motion_limits(program: &Program, planned: &PlannedProgram, report: &CheckReport) -> MotionLimits {
    let feeds: std::collections::HashMap<usize, f64> = program
        .blocks
        .iter()
        .filter_map(|b| match b.kind {
            BlockKind::Linear { feed_mm_per_min, .. }
            | BlockKind::Arc { feed_mm_per_min, .. }
            | BlockKind::Nurbs { feed_mm_per_min, .. } => Some((b.line, feed_mm_per_min / 60.0)),
            _ => None,
        })
        .collect();
    let norm = |k: usize| -> f64 {
        (0..4).filter(|&a| report.axis_present[a]).map(|a| report.axis_limit[a][k].powi(2)).sum::<f64>().sqrt()
    };
    MotionLimits {
        feed: planned.lines.iter().map(|line| feeds.get(line).copied().unwrap_or(f64::NAN)).collect(),
        acceleration: norm(1),
        jerk: norm(2),
    }
}

/// The position of `steps` in units of `resolved`'s axes, x, y, z.
fn units(resolved: &Resolved, steps: &[i32]) -> [f64; 3] {
    let mut out = [0.0; 3];
    for (axis, slot) in out.iter_mut().enumerate() {
        if resolved.axes[axis].present {
            *slot = f64::from(steps.get(axis).copied().unwrap_or(0)) / resolved.axes[axis].steps_per_unit;
        }
    }
    out
}

/// Runs `planned`'s records on `chip` (or the model's fast path when `fast`), updating
/// `live` (and pacing the fast path at its factor) when given: the steps moved per axis
/// and the clock cycles.
#[allow(clippy::too_many_arguments)]
fn run_records<B: Bus>(
    chip: &mut Option<Machine<B>>,
    planned: &PlannedProgram,
    resolved: &Resolved,
    config: &MachineConfig,
    name: &str,
    fast: bool,
    live: Option<(&Live, Option<f64>)>,
) -> anyhow::Result<(Vec<i32>, u64)> {
    let records = &planned.records;

    let period_clocks = resolved.period_clocks;
    let started = std::time::Instant::now();
    let mut last_update = f64::NEG_INFINITY;
    let progress = ProgressBar::new(records.len() as u64)
        .with_style(ProgressStyle::with_template("  {bar:40} {pos}/{len} periods {per_sec} {msg}")?);
    let drain = 2 * u64::from(period_clocks);
    if fast && resolved.gantry.is_some() {
        println!("  note: the fast path runs the motion core alone: [gantry] not carried out (the slave stays)");
    }
    let is_message = |timed: &&finestep_planner::TimedEvent| matches!(timed.event.action, IoAction::Message { .. });
    let machine_events = planned.events.iter().filter(|timed| !is_message(timed)).count();
    if fast && machine_events != 0 {
        println!(
            "  note: the fast path runs the motion core alone: {machine_events} spindle/coolant changes not carried out"
        );
    }
    let (positions, cycles) = match chip {
        None => {
            let mut inputs = CoreInputs { run: true, period_clocks, rec_valid: true, ..Default::default() };
            for (axis, slot) in inputs.axes.iter_mut().enumerate().take(resolved.timing.len()) {
                *slot = machine_setup::axis_config(resolved, axis);
            }
            let mut core = Core::new(machine_setup::model_core_params());
            let mut events = Vec::new();
            // The messages, shown as the run reaches them.
            let mut messages = planned.events.iter().filter(is_message).peekable();
            for (index, record) in records.iter().enumerate() {
                while let Some(timed) = messages.next_if(|timed| timed.period <= index as u64) {
                    print_message(name, &timed.event);
                }
                inputs.record = *record;
                while !core.run_chunk_fast(&inputs, u64::MAX, &mut events).consumed {}
                events.clear();
                if index % 1024 == 0 {
                    progress.set_position(index as u64);
                    progress.set_message(format!("line {}", planned.lines[index]));
                }
                if let Some((live, pace)) = live {
                    if let Some(pace) = pace {
                        let due = index as f64 * resolved.period_s / pace;
                        let now = started.elapsed().as_secs_f64();
                        if due > now {
                            std::thread::sleep(std::time::Duration::from_secs_f64(due - now));
                        }
                    }
                    let now = started.elapsed().as_secs_f64();
                    if now - last_update >= VIEW_UPDATE_S {
                        last_update = now;
                        let steps = core.outputs().positions.map(|p| p as i32);
                        let position = units(resolved, &steps);
                        let mut state = live.lock();
                        state.period = index as u64;
                        state.queued = index as u64 + 1;
                        state.position = position;
                        state.trail.push([position[0], position[1], position[2], index as f64]);
                    }
                }
            }
            inputs.rec_valid = false;
            core.run_chunk_fast(&inputs, drain, &mut events);
            for timed in messages {
                print_message(name, &timed.event);
            }
            let steps = core.outputs().positions.map(|p| p as i32);
            if let Some((live, _)) = live {
                let position = units(resolved, &steps);
                let mut state = live.lock();
                state.period = records.len() as u64;
                state.queued = records.len() as u64;
                state.position = position;
                state.trail.push([position[0], position[1], position[2], records.len() as f64]);
            }
            (steps.to_vec(), core.cycle())
        }
        Some(chip) => {
            // The program's origin is where the axes stand when it starts (a served chip
            // or a board keeps its positions from the run before).
            let start = chip.positions()?.steps;
            let underruns_before = underrun_count::COUNT.get(chip.bus().read_one(underrun_count::ADDR)?);
            let streamed = stream_planned(chip, planned, resolved, &config.spindle, name, |chip, queued| {
                progress.set_position(queued);
                if let Some(line) = planned.lines.get((queued as usize).saturating_sub(1)) {
                    progress.set_message(format!("line {line}"));
                }
                let Some((live, _)) = live else { return Ok(()) };
                let now = started.elapsed().as_secs_f64();
                if now - last_update < VIEW_UPDATE_S {
                    return Ok(());
                }
                // A tripped probe holds the position registers (ONE_SNAPSHOT) until the
                // run's probe check releases them and a period boundary passes: the view
                // skips its update until then; the run goes on.
                let positions = match chip.positions() {
                    Err(BusError::ProbeHoldsPositions) => return Ok(()),
                    positions => positions?,
                };
                last_update = now;
                let steps: Vec<i32> = positions.steps.iter().zip(&start).map(|(p, s)| p.wrapping_sub(*s)).collect();
                let (level, free) = chip.fifo()?;
                let underruns = underrun_count::COUNT.get(chip.bus().read_one(underrun_count::ADDR)?);
                let position = units(resolved, &steps);
                let period = queued.saturating_sub(u64::from(level));
                let mut state = live.lock();
                state.queued = queued;
                state.period = period;
                state.fifo = Some([level, free]);
                state.underruns = u64::from(underruns.wrapping_sub(underruns_before));
                state.position = position;
                state.trail.push([position[0], position[1], position[2], period as f64]);
                Ok(())
            });
            let streamed = match streamed {
                Ok(streamed) => streamed,
                Err(error) => {
                    progress.finish_and_clear();
                    return Err(error);
                }
            };
            let moved: Vec<i32> =
                streamed.end.steps.iter().zip(start).map(|(end, start)| end.wrapping_sub(start)).collect();
            if let Some((live, _)) = live {
                let position = units(resolved, &moved);
                let mut state = live.lock();
                state.queued = records.len() as u64;
                state.period = records.len() as u64;
                state.fifo = Some([0, chip.caps().fifo_depth as u32]);
                state.underruns = u64::from(streamed.stream.underruns);
                state.position = position;
                state.trail.push([position[0], position[1], position[2], records.len() as f64]);
            }
            (moved, streamed.cycles)
        }
    };
    progress.finish_and_clear();
    Ok((positions, cycles))
}

/// Prints the end of a run: steps moved per axis against the programmed end; fails when
/// an axis ended off it.
fn report_end(
    planned: &PlannedProgram,
    resolved: &Resolved,
    positions: &[i32],
    cycles: u64,
    fast: bool,
    bus: &BusTarget,
) -> anyhow::Result<()> {
    println!("  axis   steps moved   end position   programmed end   error");
    let mut worst = 0i64;
    for axis in (0..4).filter(|&a| resolved.axes[a].present) {
        let scale = resolved.axes[axis].steps_per_unit;
        let steps = i64::from(positions[axis]);
        let target = (planned.end[axis] * scale).round() as i64;
        worst = worst.max((steps - target).abs());
        println!(
            "  {:<4} {:>12} {:>12.4} {:<3} {:>12.4} {:<3} {:>4} steps",
            AXIS_NAMES[axis],
            steps,
            steps as f64 / scale,
            AXIS_UNITS[axis],
            planned.end[axis],
            AXIS_UNITS[axis],
            steps - target
        );
    }
    println!(
        "  {cycles} clock cycles{}",
        if !fast && bus.is_lockstep() { ", bit-exact RTL against the model" } else { "" }
    );
    if worst != 0 {
        bail!("the pulse train ended {worst} steps from the programmed end");
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use finestep_cosim::{rtl_top_params, ModelPins};
    use finestep_host::pins::layout::{
        OUT_COOLANT_FLOOD, OUT_COOLANT_MIST, OUT_GPIO0, OUT_PIN_A0, OUT_PIN_B0, OUT_SPINDLE_EN, OUT_SPINDLE_PWM,
    };
    use finestep_host::stream::RunReport;
    use finestep_host::{BusError, PinHost, PinTarget, PinTiming, SpiBus};
    use finestep_model::top::Top;

    /// The model at its pins, one clock at a time: chip axes 0 and 1 counted from their
    /// step and direction pins (step/dir mode: A steps on its rising edge, B high
    /// forward) with the cycle of each step, the spindle PWM's rising edges, and every
    /// change of the `watched` output pins with the two positions then.
    struct Recorder {
        inner: ModelPins,
        watched: u64,
        cycle: u64,
        at: [i64; 2],
        steps: [Vec<u64>; 2],
        pwm_rises: u64,
        changes: Vec<(u64, u64, [i64; 2])>,
    }

    impl Recorder {
        fn new(params: finestep_model::top::TopParams, watched: u64) -> Self {
            Recorder {
                inner: ModelPins(Top::new(params)),
                watched,
                cycle: 0,
                at: [0; 2],
                steps: [vec![], vec![]],
                pwm_rises: 0,
                changes: vec![],
            }
        }
    }

    impl PinTarget for Recorder {
        fn drive(&mut self, inputs: u64, cycles: u64) -> Result<(), BusError> {
            for _ in 0..cycles {
                let before = self.inner.outputs();
                self.inner.drive(inputs, 1)?;
                let now = self.inner.outputs();
                self.cycle += 1;
                for axis in 0..2 {
                    let (a, b) = (OUT_PIN_A0 + axis as u32, OUT_PIN_B0 + axis as u32);
                    if now >> a & 1 != 0 && before >> a & 1 == 0 {
                        self.at[axis] += if now >> b & 1 != 0 { 1 } else { -1 };
                        self.steps[axis].push(self.cycle);
                    }
                }
                if now >> OUT_SPINDLE_PWM & 1 != 0 && before >> OUT_SPINDLE_PWM & 1 == 0 {
                    self.pwm_rises += 1;
                }
                if (now ^ before) & self.watched != 0 {
                    self.changes.push((self.cycle, now & self.watched, self.at));
                }
            }
            Ok(())
        }

        fn outputs(&self) -> u64 {
            self.inner.outputs()
        }
    }

    /// The spindle enable, mist, flood and general output 1 pins.
    const WATCHED: u64 = 1 << OUT_SPINDLE_EN | 1 << OUT_COOLANT_MIST | 1 << OUT_COOLANT_FLOOD | 1 << (OUT_GPIO0 + 1);

    type RecordedChip = Machine<SpiBus<PinHost<Recorder>>>;

    /// `finestep run`'s machinery (resolution against the chip, planner, streamer with
    /// events) on the model's pins behind a recorder: `text` (named `name`) planned with
    /// `events` events and streamed; the chip and the configuration it was resolved to.
    fn stream_on_recorded_pins(text: &str, name: &str, events: usize) -> (RecordedChip, MachineConfig) {
        let mut host = PinHost::new(Recorder::new(rtl_top_params(), WATCHED), PinTiming::default());
        host.reset(4).unwrap();
        host.idle(8).unwrap();
        let mut chip = Machine::connect(SpiBus::new(host, 1)).unwrap();
        let n_axes = chip.caps().n_axes;
        chip.bus().set_n_axes(n_axes);
        let limits = machine_setup::chip_limits(&chip.caps());
        let (config, resolved) = machine_setup::resolve(MachineConfig::default(), limits, "<built-in>").unwrap();
        let program = finestep_gcode::parse_str(text, name).unwrap();
        let planned = plan_program(&config, &program).unwrap();
        assert_eq!(planned.events.len(), events);
        let report = stream_planned(&mut chip, &planned, &resolved, &config.spindle, name, |_, _| Ok(())).unwrap();
        assert_eq!(report.stream.underruns, 0);
        assert_eq!(report.end.steps[0], 3 * 800);
        (chip, config)
    }

    /// `finestep run`'s machinery (resolution against the chip, planner, streamer with
    /// events) on the model's pins: the spindle turns on with X at rest at 1 mm, flood at
    /// 2 mm, both off at 3 mm, and X moves only between them.
    #[test]
    fn spindle_and_coolant_switch_on_the_pins_between_the_moves() {
        let text = "G1 X1 F600\nM3 S1000\nG1 X2\nM8\nG1 X3\nM5 M9\nM2\n";
        let (mut chip, _) = stream_on_recorded_pins(text, "io.ngc", 4);
        let recorder = chip.bus().link_mut().target();
        assert_eq!(recorder.at[0], 3 * 800);
        // Each pin change with X's position then: exactly the block's point.
        let (en, flood) = (1 << OUT_SPINDLE_EN, 1 << OUT_COOLANT_FLOOD);
        let states: Vec<(u64, i64)> = recorder.changes.iter().map(|&(_, pins, at)| (pins, at[0])).collect();
        assert_eq!(states, vec![(en, 800), (en | flood, 1600), (flood, 2400), (0, 2400)], "{:?}", recorder.changes);
        // X at rest around each change: no step within four full-feed step intervals
        // (10 mm/s at 800 steps/mm: one step per 6250 clocks) either side, where blended
        // moves would pass X1 and X2 at full feed.
        let quiet = 4 * 6250;
        for &(cycle, _, _) in &recorder.changes {
            let before = recorder.steps[0].iter().rev().find(|&&s| s <= cycle).copied().unwrap_or(0);
            let after = recorder.steps[0].iter().find(|&&s| s > cycle).copied().unwrap_or(u64::MAX);
            assert!(
                cycle - before > quiet && after - cycle > quiet,
                "steps at {before} and {after}, change at {cycle}"
            );
        }
        // The spindle ran (PWM at 1000/24000 of full level) while enabled.
        assert!(recorder.pwm_rises > 10, "{}", recorder.pwm_rises);
    }

    /// M64/M65 (and M62/M63) reach the chip's general output pin at rest where they are
    /// written: output 1 on with X at 1 mm, off at 2 mm.
    #[test]
    fn digital_outputs_switch_on_the_pins_between_the_moves() {
        let text = "G1 X1 F600\nM64 P1\nG1 X2\nM63 P1\nG1 X3\nM2\n";
        let (mut chip, config) = stream_on_recorded_pins(text, "gpio.ngc", 2);
        let recorder = chip.bus().link_mut().target();
        let states: Vec<(u64, i64)> = recorder.changes.iter().map(|&(_, pins, at)| (pins, at[0])).collect();
        assert_eq!(states, vec![(1 << (OUT_GPIO0 + 1), 800), (0, 1600)], "{:?}", recorder.changes);
        // Output 8 does not exist on the chip: refused by line before anything moves.
        let program = finestep_gcode::parse_str("M64 P8\nG1 X1 F600\nM2\n", "gpio.ngc").unwrap();
        let err = plan_program(&config, &program).unwrap_err();
        assert_eq!((err.line, err.reason.as_str()), (1, "digital output P8: the chip has outputs 0 to 7"));
    }

    /// `[gantry]` from the machine configuration reaches the chip through `finestep run`'s
    /// machinery: on the gantry card's build (its model at the pins) the pair's registers
    /// are written from the section, the slave axis enabled, the pair engaged in the
    /// configured mode, and X streams to its end; a program moving the slave is refused
    /// by name, and so is a chip without the gantry.
    #[test]
    fn gantry_section_configures_and_engages_the_pair() {
        use finestep_host::regs::{axis_enable, gantry_control, gantry_limits};
        let text = "[gantry]\nenabled = true\nmaster = \"X\"\nslave = \"A\"\nenc_master = 2\nenc_slave = 0\n\
                    sync = false\ntick_us = 20.0\ndeadband_counts = 3\nlimit_counts = 50\n";
        let connect = |params| {
            let mut host = PinHost::new(ModelPins(Top::new(params)), PinTiming::default());
            host.reset(4).unwrap();
            host.idle(8).unwrap();
            let mut chip = Machine::connect(SpiBus::new(host, 1)).unwrap();
            let n_axes = chip.caps().n_axes;
            chip.bus().set_n_axes(n_axes);
            chip
        };
        let mut chip = connect(finestep_cosim::panel_chip_params());
        let limits = machine_setup::chip_limits(&chip.caps());
        let config = MachineConfig::from_toml_str(text, "g.toml").unwrap();
        let (config, resolved) = machine_setup::resolve(config, limits, "g.toml").unwrap();
        let program = finestep_gcode::parse_str("G1 X1 F600\nM2\n", "x.ngc").unwrap();
        let planned = plan_program(&config, &program).unwrap();
        let report = stream_planned(&mut chip, &planned, &resolved, &config.spindle, "x.ngc", |_, _| Ok(())).unwrap();
        assert_eq!(report.end.steps[0], 800);
        let status = chip.gantry_status().unwrap();
        assert!(status.engaged && !status.sync && !status.alarm, "{status:?}");
        let control = chip.bus().read_one(gantry_control::ADDR).unwrap();
        let fields =
            [gantry_control::MASTER, gantry_control::SLAVE, gantry_control::ENC_MASTER, gantry_control::ENC_SLAVE];
        assert_eq!(fields.map(|f| f.get(control)), [0, 3, 2, 0]);
        // 20 us at 50 MHz = 1000 clocks: 16 * 62 + 15 the nearest tick.
        assert_eq!(gantry_control::TICK.get(control), 62);
        let limits_word = chip.bus().read_one(gantry_limits::ADDR).unwrap();
        assert_eq!((gantry_limits::DEADBAND.get(limits_word), gantry_limits::LIMIT.get(limits_word)), (3, 50));
        let enabled = axis_enable::ENABLE.get(chip.bus().read_one(axis_enable::ADDR).unwrap());
        assert_eq!(enabled & 0b1001, 0b1001, "X and its slave A enabled: {enabled:#b}");

        // A program that moves A, the slave, is refused before anything is written.
        let program = finestep_gcode::parse_str("G1 X1 A2 F600\nM2\n", "xa.ngc").unwrap();
        let planned = plan_program(&config, &program).unwrap();
        let err = stream_planned(&mut chip, &planned, &resolved, &config.spindle, "xa.ngc", |_, _| Ok(())).unwrap_err();
        assert!(err.to_string().starts_with("xa.ngc: the program moves A"), "{err}");
        // A chip without the gantry: refused with the reason.
        let mut plain = connect(rtl_top_params());
        let planned = plan_program(&config, &finestep_gcode::parse_str("G1 X1 F600\nM2\n", "x.ngc").unwrap()).unwrap();
        let err = stream_planned(&mut plain, &planned, &resolved, &config.spindle, "x.ngc", |_, _| Ok(())).unwrap_err();
        assert!(err.to_string().contains("the chip has no gantry (CAPS.HAS_GANTRY 0"), "{err}");
    }

    type PbpChip = Machine<SpiBus<PinHost<Recorder>>>;

    /// A 4-axis model chip at its pins with the point-by-point interpolator (`HAS_PBP`,
    /// as the Verilated default chip builds it) or without, the spindle enable and flood
    /// pins watched.
    fn pbp_chip(has_pbp: bool) -> PbpChip {
        let params = finestep_model::top::TopParams { has_pbp, ..rtl_top_params() };
        let watched = 1 << OUT_SPINDLE_EN | 1 << OUT_COOLANT_FLOOD;
        let mut host = PinHost::new(Recorder::new(params, watched), PinTiming::default());
        host.reset(4).unwrap();
        host.idle(8).unwrap();
        let mut chip = Machine::connect(SpiBus::new(host, 1)).unwrap();
        let n_axes = chip.caps().n_axes;
        chip.bus().set_n_axes(n_axes);
        chip
    }

    fn repo(path: &str) -> std::path::PathBuf {
        Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../..")).join(path)
    }

    /// `finestep run`'s point-by-point machinery on the chip: the lathe's configuration
    /// resolved against it, `text` planned by plan_pbp and streamed with its events;
    /// the chip, the plan and the run's report.
    fn run_pbp_on_pins(text: &str) -> (PbpChip, finestep_planner::pbp::PbpPlan, RunReport, Resolved) {
        let mut chip = pbp_chip(true);
        let toml = std::fs::read_to_string(repo("tests/machines/lathe_pbp.toml")).unwrap();
        let config = MachineConfig::from_toml_str(&toml, "lathe_pbp.toml").unwrap();
        let limits = machine_setup::chip_limits(&chip.caps());
        let (config, resolved) = machine_setup::resolve(config, limits, "lathe_pbp.toml").unwrap();
        let program = finestep_gcode::parse_str(text, "lathe_pbp.ngc").unwrap();
        let plan = plan_pbp(&config, &program).unwrap();
        let report =
            stream_planned(&mut chip, &plan.planned, &resolved, &config.spindle, "lathe_pbp.ngc", |_, _| Ok(()))
                .unwrap();
        assert_eq!(report.stream.underruns, 0);
        (chip, plan, report, resolved)
    }

    /// Seed 003's lathe part (tests/programs/lathe_pbp.ngc) on the model chip with the
    /// interpolator: POSITION (X on chip axis 0, Z on 1) ends exactly on the programmed
    /// end on the step grid, the pins' step counts agree, and the spindle and the flood
    /// coolant switch on before the first step and off after the last, at rest.
    #[test]
    fn the_lathe_part_runs_point_by_point_to_its_exact_end() {
        let text = std::fs::read_to_string(repo("tests/programs/lathe_pbp.ngc")).unwrap();
        let (mut chip, plan, report, resolved) = run_pbp_on_pins(&text);
        // X12 in G7 is a radius of 6 mm, Z0.5: 600 and 50 steps; Y and A do not move.
        assert_eq!(report.end.steps, [600, 50, 0, 0]);
        assert_eq!(plan.planned.end, [6.0, 0.0, 0.5, 0.0]);
        let pins = chip.bus().link_mut().target();
        assert_eq!(pins.at, [600, 50]);
        let (en, flood) = (1 << OUT_SPINDLE_EN, 1 << OUT_COOLANT_FLOOD);
        let states: Vec<(u64, [i64; 2])> = pins.changes.iter().map(|&(_, p, at)| (p, at)).collect();
        assert_eq!(states, [(en, [0, 0]), (en | flood, [0, 0]), (en, [600, 50]), (0, [600, 50])], "{:?}", pins.changes);
        let first = pins.steps.iter().filter_map(|s| s.first()).min().copied().unwrap();
        let last = pins.steps.iter().filter_map(|s| s.last()).max().copied().unwrap();
        assert!(pins.changes[1].0 < first && pins.changes[2].0 > last, "{:?} vs steps {first}..{last}", pins.changes);
        println!(
            "lathe part: {} records ({} pbp, {} decisions), {} bursts, {:.3} s of machining planned, {} clocks run ({:.3} s), {} + {} steps",
            report.stream.records,
            plan.pbp_records,
            plan.decisions,
            report.stream.bursts,
            plan.clocks as f64 / resolved.clock_hz,
            report.cycles,
            report.cycles as f64 / resolved.clock_hz,
            pins.steps[0].len(),
            pins.steps[1].len()
        );
    }

    /// G1/G2/G3 alone (no G0: every step a decision's): the steps at the pins come at the
    /// decisions' rate, within 8 kHz (6250 clocks): closer only by what the shaper may
    /// delay one step and not the next, a direction change's set-up in whole visits of
    /// the step engine and the visit itself (252 + 4 clocks); the end exact.
    #[test]
    fn point_by_point_steps_never_come_faster_than_the_limit() {
        let text = "G18 G7\nG1 X4 F6000\nG1 Z-2\nG2 X6 Z-3 R1\nG3 X8 Z-4 R1\nG1 X2 Z-1 F9000\nM2\n";
        let (mut chip, plan, report, resolved) = run_pbp_on_pins(text);
        assert_eq!(report.end.steps, [100, -100, 0, 0]);
        assert_eq!(plan.planned.records.len(), plan.pbp_records);
        let slots = chip.caps().step_slots;
        let interval = u64::from(resolved.pbp.unwrap().min_interval);
        assert_eq!(interval, 6_250);
        let slack = u64::from(resolved.timing[0].dir_setup.div_ceil(slots) * slots + slots);
        let pins = chip.bus().link_mut().target();
        let mut all: Vec<u64> = pins.steps.concat();
        all.sort_unstable();
        assert_eq!(all.len() as u64, plan.decisions, "one step per decision");
        for (what, steps) in [("chip axis 0", &pins.steps[0]), ("chip axis 1", &pins.steps[1]), ("both", &all)] {
            let shortest = steps.windows(2).map(|w| w[1] - w[0]).min().unwrap();
            println!(
                "{what}: {} steps, the shortest interval {shortest} clocks (decisions {interval} apart)",
                steps.len()
            );
            assert!(shortest + slack >= interval, "{what}: {shortest} + {slack} < {interval}");
        }
    }

    /// `run --fast` in point-by-point mode: the lathe part's records on the model's core
    /// through its fast path end where they end on the model chip at its pins (600 and
    /// 50 steps on chip axes 0 and 1), and within a period of its clocks.
    #[test]
    fn the_lathe_part_runs_point_by_point_on_the_model_fast_path() {
        let text = std::fs::read_to_string(repo("tests/programs/lathe_pbp.ngc")).unwrap();
        let (_, _, report, _) = run_pbp_on_pins(&text);
        let toml = std::fs::read_to_string(repo("tests/machines/lathe_pbp.toml")).unwrap();
        let config = MachineConfig::from_toml_str(&toml, "lathe_pbp.toml").unwrap();
        let (config, resolved) =
            machine_setup::resolve(config, machine_setup::model_limits(), "lathe_pbp.toml").unwrap();
        let program = finestep_gcode::parse_str(&text, "lathe_pbp.ngc").unwrap();
        let plan = plan_pbp(&config, &program).unwrap();
        let (moved, cycles) = run_pbp_on_model(&plan.planned, &resolved, "lathe_pbp.ngc").unwrap();
        assert_eq!(moved[..4], report.end.steps[..4]);
        assert_eq!(moved[..2], [600, 50]);
        assert!(cycles >= plan.clocks, "{cycles} clocks run, {} planned", plan.clocks);
    }

    /// A point-by-point configuration on a chip without the interpolator is refused by
    /// key when resolved, and its records by the driver.
    #[test]
    fn a_chip_without_the_interpolator_is_refused() {
        let chip = pbp_chip(false);
        assert!(!chip.caps().has_pbp);
        let toml = std::fs::read_to_string(repo("tests/machines/lathe_pbp.toml")).unwrap();
        let config = MachineConfig::from_toml_str(&toml, "lathe_pbp.toml").unwrap();
        let err =
            machine_setup::resolve(config, machine_setup::chip_limits(&chip.caps()), "lathe_pbp.toml").unwrap_err();
        let text = format!("{err:#}");
        assert!(text.contains("lathe_pbp.toml: interpolation.mode:") && text.contains("VERSION.HAS_PBP 0"), "{text}");
        let lanes = finestep_host::PbpLanes { x: 5, tick_div: 700, ..Default::default() };
        assert!(matches!(chip.pbp_record(&lanes, 0), Err(BusError::PbpRecord { .. })));
        assert!(pbp_chip(true).pbp_record(&lanes, 0).is_ok());
    }
}

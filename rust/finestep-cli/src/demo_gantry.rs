//! Demo part 6, seed 001's gantry card at the chip's pins: two motors on one axis, X
//! (the master, chip axis 0) and its second motor (the slave, chip axis 1), each read by
//! an encoder on the chip's encoder pins (channels 0 and 1, one count a step), on the
//! gantry card's chip (`finestep_top` with the panel and the gantry pair), RTL and model
//! in lockstep on every pin every clock ([`PanelChipLockstep`], with its
//! [`GantryPlant`]). The host driver configures the pair from the machine
//! configuration's `[gantry]` and streams a planned X move over SPI, three times:
//! - forward mode, the slave's motor under a load that makes it lose steps for a while:
//!   the lost steps stay lost;
//! - synchronised mode, the same load: the chip inserts a slave step for each (a
//!   correction at most every tick), the error stays within a few counts;
//! - synchronised mode, the slave's motor stalled for good from a time on: the
//!   corrections cannot put the steps back, the error passes the limit, the alarm is
//!   raised and halts the machine (no step pin rises after it), and the card's LED menu
//!   shows its ALARM page.
//!
//! The part checks what it prints and fails on a regression.

use std::path::Path;

use anyhow::{bail, Context};
use finestep_cosim::{acknowledge_power_up, read_display, GantryPlant, PanelChipLockstep, PanelMachine, SlaveLoad};
use finestep_host::regs::{control, latch_time, period_count, status};
use finestep_host::stream::{self, RunReport};
use finestep_host::{Bus, BusError, GantryStatus, PanelMenu, PanelScan};
use finestep_model::PeriodRecord;
use finestep_planner::config::{GantryConfig, Resolved};
use finestep_planner::MachineConfig;
use plotters::prelude::*;

use crate::machine_setup;

/// X (both motors): 1000 steps/mm, one encoder count a step (1 um).
const STEPS_PER_MM: f64 = 1000.0;
/// The move: X 0 -> `MOVE_MM` at `FEED_MM_S`.
const MOVE_MM: f64 = 4.0;
const FEED_MM_S: f64 = 50.0;
/// The pair: a correction at most every 100 us, no correction within 2 counts, the alarm
/// past 200 counts (0.2 mm of racking).
const TICK_US: f64 = 100.0;
const DEADBAND: u16 = 2;
const LIMIT: u16 = 200;
/// Runs 1 and 2: from 15 ms to 60 ms after the run request the slave's motor loses one
/// step pulse in `LOAD_EVERY`.
const LOAD_MS: (f64, f64) = (15.0, 60.0);
const LOAD_EVERY: u32 = 20;
/// Run 3: the slave's motor stalls for good 30 ms after the run request.
const STALL_MS: f64 = 30.0;
/// The panel: a fast scan and refresh (a digit lit 16 clocks) so the display is read
/// from the pins in a few hundred clocks.
const SCAN: PanelScan = PanelScan { scan_div: 3, deb_scans: 2, refresh_div: 0 };
/// Periods run after the halt before the pins are checked for steps.
const AFTER_HALT_PERIODS: u64 = 3;

/// The machine streamed by the host: X alone in the program, its slave on Y.
fn gantry_config(sync: bool) -> MachineConfig {
    let mut config = machine_setup::demo_config(&[STEPS_PER_MM]);
    for limits in config.axes.values_mut() {
        limits.max_acceleration = 2000.0;
        limits.max_jerk = 200_000.0;
    }
    config.gantry = GantryConfig {
        enabled: true,
        master: "X".into(),
        slave: "Y".into(),
        enc_master: 0,
        enc_slave: 1,
        sync,
        tick_us: TICK_US,
        deadband_counts: DEADBAND,
        limit_counts: LIMIT,
    };
    config
}

/// What one run showed.
struct GantryRun {
    name: &'static str,
    /// The sync error at the pins, `(ms from the first period boundary, counts)` at every
    /// change.
    trace: Vec<(f64, i64)>,
    peak: i64,
    rms: f64,
    /// The slave's lost steps.
    lost: u32,
    /// The plant's positions at the end.
    position: [i64; 2],
    /// `GANTRY_STATUS` at the end.
    status: GantryStatus,
    /// The load's window, ms from the first period boundary.
    load_ms: (f64, f64),
    /// The end of the run (the final positions read), ms from the first period boundary.
    end_ms: f64,
    /// The halt: (ms from the first period boundary, the period it came in, from 1).
    halt: Option<(f64, u64)>,
}

/// The chip connected, the panel acknowledged, the pair configured and engaged, the plant
/// on the pins; returns the machine and the resolved configuration.
fn connect(name: &str, sync: bool) -> anyhow::Result<(PanelMachine, Resolved)> {
    let mut m = machine_setup::open(PanelChipLockstep::new(name))?;
    let caps = m.caps();
    if !(caps.has_panel && caps.has_gantry) {
        bail!("the gantry card's chip reports no panel or no gantry (CAPS)");
    }
    let (_, resolved) =
        machine_setup::resolve(gantry_config(sync), machine_setup::chip_limits(&caps), "<demo part 6>")?;
    let g = resolved.gantry.context("[gantry] is enabled")?;
    m.bus().link_mut().target_mut().plant = Some(GantryPlant::new(
        usize::from(g.master),
        usize::from(g.slave),
        usize::from(g.enc_master),
        usize::from(g.enc_slave),
    ));
    m.clear_faults_and_errors()?;
    m.configure_panel(&SCAN)?;
    let power_up = acknowledge_power_up(&mut m)?;
    if power_up.alarms & 0b0100 == 0 {
        bail!("the panel did not latch the power-up E-stop fault: {power_up:?}");
    }
    machine_setup::configure(&mut m, &resolved)?;
    m.bus().wait(16)?;
    let menu = m.panel_menu()?;
    let s = m.gantry_status()?;
    if !s.engaged || s.sync != sync || menu.mode != sync || menu.page != 0 || menu.alarms != 0 {
        bail!("the pair is not engaged in the mode asked for, or the panel is not on its MODE page: {s:?}, {menu:?}");
    }
    Ok((m, resolved))
}

/// Streams `records` with the slave's motor under `load` (from and to in ms after the
/// pre-fill, which the run request follows; one pulse lost in `every`); the run ends
/// early, without an error, if the machine halts. Times are counted from the first
/// period boundary, which the host finds while the core runs ([`first_boundary`]); the
/// lockstep's cycles are the chip's `TIMESTAMP` plus the reset's clocks.
fn run_once(
    name: &'static str,
    sync: bool,
    records: &[PeriodRecord],
    load: (f64, f64, u32),
) -> anyhow::Result<(PanelMachine, GantryRun)> {
    let (mut m, resolved) = connect(&format!("demo-gantry-{name}"), sync)?;
    machine_setup::check_gantry_records(&resolved, records, "<demo part 6>")?;
    let clock_hz = resolved.clock_hz;
    let clocks = |ms: f64| (ms * 1e-3 * clock_hz).round() as u64;
    let periods_before = m.bus().read_one(period_count::ADDR)?;
    let period = resolved.period_clocks;
    // The load is set when the pre-fill is queued, just before the run request; the first
    // boundary is found at the next event, the core running.
    let mut t0 = None;
    let mut first_ts = None;
    let result = stream::run(&mut m, records.iter().copied(), &machine_setup::stream_config(&resolved), |m, _| {
        if t0.is_some() && first_ts.is_none() {
            first_ts = Some(first_boundary(m, periods_before, period)?);
        }
        let chip = m.bus().link_mut().target_mut();
        if t0.is_none() {
            let now = chip.cycle();
            t0 = Some(now);
            let plant = chip.plant.as_mut().expect("the plant is on the pins");
            let to = if load.1.is_finite() { now + clocks(load.1) } else { u64::MAX };
            plant.load = Some(SlaveLoad { from: now + clocks(load.0), to, every: load.2 });
        }
        Ok(())
    });
    let report: Option<RunReport> = match result {
        Ok(report) => Some(report),
        // The streamer ends the run once it sees the halt (STATUS.HALT).
        Err(BusError::Halted { .. }) => None,
        Err(e) => return Err(e.into()),
    };
    if let Some(report) = &report {
        if report.stream.underruns != 0 {
            bail!("{name}: {} FIFO underruns", report.stream.underruns);
        }
    } else {
        m.bus().wait(AFTER_HALT_PERIODS * u64::from(resolved.period_clocks))?;
    }
    let periods = m.bus().read_one(period_count::ADDR)?.wrapping_sub(periods_before);
    let status = m.gantry_status()?;
    let first_boundary = first_ts.context("the stream ended before the core ran")?;
    if let Some(report) = report.as_ref().filter(|r| r.first_boundary != first_boundary) {
        bail!(
            "{name}: LATCH_TIME read after the run request says the first period boundary was at TIMESTAMP {}, the \
             period count and the latch later {first_boundary}",
            report.first_boundary
        );
    }
    let chip = m.bus_ref().link().target();
    let reset_clocks = chip.cycle().wrapping_sub(u64::from(chip.model().registers().timestamp()));
    let first = reset_clocks + u64::from(first_boundary);
    let t0 = t0.context("the stream never started")?;
    let end = chip.cycle();
    let plant = chip.plant.as_ref().expect("the plant is on the pins");
    let ms = |cycle: u64| (cycle as f64 - first as f64) / clock_hz * 1e3;
    let (peak, rms) = error_figures(&plant.error_trace, first, end);
    let trace = plant.error_trace.iter().filter(|&&(c, _)| c >= first).map(|&(c, e)| (ms(c), e)).collect();
    let load = plant.load.context("the load was set")?;
    let load_ms = (ms(load.from), if load.to == u64::MAX { f64::INFINITY } else { ms(load.to) });
    if t0 > first {
        bail!("{name}: the first period boundary at cycle {first}, before the pre-fill ended at {t0}");
    }
    let halt = match (report.is_none(), chip.halted_since) {
        (true, Some(cycle)) => {
            let since = cycle.checked_sub(first).context("halted before the first period boundary")?;
            let k = since / u64::from(period) + 1;
            if k != u64::from(periods) {
                bail!("{name}: halted at cycle {cycle}, in period {k}, but PERIOD_COUNT counted {periods}");
            }
            Some((ms(cycle), k))
        }
        _ => None,
    };
    let end_ms = ms(end);
    let run =
        GantryRun { name, trace, peak, rms, lost: plant.lost, position: plant.position, status, load_ms, end_ms, halt };
    Ok((m, run))
}

/// The `TIMESTAMP` of the first period boundary of a run, read while the core runs:
/// `LATCH_TIME` (the last boundary's) less the periods since the first
/// (`PERIOD_COUNT` less `before`, its value before the run, less one), the count read
/// on both sides of the latch until no boundary came between. The core must be running
/// (it stops the count at a halt): after 16 attempts (two periods of waiting for the
/// first boundary) this gives up.
fn first_boundary<B: Bus>(m: &mut finestep_host::Machine<B>, before: u32, period: u32) -> Result<u32, BusError> {
    const ATTEMPTS: usize = 16;
    for _ in 0..ATTEMPTS {
        let count = m.bus().read_one(period_count::ADDR)?;
        if count == before {
            // No boundary yet.
            m.bus().wait(u64::from(period / 8))?;
            continue;
        }
        let latch = m.bus().read_one(latch_time::ADDR)?;
        if m.bus().read_one(period_count::ADDR)? == count {
            let since_first = count.wrapping_sub(before).wrapping_sub(1);
            return Ok(latch.wrapping_sub(since_first.wrapping_mul(period)));
        }
    }
    Err(BusError::LatchMoving { attempts: ATTEMPTS, what: "first period boundary (PERIOD_COUNT and LATCH_TIME)" })
}

/// The peak |error| and its root mean square over the clocks `from..to` (the error
/// held between the changes of `trace`).
fn error_figures(trace: &[(u64, i64)], from: u64, to: u64) -> (i64, f64) {
    let mut error = 0i64;
    let mut at = from;
    let mut peak = 0i64;
    let mut sum = 0.0;
    for &(cycle, next) in trace.iter().chain(std::iter::once(&(to, 0))) {
        // `error` held over at..cycle (clipped to the window).
        if cycle > at {
            sum += (error * error) as f64 * (cycle.min(to) - at) as f64;
            peak = peak.max(error.abs());
            at = cycle.min(to);
        }
        if cycle >= to {
            break;
        }
        error = next;
    }
    let span = to.saturating_sub(from).max(1) as f64;
    (peak, (sum / span).sqrt())
}

pub fn run(out: &Path) -> anyhow::Result<()> {
    println!();
    println!(
        "finestep demo, part 6: seed 001's gantry card at the chip's pins (panel and gantry pair; RTL and model in \
         lockstep, every pin every clock)"
    );
    let started = std::time::Instant::now();
    let config = gantry_config(true);
    let records = machine_setup::plan_line(&config, [MOVE_MM, 0.0, 0.0, 0.0], FEED_MM_S)?;
    let commanded: i64 = records.iter().map(|r| i64::from(r.inc[0].to_bits())).sum::<i64>() >> 16;
    println!(
        "  X {MOVE_MM} mm at {FEED_MM_S} mm/s ({} periods of {} ms, {commanded} steps), streamed over SPI; its second \
         motor on axis 1; encoders on channels 0 and 1, 1 count a step",
        records.len(),
        config.period_ms
    );
    println!(
        "  [gantry]: tick {TICK_US} us, deadband {DEADBAND} counts, limit {LIMIT} counts; times from the first period \
         boundary"
    );
    println!("    run            mode           peak      RMS    lost   corrections   error at end   alarm   panel");
    let mut runs = Vec::new();
    for (name, sync) in [("forward", false), ("synchronised", true)] {
        let (mut m, run) = run_once(name, sync, &records, (LOAD_MS.0, LOAD_MS.1, LOAD_EVERY))?;
        let panel = read_display(&mut m, &SCAN)?;
        print_row(&run, if sync { "synchronised" } else { "forward" }, &panel.text);
        if run.status.alarm || run.halt.is_some() {
            bail!("{name}: the alarm was raised ({:?})", run.status);
        }
        if run.position[0] != commanded {
            bail!("{name}: the master ended at {} steps, commanded {commanded}", run.position[0]);
        }
        let plant_error = run.position[0] - run.position[1];
        if i64::from(run.status.error) != plant_error {
            bail!("{name}: GANTRY_STATUS.ERROR reads {}, the encoders are {plant_error} apart", run.status.error);
        }
        if run.lost == 0 {
            bail!("{name}: the load lost no step");
        }
        runs.push(run);
    }
    let (forward, sync) = (&runs[0], &runs[1]);
    println!(
        "  load: the slave's motor loses one step pulse in {LOAD_EVERY} from {:.2} to {:.2} ms (forward), {:.2} to \
         {:.2} ms (synchronised)",
        forward.load_ms.0, forward.load_ms.1, sync.load_ms.0, sync.load_ms.1
    );
    if forward.status.corrections != 0 || forward.position[0] - forward.position[1] != i64::from(forward.lost) {
        bail!(
            "forward: {} corrections, the error {} is not the {} lost steps",
            forward.status.corrections,
            forward.position[0] - forward.position[1],
            forward.lost
        );
    }
    // Each correction inserted a slave step: the error left is the lost steps less them
    // (CORRECTIONS holds the low 12 bits of the count).
    let left = sync.position[0] - sync.position[1];
    if i64::from(sync.status.corrections) != (i64::from(sync.lost) - left) & 0xfff {
        bail!("synchronised: {} corrections for {} lost steps, {left} left", sync.status.corrections, sync.lost);
    }
    if i64::from(sync.status.error).unsigned_abs() > u64::from(DEADBAND) {
        bail!("synchronised: the error ended at {} counts, outside the deadband", sync.status.error);
    }
    if !(sync.peak < forward.peak && sync.rms < forward.rms) {
        bail!(
            "synchronised mode does not beat forward mode: peak {} vs {} counts, RMS {:.2} vs {:.2}",
            sync.peak,
            forward.peak,
            sync.rms,
            forward.rms
        );
    }

    let (mut m, stall) = run_once("stall", true, &records, (STALL_MS, f64::INFINITY, 1))?;
    let panel = read_display(&mut m, &SCAN)?;
    print_row(&stall, "synchronised", &panel.text);
    let chip = m.bus_ref().link().target();
    let (halted_ms, period) = stall.halt.context("stall: the machine did not halt")?;
    let halted_since = chip.halted_since.context("stall: the machine did not halt")?;
    if let Some(rise) = chip.last_step_rise.filter(|&rise| rise > halted_since) {
        bail!("stall: a step pin rose at cycle {rise}, after the halt at cycle {halted_since}");
    }
    if !stall.status.alarm {
        bail!("stall: the machine halted but GANTRY_STATUS.ALARM is 0 ({:?})", stall.status);
    }
    let error = stall.position[0] - stall.position[1];
    if error != i64::from(LIMIT) + 1 {
        bail!("stall: the master stopped {error} counts ahead of the slave, not one past the limit of {LIMIT}");
    }
    if stall.position[0] >= commanded {
        bail!("stall: the master ran its whole move ({} steps) despite the alarm", stall.position[0]);
    }
    let run_bit = control::RUN.get(m.bus().read_one(control::ADDR)?);
    let halt_bit = status::HALT.get(m.status()?);
    let menu: PanelMenu = m.panel_menu()?;
    if (run_bit, halt_bit) != (0, 1)
        || menu.page != 2
        || menu.alarms & 1 == 0
        || panel.text != "AL  0001"
        || !panel.point
    {
        bail!(
            "stall: after the alarm CONTROL.RUN {run_bit}, STATUS.HALT {halt_bit}, the panel {menu:?} shows {:?} \
             (point {}): expected RUN 0, HALT 1, the ALARM page \"AL  0001\" with digit 0's point",
            panel.text,
            panel.point
        );
    }
    println!(
        "  stall: the slave's motor stalled for good at {:.2} ms; the error passed the limit of {LIMIT} counts at \
         {halted_ms:.3} ms, in period {period} of {} (PERIOD_COUNT), the master at {} of {commanded} steps: \
         GANTRY_STATUS.ALARM, the machine halted (STATUS.HALT 1, CONTROL.RUN 0), no step pin rose in the \
         {AFTER_HALT_PERIODS} periods after it, the panel on its ALARM page, \"AL  0001\" with the point lit at the \
         LED pins",
        stall.load_ms.0,
        records.len(),
        stall.position[0]
    );
    runs.push(stall);
    println!(
        "  synchronised vs forward: peak {} vs {} counts, RMS {:.2} vs {:.2} counts ({} and {} steps lost)",
        runs[1].peak, runs[0].peak, runs[1].rms, runs[0].rms, runs[1].lost, runs[0].lost
    );
    let png = out.join("demo_gantry.png");
    plot(&png, &runs)?;
    println!("  plot: {} ({:.1} s)", png.display(), started.elapsed().as_secs_f64());
    Ok(())
}

fn print_row(run: &GantryRun, mode: &str, panel: &str) {
    println!(
        "    {:<14} {:<12} {:>7} {:>8.2} {:>7} {:>13} {:>14} {:>7}   \"{panel}\"",
        run.name,
        mode,
        run.peak,
        run.rms,
        run.lost,
        run.status.corrections,
        run.status.error,
        if run.status.alarm { "yes" } else { "no" },
    );
}

/// The three errors against time, the limit and the halt marked; below, the
/// synchronised run's error at a scale that shows its counts.
fn plot(path: &Path, runs: &[GantryRun]) -> anyhow::Result<()> {
    crate::plot::register_font()?;
    let root = BitMapBackend::new(path, (1200, 800)).into_drawing_area();
    root.fill(&WHITE)?;
    let (upper, lower) = root.split_vertically(540);
    let span = runs.iter().map(|run| run.end_ms).fold(0.0, f64::max);
    let top = f64::from(LIMIT) * 1.15;
    let bottom = -0.05 * top;
    let mut chart = ChartBuilder::on(&upper)
        .caption(
            "gantry card at the chip's pins: sync error (master - slave), forward vs synchronised, and a stall",
            ("sans-serif", 20),
        )
        .margin(10)
        .x_label_area_size(35)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..span, bottom..top)?;
    chart.configure_mesh().x_desc("time from the first period boundary, ms").y_desc("error, encoder counts").draw()?;
    for (i, run) in runs.iter().enumerate() {
        let colour = crate::plot::COLOURS[i % crate::plot::COLOURS.len()];
        chart
            .draw_series(LineSeries::new(steps(run), colour.stroke_width(2)))?
            .label(format!("{} (peak {}, RMS {:.1})", run.name, run.peak, run.rms))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2)));
        if let Some((t, _)) = run.halt {
            chart
                .draw_series(std::iter::once(PathElement::new(vec![(t, bottom), (t, top)], colour.mix(0.6))))?
                .label(format!("alarm and halt, {t:.2} ms"))
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour.mix(0.6)));
        }
    }
    let limit = f64::from(LIMIT);
    chart
        .draw_series(std::iter::once(PathElement::new(vec![(0.0, limit), (span, limit)], BLACK.mix(0.5))))?
        .label(format!("limit, {LIMIT} counts"))
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK.mix(0.5)));
    chart.configure_series_labels().background_style(WHITE.mix(0.8)).border_style(BLACK).draw()?;

    let (index, sync) = runs.iter().enumerate().find(|(_, run)| run.name == "synchronised").context("no sync run")?;
    let high = sync.peak as f64 + 2.0;
    let deadband = f64::from(DEADBAND);
    let mut zoom = ChartBuilder::on(&lower)
        .margin(10)
        .x_label_area_size(35)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..span, -high..high)?;
    zoom.configure_mesh().x_desc("time, ms").y_desc("synchronised, counts (deadband lines)").draw()?;
    let colour = crate::plot::COLOURS[index % crate::plot::COLOURS.len()];
    zoom.draw_series(LineSeries::new(steps(sync), colour.stroke_width(2)))?;
    for level in [-deadband, deadband] {
        zoom.draw_series(std::iter::once(PathElement::new(vec![(0.0, level), (span, level)], BLACK.mix(0.4))))?;
    }
    root.present().with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}

/// A run's error as a step line (held between changes) to its end.
fn steps(run: &GantryRun) -> Vec<(f64, f64)> {
    let mut points = vec![(0.0, 0.0)];
    let mut last = 0.0;
    for &(t, e) in &run.trace {
        points.push((t, last));
        last = e as f64;
        points.push((t, last));
    }
    points.push((run.end_ms, last));
    points
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The figures hold the error between its changes, over the window only.
    #[test]
    fn error_figures_weigh_each_value_by_its_clocks() {
        // 0 for 10 clocks, 4 for 10, -2 for 20 over 100..140.
        let trace = [(50, 7), (100, 0), (110, 4), (120, -2)];
        let (peak, rms) = error_figures(&trace, 100, 140);
        assert_eq!(peak, 4);
        let expected = ((16.0 * 10.0 + 4.0 * 20.0) / 40.0f64).sqrt();
        assert!((rms - expected).abs() < 1e-12, "{rms} vs {expected}");
        // Before the window the error was 7: it counts from the window's start.
        let (peak, rms) = error_figures(&trace, 60, 100);
        assert_eq!((peak, rms), (7, 7.0));
        assert_eq!(error_figures(&[], 0, 10), (0, 0.0));
    }
}

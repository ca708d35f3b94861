//! The gantry card's result (seed 001): the slave side's synchronisation error with
//! forwarding only against synchronised mode, on the same run with the same disturbance.
//!
//! Two motors drive one gantry axis: axis 0 (master) and axis 1 (slave), each side read
//! by an encoder of 4 counts a step, the counts sampled once a period (a feedback path a
//! period slow). The master runs at a steady 0.75 step a period; from period
//! [`Disturbance::from`] to [`Disturbance::to`] a load makes the slave's motor lose one
//! step every [`Disturbance::every`] periods (a stall: its pulse does not move it). In
//! forward mode the slave copies the master's requests and the lost steps stay lost; in
//! synchronised mode a correction every tick (two periods) puts them back. The core runs
//! as the RTL in lockstep with the model (every output every clock,
//! [`finestep_cosim::Harness`]); the figure is printed by `finestep bench` (a figure, not
//! a timed test) and plotted.

use std::path::Path;

use anyhow::Context;
use finestep_cosim::{GantryPair, ModelPath};
use plotters::prelude::*;

/// Clocks a period.
const PERIOD: u32 = 200;
/// Encoder counts a motor step.
pub const COUNTS_PER_STEP: i64 = GantryPair::COUNTS_PER_STEP;

/// The slave motor's load: one step lost every `every` periods in `from..to`.
#[derive(Clone, Copy, Debug)]
pub struct Disturbance {
    /// The first period of the load.
    pub from: usize,
    /// The period it ends at.
    pub to: usize,
    /// One step lost every this many periods while it lasts.
    pub every: usize,
}

/// One run's slave error (master side's count less the slave side's, the error the
/// chip sees) at every period, and the chip's figures at the end.
#[derive(Clone, Debug)]
pub struct GantryRun {
    /// The error at each period, counts.
    pub errors: Vec<i64>,
    /// Steps the slave's motor lost.
    pub lost: i64,
    /// `GANTRY_STATUS.CORRECTIONS`: net correction steps.
    pub corrections: i16,
    /// Whether the alarm was raised.
    pub alarm: bool,
}

impl GantryRun {
    /// The largest |error|, counts.
    pub fn peak(&self) -> i64 {
        self.errors.iter().map(|e| e.abs()).max().unwrap_or(0)
    }

    /// The root-mean-square error, counts.
    pub fn rms(&self) -> f64 {
        let n = self.errors.len().max(1) as f64;
        (self.errors.iter().map(|&e| (e * e) as f64).sum::<f64>() / n).sqrt()
    }

    /// The error at the end, counts.
    pub fn last(&self) -> i64 {
        self.errors.last().copied().unwrap_or(0)
    }
}

/// Runs `periods` periods in forward (`sync` false) or synchronised mode with the slave
/// disturbed by `load`; a deadband of `deadband` counts; no alarm below 65 535 counts.
pub fn simulate(sync: bool, periods: usize, load: Disturbance, deadband: u16) -> anyhow::Result<GantryRun> {
    let name = if sync { "gantry_figure_sync" } else { "gantry_figure_forward" };
    let mut pair = GantryPair::new(name, ModelPath::PerClock, sync, PERIOD, 0.75, deadband, u16::MAX);
    let mut lost = 0i64;
    let mut errors = Vec::with_capacity(periods);
    for period in 0..periods {
        if (load.from..load.to).contains(&period) && (period - load.from) % load.every == load.every - 1 {
            lost += 1;
        }
        errors.push(pair.feed_period(lost).map_err(|m| anyhow::anyhow!("{m}"))?);
    }
    let out = pair.outputs();
    Ok(GantryRun { errors, lost, corrections: out.gantry_corrections as i16, alarm: out.gantry_flags & 2 != 0 })
}

/// The figure's run: 1200 periods, the load from period 200 to 800 losing a step every
/// 10 periods (60 steps), a deadband of 2 counts; forward then synchronised.
pub fn figure_runs() -> anyhow::Result<(Disturbance, GantryRun, GantryRun)> {
    let load = Disturbance { from: 200, to: 800, every: 10 };
    let forward = simulate(false, 1200, load, 2)?;
    let sync = simulate(true, 1200, load, 2)?;
    Ok((load, forward, sync))
}

/// Prints the comparison (peak, RMS and final error per mode, and the error every 100
/// periods) and plots it to `png` when given.
pub fn print_figure(png: Option<&Path>) -> anyhow::Result<()> {
    let (load, forward, sync) = figure_runs()?;
    println!(
        "gantry (seed 001): slave error, forward vs synchronised; the RTL in lockstep with the model; master 0.75 \
         step/period (P = {PERIOD} clocks), {COUNTS_PER_STEP} counts/step, the slave losing a step every {} periods \
         in periods {}..{} ({} steps)",
        load.every, load.from, load.to, forward.lost
    );
    println!("  {:<14} {:>10} {:>10} {:>10} {:>12} {:>6}", "mode", "peak", "RMS", "final", "corrections", "alarm");
    for (name, run) in [("forward", &forward), ("synchronised", &sync)] {
        println!(
            "  {:<14} {:>7} ct {:>7.1} ct {:>7} ct {:>12} {:>6}",
            name,
            run.peak(),
            run.rms(),
            run.last(),
            run.corrections,
            if run.alarm { "yes" } else { "no" }
        );
    }
    print!("  error every 100 periods, forward:     ");
    for e in forward.errors.iter().step_by(100) {
        print!(" {e:>4}");
    }
    print!("\n  error every 100 periods, synchronised:");
    for e in sync.errors.iter().step_by(100) {
        print!(" {e:>4}");
    }
    println!();
    if let Some(png) = png {
        plot(png, &forward, &sync)?;
        println!("  plot: {}", png.display());
    }
    Ok(())
}

fn plot(path: &Path, forward: &GantryRun, sync: &GantryRun) -> anyhow::Result<()> {
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    crate::plot::register_font()?;
    let root = BitMapBackend::new(path, (1200, 500)).into_drawing_area();
    root.fill(&WHITE)?;
    let t = |i: usize| i as f64 * f64::from(PERIOD) / 50e6 * 1e3;
    let periods = forward.errors.len().max(sync.errors.len());
    let hi = forward.peak().max(sync.peak()) as f64;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            "gantry slave error: forward only vs synchronised (the same disturbed run), counts",
            ("sans-serif", 20),
        )
        .margin(10)
        .x_label_area_size(35)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..t(periods), -2.0..(hi + 4.0))?;
    chart.configure_mesh().x_desc("time at 50 MHz, ms").y_desc("master - slave, counts").draw()?;
    for (i, (name, run)) in [("forward", forward), ("synchronised", sync)].into_iter().enumerate() {
        let colour = crate::plot::COLOURS[i];
        chart
            .draw_series(LineSeries::new(
                run.errors.iter().enumerate().map(|(k, &e)| (t(k), e as f64)),
                colour.stroke_width(2),
            ))?
            .label(name)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2)));
    }
    chart.configure_series_labels().background_style(WHITE.mix(0.8)).border_style(BLACK).draw()?;
    root.present().with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// On a disturbed slave the synchronised mode's peak error is smaller than forward
    /// mode's: forward keeps every lost step (4 counts each), synchronised puts them back
    /// a step a tick, so its error stays within the deadband plus the steps lost between
    /// two corrections and the period of feedback lag.
    #[test]
    fn sync_peak_error_is_smaller_than_forward_on_a_disturbed_slave() {
        let load = Disturbance { from: 50, to: 250, every: 10 };
        let forward = simulate(false, 400, load, 2).unwrap();
        let sync = simulate(true, 400, load, 2).unwrap();
        assert_eq!(forward.lost, 20);
        // Forward: the slave copies the master; the error is the lost steps, and stays.
        assert_eq!(
            (forward.peak(), forward.last(), forward.corrections),
            (20 * COUNTS_PER_STEP, 20 * COUNTS_PER_STEP, 0)
        );
        // Synchronised: every lost step put back, the error back within the deadband.
        assert_eq!(i64::from(sync.corrections), sync.lost, "{:?}", sync.errors);
        assert!(sync.last().abs() <= 2, "{}", sync.last());
        assert!(sync.peak() < forward.peak(), "sync {} forward {}", sync.peak(), forward.peak());
        assert!(sync.peak() <= 2 * COUNTS_PER_STEP, "sync peak {} counts: {:?}", sync.peak(), sync.errors);
        assert!(sync.rms() < forward.rms() / 4.0, "RMS sync {} forward {}", sync.rms(), forward.rms());
        assert!(!forward.alarm && !sync.alarm);
    }
}

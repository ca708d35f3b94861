//! PNG plots of commanded against emitted motion.

use std::path::Path;

use anyhow::Context;
use plotters::prelude::*;

/// One axis: the commanded position at every period boundary, and the emitted one
/// where it was sampled, in steps.
#[derive(Default, Clone, Debug)]
pub struct AxisTrace {
    /// Commanded position (sum of the increments so far) at boundary `i`, time `i * T`.
    pub commanded: Vec<f64>,
    /// Position the pulse train had reached, as (time from boundary 0 in s, steps).
    pub emitted: Vec<(f64, f64)>,
}

const FONT_FILE: &str = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";
const COLOURS: [RGBColor; 4] =
    [RGBColor(31, 119, 180), RGBColor(214, 39, 40), RGBColor(44, 160, 44), RGBColor(148, 103, 189)];

fn register_font() -> anyhow::Result<()> {
    let bytes = std::fs::read(FONT_FILE).with_context(|| format!("{FONT_FILE} (Debian package fonts-dejavu-core)"))?;
    plotters::style::register_font("sans-serif", FontStyle::Normal, Box::leak(bytes.into_boxed_slice()))
        .map_err(|_| anyhow::anyhow!("{FONT_FILE} is not a usable font"))
}

/// Two panels: position (commanded line, emitted dots) and step rate per axis.
pub fn plot_axes(path: &Path, traces: &[AxisTrace], names: &[&str], period_s: f64) -> anyhow::Result<()> {
    register_font()?;
    let root = BitMapBackend::new(path, (1200, 900)).into_drawing_area();
    root.fill(&WHITE)?;
    let (top, bottom) = root.split_vertically(450);
    let periods = traces.iter().map(|t| t.commanded.len()).max().unwrap_or(0);
    let t_end = periods as f64 * period_s;
    let time = |i: usize| i as f64 * period_s;

    let (lo, hi) = traces
        .iter()
        .flat_map(|t| t.commanded.iter().chain(t.emitted.iter().map(|(_, v)| v)))
        .fold((0.0f64, 0.0f64), |(lo, hi), &v| (lo.min(v), hi.max(v)));
    let mut chart = ChartBuilder::on(&top)
        .caption("position: commanded (line) vs emitted by the RTL (dots), steps", ("sans-serif", 20))
        .margin(10)
        .x_label_area_size(35)
        .y_label_area_size(70)
        .build_cartesian_2d(0.0..t_end, (lo - 1.0)..(hi + 1.0))?;
    chart.configure_mesh().x_desc("time, s").y_desc("steps").draw()?;
    for (axis, trace) in traces.iter().enumerate() {
        let colour = COLOURS[axis % COLOURS.len()];
        chart
            .draw_series(LineSeries::new(trace.commanded.iter().enumerate().map(|(i, &v)| (time(i), v)), colour))?
            .label(names[axis])
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour));
        let stride = (trace.emitted.len() / 150).max(1);
        chart
            .draw_series(trace.emitted.iter().step_by(stride).map(|&(t, v)| Circle::new((t, v), 2, colour.filled())))?;
    }
    chart.configure_series_labels().background_style(WHITE.mix(0.8)).border_style(BLACK).draw()?;

    let rate = |v: &[f64]| -> Vec<f64> { v.windows(2).map(|w| (w[1] - w[0]) / period_s).collect() };
    // Emitted rate between samples: steps over the time between them, at the midpoint.
    let sampled_rate = |v: &[(f64, f64)]| -> Vec<(f64, f64)> {
        v.windows(2)
            .filter(|w| w[1].0 > w[0].0)
            .map(|w| ((w[0].0 + w[1].0) / 2.0, (w[1].1 - w[0].1) / (w[1].0 - w[0].0)))
            .collect()
    };
    type Rates = (Vec<f64>, Vec<(f64, f64)>);
    let rates: Vec<Rates> = traces.iter().map(|t| (rate(&t.commanded), sampled_rate(&t.emitted))).collect();
    let (rlo, rhi) = rates
        .iter()
        .flat_map(|(c, e)| c.iter().chain(e.iter().map(|(_, v)| v)))
        .fold((0.0f64, 0.0f64), |(lo, hi), &v| (lo.min(v), hi.max(v)));
    let mut chart = ChartBuilder::on(&bottom)
        .caption("step rate per period: commanded (line) vs emitted (dots), steps/s", ("sans-serif", 20))
        .margin(10)
        .x_label_area_size(35)
        .y_label_area_size(70)
        .build_cartesian_2d(0.0..t_end, (rlo * 1.1 - 1.0)..(rhi * 1.1 + 1.0))?;
    chart.configure_mesh().x_desc("time, s").y_desc("steps/s").draw()?;
    for (axis, (commanded, emitted)) in rates.iter().enumerate() {
        let colour = COLOURS[axis % COLOURS.len()];
        chart.draw_series(LineSeries::new(commanded.iter().enumerate().map(|(i, &v)| (time(i + 1), v)), colour))?;
        let stride = (emitted.len() / 150).max(1);
        chart.draw_series(emitted.iter().step_by(stride).map(|&(t, v)| Circle::new((t, v), 2, colour.filled())))?;
    }
    root.present().with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}

/// At most `buckets` points of `values` against time: the largest value of each bucket,
/// so that short peaks (jerk at a junction) stay visible.
fn envelope(values: &[f64], period_s: f64, buckets: usize) -> Vec<(f64, f64)> {
    let size = values.len().div_ceil(buckets.max(1)).max(1);
    values
        .chunks(size)
        .enumerate()
        .map(|(i, chunk)| ((i * size) as f64 * period_s, chunk.iter().cloned().fold(0.0, f64::max)))
        .collect()
}

/// The commanded toolpath (every period boundary) in the X-Y and X-Z planes.
pub fn plot_toolpath(path: &Path, samples: &[finestep_planner::checker::Sample]) -> anyhow::Result<()> {
    register_font()?;
    let root = BitMapBackend::new(path, (1400, 700)).into_drawing_area();
    root.fill(&WHITE)?;
    let (left, right) = root.split_horizontally(700);
    let stride = (samples.len() / 20_000).max(1);
    for (area, (u, v), title) in [(left, (0, 1), "toolpath X-Y, mm"), (right, (0, 2), "toolpath X-Z, mm")] {
        let points: Vec<(f64, f64)> = samples.iter().step_by(stride).map(|s| (s.position[u], s.position[v])).collect();
        let (mut lo, mut hi) = ((f64::MAX, f64::MAX), (f64::MIN, f64::MIN));
        for &(x, y) in points.iter().chain(std::iter::once(&(0.0, 0.0))) {
            lo = (lo.0.min(x), lo.1.min(y));
            hi = (hi.0.max(x), hi.1.max(y));
        }
        // Equal scales on both axes, with a margin.
        let span = (hi.0 - lo.0).max(hi.1 - lo.1).max(1e-3) * 1.05;
        let (cx, cy) = (0.5 * (lo.0 + hi.0), 0.5 * (lo.1 + hi.1));
        let mut chart = ChartBuilder::on(&area)
            .caption(title, ("sans-serif", 20))
            .margin(10)
            .x_label_area_size(35)
            .y_label_area_size(60)
            .build_cartesian_2d((cx - span / 2.0)..(cx + span / 2.0), (cy - span / 2.0)..(cy + span / 2.0))?;
        chart.configure_mesh().draw()?;
        chart.draw_series(LineSeries::new(points, COLOURS[0]))?;
    }
    root.present().with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}

/// Path feed, acceleration and jerk (vector norms over the axes) against time.
pub fn plot_motion(path: &Path, samples: &[finestep_planner::checker::Sample], period_s: f64) -> anyhow::Result<()> {
    register_font()?;
    let root = BitMapBackend::new(path, (1200, 1000)).into_drawing_area();
    root.fill(&WHITE)?;
    let panels = root.split_evenly((3, 1));
    let t_end = (samples.len() as f64 * period_s).max(period_s);
    let series: [(&str, Vec<f64>); 3] = [
        ("path feed, units/s", samples.iter().map(|s| s.speed).collect()),
        ("path acceleration, units/s^2", samples.iter().map(|s| s.acceleration).collect()),
        ("path jerk, units/s^3", samples.iter().map(|s| s.jerk).collect()),
    ];
    for (area, (title, values)) in panels.iter().zip(series) {
        let points = envelope(&values, period_s, 2000);
        let top = points.iter().map(|p| p.1).fold(0.0, f64::max).max(1e-9) * 1.1;
        let mut chart = ChartBuilder::on(area)
            .caption(title, ("sans-serif", 20))
            .margin(10)
            .x_label_area_size(35)
            .y_label_area_size(80)
            .build_cartesian_2d(0.0..t_end, 0.0..top)?;
        chart.configure_mesh().x_desc("time, s").draw()?;
        chart.draw_series(LineSeries::new(points, COLOURS[1]))?;
    }
    root.present().with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}

/// Measured roller profiles (deviation less its mean, um, against Z) as lines, and the
/// compensated program's X(Z) less its mean.
pub fn plot_profiles(
    path: &Path,
    profiles: &[(&str, &finestep_profile::Profile)],
    compensated: &[(f64, f64)],
) -> anyhow::Result<()> {
    register_font()?;
    let root = BitMapBackend::new(path, (1200, 600)).into_drawing_area();
    root.fill(&WHITE)?;
    let centred = |points: Vec<(f64, f64)>| -> Vec<(f64, f64)> {
        let mean = points.iter().map(|p| p.1).sum::<f64>() / points.len().max(1) as f64;
        points.into_iter().map(|(z, x)| (z, (x - mean) * 1e3)).collect()
    };
    let mut series: Vec<(String, Vec<(f64, f64)>)> = profiles
        .iter()
        .map(|(name, p)| (format!("measured {name}"), centred(p.samples.iter().map(|s| (s.z_mm, s.x_mm)).collect())))
        .collect();
    series.push(("compensated program X(Z)".to_string(), centred(compensated.to_vec())));
    let all = series.iter().flat_map(|s| s.1.iter());
    let (zlo, zhi, lo, hi) = all
        .fold((f64::MAX, f64::MIN, 0.0f64, 0.0f64), |(a, b, c, d), &(z, x)| (a.min(z), b.max(z), c.min(x), d.max(x)));
    let mut chart = ChartBuilder::on(&root)
        .caption("roller form error: measured before and after the compensated pass, um", ("sans-serif", 20))
        .margin(10)
        .x_label_area_size(35)
        .y_label_area_size(60)
        .build_cartesian_2d(zlo.min(zhi)..zhi.max(zlo + 1e-3), (lo - 0.5)..(hi + 0.5))?;
    chart.configure_mesh().x_desc("Z, mm").y_desc("X deviation less its mean, um").draw()?;
    for (i, (name, points)) in series.into_iter().enumerate() {
        let colour = COLOURS[i % COLOURS.len()];
        chart
            .draw_series(LineSeries::new(points, colour.stroke_width(2)))?
            .label(name)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2)));
    }
    chart.configure_series_labels().background_style(WHITE.mix(0.8)).border_style(BLACK).draw()?;
    root.present().with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}

//! PNG plots of commanded against emitted motion.

use std::path::Path;

use anyhow::Context;
use plotters::prelude::*;

/// One axis sampled at every period boundary, in steps.
#[derive(Default, Clone, Debug)]
pub struct AxisTrace {
    /// Commanded position (sum of the increments so far).
    pub commanded: Vec<f64>,
    /// Position the pulse train has reached.
    pub emitted: Vec<f64>,
}

const FONT_FILE: &str = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";
const COLOURS: [RGBColor; 4] = [RGBColor(31, 119, 180), RGBColor(214, 39, 40), RGBColor(44, 160, 44), RGBColor(148, 103, 189)];

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

    let (lo, hi) = traces.iter().flat_map(|t| t.commanded.iter().chain(&t.emitted)).fold(
        (0.0f64, 0.0f64),
        |(lo, hi), &v| (lo.min(v), hi.max(v)),
    );
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
        chart.draw_series(
            trace.emitted.iter().enumerate().step_by(stride).map(|(i, &v)| Circle::new((time(i), v), 2, colour.filled())),
        )?;
    }
    chart.configure_series_labels().background_style(WHITE.mix(0.8)).border_style(BLACK).draw()?;

    let rate = |v: &[f64]| -> Vec<f64> { v.windows(2).map(|w| (w[1] - w[0]) / period_s).collect() };
    let rates: Vec<(Vec<f64>, Vec<f64>)> = traces.iter().map(|t| (rate(&t.commanded), rate(&t.emitted))).collect();
    let (rlo, rhi) = rates.iter().flat_map(|(c, e)| c.iter().chain(e)).fold((0.0f64, 0.0f64), |(lo, hi), &v| (lo.min(v), hi.max(v)));
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
        chart.draw_series(
            emitted.iter().enumerate().step_by(stride).map(|(i, &v)| Circle::new((time(i + 1), v), 2, colour.filled())),
        )?;
    }
    root.present().with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}

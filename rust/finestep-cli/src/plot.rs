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
pub(crate) const COLOURS: [RGBColor; 4] =
    [RGBColor(31, 119, 180), RGBColor(214, 39, 40), RGBColor(44, 160, 44), RGBColor(148, 103, 189)];

pub(crate) fn register_font() -> anyhow::Result<()> {
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

/// Distance from each of `points` to the polyline `path` (x, y, z), following the path in
/// order: each point is looked for from the segment nearest the previous one on, within
/// `WINDOW` segments (the executed path runs along the programmed one), so a later
/// piece passing close by never takes over.
fn deviations(points: &[[f64; 3]], path: &[[f64; 3]]) -> Vec<f64> {
    const WINDOW: usize = 400;
    let distance = |p: [f64; 3], a: [f64; 3], b: [f64; 3]| -> f64 {
        let d = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let w = [p[0] - a[0], p[1] - a[1], p[2] - a[2]];
        let len2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        let t = if len2 > 0.0 { ((w[0] * d[0] + w[1] * d[1] + w[2] * d[2]) / len2).clamp(0.0, 1.0) } else { 0.0 };
        let q = [w[0] - t * d[0], w[1] - t * d[1], w[2] - t * d[2]];
        (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]).sqrt()
    };
    let mut at = 0;
    points
        .iter()
        .map(|&p| {
            if path.len() < 2 {
                return path.first().map_or(0.0, |&a| distance(p, a, a));
            }
            let (best, d) = (at..(at + WINDOW).min(path.len() - 1))
                .map(|k| (k, distance(p, path[k], path[k + 1])))
                .fold((at, f64::MAX), |b, c| if c.1 < b.1 { c } else { b });
            at = best;
            d
        })
        .collect()
}

/// The toolpath in the X-Y and X-Z planes: the programmed path (the planner's, `programmed`)
/// and the executed one (the positions of the records at every period boundary) as lines,
/// the executed points farthest from the programmed path (at least half the largest
/// deviation, and over 0.1 um) marked in red.
pub fn plot_toolpath(
    path: &Path,
    programmed: &[[f64; 3]],
    samples: &[finestep_planner::checker::Sample],
) -> anyhow::Result<()> {
    register_font()?;
    let root = BitMapBackend::new(path, (1400, 760)).into_drawing_area();
    root.fill(&WHITE)?;
    let stride = (samples.len() / 20_000).max(1);
    let executed: Vec<[f64; 3]> = std::iter::once([0.0; 3])
        .chain(samples.iter().step_by(stride).map(|s| [s.position[0], s.position[1], s.position[2]]))
        .chain(samples.last().map(|s| [s.position[0], s.position[1], s.position[2]]))
        .collect();
    let deviation = deviations(&executed, programmed);
    let largest = deviation.iter().cloned().fold(0.0, f64::max);
    let threshold = (0.5 * largest).max(1e-4);
    let (title_area, root) = root.split_vertically(50);
    title_area.titled(
        &format!(
            "toolpath, mm: programmed (grey) and executed by the records (blue); red: {:.2} um or more from the programmed path (largest {:.2} um)",
            threshold * 1e3,
            largest * 1e3
        ),
        ("sans-serif", 18),
    )?;
    let (left, right) = root.split_horizontally(700);
    let grey = RGBColor(150, 150, 150);
    for (area, (u, v), title) in [(left, (0, 1), "X-Y"), (right, (0, 2), "X-Z")] {
        let pick = |p: &[f64; 3]| (p[u], p[v]);
        let (mut lo, mut hi) = ((f64::MAX, f64::MAX), (f64::MIN, f64::MIN));
        for (x, y) in executed.iter().chain(programmed).map(pick) {
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
        chart
            .draw_series(LineSeries::new(programmed.iter().map(pick), grey.stroke_width(4)))?
            .label("programmed")
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], grey.stroke_width(4)));
        chart
            .draw_series(LineSeries::new(executed.iter().map(pick), COLOURS[0].stroke_width(1)))?
            .label("executed (records)")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], COLOURS[0]));
        let far = executed.iter().zip(&deviation).filter(|(_, &d)| d >= threshold);
        chart
            .draw_series(far.map(|(p, _)| Circle::new(pick(p), 3, COLOURS[1].filled())))?
            .label("farthest from the programmed path")
            .legend(|(x, y)| Circle::new((x + 10, y), 3, COLOURS[1].filled()));
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()?;
    }
    root.present().with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}

/// What the motion plot draws its limits from.
pub struct MotionLimits {
    /// The programmed feed of the block each period runs on, units/s (NaN on a rapid).
    pub feed: Vec<f64>,
    /// The path acceleration bound (the norm of the axes' limits), units/s^2.
    pub acceleration: f64,
    /// The path jerk bound, units/s^3 (infinite with a trapezoid profile: not drawn).
    pub jerk: f64,
}

/// Path feed, acceleration and jerk (vector norms over the axes) against time, each with
/// its limit: the programmed feed of the block run, the norm of the axes' acceleration
/// and jerk limits.
pub fn plot_motion(
    path: &Path,
    samples: &[finestep_planner::checker::Sample],
    period_s: f64,
    limits: &MotionLimits,
) -> anyhow::Result<()> {
    register_font()?;
    let root = BitMapBackend::new(path, (1200, 1000)).into_drawing_area();
    root.fill(&WHITE)?;
    let panels = root.split_evenly((3, 1));
    let t_end = (samples.len() as f64 * period_s).max(period_s);
    let series: [(&str, Vec<f64>); 3] = [
        ("path feed, units/s (grey: the programmed feed)", samples.iter().map(|s| s.speed).collect()),
        (
            "path acceleration, units/s^2 (grey: the axes' limits' norm)",
            samples.iter().map(|s| s.acceleration).collect(),
        ),
        ("path jerk, units/s^3 (grey: the axes' limits' norm, S-curve)", samples.iter().map(|s| s.jerk).collect()),
    ];
    let grey = RGBColor(120, 120, 120);
    for (panel, (area, (title, values))) in panels.iter().zip(series).enumerate() {
        let points = envelope(&values, period_s, 2000);
        let limit: Vec<(f64, f64)> = match panel {
            0 => envelope(
                &limits.feed.iter().map(|f| if f.is_finite() { *f } else { 0.0 }).collect::<Vec<_>>(),
                period_s,
                2000,
            ),
            1 if limits.acceleration.is_finite() => vec![(0.0, limits.acceleration), (t_end, limits.acceleration)],
            2 if limits.jerk.is_finite() => vec![(0.0, limits.jerk), (t_end, limits.jerk)],
            _ => Vec::new(),
        };
        let top = points.iter().chain(&limit).map(|p| p.1).fold(0.0, f64::max).max(1e-9) * 1.1;
        let mut chart = ChartBuilder::on(area)
            .caption(title, ("sans-serif", 20))
            .margin(10)
            .x_label_area_size(35)
            .y_label_area_size(80)
            .build_cartesian_2d(0.0..t_end, 0.0..top)?;
        chart.configure_mesh().x_desc("time, s").draw()?;
        if !limit.is_empty() {
            chart.draw_series(LineSeries::new(limit, grey.stroke_width(2)))?;
        }
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

#[cfg(test)]
mod tests {
    use super::deviations;

    /// Distances to a polyline followed in order: on it 0, off it the distance to the
    /// nearest segment, and a later segment passing close by is not taken.
    #[test]
    fn deviations_follow_the_path() {
        let path = [[0.0, 0.0, 0.0], [10.0, 0.0, 0.0], [10.0, 10.0, 0.0], [0.0, 0.1, 0.0]];
        let points = [[5.0, 0.0, 0.0], [5.0, 0.02, 0.0], [10.0, 5.0, 0.5], [5.0, 0.05, 0.0]];
        let d = deviations(&points, &path);
        assert!(d[0].abs() < 1e-12 && (d[1] - 0.02).abs() < 1e-12 && (d[2] - 0.5).abs() < 1e-12, "{d:?}");
        // The last point is 0.05 from the first segment, but the path has gone on past it:
        // it is measured from the segments after the third point's.
        assert!(d[3] > 1.0, "{d:?}");
    }
}

//! Measured roller profiles (seed 000): the roller's radius deviation X along the table
//! Z, as `finestep measure` samples it, and the compensated grinding program `finestep
//! compensate` makes of it.
//!
//! - [`Profile`]: samples `(z_mm, x_mm)` with the commanded Z and the time, written and
//!   read as a commented CSV file ([`Profile::to_text`], [`Profile::parse`]).
//! - [`smooth`]: the noise filter, a local quadratic least-squares fit (tricube weights,
//!   a window of `window_mm`): it passes a taper and a crown unchanged (a quadratic is
//!   fitted exactly) and averages the noise over the window.
//! - [`compensate`]: the form error `f(z)` = the smoothed `measured - target`, less its
//!   mean (the size is the target's, the form the measurement's); the program asks for
//!   `X(z) = target(z) - f(z)`, so a machine that leaves `f` on a straight pass grinds
//!   the target. The curve becomes a polyline within half the tolerance of it, blended
//!   with `G64 P` of half the tolerance, at a feed the axis limits allow.
//! - [`FormError`]: the figures: size (mean deviation), peak-to-valley and RMS of the
//!   form, raw and filtered.
//!
//! ```
//! use finestep_profile::{compensate, CompensateOptions, Profile, Sample, Target};
//! // A roller with a 10 um crown over 20 mm, measured every 0.1 mm.
//! let samples = (0..=200).map(|i| {
//!     let z = 0.1 * i as f64;
//!     Sample { z_mm: z, x_mm: 0.010 * (1.0 - ((z - 10.0) / 10.0).powi(2)), z_commanded_mm: z, time_s: 0.0 }
//! });
//! let profile = Profile { samples: samples.collect(), z_resolution_mm: 0.0005, x_resolution_mm: 0.0005 };
//! let c = compensate(&profile, &Target::Constant(-0.02), &CompensateOptions::default()).unwrap();
//! // The program mirrors the crown about the target: 10 um crown -> 10 um hollow.
//! assert!((c.x_at(0.0) - c.x_at(10.0) - 0.010).abs() < 1e-4);
//! assert!(c.program.contains("G1 Z"));
//! ```

#![warn(missing_docs)]

use std::fmt::Write as _;

/// Why a profile, a target or a compensation is refused.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ProfileError {
    /// A line of a profile file does not parse.
    #[error("{file}:{line}: {why}")]
    Parse {
        /// The file.
        file: String,
        /// The line (1-based).
        line: usize,
        /// What is wrong.
        why: String,
    },
    /// Too few samples, or samples not along Z.
    #[error("{0}")]
    Samples(String),
    /// The target does not cover the measured Z range.
    #[error("the target covers Z {lo:.4} to {hi:.4} mm, the profile {need_lo:.4} to {need_hi:.4} mm")]
    TargetRange {
        /// The target's first Z.
        lo: f64,
        /// The target's last Z.
        hi: f64,
        /// The profile's first Z.
        need_lo: f64,
        /// The profile's last Z.
        need_hi: f64,
    },
    /// An option is out of range.
    #[error("{0}")]
    Options(String),
    /// The correction asked for is larger than allowed (a bad measurement, or a roller
    /// that needs another roughing pass).
    #[error("the form error is {pv_um:.1} um peak to valley, more than the {max_um:.1} um a compensation may correct")]
    TooLarge {
        /// Peak to valley of the filtered form error, um.
        pv_um: f64,
        /// The limit, um.
        max_um: f64,
    },
}

/// One sample of a measuring traverse.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// Table position by its grating, mm (latched with `x_mm` on one clock).
    pub z_mm: f64,
    /// Radius deviation by the gauge's grating, mm.
    pub x_mm: f64,
    /// Table position the step generator had reached at the latch, mm (the drive lags it).
    pub z_commanded_mm: f64,
    /// Latch time from the start of the traverse, s.
    pub time_s: f64,
}

/// A measured (or target) profile.
#[derive(Clone, Debug, PartialEq)]
pub struct Profile {
    /// Samples in the order taken.
    pub samples: Vec<Sample>,
    /// One count of the Z grating, mm.
    pub z_resolution_mm: f64,
    /// One count of the X (gauge) grating, mm.
    pub x_resolution_mm: f64,
}

const HEADER: &str = "z_mm,x_mm,z_commanded_mm,lag_um,time_s";

impl Profile {
    /// The profile file: `#` comments (the resolutions as `# key = value`), a header
    /// line, one sample a line.
    pub fn to_text(&self, comment: &str) -> String {
        let mut text = String::new();
        for line in comment.lines() {
            let _ = writeln!(text, "# {line}");
        }
        let _ = writeln!(text, "# z_resolution_mm = {}", self.z_resolution_mm);
        let _ = writeln!(text, "# x_resolution_mm = {}", self.x_resolution_mm);
        let _ = writeln!(text, "{HEADER}");
        for s in &self.samples {
            let lag_um = (s.z_commanded_mm - s.z_mm) * 1e3;
            let _ = writeln!(text, "{:.6},{:.6},{:.6},{:.3},{:.6}", s.z_mm, s.x_mm, s.z_commanded_mm, lag_um, s.time_s);
        }
        text
    }

    /// Reads a profile file (`file` names it in errors). Columns by the header's names:
    /// `z_mm` and `x_mm` are needed (a target profile has just these), the others
    /// optional; resolutions default to 0.
    pub fn parse(text: &str, file: &str) -> Result<Profile, ProfileError> {
        let err = |line: usize, why: String| ProfileError::Parse { file: file.to_string(), line, why };
        let mut resolution = [0.0f64; 2];
        let mut columns: Option<Vec<String>> = None;
        let mut samples = Vec::new();
        for (index, raw) in text.lines().enumerate() {
            let line = raw.trim();
            let n = index + 1;
            if line.is_empty() {
                continue;
            }
            if let Some(comment) = line.strip_prefix('#') {
                if let Some((key, value)) = comment.split_once('=') {
                    let slot = match key.trim() {
                        "z_resolution_mm" => Some(0),
                        "x_resolution_mm" => Some(1),
                        _ => None,
                    };
                    if let Some(slot) = slot {
                        let v: f64 =
                            value.trim().parse().map_err(|_| err(n, format!("{} is not a number", value.trim())))?;
                        if !(v.is_finite() && v >= 0.0) {
                            return Err(err(n, format!("resolution {v} mm")));
                        }
                        resolution[slot] = v;
                    }
                }
                continue;
            }
            let Some(names) = &columns else {
                let names: Vec<String> = line.split(',').map(|c| c.trim().to_string()).collect();
                for need in ["z_mm", "x_mm"] {
                    if !names.iter().any(|c| c == need) {
                        return Err(err(n, format!("the header has no `{need}` column (found `{line}`)")));
                    }
                }
                columns = Some(names);
                continue;
            };
            let values: Vec<&str> = line.split(',').map(str::trim).collect();
            if values.len() != names.len() {
                return Err(err(n, format!("{} values, the header names {}", values.len(), names.len())));
            }
            let get = |name: &str| -> Result<Option<f64>, ProfileError> {
                let Some(i) = names.iter().position(|c| c == name) else { return Ok(None) };
                let v: f64 =
                    values[i].parse().map_err(|_| err(n, format!("{name} `{}` is not a number", values[i])))?;
                if !v.is_finite() {
                    return Err(err(n, format!("{name} is {v}")));
                }
                Ok(Some(v))
            };
            let z_mm = get("z_mm")?.unwrap_or_default();
            let x_mm = get("x_mm")?.unwrap_or_default();
            let z_commanded_mm = get("z_commanded_mm")?.unwrap_or(z_mm);
            let time_s = get("time_s")?.unwrap_or_default();
            samples.push(Sample { z_mm, x_mm, z_commanded_mm, time_s });
        }
        if columns.is_none() {
            return Err(err(text.lines().count().max(1), "no header line (z_mm,x_mm,...)".into()));
        }
        Ok(Profile { samples, z_resolution_mm: resolution[0], x_resolution_mm: resolution[1] })
    }

    /// The Z range of the samples.
    pub fn z_range(&self) -> Option<(f64, f64)> {
        let zs = self.samples.iter().map(|s| s.z_mm);
        let lo = zs.clone().fold(f64::INFINITY, f64::min);
        let hi = zs.fold(f64::NEG_INFINITY, f64::max);
        (lo <= hi).then_some((lo, hi))
    }
}

/// The shape to grind: one radius deviation, or a profile interpolated linearly in Z.
#[derive(Clone, Debug, PartialEq)]
pub enum Target {
    /// A cylinder at this X, mm.
    Constant(f64),
    /// Points `(z_mm, x_mm)` in increasing Z.
    Points(Vec<(f64, f64)>),
}

impl Target {
    /// The target of a profile file's samples (sorted by Z; Z values must differ).
    pub fn from_profile(profile: &Profile) -> Result<Target, ProfileError> {
        let mut points: Vec<(f64, f64)> = profile.samples.iter().map(|s| (s.z_mm, s.x_mm)).collect();
        points.sort_by(|a, b| a.0.total_cmp(&b.0));
        if points.is_empty() {
            return Err(ProfileError::Samples("the target has no points".into()));
        }
        if points.windows(2).any(|w| w[1].0 <= w[0].0) {
            return Err(ProfileError::Samples("the target has two points at one Z".into()));
        }
        Ok(Target::Points(points))
    }

    /// X at `z` (linear between points; `None` outside them).
    pub fn at(&self, z: f64) -> Option<f64> {
        match self {
            Target::Constant(x) => Some(*x),
            Target::Points(p) => {
                let i = p.partition_point(|q| q.0 < z);
                match (i.checked_sub(1).map(|j| p[j]), p.get(i)) {
                    (_, Some(&(z1, x1))) if z1 == z => Some(x1),
                    (Some((z0, x0)), Some(&(z1, x1))) => Some(x0 + (x1 - x0) * (z - z0) / (z1 - z0)),
                    _ => None,
                }
            }
        }
    }

    fn check_covers(&self, lo: f64, hi: f64) -> Result<(), ProfileError> {
        match self {
            Target::Points(p) if self.at(lo).is_none() || self.at(hi).is_none() => {
                Err(ProfileError::TargetRange { lo: p[0].0, hi: p[p.len() - 1].0, need_lo: lo, need_hi: hi })
            }
            _ => Ok(()),
        }
    }
}

/// The local quadratic least-squares fit of `points` `(z, x)` at `z`, tricube weights
/// over `|z_i - z| < window / 2` (near an end the window holds fewer points, and the fit
/// is noisier there). `None` with fewer than 5 points in the window.
pub fn smooth(points: &[(f64, f64)], window_mm: f64, z: f64) -> Option<f64> {
    let h = window_mm / 2.0;
    let center = z;
    // Sums of w u^k (k = 0..4) and w u^k x (k = 0..2), u = (z_i - center) / h.
    let (mut s, mut t, mut used) = ([0.0f64; 5], [0.0f64; 3], 0);
    for &(zi, xi) in points {
        let u = (zi - center) / h;
        if u.abs() >= 1.0 {
            continue;
        }
        let w = (1.0 - u.abs().powi(3)).powi(3);
        let mut p = w;
        for (k, sk) in s.iter_mut().enumerate() {
            *sk += p;
            if k < 3 {
                t[k] += p * xi;
            }
            p *= u;
        }
        used += 1;
    }
    if used < 5 {
        return None;
    }
    // Solve [s0 s1 s2; s1 s2 s3; s2 s3 s4] c = t (Cramer), evaluate c0 + c1 u + c2 u^2.
    let det3 = |m: [[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let m = [[s[0], s[1], s[2]], [s[1], s[2], s[3]], [s[2], s[3], s[4]]];
    let d = det3(m);
    if d.abs() < 1e-12 * s[0].powi(3) {
        return None;
    }
    let column = |k: usize| {
        let mut m = m;
        for (row, value) in m.iter_mut().zip(t) {
            row[k] = value;
        }
        det3(m) / d
    };
    let u = (z - center) / h;
    Some(column(0) + column(1) * u + column(2) * u * u)
}

/// Size and form of a profile against a target.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FormError {
    /// Mean deviation from the target, mm (the size error).
    pub size_mm: f64,
    /// Peak to valley of the deviation less its mean, mm.
    pub pv_mm: f64,
    /// RMS of the deviation less its mean, mm.
    pub rms_mm: f64,
    /// Peak to valley of the deviation filtered by [`smooth`] at the window given, mm.
    pub filtered_pv_mm: f64,
}

/// The form error of `profile` against `target` (see [`FormError`]), filtered at `window_mm`.
pub fn form_error(profile: &Profile, target: &Target, window_mm: f64) -> Result<FormError, ProfileError> {
    let deviation = deviations(profile, target)?;
    let n = deviation.len() as f64;
    let size_mm = deviation.iter().map(|p| p.1).sum::<f64>() / n;
    let (lo, hi) = deviation.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| (lo.min(p.1), hi.max(p.1)));
    let rms_mm = (deviation.iter().map(|p| (p.1 - size_mm).powi(2)).sum::<f64>() / n).sqrt();
    let filtered: Vec<f64> = deviation.iter().filter_map(|p| smooth(&deviation, window_mm, p.0)).collect();
    if filtered.len() != deviation.len() {
        return Err(ProfileError::Samples(format!("fewer than 5 samples in a {window_mm} mm window somewhere")));
    }
    let (flo, fhi) = filtered.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| (lo.min(v), hi.max(v)));
    Ok(FormError { size_mm, pv_mm: hi - lo, rms_mm, filtered_pv_mm: fhi - flo })
}

/// `(z, measured - target)` per sample, checked.
fn deviations(profile: &Profile, target: &Target) -> Result<Vec<(f64, f64)>, ProfileError> {
    if profile.samples.len() < 5 {
        return Err(ProfileError::Samples(format!("{} samples: at least 5 needed", profile.samples.len())));
    }
    let (lo, hi) = profile.z_range().ok_or_else(|| ProfileError::Samples("no samples".into()))?;
    if hi - lo <= 0.0 {
        return Err(ProfileError::Samples("every sample at one Z: not a traverse".into()));
    }
    target.check_covers(lo, hi)?;
    Ok(profile.samples.iter().map(|s| (s.z_mm, s.x_mm - target.at(s.z_mm).unwrap_or_default())).collect())
}

/// How [`compensate`] works.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CompensateOptions {
    /// The noise filter's window, mm.
    pub window_mm: f64,
    /// Largest distance between the program's path and the compensated curve, mm (half
    /// for the polyline, half for the corner blends).
    pub tolerance_mm: f64,
    /// Spacing at which the curve is evaluated, mm.
    pub grid_mm: f64,
    /// The traverse feed, mm/min (lowered where the X acceleration limit asks).
    pub feed_mm_min: f64,
    /// The largest peak-to-valley form error a compensation may correct, mm.
    pub max_correction_mm: f64,
    /// How far past the measured ends the program grinds (at the end values), mm.
    pub lead_mm: f64,
    /// How far X backs off before and after the pass, mm.
    pub retract_mm: f64,
    /// X's acceleration limit, mm/s^2 (for the feed).
    pub x_acceleration_mm_s2: f64,
}

impl Default for CompensateOptions {
    /// A 2 mm filter window, 0.2 um tolerance, a 0.05 mm grid, 600 mm/min, at most 0.2
    /// mm corrected, 0.5 mm lead, 0.1 mm retract, X at 500 mm/s^2.
    fn default() -> Self {
        CompensateOptions {
            window_mm: 2.0,
            tolerance_mm: 0.0002,
            grid_mm: 0.05,
            feed_mm_min: 600.0,
            max_correction_mm: 0.2,
            lead_mm: 0.5,
            retract_mm: 0.1,
            x_acceleration_mm_s2: 500.0,
        }
    }
}

/// A compensated grinding pass.
#[derive(Clone, Debug, PartialEq)]
pub struct Compensation {
    /// The compensated curve `X(z)` on the grid, `(z_mm, x_mm)`.
    pub curve: Vec<(f64, f64)>,
    /// The filtered form error on the grid, `(z_mm, f_mm)` (mean 0).
    pub form: Vec<(f64, f64)>,
    /// The polyline the program follows, `(z_mm, x_mm)` (lead-in and lead-out included).
    pub path: Vec<(f64, f64)>,
    /// The feed the program uses, mm/min.
    pub feed_mm_min: f64,
    /// The G-code program.
    pub program: String,
}

impl Compensation {
    /// The compensated curve at `z` (linear on the grid, end values outside).
    pub fn x_at(&self, z: f64) -> f64 {
        let c = &self.curve;
        let i = c.partition_point(|p| p.0 < z).clamp(1, c.len() - 1);
        let ((z0, x0), (z1, x1)) = (c[i - 1], c[i]);
        let u = ((z - z0) / (z1 - z0)).clamp(0.0, 1.0);
        x0 + (x1 - x0) * u
    }
}

/// Douglas-Peucker: the indices of `points` to keep so that every point lies within
/// `tolerance` (in X, at its Z) of the polyline through the kept ones.
fn simplify(points: &[(f64, f64)], tolerance: f64) -> Vec<usize> {
    let mut keep = vec![0, points.len() - 1];
    let mut stack = vec![(0, points.len() - 1)];
    while let Some((a, b)) = stack.pop() {
        let ((za, xa), (zb, xb)) = (points[a], points[b]);
        let worst = (a + 1..b)
            .map(|i| {
                let (z, x) = points[i];
                (i, (x - (xa + (xb - xa) * (z - za) / (zb - za))).abs())
            })
            .max_by(|p, q| p.1.total_cmp(&q.1));
        if let Some((i, _)) = worst.filter(|w| w.1 > tolerance) {
            keep.push(i);
            stack.push((a, i));
            stack.push((i, b));
        }
    }
    keep.sort_unstable();
    keep.dedup();
    keep
}

/// The compensated program for `measured` against `target` (see the crate documentation).
pub fn compensate(
    measured: &Profile,
    target: &Target,
    options: &CompensateOptions,
) -> Result<Compensation, ProfileError> {
    let o = options;
    let positive = [
        ("window_mm", o.window_mm),
        ("tolerance_mm", o.tolerance_mm),
        ("grid_mm", o.grid_mm),
        ("feed_mm_min", o.feed_mm_min),
        ("max_correction_mm", o.max_correction_mm),
        ("x_acceleration_mm_s2", o.x_acceleration_mm_s2),
    ];
    for (name, v) in positive {
        if !(v.is_finite() && v > 0.0) {
            return Err(ProfileError::Options(format!("{name} = {v}: must be a positive number")));
        }
    }
    for (name, v) in [("lead_mm", o.lead_mm), ("retract_mm", o.retract_mm)] {
        if !(v.is_finite() && v >= 0.0) {
            return Err(ProfileError::Options(format!("{name} = {v}: must be zero or more")));
        }
    }
    let deviation = deviations(measured, target)?;
    let (lo, hi) = measured.z_range().unwrap_or_default();
    if (hi - lo) / o.grid_mm > 1e6 {
        return Err(ProfileError::Options(format!("grid_mm = {}: over a million points", o.grid_mm)));
    }
    let steps = ((hi - lo) / o.grid_mm).ceil().max(1.0) as usize;
    let mut form = Vec::with_capacity(steps + 1);
    for k in 0..=steps {
        let z = lo + (hi - lo) * k as f64 / steps as f64;
        let f = smooth(&deviation, o.window_mm, z).ok_or_else(|| {
            ProfileError::Samples(format!(
                "fewer than 5 samples within {} mm of Z {z:.3} mm: a wider filter window, or a denser traverse",
                o.window_mm / 2.0
            ))
        })?;
        form.push((z, f));
    }
    let mean = form.iter().map(|p| p.1).sum::<f64>() / form.len() as f64;
    for p in &mut form {
        p.1 -= mean;
    }
    let (flo, fhi) = form.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| (lo.min(p.1), hi.max(p.1)));
    if fhi - flo > o.max_correction_mm {
        return Err(ProfileError::TooLarge { pv_um: (fhi - flo) * 1e3, max_um: o.max_correction_mm * 1e3 });
    }
    let curve: Vec<(f64, f64)> = form.iter().map(|&(z, f)| (z, target.at(z).unwrap_or_default() - f)).collect();

    // The feed: X's acceleration along the curve, v^2 |X''|, within the limit.
    let curvature = curve
        .windows(3)
        .map(|w| ((w[2].1 - 2.0 * w[1].1 + w[0].1) / ((w[2].0 - w[0].0) / 2.0).powi(2)).abs())
        .fold(0.0, f64::max);
    let v_limit = if curvature > 0.0 { (o.x_acceleration_mm_s2 / curvature).sqrt() * 60.0 } else { f64::INFINITY };
    let feed_mm_min = o.feed_mm_min.min(v_limit);

    let kept = simplify(&curve, o.tolerance_mm / 2.0);
    let (first, last) = (curve[0], curve[curve.len() - 1]);
    let mut path = vec![(first.0 - o.lead_mm, first.1)];
    path.extend(kept.iter().map(|&i| curve[i]));
    path.push((last.0 + o.lead_mm, last.1));
    path.dedup();

    let mut p = String::new();
    let _ = writeln!(p, "( finestep compensate: a compensated grinding pass, X against Z, seed 000 )");
    let _ = writeln!(
        p,
        "( {} samples over Z {lo:.3} to {hi:.3} mm; noise filter: local quadratic fit, {} mm window )",
        measured.samples.len(),
        o.window_mm
    );
    let _ = writeln!(
        p,
        "( form error corrected: {:.2} um peak to valley; path within {:.2} um of the compensated curve )",
        (fhi - flo) * 1e3,
        o.tolerance_mm * 1e3
    );
    let _ = writeln!(p, "( {} points on a {} mm grid -> {} G1 moves )", curve.len(), o.grid_mm, path.len() - 1);
    let _ = writeln!(p, "G21 G90 G64 P{:.6}", o.tolerance_mm / 2.0);
    let _ = writeln!(p, "G0 X{:.6}", path[0].1 + o.retract_mm);
    let _ = writeln!(p, "G0 Z{:.6}", path[0].0);
    let _ = writeln!(p, "G1 X{:.6} F{:.1}", path[0].1, feed_mm_min);
    for &(z, x) in &path[1..] {
        let _ = writeln!(p, "G1 Z{z:.6} X{x:.6}");
    }
    let _ = writeln!(p, "G0 X{:.6}", path[path.len() - 1].1 + o.retract_mm);
    let _ = writeln!(p, "M2");
    Ok(Compensation { curve, form, path, feed_mm_min, program: p })
}

#[cfg(test)]
mod tests;

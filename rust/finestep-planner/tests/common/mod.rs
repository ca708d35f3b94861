//! Helpers the planner's integration tests share: the default machine per profile,
//! parsing, planning with the independent checker's verdict, the committed programs.

#![allow(dead_code)]

use std::path::PathBuf;

use finestep_gcode::Program;
use finestep_planner::{check_program, plan_program, CheckReport, MachineConfig, PlannedProgram, ProfileKind};

pub const PROFILES: [ProfileKind; 2] = [ProfileKind::Trapezoid, ProfileKind::SCurve];

pub fn programs_dir() -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../tests/programs"))
}

/// The `.ngc` files of [`programs_dir`], sorted.
pub fn program_names() -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(programs_dir())
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.file_name().to_string_lossy().to_string()))
        .filter(|n| n.ends_with(".ngc"))
        .collect();
    names.sort();
    names
}

/// `ms` rounded to a whole number of the default core's step slots: the periods a
/// machine can be configured with (the core runs periods in multiples of its `S`
/// clocks, and the configuration refuses any other).
pub fn period_in_slots(ms: f64) -> f64 {
    let core = finestep_planner::config::CoreLimits::default();
    let slot_ms = f64::from(core.step_slots) / core.clock_hz * 1e3;
    (ms / slot_ms).round().max(1.0) * slot_ms
}

pub fn config(profile: ProfileKind) -> MachineConfig {
    MachineConfig { profile, ..MachineConfig::default() }
}

pub fn parse(name: &str, source: &str) -> Program {
    finestep_gcode::parse_str(source, name).unwrap_or_else(|e| panic!("{e}"))
}

/// Plans and checks `program`, failing with the checker's findings.
pub fn plan_and_check(name: &str, program: &Program, config: &MachineConfig) -> (PlannedProgram, CheckReport) {
    let planned = plan_program(config, program).unwrap_or_else(|e| panic!("{name} ({:?}): {e}", config.profile));
    let report = check_program(config, program, &planned.records).unwrap();
    assert!(
        report.passed(),
        "{name} ({:?}): {} violations, the first: {:#?}",
        config.profile,
        report.violation_count,
        report.violations
    );
    assert_eq!(report.endpoint_error_steps, [0.0; 4], "{name}");
    (planned, report)
}

/// A program of `tests/programs/`, parsed.
pub fn read(name: &str) -> Program {
    let path = programs_dir().join(name);
    let source = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    parse(name, &source)
}

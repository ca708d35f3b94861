//! How much of the limits the plans use (issue 18's figures), computed in one place for
//! `finestep bench --host-only` and the `limit_figures` example: seed 002's machine, the
//! bench's CAM program of short segments, the peak acceleration and jerk on seed 002's
//! star, and machining time over the independent lower bound ([`crate::bound`]) on a set
//! of programs and on 20 000 short segments.

use finestep_gcode::Program;

use crate::{check_program, plan_program, plan_stream, time_lower_bound, MachineConfig, ProfileKind, ProgramError};

/// Why a figure could not be computed.
#[derive(Debug, thiserror::Error)]
pub enum FigureError {
    /// A program could not be planned or bounded.
    #[error("{name}:{line}: {reason}")]
    Program {
        /// The program.
        name: String,
        /// Its line (0: not about one line).
        line: usize,
        /// What is wrong.
        reason: String,
    },
    /// The checker could not read a program (a configuration or compensation error).
    #[error("{name}: {reason}")]
    Check {
        /// The program.
        name: String,
        /// What is wrong.
        reason: String,
    },
    /// The plan broke a limit: a figure of it would mean nothing.
    #[error("{name} ({profile:?}): the checker found {violations} violations")]
    Violations {
        /// The program.
        name: String,
        /// The profile planned.
        profile: ProfileKind,
        /// How many.
        violations: usize,
    },
    /// A program could not be read or parsed (the message names it).
    #[error("{0}")]
    Parse(String),
}

fn program_error(name: &str) -> impl Fn(ProgramError) -> FigureError + '_ {
    move |e| FigureError::Program { name: name.to_string(), line: e.line, reason: e.reason }
}

/// Seed 002's machine: 200 mm/s, 300 mm/s², 3 000 mm/s³ on X and Y, a 1 µm chord
/// (contour) tolerance, the default period; the other axes as the default machine.
pub fn seed_002(profile: ProfileKind) -> MachineConfig {
    let mut config = MachineConfig { profile, chord_tolerance_mm: 0.001, ..MachineConfig::default() };
    for (name, axis) in config.axes.iter_mut() {
        if name == "X" || name == "Y" {
            (axis.max_velocity, axis.max_acceleration, axis.max_jerk) = (200.0, 300.0, 3000.0);
        }
    }
    config
}

/// The bench's CAM program: `moves` short G1 segments along a wavy spiral with a Z
/// staircase, blended (G64 P0.01), without a program end.
pub fn cam_program(moves: usize) -> String {
    let mut text = String::with_capacity(moves * 32);
    text.push_str("G21 G90 G17 G64 P0.01\nF3000\n");
    for i in 0..moves {
        let t = i as f64 * 0.01;
        let r = 20.0 + 5.0 * (7.0 * t).sin();
        text.push_str(&format!("G1 X{:.4} Y{:.4} Z{:.4}\n", r * t.cos(), r * t.sin(), -0.001 * i as f64 % 5.0));
    }
    text
}

/// The committed test programs (`tests/programs/` of this repository), by file name.
pub fn test_programs() -> Result<Vec<(String, Program)>, FigureError> {
    let dir = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../../tests/programs"));
    let entries = std::fs::read_dir(dir).map_err(|e| FigureError::Parse(format!("{}: {e}", dir.display())))?;
    let mut names: Vec<String> = entries
        .filter_map(|e| e.ok().map(|e| e.file_name().to_string_lossy().to_string()))
        .filter(|n| n.ends_with(".ngc"))
        .collect();
    names.sort();
    names
        .into_iter()
        .map(|name| {
            let program = finestep_gcode::parse_file(dir.join(&name)).map_err(|e| FigureError::Parse(e.to_string()))?;
            Ok((name, program))
        })
        .collect()
}

/// Machining time (the periods that move) of `program` planned on `config`, in seconds.
fn moving_time(config: &MachineConfig, records: impl Iterator<Item = bool>) -> f64 {
    records.filter(|&moving| moving).count() as f64 * config.period_ms * 1e-3
}

/// The figures for `profile`, one line each: seed 002's star (`star.ngc` among
/// `programs`) peaks over the limits per axis and along the path, machining time over
/// the lower bound on `programs` (the built-in machine) and on the first 20 000 moves of
/// [`cam_program`] (with the checker's verdict on that plan). Every plan must pass the
/// checker.
pub fn limit_figures(programs: &[(String, Program)], profile: ProfileKind) -> Result<Vec<String>, FigureError> {
    let mut lines = Vec::new();
    let checked =
        |name: &str, config: &MachineConfig, program: &Program, records: &[finestep_interface::PeriodRecord]| {
            let report = check_program(config, program, records)
                .map_err(|e| FigureError::Check { name: name.to_string(), reason: e.to_string() })?;
            if !report.passed() {
                return Err(FigureError::Violations {
                    name: name.to_string(),
                    profile,
                    violations: report.violations.len(),
                });
            }
            Ok(report)
        };
    if let Some((name, star)) = programs.iter().find(|(n, _)| n == "star.ngc") {
        let config = seed_002(profile);
        let planned = plan_program(&config, star).map_err(program_error(name))?;
        let report = checked(name, &config, star, &planned.records)?;
        let [x, y] = [0, 1].map(|a| report.axis_max[a]);
        lines.push(format!(
            "{:<44} a X {:.3} Y {:.3} path {:.3}   j X {:.3} Y {:.3} path {:.3}   ({:.3} s)",
            format!("star, seed 002, peak / limit ({profile:?})"),
            x[1] / 300.0,
            y[1] / 300.0,
            report.path_max[1] / 300.0,
            x[2] / 3000.0,
            y[2] / 3000.0,
            report.path_max[2] / 3000.0,
            planned.records.len() as f64 * report.period_s
        ));
    }
    let (mut time, mut bound, mut worst) = (0.0, 0.0, (0.0f64, String::new()));
    for (name, program) in programs {
        let config = MachineConfig { profile, ..MachineConfig::default() };
        let planned = plan_program(&config, program).map_err(program_error(name))?;
        checked(name, &config, program, &planned.records)?;
        let t = moving_time(&config, planned.records.iter().map(|r| r.inc.iter().any(|i| i.to_bits() != 0)));
        let b = time_lower_bound(&config, program).map_err(program_error(name))?;
        if t / b > worst.0 {
            worst = (t / b, name.clone());
        }
        time += t;
        bound += b;
    }
    lines.push(format!(
        "{:<44} {:>7.3}   (worst {:.3} on {}; {:.2} s of motion against {:.2} s)",
        format!("time / lower bound, {} programs ({profile:?})", programs.len()),
        time / bound,
        worst.0,
        worst.1,
        time,
        bound
    ));
    let cam = finestep_gcode::parse_str(&(cam_program(20_000) + "M2\n"), "cam.ngc")
        .map_err(|e| FigureError::Parse(format!("cam.ngc: {e}")))?;
    let config = MachineConfig { profile, ..MachineConfig::default() };
    let mut records = Vec::new();
    for period in plan_stream(&config, &cam).map_err(program_error("cam.ngc"))?.periods {
        records.push(period.map_err(program_error("cam.ngc"))?.0);
    }
    let report = checked("cam.ngc", &config, &cam, &records)?;
    let t = moving_time(&config, records.iter().map(|r| r.inc.iter().any(|i| i.to_bits() != 0)));
    let b = time_lower_bound(&config, &cam).map_err(program_error("cam.ngc"))?;
    lines.push(format!(
        "{:<44} {:>7.3}   ({t:.2} s of motion against {b:.2} s; deviation {:.4} mm, path a {:.0} j {:.0})",
        format!("time / lower bound, 20 000 short G1 ({profile:?})"),
        t / b,
        report.max_deviation,
        report.path_max[1],
        report.path_max[2],
    ));
    Ok(lines)
}

/// How one program of a corpus came out ([`corpus_outcome`]).
#[derive(Debug, Clone, PartialEq)]
pub enum CorpusOutcome {
    /// Planned, passed by the checker and bounded: its machining time (the periods that
    /// move) and its lower bound ([`crate::bound`]), s.
    Timed {
        /// Machining time, s.
        time: f64,
        /// The lower bound, s.
        bound: f64,
    },
    /// Planned and passed by the checker, but nothing moves (a subroutine file, a
    /// program of settings only): no ratio.
    NoMotion,
    /// The planner or the bound refused it (line 0: not about one line).
    Refused {
        /// The line.
        line: usize,
        /// Why.
        reason: String,
    },
    /// The checker could not read it (a configuration or compensation error).
    CheckError(String),
    /// The checker found violations: a planner bug (or a checker bug).
    Violations {
        /// How many.
        count: usize,
        /// The first one.
        first: String,
    },
}

/// Plans `program` on `config`, checks the records and bounds the machining time: the
/// corpus figure's one program ([`CorpusOutcome`]).
pub fn corpus_outcome(config: &MachineConfig, program: &Program) -> CorpusOutcome {
    let planned = match plan_program(config, program) {
        Ok(planned) => planned,
        Err(e) => return CorpusOutcome::Refused { line: e.line, reason: e.reason },
    };
    let report = match check_program(config, program, &planned.records) {
        Ok(report) => report,
        Err(e) => return CorpusOutcome::CheckError(e.to_string()),
    };
    if !report.passed() {
        return CorpusOutcome::Violations {
            count: report.violation_count,
            first: report.violations.first().cloned().unwrap_or_default(),
        };
    }
    let time = moving_time(config, planned.records.iter().map(|r| r.inc.iter().any(|i| i.to_bits() != 0)));
    let bound = match time_lower_bound(config, program) {
        Ok(bound) => bound,
        Err(e) => return CorpusOutcome::Refused { line: e.line, reason: format!("(the bound) {}", e.reason) },
    };
    if time == 0.0 && bound == 0.0 {
        CorpusOutcome::NoMotion
    } else {
        CorpusOutcome::Timed { time, bound }
    }
}

/// A corpus's time over the lower bound ([`corpus_outcome`] on each program): the
/// ratio of the sums, the mean of the per-program ratios, and the programs by ratio,
/// worst first.
#[derive(Debug, Clone, PartialEq)]
pub struct CorpusSummary {
    /// Machining time over the bound, summed over the timed programs.
    pub total_ratio: f64,
    /// The mean of the timed programs' ratios.
    pub mean_ratio: f64,
    /// Their median (of an even count, the mean of the middle two).
    pub median_ratio: f64,
    /// Machining time and bound summed, s.
    pub time: f64,
    /// The bound summed, s.
    pub bound: f64,
    /// The timed programs and their ratios, worst first.
    pub ratios: Vec<(String, f64)>,
}

/// The summary of the timed programs among `outcomes` (None: none timed).
pub fn corpus_summary(outcomes: &[(String, CorpusOutcome)]) -> Option<CorpusSummary> {
    let mut ratios = Vec::new();
    let (mut time, mut bound) = (0.0, 0.0);
    for (name, outcome) in outcomes {
        if let CorpusOutcome::Timed { time: t, bound: b } = outcome {
            time += t;
            bound += b;
            ratios.push((name.clone(), t / b));
        }
    }
    if ratios.is_empty() {
        return None;
    }
    let mean_ratio = ratios.iter().map(|(_, r)| r).sum::<f64>() / ratios.len() as f64;
    ratios.sort_by(|a, b| b.1.total_cmp(&a.1));
    let n = ratios.len();
    let median_ratio = 0.5 * (ratios[(n - 1) / 2].1 + ratios[n / 2].1);
    Some(CorpusSummary { total_ratio: time / bound, mean_ratio, median_ratio, time, bound, ratios })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_corpus_summary_counts_only_the_timed_programs() {
        let outcomes = [
            ("a".to_string(), CorpusOutcome::Timed { time: 2.0, bound: 2.0 }),
            ("b".to_string(), CorpusOutcome::NoMotion),
            ("c".to_string(), CorpusOutcome::Timed { time: 3.0, bound: 1.0 }),
            ("d".to_string(), CorpusOutcome::Refused { line: 3, reason: "no".into() }),
            ("e".to_string(), CorpusOutcome::Timed { time: 3.0, bound: 2.0 }),
            ("f".to_string(), CorpusOutcome::Violations { count: 1, first: "v".into() }),
        ];
        let s = corpus_summary(&outcomes).unwrap();
        assert_eq!((s.time, s.bound, s.total_ratio), (8.0, 5.0, 1.6));
        assert_eq!((s.mean_ratio, s.median_ratio), (5.5 / 3.0, 1.5));
        let names: Vec<&str> = s.ratios.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, ["c", "e", "a"]);
        assert_eq!(corpus_summary(&outcomes[1..2]), None);
    }
}

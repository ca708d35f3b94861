//! `finestep gcode-canon FILE` (finestep's canonical events for a program) and
//! `finestep conformance MANIFEST` (the differential check against LinuxCNC's `rs274`,
//! whose outputs scripts/conformance.sh gathers): one table of agree / refused / disagree
//! / crash, a per-program list, and a diff per disagreement.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::Duration;

use anyhow::{bail, Context};
use finestep_gcode::conformance::Event;
use finestep_gcode::conformance::{compare, events_of, rs274_events};
use finestep_gcode::Options;
use finestep_planner::cutter_comp::{compensate, EntryExit, ToolTable};

/// A program interprets for at most this long before it counts as hung.
const TIMEOUT: Duration = Duration::from_secs(10);

/// Interpreter options with the tool lengths of a LinuxCNC tool table in inches (as
/// rs274 reads one without an INI file).
pub fn options(tool_table: Option<&Path>) -> anyhow::Result<Options> {
    // rs274 without an INI file keeps its offset parameters in inches.
    let mut options = Options { machine_unit_mm: 25.4, ..Options::default() };
    if let Some(path) = tool_table {
        let text = std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
        options.tools = Options::read_tool_table(&text, 25.4).map_err(anyhow::Error::msg)?;
    }
    Ok(options)
}

/// The radii of a LinuxCNC tool table's tools (its D column, a diameter in inches).
pub fn radii(tool_table: Option<&Path>) -> anyhow::Result<ToolTable> {
    // rs274 lays out the entry and exit moves of cutter compensation its own way.
    let mut table = ToolTable::new().with_entry_exit(EntryExit::LinuxCnc);
    if let Some(path) = tool_table {
        let text = std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
        for line in text.lines() {
            let line = line.split(';').next().unwrap_or("");
            let word = |letter: char| {
                line.split_whitespace()
                    .find(|w| w.starts_with(letter) || w.starts_with(letter.to_ascii_lowercase()))
                    .and_then(|w| w[1..].parse::<f64>().ok())
            };
            if let (Some(tool), Some(diameter)) = (word('T'), word('D')) {
                table.set_radius_mm(tool as u32, diameter * 25.4 / 2.0);
            }
        }
    }
    Ok(table)
}

/// finestep's events for `file`: interpreted, then cutter compensation applied as the
/// planner applies it (rs274 prints the compensated path).
fn events(file: &Path, options: &Options, radii: &ToolTable) -> Result<Vec<Event>, String> {
    let program = finestep_gcode::parse_file_with(file, options).map_err(|e| e.to_string())?;
    let program = compensate(&program, radii).map_err(|e| format!("{}: {e}", file.display()))?;
    Ok(events_of(&program))
}

/// Prints finestep's canonical events for `file`, one a line.
/// With `var`, the parameter file is read before and written back after, as `rs274 -v`.
pub fn canon(file: &Path, tool_table: Option<&Path>, var: Option<&Path>) -> anyhow::Result<()> {
    let mut options = options(tool_table)?;
    if let Some(var) = var {
        options.parameters = crate::parameter_file::load(var)?;
    }
    let (program, parameters) = finestep_gcode::parse_file_with_parameters(file, &options)?;
    if let Some(var) = var {
        crate::parameter_file::save(var, &parameters)?;
    }
    let program = compensate(&program, &radii(tool_table)?)?;
    for event in events_of(&program) {
        println!("{event}");
    }
    Ok(())
}

/// How one program came out.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
enum Outcome {
    Agree,
    RefusedUnsupported,
    RefusedOther,
    Disagree,
    Crash,
    BothRefuse,
    OnlyRs274Refuses,
}

impl Outcome {
    const ALL: [Outcome; 7] = [
        Outcome::Agree,
        Outcome::RefusedUnsupported,
        Outcome::RefusedOther,
        Outcome::Disagree,
        Outcome::Crash,
        Outcome::BothRefuse,
        Outcome::OnlyRs274Refuses,
    ];

    fn label(self) -> &'static str {
        match self {
            Outcome::Agree => "agree",
            Outcome::RefusedUnsupported => "refused: unsupported (clean)",
            Outcome::RefusedOther => "refused: other error (rs274 accepts)",
            Outcome::Disagree => "disagree",
            Outcome::Crash => "crash (panic or > 10 s)",
            Outcome::BothRefuse => "rs274 refuses, finestep refuses",
            Outcome::OnlyRs274Refuses => "rs274 refuses, finestep accepts",
        }
    }
}

/// finestep's interpretation of `file` on its own thread: Ok(events) or Err(message),
/// or None when it panicked or ran past [`TIMEOUT`].
fn interpret(file: &Path, options: &Options, radii: &ToolTable) -> Option<Result<Vec<Event>, String>> {
    let (send, receive) = mpsc::channel();
    let path = file.to_path_buf();
    let (options, radii) = (options.clone(), radii.clone());
    std::thread::spawn(move || {
        let result = std::panic::catch_unwind(|| events(&path, &options, &radii));
        // The receiver may have given up on a slow program.
        let _ = send.send(result.ok());
    });
    receive.recv_timeout(TIMEOUT).ok().flatten()
}

/// Runs the comparison over MANIFEST's lines `rs274-exit-status<TAB>program.ngc<TAB>rs274-output`
/// and writes `report.txt` and `diffs/` under `out`.
pub fn run(manifest: &Path, out: &Path, tool_table: Option<&Path>) -> anyhow::Result<()> {
    let (options, radii) = (options(tool_table)?, radii(tool_table)?);
    let text = std::fs::read_to_string(manifest).with_context(|| format!("reading {}", manifest.display()))?;
    let diffs = out.join("diffs");
    if diffs.exists() {
        std::fs::remove_dir_all(&diffs)?;
    }
    std::fs::create_dir_all(&diffs)?;
    let mut report = String::new();
    let mut counts = [0usize; Outcome::ALL.len()];
    // Quiet the default panic message: a panic is reported as a crash in the table.
    std::panic::set_hook(Box::new(|_| {}));
    for line in text.lines().filter(|l| !l.trim().is_empty()) {
        let fields: Vec<&str> = line.split('\t').collect();
        let [status, program, rs274] = fields[..] else { bail!("bad manifest line {line:?}") };
        let program = PathBuf::from(program);
        let rs274_accepts = status == "0";
        let theirs = std::fs::read_to_string(rs274).with_context(|| format!("reading {rs274}"))?;
        let (outcome, detail) = match (interpret(&program, &options, &radii), rs274_accepts) {
            (None, _) => (Outcome::Crash, "panicked or timed out".to_string()),
            (Some(Err(e)), false) => (Outcome::BothRefuse, e),
            (Some(Ok(_)), false) => {
                // rs274 prints its error on standard error (kept beside its output).
                let err = std::fs::read_to_string(format!("{rs274}.err")).unwrap_or_default();
                let why = err.lines().find(|l| !l.trim().is_empty() && l.trim() != "executing").unwrap_or("?");
                (Outcome::OnlyRs274Refuses, format!("rs274: {}", why.trim()))
            }
            (Some(Err(e)), true) if e.contains(": unsupported: ") => (Outcome::RefusedUnsupported, e),
            (Some(Err(e)), true) => (Outcome::RefusedOther, e),
            (Some(Ok(ours)), true) => {
                let theirs = rs274_events(&theirs).map_err(anyhow::Error::msg)?;
                match compare(&ours, &theirs) {
                    None => (Outcome::Agree, String::new()),
                    Some(diff) => {
                        let name = program.to_string_lossy().trim_start_matches('/').replace('/', "__");
                        let path = diffs.join(format!("{name}.diff"));
                        std::fs::write(&path, format!("{}\n{diff}", program.display()))?;
                        (Outcome::Disagree, path.display().to_string())
                    }
                }
            }
        };
        counts[outcome as usize] += 1;
        let detail = detail.lines().next().unwrap_or("");
        writeln!(report, "{:<38} {}  {detail}", outcome.label(), program.display())?;
    }
    let mut lines: Vec<&str> = report.lines().collect();
    lines.sort();
    std::fs::write(out.join("report.txt"), lines.join("\n") + "\n")?;
    let accepted: usize = counts[..5].iter().sum();
    println!(
        "conformance against rs274 ({} programs; per program: {})",
        text.lines().count(),
        out.join("report.txt").display()
    );
    for outcome in Outcome::ALL {
        println!("  {:<40} {:>4}", outcome.label(), counts[outcome as usize]);
    }
    if accepted > 0 {
        println!(
            "  agreement on programs rs274 accepts: {} of {} ({:.1} %)",
            counts[0],
            accepted,
            100.0 * counts[0] as f64 / accepted as f64
        );
    }
    Ok(())
}

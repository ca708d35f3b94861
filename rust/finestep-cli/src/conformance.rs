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
use finestep_gcode::conformance::{
    compare, diameter_in_block, events_of, m61_as_m6, rs274_events, split_length_offset, Rs274Output,
};
use finestep_gcode::{BlockKind, CompSide, Options, Plane};
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
    Rs274Artefact,
    Crash,
    BothRefuse,
    OnlyRs274Refuses,
}

impl Outcome {
    const ALL: [Outcome; 8] = [
        Outcome::Agree,
        Outcome::RefusedUnsupported,
        Outcome::RefusedOther,
        Outcome::Disagree,
        Outcome::Rs274Artefact,
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
            Outcome::Rs274Artefact => "rs274 stand-alone artefact (re-checked)",
            Outcome::Crash => "crash (panic or > 10 s)",
            Outcome::BothRefuse => "rs274 refuses, finestep refuses",
            Outcome::OnlyRs274Refuses => "rs274 refuses, finestep accepts",
        }
    }

    /// Whether rs274 accepted the program.
    fn rs274_accepts(self) -> bool {
        !matches!(self, Outcome::BothRefuse | Outcome::OnlyRs274Refuses)
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

/// Writes `text`, a variant of `program`, to `out`/variants/ (named after the program's
/// path) and gives its absolute path.
fn write_variant(out: &Path, program: &Path, text: &str) -> anyhow::Result<PathBuf> {
    let dir = out.join("variants");
    std::fs::create_dir_all(&dir)?;
    let name = program.to_string_lossy().trim_start_matches('/').replace('/', "__");
    let path = std::fs::canonicalize(&dir)?.join(name);
    std::fs::write(&path, text)?;
    Ok(path)
}

/// rs274's output for `program` run in `dir` (where its subroutines are), or None if it
/// refuses it or runs past 10 s.
fn rs274(program: &Path, dir: &Path, tool_table: &Path) -> Option<String> {
    rs274_run(program, dir, tool_table).and_then(|(accepted, text)| accepted.then_some(text))
}

/// Whether rs274 accepts `program` (run in `dir`), and what it printed (standard output,
/// then standard error).
fn rs274_run(program: &Path, dir: &Path, tool_table: &Path) -> Option<(bool, String)> {
    let output = std::process::Command::new("timeout")
        .arg("10")
        .arg("rs274")
        .arg("-g")
        .arg("-t")
        .arg(tool_table)
        .arg(program)
        .current_dir(dir)
        .stdin(std::process::Stdio::null())
        .output()
        .ok()?;
    let text = String::from_utf8_lossy(&output.stdout).into_owned() + &String::from_utf8_lossy(&output.stderr);
    Some((output.status.success(), text))
}

/// Why finestep's refusal of an entry move as long as the tool radius is LinuxCNC's rule
/// and rs274 passes it only by its unit rounding, if rs274 says
/// so: the program with that G41/G42 turned into G41.1/G42.1 with the table's diameter in
/// the block (exact, in the program's units), which rs274 refuses with LinuxCNC's message.
fn short_entry_artefact(
    program: &Path,
    error: &str,
    options: &Options,
    tool_table: &Path,
    out: &Path,
) -> anyhow::Result<Option<String>> {
    let Some(line) =
        error.split(": line ").nth(1).and_then(|rest| rest.split(':').next()).and_then(|n| n.parse::<usize>().ok())
    else {
        return Ok(None);
    };
    if !error.contains("the entry move after G41/G42") {
        return Ok(None);
    }
    let Ok(parsed) = finestep_gcode::parse_file_with(program, options) else { return Ok(None) };
    // The compensation that move enters, and the tool it names or the one in the spindle.
    let mut tool = 0;
    let mut comp = None;
    for block in parsed.blocks.iter().take_while(|b| b.line <= line) {
        match block.kind {
            BlockKind::ToolChange { tool: t } => tool = t,
            BlockKind::CutterComp { side, tool: d, plane } => {
                comp = (side != CompSide::Off && plane == Plane::Xy).then_some((block.line, d.unwrap_or(tool)))
            }
            BlockKind::CutterCompRadius { .. } => comp = None,
            _ => {}
        }
    }
    let Some((comp_line, tool)) = comp else { return Ok(None) };
    let table = std::fs::read_to_string(tool_table)?;
    let Some(diameter) = table.lines().find_map(|l| {
        let l = l.split(';').next().unwrap_or("");
        let word = |letter: char| {
            l.split_whitespace()
                .find(|w| w.to_ascii_uppercase().starts_with(letter))
                .and_then(|w| w[1..].parse::<f64>().ok())
        };
        (word('T') == Some(f64::from(tool))).then(|| word('D')).flatten()
    }) else {
        return Ok(None);
    };
    let source = std::fs::read_to_string(program)?;
    let Some(variant) = diameter_in_block(&source, comp_line, diameter) else { return Ok(None) };
    let variant_path = write_variant(out, program, &variant)?;
    let here = program.parent().unwrap_or(Path::new("."));
    let message = "Length of cutter compensation entry move is not greater than the tool radius";
    Ok(match rs274_run(&variant_path, here, &std::fs::canonicalize(tool_table)?) {
        Some((false, text)) if text.contains(message) => Some(format!(
            "{error}: LinuxCNC's rule; rs274 passes it with the radius its stand-alone canon reads from the \
             table (unit 0.03937007874016 inch/mm), and refuses it with the diameter exact in the block \
             ({message}: {})",
            variant_path.display()
        )),
        _ => None,
    })
}

/// Why a disagreement is rs274's stand-alone artefact, if it is one that is checked
/// here: the program with each M6 + G43 line split ([`split_length_offset`]) means the
/// same to finestep, and rs274 on it agrees with finestep on the program.
fn tool_change_artefact(
    program: &Path,
    ours: &[Event],
    (options, radii): (&Options, &ToolTable),
    tool_table: &Path,
    out: &Path,
) -> anyhow::Result<Option<String>> {
    let source = std::fs::read_to_string(program).with_context(|| format!("reading {}", program.display()))?;
    let Some(split) = split_length_offset(&source) else { return Ok(None) };
    let variant = write_variant(out, program, &split)?;
    match interpret(&variant, options, radii) {
        Some(Ok(split_ours)) if split_ours == ours => {}
        _ => return Ok(None),
    }
    let here = program.parent().unwrap_or(Path::new("."));
    let Some(theirs) = rs274(&variant, here, &std::fs::canonicalize(tool_table)?) else { return Ok(None) };
    let theirs = rs274_events(&theirs).map_err(anyhow::Error::msg)?;
    Ok(compare(ours, &theirs).is_none().then(|| {
        format!(
            "M6 with G43/G49 in one block: rs274's stand-alone canon re-reads the position without the \
             block's length offset; agrees with rs274 with the offset on a line of its own ({})",
            variant.display()
        )
    }))
}

/// The events without tool changes.
fn without_tool_changes(events: &[Event]) -> Vec<Event> {
    events.iter().filter(|e| !matches!(e, Event::ToolChange { .. })).cloned().collect()
}

/// Why a disagreement is rs274's stand-alone M61 artefact, if it is that: rs274's canon
/// leaves the spindle's tool-table entry at the last M6's tool after `M61 Q` (saicanon.cc
/// `CHANGE_TOOL_NUMBER`), where LinuxCNC loads the new tool's ([`m61_as_m6`]). Checked:
/// with each M61 given as M6 (the variant), rs274 agrees with finestep on the variant;
/// finestep's events on the variant are those on the program but for the variant's tool
/// changes; and the program's own tool changes are rs274's.
fn tool_number_artefact(
    program: &Path,
    (ours, theirs): (&[Event], &Rs274Output),
    (options, radii): (&Options, &ToolTable),
    tool_table: &Path,
    out: &Path,
) -> anyhow::Result<Option<String>> {
    let source = std::fs::read_to_string(program).with_context(|| format!("reading {}", program.display()))?;
    let Some(m6) = m61_as_m6(&source) else { return Ok(None) };
    let tool_changes = |events: &[Event]| -> Vec<Event> {
        events.iter().filter(|e| matches!(e, Event::ToolChange { .. })).cloned().collect()
    };
    if tool_changes(ours) != tool_changes(&theirs.events) {
        return Ok(None);
    }
    let variant = write_variant(out, program, &m6)?;
    let Some(Ok(variant_ours)) = interpret(&variant, options, radii) else { return Ok(None) };
    if without_tool_changes(&variant_ours) != without_tool_changes(ours) {
        return Ok(None);
    }
    let here = program.parent().unwrap_or(Path::new("."));
    let Some(variant_theirs) = rs274(&variant, here, &std::fs::canonicalize(tool_table)?) else { return Ok(None) };
    let variant_theirs = rs274_events(&variant_theirs).map_err(anyhow::Error::msg)?;
    Ok(compare(&variant_ours, &variant_theirs).is_none().then(|| {
        format!(
            "M61: rs274's stand-alone canon (saicanon.cc CHANGE_TOOL_NUMBER) leaves the spindle's tool-table \
             entry at the last M6's tool, which LinuxCNC's iocontrol replaces by the new tool's \
             (EMC_TOOL_SET_NUMBER: load_tool) before the interpreter re-reads it for #5400-#5409 and G43; \
             agrees with rs274 with each M61 Q given as M6 T ({})",
            variant.display()
        )
    }))
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
            (Some(Err(e)), true) if e.contains("it must move more than the tool radius") => {
                let artefact = match tool_table {
                    Some(table) => short_entry_artefact(&program, &e, &options, table, out)?,
                    None => None,
                };
                match artefact {
                    Some(why) => (Outcome::Rs274Artefact, why),
                    None => (Outcome::RefusedOther, e),
                }
            }
            (Some(Err(e)), true) => (Outcome::RefusedOther, e),
            (Some(Ok(ours)), true) => {
                let theirs = rs274_events(&theirs).map_err(anyhow::Error::msg)?;
                match compare(&ours, &theirs) {
                    None => (Outcome::Agree, String::new()),
                    Some(diff) => {
                        let artefact = match tool_table {
                            Some(table) => match tool_change_artefact(&program, &ours, (&options, &radii), table, out)?
                            {
                                Some(why) => Some(why),
                                None => tool_number_artefact(
                                    &program,
                                    (ours.as_slice(), &theirs),
                                    (&options, &radii),
                                    table,
                                    out,
                                )?,
                            },
                            None => None,
                        };
                        if let Some(why) = artefact {
                            (Outcome::Rs274Artefact, why)
                        } else {
                            let name = program.to_string_lossy().trim_start_matches('/').replace('/', "__");
                            let path = diffs.join(format!("{name}.diff"));
                            std::fs::write(&path, format!("{}\n{diff}", program.display()))?;
                            (Outcome::Disagree, path.display().to_string())
                        }
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
    let accepted: usize = Outcome::ALL.iter().filter(|o| o.rs274_accepts()).map(|&o| counts[o as usize]).sum();
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

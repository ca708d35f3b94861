//! Issue 18's corpus figure: machining time over the independent lower bound
//! ([`finestep_planner::bound`]) on `tests/programs` and the LinuxCNC example programs
//! that plan on the built-in machine (motion only), trapezoid and S-curve, with every
//! program refused or failing the checker listed. `cargo run --release -p
//! finestep-planner --example corpus_figures [-- [-v] [FILE.ngc | DIR]...]`: without
//! paths, `tests/programs` and the `.ngc` files under the folders where Debian's
//! `linuxcnc-uspace` installs them (`/usr/share/linuxcnc/ncfiles`,
//! `/usr/share/doc/linuxcnc/examples`, `/usr/share/axis/images`: the list `make
//! conformance` reads from `dpkg -L linuxcnc-uspace`); where LinuxCNC is not installed,
//! `tests/programs` alone; each file once however many links reach it. `-v` prints
//! every program's outcome. Not part of `make test`.

use std::path::{Path, PathBuf};

use finestep_planner::figures::{corpus_outcome, corpus_summary, CorpusOutcome};
use finestep_planner::{MachineConfig, ProfileKind};

/// The folders `linuxcnc-uspace` installs `.ngc` files into.
const LINUXCNC_DIRS: [&str; 3] =
    ["/usr/share/linuxcnc/ncfiles", "/usr/share/doc/linuxcnc/examples", "/usr/share/axis/images"];

fn ngc_files(path: &Path, out: &mut Vec<PathBuf>) -> std::io::Result<()> {
    if path.is_dir() {
        let mut entries: Vec<PathBuf> =
            std::fs::read_dir(path)?.map(|e| e.map(|e| e.path())).collect::<Result<_, _>>()?;
        entries.sort();
        for entry in entries {
            ngc_files(&entry, out)?;
        }
    } else if path.extension().is_some_and(|e| e == "ngc") {
        out.push(path.to_path_buf());
    }
    Ok(())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let verbose = args.iter().any(|a| a == "-v");
    let mut roots: Vec<PathBuf> = args.iter().filter(|a| *a != "-v").map(PathBuf::from).collect();
    if roots.is_empty() {
        roots.push(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/programs"));
        let installed: Vec<PathBuf> = LINUXCNC_DIRS.iter().map(PathBuf::from).filter(|d| d.is_dir()).collect();
        if installed.is_empty() {
            println!("LinuxCNC's examples are not installed (linuxcnc-uspace): tests/programs only");
        }
        roots.extend(installed);
    }
    let mut found = Vec::new();
    for root in &roots {
        ngc_files(root, &mut found)?;
    }
    // The examples' folders link to one another (`by_machine/nc_files` is `ncfiles`):
    // each file once, by the first path that reaches it.
    let mut seen = std::collections::HashSet::new();
    let mut files = Vec::new();
    for file in found {
        if seen.insert(std::fs::canonicalize(&file)?) {
            files.push(file);
        }
    }
    let name = |file: &Path| {
        let text = file.display().to_string();
        text.rsplit_once("tests/programs/").map_or(text.clone(), |(_, n)| format!("tests/programs/{n}"))
    };
    let mut parsed = Vec::new();
    let mut not_parsed = 0;
    for file in &files {
        match finestep_gcode::parse_file(file) {
            Ok(program) => parsed.push((name(file), program)),
            Err(e) => {
                not_parsed += 1;
                if verbose {
                    println!("not parsed: {e}");
                }
            }
        }
    }
    println!("{} .ngc files: {} parsed, {not_parsed} refused by the parser", files.len(), parsed.len());
    for profile in [ProfileKind::Trapezoid, ProfileKind::SCurve] {
        let config = MachineConfig { profile, ..MachineConfig::default() };
        let mut outcomes = Vec::new();
        for (name, program) in &parsed {
            let outcome = corpus_outcome(&config, program);
            if verbose {
                println!("{profile:?} {name}: {outcome:?}");
            }
            outcomes.push((name.clone(), outcome));
        }
        let count = |f: fn(&CorpusOutcome) -> bool| outcomes.iter().filter(|(_, o)| f(o)).count();
        let timed = count(|o| matches!(o, CorpusOutcome::Timed { .. }));
        let no_motion = count(|o| matches!(o, CorpusOutcome::NoMotion));
        let refused = count(|o| matches!(o, CorpusOutcome::Refused { .. }));
        println!(
            "{profile:?}: {timed} timed, {no_motion} without motion, {refused} refused by the planner, {} failing the checker",
            outcomes.len() - timed - no_motion - refused
        );
        for (name, outcome) in &outcomes {
            match outcome {
                CorpusOutcome::CheckError(e) => println!("  CHECKER COULD NOT READ {name}: {e}"),
                CorpusOutcome::Violations { count, first } => {
                    println!("  CHECKER FAILED {name}: {count} violations, first: {first}")
                }
                _ => {}
            }
        }
        match corpus_summary(&outcomes) {
            Some(summary) => {
                println!(
                    "  time / lower bound ({profile:?}): {:.3} over the sums ({:.2} s of motion against {:.2} s), the {} programs' ratios: mean {:.3}, median {:.3}",
                    summary.total_ratio,
                    summary.time,
                    summary.bound,
                    summary.ratios.len(),
                    summary.mean_ratio,
                    summary.median_ratio
                );
                for (name, ratio) in summary.ratios.iter().take(8) {
                    println!("    {ratio:.3} {name}");
                }
            }
            None => println!("  no program timed"),
        }
    }
    Ok(())
}

//! The quick slice of `make conformance`: each program in tests/conformance/ against the
//! output LinuxCNC's `rs274 -g -t tool.tbl` gave for it (committed as NAME.rs274 by
//! scripts/conformance_expect.sh), without LinuxCNC installed.

use std::path::Path;

use finestep_gcode::conformance::{compare, events_of, rs274_events};
use finestep_gcode::Options;

#[test]
fn programs_agree_with_rs274() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/conformance");
    let mut programs: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "ngc"))
        .collect();
    programs.sort();
    let table = std::fs::read_to_string(dir.join("tool.tbl")).unwrap();
    // rs274 without an INI file reads the tool table in inches.
    let options =
        Options { tools: Options::read_tool_table(&table, 25.4).unwrap(), machine_unit_mm: 25.4, ..Options::default() };
    let mut failures = Vec::new();
    for program in &programs {
        let expected = program.with_extension("rs274");
        let theirs = std::fs::read_to_string(&expected).unwrap_or_else(|e| panic!("{}: {e}", expected.display()));
        let theirs = rs274_events(&theirs).unwrap();
        match finestep_gcode::parse_file_with(program, &options) {
            Ok(ours) => {
                if let Some(diff) = compare(&events_of(&ours), &theirs) {
                    failures.push(format!("{}: {diff}", program.display()));
                }
            }
            Err(e) => failures.push(format!("{}: finestep refuses: {e}", program.display())),
        }
    }
    assert!(programs.len() >= 40, "only {} programs in {}", programs.len(), dir.display());
    assert!(failures.is_empty(), "{} of {} disagree:\n{}", failures.len(), programs.len(), failures.join("\n"));
}

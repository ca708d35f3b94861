//! The program read as it is planned (`plan_blocks` over the parser's stream,
//! `finestep_gcode::stream_file`) against the program parsed whole and planned
//! (`plan_program`): the same records, source lines, events and end on every program of
//! `tests/programs/` and `tests/conformance/` with both profiles, cutter compensation
//! included; a parse error far into a file ends the stream there, after the records
//! before it, with the parser's own `file:line:col` message.

mod common;

use std::path::{Path, PathBuf};

use finestep_gcode::Options;
use finestep_planner::{plan_blocks, plan_program, MachineConfig, PlannedProgram, ProgramError};

use common::{config, programs_dir, PROFILES};

/// Every record, line and event of the streamed plan, and its end, collected.
fn streamed(config: &MachineConfig, blocks: finestep_gcode::BlockStream<'_>) -> Result<PlannedProgram, ProgramError> {
    let mut stream = plan_blocks(config, blocks)?;
    let (mut records, mut lines) = (Vec::new(), Vec::new());
    for period in stream.periods.by_ref() {
        let (record, line) = period?;
        records.push(record);
        lines.push(line);
    }
    let events = stream.periods.take_events();
    let elements = stream.periods.elements_read();
    let end = stream.end().expect("the end is known once the stream has ended");
    Ok(PlannedProgram { records, lines, end, elements, notes: stream.notes, events })
}

fn ngc_files(dir: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "ngc"))
        .collect();
    files.sort();
    files
}

#[test]
fn the_program_read_as_it_is_planned_gives_the_records_of_the_whole_program() {
    let conformance = programs_dir().join("../conformance");
    let files: Vec<PathBuf> = ngc_files(&programs_dir()).into_iter().chain(ngc_files(&conformance)).collect();
    let (mut planned_count, mut refused) = (0, 0);
    for file in &files {
        for profile in PROFILES {
            let config = config(profile);
            let whole = finestep_gcode::parse_file(file)
                .map_err(|e| ProgramError::parse(&e))
                .and_then(|program| plan_program(&config, &program));
            let stream = finestep_gcode::stream_file(file, &Options::default())
                .map_err(|e| ProgramError::parse(&e))
                .and_then(|blocks| streamed(&config, blocks));
            match (whole, stream) {
                (Ok(whole), Ok(stream)) => {
                    assert_eq!(whole, stream, "{} ({profile:?})", file.display());
                    planned_count += 1;
                }
                (Err(whole), Err(stream)) => {
                    // A parse error is the parser's, the same either way.
                    if whole.located.is_some() {
                        assert_eq!(whole, stream, "{} ({profile:?})", file.display());
                    }
                    refused += 1;
                }
                (whole, stream) => panic!("{} ({profile:?}): whole {whole:?}, streamed {stream:?}", file.display()),
            }
        }
    }
    assert!(planned_count >= 2 * 8 + 2 * 30, "{planned_count} plans compared ({refused} refused both ways)");
}

/// Cutter compensation on blocks as they are read: the same tool-centre path.
#[test]
fn compensation_applied_as_the_blocks_are_read_gives_the_same_records() {
    let programs = [
        "G21 G90 G17 F1200\nG0 X-10 Y-10\nG42 D1\nG1 X0 Y0\nG1 X20\nG1 Y20\nG1 X0\nG1 Y0\nG40\nG1 X-10 Y-10\nM2\n",
        "G21 G90 G17 F600\nG0 X-5 Y-5\nG41 D1\nG1 X0 Y0\nG1 X10\nG3 X20 Y0 R5\nG1 Y-10\nG40\nG0 X30 Y-20\nM2\n",
        "G20 F10\nG0 X0 Y5\nG41.1 D0.5 G1 X0 Y0\nG1 X5\nG3 X6 Y1 I0 J1\nG1 Y4\nG40\nG1 X8 Y3\nM2\n",
    ];
    let config = MachineConfig::from_toml_str("[[tools]]\nnumber = 1\nradius_mm = 3.0\n", "t.toml").unwrap();
    for text in programs {
        let program = finestep_gcode::parse_str(text, "comp.ngc").unwrap();
        let whole = plan_program(&config, &program).unwrap();
        let blocks = finestep_gcode::stream_str(text, "comp.ngc", &Options::default()).unwrap();
        assert_eq!(whole, streamed(&config, blocks).unwrap(), "{text}");
    }
}

/// A word given twice on the last line of a 3 000-move program: the records before it
/// come first (the program is not parsed whole before the first record), then the
/// parser's error as the parser gives it.
#[test]
fn a_parse_error_far_into_a_program_ends_the_stream_there() {
    let mut text = String::from("G21 G90 G64 P0.01\nF3000\n");
    for i in 0..3000 {
        let t = i as f64 * 0.01;
        text.push_str(&format!("G1 X{:.4} Y{:.4}\n", 20.0 * t.cos(), 20.0 * t.sin()));
    }
    text.push_str("G1 X1 X2\nM2\n");
    let config = MachineConfig { lookahead_moves: 50, ..MachineConfig::default() };
    let blocks = finestep_gcode::stream_str(&text, "bad.ngc", &Options::default()).unwrap();
    let mut stream = plan_blocks(&config, blocks).unwrap();
    let mut records = 0usize;
    let error = loop {
        match stream.periods.next() {
            Some(Ok(_)) => records += 1,
            Some(Err(error)) => break error,
            None => panic!("the stream ended without the error"),
        }
    };
    assert_eq!(error.in_file("ignored.ngc"), "bad.ngc:3003:7: word X appears twice");
    assert_eq!(error.line, 3003);
    assert!(records > 1000, "{records}");
    assert!(stream.periods.next().is_none());
    assert!(stream.end().is_none());
}

//! docs/gcode.md's list of what is refused ("What is refused") against the parser and
//! against `finestep_gcode::unsupported`, the table every refusal's reason comes from:
//! each row's program is refused with the row's exact message at its `file:line:col`,
//! and every reason in the table has a row. The doc and the code cannot drift apart.

use finestep_gcode::{parse_str, unsupported};

/// The rows of the list: (what, program, message). The program's `\n` separate lines.
fn rows() -> Vec<(String, String, String)> {
    let doc = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../docs/gcode.md")).unwrap();
    let start = doc.find("\n### What is refused\n").expect("docs/gcode.md has a section \"What is refused\"");
    let section = &doc[start + 1..];
    let section = &section[..section[4..].find("\n#").map_or(section.len(), |end| end + 4)];
    let mut rows = Vec::new();
    for line in section.lines().filter(|l| l.starts_with("| ") && !l.starts_with("| what") && !l.starts_with("| ---")) {
        let cells: Vec<&str> = line.trim_matches('|').split(" | ").map(str::trim).collect();
        assert_eq!(cells.len(), 3, "a row has three cells: {line}");
        let code = |cell: &str| cell.strip_prefix('`').and_then(|c| c.strip_suffix('`')).map(str::to_string);
        let program = code(cells[1]).unwrap_or_else(|| panic!("program in backticks: {line}")).replace("\\n", "\n");
        let message = code(cells[2]).unwrap_or_else(|| panic!("message in backticks: {line}"));
        rows.push((cells[0].to_string(), program, message));
    }
    rows
}

#[test]
fn every_row_of_the_list_is_refused_with_its_message_at_its_place() {
    let rows = rows();
    // The section was read: at least a row per reason of the table (rows leave the list
    // as codes get implemented; `every_reason_in_the_table_has_a_row` checks each).
    assert!(rows.len() >= unsupported::reasons().len(), "{} rows", rows.len());
    let mut wrong = Vec::new();
    for (what, program, message) in &rows {
        assert!(message.starts_with("t.ngc:") && message.contains(": unsupported: "), "{what}: {message}");
        let got = match parse_str(&format!("{program}\nM2\n"), "t.ngc") {
            Ok(_) => "accepted".to_string(),
            Err(e) => e.to_string(),
        };
        if &got != message {
            wrong.push(format!("{what}: `{program}`\n  doc:    {message}\n  parser: {got}"));
        }
    }
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}

#[test]
fn every_reason_in_the_table_has_a_row() {
    let rows = rows();
    for why in unsupported::reasons() {
        assert!(rows.iter().any(|(_, _, message)| message.ends_with(&format!("({why})"))), "no row says: {why}");
    }
    // Every G and M number of the table is in some row's "what".
    for &(codes, _) in unsupported::G_CODES {
        for &code in codes {
            let name = if code % 10 == 0 { format!("G{}", code / 10) } else { format!("G{}.{}", code / 10, code % 10) };
            assert!(rows.iter().any(|(what, _, _)| what.split([' ', ',']).any(|w| w == name)), "{name} not listed");
        }
    }
}

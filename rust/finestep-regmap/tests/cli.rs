//! The `finestep-regmap` binary: its subcommands write what the library generates, and
//! `check` fails on stale docs with a message.

use finestep_regmap::{
    default_root, load_map, markdown, verilog, DOCS_PATH, INTERFACE_DOCS_PATH, INTERFACE_PATH, MAP_PATH,
};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn regmap(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_finestep-regmap")).args(args).output().expect("cannot run finestep-regmap")
}

fn scratch(test: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("regmap-cli-{test}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn verilog_and_markdown_write_the_generated_text() {
    let map = load_map(&default_root()).unwrap();
    let dir = scratch("write");
    let header = dir.join("nested/finestep_regs.vh");
    let docs = dir.join("registers.md");
    for (command, path) in [("verilog", &header), ("markdown", &docs)] {
        let output = regmap(&[command, path.to_str().unwrap()]);
        assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    }
    assert_eq!(std::fs::read_to_string(header).unwrap(), verilog::generate(&map));
    assert_eq!(std::fs::read_to_string(docs).unwrap(), markdown::generate(&map));
}

#[test]
fn check_passes_on_this_repository_and_fails_on_stale_docs() {
    let output = regmap(&["check"]);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));

    let root = scratch("stale");
    std::fs::create_dir_all(root.join("hdl")).unwrap();
    std::fs::create_dir_all(root.join("docs")).unwrap();
    std::fs::copy(default_root().join(MAP_PATH), root.join(MAP_PATH)).unwrap();
    std::fs::copy(default_root().join(INTERFACE_PATH), root.join(INTERFACE_PATH)).unwrap();
    std::fs::copy(default_root().join(INTERFACE_DOCS_PATH), root.join(INTERFACE_DOCS_PATH)).unwrap();
    std::fs::write(root.join(DOCS_PATH), "# an old copy\n").unwrap();
    let output = regmap(&["check", "--root", root.to_str().unwrap()]);
    assert!(!output.status.success());
    let message = String::from_utf8_lossy(&output.stderr);
    assert!(message.contains("docs/registers.md is stale: line 1"), "{message}");
}

#[test]
fn an_invalid_map_fails_with_the_problem_not_a_panic() {
    let root = scratch("invalid");
    std::fs::create_dir_all(root.join("hdl")).unwrap();
    let map = std::fs::read_to_string(default_root().join(MAP_PATH)).unwrap();
    // Move RECORD_PUSH onto CONTROL's address.
    let broken = map.replace("address = 0x50", "address = 0x04");
    assert_ne!(broken, map);
    std::fs::write(root.join(MAP_PATH), broken).unwrap();
    let output = regmap(&["verilog", root.join("out.vh").to_str().unwrap(), "--root", root.to_str().unwrap()]);
    assert_eq!(output.status.code(), Some(1));
    let message = String::from_utf8_lossy(&output.stderr);
    assert!(message.contains("register RECORD_PUSH: RECORD_PUSH at address 0x04 overlaps CONTROL"), "{message}");
    assert!(!message.contains("panicked"), "{message}");
}

#[test]
fn headers_writes_every_verilog_header_and_docs_regenerates_both_pages() {
    let dir = scratch("headers");
    let output = regmap(&["headers", dir.to_str().unwrap()]);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    for name in ["finestep_regs.vh", "finestep_interface.vh", "finestep_top_checks.vh", "finestep_core_checks.vh"] {
        assert!(dir.join(name).is_file(), "{name} missing");
    }
    let root = scratch("docs");
    std::fs::create_dir_all(root.join("hdl")).unwrap();
    std::fs::create_dir_all(root.join("docs")).unwrap();
    std::fs::copy(default_root().join(MAP_PATH), root.join(MAP_PATH)).unwrap();
    std::fs::copy(default_root().join(INTERFACE_PATH), root.join(INTERFACE_PATH)).unwrap();
    let output = regmap(&["docs", "--root", root.to_str().unwrap()]);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let output = regmap(&["check", "--root", root.to_str().unwrap()]);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
}

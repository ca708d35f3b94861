//! The generated Verilog header: it declares exactly the names the scheme promises (the
//! finestep-interface crate checks it against the Rust constants), and passes Verilator `-Wall` and Yosys when those tools are
//! on PATH (skipped with a note otherwise).

use finestep_regmap::spec::{naming, MapSpec};
use finestep_regmap::{default_root, load_map, verilog};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

/// A constant read back from the header text: its declared width (`None` for
/// `integer`) and its value.
#[derive(Debug, PartialEq, Eq, Clone, Copy)]
struct Constant {
    width: Option<u32>,
    value: u64,
}

fn map() -> MapSpec {
    load_map(&default_root()).unwrap_or_else(|error| panic!("{error}"))
}

/// Parses every `localparam` line of the header; panics on a line it does not expect,
/// so the header cannot grow other kinds of declaration unnoticed.
fn parse_header(text: &str) -> BTreeMap<String, Constant> {
    let mut constants = BTreeMap::new();
    for line in text.lines() {
        let line = line.trim();
        if line.is_empty() || line.starts_with("//") || line.starts_with("/* verilator lint_") {
            continue;
        }
        let declaration = line.strip_prefix("localparam ").unwrap_or_else(|| panic!("unexpected line {line:?}"));
        let statement = declaration.split(';').next().unwrap();
        let (left, literal) = statement.split_once(" = ").unwrap();
        let (kind, name) = left.split_once(' ').unwrap();
        let width = match kind {
            "integer" => None,
            range => {
                let msb: u32 = range.strip_prefix('[').and_then(|r| r.strip_suffix(":0]")).unwrap().parse().unwrap();
                Some(msb + 1)
            }
        };
        let value = match literal.split_once("'h") {
            Some((size, hex)) => {
                assert_eq!(Some(size.parse().unwrap()), width, "{name}: literal size differs from declared range");
                u64::from_str_radix(hex, 16).unwrap()
            }
            None => literal.parse().unwrap(),
        };
        let previous = constants.insert(name.to_string(), Constant { width, value });
        assert!(previous.is_none(), "{name} declared twice");
    }
    constants
}

fn integer(value: impl Into<u64>) -> Constant {
    Constant { width: None, value: value.into() }
}

fn sized(width: u32, value: impl Into<u64>) -> Constant {
    Constant { width: Some(width), value: value.into() }
}

#[test]
fn a_few_constants_by_hand() {
    let constants = parse_header(&verilog::generate(&map()));
    assert_eq!(constants["FS_CONTROL_ADDR"], sized(7, 0x04u8));
    assert_eq!(constants["FS_CONTROL_ESTOP_ACTIVE_HIGH_LSB"], integer(2u32));
    assert_eq!(constants["FS_CONTROL_ESTOP_ACTIVE_HIGH_RESET"], sized(1, 1u32));
    assert_eq!(constants["FS_PERIOD_CLOCKS_CLOCKS_WIDTH"], integer(24u32));
    assert_eq!(constants["FS_PERIOD_CLOCKS_CLOCKS_RESET"], sized(24, 50_000u32));
    assert_eq!(constants["FS_ID_MAGIC_VALUE"], sized(32, 0x4653_5450u32));
    assert_eq!(constants["FS_AXIS_MODE_ADDR"], sized(7, 0x22u8));
    assert_eq!(constants["FS_AXIS_MODE_COUNT"], integer(8u32));
    assert_eq!(constants["FS_AXIS_MODE_STRIDE"], integer(4u32));
    assert_eq!(constants["FS_ADDR_WIDTH"], integer(7u32));
    assert_eq!(constants["FS_MAP_VERSION_MAJOR"], integer(1u32));
    assert_eq!(constants["FS_MAP_VERSION_MINOR"], integer(1u32));
    assert_eq!(constants["FS_CAPS_STEP_ROUND_LOG2_LSB"], integer(22u32));
    assert_eq!(constants["FS_CAPS_STEP_ROUND_LOG2_WIDTH"], integer(4u32));
    assert_eq!(constants["FS_ENC_COUNT_ADDR"], sized(7, 0x60u8));
    assert_eq!(constants["FS_ENC_COUNT_COUNT"], integer(4u32));
    assert_eq!(constants["FS_MPG_CONTROL_PRESCALE_RESET"], sized(16, 499u32));
    assert_eq!(constants["FS_JOG_VMAX_STEPS_WIDTH"], integer(31u32));
}

#[test]
fn header_declares_exactly_the_names_validation_knows() {
    let map = map();
    let declared: Vec<String> = parse_header(&verilog::generate(&map)).into_keys().collect();
    let mut promised: Vec<String> = naming::verilog_constants(&map).into_iter().map(|(name, _)| name).collect();
    promised.sort();
    assert_eq!(declared, promised);
}

/// A module that uses every constant of the header once, lint-clean by construction:
/// each use is a one-bit check on `word` or `address`, gathered in `checks`.
fn module_using_every_constant(map: &MapSpec) -> String {
    let mut checks = vec![
        "word == FS_MAP_VERSION_MAJOR".to_string(),
        "word == FS_MAP_VERSION_MINOR".to_string(),
        "word == FS_MAP_VERSION_PATCH".to_string(),
    ];
    for register in &map.registers {
        let prefix = format!("FS_{}", register.name);
        checks.push(format!("address == {prefix}_ADDR"));
        if register.array.is_some() {
            // The last element's address, in 32 bits like the integer arithmetic; the
            // zero extension keeps Verilator's width check quiet, as RTL would need to.
            checks.push(format!(
                "address_word == {{{{(32 - FS_ADDR_WIDTH){{1'b0}}}}, {prefix}_ADDR}} + ({prefix}_COUNT - 1) * {prefix}_STRIDE"
            ));
        }
        for field in &register.fields {
            let prefix = format!("{prefix}_{}", field.name);
            let bits = format!("word[{prefix}_LSB +: {prefix}_WIDTH]");
            checks.push(match (field.reset, field.value) {
                (Some(_), _) => format!("{bits} == {prefix}_RESET"),
                (None, Some(_)) => format!("{bits} == {prefix}_VALUE"),
                (None, None) => format!("|{bits}"),
            });
        }
    }
    let address_bits = map.address_bits;
    let mut text = format!(
        "`timescale 1ns / 1ps\n`default_nettype none\n\
         module uses_every_constant (\n\
         \x20   input  wire [{}:0] address,\n\
         \x20   input  wire [31:0] word,\n\
         \x20   output wire [{}:0] checks\n\
         );\n\
         `include \"{}\"\n\
         \x20   wire [31:0] address_word = {{{{(32 - FS_ADDR_WIDTH){{1'b0}}}}, address}};\n",
        address_bits - 1,
        checks.len() - 1,
        verilog::HEADER_NAME
    );
    for (index, check) in checks.iter().enumerate() {
        text.push_str(&format!("    assign checks[{index}] = ({check});\n"));
    }
    text.push_str("endmodule\n`default_nettype wire\n");
    text
}

/// A module that uses one constant: the header's other constants must not warn.
fn module_using_one_constant(map: &MapSpec) -> String {
    format!(
        "`timescale 1ns / 1ps\n`default_nettype none\n\
         module uses_one_constant (\n\
         \x20   input  wire [{}:0] address,\n\
         \x20   output wire        hit\n\
         );\n\
         `include \"{}\"\n\
         \x20   assign hit = (address == FS_CONTROL_ADDR);\n\
         endmodule\n`default_nettype wire\n",
        map.address_bits - 1,
        verilog::HEADER_NAME
    )
}

/// Writes the header and the test modules to a fresh directory for the tools.
fn write_sources(test: &str) -> (PathBuf, Vec<(&'static str, PathBuf)>) {
    let map = map();
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("regmap-{test}"));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join(verilog::HEADER_NAME), verilog::generate(&map)).unwrap();
    let mut modules = Vec::new();
    for (top, source) in [
        ("uses_every_constant", module_using_every_constant(&map)),
        ("uses_one_constant", module_using_one_constant(&map)),
    ] {
        let path = dir.join(format!("{top}.v"));
        std::fs::write(&path, source).unwrap();
        modules.push((top, path));
    }
    (dir, modules)
}

fn on_path(tool: &str) -> bool {
    let found = std::env::var_os("PATH")
        .map(|path| std::env::split_paths(&path).any(|dir| dir.join(tool).is_file()))
        .unwrap_or(false);
    if !found {
        println!("note: {tool} is not on PATH; skipping this check");
    }
    found
}

fn run(command: &mut Command) {
    let output = command.output().unwrap_or_else(|error| panic!("cannot run {command:?}: {error}"));
    assert!(
        output.status.success() && output.stderr.is_empty(),
        "{command:?} failed:\n{}{}",
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    );
}

#[test]
fn verilator_lints_the_header_clean() {
    if !on_path("verilator") {
        return;
    }
    let (dir, modules) = write_sources("verilator");
    for (top, path) in modules {
        run(Command::new("verilator")
            .args(["--lint-only", "-Wall", "--top-module", top])
            .arg(format!("-I{}", dir.display()))
            .arg(&path));
    }
}

#[test]
fn yosys_reads_the_header() {
    if !on_path("yosys") {
        return;
    }
    let (dir, modules) = write_sources("yosys");
    for (top, path) in modules {
        let script = format!(
            "read_verilog -I{} {}; hierarchy -check -top {top}; proc; check -assert",
            dir.display(),
            path.display()
        );
        let output = Command::new("yosys").args(["-q", "-p", &script]).output().expect("cannot run yosys");
        let log = format!("{}{}", String::from_utf8_lossy(&output.stdout), String::from_utf8_lossy(&output.stderr));
        assert!(output.status.success() && !log.contains("Warning"), "yosys on {top}:\n{log}");
    }
}

#[test]
fn no_comment_line_starts_with_a_tool_pragma_word() {
    // Verilator reads `// verilator ...` and Yosys `// synthesis ...` as directives.
    for line in verilog::generate(&map()).lines() {
        if let Some(comment) = line.trim().strip_prefix("//") {
            let first_word = comment.split_whitespace().next().unwrap_or("").to_ascii_lowercase();
            assert!(
                !["verilator", "synthesis", "synopsys", "pragma", "lint_checking"]
                    .iter()
                    .any(|word| first_word.starts_with(word)),
                "comment line {line:?} could be read as a pragma"
            );
        }
    }
}

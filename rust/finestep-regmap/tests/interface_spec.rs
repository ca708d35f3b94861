//! `hdl/interface.toml`: the real description passes, and each broken one is refused with
//! a message naming the part at fault, never a panic.

use finestep_regmap::interface::{parse, InterfaceError};
use finestep_regmap::{default_root, load_interface, load_map, INTERFACE_PATH};

fn real_text() -> String {
    std::fs::read_to_string(default_root().join(INTERFACE_PATH)).unwrap()
}

/// The problems of `text` (the real description edited), as displayed; fails the test if
/// it is accepted or fails for another reason.
fn problems(text: &str) -> Vec<String> {
    let map = load_map(&default_root()).unwrap();
    match parse(text, "test.toml", &map) {
        Err(error @ InterfaceError::Invalid { .. }) => error.problems().iter().map(ToString::to_string).collect(),
        Err(other) => panic!("expected Invalid, got {other}"),
        Ok(_) => panic!("accepted:\n{text}"),
    }
}

/// The real description with `from` replaced by `to` (which must occur).
fn edited(from: &str, to: &str) -> String {
    let text = real_text();
    assert!(text.contains(from), "{from:?} is not in the description");
    text.replacen(from, to, 1)
}

fn assert_problem(text: &str, expected: &str) {
    let found = problems(text);
    assert!(found.iter().any(|p| p.contains(expected)), "expected a problem containing {expected:?}, got {found:#?}");
}

#[test]
fn the_real_description_is_valid() {
    let (_, interface) = load_interface(&default_root()).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(interface.record.max_axes.value, 8);
    assert_eq!(interface.record.increment.width(), 32);
    let top = interface.modules.iter().find(|m| m.name == "finestep_top").unwrap();
    let p_width = top.parameter("P_WIDTH").unwrap();
    assert_eq!((p_width.min.value, p_width.max.value), (1, 24), "P_WIDTH <= width of PERIOD_CLOCKS.CLOCKS");
    assert_eq!(top.parameter("FIFO_DEPTH_LOG2").unwrap().max.value, 15);
    assert_eq!(p_width.check_module("finestep_top"), "finestep_top_P_WIDTH_must_be_1_to_24");
}

#[test]
fn references_must_resolve() {
    assert_problem(
        &edited("field = \"AXIS_MODE.OUT_MODE\"", "field = \"AXIS_MODE.NOPE\""),
        "enum OUT_MODE: `AXIS_MODE.NOPE` is not a REG.FIELD",
    );
    assert_problem(
        &edited("max = \"PERIOD_CLOCKS.CLOCKS.width\"", "max = \"PERIOD_CLOCKS.width\""),
        "module finestep_top, parameter P_WIDTH: max `PERIOD_CLOCKS.width` is neither",
    );
    assert_problem(
        &edited("max_axes = \"RECORD_INC.count\"", "max_axes = \"CONTROL.count\""),
        "record: max_axes `CONTROL.count`",
    );
}

#[test]
fn values_and_codes_must_fit_and_be_unique() {
    assert_problem(
        &edited("{ name = \"QUADRATURE\", value = 2", "{ name = \"QUADRATURE\", value = 4"),
        "value 4 does not fit field AXIS_MODE.OUT_MODE (2 bits)",
    );
    assert_problem(&edited("{ name = \"X2\", value = 1", "{ name = \"X2\", value = 0"), "value 0 is also X4");
    assert_problem(&edited("code = 0xE2", "code = 0xE1"), "spi result BAD_COMMAND: code 0xe1 is also CRC_MISMATCH");
    assert_problem(&edited("code = 0x03", "code = 0x103"), "spi command FIFO: code 259 is not a byte");
    assert_problem(
        &edited("{ name = \"BLOCK_END\", bit = 0", "{ name = \"BLOCK_END\", bit = 8"),
        "record flags, bit BLOCK_END: bit 8 is outside 0..=7",
    );
}

#[test]
fn an_enum_that_leaves_values_unlisted_says_what_they_act_as() {
    assert_problem(&edited("otherwise = \"STEP_DIR\"\n", ""), "enum OUT_MODE: some field values are unlisted");
    assert_problem(
        &edited("otherwise = \"X100\"", "otherwise = \"X1000\""),
        "otherwise X1000 is not one of its values",
    );
}

#[test]
fn parameter_ranges_hold_their_default_and_fit_caps() {
    assert_problem(
        &edited("{ name = \"WD_W\", default = 24", "{ name = \"WD_W\", default = 25"),
        "default 25 is outside min..=max (1..=24)",
    );
    // CAPS.N_ENC is 3 bits: 16 channels would not fit.
    assert_problem(
        &edited("max = \"ENC_COUNT.count\"", "max = 16"),
        "max 16 does not fit its CAPS field CAPS.N_ENC (3 bits)",
    );
}

#[test]
fn timing_fields_are_equally_wide_rw_fields() {
    assert_problem(
        &edited("field = \"AXIS_TIMING_B.DIR_HOLD\"", "field = \"ESTOP_FILTER.SAMPLES\""),
        "timing fields are equally wide",
    );
    assert_problem(&edited("field = \"AXIS_TIMING_B.DIR_HOLD\"", "field = \"FIFO_LEVEL.FREE\""), "not an rw field");
}

#[test]
fn generated_verilog_names_do_not_collide_with_the_map() {
    // An enum named after a register field prefix: FS_CONTROL_RUN... vs the map's FS_CONTROL_RUN_LSB.
    let text = edited("name = \"COUNT_MODE\"", "name = \"CONTROL_RUN\"").replacen("name = \"X4\"", "name = \"LSB\"", 1);
    assert_problem(
        &text,
        "its Verilog constant FS_CONTROL_RUN_LSB is also generated for the register map's register CONTROL, field RUN",
    );
}

#[test]
fn unknown_keys_are_syntax_errors_with_a_line() {
    let map = load_map(&default_root()).unwrap();
    let text = edited("[spi]\n", "[spi]\nbaud = 1\n");
    match parse(&text, "test.toml", &map) {
        Err(InterfaceError::Syntax { source, .. }) => assert!(source.to_string().contains("baud"), "{source}"),
        other => panic!("expected a syntax error, got {other:?}"),
    }
}

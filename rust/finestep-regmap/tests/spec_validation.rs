//! Broken maps: each must be refused with a message naming the register and field at
//! fault, never a panic; and the real map must pass.

use finestep_regmap::spec::{parse, Access, Place, SpecError};

const HEADER: &str = "name = \"test\"\naddress_bits = 7\nversion = { major = 1, minor = 2, patch = 3 }\n";

/// A map with the given `[[register]]` tables after a valid header.
fn map_with(registers: &str) -> String {
    format!("{HEADER}{registers}")
}

/// One plain register with the given fields lines.
fn register(name: &str, address: u32, fields: &str) -> String {
    format!("\n[[register]]\nname = \"{name}\"\naddress = {address}\ndescription = \"d\"\nfields = [\n{fields}\n]\n")
}

fn rw(name: &str, lsb: i64, width: i64, reset: i64) -> String {
    format!("  {{ name = \"{name}\", lsb = {lsb}, width = {width}, access = \"rw\", reset = {reset}, description = \"d\" }},")
}

fn ro(name: &str, lsb: i64, width: i64) -> String {
    format!("  {{ name = \"{name}\", lsb = {lsb}, width = {width}, access = \"ro\", description = \"d\" }},")
}

/// The problems of an invalid map, as displayed; fails the test if the map is accepted
/// or fails for another reason.
fn problems(text: &str) -> Vec<String> {
    match parse(text, "test.toml") {
        Err(error @ SpecError::Invalid { .. }) => error.problems().iter().map(ToString::to_string).collect(),
        Err(other) => panic!("expected validation problems, got: {other}"),
        Ok(_) => panic!("the broken map was accepted:\n{text}"),
    }
}

/// Asserts that exactly one problem is reported, at `place`, mentioning `needle`.
fn assert_single_problem(text: &str, place: Place, needle: &str) {
    let error = parse(text, "test.toml").expect_err("the broken map was accepted");
    let found = error.problems();
    assert_eq!(found.len(), 1, "expected one problem, got: {error}");
    assert_eq!(found[0].place, place, "{error}");
    assert!(found[0].message.contains(needle), "{:?} does not mention {needle:?}", found[0].message);
}

fn syntax_error(text: &str) -> String {
    match parse(text, "test.toml") {
        Err(error @ SpecError::Syntax { .. }) => error.to_string(),
        Err(other) => panic!("expected a syntax error, got: {other}"),
        Ok(_) => panic!("the broken map was accepted:\n{text}"),
    }
}

#[test]
fn the_repository_map_is_valid() {
    let map = finestep_regmap::load_map(&finestep_regmap::default_root()).unwrap_or_else(|error| panic!("{error}"));
    let control = map.registers.iter().find(|r| r.name == "CONTROL").unwrap();
    assert_eq!(control.address, 0x04);
    assert_eq!(control.fields[2].name, "ESTOP_ACTIVE_HIGH");
    assert_eq!(control.fields[2].reset, Some(1));
}

#[test]
fn a_small_valid_map_parses_to_what_it_says() {
    let text = map_with(&format!(
        "{}\n[[register]]\nname = \"TABLE\"\naddress = 0x10\narray = {{ count = 4, stride = 2 }}\ndescription = \"t\"\nfields = [\n{}\n]\n",
        register("CTRL", 1, &format!("{}\n{}", rw("GO", 0, 1, 1), ro("STATE", 4, 3))),
        rw("ENTRY", 0, 32, 0xFFFF_FFFF)
    ));
    let map = parse(&text, "test.toml").unwrap_or_else(|error| panic!("{error}"));
    assert_eq!(map.version.minor, 2);
    let control = &map.registers[0];
    assert_eq!(control.fields[1].access, Access::ReadOnly);
    assert_eq!(control.fields[1].mask(), 0b111_0000);
    assert_eq!(control.reset_word(), None, "STATE is a hardware value");
    let table = &map.registers[1];
    assert_eq!(table.addresses().collect::<Vec<_>>(), [0x10, 0x12, 0x14, 0x16]);
    assert_eq!(table.reset_word(), Some(0xFFFF_FFFF));
}

#[test]
fn address_outside_the_address_bits() {
    let text = map_with(&register("FAR", 0x80, &ro("X", 0, 1)));
    assert_single_problem(&text, Place::register("FAR"), "address 128 is outside 0..=0x7f");
}

#[test]
fn address_bits_beyond_a_u8() {
    let text = map_with(&register("A", 0, &ro("X", 0, 1))).replace("address_bits = 7", "address_bits = 9");
    assert_single_problem(&text, Place::Map, "address_bits 9");
}

#[test]
fn array_running_past_the_last_address() {
    let text = map_with(
        "\n[[register]]\nname = \"ARR\"\naddress = 0x7C\narray = { count = 3, stride = 2 }\ndescription = \"d\"\nfields = [ { name = \"X\", lsb = 0, width = 1, access = \"ro\", description = \"d\" } ]\n",
    );
    assert_single_problem(&text, Place::register("ARR"), "element 2 would be at address 0x80");
}

#[test]
fn array_with_zero_count_or_stride() {
    let base = "\n[[register]]\nname = \"ARR\"\naddress = 0x10\narray = { count = COUNT, stride = STRIDE }\ndescription = \"d\"\nfields = [ { name = \"X\", lsb = 0, width = 1, access = \"ro\", description = \"d\" } ]\n";
    let zero_count = map_with(&base.replace("COUNT", "0").replace("STRIDE", "1"));
    assert_single_problem(&zero_count, Place::register("ARR"), "array count 0");
    let zero_stride = map_with(&base.replace("COUNT", "2").replace("STRIDE", "0"));
    assert_single_problem(&zero_stride, Place::register("ARR"), "array stride 0");
}

#[test]
fn array_element_landing_on_another_register() {
    let array = "\n[[register]]\nname = \"ARR\"\naddress = 0x20\narray = { count = 4, stride = 4 }\ndescription = \"d\"\nfields = [ { name = \"X\", lsb = 0, width = 1, access = \"ro\", description = \"d\" } ]\n";
    let single = register("LONE", 0x28, &ro("Y", 0, 1));
    // Whichever comes second in the file is the one reported.
    assert_single_problem(
        &map_with(&format!("{array}{single}")),
        Place::register("LONE"),
        "LONE at address 0x28 overlaps ARR[2]",
    );
    assert_single_problem(
        &map_with(&format!("{single}{array}")),
        Place::register("ARR"),
        "ARR[2] at address 0x28 overlaps LONE",
    );
}

#[test]
fn interleaved_arrays_that_do_not_collide_are_fine() {
    let array = |name: &str, address: u32| {
        format!("\n[[register]]\nname = \"{name}\"\naddress = {address}\narray = {{ count = 8, stride = 2 }}\ndescription = \"d\"\nfields = [ {{ name = \"X\", lsb = 0, width = 1, access = \"ro\", description = \"d\" }} ]\n")
    };
    let text = map_with(&format!("{}{}", array("EVEN", 0x20), array("ODD", 0x21)));
    parse(&text, "test.toml").unwrap_or_else(|error| panic!("{error}"));
    let clash = map_with(&format!("{}{}", array("EVEN", 0x20), array("LATE", 0x2E)));
    assert_single_problem(&clash, Place::register("LATE"), "LATE[0] at address 0x2e overlaps EVEN[7]");
}

#[test]
fn two_registers_at_one_address() {
    let text = map_with(&format!("{}{}", register("A", 3, &ro("X", 0, 1)), register("B", 3, &ro("X", 0, 1))));
    assert_single_problem(&text, Place::register("B"), "B at address 0x03 overlaps A");
}

#[test]
fn field_past_bit_31() {
    let text = map_with(&register("R", 0, &ro("WIDE", 20, 16)));
    assert_single_problem(&text, Place::field("R", "WIDE"), "bits 35:20 do not fit in a 32-bit register");
}

#[test]
fn field_of_zero_width_or_negative_lsb() {
    assert_single_problem(&map_with(&register("R", 0, &ro("EMPTY", 0, 0))), Place::field("R", "EMPTY"), "width 0");
    assert_single_problem(&map_with(&register("R", 0, &ro("NEG", -1, 2))), Place::field("R", "NEG"), "lsb -1");
}

#[test]
fn overlapping_fields() {
    let fields = format!("{}\n{}", ro("LOW", 0, 8), ro("MID", 4, 8));
    assert_single_problem(
        &map_with(&register("R", 0, &fields)),
        Place::field("R", "MID"),
        "bits 11:4 overlap field LOW (bits 7:0)",
    );
}

#[test]
fn reset_too_big_for_the_field() {
    assert_single_problem(
        &map_with(&register("R", 0, &rw("FLAG", 0, 1, 2))),
        Place::field("R", "FLAG"),
        "reset 2 does not fit in 1 bit (0..=0x1)",
    );
    assert_single_problem(
        &map_with(&register("R", 0, &rw("COUNT", 0, 8, -1))),
        Place::field("R", "COUNT"),
        "reset -1 does not fit in 8 bits",
    );
}

#[test]
fn value_too_big_for_the_field() {
    let field = "  { name = \"MAGIC\", lsb = 0, width = 8, access = \"ro\", value = 256, description = \"d\" }";
    assert_single_problem(
        &map_with(&register("R", 0, field)),
        Place::field("R", "MAGIC"),
        "value 256 does not fit in 8 bits",
    );
}

#[test]
fn reset_and_value_only_where_they_belong() {
    let rw_without_reset = "  { name = \"F\", lsb = 0, width = 1, access = \"rw\", description = \"d\" }";
    assert_single_problem(&map_with(&register("R", 0, rw_without_reset)), Place::field("R", "F"), "needs a `reset`");
    let w1c_with_reset = "  { name = \"F\", lsb = 0, width = 1, access = \"w1c\", reset = 0, description = \"d\" }";
    assert_single_problem(
        &map_with(&register("R", 0, w1c_with_reset)),
        Place::field("R", "F"),
        "`reset` is only for rw and ro fields, this one is w1c",
    );
    let ro_with_both =
        "  { name = \"F\", lsb = 0, width = 1, access = \"ro\", reset = 0, value = 1, description = \"d\" }";
    assert_single_problem(&map_with(&register("R", 0, ro_with_both)), Place::field("R", "F"), "not both");
    // An ro field with a reset: what it reads out of reset (a hardware value after that).
    let ro_with_reset = "  { name = \"F\", lsb = 4, width = 4, access = \"ro\", reset = 5, description = \"d\" }";
    let map = parse(&map_with(&register("R", 0, ro_with_reset)), "test.toml").unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(map.registers[0].reset_word(), Some(0x50));
    let rw_with_value =
        "  { name = \"F\", lsb = 0, width = 1, access = \"rw\", reset = 0, value = 1, description = \"d\" }";
    assert_single_problem(
        &map_with(&register("R", 0, rw_with_value)),
        Place::field("R", "F"),
        "`value` is only for ro fields, this one is rw",
    );
}

#[test]
fn unknown_access_type() {
    let field = "  { name = \"F\", lsb = 0, width = 1, access = \"rx\", description = \"d\" }";
    assert_single_problem(
        &map_with(&register("R", 0, field)),
        Place::field("R", "F"),
        "unknown access `rx` (known: ro, rw, pulse, wo, w1c)",
    );
}

#[test]
fn duplicate_names() {
    let twice = map_with(&format!("{}{}", register("SAME", 0, &ro("X", 0, 1)), register("SAME", 1, &ro("X", 0, 1))));
    let found = problems(&twice);
    assert!(found.contains(&"register SAME: the name appears twice in the map".to_string()), "{found:?}");
    let fields = format!("{}\n{}", ro("F", 0, 1), ro("F", 1, 1));
    assert_single_problem(
        &map_with(&register("R", 0, &fields)),
        Place::field("R", "F"),
        "appears twice in this register",
    );
}

#[test]
fn names_must_be_upper_snake() {
    for bad in ["Control", "_LEAD", "TRAIL_", "DOUBLE__UNDERSCORE", "9LIVES", "HY-PHEN", ""] {
        let text = map_with(&register(bad, 0, &ro("X", 0, 1)));
        let found = problems(&text);
        assert!(found.iter().any(|problem| problem.contains("is not UPPER_SNAKE")), "register name {bad:?}: {found:?}");
        let text = map_with(&register("R", 0, &ro(bad, 0, 1)));
        let found = problems(&text);
        assert!(
            found.iter().any(|problem| problem.contains(&format!("field name {bad:?} is not UPPER_SNAKE"))),
            "field name {bad:?}: {found:?}"
        );
    }
}

#[test]
fn register_named_like_a_rust_keyword() {
    assert_single_problem(
        &map_with(&register("TYPE", 0, &ro("X", 0, 1))),
        Place::register("TYPE"),
        "`type` is a Rust keyword",
    );
}

#[test]
fn generated_verilog_names_must_not_collide() {
    // FS_A_B_C_LSB would be generated for both.
    let text = map_with(&format!("{}{}", register("A", 0, &ro("B_C", 0, 1)), register("A_B", 1, &ro("C", 0, 1))));
    let found = problems(&text);
    assert!(
        found.contains(
            &"register A_B, field C: its Verilog constant FS_A_B_C_LSB is also generated for register A, field B_C"
                .to_string()
        ),
        "{found:?}"
    );
}

#[test]
fn generated_rust_names_must_not_collide() {
    // `ADDR` is the register's own address constant.
    let text = map_with(&register("R", 0, &ro("ADDR", 0, 1)));
    let found = problems(&text);
    assert!(
        found.iter().any(|problem| problem.contains("its Rust constant r::ADDR is also generated for register R")),
        "{found:?}"
    );
    // RUN's reset constant is RUN_RESET.
    let fields = format!("{}\n{}", rw("RUN", 0, 1, 0), ro("RUN_RESET", 1, 1));
    let found = problems(&map_with(&register("R", 0, &fields)));
    assert!(
        found.iter().any(|problem| problem.contains("r::RUN_RESET is also generated for register R, field RUN")),
        "{found:?}"
    );
}

#[test]
fn empty_maps_registers_and_descriptions() {
    assert_single_problem(HEADER, Place::Map, "no [[register]]");
    assert_single_problem(&map_with(&register("R", 0, "")), Place::register("R"), "has no fields");
    let text = map_with(&register("R", 0, &ro("X", 0, 1)))
        .replace("description = \"d\"\nfields", "description = \" \"\nfields");
    assert_single_problem(&text, Place::register("R"), "description is empty");
    let field = "  { name = \"F\", lsb = 0, width = 1, access = \"ro\", description = \"two\\nlines\" }";
    assert_single_problem(&map_with(&register("R", 0, field)), Place::field("R", "F"), "line break");
}

#[test]
fn every_problem_is_reported_not_just_the_first() {
    let fields = format!("{}\n{}", rw("A", 0, 1, 5), ro("lower", 40, 1));
    let error = parse(&map_with(&register("R", 0, &fields)), "test.toml").unwrap_err();
    let message = error.to_string();
    assert_eq!(error.problems().len(), 3, "{message}");
    assert!(message.starts_with("test.toml: invalid register map:"), "{message}");
    assert!(message.contains("register R, field A: reset 5 does not fit"), "{message}");
    assert!(message.contains("register R, field lower: field name \"lower\" is not UPPER_SNAKE"), "{message}");
    assert!(message.contains("register R, field lower: lsb 40 is outside 0..=31"), "{message}");
}

#[test]
fn malformed_toml_and_unknown_keys_are_syntax_errors_with_a_position() {
    let message = syntax_error("name = \"x\"\naddress_bits = \n");
    assert!(message.starts_with("test.toml: "), "{message}");
    assert!(message.contains("line 2"), "{message}");
    // A misspelt key must not be ignored (a `rest` would silently leave reset unset).
    let typo = map_with(&register(
        "R",
        0,
        "  { name = \"F\", lsb = 0, width = 1, access = \"rw\", rest = 0, description = \"d\" }",
    ));
    let message = syntax_error(&typo);
    assert!(message.contains("rest"), "{message}");
    let missing = map_with(&register("R", 0, "  { name = \"F\", width = 1, access = \"ro\", description = \"d\" }"));
    let message = syntax_error(&missing);
    assert!(message.contains("lsb"), "{message}");
}

#[test]
fn a_missing_file_is_an_error_naming_it() {
    let error = finestep_regmap::spec::load(std::path::Path::new("/nonexistent/registers.toml")).unwrap_err();
    assert!(error.to_string().contains("cannot read /nonexistent/registers.toml"), "{error}");
}

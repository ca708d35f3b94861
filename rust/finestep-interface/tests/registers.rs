//! The generated `regs` module: accessors that round-trip, masks that do not overlap,
//! and constants that say what `hdl/registers.toml` says (read with finestep-regmap's
//! parser, and for CONTROL straight from the TOML text).

use finestep_interface::regs::{self, axis_mode, axis_timing_a, control, id, period_clocks, position};
use finestep_interface::{Access, Field};
use finestep_regmap::{default_root, load_map, MAP_PATH};

/// Words that the untouched bits of a register may hold around a field.
const BACKGROUNDS: [u32; 4] = [0, u32::MAX, 0xA5A5_5A5A, 0x1234_5678];

/// Values to store in a field: its extremes and some bit patterns, cut to its width.
fn values_for(field: Field) -> Vec<u32> {
    let max = field.max();
    vec![0, 1 & max, max, max >> 1, 0x5555_5555 & max, 0xAAAA_AAAA & max]
}

#[test]
fn every_rw_field_round_trips_and_leaves_the_other_bits_alone() {
    let mut rw_fields = 0;
    for register in regs::REGISTERS {
        for info in register.fields.iter().filter(|info| info.access == Access::ReadWrite) {
            rw_fields += 1;
            let field = info.field;
            for background in BACKGROUNDS {
                for value in values_for(field) {
                    let word = field.set(background, value);
                    assert_eq!(field.get(word), value, "{}.{} value {value:#x}", register.name, info.name);
                    assert_eq!(
                        word & !field.mask(),
                        background & !field.mask(),
                        "{}.{} disturbed other bits",
                        register.name,
                        info.name
                    );
                }
            }
        }
    }
    let map = load_map(&default_root()).unwrap_or_else(|error| panic!("{error}"));
    let rw_in_map = map
        .registers
        .iter()
        .flat_map(|register| &register.fields)
        .filter(|field| field.access.keyword() == Access::ReadWrite.keyword())
        .count();
    assert_eq!(rw_fields, rw_in_map, "the table misses rw fields");
}

#[test]
fn masks_have_width_bits_at_lsb_and_fields_do_not_share_bits() {
    for register in regs::REGISTERS {
        let mut used = 0u32;
        for info in register.fields {
            let mask = info.field.mask();
            assert_eq!(mask.count_ones(), info.field.width, "{}.{}", register.name, info.name);
            assert_eq!(mask.trailing_zeros(), info.field.lsb, "{}.{}", register.name, info.name);
            assert_eq!(used & mask, 0, "{}.{} overlaps another field", register.name, info.name);
            used |= mask;
        }
    }
}

/// Reads CONTROL's reset values from the TOML text directly, not through the crate's
/// parser, so a parser or generator bug cannot hide in both sides.
#[test]
fn control_reset_values_are_what_the_toml_says() {
    let text = std::fs::read_to_string(default_root().join(MAP_PATH)).unwrap();
    let document: toml::Table = text.parse().unwrap();
    let registers = document["register"].as_array().unwrap();
    let control_table =
        registers.iter().find(|register| register["name"].as_str() == Some("CONTROL")).expect("the map has CONTROL");
    let reset_of = |name: &str| -> u32 {
        let fields = control_table["fields"].as_array().unwrap();
        let field = fields.iter().find(|field| field["name"].as_str() == Some(name)).unwrap();
        field["reset"].as_integer().unwrap() as u32
    };
    assert_eq!(control::RUN_RESET, reset_of("RUN"));
    assert_eq!(control::WATCHDOG_ENABLE_RESET, reset_of("WATCHDOG_ENABLE"));
    assert_eq!(control::ESTOP_ACTIVE_HIGH_RESET, reset_of("ESTOP_ACTIVE_HIGH"));
    assert_eq!(control::ADDR as i64, control_table["address"].as_integer().unwrap());
    // And as numbers, for the reader: only ESTOP_ACTIVE_HIGH (bit 2) is set out of reset.
    assert_eq!(control::reset_word(), 0b100);
}

#[test]
fn reset_word_is_the_reset_and_fixed_values_put_together() {
    let mut with_reset_word = 0;
    for register in regs::REGISTERS {
        let composed = register.fields.iter().try_fold(0u32, |word, info| {
            let after_reset = match info.access {
                Access::ReadWrite => info.reset,
                Access::ReadOnly => info.value.or(info.reset),
                Access::Pulse | Access::WriteOnly => Some(0),
                Access::WriteOneToClear => None,
            };
            after_reset.map(|value| info.field.set(word, value))
        });
        assert_eq!(register.reset_word, composed, "{}", register.name);
        with_reset_word += usize::from(composed.is_some());
    }
    assert!(with_reset_word > 0);
    let reset_word_of = |name: &str| regs::REGISTERS.iter().find(|register| register.name == name).unwrap().reset_word;
    assert_eq!(reset_word_of("STATUS"), None, "hardware flags");
    assert_eq!(reset_word_of("IRQ_STATUS"), None, "w1c flags");
    assert_eq!(reset_word_of("COMMAND"), Some(0), "pulse fields read 0");
    assert_eq!(reset_word_of("PROBE_TIME"), Some(0), "an ro field with a reset: 0 until the first probe event");
    assert_eq!(id::reset_word(), id::MAGIC_VALUE);
    assert_eq!(id::MAGIC_VALUE.to_be_bytes(), *b"FSTP");
}

#[test]
fn table_matches_the_map_file() {
    let map = load_map(&default_root()).unwrap_or_else(|error| panic!("{error}"));
    assert_eq!(regs::REGISTERS.len(), map.registers.len());
    assert_eq!(regs::ADDRESS_BITS, map.address_bits);
    assert_eq!(
        (regs::MAP_VERSION_MAJOR, regs::MAP_VERSION_MINOR, regs::MAP_VERSION_PATCH),
        (map.version.major, map.version.minor, map.version.patch)
    );
    for (info, spec) in regs::REGISTERS.iter().zip(&map.registers) {
        assert_eq!(info.name, spec.name);
        assert_eq!(u32::from(info.addr), spec.address, "{}", spec.name);
        assert_eq!(info.description, spec.description, "{}", spec.name);
        assert_eq!(info.reset_word, spec.reset_word(), "{}", spec.name);
        assert_eq!(info.count(), spec.count() as usize, "{}", spec.name);
        let info_addresses: Vec<u32> = (0..info.count()).map(|index| u32::from(info.addr_of(index).unwrap())).collect();
        assert_eq!(info_addresses, spec.addresses().collect::<Vec<_>>(), "{}", spec.name);
        assert_eq!(info.fields.len(), spec.fields.len(), "{}", spec.name);
        for (field_info, field_spec) in info.fields.iter().zip(&spec.fields) {
            let place = format!("{}.{}", spec.name, field_spec.name);
            assert_eq!(field_info.name, field_spec.name, "{place}");
            assert_eq!(field_info.field, Field { lsb: field_spec.lsb, width: field_spec.width }, "{place}");
            assert_eq!(field_info.access.keyword(), field_spec.access.keyword(), "{place}");
            assert_eq!(field_info.reset, field_spec.reset, "{place}");
            assert_eq!(field_info.value, field_spec.value, "{place}");
            assert_eq!(field_info.description, field_spec.description, "{place}");
        }
    }
}

#[test]
fn no_two_register_elements_share_an_address() {
    let mut owners = std::collections::BTreeMap::new();
    for register in regs::REGISTERS {
        for index in 0..register.count() {
            let addr = register.addr_of(index).unwrap();
            assert!(u32::from(addr) < 1 << regs::ADDRESS_BITS);
            if let Some(other) = owners.insert(addr, (register.name, index)) {
                panic!("{}[{index}] and {other:?} share {addr:#04x}", register.name);
            }
        }
    }
}

#[test]
fn array_addresses() {
    assert_eq!(axis_timing_a::COUNT, 8);
    assert_eq!(
        (0..axis_timing_a::COUNT).map(axis_timing_a::addr).collect::<Vec<_>>(),
        [0x20, 0x24, 0x28, 0x2C, 0x30, 0x34, 0x38, 0x3C]
    );
    assert_eq!(axis_mode::addr(7), 0x22 + 7 * 4);
    assert_eq!(position::addr(3), 0x43);
    let table_entry = regs::REGISTERS.iter().find(|register| register.name == "AXIS_MODE").unwrap();
    assert_eq!(table_entry.addr_of(7), Some(axis_mode::addr(7)));
    assert_eq!(table_entry.addr_of(axis_mode::COUNT), None);
    let single = regs::REGISTERS.iter().find(|register| register.name == "CONTROL").unwrap();
    assert_eq!(single.addr_of(0), Some(control::ADDR));
    assert_eq!(single.addr_of(1), None);
}

#[test]
#[should_panic(expected = "AXIS_MODE index out of range")]
fn array_address_past_the_end_panics() {
    let _ = axis_mode::addr(axis_mode::COUNT);
}

#[test]
fn accessors_are_usable_in_constants() {
    // A driver can build configuration words at compile time.
    const QUADRATURE_INVERTED_A: u32 = axis_mode::INVERT_A.set(axis_mode::OUT_MODE.set(axis_mode::reset_word(), 2), 1);
    assert_eq!(QUADRATURE_INVERTED_A, 0b110);
    assert_eq!(period_clocks::CLOCKS.max(), (1 << 24) - 1);
    assert!(period_clocks::CLOCKS.fits(period_clocks::CLOCKS_RESET));
}

//! The generated Rust agrees with the generated Verilog, constant by constant: every
//! register constant of `finestep_regs.vh` and every interface constant of
//! `finestep_interface.vh` has the value of its Rust counterpart.

use finestep_interface::params::{finestep_core, finestep_top};
use finestep_interface::spi::{self, Command, ResultCode};
use finestep_interface::{flags, invert, record_layout, regs, Access, CountMode, JogMultiplier, OutMode, MAX_AXES};
use finestep_regmap::spec::MapSpec;
use finestep_regmap::{default_root, interface_verilog, load_interface, load_map, verilog};
use std::collections::BTreeMap;

fn map() -> MapSpec {
    load_map(&default_root()).unwrap_or_else(|error| panic!("{error}"))
}

/// A constant read back from the header text: its declared width (`None` for
/// `integer`) and its value.
#[derive(Debug, PartialEq, Eq, Clone, Copy)]
struct Constant {
    width: Option<u32>,
    value: u64,
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
fn every_verilog_constant_equals_its_rust_counterpart() {
    let constants = parse_header(&verilog::generate(&map()));
    let get = |name: String| -> Constant {
        *constants.get(&name).unwrap_or_else(|| panic!("{name} is missing from the header"))
    };
    assert_eq!(get("FS_ADDR_WIDTH".into()), integer(regs::ADDRESS_BITS));
    assert_eq!(get("FS_MAP_VERSION_MAJOR".into()), integer(regs::MAP_VERSION_MAJOR));
    assert_eq!(get("FS_MAP_VERSION_MINOR".into()), integer(regs::MAP_VERSION_MINOR));
    assert_eq!(get("FS_MAP_VERSION_PATCH".into()), integer(regs::MAP_VERSION_PATCH));
    let mut expected_names = 4;
    for register in regs::REGISTERS {
        let prefix = format!("FS_{}", register.name);
        assert_eq!(get(format!("{prefix}_ADDR")), sized(regs::ADDRESS_BITS, register.addr));
        expected_names += 1;
        if let Some(array) = register.array {
            assert_eq!(get(format!("{prefix}_COUNT")), integer(array.count as u64));
            assert_eq!(get(format!("{prefix}_STRIDE")), integer(array.stride));
            expected_names += 2;
        }
        for info in register.fields {
            let prefix = format!("{prefix}_{}", info.name);
            assert_eq!(get(format!("{prefix}_LSB")), integer(info.field.lsb));
            assert_eq!(get(format!("{prefix}_WIDTH")), integer(info.field.width));
            expected_names += 2;
            if let Some(reset) = info.reset {
                assert!(matches!(info.access, Access::ReadWrite | Access::ReadOnly), "{prefix}");
                assert_eq!(get(format!("{prefix}_RESET")), sized(info.field.width, reset));
                expected_names += 1;
            }
            if let Some(value) = info.value {
                assert_eq!(get(format!("{prefix}_VALUE")), sized(info.field.width, value));
                expected_names += 1;
            }
        }
    }
    assert_eq!(constants.len(), expected_names, "the header declares constants the Rust side lacks");
}

#[test]
fn every_interface_constant_equals_its_rust_counterpart() {
    let (_, interface) = load_interface(&default_root()).unwrap_or_else(|e| panic!("{e}"));
    let constants = parse_header(&interface_verilog::generate(&interface));
    let get = |name: &str| -> Constant {
        *constants.get(name).unwrap_or_else(|| panic!("{name} is missing from finestep_interface.vh"))
    };
    assert_eq!(get("FS_MAX_AXES"), integer(MAX_AXES as u64));
    assert_eq!(get("FS_REC_INC_WIDTH"), integer(record_layout::INC_WIDTH));
    assert_eq!(get("FS_REC_INC_FRAC_BITS"), integer(record_layout::INC_FRAC_BITS));
    assert_eq!(get("FS_REC_FLAGS_WIDTH"), integer(record_layout::FLAGS_WIDTH));
    assert_eq!(get("FS_REC_FLAG_BLOCK_END_BIT"), integer(flags::BLOCK_END_BIT));
    assert_eq!(1u8 << flags::BLOCK_END_BIT, flags::BLOCK_END);
    assert_eq!(get("FS_SPI_MAX_COUNT"), integer(spi::MAX_COUNT as u64));
    assert_eq!(get("FS_SPI_CRC_POLYNOMIAL"), sized(16, spi::CRC_POLYNOMIAL));
    assert_eq!(get("FS_SPI_CRC_INITIAL"), sized(16, spi::CRC_INITIAL));
    for command in Command::ALL {
        assert_eq!(get(&format!("FS_SPI_CMD_{}", command.name())), sized(8, command.code()));
    }
    for result in ResultCode::ALL {
        assert_eq!(get(&format!("FS_SPI_RESULT_{}", result.name())), sized(8, result.code()));
    }
    for mode in OutMode::ALL {
        assert_eq!(get(&format!("FS_OUT_MODE_{}", mode.name())), sized(OutMode::FIELD.width, mode.bits()));
    }
    for mode in CountMode::ALL {
        assert_eq!(get(&format!("FS_COUNT_MODE_{}", mode.name())), sized(CountMode::FIELD.width, mode.bits()));
    }
    for multiplier in JogMultiplier::ALL {
        let name = format!("FS_JOG_MULTIPLIER_{}", multiplier.name());
        assert_eq!(get(&name), sized(JogMultiplier::FIELD.width, multiplier.bits()));
    }
    assert_eq!(get("FS_INVERT_WIDTH"), integer(invert::WIDTH));
    for (name, bit, mask) in [
        ("PIN_A", invert::PIN_A_BIT, invert::PIN_A),
        ("PIN_B", invert::PIN_B_BIT, invert::PIN_B),
        ("PIN_EN", invert::PIN_EN_BIT, invert::PIN_EN),
    ] {
        assert_eq!(get(&format!("FS_INVERT_{name}_BIT")), integer(bit));
        assert_eq!(1u8 << bit, mask);
    }
    for (module, ranges) in [("FINESTEP_CORE", &finestep_core::ALL[..]), ("FINESTEP_TOP", &finestep_top::ALL[..])] {
        for range in ranges {
            assert_eq!(get(&format!("FS_{module}_{}_DEFAULT", range.name)), integer(range.default));
            assert_eq!(get(&format!("FS_{module}_{}_MIN", range.name)), integer(range.min));
            assert_eq!(get(&format!("FS_{module}_{}_MAX", range.name)), integer(range.max));
        }
    }
    let declared = constants.len();
    let named = finestep_regmap::interface::verilog_names(&interface).len();
    assert_eq!(declared, named, "the header declares constants the names table lacks");
}

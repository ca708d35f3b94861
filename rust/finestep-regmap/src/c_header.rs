//! `finestep_interface.h`: the interface constants and the drive-timing struct for the
//! C shims of the Verilator simulations (`sim/`), generated into the -sys crate's
//! `OUT_DIR` by its build script.
//!
//! Flags and bits are masks (`FS_REC_FLAG_BLOCK_END` is `0x01u`) with `_BIT` the
//! position; enum values are plain numbers; `FS_<ENUM>_WIDTH` and `FS_<ENUM>_MASK` (and
//! the same for a bit set) give the bits of one value.

use crate::interface::InterfaceSpec;
use crate::spec::low_bits;
use std::fmt::Write;

/// The file name the shims include.
pub const HEADER_NAME: &str = "finestep_interface.h";

/// The header text.
pub fn generate(spec: &InterfaceSpec) -> String {
    let mut out = String::new();
    out.push_str(
        "/* finestep_interface.h: the host<->core interface for the C shims.\n \
         * Generated from hdl/interface.toml by finestep-regmap; do not edit. */\n\
         #ifndef FINESTEP_INTERFACE_H\n\
         #define FINESTEP_INTERFACE_H\n\
         \n\
         #include <stdint.h>\n\n",
    );
    let record = &spec.record;
    let _ = writeln!(out, "/* The most axes a record holds. */");
    let _ = writeln!(out, "#define FS_MAX_AXES {}", record.max_axes.value);
    let _ = writeln!(out, "/* Record flags ({} bits). */", record.flags_width());
    let _ = writeln!(out, "#define FS_REC_FLAGS_WIDTH {}", record.flags_width());
    for flag in &record.flags {
        let _ = writeln!(out, "#define FS_REC_FLAG_{}_BIT {}", flag.name, flag.bit);
        let _ =
            writeln!(out, "#define FS_REC_FLAG_{} 0x{:02x}u /* {} */", flag.name, 1u32 << flag.bit, flag.description);
    }
    for enumeration in &spec.enums {
        let _ =
            writeln!(out, "\n/* {} ({}): {} */", enumeration.name, enumeration.field.path(), enumeration.description);
        let _ = writeln!(out, "#define FS_{}_WIDTH {}", enumeration.name, enumeration.width());
        let _ = writeln!(out, "#define FS_{}_MASK 0x{:x}u", enumeration.name, low_bits(enumeration.width()));
        for value in &enumeration.values {
            let _ = writeln!(out, "#define FS_{}_{} {}u", enumeration.name, value.name, value.value);
        }
    }
    for bitset in &spec.bitsets {
        let _ = writeln!(out, "\n/* {}: {} */", bitset.name, bitset.description);
        let _ = writeln!(out, "#define FS_{}_WIDTH {}", bitset.name, bitset.width);
        let _ = writeln!(out, "#define FS_{}_MASK 0x{:x}u", bitset.name, low_bits(bitset.width));
        for bit in &bitset.bits {
            let _ = writeln!(
                out,
                "#define FS_{}_{} 0x{:x}u /* {} */",
                bitset.name,
                bit.name,
                1u32 << bit.bit,
                bit.description
            );
        }
    }
    let pbp = &spec.pbp;
    let _ = writeln!(out, "\n/* A record with the flag PBP: its fields' lanes, lowest bits and widths. */");
    let _ = writeln!(out, "#define FS_PBP_BITS_LANE {}", pbp.bits.lane);
    let _ = writeln!(out, "#define FS_PBP_BITS_LSB {}", pbp.bits.lsb);
    for field in pbp.fields() {
        for (what, value) in [("LANE", field.lane), ("LSB", field.lsb), ("WIDTH", field.width)] {
            let _ = writeln!(out, "#define FS_PBP_{}_{what} {value}", field.name);
        }
    }
    for module in &spec.modules {
        let _ = writeln!(out, "\n/* Defaults of {}'s build parameters. */", module.name);
        for parameter in &module.parameters {
            let _ = writeln!(
                out,
                "#define FS_{}_{}_DEFAULT {}",
                module.name.to_ascii_uppercase(),
                parameter.name,
                parameter.default
            );
        }
    }
    out.push_str("\n/* Drive timing of one axis, in clocks. */\ntypedef struct fs_drive_timing {\n");
    for field in &spec.timing {
        let _ = writeln!(
            out,
            "    uint32_t {}; /* {}: {} */",
            field.name.to_ascii_lowercase(),
            field.symbol,
            field.description
        );
    }
    out.push_str("} fs_drive_timing;\n\n#endif\n");
    out
}

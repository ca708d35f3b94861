//! The Verilog-2005 header `finestep_regs.vh`: the map as `localparam`s, to be
//! `` `include``d inside a module body.
//!
//! Naming (every name starts with `FS_`):
//!
//! | constant | kind |
//! | --- | --- |
//! | `FS_ADDR_WIDTH` | integer: bits of a word address |
//! | `FS_MAP_VERSION_MAJOR`, `_MINOR`, `_PATCH` | integers |
//! | `FS_<REG>_ADDR` | `[FS_ADDR_WIDTH-1:0]`: word address (element 0 of an array) |
//! | `FS_<REG>_COUNT`, `FS_<REG>_STRIDE` | integers, arrays only |
//! | `FS_<REG>_<FIELD>_LSB`, `FS_<REG>_<FIELD>_WIDTH` | integers |
//! | `FS_<REG>_<FIELD>_RESET` | sized to the field: reset value of an `rw` field (or of an `ro` field that has one) |
//! | `FS_<REG>_<FIELD>_VALUE` | sized to the field: fixed value of an `ro` field |
//!
//! For example `localparam [6:0] FS_CONTROL_ADDR = 7'h04;` and
//! `localparam [0:0] FS_CONTROL_ESTOP_ACTIVE_HIGH_RESET = 1'h1;`.

use crate::spec::{bit_range, naming, MapSpec};
use std::fmt::Write;

/// The file name the RTL includes.
pub const HEADER_NAME: &str = "finestep_regs.vh";

/// The header text for a validated map.
pub fn generate(map: &MapSpec) -> String {
    let mut out = String::new();
    let version = map.version;
    let address_bits = map.address_bits;
    // Writing to a String cannot fail; the `let _ =` are for that.
    let _ = writeln!(
        out,
        "// {HEADER_NAME}: the {} register map, version {}.{}.{}, as Verilog constants.",
        map.name, version.major, version.minor, version.patch
    );
    // No comment line may start with a tool's pragma word (`verilator`, `synthesis`,
    // `pragma`): each generated one starts with a fixed word of ours.
    out.push_str(
        "// Generated from hdl/registers.toml by finestep-regmap; do not edit.\n\
         //\n\
         // `include this inside a module body. It declares only localparams, so it has no\n\
         // include guard: every module that includes it gets its own copy. Addresses are\n\
         // word addresses of FS_ADDR_WIDTH bits; LSB, WIDTH, COUNT and STRIDE are integers;\n\
         // RESET and VALUE are sized to their field. A module uses only some of these, so\n\
         // the unused-parameter warning of Verilator is off inside this file alone.\n\
         \n\
         /* verilator lint_save */\n\
         /* verilator lint_off UNUSEDPARAM */\n\
         \n",
    );
    let _ = writeln!(out, "localparam integer {} = {address_bits};", naming::VERILOG_ADDR_WIDTH);
    for (part, number) in [("MAJOR", version.major), ("MINOR", version.minor), ("PATCH", version.patch)] {
        let _ = writeln!(out, "localparam integer {} = {number};", naming::verilog_map_version(part));
    }
    for register in &map.registers {
        let _ = writeln!(out, "\n// register {}: {}", register.name, register.description);
        let _ = writeln!(
            out,
            "localparam [{}:0] {} = {};",
            address_bits - 1,
            naming::verilog_register(register, "ADDR"),
            sized(address_bits, register.address)
        );
        if let Some(array) = register.array {
            let _ =
                writeln!(out, "localparam integer {} = {};", naming::verilog_register(register, "COUNT"), array.count);
            let _ = writeln!(
                out,
                "localparam integer {} = {};",
                naming::verilog_register(register, "STRIDE"),
                array.stride
            );
        }
        for field in &register.fields {
            let _ = writeln!(
                out,
                "// field {}.{} [{}] {}: {}",
                register.name,
                field.name,
                bit_range(field),
                field.access,
                field.description
            );
            let _ =
                writeln!(out, "localparam integer {} = {};", naming::verilog_field(register, field, "LSB"), field.lsb);
            let _ = writeln!(
                out,
                "localparam integer {} = {};",
                naming::verilog_field(register, field, "WIDTH"),
                field.width
            );
            for (what, constant) in [("RESET", field.reset), ("VALUE", field.value)] {
                if let Some(constant) = constant {
                    let _ = writeln!(
                        out,
                        "localparam [{}:0] {} = {};{}",
                        field.width - 1,
                        naming::verilog_field(register, field, what),
                        sized(field.width, constant),
                        decimal_comment(constant)
                    );
                }
            }
        }
    }
    out.push_str("\n/* verilator lint_restore */\n");
    out
}

/// A sized hexadecimal literal with as many digits as the width needs: `7'h04`.
fn sized(width: u32, value: u32) -> String {
    let digits = width.div_ceil(4) as usize;
    format!("{width}'h{value:0digits$X}")
}

/// ` // 50000` after a hex literal whose decimal value is not obvious.
fn decimal_comment(value: u32) -> String {
    if value < 10 {
        String::new()
    } else {
        format!(" // {value}")
    }
}

#[cfg(test)]
mod tests {
    use super::sized;

    #[test]
    fn sized_literals_have_the_digits_of_their_width() {
        assert_eq!(sized(7, 4), "7'h04");
        assert_eq!(sized(1, 1), "1'h1");
        assert_eq!(sized(24, 50_000), "24'h00C350");
        assert_eq!(sized(32, 0x4653_5450), "32'h46535450");
    }
}

//! The Verilog side of the interface description: `finestep_interface.vh` (constants)
//! and one `<module>_checks.vh` per module with build parameters (elaboration checks).
//!
//! Naming of `finestep_interface.vh` (every name starts with `FS_`; see
//! [`crate::interface::verilog_names`]):
//!
//! | constant | kind |
//! | --- | --- |
//! | `FS_MAX_AXES`, `FS_REC_INC_WIDTH`, `FS_REC_INC_FRAC_BITS`, `FS_REC_FLAGS_WIDTH` | integers |
//! | `FS_REC_FLAG_<FLAG>_BIT` | integer: bit position in the flags |
//! | `FS_SPI_MAX_COUNT` | integer |
//! | `FS_SPI_CRC_POLYNOMIAL`, `FS_SPI_CRC_INITIAL` | sized to the CRC |
//! | `FS_SPI_CMD_<NAME>`, `FS_SPI_RESULT_<NAME>` | `[7:0]` |
//! | `FS_<ENUM>_WIDTH`; `FS_<ENUM>_<VALUE>` | integer; sized to the field |
//! | `FS_<BITS>_WIDTH`, `FS_<BITS>_<BIT>_BIT` | integers |
//! | `FS_PBP_BITS_LANE`, `FS_PBP_BITS_LSB`; `FS_PBP_<FIELD>_LANE`, `_LSB`, `_WIDTH` | integers |
//! | `FS_<MODULE>_<PARAM>_DEFAULT`, `_MIN`, `_MAX` | integers |

use crate::interface::{InterfaceSpec, ModuleSpec};
use std::fmt::Write;

/// The file name of the constants header.
pub const HEADER_NAME: &str = "finestep_interface.vh";

/// The file name of a module's checks header.
pub fn checks_name(module: &ModuleSpec) -> String {
    format!("{}_checks.vh", module.name)
}

fn sized(width: u32, value: u32) -> String {
    let digits = width.div_ceil(4) as usize;
    format!("{width}'h{value:0digits$X}")
}

/// The constants header.
pub fn generate(spec: &InterfaceSpec) -> String {
    let mut out = String::new();
    // Writing to a String cannot fail; the `let _ =` are for that. No comment line may
    // start with a tool's pragma word (`verilator`, `synthesis`, `pragma`).
    out.push_str(
        "// finestep_interface.vh: the host<->core interface as Verilog constants.\n\
         // Generated from hdl/interface.toml by finestep-regmap; do not edit.\n\
         //\n\
         // `include this inside a module body, beside finestep_regs.vh (the register map).\n\
         // It declares only localparams, so it has no include guard: every module that\n\
         // includes it gets its own copy. A module uses only some of these, so the\n\
         // unused-parameter warning of Verilator is off inside this file alone.\n\
         \n\
         /* verilator lint_save */\n\
         /* verilator lint_off UNUSEDPARAM */\n",
    );
    let record = &spec.record;
    let _ = writeln!(
        out,
        "\n// The period record: axis i's increment in bits FS_REC_INC_WIDTH*i +: FS_REC_INC_WIDTH\n\
         // (two's complement, FS_REC_INC_FRAC_BITS fraction bits), the flags above the last axis."
    );
    let _ = writeln!(out, "localparam integer FS_MAX_AXES = {};", record.max_axes.value);
    let _ = writeln!(out, "localparam integer FS_REC_INC_WIDTH = {};", record.increment.width());
    let _ = writeln!(out, "localparam integer FS_REC_INC_FRAC_BITS = {};", record.increment.frac_bits);
    let _ = writeln!(out, "localparam integer FS_REC_FLAGS_WIDTH = {};", record.flags_width());
    for flag in &record.flags {
        let _ = writeln!(out, "// flag {}: {}", flag.name, flag.description);
        let _ = writeln!(out, "localparam integer FS_REC_FLAG_{}_BIT = {};", flag.name, flag.bit);
    }

    let spi = &spec.spi;
    let _ =
        writeln!(out, "\n// SPI frames: command, address, count, data; {} ({}).", spi.crc.name, spi.crc.description);
    let _ = writeln!(out, "localparam integer FS_SPI_MAX_COUNT = {};", spi.max_count);
    let crc_width = spi.crc.width;
    let _ = writeln!(
        out,
        "localparam [{}:0] FS_SPI_CRC_POLYNOMIAL = {};",
        crc_width - 1,
        sized(crc_width, spi.crc.polynomial)
    );
    let _ =
        writeln!(out, "localparam [{}:0] FS_SPI_CRC_INITIAL = {};", crc_width - 1, sized(crc_width, spi.crc.initial));
    for (kind, codes) in [("CMD", &spi.commands), ("RESULT", &spi.results)] {
        for code in codes {
            let _ = writeln!(
                out,
                "localparam [7:0] FS_SPI_{kind}_{} = {}; // {}",
                code.name,
                sized(8, code.code.into()),
                code.description
            );
        }
    }

    for enumeration in &spec.enums {
        let width = enumeration.width();
        let _ = writeln!(out, "\n// {} ({}): {}", enumeration.name, enumeration.field.path(), enumeration.description);
        if let Some(otherwise) = &enumeration.otherwise {
            let _ = writeln!(out, "// Values not listed act as {otherwise}.");
        }
        let _ = writeln!(out, "localparam integer FS_{}_WIDTH = {width};", enumeration.name);
        for value in &enumeration.values {
            let _ = writeln!(
                out,
                "localparam [{}:0] FS_{}_{} = {}; // {}",
                width - 1,
                enumeration.name,
                value.name,
                sized(width, value.value),
                value.description
            );
        }
    }

    for bitset in &spec.bitsets {
        let _ = writeln!(out, "\n// {}: {}", bitset.name, bitset.description);
        let _ = writeln!(out, "localparam integer FS_{}_WIDTH = {};", bitset.name, bitset.width);
        for bit in &bitset.bits {
            let _ = writeln!(
                out,
                "localparam integer FS_{}_{}_BIT = {}; // {}",
                bitset.name, bit.name, bit.bit, bit.description
            );
        }
    }

    let pbp = &spec.pbp;
    let _ = writeln!(out, "\n// A record with the flag PBP: {}", pbp.description);
    let _ = writeln!(
        out,
        "// {} in lane {} bits {} +: {}.",
        pbp.bits.description, pbp.bits.lane, pbp.bits.lsb, pbp.bits.width
    );
    let _ = writeln!(out, "localparam integer FS_PBP_BITS_LANE = {};", pbp.bits.lane);
    let _ = writeln!(out, "localparam integer FS_PBP_BITS_LSB = {};", pbp.bits.lsb);
    for field in pbp.fields() {
        let _ = writeln!(out, "// {}: {}", field.name, field.description);
        for (what, value) in [("LANE", field.lane), ("LSB", field.lsb), ("WIDTH", field.width)] {
            let _ = writeln!(out, "localparam integer FS_PBP_{}_{what} = {value};", field.name);
        }
    }

    for module in &spec.modules {
        let upper = module.name.to_ascii_uppercase();
        let _ = writeln!(out, "\n// Build parameters of {} (checked by {}).", module.name, checks_name(module));
        for parameter in &module.parameters {
            for (what, value) in
                [("DEFAULT", parameter.default), ("MIN", parameter.min.value), ("MAX", parameter.max.value)]
            {
                let _ = writeln!(out, "localparam integer FS_{upper}_{}_{what} = {value};", parameter.name);
            }
        }
    }
    out.push_str("\n/* verilator lint_restore */\n");
    out
}

/// The checks header of `module`: an out-of-range parameter instantiates a module that
/// does not exist, named after the parameter and its range.
pub fn generate_checks(module: &ModuleSpec) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "// {}: elaboration checks of {}'s build parameters.", checks_name(module), module.name);
    out.push_str(
        "// Generated from hdl/interface.toml by finestep-regmap; do not edit.\n\
         //\n",
    );
    let _ = writeln!(
        out,
        "// `include this inside the body of {0}, after its ports. A parameter outside its\n\
         // legal range instantiates a module that does not exist, named after the parameter\n\
         // and its range ({0}_<PARAM>_must_be_<min>_to_<max>): Verilator, Yosys, Quartus\n\
         // and Diamond all stop there and print that name. Plain Verilog-2005.",
        module.name
    );
    if !module.derived.is_empty() {
        out.push_str("\n// Values derived from the parameters, for the constraints below.\n");
    }
    for derived in &module.derived {
        let _ = writeln!(out, "// {}: {}", derived.name, derived.description);
        let _ =
            writeln!(out, "localparam integer {} = {};", derived.verilog_name(), verilog_expr(module, &derived.value));
    }
    // A constraint is checked only with every parameter in its range, so an
    // out-of-range parameter is named alone (and a constraint's expression never sees
    // an out-of-range value).
    let in_range: Vec<String> = module
        .parameters
        .iter()
        .map(|p| format!("({name} >= {min} && {name} <= {max})", name = p.name, min = p.min.value, max = p.max.value))
        .collect();
    if !module.constraints.is_empty() {
        out.push_str("\n// Every parameter within its range: the constraints below are checked only then.\n");
        let _ = writeln!(out, "localparam FS_CHECK_IN_RANGE = {};", in_range.join(" && "));
    }
    out.push_str("\ngenerate\n");
    for parameter in &module.parameters {
        let _ = writeln!(out, "    // {}: {}", parameter.name, parameter.description);
        let _ = writeln!(
            out,
            "    if ({name} < {min} || {name} > {max}) begin : fs_check_{lower}\n\
             \x20       {module} out_of_range ();\n\
             \x20   end",
            name = parameter.name,
            min = parameter.min.value,
            max = parameter.max.value,
            lower = parameter.name.to_ascii_lowercase(),
            module = parameter.check_module(&module.name)
        );
    }
    if !module.constraints.is_empty() {
        let _ = writeln!(
            out,
            "    // Constraints across parameters: a combination that breaks one instantiates\n\
             \x20   // {}_<constraint>, a module that does not exist.",
            module.name
        );
    }
    for constraint in &module.constraints {
        let _ = writeln!(out, "    // {}", constraint.description);
        let require = verilog_expr(module, &constraint.require);
        let broken = match &constraint.when {
            Some(when) => format!("FS_CHECK_IN_RANGE && ({}) && !({require})", verilog_expr(module, when)),
            None => format!("FS_CHECK_IN_RANGE && !({require})"),
        };
        let _ = writeln!(
            out,
            "    if ({broken}) begin : fs_constraint_{lower}\n\
             \x20       {module} out_of_range ();\n\
             \x20   end",
            lower = constraint.name.to_ascii_lowercase(),
            module = constraint.check_module(&module.name)
        );
    }
    out.push_str("endgenerate\n");
    out
}

/// `expr` in `module`'s checks header: a derived value by its localparam.
fn verilog_expr(module: &ModuleSpec, expr: &crate::expr::Expr) -> String {
    expr.verilog(&|name| match module.derived.iter().find(|d| d.name == name) {
        Some(derived) => derived.verilog_name(),
        None => name.to_string(),
    })
}

//! `docs/interface.md`: the interface description as prose and tables, committed beside
//! `docs/registers.md`; a test fails when it is stale.

use crate::interface::{Bound, InterfaceSpec};
use crate::interface_verilog;
use std::fmt::Write;

/// Text safe inside a table cell.
fn cell(text: &str) -> String {
    text.replace('|', "\\|")
}

fn bound(bound: &Bound) -> String {
    if bound.is_derived() {
        format!("{} (`{}`)", bound.value, bound.expression)
    } else {
        bound.value.to_string()
    }
}

/// The Markdown text.
pub fn generate(spec: &InterfaceSpec) -> String {
    let mut out = String::new();
    // Writing to a String cannot fail; the `let _ =` are for that.
    out.push_str(
        "# finestep host<->core interface\n\n\
         Generated from `hdl/interface.toml` by `make regmap`; do not edit. (`make test` \
         fails when this file is stale.)\n\n\
         What the RTL, the Rust crates and the C shims agree on besides the register map \
         ([registers.md](registers.md)): the period record, the SPI frame codes, the values \
         of the register fields the RTL decodes, the drive timing and the build parameters \
         with their legal ranges. `rust/finestep-regmap` validates `hdl/interface.toml` \
         against `hdl/registers.toml` and generates from both: the Verilog headers \
         `finestep_regs.vh`, `finestep_interface.vh` and `<module>_checks.vh` (into \
         `build/gen`, never committed), the C header `finestep_interface.h` of the Verilator \
         shims, the constants and types of the `finestep-interface` crate, and this page.\n",
    );

    let record = &spec.record;
    let increment = &record.increment;
    let _ = writeln!(
        out,
        "\n## Period record\n\n\
         One increment per axis, at most {max} axes (`MAX_AXES`, `{max_expr}`), and {flags} \
         bits of flags. An increment is {width} bits, {desc}: I{int}F{frac} \
         (`{field}`). In the FIFO, axis i sits in bits `{width}*i +: {width}` and the flags \
         above the last axis; an SPI FIFO frame carries each axis big-endian, axis 0 \
         first, then the flags byte (`{flags_field}` for a RECORD_PUSH).\n",
        max = record.max_axes.value,
        max_expr = record.max_axes.expression,
        flags = record.flags_width(),
        width = increment.width(),
        desc = increment.description,
        int = increment.int_bits,
        frac = increment.frac_bits,
        field = increment.field.path(),
        flags_field = record.flags_field.path(),
    );
    out.push_str("| bit | flag | meaning |\n| --- | --- | --- |\n");
    for flag in &record.flags {
        let _ = writeln!(out, "| {} | {} | {} |", flag.bit, flag.name, cell(&flag.description));
    }
    let _ = writeln!(out, "\nOther flag bits are reserved: the core ignores them.");

    let spi = &spec.spi;
    let _ = writeln!(
        out,
        "\n## SPI frames\n\n\
         Every frame is `command, address, count`, then data; `count` is at most {}. The \
         CRC is {} (width {}, polynomial {:#06x}, initial value {:#06x}): {}.\n",
        spi.max_count, spi.crc.name, spi.crc.width, spi.crc.polynomial, spi.crc.initial, spi.crc.description
    );
    out.push_str("| command | byte | meaning |\n| --- | --- | --- |\n");
    for command in &spi.commands {
        let _ = writeln!(out, "| {} | {:#04x} | {} |", command.name, command.code, cell(&command.description));
    }
    out.push_str("\nThe result byte of a WRITE or FIFO frame (and of a rejected frame):\n\n");
    out.push_str("| result | byte | meaning |\n| --- | --- | --- |\n");
    for result in &spi.results {
        let _ = writeln!(out, "| {} | {:#04x} | {} |", result.name, result.code, cell(&result.description));
    }

    out.push_str("\n## Field values\n\nRegister fields whose values the RTL decodes.\n");
    for enumeration in &spec.enums {
        let _ = writeln!(
            out,
            "\n### {}\n\n{} Field `{}` ({} bits).",
            enumeration.name,
            enumeration.description,
            enumeration.field.path(),
            enumeration.width()
        );
        if let Some(otherwise) = &enumeration.otherwise {
            let _ = writeln!(out, "Values not listed act as {otherwise}.");
        }
        let factors = enumeration.has_factors();
        out.push_str(if factors {
            "\n| value | name | factor | meaning |\n| --- | --- | --- | --- |\n"
        } else {
            "\n| value | name | meaning |\n| --- | --- | --- |\n"
        });
        for value in &enumeration.values {
            let reset = if enumeration.reset_value() == Some(value) { " (reset)" } else { "" };
            match value.factor {
                Some(factor) if factors => {
                    let _ = writeln!(
                        out,
                        "| {} | {}{reset} | {factor} | {} |",
                        value.value,
                        value.name,
                        cell(&value.description)
                    );
                }
                _ => {
                    let _ = writeln!(out, "| {} | {}{reset} | {} |", value.value, value.name, cell(&value.description));
                }
            }
        }
    }

    out.push_str("\n## Bit vectors\n");
    for bitset in &spec.bitsets {
        let _ = writeln!(out, "\n### {}\n\n{} {} bits.\n", bitset.name, bitset.description, bitset.width);
        out.push_str("| bit | name | field | meaning |\n| --- | --- | --- | --- |\n");
        for bit in &bitset.bits {
            let field = bit.field.as_ref().map_or_else(|| "-".to_string(), |f| format!("`{}`", f.path()));
            let _ = writeln!(out, "| {} | {} | {field} | {} |", bit.bit, bit.name, cell(&bit.description));
        }
    }

    let pbp = &spec.pbp;
    let _ = writeln!(
        out,
        "\n## PBP record lanes\n\n{}\n\n| field | lane | bits | meaning |\n| --- | --- | --- | --- |",
        pbp.description
    );
    for field in std::iter::once(&pbp.bits).chain(pbp.fields()) {
        let _ = writeln!(
            out,
            "| {} | {} | {}:{} | {} |",
            field.name,
            field.lane,
            field.lsb + field.width - 1,
            field.lsb,
            cell(&field.description)
        );
    }

    let _ = writeln!(
        out,
        "\n## Drive timing\n\n\
         Per axis, in clocks (the Rust type `DriveTiming`, the C struct `fs_drive_timing`); \
         the core uses the low `TIMING_W` bits of each.\n\n\
         | field | symbol | register field | meaning |\n| --- | --- | --- | --- |"
    );
    for field in &spec.timing {
        let _ = writeln!(
            out,
            "| {} | {} | `{}` | {} |",
            field.name.to_ascii_lowercase(),
            field.symbol,
            field.field.path(),
            cell(&field.description)
        );
    }

    out.push_str(
        "\n## Build parameters\n\n\
         Verilog module parameters with their defaults and legal ranges. Each module \
         includes its checks header: a value outside the range stops elaboration in every \
         tool at a module that does not exist, named after the parameter \
         (`finestep_top_N_AXES_must_be_1_to_8`).\n",
    );
    for module in &spec.modules {
        let _ = writeln!(
            out,
            "\n### {}\n\n{} Checked by `{}`.\n\n\
             | parameter | default | min | max | reported in | meaning |\n| --- | --- | --- | --- | --- | --- |",
            module.name,
            module.description,
            interface_verilog::checks_name(module)
        );
        for parameter in &module.parameters {
            let caps = parameter.caps.as_ref().map_or_else(|| "-".to_string(), |f| format!("`{}`", f.path()));
            let _ = writeln!(
                out,
                "| {} | {} | {} | {} | {caps} | {} |",
                parameter.name,
                parameter.default,
                bound(&parameter.min),
                bound(&parameter.max),
                cell(&parameter.description)
            );
        }
        if !module.derived.is_empty() {
            let _ = writeln!(
                out,
                "\nDerived values (for the constraints below):\n\n| name | value | meaning |\n| --- | --- | --- |"
            );
            for derived in &module.derived {
                let value = cell(&format!("`{}`", derived.value_text));
                let _ = writeln!(out, "| {} | {value} | {} |", derived.name, cell(&derived.description));
            }
        }
        if !module.constraints.is_empty() {
            let _ = writeln!(
                out,
                "\nConstraints across parameters: a combination that breaks one stops elaboration at \
                 `{}_<name>`.\n\n| name | when | requires | why |\n| --- | --- | --- | --- |",
                module.name
            );
            for constraint in &module.constraints {
                let when =
                    constraint.when_text.as_ref().map_or_else(|| "always".to_string(), |w| cell(&format!("`{w}`")));
                let _ = writeln!(
                    out,
                    "| `{}` | {when} | {} | {} |",
                    constraint.name,
                    cell(&format!("`{}`", constraint.require_text)),
                    cell(&constraint.description)
                );
            }
        }
    }
    out
}

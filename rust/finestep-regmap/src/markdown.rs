//! `docs/registers.md`: the address table, then every register's fields, with the
//! access-type legend. This is the one generated file that is committed.

use crate::spec::{bit_range, Access, FieldSpec, MapSpec, RegisterSpec};
use std::fmt::Write;

/// The Markdown text for a validated map.
pub fn generate(map: &MapSpec) -> String {
    let mut out = String::new();
    let version = map.version;
    let last_address = (1u32 << map.address_bits) - 1;
    // Writing to a String cannot fail; the `let _ =` are for that.
    let _ = writeln!(out, "# {} register map\n", map.name);
    out.push_str(
        "Generated from `hdl/registers.toml` by `make regmap`; do not edit. \
         (`make test` fails when this file is stale.)\n\n",
    );
    let _ = writeln!(
        out,
        "Map version {}.{}.{} (register VERSION). Registers are 32 bits wide at word \
         addresses 0x00..={last_address:#04x} ({} address bits). Unmapped addresses and \
         bits read 0 and ignore writes. An array register `NAME[i]` repeats: element i is \
         at its address + i * stride.\n",
        version.major, version.minor, version.patch, map.address_bits
    );

    out.push_str("## Access types\n\n| access | meaning |\n| --- | --- |\n");
    for access in Access::ALL {
        let _ = writeln!(out, "| {} | {} |", access.keyword(), access.meaning());
    }
    out.push_str(
        "\nThe reset column says what a read returns right after reset where the map fixes \
         it: the reset value of an rw field, the constant or the reset value of an ro \
         field that has one, 0 for a pulse field; - is a hardware value.\n\n",
    );

    out.push_str("## Address map\n\n| address | register | reset | description |\n| --- | --- | --- | --- |\n");
    for register in &map.registers {
        let reset = register.reset_word().map_or_else(|| "-".to_string(), |word| format!("{word:#010x}"));
        let _ = writeln!(
            out,
            "| {} | [{}](#{}) | {reset} | {} |",
            addresses(register),
            display_name(register),
            register.name.to_ascii_lowercase(),
            cell(&register.description)
        );
    }

    out.push_str("\n## Registers\n");
    for register in &map.registers {
        let _ = writeln!(out, "\n### {}\n", register.name);
        let _ = writeln!(out, "{}\n", register.description);
        let _ = write!(out, "Address {}", addresses(register));
        if let Some(word) = register.reset_word() {
            let _ = write!(out, "; reads {word:#010x} after reset");
        }
        out.push_str(".\n\n| bits | field | access | reset | description |\n| --- | --- | --- | --- | --- |\n");
        let mut fields: Vec<&FieldSpec> = register.fields.iter().collect();
        // Highest bits first, as a register diagram reads.
        fields.sort_by_key(|field| std::cmp::Reverse(field.lsb));
        for field in fields {
            let _ = writeln!(
                out,
                "| {} | {} | {} | {} | {} |",
                bit_range(field),
                field.name,
                field.access,
                field.value_after_reset().map_or_else(|| "-".to_string(), number),
                cell(&field.description)
            );
        }
    }
    out
}

/// `AXIS_MODE[i]` for an array, the plain name otherwise.
fn display_name(register: &RegisterSpec) -> String {
    match register.array {
        Some(_) => format!("{}\\[i\\]", register.name),
        None => register.name.clone(),
    }
}

/// `0x04`, or `0x20 + 4i (i = 0..7)` for an array.
fn addresses(register: &RegisterSpec) -> String {
    match register.array {
        None => format!("{:#04x}", register.address),
        Some(array) => {
            let step = if array.stride == 1 { "i".to_string() } else { format!("{}i", array.stride) };
            format!("{:#04x} + {step} (i = 0..{})", register.address, array.count - 1)
        }
    }
}

/// Small numbers in decimal, larger ones in decimal and hex.
fn number(value: u32) -> String {
    if value < 16 {
        value.to_string()
    } else {
        format!("{value} ({value:#x})")
    }
}

/// Text safe inside a table cell.
fn cell(text: &str) -> String {
    text.replace('|', "\\|")
}

#[cfg(test)]
mod tests {
    use super::{cell, number};

    #[test]
    fn table_cells_escape_the_column_separator() {
        assert_eq!(cell("a | b"), "a \\| b");
    }

    #[test]
    fn numbers_show_hex_once_it_helps() {
        assert_eq!(number(1), "1");
        assert_eq!(number(50_000), "50000 (0xc350)");
    }
}

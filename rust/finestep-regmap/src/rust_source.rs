//! The Rust source of the `finestep-interface` crate's `regs` module: one module per
//! register with its address, its fields as `Field` constants, their reset and fixed
//! values, and a table of the whole map. That crate's build script writes it to
//! `OUT_DIR/registers.rs`.
//!
//! The generated code names `crate::Field`, `crate::Access`, `crate::RegisterInfo`,
//! `crate::ArrayInfo` and `crate::FieldInfo`, the support types of that crate. Every
//! item carries the map's description as its doc comment.

use crate::spec::{bit_range, naming, Access, FieldSpec, MapSpec, RegisterSpec};
use std::fmt::Write;

/// The Rust source for a validated map.
pub fn generate(map: &MapSpec) -> String {
    let mut out = String::new();
    let version = map.version;
    // Writing to a String cannot fail; the `let _ =` are for that.
    out.push_str("// Generated from hdl/registers.toml by finestep-regmap; do not edit.\n\n");
    let _ = writeln!(out, "/// Name of the register map.");
    let _ = writeln!(out, "pub const MAP_NAME: &str = {:?};", map.name);
    let _ = writeln!(out, "/// Bits of a word address: every address is below `1 << ADDRESS_BITS`.");
    let _ = writeln!(out, "pub const ADDRESS_BITS: u32 = {};", map.address_bits);
    for (part, meaning, number) in [
        ("MAJOR", "incompatible changes", version.major),
        ("MINOR", "compatible additions", version.minor),
        ("PATCH", "fixes", version.patch),
    ] {
        let _ = writeln!(out, "/// Version of the register map, {part}: {meaning}.");
        let _ = writeln!(out, "pub const MAP_VERSION_{part}: u32 = {number};");
    }
    for register in &map.registers {
        register_module(&mut out, register);
    }
    register_table(&mut out, map);
    out
}

fn doc(out: &mut String, indent: &str, text: &str) {
    let _ = writeln!(out, "{indent}#[doc = {:?}]", escape_links(text));
}

/// The map's prose with `[` and `]` outside code spans escaped, so that rustdoc does not
/// take `RECORD_INC[index]` for a link.
fn escape_links(text: &str) -> String {
    let mut escaped = String::with_capacity(text.len());
    let mut in_code = false;
    for c in text.chars() {
        match c {
            '`' => in_code = !in_code,
            '[' | ']' if !in_code => escaped.push('\\'),
            _ => {}
        }
        escaped.push(c);
    }
    escaped
}

fn register_module(out: &mut String, register: &RegisterSpec) {
    let module = naming::rust_module(register);
    let name = &register.name;
    out.push('\n');
    doc(out, "", &register.description);
    doc(out, "", "");
    match register.array {
        None => doc(out, "", &format!("Register `{name}`, word address {:#04x}.", register.address)),
        Some(array) => doc(
            out,
            "",
            &format!(
                "Register array `{name}[i]`, i < {}, at word address {:#04x} + {} * i.",
                array.count, register.address, array.stride
            ),
        ),
    }
    let _ = writeln!(out, "pub mod {module} {{");
    let _ = writeln!(out, "    use crate::Field;\n");
    match register.array {
        None => {
            doc(out, "    ", &format!("Word address of `{name}`."));
            let _ = writeln!(out, "    pub const ADDR: u8 = {:#04x};", register.address);
        }
        Some(array) => {
            doc(out, "    ", &format!("Word address of `{name}[0]`."));
            let _ = writeln!(out, "    pub const ADDR: u8 = {:#04x};", register.address);
            doc(out, "    ", "Number of elements.");
            let _ = writeln!(out, "    pub const COUNT: usize = {};", array.count);
            doc(out, "    ", "Address distance between consecutive elements.");
            let _ = writeln!(out, "    pub const STRIDE: u8 = {};", array.stride);
            doc(out, "    ", &format!("Word address of `{name}[index]`."));
            doc(out, "    ", "");
            doc(out, "    ", "# Panics");
            doc(out, "    ", "");
            doc(out, "    ", "If `index >= COUNT`, like indexing a slice out of range.");
            let _ = writeln!(out, "    pub const fn addr(index: usize) -> u8 {{");
            let _ = writeln!(out, "        assert!(index < COUNT, \"{name} index out of range\");");
            // The map validation guarantees the last element's address fits in a u8.
            let _ = writeln!(out, "        ADDR + index as u8 * STRIDE");
            let _ = writeln!(out, "    }}");
        }
    }
    for field in &register.fields {
        field_items(out, field);
    }
    if let Some(word) = register.reset_word() {
        out.push('\n');
        doc(
            out,
            "    ",
            &format!(
                "The word {name} reads right after reset ({word:#010x}): every field at its \
                 reset or fixed value, pulse fields and unmapped bits 0."
            ),
        );
        let _ = writeln!(out, "    pub const fn reset_word() -> u32 {{");
        let _ = writeln!(out, "        {word:#010x}");
        let _ = writeln!(out, "    }}");
    }
    let _ = writeln!(out, "}}");
}

fn field_items(out: &mut String, field: &FieldSpec) {
    let name = &field.name;
    out.push('\n');
    doc(out, "    ", &field.description);
    doc(out, "    ", "");
    let bits = if field.width == 1 { "Bit" } else { "Bits" };
    let mut summary = format!("{bits} {}, {}", bit_range(field), field.access);
    if let Some(reset) = field.reset {
        let _ = write!(summary, ", reset {reset}");
    }
    if let Some(value) = field.value {
        let _ = write!(summary, ", always {value:#x}");
    }
    summary.push('.');
    doc(out, "    ", &summary);
    let _ = writeln!(out, "    pub const {name}: Field = Field {{ lsb: {}, width: {} }};", field.lsb, field.width);
    if let Some(reset) = field.reset {
        let _ = writeln!(out, "    /// Value of [`{name}`] after reset.");
        let _ = writeln!(out, "    pub const {}: u32 = {reset:#x};", naming::rust_reset(field));
    }
    if let Some(value) = field.value {
        let _ = writeln!(out, "    /// The value [`{name}`] always reads.");
        let _ = writeln!(out, "    pub const {}: u32 = {value:#x};", naming::rust_value(field));
    }
}

fn register_table(out: &mut String, map: &MapSpec) {
    out.push('\n');
    doc(
        out,
        "",
        "Every register in map order, as data, for code that walks the whole map \
         (register dumps, tests that cover every field).",
    );
    let _ = writeln!(out, "pub static REGISTERS: &[crate::RegisterInfo] = &[");
    for register in &map.registers {
        let module = naming::rust_module(register);
        let _ = writeln!(out, "    crate::RegisterInfo {{");
        let _ = writeln!(out, "        name: {:?},", register.name);
        let _ = writeln!(out, "        addr: {module}::ADDR,");
        match register.array {
            None => {
                let _ = writeln!(out, "        array: None,");
            }
            Some(_) => {
                let _ = writeln!(
                    out,
                    "        array: Some(crate::ArrayInfo {{ count: {module}::COUNT, stride: {module}::STRIDE }}),"
                );
            }
        }
        let _ = writeln!(out, "        description: {:?},", register.description);
        let _ = writeln!(out, "        fields: &[");
        for field in &register.fields {
            let name = &field.name;
            let reset = match field.reset {
                Some(_) => format!("Some({module}::{})", naming::rust_reset(field)),
                None => "None".to_string(),
            };
            let value = match field.value {
                Some(_) => format!("Some({module}::{})", naming::rust_value(field)),
                None => "None".to_string(),
            };
            let _ = writeln!(
                out,
                "            crate::FieldInfo {{ name: {name:?}, field: {module}::{name}, access: {}, reset: {reset}, value: {value}, description: {:?} }},",
                access_path(field.access),
                field.description
            );
        }
        let _ = writeln!(out, "        ],");
        let reset_word = match register.reset_word() {
            Some(_) => format!("Some({module}::reset_word())"),
            None => "None".to_string(),
        };
        let _ = writeln!(out, "        reset_word: {reset_word},");
        let _ = writeln!(out, "    }},");
    }
    let _ = writeln!(out, "];");
}

fn access_path(access: Access) -> &'static str {
    match access {
        Access::ReadOnly => "crate::Access::ReadOnly",
        Access::ReadWrite => "crate::Access::ReadWrite",
        Access::Pulse => "crate::Access::Pulse",
        Access::WriteOnly => "crate::Access::WriteOnly",
        Access::WriteOneToClear => "crate::Access::WriteOneToClear",
    }
}

#[cfg(test)]
mod tests {
    use super::escape_links;

    #[test]
    fn brackets_are_escaped_outside_code_spans_only() {
        assert_eq!(escape_links("RECORD_INC[i]"), "RECORD_INC\\[i\\]");
        assert_eq!(escape_links("`a[0]` b[1]"), "`a[0]` b\\[1\\]");
    }
}

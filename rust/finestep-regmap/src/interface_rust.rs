//! The Rust source of the `finestep-interface` crate's generated items: its build script
//! writes [`generate`]'s output to `OUT_DIR/interface.rs` (included at the crate root)
//! beside [`crate::rust_source`]'s `registers.rs` (the `regs` module).
//!
//! The generated code names the crate's hand-written support types: `crate::Field`,
//! `crate::ParamRange`, `crate::TimingField` and `crate::regs`. Every item carries the
//! description's prose as its doc comment.

use crate::interface::{CodeSpec, EnumSpec, InterfaceSpec};
use crate::spec::{low_bits, Access};
use std::fmt::Write;

fn doc(out: &mut String, indent: &str, text: &str) {
    let _ = writeln!(out, "{indent}#[doc = {:?}]", text.replace('[', "\\[").replace(']', "\\]"));
}

/// `STEP_DIR` -> `StepDir`, `X100` -> `X100`.
pub fn camel(name: &str) -> String {
    name.split('_')
        .map(|part| {
            let mut chars = part.chars();
            match chars.next() {
                Some(first) => first.to_ascii_uppercase().to_string() + &chars.as_str().to_ascii_lowercase(),
                None => String::new(),
            }
        })
        .collect()
}

fn access_variant(access: Access) -> &'static str {
    match access {
        Access::ReadOnly => "ReadOnly",
        Access::ReadWrite => "ReadWrite",
        Access::Pulse => "Pulse",
        Access::WriteOnly => "WriteOnly",
        Access::WriteOneToClear => "WriteOneToClear",
    }
}

/// The Rust type holding a value of `width` bits.
fn uint(width: u32) -> &'static str {
    match width {
        0..=8 => "u8",
        9..=16 => "u16",
        _ => "u32",
    }
}

/// The generated source.
pub fn generate(spec: &InterfaceSpec) -> String {
    let mut out = String::new();
    // Writing to a String cannot fail; the `let _ =` are for that.
    out.push_str("// Generated from hdl/interface.toml and hdl/registers.toml by finestep-regmap; do not edit.\n\n");
    access(&mut out);
    record(&mut out, spec);
    spi(&mut out, spec);
    for enumeration in &spec.enums {
        enumeration_items(&mut out, enumeration);
    }
    for bitset in &spec.bitsets {
        out.push('\n');
        doc(&mut out, "", &bitset.description);
        let _ = writeln!(out, "pub mod {} {{", bitset.name.to_ascii_lowercase());
        doc(&mut out, "    ", "Bits of the vector.");
        let _ = writeln!(out, "    pub const WIDTH: u32 = {};", bitset.width);
        for bit in &bitset.bits {
            let field = bit.field.as_ref().map_or_else(String::new, |f| format!(" (register field `{}`)", f.path()));
            doc(&mut out, "    ", &format!("Bit {}: {}{field}.", bit.bit, bit.description));
            let _ = writeln!(out, "    pub const {}: u8 = 1 << {};", bit.name, bit.bit);
            doc(&mut out, "    ", &format!("Position of [`{}`].", bit.name));
            let _ = writeln!(out, "    pub const {}_BIT: u32 = {};", bit.name, bit.bit);
        }
        let all = bitset.bits.iter().fold(0u32, |all, bit| all | 1 << bit.bit);
        doc(&mut out, "    ", "Every named bit.");
        let _ = writeln!(out, "    pub const ALL: u8 = {all:#04x};");
        let _ = writeln!(out, "}}");
    }
    pbp_lanes(&mut out, spec);
    params(&mut out, spec);
    timing(&mut out, spec);
    out
}

/// The `pbp_lanes` module: where each field of a record with the flag PBP lies.
fn pbp_lanes(out: &mut String, spec: &InterfaceSpec) {
    let pbp = &spec.pbp;
    out.push('\n');
    doc(out, "", &format!("The lanes of a record with the flag PBP: {}", pbp.description));
    let _ = writeln!(out, "pub mod pbp_lanes {{");
    doc(out, "    ", &format!("The lane of the bit set `{}`.", pbp.bits.name));
    let _ = writeln!(out, "    pub const BITS_LANE: usize = {};", pbp.bits.lane);
    doc(out, "    ", &format!("The lane bit of the bit set `{}`'s bit 0.", pbp.bits.name));
    let _ = writeln!(out, "    pub const BITS_LSB: u32 = {};", pbp.bits.lsb);
    for field in pbp.fields() {
        doc(out, "    ", &format!("The lane of `{}`: {}", field.name, field.description));
        let _ = writeln!(out, "    pub const {}_LANE: usize = {};", field.name, field.lane);
        doc(out, "    ", &format!("The lowest lane bit of `{}`.", field.name));
        let _ = writeln!(out, "    pub const {}_LSB: u32 = {};", field.name, field.lsb);
        doc(out, "    ", &format!("The bits of `{}`.", field.name));
        let _ = writeln!(out, "    pub const {}_WIDTH: u32 = {};", field.name, field.width);
    }
    let _ = writeln!(out, "}}");
}

fn access(out: &mut String) {
    doc(out, "", "How the host may access a register field (the legend of `hdl/registers.toml`).");
    let _ = writeln!(out, "#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]\npub enum Access {{");
    for access in Access::ALL {
        doc(out, "    ", &format!("`{}`: {}.", access.keyword(), access.meaning()));
        let _ = writeln!(out, "    {},", access_variant(access));
    }
    let _ = writeln!(out, "}}\n\nimpl Access {{");
    doc(out, "    ", "Every access type, in the order of the legend.");
    let list: Vec<String> = Access::ALL.iter().map(|a| format!("Access::{}", access_variant(*a))).collect();
    let _ = writeln!(out, "    pub const ALL: [Access; {}] = [{}];", list.len(), list.join(", "));
    doc(out, "    ", "The keyword of the map file (`ro`, `rw`, ...).");
    let _ = writeln!(out, "    pub const fn keyword(self) -> &'static str {{\n        match self {{");
    for access in Access::ALL {
        let _ = writeln!(out, "            Access::{} => {:?},", access_variant(access), access.keyword());
    }
    let _ = writeln!(out, "        }}\n    }}\n}}");
}

fn record(out: &mut String, spec: &InterfaceSpec) {
    let record = &spec.record;
    out.push('\n');
    doc(out, "", &format!("The most axes a core can have and a record holds (`{}`).", record.max_axes.expression));
    let _ = writeln!(out, "pub const MAX_AXES: usize = {};", record.max_axes.value);
    out.push('\n');
    doc(out, "", "Layout of the period record: axis i's increment, then the flags.");
    let _ = writeln!(out, "pub mod record_layout {{");
    let increment = &record.increment;
    for (name, text, value) in [
        (
            "INC_WIDTH",
            format!("Bits of one increment (`{}`): {}.", increment.field.path(), increment.description),
            increment.width(),
        ),
        ("INC_INT_BITS", "Integer bits of an increment, sign included.".to_string(), increment.int_bits),
        ("INC_FRAC_BITS", "Fraction bits of an increment.".to_string(), increment.frac_bits),
        ("FLAGS_WIDTH", format!("Bits of the flags (`{}`).", record.flags_field.path()), record.flags_width()),
    ] {
        doc(out, "    ", &text);
        let _ = writeln!(out, "    pub const {name}: u32 = {value};");
    }
    let _ = writeln!(out, "}}\n");
    doc(out, "", "Bits of a period record's flags; the others are reserved and ignored.");
    let _ = writeln!(out, "pub mod flags {{");
    for flag in &record.flags {
        doc(out, "    ", &format!("Bit {}: {}.", flag.bit, flag.description));
        let _ = writeln!(out, "    pub const {}: u8 = 1 << {};", flag.name, flag.bit);
        doc(out, "    ", &format!("Position of [`{}`].", flag.name));
        let _ = writeln!(out, "    pub const {}_BIT: u32 = {};", flag.name, flag.bit);
    }
    let all = record.flags.iter().fold(0u32, |all, flag| all | 1 << flag.bit);
    doc(out, "    ", "Every defined flag.");
    let _ = writeln!(out, "    pub const ALL: u8 = {all:#04x};\n}}");
}

fn code_enum(out: &mut String, indent: &str, name: &str, what: &str, codes: &[CodeSpec]) {
    doc(out, indent, what);
    let _ = writeln!(
        out,
        "{indent}#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]\n{indent}#[repr(u8)]\n{indent}pub enum {name} {{"
    );
    for code in codes {
        doc(out, &format!("{indent}    "), &format!("{:#04x}: {}.", code.code, code.description));
        let _ = writeln!(out, "{indent}    {} = {:#04x},", camel(&code.name), code.code);
    }
    let _ = writeln!(out, "{indent}}}\n\n{indent}impl {name} {{");
    let list: Vec<String> = codes.iter().map(|c| format!("{name}::{}", camel(&c.name))).collect();
    doc(out, &format!("{indent}    "), "Every code, in the order of the description.");
    let _ = writeln!(out, "{indent}    pub const ALL: [{name}; {}] = [{}];", list.len(), list.join(", "));
    doc(out, &format!("{indent}    "), "The byte on the wire.");
    let _ = writeln!(out, "{indent}    pub const fn code(self) -> u8 {{\n{indent}        self as u8\n{indent}    }}");
    doc(out, &format!("{indent}    "), "The code of `byte`, if it is one.");
    let _ = writeln!(
        out,
        "{indent}    pub const fn from_code(byte: u8) -> Option<{name}> {{\n{indent}        match byte {{"
    );
    for code in codes {
        let _ = writeln!(out, "{indent}            {:#04x} => Some({name}::{}),", code.code, camel(&code.name));
    }
    let _ = writeln!(out, "{indent}            _ => None,\n{indent}        }}\n{indent}    }}");
    doc(out, &format!("{indent}    "), "The name in the interface description.");
    let _ = writeln!(out, "{indent}    pub const fn name(self) -> &'static str {{\n{indent}        match self {{");
    for code in codes {
        let _ = writeln!(out, "{indent}            {name}::{} => {:?},", camel(&code.name), code.name);
    }
    let _ = writeln!(out, "{indent}        }}\n{indent}    }}\n{indent}}}");
}

fn spi(out: &mut String, spec: &InterfaceSpec) {
    let spi = &spec.spi;
    out.push('\n');
    doc(out, "", "The SPI frame layer: every frame is `command, address, count`, then data.");
    let _ = writeln!(out, "pub mod spi {{");
    doc(out, "    ", "Most words of a READ frame and records of a FIFO frame (the count is one byte).");
    let _ = writeln!(out, "    pub const MAX_COUNT: usize = {};", spi.max_count);
    let crc_type = uint(spi.crc.width);
    doc(out, "    ", &format!("The frames' CRC: {}, {}.", spi.crc.name, spi.crc.description));
    let _ = writeln!(out, "    pub const CRC_NAME: &str = {:?};", spi.crc.name);
    doc(out, "    ", "Bits of the CRC.");
    let _ = writeln!(out, "    pub const CRC_WIDTH: u32 = {};", spi.crc.width);
    doc(out, "    ", "The CRC's generator polynomial (MSB first, top bit implied).");
    let _ = writeln!(out, "    pub const CRC_POLYNOMIAL: {crc_type} = {:#06x};", spi.crc.polynomial);
    doc(out, "    ", "The CRC register at the start of a frame.");
    let _ = writeln!(out, "    pub const CRC_INITIAL: {crc_type} = {:#06x};", spi.crc.initial);
    for (module, what, codes) in [
        ("command", "Command bytes (the first byte of a frame).", &spi.commands),
        ("result", "Result bytes of WRITE and FIFO frames, and of every rejected frame.", &spi.results),
    ] {
        out.push('\n');
        doc(out, "    ", what);
        let _ = writeln!(out, "    pub mod {module} {{");
        for code in codes {
            doc(out, "        ", &code.description);
            let _ = writeln!(out, "        pub const {}: u8 = {:#04x};", code.name, code.code);
        }
        let _ = writeln!(out, "    }}");
    }
    out.push('\n');
    code_enum(out, "    ", "Command", "A frame's command byte.", &spi.commands);
    out.push('\n');
    code_enum(
        out,
        "    ",
        "ResultCode",
        "The result byte a WRITE or FIFO frame (or a rejected frame) answers with.",
        &spi.results,
    );
    let _ = writeln!(out, "}}");
}

fn enumeration_items(out: &mut String, enumeration: &EnumSpec) {
    let name = camel(&enumeration.name);
    let module = enumeration.name.to_ascii_lowercase();
    let width = enumeration.width();
    let field_path = enumeration.field.path();
    out.push('\n');
    doc(out, "", &format!("{} Values of `{field_path}` as numbers; see [`{name}`].", enumeration.description));
    let _ = writeln!(out, "pub mod {module} {{");
    doc(out, "    ", &format!("Bits of `{field_path}`."));
    let _ = writeln!(out, "    pub const WIDTH: u32 = {width};");
    for value in &enumeration.values {
        doc(out, "    ", &value.description);
        let _ = writeln!(out, "    pub const {}: u8 = {};", value.name, value.value);
    }
    let _ = writeln!(out, "}}\n");
    let mut text = format!("{} (`{field_path}`).", enumeration.description);
    if let Some(otherwise) = &enumeration.otherwise {
        let _ = write!(text, " Field values not listed act as `{}`.", camel(otherwise));
    }
    doc(out, "", &text);
    let default = enumeration.reset_value().unwrap_or(&enumeration.values[0]).name.clone();
    let _ =
        writeln!(out, "#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]\n#[repr(u8)]\npub enum {name} {{");
    for value in &enumeration.values {
        let mut text = format!("{}: {}", value.value, value.description);
        if value.name == default {
            text.push_str(" (the default: the field's reset value)");
        }
        doc(out, "    ", &text);
        if value.name == default {
            let _ = writeln!(out, "    #[default]");
        }
        let _ = writeln!(out, "    {} = {},", camel(&value.name), value.value);
    }
    let _ = writeln!(out, "}}\n\nimpl {name} {{");
    let list: Vec<String> = enumeration.values.iter().map(|v| format!("{name}::{}", camel(&v.name))).collect();
    doc(out, "    ", "Every value, in the order of the description.");
    let _ = writeln!(out, "    pub const ALL: [{name}; {}] = [{}];", list.len(), list.join(", "));
    doc(out, "    ", "The register field that holds a value.");
    let _ = writeln!(
        out,
        "    pub const FIELD: crate::Field = crate::regs::{}::{};",
        enumeration.field.register.to_ascii_lowercase(),
        enumeration.field.field
    );
    doc(out, "    ", "The field value.");
    let _ = writeln!(out, "    pub const fn bits(self) -> u8 {{\n        self as u8\n    }}");
    doc(out, "    ", "The value a field value acts as (only the field's bits are looked at).");
    let _ = writeln!(
        out,
        "    pub const fn from_bits(bits: u32) -> {name} {{\n        match bits & {:#x} {{",
        low_bits(width)
    );
    // A complete enum's last value takes the wildcard arm; otherwise `otherwise` does.
    let (listed, fallback) = match &enumeration.otherwise {
        Some(otherwise) => (&enumeration.values[..], otherwise.as_str()),
        None => {
            let (last, listed) = enumeration.values.split_last().expect("validated: at least one value");
            (listed, last.name.as_str())
        }
    };
    for value in listed {
        let _ = writeln!(out, "            {} => {name}::{},", value.value, camel(&value.name));
    }
    let _ = writeln!(out, "            _ => {name}::{},", camel(fallback));
    let _ = writeln!(out, "        }}\n    }}");
    doc(out, "    ", "The name in the interface description.");
    let _ = writeln!(out, "    pub const fn name(self) -> &'static str {{\n        match self {{");
    for value in &enumeration.values {
        let _ = writeln!(out, "            {name}::{} => {:?},", camel(&value.name), value.name);
    }
    let _ = writeln!(out, "        }}\n    }}");
    if enumeration.has_factors() {
        doc(out, "    ", "The number the value stands for.");
        let _ = writeln!(out, "    pub const fn factor(self) -> u32 {{\n        match self {{");
        for value in &enumeration.values {
            let _ = writeln!(out, "            {name}::{} => {},", camel(&value.name), value.factor.unwrap_or(1));
        }
        let _ = writeln!(out, "        }}\n    }}");
    }
    let _ = writeln!(out, "}}");
}

fn params(out: &mut String, spec: &InterfaceSpec) {
    out.push('\n');
    doc(out, "", "Build parameters of each module with their defaults and legal ranges.");
    let _ = writeln!(out, "pub mod params {{");
    for module in &spec.modules {
        doc(out, "    ", &module.description);
        let _ = writeln!(out, "    pub mod {} {{", module.name);
        let _ = writeln!(out, "        use crate::ParamRange;\n");
        for parameter in &module.parameters {
            let mut text = format!("`{}`: {}.", parameter.name, parameter.description);
            if parameter.max.is_derived() {
                let _ = write!(text, " Its maximum is `{}`.", parameter.max.expression);
            }
            doc(out, "        ", &text);
            let _ = writeln!(
                out,
                "        pub const {}: ParamRange = ParamRange {{ module: {:?}, name: {:?}, default: {}, min: {}, max: {} }};",
                parameter.name, module.name, parameter.name, parameter.default, parameter.min.value, parameter.max.value
            );
        }
        doc(out, "        ", "Every parameter, in the order of the description.");
        let names: Vec<&str> = module.parameters.iter().map(|p| p.name.as_str()).collect();
        let _ = writeln!(out, "        pub const ALL: [ParamRange; {}] = [{}];", names.len(), names.join(", "));
        let _ = writeln!(out, "    }}");
    }
    let _ = writeln!(out, "}}");
}

fn timing(out: &mut String, spec: &InterfaceSpec) {
    let n = spec.timing.len();
    out.push('\n');
    doc(out, "", "The drive timing of one axis, in clocks: what the step shaper keeps between pin edges.");
    doc(out, "", "");
    doc(out, "", "The core uses the low `TIMING_W` bits of each field ([`DriveTiming::masked`]).");
    let _ = writeln!(out, "#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]\npub struct DriveTiming {{");
    for field in &spec.timing {
        doc(
            out,
            "    ",
            &format!("`{}`: {} (register field `{}`).", field.symbol, field.description, field.field.path()),
        );
        let _ = writeln!(out, "    pub {}: u32,", field.name.to_ascii_lowercase());
    }
    let _ = writeln!(out, "}}\n\nimpl DriveTiming {{");
    doc(out, "    ", "Number of fields.");
    let _ = writeln!(out, "    pub const COUNT: usize = {n};");
    doc(out, "    ", "The fields in declaration order: names, symbols and register fields.");
    let _ = writeln!(out, "    pub const FIELDS: [crate::TimingField; {n}] = [");
    for field in &spec.timing {
        let module = field.field.register.to_ascii_lowercase();
        let _ = writeln!(
            out,
            "        crate::TimingField {{ name: {:?}, symbol: {:?}, register: {:?}, field: crate::regs::{module}::{}, addr: crate::regs::{module}::addr, reset: crate::regs::{module}::{}_RESET }},",
            field.name.to_ascii_lowercase(),
            field.symbol,
            field.field.register,
            field.field.field,
            field.field.field
        );
    }
    let _ = writeln!(out, "    ];");
    doc(out, "    ", "The values in the order of [`Self::FIELDS`].");
    let names: Vec<String> = spec.timing.iter().map(|f| format!("self.{}", f.name.to_ascii_lowercase())).collect();
    let _ = writeln!(out, "    pub const fn to_array(&self) -> [u32; {n}] {{\n        [{}]\n    }}", names.join(", "));
    doc(out, "    ", "The timing from values in the order of [`Self::FIELDS`].");
    let assigns: Vec<String> =
        spec.timing.iter().enumerate().map(|(i, f)| format!("{}: values[{i}]", f.name.to_ascii_lowercase())).collect();
    let _ = writeln!(
        out,
        "    pub const fn from_array(values: [u32; {n}]) -> DriveTiming {{\n        DriveTiming {{ {} }}\n    }}",
        assigns.join(", ")
    );
    doc(out, "    ", "Positional constructor, in the order of [`Self::FIELDS`].");
    let args: Vec<String> = spec.timing.iter().map(|f| format!("{}: u32", f.name.to_ascii_lowercase())).collect();
    let fields: Vec<String> = spec.timing.iter().map(|f| f.name.to_ascii_lowercase()).collect();
    let _ = writeln!(
        out,
        "    pub const fn new({}) -> DriveTiming {{\n        DriveTiming {{ {} }}\n    }}",
        args.join(", "),
        fields.join(", ")
    );
    let _ = writeln!(out, "}}");
}

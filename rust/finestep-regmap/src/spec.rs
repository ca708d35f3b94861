//! The register map as typed, validated data: `hdl/registers.toml` parsed with serde and
//! checked, so every generator can trust it.
//!
//! Parsing happens in two steps. serde reads the file into loosely typed `Raw*`
//! structs (integers as `i64`, access as a string), which rejects unknown keys and
//! malformed TOML with toml's line/column messages. Then [`parse`] checks every rule
//! and reports every broken one, each naming its register and field ([`Problem`]),
//! instead of stopping at the first or letting serde say "expected u32".

use serde::Deserialize;
use std::collections::{BTreeMap, HashSet};
use std::fmt;
use std::path::{Path, PathBuf};

/// Registers are this wide; fields must lie within.
pub const WORD_BITS: u32 = 32;

/// The widest address the map may use: the Rust constants hold addresses in a `u8`.
pub const MAX_ADDRESS_BITS: u32 = 8;

/// How the host may access a field. The meanings are those of the header comment of
/// `hdl/registers.toml`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Access {
    /// `ro`: read-only, a hardware value (with a `reset`, what it reads out of reset until
    /// the hardware changes it).
    ReadOnly,
    /// `rw`: read/write, holds what the host wrote; has a reset value.
    ReadWrite,
    /// `pulse`: write-only; writing 1 acts once, writing 0 does nothing; reads 0.
    Pulse,
    /// `wo`: write-only data; every write acts once with the value written; reads 0.
    WriteOnly,
    /// `w1c`: set by hardware (sticky), cleared by writing 1; reads the flag.
    WriteOneToClear,
}

impl Access {
    /// Every access type, in the order the legend lists them.
    pub const ALL: [Access; 5] =
        [Access::ReadOnly, Access::ReadWrite, Access::Pulse, Access::WriteOnly, Access::WriteOneToClear];

    /// The keyword the map file uses (`ro`, `rw`, `pulse`, `wo`, `w1c`).
    pub const fn keyword(self) -> &'static str {
        match self {
            Access::ReadOnly => "ro",
            Access::ReadWrite => "rw",
            Access::Pulse => "pulse",
            Access::WriteOnly => "wo",
            Access::WriteOneToClear => "w1c",
        }
    }

    /// One line saying what the access type means, for the legend in the docs.
    pub const fn meaning(self) -> &'static str {
        match self {
            Access::ReadOnly => {
                "read-only, a hardware value; a reset column, where given, is what it reads out of reset"
            }
            Access::ReadWrite => "read/write, holds what the host wrote; the reset column is its value after reset",
            Access::Pulse => "write-only: writing 1 acts once, writing 0 does nothing; reads 0",
            Access::WriteOnly => "write-only data: every write acts once with the value written; reads 0",
            Access::WriteOneToClear => "set by hardware (sticky), cleared by writing 1; reads the flag",
        }
    }

    /// The access type for a map keyword, or `None` for an unknown one.
    pub fn from_keyword(keyword: &str) -> Option<Access> {
        Access::ALL.into_iter().find(|access| access.keyword() == keyword)
    }
}

impl fmt::Display for Access {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.keyword())
    }
}

/// The whole validated register map.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MapSpec {
    /// The map's name (`finestep`).
    pub name: String,
    /// Width of a word address; every register lies below `1 << address_bits`.
    pub address_bits: u32,
    /// Version of the map, also readable from the VERSION register.
    pub version: MapVersion,
    /// The registers in file order.
    pub registers: Vec<RegisterSpec>,
}

/// Semantic version of the register map.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MapVersion {
    /// Incompatible changes.
    pub major: u32,
    /// Compatible additions.
    pub minor: u32,
    /// Fixes that change no address, bit or reset value.
    pub patch: u32,
}

/// One register, or one array of identical registers.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RegisterSpec {
    /// UPPER_SNAKE name, unique in the map.
    pub name: String,
    /// Word address (of element 0 for an array).
    pub address: u32,
    /// Present when the register repeats.
    pub array: Option<ArraySpec>,
    /// One line of prose.
    pub description: String,
    /// The fields, in file order; they do not overlap.
    pub fields: Vec<FieldSpec>,
}

/// How an array register repeats: element `i` is at `address + i * stride`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ArraySpec {
    /// Number of elements, at least 1.
    pub count: u32,
    /// Address distance between elements, at least 1.
    pub stride: u32,
}

/// One bit field of a register.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FieldSpec {
    /// UPPER_SNAKE name, unique in its register.
    pub name: String,
    /// Lowest bit.
    pub lsb: u32,
    /// Number of bits, at least 1; `lsb + width <= 32`.
    pub width: u32,
    /// How the host may access it.
    pub access: Access,
    /// Value after reset: present for every `rw` field, and for an `ro` field whose
    /// hardware value out of reset the map fixes (it reads this until the hardware
    /// changes it).
    pub reset: Option<u32>,
    /// Constant value of an `ro` field that the map fixes (such as the ID magic).
    pub value: Option<u32>,
    /// One line of prose.
    pub description: String,
}

impl FieldSpec {
    /// Highest bit.
    pub fn msb(&self) -> u32 {
        self.lsb + self.width - 1
    }

    /// The field's bits in place within the word.
    pub fn mask(&self) -> u32 {
        low_bits(self.width) << self.lsb
    }

    /// What a read returns right after reset, when the map fixes it: the reset value of
    /// an `rw` field, the `value` or `reset` of an `ro` field, 0 for a `pulse` or `wo`
    /// field. `None` for a hardware value (`ro` with neither, `w1c`).
    pub fn value_after_reset(&self) -> Option<u32> {
        match self.access {
            Access::ReadWrite => self.reset,
            Access::ReadOnly => self.value.or(self.reset),
            Access::Pulse | Access::WriteOnly => Some(0),
            Access::WriteOneToClear => None,
        }
    }
}

impl RegisterSpec {
    /// Number of elements: the array count, or 1.
    pub fn count(&self) -> u32 {
        self.array.map_or(1, |array| array.count)
    }

    /// Address of every element, in index order.
    pub fn addresses(&self) -> impl Iterator<Item = u32> + '_ {
        let stride = self.array.map_or(0, |array| array.stride);
        (0..self.count()).map(move |index| self.address + index * stride)
    }

    /// The word a read returns right after reset, when the map fixes every field's
    /// value then (see [`FieldSpec::value_after_reset`]); unmapped bits read 0.
    /// `None` when some field is a hardware value.
    pub fn reset_word(&self) -> Option<u32> {
        self.fields.iter().try_fold(0, |word, field| field.value_after_reset().map(|value| word | (value << field.lsb)))
    }

    /// Whether some field is `rw`.
    pub fn has_writable_state(&self) -> bool {
        self.fields.iter().any(|field| field.access == Access::ReadWrite)
    }
}

/// `width` ones in the low bits (`width` at most 32).
pub fn low_bits(width: u32) -> u32 {
    if width >= WORD_BITS {
        u32::MAX
    } else {
        (1 << width) - 1
    }
}

/// The names the generators give to each piece of the map. They live here so that
/// validation can reject a map whose generated names would collide.
pub mod naming {
    use super::{FieldSpec, MapSpec, Place, RegisterSpec};

    /// Prefix of every Verilog constant.
    pub const VERILOG_PREFIX: &str = "FS_";

    /// Verilog constant holding the address width.
    pub const VERILOG_ADDR_WIDTH: &str = "FS_ADDR_WIDTH";

    /// Verilog constant for one part (`MAJOR`, `MINOR`, `PATCH`) of the map version.
    pub fn verilog_map_version(part: &str) -> String {
        format!("{VERILOG_PREFIX}MAP_VERSION_{part}")
    }

    /// Verilog constant for a register-level item: `FS_<REG>_<WHAT>` (`ADDR`, `COUNT`,
    /// `STRIDE`).
    pub fn verilog_register(register: &RegisterSpec, what: &str) -> String {
        format!("{VERILOG_PREFIX}{}_{what}", register.name)
    }

    /// Verilog constant for a field-level item: `FS_<REG>_<FIELD>_<WHAT>` (`LSB`,
    /// `WIDTH`, `RESET`, `VALUE`).
    pub fn verilog_field(register: &RegisterSpec, field: &FieldSpec, what: &str) -> String {
        format!("{VERILOG_PREFIX}{}_{}_{what}", register.name, field.name)
    }

    /// Every Verilog constant the map generates, with the place it belongs to, in the
    /// order the header declares them.
    pub fn verilog_constants(map: &MapSpec) -> Vec<(String, Place)> {
        let mut names = vec![
            (VERILOG_ADDR_WIDTH.to_string(), Place::Map),
            (verilog_map_version("MAJOR"), Place::Map),
            (verilog_map_version("MINOR"), Place::Map),
            (verilog_map_version("PATCH"), Place::Map),
        ];
        for register in &map.registers {
            let owner = Place::register(&register.name);
            names.push((verilog_register(register, "ADDR"), owner.clone()));
            if register.array.is_some() {
                names.push((verilog_register(register, "COUNT"), owner.clone()));
                names.push((verilog_register(register, "STRIDE"), owner));
            }
            for field in &register.fields {
                let owner = Place::field(&register.name, &field.name);
                names.push((verilog_field(register, field, "LSB"), owner.clone()));
                names.push((verilog_field(register, field, "WIDTH"), owner.clone()));
                if field.reset.is_some() {
                    names.push((verilog_field(register, field, "RESET"), owner.clone()));
                }
                if field.value.is_some() {
                    names.push((verilog_field(register, field, "VALUE"), owner));
                }
            }
        }
        names
    }

    /// The Rust module of a register: its name in lower case (`axis_timing_a`).
    pub fn rust_module(register: &RegisterSpec) -> String {
        register.name.to_ascii_lowercase()
    }

    /// The Rust constant holding a field's reset value: `<FIELD>_RESET`.
    pub fn rust_reset(field: &FieldSpec) -> String {
        format!("{}_RESET", field.name)
    }

    /// The Rust constant holding an `ro` field's fixed value: `<FIELD>_VALUE`.
    pub fn rust_value(field: &FieldSpec) -> String {
        format!("{}_VALUE", field.name)
    }

    /// Every constant in a register's Rust module, with the field it belongs to.
    pub fn rust_constants(register: &RegisterSpec) -> Vec<(String, Option<&str>)> {
        let mut names: Vec<(String, Option<&str>)> = vec![("ADDR".to_string(), None)];
        if register.array.is_some() {
            names.push(("COUNT".to_string(), None));
            names.push(("STRIDE".to_string(), None));
        }
        for field in &register.fields {
            let owner = Some(field.name.as_str());
            names.push((field.name.clone(), owner));
            if field.reset.is_some() {
                names.push((rust_reset(field), owner));
            }
            if field.value.is_some() {
                names.push((rust_value(field), owner));
            }
        }
        names
    }
}

/// Where in the map a problem is.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Place {
    /// The top-level keys (`name`, `address_bits`, `version`).
    Map,
    /// A register as a whole.
    Register(String),
    /// One field of a register.
    Field(String, String),
    /// A part of the interface description (`hdl/interface.toml`), in words
    /// (`enum OUT_MODE`, `module finestep_top, parameter N_AXES`).
    Interface(String),
}

impl Place {
    /// The place of field `field` of register `register`.
    pub fn field(register: &str, field: &str) -> Place {
        Place::Field(register.to_string(), field.to_string())
    }

    /// The place of register `register`.
    pub fn register(register: &str) -> Place {
        Place::Register(register.to_string())
    }
}

impl fmt::Display for Place {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Place::Map => f.write_str("map"),
            Place::Register(register) => write!(f, "register {register}"),
            Place::Field(register, field) => write!(f, "register {register}, field {field}"),
            Place::Interface(part) => f.write_str(part),
        }
    }
}

/// One broken rule.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Problem {
    /// Which register or field.
    pub place: Place,
    /// What is wrong, in words.
    pub message: String,
}

impl fmt::Display for Problem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.place, self.message)
    }
}

/// Why a map could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum SpecError {
    /// The file could not be read.
    #[error("cannot read {}: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// Not TOML, or keys missing, unknown or of the wrong type.
    #[error("{origin}: {source}")]
    Syntax {
        /// The file name, for the message.
        origin: String,
        /// toml's error, with line and column.
        source: toml::de::Error,
    },
    /// Well-formed TOML that breaks the map's rules; every broken rule is listed.
    #[error("{origin}: invalid register map:{}", list(problems))]
    Invalid {
        /// The file name, for the message.
        origin: String,
        /// Every broken rule, in file order.
        problems: Vec<Problem>,
    },
}

impl SpecError {
    /// The broken rules, if the map was well-formed TOML but invalid.
    pub fn problems(&self) -> &[Problem] {
        match self {
            SpecError::Invalid { problems, .. } => problems,
            _ => &[],
        }
    }
}

fn list(problems: &[Problem]) -> String {
    problems.iter().map(|problem| format!("\n  {problem}")).collect()
}

/// Reads and validates the map file at `path`.
pub fn load(path: &Path) -> Result<MapSpec, SpecError> {
    let text = std::fs::read_to_string(path).map_err(|source| SpecError::Read { path: path.to_path_buf(), source })?;
    parse(&text, &path.display().to_string())
}

/// Parses and validates map text; `origin` names it in error messages.
pub fn parse(text: &str, origin: &str) -> Result<MapSpec, SpecError> {
    let raw: RawMap =
        toml::from_str(text).map_err(|source| SpecError::Syntax { origin: origin.to_string(), source })?;
    let mut checker = Checker::default();
    let map = checker.map(raw);
    if checker.problems.is_empty() {
        checker.cross_check(&map);
    }
    if checker.problems.is_empty() {
        Ok(map)
    } else {
        Err(SpecError::Invalid { origin: origin.to_string(), problems: checker.problems })
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawMap {
    name: String,
    address_bits: i64,
    version: RawVersion,
    #[serde(rename = "register", default)]
    registers: Vec<RawRegister>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawVersion {
    major: i64,
    minor: i64,
    patch: i64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawRegister {
    name: String,
    address: i64,
    array: Option<RawArray>,
    description: String,
    fields: Vec<RawField>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawArray {
    count: i64,
    stride: i64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawField {
    name: String,
    lsb: i64,
    width: i64,
    access: String,
    reset: Option<i64>,
    value: Option<i64>,
    description: String,
}

/// Rust keywords (strict, reserved and edition-dependent): a register whose lower-case
/// name is one of these cannot be a module.
const RUST_KEYWORDS: &[&str] = &[
    "abstract", "as", "async", "await", "become", "box", "break", "const", "continue", "crate", "do", "dyn", "else",
    "enum", "extern", "false", "final", "fn", "for", "gen", "if", "impl", "in", "let", "loop", "macro", "match", "mod",
    "move", "mut", "override", "priv", "pub", "ref", "return", "self", "static", "struct", "super", "trait", "true",
    "try", "type", "typeof", "union", "unsafe", "unsized", "use", "virtual", "where", "while", "yield",
];

/// Verilog-2005 constants are plain `integer`s: keep numbers that end up in one signed.
const MAX_VERILOG_INTEGER: i64 = i32::MAX as i64;

#[derive(Default)]
struct Checker {
    problems: Vec<Problem>,
}

impl Checker {
    fn report(&mut self, place: &Place, message: String) {
        self.problems.push(Problem { place: place.clone(), message });
    }

    /// Converts the raw map, reporting every rule that one item alone can break.
    /// Values that break a rule are replaced by harmless ones so checking goes on.
    fn map(&mut self, raw: RawMap) -> MapSpec {
        let place = Place::Map;
        self.text(&place, "name", &raw.name);
        let address_bits = match raw.address_bits {
            bits @ 1..=8 => bits as u32,
            bits => {
                self.report(
                    &place,
                    format!(
                        "address_bits {bits} is outside 1..={MAX_ADDRESS_BITS} \
                         (addresses are u8 in Rust)"
                    ),
                );
                MAX_ADDRESS_BITS
            }
        };
        let version = MapVersion {
            major: self.version_part(&raw.version.major, "major"),
            minor: self.version_part(&raw.version.minor, "minor"),
            patch: self.version_part(&raw.version.patch, "patch"),
        };
        if raw.registers.is_empty() {
            self.report(&place, "the map has no [[register]]".to_string());
        }
        let registers = raw.registers.into_iter().map(|register| self.register(register, address_bits)).collect();
        MapSpec { name: raw.name, address_bits, version, registers }
    }

    fn version_part(&mut self, value: &i64, part: &str) -> u32 {
        if (0..=MAX_VERILOG_INTEGER).contains(value) {
            *value as u32
        } else {
            self.report(&Place::Map, format!("version.{part} {value} is outside 0..={MAX_VERILOG_INTEGER}"));
            0
        }
    }

    fn register(&mut self, raw: RawRegister, address_bits: u32) -> RegisterSpec {
        let place = Place::register(&raw.name);
        self.upper_snake(&place, "register name", &raw.name);
        let lower = raw.name.to_ascii_lowercase();
        if RUST_KEYWORDS.contains(&lower.as_str()) {
            self.report(&place, format!("its Rust module name `{lower}` is a Rust keyword"));
        }
        self.text(&place, "description", &raw.description);
        let address_limit = 1i64 << address_bits;
        let address = if (0..address_limit).contains(&raw.address) {
            raw.address as u32
        } else {
            self.report(
                &place,
                format!(
                    "address {} is outside 0..={:#04x} ({address_bits} address bits)",
                    raw.address,
                    address_limit - 1
                ),
            );
            0
        };
        let array = raw.array.map(|array| {
            let mut count_ok = true;
            if !(1..=address_limit).contains(&array.count) {
                self.report(
                    &place,
                    format!("array count {} is not at least 1 and at most {address_limit}", array.count),
                );
                count_ok = false;
            }
            if !(1..address_limit).contains(&array.stride) {
                self.report(
                    &place,
                    format!("array stride {} is not at least 1 and below {address_limit}", array.stride),
                );
                count_ok = false;
            }
            if count_ok {
                let last = raw.address + (array.count - 1) * array.stride;
                if last >= address_limit {
                    self.report(
                        &place,
                        format!(
                            "element {} would be at address {last:#04x}, outside 0..={:#04x}",
                            array.count - 1,
                            address_limit - 1
                        ),
                    );
                    count_ok = false;
                }
            }
            if count_ok {
                ArraySpec { count: array.count as u32, stride: array.stride as u32 }
            } else {
                ArraySpec { count: 1, stride: 1 }
            }
        });
        if raw.fields.is_empty() {
            self.report(&place, "has no fields".to_string());
        }
        let checked: Vec<(FieldSpec, bool)> =
            raw.fields.into_iter().map(|field| self.field(&raw.name, field)).collect();
        let mut seen = HashSet::new();
        let mut occupied: Vec<(u32, &FieldSpec)> = Vec::new();
        for (field, placed) in &checked {
            let field_place = Place::field(&raw.name, &field.name);
            if !seen.insert(field.name.as_str()) {
                self.report(&field_place, "the name appears twice in this register".to_string());
            }
            // A field whose bits are already reported as wrong has no place to overlap.
            if !placed {
                continue;
            }
            for &(mask, other) in &occupied {
                if mask & field.mask() != 0 {
                    self.report(
                        &field_place,
                        format!("bits {} overlap field {} (bits {})", bit_range(field), other.name, bit_range(other)),
                    );
                }
            }
            occupied.push((field.mask(), field));
        }
        RegisterSpec {
            name: raw.name,
            address,
            array,
            description: raw.description,
            fields: checked.into_iter().map(|(field, _)| field).collect(),
        }
    }

    /// The field, and whether its bits are valid (else they are a stand-in).
    fn field(&mut self, register: &str, raw: RawField) -> (FieldSpec, bool) {
        let place = Place::field(register, &raw.name);
        self.upper_snake(&place, "field name", &raw.name);
        self.text(&place, "description", &raw.description);
        let word = i64::from(WORD_BITS);
        let geometry = if !(0..word).contains(&raw.lsb) {
            self.report(&place, format!("lsb {} is outside 0..={}", raw.lsb, word - 1));
            None
        } else if !(1..=word).contains(&raw.width) {
            self.report(&place, format!("width {} is outside 1..={word}", raw.width));
            None
        } else if raw.lsb + raw.width > word {
            self.report(
                &place,
                format!("bits {}:{} do not fit in a {word}-bit register", raw.lsb + raw.width - 1, raw.lsb),
            );
            None
        } else {
            Some((raw.lsb as u32, raw.width as u32))
        };
        let access = Access::from_keyword(&raw.access);
        if access.is_none() {
            let known: Vec<&str> = Access::ALL.iter().map(|access| access.keyword()).collect();
            self.report(&place, format!("unknown access `{}` (known: {})", raw.access, known.join(", ")));
        }
        if let Some(access) = access {
            if access == Access::ReadWrite && raw.reset.is_none() {
                self.report(&place, "an rw field needs a `reset` value".to_string());
            }
            if !matches!(access, Access::ReadWrite | Access::ReadOnly) && raw.reset.is_some() {
                self.report(&place, format!("`reset` is only for rw and ro fields, this one is {access}"));
            }
            if access == Access::ReadOnly && raw.reset.is_some() && raw.value.is_some() {
                self.report(&place, "an ro field has a `value` (constant) or a `reset`, not both".to_string());
            }
            if access != Access::ReadOnly && raw.value.is_some() {
                self.report(&place, format!("`value` is only for ro fields, this one is {access}"));
            }
        }
        // Fit is only meaningful once the width is known.
        let (reset, value) = match geometry {
            Some((_, width)) => {
                (self.constant(&place, "reset", raw.reset, width), self.constant(&place, "value", raw.value, width))
            }
            None => (None, None),
        };
        // Stand-ins for broken parts; a map with any problem is never returned.
        let (lsb, width) = geometry.unwrap_or((0, 1));
        let access = access.unwrap_or(Access::ReadOnly);
        let field = FieldSpec { name: raw.name, lsb, width, access, reset, value, description: raw.description };
        (field, geometry.is_some())
    }

    /// Checks that a reset or fixed value fits the field; `None` when absent or too big.
    fn constant(&mut self, place: &Place, key: &str, raw: Option<i64>, width: u32) -> Option<u32> {
        let value = raw?;
        if value < 0 || value > i64::from(low_bits(width)) {
            self.report(
                place,
                format!(
                    "{key} {value} does not fit in {width} bit{} (0..={:#x})",
                    if width == 1 { "" } else { "s" },
                    low_bits(width)
                ),
            );
            return None;
        }
        Some(value as u32)
    }

    fn upper_snake(&mut self, place: &Place, what: &str, name: &str) {
        if !is_upper_snake(name) {
            self.report(
                place,
                format!("{what} {name:?} is not UPPER_SNAKE (A-Z, 0-9, single underscores, a letter first)"),
            );
        }
    }

    fn text(&mut self, place: &Place, what: &str, text: &str) {
        if text.trim().is_empty() {
            self.report(place, format!("{what} is empty"));
        } else if text.chars().any(char::is_control) {
            // Descriptions become one-line comments and table cells.
            self.report(place, format!("{what} has a line break or control character"));
        }
    }

    /// Rules between registers: addresses and generated names unique.
    fn cross_check(&mut self, map: &MapSpec) {
        let mut names = HashSet::new();
        for register in &map.registers {
            if !names.insert(register.name.as_str()) {
                self.report(&Place::register(&register.name), "the name appears twice in the map".to_string());
            }
        }

        let mut owner_of_address: BTreeMap<u32, (&str, Option<u32>)> = BTreeMap::new();
        for register in &map.registers {
            for (index, address) in register.addresses().enumerate() {
                let element = register.array.map(|_| index as u32);
                if let Some((other, other_index)) = owner_of_address.get(&address) {
                    self.report(
                        &Place::register(&register.name),
                        format!(
                            "{} at address {address:#04x} overlaps {}",
                            element_name(&register.name, element),
                            element_name(other, *other_index)
                        ),
                    );
                } else {
                    owner_of_address.insert(address, (register.name.as_str(), element));
                }
            }
        }

        let mut verilog_names = BTreeMap::new();
        for (constant, owner) in naming::verilog_constants(map) {
            if let Some(first_owner) = verilog_names.get(&constant) {
                let message = format!("its Verilog constant {constant} is also generated for {first_owner}");
                self.report(&owner, message);
            } else {
                verilog_names.insert(constant, owner);
            }
        }

        for register in &map.registers {
            let mut rust_names = BTreeMap::new();
            for (constant, field) in naming::rust_constants(register) {
                if let Some(first_field) = rust_names.insert(constant.clone(), field) {
                    self.report(
                        &owner_place(&register.name, field),
                        format!(
                            "its Rust constant {}::{constant} is also generated for {}",
                            naming::rust_module(register),
                            owner_place(&register.name, first_field)
                        ),
                    );
                }
            }
        }
    }
}

/// The register, or its field when there is one.
fn owner_place(register: &str, field: Option<&str>) -> Place {
    match field {
        None => Place::register(register),
        Some(field) => Place::field(register, field),
    }
}

fn element_name(register: &str, index: Option<u32>) -> String {
    match index {
        Some(index) => format!("{register}[{index}]"),
        None => register.to_string(),
    }
}

/// `msb:lsb`, or the bit number for a one-bit field.
pub fn bit_range(field: &FieldSpec) -> String {
    if field.width == 1 {
        field.lsb.to_string()
    } else {
        format!("{}:{}", field.msb(), field.lsb)
    }
}

/// `A-Z`, `0-9` and single underscores, starting with a letter, not ending with `_`.
pub fn is_upper_snake(name: &str) -> bool {
    name.starts_with(|c: char| c.is_ascii_uppercase())
        && !name.ends_with('_')
        && !name.contains("__")
        && name.chars().all(|c| c.is_ascii_uppercase() || c.is_ascii_digit() || c == '_')
}

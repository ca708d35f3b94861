//! The host<->core interface beside the register map: `hdl/interface.toml` parsed and
//! checked against the validated map, so every generator can trust it.
//!
//! The file states the period record (increment format, flag bits), the SPI frame codes
//! and CRC, the values of the register fields the RTL decodes ([`EnumSpec`]), the bit
//! sets that travel as one vector ([`BitSetSpec`]), the drive-timing fields and the
//! build parameters of each top module with their legal ranges ([`ModuleSpec`]). It
//! refers to the map by name (`AXIS_MODE.OUT_MODE`, `RECORD_INC.count`), and a
//! reference that does not resolve is a problem like any other.
//!
//! As in [`crate::spec`], serde reads loosely typed `Raw*` structs (unknown keys are
//! refused with toml's line and column), then [`parse`] reports every broken rule, each
//! naming its place.

use crate::expr::Expr;
use crate::spec::{is_upper_snake, low_bits, naming, MapSpec, Place, Problem};
use serde::Deserialize;
use std::collections::{BTreeMap, HashSet};
use std::path::{Path, PathBuf};

/// Verilog-2005 parameters are plain `integer`s: every bound and default must fit one.
pub const MAX_PARAMETER: i64 = i32::MAX as i64;

/// The whole validated interface description.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct InterfaceSpec {
    /// The period record.
    pub record: RecordSpec,
    /// The SPI frame layer's codes.
    pub spi: SpiSpec,
    /// Decoded register field values, in file order.
    pub enums: Vec<EnumSpec>,
    /// Bit vectors, in file order.
    pub bitsets: Vec<BitSetSpec>,
    /// The lanes of a record with the flag PBP.
    pub pbp: PbpSpec,
    /// The drive-timing fields, in file order (the order of the generated struct).
    pub timing: Vec<TimingFieldSpec>,
    /// Modules with build parameters, in file order.
    pub modules: Vec<ModuleSpec>,
}

/// One field of a pbp record: bits `lsb +: width` of lane `lane`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PbpFieldSpec {
    /// The name (`X`, `Y`, `COUNT`, `TICK_DIV`, or the bit set's name).
    pub name: String,
    /// The record lane (axis) that holds it.
    pub lane: u32,
    /// Its lowest bit in the lane.
    pub lsb: u32,
    /// Its width.
    pub width: u32,
    /// What it holds.
    pub description: String,
}

/// The lanes of a record with the flag PBP (docs/spec/pbp_interp.md#in-the-core): the
/// bit set in one lane's top bits, the coordinates, the arc's decision count and the
/// decision divider, each at the low end of a lane or beside the bit set.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PbpSpec {
    /// What the record is.
    pub description: String,
    /// The bit set (a `[[bits]]` name) and where it lies.
    pub bits: PbpFieldSpec,
    /// The X coordinate (signed, the block's `COORD_W`).
    pub x: PbpFieldSpec,
    /// The Y coordinate (as wide as X).
    pub y: PbpFieldSpec,
    /// An arc's decision count (`COORD_W + 3` bits, the block's `rec_steps`).
    pub count: PbpFieldSpec,
    /// The decision divider (the block's `DIV_W`).
    pub tick_div: PbpFieldSpec,
}

impl PbpSpec {
    /// The fields in the order the generators list them: `X`, `Y`, `COUNT`, `TICK_DIV`.
    pub fn fields(&self) -> [&PbpFieldSpec; 4] {
        [&self.x, &self.y, &self.count, &self.tick_div]
    }
}

/// The extra bits of an arc's decision count over a coordinate (pbp_interp's `rec_steps`
/// is `COORD_W + 3` bits: up to 8 R decisions around a full circle).
pub const PBP_COUNT_EXTRA: u32 = 3;

/// A `REG.FIELD` reference, resolved against the map.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FieldRef {
    /// The register's name.
    pub register: String,
    /// The field's name.
    pub field: String,
    /// The field's lowest bit.
    pub lsb: u32,
    /// The field's width.
    pub width: u32,
    /// The field's reset value, when it is `rw`.
    pub reset: Option<u32>,
}

impl FieldRef {
    /// `REG.FIELD`.
    pub fn path(&self) -> String {
        format!("{}.{}", self.register, self.field)
    }
}

/// A bound or count, as written and as resolved.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Bound {
    /// The value.
    pub value: i64,
    /// How the file states it: a number, or a reference such as `PERIOD_CLOCKS.CLOCKS.width`.
    pub expression: String,
}

impl Bound {
    /// Whether the file states it by reference rather than as a number.
    pub fn is_derived(&self) -> bool {
        self.expression != self.value.to_string()
    }
}

/// The period record.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RecordSpec {
    /// The most axes a record holds (`MAX_AXES`).
    pub max_axes: Bound,
    /// The per-axis increment.
    pub increment: IncrementSpec,
    /// The register field a RECORD_PUSH carries the flags in; its width is the flags' width.
    pub flags_field: FieldRef,
    /// The flag bits.
    pub flags: Vec<BitSpec>,
}

impl RecordSpec {
    /// Bits of the flags.
    pub fn flags_width(&self) -> u32 {
        self.flags_field.width
    }
}

/// The signed fixed-point increment of one axis.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct IncrementSpec {
    /// The register field that holds one (its width is the increment's).
    pub field: FieldRef,
    /// Integer bits, sign included.
    pub int_bits: u32,
    /// Fraction bits.
    pub frac_bits: u32,
    /// One line of prose.
    pub description: String,
}

impl IncrementSpec {
    /// Bits of one increment.
    pub fn width(&self) -> u32 {
        self.int_bits + self.frac_bits
    }
}

/// One named bit of a bit set or of the record flags.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BitSpec {
    /// UPPER_SNAKE name, unique in its set.
    pub name: String,
    /// Bit position.
    pub bit: u32,
    /// The one-bit register field that carries it, if any.
    pub field: Option<FieldRef>,
    /// One line of prose.
    pub description: String,
}

/// The SPI frame layer.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SpiSpec {
    /// Most words of a READ frame and records of a FIFO frame (the count byte).
    pub max_count: u32,
    /// The frames' CRC.
    pub crc: CrcSpec,
    /// Command bytes.
    pub commands: Vec<CodeSpec>,
    /// Result bytes.
    pub results: Vec<CodeSpec>,
}

/// The CRC of the SPI frames.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CrcSpec {
    /// The catalogue name (`CRC-16/IBM-3740`).
    pub name: String,
    /// Bits.
    pub width: u32,
    /// Generator polynomial, MSB first, without the top bit.
    pub polynomial: u32,
    /// Register value at the start of a frame.
    pub initial: u32,
    /// One line of prose.
    pub description: String,
}

/// A named byte code.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CodeSpec {
    /// UPPER_SNAKE name, unique in its list.
    pub name: String,
    /// The byte.
    pub code: u8,
    /// One line of prose.
    pub description: String,
}

/// The values of a register field the RTL decodes.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct EnumSpec {
    /// UPPER_SNAKE name.
    pub name: String,
    /// The field holding a value (its width is the enum's).
    pub field: FieldRef,
    /// One line of prose.
    pub description: String,
    /// The value an unlisted field value acts as (present exactly when some value is unlisted).
    pub otherwise: Option<String>,
    /// The values, in file order.
    pub values: Vec<EnumValueSpec>,
}

impl EnumSpec {
    /// Bits of a value.
    pub fn width(&self) -> u32 {
        self.field.width
    }

    /// Whether the values carry a factor.
    pub fn has_factors(&self) -> bool {
        self.values.iter().any(|value| value.factor.is_some())
    }

    /// The value with the field's reset value, if the field has one and a value is listed for it.
    pub fn reset_value(&self) -> Option<&EnumValueSpec> {
        let reset = self.field.reset?;
        self.values.iter().find(|value| value.value == reset)
    }
}

/// One value of an [`EnumSpec`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct EnumValueSpec {
    /// UPPER_SNAKE name, unique in its enum.
    pub name: String,
    /// The field value.
    pub value: u32,
    /// A number the value stands for (the jog multiplier's 1, 10, 100).
    pub factor: Option<u32>,
    /// One line of prose.
    pub description: String,
}

/// A bit vector that travels as one port inside the RTL.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BitSetSpec {
    /// UPPER_SNAKE name.
    pub name: String,
    /// Bits of the vector (at most 8).
    pub width: u32,
    /// One line of prose.
    pub description: String,
    /// The named bits.
    pub bits: Vec<BitSpec>,
}

/// One drive-timing field.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TimingFieldSpec {
    /// UPPER_SNAKE name (`STEP_LEN`); the Rust and C field is its lower case.
    pub name: String,
    /// The letter the specification uses (`L`).
    pub symbol: String,
    /// The register field holding it, per axis.
    pub field: FieldRef,
    /// One line of prose.
    pub description: String,
}

/// A module and its build parameters.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ModuleSpec {
    /// The Verilog module name (`finestep_top`).
    pub name: String,
    /// One line of prose.
    pub description: String,
    /// The parameters, in file order.
    pub parameters: Vec<ParameterSpec>,
    /// Values derived from the parameters, for the constraints, in file order (each
    /// reads only parameters and the derived values before it).
    pub derived: Vec<DerivedSpec>,
    /// Constraints across parameters, beyond each one's range, in file order.
    pub constraints: Vec<ConstraintSpec>,
}

impl ModuleSpec {
    /// The parameter called `name`.
    pub fn parameter(&self, name: &str) -> Option<&ParameterSpec> {
        self.parameters.iter().find(|parameter| parameter.name == name)
    }

    /// The parameters' values (`values`, the defaults for the others) and the derived
    /// values computed from them.
    pub fn values(&self, values: &[(&str, i64)]) -> BTreeMap<String, i64> {
        let mut all: BTreeMap<String, i64> = self
            .parameters
            .iter()
            .map(|p| {
                let value = values.iter().find(|(name, _)| *name == p.name).map_or(p.default, |(_, v)| *v);
                (p.name.clone(), value)
            })
            .collect();
        for derived in &self.derived {
            // The parse checked that every name resolves: a value is always there.
            let value = derived.value.eval(&all).unwrap_or_default();
            all.insert(derived.name.clone(), value);
        }
        all
    }

    /// The constraints that `values` (as [`ModuleSpec::values`] takes them) break.
    pub fn violated(&self, values: &[(&str, i64)]) -> Vec<&ConstraintSpec> {
        let all = self.values(values);
        self.constraints.iter().filter(|c| !c.holds(&all)).collect()
    }
}

/// A named value derived from a module's parameters (`log2` of a period quantum, say).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DerivedSpec {
    /// UPPER_SNAKE name, unlike every parameter's.
    pub name: String,
    /// Its expression ([`crate::expr`]).
    pub value: Expr,
    /// The expression as the file writes it.
    pub value_text: String,
    /// One line of prose.
    pub description: String,
}

impl DerivedSpec {
    /// Its name in the generated Verilog checks (`FS_CHECK_<NAME>`, a localparam).
    pub fn verilog_name(&self) -> String {
        format!("FS_CHECK_{}", self.name)
    }
}

/// A constraint across build parameters: when `when` holds, `require` must.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ConstraintSpec {
    /// Its name, a Verilog identifier: the elaboration check of a combination that breaks
    /// it instantiates `<module>_<name>`, a module that does not exist.
    pub name: String,
    /// The condition under which it applies (always, when `None`).
    pub when: Option<Expr>,
    /// What must hold then.
    pub require: Expr,
    /// `when` and `require` as the file writes them.
    pub when_text: Option<String>,
    /// See `when_text`.
    pub require_text: String,
    /// One line of prose: why.
    pub description: String,
}

impl ConstraintSpec {
    /// The name of the module its elaboration check instantiates: `<module>_<name>`.
    pub fn check_module(&self, module: &str) -> String {
        format!("{module}_{}", self.name)
    }

    /// Whether it holds for `values` (parameters and derived values).
    pub fn holds(&self, values: &BTreeMap<String, i64>) -> bool {
        let applies = self.when.as_ref().is_none_or(|when| when.eval(values).unwrap_or(1) != 0);
        !applies || self.require.eval(values).unwrap_or(0) != 0
    }
}

/// One build parameter.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ParameterSpec {
    /// UPPER_SNAKE name, as in the Verilog.
    pub name: String,
    /// The Verilog default.
    pub default: i64,
    /// Least legal value.
    pub min: Bound,
    /// Greatest legal value.
    pub max: Bound,
    /// The CAPS field that reports it.
    pub caps: Option<FieldRef>,
    /// One line of prose.
    pub description: String,
}

impl ParameterSpec {
    /// The name of the module an elaboration check instantiates when the parameter is out
    /// of range: `<module>_<PARAM>_must_be_<min>_to_<max>`.
    pub fn check_module(&self, module: &str) -> String {
        format!("{module}_{}_must_be_{}_to_{}", self.name, self.min.value, self.max.value)
    }
}

/// Why the interface description could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum InterfaceError {
    /// The register map it refers to could not be loaded.
    #[error(transparent)]
    Map(#[from] crate::spec::SpecError),
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
    /// Well-formed TOML that breaks the rules; every broken rule is listed.
    #[error("{origin}: invalid interface description:{}", problems.iter().map(|p| format!("\n  {p}")).collect::<String>())]
    Invalid {
        /// The file name, for the message.
        origin: String,
        /// Every broken rule, in file order.
        problems: Vec<Problem>,
    },
}

impl InterfaceError {
    /// The broken rules, if the file was well-formed TOML but invalid.
    pub fn problems(&self) -> &[Problem] {
        match self {
            InterfaceError::Invalid { problems, .. } => problems,
            _ => &[],
        }
    }
}

/// Reads and validates the interface file at `path` against `map`.
pub fn load(path: &Path, map: &MapSpec) -> Result<InterfaceSpec, InterfaceError> {
    let text =
        std::fs::read_to_string(path).map_err(|source| InterfaceError::Read { path: path.to_path_buf(), source })?;
    parse(&text, &path.display().to_string(), map)
}

/// Parses and validates interface text against `map`; `origin` names it in errors.
pub fn parse(text: &str, origin: &str, map: &MapSpec) -> Result<InterfaceSpec, InterfaceError> {
    let raw: RawInterface =
        toml::from_str(text).map_err(|source| InterfaceError::Syntax { origin: origin.to_string(), source })?;
    let mut checker = Checker { map, problems: Vec::new() };
    let spec = checker.interface(raw);
    if checker.problems.is_empty() {
        checker.names(&spec);
    }
    if checker.problems.is_empty() {
        Ok(spec)
    } else {
        Err(InterfaceError::Invalid { origin: origin.to_string(), problems: checker.problems })
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawInterface {
    record: RawRecord,
    spi: RawSpi,
    #[serde(rename = "enum", default)]
    enums: Vec<RawEnum>,
    #[serde(rename = "bits", default)]
    bitsets: Vec<RawBitSet>,
    pbp: RawPbp,
    #[serde(default)]
    timing: Vec<RawTiming>,
    #[serde(rename = "module", default)]
    modules: Vec<RawModule>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawRecord {
    max_axes: RawBound,
    increment: RawIncrement,
    flags_field: String,
    flags: Vec<RawBit>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawIncrement {
    field: String,
    int_bits: i64,
    frac_bits: i64,
    description: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawBit {
    name: String,
    bit: i64,
    field: Option<String>,
    description: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSpi {
    max_count: i64,
    crc: RawCrc,
    commands: Vec<RawCode>,
    results: Vec<RawCode>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawCrc {
    name: String,
    width: i64,
    polynomial: i64,
    initial: i64,
    description: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawCode {
    name: String,
    code: i64,
    description: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawEnum {
    name: String,
    field: String,
    description: String,
    otherwise: Option<String>,
    values: Vec<RawEnumValue>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawEnumValue {
    name: String,
    value: i64,
    factor: Option<i64>,
    description: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawBitSet {
    name: String,
    width: i64,
    description: String,
    bits: Vec<RawBit>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawPbp {
    description: String,
    bits: String,
    bits_lane: i64,
    bits_lsb: i64,
    x: RawPbpField,
    y: RawPbpField,
    count: RawPbpField,
    tick_div: RawPbpField,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawPbpField {
    lane: i64,
    lsb: i64,
    width: i64,
    description: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTiming {
    name: String,
    symbol: String,
    field: String,
    description: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawModule {
    name: String,
    description: String,
    parameters: Vec<RawParameter>,
    #[serde(default)]
    derived: Vec<RawDerived>,
    #[serde(default)]
    constraints: Vec<RawConstraint>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawDerived {
    name: String,
    value: String,
    description: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawConstraint {
    name: String,
    when: Option<String>,
    require: String,
    description: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawParameter {
    name: String,
    default: i64,
    min: RawBound,
    max: RawBound,
    caps: Option<String>,
    description: String,
}

#[derive(Deserialize)]
#[serde(untagged)]
enum RawBound {
    Number(i64),
    Reference(String),
}

struct Checker<'a> {
    map: &'a MapSpec,
    problems: Vec<Problem>,
}

fn place(text: impl Into<String>) -> Place {
    Place::Interface(text.into())
}

impl Checker<'_> {
    fn report(&mut self, place: &Place, message: String) {
        self.problems.push(Problem { place: place.clone(), message });
    }

    fn interface(&mut self, raw: RawInterface) -> InterfaceSpec {
        let record = self.record(raw.record);
        let spi = self.spi(raw.spi);
        let enums = raw.enums.into_iter().map(|raw| self.enumeration(raw)).collect();
        let bitsets: Vec<BitSetSpec> = raw.bitsets.into_iter().map(|raw| self.bitset(raw)).collect();
        let pbp = self.pbp(raw.pbp, &record, &bitsets);
        let timing = self.timing(raw.timing);
        let modules = raw.modules.into_iter().map(|raw| self.module(raw, &record)).collect();
        InterfaceSpec { record, spi, enums, bitsets, pbp, timing, modules }
    }

    /// Resolves `REG.FIELD`; a stand-in (width 1) when it does not.
    fn field_ref(&mut self, at: &Place, text: &str) -> FieldRef {
        let found = text.split_once('.').and_then(|(register, field)| {
            let spec = self.map.registers.iter().find(|r| r.name == register)?;
            let field = spec.fields.iter().find(|f| f.name == field)?;
            Some(FieldRef {
                register: spec.name.clone(),
                field: field.name.clone(),
                lsb: field.lsb,
                width: field.width,
                reset: field.reset,
            })
        });
        found.unwrap_or_else(|| {
            self.report(at, format!("`{text}` is not a REG.FIELD of the register map"));
            FieldRef { register: String::new(), field: String::new(), lsb: 0, width: 1, reset: None }
        })
    }

    /// Resolves a bound: a number, or `REG.count`, `REG.FIELD.width` or `MAX_AXES`, each
    /// optionally `- n`.
    fn bound(&mut self, at: &Place, what: &str, raw: &RawBound, max_axes: Option<i64>) -> Bound {
        let text = match raw {
            RawBound::Number(value) => return Bound { value: *value, expression: value.to_string() },
            RawBound::Reference(text) => text.trim().to_string(),
        };
        let (reference, minus) = match text.split_once('-') {
            Some((reference, minus)) => match minus.trim().parse::<i64>() {
                Ok(minus) => (reference.trim(), minus),
                Err(_) => {
                    self.report(at, format!("{what} `{text}`: `- n` needs a number"));
                    return Bound { value: 0, expression: text };
                }
            },
            None => (text.as_str(), 0),
        };
        let parts: Vec<&str> = reference.split('.').collect();
        let value = match parts.as_slice() {
            ["MAX_AXES"] => max_axes,
            [register, "count"] => self
                .map
                .registers
                .iter()
                .find(|r| r.name == *register && r.array.is_some())
                .map(|r| i64::from(r.count())),
            [register, field, "width"] => self
                .map
                .registers
                .iter()
                .find(|r| r.name == *register)
                .and_then(|r| r.fields.iter().find(|f| f.name == *field))
                .map(|f| i64::from(f.width)),
            _ => None,
        };
        match value {
            Some(value) => Bound { value: value - minus, expression: text },
            None => {
                self.report(
                    at,
                    format!(
                        "{what} `{text}` is neither a number nor REG.count (an array register), \
                         REG.FIELD.width or MAX_AXES"
                    ),
                );
                Bound { value: 0, expression: text }
            }
        }
    }

    fn name(&mut self, at: &Place, name: &str) {
        if !is_upper_snake(name) {
            self.report(at, format!("name {name:?} is not UPPER_SNAKE (A-Z, 0-9, single underscores, a letter first)"));
        }
    }

    fn text(&mut self, at: &Place, text: &str) {
        if text.trim().is_empty() {
            self.report(at, "description is empty".to_string());
        } else if text.chars().any(char::is_control) {
            self.report(at, "description has a line break or control character".to_string());
        }
    }

    /// Names unique in a list.
    fn unique<'n>(&mut self, at: &str, what: &str, names: impl IntoIterator<Item = &'n str>) {
        let mut seen = HashSet::new();
        for name in names {
            if !seen.insert(name) {
                self.report(&place(at), format!("{what} {name} appears twice"));
            }
        }
    }

    fn bits(&mut self, owner: &str, width: u32, raw: Vec<RawBit>) -> Vec<BitSpec> {
        let mut bits = Vec::new();
        let mut taken = BTreeMap::new();
        for raw in raw {
            let at = place(format!("{owner}, bit {}", raw.name));
            self.name(&at, &raw.name);
            self.text(&at, &raw.description);
            let bit = if (0..i64::from(width)).contains(&raw.bit) {
                raw.bit as u32
            } else {
                self.report(&at, format!("bit {} is outside 0..={}", raw.bit, width - 1));
                0
            };
            if let Some(other) = taken.insert(bit, raw.name.clone()) {
                self.report(&at, format!("bit {bit} is also {other}"));
            }
            let field = raw.field.map(|text| {
                let field = self.field_ref(&at, &text);
                if field.width != 1 {
                    self.report(&at, format!("field {text} is {} bits wide, not 1", field.width));
                }
                field
            });
            bits.push(BitSpec { name: raw.name, bit, field, description: raw.description });
        }
        self.unique(owner, "bit", bits.iter().map(|b| b.name.as_str()));
        bits
    }

    fn record(&mut self, raw: RawRecord) -> RecordSpec {
        let at = place("record");
        let max_axes = self.bound(&at, "max_axes", &raw.max_axes, None);
        if !(1..=32).contains(&max_axes.value) {
            self.report(&at, format!("max_axes {} is outside 1..=32", max_axes.value));
        }
        let increment_at = place("record, increment");
        let field = self.field_ref(&increment_at, &raw.increment.field);
        self.text(&increment_at, &raw.increment.description);
        let (int_bits, frac_bits) = (raw.increment.int_bits, raw.increment.frac_bits);
        if int_bits < 1 || frac_bits < 0 || int_bits + frac_bits != i64::from(field.width) {
            self.report(
                &increment_at,
                format!(
                    "int_bits {int_bits} + frac_bits {frac_bits} must be the width of {} ({} bits), \
                     with at least the sign bit",
                    field.path(),
                    field.width
                ),
            );
        }
        let increment = IncrementSpec {
            field,
            int_bits: int_bits.clamp(0, 32) as u32,
            frac_bits: frac_bits.clamp(0, 32) as u32,
            description: raw.increment.description,
        };
        let flags_field = self.field_ref(&at, &raw.flags_field);
        if flags_field.width > 8 {
            self.report(&at, format!("flags_field {} is wider than a byte", flags_field.path()));
        }
        let flags = self.bits("record flags", flags_field.width, raw.flags);
        RecordSpec { max_axes, increment, flags_field, flags }
    }

    fn codes(&mut self, what: &str, raw: Vec<RawCode>) -> Vec<CodeSpec> {
        let mut codes: Vec<CodeSpec> = Vec::new();
        for raw in raw {
            let at = place(format!("spi {what} {}", raw.name));
            self.name(&at, &raw.name);
            self.text(&at, &raw.description);
            let code = match u8::try_from(raw.code) {
                Ok(code) => code,
                Err(_) => {
                    self.report(&at, format!("code {} is not a byte", raw.code));
                    0
                }
            };
            if let Some(other) = codes.iter().find(|other| other.code == code) {
                self.report(&at, format!("code {code:#04x} is also {}", other.name));
            }
            codes.push(CodeSpec { name: raw.name, code, description: raw.description });
        }
        self.unique(&format!("spi {what}s"), what, codes.iter().map(|c| c.name.as_str()));
        codes
    }

    fn spi(&mut self, raw: RawSpi) -> SpiSpec {
        let at = place("spi");
        if !(1..=255).contains(&raw.max_count) {
            self.report(&at, format!("max_count {} is outside 1..=255 (the count is one byte)", raw.max_count));
        }
        let crc_at = place("spi crc");
        self.text(&crc_at, &raw.crc.description);
        self.text(&crc_at, &raw.crc.name);
        let width = if (1..=32).contains(&raw.crc.width) {
            raw.crc.width as u32
        } else {
            self.report(&crc_at, format!("width {} is outside 1..=32", raw.crc.width));
            16
        };
        let mut value = |key: &str, value: i64| {
            if (0..=i64::from(low_bits(width))).contains(&value) {
                value as u32
            } else {
                self.report(&crc_at, format!("{key} {value:#x} does not fit in {width} bits"));
                0
            }
        };
        let polynomial = value("polynomial", raw.crc.polynomial);
        let initial = value("initial", raw.crc.initial);
        let crc = CrcSpec { name: raw.crc.name, width, polynomial, initial, description: raw.crc.description };
        let commands = self.codes("command", raw.commands);
        let results = self.codes("result", raw.results);
        SpiSpec { max_count: raw.max_count.clamp(0, 255) as u32, crc, commands, results }
    }

    fn enumeration(&mut self, raw: RawEnum) -> EnumSpec {
        let owner = format!("enum {}", raw.name);
        let at = place(&owner);
        self.name(&at, &raw.name);
        self.text(&at, &raw.description);
        let field = self.field_ref(&at, &raw.field);
        if field.width > 8 {
            self.report(&at, format!("field {} is wider than a byte", field.path()));
        }
        let mut values: Vec<EnumValueSpec> = Vec::new();
        for value in raw.values {
            let value_at = place(format!("{owner}, value {}", value.name));
            self.name(&value_at, &value.name);
            self.text(&value_at, &value.description);
            let number = if (0..=i64::from(low_bits(field.width))).contains(&value.value) {
                value.value as u32
            } else {
                self.report(
                    &value_at,
                    format!("value {} does not fit field {} ({} bits)", value.value, field.path(), field.width),
                );
                0
            };
            if let Some(other) = values.iter().find(|other| other.value == number) {
                self.report(&value_at, format!("value {number} is also {}", other.name));
            }
            let factor = value.factor.map(|factor| match u32::try_from(factor) {
                Ok(factor) if factor > 0 => factor,
                _ => {
                    self.report(&value_at, format!("factor {factor} is not a positive 32-bit number"));
                    1
                }
            });
            values.push(EnumValueSpec { name: value.name, value: number, factor, description: value.description });
        }
        self.unique(&owner, "value", values.iter().map(|v| v.name.as_str()));
        if values.is_empty() {
            self.report(&at, "has no values".to_string());
        }
        if values.iter().any(|v| v.factor.is_some()) && values.iter().any(|v| v.factor.is_none()) {
            self.report(&at, "either every value has a factor or none has".to_string());
        }
        let complete = values.len() as u64 == 1u64 << field.width.min(32);
        match (&raw.otherwise, complete) {
            (None, false) => {
                self.report(&at, "some field values are unlisted: say what they act as (`otherwise`)".into())
            }
            (Some(_), true) => self.report(&at, "`otherwise` is for enums that leave field values unlisted".into()),
            (Some(name), false) if !values.iter().any(|v| &v.name == name) => {
                self.report(&at, format!("otherwise {name} is not one of its values"))
            }
            _ => {}
        }
        if let Some(reset) = field.reset {
            if !values.iter().any(|v| v.value == reset) {
                self.report(&at, format!("the field's reset value {reset} is not a listed value"));
            }
        }
        EnumSpec { name: raw.name, field, description: raw.description, otherwise: raw.otherwise, values }
    }

    fn bitset(&mut self, raw: RawBitSet) -> BitSetSpec {
        let owner = format!("bits {}", raw.name);
        let at = place(&owner);
        self.name(&at, &raw.name);
        self.text(&at, &raw.description);
        let width = if (1..=8).contains(&raw.width) {
            raw.width as u32
        } else {
            self.report(&at, format!("width {} is outside 1..=8", raw.width));
            8
        };
        let bits = self.bits(&owner, width, raw.bits);
        BitSetSpec { name: raw.name, width, description: raw.description, bits }
    }

    /// The pbp record's lanes: every field inside a lane of the record (and, as the core
    /// needs, within its first four lanes), no two overlapping, X and Y equally wide and
    /// the count `PBP_COUNT_EXTRA` bits wider, the bit set a `[[bits]]` set.
    fn pbp(&mut self, raw: RawPbp, record: &RecordSpec, bitsets: &[BitSetSpec]) -> PbpSpec {
        let at = place("pbp");
        self.text(&at, &raw.description);
        let lane_w = record.increment.width();
        // The core builds the pbp block only with at least 4 axes (its HAS_PBP constraint).
        let lanes = record.max_axes.value.clamp(0, 4) as u32;
        let set_width = match bitsets.iter().find(|b| b.name == raw.bits) {
            Some(set) => set.width,
            None => {
                self.report(&at, format!("bits {} is not a [[bits]] set", raw.bits));
                1
            }
        };
        let bits_raw = RawPbpField {
            lane: raw.bits_lane,
            lsb: raw.bits_lsb,
            width: i64::from(set_width),
            description: format!("the bit set {}", raw.bits),
        };
        let mut field = |name: &str, raw: RawPbpField| -> PbpFieldSpec {
            let at = place(format!("pbp {name}"));
            self.text(&at, &raw.description);
            let ok = (0..i64::from(lanes)).contains(&raw.lane)
                && raw.lsb >= 0
                && raw.width >= 1
                && raw.lsb + raw.width <= i64::from(lane_w);
            if !ok {
                self.report(
                    &at,
                    format!(
                        "lane {} bits {} +: {} is not inside one of lanes 0..{lanes} ({lane_w} bits each)",
                        raw.lane, raw.lsb, raw.width
                    ),
                );
            }
            let clamp = |v: i64, hi: i64| v.clamp(0, hi) as u32;
            PbpFieldSpec {
                name: name.to_string(),
                lane: clamp(raw.lane, 7),
                lsb: clamp(raw.lsb, 31),
                width: clamp(raw.width, 32).max(1),
                description: raw.description,
            }
        };
        let bits = field(&raw.bits, bits_raw);
        let x = field("X", raw.x);
        let y = field("Y", raw.y);
        let count = field("COUNT", raw.count);
        let tick_div = field("TICK_DIV", raw.tick_div);
        let spec = PbpSpec { description: raw.description, bits, x, y, count, tick_div };
        if spec.x.width != spec.y.width {
            self.report(&at, format!("X ({} bits) and Y ({} bits) must be equally wide", spec.x.width, spec.y.width));
        }
        if spec.count.width != spec.x.width + PBP_COUNT_EXTRA {
            let message = format!(
                "COUNT must be {PBP_COUNT_EXTRA} bits wider than a coordinate ({} + {PBP_COUNT_EXTRA}), not {}",
                spec.x.width, spec.count.width
            );
            self.report(&at, message);
        }
        let all: Vec<&PbpFieldSpec> = std::iter::once(&spec.bits).chain(spec.fields()).collect();
        for (k, a) in all.iter().enumerate() {
            for b in &all[k + 1..] {
                if a.lane == b.lane && a.lsb < b.lsb + b.width && b.lsb < a.lsb + a.width {
                    self.report(&at, format!("{} and {} overlap in lane {}", a.name, b.name, a.lane));
                }
            }
        }
        spec
    }

    fn timing(&mut self, raw: Vec<RawTiming>) -> Vec<TimingFieldSpec> {
        if raw.is_empty() {
            self.report(&place("timing"), "no [[timing]] fields".to_string());
        }
        let fields: Vec<TimingFieldSpec> = raw
            .into_iter()
            .map(|raw| {
                let at = place(format!("timing {}", raw.name));
                self.name(&at, &raw.name);
                self.text(&at, &raw.description);
                if raw.symbol.trim().is_empty() || raw.symbol.chars().any(|c| !c.is_ascii_alphanumeric()) {
                    self.report(&at, format!("symbol {:?} is not a short alphanumeric name", raw.symbol));
                }
                let field = self.field_ref(&at, &raw.field);
                if field.reset.is_none() && !field.register.is_empty() {
                    self.report(&at, format!("field {} is not an rw field with a reset value", field.path()));
                }
                TimingFieldSpec { name: raw.name, symbol: raw.symbol, field, description: raw.description }
            })
            .collect();
        self.unique("timing", "field", fields.iter().map(|f| f.name.as_str()));
        self.unique("timing", "symbol", fields.iter().map(|f| f.symbol.as_str()));
        if let Some(first) = fields.first() {
            for field in &fields[1..] {
                if field.field.width != first.field.width {
                    self.report(
                        &place(format!("timing {}", field.name)),
                        format!(
                            "field {} is {} bits wide, {} of {} is {}: timing fields are equally wide",
                            field.field.path(),
                            field.field.width,
                            first.field.path(),
                            first.name,
                            first.field.width
                        ),
                    );
                }
            }
        }
        fields
    }

    fn module(&mut self, raw: RawModule, record: &RecordSpec) -> ModuleSpec {
        let owner = format!("module {}", raw.name);
        let at = place(&owner);
        let lower_snake = raw.name.starts_with(|c: char| c.is_ascii_lowercase())
            && raw.name.chars().all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_');
        if !lower_snake {
            self.report(&at, format!("module name {:?} is not lower_snake", raw.name));
        }
        self.text(&at, &raw.description);
        let mut parameters = Vec::new();
        for raw in raw.parameters {
            let at = place(format!("{owner}, parameter {}", raw.name));
            self.name(&at, &raw.name);
            self.text(&at, &raw.description);
            let min = self.bound(&at, "min", &raw.min, Some(record.max_axes.value));
            let max = self.bound(&at, "max", &raw.max, Some(record.max_axes.value));
            for (what, value) in [("min", min.value), ("max", max.value), ("default", raw.default)] {
                if !(0..=MAX_PARAMETER).contains(&value) {
                    self.report(&at, format!("{what} {value} is outside 0..={MAX_PARAMETER} (a Verilog integer)"));
                }
            }
            if !(min.value <= raw.default && raw.default <= max.value) {
                self.report(
                    &at,
                    format!("default {} is outside min..=max ({}..={})", raw.default, min.value, max.value),
                );
            }
            let caps = raw.caps.map(|text| {
                let field = self.field_ref(&at, &text);
                if max.value > i64::from(low_bits(field.width)) {
                    self.report(
                        &at,
                        format!("max {} does not fit its CAPS field {} ({} bits)", max.value, text, field.width),
                    );
                }
                field
            });
            parameters.push(ParameterSpec {
                name: raw.name,
                default: raw.default,
                min,
                max,
                caps,
                description: raw.description,
            });
        }
        self.unique(&owner, "parameter", parameters.iter().map(|p: &ParameterSpec| p.name.as_str()));
        let mut known: Vec<String> = parameters.iter().map(|p| p.name.clone()).collect();
        let mut derived = Vec::new();
        for raw in raw.derived {
            let at = place(format!("{owner}, derived {}", raw.name));
            self.name(&at, &raw.name);
            self.text(&at, &raw.description);
            if known.contains(&raw.name) {
                self.report(&at, format!("{} is already a parameter or a derived value", raw.name));
            }
            if let Some(value) = self.expression(&at, "value", &raw.value, &known) {
                derived.push(DerivedSpec {
                    name: raw.name.clone(),
                    value,
                    value_text: raw.value,
                    description: raw.description,
                });
            }
            known.push(raw.name);
        }
        let mut constraints = Vec::new();
        for raw in raw.constraints {
            let at = place(format!("{owner}, constraint {}", raw.name));
            self.text(&at, &raw.description);
            let identifier = raw.name.starts_with(|c: char| c.is_ascii_alphabetic())
                && raw.name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
            if !identifier {
                self.report(&at, format!("constraint name {:?} is not a Verilog identifier", raw.name));
            }
            let when = match &raw.when {
                Some(text) => self.expression(&at, "when", text, &known).map(Some),
                None => Some(None),
            };
            let require = self.expression(&at, "require", &raw.require, &known);
            if let (Some(when), Some(require)) = (when, require) {
                constraints.push(ConstraintSpec {
                    name: raw.name,
                    when,
                    require,
                    when_text: raw.when,
                    require_text: raw.require,
                    description: raw.description,
                });
            }
        }
        self.unique(&owner, "constraint", constraints.iter().map(|c: &ConstraintSpec| c.name.as_str()));
        ModuleSpec { name: raw.name, description: raw.description, parameters, derived, constraints }
    }

    /// `text` parsed, every name in `known`; else a problem and `None`.
    fn expression(&mut self, at: &Place, what: &str, text: &str, known: &[String]) -> Option<Expr> {
        match Expr::parse(text) {
            Ok(expr) => {
                let unknown: Vec<&str> = expr.names().into_iter().filter(|n| !known.iter().any(|k| k == n)).collect();
                if unknown.is_empty() {
                    Some(expr)
                } else {
                    let message =
                        format!("{what} reads {}: not a parameter or an earlier derived value", unknown.join(", "));
                    self.report(at, message);
                    None
                }
            }
            Err(message) => {
                self.report(at, format!("{what}: {message}"));
                None
            }
        }
    }

    /// Names across the whole description: enum and bit-set names unique, modules unique,
    /// and no generated Verilog constant the same as another or as one of the map's.
    fn names(&mut self, spec: &InterfaceSpec) {
        let kinds = spec.enums.iter().map(|e| e.name.as_str()).chain(spec.bitsets.iter().map(|b| b.name.as_str()));
        self.unique("interface", "enum or bit set", kinds);
        self.unique("interface", "module", spec.modules.iter().map(|m| m.name.as_str()));
        let mut owners: BTreeMap<String, String> = naming::verilog_constants(self.map)
            .into_iter()
            .map(|(name, owner)| (name, format!("the register map's {owner}")))
            .collect();
        for (name, owner) in verilog_names(spec) {
            if let Some(first) = owners.get(&name) {
                let message = format!("its Verilog constant {name} is also generated for {first}");
                self.report(&place(owner), message);
            } else {
                owners.insert(name, owner);
            }
        }
    }
}

/// Every Verilog constant `finestep_interface.vh` declares, with the part it belongs to,
/// in the order the header declares them.
pub fn verilog_names(spec: &InterfaceSpec) -> Vec<(String, String)> {
    let mut names = vec![
        ("FS_MAX_AXES".to_string(), "record".to_string()),
        ("FS_REC_INC_WIDTH".to_string(), "record".to_string()),
        ("FS_REC_INC_FRAC_BITS".to_string(), "record".to_string()),
        ("FS_REC_FLAGS_WIDTH".to_string(), "record".to_string()),
    ];
    for flag in &spec.record.flags {
        names.push((format!("FS_REC_FLAG_{}_BIT", flag.name), format!("record flag {}", flag.name)));
    }
    for name in ["FS_SPI_MAX_COUNT", "FS_SPI_CRC_POLYNOMIAL", "FS_SPI_CRC_INITIAL"] {
        names.push((name.to_string(), "spi".to_string()));
    }
    for command in &spec.spi.commands {
        names.push((format!("FS_SPI_CMD_{}", command.name), format!("spi command {}", command.name)));
    }
    for result in &spec.spi.results {
        names.push((format!("FS_SPI_RESULT_{}", result.name), format!("spi result {}", result.name)));
    }
    for enumeration in &spec.enums {
        let owner = format!("enum {}", enumeration.name);
        names.push((format!("FS_{}_WIDTH", enumeration.name), owner.clone()));
        for value in &enumeration.values {
            names.push((format!("FS_{}_{}", enumeration.name, value.name), owner.clone()));
        }
    }
    for bitset in &spec.bitsets {
        let owner = format!("bits {}", bitset.name);
        names.push((format!("FS_{}_WIDTH", bitset.name), owner.clone()));
        for bit in &bitset.bits {
            names.push((format!("FS_{}_{}_BIT", bitset.name, bit.name), owner.clone()));
        }
    }
    names.push(("FS_PBP_BITS_LANE".to_string(), "pbp".to_string()));
    names.push(("FS_PBP_BITS_LSB".to_string(), "pbp".to_string()));
    for field in spec.pbp.fields() {
        for what in ["LANE", "LSB", "WIDTH"] {
            names.push((format!("FS_PBP_{}_{what}", field.name), "pbp".to_string()));
        }
    }
    for module in &spec.modules {
        for parameter in &module.parameters {
            let owner = format!("module {}, parameter {}", module.name, parameter.name);
            for what in ["DEFAULT", "MIN", "MAX"] {
                names.push((
                    format!("FS_{}_{}_{what}", module.name.to_ascii_uppercase(), parameter.name),
                    owner.clone(),
                ));
            }
        }
    }
    names
}

//! LinuxCNC's parameter file (`[RS274NGC]PARAMETER_FILE`, e.g. `sim.var`): the numbered
//! parameters that outlive a program, read before it runs and written after it ends.
//!
//! The format is LinuxCNC's: one `index value` pair a line, indices ascending; lines that
//! do not start with such a pair are ignored when read (LinuxCNC skips them too). The
//! persistent parameters are LinuxCNC's required ones (G28 and G30 positions
//! #5161-#5169 and #5181-#5189, G92 #5210-#5219, the coordinate system in use #5220,
//! G54-G59.3 #5221-#5390) and any other parameter the file held, as LinuxCNC keeps a
//! parameter that its file lists. Values are in the machine unit
//! ([`crate::Options::machine_unit_mm`]), as LinuxCNC stores them.

use std::collections::BTreeMap;

/// Numbered parameters are #1 up to this one (LinuxCNC's RS274NGC_MAX_PARAMETERS - 1).
/// Defined here, the lowest module that needs it (the expressions read it too).
pub(crate) const MAX_PARAMETER: usize = 5601;

/// Why a parameter file was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ParameterFileError {
    /// An index outside #1-#5601.
    #[error("parameter file line {line}: parameter number {index} out of range (1 to {max})", max = MAX_PARAMETER)]
    OutOfRange {
        /// 1-based line in the file.
        line: usize,
        /// The index read.
        index: i64,
    },
    /// An index not above the one before it (LinuxCNC: "Parameter file out of order").
    #[error("parameter file line {line}: parameter {index} out of order (after {previous})")]
    OutOfOrder {
        /// 1-based line in the file.
        line: usize,
        /// The index read.
        index: usize,
        /// The index of the line before.
        previous: usize,
    },
    /// #5220 (the coordinate system in use) not 1 to 9.
    #[error("parameter 5220 (the coordinate system in use) is {value}: it must be 1 (G54) to 9 (G59.3)")]
    CoordinateSystem {
        /// The value given.
        value: f64,
    },
    /// A value that is not a finite number.
    #[error("parameter file line {line}: the value of parameter {index} is not a finite number")]
    NotFinite {
        /// 1-based line in the file.
        line: usize,
        /// The index read.
        index: usize,
    },
}

/// The parameters LinuxCNC always writes to its parameter file (its
/// `_required_parameters`): G28 and G30 positions, G92, the coordinate system in use and
/// the nine coordinate systems (X Y Z A B C U V W and the XY rotation R).
pub fn required_parameters() -> impl Iterator<Item = usize> {
    (5161..=5169)
        .chain(5181..=5189)
        .chain(5210..=5220)
        .chain((0..9).flat_map(|system| (5221 + 20 * system)..=(5230 + 20 * system)))
}

/// Numbered parameters with their values, as a parameter file holds them.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Parameters {
    /// Index to value (in machine units for lengths).
    pub values: BTreeMap<usize, f64>,
}

impl Parameters {
    /// Reads a parameter file's text.
    pub fn read(text: &str) -> Result<Parameters, ParameterFileError> {
        let mut values = BTreeMap::new();
        let mut previous: Option<usize> = None;
        for (i, raw) in text.lines().enumerate() {
            let line = i + 1;
            let mut fields = raw.split_whitespace();
            let (Some(index), Some(value)) = (fields.next(), fields.next()) else { continue };
            let (Ok(index), Ok(value)) = (index.parse::<i64>(), value.parse::<f64>()) else { continue };
            if !(1..=MAX_PARAMETER as i64).contains(&index) {
                return Err(ParameterFileError::OutOfRange { line, index });
            }
            let index = index as usize;
            if let Some(previous) = previous.filter(|&p| index <= p) {
                return Err(ParameterFileError::OutOfOrder { line, index, previous });
            }
            if !value.is_finite() {
                return Err(ParameterFileError::NotFinite { line, index });
            }
            previous = Some(index);
            values.insert(index, value);
        }
        Ok(Parameters { values })
    }

    /// The file's text: `index<TAB>value` lines in ascending order, six decimals
    /// (LinuxCNC's `%d\t%f`).
    pub fn to_text(&self) -> String {
        self.values.iter().map(|(index, value)| format!("{index}\t{value:.6}\n")).collect()
    }
}

/// Checks what the interpreter needs of parameters given before a program: #5220 in 1-9.
pub(crate) fn check(values: &BTreeMap<usize, f64>) -> Result<(), ParameterFileError> {
    match values.get(&5220) {
        Some(&value) if !(0.9999..=9.0001).contains(&value) => Err(ParameterFileError::CoordinateSystem { value }),
        _ => Ok(()),
    }
}

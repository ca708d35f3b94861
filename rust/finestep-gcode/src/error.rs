//! The one error type of the crate: where in which file, and what went wrong.

use std::fmt;

/// Why a part program was refused.
///
/// Parsing stops at the first error. [`GcodeError::Parse`] displays as
/// `file:line:col: message` with a 1-based line and a 1-based column (in characters)
/// that points at the offending word's letter (or character, for lexical errors);
/// errors about a whole move point at its motion word (the `G` word if the block has
/// one, else the first axis word).
#[derive(Debug, thiserror::Error)]
pub enum GcodeError {
    /// The program text is wrong at a place in it.
    #[error("{file}:{line}:{column}: {message}")]
    Parse {
        /// The file name given to the parser.
        file: String,
        /// 1-based source line.
        line: usize,
        /// 1-based column in characters.
        column: usize,
        /// What is wrong, e.g. `word X appears twice`.
        message: String,
    },
    /// The parameters given before the program (a parameter file) are refused.
    #[error("parameter file: {0}")]
    Parameters(#[from] crate::persistent::ParameterFileError),
    /// The file could not be read.
    #[error("{file}: {source}")]
    Io {
        /// The path as given.
        file: String,
        /// The underlying I/O error.
        #[source]
        source: std::io::Error,
    },
}

impl GcodeError {
    /// The 1-based line, for errors in the program text.
    pub fn line(&self) -> Option<usize> {
        match self {
            GcodeError::Parse { line, .. } => Some(*line),
            GcodeError::Io { .. } | GcodeError::Parameters(_) => None,
        }
    }

    /// The 1-based column, for errors in the program text.
    pub fn column(&self) -> Option<usize> {
        match self {
            GcodeError::Parse { column, .. } => Some(*column),
            GcodeError::Io { .. } | GcodeError::Parameters(_) => None,
        }
    }
}

/// An error located on a line, before the file and line are attached.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct LineError {
    pub column: usize,
    pub message: String,
}

impl LineError {
    pub(crate) fn new(column: usize, message: impl fmt::Display) -> Self {
        LineError { column, message: message.to_string() }
    }
}

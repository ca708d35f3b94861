//! The planner's error: the line of the block that cannot be planned and why.

use crate::config::ConfigError;

/// Why a program cannot be planned: the block's line and the reason.
#[derive(Clone, Debug, thiserror::Error, PartialEq)]
#[error("line {line}: {reason}")]
pub struct ProgramError {
    /// 1-based source line (0: not about one line).
    pub line: usize,
    /// What is wrong.
    pub reason: String,
}

impl From<ConfigError> for ProgramError {
    fn from(e: ConfigError) -> Self {
        ProgramError { line: 0, reason: e.to_string() }
    }
}

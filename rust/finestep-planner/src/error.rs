//! The planner's error: the line of the block that cannot be planned and why.

use crate::config::ConfigError;

/// Why a program cannot be planned: the block's line and the reason; or, for a program
/// read as it is planned ([`crate::plan_blocks`]), the parser's error where it stopped.
#[derive(Clone, Debug, PartialEq)]
pub struct ProgramError {
    /// 1-based source line (0: not about one line).
    pub line: usize,
    /// What is wrong.
    pub reason: String,
    /// The parser's error as it displays (`file:line:col: message`), when the program
    /// text is at fault.
    pub located: Option<String>,
}

impl ProgramError {
    /// The block on `line` cannot be planned, for `reason`.
    pub fn new(line: usize, reason: impl Into<String>) -> ProgramError {
        ProgramError { line, reason: reason.into(), located: None }
    }

    /// The parser refused the program text.
    pub fn parse(e: &finestep_gcode::GcodeError) -> ProgramError {
        ProgramError { line: e.line().unwrap_or(0), reason: e.to_string(), located: Some(e.to_string()) }
    }

    /// The error for a program named `name`: `name:line: reason`, or the parser's own
    /// `file:line:col: message`.
    pub fn in_file(&self, name: &str) -> String {
        match &self.located {
            Some(located) => located.clone(),
            None => format!("{name}:{}: {}", self.line, self.reason),
        }
    }
}

impl std::fmt::Display for ProgramError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match &self.located {
            Some(located) => f.write_str(located),
            None => write!(f, "line {}: {}", self.line, self.reason),
        }
    }
}

impl std::error::Error for ProgramError {}

impl From<ConfigError> for ProgramError {
    fn from(e: ConfigError) -> Self {
        ProgramError::new(0, e.to_string())
    }
}

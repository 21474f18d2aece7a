//! CLI errors: a one-line message and an exit status (2 = bad input, 1 = the
//! computation failed).

use std::fmt;

/// An error that ends the command.
#[derive(Debug)]
pub struct CliError {
    /// Exit status.
    pub code: u8,
    /// One line, no trailing newline.
    pub msg: String,
}

impl CliError {
    /// Bad input (exit status 2).
    pub fn usage(msg: impl Into<String>) -> Self {
        CliError {
            code: 2,
            msg: msg.into(),
        }
    }
    /// The same error with `at …` appended (where in a map or a sweep it happened).
    pub fn with_context(self, at: &str) -> Self {
        CliError {
            code: self.code,
            msg: format!("{} (at {at})", self.msg),
        }
    }
    /// The same error with a leading `from:` (a flag name) replaced by
    /// `to:`: for a value a command derived from another flag (`--v-rel`
    /// gives the `--v0` that a shared function checks).
    pub fn renamed(self, from: &str, to: &str) -> Self {
        match self.msg.strip_prefix(from) {
            Some(rest) if rest.starts_with(':') => CliError {
                code: self.code,
                msg: format!("{to}{rest}"),
            },
            _ => self,
        }
    }
    /// The computation or I/O failed (exit status 1).
    pub fn failure(msg: impl Into<String>) -> Self {
        CliError {
            code: 1,
            msg: msg.into(),
        }
    }
}

impl fmt::Display for CliError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.msg)
    }
}

/// Result of a command.
pub type CliResult<T = ()> = Result<T, CliError>;

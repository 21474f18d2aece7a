//! Errors of the analysis: a one-line message naming the parameter, and its
//! class — bad input (the CLI's exit status 2, Python's `ValueError`) or a
//! computation that failed (exit status 1, `fricctl.SolverError`).

use std::fmt;

/// An error that ends a computation.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Error {
    /// Its class as the CLI's exit status: 2 = bad input, 1 = the
    /// computation failed.
    pub code: u8,
    /// One line, no trailing newline, naming the parameter as its CLI flag
    /// (`--mu0: must be > 0 (got -1)`).
    pub msg: String,
}

impl Error {
    /// Bad input (exit status 2).
    pub fn usage(msg: impl Into<String>) -> Self {
        Error {
            code: 2,
            msg: without_os_error(msg.into()),
        }
    }
    /// The same error with `at …` appended (where in a map or a sweep it happened).
    pub fn with_context(self, at: &str) -> Self {
        Error {
            code: self.code,
            msg: format!("{} (at {at})", self.msg),
        }
    }
    /// The same error with a leading `from:` (a flag name) replaced by
    /// `to:`: for a value a command derived from another flag (`--v-rel`
    /// gives the `--v0` that a shared function checks).
    pub fn renamed(self, from: &str, to: &str) -> Self {
        match self.msg.strip_prefix(from) {
            Some(rest) if rest.starts_with(':') => Error {
                code: self.code,
                msg: format!("{to}{rest}"),
            },
            _ => self,
        }
    }
    /// The computation or I/O failed (exit status 1).
    pub fn failure(msg: impl Into<String>) -> Self {
        Error {
            code: 1,
            msg: without_os_error(msg.into()),
        }
    }
    /// Whether the input was bad (rather than the computation failing).
    pub fn is_bad_input(&self) -> bool {
        self.code == 2
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.msg)
    }
}

impl std::error::Error for Error {}

/// Result of an analysis.
pub type Result<T = (), E = Error> = std::result::Result<T, E>;

/// `msg` without the ` (os error N)` that `std::io::Error` appends to its
/// reason (`No such file or directory (os error 2)`): the reason is for the
/// user, the number for the C library.
fn without_os_error(mut msg: String) -> String {
    while let Some(i) = msg.find(" (os error ") {
        let rest = &msg[i + " (os error ".len()..];
        let digits = rest.bytes().take_while(u8::is_ascii_digit).count();
        if digits == 0 || rest.as_bytes().get(digits) != Some(&b')') {
            break;
        }
        msg.replace_range(i..i + " (os error ".len() + digits + 1, "");
    }
    msg
}

#[cfg(test)]
mod os_error_tests {
    use super::*;

    #[test]
    fn the_os_error_number_is_dropped_from_messages() {
        let e = std::io::Error::from_raw_os_error(2);
        let m = Error::usage(format!("--data: cannot read /nope.csv: {e}")).msg;
        assert_eq!(
            m,
            "--data: cannot read /nope.csv: No such file or directory"
        );
        let m = Error::failure("a (os error 13) and b (os error 2)").msg;
        assert_eq!(m, "a and b");
        // Text that only looks like it stays.
        assert_eq!(Error::usage("x (os error y)").msg, "x (os error y)");
    }
}

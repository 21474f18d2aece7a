//! Numeric flags: the one place where a flag's text becomes a number.
//!
//! Every numeric flag of every command is read by one of two clap value
//! parsers, [`Real`] (a real number in a stated domain) or [`Count`] (a whole
//! number in a stated range, written like any number: `1e6`). Both refuse
//! with one reason, printed by `main` as `--flag: reason` (exit status 2),
//! and echo the value as the user typed it:
//!
//! * `'abc' is not a number`, `'nan' is not a number`;
//! * the flag's own range: `must be > 0 (got -1)`, `must be < 1 (got inf)`;
//! * the magnitude every real flag shares ([`MAX_MAGNITUDE`],
//!   [`MIN_MAGNITUDE`]): `must be of magnitude ≤ 1e100 (got 1e308)`,
//!   `must be 0 or of magnitude ≥ 1e-100 (got 1e-320)`. No physical input
//!   of this tool comes near these bounds, and within them products and
//!   quotients of a few inputs stay normal `f64` numbers, so no command
//!   meets an overflow, an underflow or a subnormal number (which has lost
//!   precision) that came from a flag;
//! * counts: `must be a whole number (got 2.5)`, `must be ≤ 1000 (got 1e9)`.
//!
//! [`numbers_take_hyphens`] lets every numeric flag take a value that starts
//! with `-` (`--tol -1`, `--amp-z=-2e-6`, `--v0 -inf`), so that a negative
//! value reaches the parser and is refused by name instead of being read as
//! an unknown option. Numbers in messages are written by [`short`].

use std::ffi::OsStr;
use std::marker::PhantomData;

use clap::builder::TypedValueParser;

pub use device_host::periods::Periods;
pub use fric_analysis::numbers::{round_up_sig, short, Refused, Rounded, Short};

/// The domain of a real-valued flag ([`fric_analysis::numbers::Real`], the
/// library's one check) as a clap value parser
/// (`value_parser = Real::positive()`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Real(pub fric_analysis::numbers::Real);

impl Real {
    /// Any number (within the shared magnitude bounds).
    pub const ANY: Real = Real(fric_analysis::numbers::Real::ANY);

    /// `x > 0`.
    pub const fn positive() -> Real {
        Real(fric_analysis::numbers::Real::positive())
    }

    /// `x ≥ 0`.
    pub const fn non_negative() -> Real {
        Real(fric_analysis::numbers::Real::non_negative())
    }

    /// Also `x ≥ lo`.
    pub const fn at_least(self, lo: f64) -> Real {
        Real(self.0.at_least(lo))
    }

    /// Also `x ≤ hi`.
    pub const fn at_most(self, hi: f64) -> Real {
        Real(self.0.at_most(hi))
    }

    /// For a value sent to the device as an `f32` (library docs).
    pub const fn single_precision(self) -> Real {
        Real(self.0.single_precision())
    }

    /// The reason of the range, appended to a refusal.
    pub const fn because(self, why: &'static str) -> Real {
        Real(self.0.because(why))
    }

    /// Reads `text` as a number of this domain.
    ///
    /// # Errors
    /// The reason it is not one (module docs), echoing `text`.
    pub fn parse(&self, text: &str) -> Result<f64, Refused> {
        self.0.parse(text)
    }

    /// Checks a number given as `x`, echoing it as `shown`.
    ///
    /// # Errors
    /// The reason it is outside the domain.
    pub fn check(&self, x: f64, shown: &str) -> Result<f64, Refused> {
        self.0.check(x, shown)
    }
}

impl From<fric_analysis::numbers::Real> for Real {
    fn from(r: fric_analysis::numbers::Real) -> Real {
        Real(r)
    }
}

impl TypedValueParser for Real {
    type Value = f64;

    fn parse_ref(
        &self,
        cmd: &clap::Command,
        arg: Option<&clap::Arg>,
        value: &OsStr,
    ) -> Result<f64, clap::Error> {
        // clap's own parser for `Fn(&str)` attaches the flag and the value
        // to the error (`main` prints them).
        let me = *self;
        (move |s: &str| me.parse(s)).parse_ref(cmd, arg, value)
    }
}

/// A whole number in `[min, max]`, written as any number (`1000`, `1e3`,
/// `1000.0`): the clap value parser of counts. Negative values and values
/// below `min` answer "must be ≥ min", fractions "must be a whole number",
/// values beyond `max` (at most `T`'s largest) "must be ≤ max".
#[derive(Debug)]
pub struct Count<T> {
    min: u64,
    max: u64,
    why: Option<&'static str>,
    ty: PhantomData<fn() -> T>,
}

impl<T> Clone for Count<T> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<T> Copy for Count<T> {}

impl<T: Bounded> Count<T> {
    /// At least `min`, at most `T`'s largest value.
    pub const fn at_least(min: u64) -> Self {
        Count {
            min,
            max: T::MAX_U64,
            why: None,
            ty: PhantomData,
        }
    }

    /// Also at most `max`, for the reason `why` (appended to the refusal).
    pub const fn at_most(self, max: u64, why: &'static str) -> Self {
        Count {
            max: if max < T::MAX_U64 { max } else { T::MAX_U64 },
            why: Some(why),
            ..self
        }
    }

    /// Reads `s` as a count.
    ///
    /// # Errors
    /// The reason it is not one, echoing `s`.
    pub fn parse(&self, s: &str) -> Result<T, Refused>
    where
        T: TryFrom<u64>,
    {
        let why = self.why.map_or(String::new(), |w| format!("; {w}"));
        // Digits: read exactly as an integer (a seed above 2⁵³ is not
        // rounded through f64).
        if let Ok(n) = s.trim().trim_start_matches('+').parse::<i128>() {
            if n < i128::from(self.min) {
                return Err(Refused(format!("must be ≥ {} (got {s})", self.min)));
            }
            if n > i128::from(self.max) {
                return Err(Refused(format!("must be ≤ {} (got {s}{why})", self.max)));
            }
            let n = n as u64;
            return T::try_from(n)
                .map_err(|_| Refused(format!("must be ≤ {} (got {s}{why})", self.max)));
        }
        let x: f64 = s
            .trim()
            .parse()
            .map_err(|_| Refused(format!("'{s}' is not a number")))?;
        if x.is_nan() {
            return Err(Refused(format!("'{s}' is not a number")));
        }
        // Any other form (`1e3`, `1000.0`) through f64, exact only up to
        // 2⁵³: above, the text's value may have been rounded.
        if x.abs() > 9_007_199_254_740_992.0 && x <= self.max as f64 {
            return Err(Refused(format!(
                "above 2^53 write it in digits (got {s}: as a decimal number it may round)"
            )));
        }
        if x < self.min as f64 {
            return Err(Refused(format!("must be ≥ {} (got {s})", self.min)));
        }
        // 2⁶⁴: `u64::MAX as f64` rounds up to it, so it is tested apart.
        if x > self.max as f64 || x >= 18_446_744_073_709_551_616.0 {
            return Err(Refused(format!("must be ≤ {} (got {s}{why})", self.max)));
        }
        if x.fract() != 0.0 {
            return Err(Refused(format!("must be a whole number (got {s})")));
        }
        let n = x as u64;
        if n > self.max {
            return Err(Refused(format!("must be ≤ {} (got {s}{why})", self.max)));
        }
        T::try_from(n).map_err(|_| Refused(format!("must be ≤ {} (got {s}{why})", self.max)))
    }
}

impl<T> TypedValueParser for Count<T>
where
    T: Bounded + TryFrom<u64> + Clone + Send + Sync + 'static,
{
    type Value = T;

    fn parse_ref(
        &self,
        cmd: &clap::Command,
        arg: Option<&clap::Arg>,
        value: &OsStr,
    ) -> Result<T, clap::Error> {
        let me = *self;
        (move |s: &str| me.parse(s)).parse_ref(cmd, arg, value)
    }
}

/// The largest value of an unsigned count type.
pub trait Bounded {
    /// `Self::MAX` as `u64`.
    const MAX_U64: u64;
}

impl Bounded for u32 {
    const MAX_U64: u64 = u32::MAX as u64;
}

impl Bounded for u64 {
    const MAX_U64: u64 = u64::MAX;
}

impl Bounded for usize {
    const MAX_U64: u64 = usize::MAX as u64;
}

/// Whether an argument takes a number (its value type is `f64`, `u32`,
/// `u64` or `usize`).
pub fn is_numeric(a: &clap::Arg) -> bool {
    use std::any::TypeId;
    let t = a.get_value_parser().type_id();
    a.get_action().takes_values()
        && [
            TypeId::of::<f64>(),
            TypeId::of::<u32>(),
            TypeId::of::<u64>(),
            TypeId::of::<usize>(),
            // `--periods auto|N` of `device control` and `control-bench`.
            TypeId::of::<Periods>(),
        ]
        .iter()
        .any(|id| t == *id)
}

/// Lets every numeric option of `cmd` and its subcommands take a value that
/// starts with `-` (`--tol -1`, `--amp-z -2e-6`, `--v0 -inf`): the value
/// reaches the flag's parser, which refuses it by name where it is invalid,
/// instead of being read as an unknown option.
pub fn numbers_take_hyphens(cmd: clap::Command) -> clap::Command {
    cmd.mut_args(|a| {
        if is_numeric(&a) {
            a.allow_hyphen_values(true)
        } else {
            a
        }
    })
    .mut_subcommands(numbers_take_hyphens)
}

/// The one line `fricctl` prints for a clap error (without `error: `):
/// `--flag: reason` for a value our parsers refused, `--flag: given twice`,
/// `--flag: missing`, `--flag: unknown option`, clap's first line otherwise.
pub fn clap_message(e: &clap::Error) -> String {
    use clap::error::{ContextKind, ContextValue, ErrorKind};
    use std::error::Error as _;
    let ctx = |k: ContextKind| match e.get(k) {
        Some(ContextValue::String(s)) => Some(s.clone()),
        Some(ContextValue::Strings(v)) => Some(v.join(", ")),
        _ => None,
    };
    let arg = ctx(ContextKind::InvalidArg)
        .map(|a| a.split_whitespace().next().unwrap_or("").to_string())
        .unwrap_or_default();
    let msg = match e.kind() {
        ErrorKind::ValueValidation if refused(e).is_some() => {
            format!("{arg}: {}", refused(e).unwrap_or_default())
        }
        ErrorKind::InvalidValue if e.get(ContextKind::ValidValue).is_some() => {
            let val = ctx(ContextKind::InvalidValue).unwrap_or_default();
            let valid = ctx(ContextKind::ValidValue).unwrap_or_default();
            format!("{arg}: invalid value '{val}' (one of: {valid})")
        }
        ErrorKind::InvalidValue | ErrorKind::ValueValidation => {
            let val = ctx(ContextKind::InvalidValue).unwrap_or_default();
            let reason = e
                .source()
                .map(|s| s.to_string())
                .unwrap_or_else(|| "invalid value".to_string());
            format!("{arg}: invalid value '{val}': {reason}")
        }
        ErrorKind::MissingRequiredArgument => {
            let what = ctx(ContextKind::InvalidArg).unwrap_or_default();
            format!(
                "{}: missing",
                what.split_whitespace().next().unwrap_or("argument")
            )
        }
        ErrorKind::ArgumentConflict => {
            let other = ctx(ContextKind::PriorArg).unwrap_or_default();
            let other = other.split_whitespace().next().unwrap_or("");
            // clap reports a flag given twice (`ArgAction::Set`) as a
            // conflict with itself.
            if other == arg {
                format!("{arg}: given twice (give it once)")
            } else {
                format!("{arg}: cannot be used with {other}")
            }
        }
        ErrorKind::UnknownArgument => format!(
            "{}: unknown option",
            ctx(ContextKind::InvalidArg).unwrap_or_default()
        ),
        _ => {
            // Fall back to clap's first line.
            let s = e.render().to_string();
            s.lines()
                .next()
                .unwrap_or("invalid arguments")
                .trim_start_matches("error: ")
                .to_string()
        }
    };
    msg
}

/// The reason of a value refused by one of our value parsers ([`Refused`]).
fn refused(e: &clap::Error) -> Option<String> {
    use std::error::Error as _;
    e.source()
        .and_then(|s| s.downcast_ref::<Refused>())
        .map(|r| r.to_string())
}

/// `--periods`: `auto` or a whole number ≥ 1 (the device refuses more
/// than `CONTROL_MAX_PERIODS` by name).
pub fn parse_periods(s: &str) -> Result<Periods, Refused> {
    if s == "auto" {
        return Ok(Periods::Auto);
    }
    if s.trim().parse::<f64>().is_err() {
        return Err(Refused(format!("'{s}' is neither `auto` nor a number")));
    }
    Count::<u32>::at_least(1).parse(s).map(Periods::Fixed)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn count<T: Bounded + TryFrom<u64>>(min: u64, s: &str) -> Result<T, Refused> {
        Count::<T>::at_least(min).parse(s)
    }

    fn refused(s: &str) -> Refused {
        Refused(s.to_string())
    }

    #[test]
    fn counts_read_like_numbers() {
        assert_eq!(count::<usize>(2, "1e6"), Ok(1_000_000));
        assert_eq!(count::<usize>(2, "12"), Ok(12));
        assert_eq!(count::<u32>(1, "3.0"), Ok(3));
        assert_eq!(
            count::<usize>(2, "-5"),
            Err(refused("must be ≥ 2 (got -5)"))
        );
        assert_eq!(count::<u32>(1, "0"), Err(refused("must be ≥ 1 (got 0)")));
        assert_eq!(
            count::<u32>(1, "2.5"),
            Err(refused("must be a whole number (got 2.5)"))
        );
        assert_eq!(
            count::<u32>(1, "5e9"),
            Err(refused("must be ≤ 4294967295 (got 5e9)"))
        );
        assert_eq!(count::<u32>(1, "x"), Err(refused("'x' is not a number")));
        assert_eq!(
            count::<u32>(1, "NaN"),
            Err(refused("'NaN' is not a number"))
        );
        assert_eq!(
            count::<u32>(1, "inf"),
            Err(refused("must be ≤ 4294967295 (got inf)"))
        );
        assert_eq!(
            count::<u64>(1, "1e300"),
            Err(refused("must be ≤ 18446744073709551615 (got 1e300)"))
        );
        // 2^64 rounds to u64::MAX as f64 but is not a u64.
        assert_eq!(
            count::<u64>(1, "18446744073709551616"),
            Err(refused(
                "must be ≤ 18446744073709551615 (got 18446744073709551616)"
            ))
        );
        assert_eq!(
            Count::<usize>::at_least(1)
                .at_most(1000, "a bound")
                .parse("1e9"),
            Err(refused("must be ≤ 1000 (got 1e9; a bound)"))
        );
    }

    /// Issue 41 §3: digits are read as an integer, exactly — 2⁵³ + 1 is not
    /// rounded to 2⁵³, u64::MAX is taken; a decimal form above 2⁵³ is
    /// refused rather than rounded.
    #[test]
    fn counts_in_digits_are_exact() {
        assert_eq!(
            count::<u64>(0, "9007199254740993"),
            Ok(9_007_199_254_740_993)
        );
        assert_eq!(count::<u64>(0, "18446744073709551615"), Ok(u64::MAX));
        assert_eq!(count::<u64>(0, "+7"), Ok(7));
        assert_eq!(count::<u64>(0, " 12 "), Ok(12));
        assert_eq!(
            count::<u64>(0, "1e19"),
            Err(refused(
                "above 2^53 write it in digits (got 1e19: as a decimal number it may round)"
            ))
        );
        assert_eq!(count::<u64>(0, "9e15"), Ok(9_000_000_000_000_000));
        assert_eq!(
            count::<u32>(1, "4294967296"),
            Err(refused("must be ≤ 4294967295 (got 4294967296)"))
        );
    }
}

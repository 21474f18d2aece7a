//! Numbers in, numbers in messages: the domain of every real input
//! ([`Real`]: a finite number within a stated range and within the
//! magnitude every input shares) and the short text of a number ([`short`]).
//!
//! A value outside its domain is refused with one reason, which the caller
//! prefixes with the parameter's name (`--mu0: must be > 0 (got -1)`), echoing
//! the value as the user gave it:
//!
//! * `'nan' is not a number`;
//! * the input's own range: `must be > 0 (got -1)`, `must be < 1 (got inf)`;
//! * the magnitude every real input shares ([`MAX_MAGNITUDE`],
//!   [`MIN_MAGNITUDE`]): `must be of magnitude ≤ 1e100 (got 1e308)`,
//!   `must be 0 or of magnitude ≥ 1e-100 (got 1e-320)`. No physical input
//!   comes near these bounds, and within them products and quotients of a
//!   few inputs stay normal `f64` numbers, so no computation meets an
//!   overflow, an underflow or a subnormal number that came from an input.

use std::fmt;

/// Largest magnitude of a real flag's value.
pub const MAX_MAGNITUDE: f64 = 1e100;
/// Smallest magnitude of a non-zero real flag's value.
pub const MIN_MAGNITUDE: f64 = 1e-100;

/// Why a value was refused; the caller prints it as `--flag: reason`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Refused(pub String);

impl fmt::Display for Refused {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for Refused {}

/// A number as messages and text output write it: the shortest text that
/// reads back as the same `f64`, in plain notation for magnitudes in
/// `[1e-4, 1e9)` (`0.3`, `40000`) and in scientific notation outside
/// (`1e308`, `2.5e-12`), so that no number takes more than 24 characters.
pub fn short(x: f64) -> String {
    let a = x.abs();
    if x == 0.0 || !x.is_finite() || (1e-4..1e9).contains(&a) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// [`short`] as a `Display` value, for `format!` arguments.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Short(pub f64);

impl fmt::Display for Short {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&short(self.0))
    }
}

/// A computed result as text output writes it: rounded to 12 significant
/// digits, then [`short`]. The results printed this way carry error bounds
/// of 1e-12 relative or more (the exact solver's are ≥ 1e-9 μ0), so the
/// digits beyond the twelfth are f64 rounding noise (`0.5300000000000002`
/// is 0.53 + 2 ulp): they are dropped, and `0.53` is printed. Input values
/// in messages keep [`short`] (they read back exactly).
pub fn rounded(x: f64) -> String {
    short(round_sig(x, 12))
}

/// `x` rounded to `digits` significant digits (1 … 17); 0, infinities and
/// NaN unchanged. An error bound is printed to 3 (`1.35e-9`).
pub fn round_sig(x: f64, digits: usize) -> f64 {
    if x == 0.0 || !x.is_finite() {
        return x;
    }
    let p = digits.clamp(1, 17) - 1;
    format!("{x:.p$e}").parse().unwrap_or(x)
}

/// A bound as text output writes it: `x ≥ 0` rounded *up* to `digits`
/// significant digits, so that the printed bound still bounds
/// (`1.3499999999999999e-9` → 1.35e-9, `1.231e-9` → 1.24e-9 at 3 digits).
pub fn round_up_sig(x: f64, digits: usize) -> f64 {
    let r = round_sig(x, digits);
    if r >= x || !x.is_finite() {
        return r;
    }
    let p = digits.clamp(1, 17) as i32 - 1;
    let step = 10f64.powi(x.abs().log10().floor() as i32 - p);
    round_sig(r + step, digits)
}

/// [`rounded`] as a `Display` value, for `format!` arguments.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rounded(pub f64);

impl fmt::Display for Rounded {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&rounded(self.0))
    }
}

/// One end of a [`Real`] domain.
#[derive(Debug, Clone, Copy, PartialEq)]
enum End {
    /// No bound (beyond the shared magnitude).
    Open,
    /// `x ≥ v` (lower end) or `x ≤ v` (upper end).
    Incl(f64),
    /// `x > v` (lower end) or `x < v` (upper end).
    Excl(f64),
}

/// The domain of a real-valued input: a finite number within its own range
/// and within the shared magnitude bounds (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Real {
    lo: End,
    hi: End,
    /// Appended to a range refusal (`must be < 1 (got 2); why`).
    why: Option<&'static str>,
    /// Smallest non-zero and largest magnitude.
    magnitude: (f64, f64),
    /// `inf` is a value of its own (e.g. "no load"), beyond the magnitude.
    infinity: bool,
}

impl Real {
    /// Any number (within the shared magnitude bounds).
    pub const ANY: Real = Real {
        lo: End::Open,
        hi: End::Open,
        why: None,
        magnitude: (MIN_MAGNITUDE, MAX_MAGNITUDE),
        infinity: false,
    };

    /// `x > 0`.
    pub const fn positive() -> Real {
        Real::ANY.above(0.0)
    }

    /// `x ≥ 0`.
    pub const fn non_negative() -> Real {
        Real::ANY.at_least(0.0)
    }

    /// Also `x ≥ lo`.
    pub const fn at_least(self, lo: f64) -> Real {
        Real {
            lo: End::Incl(lo),
            ..self
        }
    }

    /// Also `x > lo`.
    pub const fn above(self, lo: f64) -> Real {
        Real {
            lo: End::Excl(lo),
            ..self
        }
    }

    /// Also `x ≤ hi`.
    pub const fn at_most(self, hi: f64) -> Real {
        Real {
            hi: End::Incl(hi),
            ..self
        }
    }

    /// Also `x < hi`.
    pub const fn below(self, hi: f64) -> Real {
        Real {
            hi: End::Excl(hi),
            ..self
        }
    }

    /// For a value sent to the device as an `f32`: its magnitude within the
    /// normal `f32` numbers, rounded inwards to `1.2e-38 … 3.4e38`, instead
    /// of the shared bounds, so that it neither overflows nor loses
    /// precision on the way.
    pub const fn single_precision(self) -> Real {
        Real {
            magnitude: (1.2e-38, 3.4e38),
            ..self
        }
    }

    /// Also accepts `inf` (where the flag gives it a meaning of its own,
    /// such as "none"); `-inf` only if the range admits it.
    pub const fn or_infinity(self) -> Real {
        Real {
            infinity: true,
            ..self
        }
    }

    /// The reason of the range, appended to a refusal.
    pub const fn because(self, why: &'static str) -> Real {
        Real {
            why: Some(why),
            ..self
        }
    }

    /// Reads `text` as a number of this domain.
    ///
    /// # Errors
    /// The reason it is not one (module docs), echoing `text`.
    pub fn parse(&self, text: &str) -> Result<f64, Refused> {
        let x: f64 = text
            .trim()
            .parse()
            .map_err(|_| Refused(format!("'{text}' is not a number")))?;
        self.check(x, text)
    }

    /// Checks a number given as `x` (from a file, or computed from flags),
    /// echoing it as `shown`.
    ///
    /// # Errors
    /// The reason it is outside the domain.
    pub fn check(&self, x: f64, shown: &str) -> Result<f64, Refused> {
        if x.is_nan() {
            return Err(Refused(format!("'{shown}' is not a number")));
        }
        let why = self.why.map_or(String::new(), |w| format!("; {w}"));
        let refuse = |rule: String| Err(Refused(format!("must be {rule} (got {shown}{why})")));
        match self.lo {
            End::Incl(lo) if x < lo => return refuse(format!("≥ {}", short(lo))),
            End::Excl(lo) if x <= lo => return refuse(format!("> {}", short(lo))),
            _ => {}
        }
        match self.hi {
            End::Incl(hi) if x > hi => return refuse(format!("≤ {}", short(hi))),
            End::Excl(hi) if x >= hi => return refuse(format!("< {}", short(hi))),
            _ => {}
        }
        let a = x.abs();
        // Whether the domain holds negative numbers (the message says
        // "magnitude" only then) and 0.
        let negatives = match self.lo {
            End::Open => true,
            End::Incl(lo) | End::Excl(lo) => lo < 0.0,
        };
        let zero = self.admits(0.0);
        if self.infinity && x.is_infinite() {
            return Ok(x);
        }
        let (min, max) = self.magnitude;
        if a > max {
            let rule = if negatives {
                format!("of magnitude ≤ {}", short(max))
            } else {
                format!("≤ {}", short(max))
            };
            return Err(Refused(format!("must be {rule} (got {shown})")));
        }
        if a != 0.0 && a < min {
            let rule = match (zero, negatives) {
                (true, _) => format!("0 or of magnitude ≥ {}", short(min)),
                (false, true) => format!("of magnitude ≥ {}", short(min)),
                (false, false) => format!("≥ {}", short(min)),
            };
            return Err(Refused(format!("must be {rule} (got {shown})")));
        }
        // −0 is 0 (so that no result or message shows "-0").
        Ok(x + 0.0)
    }

    /// Whether `x` lies within the flag's own range (not the magnitude bounds).
    fn admits(&self, x: f64) -> bool {
        let lo = match self.lo {
            End::Open => true,
            End::Incl(lo) => x >= lo,
            End::Excl(lo) => x > lo,
        };
        let hi = match self.hi {
            End::Open => true,
            End::Incl(hi) => x <= hi,
            End::Excl(hi) => x < hi,
        };
        lo && hi
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn refused(s: &str) -> Refused {
        Refused(s.to_string())
    }

    #[test]
    fn reals_name_the_limit_and_echo_the_value() {
        let p = Real::positive();
        assert_eq!(p.parse("0.5"), Ok(0.5));
        assert_eq!(p.parse("-1"), Err(refused("must be > 0 (got -1)")));
        assert_eq!(p.parse("-inf"), Err(refused("must be > 0 (got -inf)")));
        assert_eq!(p.parse("inf"), Err(refused("must be ≤ 1e100 (got inf)")));
        assert_eq!(
            p.parse("1e308"),
            Err(refused("must be ≤ 1e100 (got 1e308)"))
        );
        assert_eq!(
            p.parse("1e-320"),
            Err(refused("must be ≥ 1e-100 (got 1e-320)"))
        );
        assert_eq!(p.parse("nan"), Err(refused("'nan' is not a number")));
        assert_eq!(p.parse("1,5"), Err(refused("'1,5' is not a number")));
        let any = Real::ANY;
        assert_eq!(any.parse("-0"), Ok(0.0));
        assert_eq!(
            any.parse("-1e308"),
            Err(refused("must be of magnitude ≤ 1e100 (got -1e308)"))
        );
        assert_eq!(
            any.parse("-1e-320"),
            Err(refused("must be 0 or of magnitude ≥ 1e-100 (got -1e-320)"))
        );
        let unit = Real::ANY
            .above(-1.0)
            .below(1.0)
            .because("|μ| = μ0 is sliding");
        assert_eq!(
            unit.parse("1e300"),
            Err(refused("must be < 1 (got 1e300; |μ| = μ0 is sliding)"))
        );
        assert_eq!(
            Real::non_negative().parse("1e-200"),
            Err(refused("must be 0 or of magnitude ≥ 1e-100 (got 1e-200)"))
        );
    }

    #[test]
    fn rounded_numbers_drop_float_noise_only() {
        // The examples: each is a short decimal plus a few ulp.
        assert_eq!(rounded(0.53 + 2.0 * f64::EPSILON * 0.5), "0.53");
        assert_eq!(rounded(-0.7000000000000001), "-0.7");
        assert_eq!(rounded(1.4000000000000001), "1.4");
        assert_eq!(rounded(1.3499999999999999e-9), "1.35e-9");
        assert_eq!(rounded(0.5300000000000002), "0.53");
        // Twelve digits kept: a result differing in the 12th digit stays apart.
        assert_eq!(rounded(0.112389322493595), "0.112389322494");
        assert_eq!(rounded(-1.23456789012e-7), "-1.23456789012e-7");
        // Within 5e-12 relative of the value (half a unit of the 12th digit).
        for x in [1.0 / 3.0, -2.0 / 7.0, 123456.789012345, 9.87654321e-6] {
            let r: f64 = rounded(x).parse().unwrap();
            assert!((r - x).abs() <= 5e-12 * x.abs(), "{x} {r}");
        }
        assert_eq!(rounded(0.0), "0");
        assert_eq!(short(round_sig(3.6198584246e-10, 3)), "3.62e-10");
        assert_eq!(short(round_sig(0.00995, 1)), "0.01");
        // Bounds round up: never below the value.
        assert_eq!(short(round_up_sig(1.3499999999999999e-9, 3)), "1.35e-9");
        assert_eq!(short(round_up_sig(1.231e-9, 3)), "1.24e-9");
        assert_eq!(short(round_up_sig(2e-9, 3)), "2e-9");
        assert_eq!(short(round_up_sig(9.996e-3, 3)), "0.01");
        for x in [1.0 / 3.0, 2.7e-9 - 1e-24, 4.0801100972520985e-10, 123.4567] {
            assert!(round_up_sig(x, 3) >= x, "{x}");
            assert!(round_up_sig(x, 3) <= x * (1.0 + 1e-2), "{x}");
        }
        assert_eq!(rounded(f64::NAN), "NaN");
    }

    #[test]
    fn short_numbers() {
        assert_eq!(short(0.3), "0.3");
        assert_eq!(short(-0.0), "-0");
        assert_eq!(short(40e3), "40000");
        assert_eq!(short(1e308), "1e308");
        assert_eq!(short(1e-320), "1e-320");
        assert_eq!(short(2.5e-12), "2.5e-12");
        assert_eq!(short(f64::INFINITY), "inf");
        for x in [
            f64::MAX,
            f64::MIN_POSITIVE,
            5e-324,
            1.0 / 3.0,
            -7.123456789e-5,
        ] {
            assert!(short(x).len() <= 24, "{x}");
            assert_eq!(short(x).parse::<f64>(), Ok(x));
        }
    }
}

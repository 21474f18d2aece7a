//! Numeric argument values: counts read like every other number (`1e6`,
//! `-5`), then checked, with the reason shown as `--flag: reason`.

use std::fmt;

/// Why a value was refused; `main` prints it as `--flag: reason` (without
/// clap's "invalid value" wrapper).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Refused(pub String);

impl fmt::Display for Refused {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for Refused {}

/// A whole number ≥ `MIN`, written as any number (`1000`, `1e3`, `1000.0`):
/// the clap value parser of counts. Negative values and values below `MIN`
/// answer "must be ≥ MIN", fractions "must be a whole number", values beyond
/// `T` "must be ≤ T::MAX".
pub fn count<T, const MIN: u64>(s: &str) -> Result<T, Refused>
where
    T: TryFrom<u64> + Bounded,
{
    let x: f64 = s
        .trim()
        .parse()
        .map_err(|_| Refused(format!("'{s}' is not a number")))?;
    if x.is_nan() {
        return Err(Refused(format!("'{s}' is not a number")));
    }
    if x < MIN as f64 {
        return Err(Refused(format!("must be ≥ {MIN}")));
    }
    if x > T::MAX_U64 as f64 {
        return Err(Refused(format!("must be ≤ {}", T::MAX_U64)));
    }
    if x.fract() != 0.0 {
        return Err(Refused(format!("must be a whole number (got {s})")));
    }
    T::try_from(x as u64).map_err(|_| Refused(format!("must be ≤ {}", T::MAX_U64)))
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_read_like_numbers() {
        assert_eq!(count::<usize, 2>("1e6"), Ok(1_000_000));
        assert_eq!(count::<usize, 2>("12"), Ok(12));
        assert_eq!(count::<u32, 1>("3.0"), Ok(3));
        assert_eq!(count::<usize, 2>("-5"), Err(Refused("must be ≥ 2".into())));
        assert_eq!(count::<u32, 1>("0"), Err(Refused("must be ≥ 1".into())));
        assert_eq!(
            count::<u32, 1>("2.5"),
            Err(Refused("must be a whole number (got 2.5)".into()))
        );
        assert_eq!(
            count::<u32, 1>("5e9"),
            Err(Refused("must be ≤ 4294967295".into()))
        );
        assert_eq!(
            count::<u32, 1>("x"),
            Err(Refused("'x' is not a number".into()))
        );
        assert_eq!(
            count::<u32, 1>("inf"),
            Err(Refused("must be ≤ 4294967295".into()))
        );
    }
}

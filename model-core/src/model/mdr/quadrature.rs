//! Adaptive Gauss–Kronrod quadrature (7/15 points), `no_std`, generic over
//! [`Float`], for integrands with `N` components sharing one subdivision
//! (numerator and denominator of a ratio, and a bookkeeping component).
//!
//! Hand-written: the crates that exist (`quadrature`, `gauss-quad`,
//! `peroxide`, `integrate`) need `std` or `alloc`, or are `f64` only, and
//! none integrates a vector integrand with a shared subdivision. The rule is
//! QUADPACK's `qk15` (Piessens et al. 1983).
//!
//! **Error estimate.** On each interval the estimate is `|K₁₅ − G₇|` per
//! component — the error of the 7-point Gauss result. The value used is the
//! Kronrod one, whose error is far smaller than its Gauss partner's once the
//! integrand is resolved (degree 22 against 13), so the sum of the estimates
//! over intervals bounds the error *if* every interval is in the asymptotic
//! regime. That is an estimate, not a proof: an integrand with a feature
//! narrower than an interval that both rules miss goes undetected. The
//! splits of [`super`] put every known kink and square-root end point at an
//! interval end to make that regime reachable; the tests compare with an
//! independent brute force.

use crate::model::float::Float;

/// Kronrod nodes in `[0, 1)`, largest first (`qk15`).
const XGK: [f64; 8] = [
    0.991_455_371_120_812_6,
    0.949_107_912_342_758_5,
    0.864_864_423_359_769_1,
    0.741_531_185_599_394_4,
    0.586_087_235_467_691_1,
    0.405_845_151_377_397_2,
    0.207_784_955_007_898_5,
    0.0,
];
/// Kronrod weights.
const WGK: [f64; 8] = [
    0.022_935_322_010_529_22,
    0.063_092_092_629_978_55,
    0.104_790_010_322_250_18,
    0.140_653_259_715_525_92,
    0.169_004_726_639_267_9,
    0.190_350_578_064_785_4,
    0.204_432_940_075_298_9,
    0.209_482_141_084_727_83,
];
/// Gauss weights of the nodes `XGK[1], XGK[3], XGK[5], XGK[7]`.
const WG: [f64; 4] = [
    0.129_484_966_168_869_7,
    0.279_705_391_489_276_7,
    0.381_830_050_505_118_9,
    0.417_959_183_673_469_4,
];

/// Most intervals held at once (the adaptive loop stops with
/// [`Outcome::converged`] false when full).
pub const MAX_INTERVALS: usize = 64;

/// One interval's Kronrod values and error estimates.
#[derive(Clone, Copy, Debug)]
struct Piece<T, const N: usize> {
    lo: T,
    hi: T,
    value: [T; N],
    error: [T; N],
}

/// The result of [`integrate`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Outcome<T, const N: usize> {
    /// The integrals of both components.
    pub value: [T; N],
    /// Their error estimates (sums of `|K₁₅ − G₇|` over the intervals).
    pub error: [T; N],
    /// Integrand evaluations.
    pub evaluations: u32,
    /// Whether `weight(error) ≤ target` was reached.
    pub converged: bool,
}

fn rule<T: Float, E, const N: usize>(
    f: &mut impl FnMut(T) -> Result<[T; N], E>,
    lo: T,
    hi: T,
) -> Result<Piece<T, N>, E> {
    let c = (lo + hi) * T::HALF;
    let h = (hi - lo) * T::HALF;
    let fc = f(c)?;
    let mut k = fc.map(|x| x * T::from_f64(WGK[7]));
    let mut g = fc.map(|x| x * T::from_f64(WG[3]));
    for j in 0..7 {
        let x = h * T::from_f64(XGK[j]);
        let (f1, f2) = (f(c - x)?, f(c + x)?);
        for i in 0..N {
            let sum = f1[i] + f2[i];
            k[i] += T::from_f64(WGK[j]) * sum;
            if j % 2 == 1 {
                g[i] += T::from_f64(WG[j / 2]) * sum;
            }
        }
    }
    let mut error = [T::ZERO; N];
    for i in 0..N {
        error[i] = (k[i] - g[i]).abs() * h;
    }
    Ok(Piece {
        lo,
        hi,
        value: k.map(|x| x * h),
        error,
    })
}

/// Integrates `f` over each of the consecutive intervals `[ends[i], ends[i+1]]`,
/// bisecting the interval with the largest `weight(error)` until the total
/// `weight(Σ error, Σ value) ≤ target` or [`MAX_INTERVALS`] are held.
///
/// `weight` turns the two error sums (and the current values) into one
/// number comparable with `target` (the caller's error of the ratio).
///
/// # Errors
/// The first error of `f`.
pub fn integrate<T: Float, E, const N: usize>(
    mut f: impl FnMut(T) -> Result<[T; N], E>,
    ends: &[T],
    target: T,
    weight: impl Fn([T; N], [T; N]) -> T,
) -> Result<Outcome<T, N>, E> {
    let mut pieces: heapless::Vec<Piece<T, N>, MAX_INTERVALS> = heapless::Vec::new();
    let mut evaluations = 0u32;
    for w in ends.windows(2) {
        if w[1] > w[0] && pieces.len() < MAX_INTERVALS {
            let _ = pieces.push(rule(&mut f, w[0], w[1])?);
            evaluations += 15;
        }
    }
    let sums = |pieces: &[Piece<T, N>]| {
        let mut v = [T::ZERO; N];
        let mut e = [T::ZERO; N];
        for p in pieces {
            for i in 0..N {
                v[i] += p.value[i];
                e[i] += p.error[i];
            }
        }
        (v, e)
    };
    loop {
        let (value, error) = sums(&pieces);
        if weight(error, value) <= target || pieces.len() + 1 > MAX_INTERVALS {
            return Ok(Outcome {
                value,
                error,
                evaluations,
                converged: weight(error, value) <= target,
            });
        }
        // Bisect the worst interval (by its own weighted error).
        let mut worst = 0;
        let mut worst_err = T::ZERO - T::ONE;
        for (i, p) in pieces.iter().enumerate() {
            let e = weight(p.error, value);
            if e > worst_err {
                worst = i;
                worst_err = e;
            }
        }
        let p = pieces[worst];
        let mid = (p.lo + p.hi) * T::HALF;
        if !(mid > p.lo && mid < p.hi) {
            // The interval cannot be split further in this float type.
            return Ok(Outcome {
                value,
                error,
                evaluations,
                converged: false,
            });
        }
        pieces[worst] = rule(&mut f, p.lo, mid)?;
        let _ = pieces.push(rule(&mut f, mid, p.hi)?);
        evaluations += 30;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_and_polynomial_exactness() {
        // K15 integrates degree ≤ 22 exactly, G7 degree ≤ 13: ∫₀¹ x^k dx = 1/(k+1).
        for k in [0u32, 5, 13, 22] {
            let out = integrate::<f64, (), 2>(
                |x| Ok([libm::pow(x, f64::from(k)), 0.0]),
                &[0.0, 1.0],
                1.0,
                |e, _| e[0],
            )
            .unwrap();
            assert!(
                (out.value[0] - 1.0 / f64::from(k + 1)).abs() < 1e-15,
                "k={k}"
            );
        }
    }
}

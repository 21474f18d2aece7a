//! Safeguarded Halley iteration for a bracketed root of a smooth monotone
//! function (Halley's step where it stays in the bracket and shrinks the
//! step, bisection otherwise). Used for the stick→slip events of the exact
//! solver.

use crate::model::float::Float;

/// Root of `f` in the bracket `(lo, hi, f_lo, f_hi)`: `[lo, hi]`, where `f(lo)` and `f(hi)` have opposite signs
/// (`f_lo`, `f_hi` are those values) and `f` is monotone on the interval.
/// `guess` (if inside the bracket) is the first iterate, otherwise regula
/// falsi; the iteration stops when `|f| ≤ f_tol` (the rounding level of `f`),
/// when a Newton step is below a few ulps, or when the bracket is that small.
/// `fd(x)` returns `(f(x), f'(x), f''(x), sin x, cos x)`; the step is
/// Halley's `f/f' / (1 − f f''/(2f'²))` (cubic convergence; Newton's where
/// the correction is not small, `|f f''/(2f'²)| ≥ ½`); the root is returned as
/// `(x, sin x, cos x)` (the trig of a final Newton step is extrapolated to
/// first order, exact to O(step²), i.e. to rounding).
///
/// Converges to within a few ulps of `x`; at most `max_iter` evaluations.
/// Always returns a point inside the bracket (never NaN for finite inputs).
#[inline]
pub(crate) fn newton_bracketed<T: Float>(
    (mut lo, mut hi, f_lo, f_hi): (T, T, T, T),
    guess: T,
    f_tol: T,
    max_iter: u32,
    mut fd: impl FnMut(T) -> (T, T, T, T, T),
) -> (T, T, T) {
    // Orient so that f(lo) < 0 < f(hi).
    let increasing = f_lo < f_hi;
    let sgn = if increasing { T::ONE } else { -T::ONE };
    let (flo, fhi) = (sgn * f_lo, sgn * f_hi);
    // Regula-falsi start: exact for a linear function.
    let mut x = guess;
    if !(x > lo && x < hi) {
        x = lo + (hi - lo) * (flo / (flo - fhi));
    }
    if !(x > lo && x < hi) {
        x = T::HALF * (lo + hi);
    }
    let mut dx_old = hi - lo;
    let mut last = (x, T::ZERO, T::ONE);
    for _ in 0..max_iter {
        let (f, d, d2, sx, cx) = fd(x);
        last = (x, sx, cx);
        let (f, d, d2) = (sgn * f, sgn * d, sgn * d2);
        if f.abs() <= f_tol {
            return last;
        }
        if f < T::ZERO {
            lo = x;
        } else {
            hi = x;
        }
        let tol = T::from_f64(4.0) * T::EPSILON * (x.abs() + T::ONE);
        if hi - lo <= tol {
            return last;
        }
        // Newton step if it lands strictly inside the bracket and at least
        // halves the previous step; bisection otherwise.
        let mut step_ok = false;
        let mut xn = x;
        if d > T::ZERO {
            let newton = f / d;
            let correction = newton * d2 / (d + d);
            let dx = if correction.abs() < T::HALF {
                newton / (T::ONE - correction)
            } else {
                newton
            };
            xn = x - dx;
            step_ok = xn > lo && xn < hi && (dx + dx).abs() <= dx_old.abs();
            if step_ok {
                dx_old = dx;
                if dx.abs() <= tol {
                    // sin(x − dx) ≈ sin x − dx cos x, cos(x − dx) ≈ cos x + dx sin x.
                    return (xn, sx - dx * cx, cx + dx * sx);
                }
            }
        }
        if !step_ok {
            dx_old = hi - lo;
            xn = T::HALF * (lo + hi);
        }
        x = xn;
    }
    last
}

/// What the function of [`illinois`] says at a point.
pub(crate) enum Probe<T> {
    /// The function's value there; the iteration goes on.
    Value(T),
    /// Stop here (the caller's own criterion is met, or the function does
    /// not apply there).
    Stop,
}

/// Illinois regula falsi (Dowell & Jarratt 1971) on the bracket
/// `(lo, hi, f(lo), f(hi))` whose values have opposite signs: the secant
/// point of the bracket, with the value at an end that stayed twice in a row
/// halved. Stops when the bracket is at most `width(lo, hi)` wide, at an
/// exact zero (the bracket then collapses onto it), when `f` answers
/// [`Probe::Stop`], or after `max_iter` evaluations; returns the final
/// bracket.
///
/// # Errors
/// The first error of `f`.
pub(crate) fn illinois<T: Float, E>(
    (mut lo, mut hi, mut flo, mut fhi): (T, T, T, T),
    width: impl Fn(T, T) -> T,
    max_iter: u32,
    mut f: impl FnMut(T) -> Result<Probe<T>, E>,
) -> Result<(T, T), E> {
    let mut side = 0i8;
    for _ in 0..max_iter {
        if hi - lo <= width(lo, hi) {
            break;
        }
        let mut x = lo - flo * (hi - lo) / (fhi - flo);
        if !(x > lo && x < hi) {
            x = (lo + hi) * T::HALF;
        }
        let fx = match f(x)? {
            Probe::Value(v) => v,
            Probe::Stop => break,
        };
        if fx == T::ZERO {
            return Ok((x, x));
        }
        if (fx < T::ZERO) == (flo < T::ZERO) {
            lo = x;
            flo = fx;
            if side == -1 {
                fhi *= T::HALF;
            }
            side = -1;
        } else {
            hi = x;
            fhi = fx;
            if side == 1 {
                flo *= T::HALF;
            }
            side = 1;
        }
    }
    Ok((lo, hi))
}

//! One spring of the MDR foundation: its mean stretch `⟨s⟩` and mean band
//! `⟨w⁺⟩` at band offset `d` (eqs. M2, M3 of [`super`]).

use super::normal::mean_band;
use super::MdrError;
use crate::model::exact::{self, ExactError};
use crate::model::float::{Float, Math};
use crate::model::liftoff::{self, LiftOffError, Shape, Window};
use crate::model::scene::Drive;

/// Which one-sided limit at `V = 0` a permanent spring takes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Limit {
    /// `V ≠ 0`: the unique steady state.
    Moving,
    /// `V → 0⁺`.
    Plus,
}

/// What one spring contributes, units of `W₀` (stretch) and `d₀` (band).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Spring<T> {
    /// `⟨s⟩` over a period.
    pub(crate) stretch: T,
    /// `⟨w⁺⟩` over a period (eq. M4).
    pub(crate) band: T,
    /// `⟨w⁺⟩` if the spring's solver refused the drive as ill-conditioned
    /// (its `⟨s⟩`, bounded by `±⟨w⁺⟩`, is then taken as 0), else 0.
    pub(crate) unresolved: T,
}

/// The permanent-contact spring's drive scaled by `1/d` (`d > a`): the flat
/// punch with `(a/d, b/d)` at velocity `V/d` (eq. M3).
fn scaled<T: Float>(drive: &Drive<T>, d: T) -> Drive<T> {
    Drive {
        a: drive.a / d,
        b: drive.b / d,
        bc: drive.bc / d,
        bs: drive.bs / d,
    }
}

/// The spring at band offset `d`, forward convention `V ≥ 0` (the caller
/// mirrors; `shape` is `Shape::of(drive, v)`, shared by every spring).
/// `limit` selects μ(0⁺) for permanent springs at `V = 0`.
pub(crate) fn spring<T: Float, M: Math<T>>(
    shape: &Shape<T>,
    drive: &Drive<T>,
    d: T,
    v: T,
    limit: Limit,
) -> Result<Spring<T>, MdrError> {
    let a = drive.a;
    if d <= -a {
        return Ok(Spring {
            stretch: T::ZERO,
            band: T::ZERO,
            unresolved: T::ZERO,
        });
    }
    if d > a {
        // Permanent contact: d·μ_flat(a/d, b/d, V/d).
        let s = scaled(drive, d);
        let m = match limit {
            Limit::Moving => exact::mu_over_mu0::<T, M>(&s, v / d),
            Limit::Plus => exact::limits_at_zero::<T, M>(&s).map(|l| l.0),
        };
        return match m {
            Ok(m) => Ok(Spring {
                stretch: d * m,
                band: d,
                unresolved: T::ZERO,
            }),
            Err(ExactError::IllConditioned) => Ok(Spring {
                stretch: T::ZERO,
                band: d,
                unresolved: d,
            }),
            Err(_) => Err(MdrError::Inconsistent),
        };
    }
    // |d| ≤ a: intermittent contact, one window of w = d − a cos θ.
    let band = mean_band::<T, M>(d, a);
    // A sliver of contact at the rim (window ≲ ε^{1/3}): the walk cannot
    // resolve ⟨s⟩/⟨w⁺⟩ there; |⟨s⟩| ≤ ⟨w⁺⟩ is counted in the bound instead.
    let floor = T::from_f64(64.0) * T::EPSILON * (T::ONE + a + drive.b);
    if band <= floor {
        return Ok(Spring {
            stretch: T::ZERO,
            band,
            unresolved: band,
        });
    }
    match liftoff::banded_stretch_integral::<T, M>(shape, d) {
        Ok((s, _)) => Ok(Spring {
            stretch: s / T::TAU,
            band,
            unresolved: T::ZERO,
        }),
        // A thin window at the rim (⟨w⁺⟩ ≤ √ε (1 + a + b), window ≲ ε^{1/6}
        // rad) whose walk failed its check: |⟨s⟩| ≤ ⟨w⁺⟩ holds for any
        // spring, so it is counted in the bound like the slivers above
        // (reached by the quadrature's nodes within ~10⁻⁸ of ξ_max at tight
        // tolerances; its share of the bound is ≲ 10⁻¹³).
        Err(LiftOffError::Inconsistent) if band <= M::sqrt(T::EPSILON) * (T::ONE + a + drive.b) => {
            Ok(Spring {
                stretch: T::ZERO,
                band,
                unresolved: band,
            })
        }
        Err(LiftOffError::IllConditioned) => Err(MdrError::IllConditioned),
        Err(_) => Err(MdrError::Inconsistent),
    }
}

/// `V_c⁺(d)`: the smallest `V` at which the spring at offset `d`
/// slides forward through all its contact (eq. L5 on its window for
/// `|d| < a`; `c` of eq. 8 for `d > a`). Nondecreasing in `d`: the windows
/// are nested.
pub(crate) fn forward_critical<T: Float, M: Math<T>>(
    shape: &Shape<T>,
    drive: &Drive<T>,
    d: T,
) -> T {
    if d > drive.a {
        drive.c_forward::<M>()
    } else {
        let window = Window::of::<M>(d.max(-drive.a), drive.a);
        shape.forward_critical(&window)
    }
}

/// The arc structure of the spring at offset `d` (forward convention; a
/// permanent spring at `V = 0` takes its μ(0⁺) period), as a base-4 code: a
/// change between two offsets brackets a possible kink of `⟨s⟩(d)`. `None`
/// where it is not available (no contact, or a solver refused).
pub(crate) fn signature<T: Float, M: Math<T>>(
    shape: &Shape<T>,
    drive: &Drive<T>,
    d: T,
    v: T,
) -> Option<u32> {
    let a = drive.a;
    if d <= -a {
        return None;
    }
    if d > a {
        let s = scaled(drive, d);
        let arcs = if v == T::ZERO {
            // The V → 0⁺ period of `exact::limits_at_zero`.
            let Some(problem) = exact::Forward::at_rest::<M>(s, T::ONE) else {
                return Some(2);
            };
            let mut arcs: heapless::Vec<exact::Arc<T>, { exact::MAX_ARCS }> = heapless::Vec::new();
            let mut push = |arc: exact::Arc<T>| {
                let _ = arcs.push(arc);
            };
            exact::period::mean_stretch::<T, M>(&problem, Some(&mut push)).ok()?;
            arcs
        } else {
            exact::steady_state::<T, M>(&s, v / d).ok()?.1
        };
        let min = T::from_f64(liftoff::SIGNATURE_MIN_ARC);
        let arcs = arcs
            .iter()
            .map(|x| (x.end - x.start, liftoff::arc_digit(x.kind)));
        return Some(cycle_code(arcs, min));
    }
    Some(liftoff::banded_signature::<T, M>(shape, d))
}

/// The base-4 code of a period's arcs `(length, digit)`: arcs of length
/// `min` or less left out, neighbours of one kind merged, also across the
/// period's start (the period is a cycle), and the smallest rotation taken,
/// so that an event crossing the phase where the period is cut changes
/// nothing. At most [`exact::MAX_ARCS`] arcs count.
fn cycle_code<T: Float>(arcs: impl Iterator<Item = (T, u32)>, min: T) -> u32 {
    let mut digits = [0u32; exact::MAX_ARCS];
    let mut len = 0;
    for (_, digit) in arcs.filter(|x| x.0 > min) {
        if len == 0 || digits[len - 1] != digit {
            let Some(slot) = digits.get_mut(len) else {
                break;
            };
            *slot = digit;
            len += 1;
        }
    }
    while len > 1 && digits[0] == digits[len - 1] {
        len -= 1;
    }
    (0..len.max(1))
        .map(|r| (0..len).fold(0u32, |c, i| c * 4 + digits[(r + i) % len]))
        .min()
        .unwrap_or(0)
}

#[cfg(test)]
mod tests {
    use super::cycle_code;

    /// Codes built by hand from the rule: digits stick 1, forward slip 2,
    /// backward slip 3; slivers (≤ min) out, neighbours of one kind merged,
    /// across the cut too, the smallest base-4 rotation.
    #[test]
    fn the_code_merges_neighbours_and_ignores_the_cut() {
        let code = |arcs: &[(f64, u32)]| cycle_code(arcs.iter().copied(), 1e-6);
        // stick, slip: "12" = 6 (rotation "21" = 9).
        assert_eq!(code(&[(1.0, 1), (2.0, 2)]), 6);
        // A sliver slip between two sticks leaves one stick: the same 6.
        assert_eq!(code(&[(1.0, 1), (1e-7, 3), (1.0, 1), (2.0, 2)]), 6);
        // Cut inside a stick: slip, stick, slip, stick → the cycle "12".
        assert_eq!(code(&[(0.5, 1), (2.0, 2), (0.5, 1)]), 6);
        // Three kinds: "123" = 27, its rotations 45 ("231") and 54 ("312").
        assert_eq!(code(&[(1.0, 2), (1.0, 3), (1.0, 1)]), 27);
        // One kind all round, and nothing at all.
        assert_eq!(code(&[(3.0, 2), (1.0, 2)]), 2);
        assert_eq!(code(&[]), 0);
    }
}

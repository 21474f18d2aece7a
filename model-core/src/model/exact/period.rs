//! One steady-state period of the permanent-contact solver, in the forward
//! convention (`0 ≤ V < c`), as a walk over its arcs (see the [parent
//! module](super) for the method).
//!
//! All phases are relative to the forward window end θ_e: `τ = θ − θ_e ∈
//! [0, 2π]`. The trigonometric values at the closed-form points (window ends)
//! come from angle additions of `(V/c, √(1 − V²/c²))` and the drive phasors,
//! so the only transcendental calls are two `asin`, the square roots, and one
//! `sin_cos` per Newton iteration of the stick→slip roots.
//!
//! The steps: [`PeriodGeometry::new`] places the slip windows and writes the
//! band and the drive as sinusoids of τ; [`PeriodGeometry::forward_touch`] and
//! [`PeriodGeometry::backward_touch`] find the next stick→slip event of a stick
//! arc; [`mean_stretch`] walks the arcs and adds their closed-form integrals.

use super::{Arc, ArcKind, ExactError, Forward, MAX_ARCS};
use crate::model::float::{Float, Math};
use crate::model::root::newton_bracketed;

/// A phase `τ` with its sine and cosine.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Phase<T> {
    /// The phase, rad.
    pub(crate) at: T,
    /// `sin τ`.
    pub(crate) sin: T,
    /// `cos τ`.
    pub(crate) cos: T,
}

impl<T: Float> Phase<T> {
    /// `τ = 0`.
    pub(crate) fn zero() -> Self {
        Phase {
            at: T::ZERO,
            sin: T::ZERO,
            cos: T::ONE,
        }
    }
}

/// `(sin(x + y), cos(x + y))` from the sines and cosines of `x` and `y`.
#[inline(always)]
pub(crate) fn add_angles<T: Float>(sin_x: T, cos_x: T, sin_y: T, cos_y: T) -> (T, T) {
    (sin_x * cos_y + cos_x * sin_y, cos_x * cos_y - sin_x * sin_y)
}

/// The forward slip window: `s = +w` persists while `V − c sin(θ + ψ) ≥ 0`.
/// It ends at τ = 0 (θ_e = α − ψ, `α = asin(V/c)`) and starts at `τ_s = π − 2α`.
struct ForwardWindow<T> {
    /// `α = asin(V/c)`.
    alpha: T,
    /// `sin α = V/c`.
    sin_alpha: T,
    /// `cos α`.
    cos_alpha: T,
    /// The window start τ_s, where `s − w` has its minimum.
    start: Phase<T>,
}

/// The backward slip window (`s = −w` persists while `V − c' sin(θ + ψ') ≤ 0`),
/// present when `V < c'`: its pieces inside `[0, 2π]`, in time order.
struct BackwardWindow<T> {
    /// `(start, end)` of each piece; the window is one arc of the circle, so
    /// at most two pieces (when it wraps over τ = 2π).
    pieces: [(Phase<T>, Phase<T>); 2],
    /// How many of `pieces` are used (0, 1 or 2).
    count: usize,
    /// `c' cos α'`: minus the second derivative of `s + w` at its maximum.
    curvature: T,
}

impl<T: Float> BackwardWindow<T> {
    fn pieces(&self) -> &[(Phase<T>, Phase<T>)] {
        &self.pieces[..self.count]
    }
}

/// Everything about one period that does not depend on the stick arcs: the
/// slip windows and the band and drive as sinusoids of τ,
/// `A(τ) = a cos(τ + θ_e) = m cos τ − n sin τ` (so `w = 1 − A`) and
/// `X(τ) = b cos(τ + θ_e + φ) = p cos τ − q sin τ`.
struct PeriodGeometry<T> {
    v: T,
    c: T,
    /// `a cos θ_e`.
    m: T,
    /// `a sin θ_e`.
    n: T,
    /// `b cos(θ_e + φ)`.
    p: T,
    /// `b sin(θ_e + φ)`.
    q: T,
    forward: ForwardWindow<T>,
    backward: BackwardWindow<T>,
    /// Scale of the rounding of `s ∓ w` (without the stick constant).
    rounding_scale: T,
}

impl<T: Float> PeriodGeometry<T> {
    #[inline(always)]
    fn new<M: Math<T>>(problem: &Forward<T>) -> Self {
        let d = &problem.drive;
        let (v, c) = (problem.v, problem.c);
        let (a, bc, bs) = (d.a, d.bc, d.bs);
        // c e^{iψ} = b e^{iφ} + a = forward_re + i·bs.
        let forward_re = a + bc;
        // Forward window end: α = asin(V/c), θ_e = α − ψ.
        let sin_alpha = (v / c).min(T::ONE);
        // 0 < V < c: sin α ∈ (0, 1], so both factors are ≥ 0 (no clamp).
        let cos_alpha = M::sqrt((T::ONE - sin_alpha) * (T::ONE + sin_alpha));
        let alpha = M::asin(sin_alpha);
        let (cos_psi, sin_psi) = (forward_re / c, bs / c);
        let sin_end = sin_alpha * cos_psi - cos_alpha * sin_psi; // sin θ_e
        let cos_end = cos_alpha * cos_psi + sin_alpha * sin_psi; // cos θ_e
        let forward = ForwardWindow {
            alpha,
            sin_alpha,
            cos_alpha,
            // h⁺ = s − w has its minimum at τ_s = π − 2α.
            start: Phase {
                at: T::PI - (alpha + alpha),
                sin: T::TWO * sin_alpha * cos_alpha,
                cos: T::TWO * sin_alpha * sin_alpha - T::ONE,
            },
        };
        let backward = BackwardWindow::new::<M>(problem, &forward, forward_re);
        PeriodGeometry {
            v,
            c,
            m: a * cos_end,
            n: a * sin_end,
            p: bc * cos_end - bs * sin_end,
            q: bc * sin_end + bs * cos_end,
            forward,
            backward,
            rounding_scale: T::ONE + d.b + a + v * T::TAU,
        }
    }

    /// `∫A dτ` at `x`.
    #[inline(always)]
    fn band_swing_integral(&self, x: &Phase<T>) -> T {
        self.m * x.sin + self.n * x.cos
    }

    /// `∫X dτ` at `x`.
    #[inline(always)]
    fn drive_swing_integral(&self, x: &Phase<T>) -> T {
        self.p * x.sin + self.q * x.cos
    }

    /// The band half-width `w = 1 − A` at `x`.
    #[inline(always)]
    fn band(&self, x: &Phase<T>) -> T {
        T::ONE - (self.m * x.cos - self.n * x.sin)
    }

    /// The drive oscillation `X` at `x`.
    #[inline(always)]
    fn drive_swing(&self, x: &Phase<T>) -> T {
        self.p * x.cos - self.q * x.sin
    }

    /// `∫ w dτ` over `[x0, x1]`.
    #[inline(always)]
    fn band_integral(&self, x0: &Phase<T>, x1: &Phase<T>) -> T {
        (x1.at - x0.at) - (self.band_swing_integral(x1) - self.band_swing_integral(x0))
    }

    /// `∫ s dτ` over a stick arc `[x0, x1]` with `s = k + Vτ + X(τ)`.
    #[inline(always)]
    fn stick_integral(&self, k: T, x0: &Phase<T>, x1: &Phase<T>) -> T {
        k * (x1.at - x0.at)
            + self.v * (x1.at - x0.at) * (x1.at + x0.at) * T::HALF
            + (self.drive_swing_integral(x1) - self.drive_swing_integral(x0))
    }

    /// `h⁺ = s − w = k − 1 + Vτ + X + A` on a stick arc with constant `k`.
    #[inline(always)]
    fn above_upper_band(&self, k: T, x: &Phase<T>) -> T {
        k - T::ONE + self.v * x.at + (self.p + self.m) * x.cos - (self.q + self.n) * x.sin
    }

    /// `h⁻ = s + w = k + 1 + Vτ + X − A` on a stick arc with constant `k`.
    #[inline(always)]
    fn above_lower_band(&self, k: T, x: &Phase<T>) -> T {
        k + T::ONE + self.v * x.at + (self.p - self.m) * x.cos - (self.q - self.n) * x.sin
    }

    /// `dh⁺/dτ`.
    #[inline(always)]
    fn above_upper_band_slope(&self, x: &Phase<T>) -> T {
        self.v - (self.p + self.m) * x.sin - (self.q + self.n) * x.cos
    }

    /// `dh⁻/dτ`.
    #[inline(always)]
    fn above_lower_band_slope(&self, x: &Phase<T>) -> T {
        self.v - (self.p - self.m) * x.sin - (self.q - self.n) * x.cos
    }

    /// Rounding level of `h±` on a stick arc with constant `k` (the root
    /// finder's stopping test).
    #[inline(always)]
    fn root_tolerance(&self, k: T) -> T {
        T::from_f64(8.0) * T::EPSILON * (self.rounding_scale + k.abs())
    }

    /// The stick constant `k` of the arc that starts at `x` with stretch `s`.
    #[inline(always)]
    fn stick_constant(&self, s: T, x: &Phase<T>) -> T {
        s - self.v * x.at - self.drive_swing(x)
    }

    /// The forward stick→slip event of a stick arc (constant `k`) that starts
    /// at `from`: the first zero of `h⁺` on its increasing segment
    /// `[max(from, τ_s), 2π]`, if any.
    #[inline(always)]
    fn forward_touch<M: Math<T>>(&self, k: T, from: &Phase<T>) -> Option<Phase<T>> {
        let window_start = &self.forward.start;
        let left = if from.at >= window_start.at {
            *from
        } else {
            *window_start
        };
        let period_end = full_period::<T>();
        if left.at >= period_end.at {
            return None;
        }
        let at_left = self.above_upper_band(k, &left);
        if at_left >= T::ZERO {
            // At the band already at the segment start (rounding only): slip now.
            return Some(left);
        }
        let at_right = self.above_upper_band(k, &period_end);
        if at_right <= T::ZERO {
            return None;
        }
        // Near the minimum h⁺ ≈ h_min + ½·c cos α·(τ − τ_s)².
        let curvature = self.c * self.forward.cos_alpha;
        let guess = if left.at == window_start.at && curvature > T::ZERO {
            left.at + M::sqrt(-(at_left + at_left) / curvature)
        } else {
            left.at - at_left / self.above_upper_band_slope(&left)
        };
        Some(root::<T, M>(
            &left,
            (left.at, period_end.at, at_left, at_right),
            guess,
            self.root_tolerance(k),
            |x| {
                (
                    self.above_upper_band(k, x),
                    self.above_upper_band_slope(x),
                    (self.q + self.n) * x.sin - (self.p + self.m) * x.cos,
                )
            },
        ))
    }

    /// The backward stick→slip event of a stick arc (constant `k`) that starts
    /// at `from`, if it comes before `horizon`: the first zero of `h⁻` on a
    /// decreasing piece, returned with that piece's end (where the backward
    /// slip ends).
    #[inline(always)]
    fn backward_touch<M: Math<T>>(
        &self,
        k: T,
        from: &Phase<T>,
        horizon: T,
    ) -> Option<(Phase<T>, Phase<T>)> {
        for &(piece_start, piece_end) in self.backward.pieces() {
            let left = if from.at > piece_start.at {
                *from
            } else {
                piece_start
            };
            if left.at >= piece_end.at || left.at >= horizon {
                continue;
            }
            let at_left = self.above_lower_band(k, &left);
            if at_left <= T::ZERO {
                return Some((left, piece_end));
            }
            let at_right = self.above_lower_band(k, &piece_end);
            if at_right < T::ZERO {
                // Near the maximum h⁻ ≈ h_max − ½·c' cos α'·(τ − σ)².
                let curvature = self.backward.curvature;
                let guess = if left.at == piece_start.at && curvature > T::ZERO {
                    left.at + M::sqrt((at_left + at_left) / curvature)
                } else {
                    left.at - at_left / self.above_lower_band_slope(&left)
                };
                let touch = root::<T, M>(
                    &left,
                    (left.at, piece_end.at, at_left, at_right),
                    guess,
                    self.root_tolerance(k),
                    |x| {
                        (
                            self.above_lower_band(k, x),
                            self.above_lower_band_slope(x),
                            (self.q - self.n) * x.sin - (self.p - self.m) * x.cos,
                        )
                    },
                );
                return if touch.at < horizon {
                    Some((touch, piece_end))
                } else {
                    None
                };
            }
            // h⁻ stays positive on this piece: try the next one.
        }
        None
    }
}

impl<T: Float> BackwardWindow<T> {
    /// The backward window relative to θ_e; `forward_re = a + b cos φ`.
    #[inline(always)]
    fn new<M: Math<T>>(problem: &Forward<T>, forward: &ForwardWindow<T>, forward_re: T) -> Self {
        let d = &problem.drive;
        let (v, c) = (problem.v, problem.c);
        let (a, bc, bs) = (d.a, d.bc, d.bs);
        let mut window = BackwardWindow {
            pieces: [(Phase::zero(), Phase::zero()); 2],
            count: 0,
            curvature: T::ZERO,
        };
        // c' e^{iψ'} = b e^{iφ} − a = backward_re + i·bs.
        let backward_re = bc - a;
        let c_back = problem.c_back;
        if v >= c_back {
            return window;
        }
        let sin_alpha_b = (v / c_back).min(T::ONE);
        // 0 < V < c': as in the forward window, both factors are ≥ 0.
        let cos_alpha_b = M::sqrt((T::ONE - sin_alpha_b) * (T::ONE + sin_alpha_b));
        let alpha_b = M::asin(sin_alpha_b);
        window.curvature = c_back * cos_alpha_b;
        // δ = ψ − ψ' = arg(P·conj P'), P·conj P' = (forward_re·backward_re + bs²) − i·2a·bs.
        let re = forward_re * backward_re + bs * bs;
        let im = -(T::TWO * a * bs);
        let delta = M::atan2(im, re);
        let norm = c * c_back;
        let (sin_delta, cos_delta) = (im / norm, re / norm);
        // Window start σ = α' − ψ' − θ_e = α' − α + δ.
        let (s1, c1) = add_angles(
            sin_alpha_b,
            cos_alpha_b,
            -forward.sin_alpha,
            forward.cos_alpha,
        );
        let (sin_start, cos_start) = add_angles(s1, c1, sin_delta, cos_delta);
        let start = wrap_tau(alpha_b - forward.alpha + delta);
        let length = T::PI - (alpha_b + alpha_b);
        let (sin_end, cos_end) = add_angles(
            sin_start,
            cos_start,
            T::TWO * sin_alpha_b * cos_alpha_b,
            T::TWO * sin_alpha_b * sin_alpha_b - T::ONE,
        );
        let end = start + length;
        let start = Phase {
            at: start,
            sin: sin_start,
            cos: cos_start,
        };
        if end > T::TAU {
            let wrapped_end = Phase {
                at: end - T::TAU,
                sin: sin_end,
                cos: cos_end,
            };
            window.pieces = [(Phase::zero(), wrapped_end), (start, full_period())];
            window.count = 2;
        } else {
            let end = Phase {
                at: end,
                sin: sin_end,
                cos: cos_end,
            };
            window.pieces[0] = (start, end);
            window.count = 1;
        }
        window
    }
}

/// `τ = 2π`.
#[inline(always)]
fn full_period<T: Float>() -> Phase<T> {
    Phase {
        at: T::TAU,
        sin: T::ZERO,
        cos: T::ONE,
    }
}

/// One steady-state period for `0 ≤ V < c` (forward convention), returning
/// `⟨s⟩` (the caller applies the mirror sign). `V = 0` gives the limit
/// `μ(0⁺)/μ₀`. `record`, if given, sees each arc in order, in absolute phases.
#[inline]
pub(crate) fn mean_stretch<T: Float, M: Math<T>>(
    problem: &Forward<T>,
    mut record: Option<&mut dyn FnMut(Arc<T>)>,
) -> Result<T, ExactError> {
    let geometry = PeriodGeometry::new::<M>(problem);
    let d = &problem.drive;
    let v = problem.v;
    let window_end = if record.is_some() {
        geometry.forward.alpha - M::atan2(d.bs, d.a + d.bc)
    } else {
        T::ZERO
    };
    let mut emit = |kind: ArcKind, x0: &Phase<T>, x1: &Phase<T>| {
        if let Some(r) = record.as_mut() {
            r(Arc {
                kind,
                start: x0.at + window_end,
                end: x1.at + window_end,
            });
        }
    };

    let period_end = full_period::<T>();
    let mut total = T::ZERO;
    // Stick from τ = 0 with s = w(0): s(τ) = k + Vτ + X(τ).
    let mut stick_start = Phase::zero();
    let mut k = geometry.band(&stick_start) - geometry.drive_swing(&stick_start);
    for _ in 0..MAX_ARCS {
        let forward = geometry.forward_touch::<M>(k, &stick_start);
        let horizon = forward.map_or(period_end.at, |x| x.at);
        let backward = geometry.backward_touch::<M>(k, &stick_start, horizon);
        match (backward, forward) {
            (Some((slip_start, slip_end)), _) => {
                total += geometry.stick_integral(k, &stick_start, &slip_start);
                total -= geometry.band_integral(&slip_start, &slip_end);
                emit(ArcKind::Stick, &stick_start, &slip_start);
                emit(ArcKind::SlipBackward, &slip_start, &slip_end);
                if slip_end.at >= period_end.at {
                    // Slipping backward at the period end: not the steady state.
                    return Err(ExactError::Inconsistent);
                }
                // Stick again from s = −w.
                k = geometry.stick_constant(-geometry.band(&slip_end), &slip_end);
                stick_start = slip_end;
            }
            (None, Some(slip_start)) => {
                total += geometry.stick_integral(k, &stick_start, &slip_start);
                total += geometry.band_integral(&slip_start, &period_end);
                emit(ArcKind::Stick, &stick_start, &slip_start);
                emit(ArcKind::SlipForward, &slip_start, &period_end);
                return checked_mean(total);
            }
            (None, None) => {
                // No forward touch: only consistent if s(2π) = w(2π) already
                // (V → 0 with pure stick; otherwise h⁺(2π) ≥ 2πV).
                let tol = T::from_f64(64.0) * T::EPSILON * (T::ONE + d.b + v * T::TAU);
                if geometry.above_upper_band(k, &period_end).abs() > tol {
                    return Err(ExactError::Inconsistent);
                }
                total += geometry.stick_integral(k, &stick_start, &period_end);
                emit(ArcKind::Stick, &stick_start, &period_end);
                return checked_mean(total);
            }
        }
    }
    Err(ExactError::Inconsistent)
}

/// `⟨s⟩ = ∫s dτ / 2π`, checked against `|μ/μ₀| ≤ 1` (which holds exactly;
/// rounding is allowed, never more).
#[inline(always)]
fn checked_mean<T: Float>(total: T) -> Result<T, ExactError> {
    let mu = total / T::TAU;
    if !mu.is_finite() || mu.abs() > T::ONE + T::from_f64(1e3) * T::EPSILON {
        return Err(ExactError::Inconsistent);
    }
    Ok(mu.max(-T::ONE).min(T::ONE))
}

/// Bracketed root `(lo, hi, f(lo), f(hi))` of a stick→slip function, returned
/// with its trig. `f_and_slope` gives `(f, f', f'')` at a phase; `near` is
/// the bracket's end `lo` with its trig, as the caller has it.
///
/// The trig of an iterate closer than [`rotate_max`] to the previous one (the
/// first: of `near`) is that one's turned by the step ([`rotate`]), at most
/// [`ROTATIONS_MAX`] times in a row; otherwise `M::sin_cos` (issue 35: a
/// Halley step is small, and a rotation costs a quarter of a `sin_cos`).
/// A rotation keeps the length of the error vector it carries (to the
/// series' truncation) and adds its own rounding, so an iterate's trig
/// stays within
///
/// ```text
/// ε_trig ≤ √2·(ε₀ + 3·ε_rot)                                            (P1)
/// ```
///
/// of the exact, `ε₀` the error of the trig it started from (`M::sin_cos`'s,
/// 6.8e-8 with [`crate::model::float::FastF32`], or `near`'s, a phase the
/// solver already evaluates its functions at) and `ε_rot` ≤
/// [`ROTATE_ERR_F32`] (f32): 5.6e-7 from FastF32's — about half the f32
/// precision constant, 1e-6, for functions that are sums of terms ≤ `1 + b`
/// times the trig (the solver's μ measures within `1.82e-7·(1 + b)` of f64's
/// with the rotations, as without them: `tests/trig.rs`,
/// `exact_solver_mu_fast_f32_matches_f64`).
#[inline(always)]
pub(crate) fn root<T: Float, M: Math<T>>(
    near: &Phase<T>,
    bracket: (T, T, T, T),
    guess: T,
    f_tol: T,
    f_and_slope: impl Fn(&Phase<T>) -> (T, T, T),
) -> Phase<T> {
    // The previous iterate with its trig (first `near`), and the rotations
    // in a row since the last `sin_cos`.
    let mut prev = *near;
    let mut turns = 0u32;
    let reach = rotate_max::<T>();
    let (at, sin, cos) = newton_bracketed(bracket, guess, f_tol, 100, |at| {
        let x = if turns < ROTATIONS_MAX && (at - prev.at).abs() < reach {
            turns += 1;
            rotate(&prev, at)
        } else {
            turns = 0;
            let (sin, cos) = M::sin_cos(at);
            Phase { at, sin, cos }
        };
        prev = x;
        let (f, slope, curvature) = f_and_slope(&x);
        (f, slope, curvature, x.sin, x.cos)
    });
    Phase { at, sin, cos }
}

/// The largest step [`root`] turns the previous iterate's trig by instead of
/// calling `sin_cos`, rad (strictly less): 2⁻³ for f32; 0 for f64 — the
/// host's f64 solver keeps `M::sin_cos` at every iterate, bit for bit as
/// before rotations (its μ feeds searches, such as the load line's maximum
/// efficiency, whose results moved by 2e-9 with rotations of 2⁻⁹ and
/// errors of a few f64 ulps).
#[inline(always)]
pub(crate) fn rotate_max<T: Float>() -> T {
    if T::EPSILON < T::from_f64(1e-10) {
        T::ZERO
    } else {
        T::from_f64(0.125)
    }
}

/// The most rotations [`root`] makes in a row before it calls `sin_cos`
/// again (bounds the error they carry, eq. P1).
pub(crate) const ROTATIONS_MAX: u32 = 3;

/// The error a [`rotate`] in f32 adds to `(sin, cos)`, absolute: the
/// series' truncation (`d⁷/5040 + d⁶/720 ≤ 5.3e-9` at `|d| ≤ 2⁻³`), the
/// step `d = at − p.at` rounded (`2⁻²⁴·|d| ≤ 7.5e-9`), the correction (below
/// `|d| + d²/2 ≤ 0.133`, formed within 4 ulps of its size, `4·2⁻²⁴·0.133 =
/// 3.2e-8`) and the sum rounded once (`2⁻²⁴ = 6.0e-8`): 1.05e-7, taken as
/// 1.1e-7 (`rotation_adds_at_most_its_error` checks it against f64).
#[allow(dead_code)] // the bound of eq. P1, asserted by the tests below
pub(crate) const ROTATE_ERR_F32: f64 = 1.1e-7;

/// The trig of `at` from that of the nearby phase `p` (`|at − p.at| ≤`
/// [`rotate_max`]): `sin(p + d) = sin p + (cos p·sin d − sin p·(1 − cos d))`,
/// `cos(p + d) = cos p − (sin p·sin d + cos p·(1 − cos d))`, with
/// `sin d = d(1 − d²/6·(1 − d²/20))` and `1 − cos d = d²/2·(1 − d²/12)`
/// (Taylor series; error [`ROTATE_ERR_F32`] in f32).
#[inline(always)]
fn rotate<T: Float>(p: &Phase<T>, at: T) -> Phase<T> {
    let d = at - p.at;
    let d2 = d * d;
    let sd = d * (T::ONE - d2 * T::from_f64(1.0 / 6.0) * (T::ONE - d2 * T::from_f64(1.0 / 20.0)));
    let vd = d2 * T::HALF * (T::ONE - d2 * T::from_f64(1.0 / 12.0));
    Phase {
        at,
        sin: p.sin + (p.cos * sd - p.sin * vd),
        cos: p.cos - (p.sin * sd + p.cos * vd),
    }
}

/// Wraps `x` (|x| < 8π) into `[0, 2π)`.
#[inline]
pub(crate) fn wrap_tau<T: Float>(mut x: T) -> T {
    if !x.is_finite() {
        return T::ZERO;
    }
    while x < T::ZERO {
        x += T::TAU;
    }
    while x >= T::TAU {
        x -= T::TAU;
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `rotate` in f32 against f64's own sine and cosine: from a seed rounded
    /// to f32 (each component within 2⁻²⁵, the vector within √2·2⁻²⁵), every
    /// turn within the reach lands within that vector's length plus
    /// [`ROTATE_ERR_F32`] of the exact (eq. P1, one step), over a grid of
    /// phases around the circle and steps of both signs up to the reach.
    #[test]
    fn rotation_adds_at_most_its_error() {
        let reach = rotate_max::<f32>();
        let seed_err = core::f64::consts::SQRT_2 * 2f64.powi(-25);
        let mut worst = 0.0f64;
        for i in 0..997 {
            let p_at = (i as f32) * (core::f32::consts::TAU / 997.0);
            let p = Phase {
                at: p_at,
                sin: f64::from(p_at).sin() as f32,
                cos: f64::from(p_at).cos() as f32,
            };
            for j in -64..=64 {
                let at = p_at + reach * (j as f32 / 64.0);
                let r = rotate(&p, at);
                let (s, c) = f64::from(at).sin_cos();
                let e = (f64::from(r.sin) - s)
                    .abs()
                    .max((f64::from(r.cos) - c).abs());
                worst = worst.max(e);
                assert!(
                    e <= seed_err + ROTATE_ERR_F32,
                    "rotate({p_at}, {at}): error {e:e}"
                );
                assert_eq!(r.at, at);
            }
        }
        // The bound is not loose by orders: the rounding is there.
        assert!(worst > 2f64.powi(-25), "worst {worst:e}");
    }

    std::thread_local! {
        /// `sin_cos` calls of [`Counting`] on this thread.
        static CALLS: core::cell::Cell<u32> = const { core::cell::Cell::new(0) };
    }

    /// FastF32, counting its `sin_cos` calls.
    struct Counting;

    impl Math<f32> for Counting {
        const NAME: &'static str = "counting";
        const MAX_REL_ERROR: f64 = crate::model::float::FastF32::MAX_REL_ERROR;
        fn sqrt(x: f32) -> f32 {
            crate::model::float::FastF32::sqrt(x)
        }
        fn sin_cos(x: f32) -> (f32, f32) {
            CALLS.with(|c| c.set(c.get() + 1));
            crate::model::float::FastF32::sin_cos(x)
        }
        fn asin(x: f32) -> f32 {
            crate::model::float::FastF32::asin(x)
        }
        fn atan2(y: f32, x: f32) -> f32 {
            crate::model::float::FastF32::atan2(y, x)
        }
        fn hypot(x: f32, y: f32) -> f32 {
            crate::model::float::FastF32::hypot(x, y)
        }
    }

    /// A root found by bisection alone (the function reports no slope), in
    /// a bracket of 0.2 rad: every step is below the reach, so `root` turns
    /// the trig three times and calls `sin_cos` on every fourth evaluation
    /// (the first turns the bracket's end `near`): ⌊E/4⌋ calls for E
    /// evaluations. The root's trig is within eq. P1 of the exact (the seed
    /// exact to f32 rounding, ε₀ = 2⁻²⁵; FastF32's 6.8e-8 after a call).
    #[test]
    fn root_calls_sin_cos_after_three_turns_in_a_row() {
        let target = 1.234_567f32;
        let (lo, hi) = (1.15f32, 1.35f32);
        let near = Phase {
            at: lo,
            sin: f64::from(lo).sin() as f32,
            cos: f64::from(lo).cos() as f32,
        };
        let evals = core::cell::Cell::new(0u32);
        CALLS.with(|c| c.set(0));
        let r = root::<f32, Counting>(&near, (lo, hi, lo - target, hi - target), 1.2, 0.0, |x| {
            evals.set(evals.get() + 1);
            (x.at - target, 0.0, 0.0)
        });
        let (e, calls) = (evals.get(), CALLS.with(|c| c.get()));
        assert!(e >= 12, "bisection to f32 resolution takes many steps: {e}");
        assert_eq!(calls, e / 4, "{e} evaluations");
        assert!((r.at - target).abs() <= 4.0 * f32::EPSILON * 2.0);
        let bound = core::f64::consts::SQRT_2 * (6.8e-8 + 3.0 * ROTATE_ERR_F32);
        let (s, c) = f64::from(r.at).sin_cos();
        assert!(
            (f64::from(r.sin) - s).abs() <= bound,
            "sin {} vs {s}",
            r.sin
        );
        assert!(
            (f64::from(r.cos) - c).abs() <= bound,
            "cos {} vs {c}",
            r.cos
        );
    }

    /// The reach keeps the series' truncation, `d⁶/720 + d⁷/5040`, below one
    /// f32 rounding (5.3e-9 < 1.2e-7 at 2⁻³); f64 does not rotate.
    #[test]
    fn the_rotation_reach_keeps_the_truncation_below_rounding() {
        let trunc = |d: f64| d.powi(6) / 720.0 + d.powi(7) / 5040.0;
        assert_eq!(rotate_max::<f32>(), 0.125);
        assert!(trunc(f64::from(rotate_max::<f32>())) < f64::from(f32::EPSILON));
        assert_eq!(rotate_max::<f64>(), 0.0);
    }

    /// `checked_mean`'s documented check: `⟨s⟩ = total/2π`, clamped to
    /// `[−1, 1]` within rounding (`1e3·ε` beyond 1 is still rounding), and
    /// `Inconsistent` beyond that or when not finite — for both widths,
    /// totals formed from the mean in f64 so that the quotient lands where
    /// asked (2π·x/2π is x within an ulp or two, far inside the margins).
    #[test]
    fn the_mean_is_clamped_within_rounding_and_refused_beyond() {
        fn check<T: Float>() {
            let eps = T::EPSILON.to_f64();
            let total = |mu: f64| T::from_f64(mu * core::f64::consts::TAU);
            for mu in [0.0, 0.25, -0.7, 1.0 - 4.0 * eps] {
                let got = checked_mean(total(mu)).unwrap().to_f64();
                assert!((got - mu).abs() <= 4.0 * eps, "{mu}: {got}");
            }
            for sign in [1.0, -1.0] {
                // Beyond 1 by rounding: clamped to ±1 exactly.
                let got = checked_mean(total(sign * (1.0 + 500.0 * eps))).unwrap();
                assert_eq!(got.to_f64(), sign);
                // Beyond 1 by more than the margin: refused.
                assert_eq!(
                    checked_mean(total(sign * (1.0 + 2000.0 * eps))),
                    Err(ExactError::Inconsistent)
                );
            }
            for bad in [f64::INFINITY, f64::NEG_INFINITY, f64::NAN].map(T::from_f64) {
                assert_eq!(checked_mean(bad), Err(ExactError::Inconsistent));
            }
        }
        check::<f64>();
        check::<f32>();
    }
}

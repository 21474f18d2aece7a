//! The contact read as a machine: stall forces, no-load velocities and the
//! power balance of the steady state (the paper's class III, "functionally
//! equivalent to a vibrational drive or actuator", §3.2).
//!
//! # Conventions
//! The friction force on the body is `−μ(v)·F̄z` along `+x` (`F̄z` the mean
//! normal force: `k_z u_z0` in permanent contact, `k_z u_z0⟨w⁺⟩` with
//! lift-off, `k_z u_z0·D` for a curved profile, [`crate::model::mdr::powers`]);
//! an external force `F` on the body is balanced in the
//! quasi-static steady state when `F = μ(v)·F̄z`. The contact *pushes* forward
//! where `μ(v) < 0` for `v ≥ 0`.
//!
//! * **Stall force** forward: `−μ(0⁺)` when positive (the largest load the
//!   contact holds against at rest while pushing forward), backward `μ(0⁻)`
//!   when positive; both in units of `μ₀ F̄z`.
//! * **No-load velocity**: the root of `μ(v) = 0` between 0 and the critical
//!   velocity (μ increases with v, so it is unique; bracketed by `μ(0⁺) < 0`
//!   and `μ(v_c) = 1`).
//!
//! # Powers (dimensionless, unit `μ₀ F̄z ω W₀`)
//! With the stretch `s = u_x − u_x,c` (units W₀, so `f_x = μ₀F̄z s`), the drive
//! `u_x = Vθ + X(θ)`, `X = b cos(θ+φ)`, and the contact point's velocity
//! `u̇_x,c = V + X' − s'` (per unit phase θ = ωt):
//!
//! * input of the tangential transducer `P_in = ⟨s X'⟩`;
//! * input of the normal transducer `⟨f_z u̇_z⟩ = k_z⟨u_z u̇_z⟩ = 0`: the
//!   massless spring returns over a period all it takes (an exact derivative);
//! * output to the body `P_out = −⟨s⟩V = −(μ/μ₀)V` (positive while the contact
//!   pushes the body along its motion);
//! * friction loss `P_fric = ⟨s u̇_x,c⟩ ≥ 0` (only slip arcs contribute, where
//!   `s = ±w` and `u̇_x,c` has the sign of `s`).
//!
//! The spring's energy `s²/2` is periodic, so `⟨s s'⟩ = 0`, i.e.
//! `P_in = P_out + P_fric` exactly; the efficiency is `η = P_out/P_in`.
//! Each power is integrated in closed form over the arcs of the exact steady
//! state ([`exact::steady_state`]): on a stick arc `s = s₀ + V(θ−θ₀) + X(θ) − X(θ₀)`,
//! on a forward (backward) slip arc `s = +w` (`−w`), `w = 1 − a cos θ`.
//!
//! With lift-off (`a ≥ 1`, [`liftoff_powers`]) the same integrals run over
//! the contact window's arcs ([`liftoff::window_arcs`]) from `s = 0` at
//! landing to `s = 0` at lift-off (`|s| ≤ w → 0`), so again `⟨s s'⟩ = 0` and
//! the balance is exact; the unit is `μ₀F̄z ωW₀` with `F̄z = k_z u_z0⟨w⁺⟩`
//! (eq. L4). What becomes of the spring's energy when the contact opens is
//! derived in [`liftoff_powers`].

use crate::model::exact::{self, Arc, ArcKind, ExactError};
use crate::model::float::{Float, Math};
use crate::model::liftoff::{self, LiftOffError};
use crate::model::root::{illinois, Probe};
use crate::model::scene::Drive;

/// The powers of one steady state (unit `μ₀ F̄z ω W₀`; `F̄z = k_z u_z0`).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Powers<T> {
    /// `μ/μ₀` at this velocity.
    pub mu_over_mu0: T,
    /// Input of the tangential transducer, `⟨f_x u̇_x,osc⟩`.
    pub input: T,
    /// Output to the body, `−⟨f_x⟩v₀`.
    pub output: T,
    /// Friction loss at the contact, `⟨f_x u̇_x,c⟩`.
    pub friction: T,
}

impl<T: Float> Powers<T> {
    /// `η = P_out/P_in` where the contact delivers power (`P_out > 0`), else 0.
    pub fn efficiency(&self) -> T {
        if self.output > T::ZERO && self.input > T::ZERO {
            self.output / self.input
        } else {
            T::ZERO
        }
    }
}

/// The powers of the steady state at dimensionless velocity `v ≠ 0`.
///
/// # Errors
/// As [`exact::steady_state`].
pub fn powers<T: Float, M: Math<T>>(d: &Drive<T>, v: T) -> Result<Powers<T>, ExactError> {
    let (mu, arcs) = exact::steady_state::<T, M>(d, v)?;
    let last = arcs.last().ok_or(ExactError::Inconsistent)?;
    let first = arcs.first().ok_or(ExactError::Inconsistent)?;
    let (_, c_first) = M::sin_cos(first.start);
    // The period closes on the last arc's slip: s starts at ±w there.
    let s0 = match last.kind {
        ArcKind::SlipForward => T::ONE - d.a * c_first,
        ArcKind::SlipBackward => -(T::ONE - d.a * c_first),
        ArcKind::Stick => return Err(ExactError::Inconsistent),
    };
    let w = arc_work::<T, M>(d, T::ONE, v, &arcs, s0);
    let inv = T::ONE / T::TAU;
    Ok(Powers {
        mu_over_mu0: mu,
        input: w.input * inv,
        output: -mu * v,
        friction: w.friction * inv,
    })
}

/// The powers of a flat punch with lift-off (`a ≥ 1`) at any finite
/// dimensionless velocity (also 0), in units of `μ₀ F̄z ωW₀` with the mean
/// normal force `F̄z = k_z u_z0⟨w⁺⟩` (eq. L4).
///
/// # Energy over a period with a contact window
/// Off contact the spring carries no force (`s = 0`, `f_z = 0`): nothing is
/// done there. At landing `s = 0 = w`. Inside the window `|s| ≤ w`, and
/// `w → 0` at lift-off, so `s → 0` continuously: the stored energy
/// `½k_x s²` is 0 at both ends of the window and **nothing is released or
/// lost at the opening itself**. Where the contact sticks until lift-off the
/// stick trajectory itself reaches `s = 0` (the energy goes back to the
/// transducer through `⟨s X'⟩`); where it slips, `s = ±w` shrinks with the
/// band and the spring's energy `w²/2` is dissipated at the contact (the
/// term `−[w²/2]` of the slip arc's friction integral, with `u̇_x,c ≥ 0` on a
/// forward slip, so the loss is ≥ 0). The normal transducer's input
/// `k_z⟨u_z⁺ u̇_z⟩ = k_z⟨d((u_z⁺)²/2)/dt⟩ = 0` (a continuous periodic function's
/// derivative). With `P_in = ∫s X'`, `P_out = −V∫s`, `P_fric = ∫s(V + X' − s')`
/// over the window, `P_in − P_out − P_fric = [s²/2]_{θ_L}^{θ_R} = 0`: the
/// balance `P_in = P_out + P_fric` is exact, with the same closed forms as
/// [`powers`] on the window's arcs ([`liftoff::window_arcs`]), normalised by
/// `∫_window w dθ = 2π⟨w⁺⟩`.
///
/// # Errors
/// As [`liftoff::window_arcs`]; [`LiftOffError::Inconsistent`] when the
/// stretch at lift-off is not 0 to rounding (internal check).
pub fn liftoff_powers<T: Float, M: Math<T>>(d: &Drive<T>, v: T) -> Result<Powers<T>, LiftOffError> {
    let (mu, arcs) = liftoff::window_arcs::<T, M>(d, v)?;
    let w = arc_work::<T, M>(d, T::ONE, v, &arcs, T::ZERO);
    let scale = T::ONE + d.a + d.b + v.abs() * T::TAU;
    let tol = T::from_f64(1e3) * T::EPSILON * scale + T::from_f64(M::MAX_REL_ERROR) * scale;
    if w.s_end.is_nan() || w.s_end.abs() > tol {
        return Err(LiftOffError::Inconsistent);
    }
    let band = liftoff::mean_band::<T, M>(d.a) * T::TAU;
    Ok(Powers {
        mu_over_mu0: mu,
        input: w.input / band,
        output: -mu * v,
        friction: w.friction / band,
    })
}

/// The work integrals of a run of arcs (per unit phase, not yet divided by
/// a period): input `∫s X' dθ`, friction `∫s u̇_x,c dθ`, `∫s dθ`, and the
/// stretch at the last arc's end.
#[derive(Debug, Clone, Copy)]
pub(crate) struct ArcWork<T> {
    pub(crate) input: T,
    pub(crate) friction: T,
    /// `∫ s dθ`.
    pub(crate) stretch: T,
    pub(crate) s_end: T,
}

/// Integrates the input and friction work over consecutive arcs of the band
/// `w = offset − a cos θ`, starting from the stretch `s0` at the first arc's
/// start: on a stick arc `s = C + Vθ + X(θ)`, on a forward (backward) slip
/// arc `s = +w` (`−w`), `X = b cos(θ + φ)`.
pub(crate) fn arc_work<T: Float, M: Math<T>>(
    d: &Drive<T>,
    offset: T,
    v: T,
    arcs: &[Arc<T>],
    s0: T,
) -> ArcWork<T> {
    let (a, bc, bs) = (d.a, d.bc, d.bs);
    // X(θ) = b cos(θ+φ) = bc cos θ − bs sin θ;  ∫X = bc sin θ + bs cos θ.
    let x_at = |s: T, c: T| bc * c - bs * s;
    let x_int = |s: T, c: T| bc * s + bs * c;
    let w_at = |c: T| offset - a * c;
    // ∫ w X' dθ = offset·X − a·∫cos θ·X' dθ, and cos θ·X' = −b cos θ sin(θ+φ)
    // = −(b/2)(sin(2θ+φ) + sin φ): ∫ = (b/4)cos(2θ+φ) − (b sin φ/2)θ, with
    // b cos(2θ+φ) = bc cos 2θ − bs sin 2θ.
    let wx_int = |t: T, s: T, c: T| {
        let (s2, c2) = (T::TWO * s * c, c * c - s * s);
        offset * x_at(s, c) - a * ((bc * c2 - bs * s2) * T::from_f64(0.25) - bs * T::HALF * t)
    };
    let mut s0 = s0;
    let (mut input, mut friction, mut stretch) = (T::ZERO, T::ZERO, T::ZERO);
    for arc in arcs {
        let (t0, t1) = (arc.start, arc.end);
        let (sn0, cs0) = M::sin_cos(t0);
        let (sn1, cs1) = M::sin_cos(t1);
        match arc.kind {
            ArcKind::Stick => {
                // s = C + Vθ + X(θ), C = s₀ − Vθ₀ − X(θ₀).
                // ∫ s X' = C[X] + V([θX] − [∫X]) + [X²/2].
                let (x0, x1) = (x_at(sn0, cs0), x_at(sn1, cs1));
                let cc = s0 - v * t0 - x0;
                input += cc * (x1 - x0)
                    + v * ((t1 * x1 - t0 * x0) - (x_int(sn1, cs1) - x_int(sn0, cs0)))
                    + (x1 * x1 - x0 * x0) * T::HALF;
                stretch += cc * (t1 - t0)
                    + v * (t1 - t0) * (t1 + t0) * T::HALF
                    + (x_int(sn1, cs1) - x_int(sn0, cs0));
                s0 = cc + v * t1 + x1;
            }
            ArcKind::SlipForward | ArcKind::SlipBackward => {
                let sign = if arc.kind == ArcKind::SlipForward {
                    T::ONE
                } else {
                    -T::ONE
                };
                // s = ±w: ∫ s X' = ±∫ w X';
                // ∫ s u̇_c = ±(V∫w + ∫wX') − [w²/2]  (s' = ±a sin θ, w w' = a w sin θ).
                let wx = wx_int(t1, sn1, cs1) - wx_int(t0, sn0, cs0);
                let w_int = offset * (t1 - t0) - a * (sn1 - sn0);
                let (w0, w1) = (w_at(cs0), w_at(cs1));
                input += sign * wx;
                stretch += sign * w_int;
                friction += sign * (v * w_int + wx) - (w1 * w1 - w0 * w0) * T::HALF;
                s0 = sign * w1;
            }
        }
    }
    ArcWork {
        input,
        friction,
        stretch,
        s_end: s0,
    }
}

/// The actuator characteristics of a drive (dimensionless: forces in
/// `μ₀ F̄z`, velocities in `ωW₀`).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LoadLine<T> {
    /// `−μ(0⁺)/μ₀` when positive, else 0.
    pub stall_forward: T,
    /// `μ(0⁻)/μ₀` when positive, else 0.
    pub stall_backward: T,
    /// Root of μ(V) on `(0, c)` when the contact pushes forward, else 0.
    pub no_load_forward: T,
    /// `|V|` of the root of μ(V) on `(−c', 0)` when it pushes backward, else 0.
    pub no_load_backward: T,
}

/// Stall forces and no-load velocities of the flat punch in permanent
/// contact ([`load_line_of`] with the exact solver).
///
/// # Errors
/// As [`exact::limits_at_zero`] and [`exact::mu_over_mu0`].
pub fn load_line<T: Float, M: Math<T>>(d: &Drive<T>) -> Result<LoadLine<T>, ExactError> {
    let (plus, minus) = exact::limits_at_zero::<T, M>(d)?;
    load_line_of(plus, minus, d.c_forward::<M>(), d.c_backward::<M>(), |v| {
        exact::mu_over_mu0::<T, M>(d, v)
    })
}

/// Stall forces and no-load velocities of any law `μ(V)/μ₀` (every contact
/// model: `mu` is its solver at `V ≠ 0`): `μ(0⁺) = plus`, `μ(0⁻) = minus`
/// (equal where μ at rest is unique, e.g. with lift-off), `μ = ±1` beyond the
/// critical velocities `c_forward`, `−c_backward`. The no-load velocities are
/// the roots of `mu` in `(0, c)` and `(−c', 0)`, bracketed by the signs at
/// the ends (unique where the law increases).
///
/// # Errors
/// Those of `mu`.
pub fn load_line_of<T: Float, E>(
    plus: T,
    minus: T,
    c_forward: T,
    c_backward: T,
    mut mu: impl FnMut(T) -> Result<T, E>,
) -> Result<LoadLine<T>, E> {
    let forward = if plus < T::ZERO && c_forward > T::ZERO {
        root(T::ZERO, c_forward, plus, T::ONE, &mut mu)?
    } else {
        T::ZERO
    };
    let backward = if minus > T::ZERO && c_backward > T::ZERO {
        -root(-c_backward, T::ZERO, -T::ONE, minus, &mut mu)?
    } else {
        T::ZERO
    };
    Ok(LoadLine {
        // `if` rather than `max`: `(-0.0).max(0.0)` may be −0, printed `-0`.
        stall_forward: if -plus > T::ZERO { -plus } else { T::ZERO },
        stall_backward: if minus > T::ZERO { minus } else { T::ZERO },
        no_load_forward: forward,
        no_load_backward: backward,
    })
}

/// The root of `f` in `(lo, hi)` given `f(lo) = flo < 0 < f(hi) = fhi`:
/// Illinois regula falsi ([`illinois`]) to a bracket width of
/// 8ε·|hi − lo| or 200 iterations. Its error adds the solver's error over
/// the slope.
fn root<T: Float, E>(
    lo: T,
    hi: T,
    flo: T,
    fhi: T,
    f: &mut impl FnMut(T) -> Result<T, E>,
) -> Result<T, E> {
    let width = T::from_f64(8.0) * T::EPSILON * (hi - lo);
    let (lo, hi) = illinois(
        (lo, hi, flo, fhi),
        |_, _| width,
        200,
        |x| f(x).map(Probe::Value),
    )?;
    Ok((lo + hi) * T::HALF)
}

/// An operating point on the forward or the backward load line.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct OperatingPoint<T> {
    /// Dimensionless velocity V, signed: `V > 0` on the forward line,
    /// `V < 0` on the backward one.
    pub v: T,
    /// The contact's force on the body `−μ/μ₀` along `+x` (units μ₀F̄z):
    /// positive on the forward line, negative on the backward one, so that
    /// `P_out = force·V > 0`; the load it holds is the external force
    /// `F = μF̄z = −force`.
    pub force: T,
    /// The powers there.
    pub powers: Powers<T>,
}

/// What to maximise on the load line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Objective {
    /// Output power `P_out`.
    Power,
    /// Efficiency `η = P_out/P_in`.
    Efficiency,
}

impl Objective {
    /// The value maximised: `P_out` or `η` of `p`.
    pub fn of<T: Float>(self, p: &Powers<T>) -> T {
        match self {
            Objective::Power => p.output,
            Objective::Efficiency => p.efficiency(),
        }
    }
}

/// The forward operating point (0 < V < no-load velocity) that maximises
/// `objective`, or `None` when the contact does not push forward
/// ([`best_forward_of`] on [`powers`]; flat punch in permanent contact).
///
/// # Errors
/// As [`powers`].
pub fn best_forward<T: Float, M: Math<T>>(
    d: &Drive<T>,
    line: &LoadLine<T>,
    objective: Objective,
) -> Result<Option<OperatingPoint<T>>, ExactError> {
    best_forward_of(line, objective, |v| powers::<T, M>(d, v))
}

/// The operating point over both load lines that maximises `objective`
/// ([`best_of`] on [`powers`]; flat punch in permanent contact), `None`
/// when the contact pushes neither way.
///
/// # Errors
/// As [`powers`].
pub fn best<T: Float, M: Math<T>>(
    d: &Drive<T>,
    line: &LoadLine<T>,
    objective: Objective,
) -> Result<Option<OperatingPoint<T>>, ExactError> {
    best_of(line, objective, |v| powers::<T, M>(d, v))
}

/// The forward operating point maximising `objective` for any contact
/// model whose powers `powers(V)` are known (e.g. [`liftoff_powers`]), by
/// [`maximise_forward`]; `None` when the contact does not push forward.
///
/// # Errors
/// Those of `powers`.
pub fn best_forward_of<T: Float, E>(
    line: &LoadLine<T>,
    objective: Objective,
    mut powers: impl FnMut(T) -> Result<Powers<T>, E>,
) -> Result<Option<OperatingPoint<T>>, E> {
    let vnl = line.no_load_forward;
    if vnl <= T::ZERO {
        return Ok(None);
    }
    let v = maximise_forward(vnl, |v| Ok(objective.of(&powers(v)?)))?;
    let p = powers(v)?;
    Ok(Some(OperatingPoint {
        v,
        force: -p.mu_over_mu0,
        powers: p,
    }))
}

/// The backward operating point (`−v_nl' < V < 0`) maximising `objective`,
/// or `None` when the contact does not push backward: [`maximise_forward`]
/// on `U = −V ∈ (0, v_nl')` (the backward line read in its own direction;
/// `P_out = −μV > 0` there since `μ > 0`).
///
/// # Errors
/// Those of `powers`.
pub fn best_backward_of<T: Float, E>(
    line: &LoadLine<T>,
    objective: Objective,
    mut powers: impl FnMut(T) -> Result<Powers<T>, E>,
) -> Result<Option<OperatingPoint<T>>, E> {
    let vnl = line.no_load_backward;
    if vnl <= T::ZERO {
        return Ok(None);
    }
    let u = maximise_forward(vnl, |u| Ok(objective.of(&powers(-u)?)))?;
    let p = powers(-u)?;
    Ok(Some(OperatingPoint {
        v: -u,
        force: -p.mu_over_mu0,
        powers: p,
    }))
}

/// The operating point maximising `objective` over **both** load lines
/// (forward, [`best_forward_of`], and backward, [`best_backward_of`]; the
/// forward one where they tie), or `None` when the contact pushes neither
/// way. Under the mirror `φ → φ + π` (`μ(V; φ + π) = −μ(−V; φ)`) the
/// powers at `−V` equal those at `V`, so the point maps to `−V` with the
/// same powers.
///
/// # Errors
/// Those of `powers`.
pub fn best_of<T: Float, E>(
    line: &LoadLine<T>,
    objective: Objective,
    mut powers: impl FnMut(T) -> Result<Powers<T>, E>,
) -> Result<Option<OperatingPoint<T>>, E> {
    let f = best_forward_of(line, objective, &mut powers)?;
    let b = best_backward_of(line, objective, &mut powers)?;
    Ok(match (f, b) {
        (Some(f), Some(b)) => {
            if objective.of(&b.powers) > objective.of(&f.powers) {
                Some(b)
            } else {
                Some(f)
            }
        }
        (f, b) => f.or(b),
    })
}

/// The velocity in `(0, vnl)` maximising `value` (any contact model; e.g.
/// the output power `−μ(V)V` needs only the law): a scan of 64 points
/// locates the best cell, golden-section search refines it to a velocity
/// width of 1e-9·vnl (the objective is smooth inside the cell).
///
/// # Errors
/// Those of `value`.
pub fn maximise_forward<T: Float, E>(
    vnl: T,
    mut value: impl FnMut(T) -> Result<T, E>,
) -> Result<T, E> {
    const SCAN: usize = 64;
    let step = vnl / T::from_f64(SCAN as f64);
    let mut best = (0usize, -T::MAX);
    for i in 1..SCAN {
        let f = value(step * T::from_f64(i as f64))?;
        if f > best.1 {
            best = (i, f);
        }
    }
    let mut lo = step * T::from_f64(best.0 as f64 - 1.0);
    let mut hi = step * T::from_f64(best.0 as f64 + 1.0);
    if lo <= T::ZERO {
        lo = step * T::from_f64(1e-6);
    }
    let g = T::from_f64(0.618_033_988_749_894_9);
    let mut x1 = hi - g * (hi - lo);
    let mut x2 = lo + g * (hi - lo);
    let mut f1 = value(x1)?;
    let mut f2 = value(x2)?;
    let tol = T::from_f64(1e-9) * vnl;
    for _ in 0..200 {
        if hi - lo <= tol {
            break;
        }
        if f1 < f2 {
            lo = x1;
            x1 = x2;
            f1 = f2;
            x2 = lo + g * (hi - lo);
            f2 = value(x2)?;
        } else {
            hi = x2;
            x2 = x1;
            f2 = f1;
            x1 = hi - g * (hi - lo);
            f1 = value(x1)?;
        }
    }
    Ok((lo + hi) * T::HALF)
}

//! Inverse design: the drive value that attains a target μ, or that maximises
//! an objective, with the other drive quantities held fixed.
//!
//! # The problem (dimensionless, see [`crate::model::scene`])
//! With the velocity `V = v₀/(ωW₀)` and two of the three drive groups of
//! eq. 25 fixed, `μ/μ₀` is a continuous function of the third, the *knob*
//! ([`Knob`]): `a = Δu_z/u_z0` on `[lo, hi] ⊂ [0, 1)`, `b = k_xΔu_x/(μ₀k_z u_z0)`
//! on `[lo, hi] ⊂ [0, ∞)`, or φ on the circle `[0, 2π)`. It is not monotone in
//! general (dual-mode drives have interior extrema), so the search is:
//!
//! 1. **Scan**: the exact law ([`exact::mu_over_mu0`]) on a uniform grid of the
//!    knob; the caller's buffer sets the resolution (`n` points: `n − 1` cells
//!    for an amplitude, `n` cells for the phase).
//! 2. **Monotone pieces**: every strict local extremum of the scan is refined by
//!    golden-section search inside its two neighbouring cells (to a width of a
//!    few ulps; the best *evaluated* point is kept, so a refined extremum is
//!    never worse than the scan point). The scan points and the refined
//!    extrema split the range into pieces on which the law is taken to be
//!    monotone — true unless a pair of extrema hides inside one cell, a
//!    feature narrower than the scan resolution.
//! 3. **Roots**: on each piece whose ends straddle the target, Illinois
//!    regula falsi to a residual `|μ − μ*|/μ₀ ≤` [`exact::error_bound`]`/16`
//!    (or a bracket of a few ulps). A breakpoint within the bound of the target
//!    is itself a solution (a target at an extremum).
//!
//! **Guarantees.** Every reported solution is a drive at which the exact law
//! gives the target to within its residual (reported) plus the exact
//! solver's bound. The reachable range is the least and greatest value over
//! all breakpoints — values that are attained — so a target inside it always
//! has a solution (intermediate values on the sequence of breakpoints). A
//! target outside it is refused ([`InverseError::OutOfReach`]) with the range;
//! the true range can be wider only by a feature narrower than one scan cell
//! or by the solver's bound.
//!
//! **Objectives** ([`Objective`]) are maximised the same way: scan, refine
//! every local maximum, keep the best evaluated point.
//!
//! No allocation: the scan buffer comes from the caller, solutions are kept in
//! a `heapless::Vec` of [`MAX_SOLUTIONS`] (more are counted, not stored).

use heapless::Vec;

use crate::model::analytic::static_friction::StaticFriction;
use crate::model::exact::{self, ExactError};
use crate::model::float::{Float, Math};
use crate::model::mdr::MdrError;
use crate::model::regime::{classify_drive, ClassifyOptions, Regime};
use crate::model::root::{illinois, Probe};
use crate::model::scene::{Drive, Groups, Scene, SceneError};

/// Most solutions kept by [`solve_target`] (more are counted in
/// [`TargetOutcome::found`]).
pub const MAX_SOLUTIONS: usize = 16;

/// Fewest points a scan buffer must have.
pub const MIN_SCAN_POINTS: usize = 3;

/// Most evaluations of one golden-section refinement or one root search.
const MAX_REFINE: u32 = 200;

/// The drive quantity that is adjusted.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Knob {
    /// `a = Δu_z/u_z0` (normal amplitude).
    Duz,
    /// `b = k_xΔu_x/(μ₀k_z u_z0) = Δu_x/W₀` (tangential amplitude).
    Dux,
    /// φ, rad, on the circle `[0, 2π)`.
    Phase,
}

impl Knob {
    /// The name used on the command line (`duz`, `dux`, `phase`).
    pub const fn name(self) -> &'static str {
        match self {
            Knob::Duz => "duz",
            Knob::Dux => "dux",
            Knob::Phase => "phase",
        }
    }
}

/// What [`maximize`] maximises.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Objective {
    /// The ratchet's asymmetry `max |μ(v) + μ(−v)|/μ₀` as
    /// [`classify_drive`] computes it ([`crate::model::regime::Classification::asymmetry`]),
    /// over the drives that are *not* actuators (the contact can rest with zero
    /// force: a dynamic ratchet or active control). Actuator drives are infeasible.
    Asymmetry,
    /// The forward stall force `−μ(0⁺)/μ₀` (units `μ₀F̄z`, `F̄z = k_z u_z0`;
    /// [`exact::limits_at_zero`]): the load the contact holds while pushing forward.
    StallForce,
}

/// Why the inverse problem has no answer.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum InverseError<T> {
    /// The fixed groups are invalid ([`Groups::validate`]).
    BadGroups(SceneError),
    /// The knob range is not finite, empty (`lo ≥ hi`), negative, or reaches
    /// lift-off (`a ≥ 1`).
    BadRange,
    /// `V` is zero or not finite (a target needs a moving contact: at rest μ is
    /// not unique).
    BadVelocity,
    /// The target `μ/μ₀` is not finite or not inside `(−1, 1)` (`|μ| = μ₀` is
    /// continuous sliding, reached on a whole range of drives).
    BadTarget,
    /// The scan buffer has fewer than [`MIN_SCAN_POINTS`] points.
    BadScan,
    /// The target is outside the reachable range `[min, max]` (`μ/μ₀`).
    OutOfReach {
        /// Least `μ/μ₀` over the range of the knob.
        min: T,
        /// Greatest `μ/μ₀`.
        max: T,
    },
    /// No drive in the range is feasible for the objective (every one is an
    /// actuator for [`Objective::Asymmetry`]).
    Infeasible,
    /// The exact solver failed.
    Exact(ExactError),
    /// The MDR quadrature of a curved profile failed (the search of
    /// [`solve_target_with`] or [`maximize_with`] over a profile's law).
    Mdr(MdrError),
}

impl<T: Float> core::fmt::Display for InverseError<T> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            InverseError::BadGroups(e) => write!(f, "{e}"),
            InverseError::BadRange => f.write_str(
                "the range of the adjusted quantity must be finite, non-empty, >= 0 and below lift-off",
            ),
            InverseError::BadVelocity => {
                f.write_str("the velocity must be finite and != 0 (at rest mu is not unique)")
            }
            InverseError::BadTarget => f.write_str("the target mu/mu0 must lie strictly between -1 and 1"),
            InverseError::BadScan => write!(f, "the scan needs at least {MIN_SCAN_POINTS} points"),
            InverseError::OutOfReach { min, max } => write!(
                f,
                "out of reach: reachable mu/mu0 {}..{}",
                min.to_f64(),
                max.to_f64()
            ),
            InverseError::Infeasible => f.write_str("no drive in the range is feasible"),
            InverseError::Exact(e) => match e {
                ExactError::BadVelocity(s) => write!(f, "exact solver: {s}"),
                ExactError::BadDrive => f.write_str("exact solver: invalid drive"),
                ExactError::Inconsistent => {
                    f.write_str("exact solver: the period did not close (internal check)")
                }
                ExactError::IllConditioned => f.write_str(
                    "exact solver: the drive is too large to resolve in this float type",
                ),
            },
            InverseError::Mdr(e) => write!(f, "profile quadrature: {e}"),
        }
    }
}

impl<T: Float> core::error::Error for InverseError<T> {}

impl<T> From<ExactError> for InverseError<T> {
    fn from(e: ExactError) -> Self {
        InverseError::Exact(e)
    }
}

impl<T> From<MdrError> for InverseError<T> {
    fn from(e: MdrError) -> Self {
        InverseError::Mdr(e)
    }
}

/// One evaluated drive: the knob value and the function there.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Point<T> {
    /// The knob (`a`, `b`, or φ in rad wrapped into `[0, 2π)`).
    pub x: T,
    /// `μ/μ₀` (targets) or the objective (maximisation).
    pub value: T,
}

/// The search problem: the fixed groups, the knob and its range.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Problem<T> {
    groups: Groups<T>,
    knob: Knob,
    lo: T,
    hi: T,
    /// `(sin φ, cos φ)` of the fixed phase (amplitude knobs).
    sc: (T, T),
}

impl<T: Float> Problem<T> {
    /// The problem of adjusting `knob` in `[lo, hi]` (ignored for
    /// [`Knob::Phase`], whose range is the circle) with the other groups as in
    /// `groups` (the knob's own value there is ignored).
    ///
    /// # Errors
    /// [`InverseError::BadGroups`], [`InverseError::BadRange`].
    pub fn new<M: Math<T>>(
        groups: Groups<T>,
        knob: Knob,
        lo: T,
        hi: T,
    ) -> Result<Self, InverseError<T>> {
        groups.validate().map_err(InverseError::BadGroups)?;
        let (lo, hi) = match knob {
            Knob::Phase => (T::ZERO, T::TAU),
            Knob::Duz | Knob::Dux => {
                let ok = lo.is_finite() && hi.is_finite() && lo >= T::ZERO && lo < hi;
                if !ok || (knob == Knob::Duz && hi >= T::ONE) {
                    return Err(InverseError::BadRange);
                }
                (lo, hi)
            }
        };
        Ok(Problem {
            groups,
            knob,
            lo,
            hi,
            sc: M::sin_cos(groups.phi),
        })
    }

    /// The knob.
    pub fn knob(&self) -> Knob {
        self.knob
    }

    /// The knob's range `(lo, hi)` (`(0, 2π)` for the phase).
    pub fn range(&self) -> (T, T) {
        (self.lo, self.hi)
    }

    /// The groups with the knob set to `x`.
    pub fn groups_at(&self, x: T) -> Groups<T> {
        let mut g = self.groups;
        match self.knob {
            Knob::Duz => g.duz_rel = x,
            Knob::Dux => g.dux_rel = x,
            Knob::Phase => g.phi = x,
        }
        g
    }

    /// The dimensionless drive with the knob set to `x`.
    pub fn drive_at<M: Math<T>>(&self, x: T) -> Drive<T> {
        let g = self.groups_at(x);
        match self.knob {
            Knob::Phase => Drive::new::<M>(g.duz_rel, g.dux_rel, x),
            Knob::Duz | Knob::Dux => {
                let (s, c) = self.sc;
                Drive {
                    a: g.duz_rel,
                    b: g.dux_rel,
                    bc: g.dux_rel * c,
                    bs: g.dux_rel * s,
                }
            }
        }
    }

    /// `μ/μ₀` at velocity `v` (dimensionless, ≠ 0) with the knob at `x`.
    ///
    /// # Errors
    /// As [`exact::mu_over_mu0`].
    pub fn mu_at<M: Math<T>>(&self, x: T, v: T) -> Result<T, ExactError> {
        exact::mu_over_mu0::<T, M>(&self.drive_at::<M>(x), v)
    }

    /// The exact solver's bound ([`exact::error_bound`]) with the knob at `x`.
    pub fn bound_at<M: Math<T>>(&self, x: T) -> T {
        exact::error_bound::<T, M>(&self.drive_at::<M>(x))
    }

    /// The objective with the knob at `x`; `None` where infeasible.
    ///
    /// # Errors
    /// As [`exact::limits_at_zero`] and [`classify_drive`].
    pub fn objective_at<M: Math<T>>(
        &self,
        objective: Objective,
        x: T,
    ) -> Result<Option<T>, InverseError<T>> {
        let d = self.drive_at::<M>(x);
        match objective {
            Objective::StallForce => Ok(Some(-exact::limits_at_zero::<T, M>(&d)?.0)),
            Objective::Asymmetry => {
                let scene =
                    Scene::dimensionless(self.groups_at(x)).map_err(InverseError::BadGroups)?;
                let c = classify_drive::<T, M>(
                    &d,
                    StaticFriction::of_with::<M>(&scene),
                    &ClassifyOptions::default(),
                )?;
                Ok((c.regime != Regime::Actuator).then_some(c.asymmetry))
            }
        }
    }

    /// Knob value of scan point `j` (unwrapped for the phase: `j` may exceed
    /// the point count) for an `n`-point scan.
    fn grid(&self, j: usize, n: usize) -> T {
        match self.knob {
            Knob::Phase => T::TAU * T::from_u32(j as u32) / T::from_u32(n as u32),
            Knob::Duz | Knob::Dux => {
                if j + 1 >= n {
                    self.hi
                } else {
                    self.lo
                        + (self.hi - self.lo) * T::from_u32(j as u32) / T::from_u32(n as u32 - 1)
                }
            }
        }
    }

    fn wrap(&self, x: T) -> T {
        if self.knob != Knob::Phase {
            return x;
        }
        let mut y = x;
        while y >= T::TAU {
            y -= T::TAU;
        }
        while y < T::ZERO {
            y += T::TAU;
        }
        y
    }
}

/// The solutions of a target problem (no `defmt::Format`: it holds a
/// `heapless::Vec`, whose `defmt` support is not enabled).
#[derive(Debug, Clone, PartialEq)]
pub struct TargetOutcome<T> {
    /// Solutions in increasing knob order (the phase wrapped into `[0, 2π)`,
    /// in scan order from the scan minimum), at most [`MAX_SOLUTIONS`].
    pub solutions: Vec<Point<T>, MAX_SOLUTIONS>,
    /// How many solutions were found (may exceed `solutions.len()`).
    pub found: u32,
    /// The least `μ/μ₀` over the breakpoints (attained there).
    pub min: Point<T>,
    /// The greatest `μ/μ₀` over the breakpoints (attained there).
    pub max: Point<T>,
}

impl<T: Float> TargetOutcome<T> {
    /// The solution nearest `x` (circular distance for the phase).
    pub fn nearest(&self, knob: Knob, x: T) -> Option<Point<T>> {
        let dist = |y: T| {
            let d = (y - x).abs();
            if knob == Knob::Phase {
                let m = {
                    let mut r = d;
                    while r >= T::TAU {
                        r -= T::TAU;
                    }
                    r
                };
                m.min(T::TAU - m)
            } else {
                d
            }
        };
        let mut best: Option<Point<T>> = None;
        for s in &self.solutions {
            if best.is_none_or(|b| dist(s.x) < dist(b.x)) {
                best = Some(*s);
            }
        }
        best
    }
}

/// All drives of `p` at which `μ(v)/μ₀ = target` (module docs for the method):
/// [`solve_target_with`] on the flat punch's exact law ([`Problem::mu_at`],
/// bound [`Problem::bound_at`]). `scan` is the work buffer; its length sets
/// the scan resolution.
///
/// # Errors
/// [`InverseError::BadVelocity`], [`InverseError::BadTarget`],
/// [`InverseError::BadScan`], [`InverseError::OutOfReach`] (no solution: the
/// target is outside the reachable range), [`InverseError::Exact`].
pub fn solve_target<T: Float, M: Math<T>>(
    p: &Problem<T>,
    v: T,
    target: T,
    scan: &mut [T],
) -> Result<TargetOutcome<T>, InverseError<T>> {
    if !v.is_finite() || v == T::ZERO {
        return Err(InverseError::BadVelocity);
    }
    let mut mu = |x: T| Ok(p.mu_at::<M>(x, v)?);
    solve_target_with(p, target, scan, &mut mu, &|x| p.bound_at::<M>(x))
}

/// All knob values of `p` at which a velocity law gives `target` (module
/// docs for the method): `mu(x)` is `μ/μ₀` with the knob at `x` and the
/// velocity fixed by the caller, `bound(x)` a bound on its error there —
/// the flat punch's exact law and [`exact::error_bound`] ([`solve_target`]),
/// or a curved profile's MDR quadrature
/// ([`crate::model::mdr::mu_over_mu0`]) and the tolerance it was asked
/// for. A breakpoint within its bound of the target is a solution; a root
/// is refined to a residual of a sixteenth of the bound at the iterate (or
/// a bracket of `8ε` relative).
///
/// # Errors
/// [`InverseError::BadTarget`], [`InverseError::BadScan`],
/// [`InverseError::OutOfReach`], and the law's own errors.
pub fn solve_target_with<T: Float>(
    p: &Problem<T>,
    target: T,
    scan: &mut [T],
    mu: &mut impl FnMut(T) -> Result<T, InverseError<T>>,
    bound: &impl Fn(T) -> T,
) -> Result<TargetOutcome<T>, InverseError<T>> {
    if !(target.is_finite() && target > -T::ONE && target < T::ONE) {
        return Err(InverseError::BadTarget);
    }
    // The scan and the root searches take turns (never nested).
    let mu = core::cell::RefCell::new(mu);
    let mut f = |x: T| (mu.borrow_mut())(x);
    let mut out = TargetOutcome {
        solutions: Vec::new(),
        found: 0,
        min: Point {
            x: T::ZERO,
            value: T::ZERO,
        },
        max: Point {
            x: T::ZERO,
            value: T::ZERO,
        },
    };
    let push = |out: &mut TargetOutcome<T>, q: Point<T>| {
        let q = Point {
            x: p.wrap(q.x),
            ..q
        };
        out.found += 1;
        let _ = out.solutions.push(q);
    };
    let tol = |x: T| bound(x);
    let on_piece =
        |l: Point<T>, r: Point<T>, out: &mut TargetOutcome<T>| -> Result<(), InverseError<T>> {
            let (gl, gr) = (l.value - target, r.value - target);
            if gl.abs() <= tol(l.x) {
                push(out, l);
            } else if gl * gr < T::ZERO && gr.abs() > tol(r.x) {
                let root = bracketed_with(target, l, r, &mut |x| (mu.borrow_mut())(x), bound)?;
                push(out, root);
            }
            Ok(())
        };
    let (min, max, end) = walk(p, scan, &mut f, &mut |l, r| on_piece(l, r, &mut out))?;
    if p.knob != Knob::Phase && (end.value - target).abs() <= tol(end.x) {
        push(&mut out, end);
    }
    out.min = Point {
        x: p.wrap(min.x),
        ..min
    };
    out.max = Point {
        x: p.wrap(max.x),
        ..max
    };
    if out.found == 0 {
        return Err(InverseError::OutOfReach {
            min: min.value,
            max: max.value,
        });
    }
    Ok(out)
}

/// The root of `μ(v)/μ₀ = target` between two drives whose values straddle
/// it: [`bracketed_with`] on the flat punch's exact law. This is the step a
/// controller's feedforward uses on a range known to be monotone.
///
/// # Errors
/// [`InverseError::Exact`].
pub fn bracketed<T: Float, M: Math<T>>(
    p: &Problem<T>,
    v: T,
    target: T,
    l: Point<T>,
    r: Point<T>,
) -> Result<Point<T>, InverseError<T>> {
    let mut mu = |x: T| Ok(p.mu_at::<M>(x, v)?);
    bracketed_with(target, l, r, &mut mu, &|x| p.bound_at::<M>(x))
}

/// The root of `mu(x) = target` between two points whose values straddle
/// it: Illinois regula falsi to a residual of `bound(x)/16` at the iterate
/// or a bracket of `8ε` relative; at most 200 evaluations. The law is
/// continuous in the knob, so a root exists; on a monotone bracket it is
/// the only one. Returns the best evaluated point.
///
/// # Errors
/// The law's own.
pub fn bracketed_with<T: Float>(
    target: T,
    l: Point<T>,
    r: Point<T>,
    mu: &mut impl FnMut(T) -> Result<T, InverseError<T>>,
    bound: &impl Fn(T) -> T,
) -> Result<Point<T>, InverseError<T>> {
    let mut best = if (l.value - target).abs() <= (r.value - target).abs() {
        l
    } else {
        r
    };
    illinois(
        (l.x, r.x, l.value - target, r.value - target),
        |lo: T, hi: T| T::from_f64(8.0) * T::EPSILON * (lo.abs() + hi.abs()),
        MAX_REFINE,
        |x| {
            let fx = mu(x)?;
            let g = fx - target;
            if g.abs() < (best.value - target).abs() {
                best = Point { x, value: fx };
            }
            Ok::<_, InverseError<T>>(if g.abs() <= bound(x) / T::from_f64(16.0) {
                Probe::Stop
            } else {
                Probe::Value(g)
            })
        },
    )?;
    Ok(best)
}

/// The drive of `p` that maximises `objective` (module docs for the method):
/// [`maximize_with`] on the flat punch's [`Problem::objective_at`].
///
/// # Errors
/// [`InverseError::BadScan`], [`InverseError::Infeasible`] (no feasible
/// point found), [`InverseError::Exact`].
pub fn maximize<T: Float, M: Math<T>>(
    p: &Problem<T>,
    objective: Objective,
    scan: &mut [T],
) -> Result<Point<T>, InverseError<T>> {
    maximize_with(p, scan, &mut |x| p.objective_at::<M>(objective, x))
}

/// The knob value of `p` that maximises `f` (`None` where infeasible; the
/// flat punch's objectives, or a curved profile's from its MDR quadrature):
/// the best evaluated point over the scan and the refined local maxima.
///
/// # Errors
/// [`InverseError::BadScan`], [`InverseError::Infeasible`] (no feasible
/// point found), and `f`'s own.
pub fn maximize_with<T: Float>(
    p: &Problem<T>,
    scan: &mut [T],
    f: &mut impl FnMut(T) -> Result<Option<T>, InverseError<T>>,
) -> Result<Point<T>, InverseError<T>> {
    let mut g = |x: T| Ok(f(x)?.unwrap_or(-T::MAX));
    let (_, max, _) = walk(p, scan, &mut g, &mut |_, _| Ok(()))?;
    if max.value <= -T::MAX {
        return Err(InverseError::Infeasible);
    }
    Ok(Point {
        x: p.wrap(max.x),
        ..max
    })
}

/// The least, greatest and last breakpoints of a [`walk`].
type Walked<T> = (Point<T>, Point<T>, Point<T>);

/// Scans, refines the local extrema, and hands every monotone piece
/// `(left, right)` to `piece` in order. Returns the least and greatest
/// breakpoints and the last one.
fn walk<T: Float>(
    p: &Problem<T>,
    scan: &mut [T],
    f: &mut impl FnMut(T) -> Result<T, InverseError<T>>,
    piece: &mut impl FnMut(Point<T>, Point<T>) -> Result<(), InverseError<T>>,
) -> Result<Walked<T>, InverseError<T>> {
    let n = scan.len();
    if n < MIN_SCAN_POINTS {
        return Err(InverseError::BadScan);
    }
    for (j, s) in scan.iter_mut().enumerate() {
        *s = f(p.grid(j, n))?;
    }
    let periodic = p.knob == Knob::Phase;
    let at = |j: usize| scan[j % n];
    // Start and end points, and the interior scan indices (unwrapped).
    let (start, end, first, last) = if periodic {
        // Start at the scan's minimum, refined: the circle becomes a line
        // from there to the same point one turn later.
        let mut s = 0;
        for j in 1..n {
            if scan[j] < scan[s] {
                s = j;
            }
        }
        let j0 = s + n; // unwrapped index with room for j0 − 1
        let seed = Point {
            x: p.grid(j0, n),
            value: scan[s],
        };
        let e = golden(p.grid(j0 - 1, n), p.grid(j0 + 1, n), -T::ONE, seed, f)?;
        let end = Point {
            x: e.x + T::TAU,
            value: e.value,
        };
        (e, end, j0 + 1, j0 + n - 1)
    } else {
        let start = Point {
            x: p.grid(0, n),
            value: scan[0],
        };
        let end = Point {
            x: p.grid(n - 1, n),
            value: scan[n - 1],
        };
        (start, end, 1, n - 2)
    };
    let (mut min, mut max) = (start, start);
    let note = |q: Point<T>, min: &mut Point<T>, max: &mut Point<T>| {
        if q.value < min.value {
            *min = q;
        }
        if q.value > max.value {
            *max = q;
        }
    };
    let mut cur = start;
    for j in first..=last {
        let (fl, fm, fr) = (at(j - 1), at(j), at(j + 1));
        let is_max = (fm > fl && fm >= fr) || (fm >= fl && fm > fr);
        let is_min = (fm < fl && fm <= fr) || (fm <= fl && fm < fr);
        let q = if is_max || is_min {
            let l = p.grid(j - 1, n).max(cur.x);
            let r = p.grid(j + 1, n).min(end.x);
            let sign = if is_max { T::ONE } else { -T::ONE };
            golden(
                l,
                r,
                sign,
                Point {
                    x: p.grid(j, n),
                    value: fm,
                },
                f,
            )?
        } else {
            Point {
                x: p.grid(j, n),
                value: fm,
            }
        };
        if q.x > cur.x {
            piece(cur, q)?;
            note(q, &mut min, &mut max);
            cur = q;
        }
    }
    piece(cur, end)?;
    note(end, &mut min, &mut max);
    Ok((min, max, end))
}

/// Golden-section search for the maximum of `sign·f` on `[l, r]`, seeded with
/// a known point inside; returns the best evaluated point (never worse than
/// the seed). Stops at a width of 8ε relative or after 200 evaluations.
fn golden<T: Float>(
    mut l: T,
    mut r: T,
    sign: T,
    seed: Point<T>,
    f: &mut impl FnMut(T) -> Result<T, InverseError<T>>,
) -> Result<Point<T>, InverseError<T>> {
    let g = T::from_f64(0.618_033_988_749_894_9);
    let mut best = seed;
    let consider = |x: T, v: T, best: &mut Point<T>| {
        if sign * v > sign * best.value {
            *best = Point { x, value: v };
        }
    };
    let mut x1 = r - g * (r - l);
    let mut x2 = l + g * (r - l);
    let mut f1 = f(x1)?;
    let mut f2 = f(x2)?;
    consider(x1, f1, &mut best);
    consider(x2, f2, &mut best);
    for _ in 0..MAX_REFINE {
        if r - l <= T::from_f64(8.0) * T::EPSILON * (l.abs() + r.abs() + T::EPSILON) {
            break;
        }
        if sign * f1 < sign * f2 {
            l = x1;
            x1 = x2;
            f1 = f2;
            x2 = l + g * (r - l);
            f2 = f(x2)?;
            consider(x2, f2, &mut best);
        } else {
            r = x2;
            x2 = x1;
            f2 = f1;
            x1 = r - g * (r - l);
            f1 = f(x1)?;
            consider(x1, f1, &mut best);
        }
    }
    Ok(best)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn golden_finds_an_interior_maximum_and_never_loses_the_seed() {
        let mut f = |x: f64| Ok(-(x - 0.3) * (x - 0.3));
        let seed = Point {
            x: 0.25,
            value: -0.0025,
        };
        let p = golden(0.0, 1.0, 1.0, seed, &mut f).unwrap();
        // Near a smooth maximum the value is resolved to ε, the abscissa to √ε.
        assert!((p.x - 0.3).abs() < 1e-7 && p.value >= seed.value);
        // A cliff (infeasible beyond 0.6, value −MAX): the best feasible point is kept.
        let mut g = |x: f64| Ok(if x > 0.6 { -f64::MAX } else { x });
        let p = golden(0.0, 1.0, 1.0, Point { x: 0.5, value: 0.5 }, &mut g).unwrap();
        assert!(p.x <= 0.6 && p.x > 0.6 - 1e-12);
    }

    #[test]
    fn nearest_uses_the_circle_for_the_phase() {
        let mut o = TargetOutcome {
            solutions: Vec::new(),
            found: 2,
            min: Point { x: 0.0, value: 0.0 },
            max: Point { x: 0.0, value: 0.0 },
        };
        o.solutions.push(Point { x: 0.1, value: 0.0 }).unwrap();
        o.solutions.push(Point { x: 3.0, value: 0.0 }).unwrap();
        // 6.2 rad is 0.183 rad from 0.1 around the circle, 3.2 rad from 3.0.
        assert_eq!(o.nearest(Knob::Phase, 6.2).unwrap().x, 0.1);
        assert_eq!(o.nearest(Knob::Dux, 6.2).unwrap().x, 3.0);
    }
}

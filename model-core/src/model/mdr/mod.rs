//! Curved profiles through the method of dimensionality reduction (MDR).
//!
//! # Model
//!
//! A rigid axisymmetric indenter `f(r) = c·rⁿ` on an elastic half-space maps
//! to a 1D foundation of independent springs (Popov & Heß 2015) with the
//! profile `g(x) = κₙ c |x|ⁿ`, `κₙ = √π Γ(n/2 + 1)/Γ(n/2 + 1/2)`
//! ([`kappa`]: `κ₁ = π/2`, `κ₂ = 2`, so a sphere `f = r²/(2R)` gives
//! `g = x²/R`), normal and tangential stiffness per length `E*`, `G*`. Each
//! spring is the paper's single spring with its own mean indentation
//! `d₀ − g(x)` and the common `Δu_z`, `u_x` (eqs. 1, 2). The mean contact
//! radius is `a₀ = (d₀/(κₙ c))^{1/n}` ([`mean_contact_radius`]; Hertz
//! `a₀ = √(R d₀)`), and with `ξ = |x|/a₀` (κₙ and c are absorbed here):
//!
//! ```text
//! d(ξ) = 1 − ξⁿ                          band offset, units of d₀          (M1)
//! w(ξ, θ) = d(ξ) − a cos θ              the spring's friction band        (M2)
//! ```
//!
//! in the dimensionless variables of [`crate::model::scene`] with `u_z0`
//! read as the mean indentation `d₀` and `k_z/k_x` as `E*/G*`
//! (`W₀ = μ₀ (E*/G*) d₀`, `a = Δu_z/d₀`, `b = Δu_x/W₀`, `V = v₀/(ωW₀)`); the
//! same dimensionless groups as the flat punch hold. A spring
//!
//! * with `d > a` touches all the time: it is *exactly* the flat punch
//!   scaled by `d` — `s/d` lives in the band `1 − (a/d) cos θ` with the drive
//!   `(V/d)θ + (b/d) cos(θ + φ)`, so `⟨s⟩ = d · μ_flat(a/d, b/d, V/d)` (M3),
//!   solved by [`crate::model::exact`] (μ(0⁺) at `V = 0`);
//! * with `|d| ≤ a` touches while `w > 0`, i.e. in the window
//!   `θ ∈ [θ_c, 2π − θ_c]`, `cos θ_c = d/a` — shorter than π for `d < 0` —
//!   and its state resets at every landing: the lift-off walk of
//!   [`crate::model::liftoff`] with band offset `d` (one implementation);
//! * with `d ≤ −a` never touches.
//!
//! The friction coefficient is the ratio of the mean forces,
//!
//! ```text
//! μ/μ₀ = ∫₀^{ξ_max} ⟨s⟩ dξ / ∫₀^{ξ_max} ⟨w⁺⟩ dξ,   ξ_max = (1 + a)^{1/n}       (M8)
//! ```
//!
//! with the denominator `D` of [`normal`] (closed form for the cone and for
//! the sphere at `a ≤ 1`, eqs. M6, M7; integrated with the numerator otherwise).
//!
//! # Critical velocities ([`critical_velocities`])
//!
//! `μ/μ₀ = 1` iff every spring slides forward through all its contact. For
//! `d > a` that is `V ≥ c` (eq. 8, independent of `d` after scaling); for
//! `|d| ≤ a` it is `V ≥ V_c⁺(d)`, eq. L5 on the window of `d`. The windows
//! are nested (they shrink as `d` falls), so `V_c⁺(d)` is nondecreasing in
//! `d` and the central spring (`d = 1`) decides: **the critical velocities
//! of every profile equal the flat punch's** (eq. 8 for `a < 1`, eq. L5 for
//! `a ≥ 1`). Below them the outer springs already slide: `ξ*` with
//! `V_c⁺(d(ξ*)) = V` (bisection on the closed-form L5) splits the quadrature.
//!
//! # At rest
//!
//! With `a < 1` the central springs (`ξ < (1 − a)^{1/n}`) never lift off and
//! have no unique state at `V = 0`: [`limits_at_zero`] gives μ(0⁺) and μ(0⁻)
//! (each permanent spring at its own one-sided limit, the intermittent ones
//! unique), and [`mu_over_mu0`] refuses `V = 0` with [`MdrError::AtRest`].
//! With `a ≥ 1` every spring lifts off and μ(0) is unique.
//! Mirror symmetry `μ(V, φ) = −μ(−V, φ + π)` holds spring by spring;
//! `V < 0` is computed through it.
//!
//! # Quadrature and its error bound
//!
//! `μ/μ₀ = 1 − I/D` with `I = ∫ (⟨w⁺⟩ − ⟨s⟩) dξ`, which vanishes beyond
//! `ξ*`. The ξ-range is split at `ξ_a = (1 − a)^{1/n}` (lift-off onset,
//! `a < 1`), at `ξ*` and at `ξ_max`; on each piece `ξ = l + (r − l)(1 − cos t)/2`,
//! `t ∈ [0, π]`, which turns the square-root behaviour at the onset and at the
//! rim (`θ_c ∝ √(a − d)`, `⟨w⁺⟩ ∝ (a + d)^{3/2}`) into smooth functions of `t`.
//! [`quadrature`] (adaptive, nested Gauss–Kronrod–Patterson 10/21/43: each
//! piece starts with `K₂₁`, the worst is raised to `P₄₃`, then bisected)
//! refines until
//!
//! ```text
//! bound = [4·E_quad + ε_s ξ* + U]/D + 64 ε  ≤ tol
//! ```
//!
//! where `E_quad` is the sum of the per-interval estimates (`|K₂₁ − G₁₀|`,
//! or `|P₄₃ − K₂₁|` where that is at most a tenth of it; of `I`, and of `D`
//! times `I/D` when `D` is not closed form) with a safety factor 4
//! ([`SAFETY`]; 2 was enough for the 7/15 pair used before, whose estimate
//! is more pessimistic: with 2 the estimate check below reached 0.99 of the
//! bounds), `ε_s = (SPRING_PRECISION + M::MAX_REL_ERROR)(1 + a + b)` the per-spring
//! solver error in absolute units of `W₀` ([`SPRING_PRECISION`] = 10⁻¹¹ in
//! f64, checked spring by spring against a brute force at 2²¹ steps per
//! period, at `V > 0` and at rest; f32 keeps the flat solvers' generic
//! constant, [`precision_constant`](crate::model::exact::precision_constant)), and `U`
//! the band of springs a solver could not resolve (counted as `|⟨s⟩| ≤ ⟨w⁺⟩`:
//! slivers of contact at the rim below `64ε(1 + a + b)`, thin rim windows
//! with `⟨w⁺⟩ ≤ √ε(1 + a + b)` whose event walk fails its check, and
//! permanent springs whose scaled drive `b/d > 10⁷` the exact solver refuses).
//! `E_quad` is an **estimate**, not a proof (see [`quadrature`]).
//!
//! **Kinks.** Inside the pieces `⟨s⟩(ξ)` has kinks — slope jumps where the
//! springs' arc structure changes (e.g. a backward slip that appears with a
//! finite length when a stick trajectory first reaches the lower band near the
//! end of a backward-slip piece). They are found, not bounded: the arc
//! sequence of a spring (stick / forward / backward, arcs shorter than
//! 10⁻⁶ rad ignored — at `V = 0` rounding makes and unmakes such slivers —
//! the permanent spring's period taken as a cycle) is sampled at 8 interior
//! points of each segment, plus one at `10⁻⁴π` in `t` from the lift-off
//! onset `ξ_a` on each side (the permanent springs change their arc
//! structure in a layer `d − a ≈ 10⁻⁴` in some scenes, which otherwise cost
//! the adaptive bisection several rounds; without the sample on the
//! intermittent side the estimate check below fails at μ(0±) of one sphere
//! scene — an arc change there was missed), every change between neighbours is located to
//! `10⁻⁵π` in `t` — by a closed-form candidate where one lies in the bracket
//! and the signatures either side of it match the bracket's ends (two
//! solves, a few more where a sliver arc hides on one side; the candidates
//! of `kink_candidates`: piece boundaries of `h±` crossing the window's
//! edges, landing slips `a sin θ_c = |V − b sin(θ_c + φ)|`, the last stick
//! of a window reaching the lift-off pinch, and a stick grazing the other
//! band — 131 of 132 changes over 60 random drives have one, test
//! `kink_candidates_cover_the_arc_structure_changes`),
//! else by bisection (~14 solves) —, and the segment is cut there into pieces, each with its own
//! `1 − cos t` map (a slip that sets in tangentially makes `⟨s⟩` behave like
//! `(ξ − ξ_k)^{3/2}` past the kink, smooth in that piece's `t`). Two
//! changes that cancel between samples, and changes the sequence does not
//! show, are left to the adaptive bisection and to the estimate (checked
//! below, "Cost"); against the brute force over springs all gaps are within
//! the brute force's own error, itself at most 4× the MDR's bound
//! (`tests/mdr.rs`, `integration_tests::springs`).
//!
//! **Cost.** Each spring is one solve (~0.45 µs: the touch events by
//! Halley's method, the drive's walk geometry — `liftoff::Shape` — shared
//! by all springs of one μ). Averaged over 1000 velocities across ±v_c for
//! three drives (`cargo run --release -p model-core --example
//! mdr_cpu_sweep`, idle machine), a sphere's μ took
//! 103/104/60 spring solves and 37/44/16 µs of CPU at `tol = 10⁻⁶`,
//! 142/125/91 and 50/48/28 µs at `10⁻⁸`, 170/150/103 and 58/60/28 µs at
//! `10⁻⁹` (a = 0.5, b = 0.25, φ = 1; a = 0.5, b = 1, φ = 0.3; a = 1.5,
//! b = 0.7, φ = 2); with bisected kinks and a solve per spring that
//! computed its own geometry it was 173/156/104 solves at `10⁻⁹` and
//! 92–99 µs at the fixed scenes of `examples/mdr_cpu.rs` (now 67–72 µs,
//! README "Cost of one μ"); with the 7/15 rules 172/184/143
//! solves. A tolerance below the per-spring solvers' part ([`solver_bound`],
//! ~10⁻¹⁰ for a sphere in f64, the same for μ(0±)) is refused with
//! [`MdrError::ToleranceTooTight`]. The quadrature's bound stays an
//! estimate: over 80 random scenes and four profiles the answers at
//! `tol = 10⁻⁶` and `10⁻⁹` (at V) and at `10⁻⁶` (the limits μ(0±)) differ
//! from those at the tightest tolerance (≈ 10⁻¹⁰) by at most 0.60 of
//! the two bounds, 0 of 320 comparisons outside them (`tests/mdr.rs`,
//! `bound_estimate_holds_against_a_tighter_run`). On dense curves it fails
//! at isolated velocities: of 20 001 velocities across ±v_c (sphere and
//! cone, with and without lift-off), 21–70 give answers at `10⁻⁹` and at
//! `2·10⁻¹⁰` farther apart than their two bounds, by up to 230×. Where the
//! brute force over springs was run (51 such velocities), it agreed with
//! the smooth curve through the neighbouring velocities, not with the
//! quadrature there (docs/guide/speed.md; presumably a change of the arc
//! structure that the kink search misses at those velocities — not yet
//! found or fixed).

mod bed;
mod bound;
mod error;
mod kinks;
mod law;
pub mod normal;
pub mod powers;
pub mod profile;
pub mod quadrature;
pub(crate) mod spring;

pub use bound::{solver_bound, solver_bound_at_rest, SAFETY, SPRING_PRECISION};
pub use error::{MdrError, MdrResult};
pub(crate) use law::check_moving;
pub use law::{
    critical_velocities, limits_at_zero, mean_normal_force, mu_over_mu0, spring_means,
    spring_means_at_rest, static_interval_exists,
};
pub use profile::{kappa, mean_contact_radius, Profile};

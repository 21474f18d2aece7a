//! Inverse design (`model::inverse`): tune round trips checked by an
//! independent computation, refusals checked against a dense brute-force scan,
//! maximisation no worse than a dense scan.
//!
//! The independent reference for μ is the paper's fixed-step scheme
//! (`integration_tests::fixed_warm`) at N = 65 536 steps per period with its
//! stated bound `(1 + b)(K_D/N² + N·ε)` ≈ 2.3e-9·(1 + b), whose constants are
//! measured without the exact solver. The tune claims
//! `|μ_exact(x*) − μ*| ≤ |residual|`, and the exact solver's own bound covers
//! `|μ_exact − μ|`; so every round trip must satisfy
//! `|μ_fixed(x*) − μ*| ≤ fixed bound + exact bound + |residual|`, with the
//! residual itself asserted ≤ the exact bound.

use integration_tests::{fixed_warm, Rng};
use model_core::exact;
use model_core::model::inverse::{
    maximize, solve_target, InverseError, Knob, Objective, Problem, MAX_SOLUTIONS,
};
use model_core::{Groups, Libm};

/// Steps per period of the reference runs.
const N_REF: u32 = 65_536;
/// Scan points of the searches (256 cells, as `fricctl tune`).
const SCAN: usize = 257;
/// Points of the brute-force scans (16× finer than the search's scan).
const DENSE: usize = 4097;

fn knob_of(i: u32) -> Knob {
    [Knob::Duz, Knob::Dux, Knob::Phase][(i % 3) as usize]
}

fn random_problem(rng: &mut Rng, knob: Knob) -> Problem<f64> {
    let g = Groups {
        duz_rel: rng.range(0.0, 0.9),
        dux_rel: rng.range(0.0, 2.0),
        phi: rng.range(0.0, std::f64::consts::TAU),
    };
    let hi = match knob {
        Knob::Duz => rng.range(0.3, 0.95),
        Knob::Dux => rng.range(0.3, 3.0),
        Knob::Phase => 0.0,
    };
    Problem::new::<Libm>(g, knob, 0.0, hi).expect("valid problem")
}

/// The knob value of dense point `i` (the phase over one turn).
fn dense_x(p: &Problem<f64>, i: usize) -> f64 {
    let (lo, hi) = p.range();
    lo + (hi - lo) * i as f64 / (DENSE - 1) as f64
}

/// `(min, max)` of `f` over the dense grid.
fn dense_range(p: &Problem<f64>, f: impl Fn(f64) -> f64) -> (f64, f64) {
    (0..DENSE)
        .map(|i| f(dense_x(p, i)))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), y| {
            (lo.min(y), hi.max(y))
        })
}

/// The largest secant slope of `f` between neighbouring dense points, times
/// half the spacing: with a slope at most this secant bound inside each
/// cell, an extremum between two dense points lies at most this far beyond
/// the dense range (the Lipschitz bound of the scan).
fn dense_overshoot(p: &Problem<f64>, f: impl Fn(f64) -> f64) -> f64 {
    let ys: Vec<f64> = (0..DENSE).map(|i| f(dense_x(p, i))).collect();
    let h = dense_x(p, 1) - dense_x(p, 0);
    let slope = ys
        .windows(2)
        .map(|w| (w[1] - w[0]).abs() / h)
        .fold(0.0, f64::max);
    slope * h / 2.0
}

/// Asserts the round trip of one solution against the fixed-step reference.
fn check_round_trip(p: &Problem<f64>, v: f64, target: f64, x: f64, value: f64) {
    let d = p.drive_at::<Libm>(x);
    let exact_bound = exact::error_bound::<f64, Libm>(&d);
    let residual = value - target;
    assert!(
        residual.abs() <= exact_bound,
        "residual {residual:e} > bound {exact_bound:e} at x = {x}"
    );
    let (mu_ref, ref_bound) = fixed_warm(&d, v, N_REF);
    let err = (mu_ref - target).abs();
    assert!(
        err <= ref_bound + exact_bound + residual.abs(),
        "{p:?} v = {v} x = {x}: fixed-step {mu_ref} vs target {target}: {err:e} > {:e}",
        ref_bound + exact_bound + residual.abs()
    );
}

/// Targets attained by construction (μ at a random drive in the range): the
/// tune must find solutions, each of which round-trips. Refusals would be a
/// failure of the search (the target is reachable): counted, and allowed
/// only for features narrower than a scan cell — measured 0.
#[test]
fn tune_round_trips_on_random_scenes() {
    let mut rng = Rng::new(0x7e57_1e55);
    let (mut cases, mut refused, mut solutions) = (0u32, 0u32, 0u32);
    let mut scan = [0.0; SCAN];
    for i in 0..240 {
        let knob = knob_of(i);
        let p = random_problem(&mut rng, knob);
        let v = rng.range(0.01, 0.8);
        let (lo, hi) = p.range();
        let x_true = rng.range(lo, hi);
        let target = p.mu_at::<Libm>(x_true, v).unwrap();
        if target.abs() >= 1.0 {
            continue; // continuous sliding: refused by design (BadTarget)
        }
        cases += 1;
        match solve_target::<f64, Libm>(&p, v, target, &mut scan) {
            Ok(r) => {
                assert!(r.found as usize >= r.solutions.len());
                for s in &r.solutions {
                    check_round_trip(&p, v, target, s.x, s.value);
                    assert!(s.x >= lo && s.x <= hi, "solution outside the range");
                    solutions += 1;
                }
                // The true drive is reached: some solution has its μ (the law may be
                // many-to-one, so x_true itself need not be listed).
                assert!(r.min.value <= target && target <= r.max.value);
            }
            Err(InverseError::OutOfReach { .. }) => refused += 1,
            Err(e) => panic!("{p:?} v = {v}: {e}"),
        }
    }
    eprintln!("round trips: {cases} targets, {solutions} solutions checked, {refused} refused");
    assert!(cases >= 120, "too few stick-slip cases: {cases}");
    assert_eq!(refused, 0, "reachable targets refused");
}

/// Random targets in (−1, 1): refused ones must be out of reach for a dense
/// brute-force scan of the exact law too, and the reported range must contain
/// the dense range (to the solver's bound: the reported ends are attained
/// values, refined, so a dense scan cannot beat them by more than a feature
/// narrower than a cell — counted, measured 0). Accepted ones round-trip.
#[test]
fn out_of_reach_targets_are_refused_with_the_right_range() {
    let mut rng = Rng::new(0x0bad_7a59);
    let (mut refused, mut accepted, mut wider) = (0u32, 0u32, 0u32);
    let mut scan = [0.0; SCAN];
    for i in 0..90 {
        let p = random_problem(&mut rng, knob_of(i));
        let v = rng.range(0.02, 1.0);
        let target = rng.range(-0.95, 0.95);
        let mu = |x: f64| p.mu_at::<Libm>(x, v).unwrap();
        let (dmin, dmax) = dense_range(&p, mu);
        // Solver bound at the largest b of the range (the bound grows with b only).
        let bound = exact::error_bound::<f64, Libm>(&p.drive_at::<Libm>(p.range().1));
        match solve_target::<f64, Libm>(&p, v, target, &mut scan) {
            Err(InverseError::OutOfReach { min, max }) => {
                refused += 1;
                assert!(
                    target < dmin - bound || target > dmax + bound,
                    "refused {target} but the dense scan reaches {dmin}..{dmax}"
                );
                // The ends are attained values: inside the dense range's hull,
                // widened by the scan's Lipschitz bound (an extremum between
                // two dense points) and the solver's bound…
                let over = dense_overshoot(&p, mu) + bound;
                assert!(
                    min >= dmin - over && max <= dmax + over,
                    "reported {min}..{max}, dense {dmin}..{dmax} ± {over:e}"
                );
                // …and at least as wide as the dense range (to the bound).
                if min > dmin + bound || max < dmax - bound {
                    wider += 1;
                }
            }
            Ok(r) => {
                accepted += 1;
                for s in r.solutions.iter().take(MAX_SOLUTIONS) {
                    check_round_trip(&p, v, target, s.x, s.value);
                }
                if r.min.value > dmin + bound || r.max.value < dmax - bound {
                    wider += 1;
                }
            }
            Err(e) => panic!("{p:?}: {e}"),
        }
    }
    eprintln!("random targets: {accepted} accepted, {refused} refused, {wider} dense ranges wider than reported");
    assert!(
        refused >= 10 && accepted >= 10,
        "{refused} refused / {accepted} accepted: not both exercised"
    );
    assert_eq!(
        wider, 0,
        "a dense scan found values outside the reported range"
    );
}

/// The reachable range's ends are values attained at the reported drives:
/// the fixed-step reference there agrees within both bounds.
#[test]
fn range_ends_are_attained() {
    let mut rng = Rng::new(0xe7d5);
    let mut scan = [0.0; SCAN];
    let mut checked = 0u32;
    for i in 0..30 {
        let p = random_problem(&mut rng, knob_of(i));
        let v = rng.range(0.02, 1.0);
        let (lo, hi) = p.range();
        let target = p.mu_at::<Libm>(rng.range(lo, hi), v).unwrap();
        if target.abs() >= 1.0 {
            continue;
        }
        let r = solve_target::<f64, Libm>(&p, v, target, &mut scan).unwrap();
        for end in [r.min, r.max] {
            let d = p.drive_at::<Libm>(end.x);
            let (m_ref, rb) = fixed_warm(&d, v, N_REF);
            let b = exact::error_bound::<f64, Libm>(&d);
            assert!(
                (m_ref - end.value).abs() <= rb + b,
                "{p:?} x = {}: {m_ref} vs {}",
                end.x,
                end.value
            );
            checked += 1;
        }
    }
    assert!(checked >= 40, "{checked}");
}

/// Maximisation is no worse than a dense brute-force scan (16× finer),
/// within the objective's bound (two exact-solver bounds for the asymmetry,
/// one for the stall force); cases where the dense scan wins are counted —
/// measured 0.
#[test]
fn maximize_is_no_worse_than_a_dense_scan() {
    let mut rng = Rng::new(0x03a7_1117);
    let mut scan = [0.0; SCAN];
    let (mut checked, mut beaten, mut infeasible) = (0u32, 0u32, 0u32);
    for i in 0..36 {
        let p = random_problem(&mut rng, knob_of(i));
        let objective = if i % 2 == 0 {
            Objective::Asymmetry
        } else {
            Objective::StallForce
        };
        let obj = |x: f64| {
            p.objective_at::<Libm>(objective, x)
                .unwrap()
                .unwrap_or(f64::NEG_INFINITY)
        };
        let (_, dense_best) = dense_range(&p, obj);
        // The bound grows with b only: take it at the range's upper end.
        let bound = 2.0 * exact::error_bound::<f64, Libm>(&p.drive_at::<Libm>(p.range().1));
        match maximize::<f64, Libm>(&p, objective, &mut scan) {
            Ok(best) => {
                checked += 1;
                // The reported point is feasible and its value is what the objective
                // gives there (to rounding: the phase is reported wrapped into [0, 2π)).
                let again = p.objective_at::<Libm>(objective, best.x).unwrap();
                assert!(again.is_some_and(|y| (y - best.value).abs() <= bound));
                if best.value < dense_best - bound {
                    beaten += 1;
                    eprintln!("{p:?} {objective:?}: {} < dense {dense_best}", best.value);
                }
            }
            Err(InverseError::Infeasible) => {
                infeasible += 1;
                assert_eq!(
                    dense_best,
                    f64::NEG_INFINITY,
                    "dense scan found a feasible drive"
                );
            }
            Err(e) => panic!("{e}"),
        }
    }
    eprintln!(
        "maximise: {checked} checked, {beaten} beaten by the dense scan, {infeasible} infeasible"
    );
    assert!(checked >= 24);
    assert_eq!(beaten, 0);
}

/// The stall-force maximum against its independent meaning: at the optimum,
/// −μ(0⁺) is the forward push of a slowly moving contact. The fixed-step
/// reference (warm start, N = 65 536) at V, 2V and 4V with V = 10⁻⁶ gives
/// μ(0⁺) by the two-point extrapolation `E₁ = 2μ(V) − μ(2V) = μ(0⁺) − 2CV² + …`
/// (μ is smooth in V on (0, c)); with `E₂ = 2μ(2V) − μ(4V) = μ(0⁺) − 8CV² + …`
/// its remainder is `(E₁ − E₂)/3`. Tolerance: that estimate, plus each run's
/// stated bound times its weight in `E₁` (2 + 1) and in `(E₁ − E₂)/3`
/// ((2 + 3 + 1)/3), plus the maximum's own bound.
///
/// And the closed form (static friction, README): with a static equilibrium,
/// μ(0⁺) = 1 − c, c = |a + b e^{iφ}|, which decreases in b while the static
/// interval [c' − 1, 1 − c] is non-empty, `c + c' ≤ 2`; at its end the
/// interval is the point μ(0⁺) = μ(0⁻) and `c − c' = (c² − c'²)/2 = 2ab cos φ`,
/// so `c = 1 + ab cos φ` and the stall force is `ab* cos φ` at
/// `b* = √((1 − a²)/(1 − a² cos² φ))`. The maximum over Δu_x is there.
#[test]
fn stall_force_optimum_pushes_at_low_speed() {
    let (a, phi) = (0.4f64, 50f64.to_radians());
    let g = Groups {
        duz_rel: a,
        dux_rel: 0.35,
        phi,
    };
    let p = Problem::new::<Libm>(g, Knob::Dux, 0.0, 10.0).unwrap();
    let mut scan = [0.0; SCAN];
    let best = maximize::<f64, Libm>(&p, Objective::StallForce, &mut scan).unwrap();
    let d = p.drive_at::<Libm>(best.x);
    let own = exact::error_bound::<f64, Libm>(&d);
    // The closed form.
    let b_star = ((1.0 - a * a) / (1.0 - (a * phi.cos()).powi(2))).sqrt();
    let f_star = a * b_star * phi.cos();
    // The value at the kink: left of b* its slope is dc/db = (b + a cos φ)/c
    // ≤ 1, so the golden section's bracket (8ε relative) costs ≤ 16ε(1 + b*).
    let tol = own + 16.0 * f64::EPSILON * (1.0 + b_star);
    assert!(
        (best.value - f_star).abs() <= tol,
        "stall force {} vs closed form {f_star} (tol {tol:e})",
        best.value
    );
    // Left of b* the value falls at slope (b + a cos φ)/c ≥ 0.9 here: the
    // value's tolerance bounds how far left the optimum can sit.
    let c_star = 1.0 + a * b_star * phi.cos();
    let slope_left = (b_star + a * phi.cos()) / c_star;
    assert!(
        best.x >= b_star - 2.0 * tol / slope_left,
        "optimum at b = {} left of b* = {b_star}",
        best.x
    );
    let v = 1e-6;
    let (m1, r1) = fixed_warm(&d, v, N_REF);
    let (m2, r2) = fixed_warm(&d, 2.0 * v, N_REF);
    let (m4, r4) = fixed_warm(&d, 4.0 * v, N_REF);
    let extrapolated = 2.0 * m1 - m2;
    let remainder = (extrapolated - (2.0 * m2 - m4)).abs() / 3.0;
    let allowed = remainder + (2.0 * r1 + r2) + (2.0 * r1 + 3.0 * r2 + r4) / 3.0 + own;
    println!(
        "stall force {} (closed form {f_star}), −(2μ(V) − μ(2V)) = {} (allowed {allowed:.1e}; μ(V) − μ(0⁺) = {:.2e})",
        best.value,
        -extrapolated,
        m1 + best.value
    );
    assert!(
        (-extrapolated - best.value).abs() <= allowed,
        "{extrapolated} vs {}",
        best.value
    );
}

/// The asymmetry's maximum over the phase, closed form: at φ ∈ {0, π},
/// μ(0±) = ±(1 − |a − b|) and ∓(1 − (a + b)) (the static interval
/// `[c' − 1, 1 − c]` with c, c' = a + b and |a − b|), so
/// |μ(0⁺) + μ(0⁻)| = 2·min(a, b); by the triangle inequality
/// |c − c'| ≤ 2·min(a, b) at every φ, so that is the maximum when the
/// sampled |μ(v) + μ(−v)| do not exceed it (they do not: the test would
/// fail). Random `a`, `b` with `a + b < 1` (a static equilibrium at every φ).
/// Tolerances: the value, two exact bounds (|μ(0⁺) + μ(0⁻)|); the phase,
/// from the curvature at the maximum, asym ≈ 2min(a, b) − κφ²/2 with
/// κ = ab/|a − b| + ab/(a + b): |φ − φ*| ≤ √(2·tol/κ).
#[test]
fn asymmetry_optimum_over_the_phase_is_two_min_a_b() {
    let mut rng = Rng::new(0xa5e7_0001);
    let mut scan = [0.0; SCAN];
    let mut at_pi = 0;
    for _ in 0..24 {
        let a = rng.range(0.05, 0.9);
        let b = rng.range(0.05, 0.95 - a);
        let g = Groups {
            duz_rel: a,
            dux_rel: b,
            phi: rng.range(0.0, std::f64::consts::TAU),
        };
        let p = Problem::new::<Libm>(g, Knob::Phase, 0.0, 0.0).unwrap();
        let best = maximize::<f64, Libm>(&p, Objective::Asymmetry, &mut scan).unwrap();
        let want = 2.0 * a.min(b);
        let tol = 2.0 * exact::error_bound::<f64, Libm>(&p.drive_at::<Libm>(best.x));
        assert!(
            (best.value - want).abs() <= tol,
            "a={a} b={b}: asymmetry {} vs 2·min(a, b) = {want}",
            best.value
        );
        let kappa = a * b / (a - b).abs() + a * b / (a + b);
        let dphi = (2.0 * tol / kappa).sqrt();
        let from_zero = best.x.min(std::f64::consts::TAU - best.x);
        let from_pi = (best.x - std::f64::consts::PI).abs();
        assert!(
            from_zero.min(from_pi) <= dphi,
            "a={a} b={b}: optimum at φ = {} (allowed {dphi:e} from 0 or π)",
            best.x
        );
        at_pi += usize::from(from_pi < from_zero);
    }
    println!("asymmetry optimum at φ = π in {at_pi} of 24 scenes (0 in the others)");
}

/// Bad inputs are typed errors, never panics.
#[test]
fn bad_inputs_are_refused() {
    let g = Groups {
        duz_rel: 0.4,
        dux_rel: 0.35,
        phi: 0.3,
    };
    assert_eq!(
        Problem::new::<Libm>(g, Knob::Duz, 0.0, 1.0),
        Err(InverseError::BadRange)
    );
    assert_eq!(
        Problem::new::<Libm>(g, Knob::Dux, 0.5, 0.5),
        Err(InverseError::BadRange)
    );
    assert_eq!(
        Problem::new::<Libm>(g, Knob::Dux, 0.0, f64::NAN),
        Err(InverseError::BadRange)
    );
    let p = Problem::new::<Libm>(g, Knob::Duz, 0.0, 0.9).unwrap();
    let mut scan = [0.0; SCAN];
    assert_eq!(
        solve_target::<f64, Libm>(&p, 0.0, 0.3, &mut scan),
        Err(InverseError::BadVelocity)
    );
    assert_eq!(
        solve_target::<f64, Libm>(&p, 0.1, 1.0, &mut scan),
        Err(InverseError::BadTarget)
    );
    assert_eq!(
        solve_target::<f64, Libm>(&p, 0.1, 0.3, &mut scan[..2]),
        Err(InverseError::BadScan)
    );
    // MIN_SCAN_POINTS (3) is the least accepted, as documented: a scan of
    // exactly that many runs (whatever it finds), one fewer is refused.
    assert_eq!(model_core::model::inverse::MIN_SCAN_POINTS, 3);
    assert!(!matches!(
        solve_target::<f64, Libm>(&p, 0.1, 0.3, &mut scan[..3]),
        Err(InverseError::BadScan)
    ));
}

/// The f32 build (the firmware's feedforward): targets attained in f64 at a
/// random drive are solved in f32, and each f32 solution, evaluated by the
/// f64 exact solver, gives the target within the f32 solver's bound
/// (`exact::error_bound::<f32>`, 1e-6·(1 + b)) plus the f32 residual plus the
/// f64 bound. A refusal is legitimate only for a target within its derived
/// distance of a range end (the f32 law differs from the f64 one by the
/// groups' rounding and the two bounds): each refusal is checked so.
#[test]
fn f32_solutions_hold_in_f64() {
    let mut rng = Rng::new(0xf32f_0032);
    let mut scan = [0.0f32; 65];
    let (mut cases, mut refused) = (0u32, 0u32);
    for i in 0..60 {
        let p64 = random_problem(&mut rng, knob_of(i));
        let g = p64.groups_at(0.0);
        let g32 = Groups {
            duz_rel: g.duz_rel as f32,
            dux_rel: g.dux_rel as f32,
            phi: g.phi as f32,
        };
        let (lo, hi) = p64.range();
        let p32 = Problem::new::<Libm>(g32, p64.knob(), lo as f32, hi as f32).unwrap();
        let v = rng.range(0.02, 0.8);
        let x_true = rng.range(lo, hi);
        let target = p64.mu_at::<Libm>(x_true, v).unwrap();
        if target.abs() >= 0.999 {
            continue;
        }
        cases += 1;
        match solve_target::<f32, Libm>(&p32, v as f32, target as f32, &mut scan) {
            Ok(r) => {
                for s in &r.solutions {
                    // The f64 problem with the f32 groups, at the f32 solution.
                    let q = Problem::new::<Libm>(
                        Groups {
                            duz_rel: g32.duz_rel as f64,
                            dux_rel: g32.dux_rel as f64,
                            phi: g32.phi as f64,
                        },
                        p64.knob(),
                        lo,
                        hi,
                    )
                    .unwrap();
                    let x = s.x as f64;
                    let mu64 = q.mu_at::<Libm>(x, v as f32 as f64).unwrap();
                    let b32 = exact::error_bound::<f32, Libm>(&p32.drive_at::<Libm>(s.x)) as f64;
                    let b64 = q.bound_at::<Libm>(x);
                    let res = (s.value as f64 - target as f32 as f64).abs();
                    assert!(
                        (mu64 - target as f32 as f64).abs() <= b32 + b64 + res,
                        "{p32:?} x = {x}: {mu64} vs {target}"
                    );
                }
            }
            Err(InverseError::OutOfReach { min, max }) => {
                // The target is attained in f64 at x_true. The f32 law at the
                // f32 knob value x₃₂ = x_true as f32 lies in the reported
                // range (the ends are the range's attained extremes), and
                // differs from the target by at most: the f64 law's change
                // from the f64 problem to the f32 groups at x₃₂ (computed here,
                // in f64), the f32 and f64 solvers' bounds there, and the
                // rounding of the target to f32. So a refused target lies
                // within that of a range end.
                refused += 1;
                let q = Problem::new::<Libm>(
                    Groups {
                        duz_rel: g32.duz_rel as f64,
                        dux_rel: g32.dux_rel as f64,
                        phi: g32.phi as f64,
                    },
                    p64.knob(),
                    lo,
                    hi,
                )
                .unwrap();
                let x32 = x_true as f32;
                let moved = (q
                    .mu_at::<Libm>(f64::from(x32), f64::from(v as f32))
                    .unwrap()
                    - target)
                    .abs();
                let b32 = f64::from(exact::error_bound::<f32, Libm>(&p32.drive_at::<Libm>(x32)));
                let b64 = q.bound_at::<Libm>(f64::from(x32));
                let allowed = moved + b32 + b64 + target.abs() * f64::from(f32::EPSILON) / 2.0;
                let t = target as f32 as f64;
                let dist = if t < min as f64 {
                    min as f64 - t
                } else {
                    t - max as f64
                };
                assert!(
                    dist <= allowed,
                    "f32 refused {t}, {dist:e} beyond its range {min}..{max} (allowed {allowed:e})"
                );
            }
            Err(e) => panic!("{e}"),
        }
    }
    eprintln!(
        "f32: {cases} targets, {refused} refused (each within its derived distance of a range end)"
    );
    assert!(cases >= 40);
}

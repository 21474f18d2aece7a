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
                // The ends are attained values: inside the dense range's hull…
                assert!(min >= dmin - 1e-3 && max <= dmax + 1e-3);
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
/// −μ(0⁺) is the forward push of a slowly moving contact, so the fixed-step
/// reference at a small velocity V = 1e-4 gives −μ within its bound plus the
/// slope term (μ is Lipschitz in V with constant ≤ 10 per unit V,
/// tests/stability.rs, so |μ(V) − μ(0⁺)| ≤ 1e-3).
#[test]
fn stall_force_optimum_pushes_at_low_speed() {
    let g = Groups {
        duz_rel: 0.4,
        dux_rel: 0.35,
        phi: 50f64.to_radians(),
    };
    let p = Problem::new::<Libm>(g, Knob::Dux, 0.0, 10.0).unwrap();
    let mut scan = [0.0; SCAN];
    let best = maximize::<f64, Libm>(&p, Objective::StallForce, &mut scan).unwrap();
    assert!(best.value > 0.0);
    let (mu_ref, rb) = fixed_warm(&p.drive_at::<Libm>(best.x), 1e-4, 16_384);
    assert!(
        (-mu_ref - best.value).abs() <= rb + 1e-3,
        "{mu_ref} vs {}",
        best.value
    );
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
}

/// The f32 build (the firmware's feedforward): targets attained in f64 at a
/// random drive are solved in f32, and each f32 solution, evaluated by the
/// f64 exact solver, gives the target within the f32 solver's bound
/// (`exact::error_bound::<f32>`, 1e-6·(1 + b)) plus the f32 residual plus the
/// f64 bound. Refusals can only come from targets within the f32 bound of a
/// range end (the f32 law differs from f64 by that bound): counted, at most
/// 2 of 60 allowed, measured below.
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
        let target = p64.mu_at::<Libm>(rng.range(lo, hi), v).unwrap();
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
                refused += 1;
                let b32 = exact::error_bound::<f32, Libm>(&p32.drive_at::<Libm>(hi as f32)) as f64;
                let t = target;
                assert!(
                    (t - min as f64).abs() <= 2.0 * b32 || (t - max as f64).abs() <= 2.0 * b32,
                    "f32 refused {t} far from its range ends {min}..{max}"
                );
            }
            Err(e) => panic!("{e}"),
        }
    }
    eprintln!("f32: {cases} targets, {refused} refused");
    assert!(cases >= 40);
    assert!(refused <= 2);
}

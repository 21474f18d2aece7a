//! `select::mu_within`: the cheapest method whose stated bound meets the
//! tolerance, over random scenes and tolerances: the bound never exceeds the
//! tolerance, the value is within its bound of an independent computation,
//! and the choice follows the documented order. References never call the
//! function `mu_within` answers with: eq. 8 by hand for the sliding shortcut,
//! the exact solver for the approximations, the paper's fixed-step scheme
//! (with its own stated bound) for the exact solver, and a brute-force phase
//! grid or a fixed-step bracket for the limits at rest.

use integration_tests::{critical_velocities, fixed_bounded, scene, static_interval_grid, Rng};
use model_core::analytic::approx::MAX_ERROR_OVER_A;
use model_core::analytic::{ApproxKind, CriticalVelocity};
use model_core::exact;
use model_core::select::{mu_within, Method, SelectError, Value};
use model_core::Libm;

#[test]
fn choice_bound_and_value_over_random_scenes() {
    let mut rng = Rng::new(2026);
    let mut seen = [0usize; 5];
    let mut worst_exact = 0.0f64;
    for i in 0..4000 {
        // A third single-mode normal, a third single-mode tangential, a third dual.
        let (a, b) = match i % 3 {
            0 => (rng.range(0.0, 0.99), 0.0),
            1 => (0.0, rng.range(0.0, 2.0)),
            _ => (rng.range(0.01, 0.99), rng.range(0.01, 3.0)),
        };
        let s = scene(a, b, rng.range(-4.0, 4.0));
        let vc = CriticalVelocity::of(&s);
        let x = rng.range(-1.5, 1.5);
        let v = if i % 17 == 0 {
            0.0
        } else {
            x * if x > 0.0 { vc.forward } else { vc.backward }
        };
        let tol = 10f64.powf(rng.range(-9.0, -1.0));
        let exact_bound = exact::error_bound::<f64, Libm>(&s.drive());
        let ans = match mu_within::<f64, Libm>(&s, v, tol) {
            Ok(ans) => ans,
            Err(SelectError::ToleranceTooTight { best }) => {
                assert_eq!(best, exact_bound);
                assert!(tol < best, "tol {tol} refused with best {best}");
                continue;
            }
            Err(e) => panic!("{e:?}"),
        };
        assert!(ans.bound <= tol, "bound {} > tol {tol}", ans.bound);
        match (ans.method, ans.value) {
            (Method::Sliding, Value::Mu(m)) => {
                seen[0] += 1;
                // Eq. 8 by hand (velocities of a dimensionless scene are V = v/(ωW₀)),
                // with one rounding of slack.
                let (c, cb) = critical_velocities(a, b, s.params().phi);
                let c_here = if v > 0.0 { c } else { cb };
                assert!(
                    v != 0.0 && v.abs() >= c_here * (1.0 - 1e-15),
                    "v={v} c={c_here}"
                );
                assert_eq!(m, v.signum());
                assert_eq!(ans.bound, 0.0);
            }
            (
                Method::Static,
                Value::AtRest {
                    mu_0plus,
                    mu_0minus,
                    ..
                },
            ) => {
                seen[1] += 1;
                assert_eq!(v, 0.0);
                let (c, cb) = critical_velocities(a, b, s.params().phi);
                if c + cb < 2.0 - 1e-9 {
                    // A static equilibrium: μ(0⁺) = hi = min_θ(1 − a cos θ − b cos(θ+φ)),
                    // μ(0⁻) = lo, on a phase grid of 2·10⁵ points (grid error
                    // ≤ (a + b)·(π/n)²/2 ≤ (a + b)·1.3e-10, see tests/analytic.rs).
                    let (lo, hi) = static_interval_grid(a, b, s.params().phi, 200_000);
                    let tol = ans.bound + (a + b) * 2e-10;
                    assert!(
                        (mu_0plus - hi).abs() <= tol && (mu_0minus - lo).abs() <= tol,
                        "a={a} b={b}: ({mu_0plus}, {mu_0minus}) vs grid ({hi}, {lo})"
                    );
                } else if c + cb > 2.0 + 1e-9 {
                    // No equilibrium: μ(0⁺) = μ(0⁻), and μ(v) is non-decreasing
                    // (tests/regime.rs), so μ(−V) ≤ μ(0±) ≤ μ(V) for V > 0: a
                    // bracket by the fixed-step scheme at V = ±10⁻³·c with its bound.
                    let d = s.drive();
                    let (up, bu) = fixed_bounded(&d, 1e-3 * c, 4096);
                    let (down, bd) = fixed_bounded(&d, -1e-3 * cb, 4096);
                    for m in [mu_0plus, mu_0minus] {
                        assert!(
                            m >= down - bd - ans.bound && m <= up + bu + ans.bound,
                            "a={a} b={b}: μ(0±) = {m} outside [{down}, {up}]"
                        );
                    }
                }
            }
            (Method::Approx(kind), Value::Mu(m)) => {
                seen[2 + (kind == ApproxKind::TangentialEq24) as usize] += 1;
                let amp = match kind {
                    ApproxKind::NormalEq21 => {
                        assert_eq!(b, 0.0);
                        a
                    }
                    ApproxKind::TangentialEq24 => {
                        assert!(a == 0.0 && b <= 1.0);
                        b
                    }
                };
                assert_eq!(ans.bound, MAX_ERROR_OVER_A * amp);
                let e = exact::solve(&s, v).unwrap().mu_over_mu0().unwrap();
                assert!(
                    (m - e).abs() <= ans.bound,
                    "{m} vs {e} (bound {})",
                    ans.bound
                );
            }
            (Method::Exact, Value::Mu(m)) => {
                seen[4] += 1;
                // Chosen only when no approximation met the tolerance.
                let single = b == 0.0 || (a == 0.0 && b <= 1.0);
                if single {
                    let amp = if b == 0.0 { a } else { b };
                    assert!(MAX_ERROR_OVER_A * amp > tol);
                }
                assert_eq!(ans.bound, exact_bound);
                // Against the paper's fixed-step scheme at N = 4096 with its own
                // stated bound (K_D(1 + b)/N² ≤ 2.4e-6 for b ≤ 3): the two errors add.
                let (f, fb) = fixed_bounded(&s.drive(), v, 4096);
                let gap = (m - f).abs();
                worst_exact = worst_exact.max(gap / (fb + ans.bound));
                assert!(
                    gap <= fb + ans.bound,
                    "a={a} b={b} v={v}: exact {m} vs fixed {f} (bounds {fb:e} + {:e})",
                    ans.bound
                );
            }
            other => panic!("inconsistent answer {other:?}"),
        }
    }
    println!(
        "sliding/static/eq21/eq24/exact = {seen:?}; worst exact gap / allowed = {worst_exact:.3}"
    );
    // Every branch was exercised.
    assert!(seen.iter().all(|&n| n > 20), "{seen:?}");
}

#[test]
fn refusals() {
    let s = scene(0.5, 0.25, 1.0);
    for bad in [0.0, -1e-3, f64::NAN, f64::INFINITY] {
        assert_eq!(
            mu_within::<f64, Libm>(&s, 0.1, bad),
            Err(SelectError::BadTolerance)
        );
    }
    assert!(matches!(
        mu_within::<f64, Libm>(&s, f64::NAN, 1e-3),
        Err(SelectError::Exact(_))
    ));
    // Sliding needs no tolerance at all: bound 0 meets any positive one.
    let vc = CriticalVelocity::of(&s).forward;
    let a = mu_within::<f64, Libm>(&s, 2.0 * vc, 1e-300).unwrap();
    assert_eq!((a.method, a.bound), (Method::Sliding, 0.0));
    // f32 with its own (looser) exact bound.
    let s32 = model_core::Scene::dimensionless(model_core::Groups {
        duz_rel: 0.5f32,
        dux_rel: 0.25,
        phi: 1.0,
    })
    .unwrap();
    assert_eq!(
        mu_within::<f32, Libm>(&s32, 0.1, 1e-7),
        Err(SelectError::ToleranceTooTight {
            best: exact::error_bound::<f32, Libm>(&s32.drive())
        })
    );
    assert_eq!(
        mu_within::<f32, Libm>(&s32, 0.1, 1e-5).unwrap().method,
        Method::Exact
    );
}

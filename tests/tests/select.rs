//! `select::mu_within`: the cheapest method whose stated bound meets the
//! tolerance. Checked against the exact solver (an independent computation
//! for the approximations and the sliding shortcut) over random scenes and
//! tolerances: the bound never exceeds the tolerance, the value is within its
//! bound, and the choice follows the documented order.

use integration_tests::{scene, Rng};
use model_core::analytic::approx::MAX_ERROR_OVER_A;
use model_core::analytic::{ApproxKind, CriticalVelocity};
use model_core::exact::{self, Solution};
use model_core::select::{mu_within, Method, SelectError, Value};
use model_core::Libm;

#[test]
fn choice_bound_and_value_over_random_scenes() {
    let mut rng = Rng::new(2026);
    let mut seen = [0usize; 5];
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
                assert!(v != 0.0 && v.abs() >= vc.for_velocity(v));
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
                match exact::solve(&s, 0.0).unwrap() {
                    Solution::AtRest {
                        mu_0plus: p,
                        mu_0minus: m,
                        ..
                    } => assert_eq!((mu_0plus, mu_0minus), (p, m)),
                    other => panic!("{other:?}"),
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
                assert_eq!(m, exact::solve(&s, v).unwrap().mu_over_mu0().unwrap());
            }
            other => panic!("inconsistent answer {other:?}"),
        }
    }
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

//! `eval::regime_of_profile` (a regime map's cell: the class decided early
//! where it is certain) against the full `eval::classify_scene_profile`
//! (the definition, with its 64 sampled asymmetries): the same class on
//! every cell of a grid that crosses the three classes and the φ = 90°
//! line where the law is symmetric (cells at 89.9°, 90°, 90.1°), for a
//! sphere, a cone and a power law, with and without lift-off of the centre.

use fric_analysis::eval::{classify_scene_profile, regime_of_profile};
use fric_analysis::grid::cell_scene;
use model_core::mdr::Profile;
use model_core::regime::Regime;

#[test]
fn the_early_class_is_the_full_classifications() {
    let mut seen = [0usize; 3];
    let mut cells = 0;
    for p in [Profile::Sphere, Profile::Cone, Profile::Power(3.5)] {
        for a in [0.3, 0.5, 1.5] {
            for r in [0.0, 0.05, 0.3, 1.0, 3.0] {
                for phi in [0.0, 45.0, 89.9, 90.0, 90.1, 150.0, 180.0, 270.0] {
                    let s = cell_scene(a, r, phi).unwrap();
                    let full = classify_scene_profile(&s, &p).unwrap();
                    let (fast, st) = regime_of_profile(&s, &p).unwrap();
                    assert_eq!(
                        fast, full.regime,
                        "{p:?} a={a} ratio={r} φ={phi}°: early {fast:?}, full {:?}",
                        full.regime
                    );
                    let st = st.unwrap();
                    assert_eq!((st.mu_0plus, st.mu_0minus), (full.mu_0plus, full.mu_0minus));
                    seen[match fast {
                        Regime::ActiveControl => 0,
                        Regime::DynamicRatchet => 1,
                        Regime::Actuator => 2,
                    }] += 1;
                    cells += 1;
                }
            }
        }
    }
    println!("{cells} cells: {seen:?} (active control, ratchet, actuator)");
    assert!(seen.iter().all(|&k| k > 0), "every class met: {seen:?}");
}

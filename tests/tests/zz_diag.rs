use model_core::mdr::{self, Profile};
use model_core::{Drive, Libm};
#[test]
fn diag() {
    for p in [Profile::Sphere, Profile::Cone] {
        for &(a, b, phi, v) in &[(0.5, 1.0, 0.3, 0.2), (1.5, 0.7, 2.0, 0.1)] {
            let d = Drive::new::<Libm>(a, b, phi);
            for tol in [1e-6, 1e-8, 1e-9] {
                let r = mdr::mu_over_mu0::<f64, Libm>(&d, &p, v, tol);
                println!(
                    "{p:?} a={a} tol={tol:e}: {:?}",
                    r.map(|r| (r.mu_over_mu0, r.bound, r.evaluations))
                );
            }
        }
    }
}

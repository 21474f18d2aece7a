//! Criterion bench of the MDR quadrature: a sphere's and a cone's μ at a few
//! tolerances (f64, one core), median per evaluation.
//!
//! `cargo bench -p model-core --bench mdr`

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use model_core::mdr::{self, Profile};
use model_core::{Drive, Libm};

fn profiles(c: &mut Criterion) {
    // Stick–slip with a permanent core and an intermittent rim (a < 1: the
    // lift-off onset ξ_a inside the contact) and with every spring lifting
    // off (a = 1.5).
    let sphere: &[(&str, f64, f64, f64, f64)] = &[
        ("a0.25_b1_phi0.3_v0.2", 0.25, 1.0, 0.3, 0.2),
        ("a0.5_b1_phi0.3_v0.2", 0.5, 1.0, 0.3, 0.2),
        ("a0.9_b1_phi0.3_v0.2", 0.9, 1.0, 0.3, 0.2),
        ("a1.5_b0.7_phi2_v0.1", 1.5, 0.7, 2.0, 0.1),
    ];
    let cone: &[(&str, f64, f64, f64, f64)] = &[
        ("a0.5_b1_phi0.3_v0.2", 0.5, 1.0, 0.3, 0.2),
        ("a1.5_b0.7_phi2_v0.1", 1.5, 0.7, 2.0, 0.1),
    ];
    for (group, profile, scenes) in [
        ("mdr_sphere", Profile::Sphere, sphere),
        ("mdr_cone", Profile::Cone, cone),
    ] {
        let mut g = c.benchmark_group(group);
        for &(name, a, b, phi, v) in scenes {
            let d = Drive::new::<Libm>(a, b, phi);
            for tol in [1e-6, 1e-8, 1e-9] {
                g.bench_with_input(BenchmarkId::new(name, tol), &tol, |bench, &tol| {
                    bench.iter(|| {
                        mdr::mu_over_mu0::<f64, Libm>(
                            black_box(&d),
                            black_box(&profile),
                            black_box(v),
                            tol,
                        )
                        .unwrap()
                        .mu_over_mu0
                    })
                });
            }
        }
        g.finish();
    }
}

criterion_group!(benches, profiles);
criterion_main!(benches);

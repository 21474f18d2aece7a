//! Criterion bench of the MDR quadrature: a sphere's and a cone's μ at a few
//! tolerances (f64, one core), median per evaluation.
//!
//! `cargo bench -p model-core --bench mdr`

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use model_core::mdr::{self, Profile};
use model_core::{Drive, Libm};

fn profiles(c: &mut Criterion) {
    for (group, profile) in [("mdr_sphere", Profile::Sphere), ("mdr_cone", Profile::Cone)] {
        let mut g = c.benchmark_group(group);
        // Stick–slip at a = 0.5 (permanent core + intermittent rim) and a = 1.5
        // (all springs lift off).
        for (name, a, b, phi, v) in [
            ("a0.5_b1_phi0.3_v0.2", 0.5, 1.0, 0.3, 0.2),
            ("a1.5_b0.7_phi2_v0.1", 1.5, 0.7, 2.0, 0.1),
        ] {
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

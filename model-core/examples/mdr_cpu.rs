//! CPU time and spring solves of one MDR μ (f64, libm) for the scenes of
//! `benches/mdr.rs`: this thread's CPU time from `/proc/thread-self/schedstat`
//! (Linux), so other processes on a shared machine count less than in a
//! wall-clock bench. Each scene × tolerance: 5 batches of 4000 calls (schedstat advances in scheduler ticks of 4 ms, 1 µs per call), the
//! median batch mean is printed.
//!
//! `cargo run --release -p model-core --example mdr_cpu`

use std::hint::black_box;

use model_core::mdr::{self, Profile};
use model_core::{Drive, Libm};

fn cpu_ns() -> u64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse().ok())
        .unwrap_or(0)
}

/// A scene: profile name, profile, a, b, φ (rad), V (units of ωW₀).
type SceneRow = (&'static str, Profile<f64>, f64, f64, f64, f64);

fn main() {
    let scenes: &[SceneRow] = &[
        ("sphere", Profile::Sphere, 0.25, 1.0, 0.3, 0.2),
        ("sphere", Profile::Sphere, 0.5, 1.0, 0.3, 0.2),
        ("sphere", Profile::Sphere, 0.9, 1.0, 0.3, 0.2),
        ("sphere", Profile::Sphere, 1.5, 0.7, 2.0, 0.1),
        ("cone", Profile::Cone, 0.5, 1.0, 0.3, 0.2),
        ("cone", Profile::Cone, 1.5, 0.7, 2.0, 0.1),
    ];
    println!("profile  a     b    phi  V     tol    solves  CPU µs (median of 5 × 4000)");
    for &(name, p, a, b, phi, v) in scenes {
        let d = Drive::new::<Libm>(a, b, phi);
        for tol in [1e-6, 1e-8, 1e-9] {
            let r = mdr::mu_over_mu0::<f64, Libm>(&d, &p, v, tol).expect("mu");
            let mut batches: Vec<f64> = (0..5)
                .map(|_| {
                    let c0 = cpu_ns();
                    for _ in 0..4000 {
                        black_box(mdr::mu_over_mu0::<f64, Libm>(black_box(&d), &p, v, tol).ok());
                    }
                    (cpu_ns() - c0) as f64 / 4000.0 * 1e-3
                })
                .collect();
            batches.sort_by(f64::total_cmp);
            println!(
                "{name:8} {a:<5} {b:<4} {phi:<4} {v:<5} {tol:<6e} {:>6}  {:>7.1}",
                r.evaluations, batches[2]
            );
        }
    }
}

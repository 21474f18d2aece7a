//! CPU time per μ of a sphere through the MDR (f64, libm), averaged over
//! 1000 velocities across `(−V_c⁻, V_c⁺)` for three drives at three
//! tolerances, with the mean number of spring solves and the worst bound.
//! This thread's CPU time from `/proc/thread-self/schedstat` (Linux), so other
//! processes on a loaded machine count less than in a wall-clock bench.
//!
//! `cargo run --release -p model-core --example mdr_cpu_sweep`

use model_core::mdr::{self, Profile};
use model_core::{Drive, Libm};

fn cpu_ns() -> u64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse().ok())
        .unwrap_or(0)
}

fn main() {
    for &(a, b, phi) in &[(0.5, 0.25, 1.0), (0.5, 1.0, 0.3), (1.5, 0.7, 2.0)] {
        let d = Drive::new::<Libm>(a, b, phi);
        let (cf, cb) =
            mdr::critical_velocities::<f64, Libm>(&d, &Profile::Sphere).expect("critical");
        for tol in [1e-6, 1e-8, 1e-9] {
            let n = 1000u32;
            let mut springs = 0;
            let mut worst_bound: f64 = 0.0;
            let c0 = cpu_ns();
            for i in 0..n {
                let v = -cb + (cf + cb) * (f64::from(i) + 0.5) / f64::from(n);
                let r = mdr::mu_over_mu0::<f64, Libm>(&d, &Profile::Sphere, v, tol).expect("mu");
                springs += r.evaluations;
                worst_bound = worst_bound.max(r.bound);
            }
            let us = (cpu_ns() - c0) as f64 / f64::from(n) * 1e-3;
            println!(
                "sphere a={a} b={b} phi={phi} tol={tol:e}: {us:.1} µs CPU per point, {} springs per point, worst bound {worst_bound:.1e}",
                springs / n
            );
        }
    }
}

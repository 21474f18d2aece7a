//! Criterion benches: exact μ evaluation (permanent contact and lift-off), fixed-step throughput (f32, f64), and
//! the paper's method (fixed-step from rest to 1e-8) against the exact solver.
//!
//! `cargo bench -p model-core --bench solvers`

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use model_core::fixed_step::{run_dimensionless, FixedStepConfig, Start};
use model_core::model::liftoff::{self, stepping};
use model_core::{exact, Drive, Libm};

/// A dual-mode ratchet scene with back-and-forth stick–slip (a = 0.5, b = 0.25, φ = 1).
fn drive64() -> Drive<f64> {
    Drive::new::<Libm>(0.5, 0.25, 1.0)
}

fn exact_mu(c: &mut Criterion) {
    let mut g = c.benchmark_group("exact_mu");
    let d = drive64();
    let cf = d.c_forward::<Libm>();
    // 64 velocities spread over (−v_c, v_c): the median per evaluation.
    let vs: Vec<f64> = (0..64)
        .map(|i| cf * (-0.98 + 1.96 * (i as f64 + 0.5) / 64.0))
        .collect();
    g.throughput(Throughput::Elements(vs.len() as u64));
    g.bench_function("f64", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for &v in &vs {
                acc += exact::mu_over_mu0::<f64, Libm>(black_box(&d), black_box(v)).unwrap();
            }
            acc
        })
    });
    let d32 = Drive::new::<Libm>(0.5f32, 0.25, 1.0);
    let vs32: Vec<f32> = vs.iter().map(|&v| v as f32).collect();
    g.bench_function("f32", |b| {
        b.iter(|| {
            let mut acc = 0.0f32;
            for &v in &vs32 {
                acc += exact::mu_over_mu0::<f32, Libm>(black_box(&d32), black_box(v)).unwrap();
            }
            acc
        })
    });
    g.finish();
}

fn exact_liftoff_mu(c: &mut Criterion) {
    // The lift-off solver on the same drive with a = 1.5 (the contact is in
    // the air for |θ| < 48.2°), 64 velocities over (−1.2 V_c⁻, 1.2 V_c⁺)
    // (about a fifth slide continuously and return ±1 at once).
    let mut g = c.benchmark_group("exact_liftoff_mu");
    let d = Drive::new::<Libm>(1.5, 0.25, 1.0);
    let (cp, cm) = liftoff::critical_velocities::<f64, Libm>(&d).unwrap();
    let vs: Vec<f64> = (0..64)
        .map(|i| -1.2 * cm + 1.2 * (cp + cm) * (i as f64 + 0.5) / 64.0)
        .collect();
    g.throughput(Throughput::Elements(vs.len() as u64));
    g.bench_function("f64", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for &v in &vs {
                acc += liftoff::mu_over_mu0::<f64, Libm>(black_box(&d), black_box(v)).unwrap();
            }
            acc
        })
    });
    let d32 = Drive::new::<Libm>(1.5f32, 0.25, 1.0);
    let vs32: Vec<f32> = vs.iter().map(|&v| v as f32).collect();
    g.bench_function("f32", |b| {
        b.iter(|| {
            let mut acc = 0.0f32;
            for &v in &vs32 {
                acc += liftoff::mu_over_mu0::<f32, Libm>(black_box(&d32), black_box(v)).unwrap();
            }
            acc
        })
    });
    // The fixed-step scheme with exact landing at N = 4096 (one window, no
    // transient), for comparison.
    g.throughput(Throughput::Elements(1));
    let v = 0.3 * cp;
    g.bench_function("stepping_f64_N4096_one_point", |b| {
        b.iter(|| stepping::mu_over_mu0::<f64, Libm>(black_box(&d), black_box(v), 4096).unwrap())
    });
    g.finish();
}

fn fixed_step_throughput(c: &mut Criterion) {
    let mut g = c.benchmark_group("fixed_step");
    let n = 4096u32;
    let d = drive64();
    let v = 0.3 * d.c_forward::<Libm>();
    let cfg = FixedStepConfig::<f64>::new(n);
    let steps = run_dimensionless::<f64, Libm>(&d, v, &cfg, Start::Rest)
        .unwrap()
        .steps;
    g.throughput(Throughput::Elements(steps));
    g.bench_function(BenchmarkId::new("f64_steps", n), |b| {
        b.iter(|| {
            run_dimensionless::<f64, Libm>(black_box(&d), black_box(v), &cfg, Start::Rest).unwrap()
        })
    });
    // f32 refuses N beyond its precision limit (`max_steps_per_period`, 2 204).
    let n32 = 2048u32;
    let d32 = Drive::new::<Libm>(0.5f32, 0.25, 1.0);
    let cfg32 = FixedStepConfig::<f32>::new(n32);
    let steps32 = run_dimensionless::<f32, Libm>(&d32, v as f32, &cfg32, Start::Rest)
        .unwrap()
        .steps;
    g.throughput(Throughput::Elements(steps32));
    g.bench_function(BenchmarkId::new("f32_steps", n32), |b| {
        b.iter(|| {
            run_dimensionless::<f32, Libm>(
                black_box(&d32),
                black_box(v as f32),
                &cfg32,
                Start::Rest,
            )
            .unwrap()
        })
    });
    g.finish();
}

fn paper_method_vs_exact(c: &mut Criterion) {
    // The paper's method at the resolution that reaches |Δμ| ≤ 1e-8 for this
    // point (N = 16384, checked below), against one exact evaluation.
    let mut g = c.benchmark_group("one_point_1e-8");
    let d = drive64();
    let v = 0.3 * d.c_forward::<Libm>();
    let e = exact::mu_over_mu0::<f64, Libm>(&d, v).unwrap();
    let cfg = FixedStepConfig::<f64>::new(16384);
    let f = run_dimensionless::<f64, Libm>(&d, v, &cfg, Start::Rest)
        .unwrap()
        .mu_over_mu0;
    assert!(
        (f - e).abs() <= 1e-8,
        "N = 16384 does not reach 1e-8 here: {}",
        (f - e).abs()
    );
    g.bench_function("fixed_step_from_rest_N16384", |b| {
        b.iter(|| {
            run_dimensionless::<f64, Libm>(black_box(&d), black_box(v), &cfg, Start::Rest).unwrap()
        })
    });
    g.bench_function("exact", |b| {
        b.iter(|| exact::mu_over_mu0::<f64, Libm>(black_box(&d), black_box(v)).unwrap())
    });
    // Low velocity (v = 0.02 v_c): the transient from rest takes many periods.
    let vl = 0.02 * d.c_forward::<Libm>();
    let el = exact::mu_over_mu0::<f64, Libm>(&d, vl).unwrap();
    let out = run_dimensionless::<f64, Libm>(&d, vl, &cfg, Start::Rest).unwrap();
    assert!(
        (out.mu_over_mu0 - el).abs() <= 1e-8,
        "{}",
        (out.mu_over_mu0 - el).abs()
    );
    eprintln!(
        "low velocity: fixed-step from rest used {} periods",
        out.periods
    );
    g.bench_function("fixed_step_from_rest_N16384_low_v", |b| {
        b.iter(|| {
            run_dimensionless::<f64, Libm>(black_box(&d), black_box(vl), &cfg, Start::Rest).unwrap()
        })
    });
    g.bench_function("exact_low_v", |b| {
        b.iter(|| exact::mu_over_mu0::<f64, Libm>(black_box(&d), black_box(vl)).unwrap())
    });
    g.finish();
}

criterion_group!(
    benches,
    exact_mu,
    exact_liftoff_mu,
    fixed_step_throughput,
    paper_method_vs_exact
);
criterion_main!(benches);

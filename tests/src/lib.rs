//! Shared helpers for the integration tests: scene builders and independent
//! reference computations (none of them calls the code path it checks).
#![deny(missing_docs)]

pub mod wire;

use model_core::device::DeviceConfig;
use model_core::fixed_step::{run_dimensionless, FixedStepConfig, Start};
use model_core::{Drive, Groups, Libm, Scene, SceneParams};

/// The dimensionless scene with groups `(a, b, φ)`.
pub fn scene(a: f64, b: f64, phi: f64) -> Scene<f64> {
    Scene::dimensionless(Groups {
        duz_rel: a,
        dux_rel: b,
        phi,
    })
    .expect("valid test scene")
}

/// The physical scene of the README's examples (and of the CLI tests' flags):
/// μ₀ = 0.3, k_z = 2e6 N/m, k_x = 1.5e6 N/m, u_z0 = 5 µm, Δu_z = 2 µm,
/// Δu_x = 0.7 µm, f = 40 kHz, φ = 50°.
pub fn physical_scene() -> Scene<f64> {
    Scene::new(SceneParams {
        mu0: 0.3,
        kz: 2e6,
        kx: 1.5e6,
        uz0: 5e-6,
        duz: 2e-6,
        dux: 0.7e-6,
        omega: std::f64::consts::TAU * 40e3,
        phi: 50f64.to_radians(),
    })
    .expect("valid physical scene")
}

/// The dimensionless scene from eq. 26 groups (`ratio = b/a`).
pub fn scene_ratio(a: f64, ratio: f64, phi: f64) -> Scene<f64> {
    Scene::dimensionless(Groups::from_ratio(a, ratio, phi).expect("valid groups"))
        .expect("valid test scene")
}

/// The fixed-step (paper's) scheme from rest with `n` steps per period,
/// dimensionless velocity `v`; panics if it does not converge.
pub fn fixed(d: &Drive<f64>, v: f64, n: u32) -> f64 {
    let mut cfg = FixedStepConfig::<f64>::new(n);
    cfg.max_periods = 2_000_000;
    run_dimensionless::<f64, Libm>(d, v, &cfg, Start::Rest)
        .expect("fixed-step converges")
        .mu_over_mu0
}

/// Brute-force static interval: `[max_θ(−1 + a cos θ − b cos(θ+φ)), min_θ(1 − a cos θ − b cos(θ+φ))]`
/// on a grid of `n` phases (an upper bound on `lo`'s error of O(1/n²)).
pub fn static_interval_grid(a: f64, b: f64, phi: f64, n: usize) -> (f64, f64) {
    let mut lo = f64::NEG_INFINITY;
    let mut hi = f64::INFINITY;
    for i in 0..n {
        let t = std::f64::consts::TAU * i as f64 / n as f64;
        let w = 1.0 - a * t.cos();
        let x = b * (t + phi).cos();
        hi = hi.min(w - x);
        lo = lo.max(-w - x);
    }
    (lo, hi)
}

/// A small deterministic PRNG (xorshift64*), for reproducible random scenes.
pub struct Rng(u64);

impl Rng {
    /// Seeded generator (seed ≠ 0).
    pub fn new(seed: u64) -> Self {
        Rng(seed.max(1))
    }
    /// Uniform in `[0, 1)`.
    pub fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Uniform in `[lo, hi)`.
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.uniform()
    }
}

/// The driver board's configuration (model-core) at 1 MS/s, so that sample
/// counts in the device tests are microseconds.
pub fn board_config_1mhz() -> DeviceConfig {
    DeviceConfig {
        sample_rate_hz: 1_000_000.0,
        ..DeviceConfig::driver_board(0)
    }
}

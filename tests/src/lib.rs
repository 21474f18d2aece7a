//! Shared helpers for the integration tests: scene builders and independent
//! reference computations (none of them calls the code path it checks).
#![deny(missing_docs)]

pub mod resonant;
pub mod springs;
pub mod wire;

use board::device::DeviceConfig;
use model_core::fixed_step::{run_dimensionless, FixedStepConfig, Start, State};
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

/// The fixed-step (paper's) scheme from rest with `n` steps per period at
/// dimensionless velocity `v`: `(μ/μ₀, its stated error bound)` — the bound
/// `(1 + b)(K_D/N² + K_R·N·ε)` of `fixed_step::error_bound`. Its constants are
/// calibrated on the scheme alone (`K_D` by self-convergence against the same
/// scheme at 2¹⁸ steps per period, `K_R` by the scheme in f32 against f64:
/// `tests/fixed_step_bound.rs`), without the exact solver, so a comparison of
/// the exact solver with this run within this bound is an independent check.
/// Panics if it does not converge.
pub fn fixed_bounded(d: &Drive<f64>, v: f64, n: u32) -> (f64, f64) {
    let mut cfg = FixedStepConfig::<f64>::new(n);
    cfg.max_periods = 2_000_000;
    let r = run_dimensionless::<f64, Libm>(d, v, &cfg, Start::Rest).expect("fixed-step converges");
    (r.mu_over_mu0, r.error_bound)
}

/// The fixed-step scheme started on the band edge where a clamp in the
/// direction of motion is certain in the first step: `(μ/μ₀, stated bound)`.
///
/// While stuck, the stretch moves at `V − b sin(θ+φ)` and the band edge `+w` at
/// `a sin θ`, so a forward clamp (V > 0) needs `V > Im((b e^{iφ} + a) e^{iθ})`,
/// which holds where that sinusoid is at its minimum `−c`: start there with
/// `s = +w`. For V < 0, start at the maximum `c'` of `Im((b e^{iφ} − a) e^{iθ})`
/// with `s = −w`. The scheme's steady state does not depend on the start, and
/// it is proven steady two periods after the first clamp, so the run takes
/// ≈ 3 periods at any |V| (from rest it takes ≈ 1/(2π|V|)). Panics if the run
/// does not converge.
pub fn fixed_warm(d: &Drive<f64>, v: f64, n: u32) -> (f64, f64) {
    let (bc, bs) = (d.bc, d.bs); // b cos φ, b sin φ
    let phase = if v > 0.0 {
        -std::f64::consts::FRAC_PI_2 - bs.atan2(bc + d.a)
    } else {
        std::f64::consts::FRAC_PI_2 - bs.atan2(bc - d.a)
    };
    // A few ulps inside the band, so rounding of w(θ) cannot reject the start.
    let w = (1.0 - d.a * phase.cos()) * (1.0 - 4.0 * f64::EPSILON);
    let start = Start::State(State {
        phase,
        stretch: if v > 0.0 { w } else { -w },
    });
    let mut cfg = FixedStepConfig::<f64>::new(n);
    cfg.max_periods = 2_000_000;
    let r = run_dimensionless::<f64, Libm>(d, v, &cfg, start).expect("fixed-step converges");
    (r.mu_over_mu0, r.error_bound)
}

/// The sampling (quadrature) error of a sampled plant: the range `(min, max)`
/// over sampling offsets of `⟨s⟩_sampled − ⟨s⟩` (units of μ₀), where the paper's
/// scheme — written out here, independent of `model_core::fixed_step` — runs
/// with `samples·sub` steps per period and the mean is taken either over every
/// step (`⟨s⟩`) or over every `sub`-th step only, as an estimator that sees
/// `samples` ADC samples per period does. The stretch has kinks (stick → slip),
/// so the sampled mean is off by O((2π/samples)²), depending on where the
/// samples fall: this is that error for every offset on the sub-step grid.
/// The run is steady after `D/(2π|V|) + 4` periods, `D = 2(1 + a + b)` (the
/// transient bound derived in tests/stability.rs).
pub fn sampling_error_range(
    a: f64,
    b: f64,
    phi: f64,
    v: f64,
    samples: u32,
    sub: u32,
) -> (f64, f64) {
    let n = (samples * sub) as usize;
    let delta = std::f64::consts::TAU / n as f64;
    let periods = (2.0 * (1.0 + a + b) / (std::f64::consts::TAU * v.abs())).ceil() as usize + 6;
    let (mut s, mut x_prev) = (0.0f64, b * phi.cos());
    let (mut ss, mut ws) = (vec![0.0; n], vec![0.0; n]);
    for _ in 0..periods {
        for k in 0..n {
            let th = delta * (k + 1) as f64;
            let x = b * (th + phi).cos();
            let w = 1.0 - a * th.cos();
            s = (s + v * delta + (x - x_prev)).clamp(-w, w);
            x_prev = x;
            ss[k] = s;
            ws[k] = w;
        }
    }
    let full = ss.iter().sum::<f64>() / ws.iter().sum::<f64>();
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for j in 0..sub as usize {
        let num: f64 = ss.iter().skip(j).step_by(sub as usize).sum();
        let den: f64 = ws.iter().skip(j).step_by(sub as usize).sum();
        let e = num / den - full;
        lo = lo.min(e);
        hi = hi.max(e);
    }
    (lo, hi)
}

/// The dimensionless critical velocities `(c, c')` of eq. 8 written out by
/// hand: `c = √(a² + 2ab cos φ + b²)` (forward), `c' = √(a² − 2ab cos φ + b²)`
/// (backward), in units of ωW₀.
pub fn critical_velocities(a: f64, b: f64, phi: f64) -> (f64, f64) {
    let k = 2.0 * a * b * phi.cos();
    (
        (a * a + k + b * b).max(0.0).sqrt(),
        (a * a - k + b * b).max(0.0).sqrt(),
    )
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

/// The worst-case effect of an error of at most ±1 (count) on every sample
/// on a lock-in window's amplitude (`board::lockin`, the
/// least-squares fit of d + a cos θ + b sin θ): the fit's a and b are linear
/// in the samples with weights `w_a`, `w_b` (rows of `(XᵀX)⁻¹Xᵀ`), so
/// `|δa| ≤ Σ|w_a|`, `|δb| ≤ Σ|w_b|` and `|δA| ≤ √((Σ|w_a|)² + (Σ|w_b|)²)`;
/// the phase moves by at most that over the amplitude. Computed here for a
/// window of `n` samples `dtheta` apart, the worst over 64 starting phases.
pub fn lockin_error_gain(n: usize, dtheta: f64) -> f64 {
    let mut worst: f64 = 0.0;
    for k in 0..64 {
        let th0 = std::f64::consts::TAU * k as f64 / 64.0;
        let rows: Vec<[f64; 3]> = (0..n)
            .map(|i| {
                let t = th0 + i as f64 * dtheta;
                [1.0, t.cos(), t.sin()]
            })
            .collect();
        let mut m = [[0.0f64; 3]; 3];
        for r in &rows {
            for i in 0..3 {
                for j in 0..3 {
                    m[i][j] += r[i] * r[j];
                }
            }
        }
        // Inverse of the symmetric 3×3 by cofactors.
        let c = |i: usize, j: usize| {
            let (a, b) = ((i + 1) % 3, (i + 2) % 3);
            let (p, q) = ((j + 1) % 3, (j + 2) % 3);
            m[a][p] * m[b][q] - m[a][q] * m[b][p]
        };
        let det = m[0][0] * c(0, 0) + m[0][1] * c(0, 1) + m[0][2] * c(0, 2);
        let inv = |i: usize, j: usize| c(j, i) / det;
        let (mut sa, mut sb) = (0.0, 0.0);
        for r in &rows {
            let wa: f64 = (0..3).map(|j| inv(1, j) * r[j]).sum();
            let wb: f64 = (0..3).map(|j| inv(2, j) * r[j]).sum();
            sa += wa.abs();
            sb += wb.abs();
        }
        worst = worst.max((sa * sa + sb * sb).sqrt());
    }
    worst
}

/// A law's one-sided limit at 0 from its values at `V`, `2V`, `4V`, each
/// with its error: `(E₁, allowance)`. `E₁ = 2μ(V) − μ(2V)` removes the
/// linear term (the law is smooth on each side of 0); its remainder is
/// estimated as `(E₁ − E₂)/3`, `E₂ = 2μ(2V) − μ(4V)`; the values' errors
/// enter with their weights (2 + 1 in `E₁`, (2 + 3 + 1)/3 in the remainder).
pub fn limit_by_extrapolation(at: [(f64, f64); 3]) -> (f64, f64) {
    let [(m1, e1), (m2, e2), (m4, e4)] = at;
    let x1 = 2.0 * m1 - m2;
    let x2 = 2.0 * m2 - m4;
    let allowance = (x1 - x2).abs() / 3.0 + (2.0 * e1 + e2) + (2.0 * e1 + 3.0 * e2 + e4) / 3.0;
    (x1, allowance)
}

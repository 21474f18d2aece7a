//! The fast `f32` trigonometry (`model_core::float::trig`, backend `FastF32`)
//! against `f64` (Rust's `std`, i.e. the platform libm, within an `f64` ulp —
//! 10⁻¹⁶, far below the `f32` errors measured here).
//!
//! * `dense_*`: a strided enumeration of the `f32` bit patterns of each
//!   function's whole range (every exponent, ~10⁶ arguments each) must stay
//!   within the documented bounds (`trig::ERR_*`).
//! * `exhaustive_*` (ignored by `cargo test`; run by CI, `.ci/run`:
//!   `cargo test -p integration-tests --test trig -- --ignored --nocapture`):
//!   *every* `f32` of the range — the proof of those bounds, since the
//!   functions are symmetric by construction (computed on `|x|`, sign applied
//!   last) and bit-identical on the host and the Cortex-M4F (IEEE single, no
//!   FMA). For `atan2` the proof covers the one-parameter families
//!   `(t, ±1)`, `(±1, ±t)` only (every f32 ratio of the reduced argument),
//!   not every pair; `random_pairs_atan2_hypot_within_bound` samples pairs.
//!   (`same_bits_as_the_target`: the digest the firmware's `f32_vectors`
//!   checks on the emulated M4F).
//! * `exact_solver_mu_*`, `device_prediction_path_with_fast_f32`: μ/μ₀ of the
//!   exact solver in `f32` with `FastF32` against the `f64` solver over
//!   thousands of random scenes and on the board's scene.
//! * `calls_per_prediction`: where the solver's transcendental calls go.

use integration_tests::Rng;
use model_core::float::trig;
use model_core::float::FastF32;
use model_core::{exact, Drive, Libm, Math};

/// Worst absolute error of `sin_cos` over the `f32` bit patterns
/// `lo, lo + step, …, ≤ hi` (positive arguments).
fn sin_cos_err(lo: u32, hi: u32, step: usize) -> (f64, f32) {
    let mut worst = (0.0f64, 0.0f32);
    for bits in (lo..=hi).step_by(step) {
        let x = f32::from_bits(bits);
        let (s, c) = trig::sin_cos(x);
        let xd = f64::from(x);
        let e = (f64::from(s) - xd.sin())
            .abs()
            .max((f64::from(c) - xd.cos()).abs());
        if e > worst.0 {
            worst = (e, x);
        }
    }
    worst
}

fn asin_err(lo: u32, hi: u32, step: usize) -> (f64, f32) {
    let mut worst = (0.0f64, 0.0f32);
    for bits in (lo..=hi).step_by(step) {
        let x = f32::from_bits(bits);
        let e = (f64::from(trig::asin(x)) - f64::from(x).asin()).abs();
        if e > worst.0 {
            worst = (e, x);
        }
    }
    worst
}

/// Worst relative error of `sqrt` over positive `f32` bit patterns.
fn sqrt_err(lo: u32, hi: u32, step: usize) -> (f64, f32) {
    let mut worst = (0.0f64, 0.0f32);
    for bits in (lo..=hi).step_by(step) {
        let x = f32::from_bits(bits);
        let r = f64::from(x).sqrt();
        let e = if r == 0.0 {
            f64::from(trig::sqrt(x)).abs()
        } else {
            (f64::from(trig::sqrt(x)) - r).abs() / r
        };
        if e > worst.0 {
            worst = (e, x);
        }
    }
    worst
}

/// atan2 over every direction the one-argument sweep reaches: `(t, 1)`,
/// `(1, t)`, `(t, −1)`, `(−1, −t)` for `t` on the bit patterns — every ratio
/// `t ∈ [0, ∞)` in all four quadrants, in both branches of the swap. This is
/// a proof over these one-parameter families only (one of `|x|`, `|y|` is 1),
/// not over all pairs `(y, x)`: for other pairs the reduced argument
/// (`num/den`, or `(num − den)/(num + den)` above tan π/8) is rounded
/// differently, and pairs are only sampled
/// (`random_pairs_atan2_hypot_within_bound`).
///
/// The f64 reference is one `atan(t)` per `t`, the four directions from the
/// identities `atan2(1, t) = π/2 − atan t`, `atan2(t, −1) = π − atan t`,
/// `atan2(−1, −t) = −π/2 − atan t` (t ≥ 0): each one rounding more in f64
/// (≤ 4.5e-16), far below the f32 errors measured, and a quarter of the
/// f64 work of four `atan2` calls.
fn atan2_err(lo: u32, hi: u32, step: usize) -> (f64, f32) {
    use std::f64::consts::{FRAC_PI_2, PI};
    let mut worst = (0.0f64, 0.0f32);
    for bits in (lo..=hi).step_by(step) {
        let t = f32::from_bits(bits);
        let at = f64::from(t).atan();
        for ((y, x), want) in [
            ((t, 1.0f32), at),
            ((1.0, t), FRAC_PI_2 - at),
            ((t, -1.0), PI - at),
            ((-1.0, -t), -FRAC_PI_2 - at),
        ] {
            let e = angle_diff(f64::from(trig::atan2(y, x)), want);
            if e > worst.0 {
                worst = (e, t);
            }
        }
    }
    worst
}

fn angle_diff(a: f64, b: f64) -> f64 {
    (a - b).abs()
}

const PI4_BITS_HI: u32 = 0x4580_0000; // 4096.0 = SIN_COS_MAX_ARG
const ONE_BITS: u32 = 0x3f80_0000;

#[test]
fn range_constants() {
    assert_eq!(f32::from_bits(PI4_BITS_HI), trig::SIN_COS_MAX_ARG);
    assert_eq!(f32::from_bits(ONE_BITS), 1.0);
}

#[test]
fn dense_sin_cos_within_bound() {
    // Prime stride over all 1.17e9 positive f32 ≤ 4096: ~1.2e6 arguments, every exponent.
    let (e, x) = sin_cos_err(0, PI4_BITS_HI, 977);
    println!("sin_cos dense: worst {e:.3e} at x = {x}");
    assert!(e <= trig::ERR_SIN_COS, "sin_cos error {e:e} at x = {x}");
    // Odd/even symmetry is exact by construction: check it on the same grid.
    for bits in (0..PI4_BITS_HI).step_by(100_003) {
        let x = f32::from_bits(bits);
        let (s, c) = trig::sin_cos(x);
        let (sn, cn) = trig::sin_cos(-x);
        assert!(sn == -s && cn == c, "symmetry at {x}");
    }
}

#[test]
fn dense_asin_within_bound() {
    let (e, x) = asin_err(0, ONE_BITS, 887);
    println!("asin dense: worst {e:.3e} at x = {x}");
    assert!(e <= trig::ERR_ASIN, "asin error {e:e} at x = {x}");
}

#[test]
fn dense_atan2_within_bound() {
    // t over all finite positive f32: 0 … f32::MAX.
    let (e, t) = atan2_err(0, f32::MAX.to_bits(), 2_111);
    println!("atan2 dense: worst {e:.3e} at t = {t}");
    assert!(e <= trig::ERR_ATAN2, "atan2 error {e:e} at t = {t}");
}

#[test]
fn dense_sqrt_within_bound() {
    // Every exponent: zero, subnormals (libm), normals up to f32::MAX.
    let (e, x) = sqrt_err(0, f32::MAX.to_bits(), 1_999);
    println!("sqrt dense: worst {e:.3e} relative at x = {x}");
    assert!(e <= trig::ERR_SQRT, "sqrt error {e:e} at x = {x}");
    assert_eq!(trig::sqrt(0.0), 0.0);
    assert_eq!(trig::sqrt(f32::INFINITY), f32::INFINITY);
    assert!(trig::sqrt(-1.0).is_nan() && trig::sqrt(f32::NAN).is_nan());
}

#[test]
fn random_pairs_atan2_hypot_within_bound() {
    // Two-argument functions: 10⁶ random pairs over 40 decades (the division
    // and the sum of squares round differently for each pair).
    let mut rng = Rng::new(7);
    let (mut ea, mut eh) = (0.0f64, 0.0f64);
    for _ in 0..1_000_000 {
        let y = (rng.range(-1.0, 1.0) * 10f64.powf(rng.range(-20.0, 20.0))) as f32;
        let x = (rng.range(-1.0, 1.0) * 10f64.powf(rng.range(-20.0, 20.0))) as f32;
        let (yd, xd) = (f64::from(y), f64::from(x));
        ea = ea.max(angle_diff(f64::from(trig::atan2(y, x)), yd.atan2(xd)));
        let h = yd.hypot(xd);
        eh = eh.max((f64::from(trig::hypot(y, x)) - h).abs() / h);
    }
    println!("random pairs: atan2 {ea:.3e} rad, hypot {eh:.3e} relative");
    assert!(ea <= trig::ERR_ATAN2);
    assert!(eh <= trig::ERR_HYPOT);
}

#[test]
fn special_values_follow_libm() {
    // Beyond the reduced range and non-finite: libm's answers exactly.
    for x in [5000.0f32, -1e7, 3.4e38] {
        assert_eq!(trig::sin_cos(x), <Libm as Math<f32>>::sin_cos(x), "x = {x}");
    }
    for x in [f32::INFINITY, f32::NEG_INFINITY, f32::NAN] {
        let (s, c) = trig::sin_cos(x);
        assert!(s.is_nan() && c.is_nan(), "x = {x}");
    }
    assert_eq!(trig::sin_cos(0.0), (0.0, 1.0));
    assert!(trig::sin_cos(-0.0).0.is_sign_negative());
    // asin: ±1 → ±π/2 (f32-rounded), outside [-1, 1] and NaN → NaN.
    assert_eq!(trig::asin(1.0), core::f32::consts::FRAC_PI_2);
    assert_eq!(trig::asin(-1.0), -core::f32::consts::FRAC_PI_2);
    assert!(trig::asin(1.000_001).is_nan() && trig::asin(f32::NAN).is_nan());
    // atan2's signed zeros as libm (C99 Annex F).
    use core::f32::consts::PI;
    assert_eq!(trig::atan2(0.0, 0.0).to_bits(), 0.0f32.to_bits());
    assert_eq!(trig::atan2(-0.0, 0.0).to_bits(), (-0.0f32).to_bits());
    assert_eq!(trig::atan2(0.0, -0.0), PI);
    assert_eq!(trig::atan2(-0.0, -0.0), -PI);
    assert_eq!(trig::atan2(0.0, -1.0), PI);
    assert_eq!(trig::atan2(1.0, f32::INFINITY), 0.0);
    assert!(trig::atan2(f32::NAN, 1.0).is_nan());
    // hypot: zero, huge and tiny (scaled by libm), ∞.
    assert_eq!(trig::hypot(0.0, -0.0), 0.0);
    assert_eq!(
        trig::hypot(3e30, 4e30),
        <Libm as Math<f32>>::hypot(3e30, 4e30)
    );
    assert_eq!(
        trig::hypot(3e-30, 4e-30),
        <Libm as Math<f32>>::hypot(3e-30, 4e-30)
    );
    assert_eq!(trig::hypot(f32::INFINITY, 1.0), f32::INFINITY);
    // NaN as C99 Annex F (and libm): NaN, unless the other is ±∞. A NaN
    // beside a zero once came out 0 (the larger of |NaN| and 0 was 0).
    for (x, y) in [
        (f32::NAN, 0.0),
        (0.0, f32::NAN),
        (f32::NAN, 1.0),
        (-0.0, f32::NAN),
    ] {
        assert!(trig::hypot(x, y).is_nan(), "hypot({x}, {y})");
    }
    assert_eq!(trig::hypot(f32::NAN, f32::INFINITY), f32::INFINITY);
}

/// μ/μ₀ of the f32 solver with `M` against the f64 solver on the
/// f32-rounded drive and velocity (so only the arithmetic differs), over
/// `n` random stick–slip scenes; returns (worst |Δμ/μ₀|, worst |Δμ/μ₀|/(1 + b)).
fn mu_errors<M: Math<f32>>(n: usize, b_max: f64) -> (f64, f64, usize) {
    let mut rng = Rng::new(2026);
    let (mut worst, mut worst_rel, mut stick_slip) = (0.0f64, 0.0f64, 0);
    for _ in 0..n {
        let a = rng.range(0.0, 0.99) as f32;
        let b = (b_max * rng.uniform().powi(2)) as f32;
        let phi = rng.range(-std::f64::consts::PI, std::f64::consts::PI) as f32;
        let x = rng.range(-1.1, 1.1);
        let d64 = Drive::new::<Libm>(f64::from(a), f64::from(b), f64::from(phi));
        let vc = if x > 0.0 {
            d64.c_forward::<Libm>()
        } else {
            d64.c_backward::<Libm>()
        };
        let v = (x * vc) as f32;
        if v == 0.0 {
            continue;
        }
        let d32 = Drive::new::<M>(a, b, phi);
        let m64 = exact::mu_over_mu0::<f64, Libm>(&d64, f64::from(v)).expect("f64 solves");
        let m32 = exact::mu_over_mu0::<f32, M>(&d32, v).unwrap_or_else(|e| {
            panic!(
                "f32 {} fails: {e:?} at a={a} b={b} phi={phi} v={v}",
                M::NAME
            )
        });
        if m64.abs() < 1.0 {
            stick_slip += 1;
        }
        let err = (f64::from(m32) - m64).abs();
        worst = worst.max(err);
        worst_rel = worst_rel.max(err / (1.0 + f64::from(b)));
        // The solver's own bound for this backend (precision constant 1e-6
        // plus the backend's MAX_REL_ERROR, times 1 + b).
        let bound = f64::from(exact::error_bound::<f32, M>(&d32));
        assert!(
            err <= bound,
            "{}: |Δμ/μ₀| = {err:e} > bound {bound:e} at a={a} b={b} phi={phi} v={v}",
            M::NAME
        );
    }
    (worst, worst_rel, stick_slip)
}

#[test]
fn exact_solver_mu_fast_f32_matches_f64() {
    // 20 000 scenes with a ∈ [0, 0.99), b ∈ [0, 5) (weighted to small b; the
    // README's and the board's scenes have b ≈ 0.25–0.35), φ ∈ [−π, π),
    // v ∈ (−1.1, 1.1)·v_c. Each must meet the solver's bound
    // (1e-6 + 3e-7)·(1 + b) ≤ 7.8e-6 < 1e-5 (the accuracy asked of the f32 build), checked per
    // scene in `mu_errors`.
    let (w_fast, r_fast, n_ss) = mu_errors::<FastF32>(20_000, 5.0);
    let (w_libm, r_libm, _) = mu_errors::<Libm>(20_000, 5.0);
    println!(
        "μ/μ₀ f32 vs f64 over 20000 scenes, b < 5 ({n_ss} stick–slip): fast-f32 worst {w_fast:.3e} \
         ({r_fast:.3e}·(1+b)), libm f32 worst {w_libm:.3e} ({r_libm:.3e}·(1+b))"
    );
    assert!(n_ss > 10_000, "most scenes must be stick–slip, got {n_ss}");
    assert!(w_fast <= 1e-5);
    // The backend's own error (≤ 3e-7 rad, a few f32 ulps) is of the order of
    // the f32 rounding the solver already has with libm: the fast backend may
    // at most double the libm f32 run's worst error (measured: 2.0e-7·(1 + b)
    // for both).
    assert!(
        r_fast <= 2.0 * r_libm,
        "fast-f32 {r_fast:e}·(1+b) vs libm {r_libm:e}·(1+b)"
    );
}

#[test]
fn exact_solver_mu_fast_f32_large_b() {
    // b up to 100: the f32 error grows ∝ 1 + b for both backends (the stretch
    // swings over ±b while μ is decided by differences of order 1); every
    // scene within the solver's bound (checked in `mu_errors`), and the fast
    // backend at most twice libm's worst.
    let (w_fast, r_fast, _) = mu_errors::<FastF32>(5_000, 100.0);
    let (w_libm, r_libm, _) = mu_errors::<Libm>(5_000, 100.0);
    println!(
        "μ/μ₀ f32 vs f64 over 5000 scenes, b < 100: fast-f32 worst {w_fast:.3e} ({r_fast:.3e}·(1+b)), \
         libm f32 worst {w_libm:.3e} ({r_libm:.3e}·(1+b))"
    );
    assert!(r_fast <= 2.0 * r_libm);
}

/// Runs `f` over the bit patterns `lo..=hi` on every available core, in
/// chunks of 2²² patterns handed out in order (the cost per argument differs
/// across the range, so a static split would leave a core idle); the worst
/// of all chunks.
fn exhaustive_run(f: fn(u32, u32, usize) -> (f64, f32), lo: u32, hi: u32) -> (f64, f32) {
    use std::sync::atomic::{AtomicU64, Ordering};
    const CHUNK: u64 = 1 << 22;
    let next = AtomicU64::new(u64::from(lo));
    let threads = std::thread::available_parallelism().map_or(2, |n| n.get());
    std::thread::scope(|sc| {
        let hs: Vec<_> = (0..threads)
            .map(|_| {
                sc.spawn(|| {
                    let mut worst = (0.0f64, 0.0f32);
                    loop {
                        let a = next.fetch_add(CHUNK, Ordering::Relaxed);
                        if a > u64::from(hi) {
                            return worst;
                        }
                        let b = (a + CHUNK - 1).min(u64::from(hi));
                        let e = f(a as u32, b as u32, 1);
                        if e.0 > worst.0 {
                            worst = e;
                        }
                    }
                })
            })
            .collect();
        hs.into_iter()
            .map(|h| h.join().expect("thread"))
            .fold((0.0f64, 0.0f32), |w, e| if e.0 > w.0 { e } else { w })
    })
}

// The proofs of the `trig::ERR_*` bounds: every positive f32 of each range
// (the negative ones are the exact mirror by construction, which
// `dense_sin_cos_within_bound` checks); for atan2 the one-parameter families
// of `atan2_err`. CI runs them (`.ci/run`, "exhaustive f32 proofs") with
// `cargo test -p integration-tests --test trig -- --ignored` (the test
// profile is optimised, opt-level 2: no extra build).

#[test]
#[ignore = "exhaustive: 1.17e9 arguments; CI runs it (.ci/run)"]
fn exhaustive_sin_cos() {
    let (e, x) = exhaustive_run(sin_cos_err, 0, PI4_BITS_HI);
    println!(
        "sin_cos, all {} f32 in [0, 4096]: worst {e:.4e} at {x}",
        PI4_BITS_HI + 1
    );
    assert!(e <= trig::ERR_SIN_COS);
}

#[test]
#[ignore = "exhaustive: 1.07e9 arguments; CI runs it (.ci/run)"]
fn exhaustive_asin() {
    let (e, x) = exhaustive_run(asin_err, 0, ONE_BITS);
    println!(
        "asin, all {} f32 in [0, 1]: worst {e:.4e} at {x}",
        ONE_BITS + 1
    );
    assert!(e <= trig::ERR_ASIN);
}

#[test]
#[ignore = "exhaustive: 4 × 2.14e9 one-parameter pairs; CI runs it (.ci/run)"]
fn exhaustive_atan2() {
    let (e, t) = exhaustive_run(atan2_err, 0, f32::MAX.to_bits());
    println!(
        "atan2, (t, 1), (1, t), (t, −1), (−1, −t) for all {} finite f32 t ≥ 0: worst {e:.4e} at t = {t}",
        f32::MAX.to_bits() + 1
    );
    assert!(e <= trig::ERR_ATAN2);
}

#[test]
#[ignore = "exhaustive: 2.14e9 arguments; CI runs it (.ci/run)"]
fn exhaustive_sqrt() {
    let (e, x) = exhaustive_run(sqrt_err, 0, f32::MAX.to_bits());
    println!(
        "sqrt, all {} finite f32 ≥ 0: worst {e:.4e} relative at {x}",
        f32::MAX.to_bits() + 1
    );
    assert!(e <= trig::ERR_SQRT);
}

mod counting {
    //! A backend that counts calls (FastF32 underneath), to see where the
    //! exact solver's transcendental work goes.
    use super::*;
    use std::sync::atomic::{AtomicU32, Ordering::Relaxed};

    pub static CALLS: [AtomicU32; 5] = [const { AtomicU32::new(0) }; 5];
    pub struct Counting;
    impl Math<f32> for Counting {
        const NAME: &'static str = "counting";
        const MAX_REL_ERROR: f64 = <FastF32 as Math<f32>>::MAX_REL_ERROR;
        fn sqrt(x: f32) -> f32 {
            CALLS[0].fetch_add(1, Relaxed);
            trig::sqrt(x)
        }
        fn sin_cos(x: f32) -> (f32, f32) {
            CALLS[1].fetch_add(1, Relaxed);
            trig::sin_cos(x)
        }
        fn asin(x: f32) -> f32 {
            CALLS[2].fetch_add(1, Relaxed);
            trig::asin(x)
        }
        fn atan2(y: f32, x: f32) -> f32 {
            CALLS[3].fetch_add(1, Relaxed);
            trig::atan2(y, x)
        }
        fn hypot(x: f32, y: f32) -> f32 {
            CALLS[4].fetch_add(1, Relaxed);
            trig::hypot(x, y)
        }
    }
}

#[test]
fn calls_per_prediction() {
    // The transcendental calls of one exact-solver μ (stick–slip, the board's
    // scene family: a ∈ [0, 0.99), b < 5): per call, at most 2 asin (forward
    // and backward window) and 1 atan2 (the backward window's phase); the
    // sin_cos calls are the Newton iterations of the ≤ 2 stick→slip roots
    // (bounded by the root finder's 100-iteration cap per root).
    use counting::{Counting, CALLS};
    use std::sync::atomic::Ordering::Relaxed;
    let mut rng = Rng::new(99);
    let n = 2_000;
    let mut max = [0u32; 5];
    let mut sum = [0u32; 5];
    let mut solved = 0;
    for _ in 0..n {
        let d = Drive::new::<Libm>(
            rng.range(0.0, 0.99) as f32,
            (5.0 * rng.uniform().powi(2)) as f32,
            rng.range(-std::f64::consts::PI, std::f64::consts::PI) as f32,
        );
        let v = (rng.range(0.02, 0.98) * f64::from(d.c_forward::<Libm>())) as f32;
        for c in &CALLS {
            c.store(0, Relaxed);
        }
        if exact::mu_over_mu0::<f32, Counting>(&d, v).is_ok() {
            solved += 1;
        }
        for (k, c) in CALLS.iter().enumerate() {
            let c = c.load(Relaxed);
            max[k] = max[k].max(c);
            sum[k] += c;
        }
    }
    let mean = sum.map(|s| s as f64 / n as f64);
    println!(
        "calls per μ (mean / max over {n} stick–slip scenes): sqrt {:.2}/{}, sin_cos {:.2}/{}, asin {:.2}/{}, atan2 {:.2}/{}, hypot {:.2}/{}",
        mean[0], max[0], mean[1], max[1], mean[2], max[2], mean[3], max[3], mean[4], max[4]
    );
    assert_eq!(solved, n);
    assert!(max[2] <= 2 && max[3] <= 1);
    // f32 turns an iterate's trig from the previous one's within 2⁻³ rad (at
    // most 3 times in a row, `exact::period::root`): of the 4.49 evaluations
    // per μ before, 2.02 still call sin_cos (the first guess of each root,
    // and steps beyond the reach); 2.5 leaves a margin, and a root finder
    // that rotated never would sit at 4.49.
    assert!(mean[1] <= 2.5, "sin_cos calls per μ: {:.2}", mean[1]);
}

#[test]
fn same_bits_as_the_target() {
    // The firmware's f32_vectors checks the same digest on the Cortex-M4F.
    let d = trig::digest(4096);
    println!("digest(4096) = {d:#010x}");
    assert_eq!(d, trig::DIGEST_4096);
}

#[test]
fn device_prediction_path_with_fast_f32() {
    // What `device::predict` computes (critical velocities + exact solver on
    // a physical f32 scene), with FastF32 instead of libm: the board's test
    // scene of tests/device.rs and predict_cost, within the 1e-5 that
    // tests/device.rs and the QEMU test require of the device against f64.
    use model_core::analytic::CriticalVelocity;
    use model_core::{Scene, SceneParams};
    let p = |omega: f64, phi: f64| SceneParams {
        mu0: 0.3,
        kz: 1e7,
        kx: 1e7,
        uz0: 4e-6,
        duz: 2e-6,
        dux: 0.3e-6,
        omega,
        phi,
    };
    let (omega, phi) = (std::f64::consts::TAU * 20e3, 0.7);
    let pf = p(omega, phi);
    let s32 = Scene::<f32>::new(SceneParams {
        mu0: pf.mu0 as f32,
        kz: pf.kz as f32,
        kx: pf.kx as f32,
        uz0: pf.uz0 as f32,
        duz: pf.duz as f32,
        dux: pf.dux as f32,
        omega: omega as f32,
        phi: phi as f32,
    })
    .unwrap();
    let s64 = Scene::new(p(omega, phi)).unwrap();
    let vc32 = CriticalVelocity::of_with::<FastF32>(&s32);
    let vc64 = CriticalVelocity::of(&s64);
    assert!((f64::from(vc32.forward) / vc64.forward - 1.0).abs() <= 1e-6);
    assert!((f64::from(vc32.backward) / vc64.backward - 1.0).abs() <= 1e-6);
    for v0 in [-0.02f32, -0.001, 0.001, 0.004, 0.01, 0.05] {
        let m32 = exact::solve_with::<f32, FastF32>(&s32, v0)
            .unwrap()
            .mu_over_mu0()
            .unwrap();
        let m64 = exact::solve(&s64, f64::from(v0))
            .unwrap()
            .mu_over_mu0()
            .unwrap();
        assert!(
            (f64::from(m32) - m64).abs() <= 1e-5,
            "v0={v0}: {m32} vs {m64}"
        );
    }
}

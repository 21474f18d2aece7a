//! The friction estimator on synthetic forces with a known μ (noise, DC
//! offsets, a non-integer number of samples per period) and on forces
//! produced by the model itself.

use std::f64::consts::TAU;

use board::dds::{phase_rad, SineTable};
use board::estimator::{Calibration, EstimateError, Estimator};
use integration_tests::Rng;
use model_core::fixed_step::Stepper;
use model_core::{exact, Drive, Libm};

const FULL: u16 = 4095;

/// Feeds `(x, z)` count functions of the drive phase at tuning word `tw`
/// until the window closes; returns the estimate.
fn run(
    est: &mut Estimator,
    table: &SineTable<1024>,
    tw: u32,
    periods: u32,
    f: impl FnMut(f64) -> (u16, u16),
) -> board::estimator::Estimate {
    run_from(est, table, tw, periods, 12345, f)
}

/// As [`run`], with the accumulator starting at `acc0`.
fn run_from(
    est: &mut Estimator,
    table: &SineTable<1024>,
    tw: u32,
    periods: u32,
    acc0: u32,
    mut f: impl FnMut(f64) -> (u16, u16),
) -> board::estimator::Estimate {
    est.start(periods).unwrap();
    let mut acc: u32 = acc0;
    for _ in 0..(periods as u64 + 3) * (4_294_967_296 / tw as u64 + 2) {
        let (x, z) = f(phase_rad(acc));
        if est.push(table, acc, x, z) {
            return est.estimate().unwrap();
        }
        acc = acc.wrapping_add(tw);
    }
    panic!("window did not close");
}

#[test]
fn known_mu_with_noise_offsets_and_non_integer_period() {
    let table = SineTable::<1024>::libm();
    // Calibrations: 0.01 N/count (x) with 300 counts offset, 0.02 N/count (z) with 150.
    let cx = Calibration {
        gain: 0.01,
        offset: 300.0,
    };
    let cz = Calibration {
        gain: 0.02,
        offset: 150.0,
    };
    let mut est = Estimator::new(cx, cz, FULL).unwrap();
    // f_s/f = 25.0013…: not an integer number of samples per period.
    let tw = (4_294_967_296.0 / 25.0013) as u32;
    let mut rng = Rng::new(1);
    let (fz0, fz1, mu, fx1, phx) = (30.0, 12.0, 0.27, 5.0, 0.8);
    let r = run(&mut est, &table, tw, 2000, |th| {
        let noise = |rng: &mut Rng| 3.0 * (rng.uniform() - 0.5); // ±1.5 counts
        let fz = fz0 - fz1 * th.cos();
        let fx = mu * fz0 + fx1 * (th + phx).cos();
        let z = fz / 0.02 + 150.0 + noise(&mut rng);
        let x = fx / 0.01 + 300.0 + noise(&mut rng);
        (x.round() as u16, z.round() as u16)
    });
    // One sample of window error in ≈ 50 000, noise and rounding: ≤ 1e-3 relative.
    assert!((f64::from(r.mu) - mu).abs() <= 1e-3 * mu, "{r:?}");
    assert!((f64::from(r.fz_mean) - fz0).abs() <= 1e-3 * fz0);
    assert!(
        (f64::from(r.fz_h1.amplitude) - fz1).abs() <= 5e-3 * fz1,
        "{r:?}"
    );
    // −12 cos θ = 12 cos(θ + π).
    assert!(
        (f64::from(r.fz_h1.phase).abs() - std::f64::consts::PI).abs() <= 2e-3,
        "{r:?}"
    );
    assert!((f64::from(r.fx_h1.amplitude) - fx1).abs() <= 5e-3 * fx1);
    assert!((f64::from(r.fx_h1.phase) - phx).abs() <= 2e-3);
    assert_eq!(r.periods, 2000);
    let per = 25.0013 * 2000.0;
    assert!((f64::from(r.samples) - per).abs() <= 1.0, "{}", r.samples);
    assert!(!r.saturated);
}

#[test]
fn saturation_and_refusals() {
    let table = SineTable::<1024>::libm();
    let c = Calibration {
        gain: 1.0,
        offset: 0.0,
    };
    let mut est = Estimator::new(c, c, FULL).unwrap();
    assert_eq!(est.estimate(), Err(EstimateError::NotReady));
    assert_eq!(est.start(0), Err(EstimateError::BadConfig));
    let r = run(&mut est, &table, 1 << 27, 4, |th| {
        (if th < 0.1 { 4095 } else { 100 }, 2000)
    });
    assert!(r.saturated);
    let mut est = Estimator::new(c, c, FULL).unwrap();
    est.start(2).unwrap();
    let mut acc = 0u32;
    loop {
        if est.push(&table, acc, 100, 0) {
            break;
        }
        acc = acc.wrapping_add(1 << 26);
    }
    assert_eq!(est.estimate(), Err(EstimateError::NoNormalForce));
    assert_eq!(
        Estimator::new(
            Calibration {
                gain: 0.0,
                offset: 0.0
            },
            c,
            FULL
        )
        .err(),
        Some(EstimateError::BadConfig)
    );
    assert_eq!(
        Estimator::new(
            Calibration {
                gain: f32::NAN,
                offset: 0.0
            },
            c,
            FULL
        )
        .err(),
        Some(EstimateError::BadConfig)
    );
}

#[test]
fn estimate_of_model_forces_matches_the_exact_solver() {
    // The plant: the model's own forces at an ADC rate of ≈ 1000.37 samples per
    // period, digitised to 12 bits, measured by the estimator; compared with the
    // exact steady-state μ.
    let table = SineTable::<1024>::libm();
    for &(a, b, phi, x) in &[
        (0.5, 0.25, 1.0, 0.3),
        (0.5, 1.0, 0.3, -0.4),
        (0.3, 0.0, 0.0, 0.6),
    ] {
        let d = Drive::new::<Libm>(a, b, phi);
        let c = if x > 0.0 {
            d.c_forward::<Libm>()
        } else {
            d.c_backward::<Libm>()
        };
        let v = x * c;
        let mu_exact = exact::mu_over_mu0::<f64, Libm>(&d, v).unwrap();
        let tw = (4_294_967_296.0 / 1000.37) as u32;
        let delta = TAU * f64::from(tw) / 4_294_967_296.0;
        let mut plant = Stepper::<f64>::new::<Libm>(d, v, 0.0, 0.0, delta);
        // Settle for 50 periods.
        for _ in 0..50_000 {
            plant.step();
        }
        // Forces in counts: f_z = k_z u_z0 · w with k_z u_z0 = 10 N at 0.01 N/count;
        // f_x = μ0 k_z u_z0 · s with μ0 = 1, offset 2048 counts.
        let cz = Calibration {
            gain: 0.01,
            offset: 0.0,
        };
        let cx = Calibration {
            gain: 0.01,
            offset: 2048.0,
        };
        let mut est = Estimator::new(cx, cz, FULL).unwrap();
        // The estimator's phase must be the plant's: the plant started at θ = 0
        // and has advanced 50 000 steps.
        let acc0 = 50_000u32.wrapping_mul(tw);
        est.start(200).unwrap();
        let mut acc = acc0;
        let r = loop {
            let (_, s, w) = plant.step();
            acc = acc.wrapping_add(tw);
            let z = (w * 1000.0).round() as u16;
            let xr = (s * 1000.0 + 2048.0).round() as u16;
            if est.push(&table, acc, xr, z) {
                break est.estimate().unwrap();
            }
        };
        // Scheme error at ~1000 steps/period (≲ 1e-6 · a few) plus 12-bit rounding
        // averaged over 2·10⁵ samples: 2e-4.
        assert!(
            (f64::from(r.mu) - mu_exact).abs() <= 2e-4,
            "a={a} b={b}: {} vs {mu_exact}",
            r.mu
        );
    }
}

/// A standard normal deviate (Box–Muller) from the test PRNG.
fn gauss(rng: &mut Rng) -> f64 {
    let u1 = rng.uniform().max(1e-300);
    let u2 = rng.uniform();
    (-2.0 * u1.ln()).sqrt() * (TAU * u2).cos()
}

#[test]
fn std_error_matches_the_closed_form_for_white_noise() {
    use board::estimator::{reasons, BATCHES};
    // 64 samples per period exactly (tw = 2^26), 320 periods: 32 batches of 10
    // periods, N = 20 480 samples. f_z = 0.02 N/count · 2000 counts (+ a
    // harmonic, no noise); f_x = 0.01 N/count · (2048 + 300 cos(θ + 0.4) + g),
    // g white Gaussian with σ_c = 8 counts, then rounded to counts.
    let table = SineTable::<1024>::libm();
    let cx = Calibration {
        gain: 0.01,
        offset: 2048.0,
    };
    let cz = Calibration {
        gain: 0.02,
        offset: 0.0,
    };
    let (periods, sigma_c) = (320u32, 8.0);
    let n = f64::from(periods) * 64.0;
    // Closed form (estimator docs): σ_μ → σ_fx/(f̄_z √N), where the rounded
    // noise has variance σ_c² + 1/12 counts² (Sheppard; exact to e^(−2π²σ_c²)).
    // With equal batches and a noiseless f_z, E[σ_μ²] equals it exactly.
    let fz_mean = 0.02 * 2000.0;
    let sigma_fx = 0.01 * (sigma_c * sigma_c + 1.0 / 12.0_f64).sqrt();
    let expected = sigma_fx / (fz_mean * n.sqrt());
    let runs = 40;
    let mut sum_sq = 0.0;
    for seed in 1..=runs {
        let mut rng = Rng::new(seed);
        let mut est = Estimator::new(cx, cz, FULL).unwrap();
        let r = run(&mut est, &table, 1 << 26, periods, |th| {
            let x = 2048.0 + 300.0 * (th + 0.4).cos() + sigma_c * gauss(&mut rng);
            let z = 2000.0 - 500.0 * th.cos();
            (x.round() as u16, z.round() as u16)
        });
        assert_eq!(r.samples as f64, n);
        assert_eq!(r.reasons, 0, "{r:?}");
        let se = f64::from(r.std_error);
        // One run: σ_μ from B − 1 = 31 degrees of freedom has a relative
        // spread of 1/√(2·31) = 0.127; 0.55 is 4.3 of those.
        assert!(
            (se / expected - 1.0).abs() <= 0.55,
            "seed {seed}: {se} vs {expected}"
        );
        sum_sq += se * se;
    }
    println!(
        "mean σ_μ²/closed form = {}",
        sum_sq / f64::from(runs as u32) / (expected * expected)
    );
    // Mean of σ_μ² over 40 runs: relative spread √(2/31)/√40 = 0.040; allow 4×.
    let ratio = sum_sq / f64::from(runs as u32) / (expected * expected);
    assert!(
        (ratio - 1.0).abs() <= 0.16,
        "mean σ_μ²/closed form = {ratio}"
    );
    assert_eq!(BATCHES, 32);
    // Fewer periods than batches: flagged, and the error still from the batches there are.
    let mut est = Estimator::new(cx, cz, FULL).unwrap();
    let mut rng = Rng::new(99);
    let r = run(&mut est, &table, 1 << 26, 8, |_| {
        ((2048.0 + sigma_c * gauss(&mut rng)).round() as u16, 2000)
    });
    assert_eq!(r.reasons, reasons::FEW_PERIODS);
    assert!(!r.valid());
    assert!(r.std_error > 0.0);
}

/// Short windows at a non-integer number of samples per period: the
/// fractional edges (module docs of `board::estimator`) make the
/// window exactly `P` periods long.
///
/// **The bound.** For a force `B·cos(θ + c)` the weighted sum over the
/// window `[a, a + P·T)` (sample time, `T = f_s/f` samples per period, the
/// boundaries `ε₀`, `ε_e` of a sample before the wraps) is, in closed form,
/// `z·I(ε₀, ε_e, ω)`, `|z| = B`, with `ω = 2π/T` and
///
/// `I = ε₀e^{jω(ε₀−1)} + (e^{jω(ε_e−1)} − e^{jωε₀})/(e^{jω} − 1) + (1 − ε_e)e^{jω(ε_e−1)}`
///
/// whose series is `I = (jω/2)·(ε₀(ε₀ − 1) − ε_e(ε_e − 1)) + ω²·p/12 + O(ω³)`
/// with `|p| ≤ 0.82` on `[0, 1]²`, so `|I| ≤ ω/8 + ω²/4` (the first
/// term is at most `1/4·ω/2`; `ω²/4` covers the second, `0.07·ω²`, with room
/// for the rest at `ω ≤ 0.52`). The mean of the force is off by at most
/// `B·(ω/8 + ω²/4)/(P·T)`, plus 0.5 count of rounding. Without the edges
/// (whole samples) it is off by up to `B/(P·T)` (a missing or extra sample
/// at the wrap, where `cos` is largest): `1/(ω/8 + ω²/4)` = 8 to 40 times
/// the bound's first part at these rates. 450 windows from random phases.
#[test]
fn short_windows_span_exact_periods_at_non_integer_samples_per_period() {
    let table = SineTable::<1024>::libm();
    let unit = Calibration {
        gain: 1.0,
        offset: 0.0,
    };
    let mut rng = Rng::new(7);
    // Counts: f_z = 2000 + 1000 cos θ, f_x = 500 + 400 cos(θ + 0.3).
    let (z0, za, x0, xa) = (2000.0, 1000.0, 500.0, 400.0);
    let mut worst = 0.0f64;
    for spp in [24.876_f64, 12.34, 40.7] {
        let tw = (4_294_967_296.0 / spp) as u32;
        let t = 4_294_967_296.0 / f64::from(tw);
        let w = TAU / t;
        for periods in [1u32, 2, 4] {
            let p = f64::from(periods);
            let e = |b: f64| b * (w / 8.0 + w * w / 4.0) / (p * t) + 0.5;
            let (ex, ez) = (e(xa), e(za));
            let mu_true = x0 / z0;
            // μ = (x0 + δx)/(z0 + δz): |μ − x0/z0| ≤ (ex + μ·ez)/(z0 − ez).
            let bound = (ex + mu_true * ez) / (z0 - ez);
            for _ in 0..50 {
                let mut est = Estimator::new(unit, unit, FULL).unwrap();
                let acc0 = (rng.uniform() * 4_294_967_296.0) as u32;
                let r = run_from(&mut est, &table, tw, periods, acc0, |th| {
                    let z = (z0 + za * th.cos()).round() as u16;
                    let x = (x0 + xa * (th + 0.3).cos()).round() as u16;
                    (x, z)
                });
                let err = (f64::from(r.mu) - mu_true).abs();
                worst = worst.max(err / bound);
                assert!(
                    err <= bound,
                    "{spp} samples/period, {periods} periods: mu {} vs {mu_true}, bound {bound:.2e}",
                    r.mu
                );
                // The edges do not change the whole samples counted.
                assert!((f64::from(r.samples) - p * t).abs() <= 1.0);
            }
        }
    }
    println!("largest error / bound: {worst:.3}");
}

/// μ from the window's integer sums without f64 (eq. E2: each sum taken
/// about an integer near its offset, exactly, before any rounding): a
/// constant force, whose exact means are its counts whatever the window's
/// fractional edges, against μ = g_x(c_x − o_x)/(g_z(c_z − o_z)) in f64 —
/// with the tangential count 0.7 above its offset (the cancellation a mean
/// formed in f32 first would lose: 2048·2⁻²⁴/0.7 ≈ 1.7e-4 relative) and
/// windows long enough that the raw sums pass 2²⁴ (f32's exact integers).
/// The bound: D, e₁ − e₀·k and the quotient each rounded once in f32, so δ
/// is within (|D| + 2·(|e₁| + |e₀ k|))·2⁻²³/W + |δ|·2⁻²², which carries to
/// μ relatively through each signal's δ − (o − k) (the difference of an
/// f32 and an integer near it, exact), and four roundings more.
#[test]
fn mu_from_integer_sums_keeps_a_small_force_exact() {
    let table = SineTable::<1024>::libm();
    let tw = (4_294_967_296.0 / 25.0013) as u32;
    for (periods, cx, cz, ox, oz) in [
        (2_000u32, 2048u16, 3000u16, 2047.3f32, 150.25f32),
        (20_000, 2048, 3000, 2047.3, 150.25),
        (1, 301, 4000, 300.5, 2.0),
        (500, 4094, 2049, 100.0, 2048.9),
        // Below the integer k = 300: δ < 0, μ < 0.
        (300, 299, 3000, 300.5, 150.25),
    ] {
        let (gx, gz) = (0.01f32, 0.02f32);
        let mut est = Estimator::new(
            Calibration {
                gain: gx,
                offset: ox,
            },
            Calibration {
                gain: gz,
                offset: oz,
            },
            FULL,
        )
        .unwrap();
        let r = run(&mut est, &table, tw, periods, |_| (cx, cz));
        let exact = f64::from(gx) * (f64::from(cx) - f64::from(ox))
            / (f64::from(gz) * (f64::from(cz) - f64::from(oz)));
        // W ≥ samples; |e₁| ≤ 2·4095, |e₀ k| ≤ 2·4095 (two edges of weight < 1).
        let w = f64::from(r.samples);
        let rel = |c: f64, o: f64| {
            let delta = c - o.trunc();
            let d = w * delta.abs();
            let err = (d + 4.0 * 4095.0) * 2f64.powi(-23) / w + delta.abs() * 2f64.powi(-22);
            err / (c - o).abs()
        };
        let bound = exact.abs()
            * (rel(f64::from(cx), f64::from(ox))
                + rel(f64::from(cz), f64::from(oz))
                + 4.0 * 2f64.powi(-24));
        let err = (f64::from(r.mu) - exact).abs();
        eprintln!(
            "periods {periods}: mu {} vs {exact}, error {err:.2e} of bound {bound:.2e}",
            r.mu
        );
        assert!(
            err <= bound,
            "periods {periods}: {} vs {exact} ({bound})",
            r.mu
        );
        // A constant force: every batch the same, the standard error 0 to
        // f32's rounding of the residuals.
        assert!(f64::from(r.std_error) <= 1e-6 * exact.abs(), "{r:?}");
    }
}

/// The calibrations of the standard-error tests: x about mid-scale (offset
/// 2047.5 counts, 0.01 N/count), z with a large normal force (offset 100,
/// 0.02 N/count).
fn batch_calibrations() -> (Calibration, Calibration) {
    (
        Calibration {
            gain: 0.01,
            offset: 2047.5,
        },
        Calibration {
            gain: 0.02,
            offset: 100.0,
        },
    )
}

/// The standard error against its definition (estimator docs, eq. E1),
/// computed here in f64 from the samples fed: 64 samples per period exactly
/// (no fractional edges), 320 periods in 32 batches of 10, the counts
/// `2048 + d_b` (tangential) and `2000 + e_b` (normal) constant within
/// batch `b` (d_b from −5 to 5, e_b from −3 to 3): `σ_μ = √(B/(B−1)·Σ
/// r_b²)/|Z|` with `r_b = 640·(g_x·(d_b − d̄) − μ·g_z·(e_b − ē))` and `Z =
/// W·⟨f_z⟩`. The estimator's residuals are exact
/// integers in Q16 and its sums of 32 squares in f32: within 1e-5 relative.
/// (Without the B/(B−1) factor the value is 1.6 % low.)
#[test]
fn the_std_error_is_its_definition_on_batches_known_exactly() {
    use board::estimator::BATCHES;
    let table = SineTable::<1024>::libm();
    let (cx, cz) = batch_calibrations();
    let mut est = Estimator::new(cx, cz, FULL).unwrap();
    let d = |b: usize| ((b * 7) % 11) as f64 - 5.0;
    let e = |b: usize| ((b * 3) % 7) as f64 - 3.0;
    let periods = 320u32;
    let per_batch = 64 * periods as usize / BATCHES;
    // The window opens at the first wrap after the start at phase 0: sample 64.
    let mut i = 0usize;
    let r = run_from(&mut est, &table, 1 << 26, periods, 0, |_| {
        let b = (i.saturating_sub(64) / per_batch).min(BATCHES - 1);
        i += 1;
        ((2048.0 + d(b)) as u16, (2000.0 + e(b)) as u16)
    });
    let w = 64.0 * f64::from(periods);
    assert_eq!(f64::from(r.samples), w);
    let mean_d = (0..BATCHES).map(d).sum::<f64>() / BATCHES as f64;
    let mean_e = (0..BATCHES).map(e).sum::<f64>() / BATCHES as f64;
    let (gx, gz) = (f64::from(cx.gain), f64::from(cz.gain));
    let fz = gz * (2000.0 + mean_e - f64::from(cz.offset));
    let mu = gx * (2048.0 + mean_d - f64::from(cx.offset)) / fz;
    let sum_sq: f64 = (0..BATCHES)
        .map(|b| (per_batch as f64 * (gx * (d(b) - mean_d) - mu * gz * (e(b) - mean_e))).powi(2))
        .sum();
    let bb = BATCHES as f64;
    let want = (bb / (bb - 1.0) * sum_sq).sqrt() / (w * fz);
    assert!(
        (f64::from(r.mu) / mu - 1.0).abs() <= 1e-6,
        "{} vs {mu}",
        r.mu
    );
    let got = f64::from(r.std_error);
    assert!((got / want - 1.0).abs() <= 1e-5, "σ_μ {got} vs {want}");
}

/// The standard error and μ against their definitions (estimator docs) on
/// a window whose periods are not whole samples (`f_s/f` = 24.9013…), so
/// that the window's two edge samples and the sample before each inner
/// wrap are split between batches: each sample `s` stands for `[s, s + 1)`,
/// wrap `j` is at `t_j = (j·2³² − a₀)/tw` samples, the window spans
/// `[t₁, t_{P+1}]`, period `k` goes to batch `⌊k·B/P⌋` with `B = min(32,
/// P)`, and a sample's weight in a batch is the length of its interval
/// inside the batch's time — all formed here in f64 from those rules, not
/// from the estimator's sums. The counts are levels that step every 40
/// samples plus a ripple from sample to sample, so the batches' residuals
/// `r_b = X_b − μZ_b` differ. P = 2, 3, 5 (fewer batches than [`BATCHES`]:
/// the empty ones must not count, and two batches are the fewest with a
/// σ_μ) and 40; P = 1 gives σ_μ = 0.
///
/// Tolerance on σ_μ, relative: 2·10⁻⁴. σ_μ is `√(B/(B−1))·‖r‖/|Z|`, so an
/// error `Δ` in the residuals moves it by at most `‖Δ‖/‖r‖ ≤ max|Δ_b| /
/// rms(r_b)`. Each residual carries the means' Q16 rounding (`W_b·2⁻¹⁷`
/// counts, ≤ 0.002 for 250 samples) and the f32 edge sums (`≈ 2048·2⁻²⁴`
/// counts per edge, three per batch): ≤ 0.003 counts, against an rms of
/// ≥ 30 counts here (printed): 10⁻⁴; the f32 sum of squares and its root
/// add ~10⁻⁶. An edge term dropped or with its sign flipped moves a
/// residual by `(count − mean)·ε` or `2·mean·ε` counts, and an empty batch
/// counted changes `B/(B − 1)` (by 4 % at P = 5 with 32): each far outside.
/// The two forces' first harmonics are checked against their definition on
/// the same samples (bound in the body).
#[test]
fn the_std_error_is_its_definition_on_fractional_edges_and_few_batches() {
    use board::estimator::BATCHES;
    let table = SineTable::<1024>::libm();
    let (cx, cz) = batch_calibrations();
    let tw = (4_294_967_296.0 / 24.9013) as u32;
    let acc0 = 12_345u32;
    // A level that steps every 40 samples, and a ripple from sample to sample.
    let x_of = |s: usize| 2048.0 + ((s / 40 * 7) % 13) as f64 - 6.0 + ((s * 37) % 11) as f64 - 5.0;
    let z_of = |s: usize| 2000.0 + ((s / 40 * 5) % 9) as f64 - 4.0 + ((s * 13) % 7) as f64 - 3.0;
    let (gx, gz) = (f64::from(cx.gain), f64::from(cz.gain));
    for periods in [1u32, 2, 3, 5, 40] {
        let mut est = Estimator::new(cx, cz, FULL).unwrap();
        let mut s = 0usize;
        let r = run_from(&mut est, &table, tw, periods, acc0, |_| {
            let c = (x_of(s) as u16, z_of(s) as u16);
            s += 1;
            c
        });
        // The definitions, in f64.
        let p = periods as usize;
        let b_count = p.min(BATCHES);
        let t = |j: usize| (j as f64 * 4_294_967_296.0 - f64::from(acc0)) / f64::from(tw);
        let mut xb = vec![0.0f64; b_count];
        let mut zb = vec![0.0f64; b_count];
        // The harmonics' sums Σ w·count·(cos θ, sin θ) of each force, and
        // Σ w·count for their bound.
        let (mut hx, mut hz, mut mass) = ([0.0f64; 2], [0.0f64; 2], 0.0f64);
        for k in 0..p {
            let b = k * b_count / p;
            let (t0, t1) = (t(1 + k), t(2 + k));
            for smp in (t0.floor() as usize)..=(t1.floor() as usize) {
                let w = (t1.min(smp as f64 + 1.0) - t0.max(smp as f64)).max(0.0);
                xb[b] += w * gx * (x_of(smp) - f64::from(cx.offset));
                zb[b] += w * gz * (z_of(smp) - f64::from(cz.offset));
                let acc = acc0.wrapping_add(tw.wrapping_mul(smp as u32));
                let th = TAU * f64::from(acc) / 4_294_967_296.0;
                hx[0] += w * x_of(smp) * th.cos();
                hx[1] += w * x_of(smp) * th.sin();
                hz[0] += w * z_of(smp) * th.cos();
                hz[1] += w * z_of(smp) * th.sin();
                mass += w * (x_of(smp) + z_of(smp));
            }
        }
        // The harmonics (estimator docs): `re = 2g/W·Σ w·count·cos θ`, `im =
        // −2g/W·Σ w·count·sin θ`, W the window's length in samples. The
        // estimator's reference words are each within ε_r ≤ 7·10⁻⁵ (eq. R2)
        // of cos θ and sin θ: its sums are within Σ w·count·ε_r of these,
        // plus f32's rounding of the edges and the result (10⁻⁶ of them).
        // A wrong edge term moves them by ≈ w·count ~ 10³ counts.
        let w_len = t(1 + p) - t(1);
        for (h, sums, g, what) in [(r.fx_h1, hx, gx, "f_x"), (r.fz_h1, hz, gz, "f_z")] {
            let k = 2.0 * g / w_len;
            let (re, im) = (k * sums[0], -k * sums[1]);
            let (a, ph) = (f64::from(h.amplitude), f64::from(h.phase));
            let err = (a * ph.cos() - re).hypot(a * ph.sin() - im);
            let bound = k * mass * 7e-5 + 1e-6 * (re.hypot(im) + k * mass);
            assert!(
                err <= bound,
                "P = {periods}: {what}'s harmonic ({}, {}) vs ({re}, {im}): off by {err:e} > {bound:e}",
                a * ph.cos(),
                a * ph.sin()
            );
        }
        let (x, z): (f64, f64) = (xb.iter().sum(), zb.iter().sum());
        let mu = x / z;
        let sum_sq: f64 = (0..b_count)
            .map(|b| {
                let r = xb[b] - mu * zb[b];
                r * r
            })
            .sum();
        let want = if b_count < 2 {
            0.0
        } else {
            let bb = b_count as f64;
            (bb / (bb - 1.0) * sum_sq).sqrt() / z.abs()
        };
        let rms = (sum_sq / b_count as f64).sqrt() / gx;
        println!(
            "P = {periods}: σ_μ {} vs {want:e}, residuals' rms {rms:.1} counts",
            r.std_error
        );
        if b_count >= 2 {
            assert!(rms >= 30.0, "the test's own premise: rms {rms}");
        }
        assert_eq!(r.periods, periods);
        assert!(
            (t(1 + p) - t(1) - f64::from(r.samples)).abs() <= 1.0,
            "{r:?}"
        );
        assert!(
            (f64::from(r.mu) / mu - 1.0).abs() <= 1e-6,
            "P = {periods}: μ {} vs {mu}",
            r.mu
        );
        let got = f64::from(r.std_error);
        if want == 0.0 {
            assert_eq!(got, 0.0, "P = {periods}");
        } else {
            assert!(
                (got / want - 1.0).abs() <= 2e-4,
                "P = {periods}: σ_μ {got} vs {want}"
            );
        }
    }
}

//! The lock-in on the DDS reference (`board::lockin`): exact
//! recovery of mean, amplitude and phase over windows of any length (the
//! case the textbook `2/N Σ` lock-in gets wrong by its 2θ leak, measured
//! here too), noise within its least-squares standard error, and refusal
//! of windows too short to separate the terms.

use std::f64::consts::TAU;

use board::lockin::{LockIn, LockInError, MIN_SPAN_RAD};
use model_core::Libm;

/// Samples of d + A cos(θ + ψ) at θ_i = θ0 + i·dθ, into a lock-in.
fn window(n: usize, dtheta: f64, theta0: f64, d: f64, amp: f64, psi: f64) -> LockIn<f64, 1> {
    let mut l = LockIn::new();
    for i in 0..n {
        let th = theta0 + i as f64 * dtheta;
        let p = d + amp * (th + psi).cos();
        l.push(th.cos(), th.sin(), if i == 0 { 0.0 } else { dtheta }, [p]);
    }
    l
}

#[test]
fn fit_is_exact_over_windows_of_any_length() {
    // The board's half-buffer: 64 samples at 500 kS/s; drives from 5 to
    // 90 kHz (0.64 to 11.5 periods, never whole), mean 2000 counts,
    // amplitude 300 counts, phases all round.
    let mut worst_fit: f64 = 0.0;
    let mut worst_naive: f64 = 0.0;
    for f in [5e3, 12.3e3, 20e3, 33.3e3, 40e3, 61e3, 90e3] {
        let dth = TAU * f / 500e3;
        for k in 0..12 {
            let psi = -3.0 + 0.5 * k as f64;
            let theta0 = 0.37 * k as f64;
            let l = window(64, dth, theta0, 2000.0, 300.0, psi);
            let [ph] = l.solve().unwrap();
            let amp = ph.amplitude::<Libm>();
            let dpsi = (ph.phase::<Libm>() - psi + 3.0 * TAU / 2.0).rem_euclid(TAU) - TAU / 2.0;
            // Rounding only: sums of 64 terms of size ≤ 2300 (f64), a 2×2
            // solve whose condition number over ≥ 0.64 periods is < 10:
            // a relative error ≤ 64·2300/300·ε·10 ≈ 1e-12.
            worst_fit = worst_fit.max((amp / 300.0 - 1.0).abs()).max(dpsi.abs());
            assert!((ph.mean - 2000.0).abs() <= 1e-9, "{f} {k}: {ph:?}");
            // The textbook lock-in over the same window, for comparison.
            let (mut c, mut s) = (0.0, 0.0);
            for i in 0..64 {
                let th = theta0 + i as f64 * dth;
                let p = 2000.0 + 300.0 * (th + psi).cos();
                c += p * th.cos();
                s += p * th.sin();
            }
            let naive = 2.0 * (c * c + s * s).sqrt() / 64.0;
            worst_naive = worst_naive.max((naive / 300.0 - 1.0).abs());
        }
    }
    assert!(worst_fit <= 1e-12, "fit: {worst_fit:e}");
    // The textbook lock-in is off by percent to many times the amplitude
    // (the DC leaks in too over a non-whole window): the fit is not a
    // cosmetic change.
    assert!(worst_naive > 0.05, "naive: {worst_naive:e}");
}

#[test]
fn noise_stays_within_the_least_squares_standard_error() {
    // White noise σ = 2 counts on a 20 kHz signal, 64 samples: the LS
    // standard error of a (and b) is ≈ σ·√(2/N) = 0.354 counts. Over 2000
    // windows the RMS error of the amplitude must be within 10 % of it
    // (the χ² spread of 2000 draws: ±3.2 % at 2σ; the regressors over 2.56
    // periods are orthogonal to O(1/N)), and of the phase within
    // 10 % of σ_a/A.
    let mut state = 0x2545_F491_4F6C_DD1Du64;
    let mut gauss = || {
        let mut u = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            ((state >> 11) as f64 + 0.5) / (1u64 << 53) as f64
        };
        let (u1, u2) = (u(), u());
        (-2.0 * u1.ln()).sqrt() * (TAU * u2).cos()
    };
    let (sigma, amp, n) = (2.0, 300.0, 64usize);
    let dth = TAU * 20e3 / 500e3;
    let (mut e_amp, mut e_phase) = (0.0, 0.0);
    let windows = 2000;
    for w in 0..windows {
        let psi = 0.001 * w as f64;
        let mut l = LockIn::<f64, 1>::new();
        for i in 0..n {
            let th = 0.1 * w as f64 + i as f64 * dth;
            let p = 2000.0 + amp * (th + psi).cos() + sigma * gauss();
            l.push(th.cos(), th.sin(), if i == 0 { 0.0 } else { dth }, [p]);
        }
        let [ph] = l.solve().unwrap();
        e_amp += (ph.amplitude::<Libm>() - amp).powi(2);
        let d = (ph.phase::<Libm>() - psi + 3.0 * TAU / 2.0).rem_euclid(TAU) - TAU / 2.0;
        e_phase += d * d;
    }
    let se = sigma * (2.0 / n as f64).sqrt();
    let rms_amp = (e_amp / windows as f64).sqrt();
    let rms_phase = (e_phase / windows as f64).sqrt();
    assert!(
        (rms_amp / se - 1.0).abs() < 0.1,
        "amp rms {rms_amp} vs {se}"
    );
    assert!(
        (rms_phase / (se / amp) - 1.0).abs() < 0.1,
        "phase rms {rms_phase} vs {}",
        se / amp
    );
}

#[test]
fn too_short_windows_are_refused() {
    let l = window(2, 0.5, 0.0, 1.0, 1.0, 0.0);
    assert_eq!(l.solve(), Err(LockInError::TooFewSamples));
    // 64 samples of a 1 kHz drive span 0.13 periods (46°) < a quarter period.
    let dth = TAU * 1e3 / 500e3;
    let l = window(64, dth, 0.0, 1.0, 1.0, 0.0);
    assert!(l.span_rad() < MIN_SPAN_RAD);
    assert_eq!(l.solve(), Err(LockInError::ShortWindow));
    // Eight such windows accumulated (368°) are long enough.
    let l = window(8 * 64, dth, 0.0, 1.0, 1.0, 0.3);
    let [ph] = l.solve().unwrap();
    assert!((ph.amplitude::<Libm>() - 1.0).abs() < 1e-9);
}

//! The lock-in on the DDS reference (`board::lockin`): exact
//! recovery of mean, amplitude and phase over windows of any length (the
//! case the textbook `2/N Σ` lock-in gets wrong by its 2θ leak, measured
//! here too), noise within its least-squares standard error, and refusal
//! of windows too short to separate the terms.

use std::f64::consts::TAU;

use board::dds::SineTable;
use board::lockin::{f32_of, LockIn, LockInError, LockInQ, MAX_Q_SAMPLES, MIN_SPAN_RAD};
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
    // Exactly a quarter period (three samples π/4 apart; the sum is exact):
    // taken, the limit is inclusive — and the fit is exact there too.
    let l = window(3, std::f64::consts::FRAC_PI_4, 0.0, 1.0, 1.0, 0.0);
    assert_eq!(l.span_rad(), MIN_SPAN_RAD);
    let [ph] = l.solve().unwrap();
    assert!((ph.amplitude::<Libm>() - 1.0).abs() <= 1e-12, "{ph:?}");
    // Eight such windows accumulated (368°) are long enough.
    let l = window(8 * 64, dth, 0.0, 1.0, 1.0, 0.3);
    let [ph] = l.solve().unwrap();
    assert!((ph.amplitude::<Libm>() - 1.0).abs() < 1e-9);
}

/// The least-squares fit of `p ≈ d + a cos θ + b sin θ` in f64 with exact
/// cos and sin (the normal equations solved with the inverse by cofactors), its
/// largest residual, and `G = max_j Σ_i |((XᵀX)⁻¹Xᵀ)_ji|`, the gain from a
/// perturbation of the samples to a coefficient.
fn f64_fit(theta: &[f64], p: &[f64]) -> ([f64; 3], f64, f64) {
    let x: Vec<[f64; 3]> = theta.iter().map(|t| [1.0, t.cos(), t.sin()]).collect();
    let m: [[f64; 3]; 3] =
        std::array::from_fn(|i| std::array::from_fn(|j| x.iter().map(|r| r[i] * r[j]).sum()));
    // The inverse of the symmetric 3×3 normal matrix by cofactors (the
    // cyclic form carries the signs): inv = adj/det.
    let cof = |i: usize, j: usize| {
        let (i1, i2, j1, j2) = ((i + 1) % 3, (i + 2) % 3, (j + 1) % 3, (j + 2) % 3);
        m[i1][j1] * m[i2][j2] - m[i1][j2] * m[i2][j1]
    };
    let det: f64 = (0..3).map(|j| m[0][j] * cof(0, j)).sum();
    let inv: [[f64; 3]; 3] = std::array::from_fn(|i| std::array::from_fn(|j| cof(j, i) / det));
    let rows: Vec<[f64; 3]> = x
        .iter()
        .map(|r| {
            let mut out = [0.0; 3];
            for (j, o) in out.iter_mut().enumerate() {
                *o = (0..3).map(|k| inv[j][k] * r[k]).sum();
            }
            out
        })
        .collect();
    let mut coef = [0.0f64; 3];
    for (row, &pi) in rows.iter().zip(p) {
        for j in 0..3 {
            coef[j] += row[j] * pi;
        }
    }
    let g = (0..3)
        .map(|j| rows.iter().map(|r| r[j].abs()).sum::<f64>())
        .fold(0.0, f64::max);
    let resid = x
        .iter()
        .zip(p)
        .map(|(r, &pi)| (pi - coef[0] - coef[1] * r[1] - coef[2] * r[2]).abs())
        .fold(0.0, f64::max);
    (coef, resid, g)
}

/// The condition number κ of the centred 2×2 normal system of the phases
/// `theta`, from its exact sums (f64).
fn centred_condition(theta: &[f64]) -> f64 {
    let n = theta.len() as f64;
    let (mc, ms) = (
        theta.iter().map(|t| t.cos()).sum::<f64>() / n,
        theta.iter().map(|t| t.sin()).sum::<f64>() / n,
    );
    let scc: f64 = theta.iter().map(|t| (t.cos() - mc).powi(2)).sum();
    let sss: f64 = theta.iter().map(|t| (t.sin() - ms).powi(2)).sum();
    let scs: f64 = theta.iter().map(|t| (t.cos() - mc) * (t.sin() - ms)).sum();
    let (tr, det) = (scc + sss, scc * sss - scs * scs);
    let disc = (tr * tr / 4.0 - det).max(0.0).sqrt();
    (tr / 2.0 + disc) / (tr / 2.0 - disc)
}

/// Asserts each coefficient of `ph` (mean, in-phase, quadrature) within
/// `bound` of the f64 fit `coef`; returns the largest error as a share of it.
fn within(ph: &board::lockin::Phasor<f32>, coef: &[f64; 3], bound: f64, label: &str) -> f64 {
    let got = [
        f64::from(ph.mean),
        f64::from(ph.in_phase),
        f64::from(ph.quadrature),
    ];
    let mut worst = 0.0f64;
    for j in 0..3 {
        let e = (got[j] - coef[j]).abs();
        assert!(
            e <= bound,
            "{label}, coef {j}: {} vs {} (bound {bound})",
            got[j],
            coef[j]
        );
        worst = worst.max(e / bound);
    }
    worst
}

/// The integer lock-in (`LockInQ`, eqs. LQ1–LQ3; docs/transducers.md, "The
/// lock-ins in integers") against the f64 fit of the same integer samples
/// with exact cos and sin. The reference errs by at most
/// `ε_r = ε_t + (2π/N)²/8 + 2⁻²⁹ + 2⁻¹⁶` (table, interpolation, Q30 floor,
/// Q15 rounding); to first order the coefficients then move by at most
/// `G·ε_r·(|a| + |b| + max|r|)` (`r` the f64 fit's residuals, `G` its
/// gain), and the f32 solve adds `2⁻²⁰·κ·(|d| + A)` (16 roundings of 2⁻²⁴
/// over the centred 2×2 system of condition `κ`, computed here; windows
/// of at least one period).
#[test]
fn integer_lock_in_is_within_its_derived_bound_of_the_f64_fit() {
    let t = SineTable::<1024>::libm();
    let eps_t = (0..1024)
        .map(|i| (f64::from(t.entry(i)) - (TAU * i as f64 / 1024.0).sin()).abs())
        .fold(0.0, f64::max);
    let eps_r = eps_t + (TAU / 1024.0).powi(2) / 8.0 + 2f64.powi(-29) + 2f64.powi(-16);
    assert!(eps_r < 2.05e-5, "{eps_r}");
    let mut worst = 0.0f64;
    let mut noise = 0x9E37_79B9u32;
    for f in [8e3f64, 12.3e3, 20e3, 20.1e3, 33.3e3, 40e3, 61e3] {
        let tw = (f / 500e3 * 4_294_967_296.0).round() as u32;
        for k in 0..16u32 {
            let (d, amp, psi) = (
                2048.0 + 20.0 * f64::from(k),
                100.0 + 100.0 * f64::from(k),
                -3.0 + 0.4 * f64::from(k),
            );
            let acc0 = k.wrapping_mul(0x1234_5678);
            let mut l = LockInQ::<1>::new();
            let (mut theta, mut p) = (Vec::new(), Vec::new());
            // Whole 64-sample blocks until the window spans a period (the
            // pickups' rule).
            let mut i = 0u32;
            while l.span_words() < 1 << 32 {
                for _ in 0..64 {
                    let w = acc0.wrapping_add(tw.wrapping_mul(i));
                    let th = board::dds::phase_rad(w);
                    noise = noise.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                    let jitter = f64::from(noise >> 8) / f64::from(1u32 << 24) - 0.5;
                    let v = (d + amp * (th + psi).cos() + 2.0 * jitter).round();
                    let (c, s) = LockInQ::<1>::reference(&t, w);
                    l.push(c, s, tw, [v as u16]);
                    theta.push(th);
                    p.push(v);
                    i += 1;
                }
            }
            let [ph] = l.solve().unwrap();
            let (coef, resid, g) = f64_fit(&theta, &p);
            let kappa = centred_condition(&theta);
            let a_f = coef[1].abs() + coef[2].abs();
            let bound_ab = g * eps_r * (a_f + resid) + 2f64.powi(-20) * kappa * (coef[0] + a_f);
            let label = format!("{f} Hz, case {k}");
            worst = worst.max(within(&ph, &coef, bound_ab, &label));
        }
    }
    // The bound is not loose by orders of magnitude.
    assert!(worst > 0.01, "worst {worst} of the bound");
}

/// The board's pickup path (issue 35): the pickups summed against the
/// forces' reference (`board::reference`, eq. R1: Q15 clamped at
/// `2¹⁵ − 1`, each run's first phase times its steps (R3), error
/// `ε_r ≤ max(2√2·ε_s + 2ε_s² + 2⁻²⁷ + 2⁻¹⁶, 2⁻¹⁵)` with
/// `ε_s = ε_t + (2π/N)²/8 + 2⁻²⁹`, R2),
/// in blocks of 64 (`push_sums`), the fit turned by the pickups' delay δ
/// with the table's cos δ and sin δ (each within `ε_δ = ε_t + (2π/N)²/8 +
/// 2⁻²⁹` + f32 rounding 2⁻²⁴), against the f64 fit of the same integer
/// samples on their own exact phases θ + δ. The bound is the integer
/// lock-in's with R2's `ε_r`, times the turn's gain `|cos δ| + |sin δ|`,
/// plus the turn's own `2·ε_δ·(|a| + |b|)` and its f32 products (2⁻²³ of
/// the same); two signals per block, as the board's.
#[test]
fn the_pickups_on_the_forces_reference_are_within_their_bound() {
    use board::reference::{Gram, PairSums, Reference};
    let t = SineTable::<1024>::libm();
    let eps_t = (0..1024)
        .map(|i| (f64::from(t.entry(i)) - (TAU * i as f64 / 1024.0).sin()).abs())
        .fold(0.0, f64::max);
    let interp = (TAU / 1024.0).powi(2) / 8.0 + 2f64.powi(-29);
    let eps_d = eps_t + interp + 2f64.powi(-24);
    let mut worst = 0.0f64;
    let mut noise = 0x2545_F491u32;
    for f in [8e3f64, 20e3, 20.1e3, 40e3, 61e3] {
        let tw = (f / 500e3 * 4_294_967_296.0).round() as u32;
        // R2: the run's first phase times its step (tests/reference.rs).
        let eps_s = eps_t + interp;
        let eps_r =
            (2.0 * 2f64.sqrt() * eps_s + 2.0 * eps_s * eps_s + 2f64.powi(-27) + 2f64.powi(-16))
                .max(2f64.powi(-15));
        // δ = 0.714 µs of the drive in words (the board's ADC scan).
        let delay = (f64::from(tw) * 0.714e-6 * 500e3).round() as u32;
        let q30 = 1.0 / 1_073_741_824.0;
        let (cd, sd) = (
            t.sin_q30(delay.wrapping_add(1 << 30)) as f32 * q30 as f32,
            t.sin_q30(delay) as f32 * q30 as f32,
        );
        for k in 0..8u32 {
            let acc0 = k.wrapping_mul(0x0765_4321);
            let (d, amp, psi) = (
                2048.0 + 30.0 * f64::from(k),
                150.0 + 180.0 * f64::from(k),
                -2.9 + 0.7 * f64::from(k),
            );
            let mut l = LockInQ::<2>::new();
            let (mut theta, mut p0, mut p1) = (Vec::new(), Vec::new(), Vec::new());
            let mut i = 0u32;
            while l.span_words() < 1 << 32 {
                let a = acc0.wrapping_add(tw.wrapping_mul(i));
                let r = Reference::new(&t, a, tw, 64);
                let mut pairs = Vec::new();
                for j in 0..64u32 {
                    let w = a.wrapping_add(tw.wrapping_mul(j)).wrapping_add(delay);
                    let th = board::dds::phase_rad(w);
                    noise = noise.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                    let jitter = f64::from(noise >> 8) / f64::from(1u32 << 24) - 0.5;
                    let v0 = (d + amp * (th + psi).cos() + 2.0 * jitter).round();
                    let v1 = (d - 0.5 * amp * (th - psi).sin()).round();
                    pairs.push((v0 as u16, v1 as u16));
                    theta.push(th);
                    p0.push(v0);
                    p1.push(v1);
                }
                l.push_sums(&Gram::of(r.words()), &PairSums::of(r.words(), &pairs), tw);
                i += 64;
            }
            let fits = l.solve().unwrap().map(|ph| ph.turned(cd, sd));
            for (ph, p) in fits.iter().zip([&p0, &p1]) {
                let (coef, resid, g) = f64_fit(&theta, p);
                let kappa = centred_condition(&theta);
                let a_f = coef[1].abs() + coef[2].abs();
                // The turn maps the fit's errors in (a', b') into (a, b)
                // with the gain |cos δ| + |sin δ| ≤ √2.
                let turn = f64::from(cd.abs() + sd.abs());
                let bound = turn
                    * (g * eps_r * (a_f + resid) + 2f64.powi(-20) * kappa * (coef[0] + a_f))
                    + (2.0 * eps_d + 2f64.powi(-23)) * a_f;
                let label = format!("{f} Hz, case {k}");
                worst = worst.max(within(ph, &coef, bound, &label));
            }
        }
    }
    assert!(worst > 0.01, "worst {worst} of the bound");
}

#[test]
fn integer_lock_in_refuses_what_it_cannot_fit() {
    let t = SineTable::<1024>::libm();
    let mut l = LockInQ::<1>::new();
    let (c, s) = LockInQ::<1>::reference(&t, 0);
    assert_eq!((c, s), (32_768, 0));
    l.push(c, s, 0, [100]);
    l.push(c, s, 0, [100]);
    assert_eq!(l.solve(), Err(LockInError::TooFewSamples));
    // 64 samples of a 1 kHz drive: 46°, below a quarter period.
    let tw = (1e3 / 500e3 * 4_294_967_296.0) as u32;
    let mut l = LockInQ::<1>::new();
    for i in 0..64u32 {
        let (c, s) = LockInQ::<1>::reference(&t, tw.wrapping_mul(i));
        l.push(c, s, tw, [2000]);
    }
    assert!(l.span_rad() < MIN_SPAN_RAD as f32);
    // The span is the phase from the first sample to the last: 63 steps,
    // 63·2π·tw/2³² (f32: a few ulps).
    let span = 63.0 * TAU * f64::from(tw) / 4_294_967_296.0;
    assert!(
        (f64::from(l.span_rad()) - span).abs() <= 1e-6 * span,
        "{}",
        l.span_rad()
    );
    assert_eq!(l.solve(), Err(LockInError::ShortWindow));
    // More than MAX_Q_SAMPLES: refused, not overflowed.
    let mut l = LockInQ::<1>::new();
    for i in 0..=MAX_Q_SAMPLES {
        let (c, s) = LockInQ::<1>::reference(&t, tw.wrapping_mul(i));
        l.push(c, s, tw, [4095]);
    }
    assert_eq!(l.solve(), Err(LockInError::LongWindow));
}

/// `LockInQ::reference` (eq. LQ1) against f64 at 10 000 phase words: each
/// of `(c, s)` within `½` (the rounding to Q15) plus `2¹⁵·(ε_t + (2π/N)²/8 +
/// 2⁻²⁹)` (the table read of eq. Q1: its entries' error, measured here, its
/// interpolation, its floor) of `2¹⁵·(cos θ, sin θ)`. A floor for the
/// rounding would miss by up to a whole unit.
#[test]
fn the_integer_reference_is_the_rounded_table_read() {
    let t = SineTable::<1024>::libm();
    let eps_t = (0..1024)
        .map(|i| (f64::from(t.entry(i)) - (TAU * i as f64 / 1024.0).sin()).abs())
        .fold(0.0, f64::max);
    let q15 = 32_768.0;
    let bound = 0.5 + q15 * (eps_t + (TAU / 1024.0).powi(2) / 8.0 + 2f64.powi(-29));
    let mut worst = 0.0f64;
    let mut p = 0x9E37_79B9u32;
    for _ in 0..10_000 {
        p = p.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        let th = TAU * f64::from(p) / 4_294_967_296.0;
        let (c, s) = LockInQ::<1>::reference(&t, p);
        worst = worst
            .max((f64::from(c) - q15 * th.cos()).abs())
            .max((f64::from(s) - q15 * th.sin()).abs());
    }
    assert!(worst <= bound, "{worst} > {bound}");
    assert!(worst > 0.4, "the rounding is exercised: {worst}");
}

/// The solve's i64 → f32 conversion (`lockin::f32_of`) is Rust's own
/// `as f32` (round to nearest, ties to even), bit for bit: at every power
/// of two and its neighbours, at the halfway points between neighbouring
/// f32 values (ties, and one above and below), at the ends of i64 and of
/// i32, and at 10⁶ random values of every bit length.
#[test]
fn the_solves_conversion_is_the_correctly_rounded_one() {
    let check = |v: i64| {
        assert_eq!(f32_of(v).to_bits(), (v as f32).to_bits(), "{v}");
    };
    for v in [0, 1, -1, i64::MAX, i64::MIN, i64::MIN + 1] {
        check(v);
    }
    for k in 0..63 {
        let p = 1i64 << k;
        for d in -3..=3 {
            for v in [p.saturating_add(d), (-p).saturating_add(d)] {
                check(v);
            }
        }
        // Halfway between the f32 neighbours above 2^k (k ≥ 24: an ulp of
        // 2^(k−23)), for odd and even significands, and one either side.
        if k >= 24 {
            let ulp = 1i64 << (k - 23);
            for m in [0i64, 1, 2, 3, 0x7F_FFFE, 0x7F_FFFF] {
                let tie = p + m * ulp + ulp / 2;
                for v in [tie - 1, tie, tie + 1] {
                    check(v);
                    check(-v);
                }
            }
        }
    }
    let mut rng = integration_tests::Rng::new(35);
    for i in 0..1_000_000u32 {
        let bits = (rng.uniform() * 2f64.powi(53)) as u64;
        let mixed = bits ^ (bits << 11) ^ ((i as u64) << 40);
        check((mixed >> (i % 64)) as i64);
        check(-((mixed >> (i % 64)) as i64 >> 1));
    }
}

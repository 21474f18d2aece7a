//! Identification of one transducer mode (`board::identify`):
//! synthetic stepped-sine records of eq. 1, `H = g·e^{−jθ}/(1 − r² + j r/Q)`,
//! from known f_r, Q, g, θ (computed here by hand, not by the module), noise
//! free and with Gaussian noise of known σ; the intervals' coverage over many
//! seeds against its binomial tolerance; the refusals by name.
//!
//! Run with `--nocapture` to see the measured accuracy and coverage.

use std::f64::consts::PI;

use board::identify::{
    chi2_upper, fit, t_quantile_975, Fit, FitConfig, FitError, NoResonance, Sample, MIN_POINTS,
};
use board::resonator::ModeParams;
use model_core::Libm;

/// One mode of eq. 1.
#[derive(Clone, Copy, Debug)]
struct Truth {
    fr: f64,
    q: f64,
    g: f64,
    theta: f64,
}

impl Truth {
    /// `(Re H, Im H)` of eq. 1: `g·e^{−jθ}·conj(D)/|D|²`.
    fn h(&self, f: f64) -> (f64, f64) {
        let r = f / self.fr;
        let (dr, di) = (1.0 - r * r, r / self.q);
        let n = dr * dr + di * di;
        let (cr, ci) = (self.g * self.theta.cos(), -self.g * self.theta.sin());
        ((cr * dr + ci * di) / n, (ci * dr - cr * di) / n)
    }
    /// |H| at resonance, g·Q.
    fn peak(&self) -> f64 {
        self.g * self.q
    }
}

/// The four modes of the brief, off-centre in a ±5 % span around 20 kHz.
const CASES: [Truth; 4] = [
    Truth {
        fr: 20_300.0,
        q: 300.0,
        g: 1e-7,
        theta: 0.7,
    },
    Truth {
        fr: 19_700.0,
        q: 200.0,
        g: 2e-7,
        theta: -1.2,
    },
    Truth {
        fr: 20_120.0,
        q: 100.0,
        g: 1e-7,
        theta: 2.5,
    },
    Truth {
        fr: 19_950.0,
        q: 1000.0,
        g: 5e-8,
        theta: 0.3,
    },
];

/// ±5 % around 20 kHz, 201 points: 10 Hz steps (at Q = 1000 two steps per
/// half-power bandwidth of 20 Hz).
const F_LO: f64 = 19_000.0;
const F_HI: f64 = 21_000.0;
const N: usize = 201;

fn freqs(lo: f64, hi: f64, n: usize) -> impl Iterator<Item = f64> {
    (0..n).map(move |i| lo + (hi - lo) * i as f64 / (n - 1) as f64)
}

/// xorshift64* with Box–Muller: a deterministic standard normal source.
struct Gauss {
    state: u64,
    spare: Option<f64>,
}

impl Gauss {
    fn new(seed: u64) -> Self {
        // Never zero; decorrelate small seeds with a SplitMix64 step.
        let mut z = seed.wrapping_add(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        Gauss {
            state: (z ^ (z >> 31)) | 1,
            spare: None,
        }
    }
    /// Uniform in (0, 1).
    fn uniform(&mut self) -> f64 {
        self.state ^= self.state >> 12;
        self.state ^= self.state << 25;
        self.state ^= self.state >> 27;
        let x = self.state.wrapping_mul(0x2545_F491_4F6C_DD1D);
        ((x >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }
    fn normal(&mut self) -> f64 {
        if let Some(s) = self.spare.take() {
            return s;
        }
        let (u1, u2) = (self.uniform(), self.uniform());
        let rad = (-2.0 * u1.ln()).sqrt();
        let (s, c) = (2.0 * PI * u2).sin_cos();
        self.spare = Some(rad * s);
        rad * c
    }
}

/// The record of `truth` at `fs` with noise σ on each of Re, Im.
fn record(
    truth: &Truth,
    fs: impl Iterator<Item = f64>,
    sigma: f64,
    rng: &mut Gauss,
) -> Vec<Sample> {
    fs.map(|f| {
        let (re, im) = truth.h(f);
        Sample {
            freq_hz: f,
            re_m_per_v: re + sigma * rng.normal(),
            im_m_per_v: im + sigma * rng.normal(),
        }
    })
    .collect()
}

fn clean(truth: &Truth) -> Vec<Sample> {
    record(truth, freqs(F_LO, F_HI, N), 0.0, &mut Gauss::new(0))
}

/// θ difference wrapped into (−π, π].
fn dtheta(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(2.0 * PI);
    if d > PI {
        d - 2.0 * PI
    } else {
        d
    }
}

/// `(f_r, Q, g, θ)` errors: relative, relative, relative, rad.
fn errors(fit: &Fit, t: &Truth) -> [f64; 4] {
    [
        (fit.resonance_hz.value - t.fr).abs() / t.fr,
        (fit.q.value - t.q).abs() / t.q,
        (fit.gain_m_per_v.value - t.g).abs() / t.g,
        dtheta(fit.phase_lag_rad.value, t.theta).abs(),
    ]
}

#[test]
fn noise_free_records_are_recovered_to_the_stopping_step() {
    // LM stops when a step has max|δ_k| ≤ xtol in p = ((f_r − f_c)/S, ln Q,
    // ln g, θ); near the optimum the steps shrink at least at a linear rate
    // κ ≤ 1/2 (quadratically here: zero residual), so what remains after the
    // last step is ≤ κ/(1 − κ)·xtol ≤ xtol. The data's rounding (a few ulps
    // of |H|) moves the optimum by ~1e-15, far below. Hence the tolerances:
    // f_r to 2·xtol·S/f_r relative, Q and g to 2·xtol relative, θ to 2·xtol
    // rad (a factor 2 of margin).
    let cfg = FitConfig::DEFAULT;
    let span = F_HI - F_LO;
    for t in &CASES {
        let fit = fit(&clean(t), None, &cfg).unwrap_or_else(|e| panic!("{t:?}: {e}"));
        let e = errors(&fit, t);
        let tol = [
            2.0 * cfg.xtol * span / t.fr,
            2.0 * cfg.xtol,
            2.0 * cfg.xtol,
            2.0 * cfg.xtol,
        ];
        println!(
            "noise-free {:?}: errors f_r {:.1e}, Q {:.1e}, g {:.1e}, θ {:.1e} rad; rel RMS {:.1e}; {} iterations",
            t, e[0], e[1], e[2], e[3], fit.rel_rms, fit.iterations
        );
        for k in 0..4 {
            assert!(
                e[k] <= tol[k],
                "{t:?} parameter {k}: {:e} > {:e}",
                e[k],
                tol[k]
            );
        }
        assert!(fit.rel_rms < 1e-12, "{}", fit.rel_rms);
        assert_eq!(fit.points, N);
        assert_eq!(fit.dof, 2 * N - 4);
    }
}

#[test]
fn the_convention_is_the_resonators_phase_lag() {
    // The plant's mode (`resonator::ModeParams::response`) gives amplitude
    // and lag of x behind the drive; a chain lag θ adds to it. The record
    // H = |H|·e^{−j(lag + θ)} must give back the plant's f_r, Q, g and θ.
    let p = ModeParams {
        resonance_hz: 20_300.0,
        q: 300.0,
        gain_m_per_v: 1e-7,
    };
    let theta = 0.4;
    let rec: Vec<Sample> = freqs(F_LO, F_HI, N)
        .map(|f| {
            let (mag, lag) = p.response::<Libm>(f);
            Sample {
                freq_hz: f,
                re_m_per_v: mag * (lag + theta).cos(),
                im_m_per_v: -mag * (lag + theta).sin(),
            }
        })
        .collect();
    let fit = fit(&rec, None, &FitConfig::DEFAULT).unwrap();
    assert!((fit.resonance_hz.value / 20_300.0 - 1.0).abs() < 1e-12);
    assert!((fit.q.value / 300.0 - 1.0).abs() < 1e-9);
    assert!((fit.gain_m_per_v.value / 1e-7 - 1.0).abs() < 1e-9);
    assert!((fit.phase_lag_rad.value - theta).abs() < 1e-9);
    // And the fitted model evaluates eq. 1 as the record does.
    let t = Truth {
        fr: 20_300.0,
        q: 300.0,
        g: 1e-7,
        theta,
    };
    for f in [19_000.0, 20_250.0, 20_300.0, 20_333.0, 21_000.0] {
        let (re, im) = fit.model.response(f);
        let (tr, ti) = t.h(f);
        assert!(((re - tr).powi(2) + (im - ti).powi(2)).sqrt() < 1e-9 * t.peak());
        let (mag, lag) = fit.model.magnitude_lag(f);
        assert!((mag - tr.hypot(ti)).abs() < 1e-9 * t.peak());
        assert!(dtheta(-lag, ti.atan2(tr)).abs() < 1e-9);
    }
}

/// Coverage tolerance over `n` seeds at nominal 0.95: three binomial
/// standard deviations, 3·√(0.95·0.05/n) (0.046 at n = 200; the normal
/// approximation of the binomial is fair at n·0.05 = 10). Each rate falls
/// outside it by chance with probability ≈ 0.3 %; over the 36 rates checked
/// here, a false failure for fresh seeds has probability ≲ 10 %. The seeds
/// are fixed, so the test is deterministic; a systematic under-coverage
/// (e.g. intervals 20 % too narrow: coverage 0.88) would fail it.
fn coverage_tolerance(n: usize) -> f64 {
    3.0 * (0.95 * 0.05 / n as f64).sqrt()
}

const SEEDS: u64 = 200;

#[test]
fn noisy_records_meet_the_issue_targets_and_intervals_cover_at_95_percent() {
    // Noise σ = 1 % of the peak response g·Q on each of Re, Im. Targets of
    // issue 23 for every seed: f_r within 0.1 %, Q within 10 %. Coverage of
    // the 95 % intervals, with σ given (normal quantile) and estimated
    // (Student t, ν = 398), within the binomial tolerance.
    let cfg = FitConfig::DEFAULT;
    let tol = coverage_tolerance(SEEDS as usize);
    let mut failures = Vec::new();
    for (ci, t) in CASES.iter().enumerate() {
        let sigma = 0.01 * t.peak();
        for given in [true, false] {
            let mut cover = [0usize; 4];
            let mut worst = [0.0f64; 4];
            let mut worst_rms = 0.0f64;
            let mut max_iter = 0;
            for seed in 0..SEEDS {
                let mut rng = Gauss::new(seed * 16 + ci as u64);
                let rec = record(t, freqs(F_LO, F_HI, N), sigma, &mut rng);
                let sig = vec![sigma; N];
                let fit = fit(&rec, given.then_some(&sig[..]), &cfg)
                    .unwrap_or_else(|e| panic!("{t:?} seed {seed}: {e}"));
                let e = errors(&fit, t);
                for k in 0..4 {
                    worst[k] = worst[k].max(e[k]);
                }
                worst_rms = worst_rms.max(fit.rel_rms);
                max_iter = max_iter.max(fit.iterations);
                assert!(e[0] <= 1e-3, "{t:?} seed {seed}: f_r off by {:e}", e[0]);
                assert!(e[1] <= 0.1, "{t:?} seed {seed}: Q off by {:e}", e[1]);
                cover[0] += fit.resonance_hz.covers(t.fr) as usize;
                cover[1] += fit.q.covers(t.q) as usize;
                cover[2] += fit.gain_m_per_v.covers(t.g) as usize;
                let th = &fit.phase_lag_rad;
                let tt = th.value + dtheta(t.theta, th.value);
                cover[3] += th.covers(tt) as usize;
            }
            let rate = cover.map(|c| c as f64 / SEEDS as f64);
            println!(
                "f_r {:.0} Q {:.0} σ {}: coverage f_r {:.3} Q {:.3} g {:.3} θ {:.3}; \
                 worst error f_r {:.1e} Q {:.1e} g {:.1e} θ {:.1e} rad; worst rel RMS {:.4}; ≤ {} iterations",
                t.fr,
                t.q,
                if given { "given" } else { "estimated" },
                rate[0],
                rate[1],
                rate[2],
                rate[3],
                worst[0],
                worst[1],
                worst[2],
                worst[3],
                worst_rms,
                max_iter
            );
            for (k, r) in rate.iter().enumerate() {
                if (r - 0.95).abs() > tol {
                    failures.push(format!("{t:?} σ given {given}: parameter {k} covers {r}"));
                }
            }
        }
    }
    assert!(
        failures.is_empty(),
        "coverage outside 0.95 ± {tol:.4}: {failures:#?}"
    );
}

/// Levenberg–Marquardt's damping (eq. 7, Nielsen's rule on the gain ratio
/// ρ) on a long way to the optimum. A noise-free record of a mode 5·10⁴
/// times narrower than its 200 Hz step (f_r = 20 kHz, Q = 5·10⁶, 11 points
/// over 19–21 kHz, one of them at f_r): the peak point gives g·Q and the
/// flanks g and f_r, so the record determines the mode exactly, but the
/// start of eq. 6 sees a half-power width of about one step (Q ≈ 100), and
/// LM has to move ln Q by ≈ 10.8 along a curved valley. With λ following
/// ρ it arrives within the iteration cap (200; it takes 90), and then to
/// the stopping step as `noise_free_records_are_recovered_to_the_stopping_step`
/// argues: zero residual, so f_r within 2·xtol·S/f_r relative, Q and g
/// within 2·xtol relative, θ within 2·xtol rad. (A damping that ignores ρ —
/// λ/3 after every accepted step — or that raises λ too much for ρ < ½ and
/// lowers it too much for ρ > ½ runs into the cap on this record.)
#[test]
fn a_long_way_to_the_optimum_converges_within_the_iteration_cap() {
    let t = Truth {
        fr: 20_000.0,
        q: 5e6,
        g: 1e-7,
        theta: 0.3,
    };
    let cfg = FitConfig::DEFAULT;
    let (lo, hi) = (19_000.0, 21_000.0);
    let rec = record(&t, freqs(lo, hi, 11), 0.0, &mut Gauss::new(0));
    let fit = fit(&rec, None, &cfg).unwrap_or_else(|e| panic!("{t:?}: {e}"));
    let e = errors(&fit, &t);
    println!(
        "Q = 5e6 on 200 Hz steps: {} iterations; errors f_r {:.1e}, Q {:.1e}, g {:.1e}, θ {:.1e}",
        fit.iterations, e[0], e[1], e[2], e[3]
    );
    let tol = [
        2.0 * cfg.xtol * (hi - lo) / t.fr,
        2.0 * cfg.xtol,
        2.0 * cfg.xtol,
        2.0 * cfg.xtol,
    ];
    for k in 0..4 {
        assert!(e[k] <= tol[k], "parameter {k}: {:e} > {:e}", e[k], tol[k]);
    }
}

/// A record that does not tell Q and g apart is refused by the name of that
/// cause, eq. 14 ([`FitError::SingularNormalMatrix`]), not as a fit that
/// did not converge. Noise-free, Q = 10⁹ at 20 kHz, 7 points over 100 Hz,
/// the middle one at f_r: there `D = j/Q`, so ∂H/∂ln Q = H·(j r/Q)/D equals
/// ∂H/∂ln g = H (eq. 5), and the flanks, where the two differ, are ~10⁻⁶
/// of the peak. Eq. 14's pivot of ln g is 1 − R² of its column regressed on
/// the columns before it (a, ln Q), at most 1 − corr²(ln g, ln Q),
/// computed here from eq. 5 at the true parameters: far below 1e-10.
#[test]
fn a_record_that_does_not_separate_q_and_g_is_refused_as_singular() {
    let t = Truth {
        fr: 20_000.0,
        q: 1e9,
        g: 1e-7,
        theta: 0.3,
    };
    let rec = record(&t, freqs(19_950.0, 20_050.0, 7), 0.0, &mut Gauss::new(0));
    assert_eq!(rec[3].freq_hz, t.fr);
    // Columns ln Q and ln g of eq. 5 at the truth, as 2N real numbers.
    let (mut qq, mut gg, mut qg) = (0.0, 0.0, 0.0);
    for s in &rec {
        let (hr, hi) = t.h(s.freq_hz);
        let r = s.freq_hz / t.fr;
        let (dr, di) = (1.0 - r * r, r / t.q);
        let n = dr * dr + di * di;
        // (j r/Q)/D = j·(r/Q)·conj(D)/|D|²
        let (wr, wi) = (di * di / n, di * dr / n);
        let (cr, ci) = (hr * wr - hi * wi, hr * wi + hi * wr);
        qq += cr * cr + ci * ci;
        gg += hr * hr + hi * hi;
        qg += cr * hr + ci * hi;
    }
    let pivot_bound = 1.0 - qg * qg / (qq * gg);
    println!("1 − corr²(ln Q, ln g) = {pivot_bound:.1e}");
    assert!(pivot_bound < 1e-11, "{pivot_bound:e}");
    assert_eq!(fit_err(&rec, None), FitError::SingularNormalMatrix);
}

#[test]
fn a_span_with_the_peak_near_its_end_still_fits() {
    // The span starts half a bandwidth below f_r: the peak is the span's
    // second or third point, the lower half-power point is not in it.
    let t = CASES[0];
    let bw = t.fr / t.q;
    let lo = t.fr - 0.5 * bw;
    let hi = lo + 1000.0;
    for seed in 0..20 {
        let rec = record(
            &t,
            freqs(lo, hi, 101),
            0.01 * t.peak(),
            &mut Gauss::new(1000 + seed),
        );
        let fit =
            fit(&rec, None, &FitConfig::DEFAULT).unwrap_or_else(|e| panic!("seed {seed}: {e}"));
        let e = errors(&fit, &t);
        assert!(e[0] <= 1e-3 && e[1] <= 0.1, "seed {seed}: {e:?}");
    }
}

#[test]
fn the_fewest_points_fit_and_fewer_are_refused() {
    let t = CASES[0];
    let bw = t.fr / t.q;
    let six: Vec<Sample> = record(
        &t,
        freqs(t.fr - 1.3 * bw, t.fr + 1.7 * bw, MIN_POINTS),
        0.0,
        &mut Gauss::new(0),
    );
    let fit = fit(&six, None, &FitConfig::DEFAULT).unwrap();
    assert_eq!(fit.dof, 8);
    assert!((fit.quantile - 2.306_004).abs() < 1e-4);
    assert!(errors(&fit, &t).iter().all(|&e| e < 1e-9));
    for n in [0, 1, 3, MIN_POINTS - 1] {
        assert_eq!(
            fit_err(&six[..n], None),
            FitError::TooFewPoints { points: n }
        );
    }
}

fn fit_err(rec: &[Sample], sigma: Option<&[f64]>) -> FitError {
    fit(rec, sigma, &FitConfig::DEFAULT).expect_err("refused")
}

#[test]
fn a_span_on_one_flank_is_refused_as_no_resonance() {
    let t = CASES[0];
    for (lo, hi) in [(18_000.0, 19_800.0), (20_600.0, 22_000.0)] {
        let exact = record(&t, freqs(lo, hi, 101), 0.0, &mut Gauss::new(0));
        assert_eq!(
            fit_err(&exact, None),
            FitError::NoResonance(NoResonance::PeakAtEdge),
            "{lo}–{hi}"
        );
        // With noise of 1 % of the (absent) peak the largest point may be
        // inside the record; the fit then runs f_r out of the span.
        let mut inner = 0;
        for seed in 0..50 {
            let mut rng = Gauss::new(500 + seed);
            let noisy = record(&t, freqs(lo, hi, 101), 0.01 * t.peak(), &mut rng);
            match fit_err(&noisy, None) {
                FitError::NoResonance(NoResonance::PeakAtEdge) => {}
                FitError::NoResonance(NoResonance::OutsideSpan { .. }) => inner += 1,
                e => panic!("{lo}–{hi} seed {seed}: {e:?}"),
            }
        }
        println!("flank {lo}–{hi}: {inner} of 50 noisy records had their peak inside");
    }
}

#[test]
fn two_close_resonances_are_refused_by_the_residual() {
    // Two equal modes 150 Hz apart (2.2 bandwidths at Q = 300): one mode of
    // eq. 1 leaves the other's peak in the residual.
    let a = Truth {
        fr: 19_950.0,
        q: 300.0,
        g: 1e-7,
        theta: 0.0,
    };
    let b = Truth { fr: 20_100.0, ..a };
    let rec: Vec<Sample> = freqs(F_LO, F_HI, N)
        .map(|f| {
            let (ar, ai) = a.h(f);
            let (br, bi) = b.h(f);
            Sample {
                freq_hz: f,
                re_m_per_v: ar + br,
                im_m_per_v: ai + bi,
            }
        })
        .collect();
    match fit_err(&rec, None) {
        FitError::ResidualTooLarge { rel_rms, limit } => {
            println!("two modes: rel RMS {rel_rms:.3} > {limit}");
            assert!(rel_rms > limit);
        }
        e => panic!("{e:?}"),
    }
}

#[test]
fn a_small_misfit_passes_the_rms_test_but_not_chi_square_with_sigma() {
    // A second mode at 3 % of the first's peak, well apart: the single-mode
    // fit misses by ≈ 0.3 % RMS (below 5 %), but with σ = 0.1 % of the peak
    // given, χ² is far above its quantile.
    let a = CASES[0];
    let b = Truth {
        fr: 19_500.0,
        g: 0.03 * a.g,
        ..a
    };
    let sigma = 1e-3 * a.peak();
    let mut rng = Gauss::new(3);
    let rec: Vec<Sample> = freqs(F_LO, F_HI, N)
        .map(|f| {
            let (ar, ai) = a.h(f);
            let (br, bi) = b.h(f);
            Sample {
                freq_hz: f,
                re_m_per_v: ar + br + sigma * rng.normal(),
                im_m_per_v: ai + bi + sigma * rng.normal(),
            }
        })
        .collect();
    let unknown = fit(&rec, None, &FitConfig::DEFAULT).expect("passes the RMS test");
    assert!(unknown.rel_rms < 0.05);
    match fit_err(&rec, Some(&vec![sigma; N])) {
        FitError::ChiSquareTooLarge { chi2, limit, dof } => {
            println!(
                "weak second mode: rel RMS {:.4}; χ² {chi2:.0} > {limit:.0} (ν = {dof})",
                unknown.rel_rms
            );
            assert_eq!(dof, 2 * N - 4);
        }
        e => panic!("{e:?}"),
    }
}

#[test]
fn pure_noise_is_refused() {
    for seed in 0..50 {
        let mut rng = Gauss::new(900 + seed);
        let rec: Vec<Sample> = freqs(F_LO, F_HI, N)
            .map(|f| Sample {
                freq_hz: f,
                re_m_per_v: 1e-7 * rng.normal(),
                im_m_per_v: 1e-7 * rng.normal(),
            })
            .collect();
        let e = fit_err(&rec, None);
        if seed < 3 {
            println!("pure noise: {e}");
        }
    }
}

#[test]
fn random_modes_anywhere_in_the_span_fit_from_the_robust_start() {
    // f_r uniform over the inner 90 % of the span, Q log-uniform over
    // 100…1000, g over a decade, θ uniform: every record with 1 % noise fits
    // and meets the targets (the start of eq. 6 is within reach of LM).
    let mut rng = Gauss::new(4242);
    let mut worst = [0.0f64; 2];
    for case in 0..300 {
        let t = Truth {
            fr: F_LO + (F_HI - F_LO) * (0.05 + 0.9 * rng.uniform()),
            q: 100.0 * 10f64.powf(rng.uniform()),
            g: 1e-8 * 10f64.powf(rng.uniform()),
            theta: PI * (2.0 * rng.uniform() - 1.0),
        };
        let rec = record(&t, freqs(F_LO, F_HI, N), 0.01 * t.peak(), &mut rng);
        let fit = fit(&rec, None, &FitConfig::DEFAULT)
            .unwrap_or_else(|e| panic!("case {case} {t:?}: {e}"));
        let e = errors(&fit, &t);
        worst[0] = worst[0].max(e[0]);
        worst[1] = worst[1].max(e[1]);
        assert!(e[0] <= 1e-3 && e[1] <= 0.1, "case {case} {t:?}: {e:?}");
    }
    println!(
        "300 random modes: worst f_r error {:.1e}, Q error {:.1e}",
        worst[0], worst[1]
    );
}

#[test]
fn malformed_records_are_refused_by_name() {
    let t = CASES[0];
    let good = clean(&t);
    let mut nan = good.clone();
    nan[17].im_m_per_v = f64::NAN;
    assert_eq!(fit_err(&nan, None), FitError::NonFinite { index: 17 });
    let mut inf = good.clone();
    inf[3].freq_hz = f64::INFINITY;
    assert_eq!(fit_err(&inf, None), FitError::NonFinite { index: 3 });
    let mut sig = vec![1e-9; N];
    sig[40] = f64::NAN;
    assert_eq!(
        fit_err(&good, Some(&sig)),
        FitError::NonFinite { index: 40 }
    );
    sig[40] = 0.0;
    assert_eq!(fit_err(&good, Some(&sig)), FitError::Sigma { index: 40 });
    assert_eq!(
        fit_err(&good, Some(&sig[..10])),
        FitError::SigmaLength {
            expected: N,
            got: 10
        }
    );
    let mut unsorted = good.clone();
    unsorted.swap(50, 51);
    assert_eq!(fit_err(&unsorted, None), FitError::Frequency { index: 51 });
    let mut negative = good;
    negative[0].freq_hz = -1.0;
    assert_eq!(fit_err(&negative, None), FitError::Frequency { index: 0 });
}

#[test]
fn the_t_quantile_matches_the_table() {
    // Student t 0.975 quantiles (standard tables, 6 decimals).
    for (nu, t) in [
        (8, 2.306_004),
        (10, 2.228_139),
        (20, 2.085_963),
        (30, 2.042_272),
        (60, 2.000_298),
        (120, 1.979_930),
    ] {
        let got = t_quantile_975(nu);
        assert!((got - t).abs() < 5e-5, "ν = {nu}: {got} vs {t}");
    }
}

#[test]
fn the_chi_square_quantile_matches_the_table() {
    // Wilson–Hilferty against table quantiles of χ²_ν (0.95 at ν = 10,
    // 0.99 at ν = 100, 0.999 at ν = 400, the last from the regularised
    // incomplete gamma function by its series): within 0.2 % relative (the
    // default test, 1 − 1e-6 at ν = 398: 546.91 against 546.78).
    for (nu, z, q) in [
        (10, 1.644_854, 18.307),
        (100, 2.326_348, 135.807),
        (400, 3.090_232, 493.132),
    ] {
        let got = chi2_upper(nu, z);
        assert!((got / q - 1.0).abs() < 2e-3, "ν = {nu}: {got} vs {q}");
    }
}

#[test]
fn per_point_sigma_weights_the_fit_and_its_intervals_cover() {
    // Noise growing 4× across the span (σ_i given): the weighted fit's
    // intervals still cover at 0.95 within the binomial tolerance.
    let t = CASES[0];
    let tol = coverage_tolerance(SEEDS as usize);
    let sig: Vec<f64> = (0..N)
        .map(|i| 0.005 * t.peak() * (1.0 + 3.0 * i as f64 / (N - 1) as f64))
        .collect();
    let mut cover = [0usize; 4];
    for seed in 0..SEEDS {
        let mut rng = Gauss::new(7000 + seed);
        let rec: Vec<Sample> = freqs(F_LO, F_HI, N)
            .zip(&sig)
            .map(|(f, &s)| {
                let (re, im) = t.h(f);
                Sample {
                    freq_hz: f,
                    re_m_per_v: re + s * rng.normal(),
                    im_m_per_v: im + s * rng.normal(),
                }
            })
            .collect();
        let fit = fit(&rec, Some(&sig), &FitConfig::DEFAULT)
            .unwrap_or_else(|e| panic!("seed {seed}: {e}"));
        cover[0] += fit.resonance_hz.covers(t.fr) as usize;
        cover[1] += fit.q.covers(t.q) as usize;
        cover[2] += fit.gain_m_per_v.covers(t.g) as usize;
        let th = &fit.phase_lag_rad;
        cover[3] += th.covers(th.value + dtheta(t.theta, th.value)) as usize;
    }
    let rate = cover.map(|c| c as f64 / SEEDS as f64);
    println!(
        "per-point σ (×4 across the span): coverage f_r {:.3} Q {:.3} g {:.3} θ {:.3}",
        rate[0], rate[1], rate[2], rate[3]
    );
    for r in rate {
        assert!((r - 0.95).abs() <= tol, "{rate:?}");
    }
}

#[test]
fn a_resonance_drifting_during_the_sweep_biases_q_and_the_residual_cannot_tell() {
    // A quasi-static record whose f_r moves linearly by `drift` Hz while the
    // sweep crosses the span S: the detuning f − f_r(t) runs at
    // (1 − drift/S) of the sweep's rate, so near resonance the record is
    // eq. 1 with Q' = Q·(1 − drift/S) (first order), resonance at the
    // frequency where the sweep met it. The residual stays at the noise: only
    // a sweep in both directions shows it (the mean of the two Q's cancels
    // the first-order bias). Shown for the `identify` command's design.
    let t = CASES[0];
    let span = F_HI - F_LO;
    let rec = |drift: f64| -> Vec<Sample> {
        freqs(F_LO, F_HI, N)
            .enumerate()
            .map(|(i, f)| {
                let now = Truth {
                    fr: t.fr + drift * (i as f64 / (N - 1) as f64 - 0.5),
                    ..t
                };
                let (re, im) = now.h(f);
                Sample {
                    freq_hz: f,
                    re_m_per_v: re,
                    im_m_per_v: im,
                }
            })
            .collect()
    };
    let mut qs = Vec::new();
    for drift in [20.0, -20.0] {
        let fit = fit(&rec(drift), None, &FitConfig::DEFAULT).expect("fits");
        // Where the sweep met the resonance: f = f_r(t(f)).
        let k = drift / span;
        let f_meet = (t.fr - k * (F_LO + 0.5 * span)) / (1.0 - k);
        let q_pred = t.q * (1.0 - k);
        println!(
            "drift {drift:+} Hz over the sweep: Q {:.2} (first order {q_pred:.2}), f_r {:.3} (met at {f_meet:.3}), rel RMS {:.1e}",
            fit.q.value, fit.resonance_hz.value, fit.rel_rms
        );
        assert!((fit.q.value / q_pred - 1.0).abs() < 1e-3);
        assert!((fit.resonance_hz.value - f_meet).abs() < 0.01 * t.fr / t.q);
        assert!(fit.rel_rms < 0.01);
        qs.push(fit.q.value);
    }
    assert!((0.5 * (qs[0] + qs[1]) / t.q - 1.0).abs() < 1e-3);
}

/// The residual figures of a fit from its own point estimates: the SSR of
/// eq. 1 written out here (`Truth::h`, not the module's model) at the fitted
/// f_r, Q, g, θ over a noisy record (σ = 1 % of the peak), then
/// `noise = √(SSR/ν)`, ν = 2N − 4, and `ρ_rms = √(SSR/N)/max|H(f_i)|`
/// (eq. 15). Both sums of 402 squares agree to rounding: allowed 10⁻⁹
/// relative.
#[test]
fn the_noise_and_rms_figures_are_the_residual_of_the_fitted_model() {
    for (ci, t) in CASES.iter().enumerate() {
        let sigma = 0.01 * t.peak();
        let rec = record(
            t,
            freqs(F_LO, F_HI, N),
            sigma,
            &mut Gauss::new(77 + ci as u64),
        );
        let fit = fit(&rec, None, &FitConfig::DEFAULT).expect("a fit");
        let m = fit.model;
        let model = Truth {
            fr: m.resonance_hz,
            q: m.q,
            g: m.gain_m_per_v,
            theta: m.phase_lag_rad,
        };
        let (mut ssr, mut largest) = (0.0f64, 0.0f64);
        for s in &rec {
            let (re, im) = model.h(s.freq_hz);
            ssr += (re - s.re_m_per_v).powi(2) + (im - s.im_m_per_v).powi(2);
            largest = largest.max(re.hypot(im));
        }
        assert_eq!((fit.points, fit.dof), (N, 2 * N - 4));
        let noise = (ssr / (2 * N - 4) as f64).sqrt();
        let rms = (ssr / N as f64).sqrt() / largest;
        assert!(
            (fit.noise_m_per_v / noise - 1.0).abs() <= 1e-9,
            "case {ci}: noise {:e}, from the SSR {noise:e}",
            fit.noise_m_per_v
        );
        assert!(
            (fit.rel_rms / rms - 1.0).abs() <= 1e-9,
            "case {ci}: ρ_rms {:e}, from the SSR {rms:e}",
            fit.rel_rms
        );
        // And the noise is the record's σ, within its χ² spread (ν = 398:
        // √(SSR/ν)/σ within ±4·√(1/(2ν)) = ±14 %).
        assert!((noise / sigma - 1.0).abs() <= 4.0 * (0.5 / (2 * N - 4) as f64).sqrt());
    }
}

/// The fit is the least-squares optimum, checked on the SSR of eq. 1
/// written out here: from the fitted (f_r, Q, g, θ), a step of a tenth of a
/// standard error in either direction of each parameter does not lower the
/// SSR (at an interior minimum it rises by ≈ ½·(0.1)²·2σ² = 0.01σ², far
/// above the sums' rounding, 10⁻¹²·SSR; a stationary point of a wrong
/// gradient lowers it to first order on one side). A low-Q mode over a
/// wide span (Q = 3, r from 0.5 to 1.5), where the model's derivative in
/// f_r, ∝ 2r² − jr/Q, is far from its value at r = 1, and the bench's
/// Q = 300, with noise of 1 % of the peak.
#[test]
fn the_fit_is_a_minimum_of_the_sum_of_squares_in_every_parameter() {
    let modes = [
        (
            Truth {
                fr: 20_000.0,
                q: 3.0,
                g: 1e-7,
                theta: 0.4,
            },
            (10_000.0, 30_000.0),
        ),
        (CASES[0], (F_LO, F_HI)),
    ];
    for (ci, (t, (lo, hi))) in modes.into_iter().enumerate() {
        let sigma = 0.01 * t.peak();
        let rec = record(&t, freqs(lo, hi, N), sigma, &mut Gauss::new(5 + ci as u64));
        let fit = fit(&rec, None, &FitConfig::DEFAULT).expect("a fit");
        let ssr = |m: Truth| -> f64 {
            rec.iter()
                .map(|s| {
                    let (re, im) = m.h(s.freq_hz);
                    (re - s.re_m_per_v).powi(2) + (im - s.im_m_per_v).powi(2)
                })
                .sum()
        };
        let m = fit.model;
        let at = Truth {
            fr: m.resonance_hz,
            q: m.q,
            g: m.gain_m_per_v,
            theta: m.phase_lag_rad,
        };
        let s0 = ssr(at);
        // (Q's and g's standard errors are in their units: value·SE(ln).)
        let steps = [
            0.1 * fit.resonance_hz.std_error,
            0.1 * fit.q.std_error,
            0.1 * fit.gain_m_per_v.std_error,
            0.1 * fit.phase_lag_rad.std_error,
        ];
        for (k, d) in steps.into_iter().enumerate() {
            assert!(d > 0.0 && d.is_finite(), "case {ci}: step {k} {d}");
            for sgn in [-1.0, 1.0] {
                let mut p = at;
                match k {
                    0 => p.fr += sgn * d,
                    1 => p.q += sgn * d,
                    2 => p.g += sgn * d,
                    _ => p.theta += sgn * d,
                }
                let s1 = ssr(p);
                assert!(
                    s1 >= s0 * (1.0 - 1e-12),
                    "case {ci}: parameter {k} {sgn:+} step: SSR {s1:e} below the fit's {s0:e} (by {:e} σ²)",
                    (s0 - s1) / (sigma * sigma)
                );
            }
        }
    }
}

/// The standard errors of a fit (eq. 9 without σ: `C = s²(JᵀJ)⁻¹`, `s² =
/// SSR/ν`) against a Jacobian formed here by central differences of eq. 1
/// written out (`Truth::h`) in (f_r, ln Q, ln g, θ) at the fitted point, and
/// a 4×4 Gauss–Jordan inverse: the differences' error is O(h²) = 10⁻¹²
/// relative, the inverse's a few ulps times JᵀJ's condition (≤ 10⁶ here):
/// allowed 10⁻⁵ relative. The low-Q mode over a wide span (Q = 3, r from
/// 0.5 to 1.5) makes the f_r column's r-dependence, ∝ 2r² − jr/Q, count.
#[test]
fn the_standard_errors_are_those_of_the_model_s_own_jacobian() {
    let modes = [
        (
            Truth {
                fr: 20_000.0,
                q: 3.0,
                g: 1e-7,
                theta: 0.4,
            },
            (10_000.0, 30_000.0),
        ),
        (CASES[0], (F_LO, F_HI)),
    ];
    for (ci, (t, (lo, hi))) in modes.into_iter().enumerate() {
        let sigma = 0.01 * t.peak();
        let rec = record(&t, freqs(lo, hi, N), sigma, &mut Gauss::new(5 + ci as u64));
        let fit = fit(&rec, None, &FitConfig::DEFAULT).expect("a fit");
        let m = fit.model;
        let p0 = [
            m.resonance_hz,
            m.q.ln(),
            m.gain_m_per_v.ln(),
            m.phase_lag_rad,
        ];
        let at = |p: [f64; 4]| Truth {
            fr: p[0],
            q: p[1].exp(),
            g: p[2].exp(),
            theta: p[3],
        };
        let h = [1e-6 * p0[0], 1e-6, 1e-6, 1e-6];
        // JᵀJ and the SSR.
        let mut jtj = [[0.0f64; 4]; 4];
        let mut ssr = 0.0;
        for s in &rec {
            let (re0, im0) = at(p0).h(s.freq_hz);
            ssr += (re0 - s.re_m_per_v).powi(2) + (im0 - s.im_m_per_v).powi(2);
            let col = |k: usize| {
                let (mut a, mut b) = (p0, p0);
                a[k] += h[k];
                b[k] -= h[k];
                let ((ra, ia), (rb, ib)) = (at(a).h(s.freq_hz), at(b).h(s.freq_hz));
                ((ra - rb) / (2.0 * h[k]), (ia - ib) / (2.0 * h[k]))
            };
            let cols = [col(0), col(1), col(2), col(3)];
            for j in 0..4 {
                for k in 0..4 {
                    jtj[j][k] += cols[j].0 * cols[k].0 + cols[j].1 * cols[k].1;
                }
            }
        }
        // Gauss–Jordan with partial pivoting on [JᵀJ | I].
        let mut a = [[0.0f64; 8]; 4];
        for j in 0..4 {
            a[j][..4].copy_from_slice(&jtj[j]);
            a[j][4 + j] = 1.0;
        }
        for c in 0..4 {
            let piv = (c..4)
                .max_by(|&x, &y| a[x][c].abs().total_cmp(&a[y][c].abs()))
                .unwrap();
            a.swap(c, piv);
            let d = a[c][c];
            for x in a[c].iter_mut() {
                *x /= d;
            }
            for r in 0..4 {
                if r != c {
                    let f = a[r][c];
                    let row = a[c];
                    for (x, y) in a[r].iter_mut().zip(row) {
                        *x -= f * y;
                    }
                }
            }
        }
        let s2 = ssr / (2 * N - 4) as f64;
        // Q's and g's standard errors are reported in their units, by the
        // delta method: value·SE(ln value).
        let scale = [1.0, m.q, m.gain_m_per_v, 1.0];
        let se: [f64; 4] = core::array::from_fn(|k| scale[k] * (s2 * a[k][4 + k]).sqrt());
        let got = [
            fit.resonance_hz.std_error,
            fit.q.std_error,
            fit.gain_m_per_v.std_error,
            fit.phase_lag_rad.std_error,
        ];
        for k in 0..4 {
            assert!(
                (got[k] / se[k] - 1.0).abs() <= 1e-5,
                "case {ci}: parameter {k}: SE {:e}, from the Jacobian {:e}",
                got[k],
                se[k]
            );
        }
    }
}

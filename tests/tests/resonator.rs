//! One transducer mode (`board::resonator`): the exact
//! zero-order-hold update against closed forms of the continuous mode
//! (step response, free decay with its envelope time constant τ = Q/(π f_r))
//! and against an independent fine Runge–Kutta integration of the same
//! held drive; the steady response against the transfer function.

use std::f64::consts::{PI, TAU};

use board::resonator::{Mode, ModeError, ModeParams};
use model_core::Libm;

const FR: f64 = 20_300.0;
const Q: f64 = 300.0;
const G: f64 = 1e-7; // m/V
/// The board's sample step, 2 µs (500 kS/s).
const H: f64 = 2e-6;

fn params() -> ModeParams<f64> {
    ModeParams {
        resonance_hz: FR,
        q: Q,
        gain_m_per_v: G,
    }
}

/// Rounding bound of `k` exact-update steps on a state of size ≤ `scale`:
/// each step forms x and v from three products and two sums (≤ 5 roundings
/// of terms each ≤ 2·scale in the energy norm, in which Φ does not grow),
/// and Φ, Γ carry one rounding each (a relative ε on terms of the same
/// size): ≤ 7ε·2·scale per step, summed over the steps.
fn rounding_bound(k: usize, scale: f64) -> f64 {
    k as f64 * 14.0 * f64::EPSILON * scale
}

#[test]
fn step_response_is_the_closed_form_at_every_sample() {
    // A held step is exactly what the ZOH update assumes: the samples equal
    // x(t) = g·u·[1 − e^{−σt}(cos ω_d t + (σ/ω_d) sin ω_d t)].
    let mut m = Mode::new(params(), H).unwrap();
    let u = 2.5;
    let (wr, zeta) = (TAU * FR, 0.5 / Q);
    let (sigma, wd) = (zeta * wr, wr * (1.0 - zeta * zeta).sqrt());
    let n = 25_000; // 50 ms ≈ 10 τ
    let mut worst: f64 = 0.0;
    for k in 1..=n {
        let x = m.step(u);
        let t = k as f64 * H;
        let exact =
            G * u * (1.0 - (-sigma * t).exp() * ((wd * t).cos() + sigma / wd * (wd * t).sin()));
        worst = worst.max((x - exact).abs());
    }
    // The state stays within 2·g·u (overshoot of an underdamped step).
    let bound = rounding_bound(n, 2.0 * G * u);
    assert!(worst <= bound, "worst {worst:e} > {bound:e}");
    // After 10 τ the step has settled to g·u within e^{−10}.
    assert!((m.x() - G * u).abs() <= G * u * (-10.0f64).exp() * 1.01);
}

#[test]
fn free_decay_has_the_envelope_time_constant_q_over_pi_fr() {
    let mut m = Mode::new(params(), H).unwrap();
    let x0 = 1e-6;
    m.set_state(x0, 0.0);
    let (wr, zeta) = (TAU * FR, 0.5 / Q);
    let (sigma, wd) = (zeta * wr, wr * (1.0 - zeta * zeta).sqrt());
    let n = 25_000;
    let mut worst: f64 = 0.0;
    let mut xs = Vec::with_capacity(n);
    for k in 1..=n {
        let x = m.step(0.0);
        let t = k as f64 * H;
        let exact = x0 * (-sigma * t).exp() * ((wd * t).cos() + sigma / wd * (wd * t).sin());
        worst = worst.max((x - exact).abs());
        xs.push(x);
    }
    assert!(worst <= rounding_bound(n, x0), "{worst:e}");
    // The envelope: the energy E = x² + (v/ω_r)² of a lightly damped mode
    // decays as e^{−2t/τ} on average; measured over whole stretches of 5 τ
    // from the peaks of |x| in the first and last period of the record.
    let tau = params().tau_s();
    assert!((tau - Q / (PI * FR)).abs() <= 1e-15 * tau);
    let per = (1.0 / FR / H).ceil() as usize + 1;
    let peak = |from: usize| {
        xs[from..from + per]
            .iter()
            .fold(0.0f64, |a, x| a.max(x.abs()))
    };
    let (a0, a1) = (peak(0), peak(n - per));
    let span = (n - per) as f64 * H;
    let tau_measured = span / (a0 / a1).ln();
    // A peak of a sampled sine misses the true peak by ≤ 1 − cos(ω h/2)
    // (relative), at each end: the log ratio is off by ≤ 2(1 − cos(ω_d h/2)).
    let dlog = 2.0 * (1.0 - (wd * H / 2.0).cos());
    let rel = dlog / (a0 / a1).ln();
    assert!(
        (tau_measured - tau).abs() <= rel * tau * 1.01,
        "τ measured {tau_measured:e}, closed form {tau:e}, allowed rel {rel:e}"
    );
}

/// An independent reference: classical RK4 on the continuous mode with the
/// same held drive, `sub` steps per sample.
fn rk4(us: &[f64], sub: usize) -> Vec<f64> {
    let (wr, zeta) = (TAU * FR, 0.5 / Q);
    let f = |x: f64, v: f64, u: f64| (v, wr * wr * (G * u - x) - 2.0 * zeta * wr * v);
    let dt = H / sub as f64;
    let (mut x, mut v) = (0.0, 0.0);
    let mut out = Vec::with_capacity(us.len());
    for &u in us {
        for _ in 0..sub {
            let (k1x, k1v) = f(x, v, u);
            let (k2x, k2v) = f(x + 0.5 * dt * k1x, v + 0.5 * dt * k1v, u);
            let (k3x, k3v) = f(x + 0.5 * dt * k2x, v + 0.5 * dt * k2v, u);
            let (k4x, k4v) = f(x + dt * k3x, v + dt * k3v, u);
            x += dt / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
            v += dt / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
        }
        out.push(x);
    }
    out
}

#[test]
fn sine_drive_agrees_with_a_fine_runge_kutta_run() {
    // 20 kHz drive (25 samples a period) on the 20.3 kHz mode: the board's case.
    let n = 10_000; // 20 ms ≈ 4 τ: through the transient
    let us: Vec<f64> = (0..n)
        .map(|k| 3.0 * (TAU * 20e3 * k as f64 * H).cos())
        .collect();
    let mut m = Mode::new(params(), H).unwrap();
    let exact: Vec<f64> = us.iter().map(|&u| m.step(u)).collect();
    let (r1, r2) = (rk4(&us, 20), rk4(&us, 40));
    // RK4's own error, by self-convergence (order 4): |R(40) − R(20)|·16/15
    // bounds the error of R(40) up to higher order; the comparison allows
    // that plus the update's rounding.
    let scale = Q * G * 3.0;
    let mut worst: f64 = 0.0;
    let mut rk_err: f64 = 0.0;
    for k in 0..n {
        rk_err = rk_err.max((r2[k] - r1[k]).abs() * 16.0 / 15.0);
        worst = worst.max((exact[k] - r2[k]).abs());
    }
    let allowed = 2.0 * rk_err + rounding_bound(n, scale);
    assert!(
        worst <= allowed,
        "worst {worst:e} > {allowed:e} (RK4 error {rk_err:e})"
    );
    // And the comparison is not vacuous: what it allows is far below the
    // response's scale (an error of the update's order would show).
    assert!(allowed <= 1e-7 * scale, "{allowed:e}");
}

#[test]
fn steady_response_is_the_transfer_function_with_the_hold() {
    // After 30 τ the transient is e^{−30} of the start: the lock-in over
    // whole periods (25 samples of 20 kHz) gives the steady amplitude and
    // phase. The held drive is the sine delayed by h/2 with amplitude
    // sinc(Ωh/2) plus images near k·f_s ± f, which the mode passes with
    // gain ≤ g/((f_s − f)²/f_r² − 1) each, at amplitudes ≤ U·f/(f_s − f):
    // together < 1e-5 of the resonant response here.
    let p = params();
    let f = 20e3;
    let u0 = 3.0;
    let mut m = Mode::new(p, H).unwrap();
    let settle = (30.0 * p.tau_s() / H) as usize;
    let periods = 400;
    let per = 25;
    let (mut c, mut s) = (0.0, 0.0);
    for k in 0..settle + periods * per {
        let th = TAU * f * k as f64 * H;
        // The step from t_k with u(t_k) held returns x(t_{k+1}).
        let x = m.step(u0 * th.cos());
        let th1 = th + TAU * f * H;
        if k >= settle {
            c += x * th1.cos();
            s += x * th1.sin();
        }
    }
    let n = (periods * per) as f64;
    let amp = 2.0 * (c * c + s * s).sqrt() / n;
    let lag = s.atan2(c); // x = A cos(θ − lag)
    let (mag, phase) = p.response::<Libm>(f);
    let w = TAU * f * H / 2.0;
    let sinc = w.sin() / w;
    let want_amp = u0 * mag * sinc;
    let want_lag = phase + w;
    let fs = 1.0 / H;
    let images = 2.0 * u0 * G * (f / (fs - f)) / ((fs - f).powi(2) / FR.powi(2) - 1.0);
    assert!(
        (amp - want_amp).abs() <= images + 1e-12 * want_amp,
        "amplitude {amp:e} vs {want_amp:e} (images {images:e})"
    );
    assert!(
        (lag - want_lag).abs() <= images / want_amp + 1e-12,
        "lag {lag} vs {want_lag}"
    );
    // The physics in words: 300 Hz below a Q = 300 resonance (4.4 half
    // bandwidths) the response is ≈ 34× static (1/√(0.0293² + 0.0033²)
    // × sinc 0.9974 = 33.78), lagging 6.4° + 7.2° of the hold.
    assert!((amp / (u0 * G) - 33.78).abs() < 0.01, "{}", amp / (u0 * G));
}

#[test]
fn bad_parameters_are_refused_by_name() {
    let ok = params();
    let bad = |p: ModeParams<f64>, h: f64| Mode::new(p, h).err();
    assert_eq!(
        bad(
            ModeParams {
                resonance_hz: 0.0,
                ..ok
            },
            H
        ),
        Some(ModeError::Resonance)
    );
    assert_eq!(
        bad(
            ModeParams {
                resonance_hz: f64::NAN,
                ..ok
            },
            H
        ),
        Some(ModeError::Resonance)
    );
    assert_eq!(
        bad(ModeParams { q: 0.5, ..ok }, H),
        Some(ModeError::Quality)
    );
    assert_eq!(
        bad(
            ModeParams {
                q: f64::INFINITY,
                ..ok
            },
            H
        ),
        Some(ModeError::Quality)
    );
    assert_eq!(
        bad(
            ModeParams {
                gain_m_per_v: f64::NAN,
                ..ok
            },
            H
        ),
        Some(ModeError::Gain)
    );
    assert_eq!(bad(ok, 0.0), Some(ModeError::Step));
    assert_eq!(bad(ok, -H), Some(ModeError::Step));
}

/// The plant's sub-step: one sample of 2 µs in 32 (the virtual device's).
const H_SUB: f64 = H / 32.0;

#[test]
fn an_undriven_mode_rings_in_the_subnormals_for_ever_without_the_floor() {
    // The premise of `Mode::settle_below`: from x = 10⁻³¹⁸ m (a subnormal,
    // 2·10⁵ quanta of 4.9·10⁻³²⁴), 2·10⁶ undriven sub-steps (125 ms ≈ 27 τ,
    // τ = Q/(π f_r) = 4.7 ms) would decay the exact amplitude by e⁻²⁷ to
    // 3·10⁻³³⁰, far under half a quantum: rounded, zero. In floating point the
    // damping per step, 1 − e^{−h/τ} = 1.3·10⁻⁵, is below half a quantum
    // once the amplitude is under ~4·10⁴ quanta, and rounding keeps it ringing.
    let mut m = Mode::new(params(), H_SUB).unwrap();
    m.set_state(1e-318, 0.0);
    let tau = Q / (PI * FR);
    let steps = 2_000_000;
    // In logarithms (the product itself would underflow): e^{−t/τ} < ½ quantum/x₀.
    let quantum = f64::from_bits(1);
    assert!(-(steps as f64) * H_SUB / tau < (quantum / 1e-318).ln() + 0.5f64.ln());
    let mut peak_late: f64 = 0.0;
    for k in 0..steps {
        m.step(0.0);
        if k >= steps - 10_000 {
            peak_late = peak_late.max(m.x().abs());
        }
    }
    assert!(peak_late > 0.0, "the mode came to rest by itself");
    assert!(
        peak_late < f64::MIN_POSITIVE,
        "{peak_late:e} is not subnormal"
    );
}

#[test]
fn settle_below_rests_a_mode_under_the_floor_in_displacement_and_velocity() {
    let w = TAU * FR;
    let floor = 1e-30;
    // (x, v) → whether it is set to rest: both below the floor (v over ω).
    for (x, v, rests) in [
        (0.9e-30, 0.0, true),
        (-0.9e-30, 0.9e-30 * w, true),
        (0.0, -0.9e-30 * w, true),
        (1.1e-30, 0.0, false),
        (0.0, 1.1e-30 * w, false),
        (-1.1e-30, 0.5e-30 * w, false),
    ] {
        let mut m = Mode::new(params(), H_SUB).unwrap();
        m.set_state(x, v);
        assert_eq!(m.settle_below(floor), rests, "({x:e}, {v:e})");
        let want = if rests { (0.0, 0.0) } else { (x, v) };
        assert_eq!((m.x(), m.v()), want, "({x:e}, {v:e})");
    }
}

//! One transducer mode: a lightly damped second-order resonator driven by
//! its DAC channel, advanced by its **exact** discrete update for a drive
//! held constant over a sample (zero-order hold, as a DAC holds its output).
//!
//! The mode (displacement `x`, m; velocity `v`, m/s) obeys
//!
//! ```text
//! x'' + 2ζω_r x' + ω_r² x = ω_r² g u(t),      ζ = 1/(2Q),  ω_r = 2π f_r,
//! ```
//!
//! with `u` the drive (V) and `g` the static gain (m/V): a constant drive `u`
//! settles at `x = g u`; a drive `u cos Ωt` gives the steady amplitude
//! `g u / √((1 − r²)² + (r/Q)²)`, `r = Ω/ω_r` (Q·g u at resonance), lagging by
//! `atan2(r/Q, 1 − r²)`; the envelope follows a change with the time
//! constant `τ = 2Q/ω_r = Q/(π f_r)`.
//!
//! **Exact update.** With `u` constant over a step `h`, `y = x − g u` obeys
//! the free equation, whose solution over `h` is the matrix exponential of
//! the state matrix `A = [[0, 1], [−ω_r², −2ζω_r]]` (underdamped, `ζ < 1`,
//! `ω_d = ω_r √(1 − ζ²)`, `σ = ζω_r`):
//!
//! ```text
//! e^{Ah} = e^{−σh} [[cos ω_d h + (σ/ω_d) sin ω_d h,  (1/ω_d) sin ω_d h],
//!                   [−(ω_r²/ω_d) sin ω_d h,            cos ω_d h − (σ/ω_d) sin ω_d h]]
//! ```
//!
//! so `(x, v)_{k+1} = Φ (x, v)_k + Γ u_k` with `Φ = e^{Ah}` and
//! `Γ = (I − Φ)(g, 0)ᵀ`: exact for any step, no Euler or Runge–Kutta error
//! (the only error is the arithmetic's rounding, a few ulps per step,
//! damped with the mode). [`Mode::new`] computes `Φ` and `Γ` once, in
//! `f64` with libm whatever `F` is (so an `f32` plant carries coefficients
//! rounded once); a step costs four multiplications and four additions per
//! state.

use crate::float::{Float, Math};

/// Why a mode cannot be formed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ModeError {
    /// The resonance `f_r` must be finite and > 0.
    Resonance,
    /// `Q` must be finite and > 1/2 (underdamped).
    Quality,
    /// The gain must be finite.
    Gain,
    /// The step must be finite and > 0.
    Step,
}

impl core::fmt::Display for ModeError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            ModeError::Resonance => "the resonance frequency must be finite and > 0",
            ModeError::Quality => "the quality factor Q must be finite and > 0.5",
            ModeError::Gain => "the static gain must be finite",
            ModeError::Step => "the time step must be finite and > 0",
        })
    }
}

impl core::error::Error for ModeError {}

/// The parameters of a mode.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ModeParams<F> {
    /// Resonance frequency f_r, Hz.
    pub resonance_hz: F,
    /// Quality factor Q (> 1/2).
    pub q: F,
    /// Static gain g, m/V (displacement per volt at zero frequency).
    pub gain_m_per_v: F,
}

impl<F: Float> ModeParams<F> {
    /// The envelope time constant τ = Q/(π f_r), s.
    pub fn tau_s(&self) -> F {
        self.q / (F::PI * self.resonance_hz)
    }

    /// The steady response to a drive `u cos(2π f t)`: (amplitude per volt,
    /// m/V; phase lag, rad, in [0, π]), from the transfer function
    /// `g / (1 − r² + j r/Q)`, `r = f/f_r`.
    pub fn response<M: Math<F>>(&self, f_hz: F) -> (F, F) {
        let r = f_hz / self.resonance_hz;
        let re = F::ONE - r * r;
        let im = r / self.q;
        let mag = self.gain_m_per_v / M::sqrt(re * re + im * im);
        (mag, M::atan2(im, re))
    }
}

/// A mode with its exact one-step update for the step `h`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mode<F> {
    params: ModeParams<F>,
    /// Φ = e^{Ah}, row-major.
    phi: [[F; 2]; 2],
    /// Γ = (I − Φ)(g, 0)ᵀ.
    gamma: [F; 2],
    /// Displacement, m.
    x: F,
    /// Velocity, m/s.
    v: F,
}

impl<F: Float> Mode<F> {
    /// A mode at rest with the update for steps of `h` seconds.
    ///
    /// # Errors
    /// [`ModeError`] naming the first parameter out of its domain.
    pub fn new(p: ModeParams<F>, h: F) -> Result<Self, ModeError> {
        if !(p.resonance_hz.is_finite() && p.resonance_hz > F::ZERO) {
            return Err(ModeError::Resonance);
        }
        if !(p.q.is_finite() && p.q > F::HALF) {
            return Err(ModeError::Quality);
        }
        if !p.gain_m_per_v.is_finite() {
            return Err(ModeError::Gain);
        }
        if !(h.is_finite() && h > F::ZERO) {
            return Err(ModeError::Step);
        }
        let mut m = Mode {
            params: p,
            phi: [[F::ONE, F::ZERO], [F::ZERO, F::ONE]],
            gamma: [F::ZERO, F::ZERO],
            x: F::ZERO,
            v: F::ZERO,
        };
        m.set_step(h);
        Ok(m)
    }

    /// Recomputes Φ and Γ for the step `h` (and the current parameters), in
    /// `f64`.
    fn set_step(&mut self, h: F) {
        let p = self.params;
        let h = h.to_f64();
        let wr = core::f64::consts::TAU * p.resonance_hz.to_f64();
        let zeta = 0.5 / p.q.to_f64();
        let sigma = zeta * wr;
        let wd = wr * libm::sqrt(1.0 - zeta * zeta);
        let (s, c) = libm::sincos(wd * h);
        let e = libm::exp(-sigma * h);
        let phi = [
            [e * (c + sigma / wd * s), e * s / wd],
            [-e * wr * wr / wd * s, e * (c - sigma / wd * s)],
        ];
        let g = p.gain_m_per_v.to_f64();
        let f = F::from_f64;
        self.gamma = [f((1.0 - phi[0][0]) * g), f(-phi[1][0] * g)];
        self.phi = [[f(phi[0][0]), f(phi[0][1])], [f(phi[1][0]), f(phi[1][1])]];
    }

    /// Changes f_r, Q and the gain keeping the state (drift, thermal shift,
    /// contact load), for steps of `h` seconds.
    ///
    /// # Errors
    /// [`ModeError`]; nothing changes on error.
    pub fn retune(&mut self, p: ModeParams<F>, h: F) -> Result<(), ModeError> {
        let fresh = Mode::<F>::new(p, h)?;
        self.params = fresh.params;
        self.phi = fresh.phi;
        self.gamma = fresh.gamma;
        Ok(())
    }

    /// The parameters.
    pub fn params(&self) -> &ModeParams<F> {
        &self.params
    }

    /// Displacement x, m.
    pub fn x(&self) -> F {
        self.x
    }

    /// Velocity v, m/s.
    pub fn v(&self) -> F {
        self.v
    }

    /// Sets the state (m, m/s).
    pub fn set_state(&mut self, x: F, v: F) {
        self.x = x;
        self.v = v;
    }

    /// One step with the drive `u` (V) held over it; returns the new
    /// displacement, m.
    pub fn step(&mut self, u: F) -> F {
        let [[a, b], [c, d]] = self.phi;
        let x = a * self.x + b * self.v + self.gamma[0] * u;
        let v = c * self.x + d * self.v + self.gamma[1] * u;
        self.x = x;
        self.v = v;
        x
    }
}

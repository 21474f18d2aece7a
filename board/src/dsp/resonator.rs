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
//! state. [`Mode::update_for`] forms the same exact update for any other
//! step length, [`Mode::x_after`] applies it without moving the state: the
//! plant's motion pickups sample a mode a fixed delay after the sample's
//! start, within the held sample ([`crate::plant`]).

use model_core::float::{Float, Math};

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

/// The exact zero-order-hold update of a mode over one step `h`:
/// `(x, v) ← Φ (x, v) + Γ u` with `Φ = e^{Ah}`, `Γ = (I − Φ)(g, 0)ᵀ` (module
/// docs), for the mode's parameters when it was formed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HoldUpdate<F> {
    /// Φ = e^{Ah}, row-major.
    phi: [[F; 2]; 2],
    /// Γ = (I − Φ)(g, 0)ᵀ.
    gamma: [F; 2],
}

impl<F: Float> HoldUpdate<F> {
    /// The update over `h` seconds for the parameters `p` (already checked),
    /// in `f64` with libm, rounded once to `F`.
    fn of(p: &ModeParams<F>, h: F) -> Self {
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
        HoldUpdate {
            gamma: [f((1.0 - phi[0][0]) * g), f(-phi[1][0] * g)],
            phi: [[f(phi[0][0]), f(phi[0][1])], [f(phi[1][0]), f(phi[1][1])]],
        }
    }

    /// The state `(x, v)` after the step from `(x, v)` with the drive `u`
    /// (V) held over it.
    #[inline]
    pub fn apply(&self, x: F, v: F, u: F) -> (F, F) {
        let [[a, b], [c, d]] = self.phi;
        (
            a * x + b * v + self.gamma[0] * u,
            c * x + d * v + self.gamma[1] * u,
        )
    }
}

/// A mode with its exact one-step update for the step `h`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mode<F> {
    params: ModeParams<F>,
    /// The update over one step `h`.
    update: HoldUpdate<F>,
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
        Ok(Mode {
            params: p,
            update: HoldUpdate::of(&p, h),
            x: F::ZERO,
            v: F::ZERO,
        })
    }

    /// The exact update over a step of `h` seconds (any length, e.g. a
    /// fraction of the sub-step: the plant's pickups sample a mode a fixed
    /// delay after the sample's start) for the current parameters. Compute
    /// it once and apply it with [`Mode::x_after`] (it costs what a retune
    /// does: a `sincos` and an `exp` in `f64`).
    ///
    /// # Errors
    /// [`ModeError::Step`] unless `h` is finite and > 0.
    pub fn update_for(&self, h: F) -> Result<HoldUpdate<F>, ModeError> {
        if !(h.is_finite() && h > F::ZERO) {
            return Err(ModeError::Step);
        }
        Ok(HoldUpdate::of(&self.params, h))
    }

    /// The displacement (m) the mode would reach from its current state
    /// after the update `u` with the drive `volts` held over it; the state
    /// is not changed (a look ahead within the current step).
    #[inline]
    pub fn x_after(&self, u: &HoldUpdate<F>, volts: F) -> F {
        u.apply(self.x, self.v, volts).0
    }

    /// Changes f_r, Q and the gain keeping the state (drift, thermal shift,
    /// contact load), for steps of `h` seconds.
    ///
    /// # Errors
    /// [`ModeError`]; nothing changes on error.
    pub fn retune(&mut self, p: ModeParams<F>, h: F) -> Result<(), ModeError> {
        let fresh = Mode::<F>::new(p, h)?;
        self.params = fresh.params;
        self.update = fresh.update;
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

    /// Sets the state to exactly zero when both the displacement and the
    /// velocity over ω = 2π f_r are below `floor_m` (m); returns whether it
    /// did.
    ///
    /// An undriven mode does not decay to zero in floating point: once its
    /// amplitude is a few thousand subnormal quanta, one step's damping
    /// (1 − e^{−πf_r h/Q}, 1.6·10⁻⁵ for the bench's sub-step) is less than
    /// half a quantum and rounding sustains the oscillation for ever (the
    /// zero-input limit cycle of a recursive filter). On x86 every
    /// operation on a subnormal costs about a hundred cycles: once a mode
    /// had rung down, the virtual device could no longer keep real time
    /// (`fricctl device identify` on `fricctl sim-device` took 187 s of
    /// wall time with the simulator at 100 % of a core, 51 s with the
    /// floor, the simulator using 8 s of CPU). The plant calls this once per half-buffer with
    /// [`SUBNORMAL_FLOOR_M`](crate::plant::SUBNORMAL_FLOOR_M).
    pub fn settle_below(&mut self, floor_m: F) -> bool {
        let w = F::TAU * self.params.resonance_hz;
        let quiet = self.x.abs() < floor_m && self.v.abs() < floor_m * w;
        if quiet {
            self.x = F::ZERO;
            self.v = F::ZERO;
        }
        quiet
    }

    /// One step with the drive `u` (V) held over it; returns the new
    /// displacement, m.
    pub fn step(&mut self, u: F) -> F {
        let (x, v) = self.update.apply(self.x, self.v, u);
        self.x = x;
        self.v = v;
        x
    }
}

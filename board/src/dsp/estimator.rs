//! The friction estimator (eq. 20): `μ = Σf_x / Σf_z` over an integer number of
//! drive periods, from calibrated ADC samples taken on the DAC's timer (so each
//! sample's drive phase is the DDS accumulator of that tick), plus the first
//! harmonic (lock-in) of each force, the sample count and a saturation flag.
//!
//! Raw ADC counts are summed in `u64` (exact), so the mean force has no
//! accumulation error however long the window; the lock-in sums are the
//! counts times the block's Q15 reference ([`crate::reference`], eq. R1),
//! exact in i64 (issue 35: one integer pass per ADC block, the reference
//! shared with the pickups' lock-ins; the harmonics' error is the
//! reference's `ε_r` of eq. R2, ≤ 5.1e-5 of the amplitude, times `√2`).
//! The window opens at the
//! first accumulator wrap after [`Estimator::start`] and closes at the `n`-th
//! wrap after that.
//!
//! **Fractional edges.** Sample `k` stands for the interval `[k, k+1)` of
//! sample time. A wrap seen at sample `i` with accumulator `φ_i` and
//! increment `tw` happened `ε = φ_i/tw ∈ [0, 1)` samples before it, inside
//! the interval of sample `i − 1`: that sample counts `ε` after the boundary
//! and `1 − ε` before it. The window therefore takes sample `i₀ − 1` with
//! weight `ε₀` at its start, gives sample `i_e − 1` weight `1 − ε_e` at its
//! end, and splits the sample before each inner wrap between the two
//! batches it straddles, so that it spans exactly `n` drive periods (the
//! rectangle rule on the exact interval) also for a non-integer number of
//! samples per period. Without the edges, a window of whole samples is up to
//! one sample longer or shorter than `n` periods, and the mean of a force
//! that oscillates with amplitude `A` is off by up to `A/N` (`N` samples):
//! at 20.1 kHz (24.9 samples per period) and one period, ≈ 2 % of μ. With
//! a whole number of samples per period every `ε` is the same and the
//! weights add back to the whole-sample window. The integer sums stay
//! exact; the edge corrections are `f32` (a few per window).
//!
//! **Quality.** Each estimate carries `reasons` (bit flags, [`reasons`]; the
//! estimate is valid iff none is set) and the standard error of μ from the
//! scatter of sub-blocks (batch means): the window's periods are dealt into
//! `B = min(BATCHES, periods)` batches of whole periods (period `k` of `P`
//! goes to batch `⌊k·B/P⌋`); with `X_b`, `Z_b` the calibrated force sums of
//! batch `b`, `X = ΣX_b`, `Z = ΣZ_b` and `μ = X/Z`,
//!
//! `σ_μ = √( B/(B−1) · Σ_b (X_b − μ·Z_b)² ) / |Z|`
//!
//! (the linearised variance of a ratio of sums; with equal batches it is the
//! batch-means standard error `s_μb/√B` of the batch ratios `μ_b = X_b/Z_b`).
//! For white noise of standard deviation σ on f_x and a steady f̄_z over `N`
//! samples it tends to `σ/(f̄_z·√N)`. Fewer than two batches give `σ_μ = 0`
//! with [`reasons::FEW_PERIODS`] set.

use super::dds::SineTable;
use super::reference::{self, PairSums};
use model_core::float::{FastF32, Math};

/// Linear ADC calibration: `force = gain · (count − offset)` (N per count, counts).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Calibration {
    /// N per ADC count.
    pub gain: f32,
    /// ADC count at zero force.
    pub offset: f32,
}

/// First harmonic of a force (lock-in against the drive phase).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Harmonic {
    /// Amplitude, N.
    pub amplitude: f32,
    /// Phase φ_h of `amplitude · cos(θ + φ_h)` against the drive phase θ, rad.
    pub phase: f32,
}

/// A finished estimate.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Estimate {
    /// `μ = ⟨f_x⟩/⟨f_z⟩` (eq. 20).
    pub mu: f32,
    /// Mean tangential force, N.
    pub fx_mean: f32,
    /// Mean normal force, N.
    pub fz_mean: f32,
    /// First harmonic of f_x.
    pub fx_h1: Harmonic,
    /// First harmonic of f_z.
    pub fz_h1: Harmonic,
    /// Samples in the window.
    pub samples: u32,
    /// Drive periods in the window.
    pub periods: u32,
    /// Some sample was at the ADC's rail (0 or full scale): the estimate is suspect.
    pub saturated: bool,
    /// Standard error of `mu` from the scatter of batches (module docs).
    pub std_error: f32,
    /// Why the estimate is not valid: bits of [`reasons`] (0 = valid).
    pub reasons: u32,
}

impl Estimate {
    /// No reason against the estimate ([`Estimate::reasons`] is 0).
    pub fn valid(&self) -> bool {
        self.reasons == 0
    }
}

/// Bits of [`Estimate::reasons`]: why an estimate is not valid.
pub mod reasons {
    /// The drive was not running during part of the window.
    pub const NOT_RUNNING: u32 = 1 << 0;
    /// The drive's ramps had not settled during part of the window.
    pub const NOT_SETTLED: u32 = 1 << 1;
    /// A sample was at an ADC rail.
    pub const SATURATED: u32 = 1 << 2;
    /// Fewer than [`super::MIN_VALID_PERIODS`] periods (too few batches for
    /// the standard error).
    pub const FEW_PERIODS: u32 = 1 << 3;
    /// A fault was latched during part of the window.
    pub const FAULT: u32 = 1 << 4;

    /// Every reason with its name (as the host prints it).
    pub const NAMES: [(u32, &str); 5] = [
        (NOT_RUNNING, "not_running"),
        (NOT_SETTLED, "not_settled"),
        (SATURATED, "saturated"),
        (FEW_PERIODS, "few_periods"),
        (FAULT, "fault"),
    ];
}

/// Batches of the standard error (at most; fewer for fewer periods).
pub const BATCHES: usize = 32;

/// Fewest periods of a valid estimate (one per batch).
pub const MIN_VALID_PERIODS: u32 = BATCHES as u32;

/// Why no estimate.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum EstimateError {
    /// The window has not closed yet.
    NotReady,
    /// Zero periods requested, a calibration that is not finite / has zero
    /// gain, or a full scale other than [`reference::ADC_FULL_SCALE`] (the
    /// board's 12-bit converters).
    BadConfig,
    /// The mean normal force is not > 0 (no contact, or a wrong calibration).
    NoNormalForce,
}

impl core::fmt::Display for EstimateError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            EstimateError::NotReady => "no finished measurement",
            EstimateError::BadConfig => {
                "estimator: zero periods, a calibration that is not finite / has zero gain, or a full scale other than the 12-bit converters' 4095"
            }
            EstimateError::NoNormalForce => {
                "the mean normal force is not > 0 (no contact or a wrong calibration)"
            }
        })
    }
}

impl core::error::Error for EstimateError {}

#[derive(Debug, Clone, Copy)]
struct Sums {
    n: u32,
    raw_x: u64,
    raw_z: u64,
    /// Lock-in: Σx·c, Σx·s, Σz·c, Σz·s (counts × the Q15 reference, exact).
    tx: [i64; 4],
    /// Per batch: samples, Σ raw x, Σ raw z.
    batch: [(u32, u64, u64); BATCHES],
    /// The fractional edges (module docs): weight, Σ raw x, Σ raw z added
    /// to the window's totals …
    edge: [f32; 3],
    /// … and the lock-in totals (counts × Q15, as `tx`) …
    edge_h: [f32; 4],
    /// … and per batch.
    edge_b: [[f32; 3]; BATCHES],
}

impl Default for Sums {
    fn default() -> Self {
        Sums {
            n: 0,
            raw_x: 0,
            raw_z: 0,
            tx: [0; 4],
            batch: [(0, 0, 0); BATCHES],
            edge: [0.0; 3],
            edge_h: [0.0; 4],
            edge_b: [[0.0; 3]; BATCHES],
        }
    }
}

impl Sums {
    /// Zeroes the sums in place, field by field (the pattern names every
    /// field). `*self = Sums::default()` built the 1.2 KB on the stack and
    /// copied it: ≈ 2 700 instructions on the Cortex-M4F at `opt-level =
    /// "z"`, inside the critical section of a `Measure` or a stream's poll.
    fn clear(&mut self) {
        let Sums {
            n,
            raw_x,
            raw_z,
            tx,
            batch,
            edge,
            edge_h,
            edge_b,
        } = self;
        *n = 0;
        *raw_x = 0;
        *raw_z = 0;
        tx.fill(0);
        batch.fill((0, 0, 0));
        edge.fill(0.0);
        edge_h.fill(0.0);
        edge_b.fill([0.0; 3]);
    }
}

/// Accumulates samples into an estimate over `periods` drive periods.
#[derive(Debug, Clone)]
pub struct Estimator {
    cal_x: Calibration,
    cal_z: Calibration,
    periods: u32,
    state: State,
    sums: Sums,
    wraps: u32,
    saturated: bool,
    last_phase: u32,
    /// The last sample pushed (raw x, z): the one a wrap splits …
    last_sample: (u16, u16),
    /// … and its reference word ([`crate::reference`], eq. R1).
    last_ref: u32,
    /// Reasons that hold for the samples now being pushed ([`Estimator::set_conditions`]).
    conditions: u32,
    /// Reasons collected over the window.
    reasons: u32,
    /// Batch of the current period.
    batch: usize,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum State {
    Idle,
    WaitingForWrap,
    Running,
    Done,
}

impl Estimator {
    /// An idle estimator for ADC counts in `0..=full_scale`.
    ///
    /// # Errors
    /// [`EstimateError::BadConfig`] for a non-finite calibration or zero gain.
    pub fn new(
        cal_x: Calibration,
        cal_z: Calibration,
        full_scale: u16,
    ) -> Result<Self, EstimateError> {
        for c in [cal_x, cal_z] {
            if !(c.gain.is_finite() && c.offset.is_finite() && c.gain != 0.0) {
                return Err(EstimateError::BadConfig);
            }
        }
        // The integer sums and their rail check (`reference` module docs)
        // are those of the board's 12-bit converters.
        if full_scale != reference::ADC_FULL_SCALE {
            return Err(EstimateError::BadConfig);
        }
        Ok(Estimator {
            cal_x,
            cal_z,
            periods: 0,
            state: State::Idle,
            sums: Sums::default(),
            wraps: 0,
            saturated: false,
            last_phase: 0,
            last_sample: (0, 0),
            last_ref: 0,
            conditions: 0,
            reasons: 0,
            batch: 0,
        })
    }

    /// Starts a window of `periods` drive periods (it opens at the next wrap).
    ///
    /// # Errors
    /// [`EstimateError::BadConfig`] for 0 periods.
    pub fn start(&mut self, periods: u32) -> Result<(), EstimateError> {
        if periods == 0 {
            return Err(EstimateError::BadConfig);
        }
        self.periods = periods;
        self.state = State::WaitingForWrap;
        self.sums.clear();
        self.wraps = 0;
        self.saturated = false;
        self.reasons = 0;
        self.batch = 0;
        Ok(())
    }

    /// The [`reasons`] that hold for the samples pushed from now on (e.g. the
    /// drive is not running); each accumulated sample adds them to the
    /// estimate's reasons.
    pub fn set_conditions(&mut self, bits: u32) {
        self.conditions = bits;
    }

    /// Abandons a window (open or pending): the estimator is idle, with no
    /// estimate.
    pub fn abort(&mut self) {
        self.state = State::Idle;
    }

    /// Whether the window has closed.
    pub fn done(&self) -> bool {
        self.state == State::Done
    }

    /// Whether a window is open or pending.
    pub fn busy(&self) -> bool {
        matches!(self.state, State::WaitingForWrap | State::Running)
    }

    /// Feeds one sample: raw ADC counts of f_x and f_z taken at drive phase
    /// `phase` (the DDS accumulator of that tick). `table` gives the lock-in
    /// reference. Returns `true` when this sample closed the window (a
    /// one-sample [`Estimator::push_block`]).
    pub fn push<const N: usize>(
        &mut self,
        table: &SineTable<N>,
        phase: u32,
        x: u16,
        z: u16,
    ) -> bool {
        let w = [reference::packed(table, phase)];
        self.push_block(&w, phase, 0, &[(x, z)]).is_some()
    }

    /// Feeds a block of samples `(f_x, f_z)` (raw ADC counts) taken at the
    /// drive phases `acc0 + i·tw`, with their reference words `refs`
    /// ([`crate::reference::Reference`], eq. R1; as many as `samples`,
    /// the shorter of the two counts): the same window as one
    /// [`Estimator::push`] per sample, in one integer pass per run of
    /// samples between drive-period wraps (module docs). Returns the
    /// index of the sample that closed the window, if one did (the samples
    /// after it are not taken).
    pub fn push_block(
        &mut self,
        refs: &[u32],
        acc0: u32,
        tw: u32,
        samples: &[(u16, u16)],
    ) -> Option<usize> {
        let n = samples.len().min(refs.len());
        let mut i = 0;
        let mut phase = acc0;
        let mut closed = None;
        while i < n {
            // The boundary: sample i starts a drive period (eps of the
            // module docs: how far past the boundary it is).
            if phase < self.last_phase && closed.is_none() && self.wrap(phase) {
                closed = Some(i);
            }
            // The run up to the next wrap (none within `n` for tw = 0).
            let j = match tw {
                0 => n,
                tw => n.min(i + ((u32::MAX - phase) / tw) as usize + 1),
            };
            if closed.is_none() && self.state == State::Running {
                let sums = PairSums::of(&refs[i..j], &samples[i..j]);
                self.take(&sums, (j - i) as u32);
            }
            let k = (j - i) as u32;
            self.last_phase = phase.wrapping_add((k - 1).wrapping_mul(tw));
            self.last_sample = samples[j - 1];
            self.last_ref = refs[j - 1];
            phase = phase.wrapping_add(k.wrapping_mul(tw));
            i = j;
        }
        closed
    }

    /// A drive-period boundary at the sample of phase `phase` (the sample
    /// before is [`Estimator::last_sample`]): opens, moves a batch or
    /// closes the window. Returns `true` if it closed it.
    fn wrap(&mut self, phase: u32) -> bool {
        let eps = phase as f32 / phase.wrapping_sub(self.last_phase).max(1) as f32;
        let (prev, prev_ref) = (self.last_sample, self.last_ref);
        match self.state {
            State::Idle | State::Done => false,
            State::WaitingForWrap => {
                self.state = State::Running;
                // The sample before: ε of it is inside the window (batch 0).
                self.edge(0, eps, prev, prev_ref);
                false
            }
            State::Running => {
                self.wraps += 1;
                let old = self.batch;
                if self.wraps == self.periods {
                    // The sample before: ε of it is past the end.
                    self.edge(old, -eps, prev, prev_ref);
                    self.state = State::Done;
                    return true;
                }
                // Period k of P goes to batch ⌊k·B/P⌋ (k·B ≤ 3.2e7: no overflow).
                self.batch = (self.wraps as usize * BATCHES) / self.periods as usize;
                if self.batch != old {
                    // ε of the sample before belongs to the new batch.
                    let b = &mut self.sums.edge_b;
                    let (wx, wz) = (eps * f32::from(prev.0), eps * f32::from(prev.1));
                    b[old][0] -= eps;
                    b[old][1] -= wx;
                    b[old][2] -= wz;
                    b[self.batch][0] += eps;
                    b[self.batch][1] += wx;
                    b[self.batch][2] += wz;
                }
                false
            }
        }
    }

    /// Adds a run's sums (`len` samples) to the window and its batch.
    fn take(&mut self, p: &PairSums, len: u32) {
        if p.railed {
            self.saturated = true;
        }
        self.reasons |= self.conditions;
        let s = &mut self.sums;
        s.n += len;
        s.raw_x += p.p[0] as u64;
        s.raw_z += p.p[1] as u64;
        let b = &mut s.batch[self.batch];
        b.0 += len;
        b.1 += p.p[0] as u64;
        b.2 += p.p[1] as u64;
        s.tx[0] += p.pc[0];
        s.tx[1] += p.ps[0];
        s.tx[2] += p.pc[1];
        s.tx[3] += p.ps[1];
    }

    /// Whether a sample of the window so far sat at a rail (what the
    /// estimate's `saturated` will say).
    pub fn saturated(&self) -> bool {
        self.saturated
    }

    /// Adds `w` (±ε) of sample `prev` (raw x, z; its reference word
    /// `r`) to the window's totals, its lock-in and batch `b`.
    fn edge(&mut self, b: usize, w: f32, prev: (u16, u16), r: u32) {
        if w == 0.0 {
            return;
        }
        let (x, z) = (w * f32::from(prev.0), w * f32::from(prev.1));
        let s = &mut self.sums;
        s.edge[0] += w;
        s.edge[1] += x;
        s.edge[2] += z;
        let (cs, sn) = (reference::cos_of(r) as f32, reference::sin_of(r) as f32);
        s.edge_h[0] += x * cs;
        s.edge_h[1] += x * sn;
        s.edge_h[2] += z * cs;
        s.edge_h[3] += z * sn;
        s.edge_b[b][0] += w;
        s.edge_b[b][1] += x;
        s.edge_b[b][2] += z;
    }

    /// The estimate of the closed window.
    ///
    /// # Errors
    /// [`EstimateError::NotReady`] before the window closes,
    /// [`EstimateError::NoNormalForce`] if ⟨f_z⟩ ≤ 0.
    pub fn estimate(&self) -> Result<Estimate, EstimateError> {
        let m = self.mu_estimate()?;
        let s = &self.sums;
        // Lock-in: f ≈ A cos(θ + φ) ⇒ Σ f cos θ = (n/2) A cos φ, Σ f sin θ = −(n/2) A sin φ.
        // The DC offset in counts drops out over whole periods. The totals
        // are counts × Q15 (exact, plus the f32 edges), the result f32 (the
        // f32 backend, FastF32: a few ulps; the solver's too, one copy in
        // the firmware): f32 throughout, ≈ 1e-7 of the amplitude.
        let h = |c: i64, ce: f32, sn: i64, se: f32, gain: f32| {
            let k = 2.0 / (m.weight * 32_768.0) * gain;
            let re = (c as f32 + ce) * k;
            let im = -(sn as f32 + se) * k;
            Harmonic {
                amplitude: FastF32::hypot(re, im),
                phase: FastF32::atan2(im, re),
            }
        };
        Ok(Estimate {
            fx_h1: h(s.tx[0], s.edge_h[0], s.tx[1], s.edge_h[1], self.cal_x.gain),
            fz_h1: h(s.tx[2], s.edge_h[2], s.tx[3], s.edge_h[3], self.cal_z.gain),
            ..m.estimate
        })
    }

    /// The closed window's μ, mean forces, standard error and reasons — the
    /// [`Estimator::estimate`] without the harmonics (zero here), which is
    /// all the μ loop uses (issue 35: the harmonics' two `hypot`s and
    /// `atan2`s stay out of its update).
    ///
    /// # Errors
    /// As [`Estimator::estimate`].
    pub fn estimate_mu(&self) -> Result<Estimate, EstimateError> {
        self.mu_estimate().map(|m| m.estimate)
    }

    /// μ and the means from the exact integer sums with no soft-float f64
    /// (issue 35: ≈ 1 900 instructions of soft-float on the M4 before):
    /// each signal's sum is first taken about an integer `k` near its zero
    /// offset, in i64, exactly,
    ///
    /// ```text
    /// D = Σcounts − n·k,   δ = (D + e₁ − e₀·k)/W,   ⟨f⟩ = g·(δ − (o − k))       (E2)
    /// ```
    ///
    /// (`W = n + e₀` the window's weight with its fractional edges `e₀`, `e₁`
    /// the edges' weighted counts; `o` the calibration's offset, `g` its
    /// gain), so the large common part `n·k` never meets a float: `D` is
    /// exact before its one rounding to f32, and δ, the mean count above
    /// `k`, is a number of counts near the force's own (tens), rounded at
    /// ≈ 6e-8 of itself. μ = ⟨f_x⟩/⟨f_z⟩ is then within a few f32 roundings
    /// of the exact ratio of the sums (≈ 4e-7 relative; the f64 path's μ
    /// was rounded to f32 for the answer too). The means the standard error
    /// takes are `k + δ`, in Q16 as `k·2¹⁶ + round(δ·2¹⁶)`
    /// ([`Estimator::std_error`]).
    fn mu_estimate(&self) -> Result<MuEstimate, EstimateError> {
        if self.state != State::Done || self.sums.n == 0 {
            return Err(EstimateError::NotReady);
        }
        let s = &self.sums;
        let w = s.n as f32 + s.edge[0];
        // (E2) for one signal: (k, δ) of its sum `raw` and edge sum `e1`
        // about the integer `k` nearest below its offset.
        let about = |raw: u64, e1: f32, offset: f32| {
            let k = offset as i32;
            let d = raw as i64 - i64::from(s.n) * i64::from(k);
            let delta = (d as f32 + (e1 - s.edge[0] * k as f32)) / w;
            (k, delta, delta - (offset - k as f32))
        };
        let (kx, dx, ax) = about(s.raw_x, s.edge[1], self.cal_x.offset);
        let (kz, dz, az) = about(s.raw_z, s.edge[2], self.cal_z.offset);
        let fx = self.cal_x.gain * ax;
        let fz = self.cal_z.gain * az;
        if fz.is_nan() || fz <= 0.0 {
            return Err(EstimateError::NoNormalForce);
        }
        let mu = fx / fz;
        let std_error = self.std_error(mu, [(kx, dx), (kz, dz)], w * fz);
        let mut reasons = self.reasons;
        if self.saturated {
            reasons |= reasons::SATURATED;
        }
        if self.periods < MIN_VALID_PERIODS {
            reasons |= reasons::FEW_PERIODS;
        }
        let none = Harmonic {
            amplitude: 0.0,
            phase: 0.0,
        };
        Ok(MuEstimate {
            weight: w,
            estimate: Estimate {
                mu,
                fx_mean: fx,
                fz_mean: fz,
                fx_h1: none,
                fz_h1: none,
                samples: s.n,
                periods: self.periods,
                saturated: self.saturated,
                std_error,
                reasons,
            },
        })
    }

    /// `σ_μ = √(B/(B−1)·Σ(X_b − μZ_b)²)/|Z|` over the non-empty batches
    /// (module docs); 0 for fewer than two. `means` are the window's mean
    /// counts that `μ` was formed from, as `(k, δ)`: `m = k + δ` (eq. E2),
    /// `z` the window's calibrated normal sum `Z = W·⟨f_z⟩`. Each batch's
    /// residual is formed from its deviations from the window's means,
    /// `d = S_b − W_b·m` (counts; the integer part exact in i64 with the
    /// means in Q16, the edges in f32), as
    ///
    /// ```text
    /// X_b − μ·Z_b = g_x·d_x − μ·g_z·d_z                             (E1)
    /// ```
    ///
    /// — exact, because `g_x(m_x − o_x) = μ·g_z(m_z − o_z)` defines μ — so
    /// the calibrated sums' large common part never meets f32 (issue 35:
    /// per batch a few integer and f32 operations, not soft-float f64).
    fn std_error(&self, mu: f32, means: [(i32, f32); 2], z: f32) -> f32 {
        let q16 = |(k, delta): (i32, f32)| {
            let x = delta * 65_536.0;
            (i64::from(k) << 16) + (if x >= 0.0 { x + 0.5 } else { x - 0.5 }) as i64
        };
        let (qx, qz) = (q16(means[0]), q16(means[1]));
        let m = |(k, delta): (i32, f32)| k as f32 + delta;
        let (mx, mz) = (m(means[0]), m(means[1]));
        let (gx, gz, muf) = (self.cal_x.gain, self.cal_z.gain, mu);
        let (mut used, mut sum_sq) = (0u32, 0.0f32);
        let edges = self.sums.edge_b.iter();
        for (&(n, rx, rz), e) in self.sums.batch.iter().zip(edges).filter(|b| b.0 .0 > 0) {
            let dev = |r: u64, q: i64, m: f32, e_sum: f32| {
                let whole = ((r as i64) << 16) - i64::from(n) * q;
                whole as f32 * (1.0 / 65_536.0) + (e_sum - e[0] * m)
            };
            let (dx, dz) = (dev(rx, qx, mx, e[1]), dev(rz, qz, mz, e[2]));
            let r = gx * dx - muf * gz * dz;
            used += 1;
            sum_sq += r * r;
        }
        if used < 2 || z == 0.0 {
            return 0.0;
        }
        let b = used as f32;
        // The root in f32 (FastF32, relative error a few ulps).
        FastF32::sqrt(b / (b - 1.0) * sum_sq) / z.abs()
    }
}

/// [`Estimator::mu_estimate`]'s result: the estimate without harmonics
/// and the window's weight `W` (samples with the fractional edges).
struct MuEstimate {
    weight: f32,
    estimate: Estimate,
}

//! The virtual plant's transducers: ideal (the DAC level times the
//! calibration, today's board assumption) or resonant modes
//! ([`board::plant::Resonant`]: f_r, Q, static gain, drift,
//! self-heating, cross-talk, the contact's load), shared by
//! `fricctl sim-device`, `fricctl device --sim` and `device control-bench`.
//!
//! **Defaults of the resonant plant** (the bench: a Langevin pair
//! near 20 kHz): normal mode 20 300 Hz, Q 300; tangential 19 700 Hz, Q 200;
//! static gains a thirtieth of the board's ideal calibration
//! (`metres_per_code / DAC_VOLTS_PER_CODE / 30`: 8.27e-8 m/V normal,
//! 4.14e-8 m/V tangential), so that driven at 20 kHz (1.5 % off both
//! resonances) the amplitudes come out near the calibration (×1.13 and
//! ×1.07) but the phases lag by 6.4° and 170°: φ between the modes is off
//! by ≈ 164°, the paper's control variable on the wrong side. No drift,
//! heating or cross-talk unless asked; the load 1/Q_load = 1/2000.
//!
//! **The virtual device's default is resonant** (`sim-device`, `device
//! --sim`): users test against the default, and the board now identifies
//! its transducers (`device identify`) and commands displacements.
//! `--plant-ideal-transducers` gives the ideal ones (and refuses the
//! resonant flags). `device control-bench` is resonant by default too (its
//! loop runs on the displacement loops; `--plant-ideal-transducers` for the
//! ideal pipeline).

use board::plant::ResonantOptions;
use board::resonator::ModeParams;

use fric_analysis::numbers::{short, Real};

use crate::{Error, Result};

pub use board::plant::bench::{LOAD_Q, Q_X, Q_Z, RESONANCE_X_HZ, RESONANCE_Z_HZ};

/// Default static gain of a channel, m/V: a thirtieth of the ideal
/// calibration `metres_per_code` per DAC volt (module documentation).
pub fn default_gain(metres_per_code: f32) -> f64 {
    board::plant::bench::gain(metres_per_code)
}

/// The domain of a transducer's Q (`--plant-q-z`, `--plant-q-x`,
/// `--plant-load-q` without `inf`).
pub const Q_DOMAIN: Real = Real::ANY
    .above(0.5)
    .at_most(1e6)
    .because("a resonance with Q ≤ 0.5 does not ring; the device's model holds Q ≤ 1e6");

/// The domain of a resonance, Hz: what the device's transducer model holds
/// (`board::device::displacement::check_model`: 0 < f_r ≤ 10 MHz, in `f32`),
/// so that the plant's identification can be stored.
pub const RESONANCE: Real = Real::positive()
    .at_most(1e7)
    .because("the device's transducer model holds up to 10 MHz")
    .single_precision();
/// The domain of a static gain, m/V: as the device's model (0 < g ≤ 1).
pub const GAIN: Real = Real::positive()
    .at_most(1.0)
    .because("the device's transducer model holds up to 1 m/V")
    .single_precision();
/// The domain of a drift (Hz/s) and of the self-heating shift (Hz/µm²).
pub const ANY: Real = Real::ANY;
/// The domain of the cross-talk: a fraction of the other channel's drive.
pub const CROSSTALK: Real = Real::ANY
    .above(-1.0)
    .below(1.0)
    .because("a fraction of the other channel's drive");
/// The domain of the contact's load as a Q (`inf` for none).
pub const LOAD_Q_DOMAIN: Real = Real::positive().or_infinity().because("inf for no load");

/// The transducers asked for: each field is a flag of `fricctl` (named in
/// errors), `None` for the default (module documentation).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct TransducerSpec {
    /// Virtual plant: ideal transducers (displacement = DAC level × calibration) instead of the default resonant ones; refuses the resonant flags
    pub plant_ideal_transducers: bool,
    /// Virtual plant: resonance of the normal transducer, Hz (resonant plant; default 20300)
    pub plant_resonance_z: Option<f64>,
    /// Virtual plant: Q of the normal transducer (> 0.5; default 300)
    pub plant_q_z: Option<f64>,
    /// Virtual plant: resonance of the tangential transducer, Hz (default 19700)
    pub plant_resonance_x: Option<f64>,
    /// Virtual plant: Q of the tangential transducer (> 0.5; default 200)
    pub plant_q_x: Option<f64>,
    /// Virtual plant: static gain of the normal transducer, m per DAC volt (default 8.27e-8)
    pub plant_gain_z: Option<f64>,
    /// Virtual plant: static gain of the tangential transducer, m per DAC volt (default 4.14e-8)
    pub plant_gain_x: Option<f64>,
    /// Virtual plant: drift of the normal resonance, Hz per second of device time (default 0)
    pub plant_resonance_drift_z: Option<f64>,
    /// Virtual plant: drift of the tangential resonance, Hz/s (default 0)
    pub plant_resonance_drift_x: Option<f64>,
    /// Virtual plant: self-heating shift of each resonance per squared amplitude, Hz/µm² (thermal time 1 s; default 0)
    pub plant_thermal_shift: Option<f64>,
    /// Virtual plant: fraction of each channel's drive that also drives the other transducer (|c| < 1; default 0)
    pub plant_crosstalk: Option<f64>,
    /// Virtual plant: the contact's load as damping, 1/Q_eff = 1/Q + 1/Q_load (> 0, `inf` for none; default 2000)
    pub plant_load_q: Option<f64>,
}

impl TransducerSpec {
    /// The resonant options, or `None` for ideal transducers, with the
    /// calibrations `(metres_per_code_z, metres_per_code_x)` for the
    /// default gains.
    ///
    /// # Errors
    /// One line naming the flag out of its domain, or the ideal flag given
    /// with resonant ones.
    pub fn options(
        &self,
        cal: (f32, f32),
        default_resonant: bool,
    ) -> Result<Option<ResonantOptions<f64>>> {
        let given: Vec<&str> = [
            (self.plant_resonance_z, "--plant-resonance-z"),
            (self.plant_q_z, "--plant-q-z"),
            (self.plant_resonance_x, "--plant-resonance-x"),
            (self.plant_q_x, "--plant-q-x"),
            (self.plant_gain_z, "--plant-gain-z"),
            (self.plant_gain_x, "--plant-gain-x"),
            (self.plant_resonance_drift_z, "--plant-resonance-drift-z"),
            (self.plant_resonance_drift_x, "--plant-resonance-drift-x"),
            (self.plant_thermal_shift, "--plant-thermal-shift"),
            (self.plant_crosstalk, "--plant-crosstalk"),
            (self.plant_load_q, "--plant-load-q"),
        ]
        .iter()
        .filter(|(v, _)| v.is_some())
        .map(|(_, n)| *n)
        .collect();
        if given.is_empty() && (self.plant_ideal_transducers || !default_resonant) {
            return Ok(None);
        }
        if self.plant_ideal_transducers {
            return Err(Error::usage(format!(
                "--plant-ideal-transducers: cannot be used with {} (a resonant plant)",
                given[0]
            )));
        }
        self.check()?;
        let fz = self.plant_resonance_z.unwrap_or(RESONANCE_Z_HZ);
        let fx = self.plant_resonance_x.unwrap_or(RESONANCE_X_HZ);
        let qz = self.plant_q_z.unwrap_or(Q_Z);
        let qx = self.plant_q_x.unwrap_or(Q_X);
        let gz = self.plant_gain_z.unwrap_or(default_gain(cal.0));
        let gx = self.plant_gain_x.unwrap_or(default_gain(cal.1));
        let dz = self.plant_resonance_drift_z.unwrap_or(0.0);
        let dx = self.plant_resonance_drift_x.unwrap_or(0.0);
        let th = self.plant_thermal_shift.unwrap_or(0.0);
        let ct = self.plant_crosstalk.unwrap_or(0.0);
        let load_q = self.plant_load_q.unwrap_or(LOAD_Q);
        // The loaded Q of each mode, 1/Q_eff = 1/Q + 1/Q_load, must still
        // ring: a plant that would not is refused, never made ideal.
        for (q, flag) in [(qz, "--plant-q-z"), (qx, "--plant-q-x")] {
            let q_eff = 1.0 / (1.0 / q + 1.0 / load_q);
            if q_eff <= 0.5 {
                let flag = if self.plant_load_q.is_some() {
                    "--plant-load-q"
                } else {
                    flag
                };
                return Err(Error::usage(format!(
                    "{flag}: the loaded Q 1/(1/Q + 1/Q_load) = {} must be > 0.5 (a resonance with Q ≤ 0.5 does not ring)",
                    short(q_eff)
                )));
            }
        }
        Ok(Some(ResonantOptions {
            modes: [
                ModeParams {
                    resonance_hz: fz,
                    q: qz,
                    gain_m_per_v: gz,
                },
                ModeParams {
                    resonance_hz: fx,
                    q: qx,
                    gain_m_per_v: gx,
                },
            ],
            drift_hz_per_s: [dz, dx],
            thermal_hz_per_um2: th,
            crosstalk: ct,
            load_q,
        }))
    }
}

impl TransducerSpec {
    /// Each given value within its domain, named by its flag.
    fn check(&self) -> Result<()> {
        let fields = [
            (self.plant_resonance_z, "--plant-resonance-z", RESONANCE),
            (self.plant_q_z, "--plant-q-z", Q_DOMAIN),
            (self.plant_resonance_x, "--plant-resonance-x", RESONANCE),
            (self.plant_q_x, "--plant-q-x", Q_DOMAIN),
            (self.plant_gain_z, "--plant-gain-z", GAIN),
            (self.plant_gain_x, "--plant-gain-x", GAIN),
            (
                self.plant_resonance_drift_z,
                "--plant-resonance-drift-z",
                ANY,
            ),
            (
                self.plant_resonance_drift_x,
                "--plant-resonance-drift-x",
                ANY,
            ),
            (self.plant_thermal_shift, "--plant-thermal-shift", ANY),
            (self.plant_crosstalk, "--plant-crosstalk", CROSSTALK),
            (self.plant_load_q, "--plant-load-q", LOAD_Q_DOMAIN),
        ];
        for (v, flag, domain) in fields {
            if let Some(x) = v {
                domain
                    .check(x, &short(x))
                    .map_err(|r| Error::usage(format!("{flag}: {r}")))?;
            }
        }
        Ok(())
    }
}

//! The virtual plant's flags (`fricctl sim-device`, `fricctl device --sim`,
//! `device control-bench`): clap's front end of
//! [`device_host::virtual_device::PlantSpec`] and
//! [`device_host::transducers::TransducerSpec`], which check the values and
//! build the plant.

use device_host::transducers::{self as tr, TransducerSpec};
use device_host::virtual_device::{self as vd, PlantOptions, PlantSpec, DEFAULT_CONTACT};

use crate::args::Real;
use crate::error::CliResult;

/// The plant's flags, shared by `fricctl sim-device` and `fricctl device --sim`.
#[derive(clap::Args, Debug, Clone)]
pub struct PlantArgs {
    /// Virtual plant: true μ0 (the device's model keeps its own, see `scene`)
    #[arg(long, default_value_t = DEFAULT_CONTACT.0, value_parser = Real(vd::PLANT_CONTACT))]
    pub plant_mu0: f64,
    /// Virtual plant: true k_z, N/m
    #[arg(long, default_value_t = DEFAULT_CONTACT.1, value_parser = Real(vd::PLANT_CONTACT))]
    pub plant_kz: f64,
    /// Virtual plant: true k_x, N/m
    #[arg(long, default_value_t = DEFAULT_CONTACT.2, value_parser = Real(vd::PLANT_CONTACT))]
    pub plant_kx: f64,
    /// Virtual plant: ideal transducers whose displacement amplitudes follow with a first-order lag, time constant in drive periods (0 = none; non-zero implies ideal transducers)
    #[arg(long, default_value_t = 0.0, value_parser = Real(vd::LAG_PERIODS))]
    pub plant_lag_periods: f64,
    /// Virtual plant: drift of μ0, per second of device time (μ0 stops at 0)
    #[arg(long, default_value_t = 0.0, value_parser = Real(vd::MU0_DRIFT))]
    pub plant_mu0_drift: f64,
    /// Virtual plant: stage velocity profile, CSV `t_s,v0_m_s` (header line, t strictly increasing), piecewise linear in device time, held outside; replaces the constant velocity
    #[arg(long, value_name = "FILE")]
    pub v0_profile: Option<std::path::PathBuf>,
    /// The transducers: ideal or resonant.
    #[command(flatten)]
    pub transducers: TransducerArgs,
}

impl PlantArgs {
    /// The plant the flags ask for.
    pub fn spec(&self) -> PlantSpec {
        PlantSpec {
            plant_mu0: self.plant_mu0,
            plant_kz: self.plant_kz,
            plant_kx: self.plant_kx,
            plant_lag_periods: self.plant_lag_periods,
            plant_mu0_drift: self.plant_mu0_drift,
            v0_profile: self.v0_profile.clone(),
            transducers: self.transducers.spec(),
        }
    }

    /// The checked plant options ([`PlantSpec::options`]).
    ///
    /// # Errors
    /// One line naming the flag.
    pub fn options(
        &self,
        v0: f64,
        noise: f64,
        offset: f64,
        names: [&str; 3],
    ) -> CliResult<PlantOptions> {
        self.spec().options(v0, noise, offset, names)
    }
}

/// The transducer flags.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct TransducerArgs {
    /// Virtual plant: ideal transducers (displacement = DAC level × calibration) instead of the default resonant ones; refuses the resonant flags
    #[arg(long)]
    pub plant_ideal_transducers: bool,
    /// Virtual plant: resonance of the normal transducer, Hz (resonant plant; default 20300)
    #[arg(long, value_name = "HZ", value_parser = Real(tr::RESONANCE))]
    pub plant_resonance_z: Option<f64>,
    /// Virtual plant: Q of the normal transducer (> 0.5; default 300)
    #[arg(long, value_name = "Q", value_parser = Real(tr::Q_DOMAIN))]
    pub plant_q_z: Option<f64>,
    /// Virtual plant: resonance of the tangential transducer, Hz (default 19700)
    #[arg(long, value_name = "HZ", value_parser = Real(tr::RESONANCE))]
    pub plant_resonance_x: Option<f64>,
    /// Virtual plant: Q of the tangential transducer (> 0.5; default 200)
    #[arg(long, value_name = "Q", value_parser = Real(tr::Q_DOMAIN))]
    pub plant_q_x: Option<f64>,
    /// Virtual plant: static gain of the normal transducer, m per DAC volt (default 8.27e-8)
    #[arg(long, value_name = "M_PER_V", value_parser = Real(tr::GAIN))]
    pub plant_gain_z: Option<f64>,
    /// Virtual plant: static gain of the tangential transducer, m per DAC volt (default 4.14e-8)
    #[arg(long, value_name = "M_PER_V", value_parser = Real(tr::GAIN))]
    pub plant_gain_x: Option<f64>,
    /// Virtual plant: drift of the normal resonance, Hz per second of device time (default 0)
    #[arg(long, value_name = "HZ_PER_S", value_parser = Real(tr::ANY))]
    pub plant_resonance_drift_z: Option<f64>,
    /// Virtual plant: drift of the tangential resonance, Hz/s (default 0)
    #[arg(long, value_name = "HZ_PER_S", value_parser = Real(tr::ANY))]
    pub plant_resonance_drift_x: Option<f64>,
    /// Virtual plant: self-heating shift of each resonance per squared amplitude, Hz/µm² (thermal time 1 s; default 0)
    #[arg(long, value_name = "HZ_PER_UM2", value_parser = Real(tr::ANY))]
    pub plant_thermal_shift: Option<f64>,
    /// Virtual plant: fraction of each channel's drive that also drives the other transducer (|c| < 1; default 0)
    #[arg(long, value_name = "FRACTION", value_parser = Real(tr::CROSSTALK))]
    pub plant_crosstalk: Option<f64>,
    /// Virtual plant: the contact's load as damping, 1/Q_eff = 1/Q + 1/Q_load (> 0, `inf` for none; default 2000; the loaded Q must stay > 0.5)
    #[arg(long, value_name = "Q", value_parser = Real(tr::LOAD_Q_DOMAIN))]
    pub plant_load_q: Option<f64>,
}

impl TransducerArgs {
    /// The transducers the flags ask for.
    pub fn spec(&self) -> TransducerSpec {
        TransducerSpec {
            plant_ideal_transducers: self.plant_ideal_transducers,
            plant_resonance_z: self.plant_resonance_z,
            plant_q_z: self.plant_q_z,
            plant_resonance_x: self.plant_resonance_x,
            plant_q_x: self.plant_q_x,
            plant_gain_z: self.plant_gain_z,
            plant_gain_x: self.plant_gain_x,
            plant_resonance_drift_z: self.plant_resonance_drift_z,
            plant_resonance_drift_x: self.plant_resonance_drift_x,
            plant_thermal_shift: self.plant_thermal_shift,
            plant_crosstalk: self.plant_crosstalk,
            plant_load_q: self.plant_load_q,
        }
    }
}

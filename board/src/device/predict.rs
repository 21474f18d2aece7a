//! The model's prediction for the current drive: μ at a sliding velocity
//! (exact solver, f32) and the regime (§3.2). A drive that lifts the contact
//! off (`a = Δu_z/u_z0 ≥ 1`, only accepted while lift-off is allowed) is
//! answered by the lift-off model ([`model_core::model::liftoff`], f32, FastF32).

use super::config::MAX_VELOCITY_M_S;
use super::{in_range, Device, DeviceError, DriveParam, Prediction, SceneInputs};
use model_core::analytic::StaticFriction;
use model_core::exact::{self, Solution};
use model_core::float::FastF32;
use model_core::model::liftoff;
use model_core::regime::{classify_drive, ClassifyOptions, Regime};
use model_core::scene::{Scene, SceneParams};

impl<const N: usize> Device<'_, N> {
    /// The model's μ at sliding velocity `v0` (m/s) for the current drive
    /// (f32, exact solver).
    ///
    /// # Errors
    /// [`DeviceError::OutOfRange`] for a non-finite velocity, [`DeviceError::Scene`], [`DeviceError::Model`].
    pub fn predict(&self, v0: f32) -> Result<Prediction, DeviceError> {
        predict(&self.scene()?, v0)
    }

    /// The parameters of the scene a prediction uses (a copy: the server
    /// forms the scene, [`super::SceneInputs::scene`], with the device
    /// released): while the drive runs in displacement mode and holds
    /// ([`Device::drive_settled`]), the *measured* drive (the pickups' Δu_z,
    /// Δu_x and φ as [`Device::status`] reports them, averaged over
    /// `displacement::SMOOTHING_S`, with the setting's offset and the DDS
    /// frequency); while tracking, the accepted drive at the frequency that
    /// runs; otherwise [`Device::scene_inputs`].
    pub fn prediction_inputs(&self) -> SceneInputs {
        // The status' measured drive: smoothed over 1 ms in this mode.
        match self.status().measured {
            Some(m) if self.running && self.displacement_mode() && self.drive_settled() => {
                let d = self.drive();
                self.scene_inputs_with(SceneParams {
                    mu0: self.contact.mu0,
                    kz: self.contact.kz,
                    kx: self.contact.kx,
                    uz0: d.offset_z_m,
                    duz: m.amp_z_m,
                    dux: m.amp_x_m,
                    omega: (core::f64::consts::TAU * self.applied.achieved.freq_hz) as f32,
                    phi: m.phase_rad,
                })
            }
            // While tracking, the scene at the frequency that runs (the
            // stored one holds the setting's).
            _ if self.tracking_active() => self.live_scene_inputs(),
            _ => self.scene_inputs(),
        }
    }

    /// The regime of the current drive.
    ///
    /// # Errors
    /// As [`Device::predict`].
    pub fn regime(&self) -> Result<Regime, DeviceError> {
        regime(&self.scene()?)
    }
}

/// The model's μ at `v0` (m/s) for a scene (what [`Device::predict`] computes;
/// callable on a snapshot outside the device's critical section).
///
/// # Errors
/// [`DeviceError::OutOfRange`] for a velocity that is not finite or beyond
/// ±[`MAX_VELOCITY_M_S`], [`DeviceError::Model`], [`DeviceError::LiftOffModel`].
pub fn predict(s: &Scene<f32>, v0: f32) -> Result<Prediction, DeviceError> {
    in_range(
        v0,
        -MAX_VELOCITY_M_S,
        MAX_VELOCITY_M_S,
        DriveParam::Velocity,
    )?;
    if s.drive().a >= 1.0 {
        // Intermittent contact: μ(0) is unique, the law continuous at rest.
        let m = liftoff::solve_with::<f32, FastF32>(s, v0).map_err(DeviceError::LiftOffModel)?;
        let (cf, cb) = liftoff::critical_velocities::<f32, FastF32>(&s.drive())
            .map_err(DeviceError::LiftOffModel)?;
        let scale = s.velocity_scale();
        return Ok(Prediction {
            mu_over_mu0: m,
            mu: m * s.mu0(),
            vc: (cf * scale, cb * scale),
            mu_0minus_over_mu0: m,
            liftoff: true,
        });
    }
    let (solution, vc) =
        exact::solve_with_critical::<f32, FastF32>(s, v0).map_err(DeviceError::Model)?;
    let (m, m_minus) = match solution {
        Solution::Sliding { mu_over_mu0 } | Solution::StickSlip { mu_over_mu0 } => {
            (mu_over_mu0, mu_over_mu0)
        }
        Solution::AtRest {
            mu_0plus,
            mu_0minus,
            ..
        } => (mu_0plus, mu_0minus),
    };
    Ok(Prediction {
        mu_over_mu0: m,
        mu: m * s.mu0(),
        vc: (vc.forward, vc.backward),
        mu_0minus_over_mu0: m_minus,
        liftoff: false,
    })
}

/// The regime of a scene (what [`Device::regime`] computes; for a lift-off
/// drive [`liftoff::regime::classify`]), with the same
/// f32 backend as [`predict`] ([`FastF32`]: one copy of the solver in flash).
///
/// # Errors
/// [`DeviceError::Model`].
pub fn regime(s: &Scene<f32>) -> Result<Regime, DeviceError> {
    if s.drive().a >= 1.0 {
        return liftoff::regime::classify::<f32, FastF32>(&s.drive(), &ClassifyOptions::default())
            .map(|c| c.regime)
            .map_err(DeviceError::LiftOffModel);
    }
    classify_drive::<f32, FastF32>(
        &s.drive(),
        StaticFriction::of_with::<FastF32>(s),
        &ClassifyOptions::default(),
    )
    .map(|c| c.regime)
    .map_err(DeviceError::Model)
}

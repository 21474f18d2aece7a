//! The reference for a device's lift-off prediction: the fixed-step scheme
//! with exact landing (`liftoff::stepping`, f64, 20 000 steps per period) on
//! the device's own f32 scene, rebuilt from `device drive get --json`.

use model_core::model::liftoff;
use model_core::scene::ContactMode;
use model_core::{Drive, FastF32, Libm, Scene, SceneParams};
use serde_json::Value;

/// `(μ/μ0, tolerance)` for `predict --v0 V0` of a device with the contact
/// μ0 = 0.3, k_z = k_x = 10⁷ N/m and the drive `drive` (`drive get --json`):
/// f32 inputs as the device forms them (ω from the achieved frequency, φ the
/// achieved phase). Tolerance: the stepping's stated bound + the f32 lift-off
/// solver's stated bound with FastF32 (`liftoff::error_bound`), + 1e-6 for the
/// f32 rounding of μ0 = 0.3 and of the printed value (shortest f32 form).
pub fn reference(drive: &Value, v0: f64) -> (f64, f64) {
    let f32_of = |v: &Value| f64::from(v.as_f64().unwrap() as f32);
    let omega =
        f64::from((std::f64::consts::TAU * drive["freq_achieved"].as_f64().unwrap()) as f32);
    let phi = f64::from(drive["phi_achieved_deg"].as_f64().unwrap().to_radians() as f32);
    let scene = Scene::new_with_contact(
        SceneParams {
            mu0: 0.3,
            kz: 1e7,
            kx: 1e7,
            uz0: f32_of(&drive["uz0"]),
            duz: f32_of(&drive["duz"]),
            dux: f32_of(&drive["dux"]),
            omega,
            phi,
        },
        ContactMode::Intermittent,
    )
    .unwrap();
    let d = scene.drive();
    let d32 = Drive::new::<Libm>(d.a as f32, d.b as f32, phi as f32);
    let dev_bound = f64::from(liftoff::error_bound::<f32, FastF32>(&d32));
    let r = liftoff::stepping::mu_over_mu0::<f64, Libm>(&d, v0 / scene.velocity_scale(), 20_000)
        .unwrap();
    (r.mu_over_mu0, r.error_bound + dev_bound + 1e-6)
}

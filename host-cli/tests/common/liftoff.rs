//! The reference for a device's lift-off prediction: the fixed-step scheme
//! with exact landing (`liftoff::stepping`, f64, 20 000 steps per period) on
//! the device's own f32 scene, rebuilt from `device drive get --json`.

use model_core::model::liftoff;
use model_core::scene::ContactMode;
use model_core::{Drive, FastF32, Libm, Scene, SceneParams};
use serde_json::Value;

/// `(μ/μ0, tolerance)` for `predict --v0 V0` of a device with the contact
/// μ0 = 0.3, k_z = k_x = 10⁷ N/m and the drive `drive` (`drive get --json`).
///
/// The device forms its scene in f32 (`Scene::<f32>::new_with_contact`, ω
/// from the achieved frequency, φ the achieved phase) and solves it with the
/// f32 lift-off solver (FastF32). The reference forms the same f32 scene
/// here, takes its f32 drive and velocity exactly into f64, and runs the
/// stepping in f64 on them: the two differ only by the f32 solver's
/// arithmetic. Tolerance: the stepping's stated bound, the f32 solver's
/// stated bound (`liftoff::error_bound::<f32, FastF32>`), half an f32 ulp of
/// μ/μ0 (the device's f32 result printed in its shortest form), and the
/// spread of the reference over φ₃₂ ± one f32 ulp (the phase reaches the
/// JSON in degrees, computed from the device's radians in f64: the round
/// trip can move the f32 phase by one ulp).
pub fn reference(drive: &Value, v0: f64) -> (f64, f64) {
    let f32_of = |v: &Value| v.as_f64().unwrap() as f32;
    let omega = (std::f64::consts::TAU * drive["freq_achieved"].as_f64().unwrap()) as f32;
    let phi = drive["phi_achieved_deg"].as_f64().unwrap().to_radians() as f32;
    let run = |phi: f32| {
        let scene = Scene::<f32>::new_with_contact(
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
        let d32 = scene.drive();
        let v32 = scene.dimensionless_velocity(v0 as f32).unwrap();
        let d = Drive {
            a: f64::from(d32.a),
            b: f64::from(d32.b),
            bc: f64::from(d32.bc),
            bs: f64::from(d32.bs),
        };
        let r = liftoff::stepping::mu_over_mu0::<f64, Libm>(&d, f64::from(v32), 20_000).unwrap();
        let dev_bound = f64::from(liftoff::error_bound::<f32, FastF32>(&d32));
        (r.mu_over_mu0, r.error_bound + dev_bound)
    };
    let (mu, bounds) = run(phi);
    // The f32 neighbours of x (the smallest subnormals either side of 0).
    let ulp = |x: f32, up: bool| {
        if x == 0.0 {
            let tiny = f32::from_bits(1);
            return if up { tiny } else { -tiny };
        }
        let bits = x.to_bits();
        f32::from_bits(if up == (x > 0.0) { bits + 1 } else { bits - 1 })
    };
    let spread = [ulp(phi, true), ulp(phi, false)]
        .into_iter()
        .map(|p| (run(p).0 - mu).abs())
        .fold(0.0, f64::max);
    let half_ulp_mu = f64::from(f32::EPSILON) * mu.abs().max(f64::from(f32::MIN_POSITIVE)) / 2.0;
    (mu, bounds + half_ulp_mu + spread)
}

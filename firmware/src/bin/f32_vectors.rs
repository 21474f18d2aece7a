//! model-core's f32 accuracy checks on the Cortex-M4F's own instruction set
//! (run under QEMU, exits through semihosting: status 0 = pass, 1 = fail).
//!
//! For a grid of scenes and velocities the f32 exact solver must agree with
//! the f64 solver (soft double on the M4) to 1e-5, |v| ≥ v_c must give ±1
//! exactly, the limit μ(0⁺) must equal the closed form 1 − c where a static
//! equilibrium exists, and the normal-only and tangential-only laws must
//! coincide (paper §3.1).
#![no_std]
#![no_main]

use cortex_m_rt::entry;
use cortex_m_semihosting::{debug, hprintln};
use defmt_rtt as _;
use model_core::{exact, Drive, Libm};
use panic_probe as _;
use stm32f4 as _;

#[entry]
fn main() -> ! {
    let mut checks = 0u32;
    let mut fails = 0u32;
    let mut worst = 0.0f64;
    let mut check = |ok: bool| {
        checks += 1;
        if !ok {
            fails += 1;
        }
    };
    let phis = [
        -2.5f64,
        -1.0,
        0.0,
        0.7,
        core::f64::consts::FRAC_PI_2,
        2.2,
        3.0,
    ];
    for &a in &[0.0f64, 0.2, 0.5, 0.9] {
        for &b in &[0.0f64, 0.3, 1.0, 2.5] {
            for &phi in &phis {
                let d64 = Drive::new::<Libm>(a, b, phi);
                let d32 = Drive::new::<Libm>(a as f32, b as f32, phi as f32);
                let (cf, cb) = (d64.c_forward::<Libm>(), d64.c_backward::<Libm>());
                for i in 0..12 {
                    let x = -1.1 + 2.2 * (i as f64 + 0.5) / 12.0;
                    let v = x * if x > 0.0 { cf } else { cb };
                    if v == 0.0 {
                        continue;
                    }
                    let (Ok(m64), Ok(m32)) = (
                        exact::mu_over_mu0::<f64, Libm>(&d64, v),
                        exact::mu_over_mu0::<f32, Libm>(&d32, v as f32),
                    ) else {
                        check(false);
                        continue;
                    };
                    // Reference on the f32-rounded inputs, so only the arithmetic differs.
                    let dr = Drive::new::<Libm>(
                        f64::from(a as f32),
                        f64::from(b as f32),
                        f64::from(phi as f32),
                    );
                    let mr = exact::mu_over_mu0::<f64, Libm>(&dr, f64::from(v as f32))
                        .unwrap_or(f64::NAN);
                    let err = (f64::from(m32) - mr).abs();
                    if err > worst {
                        worst = err;
                    }
                    check(err <= 1e-5);
                    if x.abs() >= 1.0 {
                        check(m64 == x.signum() && f64::from(m32) == x.signum());
                    }
                }
                // μ(0⁺) = 1 − c where c + c' ≤ 2 (static equilibrium).
                if cf + cb <= 2.0 {
                    if let Ok((p, _)) = exact::limits_at_zero::<f32, Libm>(&d32) {
                        check((f64::from(p) - (1.0 - cf)).abs() <= 1e-5);
                    } else {
                        check(false);
                    }
                }
            }
        }
    }
    // Normal-only and tangential-only laws coincide at equal amplitude and v/v_c.
    for &amp in &[0.2f32, 0.7] {
        let n = Drive::new::<Libm>(amp, 0.0, 0.0);
        let t = Drive::new::<Libm>(0.0, amp, 1.0);
        for &x in &[0.1f32, 0.5, 0.9] {
            let mn = exact::mu_over_mu0::<f32, Libm>(&n, x * n.c_forward::<Libm>());
            let mt = exact::mu_over_mu0::<f32, Libm>(&t, x * t.c_forward::<Libm>());
            check(matches!((mn, mt), (Ok(p), Ok(q)) if (p - q).abs() <= 1e-5));
        }
    }
    hprintln!(
        "f32 vectors on the target: {} checks, {} failed, worst |mu32 - mu64| = {}",
        checks,
        fails,
        worst
    );
    debug::exit(if fails == 0 {
        debug::EXIT_SUCCESS
    } else {
        debug::EXIT_FAILURE
    });
    loop {
        cortex_m::asm::wfi();
    }
}

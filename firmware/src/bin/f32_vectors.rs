//! model-core's f32 accuracy checks on the Cortex-M4F's own instruction set
//! (run under QEMU, exits through semihosting: status 0 = pass, 1 = fail).
//!
//! For a grid of scenes and velocities the f32 exact solver must agree with
//! the f64 solver (soft double on the M4) to 1e-5, |v| ≥ v_c must give ±1
//! exactly, the limit μ(0⁺) must equal the closed form 1 − c where a static
//! equilibrium exists, and the normal-only and tangential-only laws must
//! coincide (paper §3.1). All of this with the libm backend and with the
//! float-native `FastF32` backend; and `FastF32`'s functions themselves
//! against f64 libm (soft double) on a grid over their ranges, within the
//! bounds `model_core::float::trig::ERR_*` (proven on the host by exhaustive
//! enumeration; this checks that the M4F computes the same, and that its
//! result bits on a grid over every exponent equal the host's, `trig::digest`).
#![no_std]
#![no_main]

use cortex_m_rt::entry;
use cortex_m_semihosting::{debug, hprintln};
use defmt_rtt as _;
use model_core::float::{trig, FastF32};
use model_core::{exact, Drive, Libm, Math};
use panic_probe as _;
use stm32f4 as _;

/// The solver checks with backend `M`: (checks, failures, worst |μ32 − μ64|).
fn solver_checks<M: Math<f32>>() -> (u32, u32, f64) {
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
                let d32 = Drive::new::<M>(a as f32, b as f32, phi as f32);
                let (cf, cb) = (d64.c_forward::<Libm>(), d64.c_backward::<Libm>());
                for i in 0..12 {
                    let x = -1.1 + 2.2 * (i as f64 + 0.5) / 12.0;
                    let v = x * if x > 0.0 { cf } else { cb };
                    if v == 0.0 {
                        continue;
                    }
                    let (Ok(m64), Ok(m32)) = (
                        exact::mu_over_mu0::<f64, Libm>(&d64, v),
                        exact::mu_over_mu0::<f32, M>(&d32, v as f32),
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
                    if let Ok((p, _)) = exact::limits_at_zero::<f32, M>(&d32) {
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
        let n = Drive::new::<M>(amp, 0.0, 0.0);
        let t = Drive::new::<M>(0.0, amp, 1.0);
        for &x in &[0.1f32, 0.5, 0.9] {
            let mn = exact::mu_over_mu0::<f32, M>(&n, x * n.c_forward::<M>());
            let mt = exact::mu_over_mu0::<f32, M>(&t, x * t.c_forward::<M>());
            check(matches!((mn, mt), (Ok(p), Ok(q)) if (p - q).abs() <= 1e-5));
        }
    }
    (checks, fails, worst)
}

/// `FastF32`'s functions against f64 libm on the target: (checks, failures,
/// worst error of sin/cos, asin, atan2 (rad), sqrt (relative)).
fn function_checks() -> (u32, u32, [f64; 4]) {
    let (mut checks, mut fails) = (0u32, 0u32);
    let mut worst = [0.0f64; 4];
    let mut record = |k: usize, e: f64, bound: f64| {
        checks += 1;
        // A NaN error counts as a failure.
        if e.is_nan() || e > bound {
            fails += 1;
        }
        if e > worst[k] {
            worst[k] = e;
        }
    };
    let n = 4096;
    for i in 0..=n {
        let t = i as f64 / n as f64;
        // sin/cos over [-4096, 4096] (the reduced range) and densely over [-2π, 2π].
        for x in [8192.0 * t - 4096.0, 4.0 * core::f64::consts::PI * (t - 0.5)] {
            let x = x as f32;
            let (s, c) = trig::sin_cos(x);
            let (s64, c64) = <Libm as Math<f64>>::sin_cos(f64::from(x));
            let e = (f64::from(s) - s64).abs().max((f64::from(c) - c64).abs());
            record(0, e, trig::ERR_SIN_COS);
        }
        let x = (2.0 * t - 1.0) as f32;
        let e = (f64::from(trig::asin(x)) - <Libm as Math<f64>>::asin(f64::from(x))).abs();
        record(1, e, trig::ERR_ASIN);
        let (y, xx) = ((4.0 * t - 2.0) as f32, (1.5 - 3.0 * t * t) as f32);
        let e = (f64::from(trig::atan2(y, xx))
            - <Libm as Math<f64>>::atan2(f64::from(y), f64::from(xx)))
        .abs();
        record(2, e, trig::ERR_ATAN2);
        let q = (1e-3 + 1e3 * t * t) as f32;
        let r = <Libm as Math<f64>>::sqrt(f64::from(q));
        record(3, (f64::from(trig::sqrt(q)) - r).abs() / r, trig::ERR_SQRT);
    }
    (checks, fails, worst)
}

#[entry]
fn main() -> ! {
    let mut fails = 0u32;
    for (name, (c, f, w)) in [
        (<Libm as Math<f32>>::NAME, solver_checks::<Libm>()),
        (<FastF32 as Math<f32>>::NAME, solver_checks::<FastF32>()),
    ] {
        hprintln!(
            "f32 vectors on the target, {} backend: {} checks, {} failed, worst |mu32 - mu64| = {}",
            name,
            c,
            f,
            w
        );
        fails += f;
    }
    let (c, f, w) = function_checks();
    hprintln!(
        "fast-f32 functions vs f64 on the target: {} checks, {} failed, worst sin/cos {}, asin {}, atan2 {}, sqrt (relative) {}",
        c,
        f,
        w[0],
        w[1],
        w[2],
        w[3]
    );
    fails += f;
    // The same result bits as on the host, where the bounds are proven.
    let digest = trig::digest(4096);
    hprintln!(
        "fast-f32 digest(4096) on the target: {:#010x} (host: {:#010x})",
        digest,
        trig::DIGEST_4096
    );
    if digest != trig::DIGEST_4096 {
        fails += 1;
    }
    debug::exit(if fails == 0 {
        debug::EXIT_SUCCESS
    } else {
        debug::EXIT_FAILURE
    });
    loop {
        cortex_m::asm::wfi();
    }
}

//! Measured error bounds of the `Micromath` backend (documented in
//! `model_core::float`), against `f64` libm over 2²⁰ arguments.

use model_core::{Libm, Math, Micromath};

#[test]
fn micromath_error_bounds() {
    let n = 1 << 20;
    let (mut e_sin, mut e_cos, mut e_sqrt, mut e_asin, mut e_atan2) =
        (0.0f64, 0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for i in 0..n {
        let t = i as f64 / n as f64;
        let x = (-std::f64::consts::PI + std::f64::consts::TAU * t) as f32;
        let (s, c) = <Micromath as Math<f32>>::sin_cos(x);
        let (s64, c64) = <Libm as Math<f64>>::sin_cos(f64::from(x));
        e_sin = e_sin.max((f64::from(s) - s64).abs());
        e_cos = e_cos.max((f64::from(c) - c64).abs());
        let y = (1e-3 + 1e3 * t) as f32;
        let r = <Micromath as Math<f32>>::sqrt(y);
        e_sqrt = e_sqrt.max(((f64::from(r) - f64::from(y).sqrt()) / f64::from(y).sqrt()).abs());
        let z = (-1.0 + 2.0 * t) as f32;
        e_asin =
            e_asin.max((f64::from(<Micromath as Math<f32>>::asin(z)) - f64::from(z).asin()).abs());
        let (yy, xx) = (x.sin(), x.cos());
        let at = <Micromath as Math<f32>>::atan2(yy, xx);
        let mut d = (f64::from(at) - f64::from(yy).atan2(f64::from(xx))).abs();
        if d > std::f64::consts::PI {
            d = std::f64::consts::TAU - d;
        }
        e_atan2 = e_atan2.max(d);
    }
    println!("micromath: sin {e_sin:.2e}, cos {e_cos:.2e}, sqrt rel {e_sqrt:.2e}, asin {e_asin:.2e}, atan2 {e_atan2:.2e}");
    // The documented bounds (model_core::float module docs).
    assert!(e_sin <= 1.1e-3 && e_cos <= 1.1e-3);
    assert!(e_sqrt <= 6.2e-2);
    assert!(e_asin <= 1.9e-2);
    assert!(e_atan2 <= 2.9e-3);
}

//! Float-native `f32` trigonometry for the [`FastF32`](super::FastF32)
//! backend: only `f32` additions, multiplications and one division or square
//! root per call — no `f64` (which the Cortex-M4F computes in software).
//!
//! # Construction
//!
//! Each function reduces its argument to a small interval and evaluates a
//! minimax polynomial there. The coefficients come from a Remez exchange in
//! 60-digit arithmetic (`fit_trig.py` next to this file, run with
//! `python3 model-core/src/model/float/fit_trig.py`), rounded to `f32`; the
//! error of the rounded polynomial itself (exact arithmetic, printed by the
//! script) is
//!
//! | kernel | interval | polynomial error |
//! |---|---|---|
//! | `sin r = r + r³S(r²)` | `|r| ≤ π/4 + 10⁻³` | `8.9e-9` relative |
//! | `cos r = 1 − r²/2 + r⁴C(r²)` | `|r| ≤ π/4 + 10⁻³` | `4.6e-10` absolute |
//! | `asin x = x + x³P(x²)` | `|x| ≤ 1/2` | `5.9e-9` relative |
//! | `atan u = u + u³A(u²)` | `|u| ≤ tan(π/8)` | `2.9e-9` relative |
//!
//! all far below the `f32` rounding unit `2⁻²⁴ ≈ 6.0e-8`, so the error of each
//! function is that of its `f32` evaluation. That total is *proven* by
//! exhaustive enumeration against `f64` (`tests/tests/trig.rs`, ignored tests
//! `exhaustive_*`: `cargo test --release -p integration-tests --test trig --
//! --ignored --nocapture`): every `f32` argument of `sin_cos` (`|x| ≤ 4096`),
//! `asin` (`[-1, 1]`) and `sqrt` (`[0, f32::MAX]`), and for `atan2` every
//! finite ratio in each quadrant and both halves of the swap (`(t, 1)`,
//! `(1, t)`, `(t, −1)`, `(−1, −t)` for every `f32` `t ≥ 0`) plus 10⁶ random
//! pairs over 40 decades. Those runs give [`ERR_SIN_COS`], [`ERR_ASIN`],
//! [`ERR_ATAN2`] and [`ERR_SQRT`]; [`ERR_HYPOT`] follows from [`ERR_SQRT`].
//! The arithmetic is IEEE single precision with round-to-nearest on the host
//! and on the Cortex-M4F alike (no fused multiply-add is used; the M4F's
//! `vmla` rounds the product and the sum separately), so the host's
//! enumeration covers the target's results bit for bit — checked by
//! [`digest`] on both.
//!
//! # Range reduction of `sin`/`cos` (Cody–Waite)
//!
//! `x = k·π/2 + r` with `k = ⌊2|x|/π + ½⌋` (`k ≤ 2608` for `|x| ≤ 4096`) and
//! `π/2 = C₁ + C₂ + C₃`, where `C₁ = 1.5703125` (8 bits, a multiple of 2⁻⁷)
//! and `C₂ = 2029·2⁻²²` are short enough that `k·C₁` and `k·C₂` are exact,
//! and so are `r₁ = |x| − kC₁` and `r₂ = r₁ − kC₂`: each is a multiple of
//! `min(ulp(x), 2⁻²²)` and needs at most 24 bits for `|x| ≤ 4096`. `C₃ =
//! f32(π/2 − C₁ − C₂)` leaves `|π/2 − C₁ − C₂ − C₃| ≤ 1.8e-15`. The reduced
//! argument `r = r₂ − kC₃` is therefore within half an ulp of `r` (the last
//! subtraction) plus `k·1.8e-15 + ½ulp(kC₃) ≤ 1.2e-11` (absolute) of the
//! true `|x| − kπ/2`, up to [`SIN_COS_MAX_ARG`] = 4096 (the exact solver uses
//! phases in `[0, 2π]`, a scene's drive phase φ any finite value). Beyond it,
//! and for ±∞ and NaN,
//! [`sin_cos`] calls `libm::sincosf` (correct, but at libm's cost).

/// Largest `|x|` that [`sin_cos`] reduces itself (`2¹²`); larger arguments go
/// to `libm::sincosf`.
pub const SIN_COS_MAX_ARG: f32 = 4096.0;

/// Worst absolute error of [`sin_cos`] (either component) over every `f32`
/// with `|x| ≤ 4096`, against `f64` (exhaustive: 6.72e-8 at x = 2030.252).
pub const ERR_SIN_COS: f64 = 6.8e-8;
/// Worst absolute error of [`asin`] (rad) over every `f32` in `[-1, 1]`
/// (exhaustive: 1.52e-7 at x = 0.5067804, just above ½ where the
/// `π/2 − 2 asin √z` branch starts).
pub const ERR_ASIN: f64 = 1.6e-7;
/// Worst absolute error of [`atan2`] (rad): every finite ratio in each
/// quadrant (exhaustive over the four one-parameter families of the module
/// docs: 2.86e-7 at t = 0.4594648) and 10⁶ random pairs (2.75e-7). About one ulp of
/// results near ±π (ulp 2.4e-7).
pub const ERR_ATAN2: f64 = 3.0e-7;
/// Worst relative error of [`sqrt`] over every finite `f32 ≥ 0`
/// (exhaustive: 8.83e-8, below one ulp); zero, subnormals, ∞ and NaN are
/// libm's, correctly rounded.
pub const ERR_SQRT: f64 = 1.0e-7;
/// Worst relative error of [`hypot`]: the sum of squares carries at most
/// `(1 + u)² − 1 ≈ 2u` (`u = 2⁻²⁴`), halved by the root, plus [`ERR_SQRT`]:
/// `u + 1.0e-7 ≤ 1.6e-7` (measured 1.3e-7 over 10⁶ random pairs).
pub const ERR_HYPOT: f64 = 1.6e-7;

// 2/π and π/2 = C1 + C2 + C3 (Cody–Waite; see the module docs).
const FRAC_2_PI: f32 = 0.636_619_75;
const PIO2_C1: f32 = 1.570_312_5;
const PIO2_C2: f32 = 4.837_513e-4;
const PIO2_C3: f32 = 7.549_79e-8;

// Constants as a rounded head and the rounding error: c = HI + LO.
const PIO2_HI: f32 = core::f32::consts::FRAC_PI_2;
const PIO2_LO: f32 = -4.371_139e-8;
const PI_HI: f32 = core::f32::consts::PI;
const PI_LO: f32 = -8.742_278e-8;
const PIO4_HI: f32 = core::f32::consts::FRAC_PI_4;
const PIO4_LO: f32 = -2.185_569_4e-8;
const TAN_PI_8: f32 = 0.414_213_57;
// 2⁻⁵⁰ and 2⁵⁰: the range of the direct hypot.
const TWO_POW_M50: f32 = f32::from_bits((127 - 50) << 23);
const TWO_POW_50: f32 = f32::from_bits((127 + 50) << 23);

// Minimax coefficients (fit_trig.py).
const S1: f32 = -0.166_666_55;
const S2: f32 = 0.008_332_155;
const S3: f32 = -0.000_195_144_54;
const C1: f32 = 0.041_666_646;
const C2: f32 = -0.001_388_736;
const C3: f32 = 2.443_753_3e-5;
const P1: f32 = 0.166_667_52;
const P2: f32 = 0.074_952_975;
const P3: f32 = 0.045_470_376;
const P4: f32 = 0.024_179_514;
const P5: f32 = 0.042_166_308;
const A1: f32 = -0.333_333_16;
const A2: f32 = 0.199_984_71;
const A3: f32 = -0.142_435_33;
const A4: f32 = 0.105_938_12;
const A5: f32 = -0.060_782_17;

/// `(sin x, cos x)` for `x` in radians: Cody–Waite reduction to
/// `|r| ≤ π/4` and two minimax polynomials (module docs). Absolute error
/// ≤ [`ERR_SIN_COS`] for `|x| ≤` [`SIN_COS_MAX_ARG`]; `libm::sincosf` beyond.
#[inline]
pub fn sin_cos(x: f32) -> (f32, f32) {
    let ax = x.abs();
    // NaN fails the comparison and goes to libm too.
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    if !(ax <= SIN_COS_MAX_ARG) {
        return libm::sincosf(x);
    }
    let (r, q) = if ax <= PIO4_HI {
        (ax, 0u32)
    } else {
        // ax ≥ 0, so the truncating cast is the floor.
        let k = (ax * FRAC_2_PI + 0.5) as u32;
        let kf = k as f32;
        (((ax - kf * PIO2_C1) - kf * PIO2_C2) - kf * PIO2_C3, k & 3)
    };
    let z = r * r;
    let s = r + (r * z) * (S1 + z * (S2 + z * S3));
    // cos r = 1 − z/2 + z²C(z), with the rounding of 1 − z/2 carried (exact
    // by Sterbenz: 1 − w ≈ z/2).
    let hz = 0.5 * z;
    let w = 1.0 - hz;
    let c = w + (((1.0 - w) - hz) + (z * z) * (C1 + z * (C2 + z * C3)));
    let (s, c) = match q {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    };
    (if x.is_sign_negative() { -s } else { s }, c)
}

/// `sin x` ([`sin_cos`]).
#[inline]
pub fn sin(x: f32) -> f32 {
    sin_cos(x).0
}

/// `cos x` ([`sin_cos`]).
#[inline]
pub fn cos(x: f32) -> f32 {
    sin_cos(x).1
}

#[inline(always)]
fn asin_poly(z: f32) -> f32 {
    P1 + z * (P2 + z * (P3 + z * (P4 + z * P5)))
}

/// Arcsine in `[-π/2, π/2]`: the polynomial on `|x| ≤ ½`, and
/// `asin x = π/2 − 2 asin √((1−|x|)/2)` above (the same polynomial at an
/// argument `≤ ½`). NaN outside `[-1, 1]`. Absolute error ≤ [`ERR_ASIN`].
#[inline]
pub fn asin(x: f32) -> f32 {
    let ax = x.abs();
    let r = if ax <= 0.5 {
        let z = ax * ax;
        ax + (ax * z) * asin_poly(z)
    } else if ax <= 1.0 {
        // 1 − ax is exact (Sterbenz), the halving too.
        let z = (1.0 - ax) * 0.5;
        let s = sqrt(z);
        let t = s + (s * z) * asin_poly(z);
        PIO2_HI - ((t + t) - PIO2_LO)
    } else {
        return f32::NAN;
    };
    if x.is_sign_negative() {
        -r
    } else {
        r
    }
}

#[inline(always)]
fn atan_kernel(u: f32) -> f32 {
    let z = u * u;
    u + (u * z) * (A1 + z * (A2 + z * (A3 + z * (A4 + z * A5))))
}

/// Four-quadrant arctangent of `y/x` in `[-π, π]`, with libm's signs of zero
/// (`atan2(±0, −0) = ±π`, `atan2(±0, +0) = ±0`). One division: the ratio
/// `t = min/max ∈ [0, 1]`, or `(t − 1)/(t + 1)` with `atan t = π/4 + atan((t−1)/(t+1))`
/// above `tan(π/8)`. Infinite or NaN arguments go to `libm::atan2f`.
/// Absolute error ≤ [`ERR_ATAN2`].
#[inline]
pub fn atan2(y: f32, x: f32) -> f32 {
    if !(x.is_finite() && y.is_finite()) {
        return libm::atan2f(y, x);
    }
    let (ax, ay) = (x.abs(), y.abs());
    let swap = ay > ax;
    let (num, den) = if swap { (ax, ay) } else { (ay, ax) };
    let mut r = if den == 0.0 {
        0.0
    } else if num <= TAN_PI_8 * den {
        atan_kernel(num / den)
    } else {
        PIO4_HI + (atan_kernel((num - den) / (num + den)) + PIO4_LO)
    };
    if swap {
        r = PIO2_HI - (r - PIO2_LO);
    }
    if x.is_sign_negative() {
        r = PI_HI - (r - PI_LO);
    }
    if y.is_sign_negative() {
        -r
    } else {
        r
    }
}

/// Square root of a positive normal `x`: the bit-level reciprocal square
/// root estimate (relative error ≤ 3.5e-2), two Newton steps for `1/√x`
/// (≤ 4.6e-6) and one Newton step for `√x` itself
/// (`s + ½y(x − s²)`, quadratic: rounding only). About 20 instructions on the
/// Cortex-M4F, against ~80 for `libm::sqrtf`, which does integer arithmetic
/// (the hardware `vsqrt.f32` is out of reach without `unsafe` inline assembly
/// or an unstable intrinsic). Zero, subnormal, negative, infinite and NaN
/// arguments go to `libm::sqrtf`. Relative error ≤ [`ERR_SQRT`] (exhaustive
/// over every positive normal `f32`).
#[inline]
pub fn sqrt(x: f32) -> f32 {
    // Outside the positive normals: zero, subnormals, ∞, NaN, negatives.
    if outside(x, f32::MIN_POSITIVE, f32::MAX) {
        return libm::sqrtf(x);
    }
    let y = f32::from_bits(0x5f37_5a86 - (x.to_bits() >> 1));
    let hx = 0.5 * x;
    let y = y * (1.5 - hx * y * y);
    let y = y * (1.5 - hx * y * y);
    let s = x * y;
    s + (0.5 * y) * (x - s * s)
}

/// Whether `x` lies outside `[lo, hi]` (`0 < lo ≤ hi`, both finite), as
/// one unsigned compare of the bits: the bits of non-negative floats are
/// ordered as their values, so zero and anything below `lo` wrap to large
/// differences, and ∞, NaN and every negative (sign bit set) lie above
/// `hi`'s. Two float compares and their flag moves cost twice as many
/// instructions on the M4F.
#[inline(always)]
fn outside(x: f32, lo: f32, hi: f32) -> bool {
    x.to_bits().wrapping_sub(lo.to_bits()) > hi.to_bits() - lo.to_bits()
}

/// `√(x² + y²)`: direct for `max(|x|, |y|) ∈ [2⁻⁵⁰, 2⁵⁰]` (no overflow, and an
/// underflowing square is below half an ulp of the sum), `libm::hypotf`
/// otherwise (and for ±∞, NaN). Relative error ≤ [`ERR_HYPOT`].
#[inline]
pub fn hypot(x: f32, y: f32) -> f32 {
    let (ax, ay) = (x.abs(), y.abs());
    let big = if ax > ay { ax } else { ay };
    // `big` is non-negative or NaN (whose bits lie above 2⁵⁰'s).
    if outside(big, TWO_POW_M50, TWO_POW_50) {
        // Both zero: 0. A NaN beside a zero makes `big` the zero (NaN
        // compares false), so the test is on both, not on `big`.
        return if ax == 0.0 && ay == 0.0 {
            0.0
        } else {
            libm::hypotf(x, y)
        };
    }
    sqrt(ax * ax + ay * ay)
}

/// FNV-1a digest of the result bits of [`sin_cos`], [`asin`], [`atan2`],
/// [`sqrt`] and [`hypot`] at `n` arguments each, spread evenly over the bit patterns of
/// their ranges (every exponent). The host, where the bounds are proven by
/// exhaustive enumeration (`hypot`'s tested on random pairs), and the Cortex-M4F (the firmware's `f32_vectors`)
/// must both give [`DIGEST_4096`] for `n = 4096`: the same bits on both.
pub fn digest(n: u32) -> u32 {
    let mut h: u32 = 0x811c_9dc5;
    let mut eat = |x: f32| {
        for b in x.to_bits().to_le_bytes() {
            h = (h ^ u32::from(b)).wrapping_mul(0x0100_0193);
        }
    };
    let n = n.max(1);
    for i in 0..n {
        let at = |hi: u32| f32::from_bits((u64::from(hi) * u64::from(i) / u64::from(n)) as u32);
        let x = at(SIN_COS_MAX_ARG.to_bits());
        let (s, c) = sin_cos(x);
        eat(s);
        eat(c);
        eat(sin_cos(-x).0);
        let u = at(1.0f32.to_bits());
        eat(asin(u));
        eat(asin(-u));
        let t = at(f32::MAX.to_bits());
        eat(atan2(t, 1.0));
        eat(atan2(-1.0, -t));
        eat(sqrt(t));
        eat(hypot(t, u));
    }
    h
}

/// [`digest`]`(4096)` (computed on x86-64 and on the emulated Cortex-M4F).
pub const DIGEST_4096: u32 = 0x58d8_c87b;

//! The small float abstraction the model is generic over.
//!
//! [`Float`] carries the arithmetic and the constants; [`Math`] carries the
//! transcendental functions, so one algorithm can run on several *math backends*:
//!
//! * [`Libm`] — `libm` (a port of musl's libm) for `f32` and `f64`: correctly
//!   rounded `sqrt`, and `sin`/`cos`/`asin`/`atan2` within 1 ulp. This is the
//!   default everywhere and what every accuracy figure of the crate refers to.
//! * [`Micromath`] — `micromath`'s fast `f32` approximations (Cortex-M
//!   friendly, no tables). Measured error bounds (`tests/tests/micromath_bounds.rs`
//!   in the workspace: 2²⁰ arguments against `f64` libm): `sin`/`cos`
//!   ≤ 1.1e-3 absolute, `sqrt` ≤ 6.2e-2 *relative* (a bit-trick estimate),
//!   `asin` ≤ 1.9e-2 rad, `atan2` ≤ 2.9e-3 rad. Usable for a quick look or a
//!   coarse waveform, not for the exact solver, whose f32 results with
//!   [`Libm`] agree with f64 to ~3e-7.
//! * [`FastF32`] — float-native `f32` functions ([`trig`]: Cody–Waite range
//!   reduction and Remez minimax polynomials, no `f64` arithmetic, which the
//!   Cortex-M4F does in software). Absolute error of `sin`/`cos` ≤ 6.8e-8,
//!   `asin` ≤ 1.6e-7 rad, `atan2` ≤ 3.0e-7 rad; `sqrt` ≤ 1.0e-7 relative
//!   (bounds proven by exhaustive enumeration of the `f32` arguments, see
//!   [`trig`]). The exact solver's μ with it agrees with f64 as closely as with
//!   [`Libm`] (worst 2.0e-7·(1 + b) over 20 000 random scenes for both,
//!   `tests/tests/trig.rs`), and one f32 prediction on the Cortex-M4F costs
//!   ~1 150 instructions instead of ~11 250 (`predict_cost` under QEMU).
//!

pub mod trig;

use core::fmt::Debug;
use core::ops::{Add, AddAssign, Div, Mul, MulAssign, Neg, Sub, SubAssign};

/// A binary floating-point type the model can run in (`f32` on the
/// microcontroller, `f64` on the host).
pub trait Float:
    Copy
    + Debug
    + PartialOrd
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + AddAssign
    + SubAssign
    + MulAssign
    + Default
    + 'static
{
    /// 0.
    const ZERO: Self;
    /// 1.
    const ONE: Self;
    /// 2.
    const TWO: Self;
    /// 1/2.
    const HALF: Self;
    /// π.
    const PI: Self;
    /// 2π.
    const TAU: Self;
    /// π/2.
    const FRAC_PI_2: Self;
    /// Machine epsilon (distance from 1 to the next larger number).
    const EPSILON: Self;
    /// Largest finite value.
    const MAX: Self;
    /// Smallest positive normal value.
    const MIN_POSITIVE: Self;

    /// Nearest representable value of an `f64` (rounds for `f32`).
    fn from_f64(x: f64) -> Self;
    /// Exact widening to `f64`.
    fn to_f64(self) -> f64;
    /// Conversion of a count (exact up to 2²⁴ for `f32`, 2⁵³ for `f64`).
    fn from_u32(n: u32) -> Self;
    /// Truncation towards zero to a count, saturating at 0 and `u32::MAX`
    /// (NaN gives 0): Rust's `as` cast.
    fn to_u32(self) -> u32;
    /// `true` unless NaN or ±∞.
    fn is_finite(self) -> bool;
    /// `true` for NaN.
    fn is_nan(self) -> bool;
    /// Absolute value.
    fn abs(self) -> Self;
    /// Fused multiply-add `self * a + b` where the target has it (plain
    /// multiply and add otherwise; the result differs only in rounding).
    fn mul_add(self, a: Self, b: Self) -> Self;
    /// `libm` square root (correctly rounded).
    fn libm_sqrt(self) -> Self;
    /// `libm` `(sin, cos)`.
    fn libm_sin_cos(self) -> (Self, Self);
    /// `libm` arcsine.
    fn libm_asin(self) -> Self;
    /// `libm` four-quadrant arctangent `atan2(self, x)`.
    fn libm_atan2(self, x: Self) -> Self;
    /// `libm` hypotenuse.
    fn libm_hypot(self, y: Self) -> Self;

    /// Smaller of two numbers (NaN-free inputs assumed).
    #[inline(always)]
    fn min(self, other: Self) -> Self {
        if other < self {
            other
        } else {
            self
        }
    }
    /// Larger of two numbers (NaN-free inputs assumed).
    #[inline(always)]
    fn max(self, other: Self) -> Self {
        if other > self {
            other
        } else {
            self
        }
    }
}

macro_rules! impl_float {
    ($t:ty, $fma:expr, $sqrt:path, $sincos:path, $asin:path, $atan2:path, $hypot:path) => {
        impl Float for $t {
            const ZERO: Self = 0.0;
            const ONE: Self = 1.0;
            const TWO: Self = 2.0;
            const HALF: Self = 0.5;
            const PI: Self = core::f64::consts::PI as $t;
            const TAU: Self = core::f64::consts::TAU as $t;
            const FRAC_PI_2: Self = core::f64::consts::FRAC_PI_2 as $t;
            const EPSILON: Self = <$t>::EPSILON;
            const MAX: Self = <$t>::MAX;
            const MIN_POSITIVE: Self = <$t>::MIN_POSITIVE;
            #[inline(always)]
            fn from_f64(x: f64) -> Self {
                x as $t
            }
            #[inline(always)]
            fn to_f64(self) -> f64 {
                self as f64
            }
            #[inline(always)]
            fn from_u32(n: u32) -> Self {
                n as $t
            }
            #[inline(always)]
            fn to_u32(self) -> u32 {
                self as u32
            }
            #[inline(always)]
            fn is_finite(self) -> bool {
                <$t>::is_finite(self)
            }
            #[inline(always)]
            fn is_nan(self) -> bool {
                <$t>::is_nan(self)
            }
            #[inline(always)]
            fn abs(self) -> Self {
                <$t>::abs(self)
            }
            #[inline(always)]
            fn mul_add(self, a: Self, b: Self) -> Self {
                $fma(self, a, b)
            }
            #[inline(always)]
            fn libm_sqrt(self) -> Self {
                $sqrt(self)
            }
            #[inline(always)]
            fn libm_sin_cos(self) -> (Self, Self) {
                $sincos(self)
            }
            #[inline(always)]
            fn libm_asin(self) -> Self {
                $asin(self)
            }
            #[inline(always)]
            fn libm_atan2(self, x: Self) -> Self {
                $atan2(self, x)
            }
            #[inline(always)]
            fn libm_hypot(self, y: Self) -> Self {
                $hypot(self, y)
            }
        }
    };
}

#[inline(always)]
fn fma64(x: f64, a: f64, b: f64) -> f64 {
    // A real FMA only where the hardware has one; libm's software fma is slow.
    if cfg!(target_feature = "fma") {
        libm::fma(x, a, b)
    } else {
        x * a + b
    }
}
#[inline(always)]
fn fma32(x: f32, a: f32, b: f32) -> f32 {
    // Cortex-M4F has VFMA.F32; x86-64 only with the `fma` target feature.
    if cfg!(any(target_feature = "fma", target_arch = "arm")) {
        libm::fmaf(x, a, b)
    } else {
        x * a + b
    }
}

impl_float!(
    f64,
    fma64,
    libm::sqrt,
    libm::sincos,
    libm::asin,
    libm::atan2,
    libm::hypot
);
impl_float!(
    f32,
    fma32,
    libm::sqrtf,
    libm::sincosf,
    libm::asinf,
    libm::atan2f,
    libm::hypotf
);

/// Transcendental functions for a [`Float`]: a *math backend*.
pub trait Math<T: Float> {
    /// Short name for reports ("libm", "micromath").
    const NAME: &'static str;
    /// Worst relative error of the backend's functions beyond the rounding of
    /// the float type (0 for libm, whose functions are within an ulp or two;
    /// 0.062 for micromath, its measured `sqrt` worst case; 3e-7 for
    /// fast-f32, its proven `atan2` worst case). The error bounds
    /// of the solvers ([`crate::model::exact::error_bound`],
    /// [`crate::model::fixed_step::error_bound`]) add a term proportional to it.
    const MAX_REL_ERROR: f64;
    /// Square root of a non-negative number.
    fn sqrt(x: T) -> T;
    /// `(sin x, cos x)`, radians.
    fn sin_cos(x: T) -> (T, T);
    /// Arcsine of `x ∈ [-1, 1]`, in `[-π/2, π/2]`.
    fn asin(x: T) -> T;
    /// Four-quadrant arctangent of `y/x`, in `(-π, π]`.
    fn atan2(y: T, x: T) -> T;
    /// `sqrt(x² + y²)` without undue overflow or underflow.
    fn hypot(x: T, y: T) -> T;
}

/// The accurate backend: the `libm` crate (musl's algorithms), `f32` and `f64`.
#[derive(Debug, Clone, Copy, Default)]
pub struct Libm;

impl<T: Float> Math<T> for Libm {
    const NAME: &'static str = "libm";
    const MAX_REL_ERROR: f64 = 0.0;
    #[inline(always)]
    fn sqrt(x: T) -> T {
        x.libm_sqrt()
    }
    #[inline(always)]
    fn sin_cos(x: T) -> (T, T) {
        x.libm_sin_cos()
    }
    #[inline(always)]
    fn asin(x: T) -> T {
        x.libm_asin()
    }
    #[inline(always)]
    fn atan2(y: T, x: T) -> T {
        y.libm_atan2(x)
    }
    #[inline(always)]
    fn hypot(x: T, y: T) -> T {
        x.libm_hypot(y)
    }
}

/// The fast backend: `micromath`'s `f32` approximations (error bounds in the
/// module docs). Only for `f32`.
#[derive(Debug, Clone, Copy, Default)]
pub struct Micromath;

impl Math<f32> for Micromath {
    const NAME: &'static str = "micromath";
    const MAX_REL_ERROR: f64 = 0.062;
    #[inline(always)]
    fn sqrt(x: f32) -> f32 {
        micromath::F32(x).sqrt().0
    }
    #[inline(always)]
    fn sin_cos(x: f32) -> (f32, f32) {
        let v = micromath::F32(x);
        (v.sin().0, v.cos().0)
    }
    #[inline(always)]
    fn asin(x: f32) -> f32 {
        micromath::F32(x).asin().0
    }
    #[inline(always)]
    fn atan2(y: f32, x: f32) -> f32 {
        micromath::F32(y).atan2(micromath::F32(x)).0
    }
    #[inline(always)]
    fn hypot(x: f32, y: f32) -> f32 {
        micromath::F32(x * x + y * y).sqrt().0
    }
}

/// The fast accurate `f32` backend: float-native trigonometry ([`trig`]).
/// Absolute error of `sin`/`cos` ≤ [`trig::ERR_SIN_COS`], of `asin` ≤
/// [`trig::ERR_ASIN`], of `atan2` ≤ [`trig::ERR_ATAN2`] (rad); relative
/// error of `sqrt` ≤ [`trig::ERR_SQRT`], of `hypot` ≤ [`trig::ERR_HYPOT`].
/// Only for `f32`.
#[derive(Debug, Clone, Copy, Default)]
pub struct FastF32;

impl Math<f32> for FastF32 {
    const NAME: &'static str = "fast-f32";
    /// The largest of the functions' error bounds ([`trig::ERR_ATAN2`]): a
    /// few `f32` ulps, the same order as the rounding already in the f32
    /// precision constant of the solvers.
    const MAX_REL_ERROR: f64 = trig::ERR_ATAN2;
    #[inline(always)]
    fn sqrt(x: f32) -> f32 {
        trig::sqrt(x)
    }
    #[inline(always)]
    fn sin_cos(x: f32) -> (f32, f32) {
        trig::sin_cos(x)
    }
    #[inline(always)]
    fn asin(x: f32) -> f32 {
        trig::asin(x)
    }
    #[inline(always)]
    fn atan2(y: f32, x: f32) -> f32 {
        trig::atan2(y, x)
    }
    #[inline(always)]
    fn hypot(x: f32, y: f32) -> f32 {
        trig::hypot(x, y)
    }
}

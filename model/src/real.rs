//! The scalar type the model computes in.
//!
//! The model is generic over [`Real`] so the same code runs in `f64` (bit-exact with the host
//! reference) and in `f32` (the Cortex-M4F's single-precision FPU). Every elementary function
//! goes through `libm`, never through `std`, so results do not depend on the platform's C
//! library: the f64 bits are the same on x86_64 and on a Cortex-M4F.

use core::ops::{Add, Div, Mul, Neg, Sub};

/// A floating-point scalar with the operations the model needs.
///
/// Implemented for `f64` (reference precision) and `f32` (embedded FPU precision).
pub trait Real:
    Copy
    + PartialOrd
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + core::fmt::Debug
{
    /// 0.
    const ZERO: Self;
    /// 1.
    const ONE: Self;
    /// 2.
    const TWO: Self;
    /// 3.
    const THREE: Self;
    /// 6.
    const SIX: Self;
    /// 0.5.
    const HALF: Self;
    /// Rounds an `f64` to this type (exact for `f64`).
    fn from_f64(x: f64) -> Self;
    /// Widens this value to `f64` (exact).
    fn to_f64(self) -> f64;
    /// This value rounded to `f32`: the same bits as `self.to_f64() as f32` (for `f32` the
    /// value itself, without the round trip through `f64`, which a Cortex-M4F computes in
    /// software).
    #[inline]
    fn to_f32(self) -> f32 {
        self.to_f64() as f32
    }
    /// Sine (radians), from `libm`.
    fn sin(self) -> Self;
    /// Cosine (radians), from `libm`.
    fn cos(self) -> Self;
    /// Sine and cosine of one angle (radians): the same bits as `(self.sin(), self.cos())`,
    /// cheaper where the library shares the argument reduction (`libm::sincos` for `f64`;
    /// the identity is checked in `host-tests/tests/sincos.rs`).
    #[inline]
    fn sin_cos(self) -> (Self, Self) {
        (self.sin(), self.cos())
    }
    /// Hyperbolic tangent, from `libm`.
    fn tanh(self) -> Self;
    /// Exponential, from `libm`.
    fn exp(self) -> Self;
    /// `true` unless NaN or infinite.
    fn is_finite(self) -> bool;
}

impl Real for f64 {
    const ZERO: Self = 0.0;
    const ONE: Self = 1.0;
    const TWO: Self = 2.0;
    const THREE: Self = 3.0;
    const SIX: Self = 6.0;
    const HALF: Self = 0.5;
    #[inline]
    fn from_f64(x: f64) -> Self {
        x
    }
    #[inline]
    fn to_f64(self) -> f64 {
        self
    }
    #[inline]
    fn sin(self) -> Self {
        libm::sin(self)
    }
    #[inline]
    fn cos(self) -> Self {
        libm::cos(self)
    }
    #[inline]
    fn sin_cos(self) -> (Self, Self) {
        libm::sincos(self)
    }
    #[inline]
    fn tanh(self) -> Self {
        libm::tanh(self)
    }
    #[inline]
    fn exp(self) -> Self {
        libm::exp(self)
    }
    #[inline]
    fn is_finite(self) -> bool {
        f64::is_finite(self)
    }
}

impl Real for f32 {
    const ZERO: Self = 0.0;
    const ONE: Self = 1.0;
    const TWO: Self = 2.0;
    const THREE: Self = 3.0;
    const SIX: Self = 6.0;
    const HALF: Self = 0.5;
    #[inline]
    fn from_f64(x: f64) -> Self {
        x as f32
    }
    #[inline]
    fn to_f64(self) -> f64 {
        f64::from(self)
    }
    #[inline]
    fn to_f32(self) -> f32 {
        self
    }
    #[inline]
    fn sin(self) -> Self {
        libm::sinf(self)
    }
    #[inline]
    fn cos(self) -> Self {
        libm::cosf(self)
    }
    #[inline]
    fn tanh(self) -> Self {
        libm::tanhf(self)
    }
    #[inline]
    fn exp(self) -> Self {
        libm::expf(self)
    }
    #[inline]
    fn is_finite(self) -> bool {
        f32::is_finite(self)
    }
}

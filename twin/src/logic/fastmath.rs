//! [`F32x`]: `f32` with single-precision sine and cosine, a [`Real`] for the Cortex-M4F's FPU.
//!
//! The model's own `f32` calls `libm::sinf`/`cosf`, which compute in f64 internally: soft float
//! on the M4F, and most of an f32 model step. `F32x` does every operation in `f32` (FPU
//! instructions only) with a Cody-Waite reduction by `pi/2` in three parts and the Cephes
//! minimax polynomials on `[-pi/4, pi/4]`; its error against the correctly rounded value is
//! measured by the tests (`twin/tests/fastmath.rs`). `tanh` and `exp` (friction extensions only)
//! stay with libm. All operations are IEEE single precision without fused multiply-add, so the
//! results are the same bits on the host and the M4F.

use core::ops::{Add, Div, Mul, Neg, Sub};
use crane_model::Real;

/// `f32` with FPU-only sine and cosine.
#[derive(Clone, Copy, Debug, PartialEq, PartialOrd, Default)]
pub struct F32x(pub f32);

impl Add for F32x {
    type Output = F32x;
    #[inline]
    fn add(self, o: F32x) -> F32x {
        F32x(self.0 + o.0)
    }
}

impl Sub for F32x {
    type Output = F32x;
    #[inline]
    fn sub(self, o: F32x) -> F32x {
        F32x(self.0 - o.0)
    }
}

impl Mul for F32x {
    type Output = F32x;
    #[inline]
    fn mul(self, o: F32x) -> F32x {
        F32x(self.0 * o.0)
    }
}

impl Div for F32x {
    type Output = F32x;
    #[inline]
    fn div(self, o: F32x) -> F32x {
        F32x(self.0 / o.0)
    }
}

impl Neg for F32x {
    type Output = F32x;
    #[inline]
    fn neg(self) -> F32x {
        F32x(-self.0)
    }
}

/// `2/pi`.
const FRAC_2_PI: f32 = core::f32::consts::FRAC_2_PI;
/// `pi/2` in three parts (Cody-Waite): `P1 + P2 + P3`, `P1` and `P2` with few significant bits
/// so `k * P1` and `k * P2` are exact for `|k| < 2^10`.
const P1: f32 = 1.570_312_5;
const P2: f32 = 4.837_513e-4;
const P3: f32 = 7.549_79e-8;

/// Sine and cosine of `x` [rad] in single precision. Accurate for `|x| < 1000` (the swing
/// angles stay within `(0, pi)` and a few radians); NaN or infinity gives NaN.
#[inline]
pub fn sincosf(x: f32) -> (f32, f32) {
    if !x.is_finite() {
        return (f32::NAN, f32::NAN);
    }
    let t = x * FRAC_2_PI;
    let k = if t >= 0.0 {
        (t + 0.5) as i32
    } else {
        (t - 0.5) as i32
    };
    let kf = k as f32;
    let r = ((x - kf * P1) - kf * P2) - kf * P3;
    let z = r * r;
    let s = ((-1.951_529_6e-4 * z + 8.332_161e-3) * z - 1.666_665_5e-1) * z * r + r;
    let c = ((2.443_315_7e-5 * z - 1.388_731_6e-3) * z + 4.166_664_6e-2) * z * z - 0.5 * z + 1.0;
    match k & 3 {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

impl Real for F32x {
    const ZERO: Self = F32x(0.0);
    const ONE: Self = F32x(1.0);
    const TWO: Self = F32x(2.0);
    const THREE: Self = F32x(3.0);
    const SIX: Self = F32x(6.0);
    const HALF: Self = F32x(0.5);

    #[inline]
    fn from_f64(x: f64) -> Self {
        F32x(x as f32)
    }

    #[inline]
    fn to_f64(self) -> f64 {
        f64::from(self.0)
    }

    #[inline]
    fn to_f32(self) -> f32 {
        self.0
    }

    #[inline]
    fn sin(self) -> Self {
        F32x(sincosf(self.0).0)
    }

    #[inline]
    fn cos(self) -> Self {
        F32x(sincosf(self.0).1)
    }

    #[inline]
    fn tanh(self) -> Self {
        F32x(<f32 as Real>::tanh(self.0))
    }

    #[inline]
    fn exp(self) -> Self {
        F32x(<f32 as Real>::exp(self.0))
    }

    #[inline]
    fn is_finite(self) -> bool {
        self.0.is_finite()
    }
}

//! The candidates measured on the Cortex-M4F, each behind a function that is never inlined
//! (model/NUMERICS.md "nalgebra and micromath: measured, not used").
#![no_std]

use crane_model::Real;
use nalgebra::{RealField, SMatrix, SVector};
use panic_semihosting as _;

/// The model's `solve5` (`model/src/solve.rs`, `pub(crate)` there), copied operation for
/// operation: Gaussian elimination without pivoting, NUMERICS.md "Linear solve".
#[inline(never)]
pub fn solve5<R: Real>(mut a: [[R; 5]; 5], mut r: [R; 5]) -> Option<[R; 5]> {
    for k in 0..5 {
        let pivot = a[k][k];
        if pivot.partial_cmp(&R::ZERO) != Some(core::cmp::Ordering::Greater) {
            return None;
        }
        let row_k = a[k];
        let r_k = r[k];
        for i in (k + 1)..5 {
            let f = a[i][k] / pivot;
            for j in k..5 {
                a[i][j] = a[i][j] - f * row_k[j];
            }
            r[i] = r[i] - f * r_k;
        }
    }
    let mut x = [R::ZERO; 5];
    for i in (0..5).rev() {
        let mut s = r[i];
        for j in (i + 1)..5 {
            s = s - a[i][j] * x[j];
        }
        x[i] = s / a[i][i];
    }
    Some(x)
}

/// nalgebra's LU with partial pivoting: `SMatrix::lu().solve`.
#[inline(never)]
pub fn lu<T: RealField + Copy>(a: [[T; 5]; 5], r: [T; 5]) -> Option<[T; 5]> {
    let m = SMatrix::<T, 5, 5>::from_fn(|i, j| a[i][j]);
    m.lu().solve(&SVector::from(r)).map(Into::into)
}

/// nalgebra's Cholesky: `SMatrix::cholesky()` and its `solve`.
#[inline(never)]
pub fn cholesky<T: RealField + Copy>(a: [[T; 5]; 5], r: [T; 5]) -> Option<[T; 5]> {
    let m = SMatrix::<T, 5, 5>::from_fn(|i, j| a[i][j]);
    m.cholesky().map(|c| c.solve(&SVector::from(r)).into())
}

/// The twin's `F32x` sine and cosine.
#[inline(never)]
pub fn fastmath_sincos(x: f32) -> (f32, f32) {
    crane_twin::logic::fastmath::sincosf(x)
}

/// libm's `sinf` and `cosf` (the model's own `f32`).
#[inline(never)]
pub fn libm_sincos(x: f32) -> (f32, f32) {
    (libm::sinf(x), libm::cosf(x))
}

/// micromath's `F32Ext::sin` and `cos`.
#[inline(never)]
pub fn micromath_sincos(x: f32) -> (f32, f32) {
    (micromath::F32Ext::sin(x), micromath::F32Ext::cos(x))
}

/// Nothing: the cost of a measured call itself.
#[inline(never)]
pub fn nothing(x: f32) -> (f32, f32) {
    (x, x)
}

/// Start of a measured interval (watched by the QEMU plugin).
#[inline(never)]
#[no_mangle]
pub extern "C" fn bench_start() {
    cortex_m::asm::nop();
}

/// End of a measured interval; its body differs from `bench_start`'s so the linker cannot
/// fold the two.
#[inline(never)]
#[no_mangle]
pub extern "C" fn bench_stop() {
    cortex_m::asm::nop();
    cortex_m::asm::nop();
}

/// A program that calls `$f` once on a `black_box`ed `1.0f32` (inputs and result through `black_box`) and exits:
/// the `size_*` binaries, whose `.text` minus `size_base`'s is the flash a candidate adds.
/// Every one of them carries a formatted panic, so the panic and formatting code is in the
/// base and not charged to a candidate that can panic.
#[macro_export]
macro_rules! size_main {
    ($f:expr) => {
        #[cortex_m_rt::entry]
        fn main() -> ! {
            let x = core::hint::black_box(1.0f32);
            if x > 2.0 {
                panic!("{}", x);
            }
            core::hint::black_box(($f)(x));
            cortex_m_semihosting::debug::exit(cortex_m_semihosting::debug::EXIT_SUCCESS);
            loop {
                cortex_m::asm::wfi();
            }
        }
    };
}

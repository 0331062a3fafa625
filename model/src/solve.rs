//! Linear solve of the 5x5 mass-matrix system.
//!
//! Gaussian elimination without pivoting: the mass matrix is symmetric positive definite, so
//! pivoting is not needed for stability, and a fixed operation order keeps the result
//! bit-identical to the reference (see `NUMERICS.md`). No term is skipped, even when zero.

use crate::real::Real;

/// The matrix had a non-positive (or NaN) pivot: not positive definite.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Singular;

/// Solves `a x = r` in place (`a`, `r` are overwritten); returns `x`.
pub(crate) fn solve5<R: Real>(mut a: [[R; 5]; 5], mut r: [R; 5]) -> Result<[R; 5], Singular> {
    for k in 0..5 {
        let pivot = a[k][k];
        // Rejects zero, negative and NaN pivots.
        if pivot.partial_cmp(&R::ZERO) != Some(core::cmp::Ordering::Greater) {
            return Err(Singular);
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
    Ok(x)
}

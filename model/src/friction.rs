//! Friction laws of the drive axes.
//!
//! Effective friction force `f` [N] opposes motion: it is subtracted from the drive force
//! `K u`. Hybrid law (moving axis): `f = Dbar(sign) qd + sign(qd) Cbar(sign)(q)`; a stopped
//! axis has no friction law, its friction is the holding force. Comparison law (the paper's
//! baseline, no modes): `f = Dbar qd + Cbar(q) tanh(gamma qd)`.

use crate::dynamics::AxisCoeffs;
use crate::modes::Mode;
use crate::real::Real;

/// Dry-friction magnitude `c0 + c1 p + c2 p^2 + c3 p^3 + c4 p^4` [N] by Horner, clamped at 0.
#[inline]
pub fn dry<R: Real>(c: &[R; 5], p: R) -> R {
    let [c0, c1, c2, c3, c4] = *c;
    let acc = c4;
    let acc = acc * p + c3;
    let acc = acc * p + c2;
    let acc = acc * p + c1;
    let acc = acc * p + c0;
    if acc > R::ZERO {
        acc
    } else {
        R::ZERO
    }
}

/// Hybrid friction [N] of an axis moving in `mode` with position `q` [m], velocity `qd` [m/s].
/// `Stopped` gives 0 (a stopped axis is held by the constraint instead).
#[inline]
pub(crate) fn hybrid<R: Real>(ax: &AxisCoeffs<R>, mode: Mode, q: R, qd: R) -> R {
    match mode {
        Mode::Positive => ax.visc_pos * qd + dry(&ax.dry_pos, q),
        Mode::Negative => ax.visc_neg * qd - dry(&ax.dry_neg, q),
        Mode::Stopped => R::ZERO,
    }
}

/// Smoothed friction `Dbar qd + Cbar(q) tanh(gamma qd)` [N]; the `+` coefficients are used
/// for `qd > 0`, the `-` ones otherwise.
#[inline]
pub(crate) fn smooth<R: Real>(ax: &AxisCoeffs<R>, gamma: R, q: R, qd: R) -> R {
    if qd > R::ZERO {
        ax.visc_pos * qd + dry(&ax.dry_pos, q) * (gamma * qd).tanh()
    } else {
        ax.visc_neg * qd + dry(&ax.dry_neg, q) * (gamma * qd).tanh()
    }
}

//! Friction laws of the drive axes.
//!
//! Effective friction force `f` [N] opposes motion: it is subtracted from the drive force
//! `K u`. Hybrid law (moving axis): `f = Dbar(sign) qd + sign(qd) Cbar(sign)(q)`; a stopped
//! axis has no friction law, its friction is the holding force. Comparison law (the paper's
//! baseline, no modes): `f = Dbar qd + Cbar(q) tanh(gamma qd)`.
//!
//! With [`Extensions`](crate::Extensions), `Cbar` gains localised bumps and, with stiction,
//! a Stribeck rise near zero speed and a breakaway threshold `ratio * Cbar`.

use crate::coeffs::AxisCoeffs;
use crate::mode::Mode;
use crate::real::Real;

/// `c0 + c1 p + c2 p^2 + c3 p^3 + c4 p^4` by Horner, not clamped.
#[inline]
pub fn horner<R: Real>(c: &[R; 5], p: R) -> R {
    let [c0, c1, c2, c3, c4] = *c;
    let acc = c4;
    let acc = acc * p + c3;
    let acc = acc * p + c2;
    let acc = acc * p + c1;
    acc * p + c0
}

#[inline]
fn clamp_zero<R: Real>(x: R) -> R {
    if x > R::ZERO {
        x
    } else {
        R::ZERO
    }
}

/// Dry-friction magnitude `c0 + c1 p + c2 p^2 + c3 p^3 + c4 p^4` [N] by Horner, clamped at 0.
#[inline]
pub fn dry<R: Real>(c: &[R; 5], p: R) -> R {
    clamp_zero(horner(c, p))
}

/// Sliding dry-friction magnitude [N] of an axis at position `q` [m] for direction `dir`
/// (`Positive` or `Negative`): the polynomial plus any localised bumps, clamped at 0.
#[inline]
pub fn dry_at<R: Real>(ax: &AxisCoeffs<R>, dir: Mode, q: R) -> R {
    let neg = dir == Mode::Negative;
    let mut acc = horner(if neg { &ax.dry_neg } else { &ax.dry_pos }, q);
    for b in ax.bumps.iter().take(ax.n_bumps) {
        if (neg && b.neg) || (!neg && b.pos) {
            let s = (q - b.center) / b.width;
            if s > -R::ONE && s < R::ONE {
                let t = R::ONE - s * s;
                acc = acc + b.amplitude * t * t;
            }
        }
    }
    clamp_zero(acc)
}

/// Breakaway threshold [N] of a stopped axis for direction `dir`: the sliding magnitude
/// times the stiction ratio when stiction is on.
#[inline]
pub fn breakaway<R: Real>(ax: &AxisCoeffs<R>, dir: Mode, q: R) -> R {
    let c = dry_at(ax, dir, q);
    match ax.stiction {
        Some((ratio, _)) => ratio * c,
        None => c,
    }
}

/// Sliding magnitude with the Stribeck rise near zero speed, when stiction is on.
#[inline]
fn sliding<R: Real>(ax: &AxisCoeffs<R>, dir: Mode, q: R, qd: R) -> R {
    let c = dry_at(ax, dir, q);
    match ax.stiction {
        Some((ratio, vs)) => {
            let x = qd / vs;
            c * (R::ONE + (ratio - R::ONE) * (-(x * x)).exp())
        }
        None => c,
    }
}

/// Hybrid friction [N] of an axis moving in `mode` with position `q` [m], velocity `qd` [m/s].
/// `Stopped` gives 0 (a stopped axis is held by the constraint instead).
#[inline]
pub(crate) fn hybrid<R: Real>(ax: &AxisCoeffs<R>, mode: Mode, q: R, qd: R) -> R {
    match mode {
        Mode::Positive => ax.visc_pos * qd + sliding(ax, Mode::Positive, q, qd),
        Mode::Negative => ax.visc_neg * qd - sliding(ax, Mode::Negative, q, qd),
        Mode::Stopped => R::ZERO,
    }
}

/// Smoothed friction `Dbar qd + Cbar(q) tanh(gamma qd)` [N]; the `+` coefficients are used
/// for `qd > 0`, the `-` ones otherwise.
#[inline]
pub(crate) fn smooth<R: Real>(ax: &AxisCoeffs<R>, gamma: R, q: R, qd: R) -> R {
    if qd > R::ZERO {
        ax.visc_pos * qd + dry_at(ax, Mode::Positive, q) * (gamma * qd).tanh()
    } else {
        ax.visc_neg * qd + dry_at(ax, Mode::Negative, q) * (gamma * qd).tanh()
    }
}

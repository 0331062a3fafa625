//! Friction-aware feedforward: the voltages the model says a reference motion of the trolley
//! (X, Y) and the rope needs.
//!
//! `F = M_red(q) a_ref + F_0(q, qd) + f(q_ref, v_ref)` per drive axis, `u = (F - d - b) / K`
//! (`b` the model's bias force, if on), saturated to +-12 V, where
//! - `F_0 = M_ds qdd_s + h_d + G_d` is the force that holds the drive axes still against the
//!   swing, Coriolis and gravity terms: the model's own terms at the state
//!   ([`dynamics::at_state`]), with the swing accelerations `qdd_s = M_ss^-1 (Q_s - h_s - G_s)`
//!   of the held drive axes (the model's holding force with all three drive axes stopped,
//!   without a full evaluation);
//! - `M_red` is the drive-axis mass matrix with the swing accelerations eliminated
//!   (`M_dd - M_ds M_ss^-1 M_sd`; `M_ss` is diagonal);
//! - `f` is the model's friction at the reference: `Dbar+ v + Cbar+(p)` or `Dbar- v - Cbar-(p)`
//!   (position- and direction-dependent, localised bumps included); from standstill (the twin
//!   holds the axis `Stopped`) the breakaway threshold (`ratio * Cbar`, times `1 + margin`) in
//!   the direction of the reference velocity, or of the acceleration when the velocity is 0;
//! - `d` is the observer's disturbance estimate (the friction the model gets wrong).

use crane_model::friction::{breakaway, dry_at};
use crane_model::{dynamics, Coeffs, Mode, Real, State};

/// Reference of the drive axes X, Y, L: position [m], velocity [m/s], acceleration [m/s^2].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reference<R: Real> {
    /// Positions.
    pub pos: [R; 3],
    /// Velocities.
    pub vel: [R; 3],
    /// Accelerations.
    pub acc: [R; 3],
}

/// Saturates to +-12 V; NaN gives 0.
pub fn saturate<R: Real>(u: R) -> R {
    let lim = R::from_f64(super::io::U_MAX);
    if !u.is_finite() {
        if u > R::ZERO {
            lim
        } else if u < R::ZERO {
            -lim
        } else {
            R::ZERO
        }
    } else if u > lim {
        lim
    } else if u < -lim {
        -lim
    } else {
        u
    }
}

/// The feedforward voltages for reference `r`, with the swing state taken from `est` (the
/// twin), standstill from `modes` (the twin's), disturbance estimate `dist` [N] and breakaway
/// `margin` (fraction). Saturated to +-12 V; a singular evaluation gives zeros.
pub fn voltages<R: Real>(
    c: &Coeffs<R>,
    est: &State<R>,
    modes: &[Mode; 3],
    r: &Reference<R>,
    dist: &[R; 3],
    margin: R,
) -> [R; 3] {
    let mut y = *est;
    for i in 0..3 {
        y.q[i] = r.pos[i];
        y.qd[i] = r.vel[i];
    }
    let zero = [R::ZERO; 3];
    // The model's terms at the reference (drive axes) and the twin's swing state.
    let pre = dynamics::at_state(c, &y);
    let m = &pre.m;
    let (m33, m44) = (m[3][3], m[4][4]);
    if !(m33 > R::ZERO && m44 > R::ZERO) {
        return zero;
    }
    // Swing accelerations with the drive axes held (M_ss is diagonal).
    let qdd3 = (-(c.damp_alpha * y.qd[3]) - pre.hv[3] - pre.gv[3]) / m33;
    let qdd4 = (-(c.damp_beta * y.qd[4]) - pre.hv[4] - pre.gv[4]) / m44;
    let k3 = [m[0][3] / m33, m[1][3] / m33, m[2][3] / m33];
    let k4 = [m[0][4] / m44, m[1][4] / m44, m[2][4] / m44];
    let one = R::ONE;
    let mut u = [R::ZERO; 3];
    for i in 0..3 {
        // F_0: the force holding the drive axis against swing, Coriolis and gravity terms.
        let mut f = m[i][3] * qdd3 + m[i][4] * qdd4 + pre.hv[i] + pre.gv[i];
        for (j, (row, acc)) in m.iter().zip(r.acc).enumerate() {
            // M_red = M_dd - M_ds M_ss^-1 M_sd.
            let mred = m[i][j] - (k3[i] * row[3] + k4[i] * row[4]);
            f = f + mred * acc;
        }
        let ax = &c.axes[i];
        let (p, v, a) = (r.pos[i], r.vel[i], r.acc[i]);
        let dir = if v > R::ZERO {
            Mode::Positive
        } else if v < R::ZERO {
            Mode::Negative
        } else if modes[i] == Mode::Stopped && a > R::ZERO {
            Mode::Positive
        } else if modes[i] == Mode::Stopped && a < R::ZERO {
            Mode::Negative
        } else {
            Mode::Stopped
        };
        let dry = match dir {
            Mode::Stopped => R::ZERO,
            d if modes[i] == Mode::Stopped => breakaway(ax, d, p) * (one + margin),
            d => dry_at(ax, d, p),
        };
        let fr = match dir {
            Mode::Positive => ax.visc_pos * v + dry,
            Mode::Negative => ax.visc_neg * v - dry,
            Mode::Stopped => R::ZERO,
        };
        let bias = ax.offset.unwrap_or(R::ZERO);
        u[i] = saturate((f + fr - dist[i] - bias) / ax.gain);
    }
    u
}

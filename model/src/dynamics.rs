//! The continuous dynamics inside one mode: `M(q) qdd + h(q, qd) + G(q) = Q`.
//!
//! This is the energy-consistent Lagrangian form of `docs/MODEL.md` (the mass matrix
//! couples the rope to the trolley through `Jbar_l`, unlike the paper's printed coupling).
//! Stopped drive axes are constrained to `qdd_i = 0`: their row and column of `M` are
//! replaced by the unit vector and the holding force that friction must supply is computed
//! from the original row. The exact operation order is fixed by `NUMERICS.md`.

pub use crate::coeffs::{AxisCoeffs, BumpCoeffs, Coeffs};
use crate::friction::{hybrid, smooth};
use crate::mode::Mode;
use crate::real::Real;
use crate::solve::solve5;
pub use crate::solve::Singular;
use crate::state::State;

/// Friction law used by [`eval`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Law<R: Real> {
    /// The hybrid automaton: friction by mode, stopped axes held exactly.
    Hybrid,
    /// The smooth comparison law `tanh(gamma qd)` (gamma in s/m); modes are ignored.
    Tanh(R),
}

/// Result of one evaluation of the dynamics.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Eval<R: Real> {
    /// Accelerations `[xdd, ydd, Ldd, alphadd, betadd]` (0 exactly for stopped axes).
    pub qdd: [R; 5],
    /// Holding force [N] of each stopped drive axis (the force friction must supply, positive
    /// along the axis); 0 for moving axes.
    pub hold: [R; 3],
    /// Friction force [N] of each drive axis: the law's force when moving, the holding force
    /// when stopped.
    pub fric: [R; 3],
}

/// Mass matrix `M(q)` (symmetric, 5x5, SI units: kg, kg m, kg m^2).
#[inline]
fn mass_matrix<R: Real>(c: &Coeffs<R>, l: R, sa: R, ca: R, sb: R, cb: R) -> [[R; 5]; 5] {
    let mp = c.mp;
    let mpl = mp * l;
    let m02 = mp * sa * sb;
    let m03 = mpl * ca * sb;
    let m04 = mpl * sa * cb;
    let m12 = mp * ca;
    let m13 = -(mpl * sa);
    let m33 = mpl * l;
    let m44 = m33 * sa * sa;
    let z = R::ZERO;
    [
        [c.m00, z, m02, m03, m04],
        [z, c.m11, m12, m13, z],
        [m02, m12, c.m22, z, z],
        [m03, m13, z, m33, z],
        [m04, z, z, z, m44],
    ]
}

/// The mode-independent part of an evaluation at one state, `M(q) qdd + h(q, qd) + G(q) = Q`:
/// mass matrix, centrifugal and Coriolis terms, gravity. Computing it once lets the mode
/// resolution try several mode sets at the same state without repeating the trigonometry
/// (the same bits as [`eval`]), and gives tools (feedforward) the model's own terms.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AtState<R: Real> {
    /// Mass matrix `M(q)` (symmetric; kg, kg m, kg m^2).
    pub m: [[R; 5]; 5],
    /// Centrifugal and Coriolis terms `h(q, qd)` [N, N, N, N m, N m].
    pub hv: [R; 5],
    /// Gravity terms `G(q)` [N, N, N, N m, N m] (0 for X and Y).
    pub gv: [R; 5],
}

/// The mode-independent part of [`eval`] at state `y` (NUMERICS.md "One evaluation").
pub fn at_state<R: Real>(c: &Coeffs<R>, y: &State<R>) -> AtState<R> {
    let [_, _, l, a, b] = y.q;
    let [_, _, ld, ad, bd] = y.qd;
    let ((sa, ca), (sb, cb)) = (a.sin_cos(), b.sin_cos());
    let mp = c.mp;
    let mpl = mp * l;
    let ad2 = ad * ad;
    let bd2 = bd * bd;
    let two = R::TWO;
    let z = R::ZERO;

    let m = mass_matrix(c, l, sa, ca, sb, cb);
    // Centrifugal and Coriolis terms.
    let hv = [
        mp * (l * (two * ad * bd * ca * cb - (ad2 + bd2) * sa * sb)
            + two * ld * (ad * sb * ca + bd * sa * cb)),
        -(mp * ad * (l * ad * ca + two * ld * sa)),
        -(mpl * (ad2 + bd2 * sa * sa)),
        mpl * (two * ld * ad - l * bd2 * sa * ca),
        mpl * bd * (two * l * ad * sa * ca + two * ld * sa * sa),
    ];
    // Gravity.
    let gv = [
        z,
        z,
        -(c.mpg * sa * cb),
        -(c.mpg * l * ca * cb),
        c.mpg * l * sa * sb,
    ];
    AtState { m, hv, gv }
}

/// Evaluates the accelerations, holding and friction forces at state `y`, in `modes`, with
/// (already saturated) input voltages `u` [V].
pub fn eval<R: Real>(
    c: &Coeffs<R>,
    law: Law<R>,
    y: &State<R>,
    modes: &[Mode; 3],
    u: &[R; 3],
) -> Result<Eval<R>, Singular> {
    eval_at(c, law, &at_state(c, y), y, modes, u)
}

/// [`eval`] with its mode-independent part `pre = at_state(c, y)` already computed.
pub(crate) fn eval_at<R: Real>(
    c: &Coeffs<R>,
    law: Law<R>,
    pre: &AtState<R>,
    y: &State<R>,
    modes: &[Mode; 3],
    u: &[R; 3],
) -> Result<Eval<R>, Singular> {
    let [_, _, _, ad, bd] = y.qd;
    let z = R::ZERO;
    let (m, hv, gv) = (&pre.m, &pre.hv, &pre.gv);

    // Friction of the drive axes (0 for stopped axes: the constraint holds them).
    let mut f = [z; 3];
    for i in 0..3 {
        let ax = &c.axes[i];
        f[i] = match law {
            Law::Hybrid => hybrid(ax, modes[i], y.q[i], y.qd[i]),
            Law::Tanh(gamma) => smooth(ax, gamma, y.q[i], y.qd[i]),
        };
    }
    let qv = [
        c.axes[0].drive(u[0]) - f[0],
        c.axes[1].drive(u[1]) - f[1],
        c.axes[2].drive(u[2]) - f[2],
        -(c.damp_alpha * ad),
        -(c.damp_beta * bd),
    ];
    let mut r = [z; 5];
    for j in 0..5 {
        r[j] = qv[j] - hv[j] - gv[j];
    }

    // Stopped axes: qdd_i = 0 exactly, by a unit row and column.
    let mut am = *m;
    let mut stopped = [false; 3];
    if law == Law::Hybrid {
        for i in 0..3 {
            if modes[i] == Mode::Stopped {
                stopped[i] = true;
                for row in am.iter_mut() {
                    row[i] = z;
                }
                am[i] = [z; 5];
                am[i][i] = R::ONE;
                r[i] = z;
            }
        }
    }
    let qdd = solve5(am, r)?;

    let mut hold = [z; 3];
    let mut fric = f;
    for i in 0..3 {
        if stopped[i] {
            let row = m[i];
            let mut s = row[0] * qdd[0];
            for j in 1..5 {
                s = s + row[j] * qdd[j];
            }
            let hf = c.axes[i].drive(u[i]) - (s + hv[i] + gv[i]);
            hold[i] = hf;
            fric[i] = hf;
        }
    }
    Ok(Eval { qdd, hold, fric })
}

/// Plastic impact of moving drive axis `i` on its end stop, applied to the velocities.
///
/// The stop acts on coordinate `i` only (the bumper touches only the rail or trolley; the rope
/// force stays finite, so the payload's velocity is continuous). The impulse `p e_i` that
/// brings `qd_i` to zero changes the free velocities by `-(qd_i / w_i) w` with
/// `w = M_FF^-1 e_i` (stopped axes held), and the kinetic energy by `-qd_i^2 / (2 w_i) <= 0`:
/// an end stop never adds energy. The caller then sets `qd_i := 0` exactly.
pub(crate) fn end_stop_impulse<R: Real>(
    c: &Coeffs<R>,
    y: &mut State<R>,
    modes: &[Mode; 3],
    i: usize,
) -> Result<(), Singular> {
    let [_, _, l, a, b] = y.q;
    let ((sa, ca), (sb, cb)) = (a.sin_cos(), b.sin_cos());
    let mut am = mass_matrix(c, l, sa, ca, sb, cb);
    let z = R::ZERO;
    let mut held = [false; 5];
    for (j, m) in modes.iter().enumerate() {
        if *m == Mode::Stopped {
            for row in am.iter_mut() {
                row[j] = z;
            }
            am[j] = [z; 5];
            am[j][j] = R::ONE;
            held[j] = true;
        }
    }
    let mut r = [z; 5];
    r[i] = R::ONE;
    let w = solve5(am, r)?;
    let wi = w[i];
    if wi.partial_cmp(&z) != Some(core::cmp::Ordering::Greater) {
        return Err(Singular);
    }
    let k = y.qd[i] / wi;
    for j in 0..5 {
        if j != i && !held[j] {
            y.qd[j] = y.qd[j] - k * w[j];
        }
    }
    Ok(())
}

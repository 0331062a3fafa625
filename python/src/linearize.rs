//! `crane_twin.linearize`: the Jacobians `A = df/dx`, `B = df/du` of the continuous-time
//! right-hand side `dx/dt = f(x, u)` of the model at an operating point, by central finite
//! differences (for python-control and other linear tools).
//!
//! `x = [x, y, L, alpha, beta, xd, yd, Ld, alphad, betad]` [m, m, m, rad, rad, m/s, m/s, m/s,
//! rad/s, rad/s] and `u = [u_x, u_y, u_l]` [V]; `f(x, u) = [qd, qdd]` with `qdd` the model's
//! own accelerations (`crane_model::dynamics::eval`, the function the integrator steps).
//!
//! - Hybrid law: evaluated in the modes of the point. Dry friction is not differentiable at
//!   zero velocity, so X and Y must slide; the rope may slide or be held by its friction
//!   (then its rows and its velocity's column are zero: `L` stays constant while the holding
//!   force stays inside the breakaway band).
//! - `tanh` law (`Dbar qd + Cbar(q) tanh(gamma qd)`): smooth in every velocity, so any point
//!   is accepted, the hanging equilibrium at rest included. The `+` and `-` coefficients of
//!   an axis meet at `qd = 0` with one-sided slopes `Dbar(+-) + gamma Cbar(+-)(q)`; where they
//!   differ, the central difference gives their mean.

use crate::arrays::array;
use crate::errors::{input, py_result, Failure, Fallible};
use crate::py_crane::setup_from;
use crane_model::dynamics::{eval, Law};
use crane_model::friction::breakaway;
use crane_model::{Crane, FrictionLaw, Mode, State, U_MAX};
use pyo3::prelude::*;

/// Largest relative difference step accepted for `eps`.
const MAX_EPS: f64 = 1e-3;
/// Largest `eps * gamma` accepted for the `tanh` law: a velocity step [m/s] of at most 1 %
/// of the law's velocity scale `1 / gamma`, so the difference's relative error stays below
/// about `(eps gamma)^2 / 3 = 3.3e-5`.
const MAX_EPS_GAMMA: f64 = 1e-2;
const AXIS: [&str; 3] = ["X", "Y", "the rope"];
const QD: [&str; 3] = ["xd", "yd", "Ld"];

/// The Jacobians at one point: `a[i][j] = d f_i / d x_j`, `b[i][k] = d f_i / d u_k`.
#[derive(Clone, Debug, PartialEq)]
pub struct Linear {
    /// `df/dx`, 10 x 10.
    pub a: [[f64; 10]; 10],
    /// `df/du`, 10 x 3.
    pub b: [[f64; 3]; 10],
}

/// Whether the rope is held by friction at the point: checks that X and Y slide, the rope
/// slides or is held strictly inside its breakaway band, and every sliding velocity is larger
/// than its difference step.
fn check_point(crane: &Crane, u: &[f64; 3], step: impl Fn(f64) -> f64) -> Fallible<bool> {
    let (s, modes) = (crane.state(), crane.modes());
    for i in 0..3 {
        let qd = s.qd[i];
        if modes[i] == Mode::Stopped && i < 2 {
            return input(format!(
                "`state.qd[{i}]` ({}) is {qd}: {} is stopped (mode 0), held by dry friction, which is not differentiable at zero velocity; linearise at a point where X and Y slide (xd and yd nonzero; a limit stops an axis too)",
                QD[i], AXIS[i]
            ));
        }
        if modes[i] != Mode::Stopped && qd.abs() <= 2.0 * step(qd) {
            return input(format!(
                "`state.qd[{i}]` ({}) is {qd} m/s: {} slides too slowly for the difference step {} (choose a smaller `eps` or a faster point)",
                QD[i], AXIS[i], step(qd)
            ));
        }
    }
    if modes[2] != Mode::Stopped {
        return Ok(false);
    }
    let c = crane.coeffs();
    let e = eval(c, Law::Hybrid, &s, &modes, u)
        .map_err(|_| Failure::Input("`state`: the mass matrix is singular there".into()))?;
    let (ax, l, hold) = (&c.axes[2], s.q[2], e.hold[2]);
    let up = breakaway(ax, Mode::Positive, l);
    let down = breakaway(ax, Mode::Negative, l);
    if (l < ax.max && hold >= up) || (l > ax.min && hold <= -down) {
        return input(format!(
            "the rope is stopped (`state.qd[2]` = 0) but its holding force {hold} N is not strictly inside its breakaway band (-{down}, {up}) N: it breaks away at this input, so the point is not differentiable; linearise with Ld nonzero or a smaller `u[2]`"
        ));
    }
    Ok(true)
}

/// `f(x, u) = [qd, qdd]` under `law`, in the fixed `modes` (ignored by the `tanh` law).
fn rhs(
    crane: &Crane,
    law: Law<f64>,
    x: &[f64; 10],
    u: &[f64; 3],
    modes: &[Mode; 3],
) -> Fallible<[f64; 10]> {
    let mut s = State {
        q: [0.0; 5],
        qd: [0.0; 5],
    };
    s.q.copy_from_slice(&x[..5]);
    s.qd.copy_from_slice(&x[5..]);
    let e = eval(crane.coeffs(), law, &s, modes, u).map_err(|_| {
        Failure::Input("`state`: the mass matrix is singular near the point".into())
    })?;
    let mut f = [0.0; 10];
    f[..5].copy_from_slice(&s.qd);
    f[5..].copy_from_slice(&e.qdd);
    Ok(f)
}

/// The Jacobians of `crane`'s right-hand side under `law` at its state and the input `u` [V]
/// by central differences with steps `eps * max(1, |v|)` (`eps` relative, in `(0, 1e-3]`).
/// Hybrid law: in the modes of the state. Errors: `InputError` for an input within a step of
/// the +-12 V saturation or a bad `eps`; hybrid law: a stopped X or Y, a rope at its
/// breakaway; `tanh` law: `eps * gamma` above 0.01 (a velocity step too large for the law's
/// velocity scale `1 / gamma` [m/s]).
pub fn jacobians(crane: &Crane, law: FrictionLaw, u: [f64; 3], eps: f64) -> Fallible<Linear> {
    if !(eps > 0.0 && eps <= MAX_EPS) {
        return input(format!("`eps` must be in (0, {MAX_EPS}] (got {eps})"));
    }
    let law = match law {
        FrictionLaw::Hybrid => Law::Hybrid,
        FrictionLaw::Tanh { gamma } => {
            if eps * gamma > MAX_EPS_GAMMA {
                return input(format!(
                    "`eps` ({eps}) times `gamma` ({gamma} s/m) must be at most {MAX_EPS_GAMMA}: the tanh law bends over velocities of 1/gamma, so choose `eps` <= {} or a smaller `gamma`",
                    MAX_EPS_GAMMA / gamma
                ));
            }
            Law::Tanh(gamma)
        }
    };
    let step = |v: f64| eps * v.abs().max(1.0);
    for (k, &v) in u.iter().enumerate() {
        if !v.is_finite() || v.abs() + step(v) >= U_MAX {
            return input(format!(
                "`u[{k}]` is {v} V: the input must be finite and inside the +-{U_MAX} V saturation by more than the difference step (the saturation is not differentiable, and beyond it the input has no effect)"
            ));
        }
    }
    let held = law == Law::Hybrid && check_point(crane, &u, step)?;
    let modes = crane.modes();
    let s = crane.state();
    let mut x0 = [0.0; 10];
    x0[..5].copy_from_slice(&s.q);
    x0[5..].copy_from_slice(&s.qd);
    let mut lin = Linear {
        a: [[0.0; 10]; 10],
        b: [[0.0; 3]; 10],
    };
    for j in 0..10 {
        if held && j == 7 {
            continue; // Ld is held at 0: no column
        }
        let (mut xp, mut xm) = (x0, x0);
        xp[j] += step(x0[j]);
        xm[j] -= step(x0[j]);
        let (fp, fm) = (
            rhs(crane, law, &xp, &u, &modes)?,
            rhs(crane, law, &xm, &u, &modes)?,
        );
        for (i, row) in lin.a.iter_mut().enumerate() {
            row[j] = (fp[i] - fm[i]) / (xp[j] - xm[j]);
        }
    }
    for k in 0..3 {
        let (mut up, mut um) = (u, u);
        up[k] += step(u[k]);
        um[k] -= step(u[k]);
        let (fp, fm) = (
            rhs(crane, law, &x0, &up, &modes)?,
            rhs(crane, law, &x0, &um, &modes)?,
        );
        for (i, row) in lin.b.iter_mut().enumerate() {
            row[k] = (fp[i] - fm[i]) / (up[k] - um[k]);
        }
    }
    if held {
        // L and Ld do not move while the rope is held: zero rows.
        lin.a[2] = [0.0; 10];
        lin.a[7] = [0.0; 10];
        lin.b[2] = [0.0; 3];
        lin.b[7] = [0.0; 3];
    }
    Ok(lin)
}

/// `linearize(params, state, u, *, law="hybrid", gamma=1000.0, stiction=None, eps=1e-6)` ->
/// `(A, B)`: the Jacobians of the model's continuous-time right-hand side `dx/dt = f(x, u)`
/// at an operating point, for python-control (`control.ss(A, B, C, D)`) and other linear
/// tools.
///
/// `x = [x, y, L, alpha, beta, xd, yd, Ld, alphad, betad]` [m, m, m, rad, rad, m/s, m/s,
/// m/s, rad/s, rad/s] (hanging straight down is `alpha = pi/2, beta = 0`; positive `Ld`
/// lowers the payload), `u = [u_x, u_y, u_l]` [V]. `A` is `(10, 10)`, `B` `(10, 3)`, both
/// float64, by central finite differences of the model's own accelerations (not of one step)
/// with steps `eps * max(1, |v|)` per component. `params`, `state`, `law`, `gamma` [s/m] and
/// `stiction` take the forms `Crane` takes.
///
/// `law="hybrid"` (the product): in the modes of the point. X and Y must slide (`xd`, `yd`
/// nonzero): dry friction is not differentiable at zero velocity, and a stopped axis raises
/// `InputError` naming `state.qd[i]`. The rope may slide or be held by its friction with the
/// holding force strictly inside its breakaway band; held, its rows (`L`, `Ld`) and the `Ld`
/// column are zero. A sliding point is no equilibrium (`f(x0, u0) != 0`): `d(dx)/dt = A dx +
/// B du` describes deviations `dx`, `du` from the nonlinear trajectory through the point,
/// valid over short horizons while no axis stops.
///
/// `law="tanh"` (`Dbar qd + Cbar(q) tanh(gamma qd)`, no sticking): differentiable in every
/// velocity, so any point is accepted, at rest included. The hanging equilibrium is `q =
/// [x, y, L, pi/2, 0]`, `qd = 0`, `u = [0, 0, -payload_mass * gravity / rope.gain]` (the rope
/// drive carries the payload's weight; with `u_l = 0` the rope creeps down); there `A`, `B`
/// model small deviations for as long as they stay small, with friction acting as a viscous
/// slope `Dbar + gamma Cbar(q)` [N s/m], valid while `|gamma qd|` stays well below 1. Where an
/// axis' `+` and `-` coefficients differ, that slope has a kink at `qd = 0` and `A` holds the
/// mean of the two one-sided slopes. `eps * gamma` must be at most 0.01 (`InputError`).
/// `stiction` has no effect under this law (as in `Crane`). `A`'s fastest eigenvalue (real,
/// about `-(Dbar + gamma Cbar) / M` of the rope) bounds `Crane`'s fixed step under this law:
/// RK4 is stable for `h < 2.785 / |lambda|` (default parameters: 5.59 ms at `gamma=1000`,
/// 0.599 ms at 1e4).
#[pyfunction]
#[pyo3(signature = (params, state, u, *, law = "hybrid", gamma = 1000.0, stiction = None, eps = 1e-6))]
#[allow(clippy::too_many_arguments)]
pub fn linearize<'py>(
    py: Python<'py>,
    params: Option<&Bound<'py, PyAny>>,
    state: &Bound<'py, PyAny>,
    u: &Bound<'py, PyAny>,
    law: &str,
    gamma: f64,
    stiction: Option<&Bound<'py, PyAny>>,
    eps: f64,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
    if state.is_none() {
        return Err(Failure::Input(
            "`state`: linearize needs the operating point's 10 values (hybrid law: X and Y sliding)"
                .into(),
        )
        .into_pyerr(py));
    }
    let setup = setup_from(py, params, 1e-3, law, Some(state), gamma, stiction)?;
    let crane = py_result(py, setup.build().map_err(Failure::Param))?;
    let u: [f64; 3] = u.extract().map_err(|_| {
        Failure::Input("`u`: expected 3 voltages [u_x, u_y, u_l]".into()).into_pyerr(py)
    })?;
    let lin = py_result(py, jacobians(&crane, setup.config.law, u, eps))?;
    let a = array(py, lin.a.iter().flatten().copied().collect(), &[10, 10])?;
    let b = array(py, lin.b.iter().flatten().copied().collect(), &[10, 3])?;
    Ok((a, b))
}

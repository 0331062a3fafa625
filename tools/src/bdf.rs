//! The strongest stiff peer of the `tanh` models: `diffsol`'s variable-order BDF, driven on
//! the same right-hand side, error norm and output grid as [`crate::ode45`] and
//! [`crate::ode23s`].
//!
//! Why a crate here: a variable-order, variable-step BDF with Jacobian reuse is what LSODA's
//! stiff side and MATLAB's `ode15s` do, and `diffsol` (maintained, on crates.io) implements
//! exactly that; writing it again would be a second, less tested copy.
//!
//! Method: `diffsol::Bdf`, orders 1..5, the NDF formulas of `ode15s` (Shampine & Reichelt
//! 1997) in quasi-constant-step difference-table form; local error estimated from the next
//! difference, order and step chosen per step. Each step solves the implicit corrector by a
//! simplified Newton iteration with the matrix `I - c h J` factorised (dense LU, `nalgebra`)
//! and **kept across steps**: `J` is re-evaluated only when Newton fails to converge or the
//! step changed enough, so most steps cost 1..3 right-hand side evaluations and no
//! factorisation.
//!
//! Error control: `diffsol`'s RMS norm `sqrt(mean((e_i / (atol + rtol |y_i|))^2)) <= 1`, the
//! same form as [`crate::ode45`]'s. Output on the fixed grid by the solver's own interpolant
//! (the difference table, of the current order), so the samples cost no evaluation.
//!
//! Not used: `diffsol`'s ESDIRK34. On `y' = -1e4 (y - cos t)` sampled every 10 ms it missed
//! its tolerance by three orders (error 1.8e-3 at rtol 1e-6, where BDF gives 2.9e-7; not
//! investigated further), and on both crane cases it was never faster than BDF (1.0..7x its
//! time over gamma 1e2..1e6, rtol 1e-3..1e-8).
//!
//! Jacobian: by forward differences of `f` along the direction `diffsol` asks for
//! (`J v ~ (f(y + e v) - f(y)) / e`, `e = sqrt(eps) max(|y_j|, 1e-5) / |v_j|` over the
//! non-zero `v_j`, as [`crate::ode23s`]), with `f(y)` cached, so one dense Jacobian costs
//! `N + 1` evaluations (`diffsol` builds it column by column from unit vectors). An analytic
//! Jacobian of `M(q)^-1 (...)` is not available from `crane_model`; the upper half
//! (`q' = qd`) is linear, so its differences are exact to rounding.
//!
//! Cost per step: the Newton iterations (usually 1..3 evaluations), plus, rarely, a Jacobian
//! (`N + 1` evaluations) and a 10x10 LU; on the crane's `tanh` models 2.6..4.3 evaluations per
//! accepted step, Jacobians and rejected steps included (Rosenbrock 2(3): 13). [`Stats::evals`]
//! counts every evaluation. Measured (case 2, `tanh(1e6 v)`, rtol 1e-5, release build): an
//! evaluation of the crane's right-hand side costs 0.06 us, a run 1.0 ms for 3,039
//! evaluations in 891 steps: ~20 % of the time is the right-hand side, ~15 % interpolating the
//! 8,000 grid points and ~65 % `diffsol`'s own per-step work on heap vectors (~0.75 us per
//! step); a fixed-size BDF written for `N = 10` could be faster still.

use crate::ode45::{Options, Stats};
use diffsol::{
    NalgebraLU, NalgebraMat, NalgebraVec, OdeBuilder, OdeSolverMethod, Vector, VectorCommon,
};
use std::cell::{Cell, RefCell};

/// Newton failures allowed over one whole run. `diffsol` counts them over the run, not per
/// step, and stops at 50 by default: a `tanh` run passes 50 at its stick-slip transitions
/// (each one a Newton failure and a smaller step, then success). A hopeless step still stops
/// at `diffsol`'s smallest step.
const NEWTON_FAILS: usize = 1_000_000;

/// Why an integration stopped early.
#[derive(Clone, Debug, PartialEq)]
pub enum Failure {
    /// The right-hand side failed (e.g. singular mass matrix) at this time [s].
    Rhs(f64),
    /// `diffsol` gave up (step too small, Newton failures, bad options) at this time [s].
    Solver {
        /// Time reached [s].
        t: f64,
        /// `diffsol`'s message.
        message: String,
    },
}

impl core::fmt::Display for Failure {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Failure::Rhs(t) => write!(f, "right-hand side failed at t = {t}"),
            Failure::Solver { t, message } => write!(f, "diffsol stopped at t = {t}: {message}"),
        }
    }
}

/// Integrates `y' = f(t, y)` from `t0` to `t0 + n dt` by BDF, calling
/// `out(k, t_k, y(t_k))` for every grid time `t_k = t0 + k dt`, `k = 1..=n` (the solver's
/// interpolant). `f` returns `None` when it cannot be evaluated; the run then fails with
/// [`Failure::Rhs`]. `opts.hmax` is not used (`diffsol` has no largest step).
/// [`Stats::rejected`] counts error-test and Newton failures.
pub fn integrate<const N: usize>(
    f: impl Fn(f64, &[f64; N]) -> Option<[f64; N]>,
    t0: f64,
    y0: [f64; N],
    dt: f64,
    n: usize,
    opts: &Options,
    mut out: impl FnMut(usize, f64, &[f64; N]),
) -> Result<Stats, Failure> {
    let evals = Cell::new(0u64);
    let failed: Cell<Option<f64>> = Cell::new(None);
    // f(t, y) of the last Jacobian point: every column of one Jacobian shares it.
    let cache: RefCell<Option<Evaluated<N>>> = RefCell::new(None);
    let eval = |t: f64, x: &[f64]| -> [f64; N] {
        let mut y = [0.0; N];
        y.copy_from_slice(x);
        evals.set(evals.get() + 1);
        match f(t, &y) {
            Some(d) => d,
            None => {
                if failed.get().is_none() {
                    failed.set(Some(t));
                }
                [f64::NAN; N]
            }
        }
    };
    let rhs = |x: &[f64], _p: &[f64], t: f64, y: &mut [f64]| y.copy_from_slice(&eval(t, x));
    let jvp = |x: &[f64], _p: &[f64], t: f64, v: &[f64], y: &mut [f64]| {
        let fx = {
            let c = cache.borrow();
            match &*c {
                Some(e) if e.t == t && e.y[..] == *x => Some(e.f),
                _ => None,
            }
        };
        let fx = fx.unwrap_or_else(|| {
            let fx = eval(t, x);
            let mut cx = [0.0; N];
            cx.copy_from_slice(x);
            *cache.borrow_mut() = Some(Evaluated { t, y: cx, f: fx });
            fx
        });
        let (mut xs, mut vs) = (0.0f64, 0.0f64);
        for (xi, vi) in x.iter().zip(v) {
            if *vi != 0.0 {
                xs = xs.max(xi.abs());
                vs = vs.max(vi.abs());
            }
        }
        if vs == 0.0 {
            y.fill(0.0);
            return;
        }
        let e = f64::EPSILON.sqrt() * xs.max(1e-5) / vs;
        let mut xp = [0.0; N];
        for ((p, xi), vi) in xp.iter_mut().zip(x).zip(v) {
            *p = xi + e * vi;
        }
        let fp = eval(t, &xp);
        for ((yi, a), b) in y.iter_mut().zip(&fp).zip(&fx) {
            *yi = (a - b) / e;
        }
    };
    let problem = OdeBuilder::<NalgebraMat<f64>>::new()
        .t0(t0)
        .rtol(opts.rtol)
        .atol([opts.atol])
        .rhs_implicit(rhs, jvp)
        .init(move |_p, _t, y| y.copy_from_slice(&y0), N)
        .build()
        .map_err(|e| Failure::Solver {
            t: t0,
            message: e.to_string(),
        })?;
    let t_end = t0 + n as f64 * dt;
    let mut s = problem
        .bdf::<NalgebraLU<f64>>()
        .map_err(|e| solver_failure(t0, e))?;
    s.config_mut().maximum_newton_fails = NEWTON_FAILS;
    let mut st = drive(s, t0, dt, n, t_end, &failed, &mut out)?;
    st.evals = evals.get();
    Ok(st)
}

/// One evaluation `f = f(t, y)`.
struct Evaluated<const N: usize> {
    t: f64,
    y: [f64; N],
    f: [f64; N],
}

fn solver_failure(t: f64, e: diffsol::DiffsolError) -> Failure {
    Failure::Solver {
        t,
        message: e.to_string(),
    }
}

/// Steps `s` to `t_end`, writing every grid point as soon as a step passes it.
fn drive<'a, const N: usize, Eqn, S>(
    mut s: S,
    t0: f64,
    dt: f64,
    n: usize,
    t_end: f64,
    failed: &Cell<Option<f64>>,
    out: &mut impl FnMut(usize, f64, &[f64; N]),
) -> Result<Stats, Failure>
where
    Eqn: diffsol::OdeEquations<T = f64, V = NalgebraVec<f64>> + 'a,
    S: OdeSolverMethod<'a, Eqn>,
{
    s.set_stop_time(t_end).map_err(|e| solver_failure(t0, e))?;
    let mut buf = NalgebraVec::zeros(N, *s.state().y.context());
    let mut yk = [0.0; N];
    let mut next = 1usize;
    loop {
        let reason = s.step().map_err(|e| solver_failure(s.state().t, e));
        if let Some(t) = failed.get() {
            return Err(Failure::Rhs(t));
        }
        let reason = reason?;
        let t_now = s.state().t;
        while next <= n {
            let tk = t0 + next as f64 * dt;
            if tk > t_now {
                break;
            }
            s.interpolate_inplace(tk, &mut buf)
                .map_err(|e| solver_failure(t_now, e))?;
            yk.copy_from_slice(buf.inner().as_slice());
            out(next, tk, &yk);
            next += 1;
        }
        if matches!(reason, diffsol::OdeSolverStopReason::TstopReached) || next > n {
            break;
        }
    }
    let ds = s.get_statistics();
    Ok(Stats {
        accepted: ds.number_of_steps as u64,
        rejected: (ds.number_of_error_test_failures + ds.number_of_nonlinear_solver_fails) as u64,
        evals: 0,
    })
}

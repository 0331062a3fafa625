//! One way to run a `tanh(gamma v)` model of a case under a grid-output solver: the smoothed
//! model's right-hand side ([`crate::smooth`]) with the case's continuous-time input, the
//! solution written on the case's output grid (every component at every grid point, inside
//! the solver's run) by the solver's dense output.

use crate::cases::Case;
use crate::error::{Error, Result};
use crate::ode45::{Options, Stats};
use crate::reference::Trajectory;
use crate::smooth::{pack, unpack, Friction, Smooth};
use crate::{bdf, ode23s, ode45};

/// The solvers of the `tanh` models that write their solution on a grid.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GridSolver {
    /// Dormand-Prince 5(4), explicit ([`crate::ode45`]).
    Dp45,
    /// Rosenbrock 2(3), MATLAB's `ode23s` pair, stiff ([`crate::ode23s`]).
    Rosenbrock,
    /// `diffsol`'s variable-order BDF, stiff ([`crate::bdf`]).
    Bdf,
}

/// The `tanh(gamma v)` model of `case` (`gamma` [s/m or s/rad]) under `solver` with `opts`:
/// the trajectory on the case's grid and the solver's work. A failure names the solver's
/// reason and `gamma`.
pub fn tanh_run(
    case: &Case,
    gamma: f64,
    solver: GridSolver,
    opts: &Options,
) -> Result<(Trajectory, Stats)> {
    let sys = Smooth::new(&case.params, Friction::Tanh(gamma), case.held);
    let n = case.samples();
    let mut tr = Trajectory {
        h: 0.0,
        stride: 1,
        states: Vec::with_capacity(n + 1),
        ..Trajectory::default()
    };
    tr.states.push(case.init);
    let f = |t: f64, y: &[f64; 10]| sys.rhs(y, &case.u_at(t)).ok();
    let y0 = pack(&case.init);
    let out = |_: usize, _: f64, y: &[f64; 10]| tr.states.push(unpack(y));
    let stats = match solver {
        GridSolver::Dp45 => ode45::integrate(f, 0.0, y0, case.sample, n, opts, out)
            .map_err(|failure| Error::Ode45 { gamma, failure })?,
        GridSolver::Rosenbrock => ode23s::integrate(f, 0.0, y0, case.sample, n, opts, out)
            .map_err(|e| Error::Rosenbrock {
                gamma,
                failure: e.to_string(),
            })?,
        GridSolver::Bdf => bdf::integrate(f, 0.0, y0, case.sample, n, opts, out)
            .map_err(|failure| Error::Bdf { gamma, failure })?,
    };
    tr.steps = stats.accepted;
    Ok((tr, stats))
}

/// A tanh model of the case integrated by ode45; returns the trajectory and the solver's work.
pub fn tanh_ode45(case: &Case, gamma: f64, opts: &Options) -> Result<(Trajectory, Stats)> {
    tanh_run(case, gamma, GridSolver::Dp45, opts)
}

/// Name of a tanh model, e.g. `tanh(1000 v)`.
pub fn tanh_name(g: f64) -> String {
    if g == 1.0 {
        "tanh(v)".into()
    } else {
        format!("tanh({g} v)")
    }
}

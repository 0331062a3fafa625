//! `crane_twin.Crane`: one simulator, stepped from Python or rolled out in Rust.

use crate::args::{all_finite, f64_array, law_arg, params_arg, shape_str, state_arg, stiction_arg};
use crate::arrays::{state_array, tables_dict};
use crate::errors::{py_result, Failure};
use crate::py_params::PyParams;
use crate::rollout as run;
use crate::setup::{mode_code, Setup};
use crate::sim::Sim;
use crate::snapshot;
use crane_model::Config;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// Steps between two looks at Python's signals in a long `advance` (16384 steps: a few
/// milliseconds of model work, so Ctrl-C answers at once).
pub const SIGNAL_STEPS: usize = 1 << 14;

/// Builds a [`Setup`] from the Python arguments shared by `Crane`, `rollout`, `rollouts`.
#[allow(clippy::too_many_arguments)]
pub fn setup_from(
    py: Python<'_>,
    params: Option<&Bound<'_, PyAny>>,
    h: f64,
    law: &str,
    state: Option<&Bound<'_, PyAny>>,
    gamma: f64,
    stiction: Option<&Bound<'_, PyAny>>,
) -> PyResult<Setup> {
    let params = params_arg(py, params)?;
    let law = py_result(py, law_arg(law, gamma))?;
    let init = state_arg(py, state, "state")?;
    let ext = stiction_arg(py, stiction)?;
    Ok(Setup {
        params,
        config: Config { h, law },
        ext,
        init,
    })
}

/// The inputs `u` as `n` rows of 3 voltages [V] (shape `(n, 3)`), all finite.
pub fn inputs_2d(py: Python<'_>, u: &Bound<'_, PyAny>) -> PyResult<Vec<f64>> {
    let (data, shape) = f64_array(py, u, "u")?;
    if shape.len() != 2 || shape[1] != 3 {
        return Err(Failure::Input(format!(
            "`u`: expected shape (n, 3) of voltages [u_x, u_y, u_l], got {}",
            shape_str(&shape)
        ))
        .into_pyerr(py));
    }
    py_result(py, all_finite("u", &data, &shape))?;
    Ok(data)
}

/// A simulator of the crane: hybrid (exact-sticking) or `tanh` friction, fixed step.
///
/// `Crane(params=None, h=1e-3, law="hybrid", state=None, *, gamma=1000.0, stiction=None)`.
/// With `law="tanh"`, a large `gamma` [s/m] is stiff at rest: the fixed-step RK4 is stable
/// only for `h` below about `2.785 M / (Dbar + gamma Cbar)` of the stiffest axis (default
/// parameters: 5.59 ms at `gamma=1000`, 0.599 ms at 1e4, 0.060 ms at 1e5); above it the crane
/// at rest creeps without an error (see `model/NUMERICS.md`).
/// State vectors are `[x, y, L, alpha, beta, xd, yd, Ld, alphad, betad]` [m, rad, m/s,
/// rad/s]; inputs `[u_x, u_y, u_l]` [V], saturated to +-12 V.
///
/// Full snapshots (issue 23's `get_state` / `set_state`): `snapshot()` returns a dict of plain
/// values, `restore(snapshot)` and `Crane.from_snapshot(snapshot)` continue from it bit for
/// bit; `pickle` goes through them. `state` is only the physical state vector.
#[pyclass(module = "crane_twin._native", name = "Crane")]
pub struct PyCrane {
    sim: Sim,
    setup: Setup,
}

#[pymethods]
impl PyCrane {
    #[new]
    #[pyo3(signature = (params = None, h = 1e-3, law = "hybrid", state = None, *, gamma = 1000.0, stiction = None))]
    fn new(
        py: Python<'_>,
        params: Option<&Bound<'_, PyAny>>,
        h: f64,
        law: &str,
        state: Option<&Bound<'_, PyAny>>,
        gamma: f64,
        stiction: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let setup = setup_from(py, params, h, law, state, gamma, stiction)?;
        let crane = py_result(py, setup.build().map_err(Failure::Param))?;
        Ok(PyCrane {
            sim: Sim::new(crane),
            setup,
        })
    }

    /// An exact copy: same parameters, state, modes, step count and input history, so both
    /// continue bit for bit alike (`copy.copy`, `copy.deepcopy`; `pickle` too, through
    /// `snapshot`).
    fn __copy__(&self) -> Self {
        PyCrane {
            sim: self.sim.clone(),
            setup: self.setup.clone(),
        }
    }

    /// A full snapshot (what issue 23 calls `get_state`): a dict of plain Python values
    /// (picklable, JSON-serialisable) holding the parameters, `h`, `law`, `gamma`, `stiction`,
    /// the initial state `init` (for `reset()`), the `state` (10 values [m, rad, m/s,
    /// rad/s]), `modes` (-1, 0, 1 per drive axis), `steps` and the last input `u_last` [V],
    /// tagged `format = "crane_twin.Crane"`, `version = 1`. Not the `state` property (the
    /// physical state vector only).
    fn snapshot<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        snapshot::crane_to_dict(py, &self.sim, &self.setup)
    }

    /// Puts this simulator where `snapshot` (a dict from `snapshot()`, of any `Crane`) says
    /// (what issue 23 calls `set_state`): parameters, step, law, state, modes, step count and
    /// last input; it then continues bit for bit as the simulator the snapshot was taken of.
    /// A missing, unknown or malformed key raises `InputError` naming it
    /// (`snapshot["modes"]`), a value the model refuses `ParameterError`; on error nothing
    /// changes.
    fn restore(&mut self, py: Python<'_>, snapshot: &Bound<'_, PyAny>) -> PyResult<()> {
        let (sim, setup) = snapshot::crane_from_dict(py, snapshot, "snapshot")?;
        self.sim = sim;
        self.setup = setup;
        Ok(())
    }

    /// A new simulator from a `snapshot()` dict (see `restore`).
    #[staticmethod]
    fn from_snapshot(py: Python<'_>, snapshot: &Bound<'_, PyAny>) -> PyResult<Self> {
        let (sim, setup) = snapshot::crane_from_dict(py, snapshot, "snapshot")?;
        Ok(PyCrane { sim, setup })
    }

    /// Pickling: `Crane.from_snapshot(self.snapshot())`, exact (a versioned dict of plain
    /// values; see `snapshot`).
    fn __reduce__<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<(Bound<'py, PyAny>, (Bound<'py, PyDict>,))> {
        let ctor = py.get_type::<PyCrane>().getattr("from_snapshot")?;
        Ok((ctor, (self.snapshot(py)?,)))
    }

    /// See `__copy__` (a `Crane` holds no Python object, so `memo` is not needed).
    fn __deepcopy__(&self, _memo: &Bound<'_, PyAny>) -> Self {
        self.__copy__()
    }

    /// One step of `h` with voltages `u = [u_x, u_y, u_l]` [V]; returns the new state.
    /// A rejected step (`StepError`) leaves the simulator unchanged.
    fn step<'py>(&mut self, py: Python<'py>, u: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
        self.advance(py, u, 1)
    }

    /// `n` steps with the voltages `u` held; returns the new state. On a rejected step the
    /// simulator stays after the last accepted one (`StepError.step` tells which). Ctrl-C
    /// is seen every [`SIGNAL_STEPS`] steps (`KeyboardInterrupt`, the state after the last
    /// step taken).
    fn advance<'py>(
        &mut self,
        py: Python<'py>,
        u: &Bound<'py, PyAny>,
        n: i64,
    ) -> PyResult<Bound<'py, PyAny>> {
        let u: [f64; 3] = u.extract().map_err(|_| {
            Failure::Input("`u`: expected 3 voltages [u_x, u_y, u_l]".into()).into_pyerr(py)
        })?;
        let n = usize::try_from(n).map_err(|_| {
            Failure::Input(format!("`n`: the number of steps must be >= 0 (got {n})"))
                .into_pyerr(py)
        })?;
        for k in 0..n {
            if k % SIGNAL_STEPS == SIGNAL_STEPS - 1 {
                py.check_signals()?;
            }
            self.sim.step(u).map_err(|err| {
                Failure::Step {
                    err,
                    step: k,
                    sim: None,
                }
                .into_pyerr(py)
            })?;
        }
        state_array(py, &self.sim.crane().state())
    }

    /// Rolls out over the inputs `u` of shape `(n, 3)` from the current state (the GIL is
    /// released); returns the dict of `crane_twin.rollout`. The simulator ends after the run.
    fn rollout<'py>(
        &mut self,
        py: Python<'py>,
        u: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let data = inputs_2d(py, u)?;
        let t0 = self.sim.steps();
        let mut sim = self.sim.clone();
        let result = py.detach(|| {
            let r = run::rollout(&mut sim, &data);
            (r, sim)
        });
        self.sim = result.1;
        let tables = py_result(py, result.0)?;
        tables_dict(py, tables, self.sim.crane().h(), t0, false)
    }

    /// Back to a new simulator (step count 0) at `state` (default: the initial state).
    #[pyo3(signature = (state = None))]
    fn reset(&mut self, py: Python<'_>, state: Option<&Bound<'_, PyAny>>) -> PyResult<()> {
        let mut setup = self.setup.clone();
        if state.is_some_and(|s| !s.is_none()) {
            setup.init = state_arg(py, state, "state")?;
        }
        self.sim = Sim::new(py_result(py, setup.build().map_err(Failure::Param))?);
        Ok(())
    }

    /// The state `[x, y, L, alpha, beta, xd, yd, Ld, alphad, betad]`; setting it checks it
    /// (`ParameterError` naming `state.q[i]`) and derives the modes from the velocities.
    #[getter]
    fn state<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        state_array(py, &self.sim.crane().state())
    }

    #[setter(state)]
    fn set_state(&mut self, py: Python<'_>, value: &Bound<'_, PyAny>) -> PyResult<()> {
        let s = state_arg(py, Some(value), "state")?;
        py_result(py, self.sim.set_state(s).map_err(Failure::Param))
    }

    /// Modes of X, Y, rope: -1 moving negative, 0 stopped (held by friction), 1 positive.
    #[getter]
    fn modes(&self) -> (i8, i8, i8) {
        let m = self.sim.modes().map(mode_code);
        (m[0], m[1], m[2])
    }

    /// Derived quantities at the current state with the last input: `qdd` (5,), `friction`
    /// [N] (3,), `tension` [N], `payload` position [m] (3,).
    #[getter]
    fn output<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let o = self.sim.crane().output().map_err(|err| {
            Failure::Step {
                err,
                step: 0,
                sim: None,
            }
            .into_pyerr(py)
        })?;
        let d = PyDict::new(py);
        d.set_item("qdd", crate::arrays::array(py, o.qdd.to_vec(), &[5])?)?;
        d.set_item(
            "friction",
            crate::arrays::array(py, o.friction.to_vec(), &[3])?,
        )?;
        d.set_item("tension", o.tension)?;
        d.set_item(
            "payload",
            crate::arrays::array(py, o.payload.to_vec(), &[3])?,
        )?;
        Ok(d)
    }

    /// Simulated time [s].
    #[getter]
    fn time(&self) -> f64 {
        self.sim.time()
    }

    /// Accepted steps.
    #[getter]
    fn steps(&self) -> u64 {
        self.sim.steps()
    }

    /// Step [s].
    #[getter]
    fn h(&self) -> f64 {
        self.sim.crane().h()
    }

    /// The parameters.
    #[getter]
    fn params(&self) -> PyParams {
        PyParams {
            inner: self.setup.params,
        }
    }

    fn __repr__(&self) -> String {
        format!(
            "Crane(h={}, law={:?}, t={} s)",
            self.sim.crane().h(),
            self.setup.config.law,
            self.sim.time()
        )
    }
}

/// `rollout(u, params=None, h=1e-3, law="hybrid", state=None, *, gamma=1000.0,
/// stiction=None)`: a new simulator run over `u` `(n, 3)` [V] in Rust with the GIL released.
#[pyfunction(name = "rollout")]
#[pyo3(signature = (u, params = None, h = 1e-3, law = "hybrid", state = None, *, gamma = 1000.0, stiction = None))]
#[allow(clippy::too_many_arguments)]
pub fn rollout_fn<'py>(
    py: Python<'py>,
    u: &Bound<'py, PyAny>,
    params: Option<&Bound<'py, PyAny>>,
    h: f64,
    law: &str,
    state: Option<&Bound<'py, PyAny>>,
    gamma: f64,
    stiction: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let setup = setup_from(py, params, h, law, state, gamma, stiction)?;
    let mut sim = Sim::new(py_result(py, setup.build().map_err(Failure::Param))?);
    let data = inputs_2d(py, u)?;
    let tables = py_result(py, py.detach(|| run::rollout(&mut sim, &data)))?;
    tables_dict(py, tables, h, 0, false)
}

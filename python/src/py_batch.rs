//! Many simulators at once, in Rust, in parallel on rayon with the GIL released:
//! `rollouts` (whole runs) and `CraneBatch` (stepped together, for vector environments).

use crate::args::{
    all_finite, f64_array, law_arg, params_arg, shape_str, state_arg, state_from_flat, stiction_arg,
};
use crate::arrays::{array, tables_dict};
use crate::errors::{py_result, Failure, Fallible};
use crate::py_params::params_from_dict_unchecked;
use crate::rollout::{self, Inputs};
use crate::setup::{mode_code, Setup};
use crate::sim::Sim;
use crate::snapshot;
use crane_model::{Config, Crane, Extensions, State};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rayon::prelude::*;

/// Largest thread count accepted for `threads`.
const MAX_THREADS: usize = 1024;

/// Runs `f` on a rayon pool of `threads` threads (`None`: the global pool, one per core).
fn on_pool<T: Send>(threads: Option<usize>, f: impl FnOnce() -> T + Send) -> Fallible<T> {
    match threads {
        None => Ok(f()),
        Some(n) if (1..=MAX_THREADS).contains(&n) => {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .map_err(|e| Failure::Input(format!("`threads`: {e}")))?;
            Ok(pool.install(f))
        }
        Some(n) => Err(Failure::Input(format!(
            "`threads` must be in 1..={MAX_THREADS} (got {n})"
        ))),
    }
}

/// Initial states: `None` (the default for all), one state for all, or `(sims, 10)`.
fn states_arg(py: Python<'_>, obj: Option<&Bound<'_, PyAny>>, sims: usize) -> PyResult<Vec<State>> {
    let Some(obj) = obj.filter(|o| !o.is_none()) else {
        return Ok(vec![state_arg(py, None, "state")?; sims]);
    };
    if obj.cast::<PyDict>().is_ok() {
        return Ok(vec![state_arg(py, Some(obj), "state")?; sims]);
    }
    let (data, shape) = f64_array(py, obj, "state")?;
    if shape.len() == 2 && shape[0] == sims && shape[1] == 10 {
        return data
            .chunks_exact(10)
            .map(|c| state_from_flat(c, &[10], "state").map_err(|f| f.into_pyerr(py)))
            .collect();
    }
    if shape == [10] || shape == [2, 5] {
        let s = py_result(py, state_from_flat(&data, &shape, "state"))?;
        return Ok(vec![s; sims]);
    }
    Err(Failure::Input(format!(
        "`state`: expected 10 values or shape ({sims}, 10), got {}",
        shape_str(&shape)
    ))
    .into_pyerr(py))
}

/// Builds every simulator, naming the first bad list element.
fn build_all(setups: &[Setup]) -> Fallible<Vec<Crane>> {
    setups
        .iter()
        .enumerate()
        .map(|(i, s)| s.build().map_err(|e| Failure::ParamIn("params_list", i, e)))
        .collect()
}

/// The setups of a batch from the shared Python arguments.
#[allow(clippy::too_many_arguments)]
fn setups_from(
    py: Python<'_>,
    params_list: &Bound<'_, PyAny>,
    h: f64,
    law: &str,
    state: Option<&Bound<'_, PyAny>>,
    gamma: f64,
    stiction: Option<&Bound<'_, PyAny>>,
) -> PyResult<Vec<Setup>> {
    let items: Vec<Bound<'_, PyAny>> =
        params_list
            .try_iter()
            .and_then(|it| it.collect())
            .map_err(|_| {
                Failure::Input("`params_list`: expected a sequence of parameters".into())
                    .into_pyerr(py)
            })?;
    let law = py_result(py, law_arg(law, gamma))?;
    let ext = stiction_arg(py, stiction)?;
    let states = states_arg(py, state, items.len())?;
    items
        .iter()
        .zip(states)
        .enumerate()
        .map(|(i, (p, init))| {
            // Dicts are validated with the others by `build_all`, naming the element.
            let params = match p.cast::<PyDict>() {
                Ok(d) => params_from_dict_unchecked(py, d)?,
                Err(_) => params_arg(py, Some(p)).map_err(|e| {
                    if e.is_instance_of::<pyo3::exceptions::PyTypeError>(py)
                        || e.value(py)
                            .get_type()
                            .name()
                            .is_ok_and(|n| n == "InputError")
                    {
                        Failure::Input(format!("params_list[{i}]: {}", e.value(py))).into_pyerr(py)
                    } else {
                        e
                    }
                })?,
            };
            Ok(Setup {
                params,
                config: Config { h, law },
                ext: ext.clone(),
                init,
            })
        })
        .collect()
}

/// `rollouts(params_list, u, threads=None, h=1e-3, law="hybrid", state=None, *,
/// gamma=1000.0, stiction=None)`: one simulation per parameter set, all in Rust on rayon
/// (`threads` workers; default one per core) with the GIL released. `u` is `(n, 3)` (shared)
/// or `(len(params_list), n, 3)`; `state` one state or `(len(params_list), 10)`. Returns the
/// dict of `rollout` with a leading simulation axis.
#[pyfunction]
#[pyo3(signature = (params_list, u, threads = None, h = 1e-3, law = "hybrid", state = None, *, gamma = 1000.0, stiction = None))]
#[allow(clippy::too_many_arguments)]
pub fn rollouts<'py>(
    py: Python<'py>,
    params_list: &Bound<'py, PyAny>,
    u: &Bound<'py, PyAny>,
    threads: Option<usize>,
    h: f64,
    law: &str,
    state: Option<&Bound<'py, PyAny>>,
    gamma: f64,
    stiction: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let setups = setups_from(py, params_list, h, law, state, gamma, stiction)?;
    py_result(py, build_all(&setups))?;
    let (data, shape) = f64_array(py, u, "u")?;
    py_result(py, all_finite("u", &data, &shape))?;
    let sims = setups.len();
    let (shared, n) = match shape.as_slice() {
        [n, 3] => (true, *n),
        [m, n, 3] if *m == sims => (false, *n),
        _ => {
            return Err(Failure::Input(format!(
                "`u`: expected shape (n, 3) or ({sims}, n, 3), got {}",
                shape_str(&shape)
            ))
            .into_pyerr(py))
        }
    };
    let tables = py.detach(|| {
        let inputs = if shared {
            Inputs::Shared(&data)
        } else {
            Inputs::Each(&data)
        };
        on_pool(threads, || rollout::rollouts(&setups, inputs, n)).and_then(|r| r)
    });
    tables_dict(py, py_result(py, tables)?, h, 0, true)
}

/// Simulators stepped together: `CraneBatch(params_list, h=1e-3, law="hybrid", state=None,
/// *, gamma=1000.0, stiction=None)`. `step(u)` advances all of them in Rust (in parallel
/// for large batches) with the GIL released; the vector environment is built on it.
///
/// Full snapshots (issue 23's `get_state` / `set_state`): `snapshot()`, `restore(snapshot)`,
/// `CraneBatch.from_snapshot(snapshot)`; `pickle` goes through them.
#[pyclass(module = "crane_twin._native", name = "CraneBatch")]
pub struct PyCraneBatch {
    cranes: Vec<Sim>,
    setups: Vec<Setup>,
}

/// Batches smaller than this are stepped on the calling thread (rayon's hand-off costs more).
const PARALLEL_FROM: usize = 64;

#[pymethods]
impl PyCraneBatch {
    #[new]
    #[pyo3(signature = (params_list, h = 1e-3, law = "hybrid", state = None, *, gamma = 1000.0, stiction = None))]
    fn new(
        py: Python<'_>,
        params_list: &Bound<'_, PyAny>,
        h: f64,
        law: &str,
        state: Option<&Bound<'_, PyAny>>,
        gamma: f64,
        stiction: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let setups = setups_from(py, params_list, h, law, state, gamma, stiction)?;
        let cranes = py_result(py, build_all(&setups))?;
        Ok(PyCraneBatch {
            cranes: cranes.into_iter().map(Sim::new).collect(),
            setups,
        })
    }

    /// A full snapshot of every simulator (what issue 23 calls `get_state`): the dict
    /// `{"format": "crane_twin.CraneBatch", "version": 1, "sims": [...]}` with one
    /// `Crane.snapshot()` dict per simulator (its parameters, stiction and initial state as
    /// `reset_sim` left them, state, modes, step count, last input). Plain Python values:
    /// picklable and JSON-serialisable.
    fn snapshot<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        snapshot::batch_to_dict(py, &self.cranes, &self.setups)
    }

    /// Replaces every simulator by those of `snapshot` (a dict from `snapshot()`; the batch
    /// takes its length), which then continue bit for bit (what issue 23 calls `set_state`).
    /// A missing, unknown or malformed key raises `InputError` naming it
    /// (`snapshot["sims"][2]["state"]`), a value the model refuses `ParameterError`; on error
    /// nothing changes.
    fn restore(&mut self, py: Python<'_>, snapshot: &Bound<'_, PyAny>) -> PyResult<()> {
        let (cranes, setups) = snapshot::batch_from_dict(py, snapshot, "snapshot")?;
        self.cranes = cranes;
        self.setups = setups;
        Ok(())
    }

    /// A new batch from a `snapshot()` dict (see `restore`).
    #[staticmethod]
    fn from_snapshot(py: Python<'_>, snapshot: &Bound<'_, PyAny>) -> PyResult<Self> {
        let (cranes, setups) = snapshot::batch_from_dict(py, snapshot, "snapshot")?;
        Ok(PyCraneBatch { cranes, setups })
    }

    /// Pickling: `CraneBatch.from_snapshot(self.snapshot())`, exact.
    fn __reduce__<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<(Bound<'py, PyAny>, (Bound<'py, PyDict>,))> {
        let ctor = py.get_type::<PyCraneBatch>().getattr("from_snapshot")?;
        Ok((ctor, (self.snapshot(py)?,)))
    }

    /// An exact copy of every simulator (`copy.copy`, `copy.deepcopy`): both batches continue
    /// bit for bit alike.
    fn __copy__(&self) -> Self {
        PyCraneBatch {
            cranes: self.cranes.clone(),
            setups: self.setups.clone(),
        }
    }

    /// See `__copy__` (a batch holds no Python object, so `memo` is not needed).
    fn __deepcopy__(&self, _memo: &Bound<'_, PyAny>) -> Self {
        self.__copy__()
    }

    fn __len__(&self) -> usize {
        self.cranes.len()
    }

    /// Advances every simulator `substeps` steps with its voltages held: `u` of shape
    /// `(len, 3)` [V]. Returns the states `(len, 10)`. A rejected step raises `StepError`
    /// naming the simulation; that simulator stays at its last accepted step (the others
    /// have taken their steps).
    #[pyo3(signature = (u, substeps = 1))]
    fn step<'py>(
        &mut self,
        py: Python<'py>,
        u: &Bound<'py, PyAny>,
        substeps: usize,
    ) -> PyResult<Bound<'py, PyAny>> {
        let (data, shape) = f64_array(py, u, "u")?;
        let m = self.cranes.len();
        if shape != [m, 3] {
            return Err(Failure::Input(format!(
                "`u`: expected shape ({m}, 3), got {}",
                shape_str(&shape)
            ))
            .into_pyerr(py));
        }
        py_result(py, all_finite("u", &data, &shape))?;
        let cranes = &mut self.cranes;
        let result: Result<(), Failure> = py.detach(|| {
            let one = |(i, (c, u)): (usize, (&mut Sim, &[f64]))| -> Result<(), Failure> {
                for k in 0..substeps {
                    c.step([u[0], u[1], u[2]]).map_err(|err| Failure::Step {
                        err,
                        step: k,
                        sim: Some(i),
                    })?;
                }
                Ok(())
            };
            if m >= PARALLEL_FROM {
                cranes
                    .par_iter_mut()
                    .zip(data.par_chunks_exact(3))
                    .enumerate()
                    .with_min_len(16)
                    .map(one)
                    .collect::<Vec<_>>()
                    .into_iter()
                    .collect()
            } else {
                cranes
                    .iter_mut()
                    .zip(data.chunks_exact(3))
                    .enumerate()
                    .map(one)
                    .collect::<Vec<_>>()
                    .into_iter()
                    .collect()
            }
        });
        py_result(py, result)?;
        self.states(py)
    }

    /// Rebuilds simulator `i` (a new episode): new parameters (any form `Crane` takes; None
    /// keeps them), state (None: the batch's initial state) and stiction (None: off).
    #[pyo3(signature = (i, params = None, state = None, stiction = None))]
    fn reset_sim(
        &mut self,
        py: Python<'_>,
        i: usize,
        params: Option<&Bound<'_, PyAny>>,
        state: Option<&Bound<'_, PyAny>>,
        stiction: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<()> {
        let m = self.cranes.len();
        let Some(setup) = self.setups.get(i) else {
            return Err(Failure::Input(format!("`i` must be below {m} (got {i})")).into_pyerr(py));
        };
        let mut setup = setup.clone();
        if params.is_some_and(|p| !p.is_none()) {
            setup.params = params_arg(py, params)?;
        }
        if state.is_some_and(|s| !s.is_none()) {
            setup.init = state_arg(py, state, "state")?;
        }
        setup.ext = if stiction.is_some() {
            stiction_arg(py, stiction)?
        } else {
            Extensions::default()
        };
        let crane = py_result(py, setup.build().map_err(Failure::Param))?;
        self.cranes[i] = Sim::new(crane);
        self.setups[i] = setup;
        Ok(())
    }

    /// States `(len, 10)`: `[x, y, L, alpha, beta, xd, yd, Ld, alphad, betad]`.
    #[getter]
    fn states<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let mut v = Vec::with_capacity(self.cranes.len() * 10);
        for c in &self.cranes {
            let s = c.crane().state();
            v.extend_from_slice(&s.q);
            v.extend_from_slice(&s.qd);
        }
        array(py, v, &[self.cranes.len(), 10])
    }

    /// Payload positions `(len, 3)` [m].
    #[getter]
    fn payload<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let mut v = Vec::with_capacity(self.cranes.len() * 3);
        for c in &self.cranes {
            v.extend_from_slice(&c.crane().state().payload());
        }
        array(py, v, &[self.cranes.len(), 3])
    }

    /// Modes `(len, 3)` int8: -1, 0 (stopped), 1.
    #[getter]
    fn modes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let v: Vec<i8> = self
            .cranes
            .iter()
            .flat_map(|c| c.modes().map(mode_code))
            .collect();
        array(py, v, &[self.cranes.len(), 3])
    }
}

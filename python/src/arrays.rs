//! Results to numpy arrays (owned by numpy, no copy after the Rust run).

use crate::rollout::Tables;
use numpy::{IntoPyArray, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// `data` as a numpy array of `shape` (row-major).
pub fn array<'py, T: numpy::Element>(
    py: Python<'py>,
    data: Vec<T>,
    shape: &[usize],
) -> PyResult<Bound<'py, PyAny>> {
    Ok(data.into_pyarray(py).reshape(shape.to_vec())?.into_any())
}

/// The dict of a rollout (`batch = false`: arrays `(n + 1, ...)`) or of a batch
/// (`(sims, n + 1, ...)`): `t` [s] `(n + 1,)`, `q`, `qd` `(..., 5)`, `modes` int8 `(..., 3)`,
/// `friction` [N] `(..., 3)`, `tension` [N] `(...)`, `payload` [m] `(..., 3)`.
pub fn tables_dict<'py>(
    py: Python<'py>,
    t: Tables,
    h: f64,
    t0_steps: u64,
    batch: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let lead: Vec<usize> = if batch {
        vec![t.sims, t.rows]
    } else {
        vec![t.rows]
    };
    let with = |k: usize| -> Vec<usize> {
        let mut s = lead.clone();
        s.push(k);
        s
    };
    let times: Vec<f64> = (0..t.rows as u64)
        .map(|k| (t0_steps + k) as f64 * h)
        .collect();
    d.set_item("t", array(py, times, &[t.rows])?)?;
    d.set_item("q", array(py, t.q, &with(5))?)?;
    d.set_item("qd", array(py, t.qd, &with(5))?)?;
    d.set_item("modes", array(py, t.modes, &with(3))?)?;
    d.set_item("friction", array(py, t.friction, &with(3))?)?;
    d.set_item("tension", array(py, t.tension, &lead)?)?;
    d.set_item("payload", array(py, t.payload, &with(3))?)?;
    Ok(d)
}

/// The state `[q, qd]` as a `(10,)` array.
pub fn state_array<'py>(py: Python<'py>, s: &crane_model::State) -> PyResult<Bound<'py, PyAny>> {
    let mut v = Vec::with_capacity(10);
    v.extend_from_slice(&s.q);
    v.extend_from_slice(&s.qd);
    array(py, v, &[10])
}

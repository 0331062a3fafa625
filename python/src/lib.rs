//! # crane-twin-py
//!
//! The Python extension `crane_twin._native` (package `crane_twin`, built by maturin from
//! `python/pyproject.toml`): the crane model of `crane-model` as `Crane`, `Params`,
//! `rollout`, `rollouts`, `CraneBatch` and `linearize`, with full snapshots (`snapshot` /
//! `restore`, pickling) of `Crane` and `CraneBatch`. Runs happen in Rust without per-step
//! Python calls; long runs release the GIL, and batches run in parallel on rayon.
//!
//! Every input from Python is checked before it reaches the model; the model's errors become
//! the typed exceptions of `crane_twin.errors` (a bad parameter names its field). Panics
//! cannot cross into Python: pyo3 turns one into `pyo3_runtime.PanicException`, and the crate
//! has no panicking path on user input (indices and shapes are checked first).

pub mod args;
pub mod arrays;
pub mod errors;
pub mod fields;
pub mod linearize;
pub mod params_toml;
pub mod py_batch;
pub mod py_crane;
pub mod py_params;
pub mod rollout;
pub mod setup;
pub mod sim;
pub mod snapshot;

use pyo3::prelude::*;

/// The extension module.
#[pymodule]
#[pyo3(name = "_native")]
fn native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<py_params::PyParams>()?;
    m.add_class::<py_crane::PyCrane>()?;
    m.add_class::<py_batch::PyCraneBatch>()?;
    m.add_function(wrap_pyfunction!(py_crane::rollout_fn, m)?)?;
    m.add_function(wrap_pyfunction!(py_batch::rollouts, m)?)?;
    m.add_function(wrap_pyfunction!(linearize::linearize, m)?)?;
    m.add("U_MAX", crane_model::U_MAX)?;
    Ok(())
}

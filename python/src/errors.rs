//! The model's errors as the typed Python exceptions of `crane_twin.errors`.
//!
//! The classes are defined in Python (so they carry attributes and docstrings, and
//! `except crane_twin.ParameterError` works without the extension); this module builds an
//! instance of the right class. If that module cannot be imported (the extension used on its
//! own), the built-in base class (`ValueError`, `RuntimeError`) is raised with the same text.

use crane_model::{Error, Problem, StepError};
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;

/// Why a call failed, before it becomes a Python exception.
#[derive(Debug)]
pub enum Failure {
    /// A rejected parameter, configuration or state field (`ParameterError`).
    Param(Error),
    /// [`Failure::Param`] of element `i` of a list argument named by the string.
    ParamIn(&'static str, usize, Error),
    /// [`Failure::Param`] inside a structured argument named by the string (a snapshot:
    /// `snapshot["state"]`); the message starts with that name, `field` is the model's.
    ParamAt(String, Error),
    /// A parameter file that cannot be read or parsed (`ParamsFileError`): the message
    /// names the file and, for syntax errors, the line and column.
    File(String),
    /// A rejected step (`StepError`): the simulation index in a batch, the step index.
    Step {
        /// What went wrong.
        err: StepError,
        /// Index of the step that was rejected (0 is the first step of the call).
        step: usize,
        /// Index of the simulation in a batch, if any.
        sim: Option<usize>,
    },
    /// An argument of the wrong type, shape or value (`InputError`).
    Input(String),
}

/// Snake-case name of a [`Problem`] (the `problem` attribute of `ParameterError`).
pub fn problem_name(p: Problem) -> &'static str {
    match p {
        Problem::NotFinite => "not_finite",
        Problem::NotPositive => "not_positive",
        Problem::Negative => "negative",
        Problem::EmptyRange => "empty_range",
        Problem::OutOfLimits => "out_of_limits",
        Problem::AngleOutOfRange => "angle_out_of_range",
        Problem::BelowOne => "below_one",
        Problem::TooLarge => "too_large",
        Problem::BelowKinetic => "below_kinetic",
        Problem::NotANumber => "not_a_number",
        Problem::NotBelowOne => "not_below_one",
        Problem::LevelBelowZero => "level_below_zero",
    }
}

/// Snake-case name of a [`StepError`] (the `kind` attribute of `StepError`).
pub fn step_kind(e: StepError) -> &'static str {
    match e {
        StepError::InputNotFinite { .. } => "input_not_finite",
        StepError::Singular => "singular",
        StepError::NonFinite => "non_finite",
        StepError::OutOfDomain => "out_of_domain",
        StepError::OutOfLimits { .. } => "out_of_limits",
    }
}

fn class<'py>(py: Python<'py>, name: &str) -> Option<Bound<'py, PyAny>> {
    py.import("crane_twin.errors")
        .and_then(|m| m.getattr(name))
        .ok()
}

fn build(
    py: Python<'_>,
    name: &str,
    args: Bound<'_, pyo3::types::PyTuple>,
    msg: String,
    runtime: bool,
) -> PyErr {
    if let Some(cls) = class(py, name) {
        match cls.call1(args) {
            Ok(v) => return PyErr::from_value(v),
            Err(e) => return e,
        }
    }
    if runtime {
        PyRuntimeError::new_err(msg)
    } else {
        PyValueError::new_err(msg)
    }
}

impl Failure {
    /// The Python exception.
    pub fn into_pyerr<'py>(self, py: Python<'py>) -> PyErr {
        use pyo3::types::PyTuple;
        let tuple = |items: Vec<Bound<'py, PyAny>>| PyTuple::new(py, items);
        let r = (|| -> PyResult<PyErr> {
            Ok(match self {
                Failure::Param(_) | Failure::ParamIn(..) | Failure::ParamAt(..) => {
                    let (e, msg) = match self {
                        Failure::ParamIn(list, i, e) => (e, format!("{list}[{i}]: {e}")),
                        Failure::ParamAt(at, e) => (e, format!("{at}: {e}")),
                        Failure::Param(e) => (e, e.to_string()),
                        _ => return Err(PyRuntimeError::new_err("unreachable")),
                    };
                    let args = tuple(vec![
                        msg.clone().into_pyobject(py)?.into_any(),
                        e.field.into_pyobject(py)?.into_any(),
                        problem_name(e.problem).into_pyobject(py)?.into_any(),
                        e.value.into_pyobject(py)?.into_any(),
                    ])?;
                    build(py, "ParameterError", args, msg, false)
                }
                Failure::File(msg) => {
                    let args = tuple(vec![msg.clone().into_pyobject(py)?.into_any()])?;
                    build(py, "ParamsFileError", args, msg, false)
                }
                Failure::Input(msg) => {
                    let args = tuple(vec![msg.clone().into_pyobject(py)?.into_any()])?;
                    build(py, "InputError", args, msg, false)
                }
                Failure::Step { err, step, sim } => {
                    let msg = match sim {
                        Some(s) => format!("simulation {s}, step {step}: {err}"),
                        None => format!("step {step}: {err}"),
                    };
                    let axis = match err {
                        StepError::InputNotFinite { axis } => Some(axis),
                        _ => None,
                    };
                    let args = tuple(vec![
                        msg.clone().into_pyobject(py)?.into_any(),
                        step_kind(err).into_pyobject(py)?.into_any(),
                        step.into_pyobject(py)?.into_any(),
                        sim.into_pyobject(py)?.into_any(),
                        axis.into_pyobject(py)?.into_any(),
                    ])?;
                    build(py, "StepError", args, msg, true)
                }
            })
        })();
        r.unwrap_or_else(|e| e)
    }
}

impl From<Error> for Failure {
    fn from(e: Error) -> Self {
        Failure::Param(e)
    }
}

/// Result of the crate's internal functions.
pub type Fallible<T> = Result<T, Failure>;

/// Converts a [`Fallible`] into a `PyResult`.
pub fn py_result<T>(py: Python<'_>, r: Fallible<T>) -> PyResult<T> {
    r.map_err(|f| f.into_pyerr(py))
}

/// An `InputError`.
pub fn input<T>(msg: impl Into<String>) -> Fallible<T> {
    Err(Failure::Input(msg.into()))
}

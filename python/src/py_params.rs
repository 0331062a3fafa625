//! `crane_twin.Params`: validated model parameters, to and from the CLI's TOML files.

use crate::errors::{py_result, Failure};
use crate::fields::{self, Shape, Value};
use crate::params_toml;
use crane_model::params::DRY_COEFFICIENTS;
use crane_model::Params;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

/// Model parameters (SI units; field names and meaning as `crane_model::Params` and the
/// TOML files of `crane identify`). Always valid: every constructor checks every field and
/// raises `ParameterError` naming the first bad one. Immutable; `replace` gives a changed copy.
#[pyclass(frozen, eq, module = "crane_twin._native", name = "Params")]
#[derive(Clone, Debug, PartialEq)]
pub struct PyParams {
    /// The parameters.
    pub inner: Params,
}

fn validated(py: Python<'_>, p: Params) -> PyResult<PyParams> {
    py_result(py, p.validate().map_err(Failure::Param))?;
    Ok(PyParams { inner: p })
}

fn input_err(py: Python<'_>, msg: String) -> PyErr {
    Failure::Input(msg).into_pyerr(py)
}

/// Sets the dotted field `name` from a Python value (a number, or 5 numbers for `dry_*`).
fn set_field(py: Python<'_>, p: &mut Params, name: &str, v: &Bound<'_, PyAny>) -> PyResult<()> {
    match fields::shape(name) {
        Some(Shape::Scalar) => {
            let x = v
                .extract::<f64>()
                .map_err(|_| input_err(py, format!("`{name}`: expected a number")))?;
            fields::set(p, name, Value::Scalar(x));
        }
        Some(Shape::Poly) => {
            let c = v.extract::<[f64; DRY_COEFFICIENTS]>().map_err(|_| {
                input_err(
                    py,
                    format!("`{name}`: expected {DRY_COEFFICIENTS} numbers c0..c4"),
                )
            })?;
            fields::set(p, name, Value::Poly(c));
        }
        None => {
            return Err(input_err(
                py,
                format!(
                    "unknown parameter `{name}` (known: {})",
                    fields::names().join(", ")
                ),
            ))
        }
    }
    Ok(())
}

/// Parameters from a nested dict (as the TOML file: `{"payload_mass": 0.3, "x": {"gain":
/// 3.2}}`); missing fields keep their defaults, unknown keys raise `InputError`.
pub fn params_from_dict(py: Python<'_>, d: &Bound<'_, PyDict>) -> PyResult<Params> {
    let p = params_from_dict_unchecked(py, d)?;
    py_result(py, p.validate().map_err(Failure::Param))?;
    Ok(p)
}

/// [`params_from_dict`] without the final validation (the caller validates, e.g. naming
/// the list element).
pub fn params_from_dict_unchecked(py: Python<'_>, d: &Bound<'_, PyDict>) -> PyResult<Params> {
    let mut p = Params::default();
    for (k, v) in d.iter() {
        let key: String = k
            .extract()
            .map_err(|_| input_err(py, "parameter keys must be strings".into()))?;
        if fields::is_axis(&key) {
            let sub = v
                .cast::<PyDict>()
                .map_err(|_| input_err(py, format!("`{key}`: expected a dict of axis fields")))?;
            for (fk, fv) in sub.iter() {
                let f: String = fk
                    .extract()
                    .map_err(|_| input_err(py, "parameter keys must be strings".into()))?;
                set_field(py, &mut p, &format!("{key}.{f}"), &fv)?;
            }
        } else {
            set_field(py, &mut p, &key, &v)?;
        }
    }
    Ok(p)
}

fn value_of<'py>(py: Python<'py>, p: &Params, name: &str) -> PyResult<Option<Bound<'py, PyAny>>> {
    Ok(match fields::get(p, name) {
        Some(Value::Scalar(x)) => Some(x.into_pyobject(py)?.into_any()),
        Some(Value::Poly(c)) => Some(PyList::new(py, c.iter())?.into_any()),
        None => None,
    })
}

impl PyParams {
    /// Reads and validates a parameter file; errors name the file (`ParamsFileError`).
    pub fn load_path(py: Python<'_>, path: &str) -> PyResult<PyParams> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| Failure::File(format!("{path}: {e}")).into_pyerr(py))?;
        let p = params_toml::parse(&text, path).map_err(|m| Failure::File(m).into_pyerr(py))?;
        Ok(PyParams { inner: p })
    }
}

#[pymethods]
impl PyParams {
    /// The default parameters (the INTECO 3D-Crane of `shared/MODEL.md`), with keyword
    /// overrides nested as the file: `Params(payload_mass=0.3, x={"gain": 3.0})`.
    #[new]
    #[pyo3(signature = (**fields))]
    fn new(py: Python<'_>, fields: Option<&Bound<'_, PyDict>>) -> PyResult<Self> {
        match fields {
            Some(d) => Ok(PyParams {
                inner: params_from_dict(py, d)?,
            }),
            None => validated(py, Params::default()),
        }
    }

    /// Parameters from the text of a TOML parameter file (every field required, unknown
    /// fields rejected, as the CLI). Raises `ParamsFileError` (with line and column) or
    /// `ParameterError`... both name `origin`.
    #[staticmethod]
    #[pyo3(signature = (text, origin = "<string>"))]
    fn from_toml(py: Python<'_>, text: &str, origin: &str) -> PyResult<Self> {
        let p = params_toml::parse(text, origin).map_err(|m| Failure::File(m).into_pyerr(py))?;
        Ok(PyParams { inner: p })
    }

    /// Reads a TOML parameter file (as written by `crane identify` or [`Params.save`]).
    #[staticmethod]
    fn load(py: Python<'_>, path: &Bound<'_, PyAny>) -> PyResult<Self> {
        let path: String = py
            .import("os")?
            .getattr("fspath")?
            .call1((path,))?
            .extract()?;
        Self::load_path(py, &path)
    }

    /// The TOML text of the parameter file.
    fn to_toml(&self, py: Python<'_>) -> PyResult<String> {
        params_toml::render(&self.inner).map_err(|m| Failure::File(m).into_pyerr(py))
    }

    /// Writes the parameter file atomically (a temporary file beside it, then a rename).
    fn save(&self, py: Python<'_>, path: &Bound<'_, PyAny>) -> PyResult<()> {
        let path: String = py
            .import("os")?
            .getattr("fspath")?
            .call1((path,))?
            .extract()?;
        let text = self.to_toml(py)?;
        let target = std::path::Path::new(&path);
        let name = target
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| "params.toml".into());
        let tmp = target.with_file_name(format!(".{name}.tmp{}", std::process::id()));
        let io = |e: std::io::Error| Failure::File(format!("{path}: {e}")).into_pyerr(py);
        std::fs::write(&tmp, text).map_err(io)?;
        std::fs::rename(&tmp, target).map_err(|e| {
            let _ = std::fs::remove_file(&tmp);
            io(e)
        })
    }

    /// Parameters from a nested dict; missing fields keep their defaults.
    #[staticmethod]
    fn from_dict(py: Python<'_>, d: &Bound<'_, PyDict>) -> PyResult<Self> {
        Ok(PyParams {
            inner: params_from_dict(py, d)?,
        })
    }

    /// The nested dict of every field (axis tables `x`, `y`, `rope` as dicts).
    pub fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let p = &self.inner;
        let d = PyDict::new(py);
        // an axis' dict is placed where its first field comes, in file order
        let mut axes: Vec<(crane_model::Axis, Bound<'py, PyDict>)> = Vec::new();
        for f in fields::fields() {
            let value = value_of(py, p, f.path)?;
            let Some(axis) = f.axis else {
                d.set_item(f.key, value)?;
                continue;
            };
            if let Some((_, sub)) = axes.iter().find(|(a, _)| *a == axis) {
                sub.set_item(f.key, value)?;
            } else {
                let sub = PyDict::new(py);
                sub.set_item(f.key, value)?;
                d.set_item(axis.name(), &sub)?;
                axes.push((axis, sub));
            }
        }
        Ok(d)
    }

    /// A copy with the dotted fields changed: `p.replace({"x.viscous_pos": 90.0})`, checked.
    fn replace(&self, py: Python<'_>, changes: &Bound<'_, PyDict>) -> PyResult<Self> {
        let mut p = self.inner;
        for (k, v) in changes.iter() {
            let key: String = k
                .extract()
                .map_err(|_| input_err(py, "parameter names must be strings".into()))?;
            set_field(py, &mut p, &key, &v)?;
        }
        validated(py, p)
    }

    /// Every dotted field name, in file order.
    #[staticmethod]
    fn names() -> Vec<String> {
        fields::names()
    }

    /// The value of a dotted field (`p["x.gain"]`): a float, or 5 floats for `dry_*`.
    fn __getitem__<'py>(&self, py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyAny>> {
        value_of(py, &self.inner, name)?.ok_or_else(|| {
            pyo3::exceptions::PyKeyError::new_err(format!("unknown parameter `{name}`"))
        })
    }

    fn __repr__(&self) -> String {
        format!(
            "Params(payload_mass={}, trolley_mass={}, rail_mass={}, gravity={}, ...)",
            self.inner.payload_mass,
            self.inner.trolley_mass,
            self.inner.rail_mass,
            self.inner.gravity
        )
    }

    /// Pickling (Ray, multiprocessing) through the dict of floats: exact.
    fn __reduce__<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<(Bound<'py, PyAny>, (Bound<'py, PyDict>,))> {
        let ctor = py.get_type::<PyParams>().getattr("from_dict")?;
        Ok((ctor, (self.to_dict(py)?,)))
    }
}

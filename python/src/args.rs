//! Arguments from Python: arrays, parameters, friction law, state, stiction. Every bad value
//! becomes an `InputError` (type, shape, unknown name) or a `ParameterError` (a model field)
//! naming the argument.

use crate::errors::{input, Failure, Fallible};
use crate::py_params::{params_from_dict, PyParams};
use crane_model::{Extensions, FrictionLaw, State, Stiction};
use numpy::{PyArrayDyn, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString};

/// The default initial state: `q = [0.25, 0.3, 0.35, pi/2, 0]` [m, m, m, rad, rad] at rest
/// (the default of `crane simulate`).
pub const DEFAULT_Q: [f64; 5] = [0.25, 0.3, 0.35, core::f64::consts::FRAC_PI_2, 0.0];

/// A C-contiguous float64 copy (or view) of `obj` with its shape, or an `InputError`
/// naming `name` if numpy cannot convert it.
pub fn f64_array(
    py: Python<'_>,
    obj: &Bound<'_, PyAny>,
    name: &str,
) -> PyResult<(Vec<f64>, Vec<usize>)> {
    let np = py.import("numpy")?;
    let conv = np
        .getattr("ascontiguousarray")?
        .call((obj, np.getattr("float64")?), None);
    let arr = match conv {
        Ok(a) => a,
        Err(e) => {
            return Err(Failure::Input(format!(
                "`{name}`: not convertible to a float64 array ({})",
                e.value(py)
            ))
            .into_pyerr(py))
        }
    };
    let arr = arr
        .cast::<PyArrayDyn<f64>>()
        .map_err(|_| Failure::Input(format!("`{name}`: not a float64 array")).into_pyerr(py))?;
    let ro = arr.readonly();
    let shape = ro.shape().to_vec();
    let data = ro
        .as_slice()
        .map_err(|_| Failure::Input(format!("`{name}`: not contiguous")).into_pyerr(py))?
        .to_vec();
    Ok((data, shape))
}

/// Checks that every value is finite, naming the first bad element.
pub fn all_finite(name: &str, data: &[f64], shape: &[usize]) -> Fallible<()> {
    if let Some(k) = data.iter().position(|v| !v.is_finite()) {
        let mut idx = Vec::with_capacity(shape.len());
        let mut rest = k;
        for d in shape.iter().rev() {
            let d = (*d).max(1);
            idx.push(rest % d);
            rest /= d;
        }
        idx.reverse();
        let idx: Vec<String> = idx.iter().map(|i| i.to_string()).collect();
        return input(format!(
            "`{name}[{}]` is not finite (got {})",
            idx.join(", "),
            data[k]
        ));
    }
    Ok(())
}

/// Shape as Python prints it.
pub fn shape_str(shape: &[usize]) -> String {
    let s: Vec<String> = shape.iter().map(|d| d.to_string()).collect();
    if s.len() == 1 {
        format!("({},)", s[0])
    } else {
        format!("({})", s.join(", "))
    }
}

/// Parameters: `None` (the defaults), a `Params`, a path (`str` or `os.PathLike`) of a TOML
/// parameter file, or a dict (nested as the file; missing fields keep their defaults).
pub fn params_arg(py: Python<'_>, obj: Option<&Bound<'_, PyAny>>) -> PyResult<crane_model::Params> {
    let Some(obj) = obj else {
        return Ok(crane_model::Params::default());
    };
    if obj.is_none() {
        return Ok(crane_model::Params::default());
    }
    if let Ok(p) = obj.cast::<PyParams>() {
        return Ok(p.get().inner);
    }
    if let Ok(d) = obj.cast::<PyDict>() {
        return params_from_dict(py, d);
    }
    let os = py.import("os")?;
    if obj.is_instance_of::<PyString>() || obj.is_instance(&os.getattr("PathLike")?)? {
        let path: String = os.getattr("fspath")?.call1((obj,))?.extract()?;
        return PyParams::load_path(py, &path).map(|p| p.inner);
    }
    Err(Failure::Input(format!(
        "`params`: expected None, crane_twin.Params, a path or a dict (got {})",
        obj.get_type().name()?
    ))
    .into_pyerr(py))
}

/// Friction law from its name: `"hybrid"` or `"tanh"` (with slope `gamma` [s/m]).
pub fn law_arg(law: &str, gamma: f64) -> Fallible<FrictionLaw> {
    match law {
        "hybrid" => Ok(FrictionLaw::Hybrid),
        "tanh" => Ok(FrictionLaw::Tanh { gamma }),
        _ => input(format!(
            "`law` must be \"hybrid\" or \"tanh\" (got {law:?})"
        )),
    }
}

/// A state from `None` (the default, at rest), a dict `{"q": [5], "qd": [5]}`, or an
/// array-like of 10 values `[x, y, L, alpha, beta, xd, yd, Ld, alphad, betad]` (or shape
/// `(2, 5)`). The model checks the values (limits, swing domain) when it is built.
pub fn state_arg(py: Python<'_>, obj: Option<&Bound<'_, PyAny>>, name: &str) -> PyResult<State> {
    let Some(obj) = obj.filter(|o| !o.is_none()) else {
        return Ok(State {
            q: DEFAULT_Q,
            qd: [0.0; 5],
        });
    };
    if let Ok(d) = obj.cast::<PyDict>() {
        let mut s = State {
            q: DEFAULT_Q,
            qd: [0.0; 5],
        };
        for (k, v) in d.iter() {
            let key: String = k.extract().map_err(|_| {
                Failure::Input(format!("`{name}`: keys must be \"q\" or \"qd\"")).into_pyerr(py)
            })?;
            let (data, shape) = f64_array(py, &v, &format!("{name}[{key:?}]"))?;
            if shape != [5] {
                return Err(Failure::Input(format!(
                    "`{name}[{key:?}]`: expected 5 values, got shape {}",
                    shape_str(&shape)
                ))
                .into_pyerr(py));
            }
            let mut a = [0.0; 5];
            a.copy_from_slice(&data);
            match key.as_str() {
                "q" => s.q = a,
                "qd" => s.qd = a,
                other => {
                    return Err(Failure::Input(format!(
                        "`{name}`: unknown key {other:?} (expected \"q\", \"qd\")"
                    ))
                    .into_pyerr(py))
                }
            }
        }
        return Ok(s);
    }
    let (data, shape) = f64_array(py, obj, name)?;
    state_from_flat(&data, &shape, name).map_err(|f| f.into_pyerr(py))
}

/// A state from 10 values (shape `(10,)` or `(2, 5)`).
pub fn state_from_flat(data: &[f64], shape: &[usize], name: &str) -> Fallible<State> {
    if !(shape == [10] || shape == [2, 5]) {
        return input(format!(
            "`{name}`: expected 10 values [x, y, L, alpha, beta, xd, yd, Ld, alphad, betad] (shape (10,) or (2, 5)), got shape {}",
            shape_str(shape)
        ));
    }
    let mut q = [0.0; 5];
    let mut qd = [0.0; 5];
    q.copy_from_slice(&data[..5]);
    qd.copy_from_slice(&data[5..10]);
    Ok(State { q, qd })
}

/// Stiction per axis: `None` (off), one `(ratio, velocity)` pair for X and Y, or a sequence
/// of three entries (X, Y, rope), each `None` or `(ratio >= 1, Stribeck velocity [m/s] > 0)`.
/// The values are checked by the model (`ParameterError` naming `stiction[i].ratio`).
pub fn stiction_arg(py: Python<'_>, obj: Option<&Bound<'_, PyAny>>) -> PyResult<Extensions> {
    let mut ext = Extensions::default();
    let Some(obj) = obj.filter(|o| !o.is_none()) else {
        return Ok(ext);
    };
    let bad = || {
        Failure::Input(
            "`stiction`: expected None, (ratio, velocity) for X and Y, or 3 entries (X, Y, rope) each None or (ratio, velocity)"
                .to_string(),
        )
        .into_pyerr(py)
    };
    if let Ok((ratio, velocity)) = obj.extract::<(f64, f64)>() {
        let s = Some(Stiction { ratio, velocity });
        ext.stiction = [s, s, None];
        return Ok(ext);
    }
    let items: Vec<Bound<'_, PyAny>> = obj.extract().map_err(|_| bad())?;
    if items.len() != 3 {
        return Err(bad());
    }
    for (slot, item) in ext.stiction.iter_mut().zip(items) {
        if item.is_none() {
            continue;
        }
        let (ratio, velocity) = item.extract::<(f64, f64)>().map_err(|_| bad())?;
        *slot = Some(Stiction { ratio, velocity });
    }
    Ok(ext)
}

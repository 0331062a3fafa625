//! Full snapshots of simulators as plain Python data (what issue 23 calls `get_state` /
//! `set_state`), and pickling through them.
//!
//! A `Crane` snapshot is a dict of plain Python values (floats, ints, strings, lists, None),
//! so it pickles and even goes through `json` exactly (Python writes floats with `repr`):
//!
//! | key | value |
//! |---|---|
//! | `format` | `"crane_twin.Crane"` |
//! | `version` | `1` |
//! | `params` | the nested dict of `Params.to_dict()` |
//! | `h` | step [s] |
//! | `law` | `"hybrid"` or `"tanh"` |
//! | `gamma` | the `tanh` slope [s/m], or None for `"hybrid"` |
//! | `stiction` | 3 entries (X, Y, rope), each None or `[ratio, velocity [m/s]]` |
//! | `init` | the 10 values `reset()` returns to |
//! | `state` | the 10 values `[x, y, L, alpha, beta, xd, yd, Ld, alphad, betad]` |
//! | `modes` | 3 ints (X, Y, rope): -1, 0, 1 |
//! | `steps` | accepted steps (`time = steps * h`) |
//! | `u_last` | the saturated input of the last step [V] (`output` uses it) |
//!
//! A `CraneBatch` snapshot is `{"format": "crane_twin.CraneBatch", "version": 1, "sims":
//! [one Crane snapshot per simulator]}`. Restoring checks every key: a missing, unknown or
//! malformed one raises `InputError` naming it (`snapshot["state"]`, `snapshot["sims"][2]
//! ["modes"]`); a value the model refuses raises `ParameterError` (its `field` the model's,
//! the message starting with the key). Nothing panics.

use crate::args::{f64_array, law_arg, shape_str, state_from_flat};
use crate::errors::{py_result, Failure};
use crate::py_params::{params_from_dict_unchecked, PyParams};
use crate::setup::{mode_code, Setup};
use crate::sim::Sim;
use crane_model::{Config, Extensions, FrictionLaw, State, Stiction};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyString};

/// The `format` of a `Crane` snapshot.
pub const CRANE_FORMAT: &str = "crane_twin.Crane";
/// The `format` of a `CraneBatch` snapshot.
pub const BATCH_FORMAT: &str = "crane_twin.CraneBatch";
/// The snapshot version this build writes and reads.
pub const VERSION: u64 = 1;

const CRANE_KEYS: [&str; 12] = [
    "format", "version", "params", "h", "law", "gamma", "stiction", "init", "state", "modes",
    "steps", "u_last",
];
const BATCH_KEYS: [&str; 3] = ["format", "version", "sims"];

fn input_err(py: Python<'_>, msg: String) -> PyErr {
    Failure::Input(msg).into_pyerr(py)
}

fn state_list<'py>(py: Python<'py>, s: &State) -> PyResult<Bound<'py, PyList>> {
    PyList::new(py, s.q.iter().chain(s.qd.iter()))
}

/// The snapshot dict of one simulator and its setup.
pub fn crane_to_dict<'py>(
    py: Python<'py>,
    sim: &Sim,
    setup: &Setup,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("format", CRANE_FORMAT)?;
    d.set_item("version", VERSION)?;
    let params = PyParams {
        inner: setup.params,
    };
    d.set_item("params", params.to_dict(py)?)?;
    d.set_item("h", setup.config.h)?;
    let (law, gamma) = match setup.config.law {
        FrictionLaw::Hybrid => ("hybrid", None),
        FrictionLaw::Tanh { gamma } => ("tanh", Some(gamma)),
    };
    d.set_item("law", law)?;
    d.set_item("gamma", gamma)?;
    let stiction = PyList::empty(py);
    for s in &setup.ext.stiction {
        match s {
            Some(s) => stiction.append(PyList::new(py, [s.ratio, s.velocity])?)?,
            None => stiction.append(py.None())?,
        }
    }
    d.set_item("stiction", stiction)?;
    d.set_item("init", state_list(py, &setup.init)?)?;
    d.set_item("state", state_list(py, &sim.crane().state())?)?;
    d.set_item("modes", PyList::new(py, sim.modes().map(mode_code))?)?;
    d.set_item("steps", sim.steps())?;
    d.set_item("u_last", PyList::new(py, sim.u_last())?)?;
    Ok(d)
}

/// The snapshot dict of a batch.
pub fn batch_to_dict<'py>(
    py: Python<'py>,
    sims: &[Sim],
    setups: &[Setup],
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("format", BATCH_FORMAT)?;
    d.set_item("version", VERSION)?;
    let list = PyList::empty(py);
    for (sim, setup) in sims.iter().zip(setups) {
        list.append(crane_to_dict(py, sim, setup)?)?;
    }
    d.set_item("sims", list)?;
    Ok(d)
}

/// `obj` as a snapshot dict of `format` and [`VERSION`] with no key outside `keys`.
fn checked_dict<'py>(
    py: Python<'py>,
    obj: &Bound<'py, PyAny>,
    at: &str,
    format: &str,
    keys: &[&str],
) -> PyResult<Bound<'py, PyDict>> {
    let d = obj.cast::<PyDict>().map_err(|_| {
        input_err(
            py,
            format!(
                "`{at}`: expected the dict of a {format} snapshot (got {})",
                obj.get_type()
                    .name()
                    .map(|n| n.to_string())
                    .unwrap_or_default()
            ),
        )
    })?;
    let fmt = get(py, d, at, "format")?;
    if fmt.extract::<String>().ok().as_deref() != Some(format) {
        return Err(input_err(
            py,
            format!(
                "`{at}[\"format\"]` must be {format:?} (got {})",
                fmt.repr()?
            ),
        ));
    }
    let version = get(py, d, at, "version")?;
    if version.extract::<u64>().ok() != Some(VERSION) {
        return Err(input_err(
            py,
            format!(
                "`{at}[\"version\"]`: version {} is not known (this crane_twin reads version {VERSION})",
                version.repr()?
            ),
        ));
    }
    for k in d.keys() {
        let known = k
            .cast::<PyString>()
            .ok()
            .and_then(|s| s.to_str().ok().map(|s| keys.contains(&s)))
            .unwrap_or(false);
        if !known {
            return Err(input_err(
                py,
                format!(
                    "`{at}`: unknown key {} (a version-{VERSION} snapshot has {})",
                    k.repr()?,
                    keys.join(", ")
                ),
            ));
        }
    }
    Ok(d.clone())
}

/// The value of `key`, or an `InputError` naming it.
fn get<'py>(
    py: Python<'py>,
    d: &Bound<'py, PyDict>,
    at: &str,
    key: &str,
) -> PyResult<Bound<'py, PyAny>> {
    d.get_item(key)?
        .ok_or_else(|| input_err(py, format!("`{at}[\"{key}\"]` is missing")))
}

/// `N` numbers (any sequence or array of shape `(N,)`), or an `InputError` naming `name`.
fn floats<const N: usize>(py: Python<'_>, v: &Bound<'_, PyAny>, name: &str) -> PyResult<[f64; N]> {
    let (data, shape) = f64_array(py, v, name)?;
    if shape != [N] {
        return Err(input_err(
            py,
            format!(
                "`{name}`: expected {N} numbers, got shape {}",
                shape_str(&shape)
            ),
        ));
    }
    let mut out = [0.0; N];
    out.copy_from_slice(&data);
    Ok(out)
}

fn params_of(py: Python<'_>, v: &Bound<'_, PyAny>, name: &str) -> PyResult<crane_model::Params> {
    if let Ok(p) = v.cast::<PyParams>() {
        return Ok(p.get().inner);
    }
    let d = v.cast::<PyDict>().map_err(|_| {
        input_err(
            py,
            format!("`{name}`: expected the dict of Params.to_dict() or a Params"),
        )
    })?;
    let p = params_from_dict_unchecked(py, d).map_err(|e| {
        if e.value(py)
            .get_type()
            .name()
            .is_ok_and(|n| n == "InputError")
        {
            input_err(py, format!("`{name}`: {}", e.value(py)))
        } else {
            e
        }
    })?;
    py_result(
        py,
        p.validate()
            .map_err(|e| Failure::ParamAt(name.to_string(), e)),
    )?;
    Ok(p)
}

fn law_of(py: Python<'_>, d: &Bound<'_, PyDict>, at: &str) -> PyResult<FrictionLaw> {
    let law: String = get(py, d, at, "law")?.extract().map_err(|_| {
        input_err(
            py,
            format!("`{at}[\"law\"]` must be \"hybrid\" or \"tanh\""),
        )
    })?;
    let gamma = get(py, d, at, "gamma")?;
    let gamma = match (law.as_str(), gamma.is_none()) {
        ("tanh", true) => {
            return Err(input_err(
                py,
                format!("`{at}[\"gamma\"]`: the tanh law needs its slope [s/m] (got None)"),
            ))
        }
        (_, true) => 0.0,
        _ => gamma
            .extract::<f64>()
            .map_err(|_| input_err(py, format!("`{at}[\"gamma\"]` must be a number or None")))?,
    };
    py_result(py, law_arg(&law, gamma))
}

fn stiction_of(py: Python<'_>, v: &Bound<'_, PyAny>, name: &str) -> PyResult<Extensions> {
    let bad = || {
        input_err(
            py,
            format!("`{name}`: expected 3 entries (X, Y, rope), each None or [ratio, velocity]"),
        )
    };
    if v.is_instance_of::<PyString>() {
        return Err(bad());
    }
    let items: Vec<Bound<'_, PyAny>> = v.extract().map_err(|_| bad())?;
    if items.len() != 3 {
        return Err(bad());
    }
    let mut ext = Extensions::default();
    for (i, (slot, item)) in ext.stiction.iter_mut().zip(&items).enumerate() {
        if !item.is_none() {
            let [ratio, velocity] = floats::<2>(py, item, &format!("{name}[{i}]"))?;
            *slot = Some(Stiction { ratio, velocity });
        }
    }
    Ok(ext)
}

fn modes_of(py: Python<'_>, v: &Bound<'_, PyAny>, name: &str) -> PyResult<[i8; 3]> {
    let bad = || input_err(py, format!("`{name}`: expected 3 ints, each -1, 0 or 1"));
    if v.is_instance_of::<PyString>() {
        return Err(bad());
    }
    let m: Vec<i64> = v.extract().map_err(|_| bad())?;
    let mut out = [0i8; 3];
    if m.len() != 3 {
        return Err(bad());
    }
    for (o, x) in out.iter_mut().zip(m) {
        *o = match x {
            -1 => -1,
            0 => 0,
            1 => 1,
            _ => return Err(bad()),
        };
    }
    Ok(out)
}

/// One simulator and its setup from a `Crane` snapshot; `at` names it in messages.
pub fn crane_from_dict(py: Python<'_>, obj: &Bound<'_, PyAny>, at: &str) -> PyResult<(Sim, Setup)> {
    let d = checked_dict(py, obj, at, CRANE_FORMAT, &CRANE_KEYS)?;
    let key = |k: &str| format!("{at}[\"{k}\"]");
    let params = params_of(py, &get(py, &d, at, "params")?, &key("params"))?;
    let h: f64 = get(py, &d, at, "h")?
        .extract()
        .map_err(|_| input_err(py, format!("`{}` must be a number [s]", key("h"))))?;
    let law = law_of(py, &d, at)?;
    let ext = stiction_of(py, &get(py, &d, at, "stiction")?, &key("stiction"))?;
    let flat = |k: &str| -> PyResult<State> {
        let v = floats::<10>(py, &get(py, &d, at, k)?, &key(k))?;
        py_result(py, state_from_flat(&v, &[10], &key(k)))
    };
    let (init, state) = (flat("init")?, flat("state")?);
    let modes = modes_of(py, &get(py, &d, at, "modes")?, &key("modes"))?;
    let steps: u64 = get(py, &d, at, "steps")?
        .extract()
        .map_err(|_| input_err(py, format!("`{}` must be an int >= 0", key("steps"))))?;
    let u_last = floats::<3>(py, &get(py, &d, at, "u_last")?, &key("u_last"))?;
    let setup = Setup {
        params,
        config: Config { h, law },
        ext,
        init,
    };
    let sim = py_result(py, Sim::restore(&setup, state, steps, u_last, at))?;
    let got = sim.crane().state();
    let same =
        |a: &[f64; 5], b: &[f64; 5]| a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits());
    if !(same(&got.q, &state.q) && same(&got.qd, &state.qd)) {
        return Err(input_err(
            py,
            format!(
                "`{}` moves an axis into the limit it sits at, which no accepted step leaves (the model would stop it)",
                key("state")
            ),
        ));
    }
    let derived = sim.modes().map(mode_code);
    if derived != modes {
        return Err(input_err(
            py,
            format!(
                "`{}` is {modes:?} but the velocities of `{}` give {derived:?} (after an accepted step the modes follow from the velocities)",
                key("modes"),
                key("state")
            ),
        ));
    }
    Ok((sim, setup))
}

/// Every simulator and setup of a `CraneBatch` snapshot; `at` names it in messages.
pub fn batch_from_dict(
    py: Python<'_>,
    obj: &Bound<'_, PyAny>,
    at: &str,
) -> PyResult<(Vec<Sim>, Vec<Setup>)> {
    let d = checked_dict(py, obj, at, BATCH_FORMAT, &BATCH_KEYS)?;
    let sims = get(py, &d, at, "sims")?;
    let bad = || {
        input_err(
            py,
            format!("`{at}[\"sims\"]`: expected a list of Crane snapshots"),
        )
    };
    if sims.is_instance_of::<PyString>() {
        return Err(bad());
    }
    let items: Vec<Bound<'_, PyAny>> = sims.extract().map_err(|_| bad())?;
    let mut out = (
        Vec::with_capacity(items.len()),
        Vec::with_capacity(items.len()),
    );
    for (i, item) in items.iter().enumerate() {
        let (sim, setup) = crane_from_dict(py, item, &format!("{at}[\"sims\"][{i}]"))?;
        out.0.push(sim);
        out.1.push(setup);
    }
    Ok(out)
}

//! Named access to the fields of [`Params`]: the dotted names the model's errors use
//! (`"payload_mass"`, `"x.viscous_pos"`, `"rope.dry_pos"`), for reading, writing and the
//! nested-dict form. The fields, their names and order are the model's table
//! ([`crane_model::params::PARAM_FIELDS`]); what is Python's own is that a polynomial is one
//! value of [`DRY_COEFFICIENTS`] numbers and an axis a nested dict.

use crane_model::params::{param_entries, ParamField, DRY_COEFFICIENTS, PARAM_FIELDS};
use crane_model::{Axis, Params};

/// Whether `key` names an axis table (`"x"`, `"y"`, `"rope"`).
pub fn is_axis(key: &str) -> bool {
    Axis::ALL.iter().any(|a| a.name() == key)
}

/// The fields as Python sees them, in file order: every table entry, a polynomial once (at
/// its coefficient `c0`).
pub fn fields() -> impl Iterator<Item = &'static ParamField> {
    PARAM_FIELDS
        .iter()
        .filter(|f| f.coefficient.unwrap_or(0) == 0)
}

/// A field's value: one number [SI unit of the field] or a friction polynomial [N, N/m, ...].
pub enum Value {
    /// A scalar.
    Scalar(f64),
    /// Coefficients c0..c4 of a dry-friction polynomial.
    Poly([f64; DRY_COEFFICIENTS]),
}

/// What a field holds.
pub enum Shape {
    /// One number.
    Scalar,
    /// A dry-friction polynomial of [`DRY_COEFFICIENTS`] numbers.
    Poly,
}

/// The shape of the field named `name` (dotted: `"x.gain"`), `None` if there is none.
pub fn shape(name: &str) -> Option<Shape> {
    let f = param_entries(name).next()?;
    Some(match f.coefficient {
        None => Shape::Scalar,
        Some(_) => Shape::Poly,
    })
}

/// The value of the field named `name`, or `None` if there is none.
pub fn get(p: &Params, name: &str) -> Option<Value> {
    Some(match shape(name)? {
        Shape::Scalar => Value::Scalar(param_entries(name).next().map(|f| (f.get)(p))?),
        Shape::Poly => {
            let mut c = [0.0; DRY_COEFFICIENTS];
            for (c, f) in c.iter_mut().zip(param_entries(name)) {
                *c = (f.get)(p);
            }
            Value::Poly(c)
        }
    })
}

/// Sets the field named `name` (of the shape of `value`); nothing if there is none.
pub fn set(p: &mut Params, name: &str, value: Value) {
    match value {
        Value::Scalar(x) => {
            for f in param_entries(name) {
                *(f.get_mut)(p) = x;
            }
        }
        Value::Poly(c) => {
            for (x, f) in c.into_iter().zip(param_entries(name)) {
                *(f.get_mut)(p) = x;
            }
        }
    }
}

/// Every dotted field name, in file order.
pub fn names() -> Vec<String> {
    fields().map(|f| f.path.to_string()).collect()
}

//! Named access to the fields of [`Params`]: the dotted names the model's errors use
//! (`"payload_mass"`, `"x.viscous_pos"`, `"rope.dry_pos"`), one table for reading, writing
//! and the nested-dict form.

use crane_model::{AxisParams, Params};

/// Scalar fields at the top level, in file order.
pub const TOP: [&str; 4] = ["payload_mass", "trolley_mass", "rail_mass", "gravity"];
/// Scalar fields after the axes.
pub const SWING: [&str; 2] = ["damping_alpha", "damping_beta"];
/// Axis tables.
pub const AXES: [&str; 3] = ["x", "y", "rope"];
/// Fields of an axis table (`dry_pos`, `dry_neg` are 5 coefficients c0..c4).
pub const AXIS_FIELDS: [&str; 8] = [
    "inertia",
    "gain",
    "viscous_pos",
    "viscous_neg",
    "dry_pos",
    "dry_neg",
    "min",
    "max",
];

/// A field's storage: one number [SI unit of the field] or a friction polynomial [N].
pub enum Slot<'a> {
    /// A scalar.
    Scalar(&'a mut f64),
    /// Coefficients c0..c4 of a dry-friction polynomial.
    Poly(&'a mut [f64; 5]),
}

fn axis_slot<'a>(a: &'a mut AxisParams, field: &str) -> Option<Slot<'a>> {
    Some(match field {
        "inertia" => Slot::Scalar(&mut a.inertia),
        "gain" => Slot::Scalar(&mut a.gain),
        "viscous_pos" => Slot::Scalar(&mut a.viscous_pos),
        "viscous_neg" => Slot::Scalar(&mut a.viscous_neg),
        "dry_pos" => Slot::Poly(&mut a.dry_pos),
        "dry_neg" => Slot::Poly(&mut a.dry_neg),
        "min" => Slot::Scalar(&mut a.min),
        "max" => Slot::Scalar(&mut a.max),
        _ => return None,
    })
}

/// The storage of the field named `name` (dotted: `"x.gain"`), or `None` if there is none.
pub fn slot<'a>(p: &'a mut Params, name: &str) -> Option<Slot<'a>> {
    if let Some((axis, field)) = name.split_once('.') {
        let a = match axis {
            "x" => &mut p.x,
            "y" => &mut p.y,
            "rope" => &mut p.rope,
            _ => return None,
        };
        return axis_slot(a, field);
    }
    Some(Slot::Scalar(match name {
        "payload_mass" => &mut p.payload_mass,
        "trolley_mass" => &mut p.trolley_mass,
        "rail_mass" => &mut p.rail_mass,
        "gravity" => &mut p.gravity,
        "damping_alpha" => &mut p.damping_alpha,
        "damping_beta" => &mut p.damping_beta,
        _ => return None,
    }))
}

/// Every dotted field name, in file order.
pub fn names() -> Vec<String> {
    let mut v: Vec<String> = TOP.iter().map(|s| s.to_string()).collect();
    for a in AXES {
        v.extend(AXIS_FIELDS.iter().map(|f| format!("{a}.{f}")));
    }
    v.extend(SWING.iter().map(|s| s.to_string()));
    v
}

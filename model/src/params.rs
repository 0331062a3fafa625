//! Physical parameters of the crane, their defaults and their validation.
//!
//! All values are SI. Forces and friction of the drive axes are *effective* (reflected to the
//! load side, motor friction included, as in the paper's `fbar`): newtons for X, Y and the
//! rope. Validation happens once, in [`Params::validate`] (called by
//! [`Crane::new`](crate::Crane::new)); the step path never checks parameters again.
//!
//! [`PARAM_FIELDS`] is the one table of the parameters: every number of [`Params`] with its
//! dotted name, unit, description, rule and place. `validate` checks by it; the parameter
//! files of `crane-ident`, the Python package and the FMU read their names from it.

use crate::extensions::Axis;
use core::fmt;

/// Parameters of one drive axis (X rail, Y trolley, or rope).
///
/// Sign convention: positive velocity is increasing coordinate (for the rope: lowering the
/// payload). Friction magnitudes are non-negative; the model applies the sign.
///
/// With the `serde` feature: (de)serializable with these field names, unknown fields
/// refused (the TOML parameter files of `crane-ident`).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
pub struct AxisParams {
    /// Reflected motor inertia `Jbar` [kg] (>= 0).
    pub inertia: f64,
    /// Motor gain `K` [N/V] (> 0): drive force is `K u`.
    pub gain: f64,
    /// Viscous coefficient `Dbar+` for positive velocity [N s/m] (>= 0).
    pub viscous_pos: f64,
    /// Viscous coefficient `Dbar-` for negative velocity [N s/m] (>= 0).
    pub viscous_neg: f64,
    /// Dry friction magnitude `Cbar+(p) = c0 + c1 p + ... + c4 p^4` [N], p in m, for positive
    /// velocity. Evaluated by Horner and clamped at 0.
    pub dry_pos: [f64; DRY_COEFFICIENTS],
    /// Dry friction magnitude `Cbar-(p)` [N] for negative velocity (same form as `dry_pos`).
    pub dry_neg: [f64; DRY_COEFFICIENTS],
    /// Lower position limit [m].
    pub min: f64,
    /// Upper position limit [m] (> `min`).
    pub max: f64,
}

/// All parameters of the crane model.
///
/// With the `serde` feature: (de)serializable with these field names, unknown fields
/// refused (the TOML parameter files of `crane-ident`).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(deny_unknown_fields))]
pub struct Params {
    /// Payload mass `m_p` [kg] (> 0).
    pub payload_mass: f64,
    /// Trolley mass `m_t` [kg] (> 0); it moves along Y and, with the rail, along X.
    pub trolley_mass: f64,
    /// Rail mass `m_r` [kg] (>= 0); it moves along X only.
    pub rail_mass: f64,
    /// Gravity `g` [m/s^2] (>= 0).
    pub gravity: f64,
    /// X axis (rail along the bridge beams).
    pub x: AxisParams,
    /// Y axis (trolley along the rail).
    pub y: AxisParams,
    /// Rope axis (length `L`; positive velocity lowers the payload). Its dry friction is the
    /// constant `Cbar_l`: only `c0` is nonzero in the defaults.
    pub rope: AxisParams,
    /// Swing damping `D_alpha` [kg m^2/s] (>= 0).
    pub damping_alpha: f64,
    /// Swing damping `D_beta` [kg m^2/s] (>= 0).
    pub damping_beta: f64,
}

impl Default for Params {
    /// The INTECO 3D-Crane parameters of `docs/MODEL.md` (paper's Table "Estimated System
    /// Parameters"), payload 0.457 kg.
    fn default() -> Self {
        Params {
            payload_mass: 0.457,
            trolley_mass: 1.155,
            rail_mass: 2.20,
            gravity: 9.81,
            x: AxisParams {
                inertia: 2.56,
                gain: 3.20,
                viscous_pos: 105.87,
                viscous_neg: 101.44,
                dry_pos: [1.23, 0.29, -1.95, 3.98, 5.02],
                dry_neg: [1.29, -0.089, -4.24, 17.82, -13.75],
                min: 0.0,
                max: 0.505,
            },
            y: AxisParams {
                inertia: 2.56,
                gain: 3.20,
                viscous_pos: 98.50,
                viscous_neg: 97.13,
                dry_pos: [1.08, -0.95, 6.08, -12.41, 8.56],
                dry_neg: [1.06, -0.09, 0.29, 0.79, -1.74],
                min: 0.0,
                max: 0.625,
            },
            rope: AxisParams {
                inertia: 18.19,
                gain: 8.53,
                viscous_pos: 701.81,
                viscous_neg: 701.81,
                dry_pos: [8.583, 0.0, 0.0, 0.0, 0.0],
                dry_neg: [8.583, 0.0, 0.0, 0.0, 0.0],
                min: 0.13,
                max: 0.57,
            },
            damping_alpha: 2.573e-4,
            damping_beta: 0.0059,
        }
    }
}

/// What is wrong with a field.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Problem {
    /// NaN or infinite.
    NotFinite,
    /// Must be strictly positive.
    NotPositive,
    /// Must be zero or positive.
    Negative,
    /// A range whose lower end is not below its upper end.
    EmptyRange,
    /// A position outside its axis limits.
    OutOfLimits,
    /// Swing angles outside the model's domain: beyond the swing stops
    /// (`alpha` within `pi/2 +- SWING_STOP`, `beta` within `+-SWING_STOP`).
    AngleOutOfRange,
    /// Must be >= 1.
    BelowOne,
    /// Above the fixed capacity (e.g. a delay longer than the delay line).
    TooLarge,
    /// A breakaway (static friction) level below the kinetic friction of its direction.
    BelowKinetic,
    /// NaN where an infinite value is allowed (e.g. an absent end stop).
    NotANumber,
    /// Must be < 1 (e.g. a load-dependent friction coefficient).
    NotBelowOne,
    /// Would make a friction level negative somewhere (e.g. a localised dip deeper than a
    /// dry level).
    LevelBelowZero,
}

/// A rejected parameter, configuration or initial-state field.
///
/// `field` is the dotted path of the field, e.g. `"x.viscous_pos"`, `"rope.dry_neg[0]"`,
/// `"config.h"`, `"state.q[2]"`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Error {
    /// Dotted path of the offending field.
    pub field: &'static str,
    /// What is wrong with it.
    pub problem: Problem,
    /// The offending value.
    pub value: f64,
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.problem == Problem::EmptyRange {
            // (the pair is wrong, not one of them: whichever the user just set is named)
            let axis = self.field.strip_suffix(".min").unwrap_or(self.field);
            return write!(
                f,
                "`{axis}.min` must be below `{axis}.max`: the travel [min, max] is empty (min = {})",
                self.value
            );
        }
        let what = match self.problem {
            Problem::NotFinite => "must be finite",
            Problem::NotPositive => "must be > 0",
            Problem::Negative => "must be >= 0",
            Problem::EmptyRange => "must be below the upper limit",
            Problem::OutOfLimits => "is outside the axis limits",
            Problem::AngleOutOfRange => {
                "is outside the swing stops (alpha within pi/2 +- 1.4, beta within +-1.4 rad)"
            }
            Problem::BelowOne => "must be >= 1",
            Problem::TooLarge => "exceeds the fixed capacity",
            Problem::BelowKinetic => "must be >= the kinetic friction of its direction",
            Problem::NotANumber => "must not be NaN",
            Problem::NotBelowOne => "must be < 1",
            Problem::LevelBelowZero => {
                "makes a friction level negative (every dry level plus it must be >= 0)"
            }
        };
        write!(f, "`{}` {} (got {})", self.field, what, self.value)
    }
}

pub(crate) fn check(field: &'static str, value: f64, problem: Problem) -> Result<(), Error> {
    let ok = match problem {
        Problem::NotFinite => value.is_finite(),
        Problem::NotPositive => value.is_finite() && value > 0.0,
        Problem::Negative => value.is_finite() && value >= 0.0,
        _ => true,
    };
    if ok {
        Ok(())
    } else if !value.is_finite() {
        Err(Error {
            field,
            problem: Problem::NotFinite,
            value,
        })
    } else {
        Err(Error {
            field,
            problem,
            value,
        })
    }
}

/// Coefficients `c0 .. c4` of a dry-friction polynomial `Cbar(p) = c0 + c1 p + ... + c4 p^4`
/// (dimensionless count).
pub const DRY_COEFFICIENTS: usize = 5;

/// Number of scalar parameters: the `f64` fields of [`Params`], a dry-friction polynomial
/// counted once per coefficient (dimensionless count); the length of [`PARAM_FIELDS`].
pub const N_PARAMS: usize = 6 + 3 * 16;

// `Params` is nothing but its `N_PARAMS` numbers: a field added to it (or to `AxisParams`)
// without a table entry stops the build here; raising `N_PARAMS` then stops it at the table's
// length until the entry is written.
const _: () = assert!(core::mem::size_of::<Params>() == N_PARAMS * core::mem::size_of::<f64>());

/// The rule [`Params::validate`] checks a parameter against, taken alone (every value must
/// also be finite). Conditions on a pair (`min < max` of an axis) are not rules of one field.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Rule {
    /// Any finite value (in the field's unit).
    Finite,
    /// `>= 0` (in the field's unit).
    NonNegative,
    /// `> 0` (in the field's unit).
    Positive,
}

impl Rule {
    /// The [`Problem`] a value breaking the rule is reported with.
    pub const fn problem(self) -> Problem {
        match self {
            Rule::Finite => Problem::NotFinite,
            Rule::NonNegative => Problem::Negative,
            Rule::Positive => Problem::NotPositive,
        }
    }
}

/// Which end of a drive axis' travel a parameter is (`x.min`, `rope.max`...).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LimitEnd {
    /// The lower position limit `min` [m].
    Min,
    /// The upper position limit `max` [m].
    Max,
}

impl Axis {
    /// The three drive axes in model order (X, Y, rope), as [`Params::axes`].
    pub const ALL: [Axis; 3] = [Axis::X, Axis::Y, Axis::Rope];

    /// The axis' key among the parameters (`"x"`, `"y"`, `"rope"`): the [`Params`] field, the
    /// table of the parameter file, the first part of its fields' dotted names.
    pub const fn name(self) -> &'static str {
        match self {
            Axis::X => "x",
            Axis::Y => "y",
            Axis::Rope => "rope",
        }
    }
}

/// One scalar parameter of [`Params`]: an entry of [`PARAM_FIELDS`], the one table of the
/// parameters' names, units, descriptions and rules that the parameter files, the Python
/// package and the FMU read.
#[derive(Clone, Copy, Debug)]
pub struct ParamField {
    /// Dotted path of the number, as [`Error::field`] names it: `"payload_mass"`, `"x.gain"`,
    /// `"rope.dry_neg[0]"`.
    pub name: &'static str,
    /// Dotted path of the [`Params`] field it is (part of), without a coefficient index:
    /// `"payload_mass"`, `"x.gain"`, `"rope.dry_neg"`; the key path of the parameter file.
    pub path: &'static str,
    /// The drive axis whose [`AxisParams`] holds it; `None` for a field of [`Params`] itself.
    pub axis: Option<Axis>,
    /// The Rust (and file) field name inside its struct: `"payload_mass"`, `"gain"`,
    /// `"dry_neg"`.
    pub key: &'static str,
    /// For a dry-friction polynomial: the index `k` of its coefficient `ck` (`0 ..`
    /// [`DRY_COEFFICIENTS`]); `None` for a scalar field.
    pub coefficient: Option<usize>,
    /// SI unit of the value, written as FMI and Modelica write units (`.` multiplies, a
    /// power follows its base): `"kg"`, `"N.s/m"`, `"kg.m2/s"`, `"m/s2"`, `"N/m3"`.
    pub unit: &'static str,
    /// One line for humans: the symbol of `docs/MODEL.md`, the axis, the rule (no unit).
    pub description: &'static str,
    /// The rule [`Params::validate`] checks the value against, taken alone.
    pub rule: Rule,
    /// For a position limit [m]: which end of its axis' travel it is.
    pub limit: Option<LimitEnd>,
    /// Reads the value from parameters (in [`ParamField::unit`]).
    pub get: fn(&Params) -> f64,
    /// The value's place in parameters (in [`ParamField::unit`]), to write it.
    pub get_mut: fn(&mut Params) -> &mut f64,
}

/// A table entry for a field of [`Params`] itself.
macro_rules! scalar {
    ($key:ident, $unit:literal, $rule:ident, $desc:literal) => {
        ParamField {
            name: stringify!($key),
            path: stringify!($key),
            axis: None,
            key: stringify!($key),
            coefficient: None,
            unit: $unit,
            description: $desc,
            rule: Rule::$rule,
            limit: None,
            get: {
                fn get(p: &Params) -> f64 {
                    p.$key
                }
                get
            },
            get_mut: {
                fn get_mut(p: &mut Params) -> &mut f64 {
                    &mut p.$key
                }
                get_mut
            },
        }
    };
}

/// A table entry for a scalar field of an axis.
macro_rules! axis_scalar {
    ($a:ident, $axis:ident, $key:ident, $unit:literal, $rule:expr, $limit:expr, $desc:expr) => {
        ParamField {
            name: concat!(stringify!($a), ".", stringify!($key)),
            path: concat!(stringify!($a), ".", stringify!($key)),
            axis: Some(Axis::$axis),
            key: stringify!($key),
            coefficient: None,
            unit: $unit,
            description: $desc,
            rule: $rule,
            limit: $limit,
            get: {
                fn get(p: &Params) -> f64 {
                    p.$a.$key
                }
                get
            },
            get_mut: {
                fn get_mut(p: &mut Params) -> &mut f64 {
                    &mut p.$a.$key
                }
                get_mut
            },
        }
    };
}

/// A table entry for coefficient `$k` of a dry-friction polynomial of an axis.
macro_rules! coefficient {
    ($a:ident, $axis:ident, $key:ident, $k:literal, $unit:literal, $desc:expr) => {
        ParamField {
            name: concat!(
                stringify!($a),
                ".",
                stringify!($key),
                "[",
                stringify!($k),
                "]"
            ),
            path: concat!(stringify!($a), ".", stringify!($key)),
            axis: Some(Axis::$axis),
            key: stringify!($key),
            coefficient: Some($k),
            unit: $unit,
            description: $desc,
            rule: Rule::Finite,
            limit: None,
            get: {
                fn get(p: &Params) -> f64 {
                    p.$a.$key[$k]
                }
                get
            },
            get_mut: {
                fn get_mut(p: &mut Params) -> &mut f64 {
                    &mut p.$a.$key[$k]
                }
                get_mut
            },
        }
    };
}

/// The whole table: the scalars of [`Params`] before the axes, every axis' 16 numbers, the
/// scalars after the axes (the struct's declaration order).
macro_rules! param_table {
    (
        before: [$(($s:ident, $su:literal, $sr:ident, $sd:literal)),* $(,)?],
        axes: [$(($a:ident, $axis:ident, $what:literal, $min_rule:ident)),* $(,)?],
        after: [$(($t:ident, $tu:literal, $tr:ident, $td:literal)),* $(,)?] $(,)?
    ) => {
        [
            $(scalar!($s, $su, $sr, $sd),)*
            $(
                axis_scalar!($a, $axis, inertia, "kg", Rule::NonNegative, None,
                    concat!("reflected motor inertia Jbar of ", $what, " (>= 0)")),
                axis_scalar!($a, $axis, gain, "N/V", Rule::Positive, None,
                    concat!("motor gain K of ", $what, ": drive force K u (> 0)")),
                axis_scalar!($a, $axis, viscous_pos, "N.s/m", Rule::NonNegative, None,
                    concat!("viscous coefficient Dbar+ of ", $what, " (>= 0)")),
                axis_scalar!($a, $axis, viscous_neg, "N.s/m", Rule::NonNegative, None,
                    concat!("viscous coefficient Dbar- of ", $what, " (>= 0)")),
                coefficient!($a, $axis, dry_pos, 0, "N",
                    concat!("dry friction Cbar+(p) of ", $what, ", coefficient c0")),
                coefficient!($a, $axis, dry_pos, 1, "N/m",
                    concat!("dry friction Cbar+(p) of ", $what, ", coefficient c1 (of p)")),
                coefficient!($a, $axis, dry_pos, 2, "N/m2",
                    concat!("dry friction Cbar+(p) of ", $what, ", coefficient c2 (of p^2)")),
                coefficient!($a, $axis, dry_pos, 3, "N/m3",
                    concat!("dry friction Cbar+(p) of ", $what, ", coefficient c3 (of p^3)")),
                coefficient!($a, $axis, dry_pos, 4, "N/m4",
                    concat!("dry friction Cbar+(p) of ", $what, ", coefficient c4 (of p^4)")),
                coefficient!($a, $axis, dry_neg, 0, "N",
                    concat!("dry friction Cbar-(p) of ", $what, ", coefficient c0")),
                coefficient!($a, $axis, dry_neg, 1, "N/m",
                    concat!("dry friction Cbar-(p) of ", $what, ", coefficient c1 (of p)")),
                coefficient!($a, $axis, dry_neg, 2, "N/m2",
                    concat!("dry friction Cbar-(p) of ", $what, ", coefficient c2 (of p^2)")),
                coefficient!($a, $axis, dry_neg, 3, "N/m3",
                    concat!("dry friction Cbar-(p) of ", $what, ", coefficient c3 (of p^3)")),
                coefficient!($a, $axis, dry_neg, 4, "N/m4",
                    concat!("dry friction Cbar-(p) of ", $what, ", coefficient c4 (of p^4)")),
                axis_scalar!($a, $axis, min, "m", Rule::$min_rule, Some(LimitEnd::Min),
                    concat!("lower position limit of ", $what)),
                axis_scalar!($a, $axis, max, "m", Rule::Finite, Some(LimitEnd::Max),
                    concat!("upper position limit of ", $what, " (> min)")),
            )*
            $(scalar!($t, $tu, $tr, $td),)*
        ]
    };
}

/// Every scalar parameter of [`Params`], in the struct's declaration order (a polynomial's
/// coefficients `c0 .. c4` in turn): the one table of their names, units [SI, see
/// [`ParamField::unit`]], descriptions, rules and places. [`Params::validate`] checks by it;
/// `crane-ident`'s parameter files, the Python package and the FMU name and reach the
/// parameters through it.
pub static PARAM_FIELDS: [ParamField; N_PARAMS] = param_table! {
    before: [
        (payload_mass, "kg", Positive, "payload mass m_p (> 0)"),
        (trolley_mass, "kg", Positive, "trolley mass m_t (> 0)"),
        (rail_mass, "kg", NonNegative, "rail mass m_r (>= 0)"),
        (gravity, "m/s2", NonNegative, "gravity g (>= 0)"),
    ],
    axes: [
        (x, X, "the X axis (rail)", Finite),
        (y, Y, "the Y axis (trolley)", Finite),
        // the rope length divides: `rope.min > 0`
        (rope, Rope, "the rope axis (positive lowers the payload)", Positive),
    ],
    after: [
        (damping_alpha, "kg.m2/s", NonNegative, "swing damping D_alpha (>= 0)"),
        (damping_beta, "kg.m2/s", NonNegative, "swing damping D_beta (>= 0)"),
    ],
};

/// The entry of [`PARAM_FIELDS`] named `name` (`"x.gain"`, `"rope.dry_neg[0]"`) and its
/// index, if any.
pub fn param_field(name: &str) -> Option<(usize, &'static ParamField)> {
    PARAM_FIELDS
        .iter()
        .enumerate()
        .find(|(_, f)| f.name == name)
}

/// The entries of [`PARAM_FIELDS`] that make up the [`Params`] field at dotted `path`: one
/// for a scalar (`"x.gain"`), the coefficients `c0 .. c4` in order for a polynomial
/// (`"x.dry_pos"`), none for an unknown path.
pub fn param_entries(path: &str) -> impl Iterator<Item = &'static ParamField> + '_ {
    PARAM_FIELDS.iter().filter(move |f| f.path == path)
}

impl AxisParams {
    /// The entries of axis `axis` in [`PARAM_FIELDS`], in table order.
    fn entries(axis: Axis) -> impl Iterator<Item = &'static ParamField> {
        PARAM_FIELDS.iter().filter(move |f| f.axis == Some(axis))
    }
}

impl Params {
    /// Checks every field; the first bad one is returned as an [`Error`] naming it.
    ///
    /// Rules ([`ParamField::rule`] of [`PARAM_FIELDS`]): masses `payload_mass`,
    /// `trolley_mass` > 0; `rail_mass`, `gravity`, inertias, viscous and swing damping
    /// coefficients >= 0; gains > 0; polynomial coefficients finite; limits finite with
    /// `min < max`; rope `min` > 0 (the rope length divides).
    ///
    /// Order: the scalars of `Params` itself; then per axis (X, Y, rope) its numbers, the
    /// limits for finiteness only, and its travel `min < max`; last the limits' own rules.
    pub fn validate(&self) -> Result<(), Error> {
        for f in PARAM_FIELDS.iter().filter(|f| f.axis.is_none()) {
            check(f.name, (f.get)(self), f.rule.problem())?;
        }
        for axis in Axis::ALL {
            let mut min_name = None;
            for f in AxisParams::entries(axis) {
                let problem = match f.limit {
                    Some(_) => Problem::NotFinite,
                    None => f.rule.problem(),
                };
                check(f.name, (f.get)(self), problem)?;
                if f.limit == Some(LimitEnd::Min) {
                    min_name = Some(f.name);
                }
            }
            let a = self.axis(axis);
            if let Some(field) = min_name {
                if a.min >= a.max {
                    return Err(Error {
                        field,
                        problem: Problem::EmptyRange,
                        value: a.min,
                    });
                }
            }
        }
        for f in PARAM_FIELDS.iter().filter(|f| f.limit.is_some()) {
            check(f.name, (f.get)(self), f.rule.problem())?;
        }
        Ok(())
    }

    /// The three drive axes in model order (X, Y, rope).
    pub fn axes(&self) -> [&AxisParams; 3] {
        [&self.x, &self.y, &self.rope]
    }

    /// The parameters of drive axis `axis`.
    pub fn axis(&self, axis: Axis) -> &AxisParams {
        match axis {
            Axis::X => &self.x,
            Axis::Y => &self.y,
            Axis::Rope => &self.rope,
        }
    }

    /// Scalar parameter `i` of [`PARAM_FIELDS`] (in its [`ParamField::unit`]), `None` past
    /// the end.
    pub fn scalar(&self, i: usize) -> Option<f64> {
        PARAM_FIELDS.get(i).map(|f| (f.get)(self))
    }

    /// The place of scalar parameter `i` of [`PARAM_FIELDS`] (in its [`ParamField::unit`]),
    /// `None` past the end.
    pub fn scalar_mut(&mut self, i: usize) -> Option<&mut f64> {
        PARAM_FIELDS.get(i).map(|f| (f.get_mut)(self))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every number of `p` in declaration order, field by field, and how many there are. The
    /// destructuring is exhaustive: a field added to `Params` or `AxisParams` does not compile
    /// here until it is listed, and then fails the test below until the table has it.
    fn numbers(p: &Params) -> ([f64; N_PARAMS], usize) {
        let Params {
            payload_mass,
            trolley_mass,
            rail_mass,
            gravity,
            x,
            y,
            rope,
            damping_alpha,
            damping_beta,
        } = *p;
        let mut all = List {
            out: [0.0; N_PARAMS],
            n: 0,
        };
        all.extend([payload_mass, trolley_mass, rail_mass, gravity]);
        for a in [x, y, rope] {
            let AxisParams {
                inertia,
                gain,
                viscous_pos,
                viscous_neg,
                dry_pos,
                dry_neg,
                min,
                max,
            } = a;
            all.extend([inertia, gain, viscous_pos, viscous_neg]);
            all.extend(dry_pos);
            all.extend(dry_neg);
            all.extend([min, max]);
        }
        all.extend([damping_alpha, damping_beta]);
        (all.out, all.n)
    }

    /// A fixed-size list (the crate has no heap): what does not fit is counted, not stored.
    struct List {
        out: [f64; N_PARAMS],
        n: usize,
    }

    impl List {
        fn extend(&mut self, values: impl IntoIterator<Item = f64>) {
            for v in values {
                if let Some(o) = self.out.get_mut(self.n) {
                    *o = v;
                }
                self.n += 1;
            }
        }
    }

    #[test]
    fn the_table_reaches_every_field_once_in_declaration_order() {
        let mut p = Params::default();
        for i in 0..N_PARAMS {
            if let Some(v) = p.scalar_mut(i) {
                *v = 1000.0 + i as f64;
            }
        }
        let expected: [f64; N_PARAMS] = core::array::from_fn(|i| 1000.0 + i as f64);
        assert_eq!(numbers(&p), (expected, N_PARAMS));
        for (i, f) in PARAM_FIELDS.iter().enumerate() {
            assert_eq!((f.get)(&p), expected[i], "{}", f.name);
            assert_eq!(p.scalar(i), Some(expected[i]), "{}", f.name);
            assert_eq!(param_field(f.name).map(|(j, _)| j), Some(i), "{}", f.name);
        }
        assert_eq!(p.scalar(N_PARAMS), None);
        assert!(p.scalar_mut(N_PARAMS).is_none());
        assert!(param_field("x.dry_pos").is_none());
    }

    #[test]
    fn names_paths_and_keys_agree() {
        const INDEX: [&str; DRY_COEFFICIENTS] = ["[0]", "[1]", "[2]", "[3]", "[4]"];
        for f in &PARAM_FIELDS {
            let key = match f.axis {
                None => Some(f.path),
                Some(a) => f
                    .path
                    .strip_prefix(a.name())
                    .and_then(|k| k.strip_prefix('.')),
            };
            assert_eq!(key, Some(f.key), "{}", f.name);
            let suffix = f.name.strip_prefix(f.path);
            match f.coefficient {
                None => assert_eq!(suffix, Some(""), "{}", f.name),
                Some(k) => assert_eq!(suffix, INDEX.get(k).copied(), "{}", f.name),
            }
            assert_eq!(f.limit.is_some(), f.key == "min" || f.key == "max");
            assert_eq!(
                param_entries(f.path).count(),
                f.coefficient.map_or(1, |_| DRY_COEFFICIENTS),
                "{}",
                f.name
            );
        }
        assert_eq!(param_entries("x").count(), 0);
    }

    #[test]
    fn validation_names_the_first_bad_field_scalars_then_axes_then_the_rope_length() {
        let field = |p: &Params| p.validate().err().map(|e| (e.field, e.problem));
        let base = Params::default();
        assert_eq!(field(&base), None);
        let mut p = base;
        p.x.gain = -1.0;
        p.damping_beta = -1.0;
        assert_eq!(field(&p), Some(("damping_beta", Problem::Negative)));
        let mut p = base;
        p.rope.min = -1.0;
        assert_eq!(field(&p), Some(("rope.min", Problem::NotPositive)));
        p.rope.max = -2.0;
        assert_eq!(field(&p), Some(("rope.min", Problem::EmptyRange)));
        p.rope.max = f64::NAN;
        assert_eq!(field(&p), Some(("rope.max", Problem::NotFinite)));
        let mut p = base;
        p.y.dry_neg[3] = f64::INFINITY;
        p.y.max = -1.0;
        assert_eq!(field(&p), Some(("y.dry_neg[3]", Problem::NotFinite)));
    }
}

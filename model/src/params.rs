//! Physical parameters of the crane, their defaults and their validation.
//!
//! All values are SI. Forces and friction of the drive axes are *effective* (reflected to the
//! load side, motor friction included, as in the paper's `fbar`): newtons for X, Y and the
//! rope. Validation happens once, in [`Params::validate`] (called by
//! [`Crane::new`](crate::Crane::new)); the step path never checks parameters again.

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
    pub dry_pos: [f64; 5],
    /// Dry friction magnitude `Cbar-(p)` [N] for negative velocity (same form as `dry_pos`).
    pub dry_neg: [f64; 5],
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

/// Field names of one axis, so errors can name them without allocation.
struct AxisNames {
    inertia: &'static str,
    gain: &'static str,
    viscous_pos: &'static str,
    viscous_neg: &'static str,
    dry_pos: [&'static str; 5],
    dry_neg: [&'static str; 5],
    min: &'static str,
    max: &'static str,
}

macro_rules! axis_names {
    ($a:literal) => {
        AxisNames {
            inertia: concat!($a, ".inertia"),
            gain: concat!($a, ".gain"),
            viscous_pos: concat!($a, ".viscous_pos"),
            viscous_neg: concat!($a, ".viscous_neg"),
            dry_pos: [
                concat!($a, ".dry_pos[0]"),
                concat!($a, ".dry_pos[1]"),
                concat!($a, ".dry_pos[2]"),
                concat!($a, ".dry_pos[3]"),
                concat!($a, ".dry_pos[4]"),
            ],
            dry_neg: [
                concat!($a, ".dry_neg[0]"),
                concat!($a, ".dry_neg[1]"),
                concat!($a, ".dry_neg[2]"),
                concat!($a, ".dry_neg[3]"),
                concat!($a, ".dry_neg[4]"),
            ],
            min: concat!($a, ".min"),
            max: concat!($a, ".max"),
        }
    };
}

impl AxisParams {
    fn validate(&self, n: &AxisNames) -> Result<(), Error> {
        check(n.inertia, self.inertia, Problem::Negative)?;
        check(n.gain, self.gain, Problem::NotPositive)?;
        check(n.viscous_pos, self.viscous_pos, Problem::Negative)?;
        check(n.viscous_neg, self.viscous_neg, Problem::Negative)?;
        for (name, c) in n.dry_pos.iter().zip(self.dry_pos.iter()) {
            check(name, *c, Problem::NotFinite)?;
        }
        for (name, c) in n.dry_neg.iter().zip(self.dry_neg.iter()) {
            check(name, *c, Problem::NotFinite)?;
        }
        check(n.min, self.min, Problem::NotFinite)?;
        check(n.max, self.max, Problem::NotFinite)?;
        if self.min >= self.max {
            return Err(Error {
                field: n.min,
                problem: Problem::EmptyRange,
                value: self.min,
            });
        }
        Ok(())
    }
}

impl Params {
    /// Checks every field; the first bad one is returned as an [`Error`] naming it.
    ///
    /// Rules: masses `payload_mass`, `trolley_mass` > 0; `rail_mass`, `gravity`, inertias,
    /// viscous and swing damping coefficients >= 0; gains > 0; polynomial coefficients
    /// finite; limits finite with `min < max`; rope `min` > 0 (the rope length divides).
    pub fn validate(&self) -> Result<(), Error> {
        check("payload_mass", self.payload_mass, Problem::NotPositive)?;
        check("trolley_mass", self.trolley_mass, Problem::NotPositive)?;
        check("rail_mass", self.rail_mass, Problem::Negative)?;
        check("gravity", self.gravity, Problem::Negative)?;
        check("damping_alpha", self.damping_alpha, Problem::Negative)?;
        check("damping_beta", self.damping_beta, Problem::Negative)?;
        self.x.validate(&axis_names!("x"))?;
        self.y.validate(&axis_names!("y"))?;
        self.rope.validate(&axis_names!("rope"))?;
        check("rope.min", self.rope.min, Problem::NotPositive)?;
        Ok(())
    }

    /// The three drive axes in model order (X, Y, rope).
    pub fn axes(&self) -> [&AxisParams; 3] {
        [&self.x, &self.y, &self.rope]
    }
}

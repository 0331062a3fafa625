//! Parameters of a single-axis drive and their validation.
//!
//! One equation for a linear axis (positions in m, forces in N, inertia in kg) and a rotary
//! one (rad, N m, kg m^2); [`Motion`] only names the units. "Force" below means N for a
//! linear axis and N m for a rotary one; "position" m or rad.
//!
//! Sign convention: positive velocity is increasing position; the applied force
//! `gain * u + offset` is positive along the axis; friction coefficients are magnitudes
//! (`>= 0`), the model applies the sign.

use crate::params::{check, Error, Problem};

/// Largest input delay of a drive, in steps (the delay line's fixed capacity).
pub const MAX_DRIVE_DELAY_STEPS: usize = 64;

/// Whether the axis translates or rotates. Only the units differ: the equations are the same.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Motion {
    /// A carriage: position [m], force [N], inertia [kg].
    Linear,
    /// A joint: position [rad], torque [N m], inertia [kg m^2].
    Rotary,
}

impl Motion {
    /// Unit of position: `"m"` or `"rad"`.
    pub fn position_unit(self) -> &'static str {
        match self {
            Motion::Linear => "m",
            Motion::Rotary => "rad",
        }
    }

    /// Unit of force: `"N"` or `"N m"`.
    pub fn force_unit(self) -> &'static str {
        match self {
            Motion::Linear => "N",
            Motion::Rotary => "N m",
        }
    }

    /// Unit of inertia: `"kg"` or `"kg m^2"`.
    pub fn inertia_unit(self) -> &'static str {
        match self {
            Motion::Linear => "kg",
            Motion::Rotary => "kg m^2",
        }
    }
}

/// A force that depends on position only, restoring towards `center` (subtracted from the
/// applied force in the equation of motion).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PositionForce {
    /// No position force.
    None,
    /// Linear spring: `stiffness * (x - center)`.
    Spring {
        /// Stiffness [N/m or N m/rad] (>= 0, finite).
        stiffness: f64,
        /// Rest position [m or rad] (finite).
        center: f64,
    },
    /// Pendulum (gravity on a joint, or a cam): `stiffness * sin(x - center)`; for a joint in
    /// a vertical plane `stiffness = m g l` and `center` the hanging angle.
    Pendulum {
        /// Stiffness at the centre [N/m or N m/rad] (>= 0, finite).
        stiffness: f64,
        /// Stable rest position [m or rad] (finite).
        center: f64,
    },
}

/// Dry friction that depends on position: a stretch of the axis where the dry friction is
/// higher (a tight spot of a screw, a dirty patch of a rail, a worn gear tooth) or lower.
/// Added to all four dry levels of [`DriveParams`] (kinetic and breakaway, both directions).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LocalFriction {
    /// No position-dependent friction: the dry levels are the same everywhere.
    None,
    /// A smooth bump (or, with a negative amplitude, a dip) of dry friction:
    /// `b(x) = amplitude * (1 - s^2)^2` for `|s| < 1`, `s = (x - center) / half_width`, and
    /// `0` outside (the kernel of the crane's localised friction, [`Bump`](crate::Bump), with
    /// the same operation order). `b` is continuous with a continuous slope, its peak is
    /// `amplitude` at `center`, its slope at most `1.54 |amplitude| / half_width`, and its
    /// integral over the axis `amplitude * half_width * 16 / 15` (the work it takes from a
    /// slide across it).
    Bump {
        /// Centre [m or rad] (finite).
        center: f64,
        /// Half the width of the support [m or rad] (> 0, finite): `b = 0` where
        /// `|x - center| >= half_width`.
        half_width: f64,
        /// Peak change of every dry level [N or N m] (finite; negative for a dip, then
        /// `kinetic_pos`, `kinetic_neg`, `breakaway_pos` and `breakaway_neg` plus it must each
        /// be `>= 0`, so no level turns negative).
        amplitude: f64,
    },
}

/// Parameters of a single-axis drive (motor + screw, belt or gear + carriage, or a
/// direct-drive joint), in SI or input units (see [`Motion`]).
///
/// Equation of motion, with the drive effort `Fd = gain * deadband(u(t - delay), deadband)`
/// and the applied force `F = Fd + offset`:
/// `inertia * xdd = F - position_force(x) - friction(mode, x, v)`.
///
/// Friction levels of a step (the input is held over it, so they are constant in it), with
/// the load share `L = load_friction * |Fd|` (the offset carries no load: `L` grows with the
/// effort the transmission passes, not with a constant bias): kinetic `Cp = kinetic_pos + L`,
/// `Cn = kinetic_neg + L`, breakaway `Bp = breakaway_pos + L`, `Bn = breakaway_neg + L`.
/// Dry friction of a moving axis, with `g = exp(-(v / stribeck_velocity)^2)` (`g = 0` when
/// `stribeck_velocity = 0`): `Sp = Cp + (Bp - Cp) g` moving positive, `Sn = Cn + (Bn - Cn) g`
/// moving negative, so it falls from the breakaway level at `v -> 0` to the kinetic level at
/// `|v| >> stribeck_velocity`. Friction `Sp + viscous_pos * v` moving positive,
/// `-Sn + viscous_neg * v` moving negative (both oppose the motion). A stopped axis holds
/// (`v = 0`, `xdd = 0`) while `-Bn <= F - position_force(x) <= Bp`, and breaks away when the
/// holding force passes `Bp` or `-Bn`.
///
/// With localised friction ([`LocalFriction::Bump`], `b(x)`) the four levels are taken at the
/// position: `Cp = kinetic_pos + L + b(x)`, `Cn = kinetic_neg + L + b(x)`,
/// `Bp = breakaway_pos + L + b(x)`, `Bn = breakaway_neg + L + b(x)` (the load share first,
/// then the bump; the Stribeck blend above works on these), so a moving axis meets `b` at
/// the position of each RK4 stage and a stopped one needs `breakaway + L + b(x)` at its
/// resting position to break away.
///
/// With `stribeck_velocity = 0`, `load_friction = 0` and `local_friction = None` (the
/// defaults) the friction is the classic kinetic + viscous law with stiction, computed with
/// exactly the operations it had before these three fields existed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DriveParams {
    /// Linear or rotary (units only).
    pub motion: Motion,
    /// Moving inertia, reflected to the axis [kg or kg m^2] (> 0, finite).
    pub inertia: f64,
    /// Input gain [N or N m per input unit, e.g. N/V] (> 0, finite); 1 when the input
    /// is already a force.
    pub gain: f64,
    /// Viscous friction for positive velocity [N s/m or N m s/rad] (>= 0).
    pub viscous_pos: f64,
    /// Viscous friction for negative velocity [N s/m or N m s/rad] (>= 0).
    pub viscous_neg: f64,
    /// Kinetic (sliding) dry friction magnitude for positive velocity [N or N m] (>= 0).
    pub kinetic_pos: f64,
    /// Kinetic (sliding) dry friction magnitude for negative velocity [N or N m] (>= 0).
    pub kinetic_neg: f64,
    /// Breakaway (static friction) magnitude towards positive [N or N m] (>= `kinetic_pos`;
    /// equal means no stiction): a stopped axis starts moving positive when
    /// `F - position_force(x) > breakaway_pos`.
    pub breakaway_pos: f64,
    /// Breakaway magnitude towards negative [N or N m] (>= `kinetic_neg`): a stopped axis starts
    /// moving negative when `F - position_force(x) < -breakaway_neg`.
    pub breakaway_neg: f64,
    /// Constant force added to the drive force [N or N m], positive along the axis (finite):
    /// a bias, a constant load, an amplifier offset times the gain.
    pub offset: f64,
    /// Position-dependent restoring force.
    pub position_force: PositionForce,
    /// Input dead band [input units] (>= 0, finite): `|u| <= d` gives 0, else
    /// `u - sign(u) d`.
    pub deadband: f64,
    /// Input delay in whole steps of the simulator (`0..=MAX_DRIVE_DELAY_STEPS`).
    pub delay_steps: usize,
    /// Lower end stop [m or rad] (may be `-inf`: none; not NaN).
    pub min: f64,
    /// Upper end stop [m or rad] (may be `+inf`: none; not NaN; > `min`).
    pub max: f64,
    /// Stribeck velocity `vs` [m/s or rad/s] (>= 0, finite); 0: no velocity weakening.
    /// Positive: the dry friction of a moving axis falls from the breakaway level to the
    /// kinetic level as `exp(-(v / vs)^2)` (about 37 % of the excess left at `|v| = vs`, 2 % at
    /// `2 vs`). Needs stiction (`breakaway > kinetic`) to have an effect.
    pub stribeck_velocity: f64,
    /// Load-dependent friction coefficient `mu` (dimensionless, in `[0, 1)`, finite); 0: none.
    /// Both the kinetic and the breakaway levels grow by `mu * |gain * deadband(u)|`, the drive
    /// effort before the `offset` is added (gearbox or screw friction that grows with the
    /// transmitted force). A stopped axis under `F = Fd` (no offset, no position force) then
    /// holds while `|F| <= breakaway / (1 - mu)`.
    pub load_friction: f64,
    /// Position-dependent dry friction added to all four dry levels ([`LocalFriction`]);
    /// `LocalFriction::None`: none.
    pub local_friction: LocalFriction,
}

impl Default for DriveParams {
    /// A 1 kg linear carriage with 1 N/V gain, no friction (no Stribeck weakening, no load
    /// friction, no localised friction), no position force, no dead band, no delay and no end stops: the frictionless
    /// point mass.
    fn default() -> Self {
        DriveParams {
            motion: Motion::Linear,
            inertia: 1.0,
            gain: 1.0,
            viscous_pos: 0.0,
            viscous_neg: 0.0,
            kinetic_pos: 0.0,
            kinetic_neg: 0.0,
            breakaway_pos: 0.0,
            breakaway_neg: 0.0,
            offset: 0.0,
            position_force: PositionForce::None,
            deadband: 0.0,
            delay_steps: 0,
            min: f64::NEG_INFINITY,
            max: f64::INFINITY,
            stribeck_velocity: 0.0,
            load_friction: 0.0,
            local_friction: LocalFriction::None,
        }
    }
}

fn not_nan(field: &'static str, value: f64) -> Result<(), Error> {
    if value.is_nan() {
        Err(Error {
            field,
            problem: Problem::NotANumber,
            value,
        })
    } else {
        Ok(())
    }
}

fn at_least(field: &'static str, value: f64, floor: f64) -> Result<(), Error> {
    if value < floor {
        Err(Error {
            field,
            problem: Problem::BelowKinetic,
            value,
        })
    } else {
        Ok(())
    }
}

impl DriveParams {
    /// Checks every field; the first bad one is returned as an [`Error`] naming it
    /// (`"inertia"`, `"breakaway_pos"`, `"position_force.stiffness"`, `"max"`...).
    ///
    /// Rules: `inertia`, `gain` > 0 and finite; viscous and kinetic coefficients and
    /// `deadband` at least 0 and finite; `breakaway_pos >= kinetic_pos`, `breakaway_neg >= kinetic_neg`
    /// (finite; `BelowKinetic` otherwise); `offset` finite; position-force stiffness >= 0 and
    /// centre finite; `delay_steps <= MAX_DRIVE_DELAY_STEPS` (`TooLarge`); `min`, `max` not
    /// NaN (infinite allowed) with `min < max` (`EmptyRange`, field `"min"`);
    /// `stribeck_velocity` at least 0 and finite; `load_friction` at least 0, finite and
    /// below 1 (`NotBelowOne`); a bump's `center` finite, `half_width` > 0 and finite,
    /// `amplitude` finite and at least minus the smallest of the four dry levels
    /// (`LevelBelowZero`, field `"local_friction.amplitude"`).
    pub fn validate(&self) -> Result<(), Error> {
        check("inertia", self.inertia, Problem::NotPositive)?;
        check("gain", self.gain, Problem::NotPositive)?;
        check("viscous_pos", self.viscous_pos, Problem::Negative)?;
        check("viscous_neg", self.viscous_neg, Problem::Negative)?;
        check("kinetic_pos", self.kinetic_pos, Problem::Negative)?;
        check("kinetic_neg", self.kinetic_neg, Problem::Negative)?;
        check("breakaway_pos", self.breakaway_pos, Problem::NotFinite)?;
        at_least("breakaway_pos", self.breakaway_pos, self.kinetic_pos)?;
        check("breakaway_neg", self.breakaway_neg, Problem::NotFinite)?;
        at_least("breakaway_neg", self.breakaway_neg, self.kinetic_neg)?;
        check("offset", self.offset, Problem::NotFinite)?;
        match self.position_force {
            PositionForce::None => {}
            PositionForce::Spring { stiffness, center }
            | PositionForce::Pendulum { stiffness, center } => {
                check("position_force.stiffness", stiffness, Problem::Negative)?;
                check("position_force.center", center, Problem::NotFinite)?;
            }
        }
        check("deadband", self.deadband, Problem::Negative)?;
        if self.delay_steps > MAX_DRIVE_DELAY_STEPS {
            return Err(Error {
                field: "delay_steps",
                problem: Problem::TooLarge,
                value: self.delay_steps as f64,
            });
        }
        check(
            "stribeck_velocity",
            self.stribeck_velocity,
            Problem::Negative,
        )?;
        check("load_friction", self.load_friction, Problem::Negative)?;
        if self.load_friction >= 1.0 {
            return Err(Error {
                field: "load_friction",
                problem: Problem::NotBelowOne,
                value: self.load_friction,
            });
        }
        if let LocalFriction::Bump {
            center,
            half_width,
            amplitude,
        } = self.local_friction
        {
            check("local_friction.center", center, Problem::NotFinite)?;
            check(
                "local_friction.half_width",
                half_width,
                Problem::NotPositive,
            )?;
            check("local_friction.amplitude", amplitude, Problem::NotFinite)?;
            // A dip may lower a level to 0, not below (the sign of a sum of two finite f64
            // is that of the exact sum, so this test is exact).
            for level in [
                self.kinetic_pos,
                self.kinetic_neg,
                self.breakaway_pos,
                self.breakaway_neg,
            ] {
                if level + amplitude < 0.0 {
                    return Err(Error {
                        field: "local_friction.amplitude",
                        problem: Problem::LevelBelowZero,
                        value: amplitude,
                    });
                }
            }
        }
        not_nan("min", self.min)?;
        not_nan("max", self.max)?;
        if self.min >= self.max {
            return Err(Error {
                field: "min",
                problem: Problem::EmptyRange,
                value: self.min,
            });
        }
        Ok(())
    }
}

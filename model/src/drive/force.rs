//! Forces of the drive: the position force, friction per mode (with the optional Stribeck
//! weakening, load-dependent and localised friction), and the acceleration.
//!
//! The operation order of every expression is the contract of `NUMERICS.md` ("Single-axis
//! drive"); the reference in `host-tests/src/drive_reference.rs` computes the same bits.

use super::params::{DriveParams, LocalFriction, PositionForce};
use crate::modes::Mode;
use crate::real::Real;

/// The position force in the model's scalar type.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Restoring<R> {
    None,
    Spring { k: R, c: R },
    Pendulum { k: R, c: R },
}

impl<R: Real> Restoring<R> {
    fn new(p: PositionForce) -> Self {
        match p {
            PositionForce::None => Restoring::None,
            PositionForce::Spring { stiffness, center } => Restoring::Spring {
                k: R::from_f64(stiffness),
                c: R::from_f64(center),
            },
            PositionForce::Pendulum { stiffness, center } => Restoring::Pendulum {
                k: R::from_f64(stiffness),
                c: R::from_f64(center),
            },
        }
    }

    /// Restoring force at `x` [N or N m]: `0`, `k * (x - c)` or `k * sin(x - c)`.
    #[inline]
    pub(crate) fn at(&self, x: R) -> R {
        match *self {
            Restoring::None => R::ZERO,
            Restoring::Spring { k, c } => k * (x - c),
            Restoring::Pendulum { k, c } => k * (x - c).sin(),
        }
    }
}

/// The localised friction bump `b(x)` in the model's scalar type (see
/// [`LocalFriction::Bump`]); all zero when there is none.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Bump<R> {
    /// Centre [m or rad].
    pub(crate) center: R,
    /// Half-width of the support [m or rad] (> 0).
    pub(crate) half_width: R,
    /// Peak change of the dry levels [N or N m].
    pub(crate) amplitude: R,
}

impl<R: Real> Bump<R> {
    fn new(l: LocalFriction) -> Self {
        match l {
            LocalFriction::None => Bump {
                center: R::ZERO,
                half_width: R::ONE,
                amplitude: R::ZERO,
            },
            LocalFriction::Bump {
                center,
                half_width,
                amplitude,
            } => Bump {
                center: R::from_f64(center),
                half_width: R::from_f64(half_width),
                amplitude: R::from_f64(amplitude),
            },
        }
    }
}

impl<R: Real> Bump<R> {
    /// `b(x)` inside the support, `None` outside (see [`Coeffs::bump_at`]).
    #[inline]
    fn at(&self, x: R) -> Option<R> {
        let s = (x - self.center) / self.half_width;
        if s > -R::ONE && s < R::ONE {
            let t = R::ONE - s * s;
            Some(self.amplitude * t * t)
        } else {
            None
        }
    }
}

/// Validated parameters in the model's scalar type.
///
/// The four dry-friction levels are the parameters' own in [`Drive`](super::Drive)'s copy;
/// with load friction, a step works on a copy whose levels include the step's load share
/// (see [`Coeffs::loaded`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Coeffs<R> {
    pub(crate) inertia: R,
    pub(crate) gain: R,
    pub(crate) viscous_pos: R,
    pub(crate) viscous_neg: R,
    pub(crate) kinetic_pos: R,
    pub(crate) kinetic_neg: R,
    pub(crate) breakaway_pos: R,
    pub(crate) breakaway_neg: R,
    pub(crate) offset: R,
    pub(crate) restoring: Restoring<R>,
    pub(crate) deadband: R,
    pub(crate) min: R,
    pub(crate) max: R,
    /// Stribeck velocity [m/s or rad/s]; used only when `stribeck_on`.
    pub(crate) stribeck: R,
    /// `stribeck > 0` in `R` (a velocity that rounds to 0 in `f32` means none).
    pub(crate) stribeck_on: bool,
    /// Load friction coefficient `mu`; used only when `load_on`.
    pub(crate) load: R,
    /// `load > 0` in `R`.
    pub(crate) load_on: bool,
    /// Localised friction; used only when `bump_on`.
    pub(crate) bump: Bump<R>,
    /// A bump whose amplitude is not 0 in `R` (a zero amplitude adds nothing: off).
    pub(crate) bump_on: bool,
    /// `load_on as u8 + 2 * bump_on as u8`: which compiled step [`Drive`](super::Drive) runs.
    pub(crate) extras: u8,
}

impl<R: Real> Coeffs<R> {
    /// Converts validated parameters (each value rounded once to `R`).
    pub(crate) fn new(p: &DriveParams) -> Self {
        Coeffs {
            inertia: R::from_f64(p.inertia),
            gain: R::from_f64(p.gain),
            viscous_pos: R::from_f64(p.viscous_pos),
            viscous_neg: R::from_f64(p.viscous_neg),
            kinetic_pos: R::from_f64(p.kinetic_pos),
            kinetic_neg: R::from_f64(p.kinetic_neg),
            breakaway_pos: R::from_f64(p.breakaway_pos),
            breakaway_neg: R::from_f64(p.breakaway_neg),
            offset: R::from_f64(p.offset),
            restoring: Restoring::new(p.position_force),
            deadband: R::from_f64(p.deadband),
            min: R::from_f64(p.min),
            max: R::from_f64(p.max),
            stribeck: R::from_f64(p.stribeck_velocity),
            stribeck_on: R::from_f64(p.stribeck_velocity) > R::ZERO,
            load: R::from_f64(p.load_friction),
            load_on: R::from_f64(p.load_friction) > R::ZERO,
            bump: Bump::new(p.local_friction),
            bump_on: Bump::<R>::new(p.local_friction).amplitude != R::ZERO,
            extras: 0,
        }
        .with_extras()
    }

    /// Sets `extras` from `load_on` and `bump_on`.
    fn with_extras(mut self) -> Self {
        self.extras = u8::from(self.load_on) + 2 * u8::from(self.bump_on);
        self
    }

    /// The coefficients of a step whose drive effort is `fd = gain * deadband(u)` [N or N m]
    /// under load friction (`load_on`): each dry level grows by `L = load * |fd|` (`Cp + L`,
    /// `Cn + L`, `Bp + L`, `Bn + L`, one rounding each). Without load friction the step uses
    /// the parameters' levels as they are (no operation added; the caller does not call this).
    #[inline]
    pub(crate) fn loaded(&self, fd: R) -> Self {
        let mag = if fd < R::ZERO { -fd } else { fd };
        let l = self.load * mag;
        Coeffs {
            kinetic_pos: self.kinetic_pos + l,
            kinetic_neg: self.kinetic_neg + l,
            breakaway_pos: self.breakaway_pos + l,
            breakaway_neg: self.breakaway_neg + l,
            ..*self
        }
    }

    /// Holding force at `x` under the applied force `f`: `f - position_force(x)`.
    #[inline]
    pub(crate) fn hold(&self, x: R, f: R) -> R {
        f - self.restoring.at(x)
    }

    /// The localised friction at `x` [N or N m]: `Some(amplitude * t * t)` with
    /// `t = 1 - s * s`, `s = (x - center) / half_width`, where `-1 < s < 1` (each operation
    /// left to right, one rounding each: the crane's bump kernel); `None` (nothing to add)
    /// outside the support and, with no evaluation, when there is no bump (`bump_on`).
    #[inline]
    pub(crate) fn bump_at(&self, x: R) -> Option<R> {
        if !self.bump_on {
            return None;
        }
        self.bump.at(x)
    }

    /// [`Coeffs::bump_at`] in a step compiled for `BUMP == bump_on`: `false` is `None` with no
    /// operation and no flag test (the step without localised friction is the code it was
    /// before the bump existed).
    #[inline]
    pub(crate) fn local<const BUMP: bool>(&self, x: R) -> Option<R> {
        if BUMP {
            self.bump.at(x)
        } else {
            None
        }
    }

    /// The breakaway levels `(Bp, Bn)` [N or N m] at a position whose localised friction is
    /// `b` ([`Coeffs::bump_at`]): `(breakaway_pos + b, breakaway_neg + b)`, or the levels of
    /// `self` as they are (no operation) when `b` is `None`.
    #[inline]
    pub(crate) fn breakaway_at(&self, b: Option<R>) -> (R, R) {
        match b {
            Some(b) => (self.breakaway_pos + b, self.breakaway_neg + b),
            None => (self.breakaway_pos, self.breakaway_neg),
        }
    }

    /// Dry friction magnitude [N or N m] of an axis moving at `v` between the `kinetic` and
    /// `breakaway` levels of its direction, first raised by the localised friction `b` when
    /// it is `Some` (`kinetic + b`, `breakaway + b`):
    /// `kinetic + (breakaway - kinetic) * exp(-(x * x))` with `x = v / stribeck` (libm `exp`,
    /// one evaluation); `kinetic` itself, no operation, without Stribeck weakening.
    #[inline]
    fn dry(&self, kinetic: R, breakaway: R, b: Option<R>, v: R) -> R {
        let (kinetic, breakaway) = match b {
            Some(b) => (kinetic + b, breakaway + b),
            None => (kinetic, breakaway),
        };
        if !self.stribeck_on {
            return kinetic;
        }
        let x = v / self.stribeck;
        kinetic + (breakaway - kinetic) * (-(x * x)).exp()
    }

    /// Friction of an axis moving at `(x, v)` [N or N m], the term subtracted in the
    /// equation of motion: `Sp + viscous_pos * v` (Positive), `-Sn + viscous_neg * v`
    /// (Negative), with the dry magnitudes `Sp`, `Sn` of `dry` at `x` (`kinetic_pos`,
    /// `kinetic_neg` without Stribeck weakening and localised friction); 0 when stopped (the
    /// holding force is then the friction, see `output`).
    #[inline]
    pub(crate) fn friction(&self, mode: Mode, x: R, v: R) -> R {
        self.friction_with(mode, self.bump_at(x), v)
    }

    /// [`Coeffs::friction`] with the localised friction `b` at the position already known
    /// (`bump_at(x)`).
    #[inline]
    pub(crate) fn friction_with(&self, mode: Mode, b: Option<R>, v: R) -> R {
        match mode {
            Mode::Positive => {
                self.dry(self.kinetic_pos, self.breakaway_pos, b, v) + self.viscous_pos * v
            }
            Mode::Negative => {
                -self.dry(self.kinetic_neg, self.breakaway_neg, b, v) + self.viscous_neg * v
            }
            Mode::Stopped => R::ZERO,
        }
    }

    /// Acceleration: `((f - position_force(x)) - friction(mode, x, v)) / inertia`; exactly 0
    /// when stopped. `BUMP` must be `bump_on` (see [`Coeffs::local`]).
    #[inline]
    pub(crate) fn accel<const BUMP: bool>(&self, x: R, v: R, mode: Mode, f: R) -> R {
        if mode == Mode::Stopped {
            return R::ZERO;
        }
        (self.hold(x, f) - self.friction_with(mode, self.local::<BUMP>(x), v)) / self.inertia
    }
}

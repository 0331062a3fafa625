//! A hybrid single-axis drive: motor + screw, belt or gear + carriage, or a direct-drive joint.
//!
//! `inertia * xdd = gain * deadband(u(t - delay)) + offset - position_force(x) - friction`,
//! with exact sticking: a stopped axis has `v = 0`, `xdd = 0` and is held by static friction
//! until the holding force `F - position_force(x)` passes a breakaway level (which may exceed
//! the kinetic level: stiction); a moving axis whose velocity reaches 0 stops, the stop
//! located inside the step, and sticks again while the holding force stays within the
//! breakaway levels. So a force ramp against a spring gives the exact stick-slip staircase.
//! Optional: Stribeck weakening (the sliding dry friction falls from the breakaway to the
//! kinetic level with speed), load-dependent friction (all dry levels grow with the drive
//! effort) and localised friction (all dry levels grow, or fall, over a stretch of the axis:
//! [`LocalFriction`]); see [`DriveParams`].
//!
//! Where to look:
//! - [`DriveParams`] (`params.rs`): parameters, units, signs, validation.
//! - `force.rs`: the position force, friction per mode, the acceleration.
//! - `step.rs`: RK4, event location, resets, mode resolution, the work bound.
//! - `NUMERICS.md`, section "Single-axis drive": the exact operation order, reproduced bit
//!   for bit by `host-tests/src/drive_reference.rs`.
//!
//! ```
//! use crane_model::{Drive, DriveParams, Mode, PositionForce};
//! let p = DriveParams {
//!     kinetic_pos: 1.0,
//!     kinetic_neg: 1.0,
//!     breakaway_pos: 1.5,
//!     breakaway_neg: 1.5,
//!     position_force: PositionForce::Spring { stiffness: 100.0, center: 0.0 },
//!     ..DriveParams::default()
//! };
//! let mut d: Drive = Drive::new(&p, 1e-3, 0.0)?;
//! d.step(1.2).unwrap(); // below breakaway: stays put
//! assert_eq!((d.x(), d.v(), d.mode()), (0.0, 0.0, Mode::Stopped));
//! d.step(2.0).unwrap(); // above: slips positive
//! assert_eq!(d.mode(), Mode::Positive);
//! # Ok::<(), crane_model::Error>(())
//! ```

mod delay;
mod force;
mod params;
mod step;

pub use params::{DriveParams, LocalFriction, Motion, PositionForce, MAX_DRIVE_DELAY_STEPS};
pub use step::{DriveReport, DRIVE_MAX_SEGMENTS};

use crate::extensions::deadband;
use crate::modes::Mode;
use crate::params::{check, Error, Problem};
use crate::real::Real;
use core::fmt;
use delay::DelayLine;
use force::Coeffs;

/// Why a drive step was rejected. State, mode, time and delay line stay as they were.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DriveStepError {
    /// The input `u` is NaN or infinite.
    InputNotFinite,
    /// The applied force `gain * deadband(u) + offset` overflowed to infinity.
    ForceNotFinite,
    /// The step produced a non-finite position or velocity.
    NonFinite,
}

impl fmt::Display for DriveStepError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            DriveStepError::InputNotFinite => {
                write!(f, "drive input `u` is not finite; step rejected")
            }
            DriveStepError::ForceNotFinite => {
                write!(
                    f,
                    "drive force `gain * u + offset` is not finite; step rejected"
                )
            }
            DriveStepError::NonFinite => {
                write!(f, "drive step gave a non-finite state; step rejected")
            }
        }
    }
}

/// Forces and acceleration at the current state with the last applied force
/// (see [`Drive::output`]). Units: force N (linear) or N m (rotary).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DriveOutput<R: Real = f64> {
    /// Acceleration [m/s^2 or rad/s^2]; exactly 0 when stopped.
    pub acceleration: R,
    /// Friction [N or N m], the term subtracted in the equation of motion: moving positive
    /// `Sp + viscous_pos * v` (> 0 opposes motion), moving negative `-Sn + viscous_neg * v`,
    /// with the dry levels `Sp`, `Sn` of [`DriveParams`] (`kinetic_pos`, `kinetic_neg` without
    /// Stribeck weakening, load and localised friction; the load share from the last step's
    /// drive effort, the bump at the current position); stopped, the static friction that holds the axis, equal to the holding force
    /// `applied - position_force`.
    pub friction: R,
    /// Position force `position_force(x)` [N or N m], positive when it pushes towards negative
    /// (restoring from above the centre).
    pub position_force: R,
    /// Applied force `gain * deadband(u(t - delay)) + offset` [N or N m], positive along the axis.
    pub applied: R,
}

/// The single-axis drive simulator: a hybrid automaton with a fixed step `h`.
///
/// Generic over [`Real`]: `f64` is bit-exact with the host reference, `f32` runs on the
/// Cortex-M4F's FPU.
#[derive(Clone, Debug)]
pub struct Drive<R: Real = f64> {
    params: DriveParams,
    c: Coeffs<R>,
    h: R,
    h64: f64,
    x: R,
    v: R,
    mode: Mode,
    steps: u64,
    applied: R,
    /// Drive effort `gain * deadband(u)` of the last accepted step [N or N m] (0 before the
    /// first): the load-friction share of [`Drive::output`].
    effort: R,
    delay: DelayLine<R>,
    /// `position_force(x)` of a stopped axis that has not moved since it was computed: a
    /// resting axis costs no position-force evaluation per step (same bits).
    resting_force: Option<R>,
    /// With localised friction, `b(x)` (`None`: 0 there) computed with `resting_force`, at the
    /// same position: a resting axis costs no bump evaluation per step either. Unused (never
    /// read or written) without localised friction.
    resting_bump: Option<R>,
}

impl<R: Real> Drive<R> {
    /// Validates the parameters and the step `h` [s] (> 0, finite; field `"h"`), and starts
    /// at rest (`Stopped`) at position `x0` [m or rad] (finite, within `[min, max]`; field
    /// `"state.x"`). Errors name the field.
    pub fn new(params: &DriveParams, h: f64, x0: f64) -> Result<Self, Error> {
        params.validate()?;
        check("h", h, Problem::NotPositive)?;
        let mut d = Drive {
            params: *params,
            c: Coeffs::new(params),
            h: R::from_f64(h),
            h64: h,
            x: R::ZERO,
            v: R::ZERO,
            mode: Mode::Stopped,
            steps: 0,
            applied: R::ZERO,
            effort: R::ZERO,
            delay: DelayLine::new(),
            resting_force: None,
            resting_bump: None,
        };
        d.set_state(x0, 0.0)?;
        Ok(d)
    }

    /// Replaces position `x` [m or rad] and velocity `v` [m/s or rad/s] (both finite, `x`
    /// within `[min, max]`; fields `"state.x"`, `"state.v"`). The mode follows the velocity
    /// (`0.0` and `-0.0` are `Stopped`, `-0.0` kept as given); at an end stop a velocity into
    /// it becomes `+0.0`. Parameters, delay line, time and last applied force are kept. On
    /// error nothing changes.
    pub fn set_state(&mut self, x: f64, v: f64) -> Result<(), Error> {
        check("state.x", x, Problem::NotFinite)?;
        check("state.v", v, Problem::NotFinite)?;
        let (xr, mut vr) = (R::from_f64(x), R::from_f64(v));
        if xr < self.c.min || xr > self.c.max {
            return Err(Error {
                field: "state.x",
                problem: Problem::OutOfLimits,
                value: x,
            });
        }
        if (xr >= self.c.max && vr > R::ZERO) || (xr <= self.c.min && vr < R::ZERO) {
            vr = R::ZERO;
        }
        self.mode = if vr > R::ZERO {
            Mode::Positive
        } else if vr < R::ZERO {
            Mode::Negative
        } else {
            Mode::Stopped
        };
        self.x = xr;
        self.v = vr;
        self.resting_force = None;
        Ok(())
    }

    /// Advances by one step `h` with input `u` [input units, e.g. V, or force when
    /// `gain = 1`], held over the step. Input path: delay line, dead band, then
    /// `gain * u + offset`. With load friction the step's dry-friction levels grow by
    /// `load_friction * |gain * deadband(u)|` (constant over the step, like the force); with
    /// localised friction they grow by `b(x)` at each evaluation's position.
    ///
    /// A non-finite input or force, or a non-finite result, rejects the step: state, mode,
    /// time and delay line stay as they were. Every accepted state is finite and within
    /// `[min, max]`.
    #[inline]
    pub fn step(&mut self, u: R) -> Result<DriveReport, DriveStepError> {
        // One test for the usual step with neither (the one the load flag alone had).
        match self.c.extras {
            0 => self.advance::<false, false>(u),
            1 => self.advance::<true, false>(u),
            2 => self.advance::<false, true>(u),
            _ => self.advance::<true, true>(u),
        }
    }

    /// [`Drive::step`] compiled for `LOAD == self.c.load_on` and `BUMP == self.c.bump_on`:
    /// without localised friction the step has exactly the operations it had before the bump
    /// existed (no flag test per evaluation either).
    #[inline]
    fn advance<const LOAD: bool, const BUMP: bool>(
        &mut self,
        u: R,
    ) -> Result<DriveReport, DriveStepError> {
        if !u.is_finite() {
            return Err(DriveStepError::InputNotFinite);
        }
        let k = self.params.delay_steps;
        let ud = self.delay.delayed(u, k);
        let fd = self.c.gain * deadband(ud, self.c.deadband);
        let f = fd + self.c.offset;
        if !f.is_finite() {
            return Err(DriveStepError::ForceNotFinite);
        }
        // The step's coefficients: the parameters', or with the load share in the levels.
        let loaded;
        let c = if LOAD {
            loaded = self.c.loaded(fd);
            &loaded
        } else {
            &self.c
        };
        let px = if self.mode == Mode::Stopped {
            Some(match self.resting_force {
                Some(p) => p,
                None => {
                    if BUMP {
                        self.resting_bump = self.c.local::<BUMP>(self.x);
                    }
                    self.c.restoring.at(self.x)
                }
            })
        } else {
            None
        };
        if let Some(p) = px {
            let hold = f - p;
            // `b(x)` at the resting position, computed with `p` (none without a bump).
            let b = if BUMP { self.resting_bump } else { None };
            // No breakaway guard open (the usual resting step: no friction evaluation), or a
            // release that its acceleration check refuses.
            let held = step::breakaway::<R, BUMP>(c, self.x, hold, b).is_none()
                || step::release::<R, BUMP>(c, self.x, self.v, hold, b).0 == Mode::Stopped;
            if held {
                // Held for the whole step (the holding force is constant over it): the state
                // stays as it is, bit for bit; what `step::step` would do, without its set-up.
                self.commit_input(f, fd, u, k);
                self.resting_force = Some(p);
                return Ok(DriveReport::default());
            }
        }
        let start = (self.x, self.v, self.mode);
        let (x, v, mode, report) = step::step::<R, BUMP>(c, self.h, start, f, px.map(|p| f - p));
        if !(x.is_finite() && v.is_finite()) {
            return Err(DriveStepError::NonFinite);
        }
        // Stopped at the start and at the end without an event or a late reset: the axis
        // never moved, `x` is the same value and so are its position force and bump.
        let rested = mode == Mode::Stopped && report == DriveReport::default();
        self.resting_force = if rested { px } else { None };
        self.x = x;
        self.v = v;
        self.mode = mode;
        self.commit_input(f, fd, u, k);
        Ok(report)
    }

    /// Records an accepted step's applied force `f`, drive effort `fd` and input `u` (delay
    /// `k` steps).
    #[inline]
    fn commit_input(&mut self, f: R, fd: R, u: R, k: usize) {
        self.applied = f;
        self.effort = fd;
        if k > 0 {
            self.delay.push(u);
        }
        self.steps += 1;
    }

    /// Position [m or rad].
    #[inline]
    pub fn x(&self) -> R {
        self.x
    }

    /// Velocity [m/s or rad/s] (exactly 0 when stopped).
    #[inline]
    pub fn v(&self) -> R {
        self.v
    }

    /// Motion mode.
    #[inline]
    pub fn mode(&self) -> Mode {
        self.mode
    }

    /// Simulated time [s]: `n h` after `n` accepted steps.
    pub fn time(&self) -> f64 {
        self.steps as f64 * self.h64
    }

    /// Number of accepted steps.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// Step length [s].
    pub fn h(&self) -> f64 {
        self.h64
    }

    /// The validated parameters.
    pub fn params(&self) -> &DriveParams {
        &self.params
    }

    /// Forces and acceleration at the current state with the last applied force and drive
    /// effort (0 before the first step).
    pub fn output(&self) -> DriveOutput<R> {
        let loaded;
        let c = if self.c.load_on {
            loaded = self.c.loaded(self.effort);
            &loaded
        } else {
            &self.c
        };
        let position_force = c.restoring.at(self.x);
        let friction = match self.mode {
            Mode::Stopped => self.applied - position_force,
            m => c.friction(m, self.x, self.v),
        };
        let acceleration = if c.bump_on {
            c.accel::<true>(self.x, self.v, self.mode, self.applied)
        } else {
            c.accel::<false>(self.x, self.v, self.mode, self.applied)
        };
        DriveOutput {
            acceleration,
            friction,
            position_force,
            applied: self.applied,
        }
    }
}

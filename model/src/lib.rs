//! # crane-model
//!
//! A `no_std`, allocation-free, fixed-step hybrid model of a 3-D overhead crane (INTECO
//! 3D-Crane) with position- and direction-dependent dry friction, after Vicente-Martinez &
//! Ramirez-Laboreo, "A hybrid dynamic model and parameter estimation method for accurately
//! simulating overhead cranes with friction", in the energy-consistent form of
//! `docs/MODEL.md`.
//!
//! Where to look:
//! - [`dynamics`]: the equations of motion `M(q) qdd + h + G = Q` and the holding forces.
//! - [`mode`]: the mode (direction of motion) of a drive axis.
//! - [`coeffs`]: the coefficient tables precomputed from the parameters.
//! - [`modes`]: the automaton's guards (breakaway margins, resolution), above the dynamics.
//! - [`adaptive`]: the adaptive (Dormand-Prince 5(4), event-located) integrator for
//!   offline use.
//! - [`integrator`]: RK4, event location, resets, the bounded work per step.
//! - [`friction`]: the hybrid and `tanh` friction laws, the dry-friction polynomial.
//! - [`params`]: parameters, defaults, validation.
//! - [`extensions`]: effects beyond the paper (localised friction, stiction, bias force, dead
//!   band, input delay), off by default.
//! - [`drive`]: a hybrid single-axis drive (inertia, friction per direction with stiction, a
//!   spring or pendulum force, gain, dead band, delay, end stops), linear or rotary.
//! - `NUMERICS.md` (next to `Cargo.toml`): the exact operation order that makes the f64 bits
//!   the same on every platform and equal to the host reference.
//!
//! Units are SI throughout; coordinates `q = [x, y, L, alpha, beta]` (see [`State`]).

#![no_std]
#![forbid(unsafe_code)]
#![deny(missing_docs)]
// Units are written in brackets, `[m]`, `[N s/m]`: they are not intra-doc links.
#![allow(rustdoc::broken_intra_doc_links)]
#![deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

pub mod adaptive;
pub mod coeffs;
pub mod crane;
pub mod dopri5;
pub mod drive;
pub mod dynamics;
pub mod extensions;
pub mod friction;
pub mod integrator;
pub mod mode;
pub mod modes;
pub mod params;
pub mod real;
pub mod solve;
pub mod state;

pub use crane::{hangs, Config, Crane, FrictionLaw, Output, StepError, MIN_HANG, U_MAX};
pub use drive::{
    Drive, DriveOutput, DriveParams, DriveReport, DriveStepError, LocalFriction, Motion,
    PositionForce, DRIVE_MAX_SEGMENTS, MAX_DRIVE_DELAY_STEPS,
};
pub use dynamics::{Coeffs, Eval, Law};
pub use extensions::{Axis, Bump, Direction, Extensions, Stiction, MAX_BUMPS, MAX_DELAY_STEPS};
pub use integrator::{StepReport, MAX_SEGMENTS, SWING_STOP};
pub use modes::Mode;
pub use params::{AxisParams, Error, Params, Problem};
pub use real::Real;
pub use state::State;

//! [`Sim`]: one model simulator with what a full snapshot needs and the model does not let a
//! caller read back or set: the step count of a restored simulator and the last input.
//!
//! `crane_model::Crane` keeps its step count and last applied input private (the count gives
//! `time`; the input gives `output`, the friction, tension and accelerations "with the last
//! input"). Every step of this crate goes through [`Sim::step`], which records the input
//! the model applied, so a snapshot can hold it; a restored simulator carries the steps taken
//! before the snapshot in `base`. With both, a restored simulator answers `steps`, `time`,
//! `output` and every later step with the same bits as the one the snapshot was taken of.

use crate::errors::{Failure, Fallible};
use crate::setup::Setup;
use crane_model::{Crane, Error, Mode, State, StepError, StepReport, U_MAX};

/// The input the model applies and records for voltages `u` [V]: each saturated to
/// +-[`U_MAX`] by the same comparisons as `Crane::step` (bit for bit, `-0.0` kept).
///
/// This is the model's recorded input only because the setups of this crate never switch on
/// the dead band or the input delay (`Setup::ext` carries stiction only); the model applies
/// those after saturation.
pub fn saturate(u: [f64; 3]) -> [f64; 3] {
    // `clamp` compares as `Crane::step` does (`v < min`, `v > max`; `v` kept otherwise).
    u.map(|v| v.clamp(-U_MAX, U_MAX))
}

/// A simulator stepped from Python (alone, in a batch, or in a rollout).
#[derive(Clone, Debug)]
pub struct Sim {
    crane: Crane,
    /// Steps taken before the model's own count began (a restored simulator's past).
    base: u64,
    /// The (saturated) input of the last accepted step [V]; 0 V before the first.
    u_last: [f64; 3],
}

impl Sim {
    /// A new simulator (no step taken yet).
    pub fn new(crane: Crane) -> Self {
        Sim {
            crane,
            base: 0,
            u_last: [0.0; 3],
        }
    }

    /// The model's simulator.
    pub fn crane(&self) -> &Crane {
        &self.crane
    }

    /// One step of `h` with voltages `u` [V] (`Crane::step`); a rejected step changes nothing.
    #[inline]
    pub fn step(&mut self, u: [f64; 3]) -> Result<StepReport, StepError> {
        let report = self.crane.step(u)?;
        self.u_last = saturate(u);
        Ok(report)
    }

    /// Replaces the physical state (`Crane::set_state`: modes from the velocities; the step
    /// count and the last input are kept).
    pub fn set_state(&mut self, s: State) -> Result<(), Error> {
        self.crane.set_state(s)
    }

    /// Accepted steps, those before a restore included.
    pub fn steps(&self) -> u64 {
        self.base.saturating_add(self.crane.steps())
    }

    /// Simulated time [s]: `steps * h`, the model's own formula (the same bits).
    pub fn time(&self) -> f64 {
        self.steps() as f64 * self.crane.h()
    }

    /// The (saturated) input of the last accepted step [V] (`[0, 0, 0]` before the first).
    pub fn u_last(&self) -> [f64; 3] {
        self.u_last
    }

    /// A simulator of `setup` at `state` (velocities, positions: exact bits) with `steps`
    /// taken and last input `u_last` [V] (already saturated: within +-12 V), the way a
    /// snapshot describes it. `at` names the snapshot in messages (`snapshot`,
    /// `snapshot["sims"][3]`).
    ///
    /// The model keeps its last input private, so it is put there by one step with it
    /// (`Crane::set_state` keeps the last input), from `state` or, should the model reject
    /// that step, from the setup's initial state; `state` is then set again. The modes follow
    /// from the velocities, as after every accepted step (the caller compares them with the
    /// snapshot's).
    pub fn restore(
        setup: &Setup,
        state: State,
        steps: u64,
        u_last: [f64; 3],
        at: &str,
    ) -> Fallible<Sim> {
        let mut crane = setup.build().map_err(|e| {
            // The snapshot's key of the model's field.
            let key = match e.field {
                f if f.starts_with("state.") => "init",
                f if f.starts_with("config.law") => "gamma",
                f if f.starts_with("config.") => "h",
                f if f.starts_with("stiction") => "stiction",
                _ => "params",
            };
            Failure::ParamAt(format!("{at}[\"{key}\"]"), e)
        })?;
        let put = |c: &mut Crane| {
            c.set_state(state)
                .map_err(|e| Failure::ParamAt(format!("{at}[\"state\"]"), e))
        };
        put(&mut crane)?;
        if let Some(i) = u_last
            .iter()
            .position(|v| !v.is_finite() || v.abs() > U_MAX)
        {
            return Err(Failure::Input(format!(
                "`{at}[\"u_last\"][{i}]` must be a saturated voltage within +-{U_MAX} V (got {})",
                u_last[i]
            )));
        }
        if u_last.iter().any(|v| v.to_bits() != 0) {
            if steps == 0 {
                return Err(Failure::Input(format!(
                    "`{at}[\"u_last\"]` must be [0.0, 0.0, 0.0] while `steps` is 0 (no step taken, no input applied; got {u_last:?})"
                )));
            }
            // A rejected step leaves the simulator as it was.
            let applied = crane.step(u_last).is_ok() || {
                crane
                    .set_state(setup.init)
                    .map_err(|e| Failure::ParamAt(format!("{at}[\"init\"]"), e))?;
                crane.step(u_last).is_ok()
            };
            if !applied {
                return Err(Failure::Input(format!(
                    "`{at}[\"u_last\"]`: the model rejects a step with {u_last:?} V from both the state and the initial state, so it cannot be restored as the last input"
                )));
            }
            put(&mut crane)?;
        }
        Ok(Sim {
            base: steps.saturating_sub(crane.steps()),
            crane,
            u_last,
        })
    }

    /// The modes of X, Y, rope.
    pub fn modes(&self) -> [Mode; 3] {
        self.crane.modes()
    }
}

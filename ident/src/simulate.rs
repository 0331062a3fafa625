//! Simulating a recorded single-axis run: the recorded input, held over each sample
//! (zero-order hold), drives the hybrid single-axis model (`crane_model::drive`) from the
//! recorded initial position at rest. This is the one way a recorded drive run is simulated
//! (the diagnosis scores every candidate model with it).
//!
//! The simulator's step is the sample period divided into `n` equal sub-steps, with
//! `h = dt / n <= min(1 ms, sqrt(J / k) / 4, J / (4 D))` (RK4 well inside its stability limit
//! for the stiffest linear part of the model), `n <= MAX_SUBSTEPS`.

use crane_model::drive::{Drive, DriveParams, DriveStepError, PositionForce};

/// Largest number of simulator steps per recorded sample.
pub const MAX_SUBSTEPS: usize = 2000;

/// Why a recorded run could not be simulated.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum SimulateError {
    /// The parameters or the initial state were rejected by the model.
    #[error("model parameters rejected: {0}")]
    Params(String),
    /// A step was rejected (non-finite input or state).
    #[error("simulation step {step} rejected: {error:?}")]
    Step {
        /// Sample index.
        step: usize,
        /// The model's reason.
        error: DriveStepError,
    },
    /// The sample period is not a positive finite number.
    #[error("sample period {0} s is not positive and finite")]
    Period(f64),
}

/// Number of simulator steps per sample of period `dt` for these parameters.
pub fn substeps(p: &DriveParams, dt: f64) -> usize {
    let k = match p.position_force {
        PositionForce::None => 0.0,
        PositionForce::Spring { stiffness, .. } | PositionForce::Pendulum { stiffness, .. } => {
            stiffness
        }
    };
    let d = p.viscous_pos.max(p.viscous_neg);
    let mut h = 1e-3f64;
    if k > 0.0 {
        h = h.min(0.25 * (p.inertia / k).sqrt());
    }
    if d > 0.0 {
        h = h.min(0.25 * p.inertia / d);
    }
    let n = (dt / h).ceil();
    if n.is_finite() && n >= 1.0 {
        (n as usize).min(MAX_SUBSTEPS)
    } else {
        1
    }
}

/// Simulates a run: `u[i]` [input units] is applied over `[t_i, t_i + dt)`, the model starts
/// at `x0` with velocity `v0` (0: at rest; a log that starts mid-motion starts the model
/// moving, its mode following the sign); returns the simulated position at every sample time
/// (`x[0] = x0`).
pub fn simulate_drive(
    p: &DriveParams,
    x0: f64,
    v0: f64,
    dt: f64,
    u: &[f64],
) -> Result<Vec<f64>, SimulateError> {
    if !(dt > 0.0 && dt.is_finite()) {
        return Err(SimulateError::Period(dt));
    }
    let n = substeps(p, dt);
    let h = dt / n as f64;
    let mut d = Drive::<f64>::new(p, h, x0).map_err(|e| SimulateError::Params(e.to_string()))?;
    if v0 != 0.0 {
        d.set_state(x0, v0)
            .map_err(|e| SimulateError::Params(e.to_string()))?;
    }
    let mut out = Vec::with_capacity(u.len());
    if u.is_empty() {
        return Ok(out);
    }
    out.push(x0);
    for (i, &ui) in u.iter().enumerate().take(u.len() - 1) {
        for _ in 0..n {
            d.step(ui)
                .map_err(|error| SimulateError::Step { step: i, error })?;
        }
        out.push(d.x());
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stuck_axis_stays_at_its_recorded_start() {
        let p = DriveParams {
            kinetic_pos: 1.0,
            kinetic_neg: 1.0,
            breakaway_pos: 1.0,
            breakaway_neg: 1.0,
            ..DriveParams::default()
        };
        let x = simulate_drive(&p, 0.3, 0.0, 0.01, &[0.5; 100]).unwrap();
        assert_eq!(x.len(), 100);
        assert!(x.iter().all(|&q| q == 0.3));
    }

    #[test]
    fn a_free_mass_follows_the_input() {
        // 1 kg, 1 N for 1 s: x = t^2 / 2
        let p = DriveParams::default();
        let x = simulate_drive(&p, 0.0, 0.0, 0.01, &[1.0; 101]).unwrap();
        assert!((x[100] - 0.5).abs() < 1e-9, "{}", x[100]);
    }

    #[test]
    fn bad_period_is_an_error() {
        assert!(simulate_drive(&DriveParams::default(), 0.0, 0.0, f64::NAN, &[0.0]).is_err());
        assert!(simulate_drive(&DriveParams::default(), 0.0, 0.0, 0.0, &[0.0]).is_err());
    }
}

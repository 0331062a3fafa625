//! Simulating a recorded single-axis run: the recorded input, held over each sample
//! (zero-order hold), drives the hybrid single-axis model (`crane_model::drive`) from the
//! recorded initial position at rest. This is the one way a recorded drive run is simulated
//! (the diagnosis scores every candidate model with it).
//!
//! The simulator's step is the sample period divided into `n` equal sub-steps, with
//! `h = dt / n <= min(1 ms, sqrt(J / k) / 4, J / (4 D))` (RK4 well inside its stability limit
//! for the stiffest linear part of the model), `n <= MAX_SUBSTEPS`. `D` is the larger viscous
//! coefficient or, with Stribeck weakening (`vs > 0`), the steepest slope of the weakening
//! friction if larger, `0.86 (breakaway - kinetic) / vs` (the largest of
//! `|d/dv (B - C) exp(-(v / vs)^2)|` is `sqrt(2 / e) (B - C) / vs`); the load friction
//! (constant over a step) adds nothing. `k` is the position force's stiffness plus, with a
//! localised friction bump, its steepest slope `1.54 |A| / w` (the largest of
//! `|d/dx A (1 - s^2)^2|`, `s = (x - c) / w`, is `8 / (3 sqrt 3) |A| / w`): a friction that
//! changes with position acts on the motion like a spring of that stiffness. Every
//! parameter set the model takes, the three friction effects included, is simulated as given
//! (`DriveParams` is passed through unchanged).

use crane_model::drive::{Drive, DriveParams, DriveStepError, LocalFriction, PositionForce};

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
    let mut k = match p.position_force {
        PositionForce::None => 0.0,
        PositionForce::Spring { stiffness, .. } | PositionForce::Pendulum { stiffness, .. } => {
            stiffness
        }
    };
    if let LocalFriction::Bump {
        half_width,
        amplitude,
        ..
    } = p.local_friction
    {
        k += 1.54 * amplitude.abs() / half_width;
    }
    let mut d = p.viscous_pos.max(p.viscous_neg);
    if p.stribeck_velocity > 0.0 {
        let excess = (p.breakaway_pos - p.kinetic_pos).max(p.breakaway_neg - p.kinetic_neg);
        d = d.max(0.86 * excess / p.stribeck_velocity);
    }
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
    fn the_friction_effects_reach_the_model() {
        // 1 kg, kinetic 1 N, breakaway 2 N, pushed with 3 N for 1 s from rest.
        let base = DriveParams {
            kinetic_pos: 1.0,
            kinetic_neg: 1.0,
            breakaway_pos: 2.0,
            breakaway_neg: 2.0,
            ..DriveParams::default()
        };
        let x = |p: &DriveParams| simulate_drive(p, 0.0, 0.0, 0.01, &[3.0; 101]).unwrap()[100];
        // Plain: a = 2 m/s^2; load friction 0.2: a = (3 - 1 - 0.6) = 1.4 m/s^2.
        assert!((x(&base) - 1.0).abs() < 1e-9, "{}", x(&base));
        let loaded = DriveParams {
            load_friction: 0.2,
            ..base
        };
        assert!((x(&loaded) - 0.7).abs() < 1e-9, "{}", x(&loaded));
        // Stribeck weakening: the friction starts at breakaway, so it lags the plain run a
        // little; and the weakening slope shortens the step.
        let weak = DriveParams {
            stribeck_velocity: 0.002,
            ..base
        };
        let xw = x(&weak);
        assert!(xw < x(&base) - 1e-4 && xw > x(&base) - 0.05, "{xw}");
        assert!(substeps(&weak, 0.01) > substeps(&base, 0.01));
        // A bump of 0.5 N over +-0.1 m at 0.5 m: the run crosses it (x = t^2 at 2 m/s^2)
        // and lags the plain one by about the work it takes, 0.5 * 0.1 * 16 / 15 J.
        let bumpy = DriveParams {
            local_friction: LocalFriction::Bump {
                center: 0.5,
                half_width: 0.1,
                amplitude: 0.5,
            },
            ..base
        };
        let xb = x(&bumpy);
        assert!(xb < x(&base) - 0.01 && xb > x(&base) - 0.1, "{xb}");
        // Its slope (77 kN/m on 1 kg over +-10 um) shortens the step like a spring of that
        // stiffness.
        let steep = DriveParams {
            local_friction: LocalFriction::Bump {
                center: 0.5,
                half_width: 1e-5,
                amplitude: 0.5,
            },
            ..base
        };
        let spring = DriveParams {
            position_force: PositionForce::Spring {
                stiffness: 1.54 * 0.5 / 1e-5,
                center: 0.0,
            },
            ..base
        };
        assert_eq!(substeps(&steep, 0.01), substeps(&spring, 0.01));
        assert!(substeps(&steep, 0.01) > substeps(&base, 0.01));
    }

    #[test]
    fn bad_period_is_an_error() {
        assert!(simulate_drive(&DriveParams::default(), 0.0, 0.0, f64::NAN, &[0.0]).is_err());
        assert!(simulate_drive(&DriveParams::default(), 0.0, 0.0, 0.0, &[0.0]).is_err());
    }
}

//! Stage 3: a structure's fitted model simulated on recorded runs, scored by position NMAE.

use super::estimate::{Estimate, Structure};
use super::prep::Prepared;
use crane_ident::simulate::{simulate_drive, SimulateError};

/// A fitted model with its simulations of the held-out runs.
#[derive(Clone, Debug)]
pub struct Scored {
    /// The fit.
    pub est: Estimate,
    /// Mean held-out position NMAE [%].
    pub nmae: f64,
    /// Per held-out run NMAE [%] (same order as the runs).
    pub per_run: Vec<f64>,
    /// Simulated positions per held-out run.
    pub sims: Vec<Vec<f64>>,
    /// Mean NMAE over the held-out runs the selection scores (those that move) [%].
    pub selection: f64,
}

/// The recorded input as the structure applies it: shifted by the delay in whole samples
/// (the first value held before the record starts). The dead band is applied by the model.
pub fn delayed_input(u: &[f64], s: &Structure) -> Vec<f64> {
    (0..u.len()).map(|i| u[i.saturating_sub(s.delay)]).collect()
}

/// Simulates a fitted model on a run (from the run's first position, at rest).
pub fn simulate(est: &Estimate, run: &Prepared) -> Result<Vec<f64>, SimulateError> {
    let mut p = est.params;
    p.deadband = est.structure.deadband;
    let x0 = run.run.x.first().copied().unwrap_or(0.0);
    simulate_drive(
        &p,
        x0,
        run.run.dt,
        &delayed_input(&run.run.u, &est.structure),
    )
}

/// Position NMAE [%]: mean absolute error over the measured position range (floored at the
/// position quantum, so a run that never moves is scored against the encoder step).
pub fn nmae(sim: &[f64], meas: &[f64], quantum: f64) -> f64 {
    if meas.is_empty() || sim.len() != meas.len() {
        return f64::INFINITY;
    }
    let (lo, hi) = meas
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &x| {
            (l.min(x), h.max(x))
        });
    let range = (hi - lo).max(quantum).max(f64::MIN_POSITIVE);
    let mae = sim
        .iter()
        .zip(meas)
        .map(|(s, m)| (s - m).abs())
        .sum::<f64>()
        / meas.len() as f64;
    100.0 * mae / range
}

/// NMAE of predicting no motion at all (the run's first position throughout) [%].
pub fn nmae_no_motion(run: &Prepared, quantum: f64) -> f64 {
    let x0 = run.run.x.first().copied().unwrap_or(0.0);
    nmae(&vec![x0; run.run.x.len()], &run.run.x, quantum)
}

/// Simulates and scores a fit on the held-out runs; `Err` names the run whose simulation
/// failed.
pub fn score(est: Estimate, held: &[&Prepared], quantum: f64) -> Result<Scored, String> {
    let mut per_run = Vec::with_capacity(held.len());
    let mut sims = Vec::with_capacity(held.len());
    for r in held {
        let sim = simulate(&est, r).map_err(|e| format!("{}: {e}", r.run.name))?;
        per_run.push(nmae(&sim, &r.run.x, quantum));
        sims.push(sim);
    }
    let nmae = if per_run.is_empty() {
        f64::INFINITY
    } else {
        per_run.iter().sum::<f64>() / per_run.len() as f64
    };
    Ok(Scored {
        est,
        nmae,
        selection: nmae,
        per_run,
        sims,
    })
}

//! Stage 3: a structure's fitted model simulated on recorded runs, scored by position NMAE.

use super::estimate::{Estimate, Structure};
use super::prep::Prepared;
use crane_ident::simulate::{simulate_drive, SimulateError};
use rayon::prelude::*;

/// A fitted model with its simulations of the held-out runs.
#[derive(Clone, Debug)]
pub struct Scored {
    /// The fit.
    pub est: Estimate,
    /// Mean held-out position NMAE [%] (`f64::INFINITY` when a run's simulation diverged).
    pub nmae: f64,
    /// Per held-out run NMAE [%] (same order as the runs; `f64::INFINITY`: diverged).
    pub per_run: Vec<f64>,
    /// Simulated positions per held-out run.
    pub sims: Vec<Vec<f64>>,
    /// Mean NMAE over the held-out runs the selection scores (those that move) [%].
    pub selection: f64,
}

/// The recorded input as the structure applies it: delayed ([`super::estimate::delayed`])
/// and saturated ([`super::estimate::saturate`]). The dead band is applied by the model.
pub fn delayed_input(u: &[f64], s: &Structure) -> Vec<f64> {
    (0..u.len())
        .map(|i| super::estimate::saturate(super::estimate::delayed(u, i, s.delay), s))
        .collect()
}

/// Simulates a fitted model on a run, from the run's first position and its start velocity
/// ([`Prepared::v0`]: 0 unless the log starts mid-motion). With an input delay of `d`
/// samples the input of the first `ceil d` samples was sent before the record began and is
/// unknown: those samples are the measured positions, and the simulation starts after them
/// from the measured position and velocity there ([`Prepared::v_at`]). Holding the first
/// recorded input over them instead drove a log that begins with a command for a delay it
/// never had (a 0.1 s delay on a 10 kHz log of pulses that starts with one read as 87 ms).
pub fn simulate(est: &Estimate, run: &Prepared) -> Result<Vec<f64>, SimulateError> {
    let mut p = est.params;
    p.deadband = est.structure.deadband;
    let u = delayed_input(&run.run.u, &est.structure);
    let x = &run.run.x;
    // the first sample whose delayed input was recorded (none past the run's last sample)
    let start = (est.structure.delay.max(0.0).ceil() as usize).min(x.len().saturating_sub(1));
    if start == 0 {
        let x0 = x.first().copied().unwrap_or(0.0);
        return simulate_drive(&p, x0, run.v0, run.run.dt, &u);
    }
    let tail = simulate_drive(&p, x[start], run.v_at(start), run.run.dt, &u[start..])?;
    let mut out = x[..start].to_vec();
    out.extend(tail);
    Ok(out)
}

/// Position NMAE [%]: mean absolute error over the measured position range (floored at the
/// position quantum, so a run that never moves is scored against the encoder step).
pub fn nmae(sim: &[f64], meas: &[f64], quantum: f64) -> f64 {
    if meas.is_empty() || sim.len() != meas.len() {
        return f64::INFINITY;
    }
    nmae_over(sim, meas, extent(meas), quantum)
}

/// The smallest and largest of `x` (`(inf, -inf)` when empty).
fn extent(x: &[f64]) -> (f64, f64) {
    x.iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &x| {
            (l.min(x), h.max(x))
        })
}

/// [`nmae`] with the measured range `(lo, hi)` given.
fn nmae_over(sim: &[f64], meas: &[f64], (lo, hi): (f64, f64), quantum: f64) -> f64 {
    let range = (hi - lo).max(quantum).max(f64::MIN_POSITIVE);
    let mae = sim
        .iter()
        .zip(meas)
        .map(|(s, m)| (s - m).abs())
        .sum::<f64>()
        / meas.len() as f64;
    100.0 * mae / range
}

/// A change of the input smaller than this fraction of the run's largest change from its
/// first value is "nothing happening yet" for [`active_from`].
pub const INPUT_STILL_FRACTION: f64 = 0.01;

/// The first sample of a run's active part: one before the input first departs from its first
/// value by more than [`INPUT_STILL_FRACTION`] of the run's largest departure, or the measured
/// position from its first value by more than two position quanta, whichever comes first.
///
/// Every model starts at the run's first position at rest, so over a leading rest (a logger
/// started before the test, a rig waiting for its operator) every model's error is zero:
/// scored, that rest would only dilute each run's mean error, by as much as the wait is long.
/// The scores, the `none` level and the report are computed from here on, so a log with 20 s
/// of rest in front is diagnosed as the same log without it. Depends on the run only, never on
/// the model, so every model is scored on the same samples.
pub fn active_from(run: &Prepared, quantum: f64) -> usize {
    let (x, u) = (&run.run.x, &run.run.u);
    let (Some(&x0), Some(&u0)) = (x.first(), u.first()) else {
        return 0;
    };
    let du_max = u.iter().fold(0.0f64, |m, &v| m.max((v - u0).abs()));
    let du_tol = INPUT_STILL_FRACTION * du_max;
    let dx_tol = 2.0 * quantum;
    let first = x
        .iter()
        .zip(u)
        .position(|(&xk, &uk)| (uk - u0).abs() > du_tol || (xk - x0).abs() > dx_tol)
        .unwrap_or(0);
    first.saturating_sub(1)
}

/// A simulation has diverged when it leaves the measured range by this many ranges (either
/// side, the range floored at the position quantum): its error is no figure, only "diverged"
/// (a baseline drifting away once printed a held-out NMAE of 33,291,078 %). Tenfold is far
/// beyond any error a model that follows the run can make (an NMAE of 100 % is a model off
/// by the whole range on average), and close enough that a runaway is caught before it
/// dominates a mean.
pub const DIVERGED_RANGES: f64 = 10.0;

/// Whether a simulation left the measured range by [`DIVERGED_RANGES`] ranges, or is not
/// finite.
pub fn diverged(sim: &[f64], meas: &[f64], quantum: f64) -> bool {
    diverged_from(sim, extent(meas), quantum)
}

/// [`diverged`] with the measured range `(lo, hi)` given.
fn diverged_from(sim: &[f64], (lo, hi): (f64, f64), quantum: f64) -> bool {
    let range = (hi - lo).max(quantum);
    let (a, b) = (lo - DIVERGED_RANGES * range, hi + DIVERGED_RANGES * range);
    sim.iter().any(|&s| !(s >= a && s <= b))
}

/// Position NMAE of a simulation of a run over the run's active part ([`active_from`]) [%];
/// `f64::INFINITY` when the simulation diverged ([`diverged`]).
pub fn run_nmae(sim: &[f64], run: &Prepared, quantum: f64) -> f64 {
    if sim.len() != run.run.x.len() || diverged(sim, &run.run.x, quantum) {
        return f64::INFINITY;
    }
    let k = active_from(run, quantum);
    nmae(&sim[k..], &run.run.x[k..], quantum)
}

/// What [`run_nmae`] reads of a run besides the simulation, computed once per run (a
/// grid search scores hundreds of simulations of the same fitting runs).
#[derive(Clone, Copy, Debug)]
pub struct RunScale {
    /// The run's active part's first sample ([`active_from`]).
    active: usize,
    /// The smallest and largest measured position.
    whole: (f64, f64),
    /// The same over the active part.
    part: (f64, f64),
    /// The position quantum.
    quantum: f64,
}

impl RunScale {
    /// The scale of `run` with position quantum `quantum`.
    pub fn new(run: &Prepared, quantum: f64) -> RunScale {
        let x = &run.run.x;
        let active = active_from(run, quantum);
        RunScale {
            active,
            whole: extent(x),
            part: extent(x.get(active..).unwrap_or(&[])),
            quantum,
        }
    }

    /// [`run_nmae`] of a simulation of `run`, the run this scale was made of: the same value.
    pub fn run_nmae(&self, sim: &[f64], run: &Prepared) -> f64 {
        let x = &run.run.x;
        if sim.len() != x.len() || diverged_from(sim, self.whole, self.quantum) {
            return f64::INFINITY;
        }
        let k = self.active;
        if x.len() == k {
            return f64::INFINITY;
        }
        nmae_over(&sim[k..], &x[k..], self.part, self.quantum)
    }
}

/// NMAE of predicting no motion at all (the run's first position throughout) [%], over the
/// run's active part.
pub fn nmae_no_motion(run: &Prepared, quantum: f64) -> f64 {
    let x0 = run.run.x.first().copied().unwrap_or(0.0);
    run_nmae(&vec![x0; run.run.x.len()], run, quantum)
}

/// Simulates and scores a fit on the held-out runs; `Err` names the run whose simulation
/// failed.
///
/// The runs are simulated in parallel (rayon), each on its own; the results are gathered in
/// the runs' order, so the score and the first failing run named are those of a serial loop.
pub fn score(est: Estimate, held: &[&Prepared], quantum: f64) -> Result<Scored, String> {
    let simulated: Vec<Result<Vec<f64>, String>> = held
        .par_iter()
        .map(|r| simulate(&est, r).map_err(|e| format!("{}: {e}", r.run.name)))
        .collect();
    let mut per_run = Vec::with_capacity(held.len());
    let mut sims = Vec::with_capacity(held.len());
    for (r, sim) in held.iter().zip(simulated) {
        let sim = sim?;
        per_run.push(run_nmae(&sim, r, quantum));
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::{nmae_or_diverged, RunSimulation};

    #[test]
    fn a_runaway_simulation_is_diverged_and_never_a_figure() {
        let meas = [0.0, 0.01, 0.02, 0.01];
        // within the range, or a few ranges off: a (bad) figure
        assert!(!diverged(&[0.0, 0.05, 0.1, 0.2], &meas, 1e-6));
        // 10 ranges beyond the largest measured position, or not finite: diverged
        assert!(diverged(&[0.0, 0.05, 0.1, 0.23], &meas, 1e-6));
        assert!(diverged(&[0.0, f64::NAN, 0.0, 0.0], &meas, 1e-6));
        // a run at rest: the range is the quantum
        assert!(diverged(&[0.0, 0.0, 0.0, 1.2e-5], &[0.0; 4], 1e-6));
        let r = RunSimulation {
            file: "a.csv".into(),
            nmae_before: f64::INFINITY,
            nmae_after: 3.25,
            nmae_no_motion: 40.0,
            moves: true,
            diverged_before: true,
            diverged_after: false,
        };
        let j = serde_json::to_value(&r).unwrap();
        assert!(j["nmae_before"].is_null(), "{j}");
        assert_eq!(j["nmae_after"], 3.25);
        let back: RunSimulation = serde_json::from_value(j).unwrap();
        assert_eq!(back, r);
        assert_eq!(nmae_or_diverged::text(f64::INFINITY, 2), "diverged");
        assert_eq!(nmae_or_diverged::text(3.254, 2), "3.25 %");
    }

    #[test]
    fn a_delayed_model_starts_where_its_input_was_recorded() {
        use crate::drive::prep::DriveRun;
        // a log that begins with a command (5 against a dry level of 1); the axis, 20
        // samples late, is at rest over them
        let n = 60;
        let u: Vec<f64> = (0..n).map(|k| if k < 10 { 5.0 } else { 0.0 }).collect();
        let run = DriveRun {
            name: "a.csv".into(),
            held_out: false,
            dt: 0.01,
            x: vec![0.25; n],
            u,
            refresh: 1,
            input_at: (0..n).map(|k| k as f64 * 0.01).collect(),
            read_at: (0..n).map(|k| k as f64 * 0.01).collect(),
        };
        let mut run = Prepared::with_window(run, 2);
        run.set_start(1e-3);
        let mut est = crate::drive::refine::tests::estimate(1.0, [1.0, 1.0], [1.0, 1.0]);
        est.structure.delay = 19.5;
        let sim = simulate(&est, &run).expect("simulates");
        assert_eq!(sim.len(), n);
        // the first ceil(19.5) samples are the record; the model starts there, at rest, and
        // is then driven by the first recorded command
        assert!(sim[..=20].iter().all(|&x| x == 0.25), "{:?}", &sim[..22]);
        assert!(sim[22] > 0.25, "{}", sim[22]);
        // without a delay the command drives it from the first sample
        est.structure.delay = 0.0;
        let sim = simulate(&est, &run).expect("simulates");
        assert!(sim[2] > 0.25, "{}", sim[2]);
    }
}

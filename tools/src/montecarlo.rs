//! Many independent hybrid simulations over friction uncertainty, on all cores (rayon).
//!
//! Scenario: case 1 (payload released from `alpha = pi/2 + 0.6`, trolley free, rope held)
//! with the trolley's dry friction uncertain: `Cbar_y+` and `Cbar_y-` drawn independently
//! and uniformly in `[0.7, 1.3]` N (the nominal 1 N +- 30 %), likewise `Cbar_x`. Each
//! simulation reports where the trolley ends and since when it has been stopped. With
//! `Cbar+ != Cbar-` every slip is biased towards the weaker direction, so the trolley walks
//! (ratchets) under the swinging payload: the spread of the end position is large. Draws come from
//! the host's generator ([`crane_ident::rng::Rng`]) seeded per simulation index, so results do
//! not depend on the thread count or schedule.

use crate::adaptive_run::tolerances;
use crate::cases::Case;
use crate::error::{Error, Result};
use crane_ident::rng::Rng;
use crane_model::adaptive::Adaptive;
use crane_model::{Config, Crane, FrictionLaw, Mode};
use rayon::prelude::*;
use serde::Serialize;
use std::time::Instant;

/// One simulation's outcome.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Outcome {
    /// Drawn dry friction `[Cx+, Cx-, Cy+, Cy-]` [N].
    pub friction: [f64; 4],
    /// Final trolley position [m].
    pub y_final: f64,
    /// Start of the trolley's last stopped interval, which lasts to the end [s] (None: moving
    /// at the end).
    pub rest_from: Option<f64>,
    /// Steps simulated.
    pub steps: u64,
}

/// Summary of a batch.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Summary {
    /// Simulations.
    pub sims: usize,
    /// Simulated time of each [s].
    pub duration: f64,
    /// Fixed step [s] (fixed-step runs; else 0).
    pub h: f64,
    /// Tolerance `rtol` of the adaptive integrator (adaptive runs).
    pub rtol: Option<f64>,
    /// Worker threads.
    pub threads: usize,
    /// Wall time of the batch [s].
    pub wall_s: f64,
    /// Simulations per second.
    pub sims_per_s: f64,
    /// Model steps per second (all threads).
    pub steps_per_s: f64,
    /// Mean final trolley position [m].
    pub y_final_mean: f64,
    /// Standard deviation of the final trolley position [m].
    pub y_final_std: f64,
    /// Fraction of simulations whose trolley is stopped at the end.
    pub at_rest: f64,
}

/// How each simulation is integrated.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Stepper {
    /// The fixed-step (real-time) path at this step [s].
    Fixed(f64),
    /// The adaptive integrator at this `rtol` (tolerances of [`tolerances`]).
    Adaptive(f64),
}

/// Simulation `index` of a batch with `seed`: `duration` seconds at step `h`.
pub fn simulate(seed: u64, index: u64, duration: f64, h: f64) -> Result<Outcome> {
    simulate_with(seed, index, duration, Stepper::Fixed(h))
}

/// Simulation `index` of a batch with `seed`: `duration` seconds with `stepper`.
pub fn simulate_with(seed: u64, index: u64, duration: f64, stepper: Stepper) -> Result<Outcome> {
    let case = Case::one();
    let mut rng = Rng::new(seed ^ index.wrapping_mul(0xD1B5_4A32_D192_ED03));
    let mut draw = || 0.7 + 0.6 * rng.uniform();
    let friction = [draw(), draw(), draw(), draw()];
    let mut p = case.params;
    p.x.dry_pos[0] = friction[0];
    p.x.dry_neg[0] = friction[1];
    p.y.dry_pos[0] = friction[2];
    p.y.dry_neg[0] = friction[3];
    let h = match stepper {
        Stepper::Fixed(h) => h,
        Stepper::Adaptive(_) => 1e-3,
    };
    let mut crane: Crane = Crane::new(
        &p,
        Config {
            h,
            law: FrictionLaw::Hybrid,
        },
        case.init,
    )
    .map_err(|error| Error::Setup {
        what: "Monte Carlo model",
        error,
    })?;
    if let Stepper::Adaptive(rtol) = stepper {
        let tol = tolerances(&case, rtol);
        let mut a = Adaptive::new(crane.coeffs(), tol, 0.0, crane.state(), crane.modes()).map_err(
            |error| Error::Adaptive {
                what: "Monte Carlo model (adaptive)",
                t: 0.0,
                error,
            },
        )?;
        let mut rest_from = None;
        let mut u = |_t: f64| [0.0; 3];
        while a.time() < duration {
            let t = a.time();
            let s = a.step(duration, &mut u).map_err(|error| Error::Adaptive {
                what: "Monte Carlo model (adaptive)",
                t,
                error,
            })?;
            if a.modes()[1] == Mode::Stopped {
                rest_from.get_or_insert(s.t1);
            } else {
                rest_from = None;
            }
        }
        return Ok(Outcome {
            friction,
            y_final: a.state().q[1],
            rest_from,
            steps: a.stats().accepted,
        });
    }
    let n = (duration / h).round() as u64;
    let mut rest_from = None;
    for k in 0..n {
        crane.step([0.0; 3]).map_err(|error| Error::Step {
            what: "Monte Carlo model",
            t: crane.time(),
            error,
        })?;
        if crane.modes()[1] == Mode::Stopped {
            rest_from.get_or_insert((k + 1) as f64 * h);
        } else {
            rest_from = None;
        }
    }
    Ok(Outcome {
        friction,
        y_final: crane.state().q[1],
        rest_from,
        steps: n,
    })
}

/// `sims` simulations at fixed step `h` in parallel on the current rayon pool.
pub fn run(sims: usize, duration: f64, h: f64, seed: u64) -> Result<(Summary, Vec<Outcome>)> {
    run_with(sims, duration, Stepper::Fixed(h), seed)
}

/// [`run_with_progress`] without a progress callback.
pub fn run_with(
    sims: usize,
    duration: f64,
    stepper: Stepper,
    seed: u64,
) -> Result<(Summary, Vec<Outcome>)> {
    run_with_progress(sims, duration, stepper, seed, || {})
}

/// `sims` simulations with `stepper` in parallel on the current rayon pool, calling `done`
/// after each finished simulation (from the worker threads; e.g. a progress bar's `inc(1)`).
/// The results do not depend on `done`.
pub fn run_with_progress(
    sims: usize,
    duration: f64,
    stepper: Stepper,
    seed: u64,
    done: impl Fn() + Sync,
) -> Result<(Summary, Vec<Outcome>)> {
    let t0 = Instant::now();
    let out: Result<Vec<Outcome>> = (0..sims as u64)
        .into_par_iter()
        .map(|i| {
            let r = simulate_with(seed, i, duration, stepper);
            done();
            r
        })
        .collect();
    let (h, rtol) = match stepper {
        Stepper::Fixed(h) => (h, None),
        Stepper::Adaptive(r) => (0.0, Some(r)),
    };
    let out = out?;
    let wall_s = t0.elapsed().as_secs_f64();
    let n = out.len().max(1) as f64;
    let mean = out.iter().map(|o| o.y_final).sum::<f64>() / n;
    let var = out.iter().map(|o| (o.y_final - mean).powi(2)).sum::<f64>() / n;
    let steps: u64 = out.iter().map(|o| o.steps).sum();
    Ok((
        Summary {
            sims,
            duration,
            h,
            rtol,
            threads: rayon::current_num_threads(),
            wall_s,
            sims_per_s: sims as f64 / wall_s,
            steps_per_s: steps as f64 / wall_s,
            y_final_mean: mean,
            y_final_std: var.sqrt(),
            at_rest: out.iter().filter(|o| o.rest_from.is_some()).count() as f64 / n,
        },
        out,
    ))
}

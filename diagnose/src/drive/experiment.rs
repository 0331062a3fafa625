//! The runs of one single-axis diagnosis, split into fitting and held-out runs, and the three
//! measures every structure is judged by: fitted on the fitting runs, their simulated error,
//! and the held-out runs' simulated error.
//!
//! One type so that the diagnosis of the recorded runs and of the baseline's own synthetic
//! log ([`super::floor`]) are the same pipeline, not two copies of it.

use super::estimate::{DryLevel, Estimate, Flag, Sliding, Structure};
use super::prep::{moves, Prepared, Thresholds};
use super::score::{score, simulate, RunScale, Scored};
use crate::DiagnoseError;
use crane_model::drive::Motion;
use rayon::prelude::*;

/// The sliding least-squares dry level replaces the level at first motion (see
/// [`DryLevel`]) when its simulated NMAE of the fitting runs is this many times smaller.
/// The level at first motion is the default: it is what keeps an axis at rest under forces
/// below breakaway (runs that never slip are predicted by it alone) and it is right for short
/// stick-slip motions (CICESE: slips of a few samples at 67 Hz, where the sliding rows'
/// accelerations are least reliable; there the sliding level simulates the fitting runs at
/// most 1.3 times better). From only two or three run starts its median is noisy, and on
/// long slides the sliding least squares (thousands of rows) is the better measure: on the
/// strangers' rigs of `tests/strangers.rs` it simulates the fitting runs 2 to 150 times
/// better.
pub const SLIDING_LEVEL_GAIN: f64 = 1.5;

/// Fitting and held-out runs with the thresholds derived from the fitting runs.
pub struct Experiment<'a> {
    /// The runs the models are fitted on.
    pub fit: Vec<&'a Prepared>,
    /// The runs the models are scored on (simulated from their recorded input).
    pub held: Vec<&'a Prepared>,
    /// Motion thresholds and the encoder count.
    pub th: Thresholds,
    /// Linear or rotary.
    pub motion: Motion,
    /// The restoring force's centre [m or rad].
    pub center: f64,
    /// Whether each held-out run moves (beyond the motion threshold).
    pub moving: Vec<bool>,
    /// The held-out runs the selection scores: those that move, or all when none does.
    /// Held-out runs in which the axis never leaves rest cannot tell friction models apart
    /// (every model that sticks predicts them equally).
    pub selection_runs: Vec<usize>,
    /// What scoring a simulation reads of each fitting run, computed once.
    fit_scales: Vec<RunScale>,
}

/// The baseline structure fitted by least squares, and refined by output error.
pub struct Baseline {
    /// Fitted by the least squares ([`super::estimate`]).
    pub ls: Scored,
    /// Its inertia, viscous and dry friction refined on the fitting runs' simulation
    /// ([`super::refine`]); `None` when that does not cut the held-out error, or with the
    /// inertia at its floor (not identifiable).
    pub refined: Option<Scored>,
    /// The sliding samples do not determine the inertia (it sits at its floor).
    pub inertia_unknown: bool,
}

impl Baseline {
    /// The better of the two baselines by the held-out runs that move [%].
    pub fn best_selection(&self) -> f64 {
        self.refined
            .as_ref()
            .map_or(self.ls.selection, |r| r.selection.min(self.ls.selection))
    }
}

/// Whether a model's inertia sits at its floor or is below what the log resolves (not
/// determined by the sliding samples).
pub fn at_floor(est: &Estimate) -> bool {
    est.flags.iter().any(|f| {
        matches!(
            f,
            Flag::InertiaAtFloor { .. } | Flag::InertiaUnresolved { .. }
        )
    })
}

impl<'a> Experiment<'a> {
    /// The experiment of `prepared` (each run fitted or held out by its flag).
    pub fn new(prepared: &'a [Prepared], th: Thresholds, motion: Motion, center: f64) -> Self {
        let fit: Vec<&Prepared> = prepared.iter().filter(|p| !p.run.held_out).collect();
        let held: Vec<&Prepared> = prepared.iter().filter(|p| p.run.held_out).collect();
        let moving: Vec<bool> = held.iter().map(|r| moves(&r.v, th.v_move)).collect();
        let selection_runs: Vec<usize> = if moving.iter().any(|&m| m) {
            (0..held.len()).filter(|&i| moving[i]).collect()
        } else {
            (0..held.len()).collect()
        };
        let fit_scales = fit.iter().map(|r| RunScale::new(r, th.quantum)).collect();
        Experiment {
            fit_scales,
            fit,
            held,
            th,
            motion,
            center,
            moving,
            selection_runs,
        }
    }

    /// Mean simulated position NMAE of the fitting runs [%] (infinite when one does not
    /// simulate): the measure every grid-searched value is chosen by. Infinite, without a
    /// simulation, for a model whose inertia the log does not resolve
    /// ([`Flag::InertiaUnresolved`]): no value is chosen by it, and its simulation would take
    /// thousands of steps per sample. The runs are simulated in parallel (rayon) and summed in
    /// their order: the same value as a serial loop.
    pub fn fit_error(&self, est: &Estimate) -> f64 {
        if est
            .flags
            .iter()
            .any(|f| matches!(f, Flag::InertiaUnresolved { .. }))
        {
            return f64::INFINITY;
        }
        // the runs in parallel, summed in their order below: the same bits as a serial loop
        let v: Vec<f64> = self
            .fit
            .par_iter()
            .zip(&self.fit_scales)
            .map(|(r, scale)| {
                simulate(est, r)
                    .map(|s| scale.run_nmae(&s, r))
                    .unwrap_or(f64::INFINITY)
            })
            .collect();
        v.iter().sum::<f64>() / v.len().max(1) as f64
    }

    /// A structure fitted on the fitting runs. Without stiction a structure has one dry level
    /// per direction, measured at first motion or by the sliding least squares; which one
    /// describes these data is decided by simulating the fitting runs (never the held-out
    /// ones): the level at first motion unless the sliding one simulates them
    /// [`SLIDING_LEVEL_GAIN`] times better.
    pub fn fit_only(&self, s: Structure) -> Result<Estimate, String> {
        self.fit_with_error(s).map(|(est, _)| est)
    }

    /// [`Experiment::fit_only`] with the chosen model's [`Experiment::fit_error`] when the
    /// choice simulated it (a structure without stiction), so a caller that needs it does
    /// not simulate the fitting runs again. Both levels are fitted and simulated side by
    /// side (rayon): the same values as one after the other.
    pub fn fit_with_error(&self, s: Structure) -> Result<(Estimate, Option<f64>), String> {
        let (th, motion, center) = (&self.th, self.motion, self.center);
        // the sliding least squares with every coefficient free is the same for both levels
        let first = Sliding::new(&self.fit, th, motion, center, s).map_err(|e| e.to_string())?;
        if s.stiction {
            let est = first.estimate(&self.fit, th, DryLevel::FirstMotion);
            return est.map(|e| (e, None)).map_err(|e| e.to_string());
        }
        let (est, sliding) = rayon::join(
            || first.estimate(&self.fit, th, DryLevel::FirstMotion),
            || first.estimate(&self.fit, th, DryLevel::Sliding),
        );
        let est = est.map_err(|e| e.to_string())?;
        let Ok(sliding) = sliding else {
            return Ok((est, None));
        };
        let (e_sliding, e_first) =
            rayon::join(|| self.fit_error(&sliding), || self.fit_error(&est));
        Ok(if SLIDING_LEVEL_GAIN * e_sliding < e_first {
            (sliding, Some(e_sliding))
        } else {
            (est, Some(e_first))
        })
    }

    /// A fitted model scored on the held-out runs, with its selection score (the mean over
    /// [`Experiment::selection_runs`]).
    pub fn score(&self, est: Estimate) -> Result<Scored, String> {
        let mut r = score(est, &self.held, self.th.quantum)?;
        r.selection = self.selection(&r.per_run);
        Ok(r)
    }

    /// A structure fitted on the fitting runs and scored on the held-out runs.
    pub fn fit_and_score(&self, s: Structure) -> Result<Scored, String> {
        self.score(self.fit_only(s)?)
    }

    /// The mean of per-held-out-run values over [`Experiment::selection_runs`].
    pub fn selection(&self, per_run: &[f64]) -> f64 {
        self.selection_runs.iter().map(|&i| per_run[i]).sum::<f64>()
            / self.selection_runs.len() as f64
    }

    /// The baseline structure `s` fitted, refined and scored. Too few sliding samples or a
    /// singular least squares is the data's limit (an input error naming it), a failed
    /// simulation the model's.
    ///
    /// The refinement: derivative-based least squares are biased by a coarse encoder or a
    /// long derivative window, and the model then drifts in simulation although its structure
    /// is right; the baseline's inertia, viscous and dry friction are tuned on the fitting
    /// runs' simulation ([`super::refine`]). Not refined with the inertia at its floor (the
    /// verdict says it is not identifiable), and kept only when it cuts the held-out error.
    pub fn baseline(&self, s: Structure) -> Result<Baseline, DiagnoseError> {
        let ls = self
            .score(self.fit_only(s).map_err(DiagnoseError::Input)?)
            .map_err(DiagnoseError::Model)?;
        let inertia_unknown = at_floor(&ls.est);
        let refined = (!inertia_unknown)
            .then(|| super::refine::refine(&ls.est, &|e: &Estimate| self.fit_error(e)))
            .flatten()
            .and_then(|(est, _)| self.score(est).ok())
            .filter(|r| r.selection < ls.selection);
        Ok(Baseline {
            ls,
            refined,
            inertia_unknown,
        })
    }
}

//! The runs of one single-axis diagnosis, split into fitting and held-out runs, and the three
//! measures every structure is judged by: fitted on the fitting runs, their simulated error,
//! and the held-out runs' simulated error.
//!
//! One type so that the diagnosis of the recorded runs and of the baseline's own synthetic
//! log ([`super::floor`]) are the same pipeline, not two copies of it.

use super::estimate::{unresolved_at, DryLevel, Estimate, Flag, Sliding, Structure};
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

/// Fitting samples above which a delayed model is refined on the fitting runs' heads
/// ([`Experiment::refine_delayed`]). The delay's refinement simulates the fitting runs
/// 1,000-1,500 times (its Nelder-Mead polish along the delay's valley with the inertia,
/// [`super::refine`]); on a 10 kHz log with a 60 s fitting run (600,000 samples, about
/// 0.08 s a simulation) the whole diagnosis took 98.4 s with it, against 14.5 s for the same
/// log without a delay (`diagnose/benches/diagnose.rs`), and 57.9 s with these heads. The
/// stranger plants' logs hold at most 180,000 rows in all, fitting and held-out: their
/// refinement uses every fitting sample.
pub const REFINE_SAMPLES: usize = 150_000;

/// Starts from rest the heads of [`Experiment::refine_delayed`] hold at least (each one an
/// observation of the lag between a command and the motion it starts; the heads grow until
/// they hold these, up to the whole runs). A delay is one number and the inertia another: a
/// few starts fix them on a clean log, and twenty leave the noise of each start a fifth of
/// its weight (`1 / sqrt 20`).
pub const REFINE_STARTS: usize = 20;

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
    /// ([`Flag::InertiaUnresolved`], or the same test on its parameters: a refinement scales
    /// them after the flags were set): no value is chosen by it, and its simulation would take
    /// thousands of steps per sample (stranger s032, 1 kHz: the output-error polish of a delay
    /// candidate walked the inertia from 2.2e-5 to 5e-8, a time constant of 0.002 sample
    /// periods, and each simulation took 0.8-1.3 s instead of 3 ms: 107 s for the case). The
    /// runs are simulated in parallel (rayon) and summed in their order: the same value as a
    /// serial loop.
    pub fn fit_error(&self, est: &Estimate) -> f64 {
        let p = &est.params;
        let dt = self
            .fit
            .iter()
            .map(|r| r.run.dt)
            .fold(f64::INFINITY, f64::min);
        if est
            .flags
            .iter()
            .any(|f| matches!(f, Flag::InertiaUnresolved { .. }))
            || unresolved_at(dt, p.inertia, [p.viscous_pos, p.viscous_neg]).is_some()
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

    /// [`super::refine::refine_delayed`] on the fitting runs, with its result's
    /// [`Experiment::fit_error`]. A delayed model on more than [`REFINE_SAMPLES`] fitting
    /// samples is refined on the runs' heads (each run's first samples, the same fraction of
    /// every run) that hold [`REFINE_SAMPLES`] and at least [`REFINE_STARTS`] starts from
    /// rest, and kept when it also cuts the error of the whole runs.
    pub fn refine_delayed(&self, est: &Estimate, dt: f64) -> Option<(Estimate, f64)> {
        self.refine_delayed_within(est, dt, REFINE_SAMPLES)
    }

    /// [`Experiment::refine_delayed`] with heads of `budget` samples.
    fn refine_delayed_within(
        &self,
        est: &Estimate,
        dt: f64,
        budget: usize,
    ) -> Option<(Estimate, f64)> {
        let whole = |e: &Estimate| self.fit_error(e);
        let heads = (est.structure.delay > 0.0)
            .then(|| self.heads(budget))
            .flatten();
        let Some(heads) = heads else {
            return super::refine::refine_delayed(est, &whole, dt);
        };
        let short = Experiment::new(&heads, self.th, self.motion, self.center);
        let (e, _) = super::refine::refine_delayed(est, &|e: &Estimate| short.fit_error(e), dt)?;
        let (v, start) = rayon::join(|| self.fit_error(&e), || self.fit_error(est));
        (v < start).then_some((e, v))
    }

    /// The fitting runs' heads on a long log: [`REFINE_SAMPLES`] samples in all, the same
    /// fraction of every run, holding at least [`REFINE_STARTS`] starts from rest; `None` when
    /// the fitting runs hold no more than that (or the heads would be the whole runs). The
    /// grid-searched values of [`super::trial`] are chosen on an experiment of these, as the
    /// delayed model is refined on them ([`Experiment::refine_delayed`]).
    pub fn long_heads(&self) -> Option<Vec<Prepared>> {
        self.heads(REFINE_SAMPLES)
    }

    /// The fitting runs' heads for [`Experiment::refine_delayed_within`]: the same fraction
    /// of every run, `budget` samples in all, doubled until they hold [`REFINE_STARTS`]
    /// starts from rest; `None` when the runs hold no more than `budget` samples, or the
    /// heads would be the whole runs.
    pub(super) fn heads(&self, budget: usize) -> Option<Vec<Prepared>> {
        let total: usize = self.fit.iter().map(|r| r.run.x.len()).sum();
        let mut fraction = budget as f64 / total as f64;
        while fraction < 1.0 {
            let heads: Vec<Prepared> = self
                .fit
                .iter()
                .map(|r| r.head((fraction * r.run.x.len() as f64).ceil() as usize))
                .collect();
            if heads.iter().map(Prepared::starts).sum::<usize>() >= REFINE_STARTS {
                return Some(heads);
            }
            fraction *= 2.0;
        }
        None
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

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::drive::prep::DriveRun;

    /// A run of `n` samples at 1 kHz: pulses of 5 (0.3 s) of alternating sign, each followed
    /// by 0.7 s of rest, positions simulated by `truth`.
    pub(crate) fn pulses(truth: &Estimate, n: usize) -> Prepared {
        let dt = 1e-3;
        let u: Vec<f64> = (0..n)
            .map(|k| match k % 2000 {
                0..300 => 5.0,
                1000..1300 => -5.0,
                _ => 0.0,
            })
            .collect();
        let run = |x: Vec<f64>| DriveRun {
            name: "a.csv".into(),
            held_out: false,
            dt,
            x,
            u: u.clone(),
            refresh: 1,
            input_at: (0..n).map(|k| k as f64 * dt).collect(),
            read_at: (0..n).map(|k| k as f64 * dt).collect(),
        };
        let mut rest = Prepared::with_window(run(vec![0.0; n]), 2);
        rest.set_start(1e-3);
        let x = simulate(truth, &rest).expect("simulates");
        let mut p = Prepared::with_window(run(x), 2);
        p.set_start(1e-3);
        p
    }

    /// The carriage [`pulses`] are simulated with in the delay tests: J 0.5, viscous 2, dry 1,
    /// the input 20 samples late; and the thresholds of its runs.
    pub(crate) fn delayed_carriage() -> (Estimate, Thresholds) {
        let mut truth = crate::drive::refine::tests::estimate(0.5, [2.0, 2.0], [1.0, 1.0]);
        truth.structure.delay = 20.0;
        let th = Thresholds {
            v_peak: 2.0,
            v_move: 1e-3,
            v_slide: 0.2,
            quantum: 1e-9,
        };
        (truth, th)
    }

    #[test]
    fn a_long_delayed_log_is_refined_on_its_heads_and_judged_on_the_whole() {
        let (truth, th) = delayed_carriage();
        let runs = [pulses(&truth, 48_000)];
        let ex = Experiment::new(&runs, th, Motion::Linear, 0.0);
        // 48 s of pulses: 48 starts; heads of 6,000 samples hold 6, doubled to 24,000 (24)
        assert_eq!(runs[0].starts(), 48);
        let heads = ex.heads(6_000).expect("heads");
        assert_eq!(heads[0].run.x.len(), 24_000);
        assert_eq!(heads[0].starts(), 24);
        assert_eq!(heads[0].v[..], runs[0].v[..24_000]);
        assert_eq!(heads[0].run.read_at[..], runs[0].run.read_at[..24_000]);
        // no heads when the runs are within the budget, or only the whole runs hold the starts
        assert!(ex.heads(48_000).is_none());
        assert!(ex.heads(20_000).is_some());
        let short = [pulses(&truth, 20_000)];
        assert!(Experiment::new(&short, th, Motion::Linear, 0.0)
            .heads(6_000)
            .is_none());
        // the least squares' kind of error: the inertia low, the delay long by its lag
        let mut est = truth.clone();
        est.params.inertia = 0.2;
        est.structure.delay += 0.3 / 2.0 / 1e-3;
        let (e, v) = ex
            .refine_delayed_within(&est, 1e-3, 6_000)
            .expect("refined");
        // the error returned is the whole run's, and the truth is found on the heads
        assert_eq!(v.to_bits(), ex.fit_error(&e).to_bits());
        assert!(v < ex.fit_error(&est));
        assert!(
            (e.structure.delay - 20.0).abs() < 1.0,
            "{}",
            e.structure.delay
        );
        assert!(
            (e.params.inertia / 0.5 - 1.0).abs() < 0.05,
            "{}",
            e.params.inertia
        );
        // without a delay the whole runs are refined (the plain refinement)
        let mut plain = est.clone();
        plain.structure.delay = 0.0;
        let fit_error = |e: &Estimate| ex.fit_error(e);
        assert_eq!(
            ex.refine_delayed_within(&plain, 1e-3, 6_000)
                .map(|(e, v)| (e.params, v.to_bits())),
            super::super::refine::refine_delayed(&plain, &fit_error, 1e-3)
                .map(|(e, v)| (e.params, v.to_bits()))
        );
    }

    #[test]
    fn a_model_scaled_below_the_logs_inertia_resolution_is_not_simulated() {
        let (truth, th) = delayed_carriage();
        let runs = [pulses(&truth, 4_000)];
        let ex = Experiment::new(&runs, th, Motion::Linear, 0.0);
        assert!(ex.fit_error(&truth).is_finite());
        // J / D 2.5 ms at 1 ms samples, then scaled to just above and below a tenth of a
        // sample (`UNRESOLVED_TAU`) with no flag set, as a refinement scales it
        let mut e = truth.clone();
        e.params.inertia = 2.0 * 0.11e-3;
        assert!(ex.fit_error(&e).is_finite());
        e.params.inertia = 2.0 * 0.09e-3;
        assert!(e.flags.is_empty());
        assert_eq!(ex.fit_error(&e), f64::INFINITY);
    }
}

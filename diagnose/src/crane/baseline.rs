//! The baseline model: which one the options ask for, its re-fit by inverse dynamics
//! (`--fit-baseline`), its errors (the reference every candidate is scored against), and why
//! it does not score when it does not.

use super::asymmetry::asym_cols;
use super::gather::{gather, gather_series, sumsq, Gathered};
use super::nmae::Ctx;
use super::residual::{axis_params, drive_series, Prep};
use super::simulate::simulate_checked;
use super::{Ext, AXIS_NAMES, CUTOFF_HZ};
use crate::fit::ls;
use crate::{AxisError, Baseline, DiagnoseError, DiagnoseOptions};
use crane_ident::signal::butter;
use crane_model::{Extensions, Params};

/// The baseline the options ask for, before any re-fit.
pub(super) struct BaselineChoice {
    /// Parameters (the payload mass is replaced by each run's declared one).
    pub(super) params: Params,
    /// Whether the dry magnitudes and viscous coefficients are re-fitted ([`fit_baseline`]).
    pub(super) fitted: bool,
    /// What the baseline is, for the report.
    pub(super) doc: String,
}

impl BaselineChoice {
    /// The baseline of `opts`; an input error for the single-axis symmetric baseline.
    pub(super) fn from_options(opts: &DiagnoseOptions) -> Result<BaselineChoice, DiagnoseError> {
        let (params, fitted, doc) = match &opts.baseline {
            Baseline::Auto => (
                Params::default(),
                false,
                "built-in defaults (shared/MODEL.md) with each run's declared payload".to_string(),
            ),
            Baseline::Params(p) => (*p, false, "the given parameters".to_string()),
            Baseline::Fit(p) => (
                p.unwrap_or_default(),
                true,
                "dry magnitudes and viscous coefficients per drive and direction re-fitted by inverse dynamics on the fitting part".to_string(),
            ),
            Baseline::Symmetric => {
                return Err(DiagnoseError::Input(
                    "the symmetric baseline is for single-axis data".into(),
                ))
            }
        };
        Ok(BaselineChoice {
            params,
            fitted,
            doc,
        })
    }
}

/// Refits the dry magnitudes and viscous coefficients of every drive on the fitting part
/// (`--fit-baseline`), by inverse dynamics on top of `params`.
pub(super) fn fit_baseline(preps: &[Prep], params: &mut Params) {
    for i in 0..3 {
        let g = gather(preps, i, false);
        if g.r.len() < 20 {
            continue;
        }
        let cols = asym_cols(&g);
        let refs: Vec<&[f64]> = cols.iter().map(|c| c.as_slice()).collect();
        if let Some(th) = ls(&refs, &g.r) {
            let mut ext = Extensions::default();
            Ext::Asymmetry {
                dry_pos: th[0],
                dry_neg: th[1],
                viscous_pos: th[2],
                viscous_neg: th[3],
            }
            .apply(i, params, &mut ext);
        }
    }
}

/// The baseline's errors, and the force residuals every candidate is fitted and scored on.
/// Axes are indexed 0 X, 1 Y, 2 rope.
pub(super) struct BaselineScore {
    /// Held-out simulated NMAE per axis [%].
    pub(super) before_h: [f64; 3],
    /// Fitting-part simulated NMAE per axis [%] (NaN when no run has a fitting part or a
    /// simulation fails).
    pub(super) before_f: [f64; 3],
    /// Kept samples of each drive on the fitting part.
    pub(super) fit_g: Vec<Gathered>,
    /// Kept samples of each drive on the held-out part.
    pub(super) held_g: Vec<Gathered>,
    /// Held-out sum of squared force residuals per drive [N^2].
    pub(super) sse_b: [f64; 3],
    /// The report's baseline errors per axis.
    pub(super) errors: Vec<AxisError>,
}

/// Scores the baseline of the prepared runs `ctx`: simulated NMAE on both parts and force residuals; an error
/// naming the first run it does not simulate ([`baseline_failure`]) when the held-out part
/// cannot be scored.
/// `names`: the runs' names in the order of `ctx.preps`; `base_doc`: what the baseline is;
/// `noise`: the encoder quantisation NMAE per axis [%]. (The stage's inputs, not the
/// `runs::Setup` holding them: `runs` calls this module's re-fit.)
pub(super) fn score(
    ctx: &Ctx,
    names: &[&str],
    base_doc: &str,
    noise: [f64; 3],
) -> Result<BaselineScore, DiagnoseError> {
    let before_h = ctx
        .nmae(None, true)
        .ok_or_else(|| baseline_failure(&ctx.preps, names, base_doc))?;
    let before_f = ctx.nmae(None, false).unwrap_or([f64::NAN; 3]);
    let fit_g: Vec<Gathered> = (0..3).map(|i| gather(&ctx.preps, i, false)).collect();
    let held_g: Vec<Gathered> = (0..3).map(|i| gather(&ctx.preps, i, true)).collect();
    let sse_b: [f64; 3] = std::array::from_fn(|i| sumsq(&held_g[i].r));
    let mut baseline_errors = Vec::new();
    for i in 0..3 {
        let f_all: Vec<f64> = gather_series(&ctx.preps, i, true, &|p: &Prep| {
            let f = butter(4, CUTOFF_HZ * 2.0 * p.run.dt());
            let g = axis_params(&p.params, i).gain;
            drive_series(&f, &p.run.u[i])
                .iter()
                .map(|u| g * u)
                .collect()
        });
        let n_h = held_g[i].r.len().max(1) as f64;
        let n_f = fit_g[i].r.len().max(1) as f64;
        baseline_errors.push(AxisError {
            axis: AXIS_NAMES[i].into(),
            nmae_fit: before_f[i],
            nmae_held_out: before_h[i],
            nmae_noise: noise[i],
            nmae_own_log: None,
            force_rms_fit_n: (sumsq(&fit_g[i].r) / n_f).sqrt(),
            force_rms_held_out_n: (sse_b[i] / n_h).sqrt(),
            force_rel_err_held_out_pct: 100.0 * (sse_b[i] / sumsq(&f_all).max(1e-300)).sqrt(),
        });
    }
    Ok(BaselineScore {
        before_h,
        before_f,
        fit_g,
        held_g,
        sse_b,
        errors: baseline_errors,
    })
}

/// Why the baseline does not score: the first run it does not simulate, with the model's
/// reason, or no held-out sample at all. `doc` says which baseline it is.
fn baseline_failure(preps: &[Prep], names: &[&str], doc: &str) -> DiagnoseError {
    for (p, name) in preps.iter().zip(names) {
        // a run that starts outside the travel: said in the data set's and the file's terms
        let (q, k) = (&p.params, [("x", "x"), ("y", "y"), ("l", "rope")]);
        let travel = [&q.x, &q.y, &q.rope];
        let first = [p.run.x.first(), p.run.y.first(), p.run.l.first()];
        for ((col, key), (a, v)) in k.iter().zip(travel.iter().zip(first)) {
            if let Some(&v) = v.filter(|&&v| !(v >= a.min && v <= a.max)) {
                return DiagnoseError::Model(format!(
                    "the baseline ({doc}) does not simulate run {name}: its first `{col}` = {v:.4} m is outside the travel [{key}.min, {key}.max] = [{}, {}]",
                    a.min, a.max
                ));
            }
        }
        if let Err(e) = simulate_checked(p.run, &p.params, &Extensions::default()) {
            return DiagnoseError::Model(format!(
                "the baseline ({doc}) does not simulate run {name}: {e}"
            ));
        }
    }
    DiagnoseError::Model(format!(
        "the baseline ({doc}) leaves no held-out sample to score"
    ))
}

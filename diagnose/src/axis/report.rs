//! Stage 6: the report. The relative force errors of the baseline and of the best-ranked
//! candidate, the EMPS benchmark's published figures next to the closed-loop ones, the
//! verdict, and the baseline's errors.

use super::baseline::BaselineFit;
use super::prepare::Prepared;
use super::score::Scored;
use super::select::Selection;
use crate::{AxisError, Finding, Report, Verdict};
use crane_ident::data::Dataset;
use std::collections::BTreeMap;

/// The relative force errors `100 ||F - F_model|| / ||F||` [%] on the fitting and the
/// held-out rows: the baseline's (`force_rel_err_{fit,held_out}_pct`) and, with any
/// candidate scored, the best-ranked one's (`force_rel_err_{fit,held_out}_after_pct`, whether
/// supported or not).
pub(super) fn force_error_measures(
    base: &BaselineFit,
    scored: &[Scored],
    measures: &mut BTreeMap<String, f64>,
) {
    let (sse0, ssef0) = (base.fitted.sse_h, base.fitted.sse_f);
    let (fnorm_f, fnorm_h) = (base.fnorm_f, base.fnorm_h);
    measures.insert(
        "force_rel_err_fit_pct".into(),
        100.0 * (ssef0 / fnorm_f).sqrt(),
    );
    measures.insert(
        "force_rel_err_held_out_pct".into(),
        100.0 * (sse0 / fnorm_h).sqrt(),
    );
    if let Some(f) = scored.first() {
        measures.insert(
            "force_rel_err_fit_after_pct".into(),
            100.0 * (f.cand.sse_f / fnorm_f).sqrt(),
        );
        measures.insert(
            "force_rel_err_held_out_after_pct".into(),
            100.0 * (f.cand.sse_h / fnorm_h).sqrt(),
        );
    }
}

/// The EMPS benchmark's published figures [%], next to ours (only for the EMPS runs).
pub(super) fn published_measures(measures: &mut BTreeMap<String, f64>) {
    measures.insert("published_symmetric_cross_test_pct".into(), 5.98);
    measures.insert("published_direction_dependent_fit_pct".into(), 3.11);
    measures.insert("published_sim_force_err_estimation_pct".into(), 5.85);
    measures.insert("published_sim_force_err_validation_pct".into(), 8.94);
}

/// Stage 6: the verdict and the report, from the prepared data, the baseline and the
/// selection (its measures complete).
pub(super) fn report(ds: &Dataset, prep: Prepared, base: &BaselineFit, sel: Selection) -> Report {
    let (verdict, reason) = verdict(&sel.findings, &sel.measures, base);
    let (sse0, mae0, ssef0) = (base.fitted.sse_h, base.fitted.mae_h, base.fitted.sse_f);
    let n_h = prep.held.f.len();
    let baseline_errors = vec![AxisError {
        axis: "axis".into(),
        nmae_fit: base.nmae_fit(&prep),
        nmae_held_out: 100.0 * mae0 / base.hrange,
        nmae_noise: 0.0,
        nmae_own_log: None,
        force_rms_fit_n: (ssef0 / prep.fit.f.len() as f64).sqrt(),
        force_rms_held_out_n: (sse0 / n_h as f64).sqrt(),
        force_rel_err_held_out_pct: 100.0 * (sse0 / base.fnorm_h).sqrt(),
    }];
    Report {
        dataset: ds.dir.display().to_string(),
        data: "single_axis".into(),
        baseline: prep.base_doc,
        split: prep.split_doc,
        baseline_errors,
        findings: sel.findings,
        verdict,
        verdict_reason: reason,
        candidates: sel.candidates,
        measures: sel.measures,
        heldout_simulation: None,
        final_model: None,
    }
}

/// The verdict and its reason: the first finding; else `unexplained` when the baseline does
/// not fit (its worst held-out force error [%], by the inverse model or in a declared closed
/// loop, at or above 100: what predicting zero force scores); else `none`.
fn verdict(
    findings: &[Finding],
    measures: &BTreeMap<String, f64>,
    base: &BaselineFit,
) -> (Verdict, String) {
    let (sse0, fnorm_h) = (base.fitted.sse_h, base.fnorm_h);
    // the baseline's worst held-out force error [%] over the inverse model and, where a
    // controller is declared, the closed-loop simulations
    let no_fit_pct = measures
        .iter()
        .filter(|(k, _)| k.starts_with("closed_loop_force_err_held_out_"))
        .map(|(_, v)| *v)
        .fold(100.0 * (sse0 / fnorm_h).sqrt(), f64::max);
    match findings.first() {
        Some(f) => (
            Verdict::Found(f.cause),
            format!(
                "{} cuts the held-out force NMAE from {:.3} % to {:.3} %",
                f.cause, f.nmae_before, f.nmae_after
            ),
        ),
        // `none` only when the baseline fits: a held-out force error at or above the
        // force itself (what predicting zero force scores), by the inverse model or in the
        // declared closed loop, is no fit at all (a wrong gain or unit); with nothing found
        // that is unexplained
        None if no_fit_pct >= 100.0 => (
            Verdict::Unexplained,
            format!(
                "the baseline does not fit: its held-out force error is {no_fit_pct:.0} % of \
                 the force (predicting zero force scores 100 %); check the gain and the \
                 units; no candidate explains it"
            ),
        ),
        None => (
            Verdict::None,
            "no candidate improves the held-out force residual beyond the penalty".into(),
        ),
    }
}

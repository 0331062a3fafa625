//! The single-axis diagnosis, stage by stage: prepare the runs ([`super::prep`]) and check
//! them ([`super::checks`]) → fit the baseline ([`super::experiment`]) and measure its floors
//! ([`super::floor`]) → forward selection of the causes ([`super::select`], each tried by
//! [`super::trial`]) → final model and verdict ([`super::verdict`]) → report
//! ([`super::report`]).

use super::checks::{never_moves, reversed_sign};
use super::estimate::Structure;
use super::experiment::Experiment;
use super::info::DriveInfo;
use super::prep::{DriveRun, Prepared, Thresholds};
use super::report::Heading;
use super::select::Context;
use super::trial::Search;
use crate::{DiagnoseError, DiagnoseOptions, Report};

/// Diagnoses single-axis runs (open loop: the recorded input drives the model).
pub fn diagnose_drive(
    dataset: &str,
    runs: Vec<DriveRun>,
    split: String,
    info: &DriveInfo,
    opts: &DiagnoseOptions,
) -> Result<Report, DiagnoseError> {
    let (prepared, th, window) = prepare(runs)?;
    // The restoring force's centre: the mean rest position the runs start from (a rig is
    // homed at its equilibrium; the centre is not separable from a force offset otherwise).
    let center =
        prepared.iter().filter_map(|p| p.run.x.first()).sum::<f64>() / prepared.len() as f64;
    let ex = Experiment::new(&prepared, th, info.motion, center);
    reversed_sign(&ex.fit, &th, info.motion, center)?;

    // The baseline: fitted by least squares and refined by output error. A model whose
    // inertia the sliding samples do not determine (too short a run, too few slides, or a
    // missing position force) cannot carry a cause: the extension would only trade against
    // its guesses; a cause is named only with the inertia determined. A first cause must cut
    // the held-out error both ways, least squares against least squares and refined against
    // refined (else it stands in for the least squares' bias: a 1 mm encoder count named a
    // saturation). Above NONE_LEVEL, with no cause named, the refined baseline is the final
    // model, and `none` within NONE_LEVEL. The least-squares baseline stays the one the
    // candidates extend.
    let base_s = Structure {
        restoring: false,
        stiction: false,
        asymmetric: !info.symmetric,
        offset: false,
        deadband: 0.0,
        delay: 0.0,
        saturation: 0.0,
        load: 0.0,
        bump: None,
        stribeck: 0.0,
    };
    let base = ex.baseline(base_s)?;
    let own_floor = super::floor::own_log(
        &prepared,
        base.refined.as_ref().map_or(&base.ls.est, |r| &r.est),
        &th,
        info.motion,
        center,
        base_s,
    );
    let ctx = Context::new(&ex, info, &base, own_floor, &prepared);

    let fit = &ex.fit;
    let sat_grid = super::trial::saturation_grid(fit, &th, ctx.umax);
    let shortest = fit.iter().map(|p| p.run.x.len()).min().unwrap_or(0);
    let heads = ex.long_heads();
    let short = heads
        .as_ref()
        .map(|h| Experiment::new(h, th, info.motion, center));
    let search = Search {
        ex: &ex,
        heads: short.as_ref(),
        umax: ctx.umax,
        sat_grid: &sat_grid,
        stribeck_grid: &super::trial::stribeck_grid(fit, &th),
        delay_grid: &super::grid::delay_grid(ctx.dt, shortest),
        dt: ctx.dt,
        bump_guess: &|e| super::local::guess(e, fit, &th, info.motion).map(|g| g.0),
    };
    let sel = super::select::forward(&ctx, &search);
    let fin = super::verdict::final_model(&ctx, &sel);
    let verdict = super::verdict::verdict(&ctx, &sel, &fin);
    let head = Heading {
        dataset,
        split,
        window,
        opts,
    };
    super::report::report(head, &ctx, sel, fin, verdict)
}

/// The runs prepared with one derivative window (half width [samples], returned), checked
/// to hold fitting and held-out runs, with the motion thresholds of the fitting runs; a run
/// logged from mid-motion is simulated from its first velocity.
fn prepare(runs: Vec<DriveRun>) -> Result<(Vec<Prepared>, Thresholds, usize), DiagnoseError> {
    let w = super::prep::window(&runs);
    let mut prepared: Vec<Prepared> = runs
        .into_iter()
        .map(|r| Prepared::with_window(r, w))
        .collect();
    if !prepared.iter().any(|p| !p.run.held_out) || !prepared.iter().any(|p| p.run.held_out) {
        return Err(DiagnoseError::Input(
            "single-axis diagnosis needs at least one fitting and one held-out run".into(),
        ));
    }
    let th = Thresholds::from_runs(
        &prepared
            .iter()
            .filter(|p| !p.run.held_out)
            .collect::<Vec<_>>(),
    )
    .ok_or_else(|| never_moves(&prepared))?;
    for p in &mut prepared {
        p.set_start(th.v_move);
    }
    Ok((prepared, th, w))
}

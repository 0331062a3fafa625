//! Stage 6: the report of a single-axis diagnosis: the baseline's errors, the held-out
//! simulation before and after, the findings and candidates, the final model with its flags,
//! and the plots.

use super::estimate::{Dir, DryLevel, Estimate, Flag};
use super::evidence::{force_rel, force_rms};
use super::info::DriveInfo;
use super::physical::{center_of, stiffness};
use super::score::{run_nmae, simulate};
use super::select::{Context, Selection};
use super::verdict::Final;
use crate::{
    AxisError, Cause, DiagnoseError, DiagnoseOptions, FinalModel, HeldoutSimulation, Report,
    RunSimulation, Verdict,
};
use std::collections::BTreeMap;

/// Where the report goes and what it says about the data set.
pub(super) struct Heading<'a> {
    /// The data set's name (its folder).
    pub dataset: &'a str,
    /// How the runs were split into fitting and held-out runs.
    pub split: String,
    /// The derivative window's half width [samples].
    pub window: usize,
    /// The caller's options (plots).
    pub opts: &'a DiagnoseOptions,
}

/// The report of a diagnosis whose selection gave `sel`, final model `fin` and `verdict`.
pub(super) fn report(
    head: Heading<'_>,
    ctx: &Context<'_>,
    sel: Selection,
    fin: Final,
    verdict: (Verdict, String),
) -> Result<Report, DiagnoseError> {
    let (fit, held, th, info) = (&ctx.ex.fit, &ctx.ex.held, &ctx.ex.th, ctx.info);
    let (baseline, final_) = (&ctx.base.ls, &fin.scored);
    let fit_nmae = |est: &Estimate| -> f64 {
        let v: Vec<f64> = fit
            .iter()
            .filter_map(|r| simulate(est, r).ok().map(|s| run_nmae(&s, r, th.quantum)))
            .collect();
        if v.is_empty() {
            f64::INFINITY
        } else {
            v.iter().sum::<f64>() / v.len() as f64
        }
    };
    let baseline_errors = vec![AxisError {
        axis: "axis".into(),
        nmae_fit: finite_or_zero(fit_nmae(&baseline.est)),
        nmae_held_out: baseline.nmae,
        nmae_noise: ctx.noise_floor,
        nmae_own_log: ctx.own_floor,
        force_rms_fit_n: force_rms(&baseline.est, fit, th),
        force_rms_held_out_n: force_rms(&baseline.est, held, th),
        force_rel_err_held_out_pct: force_rel(&baseline.est, held, th),
    }];
    let flags = flags(ctx, &head, &fin, sel.notes);
    let final_model = final_model(&final_.est, info, &flags, ctx.dt);
    if let Some(dir) = &head.opts.plots_dir {
        super::plots::write_all(dir, held, baseline, final_, th, info)
            .map_err(|e| DiagnoseError::Io(e.to_string()))?;
    }
    Ok(Report {
        dataset: head.dataset.into(),
        data: "single_axis".into(),
        baseline: format!(
            "{} Coulomb + viscous friction fitted on the fitting runs (sliding least squares, breakaway at first motion), no position force; simulated from the recorded input",
            if info.symmetric { "symmetric" } else { "direction-dependent" }
        ),
        split: head.split,
        baseline_errors,
        findings: sel.findings,
        verdict: verdict.0,
        verdict_reason: verdict.1,
        candidates: sel.candidates,
        measures: BTreeMap::new(),
        heldout_simulation: Some(heldout_simulation(ctx, final_)),
        final_model: Some(final_model),
    })
}

/// The held-out runs simulated by the baseline and the final model, against no motion.
fn heldout_simulation(ctx: &Context<'_>, final_: &super::score::Scored) -> HeldoutSimulation {
    let (baseline, held, moving) = (&ctx.base.ls, &ctx.ex.held, &ctx.ex.moving);
    let no_motion = &ctx.no_motion;
    HeldoutSimulation {
        nmae_before: baseline.nmae,
        nmae_after: final_.nmae,
        nmae_no_motion: no_motion.iter().sum::<f64>() / no_motion.len() as f64,
        moving_nmae_before: baseline.selection,
        moving_nmae_after: final_.selection,
        moving_nmae_no_motion: ctx.sel_no_motion,
        runs: held
            .iter()
            .enumerate()
            .map(|(i, r)| RunSimulation {
                file: r.run.name.clone(),
                nmae_before: baseline.per_run[i],
                nmae_after: final_.per_run[i],
                nmae_no_motion: no_motion[i],
                moves: moving[i],
                diverged_before: !baseline.per_run[i].is_finite(),
                diverged_after: !final_.per_run[i].is_finite(),
            })
            .collect(),
    }
}

/// The final model's flags: what the loader did, the refinement, the floors, the derivative
/// window, the estimate's own flags, the dry level used, and why causes were not named.
fn flags(
    ctx: &Context<'_>,
    head: &Heading<'_>,
    fin: &Final,
    notes: BTreeMap<Cause, String>,
) -> Vec<String> {
    let (fit, final_) = (&ctx.ex.fit, &fin.scored);
    let w = head.window;
    let mut flags: Vec<String> = ctx.info.load_notes.clone();
    flags.extend(fin.note.clone());
    if let Some(f) = ctx.own_floor {
        flags.push(format!("own-log floor: the baseline's own simulation, logged as these data, leaves {f:.4} % held out (the baseline: {:.4} %)", ctx.base_best()));
    }
    if let Some(f) = ctx.own_floor_failed {
        flags.push(format!("own-log floor not used: the baseline's own simulation, logged as these data and fitted again, leaves {f:.4} % held out, more than {:.0} % of what predicting no motion leaves ({:.4} %): there the fit fails (as it does with an effect the baseline lacks: a long delay, a spring), so that error says nothing of what the log resolves, and causes are tried", 100.0 * super::floor::MAX_SHARE_OF_REST, ctx.sel_no_motion));
    }
    flags.push(format!(
        "velocity and acceleration from local quadratic fits over {} samples ({:.4} s): the shortest window whose acceleration noise is below {:.0} % of the motion's",
        2 * w + 1,
        (2 * w + 1) as f64 * fit.iter().map(|p| p.run.dt).fold(f64::INFINITY, f64::min),
        100.0 * super::prep::ACCEL_NOISE_FRACTION
    ));
    flags.extend(final_.est.flags.iter().map(Flag::to_string));
    // (with no first motion in either direction both levels are the sliding one, and the
    // flags say so above)
    let no_onsets = Dir::BOTH
        .iter()
        .all(|&dir| final_.est.flags.contains(&Flag::NoFirstMotion { dir }));
    if !final_.est.structure.stiction && !no_onsets {
        flags.push(match final_.est.level {
            DryLevel::FirstMotion => "dry friction level measured where the axis leaves rest at the start of each fitting run (it simulates the fitting runs better than the sliding least squares)".to_string(),
            DryLevel::Sliding => "dry friction level from the sliding least squares (it simulates the fitting runs better than the level at first motion)".to_string(),
        });
    }
    flags.extend(notes.into_values());
    flags
}

/// `x`, or 0 where it is not finite (a diverged simulation in a field that must be a number).
fn finite_or_zero(x: f64) -> f64 {
    if x.is_finite() {
        x
    } else {
        0.0
    }
}

/// The final model of the report, in the data set's units; `dt` the sample period [s].
fn final_model(est: &Estimate, info: &DriveInfo, flags: &[String], dt: f64) -> FinalModel {
    let p = &est.params;
    FinalModel {
        position_unit: info.position_unit.clone(),
        force_unit: info.force_unit.clone(),
        inertia: p.inertia,
        breakaway_pos: p.breakaway_pos,
        breakaway_neg: p.breakaway_neg,
        kinetic_pos: p.kinetic_pos,
        kinetic_neg: p.kinetic_neg,
        viscous_pos: p.viscous_pos,
        viscous_neg: p.viscous_neg,
        stiffness: stiffness(&p.position_force),
        center: center_of(&p.position_force),
        offset: p.offset,
        deadband: est.structure.deadband,
        delay_samples: est.structure.delay,
        delay_s: est.structure.delay * dt,
        load_friction: p.load_friction,
        stribeck_velocity: p.stribeck_velocity,
        bump: match p.local_friction {
            crane_model::drive::LocalFriction::Bump {
                center,
                half_width,
                amplitude,
            } => Some([center, half_width, amplitude]),
            crane_model::drive::LocalFriction::None => None,
        },
        saturation: (est.structure.saturation > 0.0).then_some(est.structure.saturation),
        breakaway_scatter_pos: est.breakaway_scatter[0].unwrap_or(0.0),
        breakaway_scatter_neg: est.breakaway_scatter[1].unwrap_or(0.0),
        first_motion_pos: est.first_motion[0].clone(),
        first_motion_neg: est.first_motion[1].clone(),
        flags: flags.to_vec(),
    }
}

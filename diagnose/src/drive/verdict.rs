//! Stage 5: the final model and the verdict. With a cause named the verdict is that cause;
//! without one, `none` only when the baseline is within [`NONE_LEVEL`] and within
//! [`OWN_LOG_FACTOR`] times its own-log floor, and `unexplained` (with why) otherwise; a data
//! set whose held-out runs never move is `untested`.

use super::checks::moving_names;
use super::experiment::at_floor;
use super::score::Scored;
use super::select::{Context, Selection, MIN_FIT_MOTIONS, MIN_GAIN, NONE_LEVEL, OWN_LOG_FACTOR};
use crate::report::nmae_or_diverged::text as pct;
use crate::Verdict;

/// The model the report gives, and how it was reached.
pub(super) struct Final {
    /// The model: the current one of the selection, or the refined baseline.
    pub scored: Scored,
    /// No cause named, and the baseline refined by output error is the final model.
    pub refined: bool,
    /// What the refinement changed, when it is the final model.
    pub note: Option<String>,
}

/// The final model: with no cause named, the baseline refined by output error (it simulates
/// the fitting runs better by construction) when the least-squares one is beyond
/// [`NONE_LEVEL`]; otherwise the selection's current model.
pub(super) fn final_model(ctx: &Context<'_>, sel: &Selection) -> Final {
    let baseline = &ctx.base.ls;
    let refined = sel.findings.is_empty()
        && ctx.unseen.is_none()
        && !ctx.too_thin
        && ctx.base.refined.is_some()
        && baseline.selection > NONE_LEVEL;
    let scored = match &ctx.base.refined {
        Some(r) if refined => r.clone(),
        _ => sel.current.clone(),
    };
    let note = refined.then(|| {
        let (p0, p1) = (&baseline.est.params, &scored.est.params);
        format!(
            "baseline inertia, viscous and dry friction refined by output error on the fitting runs (their simulated NMAE {} -> {}): inertia {:.4} -> {:.4}, viscous {:.4} / {:.4} -> {:.4} / {:.4}, kinetic {:.4} / {:.4} -> {:.4} / {:.4}",
            pct(ctx.ex.fit_error(&baseline.est), 2),
            pct(ctx.ex.fit_error(&scored.est), 2),
            p0.inertia,
            p1.inertia,
            p0.viscous_pos,
            p0.viscous_neg,
            p1.viscous_pos,
            p1.viscous_neg,
            p0.kinetic_pos,
            p0.kinetic_neg,
            p1.kinetic_pos,
            p1.kinetic_neg
        )
    });
    Final {
        scored,
        refined,
        note,
    }
}

/// The verdict and its reason.
pub(super) fn verdict(ctx: &Context<'_>, sel: &Selection, fin: &Final) -> (Verdict, String) {
    let (verdict, mut reason) = decide(ctx, sel, fin);
    if verdict == Verdict::None {
        reason.push_str(&absorbed(ctx));
    }
    if ctx.ex.moving.iter().any(|&m| m) {
        return (verdict, reason);
    }
    // every model that sticks predicts a resting run: such a score says nothing of the
    // motion (resting runs held out beside moving fitted runs were `none` at 0.00 %)
    let what = format!(
        "no held-out run moves (runs {}): they test only that the axis stays at rest, not the motion; declare moving runs as held out (`kind = \"validation\"` in `dataset.toml`) to test it",
        ctx.ex.held.iter().map(|p| p.run.name.as_str()).collect::<Vec<_>>().join(", ")
    );
    if matches!(verdict, Verdict::Found(_)) {
        (verdict, format!("{reason}; {what}"))
    } else {
        (Verdict::Untested, what)
    }
}

/// What a `none` cannot rule out: while the drive pushes the motion, a dead band acts exactly
/// as a higher dry level (`g (u - d sign u)` equals `g u` less `g d sign v`) and load-dependent
/// friction as a lower gain (`F - mu |F|` is `(1 - mu) F`), which the baseline's levels and
/// inertia take up. Only sliding samples whose input opposes the motion (the drive braking)
/// tell them apart; their share of the fitting runs' sliding samples says how well the data
/// could.
fn absorbed(ctx: &Context<'_>) -> String {
    let (mut sliding, mut braking) = (0usize, 0usize);
    for p in &ctx.ex.fit {
        for (u, v) in p.run.u.iter().zip(&p.v) {
            if v.abs() > ctx.ex.th.v_slide {
                sliding += 1;
                braking += usize::from(u * v < 0.0);
            }
        }
    }
    if sliding == 0 {
        return String::new();
    }
    format!(
        "; the drive brakes (its input against the motion) on {:.1} % of the fitting runs' sliding samples, the only samples on which a dead band or a load-dependent friction differs from a higher dry level or a lower gain, which the baseline carries: on data that brake little, those two cannot be told apart from them",
        100.0 * braking as f64 / sliding as f64
    )
}

/// The verdict from the findings and the levels, before the check that the held-out runs
/// move.
fn decide(ctx: &Context<'_>, sel: &Selection, fin: &Final) -> (Verdict, String) {
    let (baseline, final_) = (&ctx.base.ls, &fin.scored);
    let sel_no_motion = ctx.sel_no_motion;
    let base_best = ctx.base_best();
    let refined_none = fin.refined && final_.selection <= NONE_LEVEL;
    if let Some(f) = sel.findings.first() {
        let mut r = format!(
            "{} cuts the held-out simulated position NMAE from {} to {} (all findings: {} -> {}; predicting no motion: {:.2} %)",
            f.cause,
            pct(f.nmae_before, 2),
            pct(f.nmae_after, 2),
            pct(baseline.selection, 2),
            pct(final_.selection, 2),
            sel_no_motion
        );
        if final_.selection > NONE_LEVEL {
            r.push_str(&format!(
                "; the rest ({}) is not explained by any candidate",
                pct(final_.selection, 2)
            ));
        }
        (Verdict::Found(f.cause), r)
    } else if let Some(dir) = ctx.unseen.filter(|_| !ctx.too_thin) {
        (
            Verdict::Unexplained,
            format!(
                "not identifiable: the held-out runs move {dir} (runs {}), which no fitting run does; a model fitted on one direction cannot predict the other (a load such as gravity, or friction that depends on the direction, makes them differ), so no cause is named; the baseline's held-out simulated position NMAE is {} (predicting no motion: {:.2} %); hold out runs so that the fitting runs move in both directions (`kind = \"validation\"` on the held-out runs in `dataset.toml`)",
                moving_names(&ctx.ex.held, &ctx.ex.th, dir.sign()),
                pct(baseline.selection, 2),
                sel_no_motion
            ),
        )
    } else if ctx.too_thin {
        (
            Verdict::Unexplained,
            format!(
                "not identifiable: the fitting data hold {} motion(s), fewer than {MIN_FIT_MOTIONS}: inertia, friction and any input effect trade against each other on one slide, so no cause is named; the baseline's held-out simulated position NMAE is {} (predicting no motion: {:.2} %)",
                ctx.fit_motions, pct(baseline.selection, 2), sel_no_motion
            ),
        )
    } else if ctx.base.inertia_unknown && at_floor(&final_.est) {
        (
            Verdict::Unexplained,
            format!(
                "not identifiable: the fitting runs do not determine the inertia (it sits at its floor, or its time constant is below what the log resolves), so no cause is named; the baseline's held-out simulated position NMAE is {} (predicting no motion: {:.2} %); longer runs with several accelerations in each direction are needed",
                pct(baseline.selection, 2), sel_no_motion
            ),
        )
    } else if refined_none && ctx.consistent(final_.selection) {
        (
            Verdict::None,
            format!(
                "the baseline refined by output error on the fitting runs simulates the held-out runs at {:.2} % (<= {NONE_LEVEL} %; with its least-squares parameters {}), and no candidate cuts that by {:.0} % with physical parameters",
                final_.selection,
                pct(baseline.selection, 2),
                100.0 * MIN_GAIN
            ),
        )
    } else if baseline.selection <= NONE_LEVEL && ctx.consistent(base_best) {
        (
            Verdict::None,
            format!(
                "the baseline's held-out simulated position NMAE is {:.2} % (<= {NONE_LEVEL} %){}",
                baseline.selection,
                ctx.own_floor.map_or(String::new(), |f| format!(
                    "; on its own replayed log it leaves {f:.4} %"
                ))
            ),
        )
    } else if final_.selection <= NONE_LEVEL {
        let f = ctx
            .own_floor
            .unwrap_or(ctx.noise_floor)
            .max(ctx.noise_floor);
        (
            Verdict::Unexplained,
            format!(
                "the baseline's held-out simulated position NMAE is {} (<= {NONE_LEVEL} %; {} with its parameters refined by output error), but {:.0} times what it leaves on its own replayed log ({f:.4} %: its simulation logged as these data were, and fitted again; more than {OWN_LOG_FACTOR} times is beyond that floor's scatter): the data hold an effect the baseline does not model, and no candidate explains it with physical parameters",
                pct(final_.selection, 2),
                pct(base_best, 2),
                base_best / f
            ),
        )
    } else {
        (Verdict::Unexplained, beyond_none(ctx, fin))
    }
}

/// Why the verdict is `unexplained` when the model is beyond [`NONE_LEVEL`] and no cause was
/// named.
fn beyond_none(ctx: &Context<'_>, fin: &Final) -> String {
    let (baseline, final_) = (&ctx.base.ls, &fin.scored);
    let base_best = ctx.base_best();
    format!(
        "the baseline's held-out simulated position NMAE is {}{} (predicting no motion: {:.2} %) and no candidate cuts it by {:.0} % with physical parameters",
        pct(baseline.selection, 2),
        if fin.refined {
            format!(", {} refined by output error on the fitting runs", pct(final_.selection, 2))
        } else {
            String::new()
        },
        ctx.sel_no_motion,
        100.0 * MIN_GAIN
    ) + &ctx.own_floor.map_or(String::new(), |f| if base_best <= f {
        format!("; on its own replayed log the baseline leaves {f:.4} %, as much: this log does not resolve the motion better than that, and no cause is tried")
    } else {
        format!("; on its own replayed log it leaves {f:.4} %")
    })
}

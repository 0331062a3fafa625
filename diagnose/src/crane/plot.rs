//! The series of the residual plots: the first run with a held-out part, its position error
//! per axis before and after the best-scored extension.

use super::heldout::Scored;
use super::nmae::Ctx;
use super::simulate::simulate;
use super::AXIS_NAMES;
use crane_model::Extensions;

/// One plot series per axis of the first run with a held-out part: time [s], filtered
/// position [m] and velocity [m/s], and the position error `measured - simulated` [m] of
/// the baseline (`before`) and with the best-scored extension when its score is finite
/// (`after`; empty otherwise or when a simulation fails).
pub(super) fn series(ctx: &Ctx, scored: &[Scored]) -> Vec<crate::plots::Series> {
    let mut out = Vec::new();
    let best = scored.first().filter(|s| s.score.is_finite());
    if let Some(p) = ctx.preps.iter().find(|p| p.held.contains(&true)) {
        let base = simulate(p.run, &p.params, &Extensions::default());
        let after = best.and_then(|sc| {
            let c = &sc.cand;
            let mut params = p.params;
            let mut ext = Extensions::default();
            c.ext.apply(c.axis.min(2), &mut params, &mut ext);
            simulate(p.run, &params, &ext)
        });
        for i in 0..3 {
            let meas = [&p.run.x, &p.run.y, &p.run.l][i];
            let err = |s: &Option<Vec<[f64; 3]>>| -> Vec<f64> {
                s.as_ref()
                    .map(|s| s.iter().zip(meas).map(|(a, m)| m - a[i]).collect())
                    .unwrap_or_default()
            };
            out.push(crate::plots::Series {
                name: format!("{}_{}", AXIS_NAMES[i], out.len() / 3),
                t: p.run.t.clone(),
                q: p.q[i].clone(),
                v: p.v[i].clone(),
                before: err(&base),
                after: err(&after),
            });
        }
    }
    out
}

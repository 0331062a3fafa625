//! Input dead band and input delay: the residual they predict is the gain times the
//! difference between the recorded voltage and the voltage the drive would see, with no free
//! amplitude.

use super::candidate::{sse_one, Cand, DriveParts};
use super::gather::gather_series;
use super::nmae::Ctx;
use super::residual::{drive_series, Prep};
use super::{Ext, CUTOFF_HZ};
use crate::fit::{deadband, delay_half_samples};
use crane_ident::signal::butter;

/// The force residual [N] drive `i` would show on the kept samples of a part (`held`) if
/// the drive saw `tf(u)` instead of the recorded voltage `u` [V]: `gain * (u - tf(u))`
/// (`gain` [N/V]), taken and filtered as the residual is.
fn shifted(
    ctx: &Ctx,
    i: usize,
    gain: f64,
    tf: &dyn Fn(&[f64]) -> Vec<f64>,
    held: bool,
) -> Vec<f64> {
    gather_series(&ctx.preps, i, held, &|p: &Prep| {
        let f = butter(4, CUTOFF_HZ * 2.0 * p.run.dt());
        let u = &p.run.u[i];
        let t = tf(u);
        let diff: Vec<f64> = u.iter().zip(&t).map(|(a, b)| gain * (a - b)).collect();
        drive_series(&f, &diff)
    })
}

/// The input-dead-band candidate of one drive (`gain` [N/V]): the band [V] on a 20 mV grid
/// up to 1.5 V, refined to a millivolt, by the fitting part's residual; none when the best
/// grid point is the last (the grid's edge).
pub(super) fn deadzone_candidate(ctx: &Ctx, part: &DriveParts, gain: f64) -> Option<Cand> {
    let (i, fg, hg) = (part.i, part.fit, part.held);
    let score_dz = |d: f64| {
        let col = shifted(
            ctx,
            i,
            gain,
            &|u: &[f64]| u.iter().map(|&x| deadband(x, d)).collect(),
            false,
        );
        sse_one(&col, 1.0, &fg.r)
    };
    let keep = |best: &mut Option<(f64, f64)>, d: f64| {
        let s = score_dz(d);
        if best.is_none_or(|b| s < b.0) {
            *best = Some((s, d));
        }
    };
    let mut best_dz: Option<(f64, f64)> = None;
    let (mut d, mut last) = (0.02, 0.0);
    while d <= 1.5 + 1e-9 {
        keep(&mut best_dz, d);
        last = d;
        d += 0.02;
    }
    // a band at the grid's last point is no result: the best one may lie beyond it
    if best_dz.is_some_and(|b| b.1 == last) {
        return None;
    }
    // refine to a millivolt: the grid step alone leaves a dry-force error of `K * 0.01 V`,
    // enough for a symmetric dry-friction shift to out-score the right cause
    if let Some((_, d0)) = best_dz {
        for j in -20..=20 {
            let d = d0 + j as f64 * 1e-3;
            if d > 0.0 {
                keep(&mut best_dz, d);
            }
        }
    }
    let (_, d) = best_dz?;
    let col = shifted(
        ctx,
        i,
        gain,
        &|u: &[f64]| u.iter().map(|&x| deadband(x, d)).collect(),
        true,
    );
    let s = part.with_held_sse(sse_one(&col, 1.0, &hg.r));
    Some(Cand {
        axis: i,
        ext: Ext::Deadzone(d),
        sse_after: s,
    })
}

/// The input-delay candidate of one drive (`gain` [N/V]): the delay in half samples, 1 to
/// `MAX_DELAY_STEPS - 1`, by the fitting part's residual (none at the last, the grid's edge);
/// reported in seconds (half the first run's sampling period per step, 1 ms when there is no
/// run).
pub(super) fn delay_candidate(ctx: &Ctx, part: &DriveParts, gain: f64) -> Option<Cand> {
    let (i, fg, hg) = (part.i, part.fit, part.held);
    let dt = ctx.preps.first().map(|p| p.run.dt()).unwrap_or(0.002);
    let mut best_dl: Option<(f64, usize)> = None;
    for m in 1..crane_model::MAX_DELAY_STEPS {
        let col = shifted(ctx, i, gain, &|u: &[f64]| delay_half_samples(u, m), false);
        let s = sse_one(&col, 1.0, &fg.r);
        if best_dl.is_none_or(|b| s < b.0) {
            best_dl = Some((s, m));
        }
    }
    // a delay at the grid's last point is no result: the best one may lie beyond it
    let (_, m) = best_dl.filter(|b| b.1 < crane_model::MAX_DELAY_STEPS - 1)?;
    let col = shifted(ctx, i, gain, &|u: &[f64]| delay_half_samples(u, m), true);
    let s = part.with_held_sse(sse_one(&col, 1.0, &hg.r));
    Some(Cand {
        axis: i,
        ext: Ext::Delay(m as f64 * dt / 2.0),
        sse_after: s,
    })
}

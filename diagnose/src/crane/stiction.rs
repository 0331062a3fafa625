//! Stiction (Stribeck breakaway above the sliding dry friction): a force-domain estimate per
//! drive, then, where the simulation is off, a fit by simulation (stick-slip leaves too little
//! in the masked force residual).

use super::baseline::BaselineScore;
use super::candidate::{one_col_fit, sse_one, Cand, DriveParts};
use super::gather::{sumsq, Gathered};
use super::heldout::{force_bic, Scored};
use super::nmae::Ctx;
use super::{Ext, FORCE_BIC_MAX};

/// The stiction force column per sample at Stribeck velocity `vs` [m/s] (the residual [N]
/// per unit of `ratio - 1`): the baseline dry magnitude, signed with the velocity, times
/// `exp(-(v / vs)^2)`.
fn stiction_col(g: &Gathered, vs: f64) -> Vec<f64> {
    g.v.iter()
        .zip(&g.cdry)
        .map(|(&v, &c)| v.signum() * c * (-(v / vs) * (v / vs)).exp())
        .collect()
}

/// The force-domain stiction candidate of one drive: the Stribeck velocity [m/s] on a grid
/// by the fitting part's residual reduction, the ratio `1 + th` from a positive amplitude
/// `th`; `None` when no velocity gives one.
pub(super) fn force_candidate(part: &DriveParts) -> Option<Cand> {
    let (i, fg, hg) = (part.i, part.fit, part.held);
    let mut best: Option<(f64, f64, f64)> = None;
    for &vs in &[0.003, 0.006, 0.012, 0.025, 0.05] {
        let fc = stiction_col(fg, vs);
        let th = one_col_fit(&fc, &fg.r);
        if th <= 0.0 {
            continue;
        }
        let red = sumsq(&fg.r) - sse_one(&fc, th, &fg.r);
        if best.is_none_or(|b| red > b.0) {
            best = Some((red, vs, th));
        }
    }
    let (_, vs, th) = best?;
    let hc = stiction_col(hg, vs);
    let s = part.with_held_sse(sse_one(&hc, th, &hg.r));
    Some(Cand {
        axis: i,
        ext: Ext::Stiction {
            ratio: 1.0 + th,
            velocity: vs,
        },
        sse_after: s,
    })
}

/// Typical Stribeck velocity of a drive [m/s] (the rope's is slower), where the staged
/// stiction search starts.
const STRIBECK_START: [f64; 3] = [0.01, 0.01, 0.003];

/// Stiction fitted by simulation on the fitting part, in stages (128 simulations): the ratio
/// on a grid of 0.1 from 1.1 to 3.4 at five Stribeck velocities (0.5 to 2 times a typical
/// one: stick-slip makes the error surface rugged and ratio and velocity trade off, so a
/// coarser start lands in the wrong valley), then the velocity at that ratio, then both
/// refined.
/// Returns the best, or `None` if every simulation failed.
fn fit_stiction_sim(ctx: &Ctx, i: usize, before_f: &[f64; 3]) -> Option<Ext> {
    let mut best: Option<(f64, f64, f64)> = None; // (score, ratio, velocity)
    let try_one = |ratio: f64, vs: f64, best: &mut Option<(f64, f64, f64)>| {
        let e = Ext::Stiction {
            ratio,
            velocity: vs,
        };
        if let Some(a) = ctx.nmae(Some((&e, i)), false) {
            let s = ctx.score(before_f, &a, 0);
            if best.is_none_or(|b| s < b.0) {
                *best = Some((s, ratio, vs));
            }
        }
    };
    let v0 = STRIBECK_START[i];
    const START: [f64; 5] = [0.5, 0.7, 1.0, 1.5, 2.0];
    for f in START {
        for j in 0..24 {
            try_one(1.1 + 0.1 * j as f64, v0 * f, &mut best);
        }
    }
    let (_, r1, _) = best?;
    for f in [0.35, 0.7, 1.4, 2.8] {
        try_one(r1, v0 * f, &mut best);
    }
    let (_, _, v1) = best?;
    for dr in [-0.05, 0.05] {
        try_one(r1 + dr, v1, &mut best);
    }
    let (_, r2, _) = best?;
    for f in [0.85, 1.2] {
        try_one(r2, v1 * f, &mut best);
    }
    best.map(|(_, ratio, velocity)| Ext::Stiction { ratio, velocity })
}

/// Stiction by simulation on the fitting part (output error: stick-slip leaves too little
/// in the masked force residual), for the drives whose simulation is off: the worst one and
/// any within a third of it (in noise floors). Skipped when a candidate already brings every
/// axis's held-out NMAE down to its floor: nothing is left for stiction to explain (the
/// floored score could at most tie). A fitted one replaces the drive's force-domain stiction
/// candidate in `scored` (appended; its force SSE is the baseline's).
pub(super) fn refine_by_simulation(ctx: &Ctx, base: &BaselineScore, scored: &mut Vec<Scored>) {
    let (before_h, before_f, floor) = (base.before_h, base.before_f, ctx.floor);
    let explained = scored.iter().any(|sc| {
        sc.score.is_finite()
            && sc.force_bic < FORCE_BIC_MAX
            && (0..3).all(|j| sc.after[j] <= floor[j])
            && !matches!(sc.cand.ext, Ext::Stiction { .. })
    });
    let off: [f64; 3] = std::array::from_fn(|i| before_f[i] / floor[i]);
    let worst_off = off.iter().cloned().fold(0.0_f64, f64::max);
    for i in 0..3 {
        if explained || before_f[i] <= floor[i] || off[i] < worst_off / 3.0 {
            continue;
        }
        let Some(e) = fit_stiction_sim(ctx, i, &before_f) else {
            continue;
        };
        let Some(after) = ctx.nmae(Some((&e, i)), true) else {
            continue;
        };
        scored.retain(|sc| !(sc.cand.axis == i && matches!(sc.cand.ext, Ext::Stiction { .. })));
        let s = ctx.score(&before_h, &after, e.k());
        let c = Cand {
            axis: i,
            ext: e,
            sse_after: base.sse_b,
        };
        let fb = force_bic(&c, base);
        scored.push(Scored {
            cand: c,
            force_bic: fb,
            score: s,
            after,
        });
    }
}

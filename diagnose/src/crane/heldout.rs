//! The held-out scores of each candidate: the change of the force BIC, and the floored
//! simulated score of the held-out part.

use super::baseline::BaselineScore;
use super::candidate::Cand;
use super::nmae::Ctx;
use super::Ext;

/// A candidate with its held-out scores.
pub(super) struct Scored {
    /// The candidate.
    pub(super) cand: Cand,
    /// Held-out force BIC change against the baseline ([`force_bic`]); negative is better.
    pub(super) force_bic: f64,
    /// Simulated score ([`Ctx::score`], negative is better); infinite when not simulated.
    pub(super) score: f64,
    /// Held-out simulated NMAE per axis with the extension [%] (the baseline's when not
    /// simulated).
    pub(super) after: [f64; 3],
}

/// Held-out force BIC change of `c` against the baseline [dimensionless]: the sum over the
/// drives it acts on of `n_i ln(SSE_after / SSE_before)` (`n_i` the drive's held-out samples),
/// plus `k ln(n)` for its `k` extra parameters (`n` the sum of the `n_i`); negative when it
/// explains more than its parameters cost.
pub(super) fn force_bic(c: &Cand, base: &BaselineScore) -> f64 {
    let (held_g, sse_b) = (&base.held_g, base.sse_b);
    let axes: Vec<usize> = if c.axis == 3 {
        vec![0, 1, 2]
    } else {
        vec![c.axis]
    };
    let mut s = 0.0;
    let mut n_all = 0;
    for &i in &axes {
        let n = held_g[i].r.len();
        n_all += n;
        s += n as f64 * (c.sse_after[i].max(1e-300) / sse_b[i].max(1e-300)).ln();
    }
    s + c.ext.k() as f64 * (n_all.max(1) as f64).ln()
}

/// Scores every candidate, in order: its force BIC, and, for stiction or a candidate whose
/// force BIC is negative, its held-out simulation (the payload mass simulated on the rope).
pub(super) fn score_candidates(ctx: &Ctx, base: &BaselineScore, cands: Vec<Cand>) -> Vec<Scored> {
    let before_h = base.before_h;
    let mut scored: Vec<Scored> = Vec::new();
    let unscored = |c: Cand, fb: f64| Scored {
        cand: c,
        force_bic: fb,
        score: f64::INFINITY,
        after: before_h,
    };
    for c in cands {
        let fb = force_bic(&c, base);
        let is_stiction = matches!(c.ext, Ext::Stiction { .. });
        if !is_stiction && fb >= 0.0 {
            scored.push(unscored(c, fb));
            continue;
        }
        let axis = c.axis.min(2);
        let Some(after) = ctx.nmae(Some((&c.ext, if c.axis == 3 { 2 } else { axis })), true) else {
            scored.push(unscored(c, fb));
            continue;
        };
        let s = ctx.score(&before_h, &after, c.ext.k());
        scored.push(Scored {
            cand: c,
            force_bic: fb,
            score: s,
            after,
        });
    }
    scored
}

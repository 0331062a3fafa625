//! Stage 4: the candidates ranked by their held-out force BIC change, each with the
//! bootstrap lower bound of its held-out NMAE cut (its noise floor, `bootstrap.rs`).

use super::baseline::BaselineFit;
use super::bootstrap::{bootstrap_cuts, quantile, BOOT_BLOCKS, BOOT_LEVEL, BOOT_REPS};
use super::candidates::Cand;
use super::prepare::Prepared;
use crate::fit::delta_bic;

/// A candidate with its score.
pub(super) struct Scored {
    /// The candidate.
    pub(super) cand: Cand,
    /// Held-out force BIC change against the baseline ([`delta_bic`]; negative is support).
    pub(super) delta_bic: f64,
    /// The [`BOOT_LEVEL`] quantile of the bootstrap's held-out NMAE cuts
    /// `1 - MAE_candidate / MAE_baseline` (a fraction; positive: the candidate cuts the error).
    pub(super) lower: f64,
}

/// Stage 4: the candidates sorted by their held-out force BIC change, best (most negative)
/// first, ties in the order offered; each with the bootstrap lower bound of its cut
/// ([`BOOT_REPS`] replicates of [`BOOT_BLOCKS`] blocks).
pub(super) fn score(cands: Vec<Cand>, prep: &Prepared, base: &BaselineFit) -> Vec<Scored> {
    let n_h = prep.held.f.len();
    let sse0 = base.fitted.sse_h;
    let mut scored: Vec<(Cand, f64)> = cands
        .into_iter()
        .map(|c| {
            let b = delta_bic(n_h, sse0, c.sse_h, c.k);
            (c, b)
        })
        .collect();
    scored.sort_by(|a, b| a.1.total_cmp(&b.1));
    // the noise floor of every cut: its one-sided bootstrap lower bound
    let level = BOOT_LEVEL;
    let (bf, bh) = (&base.cols.fit, &base.cols.held);
    let lower: Vec<f64> = scored
        .iter()
        .map(|(c, _)| {
            let cuts = bootstrap_cuts(
                bf,
                bh,
                &prep.fit.f,
                &prep.held.f,
                &c.design,
                BOOT_REPS,
                BOOT_BLOCKS,
            );
            quantile(cuts, level)
        })
        .collect();
    scored
        .into_iter()
        .zip(lower)
        .map(|((cand, delta_bic), lower)| Scored {
            cand,
            delta_bic,
            lower,
        })
        .collect()
}

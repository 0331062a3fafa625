//! Payload mass: one mass change [kg] over the three drive rows, fitted against their
//! payload-mass sensitivities.

use super::candidate::{sse_one, Cand};
use super::gather::{sumsq, Gathered};
use super::Ext;

/// The payload-mass candidate (axis 3: all drives): the mass change `dm` [kg] (true =
/// declared + `dm`) by least squares over the three drives' fitting parts, each weighted by
/// the inverse of its mean squared residual [1/N^2]; `None` when no drive has a sensitivity.
pub(super) fn candidate(fit_g: &[Gathered], held_g: &[Gathered]) -> Option<Cand> {
    let w: [f64; 3] = std::array::from_fn(|i| {
        let n = fit_g[i].r.len().max(1) as f64;
        1.0 / (sumsq(&fit_g[i].r) / n).max(1e-12)
    });
    let (mut num, mut den) = (0.0, 0.0);
    for i in 0..3 {
        for (p, r) in fit_g[i].phi.iter().zip(&fit_g[i].r) {
            num += w[i] * p * r;
            den += w[i] * p * p;
        }
    }
    if den > 0.0 {
        let dm = num / den;
        let s: [f64; 3] = std::array::from_fn(|i| sse_one(&held_g[i].phi, dm, &held_g[i].r));
        Some(Cand {
            axis: 3,
            ext: Ext::Payload(dm),
            sse_after: s,
        })
    } else {
        None
    }
}

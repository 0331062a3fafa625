//! Stage 3: every candidate extension searched on the fitting rows (each cause's grid chooses
//! by the fitting rows' squared error), fitted with the baseline and scored on the held-out
//! rows; the causes this path cannot fit or identify are listed beside them.

use super::baseline::{Design, Fitted};
use crate::Cause;
use std::collections::BTreeMap;

/// A candidate extension: its best fit with the baseline.
pub(super) struct Cand {
    /// The cause the extension models.
    pub(super) cause: Cause,
    /// Its parameters, named with their unit (`center_m`, `delay_s`, ...).
    pub(super) params: BTreeMap<String, f64>,
    /// Extra parameters counted by the held-out BIC penalty.
    pub(super) k: usize,
    /// Held-out sum of squared force residuals [N^2].
    pub(super) sse_h: f64,
    /// Held-out mean absolute force residual [N].
    pub(super) mae_h: f64,
    /// Fitting sum of squared force residuals [N^2].
    pub(super) sse_f: f64,
    /// Its columns and targets, for the bootstrap.
    pub(super) design: Design,
}

/// What the search found: the candidates offered for scoring, and the causes reported as
/// unsupported candidates without a score.
#[derive(Default)]
pub(super) struct Candidates {
    /// The candidates with a fit, in the order they were searched.
    pub(super) offered: Vec<Cand>,
    /// causes whose best fit is unphysical (reported as unsupported candidates)
    pub(super) not_physical: Vec<Cause>,
    /// causes that the baseline already carries or this path cannot tell apart from it
    pub(super) not_ident: Vec<Cause>,
}

impl Candidates {
    /// Offers `cause` with its parameters, extra parameter count `k`, design and fit; a
    /// failed fit (`None`) offers nothing.
    pub(super) fn offer(
        &mut self,
        cause: Cause,
        params: BTreeMap<String, f64>,
        k: usize,
        design: Design,
        r: Option<Fitted>,
    ) {
        if let Some(r) = r {
            self.offered.push(Cand {
                cause,
                params,
                k,
                design,
                sse_h: r.sse_h,
                mae_h: r.mae_h,
                sse_f: r.sse_f,
            });
        }
    }
}

/// Named parameters.
pub(super) fn params(v: &[(&str, f64)]) -> BTreeMap<String, f64> {
    v.iter().map(|(k, x)| (k.to_string(), *x)).collect()
}

/// The coefficient of the last extra column (0 without a fit).
pub(super) fn last_coef(r: &Option<Fitted>) -> f64 {
    r.as_ref()
        .and_then(|x| x.theta.last().copied())
        .unwrap_or(0.0)
}

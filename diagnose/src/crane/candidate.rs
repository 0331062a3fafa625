//! The candidate causes fitted in the force domain on the fitting part of each drive, with
//! their held-out force error; the causes themselves live in their own modules.

use super::baseline::BaselineScore;
use super::gather::{sumsq, Gathered};
use super::residual::axis_params;
use super::runs::Setup;
use super::{asymmetry, bump, input, payload, stiction, Ext};
use crate::Cause;

/// A candidate after its force-domain fit.
pub(super) struct Cand {
    /// Drive it acts on: 0 X, 1 Y, 2 rope, 3 all three (the payload mass).
    pub(super) axis: usize,
    /// The fitted extension.
    pub(super) ext: Ext,
    /// Held-out SSE of the force residual after, per axis [N^2] (before = the baseline's).
    pub(super) sse_after: [f64; 3],
}

/// Least-squares amplitude of one column `fit_c` against the residual `fit_r` (in the unit of
/// the residual per unit of the column; 0 for an all-zero column).
pub(super) fn one_col_fit(fit_c: &[f64], fit_r: &[f64]) -> f64 {
    let cc = sumsq(fit_c);
    if cc <= 0.0 {
        return 0.0;
    }
    fit_c.iter().zip(fit_r).map(|(c, r)| c * r).sum::<f64>() / cc
}

/// Sum of squares of `r - theta c` (in the square of the unit of `r`).
pub(super) fn sse_one(c: &[f64], theta: f64, r: &[f64]) -> f64 {
    c.iter()
        .zip(r)
        .map(|(c, r)| (r - theta * c) * (r - theta * c))
        .sum()
}

/// One drive's fitting and held-out samples, with the baseline's held-out SSE.
pub(super) struct DriveParts<'a> {
    /// The drive: 0 X, 1 Y, 2 rope.
    pub(super) i: usize,
    /// Kept samples on the fitting part.
    pub(super) fit: &'a Gathered,
    /// Kept samples on the held-out part.
    pub(super) held: &'a Gathered,
    /// The baseline's held-out SSE of the force residual per drive [N^2].
    pub(super) sse_b: [f64; 3],
}

impl DriveParts<'_> {
    /// The baseline's held-out SSE per drive [N^2] with this drive's replaced by `sse_i`.
    pub(super) fn with_held_sse(&self, sse_i: f64) -> [f64; 3] {
        let mut s = self.sse_b;
        s[self.i] = sse_i;
        s
    }

    /// A candidate with one free amplitude `th` (the residual [N] per unit of the column):
    /// fitted on `fit_c`, its held-out SSE on `held_c`. An offset becomes `th * scale` [N]
    /// (`scale` -1: the residual is `r = -b`), a bump's amplitude `th` [N]; other extensions
    /// are kept as given.
    pub(super) fn one(&self, ext: Ext, fit_c: &[f64], held_c: &[f64], scale: f64) -> Cand {
        let (i, fg, hg) = (self.i, self.fit, self.held);
        let th = one_col_fit(fit_c, &fg.r);
        let mut s = self.sse_b;
        s[i] = sse_one(held_c, th, &hg.r);
        let ext = match ext {
            Ext::Offset(_) => Ext::Offset(th * scale),
            Ext::Bump {
                center,
                width,
                direction,
                ..
            } => Ext::Bump {
                center,
                width,
                amplitude: th,
                direction,
            },
            e => e,
        };
        Cand {
            axis: i,
            ext,
            sse_after: s,
        }
    }
}

/// The candidates of the force domain, and the causes not tried.
pub(super) struct ForceCandidates {
    /// Every candidate fitted, per drive in the order X, Y, rope, then the payload mass.
    pub(super) cands: Vec<Cand>,
    /// Drive (0 X, 1 Y, 2 rope) and cause not tried: not identifiable against a re-fitted
    /// baseline.
    pub(super) not_identifiable: Vec<(usize, Cause)>,
}

/// Fits every cause on every drive with at least 20 kept samples in each part: localized
/// friction, stiction, direction asymmetry and force offset (not against a re-fitted
/// baseline, which has absorbed them), input dead band and delay; then the payload mass over
/// the three drives.
pub(super) fn fit_candidates(setup: &Setup, base: &BaselineScore) -> ForceCandidates {
    let mut cands: Vec<Cand> = Vec::new();
    let mut not_identifiable: Vec<(usize, Cause)> = Vec::new();
    for i in 0..3 {
        let (fg, hg) = (&base.fit_g[i], &base.held_g[i]);
        if fg.r.len() < 20 || hg.r.len() < 20 {
            continue;
        }
        let part = DriveParts {
            i,
            fit: fg,
            held: hg,
            sse_b: base.sse_b,
        };
        // localized friction
        cands.extend(bump::candidate(&part));
        // stiction (force-domain evidence; refined by simulation later)
        cands.extend(stiction::force_candidate(&part));
        if !setup.fitted {
            cands.extend(asymmetry::candidate(&part));
            cands.push(asymmetry::offset_candidate(&part));
        } else {
            not_identifiable.push((i, Cause::ForceOffset));
            not_identifiable.push((i, Cause::DirectionAsymmetry));
        }
        // input dead band and delay: the residual they predict has no free amplitude
        let gain = axis_params(&setup.params, i).gain;
        cands.extend(input::deadzone_candidate(&setup.ctx, &part, gain));
        cands.extend(input::delay_candidate(&setup.ctx, &part, gain));
    }
    // payload mass: one parameter over the three drives, each weighted by its noise
    cands.extend(payload::candidate(&base.fit_g, &base.held_g));
    ForceCandidates {
        cands,
        not_identifiable,
    }
}

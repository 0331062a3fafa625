//! A candidate cause fitted in the force domain on the fitting part of one drive, with its
//! held-out force error ([`Cand`]), and what each cause's module fits it on ([`DriveParts`]);
//! every cause is fitted by [`super::search`].

use super::gather::{sumsq, Gathered};
use super::Ext;

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

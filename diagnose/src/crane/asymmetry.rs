//! Direction asymmetry (dry magnitude and viscous coefficient changed per direction of
//! motion) and the force offset, its one-parameter special case: a constant bias is the dry
//! magnitudes shifted oppositely while it stays below them.

use super::candidate::{Cand, DriveParts};
use super::gather::Gathered;
use super::Ext;
use crate::fit::{ls, sse};

/// The four force columns of a direction asymmetry (the residual [N] per unit of each
/// parameter): moving positive 1, moving negative -1 (the dry changes [N], positive adds
/// friction against the motion), then `max(v, 0)` and `min(v, 0)` [m/s] (the viscous changes
/// [N s/m]).
pub(super) fn asym_cols(g: &Gathered) -> [Vec<f64>; 4] {
    [
        g.v.iter()
            .map(|&v| if v > 0.0 { 1.0 } else { 0.0 })
            .collect(),
        g.v.iter()
            .map(|&v| if v < 0.0 { -1.0 } else { 0.0 })
            .collect(),
        g.v.iter().map(|&v| v.max(0.0)).collect(),
        g.v.iter().map(|&v| v.min(0.0)).collect(),
    ]
}

/// The direction-asymmetry candidate of one drive: the four changes by least squares on the
/// fitting part, `None` when the least squares fail.
pub(super) fn candidate(part: &DriveParts) -> Option<Cand> {
    let (i, fg, hg) = (part.i, part.fit, part.held);
    let fc = asym_cols(fg);
    let hc = asym_cols(hg);
    let fr: Vec<&[f64]> = fc.iter().map(|c| c.as_slice()).collect();
    let hr: Vec<&[f64]> = hc.iter().map(|c| c.as_slice()).collect();
    let th = ls(&fr, &fg.r)?;
    let s = part.with_held_sse(sse(&hr, &th, &hg.r));
    Some(Cand {
        axis: i,
        ext: Ext::Asymmetry {
            dry_pos: th[0],
            dry_neg: th[1],
            viscous_pos: th[2],
            viscous_neg: th[3],
        },
        sse_after: s,
    })
}

/// The force-offset candidate of one drive: a constant bias `b` [N] along the drive's
/// positive direction, fitted as one column of ones (the residual is `r = -b`).
pub(super) fn offset_candidate(part: &DriveParts) -> Cand {
    let (fg, hg) = (part.fit, part.held);
    let ones_f = vec![1.0; fg.r.len()];
    let ones_h = vec![1.0; hg.r.len()];
    part.one(Ext::Offset(0.0), &ones_f, &ones_h, -1.0)
}

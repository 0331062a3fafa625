//! Stage 3 of a crane diagnosis: every candidate cause fitted in the force domain on each
//! drive's fitting part (the causes live in their own modules), and the causes not tried.

use super::baseline::BaselineScore;
use super::candidate::{Cand, DriveParts};
use super::residual::axis_params;
use super::runs::Setup;
use super::{asymmetry, bump, input, payload, stiction};
use crate::Cause;

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

//! Localized friction: a dry-friction bump over a stretch of a drive's travel, fitted on a
//! grid of centres, widths and directions and then refined.

use super::candidate::{Cand, DriveParts};
use super::gather::{sumsq, Gathered};
use super::Ext;
use crate::fit::bump_shape;
use crane_model::Direction;

/// The bump's force column per sample (the residual [N] per newton of amplitude): the bump
/// shape at the position, signed with the velocity (a positive amplitude opposes the motion),
/// zero in the direction it does not act in.
fn bump_col(g: &Gathered, center: f64, width: f64, dir: Direction) -> Vec<f64> {
    g.q.iter()
        .zip(&g.v)
        .map(|(&q, &v)| {
            let on = match dir {
                Direction::Both => true,
                Direction::Positive => v > 0.0,
                Direction::Negative => v < 0.0,
            };
            if on {
                v.signum() * bump_shape(q, center, width)
            } else {
                0.0
            }
        })
        .collect()
}

/// The best bump for the fitting samples `fit` (centre and half-width [m], amplitude [N],
/// direction); `None` with fewer than 10 samples or nothing it explains.
fn fit_bump(fit: &Gathered) -> Option<Ext> {
    if fit.q.len() < 10 {
        return None;
    }
    let lo = fit.q.iter().cloned().fold(f64::INFINITY, f64::min);
    let hi = fit.q.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    let widths = [0.01, 0.015, 0.02, 0.03, 0.045, 0.065];
    let dirs = [Direction::Both, Direction::Positive, Direction::Negative];
    let mut best = (0.0, 0.0, 0.0, Direction::Both, 0.0);
    let score = |c: f64, w: f64, d: Direction| -> (f64, f64) {
        let col = bump_col(fit, c, w, d);
        let cc = sumsq(&col);
        if cc <= 1e-9 * fit.q.len() as f64 {
            return (0.0, 0.0);
        }
        let cr: f64 = col.iter().zip(&fit.r).map(|(a, b)| a * b).sum();
        (cr * cr / cc, cr / cc)
    };
    let mut c = lo;
    while c <= hi {
        for &w in &widths {
            for &d in &dirs {
                let (gain, a) = score(c, w, d);
                // a direction-restricted bump must beat the two-sided one clearly
                let gain = if d == Direction::Both {
                    gain
                } else {
                    gain * 0.98
                };
                if gain > best.0 {
                    best = (gain, c, w, d, a);
                }
            }
        }
        c += 0.0025;
    }
    if best.0 <= 0.0 {
        return None;
    }
    // refine the centre and width
    let (_, c0, w0, d0, _) = best;
    let mut refined = best;
    let mut c = c0 - 0.003;
    while c <= c0 + 0.003 {
        let mut w = w0 * 0.8;
        while w <= w0 * 1.25 {
            let (gain, a) = score(c, w, d0);
            if gain > refined.0 {
                refined = (gain, c, w, d0, a);
            }
            w += w0 * 0.05;
        }
        c += 0.0005;
    }
    Some(Ext::Bump {
        center: refined.1,
        width: refined.2,
        amplitude: refined.4,
        direction: refined.3,
    })
}

/// The localized-friction candidate of one drive: the bump fitted on the fitting part, its
/// amplitude [N] refitted as one column.
pub(super) fn candidate(part: &DriveParts) -> Option<Cand> {
    let (fg, hg) = (part.fit, part.held);
    let Some(Ext::Bump {
        center,
        width,
        direction,
        ..
    }) = fit_bump(fg)
    else {
        return None;
    };
    let e = Ext::Bump {
        center,
        width,
        amplitude: 0.0,
        direction,
    };
    Some(part.one(
        e,
        &bump_col(fg, center, width, direction),
        &bump_col(hg, center, width, direction),
        1.0,
    ))
}

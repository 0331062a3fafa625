//! Candidates of stage 3 that reshape the friction: localized friction (a bump along the
//! travel), stiction (a breakaway excess at low speed) and, against the symmetric baseline,
//! the direction asymmetry. Every extra column is a force [N] per unit of its coefficient,
//! signed with the velocity (it opposes the motion for a positive coefficient).

use super::baseline::{BaselineFit, Fitted};
use super::candidates::{last_coef, params, Candidates};
use super::prepare::Prepared;
use super::rows::{dec, Part};
use crate::fit::bump_shape;
use crate::Cause;

/// Localized friction: a grid on the fitting part over the bump's center (steps of a
/// thirtieth of the fitting positions' range, from the lowest to the highest), width (2, 4, 8
/// and 15 % of that range) and direction (both, positive only, negative only), chosen by the
/// fitting squared error, then fitted for its amplitude. Parameters: `center_m`, `width_m`
/// [m or rad], `amplitude_n` [N, positive opposing the motion], `direction` (0 both, 1
/// positive, -1 negative).
pub(super) fn localized_friction(prep: &Prepared, base: &BaselineFit, out: &mut Candidates) {
    let (fit, held) = (&prep.fit, &prep.held);
    let (lo, hi) = (base.lo, base.hi);
    // a bump needs a travel: fitting positions that never change (or a range too small to
    // step through) leave no site to try, and the grid below would never end
    let step = (hi - lo) / 30.0;
    if !(step > 0.0 && step.is_finite() && lo + step > lo) {
        return;
    }
    let mut best: Option<(f64, f64, f64, i32)> = None;
    for wi in [0.02, 0.04, 0.08, 0.15] {
        let w = wi * (hi - lo);
        let mut c = lo;
        // at most 31 centres (30 steps, one more where the sum of the steps rounds below hi)
        for _ in 0..31 {
            if c > hi {
                break;
            }
            for d in [0, 1, -1] {
                if let Some(Fitted { sse_f: sf, .. }) = base.cols.eval(
                    &[bump_column(fit, c, w, d)],
                    &[bump_column(held, c, w, d)],
                    &fit.f,
                    &held.f,
                ) {
                    if best.is_none_or(|b| sf < b.0) {
                        best = Some((sf, c, w, d));
                    }
                }
            }
            c += step;
        }
    }
    if let Some((_, c, w, d)) = best {
        let (design, r) = base.fit_extra(
            prep,
            vec![bump_column(fit, c, w, d)],
            vec![bump_column(held, c, w, d)],
        );
        let amp = last_coef(&r);
        out.offer(
            Cause::LocalizedFriction,
            params(&[
                ("center_m", c),
                ("width_m", w),
                ("amplitude_n", amp),
                ("direction", d as f64),
            ]),
            3,
            design,
            r,
        );
    }
}

/// The localized-friction column of `p`, decimated: `sign(qd) bump((q - c) / w)` where the
/// direction `d` lets it act (0 both, positive moving positive only, negative moving
/// negative only), 0 elsewhere and at rest.
fn bump_column(p: &Part, c: f64, w: f64, d: i32) -> Vec<f64> {
    dec(p, bump_column_full(p, c, w, d))
}

/// [`bump_column`] at the full rate.
fn bump_column_full(p: &Part, c: f64, w: f64, d: i32) -> Vec<f64> {
    p.q.iter()
        .zip(&p.v)
        .map(|(&q, &v)| {
            let on = d == 0 || (d > 0 && v > 0.0) || (d < 0 && v < 0.0);
            if on && v != 0.0 {
                v.signum() * bump_shape(q, c, w)
            } else {
                0.0
            }
        })
        .collect::<Vec<f64>>()
}

/// Stiction: a grid of 12 Stribeck velocities `vs` [m/s or rad/s] (from 0.2 % of the
/// fitting rows' top speed, a factor 1.6 apart), chosen by the fitting squared error, then
/// fitted for the breakaway excess. A negative excess is not stiction: the cause is then
/// listed as unphysical. Parameters: `ratio` (breakaway over the baseline's dry level at the
/// middle of the travel), `velocity_m_per_s`, `breakaway_excess_n` [N, > 0].
pub(super) fn stiction(prep: &Prepared, base: &BaselineFit, out: &mut Candidates) {
    let (fit, held) = (&prep.fit, &prep.held);
    let vmax = fit.v.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    let mut best: Option<(f64, f64)> = None;
    for j in 0..12 {
        let vs = vmax * 0.002 * 1.6_f64.powi(j);
        if let Some(Fitted { sse_f: sf, .. }) = base.cols.eval(
            &[stribeck_column(fit, vs)],
            &[stribeck_column(held, vs)],
            &fit.f,
            &held.f,
        ) {
            if best.is_none_or(|b| sf < b.0) {
                best = Some((sf, vs));
            }
        }
    }
    if let Some((_, vs)) = best {
        let (design, r) = base.fit_extra(
            prep,
            vec![stribeck_column(fit, vs)],
            vec![stribeck_column(held, vs)],
        );
        let amp = last_coef(&r);
        let th0 = &base.fitted.theta;
        let fc = if prep.sym {
            th0[2]
        } else {
            0.5 * (th0[3] + th0[8])
        };
        // stiction is breakaway ABOVE sliding friction: a negative excess (ratio < 1)
        // is not stiction and is not offered as a finding
        if amp > 0.0 {
            out.offer(
                Cause::Stiction,
                params(&[
                    ("ratio", 1.0 + amp / fc.abs().max(1e-9)),
                    ("velocity_m_per_s", vs),
                    ("breakaway_excess_n", amp),
                ]),
                2,
                design,
                r,
            );
        } else {
            out.not_physical.push(Cause::Stiction);
        }
    }
}

/// The stiction column of `p`, decimated: `sign(qd) exp(-(qd / vs)^2)` (0 at rest), `vs`
/// [m/s or rad/s].
fn stribeck_column(p: &Part, vs: f64) -> Vec<f64> {
    dec(
        p,
        p.v.iter()
            .map(|&v| {
                if v == 0.0 {
                    0.0
                } else {
                    v.signum() * (-(v / vs) * (v / vs)).exp()
                }
            })
            .collect(),
    )
}

/// The direction asymmetry, against the symmetric baseline only: a viscous term and a
/// constant force acting only while moving positive. The force offset is listed as not
/// identifiable either way (the symmetric baseline carries it; the paper's structure's dry
/// levels per direction include it), and so is the asymmetry against the paper's structure
/// (it has it). Parameters: `viscous_pos_n_s_per_m`, `viscous_neg_n_s_per_m` [N s/m],
/// `dry_pos_n`, `dry_neg_n` [N, magnitudes].
pub(super) fn direction_asymmetry(prep: &Prepared, base: &BaselineFit, out: &mut Candidates) {
    if prep.sym {
        let (design, r) = base.fit_extra(
            prep,
            positive_motion_columns(&prep.fit),
            positive_motion_columns(&prep.held),
        );
        let th = r.as_ref().map(|x| x.theta.clone()).unwrap_or_default();
        if th.len() == 6 {
            // baseline a, Fv, Fc, offset o; extras a' (v+), b (ind+):
            // Fv+ = Fv + a', Fv- = Fv; the constant force moving positive Fc + o + b, moving
            // negative Fc - o (the offset is not separable from direction-dependent dry
            // friction: the two dry levels include it)
            out.offer(
                Cause::DirectionAsymmetry,
                params(&[
                    ("viscous_pos_n_s_per_m", th[1] + th[4]),
                    ("viscous_neg_n_s_per_m", th[1]),
                    ("dry_pos_n", th[2] + th[3] + th[5]),
                    ("dry_neg_n", th[2] - th[3]),
                ]),
                2,
                design,
                r,
            );
        }
        // the symmetric baseline already carries the published offset
        out.not_ident.push(Cause::ForceOffset);
    } else {
        out.not_ident.push(Cause::ForceOffset);
        out.not_ident.push(Cause::DirectionAsymmetry);
    }
}

/// The asymmetry's columns of `p`, decimated: `max(qd, 0)` and the indicator of `qd > 0`.
fn positive_motion_columns(p: &Part) -> Vec<Vec<f64>> {
    vec![
        dec(p, p.v.iter().map(|&v| v.max(0.0)).collect::<Vec<f64>>()),
        dec(
            p,
            p.v.iter()
                .map(|&v| if v > 0.0 { 1.0 } else { 0.0 })
                .collect(),
        ),
    ]
}

//! Candidates of stage 3 that act on the drive's input: a delay (the force acts some samples
//! after it was recorded) and a dead band (small inputs produce no force). Neither adds a
//! column: each replaces the target force by its transform of the measured one.

use super::baseline::{BaselineFit, Design, Fitted};
use super::candidates::{params, Candidates};
use super::prepare::Prepared;
use super::rows::{dec, Part};
use crate::drive::grid::{delay_grid, integer};
use crate::fit::deadband;
use crate::Cause;

/// Input delay: the force acts m samples later, chosen by the fitting squared error on the
/// grid 0 (no delay at all may fit best) and [`delay_grid`]: 1, 2, 3, 4, then steps of about
/// `sqrt 2` up to 0.25 s ([`crate::drive::grid::MAX_DELAY_S`]; at least
/// [`crate::drive::grid::MAX_DELAY`] samples) in samples of the data's period, at most a
/// quarter of the shortest fitting run (or time split's share of one) with rows
/// ([`Part::shortest_share`]; a delayed row reaches back into the run's rests, see
/// [`Part::delayed`]); the best point is refined to the sample between its neighbours
/// ([`integer`]). Named only above one sample, and never at the grid's last point (the best
/// value may lie beyond it). Parameter: `delay_s` [s] (m times the sample period, positive:
/// the force lags the recorded input).
///
/// Work: one evaluation (the fitting rows' force delayed and decimated, one least squares of
/// the baseline's columns) per grid point, plus about `2 log_1.5(gap)` for the refinement
/// over the gap between the best point's neighbours (no point evaluated twice): at 1 kHz 17
/// grid points (0, then 1 to 250 samples) and at most 15 more, 32 in all (22 at 200 Hz, 38
/// at 2 kHz); then the held-out rows' delayed force and one fit scored on them for the delay
/// offered. Only the best delayed force is kept, never one per delay.
pub(super) fn input_delay(prep: &Prepared, base: &BaselineFit, out: &mut Candidates) {
    let (fit, held) = (&prep.fit, &prep.held);
    let grid: Vec<usize> = std::iter::once(0)
        .chain(delay_grid(prep.dt, fit.shortest_share()))
        .collect();
    let Some(best) = integer(&grid, |m| {
        let yf = fit.delayed(m);
        base.cols.fit_sse(&yf).map(|sf| (yf, sf))
    }) else {
        return;
    };
    // One sample is not named: the recorded input is held over each sample (zero-order
    // hold) while the central-difference acceleration at a sample spans the inputs before
    // and after it, so the data put the force half a sample late whatever the rig does,
    // and 0 and 1 fit alike up to the filter's and the controller's noise (a simulated PD
    // loop without any delay "finds" one sample). A delay at the grid's last point is no
    // result: the best one may lie beyond it.
    if best.at <= 1 || best.at_edge(&grid, false) {
        return;
    }
    let m = best.at;
    let (yf, yh) = (best.value, held.delayed(m));
    let r = base.cols.eval(&[], &[], &yf, &yh);
    out.offer(
        Cause::InputDelay,
        params(&[("delay_s", m as f64 * prep.dt)]),
        1,
        Design {
            ef: Vec::new(),
            eh: Vec::new(),
            yf,
            yh,
        },
        r,
    );
}

/// Input dead band [V, or input units] (force / gain): a grid of 30 widths, multiples of
/// 0.5 % of the fitting rows' largest input, chosen by the fitting squared error; not
/// offered at the grid's last point.
/// Parameter: `deadzone_v` (the band's half width `d`: an input `|u| <= d` gives no force,
/// a larger one `u - sign(u) d`).
pub(super) fn input_deadzone(prep: &Prepared, base: &BaselineFit, out: &mut Candidates) {
    let (fit, held, gain) = (&prep.fit, &prep.held, prep.gain);
    let umax = fit.force_rows().fold(0.0_f64, |m, v| m.max(v.abs())) / gain;
    let mut best: Option<(f64, f64)> = None;
    for j in 1..=30 {
        let d = umax * 0.005 * j as f64;
        if let Some(Fitted { sse_f: sf, .. }) = base.cols.eval(
            &[],
            &[],
            &deadzone_force(fit, gain, d),
            &deadzone_force(held, gain, d),
        ) {
            if best.is_none_or(|b| sf < b.0) {
                best = Some((sf, d));
            }
        }
    }
    // a band at the grid's last point is no result: the best one may lie beyond it
    if let Some((_, d)) = best.filter(|b| b.1 < umax * 0.005 * 30.0) {
        out.offer(
            Cause::InputDeadzone,
            params(&[("deadzone_v", d)]),
            1,
            Design {
                ef: Vec::new(),
                eh: Vec::new(),
                yf: deadzone_force(fit, gain, d),
                yh: deadzone_force(held, gain, d),
            },
            base.cols.eval(
                &[],
                &[],
                &deadzone_force(fit, gain, d),
                &deadzone_force(held, gain, d),
            ),
        );
    }
}

/// The force of `p` [N] through a dead band of half width `d` on the input (`force / gain`),
/// decimated.
fn deadzone_force(p: &Part, gain: f64, d: f64) -> Vec<f64> {
    dec(
        p,
        p.force_rows()
            .map(|f| gain * deadband(f / gain, d))
            .collect(),
    )
}

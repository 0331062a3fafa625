//! Each run turned into inverse-dynamics force residuals per drive: positions filtered
//! zero-phase and differentiated, the model's drive rows and baseline friction subtracted from
//! the applied force, and the samples the force-domain fits may use marked.

use super::{CUTOFF_HZ, DECIMATE, EXCLUDE_S, MIN_SPEED};
use crane_ident::data::CraneRun;
use crane_ident::signal::{butter, diff2_central, diff_central, Filter};
use crane_model::friction::dry;
use crane_model::Params;

/// One run prepared for the force domain. Drives are indexed 0 X, 1 Y, 2 rope; positions
/// [m], velocities [m/s] and forces [N] are positive along each drive's positive direction.
pub(super) struct Prep<'a> {
    /// The recorded run.
    pub(super) run: &'a CraneRun,
    /// Baseline parameters of this run (its declared payload mass).
    pub(super) params: Params,
    /// Per sample: `true` when it belongs to the held-out part, `false` to the fitting part.
    pub(super) held: Vec<bool>,
    /// Filtered drive positions [m].
    pub(super) q: [Vec<f64>; 3],
    /// Filtered drive velocities [m/s].
    pub(super) v: [Vec<f64>; 3],
    /// Residual `K u - [M qdd + h + G] - f` per drive [N].
    pub(super) r: [Vec<f64>; 3],
    /// Derivative of the drive rows with respect to the payload mass [N/kg].
    pub(super) phi: [Vec<f64>; 3],
    /// Baseline dry magnitude at the sample, in the direction of motion [N].
    pub(super) cdry: [Vec<f64>; 3],
    /// Kept samples (moving, away from reversals and edges, decimated).
    pub(super) keep: [Vec<bool>; 3],
}

fn filt(f: &Filter, x: &[f64]) -> Vec<f64> {
    f.filtfilt(x)
}

/// The recorded voltage [V] as the central differences see it (mean of the two samples that
/// act on the interval), then filtered by `f`; same sign as the recording.
pub(super) fn drive_series(f: &Filter, u: &[f64]) -> Vec<f64> {
    let shifted: Vec<f64> = (0..u.len())
        .map(|k| 0.5 * (u[k] + u[k.saturating_sub(1)]))
        .collect();
    filt(f, &shifted)
}

/// The parameters of drive `i` (0 X, 1 Y, anything else the rope).
pub(super) fn axis_params(p: &Params, i: usize) -> &crane_model::AxisParams {
    match i {
        0 => &p.x,
        1 => &p.y,
        _ => &p.rope,
    }
}

/// Prepares `run` with the baseline `params` and the held-out mask `held` (one flag per
/// sample): filtered positions and velocities, force residuals [N], payload-mass
/// sensitivities [N/kg], baseline dry magnitudes [N] and the kept samples, per drive.
pub(super) fn prep<'a>(run: &'a CraneRun, params: Params, held: Vec<bool>) -> Prep<'a> {
    let dt = run.dt();
    let f = butter(4, CUTOFF_HZ * 2.0 * dt);
    let raw = [&run.x, &run.y, &run.l, &run.alpha, &run.beta];
    let qf: Vec<Vec<f64>> = raw.iter().map(|x| filt(&f, x)).collect();
    let vf: Vec<Vec<f64>> = qf.iter().map(|x| diff_central(x, dt)).collect();
    let af: Vec<Vec<f64>> = qf.iter().map(|x| diff2_central(x, dt)).collect();
    let n = run.len();
    let p = &params;
    let mp = p.payload_mass;
    let mx = p.trolley_mass + p.rail_mass + p.x.inertia;
    let my = p.trolley_mass + p.y.inertia;
    let jl = p.rope.inertia;
    let g = p.gravity;
    let mut r: [Vec<f64>; 3] = Default::default();
    let mut phi: [Vec<f64>; 3] = Default::default();
    let mut cdry: [Vec<f64>; 3] = Default::default();
    let uf: Vec<Vec<f64>> = (0..3).map(|i| drive_series(&f, &run.u[i])).collect();
    for k in 0..n {
        let (l, a, b) = (qf[2][k], qf[3][k], qf[4][k]);
        let (ld, ad, bd) = (vf[2][k], vf[3][k], vf[4][k]);
        let (xdd, ydd, ldd, add, bdd) = (af[0][k], af[1][k], af[2][k], af[3][k], af[4][k]);
        let (sa, ca) = a.sin_cos();
        let (sb, cb) = b.sin_cos();
        // rows per unit payload mass
        let hx = -l * ad * ad * sa * sb + 2.0 * l * ad * bd * ca * cb - l * bd * bd * sa * sb
            + 2.0 * ld * ad * sb * ca
            + 2.0 * ld * bd * sa * cb;
        let hy = -ad * (l * ad * ca + 2.0 * ld * sa);
        let hl = -l * (ad * ad + bd * bd * sa * sa);
        let px = xdd + sa * sb * ldd + l * ca * sb * add + l * sa * cb * bdd + hx;
        let py = ydd + ca * ldd - l * sa * add + hy;
        let pl = sa * sb * xdd + ca * ydd + ldd + hl - g * sa * cb;
        let rows = [mx * xdd + mp * px, my * ydd + mp * py, jl * ldd + mp * pl];
        let phis = [px, py, pl];
        for i in 0..3 {
            let ax = axis_params(p, i);
            let (qi, vi) = (qf[i][k], vf[i][k]);
            let (fr, c) = if vi > 0.0 {
                let c = dry(&ax.dry_pos, qi);
                (ax.viscous_pos * vi + c, c)
            } else if vi < 0.0 {
                let c = dry(&ax.dry_neg, qi);
                (ax.viscous_neg * vi - c, c)
            } else {
                (0.0, 0.0)
            };
            r[i].push(ax.gain * uf[i][k] - rows[i] - fr);
            phi[i].push(phis[i]);
            cdry[i].push(c);
        }
    }
    let w = (EXCLUDE_S / dt).round() as usize;
    let edge = (0.3 / dt).round() as usize;
    let keep: [Vec<bool>; 3] = std::array::from_fn(|i| {
        let v = &vf[i];
        let mut keep = vec![true; n];
        let mut last: Option<usize> = None;
        for k in 0..n {
            if v[k].abs() < MIN_SPEED[i] || (k > 0 && v[k].signum() != v[k - 1].signum()) {
                last = Some(k);
            }
            if matches!(last, Some(s) if k - s <= w) {
                keep[k] = false;
            }
        }
        let mut next: Option<usize> = None;
        for k in (0..n).rev() {
            if v[k].abs() < MIN_SPEED[i] || (k + 1 < n && v[k].signum() != v[k + 1].signum()) {
                next = Some(k);
            }
            if matches!(next, Some(s) if s - k <= w) {
                keep[k] = false;
            }
        }
        for k in 0..n {
            if k < edge || k + edge >= n || k % DECIMATE != 0 {
                keep[k] = false;
            }
        }
        keep
    });
    let q: [Vec<f64>; 3] = std::array::from_fn(|i| qf[i].clone());
    let v: [Vec<f64>; 3] = std::array::from_fn(|i| vf[i].clone());
    Prep {
        run,
        params,
        held,
        q,
        v,
        r,
        phi,
        cdry,
        keep,
    }
}

//! The kept samples of one drive and one part (fitting or held-out), gathered over the runs in
//! run order: what the force-domain fits see.

use super::residual::Prep;

/// Gathered samples of one drive and one part, in the units and signs of [`Prep`].
#[derive(Default, Clone)]
pub(super) struct Gathered {
    /// Filtered position [m].
    pub(super) q: Vec<f64>,
    /// Filtered velocity [m/s].
    pub(super) v: Vec<f64>,
    /// Force residual `K u - [M qdd + h + G] - f` [N].
    pub(super) r: Vec<f64>,
    /// Derivative of the drive row with respect to the payload mass [N/kg].
    pub(super) phi: Vec<f64>,
    /// Baseline dry magnitude in the direction of motion [N].
    pub(super) cdry: Vec<f64>,
}

/// The kept samples of drive `i` on the held-out part (`held`) or the fitting part.
pub(super) fn gather(preps: &[Prep], i: usize, held: bool) -> Gathered {
    let mut g = Gathered::default();
    for p in preps {
        for k in 0..p.run.len() {
            if p.keep[i][k] && p.held[k] == held {
                g.q.push(p.q[i][k]);
                g.v.push(p.v[i][k]);
                g.r.push(p.r[i][k]);
                g.phi.push(p.phi[i][k]);
                g.cdry.push(p.cdry[i][k]);
            }
        }
    }
    g
}

/// Gathers a per-run full-length series (computed by `f`) on the kept samples of a part.
pub(super) fn gather_series(
    preps: &[Prep],
    i: usize,
    held: bool,
    f: &dyn Fn(&Prep) -> Vec<f64>,
) -> Vec<f64> {
    let mut out = Vec::new();
    for p in preps {
        let s = f(p);
        for k in 0..p.run.len() {
            if p.keep[i][k] && p.held[k] == held {
                out.push(s[k]);
            }
        }
    }
    out
}

/// Sum of squares of `x` (in the square of its unit, e.g. [N^2] for force residuals).
pub(super) fn sumsq(x: &[f64]) -> f64 {
    x.iter().map(|v| v * v).sum()
}

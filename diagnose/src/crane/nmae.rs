//! The simulated position error: NMAE per axis against the measured positions, its noise
//! floor, and the floored log-ratio score of an extension against the baseline.

use super::residual::Prep;
use super::simulate::simulate;
use super::{Ext, FLOOR_FACTOR, PENALTY};
use crane_ident::data::Constants;
use crane_model::Extensions;

/// The normalisation and noise level of the NMAE per axis (X, Y, rope).
pub(super) struct Scales {
    /// Travel of each axis [m]: the NMAE is the mean absolute error over it.
    pub(super) ranges: [f64; 3],
    /// Encoder quantisation NMAE [%] (a quarter of one count over the travel).
    pub(super) noise: [f64; 3],
    /// Noise floor of the simulated NMAE [%]: `FLOOR_FACTOR` times `noise`.
    pub(super) floor: [f64; 3],
}

impl Scales {
    /// The scales of the rig constants `c` (travels [m], pulley radii [m], encoder pulses).
    pub(super) fn from_constants(c: &Constants) -> Scales {
        let ranges = [
            c.x_range_m[1] - c.x_range_m[0],
            c.y_range_m[1] - c.y_range_m[0],
            c.l_range_m[1] - c.l_range_m[0],
        ];
        let radii = [
            c.pulley_radius_x_m,
            c.pulley_radius_y_m,
            c.pulley_radius_l_m,
        ];
        let noise: [f64; 3] = std::array::from_fn(|i| {
            let res = 2.0 * std::f64::consts::PI * radii[i] / c.encoder_pulses;
            100.0 * res / 4.0 / ranges[i]
        });
        let floor = noise.map(|x| x * FLOOR_FACTOR);
        Scales {
            ranges,
            noise,
            floor,
        }
    }
}

/// The prepared runs with what scoring their simulation needs.
pub(super) struct Ctx<'a> {
    /// The prepared runs, in data-set order.
    pub(super) preps: Vec<Prep<'a>>,
    /// Travel of each axis [m] ([`Scales::ranges`]).
    pub(super) ranges: [f64; 3],
    /// Noise floor of the NMAE per axis [%] ([`Scales::floor`]).
    pub(super) floor: [f64; 3],
}

impl Ctx<'_> {
    /// Held-out (or fitting) NMAE per axis [%] of the simulation with `e` on `axis`
    /// (`None`: the baseline); `None` if a simulation fails.
    pub(super) fn nmae(&self, e: Option<(&Ext, usize)>, held: bool) -> Option<[f64; 3]> {
        let mut acc = [0.0; 3];
        let mut n = 0usize;
        for p in &self.preps {
            if !p.held.contains(&held) {
                continue;
            }
            let mut params = p.params;
            let mut ext = Extensions::default();
            if let Some((e, axis)) = e {
                e.apply(axis, &mut params, &mut ext);
            }
            let sim = simulate(p.run, &params, &ext)?;
            for k in 0..p.run.len() {
                if p.held[k] != held {
                    continue;
                }
                let meas = [p.run.x[k], p.run.y[k], p.run.l[k]];
                for i in 0..3 {
                    acc[i] += (sim[k][i] - meas[i]).abs();
                }
                n += 1;
            }
        }
        if n == 0 {
            return None;
        }
        Some([0, 1, 2].map(|i| 100.0 * acc[i] / n as f64 / self.ranges[i]))
    }

    /// Score of an extension with `k` extra parameters [dimensionless]: the sum over the
    /// axes of `ln(after / before)` of the NMAE, each floored at its noise floor, plus
    /// `PENALTY` per parameter; negative when the extension cuts the error.
    pub(super) fn score(&self, before: &[f64; 3], after: &[f64; 3], k: usize) -> f64 {
        let mut s = 0.0;
        for i in 0..3 {
            s += (after[i].max(self.floor[i]) / before[i].max(self.floor[i])).ln();
        }
        s + PENALTY * k as f64
    }
}

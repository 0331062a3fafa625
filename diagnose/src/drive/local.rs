//! Where along the travel a model's sliding samples need more dry friction than it has: the
//! sites tried for a localized friction bump.
//!
//! On sliding samples the model's force balance leaves the residual
//! `r = F - P(x) - J a - sign(v) Fk - D v + offset`, which a dry-friction bump `b(x)` makes
//! `sign(v) b(x)`. Binned over the travel, `sign(v) r` peaks where the bump is: the peak bin
//! gives the centre (above the median bin, which the levels already carry), its half-height
//! width the kernel's half-width (`(1 - s^2)^2` is one half at `s = 0.54`). The sites tried
//! ([`sites`]) are that guess and its neighbours; the amplitude is fitted by the sliding
//! least squares at each ([`super::estimate::Structure::bump`]) and the site chosen by the
//! fitting runs' simulation.
//!
//! Work: one pass over the fitting runs' samples, [`BINS`] bins.

use super::estimate::{applied_input, restoring_shape, BumpSite, Estimate};
use super::prep::{Prepared, Thresholds};
use crane_model::drive::{Motion, PositionForce};

/// Bins over the travel of the sliding samples.
pub const BINS: usize = 32;
/// Fewest sliding samples a bin needs to count.
pub const MIN_BIN_SAMPLES: usize = 10;
/// Centre offsets tried around the guess, in half-widths of the guess.
pub const CENTER_STEPS: [f64; 5] = [-0.5, -0.25, 0.0, 0.25, 0.5];
/// Half-widths tried, as multiples of the guess.
pub const WIDTH_FACTORS: [f64; 3] = [0.6, 1.0, 1.6];

/// The peak of the binned sliding residual: a site and the excess friction there [force
/// units], or `None` when the sliding samples cover too little of the travel or no bin
/// stands above the others.
pub fn guess(
    est: &Estimate,
    fit: &[&Prepared],
    th: &Thresholds,
    motion: Motion,
) -> Option<(BumpSite, f64)> {
    let p = &est.params;
    let (k, c) = match p.position_force {
        PositionForce::Spring { stiffness, center }
        | PositionForce::Pendulum { stiffness, center } => (stiffness, center),
        PositionForce::None => (0.0, 0.0),
    };
    let mut rows: Vec<(f64, f64)> = Vec::new(); // (x, excess friction)
    for r in fit {
        for i in 0..r.run.x.len() {
            let v = r.v[i];
            if v.abs() <= th.v_slide {
                continue;
            }
            let x = r.run.x[i];
            let f = applied_input(&r.run.u, i, &est.structure);
            let f = f - est.structure.load * v.signum() * f.abs() + p.offset;
            let (fk, d) = if v > 0.0 {
                (p.kinetic_pos, p.viscous_pos)
            } else {
                (p.kinetic_neg, p.viscous_neg)
            };
            let res = f
                - k * restoring_shape(motion, x, c)
                - p.inertia * r.a[i]
                - v.signum() * fk
                - d * v;
            rows.push((x, v.signum() * res));
        }
    }
    let (lo, hi) = rows
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), r| {
            (l.min(r.0), h.max(r.0))
        });
    if rows.len() < BINS * MIN_BIN_SAMPLES || hi.is_nan() || hi - lo <= 4.0 * th.quantum {
        return None;
    }
    let width = (hi - lo) / BINS as f64;
    let mut sum = [0.0f64; BINS];
    let mut n = [0usize; BINS];
    for &(x, e) in &rows {
        let b = (((x - lo) / width) as usize).min(BINS - 1);
        sum[b] += e;
        n[b] += 1;
    }
    let means: Vec<Option<f64>> = (0..BINS)
        .map(|b| (n[b] >= MIN_BIN_SAMPLES).then(|| sum[b] / n[b] as f64))
        .collect();
    let mut vals: Vec<f64> = means.iter().flatten().copied().collect();
    if vals.len() < 4 {
        return None;
    }
    vals.sort_by(f64::total_cmp);
    let base = vals[vals.len() / 2];
    let (peak, amp) = means
        .iter()
        .enumerate()
        .filter_map(|(b, m)| m.map(|m| (b, m - base)))
        .max_by(|a, b| a.1.total_cmp(&b.1))?;
    if amp.is_nan() || amp <= 0.0 {
        return None;
    }
    // half height on each side of the peak
    let above = |b: usize| means[b].is_some_and(|m| m - base >= 0.5 * amp);
    let (mut l, mut r) = (peak, peak);
    while l > 0 && above(l - 1) {
        l -= 1;
    }
    while r + 1 < BINS && above(r + 1) {
        r += 1;
    }
    let site = BumpSite {
        center: lo + (peak as f64 + 0.5) * width,
        half_width: 0.5 * (r - l + 1) as f64 * width / 0.54,
    };
    Some((site, amp))
}

/// The sites tried around a guess: [`CENTER_STEPS`] x [`WIDTH_FACTORS`].
pub fn sites(g: BumpSite) -> Vec<BumpSite> {
    let mut v = Vec::with_capacity(CENTER_STEPS.len() * WIDTH_FACTORS.len());
    for dc in CENTER_STEPS {
        for f in WIDTH_FACTORS {
            v.push(BumpSite {
                center: g.center + dc * g.half_width,
                half_width: f * g.half_width,
            });
        }
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_kernel_is_one_at_the_centre_half_at_0_54_and_zero_outside() {
        let s = BumpSite {
            center: 0.3,
            half_width: 0.02,
        };
        assert_eq!(s.kernel(0.3), 1.0);
        assert!((s.kernel(0.3 + 0.54 * 0.02) - 0.5).abs() < 0.01);
        assert_eq!(s.kernel(0.33), 0.0);
        assert_eq!(sites(s).len(), 15);
        assert!(sites(s).iter().all(|t| t.half_width > 0.0));
    }
}

//! Bayesian linear regression of a dry-friction polynomial over an axis, and the paper's
//! active learning: posterior update, acquisition = predictive standard deviation times the
//! squared distance to the nearest measured point over a fine candidate grid, stop on a
//! variance threshold, a point budget or a time limit.
//!
//! The polynomial is fitted in the normalised coordinate `s = (p - lo) / (hi - lo)` (well
//! conditioned) with a zero-mean Gaussian prior of standard deviation `prior_std` on each
//! coefficient, and reported in powers of `p` [m] like the model's `Cbar(p)`.

use crate::linalg::spd_inverse;
use crate::rng::Rng;
use serde::{Deserialize, Serialize};
use std::time::{Duration, Instant};

/// Options of the regression and of the active learning.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct BlrOptions {
    /// Polynomial degree (4 in the paper).
    pub degree: usize,
    /// Prior standard deviation of each normalised coefficient [N].
    pub prior_std: f64,
    /// Candidate positions of the acquisition grid.
    pub candidates: usize,
    /// Margin kept from each end of the axis for probes [m] (motion into an end stop is
    /// impossible, so the ends themselves cannot be probed in both directions).
    pub margin: f64,
    /// Random initial probes before the acquisition takes over.
    pub initial: usize,
    /// Point budget per axis and direction.
    pub budget: usize,
    /// Stop when the largest predictive standard deviation over the grid is below this [N].
    pub std_threshold: f64,
    /// Stop when this much wall time has passed [s] (0: no limit).
    pub time_limit_s: f64,
}

impl Default for BlrOptions {
    fn default() -> Self {
        BlrOptions {
            degree: 4,
            prior_std: 10.0,
            candidates: 201,
            margin: 0.005,
            initial: 1,
            budget: 15,
            std_threshold: 0.02,
            time_limit_s: 0.0,
        }
    }
}

/// Posterior of the polynomial coefficients given breakaway samples.
#[derive(Clone, Debug, PartialEq)]
pub struct Blr {
    lo: f64,
    hi: f64,
    degree: usize,
    prior_var: f64,
    noise_var: f64,
    /// Measured positions [m].
    pub xs: Vec<f64>,
    /// Measured breakaway forces [N].
    pub ys: Vec<f64>,
    mean: Vec<f64>,
    cov: Vec<Vec<f64>>,
}

impl Blr {
    /// Prior over `[lo, hi]` with known noise variance [N^2].
    pub fn new(lo: f64, hi: f64, degree: usize, prior_std: f64, noise_var: f64) -> Self {
        let p = degree + 1;
        let prior_var = prior_std * prior_std;
        let mut cov = vec![vec![0.0; p]; p];
        for (i, row) in cov.iter_mut().enumerate() {
            row[i] = prior_var;
        }
        Blr {
            lo,
            hi,
            degree,
            prior_var,
            noise_var,
            xs: Vec::new(),
            ys: Vec::new(),
            mean: vec![0.0; p],
            cov,
        }
    }

    fn phi(&self, p: f64) -> Vec<f64> {
        let s = (p - self.lo) / (self.hi - self.lo);
        let mut v = Vec::with_capacity(self.degree + 1);
        let mut a = 1.0;
        for _ in 0..=self.degree {
            v.push(a);
            a *= s;
        }
        v
    }

    /// Adds a sample and updates the posterior (recomputed from all samples).
    pub fn add(&mut self, p: f64, y: f64) {
        self.xs.push(p);
        self.ys.push(y);
        self.update();
    }

    fn update(&mut self) {
        let n = self.degree + 1;
        let mut prec = vec![vec![0.0; n]; n];
        let mut rhs = vec![0.0; n];
        for (i, row) in prec.iter_mut().enumerate() {
            row[i] = 1.0 / self.prior_var;
        }
        for (&x, &y) in self.xs.iter().zip(&self.ys) {
            let f = self.phi(x);
            for i in 0..n {
                for j in 0..n {
                    prec[i][j] += f[i] * f[j] / self.noise_var;
                }
                rhs[i] += f[i] * y / self.noise_var;
            }
        }
        if let Some(cov) = spd_inverse(&prec) {
            self.mean = (0..n)
                .map(|i| (0..n).map(|j| cov[i][j] * rhs[j]).sum())
                .collect();
            self.cov = cov;
        }
    }

    /// Posterior mean and standard deviation of the friction curve at `p` (the uncertainty
    /// of the curve itself, without the probe noise).
    pub fn predict(&self, p: f64) -> (f64, f64) {
        let f = self.phi(p);
        let n = f.len();
        let m: f64 = f.iter().zip(&self.mean).map(|(a, b)| a * b).sum();
        let mut v = 0.0;
        for i in 0..n {
            for j in 0..n {
                v += f[i] * self.cov[i][j] * f[j];
            }
        }
        (m, v.max(0.0).sqrt())
    }

    /// Standard deviation of a new breakaway measurement at `p` (curve and probe noise).
    pub fn predictive_measurement_std(&self, p: f64) -> f64 {
        let (_, s) = self.predict(p);
        (s * s + self.noise_var).sqrt()
    }

    /// Acquisition score at `p`: predictive standard deviation times the squared distance to
    /// the nearest measured point (the standard deviation alone before any measurement).
    pub fn acquisition(&self, p: f64) -> f64 {
        let (_, s) = self.predict(p);
        let d = self
            .xs
            .iter()
            .map(|x| (x - p).abs())
            .fold(f64::INFINITY, f64::min);
        if d.is_finite() {
            s * d * d
        } else {
            s
        }
    }

    /// The candidate maximising the acquisition (first one on ties).
    pub fn next_point(&self, candidates: &[f64]) -> f64 {
        let mut best = candidates[0];
        let mut score = f64::NEG_INFINITY;
        for &c in candidates {
            let a = self.acquisition(c);
            if a > score {
                score = a;
                best = c;
            }
        }
        best
    }

    /// Largest predictive standard deviation over `grid`.
    pub fn max_std(&self, grid: &[f64]) -> f64 {
        grid.iter().map(|&p| self.predict(p).1).fold(0.0, f64::max)
    }

    /// Coefficients `c0..c_degree` in powers of `p` [m] and their covariance.
    pub fn coefficients(&self) -> (Vec<f64>, Vec<Vec<f64>>) {
        // s = (p - lo) / w: s^k = sum_j binom(k, j) p^j (-lo)^(k-j) / w^k
        let n = self.degree + 1;
        let w = self.hi - self.lo;
        let mut t = vec![vec![0.0; n]; n]; // c = T a
        for k in 0..n {
            let mut binom = 1.0;
            for j in 0..=k {
                if j > 0 {
                    binom = binom * (k - j + 1) as f64 / j as f64;
                }
                t[j][k] += binom * ipow(-self.lo, k - j) / ipow(w, k);
            }
        }
        let c: Vec<f64> = (0..n)
            .map(|i| (0..n).map(|k| t[i][k] * self.mean[k]).sum())
            .collect();
        let mut cov = vec![vec![0.0; n]; n];
        for i in 0..n {
            for j in 0..n {
                let mut s = 0.0;
                for a in 0..n {
                    for b in 0..n {
                        s += t[i][a] * self.cov[a][b] * t[j][b];
                    }
                }
                cov[i][j] = s;
            }
        }
        (c, cov)
    }

    /// The axis range `[lo, hi]`.
    pub fn range(&self) -> (f64, f64) {
        (self.lo, self.hi)
    }
}

/// `x^n` by repeated multiplication (same bits in every build profile, unlike `powi`).
fn ipow(x: f64, n: usize) -> f64 {
    (0..n).fold(1.0, |a, _| a * x)
}

/// Equally spaced points over `[a, b]` (both ends included).
pub fn linspace(a: f64, b: f64, n: usize) -> Vec<f64> {
    if n == 1 {
        return vec![0.5 * (a + b)];
    }
    (0..n)
        .map(|k| a + (b - a) * k as f64 / (n - 1) as f64)
        .collect()
}

/// Why the active learning stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StopReason {
    /// The largest predictive standard deviation fell below the threshold.
    Threshold,
    /// The point budget was used.
    Budget,
    /// The time limit passed.
    Time,
}

/// The active-learning loop: `initial` random probes (seeded), then the acquisition's best
/// candidate, until the threshold, budget or time stops it. `measure(p)` probes the rig at
/// `p` and returns the breakaway force [N] and the position actually measured.
pub fn active_learning<E>(
    blr: &mut Blr,
    opt: &BlrOptions,
    rng: &mut Rng,
    mut measure: impl FnMut(f64) -> Result<(f64, f64), E>,
) -> Result<StopReason, E> {
    let start = Instant::now();
    let (lo, hi) = blr.range();
    let grid = linspace(lo + opt.margin, hi - opt.margin, opt.candidates);
    loop {
        if blr.xs.len() >= opt.budget {
            return Ok(StopReason::Budget);
        }
        if opt.time_limit_s > 0.0 && start.elapsed() > Duration::from_secs_f64(opt.time_limit_s) {
            return Ok(StopReason::Time);
        }
        if blr.xs.len() >= opt.initial && blr.max_std(&grid) < opt.std_threshold {
            return Ok(StopReason::Threshold);
        }
        let p = if blr.xs.len() < opt.initial {
            rng.range(lo + opt.margin, hi - opt.margin)
        } else {
            blr.next_point(&grid)
        };
        let (force, at) = measure(p)?;
        blr.add(at, force);
    }
}

/// A friction curve with its 95 % bands on a grid.
///
/// Two bands, because they answer two questions:
/// - pointwise (`lower`, `upper` = mean -+ 1.96 std): at any one position the true friction
///   lies inside with probability 0.95. Along the axis the errors of a 5-coefficient fit are
///   strongly correlated, so in a given realisation the truth leaves this band over whole
///   stretches: even with an exact model and known noise it holds the truth over at least
///   90 % of the axis in only about 83 % of realisations.
/// - simultaneous (`simultaneous_lower`, `simultaneous_upper` = mean -+ c std): the whole
///   true curve lies inside over the entire axis with probability 0.95. `c` follows from the
///   posterior covariance by the tube formula ([`Blr::simultaneous_multiplier`]); it is the
///   band for statements about the curve over the range.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FrictionCurve {
    /// Positions [m].
    pub position: Vec<f64>,
    /// Posterior mean [N].
    pub mean: Vec<f64>,
    /// Posterior standard deviation of the curve (without probe noise) [N].
    pub std: Vec<f64>,
    /// Lower pointwise 95 % band (mean - 1.96 std) [N].
    pub lower: Vec<f64>,
    /// Upper pointwise 95 % band (mean + 1.96 std) [N].
    pub upper: Vec<f64>,
    /// Multiplier `c` of the simultaneous 95 % band (>= 1.96).
    pub simultaneous_multiplier: f64,
    /// Lower simultaneous 95 % band over the axis (mean - c std) [N].
    pub simultaneous_lower: Vec<f64>,
    /// Upper simultaneous 95 % band over the axis (mean + c std) [N].
    pub simultaneous_upper: Vec<f64>,
}

/// `1 - Phi(c)`, the upper tail of the standard normal distribution.
fn normal_tail(c: f64) -> f64 {
    0.5 * libm::erfc(c / core::f64::consts::SQRT_2)
}

/// Points of the grid on which [`Blr::tube_length`] measures the curve.
const TUBE_POINTS: usize = 1001;

impl Blr {
    /// Length `kappa0` [rad] of the path traced on the unit sphere by the normalised error
    /// direction `L' phi(p) / |L' phi(p)|` (`L L'` = posterior covariance) as `p` runs over
    /// the axis: the angle between neighbours is `acos(phi_k' C phi_k+1 / (s_k s_k+1))`.
    pub fn tube_length(&self) -> f64 {
        let grid = linspace(self.lo, self.hi, TUBE_POINTS);
        let n = self.degree + 1;
        let cphi = |f: &[f64]| -> Vec<f64> {
            (0..n)
                .map(|i| (0..n).map(|j| self.cov[i][j] * f[j]).sum())
                .collect()
        };
        let mut prev: Option<(Vec<f64>, Vec<f64>, f64)> = None;
        let mut len = 0.0;
        for p in grid {
            let f = self.phi(p);
            let cf = cphi(&f);
            let s = f.iter().zip(&cf).map(|(a, b)| a * b).sum::<f64>().sqrt();
            if let Some((_, pcf, ps)) = &prev {
                let c: f64 = f.iter().zip(pcf).map(|(a, b)| a * b).sum::<f64>() / (s * ps);
                len += c.clamp(-1.0, 1.0).acos();
            }
            prev = Some((f, cf, s));
        }
        len
    }

    /// Multiplier `c` such that `mean -+ c std` holds the whole curve over `[lo, hi]` with
    /// probability `level` under the posterior: the root of the tube formula for a Gaussian
    /// process with finite-dimensional (here polynomial) paths over an interval (Sun and
    /// Loader 1994; Naiman 1986), `1 - level = kappa0 / pi exp(-c^2 / 2) + 2 (1 - Phi(c))`,
    /// `kappa0` from [`Blr::tube_length`]. At least the pointwise multiplier.
    pub fn simultaneous_multiplier(&self, level: f64) -> f64 {
        let k0 = self.tube_length();
        let excess =
            |c: f64| k0 / core::f64::consts::PI * (-0.5 * c * c).exp() + 2.0 * normal_tail(c);
        let alpha = 1.0 - level;
        // excess is decreasing in c; bisection on [0, 20]
        let (mut lo, mut hi) = (0.0, 20.0);
        for _ in 0..80 {
            let mid = 0.5 * (lo + hi);
            if excess(mid) > alpha {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        0.5 * (lo + hi)
    }

    /// The curve on `n` points over the axis with its pointwise and simultaneous 95 % bands.
    pub fn curve(&self, n: usize) -> FrictionCurve {
        let position = linspace(self.lo, self.hi, n);
        let c = self.simultaneous_multiplier(0.95);
        let mut out = FrictionCurve {
            position: position.clone(),
            mean: Vec::with_capacity(n),
            std: Vec::with_capacity(n),
            lower: Vec::with_capacity(n),
            upper: Vec::with_capacity(n),
            simultaneous_multiplier: c,
            simultaneous_lower: Vec::with_capacity(n),
            simultaneous_upper: Vec::with_capacity(n),
        };
        for p in position {
            let (m, s) = self.predict(p);
            out.mean.push(m);
            out.std.push(s);
            out.lower.push(m - 1.96 * s);
            out.upper.push(m + 1.96 * s);
            out.simultaneous_lower.push(m - c * s);
            out.simultaneous_upper.push(m + c * s);
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn posterior_recovers_a_polynomial_and_coefficients_convert_to_metres() {
        let truth = [1.23, 0.29, -1.95, 3.98, 5.02];
        let f = |p: f64| crane_model::friction::horner(&truth, p);
        let mut b = Blr::new(0.0, 0.505, 4, 3.0, 1e-8);
        for p in linspace(0.0, 0.505, 30) {
            b.add(p, f(p));
        }
        let (c, cov) = b.coefficients();
        for (x, t) in c.iter().zip(truth) {
            assert!((x - t).abs() < 1e-2, "{c:?}");
        }
        assert!(cov[0][0] > 0.0 && cov[4][4] > cov[0][0]);
        let (m, s) = b.predict(0.3);
        assert!((m - f(0.3)).abs() < 1e-4 && s < 1e-3);
        // with an offset range the conversion still holds
        let mut b = Blr::new(0.1, 0.6, 4, 3.0, 1e-8);
        for p in linspace(0.1, 0.6, 30) {
            b.add(p, f(p));
        }
        let (c, _) = b.coefficients();
        for (x, t) in c.iter().zip(truth) {
            assert!((x - t).abs() < 1e-2, "{c:?}");
        }
    }

    #[test]
    fn acquisition_avoids_measured_points_and_prefers_uncertainty() {
        let mut b = Blr::new(0.0, 0.5, 4, 3.0, 0.01);
        b.add(0.25, 1.0);
        b.add(0.0, 1.0);
        let grid = linspace(0.0, 0.5, 101);
        let p = b.next_point(&grid);
        // the far, unmeasured end is where the curve is least known
        assert!((p - 0.5).abs() < 1e-12, "{p}");
        assert_eq!(b.acquisition(0.25), 0.0);
    }

    #[test]
    fn simultaneous_multiplier_lies_between_pointwise_and_scheffe() {
        // a constant has fully correlated errors along the axis: simultaneous = pointwise
        let mut b = Blr::new(0.0, 0.5, 0, 10.0, 0.01);
        b.add(0.1, 1.0);
        b.add(0.4, 1.2);
        assert!(b.tube_length() < 1e-6);
        assert!((b.simultaneous_multiplier(0.95) - 1.959964).abs() < 1e-5);
        // degree 4: above 1.96, below Scheffe's sqrt(chi2_5(0.95)) = 3.327 (which covers
        // every direction of the coefficient space, not only the axis)
        let mut b = Blr::new(0.0, 0.5, 4, 10.0, 0.01);
        for p in linspace(0.0, 0.5, 15) {
            b.add(p, 1.0);
        }
        let c = b.simultaneous_multiplier(0.95);
        assert!(c > 2.3 && c < 3.327, "{c}");
        // the band's edges are mean -+ c std
        let curve = b.curve(11);
        assert_eq!(curve.simultaneous_multiplier, c);
        for k in 0..11 {
            let w = curve.simultaneous_upper[k] - curve.mean[k];
            assert!((w - c * curve.std[k]).abs() < 1e-12);
            assert!((curve.upper[k] - curve.mean[k] - 1.96 * curve.std[k]).abs() < 1e-12);
        }
        // a higher level needs a larger multiplier
        assert!(b.simultaneous_multiplier(0.99) > c);
    }
}

//! Small dense linear algebra: Householder least squares with the usual statistics,
//! Gaussian elimination, symmetric inverses. Sizes here are a handful of parameters against
//! up to some hundred thousand samples, so plain loops are enough.

use serde::{Deserialize, Serialize};

/// Solves `A x = b` by Gaussian elimination with partial pivoting; `None` if singular.
pub fn solve_dense(mut a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Option<Vec<f64>> {
    let n = b.len();
    for k in 0..n {
        let piv = (k..n).max_by(|&i, &j| a[i][k].abs().total_cmp(&a[j][k].abs()))?;
        if a[piv][k].abs() < 1e-300 || !a[piv][k].is_finite() {
            return None;
        }
        a.swap(k, piv);
        b.swap(k, piv);
        for i in k + 1..n {
            let f = a[i][k] / a[k][k];
            if f != 0.0 {
                for j in k..n {
                    a[i][j] -= f * a[k][j];
                }
                b[i] -= f * b[k];
            }
        }
    }
    let mut x = vec![0.0; n];
    for i in (0..n).rev() {
        let mut s = b[i];
        for j in i + 1..n {
            s -= a[i][j] * x[j];
        }
        x[i] = s / a[i][i];
    }
    Some(x)
}

/// Inverse of a symmetric positive-definite matrix by Cholesky; `None` if not SPD.
pub fn spd_inverse(a: &[Vec<f64>]) -> Option<Vec<Vec<f64>>> {
    let n = a.len();
    let mut l = vec![vec![0.0; n]; n];
    for i in 0..n {
        for j in 0..=i {
            let mut s = a[i][j];
            for k in 0..j {
                s -= l[i][k] * l[j][k];
            }
            if i == j {
                if s.is_nan() || s <= 0.0 {
                    return None;
                }
                l[i][i] = s.sqrt();
            } else {
                l[i][j] = s / l[j][j];
            }
        }
    }
    // inv(L)
    let mut li = vec![vec![0.0; n]; n];
    for i in 0..n {
        li[i][i] = 1.0 / l[i][i];
        for j in 0..i {
            let mut s = 0.0;
            for k in j..i {
                s -= l[i][k] * li[k][j];
            }
            li[i][j] = s / l[i][i];
        }
    }
    let mut inv = vec![vec![0.0; n]; n];
    for i in 0..n {
        for j in 0..n {
            let mut s = 0.0;
            for k in i.max(j)..n {
                s += li[k][i] * li[k][j];
            }
            inv[i][j] = s;
        }
    }
    Some(inv)
}

/// A least-squares fit `y ~ X theta` with its statistics.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LsFit {
    /// Parameter names, in column order.
    pub names: Vec<String>,
    /// Estimates.
    pub theta: Vec<f64>,
    /// Standard errors `sigma sqrt(diag((X^T X)^-1))`, `sigma` the residual standard deviation
    /// (as the EMPS script: `std(error)`; here with `n - p` degrees of freedom).
    pub std_err: Vec<f64>,
    /// Correlation matrix of the estimates.
    pub correlation: Vec<Vec<f64>>,
    /// Residual standard deviation.
    pub sigma: f64,
    /// Relative error `100 ||y - X theta|| / ||y||` [%].
    pub rel_err_pct: f64,
    /// Number of samples used.
    pub n: usize,
    /// Condition number estimate of `X` (ratio of largest to smallest |R_ii|, a lower bound).
    pub cond_est: f64,
}

/// Why a least-squares problem has no answer.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum LsError {
    /// Fewer samples than parameters.
    #[error("least squares `{what}`: {n} samples for {p} parameters")]
    TooFewSamples {
        /// Which problem.
        what: String,
        /// Samples.
        n: usize,
        /// Parameters.
        p: usize,
    },
    /// The regressor matrix is rank deficient (a column is not excited by the data).
    #[error("least squares `{what}`: regressor `{column}` is not excited (rank deficient)")]
    RankDeficient {
        /// Which problem.
        what: String,
        /// Offending column.
        column: String,
    },
}

/// Ordinary least squares by Householder QR (what MATLAB's backslash does for a tall matrix).
/// `cols` are the regressor columns, all of the length of `y`.
pub fn lstsq(what: &str, names: &[&str], cols: &[Vec<f64>], y: &[f64]) -> Result<LsFit, LsError> {
    let p = cols.len();
    let n = y.len();
    if n <= p {
        return Err(LsError::TooFewSamples {
            what: what.into(),
            n,
            p,
        });
    }
    // Column-major copy.
    let mut a: Vec<Vec<f64>> = cols.to_vec();
    let mut qty = y.to_vec();
    let mut rdiag = vec![0.0; p];
    for k in 0..p {
        let norm = a[k][k..].iter().map(|v| v * v).sum::<f64>().sqrt();
        let scale = a[k].iter().map(|v| v.abs()).fold(0.0, f64::max);
        if norm <= 1e-12 * scale.max(1e-300) || norm == 0.0 {
            return Err(LsError::RankDeficient {
                what: what.into(),
                column: names.get(k).copied().unwrap_or("?").into(),
            });
        }
        let alpha = if a[k][k] > 0.0 { -norm } else { norm };
        let mut v: Vec<f64> = a[k][k..].to_vec();
        v[0] -= alpha;
        let vnorm2: f64 = v.iter().map(|x| x * x).sum();
        rdiag[k] = alpha;
        if vnorm2 > 0.0 {
            for col in a.iter_mut().skip(k) {
                let dot: f64 = col[k..].iter().zip(&v).map(|(c, vi)| c * vi).sum();
                let f = 2.0 * dot / vnorm2;
                for (c, vi) in col[k..].iter_mut().zip(&v) {
                    *c -= f * vi;
                }
            }
            let dot: f64 = qty[k..].iter().zip(&v).map(|(c, vi)| c * vi).sum();
            let f = 2.0 * dot / vnorm2;
            for (c, vi) in qty[k..].iter_mut().zip(&v) {
                *c -= f * vi;
            }
        }
        a[k][k] = alpha;
    }
    let rmax = rdiag.iter().map(|v| v.abs()).fold(0.0, f64::max);
    let rmin = rdiag.iter().map(|v| v.abs()).fold(f64::INFINITY, f64::min);
    for (k, r) in rdiag.iter().enumerate() {
        if r.abs() < 1e-13 * rmax {
            return Err(LsError::RankDeficient {
                what: what.into(),
                column: names.get(k).copied().unwrap_or("?").into(),
            });
        }
    }
    let mut theta = vec![0.0; p];
    for i in (0..p).rev() {
        let mut s = qty[i];
        for j in i + 1..p {
            s -= a[j][i] * theta[j];
        }
        theta[i] = s / a[i][i];
    }
    let mut ss = 0.0;
    let mut yy = 0.0;
    for (k, yk) in y.iter().enumerate() {
        let pred: f64 = cols.iter().zip(&theta).map(|(c, t)| c[k] * t).sum();
        ss += (yk - pred) * (yk - pred);
        yy += yk * yk;
    }
    let sigma = (ss / (n - p) as f64).sqrt();
    // (X^T X)^-1 = R^-1 R^-T
    let mut rinv = vec![vec![0.0; p]; p];
    for i in (0..p).rev() {
        rinv[i][i] = 1.0 / a[i][i];
        for j in i + 1..p {
            let mut s = 0.0;
            for k in i + 1..=j {
                s -= a[k][i] * rinv[k][j];
            }
            rinv[i][j] = s / a[i][i];
        }
    }
    let mut cov = vec![vec![0.0; p]; p];
    for i in 0..p {
        for j in 0..p {
            let mut s = 0.0;
            for k in i.max(j)..p {
                s += rinv[i][k] * rinv[j][k];
            }
            cov[i][j] = s * sigma * sigma;
        }
    }
    let std_err: Vec<f64> = (0..p).map(|i| cov[i][i].sqrt()).collect();
    let correlation = (0..p)
        .map(|i| {
            (0..p)
                .map(|j| cov[i][j] / (std_err[i] * std_err[j]))
                .collect()
        })
        .collect();
    Ok(LsFit {
        names: names.iter().map(|s| s.to_string()).collect(),
        theta,
        std_err,
        correlation,
        sigma,
        rel_err_pct: if yy > 0.0 {
            100.0 * (ss / yy).sqrt()
        } else {
            f64::NAN
        },
        n,
        cond_est: rmax / rmin,
    })
}

impl LsFit {
    /// Estimate by name.
    pub fn get(&self, name: &str) -> Option<f64> {
        self.names
            .iter()
            .position(|n| n == name)
            .map(|i| self.theta[i])
    }

    /// Standard error by name.
    pub fn se(&self, name: &str) -> Option<f64> {
        self.names
            .iter()
            .position(|n| n == name)
            .map(|i| self.std_err[i])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lstsq_recovers_a_line_and_its_standard_errors() {
        let n = 200;
        let x: Vec<f64> = (0..n).map(|k| k as f64 / n as f64).collect();
        // deterministic "noise" with zero mean
        let e: Vec<f64> = (0..n)
            .map(|k| if k % 2 == 0 { 0.01 } else { -0.01 })
            .collect();
        let y: Vec<f64> = x.iter().zip(&e).map(|(x, e)| 2.0 + 3.0 * x + e).collect();
        let ones = vec![1.0; n];
        let fit = lstsq("line", &["a", "b"], &[ones, x], &y).unwrap();
        assert!((fit.theta[0] - 2.0).abs() < 1e-3);
        assert!((fit.theta[1] - 3.0).abs() < 1e-3);
        assert!((fit.sigma - 0.01).abs() < 2e-4);
        // intercept and slope of a line on [0, 1) are negatively correlated (about -0.87)
        assert!(fit.correlation[0][1] < -0.8 && fit.correlation[0][1] > -0.9);
        assert!(fit.std_err[1] > 0.0 && fit.std_err[1] < 0.01);
    }

    #[test]
    fn lstsq_reports_an_unexcited_column() {
        let y = vec![1.0, 2.0, 3.0, 4.0];
        let err = lstsq("t", &["a", "zero"], &[vec![1.0; 4], vec![0.0; 4]], &y).unwrap_err();
        assert!(matches!(err, LsError::RankDeficient { ref column, .. } if column == "zero"));
    }

    #[test]
    fn spd_inverse_inverts() {
        let a = vec![vec![4.0, 1.0], vec![1.0, 3.0]];
        let inv = spd_inverse(&a).unwrap();
        let det = 11.0;
        assert!((inv[0][0] - 3.0 / det).abs() < 1e-12);
        assert!((inv[0][1] + 1.0 / det).abs() < 1e-12);
        assert!(spd_inverse(&[vec![-1.0]]).is_none());
    }
}

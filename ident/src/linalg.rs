//! Small dense linear algebra on nalgebra: least squares by Householder QR with the usual
//! statistics, LU with partial pivoting, symmetric inverses by Cholesky. Sizes here are a
//! handful of parameters against up to some hundred thousand samples.
//!
//! The factorisations are nalgebra's (`DMatrix::lu`, `qr`, `cholesky`): a well-kept crate
//! instead of our own loops (issue 22). What stays ours is what the callers need beyond a
//! solution: a rank-deficient regressor named by its column, standard errors and
//! correlations, and `None` where a factorisation does not exist.

use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

/// Solves `A x = b` (`a` given by rows) by LU with partial pivoting; `None` if singular or if
/// the solution is not finite.
pub fn solve_dense(a: Vec<Vec<f64>>, b: Vec<f64>) -> Option<Vec<f64>> {
    let n = b.len();
    if a.len() != n || a.iter().any(|r| r.len() != n) {
        return None;
    }
    let m = DMatrix::from_fn(n, n, |i, j| a[i][j]);
    let x = m.lu().solve(&DVector::from_vec(b))?;
    x.iter()
        .all(|v| v.is_finite())
        .then(|| x.as_slice().to_vec())
}

/// Inverse of a symmetric positive-definite matrix (given by rows) by Cholesky; `None` if
/// not SPD.
pub fn spd_inverse(a: &[Vec<f64>]) -> Option<Vec<Vec<f64>>> {
    let n = a.len();
    if a.iter().any(|r| r.len() != n) || a.iter().flatten().any(|v| !v.is_finite()) {
        return None;
    }
    let inv = DMatrix::from_fn(n, n, |i, j| a[i][j]).cholesky()?.inverse();
    Some(
        (0..n)
            .map(|i| (0..n).map(|j| inv[(i, j)]).collect())
            .collect(),
    )
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
    /// A regressor column whose length is not that of `y` (the caller's error, not the
    /// data's).
    #[error("least squares `{what}`: regressor `{column}` has {len} samples, y has {n}")]
    ColumnLength {
        /// Which problem.
        what: String,
        /// Offending column.
        column: String,
        /// Its length.
        len: usize,
        /// Length of `y`.
        n: usize,
    },
}

/// Ordinary least squares by Householder QR (what MATLAB's backslash does for a tall matrix).
/// `cols` are the regressor columns, all of the length of `y`.
///
/// A column is not excited (rank deficient) when its diagonal entry of R, the part of it no
/// earlier column explains, is below `1e-12` of its largest entry, or below `1e-13` of R's
/// largest diagonal entry.
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
    let rank_deficient = |k: usize| LsError::RankDeficient {
        what: what.into(),
        column: names.get(k).copied().unwrap_or("?").into(),
    };
    if let Some(k) = cols.iter().position(|c| c.len() != n) {
        return Err(LsError::ColumnLength {
            what: what.into(),
            column: names.get(k).copied().unwrap_or("?").into(),
            len: cols[k].len(),
            n,
        });
    }
    let x = DMatrix::from_fn(n, p, |i, j| cols[j][i]);
    let qr = x.qr();
    let r = qr.r();
    let rdiag: Vec<f64> = (0..p).map(|k| r[(k, k)]).collect();
    for (k, (rk, c)) in rdiag.iter().zip(cols).enumerate() {
        let scale = c.iter().map(|v| v.abs()).fold(0.0, f64::max);
        if rk.is_nan() || rk.abs() <= 1e-12 * scale.max(1e-300) {
            return Err(rank_deficient(k));
        }
    }
    let rmax = rdiag.iter().map(|v| v.abs()).fold(0.0, f64::max);
    let rmin = rdiag.iter().map(|v| v.abs()).fold(f64::INFINITY, f64::min);
    if let Some(k) = rdiag.iter().position(|r| r.abs() < 1e-13 * rmax) {
        return Err(rank_deficient(k));
    }
    // theta = R^-1 (Q^T y) by back substitution (not by the inverse below: that would cost
    // accuracy on an ill-conditioned R for one triangular solve saved, once per fit)
    let mut qty = DVector::from_column_slice(y);
    qr.q_tr_mul(&mut qty);
    let qty = qty.rows(0, p).into_owned();
    let theta_v = r
        .solve_upper_triangular(&qty)
        .ok_or_else(|| rank_deficient(p.saturating_sub(1)))?;
    let theta: Vec<f64> = theta_v.as_slice().to_vec();
    let mut ss = 0.0;
    let mut yy = 0.0;
    for (k, yk) in y.iter().enumerate() {
        let pred: f64 = cols.iter().zip(&theta).map(|(c, t)| c[k] * t).sum();
        ss += (yk - pred) * (yk - pred);
        yy += yk * yk;
    }
    let sigma = (ss / (n - p) as f64).sqrt();
    // (X^T X)^-1 = R^-1 R^-T
    let rinv = r
        .solve_upper_triangular(&DMatrix::identity(p, p))
        .ok_or_else(|| rank_deficient(p.saturating_sub(1)))?;
    let cov = &rinv * rinv.transpose() * (sigma * sigma);
    let std_err: Vec<f64> = (0..p).map(|i| cov[(i, i)].sqrt()).collect();
    let correlation = (0..p)
        .map(|i| {
            (0..p)
                .map(|j| cov[(i, j)] / (std_err[i] * std_err[j]))
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
        // a column of the wrong length is the caller's error, named as such (no index panic)
        let err = lstsq("t", &["a", "short"], &[vec![1.0; 4], vec![1.0; 3]], &y).unwrap_err();
        assert!(
            matches!(err, LsError::ColumnLength { ref column, len: 3, n: 4, .. } if column == "short"),
            "{err}"
        );
    }

    #[test]
    fn solve_dense_pivots_and_refuses_a_singular_matrix() {
        // a zero first pivot: elimination without row exchange would divide by it
        let a = vec![
            vec![0.0, 2.0, 1.0],
            vec![1.0, 1.0, 0.0],
            vec![2.0, 0.0, 3.0],
        ];
        let x = solve_dense(a.clone(), vec![5.0, 3.0, 11.0]).unwrap();
        for (row, b) in a.iter().zip([5.0, 3.0, 11.0]) {
            let ax: f64 = row.iter().zip(&x).map(|(r, x)| r * x).sum();
            assert!((ax - b).abs() < 1e-12, "{x:?}");
        }
        let singular = vec![vec![1.0, 2.0], vec![2.0, 4.0]];
        assert!(solve_dense(singular, vec![1.0, 2.0]).is_none());
        assert!(
            solve_dense(vec![vec![1.0, 2.0]], vec![1.0]).is_none(),
            "not square"
        );
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

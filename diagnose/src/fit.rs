//! Small least-squares and scoring helpers shared by the crane and single-axis pipelines.

use crane_ident::linalg::solve_dense;

/// Least squares `y ~ X theta` by normal equations (a handful of columns), with a tiny ridge
/// relative to each diagonal so collinear columns give a finite answer.
pub fn ls(cols: &[&[f64]], y: &[f64]) -> Option<Vec<f64>> {
    ls_weighted(cols, y, None)
}

/// [`ls`] with a weight per row (`None`: all 1), e.g. the counts of a bootstrap resample.
pub fn ls_weighted(cols: &[&[f64]], y: &[f64], w: Option<&[f64]>) -> Option<Vec<f64>> {
    let p = cols.len();
    let wt = |k: usize| w.map_or(1.0, |w| w[k]);
    if p == 0 {
        return Some(Vec::new());
    }
    let mut a = vec![vec![0.0; p]; p];
    let mut b = vec![0.0; p];
    for i in 0..p {
        for j in i..p {
            let s: f64 = (0..y.len()).map(|k| wt(k) * cols[i][k] * cols[j][k]).sum();
            a[i][j] = s;
            a[j][i] = s;
        }
        b[i] = (0..y.len()).map(|k| wt(k) * cols[i][k] * y[k]).sum();
    }
    for (i, row) in a.iter_mut().enumerate() {
        let d = row[i];
        row[i] = d + 1e-10 * d.abs().max(1e-300);
    }
    let th = solve_dense(a, b)?;
    th.iter().all(|v| v.is_finite()).then_some(th)
}

/// Sum of squared residuals of `y - X theta`.
pub fn sse(cols: &[&[f64]], theta: &[f64], y: &[f64]) -> f64 {
    let mut s = 0.0;
    for (k, yk) in y.iter().enumerate() {
        let pred: f64 = cols.iter().zip(theta).map(|(c, t)| c[k] * t).sum();
        s += (yk - pred) * (yk - pred);
    }
    s
}

/// The residual `y - X theta`, row by row.
pub fn residual(cols: &[&[f64]], theta: &[f64], y: &[f64]) -> Vec<f64> {
    (0..y.len())
        .map(|k| y[k] - cols.iter().zip(theta).map(|(c, t)| c[k] * t).sum::<f64>())
        .collect()
}

/// Mean absolute value of `y - X theta`.
pub fn mae(cols: &[&[f64]], theta: &[f64], y: &[f64]) -> f64 {
    let mut s = 0.0;
    for (k, yk) in y.iter().enumerate() {
        let pred: f64 = cols.iter().zip(theta).map(|(c, t)| c[k] * t).sum();
        s += (yk - pred).abs();
    }
    s / y.len().max(1) as f64
}

/// BIC-like change on held-out data: `n ln(sse_after / sse_before) + k ln(n)`; negative is
/// support for the extension.
pub fn delta_bic(n: usize, sse_before: f64, sse_after: f64, k: usize) -> f64 {
    let n = n.max(1) as f64;
    n * (sse_after.max(1e-300) / sse_before.max(1e-300)).ln() + k as f64 * n.ln()
}

/// The localized-friction bump shape `(1 - s^2)^2` for `|s| < 1`.
pub fn bump_shape(q: f64, center: f64, width: f64) -> f64 {
    let s = (q - center) / width;
    if s > -1.0 && s < 1.0 {
        let t = 1.0 - s * s;
        t * t
    } else {
        0.0
    }
}

/// Input dead band, the model's own (`u - sign(u) d` outside `|u| <= d`).
pub use crane_model::extensions::deadband;

/// `u` delayed by `m` half-samples (model steps of half the sampling period), averaged over
/// each sample as a two-substep zero-order hold sees it; zero before the start.
pub fn delay_half_samples(u: &[f64], m: usize) -> Vec<f64> {
    let at = |j: isize| -> f64 {
        if j < 0 {
            0.0
        } else {
            u.get(j as usize).copied().unwrap_or(0.0)
        }
    };
    (0..u.len())
        .map(|k| {
            let a = (2 * k as isize - m as isize).div_euclid(2);
            let b = (2 * k as isize + 1 - m as isize).div_euclid(2);
            0.5 * (at(a) + at(b))
        })
        .collect()
}

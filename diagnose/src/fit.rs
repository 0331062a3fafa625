//! Small least-squares and scoring helpers shared by the crane and single-axis pipelines.

use crane_ident::linalg::solve_dense;

/// Least squares `y ~ X theta` by normal equations (a handful of columns), with a tiny ridge
/// relative to each diagonal so collinear columns give a finite answer.
pub fn ls(cols: &[&[f64]], y: &[f64]) -> Option<Vec<f64>> {
    ls_weighted(cols, y, None)
}

/// [`ls`] with a weight per row (`None`: all 1), e.g. the counts of a bootstrap resample.
pub fn ls_weighted(cols: &[&[f64]], y: &[f64], w: Option<&[f64]>) -> Option<Vec<f64>> {
    if cols.is_empty() {
        return Some(Vec::new());
    }
    solve_normal(gram(cols, y.len(), w), moments(cols, y, w))
}

/// The normal equations' matrix `X^T W X` of the first `n` rows of the columns (`w`: a
/// weight per row, `None`: all 1). One pass over the rows with every entry's sum carried
/// along: each entry is summed in row order, the same bits as one pass per entry (and a
/// sixth of the memory traffic with six columns of a million rows).
pub fn gram(cols: &[&[f64]], n: usize, w: Option<&[f64]>) -> Vec<Vec<f64>> {
    let p = cols.len();
    // `-0.0`: the neutral element `f64`'s `Sum` starts from
    let mut acc = vec![-0.0f64; p * (p + 1) / 2];
    let mut row = vec![0.0; p];
    for k in 0..n {
        let wk = w.map_or(1.0, |w| w[k]);
        for (r, c) in row.iter_mut().zip(cols) {
            *r = c[k];
        }
        let mut e = 0;
        for i in 0..p {
            let wi = wk * row[i];
            for &rj in &row[i..] {
                acc[e] += wi * rj;
                e += 1;
            }
        }
    }
    let mut a = vec![vec![0.0; p]; p];
    let mut e = 0;
    for i in 0..p {
        for j in i..p {
            a[i][j] = acc[e];
            a[j][i] = acc[e];
            e += 1;
        }
    }
    a
}

/// The normal equations' right-hand side `X^T W y`, every entry summed in row order in one
/// pass (see [`gram`]).
pub fn moments(cols: &[&[f64]], y: &[f64], w: Option<&[f64]>) -> Vec<f64> {
    let mut b = vec![-0.0f64; cols.len()];
    for (k, &yk) in y.iter().enumerate() {
        let wk = w.map_or(1.0, |w| w[k]);
        for (bi, c) in b.iter_mut().zip(cols) {
            *bi += wk * c[k] * yk;
        }
    }
    b
}

/// Solves the normal equations `a theta = b` with a tiny ridge relative to each diagonal
/// entry (collinear columns give a finite answer); `None` when singular or not finite.
pub fn solve_normal(mut a: Vec<Vec<f64>>, b: Vec<f64>) -> Option<Vec<f64>> {
    if b.is_empty() {
        return Some(Vec::new());
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

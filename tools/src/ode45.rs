//! Dormand-Prince 5(4) with error control and dense output: what MATLAB's `ode45` does.
//!
//! Explicit embedded pair of Dormand & Prince (1980), FSAL (6 new evaluations per step), local
//! extrapolation (the 5th-order solution is kept). Error per step, root mean square over the
//! components, `err = sqrt(mean((e_i / (atol + rtol max(|y_i|, |y_new_i|)))^2))`; a step is
//! accepted when `err <= 1`, and the next step is
//! `h min(5, max(0.2, 0.9 err^(-1/5)))` (no growth right after a rejection). Output on a
//! fixed grid by the 4th-order continuous extension of MATLAB's `ntrp45`, so the samples cost
//! no extra evaluation. The study uses one tolerance for every model: [`Options::default`],
//! `rtol = 1e-6`, `atol = 1e-8`. The tableau and the dense weights are the model's
//! ([`crane_model::dopri5`]), also those of its hybrid adaptive integrator.

use crane_model::dopri5::{dense_weights, A, B, C, E};

/// Solver options.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Options {
    /// Relative tolerance.
    pub rtol: f64,
    /// Absolute tolerance (same units as every component; m, rad, m/s, rad/s here).
    pub atol: f64,
    /// Largest step [s] (MATLAB: a tenth of the interval).
    pub hmax: f64,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            rtol: 1e-6,
            atol: 1e-8,
            hmax: f64::INFINITY,
        }
    }
}

/// Work done by one integration.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Stats {
    /// Accepted steps.
    pub accepted: u64,
    /// Rejected steps.
    pub rejected: u64,
    /// Evaluations of the right-hand side.
    pub evals: u64,
}

/// Why an integration stopped early.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Failure {
    /// The right-hand side failed (e.g. singular mass matrix) at this time.
    Rhs(f64),
    /// The step size fell below the resolution of `t` at this time.
    StepTooSmall(f64),
}

impl core::fmt::Display for Failure {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Failure::Rhs(t) => write!(f, "right-hand side failed at t = {t}"),
            Failure::StepTooSmall(t) => write!(f, "step size underflow at t = {t}"),
        }
    }
}

#[inline]
fn comb<const N: usize>(y: &[f64; N], h: f64, terms: &[(f64, &[f64; N])]) -> [f64; N] {
    let mut r = *y;
    for (j, r) in r.iter_mut().enumerate() {
        let mut s = 0.0;
        for (a, k) in terms {
            s += a * k[j];
        }
        *r += h * s;
    }
    r
}

fn rms_norm<const N: usize>(e: &[f64; N], y0: &[f64; N], y1: &[f64; N], o: &Options) -> f64 {
    let mut s = 0.0;
    for j in 0..N {
        let sc = o.atol + o.rtol * y0[j].abs().max(y1[j].abs());
        let r = e[j] / sc;
        s += r * r;
    }
    (s / N as f64).sqrt()
}

/// The first step [s] (Hairer, Norsett & Wanner, II.4): from the sizes of `y` and `k1 = y'`
/// at `t`, and of `y'` one trial step on, at most `hmax`; one evaluation of `f`.
fn initial_step<const N: usize>(
    f: &mut impl FnMut(f64, &[f64; N]) -> Option<[f64; N]>,
    t: f64,
    y: &[f64; N],
    k1: &[f64; N],
    hmax: f64,
    opts: &Options,
) -> Result<f64, Failure> {
    let (mut d0, mut d1) = (0.0, 0.0);
    for j in 0..N {
        let sc = opts.atol + opts.rtol * y[j].abs();
        d0 += (y[j] / sc).powi(2);
        d1 += (k1[j] / sc).powi(2);
    }
    let (d0, d1) = ((d0 / N as f64).sqrt(), (d1 / N as f64).sqrt());
    let h0 = if d0 < 1e-5 || d1 < 1e-5 {
        1e-6
    } else {
        0.01 * d0 / d1
    };
    let y1 = comb(y, h0, &[(1.0, k1)]);
    let f1 = f(t + h0, &y1).ok_or(Failure::Rhs(t))?;
    let mut d2 = 0.0;
    for j in 0..N {
        let sc = opts.atol + opts.rtol * y[j].abs();
        d2 += ((f1[j] - k1[j]) / sc).powi(2);
    }
    let d2 = (d2 / N as f64).sqrt() / h0;
    let m = d1.max(d2);
    let h1 = if m <= 1e-15 {
        (h0 * 1e-3).max(1e-6)
    } else {
        (0.01 / m).powf(0.2)
    };
    Ok((100.0 * h0).min(h1).min(hmax))
}

/// Integrates `y' = f(t, y)` from `t0` to `t0 + n dt`, calling `out(k, t_k, y(t_k))` for every
/// grid time `t_k = t0 + k dt`, `k = 1..=n` (dense output).
///
/// `f` returns `None` when it cannot be evaluated (the integration then fails).
pub fn integrate<const N: usize>(
    mut f: impl FnMut(f64, &[f64; N]) -> Option<[f64; N]>,
    t0: f64,
    y0: [f64; N],
    dt: f64,
    n: usize,
    opts: &Options,
    mut out: impl FnMut(usize, f64, &[f64; N]),
) -> Result<Stats, Failure> {
    let t_end = t0 + n as f64 * dt;
    let mut st = Stats::default();
    let mut t = t0;
    let mut y = y0;
    let mut k1 = f(t, &y).ok_or(Failure::Rhs(t))?;
    st.evals += 1;
    let hmax = opts.hmax.min((t_end - t0).abs()).max(f64::MIN_POSITIVE);
    let mut h = initial_step(&mut f, t, &y, &k1, hmax, opts)?;
    st.evals += 1;
    let mut next = 1usize;
    let mut rejected_last = false;
    while next <= n {
        let remaining = t_end - t;
        if h >= remaining {
            h = remaining;
        }
        if h <= 16.0 * f64::EPSILON * t.abs().max(1.0) {
            return Err(Failure::StepTooSmall(t));
        }
        let y2 = comb(&y, h, &[(A[0][0], &k1)]);
        let k2 = f(t + C[1] * h, &y2).ok_or(Failure::Rhs(t))?;
        let y3 = comb(&y, h, &[(A[1][0], &k1), (A[1][1], &k2)]);
        let k3 = f(t + C[2] * h, &y3).ok_or(Failure::Rhs(t))?;
        let y4 = comb(&y, h, &[(A[2][0], &k1), (A[2][1], &k2), (A[2][2], &k3)]);
        let k4 = f(t + C[3] * h, &y4).ok_or(Failure::Rhs(t))?;
        let y5 = comb(
            &y,
            h,
            &[
                (A[3][0], &k1),
                (A[3][1], &k2),
                (A[3][2], &k3),
                (A[3][3], &k4),
            ],
        );
        let k5 = f(t + C[4] * h, &y5).ok_or(Failure::Rhs(t))?;
        let y6 = comb(
            &y,
            h,
            &[
                (A[4][0], &k1),
                (A[4][1], &k2),
                (A[4][2], &k3),
                (A[4][3], &k4),
                (A[4][4], &k5),
            ],
        );
        let k6 = f(t + h, &y6).ok_or(Failure::Rhs(t))?;
        let yn = comb(
            &y,
            h,
            &[
                (B[0], &k1),
                (B[2], &k3),
                (B[3], &k4),
                (B[4], &k5),
                (B[5], &k6),
            ],
        );
        let k7 = f(t + h, &yn).ok_or(Failure::Rhs(t))?;
        st.evals += 6;
        let mut e = [0.0; N];
        for j in 0..N {
            e[j] = h
                * (E[0] * k1[j]
                    + E[2] * k3[j]
                    + E[3] * k4[j]
                    + E[4] * k5[j]
                    + E[5] * k6[j]
                    + E[6] * k7[j]);
        }
        let err = rms_norm(&e, &y, &yn, opts);
        let accept = err <= 1.0; // false for NaN too
        if !accept {
            st.rejected += 1;
            let fac = if err.is_finite() {
                (0.9 * err.powf(-0.2)).max(0.2)
            } else {
                0.2
            };
            h *= fac.min(1.0);
            rejected_last = true;
            continue;
        }
        st.accepted += 1;
        let t_new = if h == remaining { t_end } else { t + h };
        // Grid samples in (t, t_new].
        let ks = [&k1, &k2, &k3, &k4, &k5, &k6, &k7];
        while next <= n {
            let tk = t0 + next as f64 * dt;
            if tk > t_new {
                break;
            }
            let th = ((tk - t) / h).clamp(0.0, 1.0);
            let w = dense_weights(th);
            let mut yk = y;
            for (j, v) in yk.iter_mut().enumerate() {
                let mut s = 0.0;
                for i in 0..7 {
                    s += w[i] * ks[i][j];
                }
                *v += h * s;
            }
            out(next, tk, &yk);
            next += 1;
        }
        t = t_new;
        y = yn;
        k1 = k7;
        let fac = if err == 0.0 {
            5.0
        } else {
            (0.9 * err.powf(-0.2)).clamp(0.2, 5.0)
        };
        h = (h * if rejected_last { fac.min(1.0) } else { fac }).min(hmax);
        rejected_last = false;
    }
    Ok(st)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exponential_decay_to_tolerance() {
        let o = Options {
            rtol: 1e-8,
            atol: 1e-10,
            ..Options::default()
        };
        let mut worst: f64 = 0.0;
        let st = integrate(
            |_, y: &[f64; 1]| Some([-y[0]]),
            0.0,
            [1.0],
            0.01,
            300,
            &o,
            |_, t, y| worst = worst.max((y[0] - (-t).exp()).abs()),
        )
        .unwrap();
        assert!(worst < 1e-7, "{worst}");
        assert!(st.accepted > 5);
    }

    #[test]
    fn dense_output_is_fourth_order_and_exact_at_step_ends() {
        // Harmonic oscillator, coarse tolerance: samples between steps stay accurate.
        let o = Options {
            rtol: 1e-9,
            atol: 1e-12,
            ..Options::default()
        };
        let mut worst: f64 = 0.0;
        let mut count = 0;
        integrate(
            |_, y: &[f64; 2]| Some([y[1], -y[0]]),
            0.0,
            [0.0, 1.0],
            0.001,
            10_000,
            &o,
            |k, t, y| {
                count += 1;
                assert_eq!(k, count);
                worst = worst.max((y[0] - t.sin()).abs());
            },
        )
        .unwrap();
        assert_eq!(count, 10_000);
        assert!(worst < 1e-7, "{worst}");
    }
}

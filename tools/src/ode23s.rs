//! A stiff solver: the modified Rosenbrock 2(3) pair of Shampine & Reichelt, "The MATLAB ODE
//! Suite" (SIAM J. Sci. Comput. 18, 1997), which is MATLAB's `ode23s`.
//!
//! Why written here: it is the stiff peer of the `tanh` models in the work-precision study, so
//! it must run on the same right-hand side, the same error norm and the same output grid as
//! [`crate::ode45`] and cost nothing to build. The stronger stiff peer, a variable-order BDF,
//! comes from a crate (`diffsol`, [`crate::bdf`]); this pair stays as MATLAB's `ode23s`.
//!
//! One step from `(t, y)` of length `h`, with `d = 1/(2 + sqrt 2)`, `e32 = 6 + sqrt 2`,
//! `J = df/dy` and `T = df/dt` by forward differences (recomputed every step: the friction
//! slope `gamma Cbar / cosh^2(gamma v)` changes by orders of magnitude within one step), and
//! `W = I - h d J` factorised once (LU with partial pivoting):
//! ```text
//! k1 = W \ (F0 + h d T)
//! F1 = f(t + h/2, y + h/2 k1);   k2 = W \ (F1 - k1) + k1
//! y_new = y + h k2;   F2 = f(t + h, y_new)
//! k3 = W \ (F2 - e32 (k2 - F1) - 2 (k1 - F0) + h d T)
//! error = h/6 (k1 - 2 k2 + k3)
//! ```
//! L-stable and of order 2 (error estimate of order 3); the error norm is the RMS norm of
//! [`crate::ode45`] (`atol + rtol max(|y|, |y_new|)`); a step is accepted when it is <= 1,
//! the next step is `h min(5, 0.8 err^(-1/3))` (after a rejection `h max(0.5, ...)`, no
//! growth). Dense output by MATLAB's `ntrp23s`:
//! `y(t + s h) = y + h (s (1 - s) / (1 - 2 d) k1 + s (s - 2 d) / (1 - 2 d) k2)`.
//! Work per step: 2 new evaluations, `N + 1` for the Jacobian and `T`, one LU.

pub use crate::ode45::{Failure, Options, Stats};

const SQRT2: f64 = core::f64::consts::SQRT_2;

fn rms_norm<const N: usize>(e: &[f64; N], y0: &[f64; N], y1: &[f64; N], o: &Options) -> f64 {
    let mut s = 0.0;
    for j in 0..N {
        let sc = o.atol + o.rtol * y0[j].abs().max(y1[j].abs());
        let r = e[j] / sc;
        s += r * r;
    }
    (s / N as f64).sqrt()
}

/// LU factorisation with partial pivoting of an `N x N` matrix (in place).
struct Lu<const N: usize> {
    a: [[f64; N]; N],
    piv: [usize; N],
}

// Index loops read as the textbook elimination; iterator forms would hide the row/column roles.
#[allow(clippy::needless_range_loop)]
impl<const N: usize> Lu<N> {
    fn new(mut a: [[f64; N]; N]) -> Option<Self> {
        let mut piv = [0usize; N];
        for k in 0..N {
            let mut p = k;
            for i in k + 1..N {
                if a[i][k].abs() > a[p][k].abs() {
                    p = i;
                }
            }
            if a[p][k] == 0.0 || !a[p][k].is_finite() {
                return None;
            }
            a.swap(k, p);
            piv[k] = p;
            for i in k + 1..N {
                let f = a[i][k] / a[k][k];
                a[i][k] = f;
                for j in k + 1..N {
                    a[i][j] -= f * a[k][j];
                }
            }
        }
        Some(Lu { a, piv })
    }

    fn solve(&self, b: &[f64; N]) -> [f64; N] {
        let mut x = *b;
        for k in 0..N {
            x.swap(k, self.piv[k]);
            for i in k + 1..N {
                x[i] -= self.a[i][k] * x[k];
            }
        }
        for i in (0..N).rev() {
            let mut s = x[i];
            for j in i + 1..N {
                s -= self.a[i][j] * x[j];
            }
            x[i] = s / self.a[i][i];
        }
        x
    }
}

/// `d = 1/(2 + sqrt 2)` of the method.
const D: f64 = 1.0 / (2.0 + SQRT2);
/// `e32 = 6 + sqrt 2` of the method.
const E32: f64 = 6.0 + SQRT2;

/// The solution at the start of a step: time `t`, state `y` and its derivative `f0 = f(t, y)`.
#[derive(Clone, Copy)]
struct Point<const N: usize> {
    t: f64,
    y: [f64; N],
    f0: [f64; N],
}

/// The results of one step's three stages: `k1`, `k2`, the new state `yn`, its derivative
/// `f2 = f(t + h, yn)` and the error estimate `e = h/6 (k1 - 2 k2 + k3)`.
struct Stages<const N: usize> {
    k1: [f64; N],
    k2: [f64; N],
    yn: [f64; N],
    f2: [f64; N],
    e: [f64; N],
}

/// Integrates `y' = f(t, y)` from `t0` to `t0 + n dt`, calling `out(k, t_k, y(t_k))` for every
/// grid time `t_k = t0 + k dt`, `k = 1..=n` (dense output). `f` returns `None` when it cannot
/// be evaluated. `Stats::evals` counts every evaluation (the Jacobian's included).
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
    let mut p = Point {
        t: t0,
        y: y0,
        f0: f(t0, &y0).ok_or(Failure::Rhs(t0))?,
    };
    st.evals += 1;
    let hmax = opts.hmax.min((t_end - t0).abs()).max(f64::MIN_POSITIVE);
    let mut h = initial_step(&p, hmax, opts);
    let mut next = 1usize;
    let mut rejected_last = false;
    let mut jac: Option<([[f64; N]; N], [f64; N])> = None;
    while next <= n {
        let remaining = t_end - p.t;
        if h >= remaining {
            h = remaining;
        }
        if h <= 16.0 * f64::EPSILON * p.t.abs().max(1.0) {
            return Err(Failure::StepTooSmall(p.t));
        }
        // Jacobian and time derivative by forward differences (once per step, kept over
        // rejections at the same point).
        let (jm, tv) = match jac {
            Some(j) => j,
            None => {
                let j = jacobian(&mut f, &p)?;
                st.evals += N as u64 + 1;
                jac = Some(j);
                j
            }
        };
        let Some(lu) = Lu::new(iteration_matrix(&jm, h)) else {
            st.rejected += 1;
            h *= 0.5;
            rejected_last = true;
            continue;
        };
        let t_new = if h == remaining { t_end } else { p.t + h };
        let Stages { k1, k2, yn, f2, e } = stages(&mut f, &lu, &p, &tv, h, t_new)?;
        st.evals += 2;
        let err = rms_norm(&e, &p.y, &yn, opts);
        let accept = err <= 1.0 && yn.iter().all(|v| v.is_finite()); // false for NaN too
        if !accept {
            st.rejected += 1;
            let fac = if err.is_finite() {
                (0.8 * err.powf(-1.0 / 3.0)).max(0.5)
            } else {
                0.5
            };
            h *= fac.min(1.0);
            rejected_last = true;
            continue;
        }
        st.accepted += 1;
        // Dense output (MATLAB's `ntrp23s`) at every grid time inside the step.
        while next <= n {
            let tk = t0 + next as f64 * dt;
            if tk > t_new {
                break;
            }
            let s = ((tk - p.t) / h).clamp(0.0, 1.0);
            let a1 = s * (1.0 - s) / (1.0 - 2.0 * D);
            let a2 = s * (s - 2.0 * D) / (1.0 - 2.0 * D);
            let mut yk = p.y;
            for r in 0..N {
                yk[r] += h * (a1 * k1[r] + a2 * k2[r]);
            }
            out(next, tk, &yk);
            next += 1;
        }
        p = Point {
            t: t_new,
            y: yn,
            f0: f2,
        };
        jac = None;
        let fac = if err == 0.0 {
            5.0
        } else {
            (0.8 * err.powf(-1.0 / 3.0)).min(5.0)
        };
        h = (h * if rejected_last { fac.min(1.0) } else { fac }).min(hmax);
        rejected_last = false;
    }
    Ok(st)
}

/// Initial step [s] as MATLAB's ode23s: from the size of `y'` relative to the tolerance, at
/// most `hmax`, at least 16 ulps of the start time.
fn initial_step<const N: usize>(p: &Point<N>, hmax: f64, opts: &Options) -> f64 {
    let mut r = 0.0f64;
    for j in 0..N {
        let sc = opts.atol + opts.rtol * p.y[j].abs();
        r = r.max(p.f0[j].abs() / sc);
    }
    let h = if r > 0.0 {
        0.8 * opts.rtol.powf(1.0 / 3.0) / r
    } else {
        hmax
    };
    h.min(hmax).max(16.0 * f64::EPSILON * p.t.abs().max(1.0))
}

/// `J = df/dy` and `T = df/dt` at `p` by forward differences (`N + 1` evaluations).
fn jacobian<const N: usize>(
    f: &mut impl FnMut(f64, &[f64; N]) -> Option<[f64; N]>,
    p: &Point<N>,
) -> Result<([[f64; N]; N], [f64; N]), Failure> {
    let (t, y, f0) = (p.t, p.y, p.f0);
    let mut jm = [[0.0; N]; N];
    for c in 0..N {
        let del = f64::EPSILON.sqrt() * y[c].abs().max(1e-5);
        let mut yp = y;
        yp[c] += del;
        let del = yp[c] - y[c];
        let fp = f(t, &yp).ok_or(Failure::Rhs(t))?;
        for r in 0..N {
            jm[r][c] = (fp[r] - f0[r]) / del;
        }
    }
    let dtt = f64::EPSILON.sqrt() * t.abs().max(1e-3);
    let ft = f(t + dtt, &y).ok_or(Failure::Rhs(t))?;
    let mut tv = [0.0; N];
    for r in 0..N {
        tv[r] = (ft[r] - f0[r]) / dtt;
    }
    Ok((jm, tv))
}

/// `W = I - h d J`.
fn iteration_matrix<const N: usize>(jm: &[[f64; N]; N], h: f64) -> [[f64; N]; N] {
    let mut w = [[0.0; N]; N];
    for r in 0..N {
        for c in 0..N {
            w[r][c] = if r == c { 1.0 } else { 0.0 } - h * D * jm[r][c];
        }
    }
    w
}

/// The three stages of a step of length `h` from `p` to `t_new` (`t + h`, or exactly the
/// end time on the last step) with `lu` = LU of `W` and `tv` = `T` (2 evaluations).
fn stages<const N: usize>(
    f: &mut impl FnMut(f64, &[f64; N]) -> Option<[f64; N]>,
    lu: &Lu<N>,
    p: &Point<N>,
    tv: &[f64; N],
    h: f64,
    t_new: f64,
) -> Result<Stages<N>, Failure> {
    let (t, y, f0) = (p.t, p.y, p.f0);
    let mut b = [0.0; N];
    for r in 0..N {
        b[r] = f0[r] + h * D * tv[r];
    }
    let k1 = lu.solve(&b);
    let mut y1 = y;
    for r in 0..N {
        y1[r] += 0.5 * h * k1[r];
    }
    let f1 = f(t + 0.5 * h, &y1).ok_or(Failure::Rhs(t))?;
    for r in 0..N {
        b[r] = f1[r] - k1[r];
    }
    let mut k2 = lu.solve(&b);
    for r in 0..N {
        k2[r] += k1[r];
    }
    let mut yn = y;
    for r in 0..N {
        yn[r] += h * k2[r];
    }
    let f2 = f(t_new, &yn).ok_or(Failure::Rhs(t))?;
    for r in 0..N {
        b[r] = f2[r] - E32 * (k2[r] - f1[r]) - 2.0 * (k1[r] - f0[r]) + h * D * tv[r];
    }
    let k3 = lu.solve(&b);
    let mut e = [0.0; N];
    for r in 0..N {
        e[r] = h / 6.0 * (k1[r] - 2.0 * k2[r] + k3[r]);
    }
    Ok(Stages { k1, k2, yn, f2, e })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stiff_linear_problem_to_tolerance_in_few_steps() {
        // y' = -1e4 (y - cos t): the explicit stability limit is ~3e-4 s; the solution follows
        // cos t closely. 10 s in far fewer steps than an explicit solver needs.
        let o = Options {
            rtol: 1e-6,
            atol: 1e-9,
            ..Options::default()
        };
        let lam = 1e4;
        // Exact solution from y(0) = 1.
        let exact = |t: f64| {
            let a = lam * lam / (lam * lam + 1.0);
            let b = lam / (lam * lam + 1.0);
            a * t.cos() + b * t.sin() + (1.0 - a) * (-lam * t).exp()
        };
        let mut worst: f64 = 0.0;
        let st = integrate(
            |t, y: &[f64; 1]| Some([-lam * (y[0] - t.cos())]),
            0.0,
            [1.0],
            0.01,
            1000,
            &o,
            |_, t, y| worst = worst.max((y[0] - exact(t)).abs()),
        )
        .unwrap();
        assert!(worst < 1e-5, "{worst}");
        // Explicit RK needs ~10 s / (2.8 / 1e4) = 36,000 steps for stability alone.
        assert!(st.accepted < 12_000, "{st:?}");
    }

    #[test]
    fn second_order_convergence_on_a_smooth_problem() {
        // Harmonic oscillator: tightening the tolerance 1000x reduces the error about
        // 1000x (error per unit step ~ tolerance), and the answer is right.
        let run = |rtol: f64| {
            let o = Options {
                rtol,
                atol: rtol * 1e-3,
                ..Options::default()
            };
            let mut worst: f64 = 0.0;
            integrate(
                |_, y: &[f64; 2]| Some([y[1], -y[0]]),
                0.0,
                [0.0, 1.0],
                0.01,
                1000,
                &o,
                |_, t, y| worst = worst.max((y[0] - t.sin()).abs()),
            )
            .unwrap();
            worst
        };
        let (coarse, fine) = (run(1e-4), run(1e-7));
        assert!(fine < 1e-4, "{fine}");
        assert!(fine < coarse / 50.0, "{coarse} {fine}");
    }
}

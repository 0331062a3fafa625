//! Smooth comparison dynamics on the model's own equations, and fixed-step RK4.
//!
//! Everything here evaluates `crane_model::dynamics::eval` (the same mass matrix, Coriolis and
//! gravity terms as the hybrid model), with the hybrid law and fixed modes:
//! - axes listed as held are `Stopped`: row and column replaced by the constraint
//!   `qdd_i = 0`, exactly as the hybrid model holds a stopped axis;
//! - every other drive axis is `Positive` with zero friction coefficients, so `eval` applies
//!   no friction of its own; the friction law of this module is added to the drive force
//!   through the input channel (`K u - f = K (u - f / K)`).
//!
//! With [`Friction::Tanh`] that is the paper's comparison model
//! `f = Dbar qd + Cbar(q) tanh(gamma qd)` (the `+` coefficients for `qd > 0`, as the model's
//! own `tanh` law); a test checks it against `eval` with `Law::Tanh` when nothing is held.
//! With [`Friction::None`] it is the bare continuous dynamics without any friction logic,
//! the baseline of the per-step cost.

use crane_model::dynamics::{eval, Coeffs, Law, Singular};
use crane_model::friction::dry;
use crane_model::{Mode, Params, State};

/// State vector of the integrators: `[q0..q4, qd0..qd4]`.
pub type Y = [f64; 10];

/// Packs a model state.
pub fn pack(s: &State<f64>) -> Y {
    let mut y = [0.0; 10];
    y[..5].copy_from_slice(&s.q);
    y[5..].copy_from_slice(&s.qd);
    y
}

/// Unpacks into a model state.
pub fn unpack(y: &Y) -> State<f64> {
    let mut s = State {
        q: [0.0; 5],
        qd: [0.0; 5],
    };
    s.q.copy_from_slice(&y[..5]);
    s.qd.copy_from_slice(&y[5..]);
    s
}

/// Friction law of the free drive axes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Friction {
    /// No friction at all (bare dynamics).
    None,
    /// `Dbar qd + Cbar(q) tanh(gamma qd)`, gamma in s/m.
    Tanh(f64),
}

/// Continuous dynamics with a smooth friction law and some drive axes held.
#[derive(Clone, Debug)]
pub struct Smooth {
    /// Coefficients passed to `eval` (friction of free axes zeroed).
    bare: Coeffs<f64>,
    /// The original coefficients (the friction law reads them).
    orig: Coeffs<f64>,
    friction: Friction,
    modes: [Mode; 3],
    held: [bool; 3],
}

impl Smooth {
    /// Dynamics of `params` with friction law `friction` on the free axes and the axes in
    /// `held` fixed.
    pub fn new(params: &Params, friction: Friction, held: [bool; 3]) -> Smooth {
        let orig = Coeffs::<f64>::new(params);
        let mut bare = orig;
        for ax in bare.axes.iter_mut() {
            ax.visc_pos = 0.0;
            ax.visc_neg = 0.0;
            ax.dry_pos = [0.0; 5];
            ax.dry_neg = [0.0; 5];
        }
        let modes = held.map(|h| if h { Mode::Stopped } else { Mode::Positive });
        Smooth {
            bare,
            orig,
            friction,
            modes,
            held,
        }
    }

    /// The bare dynamics of `params`: nothing held, no friction.
    pub fn bare(params: &Params) -> Smooth {
        Smooth::new(params, Friction::None, [false; 3])
    }

    /// Held axes.
    pub fn held(&self) -> [bool; 3] {
        self.held
    }

    /// Friction force [N] of free axis `i` at position `q`, velocity `v`.
    #[inline]
    pub fn friction(&self, i: usize, q: f64, v: f64) -> f64 {
        match self.friction {
            Friction::None => 0.0,
            Friction::Tanh(gamma) => {
                let ax = &self.orig.axes[i];
                if v > 0.0 {
                    ax.visc_pos * v + dry(&ax.dry_pos, q) * libm::tanh(gamma * v)
                } else {
                    ax.visc_neg * v + dry(&ax.dry_neg, q) * libm::tanh(gamma * v)
                }
            }
        }
    }

    /// Time derivative `(qd, qdd)` at `y` with (unsaturated) input voltages `u`.
    #[inline]
    pub fn rhs(&self, y: &Y, u: &[f64; 3]) -> Result<Y, Singular> {
        let s = unpack(y);
        let mut ue = *u;
        if let Friction::Tanh(_) = self.friction {
            for (i, v) in ue.iter_mut().enumerate() {
                if !self.held[i] {
                    *v -= self.friction(i, s.q[i], s.qd[i]) / self.orig.axes[i].gain;
                }
            }
        }
        let e = eval(&self.bare, Law::Hybrid, &s, &self.modes, &ue)?;
        let mut d = [0.0; 10];
        d[..5].copy_from_slice(&s.qd);
        d[5..].copy_from_slice(&e.qdd);
        for (di, &h) in d.iter_mut().zip(&self.held) {
            if h {
                *di = 0.0;
            }
        }
        Ok(d)
    }
}

#[inline]
fn axpy(y: &Y, a: f64, k: &Y) -> Y {
    let mut r = *y;
    for (r, k) in r.iter_mut().zip(k) {
        *r += a * k;
    }
    r
}

/// One classic RK4 step of length `h` from time `t`; `u(t)` gives the input at a stage time.
#[inline]
pub fn rk4_step(
    sys: &Smooth,
    t: f64,
    y: &Y,
    h: f64,
    u: impl Fn(f64) -> [f64; 3],
) -> Result<Y, Singular> {
    let k1 = sys.rhs(y, &u(t))?;
    rk4_step_k1(sys, t, y, &k1, h, u)
}

/// [`rk4_step`] with the first stage `k1 = rhs(t, y)` given (3 new evaluations).
#[inline]
pub fn rk4_step_k1(
    sys: &Smooth,
    t: f64,
    y: &Y,
    k1: &Y,
    h: f64,
    u: impl Fn(f64) -> [f64; 3],
) -> Result<Y, Singular> {
    let k1 = *k1;
    let half = 0.5 * h;
    let uh = u(t + half);
    let k2 = sys.rhs(&axpy(y, half, &k1), &uh)?;
    let k3 = sys.rhs(&axpy(y, half, &k2), &uh)?;
    let k4 = sys.rhs(&axpy(y, h, &k3), &u(t + h))?;
    let w = h / 6.0;
    let mut r = *y;
    for j in 0..10 {
        r[j] += w * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j]);
    }
    Ok(r)
}

/// One RK4 step of the bare dynamics with a constant input (the per-step cost baseline).
#[inline]
pub fn rk4_bare(sys: &Smooth, y: &Y, h: f64, u: &[f64; 3]) -> Result<Y, Singular> {
    rk4_step(sys, 0.0, y, h, |_| *u)
}

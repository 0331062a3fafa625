//! Adaptive, error-controlled integration of the hybrid automaton, for offline use.
//!
//! The fixed-step path ([`crate::Crane::step`], [`crate::integrator`]) stays the real-time and
//! bit-exact one; this module is a second integrator of the same hybrid model for studies,
//! batches and references, where the cost of a run matters more than a bounded cost per step.
//!
//! - Inside a mode: the embedded Dormand-Prince 5(4) pair (FSAL, local extrapolation), the
//!   RMS error norm over the ten components `(q, qd)` with `atol + rtol max(|y|, |y_new|)`,
//!   the PI step controller of Hairer & Wanner's DOPRI5 after an accepted step,
//!   `h min(5, max(0.2, 0.9 err^(-0.17) err_prev^0.04))`, and `h max(0.2, 0.9 err^(-1/5))`
//!   after a rejection (no growth right after one), and the 4th-order continuous extension of
//!   MATLAB's `ntrp45` as dense output ([`crate::dopri5`], also the tableau of
//!   `tools/src/ode45.rs`), here on the
//!   hybrid law: a stopped axis has
//!   `qd = 0` and `qdd = 0` exactly in every stage, so it stays exactly where it is, and a
//!   state with every drive axis stopped and the swing at rest has a zero error estimate:
//!   the steps then grow freely (up to [`Tolerances::hmax`] and the guard bound below).
//! - Events, on every accepted trial step: a moving axis's velocity reaching 0 and its
//!   position reaching the limit it moves towards are found on the dense output (sampled at
//!   eight points of the step, then the crossing located), a stopped axis's breakaway by its
//!   margin at the stage evaluations, then the crossing of the margin evaluated at the dense
//!   state (the ITP method: regula falsi with bisection's worst case). A breakaway guard is
//!   seen only at the stages, so the next step is kept short enough that the holding force,
//!   at the curvature it showed over the last step, cannot cross its level and come back
//!   between two stages (`Adaptive::guard_step`; unbounded while the holding forces are
//!   constant, so stuck phases under a constant load still take steps as long as they
//!   like). Without it, case 1 (the trolleys stuck under a swinging payload) hid a crossing
//!   inside 17 / 1 / 6 / 1 accepted steps at `rtol` 1e-2 / 1e-3 / 1e-4 / 1e-5 (the guard
//!   checked at 63 points inside every step); with it, in none at 1e-3 .. 1e-7
//!   (`tools/tests/adaptive.rs`). All
//!   are located to [`Tolerances::event`] seconds. The state at the earliest event is taken
//!   from the dense output (where the event was located), the reset applied (the
//!   resets of `NUMERICS.md`: velocity `qd := 0`, limit end-stop impulse), every other
//!   violation swept, and the modes re-resolved there ([`crate::modes`]); the next step
//!   starts from the event.
//! - The input is a function of time (the caller's continuous-time input), not a held value.
//! - Not here: the swing stops of the fixed-step path (a run that leaves the model's domain
//!   fails with [`AdaptiveError::NonFinite`] or [`AdaptiveError::Singular`] instead).
//!
//! `no_std`, no heap: the integrator holds its last step's stages for the dense output
//! (`f64` only: offline use needs no `f32`).

use crate::coeffs::Coeffs;
use crate::dopri5::{dense_weights, A, B, BI, C, E};
use crate::dynamics::{at_state, eval, Eval, Law, Singular};
use crate::friction::horner;
use crate::integrator::{limit_violated, stop_limit, stop_velocity, sweep, velocity_violated};
use crate::mode::Mode;
use crate::modes::{candidate, margin, resolve};
use crate::state::State;

/// Error control of the adaptive integrator.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tolerances {
    /// Relative tolerance (> 0).
    pub rtol: f64,
    /// Absolute tolerance, in the units of every component (m, rad, m/s, rad/s; > 0).
    pub atol: f64,
    /// Largest step [s] (> 0; may be infinite). The error control follows a smooth input and
    /// the guard bound keeps breakaways from hiding between the stages; an input with
    /// features shorter than the steps would take (pulses, steps) needs this to resolve them.
    pub hmax: f64,
    /// Time tolerance [s] of the event location (> 0).
    pub event: f64,
}

impl Default for Tolerances {
    fn default() -> Self {
        Tolerances {
            rtol: 1e-6,
            atol: 1e-8,
            hmax: f64::INFINITY,
            event: 1e-10,
        }
    }
}

/// Why the adaptive integration stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AdaptiveError {
    /// The mass matrix was not positive definite.
    Singular,
    /// A non-finite state or input.
    NonFinite,
    /// The step fell below the resolution of the time.
    StepTooSmall,
    /// A tolerance was not positive (or NaN).
    BadTolerance,
}

impl From<Singular> for AdaptiveError {
    fn from(_: Singular) -> Self {
        AdaptiveError::Singular
    }
}

impl core::fmt::Display for AdaptiveError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            AdaptiveError::Singular => write!(f, "mass matrix not positive definite"),
            AdaptiveError::NonFinite => write!(f, "non-finite state or input"),
            AdaptiveError::StepTooSmall => write!(f, "step size underflow"),
            AdaptiveError::BadTolerance => write!(f, "tolerances must be positive"),
        }
    }
}

/// Work done so far.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AdaptiveStats {
    /// Accepted steps (including the shortened steps that end at an event).
    pub accepted: u64,
    /// Rejected trial steps.
    pub rejected: u64,
    /// Evaluations of the dynamics (mode resolutions count each of theirs).
    pub evals: u64,
    /// Events located (velocity zeros, limits, breakaways).
    pub events: u64,
}

/// Kind of a located event.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EventKind {
    /// A moving axis's velocity reached 0.
    Velocity,
    /// A moving axis reached the limit it moves towards.
    Limit,
    /// A stopped axis's holding force reached its breakaway threshold.
    Breakaway,
}

/// One accepted step: the dense output covers `[t0, t1]`; with an event the state at `t1`
/// is after its reset and mode resolution.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepInfo {
    /// Start [s].
    pub t0: f64,
    /// End [s].
    pub t1: f64,
    /// The event the step ended at, with its axis.
    pub event: Option<(EventKind, usize)>,
}

type Y = [f64; 10];

/// The PI controller's `beta` (the exponent of the last accepted error).
const PI_BETA: f64 = 0.04;
/// `ln(1e-4)`: the floor of the previous error norm in the PI controller (DOPRI5's).
const LN_ERR_FLOOR: f64 = -9.210_340_371_976_184;
/// Dense-output samples per step for finding velocity and limit events.
const EVENT_SAMPLES: usize = 8;
/// Evaluations at most when locating an event (`locate`): past bisection's count for any
/// bracket of fractions of a step and any tolerance that is not denormal.
const MAX_LOCATE: usize = 100;

fn join(a: &[f64; 5], b: &[f64; 5]) -> Y {
    let [a0, a1, a2, a3, a4] = *a;
    let [b0, b1, b2, b3, b4] = *b;
    [a0, a1, a2, a3, a4, b0, b1, b2, b3, b4]
}

fn pack(s: &State<f64>) -> Y {
    join(&s.q, &s.qd)
}

fn unpack(y: &Y) -> State<f64> {
    let [a, b, c, d, e, f, g, h, i, j] = *y;
    State {
        q: [a, b, c, d, e],
        qd: [f, g, h, i, j],
    }
}

fn deriv(s: &State<f64>, e: &Eval<f64>) -> Y {
    join(&s.qd, &e.qdd)
}

fn saturate(u: [f64; 3]) -> Result<[f64; 3], AdaptiveError> {
    let lim = crate::crane::U_MAX;
    let mut out = [0.0; 3];
    for (o, v) in out.iter_mut().zip(u) {
        if !v.is_finite() {
            return Err(AdaptiveError::NonFinite);
        }
        *o = v.clamp(-lim, lim);
    }
    Ok(out)
}

/// The first point in `(lo, hi]` where an event function crosses into its violated side, to
/// `tol` seconds on a step of length `h` (fractions of the step in, fraction out).
///
/// `f(th)` returns whether the event has happened at `th` and a signed value `g` of the
/// event function, `g >= 0` where it has (the side is decided by the flag, so a value that
/// rounds to the wrong sign cannot mislead the bracket). `f(lo)` must be false and `f(hi)`
/// true, `g_lo <= 0 <= g_hi` their values. `guess`, if inside the bracket, is evaluated
/// first (an estimate of the root from elsewhere).
///
/// The ITP method (interpolate, truncate, project: Oliveira & Takahashi, ACM TOMS 47(1), 2020)
/// with `k1 = 0.2 / (hi - lo)`, `k2 = 2`, `n0 = 1`, the truncation at least `tol / 2` (an
/// interpolant closer than that to the root then lands past it, closing the bracket from both
/// sides) and the Illinois weighting of an end kept twice: regula falsi on a smooth `g`
/// (superlinear, typically 4-8 evaluations to 1e-10 s), never more than one evaluation over
/// bisection's `ceil(log2((hi - lo) h / tol))` whatever `g` does (two with a `guess`), and at
/// most [`MAX_LOCATE`].
fn locate(
    h: f64,
    tol: f64,
    (mut lo, mut g_lo): (f64, f64),
    (mut hi, mut g_hi): (f64, f64),
    guess: Option<f64>,
    mut f: impl FnMut(f64) -> Result<(bool, f64), AdaptiveError>,
) -> Result<f64, AdaptiveError> {
    let eps = 0.5 * tol / h;
    let w0 = hi - lo;
    // Already to tolerance (or a NaN bracket, which the loop could not shrink).
    if w0.partial_cmp(&(2.0 * eps)) != Some(core::cmp::Ordering::Greater) {
        return Ok(hi);
    }
    let k1 = 0.2 / w0;
    let n_half = libm::ceil(libm::log2(w0 / (2.0 * eps))).min(MAX_LOCATE as f64 - 1.0);
    // `eps 2^(n_max - j)`: the projection radius's budget, halved every iteration.
    let mut budget = eps * libm::exp2(n_half + 1.0);
    let mut moved_hi: Option<bool> = None;
    let mut guess = guess.filter(|x| *x > lo && *x < hi);
    for _ in 0..MAX_LOCATE {
        let w = hi - lo;
        if w <= 2.0 * eps {
            break;
        }
        if let Some(x) = guess.take() {
            // The caller's estimate first (the budget is not spent on it).
            let (hit, g) = f(x)?;
            if hit {
                hi = x;
                g_hi = g.max(0.0);
            } else {
                lo = x;
                g_lo = g.min(0.0);
            }
            continue;
        }
        let mid = lo + 0.5 * w;
        // Interpolation (regula falsi), where the values allow it; else the midpoint.
        let falsi = if g_lo < 0.0 && g_hi > 0.0 {
            (g_hi * lo - g_lo * hi) / (g_hi - g_lo)
        } else {
            mid
        };
        // Truncation towards the midpoint by `k1 w^2`, but at least by `eps` (so that an
        // interpolation already closer than `eps` to the root lands past it and closes the
        // bracket from that side too), then projection into the ball of radius `r` around it
        // that keeps the worst case of bisection.
        let sigma = if mid >= falsi { 1.0 } else { -1.0 };
        let delta = (k1 * w * w).max(eps);
        let trunc = if delta <= libm::fabs(mid - falsi) {
            falsi + sigma * delta
        } else {
            mid
        };
        let r = (budget - 0.5 * w).max(0.0);
        let x = if libm::fabs(trunc - mid) <= r {
            trunc
        } else {
            mid - sigma * r
        };
        budget *= 0.5;
        let (hit, g) = f(x)?;
        // Illinois: an end kept twice in a row has its value halved for the interpolation,
        // so that regula falsi does not creep towards the root from one side only.
        if hit {
            hi = x;
            g_hi = g.max(0.0);
            if moved_hi == Some(true) {
                g_lo *= 0.5;
            }
        } else {
            lo = x;
            g_lo = g.min(0.0);
            if moved_hi == Some(false) {
                g_hi *= 0.5;
            }
        }
        moved_hi = Some(hit);
    }
    Ok(hi)
}

/// The last accepted step's stages, for the dense output.
#[derive(Clone, Copy, Debug)]
struct Dense {
    t0: f64,
    /// Length of the trial step the stages belong to [s].
    h: f64,
    /// End of the accepted part, as a fraction of `h` (1, or the event's fraction).
    th_end: f64,
    y0: Y,
    k: [Y; 7],
}

impl Dense {
    /// Component `j` of the dense output as its polynomial in `th`, lowest power first:
    /// `y0 + c1 th + c2 th^2 + c3 th^3 + c4 th^4` (28 multiply-adds once, then 4 a point by
    /// [`horner`], against 35 a point from the weights of [`dense_weights`]).
    fn component_poly(&self, j: usize) -> [f64; 5] {
        let mut c = [self.y0[j], 0.0, 0.0, 0.0, 0.0];
        for (p, cp) in c[1..].iter_mut().enumerate() {
            let mut s = 0.0;
            for (b, k) in BI.iter().zip(self.k.iter()) {
                s += b[p] * k[j];
            }
            *cp = self.h * s;
        }
        c
    }

    fn state(&self, th: f64) -> Y {
        let w = dense_weights(th);
        let mut y = self.y0;
        for (j, v) in y.iter_mut().enumerate() {
            let mut s = 0.0;
            for (wi, k) in w.iter().zip(self.k.iter()) {
                s += wi * k[j];
            }
            *v += self.h * s;
        }
        y
    }
}

/// The dense output of one accepted step as a polynomial in `th = (t - t0) / h`: cheap to
/// evaluate at many times (degree 4 per component, by Estrin's scheme: 4 multiplications and
/// 4 additions per component).
#[derive(Clone, Copy, Debug)]
pub struct DensePoly {
    t0: f64,
    /// `1 / h` [1/s] (0 for a step of length 0).
    inv_h: f64,
    th_end: f64,
    y0: Y,
    c: [Y; 4],
}

impl DensePoly {
    fn new(d: &Dense) -> Self {
        let mut c = [[0.0; 10]; 4];
        for (p, cp) in c.iter_mut().enumerate() {
            for (j, v) in cp.iter_mut().enumerate() {
                let mut s = 0.0;
                for (b, k) in BI.iter().zip(d.k.iter()) {
                    s += b[p] * k[j];
                }
                *v = d.h * s;
            }
        }
        DensePoly {
            t0: d.t0,
            inv_h: if d.h > 0.0 { 1.0 / d.h } else { 0.0 },
            th_end: d.th_end,
            y0: d.y0,
            c,
        }
    }

    /// The state at time `t` [s], clamped into the step (before an event's reset).
    #[inline]
    pub fn at(&self, t: f64) -> State<f64> {
        let th = ((t - self.t0) * self.inv_h).max(0.0).min(self.th_end);
        let mut y = self.y0;
        let [c0, c1, c2, c3] = &self.c;
        // Estrin's scheme: a shorter dependency chain than Horner's.
        let th2 = th * th;
        for (j, v) in y.iter_mut().enumerate() {
            *v += th * ((c0[j] + th * c1[j]) + th2 * (c2[j] + th * c3[j]));
        }
        unpack(&y)
    }
}

/// One Dormand-Prince trial step: stages, the 5th-order solution, its error vector, and the
/// evaluations at the stages (for the breakaway guards).
struct Trial {
    k: [Y; 7],
    yn: Y,
    err: Y,
    evals: [Eval<f64>; 7],
}

/// The adaptive integrator of the hybrid model (see the module documentation).
#[derive(Clone, Debug)]
pub struct Adaptive {
    c: Coeffs<f64>,
    tol: Tolerances,
    t: f64,
    y: State<f64>,
    modes: [Mode; 3],
    /// Evaluation at `(t, y)` in `modes` (FSAL); None before the first step.
    e1: Option<Eval<f64>>,
    h: f64,
    dense: Option<Dense>,
    /// The modes the last accepted step was taken in (those of its dense output).
    step_modes: [Mode; 3],
    stats: AdaptiveStats,
    rejected_last: bool,
    /// `ln` of the last accepted error norm (floored at 1e-4), for the PI controller.
    ln_err_prev: f64,
    /// The last accepted step [s] taken with a drive axis moving (infinite before one).
    h_moving: f64,
    /// The longest step [s] over which the stopped axes' breakaway guards, sampled at the
    /// stages, cannot hide a crossing (from the last accepted step; see [`Adaptive::guard_step`]).
    h_guard: f64,
}

impl Adaptive {
    /// An integrator at time `t0` [s], state `y0` and modes `modes0` (e.g. from a
    /// [`crate::Crane`]: `crane.coeffs()`, `crane.state()`, `crane.modes()`).
    pub fn new(
        c: &Coeffs<f64>,
        tol: Tolerances,
        t0: f64,
        y0: State<f64>,
        modes0: [Mode; 3],
    ) -> Result<Self, AdaptiveError> {
        let ok = |x: f64| x > 0.0;
        if !(ok(tol.rtol) && ok(tol.atol) && ok(tol.hmax) && ok(tol.event)) {
            return Err(AdaptiveError::BadTolerance);
        }
        if !y0.is_finite() || !t0.is_finite() {
            return Err(AdaptiveError::NonFinite);
        }
        Ok(Adaptive {
            c: *c,
            tol,
            t: t0,
            y: y0,
            modes: modes0,
            e1: None,
            h: 0.0,
            dense: None,
            step_modes: modes0,
            stats: AdaptiveStats::default(),
            rejected_last: false,
            ln_err_prev: LN_ERR_FLOOR,
            h_moving: f64::INFINITY,
            h_guard: f64::INFINITY,
        })
    }

    /// Current time [s].
    pub fn time(&self) -> f64 {
        self.t
    }

    /// Current state.
    pub fn state(&self) -> State<f64> {
        self.y
    }

    /// Current modes.
    pub fn modes(&self) -> [Mode; 3] {
        self.modes
    }

    /// The modes the last accepted step was taken in: those of its dense output (the current
    /// modes differ after an event).
    pub fn step_modes(&self) -> [Mode; 3] {
        self.step_modes
    }

    /// Work done so far.
    pub fn stats(&self) -> AdaptiveStats {
        self.stats
    }

    /// The dense output of the last accepted step at time `t` [s] (clamped into that step;
    /// before an event's reset). None before the first step.
    pub fn dense(&self, t: f64) -> Option<State<f64>> {
        let d = self.dense.as_ref()?;
        let th = if d.h > 0.0 {
            ((t - d.t0) / d.h).max(0.0).min(d.th_end)
        } else {
            0.0
        };
        Some(unpack(&d.state(th)))
    }

    /// The dense output of the last accepted step as a polynomial ([`DensePoly`]), for
    /// sampling it at many times. None before the first step.
    pub fn dense_poly(&self) -> Option<DensePoly> {
        self.dense.as_ref().map(DensePoly::new)
    }

    fn eval(&mut self, y: &State<f64>, u: &[f64; 3]) -> Result<Eval<f64>, AdaptiveError> {
        self.stats.evals += 1;
        Ok(eval(&self.c, Law::Hybrid, y, &self.modes, u)?)
    }

    fn resolve(&mut self, u: [f64; 3]) -> Result<Eval<f64>, AdaptiveError> {
        let u = saturate(u)?;
        self.stats.evals += 1;
        let stopped = self.modes.iter().filter(|m| **m == Mode::Stopped).count();
        let e = resolve(&self.c, Law::Hybrid, &self.y, &u, &mut self.modes)?;
        self.stats.evals += stopped as u64;
        Ok(e)
    }

    fn trial(
        &mut self,
        h: f64,
        e1: &Eval<f64>,
        u: &mut impl FnMut(f64) -> [f64; 3],
    ) -> Result<Trial, AdaptiveError> {
        let y0 = pack(&self.y);
        let mut k = [[0.0; 10]; 7];
        let mut evals = [*e1; 7];
        k[0] = deriv(&self.y, e1);
        for s in 1..6 {
            let mut ys = y0;
            for (j, v) in ys.iter_mut().enumerate() {
                let mut acc = 0.0;
                for (a, kk) in A[s - 1].iter().zip(k.iter()).take(s) {
                    acc += a * kk[j];
                }
                *v += h * acc;
            }
            let st = unpack(&ys);
            let us = saturate(u(self.t + C[s] * h))?;
            let e = self.eval(&st, &us)?;
            k[s] = deriv(&st, &e);
            evals[s] = e;
        }
        let mut yn = y0;
        for (j, v) in yn.iter_mut().enumerate() {
            let mut acc = 0.0;
            for (b, kk) in B.iter().zip(k.iter()) {
                acc += b * kk[j];
            }
            *v += h * acc;
        }
        let sn = unpack(&yn);
        if !sn.is_finite() {
            return Err(AdaptiveError::NonFinite);
        }
        let un = saturate(u(self.t + h))?;
        let e7 = self.eval(&sn, &un)?;
        k[6] = deriv(&sn, &e7);
        evals[6] = e7;
        let mut err = [0.0; 10];
        for (j, e) in err.iter_mut().enumerate() {
            let mut acc = 0.0;
            for (w, kk) in E.iter().zip(k.iter()) {
                acc += w * kk[j];
            }
            *e = h * acc;
        }
        Ok(Trial { k, yn, err, evals })
    }

    fn norm(&self, e: &Y, y0: &Y, y1: &Y) -> f64 {
        let mut s = 0.0;
        for j in 0..10 {
            let sc = self.tol.atol + self.tol.rtol * libm::fabs(y0[j]).max(libm::fabs(y1[j]));
            let r = e[j] / sc;
            s += r * r;
        }
        libm::sqrt(s / 10.0)
    }

    /// Initial step (Hairer, Norsett & Wanner, II.4), from the size of `y` and `y'`.
    fn initial_step(
        &mut self,
        e1: &Eval<f64>,
        u: &mut impl FnMut(f64) -> [f64; 3],
    ) -> Result<f64, AdaptiveError> {
        let y = pack(&self.y);
        let k1 = deriv(&self.y, e1);
        let (mut d0, mut d1) = (0.0, 0.0);
        for j in 0..10 {
            let sc = self.tol.atol + self.tol.rtol * libm::fabs(y[j]);
            d0 += (y[j] / sc) * (y[j] / sc);
            d1 += (k1[j] / sc) * (k1[j] / sc);
        }
        let (d0, d1) = (libm::sqrt(d0 / 10.0), libm::sqrt(d1 / 10.0));
        let h0 = if d0 < 1e-5 || d1 < 1e-5 {
            1e-6
        } else {
            0.01 * d0 / d1
        };
        let mut y1 = y;
        for (v, k) in y1.iter_mut().zip(k1) {
            *v += h0 * k;
        }
        let s1 = unpack(&y1);
        let u1 = saturate(u(self.t + h0))?;
        let e = self.eval(&s1, &u1)?;
        let f1 = deriv(&s1, &e);
        let mut d2 = 0.0;
        for j in 0..10 {
            let sc = self.tol.atol + self.tol.rtol * libm::fabs(y[j]);
            d2 += ((f1[j] - k1[j]) / sc) * ((f1[j] - k1[j]) / sc);
        }
        let d2 = libm::sqrt(d2 / 10.0) / h0;
        let m = d1.max(d2);
        let h1 = if m <= 1e-15 {
            (h0 * 1e-3).max(1e-6)
        } else {
            libm::pow(0.01 / m, 0.2)
        };
        Ok((100.0 * h0).min(h1).min(self.tol.hmax))
    }

    /// The longest next step [s] over which the breakaway guards of the stopped axes, seen only
    /// at the stages, cannot hide a crossing, from an accepted step of length `h` without an
    /// event and the evaluations at its stages.
    ///
    /// A guard crossed and recrossed between two samples `D` apart needs the holding force to
    /// bulge past its stage values by the distance `d` to the breakaway level, and a force of
    /// curvature `K` bulges at most `K D^2 / 8` over such a gap. The stages' widest gap is half
    /// the step (`c` 0.3 to 0.8), so a next step `H` with `K H^2 / 32 <= d / 4`, `H = sqrt(8 d
    /// / K)`, leaves a fourfold margin for `K` and `d` changing over it. `K` is the largest
    /// second divided difference of the holding force over the stage times; `d` the distance
    /// at the step's end to the nearer level the axis could break away towards. A single
    /// crossing needs no bound: it is seen at the next stage and located. Unbounded with every
    /// axis moving or a holding force without curvature (an axis at rest under a constant
    /// load), so the steps grow freely while the axes are stuck under any smooth input; never
    /// below 16 event tolerances (an axis resting at its level with `d` near 0).
    fn guard_step(&self, h: f64, evals: &[Eval<f64>; 7]) -> f64 {
        // stage times in order (stage 5 and the end share `c` = 1: the end is on the trajectory)
        const ORDER: [usize; 6] = [0, 1, 2, 3, 4, 6];
        let mut bound = f64::INFINITY;
        for i in 0..3 {
            if self.modes[i] != Mode::Stopped || h <= 0.0 {
                continue;
            }
            let hold = |s: usize| evals[s].hold[i];
            let mut k: f64 = 0.0;
            for w in ORDER.windows(3) {
                let (ta, tb, tc) = (C[w[0]] * h, C[w[1]] * h, C[w[2]] * h);
                let d1 = (hold(w[1]) - hold(w[0])) / (tb - ta);
                let d2 = (hold(w[2]) - hold(w[1])) / (tc - tb);
                k = k.max(libm::fabs(2.0 * (d2 - d1) / (tc - ta)));
            }
            if k.is_nan() || k == 0.0 {
                continue;
            }
            let (ax, q, end) = (self.c.axes[i], self.y.q[i], hold(6));
            let mut d = f64::INFINITY;
            if q < ax.max {
                d = d.min(-margin(&ax, q, end, Mode::Positive));
            }
            if q > ax.min {
                d = d.min(-margin(&ax, q, end, Mode::Negative));
            }
            if d.is_finite() {
                bound = bound.min(libm::sqrt(8.0 * d.max(0.0) / k));
            }
        }
        bound.max(16.0 * self.tol.event)
    }

    /// The earliest event in the trial step `d` (its whole length) with the evaluations at
    /// its stages (fraction of the step, kind, axis).
    fn find_event(
        &mut self,
        d: &Dense,
        evals: &[Eval<f64>; 7],
        u: &mut impl FnMut(f64) -> [f64; 3],
    ) -> Result<Option<(f64, EventKind, usize)>, AdaptiveError> {
        let h = d.h;
        let mut first: Option<(f64, EventKind, usize)> = None;
        let mut consider = |th: f64, k: EventKind, i: usize| {
            if first.is_none_or(|(b, _, _)| th < b) {
                first = Some((th, k, i));
            }
        };
        for i in 0..3 {
            let mode = self.modes[i];
            let (min, max) = (self.c.axes[i].min, self.c.axes[i].max);
            if mode == Mode::Stopped {
                // Breakaway: the margin at the stages (in time order), then the crossing of
                // the margin evaluated at the dense state.
                let ax = self.c.axes[i];
                let q = self.y.q[i];
                let mut prev = 0usize;
                let mut found = None;
                for s in [1usize, 2, 3, 4, 6] {
                    if let Some((dir, m)) = candidate(&ax, q, evals[s].hold[i]) {
                        found = Some((prev, s, dir, m));
                        break;
                    }
                    prev = s;
                }
                if let Some((s_lo, s_hi, dir, m_hi)) = found {
                    let (t0, c, modes) = (self.t, &self.c, &self.modes);
                    let m_lo = margin(&ax, q, evals[s_lo].hold[i], dir);
                    // On the trajectory the margin is known at both ends of the step (the
                    // evaluations at its start and, FSAL, at its end). Where the guard holds
                    // at the end, the crossing is located on the whole step, starting from
                    // the stages' estimate (regula falsi between the two stages that bracket
                    // it: stage states are off the trajectory, so the crossing may lie outside
                    // them); else between those stages.
                    let m_start = margin(&ax, q, evals[0].hold[i], dir);
                    let m_end = margin(&ax, q, evals[6].hold[i], dir);
                    let guess = (m_hi * C[s_lo] - m_lo * C[s_hi]) / (m_hi - m_lo);
                    let mut n = 0;
                    let th = {
                        let mut g = |th: f64| {
                            let st = unpack(&d.state(th));
                            let us = saturate(u(t0 + th * h))?;
                            n += 1;
                            let e = eval(c, Law::Hybrid, &st, modes, &us)?;
                            let m = margin(&ax, q, e.hold[i], dir);
                            Ok((m > 0.0, m))
                        };
                        let tol = self.tol.event;
                        if m_end > 0.0 && m_start <= 0.0 {
                            locate(h, tol, (0.0, m_start), (1.0, m_end), Some(guess), &mut g)?
                        } else {
                            locate(h, tol, (C[s_lo], m_lo), (C[s_hi], m_hi), None, &mut g)?
                        }
                    };
                    self.stats.evals += n;
                    consider(th, EventKind::Breakaway, i);
                }
                continue;
            }
            // The axis's position and velocity on the step as polynomials: the event
            // functions below are sampled and located on them.
            let (pos, vel) = (d.component_poly(i), d.component_poly(5 + i));
            for kind in [EventKind::Velocity, EventKind::Limit] {
                // The event function, >= 0 once the event has happened.
                let g = |th: f64| match kind {
                    EventKind::Velocity => {
                        let v = horner(&vel, th);
                        (
                            velocity_violated(mode, v),
                            if mode == Mode::Positive { -v } else { v },
                        )
                    }
                    _ => {
                        let x = horner(&pos, th);
                        let over = if mode == Mode::Positive {
                            x - max
                        } else {
                            min - x
                        };
                        (limit_violated(mode, x, min, max), over)
                    }
                };
                let mut prev = (0.0, g(0.0).1);
                for n in 1..=EVENT_SAMPLES {
                    let th = n as f64 / EVENT_SAMPLES as f64;
                    let (hit, v) = g(th);
                    if hit {
                        let th = locate(h, self.tol.event, prev, (th, v), None, |t| Ok(g(t)))?;
                        consider(th, kind, i);
                        break;
                    }
                    prev = (th, v);
                }
            }
        }
        Ok(first)
    }

    /// Takes one accepted step, not past `t_end`, with the input `u(t)` [V] (saturated to
    /// +-12 V here). Returns what the step covered; the dense output ([`Adaptive::dense`])
    /// then covers it. At `t_end` already, returns a step of length 0.
    pub fn step(
        &mut self,
        t_end: f64,
        u: &mut impl FnMut(f64) -> [f64; 3],
    ) -> Result<StepInfo, AdaptiveError> {
        let t0 = self.t;
        if t_end <= t0 {
            return Ok(StepInfo {
                t0,
                t1: t0,
                event: None,
            });
        }
        let e1 = match self.e1 {
            Some(e) => e,
            None => {
                let e = self.resolve(u(t0))?;
                self.h = self.initial_step(&e, u)?;
                self.e1 = Some(e);
                e
            }
        };
        loop {
            let remaining = t_end - self.t;
            let mut h = self.h.min(self.tol.hmax).min(self.h_guard);
            let last = h >= remaining;
            if last {
                h = remaining;
            }
            if h <= 16.0 * f64::EPSILON * self.t.abs().max(1.0) {
                return Err(AdaptiveError::StepTooSmall);
            }
            let tr = self.trial(h, &e1, u)?;
            let y0 = pack(&self.y);
            let err = self.norm(&tr.err, &y0, &tr.yn);
            let accept = err <= 1.0; // false for NaN too
            if !accept {
                self.stats.rejected += 1;
                let fac = if err.is_finite() {
                    (0.9 * libm::pow(err, -0.2)).max(0.2)
                } else {
                    0.2
                };
                self.h = h * fac.min(1.0);
                self.rejected_last = true;
                continue;
            }
            // PI control (Gustafsson; Hairer & Wanner's DOPRI5: beta = 0.04): the last
            // accepted error damps the growth.
            // err^a err_prev^b as one exponential of cached logarithms: one `log` and one
            // `exp` a step instead of two `pow`s (these were 7.6 % of a case 1 run at rtol
            // 1e-3)
            let (fac, ln_err) = if err == 0.0 {
                (5.0, LN_ERR_FLOOR)
            } else {
                let ln_err = libm::log(err);
                let a = -(0.2 - 0.75 * PI_BETA);
                let fac = 0.9 * libm::exp(a * ln_err + PI_BETA * self.ln_err_prev);
                (fac.clamp(0.2, 5.0), ln_err.max(LN_ERR_FLOOR))
            };
            self.ln_err_prev = ln_err;
            let next = h * if self.rejected_last {
                fac.min(1.0)
            } else {
                fac
            };
            self.rejected_last = false;
            self.stats.accepted += 1;
            self.step_modes = self.modes;
            if self.modes.iter().any(|m| *m != Mode::Stopped) {
                self.h_moving = h;
            }
            let mut d = Dense {
                t0,
                h,
                th_end: 1.0,
                y0,
                k: tr.k,
            };
            let event = self.find_event(&d, &tr.evals, u)?;
            let Some((th, kind, i)) = event else {
                self.dense = Some(d);
                self.h_guard = self.guard_step(h, &tr.evals);
                self.t = if last { t_end } else { self.t + h };
                self.y = unpack(&tr.yn);
                self.e1 = Some(tr.evals[6]);
                if !last || next > self.h {
                    self.h = next;
                }
                return Ok(StepInfo {
                    t0,
                    t1: self.t,
                    event: None,
                });
            };
            // The state at the event from the dense output (where the event was located), then
            // the reset and the modes re-resolved; the next step starts there.
            let s = th * h;
            d.th_end = th;
            let ye = d.state(th);
            self.dense = Some(d);
            let mut y = unpack(&ye);
            match kind {
                EventKind::Velocity => stop_velocity(&self.c, &mut y, &mut self.modes, i),
                EventKind::Limit => stop_limit(&self.c, &mut y, &mut self.modes, i)?,
                EventKind::Breakaway => {}
            }
            sweep(&self.c, &mut y, &mut self.modes)?;
            self.y = y;
            self.t += s;
            self.stats.events += 1;
            let e = self.resolve(u(self.t))?;
            self.e1 = Some(e);
            // Keep the controller's step (the event cut the step, not the error); after a
            // breakaway no longer than the last step taken with an axis moving: the stuck
            // phase's steps grew with nothing moving, and the first moving step would be
            // rejected (case 1: about one rejection per breakaway without this).
            self.h = match kind {
                EventKind::Breakaway => next.max(h).min(self.h_moving),
                _ => next.max(h),
            };
            return Ok(StepInfo {
                t0,
                t1: self.t,
                event: Some((kind, i)),
            });
        }
    }
}

/// Total mechanical energy [J] of state `y`: kinetic `qd^T M(q) qd / 2` plus the payload's
/// potential energy `-m_p g L sin(alpha) cos(beta)` (zero at the trolley's height). Friction
/// and damping can only lower it.
pub fn energy(c: &Coeffs<f64>, y: &State<f64>) -> f64 {
    let pre = at_state(c, y);
    let mut kin = 0.0;
    for i in 0..5 {
        for j in 0..5 {
            kin += y.qd[i] * pre.m[i][j] * y.qd[j];
        }
    }
    let [_, _, l, a, b] = y.q;
    0.5 * kin - c.mpg * l * libm::sin(a) * libm::cos(b)
}

#[cfg(test)]
mod tests {
    use super::{locate, AdaptiveError};

    /// Locates the root of `g` in `(lo, hi]` on a 1 s step to `tol`; returns the point and the
    /// number of evaluations.
    fn run(
        g: impl Fn(f64) -> f64,
        lo: f64,
        hi: f64,
        tol: f64,
    ) -> Result<(f64, usize), AdaptiveError> {
        let mut n = 0;
        let th = locate(1.0, tol, (lo, g(lo)), (hi, g(hi)), None, |x| {
            n += 1;
            let v = g(x);
            Ok((v >= 0.0, v))
        })?;
        Ok((th, n))
    }

    #[test]
    fn a_smooth_crossing_is_bracketed_to_tolerance_in_few_evaluations() -> Result<(), AdaptiveError>
    {
        // A velocity through zero with curvature, as in a decelerating slip: root at 0.3.
        let g = |x: f64| (x - 0.3) * (1.0 + 4.0 * x * x);
        let (th, n) = run(g, 0.0, 1.0, 1e-10)?;
        assert!(g(th) >= 0.0, "the returned point is on the violated side");
        assert!((th - 0.3).abs() <= 1e-10, "th = {th}");
        // Bisection would take ceil(log2(1e10)) = 34 (measured: 8).
        assert!(n <= 10, "{n} evaluations");
        Ok(())
    }

    #[test]
    fn a_guess_is_tried_first_and_costs_at_most_one_evaluation() -> Result<(), AdaptiveError> {
        let g = |x: f64| (x - 0.3) * (1.0 + 4.0 * x * x);
        let (_, n_plain) = run(g, 0.0, 1.0, 1e-10)?;
        for guess in [0.3 + 1e-9, 0.29, 0.5, 0.95] {
            let mut first = None;
            let mut n = 0;
            let th = locate(1.0, 1e-10, (0.0, g(0.0)), (1.0, g(1.0)), Some(guess), |x| {
                n += 1;
                first.get_or_insert(x);
                let v = g(x);
                Ok((v >= 0.0, v))
            })?;
            assert_eq!(first, Some(guess));
            assert!((th - 0.3).abs() <= 1e-10 && g(th) >= 0.0, "th = {th}");
            assert!(
                n <= n_plain + 1,
                "guess {guess}: {n} vs {n_plain} evaluations"
            );
        }
        Ok(())
    }

    #[test]
    fn a_jump_without_a_slope_still_converges_by_bisection() -> Result<(), AdaptiveError> {
        // Only the sign carries information: the safeguard must still shrink the bracket.
        let g = |x: f64| if x >= 0.6180339887 { 1.0 } else { -1e-9 };
        let (th, n) = run(g, 0.0, 1.0, 1e-9)?;
        assert!(
            (0.6180339887..=0.6180339887 + 1e-9).contains(&th),
            "th = {th}"
        );
        // Bisection: ceil(log2(1e9)) = 30; ITP: at most one more.
        assert!(n <= 31, "{n} evaluations");
        Ok(())
    }

    #[test]
    fn the_flag_decides_the_side_not_the_value() -> Result<(), AdaptiveError> {
        // A value that says "not yet" (0) where the flag says "happened" at exactly the root.
        let mut n = 0;
        let th = locate(1.0, 1e-12, (0.0, -1.0), (1.0, 1.0), None, |x| {
            n += 1;
            Ok((x >= 0.25, (x - 0.25).min(0.0)))
        })?;
        assert!(th >= 0.25 && th - 0.25 <= 1e-12, "th = {th}");
        assert!(n < super::MAX_LOCATE);
        Ok(())
    }
}

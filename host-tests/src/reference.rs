//! Independent reference implementation of the hybrid crane model (f64, `std`).
//!
//! Written directly from `docs/MODEL.md` (equations, conventions) and `model/NUMERICS.md`
//! (the floating-point contract, including the end-stop impulse, the swing domain and the
//! "Extensions" section). It is meant to be read as the specification: plain functions on
//! plain arrays, one expression per line of the contract, in the contract's operation order,
//! so that `crane_model` must reproduce it bit for bit. Where the contract allows more than
//! one reading, `host-tests/CONTRACT_NOTES.md` lists the one chosen.
//!
//! Conventions (SI units throughout):
//! - `q = [x, y, L, alpha, beta]`: rail position X [m], trolley position Y [m], rope length L
//!   [m] (positive velocity lowers the payload), swing angles alpha, beta [rad]. Hanging
//!   straight down is `alpha = pi/2`, `beta = 0`.
//! - `qd` likewise [m/s, rad/s]. Drive axes `i = 0, 1, 2` are `x, y, L`.
//! - Inputs `u = [u_x, u_y, u_l]` are motor voltages [V], saturated to +-12 V.
//! - Friction `f_i` [N] opposes motion: it is *subtracted* from the drive force `K_i u_i`.
//!
//! Rust evaluates `a * b * c` as `(a * b) * c` and `a - b + c` as `(a - b) + c`; every
//! expression below is written so that this left-to-right association is the contract's.
//! No `mul_add`, no `powi`; `sin`, `cos`, `tanh` come from `libm`.

// The code mirrors NUMERICS.md line by line: index loops as in the contract, `a = a - f * b`
// spelled out like the contract's pseudo-code (same IEEE result as `-=`), the explicit
// saturation, and `!(pivot > 0.0)`, which is the contract's NaN-rejecting pivot test.
#![allow(
    clippy::needless_range_loop,
    clippy::assign_op_pattern,
    clippy::manual_clamp,
    clippy::neg_cmp_op_on_partial_ord
)]

use std::fmt;

/// Voltage saturation [V].
pub const U_SAT: f64 = 12.0;
/// Maximum number of integration segments in one step (NUMERICS.md "One step").
pub const MAX_SEGMENTS: usize = 8;
/// Bisection iterations of the Hermite event location.
pub const BISECTION_ITERATIONS: usize = 30;
/// Domain of the swing coordinates: a state is accepted only if
/// `sin(alpha) * cos(beta) >= MIN_HANG` (NUMERICS.md "Domain").
pub const MIN_HANG: f64 = 0.02;

/// Swing stops [rad] from the vertical, per angle (NUMERICS.md "Swing stops").
pub const SWING_STOP: f64 = 1.4;
/// Largest input delay in steps (NUMERICS.md "Extensions": `n_i` at most 63).
pub const MAX_DELAY_STEPS: usize = 63;
/// Largest number of friction bumps (the model's fixed capacity).
pub const MAX_BUMPS: usize = 4;

/// Motion mode of one drive axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum RefMode {
    /// Moving with negative velocity (friction pushes in +direction).
    Negative,
    /// Stuck: velocity and acceleration are exactly 0, friction holds the axis.
    Stopped,
    /// Moving with positive velocity (friction pushes in -direction).
    Positive,
}

impl RefMode {
    /// The mode of a velocity sign (`0.0` and `-0.0` are Stopped).
    pub fn of_velocity(v: f64) -> RefMode {
        if v > 0.0 {
            RefMode::Positive
        } else if v < 0.0 {
            RefMode::Negative
        } else {
            RefMode::Stopped
        }
    }
}

/// Friction law.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RefLaw {
    /// The hybrid automaton (modes, events, resets).
    Hybrid,
    /// The paper's smooth baseline `f = Dbar v + Cbar tanh(gamma v)`; no modes, plain RK4.
    Tanh {
        /// Steepness `gamma` [s/m].
        gamma: f64,
    },
}

/// Parameters of one drive axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RefAxis {
    /// Reflected inertia `Jbar` [kg].
    pub inertia: f64,
    /// Motor gain `K` [N/V]: drive force is `K u`.
    pub gain: f64,
    /// Viscous friction `Dbar+` for positive velocity [N s/m].
    pub visc_pos: f64,
    /// Viscous friction `Dbar-` for negative velocity [N s/m].
    pub visc_neg: f64,
    /// Dry friction magnitude `Cbar+(p)`, coefficients c0..c4 [N, p in m].
    pub dry_pos: [f64; 5],
    /// Dry friction magnitude `Cbar-(p)`, coefficients c0..c4 [N, p in m].
    pub dry_neg: [f64; 5],
    /// Lower position limit [m].
    pub min: f64,
    /// Upper position limit [m].
    pub max: f64,
}

/// All parameters of the crane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RefParams {
    /// Payload mass `m_p` [kg].
    pub m_p: f64,
    /// Trolley mass `m_t` [kg].
    pub m_t: f64,
    /// Rail mass `m_r` [kg].
    pub m_r: f64,
    /// Gravity `g` [m/s^2].
    pub g: f64,
    /// Drive axes X, Y, rope.
    pub axes: [RefAxis; 3],
    /// Swing damping `D_alpha` [kg m^2/s].
    pub d_alpha: f64,
    /// Swing damping `D_beta` [kg m^2/s].
    pub d_beta: f64,
}

impl RefParams {
    /// The INTECO 3D-Crane defaults, typed in again from the tables of `docs/MODEL.md`
    /// (independently of `crane_model::Params::default()`, so the two can be compared).
    pub fn model_md_defaults() -> Self {
        RefParams {
            m_p: 0.457,
            m_t: 1.155,
            m_r: 2.20,
            g: 9.81,
            axes: [
                RefAxis {
                    inertia: 2.56,
                    gain: 3.20,
                    visc_pos: 105.87,
                    visc_neg: 101.44,
                    dry_pos: [1.23, 0.29, -1.95, 3.98, 5.02],
                    dry_neg: [1.29, -0.089, -4.24, 17.82, -13.75],
                    min: 0.0,
                    max: 0.505,
                },
                RefAxis {
                    inertia: 2.56,
                    gain: 3.20,
                    visc_pos: 98.50,
                    visc_neg: 97.13,
                    dry_pos: [1.08, -0.95, 6.08, -12.41, 8.56],
                    dry_neg: [1.06, -0.09, 0.29, 0.79, -1.74],
                    min: 0.0,
                    max: 0.625,
                },
                RefAxis {
                    inertia: 18.19,
                    gain: 8.53,
                    visc_pos: 701.81,
                    visc_neg: 701.81,
                    dry_pos: [8.583, 0.0, 0.0, 0.0, 0.0],
                    dry_neg: [8.583, 0.0, 0.0, 0.0, 0.0],
                    min: 0.13,
                    max: 0.57,
                },
            ],
            d_alpha: 2.573e-4,
            d_beta: 0.0059,
        }
    }

    /// A light sanity check (the model's validation is tested separately; this only keeps
    /// the reference from running on nonsense). Returns the name of the first bad field.
    pub fn check(&self) -> Result<(), RefError> {
        let pos = |name: &'static str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(RefError::InvalidParam(name))
            }
        };
        let nonneg = |name: &'static str, v: f64| {
            if v.is_finite() && v >= 0.0 {
                Ok(())
            } else {
                Err(RefError::InvalidParam(name))
            }
        };
        pos("payload_mass", self.m_p)?;
        pos("trolley_mass", self.m_t)?;
        nonneg("rail_mass", self.m_r)?;
        nonneg("gravity", self.g)?;
        nonneg("damping_alpha", self.d_alpha)?;
        nonneg("damping_beta", self.d_beta)?;
        for a in &self.axes {
            nonneg("inertia", a.inertia)?;
            pos("gain", a.gain)?;
            nonneg("viscous_pos", a.visc_pos)?;
            nonneg("viscous_neg", a.visc_neg)?;
            if a.dry_pos
                .iter()
                .chain(a.dry_neg.iter())
                .any(|c| !c.is_finite())
            {
                return Err(RefError::InvalidParam("dry"));
            }
            if !(a.min.is_finite() && a.max.is_finite() && a.min < a.max) {
                return Err(RefError::InvalidParam("min/max"));
            }
        }
        pos("rope.min", self.axes[2].min)?;
        Ok(())
    }
}

impl From<&crane_model::Params> for RefParams {
    /// Copies the model's public parameter fields into the reference's own struct.
    fn from(p: &crane_model::Params) -> Self {
        let ax = |a: &crane_model::AxisParams| RefAxis {
            inertia: a.inertia,
            gain: a.gain,
            visc_pos: a.viscous_pos,
            visc_neg: a.viscous_neg,
            dry_pos: a.dry_pos,
            dry_neg: a.dry_neg,
            min: a.min,
            max: a.max,
        };
        RefParams {
            m_p: p.payload_mass,
            m_t: p.trolley_mass,
            m_r: p.rail_mass,
            g: p.gravity,
            axes: [ax(&p.x), ax(&p.y), ax(&p.rope)],
            d_alpha: p.damping_alpha,
            d_beta: p.damping_beta,
        }
    }
}

impl From<crane_model::Params> for RefParams {
    fn from(p: crane_model::Params) -> Self {
        RefParams::from(&p)
    }
}

/// A localised change of the dry-friction magnitude of one drive axis (NUMERICS.md
/// "Extensions"): `amplitude * (1 - s^2)^2` for `|s| < 1`, `s = (q - center) / width`, added
/// to the polynomial before its clamp at zero.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RefBump {
    /// Drive axis 0 (X), 1 (Y), 2 (rope).
    pub axis: usize,
    /// Centre [m].
    pub center: f64,
    /// Half-width of the support [m] (> 0).
    pub width: f64,
    /// Peak change [N] (negative: a dip).
    pub amplitude: f64,
    /// Applies to the `Positive` direction (`C_plus`).
    pub pos: bool,
    /// Applies to the `Negative` direction (`C_minus`).
    pub neg: bool,
}

/// The model extensions of NUMERICS.md "Extensions" in the reference's own terms. The
/// default is "all off", which adds no floating-point operation.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RefExtensions {
    /// Friction bumps, in insertion order (at most [`MAX_BUMPS`]).
    pub bumps: Vec<RefBump>,
    /// Stiction `(ratio, vs)` per drive axis: `ratio >= 1` (1 is off), `vs > 0` [m/s].
    pub stiction: [Option<(f64, f64)>; 3],
    /// Bias force `b` per drive axis [N] (0 is off): the drive force is `K u + b`.
    pub bias: [f64; 3],
    /// Dead band `d` per drive axis [V] (>= 0; 0 is off).
    pub dead_band: [f64; 3],
    /// Input delay per drive axis [s] (>= 0), `round(delay / h)` steps, at most 63.
    pub delay: [f64; 3],
}

impl From<&crane_model::Extensions> for RefExtensions {
    /// Copies the model's public extension fields into the reference's own struct.
    fn from(e: &crane_model::Extensions) -> Self {
        use crane_model::{Axis, Direction};
        let bumps = e
            .bumps
            .iter()
            .map(|b| RefBump {
                axis: match b.axis {
                    Axis::X => 0,
                    Axis::Y => 1,
                    Axis::Rope => 2,
                },
                center: b.center,
                width: b.width,
                amplitude: b.amplitude,
                pos: matches!(b.direction, Direction::Positive | Direction::Both),
                neg: matches!(b.direction, Direction::Negative | Direction::Both),
            })
            .collect();
        RefExtensions {
            bumps,
            stiction: e.stiction.map(|s| s.map(|s| (s.ratio, s.velocity))),
            bias: e.force_offset,
            dead_band: e.deadzone,
            delay: e.delay,
        }
    }
}

/// Why the reference refused something.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RefError {
    /// A parameter is out of range (field name).
    InvalidParam(&'static str),
    /// The step size or gamma is out of range (field name).
    InvalidConfig(&'static str),
    /// The initial state is out of range (field name).
    InvalidState(&'static str),
    /// An input voltage is NaN or infinite; nothing changed.
    NonFiniteInput,
    /// The extensions are out of range (field name).
    InvalidExtension(&'static str),
    /// A pivot of the mass matrix was not `> 0`; the step was rejected.
    Singular,
    /// The state after the step was not finite; the step was rejected.
    NonFiniteState,
    /// The state after the step left the domain `sin(alpha) cos(beta) >= MIN_HANG`; the step
    /// was rejected.
    OutOfDomain,
    /// A drive position after the step was outside its limits (axis index); the step was
    /// rejected.
    OutOfLimits(usize),
}

impl fmt::Display for RefError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RefError::InvalidParam(n) => write!(f, "invalid parameter `{n}`"),
            RefError::InvalidConfig(n) => write!(f, "invalid configuration `{n}`"),
            RefError::InvalidState(n) => write!(f, "invalid initial state `{n}`"),
            RefError::InvalidExtension(n) => write!(f, "invalid extension `{n}`"),
            RefError::NonFiniteInput => write!(f, "non-finite input"),
            RefError::Singular => write!(f, "singular mass matrix"),
            RefError::NonFiniteState => write!(f, "non-finite state"),
            RefError::OutOfDomain => write!(f, "state outside the swing domain"),
            RefError::OutOfLimits(i) => write!(f, "drive {i} outside its limits"),
        }
    }
}

impl std::error::Error for RefError {}

/// A point of the continuous state: generalised positions and velocities.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RefState {
    /// `[x, y, L, alpha, beta]` [m, m, m, rad, rad].
    pub q: [f64; 5],
    /// Their time derivatives [m/s, rad/s].
    pub qd: [f64; 5],
}

/// The result of one evaluation of the dynamics (NUMERICS.md "One evaluation").
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RefEval {
    /// Generalised accelerations (0 exactly for stopped axes).
    pub qdd: [f64; 5],
    /// Holding force of each stopped drive axis [N] (0 for moving axes).
    pub hold: [f64; 3],
    /// Friction of each drive axis [N]: the law's `f` when moving, `hold` when stopped.
    pub fric: [f64; 3],
    /// The full (unmodified) mass matrix `M(q)`.
    pub m: [[f64; 5]; 5],
    /// Velocity terms `h(q, qd)`.
    pub h: [f64; 5],
    /// Gravity terms `G(q)`.
    pub g: [f64; 5],
}

/// What `output()` reports (NUMERICS.md "Outputs").
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RefOutput {
    /// Generalised accelerations.
    pub qdd: [f64; 5],
    /// Friction of each drive axis [N] (holding force for a stopped axis).
    pub friction: [f64; 3],
    /// Rope tension `S = Jbar_l Ldd - (K_l u_l - f_l)` [N], positive when the rope pulls.
    pub tension: f64,
    /// Payload position `[x_p, y_p, z_p]` [m].
    pub payload: [f64; 3],
}

/// Kind of an event located inside a step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RefEventKind {
    /// A moving velocity reached 0.
    Velocity,
    /// A moving axis reached the limit it moves towards.
    Limit,
    /// A stopped axis' holding force crossed its dry-friction threshold.
    Breakaway,
}

/// One located (triggering) event.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RefEvent {
    /// Drive axis 0, 1, 2.
    pub axis: usize,
    /// What happened.
    pub kind: RefEventKind,
    /// Time of the event inside the step, from the step's start [s].
    pub at: f64,
}

/// What happened in one step (diagnostics only; the contract fixes only the state).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RefStepInfo {
    /// Number of integration segments used (1 when no event).
    pub segments: usize,
    /// The triggering event of every relocated segment, in order.
    pub events: Vec<RefEvent>,
    /// Number of moving axes reset after the segment loop (late events).
    pub late_resets: usize,
    /// Number of swing angles stopped at their swing stop at the end of the step.
    pub swing_stops: usize,
}

/// Horner sum `c0 + c1 p + ... + c4 p^4` of a dry-friction polynomial, not clamped [N].
///
/// Kept apart from `crane_model::friction::horner` on purpose: this module is the independent
/// reference the model is checked against bit for bit, so it shares no code with the model.
pub fn horner(c: &[f64; 5], p: f64) -> f64 {
    let mut acc = c[4];
    acc = acc * p + c[3];
    acc = acc * p + c[2];
    acc = acc * p + c[1];
    acc = acc * p + c[0];
    acc
}

/// Horner evaluation of a dry-friction polynomial, clamped at 0 [N].
pub fn dry_friction(c: &[f64; 5], p: f64) -> f64 {
    clamp_at_zero(horner(c, p))
}

/// `if acc > 0 { acc } else { 0 }` (NaN gives 0).
fn clamp_at_zero(acc: f64) -> f64 {
    if acc > 0.0 {
        acc
    } else {
        0.0
    }
}

/// The dead band `d` of NUMERICS.md "Extensions" (`d > 0`).
pub fn dead_band(u: f64, d: f64) -> f64 {
    if u > d {
        u - d
    } else if u < -d {
        u + d
    } else {
        0.0
    }
}

/// `sin(alpha) * cos(beta) >= MIN_HANG` (NUMERICS.md "Domain"; false for NaN).
pub fn in_domain(q: &[f64; 5]) -> bool {
    libm::sin(q[3]) * libm::cos(q[4]) >= MIN_HANG
}

/// Voltage saturation to +-12 V (the input is already known to be finite).
pub fn saturate(u: f64) -> f64 {
    if u > U_SAT {
        U_SAT
    } else if u < -U_SAT {
        -U_SAT
    } else {
        u
    }
}

/// Cubic Hermite interpolation on `th in [0, 1]` through `y0`, `y1` with end slopes `m0`, `m1`
/// (slopes already scaled to the interval).
pub fn hermite(th: f64, y0: f64, m0: f64, y1: f64, m1: f64) -> f64 {
    let t2 = th * th;
    let t3 = t2 * th;
    let h00 = 2.0 * t3 - 3.0 * t2 + 1.0;
    let h10 = t3 - 2.0 * t2 + th;
    let h01 = -2.0 * t3 + 3.0 * t2;
    let h11 = t3 - t2;
    h00 * y0 + h10 * m0 + h01 * y1 + h11 * m1
}

/// Bisection on `[0, 1]`, 30 iterations: `moving(mid)` true means the event has not happened
/// yet at `mid`. Returns `hi`, the first fraction known to be at or past the event.
fn bisect(moving: impl Fn(f64) -> bool) -> f64 {
    let mut lo = 0.0_f64;
    let mut hi = 1.0_f64;
    for _ in 0..BISECTION_ITERATIONS {
        let mid = 0.5 * (lo + hi);
        if moving(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    hi
}

/// Gaussian elimination without pivoting, no skipped terms (NUMERICS.md "Linear solve").
/// Fails with `Singular` when a pivot is not `> 0` (this also catches NaN).
pub fn solve5(mut a: [[f64; 5]; 5], mut r: [f64; 5]) -> Result<[f64; 5], RefError> {
    for k in 0..5 {
        if !(a[k][k] > 0.0) {
            return Err(RefError::Singular);
        }
        for i in k + 1..5 {
            let f = a[i][k] / a[k][k];
            for j in k..5 {
                a[i][j] = a[i][j] - f * a[k][j];
            }
            r[i] = r[i] - f * r[k];
        }
    }
    let mut x = [0.0_f64; 5];
    for i in (0..5).rev() {
        let mut s = r[i];
        for j in i + 1..5 {
            s = s - a[i][j] * x[j];
        }
        x[i] = s / a[i][i];
    }
    Ok(x)
}

/// The reference crane: parameters, step size, law and the hybrid state.
#[derive(Clone, Debug)]
pub struct RefCrane {
    p: RefParams,
    /// `((m_t + m_r) + Jbar_x) + m_p` [kg].
    m00: f64,
    /// `(m_t + Jbar_y) + m_p` [kg].
    m11: f64,
    /// `Jbar_l + m_p` [kg].
    m22: f64,
    /// `m_p * g` [N].
    mpg: f64,
    h: f64,
    law: RefLaw,
    y: RefState,
    modes: [RefMode; 3],
    /// Accepted steps.
    n: u64,
    /// Input `u` of `eval` in the last accepted step (saturated, delayed, dead band; 0 before
    /// the first step).
    u_last: [f64; 3],
    /// Extensions (all off unless `with_extensions`).
    ext: RefExtensions,
    /// Input delay per axis in steps, `round(delay_i / h)`.
    delay_steps: [usize; 3],
    /// Saturated inputs pushed into the delay line by the accepted steps, oldest first (only
    /// the last `MAX_DELAY_STEPS` are kept).
    pushed: std::collections::VecDeque<[f64; 3]>,
    /// Segments one hybrid step may use (NUMERICS.md "One step"; `MAX_SEGMENTS` unless set).
    segment_budget: usize,
}

impl RefCrane {
    /// Builds the reference crane.
    ///
    /// Initial modes follow the sign of the initial drive velocities (`0.0` or `-0.0` ->
    /// Stopped, the zero kept as given, NUMERICS.md "Initial states"); an axis at the limit it
    /// moves towards starts Stopped with velocity `+0.0`. Rejects invalid parameters, `h` not
    /// finite and > 0, `gamma` not finite and > 0, and initial states that are not finite,
    /// have a drive position outside its limits, `alpha` outside `(0, pi)` or are outside the
    /// swing domain `sin(alpha) cos(beta) >= MIN_HANG` (`InvalidState("q[4]")`).
    pub fn new(
        params: RefParams,
        h: f64,
        law: RefLaw,
        q0: [f64; 5],
        qd0: [f64; 5],
    ) -> Result<Self, RefError> {
        params.check()?;
        if !(h.is_finite() && h > 0.0) {
            return Err(RefError::InvalidConfig("h"));
        }
        if let RefLaw::Tanh { gamma } = law {
            if !(gamma.is_finite() && gamma > 0.0) {
                return Err(RefError::InvalidConfig("gamma"));
            }
        }
        if q0.iter().chain(qd0.iter()).any(|v| !v.is_finite()) {
            return Err(RefError::InvalidState("not finite"));
        }
        for i in 0..3 {
            let a = &params.axes[i];
            if !(q0[i] >= a.min && q0[i] <= a.max) {
                return Err(RefError::InvalidState("q out of limits"));
            }
        }
        if !(q0[3] > 0.0 && q0[3] < core::f64::consts::PI) {
            return Err(RefError::InvalidState("q[3]"));
        }
        let half_pi = core::f64::consts::FRAC_PI_2;
        if !(q0[3] >= half_pi - SWING_STOP && q0[3] <= half_pi + SWING_STOP) {
            return Err(RefError::InvalidState("q[3]"));
        }
        if !(q0[4] >= -SWING_STOP && q0[4] <= SWING_STOP) {
            return Err(RefError::InvalidState("q[4]"));
        }
        if !in_domain(&q0) {
            return Err(RefError::InvalidState("q[4]"));
        }
        let q = q0;
        let mut qd = qd0;
        let mut modes = [RefMode::Stopped; 3];
        for i in 0..3 {
            let a = &params.axes[i];
            // Moving into the limit it sits at: starts stopped with velocity 0.0.
            if (qd[i] > 0.0 && q[i] >= a.max) || (qd[i] < 0.0 && q[i] <= a.min) {
                qd[i] = 0.0;
            }
            // 0.0 and -0.0 are Stopped; the given zero is kept as it is (CONTRACT_NOTES D3).
            modes[i] = RefMode::of_velocity(qd[i]);
        }
        let p = params;
        Ok(RefCrane {
            m00: ((p.m_t + p.m_r) + p.axes[0].inertia) + p.m_p,
            m11: (p.m_t + p.axes[1].inertia) + p.m_p,
            m22: p.axes[2].inertia + p.m_p,
            mpg: p.m_p * p.g,
            p,
            h,
            law,
            y: RefState { q, qd },
            modes,
            n: 0,
            u_last: [0.0; 3],
            ext: RefExtensions::default(),
            delay_steps: [0; 3],
            pushed: std::collections::VecDeque::new(),
            segment_budget: MAX_SEGMENTS,
        })
    }

    /// Switches on the extensions of NUMERICS.md "Extensions" (before the first step).
    /// Rejects non-finite or out-of-range fields, more than [`MAX_BUMPS`] bumps and delays of
    /// more than [`MAX_DELAY_STEPS`] steps.
    pub fn with_extensions(mut self, ext: &RefExtensions) -> Result<Self, RefError> {
        let bad = RefError::InvalidExtension;
        if ext.bumps.len() > MAX_BUMPS {
            return Err(bad("bumps"));
        }
        for b in &ext.bumps {
            if b.axis > 2 {
                return Err(bad("bumps.axis"));
            }
            if !(b.center.is_finite() && b.amplitude.is_finite()) {
                return Err(bad("bumps.center/amplitude"));
            }
            if !(b.width.is_finite() && b.width > 0.0) {
                return Err(bad("bumps.width"));
            }
        }
        for i in 0..3 {
            if let Some((ratio, vs)) = ext.stiction[i] {
                if !(ratio.is_finite() && ratio >= 1.0) {
                    return Err(bad("stiction.ratio"));
                }
                if !(vs.is_finite() && vs > 0.0) {
                    return Err(bad("stiction.velocity"));
                }
            }
            if !ext.bias[i].is_finite() {
                return Err(bad("bias"));
            }
            if !(ext.dead_band[i].is_finite() && ext.dead_band[i] >= 0.0) {
                return Err(bad("dead_band"));
            }
            let d = ext.delay[i];
            if !(d.is_finite() && d >= 0.0) {
                return Err(bad("delay"));
            }
            let n = libm::round(d / self.h);
            if n > MAX_DELAY_STEPS as f64 {
                return Err(bad("delay"));
            }
            self.delay_steps[i] = n as usize;
        }
        self.ext = ext.clone();
        Ok(self)
    }

    /// Sets the segment budget of a hybrid step (NUMERICS.md "One step": the loop runs over at
    /// most `budget` segments and the last one locates nothing). Rejects 0 and more than
    /// `MAX_SEGMENTS`.
    pub fn with_segment_budget(mut self, budget: usize) -> Result<Self, RefError> {
        if budget == 0 || budget > MAX_SEGMENTS {
            return Err(RefError::InvalidConfig("segment_budget"));
        }
        self.segment_budget = budget;
        Ok(self)
    }

    /// The extensions in use.
    pub fn extensions(&self) -> &RefExtensions {
        &self.ext
    }

    /// Parameters in use.
    pub fn params(&self) -> &RefParams {
        &self.p
    }
    /// Generalised positions `[x, y, L, alpha, beta]`.
    pub fn q(&self) -> [f64; 5] {
        self.y.q
    }
    /// Generalised velocities.
    pub fn qd(&self) -> [f64; 5] {
        self.y.qd
    }
    /// Full continuous state.
    pub fn state(&self) -> RefState {
        self.y
    }
    /// Modes of the drive axes X, Y, rope.
    pub fn modes(&self) -> [RefMode; 3] {
        self.modes
    }
    /// Time `n * h` [s], `n` = accepted steps.
    pub fn time(&self) -> f64 {
        self.n as f64 * self.h
    }
    /// Number of accepted steps.
    pub fn steps(&self) -> u64 {
        self.n
    }
    /// The input `u` that `eval` used in the last accepted step (saturated, then delayed and
    /// dead-banded when those extensions are on).
    pub fn last_input(&self) -> [f64; 3] {
        self.u_last
    }
    /// Step size [s].
    pub fn h(&self) -> f64 {
        self.h
    }

    /// Dry-friction magnitude `C` of axis `i` for direction `dir` (`Positive`: `C_plus`,
    /// otherwise `C_minus`) at position `qi` [N]: the Horner sum, plus the bumps of this
    /// axis and direction in insertion order, then clamped at 0 (NUMERICS.md "Extensions").
    /// Without bumps this is exactly `dry_friction`.
    pub fn dry(&self, i: usize, dir: RefMode, qi: f64) -> f64 {
        let a = &self.p.axes[i];
        let positive = dir == RefMode::Positive;
        let mut acc = horner(if positive { &a.dry_pos } else { &a.dry_neg }, qi);
        for b in &self.ext.bumps {
            let applies = if positive { b.pos } else { b.neg };
            if b.axis != i || !applies {
                continue;
            }
            let s = (qi - b.center) / b.width;
            if s > -1.0 && s < 1.0 {
                let t = 1.0 - s * s;
                acc = acc + b.amplitude * t * t;
            }
        }
        clamp_at_zero(acc)
    }

    /// Stiction of axis `i`, if on (`ratio != 1`).
    fn stiction(&self, i: usize) -> Option<(f64, f64)> {
        self.ext.stiction[i].filter(|&(ratio, _)| ratio != 1.0)
    }

    /// The `C` of the hybrid law's moving friction: `C * (1 + (ratio - 1) exp(-(x x)))`,
    /// `x = qd_i / vs`, with stiction; `C` without.
    fn sliding(&self, i: usize, dir: RefMode, qi: f64, qdi: f64) -> f64 {
        let c = self.dry(i, dir, qi);
        match self.stiction(i) {
            Some((ratio, vs)) => {
                let x = qdi / vs;
                c * (1.0 + (ratio - 1.0) * libm::exp(-(x * x)))
            }
            None => c,
        }
    }

    /// The `C` of the breakaway margins: `ratio * C` with stiction, `C` without.
    fn threshold(&self, i: usize, dir: RefMode, qi: f64) -> f64 {
        let c = self.dry(i, dir, qi);
        match self.stiction(i) {
            Some((ratio, _)) => ratio * c,
            None => c,
        }
    }

    /// Drive force of axis `i` [N]: `K u`, or `K u + b` with a (nonzero) bias force.
    fn drive(&self, i: usize, ui: f64) -> f64 {
        let b = self.ext.bias[i];
        if b != 0.0 {
            self.p.axes[i].gain * ui + b
        } else {
            self.p.axes[i].gain * ui
        }
    }

    fn is_stopped(&self, modes: &[RefMode; 3], j: usize) -> bool {
        match self.law {
            RefLaw::Hybrid => j < 3 && modes[j] == RefMode::Stopped,
            RefLaw::Tanh { .. } => false,
        }
    }

    /// One evaluation of the dynamics at `y` with the drive modes `modes` and the saturated
    /// input `u` (NUMERICS.md "One evaluation").
    pub fn eval(
        &self,
        y: &RefState,
        modes: &[RefMode; 3],
        u: [f64; 3],
    ) -> Result<RefEval, RefError> {
        let p = &self.p;
        let m_p = p.m_p;
        let q = &y.q;
        let qd = &y.qd;
        let sa = libm::sin(q[3]);
        let ca = libm::cos(q[3]);
        let sb = libm::sin(q[4]);
        let cb = libm::cos(q[4]);
        let l = q[2];
        let ld = qd[2];
        let ad = qd[3];
        let bd = qd[4];
        let mpl = m_p * l;
        let ad2 = ad * ad;
        let bd2 = bd * bd;

        // Mass matrix [kg, kg m, kg m^2].
        let m = self.mass_matrix(q);

        // Velocity (Coriolis/centrifugal) terms [N, N m].
        let h0 = m_p
            * (l * (2.0 * ad * bd * ca * cb - (ad2 + bd2) * sa * sb)
                + 2.0 * ld * (ad * sb * ca + bd * sa * cb));
        let h1 = -(m_p * ad * (l * ad * ca + 2.0 * ld * sa));
        let h2 = -(mpl * (ad2 + bd2 * sa * sa));
        let h3 = mpl * (2.0 * ld * ad - l * bd2 * sa * ca);
        let h4 = mpl * bd * (2.0 * l * ad * sa * ca + 2.0 * ld * sa * sa);
        let hv = [h0, h1, h2, h3, h4];

        // Gravity terms [N, N m].
        let g2 = -(self.mpg * sa * cb);
        let g3 = -(self.mpg * l * ca * cb);
        let g4 = self.mpg * l * sa * sb;
        let gv = [0.0, 0.0, g2, g3, g4];

        // Friction of the drive axes [N], opposing motion. Stiction acts on the hybrid law's
        // moving friction only (CONTRACT_NOTES.md, readings).
        let mut f = [0.0_f64; 3];
        for i in 0..3 {
            let a = &p.axes[i];
            let pos = RefMode::Positive;
            let neg = RefMode::Negative;
            f[i] = match self.law {
                RefLaw::Hybrid => match modes[i] {
                    RefMode::Positive => a.visc_pos * qd[i] + self.sliding(i, pos, q[i], qd[i]),
                    RefMode::Negative => a.visc_neg * qd[i] - self.sliding(i, neg, q[i], qd[i]),
                    RefMode::Stopped => 0.0,
                },
                RefLaw::Tanh { gamma } => {
                    if qd[i] > 0.0 {
                        a.visc_pos * qd[i] + self.dry(i, pos, q[i]) * libm::tanh(gamma * qd[i])
                    } else {
                        a.visc_neg * qd[i] + self.dry(i, neg, q[i]) * libm::tanh(gamma * qd[i])
                    }
                }
            };
        }

        // Generalised forces and right-hand side r = (Q - h) - G.
        let qf = [
            self.drive(0, u[0]) - f[0],
            self.drive(1, u[1]) - f[1],
            self.drive(2, u[2]) - f[2],
            -(p.d_alpha * ad),
            -(p.d_beta * bd),
        ];
        let mut r = [0.0_f64; 5];
        for j in 0..5 {
            r[j] = qf[j] - hv[j] - gv[j];
        }

        // Stopped axes: row and column become e_i, r_i = 0.
        let mut a = m;
        for i in 0..3 {
            if self.is_stopped(modes, i) {
                for k in 0..5 {
                    a[i][k] = 0.0;
                    a[k][i] = 0.0;
                }
                a[i][i] = 1.0;
                r[i] = 0.0;
            }
        }
        let qdd = solve5(a, r)?;

        // Holding forces of stopped axes, from the unmodified rows of M.
        let mut hold = [0.0_f64; 3];
        let mut fric = f;
        for i in 0..3 {
            if self.is_stopped(modes, i) {
                let mut s = m[i][0] * qdd[0];
                for j in 1..5 {
                    s = s + m[i][j] * qdd[j];
                }
                hold[i] = self.drive(i, u[i]) - (s + hv[i] + gv[i]);
                fric[i] = hold[i];
            }
        }
        Ok(RefEval {
            qdd,
            hold,
            fric,
            m,
            h: hv,
            g: gv,
        })
    }

    /// The breakaway candidate of a stopped axis `i` at position `qi` with holding force
    /// `hold`: `(direction, margin)` for the larger positive margin (`up` wins a tie), or
    /// `None`. `up` exists only below `max`, `down` only above `min`.
    fn candidate(&self, i: usize, qi: f64, hold: f64) -> Option<(RefMode, f64)> {
        let mut best: Option<(RefMode, f64)> = None;
        if let Some(up) = self.margin(i, qi, hold, RefMode::Positive) {
            if up > 0.0 {
                best = Some((RefMode::Positive, up));
            }
        }
        if let Some(down) = self.margin(i, qi, hold, RefMode::Negative) {
            if down > 0.0 && (best.is_none() || best.is_some_and(|b| down > b.1)) {
                best = Some((RefMode::Negative, down));
            }
        }
        best
    }

    /// Margin of a stopped axis in direction `dir` [N] (positive: the guard holds), or `None`
    /// when the axis sits at the limit of that direction.
    fn margin(&self, i: usize, qi: f64, hold: f64, dir: RefMode) -> Option<f64> {
        let a = &self.p.axes[i];
        match dir {
            RefMode::Positive => (qi < a.max).then(|| hold - self.threshold(i, dir, qi)),
            RefMode::Negative => (qi > a.min).then(|| -self.threshold(i, dir, qi) - hold),
            RefMode::Stopped => None,
        }
    }

    /// Mode resolution at `y` (NUMERICS.md "Mode resolution").
    fn resolve(
        &self,
        y: &RefState,
        u: [f64; 3],
        mut modes: [RefMode; 3],
    ) -> Result<([RefMode; 3], RefEval), RefError> {
        let mut blocked = [false; 3];
        let mut e = self.eval(y, &modes, u)?;
        for _ in 0..3 {
            let mut pick: Option<(usize, RefMode, f64)> = None;
            for i in 0..3 {
                if modes[i] != RefMode::Stopped || blocked[i] {
                    continue;
                }
                if let Some((dir, m)) = self.candidate(i, y.q[i], e.hold[i]) {
                    if pick.is_none() || pick.is_some_and(|b| m > b.2) {
                        pick = Some((i, dir, m));
                    }
                }
            }
            let Some((i, dir, _)) = pick else { break };
            modes[i] = dir;
            let e2 = self.eval(y, &modes, u)?;
            let accelerates = match dir {
                RefMode::Positive => e2.qdd[i] > 0.0,
                _ => e2.qdd[i] < 0.0,
            };
            if accelerates {
                e = e2;
            } else {
                modes[i] = RefMode::Stopped;
                blocked[i] = true;
            }
        }
        Ok((modes, e))
    }

    /// `base + c * (kq, kqd)` per component; stopped axes copied unchanged.
    fn stage(
        &self,
        base: &RefState,
        modes: &[RefMode; 3],
        c: f64,
        kq: &[f64; 5],
        kqd: &[f64; 5],
    ) -> RefState {
        let mut s = *base;
        for j in 0..5 {
            if self.is_stopped(modes, j) {
                continue;
            }
            s.q[j] = base.q[j] + c * kq[j];
            s.qd[j] = base.qd[j] + c * kqd[j];
        }
        s
    }

    /// Classic RK4 over `tau` from `y` with first stage `k1` (the evaluation at `y`).
    /// Returns the end point and the last stage `E4 = eval(Y4)`.
    fn rk4(
        &self,
        y: &RefState,
        k1: &RefEval,
        tau: f64,
        modes: &[RefMode; 3],
        u: [f64; 3],
    ) -> Result<(RefState, RefEval), RefError> {
        let y2 = self.stage(y, modes, tau * 0.5, &y.qd, &k1.qdd);
        let k2 = self.eval(&y2, modes, u)?;
        let y3 = self.stage(y, modes, tau * 0.5, &y2.qd, &k2.qdd);
        let k3 = self.eval(&y3, modes, u)?;
        let y4 = self.stage(y, modes, tau, &y3.qd, &k3.qdd);
        let k4 = self.eval(&y4, modes, u)?;
        let c = tau / 6.0;
        let mut yn = *y;
        for j in 0..5 {
            if self.is_stopped(modes, j) {
                continue;
            }
            yn.q[j] = y.q[j] + c * (y.qd[j] + 2.0 * y2.qd[j] + 2.0 * y3.qd[j] + y4.qd[j]);
            yn.qd[j] = y.qd[j] + c * (k1.qdd[j] + 2.0 * k2.qdd[j] + 2.0 * k3.qdd[j] + k4.qdd[j]);
        }
        Ok((yn, k4))
    }

    /// Velocity-event predicate of a moving axis at `y`.
    fn velocity_violated(mode: RefMode, qdi: f64) -> bool {
        match mode {
            RefMode::Positive => qdi <= 0.0,
            RefMode::Negative => qdi >= 0.0,
            RefMode::Stopped => false,
        }
    }

    /// Limit-event predicate of a moving axis at `y`.
    fn limit_violated(&self, i: usize, mode: RefMode, qi: f64) -> bool {
        let a = &self.p.axes[i];
        match mode {
            RefMode::Positive => qi >= a.max,
            RefMode::Negative => qi <= a.min,
            RefMode::Stopped => false,
        }
    }

    /// End-stop impulse of moving axis `i` (NUMERICS.md "End-stop impulse"): a plastic
    /// impact on coordinate `i` only, with the modes as they are before the axis stops.
    /// `w = A^-1 e_i` with `A = M(q)`, rows and columns of stopped axes replaced by `e_j`;
    /// every free velocity `j != i` changes by `-(qd_i / w_i) w_j` (`qd_i` itself is set to 0
    /// by the caller). The kinetic energy falls by `qd_i^2 / (2 w_i)`.
    fn end_stop_impulse(
        &self,
        y: &mut RefState,
        modes: &[RefMode; 3],
        i: usize,
    ) -> Result<(), RefError> {
        let mut a = self.mass_matrix(&y.q);
        for j in 0..3 {
            if self.is_stopped(modes, j) {
                for k in 0..5 {
                    a[j][k] = 0.0;
                    a[k][j] = 0.0;
                }
                a[j][j] = 1.0;
            }
        }
        let mut e = [0.0_f64; 5];
        e[i] = 1.0;
        let w = solve5(a, e)?;
        if !(w[i] > 0.0) {
            return Err(RefError::Singular);
        }
        let k = y.qd[i] / w[i];
        for j in 0..5 {
            if j == i || self.is_stopped(modes, j) {
                continue;
            }
            y.qd[j] = y.qd[j] - k * w[j];
        }
        Ok(())
    }

    /// Limit reset: end-stop impulse, then `q_i := limit moved towards`, `qd_i := 0`,
    /// Stopped.
    fn reset_limit(
        &self,
        y: &mut RefState,
        modes: &mut [RefMode; 3],
        i: usize,
    ) -> Result<(), RefError> {
        self.end_stop_impulse(y, modes, i)?;
        let a = &self.p.axes[i];
        y.q[i] = if modes[i] == RefMode::Positive {
            a.max
        } else {
            a.min
        };
        y.qd[i] = 0.0;
        modes[i] = RefMode::Stopped;
        Ok(())
    }

    /// Velocity reset: `qd_i := 0`, `q_i` clamped into `[min_i, max_i]`, Stopped.
    fn reset_velocity(&self, y: &mut RefState, modes: &mut [RefMode; 3], i: usize) {
        let a = &self.p.axes[i];
        y.qd[i] = 0.0;
        let qi = y.q[i];
        y.q[i] = if qi > a.max {
            a.max
        } else if qi < a.min {
            a.min
        } else {
            qi
        };
        modes[i] = RefMode::Stopped;
    }

    /// Resets every moving axis of `y` with a limit (first) or velocity violation, axis by
    /// axis in the order 0, 1, 2. Returns how many were reset.
    fn reset_violations(
        &self,
        y: &mut RefState,
        modes: &mut [RefMode; 3],
    ) -> Result<usize, RefError> {
        let mut n = 0;
        for i in 0..3 {
            let mode = modes[i];
            if mode == RefMode::Stopped {
                continue;
            }
            if self.limit_violated(i, mode, y.q[i]) {
                self.reset_limit(y, modes, i)?;
                n += 1;
            } else if Self::velocity_violated(mode, y.qd[i]) {
                self.reset_velocity(y, modes, i);
                n += 1;
            }
        }
        Ok(n)
    }

    /// One hybrid step of length `h` with saturated input `u` (NUMERICS.md "One step").
    /// Works on copies; returns the new state and modes without committing them.
    fn hybrid_step(&self, u: [f64; 3]) -> Result<(RefState, [RefMode; 3], RefStepInfo), RefError> {
        let h = self.h;
        let mut info = RefStepInfo::default();
        let mut y = self.y;
        let mut s_done = 0.0_f64;
        let (mut modes, mut e1) = self.resolve(&y, u, self.modes)?;
        let last = self.segment_budget - 1;
        for seg in 0..self.segment_budget {
            info.segments = seg + 1;
            let tau = h - s_done;
            let (yn, e4) = self.rk4(&y, &e1, tau, &modes, u)?;

            // Locate the events of this segment; keep the earliest (strict '<' keeps the
            // first in the order: axis 0, 1, 2; velocity, limit, breakaway within an axis).
            let mut any = false;
            let mut first: Option<(f64, usize, RefEventKind, RefMode)> = None;
            let mut consider = |theta: f64, i: usize, kind: RefEventKind, dir: RefMode| {
                any = true;
                if first.is_none() || first.is_some_and(|f| theta < f.0) {
                    first = Some((theta, i, kind, dir));
                }
            };
            for i in 0..3 {
                let mode = modes[i];
                match mode {
                    RefMode::Positive | RefMode::Negative => {
                        if Self::velocity_violated(mode, yn.qd[i]) {
                            let (v0, v1) = (y.qd[i], yn.qd[i]);
                            let (s0, s1) = (tau * e1.qdd[i], tau * e4.qdd[i]);
                            // Still moving at mid: the event predicate is false there
                            // (a NaN counts as still moving).
                            let theta = bisect(|th| {
                                let v = hermite(th, v0, s0, v1, s1);
                                !Self::velocity_violated(mode, v)
                            });
                            consider(theta, i, RefEventKind::Velocity, mode);
                        }
                        if self.limit_violated(i, mode, yn.q[i]) {
                            let (p0, p1) = (y.q[i], yn.q[i]);
                            let (s0, s1) = (tau * y.qd[i], tau * yn.qd[i]);
                            let theta = bisect(|th| {
                                let p = hermite(th, p0, s0, p1, s1);
                                !self.limit_violated(i, mode, p)
                            });
                            consider(theta, i, RefEventKind::Limit, mode);
                        }
                    }
                    RefMode::Stopped => {
                        // Breakaway: margin positive at the last stage, negative (same
                        // direction) at the segment start.
                        if let Some((dir, m1)) = self.candidate(i, y.q[i], e4.hold[i]) {
                            if let Some(m0) = self.margin(i, y.q[i], e1.hold[i], dir) {
                                if m0 < 0.0 {
                                    let mut theta = m0 / (m0 - m1);
                                    if theta > 1.0 {
                                        theta = 1.0;
                                    }
                                    consider(theta, i, RefEventKind::Breakaway, dir);
                                }
                            }
                        }
                    }
                }
            }

            if !any || seg == last {
                y = yn;
                break;
            }
            let (theta, i, kind, _) = first.expect("an event was considered");
            let s = theta * tau;
            let (yr, _) = self.rk4(&y, &e1, s, &modes, u)?;
            y = yr;
            match kind {
                RefEventKind::Velocity => self.reset_velocity(&mut y, &mut modes, i),
                RefEventKind::Limit => self.reset_limit(&mut y, &mut modes, i)?,
                RefEventKind::Breakaway => {}
            }
            self.reset_violations(&mut y, &mut modes)?;
            info.events.push(RefEvent {
                axis: i,
                kind,
                at: s_done + s,
            });
            s_done = s_done + s;
            let (m2, e2) = self.resolve(&y, u, modes)?;
            modes = m2;
            e1 = e2;
            if s_done >= h {
                break;
            }
        }
        // Late events: violations left at the end of the step.
        info.late_resets = self.reset_violations(&mut y, &mut modes)?;
        // Swing stops: an angle beyond its stop is clamped to it; if it still moves outwards
        // it first gets the end-stop impulse on its own coordinate and a zero rate.
        let half_pi = core::f64::consts::FRAC_PI_2;
        for (j, lo, hi) in [
            (3, half_pi - SWING_STOP, half_pi + SWING_STOP),
            (4, -SWING_STOP, SWING_STOP),
        ] {
            let qj = y.q[j];
            if qj > hi || qj < lo {
                let outward = if qj > hi {
                    y.qd[j] > 0.0
                } else {
                    y.qd[j] < 0.0
                };
                if outward {
                    self.end_stop_impulse(&mut y, &modes, j)?;
                    y.qd[j] = 0.0;
                }
                y.q[j] = if qj > hi { hi } else { lo };
                info.swing_stops += 1;
            }
        }
        // The swing-stop impulse changes the drive velocities too: reset any violation again.
        if info.swing_stops > 0 {
            info.late_resets += self.reset_violations(&mut y, &mut modes)?;
        }
        Ok((y, modes, info))
    }

    /// One step of the tanh comparison model: plain RK4 over `h`, then projection on the
    /// limits (NUMERICS.md "tanh comparison model").
    fn tanh_step(&self, u: [f64; 3]) -> Result<RefState, RefError> {
        let modes = self.modes;
        let e1 = self.eval(&self.y, &modes, u)?;
        let (mut y, _) = self.rk4(&self.y, &e1, self.h, &modes, u)?;
        for i in 0..3 {
            let a = &self.p.axes[i];
            if y.q[i] > a.max {
                y.q[i] = a.max;
                if y.qd[i] > 0.0 {
                    y.qd[i] = 0.0;
                }
            } else if y.q[i] < a.min {
                y.q[i] = a.min;
                if y.qd[i] < 0.0 {
                    y.qd[i] = 0.0;
                }
            }
        }
        Ok(y)
    }

    /// The input path of one step (NUMERICS.md "Extensions"): `sat` is the saturated input;
    /// returns the `u` of `eval`. Reads the delay line without pushing (`step` pushes `sat`
    /// only when the step is accepted).
    fn input_of_step(&self, sat: [f64; 3]) -> [f64; 3] {
        let mut u = sat;
        for i in 0..3 {
            let n = self.delay_steps[i];
            if n > 0 {
                // After pushing `sat`, the vector pushed `n` pushes ago is the `n`-th newest
                // of the earlier pushes; zeros before the start.
                let len = self.pushed.len();
                u[i] = if len >= n {
                    self.pushed[len - n][i]
                } else {
                    0.0
                };
            }
        }
        for i in 0..3 {
            let d = self.ext.dead_band[i];
            if d != 0.0 {
                u[i] = dead_band(u[i], d);
            }
        }
        u
    }

    /// Advances one sample `h` with the voltages `u` [V] held constant.
    ///
    /// A non-finite input is rejected; otherwise it is saturated to +-12 V, then delayed and
    /// dead-banded if those extensions are on. A step whose evaluation fails (`Singular`),
    /// whose result is not finite (`NonFiniteState`) or is outside the swing domain
    /// (`OutOfDomain`) or leaves a drive outside its limits (`OutOfLimits`) is rejected. On any error the state, the modes, the time, the last
    /// input and the delay line stay as they were.
    pub fn step(&mut self, u: [f64; 3]) -> Result<RefStepInfo, RefError> {
        if u.iter().any(|v| !v.is_finite()) {
            return Err(RefError::NonFiniteInput);
        }
        let sat = [saturate(u[0]), saturate(u[1]), saturate(u[2])];
        let uc = self.input_of_step(sat);
        let (y, modes, info) = match self.law {
            RefLaw::Hybrid => self.hybrid_step(uc)?,
            RefLaw::Tanh { .. } => {
                let y = self.tanh_step(uc)?;
                // No automaton: the reported modes are the signs of the new velocities.
                let modes = [0, 1, 2].map(|i| RefMode::of_velocity(y.qd[i]));
                (
                    y,
                    modes,
                    RefStepInfo {
                        segments: 1,
                        ..RefStepInfo::default()
                    },
                )
            }
        };
        if y.q.iter().chain(y.qd.iter()).any(|v| !v.is_finite()) {
            return Err(RefError::NonFiniteState);
        }
        if !in_domain(&y.q) {
            return Err(RefError::OutOfDomain);
        }
        if let Some(i) =
            (0..3).find(|&i| !(y.q[i] >= self.p.axes[i].min && y.q[i] <= self.p.axes[i].max))
        {
            return Err(RefError::OutOfLimits(i));
        }
        self.y = y;
        self.modes = modes;
        self.n += 1;
        self.u_last = uc;
        if self.ext.delay.iter().any(|&d| d != 0.0) {
            self.pushed.push_back(sat);
            if self.pushed.len() > MAX_DELAY_STEPS {
                self.pushed.pop_front();
            }
        }
        Ok(info)
    }

    /// Evaluates the dynamics once at the current state with the current modes and the last
    /// (saturated) input, no resolution (NUMERICS.md "Outputs").
    pub fn output(&self) -> Result<RefOutput, RefError> {
        let e = self.eval(&self.y, &self.modes, self.u_last)?;
        let q = &self.y.q;
        let sa = libm::sin(q[3]);
        let ca = libm::cos(q[3]);
        let sb = libm::sin(q[4]);
        let cb = libm::cos(q[4]);
        let l = q[2];
        let rope = &self.p.axes[2];
        Ok(RefOutput {
            qdd: e.qdd,
            friction: e.fric,
            tension: rope.inertia * e.qdd[2] - (self.drive(2, self.u_last[2]) - e.fric[2]),
            payload: [q[0] + l * sb * sa, q[1] + l * ca, -(l * sa * cb)],
        })
    }

    /// The full mass matrix `M(q)` (NUMERICS.md "One evaluation"; also used for energy).
    /// Entries [kg, kg m, kg m^2]; assembled directly, so it exists where M is singular.
    pub fn mass_matrix(&self, q: &[f64; 5]) -> [[f64; 5]; 5] {
        let m_p = self.p.m_p;
        let sa = libm::sin(q[3]);
        let ca = libm::cos(q[3]);
        let sb = libm::sin(q[4]);
        let cb = libm::cos(q[4]);
        let l = q[2];
        let mpl = m_p * l;
        let m02 = m_p * sa * sb;
        let m03 = mpl * ca * sb;
        let m04 = mpl * sa * cb;
        let m12 = m_p * ca;
        let m13 = -(mpl * sa);
        let m33 = mpl * l;
        let m44 = m33 * sa * sa;
        // M01 = M14 = M23 = M24 = M34 = 0; symmetric.
        [
            [self.m00, 0.0, m02, m03, m04],
            [0.0, self.m11, m12, m13, 0.0],
            [m02, m12, self.m22, 0.0, 0.0],
            [m03, m13, 0.0, m33, 0.0],
            [m04, 0.0, 0.0, 0.0, m44],
        ]
    }

    /// Mechanical energy `E = 1/2 qd^T M qd + m_p g z_p` [J] of a state (not part of the
    /// contract; `z_p = -L sin(alpha) cos(beta)`, zero at the rope's suspension point).
    pub fn energy_of(&self, s: &RefState) -> f64 {
        let m = self.mass_matrix(&s.q);
        let mut kin = 0.0;
        for i in 0..5 {
            for j in 0..5 {
                kin += s.qd[i] * m[i][j] * s.qd[j];
            }
        }
        let zp = -(s.q[2] * libm::sin(s.q[3]) * libm::cos(s.q[4]));
        0.5 * kin + self.mpg * zp
    }

    /// Mechanical energy of the current state [J].
    pub fn energy(&self) -> f64 {
        self.energy_of(&self.y)
    }
}

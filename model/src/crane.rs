//! The simulator object: validated parameters, state, modes, fixed step.

use crate::dynamics::{eval, Coeffs, Law};
use crate::extensions::{deadband, DelayLine, Extensions};
use crate::integrator::{step_hybrid, step_smooth, StepReport, MAX_SEGMENTS};
use crate::modes::Mode;
use crate::params::{check, Error, Params, Problem};
use crate::real::Real;
use crate::solve::Singular;
use crate::state::State;
use core::fmt;

/// Input voltage saturation [V], as the rig's amplifiers.
pub const U_MAX: f64 = 12.0;

/// Domain of the swing: the payload must hang below the trolley with
/// `sin(alpha) cos(beta) >= MIN_HANG` (the cosine of the rope's angle from the vertical).
/// The swing stops ([`SWING_STOP`](crate::integrator::SWING_STOP), 1.4 rad per angle) keep
/// every state at or above `cos(1.4)^2 = 0.029`, so this check is a last guard; initial
/// states below it are rejected.
pub const MIN_HANG: f64 = 0.02;

/// Which friction law the simulator uses.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FrictionLaw {
    /// The hybrid automaton (exact sticking). The product.
    Hybrid,
    /// The paper's comparison model, `Dbar qd + Cbar(q) tanh(gamma qd)`, `gamma` in s/m (> 0).
    Tanh {
        /// Slope factor [s/m].
        gamma: f64,
    },
}

/// Simulator configuration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Config {
    /// Fixed step [s] (> 0). Default 1 ms; the rig samples at 2 ms.
    pub h: f64,
    /// Friction law.
    pub law: FrictionLaw,
}

impl Default for Config {
    fn default() -> Self {
        Config {
            h: 1e-3,
            law: FrictionLaw::Hybrid,
        }
    }
}

/// Why a step was rejected. The state and modes are left as they were before the step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StepError {
    /// Input voltage of axis 0 (X), 1 (Y) or 2 (rope) is NaN or infinite.
    InputNotFinite {
        /// Axis index.
        axis: usize,
    },
    /// The mass matrix was not positive definite (e.g. `alpha` reached 0 or pi).
    Singular,
    /// The step produced a non-finite state.
    NonFinite,
    /// The step would take the payload out of the model's domain ([`MIN_HANG`]).
    OutOfDomain,
    /// The step would leave drive axis 0 (X), 1 (Y) or 2 (rope) outside its limits
    /// (`min..=max`): the automaton's resets did not hold it, which stiff but valid
    /// parameters (a drive axis far lighter than its gain and friction) can do at a given
    /// step. A smaller step `h` is the remedy.
    OutOfLimits {
        /// Axis index.
        axis: usize,
    },
}

impl fmt::Display for StepError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            StepError::InputNotFinite { axis } => {
                let name = ["u_x", "u_y", "u_l"].get(*axis).copied().unwrap_or("u");
                write!(f, "input `{name}` is not finite; step rejected")
            }
            StepError::Singular => write!(f, "mass matrix not positive definite; step rejected"),
            StepError::NonFinite => write!(f, "step gave a non-finite state; step rejected"),
            StepError::OutOfDomain => write!(
                f,
                "step would swing the payload above {MIN_HANG} of the rope below the trolley; step rejected"
            ),
            StepError::OutOfLimits { axis } => {
                let name = ["x", "y", "l"].get(*axis).copied().unwrap_or("axis");
                write!(
                    f,
                    "step would leave `{name}` outside its limits (parameters too stiff for the step h); step rejected"
                )
            }
        }
    }
}

/// Checks a state given from outside (finite, positions within limits, swing in its domain)
/// and derives the modes from the velocities; an axis at a limit moving into it gets
/// `qd = +0.0`. Velocities of `-0.0` are kept as given (and are `Stopped`).
fn admit<R: Real>(c: &Coeffs<R>, init: &State<f64>) -> Result<(State<R>, [Mode; 3]), Error> {
    const Q: [&str; 5] = [
        "state.q[0]",
        "state.q[1]",
        "state.q[2]",
        "state.q[3]",
        "state.q[4]",
    ];
    const QD: [&str; 5] = [
        "state.qd[0]",
        "state.qd[1]",
        "state.qd[2]",
        "state.qd[3]",
        "state.qd[4]",
    ];
    for ((name, v), (dname, dv)) in Q.iter().zip(init.q).zip(QD.iter().zip(init.qd)) {
        check(name, v, Problem::NotFinite)?;
        check(dname, dv, Problem::NotFinite)?;
    }
    let q = init.q;
    let mut qd = init.qd;
    let mut modes = [Mode::Stopped; 3];
    for (i, ax) in c.axes.iter().enumerate() {
        let (min, max) = (ax.min.to_f64(), ax.max.to_f64());
        let (p, v) = (q[i], qd[i]);
        if p < min || p > max {
            return Err(Error {
                field: Q[i],
                problem: Problem::OutOfLimits,
                value: p,
            });
        }
        if (p >= max && v > 0.0) || (p <= min && v < 0.0) {
            qd[i] = 0.0;
        }
        modes[i] = Mode::of_velocity(qd[i]);
    }
    let alpha = q[3];
    if !(alpha > 0.0 && alpha < core::f64::consts::PI) {
        return Err(Error {
            field: Q[3],
            problem: Problem::AngleOutOfRange,
            value: alpha,
        });
    }
    let (half_pi, stop) = (core::f64::consts::FRAC_PI_2, crate::integrator::SWING_STOP);
    if !(alpha >= half_pi - stop && alpha <= half_pi + stop) {
        return Err(Error {
            field: Q[3],
            problem: Problem::AngleOutOfRange,
            value: alpha,
        });
    }
    if !(q[4] >= -stop && q[4] <= stop) {
        return Err(Error {
            field: Q[4],
            problem: Problem::AngleOutOfRange,
            value: q[4],
        });
    }
    if !in_domain(&State { q, qd }) {
        return Err(Error {
            field: Q[4],
            problem: Problem::AngleOutOfRange,
            value: q[4],
        });
    }
    Ok((
        State {
            q: q.map(R::from_f64),
            qd: qd.map(R::from_f64),
        },
        modes,
    ))
}

/// The first drive axis whose position is outside its limits `min..=max`, if any (the
/// contract of an accepted step: finite, inside the limits, in the swing domain).
fn outside_limits<R: Real>(c: &Coeffs<R>, s: &State<R>) -> Option<usize> {
    c.axes
        .iter()
        .zip(s.q)
        .position(|(ax, q)| q < ax.min || q > ax.max)
}

/// `sin(alpha) cos(beta) >= MIN_HANG` (see [`MIN_HANG`]) for a state.
fn in_domain<R: Real>(s: &State<R>) -> bool {
    hangs(s.q[3], s.q[4])
}

/// Whether swing angles `alpha`, `beta` [rad] are in the model's domain:
/// `sin(alpha) cos(beta) >= MIN_HANG` (libm `sin`, `cos` in `R`; NaN gives `false`).
///
/// Inside the swing stops (`alpha` within `pi/2 +- SWING_STOP`, `|beta| <= SWING_STOP`) the
/// product is at least `cos(1.4)^2 = 0.0289`, far above `MIN_HANG = 0.02` (and above any
/// rounding of `sin`, `cos` in f64, f32 or `F32x`), so the answer there is `true` without
/// the trigonometry: the same answer, at the cost of four comparisons.
pub fn hangs<R: Real>(alpha: R, beta: R) -> bool {
    let (a, b) = (alpha.to_f64(), beta.to_f64());
    let (half_pi, stop) = (core::f64::consts::FRAC_PI_2, crate::integrator::SWING_STOP);
    if a >= half_pi - stop && a <= half_pi + stop && b >= -stop && b <= stop {
        return true;
    }
    alpha.sin() * beta.cos() >= R::from_f64(MIN_HANG)
}

impl From<Singular> for StepError {
    fn from(_: Singular) -> Self {
        StepError::Singular
    }
}

/// Quantities derived from the current state (see [`Crane::output`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Output<R: Real = f64> {
    /// Accelerations `[xdd, ydd, Ldd, alphadd, betadd]` with the last input.
    pub qdd: [R; 5],
    /// Friction force [N] of X, Y, rope, opposing motion when moving; the holding (static
    /// friction) force when stopped, positive along the axis.
    pub friction: [R; 3],
    /// Rope tension [N], positive when the rope pulls: `Jbar_l Ldd - (K_l u_l - f_l)`
    /// (plus the rope's bias force, if that extension is on).
    pub tension: R,
    /// Payload position `[x_p, y_p, z_p]` [m].
    pub payload: [R; 3],
}

/// The crane simulator: a hybrid automaton with three drive axes and a fixed step.
///
/// ```
/// use crane_model::{Crane, Config, Params, State};
/// let q = [0.2, 0.3, 0.4, core::f64::consts::FRAC_PI_2, 0.0];
/// let mut crane: Crane = Crane::new(&Params::default(), Config::default(), State { q, qd: [0.0; 5] })?;
/// crane.step([3.0, 0.0, 0.0]).unwrap();
/// # Ok::<(), crane_model::Error>(())
/// ```
#[derive(Clone, Debug)]
pub struct Crane<R: Real = f64> {
    coeffs: Coeffs<R>,
    law: Law<R>,
    h: R,
    h64: f64,
    state: State<R>,
    modes: [Mode; 3],
    steps: u64,
    u_last: [R; 3],
    delay: DelayLine<R>,
    delay_steps: [usize; 3],
    segments: usize,
}

impl<R: Real> Crane<R> {
    /// Validates parameters, configuration and initial state, and builds the simulator.
    ///
    /// The initial modes follow the initial velocities (0.0 is `Stopped`); an axis sitting at
    /// a limit while moving into it starts `Stopped` with zero velocity. Errors name the field
    /// (`"config.h"`, `"state.q[0]"`, `"x.viscous_pos"`...).
    pub fn new(params: &Params, config: Config, init: State<f64>) -> Result<Self, Error> {
        params.validate()?;
        check("config.h", config.h, Problem::NotPositive)?;
        let law = match config.law {
            FrictionLaw::Hybrid => Law::Hybrid,
            FrictionLaw::Tanh { gamma } => {
                check("config.law.gamma", gamma, Problem::NotPositive)?;
                Law::Tanh(R::from_f64(gamma))
            }
        };
        let coeffs = Coeffs::new(params);
        let (state, modes) = admit(&coeffs, &init)?;
        let h = R::from_f64(config.h);
        Ok(Crane {
            coeffs,
            law,
            h,
            h64: config.h,
            state,
            modes,
            steps: 0,
            u_last: [R::ZERO; 3],
            delay: DelayLine::new(R::ZERO),
            delay_steps: [0; 3],
            segments: MAX_SEGMENTS,
        })
    }

    /// Switches on model extensions (localised friction, stiction, bias force, dead band,
    /// input delay), validated; errors name the field (`"bumps[0].width"`...). Call before
    /// the first step. `Extensions::default()` leaves the model unchanged, bit for bit.
    pub fn with_extensions(mut self, ext: &Extensions) -> Result<Self, Error> {
        self.delay_steps = ext.validate(self.h64)?;
        self.coeffs.extend(ext);
        Ok(self)
    }

    /// Sets the segment budget of a step: how many integration segments (one more than the
    /// located events) one step may use, `1..=MAX_SEGMENTS` ([`MAX_SEGMENTS`] = 8 is the
    /// default, and setting it again changes nothing, bit for bit). A real-time bound on the
    /// work of a step: when the budget is used up, the last segment integrates to the step end
    /// and the events it detects are applied there, unlocated (counted in
    /// [`StepReport::late_resets`]; a breakaway is then released by the next step's
    /// resolution). Budget 1 locates nothing and costs at most 12 evaluation-sized pieces of
    /// work per step (NUMERICS.md "One step").
    ///
    /// Error `"config.segment_budget"` (`NotPositive` for 0, `TooLarge` above
    /// [`MAX_SEGMENTS`]); the hybrid law only uses it.
    pub fn with_segment_budget(mut self, segments: usize) -> Result<Self, Error> {
        let problem = if segments == 0 {
            Some(Problem::NotPositive)
        } else if segments > MAX_SEGMENTS {
            Some(Problem::TooLarge)
        } else {
            None
        };
        if let Some(problem) = problem {
            return Err(Error {
                field: "config.segment_budget",
                problem,
                value: segments as f64,
            });
        }
        self.segments = segments;
        Ok(self)
    }

    /// The segment budget of a step (see [`Crane::with_segment_budget`]).
    pub fn segment_budget(&self) -> usize {
        self.segments
    }

    /// Advances by one step `h` with input voltages `u = [u_x, u_y, u_l]` [V], held constant
    /// over the step and saturated to +-12 V.
    ///
    /// A non-finite input, a singular mass matrix, a non-finite result, a result outside the
    /// swing domain or a drive position outside its limits rejects the step: state, modes
    /// and time stay as they were. An accepted step is finite, inside the limits and in the
    /// swing domain, for every valid parameter set.
    pub fn step(&mut self, u: [R; 3]) -> Result<StepReport, StepError> {
        let lim = R::from_f64(U_MAX);
        let mut uc = [R::ZERO; 3];
        for (axis, (dst, v)) in uc.iter_mut().zip(u).enumerate() {
            if !v.is_finite() {
                return Err(StepError::InputNotFinite { axis });
            }
            *dst = if v > lim {
                lim
            } else if v < -lim {
                -lim
            } else {
                v
            };
        }
        // Transport delay, then the amplifier's dead band (both off by default).
        let mut delay = self.delay;
        if self.delay_steps != [0; 3] {
            uc = delay.push(uc, &self.delay_steps);
        }
        for (v, ax) in uc.iter_mut().zip(self.coeffs.axes.iter()) {
            if let Some(d) = ax.deadzone {
                *v = deadband(*v, d);
            }
        }
        let (state, modes, report) = match self.law {
            Law::Hybrid => step_hybrid(
                &self.coeffs,
                self.h,
                &self.state,
                &self.modes,
                &uc,
                self.segments,
            )?,
            Law::Tanh(gamma) => {
                let s = step_smooth(&self.coeffs, gamma, self.h, &self.state, &uc)?;
                let modes = [0, 1, 2].map(|i| Mode::of_velocity(s.qd[i].to_f64()));
                (s, modes, StepReport::default())
            }
        };
        if !state.is_finite() {
            return Err(StepError::NonFinite);
        }
        if !in_domain(&state) {
            return Err(StepError::OutOfDomain);
        }
        if let Some(axis) = outside_limits(&self.coeffs, &state) {
            return Err(StepError::OutOfLimits { axis });
        }
        self.state = state;
        self.modes = modes;
        self.u_last = uc;
        self.delay = delay;
        self.steps += 1;
        Ok(report)
    }

    /// Replaces the state (e.g. an observer's correction), with the checks and mode rules of
    /// [`Crane::new`]; parameters, extensions, delay line, step count and last input are kept.
    /// On error nothing changes.
    pub fn set_state(&mut self, state: State<f64>) -> Result<(), Error> {
        let (state, modes) = admit(&self.coeffs, &state)?;
        self.state = state;
        self.modes = modes;
        Ok(())
    }

    /// Current state.
    pub fn state(&self) -> State<R> {
        self.state
    }

    /// Current modes of X, Y, rope.
    pub fn modes(&self) -> [Mode; 3] {
        self.modes
    }

    /// Simulated time [s]: `n h` after `n` accepted steps.
    pub fn time(&self) -> f64 {
        self.steps as f64 * self.h64
    }

    /// Number of accepted steps.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// Step length [s].
    pub fn h(&self) -> f64 {
        self.h64
    }

    /// The precomputed coefficients (for tools that evaluate the dynamics themselves).
    pub fn coeffs(&self) -> &Coeffs<R> {
        &self.coeffs
    }

    /// Accelerations, friction forces, rope tension and payload position at the current
    /// state with the last applied (saturated) input. Costs one evaluation of the dynamics.
    pub fn output(&self) -> Result<Output<R>, StepError> {
        let e = eval(
            &self.coeffs,
            self.law,
            &self.state,
            &self.modes,
            &self.u_last,
        )?;
        let rope = &self.coeffs.axes[2];
        let tension = self.coeffs.jbar_l * e.qdd[2] - (rope.drive(self.u_last[2]) - e.fric[2]);
        Ok(Output {
            qdd: e.qdd,
            friction: e.fric,
            tension,
            payload: self.state.payload(),
        })
    }
}

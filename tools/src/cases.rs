//! The paper's two simulation cases (section "Simulation"), with every value it leaves open
//! fixed here once.
//!
//! Common to both (paper): no viscous friction (`Dbar = 0`) and no motor inertia (`Jbar = 0`)
//! on every drive axis, dry friction constant over position and equal in both directions.
//! Choices made here (the paper does not state them):
//! - swing damping at its defaults `D_alpha = 2.573e-4`, `D_beta = 0.0059` (the paper names
//!   only the drive axes' viscous friction; without any swing damping the case-1 trolley
//!   would stick and slip forever with ever smaller slips);
//! - masses `m_t = 1.155`, `m_r = 2.20` kg (the defaults), `g = 9.81`, the rig's limits;
//! - axes that take no part in a case are held: in the hybrid model by a large dry friction
//!   (1000 N, they stay `Stopped`, which the tests check), in the smooth models exactly (the
//!   `tanh` law has no modes, so a held axis is a constraint there, see [`crate::smooth`]).
//!
//! **Case 1** (trolley released by the swinging payload): `m_p = 0.457` kg,
//! `Cbar_x = Cbar_y = 1` N, rope held at `L = 0.40` m, released at rest from
//! `alpha = pi/2 + 0.6`, `beta = 0`, trolley at mid-range `x = 0.25`, `y = 0.3125` m, zero
//! input, 30 s (the hybrid trolley comes to rest for good at about 24 s). The swing is in the Y-Z plane, so the X axis feels no force and stays stopped;
//! the compared velocity is the trolley's `yd`.
//!
//! **Case 2** (rope driven by a sinusoidal force): `m_p = 1` kg, `Cbar_l = 9.81` N, X and Y
//! held, payload hanging straight down (`alpha = pi/2`, `beta = 0`), `L(0) = 0.35` m
//! (mid-range). Rope force `F_l(t) = K_l u_l(t) = -m_p g + A sin(2 pi f t)` with
//! `A = 12` N, `f = 0.5` Hz, `K_l = 8.53` N/V (so `|u_l| <= 2.6` V, far from the 12 V
//! saturation), 8 s (4 periods). The hybrid rope then moves between 0.35 and 0.539 m (limit
//! 0.57); the `tanh` models are integrated without end stops, as in the paper's study. The hoist carries the payload's weight and a sinusoid on
//! top, so the net force on the rope axis is `N(t) = F_l + m_p g = A sin(2 pi f t)`; the rope
//! breaks away when `|N| > Cbar_l`, i.e. while `|sin| > 9.81/12`. (With `Cbar_l = m_p g` and a
//! sinusoid without that offset the rope would lower at every positive force and never
//! hoist.) The compared velocity is the rope's `Ld`.
//!
//! Inputs: the smooth models (ode45, fixed RK4) take the continuous-time force. The hybrid
//! model holds its input over each step (zero-order hold, like a DAC); it gets the force
//! averaged over the step (exact impulse per step), which makes the hold error `O(h^2)`.

use crane_model::{AxisParams, Params, State};
use serde::Serialize;

/// Which of the paper's cases.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum CaseId {
    /// Trolley released by the swinging payload.
    One,
    /// Rope driven by a sinusoidal force.
    Two,
}

/// Input of a case.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub enum Input {
    /// All voltages zero.
    Zero,
    /// Rope force `offset + amplitude sin(2 pi freq t)` [N], X and Y zero.
    RopeSine {
        /// Constant part [N].
        offset: f64,
        /// Amplitude [N].
        amplitude: f64,
        /// Frequency [Hz].
        freq: f64,
    },
}

/// One simulation case: parameters, initial state, input, duration, and what is compared.
#[derive(Clone, Debug, PartialEq)]
pub struct Case {
    /// Which case.
    pub id: CaseId,
    /// Short name.
    pub name: &'static str,
    /// Model parameters (validated by `Crane::new`).
    pub params: Params,
    /// Initial state.
    pub init: State<f64>,
    /// Simulated time [s].
    pub duration: f64,
    /// Drive axes held fixed (X, Y, rope): large friction in the hybrid model, a constraint
    /// in the smooth models.
    pub held: [bool; 3],
    /// Index of the compared velocity in `qd` (1: trolley `yd`, 2: rope `Ld`).
    pub observed: usize,
    /// Input.
    pub input: Input,
    /// Output grid [s]: every run is sampled on multiples of this (or of its own step, if
    /// longer).
    pub sample: f64,
}

/// Dry friction [N] that holds an axis which takes no part in a case.
pub const HOLD_FRICTION: f64 = 1000.0;

fn axis(inertia: f64, gain: f64, dry: f64, min: f64, max: f64) -> AxisParams {
    AxisParams {
        inertia,
        gain,
        viscous_pos: 0.0,
        viscous_neg: 0.0,
        dry_pos: [dry, 0.0, 0.0, 0.0, 0.0],
        dry_neg: [dry, 0.0, 0.0, 0.0, 0.0],
        min,
        max,
    }
}

fn base(payload: f64, dry: [f64; 3]) -> Params {
    let d = Params::default();
    Params {
        payload_mass: payload,
        trolley_mass: d.trolley_mass,
        rail_mass: d.rail_mass,
        gravity: d.gravity,
        x: axis(0.0, d.x.gain, dry[0], d.x.min, d.x.max),
        y: axis(0.0, d.y.gain, dry[1], d.y.min, d.y.max),
        rope: axis(0.0, d.rope.gain, dry[2], d.rope.min, d.rope.max),
        damping_alpha: d.damping_alpha,
        damping_beta: d.damping_beta,
    }
}

impl Case {
    /// Case 1 of the paper (see the module documentation).
    pub fn one() -> Case {
        Case {
            id: CaseId::One,
            name: "case 1",
            params: base(0.457, [1.0, 1.0, HOLD_FRICTION]),
            init: State {
                q: [0.25, 0.3125, 0.40, core::f64::consts::FRAC_PI_2 + 0.6, 0.0],
                qd: [0.0; 5],
            },
            duration: 30.0,
            held: [false, false, true],
            observed: 1,
            input: Input::Zero,
            sample: 1e-3,
        }
    }

    /// Case 2 of the paper (see the module documentation).
    pub fn two() -> Case {
        let params = base(1.0, [HOLD_FRICTION, HOLD_FRICTION, 9.81]);
        Case {
            id: CaseId::Two,
            name: "case 2",
            params,
            init: State {
                q: [0.25, 0.3125, 0.35, core::f64::consts::FRAC_PI_2, 0.0],
                qd: [0.0; 5],
            },
            duration: 8.0,
            held: [true, true, false],
            observed: 2,
            input: Input::RopeSine {
                offset: -(params.payload_mass * params.gravity),
                amplitude: 12.0,
                freq: 0.5,
            },
            sample: 1e-3,
        }
    }

    /// Both cases.
    pub fn all() -> [Case; 2] {
        [Case::one(), Case::two()]
    }

    /// Number of output samples after `t = 0` on the grid `sample`.
    pub fn samples(&self) -> usize {
        (self.duration / self.sample).round() as usize
    }

    /// Rope force [N] at time `t` (0 for case 1).
    pub fn rope_force(&self, t: f64) -> f64 {
        match self.input {
            Input::Zero => 0.0,
            Input::RopeSine {
                offset,
                amplitude,
                freq,
            } => offset + amplitude * (2.0 * core::f64::consts::PI * freq * t).sin(),
        }
    }

    /// Rope force [N] averaged over `[t, t + h]` (exact, closed form).
    pub fn rope_force_avg(&self, t: f64, h: f64) -> f64 {
        match self.input {
            Input::Zero => 0.0,
            Input::RopeSine {
                offset,
                amplitude,
                freq,
            } => {
                let w = 2.0 * core::f64::consts::PI * freq;
                offset + amplitude * ((w * t).cos() - (w * (t + h)).cos()) / (w * h)
            }
        }
    }

    /// Net force [N] on the rope axis of a payload hanging straight down, `F_l + m_p g`: what
    /// dry friction must hold while the rope is stopped (case 2).
    pub fn rope_net_force(&self, t: f64) -> f64 {
        self.rope_force(t) + self.params.payload_mass * self.params.gravity
    }

    /// Rope dry-friction threshold `Cbar_l` [N].
    pub fn rope_threshold(&self) -> f64 {
        self.params.rope.dry_pos[0]
    }

    /// Input voltages at time `t` (continuous time; smooth models).
    pub fn u_at(&self, t: f64) -> [f64; 3] {
        [0.0, 0.0, self.rope_force(t) / self.params.rope.gain]
    }

    /// Input voltages held over the step `[t, t + h]` (hybrid model): the step average.
    pub fn u_step(&self, t: f64, h: f64) -> [f64; 3] {
        [0.0, 0.0, self.rope_force_avg(t, h) / self.params.rope.gain]
    }
}

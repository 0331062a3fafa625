//! The control period: read the encoders, update the twin (observer), compute feedforward plus
//! a PD correction on the estimate, apply through the motor drivers. Hardware is reached only
//! through [`Io`], which the embedded-hal drivers (`crate::hal`), the QEMU board and the
//! host-side simulated plant implement.

use super::feedforward::{saturate, voltages, Reference};
use super::io::{Channel, EncoderScale};
use super::observer::{Gains, Observer, Rejected, Update};
use crane_model::{Error, Mode, Params, Real, State, MAX_SEGMENTS};

/// A failed hardware access.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum IoError {
    /// Encoder channel (0 x, 1 y, 2 L, 3 alpha, 4 beta) could not be read.
    Encoder(u8),
    /// Motor driver of axis (0 X, 1 Y, 2 rope) could not be set.
    Driver(u8),
}

/// The hardware as the control loop sees it.
pub trait Io {
    /// Encoder counts of `x, y, L, alpha, beta`, each on its own (a failed channel is
    /// rejected by the observer, the others are used).
    fn read(&mut self) -> [Result<i32, IoError>; 5];
    /// Applies voltages [V]; returns the voltages really applied (after PWM quantisation).
    fn write(&mut self, u: [f64; 3]) -> Result<[f64; 3], IoError>;
    /// Waits for the start of the next period (the simulated board steps its plant here).
    fn wait(&mut self);
    /// The true plant state, where one exists (simulation only).
    fn truth(&self) -> Option<State<f64>> {
        None
    }
}

/// Loop settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LoopConfig {
    /// Control period [s] (the twin steps once per period).
    pub period: f64,
    /// Proportional gains [V/m] of X, Y, rope on the estimated position error.
    pub kp: [f64; 3],
    /// Derivative gains [V s/m] on the estimated velocity error.
    pub kd: [f64; 3],
    /// Breakaway margin of the feedforward (fraction of the threshold).
    pub margin: f64,
    /// Compensate the observer's disturbance estimate in the feedforward.
    pub use_disturbance: bool,
    /// Observer gains.
    pub gains: Gains,
    /// Encoder scale.
    pub scale: EncoderScale,
    /// Segment budget of the twin's step (`1..=MAX_SEGMENTS`, see
    /// `Crane::with_segment_budget`): bounds the work of one period. Default
    /// [`MAX_SEGMENTS`] (every event located); the f64 firmware uses
    /// [`F64_SEGMENT_BUDGET`].
    pub segment_budget: usize,
}

/// Segment budget of the f64 (soft-float) twin on the Cortex-M4F, chosen from the measured
/// cost of a period (firmware/README.md "Measured cost"): every additional segment costs an
/// RK4 over the rest of the step, a relocation and a resolution, about 7 evaluations of the
/// dynamics (~150,000 instructions in soft float), more than the headroom of a 2 ms period
/// at 168 MHz. With 1 the twin locates no event inside a period: stops and end-stop hits are
/// applied at the period's end, breakaways at the next period's start.
pub const F64_SEGMENT_BUDGET: usize = 1;

impl Default for LoopConfig {
    fn default() -> Self {
        LoopConfig {
            period: 2e-3,
            kp: [100.0, 100.0, 300.0],
            kd: [8.0, 8.0, 20.0],
            margin: 0.05,
            use_disturbance: true,
            gains: Gains::default(),
            scale: EncoderScale::RIG,
            segment_budget: MAX_SEGMENTS,
        }
    }
}

/// What one period did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Period<R: Real> {
    /// Voltages commanded [V].
    pub command: [R; 3],
    /// The observer's update, or why it was rejected.
    pub update: Result<Update<R>, Rejected>,
    /// Voltages [V] the update predicted with: those applied during the period that just
    /// ended (what the friction monitor takes as the drive force at rest).
    pub predicted: [R; 3],
}

/// Observer + feedforward + PD on the estimate.
#[derive(Clone, Debug)]
pub struct Controller<R: Real> {
    observer: Observer<R>,
    applied: [R; 3],
    kp: [R; 3],
    kd: [R; 3],
    margin: R,
    use_dist: bool,
    scale: EncoderScale,
}

impl<R: Real> Controller<R> {
    /// A controller whose twin has parameters `params` and starts at `init`. Errors name the
    /// field (parameters, `"state.q[3]"`, `"config.segment_budget"`...).
    pub fn new(params: &Params, init: State<f64>, cfg: &LoopConfig) -> Result<Self, Error> {
        Ok(Controller {
            observer: Observer::new(params, cfg.period, init, &cfg.gains)?
                .with_segment_budget(cfg.segment_budget)?,
            applied: [R::ZERO; 3],
            kp: cfg.kp.map(R::from_f64),
            kd: cfg.kd.map(R::from_f64),
            margin: R::from_f64(cfg.margin),
            use_dist: cfg.use_disturbance,
            scale: cfg.scale,
        })
    }

    /// Positions of encoder counts (a failed channel gives NaN, which the observer rejects).
    pub fn positions(&self, counts: &[Result<i32, IoError>; 5]) -> [R; 5] {
        let mut y = [R::ZERO; 5];
        for ((yi, c), ch) in y.iter_mut().zip(counts).zip(Channel::ALL) {
            *yi = match c {
                Ok(c) => R::from_f64(self.scale.position(ch, *c)),
                Err(_) => R::from_f64(f64::NAN),
            };
        }
        y
    }

    /// One period: update the twin with the voltages applied during the last period and the
    /// positions `y` measured now, then compute the command for reference `r`.
    pub fn period(&mut self, y: [R; 5], r: &Reference<R>) -> Period<R> {
        let predicted = self.applied;
        let update = self.observer.update(predicted, y);
        let est = self.observer.state();
        let modes: [Mode; 3] = self.observer.modes();
        let dist = if self.use_dist {
            self.observer.disturbance()
        } else {
            [R::ZERO; 3]
        };
        let ff = voltages(
            self.observer.twin().coeffs(),
            &est,
            &modes,
            r,
            &dist,
            self.margin,
        );
        let mut command = [R::ZERO; 3];
        for i in 0..3 {
            let fb = self.kp[i] * (r.pos[i] - est.q[i]) + self.kd[i] * (r.vel[i] - est.qd[i]);
            command[i] = saturate(ff[i] + fb);
        }
        Period {
            command,
            update,
            predicted,
        }
    }

    /// Records the voltages the drivers really applied (what the next update predicts with).
    /// Non-finite values are stored as 0 V (the drivers switch off on them).
    pub fn applied(&mut self, u: [R; 3]) {
        self.applied = u.map(|v| if v.is_finite() { v } else { R::ZERO });
    }

    /// The observer.
    pub fn observer(&self) -> &Observer<R> {
        &self.observer
    }

    /// One full period on hardware `io`: read, update, compute, write. Returns the period's
    /// record; a driver error leaves the applied voltage at 0 for the twin.
    pub fn run_period<I: Io>(&mut self, io: &mut I, r: &Reference<R>) -> Period<R> {
        let counts = io.read();
        let y = self.positions(&counts);
        let p = self.period(y, r);
        let applied = match io.write(p.command.map(R::to_f64)) {
            Ok(a) => a.map(R::from_f64),
            Err(_) => [R::ZERO; 3],
        };
        self.applied(applied);
        p
    }
}

/// A minimum-jerk move of the three drive axes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Move {
    /// Start time [s].
    pub start: f64,
    /// Duration [s] (> 0).
    pub duration: f64,
    /// Target positions [m] of X, Y, L.
    pub to: [f64; 3],
}

/// A reference: an initial position and a sequence of moves (in time order, not overlapping).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Trajectory<'a> {
    /// Initial positions [m].
    pub from: [f64; 3],
    /// Moves.
    pub moves: &'a [Move],
}

/// A demonstration: transport, hoist/lower, a short slow move (breakaway dominated), dwell.
pub const DEMO: Trajectory<'static> = Trajectory {
    from: [0.10, 0.15, 0.30],
    moves: &[
        Move {
            start: 0.2,
            duration: 1.5,
            to: [0.35, 0.15, 0.30],
        },
        Move {
            start: 2.0,
            duration: 1.5,
            to: [0.35, 0.45, 0.40],
        },
        Move {
            start: 4.0,
            duration: 2.0,
            to: [0.12, 0.30, 0.25],
        },
        Move {
            start: 6.5,
            duration: 0.8,
            to: [0.135, 0.31, 0.25],
        },
    ],
};

impl Trajectory<'_> {
    /// Reference at time `t` [s] (f64 arithmetic, rounded to `R`).
    pub fn at<R: Real>(&self, t: f64) -> Reference<R> {
        let mut from = self.from;
        let mut pos = from;
        let mut vel = [0.0; 3];
        let mut acc = [0.0; 3];
        for m in self.moves {
            if t < m.start {
                break;
            }
            let tau = (t - m.start) / m.duration;
            if tau >= 1.0 {
                pos = m.to;
                vel = [0.0; 3];
                acc = [0.0; 3];
                from = m.to;
                continue;
            }
            let s = tau * tau * tau * (10.0 - 15.0 * tau + 6.0 * tau * tau);
            let sd = 30.0 * tau * tau * (1.0 - tau) * (1.0 - tau) / m.duration;
            let sdd = 60.0 * tau * (1.0 - tau) * (1.0 - 2.0 * tau) / (m.duration * m.duration);
            for i in 0..3 {
                let d = m.to[i] - from[i];
                pos[i] = from[i] + d * s;
                vel[i] = d * sd;
                acc[i] = d * sdd;
            }
            break;
        }
        Reference {
            pos: pos.map(R::from_f64),
            vel: vel.map(R::from_f64),
            acc: acc.map(R::from_f64),
        }
    }
}

//! The twin and its observer: a model instance driven by the applied voltages and corrected,
//! every period, by the encoder residual.
//!
//! Per drive axis (X, Y, rope) the correction is a fading-memory (critically damped)
//! alpha-beta-gamma filter around the hybrid model's prediction: position, velocity and a
//! disturbance force `d` [N] (what the model's friction gets wrong; it enters the twin as the
//! equivalent voltage `d / K`). Per swing angle it is an alpha-beta filter. All poles of the
//! correction sit at `theta` (checked in the tests against the triple integrator).
//!
//! Hybrid detail: a drive axis that the twin holds `Stopped` and whose residual stays within
//! `stick_band` only gets its position corrected, so quantisation noise neither releases it
//! nor winds up `d`; a larger residual corrects the velocity too, which releases the axis (the
//! plant moved while the model said it sticks).
//!
//! Rejections: a non-finite voltage rejects the whole update (nothing changes); a non-finite
//! measurement is not used (the twin runs open loop for that period). The twin's state stays
//! finite in every case: the model itself rejects steps that would leave it non-finite.

use crane_model::{hangs, Config, Crane, Error, Mode, Params, Real, State, StepError};

/// Observer gains (in `f64`; converted once to the twin's scalar type).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Gains {
    /// Position gain of the drive axes.
    pub alpha: f64,
    /// Velocity gain of the drive axes (times `1/T`).
    pub beta: f64,
    /// Disturbance gain of the drive axes (times `2 M_ii / T^2`).
    pub gamma: f64,
    /// Position gain of the swing angles.
    pub swing_alpha: f64,
    /// Velocity gain of the swing angles (times `1/T`).
    pub swing_beta: f64,
    /// Residual [m] below which a stopped axis stays stopped (position correction only).
    pub stick_band: [f64; 3],
    /// Bound on the disturbance estimate [N] (anti-windup).
    pub max_disturbance: f64,
    /// Forgetting factor of the residual mean square (per period).
    pub rms_lambda: f64,
}

impl Gains {
    /// Critically damped gains with all poles at `theta` (drive axes) and `theta_swing`
    /// (swing angles): `alpha = 1 - th^3`, `beta = 1.5 (1 - th^2)(1 - th)`,
    /// `gamma = 0.5 (1 - th)^3`; swing `1 - th^2`, `(1 - th)^2`.
    pub fn fading_memory(theta: f64, theta_swing: f64) -> Self {
        let t = theta;
        let s = theta_swing;
        let res = super::io::EncoderScale::RIG.res;
        Gains {
            alpha: 1.0 - t * t * t,
            beta: 1.5 * (1.0 - t * t) * (1.0 - t),
            gamma: 0.5 * (1.0 - t) * (1.0 - t) * (1.0 - t),
            swing_alpha: 1.0 - s * s,
            swing_beta: (1.0 - s) * (1.0 - s),
            stick_band: [2.5 * res[0], 2.5 * res[1], 2.5 * res[2]],
            max_disturbance: 30.0,
            rms_lambda: 0.02,
        }
    }
}

impl Default for Gains {
    /// Poles at 0.9 (drive axes, time constant about 20 ms at 2 ms) and 0.8 (swing).
    fn default() -> Self {
        Gains::fading_memory(0.9, 0.8)
    }
}

/// Why an update was not (fully) used.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Rejected {
    /// Applied voltage of this axis is not finite: the update was rejected, nothing changed.
    InputNotFinite {
        /// Axis index (0 X, 1 Y, 2 rope).
        axis: usize,
    },
    /// Measurement of this channel is not finite: the twin ran open loop for this period.
    MeasurementNotFinite {
        /// Channel (0 x, 1 y, 2 L, 3 alpha, 4 beta).
        channel: usize,
    },
}

/// Counters of what happened since start: `u64`, so they do not wrap in any service life
/// (a `u32` of 2 ms periods wrapped after 99 days), and saturating.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Counters {
    /// Updates done.
    pub updates: u64,
    /// Updates rejected for a non-finite voltage.
    pub bad_inputs: u64,
    /// Measurements not used (non-finite).
    pub bad_measurements: u64,
    /// Twin steps the model rejected (the twin kept its state).
    pub twin_errors: u64,
    /// Corrections the model rejected (the prediction was kept).
    pub correction_errors: u64,
    /// Swing corrections skipped because they left the domain.
    pub swing_skips: u64,
}

/// Result of one update.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Update<R: Real> {
    /// Residual `measurement - prediction` per channel [m, rad].
    pub innovation: [R; 5],
    /// The model's verdict on the prediction step, if it rejected it.
    pub twin_error: Option<StepError>,
}

/// The twin with its observer.
#[derive(Clone, Debug)]
pub struct Observer<R: Real> {
    twin: Crane<R>,
    g_alpha: R,
    g_beta: R,
    g_dist: [R; 3],
    s_alpha: R,
    s_beta: R,
    band: [R; 3],
    dmax: R,
    lambda: R,
    inv_gain: [R; 3],
    dist: [R; 3],
    innovation: [R; 5],
    mean_sq: [R; 5],
    counters: Counters,
}

fn abs<R: Real>(x: R) -> R {
    if x < R::ZERO {
        -x
    } else {
        x
    }
}

fn clamp<R: Real>(x: R, lo: R, hi: R) -> R {
    if x > hi {
        hi
    } else if x < lo {
        lo
    } else {
        x
    }
}

impl<R: Real> Observer<R> {
    /// A twin of the crane with parameters `params`, stepped once per period `period` [s],
    /// starting at `init`.
    pub fn new(
        params: &Params,
        period: f64,
        init: State<f64>,
        gains: &Gains,
    ) -> Result<Self, Error> {
        let config = Config {
            h: period,
            ..Config::default()
        };
        let twin = Crane::<R>::new(params, config, init)?;
        let t = period;
        let m = [
            twin.coeffs().m00.to_f64(),
            twin.coeffs().m11.to_f64(),
            twin.coeffs().m22.to_f64(),
        ];
        let axes = params.axes();
        let d = |i: usize| R::from_f64(m[i] * 2.0 * gains.gamma / (t * t));
        Ok(Observer {
            twin,
            g_alpha: R::from_f64(gains.alpha),
            g_beta: R::from_f64(gains.beta / t),
            g_dist: [d(0), d(1), d(2)],
            s_alpha: R::from_f64(gains.swing_alpha),
            s_beta: R::from_f64(gains.swing_beta / t),
            band: gains.stick_band.map(R::from_f64),
            dmax: R::from_f64(gains.max_disturbance),
            lambda: R::from_f64(gains.rms_lambda),
            inv_gain: [
                R::from_f64(1.0 / axes[0].gain),
                R::from_f64(1.0 / axes[1].gain),
                R::from_f64(1.0 / axes[2].gain),
            ],
            dist: [R::ZERO; 3],
            innovation: [R::ZERO; 5],
            mean_sq: [R::ZERO; 5],
            counters: Counters::default(),
        })
    }

    /// Sets the twin's segment budget ([`Crane::with_segment_budget`]: at most `segments`
    /// integration segments per period, events beyond it applied at the period's end), a
    /// bound on the work of one update. Errors name `"config.segment_budget"`.
    pub fn with_segment_budget(mut self, segments: usize) -> Result<Self, Error> {
        self.twin = self.twin.with_segment_budget(segments)?;
        Ok(self)
    }

    /// One period: predict with the voltages `u` [V] applied during the period that just
    /// ended, then correct with the positions `y` [m, m, m, rad, rad] measured at its end.
    pub fn update(&mut self, u: [R; 3], y: [R; 5]) -> Result<Update<R>, Rejected> {
        if let Some(axis) = u.iter().position(|v| !v.is_finite()) {
            self.counters.bad_inputs = self.counters.bad_inputs.saturating_add(1);
            return Err(Rejected::InputNotFinite { axis });
        }
        self.counters.updates = self.counters.updates.saturating_add(1);
        // Predict: the model with the disturbance estimate as an equivalent voltage.
        let mut ut = u;
        for i in 0..3 {
            ut[i] = u[i] + self.dist[i] * self.inv_gain[i];
        }
        let twin_error = self.twin.step(ut).err();
        if twin_error.is_some() {
            self.counters.twin_errors = self.counters.twin_errors.saturating_add(1);
        }
        if let Some(channel) = y.iter().position(|v| !v.is_finite()) {
            self.counters.bad_measurements = self.counters.bad_measurements.saturating_add(1);
            return Err(Rejected::MeasurementNotFinite { channel });
        }
        // Correct.
        let s = self.twin.state();
        let modes = self.twin.modes();
        let mut q = s.q;
        let mut qd = s.qd;
        let mut r = [R::ZERO; 5];
        for i in 0..5 {
            r[i] = y[i] - s.q[i];
        }
        let ax = &self.twin.coeffs().axes;
        for i in 0..3 {
            let ri = r[i];
            q[i] = clamp(q[i] + self.g_alpha * ri, ax[i].min, ax[i].max);
            let held = modes[i] == Mode::Stopped && abs(ri) <= self.band[i];
            if !held {
                qd[i] = qd[i] + self.g_beta * ri;
                self.dist[i] = clamp(self.dist[i] + self.g_dist[i] * ri, -self.dmax, self.dmax);
            }
        }
        let a = q[3] + self.s_alpha * r[3];
        let b = q[4] + self.s_alpha * r[4];
        if hangs(a, b) {
            q[3] = a;
            q[4] = b;
            qd[3] = qd[3] + self.s_beta * r[3];
            qd[4] = qd[4] + self.s_beta * r[4];
        } else {
            self.counters.swing_skips = self.counters.swing_skips.saturating_add(1);
        }
        let corrected = State {
            q: q.map(R::to_f64),
            qd: qd.map(R::to_f64),
        };
        // Same checks and mode rules as `Crane::new`; keeps extensions and the segment budget.
        if self.twin.set_state(corrected).is_err() {
            self.counters.correction_errors = self.counters.correction_errors.saturating_add(1);
        }
        for (ms, ri) in self.mean_sq.iter_mut().zip(r) {
            *ms = *ms + self.lambda * (ri * ri - *ms);
        }
        self.innovation = r;
        Ok(Update {
            innovation: r,
            twin_error,
        })
    }

    /// The twin's state estimate.
    pub fn state(&self) -> State<R> {
        self.twin.state()
    }

    /// The twin's modes.
    pub fn modes(&self) -> [Mode; 3] {
        self.twin.modes()
    }

    /// The twin (model instance), e.g. for [`Crane::output`] or its coefficients.
    pub fn twin(&self) -> &Crane<R> {
        &self.twin
    }

    /// Disturbance force estimates [N] of X, Y, rope: the force the plant has and the model
    /// lacks (positive along the axis). A friction model that is too high shows as `d`
    /// along the motion.
    pub fn disturbance(&self) -> [R; 3] {
        self.dist
    }

    /// Last residual per channel [m, rad].
    pub fn innovation(&self) -> [R; 5] {
        self.innovation
    }

    /// Exponentially weighted mean square of the residual per channel: the online "model is
    /// wrong here" signal (compare with the quantisation floor `res^2 / 12`).
    pub fn residual_mean_square(&self) -> [R; 5] {
        self.mean_sq
    }

    /// What happened since start.
    pub fn counters(&self) -> Counters {
        self.counters
    }
}

//! The virtual rig: the crane model as the plant, recorded as the INTECO rig records it
//! (2 ms sampling, 4096-pulse encoders on the motor shafts and swing axes, zero-order-hold
//! voltages saturated at +-12 V), with optional noise and a hook for effects the model does
//! not have; and the [`Rig`] trait that the identification campaign drives, which a real rig
//! could implement too.

use crate::data::{BreakawayNoise, CraneRun, RunKind};
use crate::rng::Rng;
use crane_model::{Config, Crane, Extensions, FrictionLaw, Params, State, StepError};
use serde::{Deserialize, Serialize};

/// Index of the X drive.
pub const AXIS_X: usize = 0;
/// Index of the Y drive.
pub const AXIS_Y: usize = 1;
/// Index of the rope drive.
pub const AXIS_L: usize = 2;

/// How the virtual rig measures and disturbs.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PlantConfig {
    /// Sampling period [s].
    pub sample_time: f64,
    /// Model steps per sample (the model's step is `sample_time / substeps`).
    pub substeps: usize,
    /// Encoder pulses per revolution (motor shafts of X, Y, rope and the two swing axes).
    pub encoder_pulses: f64,
    /// Drive pulley radii `R_x, R_y, R_l` [m]: a motor revolution is `2 pi R` of travel.
    pub radii: [f64; 3],
    /// Mass hanging on the rope in runs declared unloaded (`payload_kg = 0`) [kg]: the
    /// model needs a positive payload; this is the hook.
    pub hook_kg: f64,
    /// Breakaway noise: on every breakaway probe the dry friction of the probed axis and
    /// direction is shifted by a normal deviate of this variance [N^2] (the probe-to-probe
    /// scatter of a real rig). `None`: no scatter.
    pub breakaway_noise: Option<BreakawayNoise>,
    /// Standard deviation of position noise added before quantisation [encoder counts].
    pub position_noise_counts: f64,
    /// Standard deviation of voltage noise reaching the motors (not recorded) [V].
    pub input_noise_v: f64,
    /// Seed of all random draws of the plant.
    pub seed: u64,
}

impl Default for PlantConfig {
    fn default() -> Self {
        PlantConfig {
            sample_time: 0.002,
            substeps: 2,
            encoder_pulses: 4096.0,
            radii: [0.040, 0.040, 0.015],
            hook_kg: 0.001,
            breakaway_noise: Some(BreakawayNoise::default()),
            position_noise_counts: 0.0,
            input_noise_v: 0.0,
            seed: 1,
        }
    }
}

impl PlantConfig {
    /// Resolution of coordinate `i` of `q = [x, y, L, alpha, beta]`: `2 pi R / pulses` for
    /// the drives, `2 pi / pulses` for the angles.
    pub fn resolution(&self, i: usize) -> f64 {
        let rev = 2.0 * core::f64::consts::PI / self.encoder_pulses;
        match i {
            0..=2 => rev * self.radii[i],
            _ => rev,
        }
    }
}

/// Extra physical effects the model does not have, for the discrepancy workbench. Every
/// method has a no-op default.
pub trait Effect {
    /// Changes the plant's parameters and model extensions for an experiment of `kind`.
    fn plant(&self, _kind: RunKind, _params: &mut Params, _ext: &mut Extensions) {}
    /// Transforms the voltages reaching the motors at time `t` (the record keeps the
    /// commanded ones).
    fn input(&mut self, _t: f64, u: [f64; 3]) -> [f64; 3] {
        u
    }
    /// Transforms the true coordinates before the encoders at time `t`.
    fn measure(&mut self, _t: f64, q: [f64; 5]) -> [f64; 5] {
        q
    }
}

/// The voltages of an experiment, one vector per sample, held over the sample.
#[derive(Clone, Debug, PartialEq)]
pub enum Input {
    /// Open loop.
    Open(Vec<[f64; 3]>),
    /// A signal plus a weak centring feedback on the measured drive positions,
    /// `u = signal + gain (center - q)`, as a lab keeps a rich excitation off the end stops.
    Centred {
        /// Signal [V].
        signal: Vec<[f64; 3]>,
        /// Centre of each drive [m].
        center: [f64; 3],
        /// Feedback gain of each drive [V/m] (0: open loop on that drive).
        gain: [f64; 3],
    },
}

impl Input {
    /// Number of samples.
    pub fn len(&self) -> usize {
        match self {
            Input::Open(s) => s.len(),
            Input::Centred { signal, .. } => signal.len(),
        }
    }
    /// No samples.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// An experiment: initial configuration at rest, payload, inputs.
#[derive(Clone, Debug, PartialEq)]
pub struct Experiment {
    /// Name (becomes the file stem).
    pub name: String,
    /// Kind.
    pub kind: RunKind,
    /// Payload [kg] (0: unloaded, the hook only).
    pub payload_kg: f64,
    /// Initial `q = [x, y, L, alpha, beta]`, at rest.
    pub init: [f64; 5],
    /// Inputs.
    pub input: Input,
}

/// A breakaway probe: the axis at rest at `position`, a voltage ramp in one direction until
/// the encoder sees motion.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Probe {
    /// Drive axis (0 X, 1 Y, 2 rope).
    pub axis: usize,
    /// Direction of the ramp (`true`: positive voltage, increasing coordinate).
    pub positive: bool,
    /// Position of the probed axis [m].
    pub position: f64,
    /// Payload [kg] (0: unloaded).
    pub payload_kg: f64,
    /// First voltage of the ramp (magnitude) [V].
    pub start_v: f64,
    /// Ramp rate (magnitude) [V/s].
    pub rate_v_per_s: f64,
    /// Largest voltage tried (magnitude) [V].
    pub max_v: f64,
}

impl Probe {
    /// A probe with the default ramp of its axis: X and Y from 0.15 V at 0.02 V/s, the rope
    /// from 0.8 V at 0.01 V/s.
    pub fn new(axis: usize, positive: bool, position: f64) -> Self {
        let (start_v, rate_v_per_s) = if axis == AXIS_L {
            (0.8, 0.01)
        } else {
            (0.15, 0.02)
        };
        Probe {
            axis,
            positive,
            position,
            payload_kg: 0.0,
            start_v,
            rate_v_per_s,
            max_v: 4.0,
        }
    }
}

/// Motion onset found in a breakaway ramp.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Onset {
    /// Sample index where the encoder first shows motion.
    pub index: usize,
    /// Voltage held during the sample in which motion began (signed) [V].
    pub volts: f64,
    /// Measured position at rest before the ramp [m].
    pub position: f64,
}

/// Finds the onset of motion of `axis` in a ramp record: the first sample whose measured
/// position differs from the first one by more than `threshold` [m] (half an encoder count
/// for clean data); the onset voltage is the one held over the preceding sample.
pub fn detect_onset(run: &CraneRun, axis: usize, threshold: f64) -> Option<Onset> {
    let pos = run.pos(axis);
    let p0 = *pos.first()?;
    let k = pos.iter().position(|&p| (p - p0).abs() > threshold)?;
    if k == 0 {
        return None;
    }
    Some(Onset {
        index: k,
        volts: run.u[axis][k - 1],
        position: p0,
    })
}

/// Drive displacement `tau` seconds after breakaway under a voltage ramp, for a drive with
/// viscous coefficient `d` per unit of drive (N s/m per N/V of gain, i.e. `Dbar / K`), time
/// constant `t = M / Dbar` and ramp rate `r` [V/s]: `(r / d) (tau^2/2 - t tau + t^2 (1 -
/// exp(-tau / t)))`.
pub fn ramp_displacement(tau: f64, r: f64, d: f64, t: f64) -> f64 {
    if tau <= 0.0 {
        return 0.0;
    }
    let core = if t > 0.0 {
        0.5 * tau * tau - t * tau + t * t * (1.0 - (-tau / t).exp())
    } else {
        0.5 * tau * tau
    };
    r / d * core
}

/// The onset of a breakaway ramp corrected for the detection lag: the encoder sees motion
/// only once the drive has crossed into the next count, while the ramp goes on. From the
/// times at which the following counts are crossed and the drive's known dynamics
/// (`d = Dbar / K` [V s/m], `t = M / Dbar` [s]) this fits the breakaway time and the unknown
/// sub-count offset, and returns the ramp voltage at the breakaway time. Falls back to
/// [`detect_onset`] when fewer than two counts follow or the ramp rate is not constant.
pub fn corrected_onset(run: &CraneRun, axis: usize, res: f64, d: f64, t: f64) -> Option<Onset> {
    let o = detect_onset(run, axis, 0.5 * res)?;
    let pos = run.pos(axis);
    let u = &run.u[axis];
    if run.len() < 3 || d.is_nan() || d <= 0.0 {
        return Some(o);
    }
    let dt = run.t[1] - run.t[0];
    let sgn = o.volts.signum();
    let r = (u[1] - u[0]).abs() / dt;
    if r.is_nan() || r <= 0.0 || ((u[2] - u[1]).abs() / dt - r).abs() > 1e-6 * r.max(1e-9) {
        return Some(o);
    }
    let mut crossings = Vec::new();
    let mut j = 1usize;
    for k in 0..pos.len() {
        while sgn * (pos[k] - o.position) > (j as f64 - 0.5) * res {
            crossings.push((j as f64, run.t[k] - 0.5 * dt));
            j += 1;
        }
    }
    if crossings.len() < 2 {
        return Some(o);
    }
    let inv = |x: f64| {
        // displacement is increasing in tau; bisection on [0, 100 s]
        let (mut lo, mut hi) = (0.0, 100.0);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if ramp_displacement(mid, r, d, t) < x {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        0.5 * (lo + hi)
    };
    let mut best = (f64::INFINITY, 0.0);
    let steps = 64;
    for i in 0..steps {
        let delta = (i as f64 + 0.5) / steps as f64 * res;
        let tb: Vec<f64> = crossings
            .iter()
            .map(|&(j, tj)| tj - inv(j * res - delta))
            .collect();
        let mean = tb.iter().sum::<f64>() / tb.len() as f64;
        let sse: f64 = tb.iter().map(|x| (x - mean) * (x - mean)).sum();
        if sse < best.0 {
            best = (sse, mean);
        }
    }
    let tb = best.1.max(run.t[0]);
    let volts = sgn * (u[0].abs() + r * (tb - run.t[0]));
    Some(Onset { volts, ..o })
}

/// A breakaway probe's outcome.
#[derive(Clone, Debug, PartialEq)]
pub struct BreakawayRecord {
    /// What was asked.
    pub probe: Probe,
    /// The ramp as recorded.
    pub run: CraneRun,
    /// The onset, if the axis moved before `max_v`.
    pub onset: Option<Onset>,
}

/// A rig failure.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum RigError {
    /// The plant simulation rejected a step.
    #[error("experiment `{experiment}` at t = {time} s: {error}")]
    Step {
        /// Experiment name.
        experiment: String,
        /// Time.
        time: f64,
        /// Model error.
        error: StepError,
    },
    /// Bad parameters or initial state for the plant.
    #[error("experiment `{experiment}`: {message}")]
    Setup {
        /// Experiment name.
        experiment: String,
        /// Message.
        message: String,
    },
}

/// What the identification campaign needs from a rig, virtual or real.
pub trait Rig {
    /// Sampling period [s].
    fn sample_time(&self) -> f64;
    /// Measurement resolution of coordinate `i` of `[x, y, L, alpha, beta]`.
    fn resolution(&self, i: usize) -> f64;
    /// Runs an experiment and returns the record.
    fn run(&mut self, exp: &Experiment) -> Result<CraneRun, RigError>;
    /// Puts the axis at rest at the probe's position, ramps the voltage, and returns the
    /// record with the onset of motion (the breakaway voltage; times the axis gain it is the
    /// breakaway force).
    fn breakaway(&mut self, probe: &Probe) -> Result<BreakawayRecord, RigError>;
}

/// The crane model as a rig.
pub struct VirtualRig {
    truth: Params,
    cfg: PlantConfig,
    rng: Rng,
    effect: Option<Box<dyn Effect>>,
}

impl std::fmt::Debug for VirtualRig {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("VirtualRig")
            .field("truth", &self.truth)
            .field("cfg", &self.cfg)
            .field("effect", &self.effect.is_some())
            .finish()
    }
}

/// Encoder counts recorded after a breakaway onset.
pub const TAIL_COUNTS: usize = 6;

/// Where the other axes stand during a probe.
const PARK: [f64; 3] = [0.25, 0.30, 0.35];

impl VirtualRig {
    /// A rig whose plant has the parameters `truth` (the payload is set per experiment).
    pub fn new(truth: Params, cfg: PlantConfig) -> Self {
        VirtualRig {
            truth,
            rng: Rng::new(cfg.seed),
            cfg,
            effect: None,
        }
    }

    /// Adds an extra physical effect.
    pub fn with_effect(mut self, effect: Box<dyn Effect>) -> Self {
        self.effect = Some(effect);
        self
    }

    /// The plant's true parameters.
    pub fn truth(&self) -> &Params {
        &self.truth
    }

    /// The plant configuration.
    pub fn config(&self) -> &PlantConfig {
        &self.cfg
    }

    fn quantise(&mut self, q: [f64; 5]) -> [f64; 5] {
        let mut out = q;
        for (i, v) in out.iter_mut().enumerate() {
            let res = self.cfg.resolution(i);
            let mut counts = *v / res;
            if self.cfg.position_noise_counts > 0.0 {
                counts += self.cfg.position_noise_counts * self.rng.normal();
            }
            *v = counts.round() * res;
        }
        out
    }

    /// Simulates `n` samples; `input(k, measured q)` gives the commanded voltages, `stop`
    /// ends the run early (after recording sample k).
    #[allow(clippy::too_many_arguments)]
    fn simulate(
        &mut self,
        name: &str,
        kind: RunKind,
        params: Params,
        init: [f64; 5],
        n: usize,
        mut input: impl FnMut(usize, &[f64; 5]) -> [f64; 3],
        mut stop: impl FnMut(usize, &[f64; 5]) -> bool,
    ) -> Result<CraneRun, RigError> {
        let mut params = params;
        let mut ext = Extensions::default();
        if let Some(e) = &self.effect {
            e.plant(kind, &mut params, &mut ext);
        }
        let setup = |m: String| RigError::Setup {
            experiment: name.to_string(),
            message: m,
        };
        let h = self.cfg.sample_time / self.cfg.substeps as f64;
        let crane: Crane = Crane::new(
            &params,
            Config {
                h,
                law: FrictionLaw::Hybrid,
            },
            State {
                q: init,
                qd: [0.0; 5],
            },
        )
        .map_err(|e| setup(e.to_string()))?;
        let mut crane = crane
            .with_extensions(&ext)
            .map_err(|e| setup(e.to_string()))?;
        let mut rec = CraneRun::default();
        for k in 0..n {
            let t = k as f64 * self.cfg.sample_time;
            let mut q = crane.state().q;
            if let Some(e) = self.effect.as_mut() {
                q = e.measure(t, q);
            }
            let qm = self.quantise(q);
            let mut u = input(k, &qm);
            for v in u.iter_mut() {
                *v = v.clamp(-12.0, 12.0);
            }
            rec.t.push(t);
            for (i, col) in rec.u.iter_mut().enumerate() {
                col.push(u[i]);
            }
            rec.x.push(qm[0]);
            rec.y.push(qm[1]);
            rec.l.push(qm[2]);
            rec.alpha.push(qm[3]);
            rec.beta.push(qm[4]);
            if stop(k, &qm) {
                break;
            }
            let mut up = u;
            if let Some(e) = self.effect.as_mut() {
                up = e.input(t, up);
            }
            if self.cfg.input_noise_v > 0.0 {
                for v in up.iter_mut() {
                    *v += self.cfg.input_noise_v * self.rng.normal();
                }
            }
            for _ in 0..self.cfg.substeps {
                crane.step(up).map_err(|error| RigError::Step {
                    experiment: name.to_string(),
                    time: t,
                    error,
                })?;
            }
        }
        Ok(rec)
    }

    fn params_for(&self, payload_kg: f64) -> Params {
        let mut p = self.truth;
        p.payload_mass = if payload_kg > 0.0 {
            payload_kg
        } else {
            self.cfg.hook_kg
        };
        p
    }
}

impl Rig for VirtualRig {
    fn sample_time(&self) -> f64 {
        self.cfg.sample_time
    }

    fn resolution(&self, i: usize) -> f64 {
        self.cfg.resolution(i)
    }

    fn run(&mut self, exp: &Experiment) -> Result<CraneRun, RigError> {
        let params = self.params_for(exp.payload_kg);
        let n = exp.input.len();
        let input = exp.input.clone();
        self.simulate(
            &exp.name,
            exp.kind,
            params,
            exp.init,
            n,
            move |k, q| match &input {
                Input::Open(s) => s[k],
                Input::Centred {
                    signal,
                    center,
                    gain,
                } => {
                    let mut u = signal[k];
                    for i in 0..3 {
                        u[i] += gain[i] * (center[i] - q[i]);
                    }
                    u
                }
            },
            |_, _| false,
        )
    }

    fn breakaway(&mut self, probe: &Probe) -> Result<BreakawayRecord, RigError> {
        let mut params = self.params_for(probe.payload_kg);
        let kind = match probe.axis {
            AXIS_X => RunKind::BreakawayX,
            AXIS_Y => RunKind::BreakawayY,
            _ => RunKind::RopeQuasistatic,
        };
        if let Some(noise) = self.cfg.breakaway_noise {
            let var = match (probe.axis, probe.positive) {
                (AXIS_X, true) => noise.x_pos,
                (AXIS_X, false) => noise.x_neg,
                (AXIS_Y, true) => noise.y_pos,
                (AXIS_Y, false) => noise.y_neg,
                _ => 0.0,
            };
            let shift = var.sqrt() * self.rng.normal();
            let ax = match probe.axis {
                AXIS_X => &mut params.x,
                AXIS_Y => &mut params.y,
                _ => &mut params.rope,
            };
            if probe.positive {
                ax.dry_pos[0] += shift;
            } else {
                ax.dry_neg[0] += shift;
            }
        }
        let mut init = [PARK[0], PARK[1], PARK[2], core::f64::consts::FRAC_PI_2, 0.0];
        init[probe.axis] = probe.position;
        let dt = self.cfg.sample_time;
        let sign = if probe.positive { 1.0 } else { -1.0 };
        let steps_to_max = ((probe.max_v - probe.start_v).max(0.0) / (probe.rate_v_per_s * dt))
            .ceil() as usize
            + 1;
        let threshold = 0.5 * self.cfg.resolution(probe.axis);
        let axis = probe.axis;
        let mut p0: Option<f64> = None;
        let mut moved_at: Option<usize> = None;
        // Keep ramping after the onset until the drive has crossed a few more counts (or
        // 3 s passed): the count times tell how late the onset was seen.
        let tail = (3.0 / dt).round() as usize;
        let enough = (TAIL_COUNTS as f64 + 0.5) * self.cfg.resolution(probe.axis);
        let name = format!("breakaway_{}", ["x", "y", "l"][axis]);
        let run = self.simulate(
            &name,
            kind,
            params,
            init,
            steps_to_max + tail,
            |k, _| {
                let mut u = [0.0; 3];
                let v = (probe.start_v + probe.rate_v_per_s * k as f64 * dt).min(probe.max_v);
                u[axis] = sign * v;
                u
            },
            |k, q| {
                let p = q[axis];
                let start = *p0.get_or_insert(p);
                if moved_at.is_none() && (p - start).abs() > threshold {
                    moved_at = Some(k);
                }
                (p - start).abs() > enough || matches!(moved_at, Some(m) if k >= m + tail)
            },
        )?;
        let onset = detect_onset(&run, axis, threshold);
        Ok(BreakawayRecord {
            probe: *probe,
            run,
            onset,
        })
    }
}

/// Input signals of the experiments.
pub mod signals {
    use crate::rng::Rng;

    /// Steps on one drive: levels of random magnitude in `[lo, hi]` V with alternating sign,
    /// each held a random time in `[t_min, t_max]` s.
    pub fn multistep(
        rng: &mut Rng,
        n: usize,
        dt: f64,
        axis: usize,
        (lo, hi): (f64, f64),
        (t_min, t_max): (f64, f64),
    ) -> Vec<[f64; 3]> {
        let mut out = Vec::with_capacity(n);
        let mut sign = 1.0;
        while out.len() < n {
            let level = sign * rng.range(lo, hi);
            let hold = (rng.range(t_min, t_max) / dt).round().max(1.0) as usize;
            for _ in 0..hold.min(n - out.len()) {
                let mut u = [0.0; 3];
                u[axis] = level;
                out.push(u);
            }
            sign = -sign;
        }
        out
    }

    /// Linear chirp on one drive from `f0` to `f1` Hz over the run, amplitude `a` V.
    pub fn chirp(n: usize, dt: f64, axis: usize, f0: f64, f1: f64, a: f64) -> Vec<[f64; 3]> {
        let total = n as f64 * dt;
        (0..n)
            .map(|k| {
                let t = k as f64 * dt;
                let ph = 2.0 * core::f64::consts::PI * (f0 * t + (f1 - f0) * t * t / (2.0 * total));
                let mut u = [0.0; 3];
                u[axis] = a * ph.sin();
                u
            })
            .collect()
    }

    /// Sum of sines per drive: `freqs[i]` [Hz] with amplitudes `amps[i]` [V].
    pub fn multisine(
        n: usize,
        dt: f64,
        freqs: &[[f64; 4]; 3],
        amps: &[[f64; 4]; 3],
    ) -> Vec<[f64; 3]> {
        (0..n)
            .map(|k| {
                let t = k as f64 * dt;
                let mut u = [0.0; 3];
                for i in 0..3 {
                    for j in 0..4 {
                        u[i] += amps[i][j] * (2.0 * core::f64::consts::PI * freqs[i][j] * t).sin();
                    }
                }
                u
            })
            .collect()
    }

    /// Concatenates signals.
    pub fn concat(parts: &[Vec<[f64; 3]>]) -> Vec<[f64; 3]> {
        parts.iter().flat_map(|p| p.iter().copied()).collect()
    }
}

//! The paper's experiments, run against any [`Rig`]: rope quasistatic ramps, rope motion
//! unloaded and with four payloads, breakaway ramps chosen by active learning on X and Y,
//! multi-step and chirp motion of X and Y, free swings, and the validation multisine. The
//! runs form a data set (in memory, and written to a directory if asked).

use crate::blr::{active_learning, linspace, Blr, BlrOptions, StopReason};
use crate::data::{
    write_crane_run, write_spec, BreakawayNoise, Constants, CraneRun, Dataset, DatasetSpec, Run,
    RunKind, RunSpec, Samples,
};
use crate::identify::{identify_rope, IdentError, IdentOptions};
use crate::rig::{signals, Experiment, Input, Probe, Rig, RigError, AXIS_L, AXIS_X, AXIS_Y};
use crate::rng::Rng;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Pendulum-free initial configuration at rest: mid-travel, hanging straight down.
pub const HOME: [f64; 5] = [0.25, 0.30, 0.35, core::f64::consts::FRAC_PI_2, 0.0];

/// Validation multisine of `docs/MODEL.md`: frequencies [Hz] of X, Y and the rope.
pub const VALIDATION_FREQS: [[f64; 4]; 3] = [
    [0.135, 0.404, 0.673, 0.942],
    [0.105, 0.314, 0.523, 0.942],
    [0.135, 0.406, 0.219, 0.744],
];
/// Amplitudes [V] of the validation multisine (the paper does not print them; these keep
/// the crane inside its travel).
pub const VALIDATION_AMPS: [[f64; 4]; 3] = [
    [2.5, 2.0, 1.5, 1.0],
    [2.5, 2.0, 1.5, 1.0],
    [4.0, 3.0, 3.0, 2.0],
];

/// What to run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Campaign {
    /// Seed of the excitation signals and of the active learning's initial probes.
    pub seed: u64,
    /// Quasistatic rope ramps per direction.
    pub rope_ramps: usize,
    /// Payloads of the loaded rope runs [kg].
    pub loaded_payloads: Vec<f64>,
    /// Length of each multi-step and each chirp run [s].
    pub motion_s: f64,
    /// Active learning (point budget, threshold, time limit, prior).
    pub blr: BlrOptions,
    /// `false`: probe a uniform grid of `blr.budget` points instead of active learning.
    pub active_learning: bool,
    /// Breakaway noise variances assumed by the regression [N^2].
    pub noise_var: BreakawayNoise,
    /// Payload of the free swings [kg].
    pub swing_payload_kg: f64,
    /// Rope length of the free swings [m].
    pub swing_length_m: f64,
    /// Length of each free swing after the excitation [s].
    pub swing_s: f64,
    /// Payload of the validation run [kg].
    pub validation_payload_kg: f64,
    /// Length of the validation run [s].
    pub validation_s: f64,
    /// Identification options (used for the rope step inside the campaign).
    pub ident: IdentOptions,
}

impl Default for Campaign {
    fn default() -> Self {
        Campaign {
            seed: 1,
            rope_ramps: 3,
            loaded_payloads: vec![0.064, 0.325, 0.457, 0.550],
            motion_s: 40.0,
            blr: BlrOptions::default(),
            active_learning: true,
            noise_var: BreakawayNoise::default(),
            swing_payload_kg: 0.457,
            swing_length_m: 0.45,
            swing_s: 120.0,
            validation_payload_kg: 0.064,
            validation_s: 60.0,
            ident: IdentOptions::default(),
        }
    }
}

/// Why a campaign failed.
#[derive(Debug, thiserror::Error)]
pub enum CampaignError {
    /// The rig failed.
    #[error(transparent)]
    Rig(#[from] RigError),
    /// The rope identification inside the campaign failed.
    #[error(transparent)]
    Ident(#[from] IdentError),
    /// A breakaway ramp reached its largest voltage without motion.
    #[error(
        "breakaway probe on axis {axis} at {position} m ({dir}) saw no motion up to {max_v} V"
    )]
    NoMotion {
        /// Axis.
        axis: usize,
        /// Position.
        position: f64,
        /// Direction.
        dir: &'static str,
        /// Largest voltage.
        max_v: f64,
    },
    /// Writing failed.
    #[error("{path}: {error}")]
    Io {
        /// File.
        path: PathBuf,
        /// Error.
        error: String,
    },
}

/// How the breakaway probing went on one axis and direction.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ProbeSummary {
    /// Axis (`x` or `y`).
    pub axis: String,
    /// Direction (`+` or `-`).
    pub direction: String,
    /// Probe positions in order [m].
    pub positions: Vec<f64>,
    /// Breakaway forces [N].
    pub forces: Vec<f64>,
    /// Why it stopped.
    pub stop: StopReason,
    /// Largest predictive standard deviation at the end [N].
    pub max_std: f64,
}

/// A campaign's data set and what happened.
#[derive(Clone, Debug)]
pub struct CampaignResult {
    /// The data set (as written, if written).
    pub dataset: Dataset,
    /// Breakaway probing per axis and direction.
    pub probes: Vec<ProbeSummary>,
}

struct Recorder<'a> {
    out: Option<&'a Path>,
    runs: Vec<Run>,
    specs: Vec<RunSpec>,
}

impl Recorder<'_> {
    fn add(
        &mut self,
        name: &str,
        kind: RunKind,
        payload: f64,
        run: CraneRun,
    ) -> Result<(), CampaignError> {
        let file = format!("{:03}_{name}.csv", self.runs.len());
        if let Some(dir) = self.out {
            let path = dir.join(&file);
            write_crane_run(
                &path,
                &run,
                &format!("crane-ident virtual rig: {name}, kind {kind:?}, payload {payload} kg"),
            )
            .map_err(|e| CampaignError::Io {
                path: path.clone(),
                error: e.to_string(),
            })?;
        }
        self.specs.push(RunSpec {
            file: file.clone(),
            kind,
            payload_kg: Some(payload),
            ..RunSpec::default()
        });
        self.runs.push(Run {
            name: file,
            kind,
            payload_kg: payload,
            samples: Samples::Crane(run),
        });
        Ok(())
    }

    fn dataset(&self, spec: &DatasetSpec) -> Dataset {
        let mut spec = spec.clone();
        spec.runs = self.specs.clone();
        Dataset {
            dir: self.out.map(Path::to_path_buf).unwrap_or_default(),
            spec,
            runs: self.runs.clone(),
        }
    }
}

fn centred(signal: Vec<[f64; 3]>, axis: usize) -> Input {
    let mut gain = [0.0; 3];
    gain[axis] = if axis == AXIS_L { 50.0 } else { 20.0 };
    Input::Centred {
        signal,
        center: [HOME[0], HOME[1], HOME[2]],
        gain,
    }
}

/// Runs the campaign on `rig`; writes every run and `dataset.toml` into `out` if given.
pub fn run_campaign(
    rig: &mut dyn Rig,
    c: &Campaign,
    constants: &Constants,
    out: Option<&Path>,
) -> Result<CampaignResult, CampaignError> {
    if let Some(dir) = out {
        std::fs::create_dir_all(dir).map_err(|e| CampaignError::Io {
            path: dir.to_path_buf(),
            error: e.to_string(),
        })?;
    }
    let dt = rig.sample_time();
    let mut rng = Rng::new(c.seed);
    let mut rec = Recorder {
        out,
        runs: Vec::new(),
        specs: Vec::new(),
    };
    let mut spec = DatasetSpec::minimal(c.validation_payload_kg);
    spec.constants = *constants;
    spec.breakaway_noise_var = c.noise_var;

    // 1. Rope: quasistatic ramps (no payload).
    rope_ramps(rig, c, &mut rec)?;
    // 2. Rope motion unloaded and loaded: multi-step then chirp.
    rope_motion(rig, c, dt, &mut rng, &mut rec)?;
    // 3. Rope estimates give the gains that turn breakaway voltages into forces.
    let rope = identify_rope(&rec.dataset(&spec), &c.ident)?;
    // 4. Breakaway probes, by active learning (or a uniform grid).
    let probes = breakaway_probes(rig, c, constants, rope.gain.value, &mut rng, &mut rec)?;
    // 5. X and Y motion: multi-step and chirp 0.1-2.5 Hz, no payload.
    axis_motion(rig, c, dt, &mut rng, &mut rec)?;
    // 6. Free swings.
    free_swings(rig, c, constants, dt, &mut rec)?;
    // 7. Validation multisine (open loop).
    validation(rig, c, dt, &mut rec)?;

    let dataset = rec.dataset(&spec);
    if let Some(dir) = out {
        write_spec(dir, &dataset.spec).map_err(|e| CampaignError::Io {
            path: dir.join(crate::data::DATASET_FILE),
            error: e.to_string(),
        })?;
    }
    Ok(CampaignResult { dataset, probes })
}

/// Samples in `secs` seconds at sample time `dt` [s] (rounded to the nearest).
fn samples(secs: f64, dt: f64) -> usize {
    (secs / dt).round() as usize
}

/// Stage 1: `c.rope_ramps` quasistatic rope ramps per direction from `HOME`, no payload
/// (lowering first, then hoisting).
fn rope_ramps(
    rig: &mut dyn Rig,
    c: &Campaign,
    rec: &mut Recorder<'_>,
) -> Result<(), CampaignError> {
    for i in 0..c.rope_ramps {
        for positive in [true, false] {
            let probe = Probe::new(AXIS_L, positive, HOME[2]);
            let r = rig.breakaway(&probe)?;
            let dir = if positive { "lower" } else { "hoist" };
            rec.add(
                &format!("rope_ramp_{dir}_{i}"),
                RunKind::RopeQuasistatic,
                0.0,
                r.run,
            )?;
        }
    }
    Ok(())
}

/// The rope's excitation of `secs` seconds at sample time `dt` [s]: a multi-step then a chirp
/// of the same length (draws the steps from `rng`).
fn rope_signal(rng: &mut Rng, secs: f64, dt: f64) -> Vec<[f64; 3]> {
    signals::concat(&[
        signals::multistep(rng, samples(secs, dt), dt, AXIS_L, (2.0, 7.0), (0.3, 1.5)),
        signals::chirp(samples(secs, dt), dt, AXIS_L, 0.1, 2.5, 6.0),
    ])
}

/// Stage 2: rope motion unloaded (`c.motion_s` of each signal), then with each of
/// `c.loaded_payloads` (half as long).
fn rope_motion(
    rig: &mut dyn Rig,
    c: &Campaign,
    dt: f64,
    rng: &mut Rng,
    rec: &mut Recorder<'_>,
) -> Result<(), CampaignError> {
    let exp = Experiment {
        name: "rope_unloaded".into(),
        kind: RunKind::RopeUnloaded,
        payload_kg: 0.0,
        init: HOME,
        input: centred(rope_signal(rng, c.motion_s, dt), AXIS_L),
    };
    let run = rig.run(&exp)?;
    rec.add(&exp.name, exp.kind, 0.0, run)?;
    for &m in &c.loaded_payloads {
        let exp = Experiment {
            name: format!("rope_loaded_{:.0}g", m * 1000.0),
            kind: RunKind::RopeLoaded,
            payload_kg: m,
            init: HOME,
            input: centred(rope_signal(rng, 0.5 * c.motion_s, dt), AXIS_L),
        };
        let run = rig.run(&exp)?;
        rec.add(&exp.name, exp.kind, m, run)?;
    }
    Ok(())
}

/// Stage 4: breakaway probes on X then Y, each in the positive then the negative direction.
/// `rope_gain` [N/V] is the rope's identified gain; times the ratio of the pulley radii it
/// turns an axis's breakaway voltage into a force. Returns one summary per axis and direction.
fn breakaway_probes(
    rig: &mut dyn Rig,
    c: &Campaign,
    constants: &Constants,
    rope_gain: f64,
    rng: &mut Rng,
    rec: &mut Recorder<'_>,
) -> Result<Vec<ProbeSummary>, CampaignError> {
    let ratios = [
        constants.pulley_radius_l_m / constants.pulley_radius_x_m,
        constants.pulley_radius_l_m / constants.pulley_radius_y_m,
    ];
    let mut probes = Vec::new();
    for axis in [AXIS_X, AXIS_Y] {
        let range = if axis == AXIS_X {
            constants.x_range_m
        } else {
            constants.y_range_m
        };
        let gain = rope_gain * ratios[axis];
        for positive in [true, false] {
            let (summary, records) = probe_direction(rig, c, rng, axis, positive, range, gain)?;
            probes.push(summary);
            let kind = if axis == AXIS_X {
                RunKind::BreakawayX
            } else {
                RunKind::BreakawayY
            };
            for (i, run) in records.into_iter().enumerate() {
                let dir = if positive { "pos" } else { "neg" };
                rec.add(
                    &format!("breakaway_{}_{dir}_{i:02}", ["x", "y"][axis]),
                    kind,
                    0.0,
                    run,
                )?;
            }
        }
    }
    Ok(probes)
}

/// Probes the breakaway force of `axis` in one direction (`positive`: increasing position)
/// over its travel `range` [m], by active learning or (without it) a uniform grid; `gain`
/// [N/V] turns the breakaway voltage into a force. Returns the summary and the ramps' runs
/// in probing order.
fn probe_direction(
    rig: &mut dyn Rig,
    c: &Campaign,
    rng: &mut Rng,
    axis: usize,
    positive: bool,
    range: [f64; 2],
    gain: f64,
) -> Result<(ProbeSummary, Vec<CraneRun>), CampaignError> {
    let var = match (axis, positive) {
        (AXIS_X, true) => c.noise_var.x_pos,
        (AXIS_X, false) => c.noise_var.x_neg,
        (_, true) => c.noise_var.y_pos,
        (_, false) => c.noise_var.y_neg,
    };
    let mut blr = Blr::new(range[0], range[1], c.blr.degree, c.blr.prior_std, var);
    let mut records = Vec::new();
    let mut measure = |p: f64| -> Result<(f64, f64), CampaignError> {
        let probe = Probe::new(axis, positive, p);
        let r = rig.breakaway(&probe)?;
        let onset = r.onset.ok_or(CampaignError::NoMotion {
            axis,
            position: p,
            dir: if positive { "+" } else { "-" },
            max_v: probe.max_v,
        })?;
        records.push(r.run);
        Ok((gain * onset.volts.abs(), onset.position))
    };
    let stop = if c.active_learning {
        active_learning(&mut blr, &c.blr, rng, &mut measure)?
    } else {
        for p in linspace(
            range[0] + c.blr.margin,
            range[1] - c.blr.margin,
            c.blr.budget,
        ) {
            let (f, at) = measure(p)?;
            blr.add(at, f);
        }
        StopReason::Budget
    };
    let grid = linspace(range[0], range[1], 201);
    let names = (["x", "y"][axis], if positive { "+" } else { "-" });
    let summary = ProbeSummary {
        axis: names.0.into(),
        direction: names.1.into(),
        positions: blr.xs.clone(),
        forces: blr.ys.clone(),
        stop,
        max_std: blr.max_std(&grid),
    };
    Ok((summary, records))
}

/// Stage 5: X then Y motion, no payload: a multi-step then a chirp of 0.1-2.5 Hz,
/// `c.motion_s` each.
fn axis_motion(
    rig: &mut dyn Rig,
    c: &Campaign,
    dt: f64,
    rng: &mut Rng,
    rec: &mut Recorder<'_>,
) -> Result<(), CampaignError> {
    for axis in [AXIS_X, AXIS_Y] {
        let name = ["x", "y"][axis];
        let kind = if axis == AXIS_X {
            RunKind::MotionX
        } else {
            RunKind::MotionY
        };
        let steps = signals::multistep(
            rng,
            samples(c.motion_s, dt),
            dt,
            axis,
            (1.5, 6.0),
            (0.3, 1.5),
        );
        let chirp = signals::chirp(samples(c.motion_s, dt), dt, axis, 0.1, 2.5, 5.0);
        for (what, sig) in [("multistep", steps), ("chirp", chirp)] {
            let exp = Experiment {
                name: format!("{name}_{what}"),
                kind,
                payload_kg: 0.0,
                init: HOME,
                input: centred(sig, axis),
            };
            let run = rig.run(&exp)?;
            rec.add(&exp.name, kind, 0.0, run)?;
        }
    }
    Ok(())
}

/// Stage 6: three free swings. The trolley pumps the pendulum at its frequency for two
/// periods and stops; the swing is then recorded with the drives at rest for `c.swing_s`.
fn free_swings(
    rig: &mut dyn Rig,
    c: &Campaign,
    constants: &Constants,
    dt: f64,
    rec: &mut Recorder<'_>,
) -> Result<(), CampaignError> {
    let l = c.swing_length_m;
    let w = (constants.gravity / l).sqrt();
    let pump = (2.0 * 2.0 * core::f64::consts::PI / w / dt).round() as usize;
    for (i, amps) in [[0.0, 2.5], [2.5, 0.0], [2.0, 2.0]].iter().enumerate() {
        let n = pump + samples(c.swing_s, dt);
        let sig: Vec<[f64; 3]> = (0..n)
            .map(|k| {
                if k < pump {
                    let t = k as f64 * dt;
                    [amps[0] * (w * t).sin(), amps[1] * (w * t + 0.5).sin(), 0.0]
                } else {
                    [0.0; 3]
                }
            })
            .collect();
        let mut init = HOME;
        init[2] = l;
        let exp = Experiment {
            name: format!("free_swing_{i}"),
            kind: RunKind::FreeSwing,
            payload_kg: c.swing_payload_kg,
            init,
            input: Input::Open(sig),
        };
        let run = rig.run(&exp)?;
        rec.add(&exp.name, exp.kind, c.swing_payload_kg, run)?;
    }
    Ok(())
}

/// Stage 7: the validation multisine (open loop), `c.validation_s` long.
fn validation(
    rig: &mut dyn Rig,
    c: &Campaign,
    dt: f64,
    rec: &mut Recorder<'_>,
) -> Result<(), CampaignError> {
    let exp = Experiment {
        name: "validation_multisine".into(),
        kind: RunKind::Validation,
        payload_kg: c.validation_payload_kg,
        init: HOME,
        input: Input::Open(signals::multisine(
            samples(c.validation_s, dt),
            dt,
            &VALIDATION_FREQS,
            &VALIDATION_AMPS,
        )),
    };
    let run = rig.run(&exp)?;
    rec.add(&exp.name, exp.kind, c.validation_payload_kg, run)?;
    Ok(())
}

/// Everything `crane rig` needs: the plant's true parameters, how the rig measures, and
/// the campaign.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RigOptions {
    /// The plant's true parameters (default: the paper's table; the payload is set per run).
    pub truth: crane_model::Params,
    /// Measurement, noise and seed of the plant.
    pub plant: crate::rig::PlantConfig,
    /// The experiments.
    pub campaign: Campaign,
    /// Known constants written into the data set (default: `docs/MODEL.md`).
    pub constants: Constants,
}

/// What `run_rig` did.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RigSummary {
    /// Data set directory.
    pub dir: PathBuf,
    /// Runs written.
    pub runs: usize,
    /// Samples written over all runs.
    pub samples: usize,
    /// Breakaway probing per axis and direction.
    pub probes: Vec<ProbeSummary>,
    /// Wall time [s].
    pub seconds: f64,
}

/// Name of the file with the plant's true parameters that `run_rig` writes next to the data
/// set (not part of the data format; the loader ignores it).
pub const TRUTH_FILE: &str = "truth_params.toml";

/// Runs the virtual rig's campaign and writes the data set into `out_dir` (created if
/// needed), plus the true parameters as `truth_params.toml`.
pub fn run_rig(out_dir: &Path, opts: &RigOptions) -> Result<RigSummary, CampaignError> {
    let t0 = std::time::Instant::now();
    let truth = opts.truth;
    let mut rig = crate::rig::VirtualRig::new(truth, opts.plant);
    let res = run_campaign(&mut rig, &opts.campaign, &opts.constants, Some(out_dir))?;
    let path = out_dir.join(TRUTH_FILE);
    crate::params_file::write(&path, &opts.truth).map_err(|e| CampaignError::Io {
        path,
        error: e.to_string(),
    })?;
    Ok(RigSummary {
        dir: out_dir.to_path_buf(),
        runs: res.dataset.runs.len(),
        samples: res
            .dataset
            .runs
            .iter()
            .map(|r| r.crane().map(|c| c.len()).unwrap_or(0))
            .sum(),
        probes: res.probes,
        seconds: t0.elapsed().as_secs_f64(),
    })
}

//! # crane-diagnose
//!
//! The discrepancy workbench: given measured runs (crane runs or single-axis runs, the data
//! format of `crane-ident`), it simulates the baseline model against each run, measures where
//! it is wrong (held-out NMAE per axis, inverse-dynamics force residual), fits a library of
//! candidate causes as model extensions on the fitting part, scores them on the held-out
//! part with a penalty for their extra parameters, and reports the supported cause(s) or a
//! verdict `none` / `unexplained`. The report's JSON schema is `REPORT_SCHEMA.md`.
//!
//! Entry point: [`diagnose`] (a data-set directory) or [`diagnose_dataset`] (in memory).
//! [`hidden`] is the hidden-effect generator the tests use (a virtual rig with one seeded
//! random effect).

#![forbid(unsafe_code)]
#![deny(missing_docs)]
#![allow(clippy::needless_range_loop)]
#![allow(rustdoc::broken_intra_doc_links)]

pub mod axis;
pub mod crane;
pub mod drive;
pub mod fit;
pub mod hidden;
pub mod plots;
mod summary;

use crane_ident::data::{load_dataset, Dataset, Samples};
use crane_ident::params_file::ParamsFile;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The names of the candidate causes, as reported.
pub const CAUSES: [&str; 7] = [
    "localized_friction",
    "stiction",
    "direction_asymmetry",
    "force_offset",
    "input_deadzone",
    "input_delay",
    "payload_mass",
];

/// Which baseline model the discrepancies are measured against.
#[derive(Clone, Debug, Default, PartialEq)]
pub enum Baseline {
    /// Crane data: the built-in defaults of `shared/MODEL.md` with each run's declared payload;
    /// single-axis data: the paper's structure fitted on the fitting part.
    #[default]
    Auto,
    /// These parameters (crane data; `--params`).
    Params(ParamsFile),
    /// The paper's structure fitted on the fitting part (`--fit-baseline`): for crane data the
    /// dry-friction magnitudes and viscous coefficients of every drive are re-fitted by
    /// inverse dynamics on top of the defaults (or `--params`).
    Fit(Option<ParamsFile>),
    /// Single-axis data only: the symmetric Coulomb + viscous model `M qdd + Fv qd + Fc sign(qd)`
    /// fitted on the fitting part (the reference the EMPS story starts from).
    Symmetric,
}

/// Options of [`diagnose`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DiagnoseOptions {
    /// Baseline model.
    pub baseline: Baseline,
    /// Write SVG plots of the residuals before and after the extension here.
    pub plots_dir: Option<PathBuf>,
}

/// Evidence behind a finding.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Evidence {
    /// Held-out BIC-like change of the inverse-dynamics force residual
    /// `n ln(SSE_after / SSE_before) + k ln n` (negative supports the extension).
    pub force_delta_bic: f64,
    /// Held-out RMS inverse-dynamics force residual before / after [N] (affected axis).
    pub force_rms_before_n: f64,
    /// Same after the extension [N].
    pub force_rms_after_n: f64,
    /// Held-out score used for the ranking (crane: sum over axes of the log ratio of the
    /// simulated NMAE after / before, each floored at the noise level, plus the parameter
    /// penalty; single-axis: `force_delta_bic / n`); lower is stronger.
    pub score: f64,
    /// Extra parameters of the extension.
    pub extra_parameters: usize,
    /// Held-out samples used (after masking and decimation, affected axis).
    pub held_out_samples: usize,
    /// Whether the finding can be told apart from a change of the baseline itself.
    pub identifiable: bool,
    /// Explanation (equivalences, caveats).
    pub note: String,
}

/// One supported cause.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Finding {
    /// One of [`CAUSES`].
    pub cause: String,
    /// `x`, `y`, `l`, or `axis` for single-axis data.
    pub axis: String,
    /// Estimated parameters, SI.
    pub parameters: BTreeMap<String, f64>,
    /// Held-out NMAE of the axis before the extension [%].
    pub nmae_before: f64,
    /// Held-out NMAE of the axis after the extension [%].
    pub nmae_after: f64,
    /// Evidence.
    pub evidence: Evidence,
}

/// Baseline error of one axis.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AxisError {
    /// Axis name.
    pub axis: String,
    /// NMAE on the fitting part [%].
    pub nmae_fit: f64,
    /// NMAE on the held-out part [%].
    pub nmae_held_out: f64,
    /// Noise level of the NMAE [%] (crane: encoder quantisation); below it nothing is claimed.
    pub nmae_noise: f64,
    /// RMS inverse-dynamics force residual on the fitting part [N].
    pub force_rms_fit_n: f64,
    /// RMS inverse-dynamics force residual on the held-out part [N].
    pub force_rms_held_out_n: f64,
    /// Relative force error `100 ||F - F_model|| / ||F||` on the held-out part [%].
    pub force_rel_err_held_out_pct: f64,
}

/// Every candidate tried, for transparency.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Candidate {
    /// Cause.
    pub cause: String,
    /// Axis.
    pub axis: String,
    /// Fitted parameters.
    pub parameters: BTreeMap<String, f64>,
    /// Ranking score (see [`Evidence::score`]).
    pub score: f64,
    /// Held-out force BIC change.
    pub force_delta_bic: f64,
    /// Whether it passed the support thresholds.
    pub supported: bool,
}

/// The report (`REPORT_SCHEMA.md`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Report {
    /// Data-set directory.
    pub dataset: String,
    /// `crane` or `single_axis`.
    pub data: String,
    /// Baseline description.
    pub baseline: String,
    /// How runs were split into fitting and held-out parts.
    pub split: String,
    /// Baseline error per axis.
    pub baseline_errors: Vec<AxisError>,
    /// Supported causes, strongest first.
    pub findings: Vec<Finding>,
    /// The first finding's cause, or `none` / `unexplained`.
    pub verdict: String,
    /// Why the verdict.
    pub verdict_reason: String,
    /// Every candidate tried.
    pub candidates: Vec<Candidate>,
    /// Extra numbers of the single-axis pipeline (published-measure comparisons).
    #[serde(skip_serializing_if = "BTreeMap::is_empty", default)]
    pub measures: BTreeMap<String, f64>,
    /// Single-axis open-loop data: the held-out runs simulated from their recorded input with
    /// the baseline and with the final model.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub heldout_simulation: Option<HeldoutSimulation>,
    /// Single-axis open-loop data: the final model (baseline plus every finding).
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub final_model: Option<FinalModel>,
}

/// Held-out runs simulated from their recorded input (position NMAE: mean absolute error over
/// the measured run's position range) [%].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct HeldoutSimulation {
    /// Mean over held-out runs, baseline [%].
    pub nmae_before: f64,
    /// Mean over held-out runs, final model [%].
    pub nmae_after: f64,
    /// Mean over held-out runs of predicting no motion at all (the first position) [%].
    pub nmae_no_motion: f64,
    /// Mean over the held-out runs in which the axis moves (beyond pre-sliding), baseline [%]:
    /// the measure the causes are selected by (runs that stay at rest cannot tell friction
    /// models apart).
    pub moving_nmae_before: f64,
    /// Same, final model [%].
    pub moving_nmae_after: f64,
    /// Same, predicting no motion [%].
    pub moving_nmae_no_motion: f64,
    /// Per held-out run.
    pub runs: Vec<RunSimulation>,
}

/// One held-out run's simulated position error [%].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunSimulation {
    /// Run file.
    pub file: String,
    /// Baseline [%].
    pub nmae_before: f64,
    /// Final model [%].
    pub nmae_after: f64,
    /// Predicting no motion [%].
    pub nmae_no_motion: f64,
    /// Whether the measured axis moves in this run (faster than the motion threshold).
    pub moves: bool,
}

/// The final single-axis model, in SI units or, when the input gain is unknown, in input
/// units (`force_unit`). Friction magnitudes are >= 0; `breakaway_*` are net of the modelled
/// position force, at first motion.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FinalModel {
    /// Unit of positions (`m` or `rad`).
    pub position_unit: String,
    /// Unit of forces (`N`, `N m`, or the input unit).
    pub force_unit: String,
    /// Inertia [force unit per (position unit / s^2)].
    pub inertia: f64,
    /// Breakaway level towards positive [force unit].
    pub breakaway_pos: f64,
    /// Breakaway level towards negative (magnitude) [force unit].
    pub breakaway_neg: f64,
    /// Kinetic friction moving positive [force unit].
    pub kinetic_pos: f64,
    /// Kinetic friction moving negative (magnitude) [force unit].
    pub kinetic_neg: f64,
    /// Viscous friction moving positive [force unit per (position unit / s)].
    pub viscous_pos: f64,
    /// Viscous friction moving negative [force unit per (position unit / s)].
    pub viscous_neg: f64,
    /// Restoring stiffness [force unit per position unit] (0 when none).
    pub stiffness: f64,
    /// Centre of the restoring force [position unit].
    pub center: f64,
    /// Constant force offset [force unit].
    pub offset: f64,
    /// Input dead band [input units].
    pub deadband: f64,
    /// Input delay [samples].
    pub delay_samples: usize,
    /// Scatter (standard deviation) of the breakaway levels at every rest-to-motion onset of
    /// the fitting runs, positive direction [force unit] (0 when unknown).
    pub breakaway_scatter_pos: f64,
    /// Same, negative direction.
    pub breakaway_scatter_neg: f64,
    /// Net force at first motion per fitting run, positive direction [force unit].
    pub first_motion_pos: Vec<f64>,
    /// Same, negative direction (magnitudes).
    pub first_motion_neg: Vec<f64>,
    /// What the estimator had to decide (parameters at a bound, directions not fitted,
    /// causes not named and why).
    pub flags: Vec<String>,
}

impl Report {
    /// Pretty JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_default()
    }
}

/// Why the diagnosis failed.
#[derive(Debug)]
pub enum DiagnoseError {
    /// The data set did not load.
    Data(String),
    /// Nothing to diagnose or an unusable combination.
    Input(String),
    /// The model rejected parameters or a step.
    Model(String),
    /// Writing plots failed.
    Io(String),
}

impl std::fmt::Display for DiagnoseError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            DiagnoseError::Data(m) => write!(f, "data: {m}"),
            DiagnoseError::Input(m) => write!(f, "{m}"),
            DiagnoseError::Model(m) => write!(f, "model: {m}"),
            DiagnoseError::Io(m) => write!(f, "plots: {m}"),
        }
    }
}

impl std::error::Error for DiagnoseError {}

/// Loads the data set in `dataset_dir` and diagnoses it.
pub fn diagnose(dataset_dir: &Path, opts: &DiagnoseOptions) -> Result<Report, DiagnoseError> {
    let ds = load_dataset(dataset_dir).map_err(|e| DiagnoseError::Data(e.to_string()))?;
    diagnose_dataset(&ds, opts)
}

/// Diagnoses a loaded data set (crane runs, or else single-axis runs).
pub fn diagnose_dataset(ds: &Dataset, opts: &DiagnoseOptions) -> Result<Report, DiagnoseError> {
    let crane = ds
        .runs
        .iter()
        .filter(|r| matches!(r.samples, Samples::Crane(_)))
        .count();
    if crane > 0 {
        crane::diagnose_crane(ds, opts)
    } else if ds.runs.is_empty() {
        Err(DiagnoseError::Input("the data set has no run".into()))
    } else if opts.baseline == Baseline::Symmetric || closed_loop(ds) {
        axis::diagnose_axis(ds, opts)
    } else {
        let (runs, split, info) = drive_runs(ds)?;
        drive::diagnose_drive(&ds.dir.display().to_string(), runs, split, &info, opts)
    }
}

/// Whether single-axis data come from a closed loop (the recorded input depends on the
/// motion; the inverse-dynamics pipeline of [`axis`] with the rig's controller handles them).
fn closed_loop(ds: &Dataset) -> bool {
    ds.runs
        .iter()
        .any(|r| r.name.contains("emps") || r.name.contains("EMPS"))
}

/// The single-axis runs of a data set for the simulation pipeline, split into fitting and
/// held-out runs ([`split_runs`]; one run is cut into its first 70 % and last 30 %).
fn drive_runs(
    ds: &Dataset,
) -> Result<(Vec<drive::DriveRun>, String, drive::DriveInfo), DiagnoseError> {
    let axis: Vec<(&crane_ident::data::Run, &crane_ident::data::AxisRun)> = ds
        .runs
        .iter()
        .filter_map(|r| r.axis().map(|a| (r, a)))
        .collect();
    let kinds: Vec<_> = axis.iter().map(|(r, _)| r.kind).collect();
    let (split, doc) = split_runs(&kinds);
    let mut runs = Vec::new();
    for ((r, a), held) in axis.iter().zip(split) {
        let dt = a.dt();
        if !(dt > 0.0 && dt.is_finite()) {
            return Err(DiagnoseError::Input(format!(
                "{}: the sample period is not positive",
                r.name
            )));
        }
        let mk = |lo: usize, hi: usize, held_out: bool| drive::DriveRun {
            name: r.name.clone(),
            held_out,
            dt,
            x: a.x[lo..hi].to_vec(),
            u: a.force[lo..hi].to_vec(),
        };
        match held {
            Some(h) => runs.push(mk(0, a.x.len(), h)),
            None => {
                let cut = ((a.x.len() as f64) * FIT_FRACTION) as usize;
                runs.push(mk(0, cut, false));
                runs.push(mk(cut, a.x.len(), true));
            }
        }
    }
    let info = drive::DriveInfo {
        motion: crane_model::drive::Motion::Linear,
        position_unit: "m".into(),
        force_unit: "N".into(),
        symmetric: false,
    };
    Ok((runs, doc, info))
}

/// The documented split: runs of kind `validation` are held out when some runs are not;
/// otherwise with several runs every second run (indices 1, 3, ...) is held out; with one run
/// the last 30 % of its samples are held out. Returns per run `Some(true)` (held out),
/// `Some(false)` (fitting) or `None` (time-block split of a single run).
pub fn split_runs(kinds: &[crane_ident::data::RunKind]) -> (Vec<Option<bool>>, String) {
    use crane_ident::data::RunKind;
    let n = kinds.len();
    let n_val = kinds.iter().filter(|k| **k == RunKind::Validation).count();
    if n_val > 0 && n_val < n {
        (
            kinds
                .iter()
                .map(|k| Some(*k == RunKind::Validation))
                .collect(),
            "whole runs: `validation` runs held out, the others fitted".into(),
        )
    } else if n >= 2 {
        (
            (0..n).map(|i| Some(i % 2 == 1)).collect(),
            "whole runs: every second run (1, 3, ... in data-set order) held out".into(),
        )
    } else {
        (
            vec![None; n],
            "time blocks: first 70 % of the run fitted, last 30 % held out".into(),
        )
    }
}

/// Fraction of a single run used for fitting in a time-block split.
pub const FIT_FRACTION: f64 = 0.7;

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
pub mod fit;
pub mod hidden;
pub mod plots;

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
    } else {
        axis::diagnose_axis(ds, opts)
    }
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

//! Validation: simulate the model with the recorded voltages of each `validation` run from
//! its recorded initial state, and compare payload positions. The error measure is the
//! paper's: normalised mean absolute error per payload coordinate, normalised by the total
//! physical range of that axis (X travel, Y travel, rope length range).

use crate::data::{CraneRun, Dataset, RunKind};
use crane_model::{Config, Crane, FrictionLaw, Params, State};
use serde::{Deserialize, Serialize};

/// The paper's validation NMAE [%] of the payload position (x, y, z).
pub const PAPER_NMAE_PCT: [f64; 3] = [2.59, 4.95, 0.13];

/// Result on one run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunValidation {
    /// Run file.
    pub run: String,
    /// Payload [kg].
    pub payload_kg: f64,
    /// NMAE of payload x, y, z [%].
    pub nmae_pct: [f64; 3],
    /// Simulated drive positions and angles per sample `[x, y, L, alpha, beta]`, for plots.
    #[serde(skip)]
    pub simulated: Vec<[f64; 5]>,
}

/// Validation report.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ValidationReport {
    /// Per run.
    pub runs: Vec<RunValidation>,
    /// The paper's numbers for the same measure.
    pub paper_nmae_pct: [f64; 3],
    /// Normalisation ranges used [m].
    pub ranges_m: [f64; 3],
}

impl ValidationReport {
    /// The paper's table form: axis, ours, paper.
    pub fn table(&self) -> String {
        let mut s = String::from(
            "| payload coordinate | NMAE (this model) | NMAE (paper, real rig) |\n|---|---|---|\n",
        );
        for (i, name) in ["x_p", "y_p", "z_p"].iter().enumerate() {
            let ours: Vec<String> = self
                .runs
                .iter()
                .map(|r| format!("{:.2} %", r.nmae_pct[i]))
                .collect();
            s.push_str(&format!(
                "| {name} | {} | {:.2} % |\n",
                ours.join(", "),
                self.paper_nmae_pct[i]
            ));
        }
        s
    }
}

/// Why the simulation of one run failed.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// The model rejected the parameters, the step or the run's first configuration (the
    /// error names the field: `payload_mass`, `config.h`, or the run's column for the first
    /// state, `x`, `alpha`...).
    #[error("{}", setup_message(.0))]
    Setup(crane_model::Error),
    /// The model rejected a step (e.g. "mass matrix not positive definite").
    #[error("sample {sample} (t = {t} s, input u = {u:?} V): {error}")]
    Step {
        /// Sample index of the run (0-based; the line is this plus the header lines).
        sample: usize,
        /// Time of the sample [s].
        t: f64,
        /// The voltages held over the step [V].
        u: [f64; 3],
        /// What the model said.
        error: crane_model::StepError,
    },
}

/// The model's message for `e`, the first state named by the run's columns (`state.q[0]` is
/// the run's first `x`, ...) and its value short.
fn setup_message(e: &crane_model::Error) -> String {
    const COLUMNS: [&str; 5] = ["x", "y", "l", "alpha", "beta"];
    let mut text = e.to_string();
    for (i, c) in COLUMNS.iter().enumerate() {
        text = text.replace(
            &format!("`state.q[{i}]`"),
            &format!("the run's first `{c}`"),
        );
    }
    let long = e.value.to_string();
    let short = crate::num::Num(e.value).to_string();
    if long != short {
        text = text.replace(&long, &short);
    }
    if e.problem == crane_model::Problem::OutOfLimits {
        text.push_str(" of the parameters ([x], [y], [rope] min and max)");
    }
    text
}

/// Why validation failed.
#[derive(Debug, thiserror::Error)]
pub enum ValidateError {
    /// No validation run.
    #[error("the data set has no `validation` crane run")]
    NoRun,
    /// The data set did not load.
    #[error(transparent)]
    Data(#[from] crate::data::DataError),
    /// The model failed on a run.
    #[error("validation run `{run}` (payload {payload_kg} kg): {source}")]
    Run {
        /// Run file.
        run: String,
        /// The payload simulated [kg].
        payload_kg: f64,
        /// What failed.
        source: SimError,
    },
}

fn payload(q: &[f64; 5]) -> [f64; 3] {
    let [x, y, l, a, b] = *q;
    let (sa, ca) = a.sin_cos();
    let (sb, cb) = b.sin_cos();
    [x + l * sb * sa, y + l * ca, -(l * sa * cb)]
}

/// Simulates `params` on the inputs of a crane run (model step = half the sampling period,
/// voltages held over each sample) from the run's first recorded configuration at rest;
/// returns the simulated `q` at every sample time.
pub fn simulate_run(params: &Params, run: &CraneRun) -> Result<Vec<[f64; 5]>, SimError> {
    let dt = run.dt();
    let q0 = [run.x[0], run.y[0], run.l[0], run.alpha[0], run.beta[0]];
    let mut crane: Crane = Crane::new(
        params,
        Config {
            h: dt / 2.0,
            law: FrictionLaw::Hybrid,
        },
        State {
            q: q0,
            qd: [0.0; 5],
        },
    )
    .map_err(SimError::Setup)?;
    let mut out = Vec::with_capacity(run.len());
    for k in 0..run.len() {
        out.push(crane.state().q);
        let u = [run.u[0][k], run.u[1][k], run.u[2][k]];
        for _ in 0..2 {
            crane.step(u).map_err(|error| SimError::Step {
                sample: k,
                t: run.t[k],
                u,
                error,
            })?;
        }
    }
    Ok(out)
}

/// NMAE [%] of payload positions of `sim` against the record, normalised by `ranges`.
pub fn nmae(run: &CraneRun, sim: &[[f64; 5]], ranges: [f64; 3]) -> [f64; 3] {
    let mut acc = [0.0; 3];
    for (k, s) in sim.iter().enumerate() {
        let meas = payload(&[run.x[k], run.y[k], run.l[k], run.alpha[k], run.beta[k]]);
        let simp = payload(s);
        for i in 0..3 {
            acc[i] += (meas[i] - simp[i]).abs();
        }
    }
    let n = sim.len() as f64;
    [0, 1, 2].map(|i| 100.0 * acc[i] / n / ranges[i])
}

/// Validates `params` on every `validation` run of a data set (payload from each run; an
/// unloaded run simulates a 1 g hook).
pub fn validate_dataset(params: &Params, ds: &Dataset) -> Result<ValidationReport, ValidateError> {
    let c = &ds.spec.constants;
    let ranges = [
        c.x_range_m[1] - c.x_range_m[0],
        c.y_range_m[1] - c.y_range_m[0],
        c.l_range_m[1] - c.l_range_m[0],
    ];
    let mut runs = Vec::new();
    for run in ds.of_kind(RunKind::Validation) {
        let Some(cr) = run.crane() else { continue };
        let mut p = *params;
        p.payload_mass = if run.payload_kg > 0.0 {
            run.payload_kg
        } else {
            0.001
        };
        let sim = simulate_run(&p, cr).map_err(|source| ValidateError::Run {
            run: run.name.clone(),
            payload_kg: p.payload_mass,
            source,
        })?;
        runs.push(RunValidation {
            run: run.name.clone(),
            payload_kg: run.payload_kg,
            nmae_pct: nmae(cr, &sim, ranges),
            simulated: sim,
        });
    }
    if runs.is_empty() {
        return Err(ValidateError::NoRun);
    }
    Ok(ValidationReport {
        runs,
        paper_nmae_pct: PAPER_NMAE_PCT,
        ranges_m: ranges,
    })
}

/// Loads a data set directory and validates `params` on it.
pub fn validate(
    params: &Params,
    dataset_dir: &std::path::Path,
) -> Result<ValidationReport, ValidateError> {
    let ds = crate::data::load_dataset(dataset_dir)?;
    validate_dataset(params, &ds)
}

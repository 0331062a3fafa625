//! Inverse-dynamics least squares (IDIM-LS) of a single friction-dominated axis, as in the
//! EMPS benchmark (Janot, Gautier & Brunot 2019): the position is low-pass filtered without
//! phase (Butterworth, `filtfilt`), differentiated twice by central differences, the first
//! samples dropped, and every regressor column and the force decimated in parallel (MATLAB
//! `decimate`) before the least squares.
//!
//! Models: symmetric `tau = M qdd + Fv qd + Fc sign(qd) + offset`, and direction-dependent
//! `tau = M qdd + Fv+ qd+ + Fv- qd- + Fc+ [qd > 0] - Fc- [qd < 0]`.

use crate::data::AxisRun;
use crate::linalg::{lstsq, LsError, LsFit};
use crate::signal::{butter, decimate, diff_central};
use serde::{Deserialize, Serialize};

/// Processing of the EMPS benchmark's IDIM-LS script.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct IdimOptions {
    /// Butterworth order of the position filter.
    pub filter_order: usize,
    /// Cut-off of the position filter [Hz].
    pub cutoff_hz: f64,
    /// Decimation factor applied to every column (MATLAB `decimate`).
    pub decimation: usize,
    /// Samples dropped at the start (edge effects of the differentiation); MATLAB's
    /// `n_border = 50` keeps samples 50..N (1-based), i.e. drops 49.
    pub drop_start: usize,
}

impl Default for IdimOptions {
    /// The benchmark's script: 4th order at `5 * 20` Hz for 1 kHz sampling, decimation
    /// `round(0.8 * 500 / 40) = 10`, `n_border = 50`.
    fn default() -> Self {
        IdimOptions {
            filter_order: 4,
            cutoff_hz: 100.0,
            decimation: 10,
            drop_start: 49,
        }
    }
}

/// Which inverse model.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum IdimModel {
    /// `M, Fv, Fc, offset`.
    Symmetric,
    /// `M, Fv+, Fv-, Fc+, Fc-`, no offset.
    DirectionDependent,
}

/// Filtered signals of a single-axis run (before decimation).
#[derive(Clone, Debug, PartialEq)]
pub struct Processed {
    /// Filtered position.
    pub q: Vec<f64>,
    /// Velocity.
    pub qd: Vec<f64>,
    /// Acceleration.
    pub qdd: Vec<f64>,
    /// Force (unfiltered).
    pub force: Vec<f64>,
}

/// Filters and differentiates as the IDIM-LS script: `q_f = filtfilt(butter)`,
/// `dq = diffcent(q_f)`, `ddq = diffcent(dq)`, then drops `drop_start` samples.
pub fn process(run: &AxisRun, opt: &IdimOptions) -> Processed {
    let dt = run.dt();
    let f = butter(opt.filter_order, opt.cutoff_hz * 2.0 * dt);
    let q = f.filtfilt(&run.x);
    let qd = diff_central(&q, dt);
    let qdd = diff_central(&qd, dt);
    let s = opt.drop_start.min(q.len());
    Processed {
        q: q[s..].to_vec(),
        qd: qd[s..].to_vec(),
        qdd: qdd[s..].to_vec(),
        force: run.force[s..].to_vec(),
    }
}

fn sign(v: f64) -> f64 {
    if v > 0.0 {
        1.0
    } else if v < 0.0 {
        -1.0
    } else {
        0.0
    }
}

/// Regressor columns (names, columns) of `model` on processed signals.
pub fn regressors(p: &Processed, model: IdimModel) -> (Vec<&'static str>, Vec<Vec<f64>>) {
    match model {
        IdimModel::Symmetric => (
            vec!["M", "Fv", "Fc", "offset"],
            vec![
                p.qdd.clone(),
                p.qd.clone(),
                p.qd.iter().map(|&v| sign(v)).collect(),
                vec![1.0; p.qd.len()],
            ],
        ),
        IdimModel::DirectionDependent => (
            vec!["M", "Fv+", "Fv-", "Fc+", "Fc-"],
            vec![
                p.qdd.clone(),
                p.qd.iter()
                    .map(|&v| if v > 0.0 { v } else { 0.0 })
                    .collect(),
                p.qd.iter()
                    .map(|&v| if v < 0.0 { v } else { 0.0 })
                    .collect(),
                p.qd.iter()
                    .map(|&v| if v > 0.0 { 1.0 } else { 0.0 })
                    .collect(),
                p.qd.iter()
                    .map(|&v| if v < 0.0 { -1.0 } else { 0.0 })
                    .collect(),
            ],
        ),
    }
}

/// IDIM-LS fit of `model` on a single-axis run: parallel decimation of the regressors and the
/// force, least squares, statistics (relative error on the decimated force).
pub fn idim_ls(run: &AxisRun, model: IdimModel, opt: &IdimOptions) -> Result<LsFit, LsError> {
    let p = process(run, opt);
    let (names, cols) = regressors(&p, model);
    let cols: Vec<Vec<f64>> = cols.iter().map(|c| decimate(c, opt.decimation)).collect();
    let y = decimate(&p.force, opt.decimation);
    lstsq("idim", &names, &cols, &y)
}

/// Relative force error [%] of given parameters on a run (cross-test validation), with the
/// same processing: `100 ||y - W theta|| / ||y||` on the decimated data.
pub fn cross_test(run: &AxisRun, model: IdimModel, theta: &[f64], opt: &IdimOptions) -> f64 {
    let p = process(run, opt);
    let (_, cols) = regressors(&p, model);
    let cols: Vec<Vec<f64>> = cols.iter().map(|c| decimate(c, opt.decimation)).collect();
    let y = decimate(&p.force, opt.decimation);
    let mut ss = 0.0;
    let mut yy = 0.0;
    for (k, yk) in y.iter().enumerate() {
        let pred: f64 = cols.iter().zip(theta).map(|(c, t)| c[k] * t).sum();
        ss += (yk - pred) * (yk - pred);
        yy += yk * yk;
    }
    100.0 * (ss / yy).sqrt()
}

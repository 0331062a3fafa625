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

/// The EMPS rig's position controller and drive (`shared/data/emps/README.md`):
/// `nu = kp kv (qr - q) - kv qdot` with `qdot(k) = (qf(k) - qf(k-1)) / dt`,
/// `qf(k) = (q(k) + q(k-1)) / 2`, saturated to `±sat_v`; the command reaches the drive one
/// sample later; force on the load side `gtau * vir` [N].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Controller {
    /// Position gain `kp` [1/s].
    pub kp: f64,
    /// Velocity gain `kv` [V/(m/s)].
    pub kv: f64,
    /// Saturation of the command [V].
    pub sat_v: f64,
    /// Drive gain `gtau` [N/V].
    pub gtau: f64,
    /// Samples between the controller's output and the drive (the README's rig: 1).
    pub delay_samples: usize,
}

impl Default for Controller {
    /// The benchmark's values.
    fn default() -> Self {
        Controller {
            kp: 160.18,
            kv: 243.45,
            sat_v: 10.0,
            gtau: 35.150651882485,
            delay_samples: 1,
        }
    }
}

/// A single-axis model to simulate in closed loop: `M qdd = gtau vir - f(qd) - offset`, with
/// `f = Fv+ qd + Fc+` moving positive, `Fv- qd - Fc-` moving negative, and exact sticking
/// (a stopped axis stays stopped while `|gtau vir - offset|` is below the dry magnitude of the
/// direction it is pushed in).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct AxisModel {
    /// Inertia `M` [kg].
    pub mass: f64,
    /// Viscous coefficient moving positive [N s/m].
    pub viscous_pos: f64,
    /// Viscous coefficient moving negative [N s/m].
    pub viscous_neg: f64,
    /// Dry magnitude moving positive [N] (>= 0).
    pub dry_pos: f64,
    /// Dry magnitude moving negative [N] (>= 0).
    pub dry_neg: f64,
    /// Constant force on the load side, counted like friction (positive resists positive
    /// drive) [N].
    pub offset: f64,
}

impl AxisModel {
    /// From the IDIM-LS parameters of `model` (`M, Fv, Fc, offset` or `M, Fv+, Fv-, Fc+, Fc-`).
    pub fn from_idim(model: IdimModel, theta: &[f64]) -> Option<AxisModel> {
        match (model, theta) {
            (IdimModel::Symmetric, [m, fv, fc, off]) => Some(AxisModel {
                mass: *m,
                viscous_pos: *fv,
                viscous_neg: *fv,
                dry_pos: *fc,
                dry_neg: *fc,
                offset: *off,
            }),
            (IdimModel::DirectionDependent, [m, fvp, fvn, fcp, fcn]) => Some(AxisModel {
                mass: *m,
                viscous_pos: *fvp,
                viscous_neg: *fvn,
                dry_pos: *fcp,
                dry_neg: *fcn,
                offset: 0.0,
            }),
            _ => None,
        }
    }
}

/// A recorded EMPS run with what the closed loop needs.
#[derive(Clone, Debug, PartialEq)]
pub struct ClosedLoopRun {
    /// Time [s].
    pub t: Vec<f64>,
    /// Measured position `qm` [m].
    pub q: Vec<f64>,
    /// Reference position `qg` [m].
    pub reference: Vec<f64>,
    /// Recorded drive command `vir` [V] (with the pulses, if any).
    pub vir: Vec<f64>,
    /// Pulses added to the command after the saturation [V] (`pulses_N`, which is in volts
    /// despite its name), zero when the file has none.
    pub pulses_v: Vec<f64>,
}

/// Why an EMPS closed-loop run did not load.
#[derive(Debug, thiserror::Error)]
pub enum EmpsError {
    /// The CSV did not parse (file, line and column named).
    #[error(transparent)]
    Data(#[from] crate::data::DataError),
    /// A column is missing.
    #[error("{}: no column `{column}` (found: {found})", path.display())]
    MissingColumn {
        /// The file.
        path: std::path::PathBuf,
        /// The missing column.
        column: &'static str,
        /// The header names found, comma-separated.
        found: String,
    },
    /// Too few samples for the closed loop.
    #[error("{}: {samples} samples; at least 3 needed", path.display())]
    TooShort {
        /// The file.
        path: std::path::PathBuf,
        /// Samples found.
        samples: usize,
    },
}

/// Loads an EMPS CSV (`t, qm, qg, vir` and optionally `pulses_N`); the error names the file and
/// the missing column or bad line.
pub fn load_closed_loop(path: &std::path::Path) -> Result<ClosedLoopRun, EmpsError> {
    let table = crate::data::read_table(path)?;
    let col = |name: &'static str| -> Result<Vec<f64>, EmpsError> {
        table
            .header
            .iter()
            .position(|h| h == name)
            .map(|i| table.columns[i].clone())
            .ok_or_else(|| EmpsError::MissingColumn {
                path: path.to_path_buf(),
                column: name,
                found: table.header.join(", "),
            })
    };
    let t = col("t")?;
    if t.len() < 3 {
        return Err(EmpsError::TooShort {
            path: path.to_path_buf(),
            samples: t.len(),
        });
    }
    let pulses_v = col("pulses_N").unwrap_or_else(|_| vec![0.0; t.len()]);
    Ok(ClosedLoopRun {
        q: col("qm")?,
        reference: col("qg")?,
        vir: col("vir")?,
        pulses_v,
        t,
    })
}

/// A closed-loop simulation and its relative errors `100 ||y - yhat|| / ||y||` [%].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ClosedLoopSim {
    /// Simulated position [m].
    pub q: Vec<f64>,
    /// Simulated command as recorded (saturated controller output plus pulses) [V].
    pub vir: Vec<f64>,
    /// Relative position error [%].
    pub position_err_pct: f64,
    /// Relative force error (`gtau vir`) [%].
    pub force_err_pct: f64,
}

/// Model substeps per sample of the closed-loop simulation.
pub const SUBSTEPS: usize = 10;

/// Simulates `model` in closed loop with `ctl` on the run's reference (and pulses), from the
/// run's first measured position at rest, and compares with the measured position and force.
pub fn simulate_closed_loop(
    run: &ClosedLoopRun,
    model: &AxisModel,
    ctl: &Controller,
) -> ClosedLoopSim {
    let n = run.t.len();
    let dt = (run.t[n - 1] - run.t[0]) / (n - 1) as f64;
    let h = dt / SUBSTEPS as f64;
    let (mut q, mut v) = (run.q[0], 0.0_f64);
    let mut qs = Vec::with_capacity(n);
    let mut virs = Vec::with_capacity(n);
    let (mut q_prev, mut qf_prev) = (q, q);
    for k in 0..n {
        let qf = 0.5 * q + 0.5 * q_prev;
        let qdot = if k == 0 { 0.0 } else { (qf - qf_prev) / dt };
        let nu = (ctl.kp * ctl.kv * (run.reference[k] - q) - ctl.kv * qdot)
            .clamp(-ctl.sat_v, ctl.sat_v)
            + run.pulses_v[k];
        qs.push(q);
        virs.push(nu);
        // command reaching the drive during this sample (zero before the first output)
        let applied = k.checked_sub(ctl.delay_samples).map_or(0.0, |j| virs[j]);
        let f = ctl.gtau * applied - model.offset;
        for _ in 0..SUBSTEPS {
            if v == 0.0 {
                if f > model.dry_pos {
                    v = (f - model.dry_pos) / model.mass * h * 0.5;
                    q += v * h;
                } else if f < -model.dry_neg {
                    v = (f + model.dry_neg) / model.mass * h * 0.5;
                    q += v * h;
                }
                continue;
            }
            let fr = if v > 0.0 {
                model.viscous_pos * v + model.dry_pos
            } else {
                model.viscous_neg * v - model.dry_neg
            };
            let vn = v + (f - fr) / model.mass * h;
            if vn * v < 0.0 {
                // velocity reaches zero inside the substep: stop there
                q += 0.5 * v * h * (v / (v - vn));
                v = 0.0;
            } else {
                q += 0.5 * (v + vn) * h;
                v = vn;
            }
        }
        q_prev = qs[k];
        qf_prev = qf;
    }
    let rel = |y: &[f64], yh: &[f64]| -> f64 {
        let (mut e, mut s) = (0.0, 0.0);
        for (a, b) in y.iter().zip(yh) {
            e += (a - b) * (a - b);
            s += a * a;
        }
        100.0 * (e / s.max(1e-300)).sqrt()
    };
    ClosedLoopSim {
        position_err_pct: rel(&run.q, &qs),
        force_err_pct: rel(&run.vir, &virs),
        q: qs,
        vir: virs,
    }
}

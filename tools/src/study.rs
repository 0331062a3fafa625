//! The paper's simulation study (its Table "Comparison of simulation time"), measured.
//!
//! Per case and model: wall time of one whole run (the best of repeated runs) and the RMSE of
//! the compared velocity against the reference (the hybrid model at `h / 100`, see
//! [`crate::reference`]). The models:
//! - the hybrid model at its default step (1 ms): fixed-step RK4 with located events;
//! - `tanh(gamma v)` for gamma = 1, 10, 100, 1000, 10000, integrated by [`crate::ode45`]
//!   with one tolerance for all (`rtol = 1e-6`, `atol = 1e-8`);
//! - each `tanh` model by fixed-step RK4 at its largest stable step: the largest step of a
//!   ladder (1 ms times 50, 20, 10, 8, 5, 4, 3, 2, 1, 1/2, 1/3, ... 1/512) whose run completes
//!   and whose RMSE is within 10 % of the same model's ode45 RMSE (beyond the RK4 stability
//!   limit of the friction slope `gamma Cbar`, the velocity chatters around zero with an
//!   amplitude of the order of the smoothing width `1/gamma`, which is the size of the
//!   model's own error, so accuracy is the sharp test of stability);
//! - at equal or better accuracy: the largest hybrid step (1 ms times 200, 100, 50, 40, 25, 20,
//!   10, 8, 5, 4, 2, 1) whose RMSE is at most that of each `tanh` model, and its time.
//!
//! Every RMSE is taken on the 1 ms grid, whatever the solver's step: ode45 by its dense
//! output, fixed steps longer than the grid by the cubic Hermite interpolant through the step
//! ends (see [`Trajectory::velocity_at_grid`]).

use crate::cases::{Case, CaseId};
use crate::error::{Error, Result};
use crate::numfmt::fmt_g;
use crate::reference::{self, Convergence, Trajectory};
use crate::smooth::{pack, rk4_step_k1, unpack, Friction, Smooth, Y};
use crate::tanh_run::{tanh_name, tanh_ode45};
use crate::timing::time_best;
use crate::{adaptive_run, ode45, workprec};
use serde::Serialize;
use std::time::Instant;

/// The paper's values (MATLAB, Intel Ultra 7 265K): `(time [s], RMSE [m/s])` for hybrid,
/// tanh(v), tanh(10 v), ..., tanh(10^4 v); case 1 then case 2.
pub const PAPER: [[(f64, f64); 6]; 2] = [
    [
        (0.216, 0.0),
        (0.165, 0.0864),
        (0.276, 0.0327),
        (1.235, 0.00821),
        (11.824, 0.00168),
        (117.726, 0.00102),
    ],
    [
        (0.0658, 0.0),
        (0.0933, 1.19),
        (0.229, 0.148),
        (0.572, 0.0174),
        (1.917, 0.00201),
        (18.219, 0.000228),
    ],
];

/// The paper's gammas [s/m].
pub const GAMMAS: [f64; 5] = [1.0, 10.0, 100.0, 1000.0, 10000.0];

/// Study options.
#[derive(Clone, Debug)]
pub struct Options {
    /// Hybrid model's step [s] (default 1 ms).
    pub h: f64,
    /// Reference step divisor: reference step `h / ref_div`.
    pub ref_div: usize,
    /// Check the reference's convergence (one more run at half its step).
    pub convergence: bool,
    /// The tanh slopes [s/m].
    pub gammas: Vec<f64>,
    /// ode45 tolerances.
    pub ode: ode45::Options,
    /// Search the largest stable fixed RK4 step of each tanh model.
    pub rk4_search: bool,
    /// Search the largest hybrid step at equal or better accuracy than each tanh model.
    pub equal_accuracy: bool,
    /// Wall-time budget per timed model [s]: runs are repeated until it is spent (at least
    /// 3 runs, at most 50) and the fastest run is reported.
    pub timing_budget: f64,
    /// The hybrid row's setting: the adaptive integrator at this `rtol` (the default,
    /// [`DEFAULT_RTOL`]), or, with `None`, the fixed step `h`.
    pub hybrid_rtol: Option<f64>,
    /// Run the work-precision sweep ([`crate::workprec`]).
    pub work_precision: bool,
}

/// The accuracy the defaults of `crane study` and `crane mc` are chosen for: RMSE of the
/// compared velocity at most 1e-6 m/s in both cases.
pub const STATED_ACCURACY: f64 = 1e-6;

/// The hybrid model's default setting: the adaptive integrator at `rtol = 1e-7`
/// (`atol = 1e-9`), the cheapest setting on the work-precision diagrams of both cases that
/// reaches [`STATED_ACCURACY`] (case 1: 5.7e-8 m/s, case 2: 1.5e-7 m/s; `rtol = 1e-6` misses
/// it in case 1 with 1.2e-6; fixed steps need 1 ms in case 1 and below 0.1 ms in case 2, at
/// 10x to 100x the cost).
pub const DEFAULT_RTOL: f64 = 1e-7;

impl Default for Options {
    fn default() -> Self {
        Options {
            h: 1e-3,
            ref_div: 100,
            convergence: true,
            gammas: GAMMAS.to_vec(),
            ode: ode45::Options::default(),
            rk4_search: true,
            equal_accuracy: true,
            timing_budget: 0.3,
            hybrid_rtol: Some(DEFAULT_RTOL),
            work_precision: true,
        }
    }
}

/// One model's line of the table.
#[derive(Clone, Debug, Serialize)]
pub struct Row {
    /// Display name, e.g. `tanh(1000 v)`.
    pub model: String,
    /// `hybrid` or `tanh`.
    pub law: &'static str,
    /// gamma [s/m] of a tanh model.
    pub gamma: Option<f64>,
    /// `hybrid RK4 + events`, `ode45` or `RK4`.
    pub solver: &'static str,
    /// Fixed step [s], if any.
    pub h: Option<f64>,
    /// Wall time of one run [s] (fastest of the repetitions).
    pub time_s: f64,
    /// RMSE of the compared velocity against the reference [m/s].
    pub rmse: f64,
    /// Steps taken (ode45: accepted steps).
    pub steps: u64,
    /// Right-hand-side evaluations (ode45 and RK4; the hybrid model reports events instead).
    pub evals: Option<u64>,
    /// Rejected steps (ode45).
    pub rejected: Option<u64>,
    /// Located events (hybrid).
    pub events: Option<u64>,
    /// The paper's time [s] for this model (ode45 rows and the hybrid row).
    pub paper_time_s: Option<f64>,
    /// The paper's RMSE [m/s].
    pub paper_rmse: Option<f64>,
}

/// The hybrid model at the largest step that is at least as accurate as a tanh model.
#[derive(Clone, Debug, Serialize)]
pub struct EqualAccuracy {
    /// gamma of the tanh model [s/m].
    pub gamma: f64,
    /// Its ode45 time [s] and RMSE [m/s].
    pub tanh_time_s: f64,
    /// RMSE of the tanh model (ode45) [m/s].
    pub tanh_rmse: f64,
    /// Hybrid step found [s] (None: no step on the ladder is accurate enough).
    pub hybrid_h: Option<f64>,
    /// Hybrid time at that step [s].
    pub hybrid_time_s: Option<f64>,
    /// Hybrid RMSE at that step [m/s].
    pub hybrid_rmse: Option<f64>,
    /// `tanh_time / hybrid_time`.
    pub speedup: Option<f64>,
}

/// Everything measured for one case.
#[derive(Clone, Debug, Serialize)]
pub struct CaseReport {
    /// Which case.
    pub case: CaseId,
    /// Simulated time [s].
    pub duration: f64,
    /// Index of the compared velocity in `qd`.
    pub observed: usize,
    /// Reference step [s].
    pub h_ref: f64,
    /// Convergence of the reference (if checked).
    pub convergence: Option<Convergence>,
    /// Wall time of the reference run [s].
    pub reference_time_s: f64,
    /// The table's rows: hybrid, tanh by ode45, tanh by RK4.
    pub rows: Vec<Row>,
    /// Hybrid at equal or better accuracy than each tanh model.
    pub equal_accuracy: Vec<EqualAccuracy>,
    /// `time(tanh(1000 v), ode45) / time(hybrid, default setting)` (the paper: 55 for case 1).
    pub ratio_tanh1000_hybrid: Option<f64>,
    /// Work-precision points (empty unless asked for).
    pub work_precision: Vec<workprec::Point>,
    /// The fastest hybrid and tanh settings at each error level.
    pub levels: Vec<workprec::Level>,
}

/// Trajectories kept for the figures.
#[derive(Clone, Debug)]
pub struct CaseData {
    /// The case.
    pub case: Case,
    /// The reference.
    pub reference: Trajectory,
    /// Hybrid at the default step, with friction forces.
    pub hybrid: Trajectory,
    /// tanh models (ode45), with their gammas.
    pub tanh: Vec<(f64, Trajectory)>,
}

/// A tanh model of the case by fixed-step RK4 at step `h` (continuous-time input at the
/// stage times). Steps longer than the grid keep the accelerations for the interpolant (the
/// first stage of the next step, so at no extra cost).
pub fn tanh_rk4(case: &Case, gamma: f64, h: f64) -> Result<Trajectory> {
    let sys = Smooth::new(&case.params, Friction::Tanh(gamma), case.held);
    let (per, stride) = reference::plan(h, case.sample)?;
    let n_steps = (case.duration / h).round() as usize;
    let dense = stride > 1;
    let mut tr = Trajectory {
        h,
        stride,
        states: Vec::with_capacity(n_steps / per + 1),
        ..Trajectory::default()
    };
    let fail = |t: f64| Error::Rk4 { gamma, t };
    let mut y = pack(&case.init);
    let mut k1 = sys.rhs(&y, &case.u_at(0.0)).map_err(|_| fail(0.0))?;
    tr.states.push(case.init);
    if dense {
        tr.accel.push(qdd_of(&k1));
    }
    for n in 0..n_steps {
        let t = n as f64 * h;
        y = rk4_step_k1(&sys, t, &y, &k1, h, |t| case.u_at(t)).map_err(|_| fail(t))?;
        if !y.iter().all(|v| v.is_finite()) {
            return Err(fail(t));
        }
        k1 = sys.rhs(&y, &case.u_at(t + h)).map_err(|_| fail(t + h))?;
        if (n + 1) % per == 0 {
            tr.states.push(unpack(&y));
            if dense {
                tr.accel.push(qdd_of(&k1));
            }
        }
    }
    tr.steps = n_steps as u64;
    Ok(tr)
}

fn qdd_of(k: &Y) -> [f64; 5] {
    let mut a = [0.0; 5];
    a.copy_from_slice(&k[5..]);
    a
}

/// Steps of the RK4 ladder [s] for grid `sample`, largest first.
pub fn rk4_ladder(sample: f64) -> Vec<f64> {
    let mut v: Vec<f64> = [50.0, 20.0, 10.0, 8.0, 5.0, 4.0, 3.0, 2.0]
        .iter()
        .map(|m| m * sample)
        .collect();
    for d in [
        1, 2, 3, 4, 5, 6, 8, 10, 12, 16, 20, 24, 32, 40, 48, 64, 80, 96, 128, 160, 192, 256, 320,
        384, 512,
    ] {
        v.push(sample / d as f64);
    }
    v
}

/// Steps of the hybrid ladder [s] for grid `sample` and default step `h`, largest first.
pub fn hybrid_ladder(sample: f64, h: f64) -> Vec<f64> {
    let mut v: Vec<f64> = [
        200.0, 100.0, 50.0, 40.0, 25.0, 20.0, 10.0, 8.0, 5.0, 4.0, 2.0, 1.0,
    ]
    .iter()
    .map(|m| m * sample)
    .filter(|&s| s >= h)
    .collect();
    if !v.iter().any(|&s| (s - h).abs() < 1e-15) {
        v.push(h);
    }
    v
}

fn paper(case: CaseId, k: usize) -> (f64, f64) {
    let c = match case {
        CaseId::One => 0,
        CaseId::Two => 1,
    };
    PAPER[c][k]
}

fn gamma_index(g: f64) -> Option<usize> {
    GAMMAS.iter().position(|&x| x == g).map(|i| i + 1)
}

/// Runs the study of one case. `progress` is told what is being run.
pub fn run_case(
    case: &Case,
    o: &Options,
    mut progress: impl FnMut(&str),
) -> Result<(CaseReport, CaseData)> {
    let (refr, reference_time_s, convergence) = reference_stage(case, o, &mut progress)?;

    let mut rows = Vec::new();
    progress(&format!("{}: hybrid", case.name));
    let hybrid = hybrid_row(case, o, &refr)?;
    let t_h = hybrid.time_s;
    rows.push(hybrid);

    let Ode45Runs {
        rows: ode_rows,
        tanh,
    } = ode45_rows(case, o, &refr, &mut progress)?;
    rows.extend(ode_rows.iter().cloned());

    if o.rk4_search {
        rows.extend(rk4_rows(case, o, &refr, &ode_rows, &mut progress)?);
    }

    let equal_accuracy = if o.equal_accuracy {
        equal_accuracy_rows(case, o, &refr, &ode_rows, &mut progress)?
    } else {
        Vec::new()
    };

    let ratio_tanh1000_hybrid = ode_rows
        .iter()
        .find(|r| r.gamma == Some(1000.0))
        .map(|r| r.time_s / t_h);
    let (work_precision, levels) = if o.work_precision {
        let wo = workprec::Options::default();
        let pts = workprec::sweep(case, &refr, &wo, &mut progress)?;
        let lv = workprec::compare(&pts);
        (pts, lv)
    } else {
        (Vec::new(), Vec::new())
    };
    let hybrid_out = reference::hybrid(case, o.h, true)?;
    Ok((
        CaseReport {
            case: case.id,
            duration: case.duration,
            observed: case.observed,
            h_ref: refr.h,
            convergence,
            reference_time_s,
            rows,
            equal_accuracy,
            ratio_tanh1000_hybrid,
            work_precision,
            levels,
        },
        CaseData {
            case: case.clone(),
            reference: refr,
            hybrid: hybrid_out,
            tanh,
        },
    ))
}

/// The reference run (hybrid at `o.h / o.ref_div`), its wall time [s] and, if asked for,
/// its convergence check.
fn reference_stage(
    case: &Case,
    o: &Options,
    progress: &mut impl FnMut(&str),
) -> Result<(Trajectory, f64, Option<Convergence>)> {
    progress(&format!(
        "{}: reference (h = {} s)",
        case.name,
        o.h / o.ref_div as f64
    ));
    let t0 = Instant::now();
    let refr = reference::reference(case, o.h, o.ref_div)?;
    let reference_time_s = t0.elapsed().as_secs_f64();
    let convergence = if o.convergence {
        progress(&format!("{}: reference convergence check", case.name));
        Some(reference::convergence(case, &refr)?)
    } else {
        None
    };
    Ok((refr, reference_time_s, convergence))
}

/// The hybrid model's row at its default setting (adaptive at `o.hybrid_rtol`, or the fixed
/// step `o.h`), timed, with its RMSE against `refr`.
fn hybrid_row(case: &Case, o: &Options, refr: &Trajectory) -> Result<Row> {
    let (pt, pr) = paper(case.id, 0);
    Ok(match o.hybrid_rtol {
        Some(rtol) => {
            let tol = adaptive_run::tolerances(case, rtol);
            let (t, (hyb, st)) = time_best(o.timing_budget, || {
                adaptive_run::hybrid_adaptive(case, &tol)
            })?;
            Row {
                model: "hybrid".into(),
                law: "hybrid",
                gamma: None,
                solver: "hybrid DP45 + events",
                h: None,
                time_s: t,
                rmse: reference::rmse(case, &hyb, refr),
                steps: st.accepted,
                evals: Some(st.evals),
                rejected: Some(st.rejected),
                events: Some(st.events),
                paper_time_s: Some(pt),
                paper_rmse: Some(pr),
            }
        }
        None => {
            let (t, hyb) = time_best(o.timing_budget, || reference::hybrid(case, o.h, false))?;
            Row {
                model: "hybrid".into(),
                law: "hybrid",
                gamma: None,
                solver: "hybrid RK4 + events",
                h: Some(o.h),
                time_s: t,
                rmse: reference::rmse(case, &hyb, refr),
                steps: hyb.steps,
                evals: None,
                rejected: None,
                events: Some(hyb.events),
                paper_time_s: Some(pt),
                paper_rmse: Some(pr),
            }
        }
    })
}

/// The tanh models by ode45: one row each, and the trajectories with their gammas [s/m].
struct Ode45Runs {
    rows: Vec<Row>,
    tanh: Vec<(f64, Trajectory)>,
}

/// One row per gamma of `o.gammas`: the tanh model by ode45, timed, with its RMSE against
/// `refr`; and the trajectories with their gammas.
fn ode45_rows(
    case: &Case,
    o: &Options,
    refr: &Trajectory,
    progress: &mut impl FnMut(&str),
) -> Result<Ode45Runs> {
    let mut tanh = Vec::new();
    let mut ode_rows = Vec::new();
    for &g in &o.gammas {
        progress(&format!("{}: {} (ode45)", case.name, tanh_name(g)));
        let (t, (tr, st)) = time_best(o.timing_budget, || tanh_ode45(case, g, &o.ode))?;
        let p = gamma_index(g).map(|k| paper(case.id, k));
        ode_rows.push(Row {
            model: tanh_name(g),
            law: "tanh",
            gamma: Some(g),
            solver: "ode45",
            h: None,
            time_s: t,
            rmse: reference::rmse(case, &tr, refr),
            steps: st.accepted,
            evals: Some(st.evals),
            rejected: Some(st.rejected),
            events: None,
            paper_time_s: p.map(|p| p.0),
            paper_rmse: p.map(|p| p.1),
        });
        tanh.push((g, tr));
    }
    Ok(Ode45Runs {
        rows: ode_rows,
        tanh,
    })
}

/// For each tanh model of `ode_rows`: fixed-step RK4 at the largest step of the ladder whose
/// RMSE is within 10 % (plus 1e-9 m/s) of the ode45 RMSE, timed (no row if no step is).
fn rk4_rows(
    case: &Case,
    o: &Options,
    refr: &Trajectory,
    ode_rows: &[Row],
    progress: &mut impl FnMut(&str),
) -> Result<Vec<Row>> {
    let mut rows = Vec::new();
    for r in ode_rows {
        let g = r.gamma.unwrap_or(1.0);
        progress(&format!(
            "{}: {} (RK4 step search)",
            case.name,
            tanh_name(g)
        ));
        let limit = 1.1 * r.rmse + 1e-9;
        let mut found = None;
        for h in rk4_ladder(case.sample) {
            if let Ok(tr) = tanh_rk4(case, g, h) {
                if reference::rmse(case, &tr, refr) <= limit {
                    found = Some(h);
                    break;
                }
            }
        }
        if let Some(h) = found {
            let (t, tr) = time_best(o.timing_budget, || tanh_rk4(case, g, h))?;
            rows.push(Row {
                model: tanh_name(g),
                law: "tanh",
                gamma: Some(g),
                solver: "RK4",
                h: Some(h),
                time_s: t,
                rmse: reference::rmse(case, &tr, refr),
                steps: tr.steps,
                evals: Some(4 * tr.steps),
                rejected: None,
                events: None,
                paper_time_s: None,
                paper_rmse: None,
            });
        }
    }
    Ok(rows)
}

/// For each tanh model of `ode_rows`: the largest hybrid step of the ladder at least as
/// accurate, timed, and the speedup over the tanh model's ode45 time.
fn equal_accuracy_rows(
    case: &Case,
    o: &Options,
    refr: &Trajectory,
    ode_rows: &[Row],
    progress: &mut impl FnMut(&str),
) -> Result<Vec<EqualAccuracy>> {
    progress(&format!("{}: hybrid at equal accuracy", case.name));
    // RMSE of the hybrid model on its ladder (one run each), then timing where needed.
    let ladder: Vec<(f64, f64)> = hybrid_ladder(case.sample, o.h)
        .into_iter()
        .filter_map(|h| {
            reference::hybrid(case, h, false)
                .ok()
                .map(|tr| (h, reference::rmse(case, &tr, refr)))
        })
        .collect();
    let mut equal_accuracy = Vec::new();
    for r in ode_rows {
        let pick = ladder.iter().find(|(_, e)| *e <= r.rmse).copied();
        let (hh, ht, hr) = match pick {
            Some((h, e)) => {
                // The full state on the grid inside the timed run, as ode45 delivers it.
                let (t, _) = time_best(o.timing_budget, || {
                    reference::hybrid(case, h, false).map(|tr| tr.on_grid(case))
                })?;
                (Some(h), Some(t), Some(e))
            }
            None => (None, None, None),
        };
        equal_accuracy.push(EqualAccuracy {
            gamma: r.gamma.unwrap_or(f64::NAN),
            tanh_time_s: r.time_s,
            tanh_rmse: r.rmse,
            hybrid_h: hh,
            hybrid_time_s: ht,
            hybrid_rmse: hr,
            speedup: ht.map(|t| r.time_s / t),
        });
    }
    Ok(equal_accuracy)
}

fn fmt_opt(v: Option<f64>, w: usize) -> String {
    match v {
        Some(v) => format!("{:>w$}", fmt_g(v)),
        None => format!("{:>w$}", "-"),
    }
}

/// The table in the paper's form (both cases side by side) plus the extra rows, as text.
pub fn table(reports: &[CaseReport]) -> String {
    let mut s = String::new();
    let w = 11;
    s.push_str(&format!(
        "{:<34} | {:>w$} {:>w$} {:>w$} {:>w$} | {:>w$} {:>w$} {:>w$} {:>w$}\n",
        "", "CASE 1", "", "paper", "", "CASE 2", "", "paper", ""
    ));
    s.push_str(&format!(
        "{:<34} | {:>w$} {:>w$} {:>w$} {:>w$} | {:>w$} {:>w$} {:>w$} {:>w$}\n",
        "model",
        "t_sim [s]",
        "RMSE [m/s]",
        "t_sim [s]",
        "RMSE [m/s]",
        "t_sim [s]",
        "RMSE [m/s]",
        "t_sim [s]",
        "RMSE [m/s]"
    ));
    s.push_str(&format!(
        "{}\n",
        "-".repeat(34 + 3 + 4 * (w + 1) + 3 + 4 * (w + 1))
    ));
    let n = reports.iter().map(|r| r.rows.len()).max().unwrap_or(0);
    for k in 0..n {
        let name = reports
            .iter()
            .find_map(|r| r.rows.get(k))
            .map(|r| match (r.solver, r.h) {
                ("ode45", _) => format!("{} ode45", r.model),
                ("RK4", _) => format!("{} RK4 (max stable h)", r.model),
                ("hybrid DP45 + events", _) => format!("{} adaptive (default)", r.model),
                (_, Some(h)) => format!("{} (h = {} ms)", r.model, fmt_g(h * 1e3)),
                _ => r.model.clone(),
            })
            .unwrap_or_default();
        s.push_str(&format!("{name:<34}"));
        for r in reports {
            match r.rows.get(k) {
                Some(row) => s.push_str(&format!(
                    " | {:>w$} {:>w$} {} {}",
                    fmt_g(row.time_s),
                    fmt_g(row.rmse),
                    fmt_opt(row.paper_time_s, w),
                    fmt_opt(row.paper_rmse, w)
                )),
                None => s.push_str(&format!(" | {:>w$} {:>w$} {:>w$} {:>w$}", "", "", "", "")),
            }
        }
        s.push('\n');
    }
    for r in reports {
        s.push_str(&format!("\n{:?} ({} s simulated):\n", r.case, r.duration));
        if let Some(c) = r.convergence {
            s.push_str(&format!(
                "  reference: hybrid at h = {} s ({} s wall); against h = {} s: RMSE {} m/s, max |diff| {} m/s\n",
                fmt_g(c.h_ref),
                fmt_g(r.reference_time_s),
                fmt_g(c.h_check),
                fmt_g(c.rmse),
                fmt_g(c.max_diff)
            ));
        }
        for row in r.rows.iter().filter(|x| x.solver == "RK4") {
            s.push_str(&format!(
                "  {} RK4: largest stable step h = {} ms ({} steps)\n",
                row.model,
                fmt_g(row.h.unwrap_or(0.0) * 1e3),
                row.steps
            ));
        }
        if let Some(x) = r.ratio_tanh1000_hybrid {
            s.push_str(&format!(
                "  time tanh(1000 v) ode45 / hybrid at its default setting: {} (paper, case 1: 54.7; case 2: 29.1)\n",
                fmt_g(x)
            ));
        }
        for e in &r.equal_accuracy {
            match (e.hybrid_h, e.hybrid_time_s, e.hybrid_rmse, e.speedup) {
                (Some(h), Some(t), Some(er), Some(sp)) => s.push_str(&format!(
                    "  at the accuracy of {} (RMSE {}): hybrid h = {} ms, RMSE {}, {} s: {}x faster than ode45\n",
                    tanh_name(e.gamma),
                    fmt_g(e.tanh_rmse),
                    fmt_g(h * 1e3),
                    fmt_g(er),
                    fmt_g(t),
                    fmt_g(sp)
                )),
                _ => s.push_str(&format!(
                    "  at the accuracy of {}: no hybrid step on the ladder\n",
                    tanh_name(e.gamma)
                )),
            }
        }
        if !r.levels.is_empty() {
            s.push('\n');
            s.push_str(&workprec::table(&format!("{:?}", r.case), &r.levels));
        }
    }
    s
}

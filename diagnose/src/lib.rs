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
//!
//! ## Strangers' rigs
//!
//! `tests/strangers.rs` synthesises 15 plausible single-axis rigs with the project's drive
//! model, writes each as a data set (CSV + `dataset.toml`) and diagnoses it end to end
//! (`cargo test -p crane-diagnose --release --test strangers -- --nocapture`, about 35 s). Before: the
//! pipeline as built against EMPS and CICESE (commit `d62ac5e`); after: this version. NMAE is
//! the held-out simulated position NMAE baseline -> final model; `J` the fitted inertia.
//!
//! | rig | truth | before | after |
//! |---|---|---|---|
//! | linear, N, 1 kHz, 2 kg | Coulomb 4 N + viscous, nothing hidden | `input_delay` (8, grid edge) + stiction + dead band; 18.4 -> 1.2 % | `none`; 0.14 %; J 2.00, Fk 4.02 |
//! | rotary, N m, 200 Hz | pendulum 2 N m about 0.3 rad | `restoring_force` + delay 5 + stiction + offset | `restoring_force` only (k 2.01, c 0.28); 0.44 % |
//! | rotary, A, gain unknown, 2 kHz, J 2e-5 | friction twice as large moving negative | `stiction` + offset; 75.7 -> 39.8 %; J 7x low | `none`; 0.15 %; J, Fk+/-, D+/- within 1 % |
//! | linear, V, known gain, 500 Hz, 80 kg | stiction 70 / 40 N, 2 s rests | `stiction` + delay 8; J 30 kg | `stiction` only (70.6 / 40.0 N); 5.9 -> 0.18 %; J 80.0 |
//! | linear, V, 100 Hz, 20 % stamp jitter | spring 100 N/m + dead band 0.4 V | `restoring_force` + delay 6; J 0.06 kg | `restoring_force` only (k 122); 2.3 %; dead band absorbed in the dry level |
//! | rotary, V, gain unknown, 1 kHz, noisy | 4-sample input delay | `force_offset` (delay missed); 62 -> 21 % | `input_delay` 4; 8.5 -> 0.75 % |
//! | vertical linear, A, 1 kHz | constant load -m g (offset) | `force_offset` + stiction + delay | `force_offset` only (-24.4 N; the rest in the dry levels) ; 49 -> 0.11 % |
//! | linear, N, forward only | nothing hidden | `stiction`; 25 -> 8 % | `none`; 0.11 %; negative direction flagged not fitted |
//! | linear, input below breakaway | never moves | error "never move" | same |
//! | one 0.6 s run, 100 Hz | nothing hidden | `input_delay` (8, grid edge); J 1.8e-3 of 1 | `unexplained`, "not identifiable" (one motion) |
//! | rotary, 10 kg m^2, 500 Hz | viscous 5 / 15 by direction | `force_offset` + delay + stiction | `none`; 0.08 %; D 4.9 / 14.2 |
//! | belt, V, 1 kHz | dead band 1 V (a third of the input) | `stiction` + `input_deadzone` 0.9 V; 3.8 -> 0.3 % | `none`: 0.99 %, the band in the dry level (5.1 N) |
//! | rotary, encoder reversed | position counts against the input | `unexplained`, NMAE 2e5 % | error: "the recorded position moves against the input ... a sign is reversed" |
//! | PD loop declared as `[controller]`, 1 kHz | nothing hidden | `input_delay` (1 sample) + dead band | `none` (and on 9 further input draws, which named a cause on 4 before the bootstrap rule) |
//! | the same PD loop, the drive 3 samples late | 3-sample input delay | (not tried) | `input_delay` on all 9 draws (4 samples: the zero-order hold's one on top; 5 on one draw) |
//! | the same PD loop, the drive 30 samples (30 ms) late | 30-sample input delay | `input_delay` at 12 samples on all 9 draws (the closed-loop grid stopped there) | `input_delay` on all 9 draws: 0.031 s (the hold's sample on top) on 7, 0.030 s on 2 |
//! | a slower PD loop (kp 3 V/m, kd 0.5 V s/m) behind a 150 ms link, steps then 1 s at rest | 150-sample input delay (and the same rig without one) | `input_delay` at 12 samples on 8 draws, `unexplained` on one; without the delay nothing named | `input_delay` on all 9 draws: 0.151 s on 8, 0.150 s on one; without the delay nothing named on 9 of 9 |
//! | linear, N, 1 kHz, slow ramps that stick and slip | Stribeck weakening: breakaway 6 N falling to 3 N sliding over 0.03 m/s | (added later) | `stribeck_friction`: static 6.14 / 6.22 N, sliding 3.01 / 3.03 N, velocity 0.020 m/s; 28.0 -> 0.97 % |
//! | linear, N, 1 kHz, logged from 0.35 s into each run (mid-motion) | nothing hidden | (added later) simulated from rest: `unexplained`, 20.1 % | `none`; 0.20 %: held-out runs simulated from their first velocity when they start moving |
//!
//! What changed (each general, none tuned to a rig): the derivative window follows the
//! data's noise and rate ([`drive::prep::window`]: 5 samples at 2 kHz made one encoder count
//! an acceleration spike and biased every inertia low); the breakaway is read where the motion
//! starts, not where 2 % of the peak speed is crossed ([`drive::prep::onset`]); without
//! stiction the dry level comes from the sliding least squares when it simulates the fitting
//! runs clearly better ([`drive::estimate::DryLevel`]); no cause is tried once the model is
//! within the `none` level, from a single motion, or with the inertia undetermined; delay and
//! dead-band grid points are chosen on the fitting runs; a reversed sign is refused with its
//! fix; on closed-loop data a one-sample delay (the zero-order hold's) is not named and a
//! finding must cut the force NMAE as well as the squared error.
//!
//! On the closed-loop path a finding must also beat its noise floor: its held-out force-NMAE
//! cut positive in 95 % of a moving-block bootstrap that refits baseline and extension on
//! resampled fitting blocks and scores them on resampled held-out blocks
//! (`bootstrap_cuts` in `axis/bootstrap.rs`). The held-out error of one fit was not enough:
//! with one fitting run the baseline's per-direction position quartic extrapolates on the
//! held-out run, and any extra column that moves it cuts that run's error by chance (the PD
//! rig with nothing hidden named a dead band, stiction, localized friction or a 2-sample
//! delay on draws 1, 4, 6, 7 of `STRANGERS_SEED=0..8`, held-out cuts of 5-35 %, positive in
//! only 60-78 % of the replicates; a real delay is positive in 95-100 %). `tests/strangers.rs`
//! runs both over the 9 draws. On EMPS the direction asymmetry stays (cut 12.7 %, bootstrap
//! lower bound 9.4 %); the localized friction it also named against the symmetric baseline
//! (cut 3.3 %) is now dropped: its bootstrap lower bound is -2.4 %.
//!
//! Known limits: on the spring + dead band rig some input draws (`STRANGERS_SEED=2`) name a
//! 2-sample delay for the dead band (open-loop path, not changed here). The closed-loop
//! baseline's quartic extrapolation itself is left as it is (it is the EMPS paper's
//! structure); the bootstrap only keeps it from naming causes.
//!
//! ## Messy logs
//!
//! `tests/messy_logs.rs` writes further plausible open-loop logs as data sets and diagnoses
//! them end to end (`cargo test -p crane-diagnose --test messy_logs -- --nocapture`):
//!
//! | log | before | after |
//! |---|---|---|
//! | 10 kHz x 120 s (1.2 M rows), nothing hidden / a 100 N/m spring | `none` in 1.2 s / `restoring_force` in 17 s (both runs of the diagnosis, load included) | the same causes; 1.9 s / 22 s with the saturation candidate tried (test profile, load 1.6; printed by the test, not asserted); 1.05 s / 31.4 s with the output-error refinement (release profile, machine idle: the spring rig's baseline is refined, then each candidate that passes) |
//! | one 10 ms held-out run beside 2 kHz runs | window 7 samples for every run (17 without it), J 1.35 of 2, `input_delay` 8 (grid edge) | window 17, `none`, J 1.99 |
//! | coarse encoder, a count of 1-2 mm at 1 kHz (slides of 25-50 counts) | error "0 sliding samples" (motion floored at one count per sample) | a report, J 0.52 / 0.54 / 0.58 of 0.5 |
//! | runs that never move, fitted (every second run held out) | error "the fitting runs never move" | the same error, naming the moving held-out runs and `kind = "validation"` |
//! | runs that never move, held out | `none`, 0.00 % | `none`, the reason says no held-out run moves |
//! | vertical axis logged up, down, up, down | `unexplained`, "no candidate cuts it" (54.8 %) | `unexplained`, "not identifiable: the held-out runs move negative, which no fitting run does" + the fix; declared split: `force_offset` |
//! | runs at 1 kHz and 200 Hz in one data set | `none` | same |
//! | input recorded past the amplifier's limit (8-20 N pulses, applied clamped at 12 N) | `input_delay` (8, grid edge) + `input_deadzone`, 42.3 -> 27.8 %, "the rest is not explained" | `input_saturation` alone at 12.33 N; 42.3 -> 4.64 %; J 2.05 of 2 |
//! | nothing saturated, a 100 N/m spring / a 3 N dead band (same pulses) | (added with the saturation candidate) | `restoring_force` / `input_deadzone` only; the saturation candidate cuts the held-out NMAE by 0.2 % / raises it by 3.1 % |
//!
//! `input_saturation` (the effort applied `clamp(u, -s, +s)`): `s` from a grid over the
//! quantiles of |u| while moving on the fitting runs, refined by golden-section steps, both
//! by the fitting runs' simulated NMAE; named only below the largest |u| and above the
//! breakaway levels plus their run-to-run scatter (closer, a clamped effort trades against the
//! dry level: CICESE joint 1 with jittered stamps named a level of 13.16 N m against a
//! breakaway of 12.69, the stiffness falling from 49 to 16 N m/rad).
//!
//! Output-error refinement ([`drive::refine`]): least squares on differentiated positions
//! are biased by a coarse encoder or a long derivative window, and a cause named against such
//! a baseline may only stand in for the bias. Above the `none` level the baseline's inertia,
//! viscous and dry levels are now also tuned on the fitting runs' simulation (golden section
//! on each, within a factor 1.6, two sweeps); a first cause must cut the held-out error both
//! ways, least squares against least squares and refined against refined; with no cause
//! named the refined baseline is the final model (`none` within the `none` level). Measured:
//! CICESE joint 1 and 2 unchanged (105.33 -> 10.75 %, 7.63 -> 5.83 %, `restoring_force`
//! both; joint 2 refined both ways: 6.90 -> 6.21 %), the strangers' rigs and the hidden-effect
//! sweep unchanged; the 1 mm encoder count's stand-in `input_saturation` is refused (refined:
//! 2.05 -> 2.50 %, asserted in `a_coarse_encoder`).
//!
//! Known limit: with that 1 mm count and nothing hidden a stand-in is still named, now a
//! 1-sample `input_delay` (least squares 5.67 -> 4.16 %, refined 2.05 -> 1.26 %): the
//! open-loop path has no noise floor for a cut (the closed-loop path's block bootstrap),
//! and a 38 % cut of a 2 % error passes the 5 % gain rule.
//!
//! ## The real logs, re-expressed
//!
//! `tests/real_transforms.rs` rewrites the CICESE and EMPS logs in ways that change nothing
//! physical (clock offset, input in amperes with the gain unknown or declared, encoder and
//! drive both reversed, encoder zero moved, 20 s of rest in front) and requires the same
//! report to 1e-6; resampled (asynchronous stamps, half the rate) it requires the same physics.
//! Two rules failed it and were changed, both general:
//! - the `none` level and every score were diluted by a leading rest (joint 2 with 20 s of
//!   rest in front: NMAE 30.4 -> 10.8 %, "no cause tried", gravity lost); runs are now scored
//!   from their active part ([`drive::score::active_from`]);
//! - beside a dry level per direction, a constant `force_offset` is exactly those levels
//!   shifted; its fit still "helped" by moving the inertia and viscous estimates, and came and
//!   went with the sample rate on joint 1 (named at 33 Hz and with jittered stamps, 2.3-2.5
//!   N m, breakaway 12.8 / 8.0 N m against 10.3 / 10.8; not at 67 Hz). It is now named there
//!   only when it exceeds a level (the load alone moves the axis), which no shift reproduces.
//!
//! Subsets of the same logs: one direction only (joint 1's positive ramps) still names the
//! restoring force, at 145 N m/rad against gravity's 40, because one way a load and a friction
//! level changing along the travel are one force; the finding now says it is not identifiable
//! (`tests/cicese.rs`). Left as it is: joint 1's sine runs alone (pre-sliding, 0.02 degrees)
//! name a restoring force of 16,600 N m/rad with an inertia of 69 kg m^2: the contact's
//! pre-sliding stiffness, which the hybrid model (no pre-sliding) can only call a spring.

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
pub mod report;
mod summary;

pub use report::{
    AxisError, Candidate, Cause, Evidence, FinalModel, Finding, HeldoutSimulation, Report,
    RunSimulation, Verdict,
};

use crane_ident::data::{load_dataset, Dataset, Samples};
use crane_ident::params_file::ParamsFile;
use std::path::{Path, PathBuf};

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

/// A comment right after the opening `<svg ...>` tag of every plot `crane diagnose` writes
/// ([`mark_plot`]): a later run may replace a file that carries it, and nothing else without
/// `--force` ([`foreign_plot`]).
pub const PLOT_MARK: &str = "<!-- written by crane diagnose -->";

/// How the mark of every plot the `crane` command line writes begins ([`PLOT_MARK`] here,
/// `<!-- written by crane identify -->` and the like for the other commands): a file whose
/// first kilobyte holds it is one of the tool's own plots ([`is_crane_plot`]).
pub const PLOT_MARK_PREFIX: &str = "<!-- written by crane";

/// `svg` with [`PLOT_MARK`] after its opening tag (the file still starts with `<svg`).
pub fn mark_plot(svg: &str) -> String {
    mark_plot_with(svg, PLOT_MARK)
}

/// `svg` with `mark` (a comment beginning with [`PLOT_MARK_PREFIX`]) after its opening tag.
pub fn mark_plot_with(svg: &str, mark: &str) -> String {
    match svg.find('>') {
        Some(i) => format!("{}{mark}{}", &svg[..=i], &svg[i + 1..]),
        None => svg.to_string(),
    }
}

/// Whether the file at `path` is a plot the `crane` command line wrote (its first kilobyte
/// holds [`PLOT_MARK_PREFIX`]); `false` when it cannot be read.
pub fn is_crane_plot(path: &std::path::Path) -> bool {
    use std::io::Read;
    let mut head = Vec::new();
    std::fs::File::open(path)
        .and_then(|f| f.take(1024).read_to_end(&mut head))
        .is_ok()
        && String::from_utf8_lossy(&head).contains(PLOT_MARK_PREFIX)
}

/// The first `.svg` file in `dir` that the `crane` command line did not write
/// ([`is_crane_plot`]): a user's own figure, which a run with `--plots dir` must not replace
/// without `--force`. `None` when the folder is missing or holds only the tool's plots.
pub fn foreign_plot(dir: &std::path::Path) -> Option<PathBuf> {
    let entries = std::fs::read_dir(dir).ok()?;
    let mut names: Vec<PathBuf> = entries
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x == "svg"))
        .collect();
    names.sort();
    names.into_iter().find(|p| !is_crane_plot(p))
}

/// Options of [`diagnose`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DiagnoseOptions {
    /// Baseline model.
    pub baseline: Baseline,
    /// Write SVG plots of the residuals before and after the extension here.
    pub plots_dir: Option<PathBuf>,
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
    } else if matches!(opts.baseline, Baseline::Params(_) | Baseline::Fit(Some(_))) {
        // (the open-loop pipeline fits its own baseline: a crane file would be ignored)
        Err(DiagnoseError::Input(
            "--params is a crane parameter file; single-axis data get a baseline fitted from \
             their own runs (leave --params out)"
                .into(),
        ))
    } else if opts.baseline == Baseline::Symmetric || closed_loop(ds) {
        axis::diagnose_axis(ds, opts)
    } else {
        let (runs, split, info) = drive_runs(ds)?;
        drive::diagnose_drive(&ds.dir.display().to_string(), runs, split, &info, opts)
    }
}

/// Whether single-axis data come from a closed loop: the data set declares the controller
/// (`[controller]`), so the recorded input depends on the motion and the inverse-dynamics
/// pipeline of [`axis`] with the rig's controller handles them.
fn closed_loop(ds: &Dataset) -> bool {
    ds.spec.controller.is_some()
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
        // a position channel refreshed every few rows is rebuilt between its fresh samples,
        // here, or by the loader from the rows that gave it (`x_refresh`: one sample in
        // `x_refresh` carries news, taken as read every `x_refresh` samples)
        let (refresh, x, read_at) = if a.x_refresh > 1 {
            let every = |k: usize| a.source_t[k - k % a.x_refresh];
            let read_at = (0..a.source_t.len()).map(every).collect();
            (a.x_refresh, a.x.clone(), read_at)
        } else {
            // the hold as the grid shows it, else as the file's rows did (a jittered log's
            // resampling moves the repeats off the rows' lattice: stranger seed 11's s051,
            // x every 5 rows, was read as fresh on 4 of its 6 runs, and a window spanning
            // 3 fresh positions made the inertia 4,000 times low)
            let refresh =
                crane_ident::data::timebase::held_channel(&a.x).map_or(a.x_held.max(1), |(r, _)| r);
            let read_at = drive::prep::read_instants(&a.x, &a.source_t, refresh);
            (refresh, drive::prep::unhold(&a.x, refresh), read_at)
        };
        // instants from the cut's first sample
        let from = |v: &[f64], lo: usize, hi: usize| -> Vec<f64> {
            let t0 = a.t.get(lo).copied().unwrap_or(0.0);
            v.get(lo..hi)
                .unwrap_or_default()
                .iter()
                .map(|s| s - t0)
                .collect()
        };
        let mk = |lo: usize, hi: usize, held_out: bool| drive::DriveRun {
            name: r.name.clone(),
            held_out,
            dt,
            x: x[lo..hi].to_vec(),
            u: a.force[lo..hi].to_vec(),
            refresh,
            input_at: from(&a.source_t, lo, hi),
            read_at: from(&read_at, lo, hi),
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
    let first = axis
        .first()
        .map(|(_, a)| *a)
        .ok_or_else(|| DiagnoseError::Input("the data set has no single-axis run".into()))?;
    let info = drive::DriveInfo {
        motion: match first.position_unit {
            crane_ident::data::PositionUnit::Radian => crane_model::drive::Motion::Rotary,
            crane_ident::data::PositionUnit::Metre => crane_model::drive::Motion::Linear,
        },
        position_unit: first.position_unit.symbol().into(),
        force_unit: first.effort_unit().into(),
        input_unit: first.input_unit.symbol().into(),
        effort_per_input: match first.gain {
            crane_ident::data::Gain::Known(g) if g > 0.0 && g.is_finite() => g,
            _ => 1.0,
        },
        symmetric: false,
        load_notes: axis
            .iter()
            .flat_map(|(r, a)| a.notes.iter().map(move |n| format!("{}: {n}", r.name)))
            .collect(),
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

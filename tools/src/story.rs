//! The subcommands of the identification story: rig, identify, validate, diagnose, demo.

use anyhow::{bail, Context, Result};
use crane_diagnose::{Baseline, DiagnoseOptions};
use crane_ident::campaign::TRUTH_FILE;
use crane_ident::campaign::{run_rig, RigOptions, RigSummary};
use crane_ident::identify::{Estimate, Identified};
use crane_ident::params_file;
use crane_ident::validate::ValidationReport;
use crane_tools::output::{create_parent, is_dataset, normalise, OutputError, Outputs};
use indicatif::{ProgressBar, ProgressStyle};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// A spinner for work whose length is not known in advance (stderr; hidden when not a tty).
fn spinner(msg: &str) -> ProgressBar {
    let pb = ProgressBar::new_spinner();
    pb.set_style(
        ProgressStyle::with_template("{spinner} {msg} {elapsed}")
            .unwrap_or_else(|_| ProgressStyle::default_spinner()),
    );
    pb.set_message(msg.to_string());
    pb.enable_steady_tick(Duration::from_millis(120));
    pb
}

/// A scratch folder removed when dropped (an error, a panic unwinding) and on Ctrl-C, unless
/// [`Scratch::disarm`]ed after it was renamed into place.
struct Scratch {
    path: PathBuf,
    armed: bool,
}

/// Scratch folders to remove if the process is interrupted (SIGINT, SIGTERM).
static SCRATCH: std::sync::Mutex<Vec<PathBuf>> = std::sync::Mutex::new(Vec::new());

impl Scratch {
    fn new(path: PathBuf) -> Scratch {
        static HANDLER: std::sync::Once = std::sync::Once::new();
        HANDLER.call_once(|| {
            // (if a handler cannot be set, Ctrl-C just ends the process as before)
            let _ = ctrlc::set_handler(|| {
                if let Ok(list) = SCRATCH.lock() {
                    for p in list.iter() {
                        let _ = std::fs::remove_dir_all(p);
                    }
                }
                std::process::exit(130);
            });
        });
        if let Ok(mut list) = SCRATCH.lock() {
            list.push(path.clone());
        }
        Scratch { path, armed: true }
    }

    fn path(&self) -> &Path {
        &self.path
    }

    /// Keeps the folder (it is the output now).
    fn disarm(mut self) {
        self.armed = false;
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        if let Ok(mut list) = SCRATCH.lock() {
            list.retain(|p| p != &self.path);
        }
        if self.armed {
            let _ = std::fs::remove_dir_all(&self.path);
        }
    }
}

/// When the virtual rig may replace an existing, non-empty output folder.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Replace {
    /// Never (`crane rig` without `--force`).
    Never,
    /// When every entry in it is one the new campaign writes too (`crane demo` over its own
    /// earlier data set): a file the user added there is never deleted.
    OnlyOurs,
    /// Always (`--force`).
    Always,
}

/// Runs the virtual rig into `out` atomically: the data set is written into a temporary
/// directory beside `out` and renamed into place, so `out` holds the old data set or the new
/// one, never a mix. An existing, non-empty `out` is replaced as `replace` says.
fn rig_into(out: &Path, opts: &RigOptions, replace: Replace) -> Result<RigSummary> {
    if out.exists() {
        if !out.is_dir() {
            bail!("{} exists and is not a directory", out.display());
        }
        let empty = std::fs::read_dir(out)
            .with_context(|| format!("read {}", out.display()))?
            .next()
            .is_none();
        if !empty && replace == Replace::Never {
            if is_dataset(out) {
                return Err(OutputError::ReplacesDataset {
                    out: out.to_path_buf(),
                    dataset: out.to_path_buf(),
                }
                .into());
            }
            bail!(
                "{} exists and is not empty; refusing to write a data set into it (choose another --out, or pass --force)",
                out.display()
            );
        }
    }
    // the folder is replaced by a rename: the current directory (`--out .`) or one holding
    // it cannot be, and would leave the whole campaign behind in a hidden folder
    if let Ok(cwd) = std::env::current_dir().and_then(|c| c.canonicalize()) {
        if out.exists() && cwd.starts_with(normalise(out)) {
            bail!(
                "{} is the current directory or holds it; the data set replaces its folder \
                 whole, so choose a folder below it (for example --out {})",
                out.display(),
                out.join("dataset").display()
            );
        }
    }
    create_parent(out)?;
    // removed on every way out but the last rename, Ctrl-C included
    let tmp = Scratch::new(crane_ident::atomic::temp_beside(out));
    let mut summary =
        run_rig(tmp.path(), opts).with_context(|| format!("rig into {}", out.display()))?;
    if replace == Replace::OnlyOurs && out.is_dir() {
        let foreign = std::fs::read_dir(out)
            .with_context(|| format!("read {}", out.display()))?
            .flatten()
            .map(|e| e.file_name())
            .find(|name| !tmp.path().join(name).exists());
        if let Some(name) = foreign {
            bail!(
                "{} holds {}, which the demo did not write; refusing to replace the folder \
                 (move it away, or pass --force)",
                out.display(),
                name.to_string_lossy()
            );
        }
    }
    let old = Scratch::new(crane_ident::atomic::temp_beside(out));
    let had_old = out.exists();
    if had_old {
        std::fs::rename(out, old.path())
            .with_context(|| format!("move {} aside", out.display()))?;
    }
    if let Err(e) = std::fs::rename(tmp.path(), out) {
        if had_old {
            let _ = std::fs::rename(old.path(), out);
        }
        return Err(e).with_context(|| format!("rename the new data set to {}", out.display()));
    }
    tmp.disarm();
    summary.dir = out.to_path_buf();
    Ok(summary)
}

/// `crane rig`: the virtual rig's campaign into `out` (refused over an existing, non-empty
/// directory unless `force`).
pub fn rig(out: &Path, seed: Option<u64>, force: bool, json: bool) -> Result<RigSummary> {
    let replace = if force {
        Replace::Always
    } else {
        Replace::Never
    };
    rig_with(out, seed, replace, json)
}

/// `crane rig` with a replacement policy (see [`Replace`]).
fn rig_with(out: &Path, seed: Option<u64>, replace: Replace, json: bool) -> Result<RigSummary> {
    let mut opts = RigOptions::default();
    if let Some(s) = seed {
        opts.plant.seed = s;
    }
    let pb = spinner("virtual rig: running the paper's experiments");
    let summary = rig_into(out, &opts, replace)?;
    pb.finish_and_clear();
    if !json {
        out!(
            "rig: {} runs, {} samples in {} ({:.1} s)",
            summary.runs,
            summary.samples,
            summary.dir.display(),
            summary.seconds
        );
        for p in &summary.probes {
            out!(
                "  breakaway probes {}{}: {} (max predictive std {:.3} N, stop: {:?})",
                p.axis,
                p.direction,
                p.positions.len(),
                p.max_std,
                p.stop
            );
        }
    }
    Ok(summary)
}

fn est(e: &Estimate) -> String {
    format!("{:.5} ± {:.2e}", e.value, e.std_err)
}

/// The true parameters the virtual rig left next to its data set, if any.
///
/// Loaders ignore this file (`DATA_FORMAT.md`): one that does not read as the rig's
/// parameters (a user's own file of that name) is skipped with a warning on stderr, never an
/// error.
fn rig_truth(dataset: &Path) -> Result<Option<crane_model::Params>> {
    let path = dataset.join(crane_ident::campaign::TRUTH_FILE);
    if !path.exists() {
        return Ok(None);
    }
    match params_file::read(&path) {
        Ok(p) => Ok(Some(p)),
        Err(e) => {
            eprintln!("crane: warning: {e}; not the virtual rig's truth, so the plots show none");
            Ok(None)
        }
    }
}

/// `crane identify`: every parameter from a data set, written to `out` (TOML); friction
/// plots with their bands into `plots` (SVG).
pub fn identify(
    dataset: &Path,
    out: &Path,
    plots: &Path,
    force: bool,
    json: bool,
) -> Result<Identified> {
    let outputs = Outputs::new(force)
        .input(&dataset.join(crane_ident::data::DATASET_FILE))
        .input(&dataset.join(TRUTH_FILE));
    // refuse before the work, not after it
    outputs.check(out)?;
    outputs.check_dir(plots)?;
    let pb = spinner("identifying");
    let id = crane_ident::identify::identify(dataset)
        .with_context(|| format!("identify from {}", dataset.display()))?;
    pb.finish_and_clear();
    let truth = rig_truth(dataset)?;
    // the plots first: a failure there leaves the earlier parameter file as it was
    let files = crate::plot::friction(&id, truth.as_ref(), plots, &outputs)?;
    outputs.write(out, params_file::to_toml(&id.params))?;
    if json {
        return Ok(id);
    }
    out!("identified parameters -> {}", out.display());
    out!("| parameter | estimate ± std. error |\n|---|---|");
    let r = &id.rope;
    for (name, e) in [
        ("rope Jbar_l [kg]", &r.inertia),
        ("rope K_l [N/V]", &r.gain),
        ("rope Dbar_l [N s/m]", &r.viscous),
        ("rope Cbar_l [N]", &r.dry),
    ] {
        out!("| {name} | {} |", est(e));
    }
    for (axis, d) in [("X", &id.x), ("Y", &id.y)] {
        for (name, e) in [
            ("Jbar [kg]", &d.inertia),
            ("K [N/V]", &d.gain),
            ("Dbar+ [N s/m]", &d.viscous_pos),
            ("Dbar- [N s/m]", &d.viscous_neg),
        ] {
            out!("| {axis} {name} | {} |", est(e));
        }
        for (dir, f) in [("+", &d.dry_pos), ("-", &d.dry_neg)] {
            let c: Vec<String> = f.coefficients.iter().map(|c| format!("{c:.3}")).collect();
            let widest = f
                .curve
                .simultaneous_upper
                .iter()
                .zip(&f.curve.mean)
                .map(|(u, m)| u - m)
                .fold(0.0, f64::max);
            out!(
                "| {axis} Cbar{dir}(p) c0..c4 [N] | {} ({} probes; 95 % band over the axis: mean ± {:.2} std, at most ± {:.3} N) |",
                c.join(", "),
                f.positions.len(),
                f.curve.simultaneous_multiplier,
                widest
            );
        }
    }
    out!("| D_alpha [kg m^2/s] | {} |", est(&id.swing.damping_alpha));
    out!("| D_beta [kg m^2/s] | {} |", est(&id.swing.damping_beta));
    for f in files {
        out!("plot: {}", f.display());
    }
    Ok(id)
}

/// `crane validate`: NMAE table of the validation runs and plots.
pub fn validate(
    dataset: &Path,
    params: &Path,
    plots: &Path,
    force: bool,
    json: bool,
) -> Result<ValidationReport> {
    let outputs = Outputs::new(force).input(params);
    outputs.check_dir(plots)?;
    let p = params_file::read(params).context("read parameters")?;
    let ds = crane_ident::data::load_dataset(dataset)
        .with_context(|| format!("load data set {}", dataset.display()))?;
    let report = crane_ident::validate::validate_dataset(&p, &ds)
        .with_context(|| format!("validate on {}", dataset.display()))?;
    let files = crate::plot::validation(&ds, &report, plots, &outputs)?;
    if !json {
        out!("validation (payload position NMAE, normalised by each axis's range):");
        out!("{}", report.table().trim_end());
        for f in files {
            out!("plot: {}", f.display());
        }
    }
    Ok(report)
}

/// `crane diagnose`: the text summary, or with `json` the report (JSON) on stdout; the
/// report also into `report_file` if given.
#[allow(clippy::too_many_arguments)]
pub fn diagnose(
    dataset: &Path,
    params: Option<&Path>,
    fit_baseline: bool,
    symmetric: bool,
    report_file: Option<&Path>,
    plots: Option<PathBuf>,
    force: bool,
    json: bool,
) -> Result<()> {
    let mut outputs = Outputs::new(force);
    if let Some(p) = params {
        outputs = outputs.input(p);
    }
    if let Some(r) = report_file {
        outputs.check(r)?;
    }
    if let Some(user) = plots
        .as_deref()
        .filter(|_| !force)
        .and_then(crane_diagnose::foreign_plot)
    {
        anyhow::bail!(
            "{} was not written by crane diagnose; refusing to write plots beside it, where they \
             could replace it (choose another --plots folder, or pass --force)",
            user.display()
        );
    }
    let file = match params {
        Some(p) => Some(params_file::read(p).context("read parameters")?),
        None => None,
    };
    let baseline = match (fit_baseline, file) {
        _ if symmetric => Baseline::Symmetric,
        (true, f) => Baseline::Fit(f),
        (false, Some(f)) => Baseline::Params(f),
        (false, None) => Baseline::Auto,
    };
    let opts = DiagnoseOptions {
        baseline,
        plots_dir: plots,
    };
    let pb = spinner("diagnosing");
    let report = crane_diagnose::diagnose(dataset, &opts)
        .map_err(|e| anyhow::anyhow!("{e}"))
        .with_context(|| format!("diagnose {}", dataset.display()))?;
    pb.finish_and_clear();
    if let Some(path) = report_file {
        outputs.write(path, report.to_json())?;
    }
    if json {
        out!("{}", report.to_json().trim_end());
        return Ok(());
    }
    out!("{}", report.summary().trim_end());
    Ok(())
}

/// What `crane demo --json` prints: one document with the three steps.
#[derive(Serialize)]
pub struct DemoReport {
    /// The rig's campaign.
    pub rig: RigSummary,
    /// The identification.
    pub identify: Identified,
    /// The validation.
    pub validate: ValidationReport,
}

/// `crane demo`: rig, identification, validation, into `out` (`out/dataset`,
/// `out/params.toml`, `out/plots`: the defaults of `crane identify` and `crane validate` when
/// `out` is `out`). A data set already in `out/dataset` is replaced only when the virtual rig
/// wrote it (it holds `truth_params.toml`) or with `force`.
pub fn demo(out: &Path, force: bool, json: bool) -> Result<DemoReport> {
    let dataset = out.join("dataset");
    let params = out.join("params.toml");
    let plots = out.join("plots");
    let replace = if force {
        Replace::Always
    } else if dataset.join(TRUTH_FILE).is_file() {
        Replace::OnlyOurs
    } else {
        Replace::Never
    };
    let rig = rig_with(&dataset, None, replace, json)?;
    let identify = identify(&dataset, &params, &plots, force, json)?;
    let validate = validate(&dataset, &params, &plots, force, json)?;
    Ok(DemoReport {
        rig,
        identify,
        validate,
    })
}

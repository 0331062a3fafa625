//! The subcommands of the identification story: rig, identify, validate, diagnose, demo.

use anyhow::{bail, Context, Result};
use crane_diagnose::{Baseline, DiagnoseOptions};
use crane_ident::campaign::TRUTH_FILE;
use crane_ident::campaign::{run_rig, RigOptions, RigSummary};
use crane_ident::identify::{Estimate, Identified};
use crane_ident::params_file;
use crane_ident::validate::ValidationReport;
use crane_tools::output::{is_dataset, normalise, OutputError, Outputs};
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

/// Refuses a rig output folder `out` before any work: a path that is not a folder, an
/// existing non-empty folder unless `replace` allows it, or the current directory (or one
/// holding it), which cannot be replaced by a rename.
fn check_rig_out(out: &Path, replace: Replace) -> Result<()> {
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
    Ok(())
}

/// Runs the virtual rig into a scratch folder staged in `outputs` to replace `out` whole at
/// the commit (`out` then holds the old data set or the new one, never a mix; a failure or
/// Ctrl-C before the commit leaves it as it was and removes the scratch folder). An existing,
/// non-empty `out` is replaced as `replace` says. Returns the campaign's summary (its `dir`
/// is `out`) and the scratch folder, where the new data set can be read before the commit.
fn rig_stage(
    out: &Path,
    opts: &RigOptions,
    replace: Replace,
    outputs: &mut Outputs,
) -> Result<(RigSummary, PathBuf)> {
    check_rig_out(out, replace)?;
    let tmp = outputs.stage_dir(out)?;
    let mut summary = run_rig(&tmp, opts).with_context(|| format!("rig into {}", out.display()))?;
    if replace == Replace::OnlyOurs && out.is_dir() {
        let foreign = std::fs::read_dir(out)
            .with_context(|| format!("read {}", out.display()))?
            .flatten()
            .map(|e| e.file_name())
            .find(|name| !tmp.join(name).exists());
        if let Some(name) = foreign {
            bail!(
                "{} holds {}, which the demo did not write; refusing to replace the folder \
                 (move it away, or pass --force)",
                out.display(),
                name.to_string_lossy()
            );
        }
    }
    summary.dir = out.to_path_buf();
    Ok((summary, tmp))
}

/// `crane rig`: the virtual rig's campaign into `out` (refused over an existing, non-empty
/// directory unless `force`).
pub fn rig(out: &Path, seed: Option<u64>, force: bool, json: bool) -> Result<RigSummary> {
    let replace = if force {
        Replace::Always
    } else {
        Replace::Never
    };
    let mut opts = RigOptions::default();
    if let Some(s) = seed {
        opts.plant.seed = s;
    }
    let mut outputs = Outputs::new(force);
    let pb = spinner("virtual rig: running the paper's experiments");
    let (summary, _) = rig_stage(out, &opts, replace, &mut outputs)?;
    outputs.commit()?;
    pb.finish_and_clear();
    if !json {
        print_rig(&summary)?;
    }
    Ok(summary)
}

/// The rig's lines of `crane rig` and `crane demo`.
fn print_rig(summary: &RigSummary) -> Result<()> {
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
    Ok(())
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
/// plots with their bands into `plots` (SVG). The parameter file and the plots are
/// published together at the end, or none of them.
pub fn identify(
    dataset: &Path,
    out: &Path,
    plots: &Path,
    force: bool,
    json: bool,
) -> Result<Identified> {
    let mut outputs = Outputs::new(force)
        .input(&dataset.join(crane_ident::data::DATASET_FILE))
        .input(&dataset.join(TRUTH_FILE));
    // refuse before the work, not after it
    outputs.check(out)?;
    outputs.check_dir(plots)?;
    let (id, files) = identify_stage(dataset, dataset, out, plots, &mut outputs)?;
    outputs.commit()?;
    if !json {
        print_identified(&id, out, &files)?;
    }
    Ok(id)
}

/// Identifies from the data set in `read` (named `shown` in messages) and stages the
/// parameter file `out` and the friction plots in `plots` in `outputs`.
fn identify_stage(
    read: &Path,
    shown: &Path,
    out: &Path,
    plots: &Path,
    outputs: &mut Outputs,
) -> Result<(Identified, Vec<PathBuf>)> {
    let pb = spinner("identifying");
    let id = crane_ident::identify::identify(read)
        .with_context(|| format!("identify from {}", shown.display()))?;
    pb.finish_and_clear();
    let truth = rig_truth(read)?;
    let files = crate::plot::friction(&id, truth.as_ref(), plots, outputs)?;
    outputs.stage(out, params_file::to_toml(&id.params))?;
    Ok((id, files))
}

/// The table of `crane identify` (and of `crane demo`).
fn print_identified(id: &Identified, out: &Path, files: &[PathBuf]) -> Result<()> {
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
    Ok(())
}

/// `crane validate`: NMAE table of the validation runs and plots (published together at
/// the end, or none).
pub fn validate(
    dataset: &Path,
    params: &Path,
    plots: &Path,
    force: bool,
    json: bool,
) -> Result<ValidationReport> {
    let mut outputs = Outputs::new(force).input(params);
    outputs.check_dir(plots)?;
    let p = params_file::read(params).context("read parameters")?;
    let what = format!("the parameters of {}", params.display());
    let (report, files) = validate_stage(dataset, dataset, (&p, &what), plots, &mut outputs)?;
    outputs.commit()?;
    if !json {
        print_validation(&report, &files)?;
    }
    Ok(report)
}

/// Validates the parameters `p` (named `what` in messages: their file) on the data set in
/// `read` (named `shown`) and stages the plots in `plots` in `outputs`.
fn validate_stage(
    read: &Path,
    shown: &Path,
    (p, what): (&crane_model::Params, &str),
    plots: &Path,
    outputs: &mut Outputs,
) -> Result<(ValidationReport, Vec<PathBuf>)> {
    let ds = crane_ident::data::load_dataset(read)
        .with_context(|| format!("load data set {}", shown.display()))?;
    let report = crane_ident::validate::validate_dataset(p, &ds)
        .with_context(|| format!("validate {what} on {}", shown.display()))?;
    let files = crate::plot::validation(&ds, &report, plots, outputs)?;
    Ok((report, files))
}

/// The table of `crane validate` (and of `crane demo`).
fn print_validation(report: &ValidationReport, files: &[PathBuf]) -> Result<()> {
    out!("validation (payload position NMAE, normalised by each axis's range):");
    out!("{}", report.table().trim_end());
    for f in files {
        out!("plot: {}", f.display());
    }
    Ok(())
}

/// `crane diagnose`: the text summary, or with `json` the report (JSON) on stdout; the
/// report also into `report_file` if given. The report file and the plots are published
/// together at the end, or none of them: the plots are drawn into a scratch folder inside
/// `plots` and staged from there.
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
    if let Some(dir) = &plots {
        // a plots "folder" that is a file: said before the work, not after it
        outputs.check_dir(dir)?;
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
    let scratch = match &plots {
        Some(dir) => Some(outputs.scratch_in(dir)?),
        None => None,
    };
    let opts = DiagnoseOptions {
        baseline,
        plots_dir: scratch.clone(),
    };
    let pb = spinner("diagnosing");
    let report = crane_diagnose::diagnose(dataset, &opts)
        .map_err(|e| {
            // the scratch folder is ours: name the folder the user gave
            let mut m = e.to_string();
            if let (Some(s), Some(p)) = (&scratch, &plots) {
                m = m.replace(&s.display().to_string(), &p.display().to_string());
            }
            // the baseline's parameters came from a file: name it
            if let Some(p) = &params {
                m = m.replace(
                    "the given parameters",
                    &format!("the parameters of {}", p.display()),
                );
            }
            anyhow::anyhow!(m)
        })
        .with_context(|| format!("diagnose {}", dataset.display()))?;
    pb.finish_and_clear();
    if let (Some(s), Some(p)) = (&scratch, &plots) {
        stage_drawn(&mut outputs, s, p)?;
    }
    if let Some(path) = report_file {
        outputs.stage(path, report.to_json())?;
    }
    outputs.commit()?;
    if json {
        out!("{}", report.to_json().trim_end());
        return Ok(());
    }
    out!("{}", report.summary().trim_end());
    Ok(())
}

/// Stages every file a library drew into the scratch folder `scratch` for the same name in
/// `dir`, in name order.
fn stage_drawn(outputs: &mut Outputs, scratch: &Path, dir: &Path) -> Result<()> {
    let mut names: Vec<std::ffi::OsString> = std::fs::read_dir(scratch)
        .with_context(|| format!("read {}", scratch.display()))?
        .flatten()
        .filter(|e| e.file_type().is_ok_and(|t| t.is_file()))
        .map(|e| e.file_name())
        .collect();
    names.sort();
    for name in names {
        outputs.adopt(&dir.join(&name), &scratch.join(&name))?;
    }
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
///
/// One command, one commit: the new data set is identified and validated in its scratch
/// folder, and the data set, the parameter file and the plots are published together at the
/// end. A failure or Ctrl-C on the way leaves `out` as it was.
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
    let mut outputs = Outputs::new(force);
    outputs.check_dir(out)?;
    outputs.check(&params)?;
    outputs.check_dir(&plots)?;
    let pb = spinner("virtual rig: running the paper's experiments");
    let (rig, staged) = rig_stage(&dataset, &RigOptions::default(), replace, &mut outputs)?;
    pb.finish_and_clear();
    let (identify, id_files) = identify_stage(&staged, &dataset, &params, &plots, &mut outputs)?;
    let (validate, val_files) = validate_stage(
        &staged,
        &dataset,
        (&identify.params, "the identified parameters"),
        &plots,
        &mut outputs,
    )?;
    outputs.commit()?;
    if !json {
        print_rig(&rig)?;
        print_identified(&identify, &params, &id_files)?;
        print_validation(&validate, &val_files)?;
    }
    Ok(DemoReport {
        rig,
        identify,
        validate,
    })
}

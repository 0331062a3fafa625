//! The subcommands of the identification story: rig, identify, validate, diagnose, demo.

use anyhow::{Context, Result};
use crane_diagnose::{Baseline, DiagnoseOptions};
use crane_ident::campaign::{run_rig, RigOptions, RigSummary};
use crane_ident::identify::{Estimate, Identified};
use crane_ident::params_file::ParamsFile;
use crane_ident::validate::ValidationReport;
use indicatif::{ProgressBar, ProgressStyle};
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

/// `crane rig`: the virtual rig's campaign into `out`.
pub fn rig(out: &Path, seed: Option<u64>, json: bool) -> Result<RigSummary> {
    let mut opts = RigOptions::default();
    if let Some(s) = seed {
        opts.plant.seed = s;
    }
    let pb = spinner("virtual rig: running the paper's experiments");
    let summary = run_rig(out, &opts).with_context(|| format!("rig into {}", out.display()))?;
    pb.finish_and_clear();
    if json {
        println!("{}", serde_json::to_string_pretty(&summary)?);
    } else {
        println!(
            "rig: {} runs, {} samples in {} ({:.1} s)",
            summary.runs,
            summary.samples,
            summary.dir.display(),
            summary.seconds
        );
        for p in &summary.probes {
            println!(
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
fn rig_truth(dataset: &Path) -> Result<Option<crane_model::Params>> {
    let path = dataset.join(crane_ident::campaign::TRUTH_FILE);
    if !path.exists() {
        return Ok(None);
    }
    let p = ParamsFile::read(&path)
        .map_err(anyhow::Error::msg)
        .with_context(|| format!("read {}", path.display()))?;
    Ok(Some(crane_model::Params::from(&p)))
}

/// `crane identify`: every parameter from a data set, written to `out` (TOML); friction
/// plots with their bands into `plots` (SVG).
pub fn identify(dataset: &Path, out: &Path, plots: &Path, json: bool) -> Result<Identified> {
    let pb = spinner("identifying");
    let id = crane_ident::identify::identify(dataset)
        .with_context(|| format!("identify from {}", dataset.display()))?;
    pb.finish_and_clear();
    if let Some(dir) = out.parent() {
        std::fs::create_dir_all(dir).with_context(|| format!("create {}", dir.display()))?;
    }
    id.params
        .write(out)
        .with_context(|| format!("write {}", out.display()))?;
    let truth = rig_truth(dataset)?;
    let files = crate::plot::friction(&id, truth.as_ref(), plots)?;
    if json {
        println!("{}", serde_json::to_string_pretty(&id)?);
        return Ok(id);
    }
    println!("identified parameters -> {}", out.display());
    println!("| parameter | estimate ± std. error |\n|---|---|");
    let r = &id.rope;
    for (name, e) in [
        ("rope Jbar_l [kg]", &r.inertia),
        ("rope K_l [N/V]", &r.gain),
        ("rope Dbar_l [N s/m]", &r.viscous),
        ("rope Cbar_l [N]", &r.dry),
    ] {
        println!("| {name} | {} |", est(e));
    }
    for (axis, d) in [("X", &id.x), ("Y", &id.y)] {
        for (name, e) in [
            ("Jbar [kg]", &d.inertia),
            ("K [N/V]", &d.gain),
            ("Dbar+ [N s/m]", &d.viscous_pos),
            ("Dbar- [N s/m]", &d.viscous_neg),
        ] {
            println!("| {axis} {name} | {} |", est(e));
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
            println!(
                "| {axis} Cbar{dir}(p) c0..c4 [N] | {} ({} probes; 95 % band over the axis: mean ± {:.2} std, at most ± {:.3} N) |",
                c.join(", "),
                f.positions.len(),
                f.curve.simultaneous_multiplier,
                widest
            );
        }
    }
    println!("| D_alpha [kg m^2/s] | {} |", est(&id.swing.damping_alpha));
    println!("| D_beta [kg m^2/s] | {} |", est(&id.swing.damping_beta));
    for f in files {
        println!("plot: {}", f.display());
    }
    Ok(id)
}

/// `crane validate`: NMAE table of the validation runs and plots.
pub fn validate(
    dataset: &Path,
    params: &Path,
    plots: &Path,
    json: bool,
) -> Result<ValidationReport> {
    let p = ParamsFile::read(params)
        .map_err(anyhow::Error::msg)
        .with_context(|| format!("read parameters {}", params.display()))?;
    let ds = crane_ident::data::load_dataset(dataset)
        .with_context(|| format!("load data set {}", dataset.display()))?;
    let report = crane_ident::validate::validate_dataset(&p, &ds)
        .with_context(|| format!("validate on {}", dataset.display()))?;
    let files = crate::plot::validation(&ds, &report, plots)?;
    if json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        println!("validation (payload position NMAE, normalised by each axis's range):");
        print!("{}", report.table());
        for f in files {
            println!("plot: {}", f.display());
        }
    }
    Ok(report)
}

/// `crane diagnose`.
pub fn diagnose(
    dataset: &Path,
    params: Option<&Path>,
    fit_baseline: bool,
    symmetric: bool,
    json: Option<&Path>,
    plots: Option<PathBuf>,
) -> Result<()> {
    let file = match params {
        Some(p) => Some(
            ParamsFile::read(p)
                .map_err(anyhow::Error::msg)
                .with_context(|| format!("read parameters {}", p.display()))?,
        ),
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
    if let Some(path) = json {
        std::fs::write(path, report.to_json())
            .with_context(|| format!("write {}", path.display()))?;
    }
    print!("{}", report.summary());
    Ok(())
}

/// `crane demo`: rig, identification, validation, into `out`.
pub fn demo(out: &Path, json: bool) -> Result<()> {
    let dataset = out.join("dataset");
    let params = out.join("params.toml");
    let plots = out.join("plots");
    rig(&dataset, None, json)?;
    identify(&dataset, &params, &plots, json)?;
    validate(&dataset, &params, &plots, json)?;
    Ok(())
}

//! `crane study` and `crane mc`.

use anyhow::{bail, Result};
use crane_tools::cases::Case;
use crane_tools::output::Outputs;
use crane_tools::{figures, montecarlo, study};
use std::path::Path;

/// `crane study`: both cases, the table (or JSON), the figures and `study.json` in `out`.
pub fn study(out: &Path, json: bool, quick: bool, budget: f64, force: bool) -> Result<()> {
    let outputs = Outputs::new(force);
    let jpath = out.join("study.json");
    outputs.check(&jpath)?;
    let opts = study::Options {
        rk4_search: !quick,
        equal_accuracy: !quick,
        timing_budget: budget,
        ..study::Options::default()
    };
    let [c1, c2] = Case::all();
    let progress = |m: &str| eprintln!("study: {m}");
    let (r1, d1) = study::run_case(&c1, &opts, progress)?;
    let (r2, d2) = study::run_case(&c2, &opts, progress)?;
    let reports = vec![r1, r2];
    let js = serde_json::to_string_pretty(&reports)?;
    outputs.write(&jpath, &js)?;
    let figs = figures::write(out, &d1, &d2, &outputs)?;
    if json {
        out!("{js}");
    } else {
        out!("{}", study::table(&reports));
        out!(
            "ode45: rtol {}, atol {}; reference: hybrid at h / {}; times: fastest of repeated runs, one thread",
            opts.ode.rtol, opts.ode.atol, opts.ref_div
        );
        for f in figs.iter().chain([&jpath]) {
            out!("wrote {}", f.display());
        }
    }
    Ok(())
}

/// Most model steps one simulation of `crane mc` may take.
pub const MAX_STEPS: f64 = 1e8;

/// `crane mc`: a Monte Carlo batch on all cores.
pub fn mc(sims: u64, duration: f64, h: f64, seed: u64, json: bool) -> Result<montecarlo::Summary> {
    let steps = (duration / h).round();
    if steps > MAX_STEPS {
        bail!("--duration {duration} / --h {h} = {steps:e} steps per simulation; at most {MAX_STEPS:e}");
    }
    if steps < 1.0 {
        bail!("--duration {duration} is shorter than one step --h {h}");
    }
    let sims = usize::try_from(sims)?;
    // progress on stderr; indicatif draws nothing when stderr is not a terminal
    let pb = indicatif::ProgressBar::new(sims as u64);
    pb.set_style(
        indicatif::ProgressStyle::with_template(
            "mc {bar:40} {pos}/{len} simulations {elapsed} (eta {eta})",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let result = montecarlo::run_with_progress(sims, duration, h, seed, || pb.inc(1));
    pb.finish_and_clear();
    let (s, _) = result?;
    if !json {
        out!(
            "{} simulations of {} s (h = {} s) on {} threads: {:.3} s wall, {:.1} simulations/s, {:.3e} steps/s",
            s.sims, s.duration, s.h, s.threads, s.wall_s, s.sims_per_s, s.steps_per_s
        );
        out!(
            "trolley end position {:.4} +- {:.4} m (1 sigma); stopped at the end: {:.1} %",
            s.y_final_mean,
            s.y_final_std,
            100.0 * s.at_rest
        );
    }
    Ok(s)
}

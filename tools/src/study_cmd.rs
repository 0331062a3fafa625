//! `crane study` and `crane mc`.

use anyhow::{Context, Result};
use crane_tools::cases::Case;
use crane_tools::{figures, montecarlo, study};
use std::path::Path;

/// `crane study`: both cases, the table (or JSON), the figures and `study.json` in `out`.
pub fn study(out: &Path, json: bool, quick: bool, budget: f64) -> Result<()> {
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
    std::fs::create_dir_all(out).with_context(|| format!("create {}", out.display()))?;
    let js = serde_json::to_string_pretty(&reports)?;
    let jpath = out.join("study.json");
    std::fs::write(&jpath, &js).with_context(|| format!("write {}", jpath.display()))?;
    let figs = figures::write(out, &d1, &d2)?;
    if json {
        println!("{js}");
    } else {
        print!("{}", study::table(&reports));
        println!();
        println!(
            "ode45: rtol {}, atol {}; reference: hybrid at h / {}; times: fastest of repeated runs, one thread",
            opts.ode.rtol, opts.ode.atol, opts.ref_div
        );
        for f in figs.iter().chain([&jpath]) {
            println!("wrote {}", f.display());
        }
    }
    Ok(())
}

/// `crane mc`: a Monte Carlo batch on all cores.
pub fn mc(sims: usize, duration: f64, h: f64, seed: u64, json: bool) -> Result<()> {
    let (s, _) = montecarlo::run(sims, duration, h, seed)?;
    if json {
        println!("{}", serde_json::to_string_pretty(&s)?);
    } else {
        println!(
            "{} simulations of {} s (h = {} s) on {} threads: {:.3} s wall, {:.1} simulations/s, {:.3e} steps/s",
            s.sims, s.duration, s.h, s.threads, s.wall_s, s.sims_per_s, s.steps_per_s
        );
        println!(
            "trolley end position {:.4} +- {:.4} m (1 sigma); stopped at the end: {:.1} %",
            s.y_final_mean,
            s.y_final_std,
            100.0 * s.at_rest
        );
    }
    Ok(())
}

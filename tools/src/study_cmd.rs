//! `crane study` and `crane mc`.

use anyhow::{Context, Result};
use crane_tools::cases::Case;
use crane_tools::{figures, montecarlo, study, workprec};
use std::path::Path;

/// `crane study`: both cases, the table (or JSON), the figures and `study.json` in `out`.
pub fn study(out: &Path, json: bool, quick: bool, budget: f64) -> Result<()> {
    let opts = study::Options {
        rk4_search: !quick,
        equal_accuracy: !quick,
        work_precision: !quick,
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
    let mut figs = figures::write(out, &d1, &d2)?;
    for (r, name) in reports.iter().zip(["case1", "case2"]) {
        if r.work_precision.is_empty() {
            continue;
        }
        let p = out.join(format!("{name}_work_precision.svg"));
        let title = format!(
            "{}: work-precision (wall time against velocity RMSE)",
            if name == "case1" { "Case 1" } else { "Case 2" }
        );
        workprec::diagram(&p, &title, &r.work_precision, &r.levels)?;
        figs.push(p);
    }
    if json {
        println!("{js}");
    } else {
        print!("{}", study::table(&reports));
        println!();
        println!(
            "ode45: rtol {}, atol {}; hybrid (default): adaptive DP45 with located events, rtol {:e}, atol {:e} (chosen to reach RMSE {:e} m/s in both cases at the least cost); reference: hybrid at h / {}; times: fastest of repeated runs, one thread",
            opts.ode.rtol,
            opts.ode.atol,
            study::DEFAULT_RTOL,
            study::DEFAULT_RTOL * 1e-2,
            study::STATED_ACCURACY,
            opts.ref_div
        );
        for f in figs.iter().chain([&jpath]) {
            println!("wrote {}", f.display());
        }
    }
    Ok(())
}

/// `crane mc`: a Monte Carlo batch on all cores; fixed step `h` if given, else the adaptive
/// integrator at the study's default tolerance ([`study::DEFAULT_RTOL`]).
pub fn mc(sims: usize, duration: f64, h: Option<f64>, seed: u64, json: bool) -> Result<()> {
    let stepper = match h {
        Some(h) => montecarlo::Stepper::Fixed(h),
        None => montecarlo::Stepper::Adaptive(study::DEFAULT_RTOL),
    };
    let (s, _) = montecarlo::run_with(sims, duration, stepper, seed)?;
    if json {
        println!("{}", serde_json::to_string_pretty(&s)?);
    } else {
        let how = match s.rtol {
            Some(r) => format!("adaptive, rtol {r:e}"),
            None => format!("h = {} s", s.h),
        };
        println!(
            "{} simulations of {} s ({how}) on {} threads: {:.3} s wall, {:.1} simulations/s, {:.3e} steps/s",
            s.sims, s.duration, s.threads, s.wall_s, s.sims_per_s, s.steps_per_s
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

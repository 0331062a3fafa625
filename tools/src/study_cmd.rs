//! `crane study` and `crane mc`.

use anyhow::{bail, Result};
use crane_tools::cases::Case;
use crane_tools::output::Outputs;
use crane_tools::{figures, montecarlo, study, workprec_figure};
use std::path::Path;

/// `crane study`: both cases, the table (or JSON), the figures and `study.json` in `out`
/// (published together at the end, or none).
pub fn study(out: &Path, json: bool, quick: bool, budget: f64, force: bool) -> Result<()> {
    let mut outputs = Outputs::new(force);
    let jpath = out.join("study.json");
    // refuse before minutes of work: the folder (a file there is no folder) and the JSON
    outputs.check_dir(out)?;
    outputs.check(&jpath)?;
    let opts = study::Options {
        work_precision: !quick,
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
    outputs.stage(&jpath, &js)?;
    let mut figs = figures::write(out, &d1, &d2, &mut outputs)?;
    for (r, name) in reports.iter().zip(["case1", "case2"]) {
        if r.work_precision.is_empty() {
            continue;
        }
        let p = out.join(format!("{name}_work_precision.svg"));
        let title = format!(
            "{}: work-precision (wall time against velocity RMSE)",
            if name == "case1" { "Case 1" } else { "Case 2" }
        );
        workprec_figure::diagram(&p, &title, &r.work_precision, &r.levels, &mut outputs)?;
        figs.push(p);
    }
    // the figures and study.json together, or none of them
    outputs.commit()?;
    if json {
        out!("{js}");
    } else {
        out!("{}", study::table(&reports));
        out!(
            "ode45: rtol {}, atol {}; hybrid (default): adaptive DP45 with located events, rtol {:e}, atol {:e} (chosen to reach RMSE {:e} m/s in both cases at the least cost); reference: hybrid at h / {}; times: fastest of repeated runs, one thread",
            opts.ode.rtol,
            opts.ode.atol,
            study::DEFAULT_RTOL,
            study::DEFAULT_RTOL * 1e-2,
            study::STATED_ACCURACY,
            opts.ref_div
        );
        for f in figs.iter().chain([&jpath]) {
            out!("wrote {}", f.display());
        }
    }
    Ok(())
}

/// Most model steps one simulation of `crane mc` may take.
pub const MAX_STEPS: f64 = 1e8;

/// Longest estimated wall time `crane mc` starts without `--yes` [s].
pub const MAX_WALL_S: f64 = 3600.0;

/// Simulated time of the pilot simulation that prices a Monte Carlo run [s].
pub const PILOT_S: f64 = 2.0;

/// Estimated wall time of `sims` simulations of `duration` s [s]: one pilot simulation of up
/// to [`PILOT_S`] s timed, scaled to the duration, times the simulations per thread.
fn estimate_wall_s(
    sims: usize,
    duration: f64,
    stepper: montecarlo::Stepper,
    seed: u64,
) -> Result<f64> {
    let pilot = duration.min(PILOT_S);
    let t0 = std::time::Instant::now();
    montecarlo::run_with_progress(1, pilot, stepper, seed, || {})?;
    let per_sim = t0.elapsed().as_secs_f64() * duration / pilot;
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    Ok(per_sim * sims.div_ceil(threads) as f64)
}

/// `crane mc`: a Monte Carlo batch on all cores.
/// Fixed step `h` if given (at most [`MAX_STEPS`] per simulation), else the adaptive
/// integrator at the study's default tolerance ([`study::DEFAULT_RTOL`]).
/// Refused without `yes` when the estimated wall time exceeds [`MAX_WALL_S`].
pub fn mc(
    sims: u64,
    duration: f64,
    h: Option<f64>,
    seed: u64,
    yes: bool,
    json: bool,
) -> Result<montecarlo::Summary> {
    let stepper = match h {
        Some(h) => {
            let steps = (duration / h).round();
            if steps > MAX_STEPS {
                bail!("--duration {duration} / --h {h} = {steps:e} steps per simulation; at most {MAX_STEPS:e}");
            }
            if steps < 1.0 {
                bail!("--duration {duration} is shorter than one step --h {h}");
            }
            montecarlo::Stepper::Fixed(h)
        }
        None => montecarlo::Stepper::Adaptive(study::DEFAULT_RTOL),
    };
    let sims = usize::try_from(sims)?;
    if !yes {
        let est = estimate_wall_s(sims, duration, stepper, seed)?;
        if est > MAX_WALL_S {
            bail!(
                "{sims} simulations of {duration} s would take about {:.1} h on this machine \
                 (a pilot simulation measured); pass --yes to run them anyway, or ask for fewer",
                est / 3600.0
            );
        }
    }
    // progress on stderr; indicatif draws nothing when stderr is not a terminal
    let pb = indicatif::ProgressBar::new(sims as u64);
    pb.set_style(
        indicatif::ProgressStyle::with_template(
            "mc {bar:40} {pos}/{len} simulations {elapsed} (eta {eta})",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let result = montecarlo::run_with_progress(sims, duration, stepper, seed, || pb.inc(1));
    pb.finish_and_clear();
    let (s, _) = result?;
    if !json {
        let how = match s.rtol {
            Some(r) => format!("adaptive, rtol {r:e}"),
            None => format!("h = {} s", s.h),
        };
        out!(
            "{} simulations of {} s ({how}) on {} threads: {:.3} s wall, {:.1} simulations/s, {:.3e} steps/s",
            s.sims, s.duration, s.threads, s.wall_s, s.sims_per_s, s.steps_per_s
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

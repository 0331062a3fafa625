//! The `crane` command line: the virtual rig, identification, validation and the
//! discrepancy workbench, with built-in defaults so `crane demo` runs the whole story; the
//! paper's simulation study (`crane study`) and Monte Carlo throughput (`crane mc`).

/// `println!` that returns the error (a closed pipe, `crane ... | head`) instead of
/// panicking; `main` ends quietly on a broken pipe.
macro_rules! out {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        writeln!(std::io::stdout().lock(), $($arg)*)?
    }};
}

mod plot;
mod simulate;
mod story;
mod study_cmd;

use anyhow::Result;
use clap::{Parser, Subcommand};
use serde::Serialize;
use std::path::PathBuf;

/// A clap value parser for a finite `f64` in `(lo, hi]` (`lo` excluded).
fn within(lo: f64, hi: f64) -> impl Fn(&str) -> Result<f64> + Clone + Send + Sync + 'static {
    move |s: &str| {
        let v: f64 = s
            .trim()
            .parse()
            .map_err(|e| anyhow::anyhow!("`{s}` is not a number ({e})"))?;
        if !(v.is_finite() && v > lo && v <= hi) {
            anyhow::bail!(
                "{} is outside the plausible range ({lo}, {hi}]",
                crane_ident::num::Num(v)
            );
        }
        Ok(v)
    }
}

/// The clap value parser of `crane monitor --period-s`: a control period [s] in
/// `crane_tools::monitor::PERIOD_S_RANGE` (both ends included).
fn period_s(s: &str) -> Result<f64> {
    let (lo, hi) = crane_tools::monitor::PERIOD_S_RANGE;
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|e| anyhow::anyhow!("`{s}` is not a number ({e})"))?;
    if !(v >= lo && v <= hi) {
        anyhow::bail!(
            "{} s is outside the plausible range [{lo:e}, {hi}] s",
            crane_ident::num::Num(v)
        );
    }
    Ok(v)
}

/// Prints `value` as the command's one JSON document on stdout.
fn emit<T: Serialize>(value: &T) -> Result<()> {
    out!("{}", serde_json::to_string_pretty(value)?);
    Ok(())
}

/// Whether `e` comes from writing to a closed pipe.
fn broken_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}

/// Hybrid friction model of an overhead crane: virtual rig, identification, validation,
/// diagnosis.
#[derive(Parser)]
#[command(name = "crane", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Whole story on built-in defaults: rig experiments, identification, validation table
    /// and plots, into one output directory.
    Demo {
        /// Output directory: `OUT/dataset`, `OUT/params.toml`, `OUT/plots` (with the default
        /// `out`, `crane validate` then runs on the demo's results).
        #[arg(long, default_value = "out")]
        out: PathBuf,
        /// Replace a data set in `OUT/dataset` that the virtual rig did not write.
        #[arg(long)]
        force: bool,
        /// Print machine-readable results (JSON) instead of tables.
        #[arg(long)]
        json: bool,
    },
    /// Run the virtual rig's experiments into a data set directory.
    Rig {
        /// Data set directory to write.
        #[arg(long, default_value = "out/dataset")]
        out: PathBuf,
        /// Random seed of the rig's noise.
        #[arg(long)]
        seed: Option<u64>,
        /// Replace an existing, non-empty directory (an existing data set).
        #[arg(long)]
        force: bool,
        /// Print machine-readable results (JSON).
        #[arg(long)]
        json: bool,
    },
    /// Identify every parameter from a data set; writes a parameter file (TOML).
    Identify {
        /// Data set directory.
        #[arg(default_value = "out/dataset")]
        dataset: PathBuf,
        /// Parameter file to write.
        #[arg(long, default_value = "out/params.toml")]
        out: PathBuf,
        /// Directory for the friction plots with their 95 % bands (SVG).
        #[arg(long, default_value = "out/plots")]
        plots: PathBuf,
        /// Let the outputs replace an input or a file of a data set.
        #[arg(long)]
        force: bool,
        /// Print machine-readable results (JSON).
        #[arg(long)]
        json: bool,
    },
    /// Simulate the validation runs of a data set with a parameter file: NMAE table and plots.
    Validate {
        /// Data set directory.
        #[arg(default_value = "out/dataset")]
        dataset: PathBuf,
        /// Parameter file (TOML, as written by `identify`).
        #[arg(long, default_value = "out/params.toml")]
        params: PathBuf,
        /// Directory for the plots (SVG).
        #[arg(long, default_value = "out/plots")]
        plots: PathBuf,
        /// Let the outputs replace an input or a file of a data set.
        #[arg(long)]
        force: bool,
        /// Print machine-readable results (JSON).
        #[arg(long)]
        json: bool,
    },
    /// Simulate a scenario file (TOML; default: the validation multisine) into a CSV run.
    Simulate {
        /// Scenario file (TOML; every field is documented in the example
        /// `examples/scenarios/step.toml` of the repository); default: built in (the
        /// validation multisine).
        scenario: Option<PathBuf>,
        /// CSV file to write (the plot goes beside it, same name with `.svg`).
        #[arg(long, default_value = "out/simulation.csv")]
        out: PathBuf,
        /// Let the outputs replace an input or a file of a data set.
        #[arg(long)]
        force: bool,
        /// Print machine-readable results (JSON).
        #[arg(long)]
        json: bool,
    },
    #[command(allow_negative_numbers = true)]
    /// The paper's simulation study: wall time and velocity RMSE of the hybrid model and of
    /// tanh(gamma v) friction (ode45 and fixed-step RK4) in its two cases, against a
    /// high-accuracy hybrid reference; the paper's table and its two figures (SVG).
    Study {
        /// Output directory (figures, study.json).
        #[arg(long, default_value = "out")]
        out: PathBuf,
        /// Print machine-readable results (JSON) instead of the table.
        #[arg(long)]
        json: bool,
        /// Skip the fixed-step RK4 search and the hybrid equal-accuracy search (faster).
        #[arg(long)]
        quick: bool,
        /// Wall-time budget per timed model [s] (runs repeated, fastest reported), in
        /// (0, 600].
        #[arg(long, default_value_t = 0.3, value_parser = within(0.0, 600.0))]
        budget: f64,
        /// Let the outputs replace an input or a file of a data set.
        #[arg(long)]
        force: bool,
    },
    #[command(allow_negative_numbers = true)]
    /// Monte Carlo over friction uncertainty (case 1, trolley friction +-30 %) on all cores:
    /// throughput and the spread of the trolley's end position.
    Mc {
        /// Number of simulations, 1..=10000000.
        #[arg(long, default_value_t = 1000, value_parser = clap::value_parser!(u64).range(1..=10_000_000))]
        sims: u64,
        /// Simulated time of each [s], in (0, 3600].
        #[arg(long, default_value_t = 10.0, value_parser = within(0.0, 3600.0))]
        duration: f64,
        /// Fixed model step [s], in (0, 0.1] (at most 1e8 steps per simulation); default: the
        /// adaptive integrator at rtol 1e-7 (the setting that reaches 1e-6 m/s at the least
        /// cost, BENCHMARKS.md).
        #[arg(long, value_parser = within(0.0, 0.1))]
        h: Option<f64>,
        /// Seed.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Run even when the estimated wall time exceeds an hour.
        #[arg(long)]
        yes: bool,
        /// Print machine-readable results (JSON).
        #[arg(long)]
        json: bool,
    },
    /// Find what the simulation gets wrong on measured data, name the cause, extend the model
    /// and measure the gain on held-out data.
    Diagnose {
        /// Data set directory (crane or single-axis runs); required (`crane diagnose --json
        /// DIR` with no other folder takes DIR as the data set, the report on stdout).
        dataset: Option<PathBuf>,
        /// Baseline parameter file (crane data); default: the built-in parameters.
        #[arg(long)]
        params: Option<PathBuf>,
        /// Fit the paper's friction structure as the baseline first (crane data too).
        #[arg(long)]
        fit_baseline: bool,
        /// Single-axis data: start from the symmetric Coulomb + viscous model
        /// `M qdd + Fv qd + Fc sign(qd)` instead of the paper's structure (the EMPS story).
        #[arg(long, conflicts_with_all = ["params", "fit_baseline"])]
        symmetric: bool,
        /// Also write the report (JSON) to this file.
        #[arg(long)]
        report: Option<PathBuf>,
        /// Directory for residual plots (SVG).
        #[arg(long)]
        plots: Option<PathBuf>,
        /// Let the outputs replace an input or a file of a data set.
        #[arg(long)]
        force: bool,
        /// The report (JSON): `--json` prints it on stdout instead of the text summary (as
        /// every command's `--json`); `--json FILE` writes it to FILE like `--report FILE`.
        #[arg(long, value_name = "FILE", num_args = 0..=1)]
        json: Option<Option<PathBuf>>,
    },
    /// Decode the friction monitor's frames (MALARM, MSUM, MMAP) in a firmware log: its alarms
    /// and last friction maps as a table, a JSON report and a plot (SVG).
    Monitor {
        /// The UART / semihosting log (text; lines that are not monitor frames are ignored).
        log: PathBuf,
        /// Output directory: `DIR/monitor.json` and `DIR/monitor.svg` (unless `--json FILE`
        /// or `--plot FILE` name them).
        #[arg(long, value_name = "DIR")]
        out: Option<PathBuf>,
        /// The report (JSON): `--json` prints it on stdout instead of the table (as every
        /// command's `--json`); `--json FILE` writes it to FILE.
        #[arg(long, value_name = "FILE", num_args = 0..=1)]
        json: Option<Option<PathBuf>>,
        /// Plot (SVG) of the last friction maps of the log's last section against position.
        #[arg(long, value_name = "FILE.svg")]
        plot: Option<PathBuf>,
        /// Control period of the firmware [s] (time = period index * T), in [1e-5, 1].
        #[arg(long, value_name = "T", default_value_t = crane_tools::monitor::PERIOD_S,
              value_parser = period_s)]
        period_s: f64,
    },
}

/// The data set of `crane diagnose` and its `--json`: `crane diagnose --json DIR` without a
/// data set took DIR as the report file and then found no data set; a folder there is the
/// data set, with the report on stdout. Without any data set: the usage error (exit 2).
fn diagnose_dataset(
    dataset: Option<PathBuf>,
    json: Option<Option<PathBuf>>,
) -> (PathBuf, Option<Option<PathBuf>>) {
    match (dataset, json) {
        (Some(d), j) => (d, j),
        (None, Some(Some(dir))) if dir.is_dir() => (dir, Some(None)),
        (None, _) => {
            use clap::CommandFactory;
            let root = Cli::command();
            let mut usage = root
                .find_subcommand("diagnose")
                .cloned()
                .unwrap_or_else(|| root.clone())
                .bin_name("crane diagnose");
            usage
                .error(
                    clap::error::ErrorKind::MissingRequiredArgument,
                    "the data set folder was not given: crane diagnose DATASET [OPTIONS]",
                )
                .exit()
        }
    }
}

/// `crane monitor`: decodes the log, writes the report and the plot, prints the table (or
/// the report with a bare `--json`).
fn monitor(
    log: PathBuf,
    out: Option<PathBuf>,
    json: Option<Option<PathBuf>>,
    plot: Option<PathBuf>,
    period_s: f64,
) -> Result<()> {
    use crane_tools::monitor::{self, Request};
    let (stdout, json) = match json {
        Some(Some(file)) => (false, Some(file)),
        Some(None) => (true, None),
        None => (false, None),
    };
    let req = Request {
        log,
        out,
        json,
        plot,
        period_s,
    };
    let done = monitor::run(&req)?;
    if stdout {
        return emit(&done.report);
    }
    out!("{}", monitor::report::table(&done.report).trim_end());
    for p in &done.written {
        out!("wrote {}", p.display());
    }
    Ok(())
}

fn run(command: Command) -> Result<()> {
    match command {
        Command::Demo { out, force, json } => {
            let r = story::demo(&out, force, json)?;
            if json {
                emit(&r)?;
            }
        }
        Command::Rig {
            out,
            seed,
            force,
            json,
        } => {
            let r = story::rig(&out, seed, force, json)?;
            if json {
                emit(&r)?;
            }
        }
        Command::Identify {
            dataset,
            out,
            plots,
            force,
            json,
        } => {
            let r = story::identify(&dataset, &out, &plots, force, json)?;
            if json {
                emit(&r)?;
            }
        }
        Command::Validate {
            dataset,
            params,
            plots,
            force,
            json,
        } => {
            let r = story::validate(&dataset, &params, &plots, force, json)?;
            if json {
                emit(&r)?;
            }
        }
        Command::Simulate {
            scenario,
            out,
            force,
            json,
        } => {
            let r = simulate::simulate(scenario.as_deref(), &out, force, json)?;
            if json {
                emit(&r)?;
            }
        }
        Command::Study {
            out,
            json,
            quick,
            budget,
            force,
        } => study_cmd::study(&out, json, quick, budget, force)?,
        Command::Mc {
            sims,
            duration,
            h,
            seed,
            yes,
            json,
        } => {
            let s = study_cmd::mc(sims, duration, h, seed, yes, json)?;
            if json {
                emit(&s)?;
            }
        }
        Command::Diagnose {
            dataset,
            params,
            fit_baseline,
            symmetric,
            report,
            plots,
            force,
            json,
        } => {
            let (dataset, json) = diagnose_dataset(dataset, json);
            // `--json FILE` is `--report FILE`; a bare `--json` prints the report on stdout
            let (json, report) = match json {
                Some(Some(file)) if report.is_none() => (false, Some(file)),
                Some(Some(_)) => {
                    anyhow::bail!("give the report file once: `--json FILE` or `--report FILE`")
                }
                Some(None) => (true, report),
                None => (false, report),
            };
            story::diagnose(
                &dataset,
                params.as_deref(),
                fit_baseline,
                symmetric,
                report.as_deref(),
                plots,
                force,
                json,
            )?
        }
        Command::Monitor {
            log,
            out,
            json,
            plot,
            period_s,
        } => monitor(log, out, json, plot, period_s)?,
    }
    Ok(())
}

/// `e` and its causes as one line, each cause once: a cause whose text an outer message
/// already holds (a library error that prints its source, then the source itself) is not
/// repeated.
fn message(e: &anyhow::Error) -> String {
    let mut line = String::new();
    for cause in e.chain() {
        let text = cause.to_string();
        if text.is_empty() || line.contains(&text) {
            continue;
        }
        if !line.is_empty() {
            line.push_str(": ");
        }
        line.push_str(&text);
    }
    line
}

/// Held by whoever ends the process: the interrupt handler while it removes the
/// temporaries, `main` before it reports an error or returns. So the main thread, whose
/// outputs vanish under it, cannot end the process (or print an error about them) in the
/// middle of the handler's clean-up.
static EXIT: std::sync::Mutex<()> = std::sync::Mutex::new(());

fn main() {
    // Ctrl-C, SIGTERM, SIGHUP: the temporary files and scratch folders of unfinished outputs
    // go before the exit, so an interrupted command leaves its outputs as they were (if no
    // handler can be set, a signal ends the process as before)
    let _ = ctrlc::set_handler(|| {
        let _end = EXIT.lock();
        crane_ident::atomic::remove_pending();
        std::process::exit(130);
    });
    let cli = Cli::parse();
    let result = run(cli.command);
    let _end = EXIT.lock();
    if let Err(e) = result {
        if broken_pipe(&e) {
            // `crane ... | head`: the reader has what it wanted
            std::process::exit(0);
        }
        eprintln!("crane: error: {}", message(&e));
        std::process::exit(1);
    }
}

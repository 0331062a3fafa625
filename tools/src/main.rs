//! The `crane` command line: the virtual rig, identification, validation and the
//! discrepancy workbench, with built-in defaults so `crane demo` runs the whole story; the
//! paper's simulation study (`crane study`) and Monte Carlo throughput (`crane mc`).

mod plot;
mod simulate;
mod story;
mod study_cmd;

use clap::{Parser, Subcommand};
use std::path::PathBuf;

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
        /// Output directory.
        #[arg(long, default_value = "out/demo")]
        out: PathBuf,
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
        /// Print machine-readable results (JSON).
        #[arg(long)]
        json: bool,
    },
    /// Simulate a scenario file (TOML; default: the validation multisine) into a CSV run.
    Simulate {
        /// Scenario file (see `tools/src/simulate.rs` for the format); default: built in.
        scenario: Option<PathBuf>,
        /// CSV file to write.
        #[arg(long, default_value = "out/simulation.csv")]
        out: PathBuf,
        /// Print machine-readable results (JSON).
        #[arg(long)]
        json: bool,
    },
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
        /// Wall-time budget per timed model [s] (runs repeated, fastest reported).
        #[arg(long, default_value_t = 0.3)]
        budget: f64,
    },
    /// Monte Carlo over friction uncertainty (case 1, trolley friction +-30 %) on all cores:
    /// throughput and the spread of the trolley's end position.
    Mc {
        /// Number of simulations.
        #[arg(long, default_value_t = 1000)]
        sims: usize,
        /// Simulated time of each [s].
        #[arg(long, default_value_t = 10.0)]
        duration: f64,
        /// Fixed model step [s]; default: the adaptive integrator at rtol 1e-7 (the setting
        /// that reaches 1e-6 m/s at the least cost, BENCHMARKS.md).
        #[arg(long)]
        h: Option<f64>,
        /// Seed.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Print machine-readable results (JSON).
        #[arg(long)]
        json: bool,
    },
    /// Find what the simulation gets wrong on measured data, name the cause, extend the model
    /// and measure the gain on held-out data.
    Diagnose {
        /// Data set directory (crane or single-axis runs).
        dataset: PathBuf,
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
        /// Write the report here (JSON).
        #[arg(long)]
        json: Option<PathBuf>,
        /// Directory for residual plots (SVG).
        #[arg(long)]
        plots: Option<PathBuf>,
    },
}

fn main() {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Demo { out, json } => story::demo(&out, json),
        Command::Rig { out, seed, json } => story::rig(&out, seed, json).map(|_| ()),
        Command::Identify {
            dataset,
            out,
            plots,
            json,
        } => story::identify(&dataset, &out, &plots, json).map(|_| ()),
        Command::Validate {
            dataset,
            params,
            plots,
            json,
        } => story::validate(&dataset, &params, &plots, json).map(|_| ()),
        Command::Simulate {
            scenario,
            out,
            json,
        } => simulate::simulate(scenario.as_deref(), &out, json).map(|_| ()),
        Command::Study {
            out,
            json,
            quick,
            budget,
        } => study_cmd::study(&out, json, quick, budget),
        Command::Mc {
            sims,
            duration,
            h,
            seed,
            json,
        } => study_cmd::mc(sims, duration, h, seed, json),
        Command::Diagnose {
            dataset,
            params,
            fit_baseline,
            symmetric,
            json,
            plots,
        } => story::diagnose(
            &dataset,
            params.as_deref(),
            fit_baseline,
            symmetric,
            json.as_deref(),
            plots,
        ),
    };
    if let Err(e) = result {
        eprintln!("crane: error: {e:#}");
        std::process::exit(1);
    }
}

//! The `crane` command line: the virtual rig, identification, validation and the
//! discrepancy workbench, with built-in defaults so `crane demo` runs the whole story.

mod plot;
mod story;

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
        Command::Identify { dataset, out, json } => {
            story::identify(&dataset, &out, json).map(|_| ())
        }
        Command::Validate {
            dataset,
            params,
            plots,
            json,
        } => story::validate(&dataset, &params, &plots, json).map(|_| ()),
        Command::Diagnose {
            dataset,
            params,
            fit_baseline,
            json,
            plots,
        } => story::diagnose(
            &dataset,
            params.as_deref(),
            fit_baseline,
            json.as_deref(),
            plots,
        ),
    };
    if let Err(e) = result {
        eprintln!("crane: error: {e:#}");
        std::process::exit(1);
    }
}

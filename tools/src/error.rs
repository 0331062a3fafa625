//! The error type of the library part of `crane-tools` (the binary wraps it in `anyhow`).

use std::path::PathBuf;

/// Why a study, a Monte Carlo batch or a figure failed.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A fixed step that does not fit the output grid.
    #[error("step {h} s {why} the output grid {sample} s")]
    Grid {
        /// The step [s].
        h: f64,
        /// The output grid [s].
        sample: f64,
        /// "does not divide" or "is not a multiple of".
        why: &'static str,
    },
    /// The model refused the case's parameters, step or initial state (the field is named).
    #[error("{what}: {error}")]
    Setup {
        /// Which model.
        what: &'static str,
        /// The model's error.
        error: crane_model::Error,
    },
    /// The model rejected a step.
    #[error("{what} at t = {t} s: {error}")]
    Step {
        /// Which model.
        what: &'static str,
        /// Time of the step [s].
        t: f64,
        /// The model's error.
        error: crane_model::StepError,
    },
    /// The adaptive hybrid integrator stopped (`crane_model::adaptive`).
    #[error("{what} at t = {t} s: {error}")]
    Adaptive {
        /// Which run.
        what: &'static str,
        /// Time reached [s].
        t: f64,
        /// The integrator's reason.
        error: crane_model::adaptive::AdaptiveError,
    },
    /// The adaptive integrator kept no dense output for its last step (an internal error).
    #[error("adaptive hybrid at t = {t} s: no dense output of the last step")]
    NoDenseOutput {
        /// Time reached [s].
        t: f64,
    },
    /// The Rosenbrock (ode23s) solver stopped early on a `tanh` model.
    #[error("Rosenbrock, tanh({gamma} v): {failure}")]
    Rosenbrock {
        /// The slope factor [s/m].
        gamma: f64,
        /// Why.
        failure: String,
    },
    /// The BDF solver ([`crate::bdf`], `diffsol`) stopped early on a `tanh` model.
    #[error("BDF, tanh({gamma} v): {failure}")]
    Bdf {
        /// The slope factor [s/m].
        gamma: f64,
        /// Why.
        failure: crate::bdf::Failure,
    },
    /// ode45 stopped early on a `tanh` model.
    #[error("ode45, tanh({gamma} v): {failure}")]
    Ode45 {
        /// The slope factor [s/m].
        gamma: f64,
        /// Why.
        failure: crate::ode45::Failure,
    },
    /// Fixed-step RK4 failed on a `tanh` model.
    #[error("RK4, tanh({gamma} v): singular or not finite at t = {t} s")]
    Rk4 {
        /// The slope factor [s/m].
        gamma: f64,
        /// Time [s].
        t: f64,
    },
    /// Drawing a figure failed.
    #[error("plot {}: {message}", path.display())]
    Plot {
        /// The figure's file.
        path: PathBuf,
        /// plotters' message.
        message: String,
    },
    /// Writing an output failed or was refused.
    #[error(transparent)]
    Output(#[from] crate::output::OutputError),
}

/// `Result` with [`Error`].
pub type Result<T> = std::result::Result<T, Error>;

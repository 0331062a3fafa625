//! # crane-ident
//!
//! Identification of the hybrid crane model of `crane-model` (the paper's parameter
//! estimation), a virtual rig that records experiments as the INTECO rig would, and the
//! data format both share (`DATA_FORMAT.md`).
//!
//! - [`data`]: runs (CSV) and data sets (`dataset.toml`), loading with located errors;
//!   single-axis units and gain, declared controllers, time-stamp checks and zero-order-hold
//!   resampling of asynchronous logs.
//! - [`signal`]: Butterworth / Chebyshev filters, `filtfilt`, `decimate` (per run:
//!   `decimate_each`), differences; no panic on short runs or slow sampling.
//! - [`linalg`]: least squares with standard errors and correlations.
//! - [`emps`]: the EMPS benchmark's inverse-dynamics least squares (IDIM-LS).
//! - [`rig`]: the virtual rig (quantised encoders, ZOH saturated voltages, noise, an effect
//!   hook) and the [`rig::Rig`] trait a real rig could implement.
//! - [`campaign`]: the paper's experiments against any rig; [`campaign::run_rig`].
//! - [`blr`]: Bayesian linear regression of the dry friction and the active learning.
//! - [`identify`]: the paper's estimation pipeline; [`identify::identify`].
//! - [`validate`]: NMAE of the payload position on validation runs; [`validate::validate`].
//! - [`params_file`]: the model parameters as TOML.
//! - [`shared_data`]: where the real data sets outside the repository are, for the tests
//!   that skip without them.
//! - [`atomic`]: atomic file writes (temporary file + rename), used for every output, and
//!   [`atomic::Transaction`]: the outputs of one command published together or not at all.
//! - [`num`]: numbers in messages, short whatever their magnitude.
//!
//! Entry points for the command line:
//! ```no_run
//! use crane_ident::{campaign, identify, params_file, validate};
//! let dir = std::path::Path::new("dataset");
//! let summary = campaign::run_rig(dir, &campaign::RigOptions::default())?;
//! let id = identify::identify(dir)?;                 // serde: Identified
//! params_file::write(&dir.join("identified.toml"), &id.params)?; // TOML
//! let report = validate::validate(&id.params, dir)?; // serde: ValidationReport
//! println!("{}", report.table());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![forbid(unsafe_code)]
#![deny(missing_docs)]
// Matrix and signal code indexes several arrays with one loop variable; iterator chains
// would hide the formulas.
#![allow(clippy::needless_range_loop)]
// Units are written in brackets, `[m]`, `[N s/m]`: they are not intra-doc links.
#![allow(rustdoc::broken_intra_doc_links)]

pub mod atomic;
pub mod blr;
pub mod campaign;
pub mod data;
pub mod emps;
pub mod identify;
pub mod input;
pub mod linalg;
pub mod num;
pub mod params_file;
pub mod rig;
pub mod rng;
pub mod shared_data;
pub mod signal;
pub mod simulate;
pub mod validate;

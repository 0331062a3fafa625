//! # crane-tools
//!
//! Host tooling around the hybrid crane model (`crane_model`): the simulation study of the
//! paper (hybrid friction against `tanh(gamma v)` smoothing) and its pieces, usable from the
//! `crane` binary, the tests and the benches.
//!
//! - [`error`]: the library's error type ([`error::Error`]).
//! - [`cases`]: the paper's two simulation cases, with every value the paper leaves open fixed.
//! - [`smooth`]: the comparison dynamics (`tanh` friction, axes outside a case held exactly)
//!   and the bare dynamics without friction logic, on the model's own `dynamics::eval`; fixed
//!   step RK4.
//! - [`bdf`]: the stiff peer of the `tanh` models, `diffsol`'s variable-order BDF (and
//!   ESDIRK34) on the same grid and error norm.
//! - [`ode45`]: Dormand-Prince 5(4) with error control and dense output (MATLAB's `ode45`).
//! - [`reference`]: fixed-step hybrid runs, the high-accuracy reference and its convergence
//!   check.
//! - [`study`]: the study itself (wall time and velocity RMSE per model and case, the largest
//!   stable RK4 step, the hybrid step at equal accuracy) and the paper's table.
//! - [`figures`]: the paper's two figures (SVG).
//! - [`monitor`]: `crane monitor LOG`, the friction monitor's frames from a firmware log
//!   decoded into a table, a JSON report and a plot.
//! - [`montecarlo`]: many independent simulations over friction uncertainty on all cores.
//! - [`output`]: where the command line writes: atomic writes that never replace an input or
//!   a data set unless forced.

#![forbid(unsafe_code)]

pub mod adaptive_run;
pub mod bdf;
pub mod cases;
pub mod error;
pub mod figures;
pub mod monitor;
pub mod montecarlo;
pub mod numfmt;
pub mod ode23s;
pub mod ode45;
pub mod output;
pub mod reference;
pub mod smooth;
pub mod study;
pub mod tanh_run;
pub mod timing;
pub mod workprec;
pub mod workprec_figure;

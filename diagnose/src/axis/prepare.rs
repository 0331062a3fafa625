//! Stage 1: the single-axis runs of the data set split into a fitting and a held-out part
//! ([`split_runs`]), each turned into inverse-dynamics rows ([`Part`]), and the baseline's
//! structure chosen from the options.

use super::rows::{append, Part};
use crate::{split_runs, Baseline, DiagnoseError, DiagnoseOptions, FIT_FRACTION};
use crane_ident::data::{Dataset, Run};
use crane_ident::emps::IdimOptions;

/// The data of the diagnosis, ready for the least squares: the single-axis runs and their
/// split, the baseline's structure, and the rows of the fitting and the held-out part.
pub(super) struct Prepared<'a> {
    /// The data set's single-axis runs, in the data set's order.
    pub(super) runs: Vec<&'a Run>,
    /// Per run of `runs`: `Some(true)` held out, `Some(false)` fitted, `None` cut in time
    /// (its first [`FIT_FRACTION`] fitted, the rest held out).
    pub(super) split: Vec<Option<bool>>,
    /// How the runs were split, in words (the report's `split`).
    pub(super) split_doc: String,
    /// The symmetric baseline `M qdd + Fv qd + Fc sign(qd) + offset` (4 columns); else the
    /// paper's structure (13 columns, see `baseline.rs`).
    pub(super) sym: bool,
    /// The baseline in words (the report's `baseline`).
    pub(super) base_doc: String,
    /// Rows of the fitting part (at least 50 decimated rows).
    pub(super) fit: Part,
    /// Rows of the held-out part (at least 50 decimated rows).
    pub(super) held: Part,
    /// Sample period [s] of the last single-axis run (0.001 without one): the unit of the
    /// input-delay grid.
    pub(super) dt: f64,
    /// Force per unit of input [N/V, or N per input unit]: the data set's declared gain, 1
    /// without one (the force is then the input itself). `force / gain` is the input the dead
    /// band acts on.
    pub(super) gain: f64,
}

/// Stage 1: the runs, their split, the baseline's structure and the rows of both parts.
/// Errors: a crane parameter file as the baseline; fewer than 50 decimated rows in either
/// part ("too few single-axis samples").
pub(super) fn prepare<'a>(
    ds: &'a Dataset,
    opts: &DiagnoseOptions,
) -> Result<Prepared<'a>, DiagnoseError> {
    let runs: Vec<_> = ds.runs.iter().filter(|r| r.axis().is_some()).collect();
    let kinds: Vec<_> = runs.iter().map(|r| r.kind).collect();
    let (split, split_doc) = split_runs(&kinds);
    let (sym, base_doc) = structure(&opts.baseline)?;
    let (fit, held, dt) = rows(&runs, &split);
    if fit.f.len() < 50 || held.f.len() < 50 {
        return Err(DiagnoseError::Input("too few single-axis samples".into()));
    }
    let gain = ds.runs.first().and(ds.spec.gain_n_per_v).unwrap_or(1.0);
    Ok(Prepared {
        runs,
        split,
        split_doc,
        sym,
        base_doc,
        fit,
        held,
        dt,
        gain,
    })
}

/// The baseline's structure: `true` for the symmetric model, and the baseline in words.
/// Crane parameters (`--params`) are refused.
fn structure(baseline: &Baseline) -> Result<(bool, String), DiagnoseError> {
    Ok(match baseline {
        Baseline::Symmetric => (
            true,
            "symmetric Coulomb + viscous `M qdd + Fv qd + Fc sign(qd)` fitted on the fitting part"
                .to_string(),
        ),
        Baseline::Params(_) => {
            return Err(DiagnoseError::Input(
                "crane parameters cannot be the baseline of single-axis data".into(),
            ))
        }
        _ => (
            false,
            "the paper's structure fitted on the fitting part: inertia, viscous per direction, dry friction per direction as a quartic in position".to_string(),
        ),
    })
}

/// The rows of the fitting and the held-out part, and the sample period [s] of the last run
/// (0.001 without one). Each run is processed with the filter cut-off at a tenth of its own
/// sampling rate; a run split in time gives its first [`FIT_FRACTION`] of samples to the
/// fitting part and the rest to the held-out part.
fn rows(runs: &[&Run], split: &[Option<bool>]) -> (Part, Part, f64) {
    let mut fit = Part::default();
    let mut held = Part::default();
    let mut dt = 0.001;
    for (r, s) in runs.iter().zip(split) {
        let Some(a) = r.axis() else { continue };
        dt = a.dt();
        let opt = IdimOptions {
            cutoff_hz: 0.1 / dt,
            ..IdimOptions::default()
        };
        let n = a.t.len();
        match s {
            Some(true) => append(&mut held, a, 0..n, &opt),
            Some(false) => append(&mut fit, a, 0..n, &opt),
            None => {
                let cut = (FIT_FRACTION * n as f64) as usize;
                append(&mut fit, a, 0..cut, &opt);
                append(&mut held, a, cut..n, &opt);
            }
        }
    }
    (fit, held, dt)
}

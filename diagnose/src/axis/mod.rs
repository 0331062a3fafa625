//! The single-axis pipeline (EMPS-like data): inverse-dynamics least squares of the baseline
//! and of every candidate extension on the fitting part, scored on the held-out part.
//!
//! Processing is the EMPS benchmark's IDIM-LS: zero-phase Butterworth (order 4, cut-off a tenth
//! of the sampling rate: 100 Hz at 1 kHz), central differences, 49 samples dropped, every
//! column and the force decimated by 10. The measure is the force: `nmae_*` is the mean absolute
//! force error over the held-out force range [%], and the published relative force error
//! `100 ||F - F_model|| / ||F||` is reported in `measures`.
//!
//! Stages (one file each), run in this order by [`diagnose_axis`]:
//! 1. `prepare.rs`: the single-axis runs split into a fitting and a held-out part, each turned
//!    into inverse-dynamics rows (`rows.rs`: filtered, differentiated, decimated, rests cut
//!    out), and the baseline's structure chosen.
//! 2. `baseline.rs`: the baseline fitted on the fitting rows and scored on the held-out rows.
//! 3. `search.rs`: every candidate extension searched on the fitting rows: the friction
//!    shapes (`friction.rs`) and the input's delay and dead band (`input.rs`), gathered in
//!    `candidates.rs`.
//! 4. `score.rs`: candidates ranked by their held-out force BIC change, each with the
//!    bootstrap lower bound of its held-out cut (`bootstrap.rs`).
//! 5. `select.rs`: the support rule: the findings and the list of candidates.
//! 6. `report.rs`: the force-error measures, the closed-loop simulation measures
//!    (`closed_loop.rs`), the verdict and the report.

mod baseline;
mod bootstrap;
mod candidates;
mod closed_loop;
mod friction;
mod input;
mod prepare;
mod report;
mod rows;
mod score;
mod search;
mod select;

pub use bootstrap::{BOOT_BLOCKS, BOOT_LEVEL, BOOT_REPS};
pub use rows::REST_MIN_S;
pub use select::{FORCE_BIC_MAX, MIN_CUT};

use crate::{DiagnoseError, DiagnoseOptions, Report};
use crane_ident::data::Dataset;

/// Diagnoses single-axis runs.
pub fn diagnose_axis(ds: &Dataset, opts: &DiagnoseOptions) -> Result<Report, DiagnoseError> {
    let prep = prepare::prepare(ds, opts)?;
    let base = baseline::fit_baseline(&prep)?;
    let found = search::search(&prep, &base);
    let scored = score::score(found.offered, &prep, &base);
    let unfitted = found.not_physical.into_iter().chain(found.not_ident);
    let mut sel = select::select(&scored, unfitted, &base, prep.held.f.len());
    report::force_error_measures(&base, &scored, &mut sel.measures);
    if closed_loop::closed_loop_measures(ds, &prep.runs, &prep.split, opts, &mut sel.measures)? {
        report::published_measures(&mut sel.measures);
    }
    Ok(report::report(ds, prep, &base, sel))
}

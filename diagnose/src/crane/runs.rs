//! The first stage: the crane runs of a data set, their fitting / held-out split, the
//! baseline model (re-fitted when asked) and each run prepared for the force domain.

use super::baseline::{fit_baseline, BaselineChoice};
use super::nmae::{Ctx, Scales};
use super::residual::{prep, Prep};
use crate::{split_runs, DiagnoseError, DiagnoseOptions, FIT_FRACTION};
use crane_ident::data::{Dataset, Run};
use crane_model::Params;

/// What the later stages share: the prepared runs and the baseline they were prepared with.
pub(super) struct Setup<'a> {
    /// The prepared runs with the NMAE scales.
    pub(super) ctx: Ctx<'a>,
    /// Baseline parameters (after the re-fit when `fitted`; payload mass as in the defaults
    /// or the file: each run uses its declared one).
    pub(super) params: Params,
    /// Whether the baseline's dry magnitudes and viscous coefficients were re-fitted.
    pub(super) fitted: bool,
    /// What the baseline is, for the report.
    pub(super) base_doc: String,
    /// How the runs were split, for the report.
    pub(super) split_doc: String,
    /// Encoder quantisation NMAE per axis [%] ([`Scales::noise`]).
    pub(super) noise: [f64; 3],
    /// Names of the crane runs, in the order of `ctx.preps`.
    pub(super) names: Vec<&'a str>,
}

/// Prepares the crane runs of `ds` against the baseline of `opts`; an input error for a
/// baseline crane data cannot have.
pub(super) fn prepare<'a>(
    ds: &'a Dataset,
    opts: &DiagnoseOptions,
) -> Result<Setup<'a>, DiagnoseError> {
    let runs: Vec<_> = ds.runs.iter().filter(|r| r.crane().is_some()).collect();
    let kinds: Vec<_> = runs.iter().map(|r| r.kind).collect();
    let (split, split_doc) = split_runs(&kinds);
    let BaselineChoice {
        params: mut base,
        fitted,
        doc: base_doc,
    } = BaselineChoice::from_options(opts)?;
    let scales = Scales::from_constants(&ds.spec.constants);
    let mut preps = make_preps(&runs, &split, &base);
    if fitted {
        fit_baseline(&preps, &mut base);
        preps = make_preps(&runs, &split, &base);
    }
    let ctx = Ctx {
        preps,
        ranges: scales.ranges,
        floor: scales.floor,
    };
    let names: Vec<&str> = runs
        .iter()
        .filter(|r| r.crane().is_some())
        .map(|r| r.name.as_str())
        .collect();
    Ok(Setup {
        ctx,
        params: base,
        fitted,
        base_doc,
        split_doc,
        noise: scales.noise,
        names,
    })
}

/// Prepares each crane run with `base` and its declared payload mass [kg] (1 g when it
/// declares none), held out as `split` says (`None`: its last `1 - FIT_FRACTION` of samples).
fn make_preps<'a>(runs: &[&'a Run], split: &[Option<bool>], base: &Params) -> Vec<Prep<'a>> {
    runs.iter()
        .zip(split)
        .filter_map(|(r, s)| {
            let cr = r.crane()?;
            let mut p = *base;
            p.payload_mass = if r.payload_kg > 0.0 {
                r.payload_kg
            } else {
                0.001
            };
            let n = cr.len();
            let held = match s {
                Some(h) => vec![*h; n],
                None => (0..n)
                    .map(|k| k as f64 >= FIT_FRACTION * n as f64)
                    .collect(),
            };
            Some(prep(cr, p, held))
        })
        .collect()
}

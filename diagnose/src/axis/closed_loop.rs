//! Closed-loop force errors of the EMPS benchmark's published models ([`closed_loop_measures`]),
//! beside the inverse-model figures of the report.

use crate::{DiagnoseError, DiagnoseOptions};
use crane_ident::data::Dataset;
use crane_ident::emps::IdimOptions;
use std::collections::BTreeMap;

/// Closed-loop force errors (the EMPS benchmark's simulation measure), when the runs are EMPS
/// recordings (columns `t, qm, qg, vir`, optionally `pulses_N`) split into one fitting run and
/// held-out runs: the symmetric and the direction-dependent IDIM-LS models, fitted on the
/// fitting run only, simulated in closed loop with the rig's controller
/// ([`crane_ident::emps::Controller::default`]) on each run's reference; relative force error
/// `100 ||F - F_sim|| / ||F||` [%], held-out runs pooled by their mean. With a plots directory,
/// writes `closed_loop_force_{fit,held_out}_<run>_vs_{time,position,velocity}.svg`: the force
/// residual `F - F_sim` [N] of the symmetric model (red) and the direction-dependent one (blue).
/// Returns whether the runs were such recordings (the measures were added).
pub(super) fn closed_loop_measures(
    ds: &Dataset,
    runs: &[&crane_ident::data::Run],
    split: &[Option<bool>],
    opts: &DiagnoseOptions,
    measures: &mut BTreeMap<String, f64>,
) -> Result<bool, DiagnoseError> {
    use crane_ident::emps::{
        idim_ls, load_closed_loop, simulate_closed_loop, AxisModel, Controller, IdimModel,
    };
    let fit: Vec<usize> = (0..runs.len())
        .filter(|&i| split[i] == Some(false))
        .collect();
    let held: Vec<usize> = (0..runs.len())
        .filter(|&i| split[i] == Some(true))
        .collect();
    if fit.len() != 1 || held.is_empty() {
        return Ok(false);
    }
    let Some(fit_run) = runs[fit[0]].axis() else {
        return Ok(false);
    };
    let Ok(cl) = runs
        .iter()
        .map(|r| load_closed_loop(&ds.dir.join(&r.name)))
        .collect::<Result<Vec<_>, _>>()
    else {
        return Ok(false);
    };
    let ctl = Controller::default();
    // force residual `F - F_sim` [N] per run, symmetric (index 0) and direction-dependent (1)
    let mut residual: Vec<[Vec<f64>; 2]> = vec![Default::default(); runs.len()];
    for (model, name) in [
        (IdimModel::Symmetric, "symmetric"),
        (IdimModel::DirectionDependent, "direction_dependent"),
    ] {
        let Ok(f) = idim_ls(fit_run, model, &IdimOptions::default()) else {
            continue;
        };
        let Some(m) = AxisModel::from_idim(model, &f.theta) else {
            continue;
        };
        let mut err = vec![0.0; runs.len()];
        for (i, c) in cl.iter().enumerate() {
            let sim = simulate_closed_loop(c, &m, &ctl);
            err[i] = sim.force_err_pct;
            residual[i][(model == IdimModel::DirectionDependent) as usize] = c
                .vir
                .iter()
                .zip(&sim.vir)
                .map(|(a, b)| ctl.gtau * (a - b))
                .collect();
        }
        let e_fit = err[fit[0]];
        let e_held = held.iter().map(|&i| err[i]).sum::<f64>() / held.len() as f64;
        measures.insert(format!("closed_loop_force_err_fit_{name}_pct"), e_fit);
        measures.insert(format!("closed_loop_force_err_held_out_{name}_pct"), e_held);
    }
    if let Some(dir) = &opts.plots_dir {
        let series: Vec<crate::plots::Series> = cl
            .iter()
            .zip(residual)
            .enumerate()
            .map(|(i, (c, [before, after]))| {
                let dt = (c.t[c.t.len() - 1] - c.t[0]) / (c.t.len() - 1) as f64;
                let n = c.q.len();
                let v = (0..n)
                    .map(|k| (c.q[(k + 1).min(n - 1)] - c.q[k.saturating_sub(1)]) / (2.0 * dt))
                    .collect();
                let part = if split[i] == Some(true) {
                    "held_out"
                } else {
                    "fit"
                };
                crate::plots::Series {
                    name: format!("closed_loop_force_{part}_{i}"),
                    t: c.t.clone(),
                    q: c.q.clone(),
                    v,
                    before,
                    after,
                }
            })
            .collect();
        crate::plots::crane_plots(dir, &series)?;
    }
    Ok(true)
}

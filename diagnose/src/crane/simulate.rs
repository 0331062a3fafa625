//! Simulation of a crane run from its recorded voltages.

use crane_ident::data::CraneRun;
use crane_model::{Config, Crane, Extensions, FrictionLaw, Params, State};

/// Simulates a run with `params` and extensions (model step half the sampling period, the
/// recorded voltages held); returns the drive positions per sample, or `None` if the model
/// rejects a step.
pub fn simulate(run: &CraneRun, params: &Params, ext: &Extensions) -> Option<Vec<[f64; 3]>> {
    simulate_checked(run, params, ext).ok()
}

/// [`simulate`], with the model's reason when it fails: the parameter or state field it
/// refuses, or the step and time [s] at which a step fails.
pub fn simulate_checked(
    run: &CraneRun,
    params: &Params,
    ext: &Extensions,
) -> Result<Vec<[f64; 3]>, String> {
    let dt = run.dt();
    let q0 = [run.x[0], run.y[0], run.l[0], run.alpha[0], run.beta[0]];
    let c: Crane = Crane::new(
        params,
        Config {
            h: dt / 2.0,
            law: FrictionLaw::Hybrid,
        },
        State {
            q: q0,
            qd: [0.0; 5],
        },
    )
    .map_err(|e| e.to_string())?;
    let mut c = c.with_extensions(ext).map_err(|e| e.to_string())?;
    let mut out = Vec::with_capacity(run.len());
    for k in 0..run.len() {
        let s = c.state().q;
        out.push([s[0], s[1], s[2]]);
        let u = [run.u[0][k], run.u[1][k], run.u[2][k]];
        for _ in 0..2 {
            c.step(u)
                .map_err(|e| format!("sample {k} (t = {:.4} s): {e}", k as f64 * dt))?;
        }
    }
    Ok(out)
}

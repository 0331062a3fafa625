//! The EMPS benchmark's published IDIM-LS results, reproduced on the real data.

use crane_ident::data::{load_run, DatasetSpec, RunSpec};
use crane_ident::emps::{cross_test, idim_ls, IdimModel, IdimOptions};
use std::path::PathBuf;

const GTAU: f64 = 35.150651882485;

fn emps_dir() -> PathBuf {
    crane_ident::shared_data::root().join("emps")
}

fn load(file: &str) -> crane_ident::data::AxisRun {
    let mut spec = DatasetSpec::minimal(0.0);
    spec.gain_n_per_v = Some(GTAU);
    spec.columns.insert("x".into(), "qm".into());
    spec.columns.insert("u".into(), "vir".into());
    let run = load_run(
        &emps_dir(),
        &spec,
        &RunSpec {
            file: file.into(),
            ..RunSpec::default()
        },
    )
    .expect("EMPS data loads");
    run.axis().expect("single-axis run").clone()
}

/// `true` (skip, with a one-line reason) when the shared EMPS data are absent outside CI;
/// panics when `CI` is set and they are absent.
fn within(x: f64, reference: f64, rel: f64) -> bool {
    ((x - reference) / reference).abs() <= rel
}

#[test]
fn emps_symmetric_idim_ls_matches_the_published_fit() {
    if crane_ident::shared_data::require("emps").is_none() {
        return;
    }
    let run = load("emps_estimation_raw.csv");
    assert_eq!(run.t.len(), 24841);
    let opt = IdimOptions::default();
    let fit = idim_ls(&run, IdimModel::Symmetric, &opt).unwrap();
    eprintln!("symmetric: {:?} rel err {}", fit.theta, fit.rel_err_pct);
    let published = [95.1089, 203.5034, 20.3935, -3.1648];
    for (name, (x, r)) in fit.names.iter().zip(fit.theta.iter().zip(published)) {
        assert!(within(*x, r, 0.01), "{name}: {x} vs published {r}");
    }
    assert!(
        (fit.rel_err_pct - 4.0834).abs() <= 0.2,
        "{}",
        fit.rel_err_pct
    );
    // In fact the processing is the benchmark's own: the digits agree far beyond 1 %.
    for (x, r) in fit.theta.iter().zip(published) {
        assert!(within(*x, r, 1e-5), "{x} vs {r}");
    }
    assert!((fit.rel_err_pct - 4.0834).abs() <= 1e-3);

    // cross-test on the pulses run with the estimation-run parameters: published 5.9824 %
    let pulses = load("emps_validation_pulses_raw.csv");
    let e = cross_test(&pulses, IdimModel::Symmetric, &fit.theta, &opt);
    eprintln!("cross-test {e}");
    assert!((e - 5.9824).abs() <= 0.2, "{e}");
}

#[test]
fn emps_direction_dependent_idim_ls_matches_the_published_fit() {
    if crane_ident::shared_data::require("emps").is_none() {
        return;
    }
    let run = load("emps_estimation_raw.csv");
    let fit = idim_ls(&run, IdimModel::DirectionDependent, &IdimOptions::default()).unwrap();
    eprintln!("direction: {:?} rel err {}", fit.theta, fit.rel_err_pct);
    let published = [95.1540, 166.7061, 240.4236, 20.1440, 20.6277];
    for (name, (x, r)) in fit.names.iter().zip(fit.theta.iter().zip(published)) {
        assert!(within(*x, r, 0.01), "{name}: {x} vs published {r}");
    }
    assert!(
        (fit.rel_err_pct - 3.1117).abs() <= 0.2,
        "{}",
        fit.rel_err_pct
    );
    for (x, r) in fit.theta.iter().zip(published) {
        assert!(within(*x, r, 1e-5), "{x} vs {r}");
    }
}

#[test]
fn emps_fit_depends_on_the_processing() {
    if crane_ident::shared_data::require("emps").is_none() {
        return;
    }
    // Without the benchmark's filtering the same least squares is far off: the test above
    // is not satisfied by any processing.
    let run = load("emps_estimation_raw.csv");
    let opt = IdimOptions {
        cutoff_hz: 400.0,
        decimation: 1,
        ..IdimOptions::default()
    };
    let fit = idim_ls(&run, IdimModel::Symmetric, &opt).unwrap();
    assert!(!within(fit.theta[0], 95.1089, 0.01) || fit.rel_err_pct > 4.3);
}

fn closed_loop_run(file: &str) -> crane_ident::emps::ClosedLoopRun {
    crane_ident::emps::load_closed_loop(&emps_dir().join(file)).expect("EMPS data loads")
}

/// Closed-loop force errors [%] (estimation, validation) of the IDIM-LS model `model` fitted
/// on the estimation run only.
fn closed_loop_errors(model: IdimModel) -> (f64, f64) {
    closed_loop_errors_with(model, crane_ident::emps::Controller::default())
}

fn closed_loop_errors_with(model: IdimModel, ctl: crane_ident::emps::Controller) -> (f64, f64) {
    use crane_ident::emps::{simulate_closed_loop, AxisModel};
    let fit = idim_ls(
        &load("emps_estimation_raw.csv"),
        model,
        &IdimOptions::default(),
    )
    .unwrap();
    let m = AxisModel::from_idim(model, &fit.theta).unwrap();
    let est = simulate_closed_loop(&closed_loop_run("emps_estimation_raw.csv"), &m, &ctl);
    let val = simulate_closed_loop(&closed_loop_run("emps_validation_pulses_raw.csv"), &m, &ctl);
    eprintln!(
        "{model:?}, command delay {} sample(s): estimation position {:.5} % force {:.3} %; validation position {:.5} % force {:.3} %",
        ctl.delay_samples,
        est.position_err_pct,
        est.force_err_pct,
        val.position_err_pct,
        val.force_err_pct
    );
    (est.force_err_pct, val.force_err_pct)
}

#[test]
fn emps_closed_loop_force_errors() {
    if crane_ident::shared_data::require("emps").is_none() {
        return;
    }
    let (se, sv) = closed_loop_errors(IdimModel::Symmetric);
    let (de, dv) = closed_loop_errors(IdimModel::DirectionDependent);
    // the published closed-loop simulation of the symmetric model: 5.85 % / 8.94 %; ours (the
    // README's controller with its one-sample command delay, exact sticking) is near it
    assert!(
        (se - 5.85).abs() < 2.5 && (sv - 8.94).abs() < 2.5,
        "{se} {sv}"
    );
    // the direction-dependent model is better in closed loop too, on both runs
    assert!(de < se - 0.2 && dv < sv - 0.2, "{de} {dv} vs {se} {sv}");
}

#[test]
fn emps_closed_loop_force_error_depends_on_the_command_delay() {
    if crane_ident::shared_data::require("emps").is_none() {
        return;
    }
    // The README's rig applies the command one sample later; without that delay the same
    // symmetric model's simulated force error drops (measured 5.32 % / 6.00 % against
    // 7.89 % / 9.85 %): the published 5.85 % / 8.94 % lie between, so the published
    // simulation's exact timing is not pinned down by its figures.
    let ctl = crane_ident::emps::Controller {
        delay_samples: 0,
        ..Default::default()
    };
    let (e0, v0) = closed_loop_errors_with(IdimModel::Symmetric, ctl);
    let (e1, v1) = closed_loop_errors(IdimModel::Symmetric);
    assert!(e0 < e1 - 1.0 && v0 < v1 - 1.0, "{e0} {v0} vs {e1} {v1}");
    assert!(e0 < 5.85 && 5.85 < e1, "{e0} {e1}");
    assert!(v0 < 8.94 && 8.94 < v1, "{v0} {v1}");
}

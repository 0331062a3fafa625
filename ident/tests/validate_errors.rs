//! A model failure during validation names the run, the sample, its time and the model's
//! field or step error (issue 11: "mass matrix not positive definite" named no run).

use crane_ident::data::{CraneRun, Dataset, DatasetSpec, Run, RunKind, Samples};
use crane_ident::validate::{validate_dataset, SimError, ValidateError};
use crane_model::Params;

fn dataset(name: &str, run: CraneRun, payload_kg: f64) -> Dataset {
    Dataset {
        dir: "ds".into(),
        spec: DatasetSpec::minimal(payload_kg),
        runs: vec![Run {
            name: name.into(),
            kind: RunKind::Validation,
            payload_kg,
            samples: Samples::Crane(run),
        }],
    }
}

fn shaking_run(n: usize, y0: f64) -> CraneRun {
    let t: Vec<f64> = (0..n).map(|k| k as f64 * 2e-3).collect();
    let u = [
        t.iter().map(|t| 12.0 * (3.0 * t).sin()).collect(),
        t.iter().map(|t| -12.0 * (5.0 * t).sin()).collect(),
        t.iter().map(|t| 2.0 * (2.0 * t).sin()).collect(),
    ];
    CraneRun {
        u,
        x: vec![0.25; n],
        y: vec![y0; n],
        l: vec![0.35; n],
        alpha: vec![core::f64::consts::FRAC_PI_2; n],
        beta: vec![0.0; n],
        t,
    }
}

#[test]
fn rejected_step_names_run_sample_and_time() {
    // the stiff repro of the step contract: the model rejects a step (typed error)
    let mut p = Params::default();
    p.y.inertia = 0.0;
    p.trolley_mass = 0.0167;
    let ds = dataset("007_validation_stiff.csv", shaking_run(3000, 0.3), 0.00066);
    let err = validate_dataset(&p, &ds).expect_err("stiff run fails");
    let msg = err.to_string();
    assert!(
        matches!(&err, ValidateError::Run { run, source: SimError::Step { .. }, .. } if run == "007_validation_stiff.csv"),
        "{msg}"
    );
    for part in [
        "007_validation_stiff.csv",
        "sample ",
        "t = ",
        "step rejected",
    ] {
        assert!(msg.contains(part), "`{part}` missing from: {msg}");
    }
}

#[test]
fn bad_first_configuration_names_run_and_field() {
    let ds = dataset("008_validation.csv", shaking_run(10, 0.9), 0.064);
    let err = validate_dataset(&Params::default(), &ds).expect_err("y0 beyond the rail");
    let msg = err.to_string();
    // named by the run's column, not the model's `state.q[1]` (issue 22)
    assert!(
        msg.contains("008_validation.csv") && msg.contains("the run's first `y`"),
        "{msg}"
    );
    assert!(!msg.contains("state.q"), "{msg}");
}

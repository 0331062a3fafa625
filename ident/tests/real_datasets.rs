//! The example data sets over the real logs (`examples/emps`, `examples/cicese_joint{1,2}`),
//! read in place from `../shared/data`. Skipped with a one-line reason when that folder is
//! absent, failed when the environment variable `CI` is set.

use crane_ident::data::{load_dataset, Gain, InputUnit, PositionUnit, RunKind};
use crane_ident::emps::{load_closed_loop, ClosedLoopRun, Controller};
use std::path::{Path, PathBuf};

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The shared data folder, or `None` (skip) when absent outside CI.
fn shared_data() -> Option<PathBuf> {
    let d = repo().join("../shared/data");
    if d.is_dir() {
        return Some(d);
    }
    if std::env::var_os("CI").is_some() {
        panic!("CI is set but {} is absent", d.display());
    }
    eprintln!("skipped: {} is absent (real data sets)", d.display());
    None
}

fn roles(runs_toml: &Path) -> Vec<(String, String)> {
    let t: toml::Table = toml::from_str(&std::fs::read_to_string(runs_toml).unwrap()).unwrap();
    t["runs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| {
            (
                r["file"].as_str().unwrap().to_string(),
                r["role"].as_str().unwrap().to_string(),
            )
        })
        .collect()
}

#[test]
fn cicese_examples_follow_runs_toml() {
    let Some(shared) = shared_data() else { return };
    for (joint, n) in [(1, 14), (2, 18)] {
        let ds = load_dataset(&repo().join(format!("examples/cicese_joint{joint}")))
            .unwrap_or_else(|e| panic!("{e}"));
        let expected = roles(&shared.join(format!("cicese/cicese_dd_joint{joint}/runs.toml")));
        assert_eq!(ds.runs.len(), n);
        assert_eq!(expected.len(), n);
        for ((run, spec), (file, role)) in ds.runs.iter().zip(&ds.spec.runs).zip(&expected) {
            assert!(run
                .name
                .ends_with(&format!("cicese_dd_joint{joint}/{file}")));
            let kind = if role == "heldout" {
                RunKind::Validation
            } else {
                assert_eq!(role, "fit");
                RunKind::Other
            };
            assert_eq!(run.kind, kind, "{file}");
            assert!(spec.note.as_deref().is_some_and(|n| !n.is_empty()));
            let a = run.axis().expect("single-axis");
            assert_eq!(a.position_unit, PositionUnit::Radian);
            assert_eq!(a.input_unit, InputUnit::NewtonMetre);
            assert_eq!(a.gain, Gain::Known(1.0));
            assert_eq!(a.effort_unit(), "N m");
            assert_eq!(a.force, a.u);
            // uniform 66.84 Hz, quantised angle at rest: nothing resampled, nothing held
            assert!(a.notes.is_empty(), "{file}: {:?}", a.notes);
            assert!((a.dt() - 0.01496).abs() < 1e-6, "{file} {}", a.dt());
            assert_eq!(run.payload_kg, 0.0);
        }
    }
}

#[test]
fn emps_example_declares_the_rig_controller() {
    let Some(shared) = shared_data() else { return };
    let ds = load_dataset(&repo().join("examples/emps")).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(ds.runs.len(), 2);
    assert_eq!(ds.runs[1].kind, RunKind::Validation);
    let spec = ds.spec.controller.as_ref().expect("declared");
    let a = ds.runs[0].axis().unwrap();
    assert_eq!(a.gain, Gain::Known(35.150651882485));
    assert_eq!(a.input_unit, InputUnit::Volt);
    assert!(a.notes.is_empty(), "{:?}", a.notes);
    let ctl = Controller::from_declared(spec, a.gain).unwrap();
    assert_eq!(ctl, Controller::default());
    // the declared signals are those of the hard-wired EMPS loader
    for (run, file) in ds
        .runs
        .iter()
        .zip(["emps_estimation_raw.csv", "emps_validation_pulses_raw.csv"])
    {
        let from_decl = ClosedLoopRun::from_axis(run.axis().unwrap()).unwrap();
        let hard = load_closed_loop(&shared.join("emps").join(file)).unwrap();
        assert_eq!(from_decl, hard, "{file}");
    }
    let pulses = &ds.runs[1]
        .axis()
        .unwrap()
        .closed_loop
        .as_ref()
        .unwrap()
        .added_input;
    assert!(pulses.contains(&5.0));
    assert!(ds.runs[0]
        .axis()
        .unwrap()
        .closed_loop
        .as_ref()
        .unwrap()
        .added_input
        .iter()
        .all(|&p| p == 0.0));
}

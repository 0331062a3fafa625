//! The EMPS story on the real data: fit on the estimation run only, score on the validation
//! run (pulses).

use crane_diagnose::{diagnose_dataset, Baseline, DiagnoseOptions};
use crane_ident::data::{load_run, Dataset, DatasetSpec, RunKind, RunSpec};
use std::path::PathBuf;

const GTAU: f64 = 35.150651882485;

fn emps() -> Dataset {
    emps_with_gain(GTAU)
}

/// The EMPS data set with the drive gain `gain` [N/V] declared.
fn emps_with_gain(gain: f64) -> Dataset {
    let dir = crane_ident::shared_data::root().join("emps");
    let mut spec = DatasetSpec::minimal(0.0);
    spec.gain_n_per_v = Some(gain);
    spec.columns.insert("x".into(), "qm".into());
    spec.columns.insert("u".into(), "vir".into());
    // the rig's controller, as `examples/emps` declares it: closed-loop data
    spec.controller = crane_ident::data::load_dataset(
        &PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../examples/emps"),
    )
    .expect("examples/emps loads")
    .spec
    .controller;
    let runs = [
        ("emps_estimation_raw.csv", RunKind::Other),
        ("emps_validation_pulses_raw.csv", RunKind::Validation),
    ]
    .iter()
    .map(|(f, kind)| {
        let rs = RunSpec {
            file: (*f).into(),
            kind: *kind,
            ..RunSpec::default()
        };
        load_run(&dir, &spec, &rs).expect("EMPS data loads")
    })
    .collect();
    Dataset { dir, spec, runs }
}

fn opts(baseline: Baseline) -> DiagnoseOptions {
    DiagnoseOptions {
        baseline,
        plots_dir: None,
    }
}

#[test]
fn emps_symmetric_model_misses_the_direction_dependence() {
    if crane_ident::shared_data::require("emps").is_none() {
        return;
    }
    let r = diagnose_dataset(&emps(), &opts(Baseline::Symmetric)).unwrap();
    eprintln!("{}", r.to_json());
    let m = &r.measures;
    // what the symmetric Coulomb + viscous model gets wrong: the direction dependence
    assert_eq!(r.verdict, "direction_asymmetry");
    let f = &r.findings[0];
    eprintln!(
        "Fv+ {} Fv- {} Fc+ {} Fc- {}",
        f.parameters["viscous_pos_n_s_per_m"],
        f.parameters["viscous_neg_n_s_per_m"],
        f.parameters["dry_pos_n"],
        f.parameters["dry_neg_n"]
    );
    // extended, it is the published direction-dependent model: 3.1117 % on the estimation run
    assert!(
        (m["force_rel_err_fit_after_pct"] - 3.1117).abs() < 0.01,
        "{m:?}"
    );
    assert!((f.parameters["viscous_pos_n_s_per_m"] - 166.7061).abs() < 0.5);
    assert!((f.parameters["viscous_neg_n_s_per_m"] - 240.4236).abs() < 0.5);
    // the baseline is the published symmetric model WITH its offset: its cross-test on the
    // validation run is the published 5.9824 %, so the gain of direction dependence is
    // 5.98 -> 5.36 %, not measured against a weaker baseline
    assert!((m["force_rel_err_fit_pct"] - 4.0834).abs() < 0.01, "{m:?}");
    assert!(
        (m["force_rel_err_held_out_pct"] - 5.9824).abs() < 0.01,
        "{m:?}"
    );
    // and the gain holds on the validation run (pulses), which it never saw
    assert!(
        m["force_rel_err_held_out_after_pct"] < m["force_rel_err_held_out_pct"] - 0.5,
        "{m:?}"
    );
    assert!(f.nmae_after < f.nmae_before);
    // the published measure: closed-loop simulated force error, estimation / validation
    let cl = |k: &str| m[&format!("closed_loop_force_err_{k}_pct")];
    eprintln!(
        "closed loop: symmetric {:.2} / {:.2} %, direction-dependent {:.2} / {:.2} % (published symmetric 5.85 / 8.94 %)",
        cl("fit_symmetric"),
        cl("held_out_symmetric"),
        cl("fit_direction_dependent"),
        cl("held_out_direction_dependent")
    );
    assert!(cl("held_out_direction_dependent") < cl("held_out_symmetric"));
    assert!(cl("fit_direction_dependent") < cl("fit_symmetric"));
}

#[test]
fn emps_paper_structure_claims_no_delay_that_zero_fits_as_well() {
    if crane_ident::shared_data::require("emps").is_none() {
        return;
    }
    let r = diagnose_dataset(&emps(), &opts(Baseline::Auto)).unwrap();
    eprintln!("{}", r.to_json());
    let m = &r.measures;
    // the paper's structure (quartic dry friction per direction) fits better than 3.11 %
    assert!(m["force_rel_err_fit_pct"] < 3.11, "{m:?}");
    // the baseline's fitting NMAE is a figure (it was NaN, printed as null: "diverged"), and
    // a fit is no worse on its own rows than on held-out ones by more than a few times
    let e = &r.baseline_errors[0];
    assert!(
        e.nmae_fit.is_finite() && e.nmae_fit > 0.0 && e.nmae_fit < 3.0 * e.nmae_held_out,
        "{e:?}"
    );
    // the delay grid starts at 0: on the estimation run no delay fits best, so no delay is
    // claimed (a grid starting at one sample used to report one)
    assert!(
        r.findings.iter().all(|f| f.cause != "input_delay"),
        "{:?}",
        r.findings
    );
    // every finding cuts the held-out error it reports, and no stiction below 1 is offered
    for f in &r.findings {
        assert!(f.nmae_after < f.nmae_before, "{f:?}");
    }
    for c in &r.candidates {
        if c.cause == "stiction" {
            assert!(!c.supported || c.parameters["ratio"] > 1.0, "{c:?}");
        }
    }
    // force offset and direction asymmetry are part of this baseline: not identifiable
    assert!(r
        .candidates
        .iter()
        .any(|c| c.cause == "force_offset" && !c.supported));
}

#[test]
fn emps_closed_loop_plots_are_written() {
    if crane_ident::shared_data::require("emps").is_none() {
        return;
    }
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("diagnose-emps");
    let _ = std::fs::remove_dir_all(&dir);
    let o = DiagnoseOptions {
        baseline: Baseline::Symmetric,
        plots_dir: Some(dir.clone()),
    };
    diagnose_dataset(&emps(), &o).unwrap();
    for part in ["fit_0", "held_out_1"] {
        for tag in ["time", "position", "velocity"] {
            let f = dir.join(format!("closed_loop_force_{part}_vs_{tag}.svg"));
            let text = std::fs::read_to_string(&f).unwrap_or_default();
            // both models drawn: red (symmetric) and blue (direction-dependent)
            assert!(
                text.contains("fill=\"red\"") && text.contains("fill=\"blue\""),
                "{}",
                f.display()
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// EMPS with 8 s at rest under 0.5 V appended to the fitting run: a resting axis is not an
/// inverse-dynamics row with the sign of a noisy velocity, so neither the baseline nor the
/// verdict moves (it used to turn into `input_deadzone` 0.30 V and double the baseline error).
#[test]
fn emps_with_a_long_rest_keeps_its_baseline_and_verdict() {
    if crane_ident::shared_data::require("emps").is_none() {
        return;
    }
    let plain = emps();
    let mut rested = plain.clone();
    let crane_ident::data::Samples::Axis(a) = &mut rested.runs[0].samples else {
        panic!("EMPS runs are single-axis runs");
    };
    let dt = a.dt();
    let (t_end, x_end) = (*a.t.last().unwrap(), *a.x.last().unwrap());
    for k in 1..=8000 {
        a.t.push(t_end + k as f64 * dt);
        a.x.push(x_end);
        a.u.push(0.5);
        a.force.push(0.5 * GTAU);
        if let Some(c) = a.closed_loop.as_mut() {
            let r = *c.reference.last().unwrap();
            c.reference.push(r);
            c.added_input.push(0.0);
        }
    }
    for baseline in [Baseline::Auto, Baseline::Symmetric] {
        let before = diagnose_dataset(&plain, &opts(baseline.clone())).unwrap();
        let after = diagnose_dataset(&rested, &opts(baseline.clone())).unwrap();
        let fit = |r: &crane_diagnose::Report| r.measures["force_rel_err_fit_pct"];
        eprintln!(
            "{baseline:?}: fit error {:.3} % -> {:.3} % with the rest, verdict {} -> {}",
            fit(&before),
            fit(&after),
            before.verdict,
            after.verdict
        );
        assert_eq!(before.verdict, after.verdict);
        assert!((fit(&after) - fit(&before)).abs() < 0.05 * fit(&before));
        assert!(after
            .findings
            .iter()
            .all(|f| f.cause != crane_diagnose::Cause::InputDeadzone));
    }
}

/// Issue 22: a wrong gain (1e-9 N/V declared) makes the closed-loop simulation miss the force
/// by hundreds of percent; the verdict is then `unexplained`, never `none`.
#[test]
fn emps_with_a_wrong_gain_is_not_called_none() {
    if crane_ident::shared_data::require("emps").is_none() {
        return;
    }
    let r = diagnose_dataset(&emps_with_gain(1e-9), &opts(Baseline::Auto)).expect("diagnoses");
    assert_eq!(
        r.verdict,
        crane_diagnose::Verdict::Unexplained,
        "{}",
        r.verdict_reason
    );
    assert!(
        r.verdict_reason.contains("does not fit"),
        "{}",
        r.verdict_reason
    );
    let right = diagnose_dataset(&emps(), &opts(Baseline::Auto)).expect("diagnoses");
    assert_ne!(right.verdict, crane_diagnose::Verdict::Unexplained);
}

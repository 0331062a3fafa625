//! No panic on any file of `../shared/data` in any combination of fitting and held-out runs:
//! seeded random subsets of the CICESE runs of each joint (one run included, where the
//! split is by time) with random roles, and every role assignment of the two EMPS runs. Each
//! diagnosis must end in a report or a clear error, never a panic, and a report's numbers
//! must be finite or the report must say why not.
//!
//! Skips with one line without `../shared/data`; fails then when `CI` is set.

use crane_diagnose::{diagnose_dataset, DiagnoseOptions};
use crane_ident::data::{load_dataset, RunKind};
use crane_ident::rng::Rng;
use std::path::Path;

fn root() -> Option<std::path::PathBuf> {
    crane_ident::shared_data::require("cicese")?;
    crane_ident::shared_data::require("emps")?;
    Some(Path::new(env!("CARGO_MANIFEST_DIR")).join(".."))
}

#[test]
fn real_data_in_any_combination_never_panics() {
    let Some(root) = root() else {
        return;
    };
    let mut rng = Rng::new(2024); // seeded: the subsets are the same on every run
    let (mut reports, mut errors) = (0, 0);
    for name in ["cicese_joint1", "cicese_joint2"] {
        let ds = load_dataset(&root.join("examples").join(name)).expect("example loads");
        let n = ds.runs.len();
        for case in 0..24 {
            let mut sub = ds.clone();
            // case 0: a single run (time-block split); else a random subset with random roles
            let k = if case == 0 {
                1
            } else {
                1 + rng.below(n as u64) as usize
            };
            let mut idx: Vec<usize> = (0..n).collect();
            for i in 0..n {
                let j = i + rng.below((n - i) as u64) as usize;
                idx.swap(i, j);
            }
            sub.runs = idx[..k]
                .iter()
                .map(|&i| {
                    let mut r = ds.runs[i].clone();
                    r.kind = if rng.below(2) == 0 {
                        RunKind::Validation
                    } else {
                        RunKind::Other
                    };
                    r
                })
                .collect();
            match diagnose_dataset(&sub, &DiagnoseOptions::default()) {
                Ok(r) => {
                    reports += 1;
                    if let Some(h) = &r.heldout_simulation {
                        // a figure, or a simulation that diverged and says so (issue 20:
                        // never a diverged error printed as a figure)
                        let before = h.runs.iter().any(|x| x.diverged_before);
                        let after = h.runs.iter().any(|x| x.diverged_after);
                        assert!(
                            (h.nmae_before.is_finite()
                                || (before && h.nmae_before == f64::INFINITY))
                                && (h.nmae_after.is_finite()
                                    || (after && h.nmae_after == f64::INFINITY)),
                            "{name} case {case}: {} / {}",
                            h.nmae_before,
                            h.nmae_after
                        );
                        for x in &h.runs {
                            assert_eq!(x.diverged_before, !x.nmae_before.is_finite());
                            assert_eq!(x.diverged_after, !x.nmae_after.is_finite());
                        }
                    }
                    if let Some(m) = &r.final_model {
                        assert!(
                            m.inertia > 0.0 && m.breakaway_pos >= 0.0 && m.breakaway_neg >= 0.0
                        );
                    }
                }
                Err(e) => {
                    errors += 1;
                    assert!(!e.to_string().is_empty());
                }
            }
        }
    }
    let ds = load_dataset(&root.join("examples/emps")).expect("EMPS example loads");
    for roles in 0..4u8 {
        let mut sub = ds.clone();
        for (i, r) in sub.runs.iter_mut().enumerate() {
            r.kind = if roles & (1 << i) != 0 {
                RunKind::Validation
            } else {
                RunKind::Other
            };
        }
        match diagnose_dataset(&sub, &DiagnoseOptions::default()) {
            Ok(_) => reports += 1,
            Err(e) => {
                errors += 1;
                assert!(!e.to_string().is_empty());
            }
        }
    }
    // several fitting runs of different lengths (the estimation run cut in three): every
    // column is decimated run by run, so force and regressors stay aligned (this panicked with
    // an index out of bounds when the force was decimated per run and the columns after
    // concatenation)
    {
        let mut sub = ds.clone();
        let est = sub.runs[0].clone();
        let crane_ident::data::Samples::Axis(a) = &est.samples else {
            panic!("EMPS runs are single-axis runs");
        };
        let n = a.t.len();
        let cuts = [0, 7001, 15_013, n];
        let mut pieces = Vec::new();
        for w in cuts.windows(2) {
            let mut r = est.clone();
            r.name = format!("{}[{}..{}]", est.name, w[0], w[1]);
            r.kind = RunKind::Other;
            r.samples = crane_ident::data::Samples::Axis(a.slice(w[0]..w[1]));
            pieces.push(r);
        }
        pieces.push(sub.runs[1].clone());
        pieces.last_mut().expect("a held-out run").kind = RunKind::Validation;
        sub.runs = pieces;
        let r = diagnose_dataset(&sub, &DiagnoseOptions::default())
            .expect("three fitting runs of different lengths diagnose");
        assert!(r.measures["force_rel_err_fit_pct"].is_finite());
        reports += 1;
    }
    println!("{reports} reports, {errors} clear errors, 0 panics");
    assert!(reports > 0);
}

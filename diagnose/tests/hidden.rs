//! Hidden-effect tests: the virtual rig injects one seeded random effect; the workbench must
//! name it without being told.

use crane_diagnose::crane::Ext;
use crane_diagnose::crane::CRANE_CAUSES;
use crane_diagnose::hidden::{dataset, draw, Hidden};
use crane_diagnose::{diagnose_dataset, DiagnoseOptions, Report};
use std::time::Instant;

const SECONDS: f64 = 14.0;

fn case(cause: &str, seed: u64) -> (Hidden, Report) {
    let h = draw(cause, seed);
    let ds = dataset(&h, seed, 2, SECONDS).expect("rig runs");
    let rep = diagnose_dataset(&ds, &DiagnoseOptions::default()).expect("diagnosis");
    (h, rep)
}

fn show(h: &Hidden, r: &Report) -> String {
    let f = r.findings.first();
    format!(
        "truth {} {} {:?} -> verdict {} axis {} params {:?} nmae {:?} -> {:?} | base {:?}",
        h.cause(),
        h.axis_name(),
        h.ext,
        r.verdict,
        f.map(|f| f.axis.as_str()).unwrap_or("-"),
        f.map(|f| &f.parameters),
        f.map(|f| f.nmae_before),
        f.map(|f| f.nmae_after),
        r.baseline_errors
            .iter()
            .map(|e| e.nmae_held_out)
            .collect::<Vec<_>>(),
    )
}

/// What a case got right.
struct Outcome {
    cause: bool,
    axis: bool,
    detail: bool,
    cut: bool,
}

fn judge(h: &Hidden, r: &Report) -> Outcome {
    let f = r.findings.first();
    let cause = r.verdict == h.cause();
    let axis = h.ext.is_none() || f.is_some_and(|f| f.axis == h.axis_name());
    let param = |k: &str| f.and_then(|f| f.parameters.get(k).copied());
    let detail = match &h.ext {
        Some(Ext::Bump { center, .. }) => {
            param("center_m").is_some_and(|c| (c - center).abs() <= 0.02)
        }
        Some(Ext::Delay(d)) => param("delay_s").is_some_and(|x| (x - d).abs() <= 0.002 + 1e-9),
        _ => true,
    };
    // the affected axis's held-out NMAE is cut whenever the effect moved it beyond noise
    let i = ["x", "y", "l"]
        .iter()
        .position(|a| *a == h.axis_name())
        .unwrap_or(0);
    let e = &r.baseline_errors[i];
    let moved = h.ext.is_some() && e.nmae_held_out > 3.0 * e.nmae_noise;
    let cut = !moved || f.is_some_and(|f| f.axis == h.axis_name() && f.nmae_after < f.nmae_before);
    Outcome {
        cause,
        axis,
        detail,
        cut,
    }
}

#[test]
fn clean_data_gives_none() {
    for seed in 1..3u64 {
        let (h, r) = case("none", seed);
        eprintln!("{}", show(&h, &r));
        assert_eq!(r.verdict, "none", "{}", show(&h, &r));
    }
}

#[test]
fn a_few_hidden_effects_are_found() {
    // measured: these seeds are all named right, on the right axis, with the gain
    let cases: &[(&str, u64)] = &[
        ("stiction", 2),
        ("direction_asymmetry", 1),
        ("direction_asymmetry", 2),
        ("force_offset", 1),
        ("force_offset", 2),
        ("input_deadzone", 1),
        ("input_deadzone", 2),
        ("input_delay", 1),
        ("input_delay", 2),
        ("payload_mass", 1),
        ("payload_mass", 2),
    ];
    for &(cause, seed) in cases {
        let t0 = Instant::now();
        let (h, r) = case(cause, seed);
        eprintln!("{:.2}s {}", t0.elapsed().as_secs_f64(), show(&h, &r));
        let o = judge(&h, &r);
        assert!(o.cause && o.axis && o.cut, "{}", show(&h, &r));
        let f = &r.findings[0];
        assert!(f.nmae_after < 0.5 * f.nmae_before, "{}", show(&h, &r));
    }
}

/// The cases of `cause` for `seeds`, in order, diagnosed on every core (the cases are
/// independent and each is single-threaded).
fn cases_in_parallel(cause: &str, seeds: std::ops::Range<u64>) -> Vec<(Hidden, Report)> {
    use std::sync::atomic::{AtomicUsize, Ordering};
    use std::sync::Mutex;
    let seeds: Vec<u64> = seeds.collect();
    let out: Mutex<Vec<Option<(Hidden, Report)>>> =
        Mutex::new(seeds.iter().map(|_| None).collect());
    let next = AtomicUsize::new(0);
    let workers = std::thread::available_parallelism().map_or(1, |n| n.get());
    std::thread::scope(|s| {
        for _ in 0..workers {
            s.spawn(|| loop {
                let i = next.fetch_add(1, Ordering::Relaxed);
                let Some(&seed) = seeds.get(i) else { break };
                let r = case(cause, seed);
                out.lock().expect("no worker panicked holding the lock")[i] = Some(r);
            });
        }
    });
    out.into_inner()
        .expect("no worker panicked holding the lock")
        .into_iter()
        .map(|r| r.expect("every case ran"))
        .collect()
}

/// The sweep: 40 hidden cases per cause and 40 clean cases. Prints the hit rates.
#[test]
#[ignore = "slow sweep; run by scripts/test.sh"]
fn hidden_effect_sweep() {
    let n: u64 = std::env::var("SWEEP_N")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(40);
    let mut lines = Vec::new();
    let mut rates = std::collections::BTreeMap::new();
    let only = std::env::var("SWEEP_CAUSES").ok();
    for cause in std::iter::once("none").chain(CRANE_CAUSES.iter().map(|c| c.as_str())) {
        if only
            .as_ref()
            .is_some_and(|o| !o.split(',').any(|c| c == cause))
        {
            continue;
        }
        let (mut c, mut a, mut d, mut k) = (0, 0, 0, 0);
        for (seed, (h, r)) in (100..100 + n).zip(cases_in_parallel(cause, 100..100 + n)) {
            let o = judge(&h, &r);
            c += o.cause as u32;
            a += (o.cause && o.axis) as u32;
            d += (o.cause && o.detail) as u32;
            k += o.cut as u32;
            if !(o.cause && o.axis && o.detail && o.cut) {
                eprintln!("miss: seed {seed} {}", show(&h, &r));
            }
        }
        let p = |x: u32| 100.0 * x as f64 / n as f64;
        lines.push(format!(
            "{cause:20} right cause first {:5.1} %  + axis {:5.1} %  + centre/delay {:5.1} %  NMAE cut when moved {:5.1} %",
            p(c), p(a), p(d), p(k)
        ));
        rates.insert(cause, (p(c), p(a), p(d), p(k)));
    }
    for l in &lines {
        eprintln!("{l}");
    }
    // Asserted: what the sweep measured (seeds 100..140, deterministic):
    //   right cause, axis and centre/delay: 100 % for none, direction_asymmetry, force_offset,
    //   input_deadzone, input_delay, payload_mass; 97.5 % for localized_friction and stiction.
    //   Held-out NMAE of the affected axis cut whenever the effect moved it beyond noise:
    //   100 % except localized_friction and stiction 97.5 % (their one miss each, seed 135,
    //   a rope effect the fitting run shows much less of than the held-out run: baseline
    //   rope NMAE fitting / held-out 0.004 / 1.0 % for the bump, 0.25 / 1.96 % for stiction).
    //   Time: 211 s in the test profile (opt-level 2) on the shared 2-core machine, one case
    //   after the other; the cases now run on every core (146 s in release, 2 cores, loaded).
    if n == 40 && only.is_none() {
        let floor = [
            ("none", 100.0, 100.0),
            ("direction_asymmetry", 100.0, 100.0),
            ("force_offset", 100.0, 100.0),
            ("input_deadzone", 100.0, 100.0),
            ("input_delay", 100.0, 100.0),
            ("payload_mass", 100.0, 100.0),
            ("localized_friction", 97.5, 97.5),
            ("stiction", 97.5, 97.5),
        ];
        for (cause, min, cut) in floor {
            let (c, a, d, k) = rates[cause];
            assert!(
                c >= min && a >= min && d >= min && k >= cut,
                "{cause}: {:?}",
                rates[cause]
            );
        }
    }
}

#[test]
#[ignore = "exploration print-out"]
fn explore() {
    if std::env::var_os("EXPLORE").is_none() {
        eprintln!("skipped: set EXPLORE=1 to print the exploration cases");
        return;
    }
    for cause in std::iter::once("none").chain(CRANE_CAUSES.iter().map(|c| c.as_str())) {
        for seed in 1..3u64 {
            let t0 = Instant::now();
            let (h, r) = case(cause, seed);
            eprintln!("{:.2}s {}", t0.elapsed().as_secs_f64(), show(&h, &r));
        }
    }
}

/// One case with every candidate: `CASE=cause:seed cargo test ... -- --ignored one_case`.
#[test]
#[ignore = "exploration print-out"]
fn one_case() {
    let Ok(spec) = std::env::var("CASE") else {
        eprintln!("skipped: set CASE=cause:seed to print one case");
        return;
    };
    let (cause, seed) = spec.split_once(':').expect("CASE=cause:seed");
    let t0 = Instant::now();
    let (h, r) = case(cause, seed.parse().expect("seed"));
    eprintln!("{:.2}s {}", t0.elapsed().as_secs_f64(), show(&h, &r));
    for c in &r.candidates {
        eprintln!(
            "  {:20} {} score {:8.4} fbic {:10.1} {} {:?}",
            c.cause, c.axis, c.score, c.force_delta_bic, c.supported, c.parameters
        );
    }
    for e in &r.baseline_errors {
        eprintln!("  {e:?}");
    }
}

/// Position coverage of the generated runs.
#[test]
#[ignore = "exploration print-out"]
fn coverage() {
    use crane_ident::data::Samples;
    if std::env::var_os("EXPLORE").is_none() {
        eprintln!("skipped: set EXPLORE=1 to print the runs' position coverage");
        return;
    }
    for seed in 100..106u64 {
        let h = draw("none", seed);
        let ds = dataset(&h, seed, 2, SECONDS).expect("rig runs");
        for r in &ds.runs {
            if let Samples::Crane(c) = &r.samples {
                let mm = |x: &[f64]| {
                    (
                        x.iter().cloned().fold(f64::INFINITY, f64::min),
                        x.iter().cloned().fold(f64::NEG_INFINITY, f64::max),
                    )
                };
                eprintln!(
                    "{seed} {} x {:?} y {:?} l {:?}",
                    r.name,
                    mm(&c.x),
                    mm(&c.y),
                    mm(&c.l)
                );
            }
        }
    }
}

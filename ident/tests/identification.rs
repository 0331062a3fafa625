//! The virtual rig and the identification pipeline against the issue's numbers.
//!
//! Truth: `Params::default()` (the paper's table); every breakaway probe carries the paper's
//! measured scatter (variances X+ 0.026, X- 0.0073, Y+ 0.0030, Y- 0.0056 N^2).

use crane_ident::blr::{active_learning, linspace, Blr, BlrOptions};
use crane_ident::campaign::{run_campaign, Campaign, CampaignResult};
use crane_ident::data::{load_dataset, Constants, RunKind};
use crane_ident::identify::{identify_dataset, DryFit, IdentOptions, Identified};
use crane_ident::rig::{
    corrected_onset, Effect, Experiment, Input, PlantConfig, Probe, Rig, VirtualRig,
};
use crane_ident::rng::Rng;
use crane_ident::validate::validate_dataset;
use crane_model::{Extensions, Params};
use std::time::Instant;

fn horner(c: &[f64], p: f64) -> f64 {
    c.iter().rev().fold(0.0, |a, ci| a * p + ci).max(0.0)
}

fn rel(x: f64, t: f64) -> f64 {
    ((x - t) / t).abs()
}

/// RMS error against the truth over the axis and the fraction of the axis where the truth
/// lies inside the 95 % band.
fn curve_quality(fit: &DryFit, truth: &[f64; 5]) -> (f64, f64) {
    let c = &fit.curve;
    let n = c.position.len();
    let mut se = 0.0;
    let mut inside = 0;
    for k in 0..n {
        let t = horner(truth, c.position[k]);
        se += (c.mean[k] - t).powi(2);
        if t >= c.lower[k] && t <= c.upper[k] {
            inside += 1;
        }
    }
    ((se / n as f64).sqrt(), inside as f64 / n as f64)
}

fn temp_dir(tag: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("crane-ident-{}-{tag}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

#[test]
fn virtual_rig_records_like_the_real_rig() {
    let truth = Params::default();
    let cfg = PlantConfig::default();
    let mut rig = VirtualRig::new(truth, cfg);
    let n = 500;
    let mut sig = vec![[0.0; 3]; n];
    for (k, u) in sig.iter_mut().enumerate() {
        *u = [if k < 250 { 20.0 } else { -3.0 }, 2.0, 0.0];
    }
    let exp = Experiment {
        name: "t".into(),
        kind: RunKind::Other,
        payload_kg: 0.064,
        init: [0.1, 0.3, 0.4, core::f64::consts::FRAC_PI_2, 0.0],
        input: Input::Open(sig),
    };
    let r = rig.run(&exp).unwrap();
    assert_eq!(r.len(), n);
    // 2 ms sampling
    for w in r.t.windows(2) {
        assert!((w[1] - w[0] - 0.002).abs() < 1e-12);
    }
    // saturated, zero-order-hold voltages as commanded
    assert_eq!(r.u[0][0], 12.0);
    assert_eq!(r.u[0][300], -3.0);
    // every coordinate on its encoder grid: 2 pi R / 4096 (positions), 2 pi / 4096 (angles)
    for (i, col) in [&r.x, &r.y, &r.l, &r.alpha, &r.beta].iter().enumerate() {
        let res = cfg.resolution(i);
        for v in col.iter() {
            let c = v / res;
            assert!((c - c.round()).abs() < 1e-6, "coordinate {i}: {v}");
        }
    }
    assert!((cfg.resolution(0) - 2.0 * core::f64::consts::PI * 0.040 / 4096.0).abs() < 1e-15);
    assert!((cfg.resolution(2) - 2.0 * core::f64::consts::PI * 0.015 / 4096.0).abs() < 1e-15);
    // it moved: X forward then back, the trolley along Y
    assert!(r.x[249] > r.x[0] + 0.01 && r.x[499] < r.x[249]);
    assert!(r.y[499] > r.y[0]);

    // optional seeded noise: same seed same record, another seed another record
    let noisy = PlantConfig {
        position_noise_counts: 0.5,
        input_noise_v: 0.05,
        ..cfg
    };
    let a = VirtualRig::new(truth, noisy).run(&exp).unwrap();
    let b = VirtualRig::new(truth, noisy).run(&exp).unwrap();
    let c = VirtualRig::new(truth, PlantConfig { seed: 9, ..noisy })
        .run(&exp)
        .unwrap();
    assert_eq!(a, b);
    assert_ne!(a, c);
    assert_ne!(a, r);
}

/// A constant bias force on X, through the model's extensions (issue 6 uses this hook).
struct Bias(f64);
impl Effect for Bias {
    fn plant(&self, _kind: RunKind, _p: &mut Params, ext: &mut Extensions) {
        ext.force_offset[0] = self.0;
    }
}

#[test]
fn effect_hook_changes_the_plant_and_breakaway_probes_see_it() {
    let truth = Params::default();
    let cfg = PlantConfig {
        breakaway_noise: None,
        ..PlantConfig::default()
    };
    let probe = Probe::new(0, true, 0.2);
    let mut clean = VirtualRig::new(truth, cfg);
    let mut biased = VirtualRig::new(truth, cfg).with_effect(Box::new(Bias(0.5)));
    let a = clean.breakaway(&probe).unwrap();
    let b = biased.breakaway(&probe).unwrap();
    let res = clean.resolution(0);
    let (d, m) = (
        truth.x.viscous_pos / truth.x.gain,
        5.916 / truth.x.viscous_pos,
    );
    let fa = truth.x.gain * corrected_onset(&a.run, 0, res, d, m).unwrap().volts;
    let fb = truth.x.gain * corrected_onset(&b.run, 0, res, d, m).unwrap().volts;
    let c = horner(&truth.x.dry_pos, 0.2);
    // the clean probe measures the friction (lag corrected), the biased one 0.5 N less
    assert!((fa - c).abs() < 0.01, "{fa} vs {c}");
    assert!((fa - fb - 0.5).abs() < 0.01, "{fa} {fb}");
    // the raw (uncorrected) onset is late: it overestimates
    let raw = truth.x.gain * a.onset.unwrap().volts;
    assert!(raw > fa);
}

fn campaign(seed: u64, active: bool) -> (CampaignResult, Identified, f64) {
    let truth = Params::default();
    let t0 = Instant::now();
    let mut rig = VirtualRig::new(
        truth,
        PlantConfig {
            seed,
            ..PlantConfig::default()
        },
    );
    let c = Campaign {
        seed,
        active_learning: active,
        ..Campaign::default()
    };
    let res = run_campaign(&mut rig, &c, &Constants::default(), None).unwrap();
    let id = identify_dataset(&res.dataset, &c.ident).unwrap();
    (res, id, t0.elapsed().as_secs_f64())
}

#[test]
fn identification_from_the_virtual_rig_meets_the_issue_numbers() {
    let truth = Params::default();
    let dir = temp_dir("campaign");
    let t0 = Instant::now();
    let mut rig = VirtualRig::new(truth, PlantConfig::default());
    let c = Campaign::default();
    let res = run_campaign(&mut rig, &c, &Constants::default(), Some(&dir)).unwrap();
    let t_rig = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let ds = load_dataset(&dir).unwrap();
    assert_eq!(ds.runs.len(), res.dataset.runs.len());
    let id = identify_dataset(&ds, &c.ident).unwrap();
    let t_ident = t1.elapsed().as_secs_f64();
    // The data set on disk gives bit for bit what the campaign had in memory.
    let id_mem = identify_dataset(&res.dataset, &c.ident).unwrap();
    assert_eq!(id.params, id_mem.params);
    eprintln!("rig {t_rig:.2} s (with CSV writing), load + identify {t_ident:.2} s");
    // whole identification from the virtual rig under 10 s (test profile)
    assert!(t_rig + t_ident < 10.0, "{t_rig} + {t_ident}");

    // K and Jbar within 2 %
    let r = &id.rope;
    eprintln!(
        "rope: J {:?} K {:?} D {:?} C {:?}",
        r.inertia, r.gain, r.viscous, r.dry
    );
    assert!(rel(r.gain.value, truth.rope.gain) < 0.02);
    assert!(rel(r.inertia.value, truth.rope.inertia) < 0.02);
    for (name, d, t) in [("x", &id.x, &truth.x), ("y", &id.y, &truth.y)] {
        eprintln!(
            "{name}: K {:.4} J {:.4} D+ {:.3} ({}) D- {:.3} ({})",
            d.gain.value,
            d.inertia.value,
            d.viscous_pos.value,
            t.viscous_pos,
            d.viscous_neg.value,
            t.viscous_neg
        );
        assert!(rel(d.gain.value, t.gain) < 0.02, "{name} K");
        assert!(rel(d.inertia.value, t.inertia) < 0.02, "{name} Jbar");
        // viscous within 5 %
        assert!(rel(d.viscous_pos.value, t.viscous_pos) < 0.05, "{name} D+");
        assert!(rel(d.viscous_neg.value, t.viscous_neg) < 0.05, "{name} D-");
        for (dir, f, tc) in [("+", &d.dry_pos, &t.dry_pos), ("-", &d.dry_neg, &t.dry_neg)] {
            let (rms, inside) = curve_quality(f, tc);
            eprintln!(
                "  {name}{dir}: {} probes, RMS {rms:.4} N, truth inside band {:.0} %",
                f.positions.len(),
                100.0 * inside
            );
            assert!(f.positions.len() <= 15);
            assert!(rms < 0.1, "{name}{dir} RMS {rms}");
            // per curve the 95 % band holds the truth over >= 90 % of the axis only in about
            // 80 % of the realisations (see the many-seed test); assert a looser bound here
            assert!(inside >= 0.5, "{name}{dir} inside {inside}");
        }
        // standard errors and correlation matrices are reported
        assert!(d.fit_viscous.std_err.iter().all(|s| *s > 0.0));
        assert_eq!(d.fit_viscous.correlation.len(), 2);
        assert_eq!(d.dry_pos.correlation.len(), 5);
    }
    // swing damping within 10 %
    let s = &id.swing;
    eprintln!(
        "swing: D_alpha {:?} D_beta {:?} (paper's per-sample LS: {:?} {:?}) from {:.0} s of free swing",
        s.damping_alpha, s.damping_beta, s.differential_alpha, s.differential_beta, s.seconds_used
    );
    assert!(rel(s.damping_alpha.value, truth.damping_alpha) < 0.10);
    assert!(rel(s.damping_beta.value, truth.damping_beta) < 0.10);

    // validation multisine with the identified parameters
    let v = validate_dataset(&id.params, &ds).unwrap();
    eprintln!("{}", v.table());
    for (ours, paper) in v.runs[0].nmae_pct.iter().zip(v.paper_nmae_pct) {
        assert!(ours.is_finite() && *ours < paper);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn paper_processing_without_parallel_filtering_biases_the_inertia() {
    // The same data with the voltages left unfiltered (the paper's processing taken
    // literally): the rope inertia is off by more than the 2 % the issue asks.
    let (res, id, _) = campaign(3, true);
    let literal = IdentOptions {
        filter_inputs: false,
        ..IdentOptions::default()
    };
    let r = crane_ident::identify::identify_rope(&res.dataset, &literal).unwrap();
    let truth = Params::default();
    eprintln!(
        "rope J: parallel filtering {:.3}, literal {:.3} (true {})",
        id.rope.inertia.value, r.inertia.value, truth.rope.inertia
    );
    assert!(rel(id.rope.inertia.value, truth.rope.inertia) < 0.02);
    assert!(rel(r.inertia.value, truth.rope.inertia) > 0.02);
}

/// Probes a synthetic truth with Gaussian noise (the acquisition does not depend on the
/// measured values, so this is the design question alone).
fn max_std_after(active: bool, seed: u64, var: f64, truth: &[f64; 5], range: f64) -> f64 {
    let opt = BlrOptions::default();
    let mut rng = Rng::new(seed);
    let mut noise = Rng::new(seed ^ 0xABCD);
    let mut blr = Blr::new(0.0, range, opt.degree, opt.prior_std, var);
    let mut measure = |p: f64| -> Result<(f64, f64), ()> {
        Ok((horner(truth, p) + var.sqrt() * noise.normal(), p))
    };
    if active {
        active_learning(&mut blr, &opt, &mut rng, &mut measure).unwrap();
    } else {
        for p in linspace(opt.margin, range - opt.margin, opt.budget) {
            let (y, at) = measure(p).unwrap();
            blr.add(at, y);
        }
    }
    assert_eq!(blr.xs.len(), opt.budget);
    blr.max_std(&linspace(0.0, range, 201))
}

#[test]
fn active_learning_beats_a_uniform_grid_of_the_same_size() {
    let truth = Params::default();
    let mut wins = 0;
    let mut sum = [0.0, 0.0];
    let seeds = 100;
    let uniform = max_std_after(false, 0, 0.026, &truth.x.dry_pos, 0.505);
    for seed in 0..seeds {
        let al = max_std_after(true, seed, 0.026, &truth.x.dry_pos, 0.505);
        sum[0] += al;
        sum[1] += uniform;
        if al < uniform {
            wins += 1;
        }
    }
    eprintln!(
        "X+ (0.026 N^2), 15 probes: max predictive std active {:.4} N (mean of {seeds} seeds) vs uniform grid {:.4} N; active lower in {wins}/{seeds}",
        sum[0] / seeds as f64,
        sum[1] / seeds as f64
    );
    assert!(sum[0] < sum[1]);
    // not on every seed: the random first probe sometimes leads to a worse design
    assert!(wins as f64 >= 0.7 * seeds as f64, "{wins}");
}

#[test]
fn friction_bands_are_calibrated_over_many_seeds() {
    // Several campaigns' breakaway stage (active learning against the virtual rig, the
    // paper's scatter): RMS error and band coverage per curve, and the pooled coverage.
    let truth = Params::default();
    let mut curves = 0;
    let mut rms_ok = 0;
    let mut band_ok = 0;
    let mut inside_sum = 0.0;
    for seed in 0..6u64 {
        let mut rig = VirtualRig::new(
            truth,
            PlantConfig {
                seed: 100 + seed,
                ..PlantConfig::default()
            },
        );
        let mut rng = Rng::new(seed);
        let opt = IdentOptions::default();
        for (axis, ax, range) in [(0usize, &truth.x, 0.505), (1, &truth.y, 0.625)] {
            for pos in [true, false] {
                let var = match (axis, pos) {
                    (0, true) => 0.026,
                    (0, false) => 0.0073,
                    (1, true) => 0.003,
                    _ => 0.0056,
                };
                let mut blr = Blr::new(0.0, range, 4, opt.blr.prior_std, var);
                let (k, d) = (ax.gain, if pos { ax.viscous_pos } else { ax.viscous_neg });
                let m =
                    ax.inertia + truth.trolley_mass + if axis == 0 { truth.rail_mass } else { 0.0 };
                let res = rig.resolution(axis);
                active_learning(
                    &mut blr,
                    &opt.blr,
                    &mut rng,
                    |p| -> Result<(f64, f64), ()> {
                        let r = rig.breakaway(&Probe::new(axis, pos, p)).unwrap();
                        let on = corrected_onset(&r.run, axis, res, d / k, m / d).unwrap();
                        Ok((k * on.volts.abs(), on.position))
                    },
                )
                .unwrap();
                let fit = crane_ident::identify::dry_fit_from(&blr, var, 101);
                let (rms, inside) =
                    curve_quality(&fit, if pos { &ax.dry_pos } else { &ax.dry_neg });
                curves += 1;
                rms_ok += (rms < 0.1) as usize;
                band_ok += (inside >= 0.9) as usize;
                inside_sum += inside;
            }
        }
    }
    let pooled = inside_sum / curves as f64;
    eprintln!("{curves} curves: RMS < 0.1 N in {rms_ok}, truth inside the band over >= 90 % of the axis in {band_ok}, pooled coverage {:.1} %", 100.0 * pooled);
    assert!(rms_ok as f64 >= 0.85 * curves as f64);
    // a calibrated 95 % band: pooled coverage near 95 %
    assert!(pooled > 0.88 && pooled < 0.995, "{pooled}");
    assert!(band_ok as f64 >= 0.6 * curves as f64);
}

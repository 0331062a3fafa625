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
use crane_model::friction::dry;
use crane_model::{Extensions, Params};
use std::time::Instant;

fn rel(x: f64, t: f64) -> f64 {
    ((x - t) / t).abs()
}

/// How one fitted curve compares with the truth over the axis.
struct CurveQuality {
    /// RMS error [N].
    rms: f64,
    /// Fraction of the axis where the truth lies inside the pointwise 95 % band.
    pointwise: f64,
    /// Fraction of the axis where the truth lies inside the simultaneous 95 % band.
    simultaneous: f64,
}

fn curve_quality(fit: &DryFit, truth: &[f64; 5]) -> CurveQuality {
    let c = &fit.curve;
    let n = c.position.len();
    let mut se = 0.0;
    let mut inside = [0usize; 2];
    for k in 0..n {
        let t = dry(truth, c.position[k]);
        se += (c.mean[k] - t).powi(2);
        inside[0] += (t >= c.lower[k] && t <= c.upper[k]) as usize;
        inside[1] += (t >= c.simultaneous_lower[k] && t <= c.simultaneous_upper[k]) as usize;
    }
    CurveQuality {
        rms: (se / n as f64).sqrt(),
        pointwise: inside[0] as f64 / n as f64,
        simultaneous: inside[1] as f64 / n as f64,
    }
}

fn temp_dir(tag: &str) -> std::path::PathBuf {
    let d = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("ident-{tag}"));
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
    let c = dry(&truth.x.dry_pos, 0.2);
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
    // The issue's "under 10 s" is measured by `cargo bench -p crane-ident --bench campaign`,
    // not asserted here (a wall-clock bound fails on a loaded machine, not on slow code).
    eprintln!("rig {t_rig:.2} s (with CSV writing), load + identify {t_ident:.2} s");

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
            let q = curve_quality(f, tc);
            eprintln!(
                "  {name}{dir}: {} probes, RMS {:.4} N, truth inside the 95 % band over {:.0} % of the axis (pointwise band: {:.0} %), multiplier {:.2}",
                f.positions.len(),
                q.rms,
                100.0 * q.simultaneous,
                100.0 * q.pointwise,
                f.curve.simultaneous_multiplier
            );
            assert!(f.positions.len() <= 15);
            assert!(q.rms < 0.1, "{name}{dir} RMS {}", q.rms);
            assert!(
                q.simultaneous >= 0.9,
                "{name}{dir} inside {}",
                q.simultaneous
            );
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

/// One friction curve: name, axis, direction (`true`: positive), the paper's breakaway noise
/// variance [N^2], axis length [m], true coefficients.
type CurveCase = (&'static str, usize, bool, f64, f64, [f64; 5]);

/// The four friction curves.
fn curves(truth: &Params) -> [CurveCase; 4] {
    [
        ("X+", 0, true, 0.026, 0.505, truth.x.dry_pos),
        ("X-", 0, false, 0.0073, 0.505, truth.x.dry_neg),
        ("Y+", 1, true, 0.003, 0.625, truth.y.dry_pos),
        ("Y-", 1, false, 0.0056, 0.625, truth.y.dry_neg),
    ]
}

/// Probes a synthetic truth with Gaussian noise of variance `var` (exact model, known
/// noise): by active learning or on a uniform grid of the same size.
fn synthetic_fit(active: bool, seed: u64, var: f64, truth: &[f64; 5], range: f64) -> Blr {
    let opt = BlrOptions::default();
    let mut rng = Rng::new(seed);
    let mut noise = Rng::new(seed ^ 0xABCD);
    let mut blr = Blr::new(0.0, range, opt.degree, opt.prior_std, var);
    let mut measure =
        |p: f64| -> Result<(f64, f64), ()> { Ok((dry(truth, p) + var.sqrt() * noise.normal(), p)) };
    if active {
        active_learning(&mut blr, &opt, &mut rng, &mut measure).unwrap();
    } else {
        for p in linspace(opt.margin, range - opt.margin, opt.budget) {
            let (y, at) = measure(p).unwrap();
            blr.add(at, y);
        }
    }
    assert_eq!(blr.xs.len(), opt.budget);
    blr
}

#[test]
fn active_learning_beats_a_uniform_grid_of_the_same_size() {
    // The acquisition does not depend on the measured values, so this is the design
    // question alone; the uniform grid is the same design on every seed.
    let truth = Params::default();
    let seeds = 100;
    for (name, _, _, var, range, tc) in curves(&truth) {
        let grid = linspace(0.0, range, 201);
        let uniform = synthetic_fit(false, 0, var, &tc, range).max_std(&grid);
        let mut wins = 0;
        let mut sum = 0.0;
        for seed in 0..seeds {
            let al = synthetic_fit(true, seed, var, &tc, range).max_std(&grid);
            sum += al;
            wins += (al < uniform) as usize;
        }
        let mean = sum / seeds as f64;
        eprintln!(
            "{name} ({var} N^2), 15 probes: max predictive std active {mean:.4} N (mean of {seeds} seeds) vs uniform grid {uniform:.4} N; active lower in {wins}/{seeds}"
        );
        assert!(mean < uniform, "{name}");
        // not on every seed: the random first probe sometimes leads to a worse design
        assert!(wins as f64 >= 0.7 * seeds as f64, "{name}: {wins}");
    }
}

#[test]
fn pointwise_bands_miss_the_range_criterion_and_simultaneous_bands_meet_it() {
    // The cause of "truth inside the 95 % band over >= 90 % of the axis" failing on some
    // curves: with an exact model and the exact noise variance (no bias anywhere) the
    // pointwise band is calibrated (mean coverage 95 %) yet holds the truth over >= 90 % of
    // the axis in only ~83 % of realisations, because the errors of a 5-coefficient fit are
    // correlated along the axis. The simultaneous band is calibrated for the whole axis.
    let truth = Params::default();
    let seeds = 250u64;
    let (mut n, mut pw_mean, mut pw_ok, mut sim_ok, mut sim_whole) = (0, 0.0, 0, 0, 0);
    for (ci, (name, _, _, var, range, tc)) in curves(&truth).into_iter().enumerate() {
        let mut ok = [0usize; 2];
        for seed in 0..seeds {
            // independent realisations per curve
            let blr = synthetic_fit(true, 1000 * (ci as u64 + 1) + seed, var, &tc, range);
            let fit = crane_ident::identify::dry_fit_from(&blr, var, 101);
            let q = curve_quality(&fit, &tc);
            n += 1;
            pw_mean += q.pointwise;
            ok[0] += (q.pointwise >= 0.9) as usize;
            ok[1] += (q.simultaneous >= 0.9) as usize;
            sim_whole += (q.simultaneous == 1.0) as usize;
        }
        eprintln!(
            "{name}: truth inside over >= 90 % of the axis in {}/{seeds} realisations with the pointwise band, {}/{seeds} with the simultaneous band",
            ok[0], ok[1]
        );
        pw_ok += ok[0];
        sim_ok += ok[1];
    }
    let f = |k: usize| k as f64 / n as f64;
    eprintln!(
        "{n} realisations: pointwise mean coverage {:.1} %, pointwise >= 90 % of the axis in {:.1} %; simultaneous >= 90 % in {:.1} %, whole axis in {:.1} %",
        100.0 * pw_mean / n as f64,
        100.0 * f(pw_ok),
        100.0 * f(sim_ok),
        100.0 * f(sim_whole)
    );
    // pointwise: calibrated on average, but short of the range criterion
    assert!((pw_mean / n as f64 - 0.95).abs() < 0.015);
    assert!(f(pw_ok) < 0.9);
    // simultaneous: meets it, and holds the whole curve about 95 % of the time (the tube
    // formula is slightly conservative), so it is not wider than its meaning asks
    assert!(f(sim_ok) >= 0.95);
    assert!(f(sim_whole) >= 0.93 && f(sim_whole) <= 0.99);
}

#[test]
fn friction_curves_over_several_seeds_on_the_virtual_rig() {
    // The breakaway stage of several campaigns (active learning against the virtual rig,
    // the paper's scatter, onsets corrected for the detection lag): all four curves per seed.
    let truth = Params::default();
    let seeds = 8u64;
    let (mut n, mut rms_ok, mut sim_ok, mut pw_sum) = (0, 0, 0, 0.0);
    let mut seeds_all_four = 0;
    for seed in 0..seeds {
        let mut rig = VirtualRig::new(
            truth,
            PlantConfig {
                seed: 100 + seed,
                ..PlantConfig::default()
            },
        );
        let mut rng = Rng::new(seed);
        let opt = IdentOptions::default();
        let mut line = format!("seed {seed}:");
        let mut all_four = true;
        for (name, axis, pos, var, range, tc) in curves(&truth) {
            let ax = if axis == 0 { &truth.x } else { &truth.y };
            let mut blr = Blr::new(0.0, range, 4, opt.blr.prior_std, var);
            let (k, d) = (ax.gain, if pos { ax.viscous_pos } else { ax.viscous_neg });
            let m = ax.inertia + truth.trolley_mass + if axis == 0 { truth.rail_mass } else { 0.0 };
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
            assert!(blr.xs.len() <= 15);
            let fit = crane_ident::identify::dry_fit_from(&blr, var, 101);
            let q = curve_quality(&fit, &tc);
            line += &format!(
                " {name} RMS {:.3} N, inside {:.0} % (pointwise {:.0} %);",
                q.rms,
                100.0 * q.simultaneous,
                100.0 * q.pointwise
            );
            n += 1;
            rms_ok += (q.rms < 0.1) as usize;
            sim_ok += (q.simultaneous >= 0.9) as usize;
            all_four &= q.simultaneous >= 0.9;
            pw_sum += q.pointwise;
        }
        seeds_all_four += all_four as usize;
        eprintln!("{line}");
    }
    eprintln!(
        "{n} curves: RMS < 0.1 N in {rms_ok}, truth inside the 95 % band over >= 90 % of the axis in {sim_ok}, all four curves in {seeds_all_four}/{seeds} seeds; pointwise mean coverage {:.1} %",
        100.0 * pw_sum / n as f64
    );
    // per curve the simultaneous band meets the criterion with probability ~0.985 (previous
    // test); allow one miss in 32
    assert!(sim_ok + 1 >= n, "{sim_ok}/{n}");
    // X+ (sigma 0.16 N, 15 probes) is within 0.1 N RMS in ~83 % of realisations; the
    // others always
    assert!(rms_ok as f64 >= 0.9 * n as f64, "{rms_ok}/{n}");
    // the pointwise band stays calibrated on the rig data too
    assert!((pw_sum / n as f64 - 0.95).abs() < 0.04);
}

#[test]
fn lag_corrected_breakaway_probes_are_unbiased() {
    // Not a cause of band misses: without probe scatter, the lag-corrected breakaway force
    // equals the true friction to well under a millinewton at every position (the raw
    // onset, seen one encoder count late, reads ~0.02 N high).
    let truth = Params::default();
    let cfg = PlantConfig {
        breakaway_noise: None,
        ..PlantConfig::default()
    };
    let mut rig = VirtualRig::new(truth, cfg);
    for (name, axis, pos, _, range, tc) in curves(&truth) {
        let ax = if axis == 0 { &truth.x } else { &truth.y };
        let (k, d) = (ax.gain, if pos { ax.viscous_pos } else { ax.viscous_neg });
        let m = ax.inertia + truth.trolley_mass + if axis == 0 { truth.rail_mass } else { 0.0 };
        let res = rig.resolution(axis);
        let n = 30;
        let (mut worst, mut bias, mut raw_bias) = (0.0f64, 0.0, 0.0);
        for i in 0..n {
            let p = 0.005 + (range - 0.01) * (i as f64 + 0.37) / n as f64;
            let r = rig.breakaway(&Probe::new(axis, pos, p)).unwrap();
            let on = corrected_onset(&r.run, axis, res, d / k, m / d).unwrap();
            let t = dry(&tc, on.position);
            let e = k * on.volts.abs() - t;
            worst = worst.max(e.abs());
            bias += e / n as f64;
            raw_bias += (k * r.onset.unwrap().volts.abs() - t) / n as f64;
        }
        eprintln!(
            "{name}: lag-corrected probe error mean {bias:.5} N, largest {worst:.5} N; raw onset mean error {raw_bias:.4} N"
        );
        assert!(worst < 1e-3, "{name}: {worst}");
        assert!(raw_bias > 0.01, "{name}: {raw_bias}");
    }
}

//! The single-axis pipeline (EMPS-like data): inverse-dynamics least squares of the baseline
//! and of every candidate extension on the fitting part, scored on the held-out part.
//!
//! Processing is the EMPS benchmark's IDIM-LS: zero-phase Butterworth (order 4, cut-off a tenth
//! of the sampling rate: 100 Hz at 1 kHz), central differences, 49 samples dropped, every
//! column and the force decimated by 10. The measure is the force: `nmae_*` is the mean absolute
//! force error over the held-out force range [%], and the published relative force error
//! `100 ||F - F_model|| / ||F||` is reported in `measures`.

use crate::fit::{bump_shape, deadband, delta_bic, ls, ls_weighted, mae, residual, sse};
use crate::{
    split_runs, AxisError, Baseline, Candidate, Cause, DiagnoseError, DiagnoseOptions, Evidence,
    Finding, Report, Verdict, FIT_FRACTION,
};
use crane_ident::data::{AxisRun, Dataset};
use crane_ident::emps::{process, IdimOptions};
use crane_ident::signal::decimate;
use std::collections::BTreeMap;

/// Held-out force BIC change needed for support.
pub const FORCE_BIC_MAX: f64 = -10.0;
/// Minimal relative cut of the held-out force SSE, and of the held-out force NMAE, for support.
pub const MIN_CUT: f64 = 0.02;

#[derive(Default, Clone)]
struct Part {
    q: Vec<f64>,
    v: Vec<f64>,
    a: Vec<f64>,
    f: Vec<f64>,
    /// force delayed by m samples, m = 0..MAXD (index m)
    fd: Vec<Vec<f64>>,
    /// force before decimation (for the dead band)
    u: Vec<f64>,
    /// full-rate length of every appended run segment: columns are decimated run by run,
    /// like the force, so they stay aligned whatever the run lengths
    lens: Vec<usize>,
}

const MAXD: usize = 12;

/// Bootstrap replicates of every candidate's held-out cut (`bootstrap_cuts`).
pub const BOOT_REPS: usize = 400;
/// Contiguous blocks the fitting rows and the held-out rows are each cut into for the
/// bootstrap: long enough (a twentieth of the rows) to carry the residual's serial
/// correlation after the derivative filter.
pub const BOOT_BLOCKS: usize = 20;
/// One-sided level of the bootstrap test: a finding's cut is positive in at least
/// `1 - BOOT_LEVEL` of the replicates. Not divided among the candidates (Bonferroni): the
/// bootstrap is already conservative where the baseline extrapolates (a replicate that leaves
/// a position range unfitted blows both errors up), and at 1.25 % a real 3-sample delay on
/// the closed-loop PD rig (held-out cut 85 %, positive in 380-400 of 400 replicates) was lost
/// on 3 of 9 draws; the rig with nothing hidden stays below 78 % on all 9.
pub const BOOT_LEVEL: f64 = 0.05;

/// Shortest stretch at rest that is cut out of the inverse-dynamics rows [s]: far longer than
/// a reversal takes (EMPS has none over 7 ms), so only an axis that really holds still is cut.
pub const REST_MIN_S: f64 = 0.2;

/// The moving parts of `range`: the run without its stretches at rest (the position stays
/// within two encoder steps over +-0.05 s, for at least [`REST_MIN_S`] and 20 samples).
/// A resting axis carries no sign of velocity for the least squares: its force only says
/// that friction held it, which the inverse-dynamics rows cannot express. Moving parts too
/// short for the zero-phase filter (`< 4 drop_start + 50` samples) are left out too.
fn moving_parts(
    run: &AxisRun,
    range: std::ops::Range<usize>,
    opt: &IdimOptions,
) -> Vec<std::ops::Range<usize>> {
    let x = &run.x[range.clone()];
    let n = x.len();
    let dt = run.dt();
    let quantum = x
        .windows(2)
        .map(|w| (w[1] - w[0]).abs())
        .filter(|d| *d > 0.0)
        .fold(f64::INFINITY, f64::min);
    if n == 0 || !quantum.is_finite() || dt.is_nan() || dt <= 0.0 {
        return vec![range];
    }
    let k = ((0.05 / dt).round() as usize).max(5);
    let still: Vec<bool> = (0..n)
        .map(|i| {
            let w = &x[i.saturating_sub(k)..(i + k + 1).min(n)];
            let (lo, hi) = w
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| {
                    (l.min(v), h.max(v))
                });
            hi - lo <= 2.0 * quantum
        })
        .collect();
    let min_rest = ((REST_MIN_S / dt).ceil() as usize).max(20);
    let min_part = 4 * opt.drop_start + 50;
    let mut parts = Vec::new();
    let mut start = 0usize;
    let mut i = 0usize;
    while i < n {
        if still[i] {
            let j = (i..n).find(|&j| !still[j]).unwrap_or(n);
            if j - i >= min_rest {
                // the +-k window: the k samples on either side of the still stretch lie within
                // two encoder steps of it too, so they rest as well
                let (a, b) = (i.saturating_sub(k), (j + k).min(n));
                if a > start && a - start >= min_part {
                    parts.push(range.start + start..range.start + a);
                }
                start = b;
            }
            i = j;
        } else {
            i += 1;
        }
    }
    if n - start >= min_part {
        parts.push(range.start + start..range.start + n);
    }
    parts
}

fn append(part: &mut Part, run: &AxisRun, range: std::ops::Range<usize>, opt: &IdimOptions) {
    for piece in moving_parts(run, range, opt) {
        append_part(part, run, piece, opt);
    }
}

fn append_part(part: &mut Part, run: &AxisRun, range: std::ops::Range<usize>, opt: &IdimOptions) {
    let sub = run.slice(range);
    let p = process(&sub, opt);
    let r = opt.decimation;
    part.q.extend(&p.q);
    part.v.extend(&p.qd);
    part.a.extend(&p.qdd);
    part.f.extend(decimate(&p.force, r));
    if part.fd.is_empty() {
        part.fd = vec![Vec::new(); MAXD + 1];
    }
    let s = opt.drop_start.min(sub.force.len());
    for m in 0..=MAXD {
        let d: Vec<f64> = (s..sub.force.len())
            .map(|k| sub.force[k.saturating_sub(m)])
            .collect();
        part.fd[m].extend(decimate(&d, r));
    }
    part.u.extend(&sub.force[s..]);
    part.lens.push(p.q.len());
}

/// Columns are built at the full rate and decimated like the force (the IDIM-LS order), run
/// by run.
fn dec(p: &Part, c: Vec<f64>) -> Vec<f64> {
    let r = IdimOptions::default().decimation;
    let mut out = Vec::with_capacity(c.len() / r.max(1) + p.lens.len());
    let mut at = 0;
    for &n in &p.lens {
        let end = (at + n).min(c.len());
        out.extend(decimate(&c[at..end], r));
        at = end;
    }
    out
}

fn base_cols(p: &Part, sym: bool, mid: f64, half: f64) -> Vec<Vec<f64>> {
    base_cols_full(p, sym, mid, half)
        .into_iter()
        .map(|c| dec(p, c))
        .collect()
}

fn base_cols_full(p: &Part, sym: bool, mid: f64, half: f64) -> Vec<Vec<f64>> {
    let ind = |pos: bool| -> Vec<f64> {
        p.v.iter()
            .map(|&v| {
                if pos && v > 0.0 {
                    1.0
                } else if !pos && v < 0.0 {
                    -1.0
                } else {
                    0.0
                }
            })
            .collect()
    };
    if sym {
        // the published symmetric model: M qdd + Fv qd + Fc sign(qd) + offset
        return vec![
            p.a.clone(),
            p.v.clone(),
            p.v.iter()
                .map(|&v| if v == 0.0 { 0.0 } else { v.signum() })
                .collect(),
            vec![1.0; p.v.len()],
        ];
    }
    let mut c = vec![
        p.a.clone(),
        p.v.iter().map(|&v| v.max(0.0)).collect(),
        p.v.iter().map(|&v| v.min(0.0)).collect(),
    ];
    for pos in [true, false] {
        let i = ind(pos);
        for j in 0..5 {
            c.push(
                i.iter()
                    .zip(&p.q)
                    .map(|(s, q)| s * ((q - mid) / half).powi(j))
                    .collect(),
            );
        }
    }
    c
}

struct Cand {
    cause: Cause,
    params: BTreeMap<String, f64>,
    k: usize,
    sse_h: f64,
    mae_h: f64,
    sse_f: f64,
    design: Design,
}

/// A candidate's extra columns and targets on the fitting (`f`) and held-out (`h`) rows.
struct Design {
    ef: Vec<Vec<f64>>,
    eh: Vec<Vec<f64>>,
    yf: Vec<f64>,
    yh: Vec<f64>,
}

/// A least-squares fit on the fitting part, scored on the held-out part.
struct Fitted {
    sse_h: f64,
    mae_h: f64,
    sse_f: f64,
    theta: Vec<f64>,
}

/// Diagnoses single-axis runs.
pub fn diagnose_axis(ds: &Dataset, opts: &DiagnoseOptions) -> Result<Report, DiagnoseError> {
    let runs: Vec<_> = ds.runs.iter().filter(|r| r.axis().is_some()).collect();
    let kinds: Vec<_> = runs.iter().map(|r| r.kind).collect();
    let (split, split_doc) = split_runs(&kinds);
    let (sym, base_doc) = match &opts.baseline {
        Baseline::Symmetric => (
            true,
            "symmetric Coulomb + viscous `M qdd + Fv qd + Fc sign(qd)` fitted on the fitting part"
                .to_string(),
        ),
        Baseline::Params(_) => {
            return Err(DiagnoseError::Input(
                "crane parameters cannot be the baseline of single-axis data".into(),
            ))
        }
        _ => (
            false,
            "the paper's structure fitted on the fitting part: inertia, viscous per direction, dry friction per direction as a quartic in position".to_string(),
        ),
    };
    let mut fit = Part::default();
    let mut held = Part::default();
    let mut dt = 0.001;
    for (r, s) in runs.iter().zip(&split) {
        let Some(a) = r.axis() else { continue };
        dt = a.dt();
        let opt = IdimOptions {
            cutoff_hz: 0.1 / dt,
            ..IdimOptions::default()
        };
        let n = a.t.len();
        match s {
            Some(true) => append(&mut held, a, 0..n, &opt),
            Some(false) => append(&mut fit, a, 0..n, &opt),
            None => {
                let cut = (FIT_FRACTION * n as f64) as usize;
                append(&mut fit, a, 0..cut, &opt);
                append(&mut held, a, cut..n, &opt);
            }
        }
    }
    if fit.f.len() < 50 || held.f.len() < 50 {
        return Err(DiagnoseError::Input("too few single-axis samples".into()));
    }
    let lo = fit.q.iter().cloned().fold(f64::INFINITY, f64::min);
    let hi = fit.q.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    let (mid, half) = (0.5 * (lo + hi), (0.5 * (hi - lo)).max(1e-6));
    let bf = base_cols(&fit, sym, mid, half);
    let bh = base_cols(&held, sym, mid, half);
    let gain = ds.runs.first().and(ds.spec.gain_n_per_v).unwrap_or(1.0);
    // evaluates baseline + extra columns, with target `yf` / `yh`
    let eval = |ef: &[Vec<f64>], eh: &[Vec<f64>], yf: &[f64], yh: &[f64]| -> Option<Fitted> {
        let cf: Vec<&[f64]> = bf.iter().chain(ef).map(|c| c.as_slice()).collect();
        let ch: Vec<&[f64]> = bh.iter().chain(eh).map(|c| c.as_slice()).collect();
        let th = ls(&cf, yf)?;
        Some(Fitted {
            sse_h: sse(&ch, &th, yh),
            mae_h: mae(&ch, &th, yh),
            sse_f: sse(&cf, &th, yf),
            theta: th,
        })
    };
    // the extra columns `ef` / `eh` on the measured force: the design and its fit
    let fit_extra = |ef: Vec<Vec<f64>>, eh: Vec<Vec<f64>>| -> (Design, Option<Fitted>) {
        let design = Design {
            ef,
            eh,
            yf: fit.f.clone(),
            yh: held.f.clone(),
        };
        let r = eval(&design.ef, &design.eh, &design.yf, &design.yh);
        (design, r)
    };
    // the coefficient of the last extra column (0 without a fit)
    let last_coef = |r: &Option<Fitted>| {
        r.as_ref()
            .and_then(|x| x.theta.last().copied())
            .unwrap_or(0.0)
    };
    let base0 = eval(&[], &[], &fit.f, &held.f)
        .ok_or_else(|| DiagnoseError::Model("baseline least squares failed".into()))?;
    let (sse0, mae0, ssef0, th0) = (base0.sse_h, base0.mae_h, base0.sse_f, base0.theta.clone());
    let fnorm_h: f64 = held.f.iter().map(|x| x * x).sum();
    let fnorm_f: f64 = fit.f.iter().map(|x| x * x).sum();
    let hrange = held.f.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
        - held.f.iter().cloned().fold(f64::INFINITY, f64::min);
    let mut cands: Vec<Cand> = Vec::new();
    let mut push = |cause: Cause,
                    params: BTreeMap<String, f64>,
                    k: usize,
                    design: Design,
                    r: Option<Fitted>| {
        if let Some(r) = r {
            cands.push(Cand {
                cause,
                params,
                k,
                design,
                sse_h: r.sse_h,
                mae_h: r.mae_h,
                sse_f: r.sse_f,
            });
        }
    };
    let pm = |v: &[(&str, f64)]| -> BTreeMap<String, f64> {
        v.iter().map(|(k, x)| (k.to_string(), *x)).collect()
    };
    // localized friction: grid on the fitting part
    {
        let col = |p: &Part, c: f64, w: f64, d: i32| -> Vec<f64> {
            p.q.iter()
                .zip(&p.v)
                .map(|(&q, &v)| {
                    let on = d == 0 || (d > 0 && v > 0.0) || (d < 0 && v < 0.0);
                    if on && v != 0.0 {
                        v.signum() * bump_shape(q, c, w)
                    } else {
                        0.0
                    }
                })
                .collect::<Vec<f64>>()
        };
        let col = |p: &Part, c: f64, w: f64, d: i32| dec(p, col(p, c, w, d));
        let mut best: Option<(f64, f64, f64, i32)> = None;
        let step = (hi - lo) / 30.0;
        for wi in [0.02, 0.04, 0.08, 0.15] {
            let w = wi * (hi - lo);
            let mut c = lo;
            while c <= hi {
                for d in [0, 1, -1] {
                    if let Some(Fitted { sse_f: sf, .. }) = eval(
                        &[col(&fit, c, w, d)],
                        &[col(&held, c, w, d)],
                        &fit.f,
                        &held.f,
                    ) {
                        if best.is_none_or(|b| sf < b.0) {
                            best = Some((sf, c, w, d));
                        }
                    }
                }
                c += step;
            }
        }
        if let Some((_, c, w, d)) = best {
            let (design, r) = fit_extra(vec![col(&fit, c, w, d)], vec![col(&held, c, w, d)]);
            let amp = last_coef(&r);
            push(
                Cause::LocalizedFriction,
                pm(&[
                    ("center_m", c),
                    ("width_m", w),
                    ("amplitude_n", amp),
                    ("direction", d as f64),
                ]),
                3,
                design,
                r,
            );
        }
    }
    // causes whose best fit is unphysical (reported as unsupported candidates)
    let mut not_physical: Vec<Cause> = Vec::new();
    // stiction
    {
        let col = |p: &Part, vs: f64| -> Vec<f64> {
            dec(
                p,
                p.v.iter()
                    .map(|&v| {
                        if v == 0.0 {
                            0.0
                        } else {
                            v.signum() * (-(v / vs) * (v / vs)).exp()
                        }
                    })
                    .collect(),
            )
        };
        let vmax = fit.v.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        let mut best: Option<(f64, f64)> = None;
        for j in 0..12 {
            let vs = vmax * 0.002 * 1.6_f64.powi(j);
            if let Some(Fitted { sse_f: sf, .. }) =
                eval(&[col(&fit, vs)], &[col(&held, vs)], &fit.f, &held.f)
            {
                if best.is_none_or(|b| sf < b.0) {
                    best = Some((sf, vs));
                }
            }
        }
        if let Some((_, vs)) = best {
            let (design, r) = fit_extra(vec![col(&fit, vs)], vec![col(&held, vs)]);
            let amp = last_coef(&r);
            let fc = if sym { th0[2] } else { 0.5 * (th0[3] + th0[8]) };
            // stiction is breakaway ABOVE sliding friction: a negative excess (ratio < 1)
            // is not stiction and is not offered as a finding
            if amp > 0.0 {
                push(
                    Cause::Stiction,
                    pm(&[
                        ("ratio", 1.0 + amp / fc.abs().max(1e-9)),
                        ("velocity_m_per_s", vs),
                        ("breakaway_excess_n", amp),
                    ]),
                    2,
                    design,
                    r,
                );
            } else {
                not_physical.push(Cause::Stiction);
            }
        }
    }
    let mut not_ident: Vec<Cause> = Vec::new();
    if sym {
        let cols = |p: &Part| {
            vec![
                dec(p, p.v.iter().map(|&v| v.max(0.0)).collect::<Vec<f64>>()),
                dec(
                    p,
                    p.v.iter()
                        .map(|&v| if v > 0.0 { 1.0 } else { 0.0 })
                        .collect(),
                ),
            ]
        };
        let (design, r) = fit_extra(cols(&fit), cols(&held));
        let th = r.as_ref().map(|x| x.theta.clone()).unwrap_or_default();
        if th.len() == 6 {
            // baseline a, Fv, Fc, offset o; extras a' (v+), b (ind+):
            // Fv+ = Fv + a', Fv- = Fv; the constant force moving positive Fc + o + b, moving
            // negative Fc - o (the offset is not separable from direction-dependent dry
            // friction: the two dry levels include it)
            push(
                Cause::DirectionAsymmetry,
                pm(&[
                    ("viscous_pos_n_s_per_m", th[1] + th[4]),
                    ("viscous_neg_n_s_per_m", th[1]),
                    ("dry_pos_n", th[2] + th[3] + th[5]),
                    ("dry_neg_n", th[2] - th[3]),
                ]),
                2,
                design,
                r,
            );
        }
        // the symmetric baseline already carries the published offset
        not_ident.push(Cause::ForceOffset);
    } else {
        not_ident.push(Cause::ForceOffset);
        not_ident.push(Cause::DirectionAsymmetry);
    }
    // input delay: the force acts m samples later
    {
        let mut best: Option<(f64, usize)> = None;
        // 0 is on the grid: no delay at all may fit best
        for m in 0..=MAXD {
            if let Some(Fitted { sse_f: sf, .. }) = eval(&[], &[], &fit.fd[m], &held.fd[m]) {
                if best.is_none_or(|b| sf < b.0) {
                    best = Some((sf, m));
                }
            }
        }
        // One sample is not named: the recorded input is held over each sample (zero-order
        // hold) while the central-difference acceleration at a sample spans the inputs before
        // and after it, so the data put the force half a sample late whatever the rig does,
        // and 0 and 1 fit alike up to the filter's and the controller's noise (a simulated PD
        // loop without any delay "finds" one sample).
        if let Some((_, m)) = best.filter(|b| b.1 > 1) {
            push(
                Cause::InputDelay,
                pm(&[("delay_s", m as f64 * dt)]),
                1,
                Design {
                    ef: Vec::new(),
                    eh: Vec::new(),
                    yf: fit.fd[m].clone(),
                    yh: held.fd[m].clone(),
                },
                eval(&[], &[], &fit.fd[m], &held.fd[m]),
            );
        }
    }
    // input dead band [V] (force / gain)
    {
        let dz = |p: &Part, d: f64| -> Vec<f64> {
            dec(
                p,
                p.u.iter().map(|&f| gain * deadband(f / gain, d)).collect(),
            )
        };
        let umax = fit.u.iter().fold(0.0_f64, |m, v| m.max(v.abs())) / gain;
        let mut best: Option<(f64, f64)> = None;
        for j in 1..=30 {
            let d = umax * 0.005 * j as f64;
            if let Some(Fitted { sse_f: sf, .. }) = eval(&[], &[], &dz(&fit, d), &dz(&held, d)) {
                if best.is_none_or(|b| sf < b.0) {
                    best = Some((sf, d));
                }
            }
        }
        if let Some((_, d)) = best {
            push(
                Cause::InputDeadzone,
                pm(&[("deadzone_v", d)]),
                1,
                Design {
                    ef: Vec::new(),
                    eh: Vec::new(),
                    yf: dz(&fit, d),
                    yh: dz(&held, d),
                },
                eval(&[], &[], &dz(&fit, d), &dz(&held, d)),
            );
        }
    }
    not_ident.push(Cause::PayloadMass);
    let n_h = held.f.len();
    let mut scored: Vec<(Cand, f64)> = cands
        .into_iter()
        .map(|c| {
            let b = delta_bic(n_h, sse0, c.sse_h, c.k);
            (c, b)
        })
        .collect();
    scored.sort_by(|a, b| a.1.total_cmp(&b.1));
    // the noise floor of every cut: its one-sided bootstrap lower bound
    let level = BOOT_LEVEL;
    let lower: Vec<f64> = scored
        .iter()
        .map(|(c, _)| {
            let cuts = bootstrap_cuts(&bf, &bh, &fit.f, &held.f, &c.design, BOOT_REPS, BOOT_BLOCKS);
            quantile(cuts, level)
        })
        .collect();
    let mut findings = Vec::new();
    let mut candidates = Vec::new();
    let mut measures = BTreeMap::new();
    for ((c, b), low) in scored.iter().zip(&lower) {
        // a finding must also cut the held-out force NMAE it reports, by as much: with many
        // samples a BIC gain and a squared-error cut are easy for a one-parameter grid search
        // that only reshapes the noise (a PD loop's quantised velocity feedback "found" a
        // 0.009 V dead band that left the NMAE at 0.23 %)
        // and its cut must stand above the noise floor of the estimate: positive in the
        // bootstrap's lower tail ([`bootstrap_cuts`]). The held-out error alone does not
        // suffice: on a closed loop's few fitting runs the baseline's per-direction position
        // polynomial extrapolates, and any extra column that moves it cuts one held-out run
        // by chance (a PD rig with nothing hidden "found" a dead band, stiction, localized
        // friction or a delay on 4 of 9 input draws, cuts of 5-35 % that the bootstrap puts
        // at chance: positive in 60-78 % of the replicates).
        measures.insert(format!("bootstrap_cut_lower_{}", c.cause), *low);
        let ok = *b < FORCE_BIC_MAX
            && c.sse_h < (1.0 - MIN_CUT) * sse0
            && c.mae_h < (1.0 - MIN_CUT) * mae0
            && *low > 0.0;
        candidates.push(Candidate {
            cause: c.cause,
            axis: "axis".into(),
            parameters: c.params.clone(),
            score: b / n_h as f64,
            force_delta_bic: *b,
            supported: ok,
        });
        if ok {
            let (identifiable, note) = match c.cause {
                Cause::ForceOffset => (false, "a constant offset is exactly a shift of the two dry-friction magnitudes (Fc+ by -b, Fc- by +b): not identifiable apart from direction-dependent dry friction".to_string()),
                Cause::DirectionAsymmetry => (true, "the dry part of the asymmetry overlaps a force offset; the viscous part does not".to_string()),
                _ => (true, String::new()),
            };
            let note = format!(
                "{}{}held-out NMAE cut {:.1} %, bootstrap lower bound {:.1} % ({BOOT_REPS} block replicates, one-sided level {:.3})",
                note,
                if note.is_empty() { "" } else { "; " },
                100.0 * (1.0 - c.mae_h / mae0),
                100.0 * low,
                level
            );
            findings.push(Finding {
                cause: c.cause,
                axis: "axis".into(),
                parameters: c.params.clone(),
                nmae_before: 100.0 * mae0 / hrange,
                nmae_after: 100.0 * c.mae_h / hrange,
                evidence: Evidence {
                    force_delta_bic: *b,
                    force_rms_before_n: (sse0 / n_h as f64).sqrt(),
                    force_rms_after_n: (c.sse_h / n_h as f64).sqrt(),
                    score: b / n_h as f64,
                    extra_parameters: c.k,
                    held_out_samples: n_h,
                    identifiable,
                    note,
                },
            });
        }
    }
    for c in not_physical.into_iter().chain(not_ident) {
        candidates.push(Candidate {
            cause: c,
            axis: "axis".into(),
            parameters: BTreeMap::new(),
            score: 0.0,
            force_delta_bic: 0.0,
            supported: false,
        });
    }
    measures.insert(
        "force_rel_err_fit_pct".into(),
        100.0 * (ssef0 / fnorm_f).sqrt(),
    );
    measures.insert(
        "force_rel_err_held_out_pct".into(),
        100.0 * (sse0 / fnorm_h).sqrt(),
    );
    if let Some(f) = scored.first() {
        measures.insert(
            "force_rel_err_fit_after_pct".into(),
            100.0 * (f.0.sse_f / fnorm_f).sqrt(),
        );
        measures.insert(
            "force_rel_err_held_out_after_pct".into(),
            100.0 * (f.0.sse_h / fnorm_h).sqrt(),
        );
    }
    if closed_loop_measures(ds, &runs, &split, opts, &mut measures)? {
        // the EMPS benchmark's published figures, next to ours (only for the EMPS runs)
        measures.insert("published_symmetric_cross_test_pct".into(), 5.98);
        measures.insert("published_direction_dependent_fit_pct".into(), 3.11);
        measures.insert("published_sim_force_err_estimation_pct".into(), 5.85);
        measures.insert("published_sim_force_err_validation_pct".into(), 8.94);
    }
    // the baseline's worst held-out force error [%] over the inverse model and, where a
    // controller is declared, the closed-loop simulations
    let no_fit_pct = measures
        .iter()
        .filter(|(k, _)| k.starts_with("closed_loop_force_err_held_out_"))
        .map(|(_, v)| *v)
        .fold(100.0 * (sse0 / fnorm_h).sqrt(), f64::max);
    let (verdict, reason) = match findings.first() {
        Some(f) => (
            Verdict::Found(f.cause),
            format!(
                "{} cuts the held-out force NMAE from {:.3} % to {:.3} %",
                f.cause, f.nmae_before, f.nmae_after
            ),
        ),
        // `none` only when the baseline fits: a held-out force error at or above the
        // force itself (what predicting zero force scores), by the inverse model or in the
        // declared closed loop, is no fit at all (a wrong gain or unit); with nothing found
        // that is unexplained
        None if no_fit_pct >= 100.0 => (
            Verdict::Unexplained,
            format!(
                "the baseline does not fit: its held-out force error is {no_fit_pct:.0} % of \
                 the force (predicting zero force scores 100 %); check the gain and the \
                 units; no candidate explains it"
            ),
        ),
        None => (
            Verdict::None,
            "no candidate improves the held-out force residual beyond the penalty".into(),
        ),
    };
    let baseline_errors = vec![AxisError {
        axis: "axis".into(),
        nmae_fit: f64::NAN,
        nmae_held_out: 100.0 * mae0 / hrange,
        nmae_noise: 0.0,
        nmae_own_log: None,
        force_rms_fit_n: (ssef0 / fit.f.len() as f64).sqrt(),
        force_rms_held_out_n: (sse0 / n_h as f64).sqrt(),
        force_rel_err_held_out_pct: 100.0 * (sse0 / fnorm_h).sqrt(),
    }];
    Ok(Report {
        dataset: ds.dir.display().to_string(),
        data: "single_axis".into(),
        baseline: base_doc,
        split: split_doc,
        baseline_errors,
        findings,
        verdict,
        verdict_reason: reason,
        candidates,
        measures,
        heldout_simulation: None,
        final_model: None,
    })
}

/// Closed-loop force errors (the EMPS benchmark's simulation measure), when the runs are EMPS
/// recordings (columns `t, qm, qg, vir`, optionally `pulses_N`) split into one fitting run and
/// held-out runs: the symmetric and the direction-dependent IDIM-LS models, fitted on the
/// fitting run only, simulated in closed loop with the rig's controller
/// ([`crane_ident::emps::Controller::default`]) on each run's reference; relative force error
/// `100 ||F - F_sim|| / ||F||` [%], held-out runs pooled by their mean. With a plots directory,
/// writes `closed_loop_force_{fit,held_out}_<run>_vs_{time,position,velocity}.svg`: the force
/// residual `F - F_sim` [N] of the symmetric model (red) and the direction-dependent one (blue).
fn closed_loop_measures(
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

/// Held-out NMAE cuts `1 - MAE_candidate / MAE_baseline` of a moving-block bootstrap: in each
/// of `reps` replicates the fitting rows and the held-out rows are each cut into `blocks`
/// contiguous blocks resampled with replacement; baseline and candidate are refitted on the
/// resampled fitting rows (weighted least squares) and scored on the resampled held-out rows.
/// The scatter of the cut is the noise floor of the estimate: the baseline's own parameter
/// uncertainty (a position polynomial extrapolated) and the held-out residual's serial
/// correlation both show in it.
fn bootstrap_cuts(
    bf: &[Vec<f64>],
    bh: &[Vec<f64>],
    yf0: &[f64],
    yh0: &[f64],
    d: &Design,
    reps: usize,
    blocks: usize,
) -> Vec<f64> {
    let mut rng = crane_ident::rng::Rng::new(0x6b6f_6f74);
    let weights = |rng: &mut crane_ident::rng::Rng, n: usize| -> Vec<f64> {
        let b = blocks.clamp(1, n.max(1));
        let mut w = vec![0.0; n];
        for _ in 0..b {
            let j = ((rng.uniform() * b as f64) as usize).min(b - 1);
            for x in &mut w[j * n / b..(j + 1) * n / b] {
                *x += 1.0;
            }
        }
        w
    };
    let wmae = |cols: &[&[f64]], th: &[f64], y: &[f64], w: &[f64]| -> f64 {
        residual(cols, th, y)
            .iter()
            .zip(w)
            .map(|(r, w)| w * r.abs())
            .sum()
    };
    let cf0: Vec<&[f64]> = bf.iter().map(|c| c.as_slice()).collect();
    let ch0: Vec<&[f64]> = bh.iter().map(|c| c.as_slice()).collect();
    let cf: Vec<&[f64]> = bf.iter().chain(&d.ef).map(|c| c.as_slice()).collect();
    let ch: Vec<&[f64]> = bh.iter().chain(&d.eh).map(|c| c.as_slice()).collect();
    let mut cuts = Vec::with_capacity(reps);
    for _ in 0..reps {
        let wf = weights(&mut rng, yf0.len());
        let wh = weights(&mut rng, yh0.len());
        let (Some(t0), Some(t1)) = (
            ls_weighted(&cf0, yf0, Some(&wf)),
            ls_weighted(&cf, &d.yf, Some(&wf)),
        ) else {
            cuts.push(f64::NEG_INFINITY);
            continue;
        };
        let m0 = wmae(&ch0, &t0, yh0, &wh);
        let m1 = wmae(&ch, &t1, &d.yh, &wh);
        cuts.push(1.0 - m1 / m0.max(1e-300));
    }
    cuts
}

/// The `p` quantile of `x` (nearest rank, `p` in `[0, 1]`); NaN counts as the lowest.
fn quantile(mut x: Vec<f64>, p: f64) -> f64 {
    if x.is_empty() {
        return f64::NAN;
    }
    for v in &mut x {
        if v.is_nan() {
            *v = f64::NEG_INFINITY;
        }
    }
    x.sort_by(f64::total_cmp);
    let k = ((p * x.len() as f64).floor() as usize).min(x.len() - 1);
    x[k]
}

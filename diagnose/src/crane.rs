//! The crane pipeline: inverse-dynamics residuals per drive, candidate fits in the force
//! domain, held-out simulation of the baseline and of each extension.

use crate::fit::{bump_shape, deadband, delay_half_samples, dry, ls, sse};
use crate::{
    split_runs, AxisError, Baseline, Candidate, Cause, DiagnoseError, DiagnoseOptions, Evidence,
    Finding, Report, Verdict, FIT_FRACTION,
};
use crane_ident::data::{CraneRun, Dataset};
use crane_ident::signal::{butter, diff2_central, diff_central, Filter};
use crane_model::{
    Axis, Bump, Config, Crane, Direction, Extensions, FrictionLaw, Params, State, Stiction,
};
use std::collections::BTreeMap;

/// Axis names of crane data.
pub const AXIS_NAMES: [&str; 3] = ["x", "y", "l"];
/// Zero-phase low-pass cut-off of the positions before differentiation [Hz].
pub const CUTOFF_HZ: f64 = 10.0;
/// Samples kept only when faster than this [m/s] (X, Y, rope).
pub const MIN_SPEED: [f64; 3] = [0.005, 0.005, 0.002];
/// Samples within this time of a slow sample or a reversal are dropped [s].
pub const EXCLUDE_S: f64 = 0.08;
/// Decimation of the masked samples (the filtered residual is correlated over ~fs/(4 fc)).
pub const DECIMATE: usize = 5;
/// Parameter penalty per extra parameter in the simulated-error score.
pub const PENALTY: f64 = 0.03;
/// A cause is supported when its score is below `ln(SUPPORT_RATIO)`.
pub const SUPPORT_RATIO: f64 = 0.8;
/// Held-out force BIC change a cause must reach (besides the simulated score).
pub const FORCE_BIC_MAX: f64 = -10.0;
/// Noise floor of the simulated NMAE, in multiples of the quantisation NMAE.
pub const FLOOR_FACTOR: f64 = 3.0;
/// Verdict `unexplained` when no cause is supported but some axis's held-out NMAE exceeds
/// this many noise floors.
pub const UNEXPLAINED_FLOORS: f64 = 5.0;

/// A fitted extension.
#[derive(Clone, Debug, PartialEq)]
pub enum Ext {
    /// Localised dry-friction bump.
    Bump {
        /// Centre [m].
        center: f64,
        /// Half-width of the support [m].
        width: f64,
        /// Amplitude [N].
        amplitude: f64,
        /// Directions.
        direction: Direction,
    },
    /// Stribeck stiction.
    Stiction {
        /// Breakaway / sliding.
        ratio: f64,
        /// Stribeck velocity [m/s].
        velocity: f64,
    },
    /// Direction-dependent changes of dry magnitude and viscous coefficient.
    Asymmetry {
        /// Added to `dry_pos[0]` [N].
        dry_pos: f64,
        /// Added to `dry_neg[0]` [N].
        dry_neg: f64,
        /// Added to `viscous_pos` [N s/m].
        viscous_pos: f64,
        /// Added to `viscous_neg` [N s/m].
        viscous_neg: f64,
    },
    /// Constant bias force along the axis [N].
    Offset(f64),
    /// Input dead band [V].
    Deadzone(f64),
    /// Input delay [s].
    Delay(f64),
    /// Payload mass change [kg] (true = declared + this).
    Payload(f64),
}

/// The causes tried on crane data (the hidden-effect sweep draws from these).
pub const CRANE_CAUSES: [Cause; 7] = [
    Cause::LocalizedFriction,
    Cause::Stiction,
    Cause::DirectionAsymmetry,
    Cause::ForceOffset,
    Cause::InputDeadzone,
    Cause::InputDelay,
    Cause::PayloadMass,
];

impl Ext {
    /// Reported cause.
    pub fn cause(&self) -> Cause {
        match self {
            Ext::Bump { .. } => Cause::LocalizedFriction,
            Ext::Stiction { .. } => Cause::Stiction,
            Ext::Asymmetry { .. } => Cause::DirectionAsymmetry,
            Ext::Offset(_) => Cause::ForceOffset,
            Ext::Deadzone(_) => Cause::InputDeadzone,
            Ext::Delay(_) => Cause::InputDelay,
            Ext::Payload(_) => Cause::PayloadMass,
        }
    }

    /// Extra parameters.
    pub fn k(&self) -> usize {
        match self {
            Ext::Bump { .. } => 3,
            Ext::Stiction { .. } => 2,
            Ext::Asymmetry { .. } => 4,
            _ => 1,
        }
    }

    /// SI parameters for the report.
    pub fn parameters(&self) -> BTreeMap<String, f64> {
        let mut m = BTreeMap::new();
        let mut put = |k: &str, v: f64| {
            m.insert(k.to_string(), v);
        };
        match *self {
            Ext::Bump {
                center,
                width,
                amplitude,
                direction,
            } => {
                put("center_m", center);
                put("width_m", width);
                put("amplitude_n", amplitude);
                put(
                    "direction",
                    match direction {
                        Direction::Both => 0.0,
                        Direction::Positive => 1.0,
                        Direction::Negative => -1.0,
                    },
                );
            }
            Ext::Stiction { ratio, velocity } => {
                put("ratio", ratio);
                put("velocity_m_per_s", velocity);
            }
            Ext::Asymmetry {
                dry_pos,
                dry_neg,
                viscous_pos,
                viscous_neg,
            } => {
                put("delta_dry_pos_n", dry_pos);
                put("delta_dry_neg_n", dry_neg);
                put("delta_viscous_pos_n_s_per_m", viscous_pos);
                put("delta_viscous_neg_n_s_per_m", viscous_neg);
            }
            Ext::Offset(b) => put("offset_n", b),
            Ext::Deadzone(d) => put("deadzone_v", d),
            Ext::Delay(d) => put("delay_s", d),
            Ext::Payload(dm) => put("delta_mass_kg", dm),
        }
        m
    }

    /// Applies the extension on drive `axis` to the parameters and model extensions.
    pub fn apply(&self, axis: usize, p: &mut Params, ext: &mut Extensions) {
        let ax = [Axis::X, Axis::Y, Axis::Rope][axis.min(2)];
        match *self {
            Ext::Bump {
                center,
                width,
                amplitude,
                direction,
            } => {
                let _ = ext.bumps.push(Bump {
                    axis: ax,
                    center,
                    width,
                    amplitude,
                    direction,
                });
            }
            Ext::Stiction { ratio, velocity } => {
                ext.stiction[axis] = Some(Stiction {
                    ratio: ratio.max(1.0),
                    velocity: velocity.max(1e-6),
                });
            }
            Ext::Asymmetry {
                dry_pos,
                dry_neg,
                viscous_pos,
                viscous_neg,
            } => {
                let a = match axis {
                    0 => &mut p.x,
                    1 => &mut p.y,
                    _ => &mut p.rope,
                };
                a.dry_pos[0] += dry_pos;
                a.dry_neg[0] += dry_neg;
                a.viscous_pos = (a.viscous_pos + viscous_pos).max(0.0);
                a.viscous_neg = (a.viscous_neg + viscous_neg).max(0.0);
            }
            Ext::Offset(b) => ext.force_offset[axis] += b,
            Ext::Deadzone(d) => ext.deadzone[axis] = d.max(0.0),
            Ext::Delay(d) => ext.delay[axis] = d.max(0.0),
            Ext::Payload(dm) => p.payload_mass = (p.payload_mass + dm).max(1e-3),
        }
    }
}

/// One run prepared for the force domain.
struct Prep<'a> {
    run: &'a CraneRun,
    params: Params,
    held: Vec<bool>,
    /// Filtered drive positions and velocities.
    q: [Vec<f64>; 3],
    v: [Vec<f64>; 3],
    /// Residual `K u - [M qdd + h + G] - f` per drive [N].
    r: [Vec<f64>; 3],
    /// Derivative of the drive rows with respect to the payload mass [N/kg].
    phi: [Vec<f64>; 3],
    /// Baseline dry magnitude at the sample, in the direction of motion [N].
    cdry: [Vec<f64>; 3],
    /// Kept samples (moving, away from reversals and edges, decimated).
    keep: [Vec<bool>; 3],
}

fn filt(f: &Filter, x: &[f64]) -> Vec<f64> {
    f.filtfilt(x)
}

/// The recorded voltage as the central differences see it (mean of the two samples that act
/// on the interval), then filtered.
fn drive_series(f: &Filter, u: &[f64]) -> Vec<f64> {
    let shifted: Vec<f64> = (0..u.len())
        .map(|k| 0.5 * (u[k] + u[k.saturating_sub(1)]))
        .collect();
    filt(f, &shifted)
}

fn axis_params(p: &Params, i: usize) -> &crane_model::AxisParams {
    match i {
        0 => &p.x,
        1 => &p.y,
        _ => &p.rope,
    }
}

fn prep<'a>(run: &'a CraneRun, params: Params, held: Vec<bool>) -> Prep<'a> {
    let dt = run.dt();
    let f = butter(4, CUTOFF_HZ * 2.0 * dt);
    let raw = [&run.x, &run.y, &run.l, &run.alpha, &run.beta];
    let qf: Vec<Vec<f64>> = raw.iter().map(|x| filt(&f, x)).collect();
    let vf: Vec<Vec<f64>> = qf.iter().map(|x| diff_central(x, dt)).collect();
    let af: Vec<Vec<f64>> = qf.iter().map(|x| diff2_central(x, dt)).collect();
    let n = run.len();
    let p = &params;
    let mp = p.payload_mass;
    let mx = p.trolley_mass + p.rail_mass + p.x.inertia;
    let my = p.trolley_mass + p.y.inertia;
    let jl = p.rope.inertia;
    let g = p.gravity;
    let mut r: [Vec<f64>; 3] = Default::default();
    let mut phi: [Vec<f64>; 3] = Default::default();
    let mut cdry: [Vec<f64>; 3] = Default::default();
    let uf: Vec<Vec<f64>> = (0..3).map(|i| drive_series(&f, &run.u[i])).collect();
    for k in 0..n {
        let (l, a, b) = (qf[2][k], qf[3][k], qf[4][k]);
        let (ld, ad, bd) = (vf[2][k], vf[3][k], vf[4][k]);
        let (xdd, ydd, ldd, add, bdd) = (af[0][k], af[1][k], af[2][k], af[3][k], af[4][k]);
        let (sa, ca) = a.sin_cos();
        let (sb, cb) = b.sin_cos();
        // rows per unit payload mass
        let hx = -l * ad * ad * sa * sb + 2.0 * l * ad * bd * ca * cb - l * bd * bd * sa * sb
            + 2.0 * ld * ad * sb * ca
            + 2.0 * ld * bd * sa * cb;
        let hy = -ad * (l * ad * ca + 2.0 * ld * sa);
        let hl = -l * (ad * ad + bd * bd * sa * sa);
        let px = xdd + sa * sb * ldd + l * ca * sb * add + l * sa * cb * bdd + hx;
        let py = ydd + ca * ldd - l * sa * add + hy;
        let pl = sa * sb * xdd + ca * ydd + ldd + hl - g * sa * cb;
        let rows = [mx * xdd + mp * px, my * ydd + mp * py, jl * ldd + mp * pl];
        let phis = [px, py, pl];
        for i in 0..3 {
            let ax = axis_params(p, i);
            let (qi, vi) = (qf[i][k], vf[i][k]);
            let (fr, c) = if vi > 0.0 {
                let c = dry(&ax.dry_pos, qi);
                (ax.viscous_pos * vi + c, c)
            } else if vi < 0.0 {
                let c = dry(&ax.dry_neg, qi);
                (ax.viscous_neg * vi - c, c)
            } else {
                (0.0, 0.0)
            };
            r[i].push(ax.gain * uf[i][k] - rows[i] - fr);
            phi[i].push(phis[i]);
            cdry[i].push(c);
        }
    }
    let w = (EXCLUDE_S / dt).round() as usize;
    let edge = (0.3 / dt).round() as usize;
    let keep: [Vec<bool>; 3] = std::array::from_fn(|i| {
        let v = &vf[i];
        let mut keep = vec![true; n];
        let mut last: Option<usize> = None;
        for k in 0..n {
            if v[k].abs() < MIN_SPEED[i] || (k > 0 && v[k].signum() != v[k - 1].signum()) {
                last = Some(k);
            }
            if matches!(last, Some(s) if k - s <= w) {
                keep[k] = false;
            }
        }
        let mut next: Option<usize> = None;
        for k in (0..n).rev() {
            if v[k].abs() < MIN_SPEED[i] || (k + 1 < n && v[k].signum() != v[k + 1].signum()) {
                next = Some(k);
            }
            if matches!(next, Some(s) if s - k <= w) {
                keep[k] = false;
            }
        }
        for k in 0..n {
            if k < edge || k + edge >= n || k % DECIMATE != 0 {
                keep[k] = false;
            }
        }
        keep
    });
    let q: [Vec<f64>; 3] = std::array::from_fn(|i| qf[i].clone());
    let v: [Vec<f64>; 3] = std::array::from_fn(|i| vf[i].clone());
    Prep {
        run,
        params,
        held,
        q,
        v,
        r,
        phi,
        cdry,
        keep,
    }
}

/// Gathered samples of one drive and one part.
#[derive(Default, Clone)]
struct Gathered {
    q: Vec<f64>,
    v: Vec<f64>,
    r: Vec<f64>,
    phi: Vec<f64>,
    cdry: Vec<f64>,
}

fn gather(preps: &[Prep], i: usize, held: bool) -> Gathered {
    let mut g = Gathered::default();
    for p in preps {
        for k in 0..p.run.len() {
            if p.keep[i][k] && p.held[k] == held {
                g.q.push(p.q[i][k]);
                g.v.push(p.v[i][k]);
                g.r.push(p.r[i][k]);
                g.phi.push(p.phi[i][k]);
                g.cdry.push(p.cdry[i][k]);
            }
        }
    }
    g
}

/// Gathers a per-run full-length series (computed by `f`) on the kept samples of a part.
fn gather_series(preps: &[Prep], i: usize, held: bool, f: &dyn Fn(&Prep) -> Vec<f64>) -> Vec<f64> {
    let mut out = Vec::new();
    for p in preps {
        let s = f(p);
        for k in 0..p.run.len() {
            if p.keep[i][k] && p.held[k] == held {
                out.push(s[k]);
            }
        }
    }
    out
}

fn sumsq(x: &[f64]) -> f64 {
    x.iter().map(|v| v * v).sum()
}

/// A candidate after its force-domain fit.
struct Cand {
    axis: usize, // 3: all axes (payload)
    ext: Ext,
    /// Held-out SSE after, per axis (before = the baseline's).
    sse_after: [f64; 3],
}

fn one_col_fit(fit_c: &[f64], fit_r: &[f64]) -> f64 {
    let cc = sumsq(fit_c);
    if cc <= 0.0 {
        return 0.0;
    }
    fit_c.iter().zip(fit_r).map(|(c, r)| c * r).sum::<f64>() / cc
}

fn sse_one(c: &[f64], theta: f64, r: &[f64]) -> f64 {
    c.iter()
        .zip(r)
        .map(|(c, r)| (r - theta * c) * (r - theta * c))
        .sum()
}

fn bump_col(g: &Gathered, center: f64, width: f64, dir: Direction) -> Vec<f64> {
    g.q.iter()
        .zip(&g.v)
        .map(|(&q, &v)| {
            let on = match dir {
                Direction::Both => true,
                Direction::Positive => v > 0.0,
                Direction::Negative => v < 0.0,
            };
            if on {
                v.signum() * bump_shape(q, center, width)
            } else {
                0.0
            }
        })
        .collect()
}

fn fit_bump(fit: &Gathered) -> Option<Ext> {
    if fit.q.len() < 10 {
        return None;
    }
    let lo = fit.q.iter().cloned().fold(f64::INFINITY, f64::min);
    let hi = fit.q.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    let widths = [0.01, 0.015, 0.02, 0.03, 0.045, 0.065];
    let dirs = [Direction::Both, Direction::Positive, Direction::Negative];
    let mut best = (0.0, 0.0, 0.0, Direction::Both, 0.0);
    let score = |c: f64, w: f64, d: Direction| -> (f64, f64) {
        let col = bump_col(fit, c, w, d);
        let cc = sumsq(&col);
        if cc <= 1e-9 * fit.q.len() as f64 {
            return (0.0, 0.0);
        }
        let cr: f64 = col.iter().zip(&fit.r).map(|(a, b)| a * b).sum();
        (cr * cr / cc, cr / cc)
    };
    let mut c = lo;
    while c <= hi {
        for &w in &widths {
            for &d in &dirs {
                let (gain, a) = score(c, w, d);
                // a direction-restricted bump must beat the two-sided one clearly
                let gain = if d == Direction::Both {
                    gain
                } else {
                    gain * 0.98
                };
                if gain > best.0 {
                    best = (gain, c, w, d, a);
                }
            }
        }
        c += 0.0025;
    }
    if best.0 <= 0.0 {
        return None;
    }
    // refine the centre and width
    let (_, c0, w0, d0, _) = best;
    let mut refined = best;
    let mut c = c0 - 0.003;
    while c <= c0 + 0.003 {
        let mut w = w0 * 0.8;
        while w <= w0 * 1.25 {
            let (gain, a) = score(c, w, d0);
            if gain > refined.0 {
                refined = (gain, c, w, d0, a);
            }
            w += w0 * 0.05;
        }
        c += 0.0005;
    }
    Some(Ext::Bump {
        center: refined.1,
        width: refined.2,
        amplitude: refined.4,
        direction: refined.3,
    })
}

fn asym_cols(g: &Gathered) -> [Vec<f64>; 4] {
    [
        g.v.iter()
            .map(|&v| if v > 0.0 { 1.0 } else { 0.0 })
            .collect(),
        g.v.iter()
            .map(|&v| if v < 0.0 { -1.0 } else { 0.0 })
            .collect(),
        g.v.iter().map(|&v| v.max(0.0)).collect(),
        g.v.iter().map(|&v| v.min(0.0)).collect(),
    ]
}

fn stiction_col(g: &Gathered, vs: f64) -> Vec<f64> {
    g.v.iter()
        .zip(&g.cdry)
        .map(|(&v, &c)| v.signum() * c * (-(v / vs) * (v / vs)).exp())
        .collect()
}

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

/// Why the baseline does not score: the first run it does not simulate, with the model's
/// reason, or no held-out sample at all. `doc` says which baseline it is.
fn baseline_failure(preps: &[Prep], names: &[&str], doc: &str) -> DiagnoseError {
    for (p, name) in preps.iter().zip(names) {
        // a run that starts outside the travel: said in the data set's and the file's terms
        let (q, k) = (&p.params, [("x", "x"), ("y", "y"), ("l", "rope")]);
        let travel = [&q.x, &q.y, &q.rope];
        let first = [p.run.x.first(), p.run.y.first(), p.run.l.first()];
        for ((col, key), (a, v)) in k.iter().zip(travel.iter().zip(first)) {
            if let Some(&v) = v.filter(|&&v| !(v >= a.min && v <= a.max)) {
                return DiagnoseError::Model(format!(
                    "the baseline ({doc}) does not simulate run {name}: its first `{col}` = {v:.4} m is outside the travel [{key}.min, {key}.max] = [{}, {}]",
                    a.min, a.max
                ));
            }
        }
        if let Err(e) = simulate_checked(p.run, &p.params, &Extensions::default()) {
            return DiagnoseError::Model(format!(
                "the baseline ({doc}) does not simulate run {name}: {e}"
            ));
        }
    }
    DiagnoseError::Model(format!(
        "the baseline ({doc}) leaves no held-out sample to score"
    ))
}

struct Ctx<'a> {
    preps: Vec<Prep<'a>>,
    ranges: [f64; 3],
    floor: [f64; 3],
}

impl Ctx<'_> {
    /// Held-out (or fitting) NMAE per axis [%] of the simulation with `e` on `axis`
    /// (`None`: the baseline); `None` if a simulation fails.
    fn nmae(&self, e: Option<(&Ext, usize)>, held: bool) -> Option<[f64; 3]> {
        let mut acc = [0.0; 3];
        let mut n = 0usize;
        for p in &self.preps {
            if !p.held.contains(&held) {
                continue;
            }
            let mut params = p.params;
            let mut ext = Extensions::default();
            if let Some((e, axis)) = e {
                e.apply(axis, &mut params, &mut ext);
            }
            let sim = simulate(p.run, &params, &ext)?;
            for k in 0..p.run.len() {
                if p.held[k] != held {
                    continue;
                }
                let meas = [p.run.x[k], p.run.y[k], p.run.l[k]];
                for i in 0..3 {
                    acc[i] += (sim[k][i] - meas[i]).abs();
                }
                n += 1;
            }
        }
        if n == 0 {
            return None;
        }
        Some([0, 1, 2].map(|i| 100.0 * acc[i] / n as f64 / self.ranges[i]))
    }

    fn score(&self, before: &[f64; 3], after: &[f64; 3], k: usize) -> f64 {
        let mut s = 0.0;
        for i in 0..3 {
            s += (after[i].max(self.floor[i]) / before[i].max(self.floor[i])).ln();
        }
        s + PENALTY * k as f64
    }
}

/// Typical Stribeck velocity of a drive [m/s] (the rope's is slower), where the staged
/// stiction search starts.
const STRIBECK_START: [f64; 3] = [0.01, 0.01, 0.003];

/// Stiction fitted by simulation on the fitting part, in stages (128 simulations): the ratio
/// on a grid of 0.1 from 1.1 to 3.4 at five Stribeck velocities (0.5 to 2 times a typical
/// one: stick-slip makes the error surface rugged and ratio and velocity trade off, so a
/// coarser start lands in the wrong valley), then the velocity at that ratio, then both
/// refined.
/// Returns the best, or `None` if every simulation failed.
fn fit_stiction_sim(ctx: &Ctx, i: usize, before_f: &[f64; 3]) -> Option<Ext> {
    let mut best: Option<(f64, f64, f64)> = None; // (score, ratio, velocity)
    let try_one = |ratio: f64, vs: f64, best: &mut Option<(f64, f64, f64)>| {
        let e = Ext::Stiction {
            ratio,
            velocity: vs,
        };
        if let Some(a) = ctx.nmae(Some((&e, i)), false) {
            let s = ctx.score(before_f, &a, 0);
            if best.is_none_or(|b| s < b.0) {
                *best = Some((s, ratio, vs));
            }
        }
    };
    let v0 = STRIBECK_START[i];
    const START: [f64; 5] = [0.5, 0.7, 1.0, 1.5, 2.0];
    for f in START {
        for j in 0..24 {
            try_one(1.1 + 0.1 * j as f64, v0 * f, &mut best);
        }
    }
    let (_, r1, _) = best?;
    for f in [0.35, 0.7, 1.4, 2.8] {
        try_one(r1, v0 * f, &mut best);
    }
    let (_, _, v1) = best?;
    for dr in [-0.05, 0.05] {
        try_one(r1 + dr, v1, &mut best);
    }
    let (_, r2, _) = best?;
    for f in [0.85, 1.2] {
        try_one(r2, v1 * f, &mut best);
    }
    best.map(|(_, ratio, velocity)| Ext::Stiction { ratio, velocity })
}

/// Refits the dry magnitudes and viscous coefficients of every drive on the fitting part
/// (`--fit-baseline`), by inverse dynamics on top of `params`.
fn fit_baseline(preps: &[Prep], params: &mut Params) {
    for i in 0..3 {
        let g = gather(preps, i, false);
        if g.r.len() < 20 {
            continue;
        }
        let cols = asym_cols(&g);
        let refs: Vec<&[f64]> = cols.iter().map(|c| c.as_slice()).collect();
        if let Some(th) = ls(&refs, &g.r) {
            let mut ext = Extensions::default();
            Ext::Asymmetry {
                dry_pos: th[0],
                dry_neg: th[1],
                viscous_pos: th[2],
                viscous_neg: th[3],
            }
            .apply(i, params, &mut ext);
        }
    }
}

/// Diagnoses crane runs.
pub fn diagnose_crane(ds: &Dataset, opts: &DiagnoseOptions) -> Result<Report, DiagnoseError> {
    let runs: Vec<_> = ds.runs.iter().filter(|r| r.crane().is_some()).collect();
    let kinds: Vec<_> = runs.iter().map(|r| r.kind).collect();
    let (split, split_doc) = split_runs(&kinds);
    let (mut base, fitted, base_doc) = match &opts.baseline {
        Baseline::Auto => (
            Params::default(),
            false,
            "built-in defaults (shared/MODEL.md) with each run's declared payload".to_string(),
        ),
        Baseline::Params(p) => (*p, false, "the given parameters".to_string()),
        Baseline::Fit(p) => (
            p.unwrap_or_default(),
            true,
            "dry magnitudes and viscous coefficients per drive and direction re-fitted by inverse dynamics on the fitting part".to_string(),
        ),
        Baseline::Symmetric => {
            return Err(DiagnoseError::Input(
                "the symmetric baseline is for single-axis data".into(),
            ))
        }
    };
    let c = &ds.spec.constants;
    let ranges = [
        c.x_range_m[1] - c.x_range_m[0],
        c.y_range_m[1] - c.y_range_m[0],
        c.l_range_m[1] - c.l_range_m[0],
    ];
    let radii = [
        c.pulley_radius_x_m,
        c.pulley_radius_y_m,
        c.pulley_radius_l_m,
    ];
    let noise: [f64; 3] = std::array::from_fn(|i| {
        let res = 2.0 * std::f64::consts::PI * radii[i] / c.encoder_pulses;
        100.0 * res / 4.0 / ranges[i]
    });
    let floor = noise.map(|x| x * FLOOR_FACTOR);
    let make_preps = |base: &Params| -> Vec<Prep> {
        runs.iter()
            .zip(&split)
            .filter_map(|(r, s)| {
                let cr = r.crane()?;
                let mut p = *base;
                p.payload_mass = if r.payload_kg > 0.0 {
                    r.payload_kg
                } else {
                    0.001
                };
                let n = cr.len();
                let held = match s {
                    Some(h) => vec![*h; n],
                    None => (0..n)
                        .map(|k| k as f64 >= FIT_FRACTION * n as f64)
                        .collect(),
                };
                Some(prep(cr, p, held))
            })
            .collect()
    };
    let mut preps = make_preps(&base);
    if fitted {
        fit_baseline(&preps, &mut base);
        preps = make_preps(&base);
    }
    let ctx = Ctx {
        preps,
        ranges,
        floor,
    };
    let names: Vec<&str> = runs
        .iter()
        .filter(|r| r.crane().is_some())
        .map(|r| r.name.as_str())
        .collect();
    let before_h = ctx
        .nmae(None, true)
        .ok_or_else(|| baseline_failure(&ctx.preps, &names, &base_doc))?;
    let before_f = ctx.nmae(None, false).unwrap_or([f64::NAN; 3]);
    let fit_g: Vec<Gathered> = (0..3).map(|i| gather(&ctx.preps, i, false)).collect();
    let held_g: Vec<Gathered> = (0..3).map(|i| gather(&ctx.preps, i, true)).collect();
    let sse_b: [f64; 3] = std::array::from_fn(|i| sumsq(&held_g[i].r));
    let mut baseline_errors = Vec::new();
    for i in 0..3 {
        let f_all: Vec<f64> = gather_series(&ctx.preps, i, true, &|p: &Prep| {
            let f = butter(4, CUTOFF_HZ * 2.0 * p.run.dt());
            let g = axis_params(&p.params, i).gain;
            drive_series(&f, &p.run.u[i])
                .iter()
                .map(|u| g * u)
                .collect()
        });
        let n_h = held_g[i].r.len().max(1) as f64;
        let n_f = fit_g[i].r.len().max(1) as f64;
        baseline_errors.push(AxisError {
            axis: AXIS_NAMES[i].into(),
            nmae_fit: before_f[i],
            nmae_held_out: before_h[i],
            nmae_noise: noise[i],
            nmae_own_log: None,
            force_rms_fit_n: (sumsq(&fit_g[i].r) / n_f).sqrt(),
            force_rms_held_out_n: (sse_b[i] / n_h).sqrt(),
            force_rel_err_held_out_pct: 100.0 * (sse_b[i] / sumsq(&f_all).max(1e-300)).sqrt(),
        });
    }

    // ---- force-domain fits ----
    let mut cands: Vec<Cand> = Vec::new();
    let mut not_identifiable: Vec<(usize, Cause)> = Vec::new();
    for i in 0..3 {
        let (fg, hg) = (&fit_g[i], &held_g[i]);
        if fg.r.len() < 20 || hg.r.len() < 20 {
            continue;
        }
        let one = |ext: Ext, fit_c: &[f64], held_c: &[f64], scale: f64| -> Cand {
            let th = one_col_fit(fit_c, &fg.r);
            let mut s = sse_b;
            s[i] = sse_one(held_c, th, &hg.r);
            let ext = match ext {
                Ext::Offset(_) => Ext::Offset(th * scale),
                Ext::Bump {
                    center,
                    width,
                    direction,
                    ..
                } => Ext::Bump {
                    center,
                    width,
                    amplitude: th,
                    direction,
                },
                e => e,
            };
            Cand {
                axis: i,
                ext,
                sse_after: s,
            }
        };
        // localized friction
        if let Some(Ext::Bump {
            center,
            width,
            direction,
            ..
        }) = fit_bump(fg)
        {
            let e = Ext::Bump {
                center,
                width,
                amplitude: 0.0,
                direction,
            };
            cands.push(one(
                e,
                &bump_col(fg, center, width, direction),
                &bump_col(hg, center, width, direction),
                1.0,
            ));
        }
        // stiction (force-domain evidence; refined by simulation below)
        {
            let mut best: Option<(f64, f64, f64)> = None;
            for &vs in &[0.003, 0.006, 0.012, 0.025, 0.05] {
                let fc = stiction_col(fg, vs);
                let th = one_col_fit(&fc, &fg.r);
                if th <= 0.0 {
                    continue;
                }
                let red = sumsq(&fg.r) - sse_one(&fc, th, &fg.r);
                if best.is_none_or(|b| red > b.0) {
                    best = Some((red, vs, th));
                }
            }
            if let Some((_, vs, th)) = best {
                let hc = stiction_col(hg, vs);
                let mut s = sse_b;
                s[i] = sse_one(&hc, th, &hg.r);
                cands.push(Cand {
                    axis: i,
                    ext: Ext::Stiction {
                        ratio: 1.0 + th,
                        velocity: vs,
                    },
                    sse_after: s,
                });
            }
        }
        if !fitted {
            // direction asymmetry
            let fc = asym_cols(fg);
            let hc = asym_cols(hg);
            let fr: Vec<&[f64]> = fc.iter().map(|c| c.as_slice()).collect();
            let hr: Vec<&[f64]> = hc.iter().map(|c| c.as_slice()).collect();
            if let Some(th) = ls(&fr, &fg.r) {
                let mut s = sse_b;
                s[i] = sse(&hr, &th, &hg.r);
                cands.push(Cand {
                    axis: i,
                    ext: Ext::Asymmetry {
                        dry_pos: th[0],
                        dry_neg: th[1],
                        viscous_pos: th[2],
                        viscous_neg: th[3],
                    },
                    sse_after: s,
                });
            }
            // force offset: r = -b
            let ones_f = vec![1.0; fg.r.len()];
            let ones_h = vec![1.0; hg.r.len()];
            cands.push(one(Ext::Offset(0.0), &ones_f, &ones_h, -1.0));
        } else {
            not_identifiable.push((i, Cause::ForceOffset));
            not_identifiable.push((i, Cause::DirectionAsymmetry));
        }
        // input dead band and delay: the residual they predict has no free amplitude
        let gain = axis_params(&base, i).gain;
        let shifted = |tf: &dyn Fn(&[f64]) -> Vec<f64>, held: bool| -> Vec<f64> {
            gather_series(&ctx.preps, i, held, &|p: &Prep| {
                let f = butter(4, CUTOFF_HZ * 2.0 * p.run.dt());
                let u = &p.run.u[i];
                let t = tf(u);
                let diff: Vec<f64> = u.iter().zip(&t).map(|(a, b)| gain * (a - b)).collect();
                drive_series(&f, &diff)
            })
        };
        let score_dz = |d: f64| {
            let col = shifted(
                &|u: &[f64]| u.iter().map(|&x| deadband(x, d)).collect(),
                false,
            );
            sse_one(&col, 1.0, &fg.r)
        };
        let keep = |best: &mut Option<(f64, f64)>, d: f64| {
            let s = score_dz(d);
            if best.is_none_or(|b| s < b.0) {
                *best = Some((s, d));
            }
        };
        let mut best_dz: Option<(f64, f64)> = None;
        let mut d = 0.02;
        while d <= 1.5 + 1e-9 {
            keep(&mut best_dz, d);
            d += 0.02;
        }
        // refine to a millivolt: the grid step alone leaves a dry-force error of `K * 0.01 V`,
        // enough for a symmetric dry-friction shift to out-score the right cause
        if let Some((_, d0)) = best_dz {
            for j in -20..=20 {
                let d = d0 + j as f64 * 1e-3;
                if d > 0.0 {
                    keep(&mut best_dz, d);
                }
            }
        }
        if let Some((_, d)) = best_dz {
            let col = shifted(
                &|u: &[f64]| u.iter().map(|&x| deadband(x, d)).collect(),
                true,
            );
            let mut s = sse_b;
            s[i] = sse_one(&col, 1.0, &hg.r);
            cands.push(Cand {
                axis: i,
                ext: Ext::Deadzone(d),
                sse_after: s,
            });
        }
        let dt = ctx.preps.first().map(|p| p.run.dt()).unwrap_or(0.002);
        let mut best_dl: Option<(f64, usize)> = None;
        for m in 1..crane_model::MAX_DELAY_STEPS {
            let col = shifted(&|u: &[f64]| delay_half_samples(u, m), false);
            let s = sse_one(&col, 1.0, &fg.r);
            if best_dl.is_none_or(|b| s < b.0) {
                best_dl = Some((s, m));
            }
        }
        if let Some((_, m)) = best_dl {
            let col = shifted(&|u: &[f64]| delay_half_samples(u, m), true);
            let mut s = sse_b;
            s[i] = sse_one(&col, 1.0, &hg.r);
            cands.push(Cand {
                axis: i,
                ext: Ext::Delay(m as f64 * dt / 2.0),
                sse_after: s,
            });
        }
    }
    // payload mass: one parameter over the three drives, each weighted by its noise
    {
        let w: [f64; 3] = std::array::from_fn(|i| {
            let n = fit_g[i].r.len().max(1) as f64;
            1.0 / (sumsq(&fit_g[i].r) / n).max(1e-12)
        });
        let (mut num, mut den) = (0.0, 0.0);
        for i in 0..3 {
            for (p, r) in fit_g[i].phi.iter().zip(&fit_g[i].r) {
                num += w[i] * p * r;
                den += w[i] * p * p;
            }
        }
        if den > 0.0 {
            let dm = num / den;
            let s: [f64; 3] = std::array::from_fn(|i| sse_one(&held_g[i].phi, dm, &held_g[i].r));
            cands.push(Cand {
                axis: 3,
                ext: Ext::Payload(dm),
                sse_after: s,
            });
        }
    }

    // ---- held-out force BIC ----
    let force_bic = |c: &Cand| -> f64 {
        let axes: Vec<usize> = if c.axis == 3 {
            vec![0, 1, 2]
        } else {
            vec![c.axis]
        };
        let mut s = 0.0;
        let mut n_all = 0;
        for &i in &axes {
            let n = held_g[i].r.len();
            n_all += n;
            s += n as f64 * (c.sse_after[i].max(1e-300) / sse_b[i].max(1e-300)).ln();
        }
        s + c.ext.k() as f64 * (n_all.max(1) as f64).ln()
    };

    // ---- held-out simulation scores ----
    let mut scored: Vec<(Cand, f64, f64, [f64; 3])> = Vec::new();
    for c in cands {
        let fb = force_bic(&c);
        let is_stiction = matches!(c.ext, Ext::Stiction { .. });
        if !is_stiction && fb >= 0.0 {
            scored.push((c, fb, f64::INFINITY, before_h));
            continue;
        }
        let axis = c.axis.min(2);
        let Some(after) = ctx.nmae(Some((&c.ext, if c.axis == 3 { 2 } else { axis })), true) else {
            scored.push((c, fb, f64::INFINITY, before_h));
            continue;
        };
        let s = ctx.score(&before_h, &after, c.ext.k());
        scored.push((c, fb, s, after));
    }
    // Stiction by simulation on the fitting part (output error: stick-slip leaves too little
    // in the masked force residual), for the drives whose simulation is off: the worst one and
    // any within a third of it (in noise floors). Skipped when a candidate already brings every
    // axis's held-out NMAE down to its floor: nothing is left for stiction to explain (the
    // floored score could at most tie).
    let explained = scored.iter().any(|(c, fb, s, after)| {
        s.is_finite()
            && *fb < FORCE_BIC_MAX
            && (0..3).all(|j| after[j] <= floor[j])
            && !matches!(c.ext, Ext::Stiction { .. })
    });
    let off: [f64; 3] = std::array::from_fn(|i| before_f[i] / floor[i]);
    let worst_off = off.iter().cloned().fold(0.0_f64, f64::max);
    for i in 0..3 {
        if explained || before_f[i] <= floor[i] || off[i] < worst_off / 3.0 {
            continue;
        }
        let Some(e) = fit_stiction_sim(&ctx, i, &before_f) else {
            continue;
        };
        let Some(after) = ctx.nmae(Some((&e, i)), true) else {
            continue;
        };
        scored.retain(|(c, ..)| !(c.axis == i && matches!(c.ext, Ext::Stiction { .. })));
        let s = ctx.score(&before_h, &after, e.k());
        let c = Cand {
            axis: i,
            ext: e,
            sse_after: sse_b,
        };
        let fb = force_bic(&c);
        scored.push((c, fb, s, after));
    }
    scored.sort_by(|a, b| a.2.total_cmp(&b.2));
    let supported = |fb: f64, s: f64, st: bool| -> bool {
        s < SUPPORT_RATIO.ln() && (st || fb < FORCE_BIC_MAX)
    };
    // Nested candidates: `force_offset` is `direction_asymmetry` restricted to opposite dry
    // shifts and no viscous change (exactly the same model while the bias stays below the dry
    // magnitudes), so their simulated errors differ only by noise; the held-out force BIC,
    // which charges the three extra parameters, decides between them.
    let offset_bic: [f64; 3] = std::array::from_fn(|i| {
        scored
            .iter()
            .filter(|(c, ..)| c.axis == i && matches!(c.ext, Ext::Offset(_)))
            .map(|(_, fb, ..)| *fb)
            .fold(f64::INFINITY, f64::min)
    });
    let nested_loses = |c: &Cand, fb: f64| -> bool {
        matches!(c.ext, Ext::Asymmetry { .. }) && c.axis < 3 && offset_bic[c.axis] <= fb
    };
    let mut findings = Vec::new();
    let mut used = [false; 3];
    let mut candidates = Vec::new();
    for (c, fb, s, after) in &scored {
        let st = matches!(c.ext, Ext::Stiction { .. });
        // a finding on one drive must cut that drive's own held-out NMAE (a gain on the
        // coupled axes alone is not evidence for it)
        let own_cut = c.axis == 3 || after[c.axis] < before_h[c.axis];
        let ok = supported(*fb, *s, st) && !nested_loses(c, *fb) && own_cut;
        let axis_name = if c.axis == 3 { "l" } else { AXIS_NAMES[c.axis] };
        candidates.push(Candidate {
            cause: c.ext.cause(),
            axis: axis_name.into(),
            parameters: c.ext.parameters(),
            score: *s,
            force_delta_bic: *fb,
            supported: ok,
        });
        let axes: Vec<usize> = if c.axis == 3 {
            vec![0, 1, 2]
        } else {
            vec![c.axis]
        };
        if !ok || axes.iter().any(|&i| used[i]) {
            continue;
        }
        for &i in &axes {
            used[i] = true;
        }
        let ai = if c.axis == 3 { 2 } else { c.axis };
        let n_h = held_g[ai].r.len();
        let (identifiable, note) = match c.ext {
            Ext::Offset(b) => (
                true,
                format!(
                    "a constant bias of {b:.3} N is exactly a shift of the dry magnitudes (dry_pos by {:.3} N, dry_neg by {:.3} N) while it stays below them; named force_offset against this fixed baseline because one parameter explains what direction_asymmetry needs two for",
                    -b, b
                ),
            ),
            Ext::Asymmetry {
                dry_pos, dry_neg, ..
            } if (dry_pos + dry_neg).abs() < 0.2 * (dry_pos.abs() + dry_neg.abs()) => (
                false,
                "the dry shifts are nearly opposite: indistinguishable from a force_offset of the same size".into(),
            ),
            Ext::Payload(_) => (
                true,
                "payload mass changes the three drive rows together; reported on the rope, which carries its weight".into(),
            ),
            _ => (true, String::new()),
        };
        findings.push(Finding {
            cause: c.ext.cause(),
            axis: axis_name.into(),
            parameters: c.ext.parameters(),
            nmae_before: before_h[ai],
            nmae_after: after[ai],
            evidence: Evidence {
                force_delta_bic: *fb,
                force_rms_before_n: (sse_b[ai] / n_h.max(1) as f64).sqrt(),
                force_rms_after_n: (c.sse_after[ai] / n_h.max(1) as f64).sqrt(),
                score: *s,
                extra_parameters: c.ext.k(),
                held_out_samples: n_h,
                identifiable,
                note,
            },
        });
    }
    for (i, cause) in not_identifiable {
        candidates.push(Candidate {
            cause,
            axis: AXIS_NAMES[i].into(),
            parameters: BTreeMap::new(),
            score: 0.0,
            force_delta_bic: 0.0,
            supported: false,
        });
    }
    let worst = (0..3)
        .map(|i| before_h[i] / floor[i])
        .fold(0.0_f64, f64::max);
    let (verdict, reason) = if let Some(f) = findings.first() {
        (
            Verdict::Found(f.cause),
            format!(
                "{} on {} cuts the held-out NMAE from {:.4} % to {:.4} %",
                f.cause, f.axis, f.nmae_before, f.nmae_after
            ),
        )
    } else if worst > UNEXPLAINED_FLOORS {
        (
            Verdict::Unexplained,
            format!("the held-out simulation error is {worst:.1} noise floors but no candidate cuts it by {:.0} %", 100.0 * (1.0 - SUPPORT_RATIO)),
        )
    } else {
        (
            Verdict::None,
            format!("the held-out simulation error is within {worst:.1} noise floors and no candidate is supported"),
        )
    };
    if let Some(dir) = &opts.plots_dir {
        crate::plots::crane_plots(dir, &ctx_plot_data(&ctx, &scored))?;
    }
    Ok(Report {
        dataset: ds.dir.display().to_string(),
        data: "crane".into(),
        baseline: base_doc,
        split: split_doc,
        baseline_errors,
        findings,
        verdict,
        verdict_reason: reason,
        candidates,
        measures: BTreeMap::new(),
        heldout_simulation: None,
        final_model: None,
    })
}

fn ctx_plot_data(ctx: &Ctx, scored: &[(Cand, f64, f64, [f64; 3])]) -> Vec<crate::plots::Series> {
    let mut out = Vec::new();
    let best = scored.first().filter(|s| s.2.is_finite());
    if let Some(p) = ctx.preps.iter().find(|p| p.held.contains(&true)) {
        let base = simulate(p.run, &p.params, &Extensions::default());
        let after = best.and_then(|(c, ..)| {
            let mut params = p.params;
            let mut ext = Extensions::default();
            c.ext.apply(c.axis.min(2), &mut params, &mut ext);
            simulate(p.run, &params, &ext)
        });
        for i in 0..3 {
            let meas = [&p.run.x, &p.run.y, &p.run.l][i];
            let err = |s: &Option<Vec<[f64; 3]>>| -> Vec<f64> {
                s.as_ref()
                    .map(|s| s.iter().zip(meas).map(|(a, m)| m - a[i]).collect())
                    .unwrap_or_default()
            };
            out.push(crate::plots::Series {
                name: format!("{}_{}", AXIS_NAMES[i], out.len() / 3),
                t: p.run.t.clone(),
                q: p.q[i].clone(),
                v: p.v[i].clone(),
                before: err(&base),
                after: err(&after),
            });
        }
    }
    out
}

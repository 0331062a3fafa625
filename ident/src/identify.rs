//! The paper's parameter estimation, step by step, on a data set:
//!
//! 1. data processing: zero-phase 4th-order Butterworth at 3 Hz on positions, central
//!    differences, exclusion of the regions around velocity zero crossings and stops;
//! 2. rope: `P3` from the quasistatic ramps, `P1, P2` by least squares on unloaded motion,
//!    `P4` on the loaded runs, then `Jbar_l = P1/P4`, `K_l = 1/P4`, `Dbar_l = P2/P4`,
//!    `Cbar_l = P3/P4`;
//! 3. `K_x, K_y, Jbar_x, Jbar_y` from the pulley radii;
//! 4. dry friction of X and Y: Bayesian linear regression of 4th-order polynomials on the
//!    breakaway forces (`K` times the onset voltage of each ramp);
//! 5. direction-dependent viscous coefficients of X and Y by least squares;
//! 6. `D_alpha, D_beta` from free swings.
//!
//! One deliberate addition to the paper's processing, `IdentOptions::filter_inputs`: the
//! voltages and the dry-friction column are passed through the same zero-phase filter as the
//! positions, so both sides of each regression see the same filter ("parallel filtering" of
//! inverse-dynamics identification). Without it, the step and chirp inputs' content near and
//! above the 3 Hz cut-off biases the inertia estimates.

use crate::blr::{Blr, BlrOptions, FrictionCurve};
use crate::data::{Constants, CraneRun, Dataset, RunKind};
use crate::linalg::{lstsq, LsError, LsFit};
use crate::rig::{corrected_onset, detect_onset};
use crate::signal::{butter, diff2_central, diff_central, Filter};
use crane_model::Params;
use serde::{Deserialize, Serialize};

/// Options of the identification.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct IdentOptions {
    /// Butterworth order.
    pub filter_order: usize,
    /// Cut-off [Hz].
    pub cutoff_hz: f64,
    /// Filter the voltages and dry-friction columns like the positions (see module docs).
    pub filter_inputs: bool,
    /// Samples closer than this to a stop or velocity zero crossing are excluded [s].
    pub exclude_s: f64,
    /// Below this speed a drive counts as stopped [m/s].
    pub min_speed: f64,
    /// Samples this close to the start or end of a run are excluded (filter transients) [s].
    pub edge_s: f64,
    /// Length of the windows of the free-swing energy balance [s].
    pub swing_window_s: f64,
    /// Bayesian regression of the dry friction.
    pub blr: BlrOptions,
    /// Points of the reported friction curves.
    pub curve_points: usize,
}

impl Default for IdentOptions {
    fn default() -> Self {
        IdentOptions {
            filter_order: 4,
            cutoff_hz: 3.0,
            filter_inputs: true,
            exclude_s: 0.2,
            min_speed: 0.002,
            edge_s: 0.5,
            swing_window_s: 5.0,
            blr: BlrOptions::default(),
            curve_points: 101,
        }
    }
}

/// An estimate and its standard error.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Estimate {
    /// Value.
    pub value: f64,
    /// Standard error.
    pub std_err: f64,
}

impl Estimate {
    fn new(value: f64, std_err: f64) -> Self {
        Estimate { value, std_err }
    }
}

/// Rope-axis results.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RopeResult {
    /// `P1 = Jbar_l / K_l` [V s^2/m].
    pub p1: Estimate,
    /// `P2 = Dbar_l / K_l` [V s/m].
    pub p2: Estimate,
    /// `P3 = Cbar_l / K_l` [V].
    pub p3: Estimate,
    /// `P4 = 1 / K_l` [V/N].
    pub p4: Estimate,
    /// Breakaway voltages of the quasistatic ramps (signed) [V].
    pub p3_samples: Vec<f64>,
    /// Least squares of `P1, P2` (correlation matrix inside).
    pub fit_p12: LsFit,
    /// Least squares of `P4`.
    pub fit_p4: LsFit,
    /// `Jbar_l` [kg].
    pub inertia: Estimate,
    /// `K_l` [N/V].
    pub gain: Estimate,
    /// `Dbar_l` [N s/m].
    pub viscous: Estimate,
    /// `Cbar_l` [N].
    pub dry: Estimate,
}

/// A dry-friction polynomial fitted by Bayesian linear regression.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DryFit {
    /// Coefficients c0..c4 in powers of p [m] (posterior mean) [N].
    pub coefficients: Vec<f64>,
    /// Posterior standard deviations of the coefficients.
    pub std_err: Vec<f64>,
    /// Posterior correlation matrix of the coefficients.
    pub correlation: Vec<Vec<f64>>,
    /// Probe positions [m].
    pub positions: Vec<f64>,
    /// Breakaway forces [N].
    pub forces: Vec<f64>,
    /// Noise variance assumed [N^2].
    pub noise_var: f64,
    /// Curve with its pointwise and simultaneous 95 % bands.
    pub curve: FrictionCurve,
}

/// X or Y results.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DriveResult {
    /// `K` from the rope's gain and the radii [N/V].
    pub gain: Estimate,
    /// `Jbar` from the rope's inertia and the radii [kg].
    pub inertia: Estimate,
    /// `Dbar+` [N s/m].
    pub viscous_pos: Estimate,
    /// `Dbar-` [N s/m].
    pub viscous_neg: Estimate,
    /// Least squares of the viscous coefficients.
    pub fit_viscous: LsFit,
    /// Dry friction, positive direction.
    pub dry_pos: DryFit,
    /// Dry friction, negative direction.
    pub dry_neg: DryFit,
}

/// Swing damping results.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SwingResult {
    /// `D_alpha` [kg m^2/s] (energy balance).
    pub damping_alpha: Estimate,
    /// `D_beta` [kg m^2/s] (energy balance).
    pub damping_beta: Estimate,
    /// Energy-balance least squares over windows: `-dE = D_alpha int(ad^2) + D_beta int(bd^2)`.
    pub fit_energy: LsFit,
    /// The paper's differential form (per-sample least squares), for comparison, if the data
    /// excite it: `D_alpha`.
    pub differential_alpha: Option<Estimate>,
    /// Same, `D_beta`.
    pub differential_beta: Option<Estimate>,
    /// Seconds of free swing used.
    pub seconds_used: f64,
}

/// Everything the identification estimates.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Identified {
    /// Rope.
    pub rope: RopeResult,
    /// X.
    pub x: DriveResult,
    /// Y.
    pub y: DriveResult,
    /// Swing.
    pub swing: SwingResult,
    /// The model parameters (payload: the data set's `payload_kg`).
    pub params: Params,
    /// Options used.
    pub options: IdentOptions,
}

/// Why an identification failed.
#[derive(Debug, thiserror::Error)]
pub enum IdentError {
    /// The data set lacks a kind of run.
    #[error("the data set has no usable `{0}` run (see DATA_FORMAT.md for the run kinds)")]
    Missing(&'static str),
    /// A least-squares problem failed.
    #[error(transparent)]
    Ls(#[from] LsError),
    /// Loading failed.
    #[error(transparent)]
    Data(#[from] crate::data::DataError),
}

/// Filtered position, velocity and acceleration of one coordinate.
#[derive(Clone, Debug)]
pub struct Deriv {
    /// Filtered position.
    pub p: Vec<f64>,
    /// Velocity.
    pub v: Vec<f64>,
    /// Acceleration.
    pub a: Vec<f64>,
}

/// The paper's processing of one signal: zero-phase Butterworth, central differences.
pub fn derive(f: &Filter, x: &[f64], dt: f64) -> Deriv {
    let p = f.filtfilt(x);
    let v = diff_central(&p, dt);
    let a = diff2_central(&p, dt);
    Deriv { p, v, a }
}

impl IdentOptions {
    fn filter(&self, dt: f64) -> Filter {
        butter(self.filter_order, self.cutoff_hz * 2.0 * dt)
    }

    /// Samples kept for a drive moving with velocity `v`: away from the edges and at least
    /// `exclude_s` from any sample slower than `min_speed` (stops, zero crossings).
    pub fn motion_mask(&self, v: &[f64], dt: f64) -> Vec<bool> {
        let n = v.len();
        let w = (self.exclude_s / dt).round() as usize;
        let edge = (self.edge_s / dt).round() as usize;
        let mut keep = vec![true; n];
        let mut last_slow: Option<usize> = None;
        for k in 0..n {
            if v[k].abs() < self.min_speed || (k > 0 && v[k].signum() != v[k - 1].signum()) {
                last_slow = Some(k);
            }
            if let Some(s) = last_slow {
                if k - s <= w {
                    keep[k] = false;
                }
            }
        }
        let mut next_slow: Option<usize> = None;
        for k in (0..n).rev() {
            if v[k].abs() < self.min_speed || (k + 1 < n && v[k].signum() != v[k + 1].signum()) {
                next_slow = Some(k);
            }
            if let Some(s) = next_slow {
                if s - k <= w {
                    keep[k] = false;
                }
            }
            if k < edge || k + edge >= n {
                keep[k] = false;
            }
        }
        keep
    }
}

fn sign(v: f64) -> f64 {
    if v > 0.0 {
        1.0
    } else if v < 0.0 {
        -1.0
    } else {
        0.0
    }
}

/// Mean and standard error of samples.
fn mean_se(x: &[f64]) -> Estimate {
    let n = x.len() as f64;
    let m = x.iter().sum::<f64>() / n;
    let var = if x.len() > 1 {
        x.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / (n - 1.0)
    } else {
        0.0
    };
    Estimate::new(m, (var / n).sqrt())
}

/// Relative standard error of a ratio `a / b` of independent estimates.
fn ratio(a: Estimate, b: Estimate) -> Estimate {
    let v = a.value / b.value;
    let (ra, rb) = (a.std_err / a.value, b.std_err / b.value);
    let rel = (ra * ra + rb * rb).sqrt();
    Estimate::new(v, (v * rel).abs())
}

struct Columns {
    names: Vec<&'static str>,
    cols: Vec<Vec<f64>>,
    y: Vec<f64>,
}

impl Columns {
    fn new(names: &[&'static str]) -> Self {
        Columns {
            names: names.to_vec(),
            cols: vec![Vec::new(); names.len()],
            y: Vec::new(),
        }
    }
    fn push(&mut self, row: &[f64], y: f64) {
        for (c, v) in self.cols.iter_mut().zip(row) {
            c.push(*v);
        }
        self.y.push(y);
    }
    fn fit(&self, what: &str) -> Result<LsFit, LsError> {
        lstsq(what, &self.names, &self.cols, &self.y)
    }
}

/// Rope step on a data set.
pub fn identify_rope(ds: &Dataset, opt: &IdentOptions) -> Result<RopeResult, IdentError> {
    let c = &ds.spec.constants;
    let res_l = c.resolution(2);
    // First pass with the onsets as seen, second with the detection lag corrected by the
    // first pass's P1, P2 (the rope's `Dbar/K = P2`, `M/Dbar = P1/P2`).
    let mut lag: Option<(f64, f64)> = None;
    let mut result = None;
    for _pass in 0..2 {
        let mut p3_samples = Vec::new();
        for run in ds.of_kind(RunKind::RopeQuasistatic) {
            let Some(cr) = run.crane() else { continue };
            let o = match lag {
                Some((d, t)) => corrected_onset(cr, 2, res_l, d, t),
                None => detect_onset(cr, 2, 0.5 * res_l),
            };
            if let Some(o) = o {
                p3_samples.push(o.volts);
            }
        }
        if p3_samples.is_empty() {
            return Err(IdentError::Missing("rope_quasistatic"));
        }
        let r = rope_motion(ds, opt, p3_samples)?;
        lag = Some((r.p2.value, r.p1.value / r.p2.value));
        result = Some(r);
    }
    result.ok_or(IdentError::Missing("rope_quasistatic"))
}

fn rope_motion(
    ds: &Dataset,
    opt: &IdentOptions,
    p3_samples: Vec<f64>,
) -> Result<RopeResult, IdentError> {
    let c = &ds.spec.constants;
    let abs: Vec<f64> = p3_samples.iter().map(|v| v.abs()).collect();
    let p3 = mean_se(&abs);

    // P1, P2 on unloaded motion: u - P3 sgn = P1 Ldd + P2 Ld
    let p3v = p3.value;
    let rope_dry = |_: f64, v: f64| p3v * sign(v);
    let mut cols = Columns::new(&["P1", "P2"]);
    for run in ds.of_kind(RunKind::RopeUnloaded) {
        let Some(cr) = run.crane() else { continue };
        let s = drive_signals(&cr.l, &cr.u[2], 1.0, cr.dt(), opt, rope_dry);
        for k in 0..s.v.len() {
            if s.keep[k] {
                cols.push(&[s.a[k], s.v[k]], s.drive_minus_friction[k]);
            }
        }
    }
    if cols.y.is_empty() {
        return Err(IdentError::Missing("rope_unloaded"));
    }
    let fit_p12 = cols.fit("rope P1, P2")?;
    let p1 = Estimate::new(fit_p12.theta[0], fit_p12.std_err[0]);
    let p2 = Estimate::new(fit_p12.theta[1], fit_p12.std_err[1]);

    // P4 on loaded motion: u - P1 Ldd - P2 Ld - P3 sgn = P4 m_p (Ldd - g)
    let g = c.gravity;
    let mut cols = Columns::new(&["P4"]);
    for run in ds.of_kind(RunKind::RopeLoaded) {
        let Some(cr) = run.crane() else { continue };
        let m = run.payload_kg;
        if m <= 0.0 {
            continue;
        }
        // stopped samples carry no payload term (the holding force takes it)
        let s = drive_signals(&cr.l, &cr.u[2], 1.0, cr.dt(), opt, rope_dry);
        for k in 0..s.v.len() {
            if s.keep[k] {
                cols.push(
                    &[m * (s.a[k] - g * s.moving_f[k])],
                    s.drive_minus_friction[k] - p1.value * s.a[k] - p2.value * s.v[k],
                );
            }
        }
    }
    if cols.y.is_empty() {
        return Err(IdentError::Missing("rope_loaded"));
    }
    let fit_p4 = cols.fit("rope P4")?;
    let p4 = Estimate::new(fit_p4.theta[0], fit_p4.std_err[0]);
    let gain = Estimate::new(1.0 / p4.value, p4.std_err / (p4.value * p4.value));
    Ok(RopeResult {
        p1,
        p2,
        p3,
        p4,
        p3_samples,
        inertia: ratio(p1, p4),
        gain,
        viscous: ratio(p2, p4),
        dry: ratio(p3, p4),
        fit_p12,
        fit_p4,
    })
}

/// Signals of one drive in a motion run, prepared for a filtered regression.
///
/// The drive equation `K u = M a + D v + f` holds at every sample if `f` is the friction
/// force: `Cbar(q) sgn(v)` while moving and the holding force `K u` while stopped (then `a`
/// and `v` are zero). Built that way the friction column makes the equation exact through
/// the stops too, so filtering both sides with the same zero-phase filter (when
/// `filter_inputs` is on) cannot smear a stop's holding force into the moving samples.
struct DriveSignals {
    /// Filtered acceleration and velocity.
    a: Vec<f64>,
    v: Vec<f64>,
    /// Filtered positive and negative parts of the velocity.
    v_pos: Vec<f64>,
    v_neg: Vec<f64>,
    /// Filtered `K u - f` (in the units of `K u`).
    drive_minus_friction: Vec<f64>,
    /// Filtered `[moving]`.
    moving_f: Vec<f64>,
    /// Samples kept (the paper's exclusion around stops and zero crossings, edges).
    keep: Vec<bool>,
}

/// Half-width [samples] of the window over which an unchanged encoder means "stopped".
const STILL_HALF_WINDOW: usize = 10;

fn drive_signals(
    pos: &[f64],
    u: &[f64],
    gain: f64,
    dt: f64,
    opt: &IdentOptions,
    dry: impl Fn(f64, f64) -> f64,
) -> DriveSignals {
    let n = pos.len();
    let filt = opt.filter(dt);
    let d = derive(&filt, pos, dt);
    // Zero-order hold: u[k] acts over [t_k, t_k+1), so the central differences at t_k see the
    // mean of u[k-1] and u[k]. Without this the input leads the derivatives by half a sample
    // and the inertia comes out too large by `Dbar dt / 2` (4 % on the rope).
    let u: Vec<f64> = (0..n)
        .map(|k| {
            if k == 0 {
                u[0]
            } else {
                0.5 * (u[k - 1] + u[k])
            }
        })
        .collect();
    // moving: the encoder changes within +-STILL_HALF_WINDOW samples
    let m = STILL_HALF_WINDOW;
    let mut moving = vec![false; n];
    for (k, mv) in moving.iter_mut().enumerate() {
        let lo = k.saturating_sub(m);
        let hi = (k + m).min(n - 1);
        *mv = pos[lo..=hi].iter().any(|&p| p != pos[k]);
    }
    // direction from a lightly filtered velocity (20 Hz, or the data's own if slower)
    let fast_hz = (0.2 / dt).min(20.0);
    let fast = derive(&butter(opt.filter_order, fast_hz * 2.0 * dt), pos, dt);
    let mut f = vec![0.0; n];
    let mut vp = vec![0.0; n];
    let mut vn = vec![0.0; n];
    let mut mv = vec![0.0; n];
    for k in 0..n {
        if moving[k] {
            let v = fast.v[k];
            f[k] = dry(fast.p[k], v);
            vp[k] = v.max(0.0);
            vn[k] = v.min(0.0);
            mv[k] = 1.0;
        }
    }
    for k in 0..n {
        if !moving[k] {
            f[k] = gain * u[k];
        }
    }
    let y: Vec<f64> = u.iter().zip(&f).map(|(u, f)| gain * u - f).collect();
    let (y, vp, vn, mv) = if opt.filter_inputs {
        (
            filt.filtfilt(&y),
            filt.filtfilt(&vp),
            filt.filtfilt(&vn),
            filt.filtfilt(&mv),
        )
    } else {
        (
            y,
            d.v.iter().map(|v| v.max(0.0)).collect(),
            d.v.iter().map(|v| v.min(0.0)).collect(),
            mv,
        )
    };
    let keep = opt.motion_mask(&d.v, dt);
    DriveSignals {
        a: d.a,
        v: d.v,
        v_pos: vp,
        v_neg: vn,
        drive_minus_friction: y,
        moving_f: mv,
        keep,
    }
}

/// The model's five dry-friction coefficients `c0..c4` of a fitted polynomial (missing terms
/// 0), for `crane_model::friction::dry` (the one polynomial evaluation, clamped at 0).
fn poly5(v: &[f64]) -> [f64; 5] {
    let mut a = [0.0; 5];
    for (d, s) in a.iter_mut().zip(v) {
        *d = *s;
    }
    a
}

/// Fits one dry-friction curve from `(position, force)` samples.
pub fn fit_dry(
    range: [f64; 2],
    samples: &[(f64, f64)],
    noise_var: f64,
    opt: &IdentOptions,
) -> DryFit {
    let mut blr = Blr::new(
        range[0],
        range[1],
        opt.blr.degree,
        opt.blr.prior_std,
        noise_var,
    );
    for &(p, y) in samples {
        blr.add(p, y);
    }
    dry_fit_from(&blr, noise_var, opt.curve_points)
}

/// Summarises a posterior as a [`DryFit`].
pub fn dry_fit_from(blr: &Blr, noise_var: f64, curve_points: usize) -> DryFit {
    let (c, cov) = blr.coefficients();
    let se: Vec<f64> = (0..c.len()).map(|i| cov[i][i].sqrt()).collect();
    let corr = (0..c.len())
        .map(|i| (0..c.len()).map(|j| cov[i][j] / (se[i] * se[j])).collect())
        .collect();
    DryFit {
        coefficients: c,
        std_err: se,
        correlation: corr,
        positions: blr.xs.clone(),
        forces: blr.ys.clone(),
        noise_var,
        curve: blr.curve(curve_points),
    }
}

/// `(position [m], force [N])` pairs.
pub type Samples2 = Vec<(f64, f64)>;

/// Breakaway samples `(position, force)` of `axis` (0 X, 1 Y) per direction (positive,
/// negative) found in the data set's ramps, with force `gain * |onset voltage|`.
///
/// `lag`: the drive's `(Dbar+ / K, Dbar- / K, M / Dbar+, M / Dbar-)` to correct the detection
/// lag ([`corrected_onset`]); `None` takes the onsets as seen.
pub fn breakaway_samples(
    ds: &Dataset,
    axis: usize,
    gain: f64,
    lag: Option<[f64; 4]>,
) -> (Samples2, Samples2) {
    let kind = if axis == 0 {
        RunKind::BreakawayX
    } else {
        RunKind::BreakawayY
    };
    let th = 0.5 * ds.spec.constants.resolution(axis);
    let mut pos = Vec::new();
    let mut neg = Vec::new();
    for run in ds.of_kind(kind) {
        let Some(cr) = run.crane() else { continue };
        let o = detect_onset(cr, axis, th).and_then(|raw| match lag {
            Some(l) if raw.volts > 0.0 => corrected_onset(cr, axis, 2.0 * th, l[0], l[2]),
            Some(l) => corrected_onset(cr, axis, 2.0 * th, l[1], l[3]),
            None => Some(raw),
        });
        if let Some(o) = o {
            let s = (o.position, gain * o.volts.abs());
            if o.volts > 0.0 {
                pos.push(s);
            } else {
                neg.push(s);
            }
        }
    }
    (pos, neg)
}

/// Least squares of the direction-dependent viscous coefficients of a drive given its gain,
/// moved mass and dry friction: `K u - M a - Cbar(q) sgn = Dbar+ v+ + Dbar- v-`.
#[allow(clippy::too_many_arguments)]
fn viscous_fit(
    ds: &Dataset,
    axis: usize,
    kind: RunKind,
    name: &'static str,
    gain: f64,
    mass: f64,
    dry_pos: &DryFit,
    dry_neg: &DryFit,
    opt: &IdentOptions,
) -> Result<LsFit, IdentError> {
    let mut cols = Columns::new(&["Dbar+", "Dbar-"]);
    for run in ds.of_kind(kind) {
        let Some(cr) = run.crane() else { continue };
        let (cp, cn) = (poly5(&dry_pos.coefficients), poly5(&dry_neg.coefficients));
        let dry = |p: f64, v: f64| {
            if v > 0.0 {
                crane_model::friction::dry(&cp, p)
            } else if v < 0.0 {
                -crane_model::friction::dry(&cn, p)
            } else {
                0.0
            }
        };
        let s = drive_signals(cr.pos(axis), &cr.u[axis], gain, cr.dt(), opt, dry);
        let m = mass + run.payload_kg;
        for k in 0..s.v.len() {
            if s.keep[k] {
                cols.push(
                    &[s.v_pos[k], s.v_neg[k]],
                    s.drive_minus_friction[k] - m * s.a[k],
                );
            }
        }
    }
    if cols.y.is_empty() {
        return Err(IdentError::Missing(name));
    }
    Ok(cols.fit(name)?)
}

/// X or Y step (`axis` 0 or 1): gain and inertia from the rope, dry friction, viscous.
pub fn identify_drive(
    ds: &Dataset,
    axis: usize,
    rope: &RopeResult,
    opt: &IdentOptions,
) -> Result<DriveResult, IdentError> {
    let c = &ds.spec.constants;
    let (r_axis, range, noise, kind, mass, name) = if axis == 0 {
        (
            c.pulley_radius_x_m,
            c.x_range_m,
            (
                ds.spec.breakaway_noise_var.x_pos,
                ds.spec.breakaway_noise_var.x_neg,
            ),
            RunKind::MotionX,
            c.trolley_mass_kg + c.rail_mass_kg,
            "motion_x",
        )
    } else {
        (
            c.pulley_radius_y_m,
            c.y_range_m,
            (
                ds.spec.breakaway_noise_var.y_pos,
                ds.spec.breakaway_noise_var.y_neg,
            ),
            RunKind::MotionY,
            c.trolley_mass_kg,
            "motion_y",
        )
    };
    let ratio_r = c.pulley_radius_l_m / r_axis;
    let gain = Estimate::new(rope.gain.value * ratio_r, rope.gain.std_err * ratio_r);
    let inertia = Estimate::new(
        rope.inertia.value * ratio_r * ratio_r,
        rope.inertia.std_err * ratio_r * ratio_r,
    );
    // Breakaway mass moved by the drive (payload of the probes: none).
    let m_probe = mass + inertia.value;
    let mut lag: Option<[f64; 4]> = None;
    let mut out = None;
    for _pass in 0..2 {
        let (sp, sn) = breakaway_samples(ds, axis, gain.value, lag);
        if sp.is_empty() || sn.is_empty() {
            return Err(IdentError::Missing(if axis == 0 {
                "breakaway_x"
            } else {
                "breakaway_y"
            }));
        }
        let dry_pos = fit_dry(range, &sp, noise.0, opt);
        let dry_neg = fit_dry(range, &sn, noise.1, opt);
        let fit = viscous_fit(
            ds,
            axis,
            kind,
            name,
            gain.value,
            mass + inertia.value,
            &dry_pos,
            &dry_neg,
            opt,
        )?;
        let (dp, dn) = (fit.theta[0], fit.theta[1]);
        lag = Some([dp / gain.value, dn / gain.value, m_probe / dp, m_probe / dn]);
        out = Some((dry_pos, dry_neg, fit));
    }
    let Some((dry_pos, dry_neg, fit)) = out else {
        return Err(IdentError::Missing(name));
    };
    Ok(DriveResult {
        gain,
        inertia,
        viscous_pos: Estimate::new(fit.theta[0], fit.std_err[0]),
        viscous_neg: Estimate::new(fit.theta[1], fit.std_err[1]),
        fit_viscous: fit,
        dry_pos,
        dry_neg,
    })
}

/// First sample after which no drive encoder changes any more (the trolley, rail and rope
/// are at rest for the rest of the run).
fn rest_start(cr: &CraneRun) -> usize {
    let mut last = 0;
    for k in 1..cr.len() {
        if cr.x[k] != cr.x[k - 1] || cr.y[k] != cr.y[k - 1] || cr.l[k] != cr.l[k - 1] {
            last = k;
        }
    }
    last
}

/// Swing step: `D_alpha`, `D_beta` from the free swings.
///
/// With the drives at rest the swing's energy `E = 1/2 m L^2 (ad^2 + sa^2 bd^2) - m g L sa cb`
/// obeys `dE/dt = -D_alpha ad^2 - D_beta bd^2`, the paper's two swing equations multiplied by
/// `ad` and `bd` and added. Over consecutive windows of `swing_window_s` the least squares of
/// `-(E(t2) - E(t1))` on `int ad^2` and `int bd^2` gives the coefficients. The per-sample
/// (differential) least squares of the paper is reported next to it.
pub fn identify_swing(ds: &Dataset, opt: &IdentOptions) -> Result<SwingResult, IdentError> {
    let g = ds.spec.constants.gravity;
    let mut energy = Columns::new(&["D_alpha", "D_beta"]);
    let mut diff_a = Columns::new(&["D_alpha"]);
    let mut diff_b = Columns::new(&["D_beta"]);
    let mut seconds = 0.0;
    for run in ds.of_kind(RunKind::FreeSwing) {
        let Some(cr) = run.crane() else { continue };
        let m = run.payload_kg;
        if m <= 0.0 {
            continue;
        }
        let dt = cr.dt();
        let edge = (opt.edge_s / dt).round() as usize;
        let start = rest_start(cr) + edge;
        if start + 2 * edge >= cr.len() {
            continue;
        }
        let l = cr.l[start];
        let filt = opt.filter(dt);
        let a = derive(&filt, &cr.alpha[start..], dt);
        let b = derive(&filt, &cr.beta[start..], dt);
        let n = a.p.len();
        let e: Vec<f64> = (0..n)
            .map(|k| {
                let (sa, ca) = a.p[k].sin_cos();
                let _ = ca;
                let (sb, cb) = b.p[k].sin_cos();
                let _ = sb;
                0.5 * m * l * l * (a.v[k] * a.v[k] + sa * sa * b.v[k] * b.v[k])
                    - m * g * l * sa * cb
            })
            .collect();
        let w = (opt.swing_window_s / dt).round().max(2.0) as usize;
        let mut k0 = edge;
        while k0 + w + edge < n {
            let k1 = k0 + w;
            // trapezoid integrals of ad^2, bd^2
            let mut ia = 0.0;
            let mut ib = 0.0;
            for k in k0..k1 {
                ia += 0.5 * dt * (a.v[k] * a.v[k] + a.v[k + 1] * a.v[k + 1]);
                ib += 0.5 * dt * (b.v[k] * b.v[k] + b.v[k + 1] * b.v[k + 1]);
            }
            energy.push(&[ia, ib], -(e[k1] - e[k0]));
            k0 = k1;
        }
        seconds += (n - 2 * edge) as f64 * dt;
        for k in edge..n - edge {
            let (sa, ca) = a.p[k].sin_cos();
            let (sb, cb) = b.p[k].sin_cos();
            let ml2 = m * l * l;
            let ya = -(ml2 * a.a[k] - ml2 * sa * ca * b.v[k] * b.v[k] - m * g * l * ca * cb);
            let yb = -(ml2 * sa * sa * b.a[k]
                + 2.0 * ml2 * sa * ca * a.v[k] * b.v[k]
                + m * g * l * sa * sb);
            diff_a.push(&[a.v[k]], ya);
            diff_b.push(&[b.v[k]], yb);
        }
    }
    if energy.y.len() < 3 {
        return Err(IdentError::Missing("free_swing"));
    }
    let fit = energy.fit("swing energy balance")?;
    let est = |f: Result<LsFit, LsError>| f.ok().map(|f| Estimate::new(f.theta[0], f.std_err[0]));
    Ok(SwingResult {
        damping_alpha: Estimate::new(fit.theta[0], fit.std_err[0]),
        damping_beta: Estimate::new(fit.theta[1], fit.std_err[1]),
        differential_alpha: est(diff_a.fit("swing alpha")),
        differential_beta: est(diff_b.fit("swing beta")),
        fit_energy: fit,
        seconds_used: seconds,
    })
}

/// The whole identification on a loaded data set.
pub fn identify_dataset(ds: &Dataset, opt: &IdentOptions) -> Result<Identified, IdentError> {
    let rope = identify_rope(ds, opt)?;
    let x = identify_drive(ds, 0, &rope, opt)?;
    let y = identify_drive(ds, 1, &rope, opt)?;
    let swing = identify_swing(ds, opt)?;
    let c = &ds.spec.constants;
    let mut p = Params::default();
    p.payload_mass = match ds.spec.payload_kg {
        Some(m) if m > 0.0 => m,
        _ => p.payload_mass,
    };
    p.trolley_mass = c.trolley_mass_kg;
    p.rail_mass = c.rail_mass_kg;
    p.gravity = c.gravity;
    for (ax, r, range) in [(&mut p.x, &x, c.x_range_m), (&mut p.y, &y, c.y_range_m)] {
        ax.inertia = r.inertia.value;
        ax.gain = r.gain.value;
        ax.viscous_pos = r.viscous_pos.value;
        ax.viscous_neg = r.viscous_neg.value;
        ax.dry_pos = poly5(&r.dry_pos.coefficients);
        ax.dry_neg = poly5(&r.dry_neg.coefficients);
        ax.min = range[0];
        ax.max = range[1];
    }
    p.rope.inertia = rope.inertia.value;
    p.rope.gain = rope.gain.value;
    p.rope.viscous_pos = rope.viscous.value;
    p.rope.viscous_neg = rope.viscous.value;
    p.rope.dry_pos = [rope.dry.value, 0.0, 0.0, 0.0, 0.0];
    p.rope.dry_neg = p.rope.dry_pos;
    p.rope.min = c.l_range_m[0];
    p.rope.max = c.l_range_m[1];
    p.damping_alpha = swing.damping_alpha.value.max(0.0);
    p.damping_beta = swing.damping_beta.value.max(0.0);
    Ok(Identified {
        rope,
        x,
        y,
        swing,
        params: p,
        options: *opt,
    })
}

/// Loads a data set directory and identifies every parameter (default options).
pub fn identify(dataset_dir: &std::path::Path) -> Result<Identified, IdentError> {
    identify_with(dataset_dir, &IdentOptions::default())
}

/// Loads a data set directory and identifies every parameter.
pub fn identify_with(
    dataset_dir: &std::path::Path,
    opt: &IdentOptions,
) -> Result<Identified, IdentError> {
    let ds = crate::data::load_dataset(dataset_dir)?;
    identify_dataset(&ds, opt)
}

/// The constants' resolution helper for callers that only hold [`Constants`].
pub fn resolution(c: &Constants, i: usize) -> f64 {
    c.resolution(i)
}

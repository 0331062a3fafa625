//! Stage 2: one estimator for every model structure (the baseline and each extension), so a
//! gain is never an artifact of a weaker fit of the baseline.
//!
//! 1. Sliding least squares: on the samples where the axis clearly slides
//!    (`|v| > v_slide`), `F = J a + k s(x) + Fk+ [v > 0] - Fk- [v < 0] + D+ v+ + D- v- (+ F0)`
//!    with `F` the (delayed, saturated, dead-banded) input and `s(x)` the restoring shape; every
//!    coefficient is kept in its physical range by an active-set solve (`J` above a floor,
//!    `k`, `Fk`, `D` >= 0) and a coefficient held at its bound is flagged.
//! 2. Breakaway at first motion: per fitting run and direction, the applied force net of the
//!    modelled position force and offset where the motion starts ([`super::prep::onset`]: the
//!    first sample moving faster than `v_move`, walked back to the start of the rise); the
//!    median over runs. Without stiction the one dry level is this or the sliding least
//!    squares' ([`DryLevel`], chosen by the caller on the fitting runs). Its scatter is that of every rest-to-motion onset in the fitting runs.
//! 3. Kinetic friction above the breakaway level is clamped to it (flagged): the hybrid model
//!    needs `breakaway >= kinetic`.
//!
//! Samples at rest never enter the least squares with the sign of a noisy velocity: a resting
//! axis only says that its net force stayed inside the breakaway band, which is what the
//! simulation scores.

use super::breakaway::{self, Interval};
use super::prep::{departure, motions, onset, Prepared, Thresholds};
use crane_model::drive::{DriveParams, LocalFriction, Motion, PositionForce};
use crane_model::extensions::deadband;
use std::fmt;

/// A direction of motion.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Dir {
    /// Increasing position.
    Positive,
    /// Decreasing position.
    Negative,
}

impl Dir {
    /// Both directions.
    pub const BOTH: [Dir; 2] = [Dir::Positive, Dir::Negative];
    /// `+1` or `-1`.
    pub fn sign(self) -> f64 {
        match self {
            Dir::Positive => 1.0,
            Dir::Negative => -1.0,
        }
    }
    fn index(self) -> usize {
        match self {
            Dir::Positive => 0,
            Dir::Negative => 1,
        }
    }
}

impl fmt::Display for Dir {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Dir::Positive => "positive",
            Dir::Negative => "negative",
        })
    }
}

/// Which effects a model structure contains (the baseline has none of the optional ones).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Structure {
    /// Position-dependent restoring force (pendulum for rotary axes, spring for linear ones).
    pub restoring: bool,
    /// Breakaway above kinetic friction, measured at first motion.
    pub stiction: bool,
    /// Kinetic and viscous friction per direction (else one value for both).
    pub asymmetric: bool,
    /// A constant force offset.
    pub offset: bool,
    /// Input dead band [input units] (>= 0; fixed, searched on a grid by the caller).
    pub deadband: f64,
    /// Input delay [samples] (>= 0, fractional: the input is read between samples, see
    /// [`delayed`]; fixed, searched on a grid and refined by the caller).
    pub delay: f64,
    /// Input saturation level [input units]: the effort applied is `clamp(u, -s, +s)`;
    /// `0`: no saturation (fixed, searched on a grid by the caller).
    pub saturation: f64,
    /// Load-dependent dry friction `mu` [1]: every dry level plus `mu |F|` of the applied
    /// effort; 0: none (fixed, searched on a grid by the caller). The least squares sees the
    /// effort net of it, `F - mu sign(v) |F|`: as its own regressor `sign(v) |F|` is nearly
    /// `F` itself while the drive pushes the motion, and the solve trades `mu` against the
    /// inertia and friction (stranger rigs: `mu` 0.99, the inertia at its floor).
    pub load: f64,
    /// Localized friction: a bump of dry friction at this site (fixed, chosen by the caller),
    /// its amplitude fitted by the sliding least squares as the coefficient of
    /// `sign(v) kernel(x)`; `None`: no bump.
    pub bump: Option<BumpSite>,
    /// Stribeck velocity [m/s or rad/s] (velocity weakening: the dry friction of a moving axis
    /// is `kinetic + (breakaway - kinetic) exp(-(v / stribeck)^2)`, the model's
    /// [`DriveParams::stribeck_velocity`]); needs [`Self::stiction`]; 0: none (fixed, searched
    /// on a grid by the caller).
    pub stribeck: f64,
}

impl Structure {
    /// The Stribeck weight `exp(-(v / stribeck)^2)` of a velocity `v` [1]: 1 at rest, 0 far
    /// above the Stribeck velocity; 0 without velocity weakening.
    pub fn stribeck_weight(&self, v: f64) -> f64 {
        if self.stribeck > 0.0 {
            let r = v / self.stribeck;
            libm::exp(-(r * r))
        } else {
            0.0
        }
    }
}

/// Where a bump of dry friction sits: `b(x) = A (1 - s^2)^2` for `|s| < 1`,
/// `s = (x - center) / half_width` (the model's [`LocalFriction::Bump`] kernel).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BumpSite {
    /// Centre [m or rad].
    pub center: f64,
    /// Half-width of the support [m or rad] (> 0).
    pub half_width: f64,
}

impl BumpSite {
    /// The kernel `(1 - s^2)^2` at `x` (0 outside the support) [1].
    pub fn kernel(&self, x: f64) -> f64 {
        let s = (x - self.center) / self.half_width;
        if s.abs() < 1.0 {
            let w = 1.0 - s * s;
            w * w
        } else {
            0.0
        }
    }
}

/// Something the estimator had to decide that the report must say.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case", tag = "flag")]
pub enum Flag {
    /// The inertia came out at (or below) its floor: not identifiable from these data.
    InertiaAtFloor {
        /// The floor used [kg or kg m^2, input units per acceleration].
        floor: f64,
    },
    /// The inertia's time constant with the viscous friction is below [`UNRESOLVED_TAU`] of
    /// the sample period: the log does not measure it (treated as at its floor).
    InertiaUnresolved {
        /// `inertia / viscous` [s].
        time_constant: f64,
        /// The fitting runs' shortest sample period [s].
        period: f64,
    },
    /// Too few sliding samples in this direction: its friction is not fitted but copied
    /// from the other direction.
    DirectionNotFitted {
        /// The direction.
        dir: Dir,
        /// Sliding samples found.
        samples: usize,
    },
    /// The least-squares kinetic friction lay above the breakaway level at first motion and
    /// was clamped to it (the model needs breakaway >= kinetic).
    KineticClamped {
        /// The direction.
        dir: Dir,
        /// The least-squares value [force units].
        least_squares: f64,
    },
    /// No first motion in this direction in any fitting run: breakaway set to kinetic.
    NoFirstMotion {
        /// The direction.
        dir: Dir,
    },
    /// A coefficient that must be >= 0 came out negative and is held at 0.
    AtZero {
        /// Which coefficient.
        coefficient: Coefficient,
    },
}

/// Names of the fitted coefficients that can sit at a bound.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Coefficient {
    /// Restoring stiffness.
    Stiffness,
    /// Kinetic friction, positive direction.
    KineticPos,
    /// Kinetic friction, negative direction.
    KineticNeg,
    /// Viscous friction, positive direction.
    ViscousPos,
    /// Viscous friction, negative direction.
    ViscousNeg,
}

impl fmt::Display for Flag {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Flag::InertiaAtFloor { floor } => write!(
                f,
                "inertia not identifiable from the sliding samples: held at its floor {floor:.4}"
            ),
            Flag::InertiaUnresolved {
                time_constant,
                period,
            } => write!(
                f,
                "inertia not identifiable from the sliding samples: its time constant with the viscous friction, {time_constant:.2e} s, is below {UNRESOLVED_TAU} of the sample period {period:.2e} s (the velocity would settle within a sample whatever the inertia); the derivative window may hold too few fresh positions"
            ),
            Flag::DirectionNotFitted { dir, samples } => write!(
                f,
                "{dir} direction: only {samples} sliding samples, friction not fitted (copied from the other direction)"
            ),
            Flag::KineticClamped { dir, least_squares } => write!(
                f,
                "{dir} direction: sliding friction {least_squares:.4} above the breakaway level at first motion, clamped to it"
            ),
            Flag::NoFirstMotion { dir } => write!(
                f,
                "{dir} direction: no first motion in any fitting run, breakaway not measured (set to kinetic)"
            ),
            Flag::AtZero { coefficient } => {
                write!(f, "{coefficient:?} held at 0 (the fit wanted a negative value)")
            }
        }
    }
}

/// The fitted model and how it was obtained.
#[derive(Clone, Debug)]
pub struct Estimate {
    /// Parameters for the simulator (input units, `gain = 1`, `delay_steps = 0`: the delay is
    /// applied to the recorded input, see [`Structure::delay`]).
    pub params: DriveParams,
    /// The structure.
    pub structure: Structure,
    /// Decisions the report must state.
    pub flags: Vec<Flag>,
    /// Net force at first motion per fitting run, positive and negative direction
    /// (magnitudes) [force units].
    pub first_motion: [Vec<f64>; 2],
    /// Standard deviation of the net force at every rest-to-motion onset of the fitting runs,
    /// per direction [force units] (`None` with fewer than 2 onsets).
    pub breakaway_scatter: [Option<f64>; 2],
    /// Kinetic friction from the sliding least squares, before any clamp [force units].
    pub kinetic_ls: [f64; 2],
    /// Per slip of the fitting runs (rest to rest) and direction: its onset level minus its
    /// mean kinetic friction from the energy balance [force units]; > 0 is stiction.
    pub slip_gaps: [Vec<f64>; 2],
    /// Sliding samples used.
    pub rows: usize,
    /// Where the dry-friction level of a structure without stiction came from.
    pub level: DryLevel,
}

/// Why a structure cannot be fitted.
#[derive(Clone, Debug, PartialEq)]
pub enum EstimateError {
    /// Fewer sliding samples than coefficients (both directions).
    TooFewSliding {
        /// Sliding samples found.
        samples: usize,
    },
    /// The least squares was singular.
    Singular,
}

impl fmt::Display for EstimateError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            EstimateError::TooFewSliding { samples } => write!(
                f,
                "only {samples} sliding samples in the fitting runs: friction and inertia are not identifiable"
            ),
            EstimateError::Singular => f.write_str("the sliding least squares is singular"),
        }
    }
}

/// Minimum sliding samples for a direction's friction to be fitted.
pub const MIN_DIRECTION_ROWS: usize = 8;

/// The restoring shape for an axis kind: `sin(x - c)` (rotary: gravity on a joint) or `x - c`.
pub fn restoring_shape(motion: Motion, x: f64, center: f64) -> f64 {
    match motion {
        Motion::Rotary => libm::sin(x - center),
        Motion::Linear => x - center,
    }
}

/// The recorded input `u` read `delay` samples before sample `i` [input units]: the first
/// value is held before the record starts, and between samples the two neighbours are
/// weighted linearly. For a zero-order-held input delayed by `n + f` sample periods (`n`
/// whole, `0 <= f < 1`), that weighting is the input's exact mean over the period `i`:
/// `f u[i-n-1] + (1-f) u[i-n]`. A whole delay reads one sample exactly.
pub fn delayed(u: &[f64], i: usize, delay: f64) -> f64 {
    let Some(&first) = u.first() else {
        return 0.0;
    };
    if delay == 0.0 {
        // no delay reads sample `i` itself (what the interpolation below gives, bit for bit)
        return u.get(i).copied().unwrap_or(first);
    }
    let t = i as f64 - delay;
    if t.is_nan() || t <= 0.0 {
        return first;
    }
    let j = t.floor();
    let f = t - j;
    let a = u.get(j as usize).copied().unwrap_or(first);
    if f == 0.0 {
        a
    } else {
        let b = u.get(j as usize + 1).copied().unwrap_or(a);
        a + f * (b - a)
    }
}

/// The input a structure applies at sample `i` of a run: delayed ([`delayed`]), saturated
/// and dead-banded [input units].
pub fn applied_input(u: &[f64], i: usize, s: &Structure) -> f64 {
    deadband(saturate(delayed(u, i, s.delay), s), s.deadband)
}

/// `u` clamped to the structure's saturation level (`[-s, s]`; unchanged when `s` is 0).
pub fn saturate(u: f64, s: &Structure) -> f64 {
    if s.saturation > 0.0 {
        u.clamp(-s.saturation, s.saturation)
    } else {
        u
    }
}

/// Where a structure without stiction takes its one dry-friction level from (per direction).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DryLevel {
    /// The net force where the axis leaves rest at the start of each fitting run (median):
    /// right for short stick-slip motions, where few samples slide.
    FirstMotion,
    /// The sliding least squares: right for long slides, where the few run starts give a
    /// noisy median.
    Sliding,
}

/// Fits a structure on the fitting runs; `level` matters only without stiction (with it, the
/// breakaway is always measured at first motion and the kinetic level by the energy balance).
pub fn estimate(
    fit: &[&Prepared],
    th: &Thresholds,
    motion: Motion,
    center: f64,
    s: Structure,
    level: DryLevel,
) -> Result<Estimate, EstimateError> {
    let sliding = Sliding::new(fit, th, motion, center, s)?;
    sliding.estimate(fit, th, level)
}

/// Stage 1 of [`estimate`], the sliding least squares with every coefficient free: the same
/// for either [`DryLevel`], so a caller that fits both ([`super::experiment::Experiment::fit_only`])
/// solves it once.
pub struct Sliding {
    motion: Motion,
    center: f64,
    s: Structure,
    rows: Vec<(f64, f64, f64, f64, f64)>,
    lc: LsColumns,
    first: LsFit,
    flags: Vec<Flag>,
    fit_pos: bool,
    fit_neg: bool,
    asym: bool,
}

impl Sliding {
    /// The sliding rows of structure `s` on the fitting runs and their first least squares.
    pub fn new(
        fit: &[&Prepared],
        th: &Thresholds,
        motion: Motion,
        center: f64,
        s: Structure,
    ) -> Result<Sliding, EstimateError> {
        let mut rows = sliding_rows(fit, th, motion, center, &s);
        let n_pos = rows.iter().filter(|r| r.3 > 0.0).count();
        let n_neg = rows.len() - n_pos;
        let fit_pos = n_pos >= MIN_DIRECTION_ROWS;
        let fit_neg = n_neg >= MIN_DIRECTION_ROWS;
        let mut flags = Vec::new();
        if !fit_pos && !fit_neg {
            return Err(EstimateError::TooFewSliding {
                samples: rows.len(),
            });
        }
        for (dir, ok, n) in [
            (Dir::Positive, fit_pos, n_pos),
            (Dir::Negative, fit_neg, n_neg),
        ] {
            if !ok {
                flags.push(Flag::DirectionNotFitted { dir, samples: n });
            }
        }
        // drop rows of a direction that is not fitted
        rows.retain(|r| (r.3 > 0.0 && fit_pos) || (r.3 < 0.0 && fit_neg));
        let asym = s.asymmetric && fit_pos && fit_neg;
        let both = fit_pos && fit_neg;
        // pass 1: every coefficient free (within its bounds)
        let lc = ls_columns(&rows, &s, asym, both);
        let first = ls_pass(&rows, &lc, &s, asym, None, [0.0; 2]).ok_or(EstimateError::Singular)?;
        Ok(Sliding {
            motion,
            center,
            s,
            rows,
            lc,
            first,
            flags,
            fit_pos,
            fit_neg,
            asym,
        })
    }

    /// Stages 2 and 3 of [`estimate`] with the dry level `level`.
    pub fn estimate(
        &self,
        fit: &[&Prepared],
        th: &Thresholds,
        level: DryLevel,
    ) -> Result<Estimate, EstimateError> {
        let (motion, center, s, rows, lc) =
            (self.motion, self.center, self.s, &self.rows, &self.lc);
        let (fit_pos, fit_neg, asym) = (self.fit_pos, self.fit_neg, self.asym);
        let mut flags = self.flags.clone();
        let kinetic_ls = self.first.kin;
        let mut ls = self.first.clone();
        // --- 2. breakaway at first motion, 3. kinetic <= breakaway -----------------------------
        // The breakaway level is measured where the axis leaves rest (net of the modelled position
        // force), for every structure: resting samples are constraints, not sliding rows. Without
        // stiction the dry friction is that one level and the least squares is solved again with
        // it fixed; with stiction the sliding level may lie below it.
        let mut brk = [0.0; 2];
        let mut first_motion: [Vec<f64>; 2] = [Vec::new(), Vec::new()];
        let mut breakaway_scatter = [None, None];
        let mut kin_flags = Vec::new();
        let mut gaps: [Vec<f64>; 2] = [Vec::new(), Vec::new()];
        for _pass in 0..2 {
            let on = onset_levels(fit, th, &s, motion, center, &ls);
            first_motion = on.first_motion;
            breakaway_scatter = [0, 1].map(|d| {
                breakaway::level(&on.all[d]).and_then(|b| breakaway::scatter(&on.all[d], b))
            });
            kin_flags.clear();
            for dir in Dir::BOTH {
                let d = dir.index();
                brk[d] = match breakaway::level(&on.first[d]) {
                    Some(b) => b.max(0.0),
                    None => {
                        kin_flags.push(Flag::NoFirstMotion { dir });
                        ls.kin[d]
                    }
                };
            }
            if !fit_pos && first_motion[0].is_empty() {
                brk[0] = brk[1];
            }
            if !fit_neg && first_motion[1].is_empty() {
                brk[1] = brk[0];
            }
            // kinetic friction of the stiction structure: from the energy balance of every slip
            // (rest to rest, so the kinetic energy is 0 at both ends):
            // mean friction = integral (F - P(x)) dx / dx_total, minus the viscous part; the gap
            // of a slip is its onset level minus that. This needs no acceleration estimate, which
            // at a few samples per slip is the least reliable signal.
            gaps = slip_gaps(
                fit,
                th,
                &s,
                motion,
                center,
                ls.stiffness,
                ls.offset,
                ls.visc,
                brk,
            );
            if !s.stiction && level == DryLevel::Sliding {
                brk = kinetic_ls;
            }
            let mut fixed = brk;
            // with velocity weakening the sliding least squares itself, its dry columns
            // weighted by `1 - g(v)` (see [`weakened_kinetic`]); with plain stiction the
            // slips' energy balance
            let weakened = (s.stiction && s.stribeck > 0.0)
                .then(|| weakened_kinetic(rows, &s, asym, fit_pos && fit_neg, brk))
                .flatten();
            for dir in Dir::BOTH {
                let d = dir.index();
                if !s.stiction {
                    continue;
                }
                let kinetic = match weakened {
                    Some(k) => k[d],
                    None if gaps[d].is_empty() => ls.kin[d],
                    None => brk[d] - mean(&gaps[d]),
                };
                if kinetic > brk[d] {
                    kin_flags.push(Flag::KineticClamped {
                        dir,
                        least_squares: kinetic,
                    });
                } else {
                    fixed[d] = kinetic.max(0.0);
                }
            }
            ls = ls_pass(rows, lc, &s, asym, Some(fixed), brk).ok_or(EstimateError::Singular)?;
            ls.kin = fixed;
        }
        flags.extend(ls.flags.iter().copied());
        flags.extend(kin_flags);
        let (mut kin, mut visc) = (ls.kin, ls.visc);
        // a direction that was not fitted copies the other one
        if !fit_pos {
            kin[0] = kin[1];
            visc[0] = visc[1];
        }
        if !fit_neg {
            kin[1] = kin[0];
            visc[1] = visc[0];
        }
        for d in 0..2 {
            kin[d] = kin[d].min(brk[d]);
        }
        if let Some(f) = unresolved(fit, ls.inertia, visc) {
            flags.push(f);
        }
        let params = drive_params(motion, center, &s, &ls, kin, visc, brk);
        Ok(Estimate {
            params,
            structure: s,
            flags,
            first_motion,
            breakaway_scatter,
            kinetic_ls,
            slip_gaps: gaps,
            rows: rows.len(),
            level,
        })
    }
}

/// The kinetic levels `[positive, negative]` [force units] of a velocity-weakening structure
/// ([`Structure::stribeck`]) from the sliding least squares: the dry friction of a row at
/// velocity `v` is `kinetic (1 - g) + breakaway g`, `g` the Stribeck weight, so the
/// breakaway's share moves to the left-hand side and the kinetic columns are weighted by
/// `1 - g`; inertia, viscous and position terms are fitted with them. `None` when singular.
///
/// Not the slips' energy balance (plain stiction's): that needs the viscous coefficient of a
/// least squares whose dry level was fixed, and under weakening the two trade against each
/// other (stranger s062, a Stribeck velocity of 0.32 rad/s over slides to 2.7 rad/s: kinetic
/// 1.10 and viscous 1.02 against a true 0.98 and 1.11; this least squares: 0.94 and 1.12).
fn weakened_kinetic(
    rows: &[(f64, f64, f64, f64, f64)],
    s: &Structure,
    asym: bool,
    both: bool,
    brk: [f64; 2],
) -> Option<[f64; 2]> {
    let net: Vec<(f64, f64, f64, f64, f64)> = rows
        .iter()
        .map(|r| {
            let b = if r.3 > 0.0 { brk[0] } else { -brk[1] };
            (r.0 - b * s.stribeck_weight(r.3), r.1, r.2, r.3, r.4)
        })
        .collect();
    let plain = Structure {
        stribeck: 0.0,
        ..*s
    };
    let mut lc = ls_columns(&net, &plain, asym, both);
    for (c, col) in lc.cols.iter_mut() {
        if matches!(c, Col::KineticPos | Col::KineticNeg | Col::KineticSym) {
            for (x, r) in col.iter_mut().zip(&net) {
                *x *= 1.0 - s.stribeck_weight(r.3);
            }
        }
    }
    let refs: Vec<&[f64]> = lc.cols.iter().map(|(_, c)| c.as_slice()).collect();
    lc.gram = crate::fit::gram(&refs, net.len(), None);
    ls_pass(&net, &lc, &plain, asym, None, [0.0; 2]).map(|f| f.kin)
}

/// The sliding samples as least-squares rows `(F, a, shape, v, x)`: the applied force (net of
/// the load share `mu |F|` against the motion) [force units], the acceleration [m/s^2 or
/// rad/s^2], the restoring shape, the velocity and the position.
fn sliding_rows(
    fit: &[&Prepared],
    th: &Thresholds,
    motion: Motion,
    center: f64,
    s: &Structure,
) -> Vec<(f64, f64, f64, f64, f64)> {
    let mut rows = Vec::new();
    for p in fit {
        for i in 0..p.run.x.len() {
            if p.v[i].abs() > th.v_slide {
                let f = applied_input(&p.run.u, i, s);
                rows.push((
                    f - s.load * p.v[i].signum() * f.abs(),
                    p.a[i],
                    restoring_shape(motion, p.run.x[i], center),
                    p.v[i],
                    p.run.x[i],
                ));
            }
        }
    }
    rows
}

/// The force withstood where the axis leaves rest, per direction (`[positive, negative]`,
/// each as a positive level [force units]): at the first motion of runs that start at rest,
/// and at every onset after at least 3 samples at rest. Net of the fitted position force,
/// offset and bump, and with load-dependent friction net of its load share (`F - mu |F|` is
/// the dry level).
fn onset_levels(
    fit: &[&Prepared],
    th: &Thresholds,
    s: &Structure,
    motion: Motion,
    center: f64,
    ls: &LsFit,
) -> Onsets {
    // the force withstood at an onset, net of the position force and offset, and with
    // load-dependent friction net of its load share (`F - mu |F|` is the dry level)
    let net = |p: &Prepared, i: usize| {
        let f = applied_input(&p.run.u, i, s);
        f - ls.stiffness * restoring_shape(motion, p.run.x[i], center) + ls.offset - s.load * f
    };
    // the bump's share of the force withstood where an onset rests
    let bump_at =
        |p: &Prepared, i: usize| s.bump.map_or(0.0, |site| ls.bump * site.kernel(p.run.x[i]));
    let mut first_motion: [Vec<f64>; 2] = [Vec::new(), Vec::new()];
    let mut first_iv: [Vec<Interval>; 2] = [Vec::new(), Vec::new()];
    let mut onsets: [Vec<Interval>; 2] = [Vec::new(), Vec::new()];
    for p in fit {
        let level = |i: usize, sg: f64| sg * net(p, i) - bump_at(p, i);
        for dir in Dir::BOTH {
            let sg = dir.sign();
            let m = motions(&p.v, th.v_move, sg);
            let from_rest = |i: usize| i >= 3 && p.v[i - 3..i].iter().all(|v| v.abs() <= th.v_move);
            // first motion: the run must start at rest, and the motion leave rest (not
            // reverse a motion the other way, where the force is no breakaway level)
            if p.v.iter().take(3).all(|v| v.abs() <= th.v_move) {
                if let Some(&(i, _)) = m.first().filter(|&&(i, _)| from_rest(i)) {
                    let o = left_rest(p, i, sg, th.v_move, s);
                    first_motion[dir.index()].push(level(o, sg));
                    first_iv[dir.index()].push(onset_interval(p, o, &|k| level(k, sg)));
                }
            }
            // every onset after at least 3 samples at rest
            for &(i, _) in &m {
                if from_rest(i) {
                    let o = left_rest(p, i, sg, th.v_move, s);
                    onsets[dir.index()].push(onset_interval(p, o, &|k| level(k, sg)));
                }
            }
        }
    }
    Onsets {
        first_motion,
        first: first_iv,
        all: onsets,
    }
}

/// Where a motion detected at sample `i` (direction `sign`) left rest: the velocity's onset
/// ([`onset`]), and with velocity weakening ([`Structure::stribeck`]) the position's departure
/// before it ([`departure`]): the friction then falls off only as the axis speeds up, so it
/// leaves rest slowly and crosses the motion threshold late, under a ramp at a force above
/// the level it left at (stranger s062, 250 Hz: breakaway 2.15 against a true 1.98; by the
/// position 2.05). Without weakening the axis leaves rest at once, and a creep before a slip
/// (CICESE) is no departure: the velocity's onset is kept.
fn left_rest(p: &Prepared, i: usize, sign: f64, v_move: f64, s: &Structure) -> usize {
    let o = onset(p, i, sign);
    if s.stiction && s.stribeck > 0.0 {
        departure(p, o, sign, v_move)
    } else {
        o
    }
}

/// The onsets of motion of the fitting runs, per direction (`[positive, negative]`).
struct Onsets {
    /// The net force at each run's first motion (magnitudes) [force units].
    first_motion: [Vec<f64>; 2],
    /// The bounds each first motion puts on the breakaway level.
    first: [Vec<Interval>; 2],
    /// The bounds of every onset after at least 3 samples at rest.
    all: [Vec<Interval>; 2],
}

/// Samples before an onset whose net force bounds the breakaway from below: the axis held
/// them at rest (at least 3, and the smoothing's half window: the onset found may lie a
/// sample or two late, and then the last of them already carries a step's force).
fn held_samples(p: &Prepared) -> usize {
    p.w.max(3)
}

/// The bounds an onset at sample `o` puts on the breakaway level ([`breakaway`]): the least
/// net force `level` over the [`held_samples`] before it (held at rest), and the largest over
/// `o` and as many samples after it (the axis moves there; the onset found may lie a sample or
/// two early, before a step) [force units]. An onset at the first sample bounds it only from
/// above.
fn onset_interval(p: &Prepared, o: usize, level: &dyn Fn(usize) -> f64) -> Interval {
    let h = held_samples(p);
    let hi = (o..=(o + h).min(p.run.x.len().saturating_sub(1)).max(o))
        .map(level)
        .fold(f64::NEG_INFINITY, f64::max);
    let lo = (o.saturating_sub(h)..o)
        .map(level)
        .fold(f64::INFINITY, f64::min);
    Interval::new(if lo.is_finite() { lo } else { hi.min(0.0) }, hi)
}

/// The model's parameters from the final least squares `ls` with the dry levels `kin`
/// (kinetic) and `brk` (breakaway) and viscous coefficients `visc`, each `[positive,
/// negative]`.
fn drive_params(
    motion: Motion,
    center: f64,
    s: &Structure,
    ls: &LsFit,
    kin: [f64; 2],
    visc: [f64; 2],
    brk: [f64; 2],
) -> DriveParams {
    let (inertia, stiffness, offset) = (ls.inertia, ls.stiffness, ls.offset);
    let position_force = if s.restoring {
        match motion {
            Motion::Rotary => PositionForce::Pendulum { stiffness, center },
            Motion::Linear => PositionForce::Spring { stiffness, center },
        }
    } else {
        PositionForce::None
    };
    DriveParams {
        motion,
        inertia,
        gain: 1.0,
        viscous_pos: visc[0],
        viscous_neg: visc[1],
        kinetic_pos: kin[0],
        kinetic_neg: kin[1],
        breakaway_pos: brk[0],
        breakaway_neg: brk[1],
        offset,
        position_force,
        deadband: 0.0,
        delay_steps: 0,
        min: f64::NEG_INFINITY,
        max: f64::INFINITY,
        stribeck_velocity: if s.stiction { s.stribeck } else { 0.0 },
        load_friction: s.load,
        local_friction: match s.bump {
            Some(site) => LocalFriction::Bump {
                center: site.center,
                half_width: site.half_width,
                amplitude: ls.bump,
            },
            None => LocalFriction::None,
        },
    }
}

/// One sliding least-squares solve.
#[derive(Clone)]
struct LsFit {
    inertia: f64,
    stiffness: f64,
    offset: f64,
    kin: [f64; 2],
    visc: [f64; 2],
    /// Amplitude of the bump (0 without [`Structure::bump`]).
    bump: f64,
    flags: Vec<Flag>,
}

/// A time constant `inertia / viscous` below this fraction of the sample period is not
/// measured by the log: the velocity then settles within a sample (to `e^-10`) whatever the
/// inertia.
pub const UNRESOLVED_TAU: f64 = 0.1;

/// [`Flag::InertiaUnresolved`] when the fitted inertia's time constant with the larger
/// viscous coefficient is below [`UNRESOLVED_TAU`] of the fitting runs' shortest sample
/// period. Such an inertia is a derivative artefact, not a measurement (a 5 kHz log whose
/// window held 4 fresh positions gave `1.2e-4` against a true `1.06`, and each simulation of
/// that stiff model took thousands of steps per sample: 156 s for a 45,000-row log).
fn unresolved(fit: &[&Prepared], inertia: f64, visc: [f64; 2]) -> Option<Flag> {
    let dt = fit.iter().map(|p| p.run.dt).fold(f64::INFINITY, f64::min);
    unresolved_at(dt, inertia, visc)
}

/// [`unresolved`] for the shortest sample period `dt` [s]: also what
/// `Experiment::fit_error` asks of a model a refinement has scaled.
pub(super) fn unresolved_at(dt: f64, inertia: f64, visc: [f64; 2]) -> Option<Flag> {
    let tau = inertia / visc[0].max(visc[1]);
    (dt.is_finite() && tau.is_finite() && tau < UNRESOLVED_TAU * dt).then_some(
        Flag::InertiaUnresolved {
            time_constant: tau,
            period: dt,
        },
    )
}

/// The sliding rows' least-squares columns, built once per estimate: every pass solves with
/// them (the fixed-kinetic passes without the kinetic ones), so their normal matrix and the
/// inertia floor are computed once too.
struct LsColumns {
    /// Every column of the structure, in the solve's order.
    cols: Vec<(Col, Vec<f64>)>,
    /// Their normal matrix ([`crate::fit::gram`]).
    gram: Vec<Vec<f64>>,
    /// The inertia floor: a thousandth of the force-to-acceleration scale of the sliding rows.
    floor: f64,
}

/// The columns of rows `(F, a, shape, v, x)` for structure `s` (see [`ls_pass`]).
fn ls_columns(
    rows: &[(f64, f64, f64, f64, f64)],
    s: &Structure,
    asym: bool,
    both: bool,
) -> LsColumns {
    let mut cols: Vec<(Col, Vec<f64>)> = vec![(Col::Inertia, rows.iter().map(|r| r.1).collect())];
    if s.restoring {
        cols.push((Col::Stiffness, rows.iter().map(|r| r.2).collect()));
    }
    if asym {
        cols.push((
            Col::KineticPos,
            rows.iter().map(|r| f64::from(r.3 > 0.0)).collect(),
        ));
        cols.push((
            Col::KineticNeg,
            rows.iter().map(|r| -f64::from(r.3 < 0.0)).collect(),
        ));
    } else {
        cols.push((Col::KineticSym, rows.iter().map(|r| r.3.signum()).collect()));
    }
    if asym {
        cols.push((Col::ViscousPos, rows.iter().map(|r| r.3.max(0.0)).collect()));
        cols.push((Col::ViscousNeg, rows.iter().map(|r| r.3.min(0.0)).collect()));
    } else {
        cols.push((Col::ViscousSym, rows.iter().map(|r| r.3).collect()));
    }
    // an offset is separable from the kinetic levels only when both directions slide
    if s.offset && both {
        cols.push((Col::Offset, vec![1.0; rows.len()]));
    }
    if let Some(site) = s.bump {
        cols.push((
            Col::Bump,
            rows.iter()
                .map(|r| r.3.signum() * site.kernel(r.4))
                .collect(),
        ));
    }
    let refs: Vec<&[f64]> = cols.iter().map(|(_, c)| c.as_slice()).collect();
    let gram = crate::fit::gram(&refs, rows.len(), None);
    // inertia floor: a thousandth of the force-to-acceleration scale of the sliding rows
    let scale = median(rows.iter().map(|r| r.0.abs()).collect())
        / median(rows.iter().map(|r| r.1.abs()).collect()).max(1e-12);
    let floor = (1e-3 * scale).max(1e-9);
    LsColumns { cols, gram, floor }
}

/// Rows are `(F, a, shape, v, x)`, their columns `lc` ([`ls_columns`]). With `fixed_kinetic`
/// the dry levels are moved to the
/// left-hand side and only inertia, stiffness, viscous and offset are fitted; with velocity
/// weakening ([`Structure::stribeck`]) that dry level is the Stribeck blend of the fixed
/// kinetic level and `breakaway` ([force units], `[positive, negative]`) at each row's velocity.
fn ls_pass(
    rows: &[(f64, f64, f64, f64, f64)],
    lc: &LsColumns,
    s: &Structure,
    asym: bool,
    fixed_kinetic: Option<[f64; 2]>,
    breakaway: [f64; 2],
) -> Option<LsFit> {
    let kinetic = |c: Col| matches!(c, Col::KineticPos | Col::KineticNeg | Col::KineticSym);
    let sel: Vec<usize> = (0..lc.cols.len())
        .filter(|&i| fixed_kinetic.is_none() || !kinetic(lc.cols[i].0))
        .collect();
    let cols: Vec<(Col, &[f64])> = sel
        .iter()
        .map(|&i| (lc.cols[i].0, lc.cols[i].1.as_slice()))
        .collect();
    let gram: Vec<Vec<f64>> = sel
        .iter()
        .map(|&i| sel.iter().map(|&j| lc.gram[i][j]).collect())
        .collect();

    let y: Vec<f64> = rows
        .iter()
        .map(|r| {
            let g = s.stribeck_weight(r.3);
            match fixed_kinetic {
                Some(k) if r.3 > 0.0 => r.0 - (k[0] + (breakaway[0] - k[0]).max(0.0) * g),
                Some(k) => r.0 + (k[1] + (breakaway[1] - k[1]).max(0.0) * g),
                None => r.0,
            }
        })
        .collect();
    let floor = lc.floor;
    let lower: Vec<Option<f64>> = cols
        .iter()
        .map(|(c, _)| match c {
            Col::Inertia => Some(floor),
            Col::Offset | Col::Bump => None,
            _ => Some(0.0),
        })
        .collect();
    let col_refs: Vec<&[f64]> = cols.iter().map(|(_, c)| *c).collect();
    let (theta, at_bound) = bounded_ls_gram(&col_refs, &gram, &y, &lower)?;
    let get = |want: Col| {
        cols.iter()
            .position(|(c, _)| *c == want)
            .map(|i| (theta[i], at_bound[i]))
    };
    let mut flags = Vec::new();
    let (inertia, j_low) = get(Col::Inertia).unwrap_or((floor, true));
    if j_low {
        flags.push(Flag::InertiaAtFloor { floor });
    }
    let (stiffness, k_low) = get(Col::Stiffness).unwrap_or((0.0, false));
    if s.restoring && k_low {
        flags.push(Flag::AtZero {
            coefficient: Coefficient::Stiffness,
        });
    }
    // the column of ones carries `-offset` (the offset is on the applied side)
    let offset = get(Col::Offset).map_or(0.0, |g| -g.0);
    let bump = get(Col::Bump).map_or(0.0, |g| g.0);

    let mut at_zero = |c: Col, name: Coefficient| -> f64 {
        match get(c) {
            Some((v, true)) => {
                flags.push(Flag::AtZero { coefficient: name });
                v
            }
            Some((v, false)) => v,
            None => 0.0,
        }
    };
    let (kin, visc) = if asym {
        (
            [
                at_zero(Col::KineticPos, Coefficient::KineticPos),
                at_zero(Col::KineticNeg, Coefficient::KineticNeg),
            ],
            [
                at_zero(Col::ViscousPos, Coefficient::ViscousPos),
                at_zero(Col::ViscousNeg, Coefficient::ViscousNeg),
            ],
        )
    } else {
        let k = at_zero(Col::KineticSym, Coefficient::KineticPos);
        let v = at_zero(Col::ViscousSym, Coefficient::ViscousPos);
        ([k, k], [v, v])
    };
    Some(LsFit {
        inertia,
        stiffness,
        offset,
        kin: fixed_kinetic.unwrap_or(kin),
        visc,
        bump,
        flags,
    })
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Col {
    Inertia,
    Stiffness,
    KineticPos,
    KineticNeg,
    KineticSym,
    ViscousPos,
    ViscousNeg,
    ViscousSym,
    Offset,
    Bump,
}

/// Least squares with lower bounds by an active set: the most violating coefficient is fixed
/// at its bound and the rest re-solved, at most once per coefficient. Returns the
/// coefficients and which of them sit at their bound.
pub fn bounded_ls(
    cols: &[&[f64]],
    y: &[f64],
    lower: &[Option<f64>],
) -> Option<(Vec<f64>, Vec<bool>)> {
    bounded_ls_gram(cols, &crate::fit::gram(cols, y.len(), None), y, lower)
}

/// [`bounded_ls`] with the columns' normal matrix `gram` ([`crate::fit::gram`]) given: the
/// matrix of the free columns is its rows and columns of them (the same sums as a gram of
/// those columns alone), so every re-solve of the active set sums only its right-hand side.
fn bounded_ls_gram(
    cols: &[&[f64]],
    gram: &[Vec<f64>],
    y: &[f64],
    lower: &[Option<f64>],
) -> Option<(Vec<f64>, Vec<bool>)> {
    let p = cols.len();
    let mut fixed: Vec<Option<f64>> = vec![None; p];
    for _ in 0..=p {
        let free: Vec<usize> = (0..p).filter(|&i| fixed[i].is_none()).collect();
        let fc: Vec<&[f64]> = free.iter().map(|&i| cols[i]).collect();
        let b = if fixed.iter().all(Option::is_none) {
            crate::fit::moments(&fc, y, None)
        } else {
            let mut r = y.to_vec();
            for (i, f) in fixed.iter().enumerate() {
                if let Some(val) = f {
                    for (rk, ck) in r.iter_mut().zip(cols[i]) {
                        *rk -= val * ck;
                    }
                }
            }
            crate::fit::moments(&fc, &r, None)
        };
        let a: Vec<Vec<f64>> = free
            .iter()
            .map(|&i| free.iter().map(|&j| gram[i][j]).collect())
            .collect();
        let th = crate::fit::solve_normal(a, b)?;
        let mut worst: Option<(usize, f64)> = None;
        for (j, &i) in free.iter().enumerate() {
            if let Some(lo) = lower[i] {
                let viol = lo - th[j];
                if viol > 0.0 && worst.is_none_or(|w| viol > w.1) {
                    worst = Some((i, viol));
                }
            }
        }
        match worst {
            Some((i, _)) => fixed[i] = lower[i],
            None => {
                let mut out = vec![0.0; p];
                let mut at = vec![false; p];
                for (j, &i) in free.iter().enumerate() {
                    out[i] = th[j];
                }
                for (i, f) in fixed.iter().enumerate() {
                    if let Some(v) = f {
                        out[i] = *v;
                        at[i] = true;
                    }
                }
                return Some((out, at));
            }
        }
    }
    None
}

/// Onset level (the breakaway `brk` within the slip's [`onset_interval`]) minus
/// energy-balance mean friction of every slip of the fitting runs, per
/// direction (magnitudes) [force units]. A slip is a motion
/// (see [`motions`]) with rest before and after it.
#[allow(clippy::too_many_arguments)]
fn slip_gaps(
    fit: &[&Prepared],
    th: &Thresholds,
    s: &Structure,
    motion: Motion,
    center: f64,
    stiffness: f64,
    offset: f64,
    visc: [f64; 2],
    brk: [f64; 2],
) -> [Vec<f64>; 2] {
    let mut out: [Vec<f64>; 2] = [Vec::new(), Vec::new()];
    for p in fit {
        let x = &p.run.x;
        let n = x.len();
        let net = |i: usize| {
            applied_input(&p.run.u, i, s) + offset
                - stiffness * restoring_shape(motion, x[i], center)
        };
        for dir in Dir::BOTH {
            let sg = dir.sign();
            for (a, b) in motions(&p.v, th.v_move, sg) {
                // rest before and after: 3 samples each side below the motion threshold
                let rest_before = a >= 3 && p.v[a - 3..a].iter().all(|v| v.abs() <= th.v_move);
                let rest_after = b + 3 <= n && p.v[b..b + 3].iter().all(|v| v.abs() <= th.v_move);
                if !(rest_before && rest_after) {
                    continue;
                }
                let a = left_rest(p, a, sg, th.v_move, s).max(1);
                let (lo, hi) = (a - 1, (b + 1).min(n - 1));
                let dx_total = x[hi] - x[lo];
                if sg * dx_total <= 0.0 {
                    continue;
                }
                let (mut work, mut vdx) = (0.0, 0.0);
                for i in lo..hi {
                    let dx = x[i + 1] - x[i];
                    work += net(i) * dx;
                    vdx += p.v[i] * dx;
                }
                let d = dir.index();
                // mean friction magnitude over the slip, viscous part removed
                let kinetic = sg * work / dx_total - sg * visc[d] * vdx / dx_total;
                // the slip's onset level: the breakaway level moved into the bounds its onset
                // puts on it (a step's onset is no level, only an upper bound)
                let at_onset = onset_interval(p, a, &|k| sg * net(k)).clamp(brk[d]);
                out[d].push(at_onset - kinetic);
            }
        }
    }
    out
}

fn mean(v: &[f64]) -> f64 {
    if v.is_empty() {
        0.0
    } else {
        v.iter().sum::<f64>() / v.len() as f64
    }
}

/// Median of the finite values (0 when there are none). Selection, not a sort: O(n) where
/// a sort is O(n log n) (the estimate takes two medians of every sliding row, a million on a
/// 10 kHz x 120 s log, for every candidate fitted: sorting them was a quarter of such a
/// diagnosis). The value is the sort's, bit for bit (an order statistic is one of the values).
pub fn median(mut v: Vec<f64>) -> f64 {
    v.retain(|x| x.is_finite());
    let n = v.len();
    if n == 0 {
        return 0.0;
    }
    let (lower, &mut mid, _) = v.select_nth_unstable_by(n / 2, f64::total_cmp);
    if n % 2 == 1 {
        mid
    } else {
        // the largest of the lower half is the other middle value
        let below = lower.iter().copied().max_by(f64::total_cmp).unwrap_or(mid);
        0.5 * (below + mid)
    }
}

/// Sample standard deviation (`None` below 2 values).
pub fn std_dev(v: &[f64]) -> Option<f64> {
    if v.len() < 2 {
        return None;
    }
    let m = v.iter().sum::<f64>() / v.len() as f64;
    Some((v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (v.len() - 1) as f64).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_median_by_selection_is_the_sorted_median() {
        let mut rng = crane_ident::rng::Rng::new(5);
        for n in [1usize, 2, 3, 4, 7, 10, 101, 1000] {
            let v: Vec<f64> = (0..n).map(|_| rng.range(-3.0, 3.0).round()).collect();
            let mut s = v.clone();
            s.sort_by(f64::total_cmp);
            let want = if n % 2 == 1 {
                s[n / 2]
            } else {
                0.5 * (s[n / 2 - 1] + s[n / 2])
            };
            assert_eq!(median(v).to_bits(), want.to_bits(), "n {n}");
        }
        assert_eq!(median(vec![f64::NAN, 2.0, f64::INFINITY, 1.0]), 1.5);
        assert_eq!(median(Vec::new()), 0.0);
    }

    #[test]
    fn a_fractional_delay_reads_the_mean_of_a_held_input_over_the_period() {
        let u = [1.0, 2.0, 4.0, 8.0];
        // whole delays read one sample; before the record the first value is held
        assert_eq!(delayed(&u, 3, 1.0), 4.0);
        assert_eq!(delayed(&u, 3, 0.0), 8.0);
        assert_eq!(delayed(&u, 1, 5.0), 1.0);
        // 1.25 periods: a quarter of period 3 still sees u[1], the rest u[2]
        assert_eq!(delayed(&u, 3, 1.25), 0.25 * 2.0 + 0.75 * 4.0);
        assert_eq!(delayed(&[], 3, 1.25), 0.0);
        assert_eq!(delayed(&u, 3, f64::NAN), 1.0);
    }
    use crate::drive::prep::DriveRun;

    #[test]
    fn an_inertia_the_log_cannot_resolve_is_flagged() {
        let run = |dt: f64| {
            let t: Vec<f64> = (0..10).map(|k| k as f64 * dt).collect();
            Prepared::new(DriveRun {
                name: "r".into(),
                held_out: false,
                dt,
                x: vec![0.0; 10],
                u: vec![0.0; 10],
                refresh: 1,
                input_at: t.clone(),
                read_at: t,
            })
        };
        let (fine, coarse) = (run(1e-4), run(1e-3));
        // time constant 1e-5 s: a tenth of 1e-4 s is resolved, not below a tenth of 1e-3 s
        assert!(unresolved(&[&fine], 1e-5, [1.0, 0.5]).is_none());
        assert!(unresolved(&[&coarse, &fine], 1e-5, [0.5, 1.0]).is_none());
        assert!(matches!(
            unresolved(&[&coarse], 1e-5, [0.5, 1.0]),
            Some(Flag::InertiaUnresolved { period, .. }) if period == 1e-3
        ));
        // no viscous friction: no time constant, nothing to say
        assert!(unresolved(&[&coarse], 1e-5, [0.0, 0.0]).is_none());
    }

    #[test]
    fn bounded_ls_holds_a_negative_coefficient_at_its_bound() {
        // y = 2 a - 0.5 b: with b >= 0 the solve must put b at 0 and refit a
        let a: Vec<f64> = (0..20).map(|k| k as f64).collect();
        let b: Vec<f64> = (0..20).map(|k| (k % 3) as f64).collect();
        let y: Vec<f64> = a.iter().zip(&b).map(|(a, b)| 2.0 * a - 0.5 * b).collect();
        let (th, at) = bounded_ls(&[&a, &b], &y, &[None, Some(0.0)]).unwrap();
        assert_eq!(th[1], 0.0);
        assert!(at[1] && !at[0]);
        let (th, at) = bounded_ls(&[&a, &b], &y, &[None, None]).unwrap();
        // `fit::ls` adds a 1e-10 relative ridge: agreement to 1e-6, not to rounding
        assert!((th[1] + 0.5).abs() < 1e-6 && !at[1], "{th:?}");
    }
}

//! The report's types (`REPORT_SCHEMA.md`): what is wrong, the causes found, the evidence,
//! and for single-axis open-loop data the held-out simulation and the final model.

use serde::{Deserialize, Deserializer, Serialize, Serializer};
use std::collections::BTreeMap;
use std::fmt;

/// A hidden effect the workbench can name (crane and single-axis data alike).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Cause {
    /// Friction raised or lowered over a stretch of the travel (crane data).
    LocalizedFriction,
    /// Breakaway above sliding friction (static > kinetic).
    Stiction,
    /// Friction that depends on the direction of motion.
    DirectionAsymmetry,
    /// A constant force added to the drive force.
    ForceOffset,
    /// An input dead band.
    InputDeadzone,
    /// An input delay.
    InputDelay,
    /// The effort applied saturates: `clamp(u, -s, +s)` of the recorded input `u` (an
    /// amplifier's current limit, a command recorded before the limiter). Single-axis
    /// open-loop data; the level `s` is in the final model's `force_unit`.
    InputSaturation,
    /// A payload heavier or lighter than declared (crane data).
    PayloadMass,
    /// A position-dependent restoring force: gravity on a joint, a spring, a cable
    /// (single-axis data).
    RestoringForce,
    /// Dry friction that grows with the force the transmission carries (gearboxes, lead
    /// and ball screws): every dry level plus `mu |F|` of the drive effort (single-axis
    /// open-loop data).
    LoadDependentFriction,
    /// Velocity weakening (Stribeck): the dry friction of a moving axis falls from the
    /// breakaway (static) level to the sliding level as `exp(-(v / stribeck_velocity)^2)`, so
    /// slow ramps stick and slip (single-axis open-loop data). Parameters: `static_pos`,
    /// `static_neg`, `sliding_pos`, `sliding_neg` [force units] and `stribeck_velocity` [m/s
    /// or rad/s].
    StribeckFriction,
}

impl Cause {
    /// Every cause.
    pub const ALL: [Cause; 11] = [
        Cause::LocalizedFriction,
        Cause::Stiction,
        Cause::DirectionAsymmetry,
        Cause::ForceOffset,
        Cause::InputDeadzone,
        Cause::InputDelay,
        Cause::InputSaturation,
        Cause::PayloadMass,
        Cause::RestoringForce,
        Cause::LoadDependentFriction,
        Cause::StribeckFriction,
    ];

    /// The report name (`snake_case`).
    pub fn as_str(self) -> &'static str {
        match self {
            Cause::LocalizedFriction => "localized_friction",
            Cause::Stiction => "stiction",
            Cause::DirectionAsymmetry => "direction_asymmetry",
            Cause::ForceOffset => "force_offset",
            Cause::InputDeadzone => "input_deadzone",
            Cause::InputDelay => "input_delay",
            Cause::InputSaturation => "input_saturation",
            Cause::PayloadMass => "payload_mass",
            Cause::RestoringForce => "restoring_force",
            Cause::LoadDependentFriction => "load_dependent_friction",
            Cause::StribeckFriction => "stribeck_friction",
        }
    }
}

impl fmt::Display for Cause {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

impl PartialEq<&str> for Cause {
    fn eq(&self, other: &&str) -> bool {
        self.as_str() == *other
    }
}

/// The report's conclusion.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Verdict {
    /// The strongest supported cause.
    Found(Cause),
    /// The baseline is right within the noise: nothing to explain.
    None,
    /// The baseline is wrong and no candidate explains it.
    Unexplained,
    /// The held-out runs cannot test the model: in none of them does the axis move, and
    /// every model that sticks predicts a resting run (its score, 0 %, is no figure of the
    /// motion).
    Untested,
}

impl Verdict {
    /// The report name: the cause's name, `none`, `unexplained` or `untested`.
    pub fn as_str(self) -> &'static str {
        match self {
            Verdict::Found(c) => c.as_str(),
            Verdict::None => "none",
            Verdict::Unexplained => "unexplained",
            Verdict::Untested => "untested",
        }
    }
}

impl fmt::Display for Verdict {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

impl PartialEq<&str> for Verdict {
    fn eq(&self, other: &&str) -> bool {
        self.as_str() == *other
    }
}

impl Serialize for Verdict {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.as_str())
    }
}

impl<'de> Deserialize<'de> for Verdict {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let name = String::deserialize(d)?;
        match name.as_str() {
            "none" => Ok(Verdict::None),
            "unexplained" => Ok(Verdict::Unexplained),
            "untested" => Ok(Verdict::Untested),
            other => Cause::ALL
                .into_iter()
                .find(|c| c.as_str() == other)
                .map(Verdict::Found)
                .ok_or_else(|| serde::de::Error::custom(format!("unknown verdict `{other}`"))),
        }
    }
}

/// Evidence behind a finding.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Evidence {
    /// Held-out BIC-like change of the inverse-dynamics force residual
    /// `n ln(SSE_after / SSE_before) + k ln n` (negative supports the extension).
    pub force_delta_bic: f64,
    /// Held-out RMS inverse-dynamics force residual before / after [N] (affected axis).
    pub force_rms_before_n: f64,
    /// Same after the extension [N].
    pub force_rms_after_n: f64,
    /// Held-out score used for the ranking (crane: sum over axes of the log ratio of the
    /// simulated NMAE after / before, each floored at the noise level, plus the parameter
    /// penalty; single-axis: `force_delta_bic / n`); lower is stronger.
    pub score: f64,
    /// Extra parameters of the extension.
    pub extra_parameters: usize,
    /// Held-out samples used (after masking and decimation, affected axis).
    pub held_out_samples: usize,
    /// Whether the finding can be told apart from a change of the baseline itself.
    pub identifiable: bool,
    /// Explanation (equivalences, caveats).
    pub note: String,
}

/// One supported cause.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Finding {
    /// The cause.
    pub cause: Cause,
    /// `x`, `y`, `l`, or `axis` for single-axis data.
    pub axis: String,
    /// Estimated parameters, SI.
    pub parameters: BTreeMap<String, f64>,
    /// Held-out NMAE of the axis before the extension [%]; `null` when that simulation
    /// diverged ([`nmae_or_diverged`]).
    #[serde(with = "nmae_or_diverged")]
    pub nmae_before: f64,
    /// Held-out NMAE of the axis after the extension [%]; `null` when diverged.
    #[serde(with = "nmae_or_diverged")]
    pub nmae_after: f64,
    /// Evidence.
    pub evidence: Evidence,
}

/// Baseline error of one axis.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AxisError {
    /// Axis name.
    pub axis: String,
    /// NMAE on the fitting part [%]; `null` when the simulation diverged.
    #[serde(with = "nmae_or_diverged")]
    pub nmae_fit: f64,
    /// NMAE on the held-out part [%]; `null` when the simulation diverged
    /// ([`nmae_or_diverged`]).
    #[serde(with = "nmae_or_diverged")]
    pub nmae_held_out: f64,
    /// Noise level of the NMAE [%] (crane: encoder quantisation); below it nothing is claimed.
    pub nmae_noise: f64,
    /// Held-out NMAE [%] the baseline leaves on its own replayed log (single axis: the
    /// baseline simulated from the recorded inputs, logged as these data were, and fitted
    /// again; `drive::floor`): what this log and method leave with nothing missing. `null`
    /// when not computed (crane data), when the replay cannot be fitted, or when it is above
    /// half of predicting no motion (then the fit fails, and it is no floor).
    #[serde(default)]
    pub nmae_own_log: Option<f64>,
    /// RMS inverse-dynamics force residual on the fitting part [N].
    pub force_rms_fit_n: f64,
    /// RMS inverse-dynamics force residual on the held-out part [N].
    pub force_rms_held_out_n: f64,
    /// Relative force error `100 ||F - F_model|| / ||F||` on the held-out part [%].
    pub force_rel_err_held_out_pct: f64,
}

/// Every candidate tried, for transparency.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Candidate {
    /// Cause.
    pub cause: Cause,
    /// Axis.
    pub axis: String,
    /// Fitted parameters.
    pub parameters: BTreeMap<String, f64>,
    /// Ranking score (see [`Evidence::score`]).
    pub score: f64,
    /// Held-out force BIC change.
    pub force_delta_bic: f64,
    /// Whether it passed the support thresholds.
    pub supported: bool,
}

/// The report (`REPORT_SCHEMA.md`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Report {
    /// Data-set directory.
    pub dataset: String,
    /// `crane` or `single_axis`.
    pub data: String,
    /// Baseline description.
    pub baseline: String,
    /// How runs were split into fitting and held-out parts.
    pub split: String,
    /// Baseline error per axis.
    pub baseline_errors: Vec<AxisError>,
    /// Supported causes, strongest first.
    pub findings: Vec<Finding>,
    /// The first finding's cause, or `none` / `unexplained`.
    pub verdict: Verdict,
    /// Why the verdict.
    pub verdict_reason: String,
    /// Every candidate tried.
    pub candidates: Vec<Candidate>,
    /// Extra numbers of the single-axis pipeline (published-measure comparisons).
    #[serde(skip_serializing_if = "BTreeMap::is_empty", default)]
    pub measures: BTreeMap<String, f64>,
    /// Single-axis open-loop data: the held-out runs simulated from their recorded input with
    /// the baseline and with the final model.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub heldout_simulation: Option<HeldoutSimulation>,
    /// Single-axis open-loop data: the final model (baseline plus every finding).
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub final_model: Option<FinalModel>,
}

/// A position NMAE [%] that may stand for a diverged simulation: `f64::INFINITY` in memory,
/// `null` in the JSON (with `diverged_*` flags beside it where a run is meant), "diverged" in
/// text. A simulation that leaves the measured range tenfold (see
/// `drive::score::DIVERGED_RANGES`) is never printed as a figure: a baseline drifting away
/// once printed a held-out NMAE of 33,291,078 %.
pub mod nmae_or_diverged {
    use serde::{Deserialize, Deserializer, Serializer};

    /// Serialises a finite value as a number, anything else as `null`.
    pub fn serialize<S: Serializer>(v: &f64, s: S) -> Result<S::Ok, S::Error> {
        if v.is_finite() {
            s.serialize_f64(*v)
        } else {
            s.serialize_none()
        }
    }

    /// Reads a number, or `null` as a diverged simulation (`f64::INFINITY`).
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
        Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::INFINITY))
    }

    /// `12.34 %` (with `digits` decimals), or `diverged`.
    pub fn text(v: f64, digits: usize) -> String {
        if v.is_finite() {
            format!("{v:.digits$} %")
        } else {
            "diverged".to_string()
        }
    }
}

/// Held-out runs simulated from their recorded input (position NMAE: mean absolute error over
/// the measured run's position range) [%]. A mean over runs of which one diverged is `null`
/// (diverged).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct HeldoutSimulation {
    /// Mean over held-out runs, baseline [%].
    #[serde(with = "nmae_or_diverged")]
    pub nmae_before: f64,
    /// Mean over held-out runs, final model [%].
    #[serde(with = "nmae_or_diverged")]
    pub nmae_after: f64,
    /// Mean over held-out runs of predicting no motion at all (the first position) [%].
    pub nmae_no_motion: f64,
    /// Mean over the held-out runs in which the axis moves (beyond pre-sliding), baseline [%]:
    /// the measure the causes are selected by (runs that stay at rest cannot tell friction
    /// models apart).
    #[serde(with = "nmae_or_diverged")]
    pub moving_nmae_before: f64,
    /// Same, final model [%].
    #[serde(with = "nmae_or_diverged")]
    pub moving_nmae_after: f64,
    /// Same, predicting no motion [%].
    pub moving_nmae_no_motion: f64,
    /// Per held-out run.
    pub runs: Vec<RunSimulation>,
}

/// One held-out run's simulated position error [%].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunSimulation {
    /// Run file.
    pub file: String,
    /// Baseline [%]; `null` when its simulation diverged.
    #[serde(with = "nmae_or_diverged")]
    pub nmae_before: f64,
    /// Final model [%]; `null` when its simulation diverged.
    #[serde(with = "nmae_or_diverged")]
    pub nmae_after: f64,
    /// Predicting no motion [%].
    pub nmae_no_motion: f64,
    /// Whether the measured axis moves in this run (faster than the motion threshold).
    pub moves: bool,
    /// The baseline's simulation diverged (left the measured range tenfold): no figure.
    #[serde(default)]
    pub diverged_before: bool,
    /// The final model's simulation diverged: no figure.
    #[serde(default)]
    pub diverged_after: bool,
}

/// The final single-axis model, in SI units or, when the input gain is unknown, in input
/// units (`force_unit`). Friction magnitudes are >= 0; `breakaway_*` are net of the modelled
/// position force, at first motion.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FinalModel {
    /// Unit of positions (`m` or `rad`).
    pub position_unit: String,
    /// Unit of forces (`N`, `N m`, or the input unit).
    pub force_unit: String,
    /// Inertia [force unit per (position unit / s^2)].
    pub inertia: f64,
    /// Breakaway level towards positive [force unit].
    pub breakaway_pos: f64,
    /// Breakaway level towards negative (magnitude) [force unit].
    pub breakaway_neg: f64,
    /// Kinetic friction moving positive [force unit].
    pub kinetic_pos: f64,
    /// Kinetic friction moving negative (magnitude) [force unit].
    pub kinetic_neg: f64,
    /// Viscous friction moving positive [force unit per (position unit / s)].
    pub viscous_pos: f64,
    /// Viscous friction moving negative [force unit per (position unit / s)].
    pub viscous_neg: f64,
    /// Restoring stiffness [force unit per position unit] (0 when none).
    pub stiffness: f64,
    /// Centre of the restoring force [position unit].
    pub center: f64,
    /// Constant force offset [force unit].
    pub offset: f64,
    /// Input dead band [input units].
    pub deadband: f64,
    /// Input delay [samples of the fitting runs' period] (fractional on single-axis open-loop
    /// data, whole elsewhere).
    pub delay_samples: f64,
    /// Input delay [s].
    #[serde(default)]
    pub delay_s: f64,
    /// Load share `mu` [1]: every dry level grows by `mu |F|` of the drive effort; 0: none.
    #[serde(default)]
    pub load_friction: f64,
    /// Stribeck velocity [position unit / s]: a moving axis meets `kinetic + (breakaway -
    /// kinetic) exp(-(v / stribeck_velocity)^2)`; 0: none (the dry level drops to the kinetic
    /// one as soon as the axis moves).
    #[serde(default)]
    pub stribeck_velocity: f64,
    /// Localized friction: every dry level plus `A (1 - s^2)^2`, `s = (x - center) /
    /// half_width`, as `[center, half_width, A]` [position unit, position unit, force unit];
    /// `null`: none.
    #[serde(default)]
    pub bump: Option<[f64; 3]>,
    /// Level at which the applied effort saturates, `clamp(u, -s, +s)` [force unit]; `null`
    /// when the model has no saturation.
    #[serde(default)]
    pub saturation: Option<f64>,
    /// Scatter (standard deviation) of the breakaway levels at every rest-to-motion onset of
    /// the fitting runs, positive direction [force unit] (0 when unknown).
    pub breakaway_scatter_pos: f64,
    /// Same, negative direction.
    pub breakaway_scatter_neg: f64,
    /// Net force at first motion per fitting run, positive direction [force unit].
    pub first_motion_pos: Vec<f64>,
    /// Same, negative direction (magnitudes).
    pub first_motion_neg: Vec<f64>,
    /// What the estimator had to decide (parameters at a bound, directions not fitted,
    /// causes not named and why).
    pub flags: Vec<String>,
}

impl Report {
    /// Pretty JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_default()
    }
}

//! `dataset.toml`: the description of a data set, parsed and range-checked.

use super::error::{clip, clip_quoted, err, DataError, Problem};
use super::units::{Gain, InputUnit, PositionUnit, TimeUnit};
use crate::num::Num;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// What experiment a run is; decides which identification step uses it.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize,
)]
#[serde(rename_all = "snake_case")]
pub enum RunKind {
    /// Slow rope voltage ramp from rest, no payload: the rope's dry friction `P3`.
    RopeQuasistatic,
    /// Rope motion without payload: `P1`, `P2`.
    RopeUnloaded,
    /// Rope motion with a payload: `P4`.
    RopeLoaded,
    /// Breakaway voltage ramp on X at rest: one dry-friction sample.
    BreakawayX,
    /// Breakaway voltage ramp on Y at rest: one dry-friction sample.
    BreakawayY,
    /// X motion (multi-step, chirp): viscous coefficients of X.
    MotionX,
    /// Y motion: viscous coefficients of Y.
    MotionY,
    /// Free swing with the trolley and rope at rest: `D_alpha`, `D_beta`.
    FreeSwing,
    /// Validation run: held out, not used for fitting.
    Validation,
    /// Anything else (the default): loaded and checked; fitting data for single-axis sets.
    #[default]
    Other,
}

/// One run's entry in `dataset.toml`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RunSpec {
    /// CSV file, relative to the data set directory.
    pub file: String,
    /// Kind of experiment (default `other`).
    #[serde(default)]
    pub kind: RunKind,
    /// Payload of this crane run [kg] (default: the data set's `payload_kg`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub payload_kg: Option<f64>,
    /// Input gain of this single-axis run [effort per input unit] (TOML key `gain`, alias
    /// `gain_n_per_v`; default: the data set's).
    #[serde(
        default,
        rename = "gain",
        alias = "gain_n_per_v",
        skip_serializing_if = "Option::is_none"
    )]
    pub gain_n_per_v: Option<f64>,
    /// Column renames for this run: canonical name -> name in the file.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub columns: BTreeMap<String, String>,
    /// Free-text note.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
}

/// Known constants of the crane (defaults: the INTECO rig of the paper).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Constants {
    /// Trolley mass `m_t` [kg].
    pub trolley_mass_kg: f64,
    /// Rail mass `m_r` [kg].
    pub rail_mass_kg: f64,
    /// Gravity [m/s^2].
    pub gravity: f64,
    /// X drive pulley radius `R_x` [m].
    pub pulley_radius_x_m: f64,
    /// Y drive pulley radius `R_y` [m].
    pub pulley_radius_y_m: f64,
    /// Rope drum radius `R_l` [m].
    pub pulley_radius_l_m: f64,
    /// Encoder pulses per revolution.
    pub encoder_pulses: f64,
    /// Travel of X `[min, max]` [m].
    pub x_range_m: [f64; 2],
    /// Travel of Y `[min, max]` [m].
    pub y_range_m: [f64; 2],
    /// Rope length range `[min, max]` [m].
    pub l_range_m: [f64; 2],
}

impl Default for Constants {
    fn default() -> Self {
        Constants {
            trolley_mass_kg: 1.155,
            rail_mass_kg: 2.20,
            gravity: 9.81,
            pulley_radius_x_m: 0.040,
            pulley_radius_y_m: 0.040,
            pulley_radius_l_m: 0.015,
            encoder_pulses: 4096.0,
            x_range_m: [0.0, 0.505],
            y_range_m: [0.0, 0.625],
            l_range_m: [0.13, 0.57],
        }
    }
}

impl Constants {
    /// Position resolution of coordinate `i` of `[x, y, L, alpha, beta]` for these encoders
    /// and pulleys [m or rad].
    pub fn resolution(&self, i: usize) -> f64 {
        let rev = 2.0 * core::f64::consts::PI / self.encoder_pulses;
        match i {
            0 => rev * self.pulley_radius_x_m,
            1 => rev * self.pulley_radius_y_m,
            2 => rev * self.pulley_radius_l_m,
            _ => rev,
        }
    }
}

/// Breakaway-force noise variances [N^2] per axis and direction (defaults: the paper's).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BreakawayNoise {
    /// X, positive direction.
    pub x_pos: f64,
    /// X, negative direction.
    pub x_neg: f64,
    /// Y, positive direction.
    pub y_pos: f64,
    /// Y, negative direction.
    pub y_neg: f64,
}

impl Default for BreakawayNoise {
    fn default() -> Self {
        BreakawayNoise {
            x_pos: 0.026,
            x_neg: 0.0073,
            y_pos: 0.0030,
            y_neg: 0.0056,
        }
    }
}

/// How the controller estimates the velocity from the measured position `q` (sampling period
/// `dt`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum VelocityEstimate {
    /// `qdot(k) = (q(k) - q(k-1)) / dt`.
    #[default]
    BackwardDifference,
    /// `qf(k) = (q(k) + q(k-1)) / 2`, `qdot(k) = (qf(k) - qf(k-1)) / dt` (the EMPS rig).
    AveragedDifference,
}

/// A position controller declared for closed-loop data (`[controller]`): a P or PD loop with
/// velocity feedback,
/// `u(k) = sat(P (r(k) - q(k)) - D qdot(k)) + added(k)`, applied `delay_samples` later,
/// written either in cascade form (`kp`, `kv`: `P = kv kp`, `D = kv`, the EMPS rig's
/// `u = kv (kp (r - q) - qdot)`) or in parallel form (`kp`, `kd`: `P = kp`, `D = kd`; `kd = 0`
/// is a P loop). Gains are in input units per position unit (per position unit per second for
/// `D`); `r` has the position's unit.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ControllerSpec {
    /// Column holding the reference position `r` (name in the files, after no rename).
    pub reference: String,
    /// Cascade form: outer position gain [1/s]; parallel form: proportional gain
    /// [input unit / position unit].
    pub kp: f64,
    /// Cascade form: velocity gain [input unit / (position unit / s)].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kv: Option<f64>,
    /// Parallel form: derivative gain [input unit / (position unit / s)].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kd: Option<f64>,
    /// Velocity estimate (default `backward_difference`).
    #[serde(default)]
    pub velocity: VelocityEstimate,
    /// Samples between the controller's output and the drive (default 0).
    #[serde(default)]
    pub delay_samples: usize,
    /// Saturation of the controller output `|u| <= saturation` [input units] (default none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub saturation: Option<f64>,
    /// Column added to the command after the saturation [input units] (e.g. EMPS `pulses_N`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub added_input: Option<String>,
}

impl ControllerSpec {
    /// Largest delay accepted [samples].
    pub const MAX_DELAY: usize = 1000;
    /// Plausible range of a gain.
    pub const GAIN_RANGE: (f64, f64) = (0.0, 1e9);

    /// Proportional gain `P` [input unit / position unit].
    pub fn p_gain(&self) -> f64 {
        match self.kv {
            Some(kv) => kv * self.kp,
            None => self.kp,
        }
    }

    /// Derivative gain `D` [input unit / (position unit / s)].
    pub fn d_gain(&self) -> f64 {
        self.kv.or(self.kd).unwrap_or(0.0)
    }

    /// The controller output before the delay: saturated law plus the added input, at sample
    /// `k` from reference `r`, positions `q(k), q(k-1), q(k-2)` and period `dt`; the velocity
    /// is 0 at the first sample (`first`).
    #[allow(clippy::too_many_arguments)]
    pub fn command(
        &self,
        r: f64,
        q: f64,
        q1: f64,
        q2: f64,
        dt: f64,
        first: bool,
        added: f64,
    ) -> f64 {
        let qdot = if first {
            0.0
        } else {
            match self.velocity {
                VelocityEstimate::BackwardDifference => (q - q1) / dt,
                VelocityEstimate::AveragedDifference => {
                    ((0.5 * q + 0.5 * q1) - (0.5 * q1 + 0.5 * q2)) / dt
                }
            }
        };
        let u = match self.kv {
            Some(kv) => kv * (self.kp * (r - q) - qdot),
            None => self.kp * (r - q) - self.kd.unwrap_or(0.0) * qdot,
        };
        let u = match self.saturation {
            Some(s) => u.clamp(-s, s),
            None => u,
        };
        u + added
    }

    fn check(&self) -> Result<(), (&'static str, String)> {
        let (lo, hi) = Self::GAIN_RANGE;
        let gain = |key: &'static str, v: f64| -> Result<(), (&'static str, String)> {
            if v.is_finite() && (lo..=hi).contains(&v) {
                Ok(())
            } else {
                Err((
                    key,
                    format!(
                        "controller.{key} must be in [{}, {}] (got {})",
                        Num(lo),
                        Num(hi),
                        Num(v)
                    ),
                ))
            }
        };
        gain("kp", self.kp)?;
        match (self.kv, self.kd) {
            (Some(_), Some(_)) => {
                return Err((
                    "kd",
                    "controller: give either `kv` (cascade form u = kv (kp (r - q) - qdot)) or \
                     `kd` (parallel form u = kp (r - q) - kd qdot), not both"
                        .into(),
                ))
            }
            (None, None) => {
                return Err((
                    "kp",
                    "controller: give `kv` (cascade form u = kv (kp (r - q) - qdot)) or `kd` \
                     (parallel form u = kp (r - q) - kd qdot; kd = 0 for a P loop)"
                        .into(),
                ))
            }
            (Some(kv), None) => gain("kv", kv)?,
            (None, Some(kd)) => gain("kd", kd)?,
        }
        if self.delay_samples > Self::MAX_DELAY {
            return Err((
                "delay_samples",
                format!(
                    "controller.delay_samples must be <= {} (got {})",
                    Self::MAX_DELAY,
                    self.delay_samples
                ),
            ));
        }
        if let Some(s) = self.saturation {
            if !(s.is_finite() && s > 0.0 && s <= 1e9) {
                return Err((
                    "saturation",
                    format!(
                        "controller.saturation must be in (0, 1e9] input units (got {})",
                        Num(s)
                    ),
                ));
            }
        }
        if self.reference.trim().is_empty() {
            return Err((
                "reference",
                "controller.reference must name a column".into(),
            ));
        }
        if self
            .added_input
            .as_deref()
            .is_some_and(|s| s.trim().is_empty())
        {
            return Err((
                "added_input",
                "controller.added_input must name a column".into(),
            ));
        }
        Ok(())
    }
}

/// Contents of `dataset.toml`. Nothing is required; crane runs need a payload (here or per
/// run).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DatasetSpec {
    /// Free-text description.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub description: Option<String>,
    /// Payload of every crane run unless the run says otherwise [kg] (not used by
    /// single-axis runs).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub payload_kg: Option<f64>,
    /// Unit of the time column of every run (default `s`): converted to seconds on load.
    #[serde(default, skip_serializing_if = "TimeUnit::is_second")]
    pub time_unit: TimeUnit,
    /// Unit of a single-axis position (default `m`).
    #[serde(default, skip_serializing_if = "PositionUnit::is_metre")]
    pub position_unit: PositionUnit,
    /// Recorded single-axis positions (`x` and a controller's reference) times this are in
    /// `position_unit`: 0.001 for millimetres, pi/180 = 0.017453292519943295 for degrees,
    /// lead / counts per turn for raw encoder counts. Default 1; range
    /// [`POSITION_SCALE_RANGE`]. Controller gains are per `position_unit`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub position_scale: Option<f64>,
    /// Unit of a single-axis input `u` (default `V`; a `force` column is an effort).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub input_unit: Option<InputUnit>,
    /// Gain [effort per input unit] of a single-axis input (TOML key `gain`, alias
    /// `gain_n_per_v`); absent: unknown (input units downstream) unless the input is an
    /// effort.
    #[serde(
        default,
        rename = "gain",
        alias = "gain_n_per_v",
        skip_serializing_if = "Option::is_none"
    )]
    pub gain_n_per_v: Option<f64>,
    /// Column renames for every run: canonical name -> name in the files.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub columns: BTreeMap<String, String>,
    /// Known constants of the crane.
    #[serde(default)]
    pub constants: Constants,
    /// Breakaway noise variances used by the friction regression.
    #[serde(default)]
    pub breakaway_noise_var: BreakawayNoise,
    /// The position controller that produced closed-loop single-axis data.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub controller: Option<ControllerSpec>,
    /// The runs; when absent every `*.csv` of the directory is a run of kind `other`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub runs: Vec<RunSpec>,
}

impl DatasetSpec {
    /// The minimal crane description: one payload, defaults for everything else.
    pub fn minimal(payload_kg: f64) -> Self {
        DatasetSpec {
            payload_kg: Some(payload_kg),
            ..DatasetSpec::single_axis()
        }
    }

    /// A single-axis description with every default (m, V, unknown gain, no controller).
    pub fn single_axis() -> Self {
        DatasetSpec {
            description: None,
            payload_kg: None,
            time_unit: TimeUnit::Second,
            position_unit: PositionUnit::Metre,
            position_scale: None,
            input_unit: None,
            gain_n_per_v: None,
            columns: BTreeMap::new(),
            constants: Constants::default(),
            breakaway_noise_var: BreakawayNoise::default(),
            controller: None,
            runs: Vec::new(),
        }
    }

    /// The input unit of single-axis runs with a `u` column (default volt).
    pub fn input_unit(&self) -> InputUnit {
        self.input_unit.unwrap_or_default()
    }

    /// The gain of a run (its own, else the data set's), as a [`Gain`]: 1 and known when the
    /// input is an effort.
    pub fn gain(&self, run: Option<&RunSpec>) -> Gain {
        if self.input_unit().is_effort() {
            return Gain::Known(1.0);
        }
        match run.and_then(|r| r.gain_n_per_v).or(self.gain_n_per_v) {
            Some(g) => Gain::Known(g),
            None => Gain::Unknown,
        }
    }
}

/// Plausible range of `position_scale`: from nanometre (or nanoradian) counts to a scale of a
/// million (positions logged in thousands of units).
pub const POSITION_SCALE_RANGE: (f64, f64) = (1e-12, 1e6);

/// Plausible ranges of the constants, `[min, max]`, and why.
pub const PAYLOAD_RANGE_KG: (f64, f64) = (0.0, 1e4);
/// Masses of the crane's parts [kg].
pub const MASS_RANGE_KG: (f64, f64) = (1e-3, 1e4);
/// Gravity: from the Moon (1.62) to Jupiter (24.8), rounded outwards [m/s^2].
pub const GRAVITY_RANGE: (f64, f64) = (1.0, 25.0);
/// Pulley and drum radii [m].
pub const RADIUS_RANGE_M: (f64, f64) = (1e-4, 1.0);
/// Encoder pulses per revolution.
pub const ENCODER_RANGE: (f64, f64) = (1.0, 1e9);
/// Bounds of the travel ranges [m]; a range must be at least 1 mm wide.
pub const TRAVEL_RANGE_M: (f64, f64) = (-100.0, 100.0);
/// Breakaway noise variances [N^2].
pub const NOISE_VAR_RANGE: (f64, f64) = (1e-12, 1e6);

/// 1-based line of byte offset `at` of `text`.
fn line_at(text: &str, at: usize) -> usize {
    text[..at.min(text.len())].matches('\n').count() + 1
}

/// The entry `key` of a parsed TOML table, with its key's span.
fn entry<'a, 'i>(
    table: &'a toml::de::DeTable<'i>,
    key: &str,
) -> Option<(
    &'a toml::Spanned<toml::de::DeString<'i>>,
    &'a toml::Spanned<toml::de::DeValue<'i>>,
)> {
    table.iter().find(|(k, _)| k.get_ref().as_ref() == key)
}

/// A step of a path into a TOML document: a table's key or an array's element (0-based).
#[derive(Clone, Copy)]
enum Seg<'a> {
    /// The value of this key of a table.
    Key(&'a str),
    /// This element of an array.
    At(usize),
}

/// Where a key of the table at `path` is written: its line (1-based) and its spelling, the
/// first of `spellings` (one key's name and aliases) found there. Found through the TOML
/// parser's spans, so every form gives the key's own line: `[[runs]]` tables (spaced
/// `[[ runs ]]` too), an inline `runs = [{ ... }]`, quoted keys, inline or `[runs.columns]`
/// sub-tables; never the line of a key of the same name elsewhere (the data set's own, or
/// another run's). `None` when the text does not parse or the table has no such key.
fn key_at(text: &str, path: &[Seg<'_>], spellings: &[&str]) -> Option<(usize, String)> {
    let doc = toml::de::DeTable::parse(text).ok()?;
    let mut table = doc.get_ref();
    let mut value: Option<&toml::de::DeValue<'_>> = None;
    for seg in path {
        let v = match *seg {
            Seg::Key(k) => entry(table, k)?.1.get_ref(),
            Seg::At(i) => value?.as_array()?.get(i)?.get_ref(),
        };
        if let Some(t) = v.as_table() {
            table = t;
        }
        value = Some(v);
    }
    if value.is_some_and(|v| v.as_table().is_none()) {
        return None; // the path ends on an array or a value, not a table
    }
    spellings.iter().find_map(|name| {
        entry(table, name).map(|(k, _)| (line_at(text, k.span().start), name.to_string()))
    })
}

/// [`key_at`] in the `index`-th (0-based) run (`sub`: in its sub-table of that name).
fn run_key(
    text: &str,
    index: usize,
    sub: Option<&str>,
    spellings: &[&str],
) -> Option<(usize, String)> {
    match sub {
        Some(name) => key_at(
            text,
            &[Seg::Key("runs"), Seg::At(index), Seg::Key(name)],
            spellings,
        ),
        None => key_at(text, &[Seg::Key("runs"), Seg::At(index)], spellings),
    }
}

/// The line (1-based) of the `file` key of the `index`-th (0-based) run of `dataset.toml`'s
/// `text` (a byte-order mark is skipped), in every form of the file ([`key_at`]); `None`
/// when the text does not parse or that run has no `file` key.
pub(crate) fn run_file_line(text: &str, index: usize) -> Option<usize> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    run_key(text, index, None, &["file"]).map(|(l, _)| l)
}

/// Parses `dataset.toml` text (a UTF-8 byte-order mark is skipped) and checks every number
/// against its plausible range; errors name the file and the line of the key.
pub fn parse_spec(file: &Path, text: &str) -> Result<DatasetSpec, DataError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let spec = parse_toml(file, text)?;
    let ck = Checker { file, text };
    // the data set's gain as its top level spells it (a run's own spelling does not count)
    let gain_key = key_at(text, &[], &["gain", "gain_n_per_v"]).map_or("gain".into(), |(_, k)| k);
    let gain_key = gain_key.as_str();
    check_scales(&ck, &spec, gain_key)?;
    check_constants(&ck, &spec.constants)?;
    check_noise(&ck, &spec.breakaway_noise_var)?;
    check_controller(file, text, &spec)?;
    check_run_entries(&ck, &spec, gain_key)?;
    check_columns(file, text, &spec)?;
    check_runs_listed(file, text, &spec)?;
    Ok(spec)
}

/// The TOML of `text` (without its byte-order mark) as a [`DatasetSpec`]; a syntax or type
/// error names the file and the line where it starts.
fn parse_toml(file: &Path, text: &str) -> Result<DatasetSpec, DataError> {
    toml::from_str(text).map_err(|e| {
        let line = e
            .span()
            .map(|s| text[..s.start.min(text.len())].matches('\n').count() + 1);
        err(file, line, None, Problem::Toml(clip_quoted(e.message())))
    })
}

/// Range checks of `dataset.toml`'s values: errors name the file and the line of the key.
struct Checker<'a> {
    /// The file, for the error.
    file: &'a Path,
    /// Its text (without the byte-order mark), for the line of the key.
    text: &'a str,
}

impl Checker<'_> {
    /// The line (1-based) of the checked key `key`, a dotted path from the top level
    /// (`payload_kg`, `constants.gravity`): the line of that key in that table, found through
    /// the TOML parser's spans ([`key_at`]) in every form (a `[constants]` table, spaced
    /// `[ constants ]`, inline `constants = { ... }`, dotted `constants.gravity = ...`, quoted
    /// keys); never a line of the same name elsewhere (in a multi-line string, another
    /// table). `None` when the key is not written in the file.
    fn line(&self, key: &str) -> Option<usize> {
        let mut names: Vec<&str> = key.split('.').collect();
        let last = names.pop()?;
        let path: Vec<Seg<'_>> = names.into_iter().map(Seg::Key).collect();
        key_at(self.text, &path, &[last]).map(|(l, _)| l)
    }

    /// A bad value of `key` (a dotted path, named at its line: [`Checker::line`]).
    fn bad(&self, key: &str, what: String) -> DataError {
        err(self.file, self.line(key), None, Problem::BadValue(what))
    }

    /// `v` of `key` (a dotted path, named at its line: [`Checker::line`]) must be finite and
    /// within `[lo, hi]` (`unit` is named in the error).
    fn within(&self, key: &str, v: f64, range: (f64, f64), unit: &str) -> Result<(), DataError> {
        let at = || self.line(key).map(|l| (l, key.to_string()));
        self.within_at(at, key, v, range, unit)
    }

    /// [`Checker::within`] for a key that `at` finds when the value is refused: its line
    /// (1-based) and its spelling, named in the error (`None`: not found; then named `key`).
    fn within_at(
        &self,
        at: impl FnOnce() -> Option<(usize, String)>,
        key: &str,
        v: f64,
        (lo, hi): (f64, f64),
        unit: &str,
    ) -> Result<(), DataError> {
        if v.is_finite() && v >= lo && v <= hi {
            Ok(())
        } else {
            let (line, key) = match at() {
                Some((l, k)) => (Some(l), k),
                None => (None, key.to_string()),
            };
            let what = format!(
                "{key} must be in [{}, {}] {unit} (got {})",
                Num(lo),
                Num(hi),
                Num(v)
            );
            Err(err(self.file, line, None, Problem::BadValue(what)))
        }
    }
}

/// The data set's payload, gain (under `gain_key`, the spelling the text uses), position
/// scale, and an input unit that must fit the position unit and a gain of 1 when it is an
/// effort.
fn check_scales(ck: &Checker<'_>, spec: &DatasetSpec, gain_key: &str) -> Result<(), DataError> {
    if let Some(m) = spec.payload_kg {
        ck.within("payload_kg", m, PAYLOAD_RANGE_KG, "kg")?;
    }
    if let Some(g) = spec.gain_n_per_v {
        ck.within(gain_key, g, Gain::RANGE, "(effort per input unit)")?;
    }
    if let Some(k) = spec.position_scale {
        ck.within(
            "position_scale",
            k,
            POSITION_SCALE_RANGE,
            "(position_unit per recorded unit)",
        )?;
    }
    let effort = spec.position_unit.effort_unit();
    if let Some(u) = spec.input_unit {
        if u.is_effort() && u != effort {
            return Err(ck.bad(
                "input_unit",
                format!(
                    "input_unit `{}` does not go with position_unit `{}`: a {} axis is driven \
                     in `{}`",
                    u.symbol(),
                    spec.position_unit.symbol(),
                    if spec.position_unit.is_metre() {
                        "linear"
                    } else {
                        "rotary"
                    },
                    effort.symbol()
                ),
            ));
        }
        if u.is_effort() && spec.gain_n_per_v.is_some_and(|g| g != 1.0) {
            return Err(ck.bad(
                gain_key,
                format!(
                    "the input is already an effort (`{}`): its gain is 1; remove `{gain_key}`",
                    u.symbol()
                ),
            ));
        }
    }
    Ok(())
}

/// The `[constants]`: masses [kg], gravity [m/s^2], pulley radii [m], encoder pulses per
/// revolution, and the travel ranges [m] (`[min, max]`, at least 1 mm wide; the rope's
/// `min > 0`).
fn check_constants(ck: &Checker<'_>, c: &Constants) -> Result<(), DataError> {
    ck.within(
        "constants.trolley_mass_kg",
        c.trolley_mass_kg,
        MASS_RANGE_KG,
        "kg",
    )?;
    ck.within(
        "constants.rail_mass_kg",
        c.rail_mass_kg,
        (0.0, MASS_RANGE_KG.1),
        "kg",
    )?;
    ck.within("constants.gravity", c.gravity, GRAVITY_RANGE, "m/s^2")?;
    for (key, v) in [
        ("constants.pulley_radius_x_m", c.pulley_radius_x_m),
        ("constants.pulley_radius_y_m", c.pulley_radius_y_m),
        ("constants.pulley_radius_l_m", c.pulley_radius_l_m),
    ] {
        ck.within(key, v, RADIUS_RANGE_M, "m")?;
    }
    ck.within(
        "constants.encoder_pulses",
        c.encoder_pulses,
        ENCODER_RANGE,
        "pulses per revolution",
    )?;
    for (key, r, positive) in [
        ("constants.x_range_m", c.x_range_m, false),
        ("constants.y_range_m", c.y_range_m, false),
        ("constants.l_range_m", c.l_range_m, true),
    ] {
        let (lo, hi) = TRAVEL_RANGE_M;
        let ok = r.iter().all(|v| v.is_finite() && *v >= lo && *v <= hi)
            && r[1] - r[0] >= 1e-3
            && (!positive || r[0] > 0.0);
        if !ok {
            return Err(ck.bad(
                key,
                format!(
                    "{key} must be [min, max] within [{lo}, {hi}] m, at least 1 mm wide{} \
                     (got [{}, {}])",
                    if positive { ", min > 0" } else { "" },
                    r[0],
                    r[1]
                ),
            ));
        }
    }
    Ok(())
}

/// The `[breakaway_noise_var]` variances [N^2].
fn check_noise(ck: &Checker<'_>, n: &BreakawayNoise) -> Result<(), DataError> {
    for (key, v) in [
        ("breakaway_noise_var.x_pos", n.x_pos),
        ("breakaway_noise_var.x_neg", n.x_neg),
        ("breakaway_noise_var.y_pos", n.y_pos),
        ("breakaway_noise_var.y_neg", n.y_neg),
    ] {
        ck.within(key, v, NOISE_VAR_RANGE, "N^2")?;
    }
    Ok(())
}

/// The `[controller]` table, if any; an error names the line of the key inside that table
/// ([`key_at`]: an inline `controller = { ... }` or a spaced `[ controller ]` header too).
fn check_controller(file: &Path, text: &str, spec: &DatasetSpec) -> Result<(), DataError> {
    if let Some(ctl) = &spec.controller {
        ctl.check().map_err(|(key, what)| {
            let line = key_at(text, &[Seg::Key("controller")], &[key]).map(|(l, _)| l);
            err(file, line, None, Problem::BadValue(what))
        })?;
    }
    Ok(())
}

/// Each `[[runs]]` entry: its payload [kg], its gain (under `gain_key`) and a file name.
fn check_run_entries(
    ck: &Checker<'_>,
    spec: &DatasetSpec,
    gain_key: &str,
) -> Result<(), DataError> {
    for (i, r) in spec.runs.iter().enumerate() {
        // the line of the key in this run's own table (the data set's keys of the same name
        // come first in the file), and the gain as this run spells it
        let at = |keys: &'static [&'static str]| move || run_key(ck.text, i, None, keys);
        if let Some(m) = r.payload_kg {
            ck.within_at(at(&["payload_kg"]), "payload_kg", m, PAYLOAD_RANGE_KG, "kg")?;
        }
        if let Some(g) = r.gain_n_per_v {
            let what = "(effort per input unit)";
            ck.within_at(
                at(&["gain", "gain_n_per_v"]),
                gain_key,
                g,
                Gain::RANGE,
                what,
            )?;
        }
        if r.file.trim().is_empty() {
            let what = Problem::BadValue("runs.file must name a CSV file".into());
            return Err(err(ck.file, at(&["file"])().map(|(l, _)| l), None, what));
        }
    }
    Ok(())
}

/// The canonical column names a `[columns]` table may rename: the single-axis `t`, `x`, `u`,
/// `force` and the crane's `u_x`, `u_y`, `u_l`, `y`, `l`, `alpha`, `beta`.
pub const CANONICAL_COLUMNS: [&str; 11] = [
    "t", "x", "u", "force", "u_x", "u_y", "u_l", "y", "l", "alpha", "beta",
];

/// Every key of a `[columns]` table (the data set's and each run's) must be a canonical name:
/// `pos = "x"` would otherwise be ignored without a word.
fn check_columns(file: &Path, text: &str, spec: &DatasetSpec) -> Result<(), DataError> {
    let runs = spec.runs.iter().enumerate();
    let tables =
        std::iter::once((None, &spec.columns)).chain(runs.map(|(i, r)| (Some(i), &r.columns)));
    for (run, cols) in tables {
        if let Some(k) = cols
            .keys()
            .find(|k| !CANONICAL_COLUMNS.contains(&k.as_str()))
        {
            // the key's own line: in the data set's [columns] or in this run's columns
            let line = match run {
                None => key_at(text, &[Seg::Key("columns")], &[k]),
                Some(i) => run_key(text, i, Some("columns"), &[k]),
            };
            return Err(err(
                file,
                line.map(|(l, _)| l),
                None,
                Problem::BadValue(format!(
                    "[columns] key `{k}` is no canonical column name; the keys are the names the tool expects ({}) and the values the names in your files, e.g. `x = \"{k}\"`",
                    CANONICAL_COLUMNS.join(", "),
                    k = clip(k)
                )),
            ));
        }
    }
    Ok(())
}

/// `runs = []` written out is refused (it would silently mean "every *.csv"), and so is one
/// file listed twice (as a fitting and a held-out run, a held-out score would be computed on
/// training data).
fn check_runs_listed(file: &Path, text: &str, spec: &DatasetSpec) -> Result<(), DataError> {
    let explicit_empty = text
        .parse::<toml::Table>()
        .ok()
        .and_then(|t| {
            t.get("runs")
                .and_then(|r| r.as_array())
                .map(|a| a.is_empty())
        })
        .unwrap_or(false);
    if explicit_empty {
        return Err(err(
            file,
            key_at(text, &[], &["runs"]).map(|(l, _)| l),
            None,
            Problem::BadValue(
                "`runs = []` lists no run; list them as [[runs]] tables, or leave `runs` out to read every *.csv of the directory"
                    .into(),
            ),
        ));
    }
    let dir = file.parent().unwrap_or(Path::new("."));
    let key = |f: &str| {
        let p = dir.join(f.trim());
        p.canonicalize().unwrap_or(p)
    };
    for (i, a) in spec.runs.iter().enumerate() {
        if let Some(b) = spec.runs[..i].iter().find(|b| key(&b.file) == key(&a.file)) {
            // the line of this run's own `file` key
            let line = run_key(text, i, None, &["file"]).map(|(l, _)| l);
            return Err(err(
                file,
                line,
                None,
                Problem::BadValue(format!(
                    "run `{}` is listed twice (kinds `{:?}` and `{:?}`): a run is either fitted or held out, and a held-out score on a fitting run is no held-out score",
                    clip(&a.file),
                    b.kind,
                    a.kind
                )),
            ));
        }
    }
    Ok(())
}

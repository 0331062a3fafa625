//! The data format: runs as CSV files, a data set as a directory of runs plus `dataset.toml`.
//! See `DATA_FORMAT.md` next to `Cargo.toml` for the user-facing description.

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::fmt;
use std::path::{Path, PathBuf};

/// Name of the data set description inside a data set directory.
pub const DATASET_FILE: &str = "dataset.toml";

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
    /// Validation run: not used for fitting.
    Validation,
    /// Anything else (the default): loaded and checked, not used by the identification.
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
    /// Payload of this run [kg] (default: the data set's `payload_kg`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub payload_kg: Option<f64>,
    /// Gain [N/V] for a single-axis run with a `u` column (default: the data set's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gain_n_per_v: Option<f64>,
    /// Column renames for this run: canonical name -> name in the file.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub columns: BTreeMap<String, String>,
    /// Free-text note.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
}

/// Known constants of the crane (defaults: `shared/MODEL.md`).
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

/// Contents of `dataset.toml`. Only `payload_kg` is required.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DatasetSpec {
    /// Payload of every run unless the run says otherwise [kg].
    pub payload_kg: f64,
    /// Gain [N/V] converting a single-axis `u` column to force.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gain_n_per_v: Option<f64>,
    /// Column renames for every run: canonical name -> name in the files.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub columns: BTreeMap<String, String>,
    /// Known constants.
    #[serde(default)]
    pub constants: Constants,
    /// Breakaway noise variances used by the friction regression.
    #[serde(default)]
    pub breakaway_noise_var: BreakawayNoise,
    /// The runs; when absent every `*.csv` of the directory is a run of kind `other`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub runs: Vec<RunSpec>,
}

impl DatasetSpec {
    /// The minimal description: one payload, defaults for everything else.
    pub fn minimal(payload_kg: f64) -> Self {
        DatasetSpec {
            payload_kg,
            gain_n_per_v: None,
            columns: BTreeMap::new(),
            constants: Constants::default(),
            breakaway_noise_var: BreakawayNoise::default(),
            runs: Vec::new(),
        }
    }
}

/// Samples of a crane run (all columns of equal length).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CraneRun {
    /// Time [s], strictly increasing.
    pub t: Vec<f64>,
    /// Voltages `u_x, u_y, u_l` [V].
    pub u: [Vec<f64>; 3],
    /// Rail position [m].
    pub x: Vec<f64>,
    /// Trolley position [m].
    pub y: Vec<f64>,
    /// Rope length [m].
    pub l: Vec<f64>,
    /// Swing angle alpha [rad].
    pub alpha: Vec<f64>,
    /// Swing angle beta [rad].
    pub beta: Vec<f64>,
}

impl CraneRun {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.t.len()
    }
    /// No samples.
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }
    /// Mean sampling period [s].
    pub fn dt(&self) -> f64 {
        mean_dt(&self.t)
    }
    /// Drive position of axis 0 (x), 1 (y), 2 (l).
    pub fn pos(&self, axis: usize) -> &[f64] {
        match axis {
            0 => &self.x,
            1 => &self.y,
            _ => &self.l,
        }
    }
}

/// Samples of a single-axis run.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AxisRun {
    /// Time [s], strictly increasing.
    pub t: Vec<f64>,
    /// Position [m].
    pub x: Vec<f64>,
    /// Drive force [N] (`force` column, or `gain * u`).
    pub force: Vec<f64>,
}

impl AxisRun {
    /// Mean sampling period [s].
    pub fn dt(&self) -> f64 {
        mean_dt(&self.t)
    }
}

fn mean_dt(t: &[f64]) -> f64 {
    if t.len() < 2 {
        return f64::NAN;
    }
    (t[t.len() - 1] - t[0]) / (t.len() - 1) as f64
}

/// The samples of a run.
#[derive(Clone, Debug, PartialEq)]
pub enum Samples {
    /// Crane run.
    Crane(CraneRun),
    /// Single-axis run.
    Axis(AxisRun),
}

/// A loaded run.
#[derive(Clone, Debug, PartialEq)]
pub struct Run {
    /// File name (as in `dataset.toml`).
    pub name: String,
    /// Kind of experiment.
    pub kind: RunKind,
    /// Payload [kg].
    pub payload_kg: f64,
    /// Samples.
    pub samples: Samples,
}

impl Run {
    /// The crane samples, if a crane run.
    pub fn crane(&self) -> Option<&CraneRun> {
        match &self.samples {
            Samples::Crane(c) => Some(c),
            Samples::Axis(_) => None,
        }
    }
    /// The single-axis samples, if a single-axis run.
    pub fn axis(&self) -> Option<&AxisRun> {
        match &self.samples {
            Samples::Axis(a) => Some(a),
            Samples::Crane(_) => None,
        }
    }
}

/// A loaded data set.
#[derive(Clone, Debug, PartialEq)]
pub struct Dataset {
    /// Directory.
    pub dir: PathBuf,
    /// Its description.
    pub spec: DatasetSpec,
    /// Runs in the order of `dataset.toml` (or file-name order).
    pub runs: Vec<Run>,
}

impl Dataset {
    /// Runs of a kind.
    pub fn of_kind(&self, kind: RunKind) -> impl Iterator<Item = &Run> {
        self.runs.iter().filter(move |r| r.kind == kind)
    }
}

/// Where in a file something is wrong.
#[derive(Clone, Debug, PartialEq)]
pub struct Location {
    /// File.
    pub file: PathBuf,
    /// 1-based line, if any.
    pub line: Option<usize>,
    /// Column name and its 1-based position, if any.
    pub column: Option<(String, usize)>,
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file.display())?;
        if let Some(l) = self.line {
            write!(f, ":{l}")?;
        }
        if let Some((name, pos)) = &self.column {
            write!(f, ": column {pos} `{name}`")?;
        }
        Ok(())
    }
}

/// What is wrong.
#[derive(Clone, Debug, PartialEq)]
pub enum Problem {
    /// File cannot be read.
    Io(String),
    /// `dataset.toml` does not parse or has a bad field.
    Toml(String),
    /// No header line.
    NoHeader,
    /// A required column is absent (names the candidates).
    MissingColumn(String),
    /// Two header fields map to the same column.
    DuplicateColumn,
    /// A row has a different number of fields than the header.
    FieldCount {
        /// Fields expected.
        expected: usize,
        /// Fields found.
        found: usize,
    },
    /// A field is not a number.
    NotNumeric(String),
    /// A field is NaN or infinite.
    NotFinite(String),
    /// Time does not increase.
    TimeNotIncreasing {
        /// Previous time.
        prev: f64,
        /// This time.
        this: f64,
    },
    /// A value outside the plausible range of its unit.
    OutOfRange {
        /// Value.
        value: f64,
        /// Lower bound.
        min: f64,
        /// Upper bound.
        max: f64,
        /// Unit hint.
        unit: &'static str,
    },
    /// Fewer than two samples.
    TooShort,
    /// A field of `dataset.toml` has a bad value.
    BadValue(String),
}

/// A data error: where and what.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{location}: {problem}")]
pub struct DataError {
    /// Where.
    pub location: Location,
    /// What.
    pub problem: Problem,
}

impl fmt::Display for Problem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Problem::Io(e) => write!(f, "cannot read: {e}"),
            Problem::Toml(e) => write!(f, "bad dataset description: {e}"),
            Problem::NoHeader => write!(f, "no header line"),
            Problem::MissingColumn(c) => write!(f, "missing column {c}"),
            Problem::DuplicateColumn => write!(f, "column appears twice in the header"),
            Problem::FieldCount { expected, found } => {
                write!(f, "{found} fields, the header has {expected}")
            }
            Problem::NotNumeric(s) => write!(f, "not a number: `{s}`"),
            Problem::NotFinite(s) => write!(f, "not finite: `{s}`"),
            Problem::TimeNotIncreasing { prev, this } => {
                write!(f, "time does not increase ({this} after {prev})")
            }
            Problem::OutOfRange {
                value,
                min,
                max,
                unit,
            } => write!(
                f,
                "{value} is outside [{min}, {max}] {unit} (wrong unit or sign convention?)"
            ),
            Problem::TooShort => write!(f, "fewer than two samples"),
            Problem::BadValue(s) => write!(f, "{s}"),
        }
    }
}

fn err(
    file: &Path,
    line: Option<usize>,
    column: Option<(&str, usize)>,
    problem: Problem,
) -> DataError {
    DataError {
        location: Location {
            file: file.to_path_buf(),
            line,
            column: column.map(|(n, p)| (n.to_string(), p)),
        },
        problem,
    }
}

/// A parsed CSV table: header names and numeric columns, with line numbers for errors.
#[derive(Clone, Debug, PartialEq)]
pub struct Table {
    /// File it came from.
    pub file: PathBuf,
    /// Header names (trimmed).
    pub header: Vec<String>,
    /// Values, one vector per header column.
    pub columns: Vec<Vec<f64>>,
    /// 1-based file line of each row.
    pub lines: Vec<usize>,
}

/// Parses CSV text: `#` lines are comments, blank lines are skipped, the first other line is
/// the header, every other line a row of as many numeric fields. Every field is checked
/// (numeric, finite), also in columns that will be ignored.
pub fn parse_table(file: &Path, text: &str) -> Result<Table, DataError> {
    let mut header: Option<Vec<String>> = None;
    let mut columns: Vec<Vec<f64>> = Vec::new();
    let mut lines = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let lineno = i + 1;
        let line = raw.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let fields: Vec<&str> = line.split(',').map(|s| s.trim()).collect();
        match &header {
            None => {
                let names: Vec<String> = fields
                    .iter()
                    .map(|s| s.trim_matches('"').to_string())
                    .collect();
                for (k, n) in names.iter().enumerate() {
                    if names[..k].contains(n) {
                        return Err(err(
                            file,
                            Some(lineno),
                            Some((n, k + 1)),
                            Problem::DuplicateColumn,
                        ));
                    }
                }
                columns = vec![Vec::new(); names.len()];
                header = Some(names);
            }
            Some(h) => {
                if fields.len() != h.len() {
                    return Err(err(
                        file,
                        Some(lineno),
                        None,
                        Problem::FieldCount {
                            expected: h.len(),
                            found: fields.len(),
                        },
                    ));
                }
                for (k, (s, col)) in fields.iter().zip(columns.iter_mut()).enumerate() {
                    let v: f64 = s.parse().map_err(|_| {
                        err(
                            file,
                            Some(lineno),
                            Some((&h[k], k + 1)),
                            Problem::NotNumeric(s.to_string()),
                        )
                    })?;
                    if !v.is_finite() {
                        return Err(err(
                            file,
                            Some(lineno),
                            Some((&h[k], k + 1)),
                            Problem::NotFinite(s.to_string()),
                        ));
                    }
                    col.push(v);
                }
                lines.push(lineno);
            }
        }
    }
    let header = header.ok_or_else(|| err(file, None, None, Problem::NoHeader))?;
    Ok(Table {
        file: file.to_path_buf(),
        header,
        columns,
        lines,
    })
}

impl Table {
    /// Index of the column holding canonical `name` (after `renames`).
    fn find(&self, name: &str, renames: &BTreeMap<String, String>) -> Option<usize> {
        let target = renames.get(name).map(String::as_str).unwrap_or(name);
        self.header.iter().position(|h| h == target)
    }

    fn take(
        &self,
        name: &str,
        renames: &BTreeMap<String, String>,
        range: Option<(f64, f64, &'static str)>,
    ) -> Result<Vec<f64>, DataError> {
        let idx = self.find(name, renames).ok_or_else(|| {
            let shown = match renames.get(name) {
                Some(r) => format!("`{r}` (for `{name}`)"),
                None => format!("`{name}`"),
            };
            err(&self.file, None, None, Problem::MissingColumn(shown))
        })?;
        let col = &self.columns[idx];
        if let Some((min, max, unit)) = range {
            for (k, &v) in col.iter().enumerate() {
                if v < min || v > max {
                    return Err(err(
                        &self.file,
                        Some(self.lines[k]),
                        Some((&self.header[idx], idx + 1)),
                        Problem::OutOfRange {
                            value: v,
                            min,
                            max,
                            unit,
                        },
                    ));
                }
            }
        }
        Ok(col.clone())
    }

    fn time(&self, renames: &BTreeMap<String, String>) -> Result<Vec<f64>, DataError> {
        let t = self.take("t", renames, None)?;
        let idx = self.find("t", renames).unwrap_or(0);
        if t.len() < 2 {
            return Err(err(&self.file, None, None, Problem::TooShort));
        }
        for k in 1..t.len() {
            if t[k] <= t[k - 1] {
                return Err(err(
                    &self.file,
                    Some(self.lines[k]),
                    Some((&self.header[idx], idx + 1)),
                    Problem::TimeNotIncreasing {
                        prev: t[k - 1],
                        this: t[k],
                    },
                ));
            }
        }
        Ok(t)
    }

    /// `true` if the table has the crane columns (`u_x` present, after renames).
    pub fn is_crane(&self, renames: &BTreeMap<String, String>) -> bool {
        self.find("u_x", renames).is_some()
    }

    /// Reads a crane run. Plausible ranges (a value outside is almost surely a wrong unit):
    /// voltages within +-12 V (the amplifier's saturation), `x` in [-0.05, 0.555] m, `y` in
    /// [-0.05, 0.675] m, `l` in [0.05, 1.0] m, `alpha` in (0, pi) rad, `beta` in
    /// [-pi/2, pi/2] rad.
    pub fn crane_run(&self, renames: &BTreeMap<String, String>) -> Result<CraneRun, DataError> {
        use core::f64::consts::{FRAC_PI_2, PI};
        let t = self.time(renames)?;
        let v = Some((-12.0 - 1e-9, 12.0 + 1e-9, "V"));
        Ok(CraneRun {
            t,
            u: [
                self.take("u_x", renames, v)?,
                self.take("u_y", renames, v)?,
                self.take("u_l", renames, v)?,
            ],
            x: self.take("x", renames, Some((-0.05, 0.555, "m")))?,
            y: self.take("y", renames, Some((-0.05, 0.675, "m")))?,
            l: self.take("l", renames, Some((0.05, 1.0, "m")))?,
            alpha: self.take("alpha", renames, Some((1e-9, PI - 1e-9, "rad")))?,
            beta: self.take("beta", renames, Some((-FRAC_PI_2, FRAC_PI_2, "rad")))?,
        })
    }

    /// Reads a single-axis run: `t`, `x` and `force` [N] or `u` [V] times `gain` [N/V].
    pub fn axis_run(
        &self,
        renames: &BTreeMap<String, String>,
        gain: Option<f64>,
    ) -> Result<AxisRun, DataError> {
        let t = self.time(renames)?;
        let x = self.take("x", renames, Some((-1e3, 1e3, "m")))?;
        let force = if self.find("force", renames).is_some() {
            self.take("force", renames, None)?
        } else if self.find("u", renames).is_some() {
            let g = gain.ok_or_else(|| {
                err(
                    &self.file,
                    None,
                    None,
                    Problem::BadValue(
                        "column `u` [V] needs `gain_n_per_v` in dataset.toml (or a `force` column)"
                            .into(),
                    ),
                )
            })?;
            self.take("u", renames, None)?
                .into_iter()
                .map(|u| g * u)
                .collect()
        } else {
            return Err(err(
                &self.file,
                None,
                None,
                Problem::MissingColumn("`force` or `u`".into()),
            ));
        };
        Ok(AxisRun { t, x, force })
    }
}

/// Reads and parses a CSV file.
pub fn read_table(file: &Path) -> Result<Table, DataError> {
    let text = std::fs::read_to_string(file)
        .map_err(|e| err(file, None, None, Problem::Io(e.to_string())))?;
    parse_table(file, &text)
}

/// Loads one run described by `spec` relative to `dir`, with the data set's defaults.
pub fn load_run(dir: &Path, ds: &DatasetSpec, spec: &RunSpec) -> Result<Run, DataError> {
    let path = dir.join(&spec.file);
    let table = read_table(&path)?;
    let mut renames = ds.columns.clone();
    renames.extend(spec.columns.clone());
    let payload = spec.payload_kg.unwrap_or(ds.payload_kg);
    if !(payload.is_finite() && payload >= 0.0) {
        return Err(err(
            &path,
            None,
            None,
            Problem::BadValue(format!("payload_kg must be >= 0 (got {payload})")),
        ));
    }
    let samples = if table.is_crane(&renames) {
        Samples::Crane(table.crane_run(&renames)?)
    } else {
        let gain = spec.gain_n_per_v.or(ds.gain_n_per_v);
        Samples::Axis(table.axis_run(&renames, gain)?)
    };
    Ok(Run {
        name: spec.file.clone(),
        kind: spec.kind,
        payload_kg: payload,
        samples,
    })
}

/// Parses `dataset.toml` text.
pub fn parse_spec(file: &Path, text: &str) -> Result<DatasetSpec, DataError> {
    let spec: DatasetSpec = toml::from_str(text).map_err(|e| {
        let line = e
            .span()
            .map(|s| text[..s.start.min(text.len())].lines().count().max(1));
        err(file, line, None, Problem::Toml(e.message().to_string()))
    })?;
    let bad = |what: String| err(file, None, None, Problem::BadValue(what));
    if !(spec.payload_kg.is_finite() && spec.payload_kg >= 0.0) {
        return Err(bad(format!(
            "payload_kg must be >= 0 (got {})",
            spec.payload_kg
        )));
    }
    if let Some(g) = spec.gain_n_per_v {
        if !(g.is_finite() && g > 0.0) {
            return Err(bad(format!("gain_n_per_v must be > 0 (got {g})")));
        }
    }
    let c = &spec.constants;
    for (name, v) in [
        ("constants.trolley_mass_kg", c.trolley_mass_kg),
        ("constants.gravity", c.gravity),
        ("constants.pulley_radius_x_m", c.pulley_radius_x_m),
        ("constants.pulley_radius_y_m", c.pulley_radius_y_m),
        ("constants.pulley_radius_l_m", c.pulley_radius_l_m),
        ("constants.encoder_pulses", c.encoder_pulses),
    ] {
        if !(v.is_finite() && v > 0.0) {
            return Err(bad(format!("{name} must be > 0 (got {v})")));
        }
    }
    for (name, r) in [
        ("constants.x_range_m", c.x_range_m),
        ("constants.y_range_m", c.y_range_m),
        ("constants.l_range_m", c.l_range_m),
    ] {
        if !(r[0].is_finite() && r[1].is_finite() && r[0] < r[1]) {
            return Err(bad(format!(
                "{name} must be [min, max] with min < max (got {r:?})"
            )));
        }
    }
    if !(c.rail_mass_kg.is_finite() && c.rail_mass_kg >= 0.0) {
        return Err(bad(format!(
            "constants.rail_mass_kg must be >= 0 (got {})",
            c.rail_mass_kg
        )));
    }
    let n = &spec.breakaway_noise_var;
    for (name, v) in [
        ("x_pos", n.x_pos),
        ("x_neg", n.x_neg),
        ("y_pos", n.y_pos),
        ("y_neg", n.y_neg),
    ] {
        if !(v.is_finite() && v > 0.0) {
            return Err(bad(format!(
                "breakaway_noise_var.{name} must be > 0 (got {v})"
            )));
        }
    }
    Ok(spec)
}

/// Loads a data set directory: `dataset.toml`, then every run it lists (or every `*.csv` in
/// file-name order, kind `other`, when it lists none). The first bad file stops the load with
/// an error naming file, line and column.
pub fn load_dataset(dir: &Path) -> Result<Dataset, DataError> {
    let spec_path = dir.join(DATASET_FILE);
    let text = std::fs::read_to_string(&spec_path)
        .map_err(|e| err(&spec_path, None, None, Problem::Io(e.to_string())))?;
    let mut spec = parse_spec(&spec_path, &text)?;
    if spec.runs.is_empty() {
        let mut files: Vec<String> = std::fs::read_dir(dir)
            .map_err(|e| err(dir, None, None, Problem::Io(e.to_string())))?
            .filter_map(|e| e.ok())
            .filter_map(|e| e.file_name().into_string().ok())
            .filter(|n| n.ends_with(".csv"))
            .collect();
        files.sort();
        spec.runs = files
            .into_iter()
            .map(|file| RunSpec {
                file,
                ..RunSpec::default()
            })
            .collect();
    }
    let runs = spec
        .runs
        .iter()
        .map(|r| load_run(dir, &spec, r))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(Dataset {
        dir: dir.to_path_buf(),
        spec,
        runs,
    })
}

/// Writes a crane run as CSV (header `t,u_x,u_y,u_l,x,y,l,alpha,beta`), with `comment` lines
/// first (each prefixed by `# `). Values are written with enough digits to round-trip.
pub fn write_crane_run(path: &Path, run: &CraneRun, comment: &str) -> std::io::Result<()> {
    use std::fmt::Write as _;
    let mut s = String::with_capacity(run.len() * 120 + 200);
    for line in comment.lines() {
        let _ = writeln!(s, "# {line}");
    }
    s.push_str("t,u_x,u_y,u_l,x,y,l,alpha,beta\n");
    for k in 0..run.len() {
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{},{},{}",
            run.t[k],
            run.u[0][k],
            run.u[1][k],
            run.u[2][k],
            run.x[k],
            run.y[k],
            run.l[k],
            run.alpha[k],
            run.beta[k]
        );
    }
    std::fs::write(path, s)
}

/// Writes `dataset.toml`.
pub fn write_spec(dir: &Path, spec: &DatasetSpec) -> std::io::Result<()> {
    let text = toml::to_string_pretty(spec).map_err(std::io::Error::other)?;
    std::fs::write(
        dir.join(DATASET_FILE),
        format!("# Crane data set (format: crane-ident DATA_FORMAT.md)\n{text}"),
    )
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

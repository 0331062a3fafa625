//! `crane monitor LOG`: decodes the friction monitor's frames from a UART or semihosting log
//! (format: `twin/src/logic/monitor/frame.rs`), prints its alarms and last friction maps as a
//! table, and writes a JSON report and an SVG plot.
//!
//! - [`parse`]: the frames (`MBEGIN`, `MEND`, `MALARM`, `MSUM`, `MMAP`) into a [`Report`];
//!   every other line of the log is ignored.
//! - [`report`]: the table, and the bins whose current level left its band.
//! - [`plot`]: the last maps of the last section (SVG).
//!
//! Units: positions [m], forces [N] (map rows in integer millinewtons [mN], as in the
//! frames), slopes [N s/m], speeds [m/s], times [s].

pub mod parse;
pub mod plot;
pub mod report;

use crate::output::{normalise, OutputError, Outputs};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Default control period of the firmware [s] (500 Hz).
pub const PERIOD_S: f64 = 0.002;

/// Plausible range of a control period [s] (`--period-s`), both ends included.
pub const PERIOD_S_RANGE: (f64, f64) = (1e-5, 1.0);

/// A bin is out of its band when `|cur - ref| > OUT_OF_BAND_K * band` (band standard
/// deviations; the firmware's local check `k_local`).
pub const OUT_OF_BAND_K: f64 = 4.5;

/// Tag of the section of a log whose frames come without `MBEGIN` (a capture from a board).
pub const IMPLICIT_TAG: &str = "log";

/// Drive axis of a frame (`X`: trolley, `Y`: bridge).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Axis {
    /// The trolley's axis (`X` in the frames).
    X,
    /// The bridge's axis (`Y` in the frames).
    Y,
}

impl Axis {
    /// The name in the frames.
    pub fn name(self) -> &'static str {
        match self {
            Axis::X => "X",
            Axis::Y => "Y",
        }
    }
}

/// Direction of motion of a frame: `+`, `-`, or `+-` (an alarm seen in both; never a map's).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Dir {
    /// Moving towards larger positions (`+`).
    #[serde(rename = "+")]
    Positive,
    /// Moving towards smaller positions (`-`).
    #[serde(rename = "-")]
    Negative,
    /// Both directions (`+-`, alarms only).
    #[serde(rename = "+-")]
    Both,
}

impl Dir {
    /// The name in the frames.
    pub fn name(self) -> &'static str {
        match self {
            Dir::Positive => "+",
            Dir::Negative => "-",
            Dir::Both => "+-",
        }
    }
}

/// Kind of an alarm with its size; serialized as `kind` (the frame's name) beside its
/// size fields.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum AlarmKind {
    /// The sliding friction over the whole travel moved from its reference.
    FrictionDrift {
        /// Change of the friction level [N] (positive: higher).
        change: f32,
    },
    /// A stretch of the travel left its band while the rest stayed.
    LocalFriction {
        /// Centre of the stretch [m].
        position: f32,
        /// Width of the stretch [m].
        width: f32,
        /// Largest change in the stretch [N] beyond the travel's common change.
        change: f32,
    },
    /// Breakaway from rest rose above the sliding friction more than commissioning saw.
    StictionRise {
        /// Recent breakaway over sliding friction [1].
        ratio: f32,
        /// The ratio commissioning learned [1].
        learned: f32,
    },
    /// The observer's residual is large and the map shows no pattern that explains it.
    ModelMismatch {
        /// Residual mean square now [m^2].
        mean_square: f32,
        /// Its commissioning level [m^2].
        learned: f32,
    },
}

impl AlarmKind {
    /// The frames' names of the kinds, in declaration order.
    pub const NAMES: [&'static str; 4] = [
        "friction_drift",
        "local_friction",
        "stiction_rise",
        "model_mismatch",
    ];

    /// The name in the frames.
    pub fn name(&self) -> &'static str {
        match self {
            AlarmKind::FrictionDrift { .. } => Self::NAMES[0],
            AlarmKind::LocalFriction { .. } => Self::NAMES[1],
            AlarmKind::StictionRise { .. } => Self::NAMES[2],
            AlarmKind::ModelMismatch { .. } => Self::NAMES[3],
        }
    }
}

/// One `MALARM` frame.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Alarm {
    /// Control period it was raised in (index since start).
    pub period: u64,
    /// Its time since start [s] (`period * period_s`).
    pub time_s: f64,
    /// Drive axis.
    pub axis: Axis,
    /// Direction of motion it was seen in.
    pub dir: Dir,
    /// Kind and size.
    #[serde(flatten)]
    pub kind: AlarmKind,
}

/// A bin whose current level is further from its reference than [`OUT_OF_BAND_K`] bands.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct OutOfBand {
    /// Bin index (0-based).
    pub bin: usize,
    /// Centre of the bin [m].
    pub position: f64,
    /// Reference level [mN].
    #[serde(rename = "ref_mN")]
    pub ref_mn: i32,
    /// Current level [mN].
    #[serde(rename = "cur_mN")]
    pub cur_mn: i32,
    /// Band (standard deviation) [mN].
    #[serde(rename = "band_mN")]
    pub band_mn: i32,
}

/// One map summary: an `MSUM` frame with its three `MMAP` rows.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Map {
    /// Drive axis.
    pub axis: Axis,
    /// Direction of motion (`+` or `-`).
    pub dir: Dir,
    /// Control period of the summary (index since start).
    pub period: u64,
    /// Its time since start [s].
    pub time_s: f64,
    /// Start of the mapped travel [m].
    pub lo: f32,
    /// End of the mapped travel [m].
    pub hi: f32,
    /// Number of bins over `lo..hi`.
    pub bins: usize,
    /// Friction level over the travel against the reference [N].
    pub level: f32,
    /// Band (standard deviation) of that level [N].
    pub level_sd: f32,
    /// Learned viscous slope of the residual [N s/m].
    pub slope: f32,
    /// Speed the slope is centred on [m/s].
    pub v0: f32,
    /// Whether the monitor was ready (commissioning over, it judges) at this summary; `null`
    /// for a log of a firmware without the field.
    pub ready: Option<bool>,
    /// What commissioning had seen of this axis and direction (`null` without the fields):
    /// restarts from rest learned, moves that gave the travel's level, bins judged.
    pub coverage: Option<Coverage>,
    /// Reference row [mN] per bin (`null`: no sample yet); the whole row is `null` when the
    /// log has no `what=ref` row for this summary (a truncated capture).
    #[serde(rename = "ref_mN")]
    pub ref_mn: Option<Vec<Option<i32>>>,
    /// Current level row [mN] per bin (as `ref_mN`).
    #[serde(rename = "cur_mN")]
    pub cur_mn: Option<Vec<Option<i32>>>,
    /// Band row (standard deviation) [mN] per bin (as `ref_mN`).
    #[serde(rename = "band_mN")]
    pub band_mn: Option<Vec<Option<i32>>>,
    /// Bins where `|cur - ref| > OUT_OF_BAND_K * band`.
    pub out_of_band: Vec<OutOfBand>,
}

/// What commissioning has seen of one axis and direction (the `MSUM` fields `restarts`,
/// `moves`, `judged`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Coverage {
    /// Restarts from rest whose breakaway was learned.
    pub restarts: u32,
    /// Moves that gave the travel's level.
    pub moves: u32,
    /// Bins with enough samples to be judged.
    pub judged: u32,
}

impl Map {
    /// Width of one bin [m].
    pub fn bin_width(&self) -> f64 {
        (f64::from(self.hi) - f64::from(self.lo)) / self.bins as f64
    }

    /// Centre of bin `b` [m]: `lo + (b + 0.5) (hi - lo) / bins`.
    pub fn centre(&self, b: usize) -> f64 {
        f64::from(self.lo) + (b as f64 + 0.5) * self.bin_width()
    }

    /// Number of bins with data in any row.
    pub fn bins_with_data(&self) -> usize {
        (0..self.bins)
            .filter(|&b| {
                [&self.ref_mn, &self.cur_mn, &self.band_mn].iter().any(|r| {
                    r.as_ref()
                        .and_then(|r| r.get(b).copied().flatten())
                        .is_some()
                })
            })
            .count()
    }
}

/// One section of the log (`MBEGIN` .. `MEND`, or the frames of a capture without them).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Section {
    /// Tag (`f64`, `f32x`, ...; [`IMPLICIT_TAG`] without `MBEGIN`).
    pub tag: String,
    /// Seed of the run (`null` without `MBEGIN`).
    pub seed: Option<u32>,
    /// Duration of the run [s] (`null` without `MBEGIN`).
    pub duration: Option<f64>,
    /// The `MEND` frame's hash (16 hex digits; `null` when the section did not end).
    pub hash: Option<String>,
    /// Its alarms, in log order.
    pub alarms: Vec<Alarm>,
    /// Its map summaries, in log order.
    pub maps: Vec<Map>,
}

impl Section {
    /// The last summary of each (axis, direction), in order of first appearance.
    pub fn last_maps(&self) -> Vec<&Map> {
        let mut keys: Vec<(Axis, Dir)> = Vec::new();
        for m in &self.maps {
            if !keys.contains(&(m.axis, m.dir)) {
                keys.push((m.axis, m.dir));
            }
        }
        keys.iter()
            .filter_map(|&(a, d)| self.maps.iter().rev().find(|m| m.axis == a && m.dir == d))
            .collect()
    }
}

/// A decoded log.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Report {
    /// The log, as given on the command line.
    pub log: String,
    /// Control period used for the times [s].
    pub period_s: f64,
    /// Its sections, in log order.
    pub sections: Vec<Section>,
}

/// Why `crane monitor` failed.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The log could not be read.
    #[error("read {}", path.display())]
    Read {
        /// The log.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The log is larger than [`parse::MAX_BYTES`].
    #[error("{}: larger than {} bytes; not a monitor log", path.display(), parse::MAX_BYTES)]
    TooLarge {
        /// The log.
        path: PathBuf,
    },
    /// A line is not UTF-8 text.
    #[error("{}:{line}: not UTF-8 text (invalid byte at column {column})", path.display())]
    NotUtf8 {
        /// The log.
        path: PathBuf,
        /// Line number (1-based).
        line: usize,
        /// Column of the first invalid byte (1-based).
        column: usize,
    },
    /// A frame is malformed (the frame and field are named in `message`).
    #[error("{}:{line}: {frame}: {message}", path.display())]
    Frame {
        /// The log.
        path: PathBuf,
        /// Line number (1-based).
        line: usize,
        /// The frame's name (`MSUM`, ...).
        frame: &'static str,
        /// What is wrong.
        message: String,
    },
    /// The log holds no monitor frame.
    #[error("no monitor frames in {}", path.display())]
    NoFrames {
        /// The log.
        path: PathBuf,
    },
    /// `--period-s` outside [`PERIOD_S_RANGE`].
    #[error("--period-s {0} is outside the plausible range [1e-5, 1] s")]
    Period(f64),
    /// Drawing the plot failed.
    #[error("plot {}: {message}", path.display())]
    Plot {
        /// The plot's file.
        path: PathBuf,
        /// plotters' message.
        message: String,
    },
    /// The JSON report could not be serialized.
    #[error("JSON report")]
    Json(#[from] serde_json::Error),
    /// Writing an output failed or was refused.
    #[error(transparent)]
    Output(#[from] OutputError),
}

/// What `crane monitor` was asked to do.
#[derive(Clone, Debug)]
pub struct Request {
    /// The log to decode.
    pub log: PathBuf,
    /// Output directory: `monitor.json` and `monitor.svg` unless `json` / `plot` are given.
    pub out: Option<PathBuf>,
    /// JSON report file.
    pub json: Option<PathBuf>,
    /// SVG plot file.
    pub plot: Option<PathBuf>,
    /// Control period [s].
    pub period_s: f64,
}

/// What `crane monitor` did.
#[derive(Clone, Debug)]
pub struct Done {
    /// The decoded log.
    pub report: Report,
    /// The files written, in order.
    pub written: Vec<PathBuf>,
}

/// The JSON and SVG files of `req` (`--json` / `--plot`, else in `--out`).
fn targets(req: &Request) -> (Option<PathBuf>, Option<PathBuf>) {
    let in_out = |name: &str| req.out.as_ref().map(|d| d.join(name));
    (
        req.json.clone().or_else(|| in_out("monitor.json")),
        req.plot.clone().or_else(|| in_out("monitor.svg")),
    )
}

/// Decodes `req.log` and writes its report and plot (atomically and together, or neither;
/// never over the log, a data set's file or each other). Refused outputs are found before
/// the log is read.
pub fn run(req: &Request) -> Result<Done, Error> {
    let (lo, hi) = PERIOD_S_RANGE;
    if !(req.period_s >= lo && req.period_s <= hi) {
        return Err(Error::Period(req.period_s));
    }
    let mut outputs = Outputs::new(false).input(&req.log);
    if let Some(dir) = &req.out {
        outputs.check_dir(dir)?;
    }
    let (json, svg) = targets(req);
    for p in json.iter().chain(svg.iter()) {
        outputs.check(p)?;
    }
    if let (Some(j), Some(s)) = (&json, &svg) {
        if normalise(j) == normalise(s) {
            return Err(OutputError::Clash {
                out: s.clone(),
                why: "the JSON report and the plot would be the same file",
            }
            .into());
        }
    }
    let report = parse::read(&req.log, req.period_s)?;
    if let Some(path) = json {
        outputs.stage(&path, serde_json::to_string_pretty(&report)? + "\n")?;
    }
    if let Some(path) = svg {
        let text = plot::svg(&report).map_err(|message| Error::Plot {
            path: path.clone(),
            message,
        })?;
        outputs.stage(&path, text)?;
    }
    // both or neither
    let written = outputs.commit()?;
    Ok(Done { report, written })
}

/// `path` as given, for messages and the report.
fn shown(path: &Path) -> String {
    path.display().to_string()
}

//! Located data errors: what is wrong ([`Problem`]) and where ([`Location`]: file, line,
//! column). Every text taken from a user's file is clipped to [`CLIP_CHARS`] characters
//! before it enters a message.

use crate::num::Num;
use std::fmt;
use std::path::{Path, PathBuf};

/// Longest user text echoed in a message [characters]; longer text is cut and its length
/// given.
pub const CLIP_CHARS: usize = 60;

/// `s` as shown in a message: at most [`CLIP_CHARS`] characters, then `...` and the length.
pub fn clip(s: &str) -> String {
    let n = s.chars().count();
    if n <= CLIP_CHARS {
        return s.to_string();
    }
    let head: String = s.chars().take(CLIP_CHARS - 3).collect();
    format!("{head}... ({n} characters)")
}

/// Clips every backtick-quoted span of a message (what `toml` and `serde` quote from the
/// input), so that a huge value is never echoed whole; the message itself is kept.
pub fn clip_quoted(msg: &str) -> String {
    let mut out = String::with_capacity(msg.len().min(4096));
    let mut parts = msg.split('`');
    if let Some(first) = parts.next() {
        out.push_str(&clip_long(first, 400));
    }
    for (i, p) in parts.enumerate() {
        out.push('`');
        if i % 2 == 0 {
            out.push_str(&clip(p));
        } else {
            out.push_str(&clip_long(p, 400));
        }
    }
    out
}

fn clip_long(s: &str, max: usize) -> String {
    if s.chars().count() <= max {
        s.to_string()
    } else {
        let head: String = s.chars().take(max).collect();
        format!("{head}...")
    }
}

/// Where in a file something is wrong.
#[derive(Clone, Debug, PartialEq)]
pub struct Location {
    /// File.
    pub file: PathBuf,
    /// 1-based line, if any.
    pub line: Option<usize>,
    /// Column name (clipped) and its 1-based position, if any.
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

/// Names listed after "the header has": the first few, clipped, then how many more.
fn list_names(found: &[String]) -> String {
    const SHOWN: usize = 12;
    let mut s = found
        .iter()
        .take(SHOWN)
        .map(|n| format!("`{}`", clip(n)))
        .collect::<Vec<_>>()
        .join(", ");
    if found.len() > SHOWN {
        s.push_str(&format!(" and {} more", found.len() - SHOWN));
    }
    if found.is_empty() {
        s.push_str("no names");
    }
    s
}

/// A required column that is absent, and what the header has instead.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("missing column {wanted}; the header has {}{}", list_names(found), hint.as_deref().unwrap_or(""))]
pub struct MissingColumn {
    /// The column looked for, as shown (with its rename, if any).
    pub wanted: String,
    /// Header names found (the first 64, clipped).
    pub found: Vec<String>,
    /// A hint when a header name looks like the wanted one (e.g. `t [s]`).
    pub hint: Option<String>,
}

/// What is wrong. Texts from the user's files are clipped ([`clip`]) when the problem is
/// built.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum Problem {
    /// File cannot be read.
    #[error("cannot read: {0}")]
    Io(String),
    /// `dataset.toml` does not parse or has a bad field.
    #[error("bad dataset description: {0}")]
    Toml(String),
    /// No header line.
    #[error("no header line")]
    NoHeader,
    /// A required column is absent (boxed: errors stay small).
    #[error("{0}")]
    MissingColumn(Box<MissingColumn>),
    /// Two header fields have the same name.
    #[error("column appears twice in the header")]
    DuplicateColumn,
    /// A row has a different number of fields than the header.
    #[error("{found} fields, the header has {expected}")]
    FieldCount {
        /// Fields expected.
        expected: usize,
        /// Fields found.
        found: usize,
    },
    /// A field is not a number (the field, clipped).
    #[error("not a number: `{0}`")]
    NotNumeric(String),
    /// A field is NaN or infinite (the field, clipped), or a computed value overflows.
    #[error("not finite: `{0}`")]
    NotFinite(String),
    /// Time does not increase.
    #[error("time does not increase ({} after {})", Num(*this), Num(*prev))]
    TimeNotIncreasing {
        /// Previous time [s].
        prev: f64,
        /// This time [s].
        this: f64,
    },
    /// Time steps that cannot be used or resampled sensibly (see `DATA_FORMAT.md`).
    #[error("{0}")]
    Timing(Timing),
    /// A value outside the plausible range of its unit.
    #[error("{} is outside [{}, {}] {unit} (wrong unit or sign convention?)", Num(*value), Num(*min), Num(*max))]
    OutOfRange {
        /// Value.
        value: f64,
        /// Lower bound.
        min: f64,
        /// Upper bound.
        max: f64,
        /// Unit.
        unit: &'static str,
    },
    /// An empty field where a value is needed: in a crane run, in a time stamp, or in a
    /// column that never gets a value.
    #[error("empty field: {0}")]
    BlankField(&'static str),
    /// Two rows with the same time stamp give different values in one column (an
    /// asynchronous log's rows at one instant may only complete each other).
    #[error("this row has the time stamp of line {first_line} but another value in this column ({} against {}): rows at one instant may only fill each other's empty fields", Num(*this), Num(*first))]
    SameStampConflict {
        /// Line of the first row with this stamp.
        first_line: usize,
        /// Its value.
        first: f64,
        /// This row's value.
        this: f64,
    },
    /// Fewer than two samples.
    #[error("fewer than two samples")]
    TooShort,
    /// A field of `dataset.toml` has a bad value.
    #[error("{0}")]
    BadValue(String),
}

/// Why a run's time stamps are refused (thresholds: [`super::limits`], applied by
/// `data::timebase`).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum Timing {
    /// A step longer than `MAX_GAP_STEPS` median steps: rows were lost.
    #[error("rows missing: the time step before this row is {} s, {:.1} times the median step {} s (more than {}); holding the last value over the gap would invent a rest, so the run is refused (split it into runs at the gap)", Num(*step_s), step_s / median_step_s, Num(*median_step_s), super::limits::MAX_GAP_STEPS)]
    Gap {
        /// The step [s].
        step_s: f64,
        /// The run's median step [s].
        median_step_s: f64,
    },
    /// A median sample rate outside [`super::limits::RATE_RANGE_HZ`]: almost surely
    /// stamps in another unit than `time_unit` says (milliseconds or sample indices read as
    /// seconds, or the reverse).
    #[error("the median time step is {} s, a sample rate of {:.4e} Hz, outside ({}, {}) Hz: is `time_unit` in dataset.toml right (\"s\", \"ms\", \"us\")? time stamps in milliseconds or sample indices read as seconds give 1 Hz or less", Num(*median_step_s), 1.0 / median_step_s, super::limits::RATE_RANGE_HZ.0, super::limits::RATE_RANGE_HZ.1)]
    Rate {
        /// The run's median step [s].
        median_step_s: f64,
    },
    /// Irregular stamps in a crane run, which must be uniformly sampled.
    #[error("irregular time stamps: the step ending here is {} s, the median step {} s ({irregular_steps} steps deviate more than {:.0} %); crane runs must be uniformly sampled (rows dropped or an asynchronous log?)", Num(*step_s), Num(*median_step_s), super::limits::JITTER_TOLERANCE * 100.0)]
    IrregularCrane {
        /// The most deviating step [s].
        step_s: f64,
        /// The run's median step [s].
        median_step_s: f64,
        /// Steps outside the tolerance.
        irregular_steps: usize,
    },
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

/// Builds a [`DataError`]; the column name is clipped.
pub(crate) fn err(
    file: &Path,
    line: Option<usize>,
    column: Option<(&str, usize)>,
    problem: Problem,
) -> DataError {
    DataError {
        location: Location {
            file: file.to_path_buf(),
            line,
            column: column.map(|(n, p)| (clip(n), p)),
        },
        problem,
    }
}

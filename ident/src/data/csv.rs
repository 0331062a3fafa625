//! Reading runs: CSV text to a [`Table`] of numeric columns with the file line of every row.
//!
//! Written by hand rather than with the `csv` crate because the format is a strict subset
//! (numbers only, no quoting inside fields) and every error must carry the file line counted
//! with comments and blank lines, which is what this parser tracks.

use super::error::{clip, err, DataError, MissingColumn, Problem};
use std::collections::{BTreeMap, HashSet};
use std::path::{Path, PathBuf};

/// The field separator of a file, told by its header line: a comma when the header has one,
/// else a tab, else a semicolon (spreadsheets in locales with a decimal comma write
/// `0,5;1,25`: with semicolons, a decimal comma is read as a point).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Delimiter {
    /// `,` (the format's own).
    Comma,
    /// A tab.
    Tab,
    /// `;`, numbers with a decimal point or a decimal comma.
    Semicolon,
}

impl Delimiter {
    /// The separator of the file whose header line is `header`.
    pub fn of_header(header: &str) -> Delimiter {
        if header.contains(',') {
            Delimiter::Comma
        } else if header.contains('\t') {
            Delimiter::Tab
        } else if header.contains(';') {
            Delimiter::Semicolon
        } else {
            Delimiter::Comma
        }
    }

    /// The separator character.
    pub fn char(self) -> char {
        match self {
            Delimiter::Comma => ',',
            Delimiter::Tab => '\t',
            Delimiter::Semicolon => ';',
        }
    }

    /// A field as a number (`None` if it is not one).
    pub fn number(self, field: &str) -> Option<f64> {
        match (field.parse::<f64>(), self) {
            (Ok(v), _) => Some(v),
            (Err(_), Delimiter::Semicolon) if field.matches(',').count() == 1 => {
                field.replace(',', ".").parse().ok()
            }
            _ => None,
        }
    }
}

/// An empty field in a [`Table`] column. NaN written in a file is refused while parsing, so
/// inside a table NaN always means "empty field".
pub const BLANK: f64 = f64::NAN;

/// A parsed CSV table: header names and numeric columns, with line numbers for errors.
#[derive(Clone, Debug, PartialEq)]
pub struct Table {
    /// File it came from.
    pub file: PathBuf,
    /// Header names (trimmed, surrounding quotes removed).
    pub header: Vec<String>,
    /// Values, one vector per header column.
    pub columns: Vec<Vec<f64>>,
    /// 1-based file line of each row.
    pub lines: Vec<usize>,
}

/// Parses CSV text: a UTF-8 byte-order mark is skipped, `#` lines are comments, blank lines
/// are skipped, the first other line is the header (its separator, `,`, tab or `;`, is the
/// file's: [`Delimiter`]), every other line a row of as many numeric fields. Every field is checked (numeric, finite), also in columns that will be
/// ignored; an empty field is kept as [`BLANK`] (asynchronous logs), refused later where a
/// value is needed. Duplicate header names are found in linear time.
pub fn parse_table(file: &Path, text: &str) -> Result<Table, DataError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut header: Option<Vec<String>> = None;
    let mut columns: Vec<Vec<f64>> = Vec::new();
    let mut lines = Vec::new();
    let mut delim = Delimiter::Comma;
    for (i, raw) in text.lines().enumerate() {
        let lineno = i + 1;
        let line = raw.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        match &header {
            None => {
                delim = Delimiter::of_header(line);
                let names: Vec<String> = line
                    .split(delim.char())
                    .map(|s| s.trim().trim_matches('"').trim().to_string())
                    .collect();
                let mut seen = HashSet::with_capacity(names.len());
                for (k, n) in names.iter().enumerate() {
                    if !seen.insert(n.as_str()) {
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
                let mut count = 0;
                for (k, s) in line.split(delim.char()).enumerate() {
                    count += 1;
                    let Some(col) = columns.get_mut(k) else {
                        continue;
                    };
                    let s = s.trim();
                    if s.is_empty() {
                        // a channel without a sample on this row (asynchronous logs): kept
                        // as a blank, which only `asynchronous::fill_blanks` may fill
                        col.push(BLANK);
                        continue;
                    }
                    let v: f64 = delim.number(s).ok_or_else(|| {
                        err(
                            file,
                            Some(lineno),
                            Some((&h[k], k + 1)),
                            Problem::NotNumeric(clip(s)),
                        )
                    })?;
                    if !v.is_finite() {
                        return Err(err(
                            file,
                            Some(lineno),
                            Some((&h[k], k + 1)),
                            Problem::NotFinite(clip(s)),
                        ));
                    }
                    col.push(v);
                }
                if count != h.len() {
                    return Err(err(
                        file,
                        Some(lineno),
                        None,
                        Problem::FieldCount {
                            expected: h.len(),
                            found: count,
                        },
                    ));
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

/// Reads and parses a CSV file.
pub fn read_table(file: &Path) -> Result<Table, DataError> {
    let text = crate::input::read_text(file)
        .map_err(|e| err(file, None, None, Problem::Io(e.to_string())))?;
    parse_table(file, &text)
}

/// The bare name of a header field written with a unit, `t [s]`, `x(m)`, `u / V`: the text
/// before the first space, bracket or slash.
fn bare_name(h: &str) -> &str {
    h.split([' ', '[', '(', '/', '{']).next().unwrap_or(h)
}

impl Table {
    /// Number of rows.
    pub fn len(&self) -> usize {
        self.lines.len()
    }

    /// No rows.
    pub fn is_empty(&self) -> bool {
        self.lines.is_empty()
    }

    /// Index of the column holding canonical `name` (after `renames`).
    pub fn find(&self, name: &str, renames: &BTreeMap<String, String>) -> Option<usize> {
        let target = renames.get(name).map(String::as_str).unwrap_or(name);
        self.header.iter().position(|h| h == target)
    }

    /// The "missing column" error for canonical `name`, with the header names found and a
    /// hint when one of them is that name with a unit attached.
    pub fn missing(&self, name: &str, renames: &BTreeMap<String, String>) -> DataError {
        let target = renames.get(name).map(String::as_str).unwrap_or(name);
        let wanted = match renames.get(name) {
            Some(r) => format!("`{}` (for `{name}`)", clip(r)),
            None => format!("`{name}`"),
        };
        let hint = self
            .header
            .iter()
            .find(|h| h.as_str() != target && bare_name(h) == target)
            .map(|h| {
                format!(
                    "; `{}` looks like `{target}` with a unit: header names are bare names \
                     (units are set by the format and dataset.toml), rename the column to \
                     `{target}` or map it in dataset.toml: [columns] {name} = \"{}\"",
                    clip(h),
                    clip(h)
                )
            });
        super::error::err(
            &self.file,
            None,
            None,
            Problem::MissingColumn(Box::new(MissingColumn {
                wanted,
                found: self.header.iter().take(64).map(|h| clip(h)).collect(),
                hint,
            })),
        )
    }

    /// Multiplies column `name` (after `renames`) by `factor`, when the column exists (a
    /// missing column is reported by [`Table::take`]); a unit conversion before the checks.
    pub fn scale(&mut self, name: &str, renames: &BTreeMap<String, String>, factor: f64) {
        if factor == 1.0 {
            return;
        }
        if let Some(i) = self.find(name, renames) {
            for v in &mut self.columns[i] {
                *v *= factor;
            }
        }
    }

    /// Column `name` (after `renames`), every value checked against `range` (min, max, unit).
    pub fn take(
        &self,
        name: &str,
        renames: &BTreeMap<String, String>,
        range: Option<(f64, f64, &'static str)>,
    ) -> Result<Vec<f64>, DataError> {
        let idx = self
            .find(name, renames)
            .ok_or_else(|| self.missing(name, renames))?;
        let col = &self.columns[idx];
        if let Some(k) = col.iter().position(|v| v.is_nan()) {
            return Err(err(
                &self.file,
                Some(self.lines[k]),
                Some((&self.header[idx], idx + 1)),
                Problem::BlankField(
                    "every row needs a value here (single-axis runs may leave x, u or force \
                     empty on rows of an asynchronous log: they are then filled; crane runs \
                     and time stamps may not)",
                ),
            ));
        }
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

    /// The error for row `k` (0-based) of column `name`.
    pub fn at(
        &self,
        k: usize,
        name: &str,
        renames: &BTreeMap<String, String>,
        p: Problem,
    ) -> DataError {
        let idx = self.find(name, renames);
        err(
            &self.file,
            self.lines.get(k).copied(),
            idx.map(|i| (self.header[i].as_str(), i + 1)),
            p,
        )
    }
}

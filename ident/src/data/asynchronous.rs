//! Asynchronous logs: rows that carry only some of the channels.
//!
//! A log merged from topics or sensors refreshed at their own instants (a ROS bag exported
//! to CSV, a DAQ and a drive logging apart) often writes one row per message with the other
//! channels' fields left empty, and may write several rows at one stamp. Before the time
//! checks of [`super::timebase`], a single-axis run's table is brought to one complete row per
//! instant:
//!
//! 1. consecutive rows with equal stamps are merged: each column takes the value its rows
//!    give; two different values for one column at one instant are refused
//!    ([`Problem::SameStampConflict`]): that is not one instant but a clock too coarse for
//!    the log, and picking either would be silent nonsense;
//! 2. an empty field takes its column's last value before it (zero-order hold: what the
//!    channel's receiver held), which the held-channel rule of `timebase` then sees;
//! 3. rows before every used column has had a value are dropped (nothing to hold yet).
//!
//! A blank time stamp, or a used column that is never given a value, is refused at its line.
//! A table with no empty field and no repeated stamp is returned unchanged, without a note.
//! Work: one pass over the rows, O(rows x used columns).

use super::csv::Table;
use super::error::{clip, err, DataError, Problem};
use std::fmt;

/// What [`fill_blanks`] did to a run, for its notes.
#[derive(Clone, Debug, PartialEq)]
pub struct Filled {
    /// Rows in the file.
    pub rows_in: usize,
    /// Rows after merging equal stamps and dropping the leading incomplete ones.
    pub rows_out: usize,
    /// Rows merged into the row before them (same stamp).
    pub merged: usize,
    /// Leading rows dropped (some used column had no value yet).
    pub dropped_leading: usize,
    /// Per used column (header name, clipped): empty fields filled by the last value.
    pub held: Vec<(String, usize)>,
}

/// Per used column (its index in the table), for each row [`fill_blanks`] put out whether
/// the file gave the value (`false`: an empty field filled by the last value): when each
/// value was taken, for a resampling that reads a position between the instants it was
/// given.
pub type Given = Vec<(usize, Vec<bool>)>;

impl fmt::Display for Filled {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "asynchronous log: {} rows to {} ({} rows at the time stamp of the row before merged into it; the first {} rows dropped, before every channel had a value)",
            self.rows_in, self.rows_out, self.merged, self.dropped_leading
        )?;
        let held: Vec<String> = self
            .held
            .iter()
            .filter(|(_, n)| *n > 0)
            .map(|(c, n)| format!("{c} {n}"))
            .collect();
        if !held.is_empty() {
            write!(
                f,
                "; empty fields held at the column's last value: {}",
                held.join(", ")
            )?;
        }
        Ok(())
    }
}

/// One complete row per instant from `table` (see the module doc): `t` is the index of the
/// time column, `used` those of the columns the run reads. `Ok((table, None, given))` when
/// nothing needed doing (`given` then empty), else the note and which rows gave each used
/// column's value ([`Given`]).
pub fn fill_blanks(
    table: &Table,
    t: usize,
    used: &[usize],
) -> Result<(Table, Option<Filled>, Given), DataError> {
    let tc = &table.columns[t];
    let at = |row: usize, col: usize, p: Problem| {
        err(
            &table.file,
            Some(table.lines[row]),
            Some((&table.header[col], col + 1)),
            p,
        )
    };
    if let Some(k) = tc.iter().position(|v| v.is_nan()) {
        return Err(at(k, t, Problem::BlankField("a row needs its time stamp")));
    }
    let blanks = used
        .iter()
        .any(|&c| table.columns[c].iter().any(|v| v.is_nan()));
    let repeats = tc.windows(2).any(|w| w[0] == w[1]);
    if !blanks && !repeats {
        return Ok((table.clone(), None, Vec::new()));
    }
    let rows_in = table.len();
    let cols: Vec<usize> = std::iter::once(t)
        .chain(used.iter().copied().filter(|&c| c != t))
        .collect();
    // 1. merge rows at one stamp: per group, its first row, its row count and the values of
    //    the columns in `cols`
    struct Group {
        first: usize,
        rows: usize,
        vals: Vec<f64>,
    }
    let mut groups: Vec<Group> = Vec::with_capacity(rows_in);
    for k in 0..rows_in {
        match groups.last_mut() {
            Some(g) if tc[g.first] == tc[k] => {
                g.rows += 1;
                for (j, &c) in cols.iter().enumerate() {
                    let v = table.columns[c][k];
                    if v.is_nan() {
                        continue;
                    }
                    if g.vals[j].is_nan() {
                        g.vals[j] = v;
                    } else if g.vals[j] != v {
                        return Err(at(
                            k,
                            c,
                            Problem::SameStampConflict {
                                first_line: table.lines[g.first],
                                first: g.vals[j],
                                this: v,
                            },
                        ));
                    }
                }
            }
            _ => groups.push(Group {
                first: k,
                rows: 1,
                vals: cols.iter().map(|&c| table.columns[c][k]).collect(),
            }),
        }
    }
    // 3. the first group from which every used column has had a value
    let mut start = 0;
    for (j, &c) in cols.iter().enumerate().skip(1) {
        match groups.iter().position(|g| !g.vals[j].is_nan()) {
            Some(p) => start = start.max(p),
            None => {
                return Err(err(
                    &table.file,
                    None,
                    Some((&table.header[c], c + 1)),
                    Problem::BlankField("this column has no value on any row"),
                ))
            }
        }
    }
    // 2. hold the last value over empty fields (the values of the dropped groups included)
    let mut last: Vec<f64> = vec![f64::NAN; cols.len()];
    let mut held = vec![0usize; cols.len()];
    let mut given: Vec<Vec<bool>> = vec![Vec::with_capacity(groups.len() - start); cols.len()];
    let mut out = Table {
        file: table.file.clone(),
        header: table.header.clone(),
        columns: vec![Vec::with_capacity(groups.len() - start); table.header.len()],
        lines: Vec::with_capacity(groups.len() - start),
    };
    for (i, g) in groups.iter().enumerate() {
        for (j, &x) in g.vals.iter().enumerate() {
            if !x.is_nan() {
                last[j] = x;
            } else if i >= start {
                held[j] += 1;
            }
        }
        if i < start {
            continue;
        }
        for (j, &c) in cols.iter().enumerate() {
            out.columns[c].push(last[j]);
            given[j].push(!g.vals[j].is_nan());
        }
        // columns the run does not read keep the group's first row (blank or not)
        for c in (0..table.header.len()).filter(|c| !cols.contains(c)) {
            out.columns[c].push(table.columns[c][g.first]);
        }
        out.lines.push(table.lines[g.first]);
    }
    let note = Filled {
        rows_in,
        rows_out: out.len(),
        merged: rows_in - groups.len(),
        dropped_leading: groups[..start].iter().map(|g| g.rows).sum(),
        held: cols
            .iter()
            .enumerate()
            .skip(1)
            .map(|(j, &c)| (clip(&table.header[c]), held[j]))
            .collect(),
    };
    let given = cols.iter().copied().zip(given).skip(1).collect();
    Ok((out, Some(note), given))
}

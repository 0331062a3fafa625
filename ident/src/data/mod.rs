//! The data format: runs as CSV files, a data set as a directory of runs plus `dataset.toml`.
//! See `DATA_FORMAT.md` next to `Cargo.toml` for the user-facing description.
//!
//! - [`csv`]: CSV text to a numeric [`Table`] with file lines;
//! - [`spec`]: `dataset.toml` ([`DatasetSpec`]) and its plausible ranges;
//! - [`units`]: position and input units, the input [`Gain`];
//! - [`timebase`]: time-stamp checks, held channels, zero-order-hold resampling;
//! - [`error`]: located errors ([`DataError`]: file, line, column).

pub mod asynchronous;
pub mod csv;
pub mod error;
pub mod limits;
pub mod spec;
pub mod timebase;
pub mod units;

pub use csv::{parse_table, read_table, Table};
pub use error::{clip, DataError, Location, MissingColumn, Problem, Timing};
pub use spec::{
    parse_spec, BreakawayNoise, Constants, ControllerSpec, DatasetSpec, RunKind, RunSpec,
    VelocityEstimate,
};
pub use timebase::{Irregularity, LoadNote, TimeBase};
pub use units::{Gain, InputUnit, PositionUnit, TimeUnit};

use error::err;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Name of the data set description inside a data set directory.
pub const DATASET_FILE: &str = "dataset.toml";

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

/// Signals of a closed-loop single-axis run, for the declared controller
/// ([`ControllerSpec`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LoopSignals {
    /// Reference position `r` [m or rad, the run's position unit].
    pub reference: Vec<f64>,
    /// Input added after the saturation [input units]; zeros when none is declared.
    pub added_input: Vec<f64>,
}

/// Samples of a single-axis run on a uniform time grid, with its units and what the loader
/// did to it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AxisRun {
    /// Time [s], strictly increasing and uniform within [`timebase::JITTER_TOLERANCE`]
    /// (resampled when the file's stamps were not, see `notes`).
    pub t: Vec<f64>,
    /// Per sample, the time stamp [s] of the file row whose values it holds: `t` itself
    /// unless the run was resampled by zero-order hold, then the stamp of the row the hold
    /// picked (at or before the grid instant); `t` for an exact resampling (the position
    /// interpolated at `t`, the input averaged from it over the period). What a replay of
    /// the logging needs: when each value was actually taken.
    pub source_t: Vec<f64>,
    /// Position [m or rad: `position_unit`].
    pub x: Vec<f64>,
    /// Samples per fresh position sample when the loader interpolated a position given on
    /// fewer rows than the grid has samples (an asynchronous log's empty fields): the
    /// information `x` carries is that of one sample in `x_refresh`, and derivative windows
    /// must span it. 0 or 1: every sample is fresh, or a held channel is still visible in
    /// `x` (its repeats: `timebase::held_channel`).
    pub x_refresh: usize,
    /// Rows per refresh of the position column as logged ([`timebase::held_channel`] on the
    /// file's rows, before any resampling; 1: fresh on every row). A resampled log's grid
    /// shifts the repeats off the rows' lattice, where the hold is no longer seen.
    pub x_held: usize,
    /// Drive effort `gain * u` [N or N m] when the gain is known, else `u` itself [input
    /// units].
    pub force: Vec<f64>,
    /// Recorded input [input units: `input_unit`].
    pub u: Vec<f64>,
    /// Unit of `x`.
    pub position_unit: PositionUnit,
    /// Unit of `u`.
    pub input_unit: InputUnit,
    /// Gain from `u` to the effort.
    pub gain: Gain,
    /// Reference and added input, when the data set declares a controller.
    pub closed_loop: Option<LoopSignals>,
    /// What the loader noticed or did (resampling, held channels).
    pub notes: Vec<LoadNote>,
}

impl AxisRun {
    /// Mean sampling period [s] (the grid step: the loader guarantees a uniform grid).
    pub fn dt(&self) -> f64 {
        mean_dt(&self.t)
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.t.len()
    }

    /// No samples.
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }

    /// The samples in `range` (every per-sample vector cut alike; units, gain and notes
    /// kept). An out-of-bounds range is clamped.
    pub fn slice(&self, range: std::ops::Range<usize>) -> AxisRun {
        let end = range.end.min(self.t.len());
        let start = range.start.min(end);
        let cut = |v: &[f64]| v.get(start..end).unwrap_or_default().to_vec();
        AxisRun {
            t: cut(&self.t),
            source_t: cut(&self.source_t),
            x: cut(&self.x),
            x_refresh: self.x_refresh,
            x_held: self.x_held,
            force: cut(&self.force),
            u: cut(&self.u),
            position_unit: self.position_unit,
            input_unit: self.input_unit,
            gain: self.gain,
            closed_loop: self.closed_loop.as_ref().map(|c| LoopSignals {
                reference: cut(&c.reference),
                added_input: cut(&c.added_input),
            }),
            notes: self.notes.clone(),
        }
    }

    /// Unit of the effort `force`: `N`/`N m` when the gain is known, else the input unit.
    pub fn effort_unit(&self) -> &'static str {
        match self.gain {
            Gain::Known(_) => self.position_unit.effort_unit().symbol(),
            Gain::Unknown => self.input_unit.symbol(),
        }
    }

    /// Whether the loader resampled the run (irregular time stamps).
    pub fn resampled(&self) -> bool {
        self.notes
            .iter()
            .any(|n| matches!(n, LoadNote::Resampled { .. }))
    }

    /// Largest number of rows between refreshes of a held channel (1 when none is held):
    /// differences over fewer samples than this see the holds, not the motion.
    pub fn refresh_rows(&self) -> usize {
        self.notes
            .iter()
            .filter_map(|n| match n {
                LoadNote::HeldChannel {
                    rows_per_refresh, ..
                } => Some(*rows_per_refresh),
                _ => None,
            })
            .max()
            .unwrap_or(1)
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

/// Largest |time stamp| accepted [s]: Unix time in seconds (1.7e9 in 2024) until the year
/// 2286.
pub const T_MAX_S: f64 = 1e10;

/// Checks a run's time stamps: the row index and problem become a located error.
fn time_base(
    table: &Table,
    renames: &BTreeMap<String, String>,
) -> Result<(Vec<f64>, TimeBase), DataError> {
    let t = table.take("t", renames, Some((-T_MAX_S, T_MAX_S, "s")))?;
    match timebase::check_time(&t, &table.lines) {
        Ok(tb) => Ok((t, tb)),
        Err((_, Problem::TooShort)) => Err(err(&table.file, None, None, Problem::TooShort)),
        Err((k, p)) => Err(table.at(k, "t", renames, p)),
    }
}

/// Reads a crane run. Plausible ranges (a value outside is almost surely a wrong unit):
/// voltages within +-12 V (the amplifier's saturation), `x` in [-0.05, 0.555] m, `y` in
/// [-0.05, 0.675] m, `l` in [0.05, 1.0] m, `alpha` in (0, pi) rad, `beta` in [-pi/2, pi/2]
/// rad. Time must be uniform (within [`timebase::JITTER_TOLERANCE`]): a crane run is never
/// resampled.
pub fn crane_run(table: &Table, renames: &BTreeMap<String, String>) -> Result<CraneRun, DataError> {
    use core::f64::consts::{FRAC_PI_2, PI};
    let (t, tb) = time_base(table, renames)?;
    if let TimeBase::Irregular(why) = tb {
        let idx = table.find("t", renames);
        return Err(err(
            &table.file,
            Some(why.line),
            idx.map(|i| (table.header[i].as_str(), i + 1)),
            Problem::Timing(Timing::IrregularCrane {
                step_s: why.step_s,
                median_step_s: why.median_step_s,
                irregular_steps: why.irregular_steps,
            }),
        ));
    }
    let v = Some((-12.0 - 1e-9, 12.0 + 1e-9, "V"));
    Ok(CraneRun {
        t,
        u: [
            table.take("u_x", renames, v)?,
            table.take("u_y", renames, v)?,
            table.take("u_l", renames, v)?,
        ],
        x: table.take("x", renames, Some((-0.05, 0.555, "m")))?,
        y: table.take("y", renames, Some((-0.05, 0.675, "m")))?,
        l: table.take("l", renames, Some((0.05, 1.0, "m")))?,
        alpha: table.take("alpha", renames, Some((1e-9, PI - 1e-9, "rad")))?,
        beta: table.take("beta", renames, Some((-FRAC_PI_2, FRAC_PI_2, "rad")))?,
    })
}

/// The 99th percentile of the speed `|dx/dt|` of a run [unit/s] over steps of one refresh
/// of the position (one row, or the rows a held channel repeats its value over:
/// [`timebase::held_channel`], whose jumps would otherwise count as that many times faster).
/// The percentile, not the maximum: an encoder glitch moves two differences. `None` without
/// a finite difference.
pub fn p99_speed(t: &[f64], x: &[f64]) -> Option<f64> {
    let lag = timebase::held_channel(x).map_or(1, |(r, _)| r.max(1));
    let mut v: Vec<f64> = t
        .iter()
        .zip(t.iter().skip(lag))
        .zip(x.iter().zip(x.iter().skip(lag)))
        .map(|((t0, t1), (x0, x1))| ((x1 - x0) / (t1 - t0)).abs())
        .filter(|v| v.is_finite())
        .collect();
    if v.is_empty() {
        return None;
    }
    let k = ((v.len() - 1) as f64 * 0.99) as usize;
    let (_, p99, _) = v.select_nth_unstable_by(k, f64::total_cmp);
    Some(*p99)
}

/// What to look at when positions move implausibly fast: the unit keys of `dataset.toml`.
/// Crane runs have fixed units (metres, radians, seconds unless `time_unit`); a single-axis
/// run also has `position_unit` and `position_scale`.
fn unit_keys_hint(unit: PositionUnit, crane: bool) -> String {
    let time =
        "time stamps in seconds declared as milliseconds (`time_unit`) are 1000 times too fast";
    if crane {
        return format!("is `time_unit` in dataset.toml right? {time}");
    }
    let small = if unit.is_metre() {
        "millimetres"
    } else {
        "milliradians"
    };
    format!(
        "are they in another unit than position_unit = \"{}\"? for {small} set \
         position_scale = 0.001 in dataset.toml{}; {time}",
        unit.symbol(),
        if unit.is_metre() {
            ""
        } else {
            " (for degrees 0.017453292519943295)"
        }
    )
}

/// The 99th percentile of a run's speed between samples ([`p99_speed`]) must be within the
/// unit's [`PositionUnit::max_speed`]: beyond it the positions are almost surely in another
/// unit than declared (millimetres read as metres) or the time stamps are (seconds declared
/// as milliseconds), and every fitted inertia and friction would be off by that factor
/// without a word. The error names the unit keys to look at ([`unit_keys_hint`]).
fn check_speed(
    table: &Table,
    column: &str,
    t: &[f64],
    x: &[f64],
    unit: PositionUnit,
    crane: bool,
) -> Result<(), DataError> {
    let Some(p99) = p99_speed(t, x) else {
        return Ok(());
    };
    let limit = unit.max_speed();
    if p99 > limit {
        let u = unit.symbol();
        return Err(err(
            &table.file,
            None,
            None,
            Problem::BadValue(format!(
                "the positions `{column}` move at {p99:.3e} {u}/s (99th percentile of the \
                 speed between samples), beyond a plausible {limit:e} {u}/s: {}",
                unit_keys_hint(unit, crane)
            )),
        ));
    }
    Ok(())
}

/// The data set's fastest single-axis run, when its speed ([`p99_speed`]) is beyond the
/// [`PositionUnit::typical_speed`] of its unit (but within the plausible
/// [`PositionUnit::max_speed`], which is an error): a [`LoadNote::UnitSuspect`] on that run,
/// once per data set, naming the unit keys. The data still load: a motor shaft or a fast
/// linear motor can be that fast.
fn note_fast_positions(runs: &mut [Run]) {
    let fastest = runs
        .iter()
        .enumerate()
        .filter_map(|(i, r)| r.axis().map(|a| (i, a)))
        .filter_map(|(i, a)| p99_speed(&a.t, &a.x).map(|v| (i, v, a.position_unit)))
        .max_by(|a, b| a.1.total_cmp(&b.1));
    let Some((i, speed, unit)) = fastest else {
        return;
    };
    if speed <= unit.typical_speed() {
        return;
    }
    if let Samples::Axis(a) = &mut runs[i].samples {
        let u = unit.symbol();
        a.notes.push(LoadNote::UnitSuspect(format!(
            "the positions move at up to {speed:.3e} {u}/s (99th percentile of the speed \
             between samples, the fastest run), beyond the {} {u}/s typical of {}: {} \
             (a {} may be this fast: then ignore this note)",
            unit.typical_speed(),
            if unit.is_metre() {
                "a positioning axis"
            } else {
                "a joint or direct drive"
            },
            unit_keys_hint(unit, false),
            if unit.is_metre() {
                "linear motor"
            } else {
                "motor shaft"
            }
        )));
    }
}

/// Reads a single-axis run: `t`, `x` and either `force` (an effort: N or N m, gain 1) or `u`
/// in `ds.input_unit` with the run's gain; with a declared controller, its reference and
/// added-input columns. Irregular time stamps are resampled or refused, held channels noted
/// (`timebase`): a position seen fresh on every row ([`timebase::fresh_every_row`]), or given
/// on the rows `x_given` marks (an asynchronous log whose empty fields were filled by the
/// last value), is interpolated at the grid instants between the rows that gave it, and the
/// inputs averaged over each grid period; otherwise, and in a closed loop, every channel
/// takes its last row at or before each instant (zero-order hold).
pub fn axis_run(
    table: &Table,
    renames: &BTreeMap<String, String>,
    ds: &DatasetSpec,
    run: Option<&RunSpec>,
    x_given: Option<&[bool]>,
) -> Result<AxisRun, DataError> {
    let (t, tb) = time_base(table, renames)?;
    let position_unit = ds.position_unit;
    let (plo, phi) = position_unit.range();
    let xr = Some((plo, phi, position_unit.symbol()));
    let x = table.take("x", renames, xr)?;
    check_speed(table, "x", &t, &x, position_unit, false)?;
    let (u_name, input_unit, gain) = if table.find("force", renames).is_some() {
        let effort = position_unit.effort_unit();
        if let Some(iu) = ds.input_unit.filter(|iu| *iu != effort) {
            return Err(err(
                &table.file,
                None,
                None,
                Problem::BadValue(format!(
                    "a `force` column is an effort in `{}`, but dataset.toml declares \
                     input_unit = \"{}\": name the column `u`, or drop input_unit",
                    effort.symbol(),
                    iu.symbol()
                )),
            ));
        }
        ("force", effort, Gain::Known(1.0))
    } else if table.find("u", renames).is_some() {
        ("u", ds.input_unit(), ds.gain(run))
    } else {
        let mut e = table.missing("u", renames);
        if let Problem::MissingColumn(m) = &mut e.problem {
            m.wanted = format!("{} (or `force`)", m.wanted);
        }
        return Err(e);
    };
    let (ulo, uhi) = input_unit.range();
    let u = table.take(u_name, renames, Some((ulo, uhi, input_unit.symbol())))?;
    let force = match gain {
        Gain::Known(g) if g != 1.0 => {
            let mut f = Vec::with_capacity(u.len());
            for (k, &v) in u.iter().enumerate() {
                let y = g * v;
                if !y.is_finite() {
                    return Err(table.at(
                        k,
                        u_name,
                        renames,
                        Problem::NotFinite(format!("gain {g} * u {v} overflows")),
                    ));
                }
                f.push(y);
            }
            f
        }
        _ => u.clone(),
    };
    let closed_loop = match &ds.controller {
        None => None,
        Some(c) => {
            let ident = BTreeMap::new();
            let reference = table.take(&c.reference, &ident, xr)?;
            // a run without the added-input column had nothing added (EMPS: only the
            // validation run has pulses)
            let added_input = match &c.added_input {
                Some(name) if table.find(name, &ident).is_some() => {
                    table.take(name, &ident, Some((ulo, uhi, input_unit.symbol())))?
                }
                _ => vec![0.0; t.len()],
            };
            Some(LoopSignals {
                reference,
                added_input,
            })
        }
    };
    let mut notes = Vec::new();
    // each column's hold found once: the position's is also kept as `x_held`
    let x_hold = timebase::held_channel(&x);
    let x_held = x_hold.map_or(1, |(r, _)| r.max(1));
    for (name, hold) in [("x", x_hold), (u_name, timebase::held_channel(&u))] {
        if let Some((rows_per_refresh, repeated_share)) = hold {
            let idx = table.find(name, renames).unwrap_or(0);
            notes.push(LoadNote::HeldChannel {
                column: clip(&table.header[idx]),
                rows_per_refresh,
                repeated_share,
            });
        }
    }
    let mut out = AxisRun {
        source_t: t.clone(),
        t,
        x,
        x_refresh: 0,
        x_held,
        force,
        u,
        position_unit,
        input_unit,
        gain,
        closed_loop,
        notes: Vec::new(),
    };
    if let TimeBase::Irregular(why) = tb {
        let (resampled, note) = resample(out, why, x_given);
        out = resampled;
        notes.insert(0, note);
    }
    out.notes = notes;
    Ok(out)
}

/// Resamples a run read at irregular instants onto the uniform grid of `why.grid_step_s`, and
/// the note that says how. A position seen fresh on every row, or given on the rows `x_given`
/// marks (an asynchronous log's empty fields, filled by the last value before), is read at
/// the grid instants by linear interpolation between the rows that gave it, and the inputs
/// are averaged over each grid period (no lag between them, and no stamp jitter in the
/// position: a 15 ms jittered log's zero-order hold made the inertia 60 times low; an 85 ms
/// delay read as 70 ms on a log with x on every 4th row). The run's `x_refresh` is then the
/// grid samples per given position (what derivative windows must span: without it a 5 kHz
/// log's dead band went from 0.43 % to 6.2 % held-out error). Any other position (repeated
/// between refreshes, or one whose holds cannot be told from single counts: interpolating its
/// stale rows would pass them for motion), and a closed loop's signals, keep the rows'
/// zero-order hold (a held channel is rebuilt from its fresh rows later, and a loop's
/// reference and input belong to one row).
fn resample(out: AxisRun, why: Irregularity, x_given: Option<&[bool]>) -> (AxisRun, LoadNote) {
    let h = why.grid_step_s;
    let (grid, rows) = timebase::zoh_rows(&out.t, h);
    let rows_in = out.t.len();
    let exact = out.closed_loop.is_none()
        && match x_given {
            Some(g) => g.len() == out.t.len() && g.iter().filter(|&&g| g).count() >= 2,
            None => timebase::fresh_every_row(&out.x),
        };
    let run = if exact {
        // the rows that gave the position (all of them when none was filled), and the grid
        // samples per given one
        let (tg, xg): (Vec<f64>, Vec<f64>) = match x_given {
            Some(g) => out
                .t
                .iter()
                .zip(&out.x)
                .zip(g)
                .filter(|(_, &g)| g)
                .map(|((&t, &x), _)| (t, x))
                .unzip(),
            None => (out.t.clone(), out.x.clone()),
        };
        let x_refresh = (grid.len() as f64 / tg.len().max(1) as f64).round() as usize;
        AxisRun {
            source_t: grid.clone(),
            x: timebase::interpolate(&tg, &xg, &grid),
            x_refresh,
            force: timebase::hold_mean(&out.t, &out.force, &grid, h),
            u: timebase::hold_mean(&out.t, &out.u, &grid, h),
            t: grid,
            ..out
        }
    } else {
        AxisRun {
            source_t: timebase::pick(&out.t, &rows),
            t: grid,
            x: timebase::pick(&out.x, &rows),
            force: timebase::pick(&out.force, &rows),
            u: timebase::pick(&out.u, &rows),
            closed_loop: out.closed_loop.map(|c| LoopSignals {
                reference: timebase::pick(&c.reference, &rows),
                added_input: timebase::pick(&c.added_input, &rows),
            }),
            ..out
        }
    };
    let note = LoadNote::Resampled {
        why,
        rows_in,
        rows_out: rows.len(),
        step_s: h,
        exact,
    };
    (run, note)
}

impl Table {
    /// `true` if the table has the crane columns (`u_x` present, after renames).
    pub fn is_crane(&self, renames: &BTreeMap<String, String>) -> bool {
        self.find("u_x", renames).is_some()
    }

    /// Reads a crane run ([`crane_run`]).
    pub fn crane_run(&self, renames: &BTreeMap<String, String>) -> Result<CraneRun, DataError> {
        crane_run(self, renames)
    }
}

/// Loads one run described by `spec` relative to `dir`, with the data set's defaults.
pub fn load_run(dir: &Path, ds: &DatasetSpec, spec: &RunSpec) -> Result<Run, DataError> {
    let path = dir.join(&spec.file);
    let mut table = read_table(&path)?;
    let mut renames = ds.columns.clone();
    renames.extend(spec.columns.clone());
    // units of the recorded columns, converted before any check (every rule and message is
    // then in seconds and in `position_unit`)
    table.scale("t", &renames, ds.time_unit.seconds());
    let (samples, payload) = if table.is_crane(&renames) {
        let payload = spec.payload_kg.or(ds.payload_kg).ok_or_else(|| {
            err(
                &path,
                None,
                None,
                Problem::BadValue(
                    "a crane run needs `payload_kg` (top level of dataset.toml or its [[runs]] \
                     entry; 0 = unloaded)"
                        .into(),
                ),
            )
        })?;
        let run = crane_run(&table, &renames)?;
        if !ds.time_unit.is_second() {
            // the ranges catch positions in another unit; time stamps in seconds declared
            // in a smaller unit show as speeds 1000 times too high
            for (name, q) in [("x", &run.x), ("y", &run.y), ("l", &run.l)] {
                check_speed(&table, name, &run.t, q, PositionUnit::Metre, true)?;
            }
        }
        (Samples::Crane(run), payload)
    } else {
        if let Some(k) = ds.position_scale {
            table.scale("x", &renames, k);
            if let Some(c) = &ds.controller {
                table.scale(&c.reference, &BTreeMap::new(), k);
            }
        }
        // an asynchronous log (empty fields, rows at one stamp): one complete row per instant
        let (mut filled, mut given) = (None, Vec::new());
        if let Some(t) = table.find("t", &renames) {
            let ident = BTreeMap::new();
            let mut used: Vec<usize> = ["x", "u", "force"]
                .iter()
                .filter_map(|n| table.find(n, &renames))
                .collect();
            if let Some(c) = &ds.controller {
                used.extend(table.find(&c.reference, &ident));
                if let Some(a) = &c.added_input {
                    used.extend(table.find(a, &ident));
                }
            }
            (table, filled, given) = asynchronous::fill_blanks(&table, t, &used)?;
        }
        // the rows that gave the position, when some left it empty
        let x_col = table.find("x", &renames);
        let x_given = given
            .iter()
            .find(|(c, g)| Some(*c) == x_col && g.iter().any(|&g| !g))
            .map(|(_, g)| g.as_slice());
        let mut axis = axis_run(&table, &renames, ds, Some(spec), x_given)?;
        if let Some(f) = filled {
            axis.notes.insert(0, LoadNote::Filled(f));
        }
        (
            Samples::Axis(axis),
            spec.payload_kg.or(ds.payload_kg).unwrap_or(0.0),
        )
    };
    Ok(Run {
        name: spec.file.clone(),
        kind: spec.kind,
        payload_kg: payload,
        samples,
    })
}

/// Loads a data set directory: `dataset.toml`, then every run it lists (or every `*.csv` in
/// file-name order, kind `other`, when it lists none). The first bad file stops the load with
/// an error naming file, line and column; a listed run's file that is missing or is not a
/// regular file (a directory, a FIFO) is named at the line of its `file` key in
/// `dataset.toml`, with the path looked for, before any run is read; an unlisted `*.csv`
/// that is not a regular file is named by its path, saying it was taken as a run because no
/// `[[runs]]` are listed.
pub fn load_dataset(dir: &Path) -> Result<Dataset, DataError> {
    let spec_path = dir.join(DATASET_FILE);
    let text = crate::input::read_text(&spec_path).map_err(|e| {
        let why = if e.kind() == std::io::ErrorKind::NotFound && dir.is_dir() {
            // a folder of logs without a description: say what to write
            format!(
                "{e}; a data set is a directory with a `{DATASET_FILE}` that says what the \
                 columns are (`position_unit`, `input_unit`, `[columns]`, `[[runs]]`: see \
                 ident/DATA_FORMAT.md); an empty one makes every *.csv a run in m and V"
            )
        } else {
            e.to_string()
        };
        err(&spec_path, None, None, Problem::Io(why))
    })?;
    let mut spec = parse_spec(&spec_path, &text)?;
    // a listed run's file that is missing, or is no regular file (a FIFO would wait
    // forever): named at the line of its `file` key in dataset.toml, with the path looked for
    for (i, r) in spec.runs.iter().enumerate() {
        let path = dir.join(&r.file);
        if let Err(e) = crate::input::check_regular(&path) {
            let shown = dir.join(clip(&r.file));
            let why = format!(
                "run file `{}` (the `file` of [[runs]] entry {}): {e}",
                shown.display(),
                i + 1
            );
            let line = spec::run_file_line(&text, i);
            return Err(err(&spec_path, line, None, Problem::Io(why)));
        }
    }
    if spec.runs.is_empty() {
        let mut files: Vec<String> = std::fs::read_dir(dir)
            .map_err(|e| err(dir, None, None, Problem::Io(e.to_string())))?
            .filter_map(|e| e.ok())
            .filter_map(|e| e.file_name().into_string().ok())
            .filter(|n| n.ends_with(".csv"))
            .collect();
        files.sort();
        // a `*.csv` that is no regular file (a directory named `x.csv`, a FIFO): refused as
        // a listed one is, saying why it was taken as a run (no `[[runs]]` to point at)
        for f in &files {
            let path = dir.join(f);
            if let Err(e) = crate::input::check_regular(&path) {
                let why = format!(
                    "{e}; it was taken as a run because `{DATASET_FILE}` lists no [[runs]] \
                     (then every *.csv of the directory is one): list the runs, or rename it"
                );
                return Err(err(&path, None, None, Problem::Io(why)));
            }
        }
        spec.runs = files
            .into_iter()
            .map(|file| RunSpec {
                file,
                ..RunSpec::default()
            })
            .collect();
    }
    let mut runs = spec
        .runs
        .iter()
        .map(|r| load_run(dir, &spec, r))
        .collect::<Result<Vec<_>, _>>()?;
    note_fast_positions(&mut runs);
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

//! Time stamps and refresh of logged channels: the checks every run goes through, and the
//! zero-order-hold resampling of irregular single-axis logs.
//!
//! The rules (thresholds relative to the run's own median step, so they hold for any rig and
//! any rate; `DATA_FORMAT.md` gives the reasons):
//! - time must strictly increase ([`Problem::TimeNotIncreasing`]);
//! - every step within `±`[`JITTER_TOLERANCE`] of the median step: the run is uniform and kept
//!   as recorded;
//! - otherwise the stamps are irregular. A crane run is refused. A single-axis run is
//!   resampled on the grid `t0 + k h` (`h` the mean of the ordinary steps, those up to 1.5
//!   median steps) by zero-order hold of the last
//!   row at or before each grid instant, unless a step exceeds [`MAX_GAP_STEPS`] median
//!   steps (rows lost: holding would invent a rest), which refuses the run;
//! - a channel that changes only every few rows while it moves (never on two consecutive rows,
//!   and not by single quantisation steps) is *held*: refreshed slower than the log. It is
//!   noted ([`LoadNote::HeldChannel`]); its values already are the zero-order hold of its
//!   fresh samples.

use super::error::{Problem, Timing};
use std::fmt;

// the thresholds a refused run's message quotes live in `limits` (the error messages read
// them there, so `error` need not import this module, which imports `error`)
pub use super::limits::{JITTER_TOLERANCE, MAX_GAP_STEPS, RATE_RANGE_HZ};

/// A channel must change at least this often before it can be called held.
pub const HELD_MIN_CHANGES: usize = 20;

/// Changes more than this many rows apart are rest, not refresh, and are not counted.
pub const HELD_MAX_REFRESH_ROWS: usize = 16;

/// Share of consecutive-row changes above which a channel is refreshed every row (10 %).
pub const HELD_MAX_CONSECUTIVE_SHARE: f64 = 0.10;

/// Share of a channel's gaps between changes that must be whole multiples of the shortest
/// for the gaps to be a refresh lattice ([`held_channel`]); the rest of the gaps, at least
/// as large a share, must be longer multiples. A held channel's gaps are all multiples of its
/// refresh (100 %) and a quantised signal's take every value its speed sets (about one in
/// the shortest gap on the lattice): any share between separates them.
pub const HELD_LATTICE_SHARE: f64 = 0.9;

/// What was irregular about a run's time stamps.
#[derive(Clone, Debug, PartialEq)]
pub struct Irregularity {
    /// 1-based file line of the row ending the most deviating step.
    pub line: usize,
    /// That step [s].
    pub step_s: f64,
    /// Median step of the run [s].
    pub median_step_s: f64,
    /// Step of the resampling grid: the mean of the steps not longer than 1.5 median steps
    /// (the ordinary steps; with alternating jitter the median is one of the two values) [s].
    pub grid_step_s: f64,
    /// Number of steps outside the tolerance.
    pub irregular_steps: usize,
}

/// Something the loader noticed or did, recorded on the run.
#[derive(Clone, Debug, PartialEq)]
pub enum LoadNote {
    /// Irregular time stamps: resampled by zero-order hold on a uniform grid.
    Resampled {
        /// Why.
        why: Irregularity,
        /// Rows in the file.
        rows_in: usize,
        /// Samples on the grid.
        rows_out: usize,
        /// Grid step [s] ([`Irregularity::grid_step_s`]).
        step_s: f64,
        /// The position was interpolated at the grid instants and the inputs averaged over
        /// each grid period ([`interpolate`], [`hold_mean`]); `false`: every channel took
        /// the last row at or before each instant (a held position, a closed loop).
        exact: bool,
    },
    /// A channel refreshed only every few rows (repeated values while it moves).
    HeldChannel {
        /// Header name of the column (clipped).
        column: String,
        /// Median number of rows between refreshes while it moves.
        rows_per_refresh: usize,
        /// Share of rows repeating the previous value.
        repeated_share: f64,
    },
    /// An asynchronous log: rows at one stamp merged, empty fields held
    /// ([`super::asynchronous`]).
    Filled(super::asynchronous::Filled),
    /// A derived quantity beyond what is typical of the axis (positions that move faster
    /// than [`super::PositionUnit::typical_speed`]): probably a wrong unit key; the message
    /// names the keys of `dataset.toml` to look at.
    UnitSuspect(String),
}

impl fmt::Display for LoadNote {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LoadNote::Resampled {
                why,
                rows_in,
                rows_out,
                step_s,
                exact,
            } => write!(
                f,
                "irregular time stamps ({} steps outside +-{:.0} % of the median step {} s, \
                 worst {} s at line {}): {rows_in} rows resampled to {rows_out} samples every \
                 {step_s} s {}",
                why.irregular_steps,
                JITTER_TOLERANCE * 100.0,
                why.median_step_s,
                why.step_s,
                why.line,
                if *exact {
                    "(the position interpolated linearly between its rows, the inputs averaged over each sample period)"
                } else {
                    "by zero-order hold"
                }
            ),
            LoadNote::HeldChannel {
                column,
                rows_per_refresh,
                repeated_share,
            } => write!(
                f,
                "column `{column}` is refreshed only every {rows_per_refresh} rows \
                 ({:.0} % repeated values): its effective sampling period is \
                 {rows_per_refresh} steps",
                repeated_share * 100.0
            ),
            LoadNote::Filled(what) => write!(f, "{what}"),
            LoadNote::UnitSuspect(what) => write!(f, "warning: {what}"),
        }
    }
}

/// The time base of a run after the checks.
#[derive(Clone, Debug, PartialEq)]
pub enum TimeBase {
    /// Every step within the tolerance: keep the rows.
    Uniform,
    /// Irregular but resamplable: why, and the grid step.
    Irregular(Irregularity),
}

/// Median of a non-empty slice (upper median).
fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    let mid = s.len() / 2;
    let (_, m, _) = s.select_nth_unstable_by(mid, f64::total_cmp);
    *m
}

/// Checks time stamps `t` (rows at file lines `lines`): strictly increasing, then uniform or
/// irregular. `Err((row, problem))` names the offending row (0-based).
pub fn check_time(t: &[f64], lines: &[usize]) -> Result<TimeBase, (usize, Problem)> {
    if t.len() < 2 {
        return Err((0, Problem::TooShort));
    }
    for k in 1..t.len() {
        if t[k] <= t[k - 1] {
            return Err((
                k,
                Problem::TimeNotIncreasing {
                    prev: t[k - 1],
                    this: t[k],
                },
            ));
        }
    }
    let steps: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    let h = median(&steps);
    let rate = 1.0 / h;
    if !(rate > RATE_RANGE_HZ.0 && rate < RATE_RANGE_HZ.1) {
        return Err((1, Problem::Timing(Timing::Rate { median_step_s: h })));
    }
    let mut worst = 0usize;
    let mut worst_dev = 0.0;
    let mut irregular = 0usize;
    for (k, &s) in steps.iter().enumerate() {
        let dev = (s / h - 1.0).abs();
        if dev > JITTER_TOLERANCE {
            irregular += 1;
        }
        if dev > worst_dev {
            worst_dev = dev;
            worst = k + 1;
        }
    }
    if irregular == 0 {
        return Ok(TimeBase::Uniform);
    }
    let line = lines.get(worst).copied().unwrap_or(worst + 1);
    let (sum, count) = steps
        .iter()
        .filter(|&&s| s <= 1.5 * h)
        .fold((0.0, 0usize), |(a, n), &s| (a + s, n + 1));
    let why = Irregularity {
        line,
        step_s: steps[worst - 1],
        median_step_s: h,
        grid_step_s: sum / count.max(1) as f64,
        irregular_steps: irregular,
    };
    if let Some(k) = steps.iter().position(|&s| s > MAX_GAP_STEPS * h) {
        return Err((
            k + 1,
            Problem::Timing(Timing::Gap {
                step_s: steps[k],
                median_step_s: h,
            }),
        ));
    }
    Ok(TimeBase::Irregular(why))
}

/// The uniform grid `t0 + k h` covering `[t0, t_end]` and, for every grid instant, the row
/// holding the last value at or before it (zero-order hold). Stamps within `1e-9 h` of a grid
/// instant count as on it.
pub fn zoh_rows(t: &[f64], h: f64) -> (Vec<f64>, Vec<usize>) {
    let t0 = t[0];
    let span = t[t.len() - 1] - t0;
    let n = (span / h + 1e-9).floor() as usize + 1;
    let mut grid = Vec::with_capacity(n);
    let mut rows = Vec::with_capacity(n);
    let mut j = 0;
    for k in 0..n {
        let g = t0 + k as f64 * h;
        while j + 1 < t.len() && t[j + 1] <= g + 1e-9 * h {
            j += 1;
        }
        grid.push(g);
        rows.push(j);
    }
    (grid, rows)
}

/// A sampled signal `(t, c)` read at the `grid` instants by linear interpolation between the
/// rows around each (held beyond the last row): for a position, whose samples were taken at
/// the stamps of their rows. The zero-order hold of [`zoh_rows`] would read it up to a grid
/// step late, a jitter that the derivative estimates take for motion (`v` times up to the
/// step: at 0.05 m/s and a 15 ms step 0.75 mm, many encoder counts). `t` strictly
/// increasing, `grid` non-decreasing from `t[0]`. Work O(rows + grid).
pub fn interpolate(t: &[f64], c: &[f64], grid: &[f64]) -> Vec<f64> {
    at_grid(t, c, grid, |j, n, g| {
        if j + 1 >= n || g <= t[j] {
            return c[j];
        }
        let f = (g - t[j]) / (t[j + 1] - t[j]);
        c[j] + (c[j + 1] - c[j]) * f
    })
}

/// One value per `grid` instant `g` from `read(j, n, g)`, `j` the last of the `n` usable rows
/// at or before `g` (the first row before `t[0]`): the row cursor of [`interpolate`] and
/// [`hold_mean`], which moves forward only (`grid` non-decreasing), so the work is
/// O(rows + grid). NaN for every instant of an empty signal.
fn at_grid(
    t: &[f64],
    c: &[f64],
    grid: &[f64],
    mut read: impl FnMut(usize, usize, f64) -> f64,
) -> Vec<f64> {
    let n = t.len().min(c.len());
    if n == 0 {
        return vec![f64::NAN; grid.len()];
    }
    let mut j = 0;
    grid.iter()
        .map(|&g| {
            while j + 1 < n && t[j + 1] <= g {
                j += 1;
            }
            read(j, n, g)
        })
        .collect()
}

/// A held signal `(t, c)` (each row's value in force from its stamp until the next row's)
/// averaged over each grid period `[g, g + h)`: the input a simulation holding one value per
/// period must apply to deliver the same impulse. Holding the last row's value instead
/// applies each change up to a step late, a lag that a fitted delay or inertia would take
/// up. Beyond the last row its value is held. `t` strictly increasing, `grid` increasing from
/// `t[0]` by `h > 0`; NaN for an empty signal. Work O(rows + grid).
pub fn hold_mean(t: &[f64], c: &[f64], grid: &[f64], h: f64) -> Vec<f64> {
    at_grid(t, c, grid, |j, n, g| {
        let end = g + h;
        // the row in force at g, then every row starting inside the period
        let (mut area, mut from, mut k) = (0.0, g, j);
        while k + 1 < n && t[k + 1] < end {
            area += c[k] * (t[k + 1] - from);
            from = t[k + 1];
            k += 1;
        }
        area += c[k] * (end - from);
        area / h
    })
}

/// Picks `rows` of a column.
pub fn pick(c: &[f64], rows: &[usize]) -> Vec<f64> {
    rows.iter().map(|&j| c[j]).collect()
}

/// Whether a channel is seen fresh on every row: of its changes at most
/// [`HELD_MAX_REFRESH_ROWS`] rows apart (at least [`HELD_MIN_CHANGES`] of them), more than
/// [`HELD_MAX_CONSECUTIVE_SHARE`] come on consecutive rows, which a channel refreshed every
/// few rows never does. A channel that changes less often than its rows (a fine encoder's
/// slow motion, or a hold [`held_channel`] cannot tell from one: single counts) is not.
pub fn fresh_every_row(c: &[f64]) -> bool {
    let (_, gaps) = changes_and_gaps(c);
    gaps.len() >= HELD_MIN_CHANGES && consecutive(&gaps)
}

/// The rows where a channel changes, and the gaps between consecutive changes [rows] that are
/// refreshes, not rests (at most [`HELD_MAX_REFRESH_ROWS`]).
fn changes_and_gaps(c: &[f64]) -> (Vec<usize>, Vec<usize>) {
    let changes: Vec<usize> = (1..c.len()).filter(|&k| c[k] != c[k - 1]).collect();
    let gaps = changes
        .windows(2)
        .map(|w| w[1] - w[0])
        .filter(|&g| g <= HELD_MAX_REFRESH_ROWS)
        .collect();
    (changes, gaps)
}

/// Whether more than [`HELD_MAX_CONSECUTIVE_SHARE`] of the `gaps` are of one row: a channel
/// fresh on every row (at least at times).
fn consecutive(gaps: &[usize]) -> bool {
    let ones = gaps.iter().filter(|&&g| g == 1).count();
    ones as f64 > HELD_MAX_CONSECUTIVE_SHARE * gaps.len() as f64
}

/// Whether a channel is held (refreshed every few rows): `Some((rows_per_refresh,
/// repeated_share))`. A channel whose changes are mostly single quantisation steps (within
/// 1.5 times its smallest change) is a slowly moving quantised signal, not a held one.
pub fn held_channel(c: &[f64]) -> Option<(usize, f64)> {
    if c.len() < 3 {
        return None;
    }
    let (changes, mut gaps) = changes_and_gaps(c);
    if changes.len() < HELD_MIN_CHANGES || gaps.len() < HELD_MIN_CHANGES || consecutive(&gaps) {
        return None;
    }
    let repeated = (c.len() - 1 - changes.len()) as f64 / (c.len() - 1) as f64;
    // a lattice of gaps is a hold whatever the size of the steps: a coarse encoder's held
    // position moves one count per refresh at low speed (stranger seed 11's s051: 5 kHz
    // rows, x every 5, 0.26 mrad counts; 63-70 % single counts, every gap 5, 10, 15 ... rows)
    if let Some(g) = lattice(&gaps) {
        return Some((g, repeated));
    }
    let deltas: Vec<f64> = changes.iter().map(|&k| (c[k] - c[k - 1]).abs()).collect();
    let q = deltas.iter().copied().fold(f64::INFINITY, f64::min);
    let single = deltas.iter().filter(|&&d| d <= 1.5 * q).count();
    if single * 2 > deltas.len() {
        return None;
    }
    let mid = gaps.len() / 2;
    let (_, m, _) = gaps.select_nth_unstable(mid);
    Some((*m, repeated))
}

/// The refresh [rows] of a channel whose `gaps` between changes (rests excluded) sit on a
/// lattice: the shortest is at least 2 rows, at least [`HELD_LATTICE_SHARE`] of them are
/// whole multiples of it, and at least `1 - HELD_LATTICE_SHARE` of them longer multiples (the
/// speed varied and the gaps stayed on the lattice, which a quantised signal's cannot: a
/// creep at one count every 4 rows is no hold). `None` otherwise.
fn lattice(gaps: &[usize]) -> Option<usize> {
    let g0 = *gaps.iter().min()?;
    if g0 < 2 {
        return None;
    }
    let n = gaps.len() as f64;
    let on = gaps.iter().filter(|&&g| g % g0 == 0).count() as f64;
    let longer = gaps.iter().filter(|&&g| g % g0 == 0 && g > g0).count() as f64;
    (on >= HELD_LATTICE_SHARE * n && longer >= (1.0 - HELD_LATTICE_SHARE) * n).then_some(g0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lines(n: usize) -> Vec<usize> {
        (2..n + 2).collect()
    }

    #[test]
    fn uniform_jittered_gapped_and_backwards_time() {
        let t: Vec<f64> = (0..100).map(|k| k as f64 * 0.01).collect();
        assert_eq!(check_time(&t, &lines(100)), Ok(TimeBase::Uniform));
        // 4 % jitter: still uniform
        let tj: Vec<f64> = (0..100)
            .map(|k| k as f64 * 0.01 + if k % 2 == 1 { 0.0002 } else { 0.0 })
            .collect();
        assert_eq!(check_time(&tj, &lines(100)), Ok(TimeBase::Uniform));
        // 30 % jitter: irregular, the worst step named by its line
        let mut ti = t.clone();
        ti[50] += 0.003;
        match check_time(&ti, &lines(100)) {
            Ok(TimeBase::Irregular(i)) => {
                assert_eq!(i.irregular_steps, 2);
                assert!((i.median_step_s - 0.01).abs() < 1e-12);
                assert!(i.line == 52 || i.line == 53, "{i:?}");
            }
            other => panic!("{other:?}"),
        }
        // half the rows dropped after the middle: steps of 2 h are irregular (resampled),
        // a gap of 10 h refuses
        let mut tg: Vec<f64> = (0..50).map(|k| k as f64 * 0.01).collect();
        tg.extend((0..25).map(|k| 0.5 + k as f64 * 0.02));
        assert!(matches!(
            check_time(&tg, &lines(75)),
            Ok(TimeBase::Irregular(_))
        ));
        let mut tgap = t.clone();
        for v in tgap.iter_mut().skip(60) {
            *v += 0.1;
        }
        match check_time(&tgap, &lines(100)) {
            Err((60, Problem::Timing(m @ Timing::Gap { .. }))) => {
                assert!(m.to_string().contains("rows missing"), "{m}")
            }
            other => panic!("{other:?}"),
        }
        let mut tb = t.clone();
        tb[30] = tb[29];
        assert!(matches!(
            check_time(&tb, &lines(100)),
            Err((30, Problem::TimeNotIncreasing { .. }))
        ));
        assert!(matches!(
            check_time(&[1.0], &[2]),
            Err((0, Problem::TooShort))
        ));
    }

    #[test]
    fn zero_order_hold_takes_the_last_row_at_or_before() {
        let t = [0.0, 0.1, 0.25, 0.3, 0.41];
        let (g, r) = zoh_rows(&t, 0.1);
        assert_eq!(g.len(), 5);
        assert_eq!(r, vec![0, 1, 1, 3, 3]);
        assert!((g[4] - 0.4).abs() < 1e-12);
    }

    #[test]
    fn a_channel_is_fresh_on_every_row_only_if_it_changes_on_consecutive_rows() {
        let every: Vec<f64> = (0..300).map(|k| (k as f64 * 0.05).sin()).collect();
        assert!(fresh_every_row(&every));
        // refreshed every 3 rows, by single counts or not
        let held: Vec<f64> = (0..300).map(|k| (3 * (k / 3)) as f64 * 1e-3).collect();
        assert!(!fresh_every_row(&held));
        // a slow motion of single counts every 4 rows, and a rest
        let slow: Vec<f64> = (0..300).map(|k| (k / 4) as f64 * 1e-3).collect();
        assert!(!fresh_every_row(&slow));
        assert!(!fresh_every_row(&[0.0; 50]));
    }

    #[test]
    fn positions_are_interpolated_and_inputs_averaged_over_the_period() {
        let t = [0.0, 0.12, 0.19, 0.33];
        // a ramp is read exactly at the grid instants, held beyond the last row
        let x: Vec<f64> = t.iter().map(|s| 2.0 * s).collect();
        let g = [0.0, 0.1, 0.2, 0.3, 0.4];
        let xi = interpolate(&t, &x, &g);
        for (a, b) in xi.iter().zip([0.0, 0.2, 0.4, 0.6, 0.66]) {
            assert!((a - b).abs() < 1e-12, "{xi:?}");
        }
        // a held input: 1 from 0, 3 from 0.12, 5 from 0.19, 7 from 0.33
        let u = [1.0, 3.0, 5.0, 7.0];
        let um = hold_mean(&t, &u, &g, 0.1);
        let want = [
            1.0,
            (0.02 * 1.0 + 0.07 * 3.0 + 0.01 * 5.0) / 0.1,
            5.0,
            (0.03 * 5.0 + 0.07 * 7.0) / 0.1,
            7.0,
        ];
        for (a, b) in um.iter().zip(want) {
            assert!((a - b).abs() < 1e-12, "{um:?}");
        }
        // the impulse over the record is kept
        let total: f64 = um[..3].iter().sum::<f64>() * 0.1;
        assert!((total - (0.12 * 1.0 + 0.07 * 3.0 + 0.11 * 5.0)).abs() < 1e-12);
    }

    #[test]
    fn held_channels_and_quantised_rest_are_told_apart() {
        // a sine refreshed every 3 rows
        let fresh: Vec<f64> = (0..300).map(|k| (k as f64 * 0.05).sin()).collect();
        let held: Vec<f64> = (0..300).map(|k| fresh[k - k % 3]).collect();
        let (p, share) = held_channel(&held).expect("held");
        assert_eq!(p, 3);
        assert!((share - 2.0 / 3.0).abs() < 0.01, "{share}");
        assert_eq!(held_channel(&fresh), None);
        // a quantised slow creep (one count every 4 rows) is not held
        let creep: Vec<f64> = (0..300).map(|k| (k / 4) as f64 * 5.2e-6).collect();
        assert_eq!(held_channel(&creep), None);
        // a coarse encoder held every 5 rows, mostly one count per refresh at a varying
        // speed: the gaps are 5, 10, 15 rows, a lattice, and it is held
        let counts = |t: usize| (30.0 * (t as f64 * 0.01).sin()).round();
        let coarse: Vec<f64> = (0..1200).map(|k| counts(k - k % 5)).collect();
        assert_eq!(held_channel(&coarse).map(|h| h.0), Some(5));
        // the same signal fresh on every row is a slowly moving quantised one (gaps of 3 to
        // 14 rows, every step one count), not held
        let creep2: Vec<f64> = (0..1200).map(counts).collect();
        assert_eq!(held_channel(&creep2), None);
        // at rest, then moving every row
        let mut rest = vec![0.0; 200];
        rest.extend((0..100).map(|k| k as f64 * 0.37));
        assert_eq!(held_channel(&rest), None);
    }
}

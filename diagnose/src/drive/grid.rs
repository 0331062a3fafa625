//! One-parameter searches of the grid-searched causes (dead band, saturation, load share,
//! Stribeck velocity, delay): the best point of a grid by the fitting runs' error (their
//! simulated NMAE on open-loop data; the closed-loop path, `axis/input.rs`, searches its delay
//! with the same grid and [`integer`] by the fitting squared error), refined between its
//! neighbours, and whether the result sits at the grid's edge.
//!
//! A value at the edge of what was tried is no finding: the best value may lie beyond it
//! (issue 20: a 0.1 s delay at 200 Hz was reported as the grid's 8 samples). The callers name
//! such a cause only as "not named", with the edge in the note.
//!
//! Work: `grid.len()` evaluations plus, for a continuous parameter, `steps` golden-section
//! evaluations, for an integer one about `2 log_1.5(gap)` (ternary search over the gap
//! between the best point's neighbours). Every evaluation is one fit and one simulation of
//! the fitting runs; the caller's `eval` returns `None` when the fit fails.

use std::collections::BTreeMap;

/// Largest input delay tried [samples], at least (see [`MAX_DELAY_S`]).
pub const MAX_DELAY: usize = 8;
/// Largest input delay tried [s], at least (USB, CAN and ROS rigs have 20-200 ms); the
/// grid is [`delay_grid`].
pub const MAX_DELAY_S: f64 = 0.25;

/// The golden section's shrink factor per step, `(sqrt 5 - 1) / 2` (the f64 nearest it,
/// bit for bit what `0.5 * (5f64.sqrt() - 1.0)` gives), for every golden-section search here
/// and in [`super::refine`].
pub const GOLDEN: f64 = 0.618_033_988_749_894_9;

/// The delays tried [samples]: 1, 2, 3, 4, then steps of about `sqrt 2` up to the larger of
/// [`MAX_DELAY_S`] and [`MAX_DELAY`] samples, at most a quarter of the shortest fitting run
/// (a longer delay leaves too little of a run to fit). The best point is refined to the
/// sample between its neighbours ([`integer`]).
pub fn delay_grid(dt: f64, shortest: usize) -> Vec<usize> {
    let by_time = if dt > 0.0 && dt.is_finite() {
        (MAX_DELAY_S / dt).ceil().min(1e6) as usize
    } else {
        0
    };
    let top = by_time.max(MAX_DELAY).min(shortest / 4);
    let mut g: Vec<usize> = Vec::new();
    let mut d = 1usize;
    while d < top {
        g.push(d);
        d = ((d as f64 * std::f64::consts::SQRT_2).round() as usize).max(d + 1);
    }
    if top >= 1 {
        g.push(top);
    }
    g
}

/// Points from `lo` to `hi` [any unit], both included, geometric, neighbours at most a factor
/// `ratio` apart (the fewest points that do it); empty unless `0 < lo <= hi` and `ratio > 1`.
pub fn geometric(lo: f64, hi: f64, ratio: f64) -> Vec<f64> {
    if !(lo > 0.0 && hi >= lo && hi.is_finite() && ratio > 1.0) {
        return Vec::new();
    }
    let n = ((hi / lo).ln() / ratio.ln()).ceil().clamp(0.0, 1e4) as usize;
    if n == 0 {
        return vec![lo];
    }
    let r = (hi / lo).powf(1.0 / n as f64);
    let mut g: Vec<f64> = (0..n).map(|k| lo * r.powi(k as i32)).collect();
    g.push(hi);
    g
}

/// The best point found.
#[derive(Clone, Debug)]
pub struct Best<P, T> {
    /// Index of the best grid point before refinement.
    pub k: usize,
    /// The parameter value.
    pub at: P,
    /// What `eval` returned with the error (the fitted model).
    pub value: T,
    /// The error at `at` (lower is better).
    pub err: f64,
}

impl<P: PartialEq + Copy, T> Best<P, T> {
    /// Whether the best value is the first or the last grid point (`lower`: the first one
    /// counts as an edge too).
    pub fn at_edge(&self, grid: &[P], lower: bool) -> bool {
        grid.last() == Some(&self.at) || (lower && grid.first() == Some(&self.at))
    }
}

fn keep<P, T>(best: &mut Option<Best<P, T>>, k: usize, at: P, r: Option<(T, f64)>) -> f64 {
    match r {
        Some((value, err)) if err.is_finite() => {
            if best.as_ref().is_none_or(|b| err < b.err) {
                *best = Some(Best { k, at, value, err });
            }
            err
        }
        _ => f64::INFINITY,
    }
}

/// The best grid point of an ascending `grid`, then `steps` golden-section steps between its
/// neighbours (the unimodal case converges by a factor 0.618 per step).
pub fn continuous<T>(
    grid: &[f64],
    steps: usize,
    mut eval: impl FnMut(f64) -> Option<(T, f64)>,
) -> Option<Best<f64, T>> {
    let mut best = None;
    for (k, &g) in grid.iter().enumerate() {
        let r = eval(g);
        keep(&mut best, k, g, r);
    }
    let k = best.as_ref()?.k;
    let (a, b) = (grid[k.saturating_sub(1)], grid[(k + 1).min(grid.len() - 1)]);
    golden(&mut best, k, (a, b), steps, &mut eval);
    best
}

/// `steps` golden-section evaluations over `[a, b]` (nothing when `b <= a` or `steps < 2`),
/// each kept in `best` when it is lower (`k`: the grid index the bracket came from).
fn golden<T>(
    best: &mut Option<Best<f64, T>>,
    k: usize,
    (mut a, mut b): (f64, f64),
    steps: usize,
    eval: &mut impl FnMut(f64) -> Option<(T, f64)>,
) {
    if b <= a || steps < 2 {
        return;
    }
    let g = GOLDEN;
    let (mut c, mut d) = (b - g * (b - a), a + g * (b - a));
    let r = eval(c);
    let mut fc = keep(best, k, c, r);
    let r = eval(d);
    let mut fd = keep(best, k, d, r);
    for _ in 2..steps {
        if fc <= fd {
            b = d;
            (d, fd) = (c, fc);
            c = b - g * (b - a);
            let r = eval(c);
            fc = keep(best, k, c, r);
        } else {
            a = c;
            (c, fc) = (d, fd);
            d = a + g * (b - a);
            let r = eval(d);
            fd = keep(best, k, d, r);
        }
    }
}

/// An integer best point ([`integer`]) refined to a fraction: `steps` golden-section
/// evaluations between its neighbours `at - 1` and `at + 1`, clamped to `[lo, hi]` (the whole
/// point is kept when nothing between beats it; `None` never, an `Option` as [`integer`]). A delay's error varies continuously with
/// the fraction ([`super::estimate::delayed`]); with `steps` = 8 the bracket shrinks to
/// `2 * 0.618^6`, about a tenth of a sample.
pub fn fractional<T>(
    whole: Best<usize, T>,
    (lo, hi): (f64, f64),
    steps: usize,
    mut eval: impl FnMut(f64) -> Option<(T, f64)>,
) -> Option<Best<f64, T>> {
    let at = whole.at as f64;
    let k = whole.k;
    let mut best = Some(Best {
        k,
        at,
        value: whole.value,
        err: whole.err,
    });
    let bracket = ((at - 1.0).max(lo), (at + 1.0).min(hi));
    golden(&mut best, k, bracket, steps, &mut eval);
    best
}

/// The best point of an ascending integer `grid`, then a ternary search over the integers
/// between its neighbours; no point is evaluated twice.
pub fn integer<T>(
    grid: &[usize],
    mut eval: impl FnMut(usize) -> Option<(T, f64)>,
) -> Option<Best<usize, T>> {
    let mut best = None;
    let mut seen: BTreeMap<usize, f64> = BTreeMap::new();
    for (k, &g) in grid.iter().enumerate() {
        let r = eval(g);
        seen.insert(g, keep(&mut best, k, g, r));
    }
    let k = best.as_ref()?.k;
    let (mut lo, mut hi) = (grid[k.saturating_sub(1)], grid[(k + 1).min(grid.len() - 1)]);
    let mut err = |i: usize, best: &mut Option<Best<usize, T>>| -> f64 {
        if let Some(&e) = seen.get(&i) {
            return e;
        }
        let r = eval(i);
        let e = keep(best, k, i, r);
        seen.insert(i, e);
        e
    };
    while hi - lo > 2 {
        let (m1, m2) = (lo + (hi - lo) / 3, hi - (hi - lo) / 3);
        if err(m1, &mut best) <= err(m2, &mut best) {
            hi = m2;
        } else {
            lo = m1;
        }
    }
    for i in lo..=hi {
        err(i, &mut best);
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_golden_constant_is_the_computed_ratio_bit_for_bit() {
        assert_eq!(GOLDEN.to_bits(), (0.5 * (5f64.sqrt() - 1.0)).to_bits());
    }

    #[test]
    fn continuous_refines_between_neighbours_and_flags_edges() {
        let grid = [0.1, 0.2, 0.4, 0.8];
        let b = continuous(&grid, 30, |x| Some(((), (x - 0.33f64).abs()))).unwrap();
        assert_eq!(b.k, 2);
        assert!((b.at - 0.33).abs() < 1e-4, "{}", b.at);
        assert!(!b.at_edge(&grid, true));
        // a minimum beyond the grid stays at its edge
        let b = continuous(&grid, 30, |x| Some(((), -x))).unwrap();
        assert!(b.at_edge(&grid, false), "{}", b.at);
        // failed fits are skipped
        assert!(continuous(&grid, 10, |_| None::<((), f64)>).is_none());
    }

    #[test]
    fn delays_reach_a_quarter_second_or_eight_samples_within_a_quarter_run() {
        // 200 Hz: 0.25 s is 50 samples
        let g = delay_grid(0.005, 10_000);
        assert_eq!(g[..4], [1, 2, 3, 4]);
        assert_eq!(*g.last().unwrap(), 50);
        assert!(g
            .windows(2)
            .all(|w| w[1] > w[0] && (w[1] as f64) <= 1.5 * w[0] as f64 + 1.0));
        // 10 Hz: 8 samples (0.8 s) is more than 0.25 s
        assert_eq!(*delay_grid(0.1, 10_000).last().unwrap(), 8);
        // a 100-sample run: at most 25
        assert_eq!(*delay_grid(0.001, 100).last().unwrap(), 25);
        assert!(delay_grid(0.001, 3).is_empty());
    }

    #[test]
    fn integer_search_finds_the_minimum_between_grid_points_once_each() {
        let grid = [1, 2, 3, 4, 6, 8, 11, 16, 23, 32, 45, 64];
        let mut calls = Vec::new();
        let b = integer(&grid, |d| {
            calls.push(d);
            Some(((), (d as f64 - 37.0).abs()))
        })
        .unwrap();
        assert_eq!(b.at, 37);
        let mut c = calls.clone();
        c.sort_unstable();
        c.dedup();
        assert_eq!(c.len(), calls.len(), "a point evaluated twice: {calls:?}");
        assert!(!b.at_edge(&grid, false));
        let b = integer(&grid, |d| Some(((), -(d as f64)))).unwrap();
        assert!(b.at_edge(&grid, false));
    }

    #[test]
    fn a_whole_best_point_is_refined_to_the_fraction_between_its_neighbours() {
        let grid = [1, 2, 3, 4, 6, 8];
        let err = |d: f64| (d - 4.37).abs();
        let whole = integer(&grid, |d| Some(((), err(d as f64)))).unwrap();
        assert_eq!(whole.at, 4);
        let b = fractional(whole, (0.0, 8.0), 8, |d| Some(((), err(d)))).unwrap();
        assert!((b.at - 4.37).abs() < 0.1, "{}", b.at);
        // nothing between beats a whole point: it stays
        let whole = integer(&grid, |d| Some(((), (d as f64 - 3.0).abs()))).unwrap();
        let b = fractional(whole, (0.0, 8.0), 8, |d| Some(((), (d - 3.0).abs()))).unwrap();
        assert_eq!(b.at, 3.0);
    }

    #[test]
    fn a_geometric_grid_spans_its_range_with_neighbours_within_the_ratio() {
        let g = geometric(0.01, 0.8, 1.2);
        assert_eq!(g.len(), 26);
        assert_eq!((g[0], g[25]), (0.01, 0.8));
        assert!(g
            .windows(2)
            .all(|w| w[1] > w[0] && w[1] / w[0] <= 1.2 + 1e-12));
        assert_eq!(geometric(0.5, 0.5, 1.2), vec![0.5]);
        assert!(geometric(0.0, 1.0, 1.2).is_empty());
        assert!(geometric(1.0, 2.0, 1.0).is_empty());
    }
}

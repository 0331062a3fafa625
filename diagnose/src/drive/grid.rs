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
    let (mut a, mut b) = (grid[k.saturating_sub(1)], grid[(k + 1).min(grid.len() - 1)]);
    if b > a && steps >= 2 {
        let g = 0.5 * (5f64.sqrt() - 1.0);
        let (mut c, mut d) = (b - g * (b - a), a + g * (b - a));
        let r = eval(c);
        let mut fc = keep(&mut best, k, c, r);
        let r = eval(d);
        let mut fd = keep(&mut best, k, d, r);
        for _ in 2..steps {
            if fc <= fd {
                b = d;
                (d, fd) = (c, fc);
                c = b - g * (b - a);
                let r = eval(c);
                fc = keep(&mut best, k, c, r);
            } else {
                a = c;
                (c, fc) = (d, fd);
                d = a + g * (b - a);
                let r = eval(d);
                fd = keep(&mut best, k, d, r);
            }
        }
    }
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
}

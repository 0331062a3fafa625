//! The breakaway level from the onsets of motion, each read as an interval, not a point.
//!
//! Where an axis leaves rest, the net force it held on the samples just before is a lower
//! bound of its breakaway level (it did not move), and the net force where it moves is an
//! upper bound (it did). Under a slow ramp the two meet and the onset measures the level;
//! under a step they are the levels before and after the step, and the onset says only that
//! the breakaway lies between them. Reading every onset as a point put the level at the step
//! (an independent plant driven by steps, pulses and ramps: breakaway 2.30 A against a true
//! 1.42 A, with a run-to-run "scatter" of 0.80 A that then hid a 1.85-fold stiction).
//!
//! The level is the value nearest to every interval (least total distance, the middle of the
//! set of such values); its scatter is the root mean square of those distances, `n - 1`
//! weighted: the spread the intervals cannot explain. Work: `O(n^2)` for `n` onsets (a few
//! hundred at most per direction and data set).

/// The bounds one onset puts on the breakaway level [force units] (`lo <= hi`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interval {
    /// The net force held at rest just before the onset (the axis did not move).
    pub lo: f64,
    /// The net force where the axis moves.
    pub hi: f64,
}

impl Interval {
    /// The interval between two readings, in either order.
    pub fn new(a: f64, b: f64) -> Self {
        Interval {
            lo: a.min(b),
            hi: a.max(b),
        }
    }

    /// How far `b` lies outside the interval (0 inside) [force units].
    pub fn distance(&self, b: f64) -> f64 {
        (self.lo - b).max(0.0) + (b - self.hi).max(0.0)
    }

    /// `b` moved into the interval.
    pub fn clamp(&self, b: f64) -> f64 {
        b.clamp(self.lo, self.hi)
    }
}

/// The level nearest to every interval (least total distance; the middle of the set of
/// minimisers, which is an interval because the total distance is convex and piecewise
/// linear), or `None` without a finite interval.
pub fn level(iv: &[Interval]) -> Option<f64> {
    let iv: Vec<Interval> = iv
        .iter()
        .copied()
        .filter(|i| i.lo.is_finite() && i.hi.is_finite())
        .collect();
    if iv.is_empty() {
        return None;
    }
    let cost = |b: f64| iv.iter().map(|i| i.distance(b)).sum::<f64>();
    // the minimum of a convex piecewise-linear function lies at a breakpoint
    let points: Vec<f64> = iv.iter().flat_map(|i| [i.lo, i.hi]).collect();
    let costs: Vec<f64> = points.iter().map(|&b| cost(b)).collect();
    let best = costs.iter().copied().fold(f64::INFINITY, f64::min);
    let scale = points
        .iter()
        .fold(0.0f64, |m, p| m.max(p.abs()))
        .max(1e-300);
    let tol = 1e-12 * scale * iv.len() as f64;
    let (mut a, mut b) = (f64::INFINITY, f64::NEG_INFINITY);
    for (&p, &c) in points.iter().zip(&costs) {
        if c <= best + tol {
            a = a.min(p);
            b = b.max(p);
        }
    }
    Some(0.5 * (a + b))
}

/// The scatter of the intervals about `b`: `sqrt(sum d_i^2 / (n - 1))` with `d_i` each
/// interval's distance from `b` [force units]; `None` below 2 intervals.
pub fn scatter(iv: &[Interval], b: f64) -> Option<f64> {
    let d: Vec<f64> = iv
        .iter()
        .filter(|i| i.lo.is_finite() && i.hi.is_finite())
        .map(|i| i.distance(b))
        .collect();
    (d.len() >= 2).then(|| (d.iter().map(|x| x * x).sum::<f64>() / (d.len() - 1) as f64).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_give_their_median() {
        let iv: Vec<Interval> = [1.0, 2.0, 10.0]
            .iter()
            .map(|&x| Interval::new(x, x))
            .collect();
        assert_eq!(level(&iv), Some(2.0));
        // an even count: the middle of the two middle points
        let iv: Vec<Interval> = [1.0, 2.0, 3.0, 10.0]
            .iter()
            .map(|&x| Interval::new(x, x))
            .collect();
        assert_eq!(level(&iv), Some(2.5));
    }

    #[test]
    fn steps_bound_the_level_and_a_ramp_measures_it() {
        // two steps from rest (0 -> 2.3, 0.2 -> 2.6) and one slow ramp meeting 1.42: the
        // level is the ramp's, and the steps leave no scatter
        let iv = [
            Interval::new(0.0, 2.3),
            Interval::new(0.2, 2.6),
            Interval::new(1.41, 1.43),
        ];
        let b = level(&iv).unwrap();
        assert!((b - 1.42).abs() < 1e-12, "{b}");
        assert_eq!(scatter(&iv, b), Some(0.0));
        // read as points, the median is a step's level
        let pts: Vec<Interval> = [2.3, 2.6, 1.43]
            .iter()
            .map(|&x| Interval::new(x, x))
            .collect();
        assert_eq!(level(&pts), Some(2.3));
    }

    #[test]
    fn steps_alone_give_the_middle_of_what_they_allow() {
        let iv = [Interval::new(0.5, 3.0), Interval::new(1.0, 2.0)];
        assert_eq!(level(&iv), Some(1.5));
        assert_eq!(level(&[]), None);
        assert_eq!(scatter(&iv[..1], 1.5), None);
    }
}

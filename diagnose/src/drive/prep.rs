//! Stage 1 of the single-axis pipeline: recorded runs on a uniform grid, with velocity and
//! acceleration estimates and the motion thresholds derived from the data themselves.
//!
//! Derivatives are local quadratic (Savitzky-Golay) fits over `2 w + 1` samples, run by run
//! (never across a run boundary), shortened at the ends; `w` ([`window`]) is chosen from the
//! data's position noise and motion (5 samples at 67 Hz, more at kHz rates or with a coarse
//! encoder), never a fixed count for every rig. They are used for the sliding-phase
//! least squares and to find where the axis moves; the final judgement is always a simulation.

/// Smallest half window of the Savitzky-Golay derivative estimate [samples].
pub const W: usize = 2;

/// One recorded run of a single drive, on a uniform time grid.
#[derive(Clone, Debug, PartialEq)]
pub struct DriveRun {
    /// File name (as in the data set).
    pub name: String,
    /// Held out (scored) rather than fitted.
    pub held_out: bool,
    /// Sample period [s] (> 0).
    pub dt: f64,
    /// Position [m or rad].
    pub x: Vec<f64>,
    /// Input [input units], applied over each sample (zero-order hold).
    pub u: Vec<f64>,
    /// Rows per fresh sample of the position channel (1: every row is fresh; more when the
    /// logger repeats `x` between refreshes, and `x` is then [`unhold`]'s reconstruction, or
    /// when the loader interpolated a position given on fewer rows:
    /// `crane_ident::data::AxisRun::x_refresh`).
    pub refresh: usize,
    /// Per sample, when its input was taken [s from the run's first sample]: the sample's own
    /// instant `k dt`, or for a log resampled by zero-order hold the stamp of the file row it
    /// holds (`crane_ident::data::AxisRun::source_t`).
    pub input_at: Vec<f64>,
    /// Per sample, when the logged position it rebuilds was read [s from the run's first
    /// sample] ([`read_instants`]).
    pub read_at: Vec<f64>,
}

/// When each logged position was read [s]: `source_t` (the stamp of the row each sample
/// holds) for a channel fresh on every row; for a channel refreshed every `refresh` rows the
/// stamp of its last fresh row: a row where the value changes, or, while it does not (the
/// axis at rest, or creeping by less than a count), every `refresh` rows after the last
/// change (the logger kept refreshing a value that did not change). `x_logged` is the channel
/// as logged (before [`unhold`]).
pub fn read_instants(x_logged: &[f64], source_t: &[f64], refresh: usize) -> Vec<f64> {
    if refresh <= 1 {
        return source_t.to_vec();
    }
    let mut out = Vec::with_capacity(source_t.len());
    let mut last = 0usize;
    for k in 0..source_t.len().min(x_logged.len()) {
        if k == 0 || x_logged[k] != x_logged[k - 1] || k - last >= refresh {
            last = k;
        }
        out.push(source_t[last]);
    }
    out
}

/// A position channel logged slower than its rows, rebuilt between its fresh samples: every
/// change of value is a fresh sample at its row; between two changes at most `2 refresh` rows
/// apart (the axis moving) the position is interpolated linearly; across a longer gap it is
/// held (the axis rested, or crept by less than a count) until `refresh` rows before the next
/// change, then interpolated. Before the first change it is held until `refresh` rows before
/// it, after the last one it is held. A zero-order-held position makes every difference over
/// fewer than `refresh` rows a hold or a jump: the derivatives and the simulations are then
/// compared with the logger's holds, not with the motion. Returns `x` unchanged for
/// `refresh <= 1`.
pub fn unhold(x: &[f64], refresh: usize) -> Vec<f64> {
    if refresh <= 1 || x.len() < 3 {
        return x.to_vec();
    }
    let knots: Vec<usize> = (1..x.len()).filter(|&i| x[i] != x[i - 1]).collect();
    let mut out = x.to_vec();
    let mut ramp = |from: usize, to: usize| {
        let (x0, x1) = (x[from], x[to]);
        for (i, o) in out.iter_mut().enumerate().take(to).skip(from + 1) {
            *o = x0 + (x1 - x0) * (i - from) as f64 / (to - from) as f64;
        }
    };
    if let Some(&b) = knots.first() {
        ramp(b.saturating_sub(refresh), b);
    }
    for w in knots.windows(2) {
        let (a, b) = (w[0], w[1]);
        ramp(if b - a <= 2 * refresh { a } else { b - refresh }, b);
    }
    out
}

/// A run with its derivative estimates.
#[derive(Clone, Debug)]
pub struct Prepared {
    /// The run.
    pub run: DriveRun,
    /// Velocity [m/s or rad/s].
    pub v: Vec<f64>,
    /// Acceleration [m/s^2 or rad/s^2].
    pub a: Vec<f64>,
    /// Half window of the derivative estimates [samples].
    pub w: usize,
    /// Velocity the simulations start from [m/s or rad/s]: the estimate at the first sample
    /// when it exceeds the motion threshold (a log that starts mid-motion), else 0 (at rest,
    /// exactly, so noise never starts a resting axis moving). Set by [`Prepared::set_start`].
    pub v0: f64,
    /// The motion threshold [`Prepared::v0`] was set with (infinite before
    /// [`Prepared::set_start`]): [`Prepared::v_at`] reads a later start the same way.
    pub v_move: f64,
}

impl Prepared {
    /// Estimates velocity and acceleration of a run (half window [`W`]).
    pub fn new(run: DriveRun) -> Prepared {
        Prepared::with_window(run, W)
    }

    /// Estimates velocity and acceleration of a run over `2 w + 1` samples (see [`window`]).
    pub fn with_window(run: DriveRun, w: usize) -> Prepared {
        let (v, a) = derivatives_over(&run.x, run.dt, w);
        Prepared {
            run,
            v,
            a,
            w,
            v0: 0.0,
            v_move: f64::INFINITY,
        }
    }

    /// The velocity a simulation started at sample `i` takes [m/s or rad/s]: the estimate
    /// there when it exceeds the motion threshold, else 0 (as [`Prepared::v0`] at sample 0).
    pub fn v_at(&self, i: usize) -> f64 {
        match self.v.get(i) {
            Some(&v) if v.abs() > self.v_move => v,
            _ => 0.0,
        }
    }

    /// Sets [`Prepared::v0`] from the motion threshold `v_move` [m/s or rad/s].
    pub fn set_start(&mut self, v_move: f64) {
        self.v_move = v_move;
        self.v0 = self.v_at(0);
    }

    /// The run's first `n` samples (all of it when it is shorter), with the derivatives and
    /// start computed on the whole run: the same values sample for sample.
    pub fn head(&self, n: usize) -> Prepared {
        let n = n.min(self.run.x.len());
        let cut = |v: &[f64]| v[..n.min(v.len())].to_vec();
        Prepared {
            run: DriveRun {
                name: self.run.name.clone(),
                held_out: self.run.held_out,
                dt: self.run.dt,
                x: cut(&self.run.x),
                u: cut(&self.run.u),
                refresh: self.run.refresh,
                input_at: cut(&self.run.input_at),
                read_at: cut(&self.run.read_at),
            },
            v: cut(&self.v),
            a: cut(&self.a),
            w: self.w,
            v0: self.v0,
            v_move: self.v_move,
        }
    }

    /// Starts from rest: samples whose velocity estimate exceeds the motion threshold
    /// [`Prepared::v_move`] after one that did not.
    pub fn starts(&self) -> usize {
        let moving = |v: &f64| v.abs() > self.v_move;
        self.v
            .windows(2)
            .filter(|w| !moving(&w[0]) && moving(&w[1]))
            .count()
    }
}

/// Largest half window of the derivative estimate [samples].
pub const MAX_W: usize = 64;
/// Largest acceleration noise accepted, as a fraction of the RMS acceleration of the runs.
pub const ACCEL_NOISE_FRACTION: f64 = 0.1;

/// The half window of the derivative estimates for these runs: the smallest, from [`W`] up,
/// whose acceleration noise (the position noise propagated through the quadratic fit) is at
/// most [`ACCEL_NOISE_FRACTION`] of the RMS acceleration the window sees while the axis
/// moves. A fixed number of samples is not a rule for every rig: at 2 kHz five samples span
/// 2.5 ms and one encoder count becomes an acceleration spike far above the motion's, which
/// biases the inertia towards 0 (noise in a regressor); at 67 Hz (CICESE) the same five
/// samples are right. The position noise is the larger of the encoder step's (`q / sqrt 12`)
/// and a robust scale of the third differences (`median |d3 x| / (0.6745 sqrt 20)`, rests
/// included; third differences of a smooth motion are `x''' dt^3`, far below the noise's
/// except at the lowest rates, where the window stays short anyway).
pub fn window(runs: &[DriveRun]) -> usize {
    let mut dd: Vec<f64> = Vec::new();
    let mut quantum = f64::INFINITY;
    for r in runs {
        // the noise is the logged samples': in a channel refreshed every few rows the rows
        // between fresh samples are [`unhold`]'s interpolation, whose tiny steps and zero
        // third differences once set the noise 1000 times too low and kept an 11-sample
        // window over 2 fresh positions (a 0.2 s delay on a 1 kHz log then read as an
        // inertia at its floor)
        let x = fresh(r);
        for k in 1..x.len().saturating_sub(2) {
            dd.push((x[k + 2] - 3.0 * x[k + 1] + 3.0 * x[k] - x[k - 1]).abs());
        }
        for w in x.windows(2) {
            let d = (w[1] - w[0]).abs();
            if d > 0.0 {
                quantum = quantum.min(d);
            }
        }
    }
    dd.retain(|d| d.is_finite());
    let mut sigma = if quantum.is_finite() {
        quantum / 12f64.sqrt()
    } else {
        0.0
    };
    if !dd.is_empty() {
        dd.sort_by(f64::total_cmp);
        sigma = sigma.max(dd[dd.len() / 2] / (0.6745 * 20f64.sqrt()));
    }
    if sigma.is_nan() || sigma <= 0.0 {
        return W;
    }
    // the window is bounded by the longest run, not the shortest: one short snippet (a 10 ms
    // held-out run beside minutes of log) once capped every run's window at a quarter of its
    // length (7 samples instead of 17 at 2 kHz), which put encoder noise in the
    // accelerations, biased the inertia 32 % low and named a delay at the grid edge; a run
    // shorter than the window gets the shortened end windows of `derivatives_over`
    let longest = runs.iter().map(|r| r.x.len()).max().unwrap_or(0);
    // at least one fresh sample of the position on each side of the centre
    let mut w = runs.iter().map(|r| r.refresh).max().unwrap_or(1).max(W);
    loop {
        // the quadratic fit's second-derivative weights: (k^2 - m) / S, m = w (w + 1) / 3
        let m = (w * (w + 1)) as f64 / 3.0;
        let s: f64 = (0..=2 * w)
            .map(|j| {
                let k = j as f64 - w as f64;
                (k * k - m) * (k * k - m)
            })
            .sum();
        let (mut ss, mut n, mut noise) = (0.0, 0usize, 0.0);
        for r in runs {
            if r.dt.is_nan() || r.dt <= 0.0 {
                continue;
            }
            // rebuilt rows between fresh samples are not independent: the window holds
            // `1 / refresh` as many independent positions, which multiplies the noise
            // variance by `refresh`
            noise += 2.0 * sigma * (r.refresh.max(1) as f64).sqrt() / (s.sqrt() * r.dt * r.dt);
            let (v, a) = derivatives_over(&r.x, r.dt, w);
            let v_peak = v.iter().fold(0.0f64, |p, v| p.max(v.abs()));
            for (vi, ai) in v.iter().zip(&a) {
                if vi.abs() > SLIDE_FRACTION * v_peak {
                    ss += ai * ai;
                    n += 1;
                }
            }
        }
        let noise = noise / runs.len().max(1) as f64;
        let rms = if n > 0 { (ss / n as f64).sqrt() } else { 0.0 };
        let next = (w * 3).div_ceil(2);
        if noise <= ACCEL_NOISE_FRACTION * rms || next > MAX_W || 4 * next + 2 > longest {
            return w;
        }
        w = next;
    }
}

/// The run's positions at its fresh rows (where [`DriveRun::read_at`] moves on: every row for
/// a channel fresh on every row), as logged.
fn fresh(r: &DriveRun) -> Vec<f64> {
    if r.refresh <= 1 || r.read_at.len() != r.x.len() {
        return r.x.clone();
    }
    (0..r.x.len())
        .filter(|&k| k == 0 || r.read_at[k] != r.read_at[k - 1])
        .map(|k| r.x[k])
        .collect()
}

/// Velocity and acceleration by local quadratic least squares over `2 W + 1` samples
/// (fewer at the ends; a run shorter than 3 samples gets zeros).
pub fn derivatives(x: &[f64], dt: f64) -> (Vec<f64>, Vec<f64>) {
    derivatives_over(x, dt, W)
}

/// Same as [`derivatives`] over `2 w + 1` samples (`w >= 1`).
pub fn derivatives_over(x: &[f64], dt: f64, w: usize) -> (Vec<f64>, Vec<f64>) {
    let w = w.max(1);
    let n = x.len();
    let mut v = vec![0.0; n];
    let mut a = vec![0.0; n];
    if n < 3 || dt.is_nan() || dt <= 0.0 {
        return (v, a);
    }
    for i in 0..n {
        let lo = i.saturating_sub(w);
        let hi = (i + w + 1).min(n);
        // centred moments of k = j - i over the window
        let (mut s0, mut s1, mut s2, mut s3, mut s4) = (0.0, 0.0, 0.0, 0.0, 0.0);
        let (mut b0, mut b1, mut b2) = (0.0, 0.0, 0.0);
        for (j, xj) in x.iter().enumerate().take(hi).skip(lo) {
            let k = j as f64 - i as f64;
            let k2 = k * k;
            s0 += 1.0;
            s1 += k;
            s2 += k2;
            s3 += k2 * k;
            s4 += k2 * k2;
            let d = xj - x[i];
            b0 += d;
            b1 += k * d;
            b2 += k2 * d;
        }
        // solve [s0 s1 s2; s1 s2 s3; s2 s3 s4] c = b  for d(k) = c0 + c1 k + c2 k^2
        let m = [[s0, s1, s2], [s1, s2, s3], [s2, s3, s4]];
        if let Some(c) = solve3(m, [b0, b1, b2]) {
            v[i] = c[1] / dt;
            a[i] = 2.0 * c[2] / (dt * dt);
        } else if hi - lo >= 2 {
            v[i] = (x[hi - 1] - x[lo]) / ((hi - 1 - lo) as f64 * dt);
        }
    }
    (v, a)
}

fn solve3(m: [[f64; 3]; 3], b: [f64; 3]) -> Option<[f64; 3]> {
    let det = |m: &[[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let d = det(&m);
    if d.is_nan() || d.abs() <= 1e-12 {
        return None;
    }
    let mut out = [0.0; 3];
    for (c, o) in out.iter_mut().enumerate() {
        let mut mc = m;
        for r in 0..3 {
            mc[r][c] = b[r];
        }
        *o = det(&mc) / d;
    }
    Some(out)
}

/// Velocity thresholds derived from the fitting runs (any rig: relative to the fastest motion
/// seen, floored at the position resolution per sample).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Thresholds {
    /// Largest |velocity| in the fitting runs [m/s or rad/s].
    pub v_peak: f64,
    /// Above it a sample counts as moving (first motion, stick/slip marks): 2 % of `v_peak`,
    /// at least [`count_velocity`] (twice the velocity one encoder count makes).
    pub v_move: f64,
    /// Above it a sample counts as sliding for the least squares: 10 % of `v_peak`.
    pub v_slide: f64,
    /// Position resolution: the smallest non-zero step between samples [m or rad].
    pub quantum: f64,
}

/// The motion threshold's floor for an encoder of step `quantum` [m or rad] sampled every
/// `dt` [s] with derivatives over `2 w + 1` samples [m/s or rad/s]: twice the largest
/// velocity estimate one isolated count makes, `2 * 3 q / (2 (2 w + 1) dt)` (the local fit's
/// velocity weights are `k / sum k^2`; a step of `q` after the centre sums them over
/// `k = 1..w`: `q w (w + 1) / 2 / (w (w + 1) (2 w + 1) / 3) / dt`), so an encoder flicker is
/// never motion. It was one count per sample, `q / dt`: a slow axis logged fast with a coarse
/// encoder (a 2 mm count at 1 kHz, slides of 0.5-1 m/s, 25 counts each) then never "moved"
/// and the diagnosis refused the data ("0 sliding samples"), although the smoothed velocity
/// resolves a fraction of a count per sample.
pub fn count_velocity(quantum: f64, dt: f64, w: usize) -> f64 {
    if dt.is_nan() || dt <= 0.0 {
        return f64::INFINITY;
    }
    3.0 * quantum / ((2 * w.max(1) + 1) as f64 * dt)
}

/// Fraction of the peak velocity above which an axis moves.
pub const MOVE_FRACTION: f64 = 0.02;
/// Fraction of the peak velocity above which an axis slides (least-squares rows).
pub const SLIDE_FRACTION: f64 = 0.1;

impl Thresholds {
    /// Thresholds from the fitting runs; `None` when they never move.
    pub fn from_runs(fit: &[&Prepared]) -> Option<Thresholds> {
        let v_peak = fit
            .iter()
            .flat_map(|p| p.v.iter())
            .fold(0.0f64, |m, v| m.max(v.abs()));
        let quantum = fit
            .iter()
            .flat_map(|p| p.run.x.windows(2).map(|w| (w[1] - w[0]).abs()))
            .filter(|d| *d > 0.0)
            .fold(f64::INFINITY, f64::min);
        let floor = fit
            .iter()
            .map(|p| count_velocity(quantum, p.run.dt, p.w))
            .fold(0.0f64, f64::max);
        if v_peak.is_nan() || v_peak <= 0.0 || !quantum.is_finite() || !floor.is_finite() {
            return None;
        }
        let v_move = (MOVE_FRACTION * v_peak).max(floor);
        let v_slide = (SLIDE_FRACTION * v_peak).max(v_move);
        Some(Thresholds {
            v_peak,
            v_move,
            v_slide,
            quantum,
        })
    }
}

/// Shortest motion that counts as motion [samples]: longer than the `2 W + 1` derivative
/// values one isolated position jump (an encoder flicker, a pre-sliding snap) can produce.
pub const MIN_MOTION_SAMPLES: usize = 2 * W + 2;

/// Maximal stretches `[start, end)` where `sign * v > v_th` for at least
/// [`MIN_MOTION_SAMPLES`] samples in a row (`sign` = +1 or -1).
pub fn motions(v: &[f64], v_th: f64, sign: f64) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut start: Option<usize> = None;
    for i in 0..=v.len() {
        let on = i < v.len() && sign * v[i] > v_th;
        match (on, start) {
            (true, None) => start = Some(i),
            (false, Some(s)) => {
                if i - s >= MIN_MOTION_SAMPLES {
                    out.push((s, i));
                }
                start = None;
            }
            _ => {}
        }
    }
    out
}

/// Where a motion detected at sample `i` (its first sample faster than the motion threshold,
/// direction `sign`) left rest: the velocity extrapolated back to 0 with the acceleration
/// estimated at `i`, walking back only while the estimated velocity keeps falling and stays on
/// the side of the motion (so a creep or a noise wiggle before the slip stops it), and at most
/// `2 v / a` seconds plus the derivative's half window (`v / a` is the time since rest at a
/// constant acceleration, `2 v / a` with an acceleration growing linearly from 0, as under a
/// force ramp), then moved `w - 1` samples later (the smoothing's lead). A threshold relative to the fastest motion is crossed late when the force
/// rises fast (a step or a steep ramp at a high sampling rate): the force there is above the
/// breakaway level by the force rise over that lag, which this removes. Never after `i`.
pub fn onset(p: &Prepared, i: usize, sign: f64) -> usize {
    let (v, a, dt) = (&p.v, &p.a, p.run.dt);
    let (vi, ai) = (sign * v[i], sign * a[i]);
    if !(vi > 0.0 && ai > 0.0 && dt > 0.0) {
        return i;
    }
    let back = (2.0 * vi / ai / dt).floor() + p.w as f64;
    let earliest = if back.is_finite() && back < i as f64 {
        i - back as usize
    } else {
        0
    };
    let mut j = i;
    while j > earliest && sign * v[j - 1] > 0.0 && sign * v[j - 1] < sign * v[j] {
        j -= 1;
    }
    // the local fit over `2 w + 1` samples sees a motion starting at `t0` from `t0 - w + 1` on
    // (its velocity weights are odd in the offset): the first sample of the rise is `w - 1`
    // samples early
    (j + p.w.saturating_sub(1)).min(i)
}

/// Where the position left its rest before an onset `o` ([`onset`], direction `sign`): the
/// last sample whose position is within the rest's own scatter of the rest position. The rest
/// is the stretch before `o` whose velocity stays within `v_move`; its first half gives the
/// position (median) and the scatter (largest distance from it). A velocity threshold is
/// crossed late where the friction falls off gradually with speed (velocity weakening): the
/// axis then leaves rest slowly, and under a ramp the force at the velocity's onset is above
/// the level at which it left. `o` itself when the rest is shorter than 8 samples or the
/// position did not leave it earlier. Never after `o`.
pub fn departure(p: &Prepared, o: usize, sign: f64, v_move: f64) -> usize {
    let x = &p.run.x;
    let mut r = o;
    while r > 0 && p.v[r - 1].abs() <= v_move {
        r -= 1;
    }
    let len = o - r;
    if len < 8 {
        return o;
    }
    let half = &x[r..r + len / 2];
    // the middle order statistic by selection (linear), not a sort: this runs at every onset
    // of every Stribeck grid point
    let mut order = half.to_vec();
    let mid = order.len() / 2;
    let rest = *order.select_nth_unstable_by(mid, f64::total_cmp).1;
    let band = half.iter().map(|q| (q - rest).abs()).fold(0.0, f64::max);
    let mut j = o;
    while j > r + len / 2 && sign * (x[j - 1] - rest) > band {
        j -= 1;
    }
    j
}

/// Whether a run moves at all (a motion in either direction).
pub fn moves(v: &[f64], v_th: f64) -> bool {
    !motions(v, v_th, 1.0).is_empty() || !motions(v, v_th, -1.0).is_empty()
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_single_jump_is_not_motion_a_slip_is() {
        let dt = 0.01;
        let mut x = vec![0.0; 40];
        for q in x.iter_mut().skip(20) {
            *q = 1e-3;
        }
        let (v, _) = derivatives(&x, dt);
        assert!(!moves(&v, 1e-3));
        let x: Vec<f64> = (0..40)
            .map(|k| if k < 10 { 0.0 } else { (k - 10) as f64 * 1e-3 })
            .collect();
        let (v, _) = derivatives(&x, dt);
        assert_eq!(motions(&v, 0.05, 1.0).len(), 1);
        assert!(motions(&v, 0.05, -1.0).is_empty());
    }

    use super::*;

    #[test]
    fn quadratic_derivatives_are_exact_inside() {
        let dt = 0.01;
        let x: Vec<f64> = (0..50)
            .map(|k| {
                let t = k as f64 * dt;
                1.0 + 2.0 * t + 1.5 * t * t
            })
            .collect();
        let (v, a) = derivatives(&x, dt);
        for k in 0..50 {
            let t = k as f64 * dt;
            assert!((v[k] - (2.0 + 3.0 * t)).abs() < 1e-9, "v[{k}] = {}", v[k]);
            assert!((a[k] - 3.0).abs() < 1e-6, "a[{k}] = {}", a[k]);
        }
    }

    #[test]
    fn short_runs_do_not_panic() {
        for n in 0..4 {
            let x = vec![0.1; n];
            let (v, a) = derivatives(&x, 0.01);
            assert_eq!(v.len(), n);
            assert!(v.iter().chain(&a).all(|q| q.is_finite()));
        }
    }

    fn run(dt: f64, x: Vec<f64>) -> DriveRun {
        let t: Vec<f64> = (0..x.len()).map(|k| k as f64 * dt).collect();
        DriveRun {
            refresh: 1,
            input_at: t.clone(),
            read_at: t,
            name: "r".into(),
            held_out: false,
            dt,
            u: vec![0.0; x.len()],
            x,
        }
    }

    /// A smooth swing of 0.1 m at 1 Hz, sampled at `hz` and quantised to `q`.
    fn swing(hz: f64, q: f64) -> DriveRun {
        let dt = 1.0 / hz;
        let n = (4.0 * hz) as usize;
        let x = (0..n)
            .map(|k| {
                let y = 0.1 * (std::f64::consts::TAU * k as f64 * dt).sin();
                if q > 0.0 {
                    (y / q).round() * q
                } else {
                    y
                }
            })
            .collect();
        run(dt, x)
    }

    #[test]
    fn a_held_position_was_read_at_its_last_fresh_row() {
        let t: Vec<f64> = (0..12).map(|k| k as f64).collect();
        // fresh every row: each sample's own instant
        assert_eq!(read_instants(&[0.0; 12], &t, 1), t);
        // refreshed every 3 rows: moving (changes at 3 and 6), then at rest from row 6 on,
        // where the logger still refreshed every 3 rows
        let x = [0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 2.0, 2.0, 2.0, 2.0, 2.0, 2.0];
        let r = read_instants(&x, &t, 3);
        assert_eq!(
            r,
            [0.0, 0.0, 0.0, 3.0, 3.0, 3.0, 6.0, 6.0, 6.0, 9.0, 9.0, 9.0]
        );
    }

    #[test]
    fn a_held_position_is_rebuilt_between_its_fresh_samples() {
        // a ramp then a rest, logged every row but refreshed every 4 rows
        let fresh: Vec<f64> = (0..80).map(|k| (k.min(40)) as f64 * 1e-3).collect();
        let held: Vec<f64> = (0..80).map(|k| fresh[k - k % 4]).collect();
        let x = unhold(&held, 4);
        // inside the motion the rebuilt position is the motion, shifted by less than a refresh
        for k in 8..36 {
            let lag = (x[k] - fresh[k]).abs();
            assert!(lag <= 4e-3 + 1e-12, "row {k}: {} vs {}", x[k], fresh[k]);
        }
        // every difference while moving is a motion, not a hold or a jump
        for k in 8..36 {
            let d = x[k + 1] - x[k];
            assert!(d > 0.0 && d < 2e-3, "row {k}: step {d}");
        }
        // at rest it stays at the held value; unchanged without holds
        assert_eq!(x[79], held[79]);
        assert_eq!(unhold(&fresh, 1), fresh);
    }

    #[test]
    fn a_refreshed_channel_gets_the_window_of_its_fresh_samples() {
        // the same swing and encoder, logged at 2 kHz but refreshed every 5 rows (400 Hz of
        // fresh positions), against the same swing logged at 400 Hz: the window must span
        // about the time the 400 Hz log needs (the rows in between are interpolation; the
        // window grows in steps of 1.5, hence 2 / 3 of it)
        let fresh = swing(400.0, 1e-5);
        let fine = swing(2000.0, 1e-5);
        let held: Vec<f64> = (0..fine.x.len()).map(|k| fine.x[k - k % 5]).collect();
        let mut r = run(fine.dt, unhold(&held, 5));
        r.read_at = read_instants(&held, &r.read_at, 5);
        r.refresh = 5;
        let (w_fresh, w_held) = (window(&[fresh]), window(&[r.clone()]));
        assert!(
            w_held as f64 * r.dt >= 2.0 / 3.0 * w_fresh as f64 / 400.0,
            "half window {w_held} rows at 2 kHz against {w_fresh} at 400 Hz"
        );
        // and it still finds the swing's acceleration on most samples (the rebuilt channel
        // holds at the turning points, where the encoder changes less often than refreshed)
        let (_, a) = derivatives_over(&r.x, r.dt, w_held);
        let want = 0.1 * std::f64::consts::TAU.powi(2);
        let mut err: Vec<f64> = a
            .iter()
            .enumerate()
            .map(|(k, a)| {
                let t = k as f64 * r.dt;
                (a + want * (std::f64::consts::TAU * t).sin()).abs()
            })
            .collect();
        err.sort_by(f64::total_cmp);
        let p80 = err[err.len() * 4 / 5];
        assert!(
            p80 < 0.25 * want,
            "80th percentile error {p80} vs peak {want}"
        );
    }

    #[test]
    fn the_window_grows_with_the_rate_and_the_encoder_step_not_otherwise() {
        // 67 Hz with a fine encoder: the five samples of the CICESE logs
        assert_eq!(window(&[swing(67.0, 1e-7)]), W);
        // 2 kHz with a 10 um encoder: five samples would see one count as 40 m/s^2 against
        // the swing's 4 m/s^2
        let w = window(&[swing(2000.0, 1e-5)]);
        assert!(w > 4 * W, "half window {w}");
        let (_, a) = derivatives_over(&swing(2000.0, 1e-5).x, 5e-4, w);
        let peak = a.iter().fold(0.0f64, |m, a| m.max(a.abs()));
        let want = 0.1 * std::f64::consts::TAU.powi(2);
        assert!((peak - want).abs() < 0.25 * want, "peak {peak} vs {want}");
    }

    #[test]
    fn the_onset_of_a_motion_under_a_steep_ramp_is_found_where_it_starts() {
        // at rest until sample 200, then x = c (k - 200)^3: the acceleration grows linearly
        // from 0, as under a force ramp from the breakaway level
        let dt = 1e-3;
        let x: Vec<f64> = (0..400)
            .map(|k| {
                if k < 200 {
                    0.0
                } else {
                    1e-6 * ((k - 200) as f64).powi(3)
                }
            })
            .collect();
        for w in [W, 6] {
            let p = Prepared::with_window(run(dt, x.clone()), w);
            let v_peak = p.v.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let m = motions(&p.v, MOVE_FRACTION * v_peak, 1.0);
            let i = m[0].0;
            let o = onset(&p, i, 1.0);
            assert!(i > 215, "the threshold is crossed late: {i}");
            assert!(
                (198..=206).contains(&o),
                "w {w}: onset {o} (threshold at {i})"
            );
        }
    }

    #[test]
    fn a_slow_departure_is_found_on_the_position_before_the_velocity_onset() {
        // at rest with one count of flicker until sample 200, then x = c (k - 200)^4: the
        // acceleration grows from 0 as under velocity weakening (the friction falls off only
        // as the axis speeds up); the position leaves the flicker's band at sample 206
        let (dt, q) = (1e-3, 1e-6);
        let x: Vec<f64> = (0..400)
            .map(|k| {
                if k < 200 {
                    if k % 3 == 0 {
                        q
                    } else {
                        0.0
                    }
                } else {
                    1e-9 * ((k - 200) as f64).powi(4)
                }
            })
            .collect();
        let p = Prepared::with_window(run(dt, x), W);
        let v_peak = p.v.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let v_move = MOVE_FRACTION * v_peak;
        let i = motions(&p.v, v_move, 1.0)[0].0;
        let o = onset(&p, i, 1.0);
        let d = departure(&p, o, 1.0, v_move);
        assert!(o > 212, "the velocity's onset is late: {o}");
        assert!((204..=208).contains(&d), "departure {d} (onset {o})");
        // the other direction never departs before its onset
        assert_eq!(departure(&p, o, -1.0, v_move), o);
        // a rest shorter than 8 samples gives the onset itself
        assert_eq!(departure(&p, 5, 1.0, v_move), 5);
    }
}

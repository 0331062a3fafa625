//! The inverse-dynamics rows of a part of the runs (the fitting or the held-out part): each
//! run's moving stretches filtered, differentiated and decimated as the EMPS benchmark's
//! IDIM-LS does ([`crane_ident::emps::process`]), with the force delayed by 0..=[`MAXD`]
//! samples and the undecimated force beside them.

use crane_ident::data::AxisRun;
use crane_ident::emps::{process, IdimOptions};
use crane_ident::signal::decimate;

/// The inverse-dynamics rows of one part (fitting or held out), run segment after run
/// segment. Positions are in the data set's unit (m or rad), forces in N (N m on a rotary
/// axis: the input times the declared gain, the input itself without one); signs as
/// recorded. The kinematic columns are at the full rate (the first `drop_start` samples of
/// every segment dropped) and are decimated when a regressor is built from them ([`dec`]);
/// the force columns are decimated already.
#[derive(Default, Clone)]
pub(super) struct Part {
    /// Filtered position [m or rad], full rate.
    pub(super) q: Vec<f64>,
    /// Velocity [m/s or rad/s] (central difference of `q`), full rate; positive moving up
    /// the position.
    pub(super) v: Vec<f64>,
    /// Acceleration [m/s^2 or rad/s^2] (central difference of `v`), full rate.
    pub(super) a: Vec<f64>,
    /// Force [N], decimated: the target of the least squares.
    pub(super) f: Vec<f64>,
    /// force delayed by m samples, m = 0..MAXD (index m) [N], decimated
    pub(super) fd: Vec<Vec<f64>>,
    /// force before decimation (for the dead band) [N], full rate
    pub(super) u: Vec<f64>,
    /// full-rate length of every appended run segment: columns are decimated run by run,
    /// like the force, so they stay aligned whatever the run lengths
    pub(super) lens: Vec<usize>,
}

/// Longest input delay tried [samples]: [`Part::fd`] holds the force delayed by 0..=`MAXD`.
pub(super) const MAXD: usize = 12;

/// Shortest stretch at rest that is cut out of the inverse-dynamics rows [s]: far longer than
/// a reversal takes (EMPS has none over 7 ms), so only an axis that really holds still is cut.
pub const REST_MIN_S: f64 = 0.2;

/// The moving parts of `range`: the run without its stretches at rest (the position stays
/// within two encoder steps over +-0.05 s, for at least [`REST_MIN_S`] and 20 samples).
/// A resting axis carries no sign of velocity for the least squares: its force only says
/// that friction held it, which the inverse-dynamics rows cannot express. Moving parts too
/// short for the zero-phase filter (`< 4 drop_start + 50` samples) are left out too.
fn moving_parts(
    run: &AxisRun,
    range: std::ops::Range<usize>,
    opt: &IdimOptions,
) -> Vec<std::ops::Range<usize>> {
    let x = &run.x[range.clone()];
    let n = x.len();
    let dt = run.dt();
    let quantum = x
        .windows(2)
        .map(|w| (w[1] - w[0]).abs())
        .filter(|d| *d > 0.0)
        .fold(f64::INFINITY, f64::min);
    if n == 0 || !quantum.is_finite() || dt.is_nan() || dt <= 0.0 {
        return vec![range];
    }
    let k = ((0.05 / dt).round() as usize).max(5);
    let still: Vec<bool> = (0..n)
        .map(|i| {
            let w = &x[i.saturating_sub(k)..(i + k + 1).min(n)];
            let (lo, hi) = w
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| {
                    (l.min(v), h.max(v))
                });
            hi - lo <= 2.0 * quantum
        })
        .collect();
    let min_rest = ((REST_MIN_S / dt).ceil() as usize).max(20);
    let min_part = 4 * opt.drop_start + 50;
    let mut parts = Vec::new();
    let mut start = 0usize;
    let mut i = 0usize;
    while i < n {
        if still[i] {
            let j = (i..n).find(|&j| !still[j]).unwrap_or(n);
            if j - i >= min_rest {
                // the +-k window: the k samples on either side of the still stretch lie within
                // two encoder steps of it too, so they rest as well
                let (a, b) = (i.saturating_sub(k), (j + k).min(n));
                if a > start && a - start >= min_part {
                    parts.push(range.start + start..range.start + a);
                }
                start = b;
            }
            i = j;
        } else {
            i += 1;
        }
    }
    if n - start >= min_part {
        parts.push(range.start + start..range.start + n);
    }
    parts
}

/// Appends the moving parts ([`moving_parts`]) of `run[range]` to `part`.
pub(super) fn append(
    part: &mut Part,
    run: &AxisRun,
    range: std::ops::Range<usize>,
    opt: &IdimOptions,
) {
    for piece in moving_parts(run, range, opt) {
        append_part(part, run, piece, opt);
    }
}

fn append_part(part: &mut Part, run: &AxisRun, range: std::ops::Range<usize>, opt: &IdimOptions) {
    let sub = run.slice(range);
    let p = process(&sub, opt);
    let r = opt.decimation;
    part.q.extend(&p.q);
    part.v.extend(&p.qd);
    part.a.extend(&p.qdd);
    part.f.extend(decimate(&p.force, r));
    if part.fd.is_empty() {
        part.fd = vec![Vec::new(); MAXD + 1];
    }
    let s = opt.drop_start.min(sub.force.len());
    for m in 0..=MAXD {
        let d: Vec<f64> = (s..sub.force.len())
            .map(|k| sub.force[k.saturating_sub(m)])
            .collect();
        part.fd[m].extend(decimate(&d, r));
    }
    part.u.extend(&sub.force[s..]);
    part.lens.push(p.q.len());
}

/// Columns are built at the full rate and decimated like the force (the IDIM-LS order), run
/// by run.
pub(super) fn dec(p: &Part, c: Vec<f64>) -> Vec<f64> {
    let r = IdimOptions::default().decimation;
    let mut out = Vec::with_capacity(c.len() / r.max(1) + p.lens.len());
    let mut at = 0;
    for &n in &p.lens {
        let end = (at + n).min(c.len());
        out.extend(decimate(&c[at..end], r));
        at = end;
    }
    out
}

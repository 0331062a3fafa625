//! The inverse-dynamics rows of a part of the runs (the fitting or the held-out part): each
//! run's moving stretches filtered, differentiated and decimated as the EMPS benchmark's
//! IDIM-LS does ([`crane_ident::emps::process`]), with the runs' force at the full rate
//! beside them: a delayed force ([`Part::delayed`]) and a dead band's force are built from it
//! on demand.

use crane_ident::data::AxisRun;
use crane_ident::emps::{process, IdimOptions};
use crane_ident::signal::decimate;

/// The inverse-dynamics rows of one part (fitting or held out), run segment after run
/// segment. Positions are in the data set's unit (m or rad), forces in N (N m on a rotary
/// axis: the input times the declared gain, the input itself without one); signs as
/// recorded. The kinematic columns are at the full rate (the first `drop_start` samples of
/// every segment dropped) and are decimated when a regressor is built from them ([`dec`]);
/// the force `f` is decimated already, a delayed force is decimated when it is built
/// ([`Part::delayed`]).
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
    /// Force before decimation [N], full rate: every appended run share whole (its rests
    /// and each segment's dropped start included: a delayed force reaches back into them),
    /// shares concatenated. Only shares with a moving segment are kept.
    raw: Vec<f64>,
    /// Where every appended run share with a moving segment lies in `raw` [samples].
    shares: Vec<std::ops::Range<usize>>,
    /// Every appended run segment (a moving part of a share), in order.
    pieces: Vec<Piece>,
    /// full-rate length of every appended run segment: columns are decimated run by run,
    /// like the force, so they stay aligned whatever the run lengths
    pub(super) lens: Vec<usize>,
}

/// One appended run segment of a [`Part`]: a moving part of a run share.
#[derive(Clone, Debug)]
struct Piece {
    /// Its force samples in [`Part::raw`], its dropped start included [samples].
    range: std::ops::Range<usize>,
    /// First sample of its run share in [`Part::raw`]: how far back a delay may reach.
    floor: usize,
    /// Samples dropped at its start (its rows begin there) [samples].
    drop: usize,
    /// Decimation factor of its rows.
    r: usize,
}

impl Part {
    /// The force [N] delayed by `m` samples, decimated like the rows, segment by segment:
    /// the row at sample `k` of a segment carries the force recorded at `k - m`, before the
    /// segment if need be (in its run share: a rest cut out of the rows, the dropped start),
    /// the share's first sample where `k - m` lies before the share. `delayed(0)` is `f`; for
    /// `m <= drop_start` (49 samples) every `k - m` lies in the segment, exactly as when the
    /// delayed forces were computed per segment.
    pub(super) fn delayed(&self, m: usize) -> Vec<f64> {
        let mut out = Vec::with_capacity(self.f.len());
        for pc in &self.pieces {
            let d: Vec<f64> = (pc.range.start + pc.drop..pc.range.end)
                .map(|i| self.raw[i.saturating_sub(m).max(pc.floor)])
                .collect();
            out.extend(decimate(&d, pc.r));
        }
        out
    }

    /// The force of the rows [N], full rate (every segment without its dropped start),
    /// segments concatenated: what [`dec`] decimates.
    pub(super) fn force_rows(&self) -> impl Iterator<Item = f64> + '_ {
        self.pieces.iter().flat_map(|pc| {
            self.raw[pc.range.start + pc.drop..pc.range.end]
                .iter()
                .copied()
        })
    }

    /// Length of the shortest run share with rows [samples, full rate] (0 without one): a
    /// whole run, or a time split's share of one. A delay reaches back within it only.
    pub(super) fn shortest_share(&self) -> usize {
        self.shares.iter().map(|s| s.len()).min().unwrap_or(0)
    }
}

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

/// Appends the moving parts ([`moving_parts`]) of `run[range]` to `part`, with the force of
/// the whole share (for [`Part::delayed`]) when there is one.
pub(super) fn append(
    part: &mut Part,
    run: &AxisRun,
    range: std::ops::Range<usize>,
    opt: &IdimOptions,
) {
    let pieces = moving_parts(run, range.clone(), opt);
    if pieces.is_empty() {
        return;
    }
    let floor = part.raw.len();
    part.raw.extend(&run.slice(range.clone()).force);
    part.shares.push(floor..part.raw.len());
    for piece in pieces {
        // the piece's first sample in `raw`
        let at = floor + (piece.start - range.start);
        append_part(part, run, piece, opt, at, floor);
    }
}

/// Appends one moving part `range` of `run`, whose force starts at `raw[at]`, in the share
/// starting at `raw[floor]`.
fn append_part(
    part: &mut Part,
    run: &AxisRun,
    range: std::ops::Range<usize>,
    opt: &IdimOptions,
    at: usize,
    floor: usize,
) {
    let sub = run.slice(range);
    let p = process(&sub, opt);
    let r = opt.decimation;
    part.q.extend(&p.q);
    part.v.extend(&p.qd);
    part.a.extend(&p.qdd);
    part.f.extend(decimate(&p.force, r));
    part.pieces.push(Piece {
        range: at..at + sub.force.len(),
        floor,
        drop: opt.drop_start.min(sub.force.len()),
        r,
    });
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

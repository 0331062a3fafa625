//! Stage 4: forward selection of the causes. Each round tries every cause not yet named on
//! top of the current model ([`super::trial`]), keeps those with physical parameters
//! ([`super::physical`]) that cut the held-out error enough, and names the best; it stops
//! when none does or the model is within the levels the data set ([`Context`]).

use super::cause::DRIVE_CAUSES;
use super::estimate::{Dir, Estimate};
use super::evidence::{cause_parameters, extra_parameters, force_rms};
use super::experiment::{at_floor, Baseline, Experiment};
use super::info::DriveInfo;
use super::physical::{delay_resolved, load_overlap, physical};
use super::score::{nmae_no_motion, Scored};
use super::trial::{try_cause, Search};
use crate::report::nmae_or_diverged::text as pct;
use crate::{Candidate, Cause, Evidence, Finding};
use rayon::prelude::*;
use std::collections::BTreeMap;

/// A cause is kept when it cuts the mean held-out simulated NMAE by at least this fraction.
pub const MIN_GAIN: f64 = 0.05;
/// Below this held-out simulated NMAE [%] the baseline is called right (`none`) when no
/// cause passes [`SMALL_GAIN`].
pub const NONE_LEVEL: f64 = 5.0;
/// `none` also needs the baseline's held-out error within this factor of what it leaves on
/// its own replayed log ([`super::floor`]); beyond it, below [`NONE_LEVEL`], the verdict is
/// `unexplained`: the data hold an effect the baseline does not model. The factor covers the
/// floor's own scatter: on the independent stranger plant (`tools/strangers/`), the 10 logs
/// with nothing hidden (5 uniform, 5 asynchronous with jitter and held channels) left 0.9-3.9
/// times their replayed floor (log-ratio 0.33 +- 0.54); 8 is twice the largest ratio seen, about
/// 3.5 standard deviations above the mean. A calibration on that plant, not a law.
pub const OWN_LOG_FACTOR: f64 = 8.0;
/// Below [`NONE_LEVEL`], while the baseline is within [`OWN_LOG_FACTOR`] of its own log's
/// floor, a first cause is named only when it removes at least this fraction
/// of the held-out error, cuts the error of every held-out run that moves, and passes the
/// output-error test against the refined baseline; no further cause is tried there. What is
/// left below 5 % is mostly estimation error, and any extra parameter trades against it: on
/// the rigs of `tests/strangers.rs`, where the truth is known, causes that were not there cut
/// 14-52 % of it; a hidden cause that the baseline had absorbed (a dead band taken up by the
/// Coulomb level, load-dependent friction by the inertia and gain) removed 91-96 %.
pub const SMALL_GAIN: f64 = 0.5;
/// Fewest motions (faster than the motion threshold, either direction) the fitting runs must
/// hold for a cause to be named.
pub const MIN_FIT_MOTIONS: usize = 2;

/// What the selection judges with: the runs, the baselines, and the levels measured on the
/// data (the encoder's floor, the own-log floor, the log's timing, the motions fitted).
pub(super) struct Context<'a> {
    /// The fitting and held-out runs and their thresholds.
    pub ex: &'a Experiment<'a>,
    /// What the data set says about the axis.
    pub info: &'a DriveInfo,
    /// The baseline, by least squares and refined by output error.
    pub base: &'a Baseline,
    /// The held-out NMAE the baseline leaves on its own replayed log [%]
    /// ([`super::floor::own_log`]; `None` where it could not be replayed, or where it is no
    /// floor: see [`Self::own_floor_failed`]).
    pub own_floor: Option<f64>,
    /// The own-log error [%] when it is above half of predicting no motion
    /// ([`Self::sel_no_motion`], [`super::floor::usable`]): the baseline then fails to fit
    /// even its own simulation, so that error measures the fit, not what the log resolves,
    /// and it is no floor.
    pub own_floor_failed: Option<f64>,
    /// The held-out NMAE of the encoder's own error [%] ([`super::floor::encoder`]).
    pub noise_floor: f64,
    /// Largest |input| of the fitting runs [input units].
    pub umax: f64,
    /// The fitting runs' sample period [s] (the shortest): delays are whole samples of it.
    pub dt: f64,
    /// The log's own timing uncertainty [samples]: the input is held over a sample while the
    /// position is read at its start (one sample), and a position refreshed every `r` rows
    /// is up to `r - 1` rows old.
    pub timing: usize,
    /// Motions from rest in the fitting runs, both directions.
    pub fit_motions: usize,
    /// The fitting runs move in one direction only.
    pub one_way: bool,
    /// Fewer than [`MIN_FIT_MOTIONS`] motions: one motion from rest cannot separate inertia,
    /// friction and an input effect (each trades against the others on a single slide).
    pub too_thin: bool,
    /// A direction the held-out runs move in and no fitting run does
    /// ([`super::checks::unseen_direction`]).
    pub unseen: Option<Dir>,
    /// Per held-out run, the NMAE of predicting no motion [%].
    pub no_motion: Vec<f64>,
    /// Its mean over the held-out runs the selection scores [%].
    pub sel_no_motion: f64,
}

impl<'a> Context<'a> {
    /// The levels of `ex` with its fitted `base`line.
    pub fn new(
        ex: &'a Experiment<'a>,
        info: &'a DriveInfo,
        base: &'a Baseline,
        own_floor: Option<f64>,
        prepared: &[super::prep::Prepared],
    ) -> Self {
        let (fit, held, th) = (&ex.fit, &ex.held, &ex.th);
        let no_motion: Vec<f64> = held.iter().map(|r| nmae_no_motion(r, th.quantum)).collect();
        let sel_no_motion = ex.selection_runs.iter().map(|&i| no_motion[i]).sum::<f64>()
            / ex.selection_runs.len() as f64;
        let umax = fit
            .iter()
            .flat_map(|p| p.run.u.iter())
            .fold(0.0f64, |m, u| m.max(u.abs()));
        let dt = fit.iter().map(|p| p.run.dt).fold(f64::INFINITY, f64::min);
        let motions_dir = |sign: f64| -> usize {
            fit.iter()
                .map(|p| super::prep::motions(&p.v, th.v_move, sign).len())
                .sum()
        };
        // an own log refitted barely better than predicting rest is no floor: causes are tried
        let (own_floor, own_floor_failed) = super::floor::usable(own_floor, sel_no_motion);
        let (fit_pos, fit_neg) = (motions_dir(1.0), motions_dir(-1.0));
        let fit_motions = fit_pos + fit_neg;
        let timing = prepared
            .iter()
            .map(|p| p.run.refresh)
            .max()
            .unwrap_or(1)
            .max(1);
        Context {
            ex,
            info,
            base,
            own_floor,
            own_floor_failed,
            noise_floor: super::floor::encoder(held, th),
            umax,
            dt,
            timing,
            fit_motions,
            // moving one way only, a restoring force and a friction that changes along the
            // travel are one force (below, at the finding)
            one_way: fit_pos == 0 || fit_neg == 0,
            too_thin: fit_motions < MIN_FIT_MOTIONS,
            unseen: super::checks::unseen_direction(fit, held, th),
            no_motion,
            sel_no_motion,
        }
    }

    /// The better of the two baselines by the held-out runs that move [%].
    pub fn base_best(&self) -> f64 {
        self.base.best_selection()
    }

    /// Whether a held-out error [%] is within [`OWN_LOG_FACTOR`] times the log's own floor
    /// (or the encoder's, if larger); false when there is no own floor.
    pub fn within_own_floor(&self, e: f64) -> bool {
        self.own_floor
            .is_some_and(|f| e <= OWN_LOG_FACTOR * f.max(self.noise_floor))
    }

    /// Whether a held-out error within [`NONE_LEVEL`] is also within [`OWN_LOG_FACTOR`] times
    /// the log's own floor (or the encoder's, if larger): only then is it `none`. Without an
    /// own floor there is nothing to compare with, and it is.
    pub fn consistent(&self, e: f64) -> bool {
        self.own_floor.is_none() || self.within_own_floor(e)
    }
}

/// What the forward selection found.
pub(super) struct Selection {
    /// The model with every named cause (the least-squares baseline when none is).
    pub current: Scored,
    /// The causes named, in the order named.
    pub findings: Vec<Finding>,
    /// Every cause tried, each round.
    pub candidates: Vec<Candidate>,
    /// Why causes were not named or not tried, one note per cause.
    pub notes: BTreeMap<Cause, String>,
}

/// One cause tried on top of the current model, and how it was judged.
struct Judged {
    /// The extended model, fitted and scored.
    scored: Scored,
    /// Its parameters are physical and not at a grid's edge.
    ok: bool,
    /// Why not, if not.
    why: Option<String>,
    /// It cuts the held-out error enough to be named.
    supported: bool,
    /// Against the refined baseline: its refined held-out NMAE [%] and cut (fraction).
    refined_cut: Option<(f64, f64)>,
    /// Why the output-error test failed, if it did.
    oe_note: Option<String>,
    /// The extended model refined by output error and scored, where the test ran.
    refined: Option<Scored>,
}

/// Forward selection from the least-squares baseline.
pub(super) fn forward(ctx: &Context<'_>, search: &Search<'_>) -> Selection {
    let mut sel = Selection {
        current: ctx.base.ls.clone(),
        findings: Vec::new(),
        candidates: Vec::new(),
        notes: BTreeMap::new(),
    };
    let mut used: Vec<Cause> = Vec::new();
    // per cause tried against the refined baseline: its refined held-out NMAE and cut
    let mut refined_cuts: BTreeMap<Cause, (f64, f64)> = BTreeMap::new();
    for _round in 0..DRIVE_CAUSES.len() {
        if ctx.too_thin || ctx.unseen.is_some() || stop(ctx, &mut sel) {
            break;
        }
        // the strict rule below NONE_LEVEL is for a residual that is estimation error: one
        // within OWN_LOG_FACTOR of what the baseline leaves on its own replayed log. Beyond
        // that the data hold an effect (the verdict would be `unexplained`), and a cause is
        // judged as above NONE_LEVEL (stranger s063: a Stribeck weakening cut 66 % of a
        // residual 18 times the floor and was refused for one run)
        let small = sel.current.selection <= NONE_LEVEL
            && ctx.consistent(sel.current.selection.min(ctx.base_best()));
        let mut best: Option<(Cause, Scored)> = None;
        // this round's candidates refined by output error, where the test ran
        let mut refined: BTreeMap<Cause, Scored> = BTreeMap::new();
        // stiction's held-out NMAE this round, if it was supported (see `prefer_stiction`)
        let mut stiction_sel: Option<Scored> = None;
        // the round's candidates are judged side by side (rayon: each judgement reads only
        // the round's state) and taken in DRIVE_CAUSES' order below: the same selection as
        // one after the other. A log with one fitting run simulates on one core, and this
        // keeps the other busy (the bench's delayed 10 kHz x 120 s log, release, idle: 62.3 s
        // -> 53.8-54.6 s, the same report; what is left is mostly the named delay's
        // output-error refinement, one simulation after another)
        let judged: Vec<(Cause, Option<Judged>)> = DRIVE_CAUSES
            .par_iter()
            .filter(|c| !used.contains(c))
            .map(|&c| (c, judge(ctx, search, c, &sel, small)))
            .collect();
        for (cause, j) in judged {
            let Some(j) = j else {
                continue;
            };
            if let Some(c) = j.refined_cut {
                refined_cuts.insert(cause, c);
            }
            if let Some(r) = j.refined.clone() {
                refined.insert(cause, r);
            }
            sel.candidates.push(Candidate {
                cause,
                axis: "axis".into(),
                parameters: cause_parameters(cause, &j.scored.est, ctx.dt, ctx.info),
                score: (j.scored.selection / sel.current.selection).ln(),
                force_delta_bic: 0.0,
                supported: j.supported,
            });
            if !j.ok {
                if let Some(w) = j.why {
                    sel.notes.insert(cause, w);
                }
                continue;
            }
            sel.notes.remove(&cause);
            if let Some(n) = j.oe_note {
                sel.notes.insert(cause, n);
            }
            if j.supported && cause == Cause::Stiction {
                stiction_sel = Some(j.scored.clone());
            }
            if j.supported
                && best
                    .as_ref()
                    .is_none_or(|b| j.scored.selection < b.1.selection)
            {
                best = Some((cause, j.scored));
            }
        }
        let Some((cause, scored)) = pick(ctx, &mut sel, best, stiction_sel, refined) else {
            break;
        };
        let f = finding(ctx, cause, &sel, &scored, refined_cuts.get(&cause));
        sel.findings.push(f);
        used.push(cause);
        sel.current = scored;
    }
    sel
}

/// The cause this round names: the supported one with the lowest held-out error
/// ([`prefer_stiction`]); a delay is settled first ([`settle_delay`]). A delay that settles
/// within a sample of the log's timing uncertainty ([`delay_resolved`], which [`physical`]
/// refuses too) was the least squares' bias standing in for a cause: nothing is named (with
/// a note, its candidate no longer supported), since the next best stands in for the same
/// bias (a 1 mm encoder count on a 1 kHz log: a 0.5-sample delay, then a saturation and a
/// bump, with nothing hidden).
fn pick(
    ctx: &Context<'_>,
    sel: &mut Selection,
    best: Option<(Cause, Scored)>,
    stiction: Option<Scored>,
    mut refined: BTreeMap<Cause, Scored>,
) -> Option<(Cause, Scored)> {
    let (cause, scored) = prefer_stiction(best, stiction)?;
    if cause != Cause::InputDelay {
        return Some((cause, scored));
    }
    let settled = settle_delay(ctx, scored, refined.remove(&cause));
    let (d, timing) = (settled.est.structure.delay, ctx.timing);
    if delay_resolved(d, timing) {
        return Some((cause, settled));
    }
    sel.notes.insert(
        cause,
        format!("input_delay: refined with the inertia and friction by output error, the delay is {d:.2} sample(s), within a sample of the log's own timing uncertainty ({timing}): the least squares' longer delay stood in for their bias"),
    );
    if let Some(c) = sel.candidates.iter_mut().rev().find(|c| c.cause == cause) {
        c.supported = false;
    }
    None
}

/// A named delay with the model's inertia, viscous and dry friction refined with it by output
/// error on the fitting runs ([`super::refine`]), kept when that cuts the held-out error. The
/// grid's delay is fitted by least squares at each point, whose derivative-based inertia can
/// be low (a held or jittered position): the missing inertial lag is then taken up by the
/// delay (stranger plants with 0.13-0.19 s delays: 3-24 % long, with the inertia 11-34 % low,
/// or 1,500 times, before this step).
///
/// `refined`: that refinement, where the output-error test of the selection already ran it.
fn settle_delay(ctx: &Context<'_>, scored: Scored, refined: Option<Scored>) -> Scored {
    refined
        .or_else(|| {
            ctx.ex
                .refine_delayed(&scored.est, ctx.dt)
                .and_then(|(est, _)| ctx.ex.score(est).ok())
        })
        .filter(|r| r.selection < scored.selection)
        .unwrap_or(scored)
}

/// Velocity weakening is stiction plus one parameter (the Stribeck velocity; at its lowest
/// value it is stiction): it is named over supported stiction only when it cuts stiction's
/// held-out NMAE by [`MIN_GAIN`] too, as any added parameter must; otherwise stiction is.
fn prefer_stiction(
    best: Option<(Cause, Scored)>,
    stiction: Option<Scored>,
) -> Option<(Cause, Scored)> {
    match (best, stiction) {
        (Some((Cause::StribeckFriction, s)), Some(st))
            if s.selection > (1.0 - MIN_GAIN) * st.selection =>
        {
            Some((Cause::Stiction, st))
        }
        (best, _) => best,
    }
}

/// Whether the selection stops before a round, noting why when no cause was tried.
fn stop(ctx: &Context<'_>, sel: &mut Selection) -> bool {
    let current = sel.current.selection;
    // a model that simulates the held-out runs within the encoder's own error leaves
    // nothing to explain. Above that, an error below NONE_LEVEL may still hide a cause
    // (a dead band that the Coulomb level absorbs while sliding leaves 4 % on a log whose
    // noise floor is 0.001 %); it is named only on stricter evidence (below)
    if current <= ctx.noise_floor {
        if sel.findings.is_empty() {
            let noise_floor = ctx.noise_floor;
            sel.notes.insert(
                Cause::InputDelay,
                format!("no cause tried: the baseline simulates the held-out runs at {current:.4} %, within the encoder's own error ({noise_floor:.4} %: half a count over the mean range)"),
            );
        }
        return true;
    }
    // nor does one that leaves no more than on its own replayed log: there the log
    // itself, not a missing effect, sets the error
    let base_best = ctx.base_best();
    if let Some(f) = ctx
        .own_floor
        .filter(|&f| sel.findings.is_empty() && base_best <= f)
    {
        sel.notes.insert(
            Cause::InputDelay,
            format!("no cause tried: the baseline simulates the held-out runs at {base_best:.4} %, no worse than it simulates its own replayed log ({f:.4} %: the baseline's simulation logged as these data were, and fitted again)"),
        );
        return true;
    }
    // after a first cause, a model within NONE_LEVEL is right: the first cause below it
    // must also pass the output-error test against the refined baseline (below), which
    // a further one would not get
    current <= NONE_LEVEL && !sel.findings.is_empty()
}

/// Tries `cause` on top of the current model and judges it; `small`: the current model is
/// within [`NONE_LEVEL`].
fn judge(
    ctx: &Context<'_>,
    search: &Search<'_>,
    cause: Cause,
    sel: &Selection,
    small: bool,
) -> Option<Judged> {
    let current = &sel.current;
    let (scored, edge) = try_cause(cause, current, search)?;
    let (ok, why) = if let Some(e) = &edge {
        // the best value may lie beyond what was tried: no finding
        (
            false,
            Some(format!(
                "{cause} not named: {e}; the best value may lie beyond the values tried"
            )),
        )
    } else if at_floor(&scored.est) {
        (
            false,
            Some(format!(
                "{cause}: with it the inertia is still not determined by the sliding samples (at its floor)"
            )),
        )
    } else {
        physical(cause, &scored.est, &current.est, ctx.umax, ctx.timing)
    };
    let gain = 1.0 - scored.selection / current.selection;
    // below NONE_LEVEL what is left is mostly estimation error, which any extra
    // parameter (a delay, a dead band, a tiny spring) trades against: there a cause
    // must remove most of the error (SMALL_GAIN) and cut that of every held-out run
    // that moves
    // (a run already within the log's own floor's scatter may move inside it: there the
    // log, not the model, sets its error)
    let every_run = ctx.ex.selection_runs.iter().all(|&i| {
        scored.per_run[i] < current.per_run[i] || ctx.within_own_floor(scored.per_run[i])
    });
    let mut supported = ok && gain >= MIN_GAIN && (!small || (every_run && gain >= SMALL_GAIN));
    let (mut refined_cut, mut oe_note, mut refined) = (None, None, None);
    if ok && !supported && gain >= MIN_GAIN {
        oe_note = Some(small_note(ctx, cause, &scored, current, gain, every_run));
    }
    // against the refined baseline, the candidate refined the same way: a cause must
    // cut the error whichever way the parameters are estimated (least squares against
    // least squares above, output error against output error here)
    if let Some(r) = ctx
        .base
        .refined
        .as_ref()
        .filter(|_| supported && sel.findings.is_empty())
    {
        refined = ctx
            .ex
            .refine_delayed(&scored.est, ctx.dt)
            .and_then(|(est, _)| ctx.ex.score(est).ok());
        let oe = refined
            .as_ref()
            .map_or(scored.selection, |c| c.selection.min(scored.selection));
        let gain_oe = 1.0 - oe / r.selection;
        refined_cut = Some((oe, gain_oe));
        supported = gain_oe >= MIN_GAIN;
        if !supported {
            oe_note = Some(format!(
                    "{cause}: cuts the least-squares baseline's held-out NMAE by {:.0} % but, both refined by output error on the fitting runs, {} -> {} ({:.0} %): it stands in for the least squares' bias",
                    100.0 * gain,
                    pct(r.selection, 2),
                    pct(oe, 2),
                    100.0 * gain_oe
            ));
        }
    }
    Some(Judged {
        scored,
        ok,
        why,
        supported,
        refined_cut,
        oe_note,
        refined,
    })
}

/// Why a physical candidate that cuts the held-out error is still not named below
/// [`NONE_LEVEL`]: it must remove [`SMALL_GAIN`] of the error and cut every moving held-out
/// run's.
fn small_note(
    ctx: &Context<'_>,
    cause: Cause,
    scored: &Scored,
    current: &Scored,
    gain: f64,
    every_run: bool,
) -> String {
    let worse: Vec<String> = ctx
        .ex
        .selection_runs
        .iter()
        .filter(|&&i| {
            scored.per_run[i] >= current.per_run[i] && !ctx.within_own_floor(scored.per_run[i])
        })
        .map(|&i| {
            format!(
                "{} {} -> {}",
                ctx.ex.held[i].run.name,
                pct(current.per_run[i], 2),
                pct(scored.per_run[i], 2)
            )
        })
        .collect();
    format!(
        "{cause} not named: it cuts the held-out NMAE by {:.0} % ({} -> {}), but below {NONE_LEVEL} % a cause must remove {:.0} % of the error and cut that of every held-out run that moves, unless the run stays within {OWN_LOG_FACTOR} times the log's own floor{}",
        100.0 * gain,
        pct(current.selection, 2),
        pct(scored.selection, 2),
        100.0 * SMALL_GAIN,
        if every_run {
            String::new()
        } else {
            format!(" (not: {})", worse.join(", "))
        }
    )
}

/// The finding of `cause`, named with its model `scored` over the current one; `refined_cut`:
/// its refined held-out NMAE [%] and cut against the refined baseline (first cause only).
fn finding(
    ctx: &Context<'_>,
    cause: Cause,
    sel: &Selection,
    scored: &Scored,
    refined_cut: Option<&(f64, f64)>,
) -> Finding {
    let (current, held, th) = (&sel.current, &ctx.ex.held, &ctx.ex.th);
    let mut note = format!(
        "held-out simulated position NMAE {} -> {} over the {} held-out runs that move ({} -> {} over all {})",
        pct(current.selection, 2),
        pct(scored.selection, 2),
        ctx.ex.selection_runs.len(),
        pct(current.nmae, 2),
        pct(scored.nmae, 2),
        held.len()
    );
    if let (Some(r), Some((oe, g))) = (
        ctx.base
            .refined
            .as_ref()
            .filter(|_| sel.findings.is_empty()),
        refined_cut,
    ) {
        note.push_str(&format!(
            "; both refined by output error on the fitting runs: {} -> {} ({:.0} % cut)",
            pct(r.selection, 2),
            pct(*oe, 2),
            100.0 * g
        ));
    }
    if cause == Cause::InputSaturation {
        note.push_str(&saturation_note(ctx, &scored.est));
    }
    let (mut identifiable, overlap) = load_overlap(cause, &scored.est);
    if let Some(o) = overlap {
        note.push_str("; ");
        note.push_str(o);
    }
    if cause == Cause::RestoringForce && ctx.one_way {
        // A load keeps its sign when the motion reverses, friction does not: only runs in
        // both directions tell them apart. One way, `k s(x)` and a dry level rising or
        // falling along the travel (creep, wear, a tighter stretch of the screw) are the
        // same force (CICESE joint 1's positive ramps alone: k 145 N m/rad, against 49
        // from both directions and gravity's 40).
        identifiable = false;
        note.push_str("; not identifiable apart from position-dependent friction: the fitting runs move in one direction only, where a restoring force and a friction level that changes along the travel are the same force; runs in both directions would separate them (a load keeps its sign when the motion reverses, friction does not)");
    }
    Finding {
        cause,
        axis: "axis".into(),
        parameters: cause_parameters(cause, &scored.est, ctx.dt, ctx.info),
        nmae_before: current.selection,
        nmae_after: scored.selection,
        evidence: Evidence {
            force_delta_bic: 0.0,
            force_rms_before_n: force_rms(&current.est, held, th),
            force_rms_after_n: force_rms(&scored.est, held, th),
            score: (scored.selection / current.selection).ln(),
            extra_parameters: extra_parameters(cause),
            held_out_samples: held.iter().map(|r| r.run.x.len()).sum(),
            identifiable,
            note,
        },
    }
}

/// How much of the fitting runs' moving samples a saturation level clips, for its finding.
fn saturation_note(ctx: &Context<'_>, est: &Estimate) -> String {
    let sat = est.structure.saturation;
    let (mut n, mut clipped) = (0usize, 0usize);
    for p in ctx.ex.fit.iter() {
        for i in 0..p.run.x.len() {
            if p.v[i].abs() > ctx.ex.th.v_move {
                n += 1;
                let u = super::estimate::delayed(&p.run.u, i, est.structure.delay);
                clipped += usize::from(u.abs() > sat);
            }
        }
    }
    format!(
        "; the applied effort saturates at +-{sat:.4} {} (the largest recorded |input| of the fitting runs is {:.4}; {:.1} % of their moving samples lie beyond the level)",
        ctx.info.force_unit,
        ctx.umax,
        100.0 * clipped as f64 / n.max(1) as f64
    )
}

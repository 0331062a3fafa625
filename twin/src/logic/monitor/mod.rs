//! The friction monitor: while the crane runs, a map of what the twin's friction model gets
//! wrong, per drive axis, direction and position, and alarms when it changes.
//!
//! Every period [`Monitor::update`] takes the observer (positions, velocities, modes, the
//! disturbance force `d` and the residual mean square) and the voltages applied:
//! - an axis that slides, settled (the observer's transient after a restart has decayed to 1 %)
//!   and faster than two encoder steps per period, adds the residual friction `-d sign(v)` [N]
//!   to the map of its direction ([`map::SlidingMap`]);
//! - an axis that rests feeds its breakaway watch ([`breakaway::BreakawayWatch`]);
//! - the residual mean square feeds a slow level per axis.
//!
//! Commissioning ends on coverage, not on a clock ([`Monitor::commissioned`]): until every
//! watched axis has, in each direction, [`Settings::restarts_learn`] restarts and
//! [`Settings::level_learn`] moves over at least [`MOVE_BINS`] judged bins (each with
//! [`map::MapSettings::judged`] samples), and the residual level has learned over
//! [`RESIDUAL_LEARN`] periods, nothing is judged; the maps learn their reference (what the
//! identified model still misses on this rig) and their bands (how much the current levels
//! scatter around it in normal operation). How long that takes follows how the crane is
//! operated. Afterwards references and bands follow slow changes (a temperature drift over an
//! hour) while no alarm of their map stands.
//!
//! Evaluation: one of the four maps (axis, direction) per period, round robin, O(64) work
//! (one branch-free pass over the map marks the bins out of band, [`map::SlidingMap::out_of_band`];
//! only those are read again).
//! Every threshold is [`Settings::k`] standard deviations of a learned scatter, never a force
//! constant: the monitor is as sensitive as the rig is quiet. Alarms
//! ([`alarm::AlarmKind`]) are debounced ([`alarm::Debounce`]): a condition must hold in two
//! evaluations with fresh data between them (a new pass over a bin, half a memory of the
//! travel level, a new restart, half a second of residual).
//!
//! State: everything lives in this struct (about 6.9 KiB, see [`Monitor::RAM_BYTES`]), no heap,
//! `f32` statistics whatever the twin's scalar type. It is not kept over a reset: after a
//! watchdog reset the firmware builds a new monitor, which commissions again and judges
//! nothing meanwhile (an alarm that stood is raised again if its cause is still there).

pub mod alarm;
pub mod breakaway;
pub mod frame;
pub mod inspect;
mod local;
pub mod map;
mod median;
mod settings;

use super::observer::Observer;
use alarm::{Alarm, AlarmKind, Debounce};
use breakaway::{BreakawayWatch, Limits, Sense};
use crane_model::friction::dry_at;
use crane_model::{Axis, Direction, Mode, Real};
use local::{local_pattern, Judged, Local};
use map::{SlidingMap, BINS};
use median::median_of_split_keys;
pub use settings::Settings;

/// Drive axes watched: the trolley's X and Y. The rope drive is not watched: its residual
/// carries the payload's weight and the swing's tension, not only friction, and it moves in
/// few operations, so its maps stay thin (measured: the host scenarios gave 0.3 false alarms
/// an hour from the rope's maps alone, twin/README.md "Friction monitor").
pub const AXES: [Axis; 2] = [Axis::X, Axis::Y];

/// Number of watched axes.
const N: usize = AXES.len();

// The monitor's memory bound (issue 21: the maps under 8 KiB), on every target.
const _: () = assert!(Monitor::RAM_BYTES < 8 * 1024);

/// Freshness and debounce of one map's checks.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Checks {
    drift: Debounce,
    /// Whether the last travel level out of band was above its reference.
    drift_up: bool,
    local: Debounce,
    stiction: Debounce,
    /// Bins crossed by the current slide (lowest, highest).
    span: Option<(u8, u8)>,
    /// Bin of the local candidate, and passes over it since the check was last fed.
    candidate: Option<usize>,
    passes: u16,
    entered: bool,
    last_bin: usize,
    /// Mean band of the judged bins at the last evaluation [N^2] (floor of every bin's band).
    pooled: f32,
    /// Learned variance of the travel's level [N^2], and the evaluations it learned from.
    level_band: f32,
    level_n: u32,
    /// The level at the last evaluation [N].
    level: f32,
}

/// What commissioning has seen of one axis and direction ([`Monitor::coverage`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Coverage {
    /// Restarts from rest whose breakaway was learned.
    pub restarts: u16,
    /// Moves that gave the travel's level (each over at least [`MOVE_BINS`] judged bins).
    pub moves: u32,
    /// Bins with enough samples to be judged ([`MapSettings::judged`](map::MapSettings::judged)).
    pub judged: u8,
}

/// Weight of a move's level in its band once learned: about 256 moves.
const LEVEL_SLOW: f32 = 1.0 / 256.0;
/// Judged bins a move must cross to give a level (a median of fewer is no travel level: a
/// rough spot of up to `local_bins` would move it).
pub const MOVE_BINS: usize = 9;

/// The slow level of one axis' residual mean square.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct ResidualWatch {
    /// The level is out of its band now (the twin does not track the plant).
    out: bool,
    level: f32,
    mean: f32,
    var: f32,
    n: u32,
    debounce: Debounce,
}

/// Weight per period of the residual level: one second at 2 ms.
const RESIDUAL_WEIGHT: f32 = 1.0 / 500.0;
/// Periods between two checks of the residual level (half its memory).
const RESIDUAL_EVERY: u16 = 250;
/// Periods over which the residual level's mean and scatter are learned (after it forgot its
/// start) before commissioning may end: ten of its memories.
pub const RESIDUAL_LEARN: u32 = (10.0 / RESIDUAL_WEIGHT) as u32;
/// Periods the residual level needs to forget its start: five memories.
const RESIDUAL_START: u32 = (5.0 / RESIDUAL_WEIGHT) as u32;

/// The monitor of the three drive axes.
#[derive(Clone, Debug)]
pub struct Monitor {
    settings: Settings,
    maps: [[SlidingMap; 2]; N],
    checks: [[Checks; 2]; N],
    breakaway: [BreakawayWatch; N],
    /// Mass [kg] an axis sets moving from rest (its diagonal inertia less the payload, which
    /// hangs and follows only later).
    mass: [f32; N],
    residual: [ResidualWatch; N],
    sliding_for: [u32; N],
    last_dir: [Option<usize>; N],
    pending: [Option<Alarm>; 4],
    period: u64,
    /// `period % RESIDUAL_EVERY`, counted along with `period` (and frozen with it if it ever
    /// saturates): a 64-bit remainder is a library call on the Cortex-M4, this a compare.
    residual_phase: u16,
    /// Commissioning is over (latched: it ends once).
    commissioned: bool,
}

fn dir_of(d: usize) -> Direction {
    if d == 1 {
        Direction::Positive
    } else {
        Direction::Negative
    }
}

fn mode_of(d: usize) -> Mode {
    if d == 1 {
        Mode::Positive
    } else {
        Mode::Negative
    }
}

impl Monitor {
    /// RAM of a monitor [bytes]: the four maps (X and Y, each direction) are most of it,
    /// 1,564 bytes each. Below 8 KiB, checked when this crate compiles.
    pub const RAM_BYTES: usize = core::mem::size_of::<Monitor>();

    /// A monitor of a twin whose observer is `obs` (its travel limits set the maps), with
    /// `settings`.
    pub fn new<R: Real>(obs: &Observer<R>, settings: Settings) -> Self {
        let ax = &obs.twin().coeffs().axes;
        let travel = |i: usize| (ax[i].min.to_f64() as f32, ax[i].max.to_f64() as f32);
        let c = obs.twin().coeffs();
        let mass = [
            (c.m00 - c.mp).to_f64() as f32,
            (c.m11 - c.mp).to_f64() as f32,
        ];
        Self::with_travel([travel(0), travel(1)], mass, settings)
    }

    /// A monitor of a twin with parameters `params` (the same as [`Monitor::new`] for an
    /// observer built with them): for a monitor placed in a static before the loop starts.
    pub fn for_params(params: &crane_model::Params, settings: Settings) -> Self {
        let axes = params.axes();
        let travel = |i: usize| (axes[i].min as f32, axes[i].max as f32);
        let c = crane_model::Coeffs::<f64>::new(params);
        let mass = [(c.m00 - c.mp) as f32, (c.m11 - c.mp) as f32];
        Self::with_travel([travel(0), travel(1)], mass, settings)
    }

    /// An empty monitor whose maps cover `travel` `(lo, hi)` [m] per watched axis, whose axes
    /// set `mass` [kg] moving from rest.
    fn with_travel(travel: [(f32, f32); N], mass: [f32; N], settings: Settings) -> Self {
        Monitor {
            settings,
            maps: travel.map(|(lo, hi)| [SlidingMap::new(lo, hi), SlidingMap::new(lo, hi)]),
            checks: [[Checks::default(); 2]; N],
            breakaway: [BreakawayWatch::default(); N],
            mass,
            residual: [ResidualWatch::default(); N],
            sliding_for: [0; N],
            last_dir: [None; N],
            pending: [None; 4],
            period: 0,
            residual_phase: 0,
            commissioned: false,
        }
    }

    /// The settings.
    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    /// The map of `axis` for direction `dir` (`Positive` or `Negative`; `Both` gives the
    /// positive one); `None` for an axis not watched.
    pub fn map(&self, axis: Axis, dir: Direction) -> Option<&SlidingMap> {
        let d = usize::from(dir != Direction::Negative);
        self.maps.get(axis.index()).map(|m| &m[d])
    }

    /// The travel's level of `axis` and `dir` at its last evaluation [N] (the median change
    /// of the judged bins against their reference) and its learned variance [N^2].
    pub fn level(&self, axis: Axis, dir: Direction) -> Option<(f32, f32)> {
        let d = usize::from(dir != Direction::Negative);
        let c = &self.checks.get(axis.index())?[d];
        Some((c.level, c.level_band))
    }

    /// The breakaway watch of `axis` (`None` for an axis not watched).
    pub fn breakaway(&self, axis: Axis) -> Option<&BreakawayWatch> {
        self.breakaway.get(axis.index())
    }

    /// Whether commissioning is over: at least [`Settings::commissioning`] periods, and the
    /// coverage of [`Monitor::covered`] was reached (it ends once, and the monitor judges from
    /// then on).
    pub fn commissioned(&self) -> bool {
        self.commissioned
    }

    /// Periods seen.
    pub fn period(&self) -> u64 {
        self.period
    }

    /// What commissioning has seen of `axis` moving in `dir` (`Both` gives the positive
    /// direction); `None` for an axis not watched.
    pub fn coverage(&self, axis: Axis, dir: Direction) -> Option<Coverage> {
        let i = AXES.iter().position(|a| *a == axis)?;
        let d = usize::from(dir != Direction::Negative);
        let s = &self.settings.map;
        let map = &self.maps[i][d];
        Some(Coverage {
            restarts: self.breakaway[i].restarts(d),
            moves: self.checks[i][d].level_n,
            judged: (0..BINS).filter(|b| map.view(*b, s).judged).count() as u8,
        })
    }

    /// Whether the statistics every check needs are learned: on every watched axis and in
    /// each direction the breakaway ratio over [`Settings::restarts_learn`] restarts and the
    /// travel's level over [`Settings::level_learn`] moves that each crossed at least
    /// [`MOVE_BINS`] judged bins (bins with
    /// [`MapSettings::judged`](map::MapSettings::judged) samples), and the residual level of
    /// every axis over [`RESIDUAL_LEARN`] periods.
    pub fn covered(&self) -> bool {
        let residual = self
            .residual
            .iter()
            .all(|w| w.n >= RESIDUAL_START.saturating_add(RESIDUAL_LEARN));
        residual
            && (0..N).all(|i| {
                (0..2).all(|d| {
                    self.checks[i][d].level_n >= self.settings.level_learn
                        && self.breakaway[i].restarts(d) >= self.settings.restarts_learn
                })
            })
    }

    /// Whether the monitor judges everything it watches: commissioning is over
    /// ([`Monitor::commissioned`]). Until then a change is learned as the reference, not
    /// alarmed: a fault that begins before it goes unseen. How long that takes depends on how
    /// the crane is operated (the moves' coverage of the travel), not on a clock.
    pub fn ready(&self) -> bool {
        self.commissioned
    }

    /// Whether the monitor judges the friction map of `axis` now: its residual is within its
    /// learned band and no `model_mismatch` of it stands (otherwise the map measures the model's
    /// error, not the friction, and no friction alarm of the axis is decided). `false` for an
    /// axis without a map (the rope).
    pub fn judging(&self, axis: Axis) -> bool {
        AXES.iter()
            .position(|a| *a == axis)
            .is_some_and(|i| !self.untracked(i))
    }

    /// One control period, after the observer's update: `applied` are the voltages [V] the
    /// drivers applied during the period the observer just predicted. Returns an alarm raised
    /// in this period or earlier and not yet returned (at most one per call).
    pub fn update<R: Real>(&mut self, obs: &Observer<R>, applied: [R; 3]) -> Option<Alarm> {
        if !self.commissioned && self.period >= self.settings.commissioning && self.covered() {
            self.commissioned = true;
        }
        let learning = !self.commissioned;
        let pull = self.swing_pull(obs);
        for (i, p) in pull.iter().enumerate() {
            self.axis_period(obs, i, applied[i], *p, learning);
        }
        let slot = (self.period % (2 * N as u64)) as usize;
        self.evaluate(slot / 2, slot % 2, learning);
        if !learning && self.residual_phase == 0 {
            for i in 0..N {
                self.evaluate_residual(i);
            }
        }
        if let Some(next) = self.period.checked_add(1) {
            self.period = next;
            self.residual_phase += 1;
            if self.residual_phase == RESIDUAL_EVERY {
                self.residual_phase = 0;
            }
        }
        self.pop()
    }

    /// One period of axis `i`: its breakaway watch, a map sample when it slides, its
    /// residual level. `pull` is the payload's pull on it [N].
    fn axis_period<R: Real>(
        &mut self,
        obs: &Observer<R>,
        i: usize,
        applied: R,
        pull: f32,
        learning: bool,
    ) {
        let state = obs.state();
        let ax = &obs.twin().coeffs().axes[i];
        let x = state.q[i].to_f32();
        let v = state.qd[i].to_f32();
        let d = obs.disturbance()[i].to_f32();
        let force = (ax.gain * applied).to_f32() + pull;
        let dir = match obs.modes()[i] {
            Mode::Positive => Some(1usize),
            Mode::Negative => Some(0usize),
            Mode::Stopped => None,
        };
        // The encoder's reading [m] (the estimate plus the observer's innovation times
        // `1 - alpha`) is used only by a watch that rests ([`BreakawayWatch::period`] reads
        // it then and only then): computed only for such an axis, `x` otherwise.
        let reading = if self.breakaway[i].resting() {
            x + self.settings.reading_gain * obs.innovation()[i].to_f32()
        } else {
            x
        };
        let sense = Sense {
            stopped: dir.is_none(),
            x,
            reading,
            force,
        };
        let limits = Limits {
            band: self.settings.band[i],
            quantum: self.settings.quantum[i],
            min_stop: self.settings.min_stop,
        };
        if let Some(b) = self.breakaway[i].period(sense, limits) {
            let model = dry_at(ax, mode_of(b.dir), state.q[i]).to_f32();
            let force = b.estimate(self.mass[i], self.settings.quantum[i], self.settings.period);
            self.restart(i, b.dir, x, force, model, learning);
        }
        if self.last_dir[i].is_some() && self.last_dir[i] != dir {
            if let Some(dl) = self.last_dir[i] {
                self.move_done(i, dl, learning);
            }
            self.sliding_for[i] = 0;
        }
        self.last_dir[i] = dir;
        match dir {
            None => {}
            Some(dj) => {
                self.sliding_for[i] = self.sliding_for[i].saturating_add(1);
                let speed = if v < 0.0 { -v } else { v };
                if self.sliding_for[i] >= self.settings.settle
                    && speed >= self.settings.v_min[i]
                    && x.is_finite()
                    && d.is_finite()
                {
                    let r = if dj == 1 { -d } else { d };
                    self.sample(i, dj, x - v * self.settings.lag, speed, r);
                }
            }
        }
        let m = obs.residual_mean_square()[i].to_f32();
        if m.is_finite() {
            self.residual_sample(i, m, learning);
        }
    }

    /// The payload's horizontal pull on the trolley [N] along X and Y (rope tension times the
    /// rope's direction), needed only while X or Y rests past its stop transient: one
    /// evaluation of the dynamics then, none otherwise.
    fn swing_pull<R: Real>(&self, obs: &Observer<R>) -> [f32; N] {
        let resting = self.breakaway.iter().any(BreakawayWatch::resting);
        if !resting {
            return [0.0; N];
        }
        let q = obs.state().q;
        let l = q[2];
        match obs.twin().output() {
            Ok(o) if l > R::ZERO => {
                let t = o.tension / l;
                [
                    (t * (o.payload[0] - q[0])).to_f32(),
                    (t * (o.payload[1] - q[1])).to_f32(),
                ]
            }
            _ => [0.0; N],
        }
    }

    /// A restart of axis `i` in direction `dj` at `x` after withstanding `push` [N], where
    /// the model's dry friction is `model` [N]: one breakaway ratio against the sliding
    /// friction seen there (the model plus the map's current level, or its reference while
    /// the bin is thin).
    fn restart(&mut self, i: usize, dj: usize, x: f32, push: f32, model: f32, learning: bool) {
        let map = &self.maps[i][dj];
        let b = map.bin(x);
        let seen = if map.count(b) > self.settings.map.warm {
            map.current(b)
        } else {
            map.reference(b)
        };
        let sliding = model + seen;
        if sliding > 0.25 * model && sliding > 0.0 {
            // Once learned, the statistics follow only a recent ratio within half the alarm
            // threshold of them, while no stiction alarm stands: a rise is not taught once it
            // is half-way to an alarm, however slowly it comes. (With the whole threshold as
            // the gate, a ratio rising 1.0 -> 1.8 on the independent plant taught its learned
            // mean 0.2 and its scatter 30 % before it was raised, which halved its score.)
            let k2 = 0.25 * self.settings.k * self.settings.k;
            let inside = self.breakaway[i].inside(dj, self.settings.restarts_learn, k2);
            let learn = learning || (inside && !self.checks[i][dj].stiction.standing());
            self.breakaway[i].record(dj, push / sliding, learn, self.settings.restarts_learn);
        }
    }

    fn sample(&mut self, i: usize, dj: usize, x: f32, speed: f32, r: f32) {
        let c = &mut self.checks[i][dj];
        let track = !(c.drift.standing() || c.local.standing());
        let b = self.maps[i][dj].add(x, speed, r, &self.settings.map, track);
        let bb = b as u8;
        c.span = Some(match c.span {
            Some((lo, hi)) => (lo.min(bb), hi.max(bb)),
            None => (bb, bb),
        });
        if let Some(cb) = c.candidate {
            // A pass over the candidate counts once it is complete (the axis entered it after
            // the candidate was set, and left it), so the evaluation after it sees bins updated
            // by a whole new pass.
            let near = |a: usize| a + 1 >= cb && a <= cb + 1;
            if near(b) && !near(c.last_bin) {
                c.entered = true;
            } else if !near(b) && near(c.last_bin) && c.entered {
                c.entered = false;
                c.passes = c.passes.saturating_add(1);
            }
        }
        c.last_bin = b;
    }

    fn residual_sample(&mut self, i: usize, m: f32, learning: bool) {
        let w = &mut self.residual[i];
        w.level += RESIDUAL_WEIGHT * (m - w.level);
        // Learn the level's mean and scatter once it has forgotten its start (5 memories).
        let start = RESIDUAL_START;
        w.n = w.n.saturating_add(1);
        if learning && w.n > start {
            let k = (w.n - start) as f32;
            let d = w.level - w.mean;
            w.mean += d / k;
            w.var += (d * (w.level - w.mean) - w.var) / k;
        }
    }

    fn push(&mut self, alarm: Alarm) {
        if let Some(slot) = self.pending.iter_mut().find(|p| p.is_none()) {
            *slot = Some(alarm);
        }
    }

    /// The oldest pending alarm. The pending alarms are a prefix of `pending` ([`Monitor::push`]
    /// fills the first free slot, this takes the first and shifts the rest down), so an empty
    /// first slot means none is pending: then nothing is moved (the common case, every period).
    fn pop(&mut self) -> Option<Alarm> {
        self.pending[0]?;
        let first = self.pending[0].take();
        self.pending.rotate_left(1);
        first
    }

    /// Evaluates the map of axis `i`, direction `dj` (round robin, after commissioning): a
    /// local pattern and the breakaway ratio.
    fn evaluate(&mut self, i: usize, dj: usize, learning: bool) {
        if learning || self.untracked(i) {
            return;
        }
        let local = self.local_check(i, dj);
        let stiction = self.stiction_check(i, dj);
        for (kind, direction) in [local, stiction].into_iter().flatten() {
            self.raise(i, kind, direction);
        }
    }

    /// Whether the twin does not track axis `i` now (its residual level out of band, or a
    /// `model_mismatch` of the axis stands): its friction map then measures the model's error,
    /// not the friction, and is not judged.
    fn untracked(&self, i: usize) -> bool {
        self.residual[i].out || self.residual[i].debounce.standing()
    }

    fn raise(&mut self, i: usize, kind: AlarmKind, direction: Direction) {
        self.push(Alarm {
            kind,
            axis: AXES[i],
            direction,
            period: self.period,
        });
    }

    /// A slide of axis `i` in direction `dj` ended: the travel's level seen by that move, the
    /// median change of the judged bins it crossed (a rough spot moves a few bins, not the
    /// median; bins the move did not cross are not stale evidence). Moves over fewer than
    /// [`MOVE_BINS`] judged bins give no level. The level's band is its variance over moves,
    /// learned over [`Settings::level_learn`] moves, then tracked slowly by the levels inside it while
    /// no alarm of the map stands. Also refreshes the pooled band (mean band of the judged bins).
    ///
    /// Cost (this and an evaluation in one period make the monitor's worst case): one pass
    /// over the map's 64 bins ([`SlidingMap::judged_bands`]: the judged bands summed in bin
    /// order, the crossed deviations keyed and split around the previous level) and one
    /// selection among the part that holds the median ([`median_of_split_keys`]). The level,
    /// the pooled band and every decision are the same, bit for bit, as from a loop over
    /// [`SlidingMap::view`] and `select_nth_unstable_by(n / 2, f32::total_cmp)`.
    fn move_done(&mut self, i: usize, dj: usize, learning: bool) {
        let s = self.settings.map;
        let k2 = self.settings.k * self.settings.k;
        self.maps[i][dj].end_move();
        let map = &self.maps[i][dj];
        let c = &mut self.checks[i][dj];
        let Some((lo, hi)) = c.span.take() else {
            return;
        };
        // The crossed deviations are split around the previous level (a pivot near the new
        // median: the selection then works on about half of them).
        let mut keys = [0i32; BINS];
        let pivot = map::total_key(c.level);
        let found = map.judged_bands(&s, usize::from(lo), usize::from(hi), pivot, &mut keys);
        if found.judged > 0 {
            c.pooled = found.sum / found.judged as f32;
        }
        if found.below + found.above < MOVE_BINS {
            return;
        }
        let level = median_of_split_keys(&mut keys, found.below, found.above);
        c.level = level;
        let standing = c.drift.standing() || c.local.standing();
        let learned = c.level_n >= self.settings.level_learn;
        let inside = level * level <= k2 * c.level_band;
        if !learned || (!standing && inside) {
            c.level_n = c.level_n.saturating_add(1);
            let w = 1.0 / c.level_n as f32;
            let w = if w > LEVEL_SLOW { w } else { LEVEL_SLOW };
            c.level_band += w * (level * level - c.level_band);
        }
        if learning || !learned {
            return;
        }
        if self.untracked(i) {
            return;
        }
        let c = &mut self.checks[i][dj];
        // A drift is a change of one sign: a level out of band the other way from the last
        // one starts the confirmation again (measured: a clean hour on the independent plant
        // raised one from two moves 5 sd out, -0.085 N then +0.084 N).
        let up = level > 0.0;
        if !inside && c.drift.pending() && up != c.drift_up {
            c.drift.feed(false);
        }
        if !inside {
            c.drift_up = up;
        }
        if c.drift.feed(!inside) {
            self.raise(i, AlarmKind::FrictionDrift { change: level }, dir_of(dj));
        }
    }

    /// A local pattern: a few bins out of band against the travel's level and their
    /// neighbours, confirmed by a later pass over the same place (or by the other direction's
    /// map flagging the same place: a pass the other way is an independent one).
    fn local_check(&mut self, i: usize, dj: usize) -> Option<(AlarmKind, Direction)> {
        let s = self.settings.map;
        let k2 = self.settings.k_local * self.settings.k_local;
        let map = &self.maps[i][dj];
        let other = self.checks[i][1 - dj];
        // While the whole travel's level is changing (a drift check of the axis pending or
        // standing) the bins not yet revisited look local: judge no local pattern then.
        let moving = self.checks[i]
            .iter()
            .any(|m| m.drift.pending() || m.drift.standing());
        let c = &mut self.checks[i][dj];
        if c.level_n == 0 || moving {
            return None;
        }
        let local = match local_pattern(map, &s, c.level, c.pooled, k2, self.settings.local_bins) {
            Judged::Local(l) => Some(l),
            Judged::Clear => None,
            Judged::Unjudged => return None,
        };
        let near = |a: usize, b: usize| a + 1 >= b && a <= b + 1;
        let seconded = |l: &Local| {
            other.candidate.is_some_and(|ob| near(l.peak, ob))
                && (other.local.pending() || other.local.standing())
        };
        let alarm = |l: &Local, both: bool| {
            let kind = AlarmKind::LocalFriction {
                position: l.position,
                width: l.width,
                change: l.change,
            };
            (kind, if both { Direction::Both } else { dir_of(dj) })
        };
        match (local, c.candidate) {
            (Some(l), Some(cb)) if near(l.peak, cb) => {
                if c.passes > 0 {
                    c.passes = 0;
                    return c.local.feed(true).then(|| alarm(&l, false));
                }
                None
            }
            (Some(l), _) => {
                c.local = Debounce::default();
                c.candidate = Some(l.peak);
                c.passes = 0;
                c.entered = false;
                c.local.feed(true);
                if seconded(&l) && !other.local.standing() {
                    return c.local.feed(true).then(|| alarm(&l, true));
                }
                None
            }
            (None, Some(_)) => {
                if c.passes > 0 {
                    c.passes = 0;
                    c.local.feed(false);
                    if !c.local.standing() && !c.local.pending() {
                        c.candidate = None;
                    }
                }
                None
            }
            (None, None) => None,
        }
    }

    /// Breakaway: after a new restart, the recent ratio against the learned one. The recent
    /// ratio forgets with weight `RECENT`, so its variance is `var * RECENT / (2 - RECENT)`
    /// for independent restarts.
    fn stiction_check(&mut self, i: usize, dj: usize) -> Option<(AlarmKind, Direction)> {
        let k2 = self.settings.k * self.settings.k;
        if !self.breakaway[i].take_fresh(dj) {
            return None;
        }
        let (mean, var, cur) = self.breakaway[i].stats(dj, self.settings.restarts_learn)?;
        let band = breakaway::recent_band(var);
        let e = cur - mean;
        self.checks[i][dj]
            .stiction
            .feed(e > 0.0 && e * e > k2 * band)
            .then_some((
                AlarmKind::StictionRise {
                    ratio: cur,
                    learned: mean,
                },
                dir_of(dj),
            ))
    }

    fn evaluate_residual(&mut self, i: usize) {
        let k2 = self.settings.k * self.settings.k;
        let explained = self.checks[i]
            .iter()
            .any(|c| c.drift.standing() || c.local.standing() || c.stiction.standing());
        let w = &mut self.residual[i];
        if w.n == 0 || w.var <= 0.0 {
            return;
        }
        let e = w.level - w.mean;
        w.out = e > 0.0 && e * e > k2 * w.var;
        if w.debounce.feed(!explained && w.out) {
            let alarm = Alarm {
                kind: AlarmKind::ModelMismatch {
                    mean_square: w.level,
                    learned: w.mean,
                },
                axis: AXES[i],
                direction: Direction::Both,
                period: self.period,
            };
            self.push(alarm);
        }
    }
}

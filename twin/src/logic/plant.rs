//! A simulated rig for the loop: the plant is the model itself with a perturbed parameter set
//! (so the twin, built with the nominal parameters, has something to correct), stepped at a
//! finer step than the twin, seen through quantising encoders and a PWM motor driver.
//! [`SimPlant`] implements [`Io`] directly; the embedded-hal board in `crate::board` wraps the
//! same plant behind the driver and encoder traits and gives the same bits.

use super::control::{Controller, Io, IoError, LoopConfig, Period, Trajectory};
use super::digest::{write_state, Fnv};
use super::io::{pwm_command, pwm_volts, Channel, EncoderScale, Pwm};
use super::monitor::alarm::Alarm;
use super::monitor::frame::{write_alarm, write_maps};
use super::monitor::Monitor;
use super::observer::Counters;
use core::fmt::Write;
use crane_model::{Config, Crane, Error, Extensions, Params, Real, State};

/// The simulated rig's "true" parameters: the nominal ones with X dry friction 40 % higher,
/// Y dry friction 30 % lower, X viscous friction 10 % higher, rope dry friction +1.5 N and a
/// payload of 0.5 kg instead of 0.457 kg.
pub fn rig_params() -> Params {
    let mut p = Params {
        payload_mass: 0.5,
        ..Params::default()
    };
    p.x.dry_pos = p.x.dry_pos.map(|c| 1.4 * c);
    p.x.dry_neg = p.x.dry_neg.map(|c| 1.4 * c);
    p.x.viscous_pos *= 1.1;
    p.x.viscous_neg *= 1.1;
    p.y.dry_pos = p.y.dry_pos.map(|c| 0.7 * c);
    p.y.dry_neg = p.y.dry_neg.map(|c| 0.7 * c);
    p.rope.dry_pos[0] += 1.5;
    p.rope.dry_neg[0] += 1.5;
    p
}

/// The plant: a model instance, its PWM inputs and encoders.
#[derive(Clone, Debug)]
pub struct SimPlant {
    crane: Crane<f64>,
    scale: EncoderScale,
    pwm: [Pwm; 3],
    substeps: u32,
    errors: u32,
}

impl SimPlant {
    /// A plant with parameters `params` starting at `init`, advancing `period` [s] per
    /// [`SimPlant::advance`] in `substeps` model steps.
    pub fn new(
        params: &Params,
        init: State<f64>,
        period: f64,
        substeps: u32,
    ) -> Result<Self, Error> {
        let n = if substeps == 0 { 1 } else { substeps };
        let config = Config {
            h: period / f64::from(n),
            ..Config::default()
        };
        Ok(SimPlant {
            crane: Crane::new(params, config, init)?,
            scale: EncoderScale::RIG,
            pwm: [Pwm::default(); 3],
            substeps: n,
            errors: 0,
        })
    }

    /// Switches on model extensions (localised friction, stiction...) in the plant: the faults
    /// the twin's friction monitor has to find. Errors name the field.
    pub fn with_extensions(mut self, ext: &Extensions) -> Result<Self, Error> {
        self.crane = self.crane.with_extensions(ext)?;
        Ok(self)
    }

    /// Changes the plant's parameters and extensions from now on, keeping its state (a fault
    /// that appears while the rig runs). On an error the plant is unchanged.
    pub fn retune(&mut self, params: &Params, ext: &Extensions) -> Result<(), Error> {
        let config = Config {
            h: self.crane.h(),
            ..Config::default()
        };
        self.crane = Crane::new(params, config, self.crane.state())?.with_extensions(ext)?;
        Ok(())
    }

    /// Sets the PWM command of axis `i`.
    pub fn set_pwm(&mut self, i: usize, p: Pwm) {
        if let Some(slot) = self.pwm.get_mut(i) {
            *slot = p;
        }
    }

    /// Voltages the PWM commands apply.
    pub fn volts(&self) -> [f64; 3] {
        self.pwm.map(pwm_volts)
    }

    /// Encoder counts of the current state.
    pub fn counts(&self) -> [i32; 5] {
        let s = self.crane.state();
        Channel::ALL.map(|ch| self.scale.counts(ch, s.q[ch.index()]))
    }

    /// Advances one period with the current PWM commands (a rejected model step keeps the
    /// state and is counted).
    pub fn advance(&mut self) {
        let u = self.volts();
        for _ in 0..self.substeps {
            if self.crane.step(u).is_err() {
                self.errors += 1;
            }
        }
    }

    /// True state.
    pub fn state(&self) -> State<f64> {
        self.crane.state()
    }

    /// Model steps the plant rejected.
    pub fn errors(&self) -> u32 {
        self.errors
    }
}

impl Io for SimPlant {
    fn read(&mut self) -> [Result<i32, IoError>; 5] {
        self.counts().map(Ok)
    }

    fn write(&mut self, u: [f64; 3]) -> Result<[f64; 3], IoError> {
        for (i, v) in u.iter().enumerate() {
            self.set_pwm(i, pwm_command(*v));
        }
        Ok(self.volts())
    }

    fn wait(&mut self) {
        self.advance();
    }

    fn truth(&self) -> Option<State<f64>> {
        Some(self.state())
    }
}

/// What a closed-loop run did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LoopSummary {
    /// FNV-1a over every period's twin state, modes and command bits.
    pub hash: u64,
    /// RMS estimation error (twin minus truth) of positions, from a quarter of the run on.
    pub pos_err_rms: [f64; 5],
    /// RMS estimation error of velocities, same window.
    pub vel_err_rms: [f64; 5],
    /// Largest |reference - truth| of the drive axes over the run.
    pub track_err_max: [f64; 3],
    /// Final disturbance estimates [N].
    pub disturbance: [f64; 3],
    /// Final residual mean squares.
    pub residual_ms: [f64; 5],
    /// Observer counters.
    pub counters: Counters,
}

/// Runs `periods` control periods of `ctrl` on `io` along `traj`; writes `LBEGIN`, an `L` line
/// (twin state bits) every `every` periods and `LEND` with the hash and the error figures.
#[allow(clippy::too_many_arguments)]
pub fn run_loop<R: Real, I: Io, W: Write>(
    ctrl: &mut Controller<R>,
    io: &mut I,
    cfg: &LoopConfig,
    traj: &Trajectory<'_>,
    periods: u32,
    every: u32,
    tag: &str,
    out: &mut W,
) -> Result<LoopSummary, core::fmt::Error> {
    let mut no_monitor = |_: &Controller<R>, _: &Period<R>| None;
    run_loop_with(
        ctrl,
        io,
        cfg,
        traj,
        (periods, every),
        tag,
        out,
        &mut no_monitor,
    )
}

/// What [`run_loop_with`] calls every period after the controller: the friction monitor.
pub type Watch<'a, R> = dyn FnMut(&Controller<R>, &Period<R>) -> Option<Alarm> + 'a;

/// [`run_loop`] with `watch` called every period after the controller's (the friction
/// monitor): an alarm it returns is written as an `MALARM` frame.
#[allow(clippy::too_many_arguments)]
pub fn run_loop_with<R: Real, I: Io, W: Write>(
    ctrl: &mut Controller<R>,
    io: &mut I,
    cfg: &LoopConfig,
    traj: &Trajectory<'_>,
    (periods, every): (u32, u32),
    tag: &str,
    out: &mut W,
    watch: &mut Watch<'_, R>,
) -> Result<LoopSummary, core::fmt::Error> {
    writeln!(out, "LBEGIN {tag} periods={periods}")?;
    let mut fnv = Fnv::default();
    let mut sum = LoopSummary::default();
    let mut sq_q = [0.0f64; 5];
    let mut sq_v = [0.0f64; 5];
    let mut n_err = 0u32;
    let start = periods / 4;
    for k in 0..periods {
        let t = f64::from(k) * cfg.period;
        let r = traj.at::<R>(t);
        let p = ctrl.run_period(io, &r);
        if let Some(a) = watch(ctrl, &p) {
            write_alarm(out, &a)?;
        }
        let est = ctrl.observer().state();
        let modes = ctrl.observer().modes();
        fnv.step(&est, &modes, u8::from(p.update.is_err()));
        for c in p.command {
            fnv.u64(c.to_f64().to_bits());
        }
        if let Some(tr) = io.truth() {
            let e = est.to_f64();
            for i in 0..3 {
                let d = r.pos[i].to_f64() - tr.q[i];
                let d = if d < 0.0 { -d } else { d };
                if d > sum.track_err_max[i] {
                    sum.track_err_max[i] = d;
                }
            }
            if k >= start {
                n_err += 1;
                for i in 0..5 {
                    let dq = e.q[i] - tr.q[i];
                    let dv = e.qd[i] - tr.qd[i];
                    sq_q[i] += dq * dq;
                    sq_v[i] += dv * dv;
                }
            }
        }
        if k % every == 0 {
            write!(out, "L {k}")?;
            write_state(out, &est, &modes)?;
            writeln!(out)?;
        }
        io.wait();
    }
    sum.hash = fnv.0;
    if n_err > 0 {
        let n = f64::from(n_err);
        for i in 0..5 {
            sum.pos_err_rms[i] = sqrt(sq_q[i] / n);
            sum.vel_err_rms[i] = sqrt(sq_v[i] / n);
        }
    }
    sum.disturbance = ctrl.observer().disturbance().map(R::to_f64);
    sum.residual_ms = ctrl.observer().residual_mean_square().map(R::to_f64);
    sum.counters = ctrl.observer().counters();
    writeln!(out, "LEND {tag} hash={:016x}", sum.hash)?;
    writeln!(
        out,
        "LSTAT {tag} pos_err_rms={:.3e} {:.3e} {:.3e} {:.3e} {:.3e} vel_err_rms={:.3e} {:.3e} {:.3e} {:.3e} {:.3e}",
        sum.pos_err_rms[0],
        sum.pos_err_rms[1],
        sum.pos_err_rms[2],
        sum.pos_err_rms[3],
        sum.pos_err_rms[4],
        sum.vel_err_rms[0],
        sum.vel_err_rms[1],
        sum.vel_err_rms[2],
        sum.vel_err_rms[3],
        sum.vel_err_rms[4]
    )?;
    writeln!(
        out,
        "LSTAT {tag} track_err_max={:.3e} {:.3e} {:.3e} disturbance_N={:.3} {:.3} {:.3} residual_rms={:.2e} {:.2e} {:.2e} {:.2e} {:.2e}",
        sum.track_err_max[0],
        sum.track_err_max[1],
        sum.track_err_max[2],
        sum.disturbance[0],
        sum.disturbance[1],
        sum.disturbance[2],
        sqrt(sum.residual_ms[0]),
        sqrt(sum.residual_ms[1]),
        sqrt(sum.residual_ms[2]),
        sqrt(sum.residual_ms[3]),
        sqrt(sum.residual_ms[4])
    )?;
    writeln!(out, "LSTAT {tag} counters={:?}", sum.counters)?;
    Ok(sum)
}

/// Square root by Newton's iteration from a power-of-two start (f64; only for reporting:
/// `core` has no `sqrt` without std). Within an ulp or two; `x <= 0` or non-finite gives `x`.
pub fn sqrt(x: f64) -> f64 {
    if x <= 0.0 || !x.is_finite() {
        return x;
    }
    let e = ((x.to_bits() >> 52) & 0x7ff) as i64 - 1023;
    let mut y = f64::from_bits(((e / 2 + 1023) as u64) << 52);
    for _ in 0..8 {
        y = 0.5 * (y + x / y);
    }
    y
}

/// Periods of the demonstration run (8 s at 2 ms).
pub const DEMO_PERIODS: u32 = 4000;
/// A twin state line every this many periods of the demonstration run.
pub const DEMO_EVERY: u32 = 250;

/// Where the simulated rig starts in the demonstration run.
pub fn demo_init() -> State<f64> {
    State {
        q: [0.10, 0.15, 0.30, core::f64::consts::FRAC_PI_2, 0.0],
        qd: [0.0; 5],
    }
}

/// Where the twin starts: 1 cm off in X and 0.03 rad off in alpha, so the observer has to
/// converge.
pub fn demo_twin_init() -> State<f64> {
    let mut s = demo_init();
    s.q[0] += 0.01;
    s.q[3] += 0.03;
    s
}

/// The demonstration plant: [`rig_params`], stepped at half the control period.
pub fn demo_plant() -> Result<SimPlant, Error> {
    SimPlant::new(&rig_params(), demo_init(), LoopConfig::default().period, 2)
}

/// The demonstration run on `io` (the simulated plant, directly or behind the embedded-hal
/// board): the nominal-parameter twin follows [`super::control::DEMO`] for
/// [`DEMO_PERIODS`] periods. `Ok(None)` if the controller could not be built.
pub fn run_demo<R: Real, I: Io, W: Write>(
    io: &mut I,
    tag: &str,
    out: &mut W,
) -> Result<Option<LoopSummary>, core::fmt::Error> {
    run_demo_with::<R, I, W>(io, &LoopConfig::default(), tag, out)
}

/// [`run_demo`] with loop settings `cfg` (e.g. a segment budget).
pub fn run_demo_with<R: Real, I: Io, W: Write>(
    io: &mut I,
    cfg: &LoopConfig,
    tag: &str,
    out: &mut W,
) -> Result<Option<LoopSummary>, core::fmt::Error> {
    let cfg = *cfg;
    let Ok(mut ctrl) = Controller::<R>::new(&Params::default(), demo_twin_init(), &cfg) else {
        writeln!(out, "ERROR {tag} controller")?;
        return Ok(None);
    };
    run_loop(
        &mut ctrl,
        io,
        &cfg,
        &super::control::DEMO,
        DEMO_PERIODS,
        DEMO_EVERY,
        tag,
        out,
    )
    .map(Some)
}

/// [`run_demo_with`] with the friction monitor `monitor` in the loop (build it with
/// [`Monitor::for_params`] of the default parameters; the board keeps it in a static, off the
/// stack). With [`Settings::quick`] the 8-s demonstration is all commissioning, so no alarm
/// can come: the monitor's cost and its map frames, written after `LEND`, are what this shows.
pub fn run_demo_monitored<R: Real, I: Io, W: Write>(
    io: &mut I,
    cfg: &LoopConfig,
    monitor: &mut Monitor,
    tag: &str,
    out: &mut W,
) -> Result<Option<LoopSummary>, core::fmt::Error> {
    let Ok(mut ctrl) = Controller::<R>::new(&Params::default(), demo_twin_init(), cfg) else {
        writeln!(out, "ERROR {tag} controller")?;
        return Ok(None);
    };
    let mut watch = |c: &Controller<R>, p: &Period<R>| monitor.update(c.observer(), p.predicted);
    let sum = run_loop_with(
        &mut ctrl,
        io,
        cfg,
        &super::control::DEMO,
        (DEMO_PERIODS, DEMO_EVERY),
        tag,
        out,
        &mut watch,
    )?;
    write_maps(out, monitor)?;
    Ok(Some(sum))
}

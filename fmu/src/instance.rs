//! One FMU instance without any FFI: the FMI 2.0 co-simulation state machine around a
//! [`Crane`], in safe Rust. The C entry points (`ffi.rs`) translate pointers and call this.
//!
//! Every failure is a [`Failure`]: the FMI status to return and the message to log.

use crate::snapshot::{Sim, Snapshot};
use crate::status::{Failure, Phase};
use crate::variables::{self, Kind, LimitEnd, Settings, Slot, Variability, Variable, AXES};
use crane_model::dynamics::eval;
use crane_model::{
    Config, Crane, Error, Extensions, FrictionLaw, Law, Mode, Output, Problem, State, Stiction,
    U_MAX,
};

/// Relative tolerance of "the communication step is a whole multiple of `h`" and of "the
/// communication point is the FMU's time": `|n h - dt| <= REL_TOL dt`.
pub const REL_TOL: f64 = 1e-9;

/// Most model steps one `fmi2DoStep` may take (10^8 steps of 1 ms are 28 h of simulated time
/// and about a minute of CPU): a larger request is an error, not a hang.
pub const MAX_STEPS_PER_CALL: f64 = 1e8;

/// One FMU instance (safe part).
#[derive(Clone, Debug)]
pub struct Instance {
    vars: &'static [Variable],
    settings: Settings,
    /// Per drive axis, the end of its travel (`x.min`, `x.max`...) the importer set last:
    /// the one an "empty travel" message names.
    limit_set: [Option<LimitEnd>; 3],
    inputs: [f64; 3],
    /// The input [V] the last accepted step applied (saturated to +-12 V; 0 before the first
    /// step): the friction, tension and acceleration outputs are evaluated with it.
    applied: [f64; 3],
    crane: Option<Crane>,
    start_time: f64,
    steps: u64,
    phase: Phase,
}

impl Default for Instance {
    fn default() -> Self {
        Self::new()
    }
}

fn mode_code(m: Mode) -> i32 {
    match m {
        Mode::Negative => -1,
        Mode::Stopped => 0,
        Mode::Positive => 1,
    }
}

/// The friction law of the settings (`config.law.kind`, `config.law.gamma`), with the FMU's
/// own checks: the kind is 0 or 1 and `gamma > 0` (finite) whatever the law, as its declared
/// range says.
fn friction_law(s: &Settings) -> Result<FrictionLaw, Failure> {
    if !(s.gamma.is_finite() && s.gamma > 0.0) {
        let problem = if s.gamma.is_finite() {
            Problem::NotPositive
        } else {
            Problem::NotFinite
        };
        return Err(Failure::error(format!(
            "invalid parameter: {}",
            Error {
                field: "config.law.gamma",
                problem,
                value: s.gamma,
            }
        )));
    }
    match s.law {
        0 => Ok(FrictionLaw::Hybrid),
        1 => Ok(FrictionLaw::Tanh { gamma: s.gamma }),
        k => Err(Failure::error(format!(
            "invalid parameter: `config.law.kind` must be 0 (hybrid) or 1 (tanh) (got {k})"
        ))),
    }
}

/// The law the model evaluates for `s` (the simulator was built with [`friction_law`]).
fn law(s: &Settings) -> Law<f64> {
    match friction_law(s) {
        Ok(FrictionLaw::Tanh { gamma }) => Law::Tanh(gamma),
        _ => Law::Hybrid,
    }
}

/// The model extensions of the settings: stiction on the axes whose ratio is not 1. Every
/// stiction field is checked by the model (`stiction[i].ratio >= 1`, `stiction[i].velocity >
/// 0`), also on axes without stiction. A ratio of exactly 1 leaves the axis without
/// stiction, which gives the same bits as `Stiction { ratio: 1, .. }` (`1 c = c` and
/// `c (1 + 0 e) = c`) at a lower cost.
fn extensions(s: &Settings) -> Result<Extensions, Error> {
    let stiction = |keep: fn(f64) -> bool| {
        [0, 1, 2].map(|i| {
            let ratio = s.stiction_ratio[i];
            keep(ratio).then_some(Stiction {
                ratio,
                velocity: s.stribeck_velocity[i],
            })
        })
    };
    let all = Extensions {
        stiction: stiction(|_| true),
        ..Extensions::default()
    };
    all.validate(s.h)?;
    Ok(Extensions {
        stiction: stiction(|r| r != 1.0),
        ..Extensions::default()
    })
}

/// Builds the simulator from settings at `init`, with the model's own validation (its typed
/// error, explained by [`invalid`]).
fn build(
    s: &Settings,
    init: State<f64>,
    limit_set: &[Option<LimitEnd>; 3],
) -> Result<Crane, Failure> {
    let explain = |e: Error| invalid(&e, s, limit_set);
    if s.segment_budget < 1 {
        return Err(explain(Error {
            field: "config.segment_budget",
            problem: Problem::NotPositive,
            value: f64::from(s.segment_budget),
        }));
    }
    let law = friction_law(s)?;
    let config = Config { h: s.h, law };
    // `segment_budget >= 1` here, so the conversion is exact; above 8 the model says
    // `TooLarge`.
    let budget = usize::try_from(s.segment_budget).unwrap_or(usize::MAX);
    let crane = Crane::new(&s.params, config, init).map_err(explain)?;
    let ext = extensions(s).map_err(explain)?;
    crane
        .with_extensions(&ext)
        .and_then(|c| c.with_segment_budget(budget))
        .map_err(explain)
}

/// The message of a rejected parameter. An empty travel (`min >= max` of an axis) names the
/// limit the importer set last and the bound it violates (`x.max` must be above `x.min`),
/// with both values; other errors are the model's own text.
fn invalid(e: &Error, s: &Settings, limit_set: &[Option<LimitEnd>; 3]) -> Failure {
    if e.problem == Problem::EmptyRange {
        let axis = AXES
            .iter()
            .position(|a| e.field.strip_suffix(".min") == Some(a));
        if let Some(i) = axis {
            let (a, p) = (AXES[i], s.params.axes()[i]);
            let (min, max) = (p.min, p.max);
            return Failure::error(match limit_set[i] {
                Some(LimitEnd::Max) => format!(
                    "invalid parameter: `{a}.max` must be above `{a}.min` = {min} (got {max}): the travel [{a}.min, {a}.max] is empty"
                ),
                _ => format!(
                    "invalid parameter: `{a}.min` must be below `{a}.max` = {max} (got {min}): the travel [{a}.min, {a}.max] is empty"
                ),
            });
        }
    }
    Failure::error(format!("invalid parameter: {e}"))
}

/// A voltage [V] saturated to +-[`U_MAX`], as `Crane::step` saturates it (NaN is rejected
/// before).
fn saturate(v: f64) -> f64 {
    v.clamp(-U_MAX, U_MAX)
}

/// Accelerations, friction forces, rope tension and payload position of `crane` with input
/// `u` [V] (already saturated), by the operations of `Crane::output`, so the same bits; with
/// `u` kept by the FMU, the outputs are the same after an FMU state is restored into a
/// rebuilt simulator (which does not know the last input).
fn output(crane: &Crane, law: Law<f64>, u: &[f64; 3]) -> Result<Output, String> {
    let c = crane.coeffs();
    let state = crane.state();
    let e = eval(c, law, &state, &crane.modes(), u)
        .map_err(|_| "mass matrix not positive definite".to_string())?;
    let rope = &c.axes[2];
    let tension = c.jbar_l * e.qdd[2] - (rope.drive(u[2]) - e.fric[2]);
    Ok(Output {
        qdd: e.qdd,
        friction: e.fric,
        tension,
        payload: state.payload(),
    })
}

impl Instance {
    /// A fresh instance with the start values of `modelDescription.xml`.
    pub fn new() -> Self {
        Instance {
            vars: variables::table(),
            settings: Settings::default(),
            limit_set: [None; 3],
            inputs: [0.0; 3],
            applied: [0.0; 3],
            crane: None,
            start_time: 0.0,
            steps: 0,
            phase: Phase::Instantiated,
        }
    }

    /// Current phase.
    pub fn phase(&self) -> Phase {
        self.phase
    }

    /// Marks the instance failed (after a caught panic).
    pub fn poison(&mut self) {
        self.phase = Phase::Failed;
        self.crane = None;
    }

    /// FMU time [s]: start time plus the accepted steps times `h`.
    pub fn time(&self) -> f64 {
        self.start_time + self.steps as f64 * self.settings.h
    }

    /// `fmi2Reset`: back to the start values, as after instantiation.
    pub fn reset(&mut self) {
        *self = Instance::new();
    }

    /// `fmi2SetupExperiment`: the start time [s] (finite). Tolerance and stop time are not
    /// used (the step is fixed).
    pub fn setup_experiment(&mut self, start_time: f64) -> Result<(), Failure> {
        if self.phase != Phase::Instantiated {
            return Err(Failure::error(
                "fmi2SetupExperiment is only allowed after instantiation or reset",
            ));
        }
        if !start_time.is_finite() {
            return Err(Failure::error(format!(
                "startTime must be finite (got {start_time})"
            )));
        }
        self.start_time = start_time;
        Ok(())
    }

    /// `fmi2EnterInitializationMode`.
    pub fn enter_initialization(&mut self) -> Result<(), Failure> {
        if self.phase != Phase::Instantiated {
            return Err(Failure::error(
                "fmi2EnterInitializationMode is only allowed after instantiation or reset",
            ));
        }
        self.phase = Phase::Initialization;
        Ok(())
    }

    /// `fmi2ExitInitializationMode`: validates every parameter and the initial state with the
    /// model's own checks and builds the simulator.
    pub fn exit_initialization(&mut self) -> Result<(), Failure> {
        if self.phase != Phase::Initialization {
            return Err(Failure::error(
                "fmi2ExitInitializationMode is only allowed in initialization mode",
            ));
        }
        let crane = build(&self.settings, self.settings.init, &self.limit_set)?;
        self.crane = Some(crane);
        self.steps = 0;
        self.applied = [0.0; 3];
        self.phase = Phase::StepComplete;
        Ok(())
    }

    /// `fmi2Terminate`.
    pub fn terminate(&mut self) -> Result<(), Failure> {
        match self.phase {
            Phase::StepComplete | Phase::Failed => {
                self.phase = Phase::Terminated;
                Ok(())
            }
            _ => Err(Failure::error(
                "fmi2Terminate is only allowed after initialization",
            )),
        }
    }

    /// `fmi2DoStep`: advances from `t` [s] by `dt` [s], a whole multiple of `h` (relative
    /// tolerance [`REL_TOL`]), with the inputs held over the step.
    pub fn do_step(&mut self, t: f64, dt: f64) -> Result<(), Failure> {
        if self.phase != Phase::StepComplete {
            return Err(Failure::error(
                "fmi2DoStep is only allowed after fmi2ExitInitializationMode (and not after an error or fmi2Terminate)",
            ));
        }
        let h = self.settings.h;
        if !(dt.is_finite() && dt > 0.0) {
            return Err(Failure::error(format!(
                "communicationStepSize must be finite and > 0 (got {dt})"
            )));
        }
        let n = (dt / h).round();
        if !(n >= 1.0 && (n * h - dt).abs() <= REL_TOL * dt) {
            return Err(Failure::error(format!(
                "communicationStepSize {dt} s is not a whole multiple of the model step config.h = {h} s (relative tolerance {REL_TOL}); use a multiple of h or change config.h"
            )));
        }
        if n > MAX_STEPS_PER_CALL {
            return Err(Failure::error(format!(
                "communicationStepSize {dt} s is {n} model steps, more than {MAX_STEPS_PER_CALL} in one call"
            )));
        }
        let now = self.time();
        if !(t.is_finite() && (t - now).abs() <= REL_TOL * now.abs().max(dt)) {
            return Err(Failure::error(format!(
                "currentCommunicationPoint {t} s is not the FMU's time {now} s"
            )));
        }
        let Some(crane) = self.crane.as_mut() else {
            return Err(Failure::error("internal: no simulator in step mode"));
        };
        for _ in 0..n as u64 {
            if let Err(e) = crane.step(self.inputs) {
                let at = self.start_time + self.steps as f64 * h;
                self.phase = Phase::Failed;
                return Err(Failure::error(format!("t = {at} s: {e}")));
            }
            self.applied = self.inputs.map(saturate);
            self.steps += 1;
        }
        Ok(())
    }

    fn variable(&self, kind: Kind, vr: u32) -> Result<Variable, Failure> {
        variables::lookup(self.vars, kind, vr)
            .copied()
            .ok_or_else(|| {
                Failure::error(format!("no {kind:?} variable with value reference {vr}"))
            })
    }

    /// The simulator to read outputs from: the running one, or (in initialization mode) one
    /// built from the current settings.
    fn reader(&self) -> Result<std::borrow::Cow<'_, Crane>, Failure> {
        match (&self.crane, self.phase) {
            (Some(c), _) => Ok(std::borrow::Cow::Borrowed(c)),
            (None, Phase::Initialization) => {
                build(&self.settings, self.settings.init, &self.limit_set)
                    .map(std::borrow::Cow::Owned)
            }
            _ => Err(Failure::error(
                "outputs are only available from initialization mode on",
            )),
        }
    }

    /// `fmi2GetReal` for the value references `vrs`, into `out` (same length).
    pub fn get_real(&self, vrs: &[u32], out: &mut [f64]) -> Result<(), Failure> {
        let mut crane: Option<std::borrow::Cow<'_, Crane>> = None;
        let mut output = None;
        for (vr, dst) in vrs.iter().zip(out.iter_mut()) {
            let v = self.variable(Kind::Real, *vr)?;
            if let Slot::Input(i) = v.slot {
                *dst = self.inputs[i];
                continue;
            }
            if let Some(x) = variables::setting(&self.settings, v.slot) {
                *dst = x;
                continue;
            }
            if crane.is_none() {
                crane = Some(self.reader()?);
            }
            let Some(c) = crane.as_deref() else {
                return Err(Failure::error("internal: no simulator"));
            };
            let s = c.state();
            *dst = match v.slot {
                Slot::Q(i) => s.q[i],
                Slot::Qd(i) => s.qd[i],
                slot => {
                    if output.is_none() {
                        output = Some(output_of(c, &self.settings, &self.applied, self.time())?);
                    }
                    let Some(o) = output else {
                        return Err(Failure::error("internal: no output"));
                    };
                    match slot {
                        Slot::Friction(i) => o.friction[i],
                        Slot::Tension => o.tension,
                        Slot::Payload(i) => o.payload[i],
                        _ => return Err(Failure::error(format!("{} is not a Real", v.name))),
                    }
                }
            };
        }
        Ok(())
    }

    /// `fmi2GetInteger`.
    pub fn get_integer(&self, vrs: &[u32], out: &mut [i32]) -> Result<(), Failure> {
        for (vr, dst) in vrs.iter().zip(out.iter_mut()) {
            let v = self.variable(Kind::Integer, *vr)?;
            *dst = match v.slot {
                Slot::SegmentBudget => self.settings.segment_budget,
                Slot::Law => self.settings.law,
                Slot::Mode(i) => mode_code(self.reader()?.modes()[i]),
                _ => return Err(Failure::error(format!("{} is not an Integer", v.name))),
            };
        }
        Ok(())
    }

    /// Whether a variable may be set now (FMI 2.0 rules for its causality and variability).
    fn settable(&self, v: &Variable) -> Result<(), Failure> {
        use variables::Causality as C;
        let ok = match (v.causality, v.variability, self.phase) {
            (C::Output, _, _) => false,
            (_, _, Phase::Terminated | Phase::Failed) => false,
            (C::Input, _, _) => true,
            (C::Parameter, Variability::Tunable, _) => true,
            (C::Parameter, _, Phase::Instantiated | Phase::Initialization) => true,
            _ => false,
        };
        if ok {
            Ok(())
        } else {
            Err(Failure::error(format!(
                "{} ({:?} {:?}) cannot be set in phase {:?}",
                v.name, v.causality, v.variability, self.phase
            )))
        }
    }

    /// `fmi2SetReal`. Inputs take effect at the next step. Parameters are checked at
    /// `fmi2ExitInitializationMode`; a tunable parameter set while stepping is checked at
    /// once, and then the simulator continues from its current state with the new
    /// parameters (the friction and tension outputs use the new parameters at once, with
    /// the input of the last step). On error nothing changes.
    pub fn set_real(&mut self, vrs: &[u32], values: &[f64]) -> Result<(), Failure> {
        let mut next = self.settings;
        let mut limit_set = self.limit_set;
        let mut inputs = self.inputs;
        let mut settings_changed = false;
        for (vr, value) in vrs.iter().zip(values) {
            let v = self.variable(Kind::Real, *vr)?;
            self.settable(&v)?;
            if let Slot::Input(i) = v.slot {
                inputs[i] = *value;
                continue;
            }
            if !variables::set_setting(&mut next, v.slot, *value) {
                return Err(Failure::error(format!("{} cannot be set", v.name)));
            }
            if let Slot::Param(i) = v.slot {
                if let Some((axis, end)) = variables::limit_of(i) {
                    limit_set[axis] = Some(end);
                }
            }
            settings_changed = true;
        }
        if settings_changed && self.phase == Phase::StepComplete {
            let Some(old) = self.crane.as_ref() else {
                return Err(Failure::error("internal: no simulator in step mode"));
            };
            let rebuilt = build(&next, old.state(), &limit_set)?;
            self.crane = Some(rebuilt);
        }
        self.settings = next;
        self.limit_set = limit_set;
        self.inputs = inputs;
        Ok(())
    }

    /// `fmi2SetInteger`.
    pub fn set_integer(&mut self, vrs: &[u32], values: &[i32]) -> Result<(), Failure> {
        let mut next = self.settings;
        for (vr, value) in vrs.iter().zip(values) {
            let v = self.variable(Kind::Integer, *vr)?;
            self.settable(&v)?;
            if !variables::set_setting(&mut next, v.slot, f64::from(*value)) {
                return Err(Failure::error(format!("{} cannot be set", v.name)));
            }
        }
        self.settings = next;
        Ok(())
    }

    /// The running simulator (step mode), for tests.
    pub fn crane(&self) -> Option<&Crane> {
        self.crane.as_ref()
    }

    /// `fmi2GetFMUstate`: everything that determines the instance's future, as plain data.
    pub fn snapshot(&self) -> Snapshot {
        Snapshot {
            settings: self.settings,
            limit_set: self.limit_set,
            inputs: self.inputs,
            applied: self.applied,
            start_time: self.start_time,
            steps: self.steps,
            phase: self.phase,
            sim: self.crane.as_ref().map(|c| Sim {
                state: c.state(),
                modes: c.modes(),
            }),
        }
    }

    /// `fmi2SetFMUstate`: back to `snap`. A running simulator is rebuilt from the snapshot's
    /// settings at its state, with the model's checks; its modes follow the velocities (an
    /// accepted step leaves every moving axis with a velocity of its sign and every stopped
    /// one at 0), which is checked against the snapshot's modes. The rebuilt simulator then
    /// steps to the same bits as the original: the model has no memory beyond state and
    /// modes (the input delay line, the one other, is unused by the FMU), and the last
    /// applied input is the instance's own. On error nothing changes.
    pub fn restore(&mut self, snap: &Snapshot) -> Result<(), Failure> {
        let running = match snap.phase {
            Phase::Instantiated | Phase::Initialization => Some(false),
            Phase::StepComplete => Some(true),
            // A failed step keeps its simulator (at the state before the step); a caught
            // panic drops it.
            Phase::Terminated | Phase::Failed => None,
        };
        if running.is_some_and(|r| r != snap.sim.is_some()) {
            return Err(Failure::error(format!(
                "FMU state: phase {:?} {} a simulator",
                snap.phase,
                if snap.sim.is_some() {
                    "with"
                } else {
                    "without"
                }
            )));
        }
        let crane = match &snap.sim {
            None => None,
            Some(sim) => {
                let c = build(&snap.settings, sim.state, &snap.limit_set)
                    .map_err(|f| Failure::error(format!("FMU state: {}", f.message)))?;
                if c.modes() != sim.modes {
                    return Err(Failure::error(format!(
                        "FMU state: modes {:?} do not follow the velocities {:?}",
                        sim.modes, sim.state.qd
                    )));
                }
                Some(c)
            }
        };
        *self = Instance {
            vars: self.vars,
            settings: snap.settings,
            limit_set: snap.limit_set,
            inputs: snap.inputs,
            applied: snap.applied,
            crane,
            start_time: snap.start_time,
            steps: snap.steps,
            phase: snap.phase,
        };
        Ok(())
    }
}

/// The outputs of `c` for settings `s` with the last applied input `u`; the error names the
/// time `t` [s].
fn output_of(c: &Crane, s: &Settings, u: &[f64; 3], t: f64) -> Result<Output, Failure> {
    output(c, law(s), u).map_err(|e| Failure::error(format!("outputs at t = {t} s: {e}")))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::status::Status;

    fn running() -> Instance {
        let mut i = Instance::new();
        i.setup_experiment(0.0).unwrap();
        i.enter_initialization().unwrap();
        i.exit_initialization().unwrap();
        i
    }

    #[test]
    fn step_must_be_a_multiple_of_h() {
        let mut i = running();
        i.do_step(0.0, 0.003).unwrap();
        assert_eq!(i.crane().unwrap().steps(), 3);
        let e = i.do_step(0.003, 0.0015).unwrap_err();
        assert_eq!(e.status, Status::Error);
        assert!(e.message.contains("not a whole multiple"), "{}", e.message);
        assert!(i.do_step(0.003, 0.0).is_err());
        assert!(i.do_step(0.003, f64::NAN).is_err());
        // A rejected step changes nothing; a wrong communication point is an error.
        assert_eq!(i.crane().unwrap().steps(), 3);
        assert!(i
            .do_step(0.5, 0.001)
            .unwrap_err()
            .message
            .contains("not the FMU's time"));
        i.do_step(0.003, 0.001 * (1.0 + 1e-12)).unwrap();
        assert_eq!(i.crane().unwrap().steps(), 4);
    }

    #[test]
    fn bad_parameter_is_the_models_error_at_exit_initialization() {
        let mut i = Instance::new();
        i.enter_initialization().unwrap();
        i.set_real(&[1000], &[-1.0]).unwrap();
        let e = i.exit_initialization().unwrap_err();
        assert_eq!(e.status, Status::Error);
        assert_eq!(
            e.message,
            "invalid parameter: `payload_mass` must be > 0 (got -1)"
        );
        // Fixed parameters cannot change while stepping; a bad tunable one is rejected and
        // changes nothing.
        let mut i = running();
        assert!(i.set_real(&[1100], &[0.002]).is_err());
        let e = i.set_real(&[1000 + 6 + 1], &[0.0]).unwrap_err();
        assert!(e.message.contains("`x.gain` must be > 0"), "{}", e.message);
        assert_eq!(i.settings.params.x.gain, 3.2);
        i.do_step(0.0, 0.001).unwrap();
        let mut b = Instance::new();
        b.enter_initialization().unwrap();
        b.set_integer(&[1200], &[0]).unwrap();
        let e = b.exit_initialization().unwrap_err();
        assert!(e.message.contains("config.segment_budget"), "{}", e.message);
    }

    #[test]
    fn reset_restores_start_values() {
        let mut i = running();
        i.set_real(&[0], &[5.0]).unwrap();
        i.do_step(0.0, 0.01).unwrap();
        i.reset();
        assert_eq!(i.phase(), Phase::Instantiated);
        assert_eq!(i.inputs, [0.0; 3]);
        assert_eq!(i.time(), 0.0);
        assert!(i.crane().is_none());
        let mut q = [0.0];
        assert!(i.get_real(&[100], &mut q).is_err());
        i.enter_initialization().unwrap();
        i.get_real(&[100], &mut q).unwrap();
        assert_eq!(q[0], 0.25);
    }

    fn vr(name: &str) -> u32 {
        variables::table()
            .iter()
            .find(|v| v.name == name)
            .map(|v| v.vr)
            .unwrap()
    }

    #[test]
    fn an_empty_travel_names_the_limit_set_and_the_bound_it_violates() {
        let fail = |sets: &[(&str, f64)]| {
            let mut i = Instance::new();
            i.enter_initialization().unwrap();
            for (name, value) in sets {
                i.set_real(&[vr(name)], &[*value]).unwrap();
            }
            i.exit_initialization().unwrap_err().message
        };
        // Issue 23: `x.max = -1` named `x.min`.
        assert_eq!(
            fail(&[("x.max", -1.0)]),
            "invalid parameter: `x.max` must be above `x.min` = 0 (got -1): the travel [x.min, x.max] is empty"
        );
        assert_eq!(
            fail(&[("rope.min", 0.6)]),
            "invalid parameter: `rope.min` must be below `rope.max` = 0.57 (got 0.6): the travel [rope.min, rope.max] is empty"
        );
        // Both ends set: the last one set is named.
        assert_eq!(
            fail(&[("y.min", 0.7), ("y.max", 0.65)]),
            "invalid parameter: `y.max` must be above `y.min` = 0.7 (got 0.65): the travel [y.min, y.max] is empty"
        );
        assert_eq!(
            fail(&[("y.max", 0.65), ("y.min", 0.7)]),
            "invalid parameter: `y.min` must be below `y.max` = 0.65 (got 0.7): the travel [y.min, y.max] is empty"
        );
        // A tunable limit set while stepping is refused at once, with the same message, and
        // changes nothing.
        let mut i = running();
        let e = i.set_real(&[vr("x.max")], &[-1.0]).unwrap_err();
        assert!(
            e.message
                .starts_with("invalid parameter: `x.max` must be above `x.min` = 0 (got -1)"),
            "{}",
            e.message
        );
        assert_eq!(i.settings.params.x.max, 0.505);
        assert_eq!(i.limit_set, [None; 3]);
    }

    #[test]
    fn friction_options_are_checked_with_the_variable_named() {
        let fail = |name: &str, value: f64| {
            let mut i = Instance::new();
            i.enter_initialization().unwrap();
            i.set_real(&[vr(name)], &[value]).unwrap();
            i.exit_initialization().unwrap_err().message
        };
        assert_eq!(
            fail("stiction[1].ratio", 0.9),
            "invalid parameter: `stiction[1].ratio` must be >= 1 (got 0.9)"
        );
        assert_eq!(
            fail("stiction[2].velocity", 0.0),
            "invalid parameter: `stiction[2].velocity` must be > 0 (got 0)"
        );
        // Checked whatever the law (the declared range holds always).
        assert_eq!(
            fail("config.law.gamma", -1.0),
            "invalid parameter: `config.law.gamma` must be > 0 (got -1)"
        );
        let mut i = Instance::new();
        i.enter_initialization().unwrap();
        i.set_integer(&[vr("config.law.kind")], &[2]).unwrap();
        assert_eq!(
            i.exit_initialization().unwrap_err().message,
            "invalid parameter: `config.law.kind` must be 0 (hybrid) or 1 (tanh) (got 2)"
        );
        // The law is fixed once stepping; stiction is tunable.
        let mut i = running();
        assert!(i.set_integer(&[vr("config.law.kind")], &[1]).is_err());
        i.set_real(&[vr("stiction[0].ratio")], &[1.5]).unwrap();
        assert!(i.set_real(&[vr("stiction[0].ratio")], &[0.5]).is_err());
        assert_eq!(i.settings.stiction_ratio[0], 1.5);
    }

    /// Moves every axis for `n` steps of 1 ms from the instance's time with inputs that
    /// change every step; returns every real output and mode after each step, as bits.
    fn run(i: &mut Instance, n: usize) -> Vec<Vec<u64>> {
        let outs: Vec<u32> = (100..117).collect();
        let mut rows = Vec::new();
        for _ in 0..n {
            let t = i.time();
            let u = [
                14.0 * (7.0 * t).sin(),
                5.0 * (3.0 * t).cos(),
                2.0 * (5.0 * t).sin(),
            ];
            i.set_real(&[0, 1, 2], &u).unwrap();
            i.do_step(t, 1e-3).unwrap();
            let mut o = vec![0.0; outs.len()];
            i.get_real(&outs, &mut o).unwrap();
            let mut m = [0; 3];
            i.get_integer(&[200, 201, 202], &mut m).unwrap();
            let mut row: Vec<u64> = o.iter().map(|x| x.to_bits()).collect();
            row.extend(m.iter().map(|x| *x as u64));
            rows.push(row);
        }
        rows
    }

    #[test]
    fn a_restored_snapshot_continues_to_the_same_bits() {
        let mut i = Instance::new();
        i.enter_initialization().unwrap();
        i.set_real(
            &[vr("stiction[0].ratio"), vr("stiction[1].ratio")],
            &[1.4, 1.2],
        )
        .unwrap();
        i.exit_initialization().unwrap();
        run(&mut i, 700);
        let snap = i.snapshot();
        let at_t1 = snap;
        // Every output at t1, friction and tension included (they use the last input).
        let outs: Vec<u32> = (100..117).collect();
        let read = |i: &Instance| {
            let mut o = vec![0.0; outs.len()];
            i.get_real(&outs, &mut o).unwrap();
            o.iter().map(|x| x.to_bits()).collect::<Vec<u64>>()
        };
        let t1 = read(&i);
        let first = run(&mut i, 800);
        // A later parameter change is undone by the restore too.
        i.set_real(&[vr("payload_mass")], &[0.9]).unwrap();
        i.restore(&snap).unwrap();
        assert_eq!(i.snapshot(), at_t1);
        assert_eq!(i.settings.params.payload_mass, 0.457);
        assert_eq!(read(&i), t1);
        let again = run(&mut i, 800);
        assert_eq!(first, again);
        // Through the bytes, into a fresh instance.
        let mut j = Instance::new();
        j.restore(&Snapshot::from_bytes(&snap.to_bytes()).unwrap())
            .unwrap();
        assert_eq!(read(&j), t1);
        assert_eq!(run(&mut j, 800), first);
        // The run reversed X (at up to 14 V, saturated to 12 V) and moved and stopped the rope.
        let seen = |a: usize| {
            let mut s: Vec<i64> = first.iter().map(|r| r[a] as i64).collect();
            s.sort();
            s.dedup();
            s
        };
        assert_eq!(seen(17), [-1, 1]);
        assert_eq!(seen(19), [-1, 0, 1]);
    }

    #[test]
    fn an_inconsistent_snapshot_is_refused_and_changes_nothing() {
        let mut i = running();
        i.do_step(0.0, 0.01).unwrap();
        let good = i.snapshot();
        let mut j = Instance::new();
        // A running phase without a simulator, and the other way round.
        let no_sim = Snapshot { sim: None, ..good };
        assert!(j.restore(&no_sim).unwrap_err().message.contains("without"));
        let early = Snapshot {
            phase: Phase::Initialization,
            ..good
        };
        assert!(j.restore(&early).unwrap_err().message.contains("with a"));
        // Modes that do not follow the velocities (X moving with qd = 0).
        let mut sim = good.sim.unwrap();
        sim.modes[0] = Mode::Positive;
        let e = j
            .restore(&Snapshot {
                sim: Some(sim),
                ..good
            })
            .unwrap_err();
        assert!(
            e.message.contains("do not follow the velocities"),
            "{}",
            e.message
        );
        // A state outside the limits: the model's check.
        let mut sim = good.sim.unwrap();
        sim.state.q[0] = 2.0;
        let e = j
            .restore(&Snapshot {
                sim: Some(sim),
                ..good
            })
            .unwrap_err();
        assert!(e.message.contains("`state.q[0]`"), "{}", e.message);
        assert_eq!(j.phase(), Phase::Instantiated);
        assert!(j.crane().is_none());
        j.restore(&good).unwrap();
        assert_eq!(j.time(), 0.01);
    }
}

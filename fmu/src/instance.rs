//! One FMU instance without any FFI: the FMI 2.0 co-simulation state machine around a
//! [`Crane`], in safe Rust. The C entry points (`ffi.rs`) translate pointers and call this.
//!
//! Every failure is a [`Failure`]: the FMI status to return and the message to log.

use crate::variables::{self, Kind, Settings, Slot, Variability, Variable};
use crane_model::{Config, Crane, Error, FrictionLaw, Mode, Problem, State};

/// Relative tolerance of "the communication step is a whole multiple of `h`" and of "the
/// communication point is the FMU's time": `|n h - dt| <= REL_TOL dt`.
pub const REL_TOL: f64 = 1e-9;

/// Most model steps one `fmi2DoStep` may take (10^8 steps of 1 ms are 28 h of simulated time
/// and about a minute of CPU): a larger request is an error, not a hang.
pub const MAX_STEPS_PER_CALL: f64 = 1e8;

/// FMI 2.0 status codes the instance reports (`fmi2Status`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Status {
    /// `fmi2Warning` (1).
    Warning = 1,
    /// `fmi2Discard` (2).
    Discard = 2,
    /// `fmi2Error` (3).
    Error = 3,
    /// `fmi2Fatal` (4).
    Fatal = 4,
}

/// A rejected call: the status to return and the message for the logger.
#[derive(Clone, Debug, PartialEq)]
pub struct Failure {
    /// Status to return.
    pub status: Status,
    /// Message (one line).
    pub message: String,
}

impl Failure {
    fn error(message: impl Into<String>) -> Self {
        Failure {
            status: Status::Error,
            message: message.into(),
        }
    }
}

/// Where the instance is in the FMI 2.0 co-simulation state machine.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Phase {
    /// After `fmi2Instantiate` or `fmi2Reset` (and `fmi2SetupExperiment`).
    Instantiated,
    /// Between `fmi2EnterInitializationMode` and `fmi2ExitInitializationMode`.
    Initialization,
    /// Stepping.
    StepComplete,
    /// After `fmi2Terminate`.
    Terminated,
    /// A step or a parameter change failed: only get, reset, terminate and free are allowed.
    Failed,
}

/// One FMU instance (safe part).
#[derive(Clone, Debug)]
pub struct Instance {
    vars: &'static [Variable],
    settings: Settings,
    inputs: [f64; 3],
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

/// Builds the simulator from settings, with the model's own validation (its typed error).
fn build(s: &Settings, init: State<f64>) -> Result<Crane, Error> {
    if s.segment_budget < 1 {
        return Err(Error {
            field: "config.segment_budget",
            problem: Problem::NotPositive,
            value: f64::from(s.segment_budget),
        });
    }
    let config = Config {
        h: s.h,
        law: FrictionLaw::Hybrid,
    };
    // `segment_budget >= 1` here, so the conversion is exact; above 8 the model says
    // `TooLarge`.
    let budget = usize::try_from(s.segment_budget).unwrap_or(usize::MAX);
    Crane::new(&s.params, config, init)?.with_segment_budget(budget)
}

fn invalid(e: &Error) -> Failure {
    Failure::error(format!("invalid parameter: {e}"))
}

impl Instance {
    /// A fresh instance with the start values of `modelDescription.xml`.
    pub fn new() -> Self {
        Instance {
            vars: variables::table(),
            settings: Settings::default(),
            inputs: [0.0; 3],
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
        let crane = build(&self.settings, self.settings.init).map_err(|e| invalid(&e))?;
        self.crane = Some(crane);
        self.steps = 0;
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
            (None, Phase::Initialization) => build(&self.settings, self.settings.init)
                .map(std::borrow::Cow::Owned)
                .map_err(|e| invalid(&e)),
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
            *dst = match v.slot {
                Slot::Input(i) => self.inputs[i],
                Slot::Param(i) => variables::param(&self.settings.params, i).unwrap_or(f64::NAN),
                Slot::Step => self.settings.h,
                Slot::InitQ(i) => self.settings.init.q[i],
                Slot::InitQd(i) => self.settings.init.qd[i],
                slot => {
                    if crane.is_none() {
                        crane = Some(self.reader()?);
                    }
                    let Some(c) = crane.as_deref() else {
                        return Err(Failure::error("internal: no simulator"));
                    };
                    let s = c.state();
                    match slot {
                        Slot::Q(i) => s.q[i],
                        Slot::Qd(i) => s.qd[i],
                        _ => {
                            if output.is_none() {
                                output = Some(c.output().map_err(|e| {
                                    Failure::error(format!("outputs at t = {} s: {e}", self.time()))
                                })?);
                            }
                            let Some(o) = output else {
                                return Err(Failure::error("internal: no output"));
                            };
                            match slot {
                                Slot::Friction(i) => o.friction[i],
                                Slot::Tension => o.tension,
                                Slot::Payload(i) => o.payload[i],
                                _ => {
                                    return Err(Failure::error(format!("{} is not a Real", v.name)))
                                }
                            }
                        }
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
    /// parameters (the friction and tension outputs use the new parameters from the next
    /// step on). On error nothing changes.
    pub fn set_real(&mut self, vrs: &[u32], values: &[f64]) -> Result<(), Failure> {
        let mut next = self.settings;
        let mut inputs = self.inputs;
        let mut params_changed = false;
        for (vr, value) in vrs.iter().zip(values) {
            let v = self.variable(Kind::Real, *vr)?;
            self.settable(&v)?;
            match v.slot {
                Slot::Input(i) => inputs[i] = *value,
                Slot::Param(i) => {
                    let Some(dst) = variables::param_mut(&mut next.params, i) else {
                        return Err(Failure::error(format!("no parameter {i}")));
                    };
                    *dst = *value;
                    params_changed = true;
                }
                Slot::Step => next.h = *value,
                Slot::InitQ(i) => next.init.q[i] = *value,
                Slot::InitQd(i) => next.init.qd[i] = *value,
                _ => return Err(Failure::error(format!("{} cannot be set", v.name))),
            }
        }
        if params_changed && self.phase == Phase::StepComplete {
            let Some(old) = self.crane.as_ref() else {
                return Err(Failure::error("internal: no simulator in step mode"));
            };
            let rebuilt = build(&next, old.state()).map_err(|e| invalid(&e))?;
            self.crane = Some(rebuilt);
        }
        self.settings = next;
        self.inputs = inputs;
        Ok(())
    }

    /// `fmi2SetInteger`.
    pub fn set_integer(&mut self, vrs: &[u32], values: &[i32]) -> Result<(), Failure> {
        let mut next = self.settings;
        for (vr, value) in vrs.iter().zip(values) {
            let v = self.variable(Kind::Integer, *vr)?;
            self.settable(&v)?;
            match v.slot {
                Slot::SegmentBudget => next.segment_budget = *value,
                _ => return Err(Failure::error(format!("{} cannot be set", v.name))),
            }
        }
        self.settings = next;
        Ok(())
    }

    /// The running simulator (step mode), for tests.
    pub fn crane(&self) -> Option<&Crane> {
        self.crane.as_ref()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
}

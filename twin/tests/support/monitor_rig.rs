//! The host side of the monitor's rig (`crane_twin::logic::monitor_rig`): runs it with the f64
//! twin and collects alarms and passes. Shared by `tests/monitor_scenarios.rs` (one seed each
//! in CI) and `examples/monitor_table.rs` (the README's table).
#![allow(dead_code)]

use crane_model::Axis;
use crane_twin::logic::control::LoopConfig;
use crane_twin::logic::monitor::alarm::{Alarm, AlarmKind};
use crane_twin::logic::monitor::Settings;
pub use crane_twin::logic::monitor_rig::Fault;
use crane_twin::logic::monitor_rig::{self, Event};

/// One run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Run {
    /// The fault.
    pub fault: Fault,
    /// When it appears [s].
    pub onset: f64,
    /// Length of the run [s].
    pub duration: f64,
    /// Seed of the operator's moves, the plant's identification error and the encoder noise.
    pub seed: u32,
    /// A reset of the controller (a watchdog) at this time [s]: the monitor is built anew.
    pub reset_at: Option<f64>,
}

/// What the monitor said.
#[derive(Clone, Debug, Default)]
pub struct Outcome {
    /// Alarms with their time [s].
    pub alarms: Vec<(f64, Alarm)>,
    /// Times [s] at which the true X position crossed the bump centre (a pass).
    pub passes: Vec<f64>,
    /// Seconds simulated.
    pub seconds: f64,
}

struct Sink;

impl core::fmt::Write for Sink {
    fn write_str(&mut self, _: &str) -> core::fmt::Result {
        Ok(())
    }
}

/// Runs one scenario with the f64 twin, the monitor's default settings and the plant at
/// half the control period.
pub fn run(run: &Run) -> Outcome {
    let mut out = Outcome {
        seconds: run.duration,
        ..Outcome::default()
    };
    let rig = monitor_rig::Run {
        fault: run.fault,
        onset: run.onset,
        duration: run.duration,
        seed: run.seed,
        reset_at: run.reset_at,
        substeps: 2,
        maps_every: 0,
        record: false,
    };
    let settings = Settings::for_loop(&LoopConfig::default());
    let _ = monitor_rig::run::<f64, _, _>(&rig, &settings, "host", &mut Sink, |e| match e {
        Event::Alarm(t, a) => out.alarms.push((t, a)),
        Event::Pass(t) => out.passes.push(t),
        Event::MonitorStart | Event::MonitorEnd | Event::Period { .. } => {}
    });
    out
}

/// Whether an alarm is what the fault should raise, where it should.
pub fn expected(fault: &Fault, a: &Alarm) -> bool {
    match (fault, a.kind) {
        (Fault::DryFriction { .. }, AlarmKind::FrictionDrift { change }) => {
            a.axis != Axis::Rope && change > 0.0
        }
        (
            Fault::Bump { center, .. },
            AlarmKind::LocalFriction {
                position, change, ..
            },
        ) => a.axis == Axis::X && (f64::from(position) - center).abs() <= 0.02 && change > 0.0,
        (Fault::Stiction { .. }, AlarmKind::StictionRise { .. }) => a.axis != Axis::Rope,
        (Fault::Payload { .. }, AlarmKind::ModelMismatch { .. }) => true,
        _ => false,
    }
}

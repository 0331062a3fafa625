//! The friction monitor on the host rig (`support/monitor_rig.rs`): one seed of every
//! scenario of issue 21 (the README's table, `examples/monitor_table.rs`, runs 20 clean hours
//! and 10 seeds each), the reset behaviour and the memory bound. The rig's plant is this
//! project's model: these tests show that the monitor runs and finds what it should on it,
//! not that it generalises to other plants.
#[path = "support/monitor_rig.rs"]
mod rig;

use crane_model::{Axis, Params, State};
use crane_twin::logic::control::{Controller, LoopConfig};
use crane_twin::logic::monitor::alarm::AlarmKind;
use crane_twin::logic::monitor::{Monitor, Settings};
use rig::{Fault, Run};

const ONSET: f64 = 600.0;

fn run(fault: Fault, duration: f64) -> rig::Outcome {
    rig::run(&Run {
        fault,
        onset: ONSET,
        duration,
        seed: 1,
        reset_at: None,
    })
}

fn first_expected(fault: &Fault, o: &rig::Outcome) -> Option<f64> {
    o.alarms
        .iter()
        .find(|(t, a)| *t >= ONSET && rig::expected(fault, a))
        .map(|(t, _)| *t)
}

#[test]
fn a_clean_hour_raises_no_alarm() {
    let o = run(Fault::Clean, 3600.0);
    assert!(o.alarms.is_empty(), "{:?}", o.alarms);
}

#[test]
fn dry_friction_up_30_percent_is_a_drift_within_30_s_and_nothing_else() {
    let fault = Fault::DryFriction { factor: 1.3 };
    let o = run(fault, 700.0);
    let t = first_expected(&fault, &o).unwrap_or(f64::INFINITY);
    assert!(t - ONSET <= 30.0, "{:?}", o.alarms);
    assert!(
        o.alarms.iter().all(|(_, a)| rig::expected(&fault, a)),
        "{:?}",
        o.alarms
    );
}

#[test]
fn a_1_n_bump_is_local_at_its_place_within_3_passes() {
    let fault = Fault::Bump {
        center: 0.31,
        width: 0.015,
        amplitude: 1.0,
    };
    let o = run(fault, 800.0);
    let t = first_expected(&fault, &o).unwrap_or(f64::INFINITY);
    let passes = o.passes.iter().filter(|p| **p >= ONSET && **p <= t).count();
    assert!(
        t.is_finite() && passes <= 3,
        "{passes} passes: {:?}",
        o.alarms
    );
    assert!(
        o.alarms.iter().all(|(_, a)| rig::expected(&fault, a)),
        "{:?}",
        o.alarms
    );
}

#[test]
fn stiction_ratio_1_8_is_a_stiction_rise() {
    let fault = Fault::Stiction { ratio: 1.8 };
    let o = run(fault, 900.0);
    assert!(first_expected(&fault, &o).is_some(), "{:?}", o.alarms);
    assert!(
        o.alarms.iter().all(|(_, a)| rig::expected(&fault, a)),
        "{:?}",
        o.alarms
    );
}

#[test]
fn a_slow_drift_of_5_percent_an_hour_raises_nothing() {
    let o = run(Fault::SlowDrift { per_hour: 0.05 }, ONSET + 3600.0);
    assert!(o.alarms.is_empty(), "{:?}", o.alarms);
}

/// The monitor keeps nothing over a reset: a new one commissions again, judges nothing for
/// its commissioning, and then takes the rig as it found it (a fault present at the reset is
/// the new reference: it is not raised again). Stated in twin/README.md.
#[test]
fn after_a_reset_the_monitor_commissions_again_and_a_standing_fault_is_not_raised() {
    let fault = Fault::DryFriction { factor: 1.3 };
    let reset = 700.0;
    let o = rig::run(&Run {
        fault,
        onset: ONSET,
        duration: reset + 600.0,
        seed: 1,
        reset_at: Some(reset),
    });
    assert!(
        o.alarms.iter().any(|(t, _)| *t < reset),
        "raised before the reset: {:?}",
        o.alarms
    );
    assert!(
        o.alarms.iter().all(|(t, _)| *t < reset),
        "nothing after it: {:?}",
        o.alarms
    );
}

#[test]
fn non_finite_voltages_and_an_unwatched_axis_change_nothing() {
    let cfg = LoopConfig::default();
    let init = State {
        q: [0.2, 0.3, 0.35, core::f64::consts::FRAC_PI_2, 0.0],
        qd: [0.0; 5],
    };
    let ctrl =
        Controller::<f64>::new(&Params::default(), init, &cfg).unwrap_or_else(|e| panic!("{e:?}"));
    let mut m = Monitor::new(ctrl.observer(), Settings::for_loop(&cfg));
    for _ in 0..1000 {
        assert_eq!(
            m.update(ctrl.observer(), [f64::NAN, f64::INFINITY, f64::NAN]),
            None
        );
    }
    // Nothing non-finite entered any statistic.
    let state = format!("{m:?}");
    assert!(!state.contains("NaN") && !state.contains("inf"), "{state}");
    assert!(m
        .map(Axis::Rope, crane_model::Direction::Positive)
        .is_none());
    assert!(matches!(
        AlarmKind::FrictionDrift { change: 1.0 }.name(),
        "friction_drift"
    ));
}

/// A heavier payload is not friction: the twin stops tracking the plant, which the monitor
/// reports as `model_mismatch` (its friction maps are not judged while that stands).
#[test]
fn a_heavier_payload_is_a_model_mismatch_first() {
    let fault = Fault::Payload { mass: 2.0 };
    let o = run(fault, 700.0);
    let first = o.alarms.iter().find(|(t, _)| *t >= ONSET);
    assert!(
        first.is_some_and(|(t, a)| rig::expected(&fault, a) && t - ONSET <= 30.0),
        "{:?}",
        o.alarms
    );
}

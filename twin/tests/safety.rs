//! The safety supervisor, the period clock and the encoder-count extension of the board
//! (`crane_twin::logic::safety`), each path on its own.

use crane_twin::logic::safety::{
    extend_count, Cause, Inputs, OnAlarm, State, Supervisor, TickLatch, SAFE_OUTPUTS,
};

fn armed() -> Supervisor {
    let mut s = Supervisor::new();
    assert_eq!(s.arm(&Inputs::default()), Ok(()));
    s
}

#[test]
fn starts_safe_and_arms_only_with_every_input_clear() {
    let mut s = Supervisor::new();
    assert_eq!(s.state(), State::Safe(Cause::PowerOn));
    assert_eq!(s.outputs([3.0, -2.0, 1.0]), SAFE_OUTPUTS);
    let estop = Inputs {
        estop: true,
        ..Inputs::default()
    };
    assert_eq!(s.arm(&estop), Err(Cause::EStop));
    assert_eq!(s.state(), State::Safe(Cause::EStop));
    assert_eq!(s.arm(&Inputs::default()), Ok(()));
    assert_eq!(s.state(), State::Run);
    let o = s.outputs([3.0, -2.0, 1.0]);
    assert_eq!(o.volts, [3.0, -2.0, 1.0]);
    assert!(o.driver_enable && o.brake_release);
}

#[test]
fn estop_forces_the_safe_state_and_latches() {
    let mut s = armed();
    assert_eq!(s.check(&Inputs::default(), 0), State::Run);
    let estop = Inputs {
        estop: true,
        ..Inputs::default()
    };
    assert_eq!(s.check(&estop, 0), State::Safe(Cause::EStop));
    // released: still safe until re-armed
    assert_eq!(s.check(&Inputs::default(), 0), State::Safe(Cause::EStop));
    let o = s.outputs([12.0, 12.0, 12.0]);
    assert_eq!(o, SAFE_OUTPUTS);
    assert!(!o.driver_enable && !o.brake_release);
}

#[test]
fn every_limit_switch_forces_the_safe_state_naming_axis_and_end() {
    for axis in 0..3 {
        for end in 0..2 {
            let mut s = armed();
            let mut i = Inputs::default();
            i.limits[axis][end] = true;
            assert_eq!(
                s.check(&i, 0),
                State::Safe(Cause::Limit {
                    axis: axis as u8,
                    positive: end == 1
                })
            );
            assert_eq!(s.outputs([1.0; 3]), SAFE_OUTPUTS);
        }
    }
}

#[test]
fn driver_fault_forces_the_safe_state_and_the_first_cause_is_kept() {
    let mut s = armed();
    let fault = Inputs {
        driver_fault: true,
        ..Inputs::default()
    };
    assert_eq!(s.check(&fault, 0), State::Safe(Cause::DriverFault));
    let both = Inputs {
        estop: true,
        driver_fault: true,
        ..Inputs::default()
    };
    assert_eq!(s.check(&both, 5), State::Safe(Cause::DriverFault));
    s.trip(Cause::Overrun);
    assert_eq!(s.state(), State::Safe(Cause::DriverFault));
    // cannot re-arm while an input is active, and the latched cause stays
    assert_eq!(s.arm(&both), Err(Cause::EStop));
    assert_eq!(s.state(), State::Safe(Cause::DriverFault));
}

#[test]
fn missed_periods_beyond_the_limit_trip_overrun() {
    let mut s = armed();
    assert_eq!(
        s.check(&Inputs::default(), Supervisor::MAX_MISSED),
        State::Run
    );
    assert_eq!(
        s.check(&Inputs::default(), Supervisor::MAX_MISSED + 1),
        State::Safe(Cause::Overrun)
    );
}

#[test]
fn tick_latch_counts_overruns_and_missed_periods() {
    let mut t = TickLatch::new();
    assert_eq!(t.take(), None);
    t.on_tick();
    assert_eq!(t.take(), Some(0));
    assert_eq!(t.take(), None);
    // the loop is late: three ticks before it takes one
    t.on_tick();
    t.on_tick();
    t.on_tick();
    assert_eq!(t.overruns(), 2);
    assert_eq!(t.take(), Some(2));
    for _ in 0..1000 {
        t.on_tick();
        assert_eq!(t.take(), Some(0));
    }
    assert_eq!(t.ticks(), 1004);
    assert_eq!(t.overruns(), 2);
}

#[test]
fn sixteen_bit_counts_extend_across_wraps_both_ways() {
    // forward through 65535 -> 0
    let mut c = 65_530i32;
    let mut raw = 65_530u16;
    for _ in 0..20 {
        raw = raw.wrapping_add(1);
        c = extend_count(c, raw);
    }
    assert_eq!(c, 65_550);
    // backward below zero
    let mut c = 3i32;
    let mut raw = 3u16;
    for _ in 0..10 {
        raw = raw.wrapping_sub(1);
        c = extend_count(c, raw);
    }
    assert_eq!(c, -7);
    // the largest step it resolves, each way
    assert_eq!(extend_count(0, 32_767), 32_767);
    assert_eq!(extend_count(0, 32_768), -32_768);
    assert_eq!(extend_count(100_000, (100_000u32 - 30_000) as u16), 70_000);
}

#[test]
fn a_watchdog_reset_latches_before_arming() {
    let mut s = Supervisor::new();
    s.trip(Cause::WatchdogReset);
    assert_eq!(s.state(), State::Safe(Cause::WatchdogReset));
    assert_eq!(
        s.check(&Inputs::default(), 0),
        State::Safe(Cause::WatchdogReset)
    );
    assert_eq!(s.outputs([5.0; 3]), SAFE_OUTPUTS);
}

#[test]
fn after_a_watchdog_reset_arming_is_refused_until_power_cycled() {
    let mut s = Supervisor::new();
    s.trip(Cause::WatchdogReset);
    // every input clear, tried again and again: stays safe
    for _ in 0..3 {
        assert_eq!(s.arm(&Inputs::default()), Err(Cause::WatchdogReset));
        assert_eq!(s.state(), State::Safe(Cause::WatchdogReset));
    }
    // an active input does not replace the latched cause either
    let estop = Inputs {
        estop: true,
        ..Inputs::default()
    };
    assert_eq!(s.arm(&estop), Err(Cause::WatchdogReset));
    assert_eq!(s.state(), State::Safe(Cause::WatchdogReset));
    // a power-cycle is a new supervisor: it arms
    assert_eq!(Supervisor::new().arm(&Inputs::default()), Ok(()));
}

#[test]
fn the_loop_feeds_the_watchdog_only_while_it_keeps_its_period() {
    let mut s = Supervisor::new();
    // safe at power-on (driving the outputs off): feeds
    assert!(s.feeds_watchdog());
    s.arm(&Inputs::default()).expect("clear inputs");
    for missed in 0..=Supervisor::MAX_MISSED {
        s.check(&Inputs::default(), missed);
        assert!(s.feeds_watchdog(), "late by {missed} periods is tolerated");
    }
    // an e-stop is a healthy safe state: still fed (no reset loop with floating pins)
    let mut e = s;
    e.check(
        &Inputs {
            estop: true,
            ..Inputs::default()
        },
        0,
    );
    assert_eq!(e.state(), State::Safe(Cause::EStop));
    assert!(e.feeds_watchdog());
    // one period too many missed: the loop is not healthy, and never feeds again
    s.check(&Inputs::default(), Supervisor::MAX_MISSED + 1);
    assert_eq!(s.state(), State::Safe(Cause::Overrun));
    for _ in 0..10 {
        s.check(&Inputs::default(), 0);
        assert!(!s.feeds_watchdog());
    }
    // (a watchdog-reset latch keeps feeding: safe, alive, until power-cycled)
    let mut w = Supervisor::new();
    w.trip(Cause::WatchdogReset);
    assert!(w.feeds_watchdog());
}

#[test]
fn a_monitor_alarm_is_only_reported_by_default() {
    let mut s = armed();
    assert!(!s.alarm());
    assert_eq!(s.outputs([12.0, -12.0, 3.0]).volts, [12.0, -12.0, 3.0]);
}

#[test]
fn derating_limits_every_command_until_acknowledged_and_never_lifts_the_safe_state() {
    let on = OnAlarm::derate(50).unwrap_or_default();
    assert_eq!(on, OnAlarm::Derate { percent: 50 });
    assert_eq!(OnAlarm::derate(0), None);
    assert_eq!(OnAlarm::derate(100), None);
    let mut s = armed().with_on_alarm(on);
    assert_eq!(s.outputs([12.0, -12.0, 3.0]).volts, [12.0, -12.0, 3.0]);
    assert!(s.alarm());
    assert_eq!(s.outputs([12.0, -12.0, 3.0]).volts, [6.0, -6.0, 3.0]);
    assert!(s.outputs([f64::NAN; 3]).volts.iter().all(|v| v.is_nan()));
    s.trip(Cause::EStop);
    assert_eq!(s.outputs([12.0; 3]), SAFE_OUTPUTS);
    s.acknowledge();
    assert!(!s.derated());
}

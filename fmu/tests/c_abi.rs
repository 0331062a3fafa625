//! The C entry points called in-process, as an importer would: every state component
//! (positions and velocities), mode, friction force, tension and payload coordinate equals the
//! model's own run bit for bit (also with stiction and with the `tanh` law); an FMU state set
//! again or serialized and read into another instance continues to the same bits; null
//! pointers, bad arguments and corrupt serialized states give error statuses.
//!
//! (`fmu/tests/test_fmu.py` does the same through FMPy and the packed `crane.fmu`, against
//! `crane simulate`, whose CSV has no velocities: the velocities are compared here.)

// Every unsafe call here passes pointers that are null or valid for the call.
#![allow(clippy::undocumented_unsafe_blocks)]

use crane_fmu::description::guid;
use crane_fmu::ffi::*;
use crane_model::{Config, Crane, Extensions, FrictionLaw, Mode, Params, State, Stiction};
use std::ffi::CString;
use std::ptr::{null, null_mut};

fn callbacks() -> fmi2CallbackFunctions {
    fmi2CallbackFunctions {
        logger: None,
        allocate_memory: None,
        free_memory: None,
        step_finished: None,
        component_environment: null_mut(),
    }
}

fn instantiate(cb: &fmi2CallbackFunctions) -> fmi2Component {
    let g = CString::new(guid()).unwrap();
    // SAFETY (whole test): every pointer passed is null or valid for the call.
    unsafe { fmi2Instantiate(c"crane".as_ptr(), 1, g.as_ptr(), null(), cb, 0, 0) }
}

fn get(c: fmi2Component, vr: &[u32]) -> Vec<f64> {
    let mut out = vec![0.0; vr.len()];
    let s = unsafe { fmi2GetReal(c, vr.as_ptr(), vr.len(), out.as_mut_ptr()) };
    assert_eq!(s, FMI2_OK);
    out
}

fn modes(c: fmi2Component) -> Vec<i32> {
    let vr = [200, 201, 202];
    let mut out = vec![9; 3];
    assert_eq!(
        unsafe { fmi2GetInteger(c, vr.as_ptr(), 3, out.as_mut_ptr()) },
        FMI2_OK
    );
    out
}

/// Multisine voltages plus steps (moves and stops every axis), as `crane simulate` computes
/// inputs: sums of `offset + amplitude sin(2 pi f t)`, clamped to +-12 V.
fn input(t: f64) -> [f64; 3] {
    let s = |a: f64, f: f64| a * (2.0 * std::f64::consts::PI * f * t).sin();
    let mut u = [
        s(1.5, 0.404) + s(1.5, 0.942),
        s(1.5, 0.314) + s(1.5, 0.523),
        s(0.5, 0.406),
    ];
    if (1.0..1.5).contains(&t) {
        u[2] -= 2.0;
    }
    if (3.0..3.5).contains(&t) {
        u[2] += 2.5;
    }
    if (2.0..2.4).contains(&t) {
        u[0] += 3.0;
    }
    u
}

fn code(m: Mode) -> i32 {
    match m {
        Mode::Negative => -1,
        Mode::Stopped => 0,
        Mode::Positive => 1,
    }
}

/// An FMU run's set-up: parameters set in initialization mode (Real and Integer, by value
/// reference), the same simulator built with the model directly, and a factor on the inputs
/// (above 4 they saturate at +-12 V).
struct Setup {
    reals: Vec<(u32, f64)>,
    ints: Vec<(u32, i32)>,
    crane: Crane,
    scale: f64,
}

fn init() -> State {
    State {
        q: [0.25, 0.3, 0.35, std::f64::consts::FRAC_PI_2, 0.0],
        qd: [0.0; 5],
    }
}

/// Runs 4 s through the C ABI with communication step `k h` and compares every output with
/// the model after every communication step; `all_modes`: every axis must have been stopped
/// and moved both ways. Returns the model's final state.
fn compare_setup(k: usize, setup: Setup, all_modes: bool) -> State {
    let cb = callbacks();
    let c = instantiate(&cb);
    assert!(!c.is_null());
    unsafe {
        assert_eq!(fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0), FMI2_OK);
        assert_eq!(fmi2EnterInitializationMode(c), FMI2_OK);
        for (vr, x) in &setup.reals {
            assert_eq!(fmi2SetReal(c, vr, 1, x), FMI2_OK, "vr {vr}");
        }
        for (vr, x) in &setup.ints {
            assert_eq!(fmi2SetInteger(c, vr, 1, x), FMI2_OK, "vr {vr}");
        }
        assert_eq!(fmi2ExitInitializationMode(c), FMI2_OK);
    }
    let mut crane = setup.crane;
    let h = 1e-3;
    let outs: Vec<u32> = (100..117).collect();
    let mut seen = [[false; 3]; 3];
    let n = 4000 / k;
    for j in 0..n {
        let t = (j * k) as f64 * h;
        let u = input(t).map(|v| v * setup.scale);
        unsafe {
            assert_eq!(fmi2SetReal(c, [0, 1, 2].as_ptr(), 3, u.as_ptr()), FMI2_OK);
            assert_eq!(fmi2DoStep(c, t, k as f64 * h, 1), FMI2_OK, "t = {t}");
        }
        for _ in 0..k {
            crane.step(u).unwrap();
        }
        let s = crane.state();
        let o = crane.output().unwrap();
        let want: Vec<f64> =
            s.q.iter()
                .chain(&s.qd)
                .chain(&o.friction)
                .chain([&o.tension])
                .chain(&o.payload)
                .copied()
                .collect();
        let got = get(c, &outs);
        for (i, (g, w)) in got.iter().zip(&want).enumerate() {
            assert_eq!(
                g.to_bits(),
                w.to_bits(),
                "step {j}, output vr {}: {g} vs {w}",
                100 + i
            );
        }
        let m = crane.modes();
        assert_eq!(modes(c), m.map(code).to_vec());
        for (a, mode) in m.iter().enumerate() {
            seen[a][(code(*mode) + 1) as usize] = true;
        }
    }
    if all_modes {
        // Every axis was stopped and moved in both directions at some point (the automaton
        // ran).
        for (a, s) in seen.iter().enumerate() {
            assert!(s.iter().all(|x| *x), "axis {a}: modes seen {s:?}");
        }
    }
    unsafe {
        assert_eq!(fmi2Terminate(c), FMI2_OK);
        fmi2FreeInstance(c);
    }
    crane.state()
}

/// The default crane with a 0.064 kg payload, as `test_fmu.py` runs it against
/// `crane simulate`.
fn compare(k: usize) {
    let payload = 0.064;
    let params = Params {
        payload_mass: payload,
        ..Params::default()
    };
    let setup = Setup {
        reals: vec![(1000, payload)],
        ints: vec![],
        crane: Crane::new(&params, Config::default(), init()).unwrap(),
        scale: 1.0,
    };
    compare_setup(k, setup, true);
}

#[test]
fn every_state_equals_the_model_bit_for_bit_step_h() {
    compare(1);
}

#[test]
fn every_state_equals_the_model_bit_for_bit_step_5h() {
    compare(5);
}

#[test]
fn null_pointers_and_bad_arguments_are_errors_not_crashes() {
    let cb = callbacks();
    let g = CString::new(guid()).unwrap();
    unsafe {
        // Instantiate: null callbacks, null/empty name, model exchange, wrong GUID.
        assert!(fmi2Instantiate(c"a".as_ptr(), 1, g.as_ptr(), null(), null(), 0, 0).is_null());
        assert!(fmi2Instantiate(null(), 1, g.as_ptr(), null(), &cb, 0, 0).is_null());
        assert!(fmi2Instantiate(c"".as_ptr(), 1, g.as_ptr(), null(), &cb, 0, 0).is_null());
        assert!(fmi2Instantiate(c"a".as_ptr(), 0, g.as_ptr(), null(), &cb, 0, 0).is_null());
        assert!(fmi2Instantiate(c"a".as_ptr(), 1, c"{x}".as_ptr(), null(), &cb, 0, 0).is_null());
        assert!(fmi2Instantiate(c"a".as_ptr(), 1, null(), null(), &cb, 0, 0).is_null());
        // Null component everywhere.
        let mut v = [0.0];
        assert_eq!(
            fmi2GetReal(null_mut(), [100].as_ptr(), 1, v.as_mut_ptr()),
            FMI2_ERROR
        );
        assert_eq!(
            fmi2SetReal(null_mut(), [0].as_ptr(), 1, v.as_ptr()),
            FMI2_ERROR
        );
        assert_eq!(fmi2DoStep(null_mut(), 0.0, 1e-3, 0), FMI2_ERROR);
        assert_eq!(fmi2Reset(null_mut()), FMI2_ERROR);
        assert_eq!(fmi2ExitInitializationMode(null_mut()), FMI2_ERROR);
        fmi2FreeInstance(null_mut());

        let c = instantiate(&cb);
        assert!(!c.is_null());
        // Null arrays with nvr > 0; nvr = 0 with null arrays is fine.
        assert_eq!(fmi2GetReal(c, null(), 1, v.as_mut_ptr()), FMI2_ERROR);
        assert_eq!(fmi2GetReal(c, [1000].as_ptr(), 1, null_mut()), FMI2_ERROR);
        assert_eq!(fmi2SetReal(c, [1000].as_ptr(), 1, null()), FMI2_ERROR);
        assert_eq!(fmi2SetReal(c, null(), 0, null()), FMI2_OK);
        // Unknown value references, outputs before initialisation, unsupported calls.
        assert_eq!(
            fmi2GetReal(c, [4242].as_ptr(), 1, v.as_mut_ptr()),
            FMI2_ERROR
        );
        assert_eq!(
            fmi2GetReal(c, [100].as_ptr(), 1, v.as_mut_ptr()),
            FMI2_ERROR
        );
        assert_eq!(
            fmi2SetReal(c, [100].as_ptr(), 1, [1.0].as_ptr()),
            FMI2_ERROR
        );
        assert_eq!(
            fmi2GetBoolean(c, [0].as_ptr(), 1, [0].as_mut_ptr()),
            FMI2_ERROR
        );
        // No Boolean or String variables: a reference is an error, none is fine.
        assert_eq!(fmi2SetBoolean(c, [0].as_ptr(), 1, [0].as_ptr()), FMI2_ERROR);
        assert_eq!(
            fmi2GetString(c, [0].as_ptr(), 1, [null()].as_mut_ptr()),
            FMI2_ERROR
        );
        assert_eq!(
            fmi2SetString(c, [0].as_ptr(), 1, [null()].as_ptr()),
            FMI2_ERROR
        );
        assert_eq!(
            fmi2GetString(c, [0].as_ptr(), 0, [null()].as_mut_ptr()),
            FMI2_OK
        );
        assert_eq!(fmi2GetFMUstate(c, null_mut()), FMI2_ERROR);
        assert_eq!(fmi2DoStep(c, 0.0, 1e-3, 0), FMI2_ERROR); // not initialised
                                                             // Parameters read back as set; start values from Params::default().
        assert_eq!(fmi2GetReal(c, [1000].as_ptr(), 1, v.as_mut_ptr()), FMI2_OK);
        assert_eq!(v[0], Params::default().payload_mass);
        // A wrong parameter: error at exit initialisation, then reset recovers.
        assert_eq!(fmi2EnterInitializationMode(c), FMI2_OK);
        assert_eq!(
            fmi2SetReal(c, [1002].as_ptr(), 1, [f64::NAN].as_ptr()),
            FMI2_OK
        );
        assert_eq!(fmi2ExitInitializationMode(c), FMI2_ERROR);
        assert_eq!(fmi2Reset(c), FMI2_OK);
        assert_eq!(fmi2EnterInitializationMode(c), FMI2_OK);
        assert_eq!(fmi2ExitInitializationMode(c), FMI2_OK);
        // Not a multiple of h; a NaN input rejects the step (the model's StepError).
        assert_eq!(fmi2DoStep(c, 0.0, 1.5e-3, 0), FMI2_ERROR);
        assert_eq!(fmi2DoStep(c, 0.0, 2e-3, 0), FMI2_OK);
        assert_eq!(
            fmi2SetReal(c, [0].as_ptr(), 1, [f64::NAN].as_ptr()),
            FMI2_OK
        );
        assert_eq!(fmi2DoStep(c, 2e-3, 1e-3, 0), FMI2_ERROR);
        let mut terminated = 0;
        assert_eq!(fmi2GetBooleanStatus(c, 3, &mut terminated), FMI2_OK);
        assert_eq!(terminated, 1);
        let mut t = 0.0;
        assert_eq!(fmi2GetRealStatus(c, 2, &mut t), FMI2_OK);
        assert_eq!(t, 2e-3);
        fmi2FreeInstance(c);
    }
}

#[test]
fn a_tunable_parameter_changed_while_stepping_continues_from_the_current_state() {
    let cb = callbacks();
    let c = instantiate(&cb);
    let init = State {
        q: [0.25, 0.3, 0.35, std::f64::consts::FRAC_PI_2, 0.0],
        qd: [0.0; 5],
    };
    let mut crane: Crane = Crane::new(&Params::default(), Config::default(), init).unwrap();
    let u = [4.0, -3.0, 0.0];
    unsafe {
        assert_eq!(fmi2EnterInitializationMode(c), FMI2_OK);
        assert_eq!(fmi2ExitInitializationMode(c), FMI2_OK);
        assert_eq!(fmi2SetReal(c, [0, 1, 2].as_ptr(), 3, u.as_ptr()), FMI2_OK);
        assert_eq!(fmi2DoStep(c, 0.0, 0.5, 0), FMI2_OK);
    }
    for _ in 0..500 {
        crane.step(u).unwrap();
    }
    // Heavier payload from t = 0.5 s: the model rebuilt at the current state (modes from the
    // velocities, as `Crane::new` derives them).
    let heavier = Params {
        payload_mass: 0.8,
        ..Params::default()
    };
    let mut crane: Crane = Crane::new(&heavier, Config::default(), crane.state()).unwrap();
    unsafe {
        assert_eq!(fmi2SetReal(c, [1000].as_ptr(), 1, [0.8].as_ptr()), FMI2_OK);
        // A bad value is refused and changes nothing.
        assert_eq!(
            fmi2SetReal(c, [1000].as_ptr(), 1, [-0.8].as_ptr()),
            FMI2_ERROR
        );
        assert_eq!(fmi2DoStep(c, 0.5, 0.5, 0), FMI2_OK);
    }
    for _ in 0..500 {
        crane.step(u).unwrap();
    }
    let s = crane.state();
    let want: Vec<u64> = s.q.iter().chain(&s.qd).map(|v| v.to_bits()).collect();
    let got: Vec<u64> = get(c, &(100..110).collect::<Vec<u32>>())
        .iter()
        .map(|v| v.to_bits())
        .collect();
    assert_eq!(got, want);
    unsafe { fmi2FreeInstance(c) };
}

/// Stiction on X (ratio 1.5), Y (1.3) and the rope (1.2, Stribeck velocity 0.01 m/s), set as
/// FMU parameters, equals the model with the same `Extensions` bit for bit (the Python
/// package's `stiction=` builds exactly these), with inputs up to 18 V (saturated).
#[test]
fn stiction_equals_the_model_with_stiction_bit_for_bit() {
    let s = |ratio, velocity| Some(Stiction { ratio, velocity });
    let ext = Extensions {
        stiction: [s(1.5, 0.005), s(1.3, 0.005), s(1.2, 0.01)],
        ..Extensions::default()
    };
    let crane = Crane::new(&Params::default(), Config::default(), init()).unwrap();
    let plain = crane.clone();
    let setup = Setup {
        reals: vec![(1300, 1.5), (1302, 1.3), (1304, 1.2), (1305, 0.01)],
        ints: vec![],
        crane: crane.with_extensions(&ext).unwrap(),
        scale: 3.0,
    };
    let with = compare_setup(1, setup, true);
    // Stiction changed the run: the same inputs without it end elsewhere.
    let without = compare_setup(
        1,
        Setup {
            reals: vec![],
            ints: vec![],
            crane: plain,
            scale: 3.0,
        },
        true,
    );
    assert_ne!(with.q, without.q);
}

/// The smooth `tanh` law (`config.law.kind = 1`, `config.law.gamma = 250 s/m`) equals the
/// model's `FrictionLaw::Tanh` bit for bit.
#[test]
fn the_tanh_law_equals_the_model_bit_for_bit() {
    let config = Config {
        h: 1e-3,
        law: FrictionLaw::Tanh { gamma: 250.0 },
    };
    let setup = Setup {
        reals: vec![(1111, 250.0)],
        ints: vec![(1201, 1)],
        crane: Crane::new(&Params::default(), config, init()).unwrap(),
        scale: 1.0,
    };
    compare_setup(5, setup, false);
}

/// Every real output (bits), mode, input and the time of an instance.
fn snapshot_of(c: fmi2Component) -> Vec<u64> {
    let mut v: Vec<u64> = get(c, &(100..117).chain(0..3).collect::<Vec<u32>>())
        .iter()
        .map(|x| x.to_bits())
        .collect();
    v.extend(modes(c).iter().map(|m| *m as u64));
    let mut t = 0.0;
    assert_eq!(unsafe { fmi2GetRealStatus(c, 2, &mut t) }, FMI2_OK);
    v.push(t.to_bits());
    v
}

/// Steps `n` times from step `from` with the (scaled, saturating) multisine; every output
/// after every step.
fn run(c: fmi2Component, from: usize, n: usize) -> Vec<Vec<u64>> {
    (from..from + n)
        .map(|j| {
            let t = j as f64 * 1e-3;
            let u = input(t).map(|v| 3.0 * v);
            unsafe {
                assert_eq!(fmi2SetReal(c, [0, 1, 2].as_ptr(), 3, u.as_ptr()), FMI2_OK);
                assert_eq!(fmi2DoStep(c, t, 1e-3, 0), FMI2_OK, "t = {t}");
            }
            snapshot_of(c)
        })
        .collect()
}

/// An initialised instance with stiction on X and Y.
fn running(cb: &fmi2CallbackFunctions) -> fmi2Component {
    let c = instantiate(cb);
    assert!(!c.is_null());
    unsafe {
        assert_eq!(fmi2EnterInitializationMode(c), FMI2_OK);
        let (vr, x) = ([1300, 1302], [1.4, 1.2]);
        assert_eq!(fmi2SetReal(c, vr.as_ptr(), 2, x.as_ptr()), FMI2_OK);
        assert_eq!(fmi2ExitInitializationMode(c), FMI2_OK);
    }
    c
}

#[test]
fn an_fmu_state_set_again_or_deserialized_continues_bit_for_bit() {
    let cb = callbacks();
    let c = running(&cb);
    run(c, 0, 1500);
    let mut state: fmi2FMUstate = null_mut();
    let (mut size, mut bytes) = (0usize, Vec::new());
    unsafe {
        assert_eq!(fmi2GetFMUstate(c, &mut state), FMI2_OK);
        assert!(!state.is_null());
        assert_eq!(fmi2SerializedFMUstateSize(c, state, &mut size), FMI2_OK);
        bytes.resize(size, 0 as fmi2Byte);
        assert_eq!(
            fmi2SerializeFMUstate(c, state, bytes.as_mut_ptr(), size),
            FMI2_OK
        );
    }
    let at_t1 = snapshot_of(c);
    let first = run(c, 1500, 1500);
    // Whatever happened since (other inputs, a heavier payload) is undone by the state.
    unsafe {
        assert_eq!(
            fmi2SetReal(c, [0, 1000].as_ptr(), 2, [7.0, 0.9].as_ptr()),
            FMI2_OK
        );
        assert_eq!(fmi2SetFMUstate(c, state), FMI2_OK);
    }
    assert_eq!(snapshot_of(c), at_t1);
    assert_eq!(run(c, 1500, 1500), first);
    // A second get into the same state object overwrites it in place.
    let before = state;
    unsafe { assert_eq!(fmi2GetFMUstate(c, &mut state), FMI2_OK) };
    assert_eq!(state, before);

    // The bytes, into a fresh instance that was never initialised.
    let c2 = instantiate(&cb);
    let mut s2: fmi2FMUstate = null_mut();
    let mut again = vec![0 as fmi2Byte; size];
    unsafe {
        assert_eq!(
            fmi2DeSerializeFMUstate(c2, bytes.as_ptr(), size, &mut s2),
            FMI2_OK
        );
        assert_eq!(fmi2SetFMUstate(c2, s2), FMI2_OK);
        assert_eq!(
            fmi2SerializeFMUstate(c2, s2, again.as_mut_ptr(), size),
            FMI2_OK
        );
    }
    assert_eq!(again, bytes);
    assert_eq!(snapshot_of(c2), at_t1);
    assert_eq!(run(c2, 1500, 1500), first);
    // The run exercised the automaton after t1: X reversed, the rope stopped and moved.
    let mode_x: Vec<u64> = first.iter().map(|r| r[20]).collect();
    assert!(mode_x.contains(&1) && mode_x.contains(&u64::MAX));
    unsafe {
        assert_eq!(fmi2FreeFMUstate(c, &mut state), FMI2_OK);
        assert!(state.is_null());
        assert_eq!(fmi2FreeFMUstate(c, &mut state), FMI2_OK); // null: ignored
        assert_eq!(fmi2FreeFMUstate(c2, &mut s2), FMI2_OK);
        fmi2FreeInstance(c);
        fmi2FreeInstance(c2);
    }
}

#[test]
fn a_corrupt_or_wrong_size_state_is_an_error_not_a_crash() {
    let cb = callbacks();
    let c = running(&cb);
    run(c, 0, 200);
    let mut state: fmi2FMUstate = null_mut();
    let mut size = 0usize;
    unsafe {
        // Null pointers.
        assert_eq!(fmi2GetFMUstate(null_mut(), &mut state), FMI2_ERROR);
        assert_eq!(fmi2GetFMUstate(c, null_mut()), FMI2_ERROR);
        assert_eq!(fmi2SetFMUstate(c, null_mut()), FMI2_ERROR);
        assert_eq!(fmi2FreeFMUstate(c, null_mut()), FMI2_ERROR);
        assert_eq!(
            fmi2SerializedFMUstateSize(c, null_mut(), &mut size),
            FMI2_ERROR
        );
        assert_eq!(fmi2GetFMUstate(c, &mut state), FMI2_OK);
        assert_eq!(fmi2SerializedFMUstateSize(c, state, null_mut()), FMI2_ERROR);
        assert_eq!(fmi2SerializedFMUstateSize(c, state, &mut size), FMI2_OK);
        assert!(size > 100, "{size}");
        // Serialize into a buffer of the wrong size, or none.
        let mut buf = vec![0 as fmi2Byte; size + 1];
        assert_eq!(
            fmi2SerializeFMUstate(c, state, buf.as_mut_ptr(), size - 1),
            FMI2_ERROR
        );
        assert_eq!(
            fmi2SerializeFMUstate(c, state, buf.as_mut_ptr(), size + 1),
            FMI2_ERROR
        );
        assert_eq!(
            fmi2SerializeFMUstate(c, state, null_mut(), size),
            FMI2_ERROR
        );
        assert_eq!(
            fmi2SerializeFMUstate(c, state, buf.as_mut_ptr(), size),
            FMI2_OK
        );
        // Deserialize: truncated, one byte more, a flipped bit, empty, null arguments; each
        // leaves `*state` as it was (here null).
        let mut out: fmi2FMUstate = null_mut();
        let bad = |bytes: &[fmi2Byte], out: &mut fmi2FMUstate| {
            fmi2DeSerializeFMUstate(c, bytes.as_ptr(), bytes.len(), out)
        };
        assert_eq!(bad(&buf[..size - 1], &mut out), FMI2_ERROR);
        assert_eq!(bad(&buf[..size + 1], &mut out), FMI2_ERROR);
        let mut flipped = buf[..size].to_vec();
        flipped[size / 2] ^= 0x10;
        assert_eq!(bad(&flipped, &mut out), FMI2_ERROR);
        assert_eq!(bad(&[], &mut out), FMI2_ERROR);
        assert_eq!(
            fmi2DeSerializeFMUstate(c, null(), size, &mut out),
            FMI2_ERROR
        );
        assert_eq!(
            fmi2DeSerializeFMUstate(c, buf.as_ptr(), size, null_mut()),
            FMI2_ERROR
        );
        assert!(out.is_null());
        // The instance is still usable, and the good bytes still read.
        assert_eq!(bad(&buf[..size], &mut out), FMI2_OK);
        assert_eq!(fmi2SetFMUstate(c, out), FMI2_OK);
        assert_eq!(fmi2DoStep(c, 0.2, 1e-3, 0), FMI2_OK);
        assert_eq!(fmi2FreeFMUstate(c, &mut out), FMI2_OK);
        assert_eq!(fmi2FreeFMUstate(c, &mut state), FMI2_OK);
        fmi2FreeInstance(c);
    }
}

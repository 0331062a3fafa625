//! The model (`crane_model`, f64) must reproduce the independent reference
//! (`host_tests::reference`) bit for bit: every component of q and qd, the modes and the time,
//! after every step (accepted or rejected, with the same error), for random parameters,
//! initial states, input sequences and extensions.

mod common;

use common::{compare, compare_output, pair, pair_ext, Piece, Program, FRAC_PI_2};
use crane_model::{
    Axis, Bump, Direction, Extensions, FrictionLaw, Params, StepError, Stiction, MIN_HANG,
};
use host_tests::reference::{self, RefError, RefEventKind, RefExtensions};
use proptest::prelude::*;
use proptest::test_runner::{Config as RunnerConfig, TestRunner};
use std::cell::RefCell;

/// Steps per random case (>= 5000 as required).
const STEPS: usize = 5000;
/// Random cases of the hybrid bit-exact test (>= 256 as required).
const HYBRID_CASES: u32 = 512;

fn axis_factors() -> impl Strategy<Value = (f64, f64, f64, f64, [f64; 5], [f64; 5])> {
    (
        0.5f64..1.5,                        // inertia
        0.8f64..1.25,                       // gain
        0.2f64..1.5,                        // viscous +
        0.2f64..1.5,                        // viscous -
        prop::array::uniform5(0.6f64..1.4), // dry + coefficients
        prop::array::uniform5(0.6f64..1.4), // dry - coefficients
    )
}

/// Random valid parameters: the docs/MODEL.md defaults, perturbed.
fn params_strategy() -> impl Strategy<Value = Params> {
    (
        0.05f64..0.6,
        prop::array::uniform2(0.7f64..1.3),
        prop::array::uniform3(axis_factors()),
        prop::array::uniform2(0.3f64..3.0),
    )
        .prop_map(|(mp, masses, axes, damp)| {
            let d = Params::default();
            let mut p = Params {
                payload_mass: mp,
                trolley_mass: d.trolley_mass * masses[0],
                rail_mass: d.rail_mass * masses[1],
                ..d
            };
            for (a, f) in [&mut p.x, &mut p.y, &mut p.rope].into_iter().zip(axes) {
                a.inertia *= f.0;
                a.gain *= f.1;
                a.viscous_pos *= f.2;
                a.viscous_neg *= f.3;
                for k in 0..5 {
                    a.dry_pos[k] *= f.4[k];
                    a.dry_neg[k] *= f.5[k];
                }
            }
            p.damping_alpha *= damp[0];
            p.damping_beta *= damp[1];
            p
        })
}

/// Random initial state within the limits and the swing domain: each drive axis at its lower
/// limit, its upper limit or inside, stopped (`0.0` or `-0.0`) or moving either way; swing
/// angles `alpha = pi/2 +- 0.5`, `|beta| < 0.4`, so `sin(alpha) cos(beta) > 0.8 > MIN_HANG`.
fn init_strategy(p: Params) -> impl Strategy<Value = ([f64; 5], [f64; 5])> {
    let axis = (0u8..4, 0.0f64..1.0, 0u8..4, 0.01f64..0.3);
    (
        prop::array::uniform3(axis),
        -0.5f64..0.5,
        -0.4f64..0.4,
        -1.0f64..1.0,
        -1.0f64..1.0,
    )
        .prop_map(move |(axes, da, b, ad, bd)| {
            let mut q = [0.0; 5];
            let mut qd = [0.0; 5];
            for (i, (a, (pk, frac, vk, speed))) in p.axes().into_iter().zip(axes).enumerate() {
                q[i] = match pk {
                    0 => a.min,
                    1 => a.max,
                    _ => a.min + (a.max - a.min) * frac,
                };
                qd[i] = match vk {
                    0 => 0.0,
                    1 => -0.0,
                    2 => speed,
                    _ => -speed,
                };
            }
            q[3] = FRAC_PI_2 + da;
            q[4] = b;
            qd[3] = ad;
            qd[4] = bd;
            (q, qd)
        })
}

fn piece_strategy() -> impl Strategy<Value = (Piece, usize)> {
    let sine = (0.0f64..6.0, 0.1f64..3.0, 0.0f64..6.3);
    let piece = prop_oneof![
        (-20.0f64..20.0).prop_map(Piece::Hold),
        (-20.0f64..20.0, -20.0f64..20.0).prop_map(|(a, b)| Piece::Ramp(a, b)),
        prop::array::uniform4(sine).prop_map(Piece::Multisine),
        (-20.0f64..20.0, 0.05f64..2.0).prop_map(|(a, t)| Piece::Square(a, t)),
    ];
    (piece, 100usize..2000)
}

/// Random input program of one axis: steps, ramps, multisines, squares, and always one
/// saturating square wave (|u| > 12 V).
fn program_strategy() -> impl Strategy<Value = Program> {
    (
        prop::collection::vec(piece_strategy(), 1..5),
        12.5f64..20.0,
        any::<bool>(),
        0.1f64..1.5,
        300usize..1500,
        0usize..5,
    )
        .prop_map(|(mut pieces, amp, neg, period, len, at)| {
            let a = if neg { -amp } else { amp };
            let at = at.min(pieces.len());
            pieces.insert(at, (Piece::Square(a, period), len));
            Program { pieces }
        })
}

/// One random friction bump on a random axis: centre over (and a little beyond) the axis'
/// range, half-width 1..20 cm, amplitude -1.5..2.5 times the axis' `c0` (dips can clamp the
/// friction to 0), any direction.
fn bump_strategy(p: Params) -> impl Strategy<Value = Bump> {
    (0u8..3, -0.2f64..1.2, 0.01f64..0.2, -1.5f64..2.5, 0u8..3).prop_map(
        move |(ax, frac, width, amp, dir)| {
            let (axis, a) = match ax {
                0 => (Axis::X, &p.x),
                1 => (Axis::Y, &p.y),
                _ => (Axis::Rope, &p.rope),
            };
            Bump {
                axis,
                center: a.min + (a.max - a.min) * frac,
                width,
                amplitude: amp * a.dry_pos[0],
                direction: match dir {
                    0 => Direction::Positive,
                    1 => Direction::Negative,
                    _ => Direction::Both,
                },
            }
        },
    )
}

/// Random extensions: 1-4 bumps; per axis stiction (off, ratio exactly 1, or ratio 1..2.5
/// with a Stribeck velocity of 2..50 mm/s), a bias force (+-3 N), a dead band (up to 1.5 V)
/// and an input delay (up to 40 ms), each on about half the time.
fn extensions_strategy(p: Params) -> impl Strategy<Value = Extensions> {
    let stiction = (0u8..4, 1.0f64..2.5, 0.002f64..0.05).prop_map(|(k, ratio, velocity)| match k {
        0 | 1 => None,
        2 => Some(Stiction {
            ratio: if ratio < 1.3 { 1.0 } else { ratio },
            velocity,
        }),
        _ => Some(Stiction { ratio, velocity }),
    });
    let maybe =
        |lo: f64, hi: f64| (any::<bool>(), lo..hi).prop_map(|(on, v)| if on { v } else { 0.0 });
    (
        prop::collection::vec(bump_strategy(p), 1..=4),
        prop::array::uniform3(stiction),
        prop::array::uniform3(maybe(-3.0, 3.0)),
        prop::array::uniform3(maybe(0.0, 1.5)),
        prop::array::uniform3(maybe(0.0, 0.04)),
    )
        .prop_map(|(bumps, stiction, force_offset, deadzone, delay)| {
            let mut e = Extensions {
                stiction,
                force_offset,
                deadzone,
                delay,
                ..Extensions::default()
            };
            for b in bumps {
                e.bumps.push(b).expect("at most 4 bumps");
            }
            e
        })
}

#[derive(Clone, Debug)]
struct Case {
    params: Params,
    q: [f64; 5],
    qd: [f64; 5],
    h: f64,
    programs: [Program; 3],
    /// `None`: the paper's model (no `with_extensions` call at all).
    ext: Option<Extensions>,
    /// `Some(n)`: `with_segment_budget(n)` on both (1..=8); `None`: the default, no call.
    budget: Option<usize>,
}

fn case_strategy() -> impl Strategy<Value = Case> {
    params_strategy().prop_flat_map(|p| {
        (
            Just(p),
            init_strategy(p),
            prop_oneof![Just(1e-3), Just(2e-3)],
            prop::array::uniform3(program_strategy()),
            prop_oneof![Just(None), extensions_strategy(p).prop_map(Some)],
            prop_oneof![2 => Just(None), 1 => (1usize..=8).prop_map(Some)],
        )
            .prop_map(|(params, (q, qd), h, programs, ext, budget)| Case {
                params,
                q,
                qd,
                h,
                programs,
                ext,
                budget,
            })
    })
}

fn same_error(m: &StepError, r: &RefError) -> bool {
    matches!(
        (m, r),
        (StepError::InputNotFinite { .. }, RefError::NonFiniteInput)
            | (StepError::Singular, RefError::Singular)
            | (StepError::NonFinite, RefError::NonFiniteState)
            | (StepError::OutOfDomain, RefError::OutOfDomain)
    ) || matches!((m, r), (StepError::OutOfLimits { axis }, RefError::OutOfLimits(i)) if axis == i)
}

/// What one case exercised.
#[derive(Clone, Copy, Debug, Default)]
struct Stats {
    cases: usize,
    with_extensions: usize,
    steps: usize,
    /// Mode changes between consecutive steps.
    transitions: usize,
    /// Rejected steps, by error: Singular, NonFinite, OutOfDomain.
    rejected: [usize; 3],
    cases_with_rejections: usize,
    /// Cases whose last step was rejected (stuck at the domain boundary).
    cases_stuck_at_end: usize,
    /// Located events (reference's report): velocity, limit, breakaway.
    events: [usize; 3],
    /// Cases with at least one located limit event (end-stop impulse).
    cases_with_end_stop: usize,
    late_resets: usize,
    /// Cases with a segment budget below the default, and their late resets.
    budgeted: usize,
    budgeted_late_resets: usize,
    fewest_transitions: Option<usize>,
}

impl Stats {
    fn add(&mut self, o: &Stats) {
        self.cases += o.cases;
        self.with_extensions += o.with_extensions;
        self.steps += o.steps;
        self.transitions += o.transitions;
        for k in 0..3 {
            self.rejected[k] += o.rejected[k];
            self.events[k] += o.events[k];
        }
        self.cases_with_rejections += o.cases_with_rejections;
        self.cases_stuck_at_end += o.cases_stuck_at_end;
        self.cases_with_end_stop += o.cases_with_end_stop;
        self.late_resets += o.late_resets;
        self.budgeted += o.budgeted;
        self.budgeted_late_resets += o.budgeted_late_resets;
        self.fewest_transitions = match (self.fewest_transitions, o.fewest_transitions) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        };
    }
}

/// Runs one case with the given law, comparing after every step; returns what it exercised.
fn run_case(case: &Case, law: FrictionLaw, steps: usize) -> Result<Stats, TestCaseError> {
    let (mut m, mut r) = match &case.ext {
        Some(e) => pair_ext(&case.params, case.h, law, case.q, case.qd, e),
        None => pair(&case.params, case.h, law, case.q, case.qd),
    };
    if let Some(n) = case.budget {
        m = m.with_segment_budget(n).expect("budget 1..=8 is valid");
        r = r.with_segment_budget(n).expect("budget 1..=8 is valid");
    }
    let budget = case.budget.unwrap_or(crane_model::MAX_SEGMENTS);
    if let Some(msg) = compare(0, &m, &r) {
        return Err(TestCaseError::fail(format!("after new(): {msg}")));
    }
    let mut st = Stats {
        cases: 1,
        with_extensions: usize::from(case.ext.is_some()),
        budgeted: usize::from(budget < crane_model::MAX_SEGMENTS),
        steps,
        ..Stats::default()
    };
    let mut prev = m.modes();
    let mut last_rejected = false;
    for k in 0..steps {
        let u = [
            case.programs[0].at(k, case.h),
            case.programs[1].at(k, case.h),
            case.programs[2].at(k, case.h),
        ];
        match (m.step(u), r.step(u)) {
            (Ok(rep), Ok(info)) => {
                prop_assert_eq!(
                    rep.events as usize,
                    info.events.len(),
                    "step {}: located events model {:?} vs reference {:?}",
                    k + 1,
                    rep,
                    info
                );
                prop_assert_eq!(
                    rep.late_resets as usize,
                    info.late_resets,
                    "step {}: late resets",
                    k + 1
                );
                // The budget bounds the work: at most budget - 1 located events.
                prop_assert!(
                    (rep.events as usize) < budget,
                    "step {}: {} events located with budget {budget}",
                    k + 1,
                    rep.events
                );
                for ev in &info.events {
                    st.events[match ev.kind {
                        RefEventKind::Velocity => 0,
                        RefEventKind::Limit => 1,
                        RefEventKind::Breakaway => 2,
                    }] += 1;
                }
                st.late_resets += info.late_resets;
                last_rejected = false;
            }
            (Err(a), Err(b)) => {
                prop_assert!(same_error(&a, &b), "step {}: errors {a:?} vs {b:?}", k + 1);
                match a {
                    StepError::Singular => st.rejected[0] += 1,
                    StepError::NonFinite => st.rejected[1] += 1,
                    // outside the swing domain or the limits
                    StepError::OutOfDomain | StepError::OutOfLimits { .. } => st.rejected[2] += 1,
                    StepError::InputNotFinite { .. } => {}
                }
                last_rejected = true;
            }
            (a, b) => {
                return Err(TestCaseError::fail(format!(
                    "step {}: model {a:?} vs reference {b:?}",
                    k + 1
                )))
            }
        }
        if let Some(msg) = compare(k + 1, &m, &r) {
            return Err(TestCaseError::fail(msg));
        }
        if k % 37 == 0 {
            if let Some(msg) = compare_output(k + 1, &m, &r) {
                return Err(TestCaseError::fail(msg));
            }
        }
        let now = m.modes();
        st.transitions += now.iter().zip(prev.iter()).filter(|(a, b)| a != b).count();
        prev = now;
    }
    if budget < crane_model::MAX_SEGMENTS {
        st.budgeted_late_resets = st.late_resets;
    }
    st.cases_with_rejections = usize::from(st.rejected.iter().sum::<usize>() > 0);
    st.cases_with_end_stop = usize::from(st.events[1] > 0);
    st.cases_stuck_at_end = usize::from(last_rejected);
    st.fewest_transitions = Some(st.transitions);
    Ok(st)
}

/// Runs `cases` random cases of `case_strategy()` through `check` with failure persistence
/// in `bit_exact.proptest-regressions`; returns the summed statistics of the passing run.
fn run_property(
    cases: u32,
    check: impl Fn(&Case) -> Result<Stats, TestCaseError>,
) -> Result<Stats, String> {
    let config = RunnerConfig {
        cases,
        source_file: Some(file!()),
        ..RunnerConfig::default()
    };
    let total = RefCell::new(Stats::default());
    let mut runner = TestRunner::new(config);
    runner
        .run(&case_strategy(), |case| {
            let st = check(&case)?;
            total.borrow_mut().add(&st);
            Ok(())
        })
        .map_err(|e| e.to_string())?;
    Ok(total.into_inner())
}

/// Hybrid law: bit-exact agreement at every step (accepted and rejected), and in every case
/// the automaton really switched modes. Half the cases run with random extensions, and a
/// third with a random segment budget (`with_segment_budget(1..=8)`).
#[test]
fn hybrid_model_matches_reference_bit_for_bit() {
    let stats = run_property(HYBRID_CASES, |case| {
        let st = run_case(case, FrictionLaw::Hybrid, STEPS)?;
        prop_assert!(st.transitions > 0, "no mode transition in {} steps", STEPS);
        Ok(st)
    })
    .unwrap_or_else(|e| panic!("{e}"));
    eprintln!("hybrid bit-exact: {stats:?}");
    // The run covered what it is meant to cover (the last run may include replayed
    // regression seeds, hence ">=").
    assert!(stats.cases >= HYBRID_CASES as usize);
    let share = stats.with_extensions as f64 / stats.cases as f64;
    assert!(
        (0.3..=0.7).contains(&share),
        "share of cases with extensions {share}"
    );
    assert!(stats.events.iter().all(|&n| n > 0), "{stats:?}");
    let budgeted = stats.budgeted as f64 / stats.cases as f64;
    assert!(
        (0.15..=0.4).contains(&budgeted),
        "budgeted share {budgeted}"
    );
    // The budget really cut steps short: their events were reset late.
    assert!(stats.budgeted_late_resets > 0, "{stats:?}");
    assert!(
        stats.cases_with_end_stop * 4 >= stats.cases,
        "end-stop impulses in too few cases: {stats:?}"
    );
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// tanh comparison law: bit-exact agreement at every step (half the cases with
    /// extensions; the tanh law uses the bumps, not the stiction).
    #[test]
    fn tanh_model_matches_reference_bit_for_bit(
        case in case_strategy(),
        gamma in prop_oneof![Just(1.0), Just(10.0), Just(100.0), 1.0f64..1000.0],
    ) {
        run_case(&case, FrictionLaw::Tanh { gamma }, 2000)?;
    }
}

/// The reference's constants are the model's.
#[test]
fn reference_constants_are_the_models() {
    assert_eq!(reference::MIN_HANG.to_bits(), MIN_HANG.to_bits());
    assert_eq!(reference::MAX_BUMPS, crane_model::MAX_BUMPS);
    assert_eq!(reference::MAX_DELAY_STEPS, crane_model::MAX_DELAY_STEPS - 1);
    assert_eq!(reference::MAX_SEGMENTS, crane_model::MAX_SEGMENTS);
}

/// A hand-made case on the defaults: the paper's case-1 release (alpha = pi/2 + 0.6) with
/// the axes stopped and zero input, then saturating pushes into every limit.
#[test]
fn defaults_release_then_push_into_limits() {
    let p = Params::default();
    let q = [0.25, 0.3, 0.4, FRAC_PI_2 + 0.6, 0.0];
    let (mut m, mut r) = pair(&p, 1e-3, FrictionLaw::Hybrid, q, [0.0; 5]);
    let mut transitions = 0;
    let mut end_stops = 0;
    for k in 0..20_000usize {
        let u = match k / 4000 {
            0 => [0.0, 0.0, 0.0],
            1 => [20.0, 20.0, 20.0],
            2 => [-20.0, -20.0, -20.0],
            3 => [5.0, -3.0, 1.0],
            _ => [0.0, 0.0, 0.0],
        };
        let before = m.modes();
        let a = m.step(u).expect("model step");
        let b = r.step(u).expect("reference step");
        assert_eq!(a.events as usize, b.events.len(), "step {}", k + 1);
        end_stops += b
            .events
            .iter()
            .filter(|e| e.kind == RefEventKind::Limit)
            .count();
        if let Some(msg) = compare(k + 1, &m, &r) {
            panic!("{msg}");
        }
        if let Some(msg) = compare_output(k + 1, &m, &r) {
            panic!("{msg}");
        }
        transitions += before
            .iter()
            .zip(m.modes().iter())
            .filter(|(a, b)| a != b)
            .count();
    }
    assert!(transitions > 0);
    assert!(end_stops >= 4, "{end_stops} end stops");
}

/// `with_extensions(&Extensions::default())` changes no bit: same states, modes, reports and
/// outputs as the model without the call (and as the reference), over random saturating
/// inputs that hit the end stops.
#[test]
fn default_extensions_give_the_same_bits_as_none() {
    let p = Params {
        payload_mass: 0.3,
        ..Params::default()
    };
    let q = [0.25, 0.3, 0.35, FRAC_PI_2 + 0.2, -0.1];
    let qd = [0.1, -0.2, 0.0, 0.3, -0.3];
    for h in [1e-3, 2e-3] {
        let (mut plain, mut r) = pair(&p, h, FrictionLaw::Hybrid, q, qd);
        let (mut ext, mut r_ext) =
            pair_ext(&p, h, FrictionLaw::Hybrid, q, qd, &Extensions::default());
        let mut rng = common::Rng::new(11);
        let progs = [
            common::random_program(&mut rng, 20.0),
            common::random_program(&mut rng, 20.0),
            common::random_program(&mut rng, 20.0),
        ];
        for k in 0..10_000 {
            let u = [progs[0].at(k, h), progs[1].at(k, h), progs[2].at(k, h)];
            let a = plain.step(u);
            let b = ext.step(u);
            assert_eq!(a, b, "step {}", k + 1);
            assert_eq!(r.step(u).is_ok(), a.is_ok());
            assert_eq!(r_ext.step(u).is_ok(), a.is_ok());
            let (s, t) = (plain.state(), ext.state());
            assert_eq!(
                s.q.map(f64::to_bits),
                t.q.map(f64::to_bits),
                "step {}",
                k + 1
            );
            assert_eq!(
                s.qd.map(f64::to_bits),
                t.qd.map(f64::to_bits),
                "step {}",
                k + 1
            );
            assert_eq!(plain.modes(), ext.modes());
            assert_eq!(plain.output(), ext.output());
            for (name, msg) in [
                ("model", compare(k + 1, &plain, &r)),
                ("extended model", compare(k + 1, &ext, &r_ext)),
            ] {
                if let Some(msg) = msg {
                    panic!("{name} vs reference: {msg}");
                }
            }
        }
    }
}

/// Model and reference refuse the same extensions (and accept the edge values).
#[test]
fn invalid_extensions_are_rejected_by_both() {
    let p = Params::default();
    let q = [0.2, 0.3, 0.4, FRAC_PI_2, 0.0];
    let bump = Bump {
        axis: Axis::Y,
        center: 0.3,
        width: 0.05,
        amplitude: 1.0,
        direction: Direction::Both,
    };
    type Edit = fn(&mut Extensions);
    let cases: Vec<(bool, Edit)> = vec![
        (true, |_| {}),
        (true, |e| e.delay[0] = 0.063), // 63 steps at h = 1 ms
        (false, |e| e.delay[1] = 0.064),
        (false, |e| e.delay[2] = -1e-3),
        (false, |e| e.delay[2] = f64::NAN),
        (true, |e| e.deadzone[0] = 0.0),
        (false, |e| e.deadzone[0] = -0.1),
        (false, |e| e.force_offset[1] = f64::INFINITY),
        (true, |e| {
            e.stiction[2] = Some(Stiction {
                ratio: 1.0,
                velocity: 0.01,
            })
        }),
        (false, |e| {
            e.stiction[2] = Some(Stiction {
                ratio: 0.9,
                velocity: 0.01,
            })
        }),
        (false, |e| {
            e.stiction[0] = Some(Stiction {
                ratio: 1.5,
                velocity: 0.0,
            })
        }),
        (false, |e| e.bumps[0].width = 0.0),
        (false, |e| e.bumps[0].center = f64::NAN),
        (false, |e| e.bumps[0].amplitude = f64::NEG_INFINITY),
    ];
    for (n, (ok, edit)) in cases.into_iter().enumerate() {
        let mut e = Extensions::default();
        e.bumps.push(bump).expect("capacity");
        edit(&mut e);
        let m = common::model(&p, 1e-3, FrictionLaw::Hybrid, q, [0.0; 5]).with_extensions(&e);
        let r = host_tests::reference::RefCrane::new(
            p.into(),
            1e-3,
            host_tests::reference::RefLaw::Hybrid,
            q,
            [0.0; 5],
        )
        .expect("reference new")
        .with_extensions(&RefExtensions::from(&e));
        assert_eq!(m.is_ok(), ok, "case {n}: model {:?}", m.err());
        assert_eq!(r.is_ok(), ok, "case {n}: reference {:?}", r.err());
    }
}

/// One step from `q`, `qd` with input `u` on the defaults: model and reference must agree on
/// the outcome (accepted or the same error) and on every bit of the state.
fn one_step_agrees(q: [f64; 5], qd: [f64; 5], u: [f64; 3]) -> Result<(), StepError> {
    let (mut m, mut r) = pair(&Params::default(), 1e-3, FrictionLaw::Hybrid, q, qd);
    let a = m.step(u);
    let b = r.step(u);
    match (&a, &b) {
        (Ok(_), Ok(_)) => {}
        (Err(x), Err(y)) => assert!(same_error(x, y), "model {x:?} vs reference {y:?}"),
        _ => panic!("model {a:?} vs reference {b:?}"),
    }
    if let Some(msg) = compare(1, &m, &r) {
        panic!("{msg}\nmodel {a:?}\nreference {b:?}");
    }
    a.map(|_| ())
}

/// NUMERICS.md "resets": the velocity reset clamps `q_i` into `[min_i, max_i]`
/// (CONTRACT_NOTES.md D1). The trolley, coasting towards its upper end stop with zero input,
/// stops exactly at it: at step 61 the velocity event wins (its theta is the smaller one) and
/// the relocated RK4 state has `y` one ulp beyond `max = 0.625`; without the clamp it would
/// stay at `0.6250000000000001` (this happens for about half of the initial speeds within a few
/// thousand ulps of this one, and likewise at the lower stops, e.g. `y = -4.4e-19`).
#[test]
fn velocity_reset_clamps_an_axis_that_stops_at_its_limit() {
    let p = Params::default();
    let q = [0.25, 0.625 - 0.001, 0.4, FRAC_PI_2, 0.0];
    let qd = [0.0, 0.044777299191550005, 0.0, 0.0, 0.0];
    let (mut m, mut r) = pair(&p, 1e-3, FrictionLaw::Hybrid, q, qd);
    for k in 0..100 {
        m.step([0.0; 3]).expect("model step");
        let info = r.step([0.0; 3]).expect("reference step");
        if let Some(msg) = compare(k + 1, &m, &r) {
            panic!("{msg}");
        }
        if k + 1 == 61 {
            assert_eq!(
                info.events
                    .iter()
                    .map(|e| (e.axis, e.kind))
                    .collect::<Vec<_>>(),
                [(1, RefEventKind::Velocity)],
                "the scenario needs the velocity event at step 61"
            );
        }
    }
    assert_eq!(m.state().q[1].to_bits(), p.y.max.to_bits());
    assert_eq!(m.modes()[1], crane_model::Mode::Stopped);
}

/// NUMERICS.md bisection: "still moving at mid" is "the event predicate is false at mid", so
/// a NaN Hermite value counts as still moving (CONTRACT_NOTES.md D2). In this step from an
/// in-domain state with an absurd hoisting speed (-502 m/s) the segment end overflows and the
/// velocity Hermite is NaN inside the segment: both reject with `NonFinite` and keep the
/// state (with the earlier wording, `!(v < 0)` for NaN, the event would be located at
/// theta = 2^-30 and the step would fail with `Singular` instead).
#[test]
fn bisection_counts_a_nan_hermite_value_as_still_moving() {
    let q = [
        0.20056201934280551,
        0.07012541967020419,
        0.21398696831146902,
        2.477948113863594,
        1.0603993893667094,
    ];
    let qd = [0.0, 0.0, -502.5074496463958, 0.0, -190.67539107740603];
    let u = [3.9333276909603683, -17.22752747041156, -9.450385230942086];
    assert_eq!(one_step_agrees(q, qd, u), Err(StepError::NonFinite));
}

/// NUMERICS.md "Extensions": "A rejected step does not push into the delay line" (nor does a
/// non-finite input). The payload starts swinging out towards the domain boundary
/// (`alpha = 0.9`, `alphad = -w`) with a 3 ms delay on a varying X input; `w` is tuned by
/// bisection (on the model) so that the swing just reaches `sin(alpha) cos(beta) = MIN_HANG`:
/// one step is rejected (`OutOfDomain`), and the next one, with a trolley push of 12 V on Y
/// (no delay), is accepted again. From then on the X input in effect is the one pushed three
/// accepted steps earlier; model and reference must agree at every step.
#[test]
fn a_rejected_step_does_not_push_into_the_delay_line() {
    // With a delay on X, a run with rejected (non-finite) inputs interleaved must give the
    // same bits as the run without them: a rejected step leaves the delay line untouched.
    let p = Params::default();
    let q = [0.25, 0.3, 0.4, 1.4, 0.0];
    let mut ext = Extensions::default();
    ext.delay[0] = 0.003;
    let x_input = |k: usize| 6.0 * (k as f64 * 0.37).sin() + 3.0 * ((k * k) as f64 * 0.011).cos();
    let (mut m, mut r) = pair_ext(&p, 1e-3, FrictionLaw::Hybrid, q, [0.0; 5], &ext);
    let (mut clean, _) = pair_ext(&p, 1e-3, FrictionLaw::Hybrid, q, [0.0; 5], &ext);
    let mut rejected = 0;
    for k in 0..800 {
        if k % 7 == 3 {
            for u in [[f64::NAN, 0.0, 0.0], [0.0, f64::INFINITY, 0.0]] {
                let (a, b) = (m.step(u), r.step(u));
                assert!(
                    a.is_err() && b.is_err(),
                    "step {k}: non-finite input accepted"
                );
                rejected += 1;
            }
        }
        let u = [x_input(k), 0.0, 0.0];
        assert!(m.step(u).is_ok() && r.step(u).is_ok() && clean.step(u).is_ok());
        let (sm, sc) = (m.state(), clean.state());
        for j in 0..5 {
            assert_eq!(sm.q[j].to_bits(), sc.q[j].to_bits(), "step {k}: q[{j}]");
            assert_eq!(sm.qd[j].to_bits(), sc.qd[j].to_bits(), "step {k}: qd[{j}]");
            assert_eq!(
                sm.q[j].to_bits(),
                r.q()[j].to_bits(),
                "step {k}: ref q[{j}]"
            );
            assert_eq!(
                sm.qd[j].to_bits(),
                r.qd()[j].to_bits(),
                "step {k}: ref qd[{j}]"
            );
        }
    }
    assert!(rejected > 200);
}

/// The segment budget is validated on both sides (a clear field name in the model's error),
/// and budget 1 locates no event: a velocity zero inside the step is reset at its end.
#[test]
fn segment_budget_is_validated_and_bounds_location() {
    let p = Params::default();
    let q = [0.25, 0.3, 0.4, FRAC_PI_2, 0.0];
    let (m, r) = pair(&p, 2e-3, FrictionLaw::Hybrid, q, [0.0; 5]);
    for bad in [0, crane_model::MAX_SEGMENTS + 1] {
        let e = m.clone().with_segment_budget(bad).expect_err("rejected");
        assert_eq!(e.field, "config.segment_budget");
        assert_eq!(e.value, bad as f64);
        assert!(e.to_string().contains("config.segment_budget"), "{e}");
        assert!(r.clone().with_segment_budget(bad).is_err());
    }
    assert_eq!(m.segment_budget(), crane_model::MAX_SEGMENTS);
    // X moving at 5 cm/s against a reversed full input stops within a few steps.
    let qd = [0.05, 0.0, 0.0, 0.0, 0.0];
    let (m8, r8) = pair(&p, 2e-3, FrictionLaw::Hybrid, q, qd);
    let (mut m1, mut r1) = (
        m8.clone().with_segment_budget(1).expect("valid"),
        r8.with_segment_budget(1).expect("valid"),
    );
    let mut m8 = m8;
    let (mut late, mut located8) = (0, 0);
    for k in 0..50 {
        let u = [-12.0, 0.0, 0.0];
        let a = m1.step(u).expect("step");
        let b = r1.step(u).expect("step");
        assert_eq!(a.events, 0, "budget 1 locates nothing");
        assert!(b.events.is_empty());
        assert_eq!(a.late_resets as usize, b.late_resets);
        late += a.late_resets;
        located8 += m8.step(u).expect("step").events;
        if let Some(msg) = compare(k + 1, &m1, &r1) {
            panic!("{msg}");
        }
    }
    assert!(late > 0, "the stop was applied at a step end");
    assert!(located8 > 0, "the default budget located it");
}

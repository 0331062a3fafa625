//! Qualitative facts of the paper's simulation study, each of which could fail.

use crane_model::dynamics::{eval, Coeffs, Law};
use crane_model::{Config, Crane, FrictionLaw, Mode, Params, State};
use crane_tools::cases::Case;
use crane_tools::smooth::{pack, rk4_step, unpack, Friction, Smooth};
use crane_tools::study::{tanh_rk4, GAMMAS};
use crane_tools::tanh_run::tanh_ode45;
use crane_tools::{montecarlo, reference};

const H: f64 = 1e-3;

/// Case 1: the hybrid trolley slides, then reaches exactly zero velocity and stays `Stopped`,
/// bit for bit, to the end; X and the rope never move.
#[test]
fn case1_hybrid_trolley_stops_exactly_and_stays_stopped() {
    let case = Case::one();
    let tr = reference::hybrid(&case, H, false).unwrap();
    assert_eq!(tr.states.len(), case.samples() + 1, "one sample per step");
    let vmax = tr.states.iter().map(|s| s.qd[1].abs()).fold(0.0, f64::max);
    assert!(
        vmax > 0.1,
        "the trolley must slide first (max |v| = {vmax})"
    );
    let last_moving = tr
        .modes
        .iter()
        .rposition(|m| m[1] != Mode::Stopped)
        .expect("the trolley moves");
    let t_rest = tr.time(&case, last_moving + 1);
    assert!(
        t_rest < 0.9 * case.duration,
        "at rest for good only at {t_rest} s"
    );
    let rest = tr.states[last_moving + 1];
    for (s, m) in tr.states[last_moving + 1..]
        .iter()
        .zip(&tr.modes[last_moving + 1..])
    {
        assert_eq!(m[1], Mode::Stopped);
        assert_eq!(s.qd[1].to_bits(), 0.0f64.to_bits(), "exactly zero velocity");
        assert_eq!(s.q[1].to_bits(), rest.q[1].to_bits(), "position frozen");
    }
    // Every stopped sample has exactly zero velocity; X and the rope are held throughout.
    for (s, m) in tr.states.iter().zip(&tr.modes) {
        if m[1] == Mode::Stopped {
            assert_eq!(s.qd[1], 0.0);
        }
        assert_eq!([m[0], m[2]], [Mode::Stopped, Mode::Stopped]);
        assert_eq!(s.q[2], case.init.q[2], "rope length fixed");
        assert_eq!(s.q[0], case.init.q[0], "X fixed");
    }
    // The payload still swings after the trolley stopped.
    assert!(rest.qd[3].abs() > 0.0 || tr.states.last().unwrap().qd[3].abs() > 0.01);
}

/// Case 1: with tanh(1000 v) the trolley never comes to rest: |v| > 0 at every step, by
/// fixed-step RK4 (1 ms) and by ode45 (every 1 ms sample).
#[test]
fn case1_tanh_trolley_never_stops() {
    let case = Case::one();
    let rk = tanh_rk4(&case, 1000.0, H).unwrap();
    let (ode, _) = tanh_ode45(&case, 1000.0, &Default::default()).unwrap();
    for tr in [&rk, &ode] {
        assert_eq!(tr.states.len(), case.samples() + 1);
        for (j, s) in tr.states.iter().enumerate().skip(1) {
            assert!(s.qd[1] != 0.0, "tanh trolley at rest at sample {j}");
        }
        // And it is still creeping at the end, where the hybrid trolley is at rest.
        assert!(tr.states.last().unwrap().qd[1].abs() > 1e-9);
    }
}

/// Case 2: the rope breaks away only when the net force `N = F_l + m_p g` exceeds `Cbar_l`
/// in the direction of motion, and it is at rest only while `|N| <= Cbar_l` (both within one
/// step: the hybrid model holds its input over a step). While stopped, `Ld = 0` exactly and
/// `L` is frozen; while moving, `Ld` has the mode's sign. X and Y stay held, the rope never
/// reaches a limit.
#[test]
fn case2_rope_moves_only_beyond_the_threshold() {
    let case = Case::two();
    let c = case.rope_threshold();
    let tr = reference::hybrid(&case, H, false).unwrap();
    let n_force = |a: f64, b: f64| -> Vec<f64> {
        (0..=100)
            .map(|k| case.rope_net_force(a + (b - a) * k as f64 / 100.0))
            .collect()
    };
    let (mut starts_pos, mut starts_neg, mut stopped) = (0, 0, 0);
    for j in 0..tr.states.len() {
        let (s, m) = (tr.states[j], tr.modes[j]);
        let t = tr.time(&case, j);
        assert_eq!([m[0], m[1]], [Mode::Stopped, Mode::Stopped], "X, Y held");
        assert!(s.q[2] > case.params.rope.min + 0.01 && s.q[2] < case.params.rope.max - 0.01);
        match m[2] {
            Mode::Stopped => {
                stopped += 1;
                assert_eq!(s.qd[2].to_bits(), 0.0f64.to_bits());
                if j > 0 && tr.modes[j - 1][2] == Mode::Stopped {
                    assert_eq!(s.q[2].to_bits(), tr.states[j - 1].q[2].to_bits());
                }
                let near = n_force(t - H, t + H);
                assert!(
                    near.iter().any(|f| f.abs() <= c),
                    "stopped at t = {t} s although |N| > Cbar_l all around"
                );
            }
            Mode::Positive => assert!(s.qd[2] > 0.0),
            Mode::Negative => assert!(s.qd[2] < 0.0),
        }
        if j > 0 && tr.modes[j - 1][2] == Mode::Stopped && m[2] != Mode::Stopped {
            let window = n_force(t - 2.0 * H, t);
            if m[2] == Mode::Positive {
                starts_pos += 1;
                assert!(window.iter().any(|&f| f > c), "released up at t = {t} s");
            } else {
                starts_neg += 1;
                assert!(window.iter().any(|&f| f < -c), "released down at t = {t} s");
            }
        }
    }
    assert!(
        starts_pos >= 4 && starts_neg >= 4,
        "{starts_pos} {starts_neg}"
    );
    assert!(
        stopped > tr.states.len() / 5,
        "rest phases exist: {stopped}"
    );
}

/// The reference has converged far below the hybrid model's own error; the hybrid model at
/// 1 ms is more accurate than every tanh model (ode45), by at least two orders of magnitude;
/// and the tanh error falls as gamma grows.
#[test]
fn hybrid_is_more_accurate_than_every_tanh_model() {
    for case in Case::all() {
        let refr = reference::reference(&case, H, 100).unwrap();
        let conv = reference::convergence(&case, &refr).unwrap();
        let hyb = reference::hybrid(&case, H, false).unwrap();
        let e_h = reference::rmse(&case, &hyb, &refr);
        assert!(e_h > 0.0 && e_h < 1e-5, "{:?}: hybrid RMSE {e_h}", case.id);
        assert!(
            conv.rmse < 0.1 * e_h,
            "{:?}: reference moves by {} against hybrid error {e_h}",
            case.id,
            conv.rmse
        );
        let mut prev = f64::INFINITY;
        for g in GAMMAS {
            let (tr, _) = tanh_ode45(&case, g, &Default::default()).unwrap();
            let e = reference::rmse(&case, &tr, &refr);
            assert!(
                e > 100.0 * e_h,
                "{:?}: tanh({g} v) RMSE {e} vs hybrid {e_h}",
                case.id
            );
            assert!(
                e < prev,
                "{:?}: tanh({g} v) RMSE {e} not below {prev}",
                case.id
            );
            prev = e;
        }
    }
}

fn sample_states() -> Vec<State<f64>> {
    let mut v = Vec::new();
    for k in 0..20 {
        let s = k as f64;
        v.push(State {
            q: [
                0.05 + 0.02 * s,
                0.6 - 0.025 * s,
                0.15 + 0.02 * s,
                1.2 + 0.04 * s,
                -0.3 + 0.03 * s,
            ],
            qd: [
                0.3 * (s - 10.0) / 10.0,
                -0.2 + 0.02 * s,
                (s - 7.0) * 0.01,
                0.5 - 0.05 * s,
                0.2 * (s - 5.0) / 5.0,
            ],
        });
    }
    v
}

/// The comparison dynamics (tanh friction through the input channel, nothing held) is the
/// model's own tanh law, to rounding.
#[test]
fn smooth_dynamics_equals_the_models_tanh_law() {
    let p = Params::default();
    let c = Coeffs::<f64>::new(&p);
    let sys = Smooth::new(&p, Friction::Tanh(300.0), [false; 3]);
    let u = [1.5, -2.0, 0.7];
    for s in sample_states() {
        let e = eval(&c, Law::Tanh(300.0), &s, &[Mode::Stopped; 3], &u).unwrap();
        let d = sys.rhs(&pack(&s), &u).unwrap();
        for j in 0..5 {
            assert!((d[5 + j] - e.qdd[j]).abs() <= 1e-9 * (1.0 + e.qdd[j].abs()));
            assert_eq!(d[j], s.qd[j]);
        }
    }
    // One RK4 step against the model's own tanh simulator.
    let s0 = sample_states()[3];
    let mut crane: Crane = Crane::new(
        &p,
        Config {
            h: 1e-3,
            law: FrictionLaw::Tanh { gamma: 300.0 },
        },
        s0,
    )
    .unwrap();
    crane.step(u).unwrap();
    let y = unpack(&rk4_step(&sys, 0.0, &pack(&s0), 1e-3, |_| u).unwrap());
    for j in 0..5 {
        assert!((y.q[j] - crane.state().q[j]).abs() < 1e-12);
        assert!((y.qd[j] - crane.state().qd[j]).abs() < 1e-9);
    }
}

/// Held axes of the comparison dynamics do not move, and the bare dynamics has no friction:
/// with zero input and a hanging payload at rest nothing accelerates.
#[test]
fn held_axes_and_bare_dynamics() {
    let case = Case::one();
    let sys = Smooth::new(&case.params, Friction::Tanh(1000.0), case.held);
    let mut y = pack(&case.init);
    for k in 0..2000 {
        y = rk4_step(&sys, k as f64 * 1e-3, &y, 1e-3, |_| [0.0; 3]).unwrap();
    }
    assert_eq!(y[2], case.init.q[2]);
    assert_eq!(y[7], 0.0);
    let bare = Smooth::bare(&Params::default());
    let mut hanging = pack(&case.init);
    hanging[3] = core::f64::consts::FRAC_PI_2;
    let d = bare.rhs(&hanging, &[0.0; 3]).unwrap();
    assert!(d[5..7].iter().all(|a| a.abs() < 1e-12), "{d:?}");
    // A drive force accelerates the bare X axis by exactly K u / M00 when nothing swings.
    let d = bare.rhs(&hanging, &[1.0, 0.0, 0.0]).unwrap();
    assert!(d[5] > 0.0);
}

/// Monte Carlo results do not depend on the number of threads.
#[test]
fn monte_carlo_is_deterministic_across_thread_counts() {
    let run = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| montecarlo::run(6, 2.0, 1e-3, 7).unwrap())
    };
    let (s1, o1) = run(1);
    let (s2, o2) = run(2);
    assert_eq!(s1.sims, 6);
    for (a, b) in o1.iter().zip(&o2) {
        assert_eq!(a.y_final.to_bits(), b.y_final.to_bits());
        assert_eq!(a.friction, b.friction);
    }
    assert_eq!(s1.y_final_mean.to_bits(), s2.y_final_mean.to_bits());
    assert!(s1.y_final_std > 0.0, "friction draws change the outcome");
}

/// A run with a step longer than the output grid is judged on every grid point: the
/// interpolant passes through its samples, covers the whole grid, and stays close to the
/// reference between samples.
#[test]
fn coarse_steps_are_judged_on_every_grid_point() {
    let case = Case::two();
    let refr = reference::reference(&case, H, 10).unwrap();
    let coarse = reference::hybrid(&case, 10e-3, false).unwrap();
    assert_eq!(coarse.stride, 10);
    assert_eq!(coarse.grid_len(), case.samples());
    assert_eq!(coarse.accel.len(), coarse.states.len());
    for (j, s) in coarse.states.iter().enumerate() {
        assert_eq!(coarse.velocity_at_grid(&case, 10 * j), Some(s.qd[2]));
    }
    let between: Vec<f64> = (1..coarse.grid_len())
        .filter(|g| g % 10 != 0)
        .map(|g| (coarse.velocity_at_grid(&case, g).unwrap() - refr.states[g].qd[2]).abs())
        .collect();
    assert_eq!(between.len(), case.samples() - case.samples() / 10);
    let e = reference::rmse(&case, &coarse, &refr);
    assert!(e > 0.0 && e < 5e-3, "RMSE {e}");
    assert!(between.iter().all(|d| *d < 0.05), "interpolant stays close");
}

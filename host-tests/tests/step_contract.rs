//! The step contract, for every valid parameter set: an accepted step is finite, inside the
//! drive limits and in the swing domain; a step that would break it is rejected with a typed
//! error and changes nothing, in the model and in the independent reference alike (same
//! decision, same bits).

mod common;

use common::pair;
use crane_model::{hangs, FrictionLaw, Params, StepError};
use host_tests::reference::RefError;
use proptest::prelude::*;

const HOME: [f64; 5] = [0.25, 0.3, 0.35, core::f64::consts::FRAC_PI_2, 0.0];

/// Voltages of step `k` [V]: three incommensurate sines at full scale.
fn input(k: usize, h: f64, w: [f64; 3]) -> [f64; 3] {
    let t = k as f64 * h;
    [
        12.0 * libm::sin(w[0] * t),
        12.0 * libm::sin(w[1] * t),
        4.0 * libm::sin(w[2] * t),
    ]
}

/// Steps model and reference together; checks the contract on every accepted state and that
/// both take the same decision with the same bits. Returns (accepted, out-of-limits
/// rejections).
fn run(p: &Params, h: f64, steps: usize, w: [f64; 3]) -> Result<(usize, usize), TestCaseError> {
    let (mut m, mut r) = pair(p, h, FrictionLaw::Hybrid, HOME, [0.0; 5]);
    let (mut accepted, mut limits) = (0, 0);
    for k in 0..steps {
        let u = input(k, h, w);
        let before = m.state();
        let modes = m.modes();
        match (m.step(u), r.step(u)) {
            (Ok(_), Ok(_)) => {
                let s = m.state();
                let rs = r.state();
                for j in 0..5 {
                    prop_assert_eq!(s.q[j].to_bits(), rs.q[j].to_bits(), "step {} q[{}]", k, j);
                    prop_assert_eq!(
                        s.qd[j].to_bits(),
                        rs.qd[j].to_bits(),
                        "step {} qd[{}]",
                        k,
                        j
                    );
                }
                prop_assert!(s.is_finite(), "step {}: accepted a non-finite state", k);
                for (i, ax) in p.axes().iter().enumerate() {
                    prop_assert!(
                        s.q[i] >= ax.min && s.q[i] <= ax.max,
                        "step {}: accepted drive {} at {} outside [{}, {}]",
                        k,
                        i,
                        s.q[i],
                        ax.min,
                        ax.max
                    );
                }
                prop_assert!(
                    hangs(s.q[3], s.q[4]),
                    "step {}: outside the swing domain",
                    k
                );
                accepted += 1;
            }
            (Err(a), Err(b)) => {
                prop_assert_eq!(
                    m.state(),
                    before,
                    "step {}: rejected step moved the state",
                    k
                );
                prop_assert_eq!(m.modes(), modes, "step {}", k);
                if let (StepError::OutOfLimits { axis }, RefError::OutOfLimits(i)) = (a, &b) {
                    prop_assert_eq!(axis, *i);
                    limits += 1;
                }
            }
            (a, b) => prop_assert!(false, "step {}: model {:?} vs reference {:?}", k, a, b),
        }
    }
    Ok((accepted, limits))
}

/// The repro: Y inertia 0, trolley 0.0167 kg, payload 0.66 g. Before the fix the
/// model accepted steps that put the trolley at y = 2.7 m (h = 1 ms) and 19.5 m (h = 2 ms) on
/// a 0.625 m rail; now those steps are rejected as `OutOfLimits` by model and reference.
#[test]
fn stiff_light_trolley_never_leaves_its_rail() {
    let mut p = Params::default();
    p.y.inertia = 0.0;
    p.trolley_mass = 0.0167;
    p.payload_mass = 0.00066;
    let mut limits = 0;
    for h in [1e-3, 2e-3] {
        let (_, l) = run(&p, h, 3000, [3.0, 5.0, 2.0]).expect("contract");
        limits += l;
    }
    assert!(limits > 0, "the repro no longer reaches the limit check");
}

/// A factor `10^e`, `e` uniform in [-3, 3].
fn factor() -> impl Strategy<Value = f64> {
    (-3.0f64..=3.0).prop_map(|e| libm::pow(10.0, e))
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    /// Random valid parameters within 10^+-3 of nominal (masses, inertias, gains, viscous and
    /// dry friction, swing damping), h up to 2 ms: accepted => finite, inside the limits, in
    /// the swing domain; model and reference agree.
    #[test]
    fn accepted_steps_are_finite_and_inside_limits(
        f in proptest::collection::vec(factor(), 16),
        h in prop_oneof![Just(5e-4), Just(1e-3), Just(2e-3)],
        w in proptest::array::uniform3(0.5f64..20.0),
    ) {
        let mut p = Params::default();
        p.payload_mass *= f[0];
        p.trolley_mass *= f[1];
        p.rail_mass *= f[2];
        p.damping_alpha *= f[3];
        p.damping_beta *= f[4];
        for (k, ax) in [&mut p.x, &mut p.y, &mut p.rope].into_iter().enumerate() {
            let g = &f[5 + 3 * k..8 + 3 * k];
            ax.inertia *= g[0];
            ax.gain *= g[1];
            ax.viscous_pos *= g[2];
            ax.viscous_neg *= g[2];
            for c in ax.dry_pos.iter_mut().chain(ax.dry_neg.iter_mut()) {
                *c *= f[14 + k % 2];
            }
        }
        prop_assume!(p.validate().is_ok());
        run(&p, h, 1000, w)?;
    }
}

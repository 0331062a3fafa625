//! The feedforward's holding force `F_0` (closed form from `dynamics::at_state`) is the model's
//! holding force with the three drive axes stopped, negated: compared with a full
//! `dynamics::eval` over swing states and velocities.

use crane_model::{dynamics, Config, Crane, Law, Mode, Params, State};
use crane_twin::logic::feedforward::{voltages, Reference};

#[test]
fn holding_force_matches_a_full_evaluation() {
    let p = Params::default();
    let init = State {
        q: [0.2, 0.3, 0.4, core::f64::consts::FRAC_PI_2, 0.0],
        qd: [0.0; 5],
    };
    let crane: Crane = Crane::new(&p, Config::default(), init).expect("valid");
    let c = crane.coeffs();
    let mut worst = 0.0f64;
    let mut checked = 0;
    for k in 0..400 {
        let t = f64::from(k);
        let mut y = init;
        y.q[2] = 0.25 + 0.2 * (0.37 * t).sin().abs();
        y.q[3] = core::f64::consts::FRAC_PI_2 + 0.6 * (0.11 * t).sin();
        y.q[4] = 0.5 * (0.23 * t).cos();
        y.qd = [
            0.0,
            0.0,
            0.2 * (0.5 * t).sin(),
            1.5 * (0.7 * t).cos(),
            -1.2 * (0.3 * t).sin(),
        ];
        // Zero reference velocity and acceleration, twin axes moving: only F_0 remains.
        let r = Reference {
            pos: [y.q[0], y.q[1], y.q[2]],
            vel: [0.0; 3],
            acc: [0.0; 3],
        };
        let moving = [Mode::Positive; 3];
        let u = voltages(c, &y, &moving, &r, &[0.0; 3], 0.05);
        let e = dynamics::eval(c, Law::Hybrid, &y, &[Mode::Stopped; 3], &[0.0; 3]).expect("eval");
        for (i, (&ui, ax)) in u.iter().zip(&c.axes).enumerate() {
            let want = -e.hold[i] / ax.gain;
            if want.abs() >= 12.0 {
                continue;
            }
            let err = (ui - want).abs();
            worst = worst.max(err / want.abs().max(1e-3));
            checked += 1;
            assert!(
                err <= 1e-12 * (1.0 + want.abs()),
                "state {k} axis {i}: feedforward {ui} V vs -hold/K {want} V"
            );
        }
    }
    assert!(checked > 1000, "{checked}");
    eprintln!("F_0 vs full evaluation: worst relative difference {worst:e}");
}

//! The two errors of the paper's printed equations listed in `docs/MODEL.md`, each shown
//! against the model.
//!
//! Paper: seeds/000_21f9cb0c01998783.txt, equations (x completa), (y completa), (L completa),
//! (dyn_alpha), (dyn_beta), the automaton figure "Hybrid model of the 3 axis dynamics" and
//! (Tension_cuerda_parada).

mod common;

use common::{energy, frictionless, model, FRAC_PI_2};
use crane_model::{FrictionLaw, Mode, Params};

/// The paper's printed coupled equations, frictionless and undamped, solved for the
/// accelerations. The trolley is driven by the hoist force `T_l = K_l u_l - f_l` (f_l = 0):
///
/// ```text
/// (x completa)  xdd (Jx + m_t + m_r) = K_x u_x - T_l sa sb
/// (y completa)  ydd (Jy + m_t)       = K_y u_y - T_l ca
/// (L completa)  Ldd (m_p + J_l)      = T_l - m_p ydd ca + m_p L ad^2 + m_p L bd^2 sa^2
///                                      - m_p xdd sa sb + m_p g cb sa
/// (dyn_alpha)   L add     = ydd sa - xdd ca sb + g ca cb + L bd^2 ca sa - 2 Ld ad
/// (dyn_beta)    L sa bdd  = -g sb - cb xdd - 2 sa Ld bd - 2 ca L ad bd
/// ```
///
/// The extra 11th state component integrates the power of the term the paper drops,
/// `-J_l Ldd (sa sb xd + ca yd)` (see `paper_error_1_...`).
fn paper_rhs(p: &Params, u: [f64; 3], z: &[f64; 11]) -> [f64; 11] {
    let [_, _, l, a, b, xd, yd, ld, ad, bd, _] = *z;
    let (sa, ca, sb, cb) = (a.sin(), a.cos(), b.sin(), b.cos());
    let (mp, g) = (p.payload_mass, p.gravity);
    let t_l = p.rope.gain * u[2];
    let xdd = (p.x.gain * u[0] - t_l * sa * sb) / (p.x.inertia + p.trolley_mass + p.rail_mass);
    let ydd = (p.y.gain * u[1] - t_l * ca) / (p.y.inertia + p.trolley_mass);
    let ldd = (t_l - mp * ydd * ca + mp * l * ad * ad + mp * l * bd * bd * sa * sa
        - mp * xdd * sa * sb
        + mp * g * cb * sa)
        / (mp + p.rope.inertia);
    let add = (ydd * sa - xdd * ca * sb + g * ca * cb + l * bd * bd * ca * sa - 2.0 * ld * ad) / l;
    let bdd = (-g * sb - cb * xdd - 2.0 * sa * ld * bd - 2.0 * ca * l * ad * bd) / (l * sa);
    let missing_power = -p.rope.inertia * ldd * (sa * sb * xd + ca * yd);
    [xd, yd, ld, ad, bd, xdd, ydd, ldd, add, bdd, missing_power]
}

fn rk4_paper(p: &Params, u: [f64; 3], z: &mut [f64; 11], h: f64) {
    let add = |z: &[f64; 11], k: &[f64; 11], c: f64| {
        let mut o = *z;
        for i in 0..11 {
            o[i] += c * k[i];
        }
        o
    };
    let k1 = paper_rhs(p, u, z);
    let k2 = paper_rhs(p, u, &add(z, &k1, h / 2.0));
    let k3 = paper_rhs(p, u, &add(z, &k2, h / 2.0));
    let k4 = paper_rhs(p, u, &add(z, &k3, h));
    for i in 0..11 {
        z[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
    }
}

/// Work of the drive forces `sum_i K_i u_i (q_i(t) - q_i(0))` [J]: exact for inputs held
/// constant, as here.
fn drive_work(p: &Params, u: [f64; 3], q0: &[f64; 5], q: &[f64; 5]) -> f64 {
    p.x.gain * u[0] * (q[0] - q0[0])
        + p.y.gain * u[1] * (q[1] - q0[1])
        + p.rope.gain * u[2] * (q[2] - q0[2])
}

/// Paper error 1: the rope transmits `S = J_l Ldd - (K_l u_l - f_l)`, but the printed trolley
/// equations use `T_l = K_l u_l - f_l`, dropping `J_l Ldd`.
///
/// Claim tested precisely, frictionless and undamped, inputs held constant, while the hoist
/// accelerates (`Ldd != 0`):
/// - the model keeps the energy balance `E(t) - E(0) = W(t)` (W = work of the drive forces)
///   to integration accuracy;
/// - the paper's printed equations violate it by a large amount, and the violation is exactly
///   the work of the dropped force `-J_l Ldd (sin(a) sin(b), cos(a))` on the trolley's
///   velocity `(xd, yd)`, i.e. the printed system is the model plus that spurious force.
#[test]
fn paper_error_1_trolley_coupling_drops_hoist_inertia() {
    let p = frictionless(Params::default());
    let q0 = [0.25, 0.3, 0.5, FRAC_PI_2 + 0.3, 0.2];
    let qd0 = [0.05, -0.05, -0.01, 0.3, -0.2];
    let t_end = 0.5;
    // Hoist lifting hard; hoist released (payload falls under its weight); all axes driven.
    for u in [[0.0, 0.0, -3.0], [0.0, 0.0, 0.0], [2.0, -2.0, -1.0]] {
        // The model (matrix form), 1 ms steps.
        let mut m = model(&p, 1e-3, FrictionLaw::Hybrid, q0, qd0);
        let e0 = energy(&p, &m.state());
        let mut worst_model = 0.0_f64;
        let steps = (t_end / 1e-3_f64).round() as usize;
        for _ in 0..steps {
            m.step(u).expect("model step");
            let s = m.state();
            let residual = energy(&p, &s) - e0 - drive_work(&p, u, &q0, &s.q);
            worst_model = worst_model.max(residual.abs());
        }
        let ldd_model = m.output().expect("output").qdd[2];
        // No end stop may be reached (a stop is not conservative).
        for (i, a) in p.axes().into_iter().enumerate() {
            let x = m.state().q[i];
            assert!(x > a.min && x < a.max, "u = {u:?}: axis {i} at {x}");
        }

        // The paper's printed equations, 0.1 ms RK4 steps (much finer than needed).
        let mut z = [0.0; 11];
        z[..5].copy_from_slice(&q0);
        z[5..10].copy_from_slice(&qd0);
        let h = 1e-4;
        for _ in 0..(t_end / h).round() as usize {
            rk4_paper(&p, u, &mut z, h);
        }
        let s = crane_model::State {
            q: [z[0], z[1], z[2], z[3], z[4]],
            qd: [z[5], z[6], z[7], z[8], z[9]],
        };
        let residual_paper = energy(&p, &s) - e0 - drive_work(&p, u, &q0, &s.q);
        let dropped_work = z[10];
        eprintln!(
            "u = {u:?}: Ldd = {ldd_model:.3} m/s^2; balance residual model {worst_model:.1e} J, \
             paper {residual_paper:.4} J, work of the dropped J_l Ldd force {dropped_work:.4} J"
        );
        assert!(ldd_model.abs() > 0.1, "the hoist must accelerate");
        // Model: energy balance holds (RK4 at 1 ms on a ~2 J system: ~1e-9 J).
        assert!(worst_model < 1e-7, "model residual {worst_model:e} J");
        // Paper: the balance fails by centi-joules (E itself is ~2 J)...
        assert!(
            residual_paper.abs() > 1e-2,
            "paper residual only {residual_paper:e} J"
        );
        // ...and the failure is exactly the work of the dropped term.
        assert!(
            (residual_paper - dropped_work).abs() < 1e-8,
            "paper residual {residual_paper:e} J vs dropped work {dropped_work:e} J"
        );
    }
}

/// The paper's stopped-rope `T_l` (Tension_cuerda_parada): the load force of the payload.
fn paper_t_stopped(p: &Params, q: &[f64; 5], qd: &[f64; 5], qdd: &[f64; 5]) -> f64 {
    let (mp, g) = (p.payload_mass, p.gravity);
    let [_, _, l, a, b] = *q;
    let (sa, ca, sb, cb) = (a.sin(), a.cos(), b.sin(), b.cos());
    let (ad, bd) = (qd[3], qd[4]);
    -mp * qdd[1] * ca + mp * l * ad * ad + mp * l * bd * bd * sa * sa - mp * qdd[0] * sa * sb
        + mp * g * cb * sa
}

/// The paper's moving-rope `T_l` (automaton figure, mode q_l = 3, descending):
/// `K_l u_l - Dbar_l Ld - Cbar_l`.
fn paper_t_moving_down(p: &Params, u_l: f64, ld: f64) -> f64 {
    p.rope.gain * u_l - p.rope.viscous_pos * ld - p.rope.dry_pos[0]
}

/// Paper error 2: in the automaton figure the stopped-rope `T_l` is the load force (positive
/// for a hanging payload) while the moving-rope `T_l` is the hoist force (negative for a
/// hanging payload near equilibrium), so the printed trolley equations, which use `-T_l cos(a)`
/// in both modes, jump when the rope starts to move.
///
/// Scenario: X and Y frictionless (so the trolley responds to the rope), the rope with its
/// default dry friction and initially stopped, the payload displaced (alpha = pi/2 + 0.3, so
/// the rope pulls the trolley along Y), and `u_l` ramping up until the rope breaks away
/// (lowering). At the breakaway step the paper's two `T_l` have opposite signs and about the
/// same size; the paper's trolley acceleration would jump by `(T_stop - T_move) |cos a| /
/// (Jbar_y + m_t)`, while the model's trolley acceleration and rope tension are continuous.
#[test]
fn paper_error_2_rope_force_flips_sign_between_modes() {
    let mut p = frictionless(Params::default());
    let d = Params::default();
    p.rope = d.rope;
    p.damping_alpha = d.damping_alpha;
    p.damping_beta = d.damping_beta;
    let q0 = [0.25, 0.3, 0.4, FRAC_PI_2 + 0.3, 0.0];
    let mut m = model(&p, 1e-3, FrictionLaw::Hybrid, q0, [0.0; 5]);
    assert_eq!(m.modes()[2], Mode::Stopped);
    let mut prev = m.output().expect("output");
    let mut prev_state = m.state();
    let mut found = false;
    for k in 0..3000 {
        let u_l = 1.5 * k as f64 / 3000.0 * 2.0;
        let was = m.modes()[2];
        m.step([0.0, 0.0, u_l]).expect("step");
        let now = m.output().expect("output");
        if was == Mode::Stopped && m.modes()[2] == Mode::Positive {
            let s = m.state();
            let ca = s.q[3].cos();
            let t_stop = paper_t_stopped(&p, &prev_state.q, &prev_state.qd, &prev.qdd);
            let t_move = paper_t_moving_down(&p, u_l, s.qd[2]);
            let jy = p.y.inertia + p.trolley_mass;
            let paper_jump = ((-t_move * ca) - (-t_stop * ca)) / jy;
            let model_jump = now.qdd[1] - prev.qdd[1];
            eprintln!(
                "breakaway at step {}: paper T_l stopped {t_stop:.3} N, moving {t_move:.3} N; \
                 paper ydd jump {paper_jump:.4} m/s^2, model ydd {:.4} -> {:.4} m/s^2, \
                 model tension {:.4} -> {:.4} N",
                k + 1,
                prev.qdd[1],
                now.qdd[1],
                prev.tension,
                now.tension
            );
            // Opposite signs for the same physical situation, about the same magnitude.
            assert!(t_stop > 0.0, "stopped-rope T_l = {t_stop}");
            assert!(t_move < 0.0, "moving-rope T_l = {t_move}");
            assert!(
                (t_stop + t_move).abs() < 0.05 * t_stop,
                "|T_stop| = {t_stop}, |T_move| = {t_move}"
            );
            // The printed trolley equation would jump by ~2 m_p g |cos a| / (Jy + m_t).
            assert!(paper_jump.abs() > 0.2, "paper jump {paper_jump}");
            // The model is continuous: its change over the breakaway step is tiny.
            assert!(
                model_jump.abs() < 0.01 * paper_jump.abs(),
                "model ydd jumps by {model_jump}"
            );
            assert!((now.tension - prev.tension).abs() < 0.01 * prev.tension);
            // And the model's rope pulls the trolley towards the payload (the moving-rope sign).
            assert!(now.tension > 0.0 && now.qdd[1] * ca > 0.0);
            found = true;
            break;
        }
        prev = now;
        prev_state = m.state();
    }
    assert!(found, "the rope never broke away");
}

//! The largest stable fixed step `h` [s] of the `tanh` friction law, the law FMU users
//! (`config.law.kind = 1`) and Python users (`Crane(law="tanh")`) integrate with the model's
//! own fixed-step RK4 ([`crane_model::Crane`] with [`FrictionLaw::Tanh`]).
//!
//! Near rest, `Dbar qd + Cbar(q) tanh(gamma qd)` acts as a viscous slope `Dbar + gamma Cbar`
//! [N s/m]: a decay rate `(Dbar + gamma Cbar) / M` [1/s] that explicit RK4 follows only while
//! `h` times it is below 2.785 (the real-axis end of RK4's stability region). Above that, a
//! drive axis at rest chatters: its velocity flips sign every step with an amplitude of about
//! `1 / gamma` [m/s], and its friction force flips between about `+-Cbar`.
//!
//! Measured on the default parameters, at the hanging rest (`alpha = pi/2`, the rope drive
//! holding the payload's weight): each drive axis alone gets a velocity kick of `1e-3 / gamma`
//! (inside the linear part of `tanh`), and the step is stable when every drive velocity has
//! decayed below the kick after `max(0.5 s, 400 steps)`. The largest stable `h` is bisected
//! to 0.5 % between a stable and an unstable step. Beside it: the estimate
//! `2.785 M_ii / (Dbar + gamma Cbar(q))` per axis, with `M_ii` the axis' diagonal mass
//! [kg] and `Cbar`, `Dbar` the mean of the `+` and `-` coefficients.
//!
//! `cargo run --release -p crane-model --example tanh_stable_step` (20 s); its figures are
//! in `model/NUMERICS.md`, and `tests/tanh_stable_step.rs` holds them.

use crane_model::friction::dry;
use crane_model::{Config, Crane, FrictionLaw, Params, State};

/// The rest the figures are measured at: `[x, y, L, alpha, beta]` [m, m, m, rad, rad].
pub const REST: [f64; 5] = [0.25, 0.3, 0.35, core::f64::consts::FRAC_PI_2, 0.0];

/// The `gamma` values [s/m] of the table.
pub const GAMMAS: [f64; 5] = [100.0, 1000.0, 3000.0, 1e4, 1e5];

/// RK4's stability limit on the negative real axis: `|R(z)| = 1` at `z = -2.7853`.
pub const RK4_REAL_LIMIT: f64 = 2.7853;

/// Input holding the payload at rest [V]: the rope drive carries its weight.
pub fn holding_input(p: &Params) -> [f64; 3] {
    [0.0, 0.0, -p.payload_mass * p.gravity / p.rope.gain]
}

/// Whether the `tanh` law with slope `gamma` [s/m] at fixed step `h` [s] damps a velocity
/// kick of `1e-3 / gamma` [m/s] on drive axis `axis` (0 X, 1 Y, 2 rope) at [`REST`]: the
/// largest drive velocity after `max(0.5 s, 400 steps)` is below the kick. A rejected step
/// counts as unstable.
pub fn damps(p: &Params, gamma: f64, h: f64, axis: usize) -> bool {
    let kick = 1e-3 / gamma;
    let mut qd = [0.0; 5];
    qd[axis] = kick;
    let config = Config {
        h,
        law: FrictionLaw::Tanh { gamma },
    };
    let Ok(mut crane) = Crane::<f64>::new(p, config, State { q: REST, qd }) else {
        return false;
    };
    let u = holding_input(p);
    let steps = ((0.5 / h).ceil() as usize).max(400);
    for _ in 0..steps {
        if crane.step(u).is_err() {
            return false;
        }
    }
    let s = crane.state();
    s.qd[..3].iter().all(|v| v.abs() < kick)
}

/// The largest `h` [s] at which [`damps`] holds for every drive axis of `axes`, bisected to
/// 0.5 % between 1 us and 1 s (0 when even 1 us is unstable).
pub fn largest_stable_h(p: &Params, gamma: f64, axes: &[usize]) -> f64 {
    let ok = |h: f64| axes.iter().all(|&axis| damps(p, gamma, h, axis));
    let (mut lo, mut hi) = (1e-6, 1.0);
    if !ok(lo) {
        return 0.0;
    }
    if ok(hi) {
        return hi;
    }
    while hi / lo > 1.005 {
        let mid = (lo * hi).sqrt();
        if ok(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

/// What a user sees at step `h` [s]: from [`REST`] with every drive velocity kicked by
/// `1e-3 / gamma` [m/s], 1 s at the holding input; over its last 0.5 s, the largest drive
/// velocity [m/s] and the largest distance a drive axis moved [m] (both 0 to rounding when
/// stable: the crane is at rest). `None`: a step was rejected.
pub fn creep(p: &Params, gamma: f64, h: f64) -> Option<(f64, f64)> {
    let config = Config {
        h,
        law: FrictionLaw::Tanh { gamma },
    };
    let kick = 1e-3 / gamma;
    let rest = State {
        q: REST,
        qd: [kick, kick, kick, 0.0, 0.0],
    };
    let mut crane = Crane::<f64>::new(p, config, rest).ok()?;
    let hold = holding_input(p);
    let n = ((0.5 / h).round() as usize).max(1);
    for _ in 0..n {
        crane.step(hold).ok()?;
    }
    let (q0, mut vmax) = (crane.state().q, 0.0f64);
    for _ in 0..n {
        crane.step(hold).ok()?;
        vmax = crane.state().qd[..3]
            .iter()
            .fold(vmax, |m, v| m.max(v.abs()));
    }
    let q1 = crane.state().q;
    let moved = (0..3).fold(0.0f64, |m, i| m.max((q1[i] - q0[i]).abs()));
    Some((vmax, moved))
}

/// The estimate `2.785 M_ii / (Dbar + gamma Cbar(q))` [s] for drive axis `axis` at [`REST`]
/// (the `+` and `-` coefficients averaged).
pub fn estimate_h(p: &Params, gamma: f64, axis: usize) -> f64 {
    let mp = p.payload_mass;
    let (ax, m) = match axis {
        0 => (&p.x, p.trolley_mass + p.rail_mass + p.x.inertia + mp),
        1 => (&p.y, p.trolley_mass + p.y.inertia + mp),
        _ => (&p.rope, p.rope.inertia + mp),
    };
    let q = REST[axis];
    let c = 0.5 * (dry(&ax.dry_pos, q) + dry(&ax.dry_neg, q));
    let d = 0.5 * (ax.viscous_pos + ax.viscous_neg);
    RK4_REAL_LIMIT * m / (d + gamma * c)
}

fn main() {
    let p = Params::default();
    println!("tanh law, default parameters, fixed-step RK4 (the FMU's and crane_twin's)");
    println!("largest stable h [ms]: measured, and estimated per drive axis");
    println!(
        "{:>9} {:>8} | {:>8} {:>8} {:>8}",
        "gamma", "measured", "est X", "est Y", "est rope"
    );
    for gamma in GAMMAS {
        let all = largest_stable_h(&p, gamma, &[0, 1, 2]);
        let est: Vec<String> = (0..3)
            .map(|a| format!("{:8.3}", 1e3 * estimate_h(&p, gamma, a)))
            .collect();
        println!("{gamma:>9} {:8.3} | {}", 1e3 * all, est.join(" "));
    }
    println!("at rest, every drive velocity kicked by 1e-3/gamma, 1 s; over its last 0.5 s:");
    println!(
        "{:>9} {:>7} {:>14} {:>14}",
        "gamma", "h ms", "max |qd| m/s", "moved um"
    );
    for gamma in GAMMAS {
        for h in [1e-4, 1e-3, 2e-3] {
            match creep(&p, gamma, h) {
                Some((v, d)) => println!("{gamma:>9} {:>7} {v:>14.2e} {:>14.3}", 1e3 * h, 1e6 * d),
                None => println!("{gamma:>9} {:>7} {:>14} {:>14}", 1e3 * h, "rejected", "-"),
            }
        }
    }
}

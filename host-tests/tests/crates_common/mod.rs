//! Shared by `tests/micromath_sincos.rs`, `tests/nalgebra_solve.rs` and
//! `benches/numerics_crates.rs` (model/NUMERICS.md "nalgebra and micromath: measured, not
//! used"): the three f32 sine/cosine implementations and the linear systems the model solves.
#![allow(dead_code, clippy::needless_range_loop)]

use crane_model::dynamics::{at_state, eval, Law};
use crane_model::Mode;
use crane_twin::logic::fastmath::sincosf;
use crane_twin::logic::scenarios::{InputGen, SCENARIOS};

/// The twin's `F32x` sine and cosine (`twin/src/logic/fastmath.rs`).
pub fn fastmath_sincos(x: f32) -> (f32, f32) {
    sincosf(x)
}

/// libm's `sinf`, `cosf` (what the model's own `f32` calls).
pub fn libm_sincos(x: f32) -> (f32, f32) {
    (libm::sinf(x), libm::cosf(x))
}

/// micromath's `F32Ext::sin`, `F32Ext::cos`, called through the trait: in a `std` crate
/// `x.sin()` would be std's inherent method, not micromath's.
pub fn micromath_sincos(x: f32) -> (f32, f32) {
    (micromath::F32Ext::sin(x), micromath::F32Ext::cos(x))
}

/// A sine-and-cosine implementation: `x` -> `(sin x, cos x)`.
pub type SinCos = fn(f32) -> (f32, f32);

/// The three implementations, in the order of the tables.
pub const SINCOS: [(&str, SinCos); 3] = [
    ("fastmath", fastmath_sincos),
    ("libm sinf/cosf", libm_sincos),
    ("micromath", micromath_sincos),
];

/// The arguments the twin's sine and cosine get: the swing angles between the swing stops,
/// `alpha` in `pi/2 +- 1.4` and `beta` in `+-1.4` (NUMERICS.md "Swing stops"), widened by
/// 0.1 rad for the RK4 stages that overshoot a stop before the step clamps it
/// (`micromath_sincos::twin_arguments_stay_in_the_measured_range` checks the recorded
/// arguments of the scenarios and the closed loop against this).
pub const TWIN_RANGE: (f32, f32) = (-1.5, 3.1);

/// One linear system the model solves: `a x = r` with the stopped axes' rows and columns
/// already replaced by unit vectors, and the model's own solution.
#[derive(Clone, Copy, Debug)]
pub struct System {
    /// The matrix given to `solve5` (the mass matrix, stopped axes held).
    pub a: [[f64; 5]; 5],
    /// The right-hand side.
    pub r: [f64; 5],
    /// `true` for an end-stop solve (`r = e_i`), `false` for an evaluation's `qdd`.
    pub unit_rhs: bool,
    /// The model's solution (`dynamics::eval(..).qdd` for an evaluation; `None` for an
    /// end-stop solve, which the model does not expose: the reference's `solve5`, pinned bit
    /// for bit to the model by `tests/bit_exact.rs`, stands for it).
    pub model: Option<[f64; 5]>,
}

/// The systems of every step of the five cross-check scenarios (`twin/src/logic/scenarios.rs`)
/// in f64, every `every`-th step: at the state after the step, in its modes, with the step's
/// saturated input, the evaluation's system (built from `dynamics::at_state` as
/// `dynamics::eval` builds it, NUMERICS.md "One evaluation") and for each moving drive axis
/// the end-stop system `M w = e_i`.
pub fn mass_systems(every: u32) -> Vec<System> {
    let mut out = Vec::new();
    for sc in SCENARIOS.iter() {
        let mut crane = sc.crane::<f64>().expect("scenario crane");
        let mut gen = InputGen::new(sc);
        for k in 0..sc.steps {
            let u = gen.input(sc, k);
            if crane.step(u).is_err() || k % every != 0 {
                continue;
            }
            let u = u.map(|v| v.clamp(-12.0, 12.0));
            let (c, y, modes) = (crane.coeffs(), crane.state(), crane.modes());
            let Ok(ev) = eval(c, Law::Hybrid, &y, &modes, &u) else {
                continue;
            };
            let pre = at_state(c, &y);
            // Q_i = K_i u_i - f_i; `fric` is the law's force for a moving axis.
            let qv = [
                c.axes[0].drive(u[0]) - ev.fric[0],
                c.axes[1].drive(u[1]) - ev.fric[1],
                c.axes[2].drive(u[2]) - ev.fric[2],
                -(c.damp_alpha * y.qd[3]),
                -(c.damp_beta * y.qd[4]),
            ];
            let mut r = [0.0; 5];
            for j in 0..5 {
                r[j] = qv[j] - pre.hv[j] - pre.gv[j];
            }
            let mut a = pre.m;
            for i in 0..3 {
                if modes[i] == Mode::Stopped {
                    for row in a.iter_mut() {
                        row[i] = 0.0;
                    }
                    a[i] = [0.0; 5];
                    a[i][i] = 1.0;
                    r[i] = 0.0;
                }
            }
            out.push(System {
                a,
                r,
                unit_rhs: false,
                model: Some(ev.qdd),
            });
            for i in 0..3 {
                if modes[i] != Mode::Stopped {
                    let mut e = [0.0; 5];
                    e[i] = 1.0;
                    out.push(System {
                        a,
                        r: e,
                        unit_rhs: true,
                        model: None,
                    });
                }
            }
        }
    }
    out
}

//! The Dormand-Prince 5(4) tableau (Dormand & Prince 1980; Hairer, Norsett & Wanner, "Solving
//! Ordinary Differential Equations I", table II.5.2) and the 4th-order continuous extension of
//! MATLAB's `ntrp45`: the one copy of these coefficients, used by [`crate::adaptive`] (the
//! hybrid automaton) and by the host's plain `ode45` (`tools/src/ode45.rs`).
//!
//! Stage `i` (0-based) is evaluated at `t + C[i] h` on `y + h sum_j A[i - 1][j] k_j`; the
//! 5th-order solution is `y + h sum_i B[i] k_i` (FSAL: stage 6 is `f` there), the error
//! estimate `h sum_i E[i] k_i`. `h` is the step in the caller's time unit (seconds in this
//! project); the coefficients are dimensionless.

/// Nodes `c_i` of the seven stages (fractions of the step).
pub const C: [f64; 7] = [0.0, 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0, 1.0, 1.0];

/// Coupling coefficients: row `i` gives stage `i + 1` from stages `0..=i`.
pub const A: [[f64; 5]; 5] = [
    [1.0 / 5.0, 0.0, 0.0, 0.0, 0.0],
    [3.0 / 40.0, 9.0 / 40.0, 0.0, 0.0, 0.0],
    [44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0.0, 0.0],
    [
        19372.0 / 6561.0,
        -25360.0 / 2187.0,
        64448.0 / 6561.0,
        -212.0 / 729.0,
        0.0,
    ],
    [
        9017.0 / 3168.0,
        -355.0 / 33.0,
        46732.0 / 5247.0,
        49.0 / 176.0,
        -5103.0 / 18656.0,
    ],
];

/// Weights of the 5th-order solution over stages 0..=5 (stage 1's is zero).
pub const B: [f64; 6] = [
    35.0 / 384.0,
    0.0,
    500.0 / 1113.0,
    125.0 / 192.0,
    -2187.0 / 6784.0,
    11.0 / 84.0,
];

/// Error weights: 5th-order minus 4th-order weights over the seven stages (FSAL).
pub const E: [f64; 7] = [
    71.0 / 57600.0,
    0.0,
    -71.0 / 16695.0,
    71.0 / 1920.0,
    -17253.0 / 339200.0,
    22.0 / 525.0,
    -1.0 / 40.0,
];

/// Dense output (MATLAB `ntrp45`): stage `i`'s weight at `th` is
/// `b_i(th) = sum_j BI[i][j] th^(j+1)`; row 1 is zero.
pub const BI: [[f64; 4]; 7] = [
    [1.0, -183.0 / 64.0, 37.0 / 12.0, -145.0 / 128.0],
    [0.0, 0.0, 0.0, 0.0],
    [0.0, 1500.0 / 371.0, -1000.0 / 159.0, 1000.0 / 371.0],
    [0.0, -125.0 / 32.0, 125.0 / 12.0, -375.0 / 64.0],
    [0.0, 9477.0 / 3392.0, -729.0 / 106.0, 25515.0 / 6784.0],
    [0.0, -11.0 / 7.0, 11.0 / 3.0, -55.0 / 28.0],
    [0.0, 1.5, -4.0, 2.5],
];

/// Weights `b_i(th)` of the seven stages for the dense output at `th = (t - t0) / h` in
/// `[0, 1]` (dimensionless): `y(t) = y0 + h sum_i b_i(th) k_i`.
pub fn dense_weights(th: f64) -> [f64; 7] {
    let p = [th, th * th, th * th * th, th * th * th * th];
    let mut w = [0.0; 7];
    for (wi, b) in w.iter_mut().zip(BI.iter()) {
        *wi = b[0] * p[0] + b[1] * p[1] + b[2] * p[2] + b[3] * p[3];
    }
    w
}

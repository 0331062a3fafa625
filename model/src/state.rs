//! The continuous state of the crane.

use crate::real::Real;

/// Generalised coordinates and velocities.
///
/// `q = [x, y, L, alpha, beta]`: rail position X [m], trolley position Y [m], rope length L
/// [m] (positive velocity lowers the payload), swing angles alpha, beta [rad] (hanging
/// straight down is `alpha = pi/2, beta = 0`). `qd` holds their time derivatives.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct State<R: Real = f64> {
    /// Positions `[x, y, L, alpha, beta]` [m, m, m, rad, rad].
    pub q: [R; 5],
    /// Velocities `[xd, yd, Ld, alphad, betad]` [m/s, m/s, m/s, rad/s, rad/s].
    pub qd: [R; 5],
}

impl<R: Real> State<R> {
    /// Payload position `[x_p, y_p, z_p]` [m]: `x + L sin(beta) sin(alpha)`,
    /// `y + L cos(alpha)`, `-L sin(alpha) cos(beta)` (z up, so hanging payloads have z < 0).
    pub fn payload(&self) -> [R; 3] {
        let [x, y, l, a, b] = self.q;
        let (sa, ca, sb, cb) = (a.sin(), a.cos(), b.sin(), b.cos());
        [x + l * sb * sa, y + l * ca, -(l * sa * cb)]
    }

    /// `true` if every component is finite.
    pub fn is_finite(&self) -> bool {
        self.q.iter().chain(self.qd.iter()).all(|v| v.is_finite())
    }

    /// Converts to `f64` (exact).
    pub fn to_f64(&self) -> State<f64> {
        State {
            q: self.q.map(R::to_f64),
            qd: self.qd.map(R::to_f64),
        }
    }
}

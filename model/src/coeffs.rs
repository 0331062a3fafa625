//! The model's coefficient tables: validated parameters (and extensions) precomputed in the
//! model's scalar type for the step path. No dynamics here, no friction laws: the tables sit
//! below both.

use crate::extensions::{Direction, Extensions, MAX_BUMPS};
use crate::params::{AxisParams, Params};
use crate::real::Real;

/// Coefficients of one drive axis in the model's scalar type.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AxisCoeffs<R: Real> {
    /// Gain `K` [N/V].
    pub gain: R,
    /// Viscous `Dbar+` [N s/m].
    pub visc_pos: R,
    /// Viscous `Dbar-` [N s/m].
    pub visc_neg: R,
    /// Dry-friction polynomial `Cbar+` coefficients c0..c4 [N].
    pub dry_pos: [R; 5],
    /// Dry-friction polynomial `Cbar-` coefficients c0..c4 [N].
    pub dry_neg: [R; 5],
    /// Lower limit [m].
    pub min: R,
    /// Upper limit [m].
    pub max: R,
    /// Localised friction bumps on this axis (the first `n_bumps` are used).
    pub bumps: [BumpCoeffs<R>; MAX_BUMPS],
    /// Number of bumps in use.
    pub n_bumps: usize,
    /// Stiction `(ratio, Stribeck velocity [m/s])`, if on.
    pub stiction: Option<(R, R)>,
    /// Constant bias force [N], if on.
    pub offset: Option<R>,
    /// Input dead band [V], if on.
    pub deadzone: Option<R>,
}

/// A localised friction bump in the model's scalar type (see [`crate::Bump`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BumpCoeffs<R: Real> {
    /// Centre [m].
    pub center: R,
    /// Half-width [m].
    pub width: R,
    /// Amplitude [N].
    pub amplitude: R,
    /// Applies to positive motion.
    pub pos: bool,
    /// Applies to negative motion.
    pub neg: bool,
}

impl<R: Real> AxisCoeffs<R> {
    /// Drive force [N] of input `u` [V]: `K u`, plus the bias force when on.
    #[inline]
    pub fn drive(&self, u: R) -> R {
        match self.offset {
            Some(b) => self.gain * u + b,
            None => self.gain * u,
        }
    }

    fn from_params(a: &AxisParams) -> Self {
        AxisCoeffs {
            gain: R::from_f64(a.gain),
            visc_pos: R::from_f64(a.viscous_pos),
            visc_neg: R::from_f64(a.viscous_neg),
            dry_pos: a.dry_pos.map(R::from_f64),
            dry_neg: a.dry_neg.map(R::from_f64),
            min: R::from_f64(a.min),
            max: R::from_f64(a.max),
            bumps: [BumpCoeffs {
                center: R::ZERO,
                width: R::ONE,
                amplitude: R::ZERO,
                pos: false,
                neg: false,
            }; MAX_BUMPS],
            n_bumps: 0,
            stiction: None,
            offset: None,
            deadzone: None,
        }
    }
}

/// Validated parameters, precomputed for the step path.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Coeffs<R: Real> {
    /// Payload mass `m_p` [kg].
    pub mp: R,
    /// `m_p g` [N].
    pub mpg: R,
    /// `M00 = m_t + m_r + Jbar_x + m_p` [kg].
    pub m00: R,
    /// `M11 = m_t + Jbar_y + m_p` [kg].
    pub m11: R,
    /// `M22 = Jbar_l + m_p` [kg].
    pub m22: R,
    /// Rope reflected inertia `Jbar_l` [kg].
    pub jbar_l: R,
    /// Swing damping `D_alpha` [kg m^2/s].
    pub damp_alpha: R,
    /// Swing damping `D_beta` [kg m^2/s].
    pub damp_beta: R,
    /// Drive axes X, Y, rope.
    pub axes: [AxisCoeffs<R>; 3],
}

impl<R: Real> Coeffs<R> {
    /// Precomputes from parameters (assumed validated). Sums are formed in f64 as
    /// `NUMERICS.md` states, then rounded to `R`.
    pub fn new(p: &Params) -> Self {
        let mp = p.payload_mass;
        Coeffs {
            mp: R::from_f64(mp),
            mpg: R::from_f64(mp * p.gravity),
            m00: R::from_f64(p.trolley_mass + p.rail_mass + p.x.inertia + mp),
            m11: R::from_f64(p.trolley_mass + p.y.inertia + mp),
            m22: R::from_f64(p.rope.inertia + mp),
            jbar_l: R::from_f64(p.rope.inertia),
            damp_alpha: R::from_f64(p.damping_alpha),
            damp_beta: R::from_f64(p.damping_beta),
            axes: [
                AxisCoeffs::from_params(&p.x),
                AxisCoeffs::from_params(&p.y),
                AxisCoeffs::from_params(&p.rope),
            ],
        }
    }

    /// Adds the (validated) extensions; effects that are off stay `None`/empty.
    pub fn extend(&mut self, ext: &Extensions) {
        for b in ext.bumps.iter() {
            if let Some(ax) = self.axes.get_mut(b.axis.index()) {
                if let Some(slot) = ax.bumps.get_mut(ax.n_bumps) {
                    *slot = BumpCoeffs {
                        center: R::from_f64(b.center),
                        width: R::from_f64(b.width),
                        amplitude: R::from_f64(b.amplitude),
                        pos: b.direction != Direction::Negative,
                        neg: b.direction != Direction::Positive,
                    };
                    ax.n_bumps += 1;
                }
            }
        }
        for (i, ax) in self.axes.iter_mut().enumerate() {
            ax.stiction = ext
                .stiction
                .get(i)
                .copied()
                .flatten()
                .filter(|s| s.ratio != 1.0)
                .map(|s| (R::from_f64(s.ratio), R::from_f64(s.velocity)));
            ax.offset = ext
                .force_offset
                .get(i)
                .filter(|&&b| b != 0.0)
                .map(|&b| R::from_f64(b));
            ax.deadzone = ext
                .deadzone
                .get(i)
                .filter(|&&d| d != 0.0)
                .map(|&d| R::from_f64(d));
        }
    }
}

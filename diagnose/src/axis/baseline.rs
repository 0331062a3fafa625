//! Stage 2: the baseline fitted by least squares on the fitting rows and scored on the
//! held-out rows, and the fit of the baseline with a candidate's extra columns on top
//! ([`BaseColumns::eval`]).
//!
//! Sign convention: the force is the drive's, positive pushing towards increasing position;
//! every regressor column is a force per unit of its coefficient.

use super::prepare::Prepared;
use super::rows::{dec, Part};
use crate::fit::{ls, mae, sse};
use crate::DiagnoseError;

/// A least-squares fit on the fitting part, scored on the held-out part.
pub(super) struct Fitted {
    /// Held-out sum of squared force residuals [N^2].
    pub(super) sse_h: f64,
    /// Held-out mean absolute force residual [N].
    pub(super) mae_h: f64,
    /// Fitting sum of squared force residuals [N^2].
    pub(super) sse_f: f64,
    /// Coefficients, one per column: the baseline's first, then the extra columns'.
    pub(super) theta: Vec<f64>,
}

/// A candidate's extra columns and targets on the fitting (`f`) and held-out (`h`) rows.
pub(super) struct Design {
    /// Extra columns on the fitting rows (decimated, as the baseline's).
    pub(super) ef: Vec<Vec<f64>>,
    /// Extra columns on the held-out rows.
    pub(super) eh: Vec<Vec<f64>>,
    /// Target force on the fitting rows [N] (the measured force, or the candidate's
    /// transform of it: delayed, dead band).
    pub(super) yf: Vec<f64>,
    /// Target force on the held-out rows [N].
    pub(super) yh: Vec<f64>,
}

/// The baseline's regressor columns (decimated) on the fitting and the held-out rows.
pub(super) struct BaseColumns {
    /// On the fitting rows.
    pub(super) fit: Vec<Vec<f64>>,
    /// On the held-out rows.
    pub(super) held: Vec<Vec<f64>>,
}

impl BaseColumns {
    /// Evaluates baseline + extra columns `ef` / `eh`, with target `yf` / `yh` [N]: least
    /// squares on the fitting rows, scored on both; `None` when the least squares fail.
    pub(super) fn eval(
        &self,
        ef: &[Vec<f64>],
        eh: &[Vec<f64>],
        yf: &[f64],
        yh: &[f64],
    ) -> Option<Fitted> {
        let (bf, bh) = (&self.fit, &self.held);
        let cf: Vec<&[f64]> = bf.iter().chain(ef).map(|c| c.as_slice()).collect();
        let ch: Vec<&[f64]> = bh.iter().chain(eh).map(|c| c.as_slice()).collect();
        let th = ls(&cf, yf)?;
        Some(Fitted {
            sse_h: sse(&ch, &th, yh),
            mae_h: mae(&ch, &th, yh),
            sse_f: sse(&cf, &th, yf),
            theta: th,
        })
    }

    /// The fitting sum of squared force residuals [N^2] of the baseline's columns alone with
    /// target `yf` [N] (what [`Self::eval`] gives as `sse_f` without extra columns, the
    /// held-out rows not scored); `None` when the least squares fail.
    pub(super) fn fit_sse(&self, yf: &[f64]) -> Option<f64> {
        let cf: Vec<&[f64]> = self.fit.iter().map(|c| c.as_slice()).collect();
        let th = ls(&cf, yf)?;
        Some(sse(&cf, &th, yf))
    }
}

/// The fitted baseline and the figures every later stage measures against.
pub(super) struct BaselineFit {
    /// Lowest filtered position of the fitting rows [m or rad].
    pub(super) lo: f64,
    /// Highest filtered position of the fitting rows [m or rad].
    pub(super) hi: f64,
    /// The baseline's columns.
    pub(super) cols: BaseColumns,
    /// The baseline's own fit (no extra column, the measured force as target).
    pub(super) fitted: Fitted,
    /// Sum of squared held-out forces [N^2] (`||F||^2` of the relative force error).
    pub(super) fnorm_h: f64,
    /// Sum of squared fitting forces [N^2].
    pub(super) fnorm_f: f64,
    /// Range (max - min) of the held-out force [N]: the NMAE's denominator.
    pub(super) hrange: f64,
}

impl BaselineFit {
    /// The baseline's force NMAE on the fitting rows [%]: mean |residual| over the range of
    /// the fitting force (`NaN`, reported as null, when that range is 0).
    pub(super) fn nmae_fit(&self, prep: &Prepared) -> f64 {
        let f = &prep.fit.f;
        let range = f.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
            - f.iter().cloned().fold(f64::INFINITY, f64::min);
        let cols: Vec<&[f64]> = self.cols.fit.iter().map(|c| c.as_slice()).collect();
        let e = mae(&cols, &self.fitted.theta, f);
        if range > 0.0 {
            100.0 * e / range
        } else {
            f64::NAN
        }
    }

    /// The extra columns `ef` / `eh` on the measured force: the design and its fit.
    pub(super) fn fit_extra(
        &self,
        prep: &Prepared,
        ef: Vec<Vec<f64>>,
        eh: Vec<Vec<f64>>,
    ) -> (Design, Option<Fitted>) {
        let design = Design {
            ef,
            eh,
            yf: prep.fit.f.clone(),
            yh: prep.held.f.clone(),
        };
        let r = self
            .cols
            .eval(&design.ef, &design.eh, &design.yf, &design.yh);
        (design, r)
    }
}

/// Stage 2: the baseline's columns, its least-squares fit on the fitting rows and the
/// force norms and range of the rows. Error: the least squares fail.
pub(super) fn fit_baseline(prep: &Prepared) -> Result<BaselineFit, DiagnoseError> {
    let (fit, held, sym) = (&prep.fit, &prep.held, prep.sym);
    let lo = fit.q.iter().cloned().fold(f64::INFINITY, f64::min);
    let hi = fit.q.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    let (mid, half) = (0.5 * (lo + hi), (0.5 * (hi - lo)).max(1e-6));
    let cols = BaseColumns {
        fit: base_cols(fit, sym, mid, half),
        held: base_cols(held, sym, mid, half),
    };
    let fitted = cols
        .eval(&[], &[], &fit.f, &held.f)
        .ok_or_else(|| DiagnoseError::Model("baseline least squares failed".into()))?;
    let fnorm_h: f64 = held.f.iter().map(|x| x * x).sum();
    let fnorm_f: f64 = fit.f.iter().map(|x| x * x).sum();
    let hrange = held.f.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
        - held.f.iter().cloned().fold(f64::INFINITY, f64::min);
    Ok(BaselineFit {
        lo,
        hi,
        cols,
        fitted,
        fnorm_h,
        fnorm_f,
        hrange,
    })
}

/// The baseline's columns of `p`, decimated ([`dec`]); positions scaled to `(q - mid) / half`
/// ([`base_cols_full`]).
fn base_cols(p: &Part, sym: bool, mid: f64, half: f64) -> Vec<Vec<f64>> {
    base_cols_full(p, sym, mid, half)
        .into_iter()
        .map(|c| dec(p, c))
        .collect()
}

/// The baseline's columns of `p` at the full rate. Symmetric: `[qdd, qd, sign(qd), 1]`
/// (coefficients: mass [kg], viscous [N s/m], Coulomb [N], offset [N]). The paper's
/// structure: `[qdd, max(qd, 0), min(qd, 0)]` (mass, viscous moving positive, viscous moving
/// negative), then `s^j` while moving positive and `-s^j` while moving negative, `j = 0..4`,
/// `s = (q - mid) / half`: the dry-friction magnitude of each direction [N] as a quartic in
/// the scaled position (both magnitudes positive for a friction opposing the motion).
fn base_cols_full(p: &Part, sym: bool, mid: f64, half: f64) -> Vec<Vec<f64>> {
    let ind = |pos: bool| -> Vec<f64> {
        p.v.iter()
            .map(|&v| {
                if pos && v > 0.0 {
                    1.0
                } else if !pos && v < 0.0 {
                    -1.0
                } else {
                    0.0
                }
            })
            .collect()
    };
    if sym {
        // the published symmetric model: M qdd + Fv qd + Fc sign(qd) + offset
        return vec![
            p.a.clone(),
            p.v.clone(),
            p.v.iter()
                .map(|&v| if v == 0.0 { 0.0 } else { v.signum() })
                .collect(),
            vec![1.0; p.v.len()],
        ];
    }
    let mut c = vec![
        p.a.clone(),
        p.v.iter().map(|&v| v.max(0.0)).collect(),
        p.v.iter().map(|&v| v.min(0.0)).collect(),
    ];
    for pos in [true, false] {
        let i = ind(pos);
        for j in 0..5 {
            c.push(
                i.iter()
                    .zip(&p.q)
                    .map(|(s, q)| s * ((q - mid) / half).powi(j))
                    .collect(),
            );
        }
    }
    c
}

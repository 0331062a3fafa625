//! Trying one cause: the current structure extended by it, fitted on the fitting runs and
//! scored on the held-out ones. Causes with a value to search (dead band, saturation, load
//! share, delay, the bump's site) are searched on grids chosen on the fitting runs only
//! ([`super::grid`]), and a value at a grid's edge comes back with a note: it is never named.

use super::estimate::{BumpSite, Estimate, Structure};
use super::experiment::Experiment;
use super::prep::{Prepared, Thresholds};
use super::score::Scored;
use crate::Cause;

/// Dead bands tried, as fractions of the largest |input| of the fitting runs, geometric by
/// [`GRID_RATIO`]; the best is refined between its neighbours by [`GRID_REFINE`]
/// golden-section steps.
pub const DEADBAND_RANGE: (f64, f64) = (0.005, 0.5);
/// Saturation levels tried: these quantiles of |input| over the fitting runs' moving samples
/// (levels at or above the largest |input| clip nothing and are dropped); the best is refined
/// between its neighbours by [`GRID_REFINE`] golden-section steps.
pub const SATURATION_QUANTILES: [f64; 11] =
    [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 0.95, 0.99];
/// Load shares `mu` tried for load-dependent friction (every dry level plus `mu |F|`): from
/// a fine screw or gear (a few %) to a worm gear near self-locking, geometric by
/// [`GRID_RATIO`] ([`super::grid::geometric`]).
pub const LOAD_RANGE: (f64, f64) = (0.01, 0.8);
/// Largest ratio between neighbouring points of a geometric grid (dead band, load share). The fitting runs' simulated error of a stick-slip log is not smooth in
/// these parameters: whether the axis sticks at a stair or slips on changes with a few percent
/// of a level, and the error drops in a narrow notch around the true value (stranger s055,
/// a load share 0.276: 0.37 % there against 1.33 % at 0.1 and 1.76 % at 0.2). A coarse grid
/// steps over the notch and its golden-section refinement, which searches between the best
/// point's neighbours only, never finds it. Neighbours within 20 % of each other put a point
/// within 10 % of any value.
pub const GRID_RATIO: f64 = 1.2;
/// The quantile of the moving |v| that tops the Stribeck grid.
pub const STRIBECK_TOP_QUANTILE: f64 = 0.9;
/// Stribeck velocities tried: this many, geometric from the motion threshold to the
/// [`STRIBECK_TOP_QUANTILE`]. Not [`GRID_RATIO`]: that grid (38 points on stranger s023, each
/// one a simulation whose substeps grow as the velocity falls, `crane_ident::simulate::substeps`)
/// took 83 s of one diagnosis and named no Stribeck case the 9 points missed (published and
/// held-back stranger sets, 2026-11-27).
pub const STRIBECK_POINTS: usize = 9;
/// Golden-section steps refining the best dead band, saturation or load-share grid value (on the
/// fitting runs): the bracket shrinks to 0.618^8, under 2 % of the grid step.
pub const GRID_REFINE: usize = 10;

/// Golden-section steps refining the best whole delay to a fraction of a sample between its
/// neighbours ([`super::grid::fractional`]): the bracket of two samples shrinks to
/// `2 * 0.618^6`, about a tenth of a sample. A delay is a continuous time; a log's sample
/// period need not divide it (stranger s027: 79 samples of 2.04 ms against 0.1625 s, off by
/// 1.1 ms; with the fraction, 79.39 samples, 0.1622 s).
pub const DELAY_REFINE: usize = 8;

/// What [`try_cause`] fits and scores with.
pub(super) struct Search<'a> {
    /// The runs, and how a structure is fitted and scored on them.
    pub ex: &'a Experiment<'a>,
    /// On a long log, the fitting runs' heads ([`Experiment::long_heads`]): the dead band,
    /// saturation, load share, Stribeck velocity and delay are chosen on their simulation,
    /// and the chosen structure is then fitted on the whole fitting runs and scored. A grid
    /// simulates the fitting runs once per point (40-60 points with the golden-section steps);
    /// on a 10 kHz log with a 60 s fitting run that is 600,000 samples each. The bump's site
    /// is chosen on the whole runs: a head need not reach every position the runs visit.
    pub heads: Option<&'a Experiment<'a>>,
    /// Largest |input| of the fitting runs.
    pub umax: f64,
    /// Saturation levels tried ([`saturation_grid`]).
    pub sat_grid: &'a [f64],
    /// Stribeck velocities tried [m/s or rad/s] ([`stribeck_grid`]), ascending.
    pub stribeck_grid: &'a [f64],
    /// Delays tried [samples] ([`super::grid::delay_grid`]), ascending.
    pub delay_grid: &'a [usize],
    /// The fitting runs' sample period [s] (the shortest, if they differ).
    pub dt: f64,
    /// The peak of a model's binned sliding residual ([`super::local::guess`]).
    pub bump_guess: &'a (dyn Fn(&Estimate) -> Option<BumpSite> + Sync),
}

/// The saturation levels tried: [`SATURATION_QUANTILES`] of |input| over the fitting runs'
/// samples moving faster than the motion threshold, ascending, distinct, above 0 and below
/// `umax` (a level at or above the largest |input| clips nothing).
pub(super) fn saturation_grid(fit: &[&Prepared], th: &Thresholds, umax: f64) -> Vec<f64> {
    let mut a: Vec<f64> = fit
        .iter()
        .flat_map(|p| {
            p.run
                .u
                .iter()
                .zip(&p.v)
                .filter(|(_, v)| v.abs() > th.v_move)
                .map(|(u, _)| u.abs())
        })
        .filter(|u| u.is_finite())
        .collect();
    if a.is_empty() {
        return Vec::new();
    }
    a.sort_by(f64::total_cmp);
    let mut grid: Vec<f64> = SATURATION_QUANTILES
        .iter()
        .map(|q| a[((q * (a.len() - 1) as f64).round() as usize).min(a.len() - 1)])
        .filter(|&l| l > 0.0 && l < umax)
        .collect();
    grid.dedup();
    grid
}

/// The Stribeck velocities tried [m/s or rad/s]: from the motion threshold `v_move` (a
/// weakening faster than that is stiction: the friction drops before the motion is seen) to
/// the [`STRIBECK_TOP_QUANTILE`] of |v| over the fitting runs' moving samples (a weakening
/// slower than that never ends within the motions), [`STRIBECK_POINTS`] geometric; empty when
/// that range is empty (no motion faster than the threshold). The best is refined between its
/// neighbours by [`GRID_REFINE`] golden-section steps.
pub(super) fn stribeck_grid(fit: &[&Prepared], th: &Thresholds) -> Vec<f64> {
    let mut a: Vec<f64> = fit
        .iter()
        .flat_map(|p| p.v.iter().map(|v| v.abs()))
        .filter(|v| v.is_finite() && *v > th.v_move)
        .collect();
    if a.is_empty() {
        return Vec::new();
    }
    a.sort_by(f64::total_cmp);
    let top = a[((STRIBECK_TOP_QUANTILE * (a.len() - 1) as f64).round() as usize).min(a.len() - 1)];
    if top.is_nan() || top <= th.v_move {
        return Vec::new();
    }
    let r = (top / th.v_move).powf(1.0 / (STRIBECK_POINTS - 1) as f64);
    (0..STRIBECK_POINTS)
        .map(|k| th.v_move * r.powi(k as i32))
        .collect()
}

/// Fits and scores the current structure plus one cause; for grid-searched causes the best
/// grid point, with a note when it lies at the grid's edge.
pub(super) fn try_cause(
    cause: Cause,
    current: &Scored,
    search: &Search<'_>,
) -> Option<(Scored, Option<String>)> {
    let (ex, umax) = (search.ex, search.umax);
    let s = current.est.structure;
    let one = |s: Structure| ex.fit_and_score(s).ok().map(|r| (r, None));
    // on the fitting runs, or their heads on a long log (`Search::heads`)
    let fitted = |st: Structure| fitted_on(search.heads.unwrap_or(ex), st);
    let settled = |est: Estimate| settle(search, est);
    match cause {
        Cause::RestoringForce if !s.restoring => one(Structure {
            restoring: true,
            ..s
        }),
        Cause::Stiction if !s.stiction => one(Structure {
            stiction: true,
            ..s
        }),
        Cause::StribeckFriction if !s.stiction && !search.stribeck_grid.is_empty() => {
            // stiction whose friction falls off with speed: the velocity is chosen on the
            // fitting runs' simulation (the sliding samples alone hardly see it: most slide
            // far above it)
            let grid = search.stribeck_grid;
            let b = super::grid::continuous(grid, GRID_REFINE, |vs| {
                fitted(Structure {
                    stiction: true,
                    stribeck: vs,
                    ..s
                })
            })?;
            let edge = b.at_edge(grid, true).then(|| {
                if b.at == grid[0] {
                    format!("Stribeck velocity at the lowest value tried ({:.4}, the motion threshold: the friction falls off before the motion is seen, which is stiction; grid edge)", b.at)
                } else {
                    format!("Stribeck velocity at the highest value tried ({:.4}, the {} quantile of the moving |v|: the friction does not fall off within the motions; grid edge)", b.at, STRIBECK_TOP_QUANTILE)
                }
            });
            settled(b.value).map(|r| (r, edge))
        }
        Cause::DirectionAsymmetry if !s.asymmetric => one(Structure {
            asymmetric: true,
            ..s
        }),
        Cause::ForceOffset if !s.offset => one(Structure { offset: true, ..s }),
        Cause::InputDeadzone if s.deadband == 0.0 && umax > 0.0 => {
            // the value is chosen on the fitting runs: the held-out runs then score an
            // honestly chosen value (choosing on them would select on the test set)
            let fractions = super::grid::geometric(DEADBAND_RANGE.0, DEADBAND_RANGE.1, GRID_RATIO);
            let grid: Vec<f64> = fractions.iter().map(|f| f * umax).collect();
            let b = super::grid::continuous(&grid, GRID_REFINE, |d| {
                fitted(Structure { deadband: d, ..s })
            })?;
            let edge =
                b.at_edge(&grid, true).then(|| {
                    let lowest = b.at == grid[0];
                    format!(
                    "dead band at the {} value tried ({:.4}, {} of the largest |input|; grid edge)",
                    if lowest { "smallest" } else { "largest" },
                    b.at,
                    if lowest { DEADBAND_RANGE.0 } else { DEADBAND_RANGE.1 }
                )
                });
            settled(b.value).map(|r| (r, edge))
        }
        Cause::InputSaturation if s.saturation == 0.0 && !search.sat_grid.is_empty() => {
            // levels chosen on the fitting runs, like the dead band's: the grid over quantiles
            // of |u| while moving, refined between the best level's neighbours; only the
            // chosen model is scored on the held-out runs
            let grid = search.sat_grid;
            let b = super::grid::continuous(grid, GRID_REFINE, |level| {
                fitted(Structure {
                    saturation: level,
                    ..s
                })
            })?;
            let edge = b.at_edge(grid, true).then(|| {
                format!(
                    "saturation level at the {} level tried ({:.4}, the {} quantile of |input| while moving; grid edge)",
                    if b.at == grid[0] { "lowest" } else { "highest" },
                    b.at,
                    if b.at == grid[0] { SATURATION_QUANTILES[0] } else { SATURATION_QUANTILES[SATURATION_QUANTILES.len() - 1] }
                )
            });
            settled(b.value).map(|r| (r, edge))
        }
        Cause::LoadDependentFriction if s.load == 0.0 => {
            // chosen on the fitting runs' simulation, like the dead band: a least squares of
            // `mu` against the effort it multiplies trades it for the inertia and gain
            let grid = super::grid::geometric(LOAD_RANGE.0, LOAD_RANGE.1, GRID_RATIO);
            let b = super::grid::continuous(&grid, GRID_REFINE, |mu| {
                fitted(Structure { load: mu, ..s })
            })?;
            let edge = b.at_edge(&grid, true).then(|| {
                format!(
                    "load share mu at the {} value tried ({:.4}; grid edge)",
                    if b.at == grid[0] {
                        "smallest"
                    } else {
                        "largest"
                    },
                    b.at
                )
            });
            settled(b.value).map(|r| (r, edge))
        }
        Cause::LocalizedFriction if s.bump.is_none() => {
            // the sites around the peak of the binned sliding residual, each with its
            // amplitude by least squares, chosen by the fitting runs' simulation
            let g = (search.bump_guess)(&current.est)?;
            let best = super::local::sites(g)
                .into_iter()
                .filter_map(|site| {
                    fitted_on(
                        ex,
                        Structure {
                            bump: Some(site),
                            ..s
                        },
                    )
                    .filter(|(_, e)| e.is_finite())
                })
                .min_by(|a, b| a.1.total_cmp(&b.1))?;
            ex.score(best.0).ok().map(|r| (r, None))
        }
        Cause::InputDelay if s.delay == 0.0 && !search.delay_grid.is_empty() => {
            try_delay(s, search)
        }
        _ => None,
    }
}

/// A structure fitted on the runs of `on`, with its simulated error there (the measure every
/// grid-searched value is chosen by).
fn fitted_on(on: &Experiment<'_>, st: Structure) -> Option<(Estimate, f64)> {
    let (est, e) = on.fit_with_error(st).ok()?;
    let e = e.unwrap_or_else(|| on.fit_error(&est));
    Some((est, e))
}

/// A model whose grid values were chosen on `search`'s runs (or their heads), fitted on the
/// whole fitting runs (when it was chosen on the heads) and scored on the held-out runs.
fn settle(search: &Search<'_>, est: Estimate) -> Option<Scored> {
    let ex = search.ex;
    let est = match search.heads {
        Some(_) => ex.fit_only(est.structure).ok()?,
        None => est,
    };
    ex.score(est).ok()
}

/// The delay added to structure `s`: the best whole delay of the grid, refined to a fraction
/// of a sample between its neighbours ([`DELAY_REFINE`]); at the grid's edge, the whole value
/// with a note (no finding, not refined). On a long log the whole delay is chosen on the
/// fitting runs' heads ([`Search::heads`]) and its fraction on the whole runs: the heads'
/// least squares (a quarter of a 10 kHz log's samples, `diagnose/benches/diagnose.rs`) left
/// the delay a sample short, the whole runs' within a third of one.
fn try_delay(s: Structure, search: &Search<'_>) -> Option<(Scored, Option<String>)> {
    let (ex, grid) = (search.ex, search.delay_grid);
    let at = |d: f64| Structure { delay: d, ..s };
    let whole = super::grid::integer(grid, |d| {
        fitted_on(search.heads.unwrap_or(ex), at(d as f64))
    })?;
    // an edge is no finding and is not refined; inside, the delay is refined to a
    // fraction of a sample between its whole neighbours
    if whole.at_edge(grid, false) {
        let note = format!(
            "delay at the largest value tried ({} samples, {:.4} s; grid edge)",
            whole.at,
            whole.at as f64 * search.dt
        );
        return settle(search, whole.value).map(|r| (r, Some(note)));
    }
    // the whole runs' error at the heads' choice, where the fraction starts from
    let whole = match search.heads {
        Some(_) => {
            let (value, err) = fitted_on(ex, at(whole.at as f64))?;
            super::grid::Best {
                value,
                err,
                ..whole
            }
        }
        None => whole,
    };
    let top = grid.last().map_or(0.0, |&g| g as f64);
    let b = super::grid::fractional(whole, (0.0, top), DELAY_REFINE, |d| fitted_on(ex, at(d)))?;
    ex.score(b.value).ok().map(|r| (r, None))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::drive::experiment::tests::{delayed_carriage, pulses};
    use crane_model::drive::Motion;

    #[test]
    fn a_long_logs_delay_is_chosen_on_the_heads_and_fitted_on_the_whole_runs() {
        let (truth, th) = delayed_carriage();
        let mut held = pulses(&truth, 10_000);
        held.run.held_out = true;
        let runs = [pulses(&truth, 48_000), held];
        let ex = Experiment::new(&runs, th, Motion::Linear, 0.0);
        let heads = ex.heads(6_000).expect("heads of 24,000 samples");
        let short = Experiment::new(&heads, th, Motion::Linear, 0.0);
        let grid = crate::drive::grid::delay_grid(1e-3, 48_000);
        let search = |heads| Search {
            ex: &ex,
            heads,
            umax: 5.0,
            sat_grid: &[],
            stribeck_grid: &[],
            delay_grid: &grid,
            dt: 1e-3,
            bump_guess: &|_| None,
        };
        let plain = Structure {
            delay: 0.0,
            ..truth.structure
        };
        let base = ex.fit_and_score(plain).expect("baseline");
        let delay = |heads| {
            let (r, note) = try_cause(Cause::InputDelay, &base, &search(heads)).expect("tried");
            assert!(note.is_none(), "{note:?}");
            r
        };
        let (on_heads, on_whole) = (delay(Some(&short)), delay(None));
        for r in [&on_heads, &on_whole] {
            let d = r.est.structure.delay;
            assert!((d - 20.0).abs() < 1.0, "{d}");
            assert!(r.selection < 0.5 * base.selection);
        }
        // the model named is the one the whole fitting runs give with that delay
        let refit = ex.fit_only(on_heads.est.structure).expect("fits");
        assert_eq!(refit.params, on_heads.est.params);
        // the heads chose the same whole sample: the fractions agree
        assert_eq!(
            on_heads.est.structure.delay.to_bits(),
            on_whole.est.structure.delay.to_bits()
        );
    }
}

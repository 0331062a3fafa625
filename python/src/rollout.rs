//! Rollouts without Python: one simulator over an input sequence, and many simulators in
//! parallel on rayon. Results are written straight into the arrays handed to numpy.
//!
//! Layout: for a run of `n` steps there are `n + 1` rows (row 0 is the state before the first
//! step). Row `k` holds the state after `k` steps, the modes (-1, 0, 1), and the friction
//! forces [N], rope tension [N] and payload position [m] of that state with the input of the
//! step before it (row 0: the simulator's last input, 0 V for a new one), as the CSV of
//! `crane simulate` does.

use crate::errors::{Failure, Fallible};
use crate::setup::{mode_code, Setup};
use crate::sim::Sim;
use crane_model::StepError;
use rayon::prelude::*;

/// The output arrays of `sims` runs of `n` steps (`n + 1` rows each), row-major.
#[derive(Debug, Default)]
pub struct Tables {
    /// Number of simulations.
    pub sims: usize,
    /// Rows per simulation (`n + 1`).
    pub rows: usize,
    /// Positions `[x, y, L, alpha, beta]` [m, rad], `sims * rows * 5`.
    pub q: Vec<f64>,
    /// Velocities, `sims * rows * 5`.
    pub qd: Vec<f64>,
    /// Modes of X, Y, rope, `sims * rows * 3`.
    pub modes: Vec<i8>,
    /// Friction forces [N], `sims * rows * 3`.
    pub friction: Vec<f64>,
    /// Rope tension [N], `sims * rows`.
    pub tension: Vec<f64>,
    /// Payload position [m], `sims * rows * 3`.
    pub payload: Vec<f64>,
}

/// One simulation's rows of [`Tables`].
struct Rows<'a> {
    q: &'a mut [f64],
    qd: &'a mut [f64],
    modes: &'a mut [i8],
    friction: &'a mut [f64],
    tension: &'a mut [f64],
    payload: &'a mut [f64],
}

/// A zeroed vector of `len` elements, or an error instead of an abort when memory runs out.
fn zeros<T: Copy + Default>(len: Option<usize>) -> Fallible<Vec<T>> {
    let too_big = || {
        Failure::Input("the result does not fit in memory; run fewer steps or simulations".into())
    };
    let len = len.ok_or_else(too_big)?;
    let mut v = Vec::new();
    v.try_reserve_exact(len).map_err(|_| too_big())?;
    v.resize(len, T::default());
    Ok(v)
}

impl Tables {
    /// Zeroed tables; an `InputError` (not an abort) if they cannot be allocated.
    pub fn new(sims: usize, rows: usize) -> Fallible<Self> {
        let r = sims.checked_mul(rows);
        let times = |k: usize| r.and_then(|r| r.checked_mul(k));
        Ok(Tables {
            sims,
            rows,
            q: zeros(times(5))?,
            qd: zeros(times(5))?,
            modes: zeros(times(3))?,
            friction: zeros(times(3))?,
            tension: zeros(r)?,
            payload: zeros(times(3))?,
        })
    }

    fn split(&mut self) -> Vec<Rows<'_>> {
        let r = self.rows.max(1);
        self.q
            .chunks_mut(r * 5)
            .zip(self.qd.chunks_mut(r * 5))
            .zip(self.modes.chunks_mut(r * 3))
            .zip(self.friction.chunks_mut(r * 3))
            .zip(self.tension.chunks_mut(r))
            .zip(self.payload.chunks_mut(r * 3))
            .map(|(((((q, qd), modes), friction), tension), payload)| Rows {
                q,
                qd,
                modes,
                friction,
                tension,
                payload,
            })
            .collect()
    }
}

fn record(sim: &Sim, rows: &mut Rows<'_>, k: usize) -> Result<(), StepError> {
    let crane = sim.crane();
    let s = crane.state();
    let o = crane.output()?;
    rows.q[k * 5..k * 5 + 5].copy_from_slice(&s.q);
    rows.qd[k * 5..k * 5 + 5].copy_from_slice(&s.qd);
    for (dst, m) in rows.modes[k * 3..k * 3 + 3].iter_mut().zip(crane.modes()) {
        *dst = mode_code(m);
    }
    rows.friction[k * 3..k * 3 + 3].copy_from_slice(&o.friction);
    rows.tension[k] = o.tension;
    rows.payload[k * 3..k * 3 + 3].copy_from_slice(&o.payload);
    Ok(())
}

/// Steps `sim` through the inputs `u` (`n` rows of `[u_x, u_y, u_l]` [V], flattened),
/// filling `n + 1` rows; on a rejected step returns its index (the simulator stays at the
/// state before it; rows after it are left as they were).
fn run_rows(sim: &mut Sim, u: &[f64], rows: &mut Rows<'_>) -> Result<(), (usize, StepError)> {
    record(sim, rows, 0).map_err(|e| (0, e))?;
    for (k, uk) in u.chunks_exact(3).enumerate() {
        sim.step([uk[0], uk[1], uk[2]]).map_err(|e| (k, e))?;
        record(sim, rows, k + 1).map_err(|e| (k, e))?;
    }
    Ok(())
}

/// One rollout of `sim` over `u` (`n * 3` values), continuing from its current state.
pub fn rollout(sim: &mut Sim, u: &[f64]) -> Fallible<Tables> {
    let n = u.len() / 3;
    let mut t = Tables::new(1, n + 1)?;
    let mut rows = t.split();
    if let Some(r) = rows.first_mut() {
        run_rows(sim, u, r).map_err(|(step, err)| Failure::Step {
            err,
            step,
            sim: None,
        })?;
    }
    drop(rows);
    Ok(t)
}

/// The inputs of the simulations of a batch: one sequence for all, or one each.
#[derive(Clone, Copy, Debug)]
pub enum Inputs<'a> {
    /// `n * 3` values shared by every simulation.
    Shared(&'a [f64]),
    /// `sims * n * 3` values, simulation-major.
    Each(&'a [f64]),
}

/// Runs every setup over its inputs (`n` steps) in parallel on the current rayon pool.
/// The first failure (lowest simulation index) is returned, naming simulation and step.
pub fn rollouts(setups: &[Setup], inputs: Inputs<'_>, n: usize) -> Fallible<Tables> {
    let mut t = Tables::new(setups.len(), n + 1)?;
    let mut rows = t.split();
    let per = n * 3;
    let result: Result<(), Failure> = rows
        .par_iter_mut()
        .zip(setups.par_iter())
        .enumerate()
        .map(|(i, (r, setup))| {
            let u = match inputs {
                Inputs::Shared(u) => u,
                Inputs::Each(u) => &u[i * per..(i + 1) * per],
            };
            let mut sim = Sim::new(setup.build().map_err(Failure::Param)?);
            run_rows(&mut sim, u, r).map_err(|(step, err)| Failure::Step {
                err,
                step,
                sim: Some(i),
            })
        })
        .collect::<Vec<_>>()
        .into_iter()
        .collect();
    drop(rows);
    result.map(|()| t)
}

//! Sampled trajectories, fixed-step hybrid runs, and the high-accuracy hybrid reference.
//!
//! The reference is the hybrid model itself at a much smaller step (default `h / 100`, 10 us
//! for the 1 ms default), with its located events (velocity zeros, breakaways). Its accuracy
//! is checked by halving that step again: [`convergence`] reports the RMSE and the largest
//! difference of the compared velocity between the two, which must be far below every RMSE
//! that the study reports.

use crate::cases::Case;
use crate::error::{Error, Result};
use crane_model::{Config, Crane, FrictionLaw, Mode, State};
use serde::Serialize;

/// A run sampled on the case's output grid: sample `j` is at grid index `j * stride`, time
/// `j * stride * case.sample`; sample 0 is the initial state.
#[derive(Clone, Debug, Default)]
pub struct Trajectory {
    /// Step of the integrator [s] (0 for adaptive solvers).
    pub h: f64,
    /// Grid indices per sample (1 unless the step is longer than the grid).
    pub stride: usize,
    /// Sampled states.
    pub states: Vec<State<f64>>,
    /// Modes at the samples (hybrid runs only; otherwise empty).
    pub modes: Vec<[Mode; 3]>,
    /// Friction forces [N] at the samples (hybrid runs with outputs recorded; else empty):
    /// the law's force when moving, the holding force when stopped.
    pub friction: Vec<[f64; 3]>,
    /// Accelerations `qdd` at the samples, kept when the step is longer than the grid
    /// (`stride > 1`): the compared velocity between samples is the cubic Hermite interpolant
    /// through the sampled velocities and accelerations.
    pub accel: Vec<[f64; 5]>,
    /// Integration steps taken.
    pub steps: u64,
    /// Events located (hybrid runs).
    pub events: u64,
}

impl Trajectory {
    /// Time [s] of sample `j`.
    pub fn time(&self, case: &Case, j: usize) -> f64 {
        (j * self.stride) as f64 * case.sample
    }

    /// Compared velocity (`qd[case.observed]`) at every sample.
    pub fn velocity(&self, case: &Case) -> Vec<f64> {
        self.states.iter().map(|s| s.qd[case.observed]).collect()
    }

    /// Compared velocity at grid index `g` (time `g * case.sample`): the sample itself, or,
    /// between samples, the cubic Hermite interpolant through the neighbouring samples'
    /// velocities and accelerations. None past the end (or without accelerations).
    pub fn velocity_at_grid(&self, case: &Case, g: usize) -> Option<f64> {
        let i = case.observed;
        let (j, r) = (g / self.stride, g % self.stride);
        if r == 0 {
            return self.states.get(j).map(|s| s.qd[i]);
        }
        let (s0, s1) = (self.states.get(j)?, self.states.get(j + 1)?);
        let (a0, a1) = (self.accel.get(j)?, self.accel.get(j + 1)?);
        let dt = self.stride as f64 * case.sample;
        let th = r as f64 / self.stride as f64;
        let (t2, t3) = (th * th, th * th * th);
        let h00 = 2.0 * t3 - 3.0 * t2 + 1.0;
        let h10 = t3 - 2.0 * t2 + th;
        let h01 = -2.0 * t3 + 3.0 * t2;
        let h11 = t3 - t2;
        Some(h00 * s0.qd[i] + h10 * dt * a0[i] + h01 * s1.qd[i] + h11 * dt * a1[i])
    }

    /// The full state on every grid point (stride 1): the samples themselves, and between
    /// them the cubic Hermite interpolants, positions through the samples' positions and
    /// velocities, velocities through their velocities and accelerations (the interpolant
    /// [`Trajectory::velocity_at_grid`] uses). A fixed-step run with steps longer than the
    /// grid calls this inside its timed run, so that it delivers what an adaptive solver's
    /// dense output delivers there: every component at every grid point. Modes between samples
    /// are those of the sample before. Returns `self` unchanged at stride 1 or without
    /// accelerations.
    pub fn on_grid(self, case: &Case) -> Trajectory {
        if self.stride <= 1 || self.accel.len() != self.states.len() {
            return self;
        }
        let per = self.stride;
        let n = self.grid_len();
        let dt = per as f64 * case.sample;
        // Hermite basis at the `per - 1` interior points, the same for every interval.
        let basis: Vec<[f64; 4]> = (1..per)
            .map(|r| {
                let th = r as f64 / per as f64;
                let (t2, t3) = (th * th, th * th * th);
                [
                    2.0 * t3 - 3.0 * t2 + 1.0,
                    (t3 - 2.0 * t2 + th) * dt,
                    -2.0 * t3 + 3.0 * t2,
                    (t3 - t2) * dt,
                ]
            })
            .collect();
        let mut states = Vec::with_capacity(n + 1);
        let mut modes = Vec::with_capacity(if self.modes.is_empty() { 0 } else { n + 1 });
        for (j, pair) in self.states.windows(2).enumerate() {
            let (s0, s1) = (&pair[0], &pair[1]);
            let (a0, a1) = (&self.accel[j], &self.accel[j + 1]);
            states.push(*s0);
            if let Some(m) = self.modes.get(j) {
                modes.push(*m);
            }
            for b in &basis {
                let mut s = *s0;
                for i in 0..5 {
                    s.q[i] = b[0] * s0.q[i] + b[1] * s0.qd[i] + b[2] * s1.q[i] + b[3] * s1.qd[i];
                    s.qd[i] = b[0] * s0.qd[i] + b[1] * a0[i] + b[2] * s1.qd[i] + b[3] * a1[i];
                }
                states.push(s);
                if let Some(m) = self.modes.get(j) {
                    modes.push(*m);
                }
            }
        }
        if let Some(last) = self.states.last() {
            states.push(*last);
        }
        if let Some(m) = self.modes.last() {
            modes.push(*m);
        }
        Trajectory {
            stride: 1,
            states,
            modes,
            accel: Vec::new(),
            friction: Vec::new(),
            ..self
        }
    }

    /// Number of grid points covered (after `t = 0`).
    pub fn grid_len(&self) -> usize {
        self.states.len().saturating_sub(1) * self.stride
    }
}

/// Differences of the compared velocity between `run` and `reference` (stride 1) at every
/// grid point after `t = 0` that both cover.
fn diffs<'a>(
    case: &'a Case,
    run: &'a Trajectory,
    reference: &'a Trajectory,
) -> impl Iterator<Item = f64> + 'a {
    (1..=run.grid_len()).filter_map(move |g| {
        let v = run.velocity_at_grid(case, g)?;
        let r = reference.states.get(g)?.qd[case.observed];
        Some(v - r)
    })
}

/// Root mean square difference of the compared velocity between `run` and `reference`
/// (stride 1) on the output grid after `t = 0`; a run with a step longer than the grid is
/// interpolated (see [`Trajectory::velocity_at_grid`]), so it is judged on every grid point.
pub fn rmse(case: &Case, run: &Trajectory, reference: &Trajectory) -> f64 {
    let (mut s, mut n) = (0.0, 0usize);
    for d in diffs(case, run, reference) {
        s += d * d;
        n += 1;
    }
    if n == 0 {
        return f64::NAN;
    }
    (s / n as f64).sqrt()
}

/// Largest absolute difference of the compared velocity (same points as [`rmse`]).
pub fn max_diff(case: &Case, run: &Trajectory, reference: &Trajectory) -> f64 {
    diffs(case, run, reference).fold(0.0, |m, d| m.max(d.abs()))
}

/// Sampling plan of a fixed step `h` on the grid `sample`: (steps per sample, grid stride).
pub fn plan(h: f64, sample: f64) -> Result<(usize, usize)> {
    let ratio = sample / h;
    if ratio >= 1.0 {
        let k = ratio.round();
        if (ratio - k).abs() > 1e-9 * k {
            return Err(Error::Grid {
                h,
                sample,
                why: "does not divide",
            });
        }
        Ok((k as usize, 1))
    } else {
        let k = (h / sample).round();
        if (h / sample - k).abs() > 1e-9 * k {
            return Err(Error::Grid {
                h,
                sample,
                why: "is not a multiple of",
            });
        }
        Ok((1, k as usize))
    }
}

/// The hybrid model of `case` at fixed step `h`, sampled on the case's grid. With `outputs`,
/// the friction forces are recorded too (one extra evaluation per sample).
pub fn hybrid(case: &Case, h: f64, outputs: bool) -> Result<Trajectory> {
    let (per, stride) = plan(h, case.sample)?;
    let mut crane: Crane = Crane::new(
        &case.params,
        Config {
            h,
            law: FrictionLaw::Hybrid,
        },
        case.init,
    )
    .map_err(|error| Error::Setup {
        what: "hybrid model of the case",
        error,
    })?;
    let n_steps = (case.duration / h).round() as usize;
    let n_samples = n_steps / per;
    let mut tr = Trajectory {
        h,
        stride,
        states: Vec::with_capacity(n_samples + 1),
        modes: Vec::with_capacity(n_samples + 1),
        ..Trajectory::default()
    };
    // Steps longer than the grid keep the accelerations for the interpolant (one more
    // evaluation per step, counted in the run's time).
    let dense = stride > 1;
    let record = |c: &Crane, tr: &mut Trajectory| -> Result<()> {
        tr.states.push(c.state());
        tr.modes.push(c.modes());
        if outputs || dense {
            let o = c.output().map_err(|error| Error::Step {
                what: "hybrid model output",
                t: c.time(),
                error,
            })?;
            if outputs {
                tr.friction.push(o.friction);
            }
            if dense {
                tr.accel.push(o.qdd);
            }
        }
        Ok(())
    };
    record(&crane, &mut tr)?;
    for n in 0..n_steps {
        let t = n as f64 * h;
        let rep = crane.step(case.u_step(t, h)).map_err(|error| Error::Step {
            what: "hybrid model",
            t,
            error,
        })?;
        tr.events += u64::from(rep.events);
        if (n + 1) % per == 0 {
            record(&crane, &mut tr)?;
        }
    }
    tr.steps = n_steps as u64;
    Ok(tr)
}

/// The reference: the hybrid model at step `h / div`.
pub fn reference(case: &Case, h: f64, div: usize) -> Result<Trajectory> {
    hybrid(case, h / div as f64, false)
}

/// How well the reference has converged: the reference at `h_ref` against the same model at
/// `h_ref / 2`.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Convergence {
    /// Reference step [s].
    pub h_ref: f64,
    /// Check step [s] (`h_ref / 2`).
    pub h_check: f64,
    /// RMSE of the compared velocity between the two [m/s].
    pub rmse: f64,
    /// Largest difference of the compared velocity [m/s].
    pub max_diff: f64,
}

/// Runs the check of the reference `reference` (taken at `h_ref`).
pub fn convergence(case: &Case, reference: &Trajectory) -> Result<Convergence> {
    let h_check = reference.h / 2.0;
    let fine = hybrid(case, h_check, false)?;
    Ok(Convergence {
        h_ref: reference.h,
        h_check,
        rmse: rmse(case, reference, &fine),
        max_diff: max_diff(case, reference, &fine),
    })
}

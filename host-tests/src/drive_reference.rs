//! Independent reference of the single-axis drive (f64, `std`).
//!
//! Written from `model/NUMERICS.md`, section "Single-axis drive", not from the model's code:
//! plain data, one expression per line of the contract, in its operation order, so that
//! `crane_model::Drive<f64>` must reproduce it bit for bit. It does not validate parameters
//! (the model does; the tests only give it valid ones).
//!
//! Units: position m or rad, force N or N m, inertia kg or kg m^2, time s. Positive velocity
//! is increasing position; friction magnitudes are >= 0. The optional Stribeck velocity `vs`
//! and load friction `mu` (0: off) follow the contract's "Friction of a moving axis" and
//! "Friction levels of a step"; the optional bump `(xc, w, a)` (none, or `a = 0`: off) its
//! "Friction levels at a position".

// Spelled like the contract's pseudo-code.
#![allow(clippy::assign_op_pattern, clippy::manual_clamp)]

/// Segments per step (contract's `B`).
pub const SEGMENTS: usize = 8;
/// Bisection iterations of the event location.
pub const ITERATIONS: usize = 30;
/// Delay line capacity in steps.
pub const DELAY_CAPACITY: usize = 64;

/// Mode of the axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DriveMode {
    /// Moving, `v < 0`.
    Negative,
    /// Stuck: `v = 0`, `a = 0`.
    Stopped,
    /// Moving, `v > 0`.
    Positive,
}

/// Position-dependent force.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RefPositionForce {
    /// `P(x) = 0`.
    None,
    /// `P(x) = k * (x - x0)`.
    Spring {
        /// `k` [N/m or N m/rad].
        k: f64,
        /// `x0` [m or rad].
        x0: f64,
    },
    /// `P(x) = k * sin(x - x0)`.
    Pendulum {
        /// `k` [N/m or N m/rad].
        k: f64,
        /// `x0` [m or rad].
        x0: f64,
    },
}

/// The localised friction bump of the contract: `a * (1 - s^2)^2` for `|s| < 1`,
/// `s = (x - xc) / w`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RefBump {
    /// Centre `xc` [m or rad].
    pub xc: f64,
    /// Half-width `w` [m or rad] (> 0).
    pub w: f64,
    /// Amplitude `a` [N or N m].
    pub a: f64,
}

/// Parameters, named as in the contract.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RefDriveParams {
    /// Inertia `I`.
    pub i: f64,
    /// Gain `K`.
    pub k: f64,
    /// Viscous, positive direction `Dp`.
    pub dp: f64,
    /// Viscous, negative direction `Dn`.
    pub dn: f64,
    /// Kinetic, positive `Cp`.
    pub cp: f64,
    /// Kinetic, negative `Cn`.
    pub cn: f64,
    /// Breakaway, positive `Bp`.
    pub bp: f64,
    /// Breakaway, negative `Bn`.
    pub bn: f64,
    /// Offset `b`.
    pub b: f64,
    /// Position force `P`.
    pub p: RefPositionForce,
    /// Dead band `d`.
    pub d: f64,
    /// Delay `n` [steps].
    pub n: usize,
    /// Lower end stop.
    pub min: f64,
    /// Upper end stop.
    pub max: f64,
    /// Stribeck velocity `vs` (0: none).
    pub vs: f64,
    /// Load friction coefficient `mu` (0: none).
    pub mu: f64,
    /// Localised friction bump (`None`: none).
    pub bump: Option<RefBump>,
}

/// The dry friction levels of one step: `Cp'`, `Cn'`, `Bp'`, `Bn'` of the contract (the
/// parameters' own without load friction), or those at a position (`Cp''`... with the bump).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Levels {
    /// `Cp'`.
    pub cp: f64,
    /// `Cn'`.
    pub cn: f64,
    /// `Bp'`.
    pub bp: f64,
    /// `Bn'`.
    pub bn: f64,
}

/// Why the reference rejected a step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RefDriveError {
    /// `u` not finite.
    InputNotFinite,
    /// `F` not finite.
    ForceNotFinite,
    /// Result not finite.
    NonFinite,
}

/// Counts of one step.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RefDriveInfo {
    /// Located events.
    pub events: u32,
    /// Late resets.
    pub late_resets: u32,
}

/// The reference simulator.
#[derive(Clone, Debug)]
pub struct RefDrive {
    /// Parameters.
    pub prm: RefDriveParams,
    /// Step [s].
    pub h: f64,
    /// Position.
    pub x: f64,
    /// Velocity.
    pub v: f64,
    /// Mode.
    pub mode: DriveMode,
    /// Accepted steps.
    pub n_steps: u64,
    /// Applied force of the last accepted step.
    pub f_last: f64,
    /// Drive effort `Fd` of the last accepted step.
    pub fd_last: f64,
    /// All accepted inputs, oldest first (a plain history instead of a ring).
    pub history: Vec<f64>,
}

/// `P(x)`.
pub fn position_force(p: &RefPositionForce, x: f64) -> f64 {
    match *p {
        RefPositionForce::None => 0.0,
        RefPositionForce::Spring { k, x0 } => k * (x - x0),
        RefPositionForce::Pendulum { k, x0 } => k * libm::sin(x - x0),
    }
}

/// Dead band of the contract.
pub fn dead_band(u: f64, d: f64) -> f64 {
    if u > d {
        u - d
    } else if u < -d {
        u + d
    } else {
        0.0
    }
}

fn hermite(th: f64, y0: f64, y1: f64, m0: f64, m1: f64) -> f64 {
    let t2 = th * th;
    let t3 = t2 * th;
    let h00 = 2.0 * t3 - 3.0 * t2 + 1.0;
    let h10 = t3 - 2.0 * t2 + th;
    let h01 = -2.0 * t3 + 3.0 * t2;
    let h11 = t3 - t2;
    h00 * y0 + h10 * m0 + h01 * y1 + h11 * m1
}

/// Bisection: `event(mid)` true means the event happened by `mid`.
fn locate(event: impl Fn(f64) -> bool) -> f64 {
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    for _ in 0..ITERATIONS {
        let mid = 0.5 * (lo + hi);
        if !event(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    hi
}

fn clamp(x: f64, min: f64, max: f64) -> f64 {
    if x > max {
        max
    } else if x < min {
        min
    } else {
        x
    }
}

impl RefDrive {
    /// Starts at `(x0, 0.0)`; `None` if `x0` is outside the stops or not finite.
    pub fn new(prm: RefDriveParams, h: f64, x0: f64) -> Option<Self> {
        let mut r = RefDrive {
            prm,
            h,
            x: 0.0,
            v: 0.0,
            mode: DriveMode::Stopped,
            n_steps: 0,
            f_last: 0.0,
            fd_last: 0.0,
            history: Vec::new(),
        };
        if r.set_state(x0, 0.0) {
            Some(r)
        } else {
            None
        }
    }

    /// The contract's `set_state`; `false` (nothing changed) if rejected.
    pub fn set_state(&mut self, x: f64, v: f64) -> bool {
        if !x.is_finite() || !v.is_finite() || x < self.prm.min || x > self.prm.max {
            return false;
        }
        let mut v = v;
        if x >= self.prm.max && v > 0.0 {
            v = 0.0;
        }
        if x <= self.prm.min && v < 0.0 {
            v = 0.0;
        }
        self.mode = if v > 0.0 {
            DriveMode::Positive
        } else if v < 0.0 {
            DriveMode::Negative
        } else {
            DriveMode::Stopped
        };
        self.x = x;
        self.v = v;
        true
    }

    /// Simulated time.
    pub fn time(&self) -> f64 {
        self.n_steps as f64 * self.h
    }

    fn hold(&self, x: f64, f: f64) -> f64 {
        f - position_force(&self.prm.p, x)
    }

    /// The contract's levels for the drive effort `fd`.
    pub fn levels(&self, fd: f64) -> Levels {
        let p = &self.prm;
        if p.mu > 0.0 {
            let a = if fd < 0.0 { -fd } else { fd };
            let l = p.mu * a;
            Levels {
                cp: p.cp + l,
                cn: p.cn + l,
                bp: p.bp + l,
                bn: p.bn + l,
            }
        } else {
            Levels {
                cp: p.cp,
                cn: p.cn,
                bp: p.bp,
                bn: p.bn,
            }
        }
    }

    /// The contract's levels at position `x` from the step's levels `lv`: with a bump of
    /// non-zero amplitude and `-1 < s < 1`, each level plus `bx = (a * t) * t`,
    /// `t = 1 - s * s`, `s = (x - xc) / w`; else `lv` itself.
    pub fn levels_at(&self, lv: &Levels, x: f64) -> Levels {
        let Some(bump) = self.prm.bump else {
            return *lv;
        };
        if bump.a == 0.0 {
            return *lv;
        }
        let s = (x - bump.xc) / bump.w;
        if !(s > -1.0 && s < 1.0) {
            return *lv;
        }
        let t = 1.0 - s * s;
        let bx = bump.a * t * t;
        Levels {
            cp: lv.cp + bx,
            cn: lv.cn + bx,
            bp: lv.bp + bx,
            bn: lv.bn + bx,
        }
    }

    /// Friction `f` of an axis moving at `(x, v)` (contract: `Sp + Dp*v` / `-Sn + Dn*v`, with
    /// the levels at `x`).
    fn friction(&self, lv: &Levels, mode: DriveMode, x: f64, v: f64) -> f64 {
        let lv = &self.levels_at(lv, x);
        let vs = self.prm.vs;
        // S = C' + (B' - C') * exp(-(r*r)), r = v / vs; S = C' without Stribeck.
        let stribeck = |c: f64, b: f64| -> f64 {
            if vs > 0.0 {
                let r = v / vs;
                let g = libm::exp(-(r * r));
                c + (b - c) * g
            } else {
                c
            }
        };
        match mode {
            DriveMode::Stopped => 0.0,
            DriveMode::Positive => stribeck(lv.cp, lv.bp) + self.prm.dp * v,
            DriveMode::Negative => -stribeck(lv.cn, lv.bn) + self.prm.dn * v,
        }
    }

    fn acc(&self, lv: &Levels, x: f64, v: f64, mode: DriveMode, f: f64) -> f64 {
        if mode == DriveMode::Stopped {
            return 0.0;
        }
        let fr = self.friction(lv, mode, x, v);
        (self.hold(x, f) - fr) / self.prm.i
    }

    fn resolve(&self, lv: &Levels, x: f64, v: f64, mode: DriveMode, f: f64) -> (DriveMode, f64) {
        if mode != DriveMode::Stopped {
            return (mode, self.acc(lv, x, v, mode, f));
        }
        let h = self.hold(x, f);
        let at = self.levels_at(lv, x);
        let up = if x < self.prm.max {
            Some(h - at.bp)
        } else {
            None
        };
        let down = if x > self.prm.min {
            Some(-at.bn - h)
        } else {
            None
        };
        let up_candidate = match up {
            Some(m) if m > 0.0 => Some(m),
            _ => None,
        };
        let dir = match (up_candidate, down) {
            (Some(u), Some(dn)) if dn > u => Some(DriveMode::Negative),
            (Some(_), _) => Some(DriveMode::Positive),
            (None, Some(dn)) if dn > 0.0 => Some(DriveMode::Negative),
            _ => None,
        };
        let Some(dir) = dir else {
            return (DriveMode::Stopped, 0.0);
        };
        let a = self.acc(lv, x, v, dir, f);
        let ok = if dir == DriveMode::Positive {
            a > 0.0
        } else {
            a < 0.0
        };
        if ok {
            (dir, a)
        } else {
            (DriveMode::Stopped, 0.0)
        }
    }

    /// RK4 over `tau`: `(xn, vn, a4)`.
    #[allow(clippy::too_many_arguments)]
    fn rk4(
        &self,
        lv: &Levels,
        x: f64,
        v: f64,
        a1: f64,
        mode: DriveMode,
        f: f64,
        tau: f64,
    ) -> [f64; 3] {
        let half = tau * 0.5;
        let x2 = x + half * v;
        let v2 = v + half * a1;
        let a2 = self.acc(lv, x2, v2, mode, f);
        let x3 = x + half * v2;
        let v3 = v + half * a2;
        let a3 = self.acc(lv, x3, v3, mode, f);
        let x4 = x + tau * v3;
        let v4 = v + tau * a3;
        let a4 = self.acc(lv, x4, v4, mode, f);
        let w = tau / 6.0;
        let xn = x + w * (((v + 2.0 * v2) + 2.0 * v3) + v4);
        let vn = v + w * (((a1 + 2.0 * a2) + 2.0 * a3) + a4);
        [xn, vn, a4]
    }

    /// The contract's step.
    pub fn step(&mut self, u: f64) -> Result<RefDriveInfo, RefDriveError> {
        if !u.is_finite() {
            return Err(RefDriveError::InputNotFinite);
        }
        let un = if self.prm.n == 0 {
            u
        } else if self.history.len() >= self.prm.n {
            self.history[self.history.len() - self.prm.n]
        } else {
            0.0
        };
        let fd = self.prm.k * dead_band(un, self.prm.d);
        let f = fd + self.prm.b;
        if !f.is_finite() {
            return Err(RefDriveError::ForceNotFinite);
        }
        let lv = self.levels(fd);
        let (min, max) = (self.prm.min, self.prm.max);
        let mut info = RefDriveInfo::default();
        let (mut x, mut v) = (self.x, self.v);
        let (mut mode, mut a1) = self.resolve(&lv, x, v, self.mode, f);
        let mut done = 0.0;
        for seg in 0..SEGMENTS {
            if mode == DriveMode::Stopped {
                break;
            }
            let tau = self.h - done;
            let [xn, vn, a4] = self.rk4(&lv, x, v, a1, mode, f, tau);
            if seg == SEGMENTS - 1 {
                x = xn;
                v = vn;
                break;
            }
            let positive = mode == DriveMode::Positive;
            let vel_event = |vv: f64| if positive { vv <= 0.0 } else { vv >= 0.0 };
            let lim_event = |xx: f64| if positive { xx >= max } else { xx <= min };
            let theta_v = if vel_event(vn) {
                let (m0, m1) = (tau * a1, tau * a4);
                Some(locate(|th| vel_event(hermite(th, v, vn, m0, m1))))
            } else {
                None
            };
            let theta_l = if lim_event(xn) {
                let (m0, m1) = (tau * v, tau * vn);
                Some(locate(|th| lim_event(hermite(th, x, xn, m0, m1))))
            } else {
                None
            };
            let (theta, at_limit) = match (theta_v, theta_l) {
                (None, None) => {
                    x = xn;
                    v = vn;
                    break;
                }
                (Some(tv), Some(tl)) => {
                    if tl < tv {
                        (tl, true)
                    } else {
                        (tv, false)
                    }
                }
                (Some(tv), None) => (tv, false),
                (None, Some(tl)) => (tl, true),
            };
            let s = theta * tau;
            let [xe, _, _] = self.rk4(&lv, x, v, a1, mode, f, s);
            x = if !at_limit {
                clamp(xe, min, max)
            } else if positive {
                max
            } else {
                min
            };
            v = 0.0;
            info.events += 1;
            done = done + s;
            let r = self.resolve(&lv, x, 0.0, DriveMode::Stopped, f);
            mode = r.0;
            a1 = r.1;
            if done >= self.h {
                break;
            }
        }
        match mode {
            DriveMode::Positive if x >= max => {
                x = max;
                v = 0.0;
                mode = DriveMode::Stopped;
                info.late_resets += 1;
            }
            DriveMode::Negative if x <= min => {
                x = min;
                v = 0.0;
                mode = DriveMode::Stopped;
                info.late_resets += 1;
            }
            DriveMode::Positive | DriveMode::Negative
                if (mode == DriveMode::Positive && v <= 0.0)
                    || (mode == DriveMode::Negative && v >= 0.0) =>
            {
                x = clamp(x, min, max);
                v = 0.0;
                mode = DriveMode::Stopped;
                info.late_resets += 1;
            }
            _ => {}
        }
        if !x.is_finite() || !v.is_finite() {
            return Err(RefDriveError::NonFinite);
        }
        self.x = x;
        self.v = v;
        self.mode = mode;
        self.f_last = f;
        self.fd_last = fd;
        self.history.push(u);
        self.n_steps += 1;
        Ok(info)
    }

    /// `(acceleration, friction, position force, applied force)` at the current state.
    pub fn output(&self) -> [f64; 4] {
        let p = position_force(&self.prm.p, self.x);
        let lv = self.levels(self.fd_last);
        let fr = match self.mode {
            DriveMode::Stopped => self.f_last - p,
            m => self.friction(&lv, m, self.x, self.v),
        };
        [
            self.acc(&lv, self.x, self.v, self.mode, self.f_last),
            fr,
            p,
            self.f_last,
        ]
    }
}

"""Independent single-axis plant for the `crane diagnose` stranger sweep.

Written from the physics specification in README.md only (no code of the tool was read).

State: position x (m or rad), velocity v. Effort

    Fa(t) = gain * D(S(u(t - delay)))        (S: clamp to +-usat, D: dead band dz)
    F(t)  = Fa(t) + offset

Restoring force R(x) = k_lin (x - center) + k_sin sin(x - center).
Friction while moving with s = sign(v) (per-direction parameters picked by s):

    Ff = s [Fc_s + (Fs_s - Fc_s) exp(-(|v|/vs)^2) + mu |Fa| + bump(x)] + Dv_s v
    bump(x) = A exp(-((x - xc)/w)^2 / 2)

(vs = 0: classical stiction, the static level only holds an axis at rest.)

Exact sticking: at v = 0 the axis stays while
    -(Fs_- + mu|Fa| + bump) <= H = F - R(x) <= Fs_+ + mu|Fa| + bump
and breaks away in the direction of H otherwise. A moving axis whose velocity crosses zero stops
at the crossing (located inside the step: cubic Hermite root of v, then an RK4 step to it), and
the stick test is re-evaluated there for the rest of the step.

The integrator is a fixed-step RK4 with the direction frozen over a step (the friction law is
smooth for a fixed direction, so the continuation past v = 0 is smooth and the root is well
defined). Many lanes (runs x plant variants) are integrated in lock-step with numpy; each lane
has its own step h = T_cmd / n_sub, the input is zero-order held between command updates (every
T_cmd) and the delay is rounded to a whole number of internal steps (recorded in the truth).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

# Internal step target and minimum sub-steps per command/log period (see README.md).
H_TARGET = 0.4e-3
MIN_SUB_SYNC = 2
MIN_SUB_ASYNC = 4


@dataclass
class Plant:
    J: float = 1.0
    gain: float = 1.0  # effort per input unit (physical; the tool may or may not be told)
    offset: float = 0.0  # constant effort added after the gain
    usat: float = math.inf  # input saturation [input units]
    dz: float = 0.0  # dead band [input units]
    delay: float = 0.0  # input delay [s]
    k_lin: float = 0.0  # linear spring [effort / position unit]
    k_sin: float = 0.0  # gravity-like k sin(x - center) [effort]
    center: float = 0.0
    Fc_p: float = 0.0
    Fc_n: float = 0.0
    Fs_p: float = 0.0
    Fs_n: float = 0.0
    vs: float = 0.0  # Stribeck velocity; 0 = classical stiction
    Dv_p: float = 0.0
    Dv_n: float = 0.0
    mu: float = 0.0
    bump_A: float = 0.0
    bump_c: float = 0.0
    bump_w: float = 1.0

    def replace(self, **kw) -> "Plant":
        return dataclasses.replace(self, **kw)

    def effort(self, u):
        """Fa = gain * D(S(u)) (before the offset)."""
        u = np.asarray(u, dtype=float)
        us = np.clip(u, -self.usat, self.usat)
        ud = np.sign(us) * np.maximum(np.abs(us) - self.dz, 0.0)
        return self.gain * ud

    def restoring(self, x):
        x = np.asarray(x, dtype=float)
        return self.k_lin * (x - self.center) + self.k_sin * np.sin(x - self.center)

    def bump(self, x):
        x = np.asarray(x, dtype=float)
        return self.bump_A * np.exp(-0.5 * ((x - self.bump_c) / self.bump_w) ** 2)

    def friction(self, x, v, Fa=0.0):
        """Friction force of a moving axis (v != 0), the law of the module docstring."""
        x = np.asarray(x, dtype=float)
        v = np.asarray(v, dtype=float)
        s = np.sign(v)
        pos = s > 0
        Fc = np.where(pos, self.Fc_p, self.Fc_n)
        Fs = np.where(pos, self.Fs_p, self.Fs_n)
        Dv = np.where(pos, self.Dv_p, self.Dv_n)
        strib = (Fs - Fc) * np.exp(-((v / self.vs) ** 2)) if self.vs > 0 else 0.0
        return s * (Fc + strib + self.mu * np.abs(Fa) + self.bump(x)) + Dv * v

    def to_dict(self):
        d = dataclasses.asdict(self)
        for k, v in d.items():
            if isinstance(v, float) and not math.isfinite(v):
                d[k] = None  # JSON: no saturation
        return d


_LANE_FIELDS = [f.name for f in dataclasses.fields(Plant)]


@dataclass
class Lane:
    """One simulation: a plant, its command sequence and the stamps at which x is recorded."""

    plant: Plant
    cmd: np.ndarray  # commanded input, zero-order held over [j T, (j+1) T)
    T: float  # command update period [s]
    stamps: np.ndarray  # times [s] at which x is recorded (within [0, len(cmd) T])
    n_sub: int = 0  # internal steps per command period (0: automatic)
    x0: float = 0.0
    out_x: np.ndarray | None = field(default=None, repr=False)
    h: float = 0.0
    delay_steps: int = 0


def auto_nsub(T: float, async_stamps: bool) -> int:
    n = max(1, math.ceil(T / H_TARGET - 1e-9))
    return max(n, MIN_SUB_ASYNC if async_stamps else MIN_SUB_SYNC)


def simulate(lanes: list[Lane], compact_every: int = 2000) -> list[np.ndarray]:
    """Integrate every lane; returns (and stores in lane.out_x) x at each lane's stamps."""
    n = len(lanes)
    if n == 0:
        return []
    for ln in lanes:
        if ln.n_sub <= 0:
            sp = np.diff(ln.stamps)
            regular = len(sp) == 0 or np.allclose(sp, ln.T, rtol=1e-9, atol=0)
            ln.n_sub = auto_nsub(ln.T, not regular)
        ln.h = ln.T / ln.n_sub
        ln.delay_steps = int(round(ln.plant.delay / ln.h))
        if len(ln.stamps) > 1:
            assert np.min(np.diff(ln.stamps)) > ln.h * (1 + 1e-9), "two stamps in one step"

    P = {f: np.array([getattr(ln.plant, f) for ln in lanes], dtype=float) for f in _LANE_FIELDS}
    P["h"] = np.array([ln.h for ln in lanes])
    P["nsub"] = np.array([ln.n_sub for ln in lanes], dtype=np.int64)
    P["dsteps"] = np.array([ln.delay_steps for ln in lanes], dtype=np.int64)
    lens = np.array([len(ln.cmd) for ln in lanes], dtype=np.int64)
    P["clen"] = lens
    P["coff"] = np.concatenate([[0], np.cumsum(lens)[:-1]]).astype(np.int64)
    flat_cmd = np.concatenate([np.asarray(ln.cmd, dtype=float) for ln in lanes])
    nst = np.array([len(ln.stamps) for ln in lanes], dtype=np.int64)
    P["soff"] = np.concatenate([[0], np.cumsum(nst)[:-1]]).astype(np.int64)
    P["nst"] = nst
    # stamps in units of internal steps
    flat_s = np.concatenate([np.asarray(ln.stamps, dtype=float) / ln.h for ln in lanes])
    flat_out = np.full(len(flat_s), np.nan)
    nsteps = np.array([len(ln.cmd) * ln.n_sub for ln in lanes], dtype=np.int64)
    P["nsteps"] = nsteps
    P["lane"] = np.arange(n)
    # derived constants
    P["vs_e"] = np.where(P["vs"] > 0, P["vs"], 1.0)
    P["bw"] = np.where(P["bump_w"] > 0, P["bump_w"], 1.0)
    P["usat"] = np.where(np.isfinite(P["usat"]), P["usat"], 1e300)

    x = np.array([ln.x0 for ln in lanes], dtype=float)
    v = np.zeros(n)
    stuck = np.ones(n, dtype=bool)
    sdir = np.ones(n)
    ptr = np.zeros(n, dtype=np.int64)  # next stamp index per lane

    def record(k, xa, xb, S):
        """Stamps in (k, k+1] (or <= 0 at k = -1) get x interpolated between xa and xb."""
        nonlocal ptr
        has = ptr < S["nst"]
        if not has.any():
            return
        pi = np.minimum(ptr, S["nst"] - 1)
        sv = flat_s[S["soff"] + pi]
        hit = has & (sv <= k + 1 + 1e-9)
        if not hit.any():
            return
        frac = np.clip(sv - k, 0.0, 1.0)
        val = xa + (xb - xa) * frac
        idx = (S["soff"] + pi)[hit]
        flat_out[idx] = val[hit]
        ptr = ptr + hit

    S = P
    record(-1, x, x, S)

    def accel(xx, vv, F, L, Fc, dS, Dv, s, S):
        R = S["k_lin"] * (xx - S["center"]) + S["k_sin"] * np.sin(xx - S["center"])
        B = S["bump_A"] * np.exp(-0.5 * ((xx - S["bump_c"]) / S["bw"]) ** 2)
        w = vv / S["vs_e"]
        Ff = s * (Fc + dS * np.exp(-w * w) + L + B) + Dv * vv
        return (F - R - Ff) / S["J"]

    def rk4(xx, vv, hh, F, L, Fc, dS, Dv, s, S):
        a1 = accel(xx, vv, F, L, Fc, dS, Dv, s, S)
        h2 = 0.5 * hh
        x2 = xx + h2 * vv
        v2 = vv + h2 * a1
        a2 = accel(x2, v2, F, L, Fc, dS, Dv, s, S)
        x3 = xx + h2 * v2
        v3 = vv + h2 * a2
        a3 = accel(x3, v3, F, L, Fc, dS, Dv, s, S)
        x4 = xx + hh * v3
        v4 = vv + hh * a3
        a4 = accel(x4, v4, F, L, Fc, dS, Dv, s, S)
        xn = xx + hh / 6.0 * (vv + 2 * v2 + 2 * v3 + v4)
        vn = vv + hh / 6.0 * (a1 + 2 * a2 + 2 * a3 + a4)
        return xn, vn, a1

    def dir_params(s, S):
        pos = s > 0
        Fc = np.where(pos, S["Fc_p"], S["Fc_n"])
        Fs = np.where(pos, S["Fs_p"], S["Fs_n"])
        dS = np.where(S["vs"] > 0, Fs - Fc, 0.0)
        Dv = np.where(pos, S["Dv_p"], S["Dv_n"])
        return Fc, dS, Dv

    def stick_test(xx, H, L, S):
        B = S["bump_A"] * np.exp(-0.5 * ((xx - S["bump_c"]) / S["bw"]) ** 2)
        up = S["Fs_p"] + L + B
        lo = -(S["Fs_n"] + L + B)
        return (H > up) | (H < lo)

    def sub(S, m):
        return {k: val[m] for k, val in S.items()}

    kmax = int(nsteps.max())
    for k in range(kmax):
        if k % compact_every == 0 and k > 0:
            keep = S["nsteps"] > k
            keep &= ptr < S["nst"]
            if not keep.all():
                S = sub(S, keep)
                x, v, stuck, sdir, ptr = x[keep], v[keep], stuck[keep], sdir[keep], ptr[keep]
                if len(x) == 0:
                    break
        # input at this step (zero-order hold, delayed, zero before the run)
        ci = (k - S["dsteps"]) // S["nsub"]
        before = ci < 0
        ci = np.clip(ci, 0, S["clen"] - 1)
        u = np.where(before, 0.0, flat_cmd[S["coff"] + ci])
        us = np.clip(u, -S["usat"], S["usat"])
        ud = np.sign(us) * np.maximum(np.abs(us) - S["dz"], 0.0)
        Fa = S["gain"] * ud
        F = Fa + S["offset"]
        L = S["mu"] * np.abs(Fa)
        h = S["h"]

        # stuck lanes: break away?
        if stuck.any():
            R0 = S["k_lin"] * (x - S["center"]) + S["k_sin"] * np.sin(x - S["center"])
            H0 = F - R0
            brk = stuck & stick_test(x, H0, L, S)
            if brk.any():
                sdir = np.where(brk, np.sign(H0), sdir)
                stuck = stuck & ~brk
        x_old = x
        if (~stuck).any():
            Fc, dS, Dv = dir_params(sdir, S)
            xn, vn, a1 = rk4(x, v, h, F, L, Fc, dS, Dv, sdir, S)
            xn = np.where(stuck, x, xn)
            vn = np.where(stuck, 0.0, vn)
            cross = (~stuck) & (sdir * vn <= 0.0)
            if cross.any():
                ii = np.flatnonzero(cross)
                Si = sub(S, ii)
                s_i = sdir[ii]
                Fi, Li, hi = F[ii], L[ii], h[ii]
                Fci, dSi, Dvi = Fc[ii], dS[ii], Dv[ii]
                v0, a0, v1 = v[ii], a1[ii], vn[ii]
                a_end = accel(xn[ii], v1, Fi, Li, Fci, dSi, Dvi, s_i, Si)
                # cubic Hermite v(th) on [0, 1]; root by Newton from the linear guess
                p0, m0, p1, m1 = s_i * v0, s_i * a0 * hi, s_i * v1, s_i * a_end * hi
                den = p0 - p1
                th = np.clip(np.where(den > 0, p0 / np.where(den > 0, den, 1.0), 1.0), 0.0, 1.0)
                for _ in range(4):
                    t2, t3 = th * th, th * th * th
                    val = (
                        (2 * t3 - 3 * t2 + 1) * p0
                        + (t3 - 2 * t2 + th) * m0
                        + (-2 * t3 + 3 * t2) * p1
                        + (t3 - t2) * m1
                    )
                    der = (
                        (6 * t2 - 6 * th) * p0
                        + (3 * t2 - 4 * th + 1) * m0
                        + (-6 * t2 + 6 * th) * p1
                        + (3 * t2 - 2 * th) * m1
                    )
                    ok = der < -1e-300
                    th = np.clip(np.where(ok, th - val / np.where(ok, der, -1.0), th), 0.0, 1.0)
                xc, _, _ = rk4(x[ii], v0, th * hi, Fi, Li, Fci, dSi, Dvi, s_i, Si)
                Rc = Si["k_lin"] * (xc - Si["center"]) + Si["k_sin"] * np.sin(xc - Si["center"])
                Hc = Fi - Rc
                go = stick_test(xc, Hc, Li, Si)
                new_x = xc.copy()
                new_v = np.zeros(len(ii))
                new_stuck = ~go
                if go.any():
                    g = np.flatnonzero(go)
                    Sg = sub(Si, g)
                    s2 = np.sign(Hc[g])
                    Fc2, dS2, Dv2 = dir_params(s2, Sg)
                    rem = (1.0 - th[g]) * hi[g]
                    x2, v2, _ = rk4(xc[g], np.zeros(len(g)), rem, Fi[g], Li[g], Fc2, dS2, Dv2, s2, Sg)
                    back = s2 * v2 <= 0  # stopped again inside the remainder (rare): rest there
                    new_x[g] = x2
                    new_v[g] = np.where(back, 0.0, v2)
                    new_stuck[g] = back
                    sd = sdir.copy()
                    sd[ii[g]] = s2
                    sdir = sd
                xn = xn.copy()
                vn = vn.copy()
                xn[ii] = new_x
                vn[ii] = new_v
                st = stuck.copy()
                st[ii] = new_stuck
                stuck = st
            x, v = xn, vn
        record(k, x_old, x, S)

    for i, ln in enumerate(lanes):
        o = P["soff"][i]
        ln.out_x = flat_out[o : o + len(ln.stamps)]
        if np.isnan(ln.out_x).any():
            raise RuntimeError(f"lane {i}: stamps beyond the simulated time")
    return [ln.out_x for ln in lanes]


def simulate_one(plant: Plant, cmd, T: float, stamps=None, n_sub: int = 0, x0: float = 0.0):
    cmd = np.asarray(cmd, dtype=float)
    if stamps is None:
        stamps = np.arange(len(cmd)) * T
    ln = Lane(plant=plant, cmd=cmd, T=T, stamps=np.asarray(stamps, dtype=float), n_sub=n_sub, x0=x0)
    return simulate([ln])[0]


# ---------------------------------------------------------------------------------------------
# Logging


def quantise(x, q):
    return np.round(np.asarray(x) / q) * q


def jittered_stamps(n: int, T: float, rng: np.random.Generator, jitter: float = 0.3):
    """n stamps around j T with +-jitter T uniform jitter (strictly increasing, first at 0)."""
    t = np.arange(n) * T + rng.uniform(-jitter, jitter, n) * T
    t[0] = 0.0
    t = np.maximum(t, 0.0)
    return t


def refresh_mask(n: int, every: int, phase: int) -> np.ndarray:
    """Rows on which a channel refreshed every `every` rows gets a fresh sample (row 0 always)."""
    m = (np.arange(n) % every) == (phase % every)
    m[0] = True
    return m


def hold(values: np.ndarray, fresh: np.ndarray) -> np.ndarray:
    """Zero-order hold of values over rows without a fresh sample."""
    idx = np.where(fresh, np.arange(len(values)), 0)
    idx = np.maximum.accumulate(idx)
    return values[idx]

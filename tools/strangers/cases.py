"""Seeded stranger cases for `crane diagnose`: draw, simulate, check, write.

Usage: python3 tools/strangers/cases.py --out DIR [--cases N | --only CAUSE]

Every case is one single-axis rig with one hidden cause (or none) on top of a Coulomb + viscous
baseline, driven by an operator's open-loop runs (ramps, pulses/steps, chirps, staircases) and
logged synchronously or asynchronously. The data set goes to DIR/<case>/data/, the truth to
DIR/<case>/truth.json (outside the data directory). Same master seed = same cases.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from dataclasses import dataclass, field

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import plant as P  # noqa: E402

# the seed of the published set; `--seed` (or STRANGERS_SEED) draws another set of the same
# plan, cases the tool was never run on before (a held-back check of a change)
MASTER_SEED = int(os.environ.get("STRANGERS_SEED", "20261126"))

# cause -> number of cases (none >= 10, every cause >= 6)
CAUSE_COUNTS = {
    "none": 10,
    "stiction": 6,
    "stribeck_friction": 6,
    "localized_friction": 6,
    "input_deadzone": 6,
    "input_saturation": 6,
    "input_delay": 6,
    "restoring_force": 6,
    "force_offset": 6,
    "direction_asymmetry": 6,
    "load_dependent_friction": 6,
}
CAUSES = list(CAUSE_COUNTS)

RATES = np.array([100, 200, 250, 500, 1000, 2000, 5000, 10000], dtype=float)
RATE_W = np.array([0.07, 0.16, 0.12, 0.20, 0.20, 0.15, 0.05, 0.05])

EFFECT_MIN = 0.05  # held-out position NMAE the effect must make
MAX_ATTEMPTS = 24
GUARD_STEP = 0.01  # the operator's rough mental model of the rig steps at 10 ms


# ---------------------------------------------------------------------------------------------
# Case specification


@dataclass
class Run:
    name: str
    kind: str  # "other" (fitting) or "validation" (held out)
    cmd: np.ndarray
    x0: float
    stamps: np.ndarray
    guard_x: np.ndarray  # the operator's rough position estimate on the guard grid


@dataclass
class Case:
    case_id: str
    cause: str
    index: int  # index within its cause
    attempt: int
    seed: int
    rotary: bool
    rate: float
    asynchronous: bool
    async_style: str  # "" (sync), "repeat" or "blank"
    refresh: tuple  # (x every, x phase, u every, u phase) for async logs
    input_style: str  # "known", "unknown", "force"
    input_unit: str
    gain_physical: float
    umax: float
    fmax: float
    quantum: float
    x_noise: float
    u_noise: float
    pos_scale: float  # recorded x times this = position in position_unit
    t0: float
    plant: P.Plant
    removed: P.Plant | None
    runs: list = field(default_factory=list)
    params: dict = field(default_factory=dict)
    hard_limit: float = 0.5


def _logu(rng, a, b):
    return float(math.exp(rng.uniform(math.log(a), math.log(b))))


def case_seed(cause: str, index: int, attempt: int) -> int:
    return int(
        np.random.SeedSequence([MASTER_SEED, CAUSES.index(cause), index, attempt]).generate_state(1)[0]
    )


# ---------------------------------------------------------------------------------------------
# The operator: open-loop inputs with a rough model in mind to stay inside the travel


class Guard:
    """The operator's rough picture of the rig (semi-implicit Euler at 10 ms, exact Coulomb
    stop), used only to turn inputs around before the axis leaves its travel."""

    def __init__(self, p: P.Plant, x0: float, h: float):
        self.p, self.x, self.v, self.h = p, x0, 0.0, h
        self.xs = []

    def step(self, u: float) -> float:
        p = self.p
        us = min(max(u, -p.usat), p.usat)
        ud = math.copysign(max(abs(us) - p.dz, 0.0), us)
        Fa = p.gain * ud
        F = Fa + p.offset
        x = self.x
        R = p.k_lin * (x - p.center) + p.k_sin * math.sin(x - p.center)
        B = p.bump_A * math.exp(-0.5 * ((x - p.bump_c) / p.bump_w) ** 2) if p.bump_A else 0.0
        L = p.mu * abs(Fa)
        H = F - R
        v = self.v
        if v == 0.0:
            if -(p.Fs_n + L + B) <= H <= p.Fs_p + L + B:
                self.xs.append(x)
                return x
            s = 1.0 if H > 0 else -1.0
        else:
            s = 1.0 if v > 0 else -1.0
        Fc = p.Fc_p if s > 0 else p.Fc_n
        Dv = p.Dv_p if s > 0 else p.Dv_n
        a = (H - s * (Fc + L + B)) / p.J
        vn = (v + self.h * a) / (1.0 + self.h * Dv / p.J)
        if vn * s <= 0:
            vn = 0.0
        self.v = vn
        self.x = x + self.h * vn
        self.xs.append(self.x)
        return self.x


def design_run(kind_of_input: str, dur: float, case: Case, x0: float, rng) -> tuple:
    """Commands on the guard grid (10 ms, or the log period if slower) for one run."""
    p = case.plant
    umax = case.umax
    XL = case.hard_limit
    hg = max(GUARD_STEP, 1.0 / case.rate)
    n = int(round(dur / hg))
    g = Guard(p, x0, hg)
    out = np.zeros(n)
    centre = p.center if (p.k_lin or p.k_sin) else 0.0
    k = 0

    def emit(u):
        nonlocal k
        if k < n:
            out[k] = u
            g.step(u)
            k += 1

    def rest(t):
        for _ in range(int(round(t / hg))):
            emit(0.0)

    def far():
        return abs(g.x - centre) > 0.3 * XL

    def inward():
        return -1.0 if g.x > centre else 1.0

    rest(rng.uniform(0.2, 0.8))
    if kind_of_input == "ramp":
        sgn = float(rng.choice([-1.0, 1.0]))
        while k < n:
            if far():
                sgn = inward()
            a = rng.uniform(0.5, 1.0) * umax
            tup = rng.uniform(1.5, 5.0)
            exc = rng.uniform(0.25, 0.5) * XL
            xs = g.x
            steps = max(2, int(round(tup / hg)))
            lvl = 0.0
            for i in range(1, steps + 1):
                lvl = sgn * a * i / steps
                emit(lvl)
                if abs(g.x - xs) > exc or abs(g.x - centre) > 0.75 * XL or k >= n:
                    break
            down = max(2, int(round(rng.uniform(0.15, 0.5) * tup * abs(lvl) / a / hg)))
            for i in range(1, down + 1):
                emit(lvl * (1 - i / down))
            rest(rng.uniform(0.4, 1.2))
            sgn = -sgn
    elif kind_of_input in ("pulses", "steps"):
        sgn = float(rng.choice([-1.0, 1.0]))
        while k < n:
            if far():
                sgn = inward()
            elif rng.random() < 0.5:
                sgn = -sgn
            a = rng.uniform(0.3, 1.0) * umax
            d = rng.uniform(0.08, 0.8) if kind_of_input == "pulses" else rng.uniform(0.5, 2.5)
            exc = rng.uniform(0.2, 0.45) * XL
            xs = g.x
            for _ in range(max(1, int(round(d / hg)))):
                emit(sgn * a)
                if abs(g.x - xs) > exc or abs(g.x - centre) > 0.75 * XL or k >= n:
                    break
            rest(rng.uniform(0.3, 1.2))
            sgn = -sgn
    elif kind_of_input == "chirp":
        a = rng.uniform(0.45, 1.0) * umax
        vmax = case.params["vmax"]
        fmin = vmax / (2 * math.pi * 0.25 * XL)
        f0 = max(rng.uniform(0.1, 0.5), fmin)
        f1 = max(rng.uniform(0.6, 3.0), 1.5 * f0)
        m = n - k
        ph = 0.0
        bias = 0.0
        gainf = 1.0
        for i in range(m):
            f = f0 + (f1 - f0) * i / max(m - 1, 1)
            ph += 2 * math.pi * f * hg
            # the operator nudges the bias against a drift, and turns the amplitude down near the ends
            dev = (g.x - centre) / XL
            bias += hg * (-2.0 * dev - 0.5 * bias)
            if abs(dev) > 0.6:
                gainf = max(0.4, gainf * 0.995)
            env = min(1.0, i * hg / 0.5, (m - i) * hg / 0.5)
            emit(env * (gainf * a * math.sin(ph) + max(-0.3, min(0.3, bias)) * umax))
    elif kind_of_input == "staircase":
        while k < n:
            lvl = rng.uniform(-1.0, 1.0) * umax if rng.random() > 0.2 else 0.0
            if far() and lvl * inward() < 0:
                lvl = -lvl
            xs = g.x
            exc = rng.uniform(0.2, 0.45) * XL
            for _ in range(max(1, int(round(rng.uniform(0.2, 1.5) / hg)))):
                emit(lvl)
                if abs(g.x - xs) > exc or abs(g.x - centre) > 0.75 * XL or k >= n:
                    break
            if abs(g.x - centre) > 0.6 * XL:
                rest(rng.uniform(0.3, 0.8))
    else:
        raise ValueError(kind_of_input)
    rest(0.3)  # (no-op when full) runs end quiet
    out[-max(1, int(round(0.2 / hg))):] = 0.0
    smooth = kind_of_input in ("ramp", "chirp")
    return out, hg, smooth, np.array(g.xs)


def to_log_grid(coarse: np.ndarray, hg: float, T: float, dur: float, smooth: bool) -> np.ndarray:
    n = int(round(dur / T))
    t = np.arange(n) * T
    tc = np.arange(len(coarse)) * hg
    if smooth:
        return np.interp(t, tc, coarse)
    idx = np.minimum((t / hg + 1e-9).astype(np.int64), len(coarse) - 1)
    return coarse[idx]


# ---------------------------------------------------------------------------------------------
# Drawing one case


def draw_case(cause: str, index: int, attempt: int) -> Case:
    seed = case_seed(cause, index, attempt)
    rng = np.random.default_rng(seed)
    j = index
    asynchronous = j % 2 == 1
    input_style = ["known", "unknown", "force"][(j // 2) % 3]
    rotary = ((j // 2) + j) % 2 == 1
    if cause == "none" and j >= 6:
        rotary = rng.random() < 0.5
        input_style = ["known", "unknown", "force"][int(rng.integers(3))]
    rate = float(rng.choice(RATES, p=RATE_W))
    if cause == "input_delay":
        rate = max(rate, 200.0)  # keep 20-200 ms at >= 2 samples with 3-5-row refresh

    # mechanics
    if rotary:
        J = _logu(rng, 1e-4, 5.0)
        vmax = _logu(rng, 0.6, 5.0)
        quantum = _logu(rng, 1e-5, 1e-3)
        hard = 3.0
    else:
        J = _logu(rng, 0.05, 80.0)
        vmax = _logu(rng, 0.05, 0.4)
        quantum = _logu(rng, 1e-6, 5e-5)
        hard = 0.5
    tau = _logu(rng, 0.03, 0.6)  # J / Dv: peak speed within about 3 tau = 0.09-1.8 s
    cfrac = rng.uniform(0.02, 0.25)
    if cause in ("localized_friction", "stiction", "stribeck_friction"):
        # a bump or a breakaway peak on a weak friction hardly moves the position
        cfrac = rng.uniform(0.1, 0.25)
    # plausible drives: at least 0.5 N (linear) / 0.01 N m (rotary) at full command; a light
    # axis is then a fast one (vmax up first, then a shorter time constant)
    fmin = 0.01 if rotary else 0.5
    vtop = 5.0 if rotary else 0.4
    if J * vmax / tau / (1.0 - cfrac) < fmin:
        vmax = min(vtop, fmin * tau * (1.0 - cfrac) / J)
        tau = max(0.015, min(tau, J * vmax / (fmin * (1.0 - cfrac))))
    Dv = J / tau
    fmax = Dv * vmax / (1.0 - cfrac)
    Fc = cfrac * fmax

    if input_style == "force":
        input_unit = "N m" if rotary else "N"
        umax = fmax
        gain = 1.0
    else:
        input_unit = str(rng.choice(["V", "A"]))
        umax = rng.uniform(2.0, 10.0) if input_unit == "V" else rng.uniform(0.5, 8.0)
        gain = fmax / umax

    plant = P.Plant(J=J, gain=gain, Fc_p=Fc, Fc_n=Fc, Fs_p=Fc, Fs_n=Fc, Dv_p=Dv, Dv_n=Dv)
    params: dict = {"vmax": vmax, "tau": tau, "coulomb_fraction": cfrac}
    removed = None
    if cause == "stiction":
        r = rng.uniform(1.4, 2.5)
        plant = plant.replace(Fs_p=r * Fc, Fs_n=r * Fc)
        removed = plant.replace(Fs_p=Fc, Fs_n=Fc)
        params["ratio"] = r
    elif cause == "stribeck_friction":
        r = rng.uniform(1.4, 2.5)
        vs = rng.uniform(0.1, 0.4) * 0.5 * vmax
        plant = plant.replace(Fs_p=r * Fc, Fs_n=r * Fc, vs=vs)
        removed = plant.replace(Fs_p=Fc, Fs_n=Fc, vs=0.0)
        params.update(ratio=r, vs=vs)
    elif cause == "localized_friction":
        A = rng.uniform(0.5, 1.0) * Fc
        w = rng.uniform(0.01, 0.03) if not rotary else rng.uniform(0.06, 0.2)
        params.update(amplitude=A, width=w)  # centre chosen from the designed motion below
    elif cause == "input_deadzone":
        d = rng.uniform(0.05, 0.25) * umax
        plant = plant.replace(dz=d)
        removed = plant.replace(dz=0.0)
        params["deadband"] = d
    elif cause == "input_saturation":
        params["sat_ratio"] = rng.uniform(0.5, 0.85)
        plant = plant.replace(usat=params["sat_ratio"] * umax)
    elif cause == "input_delay":
        d = rng.uniform(0.02, 0.2)
        d = max(d, 2.0 / rate)
        plant = plant.replace(delay=d)
        removed = plant.replace(delay=0.0)
        params["delay"] = d
    elif cause == "restoring_force":
        if rotary:
            k = rng.uniform(0.4, 1.5) * fmax
            c = rng.uniform(-0.6, 0.6)
            plant = plant.replace(k_sin=k, center=c)
        else:
            k = fmax / rng.uniform(0.05, 0.3)
            c = rng.uniform(-0.1, 0.1)
            plant = plant.replace(k_lin=k, center=c)
        removed = plant.replace(k_lin=0.0, k_sin=0.0)
        params.update(stiffness=k, center=c)
    elif cause == "force_offset":
        off = float(rng.choice([-1.0, 1.0])) * rng.uniform(0.2, 0.8) * Fc
        plant = plant.replace(offset=off)
        removed = plant.replace(offset=0.0)
        params["offset"] = off
    elif cause == "direction_asymmetry":
        r = rng.uniform(1.5, 3.0)
        big, small = Fc * math.sqrt(r), Fc / math.sqrt(r)
        if rng.random() < 0.5:
            fp, fn = big, small
        else:
            fp, fn = small, big
        plant = plant.replace(Fc_p=fp, Fs_p=fp, Fc_n=fn, Fs_n=fn)
        removed = plant.replace(Fc_p=Fc, Fs_p=Fc, Fc_n=Fc, Fs_n=Fc)
        params.update(ratio_pos_over_neg=fp / fn)
    elif cause == "load_dependent_friction":
        mu = rng.uniform(0.05, 0.3)
        plant = plant.replace(mu=mu)
        removed = plant.replace(mu=0.0)
        params["mu"] = mu

    # logging
    if asynchronous:
        style = "repeat" if (j // 2) % 2 == 0 else "blank"
        if cause == "none" and j >= 6:
            style = str(rng.choice(["repeat", "blank"]))
        ex, eu = int(rng.integers(3, 6)), int(rng.integers(3, 6))
        refresh = (ex, int(rng.integers(ex)), eu, int(rng.integers(eu)))
    else:
        style, refresh = "", (1, 0, 1, 0)
    pos_scale = 1.0
    if not rotary and rng.random() < 0.25:
        pos_scale = 0.001  # logged in mm
    elif rotary and rng.random() < 0.2:
        pos_scale = math.pi / 180.0  # logged in degrees
    case = Case(
        case_id="",
        cause=cause,
        index=index,
        attempt=attempt,
        seed=seed,
        rotary=rotary,
        rate=rate,
        asynchronous=asynchronous,
        async_style=style,
        refresh=refresh,
        input_style=input_style,
        input_unit=input_unit,
        gain_physical=gain,
        umax=umax,
        fmax=fmax,
        quantum=quantum,
        x_noise=float(rng.choice([0.0, 0.0, 0.3, 1.0])) * quantum,
        u_noise=rng.uniform(0.001, 0.005) * umax,
        pos_scale=pos_scale,
        t0=float(rng.choice([0.0, 0.0, rng.uniform(1.0, 5000.0)])),
        plant=plant,
        removed=removed,
        params=params,
        hard_limit=hard,
    )

    # runs
    T = 1.0 / rate
    nruns = int(rng.integers(6, 9))
    if rate >= 5000:
        nruns = 6
    # pairs of consecutive runs share an input type: one fits, the other is held out
    extra = list(rng.permutation(["chirp", "staircase", "steps"]))
    pair_types = ["ramp", "pulses"] + extra[: (nruns + 1) // 2 - 2]
    pair_types = [pair_types[k] for k in rng.permutation(len(pair_types))]
    types = [pair_types[i // 2] for i in range(nruns)]
    # the held-out member of a pair is now and then another input type
    for i in range(1, nruns, 2):
        if rng.random() < 0.25:
            types[i] = str(rng.choice(["ramp", "pulses", "chirp", "staircase", "steps"]))
    per_run_rows = rng.uniform(6000, 14000)
    for i in range(nruns):
        dur = float(np.clip(per_run_rows / rate * rng.uniform(0.7, 1.3), 3.0, 20.0))
        if rate >= 5000:
            dur = 3.0
        if types[i] == "ramp" and rate < 5000:
            dur = max(dur, 8.0)
        krest = plant.k_lin or plant.k_sin
        if krest:
            x0 = plant.center + rng.uniform(-0.3, 0.3) * Fc / krest
        else:
            x0 = rng.uniform(-0.1, 0.1) * hard
        coarse, hg, smooth, gx = design_run(types[i], dur, case, x0, rng)
        cmd = to_log_grid(coarse, hg, T, dur, smooth)
        kind = "validation" if i % 2 == 1 else "other"
        case.runs.append(
            Run(name=f"run_{i + 1:02d}_{types[i]}", kind=kind, cmd=cmd, x0=x0, stamps=None, guard_x=gx)
        )
    # saturation relative to the largest commanded |u|
    if cause == "input_saturation":
        umax_cmd = max(np.max(np.abs(r.cmd)) for r in case.runs)
        us = params["sat_ratio"] * umax_cmd
        case.plant = case.plant.replace(usat=us)
        case.removed = case.plant.replace(usat=math.inf)
        params["usat"] = us
        params["largest_u"] = umax_cmd
    if cause == "localized_friction":
        c = pick_bump_centre(case, rng)
        case.plant = case.plant.replace(bump_A=params["amplitude"], bump_c=c, bump_w=params["width"])
        case.removed = case.plant.replace(bump_A=0.0)
        params["center"] = c
    # stamps
    for r in case.runs:
        n = len(r.cmd)
        if asynchronous:
            r.stamps = P.jittered_stamps(n, T, rng)
        else:
            r.stamps = np.arange(n) * T
    return case


def applied_command(case: Case, r: Run) -> tuple:
    """(command, its period, sub-steps) the plant is driven by.

    Synchronous logs: the operator's command, updated every log period. Asynchronous logs: the
    command is published (and logged) only on the rows where `u` is refreshed, at their jittered
    stamps; the drive applies it from the first internal step at or after that stamp (a latency
    of at most one internal step, T/4 or less) and holds it until the next publication. So the
    logged `u` is the applied input (plus noise): nothing the drive saw is missing from the log.
    """
    T = 1.0 / case.rate
    if not case.asynchronous:
        return r.cmd, T, 0
    n = len(r.cmd)
    nsub = P.auto_nsub(T, True)
    h = T / nsub
    _, _, eu, pu = case.refresh
    fresh = np.flatnonzero(P.refresh_mask(n, eu, pu))
    vals = r.cmd[np.minimum((r.stamps[fresh] / T + 1e-9).astype(np.int64), n - 1)]
    kstart = np.ceil(r.stamps[fresh] / h - 1e-9).astype(np.int64)  # first step at/after the stamp
    fine = np.zeros(n * nsub)
    idx = np.searchsorted(kstart, np.arange(n * nsub), side="right") - 1
    ok = idx >= 0
    fine[ok] = vals[idx[ok]]
    return fine, h, 1


def logged_input(case: Case, r: Run) -> np.ndarray:
    """The command value logged on each row (before noise): the one in force at the stamp, or
    (asynchronous logs) the one published on that row."""
    T = 1.0 / case.rate
    return r.cmd[np.minimum((r.stamps / T + 1e-9).astype(np.int64), len(r.cmd) - 1)]


def crossings(x: np.ndarray, c: float) -> int:
    s = np.sign(x - c)
    s = s[s != 0]
    return int(np.count_nonzero(np.diff(s)))


def pick_bump_centre(case: Case, rng) -> float:
    fit = [r.guard_x for r in case.runs if r.kind == "other"]
    held = [r.guard_x for r in case.runs if r.kind == "validation"]
    allx = np.concatenate(fit + held)
    cands = np.quantile(allx, np.linspace(0.1, 0.9, 33))
    good = [
        c
        for c in cands
        if sum(crossings(x, c) for x in fit) >= 6 and sum(crossings(x, c) for x in held) >= 3
    ]
    if not good:
        good = list(cands)
    return float(rng.choice(good))


# ---------------------------------------------------------------------------------------------
# Checking a simulated case


def nmae(a, b):
    rng_ = float(np.max(a) - np.min(a))
    return float(np.mean(np.abs(a - b)) / rng_) if rng_ > 0 else 0.0


def check(case: Case, xs: list, xs_removed: list) -> tuple:
    """(ok, reason, effect_nmae)."""
    XL = case.hard_limit
    for r, x in zip(case.runs, xs):
        if not np.all(np.isfinite(x)) or np.max(np.abs(x)) > XL:
            return False, f"{r.name} leaves the travel ({np.max(np.abs(x)):.3g})", None
    minmove = 0.01 * XL
    for kind in ("other", "validation"):
        d = [np.diff(x) for r, x in zip(case.runs, xs) if r.kind == kind]
        pos = sum(float(np.sum(np.maximum(e, 0))) for e in d)
        neg = sum(float(np.sum(np.maximum(-e, 0))) for e in d)
        if pos < minmove or neg < minmove:
            return False, f"{kind} runs do not move both ways ({pos:.3g}, {neg:.3g})", None
    eff = None
    if case.cause != "none":
        held = [i for i, r in enumerate(case.runs) if r.kind == "validation"]
        eff = float(np.mean([nmae(xs[i], xs_removed[i]) for i in held]))
        if eff < EFFECT_MIN:
            return False, f"effect too small ({eff:.3f})", eff
    if case.cause == "localized_friction":
        c = case.plant.bump_c
        nf = sum(crossings(x, c) for r, x in zip(case.runs, xs) if r.kind == "other")
        nh = sum(crossings(x, c) for r, x in zip(case.runs, xs) if r.kind == "validation")
        if nf < 4 or nh < 2:
            return False, f"bump crossed {nf}/{nh} times", eff
    return True, "", eff


# ---------------------------------------------------------------------------------------------
# Writing


def fmt_num(v: float) -> str:
    return f"{v:.10g}"


def write_case(case: Case, xs: list, out_dir: str, effect: float | None):
    d = os.path.join(out_dir, case.case_id)
    dd = os.path.join(d, "data")
    os.makedirs(dd, exist_ok=True)
    rng = np.random.default_rng(case.seed + 1)
    T = 1.0 / case.rate
    toml = [
        '# single-axis rig (synthetic)',
        f'position_unit = "{"rad" if case.rotary else "m"}"',
        f'input_unit = "{case.input_unit}"',
    ]
    if case.pos_scale != 1.0:
        toml.append(f"position_scale = {case.pos_scale!r}")
    if case.input_style == "known":
        toml.append(f"gain = {case.gain_physical!r}")
    rows_total = 0
    for r, x in zip(case.runs, xs):
        n = len(r.stamps)
        xq = P.quantise(x + rng.normal(0, 1, n) * case.x_noise, case.quantum) / case.pos_scale
        ulog = logged_input(case, r) + rng.normal(0, 1, n) * case.u_noise
        t = r.stamps + case.t0
        xs_txt = [fmt_num(v) for v in xq]
        us_txt = [f"{v:.7g}" for v in ulog]
        lines = [f"# {r.name}", "t,x,u"]
        if case.asynchronous:
            ex, px, eu, pu = case.refresh
            fx = P.refresh_mask(n, ex, px)
            fu = P.refresh_mask(n, eu, pu)
            if case.async_style == "repeat":
                xi = P.hold(np.arange(n), fx)
                ui = P.hold(np.arange(n), fu)
                for k in range(n):
                    lines.append(f"{t[k]:.6f},{xs_txt[xi[k]]},{us_txt[ui[k]]}")
            else:
                for k in range(n):
                    if fx[k] or fu[k]:
                        xv = xs_txt[k] if fx[k] else ""
                        uv = us_txt[k] if fu[k] else ""
                        lines.append(f"{t[k]:.6f},{xv},{uv}")
        else:
            for k in range(n):
                lines.append(f"{t[k]:.6f},{xs_txt[k]},{us_txt[k]}")
        rows_total += len(lines) - 2
        with open(os.path.join(dd, r.name + ".csv"), "w") as f:
            f.write("\n".join(lines) + "\n")
        toml += ["", "[[runs]]", f'file = "{r.name}.csv"', f'kind = "{r.kind}"']
    with open(os.path.join(dd, "dataset.toml"), "w") as f:
        f.write("\n".join(toml) + "\n")
    truth = truth_of(case, effect)
    truth["rows"] = rows_total
    with open(os.path.join(d, "truth.json"), "w") as f:
        json.dump(truth, f, indent=1)
    return truth


def truth_of(case: Case, effect: float | None) -> dict:
    """The hidden truth, with the main parameters also in the report's units."""
    p = case.plant
    fs = 1.0 / case.gain_physical if case.input_style == "unknown" else 1.0  # force -> report unit
    if case.input_style == "unknown":
        force_unit = case.input_unit
    else:
        force_unit = "N m" if case.rotary else "N"
    main: dict = {}
    c = case.cause
    pr = case.params
    if c == "stiction":
        main = {"ratio": pr["ratio"], "breakaway": p.Fs_p * fs}
    elif c == "stribeck_friction":
        main = {"ratio": pr["ratio"], "stribeck_velocity": pr["vs"], "static": p.Fs_p * fs, "sliding": p.Fc_p * fs}
    elif c == "localized_friction":
        main = {"amplitude": p.bump_A * fs, "center": p.bump_c, "width": p.bump_w}
    elif c == "input_deadzone":
        main = {"deadband": p.dz}
    elif c == "input_saturation":
        # effort units: gain * usat (gain known or input a force), usat (gain unknown)
        main = {"saturation": p.usat * (1.0 if case.input_style == "unknown" else case.gain_physical),
                "usat_input": p.usat, "fraction_of_largest_u": pr["sat_ratio"]}
    elif c == "input_delay":
        main = {"delay_s": p.delay}
    elif c == "restoring_force":
        main = {"stiffness": (p.k_lin or p.k_sin) * fs, "center": p.center,
                "kind": "gravity_sin" if p.k_sin else "spring"}
    elif c == "force_offset":
        main = {"offset": p.offset * fs}
    elif c == "direction_asymmetry":
        main = {"kinetic_pos": p.Fc_p * fs, "kinetic_neg": p.Fc_n * fs}
    elif c == "load_dependent_friction":
        main = {"mu": p.mu}
    eff_levels = {"kinetic_pos": (p.Fc_p - p.offset) * fs, "kinetic_neg": (p.Fc_n + p.offset) * fs}
    return {
        "case_id": case.case_id,
        "cause": c,
        "main": main,
        "effective_kinetic": eff_levels,
        "report_force_unit": force_unit,
        "force_to_report": fs,
        "effect_heldout_nmae": effect,
        "rotary": case.rotary,
        "position_unit": "rad" if case.rotary else "m",
        "log_rate_hz": case.rate,
        "log_period_s": 1.0 / case.rate,
        "asynchronous": case.asynchronous,
        "async_style": case.async_style,
        "refresh_rows": {"x": case.refresh[0], "u": case.refresh[2]},
        "input_style": case.input_style,
        "input_unit": case.input_unit,
        "gain": case.gain_physical,
        "gain_declared": case.input_style == "known",
        "largest_drive_force": case.fmax,
        "quantum": case.quantum,
        "x_noise": case.x_noise,
        "u_noise": case.u_noise,
        "position_scale": case.pos_scale,
        "t0": case.t0,
        "plant": p.to_dict(),
        "draw": {k: v for k, v in case.params.items()},
        "seed": case.seed,
        "attempt": case.attempt,
        "runs": [{"file": r.name + ".csv", "kind": r.kind, "x0": r.x0, "rows": len(r.stamps)} for r in case.runs],
    }


# ---------------------------------------------------------------------------------------------
# Generation


def case_list(only: str | None = None, ncases: int | None = None) -> list:
    todo = []
    for cause, cnt in CAUSE_COUNTS.items():
        if only and cause != only:
            continue
        for i in range(cnt):
            todo.append((cause, i))
    # neutral ids: a seeded permutation (the id does not tell the cause)
    perm = np.random.default_rng(MASTER_SEED).permutation(sum(CAUSE_COUNTS.values()))
    allc = [(c, i) for c, n in CAUSE_COUNTS.items() for i in range(n)]
    ids = {allc[k]: f"s{int(perm[k]):03d}" for k in range(len(allc))}
    todo = [(c, i, ids[(c, i)]) for c, i in todo]
    if ncases is not None:
        # interleave the causes so a prefix covers all of them
        todo.sort(key=lambda ci: (ci[1], CAUSES.index(ci[0])))
        todo = todo[:ncases]
    return todo


def generate(out_dir: str, only: str | None = None, ncases: int | None = None, verbose=True) -> list:
    t_start = time.time()
    todo = case_list(only, ncases)
    pending = {(c, i): 0 for c, i, _ in todo}
    ids = {(c, i): cid for c, i, cid in todo}
    done: dict = {}
    os.makedirs(out_dir, exist_ok=True)
    passno = 0
    while pending:
        passno += 1
        K = 1 if passno == 1 else (4 if passno == 2 else 8)
        cases = []
        for (c, i), att in pending.items():
            for a in range(att, min(att + K, MAX_ATTEMPTS)):
                cs = draw_case(c, i, a)
                cs.case_id = ids[(c, i)]
                cases.append(cs)
        lanes = []
        where = []
        for ci, cs in enumerate(cases):
            for ri, r in enumerate(cs.runs):
                ucmd, Tl, nsub = applied_command(cs, r)
                lanes.append(P.Lane(plant=cs.plant, cmd=ucmd, T=Tl, stamps=r.stamps, x0=r.x0, n_sub=nsub))
                where.append((ci, ri, False))
                if cs.removed is not None and r.kind == "validation":
                    lanes.append(P.Lane(plant=cs.removed, cmd=ucmd, T=Tl, stamps=r.stamps, x0=r.x0, n_sub=nsub))
                    where.append((ci, ri, True))
        t0 = time.time()
        P.simulate(lanes)
        if verbose:
            print(f"pass {passno}: {len(cases)} draws, {len(lanes)} lanes, {time.time() - t0:.1f} s", file=sys.stderr)
        xs = [[None] * len(cs.runs) for cs in cases]
        xr = [[None] * len(cs.runs) for cs in cases]
        for ln, (ci, ri, rem) in zip(lanes, where):
            (xr if rem else xs)[ci][ri] = ln.out_x
        # per case the lowest acceptable attempt (deterministic whatever the batch)
        results: dict = {}
        for ci, cs in enumerate(cases):
            ok, why, eff = check(cs, xs[ci], xr[ci])
            results.setdefault((cs.cause, cs.index), []).append((cs.attempt, ok, why, eff, ci))
        new_pending = {}
        for key, lst in results.items():
            lst.sort()
            chosen = next((r for r in lst if r[1]), None)
            if chosen is None:
                for a, _, why, _, _ in lst:
                    if verbose:
                        print(f"  redraw {key[0]}#{key[1]} (attempt {a}): {why}", file=sys.stderr)
                if lst[-1][0] + 1 >= MAX_ATTEMPTS:
                    a, ok, why, eff, ci = lst[-1]
                    print(f"warning: {cases[ci].case_id} {key[0]}#{key[1]} kept after {MAX_ATTEMPTS} draws: {why}", file=sys.stderr)
                    chosen = lst[-1]
                else:
                    new_pending[key] = lst[-1][0] + 1
                    continue
            a, ok, why, eff, ci = chosen
            done[key] = (cases[ci], xs[ci], eff, ok, why)
        pending = new_pending
    truths = []
    for (c, i, cid) in todo:
        cs, x, eff, ok, why = done[(c, i)]
        tr = write_case(cs, x, out_dir, eff)
        tr["accepted"] = ok
        tr["accept_note"] = why
        with open(os.path.join(out_dir, cid, "truth.json"), "w") as f:
            json.dump(tr, f, indent=1)
        truths.append(tr)
    if verbose:
        print(f"generated {len(truths)} cases in {time.time() - t_start:.1f} s", file=sys.stderr)
    return truths


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True)
    ap.add_argument("--cases", type=int, default=None, help="first N cases (causes interleaved)")
    ap.add_argument("--only", default=None, choices=CAUSES)
    ap.add_argument("--seed", type=int, default=None, help=f"master seed (default {MASTER_SEED})")
    a = ap.parse_args(argv)
    set_seed(a.seed)
    generate(a.out, a.only, a.cases)


def set_seed(seed: int | None) -> None:
    """Draws the cases of another master seed (None: keep the current one)."""
    global MASTER_SEED
    if seed is not None:
        MASTER_SEED = int(seed)


if __name__ == "__main__":
    main()

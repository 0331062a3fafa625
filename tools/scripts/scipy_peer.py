#!/usr/bin/env python3
"""The Python peer of the work-precision study (issue 15): scipy's solve_ivp on the paper's two
cases, timed, so a Python user's best alternatives stand in the same table as `crane study`.

Series (every run one whole solve_ivp integration over the case, sampled on the 1 ms grid):
- `tanh(gamma v)` friction under RK45 (explicit Dormand-Prince 5(4)) and LSODA (stiff /
  non-stiff switching BDF / Adams, finite-difference Jacobian), gamma = 1e2 .. 1e6,
  rtol 1e-3 .. 1e-8, atol = rtol / 100;
- the hybrid (exact-sticking) model under RK45 with terminal events, rtol 1e-3 .. 1e-10,
  atol = rtol / 100: a moving axis's velocity reaching zero (`qd_i`, direction against the
  motion) and a stopped axis's holding force reaching its breakaway threshold
  (`|hold_i| - Cbar_i`, rising). At an event the velocity is reset to 0, the modes
  re-resolved (NUMERICS.md "Mode resolution") and solve_ivp restarted from there.

Same equations as the Rust model (NUMERICS.md "One evaluation": mass matrix, Coriolis and
gravity terms, Gaussian elimination without pivoting, a stopped or held axis as the constraint
`qdd_i = 0`) and the cases of tools/src/cases.rs (masses, damping, Cbar, inputs, durations,
held axes; continuous-time input, as the Rust adaptive integrator). Not modelled: end stops
(neither case reaches one; a run whose drive position leaves its range is an error).

Error: RMSE of the compared velocity (case 1: trolley `yd`, case 2: rope `Ld`) on the 1 ms
grid against this script's own reference, the hybrid model under RK45 at rtol 1e-12,
atol 1e-14 (checked against the Rust 10 us reference: see BENCHMARKS.md). Times: the fastest
of repeated runs (a run over 1 s timed once, else repeated for 0.5 s, at least 3 and at most
20 times; `--quick`: 3 runs under 0.2 s, else 1), one thread, the whole solve including the
samples. A series (one model, one method) stops after a run longer than
`--cap` seconds (default 3): the tighter tolerances cost more without lowering the error below
the smoothing error; a run longer than `--run-limit` seconds (default 30) is aborted and
listed as such, not as a point; and once a `tanh` series' loosest run took longer than the cap
(or was aborted), the larger gammas are not run under that method (an explicit solver's cost
grows with gamma). Every skipped or aborted run is printed and kept in the JSON.

Why the event loop is written as it is (it used to hang in case 2):
- a breakaway is NOT applied by setting the mode: the located point is only a root of the
  margin to within rounding. The old loop set the mode there, its "other velocities that
  crossed zero" sweep undid that at once (the velocity is exactly 0, so `v * mode <= 0`), and
  the mode resolution released the axis again only if the margin at the root happened to be
  positive. In case 2 it was at the first breakaway (0.3046 s), not at the second
  (1.3046 s): the axis stayed stopped, and the restarted solve_ivp found the same root again,
  forever. Now the restart point is moved past the root (a tiny explicit step, at most
  `NUDGE_MAX` seconds, until the margin is positive) and the mode resolution alone decides
  the release, as in the Rust model (its located breakaway is on the positive side);
- a released axis accelerates in its direction (the resolution checks it), so the velocity
  event `qd_i` (direction against the motion) cannot fire at the restart time;
- every run has a hard cap: `MAX_RESTARTS` restarts, and `MAX_STALLS` consecutive restarts that
  advance time by less than `STALL_DT` raise `HybridStuck` instead of looping.

Usage (needs numpy and scipy; the benchmark itself is not run in CI, its test
tools/scripts/test_scipy_peer.py is cheap):
    python3 -m venv venv && venv/bin/pip install numpy scipy
    venv/bin/python tools/scripts/scipy_peer.py [--quick] [--json out.json] [--cap S]
        [--run-limit S] [--case 1|2]
"""

import argparse
import datetime
import json
import math
import os
import platform
import sys
import tempfile
import time

import numpy as np
import scipy
from scipy.integrate import solve_ivp

G = 9.81
M_T, M_R = 1.155, 2.20
D_ALPHA, D_BETA = 2.573e-4, 0.0059
STOPPED, POS, NEG = 0, 1, -1
# Drive-axis ranges [m] (x, y, L) of the default parameters (model/src/params.rs).
LIMITS = ((0.0, 0.505), (0.0, 0.625), (0.13, 0.57))

# Hard caps of the hybrid event loop (see the module documentation).
MAX_RESTARTS = 5000
MAX_STALLS = 20
STALL_DT = 1e-9
# Largest time [s] a restart after a breakaway is moved past the located root.
NUDGE_MAX = 1e-6

RTOL_REF, ATOL_REF = 1e-12, 1e-14
HYBRID_RTOLS = [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10]
TANH_RTOLS = [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8]
GAMMAS = [1e2, 1e3, 1e4, 1e5, 1e6]
LEVELS = [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8]


class HybridStuck(RuntimeError):
    """The hybrid event loop made no progress (restart cap or stalled restarts)."""


class RunTooLong(RuntimeError):
    """A run passed its wall-time limit (`Case.deadline`) and was aborted: not a point."""


class Case:
    """One of the paper's cases (tools/src/cases.rs)."""

    def __init__(self, cid):
        if cid not in (1, 2):
            raise ValueError(f"case must be 1 or 2, not {cid!r}")
        self.cid = cid
        if cid == 1:
            self.mp = 0.457
            self.cbar = [1.0, 1.0, None]  # None: held (rope)
            self.q0 = [0.25, 0.3125, 0.40, math.pi / 2 + 0.6, 0.0]
            self.duration = 30.0
            self.observed = 1
        else:
            self.mp = 1.0
            self.cbar = [None, None, 9.81]
            self.q0 = [0.25, 0.3125, 0.35, math.pi / 2, 0.0]
            self.duration = 8.0
            self.observed = 2
        # Largest step (as tools/src/adaptive_run.rs): a tenth of the input's period; with the
        # rope stopped and the swing at rest the state is constant and RK45 would step over
        # the breakaways. Case 1 (zero input): unbounded.
        self.max_step = 0.2 if cid == 2 else math.inf
        self.held = [c is None for c in self.cbar]
        self.free = [i for i in range(3) if not self.held[i]]
        self.m00 = M_T + M_R + self.mp
        self.m11 = M_T + self.mp
        self.m22 = self.mp
        self.mpg = self.mp * G
        self.grid = np.arange(1, int(round(self.duration / 1e-3)) + 1) * 1e-3
        self.last = {}
        # Wall-clock deadline (time.perf_counter) of the current run, checked at every
        # evaluation; None: no limit.
        self.deadline = None

    def force(self, t):
        """Rope drive force [N] at time t (case 2: -m_p g + 12 sin(2 pi 0.5 t); case 1: 0)."""
        if self.cid == 1:
            return 0.0
        return -self.mpg + 12.0 * math.sin(2.0 * math.pi * 0.5 * t)

    def solve(self, t, y, fric, stopped):
        """Accelerations qdd and holding forces [N] at time t, state y = (q, qd) (a list), with
        friction forces `fric` on the drive axes and the axes in `stopped` held (qdd_i = 0).
        NUMERICS.md "One evaluation"; Gaussian elimination without pivoting (M is positive
        definite)."""
        if self.deadline is not None and time.perf_counter() > self.deadline:
            raise RunTooLong(f"case {self.cid}: aborted at t = {t:.4g} s of {self.duration:g} s")
        _, _, L, a, b, _, _, Ld, ad, bd = y
        sa, ca, sb, cb = math.sin(a), math.cos(a), math.sin(b), math.cos(b)
        mp = self.mp
        mpL = mp * L
        ad2, bd2 = ad * ad, bd * bd
        m02, m03, m04 = mp * sa * sb, mpL * ca * sb, mpL * sa * cb
        m12, m13 = mp * ca, -(mpL * sa)
        m33 = mpL * L
        m44 = m33 * sa * sa
        M = [
            [self.m00, 0.0, m02, m03, m04],
            [0.0, self.m11, m12, m13, 0.0],
            [m02, m12, self.m22, 0.0, 0.0],
            [m03, m13, 0.0, m33, 0.0],
            [m04, 0.0, 0.0, 0.0, m44],
        ]
        h = [
            mp * (L * (2.0 * ad * bd * ca * cb - (ad2 + bd2) * sa * sb)
                  + 2.0 * Ld * (ad * sb * ca + bd * sa * cb)),
            -(mp * ad * (L * ad * ca + 2.0 * Ld * sa)),
            -(mpL * (ad2 + bd2 * sa * sa)),
            mpL * (2.0 * Ld * ad - L * bd2 * sa * ca),
            mpL * bd * (2.0 * L * ad * sa * ca + 2.0 * Ld * sa * sa),
        ]
        g = [0.0, 0.0, -(self.mpg * sa * cb), -(self.mpg * L * ca * cb), self.mpg * L * sa * sb]
        F = (0.0, 0.0, self.force(t))
        r = [F[0] - fric[0] - h[0] - g[0], F[1] - fric[1] - h[1] - g[1],
             F[2] - fric[2] - h[2] - g[2],
             -(D_ALPHA * ad) - h[3] - g[3], -(D_BETA * bd) - h[4] - g[4]]
        A = [row[:] for row in M]
        for i in range(3):
            if stopped[i]:
                for j in range(5):
                    A[i][j] = 0.0
                    A[j][i] = 0.0
                A[i][i] = 1.0
                r[i] = 0.0
        for k in range(5):
            akk = A[k][k]
            if not akk > 0.0:
                raise ArithmeticError(f"mass matrix singular at t = {t}")
            rowk = A[k]
            for i in range(k + 1, 5):
                f = A[i][k] / akk
                if f != 0.0:
                    rowi = A[i]
                    for j in range(k, 5):
                        rowi[j] -= f * rowk[j]
                    r[i] -= f * r[k]
        x = [0.0] * 5
        for i in range(4, -1, -1):
            s = r[i]
            for j in range(i + 1, 5):
                s -= A[i][j] * x[j]
            x[i] = s / A[i][i]
        hold = [0.0, 0.0, 0.0]
        for i in range(3):
            if stopped[i]:
                row = M[i]
                s = row[0] * x[0] + row[1] * x[1] + row[2] * x[2] + row[3] * x[3] + row[4] * x[4]
                hold[i] = F[i] - (s + h[i] + g[i])
        return x, hold

    # --- tanh model -------------------------------------------------------------------------
    def tanh_rhs(self, gamma):
        """Right-hand side of the `tanh(gamma v)` model (held axes as constraints)."""
        cbar, held = self.cbar, self.held

        def f(t, y):
            yl = y.tolist()
            fric = [0.0 if held[i] else cbar[i] * math.tanh(gamma * yl[5 + i]) for i in range(3)]
            qdd, _ = self.solve(t, yl, fric, held)
            return np.array(yl[5:] + qdd)
        return f

    # --- hybrid model -----------------------------------------------------------------------
    def hybrid_eval(self, t, y, modes):
        """(qdd, hold) of the hybrid law in `modes` at (t, y) (y a list)."""
        stopped = [self.held[i] or modes[i] == STOPPED for i in range(3)]
        fric = [0.0 if stopped[i] else modes[i] * self.cbar[i] for i in range(3)]
        return self.solve(t, y, fric, stopped)

    def margin(self, t, y, modes, i):
        """Breakaway margin [N] of stopped axis i: `|hold_i| - Cbar_i` (> 0: the guard holds)."""
        _, hold = self.hybrid_eval(t, y, modes)
        return abs(hold[i]) - self.cbar[i]

    def resolve(self, t, y, modes):
        """Mode resolution (NUMERICS.md): releases stopped free axes whose holding force exceeds
        Cbar (largest margin first), keeping a release only if the axis then accelerates in its
        direction."""
        modes = list(modes)
        blocked = set()
        for _ in range(3):
            _, hold = self.hybrid_eval(t, y, modes)
            best = None
            for i in self.free:
                if modes[i] != STOPPED or i in blocked:
                    continue
                for d, m in ((POS, hold[i] - self.cbar[i]), (NEG, -self.cbar[i] - hold[i])):
                    if m > 0 and (best is None or m > best[2]):
                        best = (i, d, m)
            if best is None:
                return modes
            i, d, _ = best
            trial = list(modes)
            trial[i] = d
            qdd, _ = self.hybrid_eval(t, y, trial)
            if qdd[i] * d > 0:
                modes = trial
            else:
                blocked.add(i)
        return modes

    def check_range(self, ys, t):
        """Raises if a drive position in the rows `ys[0:3]` left its range (no end stops here)."""
        for i in self.free:
            lo, hi = LIMITS[i]
            if ys[i].size and (ys[i].min() < lo or ys[i].max() > hi):
                raise RuntimeError(f"case {self.cid}: drive axis {i} left its range "
                                   f"[{lo}, {hi}] m before t = {t:.6g} s (no end stops here)")

    def hybrid(self, rtol, atol, max_restarts=MAX_RESTARTS):
        """The hybrid model under RK45 with terminal events (see the module documentation).

        Returns the compared velocity on the grid and the number of right-hand-side
        evaluations (solve_ivp's nfev; event functions and mode resolutions not counted).
        Afterwards `self.last` holds the run's record: restarts, events, stop and release
        times of the free axes, final state and modes."""
        y = list(self.q0) + [0.0] * 5
        t = 0.0
        modes = self.resolve(t, y, [STOPPED] * 3)
        grid, n = self.grid, len(self.grid)
        obs = 5 + self.observed
        out = np.empty(n)
        filled = 0
        nfev = 0
        restarts = 0
        stalls = 0
        nudges = 0
        stops, releases = [], []
        for i in self.free:
            if modes[i] != STOPPED:
                releases.append((t, i, modes[i]))
        while True:
            # Grid points at or before the restart time take the restart state.
            while filled < n and grid[filled] <= t:
                out[filled] = y[obs]
                filled += 1
            if filled == n:
                break
            m = list(modes)

            def f(tt, yy, m=m):
                yl = yy.tolist()
                qdd, _ = self.hybrid_eval(tt, yl, m)
                return np.array(yl[5:] + qdd)

            events, kinds = [], []
            for i in self.free:
                if m[i] == STOPPED:
                    def ev(tt, yy, i=i, m=m):
                        return self.margin(tt, yy.tolist(), m, i)
                    ev.terminal, ev.direction = True, 1
                    kinds.append(("breakaway", i))
                else:
                    def ev(tt, yy, i=i):
                        return yy[5 + i]
                    ev.terminal, ev.direction = True, -m[i]
                    kinds.append(("velocity", i))
                events.append(ev)
            sol = solve_ivp(f, (t, self.duration), np.array(y), method="RK45", rtol=rtol,
                            atol=atol, t_eval=grid[filled:], events=events,
                            max_step=self.max_step)
            nfev += sol.nfev
            if sol.status < 0:
                raise RuntimeError(f"case {self.cid}: RK45 failed at t = {t}: {sol.message}")
            k = len(sol.t)
            if k:
                out[filled:filled + k] = sol.y[obs]
                filled += k
                self.check_range(sol.y[:3], sol.t[-1])
            if sol.status == 0:
                if filled != n:
                    raise RuntimeError(f"case {self.cid}: {filled} of {n} samples")
                y = sol.y[:, -1].tolist()
                break
            # A terminal event: the earliest one.
            restarts += 1
            if restarts > max_restarts:
                raise HybridStuck(f"case {self.cid}, rtol {rtol:g}: more than {max_restarts} "
                                  f"event restarts (t = {t:.9g} s, modes {m})")
            e = min((j for j, te in enumerate(sol.t_events) if len(te)),
                    key=lambda j: sol.t_events[j][0])
            te = float(sol.t_events[e][0])
            y = sol.y_events[e][0].tolist()
            kind, i = kinds[e]
            if kind == "velocity":
                y[5 + i] = 0.0
                m[i] = STOPPED
                stops.append((te, i))
            else:
                # The root is located to rounding; move past it (a tiny explicit step, the
                # state's change is ~1e-12 of a step's) until the margin is positive, so the
                # resolution below sees the guard hold.
                dt = 16.0 * np.finfo(float).eps * max(1.0, abs(te))
                while self.margin(te, y, m, i) <= 0.0 and dt <= NUDGE_MAX:
                    nudges += 1
                    qdd, _ = self.hybrid_eval(te, y, m)
                    yd = y[5:] + qdd
                    y = [yj + dt * dj for yj, dj in zip(y, yd)]
                    te += dt
                    dt *= 2.0
            # Any other moving axis whose velocity crossed zero stops too (NUMERICS.md sweep).
            for j in self.free:
                if m[j] != STOPPED and y[5 + j] * m[j] <= 0.0:
                    y[5 + j] = 0.0
                    m[j] = STOPPED
                    stops.append((te, j))
            new = self.resolve(te, y, m)
            for j in self.free:
                if m[j] == STOPPED and new[j] != STOPPED:
                    releases.append((te, j, new[j]))
            modes = new
            stalls = stalls + 1 if te - t < STALL_DT else 0
            if stalls > MAX_STALLS:
                raise HybridStuck(f"case {self.cid}, rtol {rtol:g}: {stalls} restarts in a row "
                                  f"advanced less than {STALL_DT:g} s (t = {te:.12g} s, "
                                  f"modes {modes}, last event {kind} of axis {i})")
            t = te
        self.last = dict(restarts=restarts, nudges=nudges, stops=stops, releases=releases, y_end=y,
                         modes_end=modes)
        return out, nfev


def tanh_run(case, gamma, method, rtol, atol):
    """The `tanh(gamma v)` model under solve_ivp `method`: compared velocity on the grid, nfev."""
    y0 = np.array(case.q0 + [0.0] * 5)
    sol = solve_ivp(case.tanh_rhs(gamma), (0.0, case.duration), y0, method=method,
                    rtol=rtol, atol=atol, t_eval=case.grid)
    if sol.status != 0:
        raise RuntimeError(f"case {case.cid}: {method} on tanh({gamma:g} v) failed: {sol.message}")
    return sol.y[5 + case.observed], sol.nfev


def best_time(fn, budget=0.5, single_above=1.0, max_runs=20):
    """Fastest wall time [s] of repeated runs of fn and the first run's result: a run longer
    than `single_above` seconds is timed once; otherwise runs are repeated until `budget`
    seconds have passed, at least 3 and at most `max_runs` (as `crane study`'s time_best)."""
    start = time.perf_counter()
    r = fn()
    best = time.perf_counter() - start
    if best > single_above:
        return best, r
    runs = 1
    while runs < 3 or (runs < max_runs and time.perf_counter() - start < budget):
        t1 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t1)
        runs += 1
    return best, r


def rmse(v, ref):
    """Root-mean-square difference of two sampled velocities of the same length [m/s]."""
    v, ref = np.asarray(v), np.asarray(ref)
    if v.shape != ref.shape:
        raise ValueError(f"{v.shape} samples against {ref.shape}")
    return float(np.sqrt(np.mean((v - ref) ** 2)))


def series_plan(quick):
    """(model, gamma, method, rtols) of every series, cheapest first within a series."""
    if quick:
        plan = [("hybrid", None, "RK45+events", [1e-3, 1e-5, 1e-7])]
        for g in (1e2, 1e3, 1e4):
            plan.append(("tanh", g, "LSODA", [1e-3, 1e-5]))
        for g in (1e2, 1e3):
            plan.append(("tanh", g, "RK45", [1e-3, 1e-5]))
        return plan
    plan = [("hybrid", None, "RK45+events", HYBRID_RTOLS)]
    for g in GAMMAS:
        plan.append(("tanh", g, "RK45", TANH_RTOLS))
        plan.append(("tanh", g, "LSODA", TANH_RTOLS))
    return plan


def label(p):
    if p is None:
        return "not reached"
    g = "" if p["gamma"] is None else f"tanh({p['gamma']:g} v) "
    return f"{g}{p['method']} rtol {p['rtol']:g}, {fmt_time(p['time_s'])}"


def fmt_time(s):
    return f"{s * 1e3:.3g} ms" if s < 1.0 else f"{s:.3g} s"


def levels_table(points):
    """Per error level: the fastest point of each family reaching it."""
    fams = {
        "hybrid": lambda p: p["model"] == "hybrid",
        "tanh_rk45": lambda p: p["model"] == "tanh" and p["method"] == "RK45",
        "tanh_lsoda": lambda p: p["model"] == "tanh" and p["method"] == "LSODA",
    }
    rows = []
    for lv in LEVELS:
        row = {"level": lv}
        for name, sel in fams.items():
            ok = [p for p in points if sel(p) and p["rmse"] <= lv]
            row[name] = min(ok, key=lambda p: p["time_s"]) if ok else None
        tanh = [row["tanh_rk45"], row["tanh_lsoda"]]
        tanh = [p for p in tanh if p is not None]
        row["tanh_best"] = min(tanh, key=lambda p: p["time_s"]) if tanh else None
        h, b = row["hybrid"], row["tanh_best"]
        row["speedup"] = b["time_s"] / h["time_s"] if h and b else None
        rows.append(row)
    return rows


def run_case(cid, quick, cap, run_limit, log):
    """Reference and every series of one case; returns (reference info, points, level rows).

    A series stops after a run longer than `cap` seconds; a run longer than `run_limit` is
    aborted (recorded as such, not a point); for one method, once a series' loosest run took
    longer than `cap`, the larger gammas are not run (their cost grows with gamma)."""
    case = Case(cid)
    t0 = time.perf_counter()
    ref, ref_nfev = case.hybrid(RTOL_REF, ATOL_REF)
    ref_info = dict(rtol=RTOL_REF, atol=ATOL_REF, time_s=time.perf_counter() - t0, nfev=ref_nfev,
                    restarts=case.last["restarts"], stops=len(case.last["stops"]),
                    first_stop_s=case.last["stops"][0][0] if case.last["stops"] else None,
                    last_stop_s=case.last["stops"][-1][0] if case.last["stops"] else None,
                    v_end=case.last["y_end"][5 + case.observed])
    log(f"case {cid}: reference (hybrid, RK45+events rtol {RTOL_REF:g}, atol {ATOL_REF:g}) in "
        f"{ref_info['time_s']:.1f} s, {ref_nfev} evaluations, {ref_info['restarts']} restarts")
    points = []
    skip_from = {}  # method -> the series after which larger gammas are not run
    print(f"\n### Case {cid}\n")
    print("| series | rtol | time | RMSE [m/s] | nfev |")
    print("|---|---|---|---|---|")
    for model, g, method, rtols in series_plan(quick):
        name = "hybrid" if g is None else f"tanh({g:g} v)"
        if model == "tanh" and method in skip_from:
            log(f"case {cid}: {name} {method}: not run ({skip_from[method]})")
            points.append(dict(case=cid, model=model, gamma=g, method=method,
                               skipped=skip_from[method]))
            print(f"| {name} {method} | - | not run | - | - |")
            continue
        for n_run, r in enumerate(rtols):
            a = r * 1e-2

            def fn(r=r, a=a):
                case.deadline = time.perf_counter() + run_limit
                try:
                    if model == "hybrid":
                        return case.hybrid(r, a)
                    return tanh_run(case, g, method, r, a)
                finally:
                    case.deadline = None
            try:
                t, (v, nfev) = (best_time(fn, budget=0.0, single_above=0.2) if quick
                                else best_time(fn))
            except Exception as e:  # a failed or aborted run is reported, and ends its series
                why = f"{type(e).__name__}: {e}"
                log(f"case {cid}: {name} {method} rtol {r:g}: {why}")
                points.append(dict(case=cid, model=model, gamma=g, method=method, rtol=r,
                                   failed=why))
                shown = f"> {run_limit:g} s (aborted)" if isinstance(e, RunTooLong) else "failed"
                print(f"| {name} {method} | {r:g} | {shown} | - | - |", flush=True)
                if n_run == 0 and model == "tanh":
                    skip_from[method] = f"{name} at rtol {r:g} was aborted"
                break
            e = rmse(v, ref)
            p = dict(case=cid, model=model, gamma=g, method=method, rtol=r, atol=a, time_s=t,
                     rmse=e, nfev=nfev)
            points.append(p)
            print(f"| {name} {method} | {r:g} | {fmt_time(t)} | {e:.2e} | {nfev} |", flush=True)
            if t > cap:
                log(f"case {cid}: {name} {method}: series stops after rtol {r:g} ({t:.1f} s > "
                    f"cap {cap:g} s)")
                if n_run == 0 and model == "tanh":
                    skip_from[method] = f"{name} took {t:.1f} s at rtol {r:g}"
                break
    ok = [p for p in points if "time_s" in p]
    rows = levels_table(ok)
    print(f"\nCase {cid}: fastest setting reaching each error level\n")
    print("| level [m/s] | hybrid RK45+events | tanh RK45 | tanh LSODA | speed-up (best tanh / hybrid) |")
    print("|---|---|---|---|---|")
    for row in rows:
        sp = "-" if row["speedup"] is None else f"{row['speedup']:.3g}"
        print(f"| {row['level']:.0e} | {label(row['hybrid'])} | {label(row['tanh_rk45'])} | "
              f"{label(row['tanh_lsoda'])} | {sp} |")
    return ref_info, points, rows


def check_json_target(path, force):
    """Raises SystemExit unless `path` may be written: absent, an earlier output of this
    script, or `force`; never a directory."""
    if os.path.isdir(path):
        raise SystemExit(f"--json {path}: is a directory")
    if os.path.exists(path) and not force:
        try:
            with open(path) as f:
                old = json.load(f)
            ours = isinstance(old, dict) and old.get("tool") == "scipy_peer"
        except (OSError, ValueError):
            ours = False
        if not ours:
            raise SystemExit(f"--json {path}: exists and is not an output of this script "
                             "(use --force to replace it)")


def write_json_atomic(path, obj, force):
    """Writes `obj` as JSON to `path` via a temporary file in the same directory and a rename
    (see `check_json_target`)."""
    check_json_target(path, force)
    d = os.path.dirname(os.path.abspath(path))
    fd, tmp = tempfile.mkstemp(prefix=".scipy_peer.", suffix=".tmp", dir=d)
    try:
        with os.fdopen(fd, "w") as f:
            json.dump(obj, f, indent=1)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def positive_seconds(s):
    v = float(s)
    if not 0.0 < v <= 600.0:
        raise argparse.ArgumentTypeError(f"must be in (0, 600] seconds, not {s}")
    return v


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true",
                    help="fewer tolerances and gammas, no repeats above 0.2 s (under a minute)")
    ap.add_argument("--json", metavar="FILE", help="also write every point as JSON (atomically)")
    ap.add_argument("--force", action="store_true", help="let --json replace any existing file")
    ap.add_argument("--cap", type=positive_seconds, default=3.0,
                    help="a series stops after a run longer than this [s], in (0, 600] (default 3)")
    ap.add_argument("--run-limit", type=positive_seconds, default=30.0,
                    help="a run longer than this [s] is aborted (not a point), in (0, 600] "
                         "(default 30)")
    ap.add_argument("--case", type=int, choices=(1, 2), action="append",
                    help="run only this case (repeatable; default both)")
    args = ap.parse_args(argv)
    if args.json:
        check_json_target(args.json, args.force)  # before the run, not after it
    log = lambda msg: print(msg, file=sys.stderr, flush=True)
    start = time.perf_counter()
    print(f"scipy {scipy.__version__}, numpy {np.__version__}, Python {platform.python_version()}"
          f"; {'quick' if args.quick else 'full'} run, series cap {args.cap:g} s, "
          f"run limit {args.run_limit:g} s")
    result = dict(tool="scipy_peer", scipy=scipy.__version__, numpy=np.__version__,
                  python=platform.python_version(), quick=args.quick, cap_s=args.cap,
                  run_limit_s=args.run_limit,
                  date=datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
                  cases=[])
    for cid in sorted(set(args.case or [1, 2])):
        ref_info, points, rows = run_case(cid, args.quick, args.cap, args.run_limit, log)
        result["cases"].append(dict(case=cid, reference=ref_info, points=points, levels=rows))
    result["wall_s"] = time.perf_counter() - start
    log(f"total {result['wall_s']:.0f} s")
    if args.json:
        write_json_atomic(args.json, result, args.force)


if __name__ == "__main__":
    main()

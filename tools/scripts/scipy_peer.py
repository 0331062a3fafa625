#!/usr/bin/env python3
"""The Python peer of the work-precision study (issue 15): scipy's solve_ivp on the paper's two
cases, timed, so a Python user's best alternatives stand in the same table as `crane study`.

- tanh(gamma v) friction under RK45 (explicit Dormand-Prince 5(4)) and LSODA (stiff/non-stiff
  switching BDF/Adams), gamma = 1e2 .. 1e6;
- the hybrid (exact-sticking) model under RK45 with terminal events: a moving axis's velocity
  reaching zero and a stopped axis's holding force reaching its breakaway threshold; at an
  event the velocity is reset to 0, the modes re-resolved and solve_ivp restarted.

Same equations as the Rust model (NUMERICS.md "One evaluation", the cases of
tools/src/cases.rs: masses, damping, Cbar, inputs, durations, held axes). Error: RMSE of the
compared velocity (case 1: trolley yd, case 2: rope Ld) on the 1 ms grid against this script's
own reference, the hybrid model under RK45 at rtol 1e-12 (independent of the Rust reference;
the two agree to the printed digits on the hybrid rows). Times: the fastest of repeated runs
(at least 3 while a run takes under 1 s), one thread, the whole solve including the samples.

STATUS (unfinished, issue 15): the hybrid RK45-with-events loop does not finish (it hangs in
case 2 from the first run, cause not found before the deadline), and the script's reference is
that loop, so no number of this script is reported in BENCHMARKS.md. The tanh runs
(`tanh_run`) work on their own.

Usage (needs numpy and scipy; not run in CI):
    python3 -m venv venv && venv/bin/pip install numpy scipy
    venv/bin/python tools/scripts/scipy_peer.py [--quick] [--json out.json]
"""

import argparse
import json
import math
import sys
import time

import numpy as np
from scipy.integrate import solve_ivp

G = 9.81
M_T, M_R = 1.155, 2.20
D_ALPHA, D_BETA = 2.573e-4, 0.0059
STOPPED, POS, NEG = 0, 1, -1


class Case:
    def __init__(self, cid):
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
        # Largest step: a tenth of the input's period (as the Rust adaptive integrator); with
        # everything stopped the state is constant and RK45 would step over the breakaways.
        self.max_step = 0.2 if cid == 2 else math.inf
        self.held = [c is None for c in self.cbar]
        self.m00 = M_T + M_R + self.mp
        self.m11 = M_T + self.mp
        self.m22 = self.mp
        self.grid = np.arange(1, int(round(self.duration / 1e-3)) + 1) * 1e-3

    def force(self, t):
        """Drive forces [N] at time t (case 2: rope force -m_p g + 12 sin(pi t))."""
        if self.cid == 1:
            return (0.0, 0.0, 0.0)
        return (0.0, 0.0, -self.mp * G + 12.0 * math.sin(2.0 * math.pi * 0.5 * t))

    def terms(self, y):
        """Mass matrix M, Coriolis h and gravity G at y = (q, qd)."""
        _, _, L, a, b = y[:5]
        _, _, Ld, ad, bd = y[5:]
        sa, ca, sb, cb = math.sin(a), math.cos(a), math.sin(b), math.cos(b)
        mp = self.mp
        mpL = mp * L
        M = np.zeros((5, 5))
        M[0, 0], M[1, 1], M[2, 2] = self.m00, self.m11, self.m22
        M[0, 2] = M[2, 0] = mp * sa * sb
        M[0, 3] = M[3, 0] = mpL * ca * sb
        M[0, 4] = M[4, 0] = mpL * sa * cb
        M[1, 2] = M[2, 1] = mp * ca
        M[1, 3] = M[3, 1] = -(mpL * sa)
        M[3, 3] = mpL * L
        M[4, 4] = mpL * L * sa * sa
        ad2, bd2 = ad * ad, bd * bd
        h = np.array([
            mp * (L * (2 * ad * bd * ca * cb - (ad2 + bd2) * sa * sb) + 2 * Ld * (ad * sb * ca + bd * sa * cb)),
            -(mp * ad * (L * ad * ca + 2 * Ld * sa)),
            -(mpL * (ad2 + bd2 * sa * sa)),
            mpL * (2 * Ld * ad - L * bd2 * sa * ca),
            mpL * bd * (2 * L * ad * sa * ca + 2 * Ld * sa * sa),
        ])
        g = np.array([0.0, 0.0, -(mp * G * sa * cb), -(mp * G * L * ca * cb), mp * G * L * sa * sb])
        return M, h, g

    def solve(self, t, y, fric, stopped):
        """Accelerations and holding forces with friction forces `fric` on the drive axes and
        the axes in `stopped` held (qdd = 0)."""
        M, h, g = self.terms(y)
        F = self.force(t)
        Q = np.array([F[0] - fric[0], F[1] - fric[1], F[2] - fric[2],
                      -D_ALPHA * y[8], -D_BETA * y[9]])
        r = Q - h - g
        A = M.copy()
        for i in range(3):
            if stopped[i]:
                A[i, :] = 0.0
                A[:, i] = 0.0
                A[i, i] = 1.0
                r[i] = 0.0
        qdd = np.linalg.solve(A, r)
        hold = [F[i] - (M[i] @ qdd + h[i] + g[i]) if stopped[i] else 0.0 for i in range(3)]
        return qdd, hold

    # --- tanh model -------------------------------------------------------------------------
    def tanh_rhs(self, gamma):
        def f(t, y):
            fric = [0.0 if self.held[i] else self.cbar[i] * math.tanh(gamma * y[5 + i]) for i in range(3)]
            qdd, _ = self.solve(t, y, fric, self.held)
            return np.concatenate([y[5:], qdd])
        return f

    # --- hybrid model -----------------------------------------------------------------------
    def hybrid_eval(self, t, y, modes):
        stopped = [self.held[i] or modes[i] == STOPPED for i in range(3)]
        fric = [0.0 if stopped[i] else modes[i] * self.cbar[i] for i in range(3)]
        return self.solve(t, y, fric, stopped)

    def resolve(self, t, y, modes):
        """Releases stopped free axes whose holding force exceeds Cbar (largest margin first),
        keeping a release only if the axis then accelerates in its direction."""
        blocked = set()
        for _ in range(3):
            _, hold = self.hybrid_eval(t, y, modes)
            best = None
            for i in range(3):
                if self.held[i] or modes[i] != STOPPED or i in blocked:
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

    def hybrid(self, rtol, atol):
        """RK45 with terminal events; returns the compared velocity on the grid and the evaluations."""
        y = np.array(self.q0 + [0.0] * 5)
        t = 0.0
        modes = self.resolve(t, y, [STOPPED] * 3)
        out = np.empty(len(self.grid))
        filled = 0
        steps = 0
        self.segments = 0
        while t < self.duration - 1e-12:
            m = list(modes)

            def f(tt, yy):
                qdd, _ = self.hybrid_eval(tt, yy, m)
                return np.concatenate([yy[5:], qdd])

            events, kinds = [], []
            for i in range(3):
                if self.held[i]:
                    continue
                if m[i] == STOPPED:
                    for d in (POS, NEG):
                        def ev(tt, yy, i=i, d=d):
                            _, hold = self.hybrid_eval(tt, yy, m)
                            return d * hold[i] - self.cbar[i]
                        ev.terminal, ev.direction = True, 1
                        events.append(ev)
                        kinds.append((i, d))
                else:
                    def ev(tt, yy, i=i):
                        return yy[5 + i]
                    ev.terminal, ev.direction = True, -m[i]
                    events.append(ev)
                    kinds.append((i, 0))
            te = self.grid[filled:]
            sol = solve_ivp(f, (t, self.duration), y, method="RK45", rtol=rtol, atol=atol,
                            t_eval=te, events=events, max_step=self.max_step)
            self.segments += 1
            steps += sol.nfev
            n = len(sol.t)
            if n:
                out[filled:filled + n] = np.asarray(sol.y)[5 + self.observed]
                filled += n
            if sol.status == 1:  # a terminal event: the earliest one
                k = min((k for k, e in enumerate(sol.t_events) if len(e)),
                        key=lambda k: sol.t_events[k][0])
                t = sol.t_events[k][0]
                y = sol.y_events[k][0].copy()
                i, kind = kinds[k]
                if kind == 0:  # velocity zero
                    y[5 + i] = 0.0
                    m[i] = STOPPED
                else:  # breakaway: the margin is ~0 here, so release in its direction
                    m[i] = kind
                for j in range(3):  # any other velocity that crossed zero
                    if not self.held[j] and m[j] != STOPPED and y[5 + j] * m[j] <= 0:
                        y[5 + j] = 0.0
                        m[j] = STOPPED
                modes = self.resolve(t, y, m)
            elif sol.status == 0:
                t = self.duration
            else:
                raise RuntimeError(sol.message)
        return out[:filled], steps


def tanh_run(case, gamma, method, rtol, atol):
    y0 = np.array(case.q0 + [0.0] * 5)
    sol = solve_ivp(case.tanh_rhs(gamma), (0.0, case.duration), y0, method=method,
                    rtol=rtol, atol=atol, t_eval=case.grid)
    if sol.status != 0:
        raise RuntimeError(sol.message)
    return sol.y[5 + case.observed], sol.nfev


def best_time(fn, budget=1.0):
    t0 = time.perf_counter()
    r = fn()
    best = time.perf_counter() - t0
    if best < budget:
        for _ in range(2):
            t1 = time.perf_counter()
            fn()
            best = min(best, time.perf_counter() - t1)
    return best, r


def rmse(v, ref):
    n = min(len(v), len(ref))
    return float(np.sqrt(np.mean((np.asarray(v[:n]) - ref[:n]) ** 2)))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="fewer tolerances, no RK45 above gamma 1e3")
    ap.add_argument("--json", help="write the points as JSON to this file")
    args = ap.parse_args()
    points = []
    levels = [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8]
    for cid in (1, 2):
        case = Case(cid)
        t0 = time.perf_counter()
        ref, _ = case.hybrid(1e-12, 1e-14)
        print(f"case {cid}: reference (hybrid, RK45 rtol 1e-12) in {time.perf_counter() - t0:.1f} s",
              file=sys.stderr)
        rtols = [1e-3, 1e-5, 1e-7] if args.quick else [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8]
        runs = [("hybrid", None, "RK45+events", r) for r in rtols]
        for g in (1e2, 1e3, 1e4, 1e5, 1e6):
            runs += [("tanh", g, "LSODA", r) for r in rtols]
            if g <= (1e3 if args.quick else 1e4):
                runs += [("tanh", g, "RK45", r) for r in rtols]
        for model, g, method, r in runs:
            a = r * 1e-2
            if model == "hybrid":
                fn = lambda: case.hybrid(r, a)
            else:
                fn = lambda: tanh_run(case, g, method, r, a)
            try:
                t, (v, work) = best_time(fn)
            except Exception as e:  # a failed run is reported, not fatal
                print(f"case {cid}: {model} {g} {method} rtol {r:g}: failed: {e}", file=sys.stderr)
                continue
            e = rmse(v, ref)
            p = dict(case=cid, model=model, gamma=g, method=method, rtol=r, time_s=t, rmse=e)
            points.append(p)
            name = "hybrid" if g is None else f"tanh({g:g} v)"
            print(f"case {cid}  {name:<16} {method:<12} rtol {r:<6g} time {t:10.4g} s  RMSE {e:.3e} m/s",
                  flush=True)
        print(f"\ncase {cid}: fastest setting reaching each level")
        for lv in levels:
            hy = [p for p in points if p["case"] == cid and p["model"] == "hybrid" and p["rmse"] <= lv]
            ta = [p for p in points if p["case"] == cid and p["model"] == "tanh" and p["rmse"] <= lv]
            fh = min(hy, key=lambda p: p["time_s"]) if hy else None
            ft = min(ta, key=lambda p: p["time_s"]) if ta else None
            fmt = lambda p: ("not reached" if p is None else
                             f"{p['model']} {'' if p['gamma'] is None else format(p['gamma'], 'g')} "
                             f"{p['method']} rtol {p['rtol']:g} ({p['time_s']:.4g} s)")
            ratio = f"{ft['time_s'] / fh['time_s']:.3g}x" if fh and ft else "-"
            print(f"  {lv:6.0e}: hybrid {fmt(fh)} | tanh {fmt(ft)} | {ratio}")
        print()
    if args.json:
        with open(args.json + ".tmp", "w") as f:
            json.dump(points, f, indent=1)
        import os
        os.replace(args.json + ".tmp", args.json)


if __name__ == "__main__":
    main()

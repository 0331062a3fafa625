"""How far the data of a case can show its effect: the held-out runs replayed on the plant
with the effect, against an *equivalent* plant without it that every sample where the drive
pushes the motion cannot tell apart.

`cases.py` accepts a case when replaying its commands on the plant without the effect (same
inertia, gain and friction) moves the held-out positions by 5 % NMAE or more. A fitted model is
not that plant: for two effects the baseline's own parameters absorb the effect wherever the
drive pushes the motion, and only braking samples (input against the motion), or a moving axis
with its input inside a dead band, tell them apart:

- load-dependent friction `s (Fc + mu |F|)`: while `sign F = s`, `m a = (1 - mu) F - s Fc -
  Dv v`, the plant with inertia, friction levels and viscous friction divided by `1 - mu`;
- a dead band `d` on the input: while `|u| > d` and `sign u = s`, `g (u - d s)` is a dry level
  higher by `g d`.

This script draws the same cases as `cases.py` (same seeds and attempts, read from each case's
`truth.json`), replays the held-out commands on the true plant and on that equivalent one, and
prints their NMAE apart (in %, with the encoder's half count over the run's range for scale).
Where it is at the noise, no method can name the effect from these data. It is an analysis of
the generator's cases, not of the tool: it never reads a report.

    python3 tools/strangers/identifiable.py --out /tmp/str
"""

from __future__ import annotations

import argparse
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import cases as C  # noqa: E402
import plant as P  # noqa: E402

CAUSES = ("load_dependent_friction", "input_deadzone")


def equivalent(case: C.Case) -> P.Plant:
    """The plant without the effect that equals it wherever the drive pushes the motion."""
    p = case.plant
    if case.cause == "load_dependent_friction":
        k = 1.0 / (1.0 - p.mu)
        return p.replace(mu=0.0, J=p.J * k, Fc_p=p.Fc_p * k, Fc_n=p.Fc_n * k, Fs_p=p.Fs_p * k,
                         Fs_n=p.Fs_n * k, Dv_p=p.Dv_p * k, Dv_n=p.Dv_n * k)
    gd = p.gain * p.dz
    return p.replace(dz=0.0, Fc_p=p.Fc_p + gd, Fc_n=p.Fc_n + gd, Fs_p=p.Fs_p + gd, Fs_n=p.Fs_n + gd)


def braking_share(case: C.Case, xs: list) -> float:
    """Share of the fitting runs' moving samples whose logged input opposes the motion [1]."""
    n = b = 0
    for r, x in zip(case.runs, xs):
        if r.kind != "other":
            continue
        v = np.gradient(x)
        u = C.logged_input(case, r)[: len(v)]
        m = np.abs(v) > 0.1 * np.max(np.abs(v))
        n += int(np.sum(m))
        b += int(np.sum(m & (u * v < 0)))
    return b / max(n, 1)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True, help="the cases' folder (cases.py --out)")
    ap.add_argument("--seed", type=int, default=None, help="the master seed the cases were drawn with")
    a = ap.parse_args(argv)
    C.set_seed(a.seed)
    print("| case | cause | parameter | log | effect vs plant without it | vs equivalent plant | half count | fitting runs braking |")
    print("|---|---|---|---|---|---|---|---|")
    for cause in CAUSES:
        for c, i, cid in C.case_list(cause):
            path = os.path.join(a.out, cid, "truth.json")
            if not os.path.exists(path):
                print(f"{cid}: no truth.json in {a.out}", file=sys.stderr)
                continue
            with open(path) as f:
                truth = json.load(f)
            case = C.draw_case(c, i, int(truth["attempt"]))
            lanes, held = [], []
            for r in case.runs:
                ucmd, T, nsub = C.applied_command(case, r)
                for pl in (case.plant, equivalent(case)) if r.kind == "validation" else (case.plant,):
                    lanes.append(P.Lane(plant=pl, cmd=ucmd, T=T, stamps=r.stamps, x0=r.x0, n_sub=nsub))
                held.append(r.kind == "validation")
            P.simulate(lanes)
            xs, eq, k = [], [], 0
            for h in held:
                xs.append(lanes[k].out_x)
                if h:
                    eq.append(lanes[k + 1].out_x)
                    k += 2
                else:
                    eq.append(None)
                    k += 1
            d = [C.nmae(x, e) for x, e in zip(xs, eq) if e is not None]
            q = [0.5 * case.quantum / max(float(np.ptp(x)), 1e-300) for x, e in zip(xs, eq) if e is not None]
            par = f"mu {case.plant.mu:.3g}" if cause == "load_dependent_friction" else f"d {case.plant.dz:.4g}"
            eff = truth.get("effect_heldout_nmae")
            print(f"| {cid} | {cause} | {par} | {'async' if case.asynchronous else 'sync'} | "
                  f"{100 * eff:.2f} % | {100 * float(np.mean(d)):.3f} % | {100 * float(np.mean(q)):.4f} % | "
                  f"{100 * braking_share(case, xs):.1f} % |")
    return 0


if __name__ == "__main__":
    sys.exit(main())

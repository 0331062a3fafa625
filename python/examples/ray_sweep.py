"""Monte Carlo over identified-parameter uncertainty on Ray, with the batch API in each task.

The identified parameters are uncertain: payload, and X's and Y's viscous and dry friction
(relative standard deviations below). For each sampled crane, a point-to-point move of the
trolley (X and Y voltage pulses, then coasting to a stop) is simulated with the hybrid model;
the sweep reports where the trolley stops and how much the payload still swings.

Local (as the test does):   python ray_sweep.py --workers 2 --sims 400
On a cluster:               python ray_sweep.py --address ray://head:10001 --sims 100000
(the cluster's nodes need `crane_twin` installed: `pip install ./python`).

Each Ray task runs ``crane_twin.rollouts`` on a chunk of parameter sets with ``threads=1``
(Ray places tasks on cores; rayon inside a task would oversubscribe them) and returns only
the per-simulation figures, not the trajectories.
"""

from __future__ import annotations

import argparse
import json
import os
import time

import numpy as np

import crane_twin as ct

#: Relative standard deviations of the identified parameters (Gaussian, truncated at 3 sigma).
SIGMA = {"payload_mass": 0.10, "viscous": 0.05, "dry": 0.10}


def sample_params(n: int, seed: int) -> list:
    """``n`` parameter sets around the defaults, as dicts (cheap to ship to workers)."""
    rng = np.random.default_rng(seed)
    base = ct.Params().to_dict()

    def factor(s):
        return float(1.0 + s * np.clip(rng.standard_normal(), -3, 3))

    out = []
    for _ in range(n):
        d = {"payload_mass": base["payload_mass"] * factor(SIGMA["payload_mass"])}
        for axis in ("x", "y"):
            a = dict(base[axis])
            fv, fd = factor(SIGMA["viscous"]), factor(SIGMA["dry"])
            a["viscous_pos"] *= fv
            a["viscous_neg"] *= fv
            a["dry_pos"] = [c * fd for c in a["dry_pos"]]
            a["dry_neg"] = [c * fd for c in a["dry_neg"]]
            d[axis] = a
        out.append(d)
    return out


def move(seconds: float, h: float) -> np.ndarray:
    """Voltages of the move: X +6 V and Y +4 V for 1 s, then 0 V (the trolley sticks)."""
    n = int(round(seconds / h))
    u = np.zeros((n, 3))
    on = int(round(1.0 / h))
    u[:on, 0], u[:on, 1] = 6.0, 4.0
    return u


def simulate_chunk(chunk: list, seconds: float, h: float) -> dict:
    """Runs one chunk with the batch API; returns per-simulation figures."""
    r = ct.rollouts(chunk, move(seconds, h), threads=1, h=h)
    q = r["q"]
    swing = np.hypot(q[:, :, 3] - np.pi / 2, q[:, :, 4])
    tail = swing[:, -int(round(1.0 / h)):]
    return {
        "x_end": q[:, -1, 0],
        "y_end": q[:, -1, 1],
        "peak_swing": swing.max(axis=1),
        "residual_swing": tail.max(axis=1),
        "stuck_at_end": (r["modes"][:, -1, :2] == 0).all(axis=1),
    }


def run(sims: int, workers: int, address: str | None, seconds: float, chunk: int, seed: int) -> dict:
    import ray

    os.environ.setdefault("RAY_USAGE_STATS_ENABLED", "0")
    if address:
        ray.init(address=address)
    else:
        ray.init(num_cpus=workers, include_dashboard=False, log_to_driver=False)
    try:
        task = ray.remote(num_cpus=1)(simulate_chunk)
        params = sample_params(sims, seed)
        chunks = [params[i : i + chunk] for i in range(0, sims, chunk)]
        # Warm-up: one tiny task per worker, so worker start-up is not timed.
        ray.get([task.remote(chunks[0][:1], 0.01, 1e-3) for _ in range(max(workers, 1))])
        t0 = time.perf_counter()
        parts = ray.get([task.remote(c, seconds, 1e-3) for c in chunks])
        wall = time.perf_counter() - t0
    finally:
        ray.shutdown()
    res = {k: np.concatenate([p[k] for p in parts]) for k in parts[0]}
    return {
        "sims": sims,
        "workers": workers if not address else None,
        "seconds_simulated": seconds,
        "wall_s": wall,
        "sims_per_s": sims / wall,
        "x_end_mean": float(res["x_end"].mean()),
        "x_end_std": float(res["x_end"].std()),
        "y_end_mean": float(res["y_end"].mean()),
        "y_end_std": float(res["y_end"].std()),
        "peak_swing_p95_rad": float(np.percentile(res["peak_swing"], 95)),
        "residual_swing_p95_rad": float(np.percentile(res["residual_swing"], 95)),
        "stuck_fraction": float(res["stuck_at_end"].mean()),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--address", default=None, help="Ray cluster address (default: a local Ray)")
    ap.add_argument("--workers", type=int, default=2, help="local worker processes (CPUs)")
    ap.add_argument("--sims", type=int, default=400)
    ap.add_argument("--chunk", type=int, default=25, help="simulations per Ray task")
    ap.add_argument("--seconds", type=float, default=3.0, help="simulated time of each run [s]")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args()
    if a.sims < 1 or a.chunk < 1 or a.workers < 1 or not (0 < a.seconds <= 600):
        ap.error("--sims, --chunk, --workers must be >= 1 and --seconds in (0, 600]")
    out = run(a.sims, a.workers, a.address, a.seconds, a.chunk, a.seed)
    if a.json:
        print(json.dumps(out))
    else:
        for k, v in out.items():
            print(f"{k:24s} {v}")


if __name__ == "__main__":
    main()

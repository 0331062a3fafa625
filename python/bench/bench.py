"""Benchmarks of ``crane_twin`` (figures, not tests): environment steps per second, single and
vectorised, against the same environment on a plain numpy model with ``tanh(1000 v)``
friction; and the batch API's simulations per second.

    python python/bench/bench.py [--quick] [--json]

Each figure is the best of ``--repeat`` timed runs (``time.perf_counter``).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))

import crane_twin as ct  # noqa: E402
from crane_twin.envs import CraneAntiSwayEnv, CraneAntiSwayVectorEnv, Task, _Episodes  # noqa: E402
from numpy_crane import NumpyCrane  # noqa: E402


class NumpyEpisodes(_Episodes):
    """The environment's episode logic (observation, reward) on the numpy model instead of
    ``CraneBatch``: the same work per step except the crane."""

    def __init__(self, m: int, task: Task, base: ct.Params) -> None:
        super().__init__(m, task, base)
        self.model = NumpyCrane(base.to_dict(), m, task.h)
        self.y = np.tile(np.array([0.25, 0.3, 0.35, np.pi / 2, 0, 0, 0, 0, 0, 0]), (m, 1))

    def step(self, actions):
        u = np.clip(np.asarray(actions, dtype=np.float64).reshape(self.m, 3), -ct.U_MAX, ct.U_MAX)
        for _ in range(self.task.substeps):
            self.y = self.model.step(self.y, u)
        states = self.y
        obs = self.observe(states)
        l, a, b = states[:, 2], states[:, 3], states[:, 4]
        payload = np.stack([states[:, 0] + l * np.sin(b) * np.sin(a), states[:, 1] + l * np.cos(a)], axis=1)
        d2 = np.sum((payload - self.targets) ** 2, axis=1)
        swing = (a - np.pi / 2) ** 2 + b**2
        energy = np.sum(u * u, axis=1) / ct.U_MAX**2
        t = self.task
        reward = -t.dt * (d2 / t.d0**2 + t.w_swing * swing + t.w_energy * energy)
        self.t += 1
        return obs, reward, self.t >= t.episode_steps, states


def best(fn, repeat, cpu=False):
    """Best of ``repeat`` runs: wall time, or this process's CPU time (``cpu``: robust to a
    shared machine for single-threaded work)."""
    clock = time.process_time if cpu else time.perf_counter
    times = []
    for _ in range(repeat):
        t0 = clock()
        fn()
        times.append(clock() - t0)
    return min(times)


def stable_step_check():
    """The numpy tanh model against the Rust tanh law (same RK4, same h) and against a run at
    h / 10: max position differences [m] over 2 s of a multisine."""
    t = np.arange(2000) * 1e-3
    u = np.stack([3 * np.sin(2 * np.pi * 0.7 * t), 3 * np.sin(2 * np.pi * 0.5 * t), 0.5 * np.sin(2 * np.pi * 0.3 * t)], 1)
    out = {}
    for h in (1e-3, 2e-3, 5e-3, 1e-2):
        k = int(round(h / 1e-3))
        uh = u[::k]
        model = NumpyCrane(ct.Params().to_dict(), 1, h)
        y = np.array([[0.25, 0.3, 0.35, np.pi / 2, 0, 0, 0, 0, 0, 0]])
        ys = [y[0].copy()]
        for uk in uh:
            y = model.step(y, uk[None, :])
            ys.append(y[0].copy())
        ys = np.array(ys)
        rust = ct.rollout(uh, h=h, law="tanh", gamma=1000.0)
        fine = ct.rollout(np.repeat(uh, 10, axis=0), h=h / 10, law="tanh", gamma=1000.0)["q"][::10]
        out[h] = {
            "numpy_vs_rust_same_h": float(np.max(np.abs(ys[:, :3] - rust["q"][:, :3]))),
            "rust_vs_h_over_10": float(np.max(np.abs(rust["q"][:, :3] - fine[:, :3]))),
            "finite": bool(np.isfinite(ys).all()),
        }
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="fewer steps (a smoke run)")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    steps = 200 if args.quick else 2000
    num_envs = 64
    rng = np.random.default_rng(0)
    res = {}

    env = CraneAntiSwayEnv(episode_steps=10**9)
    env.reset(seed=0)
    acts = rng.uniform(-12, 12, size=(steps, 3)).astype(np.float32)
    res["env_single_steps_per_s"] = steps / best(lambda: [env.step(a) for a in acts], args.repeat)
    res["env_single_steps_per_s_cpu"] = steps / best(lambda: [env.step(a) for a in acts], args.repeat, cpu=True)

    venv = CraneAntiSwayVectorEnv(num_envs=num_envs, episode_steps=10**9)
    venv.reset(seed=0)
    vacts = rng.uniform(-12, 12, size=(steps // 4, num_envs, 3)).astype(np.float32)
    res["env_vector64_steps_per_s"] = len(vacts) * num_envs / best(lambda: [venv.step(a) for a in vacts], args.repeat)
    res["env_vector64_steps_per_s_cpu"] = len(vacts) * num_envs / best(
        lambda: [venv.step(a) for a in vacts], args.repeat, cpu=True
    )

    # The numpy model at its largest step (of 1, 2, 5, 10 ms) that stays within 1e-6 m of a
    # run at a tenth of the step: the fairest (fastest) stable baseline, same 10 ms period.
    check = stable_step_check()
    res["stable_step_check"] = check
    h_np = max(h for h, c in check.items() if c["finite"] and c["rust_vs_h_over_10"] < 1e-6)
    res["numpy_h_s"] = h_np
    np_task = Task(h=h_np, substeps=int(round(0.01 / h_np)), episode_steps=10**9)
    for m, key in ((1, "numpy_env_single_steps_per_s"), (num_envs, "numpy_env_vector64_steps_per_s")):
        core = NumpyEpisodes(m, np_task, ct.Params())
        for i in range(m):
            core.reset_one(i, np.random.default_rng(i))
            core.y[i] = core.episodes[i][2]
        n = max(steps // 10, 20)
        a = rng.uniform(-12, 12, size=(n, m, 3))
        res[key] = n * m / best(lambda: [core.step(x) for x in a], args.repeat)
        res[key + "_cpu"] = n * m / best(
            lambda: [core.step(x) for x in a], args.repeat, cpu=True
        )

    # Batch API: 5 s runs (5000 steps) of the hybrid model, 64 parameter sets.
    sims = 16 if args.quick else 64
    u = np.tile([[4.0, -3.0, 0.5]], (5000, 1))
    u[2500:] *= -1
    plist = [ct.Params(payload_mass=float(mp)) for mp in np.linspace(0.1, 0.8, sims)]
    for threads in (1, 2):
        dt = best(lambda: ct.rollouts(plist, u, threads=threads), args.repeat)
        res[f"batch_sims_per_s_threads{threads}"] = sims / dt
        res[f"batch_steps_per_s_threads{threads}"] = sims * 5000 / dt
    res["batch_sims_per_s_threads1_cpu"] = sims / best(lambda: ct.rollouts(plist, u, threads=1), args.repeat, cpu=True)
    if args.json:
        print(json.dumps(res, indent=1))
        return
    for k, v in res.items():
        print(f"{k:42s} {v:,.4g}" if isinstance(v, float) else f"{k}: {v}")


if __name__ == "__main__":
    main()

"""The Python bindings give the Rust model's bits: `crane simulate` (the CLI, unchanged)
writes voltages and states to CSV with Rust's shortest round-trip float formatting; feeding
its voltages to `crane_twin.rollout` must reproduce every state, mode, friction and tension
bit, with parameters passed through a TOML file written by `Params.save`."""

from __future__ import annotations

import hashlib
import subprocess

import numpy as np

import crane_twin as ct


def _bits(a: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(a, dtype=np.float64).view(np.uint64)


def _digest(a: np.ndarray) -> str:
    return hashlib.sha256(_bits(a).tobytes()).hexdigest()[:16]


def _read_csv(path):
    lines = [l for l in path.read_text().splitlines() if not l.startswith("#")]
    header = lines[0].split(",")
    rows = [[float(v) for v in l.split(",")] for l in lines[1:]]
    return header, np.array(rows)


def test_rollout_equals_cli_bits(tmp_path, crane_cli):
    params = ct.Params().replace(
        {"x.viscous_pos": 92.5, "y.dry_neg": [1.2, -0.1, 0.3, 0.7, -1.5], "damping_beta": 0.004}
    )
    params.save(tmp_path / "p.toml")
    q0 = [0.21, 0.33, 0.4, 1.5707963267948966, 0.0]
    (tmp_path / "scenario.toml").write_text(
        "duration_s = 3.0\nh = 0.001\nsample_s = 0.001\npayload_kg = 0.3\n"
        'params = "p.toml"\n'
        f"q0 = {q0}\n"
    )
    out = tmp_path / "run.csv"
    subprocess.run(
        [str(crane_cli), "simulate", str(tmp_path / "scenario.toml"), "--out", str(out)],
        check=True,
        capture_output=True,
    )
    header, csv = _read_csv(out)
    col = {name: i for i, name in enumerate(header)}
    n = csv.shape[0] - 1
    assert n == 3000
    u = csv[:n, [col["u_x"], col["u_y"], col["u_l"]]]

    r = ct.rollout(
        u,
        params=params.replace({"payload_mass": 0.3}),
        h=1e-3,
        state=q0 + [0.0] * 5,
    )
    q_cli = csv[:, [col[c] for c in ("x", "y", "l", "alpha", "beta")]]
    assert _digest(r["q"]) == _digest(q_cli), "state bits differ from the CLI's"
    np.testing.assert_array_equal(_bits(r["q"]), _bits(q_cli))
    np.testing.assert_array_equal(
        r["modes"], csv[:, [col["mode_x"], col["mode_y"], col["mode_l"]]].astype(np.int8)
    )
    np.testing.assert_array_equal(
        _bits(r["friction"]),
        _bits(csv[:, [col["friction_x"], col["friction_y"], col["friction_l"]]]),
    )
    np.testing.assert_array_equal(_bits(r["tension"]), _bits(csv[:, col["tension"]]))
    # The run exercises the automaton: X and Y both stick and slide.
    for axis in (0, 1):
        assert (r["modes"][1:, axis] == 0).any() and (r["modes"][:, axis] != 0).any()


def test_crane_step_equals_rollout_bits():
    rng = np.random.default_rng(7)
    u = rng.uniform(-6, 6, size=(400, 3))
    r = ct.rollout(u, stiction=(1.3, 0.01))
    c = ct.Crane(stiction=(1.3, 0.01))
    states = [c.state] + [c.step(uk) for uk in u]
    s = np.array(states)
    np.testing.assert_array_equal(_bits(s[:, :5]), _bits(r["q"]))
    np.testing.assert_array_equal(_bits(s[:, 5:]), _bits(r["qd"]))
    assert c.steps == 400 and c.time == 400 * 1e-3


def test_batch_equals_single_rollouts_any_thread_count():
    rng = np.random.default_rng(3)
    u = rng.uniform(-8, 8, size=(300, 3))
    base = ct.Params()
    plist = [base.replace({"payload_mass": m}) for m in np.linspace(0.1, 0.8, 9)]
    b1 = ct.rollouts(plist, u, threads=1)
    b2 = ct.rollouts(plist, u, threads=2)
    bd = ct.rollouts(plist, u)
    for k in ("q", "qd", "friction", "tension", "payload"):
        np.testing.assert_array_equal(_bits(b1[k]), _bits(b2[k]))
        np.testing.assert_array_equal(_bits(b1[k]), _bits(bd[k]))
    for i, p in enumerate(plist):
        r = ct.rollout(u, params=p)
        np.testing.assert_array_equal(_bits(r["q"]), _bits(b1["q"][i]))
        np.testing.assert_array_equal(r["modes"], b1["modes"][i])
    # Different payloads give different runs (the batch is not one run repeated).
    assert not np.array_equal(b1["q"][0], b1["q"][-1])


def test_batch_releases_the_gil():
    """Python keeps running while a batch runs in Rust: a thread calls `rollouts`, the main
    thread records the times at which it runs. With the GIL held through the call, no main
    thread time could fall inside the middle 60 % of the call (the interpreter's 5 ms switch
    interval only blurs its ends)."""
    import threading
    import time

    u = np.tile([[5.0, -4.0, 0.3]], (5000, 1))
    plist = [ct.Params(payload_mass=float(m)) for m in np.linspace(0.1, 0.8, 32)]
    span = {}

    def work():
        span["t0"] = time.perf_counter()
        span["r"] = ct.rollouts(plist, u, threads=1)
        span["t1"] = time.perf_counter()

    t = threading.Thread(target=work)
    seen = []
    t.start()
    while t.is_alive():
        seen.append(time.perf_counter())
    t.join()
    assert span["r"]["q"].shape == (32, 5001, 5)
    t0, t1 = span["t0"], span["t1"]
    lo, hi = t0 + 0.2 * (t1 - t0), t1 - 0.2 * (t1 - t0)
    inside = sum(lo < s < hi for s in seen)
    assert inside > 100, f"main thread ran {inside} times inside the call ({t1 - t0:.3f} s)"

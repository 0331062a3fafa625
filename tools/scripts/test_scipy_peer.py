"""Tests of the scipy peer (tools/scripts/scipy_peer.py): its hybrid event loop terminates, and
its physics agrees with the Rust model.

Rust figures used here were measured with the Rust adaptive hybrid integrator at rtol 1e-10
(`crane_model::adaptive`, tolerances of tools/src/adaptive_run.rs), stepping until each
velocity event of the compared axis: case 1: 39 stops of the trolley, the first at
0.4054106741 s, the last at 24.0546067788 s (then at rest to the end); case 2: 8 stops of the
rope, the first at 0.8987132156 s. The Rust 10 us reference and this script's reference agree
to an RMSE of 6.7e-13 m/s (case 1) and 7.9e-11 m/s (case 2) on the 1 ms grid.

Needs numpy and scipy (skipped without them, unless the environment variable CI is set);
about 10 s.
"""

import json
import math
import os
import signal
import sys

import pytest

if os.environ.get("CI"):
    import numpy as np  # CI must have numpy and scipy: fail, do not skip
    import scipy
    assert scipy.__version__
else:
    np = pytest.importorskip("numpy", reason="numpy not installed")
    pytest.importorskip("scipy", reason="scipy not installed")

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import scipy_peer as sp  # noqa: E402

RUST_CASE1_STOPS = 39
RUST_CASE1_FIRST_STOP = 0.4054106741
RUST_CASE1_LAST_STOP = 24.0546067788
RUST_CASE2_STOPS = 8
RUST_CASE2_FIRST_STOP = 0.8987132156


class Alarm(Exception):
    pass


@pytest.fixture
def deadline():
    """Fails a test (instead of hanging) after the given number of seconds."""
    def handler(signum, frame):
        raise Alarm("did not finish in time: the event loop hangs")
    old = signal.signal(signal.SIGALRM, handler)

    def arm(seconds):
        signal.alarm(seconds)
    yield arm
    signal.alarm(0)
    signal.signal(signal.SIGALRM, old)


@pytest.fixture(scope="module")
def refs():
    """The script's reference (hybrid, RK45+events at rtol 1e-12) of both cases, with the
    record of its run."""
    out = {}
    for cid in (1, 2):
        c = sp.Case(cid)
        v, _ = c.hybrid(sp.RTOL_REF, sp.ATOL_REF)
        out[cid] = (c, v, dict(c.last))
    return out


def test_hybrid_loop_terminates_at_every_tolerance(deadline):
    deadline(60)
    for cid in (1, 2):
        c = sp.Case(cid)
        for rtol in (1e-3, 1e-6, 1e-9):
            v, nfev = c.hybrid(rtol, rtol * 1e-2)
            assert len(v) == len(c.grid)
            assert np.all(np.isfinite(v))
            assert nfev > 0
            assert c.last["restarts"] < sp.MAX_RESTARTS


def test_without_moving_past_the_root_the_stall_guard_raises(monkeypatch, deadline):
    # The old hang: a breakaway root with a margin <= 0 is not released, the next segment
    # finds the same root again. The guard must turn that into an error, not a loop.
    deadline(20)
    monkeypatch.setattr(sp, "NUDGE_MAX", 0.0)
    with pytest.raises(sp.HybridStuck, match="advanced less than"):
        sp.Case(2).hybrid(1e-6, 1e-8)


def test_restart_cap_raises(deadline):
    deadline(20)
    with pytest.raises(sp.HybridStuck, match="more than 5 event restarts"):
        sp.Case(1).hybrid(1e-6, 1e-8, max_restarts=5)


def test_case1_stops_like_the_rust_model_and_rests_at_the_end(refs):
    c, v, last = refs[1]
    stops = [t for t, i in last["stops"] if i == 1]
    assert len(stops) == RUST_CASE1_STOPS
    assert abs(stops[0] - RUST_CASE1_FIRST_STOP) < 1e-6
    assert abs(stops[-1] - RUST_CASE1_LAST_STOP) < 1e-5
    # At rest for good after the last stop: velocity exactly 0, every axis stopped.
    assert last["y_end"][6] == 0.0
    assert last["modes_end"] == [sp.STOPPED] * 3
    after = c.grid > stops[-1] + 1e-3
    assert after.sum() > 5000
    assert np.all(v[after] == 0.0)
    # The X axis feels no force (swing in the Y-Z plane): it never moves.
    assert all(i == 1 for _, i in last["stops"] + [(t, i) for t, i, _ in last["releases"]])


def test_case2_breakaway_where_the_sine_exceeds_cbar(refs):
    c, v, last = refs[2]
    # Hanging payload at rest: the rope's holding force is the net force 12 sin(pi t); it
    # breaks away when that reaches Cbar_l = 9.81 N.
    t_break = math.asin(9.81 / 12.0) / math.pi
    first_release = last["releases"][0]
    assert first_release[1] == 2 and first_release[2] == sp.POS
    assert abs(first_release[0] - t_break) < 1e-9
    stops = [t for t, i in last["stops"] if i == 2]
    assert len(stops) == RUST_CASE2_STOPS
    assert abs(stops[0] - RUST_CASE2_FIRST_STOP) < 1e-6
    # Before the first breakaway the rope is stuck: velocity exactly 0.
    assert np.all(v[c.grid < t_break - 1e-3] == 0.0)


def test_holding_force_of_the_hanging_rope_is_the_net_force():
    c = sp.Case(2)
    y = list(c.q0) + [0.0] * 5
    for t in (0.1, 0.7, 1.3, 3.9):
        qdd, hold = c.hybrid_eval(t, y, [sp.STOPPED] * 3)
        assert abs(hold[2] - 12.0 * math.sin(math.pi * t)) < 1e-12
        assert max(abs(a) for a in qdd) < 1e-12


def numerics_system(c, y, fric):
    """M and r = Q - h - G of NUMERICS.md "One evaluation", written out again with numpy."""
    _, _, L, a, b, _, _, Ld, ad, bd = y
    sa, ca, sb, cb = math.sin(a), math.cos(a), math.sin(b), math.cos(b)
    mp, mpL = c.mp, c.mp * L
    M = np.diag([c.m00, c.m11, c.m22, mpL * L, mpL * L * sa * sa])
    for (i, j, val) in ((0, 2, mp * sa * sb), (0, 3, mpL * ca * sb), (0, 4, mpL * sa * cb),
                        (1, 2, mp * ca), (1, 3, -mpL * sa)):
        M[i, j] = M[j, i] = val
    h = np.array([
        mp * (L * (2 * ad * bd * ca * cb - (ad * ad + bd * bd) * sa * sb)
              + 2 * Ld * (ad * sb * ca + bd * sa * cb)),
        -mp * ad * (L * ad * ca + 2 * Ld * sa),
        -mpL * (ad * ad + bd * bd * sa * sa),
        mpL * (2 * Ld * ad - L * bd * bd * sa * ca),
        mpL * bd * (2 * L * ad * sa * ca + 2 * Ld * sa * sa),
    ])
    g = c.mpg * np.array([0.0, 0.0, -sa * cb, -L * ca * cb, L * sa * sb])
    Q = np.array([-fric[0], -fric[1], -fric[2], -sp.D_ALPHA * ad, -sp.D_BETA * bd])
    return M, Q - h - g


def test_evaluation_matches_an_independent_solve():
    c = sp.Case(1)  # zero input: Q is friction and damping only
    rng = np.random.default_rng(7)
    for k in range(40):
        y = [0.25, 0.3, rng.uniform(0.2, 0.5), math.pi / 2 + rng.uniform(-1, 1),
             rng.uniform(-0.5, 0.5)] + list(rng.uniform(-1, 1, 5))
        fric = list(rng.uniform(-1, 1, 3))
        stopped = [bool(k & 1), bool(k & 2), bool(k & 4)]
        qdd, hold = c.solve(0.0, y, fric, stopped)
        M, r = numerics_system(c, y, fric)
        free = [j for j in range(5) if j > 2 or not stopped[j]]
        x = np.zeros(5)
        x[free] = np.linalg.solve(M[np.ix_(free, free)], r[free])
        assert np.allclose(qdd, x, rtol=1e-10, atol=1e-12)
        for i in range(3):
            if stopped[i]:
                assert qdd[i] == 0.0
                # Holding force: F_i - (M_i qdd + h_i + G_i), with F_i = 0 here and
                # h_i + G_i = -fric_i - r_i (the friction of a stopped axis is not used).
                expect = r[i] + fric[i] - M[i] @ x
                assert abs(hold[i] - expect) < 1e-10 * (1.0 + abs(expect))


def test_hybrid_reference_agrees_with_stiff_tanh_within_smoothing_error(refs):
    # tanh(gamma v) tends to the hybrid model as gamma grows: at gamma 1e4 the RMSE is the
    # smoothing error (Rust ode45: 1.2e-4 and 2.9e-4 m/s), at gamma 1e3 about 8x larger.
    for cid, bound in ((1, 2.5e-4), (2, 5e-4)):
        c, ref, _ = refs[cid]
        v4, _ = sp.tanh_run(c, 1e4, "LSODA", 1e-7, 1e-9)
        v3, _ = sp.tanh_run(c, 1e3, "LSODA", 1e-7, 1e-9)
        e4, e3 = sp.rmse(v4, ref), sp.rmse(v3, ref)
        assert e4 < bound, (cid, e4)
        assert e3 > 4.0 * e4, (cid, e3, e4)


def test_rk45_tanh_error_falls_with_rtol():
    # Against its own tight solution (the smoothing error is the same for every rtol).
    c = sp.Case(2)
    tight, _ = sp.tanh_run(c, 1e2, "RK45", 1e-11, 1e-13)
    errs = [sp.rmse(sp.tanh_run(c, 1e2, "RK45", r, r * 1e-2)[0], tight)
            for r in (1e-3, 1e-5, 1e-7)]
    assert errs[0] > errs[1] > errs[2], errs
    assert errs[2] < 1e-6


def test_hybrid_error_falls_with_rtol(refs):
    c, ref, _ = refs[1]
    errs = [sp.rmse(c.hybrid(r, r * 1e-2)[0], ref) for r in (1e-4, 1e-7, 1e-10)]
    assert errs[0] > errs[1] > errs[2], errs
    assert errs[2] < 1e-9


def test_json_written_atomically_and_foreign_file_kept(tmp_path, capsys):
    foreign = tmp_path / "notes.json"
    foreign.write_text("not ours")
    with pytest.raises(SystemExit):
        sp.main(["--quick", "--case", "2", "--json", str(foreign)])
    assert foreign.read_text() == "not ours"
    out = tmp_path / "peer.json"
    sp.main(["--quick", "--case", "2", "--cap", "0.5", "--json", str(out)])
    d = json.loads(out.read_text())
    assert d["tool"] == "scipy_peer" and [c["case"] for c in d["cases"]] == [2]
    pts = [p for p in d["cases"][0]["points"] if "time_s" in p]
    assert any(p["model"] == "hybrid" for p in pts)
    assert all(p["time_s"] > 0 and p["rmse"] >= 0 for p in pts)
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []
    # An earlier output may be replaced.
    sp.main(["--quick", "--case", "2", "--cap", "0.5", "--json", str(out)])
    capsys.readouterr()

"""pytest: the stranger plant's own physics, and `crane diagnose` on the stranger cases.

    CRANE_BIN=target/release/crane python3 -m pytest -q tools/strangers/test_strangers.py

The sweep (generation + scoring of every case) runs when the crane binary exists; set
STRANGERS_CASES=N to score only the first N cases (causes interleaved), STRANGERS_TIMEOUT=S
for the per-case timeout (default 300 s; a timeout fails `test_every_case_ran`);
STRANGERS_SWEEP=0 skips the sweep (the plant's own tests only).
"""

from __future__ import annotations

import json
import math
import os
import sys

import numpy as np
import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

import cases as C  # noqa: E402
import plant as P  # noqa: E402
import score as S  # noqa: E402

# Per-cause accuracy floors (right / total) asserted on the sweep: what `crane diagnose` of
# main measured on 2026-11-27 (README.md, its latest section: 57 / 70), less one case per cause. The slack of one
# case is for another machine's numpy rounding the last bit of a sample differently, which
# can move a quantised sample by a count; a regression of two cases in one cause fails.
# Stribeck is measured at 1 since velocity weakening's own onset and kinetic level (2026-11-28:
# s036 lost, four Stribeck cases of seed 11 gained); its floor stays at 1 / 6, not lowered.
MEASURED_RIGHT = {
    "none": 10, "stiction": 6, "stribeck_friction": 2, "localized_friction": 6,
    "input_deadzone": 4, "input_saturation": 6, "input_delay": 4, "restoring_force": 6,
    "force_offset": 6, "direction_asymmetry": 6, "load_dependent_friction": 1,
}
FLOORS = {c: max(MEASURED_RIGHT[c] - 1, 0) / C.CAUSE_COUNTS[c] for c in C.CAUSES}


# ---------------------------------------------------------------------------------------------
# Plant physics


def test_below_breakaway_never_moves_to_the_bit():
    p = P.Plant(J=0.7, Fc_p=2.0, Fc_n=2.0, Fs_p=3.0, Fs_n=2.5, Dv_p=1.0, Dv_n=1.0)
    T = 0.002
    t = np.arange(2000) * T
    sn = np.sin(2 * np.pi * 0.5 * t)
    cmd = np.where(sn >= 0, 2.999 * sn, 2.499 * sn)  # up to just below Fs_+ and Fs_-
    x = P.simulate_one(p, cmd, T, x0=0.123456789, n_sub=2)
    assert np.all(x == 0.123456789)


def test_load_dependent_and_bump_raise_the_holding_force():
    # 3.5 N > Fs = 3 N, but mu |F| = 0.2 * 3.5 = 0.7 N more: holds; a bump of 1 N as well
    p = P.Plant(J=1.0, Fc_p=2.0, Fc_n=2.0, Fs_p=3.0, Fs_n=3.0, mu=0.2)
    x = P.simulate_one(p, np.full(500, 3.5), 0.002)
    assert np.all(x == 0.0)
    p = P.Plant(J=1.0, Fc_p=2.0, Fc_n=2.0, Fs_p=3.0, Fs_n=3.0, bump_A=1.0, bump_c=0.01, bump_w=0.02)
    x = P.simulate_one(p, np.full(500, 3.5), 0.002)
    assert np.all(x == 0.0)
    x = P.simulate_one(p.replace(bump_A=0.0), np.full(500, 3.5), 0.002)
    assert x[-1] > 0


def test_load_share_and_dead_band_equal_their_equivalent_plants_while_the_drive_pushes():
    # identifiable.py's claim: while the input pushes the motion, load-dependent friction is
    # the plant scaled by 1 / (1 - mu) (coasting at zero input too), and a dead band a dry
    # level higher by g d (while |u| > d); braking, or coasting with the input inside the
    # band, tells them apart
    import identifiable as I

    T = 0.002
    push = np.r_[np.linspace(0.0, 9.0, 300), np.full(300, 9.0), np.zeros(600)]
    brake = np.r_[push[:600], np.full(60, -6.0), np.zeros(540)]
    for cause, kw, same in (("load_dependent_friction", dict(mu=0.25), 1200),
                            ("input_deadzone", dict(dz=1.5, gain=2.0), 600)):
        p = P.Plant(J=0.8, Fc_p=2.0, Fc_n=2.0, Fs_p=2.5, Fs_n=2.5, Dv_p=3.0, Dv_n=3.0, **kw)
        q = I.equivalent(type("Case", (), {"plant": p, "cause": cause}))
        a, b = (P.simulate_one(pl, push, T, n_sub=4) for pl in (p, q))
        assert np.ptp(a) > 0.1
        assert np.max(np.abs(a[:same] - b[:same])) < 1e-9 * np.ptp(a), cause
        a, b = (P.simulate_one(pl, brake, T, n_sub=4) for pl in (p, q))
        assert np.max(np.abs(a - b)) > 1e-3 * np.ptp(a), cause


def test_frictionless_mass_constant_force():
    J, F, T = 2.5, 3.0, 0.01
    x = P.simulate_one(P.Plant(J=J), np.full(400, F), T, n_sub=2)
    t = np.arange(400) * T
    assert np.max(np.abs(x - F * t**2 / (2 * J))) < 1e-10


def test_coulomb_slide_stops_at_analytic_time_and_place():
    # push 5 N for 1 s against 2 N Coulomb (J = 1): v = 3 m/s at 1 s, x = 1.5 m;
    # then decelerates at 2 m/s^2: stops at t = 2.5 s, x = 1.5 + 9/4 = 3.75 m, and stays
    p = P.Plant(J=1.0, Fc_p=2.0, Fc_n=2.0, Fs_p=2.0, Fs_n=2.0)
    T = 0.01
    cmd = np.r_[np.full(100, 5.0), np.zeros(300)]
    stamps = np.r_[np.arange(400) * T, [2.498, 2.502]]
    stamps.sort()
    x = P.simulate_one(p, cmd, T, stamps=np.unique(stamps), n_sub=8)
    st = np.unique(stamps)
    x_end = 3.75
    before = st < 2.5
    # analytic position while decelerating
    sel = (st > 1.0) & before
    tt = st[sel]
    xa = 1.5 + 3 * (tt - 1) - (tt - 1) ** 2
    # on the step grid exact; between steps the logger interpolates linearly (a h^2 / 8)
    on_grid = np.abs(tt / (T / 8) - np.round(tt / (T / 8))) < 1e-6
    err = np.abs(x[sel] - xa)
    assert np.max(err[on_grid]) < 1e-9
    assert np.max(err) < 2.0 * (T / 8) ** 2 / 8 + 1e-9
    assert np.all(np.abs(x[~before] - x_end) < 1e-9)
    # with viscous friction the stop is exp-linear: v' = -(Fc + D v)/J, v(0) = v0
    J, Fc, D, v0 = 2.0, 1.0, 3.0, 0.0
    p = P.Plant(J=J, Fc_p=Fc, Fc_n=Fc, Fs_p=Fc, Fs_n=Fc, Dv_p=D, Dv_n=D)
    x = P.simulate_one(p, np.r_[np.full(150, 10.0), np.zeros(250)], T, n_sub=4)
    # end of the push: v = (10 - Fc)/D (1 - exp(-D t / J)) at t = 1.5
    v0 = (10 - Fc) / D * (1 - math.exp(-D * 1.5 / J))
    t_stop = J / D * math.log(1 + D * v0 / Fc)
    x_push = (10 - Fc) / D * (1.5 - J / D * (1 - math.exp(-D * 1.5 / J)))
    x_stop = x_push + (J / D) * (v0 + Fc / D) * (1 - math.exp(-D * t_stop / J)) - Fc / D * t_stop
    assert abs(x[-1] - x_stop) < 1e-8


def test_stribeck_curve_value():
    p = P.Plant(Fc_p=2.0, Fc_n=1.5, Fs_p=3.0, Fs_n=2.5, vs=0.1, Dv_p=4.0, Dv_n=5.0, mu=0.1)
    v = np.array([0.05, -0.05, 0.1, 1.0])
    f = p.friction(np.zeros(4), v, Fa=10.0)
    want = [
        2.0 + 1.0 * math.exp(-0.25) + 1.0 + 4.0 * 0.05,
        -(1.5 + 1.0 * math.exp(-0.25) + 1.0) - 5.0 * 0.05,
        2.0 + math.exp(-1.0) + 1.0 + 0.4,
        2.0 + math.exp(-100.0) + 1.0 + 4.0,
    ]
    assert np.allclose(f, want, rtol=0, atol=1e-12)
    # vs = 0: classical stiction, the static level does not act while moving
    p0 = p.replace(vs=0.0)
    assert abs(p0.friction(0.0, 1e-6, 0.0) - (2.0 + 4e-6)) < 1e-12


def test_stribeck_breakaway_then_weakening():
    # ramp through breakaway: motion starts exactly when the force exceeds Fs (3 N)
    p = P.Plant(J=1.0, Fc_p=2.0, Fc_n=2.0, Fs_p=3.0, Fs_n=3.0, vs=0.05, Dv_p=1.0, Dv_n=1.0)
    T = 0.001
    cmd = np.arange(4000) * 0.001  # 1 N/s
    x = P.simulate_one(p, cmd, T, n_sub=2)
    moving = np.flatnonzero(x != 0)
    assert 3.0 < moving[0] * T <= 3.0 + 2.5 * T


def test_effort_saturation_deadband_offset_delay():
    p = P.Plant(gain=2.0, usat=3.0, dz=0.5)
    assert np.allclose(p.effort([0.4, -0.4, 1.0, -2.0, 5.0, -5.0]), [0, 0, 1.0, -3.0, 5.0, -5.0])
    # a delay shifts the free response by the delay exactly (rounded to internal steps)
    T = 0.01
    cmd = np.r_[np.zeros(10), np.full(200, 1.0)]
    x0 = P.simulate_one(P.Plant(J=1.0), cmd, T, n_sub=2)
    x1 = P.simulate_one(P.Plant(J=1.0, delay=0.05), cmd, T, n_sub=2)
    assert np.allclose(x1[5:], x0[:-5], atol=1e-12)
    # restoring: spring equilibrium F / k, gravity asin(F / k)
    xs = P.simulate_one(P.Plant(J=1.0, k_lin=50.0, Dv_p=20, Dv_n=20), np.full(1000, 5.0), T, n_sub=2)
    assert abs(xs[-1] - 0.1) < 1e-6
    xg = P.simulate_one(P.Plant(J=1.0, k_sin=10.0, center=0.2, Dv_p=8, Dv_n=8), np.full(2000, 5.0), T, n_sub=2)
    assert abs(xg[-1] - (0.2 + math.asin(0.5))) < 1e-6


def test_reversal_stops_and_restarts_exactly():
    # a spring pulls back: each swing stops exactly when v crosses zero, then the stick test
    # decides; with a strong spring it reverses, with a weak one it sticks for good
    p = P.Plant(J=1.0, k_lin=100.0, Fc_p=1.0, Fc_n=1.0, Fs_p=1.0, Fs_n=1.0)
    T = 0.001
    x = P.simulate_one(p, np.zeros(3000), T, x0=0.1, n_sub=2)
    # Coulomb-damped oscillator: amplitude drops by 2 Fc / k = 0.02 per half swing; rests
    # where |k x| <= Fs: 0.1 -> -0.08 -> 0.06 -> -0.04 -> 0.02 -> 0.0 (stops within the band)
    assert abs(x[-1]) <= 0.01 + 1e-9
    ext = [0.1, -0.08, 0.06, -0.04, 0.02]
    # the turning points, analytic
    w = 10.0
    for i, e in enumerate(ext[1:], start=1):
        ti = i * math.pi / w
        k = int(round(ti / T))
        assert abs(x[k] - e) < 5e-4, (i, x[k], e)
    assert np.all(x[int(round(5 * math.pi / w / T)) + 2 :] == x[-1])


def test_step_halving_converges():
    p = P.Plant(J=0.5, Fc_p=1.0, Fc_n=1.2, Fs_p=2.0, Fs_n=2.0, vs=0.05, Dv_p=1.0, Dv_n=1.0,
                k_lin=20.0, bump_A=0.5, bump_c=0.05, bump_w=0.02, mu=0.1)
    T = 0.005
    t = np.arange(600) * T
    cmd = 3 * np.sin(2 * np.pi * 0.7 * t)
    st = t.copy()
    a, b = P.simulate([P.Lane(p, cmd, T, st, n_sub=4), P.Lane(p, cmd, T, st, n_sub=32)])
    assert np.ptp(a) > 0.05 and np.count_nonzero(np.diff(a) == 0) > 20  # moves and sticks
    assert np.max(np.abs(a - b)) < 1e-7


def test_quantisation_and_async_refresh_pattern():
    q = 1e-5
    x = np.array([0.0, 0.4e-5, 0.6e-5, -1.26e-5, 3.3e-3])
    xq = P.quantise(x, q)
    assert np.allclose(xq / q, np.round(xq / q), atol=1e-9)
    assert np.allclose(xq, [0, 0, 1e-5, -1e-5, 3.3e-3])
    m = P.refresh_mask(12, 4, 2)
    assert m.tolist() == [True, False, True, False, False, False, True, False, False, False, True, False]
    v = np.arange(12.0)
    assert P.hold(v, m).tolist() == [0, 0, 2, 2, 2, 2, 6, 6, 6, 6, 10, 10]
    rng = np.random.default_rng(1)
    st = P.jittered_stamps(1000, 0.01, rng)
    d = np.diff(st)
    assert st[0] == 0 and d.min() >= 0.4 * 0.01 - 1e-12 and d.max() <= 1.6 * 0.01 + 1e-12
    assert np.std(d) > 0.05 * 0.01


def test_written_async_logs_follow_the_refresh(tmp_path):
    # one generated asynchronous case of each style: the fields change only on refresh rows
    for cause, idx in (("none", 1), ("none", 3)):
        cs = C.draw_case(cause, idx, 0)
        cs.case_id = f"t{idx}"
        assert cs.asynchronous
        xs = [np.zeros(len(r.stamps)) + 0.01 * np.arange(len(r.stamps)) for r in cs.runs]
        C.write_case(cs, xs, str(tmp_path), None)
        f = os.path.join(tmp_path, cs.case_id, "data", cs.runs[0].name + ".csv")
        lines = [ln for ln in open(f).read().splitlines() if not ln.startswith("#")][1:]
        ex, px, eu, pu = cs.refresh
        rows = [ln.split(",") for ln in lines]
        if cs.async_style == "blank":
            assert any(r[1] == "" for r in rows) and any(r[2] == "" for r in rows)
            nonempty = [i for i, r in enumerate(rows) if r[1] != ""]
            assert len(nonempty) > 10
        else:
            xcol = [r[1] for r in rows]
            changes = [i for i in range(1, len(xcol)) if xcol[i] != xcol[i - 1]]
            assert all((i % ex) == (px % ex) for i in changes)
        truth = json.load(open(os.path.join(tmp_path, cs.case_id, "truth.json")))
        assert truth["asynchronous"]
        data_dir = os.path.join(tmp_path, cs.case_id, "data")
        for fn in os.listdir(data_dir):  # no truth inside the data directory
            assert "truth" not in fn
            txt = open(os.path.join(data_dir, fn)).read()
            assert cause not in txt


def test_cases_are_seeded_and_cover_the_plan():
    a = C.draw_case("stiction", 2, 0)
    b = C.draw_case("stiction", 2, 0)
    assert a.seed == b.seed and all(np.array_equal(r.cmd, s.cmd) for r, s in zip(a.runs, b.runs))
    todo = C.case_list()
    assert len(todo) >= 66
    for cause, n in C.CAUSE_COUNTS.items():
        assert n >= (10 if cause == "none" else 6)
        sync = [i for c, i, _ in todo if c == cause and i % 2 == 0]
        asy = [i for c, i, _ in todo if c == cause and i % 2 == 1]
        assert sync and asy


# ---------------------------------------------------------------------------------------------
# The sweep


@pytest.fixture(scope="module")
def sweep(tmp_path_factory):
    if os.environ.get("STRANGERS_SWEEP") == "0":
        pytest.skip("STRANGERS_SWEEP=0: the plant's own tests only")
    binary = S.crane_bin()
    if not os.path.exists(binary):
        pytest.skip(f"crane binary absent at {binary} (set CRANE_BIN)")
    out = tmp_path_factory.mktemp("strangers")
    n = os.environ.get("STRANGERS_CASES")
    args = ["--out", str(out), "--jobs", "2", "--json", str(out / "summary.json")]
    if n:
        args += ["--cases", n]
    if os.environ.get("STRANGERS_TIMEOUT"):
        args += ["--timeout", os.environ["STRANGERS_TIMEOUT"]]
    assert S.main(args) == 0
    return json.load(open(out / "summary.json"))


def test_every_case_ran(sweep):
    bad = [r for r in sweep["cases"] if r["error"] == "timeout"]
    assert not bad, bad
    for r in sweep["cases"]:
        if r["error"]:
            assert r["error"].startswith("exit "), r  # a clear error, not a crash signal
            assert "panicked" not in r["error"], r
            assert r["error"].split(":")[0] not in ("exit None", "exit -6", "exit -11", "exit 101"), r


def test_no_honesty_failure(sweep):
    fails = [(r["case"], h) for r in sweep["cases"] for h in r["honesty"]]
    assert not fails, fails


def test_per_cause_floors(sweep):
    low = []
    for c, s in sweep["summary"]["per_cause"].items():
        if s["right"] / s["total"] < FLOORS.get(c, 0.0) - 1e-9:
            low.append((c, s["right"], s["total"], FLOORS[c]))
    assert not low, low


def test_async_input_is_what_the_log_shows():
    # asynchronous logs: the drive applies each published command from its stamp on (at most
    # one internal step later) until the next one; the rows in between show the same value
    cs = C.draw_case("none", 1, 0)
    assert cs.asynchronous
    r = cs.runs[0]
    u, h, nsub = C.applied_command(cs, r)
    assert nsub == 1 and h <= (1.0 / cs.rate) / P.MIN_SUB_ASYNC + 1e-15
    _, _, eu, pu = cs.refresh
    fresh = P.refresh_mask(len(r.cmd), eu, pu)
    shown = P.hold(C.logged_input(cs, r), fresh)  # the held u column, noise aside
    k = np.ceil(r.stamps / h - 1e-9).astype(int)  # the first internal step after each stamp
    k = np.minimum(k, len(u) - 1)
    assert np.array_equal(u[k][1:-1], shown[1:-1])

"""Every bad input raises a typed Python exception naming what is wrong; none aborts the
process (checked in a subprocess too)."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import numpy as np
import pytest

import crane_twin as ct


@pytest.mark.parametrize(
    "kwargs, field",
    [
        ({"payload_mass": -1.0}, "payload_mass"),
        ({"x": {"viscous_pos": float("nan")}}, "x.viscous_pos"),
        ({"rope": {"min": 0.7}}, "rope.min"),
        ({"y": {"dry_neg": [1, 2, 3, 4, float("inf")]}}, "y.dry_neg[4]"),
        ({"gravity": -9.81}, "gravity"),
    ],
)
def test_bad_parameter_names_its_field(kwargs, field):
    with pytest.raises(ct.ParameterError) as e:
        ct.Params(**kwargs)
    assert e.value.field == field
    assert field in str(e.value)


def test_bad_configuration_and_state():
    with pytest.raises(ct.ParameterError) as e:
        ct.Crane(h=float("nan"))
    assert e.value.field == "config.h" and e.value.problem == "not_finite"
    with pytest.raises(ct.ParameterError) as e:
        ct.Crane(h=-1e-3)
    assert e.value.problem == "not_positive"
    with pytest.raises(ct.ParameterError) as e:
        ct.Crane(law="tanh", gamma=0.0)
    assert e.value.field == "config.law.gamma"
    with pytest.raises(ct.ParameterError) as e:
        ct.Crane(state=[0.9, 0.3, 0.35, np.pi / 2, 0, 0, 0, 0, 0, 0])
    assert e.value.field == "state.q[0]" and e.value.problem == "out_of_limits"
    with pytest.raises(ct.ParameterError) as e:
        ct.Crane(state=[0.2, 0.3, 0.35, 0.01, 0, 0, 0, 0, 0, 0])
    assert e.value.field == "state.q[3]"
    with pytest.raises(ct.ParameterError) as e:
        ct.Crane(stiction=[(1.2, 0.01), (0.9, 0.01), None])
    assert e.value.field == "stiction[1].ratio"
    with pytest.raises(ct.InputError, match="law"):
        ct.Crane(law="coulomb")
    with pytest.raises(ct.InputError, match="stiction"):
        ct.Crane(stiction="yes")
    with pytest.raises(ct.InputError, match="state"):
        ct.Crane(state=[1, 2, 3])
    with pytest.raises(ct.InputError, match="params"):
        ct.Crane(params=42)
    c = ct.Crane()
    with pytest.raises(ct.ParameterError):
        c.state = [0.2, 0.3, 0.35, np.pi / 2, 0, float("nan"), 0, 0, 0, 0]


def test_bad_inputs():
    c = ct.Crane()
    before = c.state
    with pytest.raises(ct.StepError) as e:
        c.step([0.0, float("nan"), 0.0])
    assert e.value.kind == "input_not_finite" and e.value.axis == 1
    np.testing.assert_array_equal(c.state, before)
    assert c.steps == 0
    with pytest.raises(ct.InputError):
        c.step([1.0, 2.0])
    with pytest.raises(ct.InputError):
        c.step("abc")
    with pytest.raises(ct.InputError, match=r"\(n, 3\)"):
        ct.rollout(np.zeros((10, 2)))
    with pytest.raises(ct.InputError, match=r"\(n, 3\)"):
        ct.rollout(np.zeros(30))
    with pytest.raises(ct.InputError, match=r"u\[4, 1\]"):
        u = np.zeros((10, 3))
        u[4, 1] = np.inf
        ct.rollout(u)
    with pytest.raises(ct.InputError, match="float64"):
        ct.rollout([["a", "b", "c"]])
    with pytest.raises(ct.InputError, match="u"):
        ct.rollouts([ct.Params()] * 2, np.zeros((3, 10, 3)))
    with pytest.raises(ct.InputError, match="threads"):
        ct.rollouts([ct.Params()], np.zeros((10, 3)), threads=0)
    with pytest.raises(ct.InputError, match="params_list"):
        ct.rollouts(5, np.zeros((10, 3)))
    with pytest.raises(ct.ParameterError) as e:
        ct.rollouts([ct.Params(), {"x": {"gain": 0.0}}], np.zeros((10, 3)))
    assert e.value.field == "x.gain" and "params_list[1]" in str(e.value)
    b = ct.CraneBatch([ct.Params()] * 2)
    with pytest.raises(ct.InputError):
        b.step(np.zeros((3, 3)))
    with pytest.raises(ct.InputError):
        b.reset_sim(2)
    # Empty input: no step, one row.
    r = ct.rollout(np.zeros((0, 3)))
    assert r["q"].shape == (1, 5)


def test_bad_toml(tmp_path):
    # the project's `file:line:column:` form, as the CLI prints it
    with pytest.raises(ct.ParamsFileError, match=r"<string>:2:\d+: "):
        ct.Params.from_toml("payload_mass = 1.0\n[x\n")
    text = ct.Params().to_toml()
    with pytest.raises(ct.ParamsFileError, match="unknown field"):
        ct.Params.from_toml(text + "\nwind = 3\n")
    with pytest.raises(ct.ParamsFileError, match="missing field"):
        ct.Params.from_toml(text.replace("gravity = 9.81\n", ""))
    with pytest.raises(ct.ParamsFileError, match="x.gain"):
        ct.Params.from_toml(text.replace("gain = 3.2", "gain = -3.2", 1))
    bad = tmp_path / "bad.toml"
    bad.write_text("payload_mass = 'heavy'\n")
    with pytest.raises(ct.ParamsFileError, match="bad.toml"):
        ct.Params.load(bad)
    with pytest.raises(ct.ParamsFileError, match="missing.toml"):
        ct.Crane(params=str(tmp_path / "missing.toml"))
    with pytest.raises(ct.InputError, match="unknown parameter"):
        ct.Params().replace({"x.friction": 1.0})


def test_no_input_aborts_the_process():
    """A run of hostile inputs in a fresh interpreter: each must raise a CraneError (or a
    TypeError from Python's own argument parsing), and the interpreter must exit normally."""
    code = textwrap.dedent(
        """
        import numpy as np, crane_twin as ct
        bad = [np.nan, np.inf, -np.inf, 1e308, -1e308, 0.0, -0.0, 1e-320]
        n = 0
        for v in bad:
            for call in (
                lambda: ct.Crane(h=v),
                lambda: ct.Crane(params={"payload_mass": v}),
                lambda: ct.Crane(state=[v] * 10),
                lambda: ct.Crane(stiction=(v, v)),
                lambda: ct.rollout(np.full((5, 3), v)),
                lambda: ct.rollouts([ct.Params()], np.full((4, 5, 3), v)),
                lambda: ct.Crane().advance([v, v, v], 3),
                lambda: ct.Params().replace({"rope.min": v}),
            ):
                try:
                    call()
                except (ct.CraneError, TypeError):
                    n += 1
        for junk in (None, "x", b"\\x00", [], {}, object(), np.zeros((2, 2, 2, 2))):
            for call in (lambda: ct.rollout(junk), lambda: ct.Crane(state=junk if junk is not None else 1),
                         lambda: ct.Crane(params=junk if junk is not None else 1), lambda: ct.Params.from_toml(str(junk))):
                try:
                    call()
                except (ct.CraneError, TypeError):
                    n += 1
        print("survived", n)
        """
    )
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, p.stderr
    assert "survived" in p.stdout


def test_negative_step_count_is_an_input_error():
    with pytest.raises(ct.InputError, match="n"):
        ct.Crane().advance([0.0, 0.0, 0.0], -1)


@pytest.mark.skipif(sys.platform == "win32", reason="SIGALRM")
def test_a_long_advance_answers_ctrl_c():
    import signal
    import time

    def interrupt(signum, frame):
        raise KeyboardInterrupt

    old = signal.signal(signal.SIGALRM, interrupt)
    signal.setitimer(signal.ITIMER_REAL, 0.2)
    t0 = time.monotonic()
    try:
        with pytest.raises(KeyboardInterrupt):
            ct.Crane().advance([0.0, 0.0, 0.0], 10**12)
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)
    assert time.monotonic() - t0 < 10, "the interrupt waited for the loop"

"""`crane_twin.linearize` (issue 23): the linear model's response to small input steps matches
the nonlinear hybrid model's around a sliding operating point, and a stuck axis (mode 0),
where friction is not differentiable, is refused with a clear error."""

from __future__ import annotations

import copy

import numpy as np
import pytest

import crane_twin as ct

H = 1e-3


def _operating_point(u0, stiction=None, steps=400) -> ct.Crane:
    """A crane driven from rest by ``u0`` for ``steps`` steps (X and Y then slide)."""
    c = ct.Crane(stiction=stiction, h=H)
    c.advance(u0, steps)
    return c


def _linear_response(a, b, du, n):
    """``dx(k h)`` of ``d(dx)/dt = A dx + B du`` from ``dx(0) = 0`` by RK4 with step ``H``."""
    f = lambda d: a @ d + b @ du  # noqa: E731
    d = np.zeros(a.shape[0])
    out = [d]
    for _ in range(n):
        k1 = f(d)
        k2 = f(d + H / 2 * k1)
        k3 = f(d + H / 2 * k2)
        k4 = f(d + H * k3)
        d = d + H / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        out.append(d)
    return np.array(out)


def _nonlinear_deviation(c, u0, du, n):
    """States of ``c`` under ``u0 + du`` minus under ``u0``, for ``n`` steps."""
    base, moved = copy.copy(c), copy.copy(c)
    x0 = c.state
    xa = np.array([x0] + [base.step(u0) for _ in range(n)])
    xb = np.array([x0] + [moved.step(u0 + du) for _ in range(n)])
    assert base.modes[:2] == moved.modes[:2] == c.modes[:2], "no axis stopped on the way"
    return xb - xa


CASES = [
    # u0 [V], stiction, expected modes: X and Y slide; the rope is held, or slides down
    ([5.0, -5.0, 0.0], None, (1, -1, 0)),
    ([5.0, -5.0, 1.0], None, (1, -1, 1)),
    ([4.0, 5.0, -1.5], (1.3, 0.005), (1, 1, 0)),
]


@pytest.mark.parametrize("u0, stiction, modes", CASES)
def test_the_linear_model_follows_the_nonlinear_one_for_a_small_input_step(u0, stiction, modes):
    u0 = np.array(u0)
    c = _operating_point(u0, stiction)
    assert c.modes == modes
    a, b = ct.linearize(c.params, c.state, u0, stiction=stiction)
    assert a.shape == (10, 10) and b.shape == (10, 3)
    assert a.dtype == b.dtype == np.float64
    du = np.array([0.2, -0.2, 0.2])  # 2 % of the range; the held rope stays held
    n = 200  # 0.2 s: about a quarter of the swing period
    dn = _nonlinear_deviation(c, u0, du, n)
    dl = _linear_response(a, b, du, n)
    scale = np.abs(dn).max(axis=0)
    assert scale[5] > 3e-3 and scale[6] > 3e-3, "the input step moves X and Y measurably"
    assert scale[8] > 3e-3 and scale[9] > 3e-3, "and swings the payload"
    moving = scale > 0
    rel = np.abs(dn - dl).max(axis=0)[moving] / scale[moving]
    assert rel.max() < 0.05, rel
    total = np.linalg.norm(dn - dl) / np.linalg.norm(dn)
    assert total < 0.02, total
    # A matters: the input alone (A = 0) is far worse
    without_a = _linear_response(np.zeros_like(a), b, du, n)
    assert np.linalg.norm(dn - without_a) / np.linalg.norm(dn) > 10 * total
    if modes[2] == 0:
        assert not moving[2] and not moving[7], "a held rope keeps its length"
        assert np.all(dl[:, [2, 7]] == 0)


def test_ordering_units_and_signs():
    u0 = np.array([5.0, -5.0, 1.0])
    c = _operating_point(u0)
    a, b = ct.linearize(c.params, c.state, u0)
    # kinematics: d(q)/dt = qd, exactly (differences of the velocities themselves)
    np.testing.assert_array_equal(a[:5, 5:], np.eye(5))
    np.testing.assert_array_equal(a[:5, :5], np.zeros((5, 5)))
    np.testing.assert_array_equal(b[:5], np.zeros((5, 3)))
    # each drive accelerates its own axis forward [m/s^2 per V]; positive u_l lowers (Ld > 0)
    assert b[5, 0] > 0.3 and b[6, 1] > 0.3 and b[7, 2] > 0.05
    # viscous friction damps each sliding axis [1/s]
    assert a[5, 5] < -10 and a[6, 6] < -10 and a[7, 7] < -10
    # a swing angle falls back towards hanging: d(alphadd)/d(alpha) < 0, d(betadd)/d(beta) < 0
    assert a[8, 3] < 0 and a[9, 4] < 0
    # the held rope: zero rows L, Ld and column Ld
    c0 = _operating_point(np.array([5.0, -5.0, 0.0]))
    a0, b0 = ct.linearize(c0.params, c0.state, [5.0, -5.0, 0.0])
    assert not a0[[2, 7]].any() and not a0[:, 7].any() and not b0[[2, 7]].any()


def test_the_difference_step_does_not_matter():
    u0 = [5.0, -5.0, 1.0]
    c = _operating_point(u0)
    a1, b1 = ct.linearize(c.params, c.state, u0, eps=1e-5)
    a2, b2 = ct.linearize(c.params, c.state, u0, eps=1e-7)
    np.testing.assert_allclose(a1, a2, rtol=1e-5, atol=1e-7 * np.abs(a1).max())
    np.testing.assert_allclose(b1, b2, rtol=1e-5, atol=1e-7 * np.abs(b1).max())


def test_params_in_any_form_and_stiction_change_the_model():
    u0 = [5.0, -5.0, 0.0]
    c = _operating_point(u0)
    a, b = ct.linearize(None, c.state, u0)
    a_dict, _ = ct.linearize({"payload_mass": 0.457}, c.state, u0)
    np.testing.assert_array_equal(a, a_dict)
    a_heavy, _ = ct.linearize({"payload_mass": 0.6}, c.state, u0)
    assert not np.allclose(a, a_heavy)
    a_st, _ = ct.linearize(None, c.state, u0, stiction=(1.5, 0.2))
    assert not np.allclose(a[5, 5], a_st[5, 5]), "the Stribeck slope adds to the viscous one"


def test_a_stuck_axis_is_refused_because_friction_is_not_differentiable_there():
    with pytest.raises(ct.InputError, match=r"state\.qd\[0\].*stopped.*not differentiable"):
        ct.linearize(None, ct.Crane().state, [1.0, 1.0, 0.0])
    # X stuck (no voltage, held by friction) while Y slides
    c = _operating_point([0.0, 5.0, 0.0])
    assert c.modes[0] == 0 and c.modes[1] != 0
    with pytest.raises(ct.InputError, match=r"state\.qd\[0\]"):
        ct.linearize(c.params, c.state, [0.0, 5.0, 0.0])
    c = _operating_point([5.0, 0.0, 0.0])
    assert c.modes[1] == 0
    with pytest.raises(ct.InputError, match=r"state\.qd\[1\].*mode 0"):
        ct.linearize(c.params, c.state, [5.0, 0.0, 0.0])


def test_other_points_where_the_model_is_not_differentiable_are_refused():
    sliding = [0.3, 0.3, 0.35, np.pi / 2, 0.0, 0.1, 0.1, 0.0, 0.0, 0.0]
    # a held rope whose holding force is beyond its breakaway level (it would break away)
    with pytest.raises(ct.InputError, match="rope.*breakaway"):
        ct.linearize(None, sliding, [1.0, 1.0, 5.0])
    # the +-12 V saturation
    with pytest.raises(ct.InputError, match=r"u\[0\]"):
        ct.linearize(None, sliding, [12.0, 1.0, 0.0])
    with pytest.raises(ct.InputError, match=r"u\[2\]"):
        ct.linearize(None, sliding, [1.0, 1.0, float("nan")])
    # a velocity within the difference step of zero
    slow = list(sliding)
    slow[5] = 1e-7
    with pytest.raises(ct.InputError, match="too slowly"):
        ct.linearize(None, slow, [1.0, 1.0, 0.0])
    with pytest.raises(ct.InputError, match="eps"):
        ct.linearize(None, sliding, [1.0, 1.0, 0.0], eps=0.5)
    with pytest.raises(ct.InputError, match="state"):
        ct.linearize(None, None, [1.0, 1.0, 0.0])
    with pytest.raises(ct.ParameterError) as e:
        ct.linearize(None, [0.9] + sliding[1:], [1.0, 1.0, 0.0])
    assert e.value.field == "state.q[0]"

"""`crane_twin.linearize` (issue 23): the linear model's response to small input steps matches
the nonlinear hybrid model's around a sliding operating point, and a stuck axis (mode 0),
where friction is not differentiable, is refused with a clear error. With the `tanh` law the
model is smooth, and the linear model at rest (the hanging equilibrium) follows the nonlinear
one for small input steps."""

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


# ---- the tanh law: linearisation at rest (the hanging equilibrium) ----------------------------


def _hanging_at_rest(gamma, params=None):
    """The default crane at rest, hanging straight down, under the ``tanh`` law, and the input
    that holds it there: the rope drive carries the payload's weight."""
    c = ct.Crane(params, h=H, law="tanh", gamma=gamma)
    assert not np.any(c.state[5:]) and c.state[3] == np.pi / 2 and c.state[4] == 0.0
    p = c.params
    u0 = np.array([0.0, 0.0, -p["payload_mass"] * p["gravity"] / p["rope.gain"]])
    return c, u0


# Friction with equal + and - coefficients on every drive axis: the tanh law has no kink at
# qd = 0, so the central difference is the derivative itself.
SYMMETRIC = {
    "x.viscous_neg": ct.Params()["x.viscous_pos"],
    "x.dry_neg": ct.Params()["x.dry_pos"],
    "y.viscous_neg": ct.Params()["y.viscous_pos"],
    "y.dry_neg": ct.Params()["y.dry_pos"],
}


@pytest.mark.parametrize(
    "gamma, symmetric, tol",
    [
        # default parameters: X's + and - slopes at x = 0.25 differ by about 3 %, and A holds
        # their mean, so a one-way step is off by about 1.5 % (measured: largest component
        # 1.4 % at gamma 1000, 1.7 % at 100; whole trajectory 1.0 %, 1.1 %)
        (1000.0, False, (0.03, 0.02)),
        (100.0, False, (0.03, 0.02)),
        # no kink: only the tanh's own curvature over the small step remains (measured 0.09 %,
        # 0.08 %)
        (1000.0, True, (0.003, 0.002)),
    ],
)
def test_tanh_law_the_linear_model_at_rest_follows_the_nonlinear_one(gamma, symmetric, tol):
    params = ct.Params().replace(SYMMETRIC) if symmetric else None
    c, u0 = _hanging_at_rest(gamma, params)
    a, b = ct.linearize(c.params, c.state, u0, law="tanh", gamma=gamma)
    assert a.shape == (10, 10) and b.shape == (10, 3)
    n = 200  # 0.2 s
    # an equilibrium: the nonlinear model stays at rest under u0 (so f(x0, u0) = 0)
    rest = copy.copy(c)
    drift = np.array([rest.step(u0) for _ in range(n)]) - c.state
    assert np.abs(drift).max() < 1e-12, np.abs(drift).max()
    # small steps: |gamma qd| stays below 0.1, where tanh is within 0.4 % of its slope
    du = np.array([0.02, -0.02, 0.02])
    base, moved = copy.copy(c), copy.copy(c)
    xa = np.array([c.state] + [base.step(u0) for _ in range(n)])
    xb = np.array([c.state] + [moved.step(u0 + du) for _ in range(n)])
    dn = xb - xa
    dl = _linear_response(a, b, du, n)
    scale = np.abs(dn).max(axis=0)
    assert np.all(scale[5:8] > 1e-5), "the input step moves X, Y and the rope measurably"
    assert np.all(gamma * scale[5:8] < 0.1), "and slowly: the tanh stays nearly linear"
    assert scale[8] > 1e-4 and scale[9] > 1e-4, "and swings the payload"
    rel = np.abs(dn - dl).max(axis=0) / scale
    assert rel.max() < tol[0], rel
    total = np.linalg.norm(dn - dl) / np.linalg.norm(dn)
    assert total < tol[1], total
    # A matters: the input alone (A = 0) is far worse
    without_a = _linear_response(np.zeros_like(a), b, du, n)
    assert np.linalg.norm(dn - without_a) / np.linalg.norm(dn) > 10 * total
    # friction at rest is a steep viscous slope: the mean over the + and - sides of
    # Dbar + gamma Cbar(q) [N s/m]. Both A's and B's entries of an axis' velocity are that
    # slope and the gain [N/V] times the same entry of the inverse mass matrix.
    p = c.params
    for i, axis in enumerate(["x", "y", "rope"]):
        q = c.state[i]
        sides = [
            p[f"{axis}.viscous_{s}"] + gamma * np.polyval(p[f"{axis}.dry_{s}"][::-1], q)
            for s in ("pos", "neg")
        ]
        slope = -a[5 + i, 5 + i] / b[5 + i, i] * p[f"{axis}.gain"]
        assert slope == pytest.approx(np.mean(sides), rel=1e-6), (axis, slope, sides)


def test_tanh_law_far_from_zero_velocity_equals_the_hybrid_law():
    """Sliding fast (|gamma qd| >= 50), tanh(gamma qd) is sign(qd) to 1e-43 and its slope
    vanishes: both laws are Dbar qd + sign(qd) Cbar(q), so their Jacobians agree."""
    sliding = [0.3, 0.3, 0.35, np.pi / 2 + 0.01, -0.02, 0.1, -0.1, 0.05, 0.05, -0.05]
    u0 = [4.0, -4.0, 1.0]
    a_h, b_h = ct.linearize(None, sliding, u0)
    a_t, b_t = ct.linearize(None, sliding, u0, law="tanh", gamma=1000.0)
    np.testing.assert_allclose(a_t, a_h, rtol=1e-6, atol=1e-9 * np.abs(a_h).max())
    np.testing.assert_allclose(b_t, b_h, rtol=1e-6, atol=1e-9 * np.abs(b_h).max())
    # while near zero velocity the tanh law adds its steep slope
    a_slow, _ = ct.linearize(None, sliding, u0, law="tanh", gamma=10.0)
    assert a_slow[5, 5] < a_h[5, 5] - 0.5 and a_slow[6, 6] < a_h[6, 6] - 0.5


def test_tanh_law_is_differentiable_at_rest_where_the_hybrid_law_is_refused():
    c, u0 = _hanging_at_rest(1000.0)
    with pytest.raises(ct.InputError, match=r"state\.qd\[0\].*not differentiable"):
        ct.linearize(c.params, c.state, u0)
    a, b = ct.linearize(c.params, c.state, u0, law="tanh")
    assert np.all(np.isfinite(a)) and np.all(np.isfinite(b))
    np.testing.assert_array_equal(a[:5, 5:], np.eye(5))
    assert b[5, 0] > 0 and b[6, 1] > 0 and b[7, 2] > 0
    # the default gamma is Crane's (1000 s/m)
    a_1000, _ = ct.linearize(c.params, c.state, u0, law="tanh", gamma=1000.0)
    np.testing.assert_array_equal(a, a_1000)
    # stiction has no effect under the tanh law, as in Crane
    a_st, _ = ct.linearize(c.params, c.state, u0, law="tanh", stiction=(1.5, 0.01))
    np.testing.assert_array_equal(a, a_st)


def test_tanh_law_bad_options_are_refused():
    c, u0 = _hanging_at_rest(1000.0)
    with pytest.raises(ct.InputError, match=r"eps.*gamma"):
        ct.linearize(c.params, c.state, u0, law="tanh", gamma=1e5, eps=1e-6)
    a, _ = ct.linearize(c.params, c.state, u0, law="tanh", gamma=1e5, eps=1e-7)
    assert np.all(np.isfinite(a))
    with pytest.raises(ct.InputError, match="law"):
        ct.linearize(c.params, c.state, u0, law="coulomb")
    with pytest.raises(ct.ParameterError) as e:
        ct.linearize(c.params, c.state, u0, law="tanh", gamma=0.0)
    assert e.value.field == "config.law.gamma"

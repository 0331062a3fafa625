"""Gymnasium environment ``CraneAntiSway-v0``: move the payload to a target with little swing
and little energy, on the hybrid crane model with real stiction.

The crane is the exact-sticking hybrid model (``crane_twin.Crane``) with the model's Stribeck
stiction extension on X and Y; friction, stiction and payload are randomised per episode by
the environment's seeded generator (domain randomisation; more parameters on request, below).
Every option is a field of :class:`Task` (``CraneAntiSwayEnv(task=Task(...))`` or keyword
arguments, also through ``gym.make``); the defaults give the environment as it always was, and
its seeded episodes bit for bit.

- Action: the three voltages ``[u_x, u_y, u_l]``, ``Box(-12, 12, (3,), float32)``, held for
  one control period ``dt = substeps * h`` (default 10 x 1 ms). With
  ``Task(normalize_actions=True)`` the space is ``Box(-1, 1, (3,), float32)`` and the voltage
  is ``12 V`` times the action. Voltages beyond +-12 V saturate.
- Observation (12 values, float64, names in :data:`OBS_NAMES`): encoder-quantised positions
  ``x, y, L`` [m] and swing angles ``alpha - pi/2, beta`` [rad] (4096 counts a revolution, as
  the rig: 61 um on X and Y, 23 um on the rope, 1.53 mrad on the angles; the centre of the
  count's cell), their velocities estimated by the backward difference of the quantised values
  over ``dt`` [m/s, rad/s], and the target ``x*, y*`` [m].
  ``Task.obs_noise_std`` adds Gaussian noise to the first 10 values (per value, in its unit;
  the target is exact) and ``Task.obs_latency = k`` delays the whole observation by ``k``
  control periods (below).
- Reward per period: ``-dt * (|p - p*|^2 / d0^2 + w_swing ((alpha - pi/2)^2 + beta^2)
  + w_energy |u|^2 / 12^2)`` with ``p`` the payload's horizontal position and ``u`` the
  saturated voltages [V]; minus ``Task.limit_penalty`` on a period that ends the episode at a
  travel limit. Reward, success and limits use the true state (not the noisy, late reading).
- Episodes last ``episode_steps`` periods (default 500 = 5 s) and are truncated then. They are
  terminated earlier only if asked: ``Task.terminate_on_success`` (when ``info["is_success"]``
  becomes true) and ``Task.terminate_on_limits`` (when a drive axis reaches its travel limit).
- Success (``info["is_success"]``, every period, whether or not it terminates): the payload
  has been within ``success_radius`` [m] of the target (horizontal distance) with a swing
  ``sqrt((alpha - pi/2)^2 + beta^2)`` below ``success_swing`` [rad] for the last
  ``success_hold`` consecutive periods (defaults: 1 cm, 0.02 rad, 50 periods = 0.5 s).
- Travel limits: the episode's ``x.min .. x.max``, ``y.min .. y.max`` and ``rope.min ..
  rope.max`` [m] of the parameters (the model's end stops, which hold an axis exactly at the
  limit). With ``terminate_on_limits``, a period ending with ``x``, ``y`` or ``L`` within
  ``limit_margin`` [m] of (or at) one of them terminates the episode. As every reward is a
  cost (negative), ending early shortens the sum: set ``limit_penalty`` above the cost of the
  rest of an episode so that hitting a limit does not pay (with the default weights, doing
  nothing for a whole episode costs about 19 on average, at most about 52 over 20 seeds).
- ``info``: ``"state"`` (the true 10 model states), ``"target"`` [m], ``"is_success"``,
  ``"randomized"`` (the episode's drawn parameters: a dict from the names of
  :func:`randomized_names` to floats; a fresh copy each call) and ``"params"`` (the episode's
  ``Params``).
- ``render_mode``: ``"rgb_array"`` (``render()`` returns a (300, 600, 3) uint8 image: top view
  and side view, numpy only, no display) or ``"human"`` (the same frames in a matplotlib
  window, at ``metadata["render_fps"]``).
- ``reset(options=...)``, keys of :data:`RESET_OPTIONS`: ``{"target": (x*, y*)}`` sets the
  episode's target [m] (within ``Task.start_x`` / ``start_y``); ``{"state": 10 values}`` sets
  the initial state ``[x, y, L, alpha, beta, xd, yd, Ld, alphad, betad]`` [m, rad, m/s,
  rad/s] (within the travel limits and the model's swing domain; the first observation's
  velocity estimates are 0, as always). The episode's random draws are made all the same, so
  the rest of a seeded episode does not change. Any other key raises ``crane_twin.InputError``.

Domain randomisation: each episode draws, from the environment's generator and in this order,
payload mass, X and Y friction factors, X and Y stiction ratios, initial ``x, y, L`` and the
target (always, 10 draws), then only the ranges a :class:`Task` sets (``stribeck_velocity`` as a
range, ``gain_scale``, ``inertia_scale``, ``rope_friction_scale``, ``rope_stiction_ratio``,
``swing_damping_scale``, ``trolley_mass_scale``, ``rail_mass_scale``, ``param_scale``), then,
with observation noise, one draw that seeds the episode's noise generator. Setting a further
range thus keeps the earlier draws of a seeded episode. The ranges are checked when the
``Task`` is made (``crane_twin.InputError`` naming the field); that the start ranges fit the
travel limits of the nominal parameters is checked when the environment is made.

Observation latency: a FIFO of ``k`` observations per environment. ``reset`` returns the first
observation and fills the FIFO with it, so the step ``j`` of an episode (1, 2, ...) returns the
observation of period ``max(j - k, 0)``. Noise is added when an observation is made (before
the FIFO), from a generator per episode seeded by the environment's generator at ``reset``, so
seeded episodes reproduce with noise too. Noisy values are clipped to the observation space.

A step the model rejects (a non-finite action: ``crane_twin.InputError``; a state leaving the
model's domain: ``crane_twin.StepError``) raises instead of returning a made-up observation.

``CraneAntiSwayVectorEnv`` steps ``num_envs`` of these in one ``CraneBatch`` call (Rust, GIL
released); its env ``i`` reset with seed ``s`` runs exactly as ``CraneAntiSwayEnv`` reset with
seed ``s + i`` (the same bits), with every option, autoresetting on the step after a
termination or truncation.

Snapshots (what issue 23 calls ``get_state`` / ``set_state``): ``env.snapshot()`` returns a
versioned dict of plain values (simulators, episode draws, targets, encoder memory, period
counts, success counters, latency FIFOs, noise and episode generators; layout in
:mod:`crane_twin._env_snapshot`), and ``env.restore(snapshot)`` continues from it bit for bit
(on ``gym.make``'s wrappers call ``env.unwrapped.snapshot()``). ``pickle`` and
``copy.deepcopy`` of both environments are exact too (pickling goes through ``snapshot``; a
``"human"`` window is not pickled).
"""

from __future__ import annotations

import numbers
from dataclasses import dataclass, replace
from typing import Any, Optional, Sequence

import numpy as np

import gymnasium as gym
from gymnasium import spaces
from gymnasium.utils import seeding
from gymnasium.vector.utils import batch_space

from ._native import U_MAX, Crane, CraneBatch, Params
from . import _env_snapshot as _snap
from . import render as _render
from .errors import InputError, ParameterError

#: The registered id of the environment.
ENV_ID = "CraneAntiSway-v0"

__all__ = [
    "ENV_ID",
    "OBS_NAMES",
    "RESET_OPTIONS",
    "Task",
    "CraneAntiSwayEnv",
    "CraneAntiSwayVectorEnv",
    "randomized_names",
    "register",
]

#: Encoder counts a revolution (all five channels).
COUNTS_PER_REV = 4096.0
#: Encoder resolution of x, y, L [m] and alpha, beta [rad] (pulleys of 40, 40, 15 mm).
ENCODER_RES = np.array(
    [2 * np.pi * 0.040, 2 * np.pi * 0.040, 2 * np.pi * 0.015, 2 * np.pi, 2 * np.pi]
) / COUNTS_PER_REV
#: Position of count 0 of each channel (angles count from the hanging position).
ENCODER_ZERO = np.array([0.0, 0.0, 0.0, np.pi / 2, 0.0])

#: Names of the 12 observation values, in order: quantised positions [m] and swing angles
#: [rad] (``alpha`` as ``alpha - pi/2``), their estimated rates [m/s, rad/s], the target [m].
#: The first 10 are the measured ones (``Task.obs_noise_std``'s order and keys).
OBS_NAMES = (
    "x", "y", "L", "alpha", "beta", "xd", "yd", "Ld", "alphad", "betad", "x_target", "y_target"
)
_MEASURED = 10
#: Most control periods of observation latency a Task takes (``Task.obs_latency``).
MAX_LATENCY = 10_000
#: Drive axes of the model, in state order.
_AXES = ("x", "y", "rope")


def _is_real(v: Any) -> bool:
    return isinstance(v, numbers.Real) and not isinstance(v, bool)


def _checked_range(name: str, v: Any, low: Optional[float] = None, low_name: str = "") -> tuple:
    """``v`` as a ``(low, high)`` tuple of finite floats with ``low <= high`` (and, given
    ``low``, ``v[0] > low`` or ``>= 1`` for ratios), or an ``InputError`` naming ``Task.name``."""
    try:
        lo, hi = v
        ok = _is_real(lo) and _is_real(hi)
    except (TypeError, ValueError):
        ok = False
    if not ok or isinstance(v, (str, bytes)):
        raise InputError(f"Task.{name} must be a (low, high) pair of numbers (got {v!r})")
    lo, hi = float(lo), float(hi)
    if not (np.isfinite(lo) and np.isfinite(hi) and lo <= hi):
        raise InputError(f"Task.{name} must be a finite (low, high) range (got {(lo, hi)!r})")
    if low is not None and not lo > low:
        raise InputError(f"Task.{name} must be {low_name} (got {(lo, hi)!r})")
    return (lo, hi)


def _checked_ratio(name: str, v: Any) -> tuple:
    r = _checked_range(name, v)
    if r[0] < 1.0:
        raise InputError(
            f"Task.{name} is breakaway / sliding friction and must be >= 1 (got {r!r})"
        )
    return r


def _checked_number(name: str, v: Any, what: str, ok) -> float:
    if not (_is_real(v) and np.isfinite(v) and ok(float(v))):
        raise InputError(f"Task.{name} must be {what} (got {v!r})")
    return float(v)


def _checked_int(name: str, v: Any, least: int, most: Optional[int] = None) -> int:
    if not (isinstance(v, (int, np.integer)) and not isinstance(v, bool) and v >= least):
        raise InputError(f"Task.{name} must be an int >= {least} (got {v!r})")
    if most is not None and v > most:
        raise InputError(f"Task.{name} must be at most {most} (got {v!r})")
    return int(v)


def _checked_bool(name: str, v: Any) -> bool:
    if not isinstance(v, (bool, np.bool_)):
        raise InputError(f"Task.{name} must be True or False (got {v!r})")
    return bool(v)


def _checked_noise(v: Any) -> Optional[tuple]:
    """``Task.obs_noise_std`` as None (no noise) or 10 standard deviations."""
    if v is None:
        return None
    if isinstance(v, dict):
        unknown = [k for k in v if k not in OBS_NAMES[:_MEASURED]]
        if unknown:
            raise InputError(
                f"Task.obs_noise_std: unknown quantities {unknown} (the measured ones are "
                f"{list(OBS_NAMES[:_MEASURED])}; the target is exact)"
            )
        v = [v.get(k, 0.0) for k in OBS_NAMES[:_MEASURED]]
    try:
        vals = list(v)
    except TypeError:
        vals = None
    if vals is None or len(vals) != _MEASURED or not all(_is_real(s) for s in vals):
        raise InputError(
            f"Task.obs_noise_std must be None, {_MEASURED} standard deviations (in the units "
            f"of {list(OBS_NAMES[:_MEASURED])}) or a dict of some of them (got {v!r})"
        )
    std = tuple(float(s) for s in vals)
    for k, s in zip(OBS_NAMES, std):
        if not (np.isfinite(s) and s >= 0):
            raise InputError(f"Task.obs_noise_std[{k!r}] must be finite and >= 0 (got {s!r})")
    return std if any(s > 0 for s in std) else None


def _checked_param_scale(v: Any) -> tuple:
    """``Task.param_scale`` as a tuple of ``(name, low, high)``."""
    if isinstance(v, dict):
        items = [(k, r) for k, r in v.items()]
    else:
        try:
            items = [(e[0], e[1:] if len(e) == 3 else e[1]) for e in v]
        except (TypeError, IndexError, KeyError):
            raise InputError(
                f"Task.param_scale must be a dict {{name: (low, high)}} (got {v!r})"
            ) from None
    known = Params.names()
    out = []
    seen = set()
    for name, r in items:
        if name not in known:
            raise InputError(
                f"Task.param_scale: unknown parameter {name!r} (known: {', '.join(known)})"
            )
        if name.endswith((".min", ".max")):
            raise InputError(
                f"Task.param_scale: {name!r} is a travel limit (geometry), not randomised"
            )
        if name in seen:
            raise InputError(f"Task.param_scale: {name!r} given twice")
        seen.add(name)
        lo, hi = _checked_range(f"param_scale[{name!r}]", r, 0.0, "a range of factors > 0")
        out.append((name, lo, hi))
    return tuple(out)


@dataclass(frozen=True)
class Task:
    """The task's constants and options (SI units). Ranges are ``(low, high)`` of uniform draws,
    one per episode (per axis where a field says so); ``None`` leaves a parameter at its nominal
    value and draws nothing. Every field is checked here: a bad one raises
    ``crane_twin.InputError`` naming it (``Task(stiction_ratio=(0.5, 0.9))`` fails at once, not
    at ``reset``). Ranges are stored as tuples of floats."""

    h: float = 1e-3  #: model step [s], in (0, 0.01]
    substeps: int = 10  #: model steps per action
    episode_steps: int = 500  #: actions per episode (then truncated)
    payload_kg: tuple = (0.2, 0.6)  #: payload mass [kg]
    friction_scale: tuple = (0.8, 1.25)  #: factor on X's and Y's viscous and dry friction (each)
    stiction_ratio: tuple = (1.1, 1.5)  #: breakaway / sliding friction on X and Y (each), >= 1
    #: Stribeck velocity [m/s] of the stiction: a number, or a range drawn per axis with stiction.
    stribeck_velocity: Any = 0.005
    start_x: tuple = (0.1, 0.4)  #: initial and target X range [m]
    start_y: tuple = (0.1, 0.5)  #: initial and target Y range [m]
    start_l: tuple = (0.30, 0.45)  #: initial rope length [m]
    d0: float = 0.1  #: distance scale of the reward [m]
    w_swing: float = 10.0  #: weight of the squared swing angles [1/rad^2]
    w_energy: float = 0.05  #: weight of the normalised squared voltages
    # -- more domain randomisation (factors on the nominal parameters; None: nominal) --
    gain_scale: Optional[tuple] = None  #: factor on the drive gains [N/V] of X, Y, rope (each)
    inertia_scale: Optional[tuple] = None  #: factor on the drive inertias of X, Y, rope (each)
    rope_friction_scale: Optional[tuple] = None  #: factor on the rope's viscous and dry friction
    #: Breakaway / sliding friction of the rope drive (>= 1); None: no stiction on the rope.
    rope_stiction_ratio: Optional[tuple] = None
    swing_damping_scale: Optional[tuple] = None  #: factor on damping_alpha, damping_beta (each)
    trolley_mass_scale: Optional[tuple] = None  #: factor on the trolley mass
    rail_mass_scale: Optional[tuple] = None  #: factor on the rail (Y-carriage) mass
    #: Further factors on any ``Params`` field by its dotted name but the travel limits, e.g.
    #: ``{"gravity": (0.99, 1.01), "x.viscous_pos": (0.9, 1.1)}`` (a dry-friction polynomial is
    #: scaled whole); applied after the fields above, drawn in the order given.
    param_scale: Any = ()
    # -- actions --
    normalize_actions: bool = False  #: actions in [-1, 1] per axis, times 12 V
    # -- observations --
    #: Standard deviations of additive Gaussian noise on the 10 measured observation values,
    #: in their units (:data:`OBS_NAMES` order; or a dict of some of them); None: exact.
    obs_noise_std: Any = None
    obs_latency: int = 0  #: observation delay [control periods], a FIFO (0 .. MAX_LATENCY)
    # -- success and termination --
    success_radius: float = 0.01  #: success: payload within this of the target [m]
    success_swing: float = 0.02  #: success: swing sqrt((alpha - pi/2)^2 + beta^2) below [rad]
    success_hold: int = 50  #: success: both held for this many consecutive periods
    terminate_on_success: bool = False  #: end the episode (terminated) on success
    terminate_on_limits: bool = False  #: end the episode (terminated) at a travel limit
    limit_margin: float = 0.0  #: distance to a travel limit that counts as reaching it [m]
    limit_penalty: float = 0.0  #: subtracted from the reward of a period ending at a limit

    def __post_init__(self) -> None:
        def put(name: str, value: Any) -> None:
            object.__setattr__(self, name, value)

        put("substeps", _checked_int("substeps", self.substeps, 1))
        put("episode_steps", _checked_int("episode_steps", self.episode_steps, 1))
        put("h", _checked_number("h", self.h, "in (0, 0.01] s", lambda v: 0 < v <= 0.01))
        for name in ("payload_kg", "friction_scale", "start_l"):
            put(name, _checked_range(name, getattr(self, name), 0.0, "> 0"))
        for name in ("start_x", "start_y"):
            put(name, _checked_range(name, getattr(self, name)))
        put("stiction_ratio", _checked_ratio("stiction_ratio", self.stiction_ratio))
        v = self.stribeck_velocity
        if _is_real(v):
            put("stribeck_velocity", _checked_number("stribeck_velocity", v, "> 0", lambda x: x > 0))
        else:
            put("stribeck_velocity", _checked_range("stribeck_velocity", v, 0.0, "> 0"))
        put("d0", _checked_number("d0", self.d0, "> 0", lambda x: x > 0))
        for name in ("w_swing", "w_energy"):
            put(name, _checked_number(name, getattr(self, name), ">= 0", lambda x: x >= 0))
        for name in (
            "gain_scale", "inertia_scale", "rope_friction_scale", "swing_damping_scale",
            "trolley_mass_scale", "rail_mass_scale",
        ):
            r = getattr(self, name)
            if r is not None:
                put(name, _checked_range(name, r, 0.0, "a range of factors > 0"))
        if self.rope_stiction_ratio is not None:
            put("rope_stiction_ratio", _checked_ratio("rope_stiction_ratio", self.rope_stiction_ratio))
        put("param_scale", _checked_param_scale(self.param_scale))
        put("normalize_actions", _checked_bool("normalize_actions", self.normalize_actions))
        put("obs_noise_std", _checked_noise(self.obs_noise_std))
        put("obs_latency", _checked_int("obs_latency", self.obs_latency, 0, MAX_LATENCY))
        for name in ("success_radius", "success_swing"):
            put(name, _checked_number(name, getattr(self, name), "> 0", lambda x: x > 0))
        put("success_hold", _checked_int("success_hold", self.success_hold, 1))
        for name in ("terminate_on_success", "terminate_on_limits"):
            put(name, _checked_bool(name, getattr(self, name)))
        for name in ("limit_margin", "limit_penalty"):
            put(name, _checked_number(name, getattr(self, name), ">= 0", lambda x: x >= 0))

    @property
    def dt(self) -> float:
        """Control period [s]."""
        return self.h * self.substeps


def randomized_names(task: Task) -> tuple:
    """Names of the quantities each episode of ``task`` draws (besides the initial state and
    the target), in draw order: the keys of ``info["randomized"]``. A name is the ``Task``
    field that draws it, with the axis after a dot where it is drawn per axis:
    ``payload_kg`` [kg], ``friction_scale.x``, ``stiction_ratio.x``, ``stribeck_velocity.x``
    [m/s], ``gain_scale.rope``, ``swing_damping_scale.alpha``, ``param_scale.gravity``, ...
    (factors and ratios without unit)."""
    names = ["payload_kg", "friction_scale.x", "friction_scale.y", "stiction_ratio.x", "stiction_ratio.y"]
    if not _is_real(task.stribeck_velocity):
        names += ["stribeck_velocity.x", "stribeck_velocity.y"]
        if task.rope_stiction_ratio is not None:
            names.append("stribeck_velocity.rope")
    for field in ("gain_scale", "inertia_scale"):
        if getattr(task, field) is not None:
            names += [f"{field}.{a}" for a in _AXES]
    for field in ("rope_friction_scale", "rope_stiction_ratio"):
        if getattr(task, field) is not None:
            names.append(field)
    if task.swing_damping_scale is not None:
        names += ["swing_damping_scale.alpha", "swing_damping_scale.beta"]
    for field in ("trolley_mass_scale", "rail_mass_scale"):
        if getattr(task, field) is not None:
            names.append(field)
    names += [f"param_scale.{name}" for name, _, _ in task.param_scale]
    return tuple(names)


def quantise(q: np.ndarray) -> np.ndarray:
    """Encoder reading of positions ``q[..., 5]``: the centre of the count's cell, angles
    relative to hanging (``alpha - pi/2``)."""
    counts = np.floor((q - ENCODER_ZERO) / ENCODER_RES)
    return (counts + 0.5) * ENCODER_RES


#: Bounds of the quantised positions (beyond the axis limits and swing stops).
POS_LOW = np.array([-0.05, -0.05, 0.0, -1.5, -1.5])
POS_HIGH = np.array([0.6, 0.7, 0.7, 1.5, 1.5])


def _observation_space(task: "Task") -> spaces.Box:
    # A backward difference over dt of values within POS_LOW..POS_HIGH stays within this.
    vmax = (POS_HIGH - POS_LOW) / task.dt
    low = np.concatenate([POS_LOW, -vmax, [task.start_x[0], task.start_y[0]]])
    high = np.concatenate([POS_HIGH, vmax, [task.start_x[1], task.start_y[1]]])
    return spaces.Box(low, high, dtype=np.float64)


def _action_space(task: "Task") -> spaces.Box:
    if task.normalize_actions:
        return spaces.Box(-1.0, 1.0, shape=(3,), dtype=np.float32)
    return spaces.Box(-U_MAX, U_MAX, shape=(3,), dtype=np.float32)


def _check_task_fits(task: Task, base: Params) -> None:
    """The start ranges within the travel limits of ``base`` (strictly inside the margin when
    the limits terminate), checked when an env is made."""
    margin = task.limit_margin if task.terminate_on_limits else 0.0
    p: Any = base
    for field, axis in (("start_x", "x"), ("start_y", "y"), ("start_l", "rope")):
        lo, hi = getattr(task, field)
        lim_lo, lim_hi = p[f"{axis}.min"], p[f"{axis}.max"]
        if task.terminate_on_limits:
            ok = lim_lo + margin < lo and hi < lim_hi - margin
            where = f"strictly inside ({lim_lo} + {margin}, {lim_hi} - {margin}) m"
        else:
            ok = lim_lo <= lo and hi <= lim_hi
            where = f"within the travel limits [{lim_lo}, {lim_hi}] m"
        if not ok:
            raise InputError(
                f"Task.{field} = {(lo, hi)} must lie {where} of the parameters' "
                f"{axis}.min / {axis}.max"
            )


def _scale_friction(changes: dict, base: Any, axis: str, f: float) -> None:
    """Puts ``axis``'s viscous and dry friction of ``base`` times ``f`` into ``changes``."""
    for name in ("viscous_pos", "viscous_neg"):
        changes[f"{axis}.{name}"] = base[f"{axis}.{name}"] * f
    for name in ("dry_pos", "dry_neg"):
        changes[f"{axis}.{name}"] = [c * f for c in base[f"{axis}.{name}"]]


def _draw_episode(rng: np.random.Generator, task: Task, base: Any):
    """Parameters, stiction, initial state, target, drawn values (a dict by
    :func:`randomized_names`) and noise seed (None without noise) of one episode, drawn from
    ``rng`` in the fixed order of the module docstring (10 draws for the default task)."""
    u = rng.uniform
    payload = u(*task.payload_kg)
    fx, fy = u(*task.friction_scale), u(*task.friction_scale)
    rx, ry = u(*task.stiction_ratio), u(*task.stiction_ratio)
    x0, y0, l0 = u(*task.start_x), u(*task.start_y), u(*task.start_l)
    tx, ty = u(*task.start_x), u(*task.start_y)
    drawn = {
        "payload_kg": payload,
        "friction_scale.x": fx,
        "friction_scale.y": fy,
        "stiction_ratio.x": rx,
        "stiction_ratio.y": ry,
    }
    changes = {"payload_mass": payload}
    for axis, f in (("x", fx), ("y", fy)):
        _scale_friction(changes, base, axis, f)
    v = task.stribeck_velocity
    if _is_real(v):
        vx = vy = vr = v
    else:
        vx, vy = u(*v), u(*v)
        drawn["stribeck_velocity.x"], drawn["stribeck_velocity.y"] = vx, vy
        vr = None
        if task.rope_stiction_ratio is not None:
            vr = drawn["stribeck_velocity.rope"] = u(*v)
    for field, key in (("gain_scale", "gain"), ("inertia_scale", "inertia")):
        r = getattr(task, field)
        if r is not None:
            for axis in _AXES:
                s = drawn[f"{field}.{axis}"] = u(*r)
                changes[f"{axis}.{key}"] = base[f"{axis}.{key}"] * s
    if task.rope_friction_scale is not None:
        f = drawn["rope_friction_scale"] = u(*task.rope_friction_scale)
        _scale_friction(changes, base, "rope", f)
    rope_stiction = None
    if task.rope_stiction_ratio is not None:
        rr = drawn["rope_stiction_ratio"] = u(*task.rope_stiction_ratio)
        rope_stiction = (rr, vr)
    if task.swing_damping_scale is not None:
        for angle in ("alpha", "beta"):
            s = drawn[f"swing_damping_scale.{angle}"] = u(*task.swing_damping_scale)
            changes[f"damping_{angle}"] = base[f"damping_{angle}"] * s
    for field, key in (("trolley_mass_scale", "trolley_mass"), ("rail_mass_scale", "rail_mass")):
        r = getattr(task, field)
        if r is not None:
            s = drawn[field] = u(*r)
            changes[key] = base[key] * s
    for name, lo, hi in task.param_scale:
        s = drawn[f"param_scale.{name}"] = u(lo, hi)
        value = changes.get(name, base[name])
        changes[name] = [c * s for c in value] if isinstance(value, list) else value * s
    noise_seed = int(rng.integers(0, 2**63 - 1)) if task.obs_noise_std is not None else None
    params = base.replace(changes)
    stiction = [(rx, vx), (ry, vy), rope_stiction]
    state = np.array([x0, y0, l0, np.pi / 2, 0.0, 0, 0, 0, 0, 0], dtype=np.float64)
    return params, stiction, state, np.array([tx, ty]), drawn, noise_seed


class _Episodes:
    """``m`` episodes on one ``CraneBatch``: drawing, observing, rewarding, ending, noise and
    latency (numpy over m)."""

    def __init__(self, m: int, task: Task, base: Params) -> None:
        _check_task_fits(task, base)
        self.task, self.base, self.m = task, base, m
        self.batch = CraneBatch([base] * m, h=task.h)
        self.targets = np.zeros((m, 2))
        self.prev = np.zeros((m, 5))
        self.t = np.zeros(m, dtype=np.int64)
        #: Per env, the draw of its current episode: (params, stiction, initial state, target).
        self.episodes: list = [None] * m
        #: Names of the drawn quantities and, per env, their values in the current episode.
        self.names = randomized_names(task)
        self.drawn = np.zeros((m, len(self.names)))
        #: Consecutive periods meeting the success criterion, per env.
        self.hold = np.zeros(m, dtype=np.int64)
        #: Per env, the noise generator of its episode (None without noise).
        self.noise_rngs: list = [None] * m
        #: Latency FIFO (m, k, 12) and its shared read/write position (None, 0 without latency).
        k = task.obs_latency
        self.fifo = np.zeros((m, k, len(OBS_NAMES))) if k else None
        self.head = 0
        self._std = None if task.obs_noise_std is None else np.array(task.obs_noise_std)
        space = _observation_space(task)
        self._low, self._high = space.low, space.high
        self._scale = U_MAX if task.normalize_actions else None
        self._r2, self._s2 = task.success_radius**2, task.success_swing**2
        margin = task.limit_margin
        self._lim_lo = np.array([base[f"{a}.min"] for a in _AXES]) + margin
        self._lim_hi = np.array([base[f"{a}.max"] for a in _AXES]) - margin

    def reset_one(
        self,
        i: int,
        rng: np.random.Generator,
        target: Optional[np.ndarray] = None,
        state: Optional[np.ndarray] = None,
    ) -> np.ndarray:
        """Draws env ``i``'s next episode from ``rng`` (``target`` and ``state`` replace the
        drawn ones) and returns its first observation (noisy, and filling the FIFO)."""
        params, stiction, state0, target0, drawn, noise_seed = _draw_episode(rng, self.task, self.base)
        if target is not None:
            target0 = np.array(target, dtype=np.float64)
        if state is not None:
            state0 = np.array(state, dtype=np.float64)
        self.batch.reset_sim(i, params, state0, stiction)
        self.targets[i] = target0
        self.prev[i] = quantise(state0[:5])
        self.t[i] = 0
        self.hold[i] = 0
        self.episodes[i] = (params, stiction, state0, target0)
        self.drawn[i] = [drawn[n] for n in self.names]
        obs = np.concatenate([self.prev[i], np.zeros(5), self.targets[i]])
        if noise_seed is not None:
            self.noise_rngs[i] = np.random.default_rng(noise_seed)
            self._add_noise(obs[None, :], self.noise_rngs[i].standard_normal((1, _MEASURED)))
        if self.fifo is not None:
            self.fifo[i] = obs
        return obs

    def _add_noise(self, obs: np.ndarray, z: np.ndarray) -> None:
        """Adds the noise ``std * z`` (``z`` standard normal, (n, 10)) to ``obs`` (n, 12) in
        place, clipped to the observation space."""
        obs[:, :_MEASURED] += self._std * z
        np.maximum(obs, self._low, out=obs)
        np.minimum(obs, self._high, out=obs)

    def observe(self, states: np.ndarray) -> np.ndarray:
        """The exact observations of ``states`` (m, 10), the encoder memory moved on."""
        pos = quantise(states[:, :5])
        vel = (pos - self.prev) / self.task.dt
        self.prev = pos
        return np.concatenate([pos, vel, self.targets], axis=1)

    def randomized(self, i: int) -> dict:
        """Env ``i``'s drawn values of its current episode, by name (a new dict)."""
        return dict(zip(self.names, self.drawn[i].tolist()))

    def assign(self, values: dict) -> None:
        """Sets the attributes checked by ``_env_snapshot.core_values``."""
        for k, v in values.items():
            setattr(self, k, v)

    def step(self, actions: np.ndarray, skip: Optional[np.ndarray] = None):
        """One control period of every env: ``(obs, reward, terminated, truncated, success,
        states)``. Envs flagged in ``skip`` (about to be reset) draw no noise."""
        task = self.task
        a = np.asarray(actions, dtype=np.float64).reshape(self.m, 3)
        if self._scale is not None:
            a = a * self._scale
        u = np.minimum(np.maximum(a, -U_MAX), U_MAX)
        states = self.batch.step(u, task.substeps)
        obs = self.observe(states)
        diff = self.batch.payload[:, :2] - self.targets
        d2 = (diff * diff).sum(axis=1)
        swing = (states[:, 3] - np.pi / 2) ** 2 + states[:, 4] ** 2
        energy = (u * u).sum(axis=1) / U_MAX**2
        reward = -task.dt * (d2 / task.d0**2 + task.w_swing * swing + task.w_energy * energy)
        self.t += 1
        truncated = self.t >= task.episode_steps
        self.hold = (self.hold + 1) * ((d2 <= self._r2) & (swing <= self._s2))
        success = self.hold >= task.success_hold
        terminated = success.copy() if task.terminate_on_success else np.zeros(self.m, dtype=bool)
        if task.terminate_on_limits:
            q = states[:, :3]
            out = ((q <= self._lim_lo) | (q >= self._lim_hi)).any(axis=1)
            reward -= task.limit_penalty * out
            terminated |= out
        if self._std is not None:
            z = np.zeros((self.m, _MEASURED))
            for i in range(self.m) if skip is None else np.flatnonzero(~skip).tolist():
                self.noise_rngs[i].standard_normal(out=z[i])
            self._add_noise(obs, z)
        if self.fifo is not None:
            out_obs = self.fifo[:, self.head].copy()
            self.fifo[:, self.head] = obs
            self.head = (self.head + 1) % task.obs_latency
            obs = out_obs
        return obs, reward, terminated, truncated, success, states


#: The keys ``reset(options=...)`` takes.
RESET_OPTIONS = ("target", "state")


def _reset_options(task: Task, base: Params, options: Optional[dict], m: Optional[int]):
    """``(targets, states)`` that ``reset(options=...)`` asks for, checked before anything is
    drawn (each None: drawn as usual). ``m`` None: the single env (one target ``(2,)``, one
    state ``(10,)``); else also one per env, ``(m, 2)`` and ``(m, 10)``."""
    if not options:
        return None, None
    if not isinstance(options, dict):
        raise InputError(f"reset options must be a dict (got {type(options).__name__})")
    unknown = set(options) - set(RESET_OPTIONS)
    if unknown:
        raise InputError(
            f"reset options {sorted(map(str, unknown))} are not known; the options are "
            f"{list(RESET_OPTIONS)}"
        )

    def rows(key: str, n: int, what: str) -> Optional[np.ndarray]:
        if key not in options:
            return None
        try:
            a = np.array(options[key], dtype=np.float64)
        except (TypeError, ValueError) as e:
            raise InputError(f"options[{key!r}]: not {what} ({e})") from None
        shapes = [(n,)] + ([] if m is None else [(m, n)])
        if a.shape not in shapes or not np.all(np.isfinite(a)):
            per_env = "" if m is None else f", or shape {(m, n)} (one per env)"
            raise InputError(
                f"options[{key!r}] must be {what}{per_env} (got shape {a.shape}: {a!r})"
            )
        return np.broadcast_to(a, (1 if m is None else m, n))

    targets = rows("target", 2, "two finite numbers (x*, y*) [m]")
    if targets is not None:
        for col, (lo, hi), name in ((0, task.start_x, "start_x"), (1, task.start_y, "start_y")):
            for v in targets[:, col]:
                if not lo <= v <= hi:
                    raise InputError(
                        f"options['target'] {v} is outside Task.{name} = ({lo}, {hi}) m "
                        f"(the observation space's bounds)"
                    )
    states = rows(
        "state", 10, "10 finite numbers [x, y, L, alpha, beta, xd, yd, Ld, alphad, betad]"
    )
    if states is not None:
        for s in states:
            try:  # the model's own check: travel limits, swing domain
                Crane(base, h=task.h, state=s)
            except ParameterError as e:
                raise ParameterError(
                    f"options['state']: {e}", e.field, e.problem, e.value
                ) from None
    return targets, states


def _task_from(task: Optional[Task], overrides: dict) -> Task:
    t = task or Task()
    return replace(t, **overrides) if overrides else t


def _params_from(params: Any) -> Params:
    if params is None:
        return Params()
    if isinstance(params, Params):
        return params
    if isinstance(params, dict):
        return Params.from_dict(params)
    return Params.load(params)


class CraneAntiSwayEnv(gym.Env):
    """Single crane: see the module docstring. ``CraneAntiSwayEnv(task=None, params=None,
    render_mode=None, **task_fields)``; ``params`` (a ``Params``, dict or TOML path) is the
    nominal crane that each episode randomises; ``task_fields`` replace fields of ``task``
    (``CraneAntiSwayEnv(normalize_actions=True, obs_latency=2)``)."""

    metadata = {"render_modes": ["rgb_array", "human"], "render_fps": 50}

    def __init__(
        self,
        task: Optional[Task] = None,
        params: Any = None,
        render_mode: Optional[str] = None,
        **task_fields: Any,
    ) -> None:
        self.task = _task_from(task, task_fields)
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(
                f"render_mode must be one of {self.metadata['render_modes']} or None "
                f"(got {render_mode!r})"
            )
        self.render_mode = render_mode
        self._window: Optional[_render.Window] = None
        self.observation_space = _observation_space(self.task)
        self.action_space = _action_space(self.task)
        self._core = _Episodes(1, self.task, _params_from(params))
        self._started = False
        self._randomized: dict = {}

    def reset(self, *, seed: Optional[int] = None, options: Optional[dict] = None):
        """Starts an episode (Gymnasium's ``reset``); ``options``: see :data:`RESET_OPTIONS`
        and the module docstring. Returns the first observation and ``info``."""
        targets, states = _reset_options(self.task, self._core.base, options, None)
        super().reset(seed=seed)
        obs = self._core.reset_one(
            0,
            self.np_random,
            None if targets is None else targets[0],
            None if states is None else states[0],
        )
        self._randomized = self._core.randomized(0)
        self._started = True
        if self.render_mode == "human":
            self.render()
        return obs, self._info(self._core.batch.states[0], False)

    def render(self):
        """The current frame (``"rgb_array"``), or shows it (``"human"``); ``None`` without a
        render mode (Gymnasium's convention)."""
        if self.render_mode is None:
            return None
        img = _render.frame(
            self._core.batch.states[0], self._core.batch.payload[0], self._core.targets[0]
        )
        if self.render_mode == "rgb_array":
            return img
        if self._window is None:
            self._window = _render.Window(self.metadata["render_fps"])
        self._window.show(img)
        return None

    def close(self):
        """Closes the ``"human"`` window, if any."""
        if self._window is not None:
            self._window.close()
            self._window = None

    def step(self, action):
        """One control period (Gymnasium's ``step``): ``(obs, reward, terminated, truncated,
        info)``; after either flag, ``reset`` must be called."""
        if not self._started:
            raise gym.error.ResetNeeded("call reset() before step()")
        obs, reward, term, trunc, success, states = self._core.step(np.asarray(action)[None, :])
        terminated, truncated = bool(term[0]), bool(trunc[0])
        if terminated or truncated:
            self._started = False
        if self.render_mode == "human":
            self.render()
        return obs[0], float(reward[0]), terminated, truncated, self._info(states[0], bool(success[0]))

    def _info(self, state: np.ndarray, success: bool) -> dict:
        return {
            "state": state,
            "target": self._core.targets[0].copy(),
            "is_success": success,
            "randomized": dict(self._randomized),
            "params": None if self._core.episodes[0] is None else self._core.episodes[0][0],
        }

    def snapshot(self) -> dict:
        """A full snapshot (what issue 23 calls ``get_state``): a versioned dict of plain values
        holding the simulator (``CraneBatch.snapshot()``), the episode's draw, target [m],
        encoder memory, period and success counts, latency FIFO, noise generator,
        ``np_random``'s state and whether ``step`` may be called (layout:
        :mod:`crane_twin._env_snapshot`). Picklable and JSON-serialisable."""
        snap = {"format": _snap.SINGLE_FORMAT, "version": _snap.VERSION}
        snap.update(_snap.core_snapshot(self._core))
        snap["rng"] = _snap.rng_state(self._np_random)
        snap["np_random_seed"] = self._np_random_seed
        snap["started"] = self._started
        return snap

    def restore(self, snapshot: dict) -> None:
        """Continues from ``snapshot`` (from ``snapshot()`` of an env with the same task and
        nominal parameters) bit for bit: the same observations, rewards and later seeded or
        unseeded resets (what issue 23 calls ``set_state``). A bad snapshot raises
        ``crane_twin.InputError`` naming the key (or ``ParameterError``); nothing changes then."""
        snap = _snap.checked(snapshot, _snap.SINGLE_FORMAT, _snap.SINGLE_KEYS)
        values = _snap.core_values(self._core, snap)
        rng = _snap.rng_from(snap["rng"], 'snapshot["rng"]')
        seed = snap["np_random_seed"]
        if not (seed is None or (isinstance(seed, int) and not isinstance(seed, bool))):
            raise InputError(f'`snapshot["np_random_seed"]` must be an int or None (got {seed!r})')
        if not isinstance(snap["started"], bool):
            raise InputError(f'`snapshot["started"]` must be a bool (got {snap["started"]!r})')
        self._core.assign(values)
        self._np_random, self._np_random_seed = rng, seed
        self._started = snap["started"]
        self._randomized = self._core.randomized(0) if self._core.episodes[0] is not None else {}

    def __getstate__(self) -> dict:
        """Pickled state: the attributes but the simulators, random generator and window,
        plus ``{"version": VERSION, "snapshot": self.snapshot()}`` under ``"_pickled"``."""
        return _pickled_state(self, ("_np_random",))

    def __setstate__(self, state: dict) -> None:
        """Unpickling: the attributes, then ``restore`` of the pickled snapshot (no window)."""
        _unpickle(self, state, 1)
        self._window = None


class CraneAntiSwayVectorEnv(gym.vector.VectorEnv):
    """``num_envs`` cranes stepped together in Rust (one ``CraneBatch``), next-step autoreset
    (after a termination or a truncation). Env ``i`` reset with seed ``s`` equals
    ``CraneAntiSwayEnv`` reset with seed ``s + i``, for every ``Task`` option.

    ``info``: ``"target"`` (num_envs, 2) [m], ``"is_success"`` (num_envs,) bool and
    ``"randomized"`` (a dict from the names of :func:`randomized_names` to (num_envs,)
    arrays). ``reset(options=...)`` takes the single env's keys, each one value for every env
    or one per env (``"target"`` of shape (num_envs, 2), ``"state"`` (num_envs, 10))."""

    metadata = {"render_modes": [], "autoreset_mode": gym.vector.AutoresetMode.NEXT_STEP}
    # (render one env of it with CraneAntiSwayEnv: the vector env draws nothing)

    def __init__(
        self,
        num_envs: int = 8,
        task: Optional[Task] = None,
        params: Any = None,
        render_mode: Optional[str] = None,
        **task_fields: Any,
    ) -> None:
        if int(num_envs) < 1:
            raise ValueError(f"num_envs must be >= 1 (got {num_envs})")
        self.num_envs = int(num_envs)
        self.task = _task_from(task, task_fields)
        if render_mode is not None:
            raise ValueError(
                "the vector env renders nothing (render_mode=None); render a single "
                "CraneAntiSwayEnv instead"
            )
        self.render_mode = render_mode
        self.single_observation_space = _observation_space(self.task)
        self.single_action_space = _action_space(self.task)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self._core = _Episodes(self.num_envs, self.task, _params_from(params))
        self._rngs = [seeding.np_random(None)[0] for _ in range(self.num_envs)]
        self._needs_reset = np.ones(self.num_envs, dtype=bool)

    def reset(self, *, seed: Optional[int | Sequence[int]] = None, options: Optional[dict] = None):
        """Resets every env (seed ``s``: env ``i`` gets ``s + i``; or one seed per env);
        ``options`` as the single env's, for all envs or one per env."""
        targets, states = _reset_options(self.task, self._core.base, options, self.num_envs)
        if seed is not None:
            seeds = [seed + i for i in range(self.num_envs)] if isinstance(seed, int) else list(seed)
            if len(seeds) != self.num_envs:
                raise ValueError(f"expected {self.num_envs} seeds, got {len(seeds)}")
            self._rngs = [seeding.np_random(s)[0] for s in seeds]
        obs = np.empty((self.num_envs, len(OBS_NAMES)))
        for i in range(self.num_envs):
            obs[i] = self._core.reset_one(
                i,
                self._rngs[i],
                None if targets is None else targets[i],
                None if states is None else states[i],
            )
        self._needs_reset[:] = False
        return obs, self._info(np.zeros(self.num_envs, dtype=bool))

    def step(self, actions):
        """One period of every env (an env that ended on the previous step is reset instead:
        reward 0, both flags False)."""
        actions = np.array(actions, dtype=np.float64).reshape(self.num_envs, 3)
        done = self._needs_reset.copy()
        any_done = bool(done.any())
        obs, reward, terminated, truncated, success, _ = self._core.step(
            actions, done if any_done else None
        )
        if any_done:
            for i in np.flatnonzero(done):
                obs[i] = self._core.reset_one(i, self._rngs[i])
            reward[done] = 0.0
            terminated[done] = False
            truncated[done] = False
            success[done] = False
        self._needs_reset = terminated | truncated
        return obs, reward, terminated, truncated, self._info(success)

    def _info(self, success: np.ndarray) -> dict:
        drawn = self._core.drawn
        return {
            "target": self._core.targets.copy(),
            "is_success": success,
            "randomized": {n: drawn[:, j].copy() for j, n in enumerate(self._core.names)},
        }

    def snapshot(self) -> dict:
        """A full snapshot (what issue 23 calls ``get_state``): a versioned dict of plain values
        holding the ``num_envs`` simulators, episode draws, targets [m], encoder memory, period
        and success counts, latency FIFOs, noise generators, the envs' random generators and
        autoreset flags (layout: :mod:`crane_twin._env_snapshot`). Picklable and
        JSON-serialisable."""
        snap = {"format": _snap.VECTOR_FORMAT, "version": _snap.VERSION}
        snap.update(_snap.core_snapshot(self._core))
        snap["rngs"] = [_snap.rng_state(r) for r in self._rngs]
        snap["needs_reset"] = [bool(v) for v in self._needs_reset]
        return snap

    def restore(self, snapshot: dict) -> None:
        """Continues from ``snapshot`` (from ``snapshot()`` of a vector env with the same
        ``num_envs``, task and nominal parameters) bit for bit (what issue 23 calls
        ``set_state``). A bad snapshot raises ``crane_twin.InputError`` naming the key (or
        ``ParameterError``); nothing changes then."""
        snap = _snap.checked(snapshot, _snap.VECTOR_FORMAT, _snap.VECTOR_KEYS)
        values = _snap.core_values(self._core, snap)
        m = self.num_envs
        rngs = snap["rngs"]
        if not isinstance(rngs, list) or len(rngs) != m:
            raise InputError(f'`snapshot["rngs"]`: expected a list of {m} generator states')
        rngs = [_snap.rng_from(r, f'snapshot["rngs"][{i}]') for i, r in enumerate(rngs)]
        if any(r is None for r in rngs):
            raise InputError('`snapshot["rngs"]`: every env needs its generator state')
        needs = _snap.array(snap, "needs_reset", (m,), bool)
        self._core.assign(values)
        self._rngs, self._needs_reset = rngs, needs

    def __getstate__(self) -> dict:
        """Pickled state: the attributes but the simulators and random generators, plus
        ``{"version": VERSION, "snapshot": self.snapshot()}`` under ``"_pickled"``."""
        return _pickled_state(self, ("_rngs",))

    def __setstate__(self, state: dict) -> None:
        """Unpickling: the attributes, then ``restore`` of the pickled snapshot."""
        _unpickle(self, state, state.get("num_envs", 0))


def _pickled_state(env: Any, drop: tuple) -> dict:
    """``env.__dict__`` without what its snapshot holds (and the render window), plus the
    versioned snapshot."""
    skip = ("_core", "_window") + drop
    state = {k: v for k, v in env.__dict__.items() if k not in skip}
    state["_pickled"] = {"version": _snap.VERSION, "snapshot": env.snapshot()}
    return state


def _unpickle(env: Any, state: dict, m: int) -> None:
    """Rebuilds an env of ``m`` simulators from :func:`_pickled_state`'s dict."""
    state = dict(state)
    pickled = state.pop("_pickled", None)
    if not isinstance(pickled, dict) or pickled.get("version") != _snap.VERSION:
        raise InputError(
            f"pickled CraneAntiSway env of an unknown version (this crane_twin reads "
            f"version {_snap.VERSION})"
        )
    snap = pickled["snapshot"]
    env.__dict__.update(state)
    env._core = _Episodes(m, env.task, _snap.checked_params(snap))
    env.restore(snap)


def register() -> None:
    """Registers ``CraneAntiSway-v0`` (single and vector entry points); idempotent."""
    if ENV_ID in gym.registry:
        return
    gym.register(
        id=ENV_ID,
        entry_point="crane_twin.envs:CraneAntiSwayEnv",
        vector_entry_point="crane_twin.envs:CraneAntiSwayVectorEnv",
    )

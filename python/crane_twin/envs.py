"""Gymnasium environment ``CraneAntiSway-v0``: move the payload to a target with little swing
and little energy, on the hybrid crane model with real stiction.

The crane is the exact-sticking hybrid model (``crane_twin.Crane``) with the model's Stribeck
stiction extension on X and Y; friction, stiction and payload are randomised per episode by
the environment's seeded generator (domain randomisation).

- Action: the three voltages ``[u_x, u_y, u_l]``, ``Box(-12, 12, (3,), float32)``, held for
  one control period ``dt = substeps * h`` (default 10 x 1 ms).
- Observation (12 values, float64): encoder-quantised positions ``x, y, L`` [m] and swing
  angles ``alpha - pi/2, beta`` [rad] (4096 counts a revolution, as the rig: 61 um on X and
  Y, 23 um on the rope, 1.53 mrad on the angles; the centre of the count's cell), their
  velocities estimated by the backward difference of the quantised values over ``dt``
  [m/s, rad/s], and the target ``x*, y*`` [m].
- Reward per period: ``-dt * (|p - p*|^2 / d0^2 + w_swing ((alpha - pi/2)^2 + beta^2)
  + w_energy |u|^2 / 12^2)`` with ``p`` the payload's horizontal position.
- Episodes have a fixed length (``episode_steps`` periods, default 500 = 5 s): never
  terminated, truncated at the end.
- ``render_mode``: ``"rgb_array"`` (``render()`` returns a (300, 600, 3) uint8 image: top view
  and side view, numpy only, no display) or ``"human"`` (the same frames in a matplotlib
  window, at ``metadata["render_fps"]``).
- ``reset(options=...)``: ``{"target": (x*, y*)}`` sets the episode's target [m] (within
  ``Task.start_x`` / ``start_y``); the episode's random draws are made all the same, so the
  rest of a seeded episode does not change. Any other key is an error.

A step the model rejects (a non-finite action: ``crane_twin.InputError``; a state leaving the
model's domain: ``crane_twin.StepError``) raises instead of returning a made-up observation.

``CraneAntiSwayVectorEnv`` steps ``num_envs`` of these in one ``CraneBatch`` call (Rust, GIL
released); its env ``i`` reset with seed ``s`` runs exactly as ``CraneAntiSwayEnv`` reset with
seed ``s + i`` (the same bits).

Snapshots (what issue 23 calls ``get_state`` / ``set_state``): ``env.snapshot()`` returns a
versioned dict of plain values (simulators, episode draws, targets, encoder memory, period
counts, random generators; layout in :mod:`crane_twin._env_snapshot`), and
``env.restore(snapshot)`` continues from it bit for bit (on ``gym.make``'s wrappers call
``env.unwrapped.snapshot()``). ``pickle`` and ``copy.deepcopy`` of both environments are
exact too (pickling goes through ``snapshot``; a ``"human"`` window is not pickled).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any, Optional, Sequence

import numpy as np

import gymnasium as gym
from gymnasium import spaces
from gymnasium.utils import seeding
from gymnasium.vector.utils import batch_space

from ._native import U_MAX, CraneBatch, Params
from . import _env_snapshot as _snap
from . import render as _render
from .errors import InputError

ENV_ID = "CraneAntiSway-v0"

__all__ = ["ENV_ID", "Task", "CraneAntiSwayEnv", "CraneAntiSwayVectorEnv", "register"]

COUNTS_PER_REV = 4096.0
#: Encoder resolution of x, y, L [m] and alpha, beta [rad] (pulleys of 40, 40, 15 mm).
ENCODER_RES = np.array(
    [2 * np.pi * 0.040, 2 * np.pi * 0.040, 2 * np.pi * 0.015, 2 * np.pi, 2 * np.pi]
) / COUNTS_PER_REV
#: Position of count 0 of each channel (angles count from the hanging position).
ENCODER_ZERO = np.array([0.0, 0.0, 0.0, np.pi / 2, 0.0])


@dataclass(frozen=True)
class Task:
    """The task's constants (SI units). Ranges are ``(low, high)`` of uniform draws."""

    h: float = 1e-3  #: model step [s]
    substeps: int = 10  #: model steps per action
    episode_steps: int = 500  #: actions per episode
    payload_kg: tuple = (0.2, 0.6)  #: payload mass
    friction_scale: tuple = (0.8, 1.25)  #: factor on X's and Y's viscous and dry friction (each)
    stiction_ratio: tuple = (1.1, 1.5)  #: breakaway / sliding friction on X and Y
    stribeck_velocity: float = 0.005  #: Stribeck velocity [m/s]
    start_x: tuple = (0.1, 0.4)  #: initial and target X range [m]
    start_y: tuple = (0.1, 0.5)  #: initial and target Y range [m]
    start_l: tuple = (0.30, 0.45)  #: initial rope length [m]
    d0: float = 0.1  #: distance scale of the reward [m]
    w_swing: float = 10.0  #: weight of the squared swing angles [1/rad^2]
    w_energy: float = 0.05  #: weight of the normalised squared voltages

    def __post_init__(self) -> None:
        if not (isinstance(self.substeps, int) and self.substeps >= 1):
            raise ValueError(f"Task.substeps must be an int >= 1 (got {self.substeps!r})")
        if not (isinstance(self.episode_steps, int) and self.episode_steps >= 1):
            raise ValueError(f"Task.episode_steps must be an int >= 1 (got {self.episode_steps!r})")
        if not (np.isfinite(self.h) and 0 < self.h <= 0.01):
            raise ValueError(f"Task.h must be in (0, 0.01] s (got {self.h!r})")
        for name in ("payload_kg", "friction_scale", "stiction_ratio", "start_x", "start_y", "start_l"):
            lo, hi = getattr(self, name)
            if not (np.isfinite(lo) and np.isfinite(hi) and lo <= hi):
                raise ValueError(f"Task.{name} must be a finite (low, high) range (got {(lo, hi)!r})")
        if self.stiction_ratio[0] < 1.0:
            raise ValueError(
                f"Task.stiction_ratio is breakaway / sliding friction and must be >= 1 "
                f"(got {self.stiction_ratio!r})"
            )
        for name in ("payload_kg", "friction_scale", "start_l"):
            if getattr(self, name)[0] <= 0:
                raise ValueError(f"Task.{name} must be > 0 (got {getattr(self, name)!r})")
        for name in ("stribeck_velocity", "d0"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v > 0):
                raise ValueError(f"Task.{name} must be > 0 (got {v!r})")
        for name in ("w_swing", "w_energy"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v >= 0):
                raise ValueError(f"Task.{name} must be >= 0 (got {v!r})")

    @property
    def dt(self) -> float:
        """Control period [s]."""
        return self.h * self.substeps


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


def _action_space() -> spaces.Box:
    return spaces.Box(-U_MAX, U_MAX, shape=(3,), dtype=np.float32)


def _draw_episode(rng: np.random.Generator, task: Task, base: Params):
    """Parameters, stiction, initial state and target of one episode, drawn from ``rng``
    (always 10 draws, in a fixed order)."""
    u = rng.uniform
    payload = u(*task.payload_kg)
    fx, fy = u(*task.friction_scale), u(*task.friction_scale)
    rx, ry = u(*task.stiction_ratio), u(*task.stiction_ratio)
    x0, y0, l0 = u(*task.start_x), u(*task.start_y), u(*task.start_l)
    tx, ty = u(*task.start_x), u(*task.start_y)
    changes = {"payload_mass": payload}
    for axis, f in (("x", fx), ("y", fy)):
        for name in ("viscous_pos", "viscous_neg"):
            changes[f"{axis}.{name}"] = base[f"{axis}.{name}"] * f
        for name in ("dry_pos", "dry_neg"):
            changes[f"{axis}.{name}"] = [c * f for c in base[f"{axis}.{name}"]]
    params = base.replace(changes)
    v = task.stribeck_velocity
    stiction = [(rx, v), (ry, v), None]
    state = np.array([x0, y0, l0, np.pi / 2, 0.0, 0, 0, 0, 0, 0], dtype=np.float64)
    return params, stiction, state, np.array([tx, ty])


class _Episodes:
    """``m`` episodes on one ``CraneBatch``: drawing, observing, rewarding (numpy over m)."""

    def __init__(self, m: int, task: Task, base: Params) -> None:
        self.task, self.base, self.m = task, base, m
        self.batch = CraneBatch([base] * m, h=task.h)
        self.targets = np.zeros((m, 2))
        self.prev = np.zeros((m, 5))
        self.t = np.zeros(m, dtype=np.int64)
        #: Per env, the draw of its current episode: (params, stiction, initial state, target).
        self.episodes: list = [None] * m

    def reset_one(self, i: int, rng: np.random.Generator) -> None:
        params, stiction, state, target = _draw_episode(rng, self.task, self.base)
        self.batch.reset_sim(i, params, state, stiction)
        self.targets[i] = target
        self.prev[i] = quantise(state[:5])
        self.t[i] = 0
        self.episodes[i] = (params, stiction, state, target)

    def observe(self, states: np.ndarray) -> np.ndarray:
        pos = quantise(states[:, :5])
        vel = (pos - self.prev) / self.task.dt
        self.prev = pos
        return np.concatenate([pos, vel, self.targets], axis=1)

    def set_target(self, i: int, target: np.ndarray) -> None:
        """Replaces env ``i``'s target (after its reset)."""
        self.targets[i] = target
        params, stiction, state, _ = self.episodes[i]
        self.episodes[i] = (params, stiction, state, np.array(target, dtype=np.float64))

    def assign(self, values: dict) -> None:
        """Sets the attributes checked by ``_env_snapshot.core_values``."""
        for k, v in values.items():
            setattr(self, k, v)

    def first_obs(self, i: int) -> np.ndarray:
        return np.concatenate([self.prev[i], np.zeros(5), self.targets[i]])

    def step(self, actions: np.ndarray):
        u = np.clip(np.asarray(actions, dtype=np.float64).reshape(self.m, 3), -U_MAX, U_MAX)
        states = self.batch.step(u, self.task.substeps)
        obs = self.observe(states)
        payload = self.batch.payload[:, :2]
        d2 = np.sum((payload - self.targets) ** 2, axis=1)
        swing = (states[:, 3] - np.pi / 2) ** 2 + states[:, 4] ** 2
        energy = np.sum(u * u, axis=1) / U_MAX**2
        task = self.task
        reward = -task.dt * (d2 / task.d0**2 + task.w_swing * swing + task.w_energy * energy)
        self.t += 1
        truncated = self.t >= task.episode_steps
        return obs, reward, truncated, states


#: The keys ``reset(options=...)`` takes.
RESET_OPTIONS = ("target",)


def _target_option(task: Task, options: Optional[dict]) -> Optional[np.ndarray]:
    """The target ``reset(options=...)`` asks for, checked (``None``: drawn as usual)."""
    if not options:
        return None
    unknown = set(options) - set(RESET_OPTIONS)
    if unknown:
        raise ValueError(
            f"reset options {sorted(unknown)} are not known; the options are {list(RESET_OPTIONS)}"
        )
    if "target" not in options:
        return None
    t = np.asarray(options["target"], dtype=np.float64)
    if t.shape != (2,) or not np.all(np.isfinite(t)):
        raise ValueError(f"options['target'] must be two finite numbers (x*, y*) [m] (got {t!r})")
    for v, (lo, hi), name in ((t[0], task.start_x, "start_x"), (t[1], task.start_y, "start_y")):
        if not lo <= v <= hi:
            raise ValueError(
                f"options['target'] {v} is outside Task.{name} = ({lo}, {hi}) m "
                f"(the observation space's bounds)"
            )
    return t


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
    **task_fields)``; ``params`` (a ``Params``, dict or TOML path) is the nominal crane that
    each episode randomises."""

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
        self.action_space = _action_space()
        self._core = _Episodes(1, self.task, _params_from(params))
        self._started = False

    def reset(self, *, seed: Optional[int] = None, options: Optional[dict] = None):
        super().reset(seed=seed)
        target = _target_option(self.task, options)
        self._core.reset_one(0, self.np_random)
        if target is not None:
            self._core.set_target(0, target)
        self._started = True
        if self.render_mode == "human":
            self.render()
        return self._core.first_obs(0), self._info(self._core.batch.states[0])

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
        if self._window is not None:
            self._window.close()
            self._window = None

    def step(self, action):
        if not self._started:
            raise gym.error.ResetNeeded("call reset() before step()")
        obs, reward, truncated, states = self._core.step(np.asarray(action)[None, :])
        if truncated[0]:
            self._started = False
        if self.render_mode == "human":
            self.render()
        return obs[0], float(reward[0]), False, bool(truncated[0]), self._info(states[0])

    def _info(self, state: np.ndarray) -> dict:
        return {"state": state, "target": self._core.targets[0].copy()}

    def snapshot(self) -> dict:
        """A full snapshot (what issue 23 calls ``get_state``): a versioned dict of plain values
        holding the simulator (``CraneBatch.snapshot()``), the episode's draw, target [m],
        encoder memory, period count, ``np_random``'s state and whether ``step`` may be called
        (layout: :mod:`crane_twin._env_snapshot`). Picklable and JSON-serialisable."""
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

    def __getstate__(self) -> dict:
        """Pickled state: the attributes but the simulators, random generator and window,
        plus ``{"version": 1, "snapshot": self.snapshot()}`` under ``"_pickled"``."""
        return _pickled_state(self, ("_np_random",))

    def __setstate__(self, state: dict) -> None:
        """Unpickling: the attributes, then ``restore`` of the pickled snapshot (no window)."""
        _unpickle(self, state, 1)
        self._window = None


class CraneAntiSwayVectorEnv(gym.vector.VectorEnv):
    """``num_envs`` cranes stepped together in Rust (one ``CraneBatch``), next-step autoreset.
    Env ``i`` reset with seed ``s`` equals ``CraneAntiSwayEnv`` reset with seed ``s + i``."""

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
        self.single_action_space = _action_space()
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self._core = _Episodes(self.num_envs, self.task, _params_from(params))
        self._rngs = [seeding.np_random(None)[0] for _ in range(self.num_envs)]
        self._needs_reset = np.ones(self.num_envs, dtype=bool)

    def reset(self, *, seed: Optional[int | Sequence[int]] = None, options: Optional[dict] = None):
        if seed is not None:
            seeds = [seed + i for i in range(self.num_envs)] if isinstance(seed, int) else list(seed)
            if len(seeds) != self.num_envs:
                raise ValueError(f"expected {self.num_envs} seeds, got {len(seeds)}")
            self._rngs = [seeding.np_random(s)[0] for s in seeds]
        target = _target_option(self.task, options)
        for i in range(self.num_envs):
            self._core.reset_one(i, self._rngs[i])
            if target is not None:
                self._core.set_target(i, target)
        self._needs_reset[:] = False
        obs = np.stack([self._core.first_obs(i) for i in range(self.num_envs)])
        return obs, {"target": self._core.targets.copy()}

    def step(self, actions):
        actions = np.array(actions, dtype=np.float64).reshape(self.num_envs, 3)
        done = self._needs_reset.copy()
        obs, reward, truncated, states = self._core.step(actions)
        for i in np.flatnonzero(done):
            self._core.reset_one(i, self._rngs[i])
            obs[i] = self._core.first_obs(i)
            reward[i] = 0.0
            truncated[i] = False
        self._needs_reset = truncated.copy()
        terminated = np.zeros(self.num_envs, dtype=bool)
        return obs, reward, terminated, truncated, {"target": self._core.targets.copy()}

    def snapshot(self) -> dict:
        """A full snapshot (what issue 23 calls ``get_state``): a versioned dict of plain values
        holding the ``num_envs`` simulators, episode draws, targets [m], encoder memory, period
        counts, the envs' random generators and autoreset flags (layout:
        :mod:`crane_twin._env_snapshot`). Picklable and JSON-serialisable."""
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
        ``{"version": 1, "snapshot": self.snapshot()}`` under ``"_pickled"``."""
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

"""Snapshots of the Gymnasium environments as plain Python data (what issue 23 calls
``get_state`` / ``set_state`` on the env), used by ``snapshot()``, ``restore()`` and pickling
of :class:`crane_twin.envs.CraneAntiSwayEnv` and :class:`crane_twin.envs.CraneAntiSwayVectorEnv`.

A snapshot is a dict of plain values (it pickles, and goes through ``json``), version 2 (version 1,
before the Task options of issue 23, is not read: its task has fewer fields):

======================  ==========================================================================
key                     value
======================  ==========================================================================
``format``              ``"crane_twin.CraneAntiSwayEnv"`` or ``"crane_twin.CraneAntiSwayVectorEnv"``
``version``             ``2``
``task``                the :class:`~crane_twin.envs.Task` as a dict (must equal the env's own)
``params``              the nominal parameters (``Params.to_dict()``; must equal the env's own)
``batch``               ``CraneBatch.snapshot()`` of the ``m`` simulators (1 for the single env)
``targets``             ``m`` targets ``[x*, y*]`` [m]
``prev``                ``m`` rows of the last quantised positions (5 values, [m, rad])
``t``                   ``m`` periods taken in the current episodes
``episodes``            per env, None or the draw of its episode: ``params`` (dict), ``stiction``,
                        ``state`` (10 values), ``target``
``hold``                ``m`` counts of consecutive periods meeting the success criterion
``randomized``          ``m`` rows of the episodes' drawn values (``randomized_names(task)`` order)
``noise_rngs``          per env, None or the bit-generator state of its episode's noise generator
``fifo``                None (no latency) or the latency FIFOs, ``m`` x ``k`` x 12 observations
``fifo_head``           the FIFOs' next read and write position (0 without latency)
``rng``                 single env: the state of ``np_random``'s bit generator (or None)
``np_random_seed``      single env: Gymnasium's ``np_random_seed`` (or None)
``started``             single env: whether ``step`` may be called
``rngs``                vector env: the ``m`` bit-generator states of its envs
``needs_reset``         vector env: ``m`` flags of the next-step autoreset
======================  ==========================================================================

A missing, unknown or malformed key raises :class:`crane_twin.InputError` naming it
(``snapshot["targets"]``); values the model refuses raise :class:`crane_twin.ParameterError`.
"""

from __future__ import annotations

import copy
import dataclasses
from typing import Any, Optional

import numpy as np

from ._native import CraneBatch, Params
from .errors import InputError, ParameterError

#: The snapshot version written and read.
VERSION = 2
#: ``format`` of a ``CraneAntiSwayEnv`` snapshot.
SINGLE_FORMAT = "crane_twin.CraneAntiSwayEnv"
#: ``format`` of a ``CraneAntiSwayVectorEnv`` snapshot.
VECTOR_FORMAT = "crane_twin.CraneAntiSwayVectorEnv"
#: Keys both environments' snapshots have (the episodes' state).
CORE_KEYS = (
    "task", "params", "batch", "targets", "prev", "t", "episodes",
    "hold", "randomized", "noise_rngs", "fifo", "fifo_head",
)
#: Every key of a ``CraneAntiSwayEnv`` snapshot.
SINGLE_KEYS = ("format", "version") + CORE_KEYS + ("rng", "np_random_seed", "started")
#: Every key of a ``CraneAntiSwayVectorEnv`` snapshot.
VECTOR_KEYS = ("format", "version") + CORE_KEYS + ("rngs", "needs_reset")


def _name(key: str) -> str:
    return f'snapshot["{key}"]'


def _plain(v: Any) -> Any:
    return [_plain(e) for e in v] if isinstance(v, (tuple, list)) else v


def task_dict(task: Any) -> dict:
    """The task's fields, tuples (also nested) as lists (as they come back from JSON too)."""
    return {k: _plain(v) for k, v in dataclasses.asdict(task).items()}


def rng_state(rng: Optional[np.random.Generator]) -> Optional[dict]:
    """The bit generator's state of ``rng`` (a dict of ints and strings), or None."""
    return None if rng is None else dict(copy.deepcopy(rng.bit_generator.state))


def rng_from(state: Any, name: str) -> Optional[np.random.Generator]:
    """A generator continuing from ``state`` (from :func:`rng_state`), or None."""
    if state is None:
        return None
    try:
        bitgen = getattr(np.random, state["bit_generator"])()
        bitgen.state = state
    except Exception as e:  # any malformed state: the error names the key
        raise InputError(f"`{name}`: not the state of a numpy bit generator ({e!r})") from None
    return np.random.Generator(bitgen)


def checked(snap: Any, fmt: str, keys: tuple) -> dict:
    """``snap`` as a snapshot dict of format ``fmt`` and :data:`VERSION` with exactly ``keys``."""
    if not isinstance(snap, dict):
        raise InputError(
            f"`snapshot`: expected the dict of a {fmt} snapshot (got {type(snap).__name__})"
        )
    if snap.get("format") != fmt:
        raise InputError(f"`{_name('format')}` must be {fmt!r} (got {snap.get('format')!r})")
    if snap.get("version") != VERSION:
        raise InputError(
            f"`{_name('version')}`: version {snap.get('version')!r} is not known "
            f"(this crane_twin reads version {VERSION})"
        )
    unknown = [k for k in snap if k not in keys]
    if unknown:
        raise InputError(
            f"`snapshot`: unknown keys {unknown} (a version-{VERSION} snapshot has {list(keys)})"
        )
    missing = [k for k in keys if k not in snap]
    if missing:
        raise InputError(f"`{_name(missing[0])}` is missing")
    return snap


def array(snap: dict, key: str, shape: tuple, dtype: Any = np.float64) -> np.ndarray:
    """``snap[key]`` as a fresh array of ``shape``, or an ``InputError`` naming the key."""
    try:
        a = np.array(snap[key], dtype=dtype)
    except (TypeError, ValueError) as e:
        raise InputError(f"`{_name(key)}`: not an array of {np.dtype(dtype).name} ({e})") from None
    if a.shape != shape:
        raise InputError(f"`{_name(key)}`: expected shape {shape}, got {a.shape}")
    if a.dtype.kind == "f" and not np.all(np.isfinite(a)):
        raise InputError(f"`{_name(key)}`: not finite")
    return a


def _episode_dict(e: Optional[tuple]) -> Optional[dict]:
    if e is None:
        return None
    params, stiction, state, target = e
    return {
        "params": params.to_dict(),
        "stiction": [None if s is None else [float(s[0]), float(s[1])] for s in stiction],
        "state": [float(v) for v in state],
        "target": [float(v) for v in target],
    }


def _episode_from(d: Any, name: str) -> Optional[tuple]:
    if d is None:
        return None
    try:
        params = _params(d["params"], f'{name}["params"]')
        stiction = [None if s is None else (float(s[0]), float(s[1])) for s in d["stiction"]]
        state = np.array(d["state"], dtype=np.float64)
        target = np.array(d["target"], dtype=np.float64)
        ok = len(stiction) == 3 and state.shape == (10,) and target.shape == (2,)
    except (InputError, ParameterError):
        raise
    except Exception as e:  # a malformed entry: the error names it
        raise InputError(f"`{name}`: not an episode draw ({e!r})") from None
    if not ok:
        raise InputError(
            f"`{name}`: expected 3 stiction entries, 10 state values and 2 target values"
        )
    return params, stiction, state, target


def core_snapshot(core: Any) -> dict:
    """The keys of :data:`CORE_KEYS` for an ``_Episodes``."""
    return {
        "task": task_dict(core.task),
        "params": core.base.to_dict(),
        "batch": core.batch.snapshot(),
        "targets": core.targets.tolist(),
        "prev": core.prev.tolist(),
        "t": [int(v) for v in core.t],
        "episodes": [_episode_dict(e) for e in core.episodes],
        "hold": [int(v) for v in core.hold],
        "randomized": core.drawn.tolist(),
        "noise_rngs": [rng_state(r) for r in core.noise_rngs],
        "fifo": None if core.fifo is None else core.fifo.tolist(),
        "fifo_head": int(core.head),
    }


def _params(d: Any, name: str) -> Params:
    if not isinstance(d, dict):
        raise InputError(f"`{name}`: expected the dict of Params.to_dict()")
    return Params.from_dict(d)


def _batch(snap: Any) -> CraneBatch:
    """The batch of ``snapshot["batch"]``; errors name that key."""
    inner = _name("batch")
    try:
        return CraneBatch.from_snapshot(snap)
    except ParameterError as e:
        msg = str(e).replace("snapshot", inner, 1)
        raise ParameterError(msg, e.field, e.problem, e.value) from None
    except InputError as e:
        raise InputError(str(e).replace("`snapshot", "`" + inner, 1)) from None


def checked_params(snap: Any) -> Params:
    """The nominal parameters of an env snapshot (to rebuild an env when unpickling)."""
    if not isinstance(snap, dict) or "params" not in snap:
        raise InputError('`snapshot["params"]` is missing')
    return _params(snap["params"], _name("params"))


def core_values(core: Any, snap: dict) -> dict:
    """Checked new values of ``core``'s attributes from ``snap`` (nothing assigned yet)."""
    m = core.m
    if snap["task"] != task_dict(core.task):
        raise InputError(f"`{_name('task')}` differs from this env's task {core.task}")
    if _params(snap["params"], _name("params")) != core.base:
        raise InputError(f"`{_name('params')}` differs from this env's nominal parameters")
    batch = _batch(snap["batch"])
    if len(batch) != m:
        raise InputError(f"`{_name('batch')}` holds {len(batch)} simulators, this env {m}")
    episodes = snap["episodes"]
    if not isinstance(episodes, list) or len(episodes) != m:
        raise InputError(f"`{_name('episodes')}`: expected a list of {m} entries")
    t = array(snap, "t", (m,), np.int64)
    if np.any(t < 0):
        raise InputError(f"`{_name('t')}`: periods must be >= 0")
    hold = array(snap, "hold", (m,), np.int64)
    if np.any(hold < 0):
        raise InputError(f"`{_name('hold')}`: counts must be >= 0")
    noise = snap["noise_rngs"]
    if not isinstance(noise, list) or len(noise) != m:
        raise InputError(f"`{_name('noise_rngs')}`: expected a list of {m} entries")
    noise_rngs = [rng_from(r, f"{_name('noise_rngs')}[{i}]") for i, r in enumerate(noise)]
    noisy = core.task.obs_noise_std is not None
    for i, (r, e) in enumerate(zip(noise_rngs, episodes)):
        if not noisy and r is not None:
            raise InputError(f"`{_name('noise_rngs')}`: this env's task has no observation noise")
        if noisy and r is None and e is not None:
            raise InputError(
                f"`{_name('noise_rngs')}[{i}]`: an episode with observation noise needs its "
                f"noise generator's state"
            )
    k = core.task.obs_latency
    if k == 0:
        if snap["fifo"] is not None:
            raise InputError(f"`{_name('fifo')}`: this env's task has no latency (expected None)")
        fifo = None
    else:
        fifo = array(snap, "fifo", (m, k, 12))
    head = snap["fifo_head"]
    if not (isinstance(head, int) and not isinstance(head, bool) and 0 <= head < max(k, 1)):
        raise InputError(f"`{_name('fifo_head')}` must be an int in [0, {max(k, 1)}) (got {head!r})")
    return {
        "batch": batch,
        "targets": array(snap, "targets", (m, 2)),
        "prev": array(snap, "prev", (m, 5)),
        "t": t,
        "episodes": [_episode_from(e, f"{_name('episodes')}[{i}]") for i, e in enumerate(episodes)],
        "hold": hold,
        "drawn": array(snap, "randomized", (m, len(core.names))),
        "noise_rngs": noise_rngs,
        "fifo": fifo,
        "head": head,
    }

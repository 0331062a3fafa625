"""Pickling and full snapshots of the Gymnasium environments (issue 23: "Snapshot and
restore: get_state / set_state on ... the env"; pickle for vector envs with spawn, Ray actors
and checkpointing): a restored or unpickled environment gives the same observations and
rewards, across episode ends and unseeded resets, and a bad snapshot names its key."""

from __future__ import annotations

import copy
import json
import pickle

import numpy as np
import pytest

import crane_twin as ct

gym = pytest.importorskip("gymnasium")
from crane_twin.envs import CraneAntiSwayEnv, CraneAntiSwayVectorEnv  # noqa: E402

PROTOCOLS = [0, pickle.DEFAULT_PROTOCOL, pickle.HIGHEST_PROTOCOL]


def _bits(a):
    return np.ascontiguousarray(a, dtype=np.float64).view(np.uint64)


def _with(snap, **changes):
    s = copy.deepcopy(snap)
    s.update(changes)
    return s


def _run_env(env, actions):
    """Steps through ``actions``, resetting (unseeded: the env's generator draws) at the end
    of each episode; returns observations and rewards."""
    obs, rew = [], []
    for a in actions:
        o, r, term, trunc, _ = env.step(a)
        obs.append(o)
        rew.append(r)
        if term or trunc:
            o, _ = env.reset()
            obs.append(o)
    return np.array(obs), np.array(rew)


@pytest.mark.parametrize("protocol", PROTOCOLS)
def test_a_pickled_env_continues_bit_for_bit_across_episodes(protocol):
    env = gym.make("CraneAntiSway-v0", episode_steps=25)
    env.reset(seed=11)
    actions = np.random.default_rng(3).uniform(-12, 12, size=(80, 3)).astype(np.float32)
    _run_env(env, actions[:10])
    twin = pickle.loads(pickle.dumps(env, protocol=protocol))
    o1, r1 = _run_env(env, actions[10:])
    o2, r2 = _run_env(twin, actions[10:])
    np.testing.assert_array_equal(_bits(o1), _bits(o2))
    np.testing.assert_array_equal(_bits(r1), _bits(r2))
    assert twin.unwrapped.np_random_seed == env.unwrapped.np_random_seed == 11


def test_env_snapshot_step_restore_step_gives_the_same_arrays():
    env = gym.make("CraneAntiSway-v0", episode_steps=30)
    env.reset(seed=5, options={"target": (0.2, 0.3)})
    actions = np.random.default_rng(6).uniform(-12, 12, size=(100, 3)).astype(np.float32)
    _run_env(env, actions[:7])
    snap = env.unwrapped.snapshot()
    o1, r1 = _run_env(env, actions)  # crosses three episode ends: unseeded resets draw
    env.unwrapped.restore(json.loads(json.dumps(snap)))
    o2, r2 = _run_env(env, actions)
    np.testing.assert_array_equal(_bits(o1), _bits(o2))
    np.testing.assert_array_equal(_bits(r1), _bits(r2))
    # into a fresh env of the same task
    fresh = CraneAntiSwayEnv(episode_steps=30)
    fresh.restore(snap)
    o3, _ = _run_env(fresh, actions)
    np.testing.assert_array_equal(_bits(o1), _bits(o3))


def test_an_unstarted_env_pickles_and_still_needs_a_reset():
    env = CraneAntiSwayEnv()
    twin = pickle.loads(pickle.dumps(env))
    with pytest.raises(gym.error.ResetNeeded):
        twin.step(np.zeros(3, dtype=np.float32))
    a, _ = env.reset(seed=1)
    b, _ = twin.reset(seed=1)
    np.testing.assert_array_equal(a, b)


def test_a_rendering_env_pickles_and_renders_the_same_picture():
    env = CraneAntiSwayEnv(render_mode="rgb_array", episode_steps=20)
    env.reset(seed=2)
    env.step(np.array([6.0, -6.0, 0.0], dtype=np.float32))
    twin = pickle.loads(pickle.dumps(env))
    assert twin.render_mode == "rgb_array"
    np.testing.assert_array_equal(env.render(), twin.render())


@pytest.mark.parametrize("protocol", PROTOCOLS)
def test_a_pickled_vector_env_continues_bit_for_bit_through_autoreset(protocol):
    venv = gym.make_vec(
        "CraneAntiSway-v0", num_envs=3, vectorization_mode="vector_entry_point", episode_steps=10
    )
    venv.reset(seed=21)
    actions = np.random.default_rng(7).uniform(-12, 12, size=(40, 3, 3)).astype(np.float32)
    for a in actions[:4]:
        venv.step(a)
    twin = pickle.loads(pickle.dumps(venv, protocol=protocol))
    snap = venv.snapshot()
    outs = []
    for v in (venv, twin):
        outs.append(np.array([v.step(a)[0] for a in actions[4:]]))
    np.testing.assert_array_equal(_bits(outs[0]), _bits(outs[1]))
    venv.restore(json.loads(json.dumps(snap)))
    again = np.array([venv.step(a)[0] for a in actions[4:]])
    np.testing.assert_array_equal(_bits(outs[0]), _bits(again))


def test_bad_env_snapshots_raise_input_error_naming_the_key():
    env = CraneAntiSwayEnv(episode_steps=20)
    env.reset(seed=1)
    snap = env.snapshot()
    for changes, words in [
        ({"targets": [[0.1, 0.2, 0.3]]}, ['snapshot["targets"]', "shape"]),
        ({"rng": {"bit_generator": "Nope"}}, ['snapshot["rng"]']),
        ({"started": "yes"}, ['snapshot["started"]']),
        ({"t": [-1]}, ['snapshot["t"]']),
        ({"episodes": [{"params": {}}]}, ['snapshot["episodes"][0]']),
        ({"version": 9}, ['snapshot["version"]']),
        ({"extra": 1}, ["unknown keys", "extra"]),
        ({"batch": "x"}, ['snapshot["batch"]']),
    ]:
        with pytest.raises(ct.InputError) as e:
            env.restore(_with(snap, **changes))
        for w in words:
            assert w in str(e.value), (changes, str(e.value))
    with pytest.raises(ct.InputError, match="task"):
        CraneAntiSwayEnv(episode_steps=21).restore(snap)
    with pytest.raises(ct.InputError, match="params"):
        CraneAntiSwayEnv(episode_steps=20, params={"payload_mass": 0.3}).restore(snap)
    with pytest.raises(ct.InputError, match="format"):
        CraneAntiSwayVectorEnv(num_envs=1, episode_steps=20).restore(snap)
    assert env.snapshot() == snap, "a failed restore changes nothing"

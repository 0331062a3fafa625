"""`CraneAntiSway-v0`: Gymnasium's checker, seeded reproducibility, the vector env equal to
single envs, and the env's trajectory equal to the model's bits."""

from __future__ import annotations

import numpy as np
import pytest

gym = pytest.importorskip("gymnasium")

import crane_twin as ct  # noqa: E402  (registers the env)
from crane_twin.envs import CraneAntiSwayEnv, CraneAntiSwayVectorEnv  # noqa: E402
from gymnasium.utils.env_checker import check_env  # noqa: E402


def _bits(a):
    return np.ascontiguousarray(a, dtype=np.float64).view(np.uint64)


def _episode(env, seed, actions):
    obs, info = env.reset(seed=seed)
    out = [obs]
    states = [info["state"]]
    rewards = []
    for a in actions:
        obs, r, term, trunc, info = env.step(a)
        out.append(obs)
        states.append(info["state"])
        rewards.append(r)
        assert not term
    return np.array(out), np.array(rewards), np.array(states), trunc


def test_registered_and_passes_check_env():
    assert "CraneAntiSway-v0" in gym.registry
    env = gym.make("CraneAntiSway-v0")
    check_env(env.unwrapped, skip_render_check=True)


def test_seeded_episode_is_reproducible_and_seed_matters():
    env = CraneAntiSwayEnv(episode_steps=60)
    actions = np.random.default_rng(0).uniform(-12, 12, size=(60, 3)).astype(np.float32)
    o1, r1, s1, trunc = _episode(env, 42, actions)
    o2, r2, s2, _ = _episode(CraneAntiSwayEnv(episode_steps=60), 42, actions)
    assert trunc, "the episode has a fixed length"
    np.testing.assert_array_equal(_bits(o1), _bits(o2))
    np.testing.assert_array_equal(_bits(r1), _bits(r2))
    o3, _, _, _ = _episode(env, 43, actions)
    assert not np.array_equal(o1[0], o3[0]), "another seed draws another episode"


def test_env_trajectory_is_the_models_bits():
    env = CraneAntiSwayEnv(episode_steps=80)
    actions = np.random.default_rng(1).uniform(-12, 12, size=(80, 3)).astype(np.float32)
    _, _, states, _ = _episode(env, 5, actions)
    params, stiction, state0, _ = env._core.episodes[0]
    sub = env.task.substeps
    u = np.repeat(actions.astype(np.float64), sub, axis=0)
    r = ct.rollout(u, params=params, h=env.task.h, state=state0, stiction=stiction)
    np.testing.assert_array_equal(_bits(states[:, :5]), _bits(r["q"][::sub]))
    np.testing.assert_array_equal(_bits(states[:, 5:]), _bits(r["qd"][::sub]))
    # Stiction is on and the trolley does stick in this episode.
    assert stiction[0] is not None and (r["modes"][1:, :2] == 0).any()


def test_observation_is_quantised():
    env = CraneAntiSwayEnv()
    obs, info = env.reset(seed=3)
    for _ in range(20):
        obs, *_ , info = env.step(env.action_space.sample())
    res = ct.envs.ENCODER_RES
    cells = obs[:5] / res - 0.5  # readings are cell centres, relative to count 0
    np.testing.assert_allclose(cells, np.round(cells), atol=1e-6)
    true = info["state"][:5] - ct.envs.ENCODER_ZERO
    assert np.all(np.abs(obs[:5] - true) <= res / 2 + 1e-12)
    assert env.observation_space.contains(obs)


def test_vector_env_equals_single_envs_with_autoreset():
    n, steps = 3, 25
    venv = gym.make_vec("CraneAntiSway-v0", num_envs=n, vectorization_mode="vector_entry_point", episode_steps=10)
    assert isinstance(venv.unwrapped, CraneAntiSwayVectorEnv)
    actions = np.random.default_rng(2).uniform(-12, 12, size=(steps, n, 3)).astype(np.float32)
    obs, _ = venv.reset(seed=100)
    vobs, vrew, vtrunc = [obs], [], []
    for a in actions:
        obs, r, term, trunc, _ = venv.step(a)
        vobs.append(obs)
        vrew.append(r)
        vtrunc.append(trunc)
    vobs, vrew, vtrunc = np.array(vobs), np.array(vrew), np.array(vtrunc)
    assert vtrunc[9].all() and not vtrunc[10].any() and vtrunc[20].all()
    for i in range(n):
        env = CraneAntiSwayEnv(episode_steps=10)
        obs, _ = env.reset(seed=100 + i)
        np.testing.assert_array_equal(_bits(obs), _bits(vobs[0, i]))
        done = False
        for k in range(steps):
            if done:  # next-step autoreset: this step's action is ignored
                obs, _ = env.reset()
                r = 0.0
                done = False
            else:
                obs, r, _, done, _ = env.step(actions[k, i])
            np.testing.assert_array_equal(_bits(obs), _bits(vobs[k + 1, i]))
            assert _bits(np.float64(r)) == _bits(vrew[k, i])


def test_bad_env_configuration_raises():
    with pytest.raises(ValueError, match="substeps"):
        CraneAntiSwayEnv(substeps=0)
    with pytest.raises(ValueError, match="num_envs"):
        CraneAntiSwayVectorEnv(num_envs=0)
    env = CraneAntiSwayEnv()
    with pytest.raises(gym.error.ResetNeeded):
        env.step(np.zeros(3, dtype=np.float32))
    env.reset(seed=0)
    with pytest.raises(ct.InputError):
        env.step(np.array([np.nan, 0, 0], dtype=np.float32))


def test_rgb_array_render_draws_the_crane_headless():
    env = gym.make("CraneAntiSway-v0", render_mode="rgb_array", episode_steps=40)
    assert env.metadata["render_modes"] == ["rgb_array", "human"]
    env.reset(seed=3)
    first = env.render()
    assert first.shape == (300, 600, 3) and first.dtype == np.uint8
    assert len(np.unique(first.reshape(-1, 3), axis=0)) >= 4, "trolley, rope, payload, target"
    for _ in range(30):
        env.step(np.array([12.0, 12.0, 0.0], dtype=np.float32))
    moved = env.render()
    assert moved.shape == first.shape
    assert np.any(moved != first), "the picture follows the crane"
    env.close()
    assert CraneAntiSwayEnv().render() is None, "no render mode: nothing drawn"
    with pytest.raises(ValueError, match="render_mode"):
        CraneAntiSwayEnv(render_mode="ascii")


def test_human_render_runs_headless_when_matplotlib_is_there(monkeypatch):
    pytest.importorskip("matplotlib")
    monkeypatch.setenv("MPLBACKEND", "Agg")
    env = CraneAntiSwayEnv(render_mode="human", episode_steps=5)
    env.reset(seed=1)
    env.step(np.zeros(3, dtype=np.float32))
    env.close()


def test_reset_options_set_the_target_and_unknown_ones_are_refused():
    env = CraneAntiSwayEnv(episode_steps=10)
    obs, info = env.reset(seed=7, options={"target": (0.2, 0.3)})
    np.testing.assert_array_equal(info["target"], [0.2, 0.3])
    np.testing.assert_array_equal(obs[-2:], [0.2, 0.3])
    # the rest of the seeded episode is the one drawn without the option
    obs0, _ = CraneAntiSwayEnv(episode_steps=10).reset(seed=7)
    np.testing.assert_array_equal(obs[:10], obs0[:10])
    with pytest.raises(ct.InputError, match="not known"):
        env.reset(options={"goal": (0.2, 0.3)})
    with pytest.raises(ct.InputError, match="outside"):
        env.reset(options={"target": (5.0, 0.3)})
    venv = CraneAntiSwayVectorEnv(num_envs=2, episode_steps=10)
    _, info = venv.reset(seed=7, options={"target": (0.25, 0.35)})
    np.testing.assert_array_equal(info["target"], [[0.25, 0.35], [0.25, 0.35]])


def test_task_ranges_are_checked_when_made_not_at_reset():
    # the package's InputError (a ValueError), at construction (more in test_env_options.py)
    with pytest.raises(ct.InputError, match="stiction_ratio"):
        ct.envs.Task(stiction_ratio=(0.5, 0.9))
    with pytest.raises(ct.InputError, match="payload_kg"):
        ct.envs.Task(payload_kg=(0.0, 0.5))
    with pytest.raises(ct.InputError, match="stiction_ratio"):
        CraneAntiSwayEnv(stiction_ratio=(0.5, 0.9))

"""The Task options of `CraneAntiSway-v0` (issue 23, "Task options, each documented and seeded"):
normalised actions, observation noise and latency, termination on success and at the travel
limits, the randomised parameters in `info`, domain randomisation of every physical parameter,
`reset(options=...)` for targets and initial states. Each option is checked for what it does,
for `check_env`, for seeded reproducibility and for the vector env equal to Gymnasium's
`SyncVectorEnv` of single envs bit for bit."""

from __future__ import annotations

import copy
import json
import pickle

import numpy as np
import pytest

gym = pytest.importorskip("gymnasium")

import crane_twin as ct  # noqa: E402
from crane_twin.envs import (  # noqa: E402
    OBS_NAMES,
    RESET_OPTIONS,
    CraneAntiSwayEnv,
    CraneAntiSwayVectorEnv,
    Task,
    randomized_names,
)
from gymnasium.utils.env_checker import check_env  # noqa: E402

#: Every range of domain randomisation beyond the default ones, and a Stribeck velocity range.
ALL_RANGES = dict(
    stribeck_velocity=(0.002, 0.01),
    gain_scale=(0.9, 1.1),
    inertia_scale=(0.8, 1.2),
    rope_friction_scale=(0.7, 1.3),
    rope_stiction_ratio=(1.05, 1.3),
    swing_damping_scale=(0.5, 2.0),
    trolley_mass_scale=(0.9, 1.1),
    rail_mass_scale=(0.9, 1.1),
    param_scale={"gravity": (0.99, 1.01), "x.viscous_pos": (0.9, 1.1)},
)
NOISE = (1e-3, 2e-3, 5e-4, 3e-3, 0.0, 0.01, 0.02, 0.0, 0.05, 0.1)

#: Option combinations that check_env and the vector env comparison run with.
COMBOS = {
    "default": {},
    "normalized": dict(normalize_actions=True),
    "noise": dict(obs_noise_std=NOISE),
    "latency": dict(obs_latency=3),
    "noise+latency": dict(obs_noise_std=NOISE, obs_latency=2),
    "success": dict(terminate_on_success=True, success_radius=0.2, success_hold=3),
    "limits": dict(terminate_on_limits=True, limit_margin=0.09, limit_penalty=1.5),
    "randomised": ALL_RANGES,
    "everything": dict(
        normalize_actions=True,
        obs_noise_std=NOISE,
        obs_latency=4,
        terminate_on_success=True,
        success_radius=0.15,
        success_hold=2,
        terminate_on_limits=True,
        limit_margin=0.05,
        limit_penalty=2.0,
        **ALL_RANGES,
    ),
}


def _bits(a):
    return np.ascontiguousarray(a, dtype=np.float64).view(np.uint64)


def _run(env, seed, actions, options=None):
    """One episode from ``reset(seed)`` through ``actions`` (stopping when it ends): arrays of
    observations (reset's first), rewards, states (reset's first), flags and infos."""
    obs, info = env.reset(seed=seed, options=options)
    out = {"obs": [obs], "state": [info["state"]], "rew": [], "term": [], "trunc": [], "info": [info]}
    for a in actions:
        obs, r, term, trunc, info = env.step(a)
        for k, v in (("obs", obs), ("state", info["state"]), ("rew", r), ("term", term),
                     ("trunc", trunc), ("info", info)):
            out[k].append(v)
        if term or trunc:
            break
    return {k: (v if k == "info" else np.array(v)) for k, v in out.items()}


def _payload_xy(state):
    """The payload's horizontal position from the model state (the model's geometry)."""
    x, y, l, a, b = state[:5]
    return np.array([x + l * np.sin(b) * np.sin(a), y + l * np.cos(a)])


def _anti_sway(obs, kp=80.0, kd=10.0, ks=40.0):
    """A hand-tuned PD with swing feedback [V] (reaches the default success criterion)."""
    x, y, _, a, b, xd, yd, _, _, _, tx, ty = obs
    u = [kp * (tx - x) - kd * xd + ks * b, kp * (ty - y) - kd * yd - ks * a, 0.0]
    return np.clip(u, -12, 12).astype(np.float32)


# --- check_env and the vector env, for every combination ---------------------------------


@pytest.mark.parametrize("name", list(COMBOS))
def test_check_env_passes_with_each_option_combination(name):
    env = CraneAntiSwayEnv(**COMBOS[name])
    check_env(env, skip_render_check=True)
    # and through gym.make's keyword arguments
    made = gym.make("CraneAntiSway-v0", **COMBOS[name])
    assert made.unwrapped.task == env.task


@pytest.mark.parametrize("name", list(COMBOS))
def test_vector_env_equals_sync_vector_env_bit_for_bit(name):
    fields = dict(COMBOS[name], episode_steps=40)
    n, steps = 3, 100
    venv = CraneAntiSwayVectorEnv(num_envs=n, **fields)
    sync = gym.vector.SyncVectorEnv(
        [lambda: CraneAntiSwayEnv(**fields) for _ in range(n)],
        autoreset_mode=gym.vector.AutoresetMode.NEXT_STEP,
    )
    rng = np.random.default_rng(8)
    high = float(venv.single_action_space.high[0])
    # X and Y pushed one way: some episodes end at a travel limit (or succeed) early
    actions = rng.uniform(0.2 * high, high, size=(steps, n, 3)).astype(np.float32)
    actions[:, :, 2] = rng.uniform(-high, high, size=(steps, n))
    o1, i1 = venv.reset(seed=30)
    o2, i2 = sync.reset(seed=30)
    np.testing.assert_array_equal(_bits(o1), _bits(o2))
    terminated = truncated = 0
    for a in actions:
        o1, r1, t1, u1, i1 = venv.step(a)
        o2, r2, t2, u2, i2 = sync.step(a)
        np.testing.assert_array_equal(_bits(o1), _bits(o2))
        np.testing.assert_array_equal(_bits(r1), _bits(r2))
        np.testing.assert_array_equal(t1, t2)
        np.testing.assert_array_equal(u1, u2)
        np.testing.assert_array_equal(i1["is_success"], i2["is_success"])
        np.testing.assert_array_equal(i1["target"], i2["target"])
        assert list(i1["randomized"]) == list(randomized_names(venv.task))
        for key, col in i1["randomized"].items():
            np.testing.assert_array_equal(_bits(col), _bits(i2["randomized"][key]))
        terminated += int(t1.sum())
        truncated += int(u1.sum())
    assert truncated >= n, "episodes were truncated and autoreset during the comparison"
    if COMBOS[name].get("terminate_on_limits") or COMBOS[name].get("terminate_on_success"):
        assert terminated >= 1, "and some terminated"
    else:
        assert terminated == 0


# --- 1. normalised actions ----------------------------------------------------------------


def test_normalised_actions_are_12_volts_times_the_action():
    env = CraneAntiSwayEnv(normalize_actions=True, episode_steps=50)
    assert env.action_space.low.tolist() == [-1.0] * 3
    assert env.action_space.high.tolist() == [1.0] * 3
    assert CraneAntiSwayEnv().action_space.high.tolist() == [12.0] * 3, "default unchanged"
    a = np.random.default_rng(4).uniform(-1, 1, size=(50, 3)).astype(np.float32)
    norm = _run(env, 9, a)
    volts = _run(CraneAntiSwayEnv(episode_steps=50), 9, a.astype(np.float64) * 12.0)
    for k in ("obs", "rew", "state"):
        np.testing.assert_array_equal(_bits(norm[k]), _bits(volts[k]))
    # beyond +-1 saturates like +-12 V does
    sat = _run(CraneAntiSwayEnv(normalize_actions=True, episode_steps=50), 9, np.sign(a) * 3.0)
    full = _run(CraneAntiSwayEnv(normalize_actions=True, episode_steps=50), 9, np.sign(a))
    np.testing.assert_array_equal(_bits(sat["obs"]), _bits(full["obs"]))
    assert not np.array_equal(full["obs"], norm["obs"])


# --- 2. observation noise and latency ------------------------------------------------------


def test_observation_noise_has_the_given_spread_and_leaves_the_plant_alone():
    steps = 600
    a = np.random.default_rng(5).uniform(-6, 6, size=(steps, 3)).astype(np.float32)
    clean = _run(CraneAntiSwayEnv(episode_steps=steps), 17, a)
    noisy = _run(CraneAntiSwayEnv(episode_steps=steps, obs_noise_std=NOISE), 17, a)
    # the plant, reward and the episode's draws are those of the noise-free env
    np.testing.assert_array_equal(_bits(noisy["state"]), _bits(clean["state"]))
    np.testing.assert_array_equal(_bits(noisy["rew"]), _bits(clean["rew"]))
    assert noisy["info"][0]["randomized"] == clean["info"][0]["randomized"]
    err = noisy["obs"] - clean["obs"]
    # positions far from the observation bounds: no clipping, so err is the noise itself
    for j, (name, std) in enumerate(zip(OBS_NAMES, NOISE)):
        if std == 0:
            assert np.all(err[:, j] == 0), name
        else:
            assert 0.85 * std < err[:, j].std() < 1.15 * std, (name, err[:, j].std(), std)
            assert abs(err[:, j].mean()) < 4 * std / np.sqrt(len(err)), name
    assert np.all(err[:, 10:] == 0), "the target is exact"
    # independent across quantities and periods
    assert abs(np.corrcoef(err[:, 0], err[:, 1])[0, 1]) < 0.15
    assert abs(np.corrcoef(err[1:, 0], err[:-1, 0])[0, 1]) < 0.15
    # seeded: the same noise again, another seed another noise
    again = _run(CraneAntiSwayEnv(episode_steps=steps, obs_noise_std=NOISE), 17, a)
    np.testing.assert_array_equal(_bits(again["obs"]), _bits(noisy["obs"]))
    other = _run(CraneAntiSwayEnv(episode_steps=steps, obs_noise_std=NOISE), 18, a)
    assert not np.array_equal(other["obs"][:, 0] - np.round(other["obs"][:, 0], 3), err[:, 0])


def test_noise_by_name_and_clipping_to_the_space():
    task = Task(obs_noise_std={"x": 0.5, "alphad": 0.1})
    assert task.obs_noise_std == (0.5, 0, 0, 0, 0, 0, 0, 0, 0.1, 0)
    assert Task(obs_noise_std=(0.0,) * 10).obs_noise_std is None, "all zero: no noise"
    env = CraneAntiSwayEnv(task=task, episode_steps=100)
    r = _run(env, 3, np.zeros((100, 3), dtype=np.float32))
    x = r["obs"][:, 0]
    space = env.observation_space
    assert np.all(r["obs"] >= space.low) and np.all(r["obs"] <= space.high)
    assert np.any(x == space.low[0]) or np.any(x == space.high[0]), "a 0.5 m spread is clipped"


def test_latency_delays_observations_by_k_periods():
    a = np.random.default_rng(6).uniform(-12, 12, size=(60, 3)).astype(np.float32)
    for base_fields in ({}, {"obs_noise_std": NOISE}):
        now = _run(CraneAntiSwayEnv(episode_steps=60, **base_fields), 21, a)
        for k in (1, 4):
            late = _run(CraneAntiSwayEnv(episode_steps=60, obs_latency=k, **base_fields), 21, a)
            np.testing.assert_array_equal(_bits(late["obs"][0]), _bits(now["obs"][0]))
            for j in range(1, len(a) + 1):
                np.testing.assert_array_equal(_bits(late["obs"][j]), _bits(now["obs"][max(j - k, 0)]))
            np.testing.assert_array_equal(_bits(late["state"]), _bits(now["state"]))
            np.testing.assert_array_equal(_bits(late["rew"]), _bits(now["rew"]))


# --- 3. success and the travel limits ------------------------------------------------------


def _criterion_held(run, task):
    """Per step, whether the success criterion held for the last ``success_hold`` periods,
    recomputed from the true states and the target."""
    ok = []
    for state, info in zip(run["state"][1:], run["info"][1:]):
        d = np.linalg.norm(_payload_xy(state) - info["target"])
        swing = np.hypot(state[3] - np.pi / 2, state[4])
        ok.append(d <= task.success_radius and swing <= task.success_swing)
    ok = np.array(ok)
    h = task.success_hold
    return np.array([j + 1 >= h and ok[j + 1 - h : j + 1].all() for j in range(len(ok))])


def test_success_is_the_documented_criterion_and_can_terminate():
    env = CraneAntiSwayEnv()  # defaults: 1 cm, 0.02 rad, 50 periods; not terminating
    obs, _ = env.reset(seed=2)
    run = {"state": [env._core.batch.states[0].copy()], "info": [None], "obs": [obs]}
    for _ in range(env.task.episode_steps):
        obs, _, term, trunc, info = env.step(_anti_sway(obs))
        run["state"].append(info["state"])
        run["info"].append(info)
        assert not term
    flags = np.array([i["is_success"] for i in run["info"][1:]])
    np.testing.assert_array_equal(flags, _criterion_held(run, env.task))
    assert flags.any(), "the anti-sway PD reaches the target"
    first = int(np.argmax(flags))
    assert first + 1 >= env.task.success_hold
    # terminating on success ends the same episode at that step, with the same rewards
    env2 = CraneAntiSwayEnv(terminate_on_success=True)
    obs, info = env2.reset(seed=2)
    assert info["is_success"] is False
    for j in range(env2.task.episode_steps):
        obs, _, term, trunc, info = env2.step(_anti_sway(obs))
        if term:
            break
    assert term and not trunc and info["is_success"] and j == first
    with pytest.raises(gym.error.ResetNeeded):
        env2.step(np.zeros(3, dtype=np.float32))
    # doing nothing does not succeed
    idle = _run(CraneAntiSwayEnv(terminate_on_success=True), 2, np.zeros((500, 3), dtype=np.float32))
    assert not idle["term"].any() and idle["trunc"][-1]
    assert not any(i["is_success"] for i in idle["info"])


def test_leaving_the_travel_limits_terminates_with_the_penalty():
    push = np.tile(np.array([12.0, 0.0, 0.0], dtype=np.float32), (300, 1))
    task = dict(terminate_on_limits=True, limit_margin=0.02, limit_penalty=3.0, episode_steps=300)
    ended = _run(CraneAntiSwayEnv(**task), 4, push)
    free = _run(CraneAntiSwayEnv(episode_steps=300), 4, push)
    x_max = ct.Params()["x.max"]
    x = ended["state"][:, 0]
    j = len(ended["rew"])  # the terminating step
    assert ended["term"][-1] and not ended["trunc"][-1] and j < 300
    assert x[j] >= x_max - 0.02 and np.all(x[:j] < x_max - 0.02)
    assert not ended["info"][-1]["is_success"]
    # the same episode without the option: the same rewards but the penalty, and it goes on
    np.testing.assert_array_equal(_bits(ended["rew"][:-1]), _bits(free["rew"][: j - 1]))
    assert ended["rew"][-1] == free["rew"][j - 1] - 3.0
    assert not free["term"].any() and len(free["rew"]) == 300
    assert free["state"][-1][0] == x_max, "the model's end stop holds the trolley at the limit"
    # the rope limit counts too
    lower = np.tile(np.array([0.0, 0.0, 12.0], dtype=np.float32), (300, 1))
    rope = _run(CraneAntiSwayEnv(**task), 4, lower)
    assert rope["term"][-1] and rope["state"][-1][2] >= ct.Params()["rope.max"] - 0.02


# --- 4. and 5. randomised parameters in info, domain randomisation ----------------------


def test_info_carries_the_episodes_randomised_parameters():
    env = CraneAntiSwayEnv(**ALL_RANGES)
    base = ct.Params()
    obs, info = env.reset(seed=12)
    rnd, params = info["randomized"], info["params"]
    assert tuple(rnd) == randomized_names(env.task)
    assert params == env._core.episodes[0][0]
    task = env.task
    for name, value in rnd.items():
        field = name.split(".")[0]
        rng = dict((n, (lo, hi)) for n, lo, hi in task.param_scale).get(name[12:]) \
            if field == "param_scale" else getattr(task, field)
        assert rng[0] <= value <= rng[1], name
    # each drawn value is what the episode's parameters hold
    assert params["payload_mass"] == rnd["payload_kg"]
    for axis in ("x", "y", "rope"):
        assert params[f"{axis}.gain"] == base[f"{axis}.gain"] * rnd[f"gain_scale.{axis}"]
        assert params[f"{axis}.inertia"] == base[f"{axis}.inertia"] * rnd[f"inertia_scale.{axis}"]
    for axis in ("x", "y"):
        assert params[f"{axis}.viscous_neg"] == base[f"{axis}.viscous_neg"] * rnd[f"friction_scale.{axis}"]
    assert params["x.viscous_pos"] == (
        base["x.viscous_pos"] * rnd["friction_scale.x"] * rnd["param_scale.x.viscous_pos"]
    )
    f = rnd["rope_friction_scale"]
    assert params["rope.viscous_pos"] == base["rope.viscous_pos"] * f
    assert params["rope.dry_pos"] == [c * f for c in base["rope.dry_pos"]]
    assert params["damping_alpha"] == base["damping_alpha"] * rnd["swing_damping_scale.alpha"]
    assert params["damping_beta"] == base["damping_beta"] * rnd["swing_damping_scale.beta"]
    assert params["trolley_mass"] == base["trolley_mass"] * rnd["trolley_mass_scale"]
    assert params["rail_mass"] == base["rail_mass"] * rnd["rail_mass_scale"]
    assert params["gravity"] == base["gravity"] * rnd["param_scale.gravity"]
    stiction = env._core.episodes[0][1]
    assert stiction == [
        (rnd["stiction_ratio.x"], rnd["stribeck_velocity.x"]),
        (rnd["stiction_ratio.y"], rnd["stribeck_velocity.y"]),
        (rnd["rope_stiction_ratio"], rnd["stribeck_velocity.rope"]),
    ]
    # every step's info has them too (a copy: changing it changes nothing)
    _, _, _, _, info2 = env.step(env.action_space.sample())
    assert info2["randomized"] == rnd
    info2["randomized"]["payload_kg"] = -1.0
    assert env.step(env.action_space.sample())[4]["randomized"] == rnd
    # the next episode draws other values
    assert env.reset()[1]["randomized"] != rnd


def test_every_physical_parameter_can_be_randomised():
    """Over a few episodes of the task with every range set, every field of Params but the
    travel limits takes several values, and the rope has stiction."""
    env = CraneAntiSwayEnv(**dict(ALL_RANGES, param_scale={"gravity": (0.99, 1.01)}))
    base = ct.Params()
    seen = {name: set() for name in ct.Params.names()}
    for seed in range(4):
        env.reset(seed=seed)
        params, stiction, _, _ = env._core.episodes[0]
        assert stiction[2] is not None
        for name in seen:
            v = params[name]
            seen[name].add(tuple(v) if isinstance(v, list) else v)
    for name, values in seen.items():
        if name.endswith((".min", ".max")):
            assert values == {base[name]}, name
        else:
            assert len(values) == 4, f"{name} is not randomised"


def test_more_ranges_keep_the_default_draws_of_a_seeded_episode():
    d = CraneAntiSwayEnv()
    r = CraneAntiSwayEnv(**ALL_RANGES)
    _, i1 = d.reset(seed=77)
    _, i2 = r.reset(seed=77)
    np.testing.assert_array_equal(i1["state"], i2["state"])
    np.testing.assert_array_equal(i1["target"], i2["target"])
    for k, v in i1["randomized"].items():
        assert i2["randomized"][k] == v


def test_default_task_draws_what_it_always_drew():
    """The default task's episode is the 10 documented uniform draws, in order."""
    env = CraneAntiSwayEnv()
    _, info = env.reset(seed=5)
    u = np.random.Generator(np.random.PCG64(5)).uniform
    t = env.task
    draws = [u(*t.payload_kg), u(*t.friction_scale), u(*t.friction_scale), u(*t.stiction_ratio),
             u(*t.stiction_ratio), u(*t.start_x), u(*t.start_y), u(*t.start_l), u(*t.start_x),
             u(*t.start_y)]
    assert list(info["randomized"].values()) == draws[:5]
    np.testing.assert_array_equal(info["state"][:3], draws[5:8])
    np.testing.assert_array_equal(info["target"], draws[8:])


@pytest.mark.parametrize(
    "fields, words",
    [
        (dict(stiction_ratio=(0.5, 0.9)), ["stiction_ratio", ">= 1"]),
        (dict(rope_stiction_ratio=(0.9, 1.2)), ["rope_stiction_ratio", ">= 1"]),
        (dict(payload_kg=(0.0, 0.5)), ["payload_kg"]),
        (dict(gain_scale=(1.2, 0.8)), ["gain_scale", "range"]),
        (dict(gain_scale=(0.0, 1.0)), ["gain_scale", "> 0"]),
        (dict(inertia_scale=(np.nan, 1.0)), ["inertia_scale"]),
        (dict(swing_damping_scale=0.5), ["swing_damping_scale", "pair"]),
        (dict(rope_friction_scale="ab"), ["rope_friction_scale"]),
        (dict(trolley_mass_scale=(1, 2, 3)), ["trolley_mass_scale"]),
        (dict(rail_mass_scale=(-1.0, 1.0)), ["rail_mass_scale"]),
        (dict(stribeck_velocity=0.0), ["stribeck_velocity"]),
        (dict(stribeck_velocity=(0.0, 0.01)), ["stribeck_velocity"]),
        (dict(param_scale={"x.gian": (0.9, 1.1)}), ["param_scale", "x.gian"]),
        (dict(param_scale={"x.max": (0.9, 1.1)}), ["param_scale", "travel limit"]),
        (dict(param_scale={"gravity": (0.0, 1.1)}), ["param_scale", "gravity"]),
        (dict(obs_noise_std=(0.1,) * 9), ["obs_noise_std"]),
        (dict(obs_noise_std=(-0.1,) + (0.0,) * 9), ["obs_noise_std", "'x'"]),
        (dict(obs_noise_std={"x_target": 0.1}), ["obs_noise_std", "x_target"]),
        (dict(obs_latency=-1), ["obs_latency"]),
        (dict(obs_latency=1.5), ["obs_latency"]),
        (dict(obs_latency=True), ["obs_latency"]),
        (dict(obs_latency=10**7), ["obs_latency", "at most"]),
        (dict(normalize_actions="yes"), ["normalize_actions"]),
        (dict(terminate_on_success=1), ["terminate_on_success"]),
        (dict(success_radius=0.0), ["success_radius"]),
        (dict(success_swing=-1.0), ["success_swing"]),
        (dict(success_hold=0), ["success_hold"]),
        (dict(limit_margin=-0.01), ["limit_margin"]),
        (dict(limit_penalty=np.inf), ["limit_penalty"]),
        (dict(substeps=0), ["substeps"]),
        (dict(h=0.5), ["Task.h"]),
    ],
)
def test_bad_task_fields_raise_input_error_when_made(fields, words):
    with pytest.raises(ct.InputError) as e:
        Task(**fields)
    for w in words:
        assert w in str(e.value), (fields, str(e.value))
    # the same through the env's and gym.make's keyword arguments, before any reset
    with pytest.raises(ct.InputError):
        gym.make("CraneAntiSway-v0", **fields)


def test_start_ranges_must_fit_the_travel_limits_when_the_env_is_made():
    with pytest.raises(ct.InputError, match="start_x"):
        CraneAntiSwayEnv(start_x=(0.1, 0.9))
    with pytest.raises(ct.InputError, match="start_l"):
        CraneAntiSwayVectorEnv(num_envs=2, start_l=(0.05, 0.4))
    with pytest.raises(ct.InputError, match="start_y"):
        CraneAntiSwayEnv(terminate_on_limits=True, limit_margin=0.05, start_y=(0.1, 0.6))
    with pytest.raises(ct.InputError, match="start_x"):
        CraneAntiSwayEnv(params={"x": {"max": 0.3}})
    CraneAntiSwayEnv(terminate_on_limits=True, limit_margin=0.05)  # fits


def test_ranges_are_stored_as_float_tuples_and_tasks_compare_by_value():
    t = Task(payload_kg=[0.3, 0.5], gain_scale=[1, 2], param_scale=[("gravity", 1, 1)])
    assert t.payload_kg == (0.3, 0.5) and t.gain_scale == (1.0, 2.0)
    assert t.param_scale == (("gravity", 1.0, 1.0),)
    assert t == Task(payload_kg=(0.3, 0.5), gain_scale=(1.0, 2.0), param_scale={"gravity": (1, 1)})
    assert Task() == Task(param_scale={}, obs_noise_std=None)
    assert hash(t) == hash(Task(payload_kg=(0.3, 0.5), gain_scale=(1, 2), param_scale={"gravity": (1, 1)}))


# --- 6. reset options ---------------------------------------------------------------------


def test_reset_state_option_sets_the_initial_state_and_keeps_the_draws():
    assert RESET_OPTIONS == ("target", "state")
    start = np.array([0.2, 0.35, 0.4, np.pi / 2 + 0.2, -0.1, 0.05, 0.0, 0.0, 0.3, 0.0])
    env = CraneAntiSwayEnv(episode_steps=30)
    obs, info = env.reset(seed=8, options={"state": start, "target": (0.3, 0.2)})
    np.testing.assert_array_equal(_bits(info["state"]), _bits(start))
    np.testing.assert_array_equal(info["target"], [0.3, 0.2])
    np.testing.assert_array_equal(obs[:5], ct.envs.quantise(start[:5]))
    np.testing.assert_array_equal(obs[5:10], np.zeros(5))
    _, plain = CraneAntiSwayEnv(episode_steps=30).reset(seed=8)
    assert info["randomized"] == plain["randomized"]
    # it swings from the given angle: the first steps follow the model from that state
    actions = np.zeros((10, 3), dtype=np.float32)
    run = [env.step(a)[4]["state"] for a in actions]
    params, stiction, s0, _ = env._core.episodes[0]
    np.testing.assert_array_equal(s0, start)
    r = ct.rollout(np.zeros((100, 3)), params=params, state=start, stiction=stiction)
    np.testing.assert_array_equal(_bits(np.array(run)[:, :5]), _bits(r["q"][10::10]))
    assert abs(run[-1][3] - np.pi / 2) > 0.05, "swinging"


def test_bad_reset_options_raise_clear_errors():
    env = CraneAntiSwayEnv()
    with pytest.raises(ct.InputError, match="not known"):
        env.reset(options={"goal": (0.2, 0.3)})
    with pytest.raises(ct.InputError, match="not known"):
        env.reset(options={"target": (0.2, 0.3), "State": np.zeros(10)})
    with pytest.raises(ct.InputError, match="10 finite"):
        env.reset(options={"state": np.zeros(9)})
    with pytest.raises(ct.InputError, match="10 finite"):
        env.reset(options={"state": [np.nan] * 10})
    bad = [0.6, 0.3, 0.35, np.pi / 2, 0, 0, 0, 0, 0, 0]
    with pytest.raises(ct.ParameterError, match="options") as e:
        env.reset(options={"state": bad})
    assert e.value.field == "state.q[0]" and e.value.problem == "out_of_limits"
    with pytest.raises(ct.ParameterError) as e:
        env.reset(options={"state": [0.2, 0.3, 0.35, np.pi / 2 + 1.45, 0, 0, 0, 0, 0, 0]})
    assert e.value.field == "state.q[3]"
    with pytest.raises(ct.InputError, match="outside"):
        env.reset(options={"target": (0.2, 0.9)})
    with pytest.raises(ct.InputError, match="dict"):
        env.reset(options=[("target", (0.2, 0.3))])
    # a refused option changes nothing, not even the seed: the next unseeded reset is the one
    # that follows reset(seed=3)
    env.reset(seed=3)
    with pytest.raises(ct.InputError):
        env.reset(seed=4, options={"goal": 1})
    a, _ = env.reset()
    ref = CraneAntiSwayEnv()
    ref.reset(seed=3)
    b, _ = ref.reset()
    np.testing.assert_array_equal(_bits(a), _bits(b))


def test_vector_reset_options_one_for_all_or_one_per_env():
    venv = CraneAntiSwayVectorEnv(num_envs=3, episode_steps=10)
    targets = np.array([[0.15, 0.2], [0.25, 0.3], [0.35, 0.4]])
    states = np.tile([0.2, 0.3, 0.35, np.pi / 2, 0, 0, 0, 0, 0, 0], (3, 1))
    states[:, 0] = [0.12, 0.22, 0.32]
    obs, info = venv.reset(seed=1, options={"target": targets, "state": states})
    np.testing.assert_array_equal(info["target"], targets)
    np.testing.assert_array_equal(venv._core.batch.states, states)
    for i in range(3):
        o, _ = CraneAntiSwayEnv(episode_steps=10).reset(
            seed=1 + i, options={"target": targets[i], "state": states[i]}
        )
        np.testing.assert_array_equal(_bits(o), _bits(obs[i]))
    _, info = venv.reset(options={"target": (0.2, 0.3)})
    np.testing.assert_array_equal(info["target"], [[0.2, 0.3]] * 3)
    with pytest.raises(ct.InputError, match="one per env"):
        venv.reset(options={"target": targets[:2]})
    with pytest.raises(ct.InputError, match="not known"):
        venv.reset(options={"targets": targets})


# --- snapshots and pickling with the options ------------------------------------------------


def _steps(env, actions):
    out = []
    for a in actions:
        o, r, term, trunc, info = env.step(a)
        out.append(np.concatenate([o, [r, term, trunc, info["is_success"]]]))
        if term or trunc:
            out.append(env.reset()[0])
            out[-1] = np.concatenate([out[-1], [0, 0, 0, 0]])
    return np.array(out)


def test_snapshot_and_pickle_continue_bit_for_bit_with_every_option():
    fields = dict(COMBOS["everything"], episode_steps=25)
    env = CraneAntiSwayEnv(**fields)
    env.reset(seed=13)
    rng = np.random.default_rng(14)
    actions = rng.uniform(-0.3, 1.0, size=(90, 3)).astype(np.float32)
    _steps(env, actions[:7])
    snap = env.snapshot()
    assert snap["version"] == 2
    assert np.array(snap["fifo"]).shape == (1, 4, 12), "the latency FIFO is in the snapshot"
    assert snap["noise_rngs"][0] is not None, "and the noise generator"
    twin = pickle.loads(pickle.dumps(env))
    deep = copy.deepcopy(env)
    first = _steps(env, actions[7:])
    assert first[:, 13].any(), "episodes ended (terminations and truncations) in the run"
    env.restore(json.loads(json.dumps(snap)))
    for other in (env, twin, deep):
        np.testing.assert_array_equal(_bits(_steps(other, actions[7:])), _bits(first))
    fresh = CraneAntiSwayEnv(**fields)
    fresh.restore(snap)
    np.testing.assert_array_equal(_bits(_steps(fresh, actions[7:])), _bits(first))


def test_vector_snapshot_and_pickle_with_every_option():
    fields = dict(COMBOS["everything"], episode_steps=15)
    venv = CraneAntiSwayVectorEnv(num_envs=3, **fields)
    venv.reset(seed=40)
    actions = np.random.default_rng(41).uniform(-0.3, 1, size=(50, 3, 3)).astype(np.float32)
    for a in actions[:5]:
        venv.step(a)
    snap = venv.snapshot()
    twin = pickle.loads(pickle.dumps(venv))

    def run(v):
        return np.array([np.concatenate([s[0].ravel(), s[1], s[2], s[3]]) for s in map(v.step, actions[5:])])

    first = run(venv)
    venv.restore(json.loads(json.dumps(snap)))
    np.testing.assert_array_equal(_bits(run(venv)), _bits(first))
    np.testing.assert_array_equal(_bits(run(twin)), _bits(first))


def test_bad_option_snapshots_name_the_key_and_change_nothing():
    env = CraneAntiSwayEnv(obs_noise_std=NOISE, obs_latency=2, episode_steps=20)
    env.reset(seed=1)
    env.step(env.action_space.sample())
    snap = env.snapshot()
    for changes, key in [
        ({"fifo": [[[0.0] * 12] * 3]}, 'snapshot["fifo"]'),
        ({"fifo": None}, 'snapshot["fifo"]'),
        ({"fifo_head": 2}, 'snapshot["fifo_head"]'),
        ({"noise_rngs": [{"bit_generator": "Nope"}]}, 'snapshot["noise_rngs"][0]'),
        ({"noise_rngs": []}, 'snapshot["noise_rngs"]'),
        ({"noise_rngs": [None]}, 'snapshot["noise_rngs"][0]'),
        ({"hold": [-1]}, 'snapshot["hold"]'),
        ({"randomized": [[0.1, 0.2]]}, 'snapshot["randomized"]'),
    ]:
        bad = dict(copy.deepcopy(snap), **changes)
        with pytest.raises(ct.InputError) as e:
            env.restore(bad)
        assert key in str(e.value), (changes, str(e.value))
    assert env.snapshot() == snap
    plain = CraneAntiSwayEnv(episode_steps=20)
    with pytest.raises(ct.InputError, match="task"):
        plain.restore(snap)
    old = dict(copy.deepcopy(snap), version=1)
    with pytest.raises(ct.InputError, match="version"):
        env.restore(old)

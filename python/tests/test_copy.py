"""Copies of simulators and environments (issue 23): exact, independent, continuing alike."""

import copy

import gymnasium as gym
import numpy as np

import crane_twin as ct


def test_a_copied_crane_continues_bit_for_bit_and_independently():
    c = ct.Crane(stiction=(1.6, 0.01))
    c.advance([3.0, -2.0, 1.0], 500)
    for copier in (copy.copy, copy.deepcopy):
        d = copier(c)
        for u in ([4.0, 0.0, 0.0], [0.0, -5.0, 1.0], [0.0, 0.0, 0.0]):
            assert np.array_equal(c.advance(u, 300), d.advance(u, 300))
            assert c.modes == d.modes
        c.advance([12.0, 0.0, 0.0], 10)
        assert not np.array_equal(c.state, d.state)
        d.advance([12.0, 0.0, 0.0], 10)
        assert np.array_equal(c.state, d.state)


def test_a_copied_batch_continues_bit_for_bit():
    b = ct.CraneBatch([ct.Params(), ct.Params()])
    u = np.array([[2.0, -1.0, 0.5], [-3.0, 2.0, 0.0]])
    b.step(u)
    d = copy.deepcopy(b)
    for _ in range(50):
        assert np.array_equal(b.step(u), d.step(u))


def test_a_copied_environment_gives_the_same_episode():
    env = gym.make("CraneAntiSway-v0")
    env.reset(seed=3)
    action = np.full(env.action_space.shape, 0.3, dtype=env.action_space.dtype)
    for _ in range(10):
        env.step(action)
    twin = copy.deepcopy(env)
    for _ in range(20):
        a = env.step(action)
        b = twin.step(action)
        assert np.array_equal(a[0], b[0]) and a[1] == b[1]

"""The PettingZoo ParallelEnv: PettingZoo's own API test, agents per robot, determinism."""

from __future__ import annotations

import numpy as np
import pytest
from pettingzoo.test import parallel_api_test, parallel_seed_test

import regatta.pettingzoo
from conftest import world

PAIR = world("regatta_pair.wbt")


def test_parallel_api_test_passes():
    env = regatta.pettingzoo.parallel_env(PAIR, duration=2.0)
    parallel_api_test(env, num_cycles=200)


def test_parallel_seed_test_passes():
    parallel_seed_test(lambda: regatta.pettingzoo.parallel_env(PAIR, duration=1.0))


def test_agents_are_the_robots_and_share_one_world():
    env = regatta.pettingzoo.parallel_env(PAIR, duration=0.64, render_mode="rgb_array")
    assert env.possible_agents == ["red", "blue"]
    observations, infos = env.reset(seed=2)
    assert set(observations) == {"red", "blue"}
    assert observations["red"].shape == (24,) and env.state().shape == (48,)
    steps = 0
    while env.agents:
        actions = {"red": np.array([1.0, 1.0]), "blue": np.array([-1.0, 0.5])}
        observations, rewards, terminations, truncations, infos = env.step(actions)
        steps += 1
        assert env.world["red"].wheels == (20, 20) and env.world["blue"].wheels == (-20, 10)
        for agent in ("red", "blue"):
            info = infos[agent]
            assert info["reward"] == rewards[agent]
            assert info["visits"] == len(env.world[agent].visits)
            assert info["contacts"] == env.world[agent].contacts
            assert info["fitness"] == env.world[agent].fitness
    assert steps == 20 and all(truncations.values())
    assert env.render().shape == (256, 256, 3)


def test_an_agent_without_an_action_stands_still():
    env = regatta.pettingzoo.parallel_env(PAIR, duration=1.0)
    env.reset(seed=1)
    env.step({"red": np.array([0.5, 0.5])})
    assert env.world["blue"].wheels == (0, 0) and env.world["red"].wheels == (10, 10)


def test_a_subset_of_robots_as_agents():
    env = regatta.pettingzoo.parallel_env(PAIR, agents=["blue"], duration=1.0)
    assert env.possible_agents == ["blue"]
    env.reset(seed=1)
    for _ in range(20):
        env.step({"blue": np.zeros(2)})
    # red sails on with its own controller.
    assert env.world["red"].wheels != (0, 0)
    with pytest.raises(ValueError, match="no robot named"):
        regatta.pettingzoo.parallel_env(PAIR, agents=["green"])

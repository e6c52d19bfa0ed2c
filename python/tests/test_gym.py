"""The Gymnasium environments: the checker, registration, the Rust-batched vector
environment with Gymnasium 1.x autoreset, and determinism for any thread count."""

from __future__ import annotations

import json

import gymnasium
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from gymnasium.vector import AutoresetMode

import regatta
import regatta.gym
from conftest import world

ENVS = ["regatta/Regatta-v0", "regatta/Avoidance-v0"]


@pytest.mark.parametrize("env_id", ENVS)
def test_check_env_passes(env_id):
    env = gymnasium.make(env_id, render_mode="rgb_array", duration=2.0)
    check_env(env.unwrapped, skip_render_check=False)
    obs, info = env.reset(seed=1)
    assert env.observation_space.contains(obs)
    frame = env.render()
    assert frame.shape == (256, 256, 3) and frame.dtype == np.uint8


def test_regatta_env_spaces_and_episode():
    env = gymnasium.make("regatta/Regatta-v0", duration=1.0)
    assert env.observation_space.shape == (24,) and env.observation_space.dtype == np.float32
    assert env.action_space.shape == (2,)
    obs, info = env.reset(seed=3)
    steps = 0
    while True:
        obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
        steps += 1
        assert not terminated
        if truncated:
            break
    assert steps == 32  # 1 s of 32 ms steps, the last one partial


def test_step_info_holds_visits_contacts_and_the_reward():
    env = gymnasium.make("regatta/Regatta-v0", duration=60.0)
    env.reset(seed=1)
    entered = []
    for _ in range(600):
        _, reward, _, _, info = env.step(np.array([1.0, 1.0], dtype=np.float32))
        assert set(info) == {
            "time", "visits", "new_visits", "contacts", "touching", "reward", "fitness"
        }
        assert info["reward"] == reward
        entered += info["new_visits"]
    robot = env.unwrapped.world[env.unwrapped.world.controlled[0]]
    assert entered == list(robot.visits) and info["visits"] == len(entered)
    assert info["contacts"] == robot.contacts
    # The regatta fitness so far and its terms, as `regatta run --json` names them.
    fitness = info["fitness"]
    assert set(fitness) == {"value", "cyclic_visits", "other_visits", "contact_s"}
    assert fitness == robot.fitness
    assert fitness["cyclic_visits"] + fitness["other_visits"] <= len(entered)
    assert fitness["value"] == pytest.approx(
        fitness["cyclic_visits"] - 0.5 * fitness["contact_s"]
    )


def test_vector_step_info_holds_each_copy_s_visits_contacts_and_fitness():
    envs = regatta.gym.RegattaVectorEnv(3, duration=30.0)
    envs.reset(seed=1)
    total = np.zeros(3)
    for _ in range(600):
        _, rewards, _, _, info = envs.step(np.full((3, 2), 1.0, dtype=np.float32))
        total += rewards
        for key in ("time", "visits", "contacts", "touching", "reward", "fitness"):
            assert info[key].shape == (3,) and info["_" + key].all(), key
        np.testing.assert_array_equal(info["reward"], rewards)
    # The fitness so far is the sum of the rewards; the counts are each copy's robot's.
    np.testing.assert_allclose(info["fitness"], total)
    for i in range(3):
        summary = json.loads(envs.vector_world.summary_json(i))["robots"][0]
        assert info["visits"][i] == len(summary["visits"])
        assert info["contacts"][i] == summary["contacts"]["events"]
    envs.close()


def test_reset_with_a_seed_reproduces_and_without_one_continues():
    env = gymnasium.make("regatta/Regatta-v0", duration=2.0)
    a, _ = env.reset(seed=5)
    b, _ = env.reset(seed=5)
    np.testing.assert_array_equal(a, b)
    env.reset(seed=5)
    rollout = [env.step(np.array([0.8, 0.2]))[0] for _ in range(50)]
    env.reset(seed=5)
    again = [env.step(np.array([0.8, 0.2]))[0] for _ in range(50)]
    np.testing.assert_array_equal(np.stack(rollout), np.stack(again))
    # Later episodes draw their seeds from the first: the same sequence each time.
    env.reset(seed=9)
    seeds = [env.reset()[1]["seed"] for _ in range(3)]
    env.reset(seed=9)
    assert seeds == [env.reset()[1]["seed"] for _ in range(3)]


def test_make_vec_gives_the_rust_batched_env():
    envs = gymnasium.make_vec(
        "regatta/Regatta-v0", num_envs=8, vectorization_mode="vector_entry_point", duration=1.0
    )
    assert isinstance(envs.unwrapped, regatta.gym.RegattaVectorEnv)
    assert envs.metadata["autoreset_mode"] == AutoresetMode.NEXT_STEP
    obs, info = envs.reset(seed=10)
    assert obs.shape == (8, 24) and obs.dtype == np.float32
    assert envs.observation_space.contains(obs)
    obs, rewards, terminated, truncated, info = envs.step(envs.action_space.sample())
    assert rewards.shape == (8,) and rewards.dtype == np.float64
    assert terminated.dtype == np.bool_ and truncated.dtype == np.bool_
    envs.close()


def test_vector_copies_are_the_single_env_seeded_s_plus_i():
    envs = regatta.gym.RegattaVectorEnv(4, duration=1.0)
    obs, _ = envs.reset(seed=20)
    actions = np.random.default_rng(1).uniform(-1, 1, size=(40, 4, 2)).astype(np.float32)
    trace = [obs] + [envs.step(a)[0] for a in actions[:20]]
    for i in range(4):
        single = gymnasium.make("regatta/Regatta-v0", duration=1.0)
        first, _ = single.reset(seed=20 + i)
        np.testing.assert_array_equal(first, trace[0][i])
        for k in range(20):
            np.testing.assert_array_equal(single.step(actions[k, i])[0], trace[k + 1][i])


def test_next_step_autoreset():
    # 0.32 s: 10 steps per episode.
    envs = regatta.gym.RegattaVectorEnv(3, duration=0.32, threads=2)
    envs.reset(seed=1)
    actions = np.full((3, 2), 0.5, dtype=np.float32)
    for k in range(1, 11):
        obs, rewards, terminated, truncated, info = envs.step(actions)
        assert truncated.all() == (k == 10)
        assert not terminated.any()
    # The next step starts new episodes: the actions are ignored, rewards 0, not done.
    obs, rewards, terminated, truncated, info = envs.step(actions * 0 + 1)
    assert (rewards == 0).all() and not truncated.any() and not terminated.any()
    episodes = envs.vector_world.episodes()
    assert [steps for _, steps, _ in episodes] == [0, 0, 0]
    assert [count for _, _, count in episodes] == [2, 2, 2]
    # The new episode's first observation is a fresh world under its new seed.
    for i, (seed, _, _) in enumerate(episodes):
        assert seed != 1 + i
        fresh = regatta.World(regatta.embedded_world("regatta.wbt") and "regatta.wbt",
                              text=regatta.embedded_world("regatta.wbt"), seed=seed)
        np.testing.assert_array_equal(obs[i], fresh.observation[0])


def test_same_step_autoreset_returns_the_final_observation():
    nxt = regatta.gym.RegattaVectorEnv(2, duration=0.32)
    same = regatta.gym.RegattaVectorEnv(2, duration=0.32, autoreset_mode=AutoresetMode.SAME_STEP)
    assert same.metadata["autoreset_mode"] == AutoresetMode.SAME_STEP
    nxt.reset(seed=4)
    same.reset(seed=4)
    actions = np.full((2, 2), 0.3, dtype=np.float32)
    for _ in range(9):
        a = nxt.step(actions)
        b = same.step(actions)
        np.testing.assert_array_equal(a[0], b[0])
        assert "final_obs" not in b[4]
    last_next = nxt.step(actions)
    last_same = same.step(actions)
    assert last_same[3].all()
    np.testing.assert_array_equal(np.stack(last_same[4]["final_obs"]), last_next[0])
    assert last_same[4]["_final_obs"].all()
    restarted = nxt.step(actions)
    np.testing.assert_array_equal(restarted[0], last_same[0])


def test_disabled_autoreset_and_reset_mask():
    envs = regatta.gym.RegattaVectorEnv(2, duration=0.32, autoreset_mode="Disabled")
    envs.reset(seed=1)
    for _ in range(10):
        obs, r, term, trunc, _ = envs.step(np.zeros((2, 2)))
    assert trunc.all()
    obs, _ = envs.reset(options={"reset_mask": np.array([True, False])})
    episodes = envs.vector_world.episodes()
    assert episodes[0][1] == 0 and episodes[1][1] == 10


def test_results_do_not_depend_on_threads():
    actions = np.random.default_rng(2).uniform(-1, 1, size=(60, 16, 2))

    def run(threads):
        v = regatta.VectorWorld(world("regatta.wbt"), 16, seed=3, threads=threads, duration=1.0)
        out = [v.reset(seed=3)]
        rewards = []
        for a in actions:
            obs, rew, *_ = v.step(a)
            out.append(obs)
            rewards.append(rew)
        return np.stack(out), np.stack(rewards)

    one, r1 = run(1)
    two, r2 = run(2)
    np.testing.assert_array_equal(one, two)
    np.testing.assert_array_equal(r1, r2)


def test_vector_env_errors():
    with pytest.raises(ValueError, match="num_envs"):
        regatta.VectorWorld(world("regatta.wbt"), 0)
    with pytest.raises(ValueError, match="autoreset"):
        regatta.VectorWorld(world("regatta.wbt"), 2, autoreset="sometimes")
    v = regatta.VectorWorld(world("regatta.wbt"), 2)
    with pytest.raises(ValueError, match="expected 4 action values"):
        v.step(np.zeros((3, 2)))
    with pytest.raises(ValueError, match="expected 2 seeds"):
        v.reset(seed=[1, 2, 3])
    with pytest.raises(ValueError, match="out of range"):
        v.render(5)
    with pytest.raises(ValueError, match="render_mode"):
        regatta.gym.RegattaEnv(render_mode="human")


def test_vector_render_gives_one_frame_per_copy():
    envs = regatta.gym.RegattaVectorEnv(3, render_mode="rgb_array", render_size=64)
    envs.reset(seed=0)
    frames = envs.render()
    assert len(frames) == 3 and frames[0].shape == (64, 64, 3)


def test_other_worlds_and_robots(tmp_path):
    env = regatta.gym.RegattaEnv(world("regatta_pair.wbt"), robot="blue", duration=1.0)
    obs, _ = env.reset(seed=1)
    assert obs.shape == (24,)
    env.step(np.array([1.0, 1.0]))
    assert env.unwrapped.world["blue"].wheels == (20, 20)
    # The other robot sails on its own controller.
    for _ in range(30):
        env.step(np.array([0.0, 0.0]))
    assert env.unwrapped.world["red"].wheels != (0, 0)


def test_a_robot_that_observes_nothing_still_steps(tmp_path):
    blind = tmp_path / "blind.wbt"
    blind.write_text(
        '#VRML_SIM R2023b utf8\nWorldInfo { coordinateSystem "NUE" }\nArena { size 1 1 }\n'
        'Khepera { network NeuralNetwork { inputs [ "bias" ] weights [ 0 0 ] } }\n'
    )
    for mode in ["next_step", "same_step"]:
        v = regatta.VectorWorld(blind, 3, autoreset=mode, duration=0.32)
        assert v.reset(seed=1).shape == (3, 0)
        for _ in range(10):
            obs, rewards, terminated, truncated, restarted, finals = v.step(np.ones((3, 2)))
        assert obs.shape == (3, 0) and truncated.all()
        assert [steps for _, steps, _ in v.episodes()] == [0 if mode == "same_step" else 10] * 3

"""``regatta/Webots-v0``: one robot of a Webots project as a Gymnasium environment. Its spaces
come from the robot's devices, an episode is reproduced by its seed, the project's other robots
run their own controllers in lock-step, and bad arguments are clear errors."""

from __future__ import annotations

import shutil
from pathlib import Path

import gymnasium
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import regatta  # noqa: F401  (registers the environments)
from conftest import ROOT, regatta_bin

AVOID = ROOT / "webots" / "tests" / "projects" / "avoid"
PROXIMITY = [f"ps{i}" for i in range(8)]


@pytest.fixture(scope="module")
def binary(tmp_path_factory):
    found = regatta_bin()
    if found is None:
        pytest.skip("no regatta binary: build it (cargo build -p regatta) or set REGATTA_BIN")
    if shutil.which("cc") is None:
        pytest.skip("no C compiler: the controller library is built with cc")
    return found


@pytest.fixture(scope="module")
def sdk(tmp_path_factory):
    return tmp_path_factory.mktemp("webots-sdk")


def make(binary, sdk, world=AVOID / "worlds" / "epuck_avoid.wbt", **kwargs):
    return gymnasium.make(
        "regatta/Webots-v0", world=str(world), regatta=str(binary), sdk=str(sdk), **kwargs
    )


def braitenberg(observation) -> np.ndarray:
    """Obstacle avoidance from the eight proximity sensors, in rad/s."""
    left = right = 3.14
    weights = [-1.3, -1.0, -0.6, 0.0, 0.0, 0.6, 1.0, 1.3]
    for i, name in enumerate(PROXIMITY):
        x = max((observation[name][0] - 70.0) / 1000.0, 0.0)
        left += weights[i] * x * 6.28
        right -= weights[i] * x * 6.28
    return np.array([left, right])


def episode(env, seed, steps=None):
    observation, info = env.reset(seed=seed)
    trace = [observation["ps0"][0]]
    rewards = 0.0
    n = 0
    while True:
        observation, reward, terminated, truncated, info = env.step(braitenberg(observation))
        trace.append(observation["ps0"][0])
        rewards += reward
        n += 1
        if terminated or truncated or (steps is not None and n >= steps):
            return np.array(trace), rewards, info, n


def test_the_spaces_are_the_robots_devices_and_the_checker_passes(binary, sdk):
    env = make(binary, sdk, duration=1.0)
    assert env.unwrapped.robot_name == "e-puck"
    assert env.unwrapped.motor_names == ["left wheel motor", "right wheel motor"]
    assert env.action_space.shape == (2,)
    spaces = env.observation_space.spaces
    for name in PROXIMITY:
        assert spaces[name].shape == (1,)
    assert spaces["camera"].shape == (39, 52, 3) and spaces["camera"].dtype == np.uint8
    assert spaces["accelerometer"].shape == (3,)
    check_env(env.unwrapped, skip_render_check=True)
    env.close()


def test_an_episode_is_its_seeds_and_is_truncated_after_its_duration(binary, sdk):
    env = make(
        binary,
        sdk,
        duration=3.0,
        devices=PROXIMITY,
        reward=lambda observation, info: -observation["ps0"][0] / 1000.0,
    )
    assert set(env.observation_space.spaces) == set(PROXIMITY)
    first, reward_first, info, steps = episode(env, seed=5)
    again, reward_again, _, _ = episode(env, seed=5)
    other, _, _, _ = episode(env, seed=6)
    # 32 ms steps: one at reset, then 93 to reach 3 s.
    assert steps == 93 and abs(info["time"] - 3.008) < 1e-9
    assert np.array_equal(first, again) and reward_first == reward_again
    assert reward_first < 0
    # The proximity sensors' noise is drawn from the seed.
    assert not np.array_equal(first, other)
    env.close()


def test_the_projects_other_robots_run_their_own_controllers(binary, sdk, tmp_path):
    project = tmp_path / "project"
    (project / "worlds").mkdir(parents=True)
    counter = project / "controllers" / "counter"
    counter.mkdir(parents=True)
    (counter / "counter.py").write_text(
        "from controller import Robot\n"
        "robot = Robot()\n"
        "steps = 0\n"
        "while robot.step(32) != -1:\n"
        "    steps += 1\n"
        "    with open('steps.txt', 'w') as f:\n"
        "        f.write(str(steps))\n"
    )
    world = (AVOID / "worlds" / "epuck_avoid.wbt").read_text()
    world = world.replace('controller "epuck_avoid"', 'controller "none"')
    world += 'E-puck {\n  translation 0.3 -0.3 0\n  name "other"\n  controller "counter"\n}\n'
    (project / "worlds" / "w.wbt").write_text(world)
    env = make(binary, sdk, world=project / "worlds" / "w.wbt", robot="e-puck", duration=1.0)
    _, _, info, steps = episode(env, seed=1)
    env.close()
    # The other robot's controller stepped with the agent, a step at a time (it may have
    # taken one more before the run was stopped).
    counted = int((counter / "steps.txt").read_text())
    assert steps + 1 <= counted <= steps + 2, (steps, counted)


def test_bad_arguments_are_clear_errors(binary, sdk, tmp_path):
    with pytest.raises(FileNotFoundError, match="no world file"):
        make(binary, sdk, world=tmp_path / "missing.wbt")
    with pytest.raises(ValueError, match="no sensor 'ps9'"):
        make(binary, sdk, devices=["ps9"])
    with pytest.raises(ValueError, match="positive number of seconds"):
        make(binary, sdk, duration=0)
    env = make(binary, sdk, duration=1.0, devices=PROXIMITY)
    env.reset(seed=1)
    with pytest.raises(ValueError, match="2 motor velocities"):
        env.step(np.zeros(3))
    env.close()

"""regatta.World: observations, determinism, robots by name, logs and summaries as the
command line gives them, and errors as Python exceptions."""

from __future__ import annotations

import errno
import json

import numpy as np
import pytest

import regatta
from conftest import ROOT, world

REGATTA = world("regatta.wbt")


def test_observation_is_ir_ambient_and_pooled_retina():
    w = regatta.World(REGATTA, seed=3)
    names = w.observation_names
    assert names == [f"ir{i}" for i in range(8)] + [f"ambient{i}" for i in range(8)] + [
        f"retina{i}" for i in range(8)
    ]
    obs = w.observation
    assert obs.dtype == np.float32 and obs.shape == (1, 24)
    low, high = w.observation_bounds
    assert np.all(obs >= low) and np.all(obs <= high)
    robot = w["khepera"]
    # IR and ambient are the readings / 1024, exactly.
    np.testing.assert_array_equal(obs[0, :8], robot.proximity / np.float32(1024))
    np.testing.assert_array_equal(obs[0, 8:16], robot.ambient / np.float32(1024))
    # The retina sees the lit buoys: its sectors are not all the same.
    assert len(set(obs[0, 16:].tolist())) > 1
    assert w.controlled == ["khepera"] and w.speed_scale == [20.0]


def test_actions_drive_the_wheels_in_units_of_the_speed_scale():
    w = regatta.World(REGATTA, seed=1)
    w.step([0.5, -0.25])
    assert w["khepera"].wheels == (10, -5)
    # Rounded and clamped to the robot's -127..127 pulses per 10 ms.
    w.step(np.array([[100.0, -0.026]]))
    assert w["khepera"].wheels == (127, -1)
    # No actions keeps the last ones.
    w.step()
    assert w["khepera"].wheels == (127, -1)
    x0 = w["khepera"].pose
    w.step([1, 1])
    assert w["khepera"].pose != x0


def test_same_seed_same_observations_different_seed_different():
    rng = np.random.default_rng(0)
    actions = rng.uniform(-1, 1, size=(300, 2))

    def trace(seed):
        w = regatta.World(REGATTA, seed=seed)
        out = [w.observation.copy()]
        for a in actions:
            out.append(w.step(a))
        return np.stack(out), w.summary_json()

    a, summary_a = trace(7)
    b, summary_b = trace(7)
    c, _ = trace(8)
    np.testing.assert_array_equal(a, b)
    assert summary_a == summary_b
    assert not np.array_equal(a, c)
    # reset(seed) starts the same run again.
    w = regatta.World(REGATTA, seed=1)
    w.step([1, 1])
    first = w.reset(7)
    np.testing.assert_array_equal(first, a[0])
    assert w.steps == 0 and w.seed == 7


def test_run_equals_the_same_steps_one_by_one():
    w1 = regatta.World(REGATTA, seed=2)
    w2 = regatta.World(REGATTA, seed=2)
    w1.step([0.7, 0.6])
    w2.step([0.7, 0.6])
    last = w1.run(200)
    for _ in range(200):
        obs = w2.step()
    np.testing.assert_array_equal(last, obs)
    assert w1.summary_json() == w2.summary_json()


def test_rewards_are_the_fitness_terms_per_step():
    w = regatta.World(REGATTA, seed=4, fitness="avoidance")
    total = 0.0
    for _ in range(100):
        w.step([1.0, 1.0])
        r = float(w.rewards[0])
        assert 0.0 <= r <= 1.0
        total += r
    summary = w.summary()
    assert summary["fitness"]["name"] == "avoidance"
    # Avoidance is the mean of the steps' Φ.
    assert summary["fitness"]["value"] == pytest.approx(total / 100, rel=1e-12)


def test_world_controllers_run_when_nothing_is_driven(cli):
    w = regatta.World(REGATTA, seed=5, control=[])
    assert w.controlled == [] and w.observation.shape == (0, 0)
    w.run(2000)
    visits = w["khepera"].visits
    assert len(visits) >= 3, visits


# webots_ros2's e-puck world, whose robot waits for an external controller ("<extern>").
EXTERN_EPUCK = ROOT.parent / "shared" / "corpus" / "webots-ext" / "cyberbotics+webots_ros2" / "_versions" / "R2023b" / "webots_ros2_epuck" / "worlds" / "epuck_world.wbt"


def test_an_extern_robot_of_a_webots_world_is_driven_by_actions():
    if not EXTERN_EPUCK.exists():
        pytest.skip(f"the corpus is not beside the repository ({EXTERN_EPUCK})")
    # Lenient: the world's Pi-puck has no stand-in and is skipped.
    w = regatta.World(EXTERN_EPUCK, lenient=True, seed=1)
    assert w.controlled == ["e-puck"]
    x0 = w["e-puck"].pose
    for _ in range(50):
        w.step([1, 1])
    x1 = w["e-puck"].pose
    assert np.hypot(x1[0] - x0[0], x1[1] - x0[1]) > 0.01, (x0, x1)
    # Driven by nobody, it is refused as `regatta run` refuses it.
    text = '#VRML_SIM R2023b utf8\nRectangleArena { }\nE-puck { controller "<extern>" }\n'
    assert regatta.World("extern.wbt", text=text).controlled == ["e-puck"]
    with pytest.raises(regatta.WorldError, match='"<extern>"'):
        regatta.World("extern.wbt", text=text, control=[])


def test_summary_is_run_json(cli):
    help_text = cli("run", "--help").stdout.decode()
    if "--json" not in help_text:
        pytest.skip("this regatta binary has no run --json yet (issue 19)")
    w = regatta.World(REGATTA, seed=9, control=[])
    w.run(600)
    ours = w.summary()
    theirs = json.loads(cli("run", "worlds/regatta.wbt", "--steps", "600", "--seed", "9", "--json").stdout)
    theirs.pop("wall_s")
    ours["world"] = theirs["world"]
    assert ours == theirs


def test_log_is_the_run_log_byte_for_byte(cli, tmp_path, monkeypatch):
    ours = tmp_path / "ours.mcap"
    theirs = tmp_path / "theirs.mcap"
    # A log names its world as given: give the command line's relative name.
    monkeypatch.chdir(ROOT)
    w = regatta.World("worlds/regatta.wbt", seed=11, control=[])
    w.log(ours, steps=300)
    w.run(300)
    w.close()
    cli("run", "worlds/regatta.wbt", "--steps", "300", "--seed", "11", "--log", str(theirs))
    assert ours.read_bytes() == theirs.read_bytes()


def test_a_log_starts_at_step_zero(tmp_path):
    w = regatta.World(REGATTA)
    w.step([1, 1])
    with pytest.raises(ValueError, match="step 1"):
        w.log(tmp_path / "late.mcap")
    w.reset()
    with pytest.raises(ValueError, match="colour"):
        w.log(tmp_path / "bad.mcap", channels="colour")
    w.log(tmp_path / "from_start.mcap", channels="regatta")
    w.run(10)
    w.close()
    assert (tmp_path / "from_start.mcap").stat().st_size > 0
    # A driven robot's log says where its commands came from.
    assert b"controllers" in (tmp_path / "from_start.mcap").read_bytes()


def test_robots_by_name():
    w = regatta.World(world("regatta_pair.wbt"), seed=1)
    assert [r.name for r in w.robots] == ["red", "blue"]
    assert w.controlled == ["red", "blue"]
    assert w.observation.shape == (2, 24)
    red = w.robot("red")
    x, z, heading = red.pose
    assert (x, z) == pytest.approx((0.0, 0.4))
    assert red.retina("odd").shape == (150,)
    assert red.state()["name"] == "red"
    with pytest.raises(KeyError, match="red, blue"):
        w["green"]
    with pytest.raises(ValueError, match="unknown filter"):
        red.retina("sharpen")
    with pytest.raises(ValueError, match="no robot named 'green'"):
        regatta.World(world("regatta_pair.wbt"), control=["green"])
    # One robot driven, the other sails on its own controller.
    w = regatta.World(world("regatta_pair.wbt"), control=["blue"])
    w.run(300)
    assert w["red"].wheels != (0, 0) and w["blue"].wheels == (0, 0)


def test_a_bad_world_raises_with_file_line_col(tmp_path):
    bad = tmp_path / "bad.wbt"
    bad.write_text('#VRML_SIM R2023b utf8\nWorldInfo { coordinateSystem "NUE" }\nKhepera {\n  translaton 0 0 0\n}\n')
    with pytest.raises(regatta.WorldError) as error:
        regatta.World(bad)
    message = str(error.value)
    assert f"{bad}:4:3" in message
    assert "did you mean 'translation'?" in message
    assert isinstance(error.value, ValueError)
    # What a program reads without parsing the message.
    assert (error.value.file, error.value.line, error.value.column) == (str(bad), 4, 3)
    assert error.value.message == "Unknown 'translaton' parameter in Khepera PROTO."
    assert error.value.errors[0][:3] == (str(bad), 4, 3)
    # A refused world is refused, not "skipped".
    assert "Skipped" not in message
    with pytest.raises(FileNotFoundError) as missing:
        regatta.World(tmp_path / "missing.wbt")
    assert missing.value.errno == errno.ENOENT
    assert missing.value.filename == str((tmp_path / "missing.wbt").resolve())
    assert missing.value.strerror == "No such file or directory"
    with pytest.raises(IsADirectoryError) as folder:
        regatta.World(tmp_path)
    assert folder.value.filename == str(tmp_path.resolve())
    with pytest.raises(ValueError, match="unknown fitness"):
        regatta.World(REGATTA, fitness="speed")


def test_bad_arguments_raise_and_leave_the_world_usable():
    w = regatta.World(REGATTA, seed=1)
    with pytest.raises(ValueError, match="expected 2 action values"):
        w.step([1, 2, 3])
    with pytest.raises(ValueError, match="array of numbers"):
        w.step("fast")
    with pytest.raises(ValueError, match="size must be"):
        w.render(size=1)
    with pytest.raises(OverflowError):
        w.reset(seed=-1)
    w.step([np.nan, np.inf])
    assert w["khepera"].wheels == (0, 127)
    assert w.steps == 1


def test_render_draws_the_arena_from_above():
    w = regatta.World(REGATTA)
    image = w.render(128)
    assert image.shape == (128, 128, 3) and image.dtype == np.uint8
    colours = {tuple(p) for p in image.reshape(-1, 3)}
    assert len(colours) >= 4  # floor, walls, buoys, robot (and its heading)


def test_docstrings_explain_the_api():
    assert "observation" in regatta.World.__doc__
    assert "GIL" in regatta.evaluate.__doc__
    assert "file:line:col" in regatta.WorldError.__doc__

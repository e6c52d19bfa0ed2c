"""`World(..., view=True)`: the world Python steps is served to the browser viewer."""

from __future__ import annotations

import json
import urllib.request

import regatta
from conftest import WORLDS


def get(url: str) -> dict:
    with urllib.request.urlopen(url, timeout=10) as response:
        return json.load(response)


def test_a_viewed_world_serves_the_steps_python_takes():
    world = regatta.World(WORLDS / "single_buoy.wbt", seed=3, view=True)
    assert world.view_url.startswith("http://127.0.0.1:")
    scene = get(world.view_url + "scene.json")
    assert [r["name"] for r in scene["robots"]] == [r.name for r in world.robots]
    # Nobody follows the stream, so only the published first state is there.
    state = get(world.view_url + "state.json")
    assert state["sample"]["steps"] == 0
    assert state["status"]["seed"] == "3"
    # A stream client makes the steps show.
    stream = urllib.request.urlopen(world.view_url + "events", timeout=10)
    assert stream.readline().startswith(b"data: ")
    world.run(200)
    for _ in range(50):
        if get(world.view_url + "state.json")["sample"]["steps"] > 0:
            break
        world.step()
    state = get(world.view_url + "state.json")
    assert state["sample"]["steps"] > 0
    x, z = state["sample"]["robots"][0][:2]
    pose = world.robots[0].pose
    assert abs(x - pose[0]) < 0.2 and abs(z - pose[1]) < 0.2
    stream.close()


def test_no_viewer_unless_asked():
    world = regatta.World(WORLDS / "single_buoy.wbt")
    assert world.view_url is None

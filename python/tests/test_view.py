"""`World(..., view=True)`: the world Python steps is served to the browser viewer."""

from __future__ import annotations

import json
import urllib.error
import urllib.request
from urllib.parse import parse_qs, urlsplit

import pytest

import regatta
from conftest import WORLDS


def get(url: str) -> dict:
    with urllib.request.urlopen(url, timeout=10) as response:
        return json.load(response)


def test_a_viewed_world_serves_the_steps_python_takes():
    world = regatta.World(WORLDS / "single_buoy.wbt", seed=3, view=True)
    assert world.view_url.startswith("http://127.0.0.1:")
    # The URL is the page's, with the run's token; every request may carry it.
    url = urlsplit(world.view_url)
    token = parse_qs(url.query)["token"][0]
    assert len(token) == 32

    def api(path: str) -> str:
        separator = "&" if "?" in path else "?"
        return f"{url.scheme}://{url.netloc}/{path}{separator}token={token}"

    with urllib.request.urlopen(world.view_url, timeout=10) as response:
        assert f'src="view.js?token={token}"' in response.read().decode()
    with pytest.raises(urllib.error.HTTPError) as refused:
        urllib.request.urlopen(api("state.json").replace(token, "0" * 32), timeout=10)
    assert refused.value.code == 403
    scene = get(api("scene.json"))
    assert [r["name"] for r in scene["robots"]] == [r.name for r in world.robots]
    # Nobody follows the stream, so only the published first state is there.
    state = get(api("state.json"))
    assert state["sample"]["steps"] == 0
    assert state["status"]["seed"] == "3"
    # A stream client makes the steps show.
    stream = urllib.request.urlopen(api("events"), timeout=10)
    assert stream.readline().startswith(b"data: ")
    world.run(200)
    for _ in range(50):
        if get(api("state.json"))["sample"]["steps"] > 0:
            break
        world.step()
    state = get(api("state.json"))
    assert state["sample"]["steps"] > 0
    x, z = state["sample"]["robots"][0][:2]
    pose = world.robots[0].pose
    assert abs(x - pose[0]) < 0.2 and abs(z - pose[1]) < 0.2
    stream.close()


def test_no_viewer_unless_asked():
    world = regatta.World(WORLDS / "single_buoy.wbt")
    assert world.view_url is None

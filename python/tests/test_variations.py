"""Variations from Python: `evaluate`/`batch(vary=…)` draw what `regatta batch --vary` draws,
for any thread count; a World's, a Gymnasium environment's and a PettingZoo environment's
`reset(seed)` draw from the seed, and each copy of a VectorWorld is the World of its seed; a
varied World's log replays; a bad variation is a ValueError naming it."""

from __future__ import annotations

import json

import numpy as np
import pytest

import regatta
from conftest import ROOT, world

REGATTA = world("regatta.wbt")
VARY = [
    "DirectionalLight.intensity=0.02..0.8",
    "Buoy.translation=±0.1",
    "Khepera.translation=arena",
    "Khepera.rotation=any",
]


def test_evaluate_and_batch_draw_what_the_command_line_draws(cli, monkeypatch):
    monkeypatch.chdir(ROOT)
    one = regatta.evaluate("worlds/regatta.wbt", None, range(1, 5), duration=3.0, threads=1, vary=VARY)
    two = regatta.evaluate("worlds/regatta.wbt", None, range(1, 5), duration=3.0, threads=2, vary=VARY)
    np.testing.assert_array_equal(one, two)
    lines = regatta.batch("worlds/regatta.wbt", range(1, 5), duration=3.0, vary=VARY)
    flags = [a for v in VARY for a in ("--vary", v)]
    out = cli("batch", "worlds/regatta.wbt", "--seeds", "1..4", "--duration", "3", *flags)
    assert out.stdout.decode().splitlines() == lines
    rows = [json.loads(line) for line in lines]
    assert [r["fitness"]["value"] for r in rows] == one[0].tolist()
    assert len(rows[0]["variations"]) == 1 + 3 + 2


def test_reset_draws_from_its_seed():
    w = regatta.World(REGATTA, vary=VARY, seed=5)
    first = w.variations
    assert [k for k, _ in first][:2] == ["DirectionalLight[1].intensity", "Buoy[1].translation"]
    w.reset(6)
    assert w.variations != first
    w.reset(5)
    assert w.variations == first
    assert json.loads(w.summary_json())["variations"][0]["value"] == first[0][1]
    gym = pytest.importorskip("regatta.gym")
    env = gym.RegattaEnv(REGATTA, vary=VARY, duration=2.0)
    a, _ = env.reset(seed=11)
    env.step(np.zeros(2, dtype=np.float32))
    b, _ = env.reset(seed=11)
    np.testing.assert_array_equal(a, b)
    c, _ = env.reset(seed=12)
    assert not np.array_equal(a, c)


def test_a_varied_worlds_log_replays(cli, tmp_path):
    w = regatta.World(REGATTA, vary=VARY, seed=3, control=[])
    log = tmp_path / "varied.mcap"
    w.log(str(log), steps=60)
    w.run(60)
    w.close()
    out = cli("replay", "--verify", str(log))
    assert out.stdout.decode().startswith("OK: ")
    info = cli("log", "info", str(log)).stdout.decode()
    assert "varied:       Khepera[1].rotation = 0 1 0 " in info


def test_a_bad_variation_is_a_value_error_naming_it():
    with pytest.raises(ValueError, match=r"--vary 'Buoy.translation=1\.\.0': the range 1\.\.0 is empty"):
        regatta.evaluate(REGATTA, None, [1], vary=["Buoy.translation=1..0"])
    with pytest.raises(ValueError, match="no node of type or DEF name 'Rock'"):
        regatta.World(REGATTA, vary=["Rock.translation=±0.1"])


def test_a_vector_world_draws_each_copy_as_a_world_of_its_seed():
    vector = regatta.VectorWorld(REGATTA, 3, vary=VARY)
    observations = np.asarray(vector.reset(seed=20))
    for i in range(3):
        single = regatta.World(REGATTA, vary=VARY)
        np.testing.assert_array_equal(observations[i], np.asarray(single.reset(20 + i)).reshape(-1))
    again = regatta.VectorWorld(REGATTA, 3, vary=VARY, threads=2)
    np.testing.assert_array_equal(observations, np.asarray(again.reset(seed=20)))


def test_a_pettingzoo_reset_draws_from_its_seed():
    pettingzoo = pytest.importorskip("regatta.pettingzoo")
    env = pettingzoo.parallel_env(world("regatta_pair.wbt"), vary=VARY, duration=2.0)
    first, _ = env.reset(seed=7)
    variations = env.world.variations
    env.step({agent: np.zeros(2, dtype=np.float32) for agent in env.agents})
    second, _ = env.reset(seed=7)
    assert env.world.variations == variations
    for agent in first:
        np.testing.assert_array_equal(first[agent], second[agent])
    env.reset(seed=8)
    assert env.world.variations != variations

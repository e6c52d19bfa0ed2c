"""regatta.evaluate, batch and parameter_count: the numbers of `regatta batch`, bit for bit,
for any thread count; errors as exceptions."""

from __future__ import annotations

import json

import numpy as np
import pytest

import regatta
from conftest import ROOT, world

AVOIDANCE = world("avoidance.wbt")
NEURAL = world("regatta_neural.wbt")


def weights_text(row) -> str:
    # repr() is the shortest text that reads back to the same float, as the world language reads it.
    return "[ " + " ".join(repr(float(w)) for w in row) + " ]"


def test_parameter_count_and_the_worlds_weights():
    n = regatta.parameter_count(AVOIDANCE)
    own = regatta.network_weights(AVOIDANCE)
    assert own.shape == (n,) and own.dtype == np.float64
    assert regatta.parameter_count(NEURAL) == regatta.network_weights(NEURAL).size
    with pytest.raises(ValueError, match='controller "neural"'):
        regatta.parameter_count(world("regatta.wbt"))


def test_shape_and_independence_from_threads():
    n = regatta.parameter_count(AVOIDANCE)
    weights = np.random.default_rng(0).normal(0, 1, size=(5, n))
    one = regatta.evaluate(AVOIDANCE, weights, [1, 2, 3], fitness="avoidance", duration=3.0, threads=1)
    two = regatta.evaluate(AVOIDANCE, weights, [1, 2, 3], fitness="avoidance", duration=3.0, threads=2)
    assert one.shape == (5, 3) and one.dtype == np.float64
    np.testing.assert_array_equal(one, two)
    # Different weights do different things.
    assert len(set(one[:, 0].tolist())) > 1
    # A row alone gives the same numbers as in a batch.
    alone = regatta.evaluate(AVOIDANCE, weights[3:4], [1, 2, 3], fitness="avoidance", duration=3.0)
    np.testing.assert_array_equal(alone[0], one[3])
    # None: the world's own weights.
    own = regatta.evaluate(AVOIDANCE, None, range(1, 4), fitness="avoidance", duration=3.0)
    given = regatta.evaluate(
        AVOIDANCE, regatta.network_weights(AVOIDANCE)[None, :], range(1, 4), fitness="avoidance", duration=3.0
    )
    np.testing.assert_array_equal(own, given)


def test_equals_regatta_batch_bit_for_bit(cli, monkeypatch):
    monkeypatch.chdir(ROOT)
    n = regatta.parameter_count("worlds/regatta_neural.wbt")
    weights = np.random.default_rng(7).normal(0, 0.7, size=(2, n))
    ours = regatta.evaluate("worlds/regatta_neural.wbt", weights, range(1, 5), fitness="regatta", duration=4.0, threads=2)
    lines = regatta.batch("worlds/regatta_neural.wbt", range(1, 5), weights=weights, fitness="regatta", duration=4.0)
    for c, row in enumerate(weights):
        out = cli(
            "batch", "worlds/regatta_neural.wbt", "--seeds", "1..4", "--duration", "4",
            "--fitness", "regatta", "--json", "-j", "2", "--set", f"NeuralNetwork.weights={weights_text(row)}",
        ).stdout.decode()
        rows = [json.loads(line) for line in out.splitlines()]
        assert [r["seed"] for r in rows] == [1, 2, 3, 4]
        # The same bits: JSON prints the shortest text of each float, and reads it back exactly.
        assert [r["fitness"]["value"] for r in rows] == ours[c].tolist()
        # batch() gives the command's lines, with the candidate's row number added.
        for line, theirs in zip(lines[4 * c : 4 * c + 4], rows):
            mine = json.loads(line)
            assert mine.pop("candidate") == c
            assert mine == theirs
    # Without weights, batch() is the command's output byte for byte.
    out = cli("batch", "worlds/avoidance.wbt", "--seeds", "3..5", "--duration", "2", "--fitness", "avoidance", "--json").stdout.decode()
    assert "".join(line + "\n" for line in regatta.batch("worlds/avoidance.wbt", [3, 4, 5], fitness="avoidance", duration=2.0)) == out


def test_errors_raise():
    n = regatta.parameter_count(AVOIDANCE)
    with pytest.raises(ValueError, match=f"{n} parameters"):
        regatta.evaluate(AVOIDANCE, np.zeros((2, n + 1)), [1])
    with pytest.raises(ValueError, match="finite"):
        regatta.evaluate(AVOIDANCE, np.full((1, n), np.nan), [1])
    with pytest.raises(ValueError, match="2-D"):
        regatta.evaluate(AVOIDANCE, np.zeros(n), [1])
    with pytest.raises(ValueError, match="unknown fitness"):
        regatta.evaluate(AVOIDANCE, None, [1], fitness="speed")
    with pytest.raises(ValueError, match="duration"):
        regatta.evaluate(AVOIDANCE, None, [1], duration=-1)
    with pytest.raises(ValueError, match="NODE.FIELD=VALUE"):
        regatta.evaluate(AVOIDANCE, None, [1], overrides=["nonsense"])
    with pytest.raises(ValueError, match='controller "neural"'):
        regatta.evaluate(world("regatta.wbt"), np.zeros((1, 3)), [1])
    with pytest.raises(FileNotFoundError):
        regatta.evaluate(world("nowhere.wbt"), None, [1])


def test_overrides_apply_as_batch_set():
    base = regatta.evaluate(NEURAL, None, [1, 2], duration=3.0, fitness="phototaxis:range=2")
    dark = regatta.evaluate(
        NEURAL, None, [1, 2], duration=3.0, fitness="phototaxis:range=2", overrides=["Khepera.translation=0.3 0 0.3"]
    )
    assert base.min() > 0 and not np.array_equal(base, dark)


def test_with_weights_writes_a_world_that_runs_them(tmp_path):
    n = regatta.parameter_count(AVOIDANCE)
    weights = np.random.default_rng(3).normal(0, 1, size=n)
    text = regatta.with_weights(AVOIDANCE, weights.tolist())
    best = tmp_path / "best.wbt"
    best.write_text(text)
    np.testing.assert_array_equal(regatta.network_weights(best), weights)
    np.testing.assert_array_equal(
        regatta.evaluate(best, None, [1], fitness="avoidance", duration=2.0),
        regatta.evaluate(AVOIDANCE, weights[None, :], [1], fitness="avoidance", duration=2.0),
    )

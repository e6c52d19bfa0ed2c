"""regatta.ray.evaluate on a local Ray cluster: the numbers of regatta.evaluate, in order."""

from __future__ import annotations

import numpy as np
import pytest

import regatta
import regatta.ray
from conftest import world

ray = pytest.importorskip("ray")


@pytest.fixture(scope="module")
def local_cluster():
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    yield
    ray.shutdown()


def test_cluster_evaluation_equals_local(local_cluster):
    path = world("avoidance.wbt")
    n = regatta.parameter_count(path)
    weights = np.random.default_rng(5).normal(0, 1, size=(7, n))
    local = regatta.evaluate(path, weights, [1, 2], fitness="avoidance", duration=2.0)
    remote = regatta.ray.evaluate(path, weights, [1, 2], fitness="avoidance", duration=2.0, chunk_size=3, threads=1)
    np.testing.assert_array_equal(remote, local)
    default_chunks = regatta.ray.evaluate(path, weights, [1, 2], fitness="avoidance", duration=2.0)
    np.testing.assert_array_equal(default_chunks, local)
    own = regatta.ray.evaluate(path, None, [3], fitness="avoidance", duration=2.0)
    np.testing.assert_array_equal(own, regatta.evaluate(path, None, [3], fitness="avoidance", duration=2.0))


def test_errors_come_back_from_the_workers(local_cluster):
    path = world("avoidance.wbt")
    n = regatta.parameter_count(path)
    with pytest.raises(Exception, match="parameters"):
        regatta.ray.evaluate(path, np.zeros((2, n + 1)), [1], chunk_size=1)

"""The examples run end to end on a short budget."""

from __future__ import annotations

import importlib.util
import os
import subprocess
import sys

import pytest

from conftest import ROOT

EXAMPLES = ROOT / "python" / "examples"


def run(script: str, *args: str, tmp_path) -> str:
    result = subprocess.run(
        [sys.executable, str(EXAMPLES / script), *args],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=900,
        env=dict(os.environ, PYTHONWARNINGS="ignore"),
    )
    assert result.returncode == 0, result.stdout + result.stderr
    return result.stdout


def test_cmaes_evolves_the_regatta_network(tmp_path):
    out = run(
        "cmaes_regatta.py", "--generations", "3", "--population", "8", "--trials", "2",
        "--duration", "8", "--threads", "2", "--out", "evolved", tmp_path=tmp_path,
    )
    assert out.count("generation") == 3
    best = tmp_path / "evolved" / "best.wbt"
    assert best.exists() and (tmp_path / "evolved" / "fitness.csv").exists()
    import regatta

    # The written world runs the best weights: it loads and its weights are the evolved ones.
    assert regatta.parameter_count(best) == regatta.parameter_count(ROOT / "worlds" / "regatta_neural.wbt")


@pytest.mark.skipif(
    importlib.util.find_spec("stable_baselines3") is None,
    reason="stable-baselines3 is not installed (scripts/test.sh installs it unless REGATTA_SKIP_SB3=1)",
)
def test_ppo_trains_on_the_vector_env(tmp_path):
    out = run(
        "ppo_avoidance.py", "--timesteps", "4096", "--envs", "8", "--duration", "4",
        "--threads", "2", "--out", "ppo", tmp_path=tmp_path,
    )
    assert "mean avoidance" in out
    assert (tmp_path / "ppo" / "ppo_avoidance.zip").exists()


def test_pettingzoo_loop(tmp_path):
    out = run("pettingzoo_loop.py", "--duration", "10", tmp_path=tmp_path)
    assert out.startswith("red: return") and "blue: return" in out


@pytest.mark.skipif(importlib.util.find_spec("ray") is None, reason="ray is not installed")
def test_ray_example(tmp_path):
    out = run("ray_evaluate.py", "--candidates", "8", "--seeds", "2", "--duration", "2", tmp_path=tmp_path)
    assert "the same numbers" in out

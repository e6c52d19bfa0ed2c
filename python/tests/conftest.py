"""Shared fixtures: the repository's worlds, and the `regatta` command line the Python module
must agree with (REGATTA_BIN, else the newest of target/{release,debug}/regatta)."""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
WORLDS = ROOT / "worlds"


def world(name: str) -> str:
    return str(WORLDS / name)


def regatta_bin() -> Path | None:
    given = os.environ.get("REGATTA_BIN")
    if given:
        return Path(given)
    found = [ROOT / "target" / kind / "regatta" for kind in ("release", "debug")]
    found = [p for p in found if p.exists()]
    return max(found, key=lambda p: p.stat().st_mtime) if found else None


@pytest.fixture(scope="session")
def cli():
    """Runs the regatta command line; returns its completed process (stdout as bytes)."""
    binary = regatta_bin()
    if binary is None:
        pytest.skip("no regatta binary: build it (cargo build -p regatta) or set REGATTA_BIN")

    def run(*args: str, check: bool = True) -> subprocess.CompletedProcess:
        result = subprocess.run(
            [str(binary), *args], cwd=ROOT, capture_output=True, timeout=600
        )
        if check and result.returncode != 0:
            raise AssertionError(
                f"regatta {' '.join(args)} failed ({result.returncode}):\n"
                + result.stderr.decode(errors="replace")
            )
        return result

    return run

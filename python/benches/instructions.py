"""Instruction counts (callgrind: independent of the machine's load) of the Python call per
step: `World.step` called from Python against `World.run`, the same steps in one Rust call.

    python python/benches/instructions.py

Runs itself under `valgrind --tool=callgrind` for two step counts per variant and prints the
instructions per step of each, from the difference (start-up cancels out).
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
REGATTA = str(ROOT / "worlds" / "regatta.wbt")


def child(variant: str, steps: int) -> None:
    import numpy as np

    import regatta

    world = regatta.World(REGATTA, seed=1)
    action = np.array([0.6, 0.5])
    world.step(action)
    if variant == "run":
        world.run(steps)
    elif variant == "step":
        step = world.step
        for _ in range(steps):
            step(action)
    elif variant == "vector":
        vector = regatta.VectorWorld(REGATTA, 64, seed=1, threads=1)
        actions = np.tile(action, (64, 1))
        for _ in range(steps // 64):
            vector.step(actions)
    elif variant == "loop":
        worlds = [regatta.World(REGATTA, seed=1 + i) for i in range(64)]
        for _ in range(steps // 64):
            for w in worlds:
                w.step(action)


def instructions(variant: str, steps: int) -> int:
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "callgrind.out")
        result = subprocess.run(
            ["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", sys.executable, __file__, variant, str(steps)],
            capture_output=True,
            text=True,
            check=True,
        )
        match = re.search(r"Collected : (\d+)", result.stderr)
        assert match, result.stderr
        return int(match.group(1))


def main() -> None:
    if len(sys.argv) == 3:
        child(sys.argv[1], int(sys.argv[2]))
        return
    counts = {}
    for variant in ["run", "step", "vector", "loop"]:
        low, high = 1280, 6400
        per_step = (instructions(variant, high) - instructions(variant, low)) / (high - low)
        counts[variant] = per_step
        print(f"{variant:7s} {per_step:12,.0f} instructions per world-step", flush=True)
    print(f"Python call per World.step: {counts['step'] - counts['run']:,.0f} instructions")
    print(f"Python loop over 64 worlds against VectorWorld: {counts['loop'] - counts['vector']:,.0f} instructions per world-step")


if __name__ == "__main__":
    main()

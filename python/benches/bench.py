"""Throughput of the Python module, against the Rust loop it wraps (§5 of issue 20).

    python python/benches/bench.py [--regatta target/release/regatta] [--threads 2]

Prints, with the machine's load average (figures taken on a busy machine are low):
- World.run(n) (n steps in Rust, no Python in between) and World.step() from Python with
  retinas (worlds/regatta.wbt: IR, ambient and the pooled retina observed every step): steps/s,
  and the Python call's cost per step;
- VectorWorld: 64 copies stepped in one call on `--threads` threads: world-steps/s;
- the same 64 worlds stepped by a plain Python loop over 64 World objects, and over 64
  Gymnasium environments (gymnasium.vector.SyncVectorEnv of RegattaEnv);
- regatta.evaluate against `regatta batch` on the same runs (worlds/regatta_neural.wbt,
  60 simulated seconds each): evaluations/s.
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import time
from pathlib import Path

import numpy as np

import regatta

try:
    import gymnasium

    import regatta.gym
except ImportError:
    gymnasium = None

ROOT = Path(__file__).resolve().parents[2]
REGATTA = str(ROOT / "worlds" / "regatta.wbt")
NEURAL = str(ROOT / "worlds" / "regatta_neural.wbt")


def best_of(repeats: int, f) -> float:
    """The shortest wall time of `repeats` calls of f (s)."""
    times = []
    for _ in range(repeats):
        began = time.perf_counter()
        f()
        times.append(time.perf_counter() - began)
    return min(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--regatta", default=str(ROOT / "target" / "release" / "regatta"))
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--steps", type=int, default=50_000)
    parser.add_argument("--envs", type=int, default=64)
    parser.add_argument("--evaluations", type=int, default=200)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    print(f"load average before: {os.getloadavg()[0]:.2f} (1 min), {os.cpu_count()} cores")

    # One world with retinas: Rust alone, then one Python call per step.
    world = regatta.World(REGATTA, seed=1)
    action = np.array([0.6, 0.5])
    world.step(action)
    n = args.steps
    rust = best_of(args.repeats, lambda: world.run(n))

    def python_steps():
        step = world.step
        for _ in range(n):
            step(action)

    python = best_of(args.repeats, python_steps)
    print(f"World.run (Rust loop)        {n / rust:12,.0f} steps/s  {rust / n * 1e6:6.2f} µs/step")
    print(f"World.step (Python loop)     {n / python:12,.0f} steps/s  {python / n * 1e6:6.2f} µs/step"
          f"  (Python call {(python - rust) / n * 1e6:.2f} µs)")

    # 64 worlds: one call in Rust against Python loops.
    e = args.envs
    vector = regatta.VectorWorld(REGATTA, e, seed=1, threads=args.threads, duration=60.0)
    actions = np.tile(action, (e, 1))
    calls = max(1, n // e)

    def vector_steps():
        step = vector.step
        for _ in range(calls):
            step(actions)

    vector_steps()
    t = best_of(args.repeats, vector_steps)
    print(f"VectorWorld {e} worlds, {vector.threads} threads {e * calls / t:12,.0f} world-steps/s")
    # Per CPU-second of the process (every thread): what the threads do when they get a core,
    # whatever else the machine runs; on idle cores the wall figure is this times the threads.
    usage = resource.getrusage(resource.RUSAGE_SELF)
    began_cpu = usage.ru_utime + usage.ru_stime
    began = time.perf_counter()
    vector_steps()
    wall = time.perf_counter() - began
    usage = resource.getrusage(resource.RUSAGE_SELF)
    cpu = usage.ru_utime + usage.ru_stime - began_cpu
    print(f"  per CPU-second                   {e * calls / cpu:12,.0f} world-steps"
          f"  (the process had {cpu / wall:.2f} cores of {vector.threads})")

    worlds = [regatta.World(REGATTA, seed=1 + i) for i in range(e)]

    def loop_worlds():
        for _ in range(calls):
            for w in worlds:
                w.step(action)

    t = best_of(args.repeats, loop_worlds)
    print(f"Python loop over {e} World    {e * calls / t:12,.0f} world-steps/s")

    if gymnasium is not None:
        sync = gymnasium.vector.SyncVectorEnv(
            [lambda: gymnasium.make("regatta/Regatta-v0") for _ in range(e)]
        )
        sync.reset(seed=1)
        batch_actions = np.tile(action.astype(np.float32), (e, 1))
        short = max(1, calls // 4)

        def loop_gym():
            for _ in range(short):
                sync.step(batch_actions)

        t = best_of(args.repeats, loop_gym)
        print(f"Gymnasium SyncVectorEnv {e} envs {e * short / t:10,.0f} world-steps/s")
        rust_vec = regatta.gym.RegattaVectorEnv(e, threads=args.threads)
        rust_vec.reset(seed=1)

        def loop_rust_vec():
            for _ in range(calls):
                rust_vec.step(batch_actions)

        t = best_of(args.repeats, loop_rust_vec)
        print(f"RegattaVectorEnv {e} envs (make_vec) {e * calls / t:8,.0f} world-steps/s")
    else:
        print("gymnasium is not installed: no Gymnasium figures")

    # regatta.evaluate against regatta batch: the same runs.
    m = args.evaluations
    p = regatta.parameter_count(NEURAL)
    seeds = list(range(1, m + 1))
    t_eval = best_of(args.repeats, lambda: regatta.evaluate(NEURAL, None, seeds, duration=60.0, threads=args.threads))
    print(f"regatta.evaluate   {m} runs of 60 s  {m / t_eval:8.1f} evaluations/s  ({p} weights)")
    binary = Path(args.regatta)
    if binary.exists():
        command = [str(binary), "batch", NEURAL, "--seeds", f"1..{m}", "--duration", "60", "-j", str(args.threads), "--json"]
        t_batch = best_of(args.repeats, lambda: subprocess.run(command, check=True, capture_output=True))
        print(f"regatta batch      {m} runs of 60 s  {m / t_batch:8.1f} evaluations/s"
              f"  (evaluate takes {100 * (t_eval / t_batch - 1):+.1f} %)")
    else:
        print(f"no {binary}: build it with `cargo build --release -p regatta` for the batch comparison")
    print(f"load average after: {os.getloadavg()[0]:.2f} (1 min)")


if __name__ == "__main__":
    main()

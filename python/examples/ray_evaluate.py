"""Evaluate random neural controllers on a Ray cluster with regatta.ray.evaluate, and check
that the numbers are those of one machine.

    python python/examples/ray_evaluate.py                   # a local cluster
    python python/examples/ray_evaluate.py --address auto    # the cluster this machine is in

Going from one machine to a cluster changes one line: ray.init(address=...).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
import ray

import regatta
import regatta.ray

ROOT = Path(__file__).resolve().parents[2]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--world", default=str(ROOT / "worlds" / "avoidance.wbt"))
    parser.add_argument("--address", default=None, help="a Ray cluster's address (default: start a local one)")
    parser.add_argument("--num-cpus", type=int, default=2, help="CPUs of a local cluster")
    parser.add_argument("--candidates", type=int, default=64)
    parser.add_argument("--seeds", type=int, default=4)
    parser.add_argument("--duration", type=float, default=20.0)
    args = parser.parse_args()

    if args.address:
        ray.init(address=args.address)
    else:
        ray.init(num_cpus=args.num_cpus, include_dashboard=False)
    n = regatta.parameter_count(args.world)
    weights = np.random.default_rng(0).normal(0, 1, size=(args.candidates, n))
    seeds = range(1, args.seeds + 1)
    began = time.perf_counter()
    fitness = regatta.ray.evaluate(args.world, weights, seeds, fitness="avoidance", duration=args.duration)
    cluster_s = time.perf_counter() - began
    began = time.perf_counter()
    local = regatta.evaluate(args.world, weights, seeds, fitness="avoidance", duration=args.duration)
    local_s = time.perf_counter() - began
    assert np.array_equal(fitness, local), "the cluster must give the numbers of one machine"
    runs = args.candidates * args.seeds
    print(f"{runs} runs on the cluster in {cluster_s:.2f} s, on this machine in {local_s:.2f} s: the same numbers")
    print(f"best candidate {int(np.argmax(fitness.mean(axis=1)))}: mean avoidance {fitness.mean(axis=1).max():.3f}")
    ray.shutdown()


if __name__ == "__main__":
    main()

"""Evolve the regatta network of worlds/regatta_neural.wbt with CMA-ES (the `cma` package),
each generation's candidates evaluated in parallel in Rust by regatta.evaluate.

    python python/examples/cmaes_regatta.py --generations 40 --out out/cmaes

Writes the best world (the input world with the evolved weights, in canonical form: run it
with `regatta run out/cmaes/best.wbt`) and a CSV of best, mean and worst fitness per
generation.
"""

from __future__ import annotations

import argparse
import csv
import os
import time
from pathlib import Path

import cma
import numpy as np

import regatta

ROOT = Path(__file__).resolve().parents[2]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--world", default=str(ROOT / "worlds" / "regatta_neural.wbt"))
    parser.add_argument("--fitness", default="regatta")
    parser.add_argument("--generations", type=int, default=40)
    parser.add_argument("--population", type=int, default=24)
    parser.add_argument("--trials", type=int, default=3, help="seeds per candidate")
    parser.add_argument("--duration", type=float, default=60.0, help="simulated seconds per trial")
    parser.add_argument("--sigma", type=float, default=0.5)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--threads", type=int, default=0)
    parser.add_argument("--out", default="out/cmaes")
    args = parser.parse_args()

    n = regatta.parameter_count(args.world)
    start = regatta.network_weights(args.world)
    es = cma.CMAEvolutionStrategy(
        start, args.sigma, {"popsize": args.population, "seed": args.seed, "verbose": -9}
    )
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    best_fitness, best_weights = -np.inf, start
    rows = []
    began = time.perf_counter()
    for generation in range(args.generations):
        candidates = np.array(es.ask())
        # Fresh seeds every generation, the same for every candidate of it.
        seeds = [args.seed * 1000 + generation * args.trials + k for k in range(args.trials)]
        fitness = regatta.evaluate(
            args.world, candidates, seeds, fitness=args.fitness, duration=args.duration, threads=args.threads
        ).mean(axis=1)
        es.tell(list(candidates), list(-fitness))  # cma minimises
        k = int(np.argmax(fitness))
        if fitness[k] > best_fitness:
            best_fitness, best_weights = float(fitness[k]), candidates[k]
        rows.append((generation, fitness.max(), fitness.mean(), fitness.min()))
        print(
            f"generation {generation:3d}: best {fitness.max():8.3f} mean {fitness.mean():8.3f} "
            f"worst {fitness.min():8.3f} ({len(candidates) * args.trials} runs, "
            f"{time.perf_counter() - began:6.1f} s)",
            flush=True,
        )
    with open(out / "fitness.csv", "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(["generation", "best", "mean", "worst"])
        writer.writerows(rows)
    (out / "best.wbt").write_text(regatta.with_weights(args.world, best_weights.tolist()))
    print(f"best fitness {best_fitness:.3f} over {n} weights; world written to {out / 'best.wbt'}")


if __name__ == "__main__":
    main()

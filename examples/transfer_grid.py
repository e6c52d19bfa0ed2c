#!/usr/bin/env python3
"""The transfer grid of examples/evolve_regatta_transfer.sh and its target, checked.

The grid: six layouts never sailed in training (worlds/regatta_heldout_*.wbt) × the light
(the arena's DirectionalLight as written, 0.05; dimmed to 0.02; brightened to 0.4: a factor of
20; the buoys' lamps lit as point lights; the lamps alone, the arena's light off) × the buoys'
IR film (as written, 1; none, 0.5). Seeds 1 to 5, 600 s each.

`--conditions` prints the grid as `regatta transfer --condition` arguments. Otherwise each
cell runs as `regatta batch LAYOUT --network-from CONTROLLER --set … --seeds 1..5 --json` (a
controller without a network, the hand-tuned worlds/regatta.wbt, sails the layout as written:
its Khepera is regatta.wbt's), and from each run's visits (every entry into a buoy's visit
disc, in order, each with its buoy and whether it continued the cyclic order):
  - cyclic: the run's cyclic visits (fitness.regatta.cyclic_visits);
  - least: the fewest visits any buoy of the layout had;
  - % cyclic: cyclic visits / all visits.
A cell meets the target when, for every seed, every buoy has at least 3 visits and at least
80 % of the visits are cyclic. A controller meets it when every cell does and its mean cyclic
visits over the grid are at least the hand-tuned controller's. With `--runs runs.csv` (from
`regatta transfer` over the same grid) every run's visits and cyclic visits are checked
against transfer's, number for number.
"""
import argparse
import csv
import json
import os
import re
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor

LAYOUTS = ["small", "large", "kite", "rect", "pentagon", "flat"]
LIGHTS = [
    ("0.05", []),
    ("dim 0.02", ["DirectionalLight.intensity=0.02"]),
    ("bright 0.4", ["DirectionalLight.intensity=0.4"]),
    ("lamps lit", ["Buoy.lampLight=TRUE"]),
    ("lamps only", ["Buoy.lampLight=TRUE", "DirectionalLight.on=FALSE"]),
]
FILMS = [("film", []), ("no film", ["Buoy.irReflectance=0.5"])]


def grid():
    for layout in LAYOUTS:
        for light, light_sets in LIGHTS:
            for film, film_sets in FILMS:
                name = f"{layout} {light} {film}"
                yield name, f"worlds/regatta_heldout_{layout}.wbt", light_sets + film_sets


def buoys(world):
    with open(world) as f:
        return sum(1 for line in f if re.match(r"^Buoy \{", line))


def cell(regatta, controller, world, sets, seeds, duration):
    command = [regatta, "batch", world, "--seeds", seeds, "--duration", str(duration), "--json"]
    with open(controller) as f:
        if "NeuralNetwork" in f.read():
            command += ["--network-from", controller]
    for s in sets:
        command += ["--set", s]
    out = subprocess.run(command, check=True, capture_output=True, text=True).stdout
    n = buoys(world)
    runs = []
    for line in out.splitlines():
        run = json.loads(line)
        robot = run["robots"][0]
        per_buoy = [0] * n
        for visit in robot["visits"]:
            per_buoy[visit["buoy"] - 1] += 1
        visits = len(robot["visits"])
        cyclic = robot["fitness"]["regatta"]["cyclic_visits"]
        runs.append({"seed": run["seed"], "visits": visits, "cyclic": cyclic,
                     "per_buoy": per_buoy, "share": cyclic / visits if visits else 0.0})
    return runs


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("controllers", nargs="*")
    p.add_argument("--regatta", default=os.path.join(os.environ.get("CARGO_TARGET_DIR", "target"), "release", "regatta"))
    p.add_argument("--seeds", default="1..5")
    p.add_argument("--duration", type=float, default=600)
    p.add_argument("--jobs", type=int, default=2)
    p.add_argument("--runs", help="runs.csv of `regatta transfer` over the same grid, to compare")
    p.add_argument("--csv", help="write every cell here")
    p.add_argument("--conditions", action="store_true", help="print the grid as transfer conditions")
    a = p.parse_args()
    if a.conditions:
        for name, world, sets in grid():
            print(f"{name}: " + "; ".join([f"world={world}"] + sets))
        return 0
    cells = [(c, name, world, sets) for c in a.controllers for name, world, sets in grid()]
    # batch runs its seeds in parallel itself; a few cells at a time keep the cores busy.
    with ThreadPoolExecutor(max(1, a.jobs // 2)) as pool:
        results = list(pool.map(lambda x: cell(a.regatta, x[0], x[2], x[3], a.seeds, a.duration), cells))
    table = {(c, name): runs for (c, name, _, _), runs in zip(cells, results)}
    mismatches = 0
    if a.runs:
        with open(a.runs) as f:
            for row in csv.DictReader(f):
                runs = table.get((row["controller"], row["condition"]))
                if runs is None:
                    continue
                run = next(r for r in runs if str(r["seed"]) == row["seed"])
                if (run["visits"], run["cyclic"]) != (int(row["visits"]), int(row["cyclic_visits"])):
                    mismatches += 1
                    print(f"differs from transfer: {row['controller']} {row['condition']} seed {row['seed']}")
        print(f"runs.csv: {'every run agrees' if mismatches == 0 else f'{mismatches} runs differ'}")
    writer = None
    if a.csv:
        f = open(a.csv, "w", newline="")
        writer = csv.writer(f)
        writer.writerow(["controller", "condition", "mean_cyclic", "least_buoy_visits", "least_cyclic_share", "mean_cyclic_share", "meets"])
    means = {}
    verdict = {}
    width = max(len(n) for n, _, _ in grid())
    for c in a.controllers:
        print(f"\n{c}")
        print(f"{'condition':<{width}}  cyclic  least  %cyc(min)  %cyc(all)  target")
        met = 0
        total = []
        for name, _, _ in grid():
            runs = table[(c, name)]
            mean_cyclic = sum(r["cyclic"] for r in runs) / len(runs)
            least = min(min(r["per_buoy"]) for r in runs)
            least_share = min(r["share"] for r in runs)
            all_share = sum(r["cyclic"] for r in runs) / max(1, sum(r["visits"] for r in runs))
            ok = least >= 3 and least_share >= 0.8
            met += ok
            total.append(mean_cyclic)
            print(f"{name:<{width}}  {mean_cyclic:6.1f}  {least:5d}  {100 * least_share:8.1f}  {100 * all_share:8.1f}   {'meets' if ok else 'MISSES'}")
            if writer:
                writer.writerow([c, name, mean_cyclic, least, least_share, all_share, ok])
        means[c] = sum(total) / len(total)
        verdict[c] = met == len(total)
        print(f"{c}: {met} of {len(total)} cells meet the target; mean cyclic visits over the grid {means[c]:.1f}")
    hand = next((m for c, m in means.items() if c.endswith("worlds/regatta.wbt")), None)
    if hand is not None:
        print()
        for c in a.controllers:
            if c.endswith("worlds/regatta.wbt"):
                continue
            ok = verdict[c] and means[c] >= hand
            print(f"{c}: {'MEETS' if ok else 'misses'} the target (every cell: {verdict[c]}; "
                  f"mean cyclic {means[c]:.1f} against the hand-tuned {hand:.1f})")
    return 1 if mismatches else 0


if __name__ == "__main__":
    sys.exit(main())

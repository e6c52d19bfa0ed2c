#!/usr/bin/env bash
# Floreano and Mondada's experiment in regatta: evolve obstacle avoidance from random weights
# (worlds/avoidance.wbt: 8 IR sensors and a bias into two recurrent sigmoid motor neurons),
# then copy the fitness curve to docs/ and run the evolved world. Deterministic: the same
# seed gives the same figure on any machine and for any -j. Prints the wall and CPU time of
# the evolution and the first generation whose best reaches Φ = 0.3 (the target: within 2
# minutes on 2 cores).
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -p regatta
out=${OUT:-out/evolve-avoidance}
TIMEFORMAT="evolution: %R s wall, %U s user + %S s system CPU"
time target/release/regatta evolve worlds/avoidance.wbt --fitness avoidance \
  --generations 25 --trials 2 --duration 30 --seed 1 --out "$out"
cp "$out/fitness.png" docs/avoidance-fitness.png
awk -F, 'NR > 1 && $3 >= 0.3 { print "best reaches 0.3 at generation " $1 " (" $2 " runs)"; exit }' \
  "$out/fitness.csv"
target/release/regatta run "$out/best.wbt" --duration 30 --json --fitness avoidance \
  | python3 -c 'import json,sys; d=json.load(sys.stdin); print("evolved avoidance, fresh seed:", d["fitness"]["value"])'

#!/usr/bin/env bash
# Floreano and Mondada's experiment in regatta: evolve obstacle avoidance from random weights
# (worlds/avoidance.wbt: 8 IR sensors and a bias into two recurrent sigmoid motor neurons),
# then copy the fitness curve to docs/ and run the evolved world. Deterministic: the same
# seed gives the same figure on any machine and for any -j.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -p regatta
out=${OUT:-out/evolve-avoidance}
target/release/regatta evolve worlds/avoidance.wbt --fitness avoidance \
  --generations 25 --trials 2 --duration 30 --seed 1 --out "$out"
cp "$out/fitness.png" docs/avoidance-fitness.png
target/release/regatta run "$out/best.wbt" --duration 30 --json --fitness avoidance \
  | python3 -c 'import json,sys; d=json.load(sys.stdin); print("evolved avoidance, fresh seed:", d["fitness"]["value"])'

#!/usr/bin/env bash
# The regatta evolved over varied light with a choice of filter: the network of
# worlds/regatta_neural_filters.wbt reads the raw retina and the odd filter side by side, and
# evolution weighs them. As examples/evolve_regatta_varied.sh (CMA-ES, five arenas, two
# trials of 60 s), every trial draws the arena's light (a factor of 20 in intensity), whether
# the buoys' lamps shine (point lights), each buoy's IR film (or none) and the robot's start.
# Then the transfer table of the hand-tuned and the three evolved controllers.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -p regatta
regatta=target/release/regatta
out=${OUT:-out/evolve-regatta-filters}
generations=${GENERATIONS:-250}
jobs=${JOBS:-2}
mkdir -p "$out"

TIMEFORMAT="evolution: %R s wall, %U s user + %S s system CPU on $jobs threads"
time "$regatta" evolve worlds/regatta_neural_filters.wbt \
  --world worlds/regatta_small.wbt --world worlds/regatta_wide.wbt \
  --world worlds/regatta_offcentre.wbt --world worlds/regatta_four.wbt \
  --fitness regatta --generations "$generations" --trials 2 --duration 60 \
  --seed 2 -j "$jobs" --out "$out" \
  --vary 'DirectionalLight.intensity=0.02..0.4' --vary 'Buoy.lampLight=TRUE|FALSE' \
  --vary 'Buoy.irReflectance=0.5|1' \
  --vary 'Khepera.translation=arena' --vary 'Khepera.rotation=any'
cp "$out/best.wbt" worlds/regatta_evolved_filters.wbt

"$regatta" transfer worlds/regatta.wbt worlds/regatta_evolved.wbt \
  worlds/regatta_evolved_varied.wbt worlds/regatta_evolved_filters.wbt \
  --seeds 1..5 --duration 600 -j "$jobs" \
  --condition 'as trained:' --condition 'dim 0.02: DirectionalLight.intensity=0.02' \
  --condition 'bright 0.4: DirectionalLight.intensity=0.4' \
  --condition 'no film: Buoy.irReflectance=0.5' --condition 'lamps lit: Buoy.lampLight=TRUE' \
  --condition 'moved: Buoy.translation=±0.08; Khepera.translation=arena; Khepera.rotation=any' \
  --condition 'wide: world=worlds/regatta_wide.wbt' --condition 'five: world=worlds/regatta_five.wbt' \
  --out "$out/transfer"
cp "$out/transfer/transfer.png" docs/transfer.png

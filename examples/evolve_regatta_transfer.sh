#!/usr/bin/env bash
# The regatta evolved to transfer: the network of worlds/regatta_neural_transfer.wbt
# (worlds/regatta_evolved_varied.wbt's with its weights, grown by the odd filter's output and
# the ambient readings, I_bda 3), evolved on from its written weights (--from-weights,
# step size 0.3) with CMA-ES over thirteen layouts: the five arenas of
# examples/evolve_regatta_varied.sh, the five-buoy pentagon, two arenas of other sizes (0.7 m,
# 1.2 m), and five of them again with every buoy's lamp lit (point lights). Every trial draws the arena's light (0.02 to 0.4, or
# off), each buoy's IR film (or none), each buoy's place (±4 cm) and the robot's start. The
# fitness charges visits out of cyclic order. Then examples/transfer_grid.sh: the transfer
# grid on six layouts never sailed in training, and the target checked. The result stays in
# the output folder: the committed worlds/regatta_evolved_transfer.wbt is this stage evolved on
# by examples/evolve_regatta_transfer_more.sh, then examples/evolve_regatta_transfer_final.sh
# (run them after this script, in that order).
set -euo pipefail
cd "$(dirname "$0")/.."
source examples/transfer_training.sh
cargo build --release -p regatta
regatta=${CARGO_TARGET_DIR:-target}/release/regatta
out=${OUT:-out/evolve-regatta-transfer}
generations=${GENERATIONS:-150}
jobs=${JOBS:-2}
mkdir -p "$out"

TIMEFORMAT="evolution: %R s wall, %U s user + %S s system CPU on $jobs threads"
time "$regatta" evolve worlds/regatta_neural_transfer.wbt \
  "${transfer_stage1_worlds[@]}" \
  --fitness "${FITNESS:-regatta:other=-0.5}" --aggregate "${AGGREGATE:-mean}" \
  --generations "$generations" --trials 1 --duration "${DURATION:-80}" \
  --seed "${SEED:-1}" --from-weights --sigma "${SIGMA:-0.3}" -j "$jobs" --out "$out" \
  "${transfer_variations[@]}"

OUT="$out/transfer" examples/transfer_grid.sh worlds/regatta.wbt \
  worlds/regatta_evolved_varied.wbt "$out/best.wbt"

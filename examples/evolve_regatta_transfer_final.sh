#!/usr/bin/env bash
# Fourth and fifth stages of worlds/regatta_evolved_transfer.wbt. They start from the third
# stage's network, kept as worlds/regatta_evolved_transfer_stage3.wbt, so that this script
# alone reproduces the controller byte for byte in under 10 minutes on 2 cores; to run the
# whole curriculum, run examples/evolve_regatta_transfer.sh and
# examples/evolve_regatta_transfer_more.sh first and start from the latter's result
# (FROM=out/evolve-regatta-transfer-more/stage3/best.wbt). The network evolved on from its own weights (--from-weights) with
# CMA-ES over the seventeen training layouts of the third stage and two more, none of them held
# out: four buoys on an irregular quadrilateral in a 1.3 m by 0.7 m arena, and four in a 1.0 m
# by 0.7 m arena with every lamp lit (worlds/regatta_train_long4.wbt,
# worlds/regatta_train_lamps_narrow4.wbt), each with a diagonal shorter than some of its sides,
# where a controller that heads for the nearest buoy cuts across and skips one; the same
# variations, trials of 100 s, out-of-order visits charged -1. Stage 4: 100 generations, step
# size 0.1, one trial per layout; stage 5: 50 generations from stage 4's best, step size 0.07,
# two trials per layout (a less noisy fitness). Then examples/transfer_grid.sh on the six
# held-out layouts.
set -euo pipefail
cd "$(dirname "$0")/.."
source examples/transfer_training.sh
cargo build --release -p regatta
regatta=${CARGO_TARGET_DIR:-target}/release/regatta
out=${OUT:-out/evolve-regatta-transfer-final}
from=${FROM:-worlds/regatta_evolved_transfer_stage3.wbt}
jobs=${JOBS:-2}
mkdir -p "$out"

stage() { # stage FROM OUT GENERATIONS SIGMA TRIALS
  TIMEFORMAT="evolution ($2): %R s wall, %U s user + %S s system CPU on $jobs threads"
  time "$regatta" evolve "$1" \
    "${transfer_stage4_worlds[@]}" \
    --fitness 'regatta:other=-1.0' --aggregate mean \
    --generations "$3" --trials "$5" --duration 100 \
    --seed 1 --from-weights --sigma "$4" -j "$jobs" --out "$2" \
    "${transfer_variations[@]}"
}
stage "$from" "$out/stage4" 100 0.1 1
stage "$out/stage4/best.wbt" "$out/stage5" 50 0.07 2
cp "$out/stage5/best.wbt" worlds/regatta_evolved_transfer.wbt

OUT="$out/transfer" examples/transfer_grid.sh worlds/regatta.wbt \
  worlds/regatta_evolved_varied.wbt worlds/regatta_evolved_transfer.wbt

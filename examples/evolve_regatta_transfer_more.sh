#!/usr/bin/env bash
# Second and third stages of worlds/regatta_evolved_transfer.wbt, after
# examples/evolve_regatta_transfer.sh (run it first: its out/evolve-regatta-transfer/best.wbt
# is where these start, FROM=… to start elsewhere). The network evolved on from its own
# weights (--from-weights, step size 0.15) with CMA-ES over the thirteen training layouts of
# the first stage and four more, none of them held out: a three-buoy and a five-buoy 1.2 m
# arena with every lamp lit, a flat triangle with every lamp lit, and a 1.2 m by 0.8 m arena
# (worlds/regatta_train_lamps_large3.wbt, _large5.wbt, _flat.wbt, worlds/regatta_train_long.wbt);
# the same variations, trials of 100 s. Stage 2: 150 generations charging out-of-order
# visits -0.5 (as the first stage); stage 3: 120 generations from stage 2's best, charging
# them -1. Stage 3's network is worlds/regatta_evolved_transfer_stage3.wbt (written anew,
# byte for byte the committed one); then examples/transfer_grid.sh on the six held-out
# layouts. The committed worlds/regatta_evolved_transfer.wbt is stage 3 evolved on by
# examples/evolve_regatta_transfer_final.sh (run it after this script).
set -euo pipefail
cd "$(dirname "$0")/.."
source examples/transfer_training.sh
cargo build --release -p regatta
regatta=${CARGO_TARGET_DIR:-target}/release/regatta
out=${OUT:-out/evolve-regatta-transfer-more}
from=${FROM:-out/evolve-regatta-transfer/best.wbt}
jobs=${JOBS:-2}
mkdir -p "$out"

stage() { # stage FROM OUT GENERATIONS FITNESS
  TIMEFORMAT="evolution ($2): %R s wall, %U s user + %S s system CPU on $jobs threads"
  time "$regatta" evolve "$1" \
    "${transfer_stage2_worlds[@]}" \
    --fitness "$4" --aggregate mean \
    --generations "$3" --trials 1 --duration 100 \
    --seed 1 --from-weights --sigma 0.15 -j "$jobs" --out "$2" \
    "${transfer_variations[@]}"
}
stage "$from" "$out/stage2" 150 'regatta:other=-0.5'
stage "$out/stage2/best.wbt" "$out/stage3" 120 'regatta:other=-1.0'
cp "$out/stage3/best.wbt" worlds/regatta_evolved_transfer_stage3.wbt

OUT="$out/transfer" examples/transfer_grid.sh worlds/regatta.wbt \
  worlds/regatta_evolved_varied.wbt worlds/regatta_evolved_transfer_stage3.wbt

#!/usr/bin/env bash
# The transfer grid of examples/evolve_regatta_transfer.sh for the controllers (worlds) given:
# six layouts never sailed in training (worlds/regatta_heldout_*.wbt) × the arena's light at
# 0.05 (as written and as trained), 0.02 and 0.4, the buoys' lamps lit (point lights) with and
# without the arena's light × buoys with IR film and without; seeds 1 to 5, 600 s. First
# `regatta transfer` (table, runs.csv, table.csv, heat map), then examples/transfer_grid.py:
# per-buoy visits and the share of cyclic visits of every run, the target checked cell by
# cell, and every run's visits compared with transfer's runs.csv.
set -euo pipefail
cd "$(dirname "$0")/.."
regatta=${CARGO_TARGET_DIR:-target}/release/regatta
out=${OUT:-out/transfer-grid}
jobs=${JOBS:-2}
mkdir -p "$out"
conditions=()
while IFS= read -r condition; do
  conditions+=(--condition "$condition")
done < <(examples/transfer_grid.py --conditions)
"$regatta" transfer "$@" --seeds 1..5 --duration 600 -j "$jobs" "${conditions[@]}" \
  --out "$out" > "$out/transfer.txt"
examples/transfer_grid.py "$@" --regatta "$regatta" --jobs "$jobs" --runs "$out/runs.csv" \
  --csv "$out/target.csv" | tee "$out/target.txt"

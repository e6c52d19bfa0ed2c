#!/usr/bin/env bash
# The regatta evolved: a network on IR and the pooled raw retina (worlds/regatta_neural.wbt)
# evolved from random weights with CMA-ES, each candidate sailing the paper's arena and four
# other layouts (the small, wide, off-centre and four-buoy arenas take its robot as it is),
# then compared with the hand-tuned `regatta` controller over ten simulated minutes on every
# layout, including two it never sailed (five and two buoys).
#
# Writes docs/regatta-fitness.png (the figure in the README), worlds/regatta_evolved.wbt
# (the evolved world) and out/evolve-regatta/ (CSV, log, the comparison table). Deterministic:
# the same seed gives the same bytes on any machine and for any -j. Prints the wall and CPU
# time of the evolution (the target: 15 minutes on 2 cores).
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -p regatta
regatta=target/release/regatta
out=${OUT:-out/evolve-regatta}
generations=${GENERATIONS:-200}
jobs=${JOBS:-2}
mkdir -p "$out"

TIMEFORMAT="evolution: %R s wall, %U s user + %S s system CPU on $jobs threads"
time "$regatta" evolve worlds/regatta_neural.wbt \
  --world worlds/regatta_small.wbt --world worlds/regatta_wide.wbt \
  --world worlds/regatta_offcentre.wbt --world worlds/regatta_four.wbt \
  --fitness regatta --generations "$generations" --trials 2 --duration 60 \
  --seed 1 -j "$jobs" --out "$out"
cp "$out/fitness.png" docs/regatta-fitness.png
cp "$out/best.wbt" worlds/regatta_evolved.wbt

# Ten minutes, seeds 1 to 10, per layout and controller: cyclic visits (mean and least), all
# visits (mean) and mean speed.
summary() {
  awk -F, 'NR > 1 { c += $12; v += $11; s += $8; n++; if (min == "" || $12 < min) min = $12 }
    END { printf "%6.1f %5d %6.1f %6.3f", c / n, min, v / n, s / n }'
}
columns="cyclic least visits    m/s"
{
  printf '%-10s %-7s   %-26s   %s\n' "" "" "hand-tuned regatta" "evolved network"
  printf '%-10s %-7s   %-26s   %s\n' layout trained "$columns" "$columns"
  for layout in regatta regatta_small regatta_wide regatta_offcentre regatta_four regatta_five \
    regatta_two; do
    case $layout in regatta_five | regatta_two) trained=no ;; *) trained=yes ;; esac
    hand=$("$regatta" batch "worlds/$layout.wbt" --seeds 1..10 --duration 600 -j "$jobs" --csv \
      2>/dev/null | summary)
    evolved=$("$regatta" batch "worlds/$layout.wbt" --network-from worlds/regatta_evolved.wbt \
      --seeds 1..10 --duration 600 -j "$jobs" --csv 2>/dev/null | summary)
    printf '%-10s %-7s   %-26s   %s\n' "${layout#regatta_}" "$trained" "$hand" "$evolved"
  done
} | tee "$out/comparison.txt"

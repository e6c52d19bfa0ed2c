#!/bin/bash
# The viewer's cost as fast as possible, one robot: steps/s (wall time while stepping) and
# CPU seconds (user+sys, the client threads included) of `run`, of `view` with nobody
# watching, and of `view` with one client following /events. Usage: scripts/bench_view.sh
# (BIN, WORLD, STEPS, ROUNDS override the release binary, worlds/regatta.wbt, 1e6, 3).
set -u
bin=${BIN:-${CARGO_TARGET_DIR:-target}/release/regatta}
world=${WORLD:-worlds/regatta.wbt}
steps=${STEPS:-1000000}
tmp=$(mktemp -d)
cd "$(dirname "$0")/.."
[ -x "$bin" ] || { echo "no release binary at $bin (cargo build --release -p regatta)" >&2; exit 2; }
cpu() { awk '/^cpu/ {print $2+$3}' "$1"; }
rate() { grep -o '[0-9]* steps/s' "$1" | head -1; }
for round in $(seq ${ROUNDS:-3}); do
  /usr/bin/time -f "cpu %U %S" -o "$tmp/t1" $bin run $world --steps $steps --threads 1 > "$tmp/o1"
  /usr/bin/time -f "cpu %U %S" -o "$tmp/t2" $bin view $world --speed fast --steps $steps --exit --threads 1 > "$tmp/o2" 2>/dev/null
  /usr/bin/time -f "cpu %U %S" -o "$tmp/t3" $bin view $world --paused --speed fast --steps $steps --exit --threads 1 > "$tmp/o3" 2>/dev/null &
  pid=$!; sleep 0.5; url=$(head -1 "$tmp/o3")
  curl -sN "${url}events?robot=0" > "$tmp/stream" & cpid=$!
  sleep 0.3; curl -s -X POST "${url}control?cmd=play" > /dev/null
  wait $pid; kill $cpid 2>/dev/null
  echo "round $round: run $(rate "$tmp/o1") cpu $(cpu "$tmp/t1") s | unwatched $(rate "$tmp/o2") cpu $(cpu "$tmp/t2") s | watched $(rate "$tmp/o3") cpu $(cpu "$tmp/t3") s"
done
rm -rf "$tmp"

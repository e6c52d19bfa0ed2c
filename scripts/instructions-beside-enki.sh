#!/usr/bin/env bash
# Marginal instructions per step (valgrind --tool=callgrind, two run lengths, subtracted) of
# regatta and Enki on ../shared/peers/enki/swarm_world.py's worlds, one thread each: Enki with
# its camera and IR only, regatta with the crowd setting (REGATTA_CROWD added to the turrets,
# by default compare-enki-crowd.sh's `crowdDistance 0.5 crowdFarDistance 4 crowdKeepDistance
# 0.05`) and IR only; then what one retina may cost if regatta is to run at TARGET times
# Enki's rate (docs/crowd.md, "What a step may cost beside Enki"). Instruction counts do not
# depend on the machine's load, unlike the wall-clock figures of compare-enki-crowd.sh.
# Usage: scripts/instructions-beside-enki.sh ENKI_SWARM REGATTA OUTDIR [N:TARGET ...]
# (default 1:1 10:2 100:3; build Enki with ../shared/peers/enki/build.sh).
set -euo pipefail
enki=$1; regatta=$2; out=$3; shift 3
sizes=("$@"); [ ${#sizes[@]} -gt 0 ] || sizes=(1:1 10:2 100:3)
crowd=${REGATTA_CROWD:-crowdDistance 0.5 crowdFarDistance 4 crowdKeepDistance 0.05}
world=$(cd "$(dirname "$0")/.." && pwd)/../shared/peers/enki/swarm_world.py
mkdir -p "$out"
collected() { grep -o 'Collected : [0-9]*' "$1" | awk '{print $3}'; }

# regatta_marginal WORLD STEPS1 STEPS2: instructions per step between the two run lengths.
regatta_marginal() {
  local a b
  for k in "$2" "$3"; do
    valgrind --tool=callgrind --callgrind-out-file=/dev/null "$regatta" run "$1" --steps "$k" \
      --threads 1 > /dev/null 2> "$out/cg-$k.err"
  done
  a=$(collected "$out/cg-$2.err"); b=$(collected "$out/cg-$3.err")
  echo $(( (b - a) / ($3 - $2) ))
}

# enki_marginal N [--ir-only]: Enki runs for a wall time, so its step counts are read back.
enki_marginal() {
  local n=$1; shift
  # Under callgrind a 1000-robot Enki makes about a step in 3 s: longer windows there.
  local short=1 long=3
  if [ "$n" -ge 1000 ]; then short=40; long=120; fi
  for s in $short $long; do
    valgrind --tool=callgrind --callgrind-out-file=/dev/null "$enki" "$n" "$@" --seconds "$s" \
      > /dev/null 2> "$out/enki-$s.err"
  done
  python3 - "$out/enki-$short.err" "$out/enki-$long.err" <<'EOF'
import re, sys
def read(path):
    text = open(path).read()
    return (int(re.search(r'Collected : (\d+)', text).group(1)),
            int(re.search(r'; (\d+) steps', text).group(1)))
(i1, s1), (i3, s3) = read(sys.argv[1]), read(sys.argv[2])
print(round((i3 - i1) / (s3 - s1)))
EOF
}

printf 'robots\tenki_camera\tenki_ir\tenki_per_camera\tregatta_ir\tregatta_per_retina\ttarget\tbudget_per_retina\n' \
  | tee "$out/instructions.tsv"
for size in "${sizes[@]}"; do
  n=${size%%:*}; target=${size##*:}
  python3 "$world" "$n" | sed "s/PanoramicTurret { lambda 5 }/PanoramicTurret { lambda 5 $crowd }/" \
    > "$out/sw_${n}_crowd.wbt"
  python3 "$world" "$n" --ir-only > "$out/sw_${n}_ir.wbt"
  # Enough steps that the difference dwarfs start-up, few enough for callgrind.
  k1=$(( 20000 / n )); [ "$k1" -ge 20 ] || k1=20
  retina=$(regatta_marginal "$out/sw_${n}_crowd.wbt" "$k1" $(( 3 * k1 )))
  ir=$(regatta_marginal "$out/sw_${n}_ir.wbt" $(( 4 * k1 )) $(( 12 * k1 )))
  camera=$(enki_marginal "$n"); enki_ir=$(enki_marginal "$n" --ir-only)
  python3 - "$n" "$camera" "$enki_ir" "$ir" "$retina" "$target" <<'EOF' | tee -a "$out/instructions.tsv"
import sys
n, camera, enki_ir, ir, retina = (int(v) for v in sys.argv[1:6])
target = float(sys.argv[6])
budget = (camera / target - ir) / n
print(f"{n}\t{camera}\t{enki_ir}\t{(camera - enki_ir) // n}\t{ir}\t{(retina - ir) // n}\t{target:g}\t{budget:.0f}")
EOF
done

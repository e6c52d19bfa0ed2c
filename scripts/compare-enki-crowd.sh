#!/usr/bin/env bash
# Enki (camera + IR, built from source by ../shared/peers/enki/build.sh) beside
# regatta on ../shared/peers/enki/swarm_world.py's worlds, one thread each, interleaved as
# compare.sh does; regatta with its crowd setting (REGATTA_CROWD added to the turrets, by
# default `crowdDistance 0.5 crowdFarDistance 4 crowdKeepDistance 0.05`, 0.095 LSB at 1000
# robots in `regatta bench crowd`, within the 0.1 budget: the far distance changes nothing
# below 1000 robots, whose arenas are smaller) and exact. Usage: scripts/compare-enki-crowd.sh ENKI_SWARM
# REGATTA OUTDIR (build Enki with ../shared/peers/enki/build.sh). One line per run in
# OUTDIR/runs.tsv.
enki=$1; regatta=$2; out=$3; mkdir -p "$out"
crowd=${REGATTA_CROWD:-crowdDistance 0.5 crowdFarDistance 4 crowdKeepDistance 0.05}
world=$(cd "$(dirname "$0")/.." && pwd)/../shared/peers/enki/swarm_world.py
declare -A K=([1]=600000 [10]=20000 [100]=1500 [1000]=100)
declare -A KX=([1]=600000 [10]=15000 [100]=200 [1000]=5)
printf 'sim\trobots\tmode\trep\tsteps_per_s\tpeak_rss_kb\n' > "$out/runs.tsv"
for n in 1 10 100 1000; do
  python3 "$world" "$n" > "$out/sw_${n}_exact.wbt"
  sed "s/PanoramicTurret { lambda 5 }/PanoramicTurret { lambda 5 $crowd }/" "$out/sw_${n}_exact.wbt" > "$out/sw_${n}_crowd.wbt"
  for rep in 1 2; do
    /usr/bin/time -f '%M' -o "$out/enki_${n}_${rep}.time" "$enki" "$n" --seconds 3 > "$out/enki_${n}_$rep.out" 2>&1
    sps=$(grep -o 'steps_per_s=[0-9.]*' "$out/enki_${n}_$rep.out" | cut -d= -f2)
    printf 'enki\t%s\tcamera\t%s\t%s\t%s\n' "$n" "$rep" "$sps" "$(cat "$out/enki_${n}_${rep}.time")" >> "$out/runs.tsv"
    for mode in crowd exact; do
      k=${K[$n]}; [ $mode = exact ] && k=${KX[$n]}
      /usr/bin/time -f '%M' -o "$out/r.time" "$regatta" run "$out/sw_${n}_$mode.wbt" --steps "$k" --threads 1 > "$out/regatta_${n}_${mode}_$rep.out" 2>&1
      sps=$(awk -v k="$k" '/^wall time/ { w = $3; if ($4 ~ /^ms/) w /= 1000; printf "%.4g", k / w }' "$out/regatta_${n}_${mode}_$rep.out")
      printf 'regatta\t%s\t%s\t%s\t%s\t%s\n' "$n" "$mode" "$rep" "$sps" "$(cat "$out/r.time")" >> "$out/runs.tsv"
    done
    tail -3 "$out/runs.tsv"
  done
done

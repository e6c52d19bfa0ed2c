#!/usr/bin/env bash
# Writes tools/hot-code.order: the functions of the regatta executable that a run executes,
# which tools/build.rs hands to the linker (lld's --symbol-ordering-file) so that they lie
# together at the front of the code. The kernel maps an executable's code in 64 kB blocks
# around each page a process touches; with the code a run needs spread over 8 MB of text, a
# 1000-robot run kept 5.7 MB of it resident, and 1.9 MB once it is gathered (docs/crowd.md,
# "Peak memory of a run"). The order changes no instruction, only where functions lie.
#
# Usage: scripts/order-hot-code.sh [REGATTA]   (default target/release/regatta; needs
# valgrind and python3). Run it after changes that rename or add much of the run's code: a
# symbol the file names and the build lacks is passed over, and a function it does not name
# is laid out after the named ones, as before, so a stale file costs memory, never
# correctness. Give it a binary from `cargo build --release -p regatta`: one that `cargo test`
# built has other features unified and other symbol names.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
regatta=$(realpath "${1:-$root/target/release/regatta}")
swarm="$root/../shared/peers/enki/swarm_world.py"
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT

python3 "$swarm" 1000 | sed 's/PanoramicTurret { lambda 5 }/PanoramicTurret { lambda 5 crowdDistance 0.5 }/' \
  > "$work/crowd1000.wbt"
python3 "$swarm" 1000 | sed 's/PanoramicTurret { lambda 5 }/PanoramicTurret { lambda 5 crowdDistance 0.5 crowdFarDistance 5 }/' \
  > "$work/far1000.wbt"
python3 "$swarm" 1000 | sed 's/PanoramicTurret { lambda 5 }/PanoramicTurret { lambda 5 crowdDistance 0.5 crowdFarDistance 5 crowdKeepDistance 0.05 }/' \
  > "$work/kept1000.wbt"
python3 "$swarm" 1000 --ir-only > "$work/ir1000.wbt"
python3 "$swarm" 1 | sed 's/PanoramicTurret { lambda 5 }/PanoramicTurret { lambda 5 crowdDistance 0.5 }/' \
  > "$work/crowd1.wbt"

# The workloads: the crowd benchmarks' worlds (with and without a far distance, with kept
# impostors), and the paper's regatta with a log.
trace() {
  local name=$1; shift
  valgrind --tool=callgrind --dump-instr=yes --compress-strings=no --compress-pos=no \
    --callgrind-out-file="$work/$name.cg" "$regatta" "$@" > /dev/null 2>&1
}
trace crowd1000 run "$work/crowd1000.wbt" --steps 10 --threads 1
trace far1000 run "$work/far1000.wbt" --steps 200 --threads 1
trace kept1000 run "$work/kept1000.wbt" --steps 200 --threads 1
trace ir1000 run "$work/ir1000.wbt" --steps 100 --threads 1
trace crowd1 run "$work/crowd1.wbt" --steps 1000 --threads 1
trace regatta run "$root/worlds/regatta.wbt" --steps 500 --threads 1 --log "$work/regatta.mcap"

python3 - "$regatta" "$root/tools/hot-code.order" "$work"/*.cg <<'EOF'
import bisect, os, subprocess, sys

regatta, out, traces = sys.argv[1], sys.argv[2], sys.argv[3:]
executed = set()
for path in traces:
    in_regatta = False
    for line in open(path):
        if line.startswith("ob="):
            in_regatta = os.path.realpath(line[3:].strip()) == regatta
        elif in_regatta and line.startswith("0x"):
            executed.add(int(line.split()[0], 16))
functions = []
nm = subprocess.run(["nm", "-S", "--defined-only", regatta], capture_output=True, text=True, check=True)
for row in nm.stdout.splitlines():
    fields = row.split()
    if len(fields) == 4 and fields[2] in "tTwW":
        functions.append((int(fields[0], 16), int(fields[1], 16), fields[3]))
functions.sort()
starts = [f[0] for f in functions]
hot = {}
for address in executed:
    i = bisect.bisect_right(starts, address) - 1
    if i >= 0 and functions[i][0] <= address < functions[i][0] + functions[i][1]:
        hot[functions[i][2]] = functions[i][1]
with open(out, "w") as file:
    file.write("# The functions a run executes, for tools/build.rs: written by scripts/order-hot-code.sh.\n")
    file.write("".join(name + "\n" for name in sorted(hot)))
print(f"{len(hot)} functions, {sum(hot.values()) / 1e6:.2f} MB of code, written to {out}")
EOF

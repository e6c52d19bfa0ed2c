#!/usr/bin/env bash
# One controller in any language: a Python Braitenberg controller (pyserial) drives
# `regatta serve --pty`, and `regatta drive --controller braitenberg` drives another served
# copy of the same world; both recorded logs must be byte-identical to the log of the same
# world run in-process with its built-in braitenberg controller.
# Usage: tests/interop/serial.sh path/to/regatta
set -euo pipefail
cd "$(dirname "$0")/../.."
regatta="$1"
out=target/serial-interop
rm -rf "$out" && mkdir -p "$out"
steps=300

# A world whose robot runs the built-in braitenberg controller, for the reference.
sed 's/controller "regatta"/controller "braitenberg"/' worlds/regatta.wbt >"$out/braitenberg.wbt"

serve() { # serve LOG: starts a lock-step server on a pty; sets $pty and $server
  "$regatta" serve "$out/braitenberg.wbt" --pty --steps "$steps" --seed 5 --log "$1" >"$1.out" 2>"$1.err" &
  server=$!
  pty=""
  for _ in $(seq 100); do
    pty=$(sed -n 's|.* on \(/dev/[^ ]*\) .*|\1|p' "$1.out" | head -1)
    if [ -n "$pty" ]; then break; fi
    sleep 0.1
  done
  if [ -z "$pty" ]; then cat "$1.err" >&2; echo "regatta serve printed no pty" >&2; exit 1; fi
}

serve "$out/python.mcap"
python3 runtime/serial/examples/braitenberg.py "$pty" "$steps"
wait "$server"
cat "$out/python.mcap.out"

serve "$out/rust.mcap"
"$regatta" drive --port "$pty" --controller braitenberg --steps "$steps" --period 0
wait "$server"
cat "$out/rust.mcap.out"

"$regatta" run "$out/braitenberg.wbt" --steps "$steps" --seed 5 --log "$out/in-process.mcap" >/dev/null
grep -q "0 malformed, 0 refused" "$out/python.mcap.out"
cmp "$out/python.mcap" "$out/rust.mcap"
cmp "$out/python.mcap" "$out/in-process.mcap"
echo "serial interop: the Python controller and the Rust one over a pty, and the in-process run, give byte-identical logs"

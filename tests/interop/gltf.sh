#!/usr/bin/env bash
# Exports every world in worlds/, the geometry test world, an animated run, and the corpus's worlds to glTF, and runs
# the Khronos glTF-Validator (npm package gltf-validator) over all of them: any error fails.
# Usage: tests/interop/gltf.sh path/to/regatta
set -euo pipefail
cd "$(dirname "$0")/../.."
regatta="$1"
out=target/gltf-interop
rm -rf "$out" && mkdir -p "$out/corpus"

if [ ! -d target/npm/node_modules/gltf-validator ]; then
  npm install --silent --no-audit --no-fund --prefix target/npm gltf-validator@2.0.0-dev.3.10
fi

for world in worlds/*.wbt; do
  name=$(basename "$world" .wbt)
  "$regatta" gltf "$world" -o "$out/$name.glb" 2>>"$out/export.log"
  "$regatta" gltf "$world" -o "$out/$name.gltf" --quality 8 2>>"$out/export.log"
done
# Every geometry node the export reads (lines, points, mesh files), with its texture.
"$regatta" gltf tests/data/gltf/worlds/geometry.wbt -o "$out/geometry.glb" 2>>"$out/export.log"
"$regatta" run worlds/regatta.wbt --duration 20 --log "$out/run.mcap" >/dev/null
"$regatta" gltf worlds/regatta.wbt --log "$out/run.mcap" -o "$out/regatta-run.glb" 2>>"$out/export.log"

count=0
while IFS= read -r world; do
  count=$((count + 1))
  # The two parser-test files that are broken on purpose are refused, as they must be. A
  # Webots project keeps its PROTOs beside worlds/: its folder is allowed, as a user would.
  allow=()
  case "$world" in */worlds/*) allow=(--allow-path "$(dirname "$(dirname "$world")")") ;; esac
  if "$regatta" gltf --lenient "${allow[@]}" "$world" -o "$out/corpus/$count.glb" 2>>"$out/export.log"; then
    echo "$count $world" >>"$out/corpus/index.txt"
  fi
done < <(find ../shared/corpus -name '*.wbt' -o -name '*.wrl' | sort)

NODE_PATH=target/npm/node_modules node tests/interop/validate_gltf.js \
  "$out"/*.glb "$out"/*.gltf "$out"/corpus/*.glb

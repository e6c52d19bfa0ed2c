#!/usr/bin/env bash
# The tests, Rust and Python together: `cargo test --workspace` (arguments are passed on, e.g.
# `--features regatta/wgpu`), then the `regatta` Python module built into a virtual environment
# as a user installs it (`pip install ./python`), then pytest over python/tests (the module,
# the Gymnasium, PettingZoo and Ray layers, and the examples on a short budget).
#
# The virtual environment is target/python-venv (REGATTA_VENV overrides it); it is made and
# filled on first use: maturin, numpy, gymnasium, pettingzoo, cma, ray, pytest, and
# Stable-Baselines3 with torch. PyPI's torch for x86-64 Linux depends on NVIDIA's CUDA runtime
# wheels (about 3 GB installed; no CPU-only torch is on PyPI): they are installed and never
# used (training runs with device="cpu"). REGATTA_SKIP_SB3=1 leaves them out and skips the
# PPO example's test, saying so. REGATTA_SKIP_CARGO=1 runs the Python tests alone (while working on
# them; the tests compare with target/debug/regatta, which must then exist).
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD

venv=${REGATTA_VENV:-$root/target/python-venv}
python=${PYTHON:-python3}

if [ "${REGATTA_SKIP_CARGO:-0}" != 1 ]; then
  cargo test --workspace "$@"
fi

if [ ! -x "$venv/bin/python" ]; then
  "$python" -m venv "$venv"
fi
pip=("$venv/bin/python" -m pip --disable-pip-version-check)
packages=(maturin numpy gymnasium pettingzoo cma pytest ray)
if [ "${REGATTA_SKIP_SB3:-0}" != 1 ]; then
  packages+=(stable-baselines3)
fi
started=$(date +%s)
"${pip[@]}" install --quiet "${packages[@]}"
echo "python packages ready in $(( $(date +%s) - started )) s"

# The module, installed from the source folder as a user would (an abi3 wheel built by maturin).
started=$(date +%s)
"${pip[@]}" install --quiet --force-reinstall --no-deps ./python
echo "regatta module built and installed in $(( $(date +%s) - started )) s"

# The Python tests compare with the command line built by `cargo test` above.
export REGATTA_BIN=${REGATTA_BIN:-$root/target/debug/regatta}
# pytest runs from the repository's root through its own script, never `python -m pytest` from
# python/: that would put python/ first on sys.path and import the source folder (which has no
# compiled extension) instead of the installed module.
"$venv/bin/pytest" python/tests -q -p no:cacheprovider

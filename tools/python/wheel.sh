#!/usr/bin/env bash
# Build the odo-tools wheel into OUT_DIR (default build/release/package). The package's data
# (odo_tools/data: the DBC and the example robots) are symlinks into the repository's single
# copies; the build runs on a copy of tools/python with them resolved, so nothing is written into
# the source tree. Uses the pinned .venv (setuptools, wheel from requirements.txt), offline.
#   bash tools/python/wheel.sh [OUT_DIR]
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
out=$(realpath -m "${1:-$root/build/release/package}")
py="${ODO_VENV:-$root/.venv}/bin/python"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cp -rL "$root/tools/python" "$tmp/src"
find "$tmp/src" \( -name __pycache__ -o -name '*.egg-info' -o -name build \) -prune -exec rm -rf {} +
mkdir -p "$out"
"$py" -m pip wheel -q --disable-pip-version-check --no-deps --no-build-isolation --no-index \
  -w "$tmp/dist" "$tmp/src"
for w in "$tmp"/dist/*.whl; do
  mv -f "$w" "$out/"
  echo "wheel: $out/$(basename "$w")"
done

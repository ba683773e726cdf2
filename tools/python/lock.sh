#!/usr/bin/env bash
# Re-compile requirements.txt, the hash-pinned lock of every Python dependency (runtime, the dev
# extra, the build backend, and everything they pull in), from pyproject.toml with pip-tools.
# Versions already in requirements.txt are kept; pass package names to move them:
#   bash tools/python/lock.sh                 # add what pyproject.toml gained, keep the rest
#   bash tools/python/lock.sh numpy scipy     # upgrade those two (and what they need)
# Needs PyPI. pip-tools runs from a throwaway venv, so .venv is not touched; tools/deps.sh then
# installs the lock with --require-hashes.
set -euo pipefail
cd "$(dirname "$0")"
PIP_TOOLS_VERSION=7.6.2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
python3 -m venv "$tmp/venv"
"$tmp/venv/bin/pip" install -q --disable-pip-version-check "pip-tools==$PIP_TOOLS_VERSION"
upgrade=()
for p in "$@"; do upgrade+=(--upgrade-package "$p"); done
CUSTOM_COMPILE_COMMAND="bash tools/python/lock.sh" \
  "$tmp/venv/bin/pip-compile" -q --generate-hashes --allow-unsafe --strip-extras \
  --extra dev --all-build-deps --no-emit-index-url --no-emit-find-links --resolver backtracking \
  "${upgrade[@]}" --output-file requirements.txt pyproject.toml

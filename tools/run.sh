#!/usr/bin/env bash
# The README's Quick start entry point: works as root on a fresh Debian bookworm machine.
# Installs `make` if it is missing, then runs `make <target>`; every target installs what it needs
# (tools/deps.sh) and is idempotent. Usage: bash tools/run.sh demo|test|bench|build|...
set -euo pipefail
cd "$(dirname "$0")/.."
if ! command -v make >/dev/null 2>&1; then
  echo "run: installing make (Debian package)"
  SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends make >/dev/null
fi
exec make "$@"

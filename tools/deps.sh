#!/usr/bin/env bash
# Install everything the build, tests and demo need, from Debian's packages and PyPI only.
# Idempotent and quiet when there is nothing to do. Run as root on Debian bookworm (or with sudo).
set -euo pipefail
cd "$(dirname "$0")/.."

APT_PACKAGES=(
  make cmake ninja-build gcc libc6-dev pkg-config check          # host build + Check
  gcc-arm-none-eabi libnewlib-arm-none-eabi binutils-arm-none-eabi  # Cortex-M4 cross build
  python3 python3-venv                                             # host tools, pytest
  valgrind                                                         # odo-bench instruction counts
  libjansson-dev                                                   # host_sim robot/scenario JSON
  libgsl-dev                                                       # odo-calib fit: nonlinear least squares
  qemu-system-x86 busybox-static cpio can-utils                     # vcan test: Debian kernel under qemu
  clang libclang-rt-14-dev                                         # fuzz/: libFuzzer harnesses
  cppcheck clang-tidy clang-format gcovr                           # static analysis, format check, coverage
  qemu-system-arm                                                  # target tests: Cortex-M4 boards under qemu
  openocd                                                          # make flash; its config check in ctest
  dpkg-dev help2man                                                # the .deb: CPack's shlibdeps, man pages
)

missing=()
for p in "${APT_PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "deps: installing Debian packages: ${missing[*]}"
  SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# Python venv from PyPI: every package (and what it pulls in) pinned with hashes in
# tools/python/requirements.txt, compiled from pyproject.toml by tools/python/lock.sh.
# Re-installed only when a requirements file changes.
VENV=.venv
PY=/usr/bin/python3
[ -x "$PY" ] || PY=python3
stamp="$VENV/.requirements.sha256"
want=$(for f in tools/python/requirements.txt tools/python/requirements-unity.txt tools/python/pyproject.toml; do
  if [ -f "$f" ]; then cat "$f"; fi; done | sha256sum | cut -d' ' -f1)
if [ ! -x "$VENV/bin/python" ] || [ "$(cat "$stamp" 2>/dev/null)" != "$want" ]; then
  echo "deps: building $VENV from PyPI (pinned)"
  [ -x "$VENV/bin/python" ] || "$PY" -m venv "$VENV"
  "$VENV/bin/pip" install -q --disable-pip-version-check --require-hashes \
    -r tools/python/requirements.txt
  # Unity's C sources (see cmake/Unity.cmake): no dependencies, hash-checked download.
  "$VENV/bin/pip" install -q --disable-pip-version-check --no-deps --require-hashes \
    -r tools/python/requirements-unity.txt
  if [ -f tools/python/pyproject.toml ]; then
    # setuptools and wheel come from the lock above, so the build needs no unpinned download
    "$VENV/bin/pip" install -q --disable-pip-version-check --no-deps --no-build-isolation \
      -e tools/python
  fi
  echo "$want" > "$stamp"
fi

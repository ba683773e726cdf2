"""Where the tools find their data and libodosim: in a checkout, or installed from the wheel.

Two layouts, one rule each:

- A checkout (the package imported from tools/python, editable or by path): the repository
  itself, found by walking up from this file to can/odometry.dbc; libodosim.so in
  build/<preset>/lib (the gap modules' own search, tools/python/odo_tools/gap/simlib.py).
- Installed (a wheel in any environment): the DBC, the example robots and odo-flash's openocd
  configuration the wheel carries in odo_tools/data/ (laid out as in the repository: can/,
  host_sim/robots/, hal/cortexm/openocd/), and libodosim.so
  from, in order: $ODO_BUILD_DIR/lib, next to the package (odo_tools/lib/), the prefix the
  .deb's odo-sim was installed under (PREFIX/bin/odo-sim on PATH -> PREFIX/lib), the
  directories of LD_LIBRARY_PATH, this environment's prefix, /usr/local/lib and /usr/lib.

The gap modules take both locations from ODO_SOURCE_DIR and ODO_BUILD_DIR (gap/io.py
source_dir, gap/simlib.py lib_path). `export_for_gap` sets those two for an installed package
when the user has not, so an installed odo-gap or odo-import finds what the checkout would give
it; in a checkout it sets nothing.
"""

from __future__ import annotations

import os
import shutil
import sys
from pathlib import Path

PACKAGE_DIR = Path(__file__).resolve().parent
DATA_DIR = PACKAGE_DIR / "data"
LIB_NAME = "libodosim.so"


def checkout_root() -> Path | None:
    """The repository root this package was imported from, or None when installed."""
    for p in PACKAGE_DIR.parents:
        if (p / "can" / "odometry.dbc").is_file() and (p / "tools" / "python").is_dir():
            return p
    return None


def data_root() -> Path:
    """The folder holding can/, host_sim/robots/, hal/cortexm/openocd/: the checkout, else the
    wheel's odo_tools/data."""
    return checkout_root() or DATA_DIR


def dbc_path() -> Path:
    """can/odometry.dbc, the single source of truth for every frame."""
    return data_root() / "can" / "odometry.dbc"


def robot_path(name: str) -> Path:
    """An example robot description (host_sim/robots/NAME.json)."""
    return data_root() / "host_sim" / "robots" / f"{name}.json"


def lib_candidates() -> list[Path]:
    """Installed locations of libodosim.so, most specific first (see the module docstring)."""
    dirs: list[Path] = []
    if os.environ.get("ODO_BUILD_DIR"):
        dirs.append(Path(os.environ["ODO_BUILD_DIR"]) / "lib")
    dirs.append(PACKAGE_DIR / "lib")
    exe = shutil.which("odo-sim")
    if exe:
        dirs.append(Path(exe).resolve().parent.parent / "lib")
    dirs += [Path(d) for d in os.environ.get("LD_LIBRARY_PATH", "").split(os.pathsep) if d]
    dirs += [Path(sys.prefix) / "lib", Path("/usr/local/lib"), Path("/usr/lib")]
    return [d / LIB_NAME for d in dirs]


def installed_lib() -> Path | None:
    """The first installed libodosim.so that exists, or None."""
    for c in lib_candidates():
        if c.is_file():
            return c
    return None


def export_for_gap() -> None:
    """Point the gap modules at the wheel's data and the installed libodosim (installed only).

    They read ODO_SOURCE_DIR (a folder with can/odometry.dbc and host_sim/robots/) and
    ODO_BUILD_DIR (a folder with lib/libodosim.so); a value the user set is kept.
    """
    if checkout_root() is not None:
        return
    if not os.environ.get("ODO_SOURCE_DIR") and (DATA_DIR / "can" / "odometry.dbc").is_file():
        os.environ["ODO_SOURCE_DIR"] = str(DATA_DIR)
    if not os.environ.get("ODO_BUILD_DIR"):
        lib = installed_lib()
        if lib is not None:
            # gap/simlib.py looks for ODO_BUILD_DIR/lib/libodosim.so
            if lib.parent.name == "lib":
                os.environ["ODO_BUILD_DIR"] = str(lib.parent.parent)

"""Where the repository's data lives (the DBC, example robots): a leaf module, so the readers
(io.py) and the library loader (simlib.py) share it without importing each other."""

from __future__ import annotations

import os
from pathlib import Path

from .errors import GapInputError


def source_dir() -> Path:
    """The repository root (ODO_SOURCE_DIR, else found from this file)."""
    env = os.environ.get("ODO_SOURCE_DIR")
    if env:
        return Path(env)
    here = Path(__file__).resolve()
    for p in here.parents:
        if (p / "can" / "odometry.dbc").is_file():
            return p
    raise GapInputError(here, "cannot find the repository (can/odometry.dbc); set ODO_SOURCE_DIR")

"""The Python lock (tools/python/requirements.txt) against its one source, pyproject.toml.

pyproject.toml names what the tools import (and the dev extra, and the build backend);
tools/python/lock.sh compiles it with `pip-compile --generate-hashes` into requirements.txt, which
tools/deps.sh installs with --require-hashes. A dependency added to pyproject.toml without
re-locking, a pin without hashes, or a .venv that was not built from the lock fails here.
"""

import os
import re
import tomllib
from importlib import metadata
from pathlib import Path

SRC = Path(os.environ["ODO_SOURCE_DIR"])
PY = SRC / "tools/python"
PIN = re.compile(r"^([A-Za-z0-9][A-Za-z0-9._-]*)==([^\s\\;]+)")


def norm(name: str) -> str:
    return re.sub(r"[-_.]+", "-", name).lower()


def req_name(spec: str) -> str:
    return norm(re.split(r"[\s<>=!~;\[]", spec.strip(), maxsplit=1)[0])


def lock(path: Path) -> dict[str, tuple[str, int]]:
    """name -> (version, number of hashes), from a pip-compile output."""
    out: dict[str, tuple[str, int]] = {}
    cur = None
    for line in path.read_text().splitlines():
        s = line.strip()
        if not s or s.startswith("#"):
            continue
        m = PIN.match(s)
        if m:
            cur = norm(m.group(1))
            assert cur not in out, f"{path.name}: {cur} pinned twice"
            out[cur] = (m.group(2), s.count("--hash=sha256:"))  # hashes may share the line
        elif s.startswith("--hash=sha256:") and cur is not None:
            v, n = out[cur]
            out[cur] = (v, n + 1)
        else:
            raise AssertionError(f"{path.name}: not a pin or a hash: {s!r}")
    return out


def test_every_pin_carries_hashes():
    for f in ("requirements.txt", "requirements-unity.txt"):
        pins = lock(PY / f)
        assert pins, f
        missing = [n for n, (_, h) in pins.items() if h == 0]
        assert not missing, f"{f}: pinned without --hash: {missing}"


def test_lock_covers_pyproject():
    proj = tomllib.loads((PY / "pyproject.toml").read_text())
    wanted = {req_name(s) for s in proj["project"]["dependencies"]}
    for extra in proj["project"].get("optional-dependencies", {}).values():
        wanted |= {req_name(s) for s in extra}
    wanted |= {req_name(s) for s in proj["build-system"]["requires"]}
    pins = lock(PY / "requirements.txt")
    missing = sorted(wanted - set(pins))
    assert not missing, (
        f"in pyproject.toml but not in the lock (bash tools/python/lock.sh): {missing}"
    )


def test_venv_is_built_from_the_lock():
    pins = lock(PY / "requirements.txt")
    wrong = {}
    for name, (version, _) in pins.items():
        try:
            have = metadata.version(name)
        except metadata.PackageNotFoundError:
            have = None
        if have != version:
            wrong[name] = (version, have)
    assert not wrong, f"lock vs .venv (make deps): {wrong}"

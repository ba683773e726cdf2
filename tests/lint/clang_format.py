#!/usr/bin/env python3
"""The C format check (ctest lint.format) and its fixer (make format).

ROOTS below is the one statement of which C is formatted: every .c and .h under these folders,
against the repository's .clang-format (clang-format 14, Debian's). A C file anywhere else in
the tree is an error, so a new folder of C cannot slip past the check.

  clang_format.py SRC              check: clang-format --dry-run -Werror, exit 1 on any finding
  clang_format.py SRC --fix        reformat in place (clang-format -i)
  clang_format.py SRC --self-test  the check flags a misformatted file and passes a clean one
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOTS = ("firmware", "hal", "hostlib", "host_sim", "tools", "tests", "fuzz")
# Not sources: build trees, the venv, VCS data and fuzzing corpora (inputs, not code).
SKIP_DIRS = {".git", ".venv", "build", "corpus", "regressions", "__pycache__", "node_modules"}
BATCH = 64


def c_files(src: Path) -> tuple[list[Path], list[Path]]:
    """(files under ROOTS, C files elsewhere in the tree), both sorted."""
    inside, outside = [], []
    for dirpath, dirnames, filenames in os.walk(src):
        dirnames[:] = sorted(
            d for d in dirnames if d not in SKIP_DIRS and not d.startswith("build")
        )
        rel = Path(dirpath).relative_to(src)
        for name in filenames:
            if name.endswith((".c", ".h")):
                p = rel / name
                (inside if p.parts[0] in ROOTS and len(p.parts) > 1 else outside).append(p)
    return sorted(inside), sorted(outside)


def run(exe: str, src: Path, files: list[Path], args: list[str], quiet: bool = False) -> int:
    rc = 0
    for i in range(0, len(files), BATCH):
        cmd = [exe, "--style=file", *args, *map(str, files[i : i + BATCH])]
        r = subprocess.run(cmd, cwd=src, capture_output=quiet)
        rc = rc or r.returncode
    return rc


def self_test(exe: str, src: Path) -> int:
    """The check must fail on a file the style rejects and pass the same code formatted."""
    with tempfile.TemporaryDirectory() as d:
        shutil.copy(src / ".clang-format", Path(d) / ".clang-format")
        bad = Path(d) / "bad.c"
        bad.write_text("int  f(int a){return a+1;}\n")
        flagged = run(exe, Path(d), [Path("bad.c")], ["--dry-run", "-Werror"], quiet=True) != 0
        run(exe, Path(d), [Path("bad.c")], ["-i"])
        clean = run(exe, Path(d), [Path("bad.c")], ["--dry-run", "-Werror"], quiet=True) == 0
    print(f"misformatted file flagged: {flagged}; after -i it passes: {clean}")
    return 0 if flagged and clean else 1


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("src", type=Path, help="the repository's top folder")
    mode = ap.add_mutually_exclusive_group()
    mode.add_argument("--fix", action="store_true", help="reformat in place instead of checking")
    mode.add_argument("--self-test", action="store_true", help="check that the check can fail")
    ap.add_argument(
        "--clang-format", default="clang-format", help="the executable (default: on PATH)"
    )
    a = ap.parse_args(argv)
    exe = shutil.which(a.clang_format)
    if exe is None:
        print(
            f"clang_format.py: {a.clang_format} not found (make deps installs it)", file=sys.stderr
        )
        return 2
    src = a.src.resolve()
    if not (src / ".clang-format").is_file():
        print(f"clang_format.py: no .clang-format in {src}", file=sys.stderr)
        return 2
    if a.self_test:
        return self_test(exe, src)
    files, stray = c_files(src)
    if stray:
        print(
            "clang_format.py: C outside ROOTS (add its folder to ROOTS in this script):",
            *map(str, stray),
            sep="\n  ",
            file=sys.stderr,
        )
        return 1
    rc = run(exe, src, files, ["-i"] if a.fix else ["--dry-run", "-Werror"])
    verb = "reformatted" if a.fix else "checked"
    print(
        f"clang_format.py: {verb} {len(files)} files under {', '.join(ROOTS)}: "
        f"{'ok' if rc == 0 else 'findings above'}"
    )
    return 1 if rc else 0


if __name__ == "__main__":
    sys.exit(main())

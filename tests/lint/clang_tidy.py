"""Run clang-tidy (the repo's .clang-tidy) over every source of the given folders that the build's
compile_commands.json compiles; exit 1 on any finding (warnings are errors), printing them.

usage: clang_tidy.py BUILD_DIR SOURCE_DIR FOLDER... [-- EXTRA_CLANG_TIDY_ARGS...]"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path


def main() -> int:
    argv = sys.argv[1:]
    extra: list[str] = []
    if "--" in argv:
        i = argv.index("--")
        argv, extra = argv[:i], argv[i + 1 :]
    if len(argv) < 3:
        print(__doc__, file=sys.stderr)
        return 2
    build, src, folders = Path(argv[0]), Path(argv[1]), [Path(argv[1]) / f for f in argv[2:]]
    db = json.loads((build / "compile_commands.json").read_text())
    files = sorted(
        {
            e["file"]
            for e in db
            if any(Path(e["file"]).is_relative_to(f) for f in folders)
            and not Path(e["file"]).is_relative_to(build)
        }
    )
    if not files:
        print(f"clang_tidy.py: no sources of {argv[2:]} in {build}/compile_commands.json")
        return 1

    def tidy(f: str) -> tuple[str, int, str]:
        r = subprocess.run(
            ["clang-tidy", "-p", str(build), "--quiet", "--warnings-as-errors=*",
             "--extra-arg=-Wno-unknown-warning-option", *extra, f],
            capture_output=True, text=True, cwd=src,
        )  # fmt: skip
        return f, r.returncode, r.stdout

    bad = 0
    with ThreadPoolExecutor(max_workers=os.cpu_count() or 1) as ex:
        for f, rc, out in ex.map(tidy, files):
            if rc != 0 or "warning:" in out or "error:" in out:
                bad += 1
                print(out.rstrip() or f"{f}: clang-tidy exit {rc}")
    print(f"clang-tidy: {len(files)} files, {bad} with findings")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())

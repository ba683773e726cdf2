"""python -m odo_tools.validation.indep: write one case of the independent world by hand."""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

import numpy as np

from . import draw_case, simulate_case


def _inside(p: Path, folder: Path) -> bool:
    p, folder = p.resolve(), folder.resolve()
    return p == folder or folder in p.parents


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        prog="python -m odo_tools.validation.indep",
        description="Draw case K of the independent world from seed S and write its recorded "
        "data (robot.json, run-*.log, run-*.truth.csv, returns.csv) into a new folder OUT. "
        "The hidden key (effect, law, sizes, fidelity) goes only to --key FILE, never into OUT.",
    )
    ap.add_argument("--seed", type=int, required=True, help="seed of the case draw (S)")
    ap.add_argument("--case", type=int, required=True, help="case number K (0, 1, ...)")
    ap.add_argument("--out", type=Path, required=True, help="folder to create (must not exist)")
    ap.add_argument("--key", type=Path, help="write the case's key (JSON) to this file")
    ap.add_argument("--quiet", action="store_true", help="no progress output")
    a = ap.parse_args(argv)
    if a.case < 0:
        ap.error("--case must be >= 0")
    if a.out.exists():
        print(f"error: {a.out}: exists; give a new folder", file=sys.stderr)
        return 2
    if not a.out.parent.resolve().is_dir():
        print(f"error: {a.out.parent}: no such folder", file=sys.stderr)
        return 2
    if a.key is not None:
        if _inside(a.key, a.out):
            print(f"error: --key {a.key} lies inside --out {a.out}: the key must never land "
                  "beside the recorded data", file=sys.stderr)
            return 2
        if a.key.exists():
            print(f"error: {a.key}: exists; give a new file", file=sys.stderr)
            return 2
        if not a.key.parent.resolve().is_dir():
            print(f"error: {a.key.parent}: no such folder", file=sys.stderr)
            return 2
    rng = np.random.default_rng(a.seed)
    case = None
    for k in range(a.case + 1):  # case K is the K-th draw of the seed's stream
        case = draw_case(rng, k)
    assert case is not None

    def progress(k: int, n: int) -> None:
        if not a.quiet:
            print(f"\r  tick {k}/{n}", end="", file=sys.stderr, flush=True)

    if not a.quiet:
        print(f"case {a.case} (seed {a.seed}): {case['vehicle']}, {len(case['plan'])} runs, "
              f"{case['tick_ms']} ms cycle", file=sys.stderr)
    extra = simulate_case(case, a.out, seed=a.seed * 1_000_003 + a.case, progress=progress)
    if not a.quiet:
        print(f"\rwrote {a.out}: {len(extra['runs'])} runs in {extra['generation_s']:.1f} s",
              file=sys.stderr)
    if a.key is not None:
        key = dict(case)
        key.update(extra)
        tmp = a.key.with_name(f".{a.key.name}.tmp-{os.getpid()}")
        tmp.write_text(json.dumps(key, indent=1) + "\n")
        os.replace(tmp, a.key)
    return 0


if __name__ == "__main__":
    sys.exit(main())

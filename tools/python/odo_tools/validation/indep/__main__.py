"""python -m odo_tools.validation.indep: write one case of the independent world by hand."""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

import numpy as np

from .. import case_seed
from . import draw_case, simulate_case


def _inside(p: Path, folder: Path) -> bool:
    p, folder = p.resolve(), folder.resolve()
    return p == folder or folder in p.parents


def plot_tracks(real: Path, png: Path) -> None:
    """Truth track of every run (truck A, and B of a two-truck vehicle), one panel per run."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    runs = sorted(real.glob("run-*.truth.csv"))
    n = len(runs)
    cols = min(4, n)
    rows = (n + cols - 1) // cols
    fig, axs = plt.subplots(rows, cols, figsize=(3.2 * cols, 3.2 * rows), squeeze=False)
    for ax, f in zip(axs.flat, runs, strict=False):
        d = np.genfromtxt(f, delimiter=",", names=True)
        ax.plot(d["a_x_mm"] / 1000, d["a_y_mm"] / 1000, lw=0.8, label="A")
        if "b_x_mm" in d.dtype.names:
            ax.plot(d["b_x_mm"] / 1000, d["b_y_mm"] / 1000, lw=0.6, label="B")
        ax.set_title(f.name.replace(".truth.csv", ""), fontsize=8)
        ax.set_aspect("equal", "datalim")
        ax.tick_params(labelsize=7)
    for ax in list(axs.flat)[n:]:
        ax.axis("off")
    fig.suptitle(f"{real.name}: motion-capture tracks (m)", fontsize=9)
    fig.tight_layout()
    tmp = png.with_name(f".{png.name}.tmp-{os.getpid()}.png")
    fig.savefig(tmp, dpi=110)
    plt.close(fig)
    os.replace(tmp, png)


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
    ap.add_argument("--plot", type=Path, help="also draw the runs' truth tracks into this PNG "
                    "(outside --out; it shows only what the recorded data show)")
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
    for what, f in (("--plot", a.plot),):
        if f is not None and (_inside(f, a.out) or f.exists()):
            print(f"error: {what} {f}: exists or lies inside --out", file=sys.stderr)
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
    extra = simulate_case(case, a.out, seed=case_seed(a.seed, a.case), progress=progress)
    if not a.quiet:
        print(f"\rwrote {a.out}: {len(extra['runs'])} runs in {extra['generation_s']:.1f} s",
              file=sys.stderr)
    if a.plot is not None:
        plot_tracks(a.out, a.plot)
    if a.key is not None:
        key = dict(case)
        key.update(extra)
        tmp = a.key.with_name(f".{a.key.name}.tmp-{os.getpid()}")
        tmp.write_text(json.dumps(key, indent=1) + "\n")
        os.replace(tmp, a.key)
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Plot the foundation demo: believed vs true path of a UMBmark square, cw and ccw.

Reads the pose.csv files written by odo-demo and writes one PNG. A person sees at a glance that the
firmware believes it closed the square while the uncalibrated robot did not (000 Fig. 3.3 style).
"""

from __future__ import annotations

import argparse
import csv
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from .outpath import OutputError
from .plotstyle import LEGEND_PT, TITLE_PT, save_png


def read_pose(path: Path) -> dict[str, np.ndarray]:
    """Columns of an odo-demo pose.csv as float arrays, keyed by header name."""
    try:
        with path.open(newline="", encoding="utf-8") as f:
            rows = list(csv.reader(f))
    except UnicodeDecodeError as e:
        line = path.read_bytes()[: e.start].count(b"\n") + 1
        raise ValueError(f"{path}:{line}: not UTF-8 text") from None
    if len(rows) < 2:
        raise ValueError(f"{path}: no data rows")
    for i, r in enumerate(rows[1:], start=2):
        if len(r) != len(rows[0]):
            raise ValueError(f"{path}:{i}: {len(r)} fields, expected {len(rows[0])}")
        try:
            [float(x) for x in r]
        except ValueError:
            raise ValueError(f"{path}:{i}: not a number") from None
    header, data = rows[0], np.array(rows[1:], dtype=float)
    for need in ("x_mm", "y_mm", "true_x_mm", "true_y_mm"):
        if need not in header:
            raise ValueError(f"{path}:1: no column {need} (an odo-demo pose.csv?)")
    return {name: data[:, i] for i, name in enumerate(header)}


def figure(runs: dict[str, Path]) -> plt.Figure:
    fig, (ax, zoom) = plt.subplots(1, 2, figsize=(11, 5.8), gridspec_kw={"width_ratios": [1, 1.3]})
    colours = {"cw": "tab:blue", "ccw": "tab:red"}
    errors: list[float] = []
    for name, path in runs.items():
        p = read_pose(path)
        c = colours.get(name, "k")
        ax.plot(p["x_mm"] / 1000, p["y_mm"] / 1000, "--", color=c, lw=1, label=f"{name}: firmware")
        ax.plot(
            p["true_x_mm"] / 1000,
            p["true_y_mm"] / 1000,
            "-",
            color=c,
            lw=1.5,
            label=f"{name}: true path",
        )
        ex, ey = p["true_x_mm"][-1] - p["x_mm"][-1], p["true_y_mm"][-1] - p["y_mm"][-1]
        zoom.plot([0, ex], [0, ey], ":", color=c, lw=1)
        zoom.plot(
            [ex],
            [ey],
            "o",
            color=c,
            ms=9,
            label=f"{name}: ex {ex:.0f}, ey {ey:.0f} mm (|e| {np.hypot(ex, ey):.0f} mm)",
        )
        errors += [abs(ex), abs(ey)]
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title("4 x 4 m UMBmark square, uncalibrated robot", fontsize=TITLE_PT)
    ax.set_aspect("equal")
    ax.grid(True, alpha=0.3)
    # below the axes: inside, any corner covers a path
    ax.legend(fontsize=LEGEND_PT, loc="upper center", bbox_to_anchor=(0.5, -0.1), ncol=2)
    zoom.axhline(0, color="grey", lw=0.5)
    zoom.axvline(0, color="grey", lw=0.5)
    zoom.plot(0, 0, "k+", ms=14)
    zoom.set_xlabel("ex = x_true - x_firmware [mm]")
    zoom.set_ylabel("ey = y_true - y_firmware [mm]")
    zoom.set_title("return position error at the end (000 Eq. 3.1)", fontsize=TITLE_PT)
    zoom.set_aspect("equal")
    lim = 1.3 * max([50.0, *errors])
    zoom.set_xlim(-lim, lim)
    zoom.set_ylim(-lim, lim)
    zoom.grid(True, alpha=0.3)
    zoom.legend(fontsize=LEGEND_PT, loc="lower left")
    fig.tight_layout()
    return fig


def plot(runs: dict[str, Path], out: Path) -> None:
    save_png(figure(runs), out, runs.values())


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument(
        "--run",
        action="append",
        default=[],
        metavar="NAME=POSE_CSV",
        required=True,
        help="a run to draw, e.g. cw=out/demo/cw/pose.csv (repeatable)",
    )
    ap.add_argument("--out", type=Path, required=True, help="PNG to write")
    args = ap.parse_args(argv)
    runs = {}
    for spec in args.run:
        name, sep, path = spec.partition("=")
        if not sep or not path:
            ap.error(f"--run expects NAME=PATH, got '{spec}'")
        runs[name] = Path(path)
    try:
        plot(runs, args.out)
    except (OSError, ValueError, OutputError) as e:
        print(f"odo-plot-demo: {e}", file=sys.stderr)
        return 1
    print(f"odo-plot-demo: wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

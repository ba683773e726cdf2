"""odo-plot-realdata: held-out runs of a real robot, motion capture against the firmware's
replayed track before and after calibration (one panel per run).

Reads, per run, the truth track odo-import wrote (RUN.truth.csv: t_s, a_x_mm, a_y_mm,
a_theta_deg) and the poses.csv files odo-replay wrote for the same log with the robot's nominal
block (--before) and with the calibrated block (--after). The firmware's track starts at the
origin heading +x; it is placed on the truth's start pose. Titles give the return position error
(end of the replayed track vs the truth's end, in the truth's start frame) before -> after; an
inset in each panel zooms on the end, where millimetres are lost at the scale of the path.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from .outpath import OutputError
from .plotstyle import LEGEND_PT, TITLE_PT, save_png


def load_truth(p: Path) -> np.ndarray:
    try:
        a = np.loadtxt(p, delimiter=",", skiprows=1, usecols=(0, 1, 2, 3), ndmin=2)
    except (OSError, ValueError) as e:
        raise SystemExit(f"odo-plot-realdata: {p}: {e}") from None
    if a.shape[0] < 2:
        raise SystemExit(f"odo-plot-realdata: {p}: fewer than 2 rows")
    return a


def load_poses(p: Path) -> np.ndarray:
    """odo-replay poses.csv -> (n, 3) x_mm, y_mm, theta_rad of truck A."""
    try:
        a = np.genfromtxt(p, delimiter=",", names=True)
    except (OSError, ValueError) as e:
        raise SystemExit(f"odo-plot-realdata: {p}: {e}") from None
    return np.column_stack([a["x_a_mm"], a["y_a_mm"], np.radians(a["theta_a_deg"])])


def placed(track: np.ndarray, x0: float, y0: float, th0: float) -> np.ndarray:
    c, s = math.cos(th0), math.sin(th0)
    return np.column_stack(
        [x0 + c * track[:, 0] - s * track[:, 1], y0 + s * track[:, 0] + c * track[:, 1]]
    )


def return_error(track: np.ndarray, truth: np.ndarray) -> float:
    """|end of the track - truth's end| in the truth's start frame (000 Eq. 3.1), mm."""
    th0 = math.radians(truth[0, 3])
    c, s = math.cos(th0), math.sin(th0)
    dx, dy = truth[-1, 1] - truth[0, 1], truth[-1, 2] - truth[0, 2]
    tx, ty = c * dx + s * dy, -s * dx + c * dy
    return math.hypot(track[-1, 0] - tx, track[-1, 1] - ty)


def figure(panels: list[tuple[str, Path, Path, Path]]) -> plt.Figure:
    n = len(panels)
    fig, axes = plt.subplots(
        2, n, figsize=(4.2 * n, 8.0), squeeze=False, gridspec_kw={"height_ratios": [3, 1.4]}
    )
    for k, (name, tp, bp, afp) in enumerate(panels):
        ax, ae = axes[0, k], axes[1, k]
        tr = load_truth(tp)
        x0, y0, th0 = tr[0, 1], tr[0, 2], math.radians(tr[0, 3])
        before, after = load_poses(bp), load_poses(afp)
        eb, ea = return_error(before, tr), return_error(after, tr)
        pb, pa = placed(before, x0, y0, th0), placed(after, x0, y0, th0)
        # the end, zoomed: an inset in the path's empty middle
        zoom = ax.inset_axes([0.3, 0.3, 0.4, 0.4])
        half = max(1.3 * max(eb, ea), 10.0)
        xe, ye = tr[-1, 1], tr[-1, 2]
        for a, lw in ((ax, 1.0), (zoom, 1.4)):
            a.plot(tr[:, 1], tr[:, 2], "k-", lw=2.2 * lw, alpha=0.35, label="motion capture")
            a.plot(pb[:, 0], pb[:, 1], "C3-", lw=lw, label="firmware, nominal block")
            a.plot(pa[:, 0], pa[:, 1], "C0-", lw=lw, label="firmware, calibrated block")
        ax.plot([x0], [y0], "ko", ms=4, label="start")
        for tk, col in ((pb, "C3"), (pa, "C0")):
            zoom.plot([tk[-1, 0]], [tk[-1, 1]], "o", color=col, ms=5)
        zoom.plot([xe], [ye], "ko", ms=5, alpha=0.5)
        zoom.set_xlim(xe - half, xe + half)
        zoom.set_ylim(ye - half, ye + half)
        zoom.set_aspect("equal")
        zoom.set_title(f"end, {2 * half:.0f} mm wide", fontsize=LEGEND_PT)
        zoom.tick_params(labelsize=7)
        zoom.grid(alpha=0.3)
        ax.indicate_inset_zoom(zoom, edgecolor="k", alpha=0.6)
        ax.set_title(f"{name}\nreturn error {eb:.1f} -> {ea:.1f} mm", fontsize=TITLE_PT)
        ax.set_aspect("equal")
        ax.set_xlabel("x (mm)")
        ax.set_ylabel("y (mm)")
        ax.grid(alpha=0.3)
        # distance to the truth along the run: where the error builds up
        m = min(tr.shape[0], pb.shape[0], pa.shape[0])
        for tk, col, lab in ((pb, "C3", "nominal block"), (pa, "C0", "calibrated block")):
            err = np.hypot(tk[:m, 0] - tr[:m, 1], tk[:m, 1] - tr[:m, 2])
            ae.plot(tr[:m, 0], err, col, lw=1.0, label=lab)
        ae.set_xlabel("time (s)")
        ae.set_ylabel("distance to truth (mm)")
        ae.grid(alpha=0.3)
        print(f"{name}: return error {eb:.2f} -> {ea:.2f} mm", file=sys.stderr)
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(
        handles,
        labels,
        loc="upper center",
        ncol=4,
        fontsize=LEGEND_PT,
        bbox_to_anchor=(0.5, 0.955),
        frameon=False,
    )
    fig.suptitle("Held-out runs: motion capture vs the firmware replaying the logs", fontsize=11)
    fig.tight_layout(rect=(0, 0, 1, 0.93))
    return fig


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        prog="odo-plot-realdata",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    ap.add_argument(
        "--run",
        action="append",
        required=True,
        metavar="NAME=TRUTH,BEFORE,AFTER",
        help="a panel: name, the run's truth CSV, odo-replay poses.csv before and after",
    )
    ap.add_argument("--out", required=True, help="PNG to write (a temp beside it, then renamed)")
    a = ap.parse_args(argv)
    panels = []
    for spec in a.run:
        name, _, rest = spec.partition("=")
        parts = rest.split(",")
        if not name or len(parts) != 3:
            ap.error(f"--run {spec!r}: expected NAME=TRUTH,BEFORE,AFTER")
        panels.append((name, *(Path(p) for p in parts)))
    out = Path(a.out)
    try:  # the output rule (odo_tools/outpath.py): temp beside it, renamed; never an input
        save_png(figure(panels), out, [p for pn in panels for p in pn[1:]])
    except (OutputError, OSError) as e:
        print(f"odo-plot-realdata: {e}", file=sys.stderr)
        return 1
    print(f"odo-plot-realdata: wrote {out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())

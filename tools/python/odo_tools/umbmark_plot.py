"""UMBmark return-error plots (000_12e7709aa9cd375a.txt): the cw and ccw clusters of return
position errors with their centres of gravity and r_cg (Fig. 3.4 style, Eqs. 3.1-3.3) and, given
the runs after calibration, both on one set of axes (Fig. 6.5 style).

Reads returns.csv files (host_sim/README.md contract) and writes one PNG; prints Emax,syst
(Eq. 3.4) of each set. After calibration the cluster is ~20 times smaller than before, so it gets
a panel of its own at its own scale.
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
from matplotlib.patches import Rectangle

from .outpath import OutputError
from .plotstyle import LEGEND_PT, TITLE_PT, save_png

COLUMNS = [
    "run",
    "direction",
    "x_abs_mm",
    "y_abs_mm",
    "theta_abs_deg",
    "x_calc_mm",
    "y_calc_mm",
    "theta_calc_deg",
]


def read_returns(path: Path) -> dict[str, np.ndarray]:
    """Return errors (000 Eq. 3.1) per direction: {"cw": (n, 2) array of (ex, ey) mm, ...}."""
    try:
        with path.open(newline="", encoding="utf-8") as f:
            rows = [r for r in csv.reader(f) if r and not r[0].startswith("#")]
    except UnicodeDecodeError as e:
        line = path.read_bytes()[: e.start].count(b"\n") + 1
        raise ValueError(f"{path}:{line}: not UTF-8 text") from None
    except csv.Error as e:
        raise ValueError(f"{path}: not a CSV table: {e}") from None
    if not rows or rows[0] != COLUMNS:
        raise ValueError(f"{path}:1: header must be {','.join(COLUMNS)}")
    out: dict[str, list[tuple[float, float]]] = {"cw": [], "ccw": []}
    for lineno, r in enumerate(rows[1:], start=2):
        if len(r) != len(COLUMNS) or r[1] not in out:
            raise ValueError(f"{path}:{lineno}: expected 8 fields with direction cw or ccw")
        try:
            v = [float(x) for x in r[2:]]
        except ValueError as e:
            raise ValueError(f"{path}:{lineno}: {e}") from None
        if not np.all(np.isfinite(v)):
            raise ValueError(f"{path}:{lineno}: values must be finite")
        out[r[1]].append((v[0] - v[3], v[1] - v[4]))
    if not out["cw"] and not out["ccw"]:
        raise ValueError(f"{path}: no runs (a header and no rows)")
    return {d: np.array(p, dtype=float).reshape(-1, 2) for d, p in out.items()}


def emax_syst(errors: dict[str, np.ndarray]) -> float:
    """000 Eq. 3.4: the larger distance of the two centres of gravity from the origin."""
    return max(float(np.hypot(*e.mean(axis=0))) for e in errors.values() if len(e))


def draw(
    ax: plt.Axes, errors: dict[str, np.ndarray], label: str, filled: bool, annotate: bool = True
) -> None:
    style = {"cw": ("o", "tab:blue"), "ccw": ("s", "tab:red")}
    for d, e in errors.items():
        if not len(e):
            continue
        marker, color = style[d]
        ax.scatter(
            e[:, 0],
            e[:, 1],
            marker=marker,
            facecolors=color if filled else "none",
            edgecolors=color,
            label=f"{label} {d}",
        )
        cg = e.mean(axis=0)
        ax.plot(*cg, marker="x", color=color, markersize=12, mew=2)
        ax.plot([0, cg[0]], [0, cg[1]], color=color, lw=0.8, ls="--")
        if annotate:
            ax.annotate(
                f"c.g. {d} r={np.hypot(*cg):.1f} mm",
                cg,
                textcoords="offset points",
                xytext=(6, 6),
                fontsize=LEGEND_PT,
                color=color,
            )


def zoom_box(errors: dict[str, np.ndarray]) -> tuple[float, float, float, float]:
    """A square window (x0, x1, y0, y1) around a cluster and the origin, with a margin."""
    pts = np.vstack([np.zeros((1, 2)), *(e for e in errors.values() if len(e))])
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    mid, half = (lo + hi) / 2, max(float((hi - lo).max()) / 2, 1.0) * 1.25
    return mid[0] - half, mid[0] + half, mid[1] - half, mid[1] + half


def figure(
    before: dict[str, np.ndarray], after: dict[str, np.ndarray] | None, title: str
) -> plt.Figure:
    """Before alone; with after: before, both on one scale, and the after cluster zoomed (its
    window marked on the middle panel), since after calibration it sits at the origin's scale."""
    panels = 3 if after is not None else 1
    fig, axes = plt.subplots(1, panels, figsize=(6.0 * panels, 6.2), squeeze=False)
    ax = axes[0][0]
    draw(ax, before, "before", filled=True)
    ax.set_title(
        f"{title}\nbefore: Emax,syst {emax_syst(before):.1f} mm (000 Eq. 3.4)", fontsize=TITLE_PT
    )
    if after is not None:
        eb, ea = emax_syst(before), emax_syst(after)
        both, zoom = axes[0][1], axes[0][2]
        draw(both, before, "before", filled=False, annotate=False)
        draw(both, after, "after", filled=True, annotate=False)
        both.set_title(
            f"before {eb:.1f} mm, after {ea:.1f} mm ({eb / max(ea, 1e-9):.0f}-fold), one scale",
            fontsize=TITLE_PT,
        )
        x0, x1, y0, y1 = zoom_box(after)
        both.add_patch(
            Rectangle(
                (x0, y0),
                x1 - x0,
                y1 - y0,
                fill=False,
                color="k",
                lw=1.0,
                ls=":",
                label="zoomed (right)",
            )
        )
        draw(zoom, after, "after", filled=True)
        zoom.set_xlim(x0, x1)
        zoom.set_ylim(y0, y1)
        zoom.set_title(f"after calibration, zoomed: Emax,syst {ea:.1f} mm", fontsize=TITLE_PT)
    for a in axes[0]:
        a.axhline(0, color="grey", lw=0.5)
        a.axvline(0, color="grey", lw=0.5)
        a.plot(0, 0, "k+", markersize=14)
        a.set_aspect(
            "equal", adjustable="box" if a is axes[0][-1] and after is not None else "datalim"
        )
        a.set_xlabel("ex = x_abs - x_calc [mm]")
        a.set_ylabel("ey = y_abs - y_calc [mm]")
        a.legend(fontsize=LEGEND_PT, loc="best")
        a.grid(True, lw=0.3)
    fig.tight_layout()
    return fig


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        prog="odo-plot-umbmark",
        description="Plot UMBmark return errors: cw/ccw clusters and centres of gravity "
        "(000 Fig. 3.4), before and after calibration (Fig. 6.5), the after "
        "cluster zoomed.",
    )
    ap.add_argument("--before", type=Path, required=True, help="returns.csv before calibration")
    ap.add_argument("--after", type=Path, help="returns.csv after calibration")
    ap.add_argument("--out", type=Path, required=True, help="output PNG")
    ap.add_argument("--title", default="UMBmark return position errors")
    args = ap.parse_args(argv)
    try:
        before = read_returns(args.before)
        after = read_returns(args.after) if args.after else None
    except (OSError, ValueError) as e:
        print(f"odo-plot-umbmark: {e}", file=sys.stderr)
        return 1
    try:
        save_png(figure(before, after, args.title), args.out, [args.before, args.after])
    except OutputError as e:
        print(f"odo-plot-umbmark: {e}", file=sys.stderr)
        return 1
    except OSError as e:
        print(f"odo-plot-umbmark: cannot write {args.out}: {e.strerror or e}", file=sys.stderr)
        return 1
    line = f"Emax,syst before {emax_syst(before):.1f} mm"
    if after is not None:
        line += f", after {emax_syst(after):.1f} mm"
    print(f"odo-plot-umbmark: {line} -> {args.out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())

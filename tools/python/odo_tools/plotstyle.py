"""One look for the tools' PNGs (umbmark_plot, plot_demo, realdata_plot): resolution, legend and
annotation sizes, and the output rule for PNGs, in one place so a test can hold every
plot to them (tests/python/test_plots.py)."""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

from .outpath import out_file

DPI = 130  # >= 120: readable when a README or a report shows the PNG at full width
LEGEND_PT = 9.0  # legends and point annotations; >= 9 pt
TITLE_PT = 10.0


def save_png(fig: plt.Figure, out: Path, inputs: Iterable[str | Path | None] = ()) -> None:
    """Write fig to out by the output rule (odo_tools/outpath.py: a fresh temp beside it, renamed
    into place; never one of `inputs`); closes fig either way. Raises OutputError or OSError."""
    try:
        with out_file(out, list(inputs), "wb") as f:
            fig.savefig(f, format="png", dpi=DPI)
    finally:
        plt.close(fig)

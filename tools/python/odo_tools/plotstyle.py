"""One look for the tools' PNGs (umbmark_plot, plot_demo, realdata_plot): resolution, legend and
annotation sizes, and the write-a-temp-then-rename rule, in one place so a test can hold every
plot to them (tests/python/test_plots.py)."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

DPI = 130  # >= 120: readable when a README or a report shows the PNG at full width
LEGEND_PT = 9.0  # legends and point annotations; >= 9 pt
TITLE_PT = 10.0


def save_png(fig: plt.Figure, out: Path) -> None:
    """Write fig to out through a temporary file renamed into place; closes fig either way."""
    out = Path(out)
    tmp = out.with_name(out.name + ".tmp.png")
    try:
        fig.savefig(tmp, dpi=DPI)
        tmp.replace(out)
    except OSError:
        tmp.unlink(missing_ok=True)
        raise
    finally:
        plt.close(fig)

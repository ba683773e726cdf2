"""odo-gap's report folder: report.json, report.md and the plots, written all or nothing.

Its own module so that the diagnosis (diagnose.py) and the plots (plots.py, which draw with the
diagnosis' own helpers) do not import each other (issue 17; tests/lint/layers.py)."""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

from .diagnose import markdown
from .plots import plot_report


def write_report(rep: dict, out: str | Path) -> None:
    """Everything into OUT.tmp.<pid>, then renamed into place: never a partial report."""
    out = Path(out)
    tmp = out.with_name(out.name + f".tmp.{os.getpid()}")
    if tmp.exists():
        shutil.rmtree(tmp)
    tmp.mkdir(parents=True)
    try:
        extra = rep.pop("_plot", None)
        (tmp / "report.json").write_text(json.dumps(rep, indent=2) + "\n")
        (tmp / "report.md").write_text(markdown(rep))
        if extra is not None:
            plot_report(rep, extra, tmp)
        if out.exists():
            old = out.with_name(out.name + f".old.{os.getpid()}")
            out.rename(old)
            tmp.rename(out)
            shutil.rmtree(old)
        else:
            tmp.rename(out)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise

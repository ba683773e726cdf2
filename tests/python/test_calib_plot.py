"""odo-plot-umbmark (issue 4, item 4): 000 Fig. 3.4/6.5-style plots of UMBmark return errors.
Emax,syst it prints is 000 Eq. 3.4 computed here independently; bad input exits 1 and writes
nothing."""

from __future__ import annotations

import math
import os
import subprocess
from pathlib import Path

VENV_BIN = Path(os.environ["ODO_SOURCE_DIR"]) / ".venv" / "bin"
HEADER = "run,direction,x_abs_mm,y_abs_mm,theta_abs_deg,x_calc_mm,y_calc_mm,theta_calc_deg\n"


def returns(path: Path, cw: tuple[float, float], ccw: tuple[float, float]) -> Path:
    rows = [f"{k},cw,{cw[0] + k},{cw[1] - k},0,0,0,0" for k in (-1, 0, 1)]
    rows += [f"{k},ccw,{ccw[0] + k},{ccw[1]},0,0,0,0" for k in (-1, 0, 1)]
    path.write_text(HEADER + "\n".join(rows) + "\n")
    return path


def test_before_after_plot_is_written_and_reports_emax(tmp_path: Path) -> None:
    before = returns(tmp_path / "b.csv", (228.0, 209.0), (-51.0, 52.0))
    after = returns(tmp_path / "a.csv", (3.0, -4.0), (-6.0, 8.0))
    out = tmp_path / "u.png"
    r = subprocess.run([str(VENV_BIN / "odo-plot-umbmark"), "--before", str(before), "--after",
                        str(after), "--out", str(out)], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert f"before {math.hypot(228, 209):.1f} mm, after {math.hypot(-6, 8):.1f} mm" in r.stderr


def test_bad_returns_exit_1_and_write_nothing(tmp_path: Path) -> None:
    bad = tmp_path / "bad.csv"
    bad.write_text(HEADER + "1,cw,nan,0,0,0,0,0\n")
    out = tmp_path / "u.png"
    r = subprocess.run([str(VENV_BIN / "odo-plot-umbmark"), "--before", str(bad), "--out",
                        str(out)], capture_output=True, text=True, timeout=120)
    assert r.returncode == 1 and "bad.csv:2" in r.stderr
    assert not out.exists()

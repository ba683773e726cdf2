"""odo-import ticks-csv (issue 7 item 2) on the OptiOdom real runs (../shared/data/optiodom, MIT):
the log decodes with cantools to the CSV's ticks with 12-bit counter wraparound, the truth is in
the project's units, and odo-gap diagnoses the result."""

from __future__ import annotations

import json
import math
from pathlib import Path

import cantools
import numpy as np
import pytest
from gap_support import SRC, odo_gap, odo_import

DATA = SRC.parent / "shared" / "data" / "optiodom" / "square-230620202042"
ROBOT = SRC / "tools/python/odo_tools/gap/robots/optiodom.json"
pytestmark = pytest.mark.skipif(not DATA.is_dir(), reason="optiodom data not present")


@pytest.fixture(scope="module")
def imported(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("opti") / "real"
    runs = [str(DATA / f"run-{k:02d}.csv") for k in range(1, 7)]
    r = odo_import("ticks-csv", "--ticks", *runs, "--truth", *runs, "--columns",
                   "time,x,y,theta,right,left", "--directions", "cw,cw,cw,ccw,ccw,ccw",
                   "--robot", str(ROBOT), "--out", str(out))
    assert r.returncode == 0, r.stderr
    return out


def test_counts_decode_with_cantools_and_wrap_like_the_decoder(imported: Path) -> None:
    db = cantools.database.load_file(str(SRC / "can/odometry.dbc"))
    raw = np.loadtxt(DATA / "run-01.csv", delimiter=",")
    left = []
    for ln in (imported / "run-cw-01.log").read_text().splitlines():
        fid, data = ln.split()[2].split("#")
        left.append(db.decode_message(int(fid, 16), bytes.fromhex(data))["LeftCount"])
    left = np.array(left)
    assert left.size == raw.shape[0]
    expect = np.cumsum(np.concatenate([[0], raw[1:, 5]])).astype(np.int64) % 4096
    assert np.array_equal(left, expect)
    assert left.max() < 4096 and (np.diff(left) < -2000).any()   # it did wrap


def test_truth_in_mm_and_degrees(imported: Path) -> None:
    raw = np.loadtxt(DATA / "run-04.csv", delimiter=",")
    tr = np.loadtxt(imported / "run-ccw-01.truth.csv", delimiter=",", skiprows=1)
    assert tr[100, 1] == pytest.approx(raw[100, 1] * 1000.0, abs=1e-3)
    assert tr[100, 3] == pytest.approx(math.degrees(raw[100, 3]), abs=1e-5)


def test_optiodom_is_diagnosed(imported: Path, tmp_path: Path) -> None:
    r = odo_gap("diagnose", "--real", str(imported), "--robot", str(ROBOT), "--out",
                str(tmp_path / "rep"), "--quiet")
    assert r.returncode == 0, r.stderr
    rep = json.loads((tmp_path / "rep" / "report.json").read_text())
    assert rep["mode"] == "truth" and len(rep["heldout_runs"]) == 2
    assert rep["gap_before_mm"] > 1.0 and rep["shrink"] > 1.0 and rep["shrink_mm"] > 1.0
    # a real robot: the best catalog candidate leaves most of its gap unexplained (README)
    assert rep["verdict"]["effect"] == "unexplained"


def test_import_rejects_nan_and_names_the_line(tmp_path: Path) -> None:
    bad = tmp_path / "bad.csv"
    rows = (DATA / "run-01.csv").read_text().splitlines()
    rows[9] = "0.45,0,0,0,nan,3"
    bad.write_text("\n".join(rows) + "\n")
    r = odo_import("ticks-csv", "--ticks", str(bad), "--columns", "time,x,y,theta,right,left",
                   "--robot", str(ROBOT), "--out", str(tmp_path / "o"))
    assert r.returncode == 1 and "bad.csv:10:" in r.stderr
    assert not (tmp_path / "o").exists()

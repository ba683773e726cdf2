"""odo-gap diagnose (issue 7 item 1) on simulator runs whose effect the test knows and the tool does
not: 000 s. 4.6.2's Ed = 0.9985 (host_sim/scenarios/effect-ed.json). The diagnosis runs under an
audit hook that refuses every scenario file, so it provably works from recorded data alone."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import pytest
from gap_support import PY, SRC, env, odo_sim


@pytest.fixture(scope="module")
def report(tmp_path_factory: pytest.TempPathFactory) -> Path:
    tmp = tmp_path_factory.mktemp("diag")
    odo_sim("effect-ed.json", tmp / "real", runs=3)
    out = tmp / "report"
    code = (
        "import sys; from odo_tools.validation.blind import guard; "
        f"guard({str(SRC / 'host_sim' / 'scenarios')!r}); "
        "from odo_tools.gap.cli import main; "
        f"sys.exit(main(['diagnose', '--real', {str(tmp / 'real')!r}, '--robot', "
        f"{str(SRC / 'host_sim/robots/labmate.json')!r}, '--out', {str(out)!r}, '--quiet']))"
    )
    r = subprocess.run([PY, "-c", code], env=env(), capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    return out


def test_unequal_wheel_diameters_are_found_sized_and_removed(report: Path) -> None:
    rep = json.loads((report / "report.json").read_text())
    for k in ("verdict", "runner_up", "where", "gap_before", "gap_after_heldout", "shrink",
              "shrink_ci", "unidentifiable", "gap_definition", "gap_before_mm",
              "gap_after_heldout_mm", "shrink_mm"):
        assert k in rep
    v = rep["verdict"]
    assert v["effect"] == "ed"
    assert abs(v["params"]["ed.value"] - 0.9985) < 0.1 * 0.0015
    assert v["evidence"]["dbic_vs_nominal"] > 10
    assert rep["runner_up"]["margin_dbic"] > 0
    assert rep["shrink"] > 10 and rep["shrink_ci"][0] > 1
    assert rep["shrink_mm"] > 10 and rep["gap_after_heldout_mm"] < rep["gap_before_mm"]
    assert set(rep["heldout_runs"]).isdisjoint(rep["fit_runs"])
    assert {r.split("-")[1] for r in rep["heldout_runs"]} == {"cw", "ccw"}  # stratified
    assert any(u["what"] == "tire_compression" for u in rep["unidentifiable"])


def test_report_has_markdown_and_readable_plots(report: Path) -> None:
    md = (report / "report.md").read_text()
    assert "Verdict: **ed**" in md and "held-out" in md
    for png in ("ranking.png", "gap_along_path.png", "residuals.png"):
        assert (report / png).read_bytes()[:4] == b"\x89PNG"


def test_where_names_channel_and_segment(report: Path) -> None:
    rep = json.loads((report / "report.json").read_text())
    w = rep["where"][0]
    # an Ed curves straight legs: the heading and lateral channels while driving straight
    top = max(w["channels"], key=w["channels"].get)
    assert top in ("A.heading_rad", "A.lateral_mm")
    assert max(w["segments"], key=w["segments"].get) in ("straight", "acceleration")

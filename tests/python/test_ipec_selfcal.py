"""IPEC self-calibration (issue 5 item 4; 004 s. 5.1 and 5.2), run through `odo-ipec selfcal` and
`odo-ipec selfcal-link` on the SIL simulator with the effects injected by a scenario. The expected
values are the injected ones (the scenario), never the tool's output."""

from __future__ import annotations

import json
import os
import subprocess
from pathlib import Path

import pytest

BUILD = Path(os.environ["ODO_BUILD_DIR"])
TOOL = BUILD / "bin" / "odo-ipec"
ED, EB = 0.9985, 0.9911764705882353  # 000 s. 4.6.2 sizes (host_sim/scenarios/effect-ed/eb.json)
ALPHA, BETA, LINK = 0.7, -1.2, 1.5  # deg, deg, mm


def _scenario(tmp: Path, name: str, effects: dict) -> Path:
    p = tmp / name
    p.write_text(json.dumps({"description": name, "effects": effects}))
    return p


def _run(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([str(TOOL), *args], capture_output=True, text=True, timeout=300)


@pytest.fixture(scope="module")
def selfcal(tmp_path_factory: pytest.TempPathFactory) -> tuple[dict, Path]:
    tmp = tmp_path_factory.mktemp("selfcal")
    sc = _scenario(tmp, "edeb.json", {"ed": {"value": ED}, "eb": {"value": EB}})
    out = tmp / "cal.json"
    r = _run("selfcal", "--scenario", str(sc), "--out", str(out))
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout), out


def test_selfcal_recovers_ed_and_eb_of_both_trucks(selfcal: tuple[dict, Path]) -> None:
    """Smooth floor, IPEC on, two UMBmark squares each way: Ed within 2e-4 (13 % of its error)
    and Eb within 5e-4 (6 %) of the injected values, on both trucks."""
    res, _ = selfcal
    for t in res["truck"]:
        assert t["ed"] == pytest.approx(ED, abs=2e-4)
        assert t["eb"] == pytest.approx(EB, abs=5e-4)


def test_selfcal_params_need_clearly_less_correction(selfcal: tuple[dict, Path]) -> None:
    """The same runs with the estimated block: the systematic (one-sided) part of IPEC's
    corrections shrinks at least 5-fold, and the total correction work shrinks too."""
    res, _ = selfcal
    for t in res["truck"]:
        assert t["one_sided_corr_deg_before"] > 20.0  # the effect is really there
        assert t["one_sided_corr_deg_after"] * 5.0 < t["one_sided_corr_deg_before"]
        assert t["abs_corr_deg_after"] < 0.8 * t["abs_corr_deg_before"]


def test_selfcal_writes_a_parameter_block_others_read(
    selfcal: tuple[dict, Path], tmp_path: Path
) -> None:
    """The output has the `odo-params show` shape, holds the estimates, and odo-sim boots on it."""
    res, path = selfcal
    block = json.loads(path.read_text())
    assert block["status"] == "ok" and block["magic"] == "ODOP"
    for t, b in zip(res["truck"], block["truck"], strict=True):
        assert b["ed_q30"] / 2**30 == pytest.approx(t["ed"], abs=1e-6)
        assert b["eb_q30"] / 2**30 == pytest.approx(t["eb"], abs=1e-6)
    sim = BUILD / "bin" / "odo-sim"
    none = Path(os.environ["ODO_SOURCE_DIR"]) / "host_sim" / "scenarios" / "none.json"
    args = ["--experiment", "umbmark", "--vehicle", "clapper", "--scenario", str(none),
            "--out", str(tmp_path / "sim"), "--runs", "1", "--params", str(path), "--quiet"]
    r = subprocess.run([str(sim), *args], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr


@pytest.fixture(scope="module")
def selfcal_link(tmp_path_factory: pytest.TempPathFactory) -> dict:
    tmp = tmp_path_factory.mktemp("selfcal_link")
    sc = _scenario(tmp, "bias.json", {"rotary_bias": {"alpha_deg": ALPHA, "beta_deg": BETA},
                                       "link_bias": {"const_mm": LINK}})
    r = _run("selfcal-link", "--scenario", str(sc), "--out", str(tmp / "link.json"))
    assert r.returncode == 0, r.stderr
    res = json.loads(r.stdout)
    res["block"] = json.loads((tmp / "link.json").read_text())
    return res


def test_selfcal_link_recovers_the_injected_biases(selfcal_link: dict) -> None:
    """Rotary biases within 0.05 deg (a seventh of a 10-bit step); the link-length bias within
    0.15 mm (the linear encoder's 0.1 mm truncation is part of what the firmware must remove)."""
    r = selfcal_link
    assert r["alpha_bias_deg"] == pytest.approx(ALPHA, abs=0.05)
    assert r["beta_bias_deg"] == pytest.approx(BETA, abs=0.05)
    assert r["length_bias_mm"] == pytest.approx(LINK, abs=0.15)
    link = r["block"]["link"]
    assert link["alpha_bias_bam"] * 360.0 / 2**32 == pytest.approx(r["alpha_bias_deg"], abs=1e-4)
    assert link["length_bias_nm"] / 1e6 == pytest.approx(r["length_bias_mm"], abs=1e-4)


def test_selfcal_link_removes_the_curved_path_and_the_turn_drift(selfcal_link: dict) -> None:
    """002 s. 5.2 symptoms before and after: the far-mark heading error of a straight 18 m run
    (the curve IPEC cannot see) and the UMBmark return heading errors."""
    r = selfcal_link
    assert abs(r["far_mark_before"]["etheta_deg"]) > 20.0
    assert abs(r["far_mark_after"]["etheta_deg"]) < 2.0
    for d in ("cw", "ccw"):
        assert abs(r["umbmark_etheta_before_deg"][d]) > 20.0
        assert abs(r["umbmark_etheta_after_deg"][d]) < 1.5


def test_selfcal_rejects_bad_invocations(tmp_path: Path) -> None:
    r = _run("selfcal", "--out", str(tmp_path / "x.json"))
    assert r.returncode == 2 and "--scenario" in r.stderr
    bad = tmp_path / "bad.json"
    bad.write_text("{")
    r = _run("selfcal", "--scenario", str(bad), "--out", str(tmp_path / "x.json"))
    assert r.returncode == 1 and "bad.json" in r.stderr
    assert not (tmp_path / "x.json").exists()

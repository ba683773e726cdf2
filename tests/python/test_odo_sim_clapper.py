"""odo-sim --vehicle clapper: the CLAPPER (004 s. 2) drives the papers' experiments with IPEC off.

The navigation computer drives both trucks from the firmware's poses: B follows A's path l behind
at the nominal 1000 mm (free within the linkage's [900, 1100] mm stops, where the world clamps),
turns on the spot are rigid turns about the vehicle's midpoint, and floor bumps lie under both
trucks' wheels on their side (004 s. 6.1)."""

from __future__ import annotations

import csv
import json
import math
import os
import subprocess
from pathlib import Path

import pytest

SRC = Path(os.environ["ODO_SOURCE_DIR"])
SIM = Path(os.environ["ODO_BUILD_DIR"]) / "bin" / "odo-sim"
SCEN = SRC / "host_sim" / "scenarios"
L_NOM = 1000.0


def clapper(out: Path, experiment: str, *args: str) -> dict:
    r = subprocess.run([str(SIM), "--quiet", "--out", str(out), "--experiment", experiment,
                        "--vehicle", "clapper", "--scenario", str(SCEN / "none.json"),
                        "--runs", "1", "--ipec", "off", *args],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    return json.loads((out / "summary.json").read_text())


def truth(out: Path) -> dict[str, list[dict[str, str]]]:
    return {p.name: list(csv.DictReader(p.open())) for p in sorted(out.glob("run-*.truth.csv"))}


def events(rows: list[dict[str, str]]) -> list[str]:
    return [e for r in rows for e in r["events"].split("|") if e]


@pytest.mark.parametrize("experiment", ["umbmark", "umbmark-ext", "straight-36m", "rect-7x4"])
def test_truck_b_follows_a_at_the_nominal_link_length(tmp_path: Path, experiment: str) -> None:
    s = clapper(tmp_path / "o", experiment)
    assert len(s["runs"]) == (1 if experiment == "straight-36m" else 2)
    runs = truth(tmp_path / "o")
    assert len(runs) == len(s["runs"])
    for name, rows in runs.items():
        assert len(rows) > 100, name
        for r in rows:
            # Well inside the stops, so the world never had to clamp the linkage.
            assert abs(float(r["l_mm"]) - L_NOM) < 60.0, (name, r["t_s"], r["l_mm"])
            ax, ay, bx, by = (float(r[k]) for k in ("a_x_mm", "a_y_mm", "b_x_mm", "b_y_mm"))
            assert math.hypot(ax - bx, ay - by) == pytest.approx(float(r["l_mm"]), abs=0.01)
        if experiment == "rect-7x4":
            continue  # it ends with B still on the last 0.5 m corner arc
        # B ends behind A: the link points (within the trucks' heading error) along A's heading.
        last = rows[-1]
        heading = math.radians(float(last["a_theta_deg"]))
        dx = float(last["a_x_mm"]) - float(last["b_x_mm"])
        dy = float(last["a_y_mm"]) - float(last["b_y_mm"])
        assert dx * math.cos(heading) + dy * math.sin(heading) > 0.9 * L_NOM, name


@pytest.mark.parametrize("experiment,bumps", [("umbmark", []), ("straight-36m", ["--bumps", "0"]),
                                              ("rect-7x4", ["--bumps", "0"])])
def test_returns_are_small_without_effects(tmp_path: Path, experiment: str,
                                          bumps: list[str]) -> None:
    s = clapper(tmp_path / "o", experiment, *bumps)
    for run in s["runs"]:
        assert abs(run["etheta_deg"]) < 0.5, run
        assert math.hypot(run["ex_mm"], run["ey_mm"]) < 50.0, run
    assert not any(events(rows) for rows in truth(tmp_path / "o").values())


def test_straight_36m_bumps_under_both_trucks_turn_the_return_by_degrees(tmp_path: Path) -> None:
    """004 s. 6.1 (no IPEC, ten bumps under the right wheels on the return leg): about 0.6 deg per
    bump with the exact bump model (the paper: -7.7 deg average, -6 deg of it from the bumps).
    Truck A's heading only sees its own ten bumps; B meets every bump but the first, which lies
    between the trucks when the return leg starts."""
    s = clapper(tmp_path / "o", "straight-36m")
    (run,) = s["runs"]
    assert 3.0 < abs(run["etheta_deg"]) < 15.0, run
    assert abs(run["etheta_deg"]) == pytest.approx(10 * 0.5922, abs=0.3)
    (rows,) = truth(tmp_path / "o").values()
    ev = events(rows)
    a = [e for e in ev if e.startswith("bump:A:right:h10.000")]
    b = [e for e in ev if e.startswith("bump:B:right:h10.000")]
    assert len(a) == 10 and len(b) == 9 and len(ev) == 19, ev
    # Under both trucks' right wheels at the same floor spots, on the return leg; B, leading
    # backward, meets each spot before A does.
    hits = [(float(r["t_s"]), e[5], float(e.split(":x")[1].split(":")[0]))
            for r in rows for e in r["events"].split("|") if e]
    assert all(0.0 < x < 18000.0 for _t, _k, x in hits)
    for tb, k, xb in hits:
        if k == "B":
            ta, xa = min(((t, x) for t, kk, x in hits if kk == "A"), key=lambda h: abs(h[1] - xb))
            assert abs(xa - xb) < 30.0 and tb < ta


def test_umbmark_ext_bumps_reach_both_trucks_on_leg_1(tmp_path: Path) -> None:
    clapper(tmp_path / "o", "umbmark-ext")
    for name, rows in truth(tmp_path / "o").items():
        inside = "right" if "-cw-" in name else "left"
        ev = events(rows)
        assert sum(e.startswith(f"bump:A:{inside}:") for e in ev) == 10, name
        # B stops 1 m short of the corner: the bumps of leg 1's last metre stay between the trucks.
        assert sum(e.startswith(f"bump:B:{inside}:") for e in ev) == 7, name
        assert all(0.0 < float(e.split(":x")[1].split(":")[0]) < 4000.0 for e in ev)

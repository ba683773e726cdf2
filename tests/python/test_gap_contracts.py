"""One contract, one source (issue 17): the diagnosis reads what each effect applies to from the C
effects catalog, frame IDs from can/odometry.dbc, and checks its ctypes layouts against the sizes
libodosim exports; its model of the new catalog effect `scrub` is the simulator's truth."""

from __future__ import annotations

import ctypes as C
import json
import re
import subprocess
from pathlib import Path

import numpy as np
import pytest
from gap_support import BUILD, SRC, env


@pytest.fixture(autouse=True)
def _env(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("ODO_BUILD_DIR", str(BUILD))
    monkeypatch.setenv("ODO_SOURCE_DIR", str(SRC))


def test_hypotheses_follow_the_catalogs_evidence_per_mode_and_vehicle() -> None:
    from odo_tools.gap import catalog, hypotheses

    doc = json.loads(
        subprocess.run(
            [str(BUILD / "bin/odo-sim"), "--list-effects", "--json"],
            capture_output=True, text=True, check=True, env=env(),
        ).stdout
    )  # fmt: skip
    for e in doc["effects"]:
        assert set(e["vehicles"]) <= {"labmate", "clapper", "set"} and e["vehicles"]
        assert set(e["evidence"]) == {"truth", "returns", "linkage"}
        for ev in e["evidence"].values():
            assert ev["seen"] in ("yes", "weak", "no")
            assert (ev["why"] is None) == (ev["seen"] == "yes"), e["name"]
    for vehicle in ("labmate", "clapper", "set"):
        for mode in ("truth", "returns", "linkage"):
            want = {
                e["name"]
                for e in doc["effects"]
                if vehicle in e["vehicles"]
                and e["evidence"][mode]["seen"] != "no"
                and (mode != "linkage" or vehicle != "labmate")
            }
            got = {h.families[0] for h in hypotheses.singles(mode, vehicle)}
            assert got == want, (vehicle, mode)
            assert set(catalog.not_identifiable(mode, vehicle)).isdisjoint(
                catalog.identifiable(mode, vehicle)
            )
    # the ones the issue names: count loss is a truth-mode hypothesis, scrub everywhere
    assert "count_loss" in catalog.identifiable("truth", "labmate")
    assert "count_loss" not in catalog.hypotheses("returns", "labmate")
    assert "scrub" in catalog.identifiable("returns", "labmate")
    assert "link_bias" not in catalog.hypotheses("truth", "set")


def test_ctypes_layouts_match_the_sizes_libodosim_exports() -> None:
    from odo_tools.gap import simlib

    so = simlib.lib()  # refuses a library whose layouts differ
    assert simlib.check_layouts(so) == []
    assert so.odosim_sizeof(b"no_such_type") == 0

    class Shorter(C.Structure):  # a binding that forgot a field of odosim_event_t
        _fields_ = [f for f in simlib.Event._fields_ if f[0] != "at_distance_mm"]

    saved = simlib.LAYOUTS["odosim_event_t"]
    try:
        simlib.LAYOUTS["odosim_event_t"] = Shorter
        bad = simlib.check_layouts(so)
    finally:
        simlib.LAYOUTS["odosim_event_t"] = saved
    assert len(bad) == 1 and "odosim_event_t" in bad[0]


def test_python_takes_frame_ids_from_the_dbc() -> None:
    """No CAN ID is written into the diagnosis or the blind check; they come from the DBC."""
    import cantools
    from odo_tools.gap import io

    db = cantools.database.load_file(str(SRC / "can/odometry.dbc"))
    ids = {m.frame_id for m in db.messages}
    assert set(io.ID_WHEEL) == {db.get_message_by_name(f"WHEEL_COUNTS_{t}").frame_id for t in "AB"}
    assert io.ID_ROTARY == db.get_message_by_name("LINK_ROTARY").frame_id
    assert io.FRAME_LEN[io.ID_LINEAR] == db.get_message_by_name("LINK_LINEAR").length
    root = SRC / "tools/python/odo_tools"
    hits = []
    for p in [*(root / "gap").glob("*.py"), *(root / "validation").rglob("*.py")]:
        if p.parent.name == "indep":  # the independent world keeps its own copy: tested below
            continue
        text = p.read_text()
        if p.name == "io.py":  # read_log is being moved to python-can (issue 14)
            text = re.sub(r"def read_log\(.*?\n(?=def |\Z)", "", text, flags=re.S)
        for m in re.finditer(r"\b0x([0-9A-Fa-f]{3})\b", text):
            if int(m.group(1), 16) in ids:
                hits.append(f"{p.name}: {m.group(0)}")
    assert not hits, hits
    # the independent world writes its frames without our code (its independence): its IDs are a
    # copy of the DBC's, tested against it
    from odo_tools.validation.indep import simulate as indep_sim

    by_name = {m.name: m.frame_id for m in db.messages}
    assert (indep_sim.ID_A, indep_sim.ID_B, indep_sim.ID_ROT, indep_sim.ID_LIN) == tuple(
        by_name[n] for n in ("WHEEL_COUNTS_A", "WHEEL_COUNTS_B", "LINK_ROTARY", "LINK_LINEAR"))


def test_scrub_in_the_model_is_the_simulators_truth(tmp_path: Path) -> None:
    """Catalog scrub (k = 0.1) on rect-7x4's 0.5 m arcs (no bumps): driven by the recorded
    counts, the model with scrub.k = 0.1 follows the simulator's true heading to the counts'
    quantisation, and without it is off by k (1 - b/2R) of every arc (about 6 deg a corner)."""
    from odo_tools.gap.io import discover, read_robot
    from odo_tools.gap.model import dead_reckon, prepare

    sc = tmp_path / "scrub.json"
    sc.write_text('{"effects": {"scrub": {"k": 0.1}}}')
    out = tmp_path / "real"
    subprocess.run(
        [str(BUILD / "bin/odo-sim"), "--quiet", "--experiment", "rect-7x4", "--vehicle",
         "labmate", "--scenario", str(sc), "--runs", "1", "--bumps", "0", "--out", str(out)],
        check=True, timeout=300,
    )  # fmt: skip
    robot = read_robot(SRC / "host_sim/robots/labmate.json")
    run = next(r for r in discover(out, robot) if r.name == "run-ccw-01")
    pr = prepare(run, robot)
    th_true = np.interp(pr.t, run.truth.t_s, run.truth.pose[:, 0, 2])
    with_k = dead_reckon(pr, {"scrub.k": 0.1})[:, 2]
    nominal = dead_reckon(pr, {})[:, 2]
    assert np.max(np.abs(with_k - th_true)) < np.radians(0.05)
    assert np.degrees(np.max(np.abs(nominal - th_true))) > 15.0

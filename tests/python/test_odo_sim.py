"""odo-sim, the software-in-the-loop simulator CLI (host_sim issue).

The papers' experiments, determinism, the log contracts, and bad input (clear message, non-zero
exit, nothing left behind)."""

from __future__ import annotations

import csv
import itertools
import json
import os
import subprocess
from pathlib import Path

import cantools
import pytest

SRC = Path(os.environ["ODO_SOURCE_DIR"])
SIM = Path(os.environ["ODO_BUILD_DIR"]) / "bin" / "odo-sim"
SCEN = SRC / "host_sim" / "scenarios"


def sim(out: Path, *args: str, check: bool = True) -> subprocess.CompletedProcess[str]:
    r = subprocess.run([str(SIM), "--quiet", "--out", str(out), *args], capture_output=True,
                       text=True, timeout=600)
    if check:
        assert r.returncode == 0, r.stderr
    return r


@pytest.fixture(scope="module")
def set_sim_umbmark(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("umb") / "out"
    sim(out, "--experiment", "umbmark", "--vehicle", "labmate", "--scenario",
        str(SCEN / "set-sim.json"), "--runs", "5", "--seed", "7")
    return out


def test_set_sim_robot_shows_distinct_cw_and_ccw_clusters(set_sim_umbmark: Path) -> None:
    """000 s. 4.6.2 robot (b 337 vs 340 mm, Ed 0.9985) in UMBmark: two clusters, and Emax,syst in
    the hundreds of mm like the uncalibrated runs of 000 Table III (232-423 mm)."""
    s = json.loads((set_sim_umbmark / "summary.json").read_text())
    cw, ccw = s["cg_cw_mm"], s["cg_ccw_mm"]
    separation = ((cw[0] - ccw[0]) ** 2 + (cw[1] - ccw[1]) ** 2) ** 0.5
    assert 150.0 < s["emax_syst_mm"] < 600.0
    assert separation > 10 * s["sigma_mm"]
    assert len(s["runs"]) == 10
    assert s["emax_syst_mm"] > 3 * s["sem_mm"]  # 000 s. 6.3: calibration is worthwhile


def test_returns_csv_follows_the_contract(set_sim_umbmark: Path) -> None:
    rows = list(csv.DictReader((set_sim_umbmark / "returns.csv").open()))
    assert list(rows[0]) == ["run", "direction", "x_abs_mm", "y_abs_mm", "theta_abs_deg",
                             "x_calc_mm", "y_calc_mm", "theta_calc_deg"]
    assert [r["direction"] for r in rows].count("cw") == 5
    summary = json.loads((set_sim_umbmark / "summary.json").read_text())
    for row, run in zip(rows, summary["runs"], strict=True):  # 000 Eq. 3.1: absolute - calculated
        ex = float(row["x_abs_mm"]) - float(row["x_calc_mm"])
        assert ex == pytest.approx(run["ex_mm"], abs=2e-3)


def test_sensor_log_decodes_with_the_dbc_and_counts_sequences(set_sim_umbmark: Path) -> None:
    db = cantools.database.load_file(str(SRC / "can" / "odometry.dbc"))
    lines = (set_sim_umbmark / "run-cw-01.log").read_text().splitlines()
    assert len(lines) > 2000
    seqs = []
    for line in lines:
        _stamp, _iface, frame = line.split()
        can_id, data = frame.split("#")
        msg = db.get_message_by_frame_id(int(can_id, 16))
        assert msg.name == "WHEEL_COUNTS_A"
        seqs.append(msg.decode(bytes.fromhex(data))["Seq"])
    assert all((b - a) % 256 == 1 for a, b in itertools.pairwise(seqs))


def test_same_seed_gives_byte_identical_outputs(tmp_path: Path) -> None:
    args = ["--experiment", "umbmark-ext", "--vehicle", "labmate", "--scenario",
            str(SCEN / "set-sim.json"), "--runs", "1", "--seed", "11"]
    sim(tmp_path / "a", *args)
    sim(tmp_path / "b", *args)
    names = sorted(p.name for p in (tmp_path / "a").iterdir())
    assert names == sorted(p.name for p in (tmp_path / "b").iterdir())
    for n in names:
        assert (tmp_path / "a" / n).read_bytes() == (tmp_path / "b" / n).read_bytes(), n
    sim(tmp_path / "c", *args[:-1], "12")  # roughness draws differ with the seed
    assert (tmp_path / "a" / "run-cw-01.truth.csv").read_bytes() != \
        (tmp_path / "c" / "run-cw-01.truth.csv").read_bytes()


def test_umbmark_ext_puts_ten_bumps_under_the_inside_wheel_on_leg_1(tmp_path: Path) -> None:
    sim(tmp_path / "o", "--experiment", "umbmark-ext", "--vehicle", "labmate", "--scenario",
        str(SCEN / "none.json"), "--runs", "1")
    for direction, inside in (("cw", "right"), ("ccw", "left")):
        rows = list(csv.DictReader((tmp_path / "o" / f"run-{direction}-01.truth.csv").open()))
        events = [e for r in rows for e in r["events"].split("|") if e]
        assert len(events) == 10
        assert all(e.startswith(f"bump:A:{inside}:h10.000") for e in events)
        xs = [float(e.split(":x")[1].split(":")[0]) for e in events]
        assert all(0 < x < 4000 for x in xs)  # leg 1 runs along +x


def test_bumps_make_orientation_errors_only_with_bumps(tmp_path: Path) -> None:
    """Without systematic errors, UMBmark returns almost exactly; ten 10 mm bumps under the inside
    wheel leave an orientation error of several degrees (000 s. 3.4, 0.44-0.6 deg per bump)."""
    common = ["--vehicle", "labmate", "--scenario", str(SCEN / "none.json"), "--runs", "1"]
    sim(tmp_path / "plain", "--experiment", "umbmark", *common)
    sim(tmp_path / "ext", "--experiment", "umbmark-ext", *common)
    plain = json.loads((tmp_path / "plain" / "summary.json").read_text())
    ext = json.loads((tmp_path / "ext" / "summary.json").read_text())
    assert plain["emax_syst_mm"] < 20.0
    assert plain["avg_abs_theta_err_deg"] < 0.2
    assert 3.0 < ext["avg_abs_theta_err_deg"] < 8.0


@pytest.mark.parametrize("experiment,vehicle", [
    ("straight-36m", "labmate"), ("rect-7x4", "labmate"), ("umbmark", "set")])
def test_other_experiments_run(tmp_path: Path, experiment: str, vehicle: str) -> None:
    sim(tmp_path / "o", "--experiment", experiment, "--vehicle", vehicle, "--scenario",
        str(SCEN / "none.json"), "--runs", "1")
    s = json.loads((tmp_path / "o" / "summary.json").read_text())
    assert s["experiment"] == experiment
    assert len(s["runs"]) == (1 if experiment == "straight-36m" else 2)


def _nothing_left(parent: Path) -> bool:
    return not any(p.name.startswith("out") for p in parent.iterdir())


@pytest.mark.parametrize("args,code,words", [
    (["--experiment", "figure-8", "--vehicle", "labmate"], 2, "unknown experiment"),
    (["--experiment", "umbmark", "--vehicle", "tank"], 2, "unknown vehicle"),
    (["--experiment", "umbmark", "--vehicle", "labmate", "--runs", "0"], 2, "--runs"),
    (["--experiment", "umbmark", "--vehicle", "labmate", "--ipec", "maybe"], 2, "--ipec"),
])
def test_bad_arguments_fail_clearly(tmp_path: Path, args: list[str], code: int, words: str) -> None:
    r = sim(tmp_path / "out", *args, "--scenario", str(SCEN / "none.json"), check=False)
    assert r.returncode == code and words in r.stderr
    assert _nothing_left(tmp_path)


def test_bad_scenario_names_file_and_problem_and_leaves_nothing(tmp_path: Path) -> None:
    bad = tmp_path / "bad.json"
    bad.write_text('{"effects": {"ed": {"value": 7.0}}}')
    r = sim(tmp_path / "out", "--experiment", "umbmark", "--vehicle", "labmate", "--scenario",
            str(bad), check=False)
    assert r.returncode == 1 and "bad.json" in r.stderr and "ed" in r.stderr
    bad.write_text('{"effects": {')
    r = sim(tmp_path / "out", "--experiment", "umbmark", "--vehicle", "labmate", "--scenario",
            str(bad), check=False)
    assert r.returncode == 1 and "bad.json" in r.stderr
    assert _nothing_left(tmp_path)


def test_unwritable_output_and_foreign_folder_are_refused(tmp_path: Path) -> None:
    args = ["--experiment", "umbmark", "--vehicle", "labmate", "--scenario",
            str(SCEN / "none.json"), "--runs", "1"]
    (tmp_path / "plain").write_text("a file, not a folder")
    r = sim(tmp_path / "plain" / "out", *args, check=False)
    assert r.returncode == 1 and "plain is not a folder" in r.stderr
    foreign = tmp_path / "out"
    foreign.mkdir()
    (foreign / "precious.txt").write_text("keep me")
    r = sim(foreign, *args, check=False)
    assert r.returncode == 1 and "non-empty folder odo-sim did not write" in r.stderr
    assert (foreign / "precious.txt").read_text() == "keep me"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out", "plain"]

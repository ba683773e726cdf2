"""odo-gap diagnose on bad input (issue 7): a clear error naming the file (and line), a non-zero
exit, and no partial report."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
from gap_support import SRC, odo_gap, odo_sim

LABMATE = str(SRC / "host_sim/robots/labmate.json")


@pytest.fixture(scope="module")
def good(tmp_path_factory: pytest.TempPathFactory) -> Path:
    d = tmp_path_factory.mktemp("good") / "real"
    odo_sim("effect-ed.json", d, runs=1)
    return d


def copy(good: Path, tmp: Path) -> Path:
    d = tmp / "real"
    shutil.copytree(good, d)
    return d


def fails(real: Path, tmp: Path, *expect: str, robot: str = LABMATE, extra=()) -> None:
    out = tmp / "report"
    r = odo_gap("diagnose", "--real", str(real), "--robot", robot, "--out", str(out), "--quiet",
                *extra)
    assert r.returncode != 0, r.stderr
    for e in expect:
        assert e in r.stderr, (e, r.stderr)
    assert not out.exists() and not list(tmp.glob("*report.tmp*")), "partial report left"


def test_missing_folder(tmp_path: Path) -> None:
    fails(tmp_path / "nope", tmp_path, "nope", "not a folder")


def test_unreadable_log(good: Path, tmp_path: Path) -> None:
    d = copy(good, tmp_path)
    (d / "run-cw-01.log").write_bytes(b"\xff\xfe\x00garbage\n")
    fails(d, tmp_path, "run-cw-01.log")


def test_log_line_that_is_not_candump(good: Path, tmp_path: Path) -> None:
    d = copy(good, tmp_path)
    p = d / "run-ccw-01.log"
    lines = p.read_text().splitlines()
    lines[6] = "this is not a frame"
    p.write_text("\n".join(lines) + "\n")
    fails(d, tmp_path, "run-ccw-01.log:7:", "candump")


def test_log_without_wheel_counts(good: Path, tmp_path: Path) -> None:
    d = copy(good, tmp_path)
    p = d / "run-cw-01.log"
    p.write_text("".join(ln.replace(" 110#", " 180#") + "\n" for ln in p.read_text().splitlines()))
    fails(d, tmp_path, "run-cw-01.log", "WHEEL_COUNTS_A")


@pytest.mark.parametrize("what,expect", [("nan", "non-finite"), ("back", "does not increase"),
                                         ("gap", "gap of")])
def test_bad_truth(good: Path, tmp_path: Path, what: str, expect: str) -> None:
    d = copy(good, tmp_path)
    p = d / "run-ccw-01.truth.csv"
    lines = p.read_text().splitlines()
    k = 500
    if what == "nan":
        f = lines[k].split(",")
        f[2] = "nan"
        lines[k] = ",".join(f)
    elif what == "back":
        lines[k], lines[k + 1] = lines[k + 1], lines[k]
    else:
        del lines[k: k + 30]
    p.write_text("\n".join(lines) + "\n")
    line = k + 1 if what != "back" else k + 2
    fails(d, tmp_path, f"run-ccw-01.truth.csv:{line}:", expect)


def test_robot_that_does_not_match_the_logs(good: Path, tmp_path: Path) -> None:
    clapper = str(SRC / "host_sim/robots/clapper.json")
    fails(good, tmp_path, "run-ccw-01.log", "WHEEL_COUNTS_B", robot=clapper)
    r = json.loads(Path(LABMATE).read_text())
    r["tick_ms"] = 50
    rp = tmp_path / "slow.json"
    rp.write_text(json.dumps(r))
    fails(good, tmp_path, "run-ccw-01.log:1:", "tick_ms 50", robot=str(rp))


def test_mode_without_its_frames(good: Path, tmp_path: Path) -> None:
    fails(good, tmp_path, "mode linkage needs", extra=("--mode", "linkage"))
    d = copy(good, tmp_path)
    (d / "returns.csv").unlink()
    fails(d, tmp_path, "mode returns needs", extra=("--mode", "returns"))


@pytest.mark.parametrize("value", ["1", "1,0,2", "0,0.02", "-1,0.02", "1,nan", "a,b"])
def test_bad_return_accuracy(good: Path, tmp_path: Path, value: str) -> None:
    fails(good, tmp_path, "--return-accuracy", extra=("--mode", "returns", "--return-accuracy",
                                                      value))


@pytest.mark.parametrize("rng", [[1100.0, 1200.0], [900.0], "900,1100", [900.0, "x"]])
def test_bad_linkage_range(good: Path, tmp_path: Path, rng) -> None:
    r = json.loads((SRC / "host_sim/robots/clapper.json").read_text())
    r["linkage"]["range_mm"] = rng
    rp = tmp_path / "clapper-range.json"
    rp.write_text(json.dumps(r))
    fails(good, tmp_path, "clapper-range.json", "linkage.range_mm", robot=str(rp))


@pytest.mark.parametrize("extra,expect", [(("--seed", "-1"), "--seed must be 0 or more, got -1"),
                                          (("--holdout", "1"), "--holdout must be in [0, 1)"),
                                          (("--jobs", "0"), "--jobs must be at least 1, got 0")])
def test_bad_option_value_is_one_line_exit_1(good: Path, tmp_path: Path, extra, expect) -> None:
    out = tmp_path / "report"
    r = odo_gap("diagnose", "--real", str(good), "--robot", LABMATE, "--out", str(out), "--quiet",
                *extra)
    assert r.returncode == 1 and r.stderr.count("\n") == 1 and expect in r.stderr, r.stderr
    assert not out.exists()


@pytest.mark.parametrize("extra,expect", [(("--cases", "0"), "--cases must be at least 1, got 0"),
                                          (("--seed", "-1"), "--seed must be 0 or more, got -1"),
                                          (("--workers", "0"), "--workers must be at least 1")])
def test_blind_bad_option_value_is_one_line_exit_1(tmp_path: Path, extra, expect) -> None:
    out = tmp_path / "blind"
    r = odo_gap("blind", "--out", str(out), "--quiet", *extra)
    assert r.returncode == 1 and r.stderr.count("\n") == 1 and expect in r.stderr, r.stderr
    assert not out.exists() and not list(tmp_path.iterdir())


def test_a_refused_report_folder_is_refused_before_any_fit(good: Path, tmp_path: Path) -> None:
    """A user's folder or the input itself as OUT: one line, exit 1, before any fitting (the
    refusal used to come after the whole diagnosis, its progress printed first)."""
    out = tmp_path / "mine"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    for target in (out, good):
        r = odo_gap("diagnose", "--real", str(good), "--robot", LABMATE, "--out", str(target))
        assert r.returncode == 1 and r.stderr.count("\n") == 1, r.stderr
        assert "fitting" not in r.stderr
    assert sorted(p.name for p in out.iterdir()) == ["notes.txt"]


def test_report_folder_rule(good: Path, tmp_path: Path) -> None:
    """The output rule (odo_tools/outpath.py): a user's folder is refused and kept; an empty one
    is filled; a previous report is replaced file by file (its manifest), and the user's own
    files in it stay."""
    out = tmp_path / "report"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    args = ("diagnose", "--real", str(good), "--robot", LABMATE, "--out", str(out), "--quiet")
    r = odo_gap(*args)
    assert r.returncode == 1 and "odo-gap did not write" in r.stderr and r.stderr.count("\n") == 1
    assert sorted(p.name for p in out.iterdir()) == ["notes.txt"]
    assert not list(tmp_path.glob("*report.tmp*"))
    (out / "notes.txt").unlink()
    r = odo_gap(*args)  # empty folder: filled
    assert r.returncode == 0, r.stderr
    manifest = (out / ".odo-manifest").read_text().splitlines()
    assert manifest[:2] == ["odo-out-manifest 1", "tool odo-gap"]
    assert "report.json" in manifest and "report.md" in manifest
    assert sorted(manifest[2:]) == sorted(p.name for p in out.iterdir() if p.name[0] != ".")
    (out / "notes.txt").write_text("mine")
    (out / "mine").mkdir()
    (out / "mine" / "plot.png").write_bytes(b"x")
    r = odo_gap(*args)  # a previous report: its files replaced, the user's kept
    assert r.returncode == 0, r.stderr
    assert (out / "notes.txt").read_text() == "mine" and (out / "mine" / "plot.png").exists()
    assert json.loads((out / "report.json").read_text())["verdict"]
    assert not list(tmp_path.glob("*report.tmp*"))
    f = tmp_path / "afile"
    f.write_text("mine")
    r = odo_gap("diagnose", "--real", str(good), "--robot", LABMATE, "--out", str(f), "--quiet")
    assert r.returncode == 1 and "not a folder" in r.stderr and f.read_text() == "mine"
    # --force writes into a user's folder: same-named files replaced, nothing removed
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_text("mine")
    (mine / "report.md").write_text("old")
    r = odo_gap("diagnose", "--real", str(good), "--robot", LABMATE, "--out", str(mine),
                "--quiet", "--force")
    assert r.returncode == 0, r.stderr
    assert (mine / "notes.txt").read_text() == "mine" and (mine / "report.md").read_text() != "old"
    # an output inside an input folder is refused before anything is written
    r = odo_gap("diagnose", "--real", str(good), "--robot", LABMATE, "--out", str(good / "rep"),
                "--quiet")
    assert r.returncode == 1 and r.stderr.count("\n") == 1 and not (good / "rep").exists()

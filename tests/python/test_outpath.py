"""The Python output rule (odo_tools/outpath.py, issue 16 item 2), the Python CLIs' bad-input
classes (item 3: one line naming file and line, exit 1, no traceback, nothing written) and
hypothesis property tests over the importers and readers (only the tools' own error types).

Special files are a FIFO or a symlink this file makes in its own temp folder, never a /dev node."""

from __future__ import annotations

import os
import signal
import stat
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from odo_tools import importer
from odo_tools.gap import io as gap_io
from odo_tools.gap.errors import GapInputError
from odo_tools.outpath import (
    MANIFEST,
    Inputs,
    OutDir,
    OutputError,
    check_dir,
    out_file,
    read_manifest,
)

BUILD = Path(os.environ["ODO_BUILD_DIR"])
SRC = Path(os.environ["ODO_SOURCE_DIR"])
VENV = SRC / ".venv" / "bin"
OPTI = SRC / "tools" / "python" / "odo_tools" / "gap" / "robots" / "optiodom.json"
SQUARE = SRC.parent / "shared" / "data" / "optiodom" / "square-230620202042"
if not SQUARE.is_dir():
    SQUARE = Path("/work/shared/data/optiodom/square-230620202042")
COLS = "time,x,y,theta,right,left"


def temps(folder: Path) -> list[str]:
    return [p.name for p in folder.rglob("*") if ".tmp" in p.name]


# --- files -------------------------------------------------------------------------------------


def test_file_parents_created_and_replaced_whole(tmp_path: Path) -> None:
    p = tmp_path / "a" / "b" / "c.json"
    with out_file(p) as f:
        f.write("new\n")
    assert p.read_text() == "new\n"
    um = os.umask(0o22)
    os.umask(um)
    assert stat.S_IMODE(p.stat().st_mode) == 0o666 & ~um
    p.write_text("old content, longer\n")
    with out_file(p) as f:
        f.write("x")
    assert p.read_text() == "x" and temps(tmp_path) == []


@pytest.mark.parametrize("kind", ["fifo", "symlink", "folder"])
def test_file_refuses_special_targets(tmp_path: Path, kind: str) -> None:
    t = tmp_path / "t"
    victim = tmp_path / "victim"
    victim.write_text("keep")
    {"fifo": lambda: os.mkfifo(t), "symlink": lambda: t.symlink_to(victim), "folder": t.mkdir}[
        kind
    ]()
    with pytest.raises(OutputError, match="refusing to replace"), out_file(t) as f:
        f.write("x")
    assert victim.read_text() == "keep" and temps(tmp_path) == []
    assert {"fifo": stat.S_ISFIFO, "symlink": stat.S_ISLNK, "folder": stat.S_ISDIR}[kind](
        t.lstat().st_mode
    )


def test_file_failure_leaves_target_and_no_parents(tmp_path: Path) -> None:
    p = tmp_path / "keep.json"
    p.write_text("old")
    with pytest.raises(RuntimeError), out_file(p) as f:
        f.write("half")
        raise RuntimeError("the tool failed")
    assert p.read_text() == "old"
    with pytest.raises(RuntimeError), out_file(tmp_path / "n1" / "n2" / "f") as f:
        raise RuntimeError
    assert sorted(x.name for x in tmp_path.iterdir()) == ["keep.json"]


def test_file_input_and_inside_input_folder_refused(tmp_path: Path) -> None:
    runs = tmp_path / "runs"
    runs.mkdir()
    r = runs / "returns.csv"
    r.write_text("data")
    ins = Inputs([r, runs])
    with pytest.raises(OutputError, match="also an input"), out_file(r, ins):
        pass
    with (
        pytest.raises(OutputError, match="inside the input folder"),
        out_file(runs / "x" / "p", ins),
    ):
        pass
    assert r.read_text() == "data" and sorted(p.name for p in runs.iterdir()) == ["returns.csv"]


def test_file_temp_removed_on_sigterm(tmp_path: Path) -> None:
    code = textwrap.dedent(f"""
        import os, signal, time
        from odo_tools.outpath import out_file
        with out_file({str(tmp_path / "d" / "x.json")!r}) as f:
            f.write("partial"); f.flush()
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(5)
    """)
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert r.returncode == 128 + signal.SIGTERM, r.stderr
    assert list(tmp_path.iterdir()) == []


# --- folders -----------------------------------------------------------------------------------


def write_dir(path: Path, tool: str, names: list[str], text: str, force: bool = False, ins=None):
    with OutDir(path, tool, force, ins) as d:
        for n in names:
            (d.tmp / n).parent.mkdir(parents=True, exist_ok=True)
            (d.tmp / n).write_text(text)


def test_dir_fresh_foreign_force_and_rerun(tmp_path: Path) -> None:
    out = tmp_path / "x" / "o"
    write_dir(out, "odo-test", ["a.log", "sub/r.csv", "summary.json"], "1")
    assert (out / MANIFEST).read_text().splitlines() == [
        "odo-out-manifest 1",
        "tool odo-test",
        "a.log",
        "sub/r.csv",
        "summary.json",
    ]
    (out / "notes.txt").write_text("user's")
    write_dir(out, "odo-test", ["a.log"], "2")
    assert (out / "a.log").read_text() == "2" and not (out / "summary.json").exists()
    assert not (out / "sub" / "r.csv").exists() and (out / "notes.txt").read_text() == "user's"
    with pytest.raises(OutputError, match="--force"):
        write_dir(out, "another-tool", ["a.log"], "3")
    write_dir(out, "another-tool", ["a.log"], "3", force=True)
    assert (out / "a.log").read_text() == "3" and (out / "notes.txt").read_text() == "user's"
    assert temps(tmp_path) == []


def test_dir_refuses_files_links_and_inputs(tmp_path: Path) -> None:
    (tmp_path / "f").write_text("keep")
    with pytest.raises(OutputError, match="not a folder"):
        write_dir(tmp_path / "f", "t", ["a"], "x", force=True)
    (tmp_path / "real").mkdir()
    (tmp_path / "ln").symlink_to(tmp_path / "real")
    with pytest.raises(OutputError, match="symbolic link"):
        write_dir(tmp_path / "ln", "t", ["a"], "x", force=True)
    runs = tmp_path / "runs"
    runs.mkdir()
    (runs / "run.csv").write_text("t")
    with pytest.raises(OutputError, match="also an input"):
        write_dir(runs, "odo-import", ["a"], "x", force=True, ins=[runs])
    with pytest.raises(OutputError, match="inside the input folder"):
        write_dir(runs / "o", "odo-import", ["a"], "x", force=True, ins=[runs])
    assert [p.name for p in runs.iterdir()] == ["run.csv"] and temps(tmp_path) == []


def test_dir_failure_removes_temp_and_parents(tmp_path: Path) -> None:
    with pytest.raises(RuntimeError), OutDir(tmp_path / "p" / "q" / "o", "t") as d:
        (d.tmp / "a").write_text("x")
        raise RuntimeError
    assert list(tmp_path.iterdir()) == []


def test_manifest_naming_outside_paths_is_foreign(tmp_path: Path) -> None:
    (tmp_path / "precious").write_text("keep")
    o = tmp_path / "o"
    o.mkdir()
    for bad in ("../precious", "/etc/hostname", "a/../../precious"):
        (o / MANIFEST).write_text(f"odo-out-manifest 1\ntool t\n{bad}\n")
        assert read_manifest(o, "t") is None
        with pytest.raises(OutputError, match="did not write"):
            write_dir(o, "t", ["a"], "x")
    assert (tmp_path / "precious").read_text() == "keep"


def test_c_and_python_share_the_manifest(tmp_path: Path) -> None:
    """odo-sim (hostlib/odo_out.c) writes a manifest outpath reads, and the reverse."""
    out = tmp_path / "s"
    r = subprocess.run(
        [str(BUILD / "bin" / "odo-sim"), "--experiment", "rect-7x4", "--vehicle", "labmate",
         "--scenario", str(SRC / "host_sim" / "scenarios" / "none.json"), "--runs", "1",
         "--quiet", "--out", str(out)],
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert r.returncode == 0, r.stderr
    assert sorted(read_manifest(out, "odo-sim") or []) == sorted(
        p.name for p in out.iterdir() if p.name != MANIFEST
    )
    py = tmp_path / "py"
    write_dir(py, "odo-sim", ["run-cw-09.log"], "x")
    (py / "user.txt").write_text("keep")
    r = subprocess.run(
        [str(BUILD / "bin" / "odo-sim"), "--experiment", "rect-7x4", "--vehicle", "labmate",
         "--scenario", str(SRC / "host_sim" / "scenarios" / "none.json"), "--runs", "1",
         "--quiet", "--out", str(py)],
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert r.returncode == 0, r.stderr
    assert not (py / "run-cw-09.log").exists() and (py / "user.txt").read_text() == "keep"


# --- odo-import's bad-input classes (issue 16 item 3) -------------------------------------------


def odo_import(*args: object, cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [str(VENV / "odo-import"), *map(str, args)], capture_output=True, text=True, cwd=cwd,
        timeout=300,
    )  # fmt: skip


def one_line_error(r: subprocess.CompletedProcess[str], *needles: str) -> None:
    assert r.returncode == 1, r.stderr
    assert "Traceback" not in r.stderr
    err = [ln for ln in r.stderr.splitlines() if ln.startswith("odo-import: ") and "->" not in ln]
    assert len(err) == 1, r.stderr
    for n in needles:
        assert n in err[0], (n, err[0])


@pytest.mark.parametrize(
    "case,needles",
    [
        ("header_only", ["t.csv", "no data rows"]),
        ("not_utf8", ["t.csv:3", "not UTF-8"]),
        ("nul_byte", ["t.csv"]),
        ("one_row_truth", ["one.csv", "mismatched ticks/truth lengths"]),
        ("bad_truth_units", ["--truth-units", "km,rad"]),
        ("out_is_a_file", ["afile", "not a folder"]),
        ("out_under_a_file", ["afile", "not a folder"]),
        ("out_is_input_folder", ["in", "also an input"]),
    ],
)
def test_import_bad_input_classes(tmp_path: Path, case: str, needles: list[str]) -> None:
    src = SQUARE / "run-01.csv"
    (tmp_path / "in").mkdir()
    t = tmp_path / "in" / "t.csv"
    t.write_bytes(src.read_bytes())
    truth: list[object] = []
    out: Path = tmp_path / "o"
    extra: list[object] = []
    if case == "header_only":
        t.write_text("time,x,y,theta,right,left\n")
        extra = ["--map", "time=time,left=left,right=right"]
    elif case == "not_utf8":
        lines = src.read_bytes().splitlines(keepends=True)
        t.write_bytes(b"".join(lines[:2]) + b"0.1,\xff\xfe,0,0,0,0\n" + b"".join(lines[3:]))
    elif case == "nul_byte":
        t.write_bytes(src.read_bytes()[:200] + b"\0" + src.read_bytes()[200:])
    elif case == "one_row_truth":
        (tmp_path / "one.csv").write_bytes(src.read_bytes().splitlines(keepends=True)[0])
        truth = ["--truth", tmp_path / "one.csv"]
    elif case == "bad_truth_units":
        truth = ["--truth", t, "--truth-units", "km,rad"]
    elif case == "out_is_a_file":
        out = tmp_path / "afile"
        out.write_text("keep")
    elif case == "out_under_a_file":
        (tmp_path / "afile").write_text("keep")
        out = tmp_path / "afile" / "o"
    elif case == "out_is_input_folder":
        out = tmp_path / "in"  # --ticks names the folder itself: the recorded runs must stay
    if not extra:
        extra = ["--columns", COLS]
    before = sorted(p.relative_to(tmp_path) for p in tmp_path.rglob("*"))
    ticks = tmp_path / "in" if case == "out_is_input_folder" else t
    r = odo_import("ticks-csv", "--ticks", ticks, *truth, *extra, "--robot", OPTI, "--out", out)
    one_line_error(r, *needles)
    assert sorted(p.relative_to(tmp_path) for p in tmp_path.rglob("*")) == before


def test_import_into_missing_parents_and_rerun(tmp_path: Path) -> None:
    args = ["ticks-csv", "--ticks", SQUARE / "run-01.csv", "--columns", COLS, "--robot", OPTI]
    r = odo_import(*args, "--out", "a/b/o", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "a/b/o/run-fwd-01.log").is_file()
    (tmp_path / "a/b/o/notes.txt").write_text("keep")
    r = odo_import(*args, "--out", "a/b/o", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "a/b/o/notes.txt").read_text() == "keep" and temps(tmp_path) == []


# --- property tests: never a traceback, only the tools' own error types --------------------------

ROBOT = gap_io.read_robot(OPTI)
TEXT = st.one_of(
    st.binary(max_size=400),
    st.lists(
        st.lists(
            st.one_of(
                st.floats(allow_nan=True, allow_infinity=True).map(repr),
                st.integers(-(2**40), 2**40).map(str),
                st.sampled_from(["", "x", "nan", "cw", "ccw", "1e400", "-0"]),
            ),
            max_size=8,
        ).map(",".join),
        max_size=12,
    ).map(lambda rows: ("\n".join(rows) + "\n").encode()),
)
PROP = settings(
    max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)


@PROP
@given(data=TEXT, header=st.booleans())
def test_read_table_raises_only_its_own_error(tmp_path: Path, data: bytes, header: bool) -> None:
    p = tmp_path / "t.csv"
    p.write_bytes((b"time,x,y,theta,right,left\n" if header else b"") + data)
    try:
        importer.read_table(p, None if header else COLS.split(","), {})
    except GapInputError as e:
        assert str(p) in str(e)


@PROP
@given(text=st.text(max_size=60))
def test_parse_map_and_units_raise_value_errors_only(text: str) -> None:
    for f in (importer.parse_map, importer.check_truth_units):
        try:
            f(text)
        except ValueError:
            pass


@PROP
@given(lines=st.lists(st.binary(max_size=40), max_size=10))
def test_candump_reader_raises_only_gap_input_error(tmp_path: Path, lines: list[bytes]) -> None:
    p = tmp_path / "run-cw-01.log"
    p.write_bytes(b"(0.000000) can0 110#0000000000000000\n" + b"\n".join(lines))
    try:
        gap_io.read_log(p, ROBOT)
    except GapInputError as e:
        assert str(p) in str(e)


@PROP
@given(data=st.binary(max_size=300))
def test_read_manifest_never_raises(tmp_path: Path, data: bytes) -> None:
    (tmp_path / MANIFEST).write_bytes(data)
    names = read_manifest(tmp_path, "t")
    assert names is None or all(".." not in n.split("/") and not n.startswith("/") for n in names)


# --- the plot commands ---------------------------------------------------------------------------

RET_HEADER = "run,direction,x_abs_mm,y_abs_mm,theta_abs_deg,x_calc_mm,y_calc_mm,theta_calc_deg\n"


@pytest.mark.parametrize(
    "case,needles",
    [
        ("header_only", ["r.csv", "no runs"]),
        ("not_utf8", ["r.csv:2", "not UTF-8"]),
        ("out_is_input", ["r.csv", "also an input"]),
        ("out_is_fifo", ["fifo", "refusing"]),
    ],
)
def test_plot_umbmark_bad_input_classes(tmp_path: Path, case: str, needles: list[str]) -> None:
    r_csv = tmp_path / "r.csv"
    r_csv.write_text(RET_HEADER + "1,cw,10,20,1,0,0,0\n1,ccw,-5,3,1,0,0,0\n")
    out = tmp_path / "u.png"
    if case == "header_only":
        r_csv.write_text(RET_HEADER)
    elif case == "not_utf8":
        r_csv.write_bytes(RET_HEADER.encode() + b"1,cw,\xff,20,1,0,0,0\n")
    elif case == "out_is_input":
        out = r_csv
    elif case == "out_is_fifo":
        out = tmp_path / "fifo"
        os.mkfifo(out)
    before = {p.name: p.lstat().st_mode for p in tmp_path.iterdir()}
    r = subprocess.run(
        [str(VENV / "odo-plot-umbmark"), "--before", str(r_csv), "--out", str(out)],
        capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert r.returncode == 1 and "Traceback" not in r.stderr, r.stderr
    assert len(r.stderr.strip().splitlines()) == 1, r.stderr
    for n in needles:
        assert n in r.stderr, (n, r.stderr)
    assert {p.name: p.lstat().st_mode for p in tmp_path.iterdir()} == before


def test_plot_umbmark_creates_missing_parents(tmp_path: Path) -> None:
    r_csv = tmp_path / "r.csv"
    r_csv.write_text(RET_HEADER + "1,cw,10,20,1,0,0,0\n1,ccw,-5,3,1,0,0,0\n")
    r = subprocess.run(
        [str(VENV / "odo-plot-umbmark"), "--before", str(r_csv), "--out", "a/b/u.png"],
        capture_output=True, text=True, timeout=120, cwd=tmp_path,
    )  # fmt: skip
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "a/b/u.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_check_dir_refuses_what_outdir_refuses_and_creates_nothing(tmp_path: Path) -> None:
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_text("x")
    src = tmp_path / "src"
    src.mkdir()
    (tmp_path / "file").write_text("x")
    for target, inputs in ((mine, None), (src / "out", [src]), (tmp_path / "file", None)):
        with pytest.raises(OutputError):
            check_dir(target, "odo-x", inputs=inputs)
        with pytest.raises(OutputError):
            OutDir(target, "odo-x", inputs=inputs)
    check_dir(mine, "odo-x", force=True)  # --force may write there
    check_dir(tmp_path / "new" / "deeper", "odo-x")  # a fresh target: allowed, not made
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file", "mine", "src"]
    assert [p.name for p in mine.iterdir()] == ["notes.txt"] and not any(src.iterdir())

"""odo-replay (issue 6): cantools cross-check of its output log, and its bad-input contract.

The output frames are decoded with `python -m cantools decode` and can/odometry.dbc, the single
source of truth for every frame, and compared with the poses odo-replay wrote to its CSV; bad
input gives a clear message naming file and line, a non-zero exit, and leaves nothing behind."""

from __future__ import annotations

import csv
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import cantools
import pytest

SRC = Path(os.environ["ODO_SOURCE_DIR"])
BIN = Path(os.environ["ODO_BUILD_DIR"]) / "bin"
DBC = SRC / "can" / "odometry.dbc"
ROBOT = SRC / "host_sim" / "robots" / "clapper.json"


def run(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([str(BIN / "odo-replay"), *args], capture_output=True, text=True,
                          timeout=300)


@pytest.fixture(scope="module")
def sim_log(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("sim") / "out"
    r = subprocess.run([str(BIN / "odo-sim"), "--quiet", "--experiment", "straight-36m",
                        "--vehicle", "clapper", "--scenario",
                        str(SRC / "host_sim" / "scenarios" / "none.json"), "--runs", "1",
                        "--out", str(out)], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    return out / "run-fwd-01.log"


@pytest.fixture(scope="module")
def replayed(sim_log: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("replay") / "out"
    r = run("--log", str(sim_log), "--robot", str(ROBOT), "--ipec", "on", "--out", str(out),
            "--quiet")
    assert r.returncode == 0, r.stderr
    return out


DECODED = re.compile(r"can0 (?P<id>[0-9A-F]{3})#\S* :: (?P<msg>\w+)\((?P<sig>.*)\)$")


def decode_with_cantools(log: Path) -> list[tuple[str, dict[str, str]]]:
    """Every line of `log` through `python -m cantools decode --single-line DBC`."""
    r = subprocess.run([sys.executable, "-m", "cantools", "decode", "--single-line", str(DBC)],
                       stdin=log.open(), capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    out = []
    for line in r.stdout.splitlines():
        m = DECODED.search(line)
        assert m, f"cantools could not decode: {line}"
        sig = dict(kv.split(": ", 1) for kv in m["sig"].split(", "))
        out.append((m["msg"], sig))
    return out


def num(v: str) -> float:
    return float(v.split()[0])


def faults_word(status: dict[str, str]) -> int:
    """STATUS's fault bits, one named one-bit signal each (plus FaultsReserved 20|12), as the
    32-bit word the firmware raised; positions from the DBC itself."""
    msg = cantools.database.load_file(str(DBC)).get_message_by_name("STATUS")
    word = 0
    for sig in msg.signals:
        if sig.start < 32:
            word |= int(status[sig.name]) << sig.start
    return word


def test_cantools_decodes_every_output_frame_to_the_csv_poses(replayed: Path) -> None:
    """POSE_XY X/Y (0.01 mm) and POSE_THETA Theta (2^-32 turn) of both trucks, decoded by
    cantools from out.log, equal the CSV's full-resolution poses to within one LSB (rounding)."""
    rows = list(csv.DictReader((replayed / "poses.csv").open()))
    frames = decode_with_cantools(replayed / "out.log")
    assert len(rows) > 2000
    assert len(frames) == 6 * len(rows)  # XY, THETA per truck, IPEC_CORR, STATUS
    checked = 0
    for k, row in enumerate(rows):
        tick = frames[6 * k:6 * k + 6]
        assert [m for m, _ in tick] == ["POSE_XY_A", "POSE_THETA_A", "POSE_XY_B", "POSE_THETA_B",
                                       "IPEC_CORR", "STATUS"]
        for (_, xy), (_, th), t in ((tick[0], tick[1], "a"), (tick[2], tick[3], "b")):
            assert abs(num(xy["X"]) - float(row[f"x_{t}_mm"])) <= 0.0051
            assert abs(num(xy["Y"]) - float(row[f"y_{t}_mm"])) <= 0.0051
            d = (num(th["Theta"]) - float(row[f"theta_{t}_deg"]) + 180.0) % 360.0 - 180.0
            assert abs(d) <= 360.0 / 2**32 + 1e-9
            assert int(th["Seq"]) == k % 256
        status = tick[5][1]
        assert faults_word(status) == int(row["faults"], 16)
        for sig, col in (("DThetaA", "ipec_a_bam"), ("DThetaB", "ipec_b_bam")):
            assert round(num(tick[4][1][sig]) / (360.0 / 2**32)) == int(row[col])
        checked += 1
    # the run went somewhere: truck A drove 18 m out and 18 m back
    assert max(float(r["x_a_mm"]) for r in rows) > 17000.0
    assert checked == len(rows)


def test_summary_counts_every_frame(replayed: Path, sim_log: Path) -> None:
    s = json.loads((replayed / "summary.json").read_text())
    n = sum(1 for _ in sim_log.open())
    assert s["frames"] == n and s["sensor_frames"] == n
    assert s["ignored"] == 0 and s["bad_dlc"] == 0 and s["time_backwards"] == 0
    assert s["ticks"] == n // 4


def write(path: Path, lines: list[str]) -> Path:
    path.write_text("".join(line + "\n" for line in lines))
    return path


GOOD = [f"({k * 0.04:.6f}) can0 110#{k:02X}0000{k:02X}0000{k:02X}00" for k in range(5)]


@pytest.mark.parametrize(("line", "why"), [
    ("(0.200000) can0 110##1000", "CAN FD"),   # malformed; a well-formed one is skipped
    ("(0.200000) can0 110#000000000000000000", "more than 8 data bytes"),
    ("(0.200000) can0 110#0", "odd number"),
    ("0.200000 can0 110#00", "timestamp"),
    ("(0.200000) can0 1100#00", "3 (standard) or 8 (extended)"),
])
def test_malformed_line_names_file_and_line(tmp_path: Path, line: str, why: str) -> None:
    log = write(tmp_path / "bad.log", [*GOOD, line, *GOOD])
    out = tmp_path / "out"
    r = run("--log", str(log), "--robot", str(ROBOT), "--out", str(out))
    assert r.returncode == 1
    assert f"{log}:6: " in r.stderr and why in r.stderr, r.stderr
    assert not out.exists() and not list(tmp_path.glob("out.tmp.*"))


def test_unknown_ids_ignored_and_counted_wrong_dlc_flagged_time_backwards(tmp_path: Path) -> None:
    lines = [*GOOD[:3], "(0.080000) can0 555#0102", "(0.080000) can0 1ABCDEF0#00",
             "(0.120000) can0 110#03000003000003", "(0.100000) can0 110#0300000300000300",
             "(0.160000) can0 110#0400000400000400"]
    out = tmp_path / "out"
    r = run("--log", str(write(tmp_path / "in.log", lines)), "--params", str(params_bin(tmp_path)),
            "--out", str(out))
    assert r.returncode == 0, r.stderr
    assert "1 frames stamped before the previous frame" in r.stderr
    s = json.loads((out / "summary.json").read_text())
    assert (s["ignored"], s["bad_dlc"], s["time_backwards"], s["ticks"]) == (2, 1, 1, 5)
    faults = [int(row["faults"], 16) for row in csv.DictReader((out / "poses.csv").open())]
    bad_dlc, backwards = 1 << 14, 1 << 17
    assert faults[3] & bad_dlc and faults[3] & backwards
    assert not any(f & (1 << 15) for f in faults)  # unknown IDs are not the firmware's fault


def params_bin(tmp: Path) -> Path:
    """A single-truck parameter block from odo-params (default parameters)."""
    p = tmp / "p.bin"
    r = subprocess.run([str(BIN / "odo-params"), "defaults", "--out", str(p)], capture_output=True,
                       text=True)
    if r.returncode != 0 or not p.exists():
        pytest.fail(f"odo-params could not write a default block: {r.stderr}")
    return p


def test_bad_arguments_and_missing_inputs(tmp_path: Path, sim_log: Path) -> None:
    r = run("--log", str(tmp_path / "none.log"), "--robot", str(ROBOT),
            "--out", str(tmp_path / "o"))
    assert r.returncode == 1 and "none.log: cannot open" in r.stderr
    r = run("--log", str(sim_log), "--iface", "vcan0", "--robot", str(ROBOT))
    assert r.returncode == 2 and "exactly one of --log" in r.stderr
    r = run("--log", str(sim_log), "--robot", str(ROBOT), "--ipec", "maybe", "--out", "x")
    assert r.returncode == 2 and "--ipec must be off, on, paper or estimator" in r.stderr
    keep = tmp_path / "keep"
    keep.mkdir()
    (keep / "precious.txt").write_text("x")
    r = run("--log", str(sim_log), "--robot", str(ROBOT), "--out", str(keep))
    assert r.returncode == 1 and "non-empty folder odo-replay did not write" in r.stderr
    assert (keep / "precious.txt").exists()
    # live mode on a machine without CAN, or with CAN but no such interface: a clear message
    r = run("--iface", "odonosuch0", "--robot", str(ROBOT))
    assert r.returncode == 1
    assert "no SocketCAN" in r.stderr or "no interface 'odonosuch0'" in r.stderr, r.stderr
    assert "--log RUN.log" in run("--help").stdout


def test_params_block_and_its_json_give_the_same_replay(tmp_path: Path, sim_log: Path) -> None:
    """--params accepts the raw block and its JSON form (odo-params show): same outputs."""
    blk = params_bin(tmp_path)
    shown = subprocess.run([str(BIN / "odo-params"), "show", str(blk)], capture_output=True,
                           text=True)
    assert shown.returncode == 0, shown.stderr
    js = tmp_path / "p.json"
    js.write_text(shown.stdout)
    outs = []
    for p in (blk, js):
        out = tmp_path / f"out-{p.suffix[1:]}"
        r = run("--log", str(sim_log), "--params", str(p), "--out", str(out), "--quiet")
        assert r.returncode == 0, r.stderr
        outs.append((out / "out.log").read_text())
    assert outs[0] == outs[1] and len(outs[0].splitlines()) > 1000
    bad = tmp_path / "bad.json"
    bad.write_text('{"vehicle": 0}')
    r = run("--log", str(sim_log), "--params", str(bad), "--out", str(tmp_path / "o"))
    assert r.returncode == 1 and "bad.json" in r.stderr


# ---- issue 16: inputs that crashed, ground or corrupted the output before ----


def test_rotary_readings_180_deg_apart_replay_cleanly(tmp_path: Path) -> None:
    """The issue's reproducer: two frames whose rotary angles are exactly 180 deg apart reached
    signed overflow (a UBSan abort, and o.tmp.PID left behind); now an ordinary tick."""
    log = write(tmp_path / "ub.log", ["(0.000000) can0 120#000000800103",
                                      "(0.000000) can0 121#40420F000104"])
    out = tmp_path / "o"
    r = run("--log", str(log), "--robot", str(ROBOT), "--out", str(out), "--quiet")
    assert r.returncode == 0, r.stderr
    assert "runtime error" not in r.stderr
    assert json.loads((out / "summary.json").read_text())["ticks"] == 1
    assert not list(tmp_path.glob("o.tmp.*"))


def test_paths_with_quotes_and_backslashes_give_valid_json(tmp_path: Path) -> None:
    """summary.json names its input: a path with a quote used to make it invalid JSON."""
    d = tmp_path / 'we"ird\\dir'
    d.mkdir()
    log = write(d / 'run "1".log', GOOD)
    out = d / 'out"put'
    r = run("--log", str(log), "--params", str(params_bin(tmp_path)), "--out", str(out), "--quiet")
    assert r.returncode == 0, r.stderr
    s = json.loads((out / "summary.json").read_text())
    assert s["input"] == str(log) and s["ticks"] == 5


def gap_log(tmp_path: Path, gap_s: float) -> Path:
    """Ten ticks of a labmate driving 1 count a tick, a gap of gap_s seconds, ten more."""
    lines = []
    for k in range(20):
        t = k * 0.04 + (gap_s if k >= 10 else 0.0)
        lines.append(f"({t:.6f}) can0 110#{k:02X}0000{k:02X}0000{k:02X}00")
    return write(tmp_path / f"gap-{gap_s:g}.log", lines)


@pytest.mark.parametrize("gap_s", [1e5, 1e12])
def test_a_long_gap_is_reported_and_skipped(tmp_path: Path, gap_s: float) -> None:
    """A 1e5 s gap was ground through as 2.5 M empty ticks (794 MB) without a word; 1e12 s never
    ended. It is skipped, said on stderr (file and line) and counted in the summary."""
    out = tmp_path / "out"
    r = run("--log", str(gap_log(tmp_path, gap_s)), "--params", str(params_bin(tmp_path)),
            "--out", str(out), "--quiet")
    assert r.returncode == 0, r.stderr
    assert f"gap-{gap_s:g}.log:11: a gap of " in r.stderr and "skipped" in r.stderr, r.stderr
    s = json.loads((out / "summary.json").read_text())
    assert s["ticks"] == 20 and s["gaps_skipped"] == 1
    assert s["gap_skipped_s"] == pytest.approx(gap_s + 0.04, rel=1e-9)
    rows = list(csv.DictReader((out / "poses.csv").open()))
    assert len(rows) == 20
    assert float(rows[10]["t_s"]) == pytest.approx(gap_s + 0.4, rel=1e-9)  # the log's clock
    assert int(rows[10]["faults"], 16) & 0x2  # the reading across the gap is not trusted


def test_a_clock_step_back_is_re_anchored(tmp_path: Path) -> None:
    """The sender's clock steps back 2 s after five ticks: the frames open new ticks (not folded
    into the open one), and only the tick where time went back is flagged TIME_BACKWARDS."""
    t = [10.0 + k * 0.04 - (2.0 if k >= 5 else 0.0) for k in range(10)]
    lines = [f"({t[k]:.6f}) can0 110#{k:02X}0000{k:02X}0000{k:02X}00" for k in range(10)]
    out = tmp_path / "out"
    r = run("--log", str(write(tmp_path / "back.log", lines)), "--params",
            str(params_bin(tmp_path)), "--out", str(out))
    assert r.returncode == 0, r.stderr
    assert "clock stepped back 1 time(s)" in r.stderr
    s = json.loads((out / "summary.json").read_text())
    assert (s["ticks"], s["clock_steps"], s["time_backwards"]) == (10, 1, 1)
    rows = list(csv.DictReader((out / "poses.csv").open()))
    backwards = [int(row["faults"], 16) & (1 << 17) != 0 for row in rows]
    assert backwards == [False] * 5 + [True] + [False] * 4


def test_outputs_that_cannot_be_created_leave_no_temp_folder(tmp_path: Path) -> None:
    """Out of file descriptors after DIR.tmp.PID was made (the second output cannot be opened):
    a clear error, exit 1, and the temp folder removed with what it held."""
    log = write(tmp_path / "in.log", GOOD)
    r = subprocess.run(["bash", "-c", 'ulimit -n 5 && exec "$@"', "odo-replay",
                        str(BIN / "odo-replay"), "--log", str(log), "--params",
                        str(params_bin(tmp_path)), "--out", str(tmp_path / "o")],
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 1 and "cannot create" in r.stderr, r.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["in.log", "p.bin"]

"""A recorded log's start time (issue 17 item 6): odo-sim stamps its candump logs from the wall
clock by default and from a fixed epoch when told (--log-start, or SOURCE_DATE_EPOCH, which
ctest sets to 0), and the readers take a run's t = 0 from the log, not from timestamp 0.

The wall clock matters to can-utils: log2asc takes a start time of 0 s as "no start yet", so a log
from 0 gets a new ASC header before every frame of its first second (and one more); from the
wall clock it gets one.
"""

import json
import os
import shutil
import subprocess
import time
from pathlib import Path

import numpy as np
import pytest

BUILD = Path(os.environ["ODO_BUILD_DIR"])
SRC = Path(os.environ["ODO_SOURCE_DIR"])
SIM = BUILD / "bin" / "odo-sim"
ROBOT = SRC / "host_sim/robots/labmate.json"
EPOCH = 1_700_000_000  # 2023-11-14, a whole second


def sim(out: Path, *extra: str, env: dict | None = None) -> subprocess.CompletedProcess:
    return subprocess.run(
        [
            str(SIM),
            "--quiet",
            "--experiment",
            "umbmark",
            "--vehicle",
            "labmate",
            "--runs",
            "1",
            "--scenario",
            str(SRC / "host_sim/scenarios/effect-ed.json"),
            "--out",
            str(out),
            *extra,
        ],
        capture_output=True,
        text=True,
        timeout=120,
        env=env,
    )


def stamps_us(log: Path) -> list[int]:
    """Timestamps as integers, parsed from the text (no float rounding)."""
    out = []
    for line in log.read_text().splitlines():
        sec, usec = line[1 : line.index(")")].split(".")
        out.append(int(sec) * 1_000_000 + int(usec))
    return out


def frames(log: Path) -> list[str]:
    return [ln.split(") ", 1)[1] for ln in log.read_text().splitlines()]


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    d = tmp_path_factory.mktemp("logstart")
    env = {k: v for k, v in os.environ.items() if k != "SOURCE_DATE_EPOCH"}
    before = int(time.time())
    assert sim(d / "wall", env=env).returncode == 0
    after = int(time.time())
    assert sim(d / "zero", "--log-start", "0").returncode == 0
    assert sim(d / "zero2", "--log-start", "0").returncode == 0
    assert sim(d / "epoch", "--log-start", str(EPOCH)).returncode == 0
    assert sim(d / "sde", env={**env, "SOURCE_DATE_EPOCH": str(EPOCH)}).returncode == 0
    return d, before, after


def test_default_start_is_the_wall_clock_whole_second(runs):
    d, before, after = runs
    wall = stamps_us(d / "wall/run-cw-01.log")
    zero = stamps_us(d / "zero/run-cw-01.log")
    start = wall[0] - zero[0]
    assert start % 1_000_000 == 0, "the start is a whole second"
    assert before <= start // 1_000_000 <= after
    # the same run, shifted as a whole: sub-second digits are the run's own clock
    assert [w - start for w in wall] == zero
    assert frames(d / "wall/run-cw-01.log") == frames(d / "zero/run-cw-01.log")


def test_fixed_epoch_is_reproducible_and_shifts_exactly(runs):
    d, _, _ = runs
    z = d / "zero/run-cw-01.log"
    assert z.read_bytes() == (d / "zero2/run-cw-01.log").read_bytes()
    assert stamps_us(z)[0] == 0
    assert [t - EPOCH * 1_000_000 for t in stamps_us(d / "epoch/run-cw-01.log")] == stamps_us(z)
    # SOURCE_DATE_EPOCH (what ctest sets) gives the same bytes as the flag
    assert (d / "sde/run-cw-01.log").read_bytes() == (d / "epoch/run-cw-01.log").read_bytes()
    # the truth CSV is on the log's clock
    tz = np.loadtxt(
        z.with_suffix("").with_suffix(".truth.csv"), delimiter=",", skiprows=1, usecols=(0, 1, 2)
    )
    te = np.loadtxt(d / "epoch/run-cw-01.truth.csv", delimiter=",", skiprows=1, usecols=(0, 1, 2))
    np.testing.assert_allclose(te[:, 0] - EPOCH, tz[:, 0], rtol=0, atol=1e-6)
    np.testing.assert_array_equal(te[:, 1:], tz[:, 1:])


@pytest.mark.parametrize("bad", ["-1", "1.5", "", "abc", " 5", "+5", "8589934593", "1e9"])
def test_bad_log_start_is_refused_before_anything_is_written(tmp_path, bad):
    r = sim(tmp_path / "out", "--log-start", bad)
    assert r.returncode == 2 and "--log-start" in r.stderr
    assert not (tmp_path / "out").exists()


def test_bad_source_date_epoch_is_refused(tmp_path):
    r = sim(tmp_path / "out", env={**os.environ, "SOURCE_DATE_EPOCH": "yesterday"})
    assert r.returncode == 2 and "SOURCE_DATE_EPOCH" in r.stderr
    assert not (tmp_path / "out").exists()

    # only where the default is used: --help and an explicit --log-start do not read it
    h = subprocess.run([str(SIM), "--help"], capture_output=True, text=True,
                       env={**os.environ, "SOURCE_DATE_EPOCH": "yesterday"})
    assert h.returncode == 0 and "--log-start" in h.stdout
    r = sim(tmp_path / "given", "--log-start", "0",
            env={**os.environ, "SOURCE_DATE_EPOCH": "yesterday"})
    assert r.returncode == 0, r.stderr


def test_gap_pairs_a_wall_clock_log_with_its_truth(runs):
    """odo-gap's readers take the log and the truth on one clock: the same run started at 0 or at
    an epoch gives the same samples, shifted by the epoch, and the same truth at each tick."""
    from odo_tools.gap.io import read_log, read_robot, read_truth

    d, _, _ = runs
    robot = read_robot(ROBOT)
    a = read_log(d / "zero/run-cw-01.log", robot)
    b = read_log(d / "epoch/run-cw-01.log", robot)
    assert a.t_s[0] == 0.0
    np.testing.assert_allclose(b.t_s - EPOCH, a.t_s, rtol=0, atol=1e-6)
    np.testing.assert_array_equal(b.counts, a.counts)
    ta = read_truth(d / "zero/run-cw-01.truth.csv", robot)
    tb = read_truth(d / "epoch/run-cw-01.truth.csv", robot)
    xa = np.interp(a.t_s, ta.t_s, ta.pose[:, 0, 0])
    xb = np.interp(b.t_s, tb.t_s, tb.pose[:, 0, 0])
    np.testing.assert_allclose(xb, xa, rtol=0, atol=1e-3)


def test_calib_fit_pairs_a_wall_clock_log_with_its_truth(runs):
    """odo-calib fit puts its ticks on the log's clock: the same fit from either start, and the
    scenario's hidden Ed found from the wall-clock run."""
    d, _, _ = runs
    ed_true = json.loads((SRC / "host_sim/scenarios/effect-ed.json").read_text())["effects"]["ed"][
        "value"
    ]
    fits = {}
    for name in ("zero", "epoch"):
        r = subprocess.run(
            [
                str(BUILD / "bin/odo-calib"),
                "fit",
                "--runs",
                str(d / name),
                "--robot",
                str(ROBOT),
                "--free",
                "ed,eb",
                "--json",
            ],
            capture_output=True,
            text=True,
            timeout=300,
        )
        assert r.returncode == 0, r.stderr
        fits[name] = json.loads(r.stdout)
    # the same up to the 1e-9 that absolute times in doubles cost (2^-22 s at 1.7e9 s)
    for k, v in fits["zero"]["params"].items():
        assert fits["epoch"]["params"][k] == pytest.approx(v, abs=1e-8), k
    assert fits["epoch"]["rms_mm"] == pytest.approx(fits["zero"]["rms_mm"], abs=1e-3)
    assert abs(fits["epoch"]["params"]["ed"] - ed_true) < 1e-5


def test_replay_of_a_wall_clock_log_counts_from_its_first_tick(runs, tmp_path):
    """odo-replay: poses.csv counts time from the first tick; out.log keeps the input's clock."""
    d, _, _ = runs
    subprocess.run(
        [
            str(BUILD / "bin/odo-replay"),
            "--log",
            str(d / "epoch/run-cw-01.log"),
            "--robot",
            str(ROBOT),
            "--out",
            str(tmp_path / "r"),
            "--quiet",
        ],
        check=True,
        capture_output=True,
        timeout=120,
    )
    t = np.loadtxt(tmp_path / "r/poses.csv", delimiter=",", skiprows=1, usecols=1)
    assert t[0] == 0.0 and abs(t[1] - 0.04) < 1e-9
    out = stamps_us(tmp_path / "r/out.log")
    assert out[0] // 1_000_000 == EPOCH


@pytest.mark.skipif(shutil.which("log2asc") is None, reason="can-utils (tools/deps.sh) missing")
def test_log2asc_writes_one_header_for_a_wall_clock_log(runs):
    d, _, _ = runs

    def headers(log: Path) -> int:
        r = subprocess.run(
            ["log2asc", "-I", str(log), "can0"],
            capture_output=True,
            text=True,
            check=True,
            timeout=60,
        )
        return sum(1 for ln in r.stdout.splitlines() if ln.startswith("date "))

    z = d / "zero/run-cw-01.log"
    first_second = sum(1 for t in stamps_us(z) if t < 1_000_000)
    assert headers(d / "wall/run-cw-01.log") == 1
    assert headers(d / "epoch/run-cw-01.log") == 1
    assert headers(z) == first_second + 1 > 1  # the behaviour the wall clock avoids

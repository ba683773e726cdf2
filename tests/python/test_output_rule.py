"""The output rule and the CLI vocabulary through the real C CLIs (issue 16 item 2, issue 17).

Each reproducer of issue 16 is a regression test here: odo-sim deleting a user's files in a
folder holding a summary.json, odo-calib umbmark --out-params equal to --returns, odo-calib write
--out equal to --params, --out-params on a special file (a FIFO this test makes, never a /dev
node), odo-params following a symlink planted at FILE.tmp, and the README's first simulator
command on a clone without out/. The rule itself is unit-tested in tests/host/test_odo_out.c."""

from __future__ import annotations

import os
import re
import signal
import stat
import subprocess
import time
from pathlib import Path

import pytest

BUILD = Path(os.environ["ODO_BUILD_DIR"])
SRC = Path(os.environ["ODO_SOURCE_DIR"])
BIN = BUILD / "bin"
SIM, CALIB, PARAMS, REPLAY = (BIN / n for n in ("odo-sim", "odo-calib", "odo-params", "odo-replay"))
NONE = SRC / "host_sim" / "scenarios" / "none.json"
ROBOT = SRC / "host_sim" / "robots" / "labmate.json"
C_CLIS = [
    "odo-sim",
    "odo-replay",
    "odo-calib",
    "odo-params",
    "odo-ipec",
    "odo-canvec",
    "odo-demo",
    "odo-bench",
    "odo-soak",
]


def run(
    *args: object, cwd: Path | None = None, timeout: int = 300
) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [str(a) for a in args], capture_output=True, text=True, cwd=cwd, timeout=timeout
    )


def sim(out: object, *extra: object, cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
    return run(
        SIM,
        "--experiment",
        "rect-7x4",
        "--vehicle",
        "labmate",
        "--scenario",
        NONE,
        "--runs",
        "1",
        "--quiet",
        "--out",
        out,
        *extra,
        cwd=cwd,
    )


def temps(folder: Path) -> list[str]:
    return [p.name for p in folder.rglob("*") if ".tmp" in p.name]


@pytest.fixture(scope="module")
def returns(tmp_path_factory: pytest.TempPathFactory) -> Path:
    d = tmp_path_factory.mktemp("umb")
    r = run(
        SIM,
        "--experiment",
        "umbmark",
        "--vehicle",
        "labmate",
        "--scenario",
        SRC / "host_sim" / "scenarios" / "set-sim.json",
        "--runs",
        "2",
        "--quiet",
        "--out",
        d / "u",
    )
    assert r.returncode == 0, r.stderr
    return d / "u" / "returns.csv"


@pytest.fixture()
def block(tmp_path: Path) -> Path:
    p = tmp_path / "p.bin"
    r = run(PARAMS, "defaults", "--out", p)
    assert r.returncode == 0, r.stderr
    return p


# --- the CLI vocabulary ------------------------------------------------------------------------


@pytest.mark.parametrize("tool", C_CLIS)
def test_every_c_cli_prints_the_cmake_project_version(tool: str) -> None:
    version = re.search(r"project\(odometry VERSION (\S+)", (SRC / "CMakeLists.txt").read_text())
    assert version is not None
    r = run(BIN / tool, "--version")
    assert r.returncode == 0, r.stderr
    assert r.stdout == f"{tool} {version.group(1)}\n"
    h = run(BIN / tool, "--help")
    assert h.returncode == 0 and "--version" in h.stdout, tool


def test_ipec_takes_the_same_values_in_odo_sim_and_odo_replay(tmp_path: Path) -> None:
    clapper = SRC / "host_sim" / "robots" / "clapper.json"
    r = run(
        SIM,
        "--experiment=straight-36m",
        "--vehicle=clapper",
        f"--scenario={NONE}",
        "--runs=1",
        "--bumps=0",
        "--quiet",
        f"--out={tmp_path / 's'}",
    )
    assert r.returncode == 0, r.stderr
    for mode in ("off", "on", "paper", "estimator"):
        r = run(
            REPLAY,
            f"--log={tmp_path / 's' / 'run-fwd-01.log'}",
            f"--robot={clapper}",
            f"--ipec={mode}",
            "--quiet",
            f"--out={tmp_path / mode}",
        )
        assert r.returncode == 0, (mode, r.stderr)
    for tool in (SIM, REPLAY):
        r = run(tool, "--ipec=sideways")
        assert r.returncode == 2 and "--ipec must be off, on, paper or estimator" in r.stderr


def test_seed_minus_one_is_a_usage_error_everywhere() -> None:
    r = run(SIM, "--experiment", "umbmark", "--seed", "-1")
    assert r.returncode == 2 and "--seed must be a non-negative integer" in r.stderr


# --- issue 16's reproducers --------------------------------------------------------------------


def test_readme_first_simulator_command_works_without_an_out_folder(tmp_path: Path) -> None:
    """README: `odo-sim --experiment umbmark ... --out out/umbmark` on a fresh clone (no out/)."""
    r = run(
        SIM,
        "--experiment",
        "umbmark",
        "--vehicle",
        "labmate",
        "--scenario",
        SRC / "host_sim" / "scenarios" / "set-sim.json",
        "--out",
        "out/umbmark",
        "--quiet",
        cwd=tmp_path,
    )
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "out" / "umbmark" / "returns.csv").is_file()
    assert temps(tmp_path) == []


def test_sim_never_deletes_files_in_a_folder_it_did_not_write(tmp_path: Path) -> None:
    user = tmp_path / "mine"
    user.mkdir()
    (user / "summary.json").write_text("the user's own summary")
    (user / "notes.txt").write_text("keep me")
    r = sim(user)
    assert r.returncode == 1 and "--force" in r.stderr and str(user) in r.stderr
    assert sorted(p.name for p in user.iterdir()) == ["notes.txt", "summary.json"]
    assert (user / "summary.json").read_text() == "the user's own summary"
    r = sim(user, "--force")
    assert r.returncode == 0, r.stderr
    assert (user / "notes.txt").read_text() == "keep me"
    assert (user / "run-cw-01.log").is_file() and temps(tmp_path) == []


def test_sim_rerun_replaces_exactly_its_own_previous_files(tmp_path: Path) -> None:
    out = tmp_path / "o"
    assert sim(out, "--runs", "2").returncode == 0
    (out / "notes.txt").write_text("added by the user")
    r = sim(out)  # one run per direction now
    assert r.returncode == 0, r.stderr
    assert not (out / "run-cw-02.log").exists()  # ours, no longer written: removed
    assert (out / "run-cw-01.log").is_file()
    assert (out / "notes.txt").read_text() == "added by the user"


def test_fit_out_params_inside_a_runs_folder_is_refused(tmp_path: Path) -> None:
    runs = tmp_path / "runs"
    (runs / "square").mkdir(parents=True)
    (runs / "square" / "run-01.log").write_text("(0.000000) can0 110#0000000000000000\n")
    r = run(
        CALIB, "fit", "--runs", runs, "--robot", ROBOT, "--out-params", runs / "square" / "p.json"
    )
    assert r.returncode == 1 and "inside the input folder" in r.stderr
    r = run(
        CALIB, "fit", "--runs", runs, "--robot", ROBOT, "--out-params", ROBOT.with_suffix(".json")
    )
    assert r.returncode == 1 and "also an input" in r.stderr
    assert sorted(p.name for p in (runs / "square").iterdir()) == ["run-01.log"]


def test_sim_killed_mid_run_leaves_no_temp(tmp_path: Path) -> None:
    p = subprocess.Popen(
        [
            str(SIM),
            "--experiment",
            "umbmark",
            "--vehicle",
            "labmate",
            "--scenario",
            str(NONE),
            "--runs",
            "100",
            "--quiet",
            "--out",
            str(tmp_path / "a" / "b"),
        ],
        stderr=subprocess.PIPE,
        text=True,
    )
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and not list(tmp_path.rglob("run-cw-01.log")):
        time.sleep(0.05)
    p.send_signal(signal.SIGTERM)
    p.wait(timeout=60)
    assert p.returncode == -signal.SIGTERM
    assert list(tmp_path.iterdir()) == []  # neither the temp folder nor the parents made for it


def test_calib_umbmark_out_params_equal_to_returns_is_refused(returns: Path) -> None:
    before = returns.read_bytes()
    r = run(
        CALIB,
        "umbmark",
        "--returns",
        returns,
        "--side-mm",
        "4000",
        "--robot",
        ROBOT,
        "--out-params",
        returns,
    )
    assert r.returncode == 1 and "also an input" in r.stderr
    assert returns.read_bytes() == before
    assert temps(returns.parent) == []


def test_calib_write_out_equal_to_params_is_refused(tmp_path: Path, block: Path) -> None:
    image = tmp_path / "fw.bin"
    image.write_bytes(b"\xff" * 256 + block.read_bytes() + b"\xff" * 64)
    before = block.read_bytes()
    r = run(CALIB, "write", "--image", image, "--params", block, "--out", block)
    assert r.returncode == 1 and "also an input" in r.stderr
    assert block.read_bytes() == before
    r = run(
        CALIB, "write", "--image", image, "--params", block, f"--out={tmp_path / 'new' / 'fw.bin'}"
    )
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "new" / "fw.bin").read_bytes() == image.read_bytes()


@pytest.mark.parametrize("kind", ["fifo", "symlink", "folder"])
def test_calib_out_params_on_a_special_file_is_refused(
    tmp_path: Path, returns: Path, kind: str
) -> None:
    """Was: --out-params /dev/full replaced the device node with a regular file (as root)."""
    target = tmp_path / "special"
    victim = tmp_path / "victim.json"
    victim.write_text("keep")
    if kind == "fifo":
        os.mkfifo(target)
    elif kind == "symlink":
        target.symlink_to(victim)
    else:
        target.mkdir()
    r = run(
        CALIB,
        "umbmark",
        "--returns",
        returns,
        "--side-mm",
        "4000",
        "--robot",
        ROBOT,
        "--out-params",
        target,
    )
    assert r.returncode == 1 and str(target) in r.stderr and "refusing" in r.stderr, r.stderr
    mode = target.lstat().st_mode
    assert {"fifo": stat.S_ISFIFO, "symlink": stat.S_ISLNK, "folder": stat.S_ISDIR}[kind](mode)
    assert victim.read_text() == "keep"
    assert temps(tmp_path) == []


def test_params_never_follows_a_symlink_planted_at_the_old_temp_name(tmp_path: Path) -> None:
    victim = tmp_path / "victim"
    victim.write_text("keep")
    out = tmp_path / "p.bin"
    (tmp_path / "p.bin.tmp").symlink_to(victim)
    r = run(PARAMS, "defaults", "--out", out)
    assert r.returncode == 0, r.stderr
    assert victim.read_text() == "keep"
    assert out.is_file() and not out.is_symlink() and out.stat().st_size > 100
    assert (tmp_path / "p.bin.tmp").is_symlink()  # not ours: left alone


def test_replay_refuses_its_input_log_folder_and_keeps_the_log(tmp_path: Path) -> None:
    assert sim(tmp_path / "s").returncode == 0
    log = tmp_path / "s" / "run-cw-01.log"
    before = log.read_bytes()
    r = run(REPLAY, "--log", log, "--robot", ROBOT, "--out", tmp_path / "s", "--quiet")
    assert r.returncode == 1 and "non-empty folder odo-replay did not write" in r.stderr
    r = run(REPLAY, "--log", log, "--robot", ROBOT, "--out", log, "--quiet")
    assert r.returncode == 1 and "also an input" in r.stderr
    assert log.read_bytes() == before
    assert temps(tmp_path) == []

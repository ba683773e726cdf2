#!/usr/bin/env python3
"""The .deb and the wheel, installed the way a user installs them, run the tools on sample data.

No container: the release build (-O2, no sanitizers) of the installed targets goes through
`cmake --install` + CPack into a .deb; `dpkg-deb -x` unpacks it into a temp root, whose usr/bin
goes on PATH and usr/lib on the loader path; a fresh venv gets the wheel (tools/python/wheel.sh)
with pip, its dependencies made visible from the project's hash-pinned .venv (the same versions
`pip install --require-hashes -r tools/python/requirements.txt` gives a user; no network here).
Then, from a folder outside the checkout and with no ODO_* variable set, odo-sim drives a UMBmark
square, odo-calib computes the correction from its returns.csv, and odo-gap diagnoses the runs.
Each step checks what the tool wrote, not only its exit code.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

CLIS = [
    "odo-sim",
    "odo-calib",
    "odo-replay",
    "odo-params",
    "odo-ipec",
    "odo-canvec",
    "odo-soak",
    "odo-bench",
    "odo-demo",
]
PY_TOOLS = [
    "odo-gap",
    "odo-import",
    "odo-plot-umbmark",
    "odo-plot-demo",
    "odo-plot-realdata",
    "odo-flash",
    "odo-bench-target",
]
T0 = time.monotonic()


def step(msg: str) -> None:
    print(f"[{time.monotonic() - T0:6.1f} s] {msg}", flush=True)


def run(cmd: list[str], **kw) -> subprocess.CompletedProcess:
    r = subprocess.run(cmd, capture_output=True, text=True, **kw)
    if r.returncode != 0:
        sys.exit(
            f"FAIL: {' '.join(map(str, cmd))} exited {r.returncode}\n{r.stdout[-3000:]}\n"
            f"{r.stderr[-3000:]}"
        )
    return r


def check(cond: bool, what: str) -> None:
    if not cond:
        sys.exit(f"FAIL: {what}")
    print(f"  ok: {what}", flush=True)


def build_deb(a: argparse.Namespace, work: Path) -> Path:
    bld = work / "release"
    step("configure the release build (-O2, ODO_SANITIZE=OFF)")
    run(
        [
            a.cmake,
            "-S",
            a.source_dir,
            "-B",
            str(bld),
            "-G",
            "Ninja",
            "-DCMAKE_BUILD_TYPE=Release",
            "-DODO_SANITIZE=OFF",
            f"-DODO_VENV={a.venv}",
        ]
    )
    step("build the installed targets")
    # niced: the build shares the machine with timing-sensitive tests (qemu guests)
    run(
        ["nice", "-n", "10", a.cmake, "--build", str(bld), "--target", "odo_installable", "-j", "2"]
    )
    cache = (bld / "CMakeCache.txt").read_text()
    check(
        "CMAKE_BUILD_TYPE:STRING=Release" in cache and "ODO_SANITIZE:BOOL=OFF" in cache,
        "the packaged build is Release without sanitizers",
    )
    step("cpack -G DEB")
    out = work / "deb"
    shutil.rmtree(out, ignore_errors=True)
    run([a.cpack, "-G", "DEB", "--config", str(bld / "CPackConfig.cmake"), "-B", str(out)], cwd=bld)
    debs = sorted(out.glob("*.deb"))
    check(len(debs) == 1, f"one .deb ({[d.name for d in debs]})")
    return debs[0]


def unpack(deb: Path, root: Path) -> Path:
    step(f"dpkg-deb -x {deb.name}")
    info = run(["dpkg-deb", "-f", str(deb), "Package", "Depends"]).stdout
    check(
        "libjansson" in info and "libgsl" in info,
        f"Depends names the runtime libraries ({info.strip()!r})",
    )
    run(["dpkg-deb", "-x", str(deb), str(root)])
    usr = root / "usr"
    for c in CLIS:
        exe = usr / "bin" / c
        check(exe.is_file() and os.access(exe, os.X_OK), f"usr/bin/{c}")
        needed = run(["readelf", "-d", str(exe)]).stdout
        check("asan" not in needed and "ubsan" not in needed, f"{c} links no sanitizer runtime")
        check((usr / "share/man/man1" / f"{c}.1").is_file(), f"man page {c}.1")
    for f in [
        "lib/libodosim.so",
        "include/odosim/odosim.h",
        "share/odometry/can/odometry.dbc",
        "share/odometry/host_sim/robots/labmate.json",
        "share/odometry/host_sim/robots/optiodom.json",
        "share/odometry/host_sim/scenarios/set-sim.json",
        "share/odometry/hal/cortexm/openocd/odo_stm32f4.cfg",
        "share/doc/odometry/README.md",
    ]:
        check((usr / f).is_file(), f"usr/{f}")
    src_dbc = Path(ARGS.source_dir) / "can" / "odometry.dbc"
    check(
        (usr / "share/odometry/can/odometry.dbc").read_bytes() == src_dbc.read_bytes(),
        "the packaged DBC is the repository's",
    )
    return usr


def install_wheel(a: argparse.Namespace, work: Path) -> Path:
    step("build the wheel (tools/python/wheel.sh)")
    dist = work / "dist"
    shutil.rmtree(dist, ignore_errors=True)
    run(
        ["bash", str(Path(a.source_dir) / "tools/python/wheel.sh"), str(dist)],
        env={**os.environ, "ODO_VENV": a.venv},
    )
    wheels = sorted(dist.glob("*.whl"))
    check(len(wheels) == 1, f"one wheel ({[w.name for w in wheels]})")
    names = run([f"{a.venv}/bin/python", "-m", "zipfile", "-l", str(wheels[0])]).stdout
    for f in [
        "odo_tools/data/can/odometry.dbc",
        "odo_tools/data/host_sim/robots/labmate.json",
        "odo_tools/gap/robots/optiodom.json",
        "odo_tools/data/hal/cortexm/openocd/odo_stm32f4.cfg",
    ]:
        check(f in names, f"the wheel carries {f}")
    step("fresh venv + pip install the wheel")
    venv = work / "venv"
    shutil.rmtree(venv, ignore_errors=True)
    run([sys.executable, "-m", "venv", str(venv)])
    site = next(venv.glob("lib/python3*/site-packages"))
    deps = next(Path(a.venv).glob("lib/python3*/site-packages"))
    # Appended after the fresh venv's own site-packages, so the wheel's odo_tools wins; .pth
    # files inside deps (the checkout's editable install) are not processed from here.
    (site / "zz_pinned_deps.pth").write_text(f"{deps}\n")
    run(
        [
            str(venv / "bin/pip"),
            "install",
            "-q",
            "--disable-pip-version-check",
            "--no-index",
            "--no-deps",
            str(wheels[0]),
        ]
    )
    chk = subprocess.run(
        [str(venv / "bin/pip"), "check", "--disable-pip-version-check"],
        capture_output=True,
        text=True,
    )
    check("odo-tools" not in chk.stdout, f"the wheel's requirements are met ({chk.stdout.strip()})")
    return venv


def user_env(usr: Path, venv: Path) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if not k.startswith("ODO_")}
    env["PATH"] = f"{usr / 'bin'}:{venv / 'bin'}:/usr/bin:/bin"
    env["LD_LIBRARY_PATH"] = str(usr / "lib")
    env["MPLBACKEND"] = "Agg"
    env.pop("PYTHONPATH", None)
    return env


def run_tools(usr: Path, venv: Path, home: Path) -> None:
    env = user_env(usr, venv)
    share = usr / "share/odometry"
    robot = share / "host_sim/robots/labmate.json"

    def tool(*cmd: str) -> subprocess.CompletedProcess:
        exe = shutil.which(cmd[0], path=env["PATH"])
        check(exe is not None and not exe.startswith(ARGS.source_dir), f"{cmd[0]} from PATH: {exe}")
        return run(list(cmd), cwd=home, env=env)

    for t in PY_TOOLS:
        r = tool(t, "--help")
        check("usage" in r.stdout.lower(), f"{t} --help")
    where = tool(
        "python",
        "-c",
        "import odo_tools, odo_tools.gap.simlib as s, odo_tools.gap.io as i;"
        "print(odo_tools.__file__); print(s.lib_path()); print(i.source_dir())",
    ).stdout.split()
    check(where[0].startswith(str(venv)), f"odo_tools imported from the fresh venv ({where[0]})")
    check(
        Path(where[1]).resolve() == (usr / "lib/libodosim.so").resolve(),
        f"libodosim from the unpacked .deb ({where[1]})",
    )
    check(not where[2].startswith(ARGS.source_dir), f"data from the wheel ({where[2]})")

    step("odo-sim: UMBmark, 3 cw + 3 ccw runs, labmate (default robot from share/)")
    tool(
        "odo-sim",
        "--experiment",
        "umbmark",
        "--vehicle",
        "labmate",
        "--runs",
        "3",
        "--scenario",
        str(share / "host_sim/scenarios/set-sim.json"),
        "--out",
        "sim",
    )
    with open(home / "sim/returns.csv") as f:
        rows = list(csv.DictReader(f))
    check(
        len(rows) == 6 and len(list((home / "sim").glob("run-*.log"))) == 6,
        "6 runs: returns.csv rows and candump logs",
    )
    step("odo-calib umbmark on its returns.csv")
    tool(
        "odo-calib",
        "umbmark",
        "--returns",
        "sim/returns.csv",
        "--side-mm",
        "4000",
        "--robot",
        str(robot),
        "--out-params",
        "cal.json",
    )
    cal = json.loads((home / "cal.json").read_text())
    ed = cal["truck"][0]["ed_q30"] / 2**30
    # set-sim.json's robot has unequal wheels (000 s. 4.6.2, Ed 0.9985): the fit must move Ed
    check(cal["status"] == "ok" and abs(ed - 1.0) > 5e-4, f"a calibrated block (Ed {ed:.5f})")
    step("odo-gap diagnose on the runs")
    tool("odo-gap", "diagnose", "--real", "sim", "--robot", str(robot), "--out", "gap")
    rep = json.loads((home / "gap/report.json").read_text())
    check(
        isinstance(rep, dict) and (home / "gap/report.md").is_file(),
        f"report.json and report.md ({', '.join(sorted(rep)[:6])}, ...)",
    )
    step("odo-plot-umbmark")
    tool(
        "odo-plot-umbmark",
        "--before",
        "sim/returns.csv",
        "--after",
        "sim/returns.csv",
        "--out",
        "u.png",
    )
    check((home / "u.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", "u.png is a PNG")


def main() -> None:
    global ARGS
    p = argparse.ArgumentParser(description=__doc__)
    p.add_argument("--source-dir", required=True)
    p.add_argument("--work-dir", required=True)
    p.add_argument("--venv", required=True)
    p.add_argument("--cmake", default="cmake")
    p.add_argument("--cpack", default="cpack")
    ARGS = a = p.parse_args()
    a.source_dir = str(Path(a.source_dir).resolve())
    work = Path(a.work_dir)
    work.mkdir(parents=True, exist_ok=True)
    deb = build_deb(a, work)
    with tempfile.TemporaryDirectory(prefix="odo-pkg-") as tmp:
        usr = unpack(deb, Path(tmp) / "root")
        venv = install_wheel(a, Path(tmp))
        home = Path(tmp) / "home"
        home.mkdir()
        run_tools(usr, venv, home)
    step("package: every check passed")


ARGS: argparse.Namespace
if __name__ == "__main__":
    main()

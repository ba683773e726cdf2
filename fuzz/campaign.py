"""`make fuzz`: long libFuzzer campaigns over every harness in fuzz/ (issue 16 item 4).

Builds fuzz/ with clang into build/fuzz, then runs each harness for --runs executions (default
10^7, libFuzzer's -runs) from the committed seeds plus the corpus earlier campaigns grew in
build/fuzz/corpus, as many at once as there are cores. Prints progress lines on stderr and, at
the end, one JSON object on stdout: per harness the executions, crashes (a crash stops that
harness; its input is in build/fuzz/artifacts/<name>/, to be saved under fuzz/regressions/<name>/
once fixed), seconds, executions per second and new corpus units. Exit status 1 iff any crashed."""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
# Fastest first, so the slow ones (a file per run, the 40 ms step) get the most wall time last.
HARNESSES = [
    "candump",
    "can_codec",
    "params_json",
    "returns_csv",
    "params_block",
    "robot_json",
    "image",
    "replay_step",
]
MAX_LEN = {"replay_step": 480, "image": 4096, "robot_json": 4096, "params_json": 4096}


def build(bdir: Path) -> None:
    cfg = [
        "cmake",
        "-S",
        str(ROOT / "fuzz"),
        "-B",
        str(bdir),
        "-G",
        "Ninja",
        "-DCMAKE_C_COMPILER=clang",
        "-DCMAKE_BUILD_TYPE=RelWithDebInfo",
    ]
    subprocess.run(cfg, check=True, stdout=subprocess.DEVNULL)
    subprocess.run(
        ["cmake", "--build", str(bdir), "-j", str(os.cpu_count() or 1)],
        check=True,
        stdout=subprocess.DEVNULL,
    )


def last_count(log: Path) -> int:
    """The latest '#N' execution count libFuzzer printed."""
    try:
        text = log.read_bytes()[-4096:].decode("latin-1")
    except OSError:
        return 0
    found = re.findall(r"^#(\d+)\s", text, flags=re.M)
    return int(found[-1]) if found else 0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "--runs", type=int, default=10_000_000, help="executions per harness (default 10^7)"
    )
    ap.add_argument(
        "--jobs", type=int, default=os.cpu_count() or 1, help="harnesses at once (default: cores)"
    )
    ap.add_argument("--only", nargs="*", choices=HARNESSES, help="these harnesses only")
    ap.add_argument("--build-dir", type=Path, default=ROOT / "build" / "fuzz")
    a = ap.parse_args()
    if a.runs < 1 or a.jobs < 1:
        ap.error("--runs and --jobs must be positive")
    bdir = a.build_dir
    print(f"fuzz: building {bdir}", file=sys.stderr)
    build(bdir)
    todo = list(a.only or HARNESSES)
    running: dict[str, tuple[subprocess.Popen[bytes], float, Path]] = {}
    results: dict[str, dict[str, object]] = {}
    last_report = 0.0
    while todo or running:
        while todo and len(running) < a.jobs:
            name = todo.pop(0)
            corpus = bdir / "corpus" / name
            art = bdir / "artifacts" / name
            corpus.mkdir(parents=True, exist_ok=True)
            art.mkdir(parents=True, exist_ok=True)
            log = bdir / f"campaign-{name}.log"
            cmd = [
                str(bdir / f"fuzz_{name}"),
                f"-runs={a.runs}",
                "-timeout=20",
                "-rss_limit_mb=2048",
                "-print_final_stats=1",
                f"-max_len={MAX_LEN.get(name, 1024)}",
                f"-artifact_prefix={art}/",
                str(corpus),
                str(ROOT / "fuzz" / "corpus" / name),
            ]
            d = ROOT / "fuzz" / "dict" / f"{name}.dict"
            if d.exists():
                cmd.insert(1, f"-dict={d}")
            with log.open("wb") as fh:
                running[name] = (
                    subprocess.Popen(cmd, stdout=fh, stderr=subprocess.STDOUT),
                    time.monotonic(),
                    log,
                )
            print(f"fuzz: {name} started ({a.runs} runs)", file=sys.stderr)
        time.sleep(1.0)
        now = time.monotonic()
        if now - last_report >= 60.0:
            last_report = now
            for name, (_, t0, log) in running.items():
                n = last_count(log)
                rate = n / max(now - t0, 1e-9)
                eta = (a.runs - n) / rate if rate > 0 else float("inf")
                print(
                    f"fuzz: {name}: {n} execs ({100.0 * n / a.runs:.1f} %), {rate:.0f}/s, "
                    f"~{eta / 60:.0f} min left",
                    file=sys.stderr,
                )
        for name in [k for k, (p, _, _) in running.items() if p.poll() is not None]:
            p, t0, log = running.pop(name)
            text = log.read_text(errors="replace")
            stat = dict(re.findall(r"^stat::(\w+):\s+(\d+)", text, flags=re.M))
            arts = [f.name for f in (bdir / "artifacts" / name).iterdir()]
            secs = time.monotonic() - t0
            execs = int(stat.get("number_of_executed_units", last_count(log)))
            results[name] = {
                "execs": execs,
                "crashes": len(arts) if arts else int(p.returncode != 0),
                "exit_code": p.returncode,
                "seconds": round(secs, 1),
                "execs_per_s": round(execs / secs) if secs > 0 else None,
                "new_units": int(stat.get("new_units_added", 0)),
                "artifacts": arts,
            }
            print(
                f"fuzz: {name} done: {execs} execs, {results[name]['crashes']} crashes, "
                f"{secs:.0f} s",
                file=sys.stderr,
            )
    print(json.dumps({"runs_per_harness": a.runs, "harnesses": results}, indent=1))
    return 1 if any(r["crashes"] for r in results.values()) else 0


if __name__ == "__main__":
    sys.exit(main())

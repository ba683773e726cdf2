"""python -m odo_tools.gap.bench (make bench-gap): how long a 10-run diagnosis takes.

Generates a fixed set of development cases (a world of the blind check, a seed and case
numbers), diagnoses each in every evidence mode the blind check uses, and prints JSON: per
case and mode the wall and CPU seconds of `diagnose` (imports excluded: each code version runs
in its own process, warmed up on scipy's lazy imports; the CPU includes the worker processes of
its independent fits, gap/par.py, one per available core), the verdict, and medians and maxima.

With `--ref REV` the same diagnoses also run on the package as it was at git revision REV
(extracted with `git archive` into a temporary folder, run with the same data and libodosim),
interleaved case by case with the current code so that the shared machine's load falls on both
alike; the figures are then the ratios ref / current (wall and CPU) per diagnosis and over the
whole set, and whether every number of the two reports agrees to --rtol (relative; 0: bit for
bit): the speed-ups are meant to change nothing. Timing is printed, never asserted.
"""

from __future__ import annotations

import argparse
import io
import json
import math
import os
import subprocess
import sys
import tarfile
import tempfile
import time
from pathlib import Path

import numpy as np

from . import par

# a diagnosis per mode in a fresh interpreter: works on any revision that has diagnose()
CHILD = r"""
import json, resource, sys, time
import scipy.optimize, scipy.signal  # lazy imports the first diagnosis would otherwise pay
from pathlib import Path
from odo_tools.gap.diagnose import diagnose
real, modes = Path(sys.argv[1]), sys.argv[2].split(",")

def cpu():  # this process and its finished workers (gap/par.py)
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return time.process_time() + r.ru_utime + r.ru_stime

out = {}
for m in modes:
    w0, c0 = time.perf_counter(), cpu()
    rep = diagnose(real, real / "robot.json", 0.5, 1, m)
    w, c = time.perf_counter() - w0, cpu() - c0
    rep.context = None
    out[m] = {"wall_s": w, "cpu_s": c, "report": rep.to_dict()}
print(json.dumps(out, default=str))
"""

# development seeds' cases that were slow before the hot-loop work (independent world): clappers
# at 10 and 20 ms, sets at 10 and 20 ms, a LabMate at 10 ms
DEFAULT_CASES = "7:14,7:17,7:21,8:2,8:20,7:15"


def _package_root() -> Path:
    return Path(__file__).resolve().parents[2]  # .../tools/python


def extract_ref(rev: str, repo: Path, dest: Path) -> Path:
    """The odo_tools package at git revision `rev` under dest/tools/python (GapInputError-free:
    a bad revision is a usage error of this developer tool, raised as SystemExit)."""
    r = subprocess.run(
        ["git", "-C", str(repo), "archive", "--format=tar", rev, "tools/python/odo_tools"],
        capture_output=True,
    )
    if r.returncode != 0:
        raise SystemExit(f"error: --ref {rev}: {r.stderr.decode().strip()}")
    with tarfile.open(fileobj=io.BytesIO(r.stdout)) as tf:
        if hasattr(tarfile, "data_filter"):  # Python >= 3.11.4
            tf.extractall(dest, filter="data")
        else:  # our own repository's archive
            tf.extractall(dest)
    return dest / "tools" / "python"


def run_child(pkg: Path, real: Path, modes: list[str], repo: Path) -> dict:
    env = dict(os.environ, PYTHONPATH=str(pkg), ODO_SOURCE_DIR=str(repo))
    r = subprocess.run(
        [sys.executable, "-c", CHILD, str(real), ",".join(modes)],
        capture_output=True,
        text=True,
        env=env,
    )
    if r.returncode != 0:
        raise SystemExit(f"error: diagnosis of {real} failed ({pkg}):\n{r.stderr[-2000:]}")
    return json.loads(r.stdout.splitlines()[-1])


def differences(a, b, rtol: float, path: str = "") -> list[str]:
    """Where two report dicts differ: strings and structure exactly, numbers to rtol."""
    if isinstance(a, dict) and isinstance(b, dict):
        out = [f"{path}: keys {sorted(set(a) ^ set(b))}"] if set(a) != set(b) else []
        for k in sorted(set(a) & set(b)):
            if k != "elapsed_s":
                out += differences(a[k], b[k], rtol, f"{path}.{k}")
        return out
    if isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            return [f"{path}: {len(a)} vs {len(b)} items"]
        pairs = enumerate(zip(a, b, strict=True))
        return [d for i, (x, y) in pairs for d in differences(x, y, rtol, f"{path}[{i}]")]
    num = (int, float)
    if isinstance(a, num) and isinstance(b, num) and not isinstance(a, bool):
        if a == b or (math.isnan(a) and math.isnan(b)):
            return []
        return [] if abs(a - b) <= rtol * max(abs(a), abs(b)) else [f"{path}: {a!r} vs {b!r}"]
    return [] if a == b else [f"{path}: {a!r} vs {b!r}"]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        prog="python -m odo_tools.gap.bench",
        description=__doc__.split("\n\n")[1] + "\n\n" + __doc__.split("\n\n")[2],
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    ap.add_argument(
        "--world",
        choices=("independent", "sim"),
        default="independent",
        help="which world generates the cases (default independent)",
    )
    ap.add_argument(
        "--seed",
        type=int,
        default=7,
        help="seed of the case draw for case numbers "
        "given without one (default 7, a development seed)",
    )
    ap.add_argument(
        "--cases",
        default=DEFAULT_CASES,
        help="cases, comma separated: K (case K of --seed) or S:K (case K of seed S; "
        f"default {DEFAULT_CASES})",
    )
    ap.add_argument(
        "--ref",
        metavar="REV",
        help="also time the package at this git revision and compare the reports",
    )
    ap.add_argument(
        "--rtol",
        type=float,
        default=1e-6,
        help="relative tolerance of the report comparison (default 1e-6)",
    )
    a = ap.parse_args(argv)
    try:
        ks = [
            (int(x.split(":")[0]), int(x.split(":")[1])) if ":" in x else (a.seed, int(x))
            for x in a.cases.split(",")
            if x.strip()
        ]
    except (ValueError, IndexError):
        ap.error(f"--cases {a.cases!r}: expected K or S:K items separated by commas")
    if not ks or min(min(sk) for sk in ks) < 0 or a.seed < 0 or a.rtol < 0:
        ap.error("--cases, --seed and --rtol must be non-negative (and --cases non-empty)")
    from ..validation import case_seed
    from ..validation.blind import modes_of, world
    from .repo import source_dir

    repo = source_dir()
    draw, simulate = world(a.world)
    cases = {}
    for seed in sorted({s for s, _ in ks}):
        rng = np.random.default_rng(seed)  # the blind check's draw: cases in order
        for k in range(max(k for s, k in ks if s == seed) + 1):
            c = draw(rng, k)
            if (seed, k) in ks:
                cases[(seed, k)] = c
    rows = []
    with tempfile.TemporaryDirectory(prefix="odo-gap-bench-") as tmp:
        ref_pkg = extract_ref(a.ref, repo, Path(tmp) / "ref") if a.ref else None
        for n, (seed, k) in enumerate(ks):
            c = cases[(seed, k)]
            c.setdefault("world", a.world)
            real = Path(tmp) / f"case-{seed}-{k:03d}"
            t0 = time.perf_counter()
            simulate(c, real, case_seed(seed, k))
            modes = list(modes_of(c["vehicle"]))
            print(
                f"case {seed}:{k}: {c['vehicle']} {c.get('tick_ms', '')} ms, generated in "
                f"{time.perf_counter() - t0:.1f} s; diagnosing in {', '.join(modes)}",
                file=sys.stderr,
                flush=True,
            )
            # alternate which version goes first, so that a trend in the machine's load does
            # not favour one
            order = ["new", "ref"] if ref_pkg and n % 2 else ["ref", "new"] if ref_pkg else ["new"]
            got = {}
            for v in order:
                got[v] = run_child(_package_root() if v == "new" else ref_pkg, real, modes, repo)
            for m in modes:
                new = got["new"][m]
                row = {
                    "case": f"{seed}:{k}",
                    "vehicle": c["vehicle"],
                    "tick_ms": c.get("tick_ms"),
                    "mode": m,
                    "wall_s": round(new["wall_s"], 2),
                    "cpu_s": round(new["cpu_s"], 2),
                    "verdict": new["report"].get("verdict", {}).get("effect"),
                }
                if ref_pkg:
                    ref = got["ref"][m]
                    diff = differences(ref["report"], new["report"], a.rtol)
                    row.update(
                        ref_wall_s=round(ref["wall_s"], 2),
                        ref_cpu_s=round(ref["cpu_s"], 2),
                        speedup_cpu=round(ref["cpu_s"] / max(new["cpu_s"], 1e-9), 2),
                        speedup_wall=round(ref["wall_s"] / max(new["wall_s"], 1e-9), 2),
                        same=not diff,
                        differences=diff[:5],
                    )
                rows.append(row)
                print(
                    f"  {m}: {new['wall_s']:.1f} s wall, {new['cpu_s']:.1f} s CPU"
                    + (
                        f" (ref {row['ref_wall_s']:.1f} s wall, {row['ref_cpu_s']:.1f} s CPU: "
                        f"x{row['speedup_wall']:.2f} wall, x{row['speedup_cpu']:.2f} CPU, "
                        f"{'same report' if row['same'] else 'REPORTS DIFFER'})"
                        if ref_pkg
                        else ""
                    ),
                    file=sys.stderr,
                    flush=True,
                )
    summ = {"diagnoses": len(rows)}
    for key in ("wall_s", "cpu_s") + (("ref_wall_s", "ref_cpu_s") if a.ref else ()):
        v = [r[key] for r in rows]
        summ[key] = {
            "median": round(float(np.median(v)), 2),
            "max": round(max(v), 2),
            "sum": round(sum(v), 2),
        }
    if a.ref:
        summ["speedup_cpu_total"] = round(summ["ref_cpu_s"]["sum"] / summ["cpu_s"]["sum"], 2)
        summ["speedup_cpu_median"] = round(float(np.median([r["speedup_cpu"] for r in rows])), 2)
        summ["speedup_wall_total"] = round(summ["ref_wall_s"]["sum"] / summ["wall_s"]["sum"], 2)
        summ["all_reports_same"] = all(r["same"] for r in rows)
    print(
        json.dumps(
            {
                "world": a.world,
                "ref": a.ref,
                "rtol": a.rtol,
                "cores": par.available(),  # the worker processes a diagnosis's fits use
                "summary": summ,
                "diagnoses": rows,
            },
            indent=1,
        )
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())

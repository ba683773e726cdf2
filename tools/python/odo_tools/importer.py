"""odo-import: turn other robots' recordings into the project's log contracts.

`odo-import ticks-csv --ticks F --robot R.json [--truth F] --out DIR` reads a plain CSV of wheel
ticks and writes DIR/run-<dir>-NN.log (WHEEL_COUNTS_A frames via can/odometry.dbc, the counters
accumulated and wrapped at the robot's counter_bits exactly as an HCTL-style decoder register
would hold them) and, with --truth, DIR/run-<dir>-NN.truth.csv (t_s, a_x_mm, a_y_mm,
a_theta_deg) plus DIR/returns.csv (000 Eq. 3.1: the truth's end pose relative to its start).

Ticks CSV: a header naming the columns, or none with --columns. Needed: time (s), left and right
ticks; --cumulative if they are running totals rather than per-cycle increments. The cycle must be
the robot's tick_ms (odo-gap checks it): the robot JSON states the cycle explicitly, so a 50 ms
robot gets "tick_ms": 50 rather than a resampling that would invent counts.
"""

from __future__ import annotations

import argparse
import csv
import math
import os
import shutil
import sys
from pathlib import Path

import numpy as np

from .gap.errors import GapInputError
from .gap.io import encode_payload, read_robot, write_candump


def read_table(path: Path, columns: list[str] | None) -> dict[str, np.ndarray]:
    try:
        f = path.open(newline="")
    except OSError as e:
        raise GapInputError(path, f"cannot read: {e.strerror}") from None
    with f:
        rows = list(csv.reader(f))
    if not rows:
        raise GapInputError(path, "empty file")
    start = 0
    if columns is None:
        columns = [c.strip() for c in rows[0]]
        start = 1
    data = []
    for i, r in enumerate(rows[start:], start=start + 1):
        if not r or not "".join(r).strip():
            continue
        if len(r) < len(columns):
            raise GapInputError(path, f"{len(r)} fields, expected {len(columns)}", i)
        try:
            v = [float(x) for x in r[: len(columns)]]
        except ValueError:
            raise GapInputError(path, f"not a number in {r[: len(columns)]}", i) from None
        if not all(math.isfinite(x) for x in v):
            raise GapInputError(path, "NaN or infinite value", i)
        if (
            data
            and v[columns.index("time") if "time" in columns else 0]
            <= data[-1][0 if "time" not in columns else columns.index("time")]
        ):
            raise GapInputError(path, "time does not increase", i)
        data.append(v)
    a = np.asarray(data)
    return {c: a[:, k] for k, c in enumerate(columns)}


def import_ticks(
    ticks: Path,
    robot_path: Path,
    out_base: Path,
    truth: Path | None = None,
    columns: list[str] | None = None,
    truth_columns: list[str] | None = None,
    cumulative: bool = False,
    truth_units: str = "m,rad",
) -> None:
    """One run: out_base.log (+ .truth.csv). Time starts at the first row."""
    robot = read_robot(robot_path)
    if robot.n_trucks != 1:
        raise GapInputError(robot_path, "ticks-csv imports a one-truck (labmate-like) robot")
    tb = read_table(ticks, columns)
    for c in ("time", "left", "right"):
        if c not in tb:
            raise GapInputError(ticks, f"no '{c}' column (have {', '.join(tb)})", 1)
    t = tb["time"] - tb["time"][0]
    dt = np.diff(t)
    if dt.size and abs(np.median(dt) - robot.tick_s) > 0.05 * robot.tick_s:
        raise GapInputError(
            ticks,
            f"cycle {np.median(dt) * 1e3:.1f} ms but {robot_path} says "
            f"tick_ms {robot.tick_s * 1e3:g}: set tick_ms to the recording's cycle",
        )
    bits = robot.trucks[0]["counter_bits"]
    cnt = {}
    for w in ("left", "right"):
        v = np.rint(tb[w]).astype(np.int64)
        cum = v - v[0] if cumulative else np.cumsum(np.concatenate([[0], v[1:]]))
        if robot.trucks[0]["invert_" + w]:
            cum = -cum
        cnt[w] = cum % (1 << bits)  # the decoder register wraps
    n = t.size
    pay = encode_payload(
        0x110,
        {
            "LeftCount": cnt["left"],
            "RightCount": cnt["right"],
            "Seq": np.arange(n) % 256,
            "Status": np.zeros(n),
        },
    )
    write_candump(out_base.with_suffix(".log"), [(t, 0x110, pay)])
    if truth is not None:
        tt = read_table(truth, truth_columns)
        for c in ("time", "x", "y", "theta"):
            if c not in tt:
                raise GapInputError(truth, f"no '{c}' column (have {', '.join(tt)})", 1)
        lin, ang = truth_units.split(",")
        ks = {"m": 1000.0, "mm": 1.0}[lin]
        x, y = tt["x"] * ks, tt["y"] * ks
        th = tt["theta"] if ang == "rad" else np.radians(tt["theta"])
        with out_base.with_suffix(".truth.csv").open("w") as f:
            f.write("t_s,a_x_mm,a_y_mm,a_theta_deg\n")
            for r in zip(tt["time"] - tb["time"][0], x, y, np.degrees(np.unwrap(th)), strict=False):
                f.write("{:.4f},{:.4f},{:.4f},{:.6f}\n".format(*r))


def returns_row(truth_csv: Path) -> tuple[float, float, float]:
    """End pose relative to the start pose (000 Eq. 3.1 with the start as origin)."""
    a = np.loadtxt(truth_csv, delimiter=",", skiprows=1)
    x0, y0, th0 = a[0, 1], a[0, 2], math.radians(a[0, 3])
    dx, dy = a[-1, 1] - x0, a[-1, 2] - y0
    c, s = math.cos(th0), math.sin(th0)
    return c * dx + s * dy, -s * dx + c * dy, (a[-1, 3] - a[0, 3] + 180.0) % 360.0 - 180.0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        prog="odo-import", description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    sub = ap.add_subparsers(dest="cmd", required=True)
    t = sub.add_parser(
        "ticks-csv", help="plain CSV of wheel ticks (+ truth) -> candump + truth CSV"
    )
    t.add_argument("--ticks", required=True, nargs="+", help="one CSV per run")
    t.add_argument("--robot", required=True)
    t.add_argument("--truth", nargs="+", help="truth CSVs (same order; may be the ticks files)")
    t.add_argument(
        "--columns",
        help="comma list naming the ticks columns of header-less files "
        "(time,left,right; other names ignored), e.g. time,x,y,theta,right,left",
    )
    t.add_argument("--truth-columns", help="same for the truth files (time,x,y,theta)")
    t.add_argument("--truth-units", default="m,rad", help="m|mm,rad|deg (default m,rad)")
    t.add_argument("--cumulative", action="store_true", help="ticks are running totals")
    t.add_argument("--directions", help="comma list of run directions (cw/ccw/fwd), one per run")
    t.add_argument("--out", required=True)
    a = ap.parse_args(argv)
    out = Path(a.out)
    tmp = out.with_name(out.name + f".tmp.{os.getpid()}")
    shutil.rmtree(tmp, ignore_errors=True)
    tmp.mkdir(parents=True)
    try:
        dirs = a.directions.split(",") if a.directions else ["fwd"] * len(a.ticks)
        if len(dirs) != len(a.ticks) or (a.truth and len(a.truth) != len(a.ticks)):
            ap.error("--ticks, --truth and --directions need one entry per run")
        cols = a.columns.split(",") if a.columns else None
        tcols = a.truth_columns.split(",") if a.truth_columns else cols
        seen: dict[str, int] = {}
        rets = []
        for i, f in enumerate(a.ticks):
            d = dirs[i]
            seen[d] = seen.get(d, 0) + 1
            base = tmp / f"run-{d}-{seen[d]:02d}"
            tr = Path(a.truth[i]) if a.truth else None
            import_ticks(Path(f), Path(a.robot), base, tr, cols, tcols, a.cumulative, a.truth_units)
            if tr is not None:
                x, y, th = returns_row(base.with_suffix(".truth.csv"))
                rets.append(f"{seen[d]},{d},{x:.3f},{y:.3f},{th:.4f},nan,nan,nan")
            print(f"odo-import: {f} -> {base.name}", file=sys.stderr)
        if rets:
            (tmp / "returns.csv").write_text(
                "run,direction,x_abs_mm,y_abs_mm,theta_abs_deg,x_calc_mm,y_calc_mm,theta_calc_deg\n"
                + "\n".join(rets)
                + "\n"
            )
        shutil.copy(a.robot, tmp / "robot.json")
        if out.exists():
            shutil.rmtree(out)
        tmp.rename(out)
        return 0
    except GapInputError as e:
        shutil.rmtree(tmp, ignore_errors=True)
        print(f"odo-import: {e}", file=sys.stderr)
        return 1
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


if __name__ == "__main__":
    sys.exit(main())

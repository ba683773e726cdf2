"""odo-import: turn other robots' recordings into the project's log contracts.

`odo-import ros2-bag --bag B... --joints L,R [--truth-topic T] --robot R.json --out OUT` reads
ROS 2 bags (sensor_msgs/JointState wheel positions, nav_msgs/Odometry or geometry_msgs/PoseStamped
truth) with the rosbags package, no ROS install; `odo-import ros2-bag --help` for details.

`odo-import ticks-csv --ticks F|DIR... --robot R.json --out OUT` reads plain CSVs of wheel ticks
(one run per file; a folder stands for its *.csv files but metadata.csv) and writes per run
run-<dir>-NN.log (WHEEL_COUNTS_A frames via can/odometry.dbc, the counters accumulated and
wrapped at the robot's counter_bits exactly as the decoder register would hold them) and, with
truth, run-<dir>-NN.truth.csv (t_s, a_x_mm, a_y_mm, a_theta_deg) plus returns.csv (000 Eq. 3.1:
the truth's end pose relative to its start, and the calculated columns: the firmware's own step
run over the imported counts through libodosim, so returns.csv feeds odo-calib umbmark and the
plots directly). Several folders in one call: each goes to OUT/<folder name>/.

Columns: a header row mapped with --map (left=ticks_left,right=ticks_right,time=t_s, and
x=,y=,theta= for truth in the same file), or no header with --columns naming them in order.
Needed: time (s), left and right. Units: --ticks-unit counts (default), rad (wheel angle) or m
(distance rolled), converted with the robot's geometry; --cumulative if they are running totals
(joint positions always are) rather than per-cycle increments. The cycle must be the robot's
tick_ms: the robot JSON states the cycle, so a 50 ms robot gets "tick_ms": 50 rather than a
resampling that would invent counts.

Every bad input (mismatched ticks/truth lengths, time going backwards, a map naming a missing
column, a cycle or robot that does not match, a file that is not UTF-8 text) is one line naming
the file and line, exit code 1, and nothing written. OUT follows the output rule
(odo_tools/outpath.py): built in a temporary folder beside it and put into place at the end;
missing parents are created; an existing OUT must be empty or a previous odo-import output (its
.odo-manifest: only the files listed there are replaced or removed) unless --force, which writes
into it and removes nothing; OUT may not be an input nor lie inside an input folder.
"""

from __future__ import annotations

import argparse
import csv
import ctypes as C
import io
import math
import shutil
import sys
from pathlib import Path

import numpy as np

from .gap.errors import GapInputError
from .gap.io import encode_payload, read_robot, write_candump
from .outpath import OutDir, OutputError

RET_HEADER = "run,direction,x_abs_mm,y_abs_mm,theta_abs_deg,x_calc_mm,y_calc_mm,theta_calc_deg\n"


def parse_map(text: str | None) -> dict[str, str]:
    """--map left=a,right=b,time=c -> {'left': 'a', ...}."""
    out: dict[str, str] = {}
    if not text:
        return out
    for item in text.split(","):
        if "=" not in item:
            raise ValueError(f"--map: '{item}' is not role=column")
        role, col = (s.strip() for s in item.split("=", 1))
        if role not in ("time", "left", "right", "x", "y", "theta"):
            raise ValueError(f"--map: unknown role '{role}' (time, left, right, x, y, theta)")
        out[role] = col
    return out


def read_table(
    path: Path, columns: list[str] | None, mapping: dict[str, str] | None = None
) -> dict[str, np.ndarray]:
    """A CSV as role -> column: header-less with `columns`, else the header renamed by `mapping`."""
    try:
        raw = path.read_bytes()
    except OSError as e:
        raise GapInputError(path, f"cannot read: {e.strerror}") from None
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as e:
        line = raw[: e.start].count(b"\n") + 1
        raise GapInputError(path, f"not UTF-8 text (byte 0x{raw[e.start]:02x})", line) from None
    reader = csv.reader(io.StringIO(text, newline=""))
    try:
        rows = list(reader)
    except csv.Error as e:
        raise GapInputError(path, f"not a CSV table: {e}", reader.line_num) from None
    if not rows:
        raise GapInputError(path, "empty file")
    start = 0
    if columns is None:
        header = [c.strip() for c in rows[0]]
        start = 1
        mapping = mapping or {}
        for role, col in mapping.items():
            if col not in header:
                raise GapInputError(
                    path, f"--map {role}={col}: no column '{col}' (have {', '.join(header)})", 1
                )
        rename = {col: role for role, col in mapping.items()}
        columns = [rename.get(c, c) for c in header]
    ti = columns.index("time") if "time" in columns else None
    data: list[list[float]] = []
    for i, r in enumerate(rows[start:], start=start + 1):
        if not r or not "".join(r).strip():
            continue
        if len(r) < len(columns):
            raise GapInputError(path, f"{len(r)} fields, expected {len(columns)}", i)
        vals = []
        for c, x in zip(columns, r[: len(columns)], strict=True):
            try:
                v = float(x)
            except ValueError:
                if c in ("time", "left", "right", "x", "y", "theta"):
                    raise GapInputError(path, f"not a number in column {c}: {x!r}", i) from None
                v = math.nan  # a column nobody asked for (a label, a comment)
            if c in ("time", "left", "right", "x", "y", "theta") and not math.isfinite(v):
                raise GapInputError(path, f"NaN or infinite value in column {c}", i)
            vals.append(v)
        if ti is not None and data and vals[ti] <= data[-1][ti]:
            raise GapInputError(
                path, f"time {vals[ti]:g} does not increase (time goes backwards)", i
            )
        data.append(vals)
    if not data:
        raise GapInputError(path, "no data rows")
    a = np.asarray(data)
    return {c: a[:, k] for k, c in enumerate(columns)}


def to_counts(v: np.ndarray, unit: str, robot, cumulative: bool) -> np.ndarray:
    """Wheel data in `unit` -> cumulative decoder counts from 0 (rounded once, on the total)."""
    t = robot.trucks[0]
    cpr = 4.0 * t["encoder_lines"] * t["gear_ratio"]
    k = {
        "counts": 1.0,
        "rad": cpr / (2.0 * math.pi),
        "m": cpr / (math.pi * t["wheel_diameter_mm"] * 1e-3),
    }[unit]
    if cumulative:
        cum = (v - v[0]) * k
    else:
        cum = np.cumsum(np.concatenate([[0.0], v[1:]])) * k
    return np.rint(cum).astype(np.int64)


def firmware_track(robot_path: Path, raw: np.ndarray) -> np.ndarray:
    """The firmware's own step over raw counter readings (n, 2) -> poses (n, 3) mm, mm, rad."""
    from .gap.simlib import lib

    so = lib()
    fn = so.odosim_firmware_track
    fn.restype = C.c_int
    fn.argtypes = [
        C.c_char_p,
        C.POINTER(C.c_uint32),
        C.c_size_t,
        C.POINTER(C.c_double),
        C.c_char_p,
        C.c_size_t,
    ]
    r = np.ascontiguousarray(raw, dtype=np.uint32)
    out = np.zeros((r.shape[0], 3))
    err = C.create_string_buffer(512)
    rc = fn(
        str(robot_path).encode(),
        r.ctypes.data_as(C.POINTER(C.c_uint32)),
        r.shape[0],
        out.ctypes.data_as(C.POINTER(C.c_double)),
        err,
        len(err),
    )
    if rc != 0:
        raise GapInputError(robot_path, err.value.decode(errors="replace"))
    return out


def import_ticks(
    ticks: Path,
    robot_path: Path,
    out_base: Path,
    truth: Path | None = None,
    columns: list[str] | None = None,
    truth_columns: list[str] | None = None,
    cumulative: bool = False,
    truth_units: str = "m,rad",
    mapping: dict[str, str] | None = None,
    ticks_unit: str = "counts",
) -> tuple[float, float, float] | None:
    """One run from CSV: out_base.log (+ .truth.csv). Time starts at the first row. Returns the
    firmware's end pose (x mm, y mm, theta deg) when there is truth, for returns.csv."""
    tb = read_table(ticks, columns, mapping)
    tt = None
    src = ticks
    if truth is not None and not (truth == ticks and truth_columns == columns):
        tt = read_table(truth, truth_columns, mapping)
        src = truth
    elif all(c in tb for c in ("x", "y", "theta")) or truth is not None:
        tt = tb
    hint = "--map" if columns is None else "--columns"
    return write_run(
        tb,
        tt,
        robot_path,
        out_base,
        ticks,
        src,
        cumulative,
        truth_units,
        ticks_unit,
        hint,
        line_offset=0 if columns is not None else 1,
    )


def write_run(
    tb: dict[str, np.ndarray],
    tt: dict[str, np.ndarray] | None,
    robot_path: Path,
    out_base: Path,
    ticks: Path | str,
    src: Path | str,
    cumulative: bool,
    truth_units: str,
    ticks_unit: str,
    hint: str,
    line_offset: int = 0,
) -> tuple[float, float, float] | None:
    """Write one run from tables (role -> array): the log, the truth track, the firmware's end
    pose (returned when there is truth). `ticks`/`src` name the sources in messages."""
    robot = read_robot(robot_path)
    if robot.n_trucks != 1:
        raise GapInputError(robot_path, "odo-import writes a one-truck (labmate-like) robot")
    for c in ("time", "left", "right"):
        if c not in tb:
            raise GapInputError(
                ticks, f"no '{c}' column (have {', '.join(tb)}; name it with {hint})", 1
            )
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
        cum = to_counts(tb[w], ticks_unit, robot, cumulative or ticks_unit != "counts")
        step = np.abs(np.diff(cum))
        lim = robot.described["max_wheel_speed_mm_s"] * robot.tick_s / robot.mm_per_count(0)
        if step.size and step.max() > lim:
            i = int(np.argmax(step > lim)) + 2
            raise GapInputError(
                ticks,
                f"{w}: {int(step.max())} counts in one cycle, faster than the robot's "
                f"max_wheel_speed_mm_s (wrong --ticks-unit or --cumulative?)",
                i + line_offset,
            )
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
    if tt is None:
        return None
    for c in ("time", "x", "y", "theta"):
        if c not in tt:
            raise GapInputError(src, f"no '{c}' column (have {', '.join(tt)})", 1)
    if tt is not tb and tt["time"].size != n:
        raise GapInputError(
            src,
            f"{tt['time'].size} truth rows but {ticks} has {n} tick rows "
            "(mismatched ticks/truth lengths)",
        )
    lin, ang = truth_units.split(",")
    ks = {"m": 1000.0, "mm": 1.0}[lin]
    x, y = tt["x"] * ks, tt["y"] * ks
    th = tt["theta"] if ang == "rad" else np.radians(tt["theta"])
    with out_base.with_suffix(".truth.csv").open("w") as f:
        f.write("t_s,a_x_mm,a_y_mm,a_theta_deg\n")
        for r in zip(tt["time"] - tb["time"][0], x, y, np.degrees(np.unwrap(th)), strict=True):
            f.write("{:.4f},{:.4f},{:.4f},{:.6f}\n".format(*r))
    raw = np.column_stack([cnt["left"], cnt["right"]])
    pose = firmware_track(robot_path, raw)
    return float(pose[-1, 0]), float(pose[-1, 1]), math.degrees(pose[-1, 2])


def returns_row(truth_csv: Path) -> tuple[float, float, float]:
    """End pose relative to the start pose (000 Eq. 3.1 with the start as origin)."""
    a = np.loadtxt(truth_csv, delimiter=",", skiprows=1)
    x0, y0, th0 = a[0, 1], a[0, 2], math.radians(a[0, 3])
    dx, dy = a[-1, 1] - x0, a[-1, 2] - y0
    c, s = math.cos(th0), math.sin(th0)
    return c * dx + s * dy, -s * dx + c * dy, (a[-1, 3] - a[0, 3] + 180.0) % 360.0 - 180.0


def expand(items: list[str]) -> list[tuple[str | None, list[Path]]]:
    """Files and folders -> [(folder name or None, run files)]; a folder is its *.csv files."""
    out: list[tuple[str | None, list[Path]]] = []
    loose: list[Path] = []
    for it in items:
        p = Path(it)
        if p.is_dir():
            files = sorted(f for f in p.glob("*.csv") if f.name != "metadata.csv")
            if not files:
                raise GapInputError(p, "a folder without run CSV files")
            out.append((p.resolve().name, files))
        else:
            loose.append(p)
    if loose:
        out.insert(0, (None, loose))
    return out


def import_set(
    a: argparse.Namespace, files: list[Path], truths: list[Path] | None, dst: Path, label: str
):
    cols = a.columns.split(",") if a.columns else None
    tcols = a.truth_columns.split(",") if a.truth_columns else cols
    mapping = parse_map(a.map)
    dirs = a.directions.split(",") if a.directions else ["fwd"] * len(files)
    if len(dirs) != len(files):
        raise GapInputError(
            files[0].parent, f"--directions has {len(dirs)} entries for {len(files)} runs"
        )
    seen: dict[str, int] = {}
    rets = []
    dst.mkdir(exist_ok=True)
    for i, f in enumerate(files):
        d = dirs[i]
        seen[d] = seen.get(d, 0) + 1
        base = dst / f"run-{d}-{seen[d]:02d}"
        tr = truths[i] if truths else None
        calc = import_ticks(
            f,
            Path(a.robot),
            base,
            tr,
            cols,
            tcols,
            a.cumulative,
            a.truth_units,
            mapping,
            a.ticks_unit,
        )
        if calc is not None:
            x, y, th = returns_row(base.with_suffix(".truth.csv"))
            cx, cy, cth = calc
            cth = (cth + 180.0) % 360.0 - 180.0
            rets.append(f"{seen[d]},{d},{x:.3f},{y:.3f},{th:.4f},{cx:.3f},{cy:.3f},{cth:.4f}")
        print(f"odo-import: {f} -> {label}/{base.name}", file=sys.stderr)
    if rets:
        (dst / "returns.csv").write_text(RET_HEADER + "\n".join(rets) + "\n")
    shutil.copy(a.robot, dst / "robot.json")


def rosbag_doc() -> str:
    from . import rosbag_import

    return rosbag_import.__doc__ or ""


def import_bags(a: argparse.Namespace, dst: Path) -> None:
    """One run per bag, written like ticks-csv's (the wheel joints in rad, cumulative)."""
    from .rosbag_import import read_bag

    robot = read_robot(a.robot)
    joints = tuple(j.strip() for j in a.joints.split(","))
    if len(joints) != 2 or not all(joints):
        raise ValueError("--joints: give LEFT,RIGHT")
    dirs = a.directions.split(",") if a.directions else ["fwd"] * len(a.bag)
    if len(dirs) != len(a.bag):
        raise ValueError(f"--directions has {len(dirs)} entries for {len(a.bag)} bags")
    dst.mkdir(exist_ok=True)
    seen: dict[str, int] = {}
    rets = []
    for i, bag in enumerate(a.bag):
        d = dirs[i]
        seen[d] = seen.get(d, 0) + 1
        base = dst / f"run-{d}-{seen[d]:02d}"
        tb, tt = read_bag(Path(bag), a.joint_topic, joints, a.truth_topic, robot.tick_s)
        calc = write_run(
            tb,
            tt,
            Path(a.robot),
            base,
            f"{bag} {a.joint_topic}",
            f"{bag} {a.truth_topic}",
            True,
            "m,rad",
            "rad",
            "--joints",
        )
        if calc is not None:
            x, y, th = returns_row(base.with_suffix(".truth.csv"))
            cx, cy, cth = calc
            cth = (cth + 180.0) % 360.0 - 180.0
            rets.append(f"{seen[d]},{d},{x:.3f},{y:.3f},{th:.4f},{cx:.3f},{cy:.3f},{cth:.4f}")
        print(f"odo-import: {bag} -> {base.name}", file=sys.stderr)
    if rets:
        (dst / "returns.csv").write_text(RET_HEADER + "\n".join(rets) + "\n")
    shutil.copy(a.robot, dst / "robot.json")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        prog="odo-import", description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    sub = ap.add_subparsers(dest="cmd", required=True)
    t = sub.add_parser(
        "ticks-csv", help="plain CSV of wheel ticks (+ truth) -> candump + truth CSV"
    )
    t.add_argument("--ticks", required=True, nargs="+", help="CSV files (one per run) or folders")
    t.add_argument("--robot", required=True)
    t.add_argument("--truth", nargs="+", help="truth CSVs (same order; may be the ticks files)")
    t.add_argument(
        "--columns",
        help="comma list naming the columns of header-less files in order "
        "(time,left,right[,x,y,theta]; other names ignored), e.g. time,x,y,theta,right,left",
    )
    t.add_argument(
        "--map",
        help="roles of named header columns, e.g. left=ticks_left,right=ticks_right,time=t_s "
        "(and x=,y=,theta= when the truth is in the same file)",
    )
    t.add_argument("--truth-columns", help="same as --columns, for the truth files")
    t.add_argument("--truth-units", default="m,rad", help="m|mm,rad|deg (default m,rad)")
    t.add_argument(
        "--ticks-unit",
        default="counts",
        choices=("counts", "rad", "m"),
        help="wheel data in decoder counts (default), wheel angle in rad or distance in m "
        "(joint positions: cumulative)",
    )
    t.add_argument("--cumulative", action="store_true", help="ticks are running totals")
    t.add_argument("--directions", help="comma list of run directions (cw/ccw/fwd), one per run")
    t.add_argument("--out", required=True, help="output folder (several input folders: one each)")
    t.add_argument("--force", action="store_true", help="write into a non-empty foreign folder")
    b = sub.add_parser(
        "ros2-bag",
        help="ROS 2 bags (JointState wheels + Odometry/PoseStamped truth) -> candump + truth CSV",
        description=rosbag_doc(),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    b.add_argument("--bag", required=True, nargs="+", help="one bag (folder or .mcap/.db3) per run")
    b.add_argument("--robot", required=True)
    b.add_argument("--joint-topic", default="/joint_states", help="JointState topic")
    b.add_argument(
        "--joints", required=True, help="LEFT,RIGHT wheel joint names, e.g. wheel_left,wheel_right"
    )
    b.add_argument("--truth-topic", help="nav_msgs/Odometry or geometry_msgs/PoseStamped topic")
    b.add_argument("--directions", help="comma list of run directions (cw/ccw/fwd), one per run")
    b.add_argument("--out", required=True, help="output folder")
    b.add_argument("--force", action="store_true", help="write into a non-empty foreign folder")
    a = ap.parse_args(argv)
    try:
        if a.cmd == "ticks-csv":
            if a.map and a.columns:
                ap.error("--map names header columns, --columns header-less ones: give one")
            check_truth_units(a.truth_units)
            srcs = [*a.ticks, *(a.truth or [])]
        else:
            srcs = list(a.bag)
        with OutDir(a.out, "odo-import", a.force, [*srcs, a.robot]) as out:
            if a.cmd == "ros2-bag":
                import_bags(a, out.tmp)
                return 0
            sets = expand(a.ticks)
            truths = [Path(p) for p in a.truth] if a.truth else None
            if truths is not None and (len(sets) != 1 or len(truths) != len(sets[0][1])):
                ap.error(
                    "--truth needs one file per --ticks file (folders: keep the truth in them)"
                )
            if len(sets) == 1:
                import_set(a, sets[0][1], truths, out.tmp, a.out)
            else:
                for name, files in sets:
                    sub = name or "files"
                    import_set(a, files, None, out.tmp / sub, f"{a.out}/{sub}")
        return 0
    except (GapInputError, OutputError, ValueError) as e:
        print(f"odo-import: {e}", file=sys.stderr)
        return 1
    except OSError as e:
        print(f"odo-import: {e.filename or ''}: {e.strerror or e}", file=sys.stderr)
        return 1


def check_truth_units(units: str) -> None:
    """--truth-units LIN,ANG with LIN m|mm and ANG rad|deg."""
    parts = units.split(",")
    if len(parts) != 2 or parts[0] not in ("m", "mm") or parts[1] not in ("rad", "deg"):
        raise ValueError(f"--truth-units must be m|mm,rad|deg (e.g. mm,deg), not '{units}'")


if __name__ == "__main__":
    sys.exit(main())

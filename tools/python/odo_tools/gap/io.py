"""Recorded data in: candump logs (decoded with the repo's DBC), truth CSVs, returns.csv, robot.

Every reader validates what it reads and raises GapInputError naming the file and line; nothing
here reads a scenario file (the diagnosis must not know the truth's effects).
"""

from __future__ import annotations

import csv
import json
import math
import re
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path

import numpy as np

from .errors import GapInputError
from .repo import source_dir

LINE_RE = re.compile(r"^\((\d+\.\d+)\)\s+(\S+)\s+([0-9A-Fa-f]{3,8})#([0-9A-Fa-f]*)$")
RUN_RE = re.compile(r"^run-(?P<dir>[a-z]+)-(?P<idx>\d+)\.log$")


@dataclass(frozen=True)
class SignalLayout:
    start: int
    length: int
    signed: bool
    scale: float
    offset: float


@lru_cache(maxsize=1)
def _dbc():
    import cantools

    return cantools.database.load_file(str(source_dir() / "can" / "odometry.dbc"))


def frame_id(name: str) -> int:
    """A frame's ID by its DBC message name (can/odometry.dbc is the only place IDs live)."""
    return int(_dbc().get_message_by_name(name).frame_id)


# the sensor frames the diagnosis reads, by DBC name
ID_WHEEL = {frame_id("WHEEL_COUNTS_A"): 0, frame_id("WHEEL_COUNTS_B"): 1}
ID_ROTARY = frame_id("LINK_ROTARY")
ID_LINEAR = frame_id("LINK_LINEAR")
# WHEEL_COUNTS Status bits (can/odometry.dbc; firmware ODO_WHEEL_STATUS_*_SKIPPED, which
# tests/python/test_can_dbc.py holds these equal to)
STATUS_LEFT_SKIPPED, STATUS_RIGHT_SKIPPED = 0x01, 0x02
FRAME_LEN = {
    fid: int(_dbc().get_message_by_frame_id(fid).length)
    for fid in (*ID_WHEEL, ID_ROTARY, ID_LINEAR)
}


@lru_cache(maxsize=1)
def dbc_layouts() -> dict[int, dict[str, SignalLayout]]:
    """Signal layouts of the sensor frames from can/odometry.dbc via cantools (the one contract)."""
    db = _dbc()
    out: dict[int, dict[str, SignalLayout]] = {}
    for fid in (*ID_WHEEL, ID_ROTARY, ID_LINEAR):
        msg = db.get_message_by_frame_id(fid)
        lay = {}
        for s in msg.signals:
            if s.byte_order != "little_endian":
                raise GapInputError(
                    "can/odometry.dbc", f"{msg.name}.{s.name}: expected little endian"
                )
            lay[s.name] = SignalLayout(
                s.start, s.length, s.is_signed, float(s.scale), float(s.offset)
            )
        out[fid] = lay
    return out


def decode_signal(payload: np.ndarray, s: SignalLayout) -> np.ndarray:
    """Vectorised little-endian extraction of one signal from uint64 payloads."""
    raw = (payload >> np.uint64(s.start)) & np.uint64((1 << s.length) - 1)
    v = raw.astype(np.int64)
    if s.signed:
        v = np.where(v >= (1 << (s.length - 1)), v - (1 << s.length), v)
    return v * s.scale + s.offset if (s.scale != 1.0 or s.offset != 0.0) else v


@dataclass
class Robot:
    path: str
    vehicle: str
    tick_s: float
    trucks: list[dict]
    linkage: dict = field(default_factory=dict)
    trailer: dict = field(default_factory=dict)
    raw: dict = field(default_factory=dict)
    described: dict = field(default_factory=dict)  # odosim_robot_describe: what the C parser read

    def mm_per_count(self, t: int) -> float:
        d = self.trucks[t]
        return math.pi * d["wheel_diameter_mm"] / (4.0 * d["encoder_lines"] * d["gear_ratio"])

    @property
    def n_trucks(self) -> int:
        return len(self.trucks)


def read_robot(path: str | Path) -> Robot:
    """A robot description (host_sim/robots/*.json schema): what the firmware believes.

    Parsed and validated by THE validator, host_sim/src/robot.c (its limits table and the
    firmware's odo_params_validate), through libodosim: Python keeps no limits of its own.
    """
    import ctypes as C

    from .simlib import lib

    path = Path(path)
    so = lib()
    fn = so.odosim_robot_describe
    fn.restype = C.c_void_p
    fn.argtypes = [C.c_char_p, C.c_char_p, C.c_size_t]
    err = C.create_string_buffer(1024)
    ptr = fn(str(path).encode(), err, len(err))
    if not ptr:
        why = err.value.decode(errors="replace")
        # the C message is "<path>: <field>: <why>"; GapInputError adds the path again
        prefix = f"{path}: "
        raise GapInputError(path, why[len(prefix) :] if why.startswith(prefix) else why)
    try:
        doc = json.loads(C.string_at(ptr).decode())
    finally:
        so.odosim_free(ptr)
    raw = json.loads(path.read_text())
    trucks = [
        {
            "wheel_diameter_mm": t["wheel_diameter_mm"],
            "wheelbase_mm": t["wheelbase_mm"],
            "encoder_lines": t["encoder_lines"],
            "gear_ratio": t["gear_ratio"],
            "counter_bits": int(t["counter_bits"]),
            "invert_left": bool(t["invert_left"]),
            "invert_right": bool(t["invert_right"]),
        }
        for t in doc["trucks"]
    ]
    r = Robot(str(path), doc["vehicle"], doc["tick_ms"] / 1000.0, trucks, raw=raw, described=doc)
    if "linkage" in doc:
        lk = doc["linkage"]
        r.linkage = {
            "length_mm": lk["length_mm"],
            "rotary_bits": int(lk["rotary_bits"]),
            "linear_resolution_mm": lk["linear_resolution_mm"],
            "range_mm": (float(lk["range_mm"][0]), float(lk["range_mm"][1])),
        }
    if "trailer" in doc:
        tr = doc["trailer"]
        r.trailer = {
            "hitch_offset_mm": tr["hitch_offset_mm"],
            "trailer_length_mm": tr["trailer_length_mm"],
            "rotary_bits": int(tr["rotary_bits"]),
        }
    return r


@dataclass
class SensorLog:
    """One run's sensor frames, one row per firmware tick (the WHEEL_COUNTS_A frames)."""

    path: str
    t_s: np.ndarray  # (n,)
    counts: np.ndarray  # (n, trucks, 2) raw counter values, [left, right]
    alpha_deg: np.ndarray | None = None  # (n,) linkage rotary A (clapper) / joint (set)
    beta_deg: np.ndarray | None = None
    l_mm: np.ndarray | None = None
    fd_skipped: int = 0  # CAN FD lines counted and skipped
    # (n, trucks, 2) bool: the decoder saw an illegal quadrature transition (a skipped state)
    # since the previous sample, Status bits 0/1 of WHEEL_COUNTS_A/B (can/odometry.dbc); False
    # on a tick whose frame was lost
    skipped: np.ndarray | None = None


def read_log(path: str | Path, robot: Robot) -> SensorLog:
    """Decode a candump -l log of sensor frames with the DBC; checks it against the robot.

    Lines are read by python-can's CanutilsLogReader (so python-can's trailing " R"/" T" and
    every form candump writes are accepted); CAN FD frames (another node's traffic on a mixed bus)
    are counted in SensorLog.fd_skipped and skipped, as the C reader does.
    """
    import can

    path = Path(path)
    try:
        lines = path.read_text().splitlines()
    except (OSError, UnicodeDecodeError) as e:
        raise GapInputError(path, f"cannot read log: {getattr(e, 'strerror', None) or e}") from None
    content = [i + 1 for i, ln in enumerate(lines) if ln.strip()]
    if not content:
        raise GapInputError(path, "empty log: no sensor frames")
    ts_l: list[float] = []
    ids_l: list[int] = []
    pay_l: list[int] = []
    fd = 0
    done = 0  # lines python-can has parsed
    try:
        for m in can.CanutilsLogReader(str(path)):
            done += 1
            if m.is_fd:
                fd += 1
                continue
            if m.is_error_frame or m.is_remote_frame:
                continue
            ts_l.append(m.timestamp)
            ids_l.append(m.arbitration_id | (0x80000000 if m.is_extended_id else 0))
            pay_l.append(int.from_bytes(bytes(m.data).ljust(8, b"\0")[:8], "little"))
    except Exception as e:  # python-can raises ValueError/IndexError on a malformed line
        line = content[min(done, len(content) - 1)]
        bad = lines[line - 1][:60]
        raise GapInputError(path, f"not a candump -l line: {bad!r} ({e})", line) from None
    if not ts_l:
        raise GapInputError(path, "no classic CAN frames (only CAN FD, error or remote frames)")
    ts = np.asarray(ts_l)
    ids = np.asarray(ids_l, dtype=np.int64)
    pay = np.asarray(pay_l, dtype=np.uint64)
    bad = np.nonzero(np.diff(ts) < 0)[0]
    if bad.size:
        raise GapInputError(path, "time goes backwards", int(bad[0]) + 2)
    lay = dbc_layouts()
    sel_a = ids == 0x110
    if not sel_a.any():
        raise GapInputError(
            path, "no WHEEL_COUNTS_A (0x110) frames: the wheel counts every mode needs"
        )
    t = ts[sel_a]
    dt = np.diff(t)
    if dt.size and (dt <= 0).any():
        raise GapInputError(
            path,
            "two WHEEL_COUNTS_A frames with the same time",
            int(np.nonzero(sel_a)[0][np.nonzero(dt <= 0)[0][0] + 1]) + 1,
        )
    if dt.size:
        med = float(np.median(dt))
        if abs(med - robot.tick_s) > 0.1 * robot.tick_s:
            raise GapInputError(
                path,
                f"frames every {med * 1e3:.1f} ms but {robot.path} says "
                f"tick_ms {robot.tick_s * 1e3:g}",
                1,
            )
        gap = np.nonzero(dt > 3.5 * med)[0]
        if gap.size:
            line = int(np.nonzero(sel_a)[0][gap[0] + 1]) + 1
            raise GapInputError(path, f"gap of {dt[gap[0]]:.3f} s in the wheel counts", line)
    n = t.size
    counts = np.zeros((n, robot.n_trucks, 2), dtype=np.int64)
    skipped = np.zeros((n, robot.n_trucks, 2), dtype=bool)
    for fid, tr in ID_WHEEL.items():
        sel = ids == fid
        if tr >= robot.n_trucks:
            if sel.any():
                raise GapInputError(
                    path,
                    f"frames of truck B (0x{fid:X}) but {robot.path} describes a {robot.vehicle}",
                    int(np.argmax(sel)) + 1,
                )
            continue
        if not sel.any():
            raise GapInputError(
                path,
                f"no WHEEL_COUNTS_B (0x{fid:X}) frames but {robot.path} "
                f"describes a {robot.vehicle}",
            )
        idx = _align(path, ts[sel], t, np.nonzero(sel)[0])
        bits = robot.trucks[tr]["counter_bits"]
        for w, name in enumerate(("LeftCount", "RightCount")):
            v = decode_signal(pay[sel], lay[fid][name]).astype(np.int64)
            if bits < 24 and (v >= (1 << bits)).any():
                raise GapInputError(
                    path,
                    f"count {int(v.max())} exceeds the robot's {bits}-bit counter",
                    int(np.nonzero(sel)[0][np.argmax(v >= (1 << bits))]) + 1,
                )
            wrap = 1 << min(bits, lay[fid][name].length)
            counts[:, tr, w] = np.round(_fill(v, idx, t, wrap)).astype(np.int64) % wrap
        status = decode_signal(pay[sel], lay[fid]["Status"]).astype(np.int64)
        on = idx >= 0
        for w, bit in enumerate((STATUS_LEFT_SKIPPED, STATUS_RIGHT_SKIPPED)):
            skipped[idx[on], tr, w] = (status[on] & bit) != 0
    log = SensorLog(str(path), t, counts, fd_skipped=fd, skipped=skipped)
    sel_r, sel_l = ids == ID_ROTARY, ids == ID_LINEAR
    if sel_r.any():
        idx = _align(path, ts[sel_r], t, np.nonzero(sel_r)[0])
        log.alpha_deg = _fill(decode_signal(pay[sel_r], lay[ID_ROTARY]["Alpha"]), idx, t, 360.0)
        log.beta_deg = _fill(decode_signal(pay[sel_r], lay[ID_ROTARY]["Beta"]), idx, t, 360.0)
    if sel_l.any():
        idx = _align(path, ts[sel_l], t, np.nonzero(sel_l)[0])
        log.l_mm = _fill(decode_signal(pay[sel_l], lay[ID_LINEAR]["Length"]), idx, t)
    return log


def _align(path: Path, t_frames: np.ndarray, t_ticks: np.ndarray, lines: np.ndarray) -> np.ndarray:
    """The tick each frame belongs to: the nearest WHEEL_COUNTS_A frame, within half a tick;
    -1 for a frame of a tick whose WHEEL_COUNTS_A frame was lost (_fill skips it).

    A robot's controllers put one tick's frames on the bus a little apart (the independent
    world stamps them a few hundred microseconds after each other, as a real bus does), and a
    bus loses a frame now and then: a tick without its WHEEL_COUNTS_A frame has no sample (the
    counters are cumulative, so its travel shows in the next tick) and its other frames are
    dropped with it. Only a log where most frames belong to no tick is refused."""
    n = t_ticks.size
    half = 0.5 * float(np.median(np.diff(t_ticks))) if n > 1 else 0.5
    j = np.searchsorted(t_ticks, t_frames)
    left, right = np.clip(j - 1, 0, n - 1), np.clip(j, 0, n - 1)
    closer_left = np.abs(t_frames - t_ticks[left]) <= np.abs(t_ticks[right] - t_frames)
    idx = np.where(closer_left, left, right)
    off = np.abs(t_ticks[idx] - t_frames) >= half
    if off.mean() > 0.5:
        raise GapInputError(
            path,
            "frame without a WHEEL_COUNTS_A frame of the same tick (most frames are half a tick "
            "or more from every one)",
            int(lines[np.argmax(off)]) + 1,
        )
    return np.where(off, -1, idx)


def _fill(v: np.ndarray, idx: np.ndarray, t: np.ndarray, period: float | None = None) -> np.ndarray:
    """Values per tick (times t). A tick whose frame the bus lost takes the value interpolated
    in time between its neighbours' frames, the shorter way round a counter's or an angle's
    `period` (a counter rounded to whole counts); before the first frame and after the last
    it holds the nearest. Holding the previous value instead put a whole tick of one truck's
    travel into the window that ended there and took it back from the next: a clapper with no
    effect on a bus losing 0.08 % of its frames read +/-7.5 mm in l, 500 times its noise, and
    linkage mode called it "unexplained" (independent world). Frames of no tick (idx -1,
    _align) are skipped."""
    keep = idx >= 0
    v, idx = np.asarray(v, dtype=float)[keep], idx[keep]
    n = t.size
    have = np.zeros(n, dtype=bool)
    have[idx] = True
    out = np.zeros(n)
    out[idx] = v
    lost = np.nonzero(~have)[0]
    got = np.nonzero(have)[0]
    if lost.size and got.size == 1:
        out[lost] = out[got[0]]
    elif lost.size:
        k = np.clip(np.searchsorted(got, lost), 1, got.size - 1)
        a, b = got[k - 1], got[k]
        f = np.clip((t[lost] - t[a]) / (t[b] - t[a]), 0.0, 1.0)
        d = out[b] - out[a]
        if period is not None:
            d = np.mod(d + 0.5 * period, period) - 0.5 * period
        x = out[a] + f * d
        if period is not None:
            x = np.mod(x, period)
        out[lost] = x
    return out


@dataclass
class Truth:
    """A continuous ground-truth track of one run (mm, rad; angles unwrapped)."""

    path: str
    t_s: np.ndarray
    pose: np.ndarray  # (n, trucks, 3): x_mm, y_mm, theta_rad
    link: np.ndarray | None = None  # (n, 3): alpha_rad, beta_rad, l_mm (clapper/set)


TRUTH_COLS = ["t_s", "a_x_mm", "a_y_mm", "a_theta_deg"]


def read_truth(path: str | Path, robot: Robot) -> Truth:
    path = Path(path)
    try:
        f = path.open(newline="")
    except OSError as e:
        raise GapInputError(path, f"cannot read truth: {e.strerror}") from None
    with f:
        rd = csv.reader(f)
        header = next(rd, None)
        if header is None or header[:4] != TRUTH_COLS:
            raise GapInputError(path, f"expected a header starting {','.join(TRUTH_COLS)}", 1)
        ncol = 10 if robot.n_trucks == 2 else 4
        if len(header) < ncol:
            raise GapInputError(
                path,
                f"a {robot.vehicle} needs truth of both trucks and the linkage (b_x_mm ... l_mm)",
                1,
            )
        rows = []
        for i, rec in enumerate(rd, start=2):
            if not rec:
                continue
            try:
                vals = [float(x) for x in rec[:ncol]]
            except ValueError:
                raise GapInputError(path, f"not a number in {rec[:ncol]}", i) from None
            if len(vals) < ncol or not all(math.isfinite(v) for v in vals):
                raise GapInputError(path, "missing or non-finite value (NaN/inf)", i)
            if rows and vals[0] <= rows[-1][0]:
                raise GapInputError(path, f"time {vals[0]} does not increase", i)
            rows.append(vals)
    if len(rows) < 10:
        raise GapInputError(path, "fewer than 10 truth samples")
    a = np.asarray(rows)
    dt = np.diff(a[:, 0])
    med = float(np.median(dt))
    g = np.nonzero(dt > 3.5 * med)[0]
    if g.size:
        raise GapInputError(path, f"gap of {dt[g[0]]:.3f} s in the truth track", int(g[0]) + 3)
    n = a.shape[0]
    pose = np.zeros((n, robot.n_trucks, 3))
    pose[:, 0] = np.column_stack([a[:, 1], a[:, 2], np.unwrap(np.radians(a[:, 3]))])
    tr = Truth(str(path), a[:, 0], pose)
    if robot.n_trucks == 2:
        pose[:, 1] = np.column_stack([a[:, 4], a[:, 5], np.unwrap(np.radians(a[:, 6]))])
        tr.link = np.column_stack([np.radians(a[:, 7]), np.radians(a[:, 8]), a[:, 9]])
    return tr


RET_COLS = [
    "run",
    "direction",
    "x_abs_mm",
    "y_abs_mm",
    "theta_abs_deg",
    "x_calc_mm",
    "y_calc_mm",
    "theta_calc_deg",
]


def read_returns(path: str | Path) -> dict[tuple[str, int], np.ndarray]:
    """returns.csv (000 Eq. 3.1): (direction, run) -> true return pose x, y (mm), theta (rad)."""
    path = Path(path)
    try:
        f = path.open(newline="")
    except OSError as e:
        raise GapInputError(path, f"cannot read: {e.strerror}") from None
    out: dict[tuple[str, int], np.ndarray] = {}
    with f:
        rd = csv.reader(f)
        if next(rd, None) != RET_COLS:
            raise GapInputError(path, f"expected the header {','.join(RET_COLS)}", 1)
        for i, rec in enumerate(rd, start=2):
            try:
                run, d = int(rec[0]), rec[1]
                vals = [float(x) for x in rec[2:5]]
            except (ValueError, IndexError):
                raise GapInputError(path, "malformed row", i) from None
            if not all(math.isfinite(v) for v in vals):
                raise GapInputError(path, "non-finite value", i)
            out[(d, run)] = np.array([vals[0], vals[1], math.radians(vals[2])])
    return out


@dataclass
class RunData:
    name: str  # run-cw-01; "<session>/run-cw-01" when runs come from several folders
    direction: str  # cw / ccw / fwd / ...
    log: SensorLog
    truth: Truth | None = None
    ret: np.ndarray | None = None  # true return pose (returns.csv)
    session: str = ""  # the folder the run was recorded into (one session per folder)
    path: str = ""  # the log file


HALF_LEAD_IN_S = 1.0  # frames before the cut that the second half's model runs through first


def halves(run: RunData, k: int) -> tuple[RunData, RunData]:
    """A run cut at frame k (paths.cut_tick) into '<name>-h1', its frames up to k, and
    '<name>-h2', its truth from frame k on. The second half's frames start HALF_LEAD_IN_S
    earlier: the slip laws' states (a wheel's speed before the tick, a rate limiter's, a
    motor's) start from rest, and a half that starts at speed gave its first tick a 50 % slip
    (independent world, dev seed 2851 case 29); run through the lead-in, whose truth is cut
    away, they reach the cut where the whole run had them. The model is anchored where the
    truth starts (modes.TruthMode.anchored). Neither half has a return pose."""
    lg, tr = run.log, run.truth

    def part(a: int, b: int, t_from: float, tag: str) -> RunData:
        cut = lambda x: None if x is None else x[a:b]  # noqa: E731
        log = SensorLog(
            lg.path, lg.t_s[a:b], lg.counts[a:b], cut(lg.alpha_deg), cut(lg.beta_deg),
            cut(lg.l_mm), 0, cut(lg.skipped),
        )  # fmt: skip
        truth = None
        if tr is not None:
            m = (tr.t_s >= t_from) & (tr.t_s <= log.t_s[-1] + 1.0)
            truth = Truth(tr.path, tr.t_s[m], tr.pose[m], None if tr.link is None else tr.link[m])
        return RunData(f"{run.name}-{tag}", run.direction, log, truth, None, run.session, run.path)

    t = lg.t_s
    lead = int(np.searchsorted(t, t[k] - HALF_LEAD_IN_S))
    return part(0, k + 1, -math.inf, "h1"), part(lead, t.size, float(t[k]), "h2")


def discover(real: str | Path, robot: Robot) -> list[RunData]:
    """Every run in a folder: run-<dir>-NN.log, optional .truth.csv, optional returns.csv."""
    real = Path(real)
    if not real.is_dir():
        raise GapInputError(real, "not a folder of recorded runs")
    logs = sorted(p for p in real.iterdir() if p.name.endswith(".log"))
    if not logs:
        raise GapInputError(real, "no run-*.log files")
    for p in logs:
        if RUN_RE.match(p.name) is None:
            raise GapInputError(p, "expected a name run-<direction>-NN.log")
    _same_robot_in_folder(real, logs)
    rets = read_returns(real / "returns.csv") if (real / "returns.csv").exists() else {}
    runs = []
    for p in logs:
        m = RUN_RE.match(p.name)
        d, k = m.group("dir"), int(m.group("idx"))
        log = read_log(p, robot)
        tp = p.with_suffix(".truth.csv")
        truth = read_truth(tp, robot) if tp.exists() else None
        runs.append(RunData(p.stem, d, log, truth, rets.get((d, k)), real.name, str(p)))
    return runs


SCAN_LINES = 2000  # enough of a log to read its cycle and which trucks it carries


def _log_signature(p: Path) -> tuple[float | None, bool]:
    """(median cycle of the WHEEL_COUNTS_A frames in the log's first lines, whether it carries
    WHEEL_COUNTS_B frames): what tells one robot's recording from another's."""
    ida, idb = (f"{fid:03X}#" for fid in ID_WHEEL)
    ts, has_b = [], False
    try:
        with p.open() as f:
            for i, ln in enumerate(f):
                if i >= SCAN_LINES:
                    break
                m = LINE_RE.match(ln.strip())
                if m is None:
                    continue
                key = f"{int(m.group(3), 16):03X}#"
                if key == ida:
                    ts.append(float(m.group(1)))
                has_b |= key == idb
    except (OSError, UnicodeDecodeError):
        return None, False  # read_log names the problem
    dt = np.diff(ts)
    return (float(np.median(dt)) if dt.size else None), has_b


def _same_robot_in_folder(real: Path, logs: list[Path]) -> None:
    """Runs of one folder must come from one robot: the same control cycle and the same trucks.
    A folder that mixes robots would be diagnosed against one robot's description and blamed on
    an effect; say so instead."""
    sig = {p: _log_signature(p) for p in logs}
    cyc = {p: c for p, (c, _) in sig.items() if c is not None}
    if cyc:
        lo, hi = min(cyc, key=cyc.get), max(cyc, key=cyc.get)
        if cyc[hi] > 1.1 * cyc[lo]:
            raise GapInputError(
                real,
                f"runs of different robots in one folder: {lo.name} ticks every "
                f"{cyc[lo] * 1e3:.1f} ms, {hi.name} every {cyc[hi] * 1e3:.1f} ms",
            )
    two = {p for p, (_, b) in sig.items() if b}
    if two and len(two) != len(logs):
        one = next(p for p in logs if p not in two)
        raise GapInputError(
            real,
            f"runs of different robots in one folder: {next(iter(sorted(two))).name} carries "
            f"truck B's wheel counts, {one.name} does not",
        )


def _robot_geometry(raw: dict) -> dict:
    """What makes two robot descriptions the same robot (not their prose)."""
    keep = ("vehicle", "tick_ms", "trucks", "linkage", "trailer")
    return {k: raw.get(k) for k in keep}


def discover_all(folders: list[str | Path], robot: Robot) -> list[RunData]:
    """The runs of one or more folders, one recording session each (`RunData.session`). With
    several folders run names carry their session ("square/run-cw-01"). Folders that hold a
    robot.json (odo-import and the blind check write one) must describe the same robot."""
    folders = [Path(f) for f in folders]
    if not folders:
        raise GapInputError("--real", "no folder of recorded runs given")
    seen: dict[str, Path] = {}
    geo: tuple[Path, dict] | None = None
    for f in folders:
        rp = f / "robot.json"
        if rp.is_file():
            try:
                g = _robot_geometry(json.loads(rp.read_text()))
            except (OSError, json.JSONDecodeError, AttributeError):
                raise GapInputError(rp, "unreadable robot description") from None
            if geo is None:
                geo = (rp, g)
            elif g != geo[1]:
                diff = next(k for k in g if g[k] != geo[1].get(k))
                raise GapInputError(
                    rp, f"runs of different robots: differs from {geo[0]} in '{diff}'"
                )
    runs: list[RunData] = []
    for f in folders:
        label = f.name or str(f)
        if label in seen and seen[label] != f.resolve():
            label = f"{f.parent.name}/{f.name}"
        seen[label] = f.resolve()
        for r in discover(f, robot):
            r.session = label
            if len(folders) > 1:
                r.name = f"{label}/{r.name}"
            runs.append(r)
    return runs


def encode_payload(fid: int, values: dict[str, np.ndarray]) -> np.ndarray:
    """Vectorised inverse of decode_signal: uint64 payloads of frame `fid` from signal values."""
    lay = dbc_layouts()[fid]
    out = np.zeros(len(next(iter(values.values()))), dtype=np.uint64)
    for name, v in values.items():
        s = lay[name]
        raw = np.round((np.asarray(v, dtype=float) - s.offset) / s.scale).astype(np.int64)
        raw &= (1 << s.length) - 1
        out |= raw.astype(np.uint64) << np.uint64(s.start)
    return out


def write_candump(path: Path, frames: list[tuple[np.ndarray, int, np.ndarray]]) -> None:
    """frames: (t_s, frame id, payloads) per frame kind; merged in time order, kind order kept."""
    rows = []
    for order, (t, fid, pay) in enumerate(frames):
        n = FRAME_LEN[fid]
        for ti, p in zip(t, pay, strict=False):
            rows.append(
                (
                    round(float(ti), 6),
                    order,
                    f"({ti:.6f}) can0 {fid:03X}#{int(p).to_bytes(8, 'little')[:n].hex().upper()}",
                )
            )
    rows.sort(key=lambda r: (r[0], r[1]))
    path.write_text("\n".join(r[2] for r in rows) + "\n")

"""The firmware CAN codec agrees with can/odometry.dbc as cantools reads it.

The DBC is the single source of truth for frames (DESIGN.md section 4). The C side is reached
through odo-canvec, which runs the firmware's own pack/unpack functions; every batch of vectors is
one subprocess call. Values are compared raw (integers on the wire); scaling is checked separately.
"""

from __future__ import annotations

import logging
import os
import random
import re
import subprocess
import warnings
from dataclasses import dataclass
from pathlib import Path

import cantools
import pytest
from cantools.database.can import Database, Message, Signal
from odo_tools import cangen

SOURCE_DIR = Path(os.environ.get("ODO_SOURCE_DIR", Path(__file__).resolve().parents[2]))
DBC_PATH = SOURCE_DIR / "can" / "odometry.dbc"
GENERATED_HEADER_PATH = SOURCE_DIR / "firmware" / "include" / "odo" / "odo_can_dbc.h"
N_RANDOM = 200  # random vectors per message, on top of the limit vectors
FLAG_SIGNALS = ("Missing", "Jump", "Ipec", "IpecGated", "Range", "XySaturated", "FlagsReserved")
FLAGS_CLEAR = dict.fromkeys(FLAG_SIGNALS, 0)
SEED = 0x0D0CA7


# ---- access to the C codec ----


def canvec_path() -> Path:
    build = os.environ.get("ODO_BUILD_DIR")
    if not build:
        pytest.fail("ODO_BUILD_DIR is not set; run this through ctest (ctest --preset host -R can)")
    path = Path(build) / "bin" / "odo-canvec"
    if not path.is_file():
        pytest.fail(
            f"{path} is missing; build it first: cmake --build --preset host --target odo-canvec"
        )
    return path


def run_canvec(lines: list[str], *args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [str(canvec_path()), *args],
        input="".join(line + "\n" for line in lines),
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )


def canvec_batch(lines: list[str]) -> list[str]:
    """One odo-canvec process for the whole batch; one output line per input line."""
    proc = run_canvec(lines)
    assert proc.returncode == 0, f"odo-canvec exited {proc.returncode}: {proc.stderr}"
    out = proc.stdout.splitlines()
    assert len(out) == len(lines), f"{len(lines)} commands gave {len(out)} lines"
    return out


@dataclass(frozen=True)
class CSignal:
    name: str
    start: int
    length: int
    is_signed: bool


@dataclass(frozen=True)
class CMessage:
    name: str
    frame_id: int
    dlc: int
    signals: tuple[CSignal, ...]


def c_layout() -> dict[str, CMessage]:
    """The codec's own layout table, as `odo-canvec list` prints it."""
    proc = run_canvec(["list"])
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.splitlines()
    assert lines and lines[-1] == "end", proc.stdout
    msgs: dict[str, tuple[int, int]] = {}
    sigs: dict[str, list[CSignal]] = {}
    for line in lines[:-1]:
        kind, *rest = line.split()
        if kind == "message":
            name, frame_id, dlc = rest
            msgs[name] = (int(frame_id, 16), int(dlc))
            sigs[name] = []
        elif kind == "signal":
            msg, name, start, length, signedness = rest
            sigs[msg].append(CSignal(name, int(start), int(length), signedness == "signed"))
        else:
            pytest.fail(f"unexpected list line {line!r}")
    return {n: CMessage(n, i, d, tuple(sigs[n])) for n, (i, d) in msgs.items()}


def frame_text(frame_id: int, data: bytes) -> str:
    return f"{frame_id:03X}#{data.hex().upper()}"


def parse_frame(line: str) -> tuple[int, bytes]:
    assert re.fullmatch(r"[0-9A-F]{3}#(?:[0-9A-F]{2}){0,8}", line), f"not a frame: {line!r}"
    ident, data = line.split("#")
    return int(ident, 16), bytes.fromhex(data)


def parse_decoded(line: str) -> tuple[str, dict[str, int]]:
    assert not line.startswith("error"), line
    name, *pairs = line.split()
    values = {}
    for pair in pairs:
        key, value = pair.split("=")
        values[key] = int(value)
    return name, values


# ---- the DBC ----


@pytest.fixture(scope="module")
def db() -> Database:
    return cantools.database.load_file(str(DBC_PATH), strict=True)


def raw_range(sig: Signal) -> tuple[int, int]:
    if sig.is_signed:
        return -(1 << (sig.length - 1)), (1 << (sig.length - 1)) - 1
    return 0, (1 << sig.length) - 1


def limits(sig: Signal) -> list[int]:
    lo, hi = raw_range(sig)
    return [lo, -1, 0, 1, hi] if sig.is_signed else [0, 1, hi]


def random_value(sig: Signal, rng: random.Random) -> int:
    lo, hi = raw_range(sig)
    if rng.random() < 0.5:
        return rng.randint(lo, hi)
    # small magnitudes too: uniform over bit widths rather than over values
    magnitude = rng.getrandbits(rng.randint(0, sig.length - 1)) if sig.length > 1 else 0
    value = -magnitude if sig.is_signed and rng.random() < 0.5 else magnitude
    return max(lo, min(hi, value))


def vectors(msg: Message, rng: random.Random) -> list[dict[str, int]]:
    """Limit vectors (all signals at 0, at max, at min, at -1; each signal at each of its limits
    with the others random), then N_RANDOM random ones."""
    sigs = msg.signals
    vecs: list[dict[str, int]] = [
        {s.name: 0 for s in sigs},
        {s.name: raw_range(s)[1] for s in sigs},
        {s.name: raw_range(s)[0] for s in sigs},
        {s.name: -1 if s.is_signed else raw_range(s)[1] for s in sigs},
    ]
    for s in sigs:
        for value in limits(s):
            vec = {t.name: random_value(t, rng) for t in sigs}
            vec[s.name] = value
            vecs.append(vec)
    vecs += [{s.name: random_value(s, rng) for s in sigs} for _ in range(N_RANDOM)]
    return vecs


def encode_line(msg: Message, vec: dict[str, int]) -> str:
    return " ".join(["encode", msg.name, *(f"{k}={v}" for k, v in vec.items())])


# ---- the contract itself ----


def test_dbc_loads_in_strict_mode_without_warnings(caplog: pytest.LogCaptureFixture) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with caplog.at_level(logging.WARNING):
            loaded = cantools.database.load_file(str(DBC_PATH), strict=True)
    assert not [r for r in caplog.records if r.levelno >= logging.WARNING], caplog.text
    assert len(loaded.messages) == 10


def test_dbc_frames_are_classic_intel_integer_and_documented(db: Database) -> None:
    assert {n.name for n in db.nodes} == {"SENSOR", "ODO", "NAV"}
    assert all(n.comment for n in db.nodes)
    for msg in db.messages:
        assert not msg.is_extended_frame and msg.frame_id <= 0x7FF, msg.name
        assert not msg.is_fd and msg.length in (6, 8), msg.name
        assert msg.cycle_time == 40, msg.name
        sensor = msg.frame_id < 0x180
        assert msg.senders == (["SENSOR"] if sensor else ["ODO"]), msg.name
        assert msg.comment, f"{msg.name} has no CM_ comment"
        for sig in msg.signals:
            # every frame is received by someone named: the firmware, or the pose consumers
            assert sig.receivers == (["ODO"] if sensor else ["NAV"]), (msg.name, sig.name)
            assert sig.byte_order == "little_endian", (msg.name, sig.name)
            assert not sig.is_float and sig.offset == 0, (msg.name, sig.name)
            assert sig.comment, f"{msg.name}.{sig.name} has no CM_ comment"
            lo, hi = raw_range(sig)
            # min/max are the scaled raw range (within float rounding of the factor)
            assert sig.minimum == pytest.approx(lo * sig.scale, abs=sig.scale * 1e-3)
            assert sig.maximum == pytest.approx(hi * sig.scale, abs=sig.scale * 1e-3)


def test_every_dbc_message_and_signal_has_a_c_counterpart_and_vice_versa(db: Database) -> None:
    c = c_layout()
    assert sorted(c) == sorted(m.name for m in db.messages)
    for msg in db.messages:
        cm = c[msg.name]
        assert cm.frame_id == msg.frame_id, msg.name
        assert cm.dlc == msg.length, msg.name
        dbc_sigs = tuple(CSignal(s.name, s.start, s.length, s.is_signed) for s in msg.signals)
        assert cm.signals == dbc_sigs, msg.name


def test_generated_codec_is_what_the_dbc_gives() -> None:
    """odo_can_dbc.h / odo_can_dbc.c are generated from the DBC (tools/python/odo_tools/cangen.py)
    and committed: regenerating them gives the committed files byte for byte."""
    files = cangen.generate(DBC_PATH)
    assert set(files) == {cangen.HEADER_REL, cangen.SOURCE_REL}
    for rel, text in files.items():
        committed = (SOURCE_DIR / rel).read_text()
        assert committed == text, f"{rel} is out of date: run .venv/bin/python -m odo_tools.cangen"


def test_cangen_check_reports_a_stale_file(tmp_path: Path) -> None:
    """`cangen --check` fails (exit 1, a diff) on a tree whose generated file differs, and
    writes nothing; without --check it renames fresh files into place."""
    (tmp_path / "can").mkdir()
    (tmp_path / "can" / "odometry.dbc").write_text(DBC_PATH.read_text())
    assert cangen.main(["--source-dir", str(tmp_path), "--check"]) == 1
    assert not (tmp_path / cangen.HEADER_REL).exists()
    assert cangen.main(["--source-dir", str(tmp_path)]) == 0
    assert cangen.main(["--source-dir", str(tmp_path), "--check"]) == 0
    stale = tmp_path / cangen.SOURCE_REL
    stale.write_text(stale.read_text() + "/* edited */\n")
    assert cangen.main(["--source-dir", str(tmp_path), "--check"]) == 1
    assert cangen.main(["--source-dir", str(tmp_path / "nowhere"), "--check"]) == 2


def test_header_macros_match_the_dbc(db: Database) -> None:
    text = GENERATED_HEADER_PATH.read_text()
    macros = {
        name: int(value, 16)
        for name, value in re.findall(r"#define ODO_CAN_ID_(\w+)\s+0x([0-9A-Fa-f]+)U", text)
    }
    assert macros == {m.name: m.frame_id for m in db.messages}
    dlcs = {
        name: int(value) for name, value in re.findall(r"#define ODO_CAN_DLC_(\w+)\s+(\d+)U", text)
    }
    assert dlcs == {re.sub(r"_[AB]$", "", m.name): m.length for m in db.messages}
    cycle = re.search(r"#define ODO_CAN_CYCLE_TIME_US\s+(\d+)UL", text)
    assert cycle is not None
    assert {m.cycle_time * 1000 for m in db.messages} == {int(cycle.group(1))}


def test_c_encoding_decodes_identically_with_cantools(db: Database) -> None:
    rng = random.Random(SEED)
    cases = [(msg, vec) for msg in db.messages for vec in vectors(msg, rng)]
    out = canvec_batch([encode_line(msg, vec) for msg, vec in cases])
    for (msg, vec), line in zip(cases, out, strict=True):
        frame_id, data = parse_frame(line)
        assert frame_id == msg.frame_id, (msg.name, vec, line)
        assert len(data) == msg.length, (msg.name, vec, line)
        decoded = msg.decode(data, decode_choices=False, scaling=False)
        assert decoded == vec, (msg.name, line)
        # and bit for bit what cantools itself would send (unused bits zero)
        assert data == msg.encode(vec, scaling=False), (msg.name, vec, line)


def test_cantools_encoding_decodes_identically_with_c(db: Database) -> None:
    rng = random.Random(SEED + 1)
    cases = [(msg, vec) for msg in db.messages for vec in vectors(msg, rng)]
    lines = [
        "decode " + frame_text(msg.frame_id, msg.encode(vec, scaling=False)) for msg, vec in cases
    ]
    out = canvec_batch(lines)
    for (msg, vec), line in zip(cases, out, strict=True):
        name, values = parse_decoded(line)
        assert name == msg.name, line
        assert values == vec, (msg.name, line)
        assert list(values) == [s.name for s in msg.signals], line


@pytest.mark.parametrize(
    ("message", "raw", "physical", "units"),
    [
        ("POSE_XY_A", {"X": 12345, "Y": -12345}, {"X": 123.45, "Y": -123.45}, "mm"),
        ("POSE_XY_B", {"X": -(2**31), "Y": 2**31 - 1}, {"X": -21474836.48, "Y": 21474836.47}, "mm"),
        ("POSE_THETA_A", {"Theta": 2**30, "Seq": 0, **FLAGS_CLEAR}, {"Theta": 90.0}, "deg"),
        ("POSE_THETA_B", {"Theta": 2**31, "Seq": 1, **FLAGS_CLEAR}, {"Theta": 180.0}, "deg"),
        (
            "LINK_ROTARY",
            {"Alpha": 2**14, "Beta": 2**16 - 1, "Seq": 2, "Status": 3},
            {"Alpha": 90.0, "Beta": 359.9945068359375},
            "deg",
        ),
        ("LINK_LINEAR", {"Length": 1234567, "Seq": 3, "Status": 4}, {"Length": 1234.567}, "mm"),
        (
            "IPEC_CORR",
            {"DThetaA": -(2**30), "DThetaB": 2**29},
            {"DThetaA": -90.0, "DThetaB": 45.0},
            "deg",
        ),
    ],
)
def test_scaled_values_have_the_documented_units(
    db: Database, message: str, raw: dict[str, int], physical: dict[str, float], units: str
) -> None:
    msg = db.get_message_by_name(message)
    (line,) = canvec_batch([encode_line(msg, raw)])
    _, data = parse_frame(line)
    decoded = msg.decode(data, decode_choices=False, scaling=True)
    for name, value in physical.items():
        assert decoded[name] == pytest.approx(value, abs=1e-9), (message, name)
        assert msg.get_signal_by_name(name).unit == units
    # and the other way: physical values through cantools' scaling land on the same raw integers
    scaled_in = {s.name: decoded[s.name] for s in msg.signals}
    (back,) = canvec_batch(["decode " + frame_text(msg.frame_id, msg.encode(scaled_in))])
    assert parse_decoded(back) == (message, raw)


def test_status_param_state_names_follow_odo_params_status(db: Database) -> None:
    sig = db.get_message_by_name("STATUS").get_signal_by_name("ParamState")
    assert sig.choices is not None and str(sig.choices[0]) == "OK"
    header = (SOURCE_DIR / "firmware" / "include" / "odo" / "odo_params.h").read_text()
    enum_body = re.search(r"typedef enum \{([^{}]*)\} odo_params_status_t;", header)
    assert enum_body is not None
    names = re.findall(r"ODO_PARAMS_(\w+)", enum_body.group(1))
    assert [str(sig.choices[i]) for i in range(len(names))] == names


def header_bits(path: Path, pattern: str) -> dict[int, str]:
    """Bit index -> name of the macros matching `pattern` (two groups: name, bit or mask)."""
    bits = {}
    for name, value in re.findall(pattern, path.read_text()):
        v = int(value, 0)
        index = v if "<<" in pattern else v.bit_length() - 1
        bits[index] = name
    return bits


def snake(camel: str) -> str:
    """A DBC signal name as its C macro suffix: CounterJumpA -> COUNTER_JUMP_A."""
    return re.sub(r"(?<=[a-z0-9])(?=[A-Z])", "_", camel).upper()


def bit_signals(msg: Message, base: int) -> dict[int, str]:
    """Bit index (from `base`) -> C-style name of every one-bit signal of msg."""
    return {s.start - base: snake(s.name) for s in msg.signals if s.length == 1}


def readme_bits(table_header: str) -> dict[int, str]:
    text = (SOURCE_DIR / "can" / "README.md").read_text()
    table = text.split(table_header, 1)[1].split("\n\n", 1)[0]
    return {int(i): name for i, name in re.findall(r"^\| (\d+) \| ([A-Z0-9_]+) \|", table, re.M)}


def test_fault_and_flag_bits_are_named_signals_as_the_headers_define_them(db: Database) -> None:
    """One source per contract, and names for cantools: every STATUS fault bit (odo_status.h) and
    every POSE_THETA flag bit (odo_app.h) is a one-bit signal of the same name at the same
    position, the rest of the word a reserved signal; can/README.md's tables say the same."""
    include = SOURCE_DIR / "firmware" / "include" / "odo"
    faults = header_bits(include / "odo_status.h", r"#define ODO_FAULT_(\w+)\s+\(1UL << (\d+)\)")
    flags = header_bits(include / "odo_app.h", r"#define ODO_POSE_FLAG_(\w+)\s+(0x[0-9A-Fa-f]+)U")
    count = re.search(r"#define ODO_FAULT_COUNT (\d+)U", (include / "odo_status.h").read_text())
    assert count is not None and len(faults) == int(count.group(1))
    assert faults and flags
    status = db.get_message_by_name("STATUS")
    assert bit_signals(status, 0) == faults
    reserved = status.get_signal_by_name("FaultsReserved")
    assert (reserved.start, reserved.start + reserved.length) == (len(faults), 32)
    for msg in ("POSE_THETA_A", "POSE_THETA_B"):
        theta = db.get_message_by_name(msg)
        assert bit_signals(theta, 40) == flags
        reserved = theta.get_signal_by_name("FlagsReserved")
        assert (reserved.start, reserved.start + reserved.length) == (40 + len(flags), 48)
    assert readme_bits("| Faults bit | name |") == faults
    assert readme_bits("| Flags bit | name |") == flags


def test_gap_reader_reads_the_skipped_state_bits_the_firmware_defines() -> None:
    """The diagnosis reads a decoder's skipped quadrature states from WHEEL_COUNTS Status with
    the masks odo_types.h gives the firmware, not a copy that could drift."""
    from odo_tools.gap import io as gap_io

    text = (SOURCE_DIR / "firmware" / "include" / "odo" / "odo_types.h").read_text()
    pattern = r"#define ODO_WHEEL_STATUS_(\w+)_SKIPPED\s+0x([0-9A-Fa-f]+)U"
    masks = {name: int(v, 16) for name, v in re.findall(pattern, text)}
    assert masks == {"LEFT": gap_io.STATUS_LEFT_SKIPPED, "RIGHT": gap_io.STATUS_RIGHT_SKIPPED}


def test_cantools_names_the_faults_of_a_status_frame(db: Database) -> None:
    """What `cantools decode` prints for a STATUS frame: each raised fault by name."""
    status = db.get_message_by_name("STATUS")
    data = bytes.fromhex("2022000007050300")  # faults 0x2220: SEQ_GAP, LINK_MISSING, IPEC_GATED
    decoded = status.decode(data)
    one_bit = {s.name for s in status.signals if s.length == 1}
    raised = sorted(name for name, v in decoded.items() if name in one_bit and v == 1)
    assert raised == ["IpecGated", "LinkMissing", "SeqGap"]
    assert str(decoded["ParamState"]) == "ERR_CRC"


# ---- odo-canvec's own contract (the batch must survive bad lines) ----


def test_wrong_length_is_rejected_for_every_message(db: Database) -> None:
    lines, kinds = [], []
    for msg in db.messages:
        good = msg.encode({s.name: 0 for s in msg.signals}, scaling=False)
        longer = [good + b"\x00"] if msg.length < 8 else []  # classic CAN carries 8 bytes at most
        for data in (good[:-1], b"", *longer):
            lines.append("decode " + frame_text(msg.frame_id, data))
            kinds.append(msg.name)
    for line, name in zip(canvec_batch(lines), kinds, strict=True):
        assert line.startswith("error dlc:") and name in line, line


def test_bad_lines_give_error_lines_and_the_batch_goes_on() -> None:
    lines = [
        "encode POSE_XY_A X=-2147483648 Y=5",
        "decode 180#00000080050000",  # 7 bytes
        "decode 7FF#0000000000000000",  # not ours
        "decode 110#R",  # remote
        "decode 00000110#0000000000000000",  # extended identifier
        "decode 20000004#0000000000000000",  # error frame, as candump prints it
        "decode 180#zz",
        "encode POSE_XY_A X=1",  # missing Y
        "encode POSE_XY_A X=1 Y=2 Z=3",
        "encode POSE_XY_A X=2147483648 Y=0",  # out of the raw range
        "encode WHEEL_COUNTS_A LeftCount=16777216 RightCount=0 Seq=0 Status=0",
        "encode NO_SUCH X=1",
        "frobnicate",
        "decode 180#0000008005000000",
    ]
    out = canvec_batch(lines)
    assert out[0] == "180#0000008005000000"
    expected_kinds = [
        "dlc",
        "unknown-id",
        "flags",
        "flags",
        "flags",
        "syntax",
        "signal",
        "signal",
        "range",
        "range",
        "message",
        "command",
    ]
    for line, kind in zip(out[1:-1], expected_kinds, strict=True):
        assert line.startswith(f"error {kind}:"), line
    assert out[-1] == "POSE_XY_A X=-2147483648 Y=5"


def test_help_and_usage_errors() -> None:
    proc = run_canvec([], "--help")
    assert proc.returncode == 0 and "encode" in proc.stdout and "decode" in proc.stdout
    proc = run_canvec([], "--no-such-option")
    assert proc.returncode == 2 and "usage" in proc.stderr

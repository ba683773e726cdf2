"""Write fuzz/corpus/<harness>/ seed inputs from the project's own example data and tools.

Run once after `make build` (python3 fuzz/make_seeds.py); the seeds are committed, so CI and
`make fuzz` start from them. Each seed is small: a handful of real frames, stock JSON files, a
default parameter block in the three image formats."""

from __future__ import annotations

import shutil
import struct
import subprocess
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
BIN = ROOT / "build" / "host" / "bin"
CORPUS = ROOT / "fuzz" / "corpus"

# Issue 16's UB reproducer: rotary encoders exactly 180 deg apart on a clapper.
UB_LINES = ["(0.000000) can0 120#000000800103", "(0.000000) can0 121#40420F000104"]


def put(harness: str, name: str, data: bytes) -> None:
    d = CORPUS / harness
    d.mkdir(parents=True, exist_ok=True)
    (d / name).write_bytes(data)


def parse_line(line: str) -> tuple[int, int, bytes]:
    ts, _iface, frame = line.split()[:3]
    sec, usec = ts.strip("()").split(".")
    ident, data = frame.split("#", 1)
    return (
        int(sec) * 1_000_000 + int(usec),
        int(ident, 16),
        bytes.fromhex(data) if data[:1] != "R" else b"",
    )


def replay_records(lines: list[str], mode: int) -> bytes:
    sel_of = {0x110: 0, 0x111: 1, 0x120: 2, 0x121: 3, 0x180: 4, 0x1A0: 5}
    out = bytearray([mode])
    prev = None
    for line in lines:
        t, ident, data = parse_line(line)
        dt = 0 if prev is None else max(0, t - prev)
        prev = t
        long_gap = dt > 0xFFFF
        dt = min(dt >> 8, 0xFFFF) if long_gap else dt
        out += struct.pack("<H", dt) + bytes(
            [sel_of.get(ident, 6) | (0x40 if long_gap else 0), len(data)]
        )
        out += data.ljust(8, b"\0")
    return bytes(out)


def main() -> None:
    shutil.rmtree(CORPUS, ignore_errors=True)
    with tempfile.TemporaryDirectory() as tmp:
        t = Path(tmp)
        subprocess.run(
            [
                BIN / "odo-sim",
                "--experiment",
                "straight-36m",
                "--vehicle",
                "clapper",
                "--scenario",
                ROOT / "host_sim/scenarios/effect-bumps.json",
                "--runs",
                "1",
                "--bumps",
                "2",
                "--quiet",
                "--out",
                t / "s",
            ],
            check=True,
        )
        log = (t / "s" / "run-fwd-01.log").read_text().splitlines()
        subprocess.run(
            [
                BIN / "odo-sim",
                "--experiment",
                "umbmark",
                "--vehicle",
                "labmate",
                "--scenario",
                ROOT / "host_sim/scenarios/set-sim.json",
                "--runs",
                "2",
                "--quiet",
                "--out",
                t / "u",
            ],
            check=True,
        )
        subprocess.run([BIN / "odo-params", "defaults", "--out", t / "p.bin"], check=True)
        block = (t / "p.bin").read_bytes()
        show = subprocess.run(
            [BIN / "odo-params", "show", t / "p.bin"], check=True, capture_output=True
        ).stdout
        subprocess.run(
            [
                BIN / "odo-calib",
                "umbmark",
                "--returns",
                t / "u" / "returns.csv",
                "--side-mm",
                "4000",
                "--robot",
                ROOT / "host_sim/robots/labmate.json",
                "--out-params",
                t / "cal.json",
            ],
            check=True,
            capture_output=True,
        )

        # candump: real lines of every sensor, the UB pair, and the other forms of the grammar.
        for i, line in enumerate(log[:6] + UB_LINES):
            put("candump", f"line-{i:02d}", (line + "\n").encode())
        for i, line in enumerate(
            [
                "(1.5) vcan0 1A0#R3",
                "(1700000000.123456789) can0 12345678#01.02.03 T",
                "(0.000001) can0 20000004#0000000000000000 R",
                "(0.000000) can0 123##1001122334455667788",
            ]
        ):
            put("candump", f"form-{i}", (line + "\n").encode())
        # can_codec: id (LE, bit 31 clear = pick a project ID by bits 8..), flags, dlc, data.
        for i, line in enumerate(log[:6]):
            _, ident, data = parse_line(line)
            put(
                "can_codec",
                f"frame-{i}",
                struct.pack("<I", 0x80000000 | ident) + bytes([0, len(data)]) + data,
            )
        # params_block: byte 0 bit 0 = make the CRC right.
        put("params_block", "defaults", b"\0" + block)
        put("params_block", "defaults-fixcrc", b"\1" + block)
        # replay_step: the clapper run's first 120 frames in each IPEC mode, and the UB pair.
        for mode in range(3):
            put("replay_step", f"clapper-ipec{mode}", replay_records(log[:120], mode))
        put("replay_step", "ub-180deg", replay_records(UB_LINES, 0))
        put("returns_csv", "umbmark", (t / "u" / "returns.csv").read_bytes())
        put("params_json", "defaults", show)
        put("params_json", "calibrated", (t / "cal.json").read_bytes())
        for f in (
            sorted((ROOT / "host_sim/robots").glob("*.json"))
            + sorted((ROOT / "host_sim/scenarios").glob("*.json"))[:4]
        ):
            put("robot_json", f.name, f.read_bytes())
        # image: byte 0 = suffix (0 .bin, 1 .hex, 2 .elf); raw, its Intel HEX, a relocatable ELF.
        raw = b"\xff" * 64 + b"ODOP" + b"\0" * 12 + block + b"\xff" * 32
        put("image", "raw", b"\0" + raw)
        hexl = []
        for off in range(0, len(raw), 16):
            chunk = raw[off : off + 16]
            rec = bytes([len(chunk), off >> 8, off & 0xFF, 0]) + chunk
            hexl.append(":" + rec.hex().upper() + f"{(-sum(rec)) & 0xFF:02X}")
        hexl.append(":00000001FF")
        put("image", "hex", b"\1" + ("\n".join(hexl) + "\n").encode())
        c = t / "blk.c"
        c.write_text(
            '__attribute__((section(".odo_params"), used)) '
            "const unsigned char odo_param_block[] = {"
            + ",".join(str(b) for b in block)
            + "};\n"
        )
        subprocess.run(["cc", "-c", "-o", t / "blk.o", c], check=True)
        subprocess.run(["strip", "--strip-debug", t / "blk.o"], check=True)
        put("image", "elf", b"\2" + (t / "blk.o").read_bytes())


if __name__ == "__main__":
    main()

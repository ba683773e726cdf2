"""The target tools' contracts: odo-target-ticks and odo-flash refuse bad input with a message, a
non-zero exit and nothing written; odo-bench-target refuses malformed ticks files; and the
emulator's instruction counter agrees with binutils' disassembler on the firmware's own code."""

from __future__ import annotations

import os
import re
import subprocess
from pathlib import Path

import pytest
from odo_tools.target import bench, emu, flash

BUILD = Path(os.environ["ODO_BUILD_DIR"])
SRC = Path(os.environ["ODO_SOURCE_DIR"])
CM4 = SRC / "build/cm4/bin"
TICKS = BUILD / "bin/odo-target-ticks"
ROBOT = SRC / "host_sim/robots/clapper.json"
LOG_LINES = "(0.000000) vcan0 110#0000000000000000\n(0.040000) vcan0 110#0A00000A00000100\n"


def run(*args: object) -> subprocess.CompletedProcess[str]:
    return subprocess.run([str(a) for a in args], capture_output=True, text=True, timeout=120)


def test_target_ticks_help_and_a_good_log(tmp_path: Path) -> None:
    r = run(TICKS, "--help")
    assert r.returncode == 0 and "usage" in r.stdout
    log = tmp_path / "run.log"
    log.write_text(LOG_LINES)
    out = tmp_path / "t.bin"
    r = run(TICKS, "--log", log, "--robot", ROBOT, "--ipec", "paper", "--out", out)
    assert r.returncode == 0, r.stderr
    block, ticks = bench.read_ticks(out, bench.record_sizes(CM4 / "odo_bench_cm4.elf"))
    assert block[:4] == b"ODOP" and len(ticks) == 2


@pytest.mark.parametrize(
    "case, why",
    [("ipec", "--ipec must be off, paper or estimator"), ("nolog", "run.log"),
     ("malformed", "run.log:2"), ("empty", "no sensor frames")],
)
def test_target_ticks_refuses_bad_input_and_writes_nothing(tmp_path: Path, case: str,
                                                           why: str) -> None:
    log = tmp_path / "run.log"
    if case == "malformed":
        log.write_text(LOG_LINES.splitlines()[0] + "\n(0.040000) vcan0 110#0A0\n")
    elif case == "empty":
        log.write_text("")
    elif case != "nolog":
        log.write_text(LOG_LINES)
    out = tmp_path / "t.bin"
    ipec = "sideways" if case == "ipec" else "off"
    r = run(TICKS, "--log", log, "--robot", ROBOT, "--ipec", ipec, "--out", out)
    assert r.returncode == 1 and why in r.stderr, r.stderr
    assert not out.exists() and not Path(str(out) + ".tmp").exists()


def test_bench_refuses_malformed_ticks_files(tmp_path: Path) -> None:
    log = tmp_path / "run.log"
    log.write_text(LOG_LINES)
    good = tmp_path / "t.bin"
    r = run(TICKS, "--log", log, "--robot", ROBOT, "--ipec", "off", "--out", good)
    assert r.returncode == 0, r.stderr
    data = good.read_bytes()
    for name, blob, why in (("magic", b"XXXX" + data[4:], "not a ticks file"),
                            ("truncated", data[:-5], "does not match")):
        p = tmp_path / name
        p.write_bytes(blob)
        with pytest.raises(SystemExit, match=why):
            bench.read_ticks(p, bench.record_sizes(CM4 / "odo_bench_cm4.elf"))


def test_flash_refuses_what_is_not_a_good_block(tmp_path: Path) -> None:
    image = CM4 / "odo_image.elf"
    assert image.is_file(), "build/cm4 missing: target.build runs first (fixture odo_cm4)"
    r = run(SRC / ".venv/bin/odo-flash", "--help")
    assert r.returncode == 0 and "usage" in r.stdout
    syms = flash.elf_symbols(image)
    cap = syms["__odo_params_sector_end"] - syms["__odo_params_start"]
    raw = (CM4 / "odo_image.bin").read_bytes()
    at = syms["__odo_params_start"] - syms["__odo_flash_start"]
    block = raw[at : at + int.from_bytes(raw[at + 6 : at + 8], "little")]  # its length field
    assert flash.check_block(block, cap, "x") == block
    long_len = bytearray(block)
    long_len[6:8] = (cap + 1).to_bytes(2, "little")
    for blob, why in ((b"nope" + block[4:], "no parameter block"),
                      (bytes(long_len), "does not fit"),
                      (block[:-10], "does not fit")):
        with pytest.raises(flash.FlashError, match=why):
            flash.check_block(blob, cap, "x")
    bad_hex = tmp_path / "bad.hex"
    bad_hex.write_text(":0400000001020304F0\n")
    with pytest.raises(flash.FlashError, match="checksum"):
        flash.read_hex(bad_hex)
    keep = tmp_path / "k.hex"
    r = run(SRC / ".venv/bin/odo-flash", "params", "--image", image, "--dry-run", "--keep", keep)
    assert r.returncode == 1 and "--params" in r.stderr and not keep.exists()
    r = run(SRC / ".venv/bin/odo-flash", "params", "--image", image,
            "--params", image.with_suffix(".map"), "--dry-run", "--keep", keep)
    assert r.returncode == 1 and "no parameter block" in r.stderr and not keep.exists()


def test_instruction_lengths_match_the_disassembler() -> None:
    """Armv7-M ARM A5.1: the first halfword says 16 or 32 bits. Checked instruction by instruction
    on the firmware's own functions against arm-none-eabi-objdump, an independent decoder."""
    elf = CM4 / "odo_bench_cm4.elf"
    assert elf.is_file(), "build/cm4 missing: target.build runs first (fixture odo_cm4)"
    fw = emu.Firmware(elf, [])
    row = re.compile(r"^\s+([0-9a-f]+):\s+((?:[0-9a-f]{4} ?){1,2})\s+(\S+)")
    checked = 0
    for name in ("odo_app_step", "odo_truck_tick", "odo_ipec_step", "odo_atan2_bam"):
        addr, size = fw.symbols[name]
        addr &= ~1
        dis = run("arm-none-eabi-objdump", "-d", f"--start-address={addr}",
                  f"--stop-address={addr + size}", elf).stdout
        for line in dis.splitlines():
            m = row.match(line)
            if not m or m.group(3).startswith("."):  # literal pool words are data
                continue
            at, nbytes = int(m.group(1), 16), 2 * len(m.group(2).split())
            code = bytes(fw.uc.mem_read(at, nbytes))
            assert emu.thumb_instructions(code) == 1, f"{name}+{at - addr:#x}: {line}"
            if nbytes == 4:
                assert emu.thumb_instructions(code[:2] + b"\x00\xbf") == 1, line  # 32-bit
            checked += 1
    assert checked > 500


def test_profile_shares_add_up_to_the_tick_counts(tmp_path: Path) -> None:
    """odo-bench-target --profile: each function's own instructions per tick add up to the
    measured mean and to the worst tick's count, every share is a function of the ELF, and
    odo_app_step's own share is there (it is what the budget measures from)."""
    log = tmp_path / "run.log"
    log.write_text(LOG_LINES)
    out = tmp_path / "t.bin"
    r = run(TICKS, "--log", log, "--robot", ROBOT, "--ipec", "paper", "--out", out)
    assert r.returncode == 0, r.stderr
    elf = CM4 / "odo_bench_cm4.elf"
    block, ticks = bench.read_ticks(out, bench.record_sizes(elf))
    prof: dict = {}
    _, counts, differ = bench.emulate(elf, block, ticks, None, prof)
    assert not differ and len(counts) == 2
    assert abs(sum(prof["mean"].values()) - sum(counts) / len(counts)) < 0.5
    assert sum(prof["worst"].values()) == max(counts)
    symbols = emu.Firmware(elf, []).symbols
    assert set(prof["mean"]) <= set(symbols) and "odo_app_step" in prof["mean"]

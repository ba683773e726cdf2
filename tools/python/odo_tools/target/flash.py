"""odo-flash: program the Cortex-M4 image or its parameter block with openocd.

  odo-flash code   [--image ELF]   the image without its parameter sector (`make flash`)
  odo-flash params --params FILE   the parameter block alone (`make flash-params`)
  odo-flash all    [--image ELF]   everything, parameter sector included (`make flash-all`)

The parameter block lives alone in its flash erase sector (hal/cortexm/odo_cm4.ld). openocd's
`program` erases exactly the sectors its file touches, so `code` writes an Intel HEX of every
loaded section except .odo_params and the calibrated block on the part survives a firmware
update. `params` writes an Intel HEX holding only the block, taken from `odo-calib write` output
(.elf, Intel .hex or raw .bin image) or from a bare block (`odo-params defaults`, a raw .bin
starting with "ODOP"); its magic, version/length header and CRC-32 are checked before anything is
written. Addresses and sizes come from the image's linker symbols (__odo_params_start,
__odo_params_sector_start/_end, __odo_flash_start) and the block's own length field, never from
constants here.

The openocd command is `openocd -f hal/cortexm/openocd/odo_stm32f4.cfg -c "program FILE verify
reset exit"`; --dry-run prints it (and the file it would program) as JSON without running it.
Files go to a fresh temporary folder; nothing the user owns is written.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import struct
import subprocess
import sys
import tempfile
import zlib
from pathlib import Path

from elftools.elf.constants import SH_FLAGS
from elftools.elf.elffile import ELFFile
from elftools.elf.sections import SymbolTableSection

from ..resources import data_root

MAGIC = b"ODOP"
HEADER = 8  # magic, version (u16), length (u16): odo/odo_params.h


class FlashError(Exception):
    pass


def elf_symbols(elf: Path) -> dict[str, int]:
    with open(elf, "rb") as fh:
        e = ELFFile(fh)
        out = {}
        for sec in e.iter_sections():
            if isinstance(sec, SymbolTableSection):
                for s in sec.iter_symbols():
                    if s.name:
                        out[s.name] = s["st_value"]
        return out


def elf_loaded(elf: Path, skip: str | None) -> dict[int, bytes]:
    """Load address -> bytes of every section with contents, except `skip`."""
    chunks: dict[int, bytes] = {}
    with open(elf, "rb") as fh:
        e = ELFFile(fh)
        segs = [s for s in e.iter_segments() if s["p_type"] == "PT_LOAD"]
        for sec in e.iter_sections():
            if (not sec["sh_flags"] & SH_FLAGS.SHF_ALLOC or sec["sh_type"] == "SHT_NOBITS"
                    or sec["sh_size"] == 0 or sec.name == skip):
                continue
            vma, lma = sec["sh_addr"], sec["sh_addr"]
            for s in segs:
                if s["p_vaddr"] <= vma < s["p_vaddr"] + max(s["p_memsz"], 1):
                    lma = s["p_paddr"] + (vma - s["p_vaddr"])
                    break
            chunks[lma] = sec.data()
    return chunks


def read_hex(path: Path) -> dict[int, int]:
    mem: dict[int, int] = {}
    base = 0
    for n, line in enumerate(path.read_text().splitlines(), 1):
        line = line.strip()
        if not line:
            continue
        if not line.startswith(":"):
            raise FlashError(f"{path}:{n}: not an Intel HEX record")
        raw = bytes.fromhex(line[1:])
        if len(raw) < 5 or len(raw) != raw[0] + 5 or sum(raw) & 0xFF:
            raise FlashError(f"{path}:{n}: bad length or checksum")
        count, addr, rtype, data = raw[0], (raw[1] << 8) | raw[2], raw[3], raw[4:-1]
        if rtype == 0:
            for i in range(count):
                mem[base + addr + i] = data[i]
        elif rtype == 4:
            base = ((data[0] << 8) | data[1]) << 16
        elif rtype == 2:
            base = ((data[0] << 8) | data[1]) << 4
        elif rtype == 1:
            break
    return mem


def write_hex(path: Path, chunks: dict[int, bytes]) -> None:
    lines = []
    upper = None
    for start in sorted(chunks):
        data = chunks[start]
        for off in range(0, len(data), 16):
            addr = start + off
            piece = data[off : off + 16]
            if addr >> 16 != upper:
                upper = addr >> 16
                rec = bytes([2, 0, 0, 4, upper >> 8, upper & 0xFF])
                lines.append(":" + (rec + bytes([(-sum(rec)) & 0xFF])).hex().upper())
            rec = bytes([len(piece), (addr >> 8) & 0xFF, addr & 0xFF, 0]) + piece
            lines.append(":" + (rec + bytes([(-sum(rec)) & 0xFF])).hex().upper())
    lines.append(":00000001FF")
    path.write_text("\n".join(lines) + "\n")


def check_block(block: bytes, capacity: int, origin: str) -> bytes:
    """The block as its header declares it; raises FlashError on a bad one."""
    if len(block) < HEADER or block[:4] != MAGIC:
        raise FlashError(f"{origin}: no parameter block (magic is {block[:4]!r}, not {MAGIC!r})")
    _version, length = struct.unpack_from("<HH", block, 4)
    if length < HEADER + 4 or length > capacity or length > len(block):
        raise FlashError(f"{origin}: block length field {length} does not fit "
                         f"({len(block)} bytes available, sector capacity {capacity})")
    block = block[:length]
    (crc,) = struct.unpack_from("<I", block, length - 4)
    if zlib.crc32(block[: length - 4]) & 0xFFFFFFFF != crc:
        raise FlashError(f"{origin}: CRC-32 mismatch: the block is corrupt (odo-calib verify)")
    return block


def block_from(path: Path, syms: dict[str, int]) -> bytes:
    start, sector_end = syms["__odo_params_start"], syms["__odo_params_sector_end"]
    capacity = sector_end - start
    data: bytes
    if path.suffix == ".elf" or path.read_bytes()[:4] == b"\x7fELF":
        with open(path, "rb") as fh:
            sec = ELFFile(fh).get_section_by_name(".odo_params")
            if sec is None:
                raise FlashError(f"{path}: no .odo_params section")
            data = sec.data()
    elif path.suffix == ".hex":
        mem = read_hex(path)
        data = bytes(mem.get(a, 0xFF) for a in range(start, start + min(capacity, 4096)))
    else:
        raw = path.read_bytes()
        if raw[:4] == MAGIC:  # a bare block
            data = raw
        else:  # a raw image from the start of flash (odo-calib write --out fw.bin)
            off = start - syms["__odo_flash_start"]
            data = raw[off : off + min(capacity, 4096)]
    return check_block(data, capacity, str(path))


def openocd_argv(cfg: Path, target: Path) -> list[str]:
    return ["openocd", "-f", str(cfg), "-c", f"program {target} verify reset exit"]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="odo-flash", description=__doc__.splitlines()[0],
                                 epilog="See hal/cortexm/README.md, 'Flashing'.")
    ap.add_argument("what", choices=("code", "params", "all"))
    ap.add_argument("--image", type=Path, default=Path("build/cm4/bin/odo_image.elf"),
                    help="the built image (its linker symbols give every address)")
    ap.add_argument("--params", type=Path, help="params: odo-calib write output or a bare block")
    ap.add_argument("--cfg", type=Path, default=data_root() / "hal/cortexm/openocd/odo_stm32f4.cfg",
                    help="openocd configuration (default: the checkout's, or the installed one)")
    ap.add_argument("--dry-run", action="store_true",
                    help="print the openocd command and the file as JSON; program nothing")
    ap.add_argument("--keep", type=Path, help="write the programmed file here too")
    args = ap.parse_args(argv)
    try:
        if not args.image.is_file():
            raise FlashError(f"{args.image} missing (make cm4)")
        syms = elf_symbols(args.image)
        for s in ("__odo_params_start", "__odo_params_sector_start", "__odo_params_sector_end",
                  "__odo_flash_start"):
            if s not in syms:
                raise FlashError(f"{args.image}: linker symbol {s} missing (odo_cm4.ld)")
        with tempfile.TemporaryDirectory(prefix="odo-flash-") as tmpd:
            return program(args, syms, Path(tmpd))
    except (FlashError, OSError) as e:
        print(f"odo-flash: {e}", file=sys.stderr)
        return 1


def program(args: argparse.Namespace, syms: dict[str, int], tmp: Path) -> int:
    if args.what == "params":
        if args.params is None:
            raise FlashError("params needs --params FILE (odo-calib write output or a block)")
        block = block_from(args.params, syms)
        chunks = {syms["__odo_params_start"]: block}
        target = tmp / "odo_params.hex"
    else:
        skip = ".odo_params" if args.what == "code" else None
        chunks = elf_loaded(args.image, skip)
        target = tmp / f"odo_image_{args.what}.hex"
    lo, hi = syms["__odo_params_sector_start"], syms["__odo_params_sector_end"]
    in_sector = any(a < hi and a + len(d) > lo for a, d in chunks.items())
    if args.what == "code" and in_sector:
        raise FlashError(f"{args.image}: a section other than .odo_params lies in the "
                         f"parameter sector [{lo:#x}, {hi:#x}): refusing to erase it")
    write_hex(target, chunks)
    if args.keep is not None:  # a fresh temporary beside it, renamed into place
        part = args.keep.with_name(args.keep.name + ".part")
        shutil.copyfile(target, part)
        os.replace(part, args.keep)
    cmd = openocd_argv(args.cfg.resolve(), target)
    if args.dry_run:
        print(json.dumps({"argv": cmd, "file": str(target),
                          "ranges": [[a, a + len(d)] for a, d in sorted(chunks.items())],
                          "params_sector": [lo, hi], "writes_params_sector": in_sector}))
        return 0
    if shutil.which("openocd") is None:
        raise FlashError("openocd not found (make deps)")
    print("odo-flash: " + " ".join(cmd), file=sys.stderr)
    return subprocess.run(cmd).returncode


if __name__ == "__main__":
    sys.exit(main())

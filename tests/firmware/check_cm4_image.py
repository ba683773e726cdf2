#!/usr/bin/env python3
"""ctest firmware.cm4_image: cross-build the Cortex-M4 image and check what tools depend on.

Configures and builds the cm4 preset from the source tree (`cmake --preset cm4`, `cmake --build
--preset cm4`, into build/cm4; independent of the host build), then checks:

  * section .odo_params is at the fixed flash address, one block's size, alone in its erase
    sector, and the linker's __odo_params_start/__odo_params_size agree;
  * its bytes are a valid parameter block: "ODOP", the current version and length, CRC-32 (zlib)
    of all but the last 4 bytes in the last 4 (little-endian), as odo/odo_params.h specifies;
  * odo_image.bin holds the same bytes at (address - flash base), so `odo-calib write` can find
    it by magic in a raw image; odo_image.hex exists;
The block's size, version and CRC offset are read from `odo-params layout` (--layout), which
expands odo_params.h's field table, so this check holds no copy of them.
  * no soft-float, heap or stdio symbol is linked;
and prints the text/data/bss sizes. Exit 0 on success, 1 with the reasons on failure.
"""

from __future__ import annotations

import argparse
import json
import re
import shutil
import struct
import subprocess
import sys
import tempfile
import zlib
from pathlib import Path

FORBIDDEN_SYMBOLS = [
    (r"^__aeabi_[df]", "AEABI soft-float helper"),
    (r"^__(add|sub|mul|div|neg)[sdt]f3$", "libgcc soft-float arithmetic"),
    (r"^__(eq|ne|lt|le|gt|ge|unord|cmp)[sdt]f2$", "libgcc soft-float compare"),
    (r"^__(float|fix)", "int/float conversion"),
    (r"^__(extend|trunc)[sdt]f", "float/double conversion"),
    (r"^(_printf_float|_scanf_float|_dtoa_r|__ieee754)", "newlib floating point"),
    (r"^_*(malloc|calloc|realloc|free|sbrk)(_r)?$", "heap"),
    (r"^__malloc_", "heap"),
    (r"printf", "stdio formatting"),
    (r"^_*puts(_r)?$", "stdio"),
]

ODOP = b"ODOP"


def run(
    cmd: list[str], cwd: Path | None = None, echo: bool = False
) -> subprocess.CompletedProcess:
    if echo:
        print("+ " + " ".join(cmd), flush=True)
    proc = subprocess.run(
        cmd,
        cwd=cwd,
        text=True,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        check=False,
    )
    if echo and proc.stdout:
        print(proc.stdout, end="", flush=True)
    return proc


def tool(name: str) -> str:
    path = shutil.which(name)
    if path is None:
        raise SystemExit(
            f"firmware.cm4_image FAILED: {name} not found on PATH "
            "(install gcc-arm-none-eabi and libnewlib-arm-none-eabi: `make deps`)"
        )
    return path


def sections(objdump: str, elf: Path) -> dict[str, dict]:
    """Parse `objdump -h`: name -> size, vma, lma, flags."""
    out = run([objdump, "-h", str(elf)]).stdout.splitlines()
    result: dict[str, dict] = {}
    row = re.compile(
        r"^\s*\d+\s+(\S+)\s+([0-9a-fA-F]+)\s+([0-9a-fA-F]+)\s+([0-9a-fA-F]+)\s+"
    )
    for i, line in enumerate(out):
        m = row.match(line)
        if m:
            flags = out[i + 1].strip() if i + 1 < len(out) else ""
            result[m.group(1)] = {
                "size": int(m.group(2), 16),
                "vma": int(m.group(3), 16),
                "lma": int(m.group(4), 16),
                "flags": flags,
            }
    return result


def symbols(nm: str, elf: Path) -> dict[str, int]:
    result: dict[str, int] = {}
    for line in run([nm, "--defined-only", str(elf)]).stdout.splitlines():
        parts = line.split()
        if len(parts) == 3:
            result[parts[2]] = int(parts[0], 16)
    return result


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--source-dir", type=Path, required=True)
    ap.add_argument("--cmake", default="cmake")
    ap.add_argument("--params-addr", type=lambda s: int(s, 0), default=0x08004000)
    ap.add_argument(
        "--layout",
        type=Path,
        required=True,
        help="params_layout.json written by `odo-params layout` (the host build)",
    )
    ap.add_argument("--params-sector-size", type=lambda s: int(s, 0), default=0x4000)
    ap.add_argument("--flash-base", type=lambda s: int(s, 0), default=0x08000000)
    ap.add_argument(
        "--no-build", action="store_true", help="check an existing build/cm4 only"
    )
    args = ap.parse_args()

    objdump = tool("arm-none-eabi-objdump")
    objcopy = tool("arm-none-eabi-objcopy")
    nm = tool("arm-none-eabi-nm")
    size = tool("arm-none-eabi-size")
    tool("arm-none-eabi-gcc")

    src = args.source_dir.resolve()
    if not args.no_build:
        for cmd in (
            [args.cmake, "--preset", "cm4"],
            [args.cmake, "--build", "--preset", "cm4"],
        ):
            proc = run(cmd, cwd=src, echo=True)
            if proc.returncode != 0:
                print(
                    f"firmware.cm4_image FAILED: `{' '.join(cmd)}` exited {proc.returncode} "
                    "(output above)"
                )
                return 1

    bindir = src / "build" / "cm4" / "bin"
    elf, binf, hexf = (bindir / f"odo_image.{ext}" for ext in ("elf", "bin", "hex"))
    for f in (elf, binf, hexf):
        if not f.is_file():
            print(f"firmware.cm4_image FAILED: {f} was not produced by the cm4 build")
            return 1

    errors: list[str] = []
    try:
        layout = json.loads(args.layout.read_text())
    except (OSError, ValueError) as e:
        print(f"firmware.cm4_image FAILED: cannot read the layout {args.layout}: {e}")
        return 1
    addr, want_size = args.params_addr, layout["size"]
    params_version, crc_offset = layout["version"], layout["crc_offset"]

    secs = sections(objdump, elf)
    sec = secs.get(".odo_params")
    if sec is None:
        errors.append(
            f"{elf.name} has no .odo_params section (sections: {', '.join(secs)})"
        )
    else:
        if sec["vma"] != addr or sec["lma"] != addr:
            errors.append(
                f".odo_params is at VMA {sec['vma']:#010x} LMA {sec['lma']:#010x}, "
                f"must be at the fixed address {addr:#010x}"
            )
        if sec["size"] != want_size:
            errors.append(f".odo_params is {sec['size']} bytes, must be {want_size}")
        if "LOAD" not in sec["flags"] or "CONTENTS" not in sec["flags"]:
            errors.append(
                f".odo_params is not loaded into flash (flags: {sec['flags']})"
            )
    # The parameter sector is re-flashed alone, so nothing else may live in it.
    sector_end = addr + args.params_sector_size
    for name, s in secs.items():
        if name == ".odo_params" or "LOAD" not in s["flags"] or s["size"] == 0:
            continue
        if s["lma"] < sector_end and s["lma"] + s["size"] > addr:
            errors.append(
                f"section {name} ({s['lma']:#010x}+{s['size']:#x}) overlaps the "
                f"parameter sector [{addr:#010x}, {sector_end:#010x})"
            )

    syms = symbols(nm, elf)
    for name, want in (
        ("__odo_params_start", addr),
        ("__odo_params_size", want_size),
        ("odo_param_block", addr),
    ):
        if syms.get(name) != want:
            got = "missing" if name not in syms else f"{syms[name]:#x}"
            errors.append(f"symbol {name} is {got}, must be {want:#x}")

    bad = []
    for name in sorted(syms):
        for pattern, why in FORBIDDEN_SYMBOLS:
            if re.search(pattern, name):
                bad.append(f"{name} ({why})")
                break
    if bad:
        errors.append(
            "the image links floating-point, heap or stdio code (see odo_image.map, "
            "'Archive member included'): " + ", ".join(bad)
        )

    block = b""
    with tempfile.TemporaryDirectory() as tmp:
        raw = Path(tmp) / "odo_params.bin"
        proc = run(
            [objcopy, "-O", "binary", "--only-section=.odo_params", str(elf), str(raw)]
        )
        if proc.returncode != 0 or not raw.is_file():
            errors.append(f"objcopy --only-section=.odo_params failed: {proc.stdout}")
        else:
            block = raw.read_bytes()
    if block:
        if len(block) != want_size:
            errors.append(
                f"extracted .odo_params is {len(block)} bytes, must be {want_size}"
            )
        else:
            magic = block[0:4]
            version, length = struct.unpack_from("<HH", block, 4)
            (crc_stored,) = struct.unpack_from("<I", block, crc_offset)
            crc = zlib.crc32(block[:crc_offset]) & 0xFFFFFFFF
            if magic != ODOP:
                errors.append(f"parameter block magic is {magic!r}, must be {ODOP!r}")
            if version != params_version:
                errors.append(
                    f"parameter block version is {version}, must be {params_version}"
                )
            if length != want_size:
                errors.append(
                    f"parameter block length field is {length}, must be {want_size}"
                )
            if crc_stored != crc:
                errors.append(
                    f"parameter block CRC field is {crc_stored:#010x}, but "
                    f"zlib.crc32(block[:{crc_offset}]) is {crc:#010x}"
                )
            print(
                f"parameter block at {addr:#010x}: magic {magic!r} version {version} "
                f"length {length} crc {crc_stored:#010x} (computed {crc:#010x})"
            )

        image = binf.read_bytes()
        off = addr - args.flash_base
        if image[off : off + want_size] != block:
            errors.append(
                f"{binf.name} does not hold the parameter block at offset {off:#x} "
                f"(image is {len(image)} bytes)"
            )
        elif image.find(ODOP) != off:
            errors.append(
                f'the first "ODOP" in {binf.name} is at {image.find(ODOP):#x}, not at '
                f"the parameter block {off:#x}: a tool searching by magic would be fooled"
            )

    print(run([size, str(elf)]).stdout, end="")
    print(run([size, "-A", "-x", str(elf)]).stdout, end="")

    if errors:
        print("firmware.cm4_image FAILED:")
        for e in errors:
            print("  - " + e)
        return 1
    print(
        "firmware.cm4_image: image layout, parameter block and symbol set are as specified"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())

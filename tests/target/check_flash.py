#!/usr/bin/env python3
"""ctest target.openocd_flash_check: what `make flash` and `make flash-params` would program, and
openocd's own parsing of the configuration they use (no adapter needed).

  1. `make -n flash` / `make -n flash-params` run `odo-flash code` / `odo-flash params` on the cm4
     image: the command lines checked below are the ones the Makefile uses.
  2. `odo-flash code --dry-run`: the openocd command is `-f <cfg> -c "program <hex> verify reset
     exit"`; the hex holds exactly what binutils' objcopy gives for the image without .odo_params
     and not one byte in the parameter sector (linker symbols __odo_params_sector_start/_end).
  3. openocd parses <cfg> (interface, transport, target, flash bank) and knows `program`: the same
     argv with the program command replaced by queries and `shutdown`, before any adapter init.
  4. `odo-calib write` output (.elf, .hex, raw .bin) of a changed block: `odo-flash params` takes
     the block from each and programs exactly that block at __odo_params_start; the .hex that
     odo-calib writes holds it at that address too, so openocd can program it as it is.
  5. A block with a bad CRC is refused: exit 1, nothing written.
"""

from __future__ import annotations

import argparse
import json
import re
import subprocess
import sys
import tempfile
from pathlib import Path

from odo_tools.target.flash import elf_symbols, read_hex

errors: list[str] = []


def check(ok: bool, what: str) -> None:
    print(("ok: " if ok else "FAILED: ") + what)
    if not ok:
        errors.append(what)


def run(cmd: list[str], **kw) -> subprocess.CompletedProcess:
    return subprocess.run(cmd, capture_output=True, text=True, **kw)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--source-dir", type=Path, required=True)
    ap.add_argument("--build-dir", type=Path, required=True, help="host build (odo-calib)")
    ap.add_argument("--venv", type=Path, required=True)
    args = ap.parse_args()
    src = args.source_dir.resolve()
    image = src / "build/cm4/bin/odo_image.elf"
    flash = str(args.venv / "bin/odo-flash")
    syms = elf_symbols(image)
    lo, hi = syms["__odo_params_sector_start"], syms["__odo_params_sector_end"]
    start = syms["__odo_params_start"]

    # 1. The Makefile's command lines.
    for target, want in (("flash", r"odo-flash code --image build/cm4/bin/odo_image\.elf"),
                         ("flash-params", r"odo-flash params --image build/cm4/bin/odo_image\.elf "
                                          r"--params \"x\.elf\"")):
        out = run(["make", "-n", target, "PARAMS=x.elf"], cwd=src).stdout
        check(re.search(want, out) is not None, f"make {target} runs `{want}`")

    with tempfile.TemporaryDirectory() as tmpd:
        tmp = Path(tmpd)
        # 2. make flash: the code image without the parameter sector.
        code_hex = tmp / "code.hex"
        p = run([flash, "code", "--image", str(image), "--dry-run", "--keep", str(code_hex)],
                cwd=src)
        check(p.returncode == 0, f"odo-flash code --dry-run exits 0 ({p.stderr.strip()})")
        plan = json.loads(p.stdout)
        argv = plan["argv"]
        cfg = Path(argv[argv.index("-f") + 1])
        check(argv[0] == "openocd" and cfg.name == "odo_stm32f4.cfg" and cfg.is_file(),
              f"openocd -f {cfg}")
        check(argv[-2:] == ["-c", f"program {plan['file']} verify reset exit"],
              "the action is `program <hex> verify reset exit`")
        mem = read_hex(code_hex)
        check(not any(lo <= a < hi for a in mem),
              "no byte of the code image in the parameter sector")
        ref_hex = tmp / "objcopy.hex"
        run(["arm-none-eabi-objcopy", "-O", "ihex", "--remove-section=.odo_params", str(image),
             str(ref_hex)], check=True)
        check(mem == read_hex(ref_hex), "the code image equals objcopy's image without .odo_params")

        # 3. openocd parses the configuration (no adapter: stop before init).
        probe = ("echo \"banks: [flash list]\"; echo \"transport: [transport select]\"; "
                 "if {[llength [info procs program]] == 0} {error \"no program command\"}; "
                 "shutdown")
        oc = run([*argv[:-2], "-c", probe], timeout=60)
        log = oc.stdout + oc.stderr
        check(oc.returncode == 0, f"openocd parses {cfg.name} and exits 0")
        check("driver stm32f2x" in log, "openocd configured the STM32F4 flash bank (stm32f2x)")
        check("transport: hla_swd" in log, "openocd selected SWD through the ST-LINK (hla_swd)")
        bad = run(["openocd", "-f", str(cfg), "-c", "no_such_command; shutdown"], timeout=60)
        check(bad.returncode != 0, "openocd fails on a bad command (the parse check can fail)")

        # 4. odo-calib write output, three formats, one changed block.
        calib = args.build_dir / "bin/odo-calib"
        params_tool = args.build_dir / "bin/odo-params"
        block_file = tmp / "block.bin"
        run(["arm-none-eabi-objcopy", "-O", "binary", "--only-section=.odo_params", str(image),
             str(block_file)], check=True)
        shown = json.loads(run([str(params_tool), "show", str(block_file)], check=True).stdout)
        shown["truck"][0]["wheel_diameter_nm"] += 1000  # a calibration of 1 um
        pj = tmp / "calibrated.json"
        pj.write_text(json.dumps(shown))
        blocks = {}
        for ext in ("elf", "hex", "bin"):
            src_img = image if ext == "elf" else image.with_suffix(f".{ext}")
            out_img = tmp / f"fw.{ext}"
            w = run([str(calib), "write", "--image", str(src_img), "--params", str(pj),
                     "--out", str(out_img)])
            check(w.returncode == 0, f"odo-calib write --out fw.{ext} ({w.stderr.strip()})")
            kept = tmp / f"params-{ext}.hex"
            p = run([flash, "params", "--image", str(image), "--params", str(out_img),
                     "--dry-run", "--keep", str(kept)], cwd=src)
            check(p.returncode == 0, f"odo-flash params takes fw.{ext} ({p.stderr.strip()})")
            m = read_hex(kept)
            check(min(m) == start and max(m) < hi, f"fw.{ext}: only the block, at {start:#x}")
            blocks[ext] = bytes(m[a] for a in sorted(m))
            if ext == "hex":
                fw = read_hex(out_img)
                check(bytes(fw.get(a, 0) for a in range(start, start + len(blocks[ext])))
                      == blocks[ext], "odo-calib's .hex holds the block at its flash address")
        check(len(set(blocks.values())) == 1, "the same block from .elf, .hex and .bin")
        old = block_file.read_bytes()
        check(blocks["elf"] != old[: len(blocks["elf"])],
              "the calibrated block differs from the default")

        # 5. A corrupt block is refused.
        bad_block = bytearray(blocks["elf"])
        bad_block[20] ^= 1
        (tmp / "bad.bin").write_bytes(bytes(bad_block))
        kept = tmp / "bad.hex"
        p = run([flash, "params", "--image", str(image), "--params", str(tmp / "bad.bin"),
                 "--dry-run", "--keep", str(kept)], cwd=src)
        check(p.returncode == 1 and "CRC" in p.stderr and not kept.exists(),
              "a block with a bad CRC is refused, nothing written")

    print(f"{len(errors)} failed" if errors else "flash commands and openocd configuration hold")
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())

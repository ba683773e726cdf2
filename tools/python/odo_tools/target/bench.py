"""odo-bench-target: the firmware's cost on its Cortex-M4, printed as one JSON object.

`make bench-target` runs it. Steps:
  1. a recorded clapper run: odo-sim's UMBmark square, run cw-01, no effects (a candump log,
     deterministic), replayed on the host build by odo-target-ticks with IPEC off, in the paper's
     form and with the estimator: each tick's input and the host's output;
  2. the same inputs through odo_app_init/odo_app_step of the cm4 build (-O2, soft float,
     newlib-nano; build/cm4/bin/odo_bench_cm4.elf) in the unicorn emulator, counting executed
     instructions inside those two calls; every output must be byte-identical to the host's;
  3. flash (loaded sections of build/cm4/bin/odo_image.elf, split by origin from its map), static
     RAM and the worst stack from reset (-fstack-usage frames over the disassembled call graph,
     plus one exception; odo_tools.target.stack).
Budgets (issue 15) are checked and printed; a missed budget is reported, not an error. Exit 1 only
if something could not be measured or an output differs from the host's.

`--qemu-cross-check N` instead runs the first N ticks of the paper-form run under qemu's
mps2-an386 with one instruction per translation block and its execution log (-singlestep -d
exec,nochain), counts the same calls from that log and compares them call by call with unicorn.
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
import time
from pathlib import Path

import unicorn

from odo_tools.target.emu import Firmware
from odo_tools.target.stack import flash_by_origin, section_sizes, worst_stack

MODES = ("off", "paper", "estimator")
FLASH_BASE, FLASH_END = 0x08000000, 0x08100000
RAM_BASE = 0x20000000

# Issue 15 item 3: instructions per 40 ms tick (worst tick), flash of the image, static RAM plus
# worst stack.
BUDGETS = {
    "cm4_instr_tick_off_max": 900,
    "cm4_instr_tick_paper_max": 1500,
    "cm4_instr_tick_estimator_max": 1500,
    "cm4_flash_bytes": 8192,
    "cm4_ram_bytes": 1024,
}


def log(msg: str) -> None:
    print(f"odo-bench-target: {msg}", file=sys.stderr, flush=True)


def run(cmd: list[str]) -> None:
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        raise SystemExit(f"odo-bench-target: `{' '.join(cmd)}` failed:\n{proc.stdout}{proc.stderr}")


def record_sizes(elf: Path) -> tuple[int, int]:
    """ODO_BENCH_IN_SIZE and ODO_BENCH_OUT_SIZE (bench_codec.h), as the harness's buffers."""
    fw = Firmware(elf, [])
    return fw.symbols["odo_bench_in"][1], fw.symbols["odo_bench_out"][1]


def read_ticks(path: Path, sizes: tuple[int, int]) -> tuple[bytes, list[tuple[bytes, bytes]]]:
    in_size, out_size = sizes
    data = path.read_bytes()
    if data[:4] != b"ODOT":
        raise SystemExit(f"odo-bench-target: {path} is not a ticks file")
    _, n, blen = struct.unpack_from("<III", data, 4)
    block, off = data[16 : 16 + blen], 16 + blen
    if len(data) != off + n * (in_size + out_size):
        raise SystemExit(f"odo-bench-target: {path}: size does not match {n} ticks")
    ticks = []
    for _ in range(n):
        ticks.append((data[off : off + in_size], data[off + in_size : off + in_size + out_size]))
        off += in_size + out_size
    return block, ticks


def make_ticks(args: argparse.Namespace, work: Path) -> dict[str, Path]:
    src, bindir = args.source_dir, args.build_dir / "bin"
    for tool in ("odo-sim", "odo-target-ticks"):
        if not (bindir / tool).is_file():
            raise SystemExit(f"odo-bench-target: {bindir / tool} missing (make release)")
    log("recording the clapper run (odo-sim --experiment umbmark --vehicle clapper)")
    run([str(bindir / "odo-sim"), "--experiment", "umbmark", "--vehicle", "clapper",
         "--scenario", str(src / "host_sim/scenarios/none.json"), "--out", str(work / "run")])
    out = {}
    for mode in MODES:
        out[mode] = work / f"ticks-{mode}.bin"
        run([str(bindir / "odo-target-ticks"), "--log", str(work / "run/run-cw-01.log"),
             "--robot", str(src / "host_sim/robots/clapper.json"), "--ipec", mode,
             "--out", str(out[mode])])
    return out


def emulate(elf: Path, block: bytes, ticks: list[tuple[bytes, bytes]], limit: int | None,
            profile: dict | None = None):
    """Init and every tick; returns (init count, per-tick counts, ticks whose output differs).
    With profile (a dict), also fills it with each function's own instructions per tick: the
    mean over the run ("mean") and the worst tick's ("worst")."""
    fw = Firmware(elf, ["odo_app_init", "odo_app_step"], profile=profile is not None)
    fw.write("odo_bench_block", block)
    status, init = fw.call("odo_bench_init", len(block))
    if status != 0:
        raise SystemExit(f"odo-bench-target: the M4 rejected the parameter block ({status})")
    counts, differ = [], []
    tally = fw.counter.by_function
    if tally is not None:
        tally.clear()
    worst: dict[str, int] = {}
    for i, (tin, want) in enumerate(ticks[:limit]):
        fw.write("odo_bench_in", tin)
        before = tally.copy() if tally is not None else None
        _, n = fw.call("odo_bench_step")
        if tally is not None and (not counts or n > max(counts)):
            worst = dict((tally - before).most_common())
        counts.append(n)
        if fw.read("odo_bench_out") != want:
            differ.append(i)
    if profile is not None and tally is not None and counts:
        profile["mean"] = {k: round(v / len(counts), 1) for k, v in tally.most_common()}
        profile["worst"] = worst
    return init, counts, differ


def memory_figures(args: argparse.Namespace) -> dict:
    image = args.cm4_dir / "bin/odo_image.elf"
    secs = section_sizes(image)
    flash = sum(size for size, _, lma, loaded in secs.values()
                if loaded and FLASH_BASE <= lma < FLASH_END)
    static_ram = sum(size for size, vma, _, _ in secs.values()
                     if RAM_BASE <= vma < RAM_BASE + (1 << 24))
    st = worst_stack(args.objdump, image, [args.cm4_dir / "firmware", args.cm4_dir / "hal"])
    origin = flash_by_origin(args.cm4_dir / "bin/odo_image.map", FLASH_BASE, FLASH_END)
    return {
        "cm4_flash_bytes": flash,
        "cm4_flash_by_origin": dict(sorted(origin.items())),
        "cm4_static_ram_bytes": static_ram,
        "cm4_stack_bytes": st.worst_bytes,
        "cm4_stack_reset_path_bytes": st.reset_path_bytes,
        "cm4_stack_reset_path": st.reset_path,
        "cm4_stack_exception_bytes": st.exception_bytes,
        "cm4_stack_unknown": st.unknown,
        "cm4_ram_bytes": static_ram + st.worst_bytes,
    }


def qemu_cross_check(args: argparse.Namespace, ticks_file: Path, n: int, work: Path) -> int:
    elf = args.cm4_dir / "bin/odo_bench_cm4.elf"
    block, ticks = read_ticks(ticks_file, record_sizes(elf))
    ticks = ticks[:n]
    # The harness reads odo_ticks.bin from qemu's working directory (semihosting).
    hdr = b"ODOT" + struct.pack("<III", 1, len(ticks), len(block))
    (work / "odo_ticks.bin").write_bytes(hdr + block + b"".join(a + b for a, b in ticks))
    qemu = shutil.which("qemu-system-arm")
    if qemu is None:
        raise SystemExit("odo-bench-target: qemu-system-arm not found (make deps)")
    proc = subprocess.run(
        [qemu, "-M", "mps2-an386", "-display", "none", "-monitor", "none", "-serial", "none",
         "-semihosting-config", "enable=on,target=native", "-kernel", str(elf.resolve()),
         "-singlestep", "-d", "exec,nochain", "-D", "qemu-exec.log"],
        cwd=work, capture_output=True, text=True, timeout=300)
    if proc.returncode != 0:
        print(proc.stdout + proc.stderr)
        return 1
    fw = Firmware(elf, [])
    entries = {fw.addr("odo_app_init") & ~1, fw.addr("odo_app_step") & ~1}
    pc_re = re.compile(r"\[[0-9a-f]+/([0-9a-f]+)/")
    q_counts, active, prev, ret, c = [], False, 0, 0, 0
    with open(work / "qemu-exec.log") as fh:
        for line in fh:
            m = pc_re.search(line)
            if not m:
                continue
            pc = int(m.group(1), 16)
            if not active:
                if pc in entries:
                    active, ret, c = True, prev + 4, 1  # called by a 32-bit bl at prev
            elif pc == ret:
                q_counts.append(c)
                active = False
            else:
                c += 1
            prev = pc
    init, counts, differ = emulate(elf, block, ticks, None)
    u_counts = [init, *counts]
    same = q_counts == u_counts
    print(json.dumps({
        "calls": len(u_counts), "qemu_instructions": sum(q_counts),
        "unicorn_instructions": sum(u_counts), "identical_per_call": same,
        "outputs_differ": len(differ), "qemu": proc.stdout.strip(),
    }, indent=2))
    return 0 if same and not differ else 1


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="odo-bench-target", description=__doc__.splitlines()[0],
                                 epilog="Figures and budgets: README.md, 'Firmware on the target'.")
    ap.add_argument("--source-dir", type=Path, default=Path("."))
    ap.add_argument("--build-dir", type=Path, default=Path("build/release"),
                    help="host build with odo-sim and odo-target-ticks (default build/release)")
    ap.add_argument("--cm4-dir", type=Path, default=Path("build/cm4"))
    ap.add_argument("--objdump", default="arm-none-eabi-objdump")
    ap.add_argument("--ticks", type=int, default=None, help="only the first N ticks of each run")
    ap.add_argument("--qemu-cross-check", type=int, metavar="N", default=None,
                    help="compare unicorn's counts with qemu's execution log over N ticks")
    ap.add_argument("--profile", action="store_true",
                    help="also each function's own instructions per tick (mean, and in the worst "
                    "tick) as cm4_profile_<mode>: where a budget goes")
    ap.add_argument("--json", action="store_true", help="JSON only (the default prints it too)")
    args = ap.parse_args(argv)
    for p in (args.cm4_dir / "bin/odo_bench_cm4.elf", args.cm4_dir / "bin/odo_image.elf"):
        if not p.is_file():
            raise SystemExit(f"odo-bench-target: {p} missing (make cm4)")

    with tempfile.TemporaryDirectory(prefix="odo-bench-target-") as tmpd:
        work = Path(tmpd)
        files = make_ticks(args, work)
        if args.qemu_cross_check is not None:
            return qemu_cross_check(args, files["paper"], args.qemu_cross_check, work)
        res: dict = {"counting_tool": f"unicorn {unicorn.__version__} (Cortex-M4, "
                     "translation-block hook, Thumb-2 instruction lengths)"}
        elf = args.cm4_dir / "bin/odo_bench_cm4.elf"
        bad = 0
        for mode in MODES:
            t0 = time.monotonic()
            block, ticks = read_ticks(files[mode], record_sizes(elf))
            prof: dict | None = {} if args.profile else None
            init, counts, differ = emulate(elf, block, ticks, args.ticks, prof)
            if prof is not None:
                res[f"cm4_profile_{mode}"] = prof
            log(f"IPEC {mode}: {len(counts)} ticks in {time.monotonic() - t0:.1f} s, "
                f"{len(differ)} outputs differ from the host's")
            res[f"cm4_instr_tick_{mode}_mean"] = round(sum(counts) / len(counts), 1)
            res[f"cm4_instr_tick_{mode}_max"] = max(counts)
            res[f"cm4_instr_tick_{mode}_min"] = min(counts)
            res[f"cm4_outputs_differ_{mode}"] = len(differ)
            res["cm4_instr_init"] = init
            res["cm4_ticks"] = len(counts)
            bad += len(differ)
    res["cm4_outputs_bit_identical"] = bad == 0
    res.update(memory_figures(args))
    res["budgets"] = {k: {"value": res[k], "limit": v, "met": res[k] <= v}
                      for k, v in BUDGETS.items()}
    res["budgets_met"] = all(b["met"] for b in res["budgets"].values())
    print(json.dumps(res, indent=2))
    if not args.json:
        for k, b in res["budgets"].items():
            log(f"{k} {b['value']} (budget <= {b['limit']}): {'met' if b['met'] else 'MISSED'}")
    return 0 if bad == 0 and not res["cm4_stack_unknown"] else 1


if __name__ == "__main__":
    sys.exit(main())

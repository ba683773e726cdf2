"""Worst-case stack from reset and the flash/RAM split of a Cortex-M4 image.

Stack: every function's frame comes from GCC's -fstack-usage files (<object>.su, written by the
cm4 build) or, for library code built without them (libgcc, newlib), from its prologue in the
disassembly (push/stmdb of n registers: 4 n bytes; sub sp: its immediate). The call graph comes
from the image's disassembly: bl/blx to a symbol and branches to another function (tail calls).
The worst path from Reset_Handler is the longest frame sum over that graph; on top of it one
exception may arrive at any time (NMI, HardFault): its 32-byte basic stack frame (the FPU is off,
so no extended frame; Armv7-M ARM B1.5.6) plus the deepest handler's own path.

A call through a register (blx rN) or recursion makes the bound unknown; both are reported rather
than guessed.
"""

from __future__ import annotations

import re
import subprocess
from dataclasses import dataclass, field
from pathlib import Path

EXCEPTION_FRAME_BYTES = 32
FUNC_RE = re.compile(r"^([0-9a-f]+) <([^>]+)>:$")
INSN_RE = re.compile(r"^\s*([0-9a-f]+):\s+(\S+)\s*(.*)$")
BRANCH_RE = re.compile(r"^(bl|blx|b|b\.w|b\.n|beq|bne|bcs|bcc|bhi|bls|bge|blt|bgt|ble|bmi|bpl|"
                       r"beq\.w|bne\.w|cbz|cbnz)$")
TARGET_RE = re.compile(r"<([^>+]+)(\+0x[0-9a-f]+)?>")


@dataclass
class Func:
    name: str
    addr: int
    insns: list[tuple[str, str]] = field(default_factory=list)
    callees: set[str] = field(default_factory=set)
    indirect: bool = False
    frame: int = 0
    frame_from: str = ""


def disassemble(objdump: str, elf: Path) -> dict[str, Func]:
    out = subprocess.run([objdump, "-d", "--no-show-raw-insn", str(elf)], capture_output=True,
                         text=True, check=True).stdout
    funcs: dict[str, Func] = {}
    cur: Func | None = None
    for line in out.splitlines():
        m = FUNC_RE.match(line)
        if m:
            cur = funcs.setdefault(m.group(2), Func(m.group(2), int(m.group(1), 16)))
            continue
        m = INSN_RE.match(line)
        if cur is None or not m:
            continue
        op, args = m.group(2), m.group(3)
        cur.insns.append((op, args))
        if op in ("blx", "bx") and re.match(r"^(r\d+|ip|sl|fp)\b", args):
            if op == "blx":
                cur.indirect = True
            continue
        if BRANCH_RE.match(op):
            t = TARGET_RE.search(args)
            if t and t.group(1) != cur.name:
                cur.callees.add(t.group(1))
    return funcs


def prologue_frame(f: Func) -> int:
    """Bytes a function without a .su entry pushes: its largest push plus every sub sp."""
    push = sub = 0
    for op, args in f.insns:
        if op in ("push", "push.w") or (op.startswith("stmdb") and args.startswith("sp!")):
            regs = re.search(r"\{([^}]*)\}", args)
            if regs:
                n = 0
                for part in regs.group(1).split(","):
                    part = part.strip()
                    r = re.match(r"r(\d+)-r(\d+)", part)
                    n += int(r.group(2)) - int(r.group(1)) + 1 if r else 1
                push = max(push, 4 * n)
        elif op in ("sub", "sub.w", "subw") and re.match(r"sp,\s*(sp,\s*)?#", args):
            sub += int(args.rsplit("#", 1)[1].split()[0], 0)
    return push + sub


def read_su(dirs: list[Path]) -> dict[str, tuple[int, str]]:
    frames: dict[str, tuple[int, str]] = {}
    for d in dirs:
        for su in d.rglob("*.su"):
            for line in su.read_text().splitlines():
                parts = line.split("\t")
                if len(parts) < 3:
                    continue
                name = parts[0].rsplit(":", 1)[-1]
                size = int(parts[1])
                if name not in frames or size > frames[name][0]:
                    frames[name] = (size, parts[2])
    return frames


@dataclass
class StackReport:
    reset_path_bytes: int
    reset_path: list[str]
    exception_bytes: int
    exception_path: list[str]
    unknown: list[str]

    @property
    def worst_bytes(self) -> int:
        return self.reset_path_bytes + self.exception_bytes


def worst_stack(objdump: str, elf: Path, su_dirs: list[Path]) -> StackReport:
    funcs = disassemble(objdump, elf)
    su = read_su(su_dirs)
    unknown: list[str] = []
    for f in funcs.values():
        if f.name in su:
            f.frame, kind = su[f.name]
            f.frame_from = "su"
            if kind.startswith("dynamic") and "bounded" not in kind:
                unknown.append(f"{f.name}: dynamic stack")
        else:
            f.frame, f.frame_from = prologue_frame(f), "prologue"
    memo: dict[str, tuple[int, list[str]]] = {}
    onstack: set[str] = set()

    def walk(name: str) -> tuple[int, list[str]]:
        if name in memo:
            return memo[name]
        f = funcs.get(name)
        if f is None:
            return 0, [name]
        if name in onstack:
            unknown.append(f"{name}: recursion")
            return 0, [name]
        onstack.add(name)
        if f.indirect:
            unknown.append(f"{name}: call through a register")
        best, path = 0, []
        for c in sorted(f.callees):
            d, p = walk(c)
            if d > best:
                best, path = d, p
        onstack.discard(name)
        memo[name] = (f.frame + best, [name, *path])
        return memo[name]

    reset, reset_path = walk("Reset_Handler")
    exc, exc_path = 0, []
    for name in funcs:
        if name.endswith("_Handler") and name != "Reset_Handler":
            d, p = walk(name)
            if d >= exc:
                exc, exc_path = d, p
    return StackReport(reset, reset_path, exc + EXCEPTION_FRAME_BYTES, exc_path,
                       sorted(set(unknown)))


def section_sizes(elf: Path) -> dict[str, tuple[int, int, int, bool]]:
    """name -> (size, vma, lma, has contents), from the ELF's section and program headers."""
    from elftools.elf.constants import SH_FLAGS
    from elftools.elf.elffile import ELFFile

    result = {}
    with open(elf, "rb") as fh:
        e = ELFFile(fh)
        segs = [s for s in e.iter_segments() if s["p_type"] == "PT_LOAD"]
        for sec in e.iter_sections():
            if not sec["sh_flags"] & SH_FLAGS.SHF_ALLOC or sec["sh_size"] == 0:
                continue
            vma, lma = sec["sh_addr"], sec["sh_addr"]
            for s in segs:
                if s["p_vaddr"] <= vma < s["p_vaddr"] + max(s["p_memsz"], 1):
                    lma = s["p_paddr"] + (vma - s["p_vaddr"])
                    break
            result[sec.name] = (sec["sh_size"], vma, lma, sec["sh_type"] != "SHT_NOBITS")
    return result


def flash_by_origin(map_file: Path, flash_lo: int, flash_hi: int) -> dict[str, int]:
    """Bytes of flash per origin (firmware core, board port, libgcc, libc) from the linker map's
    input-section lines (alignment fill is not attributed)."""
    body = map_file.read_text().split("Linker script and memory map", 1)[-1]
    one_line = re.compile(r"^ (\.\S+|COMMON)\s+0x([0-9a-f]+)\s+0x([0-9a-f]+)\s+(\S+)$")
    name_only = re.compile(r"^ (\.\S+|COMMON)$")
    cont = re.compile(r"^\s+0x([0-9a-f]+)\s+0x([0-9a-f]+)\s+(\S+)$")
    origins: dict[str, int] = {}
    pending = False
    for line in body.splitlines():
        m = one_line.match(line)
        if m:
            addr, size, obj = int(m.group(2), 16), int(m.group(3), 16), m.group(4)
        elif name_only.match(line):
            pending = True
            continue
        elif pending and (m := cont.match(line)):
            addr, size, obj = int(m.group(1), 16), int(m.group(2), 16), m.group(3)
        else:
            pending = False
            continue
        pending = False
        if flash_lo <= addr < flash_hi and size:
            key = classify(obj)
            origins[key] = origins.get(key, 0) + size
    return origins


def classify(obj: str) -> str:
    if "libodo_core" in obj:
        return "core"  # firmware/src: the portable core
    if "libodo_app" in obj:
        return "app"  # firmware/app: the 40 ms step and the loop
    if "libgcc" in obj:
        return "libgcc"
    if "libc" in obj or "libg_nano" in obj or "libnosys" in obj:
        return "libc"
    return "board"

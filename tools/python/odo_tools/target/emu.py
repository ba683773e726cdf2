"""Run functions of a Cortex-M4 ELF in the unicorn emulator and count executed instructions.

Counting works per translation block: unicorn reports each block's start address and byte size,
and a Thumb-2 block's instruction count follows from the halfword encodings (a first halfword
whose top five bits are 0b11101, 0b11110 or 0b11111 starts a 32-bit instruction; Armv7-M ARM
A5.1). A measured function is counted from the block at its entry address until execution
reaches the return address it was called with (LR at entry), calls inside included.
"""

from __future__ import annotations

import bisect
from collections import Counter as Tally
from dataclasses import dataclass, field
from pathlib import Path

from elftools.elf.elffile import ELFFile
from elftools.elf.sections import SymbolTableSection
from unicorn import UC_ARCH_ARM, UC_HOOK_BLOCK, UC_MODE_MCLASS, UC_MODE_THUMB, Uc
from unicorn.arm_const import (
    UC_ARM_REG_LR,
    UC_ARM_REG_R0,
    UC_ARM_REG_R1,
    UC_ARM_REG_SP,
    UC_CPU_ARM_CORTEX_M4,
)

# The mps2-an386 memory map the harness is linked for (tests/target/mps2_an386.ld).
CODE_BASE, CODE_SIZE = 0x00000000, 4 << 20
RAM_BASE, RAM_SIZE = 0x20000000, 4 << 20
RETURN_TRAP = CODE_BASE + CODE_SIZE - 0x100  # mapped, never linked: "the caller"


def thumb_instructions(code: bytes) -> int:
    """Number of Thumb-2 instructions in a straight run of code."""
    n = i = 0
    while i + 1 < len(code):
        hw = code[i] | (code[i + 1] << 8)
        i += 4 if (hw >> 11) in (0b11101, 0b11110, 0b11111) else 2
        n += 1
    return n


@dataclass
class Counter:
    """Instructions spent in the measured functions, per call."""

    entries: dict[int, str]
    active: str | None = None
    ret: int = 0
    count: int = 0
    cache: dict[tuple[int, int], int] = field(default_factory=dict)
    # With profiling on: instructions per function (self, by the address of each block).
    by_function: Tally[str] | None = None


class Firmware:
    """An ELF loaded into a fresh emulated Cortex-M4."""

    def __init__(self, elf: Path, measured: list[str], profile: bool = False) -> None:
        with open(elf, "rb") as f:
            e = ELFFile(f)
            self.symbols: dict[str, tuple[int, int]] = {}
            for sec in e.iter_sections():
                if isinstance(sec, SymbolTableSection):
                    for s in sec.iter_symbols():
                        if s.name and s["st_info"]["type"] in ("STT_FUNC", "STT_OBJECT"):
                            self.symbols[s.name] = (s["st_value"], s["st_size"])
            self.uc = Uc(UC_ARCH_ARM, UC_MODE_THUMB | UC_MODE_MCLASS)
            self.uc.ctl_set_cpu_model(UC_CPU_ARM_CORTEX_M4)
            self.uc.mem_map(CODE_BASE, CODE_SIZE)
            self.uc.mem_map(RAM_BASE, RAM_SIZE)
            for seg in e.iter_segments():
                if seg["p_type"] == "PT_LOAD" and seg["p_filesz"] > 0:
                    self.uc.mem_write(seg["p_vaddr"], seg.data())
        # `bx lr` back to the trap address ends a call: a 16-bit `b .` there keeps it harmless.
        self.uc.mem_write(RETURN_TRAP, b"\xfe\xe7")
        self.counter = Counter({self.addr(n) & ~1: n for n in measured})
        if profile:
            self.counter.by_function = Tally()
        funcs = sorted((a & ~1, n) for n, (a, size) in self.symbols.items() if size > 0)
        self._func_starts = [a for a, _ in funcs]
        self._func_names = [n for _, n in funcs]
        self.uc.hook_add(UC_HOOK_BLOCK, self._on_block)

    def addr(self, name: str) -> int:
        if name not in self.symbols:
            raise KeyError(f"symbol {name} not in the ELF")
        return self.symbols[name][0]

    def _on_block(self, uc: Uc, address: int, size: int, _user: object) -> None:
        c = self.counter
        if c.active is None:
            name = c.entries.get(address)
            if name is None:
                return
            c.active = name
            c.ret = uc.reg_read(UC_ARM_REG_LR) & ~1
        elif address == c.ret:
            c.active = None
            return
        key = (address, size)
        n = c.cache.get(key)
        if n is None:
            n = c.cache[key] = thumb_instructions(bytes(uc.mem_read(address, size)))
        c.count += n
        if c.by_function is not None:
            c.by_function[self.function_at(address)] += n

    def function_at(self, address: int) -> str:
        """The symbol whose code holds address (the nearest function start at or below it)."""
        i = bisect.bisect_right(self._func_starts, address) - 1
        return self._func_names[i] if i >= 0 else "?"

    def call(self, name: str, *args: int) -> tuple[int, int]:
        """Call a function; returns (r0, instructions counted in measured functions)."""
        regs = (UC_ARM_REG_R0, UC_ARM_REG_R1)
        for reg, v in zip(regs, args, strict=False):
            self.uc.reg_write(reg, v)
        self.uc.reg_write(UC_ARM_REG_SP, RAM_BASE + RAM_SIZE)
        self.uc.reg_write(UC_ARM_REG_LR, RETURN_TRAP | 1)
        self.counter.count = 0
        self.counter.active = None
        self.uc.emu_start(self.addr(name) | 1, RETURN_TRAP)
        return self.uc.reg_read(UC_ARM_REG_R0), self.counter.count

    def write(self, name: str, data: bytes) -> None:
        addr, size = self.symbols[name]
        if len(data) > size:
            raise ValueError(f"{len(data)} bytes do not fit {name} ({size})")
        self.uc.mem_write(addr, data)

    def read(self, name: str) -> bytes:
        addr, size = self.symbols[name]
        return bytes(self.uc.mem_read(addr, size))

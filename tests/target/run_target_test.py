#!/usr/bin/env python3
"""Run one target test under qemu-system-arm (ctest label `target`, tests/target/CMakeLists.txt).

  unit      a tests/unit program cross-built for the Cortex-M4 runs on qemu's mps2-an386 with
            semihosting; its exit code must be 0 and its stdout byte-identical to the host build's
            run of the same program.
  run       a semihosting driver test (e.g. the tick timer on netduinoplus2's TIM2): exit 0.
  selftest  the real image (build/cm4/bin/odo_image.elf) boots on qemu's netduinoplus2 (an
            STM32F405); the self-test result it leaves in RAM (odo_board_selftest, read over QMP)
            must equal the host's run of the same self-test on the same parameter block. With
            --params erased|corrupt the image's parameter sector is first replaced by erased flash
            (0xFF) or gets one flipped bit, and the image must boot on defaults with
            ODO_FAULT_PARAMS_DEFAULTED and the matching odo_params_status_t.

Missing qemu is a failure, never a skip: tools/deps.sh installs it.
"""

from __future__ import annotations

import argparse
import difflib
import json
import shutil
import socket
import struct
import subprocess
import sys
import tempfile
import time
from pathlib import Path

QEMU = "qemu-system-arm"
SELFTEST_FMT = "<IIIIqqII"  # odo_board_selftest_t (hal/cortexm/odo_selftest.h), 40 bytes
SELFTEST_KEYS = (
    "params_status steps faults_or frames x_mm_q32 y_mm_q32 heading_bam done".split()
)
# odo_board_status_t (hal/cortexm/odo_board_port.h): odo_clock_t (source, sysclk, hclk, pclk1,
# pclk2, tim_apb1), can status, tick_ok, watchdog_ok, tick_overruns, tx_refused; 36 bytes, since
# arm-none-eabi-gcc makes enums as small as their values (-fshort-enums is the AAPCS default there).
BOARD_FMT = "<B3x5IBBBxII"


def fail(msg: str) -> int:
    print(f"FAILED: {msg}")
    return 1


def qemu() -> str:
    path = shutil.which(QEMU)
    if path is None:
        raise SystemExit(f"FAILED: {QEMU} not found (install qemu-system-arm: `make deps`)")
    return path


def run_unit(args: argparse.Namespace) -> int:
    host = subprocess.run([str(args.host)], capture_output=True, timeout=args.timeout)
    cmd = [
        qemu(), "-M", "mps2-an386", "-display", "none", "-monitor", "none",
        "-serial", "none", "-semihosting-config", "enable=on,target=native",
        "-kernel", str(args.elf),
    ]
    t0 = time.monotonic()
    tgt = subprocess.run(cmd, capture_output=True, timeout=args.timeout)
    dt = time.monotonic() - t0
    print(f"host exit {host.returncode}, target exit {tgt.returncode} ({dt:.1f} s under qemu)")
    sys.stdout.write(tgt.stdout.decode(errors="replace"))
    errors = []
    if host.returncode != 0:
        errors.append(f"host run exited {host.returncode}")
    if tgt.returncode != 0:
        errors.append(f"target run exited {tgt.returncode}: {tgt.stderr.decode(errors='replace')}")
    if host.stdout != tgt.stdout:
        diff = difflib.unified_diff(
            host.stdout.decode(errors="replace").splitlines(),
            tgt.stdout.decode(errors="replace").splitlines(),
            "host", "cortex-m4", lineterm="",
        )
        errors.append("output differs from the host's:\n" + "\n".join(diff))
    if errors:
        return fail("; ".join(errors))
    print(f"target output is byte-identical to the host's ({len(tgt.stdout)} bytes)")
    return 0


def run_plain(args: argparse.Namespace) -> int:
    cmd = [
        qemu(), "-M", args.machine, "-display", "none", "-monitor", "none",
        "-serial", "none", "-semihosting-config", "enable=on,target=native",
        "-kernel", str(args.elf),
    ]
    tgt = subprocess.run(cmd, capture_output=True, timeout=args.timeout)
    sys.stdout.write(tgt.stdout.decode(errors="replace"))
    if tgt.returncode != 0:
        return fail(f"{args.elf.name} on {args.machine} exited {tgt.returncode}")
    return 0


def nm_symbols(elf: Path) -> dict[str, tuple[int, int]]:
    out = subprocess.run(
        ["arm-none-eabi-nm", "-S", "--defined-only", str(elf)],
        capture_output=True, text=True, check=True,
    ).stdout
    syms = {}
    for line in out.splitlines():
        parts = line.split()
        if len(parts) == 4:
            syms[parts[3]] = (int(parts[0], 16), int(parts[1], 16))
    return syms


def patch_params(elf: Path, dest: Path, how: str, tmp: Path) -> bytes:
    """Copy the image with its .odo_params replaced; return the new block bytes."""
    block_file = tmp / "block.bin"
    subprocess.run(
        ["arm-none-eabi-objcopy", "-O", "binary", "--only-section=.odo_params",
         str(elf), str(block_file)], check=True,
    )
    block = bytearray(block_file.read_bytes())
    if how == "erased":
        block = bytearray(b"\xff" * len(block))
    elif how == "corrupt":
        block[40] ^= 0x10  # one bit of truck A's record; the CRC no longer matches
    if how != "none":
        block_file.write_bytes(block)
        subprocess.run(
            ["arm-none-eabi-objcopy", f"--update-section=.odo_params={block_file}",
             str(elf), str(dest)], check=True,
        )
    else:
        shutil.copyfile(elf, dest)
    return bytes(block)


class Qmp:
    def __init__(self, path: Path, timeout: float) -> None:
        deadline = time.monotonic() + timeout
        while True:
            try:
                self.sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
                self.sock.connect(str(path))
                break
            except OSError:
                if time.monotonic() > deadline:
                    raise
                time.sleep(0.05)
        self.sock.settimeout(timeout)
        self.buf = b""
        self._reply()  # greeting
        self.cmd("qmp_capabilities")

    def _reply(self) -> dict:
        while True:
            while b"\n" not in self.buf:
                chunk = self.sock.recv(65536)
                if not chunk:
                    raise ConnectionError("qemu closed the QMP socket")
                self.buf += chunk
            line, self.buf = self.buf.split(b"\n", 1)
            msg = json.loads(line)
            if "event" not in msg:
                return msg

    def cmd(self, name: str, **arguments) -> dict:
        self.sock.sendall(json.dumps({"execute": name, "arguments": arguments}).encode() + b"\n")
        reply = self._reply()
        if "error" in reply:
            raise RuntimeError(f"QMP {name}: {reply['error']}")
        return reply["return"]

    def read_mem(self, addr: int, size: int) -> bytes:
        words = (size + 3) // 4
        text = self.cmd("human-monitor-command", **{"command-line": f"xp /{words}wx {addr:#x}"})
        data = b"".join(struct.pack("<I", v) for v in parse_xp(text))
        return data[:size]


def parse_xp(text: str) -> list[int]:
    vals = []
    for line in text.splitlines():
        if ":" in line:
            vals += [int(v, 16) for v in line.split(":", 1)[1].split()]
    return vals


def run_selftest(args: argparse.Namespace) -> int:
    with tempfile.TemporaryDirectory() as tmpd:
        tmp = Path(tmpd)
        image = tmp / "image.elf"
        block = patch_params(args.elf, image, args.params, tmp)
        (tmp / "block.bin").write_bytes(block)
        host = subprocess.run(
            [str(args.host), str(tmp / "block.bin")], capture_output=True, text=True,
            timeout=args.timeout,
        )
        if host.returncode != 0:
            return fail(f"host self-test exited {host.returncode}: {host.stderr}")
        want = dict(kv.split("=") for kv in host.stdout.split())
        codes_out = subprocess.run([str(args.host), "--codes"], capture_output=True, text=True,
                                   check=True).stdout
        codes = {k: int(v) for k, v in (kv.split("=") for kv in codes_out.split())}

        addr, size = nm_symbols(image)["odo_board_selftest"]
        if size != struct.calcsize(SELFTEST_FMT):
            return fail(f"odo_board_selftest is {size} bytes, the reader expects "
                        f"{struct.calcsize(SELFTEST_FMT)}: update SELFTEST_FMT")
        sock = tmp / "qmp.sock"
        proc = subprocess.Popen(
            [qemu(), "-M", "netduinoplus2", "-display", "none", "-monitor", "none",
             "-serial", "none", "-kernel", str(image),
             "-qmp", f"unix:{sock},server=on,wait=off"],
            stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
        )
        try:
            qmp = Qmp(sock, 10.0)
            deadline = time.monotonic() + args.timeout
            while True:
                vals = struct.unpack(SELFTEST_FMT, qmp.read_mem(addr, size))
                got = dict(zip(SELFTEST_KEYS, vals, strict=True))
                if got["done"] == codes["selftest_done"]:
                    # the read is not atomic against the running CPU: one that races the
                    # image's copy of the struct saw `done` with the fields before it still zero
                    # (steps=0, frames=0 once in a CI run); the image never writes it again
                    time.sleep(0.1)
                    vals = struct.unpack(SELFTEST_FMT, qmp.read_mem(addr, size))
                    got = dict(zip(SELFTEST_KEYS, vals, strict=True))
                    break
                if time.monotonic() > deadline:
                    return fail(f"the image did not finish its self-test in {args.timeout} s "
                                f"(odo_board_selftest = {got})")
                time.sleep(0.1)
            board = None
            if args.params == "none":
                baddr, bsize = nm_symbols(image)["odo_board_status"]
                if bsize != struct.calcsize(BOARD_FMT):
                    return fail(f"odo_board_status is {bsize} bytes, the reader expects "
                                f"{struct.calcsize(BOARD_FMT)}: update BOARD_FMT")
                while True:
                    board = struct.unpack(BOARD_FMT, qmp.read_mem(baddr, bsize))
                    if board[7] == 1 or time.monotonic() > deadline:  # tick_ok: start-up done
                        time.sleep(0.1)  # as above: read again, not racing the first copy
                        board = struct.unpack(BOARD_FMT, qmp.read_mem(baddr, bsize))
                        break
                    time.sleep(0.1)
        finally:
            proc.kill()
            proc.communicate()
        fmt = {"faults_or": "0x{:08x}", "heading_bam": "0x{:08x}", "done": "0x{:08x}"}
        got_s = {k: fmt.get(k, "{}").format(v) for k, v in got.items()}
        print(f"netduinoplus2 ({args.params} parameter block): " +
              " ".join(f"{k}={v}" for k, v in got_s.items()))
        print(f"host:                        {host.stdout.strip()}")
        errors = [f"{k}: target {got_s[k]}, host {want.get(k)}" for k in SELFTEST_KEYS
                  if got_s[k] != want.get(k)]
        if args.params == "none":
            if (got["params_status"] != codes["params_ok"]
                    or got["faults_or"] & codes["fault_params_defaulted"]):
                errors.append("the image's own parameter block was not accepted")
            # qemu's STM32F405 has no RCC and no bxCAN: start-up must still finish, on the HSI,
            # with CAN reported down, and the tick timer running.
            print(f"board start-up under qemu: clock source {board[0]} at {board[1]} Hz, "
                  f"CAN status {board[6]}, tick timer {'on' if board[7] else 'off'}")
            if board[7] != 1:
                errors.append("board start-up did not finish (odo_board_status.tick_ok)")
            elif (board[0], board[1], board[6]) != (
                    codes["clock_hsi"], codes["clock_hsi_hz"], codes["bxcan_err_init_mode"]):
                errors.append("board start-up did not report qemu's missing RCC and bxCAN")
        else:
            want_status = codes["params_err_magic" if args.params == "erased" else "params_err_crc"]
            if got["params_status"] != want_status:
                errors.append(f"params_status {got['params_status']}, want {want_status}")
            if not got["faults_or"] & codes["fault_params_defaulted"]:
                errors.append("ODO_FAULT_PARAMS_DEFAULTED was not raised")
            if got["steps"] == 0:
                errors.append("the image did not run its self-test on defaults")
        if errors:
            return fail("; ".join(errors))
        print("the target's self-test equals the host's")
        return 0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="mode", required=True)
    u = sub.add_parser("unit", help="a tests/unit program on mps2-an386 vs the host build")
    u.add_argument("--elf", type=Path, required=True)
    u.add_argument("--host", type=Path, required=True)
    u.add_argument("--timeout", type=float, default=240.0)
    s = sub.add_parser("selftest", help="the image on netduinoplus2 vs the host self-test")
    s.add_argument("--elf", type=Path, required=True)
    s.add_argument("--host", type=Path, required=True, help="selftest_host program")
    s.add_argument("--params", choices=("none", "erased", "corrupt"), default="none")
    s.add_argument("--timeout", type=float, default=20.0)
    r = sub.add_parser("run", help="a semihosting program; exit code 0 required")
    r.add_argument("--elf", type=Path, required=True)
    r.add_argument("--machine", default="netduinoplus2")
    r.add_argument("--timeout", type=float, default=60.0)
    args = ap.parse_args()
    if args.mode == "run":
        return run_plain(args)
    for p in (args.elf, args.host):
        if not p.is_file():
            return fail(f"{p} does not exist (build the host and cm4 presets)")
    return run_unit(args) if args.mode == "unit" else run_selftest(args)


if __name__ == "__main__":
    sys.exit(main())

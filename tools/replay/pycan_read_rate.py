"""Frames per second python-can's CanutilsLogReader reads from a candump -l log (issue 6).

The reference a user would otherwise reach for: iterate the file's messages, nothing else.
Prints one number (frames/s, best of --reps) on stdout; used by odo-bench."""

from __future__ import annotations

import argparse
import time

import can


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("log", help="candump -l log")
    ap.add_argument("--reps", type=int, default=1, help="runs; the best is reported")
    a = ap.parse_args()
    best = 0.0
    for _ in range(a.reps):
        t0 = time.perf_counter()
        n = sum(1 for _ in can.CanutilsLogReader(a.log))
        best = max(best, n / (time.perf_counter() - t0))
    print(f"{best:.1f}")


if __name__ == "__main__":
    main()

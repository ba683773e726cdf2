"""python -m odo_tools.validation.indep.bench: how fast the world generates cases.

Prints JSON: per case the wall and CPU seconds of simulate_case, the robot time it simulated
(sum of its runs) and the ratio of the two (x real time, a figure that does not depend on how
long the drawn runs are); then medians and maxima. Timing is printed, never asserted (the
machine is shared and noisy; the CPU seconds are the steadier figure).
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from .. import case_seed
from . import draw_case, simulate_case


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m odo_tools.validation.indep.bench",
                                 description=__doc__.split("\n\n")[1])
    ap.add_argument("--cases", type=int, default=10, help="cases to generate (default 10)")
    ap.add_argument("--seed", type=int, default=1, help="seed of the case draw (default 1)")
    a = ap.parse_args(argv)
    rng = np.random.default_rng(a.seed)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(a.cases):
            case = draw_case(rng, k)
            w0, c0 = time.perf_counter(), time.process_time()
            extra = simulate_case(case, Path(tmp) / f"case-{k:03d}", case_seed(a.seed, k))
            wall, cpu = time.perf_counter() - w0, time.process_time() - c0
            robot_s = sum(r["duration_s"] for r in extra["runs"])
            rows.append({"case": k, "vehicle": case["vehicle"], "tick_ms": case["tick_ms"],
                         "runs": len(case["plan"]), "wall_s": round(wall, 3),
                         "cpu_s": round(cpu, 3), "robot_s": round(robot_s, 1),
                         "x_real_time_cpu": round(robot_s / cpu, 1)})
            print(f"case {k}: {case['vehicle']}, {len(case['plan'])} runs, {robot_s:.0f} s of "
                  f"robot time in {cpu:.2f} s CPU ({wall:.2f} s wall)", file=sys.stderr)
    med = {k: float(np.median([r[k] for r in rows])) for k in ("wall_s", "cpu_s",
                                                               "x_real_time_cpu")}
    top = {k: float(np.max([r[k] for r in rows])) for k in ("wall_s", "cpu_s")}
    print(json.dumps({"cases": rows, "median": med, "max": top}, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())

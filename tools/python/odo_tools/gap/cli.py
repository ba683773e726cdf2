"""odo-gap: diagnose the sim-to-real gap; check the diagnosis blind."""

from __future__ import annotations

import argparse
import math
import sys
import time

from .errors import GapInputError


def _progress(quiet: bool):
    return None if quiet else (lambda s: print(f"odo-gap: {s}", file=sys.stderr, flush=True))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="odo-gap", description=__doc__)
    sub = ap.add_subparsers(dest="cmd", required=True)
    d = sub.add_parser("diagnose", help="diagnose recorded runs (never reads a scenario)")
    d.add_argument(
        "--real", required=True, help="folder of run-<dir>-NN.log (+ .truth.csv, returns.csv)"
    )
    d.add_argument(
        "--robot", required=True, help="robot description JSON (what the firmware believes)"
    )
    d.add_argument(
        "--holdout", type=float, default=0.5, help="fraction of runs held out (default 0.5)"
    )
    d.add_argument("--seed", type=int, default=1)
    d.add_argument(
        "--mode",
        choices=["truth", "returns", "linkage"],
        help="evidence to use (default: the richest the data has)",
    )
    d.add_argument(
        "--return-accuracy",
        metavar="MM,DEG",
        help="accuracy (one sigma) of the measured return poses, e.g. 1,0.02 for a tape and a "
        "protractor: returns mode then judges their spread against it (roughness); without it "
        "the spread is the noise",
    )
    d.add_argument("--out", required=True)
    d.add_argument("--quiet", action="store_true")
    b = sub.add_parser("blind", help="the withheld-effect check: generate, diagnose, score")
    b.add_argument("--cases", type=int, default=60)
    b.add_argument("--seed", type=int, default=1)
    b.add_argument("--out", required=True)
    b.add_argument("--workers", type=int, default=2, help="processes (at most 2)")
    b.add_argument("--quiet", action="store_true")
    a = ap.parse_args(argv)
    try:
        if a.cmd == "diagnose":
            if not 0.0 <= a.holdout < 1.0:
                ap.error("--holdout must be in [0, 1)")
            acc = None
            if a.return_accuracy is not None:
                try:
                    acc = tuple(float(x) for x in a.return_accuracy.split(","))
                except ValueError:
                    acc = ()
                if len(acc) != 2 or not all(math.isfinite(x) and x > 0 for x in acc):
                    ap.error("--return-accuracy: expected MM,DEG, two positive numbers")
            from .diagnose import diagnose
            from .report import write_report

            t0 = time.perf_counter()
            rep = diagnose(a.real, a.robot, a.holdout, a.seed, a.mode, _progress(a.quiet), acc)
            write_report(rep, a.out)
            v = rep["verdict"]
            print(
                f"odo-gap: verdict {v['effect']} (best {v['best_candidate']}, dBIC "
                f"{v['evidence']['dbic_vs_nominal']:.1f}); held-out gap {rep['gap_before']:.2f} -> "
                f"{rep['gap_after_heldout']:.2f} (x{rep['shrink']:.1f}); "
                f"{time.perf_counter() - t0:.1f} s -> {a.out}",
                file=sys.stderr,
            )
            return 0
        from .blind import run_blind

        run_blind(a.cases, a.seed, a.out, min(2, max(1, a.workers)), _progress(a.quiet))
        return 0
    except GapInputError as e:
        print(f"odo-gap: {e}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())

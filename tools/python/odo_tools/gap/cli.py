"""odo-gap: diagnose the sim-to-real gap; check the diagnosis blind."""

from __future__ import annotations

import argparse
import math
import sys
import time

from .errors import GapInputError


def _progress(quiet: bool):
    return None if quiet else (lambda s: print(f"odo-gap: {s}", file=sys.stderr, flush=True))


EPILOG = """examples:
  odo-gap diagnose --real out/umbmark --robot host_sim/robots/labmate.json --out out/gap
  odo-gap diagnose --real out/opt-square out/opt-circular --robot R.json \\
      --fit 'opt-square/*' 'opt-circular/run-*-0[12]' --out out/opt-gap
  odo-gap blind --world both --cases 60 --seed 41 --out out/blind
"""


class _Usage(Exception):
    """A bad option value: one line on stderr, exit 1, nothing written."""


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        prog="odo-gap",
        description=__doc__,
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sub = ap.add_subparsers(dest="cmd", required=True)
    d = sub.add_parser(
        "diagnose",
        help="diagnose recorded runs (never reads a scenario)",
        description="Where the gap between the nominal model and recorded runs lies, which "
        "effect causes it, and how far it shrinks on held-out runs. Writes OUT/report.md, "
        "report.json and plots by the output rule: built in a fresh temp folder beside OUT and "
        "moved into place; an existing OUT is written into only when it holds odo-gap's "
        "manifest (then only the files it lists are replaced) or with --force.",
    )
    d.add_argument(
        "--real",
        required=True,
        nargs="+",
        metavar="DIR",
        help="folder(s) of run-<dir>-NN.log (+ .truth.csv, returns.csv); each folder is one "
        "recording session",
    )
    d.add_argument(
        "--robot", required=True, help="robot description JSON (what the firmware believes)"
    )
    d.add_argument(
        "--holdout", type=float, default=0.5, help="fraction of runs held out (default 0.5)"
    )
    d.add_argument("--seed", type=int, default=1, help="seed of the random hold-out split")
    d.add_argument(
        "--fit",
        nargs="+",
        metavar="GLOB",
        help="fit on these runs only: globs on run names ('square/run-cw-0[12]'; with several "
        "folders names carry the folder), log paths, or group:NAME (a folder or a --group)",
    )
    d.add_argument(
        "--judge",
        nargs="+",
        metavar="GLOB",
        help="judge on these runs (default with --fit: every run not fitted)",
    )
    d.add_argument(
        "--group",
        action="append",
        default=[],
        metavar="GLOB=LABEL",
        help="put the runs matching GLOB into group LABEL (repeatable; two runs or more per "
        "group): parameters are compared across groups, and --fit/--judge take group:LABEL",
    )
    d.add_argument(
        "--mode",
        choices=["truth", "returns", "linkage"],
        help="evidence to use (default: the richest the data has)",
    )
    d.add_argument(
        "--return-accuracy",
        metavar="MM,DEG",
        help="accuracy (one sigma) of the measured return poses, e.g. 1,0.02 for a tape and a "
        "protractor (default: a folder's instrument.json, else none): the returns' spread is "
        "judged against the larger of it and the runs' own spread",
    )
    d.add_argument(
        "--out",
        required=True,
        help="new folder (or one odo-gap wrote): report.json, report.md and the plots",
    )
    d.add_argument(
        "--force",
        action="store_true",
        help="write into a non-empty OUT odo-gap did not write (same-named files replaced, "
        "nothing removed)",
    )
    d.add_argument(
        "--jobs",
        type=int,
        default=None,
        help="processes for the independent fits (default: every available core; the report "
        "is the same with any number)",
    )
    d.add_argument("--quiet", action="store_true", help="no progress output")
    b = sub.add_parser(
        "blind",
        help="the withheld-effect check: generate, diagnose, score",
        description="Draw cases with hidden effects, simulate their recordings in one or both "
        "worlds, diagnose them in processes that cannot open the keys, and score.",
    )
    b.add_argument("--cases", type=int, default=60, help="cases drawn per world (default 60)")
    b.add_argument(
        "--seed",
        type=int,
        default=1,
        help="the draw's seed (default 1); report figures only from seeds never run before",
    )
    b.add_argument(
        "--world",
        choices=["sim", "independent", "both"],
        default="sim",
        help="sim: host_sim with hidden effects; independent: a generator that shares no code or "
        "effect law with it (validation.indep); both: each, scored separately",
    )
    b.add_argument(
        "--out",
        required=True,
        help="new folder: per world keys/, results.json, scores.json (every figure, and "
        "visible_only: the same over the cases whose effect leaves an imprint), scores.png, "
        "cases.md (each case's withheld truth beside every mode's verdict, misses marked)",
    )
    b.add_argument(
        "--force",
        action="store_true",
        help="write into a non-empty OUT odo-gap blind did not write (same-named files replaced, "
        "nothing removed)",
    )
    b.add_argument("--workers", type=int, default=2, help="processes (at most 2)")
    b.add_argument("--quiet", action="store_true", help="no progress output")
    a = ap.parse_args(argv)
    try:
        if a.cmd == "diagnose":
            if not 0.0 <= a.holdout < 1.0:
                raise _Usage(f"--holdout must be in [0, 1), got {a.holdout:g}")
            if a.seed < 0:
                raise _Usage(f"--seed must be 0 or more, got {a.seed}")
            if a.jobs is not None and a.jobs < 1:
                raise _Usage(f"--jobs must be at least 1, got {a.jobs}")
            acc = None
            if a.return_accuracy is not None:
                try:
                    acc = tuple(float(x) for x in a.return_accuracy.split(","))
                except ValueError:
                    acc = ()
                if len(acc) != 2 or not all(math.isfinite(x) and x > 0 for x in acc):
                    raise _Usage("--return-accuracy: expected MM,DEG, two positive numbers")
            from .diagnose import diagnose
            from .report import check_out, write_report

            check_out(a.out, a.force, [*a.real, a.robot])  # refused before the work, not after
            t0 = time.perf_counter()
            rep = diagnose(
                a.real,
                a.robot,
                a.holdout,
                a.seed,
                a.mode,
                _progress(a.quiet),
                acc,
                fit=a.fit,
                judge_runs=a.judge,
                groups=a.group,
                jobs=a.jobs,
            )
            write_report(rep, a.out, a.force, [*a.real, a.robot])
            v = rep.verdict
            h = rep.heldout
            print(
                f"odo-gap: verdict {v['effect']} (best {v['best_hypothesis']}, dBIC "
                f"{v['evidence']['dbic_vs_nominal']:.1f}); held-out {h['mm_before']:.1f} -> "
                f"{h['mm_after']:.1f} mm (background {rep.background['heldout_allowance_mm']:.1f}"
                f" mm; misfit {h['ratio_before']:.2f} -> {h['ratio_after']:.2f} x background); "
                f"{time.perf_counter() - t0:.1f} s -> {a.out}",
                file=sys.stderr,
            )
            return 0
        from ..validation.blind import run_blind

        worlds = ("sim", "independent") if a.world == "both" else (a.world,)
        if a.cases < 1:
            raise _Usage(f"--cases must be at least 1, got {a.cases}")
        if a.seed < 0:
            raise _Usage(f"--seed must be 0 or more, got {a.seed}")
        if a.workers < 1:
            raise _Usage(f"--workers must be at least 1, got {a.workers}")
        run_blind(
            a.cases, a.seed, a.out, min(2, max(1, a.workers)), _progress(a.quiet), worlds, a.force
        )
        return 0
    except (GapInputError, _Usage) as e:
        print(f"odo-gap: {e}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())

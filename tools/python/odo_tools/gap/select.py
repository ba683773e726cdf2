"""Which runs are fitted and which are judged (held out): a stratified random split, or the user's
explicit selection by run-name globs or by group (issue 13 item 5: fit on the UMBmark squares,
judge on the circles)."""

from __future__ import annotations

import fnmatch
from dataclasses import dataclass

import numpy as np

from .errors import GapInputError
from .io import RunData


@dataclass(frozen=True)
class Selection:
    fit: tuple[int, ...]
    held: tuple[int, ...]
    how: str  # in words, for the report

    @property
    def in_sample(self) -> bool:
        """No run held out: the shrink is in-sample (the report says so)."""
        return set(self.fit) == set(self.held)


def stratified(
    keys: list[str], frac: float, seed: int, kinds: list[str] | None = None
) -> Selection:
    """Held-out runs, stratified by `keys` (the path each run drove): each path keeps at least
    one fitting run; frac of each path driven more than once, at least one, is held out.

    `kinds` (paths.motion_kind: spot turns, arcs, straights): a kind of motion whose runs all
    drove paths of their own (a circle and a figure eight, driven once each) would otherwise
    never be judged, and an effect only that motion shows (scrub changes no spot turn) could
    never be seen on the held-out runs. Where the split leaves a kind without a held-out run,
    frac of its single-run paths (at least one) is held out whole, as long as the kind keeps a
    fitting run: judged on a path the fit never saw (no floor bumps are placed there)."""
    rng = np.random.default_rng(seed)
    fit, held = [], []
    singles = []
    for d in sorted(set(keys)):
        idx = [i for i, k in enumerate(keys) if k == d]
        if len(idx) == 1:
            singles.append(idx[0])
            continue
        nh = min(len(idx) - 1, max(1, int(frac * len(idx)))) if frac > 0 else 0
        perm = [int(x) for x in rng.permutation(idx)]
        held += perm[:nh]
        fit += perm[nh:]
    whole = 0
    if kinds is not None and frac > 0:
        rk = np.random.default_rng([seed, 1])  # the paths' split above stays as it was
        for kind in sorted({kinds[i] for i in singles}):
            if any(kinds[i] == kind for i in held):
                continue
            own = [i for i in singles if kinds[i] == kind]
            fitted = sum(1 for i in fit if kinds[i] == kind) + len(own)
            nh = min(fitted - 1, len(own), max(1, int(frac * len(own))))
            if nh <= 0:
                continue
            perm = [int(x) for x in rk.permutation(own)]
            held += perm[:nh]
            singles = [i for i in singles if i not in perm[:nh]]
            whole += nh
    fit += singles
    fit, held = sorted(fit), sorted(held)
    if not held:
        return Selection(tuple(fit), tuple(fit), "no run could be held out: judged in-sample")
    how = f"random split, {frac:.0%} of each path held out (seed {seed})"
    if whole:
        how += f"; {whole} path(s) driven once held out whole, so every kind of motion is judged"
    return Selection(tuple(fit), tuple(held), how)


def _matches(run: RunData, groups: dict[str, str], pattern: str) -> bool:
    """A run matches a glob on its name ('square/run-cw-0[12]'), on its log's path, or
    'group:NAME' on its session or --group label."""
    if pattern.startswith("group:"):
        g = pattern[len("group:") :]
        return run.session == g or groups.get(run.name) == g
    return (
        fnmatch.fnmatchcase(run.name, pattern)
        or fnmatch.fnmatchcase(run.path, pattern)
        or fnmatch.fnmatchcase(run.name.split("/")[-1], pattern)
    )


def explicit(
    runs: list[RunData], fit_pats: list[str], judge_pats: list[str] | None, groups: dict[str, str]
) -> Selection:
    """--fit GLOB... [--judge GLOB...]: without --judge every run not fitted is judged. A run
    matched by both, or a side left empty, is an error (nothing is written)."""
    fit = [i for i, r in enumerate(runs) if any(_matches(r, groups, p) for p in fit_pats)]
    if judge_pats:
        held = [i for i, r in enumerate(runs) if any(_matches(r, groups, p) for p in judge_pats)]
    else:
        held = [i for i in range(len(runs)) if i not in fit]
    names = ", ".join(r.name for r in runs)
    if not fit:
        raise GapInputError("--fit", f"{' '.join(fit_pats)} matches none of the runs ({names})")
    if not held:
        what = " ".join(judge_pats) if judge_pats else "the runs --fit leaves"
        raise GapInputError(
            "--judge", f"nothing left to judge: {what} matches none of the runs ({names})"
        )
    both = sorted(set(fit) & set(held))
    if both:
        raise GapInputError(
            "--judge",
            f"{runs[both[0]].name} is both fitted and judged: a run held out must not be fitted",
        )
    how = f"fitted on {' '.join(fit_pats)}; judged on " + (
        " ".join(judge_pats) if judge_pats else "the rest"
    )
    return Selection(tuple(fit), tuple(held), how)


def parse_groups(specs: list[str], runs: list[RunData]) -> dict[str, str]:
    """--group GLOB=LABEL (repeatable) -> run name -> label. Every group needs two runs or more
    (one run has no spread and cannot be split), and a run belongs to one group."""
    out: dict[str, str] = {}
    for spec in specs:
        if "=" not in spec:
            raise GapInputError("--group", f"{spec!r}: expected GLOB=LABEL")
        pat, label = spec.rsplit("=", 1)
        if not pat or not label:
            raise GapInputError("--group", f"{spec!r}: expected GLOB=LABEL")
        hit = [r for r in runs if _matches(r, {}, pat)]
        if not hit:
            raise GapInputError("--group", f"{pat!r} matches none of the runs")
        for r in hit:
            if r.name in out and out[r.name] != label:
                raise GapInputError(
                    "--group", f"{r.name} is in two groups: {out[r.name]!r} and {label!r}"
                )
            out[r.name] = label
    sizes: dict[str, int] = {}
    for label in out.values():
        sizes[label] = sizes.get(label, 0) + 1
    for label, n in sizes.items():
        if n < 2:
            run = next(k for k, v in out.items() if v == label)
            raise GapInputError(
                "--group",
                f"group {label!r} has a single run ({run}): a group needs two runs or more",
            )
    return out

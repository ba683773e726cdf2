"""Parameter stability across groups of runs (issue 13 item 4): the verdict's parameters (and the
kinematic calibration Ed, Eb) fitted again on each group of the fitting runs - per path shape, per
recording session (folder), per direction, per user group (--group) - and compared. A parameter
that differs between two groups by more than STABLE_Z combined standard errors (inflated by each
fit's overdispersion, since the background makes the Gaussian errors optimistic) is a finding.
An effective wheelbase that differs between turns on the spot and arcs is the signature of a
turn-radius-dependent wheelbase (catalog `scrub`), and the finding says so with the k it implies.
Where two kinds of group split the runs identically (one shape per session), the finding cannot
tell them apart, and says that too."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .fit import Fit, Problem, fit_params
from .model import Prepared
from .paths import turn_style
from .verdict import DRIFT_TREND_P, DRIFT_Z

STABLE_Z = 3.0
ALWAYS = ("ed.value", "eb.value")  # the calibration a user would carry between sessions
# the verdict's parameters compared across groups: those of a robot's geometry and sensors.
# Floor and drive laws (slip, skid, count loss, bumps, roughness) are not: each group's refit
# costs a full fit of a law that depends on the paths each group drove.
COMPARED = ("ed", "eb", "es", "scrub", "rotary_bias", "link_bias")


@dataclass
class GroupFit:
    kind: str  # shape, session, direction, group
    group: str
    runs: list[str]
    params: dict
    stderr: dict
    model: str = "verdict"  # "calibration": Ed and Eb alone; "verdict": the verdict's parameters


@dataclass
class Finding:
    param: str
    kind: str
    groups: tuple[str, str]
    values: tuple[float, float]
    stderr: tuple[float, float]
    z: float
    text: str
    confounded_with: list[str] = field(default_factory=list)
    implies: dict = field(default_factory=dict)  # e.g. {"scrub.k": 0.0095}
    model: str = "verdict"


def _kinds(prs: list[Prepared], groups: dict[str, str], mode: str) -> dict[str, list[str]]:
    out = {
        "shape": [pr.shape or "?" for pr in prs],
        "session": [pr.run.session or "?" for pr in prs],
    }
    if mode != "returns":
        # return errors of one direction hide compensating Ed and Eb (000 Fig. 3.2): a split
        # by direction would report their trade-off as a finding
        out["direction"] = [pr.run.direction for pr in prs]
    if groups:
        out["group"] = [groups.get(pr.run.name, "(none)") for pr in prs]
    return out


def _partition(labels: list[str]) -> frozenset:
    by: dict[str, set[int]] = {}
    for i, g in enumerate(labels):
        by.setdefault(g, set()).add(i)
    return frozenset(frozenset(v) for v in by.values())


def analyse(
    items: list,
    prs: list[Prepared],
    mode: str,
    sigma: np.ndarray,
    verdict: Fit | None,
    groups: dict[str, str],
    extra_keys: tuple[str, ...] = (),
) -> tuple[list[GroupFit], list[Finding]]:
    """Refit per group of the fitting runs `items`/`prs`; return the per-group fits and the
    findings. Bump events are not refitted (their heights are per bump, not per group)."""
    base = verdict.model_params() if verdict is not None else {}
    kin = [k for k in ALWAYS if not (mode == "returns" and k.startswith("es."))]
    # (a) the calibration a user would carry (Ed, Eb), every other effect at nominal: a wheelbase
    #     that moves with the way the robot turns shows here; (b) the verdict's own parameters
    sets = [("calibration", kin)]
    vkeys = [k for k in base if k.split(".")[0] in COMPARED]
    if vkeys and set(vkeys) != set(kin):
        sets.append(("verdict", vkeys))
    kinds = _kinds(prs, groups, mode)
    parts = {k: _partition(v) for k, v in kinds.items()}
    fits: list[GroupFit] = []
    for model, keys in sets:
        for kind, labels in kinds.items():
            names = sorted(set(labels))
            if len(names) < 2:
                continue
            for g in names:
                idx = [i for i, x in enumerate(labels) if x == g]
                if len(idx) < (1 if mode == "truth" else 2):
                    continue
                prob = Problem(mode, [items[i] for i in idx], sigma)
                P, se = fit_params(prob, keys)
                _, chi, n = prob.deviance(P)
                c = max(1.0, chi / max(n - len(keys), 1))
                se = {k: v * math.sqrt(c) for k, v in se.items()}
                fits.append(GroupFit(kind, g, [prs[i].run.name for i in idx], P, se, model))
    findings: list[Finding] = []
    for (model, keys), kind in ((m, k) for m in sets for k in kinds):
        gf = [f for f in fits if f.kind == kind and f.model == model]
        for k in keys:
            for a in range(len(gf)):
                for b in range(a + 1, len(gf)):
                    fa, fb = gf[a], gf[b]
                    va, vb = fa.params.get(k), fb.params.get(k)
                    sa, sb = fa.stderr.get(k, float("nan")), fb.stderr.get(k, float("nan"))
                    if va is None or vb is None or not (math.isfinite(sa) and math.isfinite(sb)):
                        continue
                    z = abs(va - vb) / max(math.hypot(sa, sb), 1e-12)
                    if z < STABLE_Z:
                        continue
                    if any(
                        f.param == k and parts[f.kind] == parts[kind] for f in findings
                    ):  # one finding per way of splitting the runs, whatever names it
                        continue
                    same = [o for o in kinds if o != kind and parts[o] == parts[kind]]
                    fd = Finding(
                        k, kind, (fa.group, fb.group), (va, vb), (sa, sb), z, "", same, {}, model
                    )
                    fd.text = _words(fd, prs, kinds)
                    findings.append(fd)
    findings.sort(key=lambda f: -f.z)
    return fits, findings


DRIFTING = ("ed", "eb", "es")  # a robot's geometry, constant in every catalog effect


def drift(items: list, prs: list[Prepared], sigma: np.ndarray, verdict: Fit) -> Finding | None:
    """Truth mode: does the verdict's geometry (Ed, Eb, Es) hold still in time? Each run, fitting
    and held out, fits it alone (the verdict's other parameters held), the runs in the order
    they were recorded; the largest difference between the runs before and after any one moment,
    over the paths (for Es, the shapes) driven on both sides, in combined standard errors
    (inflated by each run's overdispersion), is the finding when it reaches verdict.DRIFT_Z. A
    wheel whose diameter grows as it warms (out of the catalog) was named "ed + es" with Es
    0.9995 on the first cw square and 0.9968 on the later squares, 4.6 standard errors apart
    (independent world, seed 2761 case 43). Only the same paths are compared: a trailer's tyre
    deflection, an Es that depends on the path, read 1.0058 on four circles and 1.0076 on the
    square driven after them (2721 case 57). Several moments are tried, hence a threshold above
    STABLE_Z. Where no moment reaches it, a value that rises or falls run after run over every
    path (`_trend`) is the finding: a warming wheel's Es read 1.0004, 1.0016, 1.0023 ... 1.0036
    on eleven runs of five paths in turn, but the first square sat 3.5 standard errors from the
    five after it, and "ed" was named (independent world, fresh seed 3291 case 34)."""
    base = verdict.model_params()
    keys = [k for k in base if k.split(".")[0] in DRIFTING]
    if not keys or verdict.bumps or len(prs) < 3:
        return None
    if not any(k.split(".")[0] == "es" for k in keys):
        # the mean diameter beside a verdict without it: a wheel that warms shows there first,
        # and a constant Es the fitting tracks did not need left the verdict ("ed" alone on
        # 2761 case 43, diagnose._prune_members) without the wheel holding still
        keys.append("es.value")
    order = sorted(range(len(prs)), key=lambda i: float(prs[i].t[0]))
    per = []
    for i in order:
        prob = Problem("truth", [items[i]], sigma)
        P, se = fit_params(prob, keys, base=base, warm=base)
        _, chi, n = prob.deviance(P)
        c = max(1.0, chi / max(n - len(keys), 1))
        per.append((prs[i], P, {k: v * math.sqrt(c) for k, v in se.items()}))
    best = None
    for k in keys:
        runs = [(pr, P[k], se[k]) for pr, P, se in per if 0.0 < se.get(k, math.nan) < math.inf]
        # the same paths on both sides: a law that depends on the path (a trailer's tyre
        # deflection, 2721 case 57: four circles, then a square) is no drift in time. The scale
        # is compared between shapes, a path either way round: a square driven cw travels as
        # far as one driven ccw, where a heading parameter (Ed, Eb) may read them differently
        # (a load that moves to the outer wheel). A warming wheel's Es rose 1.0006 -> 1.0035 on
        # three cw squares, then 1.0056 -> 1.0065 on three ccw squares (dev seed 4005 case 23):
        # no path on both sides, and "ed" was named.
        same = [r[0].shape if k.split(".")[0] == "es" else r[0].path for r in runs]
        for j in range(1, len(runs)):
            common = set(same[:j]) & set(same[j:])
            if not common:
                continue
            early = [r for r, g in zip(runs[:j], same[:j], strict=True) if g in common]
            late = [r for r, g in zip(runs[j:], same[j:], strict=True) if g in common]
            (a, sa), (b, sb) = _wmean(early), _wmean(late)
            z = abs(a - b) / max(math.hypot(sa, sb), 1e-12)
            if best is None or z > best.z:
                best = Finding(
                    k,
                    "time",
                    (runs[j - 1][0].run.name, runs[j][0].run.name),
                    (a, b),
                    (sa, sb),
                    z,
                    "",
                )
                best.implies = {"runs_before": len(early), "runs_after": len(late)}
    if best is None or best.z < DRIFT_Z:
        return _trend(keys, per)
    what = _what(best.param)
    best.text = (
        f"{what} drifts with time: {best.values[0]:.4f} +- {best.stderr[0]:.4f} on "
        f"{best.implies['runs_before']} run(s) up to '{best.groups[0]}', {best.values[1]:.4f} +- "
        f"{best.stderr[1]:.4f} on {best.implies['runs_after']} of the same paths from "
        f"'{best.groups[1]}' on ({best.z:.1f} standard errors apart); every catalog effect holds "
        "it constant"
    )
    return best


TREND_MIN_RUNS = 8  # fewer runs in perfect order than this stay above DRIFT_TREND_P anyway


def _trend(keys: list[str], per: list) -> Finding | None:
    """The key whose per-run values (`per`: (run, values, standard errors) in the order of
    recording) follow that order most surely by Kendall's rank correlation, as a drift finding
    when its p-value is at most verdict.DRIFT_TREND_P; ranks ask nothing of the paths, and a
    value that depends on the path rises only as far as the paths were driven in some order
    (four circles, then a square: tau 0.4). On the dev seeds 4001-4007, 4121-4191 (44 thermal
    diameter drifts, 120 other robots) the drifts reached 5.5e-7 to 5.0e-5 where the moments'
    comparison missed them; of the robots with a catalog effect, none came below 2.4e-4 (an Ed
    growing with speed, on runs driven slower and faster in turn)."""
    from scipy.stats import kendalltau

    best = None
    for k in keys:
        runs = [(pr, P[k], se[k]) for pr, P, se in per if 0.0 < se.get(k, math.nan) < math.inf]
        if len(runs) < TREND_MIN_RUNS:
            continue
        tau, p = kendalltau(np.arange(len(runs)), [v for _, v, _ in runs])
        if not math.isfinite(p) or (best is not None and p >= best[0]):
            continue
        best = (float(p), float(tau), k, runs)
    if best is None or best[0] > DRIFT_TREND_P:
        return None
    p, tau, k, runs = best
    (r0, a, sa), (r1, b, sb) = runs[0], runs[-1]
    f = Finding(
        k, "time", (r0.run.name, r1.run.name), (a, b), (sa, sb), abs(b - a) / math.hypot(sa, sb), ""
    )
    f.implies = {"runs": len(runs), "kendall_tau": tau, "p": p}
    f.text = (
        f"{_what(k)} drifts with time: it {'rises' if tau > 0 else 'falls'} run after run, "
        f"{a:.4f} +- {sa:.4f} on '{r0.run.name}' to {b:.4f} +- {sb:.4f} on '{r1.run.name}' over "
        f"{len(runs)} runs in the order they were recorded (Kendall's tau {tau:+.2f}, p {p:.1g});"
        " every catalog effect holds it constant"
    )
    return f


NAMES = {
    "eb.value": "effective wheelbase (Eb)",
    "ed.value": "wheel-diameter ratio (Ed)",
    "es.value": "scale (Es)",
    "scrub.k": "scrub coefficient k",
}


def _what(param: str) -> str:
    """A parameter in words; a truck's own copy ('ed.value.A') with its truck."""
    base, _, truck = param.rpartition(".") if param.count(".") > 1 else (param, "", "")
    return f"{NAMES[base]} of truck {truck}" if base in NAMES and truck else NAMES.get(base, param)


def _wmean(runs: list) -> tuple[float, float]:
    """Inverse-variance mean of (run, value, standard error) and its standard error."""
    w = np.array([1.0 / (s * s) for _, _, s in runs])
    v = np.array([x for _, x, _ in runs])
    return float(np.sum(w * v) / np.sum(w)), float(1.0 / math.sqrt(np.sum(w)))


def _words(fd: Finding, prs: list[Prepared], kinds: dict[str, list[str]]) -> str:
    """The finding in plain words; a wheelbase that moves with the way the robot turns is named
    as tyre scrub, with the k it implies (catalog scrub: Eb_arc = Eb_spot / (1 - k (1 - s)),
    s = b / (2R))."""
    (ga, gb), (va, vb) = fd.groups, fd.values
    what = _what(fd.param)
    text = (
        f"{what} {va:.4f} +- {fd.stderr[0]:.4f} on {fd.kind} '{ga}' but {vb:.4f} +- "
        f"{fd.stderr[1]:.4f} on '{gb}' ({fd.z:.1f} standard errors apart)"
    )
    if fd.param == "eb.value":
        styles = {}
        for g in (ga, gb):
            members = [pr for pr, x in zip(prs, kinds[fd.kind], strict=False) if x == g]
            spot = sum(turn_style(pr)[0] for pr in members)
            arc = sum(turn_style(pr)[1] for pr in members)
            styles[g] = (spot, arc, members)
        (sa_, aa_, ma), (sb_, ab_, mb) = styles[ga], styles[gb]
        fa_ = aa_ / max(sa_ + aa_, 1e-9)
        fb_ = ab_ / max(sb_ + ab_, 1e-9)
        if abs(fa_ - fb_) > 0.5:
            spot_g, arc_g = (ga, gb) if fa_ < fb_ else (gb, ga)
            eb_spot, eb_arc = (va, vb) if spot_g == ga else (vb, va)
            arc_members = mb if arc_g == gb else ma
            R = _mean_radius(arc_members)
            b = arc_members[0].b[0]
            s = b / (2.0 * R)
            k = (1.0 - eb_spot / eb_arc) / (1.0 - s)
            fd.implies = {"scrub.k": k, "arc_radius_mm": R}
            text = (
                f"effective wheelbase {eb_spot:.4f} on turns on the spot ('{spot_g}'), "
                f"{eb_arc:.4f} on {R / 1000:.2f} m arcs ('{arc_g}'): turn-radius-dependent "
                f"wheelbase (tyre scrub), k = {k:.4f} ({fd.z:.1f} standard errors apart)"
            )
    if fd.confounded_with:
        text += (
            "; the runs split the same way by "
            + " and ".join(fd.confounded_with)
            + ", so these data cannot tell which of them it follows"
        )
    return text


def _mean_radius(prs: list[Prepared]) -> float:
    d = th = 0.0
    for pr in prs:
        ds = pr.ds[:, 0, :]
        same = (ds[:, 0] * ds[:, 1]) > 0.0
        d += float(np.abs(ds[same]).mean(axis=1).sum())
        th += float((np.abs(ds[same, 1] - ds[same, 0]) / pr.b[0]).sum())
    return d / max(th, 1e-9)

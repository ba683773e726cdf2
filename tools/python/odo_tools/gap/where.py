"""Where the gap lies: per run, per channel and per phase of the motion (DESIGN.md s. 6), and
where the nominal model's excess misfit lives, which proposes the families to test with their
other laws (hypotheses.propose)."""

from __future__ import annotations

import math

import numpy as np

from .fit import Fit
from .model import Prepared
from .modes import TruthMode
from .paths import group_key

PHASES = ("stationary", "turn", "arc", "straight", "acceleration")
FAST_QUANTILE = (
    0.8  # "fast": windows whose wheel speed is in the top fifth of the run's moving ones
)


ACCEL_MM_S2 = 50.0  # a tick whose smoothed speed changes faster than this is accelerating
ACCEL_JITTER_MM_S2 = 0.25 * ACCEL_MM_S2  # whole edges may scatter it by this (one sigma)


def _smoothing_ticks(pr: Prepared) -> int:
    """Ticks the speed is averaged over before its acceleration is read: ~0.25 s, or as many
    as keep the scatter that whole edges make within ACCEL_JITTER_MM_S2 (one sigma). Each
    wheel's count is its travel rounded to q mm edges (an error uniform over one edge), so a
    mean of both wheels over m ticks of length T is off by q / (sqrt(6) m T) and the centred
    difference of two such means, two ticks apart, by sqrt(2/3) q / (4 m T^2): 1.5 mm/s^2 for
    the OptiOdom robot's 0.094 mm edges on 50 ms ticks over 0.25 s, but 46 mm/s^2 for a
    LabMate's 2.8 mm edges, and half of every square it drove read as "acceleration"
    (independent world, dev seed 4121 case 34, floor bumps: 69 % of the excess there, which
    proposed slip)."""
    if not pr.dt.size:
        return 1
    T = float(np.median(pr.dt))
    m = max(1, round(0.25 / T))
    q = pr.edge_mm(0)
    if q > 0:
        m = max(m, math.ceil(math.sqrt(2 / 3) * q / (4 * T * T * ACCEL_JITTER_MM_S2) - 1e-9))
    return m


def classify(pr: Prepared) -> np.ndarray:
    """Per tick of truck A: stationary, turn (on the spot), straight, arc, acceleration."""
    ds = pr.ds[:, 0, :]
    v = 0.5 * (ds[:, 0] + ds[:, 1]) / pr.dt
    om = (ds[:, 1] - ds[:, 0]) / pr.b[0] / pr.dt
    t = pr.t[1:]
    # the acceleration of a speed smoothed over ~0.25 s: a tick's count is quantised (one count
    # in 50 ms is ~2 mm/s on the OptiOdom robot, 40 mm/s^2 tick to tick), and the raw gradient
    # called half of a steady circle "accelerating". Longer where whole edges need it
    # (_smoothing_ticks)
    m = _smoothing_ticks(pr)
    vs = np.convolve(v, np.ones(m) / m, mode="same") if v.size >= m else v
    acc = np.abs(np.gradient(vs, t)) if t.size > 1 else np.zeros_like(v)
    lab = np.full(v.size, "straight", dtype=object)
    lab[np.abs(om) * 0.5 * pr.b[0] > 0.2 * np.maximum(np.abs(v), 1e-9)] = "arc"
    lab[(ds[:, 0] * ds[:, 1] < 0) & (np.abs(om) > 0.02)] = "turn"
    lab[(acc > ACCEL_MM_S2) & (lab == "straight")] = "acceleration"
    lab[(np.abs(v) < 1.0) & (np.abs(om) < 0.005)] = "stationary"
    return lab


def window_phases(it: TruthMode) -> tuple[np.ndarray, np.ndarray]:
    """(phase label, 'fast' flag) of each truth window: the label most of its ticks carry."""
    pr = it.pr
    lab = classify(pr)
    ta, tb = it.tt[it.i], it.tt[it.j]
    ka = np.clip(np.searchsorted(pr.t, ta, side="right") - 1, 0, lab.size - 1)
    kb = np.clip(np.searchsorted(pr.t, tb, side="left"), 1, lab.size)
    out = np.empty(ta.size, dtype=object)
    for w in range(ta.size):
        seg = lab[ka[w] : max(kb[w], ka[w] + 1)]
        vals, cnt = np.unique(seg, return_counts=True)
        # a window that accelerates at all is an accelerating window: that is where slip lives
        out[w] = "acceleration" if "acceleration" in vals else vals[int(np.argmax(cnt))]
    spd = (it.wtravel[0, 0] + it.wtravel[0, 1]) / np.maximum(tb - ta, 1e-9)
    moving = out != "stationary"
    fast = np.zeros(ta.size, dtype=bool)
    if moving.any():
        fast = moving & (spd >= np.quantile(spd[moving], FAST_QUANTILE)) & (spd > 0)
    return out, fast


def phase_excess(items: list, P: dict, sigma: np.ndarray) -> dict[str, tuple[float, float]]:
    """Truth mode: phase -> (share of the excess misfit z^2 - 1 of the truck channels, share of
    the windows). 'fast' is the top fifth of wheel speeds, across phases."""
    tot = 0.0
    acc: dict[str, list[float]] = {}
    n_all = 0
    for it in items:
        if not isinstance(it, TruthMode):
            return {}
        z = it.residuals(P)[:, : 3 * it.trucks] / sigma[: 3 * it.trucks]
        ex = np.maximum((z * z).sum(axis=1) - z.shape[1], 0.0)
        lab, fast = window_phases(it)
        tot += float(ex.sum())
        n_all += ex.size
        for ph in PHASES:
            m = lab == ph
            a = acc.setdefault(ph, [0.0, 0.0])
            a[0] += float(ex[m].sum())
            a[1] += float(m.sum())
        a = acc.setdefault("fast", [0.0, 0.0])
        a[0] += float(ex[fast].sum())
        a[1] += float(fast.sum())
    if tot <= 0 or n_all == 0:
        return {}
    return {ph: (v[0] / tot, v[1] / n_all) for ph, v in acc.items()}


def truck_excess(items: list, P: dict, sigma: np.ndarray) -> list[float]:
    """Truth mode, two trucks: each truck's share of the excess misfit (z^2 - 1 summed over its
    three channels and every window)."""
    ex = np.zeros(getattr(items[0], "trucks", 1))
    for it in items:
        if not isinstance(it, TruthMode):
            return []
        r = it.residuals(P)
        for t in range(it.trucks):
            z = r[:, 3 * t : 3 * t + 3] / sigma[3 * t : 3 * t + 3]
            ex[t] += float(np.maximum((z * z).sum(axis=1) - 3.0, 0.0).sum())
    tot = ex.sum()
    return (ex / tot).tolist() if tot > 0 else []


def where_analysis(items: list, prs: list[Prepared], f: Fit | None, chans, sigma) -> list[dict]:
    out = []
    for it, pr in zip(items, prs, strict=False):
        r = it.residuals({})
        entry = {"run": pr.run.name, "gap": it.gap({})}
        w = r / sigma
        share = (w**2).sum(axis=0)
        tot = share.sum() or 1.0
        entry["channels"] = {c: float(s / tot) for c, s in zip(chans, share, strict=False)}
        if isinstance(it, TruthMode):
            wl, _ = window_phases(it)
            segs = {}
            for s in np.unique(wl):
                segs[str(s)] = float((w[wl == s] ** 2).sum() / tot)
            entry["segments"] = segs
            lab = classify(pr)
            moving = lab != "stationary"
            edges = np.flatnonzero(np.diff(moving.astype(int)))
            entry["n_legs"] = int((edges.size + 1) // 2)
            tt, err = it.error_track({})
            dist = np.interp(tt, pr.t, pr.S[:, 0].mean(axis=1))
            e = np.hypot(err[:, 0], err[:, 1])
            entry["gap_end_mm"] = float(e[-1])
            entry["gap_max_mm"] = float(e.max())
            entry["gap_max_at_mm"] = float(dist[int(np.argmax(e))])
        if f is not None and f.bumps:
            g = group_key(pr)
            entry["events"] = [
                {
                    "kind": "bump",
                    "truck": "AB"[b["truck"]],
                    "wheel": ("left", "right")[b["wheel"]],
                    "at_wheel_travel_mm": b["s0"],
                    "height_mm": b["h"],
                    "x_mm": b["x_mm"],
                    "y_mm": b["y_mm"],
                }
                for b in f.bumps
                if b["group"] == g
            ]
        out.append(entry)
    return out

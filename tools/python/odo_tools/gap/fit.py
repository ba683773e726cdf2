"""Hypotheses, fits and evidence.

Evidence is BIC: deviance -2 ln L of Gaussian residuals (per-channel noise sigma estimated once
from the data: the truth's sample noise, the returns' spread or stated accuracy, the linkage
encoders' quantisation; roughness adds its own variance) plus k ln n for k fitted parameters over
n residual scalars. Lower is better; Delta BIC > 10 is
"very strong" (Kass & Raftery 1995) and is the threshold used throughout.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
from scipy.optimize import least_squares

from .model import Prepared, bump_dd, bump_excess
from .simlib import catalog

DBIC_SIGNIFICANT = 10.0  # best hypothesis vs nominal: below -> "no significant gap"
EXPLAINED_MIN = 0.75  # share of the excess misfit a verdict must remove, else "unexplained"
DBIC_PAIR = 10.0  # a pair must beat the best single by this much
Z_GAP = 5.0  # nominal misfit above the noise-only chi^2, in its standard deviations: a gap

# Free parameters per hypothesis (others stay at the catalog default). See README for why.
FREE = {
    "ed": ["value"],
    "eb": ["value"],
    "es": ["value"],
    "roughness": ["max_height_mm"],
    "slip": ["k_per_m_s2", "tau_s"],
    "skid": ["k_s"],
    "rotary_bias": ["alpha_deg", "beta_deg"],
    "link_bias": ["const_mm", "ecc_mm"],
}
START = {"slip.k_per_m_s2": 0.05, "skid.k_s": 0.05, "roughness.max_height_mm": 0.5}
UNIDENTIFIABLE = {
    "returns": {
        "es": "closed paths do not fix the overall scale (Es)",
        "bumps": "return errors carry no positions of discrete events",
        "skid": "a corner's outward skid turns no heading, and around a closed path the "
        "corners' displacements cancel: k = 0.3 s moves these return poses by ~1 mm "
        "(tests/python/test_gap_evidence.py)",
        "rotary_bias": "needs linkage readings",
        "link_bias": "needs linkage readings",
    },
    "truth": {},
    "linkage": {"bumps": "not located from linkage readings alone (tested in truth mode)"},
}
ALWAYS_UNIDENTIFIABLE = {
    "tire_compression": "kinematically an Ed plus an Es (off-centre load and mean load): aliased "
    "with the pair ed+es, reported through them",
    "count_loss": "lost counts leave no trace in the counts themselves at these speeds",
}


def applicable(mode: str, vehicle: str) -> list[str]:
    h = ["ed", "eb", "es", "roughness", "slip", "skid"]
    if mode == "truth":
        h.append("bumps")
    if vehicle != "labmate" and mode in ("truth", "linkage"):
        h.append("rotary_bias")
        if vehicle == "clapper":
            h.append("link_bias")
    return [x for x in h if x not in UNIDENTIFIABLE[mode]]


def free_params(effect: str, vehicle: str) -> list[str]:
    f = FREE.get(effect, [])
    if effect == "rotary_bias" and vehicle == "set":
        f = ["alpha_deg"]
    return [f"{effect}.{p}" for p in f]


# model-side nuisances that are not catalog parameters: (min, max, start)
NUISANCE = {"slip.tau_s": (0.0005, 0.02, 0.004)}


def bounds(key: str) -> tuple[float, float, float]:
    if key in NUISANCE:
        return NUISANCE[key]
    e, p = key.split(".")
    d = next(x for x in catalog()[e]["params"] if x["name"] == p)
    return float(d["min"]), float(d["max"]), float(d["default"])


@dataclass
class Problem:
    """The fitting runs of one mode: residual builders, noise, data count."""

    mode: str
    items: list  # mode objects (one per run)
    sigma: np.ndarray = field(default=None)

    def __post_init__(self) -> None:
        if self.sigma is None:
            self.sigma = estimate_sigma(self.items, self.mode)

    def resid(self, P: dict) -> np.ndarray:
        return np.vstack([it.residuals(P) for it in self.items])

    def deviance(self, P: dict) -> tuple[float, float, int]:
        """(-2 ln L relative to sigma, weighted chi^2, n scalars)."""
        r = self.resid(P)
        v = np.broadcast_to(self.sigma**2, r.shape)
        ev = [it.extra_var(P) for it in self.items]
        if any(e is not None for e in ev):
            v = v + np.vstack(
                [
                    e if e is not None else np.zeros((it.residuals(P).shape[0], r.shape[1]))
                    for e, it in zip(ev, self.items, strict=False)
                ]
            )
        chi = float(np.sum(r * r / v))
        dev = chi + float(np.sum(np.log(v / self.sigma**2)))
        return dev, chi, r.size

    def wresid(self, P: dict) -> np.ndarray:
        return (self.resid(P) / self.sigma).ravel()

    @cached_property
    def e0(self) -> float:
        """Expected chi^2 under noise alone: one per Gaussian value; the truth's linkage readings
        are interval-censored (modes._censored), zero at the truth."""
        return float(
            sum(it.residuals({}).shape[0] * np.sum(it.noise_weights()) for it in self.items)
        )

    def gof_z(self, P: dict) -> float | None:
        """Misfit of P on the Gaussian channels above its noise-only level, in standard
        deviations of that level (None where the mode's noise is not calibrated for it).

        Consecutive truth windows share their end sample, so their noise is MA(1) with
        correlation -1/2 and the sum of n squares has variance 2 n (1 + 2 rho^2) = 3 n."""
        if not getattr(self.items[0], "gof", False):
            return None
        w = self.items[0].noise_weights() > 0
        z = self.resid(P)[:, w] / self.sigma[w]
        return float((np.sum(z * z) - z.size) / math.sqrt(3.0 * z.size))


def _mad(x: np.ndarray) -> float:
    """Robust standard deviation (scaled median absolute deviation)."""
    return float(1.4826 * np.median(np.abs(x - np.median(x))))


def estimate_sigma(items: list, mode: str) -> np.ndarray:
    """Per-channel noise of the nominal model's residuals (see module doc)."""
    if mode == "returns" and items[0].accuracy is not None:
        # the user's measurement accuracy: a spread beyond it is evidence (roughness), not noise
        return np.asarray(items[0].accuracy, dtype=float)
    r = np.vstack([it.residuals({}) for it in items])
    floor = np.array([2e-5 if ch.endswith("_rad") else 0.02 for ch in items[0].channels()])
    if mode == "returns":
        # no repeated-measurement floor exists: the spread of the runs around their direction's
        # mean is the non-systematic part (000 s. 3.3); a floor keeps it from vanishing
        # runs of the same path: same direction and the same travel (UMBmark squares and
        # rectangles differ systematically; grouping them by direction only made that "noise")
        dirs = np.array([group_key(it.pr) for it in items])
        dev = np.vstack([r[dirs == d] - r[dirs == d].mean(axis=0) for d in np.unique(dirs)])
        s = np.sqrt(np.sum(dev**2, axis=0) / max(1, r.shape[0] - np.unique(dirs).size))
        return np.maximum(s, np.array([0.5, 0.5, 1e-4]))
    if mode == "truth":
        for c, ch in enumerate(items[0].channels()):
            if ch in ("alpha_rad", "beta_rad"):  # encoder quantisation (10 bit: 0.1 deg)
                floor[c] = items[0].q_rad
            elif ch == "l_mm":
                floor[c] = items[0].q_l_mm
        # the truck channels: the truth's own sample noise (TruthMode.noise_diffs), measured on
        # every sample of every fitting run. A window's increment carries the noise of its two
        # end samples: sqrt(2) sigma per body axis and for the heading. (The spread of the few
        # stationary windows used before was off by 25-40 % per channel, which made small
        # effects "unexplained": a noise excess no hypothesis can remove.) The linkage channels
        # keep their quantisation floor: at the truth their censored residual is zero.
        s = floor.copy()
        for t in range(items[0].trucks):
            d = [it.noise_diffs(t) for it in items]
            pos, head = (np.concatenate([x[i] for x in d]) for i in (0, 1))
            if pos.size < 30:
                break
            sxy, sth = (_mad(x) / math.sqrt(6) for x in (pos, head))
            s[3 * t : 3 * t + 3] = math.sqrt(2) * np.array([sxy, sxy, sth])
        else:
            return np.maximum(s, floor)
    if mode == "linkage":
        # the end reading's quantisation (the start's is profiled out, modes.LinkageMode),
        # unless the profiled residuals show more
        floor = items[0].floor
        s = 1.4826 * np.median(np.abs(r - np.median(r, axis=0)), axis=0)
        return np.maximum(s, floor)
    d = np.diff(r, axis=0)
    s = 1.4826 * np.median(np.abs(d - np.median(d, axis=0)), axis=0) / math.sqrt(2)
    return np.maximum(s, floor)


@dataclass
class Fit:
    name: str  # "ed", "ed+bumps", "nominal"
    params: dict
    stderr: dict
    dev: float
    chi: float
    n: int
    k: int
    bumps: list = field(default_factory=list)

    @property
    def bic(self) -> float:
        return self.dev + self.k * math.log(max(self.n, 2))


def fit_params(
    prob: Problem, keys: list[str], base: dict | None = None, warm: dict | None = None
) -> tuple[dict, dict]:
    """Bounded least squares of `keys` (others from `base`). `warm`: start values (pairs start
    from their singles' fits, one start; else the catalog start and, for slip/skid, a second)."""
    base = dict(base or {})
    if not keys:
        return base, {}
    lo, hi, x0 = zip(*(bounds(k) for k in keys), strict=False)
    x0 = [START.get(k, d) for k, d in zip(keys, x0, strict=False)]
    if warm:
        x0 = [warm.get(k, v) for k, v in zip(keys, x0, strict=False)]

    def f(x):
        P = dict(base)
        P.update(zip(keys, x, strict=False))
        return prob.wresid(P)

    best = None
    starts = [x0]
    if not warm and any(k.startswith(("slip", "skid")) for k in keys):
        starts.append(
            [
                min(h, 0.5) if k.startswith(("slip", "skid")) else s
                for k, s, h in zip(keys, x0, hi, strict=True)
            ]
        )
    for s0 in starts:
        s0 = np.clip(s0, np.array(lo) + 1e-12, np.array(hi) - 1e-12)
        res = least_squares(f, s0, bounds=(lo, hi), x_scale="jac", max_nfev=60)
        if best is None or res.cost < best.cost:
            best = res
    P = dict(base)
    P.update(zip(keys, best.x, strict=False))
    se = {}
    try:
        J = best.jac
        cov = np.linalg.pinv(J.T @ J)
        for i, k in enumerate(keys):
            se[k] = float(math.sqrt(max(cov[i, i], 0.0)))
    except (np.linalg.LinAlgError, ValueError):
        se = {k: float("nan") for k in keys}
    return P, se


def evaluate(prob: Problem, name: str, P: dict, se: dict, k: int, bumps=None) -> Fit:
    dev, chi, n = prob.deviance(P)
    return Fit(name, P, se, dev, chi, n, k, bumps or [])


# ------------------------------------------------------------------------------------------------
# discrete bumps (truth mode): locate heading steps, fit each with the exact profile, cluster
# the events of runs of the same path into floor bumps
# ------------------------------------------------------------------------------------------------
def _signed_excess(
    pr: Prepared, truck: int, wheel: int, h: float, s0: float, a: int = 0, b: int | None = None
) -> np.ndarray:
    """Heading (rad) a bump under (truck, wheel) adds at ticks a..b (up to a constant)."""
    b = pr.S.shape[0] if b is None else b
    e = bump_excess(pr.R[truck], h, pr.S[a:b, truck, wheel] - s0)
    sg = np.sign(pr.ds[a : b - 1, truck, wheel])
    d = np.concatenate([[0.0], np.cumsum(sg * np.diff(e))])
    return (d if wheel == 0 else -d) / pr.b[truck]


def _step_detector(e: np.ndarray, m: int) -> np.ndarray:
    """Step estimate at every sample: the step between the m samples either side minus a third
    of the outer difference, x 1.5: a step's own size at a step, zero for a ramp (drift). The
    run is continued by its end values, so a bump in a run's first or last second (the last
    corner of a rectangle) is seen too."""
    ep = np.pad(e, 2 * m, mode="edge")
    c = np.concatenate([[0.0], np.cumsum(ep)])
    k = np.arange(2 * m, ep.size - 2 * m)

    def mean(a, b):
        return (c[b] - c[a]) / m

    D = (mean(k, k + m) - mean(k - m, k)) - (mean(k + m, k + 2 * m) - mean(k - 2 * m, k - m)) / 3
    return 1.5 * D


def detect_bumps(items: list, P: dict, sigma_head: float) -> list[dict]:
    """Heading steps in each run's truth-minus-model heading; each refined to (wheel, s0, h)."""
    events = []
    for it in items:
        pr = it.pr
        for truck in range(it.trucks):
            mp = it.model_pose(P, truck)
            e = it.tpose[:, truck, 2] - mp[:, 2]
            tt = it.tt
            dt = float(np.median(np.diff(tt)))
            m = max(3, round(0.5 / dt))
            if e.size < 4 * m:
                continue
            D = _step_detector(e, m)
            thr = max(8.0 * _mad(D), 6.0 * sigma_head / math.sqrt(m), 2e-4)
            masked = np.zeros(D.size, dtype=bool)
            h_grid = np.linspace(0.2, 50.0, 400)
            dd_grid = bump_dd(pr.R[truck], h_grid)
            Sa = np.stack([np.interp(tt, pr.t, pr.S[:, truck, w]) for w in (0, 1)])
            tick_all = np.clip(np.searchsorted(pr.t, tt - 1e-9), 0, pr.t.size - 1)
            for _ in range(20):
                absd = np.where(masked, 0.0, np.abs(D))
                q = int(np.argmax(absd))
                if absd[q] < thr:
                    break
                masked[max(0, q - 2 * m) : q + 2 * m] = True
                kc = q
                lo, hi = max(0, kc - 2 * m), min(e.size - 1, kc + 2 * m)
                best = None
                # a bump under the left wheel turns the truck left while that wheel rolls
                # forward (_signed_excess): where both wheels roll one way the step's sign names
                # the wheel, and its size the height (one start instead of two per wheel)
                tick = int(np.clip(np.searchsorted(pr.t, tt[kc]), 1, pr.ds.shape[0])) - 1
                roll = np.sign(pr.ds[tick, truck, :])
                wheels = [w for w in (0, 1) if (1 if w == 0 else -1) * roll[w] == np.sign(D[q])]
                if roll[0] != roll[1] or not wheels:
                    wheels = [0, 1]
                h0 = float(np.interp(abs(D[q]) * pr.b[truck], dd_grid, h_grid))
                for w in wheels:
                    s_lo, s_hi = Sa[w, lo], Sa[w, hi]
                    if s_hi - s_lo < 20.0:
                        continue
                    idx = np.arange(lo, hi + 1)
                    tick_idx = np.searchsorted(pr.t, tt[idx] - 1e-9)
                    tick_idx = np.clip(tick_idx, 0, pr.t.size - 1)
                    ta, tb = int(tick_idx[0]), int(tick_idx[-1]) + 1
                    ti_loc = tick_idx - ta
                    # offset and slope of the drift under the step enter linearly: projected
                    # out (variable projection), the fit moves only height and position
                    tau = tt[idx] - tt[kc]
                    Q, _ = np.linalg.qr(np.column_stack([np.ones_like(tau), tau]))
                    y0 = e[idx]

                    def res(x, pr=pr, w=w, ti=ti_loc, truck=truck, ta=ta, tb=tb, Q=Q, y0=y0):
                        y = y0 - _signed_excess(pr, truck, w, x[0], x[1], ta, tb)[ti]
                        return (y - Q @ (Q.T @ y)) / 1e-4

                    s_mid = Sa[w, kc]
                    try:
                        r = least_squares(
                            res,
                            [h0, s_mid - 30.0],
                            bounds=([0.2, s_lo - 100], [50.0, s_hi]),
                            max_nfev=80,
                        )
                    except ValueError:
                        continue
                    if best is None or r.cost < best[0]:
                        best = (r.cost, w, r.x)
                if best is None:
                    continue
                _, w, x = best
                # take the event out of the residual before looking for the next: the detector
                # answers a step with opposite side lobes of a third of it, and a big bump's ramp
                # carries them past the mask (spurious "bumps" on the other wheel ~1.2 s later)
                e = e - _signed_excess(pr, truck, w, x[0], x[1])[tick_all]
                D = _step_detector(e, m)
                j = int(np.clip(np.searchsorted(Sa[w], x[1]), 0, tt.size - 1))
                th = it.tpose[j, truck, 2]
                half = (0.5 if w == 0 else -0.5) * pr.b[truck]
                xy = (
                    it.tpose[j, truck, 0] - half * math.sin(th),
                    it.tpose[j, truck, 1] + half * math.cos(th),
                )
                events.append(
                    {
                        "run": pr.run.name,
                        "group": group_key(pr),
                        "truck": truck,
                        "wheel": w,
                        "s0": float(x[1]),
                        "h": float(x[0]),
                        "t_s": float(tt[j]),
                        "x_mm": float(xy[0]),
                        "y_mm": float(xy[1]),
                    }
                )
    return events


def group_key(pr: Prepared) -> str:
    """The path a run drove (assign_paths), as '<direction>:<n>'."""
    if pr.path is None:
        assign_paths([pr])
    return pr.path


PATH_TRAVEL_TOL = 0.05  # runs of one path: total travel within 5 %, and
PATH_HEADING_TOL_RAD = 0.35  # heading along the way within 20 deg RMS (room for Eb, Ed errors)


def _heading_profile(pr: Prepared, s: np.ndarray) -> np.ndarray:
    """Truck A's heading from its counts, at distances s (mm) along its travel."""
    ds = pr.ds[:, 0, :]
    th = np.concatenate([[0.0], np.cumsum((ds[:, 1] - ds[:, 0]) / pr.b[0])])
    return np.interp(s, pr.S[:, 0, :].mean(axis=1), th)


def assign_paths(prs: list[Prepared]) -> None:
    """Group runs that drove the same path: the same direction, total travel within 5 % and the
    heading they turned along the way (from the counts, against distance) within 20 deg RMS.
    Total travel alone took a clapper's UMBmark square (arcs, 21.5 m) and its 7 x 4 m rectangle
    (21.6 m) for one path, and a rounded travel put runs of one path on either side of a
    boundary. Runs of one path share floor bumps and noise estimates and are split together."""
    reps: list[tuple[str, float, Prepared]] = []
    counts: dict[str, int] = {}
    for pr in prs:
        S = float(pr.S[-1, 0].mean())
        label = None
        for key, S0, r in reps:
            if key.split(":")[0] != pr.run.direction or abs(S - S0) > PATH_TRAVEL_TOL * S0:
                continue
            grid = np.linspace(0.0, min(S, S0), 400)
            d = _heading_profile(pr, grid) - _heading_profile(r, grid)
            if math.sqrt(float(np.mean(d * d))) <= PATH_HEADING_TOL_RAD:
                label = key
                break
        if label is None:
            counts[pr.run.direction] = counts.get(pr.run.direction, 0) + 1
            label = f"{pr.run.direction}:{counts[pr.run.direction]}"
            reps.append((label, S, pr))
        pr.path = label


def cluster_bumps(events: list[dict], tol_mm: float = 80.0) -> list[dict]:
    """Events of runs on the same path at the same wheel travel are one floor bump."""
    out = []
    keyf = lambda e: (e["group"], e["truck"], e["wheel"])  # noqa: E731
    for key in sorted({keyf(e) for e in events}):
        evs = sorted((e for e in events if keyf(e) == key), key=lambda e: e["s0"])
        cur: list[dict] = []
        for e in [*evs, None]:
            if e is not None and (not cur or e["s0"] - cur[-1]["s0"] < tol_mm):
                cur.append(e)
                continue
            if cur:
                out.append(
                    {
                        "group": key[0],
                        "truck": key[1],
                        "wheel": key[2],
                        "s0": float(np.median([c["s0"] for c in cur])),
                        "h": float(np.median([c["h"] for c in cur])),
                        "x_mm": float(np.median([c["x_mm"] for c in cur])),
                        "y_mm": float(np.median([c["y_mm"] for c in cur])),
                        "t_s": float(np.median([c["t_s"] for c in cur])),
                        "runs": sorted({c["run"] for c in cur}),
                    }
                )
            cur = [e] if e is not None else []
    return out


def place_bumps(
    prs: list[Prepared], floor_bumps: list[dict], h: float | None = None, own: bool = False
) -> None:
    """Put floor bumps on the runs of their path; `own`: only on the runs whose own events made
    them (fitting: a path's runs need not share their bumps - rect-7x4 alternates the wheel)."""
    for pr in prs:
        g = group_key(pr)
        pr.bumps = [
            {
                "truck": b["truck"],
                "wheel": b["wheel"],
                "s0": b["s0"],
                "h": h if h is not None else b["h"],
            }
            for b in floor_bumps
            if b["group"] == g and (not own or pr.run.name in b.get("runs", ()))
        ]


def clear_bumps(prs: list[Prepared]) -> None:
    for pr in prs:
        pr.bumps = []

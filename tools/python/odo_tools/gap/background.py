"""The background every real world carries, measured from the data: the share of the gap that no
hypothesis should be asked to remove (issue 13 item 2, DESIGN.md s. 6).

A floor is never perfect: every wheel's floor travel wanders a little from its rotation (grains,
joints, tyre give), which shortens travel a little and random-walks the heading. On top of that
the truth has its own noise. Both are measured here, and the verdict is decided against them in
absolute terms (held-out mm and deg left after the fit, beside what the background alone would
leave), instead of against the nominal misfit.

- **Truth mode.** The random walk's intensity `q_wheel` (mm^2 of floor-travel variance per mm of
  a wheel's travel), from the heading residual under the candidate effect, less what the other
  runs of the same path show at the same travel (`unrepeated`: a walk differs from run to run,
  a misfit the candidate leaves repeats): differences of adjacent blocks of 0.4 to 3.2 s cancel
  whatever changes slowly
  along the run, and their robust variance grows as a + (q_wheel / b^2) x travel; the intercept
  takes the truth's own noise, correlated over a window or not (`walk`). The accumulated error
  the walk leaves along a held-out run (`track_var`) plus the truth's sample noise is that run's
  background allowance.
- **Returns mode.** The spread of each path's return poses about their mean (fit.estimate_sigma),
  or the stated accuracy of the return measurement; the held-out allowance is that spread.

A floor's roughness is also a catalog effect: the verdict names it when its hypothesis (grains
that shorten travel on average and spread it) closes the held-out gap like any other; the walk
measured here is what is left after the candidate, whatever it is.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .model import track_at
from .modes import ANCHOR_S, TruthMode

TRACK_VAR_CACHE = 256  # runs x trucks x sets of floor bumps kept (each a few kB)


@dataclass
class Background:
    mode: str
    # truth, per truck: the walk's intensity while driving (straights, arcs) and while turning
    # on the spot, mm^2 of floor-travel variance per mm of wheel travel (both wheels summed)
    q_wheel: list[float] = field(default_factory=list)
    q_turn: list[float] = field(default_factory=list)
    q_wheel_ci: list[tuple[float, float]] = field(default_factory=list)  # 68 % bootstrap
    q_turn_ci: list[tuple[float, float]] = field(default_factory=list)
    # truth, per truck: the longitudinal channel's own walk, mm^2 per mm of both wheels' travel
    # (travel a floor takes or gives beyond what turns the heading)
    q_long: list[float] = field(default_factory=list)
    # truth, per truck: the walk of the whole residual under the candidate, repeatable part and
    # all (driving, on the spot): what the remainder looks like, beside what is background
    q_all: list[tuple[float, float]] = field(default_factory=list)
    # truth: each truck channel's noise per window at the window scale (sqrt(intercept / 3) of
    # the multi-scale fit: 3 window variances for white sample noise), which also holds noise
    # correlated over a window that the samples' second differences miss
    window_sigma: np.ndarray | None = None
    spread: np.ndarray | None = None  # returns: per channel sigma of the runs about their path mean
    # track_var per run and truck: it does not depend on the parameters a fit moves, and a track
    # fit asked for it at every step (8 of a 10-run set's 46 s, dev seed 2841 case 37)
    _tv: dict = field(default_factory=dict, repr=False, compare=False)

    def _q(self, t: int) -> tuple[float, float]:
        qm = self.q_wheel[t] if t < len(self.q_wheel) else 0.0
        qt = self.q_turn[t] if t < len(self.q_turn) else qm
        return qm, qt

    @property
    def active(self) -> bool:
        qs = (*self.q_wheel, *self.q_turn, *self.q_long)
        return self.mode == "truth" and any(q > 0 for q in qs)

    def window_var(self, item: TruthMode) -> np.ndarray | None:
        """Variance the walk adds to each truth window's residual (nwin, channels)."""
        if not self.active:
            return None
        out = np.zeros((item.i.size, len(item.channels())))
        for t in range(item.trucks):
            qm, qt = self._q(t)
            E = item.wtravel[t, 0] + item.wtravel[t, 1]
            Et = item.wturn[t]
            v = qm * (E - Et) + qt * Et  # mm^2 of the two wheels' floor travel
            ql = self.q_long[t] if t < len(self.q_long) else 0.0
            b = item.pr.b[t]
            Lt = 0.5 * (E - Et)  # what carries a turn sideways: the travel off the spot
            out[:, 3 * t] = v / 4.0 + ql * E
            out[:, 3 * t + 1] = v / b**2 * Lt**2 / 3.0
            out[:, 3 * t + 2] = v / b**2
        return out

    def track_var(self, item: TruthMode, truck: int) -> np.ndarray:
        """(nwin, 3) variance of the accumulated x, y (mm^2) and heading (rad^2) error the walk
        leaves at each window start of a run: every tick's floor-travel noise of either wheel,
        propagated to that point (a wheel's shortfall d turns the truck by -/+ d/b, which carries
        the rest of the path sideways, and moves it back by d/2)."""
        qm, qt = self._q(truck)
        ql = self.q_long[truck] if truck < len(self.q_long) else 0.0
        # a floor that takes travel without turning the truck (the longitudinal walk alone)
        # still moves it along: the independent world's trailer on grains, 0.08 mm high under
        # 76 mm wheels, heading walk 0, lost 1-1.5 mm along a 15 m run; with only the truth's
        # 0.3 mm noise allowed, its no-effect set sat at 2.2 x the background
        if qm <= 0 and qt <= 0 and ql <= 0:
            return self.count_var(item, truck)
        # keyed by what it reads: the walk, and the floor bumps placed on the run (the nominal
        # track below is dead-reckoned over them); the item is kept with it, so that another
        # item that comes to have the same id() is not served this one's
        key = (
            id(item),
            truck,
            qm,
            qt,
            ql,
            tuple((b["truck"], b["wheel"], b["s0"], b["h"]) for b in item.pr.bumps),
        )
        return self._cached(
            key,
            item,
            lambda: self._track_var(item, truck, qm, qt, ql) + self.count_var(item, truck),
        )

    def count_var(self, item: TruthMode, truck: int) -> np.ndarray:
        """(nwin, 3) variance of the accumulated x, y, heading error that the counts' own
        resolution leaves at each window start of a run (`counting_error`), cached per run."""
        return self._cached(("counts", id(item), truck), item, lambda: counting_error(item, truck))

    def _cached(self, key: tuple, item: TruthMode, make) -> np.ndarray:
        hit = self._tv.get(key)
        if hit is not None and hit[0] is item:
            return hit[1]
        out = make()
        out.setflags(write=False)  # shared by every caller
        if len(self._tv) >= TRACK_VAR_CACHE:  # bump fits place a new set of bumps at every step
            self._tv.clear()
        self._tv[key] = (item, out)
        return out

    def _track_var(
        self, item: TruthMode, truck: int, qm: float, qt: float, ql: float
    ) -> np.ndarray:
        pr = item.pr
        tw = item.tt[item.i]
        n_out = tw.size
        from .model import dead_reckon
        from .modes import spot_ticks

        p = dead_reckon(pr, {}, truck)
        pm = 0.5 * (p[:-1] + p[1:])
        c, s_ = np.cos(pm[:, 2]), np.sin(pm[:, 2])
        q = np.where(spot_ticks(pr)[:, truck], qt, qm)[:, None]
        ew = np.abs(pr.ds[:, truck, :]) * q  # (n-1, 2) variance per tick per wheel
        b = pr.b[truck]
        # tick k's noise reaches a later point P as g = (-u_k / 2 -/+ J (P - p_k) / b): with the
        # sums A = sum e, Bx = sum e x_k, Cx = sum e x_k^2 ... up to P, Var = quadratic in P.
        k_end = np.clip(np.searchsorted(pr.t, tw, side="right") - 1, 0, pm.shape[0])
        out = np.zeros((n_out, 3))
        for w, sw in ((0, 1.0), (1, -1.0)):
            e = ew[:, w]
            x, y = pm[:, 0], pm[:, 1]
            # the along-track part (-u/2) and the lateral part (-/+ J (P - p)/b) are combined per
            # coordinate: gx = -c/2 - sw (Py - y)/b, gy = -s/2 + sw (Px - x)/b
            cs = lambda a: np.concatenate([[0.0], np.cumsum(a)])  # noqa: E731
            S0, Sy, Syy = cs(e), cs(e * y), cs(e * y * y)
            Sx, Sxx = cs(e * x), cs(e * x * x)
            Sc, Scc, Scy = cs(e * c), cs(e * c * c), cs(e * c * y)
            Ss, Sss, Ssx = cs(e * s_), cs(e * s_ * s_), cs(e * s_ * x)
            kk = k_end
            Px, Py = track_at(tw, pr.t, p[:, :2]).T
            a = sw / b
            # E[gx^2 e] = sum e (c/2 + a (Py - y))^2
            vx = (
                0.25 * Scc[kk]
                + a * (Py * Sc[kk] - Scy[kk])
                + a * a * (Py * Py * S0[kk] - 2 * Py * Sy[kk] + Syy[kk])
            )
            vy = (
                0.25 * Sss[kk]
                - a * (Px * Ss[kk] - Ssx[kk])
                + a * a * (Px * Px * S0[kk] - 2 * Px * Sx[kk] + Sxx[kk])
            )
            out[:, 0] += vx
            out[:, 1] += vy
            out[:, 2] += S0[kk] / b**2
        if ql > 0:  # the longitudinal walk moves the truck along its heading only
            el = ql * np.abs(pr.ds[:, truck, :]).sum(axis=1)
            cs = lambda a: np.concatenate([[0.0], np.cumsum(a)])  # noqa: E731
            out[:, 0] += cs(el * c * c)[k_end]
            out[:, 1] += cs(el * s_ * s_)[k_end]
        return np.maximum(out, 0.0)


COUNT_DRAWS = 64  # encoder phases drawn by counting_error
COUNT_SMOOTH = 5  # ticks the counts are averaged over to stand for the travel between counts


def counting_error(item: TruthMode, truck: int, draws: int = COUNT_DRAWS) -> np.ndarray:
    """(nwin, 3) variance of the accumulated x, y (mm^2) and heading (rad^2) error that counting
    alone leaves along a run, anchored as TruthMode.anchored anchors it. A counter reads the
    floor of its wheel's travel in counts, so the heading the model takes from two counters is
    off by the difference of the two wheels' unread fractions (up to one count over the
    wheelbase), and that error does not average out: while both wheels turn alike (a straight)
    the fractions keep their difference, a heading error held over the whole straight that
    carries the track sideways in proportion to the distance. The fractions are unknown; their
    spread is drawn: the wheels' travel (the counts, averaged over COUNT_SMOOTH ticks so that
    it moves between whole counts) under a uniform encoder phase per wheel and draw,
    dead-reckoned along the counts' own track. The independent world's encoders give one
    count from 0.003 to 11 mrad of heading (dev seeds 4061-4111, median 0.16). Seven LabMates
    of dev seeds 4061-4091 with 0.9-7.8 mrad a count, quieted (no effect, perfect floor and
    sensors: cases.quiet), left the nominal model 0.05-8.5 mm RMS along their runs (0.7-2.7 x
    what is drawn here, robot by robot), and five were "unexplained" at 1.5-24 x the
    background without this term; with it, one (4081 case 23, at 1.8 x: the robot drives from
    its own counts, and how that loop dithers the wheels about a count is not drawn here)."""
    pr = item.pr
    tw = item.tt[item.i]
    if not pr.count_mm or truck >= len(pr.count_mm) or pr.count_mm[truck] <= 0:
        return np.zeros((tw.size, 3))
    c = pr.count_mm[truck]
    b = pr.b[truck]
    ds = pr.ds[:, truck, :]
    X = np.vstack([np.zeros((1, 2)), np.cumsum(ds, axis=0)]) / c
    k = np.ones(COUNT_SMOOTH) / COUNT_SMOOTH
    h = COUNT_SMOOTH // 2
    X = np.column_stack(
        [np.convolve(np.pad(X[:, w], h, mode="edge"), k, mode="valid") for w in (0, 1)]
    )
    rng = np.random.default_rng(1)
    ph = rng.uniform(0.0, 1.0, (draws, 1, 2))
    eps = np.mod(X[None] + ph, 1.0)  # each wheel's unread fraction at each tick
    eps = eps - eps[:, :1]  # counted from the run's first tick
    dth = -(eps[..., 1] - eps[..., 0]) * c / b  # (draws, n) heading error (right - left)
    dl = -0.5 * (eps[..., 0] + eps[..., 1]) * c  # travel error along the track
    # the counts' own track (no bump or effect: only where the errors are carried matters),
    # midpoint steps as the errors below are carried
    d = 0.5 * (ds[:, 0] + ds[:, 1])  # signed: a shuttle reverses
    th = np.concatenate([[0.0], np.cumsum((ds[:, 1] - ds[:, 0]) / b)])
    hm = 0.5 * (th[:-1] + th[1:])
    px = np.concatenate([[0.0], np.cumsum(d * np.cos(hm))])
    py = np.concatenate([[0.0], np.cumsum(d * np.sin(hm))])
    mid = 0.5 * (dth[:, :-1] + dth[:, 1:])
    z = np.zeros((draws, 1))
    ex = np.concatenate([z, np.cumsum(-d * np.sin(hm) * mid, axis=1)], axis=1)
    ey = np.concatenate([z, np.cumsum(d * np.cos(hm) * mid, axis=1)], axis=1)
    ex += dl * np.cos(th)
    ey += dl * np.sin(th)
    a = pr.t <= pr.t[0] + ANCHOR_S  # the anchor takes the mean offsets over its first seconds
    d0 = dth[:, a].mean(axis=1)[:, None]
    ex += d0 * py  # the anchor turns the whole track about its start
    ey -= d0 * px
    dth = dth - d0
    ex -= ex[:, a].mean(axis=1)[:, None]
    ey -= ey[:, a].mean(axis=1)[:, None]
    # into the truth's frame: the counts' track starts at heading 0, the truth where it stands
    # (the anchor's heading offset, as TruthMode.anchored takes it, not the heading driven to)
    ka = item.tt <= item.tt[0] + ANCHOR_S
    h0 = item.tpose[ka, truck, 2] - np.interp(item.tt[ka], pr.t, th)
    h0 = math.atan2(float(np.mean(np.sin(h0))), float(np.mean(np.cos(h0))))
    ex, ey = math.cos(h0) * ex - math.sin(h0) * ey, math.sin(h0) * ex + math.cos(h0) * ey
    kk = np.clip(np.searchsorted(pr.t, tw, side="right") - 1, 0, pr.t.size - 1)
    return np.column_stack([ex[:, kk].var(axis=0), ey[:, kk].var(axis=0), dth[:, kk].var(axis=0)])


BLOCKS = (1, 2, 4, 8)  # block lengths in windows (0.4 - 3.2 s) of the multi-scale estimate


def _block_diffs(r: np.ndarray, E: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    """Differences of adjacent k-window sums of a residual, and the travel they span (E may be
    (nwin,) or (nwin, m) for m kinds of travel)."""
    n = r.size // k
    if n < 2:
        return np.zeros(0), np.zeros((0, *E.shape[1:]))
    R = r[: n * k].reshape(n, k).sum(axis=1)
    EE = E[: n * k].reshape((n, k, *E.shape[1:])).sum(axis=1)
    return np.diff(R), EE[1:] + EE[:-1]


def _multiscale(per_run: list[tuple[np.ndarray, np.ndarray]]) -> tuple[float, float]:
    """(intercept, slope) of the robust variance of adjacent block differences of a residual
    against the travel E they span, over blocks of 1 to 8 windows."""
    xs, ys, ws = [], [], []
    for k in BLOCKS:
        d = [_block_diffs(r, E, k) for r, E in per_run]
        dd = np.concatenate([x[0] for x in d])
        ee = np.concatenate([x[1] for x in d])
        if dd.size < 8:
            continue
        s = 1.4826 * np.median(np.abs(dd - np.median(dd)))
        xs.append(float(ee.mean()))
        ys.append(float(s * s))
        ws.append(dd.size)
    if len(xs) < 2:
        return (ys[0] if ys else 0.0), 0.0
    x, y, w = (np.asarray(v, dtype=float) for v in (xs, ys, ws))
    if not np.any(y > 0):  # a noiseless truth (odo-sim's own files): nothing walks
        return 0.0, 0.0
    w = w / np.maximum(y, 1e-12 * y.max()) ** 2  # a variance estimate's variance: its square
    A = np.column_stack([np.ones_like(x), x]) * np.sqrt(w)[:, None]
    coef = np.linalg.lstsq(A, y * np.sqrt(w), rcond=None)[0]
    if coef[1] < 0:  # no walk: the intercept is the mean level
        return float(np.average(y, weights=w)), 0.0
    return max(float(coef[0]), 0.0), float(coef[1])


def walk(per_run: list[tuple[np.ndarray, np.ndarray]], b: float) -> float:
    """q_wheel from the heading residuals and window travel of runs (module doc): adjacent block
    differences at 0.4 to 3.2 s; their robust variance grows as a + (q_wheel / b^2) E with
    the travel E they span. The intercept takes the truth's noise, correlated over a window or
    not (a motion-capture heading often is); the slope is the walk."""
    return _multiscale(per_run)[1] * b * b


def walk_by_phase(per_run: list[tuple[np.ndarray, np.ndarray]], b: float) -> tuple[float, float]:
    """(q while driving, q while turning on the spot) from per_run (residual, (nwin, 2) travel
    driving and on the spot): every block difference at every scale is a row of
    d^2 ~ a + q_drive E_drive / b^2 + q_turn E_turn / b^2, fitted by iteratively reweighted
    least squares (var(d^2) = 2 var(d)^2 for a Gaussian d; rows beyond 3 sigma are outliers: a
    bump the candidate did not place). Without spot turns both are the one walk."""
    rows_d, rows_e = [], []
    for k in BLOCKS:
        for r, E in per_run:
            d, e = _block_diffs(r, E, k)
            rows_d.append(d)
            rows_e.append(e)
    d2 = np.concatenate(rows_d) ** 2
    E = np.vstack(rows_e) / b**2
    if d2.size < 16 or not np.median(d2) > 0:
        return 0.0, 0.0
    tiny = 1e-9 * float(np.median(d2))
    has_turn = np.sum(E[:, 1] > 0) >= 8
    X = (
        np.column_stack([np.ones_like(d2), E[:, 0], E[:, 1]])
        if has_turn
        else np.column_stack([np.ones_like(d2), E.sum(axis=1)])
    )
    coef = np.zeros(X.shape[1])
    coef[0] = float(np.median(d2)) / 0.455
    keep = np.ones(d2.size, dtype=bool)
    for _ in range(8):
        fit = np.maximum(X @ coef, tiny)
        keep = d2 <= 9.0 * fit
        w = 1.0 / fit
        Xw = X[keep] * w[keep, None]
        coef = np.linalg.lstsq(Xw, d2[keep] * w[keep], rcond=None)[0]
        coef[1:] = np.maximum(coef[1:], 0.0)
        coef[0] = max(coef[0], tiny)
    if not has_turn:  # the columns are travel / b^2: the slopes are q_wheel itself
        return float(coef[1]), float(coef[1])
    return float(coef[1]), float(coef[2])


def measure(
    items: list,
    sigma: np.ndarray,
    mode: str,
    P: dict | None = None,
    seed: int = 1,
    pool: list | None = None,
) -> Background:
    """The background of the fitting runs, under the candidate P (its systematic part must not
    be taken for a walk). `pool` (truth): the held-out runs, whose differences from the other
    runs of their path join the walk's estimate (`unrepeated`): what does not repeat between
    runs of a path is the same under any fit. With the fitting runs alone most paths had one
    run: where none had two, the walk was the whole residual left under the candidate (a skid
    law the catalog's only approximates left 0.19 deg per sqrt(m) on a floor that walks 100
    times less, an allowance of 34 mm that vetoed the skid: independent world, seed 9 case 5);
    where only a series of spot turns had two, their little driving gave a driving walk of
    0.5 deg per sqrt(m) and a 38 mm allowance that vetoed an Ed the return errors name at 80 x
    the background (seed 10 case 11)."""
    bg = Background(mode)
    if mode == "truth":
        P = P or {}
        T = items[0].trucks
        ws = np.zeros(len(items[0].channels()))
        res = [it.residuals(P) for it in items]
        for t in range(T):
            for c in range(3 * t, 3 * t + 3):
                per = [
                    (r[:, c], it.wtravel[t, 0] + it.wtravel[t, 1])
                    for r, it in zip(res, items, strict=False)
                ]
                ws[c] = math.sqrt(_multiscale(per)[0] / 3.0)
        bg.window_sigma = ws
        both = items + list(pool or [])
        res_all = res + [it.residuals(P) for it in pool or []]
        for t in range(T):
            per_run = unrepeated(both, [heading_means(it, P, t) for it in both], t)
            b = items[0].pr.b[t]
            qm, qt = walk_by_phase(per_run, b)
            nm, nt = noise_walk(both, t, ws[3 * t + 2], b, seed)
            qm, qt = max(qm - nm, 0.0), max(qt - nt, 0.0)
            rng = np.random.default_rng(seed)
            boots = []
            for _ in range(30):
                k = rng.integers(0, len(per_run), len(per_run))
                boots.append(walk_by_phase([per_run[i] for i in k], b))
            bm = np.array(boots)
            bg.q_wheel.append(qm)
            bg.q_turn.append(qt)
            bg.q_wheel_ci.append(
                (float(np.percentile(bm[:, 0], 16)), float(np.percentile(bm[:, 0], 84)))
            )
            bg.q_turn_ci.append(
                (float(np.percentile(bm[:, 1], 16)), float(np.percentile(bm[:, 1], 84)))
            )
            whole = [
                (r[:, 3 * t + 2], E)
                for r, (_, E) in zip(res, unrepeated_expo(items, t), strict=False)
            ]
            bg.q_all.append(walk_by_phase(whole, b))
            per_long = unrepeated(both, [r[:, 3 * t] for r in res_all], t)
            bg.q_long.append(_multiscale([(d, E.sum(axis=1)) for d, E in per_long])[1])
    elif mode == "returns":
        bg.spread = np.asarray(sigma, dtype=float)
    return bg


def heading_means(item: TruthMode, P: dict, t: int) -> np.ndarray:
    """Per window: the change of the mean heading residual (truth minus model under P) over
    the window's truth samples from the previous window's (the first window: 0). The walk is
    read from these means, not from the window's two end samples: a motion capture at 200 Hz
    puts 80 samples in a 0.4 s window, and its heading noise (up to 0.3 deg per sample in the
    independent world) then hides no walk of a tenth of a degree per turn."""
    e = item.tpose[:, t, 2] - item.model_pose(P, t)[:, 2]
    c = np.concatenate([[0.0], np.cumsum(e)])
    m = (c[item.j] - c[item.i]) / (item.j - item.i)
    return np.concatenate([[0.0], np.diff(m)])


def window_samples(items: list) -> float:
    """Median number of truth samples per window."""
    return float(np.median([float(np.median(it.j - it.i)) for it in items]))


NOISE_DRAWS = 16


def noise_walk(
    items: list, t: int, window_sigma: float, b: float, seed: int
) -> tuple[float, float]:
    """The walk (driving, on the spot) that `walk_by_phase` reads, through `unrepeated`, from
    the truth's own white noise alone: the mean over NOISE_DRAWS draws of a heading noise of
    the measured size (window_sigma: a window's residual, two samples' noise) on these runs'
    windows and travel. Its estimate is a slope fitted beside an intercept and kept >= 0, so
    noise alone reads as a walk: 0.28 deg of motion-capture heading noise per sample read as
    0.25 deg per spot turn, an allowance of 36 mm that hid an Eb whose fit took the held-out
    runs from 35 mm to 3 mm (independent world). That share is the noise's, not the floor's,
    and `measure` takes it off."""
    if not window_sigma > 0:
        return 0.0, 0.0
    s = window_sigma / math.sqrt(2.0) / math.sqrt(window_samples(items))  # a window's mean
    rng = np.random.default_rng(seed + 7919)
    draws = []
    for _ in range(NOISE_DRAWS):
        rs = [np.diff(rng.normal(0.0, s, it.i.size + 1)) for it in items]
        draws.append(walk_by_phase(unrepeated(items, rs, t), b))
    m = np.mean(np.array(draws), axis=0)
    return float(m[0]), float(m[1])


def unrepeated(items: list, r: list[np.ndarray], t: int) -> list[tuple[np.ndarray, np.ndarray]]:
    """Per run: (window residual of truck t less what the other runs of its path show at the
    same travel, (nwin, 2) travel of both wheels driving and turning on the spot). A floor's walk
    and the truth's noise differ from run to run; a misfit the candidate leaves because the robot
    has something else (a gear backlash at every reversal, a diameter that breathes with time, a
    bump it did not place) repeats on every run of the path, and is not background: the
    accumulated residual of each run, against its wheels' travel, minus the mean of its path's
    runs, scaled by sqrt(n / (n - 1)). Paths with a single fitting run cannot tell the two apart
    and are used as they are only when no path has two."""
    from .paths import group_key

    def expo(it) -> np.ndarray:
        E = it.wtravel[t, 0] + it.wtravel[t, 1]
        return np.column_stack([E - it.wturn[t], it.wturn[t]])

    travel = [
        np.concatenate([[0.0], np.cumsum(it.wtravel[t, 0] + it.wtravel[t, 1])]) for it in items
    ]  # at the window ends
    acc = [np.concatenate([[0.0], np.cumsum(x)]) for x in r]
    paths: dict[str, list[int]] = {}
    for k, it in enumerate(items):
        paths.setdefault(group_key(it.pr), []).append(k)
    out = []
    for idx in paths.values():
        if len(idx) < 2:
            continue
        n = len(idx)
        for k in idx:
            s = travel[k]
            others = [np.interp(s, travel[j], acc[j]) for j in idx]
            dev = (acc[k] - np.mean(others, axis=0)) * math.sqrt(n / (n - 1.0))
            out.append((np.diff(dev), expo(items[k])))
    if not out:
        out = [(x, expo(it)) for x, it in zip(r, items, strict=False)]
    return out


def spot_turn_deg(q_turn: float, b_mm: float) -> float:
    """The walk on the spot in words: heading spread (deg) of one 90 deg turn on the spot (both
    wheels roll pi b / 4 each)."""
    return math.degrees(math.sqrt(max(q_turn, 0.0) * math.pi * b_mm / 2.0) / b_mm)


def unrepeated_expo(items: list, t: int) -> list[tuple[None, np.ndarray]]:
    """Per run: (None, (nwin, 2) travel driving and on the spot), as `unrepeated` gives it."""
    return [
        (None, np.column_stack([it.wtravel[t, 0] + it.wtravel[t, 1] - it.wturn[t], it.wturn[t]]))
        for it in items
    ]


def heading_walk_deg_per_sqrt_m(q_wheel: float, b_mm: float) -> float:
    """The walk in words: heading spread (deg) after 1 m of straight travel (2 m of wheels)."""
    return math.degrees(math.sqrt(max(q_wheel, 0.0) * 2000.0) / b_mm)

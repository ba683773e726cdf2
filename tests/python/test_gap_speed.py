"""The diagnosis's hot loops were rewritten for speed on the promise of changing no number (issue
13: a 10-run diagnosis in under 30 s). Each rewrite is held here to a plain transcription of the
form it replaced, bit for bit, and its caches to a fresh computation; `make bench-gap REF=<rev>`
compares whole reports and prints the timings."""

from __future__ import annotations

import math

import numpy as np
import pytest


def _prepared(ds: np.ndarray, link=None, driven=(True, True), dt_s: float = 0.02):
    from odo_tools.gap.model import Prepared

    n, T = ds.shape[0] + 1, ds.shape[1]
    S = np.concatenate([np.zeros((1, T, 2)), np.cumsum(np.abs(ds), axis=0)])
    return Prepared(
        None, np.arange(n) * dt_s, ds, S, [340.0] * T, [75.0] * T, np.full(n - 1, dt_s),
        driven=list(driven)[:T], link=link,
    )  # fmt: skip


def _wheels(rng: np.random.Generator, n: int) -> np.ndarray:
    """(n, 2) wheel travel per tick (mm): straights, arcs, spot turns and stops."""
    v = np.cumsum(rng.normal(0.0, 0.6, (n, 2)), axis=0)
    v[n // 5 : n // 4] = 0.0  # a stop
    v[n // 2 : n // 2 + 40, 1] = -v[n // 2 : n // 2 + 40, 0]  # a turn on the spot
    return v


def test_traction_rate_limiter_is_the_per_tick_clip_bit_for_bit() -> None:
    from odo_tools.gap.model import slip_traction

    rng = np.random.default_rng(5)
    ds = _wheels(rng, 1500)
    pr = _prepared(ds[:, None, :])
    pr.dt = 0.02 + rng.uniform(0.0, 1e-4, ds.shape[0])  # jittered ticks
    b = pr.b[0]
    for a_max in (0.05, 0.8, 3.0, 20.0):
        raw = ds / pr.dt[:, None]
        v = raw.copy()  # each tick's speed weighed with its neighbours' (model._wheel_speeds)
        v[1:-1] = 0.25 * raw[:-2] + 0.5 * raw[1:-1] + 0.25 * raw[2:]
        # the friction circle's share per tick (model.slip_traction), then the plain clip
        a = a_max * 1e3
        alat = np.abs(0.5 * (v[:, 0] + v[:, 1]) * (v[:, 1] - v[:, 0]) / b)
        lim = np.sqrt(np.maximum(a * a - alat * alat, (0.1 * a) ** 2)) * pr.dt
        u, cur = np.empty_like(v), np.zeros(2)
        for i in range(v.shape[0]):  # the form it replaced: one numpy clip per tick
            cur = cur + np.clip(v[i] - cur, -lim[i], lim[i])
            u[i] = cur
        got = slip_traction(pr, ds, a_max, b)
        assert np.array_equal(got, ds - (v - u) * pr.dt[:, None]), a_max
        if a_max < 1.0:
            assert not np.allclose(got, ds)  # the limiter bites: the comparison can fail


def _integrate_plain(ds, b, lat, g=None, pose0=(0.0, 0.0, 0.0)):
    d = 0.5 * (ds[:, 0] + ds[:, 1])
    dth = (ds[:, 1] - ds[:, 0]) / b
    if g is not None:
        dth = dth * g
    th = pose0[2] + np.concatenate([[0.0], np.cumsum(dth)])
    half = 0.5 * dth
    with np.errstate(invalid="ignore", divide="ignore"):
        chord = np.where(np.abs(half) > 1e-9, d * np.sin(half) / np.where(half == 0, 1, half), d)
    mid = th[:-1] + half
    dx = chord * np.cos(mid) - lat * np.sin(mid)
    dy = chord * np.sin(mid) + lat * np.cos(mid)
    x = pose0[0] + np.concatenate([[0.0], np.cumsum(dx)])
    y = pose0[1] + np.concatenate([[0.0], np.cumsum(dy)])
    return np.column_stack([x, y, th])


@pytest.mark.parametrize("skid", [False, True])
@pytest.mark.parametrize("pose0", [(0.0, 0.0, 0.0), (120.0, -35.0, 0.7)])
def test_exact_arc_integration_is_the_plain_form_bit_for_bit(skid: bool, pose0: tuple) -> None:
    from odo_tools.gap.model import integrate

    rng = np.random.default_rng(7)
    ds = _wheels(rng, 2000)
    lat = rng.normal(0.0, 0.05, ds.shape[0]) if skid else np.zeros(ds.shape[0])
    g = rng.uniform(0.95, 1.0, ds.shape[0])
    for gg in (None, g):
        assert np.array_equal(integrate(ds, 340.0, lat, gg, pose0),
                              _integrate_plain(ds, 340.0, lat, gg, pose0))  # fmt: skip


def _clapper(rng: np.random.Generator):
    """Two trucks 1000 mm apart whose wheels disagree enough to leave the link's range."""
    a = _wheels(rng, 600)
    b = 0.9 * a + rng.normal(0.0, 0.3, a.shape)
    ds = np.stack([a, b], axis=1)
    return ds, (1000.0, 0.05, -0.02, 990.0, 1010.0, None)


def test_clapper_clamp_shared_by_both_trucks_equals_a_fresh_replay() -> None:
    """dead_reckon caches one clamp for both trucks' calls; every answer equals the one a fresh
    run (no cache) gives, in either order and after the parameters moved and came back."""
    from odo_tools.gap.model import dead_reckon

    ds, link = _clapper(np.random.default_rng(3))
    shared = _prepared(ds, link=link)
    P1, P2 = {"ed.value": 1.004}, {"ed.value": 1.004, "eb.value.B": 1.02}
    pushed = False
    for P, truck in [(P1, 0), (P1, 1), (P2, 1), (P2, 0), (P1, 1), (P1, 0), (P2, 0)]:
        fresh = dead_reckon(_prepared(ds, link=link), P, truck)
        got = dead_reckon(shared, P, truck)
        assert np.array_equal(got, fresh), (P, truck)
        free = _integrate_plain(*_floor(ds, P, truck))
        pushed |= not np.allclose(got, free)
    assert pushed  # the link left its range: the clamp was replayed, not skipped


def _floor(ds, P, truck):
    from odo_tools.gap.model import floor_travel

    return floor_travel(_prepared(ds), P, truck)


def test_track_cache_answers_each_truck_for_its_own_parameters() -> None:
    """The track cache is keyed by what acts on a truck: a parameter of truck B moves B's track
    and leaves A's, a set trailer's track ignores slip, and none of them is a stale answer."""
    from odo_tools.gap.model import dead_reckon

    rng = np.random.default_rng(11)
    a = _wheels(rng, 800)
    ds = np.stack([a, 1.01 * a], axis=1)
    pr = _prepared(ds, driven=(True, False))
    nomA, nomB = dead_reckon(pr, {}, 0), dead_reckon(pr, {}, 1)
    PB = {"ed.value.B": 1.01}
    assert np.array_equal(dead_reckon(pr, PB, 0), nomA)
    movedB = dead_reckon(pr, PB, 1)
    assert not np.allclose(movedB, nomB)
    assert np.array_equal(movedB, dead_reckon(_prepared(ds, driven=(True, False)), PB, 1))
    slip = {"slip@traction.a_max_m_s2": 0.2}
    assert np.array_equal(dead_reckon(pr, slip, 1), nomB)  # the trailer rolls passively
    assert not np.allclose(dead_reckon(pr, slip, 0), nomA)
    assert math.isfinite(float(movedB[-1, 0]))


def _track_at_plain(tq, t: np.ndarray, y: np.ndarray) -> np.ndarray:
    """model.track_at as it was before its weights were kept (TrackAt): searched and weighted on
    every call."""
    tq = np.asarray(tq, dtype=float)
    n = t.size
    if n < 3:
        return np.interp(tq, t, y) if y.ndim == 1 else np.stack(
            [np.interp(tq, t, y[:, c]) for c in range(y.shape[1])], axis=-1)
    k = np.clip(np.searchsorted(t, tq, side="right") - 1, 0, n - 2)
    km, kp = np.maximum(k - 1, 0), np.minimum(k + 2, n - 1)
    t0, t1 = t[k], t[k + 1]
    h = t1 - t0
    u = np.clip((tq - t0) / h, 0.0, 1.0)
    a, c = h / (t1 - t[km]), h / (t[kp] - t0)
    if y.ndim > 1:
        u, a, c = u[..., None], a[..., None], c[..., None]
    y0, y1 = y[k], y[k + 1]
    d = y1 - y0
    w = 1.0 - u
    return y0 + u * (d + w * (w * ((y1 - y[km]) * a - d) - u * ((y[kp] - y0) * c - d)))


@pytest.mark.parametrize("ticks", [2, 3, 400])
def test_track_at_fixed_times_is_the_plain_form_bit_for_bit(ticks: int) -> None:
    """The truth's samples are fixed per run, so TruthMode keeps TrackAt's search and weights
    and applies them to every parameter step's track: jittered ticks, samples between, on and
    beyond them, one column and three, several tracks through one TrackAt."""
    from odo_tools.gap.model import TrackAt

    rng = np.random.default_rng(3)
    t = np.cumsum(rng.uniform(0.018, 0.022, ticks))
    tq = np.concatenate([[t[0] - 0.1], rng.uniform(t[0], t[-1], 500), t[::7], [t[-1] + 0.1]])
    at = TrackAt(tq, t)
    for _ in range(3):
        y = np.cumsum(rng.normal(0.0, 1.0, (ticks, 3)), axis=0)
        assert np.array_equal(at(y), _track_at_plain(tq, t, y))
        assert np.array_equal(at(y[:, 2]), _track_at_plain(tq, t, y[:, 2]))
    y = rng.normal(0.0, 1.0, (ticks, 3))
    lin = np.stack([np.interp(tq, t, y[:, c]) for c in range(3)], axis=-1)
    assert np.array_equal(TrackAt(tq, t, at_ticks=True)(y), lin)


def test_no_drive_effect_is_fitted_on_a_passive_trailer() -> None:
    """A set's trailer rolls passively: slip, skid and scrub on it are the nominal model
    (model.floor_travel, test_track_cache_answers_each_truck_for_its_own_parameters), so they
    are not offered as its own hypotheses; its geometry is, and a clapper's driven truck B
    keeps them all."""
    from odo_tools.gap import hypotheses

    singles = hypotheses.singles("truth", "set")
    fams = {h.families[0] for h in singles}
    assert {"slip", "scrub", "ed"} <= fams
    onB = {h.families[0] for h in singles if hypotheses.on_truck(h, "B", (True, False))}
    assert "ed" in onB and not onB & {"slip", "skid", "scrub"}
    onA = {h.families[0] for h in singles if hypotheses.on_truck(h, "A", (True, False))}
    assert {"slip", "scrub", "ed"} <= onA
    clapB = {h.families[0] for h in singles if hypotheses.on_truck(h, "B", (True, True))}
    assert {"slip", "scrub", "ed"} <= clapB


def test_rate_ceiling_law_over_every_stretch_at_once_is_the_per_stretch_loop_bit_for_bit() -> None:
    """model.count_loss_plateau adds the hidden travel of every sprint tick of both wheels in
    one step (`_plateau_stretches` keeps them as flat arrays); written as a loop over the
    sprints, one numpy expression each: stretches of saturated ticks joined across short dips,
    each sprint's ramps read from its counts short of the ceiling's edge (at most the law's
    a), its hidden speed timed from where those ramps cross the ceiling."""
    from odo_tools.gap.model import (
        PLATEAU_SUB,
        PLATEAU_TOL,
        RAMP_EDGE,
        RAMP_MIN_MM_S2,
        RAMP_S,
        SPRINT_DIP,
        SPRINT_GAP_S,
        count_loss_plateau,
        counted_speed,
    )

    rng = np.random.default_rng(11)
    ds = _wheels(rng, 1200)
    pr = _prepared(ds[:, None, :])
    pr.dt = 0.02 + rng.uniform(0.0, 1e-4, ds.shape[0])
    pr.t = np.concatenate([[0.0], np.cumsum(pr.dt)])
    level = float(np.percentile(np.abs(ds) / pr.dt[:, None], 80))  # a fifth of the ticks saturate
    v = counted_speed(pr, 0)  # the wheel speed it reads
    tm = pr.t[:-1] + 0.5 * pr.dt
    k = max(1, round(RAMP_S / float(np.median(pr.dt))))
    gap = max(1, round(SPRINT_GAP_S / float(np.median(pr.dt))))
    nt = v.shape[0]

    def ramp(w: int, start: int, step: int, edge_t: float) -> tuple[float, float]:
        """(rate, time it crosses the ceiling) of the counts' ramp from tick `start` outwards."""
        j = start
        while 0 <= j < nt and v[j, w] >= level * (1 - RAMP_EDGE) and abs(j - start) < k:
            j += step
        far = min(max(j + step * k, 0), nt - 1)
        if not 0 <= j < nt or far == j:
            return math.inf, edge_t
        r = max((v[j, w] - v[far, w]) / abs(tm[j] - tm[far]), RAMP_MIN_MM_S2)
        cross = tm[j] - step * (level - v[j, w]) / r
        return r, (min if step < 0 else max)(cross, edge_t)

    joined = 0
    for E, a in ((0.4 * level, 2.0), (3.0 * level, 0.3)):
        P = {
            "count_loss@plateau.level_mm_s": level,
            "count_loss@plateau.excess_mm_s": E,
            "count_loss@plateau.a_m_s2": a,
        }
        want = ds.copy()
        sat = v >= level * (1.0 - PLATEAU_TOL)
        f = (np.arange(PLATEAU_SUB) + 0.5) / PLATEAU_SUB
        stretches = 0
        for w in (0, 1):  # one sprint at a time
            m = np.concatenate([[False], sat[:, w], [False]]).astype(np.int8)
            up, down = np.flatnonzero(np.diff(m) == 1), np.flatnonzero(np.diff(m) == -1)
            sprints: list[list[int]] = []
            for i0, i1 in zip(up, down, strict=True):
                dip = v[sprints[-1][1] : i0, w] if sprints else None
                if dip is not None and i0 - sprints[-1][1] <= gap and np.all(
                    dip >= level * (1 - SPRINT_DIP)
                ):
                    sprints[-1][1] = i1
                    joined += 1
                else:
                    sprints.append([i0, i1])
            for i0, i1 in sprints:
                ts = pr.t[i0:i1, None] + f[None, :] * pr.dt[i0:i1, None]
                am = a * 1e3
                r_in, t_in = ramp(w, i0 - 1, -1, pr.t[i0])
                r_out, t_out = ramp(w, i1, 1, pr.t[i1])
                r_in, r_out = (r if math.isinf(r) else min(r, am) for r in (r_in, r_out))
                ex = np.minimum(np.minimum(r_in * (ts - t_in), r_out * (t_out - ts)), E)
                want[i0:i1, w] += np.sign(ds[i0:i1, w]) * ex.mean(axis=1) * pr.dt[i0:i1]
                stretches += 1
        assert stretches > 10  # sprints on both wheels: the comparison covers the flat layout
        got = count_loss_plateau(pr, ds, 0, P)
        assert np.array_equal(got, want), E
        assert not np.array_equal(got, ds)  # the law adds travel: the comparison can fail
        assert np.array_equal(count_loss_plateau(pr, ds, 0, P), got)  # served from the cache
    assert joined > 0  # some sprint goes on across a dip: the loop covers the joining


def test_scrub_factor_column_by_column_is_the_row_reduction_bit_for_bit() -> None:
    from odo_tools.gap.model import scrub_factor

    ds = _wheels(np.random.default_rng(11), 2000)
    ds[7] = (0.0, 0.0)  # a tick at rest: v = 0
    ds[8] = (-0.0, 0.3)
    for k in (0.008, -0.05, 0.4):
        a = np.abs(ds)  # the form it replaced: numpy's reductions along each row
        same = (ds[:, 0] * ds[:, 1]) > 0.0
        m = np.where(same, 2.0 * a.min(axis=1), 0.0)
        v = a.sum(axis=1)
        want = 1.0 - k * m / np.where(v > 0.0, v, 1.0)
        got = scrub_factor(ds, k)
        assert np.array_equal(got, want), k
        assert not np.all(got == 1.0)  # the factor acts: the comparison can fail
    assert scrub_factor(ds, 0.0) is None


@pytest.mark.parametrize("truck", [0, 1])
def test_truck_view_in_one_pass_is_the_two_comprehensions(truck: int) -> None:
    from odo_tools.gap.model import truck_view

    def plain(P: dict, truck: int) -> dict:
        out = {k: v for k, v in P.items() if not k.endswith((".A", ".B"))}
        suf = "." + "AB"[truck]
        out.update({k[:-2]: v for k, v in P.items() if k.endswith(suf)})
        return out

    keys = ["ed.value", "es.value.A", "es.value.B", "skid@friction.a_lim_m_s2.B", "eb.value",
            "eb.value.A", "scrub.k", "x.AB", "y.C", ".A", "B", "ab"]  # fmt: skip
    rng = np.random.default_rng(3)
    for _ in range(300):
        P = {k: float(rng.normal()) for k in rng.permutation(keys)[: rng.integers(0, 13)]}
        got, want = truck_view(P, truck), plain(P, truck)
        assert got == want and list(got) == list(want), P  # the same values, the same order


def test_friction_skid_in_c_is_numpys_form_bit_for_bit() -> None:
    from odo_tools.gap.model import integrate, skid_friction

    rng = np.random.default_rng(8)
    ds = _wheels(rng, 1200)
    pr = _prepared(ds[:, None, :])
    pr.dt = 0.02 + rng.uniform(0.0, 1e-4, ds.shape[0])  # jittered ticks
    p = integrate(ds, 340.0, np.zeros(ds.shape[0]), pose0=(120.0, -40.0, 0.3))
    for a_lim in (0.05, 0.3, 2.0):
        # the form it replaced: numpy's velocities and sums around the per-step limiter
        v = np.diff(p[:, :2], axis=0) / pr.dt[:, None]
        lim = a_lim * 1e3 * pr.dt
        u, cx, cy = np.empty_like(v), 0.0, 0.0
        for i in range(v.shape[0]):
            dx, dy = v[i, 0] - cx, v[i, 1] - cy
            m = float(np.hypot(dx, dy))  # libm's hypot, as ratelimit.c's
            f = lim[i] / m if m > lim[i] else 1.0
            cx, cy = cx + f * dx, cy + f * dy
            u[i] = cx, cy
        want = p.copy()
        np.cumsum(u[:, 0] * pr.dt, out=want[1:, 0])
        np.cumsum(u[:, 1] * pr.dt, out=want[1:, 1])
        want[1:, :2] += p[0, :2]
        got = skid_friction(pr, p, a_lim)
        assert np.array_equal(got, want), a_lim
        if a_lim < 1.0:
            assert not np.allclose(got, p)  # the floor lets go: the comparison can fail

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

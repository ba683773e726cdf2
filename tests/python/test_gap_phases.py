"""Phases of the motion (gap.where.classify) on counted wheel travel."""

from __future__ import annotations

import numpy as np
import pytest


def _counted_run(edge_mm: float, dt: float = 0.05):
    """Truck A drives straight: 0.5 s at rest, up to 300 mm/s at 700 mm/s^2, 8 s at speed,
    down at 1100 mm/s^2, 0.5 s at rest; both wheels counted on edge_mm edges, the right one
    a third of an edge behind (two wheels never tick together). Returns the Prepared run and
    each tick's true acceleration (mm/s^2)."""
    from odo_tools.gap.model import Prepared

    fine = 0.001
    ts = np.arange(0.0, 0.5 + 300 / 700 + 8.0 + 300 / 1100 + 0.5, fine)
    a = np.where(ts < 0.5, 0.0, 700.0)
    a = np.where(ts >= 0.5 + 300 / 700, 0.0, a)
    a = np.where(ts >= 0.5 + 300 / 700 + 8.0, -1100.0, a)
    a = np.where(ts >= 0.5 + 300 / 700 + 8.0 + 300 / 1100, 0.0, a)
    v = np.cumsum(a) * fine
    x = np.cumsum(v) * fine
    t = np.arange(0.0, ts[-1], dt)
    X = np.interp(t, ts, x)
    counts = np.stack([np.floor(X / edge_mm), np.floor(X / edge_mm + 1 / 3)], axis=1)
    ds = (np.diff(counts, axis=0) * edge_mm)[:, None, :]
    S = np.concatenate([np.zeros((1, 1, 2)), np.cumsum(np.abs(ds), axis=0)])
    pr = Prepared(
        None, t, ds, S, [500.0], [68.0], np.full(t.size - 1, dt), count_mm=[edge_mm]
    )  # fmt: skip
    return pr, np.interp(t[1:], ts, a)


@pytest.mark.parametrize("edge_mm", [0.11, 2.8])
def test_a_steady_straight_on_coarse_edges_is_not_accelerating(edge_mm: float) -> None:
    """Whole edges make the speed jump from tick to tick; the straight between the start and
    the stop must read as straight however coarse they are (a LabMate's 2.8 mm edges on 50 ms
    ticks read half of every square as "acceleration" over 0.25 s), and start and stop as
    acceleration."""
    from odo_tools.gap.where import classify

    pr, acc = _counted_run(edge_mm)
    lab = classify(pr)
    t = pr.t[1:]
    cruise = (t > 0.5 + 300 / 700 + 1.5) & (t < 0.5 + 300 / 700 + 8.0 - 1.5)
    assert np.mean(lab[cruise] == "straight") >= 0.95
    starting = np.flatnonzero(acc > 0)
    stopping = np.flatnonzero(acc < 0)
    assert np.any(lab[starting] == "acceleration")
    assert np.any(lab[stopping] == "acceleration")


def test_the_speed_is_read_over_more_ticks_only_where_edges_need_it() -> None:
    """0.25 s where whole edges leave the acceleration within a quarter of the threshold; as
    many ticks as the edges' scatter sqrt(2/3) q / (4 m T^2) needs where they do not."""
    from odo_tools.gap.where import ACCEL_JITTER_MM_S2, _smoothing_ticks

    fine, _ = _counted_run(0.11)
    assert _smoothing_ticks(fine) == 5
    coarse, _ = _counted_run(2.8)
    m = _smoothing_ticks(coarse)
    assert m > 5
    scatter = lambda m: np.sqrt(2 / 3) * 2.8 / (4 * m * 0.05**2)  # noqa: E731
    assert scatter(m) <= ACCEL_JITTER_MM_S2 < scatter(m - 1)

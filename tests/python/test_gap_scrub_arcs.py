"""A turn-radius-dependent wheelbase (tyre scrub) is fitted only where the fitting runs turn on
arcs (diagnose.unseen, paths.arc_turning): on spot turns and straights it can only take the
heading a straight wobbles by, whatever wobbles it. The case is the independent world's seed 3311
case 38 (a LabMate's traction slip fitted on two squares and a shuttle beside a scrub at its
bound, the held-out figure eight judged at 2.4 m), traced after its blind; of the development
seeds' cases whose fitting runs turn on no arc (32 in truth mode, 12 in returns mode, gap
README) none moved."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest
from odo_tools.gap import paths


def _counts_run(left: np.ndarray, right: np.ndarray, b_mm: float = 400.0, dt: float = 0.025):
    """A run as paths.py reads it: truck A's wheel travel per tick (mm), wheelbase, ticks."""
    ds = np.stack([left, right], axis=1)[:, None, :]
    return SimpleNamespace(ds=ds, b=np.array([b_mm]), dt=np.full(left.size, dt))


def test_a_straight_whose_counts_wobble_by_an_edge_turns_on_no_arc() -> None:
    """Whole edges make a straight's wheels read an edge more or less each tick: tick by tick
    that is turning (turn_style), net over a second it is none (arc_turning)."""
    q, n = 2.8, 800  # mm per edge; 20 s of 25 ms ticks at about 600 mm/s
    wob = np.where(np.arange(n) % 2 == 0, q, -q)
    straight = _counts_run(15.0 + wob, 15.0 - wob)
    assert paths.turn_style(straight)[1] > 10.0  # rad, tick by tick
    assert math.degrees(paths.arc_turning(straight)) < 0.5
    # a quarter circle of 1 m radius (400 mm wheelbase) on the same wobbling counts: its net
    # turning is the arc's, whichever way it turns
    om = (math.pi / 2) / n  # rad per tick
    for sign in (1.0, -1.0):
        arc = _counts_run(15.0 - sign * 200.0 * om + wob, 15.0 + sign * 200.0 * om - wob)
        assert paths.arc_turning(arc) == pytest.approx(math.pi / 2, rel=0.01)
    # a spot turn rolls the wheels opposite ways: no arc at all
    spot = _counts_run(-np.full(n, 3.0), np.full(n, 3.0))
    assert paths.arc_turning(spot) == 0.0 and paths.turn_style(spot)[0] > 0.0


@pytest.fixture(scope="module")
def slip_case(tmp_path_factory: pytest.TempPathFactory) -> dict:
    """Seed 3311 case 38: a LabMate whose floor grips at 1.22 m/s^2 (traction slip); the random
    split fits two squares and a straight shuttle and judges two squares and the one figure
    eight."""
    from gap_support import indep_case
    from odo_tools.gap.diagnose import diagnose

    real = tmp_path_factory.mktemp("scrub_arcs") / "real"
    indep_case(3311, 38, real, "labmate", {"slip": "traction"})
    return diagnose(real, real / "robot.json", mode="truth").to_dict()


def test_fitting_runs_on_no_arc_fit_no_scrub_and_the_report_says_why(slip_case: dict) -> None:
    assert "run-eight-01" in slip_case["heldout"]["runs"]
    assert not any("scrub" in r["effect"] for r in slip_case["ranking"])
    why = [u["why"] for u in slip_case["unidentifiable"] if "scrub" in u["what"]]
    assert len(why) == 1 and "deg on arcs" in why[0] and "not fitted" in why[0], why


def test_the_slip_is_named_where_a_scrub_on_straights_bent_the_held_out_eight(
    slip_case: dict,
) -> None:
    """With a scrub the windows' best was "scrub + slip" (k 0.25, its bound) and the held-out
    runs went from 14.7 to 106 x the background ("unexplained"); the traction law alone closes
    them."""
    v = slip_case["verdict"]
    assert v["effect"] == "slip", v
    assert v["laws"]["slip"]["law"] == "traction", v["laws"]
    assert v["params"]["slip@traction.a_max_m_s2"] == pytest.approx(1.217, rel=0.05)
    ev = v["evidence"]
    assert (
        ev["heldout_ratio_before"] > 5.0
        and ev["heldout_ratio_after"] < 0.25 * ev["heldout_ratio_before"]
    ), ev

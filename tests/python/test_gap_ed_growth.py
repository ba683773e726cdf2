"""An Ed that grows with speed: one tyre's rolling radius grows with the square of its speed
(centrifugal growth), beside a fixed Ed. The independent world draws Ed under this law in half
its Ed cases; under the catalog's fixed Ed the diagnosis named such a LabMate "ed + scrub"
(the independent world's seed 2791 cases 32 and 50), "eb + ed + es" (case 27) or
"unexplained" (case 58), traced after that seed was measured. The law is `ed@growth`
(hypotheses.OTHER_LAWS, model.floor_travel)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from gap_support import BUILD, SRC, indep_named


@pytest.fixture(autouse=True)
def _env(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("ODO_BUILD_DIR", str(BUILD))
    monkeypatch.setenv("ODO_SOURCE_DIR", str(SRC))


def _straight(v_mm_s: float, n: int = 50, dt: float = 0.02):
    from odo_tools.gap.model import Prepared

    ds = np.full((n, 1, 2), v_mm_s * dt)
    S = np.concatenate([np.zeros((1, 1, 2)), np.cumsum(ds, axis=0)])
    return Prepared(None, np.arange(n + 1) * dt, ds, S, [400.0], [100.0], np.full(n, dt))


@pytest.mark.parametrize("g,grows", [(0.008, 0), (-0.008, 1)])
def test_one_tyre_grows_with_the_square_of_its_speed(g: float, grows: int) -> None:
    """On a straight at 1.5 m/s the growing tyre rolls (1 + |g| 1.5^2) times its counted travel
    and the other exactly its counted travel (no fixed Ed); at 0.3 m/s a 25th of that."""
    from odo_tools.gap.model import floor_travel

    for v in (1500.0, 300.0):
        pr = _straight(v)
        ds, *_ = floor_travel(pr, {"ed@growth.g_per_m2_s2": g}, 0)
        want = np.ones(2)
        want[grows] += abs(g) * (v / 1000.0) ** 2
        np.testing.assert_allclose(ds / pr.ds[:, 0, :], np.broadcast_to(want, ds.shape))


def test_a_speed_dependent_ed_is_named_ed_with_its_law(tmp_path: Path) -> None:
    """2791 case 32: a LabMate whose left tyre grows by g = 0.00698 per (m/s)^2 beside a fixed
    Ed of 0.99688. The verdict is "ed" under the growth law, both parameters near the truth, and
    the held-out runs come to the background."""
    c, rep = indep_named(2791, 32, tmp_path, "labmate", {"ed": "speed"}, "ed", "growth")
    e = c["true"]["effects"]["ed"]
    assert e["g_right"] == 0.0  # the left tyre grows: g > 0 in the law's sign convention
    p = rep["verdict"]["params"]
    assert p["ed@growth.g_per_m2_s2"] == pytest.approx(e["g_left"], rel=0.15)
    assert p["ed.value"] == pytest.approx(e["value0"], abs=3e-4)
    assert rep["heldout"]["ratio_after"] < 1.5


def test_a_right_tyre_that_grows_is_found_in_its_own_basin(tmp_path: Path) -> None:
    """Dev seed 4091 case 33: the right tyre grows by g = 0.00829 per (m/s)^2 beside a fixed Ed
    of 0.99529. The law's sign picks the wheel (g < 0: the right), and a solver started at 0
    walks to g > 0 only: the left tyre growing fitted the tracks worse than count loss did
    ("count loss", 7.1 x the background). Each start is mirrored too (fit.WHEEL_SIGNED)."""
    c, rep = indep_named(4091, 33, tmp_path, "labmate", {"ed": "speed"}, "ed", "growth")
    e = c["true"]["effects"]["ed"]
    assert e["g_left"] == 0.0
    p = rep["verdict"]["params"]
    assert p["ed@growth.g_per_m2_s2"] == pytest.approx(-e["g_right"], rel=0.15)
    assert p["ed.value"] == pytest.approx(e["value0"], abs=3e-4)
    assert rep["heldout"]["ratio_after"] < 1.5

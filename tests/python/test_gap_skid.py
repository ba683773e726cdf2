"""Sideways skid under a linear cornering stiffness (issue 13 item 3): the tyres run at a slip
angle proportional to the centripetal acceleration from the gentlest arc up, where the catalog's
skid starts only above a threshold. The independent world draws that law; a robot whose fast
circles skidded was judged on a slower circle below the catalog's threshold and called
"unexplained"."""

from __future__ import annotations

import math
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from gap_support import BUILD, SRC, indep_named


@pytest.fixture(autouse=True)
def _env(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("ODO_BUILD_DIR", str(BUILD))
    monkeypatch.setenv("ODO_SOURCE_DIR", str(SRC))


def _circle(v: float, radius: float, b: float, n: int = 50, dt: float = 0.04):
    """A steady circle at v mm/s on `radius` mm, turning left: (pr, wheel travel per tick)."""
    w = v / radius
    dl, dr = (v - w * b / 2) * dt, (v + w * b / 2) * dt
    return SimpleNamespace(dt=np.full(n, dt)), np.tile([dl, dr], (n, 1))


def test_cornering_skid_is_outward_and_grows_with_the_centripetal_acceleration() -> None:
    """At 2 deg per m/s^2 the slip angle on a 1 m circle at 0.5 m/s (0.25 m/s^2) is 0.5 deg,
    so each tick moves d tan(0.5 deg) outward (negative lateral on a left turn, as the
    catalog's skid); at 0.25 m/s (0.0625 m/s^2), where the catalog's 0.3 m/s^2 threshold gives
    nothing, it still moves a quarter of that angle."""
    from odo_tools.gap.model import skid_cornering

    b = 400.0
    pr, ds = _circle(500.0, 1000.0, b)
    lat = skid_cornering(pr, ds, b, None, 2.0)
    d = ds.mean(axis=1)
    assert np.allclose(lat, -d * math.tan(math.radians(2.0 * 0.25)))
    pr, slow = _circle(250.0, 1000.0, b)
    lat_slow = skid_cornering(pr, slow, b, None, 2.0)
    assert np.allclose(lat_slow, -slow.mean(axis=1) * math.tan(math.radians(2.0 * 0.0625)))
    pr, right = _circle(500.0, -1000.0, b)  # a right turn skids to the left
    assert np.allclose(skid_cornering(pr, right, b, None, 2.0), -lat)


def test_cornering_skid_below_the_catalog_threshold_is_named(tmp_path: Path) -> None:
    """Independent world, seed 2721 case 28: a LabMate skidding at 7.8 deg per m/s^2
    (cornering stiffness 7.3 m/s^2 per rad), fitted on two ccw circles at 0.44 and 0.53 m/s^2
    and judged on a cw circle at 0.22 m/s^2. The catalog's skid (threshold 0.3 m/s^2) fitted
    the former and predicted nothing on the latter: 11.9 x the background before and after,
    "unexplained". The cornering law names skid, its slope within a tenth of the world's."""
    c, rep = indep_named(2721, 28, tmp_path, "labmate", {"skid": "cornering"}, "skid", "cornering")
    v = rep["verdict"]
    true = math.degrees(1.0 / c["true"]["effects"]["skid"]["c_alpha_m_s2"])
    assert v["params"]["skid@cornering.deg_per_m_s2"] == pytest.approx(true, rel=0.1)
    assert rep["heldout"]["ratio_after"] < 1.5


def test_the_skid_laws_are_tried_unproposed_and_join_no_pair_unproposed() -> None:
    """hypotheses.tried_laws: without a proposal a ranking fits the load law, the cornering
    skid, the friction circle (a skid read on the straights after the arcs proposes nothing:
    independent 2951 case 30), Ed's speed law and slip's acceleration and traction laws beside
    the catalog's laws; returns mode, which cannot see a skid, gets no skid law; a proposed
    family brings every one of its laws. An unproposed law is no partner
    (hypotheses.unproposed): the friction circle, which limits starts as well as turns, once
    joined a LabMate's slip as a "skid"."""
    from odo_tools.gap.hypotheses import tried_laws, unproposed

    def names(proposals: dict, mode: str = "truth", vehicle: str = "labmate") -> list[str]:
        return [h.name for h in tried_laws(proposals, mode, vehicle)]

    traction = ["slip@traction", "slip@motor"]  # a floor short of the motor's torque: everywhere
    skids = ["skid@cornering", "skid@friction"]
    # the acceleration slip law from return errors, which propose nothing (4021 case 26), and
    # from tracks whose slip the phases count as turns (4501 case 44)
    assert names({}) == ["eb@load", "slip@accel", *traction, *skids, "ed@growth"]
    assert names({"skid": "arcs"}) == names({})
    assert names({}, "returns") == ["eb@load", "slip@accel", *traction, "ed@growth"]
    assert "skid@cornering" not in names({}, "returns")
    # unproposed, the cornering law may lead alone but joins no pair (2721 case 13: "ed+skid")
    laws = {h.name: h for h in tried_laws({}, "truth", "set")}
    assert unproposed(laws["skid@cornering"], {})
    assert not unproposed(laws["skid@cornering"], {"skid": "arcs"})
    assert unproposed(laws["skid@friction"], {})
    assert not unproposed(laws["skid@friction"], {"skid": "arcs"})
    assert not unproposed(laws["eb@load"], {})
    assert unproposed(laws["ed@growth"], {})  # a tyre growing with speed leads alone, too
    assert unproposed(laws["slip@motor"], {})  # and traction slip where no phase proposes slip
    assert not unproposed(laws["slip@motor"], {"slip": "starts"})
    assert names({"slip": "starts"}, "returns") == names({}, "returns")


def test_a_skid_that_shows_after_its_arcs_is_tried_without_a_proposal(tmp_path: Path) -> None:
    """Independent world, seed 2761 case 1: a robot with an encoder trailer whose truck skids
    outward on its 1.5-2.2 m arcs (cornering stiffness 15.5 m/s^2 per rad). The outward step is
    made on the arc but read on the straight after it (86 % of the excess misfit there), so no
    phase proposed the skid's other laws, and a scrub of 0.062 that took the held-out runs from
    14.6 to 402 x the background led the ranking ("unexplained"). Tried always, like the load
    law, the cornering law names the skid. Its slope comes out at 1.5 deg per m/s^2 against the
    world's 3.7 (the held-out runs at 5.4 x the background, from 14.3): what keeps it low on
    this robot is not found; the test holds the verdict and that the fit more than halves the
    held-out misfit."""
    c, rep = indep_named(2761, 1, tmp_path, "set", {"skid": "cornering"}, "skid", "cornering")
    true = math.degrees(1.0 / c["true"]["effects"]["skid"]["c_alpha_m_s2"])
    assert 0.25 * true < rep["verdict"]["params"]["skid@cornering.deg_per_m_s2"] < true
    assert rep["heldout"]["ratio_after"] < 0.5 * rep["heldout"]["ratio_before"]

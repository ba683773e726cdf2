"""Two laws of the independent world's physics the catalog's do not follow (issue 13 item 3):
a friction-circle skid (the floor changes the truck's centre velocity by at most a_lim in any
direction; the catalog's skid grows with the excess over a threshold) and a wheelbase that grows
with the lateral load (Eb (1 + zeta |a_lat| / g); the catalog's Eb is one number). Each was
"unexplained", or named with a scrub beside it, on development seeds 2741 and 2721."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from gap_support import BUILD, SRC, indep_case, indep_named


@pytest.fixture(autouse=True)
def _env(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("ODO_BUILD_DIR", str(BUILD))
    monkeypatch.setenv("ODO_SOURCE_DIR", str(SRC))


def _circle(v_mm_s: float, r_mm: float, T: float = 0.04, n: int = 400) -> tuple:
    """A truck's track accelerating from rest at 0.5 m/s^2 to v on a circle of radius r: (pr, p)."""
    speed = np.minimum(500.0 * T * np.arange(1, n + 1), v_mm_s)
    s = np.concatenate([[0.0], np.cumsum(speed * T)])
    th = s / r_mm
    p = np.column_stack([r_mm * np.sin(th), r_mm * (1.0 - np.cos(th)), th])
    return SimpleNamespace(dt=np.full(n, T)), p


def test_friction_skid_leaves_a_track_the_floor_can_follow_alone() -> None:
    """Below the limit (0.5 m/s^2 to start, 0.8 m/s^2 around a 0.5 m circle at 632 mm/s) the
    track comes back as it went in; above it the centre falls behind, its velocity never
    changing faster than the limit, while the heading follows the wheels."""
    from odo_tools.gap.model import skid_friction

    pr, p = _circle(632.0, 500.0)
    assert np.allclose(skid_friction(pr, p, 1.0), p, atol=1e-9, rtol=0.0)
    out = skid_friction(pr, p, 0.6)
    assert np.array_equal(out[:, 2], p[:, 2])  # the heading follows the wheels
    v = np.diff(out[:, :2], axis=0) / pr.dt[:, None]
    a = np.hypot(*np.diff(np.vstack([[0.0, 0.0], v]), axis=0).T) / pr.dt
    assert a.max() <= 600.0 * (1 + 1e-9)
    # on the circle it settles where the floor's whole grip turns its velocity with the
    # heading: |u| omega = a_lim, so it runs at a_lim r / v, behind the wheels' 632 mm/s
    speed = np.hypot(*v[-1])
    assert speed == pytest.approx(600.0 * 500.0 / 632.0, rel=0.01)
    assert a[-1] == pytest.approx(600.0, rel=1e-6)


def test_friction_limiter_in_libodosim_is_the_plain_replay() -> None:
    """simlib.rate_limit_track (host_sim/src/ratelimit.c) against the rule written out per step,
    and its shape checks (test_gap_speed holds model.skid_friction to numpy's form bit for bit)."""
    from odo_tools.gap.simlib import rate_limit_track

    rng = np.random.default_rng(4)
    v = np.cumsum(rng.normal(0.0, 40.0, (500, 2)), axis=0)
    dt = rng.uniform(0.01, 0.03, 500)
    pose = np.zeros((501, 3))
    pose[1:, :2] = np.cumsum(v * dt[:, None], axis=0)
    pose[:, 2] = rng.normal(size=501)
    acc = 2000.0
    want, cur = pose.copy(), np.zeros(2)
    for i in range(v.shape[0]):
        d = (pose[i + 1, :2] - pose[i, :2]) / dt[i] - cur
        m, lim = float(np.hypot(*d)), acc * dt[i]
        cur = cur + (d * (lim / m) if m > lim else d)
        want[i + 1, :2] = want[i, :2] + cur * dt[i]
    got = rate_limit_track(pose, dt, acc)
    assert np.allclose(got, want, atol=1e-9, rtol=0.0)
    assert np.array_equal(got[:, 2], pose[:, 2])
    assert not np.allclose(got, pose)  # the limit bit: the comparison can fail
    for bad in (dt[:-1], np.append(dt, 0.02)):
        with pytest.raises(ValueError):
            rate_limit_track(pose, bad, acc)
    with pytest.raises(ValueError):
        rate_limit_track(pose[:, :2], dt, acc)


def test_load_dependent_wheelbase_divides_each_ticks_turn() -> None:
    """eb@load: a tick's heading change over 1 + zeta |a_lat| / g, a_lat = v omega from the
    tick's own travel; a spot turn (v = 0) keeps the catalog Eb's turn."""
    from odo_tools.gap.model import G0, eb_load

    T, b = 0.05, 300.0
    ds = np.array([[40.0, 50.0], [-10.0, 10.0], [30.0, 30.0]])  # an arc, a spot turn, a straight
    g = eb_load(SimpleNamespace(dt=np.full(3, T)), ds, b, None, 0.2)
    v, om = 45.0 / T * 1e-3, 10.0 / b / T
    assert g[0] == pytest.approx(1.0 / (1.0 + 0.2 * v * om / G0), rel=1e-12)
    assert g[1] == 1.0 and g[2] == 1.0


def test_a_friction_circle_skid_is_named_with_its_limit(tmp_path: Path) -> None:
    """Independent world, seed 2741 case 56: a LabMate (100 ms tick) whose floor gives
    0.27 m/s^2; its arcs ask 1.5. The catalog's skid (and the cornering law) left the held-out
    runs at 290 x the background, "unexplained"; the friction circle names the skid and its
    limit."""
    c, rep = indep_named(2741, 56, tmp_path, "labmate", {"skid": "friction"}, "skid", "friction")
    v = rep["verdict"]
    true = c["true"]["effects"]["skid"]["a_lim_m_s2"]
    assert v["params"]["skid@friction.a_lim_m_s2"] == pytest.approx(true, rel=0.05)
    assert rep["heldout"]["ratio_after"] < 0.1 * rep["heldout"]["ratio_before"]


def test_a_friction_skid_read_after_the_arcs_is_tried_unproposed(tmp_path: Path) -> None:
    """Independent world, seed 2951 case 30: a LabMate whose two fast circles skid 232 and
    342 mm, 92 % of it on the straights after them, so no phase proposes the friction circle;
    the cornering law left the held-out runs at 64 x the background, "unexplained". Tried on
    every robot (hypotheses.ALWAYS) the friction circle names it and closes the gap."""
    c, rep = indep_named(2951, 30, tmp_path, "labmate", {"skid": "friction"}, "skid", "friction")
    true = c["true"]["effects"]["skid"]["a_lim_m_s2"]
    assert rep["verdict"]["params"]["skid@friction.a_lim_m_s2"] == pytest.approx(true, rel=0.1)
    assert rep["heldout"]["ratio_before"] > 20.0 and rep["heldout"]["ratio_after"] < 1.5


def test_a_wheelbase_under_lateral_load_is_named_eb_alone(tmp_path: Path) -> None:
    """Independent world, seed 2721 case 10: a LabMate whose wheelbase is 0.987 on the spot and
    grows 17 % of the lateral acceleration in g. The catalog's Eb needed a scrub beside it
    ("eb+scrub"); the load law names the Eb alone, with both numbers."""
    c, rep = indep_named(2721, 10, tmp_path, "labmate", {"eb": "load_patch"}, "eb", "load")
    v = rep["verdict"]
    e = c["true"]["effects"]["eb"]
    assert v["params"]["eb.value"] == pytest.approx(e["value0"], abs=0.001)
    assert v["params"]["eb@load.zeta"] == pytest.approx(e["zeta"], abs=0.06)


def test_a_clappers_wheelbase_under_load_is_named_from_its_tracks(tmp_path: Path) -> None:
    """Independent world, seed 2721 case 12: a clapper on 10 ms ticks whose wheelbase is 0.981
    on the spot and grows 12 % of the lateral acceleration in g. The windows' ranking left its
    tracks far from the background, and the refit on the accumulated tracks knew only the
    catalog's laws: "eb+scrub" (Eb 0.994 beside a scrub of -0.013). With the load law among the
    track fit's singles it is the Eb alone, both numbers within a few per mille."""
    c, rep = indep_named(2721, 12, tmp_path, "clapper", {"eb": "load_patch"}, "eb", "load")
    v = rep["verdict"]
    e = c["true"]["effects"]["eb"]
    assert v["params"]["eb.value"] == pytest.approx(e["value0"], abs=0.001)
    assert v["params"]["eb@load.zeta"] == pytest.approx(e["zeta"], abs=0.02)
    assert rep["heldout"]["ratio_after"] < 2.0


def test_a_track_fit_member_that_stopped_earning_its_place_goes(tmp_path: Path) -> None:
    """Independent world, seed 2721 case 21: a LabMate's tyre compression, which the catalog
    reports through Ed and Es. Among the track fit's singles the load law led, Ed and Es joined
    it, and it ended at zeta 0.005 with Eb 0.99995 - a member doing nothing ("eb+ed+es"). Each
    member must still halve what is left without it (diagnose._track_prune): ed + es."""
    from odo_tools.gap.diagnose import diagnose

    real = tmp_path / "real"
    indep_case(2721, 21, real, "labmate", {"tire_compression": "linear"})
    rep = diagnose(real, real / "robot.json", mode="truth").to_dict()
    assert rep["verdict"]["effect"] == "ed+es", rep["verdict"]
    assert rep["heldout"]["ratio_after"] < 0.05 * rep["heldout"]["ratio_before"]


def test_a_load_law_at_either_end_of_its_range_is_no_candidate() -> None:
    """zeta at 0 is the catalog's Eb with a spare parameter; at the top of its range another
    effect bent into the law (the OptiOdom robot's returns took zeta 2.0, a wheelbase doubling
    under half a g, for its tyre scrub): neither ranks. Inside the range, on either truck, it
    does."""
    from odo_tools.gap import hypotheses
    from odo_tools.gap.diagnose import _real

    lo, hi, _ = hypotheses.bounds("eb@load.zeta")
    law = next(x for x in hypotheses.OTHER_LAWS["eb"] if x.name == "load")

    def fit(z: float, truck: str | None = None) -> SimpleNamespace:
        h = hypotheses.Hypothesis((law if truck is None else law.on(truck),))
        key = "eb@load.zeta" + ("" if truck is None else "." + truck)
        return SimpleNamespace(hyp=h, params={key: z})

    assert not _real(fit(lo)) and not _real(fit(hi)) and not _real(fit(hi, "B"))
    assert _real(fit(0.17)) and _real(fit(0.17, "A"))


def test_a_pair_whose_load_law_went_to_zero_is_fitted_as_the_catalog_pair() -> None:
    """A load law at zeta 0 beside a partner is that partner beside the catalog's Eb: the pair is
    refitted as eb + ed (simulator seed 2742 case 33, where eb@load led the singles, eb + ed was
    never formed and roughness won the returns), on either truck; inside its range it stays."""
    from odo_tools.gap import hypotheses
    from odo_tools.gap.diagnose import _as_catalog

    load = next(x for x in hypotheses.OTHER_LAWS["eb"] if x.name == "load")
    ed = hypotheses.catalog_law("ed", "labmate")

    def fit(z: float, truck: str | None = None) -> SimpleNamespace:
        law = load if truck is None else load.on(truck)
        sfx = "" if truck is None else "." + truck
        return SimpleNamespace(
            hyp=hypotheses.Hypothesis((law, ed)),
            params={"eb.value" + sfx: 0.974, "eb@load.zeta" + sfx: z, "ed.value": 1.004},
        )

    assert _as_catalog(fit(0.0), "labmate").name == "eb+ed"
    assert _as_catalog(fit(0.0, "B"), "clapper").name == "eb[B]+ed"
    assert _as_catalog(fit(0.09), "labmate") is None


def test_a_sets_marker_and_latency_are_read_beside_a_friction_skid(tmp_path: Path) -> None:
    """Dev seed 4071 case 43: a set (50 ms tick) whose floor gives 0.21 m/s^2; its marker sits
    on truck A's axle and the truth is 40 ms late. No spot turns, so the marker is read on arcs
    under a preliminary fit with a skid (diagnose._lever_with_skid): under the cornering law
    alone it read 207 mm behind the axle with the truth 125-168 ms late, and the friction skid
    fitted then left the held-out runs at 31 x the background ("unexplained"). Read under the
    friction circle too, the marker is near the axle, the latency near 40 ms, and the skid is
    named with its limit; the truth's clock, read drifting under it, is no clock
    (test_a_skid_is_named_beside_a_clock_that_restamping_does_not_confirm)."""
    c, rep = indep_named(4071, 43, tmp_path, "set", {"skid": "friction"}, "skid", "friction")
    inst = rep["instrument"]
    assert np.hypot(*inst["lever_arm_mm"][0]) < 30.0, inst["lever_arm_mm"]
    true_lat = c["fidelity"]["truth_latency_s"]
    assert all(abs(x - true_lat) < 0.015 for x in inst["latency_s"].values()), inst["latency_s"]
    true = c["true"]["effects"]["skid"]["a_lim_m_s2"]
    assert rep["verdict"]["params"]["skid@friction.a_lim_m_s2"] == pytest.approx(true, rel=0.05)
    h = rep["heldout"]
    assert h["ratio_after"] ** 2 - 1 < 0.05 * (h["ratio_before"] ** 2 - 1), h


@pytest.mark.parametrize(
    ("seed", "k", "vehicle", "laws", "asked"),
    [
        (4071, 43, "set", {"skid": "friction"}, True),
        (4071, 10, "clapper", {"skid": "cornering"}, False),
    ],
)
def test_the_friction_reading_is_asked_where_the_cornering_readings_leave_a_gap(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, seed, k, vehicle, laws, asked
) -> None:
    """The markers are read under a friction circle's skid only where the best cornering reading
    still leaves the tracks overdispersed by R_GAP^2 (diagnose._lever_with_skid): on dev 4071/43
    (a friction skid) it is asked, on a clapper's cornering skid at 10 ms ticks (4071/10), which
    the cornering law reads to within the noise, it is not (asked there, it doubled the time)."""
    from odo_tools.gap import diagnose as D
    from odo_tools.gap.fit import FRICTION_LIMIT

    real = tmp_path / "real"
    indep_case(seed, k, real, vehicle, laws)
    readings = []
    rounds = D._lever_rounds

    def spy(ds, keys, nominal_first=False):
        readings.append(list(keys))
        return rounds(ds, keys, nominal_first)

    monkeypatch.setattr(D, "_lever_rounds", spy)
    D.load(real, real / "robot.json", "truth")
    assert any(k.startswith("skid@cornering") for ks in readings for k in ks), readings
    assert any(k.startswith(FRICTION_LIMIT) for ks in readings for k in ks) == asked, readings

"""The truth's tracked point on a two-truck robot that never turns on the spot: its lever arm is
estimated on arcs under a preliminary fit of the geometry, and that fit is each truck's own. With
one geometry for both trucks, an Es on one truck biased the other's lever arm by a few mm
sideways, which turns the link's direction between the two tracked points by a few tenths of a
degree: the diagnosis then added a joint-encoder offset to the Es (the independent world's seed
2781 cases 13 and 31, traced after that seed was measured)."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from gap_support import BUILD, SRC, indep_case


@pytest.fixture(autouse=True)
def _env(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("ODO_BUILD_DIR", str(BUILD))
    monkeypatch.setenv("ODO_SOURCE_DIR", str(SRC))


@pytest.fixture(scope="module")
def es_on_one_truck(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict]:
    """A clapper whose truck A has an Es of 1.0104 and its marker 23.9 mm left of the axle."""
    real = tmp_path_factory.mktemp("lever") / "real"
    c = indep_case(2781, 31, real, "clapper", {"es": "diameter"})
    return real, c


def test_each_trucks_lever_arm_is_found_beside_an_es_on_one_truck(es_on_one_truck) -> None:
    from odo_tools.gap import diagnose as D

    real, c = es_on_one_truck
    assert c["true"]["effects"]["es"]["truck"] == "A"
    ds = D.load(real, real / "robot.json")
    assert any("lever arm from" in n for n in ds.notes), ds.notes  # the arcs estimate ran
    lever = c["fidelity"]["truth_lever_arm_mm"]
    for t, name in enumerate("AB"):
        want = lever.get(name, [0.0, 0.0])
        got = ds.instrument.lever_mm[t]
        assert got == pytest.approx(want, abs=1.0), (name, got, want)
    # the link's direction the two tracked points give is off by their sideways errors over
    # the link: under a tenth of the 10-bit joint encoder's step
    err = abs(ds.instrument.lever_mm[0][1] - lever["A"][1]) + abs(ds.instrument.lever_mm[1][1])
    step = 360.0 / (1 << c["robot"]["linkage"]["rotary_bits"])
    assert math.degrees(err / c["robot"]["linkage"]["length_mm"]) < 0.1 * step


def test_the_es_is_named_without_a_joint_encoder_offset(es_on_one_truck) -> None:
    from odo_tools.gap import diagnose as D

    real, c = es_on_one_truck
    v = D.diagnose(real, real / "robot.json", mode="truth").to_dict()["verdict"]
    assert v["effect"] == "es", v
    (key,) = [k for k in v["params"] if k.startswith("es.value")]
    assert v["params"][key] == pytest.approx(c["true"]["effects"]["es"]["value"], abs=5e-4)


@pytest.mark.parametrize(
    "seed,k,laws",
    [
        (2781, 44, {"skid": "cornering"}),  # skid on truck B, both markers on their axles
        (2761, 44, {"skid": "cornering"}),  # skid on truck A, B's marker 25 mm behind its axle
    ],
)
def test_a_skidding_truck_is_not_read_as_its_marker_off_the_axle(tmp_path, seed, k, laws) -> None:
    """On an arc a marker ahead of or behind the axle moves sideways as a skidding tyre does.
    Without a skid in the preliminary fit the skidding truck's marker came out 56 mm (2781
    case 44) and 102 mm (2761 case 44) behind its axle; with a skid on both trucks always, the
    truck that does not skid had its real 25 mm offset taken for one (2761 case 44)."""
    from odo_tools.gap import diagnose as D

    real = tmp_path / "real"
    c = indep_case(seed, k, real, "clapper", laws)
    ds = D.load(real, real / "robot.json")
    assert all("cornering skid" in n for n in ds.notes if "lever arm from" in n), ds.notes
    lever = c["fidelity"]["truth_lever_arm_mm"]
    for t, name in enumerate("AB"):
        want = lever.get(name, [0.0, 0.0])
        assert ds.instrument.lever_mm[t] == pytest.approx(want, abs=1.0), (name, ds.notes)


@pytest.mark.parametrize(
    "seed,k,laws,truck",
    [
        (2801, 50, {}, "A"),  # no effect: the marker 7.5 mm behind the axle read as a skid
        (2701, 37, {"ed": "fixed"}, "A"),  # an Ed on the trailer: 26.6 mm behind, read as a skid
    ],
)
def test_no_skid_is_looked_for_where_the_geometry_leaves_no_gap(tmp_path, seed, k, laws, truck):
    """A set whose tracks the geometry and the markers already fit within a gap of the noise:
    with a cornering skid tried anyway, truck A's marker behind its axle was read on the axle
    and the skid took 0.7-0.9 % off the deviance (2801 case 50, traced after that seed was
    measured, then a false alarm "skid"; dev 2701 case 37, an Ed named "unexplained")."""
    from odo_tools.gap import diagnose as D

    real = tmp_path / "real"
    c = indep_case(seed, k, real, "set", laws)
    ds = D.load(real, real / "robot.json")
    notes = [n for n in ds.notes if "lever arm from" in n]
    assert notes and not any("cornering skid" in n for n in notes), ds.notes
    want = c["fidelity"]["truth_lever_arm_mm"][truck]
    assert ds.instrument.lever_mm[0] == pytest.approx(want, abs=1.0)


@pytest.mark.parametrize(
    "seed,k,laws",
    [
        (2601, 5, {"eb": "fixed"}),  # an Eb of 0.979 on truck A
        (2608, 38, {}),  # no effect; markers 12 mm behind (A) and ahead (B) of the axles
    ],
)
def test_each_trucks_eb_is_its_own_once_the_markers_are_near(tmp_path, seed, k, laws) -> None:
    """A clapper's markers read on arcs under a preliminary geometry: with one Eb for both
    trucks, an Eb on truck A put both markers 1.7-1.9 mm sideways and a joint-encoder offset
    joined the Eb (dev seed 2601 case 5); with each truck its own Eb from the first round, truck
    B took an Eb of 0.86 for its marker's forward offset while both markers were still taken on
    the axles (dev 2608 case 38, no effect, then "unexplained" at 10.6 x). Each truck has its
    own Eb from the second round on."""
    from odo_tools.gap import diagnose as D

    real = tmp_path / "real"
    c = indep_case(seed, k, real, "clapper", laws)
    ds = D.load(real, real / "robot.json")
    assert any("lever arm from" in n for n in ds.notes), ds.notes
    lever = c["fidelity"]["truth_lever_arm_mm"]
    for t, name in enumerate("AB"):
        assert ds.instrument.lever_mm[t] == pytest.approx(lever[name], abs=1.0), name


def test_markers_read_under_the_nominal_geometry_and_an_ed_the_tracks_want(tmp_path) -> None:
    """An Ed of 0.99897 on truck B of a clapper (10 ms ticks, no spot turns, 50 Hz truth): the
    lever arms' first preliminary fit, made with the markers on the axles, wanted an Eb of 1.018
    and held both markers 2.3-2.8 mm forward of where they are; a link bias of 0.5 mm then won
    the windows, the track refit was not asked under a linkage bias, and the verdict was
    "unexplained" at 43 x (independent world, seed 3071 case 54, traced after that seed was
    measured). The markers read under the nominal geometry are chosen by their deviance, the
    tracks name the Ed, and the windows' link bias of 0.15 mm, which no longer earns its place
    beside it, leaves (diagnose._track_refit)."""
    from odo_tools.gap import diagnose as D

    real = tmp_path / "real"
    c = indep_case(3071, 54, real, "clapper", {"ed": "fixed"})
    assert c["true"]["effects"]["ed"]["truck"] == "B"
    ds = D.load(real, real / "robot.json")
    lever = c["fidelity"]["truth_lever_arm_mm"]
    for t, name in enumerate("AB"):
        want = lever.get(name, [0.0, 0.0])
        got = ds.instrument.lever_mm[t]
        assert math.hypot(got[0] - want[0], got[1] - want[1]) < 1.0, (name, got, want)
    v = D.diagnose(real, real / "robot.json", mode="truth").to_dict()["verdict"]
    assert v["effect"] == "ed", v
    ed = v["params"].get("ed.value.B", v["params"].get("ed.value"))
    assert ed == pytest.approx(c["true"]["effects"]["ed"]["value"], abs=2e-4), v["params"]
    assert v["evidence"]["heldout_ratio_after"] < 1.5, v["evidence"]
